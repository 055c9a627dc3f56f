//! Measurements shared by the firmware examples: static RAM, stack high-water mark by
//! painting, and a check of the instruction counter.

use crate::arch;
use semihosting::println;

// Defined by both cortex-m-rt's and riscv-rt's linker scripts.
extern "C" {
    pub static _stack_start: u32;
    static __sdata: u32;
    static __edata: u32;
    static __sbss: u32;
    static __ebss: u32;
}

pub fn static_ram() -> usize {
    (&raw const __edata as usize - &raw const __sdata as usize)
        + (&raw const __ebss as usize - &raw const __sbss as usize)
}

/// Bytes of stack below the entry stack pointer painted to find the high-water mark.
const PAINTED: usize = 64 * 1024;
const PAINT: u32 = 0x5AA5_C33C;

/// Fills the stack below the current frame with a pattern and returns the lowest painted
/// address: a high-water mark at or below it means the stack went deeper than the painting.
/// Writes below the stack pointer only, into memory nothing uses yet.
#[inline(never)]
pub fn paint_stack() -> usize {
    let top = arch::sp() - 256; // leave this function's own frame alone
    let bottom = top - PAINTED;
    let mut p = bottom;
    while p < top {
        // SAFETY: [top - PAINTED, top) is unused stack below the live frames (RAM is 4 MiB
        // on the MPS2 boards, 16 MiB on virt).
        unsafe { core::ptr::write_volatile(p as *mut u32, PAINT) };
        p += 4;
    }
    bottom
}

/// Deepest stack address reached since painting, found as the lowest overwritten word.
pub fn stack_low_water() -> usize {
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
pub fn calibrate() -> Result<(), &'static str> {
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
        return Err("instruction counter is not 1 per instruction (run QEMU with -icount shift=0)");
    }
    Ok(())
}
