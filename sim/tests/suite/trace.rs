//! The f64 Whitted tracer against closed-form cases, each shading and termination rule on a
//! scene made for it, the acceleration structures, and `sim trace` end to end.

use scanline3d_sim::reference::Camera;
use scanline3d_sim::trace::accel::{Accel, Structure};
use scanline3d_sim::trace::corpus;
use scanline3d_sim::trace::render::render;
use scanline3d_sim::trace::scene::{check_camera, CameraSpec, TracedScene};
use scanline3d_sim::trace::vector::{dot, normalize, sub, Ray, V3};
use scanline3d_sim::trace::whitted::{Limits, Spawn, TraceStats, Tracer, TreeRay};
use std::path::Path;
use std::process::Command;

fn parse(text: &str) -> TracedScene {
    TracedScene::parse(text, Path::new("."), "test.scene").unwrap()
}

/// Traces one ray as if it were secondary (t > ε) at depth 0, weight 1, logging its tree.
fn trace_logged(scene: &TracedScene, ray: Ray, limits: Limits) -> ([f64; 3], TraceStats) {
    let accel = Accel::build(scene, Structure::None);
    let tracer = Tracer::new(&accel, limits);
    let mut stats = TraceStats {
        log: Some(Vec::new()),
        ..Default::default()
    };
    let c = tracer.colour(&ray, 0, 1.0, &mut stats);
    (c, stats)
}

fn log(stats: &TraceStats) -> &[TreeRay] {
    stats.log.as_deref().unwrap_or(&[])
}

fn assert_close(a: V3, b: V3, tol: f64, what: &str) {
    assert!(
        (0..3).all(|k| (a[k] - b[k]).abs() <= tol),
        "{what}: {a:?} vs {b:?}"
    );
}

fn camera(eye: V3, target: V3, up: V3) -> CameraSpec {
    CameraSpec {
        eye,
        target,
        up,
        fovy: 50.0,
        near: 0.1,
        far: 100.0,
    }
}

#[test]
fn a_ray_through_a_glass_slab_exits_parallel_to_its_entry() {
    for ior in ["water", "glass", "dense-glass", "diamond"] {
        let scene = parse(&format!(
            "material slab 1 1 1 0 0 0 1 {ior}\nbox -100 0 -100 100 1 100 slab\n"
        ));
        let n2 = scene.materials[0].ior;
        for degrees in [5.0f64, 30.0, 60.0, 80.0] {
            let th = degrees.to_radians();
            let dir = [th.sin(), -th.cos(), 0.0];
            let ray = Ray {
                origin: [0.0, 3.0, 0.0],
                dir,
            };
            let (_, stats) = trace_logged(&scene, ray, Limits::default());
            let tree = log(&stats);
            assert_eq!(tree.len(), 2, "{ior} {degrees}°: {tree:?}");
            let (inside, out) = (tree[0], tree[1]);
            assert_eq!(
                (inside.spawn, out.spawn),
                (Spawn::Refraction, Spawn::Refraction)
            );
            // Snell at the entry: sin θ2 = sin θ1 / n.
            assert!((inside.ray.dir[0] - th.sin() / n2).abs() < 1e-12);
            // Entry at (2 tan θ1, 1); exit one slab thickness lower, shifted by tan θ2.
            let tan2 = inside.ray.dir[0] / -inside.ray.dir[1];
            assert_close(
                inside.ray.origin,
                [2.0 * th.tan(), 1.0, 0.0],
                1e-12,
                "entry",
            );
            assert_close(
                out.ray.origin,
                [2.0 * th.tan() + tan2, 0.0, 0.0],
                1e-12,
                "exit",
            );
            assert_close(out.ray.dir, dir, 1e-12, &format!("{ior} {degrees}° exit"));
        }
    }
}

