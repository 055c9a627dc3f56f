//! The fuzz harness for scene input: arbitrary bytes become a camera, a target size, render
//! settings and OBJ text, which go through the same loading and rendering as `sim render`;
//! or, with the header's [`TRACED`] bit, a traced scene's text, which goes through `sim
//! trace`'s parsing, the f64 tracer, the fixed-point tracer (pure and hybrid, which must give
//! the same image) and the firmware export; with [`PATCHES`], a Bezier patch model through
//! the parser, the fixed-point patch renderer, the Bezier-clipping reference and the export;
//! with [`METABALLS`], a metaball scene through the parser, the fixed-point caster, the
//! polygonizer, the f64 reference and the export. Any `Err` is fine; a panic, hang or crash is
//! a bug.
//!
//! The coverage-guided fuzzer (AFL++, through `cargo afl` on stable Rust) drives it from
//! `fuzz/`; `cargo xtask fuzz SECONDS` runs it, and the test command runs a short bounded
//! session. The tests here feed it the corpus and hand-written hostile inputs.

use crate::scene::{CameraSpec, LightSpec, MeshData};
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

/// The bit of header byte 12 that makes the text after the header a Bezier patch model.
pub const PATCHES: u8 = 8;

/// The bit of header byte 12 that makes the text after the header a metaball scene.
pub const METABALLS: u8 = 16;

/// Largest fuzzed image of a traced scene, patches or metaballs (every pixel a ray tree, or a
/// reference's root search).
const SMALL_MAX: usize = 12;

/// Most objects, patches or metaballs a scene may have for the searches whose work per pixel
/// grows with their number (brute-force tracing, the patch and metaball references).
const SMALL_SCENE: usize = 64;

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
    if head[12] & PATCHES != 0 {
        patches(head, &camera, obj);
        return;
    }
    if head[12] & METABALLS != 0 {
        metaballs(head, &camera, obj);
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
    let (w, h) = small_size(head);
    // Depths beyond both tracers' limits and thresholds above 1 are errors to reach too.
    let limits = Limits {
        max_depth: u32::from(head[11] % 8),
        threshold: f64::from(head[15]) / 128.0,
    };
    // Brute force (every ray testing every object) only for small scenes: for the corpus's
    // 1,280-triangle mesh it makes an input take seconds, which the fuzzer reports as a hang.
    let few = scene.objects.len() <= SMALL_SCENE;
    let choice = head[14] as usize;
    let structure = if few {
        Structure::ALL[choice % 4]
    } else {
        Structure::ALL[1 + choice % 3]
    };
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
    let accel = if few {
        [Accel::None, Accel::Bvh, Accel::Grid][choice % 3]
    } else {
        [Accel::Bvh, Accel::Grid][choice % 2]
    };
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

/// The image size of a traced scene, patches or metaballs.
fn small_size(head: &[u8; HEADER]) -> (usize, usize) {
    (
        1 + head[9] as usize % SMALL_MAX,
        1 + head[10] as usize % SMALL_MAX,
    )
}

/// Renders `text` (a Bezier patch model) through `camera` with the library's patch renderer
/// (flat or Gouraud, culled or two-sided, at a flatness from `head`) and the Bezier-clipping
/// reference, and exports it. Whether the fixed-point renderer drew the frame.
fn patches(head: &[u8; HEADER], camera: &CameraSpec, text: &[u8]) -> bool {
    use crate::patch::{fixed, parse, render::Reference};
    let Ok(text) = std::str::from_utf8(text) else {
        return false;
    };
    let Ok(model) = parse::parse(text, "fuzz input") else {
        return false;
    };
    let (w, h) = small_size(head);
    if let Ok(fixed_model) = fixed::FixedPatches::new(&model) {
        let _ = fixed::export_source(&fixed_model, fixed::PATCH_COLOR, "fuzz");
    }
    let shading = if head[12] & 2 != 0 {
        fixed::PatchShading::Gouraud
    } else {
        fixed::PatchShading::Flat
    };
    // Flatness from 1/64 to 4 pixels.
    let tolerance = f64::from(head[15]) / 64.0 + 1.0 / 64.0;
    let light = LightSpec::default();
    let drawn = fixed::render_fixed(
        &model,
        camera,
        &light,
        (w, h),
        tolerance,
        head[12] & 1 != 0,
        shading,
    );
    if let Ok(r) = &drawn {
        assert_eq!(r.image.ids.len(), w * h, "the patch image has every pixel");
    }
    let small = model.patches.len() <= SMALL_SCENE;
    if let (true, Ok(cam), Ok(light)) = (small, camera.reference(), light.reference()) {
        let (image, _) = Reference::new(model, cam, light).render(w, h);
        assert_eq!(
            image.ids.len(),
            w * h,
            "the patch reference has every pixel"
        );
    }
    drawn.is_ok()
}

/// Renders `text` (a metaball scene) at an animation frame from `head` through `camera` with
/// the fixed-point caster, the polygonizer on a small grid and the f64 reference, and exports
/// it. Whether the caster drew the frame.
fn metaballs(head: &[u8; HEADER], camera: &CameraSpec, text: &[u8]) -> bool {
    use crate::metaball::{compare, fixed::FixedMeta, polygonized, reference::Reference};
    let Ok(text) = std::str::from_utf8(text) else {
        return false;
    };
    let Ok(scene) = crate::metaball::MetaScene::parse(text, "fuzz input") else {
        return false;
    };
    let (w, h) = small_size(head);
    let frame = u32::from(head[11]);
    if let Ok(fixed_scene) = FixedMeta::new(&scene) {
        let _ = fixed_scene.export_source("fuzz");
    }
    let cast = compare::render_fixed(&scene, frame, camera, w, h);
    if let Ok((image, _)) = &cast {
        assert_eq!(image.ids.len(), w * h, "the cast image has every pixel");
    }
    // The three smallest grids: a large one costs milliseconds an input.
    let cells = polygonized::GRIDS[head[14] as usize % 3];
    let _ = polygonized::render_polygonized(&scene, frame, camera, (w, h), cells);
    let reference = camera
        .reference()
        .and_then(|cam| Reference::new(&scene, frame, cam));
    if let (true, Ok(reference)) = (scene.balls.len() <= SMALL_SCENE, reference) {
        let (image, _) = reference.render(w, h);
        assert_eq!(
            image.ids.len(),
            w * h,
            "the metaball reference has every pixel"
        );
    }
    cast.is_ok()
}

/// The header byte for a camera coordinate `v` under `one(data)`'s mapping `(b − 128) / scale`
/// (rounded, clamped to a byte).
fn header_byte(v: f64, scale: f64) -> u8 {
    (128.0 + v * scale).round().clamp(0.0, 255.0) as u8
}

/// A seed: a header for camera `c` and `mode` (header byte 12) before `text`.
fn seed(c: &CameraSpec, mode: u8, text: &[u8]) -> Vec<u8> {
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
        mode,
        128,
        1,
        1,
    ];
    d.extend(text);
    d
}

