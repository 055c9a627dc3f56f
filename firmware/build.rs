//! Link set-up for the QEMU firmware: the memory map and the runtime's linker script belong to
//! these images, not to the library (a user's firmware brings its own `memory.x`).

/// QEMU `virt` (RV32): 16 MiB of RAM at 0x8000_0000, loaded there with `-bios none -kernel`.
const RISCV_VIRT_MEMORY: &str = "MEMORY\n{\n  RAM : ORIGIN = 0x80000000, LENGTH = 16M\n}\n\
REGION_ALIAS(\"REGION_TEXT\", RAM);\nREGION_ALIAS(\"REGION_RODATA\", RAM);\n\
REGION_ALIAS(\"REGION_DATA\", RAM);\nREGION_ALIAS(\"REGION_BSS\", RAM);\n\
REGION_ALIAS(\"REGION_HEAP\", RAM);\nREGION_ALIAS(\"REGION_STACK\", RAM);\n";

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=../memory.x");
    // `examples/tradeoff.rs` renders every precision variant, or with
    // `--cfg scanline3d_variant="fast"` (passed by `cargo xtask tradeoff` through `cargo rustc`)
    // only that variant, so each variant's flash can be measured alone; with
    // `--cfg scanline3d_corpus` it also renders the corpus file the xtask generates.
    println!(
        "cargo::rustc-check-cfg=cfg(scanline3d_variant, values(\"fast\", \"balanced\", \"exact\", \"default\", \"bits0\", \"micromath\", \"narrowtransform\", \"reciprocal\", \"narrownormals\", \"depth16\", \"gouraudaffine\", \"gouraudsegments16\", \"gouraudsegments8\", \"gouraudperpixel\", \"baked\"))"
    );
    println!("cargo::rustc-check-cfg=cfg(scanline3d_corpus)");
    // `--cfg scanline3d_corpus_only`: the corpus alone, without the demo orbit (`cargo xtask profile`).
    println!("cargo::rustc-check-cfg=cfg(scanline3d_corpus_only)");
    // `--cfg scanline3d_no_render`: everything but the render call (`cargo xtask scene-ram`'s
    // baseline, whose stack the render's is measured against).
    println!("cargo::rustc-check-cfg=cfg(scanline3d_no_render)");
    // `examples/firmware.rs` and `examples/tradeoff.rs` with `--cfg scanline3d_vertex_cache`
    // render with a vertex cache (`cargo xtask firmware` and `cargo xtask speed` measure both).
    println!("cargo::rustc-check-cfg=cfg(scanline3d_vertex_cache)");
    // `examples/firmware.rs` with `--cfg scanline3d_baked` draws the demo's baked meshes with
    // `Unlit` shading (face colours lit on the host; `cargo xtask firmware` measures it too).
    println!("cargo::rustc-check-cfg=cfg(scanline3d_baked)");
    // `examples/metaball.rs` ray casts, or with `--cfg scanline3d_meta="poly16"` polygonizes
    // on that grid (`cargo xtask metaball-trade` measures each).
    println!(
        "cargo::rustc-check-cfg=cfg(scanline3d_meta, values(\"poly8\", \"poly16\", \"poly24\", \"poly32\"))"
    );
    // `examples/patch.rs` with `--cfg scanline3d_patch_tolerance="1"` draws at that tolerance,
    // with `--cfg scanline3d_patch_mesh` the tessellated mesh at `SCANLINE3D_PATCH_MESH`
    // (`cargo xtask patch-trade` measures each).
    println!(
        "cargo::rustc-check-cfg=cfg(scanline3d_patch_tolerance, values(\"4\", \"2\", \"1\", \"0.5\", \"0.25\"))"
    );
    println!("cargo::rustc-check-cfg=cfg(scanline3d_patch_mesh)");
    // `examples/trace.rs` with `--cfg scanline3d_trace_only="pure"` renders that frame alone
    // (`cargo xtask profile trace` profiles each mode apart).
    println!("cargo::rustc-check-cfg=cfg(scanline3d_trace_only, values(\"pure\", \"hybrid\"))");
    // `examples/hsr_table.rs` with `--cfg scanline3d_hsr_traced_only` runs the tracer's levels
    // alone, without the rasterizers' table.
    println!("cargo::rustc-check-cfg=cfg(scanline3d_hsr_traced_only)");
    if std::env::var("CARGO_CFG_TARGET_OS").as_deref() != Ok("none") {
        return;
    }
    // On Arm, cortex-m-rt's link.x includes memory.x (the QEMU MPS2 map at the top of the
    // repository) from the search path. On RISC-V, riscv-rt's link.x needs the memory layout
    // (QEMU virt's RAM, with the region aliases riscv-rt places sections through) first.
    let out = std::path::PathBuf::from(std::env::var("OUT_DIR").unwrap());
    if std::env::var("CARGO_CFG_TARGET_ARCH").as_deref() == Ok("riscv32") {
        std::fs::write(out.join("memory-riscv-virt.x"), RISCV_VIRT_MEMORY).unwrap();
        println!("cargo:rustc-link-arg-examples=-Tmemory-riscv-virt.x");
    } else {
        std::fs::copy("../memory.x", out.join("memory.x")).unwrap();
    }
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rustc-link-arg-examples=-Tlink.x");
}
