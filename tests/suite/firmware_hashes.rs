//! Bit-identical output across machines: the host renders the demo orbit through the same
//! hashing panel model as the firmware, and must reproduce the exact frame hashes the firmware
//! prints on QEMU (thumbv7em and thumbv6m; `cargo xtask test` compares them run by run).

use scanline3d::sink::HashSink;
use scanline3d::RenderOptions;
use scanline3d_demo::byte_hash::{ByteHashSink, Tee};
use scanline3d_demo::{self as demo, PanelWorkspace};

/// Printed by `cargo run --release --example firmware --target thumbv7em-none-eabihf` (and the
/// same on thumbv6m). Integer arithmetic makes them machine-independent; a change here means
/// the rendered pixels changed.
const FIRMWARE_HASHES: [u32; demo::ORBIT_FRAMES as usize] = [
    0xd2b4bae4, 0xc100d4eb, 0xa15efaa5, 0x92e5fc1b, 0xed8d3eae, 0x037c5081, 0xbbe90157, 0xbdbab4c8,
];

/// The same frames' byte-wise hashes ([`ByteHashSink`]), which the firmware printed before the
/// sink hashed one word a pixel: equal here means the pixels did not change with the hash.
const BYTE_HASHES: [u32; demo::ORBIT_FRAMES as usize] = [
    0xd2d1f78c, 0xbb40b2d0, 0xf33efadb, 0xecc76742, 0xc2454ea1, 0x85586422, 0xabe6cbad, 0xe157ee21,
];

#[test]
fn host_reproduces_firmware_frame_hashes() {
    let mut ws = Box::new(PanelWorkspace::new(demo::BACKGROUND.into()));
    let instances = demo::instances();
    let (hashes, bytes): (Vec<u32>, Vec<u32>) = (0..demo::ORBIT_FRAMES)
        .map(|frame| {
            let scene = demo::scene(&instances, frame, demo::ORBIT_FRAMES).unwrap();
            let out = demo::render_panel_frame(&mut ws, &scene).unwrap();
            assert!(out.stats.is_complete());
            // The same frame again into both hashes.
            let mut both = Tee(HashSink::new(), ByteHashSink::new());
            ws.render(&scene, &RenderOptions::default(), &mut both)
                .unwrap();
            assert_eq!(both.0.hash(), out.hash, "frame {frame}");
            (out.hash, both.1.hash())
        })
        .unzip();
    assert_eq!(bytes, BYTE_HASHES, "{bytes:08x?}");
    assert_eq!(hashes, FIRMWARE_HASHES, "{hashes:08x?}");
}
