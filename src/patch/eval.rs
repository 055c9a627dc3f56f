//! Evaluation of a rational bicubic patch in homogeneous fixed point: points (direction
//! independent on the boundary, so neighbours agree bit for bit), sub-patch control nets by
//! blossoming, and normals from the partial derivatives.
//!
//! # Bit budget
//!
//! A homogeneous control point is `(ω·x, ω·y, ω·z, ω)` in I48F16 bits ([`Hom`]): coordinates
//! within ±2^12 and weights within [1/16, 16] ([`super::MAX_WEIGHT`]) give components below
//! 2^16 in value, 2^32 in bits. De Casteljau steps are convex combinations, so every
//! intermediate stays below 2^32 bits; a step multiplies a difference (below 2^33) by a
//! parameter (at most 2^16): below 2^49. Derivatives are 3 differences (2^35); the tangent
//! of the projected surface `H_u·ω − H·ω_u` multiplies them by a weight (2^20): below 2^56.

use super::{PatchModel, Weight, PARAM_ONE};
use crate::math::{fit_bits, mul_i64, zip3, NO_WIDE_MULTIPLY};
use crate::scene::Vertex;
use fixed::types::I16F16;

/// A homogeneous point `(ω·x, ω·y, ω·z, ω)`, each component I48F16 bits in an `i64`.
pub(crate) type Hom = [i64; 4];

/// What de Casteljau interpolates: the coordinate lanes of homogeneous points, or weights.
trait Lerp: Copy {
    /// `a + (b − a)·t` for a parameter `t` in [0, 1] (I16F16 bits), rounded to nearest:
    /// exact at `t = 0` and `t = 1`.
    fn lerp(self, b: Self, t: u32) -> Self;
    /// `3·(b − a)`: a cubic's derivative from its last de Casteljau pair.
    fn slope(self, b: Self) -> Self;
}

/// The formula, one lane.
#[inline(always)]
fn lerp(a: i64, b: i64, t: u32) -> i64 {
    a + scale_rounded(b - a, t)
}

/// `(d·t + 2^15) >> 16` for a parameter `t` in [0, 2^16]. On ARMv6-M, where an `i64` multiply
/// is a library call (about 40 instructions), a `d` that fits `i32` (every difference of a
/// patch within a few thousand units of the eye) takes two 32-bit multiplies: with
/// `d = dh·2^16 + dl`, `dl` in [0, 2^16), the result is `dh·t + ⌊(dl·t + 2^15) / 2^16⌋`
/// exactly (`dh·t·2^16` is a multiple of 2^16; `|dh·t| < 2^31`; `dl·t + 2^15 < 2^32`). The
/// same value every way (test `scale_rounded_is_the_i64_formula`).
#[inline(always)]
fn scale_rounded(d: i64, t: u32) -> i64 {
    if NO_WIDE_MULTIPLY && t <= 1 << 16 {
        if let Ok(d) = i32::try_from(d) {
            return scale_rounded_in_halves(d, t);
        }
    }
    (d * t as i64 + (1 << 15)) >> 16
}

/// [`scale_rounded`] for a `d` that fits `i32` and `t` at most 2^16, in 32-bit multiplies.
#[inline(always)]
fn scale_rounded_in_halves(d: i32, t: u32) -> i64 {
    let (dh, dl) = (d >> 16, (d & 0xFFFF) as u32);
    i64::from(dh * t as i32) + i64::from((dl * t + (1 << 15)) >> 16)
}

/// Weights alone.
impl Lerp for i64 {
    #[inline(always)]
    fn lerp(self, b: i64, t: u32) -> i64 {
        lerp(self, b, t)
    }
    #[inline(always)]
    fn slope(self, b: i64) -> i64 {
        triple(b - self)
    }
}

