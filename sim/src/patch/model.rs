//! The f64 patch model: bicubic Bezier patches, polynomial or rational, optionally trimmed.
//!
//! Control points are row-major: `points[4 * i + j]` is `P_ij`, where `i` follows `u` and `j`
//! follows `v`, so `P(u, v) = Σ_ij B_i(u) B_j(v) w_ij P_ij / Σ_ij B_i(u) B_j(v) w_ij` with the
//! cubic Bernstein polynomials `B_k`. A polynomial patch has every weight 1. The front side of
//! a patch is the side `∂P/∂u × ∂P/∂v` points to.
//!
//! Rational patches are evaluated and subdivided in homogeneous coordinates `(w·P, w)`, where de
//! Casteljau's construction is exact; positive weights keep the denominator positive over the
//! whole domain, so a patch is finite everywhere.

use crate::reference::{cross, dot, normalize, V3};

/// A 4-vector in homogeneous coordinates `(w·x, w·y, w·z, w)`.
pub type H4 = [f64; 4];

/// A closed polyline in the patch's `(u, v)` domain (the last point joins the first).
#[derive(Clone, Debug, PartialEq)]
pub struct TrimLoop {
    /// Vertices in `(u, v)`, at least three, no two edges crossing.
    pub points: Vec<[f64; 2]>,
}

impl TrimLoop {
    /// Whether `(u, v)` lies inside the loop (crossing number; points exactly on an edge
    /// count as inside when the edge is a left or bottom edge, as the half-open test gives).
    pub fn contains(&self, u: f64, v: f64) -> bool {
        let mut inside = false;
        let n = self.points.len();
        for k in 0..n {
            let [ua, va] = self.points[k];
            let [ub, vb] = self.points[(k + 1) % n];
            if (va > v) != (vb > v) {
                let cross_u = ua + (v - va) / (vb - va) * (ub - ua);
                if u < cross_u {
                    inside = !inside;
                }
            }
        }
        inside
    }

    /// The edges as `(start, end)` pairs, the closing edge last.
    pub fn edges(&self) -> impl Iterator<Item = ([f64; 2], [f64; 2])> + '_ {
        let n = self.points.len();
        (0..n).map(move |k| (self.points[k], self.points[(k + 1) % n]))
    }
}

/// One bicubic patch.
#[derive(Clone, Debug, PartialEq)]
pub struct Patch {
    /// Control points, `points[4 * i + j] = P_ij` (`i` along `u`, `j` along `v`).
    pub points: [[f64; 3]; 16],
    /// Positive weights in the same order; all 1 for a polynomial patch.
    pub weights: [f64; 16],
    /// Trim loops in `(u, v)`. A point of the domain is part of the surface when it lies inside
    /// an even number of loops (even-odd rule): one loop cuts a hole, a loop inside it an island.
    pub trims: Vec<TrimLoop>,
}

/// A model: patches in file order (patch `k` has id `k`).
#[derive(Clone, Debug, PartialEq)]
pub struct PatchModel {
    /// The patches.
    pub patches: Vec<Patch>,
}

impl PatchModel {
    /// The largest absolute control-point coordinate (the model's extent for fixed-point
    /// envelopes).
    pub fn max_coord(&self) -> f64 {
        self.patches
            .iter()
            .flat_map(|p| p.points.iter().flatten())
            .fold(0.0, |m: f64, c| m.max(c.abs()))
    }

    /// Axis-aligned bounds of every control point (the model lies inside: convex hull).
    pub fn bounds(&self) -> (V3, V3) {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for (a, b) in self.patches.iter().map(Patch::bounds) {
            for k in 0..3 {
                lo[k] = lo[k].min(a[k]);
                hi[k] = hi[k].max(b[k]);
            }
        }
        (lo, hi)
    }
}

/// The cubic Bernstein polynomials at `t`.
pub fn bernstein(t: f64) -> [f64; 4] {
    let s = 1.0 - t;
    [s * s * s, 3.0 * t * s * s, 3.0 * t * t * s, t * t * t]
}

