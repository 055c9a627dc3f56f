//! The patch firmware's frames: the host draws them through the same code
//! (`scanline3d_demo::patches`) and must reproduce the hashes the firmware prints on QEMU
//! (`cargo xtask patch` compares them run by run); the firmware's teapot is the exported
//! `teapot.bpt`.

use scanline3d::sink::HashSink;
use scanline3d_demo::byte_hash::{ByteHashSink, Tee};
use scanline3d_demo::patches::{self, PanelPatches};

/// Printed by `cargo run --profile firmware --example patch --target thumbv7em-none-eabihf`
/// for frames 0, 8 and 16; a change here means the drawn pixels changed.
const FIRMWARE_HASHES: [u32; 3] = [0xcae69d8b, 0x00bb68dd, 0x9b02ae26];
/// Their byte-wise hashes ([`ByteHashSink`]), which the firmware printed before the sink hashed
/// one word a pixel: equal here means the pixels did not change with the hash.
const BYTE_HASHES: [u32; 3] = [0x2232da87, 0x23e57419, 0xe3390f34];

#[test]
fn host_reproduces_firmware_patch_hashes() {
    let mut ws = Box::new(PanelPatches::new(
        embedded_graphics::pixelcolor::Rgb565::new(0, 0, 0),
    ));
    let (hashes, bytes): (Vec<u32>, Vec<u32>) = [0, 8, 16]
        .iter()
        .map(|&frame| {
            let mut sink = Tee(HashSink::new(), ByteHashSink::new());
            let stats = patches::render_frame(&mut ws, frame, &mut sink).unwrap();
            eprintln!("frame {frame}: {stats:?}");
            assert!(
                stats.frame.pixels_written > 5000,
                "frame {frame}: {stats:?}"
            );
            assert_eq!(
                (stats.overflows, stats.late, stats.frame.dropped),
                (0, 0, 0),
                "frame {frame}: {stats:?}"
            );
            (sink.0.hash(), sink.1.hash())
        })
        .unzip();
    assert_eq!(bytes, BYTE_HASHES, "{bytes:08x?}");
    assert_eq!(hashes, FIRMWARE_HASHES, "{hashes:08x?}");
}

#[test]
fn firmware_teapot_is_the_exported_model() {
    use scanline3d_sim::patch::{fixed, parse};
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let model = parse::load(&dir.join("sim/scenes/patches/teapot.bpt")).unwrap();
    let fixed = fixed::FixedPatches::new(&model).unwrap();
    assert_eq!(patches::MODEL.points(), &fixed.points[..]);
    assert!(patches::MODEL.weights().is_none() && fixed.weights.is_none());
}
