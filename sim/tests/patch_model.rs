//! The shipped patch models parse and are what their headers say.

use scanline3d_sim::patch::{parse, PatchModel};
use std::path::Path;

fn model(name: &str) -> PatchModel {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes/patches")
        .join(name);
    parse::load(&path).unwrap()
}

#[test]
fn teapot_has_32_patches_and_collapsed_lid_and_bottom() {
    let m = model("teapot.bpt");
    assert_eq!(m.patches.len(), 32);
    // A patch whose first row of control points is one point has a collapsed u = 0 edge.
    let collapsed: Vec<usize> = (0..32)
        .filter(|&k| {
            m.patches[k].points[..4]
                .iter()
                .all(|p| *p == m.patches[k].points[0])
        })
        .collect();
    assert_eq!(collapsed, vec![20, 21, 22, 23, 28, 29, 30, 31]);
    assert!(m.patches.iter().all(|p| p.is_polynomial()));
    for (k, p) in m.patches.iter().enumerate() {
        for (u, v) in [(0.0, 0.3), (0.0, 0.0), (1.0, 1.0), (0.5, 0.5)] {
            let n = p
                .normal(u, v)
                .unwrap_or_else(|| panic!("patch {k} ({u}, {v})"));
            assert!(n.iter().all(|c| c.is_finite()));
        }
    }
}

#[test]
fn sphere_is_exact_closed_and_faces_outward() {
    let m = model("sphere.bpt");
    assert_eq!(m.patches.len(), 8);
    for p in &m.patches {
        assert!(!p.is_polynomial());
        for a in 0..=10 {
            for b in 0..=10 {
                let (u, v) = (a as f64 / 10.0, b as f64 / 10.0);
                let x = p.point(u, v);
                let r = (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt();
                assert!((r - 1.0).abs() < 1e-14, "radius {r}");
                let n = p.normal(u, v).unwrap();
                // The unit sphere's outward normal is the point itself.
                let err = (0..3).map(|k| (n[k] - x[k]).abs()).fold(0.0, f64::max);
                assert!(err < 1e-6, "normal {n:?} at {x:?}");
            }
        }
    }
    // Closed: every boundary edge that is not collapsed to a pole is another patch's edge,
    // point for point (the same parameter, or reversed).
    let edges = |p: &scanline3d_sim::patch::Patch, t: f64| {
        [
            p.point(0.0, t),
            p.point(1.0, t),
            p.point(t, 0.0),
            p.point(t, 1.0),
        ]
    };
    let close = |a: [f64; 3], b: [f64; 3]| (0..3).all(|c| (a[c] - b[c]).abs() < 1e-14);
    for (k, p) in m.patches.iter().enumerate() {
        for e in 0..4 {
            if close(edges(p, 0.2)[e], edges(p, 0.7)[e]) {
                continue; // a pole
            }
            let shared = m.patches.iter().enumerate().any(|(o, q)| {
                o != k
                    && (0..4).any(|f| {
                        [0.1, 0.37, 0.8]
                            .iter()
                            .all(|&t| close(edges(p, t)[e], edges(q, t)[f]))
                            || [0.1, 0.37, 0.8]
                                .iter()
                                .all(|&t| close(edges(p, t)[e], edges(q, 1.0 - t)[f]))
                    })
            });
            assert!(shared, "patch {k} edge {e} is not shared");
        }
    }
}

#[test]
fn trimmed_sheet_has_a_hole_and_an_island() {
    let m = model("trimmed.bpt");
    let p = &m.patches[0];
    assert_eq!(p.trims.len(), 2);
    assert!(p.is_kept(0.1, 0.1));
    assert!(!p.is_kept(0.5, 0.3));
    assert!(p.is_kept(0.5, 0.5));
    // x = 2u − 1, y = 2v − 1 exactly.
    let x = p.point(0.3, 0.8);
    assert!((x[0] + 0.4).abs() < 1e-15 && (x[1] - 0.6).abs() < 1e-15);
}
