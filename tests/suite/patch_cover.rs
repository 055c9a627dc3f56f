//! Patch cover tests: a closed patch model drawn by the fixed-point patch renderer covers every
//! pixel centre well inside its silhouette (no cracks, no T-junction holes) over random views
//! and tolerances, and a full subdivision buffer degrades deterministically and is reported, as
//! does too little room to cut trimmed triangles.

use crate::common;

use embedded_graphics::pixelcolor::Rgb888;
use fixed::types::I16F16;
use scanline3d::patch::{
    ControlPoints, PatchColors, PatchModel, PatchScene, PatchStats, PatchWorkspace, Tolerance,
    TrimLoop, TrimPoint, Weight,
};
use scanline3d::scene::Transform;
use scanline3d::sink::{FnSink, Row, TriangleId};
use scanline3d::{Flat, RenderOptions};
use scanline3d_sim::scene::CameraSpec;

const W: usize = 96;
const H: usize = 96;
const SUB: u32 = 4;

/// A closed, outward-oriented "puffy cube": each face of [−1, 1]³ cut into `n × n` bicubic
/// patches whose control points are pushed out by a function of their position alone, so
/// patches that share an edge share its control points bit for bit. With `rational`, each
/// control point also gets a weight from its position.
fn puffy_cube(n: usize, rational: bool) -> (Vec<ControlPoints>, Vec<[Weight; 16]>) {
    let push = |p: [f64; 3]| {
        let r2 = p.iter().map(|c| c * c).sum::<f64>();
        p.map(|c| c * (1.0 + 0.12 * (3.0 - r2)))
    };
    let weight = |p: [f64; 3]| {
        let r2 = p.iter().map(|c| c * c).sum::<f64>();
        if rational {
            1.0 + 0.25 * (r2 - 1.0)
        } else {
            1.0
        }
    };
    let mut points = Vec::new();
    let mut weights = Vec::new();
    for axis in 0..3 {
        for sign in [1.0, -1.0] {
            let (b, c) = ((axis + 1) % 3, (axis + 2) % 3);
            // u × v must point out of the face: e_b × e_c = e_axis.
            let (ua, va) = if sign > 0.0 { (b, c) } else { (c, b) };
            for pi in 0..n {
                for pj in 0..n {
                    let mut cp = [[I16F16::ZERO; 3]; 16];
                    let mut w = [Weight::ONE; 16];
                    for i in 0..4 {
                        for j in 0..4 {
                            let s = |p: usize, k: usize| {
                                -1.0 + 2.0 * (p as f64 + k as f64 / 3.0) / n as f64
                            };
                            let mut p = [0.0; 3];
                            p[axis] = sign;
                            p[ua] = s(pi, i);
                            p[va] = s(pj, j);
                            cp[4 * i + j] = push(p).map(I16F16::from_num);
                            w[4 * i + j] = Weight::from_num(weight(p));
                        }
                    }
                    points.push(cp);
                    weights.push(w);
                }
            }
        }
    }
    (points, weights)
}

/// The exact (f64) surface point of a patch at `(u, v)`.
fn surface(points: &ControlPoints, weights: &[Weight; 16], u: f64, v: f64) -> [f64; 3] {
    let b = |t: f64| {
        [
            (1.0 - t).powi(3),
            3.0 * t * (1.0 - t).powi(2),
            3.0 * t * t * (1.0 - t),
            t.powi(3),
        ]
    };
    let (bu, bv) = (b(u), b(v));
    let mut h = [0.0; 4];
    for i in 0..4 {
        for j in 0..4 {
            let w = weights[4 * i + j].to_num::<f64>() * bu[i] * bv[j];
            for k in 0..3 {
                h[k] += w * points[4 * i + j][k].to_num::<f64>();
            }
            h[3] += w;
        }
    }
    [h[0] / h[3], h[1] / h[3], h[2] / h[3]]
}

