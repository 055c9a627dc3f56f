//! Projection: divide by w and map to sub-pixel fixed-point screen coordinates.
//!
//! # Bit budget
//!
//! For screens up to [`MAX_SCREEN`] = 2048 pixels per side and up to 8 sub-pixel bits:
//!
//! * Eye coordinates are I16F16 within ±2^14 units (±2^30 bits), `w >= near >= 2^-8` (2^8 bits).
//! * The horizontal scale `ax = (W/2) · (focal/aspect) · 2^S` is held as a [`Scale`]: a 25-bit
//!   mantissa and a right shift. `ax · x` is then below 2^55 before the shift.
//! * The guard band keeps every projected vertex within `centre ± 4·W·2^S` (8 half-screens) in
//!   x and `centre ± 4·H·2^S` in y, so `|X|, |Y| < 5 · 2^11 · 2^8 < 2^22` sub-pixel units.
//!   Clipping against the guard band (see [`crate::clip`]) is what makes that true.
//! * `X = round(C + N / w)` is computed as one i64 division: `C·w < 2^49`, `2N < 2^56`.
//! * Depth `q = near / w` in I2F30: `near · 2^30 < 2^61`.

use crate::depth::Depth;
use crate::math::{
    bit_length_u64, div_below_float, div_rem_below, floor_div_i64, i16f16_from_f32, mul_i64_i32,
    mul_wide, shr_i64, shr_i64_high, SoftDivisor, FLOAT_ESTIMATES, NO_HARDWARE_DIVIDE,
    NO_WIDE_MULTIPLY,
};
use crate::vertex::EyePoint;
use fixed::types::I16F16;

/// Largest width or height of a render target, in pixels.
pub const MAX_SCREEN: usize = 2048;

/// Largest number of sub-pixel bits.
pub const MAX_SUB_PIXEL_BITS: u32 = 8;

/// Guard band half-width in units of the half-screen: vertices are kept within 8 half-screens of
/// the screen centre.
pub const GUARD_BAND_HALF_SCREENS: i64 = 8;

/// A screen coordinate with `S` sub-pixel bits: Q(32−S).S in pixels, in an `i32`.
///
/// Pixel `(c, r)` has its centre at `((c + ½)·2^S, (r + ½)·2^S)`; row 0 is at the top.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct SubPx<const S: u32>(pub i32);

impl<const S: u32> SubPx<S> {
    /// The coordinate in pixels, as a float (for tests and tools).
    pub fn to_f64(self) -> f64 {
        self.0 as f64 / (1u64 << S) as f64
    }
}

/// A positive scale factor `mantissa · 2^-shift` with a 25-bit mantissa (block floating point),
/// so that a scale between 2^-40 and 2^25 keeps 24 significant bits in integer arithmetic.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Scale {
    mantissa: i32,
    shift: u32,
}

impl Scale {
    /// `None` unless `0 < v < 2^25` and finite.
    ///
    /// Taken from the float's bits, with integer operations only (no soft-float calls on cores
    /// without an FPU): `v = M · 2^(e − 150)` with the 24-bit mantissa `M` (implicit bit
    /// included) and the biased exponent `e`, so `v · 2^shift` lies in `[2^24, 2^25)` for
    /// `shift = 151 − e`, where it is `2M` (doubling is exact). The shift is capped at 62 (a
    /// `v` below about 2^-37): the mantissa is then `⌊v · 2^62⌋`, `M` shifted right by
    /// `88 − e`. This is what doubling `v` in `f32` until it reaches 2^24 (at most 62 times)
    /// and truncating gave. Test `scale_equals_doubling_in_f32`.
    pub fn new(v: f32) -> Option<Scale> {
        let bits = v.to_bits();
        // Positive (sign bit clear, not zero) and below 2^25 (biased exponent 152), which
        // also excludes infinity and NaN.
        if bits == 0 || bits >= 0x4C00_0000 {
            return None;
        }
        let e = bits >> 23;
        // A subnormal `v` (e = 0) is `bits · 2^-149`: its mantissa shifted by 88 is 0, as is
        // `⌊v · 2^62⌋`.
        let m = if e == 0 {
            bits
        } else {
            bits & 0x7F_FFFF | 0x80_0000
        };
        Some(if e >= 89 {
            Scale {
                mantissa: (m << 1) as i32,
                shift: 151 - e,
            }
        } else {
            Scale {
                mantissa: m.checked_shr(88 - e).unwrap_or(0) as i32,
                shift: 62,
            }
        })
    }

