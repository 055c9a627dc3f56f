//! Ray/patch intersection by Bezier clipping (Nishita, Sederberg, Kakimoto 1990).
//!
//! The ray `O + t·D` is the meet of two planes through it, with unit normals `n₁, n₂ ⊥ D`. A
//! surface point lies on the ray exactly when its signed distances to both planes vanish.
//! For a (rational) patch those distances are `d_k(u, v) = Σ B_i(u) B_j(v) e^k_ij / W(u, v)`
//! with `e^k_ij = w_ij · n_k·(P_ij − O)`, and `W > 0` (positive weights), so the roots are the
//! common zeros of two bicubic polynomials in Bernstein form with control values `e^k_ij`.
//!
//! A polynomial's zeros in `u` lie where the convex hull of its control points
//! `(i/3, e_ij)` meets the axis: every clip keeps only that part of the `u` interval (and then
//! of `v`, with points `(j/3, e_ij)`). Both distance functions clip, and so does a third: the
//! distance to the line, in the `(d₁, d₂)` plane, along which the patch's `v` edges run; that
//! function hardly varies with `v`, so its zero set is nearly a line `u = const` and its `u`
//! clip converges fast (and likewise for `v`). When a round of clips keeps more than
//! `1 − MIN_CLIP` of both intervals, the region is split in half across its wider side and both
//! halves are searched. A region narrower than [`TOLERANCE_UV`] in `u` and in `v` is a root;
//! its centre is the hit. Every root is kept, so a trimmed-away nearer hit does not hide a
//! farther one that the trim keeps.

use super::model::{split_grid_u, split_grid_v, Patch};
use crate::reference::{cross, dot, normalize, V3};

/// Width in `u` and in `v` below which a clipped region is a root.
pub const TOLERANCE_UV: f64 = 1e-12;
/// A round of clips that removes less than this fraction of both intervals is followed by a
/// split.
pub const MIN_CLIP: f64 = 0.2;
/// A region settled in one parameter, stalled in the other and everywhere within this
/// fraction of the patch's largest distance control value of the ray is a collapsed edge on
/// the ray: a root.
pub const COLLAPSED: f64 = 1e-10;
/// Clip rounds allowed per ray and patch before the search stops (then reported as capped).
pub const MAX_ROUNDS: u32 = 4000;

/// Distance control values `(e¹_ij, e²_ij)` over one region of the domain.
type Grid = [[f64; 2]; 16];

/// Work done for one ray against one patch (or summed over patches).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ClipStats {
    /// Clip rounds (one round clips `u`, then `v`).
    pub rounds: u32,
    /// Regions split in half because a round removed too little.
    pub splits: u32,
    /// Searches stopped by [`MAX_ROUNDS`] before every region was settled.
    pub capped: u32,
}

impl ClipStats {
    /// Adds `other`'s counts.
    pub fn add(&mut self, other: ClipStats) {
        self.rounds += other.rounds;
        self.splits += other.splits;
        self.capped += other.capped;
    }
}

/// A point where the ray meets a patch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Root {
    /// Patch parameter `u`.
    pub u: f64,
    /// Patch parameter `v`.
    pub v: f64,
    /// Ray parameter: the hit is `O + t·D`.
    pub t: f64,
}

/// Two unit vectors perpendicular to `d` and to each other (`None` for a zero direction).
pub fn ray_planes(d: V3) -> Option<(V3, V3)> {
    let d = normalize(d)?;
    let n1 = if d[0].abs() > d[1].abs() && d[0].abs() > d[2].abs() {
        normalize([d[1], -d[0], 0.0])?
    } else {
        normalize([0.0, d[2], -d[1]])?
    };
    Some((n1, cross(d, n1)))
}

/// The zero range in `[0, 1]` of a polynomial with Bernstein control values `e` at abscissae
/// `k/3`, from the convex hull of its control points: `None` when all lie strictly on one side.
/// `columns[k]` holds the smallest and largest control value at abscissa `k/3`.
fn hull_range(columns: [[f64; 2]; 4]) -> Option<(f64, f64)> {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    let mut take = |x: f64| {
        lo = lo.min(x);
        hi = hi.max(x);
    };
    for (a, ca) in columns.iter().enumerate() {
        let xa = a as f64 / 3.0;
        if ca[0] <= 0.0 && ca[1] >= 0.0 {
            take(xa);
        }
        for (b, cb) in columns.iter().enumerate().skip(a + 1) {
            let xb = b as f64 / 3.0;
            for &ya in ca {
                for &yb in cb {
                    if (ya < 0.0 && yb > 0.0) || (ya > 0.0 && yb < 0.0) {
                        take(xa + (xb - xa) * ya / (ya - yb));
                    }
                }
            }
        }
    }
    (lo <= hi).then(|| (lo.max(0.0), hi.min(1.0)))
}

