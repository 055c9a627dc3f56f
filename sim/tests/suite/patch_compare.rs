//! The library's fixed-point scanline patch renderer against the Bezier-clipping reference at
//! 240×240 and a tolerance of 0.5 px: coverage mismatches (share, and how far each lies from
//! the reference's silhouette, found by bisection with reference rays), patch-id mismatches
//! (how far from a reference id boundary), depth away from the boundaries, and colour: flat and
//! Gouraud shading against the reference's exactly lit hits (PSNR over the pixels whose ids
//! agree). The trimmed sheet from random views: coverage mismatches only next to the
//! reference's trim curves and silhouette.

use embedded_graphics::pixelcolor::RgbColor;
use scanline3d_sim::patch::fixed::{render_fixed, FixedPatchRender, PatchShading, PATCH_COLOR};
use scanline3d_sim::patch::render::{distance_to_change, Reference, BASE_COLOR};
use scanline3d_sim::patch::{parse, PatchModel};
use scanline3d_sim::reference::Image;
use scanline3d_sim::scene::{CameraSpec, LightSpec};

const W: usize = 240;
const H: usize = 240;
const TOLERANCE: f64 = 0.5;

fn load(name: &str) -> PatchModel {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/patches");
    parse::load(&dir.join(name)).unwrap()
}

fn camera(eye: [f64; 3], target: [f64; 3], up: [f64; 3]) -> CameraSpec {
    CameraSpec {
        eye,
        target,
        up,
        fovy: 45.0,
        near: 0.1,
        far: 100.0,
    }
}

/// Whether every pixel within `r` rows and columns of `(x, y)` has the same reference id.
fn same_id_around(ids: &[i32], x: usize, y: usize, r: usize) -> bool {
    let id = ids[y * W + x];
    (y.saturating_sub(r)..(y + r + 1).min(H))
        .all(|yy| (x.saturating_sub(r)..(x + r + 1).min(W)).all(|xx| ids[yy * W + xx] == id))
}

struct Figures {
    coverage: usize,
    coverage_far: f64,
    ids: usize,
    ids_far: f64,
    depth: f64,
    color_mean: f64,
    psnr_gouraud: f64,
    psnr_flat: f64,
}

/// Colour PSNR (dB, peak 255) of `got` against `want` over the pixels where both show the
/// same patch.
fn psnr(got: &Image, want: &Image) -> f64 {
    let (mut sum, mut count) = (0.0, 0usize);
    for i in 0..got.ids.len() {
        if got.ids[i] >= 0 && got.ids[i] == want.ids[i] {
            for c in 0..3 {
                let d = got.color[i][c] as f64 - want.color[i][c] as f64;
                sum += d * d;
            }
            count += 3;
        }
    }
    let mse = sum / count.max(1) as f64;
    10.0 * (255.0 * 255.0 / mse).log10()
}

/// The fixed renderer at `TOLERANCE`, two-sided; its late, dropped and capped counts are 0.
fn fixed(model: &PatchModel, cam: &CameraSpec, shading: PatchShading) -> FixedPatchRender {
    let light = LightSpec::default();
    let r = render_fixed(model, cam, &light, (W, H), TOLERANCE, false, shading).unwrap();
    assert_eq!(
        (r.stats.late, r.stats.frame.dropped, r.stats.capped),
        (0, 0, 0)
    );
    r
}

fn compare(model: &PatchModel, cam: &CameraSpec) -> Figures {
    let light = LightSpec::default();
    let flat = fixed(model, cam, PatchShading::Flat);
    let fixed = fixed(model, cam, PatchShading::Gouraud);
    let reference = Reference::new(
        model.clone(),
        cam.reference().unwrap(),
        light.reference().unwrap(),
    );
    let (expected, stats) = reference.render(W, H);
    assert_eq!(stats.capped, 0);
    let covered = |x: f64, y: f64| i64::from(reference.cast(x, y, W, H).0.is_some());
    let id = |x: f64, y: f64| reference.cast(x, y, W, H).0.map_or(-1, |h| h.patch as i64);
    let mut f = Figures {
        coverage: 0,
        coverage_far: 0.0,
        ids: 0,
        ids_far: 0.0,
        depth: 0.0,
        color_mean: 0.0,
        psnr_gouraud: psnr(&fixed.image, &expected),
        psnr_flat: psnr(&flat.image, &expected),
    };
    let mut colored = 0;
    for y in 0..H {
        for x in 0..W {
            let i = y * W + x;
            let centre = (x as f64 + 0.5, y as f64 + 0.5);
            let (got, want) = (fixed.image.ids[i], expected.ids[i]);
            if (got >= 0) != (want >= 0) {
                f.coverage += 1;
                f.coverage_far = f
                    .coverage_far
                    .max(distance_to_change(&covered, centre, 4.0));
            } else if got != want {
                f.ids += 1;
                f.ids_far = f.ids_far.max(distance_to_change(&id, centre, 4.0));
            } else if got >= 0 && same_id_around(&expected.ids, x, y, 2) {
                let (a, b) = (fixed.image.depth[i] as f64, expected.depth[i] as f64);
                f.depth = f.depth.max((a - b).abs() / b);
                f.color_mean += (0..3)
                    .map(|c| (fixed.image.color[i][c] as f64 - expected.color[i][c] as f64).abs())
                    .sum::<f64>()
                    / 3.0;
                colored += 1;
            }
        }
    }
    f.color_mean /= colored.max(1) as f64;
    f
}

