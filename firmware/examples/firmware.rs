//! Firmware: renders the demo scene's camera orbit on a microcontroller, feeding each finished
//! row to a model of a frame-buffer-less SPI panel (it hashes the row stream; there is no frame
//! buffer anywhere).
//!
//! ```sh
//! cargo run --release --example firmware --target thumbv7em-none-eabihf        # QEMU mps2-an386, Cortex-M4F
//! cargo run --release --example firmware --target thumbv6m-none-eabi           # QEMU mps2-an385, no FPU, no divide
//! cargo run --release --example firmware --target riscv32imc-unknown-none-elf  # QEMU virt, RV32IMC
//! ```
//!
//! The runners in `.cargo/config.toml` start QEMU with `-icount shift=0`, which makes time
//! proportional to instructions executed, so counts are deterministic. On Arm the SysTick timer
//! (25 MHz on the MPS2 boards, 1 ns per instruction) counts 40 instructions per tick; on RISC-V
//! the `minstret` counter counts every instruction. A calibration loop of known length checks
//! the counter before anything is measured. Over semihosting the firmware prints one line per
//! frame (hash, instructions, pixels), the inner span loop's cost and a summary with the stack
//! high-water mark, then exits with status 0, or 1 on any error or panic. Built with
//! `--cfg scanline3d_vertex_cache` (through `cargo rustc`) it renders the same frames with a
//! vertex cache holding every demo vertex. Built with `--cfg scanline3d_baked` it draws the
//! demo's meshes with face colours lit ahead of time on the host (`demo::baked_instances`) with
//! `Unlit` shading: the same frames, for a static light and static objects only.
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(not(target_os = "none"))]
fn main() {
    println!("firmware example: run it on a target, e.g.");
    println!("  cargo run --release --example firmware --target thumbv7em-none-eabihf");
}

#[cfg(target_os = "none")]
#[path = "common/arch.rs"]
mod arch;
#[cfg(target_os = "none")]
#[path = "common/measure.rs"]
mod measure;

#[cfg(target_os = "none")]
mod firmware {
    use super::arch;
    use embedded_graphics::pixelcolor::Rgb565;
    use scanline3d::shading::{Shading, SpanDepth};
    use scanline3d::{Depth, Flat};
    use scanline3d_demo as demo;
    use semihosting::println;

    use crate::measure::{self, _stack_start};

    /// The demo's workspace; built with `--cfg scanline3d_vertex_cache` (`cargo xtask firmware`
    /// does that too), with a vertex cache holding every demo vertex.
    #[cfg(not(scanline3d_vertex_cache))]
    const VERTS: usize = 0;
    #[cfg(scanline3d_vertex_cache)]
    const VERTS: usize = demo::PANEL_VERTICES;
    /// Lit every frame ([`Flat`]), or with `--cfg scanline3d_baked` unlit ([`scanline3d::Unlit`])
    /// with face colours baked on the host.
    #[cfg(not(scanline3d_baked))]
    type Ws = demo::CachedPanelWorkspace<VERTS>;
    #[cfg(scanline3d_baked)]
    type Ws = demo::BakedPanelWorkspace<VERTS>;
    #[cfg(scanline3d_baked)]
    use demo::baked_instances as instances;
    #[cfg(not(scanline3d_baked))]
    use demo::instances;

    /// One flat span fill, called the way the renderer calls it: through row slices.
    #[inline(never)]
    fn fill_span(span: SpanDepth, depth: &mut [Depth], pixels: &mut [Rgb565]) -> u32 {
        Flat::fill::<_, Depth>(&Rgb565::new(31, 0, 0), span, depth, pixels)
    }

