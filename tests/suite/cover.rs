//! Cover tests: planar tilings cover every pixel centre inside exactly once and outside never,
//! and single-triangle coverage equals the exact edge-function test with the top-left rule.

use crate::common;

use common::*;
use proptest::prelude::*;
use scanline3d::raster::for_each_span;
use scanline3d::scene::Instance;

type Pt = (i32, i32);

/// Exact edge-function coverage with the top-left rule (independent of the walker).
fn covers(v: [Pt; 3], s: u32, c: i64, r: i64) -> bool {
    let (px, py) = ((2 * c + 1) << s, (2 * r + 1) << s);
    let v = v.map(|(x, y)| (2 * x as i64, 2 * y as i64));
    let area = (v[1].0 - v[0].0) * (v[2].1 - v[0].1) - (v[2].0 - v[0].0) * (v[1].1 - v[0].1);
    if area == 0 {
        return false;
    }
    (0..3).all(|i| {
        let (a, b) = if area > 0 {
            (v[i], v[(i + 1) % 3])
        } else {
            (v[(i + 1) % 3], v[i])
        };
        let e = (b.0 - a.0) * (py - a.1) - (b.1 - a.1) * (px - a.0);
        e > 0 || (e == 0 && ((a.1 == b.1 && b.0 > a.0) || b.1 < a.1))
    })
}

fn spans(v: [Pt; 3], s: u32, w: i32, h: i32, mut f: impl FnMut(i32, i32)) {
    let g = |r: i32, x0: i32, x1: i32| (x0..x1).for_each(|c| f(c, r));
    match s {
        0 => for_each_span::<0>(v, w, h, g),
        2 => for_each_span::<2>(v, w, h, g),
        4 => for_each_span::<4>(v, w, h, g),
        8 => for_each_span::<8>(v, w, h, g),
        _ => unreachable!(),
    }
}

const W: i32 = 24;
const H: i32 = 20;

/// Checks a tiling of the rectangle `[x0, x1) × [y0, y1)` (sub-pixel units): every centre
/// inside is covered exactly once, every other centre never.
fn check_tiling(tris: &[[Pt; 3]], rect: (i32, i32, i32, i32), s: u32) -> Result<(), TestCaseError> {
    let mut count = vec![0u32; (W * H) as usize];
    for &t in tris {
        spans(t, s, W, H, |c, r| count[(r * W + c) as usize] += 1);
    }
    let (x0, y0, x1, y1) = rect;
    for r in 0..H {
        for c in 0..W {
            let (cx, cy) = (((2 * c + 1) << s) as i64, ((2 * r + 1) << s) as i64);
            let inside = 2 * x0 as i64 <= cx
                && cx < 2 * x1 as i64
                && 2 * y0 as i64 <= cy
                && cy < 2 * y1 as i64;
            prop_assert_eq!(
                count[(r * W + c) as usize],
                inside as u32,
                "pixel ({}, {}) S={}",
                c,
                r,
                s
            );
        }
    }
    Ok(())
}

fn orient(a: Pt, b: Pt, c: Pt) -> i64 {
    (b.0 as i64 - a.0 as i64) * (c.1 as i64 - a.1 as i64)
        - (c.0 as i64 - a.0 as i64) * (b.1 as i64 - a.1 as i64)
}

