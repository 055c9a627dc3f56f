//! `sim`: renders scenes on the host exactly as the firmware does and writes the result to PNG.
//!
//! With no arguments it renders frame 0 of the built-in demo scene (the same data and camera the
//! firmware uses) to `frame.png` and prints the frame statistics.

use clap::{Parser, ValueEnum};
use embedded_graphics::pixelcolor::{Rgb888, RgbColor};
use embedded_graphics::prelude::*;
use scanline3d::sink::DrawTargetSink;
use scanline3d::{demo, FrameStats, RenderOptions, Workspace};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Clone, Copy, Debug, ValueEnum)]
enum ShadingArg {
    Flat,
    Gouraud,
}

/// Render the built-in demo scene to a PNG, exactly as the firmware renders it.
#[derive(Parser, Debug)]
#[command(name = "sim", version)]
struct Args {
    /// Output PNG.
    #[arg(long, default_value = "frame.png")]
    out: PathBuf,
    /// Frame of the camera orbit to render (0 = the README picture).
    #[arg(long, default_value_t = 0)]
    frame: u32,
    /// Shading model.
    #[arg(long, value_enum, default_value = "flat")]
    shading: ShadingArg,
}

/// An RGB image as an embedded-graphics draw target: the same `DrawTarget` path a display uses.
struct Image {
    width: usize,
    height: usize,
    pixels: Vec<Rgb888>,
}

impl Image {
    fn new(width: usize, height: usize) -> Self {
        Image {
            width,
            height,
            pixels: vec![Rgb888::BLACK; width * height],
        }
    }

    fn write_png(&self, path: &std::path::Path) -> Result<(), String> {
        let file = std::fs::File::create(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let mut encoder = png::Encoder::new(
            std::io::BufWriter::new(file),
            self.width as u32,
            self.height as u32,
        );
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let data: Vec<u8> = self
            .pixels
            .iter()
            .flat_map(|p| [p.r(), p.g(), p.b()])
            .collect();
        encoder
            .write_header()
            .and_then(|mut w| w.write_image_data(&data))
            .map_err(|e| format!("{}: {e}", path.display()))
    }
}

impl OriginDimensions for Image {
    fn size(&self) -> Size {
        Size::new(self.width as u32, self.height as u32)
    }
}

impl DrawTarget for Image {
    type Color = Rgb888;
    type Error = std::convert::Infallible;
    fn draw_iter<I: IntoIterator<Item = Pixel<Rgb888>>>(
        &mut self,
        pixels: I,
    ) -> Result<(), Self::Error> {
        for Pixel(p, c) in pixels {
            if p.x >= 0 && p.y >= 0 && (p.x as usize) < self.width && (p.y as usize) < self.height {
                self.pixels[p.y as usize * self.width + p.x as usize] = c;
            }
        }
        Ok(())
    }
}

const W: usize = demo::WIDTH;
const H: usize = demo::HEIGHT;
/// Capacities for the demo scene (1420 triangles in, about 600 survive culling).
const TRIS: usize = 1536;
const ACTIVE: usize = 96;

fn render<S: scanline3d::Shading>(
    frame: u32,
    image: &mut Image,
) -> Result<(FrameStats, usize), String> {
    let instances = demo::instances();
    let scene = demo::scene(&instances, frame, demo::ORBIT_FRAMES).map_err(|e| e.to_string())?;
    let mut ws: Box<Workspace<Rgb888, S, W, H, TRIS, ACTIVE>> =
        Box::new(Workspace::new(demo::BACKGROUND));
    let stats = ws
        .render(
            &scene,
            &RenderOptions::default(),
            &mut DrawTargetSink::new(image),
        )
        .map_err(|e| e.to_string())?;
    Ok((stats, Workspace::<Rgb888, S, W, H, TRIS, ACTIVE>::BYTES))
}

fn run(args: Args) -> Result<(), String> {
    let mut image = Image::new(W, H);
    let (stats, bytes) = match args.shading {
        ShadingArg::Flat => render::<scanline3d::Flat>(args.frame, &mut image)?,
        ShadingArg::Gouraud => render::<scanline3d::Gouraud>(args.frame, &mut image)?,
    };
    image.write_png(&args.out)?;
    println!(
        "wrote {} ({W}x{H}, demo frame {}, {:?} shading)",
        args.out.display(),
        args.frame,
        args.shading
    );
    println!(
        "triangles: {} in, {} culled, {} clipped, {} rejected, {} drawn (peak {} active per row)",
        stats.triangles_in,
        stats.culled,
        stats.clipped,
        stats.rejected,
        stats.activated,
        stats.peak_active
    );
    println!(
        "pixels: {} spans, {} fragments, {} written; renderer RAM {bytes} bytes{}",
        stats.spans,
        stats.fragments,
        stats.pixels_written,
        if stats.is_complete() {
            ""
        } else {
            " (INCOMPLETE: active list overflowed)"
        }
    );
    Ok(())
}

fn main() -> ExitCode {
    match run(Args::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("sim: {e}");
            ExitCode::from(2)
        }
    }
}