/// The smallest angle of incidence (from inside) at which the tracer reflects totally,
/// found by bisection on the tracer itself.
fn tracer_critical_angle(ior: &str) -> f64 {
    // A block of the material filling y < 0; rays start inside and meet its top face.
    let scene = parse(&format!(
        "material m 1 1 1 0 0 0 1 {ior}\nbox -100 -100 -100 100 0 100 m\n"
    ));
    let spawn_at = |th: f64| {
        let ray = Ray {
            origin: [0.0, -1.0, 0.0],
            dir: [th.sin(), th.cos(), 0.0],
        };
        let limits = Limits {
            max_depth: 1,
            ..Limits::default()
        };
        let (_, stats) = trace_logged(&scene, ray, limits);
        let first = log(&stats)[0];
        if first.spawn == Spawn::TotalInternalReflection {
            // T is the reflected ray.
            assert_close(first.ray.dir, [th.sin(), -th.cos(), 0.0], 1e-12, "T = R");
        }
        first.spawn
    };
    let (mut lo, mut hi) = (0.0f64, 89f64.to_radians());
    assert_eq!(spawn_at(lo), Spawn::Refraction);
    assert_eq!(spawn_at(hi), Spawn::TotalInternalReflection);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if spawn_at(mid) == Spawn::TotalInternalReflection {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    hi
}

#[test]
fn total_internal_reflection_starts_at_the_critical_angle() {
    for (ior, n) in [("water", 1.33), ("glass", 1.5), ("diamond", 2.42)] {
        let found = tracer_critical_angle(ior);
        let exact = (1.0f64 / n).asin();
        assert!(
            (found - exact).abs() < 1e-9,
            "{ior}: {} vs {}°",
            found.to_degrees(),
            exact.to_degrees()
        );
    }
    // The lecture's diamond: 24.4°.
    assert!((tracer_critical_angle("diamond").to_degrees() - 24.41).abs() < 0.01);
}

#[test]
fn a_spheres_shadow_on_a_plane_is_the_analytic_ellipse() {
    let (c, r, l) = ([0.3, 1.2, -0.2], 0.6, [1.5, 4.0, 1.0]);
    let scene = parse(&format!(
        "light point {} {} {} 1\nmaterial m 1 1 1 0.2 0.8 0 0 air\nplane 0 1 0 0 m\nsphere {} {} {} {r} m\n",
        l[0], l[1], l[2], c[0], c[1], c[2]
    ));
    // In shadow: the cone from the light tangent to the sphere, ((P−L)·u)² ≥ cos²α |P−L|²
    // with u towards the centre and sin α = r / |C − L|. On the plane y = 0 its quadratic
    // part in (x, z) has discriminant B² − 4AC < 0: an ellipse.
    let u = normalize(sub(c, l)).unwrap();
    let cos2 = 1.0 - r * r / dot(sub(c, l), sub(c, l));
    let (a, b, cc) = (u[0] * u[0] - cos2, 2.0 * u[0] * u[2], u[2] * u[2] - cos2);
    assert!(b * b - 4.0 * a * cc < 0.0, "not an ellipse");
    let conic = |p: V3| {
        let d = sub(p, l);
        (dot(d, u).powi(2) - cos2 * dot(d, d)) / dot(d, d)
    };
    let spec = camera([0.0, 7.0, 3.0], [0.5, 0.0, 0.0], [0.0, 1.0, 0.0]);
    let cam = check_camera(&spec).unwrap();
    let accel = Accel::build(&scene, Structure::Bvh);
    let tracer = Tracer::new(&accel, Limits::default());
    let (w, h) = (160, 160);
    let (mut shadowed, mut mismatches, mut near_boundary) = (0, 0, 0);
    for y in 0..h {
        for x in 0..w {
            let mut stats = TraceStats::default();
            let px = tracer.pixel(&cam, x, y, w, h, &mut stats);
            let Some(hit) = px.hit.filter(|hit| hit.id == 0) else {
                continue;
            };
            let p = Ray {
                origin: spec.eye,
                dir: cam.ray(x as f64 + 0.5, y as f64 + 0.5, w, h),
            };
            let f = conic(p.at(hit.t));
            let analytic = f > 0.0;
            let traced = px.shadow & 1 != 0;
            shadowed += traced as usize;
            if f.abs() < 1e-9 {
                near_boundary += 1;
            } else if analytic != traced {
                mismatches += 1;
            }
        }
    }
    assert!(shadowed > 500, "{shadowed} shadowed pixels");
    assert_eq!(mismatches, 0, "({near_boundary} pixels on the boundary)");
}

/// Two parallel mirrors (y = 0 facing up, y = 2 facing down) with reflection `kr`, only
/// ambient light: an endless ray tree.
fn mirrors(kr: f64) -> TracedScene {
    parse(&format!(
        "ambient 0.05\nmaterial m 1 1 1 1 0 {kr} 0 air\nplane 0 1 0 0 m\nplane 0 -1 0 2 m\n"
    ))
}

fn bounce(scene: &TracedScene, limits: Limits) -> ([f64; 3], TraceStats) {
    let ray = Ray {
        origin: [0.0, 1.0, 0.0],
        dir: normalize([1.0, -1.0, 0.3]).unwrap(),
    };
    trace_logged(scene, ray, limits)
}

#[test]
fn the_depth_limit_ends_the_ray_tree() {
    let scene = mirrors(1.0);
    for max_depth in 0..6u32 {
        let limits = Limits {
            max_depth,
            threshold: 0.0,
        };
        let (c, stats) = bounce(&scene, limits);
        // Each mirror adds its ambient term 0.05; the primary ray and max_depth reflections.
        let want = 0.05 * (max_depth + 1) as f64;
        assert_close(c, [want; 3], 1e-12, &format!("max depth {max_depth}"));
        let depths: Vec<u32> = log(&stats).iter().map(|t| t.depth).collect();
        assert_eq!(depths, (1..=max_depth).collect::<Vec<_>>());
        assert_eq!(stats.cut_by_depth, 1);
        assert_eq!(stats.cut_by_weight, 0);
    }
}

#[test]
fn a_ray_below_the_weight_threshold_is_not_traced() {
    let scene = mirrors(0.5);
    for (threshold, traced) in [(0.1, 3u32), (0.125, 3), (0.13, 2), (0.5, 1), (0.51, 0)] {
        let limits = Limits {
            max_depth: 50,
            threshold,
        };
        let (c, stats) = bounce(&scene, limits);
        let weights: Vec<f64> = log(&stats).iter().map(|t| t.weight).collect();
        let want: Vec<f64> = (1..=traced).map(|k| 0.5f64.powi(k as i32)).collect();
        assert_eq!(weights, want, "threshold {threshold}");
        let colour = 0.05 * (0..=traced).map(|k| 0.5f64.powi(k as i32)).sum::<f64>();
        assert_close(c, [colour; 3], 1e-12, "colour");
        assert_eq!((stats.cut_by_weight, stats.cut_by_depth), (1, 0));
    }
}

#[test]
fn local_term_diffuse_end_and_background() {
    let scene = parse(
        "background 0.1 0.2 0.3\nambient 0.3\nlight directional 0 1 1 0.9\nlight point 0 -5 0 2\n\
         material m 0.8 0.4 0.2 0.5 0.7 0 0 air\nsphere 0 0 0 1 m\n",
    );
    let spec = camera([0.0, 0.5, 4.0], [0.0; 3], [0.0, 1.0, 0.0]);
    let cam = check_camera(&spec).unwrap();
    let accel = Accel::build(&scene, Structure::Grid);
    let tracer = Tracer::new(&accel, Limits::default());
    let (w, h) = (41, 41);
    let (mut hits, mut misses) = (0, 0);
    let l = normalize([0.0, 1.0, 1.0]).unwrap();
    for y in 0..h {
        for x in 0..w {
            let mut stats = TraceStats {
                log: Some(Vec::new()),
                ..Default::default()
            };
            let px = tracer.pixel(&cam, x, y, w, h, &mut stats);
            // A diffuse surface spawns nothing.
            assert!(log(&stats).is_empty());
            let Some(hit) = px.hit else {
                assert_eq!(px.colour, [0.1, 0.2, 0.3]);
                assert_eq!(px.shadow, 0);
                misses += 1;
                continue;
            };
            hits += 1;
            let p = Ray {
                origin: spec.eye,
                dir: cam.ray(x as f64 + 0.5, y as f64 + 0.5, w, h),
            }
            .at(hit.t);
            let n = normalize(p).unwrap();
            // The point light below is behind every surface this camera sees from above it
            // or lights it; its N·L decides.
            let lp = normalize(sub([0.0, -5.0, 0.0], p)).unwrap();
            let mut want = [0.8, 0.4, 0.2].map(|c| 0.5 * c * 0.3);
            for (cos, i) in [(dot(n, l), 0.9), (dot(n, lp), 2.0)] {
                if cos > 0.0 {
                    for (k, base) in [0.8, 0.4, 0.2].iter().enumerate() {
                        want[k] += 0.7 * cos * base * i;
                    }
                }
            }
            assert_close(px.colour, want, 1e-9, "local term");
            let bits = (dot(n, l) <= 0.0) as u8 | ((dot(n, lp) <= 0.0) as u8) << 1;
            assert_eq!(px.shadow, bits);
        }
    }
    assert!(hits > 300 && misses > 300, "{hits} {misses}");
}

#[test]
fn every_primitive_casts_a_shadow() {
    let dir = std::env::temp_dir().join(format!("trace-shadow-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("tri.obj"),
        "v -0.4 1 -0.4\nv 0 1 0.4\nv 0.4 1 -0.4\nf 1 2 3\n",
    )
    .unwrap();
    let casters = [
        "sphere 0 1 0 0.4 m",
        "plane 1 0 0 -0.5 m",
        "box -0.4 0.6 -0.4 0.4 1.4 0.4 m",
        "cylinder 0 0.6 0 0 1.4 0 0.4 m",
        "cone 0 0.6 0 0.4 0 1.4 0 0 m",
        "ellipsoid 0 1 0 0.4 0.3 0.5 m",
        "polygon m -0.4 1 -0.4 -0.4 1 0.4 0.4 1 0.4 0.4 1 -0.4",
        "mesh tri.obj m",
    ];
    // The light comes from (−1, 1, 0): the caster around (0, 1, 0) (or, for the plane, the
    // wall x = 0.5) shadows the floor at (1, 0, 0) and not at (−1, 0, 0). Each probe is seen
    // straight from above by the single pixel of a 1×1 image.
    for caster in casters {
        let text = format!(
            "ambient 0.2\nlight directional -1 1 0 1\nmaterial m 0.8 0.8 0.8 1 0.8 0 0 air\n\
             plane 0 1 0 0 m\n{caster}\n"
        );
        let scene = TracedScene::parse(&text, &dir, "shadow.scene").unwrap();
        let accel = Accel::build(&scene, Structure::Both);
        let tracer = Tracer::new(&accel, Limits::default());
        for (probe, shadowed) in [([1.0, 0.0, 0.0], true), ([-1.0, 0.0, 0.0], false)] {
            let spec = camera([probe[0], 8.0, 0.0], probe, [0.0, 0.0, -1.0]);
            let cam: Camera = check_camera(&spec).unwrap();
            let mut stats = TraceStats::default();
            let p = tracer.pixel(&cam, 0, 0, 1, 1, &mut stats);
            assert_eq!(p.hit.map(|hit| hit.id), Some(0), "{caster}: the floor");
            assert_eq!(p.shadow & 1 != 0, shadowed, "{caster} at {probe:?}");
            // In shadow only the ambient term remains: KA·C·ambient.
            if shadowed {
                assert_close(p.colour, [0.8 * 0.2; 3], 1e-12, caster);
            }
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn each_acceleration_cuts_tests_tenfold_on_the_mesh_and_gives_the_same_image() {
    let s = corpus::by_name("mesh").unwrap();
    let scene = s.load().unwrap();
    assert!(scene.triangle_count() >= 1000);
    let (_, cam) = s.cameras[0];
    let (w, h) = (40, 30);
    let images: Vec<_> = Structure::ALL
        .iter()
        .map(|&st| {
            (
                st,
                render(&scene, &cam, w, h, Limits::default(), st).unwrap(),
            )
        })
        .collect();
    let brute = &images[0].1;
    let brute_tests = brute.stats.tests_per_ray();
    for (st, img) in &images {
        assert_eq!(img.ids, brute.ids, "{}", st.name());
        assert_eq!(img.depth, brute.depth, "{}", st.name());
        assert_eq!(img.shadow, brute.shadow, "{}", st.name());
        assert_eq!(img.color, brute.color, "{}", st.name());
        let per_ray = img.stats.tests_per_ray();
        println!(
            "{:>5}: {per_ray:8.2} object tests per ray ({:.1}x fewer than brute force), {:.2} box tests per ray",
            st.name(),
            brute_tests / per_ray,
            (img.stats.rays.box_tests + img.stats.shadows.box_tests) as f64
                / (img.stats.traced_rays() + img.stats.shadow) as f64
        );
        if *st != Structure::None {
            assert!(
                brute_tests >= 10.0 * per_ray,
                "{}: {per_ray} vs {brute_tests}",
                st.name()
            );
        }
    }
}

#[test]
fn every_corpus_scene_traces_the_same_with_every_structure() {
    for s in corpus::all() {
        let scene = s.load().unwrap();
        for (label, cam) in &s.cameras {
            let (w, h) = (24, 18);
            let brute = render(&scene, cam, w, h, Limits::default(), Structure::None).unwrap();
            assert!(brute.ids.iter().any(|&i| i >= 0), "{} {label}", s.name);
            for st in [Structure::Bvh, Structure::Grid, Structure::Both] {
                let img = render(&scene, cam, w, h, Limits::default(), st).unwrap();
                assert_eq!(
                    (&img.ids, &img.color, &img.shadow),
                    (&brute.ids, &brute.color, &brute.shadow),
                    "{} {label} {}",
                    s.name,
                    st.name()
                );
            }
        }
    }
}

#[test]
fn the_corpus_exercises_what_it_is_for() {
    let image = |name: &str, camera: usize| {
        let s = corpus::by_name(name).unwrap();
        let scene = s.load().unwrap();
        let cam = s.cameras[camera].1;
        render(&scene, &cam, 48, 36, Limits::default(), Structure::Both).unwrap()
    };
    // Seen from below, the water surface reflects totally beyond 48.8°.
    assert!(image("water", 1).stats.total_internal_reflections > 0);
    assert!(image("diamond", 0).stats.total_internal_reflections > 0);
    // Inside the glass every primary ray meets the sphere (id 0) from within and refracts out.
    let inside = image("inside-glass", 0);
    assert!(inside.ids.iter().all(|&id| id == 0));
    assert!(inside.stats.secondary_by_depth[1] >= inside.stats.primary);
}

fn sim(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_sim"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

#[test]
fn sim_trace_writes_the_documented_files() {
    let dir = std::env::temp_dir().join(format!("trace-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = |f: &str| dir.join(f).display().to_string();
    let scene = corpus::by_name("classic")
        .unwrap()
        .path()
        .display()
        .to_string();
    let (code, _, stderr) = sim(&[
        "trace",
        &scene,
        "--eye",
        "0,3,7",
        "--target",
        "0,0.8,0",
        "--size",
        "32x24",
        "--out",
        &p("t.png"),
        "--ids",
        &p("t.ids"),
        "--depth",
        &p("t.depth"),
        "--shadow",
        &p("t.shadow"),
        "--renderer",
        "reference",
        "--max-depth",
        "3",
        "--threshold",
        "0.01",
    ]);
    assert_eq!(code, 0, "{stderr}");
    let len = |f: &str| std::fs::metadata(dir.join(f)).unwrap().len();
    assert_eq!(len("t.ids"), 32 * 24 * 4);
    assert_eq!(len("t.depth"), 32 * 24 * 4);
    assert_eq!(len("t.shadow"), 32 * 24);
    assert!(len("t.png") > 0);
    let ids = std::fs::read(dir.join("t.ids")).unwrap();
    let first = i32::from_le_bytes([ids[0], ids[1], ids[2], ids[3]]);
    assert_eq!(first, -1, "the top-left pixel sees the sky");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn sim_trace_rejects_bad_scenes_and_cameras_with_one_line() {
    let dir = std::env::temp_dir().join(format!("trace-cli-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let bad = dir.join("bad.scene");
    std::fs::write(&bad, "material m 1 1 1 0 1 0 0 1\nsphere 0 0 0 -1 m\n").unwrap();
    let good = corpus::by_name("classic")
        .unwrap()
        .path()
        .display()
        .to_string();
    let bad = bad.display().to_string();
    // (scene, eye, further arguments, what the error says); the target is the origin.
    let cases: [(&str, &str, &[&str], &str); 10] = [
        (&bad, "0,0,5", &[], "bad.scene:2: radius -1"),
        ("/nonexistent.scene", "0,0,5", &[], "nonexistent"),
        (&good, "0,0,0", &[], "same point"),
        (&good, "0,5,0", &[], "parallel"),
        (&good, "0,0,5", &["--fov", "0"], "field of view"),
        (&good, "0,0,5", &["--near", "5", "--far", "1"], "near"),
        (&good, "0,0,5", &["--renderer", "magic"], "magic"),
        (
            &good,
            "0,0,5",
            &["--max-depth", "1000"],
            "max depth 1000 exceeds 64",
        ),
        (&good, "0,0,5", &["--threshold=-1"], "threshold -1"),
        (&good, "0,0,5", &["--size", "0x10"], "size 0x10"),
    ];
    for (scene, eye, extra, want) in cases {
        let mut args = vec!["trace", scene, "--eye", eye, "--target", "0,0,0"];
        args.extend_from_slice(extra);
        let (code, stdout, stderr) = sim(&args);
        assert_eq!(code, 2, "{args:?}: {stdout}{stderr}");
        assert_eq!(stderr.lines().count(), 1, "{args:?}: {stderr}");
        assert!(
            stderr.starts_with("sim: ") && stderr.contains(want),
            "{args:?}: {stderr}"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

mod hostile {
    use super::*;
    use proptest::prelude::*;

    /// Tokens of every kind, well-formed and not: keywords, numbers from tiny to huge, names.
    fn token() -> impl Strategy<Value = String> {
        prop_oneof![
            prop::sample::select(vec![
                "sphere",
                "plane",
                "box",
                "cylinder",
                "cone",
                "ellipsoid",
                "polygon",
                "mesh",
                "light",
                "point",
                "directional",
                "material",
                "background",
                "ambient",
                "m",
                "glass",
                "diamond",
                "nan",
                "inf",
                "-inf",
                "1e308",
                "-1e308",
                "1e-300",
                "0",
                "-0",
                "#",
                "x.obj",
                "",
            ])
            .prop_map(String::from),
            (-1e6f64..1e6).prop_map(|v| format!("{v}")),
            (-3.0f64..3.0).prop_map(|v| format!("{v:.2}")),
        ]
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

        /// Random lines after a valid material: either a scene or one line naming the line.
        #[test]
        fn random_scene_text_never_panics(
            lines in proptest::collection::vec(proptest::collection::vec(token(), 0..14), 0..8)
        ) {
            let text = std::iter::once("material m 1 1 1 0.2 0.8 0.3 0.3 glass".to_string())
                .chain(lines.iter().map(|l| l.join(" ")))
                .collect::<Vec<_>>()
                .join("\n");
            match TracedScene::parse(&text, Path::new("/nonexistent"), "h.scene") {
                Ok(_) => {}
                Err(e) => {
                    prop_assert!(e.starts_with("h.scene:") && !e.contains('\n'), "{}", e);
                }
            }
        }

        /// Valid scenes with extreme but finite numbers trace without panicking, and every
        /// structure gives the same image.
        #[test]
        fn extreme_scenes_trace(
            scale in prop::sample::select(vec![1e-6, 1.0, 1e6, 1e150]),
            spheres in proptest::collection::vec(([-3.0f64..3.0, -3.0f64..3.0, -3.0f64..3.0], 0.01f64..2.0), 1..6),
            depth in 0u32..8,
        ) {
            let mut text = String::from(
                "light point 0 5 5 1\nlight directional 1 1 0 0.5\n\
                 material m 1 1 1 0.2 0.8 0.4 0.6 diamond\nplane 0 1 0 3 m\n",
            );
            for (c, r) in &spheres {
                text += &format!("sphere {} {} {} {} m\n", c[0] * scale, c[1] * scale, c[2] * scale, r * scale);
                text += &format!("box {} {} {} {} {} {} m\n", c[0] * scale, c[1] * scale, c[2] * scale,
                    (c[0] + r) * scale, (c[1] + r) * scale, (c[2] + r) * scale);
            }
            let scene = parse(&text);
            let cam = CameraSpec {
                eye: [0.0, 0.0, 8.0 * scale],
                target: [0.0; 3],
                up: [0.0, 1.0, 0.0],
                fovy: 60.0,
                near: 0.01 * scale,
                far: 100.0 * scale,
            };
            let limits = Limits { max_depth: depth, threshold: 0.0 };
            let brute = render(&scene, &cam, 6, 4, limits, Structure::None).unwrap();
            for st in [Structure::Bvh, Structure::Grid, Structure::Both] {
                let img = render(&scene, &cam, 6, 4, limits, st).unwrap();
                prop_assert_eq!(&img.ids, &brute.ids);
                prop_assert_eq!(&img.color, &brute.color);
            }
        }
    }
}

#[test]
fn primary_rays_see_eye_depths_in_near_to_far() {
    // A unit sphere 3 in front of the eye: the centre pixel meets it at eye depths 2 and 4.
    let scene = parse("ambient 1\nmaterial m 1 1 1 1 0 0 0 1\nsphere 0 0 -3 1 m\n");
    let accel = Accel::build(&scene, Structure::None);
    let tracer = Tracer::new(&accel, Limits::default());
    let depth_seen = |near: f64, far: f64| {
        let spec = CameraSpec {
            eye: [0.0; 3],
            target: [0.0, 0.0, -1.0],
            up: [0.0, 1.0, 0.0],
            fovy: 40.0,
            near,
            far,
        };
        let cam = check_camera(&spec).unwrap();
        let mut stats = TraceStats::default();
        tracer.pixel(&cam, 0, 0, 1, 1, &mut stats).hit.map(|h| h.t)
    };
    assert_eq!(depth_seen(0.1, 10.0), Some(2.0));
    assert_eq!(depth_seen(2.0, 10.0), Some(2.0), "near is included");
    assert_eq!(
        depth_seen(2.5, 10.0),
        Some(4.0),
        "the front is clipped: the inside shows"
    );
    assert_eq!(depth_seen(2.5, 4.0), None, "far is excluded");
    assert_eq!(depth_seen(0.1, 2.0), None);
}

#[test]
fn the_depth_image_holds_eye_depth_along_the_view_axis() {
    // A wall facing the camera 5 units away: every pixel's eye depth is 5, not its distance.
    let scene = parse("ambient 1\nmaterial m 1 1 1 1 0 0 0 1\nplane 0 0 1 5 m\n");
    let cam = camera([0.0; 3], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]);
    let img = render(&scene, &cam, 9, 7, Limits::default(), Structure::None).unwrap();
    assert!(img.ids.iter().all(|&id| id == 0));
    assert!(
        img.depth.iter().all(|&d| (d - 5.0).abs() < 1e-5),
        "{:?}",
        img.depth
    );
}

/// The checker rule against its formula: on a textured plane seen from above (ambient light
/// only, so a pixel's colour is its material's `KA·C·ambient`), each pixel's colour is that of
/// material A where `floor(x / SIZE) + floor(z / SIZE)` is even at the hit point and B
/// elsewhere, over cells on both sides of both axes.
#[test]
fn a_checker_texture_follows_its_formula() {
    let scene = parse(
        "ambient 1\n\
         material a 0.2 0.4 0.6 1 0 0 0 1\n\
         material b 0.8 0.6 0.2 1 0 0 0 1\n\
         checker tiles a b 0.5\n\
         plane 0 1 0 0 tiles\n",
    );
    let spec = CameraSpec {
        fovy: 60.0,
        ..camera([0.3, 5.0, 0.2], [0.3, 0.0, 0.2], [0.0, 0.0, -1.0])
    };
    let cam = check_camera(&spec).unwrap();
    let (w, h) = (64, 64);
    let img = render(&scene, &spec, w, h, Limits::default(), Structure::Both).unwrap();
    let colour = |k: usize| scene.materials[k].color.map(|c| (255.0 * c).round() as u8);
    let (mut seen, mut negative) = ([0; 2], 0);
    for y in 0..h {
        for x in 0..w {
            let dir = scanline3d_sim::trace::scene::primary_ray(&cam, x, y, w, h);
            let t = -spec.eye[1] / dir[1];
            let p = [spec.eye[0] + t * dir[0], 0.0, spec.eye[2] + t * dir[2]];
            let cell = |c: f64| (c / 0.5).floor() as i64;
            let k = (cell(p[0]) + cell(p[2])).rem_euclid(2) as usize;
            seen[k] += 1;
            negative += usize::from(p[0] < 0.0 && p[2] < 0.0);
            let i = y * w + x;
            assert_eq!(img.color[i], colour(k), "pixel ({x}, {y}) at {p:?}");
            assert_eq!(img.materials[i], k as i32, "pixel ({x}, {y})");
        }
    }
    assert!(
        seen[0] > 1000 && seen[1] > 1000 && negative > 100,
        "{seen:?} {negative}"
    );
}

/// The cell boundaries and the projection: a boundary belongs to the cell above it (a floor),
/// negative coordinates included; the coordinate of the normal's largest axis is dropped (the
/// first of equal ones, as the polygon test); and everything of the material comes from the
/// cell: a mirror cell spawns a reflected ray, a diffuse one nothing.
#[test]
fn checker_cells_boundaries_axes_and_coefficients() {
    let scene = parse(
        "material a 1 1 1 1 0 0 0 1\n\
         material mirror 1 1 1 0.1 0 0.5 0 1\n\
         checker c a mirror 1\n\
         plane 0 1 0 0 c\n\
         polygon c 2 0 0 2 0 1 2 1 1 2 1 0\n\
         polygon c 0 0 0 1 1 0 1 1 1 0 0 1\n",
    );
    let at = |id: usize, p: V3| scene.material_index_at(id, p).unwrap();
    // Floor y = 0: x and z kept.
    for (p, k) in [
        ([0.0, 0.0, 0.5], 0),
        ([-1e-12, 0.0, 0.5], 1),
        ([1.0, 0.0, 0.5], 1),
        ([-1.0, 0.0, 0.5], 1),
        ([-1.0, 0.0, -1.0], 0),
        ([-0.5, 0.0, -0.5], 0),
        ([-1.5, 0.0, 0.5], 0),
        ([3.5, 0.0, -2.5], 0),
        ([3.5, 0.0, -1.5], 1),
    ] {
        assert_eq!(at(0, p), k, "{p:?}");
    }
    // The wall x = 2 (normal along x): y and z kept, x ignored.
    assert_eq!(at(1, [2.0, 0.5, 0.5]), 0);
    assert_eq!(at(1, [2.0, 1.5, 0.5]), 1);
    assert_eq!(at(1, [2.0, 0.5, -0.5]), 1);
    // A polygon whose normal (1, −1, 0)/√2 has equal x and y: x is dropped, y and z kept.
    assert_eq!(at(2, [0.5, 0.5, 0.5]), 0);
    assert_eq!(at(2, [1.5, 0.5, 0.5]), 0, "x does not count");
    assert_eq!(at(2, [0.5, 1.5, 0.5]), 1, "y does");
    // The mirror cell's KR: a ray straight down into cell (0, 0) reflects, into (1, 0) not.
    let down = |x: f64| Ray {
        origin: [x, 1.0, 0.5],
        dir: [0.0, -1.0, 0.0],
    };
    let (_, plain) = trace_logged(&scene, down(0.5), Limits::default());
    let (_, mirror) = trace_logged(&scene, down(1.5), Limits::default());
    assert!(log(&plain).is_empty());
    assert_eq!(log(&mirror).len(), 1);
    assert_eq!(log(&mirror)[0].spawn, Spawn::Reflection);
}
