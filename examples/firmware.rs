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
//! high-water mark, then exits with status 0, or 1 on any error or panic.
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(not(target_os = "none"))]
fn main() {
    println!("firmware example: run it on a target, e.g.");
    println!("  cargo run --release --example firmware --target thumbv7em-none-eabihf");
}

/// Cortex-M: SysTick as the instruction counter, cortex-m-rt start-up.
#[cfg(all(target_os = "none", target_arch = "arm"))]
mod arch {
    use cortex_m::peripheral::{syst::SystClkSource, SYST};

    /// 25 MHz SysTick, 1 ns per instruction under `-icount shift=0`.
    const INSTRUCTIONS_PER_TICK: u64 = 40;
    /// Resolution of [`instructions`].
    pub const GRANULARITY: u64 = INSTRUCTIONS_PER_TICK;

    pub fn start_counter() -> Result<(), &'static str> {
        let mut core = cortex_m::Peripherals::take().ok_or("peripherals taken")?;
        core.SYST.set_clock_source(SystClkSource::Core);
        core.SYST.set_reload(0x00FF_FFFF);
        core.SYST.clear_current();
        core.SYST.enable_counter();
        Ok(())
    }

    /// Instructions executed since `start()`. The counter runs down from 0xFF_FFFF and every
    /// measured interval is far shorter than one wrap (671 M instructions).
    pub struct Mark(u32);
    pub fn start() -> Mark {
        Mark(SYST::get_current())
    }
    pub fn instructions(since: &Mark) -> u64 {
        (since.0.wrapping_sub(SYST::get_current()) & 0x00FF_FFFF) as u64 * INSTRUCTIONS_PER_TICK
    }

    /// Runs exactly `3 n` instructions.
    pub fn known_loop(n: u32) {
        // SAFETY: a register-only countdown loop (nop, subs, bne).
        unsafe {
            core::arch::asm!("2:", "nop", "subs {0}, #1", "bne 2b", inout(reg) n => _, options(nomem, nostack));
        }
    }

    pub fn sp() -> usize {
        cortex_m::register::msp::read() as usize
    }

    #[cortex_m_rt::entry]
    fn main() -> ! {
        super::firmware::main()
    }
}

/// RISC-V: `minstret` as the instruction counter, riscv-rt start-up (machine mode).
#[cfg(all(target_os = "none", target_arch = "riscv32"))]
mod arch {
    /// `minstret` counts single instructions.
    pub const GRANULARITY: u64 = 1;

    pub fn start_counter() -> Result<(), &'static str> {
        Ok(())
    }

    pub struct Mark(u64);
    pub fn start() -> Mark {
        Mark(riscv::register::minstret::read64())
    }
    pub fn instructions(since: &Mark) -> u64 {
        riscv::register::minstret::read64().wrapping_sub(since.0)
    }

    /// Runs exactly `3 n` instructions.
    pub fn known_loop(n: u32) {
        // SAFETY: a register-only countdown loop (nop, addi, bnez).
        unsafe {
            core::arch::asm!("2:", "nop", "addi {0}, {0}, -1", "bnez {0}, 2b", inout(reg) n => _, options(nomem, nostack));
        }
    }

    pub fn sp() -> usize {
        let sp: usize;
        // SAFETY: reads the stack pointer register.
        unsafe { core::arch::asm!("mv {0}, sp", out(reg) sp, options(nomem, nostack)) };
        sp
    }

    #[riscv_rt::entry]
    fn main() -> ! {
        super::firmware::main()
    }
}

#[cfg(target_os = "none")]
mod firmware {
    use super::arch;
    use embedded_graphics::pixelcolor::Rgb565;
    use scanline3d::demo::{self, PanelWorkspace};
    use scanline3d::raster::PixelOrigin;
    use scanline3d::shading::{Shading, SpanDepth};
    use scanline3d::{Depth, Flat};
    use semihosting::println;

    // Defined by both cortex-m-rt's and riscv-rt's linker scripts.
    extern "C" {
        static _stack_start: u32;
        static __sdata: u32;
        static __edata: u32;
        static __sbss: u32;
        static __ebss: u32;
    }

    fn static_ram() -> usize {
        (&raw const __edata as usize - &raw const __sdata as usize)
            + (&raw const __ebss as usize - &raw const __sbss as usize)
    }

    /// Bytes of stack below the entry stack pointer painted to find the high-water mark.
    const PAINTED: usize = 64 * 1024;
    const PAINT: u32 = 0x5AA5_C33C;

    /// Fills the stack below the current frame with a pattern. Writes below the stack pointer
    /// only, into memory nothing uses yet.
    #[inline(never)]
    fn paint_stack() {
        let top = arch::sp() - 256; // leave this function's own frame alone
        let mut p = top - PAINTED;
        while p < top {
            // SAFETY: [top - PAINTED, top) is unused stack below the live frames (RAM is 4 MiB
            // on the MPS2 boards, 16 MiB on virt).
            unsafe { core::ptr::write_volatile(p as *mut u32, PAINT) };
            p += 4;
        }
    }

    /// Deepest stack address reached since painting, found as the lowest overwritten word.
    fn stack_low_water() -> usize {
        let top = arch::sp() - 256;
        let mut p = top - PAINTED;
        // SAFETY: reads the same painted, word-aligned region.
        while p < top && unsafe { core::ptr::read_volatile(p as *const u32) } == PAINT {
            p += 4;
        }
        p
    }

    /// Checks the instruction counter: a loop of exactly 3 instructions per iteration must read
    /// as 3 · n instructions, or every figure printed would be wrong.
    fn calibrate() -> Result<(), &'static str> {
        let n: u32 = 100_000;
        let mark = arch::start();
        arch::known_loop(n);
        let measured = arch::instructions(&mark);
        println!(
            "calibration {} instructions measured for {} executed",
            measured,
            3 * n
        );
        // The counter's own reads add a handful of instructions (RISC-V counts them exactly).
        if measured.abs_diff(3 * n as u64) > arch::GRANULARITY.max(16) {
            return Err(
                "instruction counter is not 1 per instruction (run QEMU with -icount shift=0)",
            );
        }
        Ok(())
    }

    /// One flat span fill, called the way the renderer calls it: through row slices.
    #[inline(never)]
    fn fill_span(span: SpanDepth, depth: &mut [Depth], pixels: &mut [Rgb565]) -> u32 {
        Flat::fill(
            &Rgb565::new(31, 0, 0),
            &PixelOrigin::new(0, 0),
            span,
            depth,
            pixels,
        )
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
        calibrate()?;

        // Render every frame first and print afterwards, so the stack high-water mark is the
        // renderer's (and this loop's), not the formatter's.
        let stack_top = &raw const _stack_start as usize;
        paint_stack();
        let mut lines: [Option<FrameLine>; demo::ORBIT_FRAMES as usize] = Default::default();
        {
            let mut ws = PanelWorkspace::new(demo::BACKGROUND.into());
            let instances = demo::instances();
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
        let peak_stack = stack_top - stack_low_water();

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
            static_ram(),
            PanelWorkspace::BYTES,
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