/// The three coordinate lanes only; the weight lane is `self`'s, carried unchanged. The lanes
/// are independent, so the callers below take weights from the curve's one weight (which
/// every step keeps: a polynomial patch's curves) or interpolate them alone.
impl Lerp for Hom {
    #[inline(always)]
    fn lerp(self, b: Hom, t: u32) -> Hom {
        let [x, y, z, w] = self;
        [lerp(x, b[0], t), lerp(y, b[1], t), lerp(z, b[2], t), w]
    }
    #[inline(always)]
    fn slope(self, b: Hom) -> Hom {
        let ([a0, a1, a2, a3], [b0, b1, b2, b3]) = (self, b);
        [
            triple(b0 - a0),
            triple(b1 - a1),
            triple(b2 - a2),
            triple(b3 - a3),
        ]
    }
}

/// `3·d` (not overflowing). On ARMv6-M LLVM makes `3 * d` of an `i64`, and `(d << 1) + d`
/// too, a call to the 64-bit multiply; there it is two 32-bit additions with carries
/// (test `triple_in_words_is_three_times`).
#[inline(always)]
fn triple(d: i64) -> i64 {
    if NO_WIDE_MULTIPLY {
        triple_in_words(d)
    } else {
        3 * d
    }
}

/// [`triple`] in 32-bit words: the low word added twice with its carries into three times
/// the high word.
#[inline(always)]
fn triple_in_words(d: i64) -> i64 {
    let (low, high) = (d as u32, (d >> 32) as i32);
    let (twice, c1) = low.overflowing_add(low);
    let (thrice, c2) = twice.overflowing_add(low);
    let high = high
        .wrapping_mul(3)
        .wrapping_add(i32::from(c1) + i32::from(c2));
    (i64::from(high) << 32) | i64::from(thrice)
}

/// The weights of cubic `q`, or `None` if it has one weight throughout (then every
/// de Casteljau step keeps it, and [`Lerp`] for [`Hom`] carries it: three lanes of work).
#[inline(always)]
fn weights(q: &[Hom; 4]) -> Option<[i64; 4]> {
    let [a, b, c, d] = q.map(|p| p[3]);
    // (Compared lane by lane: an array comparison calls `memcmp`.)
    (a != b || a != c || a != d).then_some([a, b, c, d])
}

/// The blossom `f(t₀, t₁, t₂)` of the cubic with control points `q`: de Casteljau with a
/// different parameter at each level. `f(a, a, a)` is the curve's point at `a`, and the
/// blossoms at `(a,a,a), (a,a,b), (a,b,b), (b,b,b)` are the control points of its piece over
/// `[a, b]`.
#[inline]
fn blossom(q: [Hom; 4], t: [u32; 3]) -> Hom {
    let mut p = blossom_of(q, t);
    if let Some(w) = weights(&q) {
        p[3] = blossom_of(w, t);
    }
    p
}

/// [`blossom`] of [`Lerp`] values.
#[inline(always)]
fn blossom_of<L: Lerp>(q: [L; 4], t: [u32; 3]) -> L {
    let [a, b, c, d] = q;
    let (ab, bc, cd) = (a.lerp(b, t[0]), b.lerp(c, t[0]), c.lerp(d, t[0]));
    let (abc, bcd) = (ab.lerp(bc, t[1]), bc.lerp(cd, t[1]));
    abc.lerp(bcd, t[2])
}

/// The control points of the piece of cubic `q` over `[a, b]`: the blossoms at `(a,a,a)`,
/// `(a,a,b)`, `(a,b,b)`, `(b,b,b)`, bit for bit as [`blossom`] computes them, with the
/// de Casteljau steps they have in common done once (16 interpolations instead of 24).
#[inline]
fn sub_curve(q: [Hom; 4], ab: [u32; 2]) -> [Hom; 4] {
    let mut s = sub_curve_of(q, ab);
    if let Some(w) = weights(&q) {
        for (p, w) in s.iter_mut().zip(sub_curve_of(w, ab)) {
            p[3] = w;
        }
    }
    s
}

/// [`sub_curve`] of [`Lerp`] values.
#[inline(always)]
fn sub_curve_of<L: Lerp>(q: [L; 4], [a, b]: [u32; 2]) -> [L; 4] {
    let [p0, p1, p2, p3] = q;
    let (ab, bc, cd) = (p0.lerp(p1, a), p1.lerp(p2, a), p2.lerp(p3, a));
    let (abc, bcd) = (ab.lerp(bc, a), bc.lerp(cd, a));
    let (abc_b, bcd_b) = (ab.lerp(bc, b), bc.lerp(cd, b));
    [
        abc.lerp(bcd, a),
        abc.lerp(bcd, b),
        abc_b.lerp(bcd_b, b),
        blossom_of(q, [b; 3]),
    ]
}