/// Seed inputs: every corpus scene behind a header that looks at it, then every traced corpus
/// scene, patch model and metaball scene behind a header near its camera.
pub fn seeds() -> Vec<Vec<u8>> {
    let mut seeds = mesh_seeds();
    for corpus in crate::trace::corpus::all() {
        if let (Ok(text), Some((_, c))) = (std::fs::read(corpus.path()), corpus.cameras.first()) {
            seeds.push(seed(c, TRACED, &text));
        }
    }
    // Not the patch firmware's z-up camera (`patch::trade::camera`): a header's up vector is
    // near +y. From here each model is in view (the seeds' test checks they are drawn).
    let patch_camera = CameraSpec {
        eye: [0.0, 4.0, 9.0],
        target: [0.0, 1.0, 0.0],
        up: [0.0, 1.0, 0.0],
        fovy: 40.0,
        near: 0.1,
        far: 100.0,
    };
    for model in PATCH_MODELS {
        let path = crate::trace::corpus::scenes_dir()
            .join("patches")
            .join(model);
        if let Ok(text) = std::fs::read(path) {
            seeds.push(seed(&patch_camera, PATCHES, &text));
        }
    }
    for (_, text, c) in crate::metaball::corpus_texts() {
        seeds.push(seed(&c, METABALLS, text.as_bytes()));
    }
    seeds
}

/// The patch models in `sim/scenes/patches/` the fuzzer is seeded with.
const PATCH_MODELS: [&str; 3] = ["teapot.bpt", "sphere.bpt", "trimmed.bpt"];

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
    fn scene_seeds_reach_the_fixed_point_renderers() {
        type Run = fn(&[u8; HEADER], &CameraSpec, &[u8]) -> bool;
        let modes: [(u8, usize, Run); 3] = [
            (TRACED, crate::trace::corpus::all().len(), traced),
            (PATCHES, PATCH_MODELS.len(), patches),
            (METABALLS, crate::metaball::corpus_texts().len(), metaballs),
        ];
        let all = seeds();
        for (mode, count, run) in modes {
            let of_mode: Vec<_> = all.iter().filter(|s| s[12] == mode).collect();
            assert_eq!(of_mode.len(), count, "seeds of mode {mode}");
            for seed in of_mode {
                let (head, text) = seed.split_first_chunk::<HEADER>().unwrap();
                assert!(
                    run(head, &camera_of(head), text),
                    "seed {:?} of mode {mode} is not drawn",
                    &head[..]
                );
            }
        }
    }
}
