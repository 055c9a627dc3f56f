//! The Bezier-clipping reference against brute force (dense tessellation, ray casting, Newton
//! refinement) and against the analytic sphere; trims; degenerate patches.

use scanline3d_sim::patch::clip;
use scanline3d_sim::patch::render::Reference;
use scanline3d_sim::patch::{parse, Patch, PatchModel, TrimLoop};
use scanline3d_sim::reference::{cross, dot, normalize, Camera, Light, V3};
use std::path::Path;

fn model(name: &str) -> PatchModel {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes/patches")
        .join(name);
    parse::load(&path).unwrap()
}

fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// A small deterministic generator (xorshift), uniform in [0, 1).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.next()
    }
}

/// Tessellation steps per side for brute force.
const N: usize = 40;

/// A patch's `(N + 1)²` grid of surface points, row-major in `u`.
fn tessellate(patch: &Patch) -> Vec<V3> {
    (0..=N)
        .flat_map(|i| (0..=N).map(move |j| (i, j)))
        .map(|(i, j)| patch.point(i as f64 / N as f64, j as f64 / N as f64))
        .collect()
}

/// Brute force: the patch tessellated into `N × N` quads (two triangles each), every triangle
/// the ray crosses gives a start `(u, v)`; Newton's method on the two plane distances refines
/// it. Returns the refined roots inside the domain: `(u, v, t)`.
fn brute_force(patch: &Patch, grid: &[V3], o: V3, d: V3) -> Vec<(f64, f64, f64)> {
    let at = |i: usize, j: usize| grid[i * (N + 1) + j];
    let uv = |i: usize, j: usize| [i as f64 / N as f64, j as f64 / N as f64];
    let mut starts = Vec::new();
    for i in 0..N {
        for j in 0..N {
            for tri in [
                [(i, j), (i + 1, j), (i + 1, j + 1)],
                [(i, j), (i + 1, j + 1), (i, j + 1)],
            ] {
                let [a, b, c] = tri.map(|(i, j)| at(i, j));
                // Möller–Trumbore, two-sided, with a generous edge margin (the surface is
                // curved: a root may sit just outside its chord triangle).
                let (e1, e2) = (sub(b, a), sub(c, a));
                let p = cross(d, e2);
                let det = dot(e1, p);
                if det.abs() < 1e-300 {
                    continue;
                }
                let s = sub(o, a);
                let bu = dot(s, p) / det;
                let q = cross(s, e1);
                let bv = dot(d, q) / det;
                let m = 0.05;
                if bu >= -m && bv >= -m && bu + bv <= 1.0 + m {
                    let [ua, ub, uc] = tri.map(|(i, j)| uv(i, j));
                    let w = 1.0 - bu - bv;
                    starts.push([
                        w * ua[0] + bu * ub[0] + bv * uc[0],
                        w * ua[1] + bu * ub[1] + bv * uc[1],
                    ]);
                }
            }
        }
    }
    let (n1, n2) = clip::ray_planes(d).unwrap();
    let mut roots: Vec<(f64, f64, f64)> = Vec::new();
    for [mut u, mut v] in starts {
        // Newton's steps settle at rounding level (about 1e-16); a last step below 1e-12
        // after 40 iterations means it converged.
        let mut last_step = f64::INFINITY;
        for _ in 0..40 {
            let f = patch.frame(u, v);
            let r = sub(f.point, o);
            let (f1, f2) = (dot(n1, r), dot(n2, r));
            let (a, b, c, e) = (dot(n1, f.du), dot(n1, f.dv), dot(n2, f.du), dot(n2, f.dv));
            let det = a * e - b * c;
            if det == 0.0 || !det.is_finite() {
                break;
            }
            let (du, dv) = ((e * f1 - b * f2) / det, (a * f2 - c * f1) / det);
            u = (u - du).clamp(-0.1, 1.1);
            v = (v - dv).clamp(-0.1, 1.1);
            last_step = du.abs().max(dv.abs());
        }
        let converged = last_step < 1e-12;
        let inside = (-1e-12..=1.0 + 1e-12).contains(&u) && (-1e-12..=1.0 + 1e-12).contains(&v);
        if converged && inside {
            let p = patch.point(u, v);
            let t = dot(sub(p, o), d) / dot(d, d);
            if !roots
                .iter()
                .any(|r| (r.0 - u).abs() < 1e-9 && (r.1 - v).abs() < 1e-9)
            {
                roots.push((u, v, t));
            }
        }
    }
    roots
}