/// The point at `t` of the cubic `q` and its derivative `q'(t)`.
#[inline]
fn point_and_tangent(q: [Hom; 4], t: u32) -> (Hom, Hom) {
    let (mut p, mut d) = point_and_tangent_of(q, t);
    if let Some(w) = weights(&q) {
        (p[3], d[3]) = point_and_tangent_of(w, t);
    }
    (p, d)
}

/// [`point_and_tangent`] of [`Lerp`] values (for [`Hom`], one weight gives slope 0).
#[inline(always)]
fn point_and_tangent_of<L: Lerp>(q: [L; 4], t: u32) -> (L, L) {
    let [a, b, c, d] = q;
    let (ab, bc, cd) = (a.lerp(b, t), b.lerp(c, t), c.lerp(d, t));
    let (abc, bcd) = (ab.lerp(bc, t), bc.lerp(cd, t));
    (abc.lerp(bcd, t), abc.slope(bcd))
}

/// The point at `t` of a boundary curve, computed the same way whichever end the caller
/// starts from: the curve is walked from its lexicographically smaller end. Two patches that
/// share an edge (the same four control points, in either order) get identical points.
#[inline]
pub(crate) fn edge_point(q: [Hom; 4], t: u32) -> Hom {
    let reversed = (q[3], q[2]) < (q[0], q[1]);
    let (q, t) = if reversed {
        let [a, b, c, d] = q;
        ([d, c, b, a], PARAM_ONE - t)
    } else {
        (q, t)
    };
    blossom(q, [t; 3])
}

/// The 16 homogeneous control points of a patch (or of a piece of one), row-major:
/// `h[4·i + j]` is `P_ij`, `u` along `i`, `v` along `j`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Net {
    pub(crate) h: [Hom; 16],
}

impl Net {
    /// The control net of patch `index` of `model` (validated, so in the envelope). Out of
    /// line: once per patch or piece taken from a bucket.
    #[inline(never)]
    pub(crate) fn of(model: &PatchModel<'_>, index: usize) -> Net {
        let zero = [[I16F16::ZERO; 3]; 16];
        let points = model.points().get(index).unwrap_or(&zero);
        let one = [Weight::ONE; 16];
        let weights = match model.weights() {
            Some(w) => w.get(index).unwrap_or(&one),
            None => &one,
        };
        let mut h = [[0i64; 4]; 16];
        for ((out, p), w) in h.iter_mut().zip(points).zip(weights) {
            let w = w.to_bits() as i64;
            *out = [
                mul_i64(p[0].to_bits() as i64, w) >> 16,
                mul_i64(p[1].to_bits() as i64, w) >> 16,
                mul_i64(p[2].to_bits() as i64, w) >> 16,
                w,
            ];
        }
        Net { h }
    }

    #[inline(always)]
    fn get(&self, i: usize, j: usize) -> Hom {
        // i, j < 4 at every call site.
        self.h.get(4 * i + j).copied().unwrap_or([0; 4])
    }

    /// The curve `P_i0 .. P_i3` (fixed `u` index, along `v`).
    #[inline(always)]
    fn along_v(&self, i: usize) -> [Hom; 4] {
        [0, 1, 2, 3].map(|j| self.get(i, j))
    }

    /// The curve `P_0j .. P_3j` (fixed `v` index, along `u`).
    #[inline(always)]
    fn along_u(&self, j: usize) -> [Hom; 4] {
        [0, 1, 2, 3].map(|i| self.get(i, j))
    }