/// Derivatives of the cubic Bernstein polynomials at `t`.
pub fn bernstein_slope(t: f64) -> [f64; 4] {
    let s = 1.0 - t;
    [
        -3.0 * s * s,
        3.0 * s * s - 6.0 * t * s,
        6.0 * t * s - 3.0 * t * t,
        3.0 * t * t,
    ]
}

/// Splits a cubic with coefficients `c` at `t` (de Casteljau): the halves on `[0, t]` and
/// `[t, 1]`, each reparametrised to `[0, 1]`.
pub fn split_cubic<const D: usize>(c: [[f64; D]; 4], t: f64) -> ([[f64; D]; 4], [[f64; D]; 4]) {
    let lerp = |a: [f64; D], b: [f64; D]| -> [f64; D] {
        let mut out = a;
        for (o, (x, y)) in out.iter_mut().zip(a.iter().zip(b)) {
            *o = x + (y - x) * t;
        }
        out
    };
    let ab = lerp(c[0], c[1]);
    let bc = lerp(c[1], c[2]);
    let cd = lerp(c[2], c[3]);
    let abc = lerp(ab, bc);
    let bcd = lerp(bc, cd);
    let mid = lerp(abc, bcd);
    ([c[0], ab, abc, mid], [mid, bcd, cd, c[3]])
}

/// Splits a 4×4 grid of coefficients (row-major, rows along `u`) at `t` in `u`.
pub fn split_grid_u<const D: usize>(
    g: &[[f64; D]; 16],
    t: f64,
) -> ([[f64; D]; 16], [[f64; D]; 16]) {
    let mut lo = *g;
    let mut hi = *g;
    for j in 0..4 {
        let (a, b) = split_cubic([g[j], g[4 + j], g[8 + j], g[12 + j]], t);
        for i in 0..4 {
            lo[4 * i + j] = a[i];
            hi[4 * i + j] = b[i];
        }
    }
    (lo, hi)
}

/// Splits a 4×4 grid of coefficients (row-major, rows along `u`) at `t` in `v`.
pub fn split_grid_v<const D: usize>(
    g: &[[f64; D]; 16],
    t: f64,
) -> ([[f64; D]; 16], [[f64; D]; 16]) {
    let mut lo = *g;
    let mut hi = *g;
    for i in 0..4 {
        let (a, b) = split_cubic([g[4 * i], g[4 * i + 1], g[4 * i + 2], g[4 * i + 3]], t);
        lo[4 * i..4 * i + 4].copy_from_slice(&a);
        hi[4 * i..4 * i + 4].copy_from_slice(&b);
    }
    (lo, hi)
}

/// A surface point with its first partial derivatives.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    /// `P(u, v)`.
    pub point: V3,
    /// `∂P/∂u`.
    pub du: V3,
    /// `∂P/∂v`.
    pub dv: V3,
}

/// How far (in `u` and `v`) the normal of a degenerate point is looked for towards the patch
/// centre: the first of these offsets whose tangents span a plane gives the normal.
const NORMAL_NUDGES: [f64; 4] = [1e-7, 1e-5, 1e-3, 1e-1];

impl Patch {
    /// A polynomial, untrimmed patch.
    pub fn polynomial(points: [[f64; 3]; 16]) -> Patch {
        Patch {
            points,
            weights: [1.0; 16],
            trims: Vec::new(),
        }
    }

    /// Whether every weight is 1.
    pub fn is_polynomial(&self) -> bool {
        self.weights.iter().all(|&w| w == 1.0)
    }

    /// The control points in homogeneous coordinates `(w·P, w)`.
    pub fn homogeneous(&self) -> [H4; 16] {
        let mut h = [[0.0; 4]; 16];
        for (o, (p, &w)) in h.iter_mut().zip(self.points.iter().zip(&self.weights)) {
            *o = [p[0] * w, p[1] * w, p[2] * w, w];
        }
        h
    }

    fn combine(h: &[H4; 16], bu: [f64; 4], bv: [f64; 4]) -> H4 {
        let mut out = [0.0; 4];
        for i in 0..4 {
            for j in 0..4 {
                let b = bu[i] * bv[j];
                for (o, c) in out.iter_mut().zip(h[4 * i + j]) {
                    *o += b * c;
                }
            }
        }
        out
    }

