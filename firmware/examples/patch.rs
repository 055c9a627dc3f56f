//! Firmware: draws the Utah teapot from 32 static Bezier patches (`scanline3d_demo::patches`),
//! turning, with the scanline patch renderer, every row to a model of a frame-buffer-less
//! panel (a hash of the row stream), and prints one line per frame: hash, instructions (QEMU,
//! not cycles), triangles made, peak active triangles.
//!
//! ```sh
//! cargo run --profile firmware --example patch --target thumbv7em-none-eabihf
//! ```
//!
//! `cargo xtask patch` runs it on the targets and checks the hashes equal the host's.
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(not(target_os = "none"))]
fn main() {
    println!("patch example: run it on a target, e.g.");
    println!("  cargo run --profile firmware --example patch --target thumbv7em-none-eabihf");
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
    use scanline3d_demo::patches::{self, PanelPatches};
    use semihosting::println;

    /// Frames drawn per run (every eighth of the turn's 24).
    const FRAMES: [u32; 3] = [0, 8, 16];

    fn run() -> Result<(), &'static str> {
        arch::start_counter()?;
        measure::calibrate()?;
        let stack_top = &raw const _stack_start as usize;
        measure::paint_stack();
        let mut lines = [(0u32, 0u64, 0u32, 0u16); FRAMES.len()];
        let ws = &mut PanelPatches::new(Rgb565::new(0, 0, 0));
        for (&frame, line) in FRAMES.iter().zip(lines.iter_mut()) {
            let mut sink = RowCounted::new(HashSink::new());
            let stats = patches::render_frame(ws, frame, &mut sink)?;
            let (hash, instructions) = (sink.sink.hash(), sink.instructions);
            *line = (
                hash,
                instructions,
                stats.frame.triangles_in,
                stats.frame.peak_active,
            );
        }
        let peak_stack = stack_top - measure::stack_low_water();
        for (frame, (hash, instructions, triangles, active)) in FRAMES.iter().zip(lines) {
            println!(
                "frame {} hash {:08x} instructions {} triangles {} peak_active {}",
                frame, hash, instructions, triangles, active
            );
        }
        println!(
            "summary side {} peak_stack {} static_ram {} workspace_ram {}",
            patches::SIDE,
            peak_stack,
            measure::static_ram(),
            PanelPatches::BYTES
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
