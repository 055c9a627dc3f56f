//! Bit-identical output across machines: the host renders the demo orbit through the same
//! hashing panel model as the firmware, and must reproduce the exact frame hashes the firmware
//! prints on QEMU (thumbv7em and thumbv6m; `cargo xtask test` compares them run by run).

use scanline3d_demo::{self as demo, PanelWorkspace};

/// Printed by `cargo run --release --example firmware --target thumbv7em-none-eabihf` (and the
/// same on thumbv6m). Integer arithmetic makes them machine-independent; a change here means
/// the rendered pixels changed.
const FIRMWARE_HASHES: [u32; demo::ORBIT_FRAMES as usize] = [
    0xd2d1f78c, 0xbb40b2d0, 0xf33efadb, 0xecc76742, 0xc2454ea1, 0x85586422, 0xabe6cbad, 0xe157ee21,
];

#[test]
fn host_reproduces_firmware_frame_hashes() {
    let mut ws = Box::new(PanelWorkspace::new(demo::BACKGROUND.into()));
    let instances = demo::instances();
    let hashes: Vec<u32> = (0..demo::ORBIT_FRAMES)
        .map(|frame| {
            let scene = demo::scene(&instances, frame, demo::ORBIT_FRAMES).unwrap();
            let out = demo::render_panel_frame(&mut ws, &scene).unwrap();
            assert!(out.stats.is_complete());
            out.hash
        })
        .collect();
    assert_eq!(hashes, FIRMWARE_HASHES, "{hashes:08x?}");
}