#[test]
fn reference_and_fixed_renderer_share_the_base_colour() {
    assert_eq!(
        BASE_COLOR,
        [PATCH_COLOR.r(), PATCH_COLOR.g(), PATCH_COLOR.b()].map(f64::from)
    );
}

#[test]
fn fixed_renderer_against_the_reference_at_half_a_pixel() {
    // Least colour PSNR (dB) where ids agree, Gouraud and flat: the measured figures (sphere
    // 51.9 and 45.0 dB, teapot 47.6 and 45.3 dB) rounded down to whole dB, less 1 dB. The
    // sphere's rim, where edge-on triangles must show the side they turn to the camera,
    // fails this (38.5 dB) when the side comes from a coarser test than the rasterizer's.
    let cases = [
        (
            "sphere.bpt",
            camera([2.0, 1.5, 2.5], [0.0; 3], [0.0, 1.0, 0.0]),
            (50.0, 44.0),
        ),
        (
            "teapot.bpt",
            camera([4.0, -7.0, 3.0], [0.2, 0.0, 1.3], [0.0, 0.0, 1.0]),
            (46.0, 44.0),
        ),
    ];
    for (name, cam, (gouraud_min, flat_min)) in cases {
        let f = compare(&load(name), &cam);
        let share = f.coverage as f64 / (W * H) as f64;
        println!(
            "{name} eye {:?}: coverage mismatches {} ({:.3} %), farthest {:.3} px from the silhouette; id mismatches {}, farthest {:.3} px from an id boundary; depth {:.1e} relative; Gouraud colour mean difference {:.2}/255; PSNR where ids agree: Gouraud {:.1} dB, flat {:.1} dB",
            cam.eye, f.coverage, 100.0 * share, f.coverage_far, f.ids, f.ids_far, f.depth, f.color_mean, f.psnr_gouraud, f.psnr_flat
        );
        // The bound: at most 0.5 % of the pixels.
        assert!(share <= 0.005, "{name}: {share}");
        // A coverage mismatch is a centre between the exact silhouette and the triangles'
        // edge: no farther from the silhouette than the tolerance (the chords' distance from
        // the surface) plus 1/16 px for the snapped vertices, the sub-pixel grid at 4 bits.
        assert!(
            f.coverage_far <= TOLERANCE + 1.0 / 16.0,
            "{name}: {}",
            f.coverage_far
        );
        // The same for a centre given another patch's id, from the reference's id boundaries
        // (patch edges, and where the teapot's spout and handle enter the body).
        assert!(f.ids_far <= TOLERANCE + 1.0 / 16.0, "{name}: {}", f.ids_far);
        // Gouraud from exactly lit vertices: a fraction of a level on average.
        assert!(f.color_mean < 1.0, "{name}: {}", f.color_mean);
        // Shading against the exact normals, every pixel whose id agrees (patch edges and
        // the teapot's creases included).
        assert!(f.psnr_gouraud >= gouraud_min, "{name}: {}", f.psnr_gouraud);
        assert!(f.psnr_flat >= flat_min, "{name}: {}", f.psnr_flat);
    }
}

/// From inside the sphere, close to its wall, the near plane cutting the wall: the triangles
/// the near plane cuts show their back, and their colours are those of the back (lit with
/// the normal reversed, as the reference lights the inside) after clipping. Measured 53.2 and
/// 53.7 dB; with the front's colours clipped instead, 18.7 and 17.4 dB.
#[test]
fn clipped_triangles_show_the_side_they_turn_to_the_camera() {
    let model = load("sphere.bpt");
    let light = LightSpec::default();
    for target in [[1.0, -1.0, 0.0], [0.0, -1.2, -0.5]] {
        let cam = CameraSpec {
            eye: [0.391, -0.695, -0.478],
            target,
            up: [0.0, 1.0, 0.0],
            fovy: 60.0,
            near: 0.1,
            far: 100.0,
        };
        let fixed = render_fixed(
            &model,
            &cam,
            &light,
            (W, H),
            TOLERANCE,
            false,
            PatchShading::Gouraud,
        )
        .unwrap();
        let reference = Reference::new(
            model.clone(),
            cam.reference().unwrap(),
            light.reference().unwrap(),
        );
        let (expected, _) = reference.render(W, H);
        let db = psnr(&fixed.image, &expected);
        println!(
            "target {target:?}: {} triangles clipped, PSNR where ids agree {db:.1} dB",
            fixed.stats.frame.clipped
        );
        assert!(fixed.stats.frame.clipped > 100, "{:?}", fixed.stats);
        assert!(db >= 52.0, "target {target:?}: {db} dB");
    }
}

