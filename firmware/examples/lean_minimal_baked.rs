//! Lean firmware, minimal build with face colours lit ahead of time: `lean_minimal` (no
//! clipping, the exported budget) drawing the scene exported with `sim export --bake-light`
//! (`lean/scene_baked.rs`: the face colours `Flat` gives under the scene's light) with `Unlit`
//! shading, so the build holds no lighting code. The same view hashes as `lean_minimal`; valid
//! only while the light and the mesh stay put (the camera moves freely).
//!
//! ```sh
//! cargo run --profile lean --example lean_minimal_baked --target thumbv6m-none-eabi
//! ```
//!
//! `cargo xtask lean` builds and runs all lean variants on every target and compares sizes.
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]

// The exported scene (`sim export --bake-light`).
#[path = "lean/scene_baked.rs"]
mod scene;

#[cfg(not(target_os = "none"))]
fn main() {
    println!("lean_minimal_baked: a firmware example; run it on a target, e.g.");
    println!("  cargo run --profile lean --example lean_minimal_baked --target thumbv6m-none-eabi");
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
    use scanline3d::{clip::NoClip, Unlit};

    pub fn main() -> ! {
        // The minimal build is only valid for scenes the analysis proved need no clipping.
        const { assert!(!scene::NEEDS_CLIPPING) };
        super::lean::exit(lean::run::<Unlit, NoClip, true>("minimal_baked", NoClip))
    }
}
