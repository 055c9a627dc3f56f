//! The fuzz harness for scene input: arbitrary bytes become a camera, a target size, render
//! settings and OBJ text, which go through the same loading and rendering as `sim render`;
//! or, with the header's [`TRACED`] bit, a traced scene's text, which goes through `sim
//! trace`'s parsing, the f64 tracer, the fixed-point tracer (pure and hybrid, which must give
//! the same image) and the firmware export. Any `Err` is fine; a panic, hang or crash is a bug.
//!
//! The coverage-guided fuzzer (AFL++, through `cargo afl` on stable Rust) drives it from
//! `fuzz/`; `cargo xtask fuzz SECONDS` runs it, and the test command runs a short bounded
//! session. The tests here feed it the corpus and hand-written hostile inputs.

use crate::scene::{CameraSpec, MeshData};
use crate::trace::accel::Structure;
use crate::trace::fixed::{self, Accel, FixedScene};
use crate::trace::scene::TracedScene;
use crate::trace::whitted::Limits;
use embedded_graphics::pixelcolor::Rgb888;
use scanline3d::scene::{Instance, Light, Scene, Transform};
use scanline3d::sink::{FnSink, Row};
use scanline3d::{Flat, Gouraud, RenderOptions, Workspace};

/// Bytes of render settings before the OBJ text.
pub const HEADER: usize = 16;

/// Largest fuzzed target (kept small so each input runs in well under a millisecond).
const MAX: usize = 64;

/// The bit of header byte 12 that makes the text after the header a traced scene.
pub const TRACED: u8 = 4;

/// Largest fuzzed traced image (every pixel is a ray tree, traced four times).
const TRACED_MAX: usize = 12;

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

/// The camera a header describes.
fn camera_of(head: &[u8; HEADER]) -> CameraSpec {
    let b = |i: usize| head[i] as f64;
    CameraSpec {
        eye: [0, 1, 2].map(|i| (b(i) - 128.0) / 8.0),
        target: [3, 4, 5].map(|i| (b(i) - 128.0) / 32.0),
        up: [(b(13) - 128.0) / 64.0, 1.0, 0.0],
        fovy: b(6) * 0.75,
        near: b(7) / 64.0,
        far: b(7) / 64.0 + b(8) * 8.0,
    }
}

/// Runs one fuzz input.
pub fn one(data: &[u8]) {
    let Some((head, obj)) = data.split_first_chunk::<HEADER>() else {
        return;
    };
    let camera = camera_of(head);
    let b = |i: usize| head[i] as f64;
    if head[12] & TRACED != 0 {
        traced(head, &camera, obj);
        return;
    }
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

/// Traces `text` (a traced scene; `mesh` lines read from `sim/scenes/`) through `camera` at
/// a size, depth limit, threshold and acceleration structure from `head`: the f64 tracer, the
/// fixed-point tracer pure and hybrid, and the export of the fixed-point scene. Whether the
/// fixed-point tracer traced the frame (what the seeds must reach).
fn traced(head: &[u8; HEADER], camera: &CameraSpec, text: &[u8]) -> bool {
    let Ok(text) = std::str::from_utf8(text) else {
        return false;
    };
    let dir = crate::trace::corpus::scenes_dir();
    let Ok(scene) = TracedScene::parse(text, &dir, "fuzz input") else {
        return false;
    };
    let (w, h) = (
        1 + head[9] as usize % TRACED_MAX,
        1 + head[10] as usize % TRACED_MAX,
    );
    // Depths beyond both tracers' limits and thresholds above 1 are errors to reach too.
    let limits = Limits {
        max_depth: u32::from(head[11] % 8),
        threshold: f64::from(head[15]) / 128.0,
    };
    let structure = Structure::ALL[head[14] as usize % Structure::ALL.len()];
    if let Ok(image) = crate::trace::render::render(&scene, camera, w, h, limits, structure) {
        assert_eq!(
            image.ids.len(),
            w * h,
            "the f64 tracer's image has every pixel"
        );
    }
    let Ok(fixed_scene) = FixedScene::new(&scene) else {
        return false;
    };
    let _ = fixed::export_source(&fixed_scene, "fuzz");
    let Ok(options) = fixed::options(limits.max_depth, limits.threshold) else {
        return false;
    };
    let accel = [Accel::None, Accel::Bvh, Accel::Grid][head[14] as usize % 3];
    let pure = fixed::render(&fixed_scene, camera, w, h, options, accel, false);
    let hybrid = fixed::render(&fixed_scene, camera, w, h, options, accel, true);
    match (pure, hybrid) {
        (Ok(pure), Ok(hybrid)) => {
            assert_eq!(
                pure.ids.len(),
                w * h,
                "the fixed tracer's image has every pixel"
            );
            assert_eq!(
                pure.ids, hybrid.ids,
                "hybrid primary ids differ from the pure tracer's"
            );
            assert_eq!(
                pure.colour, hybrid.colour,
                "hybrid colours differ from the pure tracer's"
            );
            assert_eq!(
                pure.shadow, hybrid.shadow,
                "hybrid shadow masks differ from the pure tracer's"
            );
            true
        }
        (Err(_), Err(_)) => false,
        (pure, hybrid) => panic!(
            "the pure tracer and the hybrid mode disagree on the camera: {:?} / {:?}",
            pure.err(),
            hybrid.err()
        ),
    }
}

/// The header byte for a camera coordinate `v` under `one(data)`'s mapping `(b − 128) / scale`
/// (rounded, clamped to a byte).
fn header_byte(v: f64, scale: f64) -> u8 {
    (128.0 + v * scale).round().clamp(0.0, 255.0) as u8
}

/// Seed inputs: every corpus scene behind a header that looks at it, then every traced corpus
/// scene behind a header near its first camera.
pub fn seeds() -> Vec<Vec<u8>> {
    let mut seeds = mesh_seeds();
    for corpus in crate::trace::corpus::all() {
        let Ok(text) = std::fs::read(corpus.path()) else {
            continue;
        };
        let Some((_, c)) = corpus.cameras.first() else {
            continue;
        };
        let mut d = vec![
            header_byte(c.eye[0], 8.0),
            header_byte(c.eye[1], 8.0),
            header_byte(c.eye[2], 8.0),
            header_byte(c.target[0], 32.0),
            header_byte(c.target[1], 32.0),
            header_byte(c.target[2], 32.0),
            (c.fovy / 0.75).round() as u8,
            7,
            12,
            11,
            9,
            4,
            TRACED,
            128,
            1,
            1,
        ];
        d.extend(text);
        seeds.push(d);
    }
    seeds
}

/// The mesh seeds: every corpus scene behind a header that looks at it.
fn mesh_seeds() -> Vec<Vec<u8>> {
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

    #[test]
    fn traced_seeds_reach_the_fixed_point_tracer() {
        let traced_seeds: Vec<_> = seeds()
            .into_iter()
            .filter(|s| s.get(12).is_some_and(|b| b & TRACED != 0))
            .collect();
        assert_eq!(traced_seeds.len(), crate::trace::corpus::all().len());
        for seed in traced_seeds {
            let (head, text) = seed.split_first_chunk::<HEADER>().unwrap();
            let camera = camera_of(head);
            assert!(
                traced(head, &camera, text),
                "seed {:?} does not reach the fixed-point tracer",
                &head[..]
            );
        }
    }
}
