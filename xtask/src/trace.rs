//! `cargo xtask trace`: the fixed-point tracer's firmware (`firmware/examples/trace.rs`, the
//! classic scene at 240×240, pure and hybrid mode) on QEMU for every target, with its frame
//! hashes checked against the host's fixed tracer rendering the same view.
//!
//! `cargo xtask trace alone`: the same with each mode in a firmware image of its own, as a
//! user of one mode builds it: in the image of both, the two modes share the tracer's
//! functions, which the compiler then keeps out of line where an image of one mode inlines
//! them into its frame loop.

use crate::*;

/// The view the firmware renders (the same file the firmware includes).
#[allow(dead_code)]
#[path = "../../firmware/examples/trace/view.rs"]
mod view;

/// The classic scene's file (the firmware's `trace/classic.rs` is exported from it).
const CLASSIC: &str = "sim/scenes/classic.scene";

/// The hash and statistics the host's fixed tracer gives for the firmware's frame, pure or in
/// hybrid mode.
fn host_frame(hybrid: bool) -> Result<(u32, scanline3d::trace::TraceStats), String> {
    use scanline3d_sim::trace::{fixed, scene::TracedScene};
    let scene = fixed::FixedScene::new(&TracedScene::load(&root().join(CLASSIC))?)?;
    let v = view::CLASSIC;
    let camera = scanline3d_sim::scene::CameraSpec {
        eye: v.eye,
        target: v.target,
        up: v.up,
        fovy: v.fovy,
        near: v.near,
        far: v.far,
    };
    let options = fixed::options(u32::from(view::MAX_DEPTH), 1.0 / 256.0)?;
    fixed::frame_hash(
        &scene,
        &camera,
        usize::from(v.width),
        usize::from(v.height),
        options,
        hybrid,
    )
}

pub(crate) fn trace() -> Result<(), String> {
    let expected = host_hashes()?;
    step("traced firmware for every target (a no-op when built)");
    check_targets(&expected)
}

/// Host hashes of the firmware's frame, pure and hybrid.
fn host_hashes() -> Result<Vec<u32>, String> {
    let mut expected = Vec::new();
    for (hybrid, mode) in [(false, "pure"), (true, "hybrid")] {
        let (hash, stats) = host_frame(hybrid)?;
        println!(
            "host fixed tracer, {mode}: hash {hash:08x}, {} rays, {} intersection tests, {} box tests",
            stats.rays(),
            stats.intersection_tests,
            stats.box_tests
        );
        expected.push(hash);
    }
    Ok(expected)
}

/// `cargo xtask trace alone`: per target, each mode's frame from an image that renders it
/// alone (`--cfg scanline3d_trace_only`), its hash checked against the host's, and how many
/// times fewer instructions the hybrid frame takes.
pub(crate) fn trace_alone() -> Result<(), String> {
    let expected = host_hashes()?;
    let mut summary = Vec::new();
    for (target, machine) in FIRMWARE {
        let mut counts = Vec::new();
        for (mode, hash) in ["pure", "hybrid"].into_iter().zip(&expected) {
            step(&format!(
                "traced classic scene, {mode} frame alone, on QEMU {machine}, {target}"
            ));
            let cfgs = [format!("scanline3d_trace_only=\"{mode}\"")];
            let elf = tradeoff::build_example_with_cfgs("trace", Some(target), &cfgs, None)?;
            let out = tradeoff::run_on_qemu(target, &elf)?;
            print!("{out}");
            if frame_hashes(&out) != [*hash] {
                return Err(format!(
                    "{target}: the {mode} frame's hash differs from the host's {hash:08x}"
                ));
            }
            counts.push((mean_frame_instructions(&out), text_bytes(&elf)?));
        }
        if let [(pure, pure_text), (hybrid, hybrid_text)] = counts[..] {
            summary.push(format!(
                "{target}: each mode alone, pure {pure:.0} and hybrid {hybrid:.0} instructions a frame, hybrid {:.3}× fewer; .text {pure_text} B and {hybrid_text} B",
                pure / hybrid
            ));
        }
    }
    println!();
    for line in summary {
        println!("{line}");
    }
    Ok(())
}

/// Builds the image of both modes for every target, runs it and checks its hashes.
fn check_targets(expected: &[u32]) -> Result<(), String> {
    build_firmware_examples("firmware", &["trace"])?;
    for (target, machine) in FIRMWARE {
        step(&format!("traced classic scene on QEMU {machine}, {target}"));
        let out = run_example(target, "firmware", "trace")?;
        print!("{out}");
        let hashes = frame_hashes(&out);
        if hashes != expected {
            return Err(format!(
                "{target}: traced frame hashes (pure, hybrid) {hashes:08x?} differ from the host's {expected:08x?}"
            ));
        }
        println!("traced frame hashes (pure, hybrid) equal the host's: {expected:08x?}");
        println!(
            "image of both modes: .text {} B",
            text_bytes(&firmware_elf(target, "firmware", "trace"))?
        );
    }
    Ok(())
}

/// Bytes of an ELF's `.text` section (the code).
fn text_bytes(path: &std::path::Path) -> Result<u64, String> {
    Ok(elf(path)?
        .sections
        .iter()
        .filter(|s| s.0 == ".text")
        .map(|s| s.1 as u64)
        .sum())
}
