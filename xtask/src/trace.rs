//! `cargo xtask trace`: the fixed-point tracer's firmware (`firmware/examples/trace.rs`, the
//! classic scene at 240×240, pure and hybrid mode) on QEMU for every target, with its frame
//! hashes checked against the host's fixed tracer rendering the same view.

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
    step("traced firmware for every target (a no-op when built)");
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
    }
    Ok(())
}