/// The range in `u` (`along_u`) or `v` where the function with control values `f(e)` can
/// vanish. Every control value is taken as uncertain by `zero` (its column's range widened by
/// that much): subdividing rounds, and a region that has converged onto the ray, whose values
/// are all nearly 0, must not be rejected because they came out a few ulps positive.
fn clip_range(
    grid: &Grid,
    along_u: bool,
    zero: f64,
    f: impl Fn([f64; 2]) -> f64,
) -> Option<(f64, f64)> {
    let mut columns = [[f64::INFINITY, f64::NEG_INFINITY]; 4];
    for i in 0..4 {
        for j in 0..4 {
            let y = f(grid[4 * i + j]);
            let c = &mut columns[if along_u { i } else { j }];
            c[0] = c[0].min(y - zero);
            c[1] = c[1].max(y + zero);
        }
    }
    hull_range(columns)
}

/// The part `[a, b]` (in the region's own parameter) of a grid, along `u` or `v`.
fn restrict(grid: &Grid, along_u: bool, a: f64, b: f64) -> Grid {
    let split = |g: &Grid, t: f64| {
        if along_u {
            split_grid_u(g, t)
        } else {
            split_grid_v(g, t)
        }
    };
    let upper = if b < 1.0 { split(grid, b).0 } else { *grid };
    if a > 0.0 && b > 0.0 {
        split(&upper, a / b).1
    } else {
        upper
    }
}

/// One region of the search: its distance grid and its `u` and `v` intervals.
#[derive(Clone, Copy)]
struct Region {
    grid: Grid,
    u: (f64, f64),
    v: (f64, f64),
    /// The uncertainty of a distance control value (see [`ZERO`]).
    zero: f64,
}

/// The uncertainty of a distance control value, as a fraction of the patch's largest one (far
/// above the rounding of subdivision); a region whose values are all within it of 0 lies on
/// the ray and is a root however wide it is in `u` or `v` (a collapsed edge crossed by the
/// ray).
pub const ZERO: f64 = 1e-13;

impl Region {
    /// Clips along `u` or `v`; `false` when no root can lie in the region.
    fn clip(&mut self, along_u: bool) -> bool {
        // The direction the region's edges across this parameter run, in the (d₁, d₂) plane.
        let g = &self.grid;
        let (edges, ends) = if along_u {
            ([g[0], g[12]], [g[3], g[15]])
        } else {
            ([g[0], g[3]], [g[12], g[15]])
        };
        let mut line = [0.0, 0.0];
        for (a, b) in edges.iter().zip(ends) {
            line[0] += b[0] - a[0];
            line[1] += b[1] - a[1];
        }
        let mut range = (0.0_f64, 1.0_f64);
        let mut narrow = |r: Option<(f64, f64)>| match r {
            Some((a, b)) => {
                range = (range.0.max(a), range.1.min(b));
                range.0 <= range.1
            }
            None => false,
        };
        let zero = self.zero;
        let line_zero = zero * (line[0].abs() + line[1].abs());
        let ok = narrow(clip_range(g, along_u, zero, |e| e[0]))
            && narrow(clip_range(g, along_u, zero, |e| e[1]))
            && (line == [0.0, 0.0]
                || narrow(clip_range(g, along_u, line_zero, |e| {
                    line[0] * e[1] - line[1] * e[0]
                })));
        if !ok {
            return false;
        }
        let (a, b) = range;
        self.grid = restrict(&self.grid, along_u, a, b);
        let span = if along_u { &mut self.u } else { &mut self.v };
        let w = span.1 - span.0;
        *span = (span.0 + a * w, span.0 + b * w);
        true
    }

    fn split(&self) -> (Region, Region) {
        let (du, dv) = (self.u.1 - self.u.0, self.v.1 - self.v.0);
        let (mut lo, mut hi) = (*self, *self);
        if du >= dv {
            let (a, b) = split_grid_u(&self.grid, 0.5);
            let mid = self.u.0 + du / 2.0;
            (lo.grid, lo.u.1, hi.grid, hi.u.0) = (a, mid, b, mid);
        } else {
            let (a, b) = split_grid_v(&self.grid, 0.5);
            let mid = self.v.0 + dv / 2.0;
            (lo.grid, lo.v.1, hi.grid, hi.v.0) = (a, mid, b, mid);
        }
        (lo, hi)
    }
}

