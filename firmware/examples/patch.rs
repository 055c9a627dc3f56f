//! Firmware: draws the Utah teapot from 32 static Bezier patches (`scanline3d_demo::patches`),
//! turning, with the scanline patch renderer, every row to a model of a frame-buffer-less
//! panel (a hash of the row stream), and prints one line per frame: hash, instructions (QEMU,
//! not cycles), triangles made, peak active triangles.
//!
//! `cargo xtask patch-trade` builds variants: `--cfg scanline3d_patch_tolerance="T"` (T one of
//! 4, 2, 1, 0.5, 0.25 pixels) draws at that flatness tolerance; `--cfg scanline3d_patch_mesh`
//! draws instead a triangle mesh tessellated from the teapot, the generated source at
//! `SCANLINE3D_PATCH_MESH` (`scanline3d_sim::patch::trade::mesh_source`), through the mesh
//! path's span z-buffer.
//!
//! ```sh
//! cargo run --profile firmware --example patch --target thumbv7em-none-eabihf
//! ```
//!
//! `cargo xtask patch` runs it on the targets and checks the hashes equal the host's.
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]

/// On the host it draws the same frames with the same code and prints their hashes: a target
/// for a host profiler (`valgrind --tool=callgrind`, see `docs/patch-scanline.md`).
/// An argument, a tolerance in pixels (default 0.5), draws at that tolerance.
#[cfg(not(target_os = "none"))]
fn main() -> Result<(), &'static str> {
    use embedded_graphics::pixelcolor::Rgb565;
    use scanline3d::patch::Tolerance;
    use scanline3d::sink::HashSink;
    use scanline3d_demo::patches::{self, PanelPatches, FIRMWARE_FRAMES};
    println!("patch example on the host; on a target, e.g.");
    println!("  cargo run --profile firmware --example patch --target thumbv7em-none-eabihf");
    let tolerance = match std::env::args().nth(1) {
        Some(t) => Tolerance::from_num(t.parse::<f64>().map_err(|_| "a tolerance in pixels")?),
        None => patches::TOLERANCE,
    };
    let mut ws = Box::new(PanelPatches::new(Rgb565::new(0, 0, 0)));
    for frame in FIRMWARE_FRAMES {
        let mut sink = HashSink::new();
        let stats = patches::render_frame_at(&mut ws, frame, tolerance, &mut sink)?;
        println!(
            "frame {frame} hash {:08x} triangles {} peak_active {} pieces {} pieces_culled {} overflows {} late {} dropped {}",
            sink.hash(),
            stats.frame.triangles_in,
            stats.frame.peak_active,
            stats.pieces,
            stats.pieces_culled,
            stats.overflows,
            stats.late,
            stats.frame.dropped,
        );
    }
    Ok(())
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

#[cfg(all(target_os = "none", scanline3d_patch_mesh))]
mod mesh {
    include!(env!("SCANLINE3D_PATCH_MESH"));
}

#[cfg(target_os = "none")]
mod firmware {
    use super::{arch, row_count::RowCounted};
    use crate::measure::{self, _stack_start};
    use embedded_graphics::pixelcolor::Rgb565;
    use scanline3d::sink::HashSink;
    use scanline3d_demo::patches::{self, FIRMWARE_FRAMES as FRAMES};
    use semihosting::println;

    #[cfg(not(scanline3d_patch_mesh))]
    mod renderer {
        use scanline3d::patch::Tolerance;
        use scanline3d_demo::patches::{self, PanelPatches};

        /// The workspace.
        pub type Ws = PanelPatches;
        /// What is drawn: the teapot's patches.
        pub const WHAT: &str = "patches";

        #[cfg(scanline3d_patch_tolerance = "4")]
        const TOLERANCE: Tolerance = Tolerance::lit("4");
        #[cfg(scanline3d_patch_tolerance = "2")]
        const TOLERANCE: Tolerance = Tolerance::lit("2");
        #[cfg(scanline3d_patch_tolerance = "1")]
        const TOLERANCE: Tolerance = Tolerance::lit("1");
        #[cfg(scanline3d_patch_tolerance = "0.5")]
        const TOLERANCE: Tolerance = Tolerance::lit("0.5");
        #[cfg(scanline3d_patch_tolerance = "0.25")]
        const TOLERANCE: Tolerance = Tolerance::lit("0.25");
        #[cfg(not(any(
            scanline3d_patch_tolerance = "4",
            scanline3d_patch_tolerance = "2",
            scanline3d_patch_tolerance = "1",
            scanline3d_patch_tolerance = "0.5",
            scanline3d_patch_tolerance = "0.25"
        )))]
        const TOLERANCE: Tolerance = patches::TOLERANCE;

        /// Draws `frame`: triangles made, peak active triangles.
        pub fn draw<S: scanline3d::sink::RowSink<embedded_graphics::pixelcolor::Rgb565>>(
            ws: &mut Ws,
            frame: u32,
            sink: &mut S,
        ) -> Result<(u32, u16), &'static str> {
            let stats = patches::render_frame_at(ws, frame, TOLERANCE, sink)?;
            Ok((stats.frame.triangles_in, stats.frame.peak_active))
        }
    }

    #[cfg(scanline3d_patch_mesh)]
    mod renderer {
        use crate::mesh::{MESH, TRIANGLES};
        use embedded_graphics::pixelcolor::Rgb565;
        use scanline3d_demo::patches::{self, PanelMesh};

        /// The workspace.
        pub type Ws = PanelMesh<Rgb565, TRIANGLES>;
        /// What is drawn: a tessellated teapot.
        pub const WHAT: &str = "mesh";

        /// Draws `frame`: triangles in, peak active triangles.
        pub fn draw<S: scanline3d::sink::RowSink<Rgb565>>(
            ws: &mut Ws,
            frame: u32,
            sink: &mut S,
        ) -> Result<(u32, u16), &'static str> {
            let stats = patches::render_mesh_frame(ws, &MESH, frame, sink)?;
            if stats.dropped > 0 {
                return Err("triangles dropped from a full active list");
            }
            Ok((stats.triangles_in, stats.peak_active))
        }
    }

    fn run() -> Result<(), &'static str> {
        use renderer::Ws;
        arch::start_counter()?;
        measure::calibrate()?;
        let stack_top = &raw const _stack_start as usize;
        // The workspace lives in this frame, above the painted stack: the peak stack printed
        // includes it.
        let ws = &mut Ws::new(Rgb565::new(0, 0, 0));
        measure::paint_stack();
        let mut lines = [(0u32, 0u64, 0u32, 0u16); FRAMES.len()];
        for (&frame, line) in FRAMES.iter().zip(lines.iter_mut()) {
            let mut sink = RowCounted::new(HashSink::new());
            let (triangles, active) = renderer::draw(ws, frame, &mut sink)?;
            *line = (sink.sink.hash(), sink.instructions, triangles, active);
        }
        let peak_stack = stack_top - measure::stack_low_water();
        for (frame, (hash, instructions, triangles, active)) in FRAMES.iter().zip(lines) {
            println!(
                "frame {} hash {:08x} instructions {} triangles {} peak_active {}",
                frame, hash, instructions, triangles, active
            );
        }
        println!(
            "summary drawn {} side {} peak_stack {} static_ram {} workspace_ram {}",
            renderer::WHAT,
            patches::SIDE,
            peak_stack,
            measure::static_ram(),
            Ws::BYTES
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