    /// `floor(self · v)` for `|v| <= 2^31`.
    #[inline]
    pub fn apply(self, v: i32) -> i64 {
        // The mantissa is below 2^25: a 32 × 32 → 64-bit product, and the shift by a variable
        // amount in 32-bit words (neither a call on ARMv6-M).
        let product = mul_wide(self.mantissa, v);
        if NO_WIDE_MULTIPLY && self.shift >= 32 {
            // On ARMv6-M, where a 64-bit shift by a variable amount is two words' shifts and
            // their carries, the high word's alone for a shift of 32 or more (the demo's and
            // the corpus's projections).
            return shr_i64_high(product, self.shift);
        }
        shr_i64(product, self.shift)
    }

    /// `floor(self · v) >> k` for `|v| <= 2^31`, `k < 64`, as one shift: floors by powers
    /// of two compose (`(a >> s) >> k = a >> (s + k)`, and from 63 on every shift gives the
    /// sign).
    #[inline]
    fn apply_shifted(self, v: i32, k: u32) -> i64 {
        shr_i64(mul_wide(self.mantissa, v), (self.shift + k).min(63))
    }
}

/// Per-frame projection constants for a `width × height` target with `S` sub-pixel bits.
#[derive(Clone, Copy, Debug)]
pub struct Viewport<const S: u32> {
    /// Width in pixels.
    pub width: u16,
    /// Height in pixels.
    pub height: u16,
    ax: Scale,
    ay: Scale,
    /// Near-plane distance.
    pub near: I16F16,
    /// Far-plane distance.
    pub far: I16F16,
    /// Guard band half-widths in sub-pixel units: at most `8 · 2048 / 2 · 2^8 = 2^21`.
    guard_x: i32,
    guard_y: i32,
}

/// A projected vertex: snapped screen position, depth and colour attribute.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ScreenVertex<const S: u32> {
    /// Horizontal position.
    pub x: SubPx<S>,
    /// Vertical position (down).
    pub y: SubPx<S>,
    /// Depth `near / w`.
    pub q: Depth,
    /// Colour channels 0–255 in I16F16 (used by Gouraud shading).
    pub color: [I16F16; 3],
}

impl<const S: u32> Viewport<S> {
    /// Projection for a camera with `focal = 1/tan(fovy/2)`. `None` when the size or the scale
    /// is outside the envelope (size 1..=2048, `S <= 8`, scale below 2^25).
    pub fn new(width: usize, height: usize, focal: f32, near: f32, far: f32) -> Option<Self> {
        if width == 0 || height == 0 || width > MAX_SCREEN || height > MAX_SCREEN {
            return None;
        }
        if S > MAX_SUB_PIXEL_BITS {
            return None;
        }
        let aspect = width as f32 / height as f32;
        let sub = (1u32 << S) as f32;
        let ax = Scale::new(width as f32 * 0.5 * (focal / aspect) * sub)?;
        let ay = Scale::new(height as f32 * 0.5 * focal * sub)?;
        let near = i16f16_from_f32(near)?;
        let far = i16f16_from_f32(far)?;
        Some(Viewport {
            width: width as u16,
            height: height as u16,
            ax,
            ay,
            near,
            far,
            // Below 2^21 (size and `S` checked above), so `as i32` keeps the value.
            guard_x: (((GUARD_BAND_HALF_SCREENS * width as i64) << S) >> 1) as i32,
            guard_y: (((GUARD_BAND_HALF_SCREENS * height as i64) << S) >> 1) as i32,
        })
    }

