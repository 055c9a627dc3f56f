//! How finely a patch is cut (levels from screen-space second differences) and the triangles
//! of its tessellation, in parameter space.
//!
//! A patch with interior levels `(lu, lv)` has grid points `(i/2^lu, j/2^lv)`. Its interior
//! cells, `1 ≤ i < 2^lu − 1` and `1 ≤ j < 2^lv − 1`, are split in two triangles each; the
//! ring between the innermost grid lines and the boundary is filled, side by side, by a
//! zipper between the side's `2^e` boundary segments (`e` from that edge's own control
//! points) and the inner grid line's points. So the boundary's vertices depend on the edge
//! only, and neighbours share them.
//!
//! # Flatness
//!
//! A cubic's distance from its chords over `n` equal parameter steps is at most
//! `¾·max|Δ²P|/n²` (the second differences of its control points; Filip, Magedson and Markot
//! 1986). Edges take the smallest power of two that brings this under the tolerance. Inside,
//! bilinear interpolation of a cell errs by at most `⅛·(h_u²·|S_uu| + h_v²·|S_vv|)` and
//! cutting the cell along a diagonal adds `¼·h_u·h_v·|S_uv|`; with `|S_uu| ≤ 6·max|Δ_uu P|`
//! and `|S_uv| ≤ 9·max|Δ_uv P|` the three terms are `¾·max|Δ_uu P|/n_u²`, the same in `v`,
//! and `9/4·max|Δ_uv P|/(n_u·n_v)`, each given a third of the tolerance. For rational patches
//! the same bounds hold for the homogeneous form of [`Homogeneous`], which adds a term for
//! the weights' own second differences. The bounds hold under an affine map; they are
//! applied to the projected control points, so under perspective they are an estimate (the
//! measured error against the exact reference is in the repository's
//! `docs/patch-scanline.md`). Lengths are in sub-pixels, bounded above by `max + min/2` of
//! `|dx|, |dy|`.

use super::{MAX_LEVEL, PARAM_ONE};
use crate::math::mul_i64;

/// A parameter pair `(u, v)`, I16F16 bits.
pub(crate) type Uv = [u32; 2];

/// A patch's control points projected to the screen, with their weights.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct ScreenNet {
    /// Positions in sub-pixels, `None` for points not in front of the near plane.
    pub(crate) points: [Option<[i64; 2]>; 16],
    /// Weights, I16F16 bits (positive).
    pub(crate) weights: [i64; 16],
}

/// What [`levels`] measures second differences of for the control points `indices` of a
/// net: the points themselves if their weights are equal (a polynomial curve or patch),
/// else the homogeneous form below.
///
/// For weights `ω_i`, the curve (or patch) is `P = Y/W + r` with `Y` the polynomial of
/// control points `ω_i·(p_i − r)` and `W` that of the weights. A chord (a flat triangle) is
/// the dehomogenised linear interpolant `L_Y/L_W + r` of the same vertices, so
/// `P − chord = ((Y − L_Y) − (L_Y/L_W)·(W − L_W))/W`: with `W ≥ ω_min` and `|L_Y/L_W| ≤ D`,
/// the largest distance of a control point from `r` (the chord is inside the control hull),
/// the distance is at most `(|Y − L_Y| + D·|W − L_W|)/ω_min`, and each part follows the
/// polynomial bounds of the module docs. So the second difference that stands for `Δ²p` is
/// `|Δ²(ω·(p − r))|/ω_min + D·|Δ²ω|/ω_min`, the largest of each over the triples added.
/// `r` is the centre of the points' bounding box, which keeps `D` small.
/// Test `rational_levels_bound_the_chord_distance`.
struct Homogeneous {
    /// `ω_i·(p_i − r)` in sub-pixel × I16F16 bits, or `p_i` when the weights are equal.
    points: [[i64; 2]; 16],
    /// The weights, I16F16 bits (0 when equal: no weight term).
    weights: [i64; 16],
    /// `ω_min` (1 when the weights are equal).
    divisor: i64,
    /// `D`, sub-pixels (rounded up).
    reach: i64,
}

