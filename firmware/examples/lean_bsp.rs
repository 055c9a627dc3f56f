//! Lean firmware, BSP build: the lecture's cyclic-overlap case (`sim/corpus/cyclic.obj`, three
//! triangles each over the next), drawn in the painter's order of a BSP tree built on the host
//! and exported with the mesh as `static` data (`sim export --bsp`). Flat shading, no clipping
//! (the exported analysis shows the views never cut a visible triangle).
//!
//! ```sh
//! cargo run --profile lean --example lean_bsp --target thumbv6m-none-eabi
//! ```
//!
//! `cargo xtask lean` runs it on every target and compares its hashes with the host's BSP
//! render of the OBJ.
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]

// The exported scene and tree (`sim export --bsp`).
#[path = "lean/cyclic_bsp.rs"]
mod scene;

#[cfg(not(target_os = "none"))]
fn main() {
    println!("lean_bsp: a firmware example; run it on a target, e.g.");
    println!("  cargo run --profile lean --example lean_bsp --target thumbv6m-none-eabi");
    println!(
        "tree: {} nodes over {} triangles, traversal stack {}",
        scene::BSP_NODES.len(),
        scene::BSP_TREE.triangles(),
        scene::BSP_STACK
    );
}

#[cfg(target_os = "none")]
#[path = "common/arch.rs"]
mod arch;
#[cfg(target_os = "none")]
#[allow(dead_code)] // `lean::run` is the span z-buffer's variant
#[path = "common/lean.rs"]
mod lean;
#[cfg(target_os = "none")]
#[path = "common/measure.rs"]
mod measure;

#[cfg(target_os = "none")]
mod firmware {
    use super::{lean, scene};
    use embedded_graphics::pixelcolor::Rgb565;
    use scanline3d::{clip::NoClip, Flat};

    type Ws = scene::SceneBspWorkspace<Rgb565, Flat>;

    pub fn main() -> ! {
        const { assert!(!scene::NEEDS_CLIPPING) };
        lean::exit(lean::run_with::<NoClip, _, true>(
            "bsp",
            NoClip,
            Ws::BYTES,
            || Ws::new(Rgb565::new(0, 0, 0)),
            |ws, s, options, sink| {
                ws.render(s, &scene::BSP_TREE, options, sink)
                    .map_err(|_| "render")
            },
        ))
    }
}