    /// `P(u, v)`.
    pub fn point(&self, u: f64, v: f64) -> V3 {
        let x = Self::combine(&self.homogeneous(), bernstein(u), bernstein(v));
        [x[0] / x[3], x[1] / x[3], x[2] / x[3]]
    }

    /// `P(u, v)` with `∂P/∂u` and `∂P/∂v` (quotient rule on the homogeneous form).
    pub fn frame(&self, u: f64, v: f64) -> Frame {
        let h = self.homogeneous();
        let (bu, bv) = (bernstein(u), bernstein(v));
        let x = Self::combine(&h, bu, bv);
        let xu = Self::combine(&h, bernstein_slope(u), bv);
        let xv = Self::combine(&h, bu, bernstein_slope(v));
        let point = [x[0] / x[3], x[1] / x[3], x[2] / x[3]];
        let derive = |d: H4| [0, 1, 2].map(|k| (d[k] - point[k] * d[3]) / x[3]);
        Frame {
            point,
            du: derive(xu),
            dv: derive(xv),
        }
    }

    /// The unit normal `∂P/∂u × ∂P/∂v` at `(u, v)`. Where the tangents do not span a plane (a
    /// collapsed edge such as the teapot lid's centre, or a cone tip) the normal is the limit
    /// taken from inside: the normal a small step towards the patch centre. `None` only if the
    /// patch is degenerate everywhere near the point (a patch collapsed to a curve or a point).
    pub fn normal(&self, u: f64, v: f64) -> Option<V3> {
        let scale = self.scale();
        let at = |u: f64, v: f64| {
            let f = self.frame(u, v);
            let n = cross(f.du, f.dv);
            // Relative to the patch's size: a product of two tangents is an area.
            (dot(n, n).sqrt() > 1e-10 * scale * scale)
                .then(|| normalize(n))
                .flatten()
        };
        at(u, v).or_else(|| {
            NORMAL_NUDGES.iter().find_map(|&d| {
                let step = |t: f64| t + (0.5 - t).signum() * d.min((0.5 - t).abs());
                at(step(u), step(v))
            })
        })
    }