    /// The six clip distances of an eye point: `[near, far, left, right, top, bottom]`, each
    /// `>= 0` inside. Near/far are in I16F16 bits; the guard planes in sub-pixels × w bits.
    ///
    /// The guard half-widths (below 2^21) and `w` fit `i32`, so `guard · w` is a 32 × 32 →
    /// 64-bit `mul_wide`: on cores without a wide multiply (thumbv6m) four 32-bit
    /// multiplies instead of a call of the 64-bit one, elsewhere the same `i64` product. Test
    /// `clip_distances_equal_the_64_bit_products`.
    #[inline]
    pub fn clip_distances(&self, p: &EyePoint) -> [i64; 6] {
        let w = p.w.to_bits();
        let nx = self.ax.apply(p.x.to_bits());
        let ny = self.ay.apply(p.y.to_bits());
        let (gx, gy) = (mul_wide(self.guard_x, w), mul_wide(self.guard_y, w));
        let w = w as i64;
        [
            w - self.near.to_bits() as i64,
            self.far.to_bits() as i64 - w,
            gx + nx,
            gx - nx,
            gy - ny,
            gy + ny,
        ]
    }

    /// Projects a point that is inside all clip planes (so `w > 0`). `None` only if `w <= 0`,
    /// which clipping rules out.
    #[inline]
    pub fn project(&self, p: &EyePoint, color: [I16F16; 3]) -> Option<ScreenVertex<S>> {
        self.project_with(p, color, true)
    }

    /// [`Viewport::project`], computing the depth `q` only if `depth` is true (else it is 0):
    /// where only the position matters, this saves a 64-bit division per vertex, which cores
    /// without a divider do in software.
    #[inline]
    pub fn project_with(
        &self,
        p: &EyePoint,
        color: [I16F16; 3],
        depth: bool,
    ) -> Option<ScreenVertex<S>> {
        let w = p.w.to_bits() as i64;
        if w <= 0 {
            return None;
        }
        let cx = (self.width as i64) << S;
        let cy = (self.height as i64) << S;
        let nx = self.ax.apply(p.x.to_bits());
        let ny = self.ay.apply(p.y.to_bits());
        // round(c/2 + n/w) = floor((c·w + 2n + w) / 2w)
        let (x, y) = if NO_HARDWARE_DIVIDE {
            // `c·w` by `mul_i64_i32` (`w` fits 32 bits): no `i64` multiply call on ARMv6-M.
            let w32 = p.w.to_bits();
            floor_div_pair(
                mul_i64_i32(cx, w32) + 2 * nx + w,
                mul_i64_i32(cy, w32) - 2 * ny + w,
                2 * w,
            )
        } else {
            (
                floor_div(cx * w + 2 * nx + w, 2 * w),
                floor_div(cy * w - 2 * ny + w, 2 * w),
            )
        };
        let q = match depth {
            false => 0,
            // Without a divider the step would be another copy of the soft division that
            // `floor_div_i64` holds (and takes for this quotient too, skipping its high step):
            // a function of its own cost the lean thumbv6m build 476 B of flash.
            true if NO_HARDWARE_DIVIDE => floor_div_i64((self.near.to_bits() as i64) << 30, w),
            true => depth_of(self.near.to_bits(), p.w.to_bits()),
        };
        Some(screen_vertex(x, y, q, color))
    }