    /// The inner span loop alone: a 240-pixel flat span filled `REPS` times, every pixel passing
    /// the depth test (`pass`) or every pixel failing it. Returns instructions per pixel × 100,
    /// including the call and loop set-up per span (a fraction of an instruction per pixel).
    #[inline(never)]
    fn span_loop_cost(pass: bool, depth: &mut [Depth], pixels: &mut [Rgb565]) -> u64 {
        const REPS: u64 = 50;
        depth.fill(if pass { Depth::ZERO } else { Depth::MAX });
        let mut written = 0;
        let mark = arch::start();
        for i in 0..REPS {
            // Each repetition is nearer than the last, so with `pass` every pixel is written.
            let span = SpanDepth {
                x0: 0,
                y: 0,
                q: (1 << 20) + (i as i32) * 4096,
                dq: 1,
            };
            written += fill_span(span, depth, pixels);
        }
        let cost = arch::instructions(&mark) * 100 / (REPS * depth.len() as u64);
        core::hint::black_box(written);
        cost
    }

    /// Both span-loop measurements, with their own row buffers (kept out of `run`'s frame so
    /// they do not deepen the stack while the frames render).
    #[inline(never)]
    fn benchmark_span_loop() -> (u64, u64) {
        let mut depth = [Depth::ZERO; demo::WIDTH];
        let mut pixels = [Rgb565::new(0, 0, 0); demo::WIDTH];
        (
            span_loop_cost(true, &mut depth, &mut pixels),
            span_loop_cost(false, &mut depth, &mut pixels),
        )
    }

    /// What is printed for one frame, kept compact: it lives on the stack while frames render.
    struct FrameLine {
        hash: u32,
        instructions: u32,
        pixels_written: u32,
        fragments: u32,
        triangles_in: u32,
        drawn: u32,
        bucketed: u32,
        peak_active: u16,
        complete: bool,
    }

    fn run() -> Result<(), &'static str> {
        arch::start_counter()?;
        measure::calibrate()?;

        // Render every frame first and print afterwards, so the stack high-water mark is the
        // renderer's (and this loop's), not the formatter's.
        let stack_top = &raw const _stack_start as usize;
        measure::paint_stack();
        let mut lines: [Option<FrameLine>; demo::ORBIT_FRAMES as usize] = Default::default();
        {
            let mut ws = Ws::new(demo::BACKGROUND.into());
            let instances = instances();
            for (frame, line) in lines.iter_mut().enumerate() {
                let frame = frame as u32;
                let scene =
                    demo::scene(&instances, frame, demo::ORBIT_FRAMES).map_err(|_| "scene")?;
                let mark = arch::start();
                let out = demo::render_panel_frame(&mut ws, &scene).map_err(|_| "render")?;
                let instructions = arch::instructions(&mark) as u32;
                let s = out.stats;
                *line = Some(FrameLine {
                    hash: out.hash,
                    instructions,
                    pixels_written: s.pixels_written,
                    fragments: s.fragments,
                    triangles_in: s.triangles_in,
                    drawn: s.activated,
                    bucketed: s.bucketed,
                    peak_active: s.peak_active,
                    complete: s.is_complete(),
                });
            }
        }
        let peak_stack = stack_top - measure::stack_low_water();

        let (mut max_bucketed, mut max_active) = (0, 0);
        for (frame, line) in lines.iter().enumerate() {
            let l = line.as_ref().ok_or("missing frame")?;
            if !l.complete {
                return Err("active list overflowed");
            }
            max_bucketed = max_bucketed.max(l.bucketed);
            max_active = max_active.max(l.peak_active);
            println!(
                "frame {} hash {:08x} instructions {} pixels_written {} fragments {} triangles {} drawn {} instr_per_fragment {} instr_per_triangle {}",
                frame,
                l.hash,
                l.instructions,
                l.pixels_written,
                l.fragments,
                l.triangles_in,
                l.drawn,
                l.instructions / l.fragments.max(1),
                l.instructions / l.triangles_in.max(1)
            );
        }
        let (pass, fail) = benchmark_span_loop();
        println!(
            "span_loop instr_per_pixel_x100 written {} rejected {}",
            pass, fail
        );
        println!(
            "summary peak_stack {} static_ram {} renderer_ram {} max_bucketed {} max_active {}",
            peak_stack,
            measure::static_ram(),
            Ws::BYTES,
            max_bucketed,
            max_active
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