/// The nearest brute-force root over the model with `t > 0`: (patch, u, v, t).
fn brute_nearest(
    m: &PatchModel,
    grids: &[Vec<V3>],
    o: V3,
    d: V3,
) -> Option<(usize, f64, f64, f64)> {
    m.patches
        .iter()
        .zip(grids)
        .enumerate()
        .flat_map(|(k, (p, g))| {
            brute_force(p, g, o, d)
                .into_iter()
                .filter(|r| r.2 > 0.0 && p.is_kept(r.0, r.1))
                .map(move |r| (k, r.0, r.1, r.2))
        })
        .min_by(|a, b| a.3.total_cmp(&b.3))
}

fn reference(m: PatchModel) -> Reference {
    let camera = Camera::new([0.0, 0.0, 5.0], [0.0; 3], [0.0, 1.0, 0.0], 50.0, 1e-3, 1e3).unwrap();
    let light = Light {
        direction: normalize([-0.45, 0.8, 0.55]).unwrap(),
        ambient: 0.25,
        diffuse: 0.75,
    };
    Reference::new(m, camera, light)
}

#[test]
fn sphere_agrees_with_brute_force_and_the_analytic_sphere() {
    let r = reference(model("sphere.bpt"));
    let grids: Vec<_> = r.model.patches.iter().map(tessellate).collect();
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let (mut worst_uv, mut worst_t, mut rays, mut split, mut max_rounds, mut rounds) =
        (0.0_f64, 0.0_f64, 0, 0, 0, 0u64);
    while rays < 150 {
        // Eyes outside and inside the sphere, aimed at random points within it.
        let dir_eye = normalize([
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        ]);
        let Some(dir_eye) = dir_eye else { continue };
        let dist = if rays % 5 == 0 {
            rng.range(0.0, 0.8)
        } else {
            rng.range(1.5, 6.0)
        };
        let o = dir_eye.map(|c| c * dist);
        let target = [
            rng.range(-0.7, 0.7),
            rng.range(-0.7, 0.7),
            rng.range(-0.7, 0.7),
        ];
        let d = sub(target, o);
        // Analytic: |o + t d| = 1, the nearest root with t > 0.
        let (a, b, c) = (dot(d, d), 2.0 * dot(o, d), dot(o, o) - 1.0);
        let disc = b * b - 4.0 * a * c;
        assert!(disc > 0.0);
        let (t0, t1) = (
            (-b - disc.sqrt()) / (2.0 * a),
            (-b + disc.sqrt()) / (2.0 * a),
        );
        let exact_t = if t0 > 0.0 { t0 } else { t1 };
        let (hit, stats) = r.trace(o, d, (1e-9, 1e9));
        let hit = hit.expect("the ray meets the sphere");
        let brute = brute_nearest(&r.model, &grids, o, d).expect("brute force finds the hit");
        worst_t = worst_t.max((hit.t - exact_t).abs() * dot(d, d).sqrt());
        if brute.0 == hit.patch {
            worst_uv = worst_uv
                .max((brute.1 - hit.u).abs())
                .max((brute.2 - hit.v).abs());
        } else {
            // Only on a shared edge: the two patches' points must coincide.
            let p = r.model.patches[brute.0].point(brute.1, brute.2);
            assert!(
                sub(p, hit.point).iter().all(|c| c.abs() < 1e-9),
                "{brute:?} {hit:?}"
            );
        }
        rays += 1;
        split += u32::from(stats.splits > 0);
        max_rounds = max_rounds.max(stats.rounds);
        rounds += u64::from(stats.rounds);
        assert_eq!(stats.capped, 0);
    }
    println!(
        "sphere: {rays} rays, worst |Δu|,|Δv| {worst_uv:.1e}, worst distance to the analytic hit {worst_t:.1e}, clip rounds mean {:.1} max {max_rounds}, rays with a split {split}",
        rounds as f64 / rays as f64
    );
    assert!(worst_uv <= 1e-9, "worst (u, v) difference {worst_uv:e}");
    assert!(
        worst_t <= 1e-9,
        "worst distance to the analytic hit {worst_t:e}"
    );
}

