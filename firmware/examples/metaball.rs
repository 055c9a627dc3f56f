//! Firmware: draws the animated six-ball metaball scene (`scanline3d_demo::metaballs`) in
//! fixed point, every row to a model of a frame-buffer-less panel (a hash of the row stream),
//! and prints one line per frame: hash, instructions (QEMU, not cycles) and what the method did.
//!
//! By default it ray casts; with `--cfg scanline3d_meta="poly16"` (8, 16, 24, 32: cells per
//! axis) it polygonizes each frame by marching tetrahedra and draws the mesh with the span
//! z-buffer, and prints the instructions of the two parts.
//!
//! ```sh
//! cargo run --profile firmware --example metaball --target thumbv7em-none-eabihf
//! ```
//!
//! `cargo xtask metaball` runs the ray caster on the targets and checks the hashes equal the
//! host's; `cargo xtask metaball-trade` builds and measures every method.
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(not(target_os = "none"))]
fn main() {
    println!("metaball example: run it on a target, e.g.");
    println!("  cargo run --profile firmware --example metaball --target thumbv7em-none-eabihf");
}

#[cfg(target_os = "none")]
#[path = "common/arch.rs"]
mod arch;
#[cfg(target_os = "none")]
#[path = "common/measure.rs"]
mod measure;
#[cfg(target_os = "none")]
#[path = "common/row_count.rs"]
mod row_count;

#[cfg(target_os = "none")]
mod firmware {
    use super::{arch, row_count::RowCounted};
    use crate::measure::{self, _stack_start};
    use embedded_graphics::pixelcolor::Rgb565;
    use scanline3d::sink::HashSink;
    use scanline3d_demo::metaballs;
    #[cfg(not(any(
        scanline3d_meta = "poly8",
        scanline3d_meta = "poly16",
        scanline3d_meta = "poly24",
        scanline3d_meta = "poly32"
    )))]
    use scanline3d_demo::metaballs::PanelCaster;
    use semihosting::println;

    /// Frames drawn per run: a few, to keep the test command's time budget.
    const FRAMES: u32 = 3;

    #[cfg(not(any(
        scanline3d_meta = "poly8",
        scanline3d_meta = "poly16",
        scanline3d_meta = "poly24",
        scanline3d_meta = "poly32"
    )))]
    fn run() -> Result<(), &'static str> {
        arch::start_counter()?;
        measure::calibrate()?;
        let stack_top = &raw const _stack_start as usize;
        measure::paint_stack();
        let mut lines = [(0u32, 0u64, 0u32, 0u64, 0u32); FRAMES as usize];
        let mut caster = PanelCaster::new(Rgb565::new(0, 0, 0));
        for (frame, line) in lines.iter_mut().enumerate() {
            let mut sink = RowCounted::new(HashSink::new());
            let stats = metaballs::render_frame(&mut caster, frame as u32 * 2, &mut sink)?;
            let (hash, instructions) = (sink.sink.hash(), sink.instructions);
            *line = (hash, instructions, stats.hits, stats.steps, stats.capped);
        }
        let peak_stack = stack_top - measure::stack_low_water();
        for (frame, (hash, instructions, hits, steps, capped)) in lines.iter().enumerate() {
            println!(
                "frame {} hash {:08x} instructions {} hits {} steps {} capped {}",
                frame * 2,
                hash,
                instructions,
                hits,
                steps,
                capped
            );
        }
        println!(
            "summary method raycast side {} peak_stack {} static_ram {} caster_ram {}",
            metaballs::SIDE,
            peak_stack,
            measure::static_ram(),
            core::mem::size_of::<PanelCaster>()
        );
        Ok(())
    }

    #[cfg(scanline3d_meta = "poly8")]
    type Poly = metaballs::Poly8;
    #[cfg(scanline3d_meta = "poly16")]
    type Poly = metaballs::Poly16;
    #[cfg(scanline3d_meta = "poly24")]
    type Poly = metaballs::Poly24;
    #[cfg(scanline3d_meta = "poly32")]
    type Poly = metaballs::Poly32;

    #[cfg(any(
        scanline3d_meta = "poly8",
        scanline3d_meta = "poly16",
        scanline3d_meta = "poly24",
        scanline3d_meta = "poly32"
    ))]
    fn run() -> Result<(), &'static str> {
        arch::start_counter()?;
        measure::calibrate()?;
        let stack_top = &raw const _stack_start as usize;
        // The polygonizer, mesh and z-buffer live in this frame, above the painted stack: the
        // peak stack printed includes them.
        let mut poly = Poly::new(Rgb565::new(0, 0, 0));
        measure::paint_stack();
        let mut lines = [(0u32, 0u64, 0u64, 0u32, 0u32, 0u32); FRAMES as usize];
        for (frame, line) in lines.iter_mut().enumerate() {
            let mark = arch::start();
            let mesh = poly.polygonize(frame as u32 * 2)?;
            let polygonize = arch::instructions(&mark);
            let mut sink = RowCounted::new(HashSink::new());
            let stats = poly.draw(&mut sink)?;
            *line = (
                sink.sink.hash(),
                polygonize,
                sink.instructions,
                mesh.vertices,
                mesh.triangles,
                stats.pixels_written,
            );
        }
        let peak_stack = stack_top - measure::stack_low_water();
        for (frame, (hash, polygonize, draw, vertices, triangles, pixels)) in
            lines.iter().enumerate()
        {
            println!(
                "frame {} hash {:08x} instructions {} polygonize {} draw {} vertices {} triangles {} pixels {}",
                frame * 2,
                hash,
                polygonize + draw,
                polygonize,
                draw,
                vertices,
                triangles,
                pixels
            );
        }
        println!(
            "summary method polygonize side {} peak_stack {} static_ram {} renderer_ram {}",
            metaballs::SIDE,
            peak_stack,
            measure::static_ram(),
            Poly::BYTES
        );
        Ok(())
    }

    pub fn main() -> ! {
        match run() {
            Ok(()) => semihosting::process::exit(0),
            Err(e) => {
                println!("error: {}", e);
                semihosting::process::exit(1)
            }
        }
    }

    #[panic_handler]
    fn panic(info: &core::panic::PanicInfo) -> ! {
        println!("panic: {}", info);
        semihosting::process::exit(1)
    }
}
