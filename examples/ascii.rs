//! Renders the demo scene into a small in-RAM frame buffer and prints it as ASCII art.
//!
//! `cargo run --example ascii`

use embedded_graphics::pixelcolor::{Gray8, GrayColor};
use scanline3d::sink::FrameBuffer;
use scanline3d::{Flat, RenderOptions, Workspace};
use scanline3d_demo as demo;

const W: usize = 72;
const H: usize = 36;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let instances = demo::instances();
    let scene = demo::scene(&instances, 0, demo::ORBIT_FRAMES)?;
    let mut ws: Workspace<Gray8, Flat, W, H, 1536, 96> = Workspace::new(Gray8::BLACK);
    let mut pixels = [Gray8::BLACK; W * H];
    let stats = ws
        .render(
            &scene,
            &RenderOptions::default(),
            &mut FrameBuffer::new(&mut pixels, W),
        )
        .map_err(|e| format!("{e}"))?;
    let ramp = b" .:-=+*#%@";
    for row in pixels.chunks(W) {
        let line: String = row
            .iter()
            .map(|p| ramp[p.luma() as usize * (ramp.len() - 1) / 255] as char)
            .collect();
        println!("{line}");
    }
    println!(
        "{} triangles drawn, {} pixels written, workspace {} bytes",
        stats.activated,
        stats.pixels_written,
        Workspace::<Gray8, Flat, W, H, 1536, 96>::BYTES
    );
    Ok(())
}
