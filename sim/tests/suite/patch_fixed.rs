//! The library's fixed-point patch renderer on the shipped models: the exact rational sphere
//! against its analytic silhouette and depth (coverage mismatches, their distance from the
//! silhouette, depth error) at several tolerances, shading against the analytic normals, and
//! the teapot (degenerate lid and bottom patches, drawn two-sided) without garbage.

use embedded_graphics::pixelcolor::RgbColor;
use scanline3d_sim::patch::fixed::{render_fixed, PatchShading, PATCH_COLOR};
use scanline3d_sim::patch::parse;
use scanline3d_sim::scene::{CameraSpec, LightSpec};

fn load(name: &str) -> scanline3d_sim::patch::PatchModel {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/patches");
    parse::load(&dir.join(name)).unwrap()
}

fn camera(eye: [f64; 3], target: [f64; 3], up: [f64; 3]) -> CameraSpec {
    CameraSpec {
        eye,
        target,
        up,
        fovy: 50.0,
        near: 0.1,
        far: 100.0,
    }
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Per pixel centre: the eye depth of the unit sphere's first hit, or `None`, and the signed
/// screen distance (pixels) from the silhouette (positive inside).
fn sphere_pixel(cam: &CameraSpec, x: usize, y: usize, w: usize, h: usize) -> (Option<f64>, f64) {
    let r = cam.reference().unwrap();
    let d = r.ray(x as f64 + 0.5, y as f64 + 0.5, w, h);
    let e = cam.eye;
    // |e + t·d|² = 1: t² d·d + 2t e·d + e·e − 1 = 0; t is the eye depth (d is depth-scaled).
    let (a, b, c) = (dot(d, d), dot(e, d), dot(e, e) - 1.0);
    let closest = (c + 1.0 - b * b / a).max(0.0).sqrt(); // ray's distance from the centre
    let t_closest = -b / a;
    let px = r.focal_px(h) / t_closest;
    let inside = (1.0 - closest) * px;
    let disc = b * b - a * c;
    let hit = (disc >= 0.0).then(|| (-b - disc.sqrt()) / a);
    (hit, inside)
}

#[test]
fn the_rational_sphere_matches_its_analytic_silhouette_and_depth() {
    let model = load("sphere.bpt");
    let (w, h) = (240, 240);
    let light = LightSpec::default();
    let views = [
        camera([2.0, 1.5, 2.5], [0.0; 3], [0.0, 1.0, 0.0]),
        camera([0.3, 3.2, 0.4], [0.1, 0.0, 0.0], [1.0, 0.0, 0.0]),
        camera([-1.5, -0.8, 2.2], [0.0, 0.2, 0.0], [0.0, 1.0, 0.0]),
    ];
    for tolerance in [2.0, 0.5] {
        let (mut mismatches, mut worst, mut depth_err, mut triangles) =
            (0usize, 0.0f64, 0.0f64, 0u32);
        for cam in &views {
            let r = render_fixed(
                &model,
                cam,
                &light,
                (w, h),
                tolerance,
                false,
                PatchShading::Flat,
            )
            .unwrap();
            assert_eq!(
                (r.stats.late, r.stats.frame.dropped, r.stats.capped),
                (0, 0, 0)
            );
            triangles += r.stats.frame.triangles_in;
            for y in 0..h {
                for x in 0..w {
                    let (hit, inside) = sphere_pixel(cam, x, y, w, h);
                    let id = r.image.ids[y * w + x];
                    assert!((-1..8).contains(&id));
                    if (id >= 0) != hit.is_some() {
                        mismatches += 1;
                        worst = worst.max(inside.abs());
                    } else if let Some(t) = hit {
                        // Depth compared away from the silhouette, where it is steep.
                        if inside > 2.0 {
                            let got = r.image.depth[y * w + x] as f64;
                            depth_err = depth_err.max((got - t).abs() / t);
                        }
                    }
                }
            }
        }
        let share = mismatches as f64 / (views.len() * w * h) as f64;
        eprintln!(
            "sphere, tolerance {tolerance} px: {triangles} triangles over {} views, coverage mismatches {:.3} % ({mismatches}), farthest {worst:.2} px from the silhouette, depth error {depth_err:.2e} relative",
            views.len(),
            100.0 * share
        );
        // Mismatches only where the chords cut inside the silhouette (the tolerance) or a
        // centre is within rounding of it (one pixel covers the snap and the measure's slack).
        assert!(
            worst <= tolerance + 1.0,
            "tolerance {tolerance}: {worst} px"
        );
        if tolerance <= 0.5 {
            assert!(share <= 0.005, "tolerance {tolerance}: {share}");
        }
        // The tolerance bounds screen-space distance only: where the surface faces the eye a
        // chord's sag is along the view and shows in depth alone. So depth error is measured
        // and reported, and checked here only against garbage (a few percent of the depth is
        // a sag of a few hundredths of the radius at most).
        assert!(depth_err < 0.05, "{depth_err}");
    }
}

#[test]
fn gouraud_shading_follows_the_analytic_normals() {
    let model = load("sphere.bpt");
    let (w, h) = (160, 160);
    let light = LightSpec::default();
    let cam = camera([2.0, 1.5, 2.5], [0.0; 3], [0.0, 1.0, 0.0]);
    let r = render_fixed(
        &model,
        &cam,
        &light,
        (w, h),
        0.5,
        false,
        PatchShading::Gouraud,
    )
    .unwrap();
    let dir = {
        let d = light.direction;
        let n = dot(d, d).sqrt();
        d.map(|c| c / n)
    };
    let (mut worst, mut sum, mut count) = (0.0f64, 0.0, 0);
    for y in 0..h {
        for x in 0..w {
            let (hit, inside) = sphere_pixel(&cam, x, y, w, h);
            let (Some(t), true) = (hit, inside > 2.0) else {
                continue;
            };
            let ray = cam
                .reference()
                .unwrap()
                .ray(x as f64 + 0.5, y as f64 + 0.5, w, h);
            let p = [0, 1, 2].map(|k| cam.eye[k] + t * ray[k]);
            let i = light.ambient + light.diffuse * dot(p, dir).max(0.0);
            let want = PATCH_COLOR.g() as f64 * i;
            let got = r.image.color[y * w + x][1] as f64;
            worst = worst.max((got - want).abs());
            sum += (got - want).abs();
            count += 1;
        }
    }
    let mean = sum / count as f64;
    eprintln!("sphere, Gouraud: green-channel error mean {mean:.2}, largest {worst:.2} of 255 over {count} pixels");
    // Vertex colours are lit exactly (from the patch normals); between vertices colours are
    // interpolated linearly, which errs by the shading's curvature over a triangle: small on
    // average, largest where the lit side turns fastest.
    assert!(mean < 1.0, "{mean}");
}

#[test]
fn the_teapot_renders_two_sided_without_garbage() {
    let model = load("teapot.bpt");
    let (w, h) = (200, 160);
    let light = LightSpec::default();
    for (k, eye) in [[6.0, -8.0, 5.0], [0.0, 0.01, 9.0], [2.0, 1.0, 2.4]]
        .into_iter()
        .enumerate()
    {
        let cam = camera(eye, [0.0, 0.0, 1.2], [0.0, 0.0, 1.0]);
        for shading in [PatchShading::Flat, PatchShading::Gouraud] {
            let r = render_fixed(&model, &cam, &light, (w, h), 1.0, false, shading).unwrap();
            let covered = r.image.ids.iter().filter(|&&i| i >= 0).count();
            assert!(covered > 500, "view {k}: {covered}");
            assert_eq!(r.stats.late, 0);
            assert_eq!(r.stats.frame.dropped, 0);
            for (i, &id) in r.image.ids.iter().enumerate() {
                assert!((-1..32).contains(&id));
                let d = r.image.depth[i];
                if id >= 0 {
                    // Within the teapot's reach from the eye (it fits a ball of radius 4).
                    let far = dot(eye, eye).sqrt() + 4.0;
                    assert!(
                        d.is_finite() && d > 0.0 && (d as f64) < far,
                        "view {k}: {d}"
                    );
                } else {
                    assert!(d.is_infinite());
                }
            }
        }
    }
}