impl Homogeneous {
    /// The control points `indices` of `s`; `None` if one is not projected.
    #[inline(never)]
    fn new(s: &ScreenNet, indices: &[usize]) -> Option<Self> {
        let mut h = Homogeneous {
            points: [[0; 2]; 16],
            weights: [0; 16],
            divisor: 1,
            reach: 0,
        };
        let (mut lo, mut hi) = ([i64::MAX; 2], [i64::MIN; 2]);
        let (mut w_min, mut w_max) = (i64::MAX, i64::MIN);
        for &k in indices {
            let p = s.points.get(k).copied().flatten()?;
            let w = s.weights.get(k).copied().unwrap_or(0);
            for c in 0..2 {
                lo[c] = lo[c].min(p[c]);
                hi[c] = hi[c].max(p[c]);
            }
            (w_min, w_max) = (w_min.min(w), w_max.max(w));
            if let Some(out) = h.points.get_mut(k) {
                *out = p;
            }
        }
        if w_min >= w_max || w_min <= 0 {
            return Some(h);
        }
        let ([lo_u, lo_v], [hi_u, hi_v]) = (lo, hi);
        let r = [lo_u + (hi_u - lo_u) / 2, lo_v + (hi_v - lo_v) / 2];
        for &k in indices {
            let (Some(p), Some(&w)) = (h.points.get_mut(k), s.weights.get(k)) else {
                continue;
            };
            let d = [p[0] - r[0], p[1] - r[1]];
            h.reach = h.reach.max(length(d));
            *p = d.map(|d| d.saturating_mul(w));
            if let Some(out) = h.weights.get_mut(k) {
                *out = w;
            }
        }
        h.divisor = w_min;
        Some(h)
    }

    /// The bound standing for `|Δ²p|` over the triples `(a, b, c)` (`b` doubled) or the
    /// twists `a − b − c + d` ([`NONE`] for no `d`): see [`Homogeneous`].
    #[inline(never)]
    fn largest(&self, quads: &[[u8; 4]]) -> i64 {
        let (mut points, mut weights) = (0i64, 0i64);
        let at = |k: u8| self.points.get(k as usize).copied().unwrap_or([0; 2]);
        let w = |k: u8| self.weights.get(k as usize).copied().unwrap_or(0);
        for &[a, b, c, d] in quads {
            // `a − 2b + c` is the twist with `c` for `b` and `d` for `c`.
            let (c, d) = if d == NONE { (b, c) } else { (c, d) };
            let (pa, pb, pc, pd) = (at(a), at(b), at(c), at(d));
            let twist = |[a, b, c, d]: [i64; 4]| d - b - c + a;
            let delta = [
                twist([pa[0], pb[0], pc[0], pd[0]]),
                twist([pa[1], pb[1], pc[1], pd[1]]),
            ];
            points = points.max(length(delta));
            weights = weights.max((w(d) - w(b) - w(c) + w(a)).abs());
        }
        // `divisor` is positive; `checked_div` keeps the division's panic off the render path.
        let up = |n: i64| {
            n.saturating_add(self.divisor.saturating_sub(1))
                .checked_div(self.divisor)
                .unwrap_or(i64::MAX)
        };
        up(points).saturating_add(up(weights.saturating_mul(self.reach)))
    }
}

/// Subdivision levels (log2 of segment counts) of one patch.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Levels {
    /// Interior grid along `u` and `v` (at least 1: two segments).
    pub(crate) u: u8,
    pub(crate) v: u8,
    /// Boundary edges: `v = 0`, `u = 1`, `v = 1`, `u = 0`.
    pub(crate) edges: [u8; 4],
    /// Whether some level stopped at [`MAX_LEVEL`] short of the tolerance (or a control point
    /// was not in front of the near plane, so the screen-space estimate did not apply).
    pub(crate) capped: bool,
}

/// Control point indices of the edges, in the order of [`Levels::edges`].
const EDGES: [[usize; 4]; 4] = [
    [0, 4, 8, 12],
    [12, 13, 14, 15],
    [3, 7, 11, 15],
    [0, 1, 2, 3],
];

/// No fourth point: a second difference `a − 2b + c`, not a twist.
const NONE: u8 = u8::MAX;

/// Every control point.
const ALL: [usize; 16] = [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15];

/// The second differences along `u` (`P_ij`, `P_i+1,j`, `P_i+2,j`; `u` along `i`, index
/// `4·i + j`).
const ALONG_U: [[u8; 4]; 8] = second_differences(4, 1);

/// The second differences along `v`.
const ALONG_V: [[u8; 4]; 8] = second_differences(1, 4);

