//! Metaballs: the f64 reference against dense sampling and bisection, and the library's
//! fixed-point caster against the reference on the corpus.

use scanline3d_sim::draw::MetaDraw;
use scanline3d_sim::metaball::compare::{check, compare, render_fixed};
use scanline3d_sim::metaball::reference::Reference;
use scanline3d_sim::metaball::{corpus, BallSpec, MetaScene};
use scanline3d_sim::reference::{dot, Camera, V3};

/// The first sign change of `g` along the ray, from 20 000 samples and bisection to 1e-13.
fn bisection(r: &Reference, d: V3, t0: f64, t1: f64) -> Option<f64> {
    let g = |t: f64| r.g([0, 1, 2].map(|i| r.camera.eye[i] + t * d[i]));
    const SAMPLES: usize = 20_000;
    let mut a = t0;
    let ga = g(a);
    for k in 1..=SAMPLES {
        let b = t0 + (t1 - t0) * k as f64 / SAMPLES as f64;
        let gb = g(b);
        if (gb > 0.0) != (ga > 0.0) {
            let (mut lo, mut hi) = (a, b);
            while hi - lo > 1e-13 {
                let m = (lo + hi) / 2.0;
                if (g(m) > 0.0) == (ga > 0.0) {
                    lo = m;
                } else {
                    hi = m;
                }
            }
            return Some((lo + hi) / 2.0);
        }
        a = b;
    }
    None
}

/// A small deterministic generator (xorshift), so the scenes are the same on every run.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
}

fn random_scene(rng: &mut Rng) -> MetaScene {
    let n = 1 + (rng.next() * 5.0) as usize;
    let balls = (0..n)
        .map(|_| BallSpec {
            centre: [0, 1, 2].map(|_| rng.range(-1.0, 1.0)),
            radius: rng.range(0.5, 1.5),
            density: if rng.next() < 0.2 {
                -rng.range(0.3, 1.0)
            } else {
                rng.range(0.5, 1.5)
            },
            color: [0.8; 3],
            keys: vec![],
        })
        .collect();
    MetaScene {
        threshold: rng.range(0.2, 0.7),
        light: ([0.0, 0.0, 1.0], 0.2, 0.8),
        balls,
    }
}

#[test]
fn reference_matches_bisection_on_random_scenes() {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let (mut rays, mut hits, mut total_iterations, mut max_iterations) = (0, 0, 0u64, 0);
    for _ in 0..40 {
        let scene = random_scene(&mut rng);
        let camera =
            Camera::new([0.3, 0.2, 4.0], [0.0; 3], [0.0, 1.0, 0.0], 50.0, 0.1, 20.0).unwrap();
        let r = Reference::new(&scene, 0, camera).unwrap();
        for _ in 0..40 {
            let (x, y) = (rng.range(16.0, 48.0), rng.range(16.0, 48.0));
            let d = camera.ray(x, y, 64, 64);
            let (root, iterations) = r.nearest_root(d, camera.near, camera.far);
            let expected = bisection(&r, d, camera.near, camera.far);
            rays += 1;
            total_iterations += iterations as u64;
            max_iterations = max_iterations.max(iterations);
            match (root, expected) {
                (Some(t), Some(e)) => {
                    hits += 1;
                    assert!((t - e).abs() <= 1e-9, "root {t} vs bisection {e}");
                }
                (None, None) => {}
                other => {
                    panic!("reference {other:?} disagrees with bisection, ray {d:?} in {scene:?}")
                }
            }
        }
    }
    assert!(hits > rays / 4, "{hits} hits of {rays}");
    println!(
        "{rays} rays, {hits} hits; Bezier clipping iterations per ray: mean {:.2}, max {max_iterations}",
        total_iterations as f64 / rays as f64
    );
}

