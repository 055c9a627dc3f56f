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
//! and `9/4·max|Δ_uv P|/(n_u·n_v)`, each given a third of the tolerance. The bound holds for
//! polynomial patches under an affine map;
//! it is applied to the projected control points, so under perspective and for rational
//! patches it is an estimate (the measured error against the exact reference is in the
//! repository's `docs/patches.md`). Lengths are in sub-pixels, bounded above by
//! `max + min/2` of `|dx|, |dy|`.

use super::{MAX_LEVEL, PARAM_ONE};
use crate::math::mul_i64;

/// A parameter pair `(u, v)`, I16F16 bits.
pub(crate) type Uv = [u32; 2];

/// Projected control points in sub-pixels, `None` for points not in front of the near plane.
pub(crate) type ScreenNet = [Option<[i64; 2]>; 16];

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

/// An upper bound of the length of `d`: `max + min/2` of `|dx|, |dy|` (at most 12 % over).
fn length(d: [i64; 2]) -> i64 {
    let (x, y) = (d[0].saturating_abs(), d[1].saturating_abs());
    x.max(y).saturating_add(x.min(y) / 2 + 1)
}

/// `|a − 2b + c|` (bounded above by [`length`]); `None` if a point is not projected. Out of
/// line: [`levels`] (once per patch) takes 33 of these in loops the compiler unrolls.
#[inline(never)]
fn second_difference(a: Option<[i64; 2]>, b: Option<[i64; 2]>, c: Option<[i64; 2]>) -> Option<i64> {
    let (a, b, c) = (a?, b?, c?);
    Some(length([0, 1].map(|k| a[k] - 2 * b[k] + c[k])))
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

/// The largest of some second differences (`None` if any is unknown).
fn largest(mut values: impl Iterator<Item = Option<i64>>) -> Option<i64> {
    values.try_fold(0i64, |m, v| Some(m.max(v?)))
}

/// Levels for a patch with projected control points `s`, tolerance `tol` sub-pixels (≥ 1).
pub(crate) fn levels(s: &ScreenNet, tol: i64) -> Levels {
    let at = |k: usize| s.get(k).copied().flatten();
    let mut capped = false;
    let edges = EDGES.map(|e| {
        let m = largest(
            [(0, 1, 2), (1, 2, 3)]
                .into_iter()
                .map(|(a, b, c)| second_difference(at(e[a]), at(e[b]), at(e[c]))),
        );
        let (k, c) = level(m, 3, tol);
        capped |= c;
        k
    });
    let along_u = largest(
        (0..4)
            .flat_map(|j| (0..2).map(move |i| (i, j)))
            .map(|(i, j)| {
                second_difference(at(4 * i + j), at(4 * (i + 1) + j), at(4 * (i + 2) + j))
            }),
    );
    let along_v = largest(
        (0..4)
            .flat_map(|i| (0..2).map(move |j| (i, j)))
            .map(|(i, j)| second_difference(at(4 * i + j), at(4 * i + j + 1), at(4 * i + j + 2))),
    );
    let twist = largest(
        (0..3)
            .flat_map(|i| (0..3).map(move |j| (i, j)))
            .map(|(i, j)| {
                let (a, b, c, d) = (
                    at(4 * i + j)?,
                    at(4 * i + j + 1)?,
                    at(4 * (i + 1) + j)?,
                    at(4 * (i + 1) + j + 1)?,
                );
                Some(length([0, 1].map(|k| d[k] - b[k] - c[k] + a[k])))
            }),
    );
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
        let mut s: ScreenNet = [None; 16];
        for i in 0..4 {
            for j in 0..4 {
                s[4 * i + j] = Some([100 * i as i64, 100 * j as i64]);
            }
        }
        let l = levels(&s, 8);
        assert_eq!((l.u, l.v, l.edges, l.capped), (1, 1, [0; 4], false));
        // Bend edge v = 0: P_10 moved by 64 sub-pixels: |Δ²| = 128 (bounded by 129),
        // ¾·129/n² ≤ 8 needs n = 4.
        s[4] = Some([100, -64]);
        let l = levels(&s, 8);
        assert_eq!(l.edges, [2, 0, 0, 0]);
        // A point behind the near plane: everything at the cap.
        s[5] = None;
        assert!(levels(&s, 8).capped);
    }
}
