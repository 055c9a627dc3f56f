//! The fuzz harness for scene input: arbitrary bytes become a camera, a target size, render
//! settings and OBJ text, which go through the same loading and rendering as `sim render`.
//! Any `Err` is fine; a panic, hang or crash is a bug.
//!
//! The coverage-guided fuzzer (AFL++, through `cargo afl` on stable Rust) drives it from
//! `fuzz/`; `cargo xtask fuzz SECONDS` runs it, and the test command runs a short bounded
//! session. The tests here feed it the corpus and hand-written hostile inputs.

use crate::scene::{CameraSpec, MeshData};
use embedded_graphics::pixelcolor::Rgb888;
use scanline3d::scene::{Instance, Light, Scene, Transform};
use scanline3d::sink::{FnSink, Row};
use scanline3d::{Flat, Gouraud, RenderOptions, Workspace};

/// Bytes of render settings before the OBJ text.
pub const HEADER: usize = 16;

/// Largest fuzzed target (kept small so each input runs in well under a millisecond).
const MAX: usize = 64;

fn render<S: scanline3d::Shading, const SUB: u32>(
    scene: &Scene<'_>,
    w: usize,
    h: usize,
    cull: bool,
) {
    let mut ws: Box<Workspace<Rgb888, S, MAX, MAX, 2048, 256>> =
        Box::new(Workspace::new(Rgb888::new(0, 0, 0)));
    let mut rows = 0usize;
    let mut sink = FnSink(|row: Row<'_, Rgb888>| -> Result<(), ()> {
        assert_eq!(
            row.pixels.len(),
            w,
            "a row of the wrong length reached the sink"
        );
        assert_eq!(
            row.y as usize, rows,
            "rows must arrive once each, top to bottom"
        );
        rows += 1;
        Ok(())
    });
    let options = RenderOptions::default()
        .with_back_face_culling(cull)
        .with_sub_pixel_bits::<SUB>();
    if let Ok(stats) = ws.render_sized(w, h, scene, &options, &mut sink) {
        assert_eq!(
            (stats.rows as usize, rows),
            (h, h),
            "a complete frame delivers every row"
        );
        assert!(stats.pixels_written <= stats.fragments);
    }
}

/// Runs one fuzz input.
pub fn one(data: &[u8]) {
    let Some((head, obj)) = data.split_first_chunk::<HEADER>() else {
        return;
    };
    let b = |i: usize| head[i] as f64;
    let camera = CameraSpec {
        eye: [
            (b(0) - 128.0) / 8.0,
            (b(1) - 128.0) / 8.0,
            (b(2) - 128.0) / 8.0,
        ],
        target: [
            (b(3) - 128.0) / 32.0,
            (b(4) - 128.0) / 32.0,
            (b(5) - 128.0) / 32.0,
        ],
        up: [(b(13) - 128.0) / 64.0, 1.0, 0.0],
        fovy: b(6) * 0.75,
        near: b(7) / 64.0,
        far: b(7) / 64.0 + b(8) * 8.0,
    };
    let (w, h) = (1 + head[9] as usize % MAX, 1 + head[10] as usize % MAX);
    let (sub, cull, gouraud) = (head[11] % 4, head[12] & 1 == 1, head[12] & 2 == 2);
    let Ok(mesh) = MeshData::load_obj_bytes(obj, "fuzz input") else {
        return;
    };
    let Ok(view) = camera.fixed() else { return };
    let Ok(light) = Light::new(
        [(b(14) - 128.0) as f32, 1.0, (b(15) - 128.0) as f32],
        0.25,
        0.75,
    ) else {
        return;
    };
    let Ok(m) = mesh.mesh() else { return };
    let transform = Transform::rotation_y(b(14) as f32 * 0.05);
    let instances = [Instance {
        mesh: &m,
        transform,
    }];
    let scene = Scene {
        instances: &instances,
        camera: view,
        light,
    };
    match (sub, gouraud) {
        (0, false) => render::<Flat, 0>(&scene, w, h, cull),
        (1, false) => render::<Flat, 2>(&scene, w, h, cull),
        (2, false) => render::<Flat, 4>(&scene, w, h, cull),
        (_, false) => render::<Flat, 8>(&scene, w, h, cull),
        (0, true) => render::<Gouraud, 0>(&scene, w, h, cull),
        (_, true) => render::<Gouraud, 8>(&scene, w, h, cull),
    }
}

/// Seed inputs: every corpus scene behind a header that looks at it.
pub fn seeds() -> Vec<Vec<u8>> {
    crate::corpus::all()
        .iter()
        .map(|s| {
            let mut d = vec![
                128 + 20,
                128 + 12,
                128 + 30,
                128,
                128,
                128,
                70,
                10,
                4,
                47,
                39,
                2,
                1,
                128,
                120,
                140,
            ];
            d.extend(s.mesh.to_obj().bytes());
            d
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seeds_and_hostile_inputs_do_not_panic() {
        for seed in seeds() {
            one(&seed);
            // Twenty truncations and a scattering of corruptions of each seed.
            for cut in (0..seed.len()).step_by(seed.len() / 20 + 1) {
                one(&seed[..cut]);
            }
            let mut corrupt = seed.clone();
            for (i, b) in corrupt
                .iter_mut()
                .enumerate()
                .skip(HEADER)
                .step_by(seed.len() / 200 + 7)
            {
                *b = b"-9e99 nan inf 1e40 f/v 0 -1 \\n"[i % 30];
            }
            one(&corrupt);
        }
        let hostile: [&[u8]; 6] = [
            b"",
            b"\x94\x8c\x9e\x80\x80\x80\x46\x0a\x04\x2f\x27\x02\x01\x80\x78\x8c",
            b"\x94\x8c\x9e\x80\x80\x80\x46\x0a\x04\x2f\x27\x02\x01\x80\x78\x8cv nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
            b"\x94\x8c\x9e\x80\x80\x80\x46\x0a\x04\x2f\x27\x02\x01\x80\x78\x8cv 0 0 0\nf 1 1 1\nf 1 2 3\n",
            b"\x94\x8c\x9e\x80\x80\x80\xff\x00\xff\xff\xff\x03\x03\x00\x00\xffv 4096 4096 4096\nv -4096 -4096 -4096\nv 4096 -4096 0\nf 1 2 3\n",
            b"\x80\x80\x80\x80\x80\x80\x46\x0a\x04\x2f\x27\x02\x01\x80\x78\x8cv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3 1 2 3 1 2\n",
        ];
        for h in hostile {
            one(h);
        }
    }
}
