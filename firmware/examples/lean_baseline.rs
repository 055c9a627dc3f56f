//! Lean firmware without the renderer: builds every scene of `lean_minimal` but renders nothing,
//! so `lean_minimal`'s size minus this one's is the renderer's flash.
//!
//! ```sh
//! cargo run --profile lean --example lean_baseline --target thumbv6m-none-eabi
//! ```
//!
//! `cargo xtask lean` builds and runs all lean variants on every target and compares sizes.
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]

// The exported scene (`sim export`).
#[path = "lean/scene.rs"]
mod scene;

#[cfg(not(target_os = "none"))]
fn main() {
    println!("lean_baseline: a firmware example; run it on a target, e.g.");
    println!("  cargo run --profile lean --example lean_baseline --target thumbv6m-none-eabi");
    println!(
        "scene budget: TRIS = {}, ACTIVE = {}",
        scene::MAX_TRIANGLES,
        scene::MAX_ACTIVE
    );
}

#[cfg(target_os = "none")]
#[path = "common/arch.rs"]
mod arch;
#[cfg(target_os = "none")]
#[path = "common/lean.rs"]
mod lean;
#[cfg(target_os = "none")]
#[path = "common/measure.rs"]
mod measure;

#[cfg(target_os = "none")]
mod firmware {
    use super::lean;
    #[allow(unused_imports)]
    use super::scene;
    use scanline3d::{clip::NoClip, Flat};

    pub fn main() -> ! {
        super::lean::exit(lean::run::<Flat, NoClip, false>("baseline", NoClip))
    }
}