    /// [`Viewport::project_with`] with one reciprocal per vertex instead of a division per
    /// coordinate ([`Reciprocal`]).
    ///
    /// `w` is cut to its top 16 bits (`w = wn · 2^k + rest`, `wn < 2^16`) and `r = ⌊(2^32 − 1)
    /// / wn⌋` is one 32-bit division; then `n / w ≈ ⌊n / 2^k⌋ · r / 2^32`, kept with 8 more
    /// fractional bits and rounded as the exact path rounds. Both cuts err relatively by at
    /// most `2^-15`, so a coordinate errs by at most `2^-14` of its distance from the screen
    /// centre (below 0.1 sub-pixel units anywhere in the guard band of a 240-pixel screen)
    /// before the final rounding; the depth `q` errs relatively by at most `2^-14`.
    ///
    /// Bits: `|n| < 2^22 · w` (guard band), so `|⌊n / 2^k⌋| < 2^22 · wn` and `r · wn <= 2^32`:
    /// the product is below 2^54. `near · r < 2^30 · 2^24`.
    #[inline]
    pub fn project_reciprocal(
        &self,
        p: &EyePoint,
        color: [I16F16; 3],
        depth: bool,
    ) -> Option<ScreenVertex<S>> {
        const F: u32 = 8;
        let w = p.w.to_bits();
        if w <= 0 {
            return None;
        }
        // On ARMv6-M (no divider, no wide multiply, no count-leading-zeros instruction) the
        // bit length, the division, the shifts and the products below are written out in
        // 32-bit operations instead of library calls; every value is the same.
        let length = if NO_HARDWARE_DIVIDE {
            bit_length_u64(w as u64)
        } else {
            32 - w.leading_zeros()
        };
        let k = length.saturating_sub(16);
        // wn >= 1: w > 0 and k keeps its top bit.
        let wn = ((w as u32) >> k).max(1);
        let r = if NO_HARDWARE_DIVIDE {
            SoftDivisor::new(wn).div_rem(u32::MAX).0
        } else {
            u32::MAX / wn
        } as i64;
        // r fits i32 unless wn = 1 (w of one bit, below any near plane).
        let times_r = |v: i64| match i32::try_from(r) {
            Ok(r) if NO_HARDWARE_DIVIDE => mul_i64_i32(v, r),
            _ => v * r,
        };
        // ⌊n / 2^k⌋ · r / 2^(32 − F) for n = ⌊scale · v⌋.
        let offset = |scale: Scale, v: I16F16| {
            // One variable 64-bit shift instead of two where those are written out in words;
            // the two shifts are the shorter code where they are instructions.
            let n = if NO_HARDWARE_DIVIDE {
                scale.apply_shifted(v.to_bits(), k)
            } else {
                scale.apply(v.to_bits()) >> k
            };
            times_r(n) >> (32 - F)
        };
        let half = 1i64 << (F - 1);
        let cx = (self.width as i64) << (S + F - 1);
        let cy = (self.height as i64) << (S + F - 1);
        let x = (cx + offset(self.ax, p.x) + half) >> F;
        let y = (cy - offset(self.ay, p.y) + half) >> F;
        let q = if depth {
            shr_i64(times_r(self.near.to_bits() as i64), 2 + k)
        } else {
            0
        };
        Some(screen_vertex(x, y, q, color))
    }
}

/// The exact depth `⌊near·2^30 / w⌋` (`near`, `w` raw I16F16, `w > 0`) wherever it is below 2^32,
/// and some value of at least 2^32 elsewhere, which [`screen_vertex`] saturates as it does the
/// quotient: for `near > 0` the quotient fits 32 bits exactly when the numerator's high word is
/// below `w` (a vertex no nearer than `near / 4`), and then one 64 / 32-bit step
/// ([`div_rem_below`]) divides it, without the general division's high-word step and signs; on a
/// core with an FPU, an `f32` estimate and one 32-bit division of its remainder
/// ([`div_below_float`], the same quotient). Test `depth_of_saturates_as_the_division`. Not
/// inlined, as the division it replaces was not: inlined, it made `Viewport::project_with` too
/// large to be inlined itself.
#[inline(never)]
fn depth_of(near: i32, w: i32) -> i64 {
    let n = (near as i64) << 30;
    match (u64::try_from(n), u32::try_from(w)) {
        (Ok(n), Ok(w)) if ((n >> 32) as u32) < w => {
            // On an FPU core, from an `f32` estimate (exact all the same).
            let float = if FLOAT_ESTIMATES {
                div_below_float(n, w)
            } else {
                None
            };
            match float {
                Some(q) => q as i64,
                None => div_rem_below((n >> 32) as u32, n as u32, w).0 as i64,
            }
        }
        (Ok(_), Ok(_)) => 1 << 32,
        _ => floor_div_i64(n, w as i64),
    }
}

/// `floor(n / d)` for `d > 0`: a 32-bit division when both fit `u32` (an on-screen vertex at a
/// moderate `w`: `n ≈ X · 2w`), else the 64-bit one. The same quotient either way; on 32-bit
/// cores the first is one `UDIV` (Cortex-M4) instead of a 64-bit library division. Cores
/// without a divider (Cortex-M0) take [`floor_div_pair`] instead.
#[inline]
fn floor_div(n: i64, d: i64) -> i64 {
    if let (Ok(n32), Ok(d32)) = (u32::try_from(n), u32::try_from(d)) {
        if let Some(q) = n32.checked_div(d32) {
            return q as i64;
        }
    }
    floor_div_i64(n, d)
}