/// A random triangulation of the rectangle: two triangles, then random interior point
/// insertions (1 → 3 splits) and random flips of convex quads.
fn random_triangulation(rect: (i32, i32, i32, i32), picks: &[(u32, u32, u32)]) -> Vec<[Pt; 3]> {
    let (x0, y0, x1, y1) = rect;
    let mut tris = vec![
        [(x0, y0), (x1, y0), (x1, y1)],
        [(x0, y0), (x1, y1), (x0, y1)],
    ];
    for &(a, b, k) in picks {
        let p = (
            x0 + (a % (x1 - x0) as u32) as i32,
            y0 + (b % (y1 - y0) as u32) as i32,
        );
        if k % 3 != 0 {
            // Insert p if strictly inside some triangle.
            if let Some(i) = tris.iter().position(|t| {
                let o = orient(t[0], t[1], t[2]).signum();
                (0..3).all(|e| orient(t[e], t[(e + 1) % 3], p).signum() == o)
            }) {
                let [a, b, c] = tris.swap_remove(i);
                tris.extend([[a, b, p], [b, c, p], [c, a, p]]);
            }
        } else {
            // Flip a shared edge of two triangles if their quad is strictly convex.
            let n = tris.len();
            let i = (a as usize) % n;
            for j in 0..n {
                if j == i {
                    continue;
                }
                let (ti, tj) = (tris[i], tris[j]);
                let shared: Vec<Pt> = ti.iter().copied().filter(|v| tj.contains(v)).collect();
                if shared.len() != 2 {
                    continue;
                }
                let pi = *ti.iter().find(|v| !shared.contains(v)).unwrap();
                let pj = *tj.iter().find(|v| !shared.contains(v)).unwrap();
                let (s0, s1) = (shared[0], shared[1]);
                // Convex iff pi and pj are on opposite sides of s0-s1 and s0, s1 on opposite
                // sides of pi-pj.
                if orient(s0, s1, pi).signum() * orient(s0, s1, pj).signum() < 0
                    && orient(pi, pj, s0).signum() * orient(pi, pj, s1).signum() < 0
                {
                    tris[i] = [pi, pj, s0];
                    tris[j] = [pj, pi, s1];
                }
                break;
            }
        }
    }
    tris
}

fn rect_strategy(s: u32) -> impl Strategy<Value = (i32, i32, i32, i32)> {
    let unit = 1i32 << s;
    (
        -3 * unit..(W + 2) * unit,
        -3 * unit..(H + 2) * unit,
        2 * unit..18 * unit,
        2 * unit..16 * unit,
    )
        .prop_map(|(x, y, w, h)| (x, y, x + w, y + h))
}

fn sub_bits() -> impl Strategy<Value = u32> {
    prop_oneof![Just(0u32), Just(2u32), Just(4u32), Just(8u32)]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 1500, ..ProptestConfig::default() })]

    #[test]
    fn random_triangulations_tile_exactly_once(
        (s, rect, picks) in sub_bits().prop_flat_map(|s| (Just(s), rect_strategy(s),
            proptest::collection::vec((any::<u32>(), any::<u32>(), any::<u32>()), 0..40)))
    ) {
        let tris = random_triangulation(rect, &picks);
        check_tiling(&tris, rect, s)?;
    }

    #[test]
    fn fans_tile_exactly_once(
        (s, rect, centre, cuts) in sub_bits().prop_flat_map(|s| (Just(s), rect_strategy(s),
            (any::<u32>(), any::<u32>()), proptest::collection::vec(any::<u32>(), 0..12)))
    ) {
        let (x0, y0, x1, y1) = rect;
        let c = (x0 + 1 + (centre.0 % (x1 - x0 - 1) as u32) as i32, y0 + 1 + (centre.1 % (y1 - y0 - 1) as u32) as i32);
        // Boundary points: corners plus random points on the perimeter, in order.
        let perimeter = 2 * ((x1 - x0) + (y1 - y0)) as u32;
        let mut ts: Vec<u32> = cuts.iter().map(|k| k % perimeter).collect();
        ts.extend([0, (x1 - x0) as u32, (x1 - x0 + y1 - y0) as u32, (2 * (x1 - x0) + y1 - y0) as u32]);
        ts.sort_unstable();
        ts.dedup();
        let at = |t: i32| -> Pt {
            let (w, h) = (x1 - x0, y1 - y0);
            if t < w { (x0 + t, y0) } else if t < w + h { (x1, y0 + t - w) }
            else if t < 2 * w + h { (x1 - (t - w - h), y1) } else { (x0, y1 - (t - 2 * w - h)) }
        };
        let pts: Vec<Pt> = ts.iter().map(|&t| at(t as i32)).collect();
        let tris: Vec<[Pt; 3]> = (0..pts.len()).map(|i| [c, pts[i], pts[(i + 1) % pts.len()]]).collect();
        check_tiling(&tris, rect, s)?;
    }

    #[test]
    fn jittered_grids_tile_exactly_once(
        (s, rect, n, jitter, diag) in sub_bits().prop_flat_map(|s| (Just(s), rect_strategy(s), (1usize..6, 1usize..6),
            proptest::collection::vec((any::<u32>(), any::<u32>()), 49), any::<u64>()))
    ) {
        let (x0, y0, x1, y1) = rect;
        let (nx, ny) = n;
        let (cw, ch) = ((x1 - x0) / nx as i32, (y1 - y0) / ny as i32);
        prop_assume!(cw >= 4 && ch >= 4);
        let p = |i: usize, j: usize| -> Pt {
            let x = if i == nx { x1 } else { x0 + i as i32 * cw };
            let y = if j == ny { y1 } else { y0 + j as i32 * ch };
            let (jx, jy) = jitter[(j * 7 + i) % 49];
            // Interior points move by under a quarter cell (quads stay convex); boundary points
            // slide only along their side.
            let dx = if i == 0 || i == nx { 0 } else { (jx % (cw / 2) as u32) as i32 - cw / 4 };
            let dy = if j == 0 || j == ny { 0 } else { (jy % (ch / 2) as u32) as i32 - ch / 4 };
            (x + dx, y + dy)
        };
        let mut tris = Vec::new();
        for j in 0..ny {
            for i in 0..nx {
                let (a, b, c, d) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
                if diag >> ((i + j * nx) % 64) & 1 == 0 {
                    tris.extend([[a, b, c], [a, c, d]]);
                } else {
                    tris.extend([[a, b, d], [b, c, d]]);
                }
            }
        }
        check_tiling(&tris, rect, s)?;
    }

    #[test]
    fn single_triangles_match_edge_functions(
        (s, v) in sub_bits().prop_flat_map(|s| {
            let unit = 1i32 << s;
            let p = (-4 * unit..(W + 4) * unit, -4 * unit..(H + 4) * unit);
            (Just(s), [p.clone(), p.clone(), p])
        })
    ) {
        let mut got = vec![false; (W * H) as usize];
        let mut twice = false;
        spans(v, s, W, H, |c, r| { twice |= got[(r * W + c) as usize]; got[(r * W + c) as usize] = true; });
        prop_assert!(!twice);
        for r in 0..H {
            for c in 0..W {
                prop_assert_eq!(got[(r * W + c) as usize], covers(v, s, c as i64, r as i64), "({}, {})", c, r);
            }
        }
    }
}

