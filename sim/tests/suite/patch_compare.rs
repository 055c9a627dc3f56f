//! The library's fixed-point scanline patch renderer against the Bezier-clipping reference at
//! 240×240 and a tolerance of 0.5 px: coverage mismatches (share, and how far each lies from
//! the reference's silhouette, found by bisection with reference rays), patch-id mismatches
//! (how far from a reference id boundary), depth away from the boundaries, and Gouraud colour.

use embedded_graphics::pixelcolor::RgbColor;
use scanline3d_sim::patch::fixed::{render_fixed, PatchShading, PATCH_COLOR};
use scanline3d_sim::patch::render::{Reference, BASE_COLOR};
use scanline3d_sim::patch::{parse, PatchModel};
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

/// Distance (pixels) from screen point `(x, y)` to the nearest point where `class` (a
/// function of the reference's hit at a screen point) changes, searched in 16 directions out
/// to `reach` pixels in steps of 1/4 px and refined by bisection to 1/1000 px; `reach` if none
/// is found. An upper bound up to the angular resolution (about 2 %), and a change thinner
/// than a step can be stepped over, which also errs long.
fn distance_to_change(class: &dyn Fn(f64, f64) -> i64, (x, y): (f64, f64), reach: f64) -> f64 {
    let here = class(x, y);
    let mut best = reach;
    for k in 0..16 {
        let a = k as f64 * std::f64::consts::TAU / 16.0;
        let (dx, dy) = (a.cos(), a.sin());
        // March outwards to the first change, then bisect.
        let mut inside = 0.0;
        let mut step = 0.25;
        while step <= best {
            if class(x + dx * step, y + dy * step) != here {
                let mut outside = step;
                while outside - inside > 1e-3 {
                    let mid = (inside + outside) / 2.0;
                    if class(x + dx * mid, y + dy * mid) == here {
                        inside = mid;
                    } else {
                        outside = mid;
                    }
                }
                best = best.min(outside);
                break;
            }
            inside = step;
            step += 0.25;
        }
    }
    best
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
}

fn compare(model: &PatchModel, cam: &CameraSpec) -> Figures {
    let light = LightSpec::default();
    let fixed = render_fixed(
        model,
        cam,
        &light,
        (W, H),
        TOLERANCE,
        false,
        PatchShading::Gouraud,
    )
    .unwrap();
    assert_eq!(
        (
            fixed.stats.late,
            fixed.stats.frame.dropped,
            fixed.stats.capped
        ),
        (0, 0, 0)
    );
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
    let cases = [
        (
            "sphere.bpt",
            camera([2.0, 1.5, 2.5], [0.0; 3], [0.0, 1.0, 0.0]),
        ),
        (
            "teapot.bpt",
            camera([4.0, -7.0, 3.0], [0.2, 0.0, 1.3], [0.0, 0.0, 1.0]),
        ),
    ];
    for (name, cam) in cases {
        let f = compare(&load(name), &cam);
        let share = f.coverage as f64 / (W * H) as f64;
        println!(
            "{name} eye {:?}: coverage mismatches {} ({:.3} %), farthest {:.3} px from the silhouette; id mismatches {}, farthest {:.3} px from an id boundary; depth {:.1e} relative; Gouraud colour mean difference {:.2}/255",
            cam.eye, f.coverage, 100.0 * share, f.coverage_far, f.ids, f.ids_far, f.depth, f.color_mean
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
    }
}