/// `(floor_div(a, d), floor_div(b, d))` for the core without a divider
/// ([`NO_HARDWARE_DIVIDE`]): where `d` fits 32 bits, one [`SoftDivisor`] for both, each
/// numerator that fits `u32` divided by it; else [`floor_div_i64`]. The same quotients.
#[inline(always)]
fn floor_div_pair(a: i64, b: i64, d: i64) -> (i64, i64) {
    match u32::try_from(d) {
        Ok(d32) => {
            let by = SoftDivisor::new(d32);
            let div = |n: i64| match u32::try_from(n) {
                Ok(n) => by.div_rem(n).0 as i64,
                Err(_) => floor_div_i64(n, d),
            };
            (div(a), div(b))
        }
        Err(_) => (floor_div_i64(a, d), floor_div_i64(b, d)),
    }
}

/// A projected vertex from its position and depth bits (within range after clipping; the
/// depth saturates at the top of I2F30).
#[inline]
fn screen_vertex<const S: u32>(x: i64, y: i64, q: i64, color: [I16F16; 3]) -> ScreenVertex<S> {
    ScreenVertex {
        x: SubPx(x as i32),
        y: SubPx(y as i32),
        q: Depth::from_bits(q.min(i32::MAX as i64) as i32),
        color,
    }
}

/// How vertices are divided by `w`, chosen at compile time (see
/// [`crate::arithmetic::Arithmetic`]); `Viewport::project_as` projects with it.
pub trait ProjectionPrecision:
    Copy + Default + core::fmt::Debug + PartialEq + Eq + sealed::Sealed + 'static
{
    /// Whether this is [`Reciprocal`] (else [`ExactDivision`]).
    const RECIPROCAL: bool;
}

mod sealed {
    pub trait Sealed {}
    impl Sealed for super::ExactDivision {}
    impl Sealed for super::Reciprocal {}
}

/// A 64-bit division per coordinate and for the depth, each rounded exactly
/// (`Viewport::project_with`): the default.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ExactDivision;

/// One 32-bit reciprocal per vertex and multiplications (`Viewport::project_reciprocal`):
/// positions within `2^-14` of their offset from the screen centre, for a fraction of the cost
/// on cores without a divider.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Reciprocal;

impl ProjectionPrecision for ExactDivision {
    const RECIPROCAL: bool = false;
}

impl ProjectionPrecision for Reciprocal {
    const RECIPROCAL: bool = true;
}