/// Every root of the ray `origin + t·dir` with `patch`, as found by Bezier clipping (each
/// within [`TOLERANCE_UV`] of a common zero of the two plane distances). Roots may repeat
/// when one lies on a split line. Trims and the `t` range are not applied here.
pub fn roots(patch: &Patch, origin: V3, dir: V3, stats: &mut ClipStats) -> Vec<Root> {
    let Some((n1, n2)) = ray_planes(dir) else {
        return Vec::new();
    };
    let (k1, k2) = (dot(n1, origin), dot(n2, origin));
    let mut grid = [[0.0; 2]; 16];
    for (e, h) in grid.iter_mut().zip(patch.homogeneous()) {
        let x = [h[0], h[1], h[2]];
        *e = [dot(n1, x) - h[3] * k1, dot(n2, x) - h[3] * k2];
    }
    let largest = grid.iter().flatten().fold(0.0_f64, |m, e| m.max(e.abs()));
    let zero = ZERO * largest;
    // Most rays that enter a patch's box pass beside the patch: the whole control net on one
    // side of a plane through the ray. Settled here, that costs one round.
    let one_side = |k: usize| grid.iter().all(|e| e[k] > zero) || grid.iter().all(|e| e[k] < -zero);
    if one_side(0) || one_side(1) {
        stats.rounds += 1;
        return Vec::new();
    }
    let mut found = Vec::new();
    let mut stack = vec![Region {
        grid,
        u: (0.0, 1.0),
        v: (0.0, 1.0),
        zero,
    }];
    let dd = dot(dir, dir);
    'regions: while let Some(mut r) = stack.pop() {
        loop {
            if stats.rounds >= MAX_ROUNDS {
                stats.capped += 1;
                break 'regions;
            }
            stats.rounds += 1;
            let before = (r.u.1 - r.u.0, r.v.1 - r.v.0);
            if (before.0 > TOLERANCE_UV && !r.clip(true))
                || (before.1 > TOLERANCE_UV && !r.clip(false))
            {
                continue 'regions;
            }
            let after = (r.u.1 - r.u.0, r.v.1 - r.v.0);
            let within = |limit: f64| r.grid.iter().flatten().all(|e| e.abs() <= limit);
            // Split when every direction still open kept more than 1 − MIN_CLIP.
            let stalled = |a: f64, b: f64| a <= TOLERANCE_UV || a > (1.0 - MIN_CLIP) * b;
            let stalled = stalled(after.0, before.0) && stalled(after.1, before.1);
            // Settled in one direction and stalled in the other, on the ray along its whole
            // length: a collapsed edge the ray goes through, every point of which is the hit.
            let collapsed = stalled
                && (after.0 <= TOLERANCE_UV || after.1 <= TOLERANCE_UV)
                && within(COLLAPSED * largest);
            if (after.0 <= TOLERANCE_UV && after.1 <= TOLERANCE_UV) || within(r.zero) || collapsed {
                let (u, v) = ((r.u.0 + r.u.1) / 2.0, (r.v.0 + r.v.1) / 2.0);
                let p = patch.point(u, v);
                let t = dot([p[0] - origin[0], p[1] - origin[1], p[2] - origin[2]], dir) / dd;
                found.push(Root { u, v, t });
                continue 'regions;
            }
            if stalled {
                stats.splits += 1;
                let (lo, hi) = r.split();
                stack.push(hi);
                stack.push(lo);
                continue 'regions;
            }
        }
    }
    found
}

/// The nearest root with `t` in `[t_min, t_max]` whose `(u, v)` the patch's trims keep.
pub fn nearest(
    patch: &Patch,
    origin: V3,
    dir: V3,
    (t_min, t_max): (f64, f64),
    stats: &mut ClipStats,
) -> Option<Root> {
    roots(patch, origin, dir, stats)
        .into_iter()
        .filter(|r| r.t >= t_min && r.t <= t_max && patch.is_kept(r.u, r.v))
        .min_by(|a, b| a.t.total_cmp(&b.t))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hull_range_brackets_the_line() {
        // A line from −1 to 2 over [0, 1]: root at 1/3.
        let col = |y: f64| [y, y];
        let r = hull_range([col(-1.0), col(0.0), col(1.0), col(2.0)]).unwrap();
        assert!((r.0 - 1.0 / 3.0).abs() < 1e-15 && (r.1 - 1.0 / 3.0).abs() < 1e-15);
        assert_eq!(hull_range([col(1.0), col(0.5), col(1.0), col(2.0)]), None);
    }

    #[test]
    fn flat_patch_hit_is_exact() {
        let mut points = [[0.0; 3]; 16];
        for i in 0..4 {
            for j in 0..4 {
                points[4 * i + j] = [i as f64 / 3.0, j as f64 / 3.0, 0.0];
            }
        }
        let p = Patch::polynomial(points);
        let mut stats = ClipStats::default();
        let r = nearest(
            &p,
            [0.3, 0.7, 2.0],
            [0.01, -0.02, -1.0],
            (0.0, 10.0),
            &mut stats,
        )
        .unwrap();
        assert!(
            (r.u - 0.32).abs() < 1e-12 && (r.v - 0.66).abs() < 1e-12,
            "{r:?}"
        );
        assert!((r.t - 2.0).abs() < 1e-12);
        assert_eq!(stats.capped, 0);
    }
}