/// Pixels whose centre lies in a dense f64 tessellation of the exact surface.
fn reference_cover(
    cam: &CameraSpec,
    points: &[ControlPoints],
    weights: &[[Weight; 16]],
) -> Vec<bool> {
    const N: usize = 24;
    let camera = cam.reference().unwrap();
    let mut cover = vec![false; W * H];
    for (p, w) in points.iter().zip(weights) {
        let grid: Vec<Option<[f64; 2]>> = (0..=N)
            .flat_map(|i| (0..=N).map(move |j| (i, j)))
            .map(|(i, j)| {
                camera.project(
                    surface(p, w, i as f64 / N as f64, j as f64 / N as f64),
                    W,
                    H,
                )
            })
            .collect();
        let at = |i: usize, j: usize| grid[i * (N + 1) + j];
        for i in 0..N {
            for j in 0..N {
                for t in [
                    [at(i, j), at(i + 1, j), at(i + 1, j + 1)],
                    [at(i, j), at(i + 1, j + 1), at(i, j + 1)],
                ] {
                    let [Some(a), Some(b), Some(c)] = t else {
                        continue;
                    };
                    fill(&mut cover, a, b, c);
                }
            }
        }
    }
    cover
}

/// Marks the pixel centres inside triangle `a b c` (either winding, edges included).
fn fill(cover: &mut [bool], a: [f64; 2], b: [f64; 2], c: [f64; 2]) {
    let e = |p: [f64; 2], q: [f64; 2], x: f64, y: f64| {
        (q[0] - p[0]) * (y - p[1]) - (q[1] - p[1]) * (x - p[0])
    };
    let lo = |k: usize| a[k].min(b[k]).min(c[k]).floor().max(0.0) as usize;
    let hi = |k: usize, n: usize| (a[k].max(b[k]).max(c[k]).ceil().max(0.0) as usize).min(n);
    for r in lo(1)..hi(1, H) {
        for col in lo(0)..hi(0, W) {
            let (x, y) = (col as f64 + 0.5, r as f64 + 0.5);
            let d = [e(a, b, x, y), e(b, c, x, y), e(c, a, x, y)];
            if d.iter().all(|&v| v >= 0.0) || d.iter().all(|&v| v <= 0.0) {
                cover[r * W + col] = true;
            }
        }
    }
}

fn render<const SUBS: usize, const TRIM: usize>(
    model: &PatchModel<'_>,
    cam: &CameraSpec,
    tolerance: f64,
) -> (Vec<i32>, PatchStats) {
    let scene = PatchScene {
        model,
        transform: Transform::IDENTITY,
        camera: cam.fixed().unwrap(),
        light: common::light(),
    };
    let mut ws: Box<PatchWorkspace<TriangleId, Flat, W, H, SUBS, 2048, TRIM>> =
        Box::new(PatchWorkspace::new(TriangleId::NONE));
    let mut ids = vec![-1i32; W * H];
    let mut next_row = 0u16;
    let mut sink = FnSink(|row: Row<'_, TriangleId>| -> Result<(), ()> {
        assert_eq!(row.y, next_row, "rows must arrive once each, top to bottom");
        next_row += 1;
        for (x, id) in row.pixels.iter().enumerate() {
            ids[row.y as usize * W + x] = id.0;
        }
        Ok(())
    });
    let options = RenderOptions::default().with_sub_pixel_bits::<SUB>();
    let stats = ws
        .render(&scene, &options, Tolerance::from_num(tolerance), &mut sink)
        .unwrap();
    (ids, stats)
}

/// xorshift64*, for reproducible views.
struct Rng(u64);