    /// The surface point at `(u, v)`. On the boundary it depends only on that edge's four
    /// control points, evaluated direction-independently ([`edge_point`]).
    pub(crate) fn point(&self, u: u32, v: u32) -> Hom {
        // One edge evaluation for the four edges (the code is as long as a blossom).
        let (edge, t) = if v == 0 {
            (self.along_u(0), u)
        } else if v == PARAM_ONE {
            (self.along_u(3), u)
        } else if u == 0 {
            (self.along_v(0), v)
        } else if u == PARAM_ONE {
            (self.along_v(3), v)
        } else {
            return self.column(u).point(v);
        };
        edge_point(edge, t)
    }

    /// The curve `u = const` through the interior, for evaluating many points on it: its
    /// points are bit for bit those of [`Self::point`] (same operations, same order).
    #[inline]
    pub(crate) fn column(&self, u: u32) -> Column {
        Column([0, 1, 2, 3].map(|j| blossom(self.along_u(j), [u; 3])))
    }

    /// The curve `u = const` with its `u`-tangents, for normals along it: its normals are
    /// bit for bit those of `normal_at(u, ·)`.
    #[inline]
    pub(crate) fn tangent_column(&self, u: u32) -> TangentColumn {
        let mut c = [[0i64; 4]; 4];
        let mut cu = [[0i64; 4]; 4];
        for j in 0..4 {
            let (p, d) = point_and_tangent(self.along_u(j), u);
            if let (Some(cj), Some(cuj)) = (c.get_mut(j), cu.get_mut(j)) {
                *cj = p;
                *cuj = d;
            }
        }
        TangentColumn { c, cu }
    }

    /// The control net of the piece over `[u0, u1] × [v0, v1]`.
    pub(crate) fn piece(&self, u: [u32; 2], v: [u32; 2]) -> Net {
        let cut_u = [0, 1, 2, 3].map(|j| sub_curve(self.along_u(j), u));
        let mut h = [[0i64; 4]; 16];
        for i in 0..4 {
            let q = [0, 1, 2, 3].map(|j| cut_u.get(j).and_then(|c| c.get(i)).copied());
            let q = q.map(|p| p.unwrap_or([0; 4]));
            for (j, p) in sub_curve(q, v).into_iter().enumerate() {
                if let Some(slot) = h.get_mut(4 * i + j) {
                    *slot = p;
                }
            }
        }
        Net { h }
    }

    /// The model-space normal direction at `(u, v)`: `S_u × S_v` of the dehomogenized
    /// surface (any scale), or `None` where it vanishes. A collapsed edge (a cone tip, a lid's
    /// centre) has a zero tangent at its corners: there the normal is taken a little way
    /// towards the patch centre, where it tends to the corner's limit normal.
    pub(crate) fn normal(&self, u: u32, v: u32) -> Option<[i64; 3]> {
        let half = PARAM_ONE / 2;
        let towards = |p: u32, shift: u32| {
            if p < half {
                p + ((half - p) >> shift)
            } else {
                p - ((p - half) >> shift)
            }
        };
        self.normal_at(u, v).or_else(|| {
            [8, 5, 2]
                .into_iter()
                .find_map(|shift| self.normal_at(towards(u, shift), towards(v, shift)))
        })
    }

    fn normal_at(&self, u: u32, v: u32) -> Option<[i64; 3]> {
        self.tangent_column(u).normal(v)
    }
}

/// The four control points of the curve `u = const` of a patch ([`Net::column`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Column([Hom; 4]);

impl Column {
    /// The surface point at `(u, v)`, `(u, v)` inside the patch (as [`Net::point`] there).
    #[inline]
    pub(crate) fn point(&self, v: u32) -> Hom {
        blossom(self.0, [v; 3])
    }
}

/// The curve `u = const` of a patch and its `u`-derivative curve ([`Net::tangent_column`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct TangentColumn {
    c: [Hom; 4],
    cu: [Hom; 4],
}