/// The twists `P_ij − P_i,j+1 − P_i+1,j + P_i+1,j+1`.
const TWISTS: [[u8; 4]; 9] = {
    let mut out = [[0; 4]; 9];
    let mut k = 0;
    while k < 9 {
        let p = (4 * (k / 3) + k % 3) as u8;
        out[k] = [p, p + 1, p + 4, p + 5];
        k += 1;
    }
    out
};

/// The 8 triples of points `step` apart in the direction of `step`, starting a step of
/// `across` apart across it.
const fn second_differences(step: u8, across: u8) -> [[u8; 4]; 8] {
    let mut out = [[0; 4]; 8];
    let mut k = 0;
    while k < 8 {
        let p = (k / 2) as u8 * across + (k % 2) as u8 * step;
        out[k] = [p, p + step, p + 2 * step, NONE];
        k += 1;
    }
    out
}

/// An upper bound of the length of `d`: `max + min/2` of `|dx|, |dy|` (at most 12 % over).
fn length(d: [i64; 2]) -> i64 {
    let (x, y) = (d[0].saturating_abs(), d[1].saturating_abs());
    x.max(y).saturating_add(x.min(y) / 2 + 1)
}

/// The smallest level `k` with `scale·m ≤ 4·tol·4^k`, and whether it had to stop at
/// [`MAX_LEVEL`] (or `m` is unknown).
fn level(m: Option<i64>, scale: i64, tol: i64) -> (u8, bool) {
    let Some(m) = m else {
        return (MAX_LEVEL as u8, true);
    };
    let need = m.saturating_mul(scale);
    for k in 0..=MAX_LEVEL {
        if need <= (4 * tol) << (2 * k) {
            return (k as u8, false);
        }
    }
    (MAX_LEVEL as u8, true)
}

/// Levels for a patch with projected control points `s`, tolerance `tol` sub-pixels (≥ 1).
pub(crate) fn levels(s: &ScreenNet, tol: i64) -> Levels {
    let mut capped = false;
    let edges = EDGES.map(|e| {
        let m = Homogeneous::new(s, &e).map(|h| {
            let [a, b, c, d] = e.map(|k| k as u8);
            h.largest(&[[a, b, c, NONE], [b, c, d, NONE]])
        });
        let (k, c) = level(m, 3, tol);
        capped |= c;
        k
    });
    let whole = Homogeneous::new(s, &ALL);
    let along_u = whole.as_ref().map(|h| h.largest(&ALONG_U));
    let along_v = whole.as_ref().map(|h| h.largest(&ALONG_V));
    let twist = whole.as_ref().map(|h| h.largest(&TWISTS));
    // Each of the three interior terms gets a third of the tolerance: ¾·m/n² ≤ tol/3.
    let (mut u, cu) = level(along_u, 9, tol);
    let (mut v, cv) = level(along_v, 9, tol);
    capped |= cu || cv;
    (u, v) = (u.max(1), v.max(1));
    match twist {
        // 9/4·m/(n_u·n_v) ≤ tol/3.
        Some(m) => {
            while m.saturating_mul(27) > (4 * tol) << (u + v) {
                if u.min(v) as u32 >= MAX_LEVEL {
                    capped = true;
                    break;
                }
                if u <= v {
                    u += 1;
                } else {
                    v += 1;
                }
            }
        }
        None => {
            (u, v) = (MAX_LEVEL as u8, MAX_LEVEL as u8);
            capped = true;
        }
    }
    Levels {
        u,
        v,
        edges,
        capped,
    }
}

/// Grid coordinate `index / 2^level` as a parameter.
#[inline(always)]
pub(crate) fn grid(index: u32, level: u8) -> u32 {
    index << (16 - level as u32)
}

/// Twice the signed area of `a b c` in the `(u, v)` plane (positive: counter-clockwise).
pub(crate) fn area2(a: Uv, b: Uv, c: Uv) -> i64 {
    let d = |a: Uv, b: Uv, k: usize| b[k] as i64 - a[k] as i64;
    mul_i64(d(a, b, 0), d(a, c, 1)) - mul_i64(d(a, c, 0), d(a, b, 1))
}

/// `t` with its vertices in counter-clockwise order in the `(u, v)` plane (`u` right, `v`
/// up), so screen winding follows the surface's orientation; `None` for zero area.
fn oriented(t: [Uv; 3]) -> Option<[Uv; 3]> {
    match area2(t[0], t[1], t[2]) {
        0 => None,
        a if a > 0 => Some(t),
        _ => Some([t[0], t[2], t[1]]),
    }
}