impl Rng {
    fn unit(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn random_view(rng: &mut Rng) -> CameraSpec {
    let (z, a) = (2.0 * rng.unit() - 1.0, std::f64::consts::TAU * rng.unit());
    let r = (1.0 - z * z).sqrt();
    let d = 3.5 + 3.0 * rng.unit();
    let target = [0.0; 3].map(|_| 0.4 * rng.unit() - 0.2);
    CameraSpec {
        eye: [d * r * a.cos(), d * z, d * r * a.sin()],
        target,
        up: if z.abs() > 0.95 {
            [1.0, 0.0, 0.0]
        } else {
            [0.0, 1.0, 0.0]
        },
        fovy: 45.0 + 20.0 * rng.unit(),
        near: 0.1,
        far: 100.0,
    }
}

/// Every pixel whose `radius`-neighbourhood lies inside the exact silhouette is covered.
fn check_cover(ids: &[i32], cover: &[bool], radius: usize, what: &str) {
    let mut inside = 0;
    for r in radius..H - radius {
        for c in radius..W - radius {
            let deep = (r - radius..=r + radius)
                .all(|y| (c - radius..=c + radius).all(|x| cover[y * W + x]));
            if deep {
                inside += 1;
                assert!(ids[r * W + c] >= 0, "{what}: hole at pixel ({c}, {r})");
            }
        }
    }
    assert!(
        inside > 200,
        "{what}: the model should fill part of the view ({inside})"
    );
}

#[test]
fn closed_patch_models_have_no_holes_over_random_views_and_tolerances() {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    for (n, rational) in [(1, false), (2, false), (2, true)] {
        let (points, weights) = puffy_cube(n, rational);
        let w = rational.then_some(&weights[..]);
        let model =
            PatchModel::new(&points, w, PatchColors::Uniform(Rgb888::new(200, 180, 90))).unwrap();
        for view in 0..10 {
            let cam = random_view(&mut rng);
            let tolerance = [0.25, 0.5, 1.0, 2.0, 4.0][view % 5];
            let (ids, stats) = render::<512, 64>(&model, &cam, tolerance);
            let what = format!(
                "{n}×{n} per face, rational {rational}, view {view}, tolerance {tolerance}"
            );
            assert_eq!(stats.late, 0, "{what}");
            assert_eq!(stats.overflows, 0, "{what}");
            assert_eq!(stats.frame.dropped, 0, "{what}");
            assert_eq!(stats.capped, 0, "{what}");
            let cover = reference_cover(&cam, &points, &weights);
            check_cover(&ids, &cover, tolerance.ceil() as usize + 1, &what);
            // Ids are patch indices.
            assert!(ids.iter().all(|&id| id < points.len() as i32), "{what}");
        }
    }
}

#[test]
fn the_exact_sphere_has_no_holes_at_its_poles_or_seams() {
    // sim/scenes/patches/sphere.bpt: 8 rational patches, each with an edge collapsed to a pole.
    use scanline3d_sim::patch::{fixed::FixedPatches, parse};
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("sim/scenes/patches/sphere.bpt");
    let fixed = FixedPatches::new(&parse::load(&path).unwrap()).unwrap();
    let weights = fixed.weights.clone().unwrap();
    let model = fixed
        .model(PatchColors::Uniform(Rgb888::new(200, 180, 90)))
        .unwrap();
    let mut rng = Rng(0x005e_ed0f_5a4e_7e11);
    for view in 0..10 {
        let mut cam = random_view(&mut rng);
        // The unit sphere: come closer than for the cube.
        cam.eye = cam.eye.map(|c| c * 0.7);
        let tolerance = [0.25, 0.5, 1.0, 2.0, 4.0][view % 5];
        let (ids, stats) = render::<512, 64>(&model, &cam, tolerance);
        let what = format!("sphere, view {view}, tolerance {tolerance}");
        assert_eq!(
            (stats.late, stats.overflows, stats.frame.dropped),
            (0, 0, 0),
            "{what}"
        );
        let cover = reference_cover(&cam, &fixed.points, &weights);
        check_cover(&ids, &cover, tolerance.ceil() as usize + 1, &what);
    }
}

#[test]
fn a_full_subdivision_buffer_is_reported_and_changes_nothing_else() {
    let (points, weights) = puffy_cube(1, false);
    let model = PatchModel::new(
        &points,
        None,
        PatchColors::Uniform(Rgb888::new(255, 255, 255)),
    )
    .unwrap();
    let _ = weights;
    let cam = CameraSpec {
        eye: [2.5, 1.8, 3.0],
        target: [0.0; 3],
        up: [0.0, 1.0, 0.0],
        fovy: 50.0,
        near: 0.1,
        far: 100.0,
    };
    let (roomy, roomy_stats) = render::<512, 64>(&model, &cam, 0.25);
    assert_eq!(roomy_stats.overflows, 0);
    // 6 entries: one per patch, none left for splitting pieces.
    let (tight, tight_stats) = render::<6, 64>(&model, &cam, 0.25);
    assert!(tight_stats.overflows > 0);
    // The same triangles are made, only earlier, so the image is the same.
    assert_eq!(tight, roomy);
    assert_eq!(
        tight_stats.frame.triangles_in,
        roomy_stats.frame.triangles_in
    );
    assert!(tight_stats.frame.peak_active > roomy_stats.frame.peak_active);
    // Deterministic: the same frame again gives the same statistics.
    assert_eq!(render::<6, 64>(&model, &cam, 0.25).1, tight_stats);
    // Fewer entries than patches on screen: an error before any row.
    let scene = PatchScene {
        model: &model,
        transform: Transform::IDENTITY,
        camera: cam.fixed().unwrap(),
        light: common::light(),
    };
    let mut ws: Box<PatchWorkspace<TriangleId, Flat, W, H, 4, 64>> =
        Box::new(PatchWorkspace::new(TriangleId::NONE));
    let mut rows = 0;
    let mut sink = FnSink(|_: Row<'_, TriangleId>| -> Result<(), ()> {
        rows += 1;
        Ok(())
    });
    let err = ws.render(&scene, &RenderOptions::default(), Tolerance::ONE, &mut sink);
    assert!(matches!(
        err,
        Err(scanline3d::RenderError::Capacity {
            needed: 6,
            capacity: 4,
            ..
        })
    ));
    assert_eq!(rows, 0);
}

#[test]
fn too_little_room_to_cut_trims_is_reported_and_deterministic() {
    let (points, _) = puffy_cube(1, false);
    // A 16-gon hole in every face, an island inside it.
    let q = |u: f64, v: f64| -> TrimPoint { [I16F16::from_num(u), I16F16::from_num(v)] };
    let mut trim_points = Vec::new();
    let mut loops = Vec::new();
    for patch in 0..points.len() as u16 {
        let start = trim_points.len() as u32;
        for k in 0..16 {
            let a = k as f64 * std::f64::consts::TAU / 16.0;
            trim_points.push(q(0.5 + 0.35 * a.cos(), 0.5 + 0.3 * a.sin()));
        }
        trim_points.extend([q(0.4, 0.4), q(0.6, 0.45), q(0.45, 0.6)]);
        loops.push(TrimLoop {
            patch,
            start,
            len: 16,
        });
        loops.push(TrimLoop {
            patch,
            start: start + 16,
            len: 3,
        });
    }
    let whole = PatchModel::new(
        &points,
        None,
        PatchColors::Uniform(Rgb888::new(255, 255, 255)),
    )
    .unwrap();
    let model = whole.with_trims(&loops, &trim_points).unwrap();
    let cam = CameraSpec {
        eye: [2.5, 1.8, 3.0],
        target: [0.0; 3],
        up: [0.0, 1.0, 0.0],
        fovy: 50.0,
        near: 0.1,
        far: 100.0,
    };
    let (untrimmed, _) = render::<512, 64>(&whole, &cam, 2.0);
    let (roomy, roomy_stats) = render::<512, 64>(&model, &cam, 2.0);
    assert!(roomy_stats.trim_cut > 0);
    assert_eq!(roomy_stats.trim_overflows, 0);
    // The holes show the inside of the cube (other patches) or nothing.
    let changed = roomy.iter().zip(&untrimmed).filter(|(a, b)| a != b).count();
    assert!(changed > W * H / 20, "{changed}");
    // Room for 4 boundary points: every cut triangle overflows and is kept or dropped whole.
    let (tight, tight_stats) = render::<512, 4>(&model, &cam, 2.0);
    assert!(tight_stats.trim_overflows > 0);
    assert_eq!(tight_stats.trim_cut, roomy_stats.trim_cut);
    assert_eq!(render::<512, 4>(&model, &cam, 2.0), (tight, tight_stats));
}
