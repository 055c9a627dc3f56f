//! `cargo xtask metaball`: the fixed-point metaball ray caster on QEMU for every target; the
//! frame hashes must equal the host's (`scanline3d_demo::metaballs`, the same code), and the
//! instructions per frame are printed.

use crate::*;

/// Frames the firmware example casts (`firmware/examples/metaball.rs`).
const FRAMES: [u32; 3] = [0, 2, 4];

/// The hashes the host computes for the firmware's frames.
fn host_hashes() -> Result<Vec<u32>, String> {
    use scanline3d::sink::HashSink;
    use scanline3d_demo::metaballs::{self, PanelCaster};
    let mut caster = Box::new(PanelCaster::new(
        embedded_graphics::pixelcolor::Rgb565::new(0, 0, 0),
    ));
    FRAMES
        .iter()
        .map(|&frame| {
            let mut sink = HashSink::new();
            metaballs::render_frame(&mut caster, frame, &mut sink)?;
            Ok(sink.hash())
        })
        .collect()
}

pub(crate) fn metaball() -> Result<(), String> {
    let expected = host_hashes()?;
    step("metaball firmware for every target (a no-op when built)");
    build_firmware_examples("firmware", &["metaball"])?;
    for (target, machine) in FIRMWARE {
        step(&format!("metaball ray caster on QEMU {machine}, {target}"));
        let out = run_example(target, "firmware", "metaball")?;
        print!("{out}");
        let hashes = frame_hashes(&out);
        if hashes != expected {
            return Err(format!(
                "{target}: metaball frame hashes {hashes:08x?} differ from the host's {expected:08x?}"
            ));
        }
        println!(
            "metaball frame hashes equal the host's: {expected:08x?}; {:.1} M instructions (QEMU) per frame",
            mean_frame_instructions(&out) / 1e6
        );
    }
    Ok(())
}
