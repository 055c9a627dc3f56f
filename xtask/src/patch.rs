//! `cargo xtask patch`: the scanline Bezier patch renderer (the Utah teapot from 32 static
//! patches) on QEMU for every target; the frame hashes must equal the host's
//! (`scanline3d_demo::patches`, the same code), and the instructions per frame are printed.

use crate::*;

/// Frames the firmware example draws (`firmware/examples/patch.rs`).
const FRAMES: [u32; 3] = [0, 8, 16];

/// The hashes the host computes for the firmware's frames.
fn host_hashes() -> Result<Vec<u32>, String> {
    use scanline3d::sink::HashSink;
    use scanline3d_demo::patches::{self, PanelPatches};
    let mut ws = Box::new(PanelPatches::new(
        embedded_graphics::pixelcolor::Rgb565::new(0, 0, 0),
    ));
    FRAMES
        .iter()
        .map(|&frame| {
            let mut sink = HashSink::new();
            patches::render_frame(&mut ws, frame, &mut sink)?;
            Ok(sink.hash())
        })
        .collect()
}

pub(crate) fn patch() -> Result<(), String> {
    let expected = host_hashes()?;
    step("patch firmware for every target (a no-op when built)");
    build_firmware_examples("firmware", &["patch"])?;
    for (target, machine) in FIRMWARE {
        step(&format!(
            "patch renderer (teapot) on QEMU {machine}, {target}"
        ));
        let out = run_example(target, "firmware", "patch")?;
        print!("{out}");
        let hashes = frame_hashes(&out);
        if hashes != expected {
            return Err(format!(
                "{target}: patch frame hashes {hashes:08x?} differ from the host's {expected:08x?}"
            ));
        }
        println!(
            "patch frame hashes equal the host's: {expected:08x?}; {:.1} M instructions (QEMU) per frame",
            mean_frame_instructions(&out) / 1e6
        );
    }
    Ok(())
}