/// The full pipeline (transform, projection, snapping, buckets, span z-buffer) on a planar grid
/// facing the camera: the covered pixels form the projected rectangle, each drawn once.
fn pipeline_grid<const S: u32>(
    nx: usize,
    ny: usize,
    half: [f64; 2],
    dist: f64,
    fovy: f64,
    jitter: &[(f64, f64)],
) -> Result<(), TestCaseError> {
    const PW: usize = 40;
    const PH: usize = 32;
    let mut verts = Vec::new();
    for j in 0..=ny {
        for i in 0..=nx {
            let (u, v) = (i as f64 / nx as f64, j as f64 / ny as f64);
            let (ju, jv) = jitter[(j * (nx + 1) + i) % jitter.len()];
            let du = if i == 0 || i == nx {
                0.0
            } else {
                ju * 0.2 / nx as f64
            };
            let dv = if j == 0 || j == ny {
                0.0
            } else {
                jv * 0.2 / ny as f64
            };
            verts.push([
                (2.0 * (u + du) - 1.0) * half[0],
                (2.0 * (v + dv) - 1.0) * half[1],
                0.0,
            ]);
        }
    }
    let idx = |i: usize, j: usize| (j * (nx + 1) + i) as u16;
    let mut tris = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            tris.push([idx(i, j), idx(i + 1, j), idx(i + 1, j + 1)]);
            tris.push([idx(i, j), idx(i + 1, j + 1), idx(i, j + 1)]);
        }
    }
    // Snapping moves each vertex by up to half a snap unit (2^-(S+1) px) per axis. It is
    // monotonic per axis, so an unjittered grid can never fold; a jittered one (interior
    // vertices moved by up to 20 % of a cell) can fold once cells are only a few snap units
    // across, and then the *snapped* mesh is no longer a tiling (a real rasterizer draws it
    // faithfully, overlap included). Such inputs test the premise, not the renderer: require
    // jittered cells of at least 8 snap units.
    let focal_px = (PH as f64 / 2.0) / (fovy.to_radians() / 2.0).tan();
    let cell_px = (2.0 * half[0] / nx as f64).min(2.0 * half[1] / ny as f64) * focal_px / dist;
    let jittered = jitter.iter().any(|&(u, v)| u != 0.0 || v != 0.0) && (nx > 1 || ny > 1);
    prop_assume!(!jittered || cell_px >= 8.0 / (1u32 << S) as f64);
    let data = mesh_data(&verts, &tris);
    let mesh = data.mesh().unwrap();
    let instances = [Instance {
        mesh: &mesh,
        transform: scanline3d::scene::Transform::IDENTITY,
    }];
    let cam = CameraSpec {
        eye: [0.0, 0.0, dist],
        target: [0.0; 3],
        up: [0.0, 1.0, 0.0],
        fovy,
        near: 0.1,
        far: 100.0,
    };
    let (ids, stats) = render_ids::<PW, PH, S>(&instances, &cam, true);
    let covered: Vec<(usize, usize)> = (0..PW * PH)
        .filter(|&i| ids[i] >= 0)
        .map(|i| (i % PW, i / PW))
        .collect();
    // Each covered centre was drawn exactly once: no overlap between triangles.
    prop_assert_eq!(stats.fragments as usize, covered.len());
    prop_assert_eq!(stats.pixels_written as usize, covered.len());
    if covered.is_empty() {
        return Ok(());
    }
    let (cmin, cmax) = (
        covered.iter().map(|p| p.0).min().unwrap(),
        covered.iter().map(|p| p.0).max().unwrap(),
    );
    let (rmin, rmax) = (
        covered.iter().map(|p| p.1).min().unwrap(),
        covered.iter().map(|p| p.1).max().unwrap(),
    );
    // No holes: the covered set is a full rectangle of pixels...
    prop_assert_eq!(covered.len(), (cmax - cmin + 1) * (rmax - rmin + 1));
    // ...matching the exact projection of the world rectangle to within snapping.
    let lo = project(&cam, PW, PH, [-half[0], half[1], 0.0]).unwrap();
    let hi = project(&cam, PW, PH, [half[0], -half[1], 0.0]).unwrap();
    let first = |x: f64| (x - 0.5).ceil().max(0.0);
    let tol = 1.0 / (1u32 << S) as f64 + 1e-3;
    for (got, want_lo, want_hi) in [
        (cmin as f64, first(lo[0] - tol), first(lo[0] + tol)),
        (rmin as f64, first(lo[1] - tol), first(lo[1] + tol)),
    ] {
        prop_assert!(
            got >= want_lo && got <= want_hi,
            "start {} not in [{}, {}]",
            got,
            want_lo,
            want_hi
        );
    }
    for (got, want_lo, want_hi) in [
        (
            cmax as f64 + 1.0,
            first(hi[0] - tol).min(PW as f64),
            first(hi[0] + tol).min(PW as f64),
        ),
        (
            rmax as f64 + 1.0,
            first(hi[1] - tol).min(PH as f64),
            first(hi[1] + tol).min(PH as f64),
        ),
    ] {
        prop_assert!(
            got >= want_lo && got <= want_hi,
            "end {} not in [{}, {}]",
            got,
            want_lo,
            want_hi
        );
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 150, ..ProptestConfig::default() })]

    #[test]
    fn pipeline_grids_cover_exactly_once(
        n in (1usize..7, 1usize..7),
        half in (0.2f64..1.5, 0.2f64..1.5),
        dist in 1.5f64..6.0,
        fovy in 30.0f64..100.0,
        jitter in proptest::collection::vec((-1.0f64..1.0, -1.0f64..1.0), 1..20),
        s in sub_bits(),
    ) {
        let half = [half.0, half.1];
        match s {
            0 => pipeline_grid::<0>(n.0, n.1, half, dist, fovy, &jitter)?,
            2 => pipeline_grid::<2>(n.0, n.1, half, dist, fovy, &jitter)?,
            4 => pipeline_grid::<4>(n.0, n.1, half, dist, fovy, &jitter)?,
            _ => pipeline_grid::<8>(n.0, n.1, half, dist, fovy, &jitter)?,
        }
    }
}