impl<const S: u32> Viewport<S> {
    /// Projects a point inside all clip planes with projection `P`; the depth is 0 unless
    /// `depth`.
    #[inline]
    pub fn project_as<P: ProjectionPrecision>(
        &self,
        p: &EyePoint,
        color: [I16F16; 3],
        depth: bool,
    ) -> Option<ScreenVertex<S>> {
        if P::RECIPROCAL {
            self.project_reciprocal(p, color, depth)
        } else {
            self.project_with(p, color, depth)
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// `depth_of` is the exact floored quotient wherever that is below 2^32 and at least 2^32
    /// elsewhere, so the vertex's saturated depth is the division's: every `w` around the
    /// boundary `near / 4` and the near plane, the extremes, and random pairs.
    #[test]
    fn depth_of_saturates_as_the_division() {
        let check = |near: i32, w: i32| {
            let exact = floor_div_i64((near as i64) << 30, w as i64);
            let got = depth_of(near, w);
            if exact < 1 << 32 {
                assert_eq!(got, exact, "near {near} w {w}");
            } else {
                assert!(got >= 1 << 32, "near {near} w {w}: {got}");
            }
            assert_eq!(got.min(i32::MAX as i64), exact.min(i32::MAX as i64));
        };
        for near in [
            1,
            2,
            3,
            655,
            1 << 16,
            6_553_600,
            i32::MAX - 1,
            i32::MAX,
            0,
            -1,
            -65_536,
        ] {
            let quarter = (near / 4).max(1);
            for w in (1..200)
                .chain(quarter.saturating_sub(100)..quarter.saturating_add(100))
                .chain(near.saturating_sub(100).max(1)..near.saturating_add(100).max(2))
                .chain(i32::MAX - 100..=i32::MAX)
            {
                check(near, w.max(1));
            }
        }
        let mut rng = crate::test_rng::XorShift32::new(0x2468_ace1u32);
        for _ in 0..100_000 {
            let near = (rng.next_u32() >> (rng.next_u32() % 32)) as i32;
            let w = ((rng.next_u32() >> (rng.next_u32() % 32)) as i32).max(1);
            check(near, w);
        }
    }

    /// The 32-bit path of `floor_div` gives the 64-bit quotient, on both sides of its limits.
    #[test]
    fn floor_div_equals_euclidean_division() {
        let edges = [
            0i64,
            1,
            2,
            3,
            u32::MAX as i64 - 1,
            u32::MAX as i64,
            1 << 32,
            (1 << 32) + 1,
        ];
        for n in edges.iter().flat_map(|&e| [e, -e, e + 7, -e - 7, e << 20]) {
            for d in [1i64, 2, 3, 65_536, u32::MAX as i64, 1 << 32, (1 << 40) + 3] {
                assert_eq!(floor_div(n, d), n.div_euclid(d), "{n} / {d}");
            }
        }
        let mut rng = crate::test_rng::XorShift64::new(0x1F83_D9AB_FB41_BD6Bu64);
        for _ in 0..100_000 {
            let x = rng.next_u64();
            let n = (x as i64) >> (x % 40 + 1);
            let d = ((x >> 20) % (1 << (x % 36 + 1))) as i64 + 1;
            assert_eq!(floor_div(n, d), n.div_euclid(d), "{n} / {d}");
        }
    }

    /// An eye-space point from floats (tests of the stages around projection use it too).
    pub(crate) fn eye(x: f32, y: f32, w: f32) -> EyePoint {
        EyePoint {
            x: I16F16::from_num(x),
            y: I16F16::from_num(y),
            w: I16F16::from_num(w),
        }
    }

    #[test]
    fn centre_of_view_lands_on_screen_centre() {
        let vp = Viewport::<4>::new(240, 160, 1.0, 0.5, 100.0).unwrap();
        let s = vp.project(&eye(0.0, 0.0, 5.0), [I16F16::ZERO; 3]).unwrap();
        assert_eq!((s.x.0, s.y.0), (120 * 16, 80 * 16));
        assert_eq!(s.q, Depth::from_num(0.1));
    }

    #[test]
    fn projection_matches_float_formula() {
        let (w, h, focal) = (240usize, 160usize, 1.7320508f32);
        let vp = Viewport::<4>::new(w, h, focal, 0.1, 100.0).unwrap();
        for &(x, y, z) in &[
            (1.0f32, 0.5f32, 3.0f32),
            (-2.5, 1.25, 7.0),
            (0.3, -0.7, 0.2),
        ] {
            let s = vp.project(&eye(x, y, z), [I16F16::ZERO; 3]).unwrap();
            let aspect = w as f64 / h as f64;
            let px = w as f64 / 2.0 * (1.0 + focal as f64 / aspect * x as f64 / z as f64);
            let py = h as f64 / 2.0 * (1.0 - focal as f64 * y as f64 / z as f64);
            assert!(
                (s.x.to_f64() - px).abs() <= 1.0 / 32.0 + 1e-3,
                "{} {}",
                s.x.to_f64(),
                px
            );
            assert!(
                (s.y.to_f64() - py).abs() <= 1.0 / 32.0 + 1e-3,
                "{} {}",
                s.y.to_f64(),
                py
            );
        }
    }

    #[test]
    fn odd_width_without_sub_pixels_rounds_the_centre() {
        let vp = Viewport::<0>::new(5, 5, 1.0, 0.5, 100.0).unwrap();
        let s = vp.project(&eye(0.0, 0.0, 5.0), [I16F16::ZERO; 3]).unwrap();
        assert_eq!((s.x.0, s.y.0), (3, 3)); // 2.5 rounds half up
    }

    #[test]
    fn invalid_viewports_are_rejected() {
        assert!(Viewport::<4>::new(0, 10, 1.0, 0.5, 10.0).is_none());
        assert!(Viewport::<4>::new(4096, 10, 1.0, 0.5, 10.0).is_none());
        assert!(Viewport::<9>::new(10, 10, 1.0, 0.5, 10.0).is_none());
        assert!(Viewport::<8>::new(2048, 2048, 1e6, 0.5, 10.0).is_none());
    }

    #[test]
    fn reciprocal_projection_stays_within_its_bound() {
        let mut rng = crate::test_rng::XorShift32::new(0x1234_5678u32);
        let mut next = || {
            let x = rng.next_u32();
            x as f64 / u32::MAX as f64
        };
        for (sub, vp) in [
            (4, Viewport::<4>::new(240, 160, 1.7, 0.1, 100.0).unwrap()),
            (
                4,
                Viewport::<4>::new(2048, 2048, 0.5, 1.0 / 256.0, 16384.0).unwrap(),
            ),
        ] {
            for _ in 0..5000 {
                // w across the whole envelope, x and y within the guard band.
                let w = libm::exp2(next() * 22.0 - 8.0).min(16383.0);
                let p = eye(
                    ((next() * 2.0 - 1.0) * w * 2.0) as f32,
                    ((next() * 2.0 - 1.0) * w * 2.0) as f32,
                    w as f32,
                );
                if vp.clip_distances(&p).iter().any(|&d| d < 0) {
                    continue;
                }
                let exact = vp.project_with(&p, [I16F16::ZERO; 3], true).unwrap();
                let fast = vp.project_reciprocal(&p, [I16F16::ZERO; 3], true).unwrap();
                let centre = |c: u16| (c as i64) << (sub - 1);
                let dx = (exact.x.0 as i64 - centre(vp.width)).abs() as f64;
                let dy = (exact.y.0 as i64 - centre(vp.height)).abs() as f64;
                // 2^-14 of the offset, plus one unit for rounding on either side of a tie.
                assert!(
                    ((fast.x.0 - exact.x.0).abs() as f64) <= dx / 16384.0 + 1.0,
                    "{p:?}"
                );
                assert!(
                    ((fast.y.0 - exact.y.0).abs() as f64) <= dy / 16384.0 + 1.0,
                    "{p:?}"
                );
                let q = exact.q.to_bits() as f64;
                assert!(((fast.q.to_bits() - exact.q.to_bits()).abs() as f64) <= q / 16384.0 + 1.0);
            }
        }
    }

    /// One shift by `shift + k` (capped at 63) is the scaled value shifted by `k`: every shift
    /// of a scale (its exponent over the whole range, the cap at 62), both signs, `k` up to 63.
    #[test]
    fn shifted_scale_is_the_scale_shifted() {
        let mut rng = crate::test_rng::XorShift32::new(0x9e37_79b9u32);
        for e in 1..152u32 {
            let scale = Scale::new(f32::from_bits(e << 23 | (rng.next_u32() & 0x7F_FFFF)));
            let Some(scale) = scale else { continue };
            for v in [
                0,
                1,
                -1,
                i32::MAX,
                i32::MIN,
                rng.next_u32() as i32,
                -(rng.next_u32() as i32 >> 7),
            ] {
                for k in 0..64 {
                    assert_eq!(
                        scale.apply_shifted(v, k),
                        scale.apply(v) >> k,
                        "{scale:?} {v} {k}"
                    );
                }
            }
        }
    }

    /// The reciprocal projection's soft division (its ARMv6-M form) is `u32::MAX / wn` for
    /// every `wn` it can take (a 16-bit top of `w`), so both forms project alike.
    #[test]
    fn soft_reciprocal_is_the_division() {
        for wn in 1..=u16::MAX as u32 {
            assert_eq!(
                SoftDivisor::new(wn).div_rem(u32::MAX).0,
                u32::MAX / wn,
                "{wn}"
            );
        }
    }

    /// `Scale::new` from the float's bits equals the doubling in `f32` it replaced: every
    /// exponent (subnormals, the cap at 62, the top of the range), the rejected values, and
    /// random floats.
    #[test]
    fn scale_equals_doubling_in_f32() {
        let doubling = |v: f32| -> Option<Scale> {
            if v.is_nan() || v <= 0.0 || v >= (1u32 << 25) as f32 {
                return None;
            }
            let (mut m, mut shift) = (v, 0u32);
            while m < (1u32 << 24) as f32 && shift < 62 {
                m *= 2.0;
                shift += 1;
            }
            Some(Scale {
                mantissa: m as i32,
                shift,
            })
        };
        let mut values = std::vec![
            0.0f32,
            -0.0,
            f32::NAN,
            -f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::MIN_POSITIVE,
            f32::from_bits(1),
            (1u32 << 25) as f32,
            f32::from_bits(((1u32 << 25) as f32).to_bits() - 1),
            (1u32 << 24) as f32,
            -1.0,
            1.0,
            3.0e-5,
        ];
        for e in 0..=255u32 {
            for m in [0u32, 1, 0x40_0000, 0x7F_FFFF, 0x12_3457] {
                values.extend([
                    f32::from_bits(e << 23 | m),
                    f32::from_bits(1 << 31 | e << 23 | m),
                ]);
            }
        }
        let mut rng = crate::test_rng::XorShift32::new(0x1234_5678u32);
        for _ in 0..1_000_000 {
            let x = rng.next_u32();
            values.push(f32::from_bits(x));
            values.push(f32::from_bits(x & 0x4FFF_FFFF));
        }
        for v in values {
            assert_eq!(Scale::new(v), doubling(v), "{v:e} ({:#x})", v.to_bits());
        }
    }

    /// The clip distances equal the `i64` products of the guard half-widths they replaced:
    /// the largest screen and sub-pixel bits, and eye points across the whole envelope (`w`
    /// and `x`, `y` up to ±2^30 bits, either sign).
    #[test]
    fn clip_distances_equal_the_64_bit_products() {
        fn check<const S: u32>(vp: &Viewport<S>, p: &EyePoint) {
            let w = p.w.to_bits() as i64;
            let (gx, gy) = (vp.guard_x as i64 * w, vp.guard_y as i64 * w);
            let (nx, ny) = (vp.ax.apply(p.x.to_bits()), vp.ay.apply(p.y.to_bits()));
            let want = [
                w - vp.near.to_bits() as i64,
                vp.far.to_bits() as i64 - w,
                gx + nx,
                gx - nx,
                gy - ny,
                gy + ny,
            ];
            assert_eq!(vp.clip_distances(p), want, "{p:?}");
        }
        let big = Viewport::<8>::new(MAX_SCREEN, MAX_SCREEN, 1.0, 1.0 / 256.0, 16384.0).unwrap();
        assert_eq!((big.guard_x, big.guard_y), (1 << 21, 1 << 21));
        let small = Viewport::<4>::new(240, 160, 1.7, 0.1, 100.0).unwrap();
        let ends = [0, 1, -1, 1 << 30, -(1 << 30), i32::MAX, i32::MIN];
        let mut rng = crate::test_rng::XorShift32::new(0x1234_5678u32);
        let mut next = move || {
            let x = rng.next_u32();
            (x as i32) >> (x % 32)
        };
        for k in 0..200_000 {
            let pick = |n: i32, k: usize| {
                if k.is_multiple_of(3) {
                    ends[k / 3 % 7]
                } else {
                    n
                }
            };
            let p = EyePoint {
                x: I16F16::from_bits(pick(next(), k)),
                y: I16F16::from_bits(pick(next(), k / 7)),
                w: I16F16::from_bits(pick(next(), k / 49)),
            };
            check(&big, &p);
            check(&small, &p);
        }
    }

    #[test]
    fn scale_keeps_24_significant_bits() {
        let s = Scale::new(3.0e-5).unwrap();
        let v = s.apply(1 << 30) as f64;
        assert!((v - 3.0e-5 * (1u64 << 30) as f64).abs() <= 1.0);
        assert!(Scale::new(0.0).is_none());
        assert!(Scale::new(f32::NAN).is_none());
    }
}