    /// Axis-aligned bounds of the control points (the patch lies inside: convex hull).
    pub fn bounds(&self) -> (V3, V3) {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in &self.points {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        (lo, hi)
    }

    /// The length of the control points' bounding-box diagonal (0 for a point patch).
    pub fn scale(&self) -> f64 {
        let (lo, hi) = self.bounds();
        (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt()
    }

    /// Whether `(u, v)` is on the surface (not cut away by the trim loops).
    pub fn is_kept(&self, u: f64, v: f64) -> bool {
        self.trims.iter().filter(|t| t.contains(u, v)).count() % 2 == 0
    }

    fn from_homogeneous(h: &[H4; 16], trims: Vec<TrimLoop>) -> Patch {
        let mut points = [[0.0; 3]; 16];
        let mut weights = [0.0; 16];
        for ((p, w), c) in points.iter_mut().zip(weights.iter_mut()).zip(h) {
            *w = c[3];
            *p = [c[0] / c[3], c[1] / c[3], c[2] / c[3]];
        }
        Patch {
            points,
            weights,
            trims,
        }
    }

    fn remap_trims(&self, map: impl Fn([f64; 2]) -> [f64; 2]) -> Vec<TrimLoop> {
        self.trims
            .iter()
            .map(|t| TrimLoop {
                points: t.points.iter().map(|&p| map(p)).collect(),
            })
            .collect()
    }

    /// Splits the patch at `u = t` (de Casteljau in homogeneous coordinates): the halves on
    /// `[0, t]` and `[t, 1]` in `u`, each reparametrised to `[0, 1]`, trim loops mapped along.
    pub fn split_u(&self, t: f64) -> (Patch, Patch) {
        let (lo, hi) = split_grid_u(&self.homogeneous(), t);
        (
            Self::from_homogeneous(&lo, self.remap_trims(|[u, v]| [u / t, v])),
            Self::from_homogeneous(&hi, self.remap_trims(|[u, v]| [(u - t) / (1.0 - t), v])),
        )
    }

    /// Splits the patch at `v = t`, as [`Patch::split_u`] does in `u`.
    pub fn split_v(&self, t: f64) -> (Patch, Patch) {
        let (lo, hi) = split_grid_v(&self.homogeneous(), t);
        (
            Self::from_homogeneous(&lo, self.remap_trims(|[u, v]| [u, v / t])),
            Self::from_homogeneous(&hi, self.remap_trims(|[u, v]| [u, (v - t) / (1.0 - t)])),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A bilinear-looking but genuinely cubic, curved patch.
    fn wavy() -> Patch {
        let mut points = [[0.0; 3]; 16];
        for i in 0..4 {
            for j in 0..4 {
                let (x, y) = (i as f64, j as f64);
                points[4 * i + j] = [x, y, (x * 1.3 - y * 0.7).sin() + 0.1 * x * y];
            }
        }
        Patch::polynomial(points)
    }

    #[test]
    fn corners_interpolate_and_derivatives_match_differences() {
        let mut p = wavy();
        p.weights[5] = 2.5;
        p.weights[10] = 0.4;
        assert_eq!(p.point(0.0, 0.0), p.points[0]);
        assert_eq!(p.point(1.0, 0.0), p.points[12]);
        assert_eq!(p.point(0.0, 1.0), p.points[3]);
        let f = p.frame(0.3, 0.6);
        let h = 1e-6;
        for k in 0..3 {
            let du = (p.point(0.3 + h, 0.6)[k] - p.point(0.3 - h, 0.6)[k]) / (2.0 * h);
            let dv = (p.point(0.3, 0.6 + h)[k] - p.point(0.3, 0.6 - h)[k]) / (2.0 * h);
            assert!((du - f.du[k]).abs() < 1e-7, "{du} {}", f.du[k]);
            assert!((dv - f.dv[k]).abs() < 1e-7, "{dv} {}", f.dv[k]);
        }
    }

    #[test]
    fn subdivision_reproduces_the_surface() {
        let mut p = wavy();
        p.weights[6] = 3.0;
        let (a, b) = p.split_u(0.4);
        let (c, d) = p.split_v(0.7);
        for &(s, t) in &[(0.0, 0.0), (0.25, 0.5), (0.9, 0.1), (1.0, 1.0)] {
            let close = |x: V3, y: V3| (0..3).all(|k| (x[k] - y[k]).abs() < 1e-12);
            assert!(close(a.point(s, t), p.point(0.4 * s, t)));
            assert!(close(b.point(s, t), p.point(0.4 + 0.6 * s, t)));
            assert!(close(c.point(s, t), p.point(s, 0.7 * t)));
            assert!(close(d.point(s, t), p.point(s, 0.7 + 0.3 * t)));
        }
    }

    #[test]
    fn collapsed_edge_gets_the_limit_normal() {
        // A cone: the u = 0 edge collapses to the apex (0, 0, 1); the base circle-ish at u = 1.
        let mut points = [[0.0; 3]; 16];
        for j in 0..4 {
            let a = j as f64 * 0.5;
            for i in 0..4 {
                let r = i as f64 / 3.0;
                points[4 * i + j] = [r * a.cos(), r * a.sin(), 1.0 - r];
            }
        }
        let p = Patch::polynomial(points);
        let at_tip = p.normal(0.0, 0.4).expect("limit normal");
        let near = p.normal(1e-3, 0.4).expect("normal");
        assert!(at_tip.iter().all(|c| c.is_finite()));
        assert!(dot(at_tip, near) > 0.999, "{at_tip:?} {near:?}");
    }

    #[test]
    fn trim_even_odd() {
        let square = |a: f64, b: f64| TrimLoop {
            points: vec![[a, a], [b, a], [b, b], [a, b]],
        };
        let mut p = wavy();
        p.trims = vec![square(0.2, 0.8), square(0.4, 0.6)];
        assert!(p.is_kept(0.1, 0.1));
        assert!(!p.is_kept(0.3, 0.5));
        assert!(p.is_kept(0.5, 0.5));
        let (a, _) = p.split_u(0.5);
        assert!(!a.is_kept(0.6, 0.5));
        assert!(a.is_kept(0.9, 0.5));
    }
}