/// The parameter ranges `(u, v)` of the boundary strip on `side` (the order of
/// [`Levels::edges`]): between that edge and the first inner grid line, where [`border`]
/// puts its triangles.
pub(crate) fn strip(l: &Levels, side: usize) -> ([u32; 2], [u32; 2]) {
    let (du, dv) = (grid(1, l.u), grid(1, l.v));
    let all = [0, PARAM_ONE];
    match side {
        0 => (all, [0, dv]),
        1 => ([PARAM_ONE - du, PARAM_ONE], all),
        2 => (all, [PARAM_ONE - dv, PARAM_ONE]),
        _ => ([0, du], all),
    }
}

/// Calls `f` with each triangle of the boundary strip on `side` (the order of
/// [`Levels::edges`]).
pub(crate) fn border(l: &Levels, side: usize, mut f: impl FnMut([Uv; 3])) {
    let e = l.edges.get(side).copied().unwrap_or(0);
    let outer_count = 1u32 << e;
    // The side runs along u (sides 0, 2) or v (1, 3); its inner grid line is one step in.
    let along_u = matches!(side, 0 | 2);
    let (run_level, depth_level) = if along_u { (l.u, l.v) } else { (l.v, l.u) };
    let inner_last = (1u32 << run_level) - 1;
    let step_in = grid(1, depth_level);
    let (edge_at, inner_at) = match side {
        0 => (0, step_in),
        1 => (PARAM_ONE, PARAM_ONE - step_in),
        2 => (PARAM_ONE, PARAM_ONE - step_in),
        _ => (0, step_in),
    };
    let point = |run: u32, fixed: u32| -> Uv {
        if along_u {
            [run, fixed]
        } else {
            [fixed, run]
        }
    };
    let outer = |a: u32| point(grid(a, e), edge_at);
    let inner = |b: u32| point(grid(b, run_level), inner_at);
    // Outer points a = 0 ..= 2^e on the edge; inner points b = 1 ..= 2^run − 1 on the line.
    let (mut a, mut b) = (0u32, 1u32);
    loop {
        let more_outer = a < outer_count;
        let more_inner = b < inner_last;
        let t = if more_outer && (!more_inner || grid(a + 1, e) <= grid(b + 1, run_level)) {
            a += 1;
            [outer(a - 1), inner(b), outer(a)]
        } else if more_inner {
            b += 1;
            [outer(a), inner(b - 1), inner(b)]
        } else {
            break;
        };
        if let Some(t) = oriented(t) {
            f(t);
        }
    }
}

/// The two triangles of a cell with corners `(i, j), (i+1, j), (i+1, j+1), (i, j+1)`, as
/// indices into that list: counter-clockwise in `(u, v)`.
pub(crate) const CELL_TRIANGLES: [[usize; 3]; 2] = [[0, 1, 2], [0, 2, 3]];

/// Calls `f` with the two triangles of each interior cell `(i, j)`, `i` in `is`, `j` in `js`
/// (cell `(i, j)` spans grid points `i ..= i + 1` and `j ..= j + 1`). The renderer walks the
/// cells itself, sharing grid points; this is their definition in parameter space.
#[cfg(test)]
fn cells(l: &Levels, is: [u8; 2], js: [u8; 2], mut f: impl FnMut([Uv; 3])) {
    for i in is[0]..is[1] {
        for j in js[0]..js[1] {
            let p = |di: u8, dj: u8| [grid((i + di) as u32, l.u), grid((j + dj) as u32, l.v)];
            let corners = [p(0, 0), p(1, 0), p(1, 1), p(0, 1)];
            for t in CELL_TRIANGLES {
                f(t.map(|k| corners[k]));
            }
        }
    }
}