/// Balls whose influence spheres only touch, and rays that graze a single ball's surface.
#[test]
fn reference_on_touching_balls_and_grazes() {
    // One ball: the surface is the sphere where f(s) = T/q.
    let mut one = MetaScene::parse("threshold 0.5\nmetaball 0 0 0 2 1\n", "one").unwrap();
    // f(1/4) = 1/2, so the surface radius is R/2 = 1.
    let camera = Camera::new([0.0, 0.0, 5.0], [0.0; 3], [0.0, 1.0, 0.0], 50.0, 0.1, 20.0).unwrap();
    let r = Reference::new(&one, 0, camera).unwrap();
    for k in 0..200 {
        // Rays at lateral offsets up to 1 - 1e-7 of the sphere's radius: tangent grazes.
        let offset = 1.0 - 10f64.powf(-(k as f64) / 200.0 * 7.0);
        let d = [offset, 0.0, -5.0];
        let d = d.map(|c| c / 5.0);
        let (root, _) = r.nearest_root(d, 0.1, 20.0);
        // Exact: |e + t d|² = 1.
        let (a, b, c) = (
            dot(d, d),
            2.0 * dot(camera.eye, d),
            dot(camera.eye, camera.eye) - 1.0,
        );
        let exact = (-b - (b * b - 4.0 * a * c).sqrt()) / (2.0 * a);
        let t = root.expect("graze hit");
        assert!(
            (t - exact).abs() <= 1e-9 * (1.0 + 1.0 / (b * b - 4.0 * a * c).sqrt()).min(1e3),
            "offset {offset}: {t} vs {exact}"
        );
    }
    // Two balls whose influence spheres touch at the origin: the field is 0 there, no surface.
    one.balls.push(BallSpec {
        centre: [4.0, 0.0, 0.0],
        ..one.balls[0].clone()
    });
    let camera = Camera::new(
        [2.0, 0.0, 5.0],
        [2.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        80.0,
        0.1,
        20.0,
    )
    .unwrap();
    let r = Reference::new(&one, 0, camera).unwrap();
    for x in 0..64 {
        let d = camera.ray(x as f64 + 0.5, 32.5, 64, 64);
        let (root, _) = r.nearest_root(d, 0.1, 20.0);
        assert_eq!(
            root.is_some(),
            bisection(&r, d, 0.1, 20.0).is_some(),
            "column {x}"
        );
        if let (Some(t), Some(e)) = (root, bisection(&r, d, 0.1, 20.0)) {
            assert!((t - e).abs() <= 1e-9);
        }
    }
}

#[test]
fn fixed_caster_matches_reference_on_the_corpus() {
    let (w, h) = (240, 240);
    for (name, scene, camera) in corpus() {
        let reference = Reference::new(&scene, 0, camera.reference().unwrap()).unwrap();
        let (expected, iterations) = reference.render(w, h);
        let (image, stats) = render_fixed(&scene, 0, &camera, w, h).unwrap();
        let m = compare(&image, &expected, &reference);
        let covered = expected.ids.iter().filter(|&&i| i >= 0).count();
        println!(
            "{name}: {m}; reference covers {covered}, clipping iterations mean {:.2} max {}; caster steps mean {:.1} max {}, capped {}",
            iterations.iter().map(|&i| i as f64).sum::<f64>() / iterations.len() as f64,
            iterations.iter().max().unwrap(),
            stats.steps as f64 / (w * h) as f64,
            stats.max_steps,
            stats.capped
        );
        assert!(covered > 1000, "{name}: the scene should be visible");
        assert!(m.coverage_percent() <= 0.5, "{name}: {m}");
        assert_eq!(m.off_silhouette, 0, "{name}: {m}");
        assert_eq!(m.depth_unexplained, 0, "{name}: {m}");
        assert!(m.psnr >= 40.0, "{name}: {m}");
    }
}

/// The caster against the reference on random scenes (the first cases of
/// `sim/examples/meta_random.rs`, which draws more): every coverage mismatch is at the
/// silhouette, every depth is one the caster's stopping rule explains, and no ray is capped. It found the caster's `1/|d|²` to 2^-16 (every ball moved along the
/// ray by up to 1.5·10⁻⁵ of its distance).
#[test]
fn fixed_caster_matches_reference_on_random_scenes() {
    let mut d = MetaDraw::draws();
    let mut frames = 0;
    for case in 0..1_000 {
        let (scene, camera) = MetaDraw::case(&mut d, case);
        if let Some(c) = check(scene, camera, 48) {
            assert!(c.explained(), "case {case}: {}", c.comparison);
            // Near-tangent grazes (cases 602 and 894 took more than MAX_STEPS before the
            // curvature's step) end within the cap.
            assert_eq!(c.stats.capped, 0, "case {case}: {:?}", c.stats);
            frames += 1;
        }
    }
    assert!(frames > 500, "{frames} frames");
}

/// Marching tetrahedra drawn by the span z-buffer against the reference on the corpus: the
/// surface is found wherever the reference finds it and the error shrinks as the grid refines.
#[test]
fn polygonization_converges_to_the_reference_on_the_corpus() {
    use scanline3d_sim::metaball::polygonized::render_polygonized;
    let (w, h) = (120, 120);
    for (name, scene, camera) in corpus() {
        let reference = Reference::new(&scene, 0, camera.reference().unwrap()).unwrap();
        let (expected, _) = reference.render(w, h);
        let measures: Vec<_> = [8, 32]
            .iter()
            .map(|&cells| {
                let p = render_polygonized(&scene, 0, &camera, (w, h), cells).unwrap();
                let m = compare(&p.image, &expected, &reference);
                println!(
                    "{name}, polygonize:{cells}: {m}; {} triangles",
                    p.mesh.triangles
                );
                m
            })
            .collect();
        let (coarse, fine) = (&measures[0], &measures[1]);
        assert!(fine.mean_depth_error < coarse.mean_depth_error, "{name}");
        assert!(
            fine.coverage_mismatches <= coarse.coverage_mismatches,
            "{name}"
        );
        assert!(fine.psnr > coarse.psnr, "{name}");
        assert_eq!(fine.off_silhouette, 0, "{name}: {fine}");
    }
}

/// Frame 1 of the animation at 240×240 had near-tangent rays stopped by the march's step cap
/// (then 400), drawn as background: 4 mismatches off the silhouette bound. With the cap at
/// `MAX_STEPS` every ray converges.
#[test]
fn no_ray_of_animation_frame_1_is_capped() {
    let (_, scene, camera) = corpus().into_iter().find(|c| c.0 == "six").unwrap();
    let reference = Reference::new(&scene, 1, camera.reference().unwrap()).unwrap();
    let (expected, _) = reference.render(240, 240);
    let (image, stats) = render_fixed(&scene, 1, &camera, 240, 240).unwrap();
    let m = compare(&image, &expected, &reference);
    assert_eq!(stats.capped, 0, "{stats:?}");
    assert_eq!(m.off_silhouette, 0, "{m}");
    assert_eq!(m.depth_unexplained, 0, "{m}");
}
