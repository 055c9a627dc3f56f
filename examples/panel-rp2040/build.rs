//! Links the firmware for the RP2040 on its own: puts this crate's `memory.x` on the linker
//! search path (cortex-m-rt's `link.x` includes it) and passes `-Tlink.x` and `--nmagic` to the
//! binary, so no `rustflags` are needed in any `.cargo/config.toml`.

use std::{env, fs, path::PathBuf};

fn main() {
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    fs::copy("memory.x", out.join("memory.x")).expect("copy memory.x to OUT_DIR");
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed=memory.x");
    println!("cargo:rerun-if-changed=build.rs");
    // Bare metal only: a host `cargo check` or clippy without --target would otherwise be
    // handed Arm linker scripts.
    if env::var("CARGO_CFG_TARGET_OS").as_deref() != Ok("none") {
        return;
    }
    println!("cargo:rustc-link-arg-bins=-Tlink.x");
    // Sections packed without page alignment: flash starts right after the boot loader.
    println!("cargo:rustc-link-arg-bins=--nmagic");
}