/// The interior cells of a patch with levels `l`: `(is, js)`, empty ranges when a side has
/// only two segments (its inner grid line is the only one).
pub(crate) fn interior(l: &Levels) -> ([u8; 2], [u8; 2]) {
    let last = |level: u8| ((1u32 << level) - 1) as u8;
    ([1, last(l.u).max(1)], [1, last(l.v).max(1)])
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec::Vec;

    fn area(t: [Uv; 3]) -> f64 {
        let p = t.map(|[u, v]| (u as f64 / 65536.0, v as f64 / 65536.0));
        ((p[1].0 - p[0].0) * (p[2].1 - p[0].1) - (p[2].0 - p[0].0) * (p[1].1 - p[0].1)) / 2.0
    }

    /// Every combination of levels tiles the unit square: positive areas summing to 1.
    #[test]
    fn the_tessellation_tiles_the_parameter_square() {
        for u in 1..=4u8 {
            for v in 1..=4u8 {
                for edges in [[0, 0, 0, 0], [3, 1, 0, 5], [6, 6, 6, 6], [2, 4, 1, 3]] {
                    let l = Levels {
                        u,
                        v,
                        edges,
                        capped: false,
                    };
                    let mut tris = Vec::new();
                    for side in 0..4 {
                        // Each side's triangles lie in its strip (the renderer files them
                        // under the strip's control hull).
                        let (su, sv) = strip(&l, side);
                        let inside = |p: Uv| {
                            (su[0]..=su[1]).contains(&p[0]) && (sv[0]..=sv[1]).contains(&p[1])
                        };
                        border(&l, side, |t| {
                            assert!(t.iter().all(|&p| inside(p)), "{l:?} side {side}: {t:?}");
                            tris.push(t)
                        });
                    }
                    let (is, js) = interior(&l);
                    cells(&l, is, js, |t| tris.push(t));
                    let total: f64 = tris.iter().map(|&t| area(t)).sum();
                    assert!(tris.iter().all(|&t| area(t) > 0.0), "{l:?}");
                    assert!((total - 1.0).abs() < 1e-9, "{l:?}: {total}");
                    // Boundary vertices are exactly the edges' own points.
                    for t in &tris {
                        for &[pu, pv] in t {
                            let on = |side: usize| match side {
                                0 => pv == 0,
                                1 => pu == PARAM_ONE,
                                2 => pv == PARAM_ONE,
                                _ => pu == 0,
                            };
                            for (side, &level) in edges.iter().enumerate() {
                                if on(side) {
                                    let run = if matches!(side, 0 | 2) { pu } else { pv };
                                    let step = grid(1, level);
                                    assert_eq!(run % step, 0, "{l:?} side {side}");
                                }
                            }
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn levels_follow_the_flatness_bound() {
        // A straight, evenly spaced net: one segment per edge, the minimum inside.
        let mut s = ScreenNet {
            points: [None; 16],
            weights: [1 << 16; 16],
        };
        for i in 0..4 {
            for j in 0..4 {
                s.points[4 * i + j] = Some([100 * i as i64, 100 * j as i64]);
            }
        }
        let l = levels(&s, 8);
        assert_eq!((l.u, l.v, l.edges, l.capped), (1, 1, [0; 4], false));
        // Bend edge v = 0: P_10 moved by 64 sub-pixels: |Δ²| = 128 (bounded by 129),
        // ¾·129/n² ≤ 8 needs n = 4.
        s.points[4] = Some([100, -64]);
        let l = levels(&s, 8);
        assert_eq!(l.edges, [2, 0, 0, 0]);
        // A point behind the near plane: everything at the cap.
        s.points[5] = None;
        assert!(levels(&s, 8).capped);
    }

    /// Cubic Bernstein weights at `t`.
    fn bernstein(t: f64) -> [f64; 4] {
        let m = 1.0 - t;
        [m * m * m, 3.0 * t * m * m, 3.0 * t * t * m, t * t * t]
    }

    /// The homogeneous point `(ω·x, ω·y, ω)` of the screen net `s` at `(u, v)`.
    fn hom(s: &ScreenNet, u: f64, v: f64) -> [f64; 3] {
        let (bu, bv) = (bernstein(u), bernstein(v));
        let mut h = [0.0; 3];
        for (i, bu) in bu.iter().enumerate() {
            for (j, bv) in bv.iter().enumerate() {
                let (p, w) = (s.points[4 * i + j].unwrap(), s.weights[4 * i + j] as f64);
                let b = bu * bv * w;
                h[0] += b * p[0] as f64;
                h[1] += b * p[1] as f64;
                h[2] += b;
            }
        }
        h
    }

    /// The largest distance (sub-pixels) between the surface of `s` and its chords at levels
    /// `l`: along each edge between the curve and its segments, and over every grid cell's
    /// two triangles between the surface and the dehomogenised linear interpolant of the
    /// corners (the flat triangle, as the renderer draws it), sampled.
    fn chord_distance(s: &ScreenNet, l: &Levels) -> f64 {
        let point = |h: [f64; 3]| [h[0] / h[2], h[1] / h[2]];
        let dist = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
        let mix = |hs: &[([f64; 3], f64)]| {
            let mut h = [0.0; 3];
            for (p, b) in hs {
                for k in 0..3 {
                    h[k] += b * p[k];
                }
            }
            h
        };
        let mut worst = 0.0f64;
        // Edges in the order of `EDGES`: v = 0, u = 1, v = 1, u = 0.
        let on_edge = |side: usize, t: f64| match side {
            0 => hom(s, t, 0.0),
            1 => hom(s, 1.0, t),
            2 => hom(s, t, 1.0),
            _ => hom(s, 0.0, t),
        };
        for (side, &k) in l.edges.iter().enumerate() {
            let n = 1usize << k;
            for seg in 0..n {
                let (t0, t1) = (seg as f64 / n as f64, (seg + 1) as f64 / n as f64);
                let (h0, h1) = (on_edge(side, t0), on_edge(side, t1));
                for q in 1..16 {
                    let f = q as f64 / 16.0;
                    let chord = point(mix(&[(h0, 1.0 - f), (h1, f)]));
                    let curve = point(on_edge(side, t0 + f * (t1 - t0)));
                    worst = worst.max(dist(chord, curve));
                }
            }
        }
        let (nu, nv) = (1usize << l.u, 1usize << l.v);
        for i in 0..nu {
            for j in 0..nv {
                let uv = |di: usize, dj: usize| {
                    ((i + di) as f64 / nu as f64, (j + dj) as f64 / nv as f64)
                };
                let corners = [uv(0, 0), uv(1, 0), uv(1, 1), uv(0, 1)];
                for t in CELL_TRIANGLES {
                    let c = t.map(|k| corners[k]);
                    let h = c.map(|(u, v)| hom(s, u, v));
                    for a in 0..=6 {
                        for b in 0..=6 - a {
                            let (ba, bb) = (a as f64 / 6.0, b as f64 / 6.0);
                            let bc = 1.0 - ba - bb;
                            let u = ba * c[0].0 + bb * c[1].0 + bc * c[2].0;
                            let v = ba * c[0].1 + bb * c[1].1 + bc * c[2].1;
                            let flat = point(mix(&[(h[0], ba), (h[1], bb), (h[2], bc)]));
                            worst = worst.max(dist(flat, point(hom(s, u, v))));
                        }
                    }
                }
            }
        }
        worst
    }

    /// Random rational nets (weights 1/4 to 4 times each other's, 30 to 60 pixels across):
    /// wherever the levels are not capped, every chord is within the tolerance of the
    /// surface. The same points taken as polynomial (the weights ignored, as the estimate was
    /// before) give levels whose chords are farther in some of them.
    #[test]
    fn rational_levels_bound_the_chord_distance() {
        let mut rng = crate::test_rng::XorShift64::new(0x7a7e_11a7_5eed_0001);
        let mut unit = || (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
        let (mut checked, mut too_coarse) = (0, 0);
        for case in 0..300 {
            let tol = 4 + (unit() * 28.0) as i64;
            let size = 480.0 + unit() * 480.0;
            let mut s = ScreenNet {
                points: [None; 16],
                weights: [0; 16],
            };
            for i in 0..4 {
                for j in 0..4 {
                    let jitter = |r: f64| (r - 0.5) * size / 3.0;
                    let x = i as f64 * size / 3.0 + jitter(unit());
                    let y = j as f64 * size / 3.0 + jitter(unit());
                    s.points[4 * i + j] = Some([x as i64, y as i64]);
                    s.weights[4 * i + j] = (65536.0 * (unit() * 2.0 - 1.0).exp2()) as i64;
                }
            }
            let l = levels(&s, tol);
            if l.capped {
                continue;
            }
            checked += 1;
            let d = chord_distance(&s, &l);
            assert!(d <= tol as f64, "case {case}: {d} > {tol} at {l:?}");
            let polynomial = ScreenNet {
                weights: [1 << 16; 16],
                ..s
            };
            too_coarse += (chord_distance(&s, &levels(&polynomial, tol)) > tol as f64) as u32;
        }
        assert!(checked >= 150, "{checked}");
        assert!(too_coarse > 0);
        std::println!("{checked} nets checked; the weights ignored, {too_coarse} too coarse");
    }
}
