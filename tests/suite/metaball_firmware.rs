//! The firmware's metaball frames: the host casts them through the same code
//! (`scanline3d_demo::metaballs`) and must reproduce the hashes the firmware prints on QEMU
//! (`cargo xtask metaball` compares them run by run). The balls are `sim export`'s of
//! `six.meta` (`sim/tests/suite/metaball_cli.rs` checks the generated file is up to date).

use scanline3d::sink::HashSink;
use scanline3d_demo::byte_hash::{ByteHashSink, Tee};
use scanline3d_demo::metaballs::{self, PanelCaster};

/// Printed by `cargo run --profile firmware --example metaball --target thumbv7em-none-eabihf`
/// for frames 0, 2 and 4; a change here means the cast pixels changed.
const FIRMWARE_HASHES: [u32; 3] = [0x2460db05, 0x8fcbaf8c, 0x57c078d6];
/// Their byte-wise hashes ([`ByteHashSink`]), which the firmware printed before the sink hashed
/// one word a pixel: equal here means the pixels did not change with the hash.
const BYTE_HASHES: [u32; 3] = [0xb0152c6f, 0x94c6e05f, 0x8c32f6bc];

#[test]
fn host_reproduces_firmware_metaball_hashes() {
    let mut caster = Box::new(PanelCaster::new(
        embedded_graphics::pixelcolor::Rgb565::new(0, 0, 0),
    ));
    let (hashes, bytes): (Vec<u32>, Vec<u32>) = [0, 2, 4]
        .iter()
        .map(|&frame| {
            let mut sink = Tee(HashSink::new(), ByteHashSink::new());
            let stats = metaballs::render_frame(&mut caster, frame, &mut sink).unwrap();
            assert!(stats.hits > 1000, "frame {frame}: {stats:?}");
            (sink.0.hash(), sink.1.hash())
        })
        .unzip();
    assert_eq!(bytes, BYTE_HASHES, "{bytes:08x?}");
    assert_eq!(hashes, FIRMWARE_HASHES, "{hashes:08x?}");
}

/// Printed by the same example built with `--cfg scanline3d_meta="poly16"` (`cargo xtask
/// metaball` runs it): frames 0, 2, 4 polygonized on 16 cells per axis and drawn by the span
/// z-buffer.
const POLY16_FIRMWARE_HASHES: [u32; 3] = [0xc66886cc, 0xcd4d5db5, 0x49fdc7eb];
/// Their byte-wise hashes, as [`BYTE_HASHES`].
const POLY16_BYTE_HASHES: [u32; 3] = [0xbbd42de6, 0x2422b085, 0xd7598d1d];

#[test]
fn host_reproduces_firmware_polygonized_hashes() {
    let mut poly: Box<metaballs::Poly16> = Box::new(metaballs::Poly16::new(
        embedded_graphics::pixelcolor::Rgb565::new(0, 0, 0),
    ));
    let (hashes, bytes): (Vec<u32>, Vec<u32>) = [0, 2, 4]
        .iter()
        .map(|&frame| {
            let mesh = poly.polygonize(frame).unwrap();
            assert!(mesh.triangles > 1000, "frame {frame}: {mesh:?}");
            let mut sink = Tee(HashSink::new(), ByteHashSink::new());
            let stats = poly.draw(&mut sink).unwrap();
            assert!(stats.pixels_written > 1000, "frame {frame}: {stats:?}");
            (sink.0.hash(), sink.1.hash())
        })
        .unzip();
    assert_eq!(bytes, POLY16_BYTE_HASHES, "{bytes:08x?}");
    assert_eq!(hashes, POLY16_FIRMWARE_HASHES, "{hashes:08x?}");
}