impl TangentColumn {
    /// `S_u × S_v` at `(u, v)` (as `Net::normal_at`), `None` where it vanishes.
    pub(crate) fn normal(&self, v: u32) -> Option<[i64; 3]> {
        let (h, hv) = point_and_tangent(self.c, v);
        let hu = blossom(self.cu, [v; 3]);
        // S = H/ω, so S_u ∝ H_u·ω − H·ω_u (the positive factor 1/ω² dropped).
        let tangent = |d: Hom| -> Option<[i64; 3]> {
            let w = h[3] >> 4;
            let dw = d[3] >> 4;
            let ([d0, d1, d2, _], [h0, h1, h2, _]) = (d, h);
            let t = zip3([d0, d1, d2], [h0, h1, h2], |d, h| {
                mul_i64(d >> 4, w) - mul_i64(h >> 4, dw)
            });
            // Below this a tangent is rounding noise (a few units of its last bits), and
            // scaling it up would invent a direction.
            let largest = t.iter().map(|c| c.unsigned_abs()).max().unwrap_or(0);
            if largest < 1 << 18 {
                return None;
            }
            fit_bits(t, 30).map(|t| t.map(i64::from))
        };
        let (a, b) = (tangent(hu)?, tangent(hv)?);
        let n = [
            mul_i64(a[1], b[2]) - mul_i64(a[2], b[1]),
            mul_i64(a[2], b[0]) - mul_i64(a[0], b[2]),
            mul_i64(a[0], b[1]) - mul_i64(a[1], b[0]),
        ];
        // Tangents that are (nearly) parallel give no usable direction.
        let largest = n.iter().map(|c| c.unsigned_abs()).max().unwrap_or(0);
        (largest >= 1 << 40).then_some(n)
    }
}