/// A small deterministic generator for views.
fn lcg(state: &mut u64) -> f64 {
    *state = state
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    (*state >> 11) as f64 / (1u64 << 53) as f64
}

/// The trimmed sheet (a hole, an island in it) from random views on either side, at three
/// tolerances: a pixel covered by one renderer and not the other lies within the tolerance
/// plus 1/16 px (the snapped vertices) of a place where the reference's coverage changes:
/// a trim curve or the silhouette. None elsewhere.
#[test]
fn trimmed_holes_appear_where_the_trim_says() {
    let model = load("trimmed.bpt");
    let light = LightSpec::default();
    let (w, h) = (200, 200);
    let mut seed = 22;
    let mut worst = 0.0f64;
    for view in 0..6 {
        // Eyes 2.6 to 3.6 from the sheet, at least 30° above or below its plane.
        let (a, z) = (
            std::f64::consts::TAU * lcg(&mut seed),
            0.5 + 0.5 * lcg(&mut seed),
        );
        let side = if view % 2 == 0 { 1.0 } else { -1.0 };
        let r = 2.6 + lcg(&mut seed);
        let horizontal = (1.0 - z * z).sqrt();
        let eye = [
            r * horizontal * a.cos(),
            r * horizontal * a.sin(),
            side * r * z,
        ];
        let target = [0.2 * lcg(&mut seed) - 0.1, 0.2 * lcg(&mut seed) - 0.1, 0.2];
        let cam = camera(eye, target, [0.0, 1.0, 0.0]);
        let reference = Reference::new(
            model.clone(),
            cam.reference().unwrap(),
            light.reference().unwrap(),
        );
        let (want, _) = reference.render(w, h);
        let covered = |x: f64, y: f64| i64::from(reference.cast(x, y, w, h).0.is_some());
        for tolerance in [0.5, 1.0, 2.0] {
            let got = render_fixed(
                &model,
                &cam,
                &light,
                (w, h),
                tolerance,
                false,
                PatchShading::Flat,
            )
            .unwrap();
            let s = got.stats;
            assert_eq!((s.late, s.frame.dropped, s.trim_overflows), (0, 0, 0));
            assert!(s.trim_cut > 0, "view {view}: no triangle was cut");
            let (mut mismatches, mut far) = (0usize, 0.0f64);
            for y in 0..h {
                for x in 0..w {
                    let i = y * w + x;
                    if (got.image.ids[i] >= 0) != (want.ids[i] >= 0) {
                        mismatches += 1;
                        let centre = (x as f64 + 0.5, y as f64 + 0.5);
                        far = far.max(distance_to_change(&covered, centre, 4.0));
                    }
                }
            }
            let share = mismatches as f64 / (w * h) as f64;
            println!(
                "trimmed sheet, view {view} eye {eye:.2?}, tolerance {tolerance} px: {} triangles ({} cut by trims), coverage mismatches {mismatches} ({:.3} %), farthest {far:.3} px from a trim curve or the silhouette",
                s.frame.triangles_in, s.trim_cut, 100.0 * share
            );
            assert!(
                far <= tolerance + 1.0 / 16.0,
                "view {view}, {tolerance}: {far}"
            );
            assert!(share <= 0.005, "view {view}, {tolerance}: {share}");
            worst = worst.max(far);
        }
    }
    println!("farthest of all: {worst:.3} px");
}

/// Random single patches, polynomial and rational (the first cases of
/// `sim/examples/patch_random.rs`): a pixel covered by one renderer and not the other lies
/// within the tolerance plus 1/16 px of a change of the reference's coverage, unless the
/// renderer reports a capped patch. Cases 12, 48, 67 and 166 fail (up to 0.68 px beyond) when
/// the levels ignore the weights.
#[test]
fn random_patches_follow_the_tolerance() {
    use scanline3d_sim::draw::PatchDraw;
    use scanline3d_sim::patch::compare::coverage;
    let mut d = PatchDraw::draws();
    let (mut frames, mut rational) = (0, 0);
    for case in 0..240 {
        let (model, camera, tolerance) = PatchDraw::case(&mut d, case);
        let Some(c) = coverage(&model, &camera, tolerance, 48) else {
            continue;
        };
        if !c.capped {
            let far = c.farthest();
            assert!(far <= tolerance + 1.0 / 16.0, "case {case}: {far} px");
            frames += 1;
            rational += model
                .patches
                .iter()
                .any(|p| p.weights.iter().any(|&w| w != 1.0)) as u32;
        }
    }
    assert!(rational > 30, "{rational} rational frames");
    println!("{frames} frames checked, {rational} of them rational");
    assert!(frames > 100, "{frames} frames");
}