#[test]
fn teapot_agrees_with_brute_force() {
    let r = reference(model("teapot.bpt"));
    let grids: Vec<_> = r.model.patches.iter().map(tessellate).collect();
    let mut rng = Rng(0x1234_5678_9abc_def1);
    let (mut compared, mut worst) = (0, 0.0_f64);
    let mut n = 0;
    while n < 60 {
        let o = [
            rng.range(-6.0, 6.0),
            rng.range(-6.0, 6.0),
            rng.range(-2.0, 6.0),
        ];
        let target = [
            rng.range(-2.5, 3.0),
            rng.range(-1.5, 1.5),
            rng.range(0.0, 3.0),
        ];
        let d = sub(target, o);
        let (hit, stats) = r.trace(o, d, (1e-9, 1e9));
        assert_eq!(stats.capped, 0);
        let brute = brute_nearest(&r.model, &grids, o, d);
        match (hit, brute) {
            (Some(h), Some(b)) => {
                assert!(
                    (h.t - b.3).abs() * dot(d, d).sqrt() < 1e-8,
                    "{h:?} {b:?} {o:?} {d:?}"
                );
                if h.patch == b.0 {
                    worst = worst.max((h.u - b.1).abs()).max((h.v - b.2).abs());
                    compared += 1;
                }
            }
            (None, None) => {}
            (h, b) => panic!("clipping {h:?}, brute force {b:?} for {o:?} + t{d:?}"),
        }
        n += 1;
    }
    println!("teapot: {compared} hits compared, worst |Δu|,|Δv| {worst:.1e}");
    assert!(compared > 20);
    assert!(worst <= 1e-9, "{worst:e}");
}

#[test]
fn trimmed_holes_are_exactly_where_the_trim_says() {
    let r = reference(model("trimmed.bpt"));
    // x = 2u − 1, y = 2v − 1 on this sheet; rays straight down −z.
    let (mut holes, mut kept) = (0, 0);
    for a in 0..60 {
        for b in 0..60 {
            let (u, v) = ((a as f64 + 0.5) / 60.0, (b as f64 + 0.5) / 60.0);
            let (hit, _) = r.trace(
                [2.0 * u - 1.0, 2.0 * v - 1.0, 3.0],
                [0.0, 0.0, -1.0],
                (0.0, 10.0),
            );
            let radius = ((u - 0.5).powi(2) + (v - 0.5).powi(2)).sqrt();
            // The 32-gon lies between its inradius and its circumradius 0.3.
            let inradius = 0.3 * (std::f64::consts::PI / 32.0).cos();
            // The island: the triangle (0.4, 0.42), (0.6, 0.42), (0.5, 0.6).
            let in_island =
                v > 0.42 && (v - 0.42) < 1.8 * (u - 0.4) && (v - 0.42) < 1.8 * (0.6 - u);
            let on_island_edge = (v - 0.42).abs() < 1e-3
                || ((v - 0.42) - 1.8 * (u - 0.4)).abs() < 1e-3
                || ((v - 0.42) - 1.8 * (0.6 - u)).abs() < 1e-3;
            if (radius - 0.3).abs() < 0.3 - inradius + 1e-6 || on_island_edge {
                continue;
            }
            let expect_surface = radius > 0.3 || in_island;
            match hit {
                Some(h) => {
                    assert!(expect_surface, "hit in the hole at ({u}, {v})");
                    assert!((h.u - u).abs() < 1e-9 && (h.v - v).abs() < 1e-9, "{h:?}");
                    kept += 1;
                }
                None => {
                    assert!(!expect_surface, "no hit at ({u}, {v})");
                    holes += 1;
                }
            }
        }
    }
    assert!(holes > 300 && kept > 2000, "{holes} {kept}");
}

