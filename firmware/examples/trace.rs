//! Firmware: the fixed-point Whitted tracer renders the lecture's classic scene (a mirror sphere
//! and a glass sphere over a floor polygon with a checker texture, two point lights) at 240×240, row by
//! row into a hash of the row stream (no frame buffer), with shadows and depth limit 4: frame 0
//! by the pure tracer, frame 1 in hybrid mode (primary visibility from the objects' screen
//! bounds); both hashes equal the host's.
//!
//! ```sh
//! cargo run --profile firmware -p scanline3d-firmware --example trace --target thumbv7em-none-eabihf
//! cargo run --profile firmware -p scanline3d-firmware --example trace --target thumbv6m-none-eabi
//! cargo run --profile firmware -p scanline3d-firmware --example trace --target riscv32imc-unknown-none-elf
//! ```
//!
//! The scene is the corpus's `sim/scenes/classic.scene`, exported by `cargo run --bin sim --
//! export sim/scenes/classic.scene --out firmware/examples/trace/classic.rs` as `static` I16F16
//! data. Per frame it prints the hash (equal to the host's
//! fixed tracer: `cargo xtask trace` checks it), instructions per frame, per pixel, per ray and
//! per intersection test (object tests; the box tests are counted apart) (QEMU `-icount`,
//! instructions, not cycles), the ray counts and the
//! stack high-water mark.
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]

/// The classic scene's view, shared with `cargo xtask trace` (which renders it on the host).
#[allow(dead_code)]
#[path = "trace/view.rs"]
mod view;

#[cfg(not(target_os = "none"))]
fn main() {
    println!("trace example: run it on a target, e.g.");
    println!("  cargo run --profile firmware -p scanline3d-firmware --example trace --target thumbv7em-none-eabihf");
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
#[allow(dead_code)]
#[path = "trace/classic.rs"]
mod classic;

#[cfg(target_os = "none")]
mod firmware {
    use super::{arch, classic, row_count::RowCounted, view};
    use embedded_graphics::pixelcolor::Rgb565;
    use scanline3d::sink::HashSink;
    use scanline3d::trace::{Scene, TraceCamera, TraceOptions, TraceStats, Tracer};
    #[cfg(not(scanline3d_trace_only = "pure"))]
    use scanline3d::trace::{ScreenBound, ShadowCandidate};
    use semihosting::println;

    use crate::measure::{self, _stack_start};

    /// Ray-stack capacity: the depth limit 4 needs 5.
    const STACK: usize = 5;

    fn run() -> Result<(), &'static str> {
        arch::start_counter()?;
        measure::calibrate()?;
        let scene = Scene::textured(
            &classic::OBJECTS,
            &classic::MATERIALS,
            &classic::CHECKERS,
            &classic::LIGHTS,
            classic::BACKGROUND,
            classic::AMBIENT,
        )
        .map_err(|_| "scene")?
        .with_bvh(
            &classic::BVH_NODES,
            &classic::BVH_ITEMS,
            classic::BVH_BOUNDED,
        )
        .map_err(|_| "bounding volumes")?;
        let v = view::CLASSIC;
        let camera = TraceCamera::new(
            v.eye, v.target, v.up, v.fovy, v.near, v.far, v.width, v.height,
        )
        .map_err(|_| "camera")?;
        let options = TraceOptions {
            max_depth: view::MAX_DEPTH,
            ..TraceOptions::default()
        };
        let stack_top = &raw const _stack_start as usize;
        measure::paint_stack();
        let tracer = Tracer::<STACK>::new(&scene, &camera, options);
        let mut row = [Rgb565::new(0, 0, 0); view::CLASSIC.width as usize];
        let mut peak_ray_stack = 0;
        // Frame 0: the pure tracer (`--cfg scanline3d_trace_only="hybrid"` skips it).
        #[cfg(not(scanline3d_trace_only = "hybrid"))]
        {
            let mut sink = RowCounted::new(HashSink::new());
            let stats = tracer.render(&mut row, &mut sink).map_err(|_| "render")?;
            report(0, "pure", &stats, sink.instructions, sink.sink.hash())?;
            peak_ray_stack = peak_ray_stack.max(stats.peak_stack);
        }
        // Frame 1: hybrid mode, room for every object in both buffers (the screen-bound set-up
        // is inside the count: it runs before the first row).
        #[cfg(not(scanline3d_trace_only = "pure"))]
        {
            let mut bounds = [ScreenBound::default(); classic::OBJECTS.len()];
            let mut active = [ScreenBound::default(); classic::OBJECTS.len()];
            let mut shadow =
                [ShadowCandidate::default(); classic::LIGHTS.len() * classic::OBJECTS.len()];
            let mut sink = RowCounted::new(HashSink::new());
            let stats = tracer
                .render_hybrid(&mut bounds, &mut active, &mut shadow, &mut row, &mut sink)
                .map_err(|_| "hybrid render")?;
            report(1, "hybrid", &stats, sink.instructions, sink.sink.hash())?;
            peak_ray_stack = peak_ray_stack.max(stats.peak_stack);
        }
        let peak_stack = stack_top - measure::stack_low_water();
        println!(
            "summary peak_stack {} static_ram {} ray_stack_entries {} peak_ray_stack {}",
            peak_stack,
            measure::static_ram(),
            STACK,
            peak_ray_stack
        );
        Ok(())
    }

    /// Prints one frame's line: hash, instructions per frame, pixel, ray and test, ray counts.
    fn report(
        frame: u32,
        mode: &str,
        stats: &TraceStats,
        instructions: u64,
        hash: u32,
    ) -> Result<(), &'static str> {
        if stats.dropped_rays != 0 {
            return Err("ray stack overflowed");
        }
        let v = view::CLASSIC;
        let pixels = u64::from(v.width) * u64::from(v.height);
        let rays = u64::from(stats.rays());
        let tests = u64::from(stats.intersection_tests);
        println!(
            "frame {} hash {:08x} mode {} instructions {} instr_per_pixel {} instr_per_ray {} instr_per_test {} rays {} primary {} secondary {} shadow {} shadow_cache_hits {} window_clear {} tests {} tests_per_ray_x100 {} box_tests_per_ray_x100 {} fallback_rows {} shadow_fallback_rows {}",
            frame,
            hash,
            mode,
            instructions,
            instructions / pixels,
            instructions / rays.max(1),
            instructions / tests.max(1),
            rays,
            stats.primary_rays,
            stats.secondary_rays,
            stats.shadow_rays,
            stats.shadow_cache_hits,
            stats.window_clear_rays,
            tests,
            tests * 100 / rays.max(1),
            u64::from(stats.box_tests) * 100 / rays.max(1),
            stats.fallback_rows,
            stats.shadow_fallback_rows
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
