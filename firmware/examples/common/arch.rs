//! Per-architecture start-up and instruction counting for the firmware examples (included with
//! `#[path]`; each example provides `firmware::main`).

/// Cortex-M: SysTick as the instruction counter, cortex-m-rt start-up.
#[cfg(target_arch = "arm")]
mod imp {
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
        crate::firmware::main()
    }
}

/// RISC-V: `minstret` as the instruction counter, riscv-rt start-up (machine mode).
#[cfg(target_arch = "riscv32")]
mod imp {
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
        crate::firmware::main()
    }
}

pub use imp::*;