#[test]
fn a_trimmed_rational_patch_shows_what_is_behind_it() {
    let mut m = model("sphere.bpt");
    let (o, d) = ([0.3, 0.4, 5.0], [0.0, 0.0, -1.0]);
    let (front, _) = reference(m.clone()).trace(o, d, (0.0, 10.0));
    let front = front.unwrap();
    // Cut a small square hole around the front hit.
    let (u, v) = (front.u, front.v);
    m.patches[front.patch].trims.push(TrimLoop {
        points: vec![
            [u - 0.05, v - 0.05],
            [u + 0.05, v - 0.05],
            [u + 0.05, v + 0.05],
            [u - 0.05, v + 0.05],
        ],
    });
    let (behind, _) = reference(m).trace(o, d, (0.0, 10.0));
    let behind = behind.unwrap();
    // The far side of the unit sphere: z = −√(1 − x² − y²).
    let z = -(1.0 - 0.3_f64 * 0.3 - 0.4 * 0.4).sqrt();
    assert!((behind.point[2] - z).abs() < 1e-9, "{behind:?}");
    assert!((front.point[2] + z).abs() < 1e-9, "{front:?}");
}

#[test]
fn degenerate_patches_give_finite_hits_and_normals() {
    let r = reference(model("teapot.bpt"));
    // Straight at the lid knob's collapsed centre and the base's, and around them.
    for (o, d) in [
        ([0.0, 0.0, 6.0], [0.0, 0.0, -1.0]),
        ([0.0, 0.0, -3.0], [0.0, 0.0, 1.0]),
        ([1e-9, 2e-9, 6.0], [0.0, 0.0, -1.0]),
        ([0.01, 0.0, 6.0], [0.0, 0.0, -1.0]),
        ([2.0, 1.0, 6.0], [-2.0, -1.0, -2.85]),
    ] {
        let (hit, stats) = r.trace(o, d, (0.0, 100.0));
        let hit = hit.unwrap_or_else(|| panic!("no hit for {o:?}"));
        assert_eq!(stats.capped, 0);
        assert!(hit.t.is_finite() && hit.u.is_finite() && hit.v.is_finite());
        let n = hit.normal.expect("a normal");
        assert!(n.iter().all(|c| c.is_finite()));
        // Along the axis the surface is horizontal: the normal is ±z.
        if o[0].abs() < 1e-6 {
            assert!(n[2].abs() > 0.999, "{n:?} at {hit:?}");
        }
    }
    // A whole image from above and from below: no non-finite depth, every hit shaded.
    for eye in [[0.5, 0.3, 7.0], [0.2, -0.1, -4.0]] {
        let camera = Camera::new(eye, [0.0, 0.0, 1.5], [0.0, 1.0, 0.0], 60.0, 0.1, 100.0).unwrap();
        let r = Reference::new(r.model.clone(), camera, r.light);
        let (img, stats) = r.render(40, 40);
        assert!(stats.hits > 100);
        assert_eq!(stats.capped, 0);
        for (id, z) in img.ids.iter().zip(&img.depth) {
            assert_eq!(*id >= 0, z.is_finite());
        }
    }
}