/// A homogeneous point as a model vertex (I16F16), rounded to nearest. The weight is
/// positive (a convex combination of weights of at least 1/16).
#[inline]
pub(crate) fn dehomogenize(h: Hom) -> Vertex {
    let [x, y, z, w] = h;
    if w == 1 << 16 {
        // A polynomial patch: nothing to divide.
        return [x, y, z].map(|c| I16F16::from_bits(c as i32));
    }
    // Weights are below 2^21 bits and `h` below 2^32, so nothing here overflows; `checked_`
    // keeps the render path free of panics.
    let w = w.max(1);
    [x, y, z].map(|c| {
        let q = ((c << 17) + w).checked_div_euclid(2 * w).unwrap_or(0);
        I16F16::from_bits(q as i32)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triple_in_words_is_three_times() {
        let mut rng = crate::test_rng::XorShift64::new(0x9e37_79b9_7f4a_7c15);
        let limit = i64::MAX / 3;
        for d in [
            0,
            1,
            -1,
            limit,
            -limit,
            u32::MAX as i64,
            -(u32::MAX as i64),
            1 << 32,
        ] {
            assert_eq!(triple_in_words(d), 3 * d, "{d}");
        }
        for case in 0..200_000u32 {
            let d = (rng.next_u64() as i64) >> (2 + case % 62);
            assert_eq!(triple_in_words(d), 3 * d, "{d}");
            assert_eq!(triple(d), 3 * d, "{d}");
        }
    }

    #[test]
    fn scale_rounded_is_the_i64_formula() {
        let mut rng = crate::test_rng::XorShift64::new(0x0123_4567_89ab_cdef);
        let formula = |d: i64, t: u32| (d * t as i64 + (1 << 15)) >> 16;
        let edges = [
            0i64,
            1,
            -1,
            1 << 15,
            -(1 << 15),
            i32::MAX as i64,
            i32::MIN as i64,
        ];
        for d in edges
            .into_iter()
            .chain([1i64 << 31, -(1i64 << 31) - 1, 1 << 40])
        {
            for t in [0u32, 1, 1 << 15, (1 << 16) - 1, 1 << 16] {
                assert_eq!(scale_rounded(d, t), formula(d, t), "{d} {t}");
            }
        }
        for case in 0..200_000u32 {
            let d = (rng.next_u64() as i64) >> (64 - (1 + case % 40));
            let t = (rng.next_u64() % ((1 << 16) + 1)) as u32;
            assert_eq!(scale_rounded(d, t), formula(d, t), "{d} {t}");
            // The ARMv6-M form, on every target.
            let d = d as i32;
            let want = formula(i64::from(d), t);
            assert_eq!(scale_rounded_in_halves(d, t), want, "{d} {t}");
        }
        for d in [0, 1, -1, i32::MAX, i32::MIN, 0xFFFF, -0x10000] {
            for t in [0u32, 1, (1 << 16) - 1, 1 << 16] {
                let want = formula(i64::from(d), t);
                assert_eq!(scale_rounded_in_halves(d, t), want, "{d} {t}");
            }
        }
    }
    use crate::patch::{PatchColors, PatchModel};
    use embedded_graphics::pixelcolor::Rgb888;

    fn c(v: f64) -> I16F16 {
        I16F16::from_num(v)
    }

    /// A bicubic patch `z = x·y` over [0, 3]² (control points on a grid, `z = i·j`).
    fn saddle() -> [[[I16F16; 3]; 16]; 1] {
        let mut p = [[I16F16::ZERO; 3]; 16];
        for i in 0..4 {
            for j in 0..4 {
                p[4 * i + j] = [c(i as f64), c(j as f64), c((i * j) as f64)];
            }
        }
        [p]
    }

    #[test]
    fn points_match_the_polynomial() {
        let pts = saddle();
        let model =
            PatchModel::new(&pts, None, PatchColors::Uniform(Rgb888::new(255, 255, 255))).unwrap();
        let net = Net::of(&model, 0);
        for (u, v) in [(0.0, 0.0), (0.25, 0.5), (1.0, 0.75), (0.5, 1.0), (0.1, 0.9)] {
            let p = dehomogenize(net.point((u * 65536.0) as u32, (v * 65536.0) as u32));
            let (x, y) = (3.0 * u, 3.0 * v);
            assert!((p[0].to_num::<f64>() - x).abs() < 1e-3, "{u} {v}");
            assert!((p[1].to_num::<f64>() - y).abs() < 1e-3);
            assert!((p[2].to_num::<f64>() - x * y).abs() < 1e-3);
            // Normal of z = x·y: (−y, −x, 1).
            let n = net
                .normal((u * 65536.0) as u32, (v * 65536.0) as u32)
                .unwrap();
            let len = |n: [f64; 3]| (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            let n = n.map(|c| c as f64);
            let e = [-y, -x, 1.0];
            let cos = (n[0] * e[0] + n[1] * e[1] + n[2] * e[2]) / (len(n) * len(e));
            assert!(cos > 0.9999, "{u} {v}: {cos}");
        }
    }

    /// The four-lane forms the evaluation had before the weight lane was split off.
    mod four_lanes {
        use super::Hom;

        fn lerp(a: Hom, b: Hom, t: u32) -> Hom {
            let t = t as i64;
            [0, 1, 2, 3].map(|k| a[k] + (((b[k] - a[k]) * t + (1 << 15)) >> 16))
        }

        pub fn blossom(q: [Hom; 4], t: [u32; 3]) -> Hom {
            let [a, b, c, d] = q;
            let (ab, bc, cd) = (lerp(a, b, t[0]), lerp(b, c, t[0]), lerp(c, d, t[0]));
            let (abc, bcd) = (lerp(ab, bc, t[1]), lerp(bc, cd, t[1]));
            lerp(abc, bcd, t[2])
        }

        pub fn point_and_tangent(q: [Hom; 4], t: u32) -> (Hom, Hom) {
            let [a, b, c, d] = q;
            let (ab, bc, cd) = (lerp(a, b, t), lerp(b, c, t), lerp(c, d, t));
            let (abc, bcd) = (lerp(ab, bc, t), lerp(bc, cd, t));
            (
                lerp(abc, bcd, t),
                [0, 1, 2, 3].map(|k| 3 * (bcd[k] - abc[k])),
            )
        }
    }

    #[test]
    fn split_lanes_give_the_four_lanes_bits() {
        let mut rng = crate::test_rng::XorShift64::new(0x2545_f491_4f6c_dd1du64);
        let mut next = |bits: u32| {
            let seed = rng.next_u64();
            (seed >> (64 - bits)) as i64 - (1 << (bits - 1))
        };
        // Components below 2^32 bits, weights 1/16 to 16 (2^12 to 2^20 bits).
        let extremes = [-(1i64 << 32) + 1, -1, 0, 1, (1 << 32) - 1];
        for case in 0..20_000 {
            let w = (next(21) + (1 << 20)).clamp(1 << 12, 1 << 20);
            let mut c = |k: usize| match case % 4 {
                0 => extremes[(k + case / 4) % extremes.len()],
                _ => next(33),
            };
            let one: [Hom; 4] = [0, 1, 2, 3].map(|j| [c(j), c(j + 1), c(j + 2), w]);
            // Rational: weights that differ; a derivative curve: weights all 0.
            let mut rational = one;
            for p in &mut rational {
                p[3] = (next(21) + (1 << 20)).clamp(1 << 12, 1 << 20);
            }
            rational[2][3] = w + 1;
            let derivative = one.map(|p| [p[0], p[1], p[2], 0]);
            let t = (next(18) + (1 << 17)).clamp(0, 1 << 16) as u32;
            for q in [one, rational, derivative] {
                for t in [t, 0, 1, 32768, 65535, 65536] {
                    let ts = [t, t / 2, PARAM_ONE - t];
                    assert_eq!(blossom(q, ts), four_lanes::blossom(q, ts), "{q:?} {t}");
                    let [a, b] = [t / 3, t];
                    let pieces = [[a, a, a], [a, a, b], [a, b, b], [b, b, b]];
                    let ab = [a, b];
                    let want = pieces.map(|ts| four_lanes::blossom(q, ts));
                    assert_eq!(sub_curve(q, ab), want, "{q:?} {t}");
                    let want = four_lanes::point_and_tangent(q, t);
                    assert_eq!(point_and_tangent(q, t), want, "{q:?} {t}");
                }
            }
        }
    }

    #[test]
    fn edges_do_not_depend_on_direction() {
        let q = [
            [1000, -7, 3, 65536],
            [5, 99999, 17, 60000],
            [-3000, 4, 2, 70000],
            [12, 13, 14, 65536],
        ];
        let r = [q[3], q[2], q[1], q[0]];
        for t in [0, 1, 12345, 32768, 65535, 65536] {
            assert_eq!(edge_point(q, t), edge_point(r, PARAM_ONE - t));
        }
    }

    #[test]
    fn shared_steps_give_the_blossoms_bits() {
        let q = [
            [1000, -7, 3, 65536],
            [5, 99999, 17, 60000],
            [-3000, 4, 2, 70000],
            [12, 13, 14, 65536],
        ];
        for (a, b) in [(0, 65536), (12345, 40000), (16384, 16385), (65535, 65536)] {
            let ts = [[a, a, a], [a, a, b], [a, b, b], [b, b, b]];
            assert_eq!(sub_curve(q, [a, b]), ts.map(|t| blossom(q, t)));
        }
    }

    #[test]
    fn a_piece_has_the_same_surface() {
        let pts = saddle();
        let model =
            PatchModel::new(&pts, None, PatchColors::Uniform(Rgb888::new(255, 255, 255))).unwrap();
        let net = Net::of(&model, 0);
        let piece = net.piece([16384, 49152], [0, 32768]);
        // The piece's corner (1, 1) is the patch's (0.75, 0.5).
        let a = dehomogenize(piece.point(PARAM_ONE, PARAM_ONE));
        let b = dehomogenize(net.point(49152, 32768));
        for k in 0..3 {
            assert!((a[k] - b[k]).abs() <= I16F16::from_bits(4));
        }
    }

    #[test]
    fn a_collapsed_corner_has_a_normal() {
        // A cone: the v = 0 edge collapsed to the apex (0, 0, 1).
        let mut p = [[I16F16::ZERO; 3]; 16];
        for i in 0..4 {
            for j in 0..4 {
                let r = j as f64 / 3.0;
                let a = i as f64 * 0.5;
                p[4 * i + j] = [c(r * a.cos()), c(r * a.sin()), c(1.0 - r)];
            }
        }
        let pts = [p];
        let model =
            PatchModel::new(&pts, None, PatchColors::Uniform(Rgb888::new(255, 255, 255))).unwrap();
        let net = Net::of(&model, 0);
        let n = net.normal(0, 0).expect("a normal at the apex");
        // Roughly along the cone's side: positive z component.
        assert!(n[2] != 0);
    }
}
