//! The tracer's arithmetic: 3-vectors of [`I16F16`], wide dot products in [`I32F32`], an integer
//! square root and normalisation.
//!
//! ## Bit budget
//!
//! Every coordinate the tracer stores is an [`I16F16`] (range ±32768, step 2^-16 ≈ 1.5·10^-5).
//! Scene coordinates are limited to ±[`MAX_COORD`] = 2^12, so a difference of two points is at
//! most 2^13 per axis and a dot product of two differences at most 3·2^26, far inside the
//! [`I32F32`] range (±2^31) that holds every product. A product of two I16F16 raw values is
//! below 2^58, so the sum of three fits an `i64`. Unit vectors (directions, normals) have
//! components in [−1, 1]. Narrowing an I32F32 back to I16F16 truncates towards −∞ (an error
//! below one I16F16 step) and is checked: a value outside the I16F16 range is an error or
//! saturates, never a wrapped number. The exception is a product that the scene's checked
//! limits keep inside the range (a unit vector's component times a bounded scalar, a colour
//! channel times a coefficient of at most 8): it narrows without the test
//! (`narrow_bits_in_range`), each call saying why it cannot leave the range.

use crate::math::{
    bit_length_u64, div_rem_below, leading_zeros_nonzero, mul_wide_u32, shr_low_word, shr_u64,
};
pub use crate::math::{isqrt32, isqrt32_bitwise, isqrt32_newton, wide_by_unsigned};
use fixed::types::{I16F16, I32F32};

/// The largest scene coordinate magnitude (any axis), in world units: 2^12.
pub const MAX_COORD: I16F16 = I16F16::from_bits(4096 << 16);

/// A point or direction in world space, each component an [`I16F16`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct Vec3 {
    /// x.
    pub x: I16F16,
    /// y.
    pub y: I16F16,
    /// z.
    pub z: I16F16,
}

impl Vec3 {
    /// The zero vector.
    pub const ZERO: Vec3 = Vec3::from_bits(0, 0, 0);

    /// A vector from raw I16F16 bits (what `sim export` writes).
    pub const fn from_bits(x: i32, y: i32, z: i32) -> Vec3 {
        Vec3 {
            x: I16F16::from_bits(x),
            y: I16F16::from_bits(y),
            z: I16F16::from_bits(z),
        }
    }

    /// The raw I16F16 bits, x, y, z.
    pub const fn bits(self) -> [i32; 3] {
        [self.x.to_bits(), self.y.to_bits(), self.z.to_bits()]
    }

    /// Whether every component lies within ±[`MAX_COORD`].
    pub const fn in_envelope(self) -> bool {
        let m = MAX_COORD.to_bits();
        let [x, y, z] = self.bits();
        x >= -m && x <= m && y >= -m && y <= m && z >= -m && z <= m
    }

    /// `self + o`, wrapping only outside the envelope (never inside it: 2^13 + 2^13 < 2^15).
    #[inline]
    #[allow(clippy::should_implement_trait)] // named, not an operator: it wraps outside the envelope
    pub fn add(self, o: Vec3) -> Vec3 {
        let (a, b) = (self.bits(), o.bits());
        Vec3::from_bits(
            a[0].wrapping_add(b[0]),
            a[1].wrapping_add(b[1]),
            a[2].wrapping_add(b[2]),
        )
    }

    /// `self − o` (see [`add`](Self::add)).
    #[inline]
    #[allow(clippy::should_implement_trait)] // named, not an operator: it wraps outside the envelope
    pub fn sub(self, o: Vec3) -> Vec3 {
        let (a, b) = (self.bits(), o.bits());
        Vec3::from_bits(
            a[0].wrapping_sub(b[0]),
            a[1].wrapping_sub(b[1]),
            a[2].wrapping_sub(b[2]),
        )
    }

    /// `−self`.
    #[inline]
    #[allow(clippy::should_implement_trait)] // named, not an operator: it wraps outside the envelope
    pub fn neg(self) -> Vec3 {
        let a = self.bits();
        Vec3::from_bits(
            a[0].wrapping_neg(),
            a[1].wrapping_neg(),
            a[2].wrapping_neg(),
        )
    }

    /// The dot product, exact, in I32F32.
    #[inline]
    pub const fn dot(self, o: Vec3) -> I32F32 {
        I32F32::from_bits(self.dot_bits(o))
    }

    /// The dot product's raw I32F32 bits.
    #[inline]
    pub const fn dot_bits(self, o: Vec3) -> i64 {
        let (a, b) = (self.bits(), o.bits());
        wide(a[0], b[0])
            .wrapping_add(wide(a[1], b[1]))
            .wrapping_add(wide(a[2], b[2]))
    }

    /// `self · s` for a scalar `s`, each product narrowed to I16F16 (saturating: only reached
    /// outside the envelope).
    #[inline]
    pub fn scale(self, s: I16F16) -> Vec3 {
        let a = self.bits();
        let s = s.to_bits();
        Vec3::from_bits(
            narrow_bits(wide(a[0], s)),
            narrow_bits(wide(a[1], s)),
            narrow_bits(wide(a[2], s)),
        )
    }

    /// [`scale`](Self::scale) without the range tests, for a product its call site bounds
    /// inside the I16F16 range (each says why): the same bits there, with three tests fewer.
    #[inline]
    pub(crate) fn scale_in_range(self, s: I16F16) -> Vec3 {
        let a = self.bits();
        let s = s.to_bits();
        Vec3::from_bits(
            mul_shr16_in_range(a[0], s),
            mul_shr16_in_range(a[1], s),
            mul_shr16_in_range(a[2], s),
        )
    }

    /// `self + d · t`: a point along a ray.
    #[inline]
    pub fn along(self, d: Vec3, t: I16F16) -> Vec3 {
        self.add(d.scale(t))
    }

    /// [`along`](Self::along) for a ray's direction `d` (components at most 2 in magnitude: a
    /// unit vector, or a reflected one a few steps longer): where `|t| < 2^14` no product can
    /// leave the I16F16 range, so one test of `t` replaces the three of the products. The same
    /// bits as `along`.
    #[inline]
    pub(crate) fn along_ray(self, d: Vec3, t: I16F16) -> Vec3 {
        if t.to_bits().unsigned_abs() < 1 << 30 {
            self.add(d.scale_in_range(t))
        } else {
            self.along(d, t)
        }
    }

    /// The unit vector along `self`, or `None` for a vector shorter than 2^-8 (too short to
    /// give a direction with 16 fraction bits: see [`normalize_bits`]).
    #[inline]
    pub fn normalized(self) -> Option<Vec3> {
        self.normalized_with_length().map(|(unit, _)| unit)
    }

    /// The unit vector along `self`, for any vector but zero: [`normalized`](Self::normalized)
    /// after scaling a short vector by a power of two, which keeps its direction exactly,
    /// until its longest component is at least 2^-2. `normalized` alone refuses a vector
    /// shorter than 2^-8 and takes the direction of one not much longer from a few bits (the
    /// normal of a primitive a few hundredths of a unit across, or near a cone's apex). Longer
    /// vectors are normalised as `normalized` does, with the same result.
    #[inline]
    pub fn unit(self) -> Option<Vec3> {
        let [x, y, z] = self.bits();
        let longest = x.unsigned_abs().max(y.unsigned_abs()).max(z.unsigned_abs());
        if longest == 0 {
            return None;
        }
        // Below 2^14 raw (2^-2) the bit length is under 15: shifted to 15, every component
        // stays below 2^15 raw in magnitude.
        let shift = longest.leading_zeros().saturating_sub(17);
        Vec3::from_bits(x << shift, y << shift, z << shift).normalized()
    }

    /// Whether [`normalized`](Self::normalized) gives a unit vector: its length's [`sqrt`] is
    /// at least 2^-8 exactly when `self · self` is at least 2^-16 (2^16 raw I32F32 bits; below
    /// 2^32 raw the root is exact), without the root.
    #[inline]
    pub const fn normalizable(self) -> bool {
        self.dot_bits(self) >= 1 << 16
    }

    /// The unit vector along `self` and the length it was divided by ([`sqrt`] of `self ·
    /// self`), or `None` for a vector shorter than 2^-8: one square root for both.
    #[inline]
    pub fn normalized_with_length(self) -> Option<(Vec3, I16F16)> {
        self.normalized_with_length_inlined()
    }

    /// [`normalized_with_length`](Self::normalized_with_length) inlined into its caller, for
    /// the tracer's per-ray sites (the primary ray's direction, the light vector): the copies
    /// there cost less than the calls, but on ARMv6-M (measured with `cargo xtask trace
    /// alone`, docs/tracing.md).
    #[cfg_attr(
        not(all(target_arch = "arm", not(target_has_atomic = "32"))),
        inline(always)
    )]
    #[cfg_attr(all(target_arch = "arm", not(target_has_atomic = "32")), inline)]
    pub(crate) fn normalized_with_length_inlined(self) -> Option<(Vec3, I16F16)> {
        let len = sqrt(self.dot(self));
        normalize_by(self.bits(), len.to_bits()).map(|[x, y, z]| (Vec3::from_bits(x, y, z), len))
    }
}

/// Raw I32F32 bits narrowed to raw I16F16 bits (`>> 16`, towards −∞), saturating outside the
/// I16F16 range.
#[inline]
pub const fn narrow_bits(v: i64) -> i32 {
    // `v >> 16` fits an i32 exactly when bits 47 to 63 of `v` are all equal: tested on the
    // high word alone, cheaper on a 32-bit core than two 64-bit comparisons.
    let high = (v >> 32) as i32;
    if high >> 15 == high >> 31 {
        (v >> 16) as i32
    } else if high < 0 {
        i32::MIN
    } else {
        i32::MAX
    }
}

/// [`narrow_bits`] without its range test, for a value its call site bounds inside the
/// I16F16 range (each call says why, from the scene's checked limits: unit vectors, colours
/// in [0, 1], coefficients and intensities at most 8): there the same bits, three instructions
/// fewer on a 32-bit core. Outside the range the high bits are dropped: only a scene whose
/// fields were set outside their documented limits, after its checks, can get there.
#[inline]
pub(crate) const fn narrow_bits_in_range(v: i64) -> i32 {
    (v >> 16) as i32
}

/// [`mul`] without the range test, for a product its call site bounds inside the I16F16 range
/// (see [`narrow_bits_in_range`]).
#[inline]
pub(crate) fn mul_in_range(a: I16F16, b: I16F16) -> I16F16 {
    I16F16::from_bits(mul_shr16_in_range(a.to_bits(), b.to_bits()))
}

/// `narrow_bits_in_range(wide(a, b))`, the product of two raw I16F16 values narrowed to I16F16
/// where its call site bounds it inside the range: on ARMv6-M from three 32-bit multiplies
/// instead of the wide product's four and its 64-bit sums (`mul_shr16_in_words`); elsewhere
/// the wide multiply. The same bits within the range (test
/// `range_free_forms_equal_the_saturating_ones_within_their_bounds`).
#[inline]
fn mul_shr16_in_range(a: i32, b: i32) -> i32 {
    if crate::math::NO_WIDE_MULTIPLY {
        mul_shr16_in_words(a, b)
    } else {
        narrow_bits_in_range(wide(a, b))
    }
}

/// [`mul_shr16_in_range`] in 32-bit words, on every target (tested on the host): with
/// `a = ah·2^16 + al` and `b = bh·2^16 + bl` (`ah`, `bh` signed, `al`, `bl` in `[0, 2^16)`),
/// `a·b = (a·bh + ah·bl)·2^16 + al·bl`, so `⌊a·b / 2^16⌋ = a·bh + ah·bl + ⌊al·bl / 2^16⌋`
/// (`al·bl` is non-negative and below 2^32). Only `a·bh` can leave `i32`; the sum is taken
/// modulo 2^32, which gives the value itself wherever it fits `i32`.
#[inline]
fn mul_shr16_in_words(a: i32, b: i32) -> i32 {
    let (ah, al) = (a >> 16, (a & 0xFFFF) as u32);
    let (bh, bl) = (b >> 16, (b & 0xFFFF) as u32);
    a.wrapping_mul(bh)
        .wrapping_add(ah * bl as i32)
        .wrapping_add(((al * bl) >> 16) as i32)
}

/// `a · b` for two I16F16 values, truncated, saturating outside the I16F16 range.
#[inline]
pub fn mul(a: I16F16, b: I16F16) -> I16F16 {
    I16F16::from_bits(narrow_bits(wide(a.to_bits(), b.to_bits())))
}

/// `a · b` as `i64`: on ARMv6-M, which has no 32 × 32 → 64-bit multiply (an `i64` product is a
/// call to `__aeabi_lmul` there), from four 32-bit multiplies of 16-bit halves, as
/// `math::mul_wide` does for the rasterizer (here `const`, for [`Vec3::dot_bits`]); elsewhere
/// the `i64` multiply. The same value either way (test `wide_is_the_i64_product`).
#[inline]
pub const fn wide(a: i32, b: i32) -> i64 {
    if crate::math::NO_WIDE_MULTIPLY {
        wide_in_halves(a, b)
    } else {
        a as i64 * b as i64
    }
}

/// [`wide`] from 32-bit multiplies, on every target: with `a = ah·2^16 + al` (`ah` signed, `al`
/// in `[0, 2^16)`) and `b` alike, `a·b = ah·bh·2^32 + (ah·bl + al·bh)·2^16 + al·bl`, each of the
/// four products fitting 32 bits.
#[inline]
const fn wide_in_halves(a: i32, b: i32) -> i64 {
    let (ah, al) = (a >> 16, a & 0xFFFF);
    let (bh, bl) = (b >> 16, b & 0xFFFF);
    let cross = (ah * bl) as i64 + (al * bh) as i64;
    let low = (al as u32 * bl as u32) as i64;
    (((ah * bh) as i64) << 32) + (cross << 16) + low
}

/// `(a · b) >> 32` truncated to 64 bits, exactly `((a as i128 * b as i128) >> 32) as i64` (the
/// product of two I32F32 raw values, as I32F32): on ARMv6-M (no wide multiply, where the
/// `i128` product is several library calls) from the 32-bit words, `a·b = ah·bh·2^64 +
/// (ah·bl + al·bh)·2^32 + al·bl`, the last term's low word the only one the shift drops;
/// elsewhere the `i128` product. Test `shifted_wide_products_are_exact`.
#[inline]
pub fn mul_shr32(a: i64, b: i64) -> i64 {
    if crate::math::NO_WIDE_MULTIPLY {
        mul_shr32_in_words(a, b)
    } else {
        ((a as i128 * b as i128) >> 32) as i64
    }
}

/// [`mul_shr32`] from 32-bit words, on every target (tested on the host too).
#[inline]
fn mul_shr32_in_words(a: i64, b: i64) -> i64 {
    let (ah, al) = ((a >> 32) as i32, a as u32);
    let (bh, bl) = ((b >> 32) as i32, b as u32);
    let high = (u64::from(ah.wrapping_mul(bh) as u32) << 32) as i64;
    let low = (mul_wide_u32(al, bl) >> 32) as i64;
    high.wrapping_add(wide_by_unsigned(ah, bl))
        .wrapping_add(wide_by_unsigned(bh, al))
        .wrapping_add(low)
}

/// An I32F32 narrowed to I16F16, or `None` outside the I16F16 range.
#[inline]
pub fn narrow(v: I32F32) -> Option<I16F16> {
    // In range exactly when bits 47 to 63 are all equal (see `narrow_bits`).
    let (bits, high) = (v.to_bits(), (v.to_bits() >> 32) as i32);
    (high >> 15 == high >> 31).then_some(I16F16::from_bits((bits >> 16) as i32))
}

/// Whether the tracer's square roots and reciprocals start from single-precision floating
/// point: on Arm cores with a hardware FPU (the `eabihf` targets, Cortex-M4F and the like), where
/// a conversion, multiply or divide of `f32` is one instruction. The integer corrections after the
/// estimate make the results exactly those of the integer forms on every target.
pub const FLOAT_ESTIMATES: bool = crate::math::FLOAT_ESTIMATES;

/// ⌊√v⌋ for a 32-bit integer, the tracer's: [`isqrt32_float`] where the core has an FPU
/// ([`FLOAT_ESTIMATES`]), [`isqrt32_table`] on ARMv6-M (no divider), else [`isqrt32`]. The
/// same bits every way.
#[inline]
pub fn root32(v: u32) -> u32 {
    if FLOAT_ESTIMATES {
        isqrt32_float(v)
    } else if cfg!(all(target_arch = "arm", not(target_has_atomic = "32"))) {
        // ARMv6-M is the Arm profile without 32-bit atomics (and without a divider).
        isqrt32_table(v)
    } else {
        isqrt32(v)
    }
}

/// `⌊4096·√i⌋` for `i` in 64..256: the root of `i · 2^24`, a lower bound of the root of any
/// `v` whose top byte is `i`, at most 257 below it (`4096·(√(i+1) − √i) + 1`, largest at 64).
const ROOT_SEEDS: [u16; 192] = {
    let mut t = [0u16; 192];
    let mut j = 0;
    while j < 192 {
        t[j] = isqrt32_bitwise(((j as u32) + 64) << 24) as u16;
        j += 1;
    }
    t
};

/// ⌊√v⌋ for a 32-bit integer without a division: for `v ≥ 2^30` (every radicand `sqrt` shifts
/// down to 32 bits) the root of `v`'s top byte from a table of 192 entries (`ROOT_SEEDS`), at
/// most 257 below ⌊√v⌋, then the nine low bits (up to 511) of the difference one at a time, keeping
/// `rem = v − r²` (adding `d` is allowed when `(2r + d)·d ≤ rem`): nine steps instead of
/// [`isqrt32_bitwise`]'s sixteen, which smaller `v` keep. Exact (tested against
/// [`isqrt32_newton`], every 32-bit input once).
#[inline]
pub const fn isqrt32_table(v: u32) -> u32 {
    if v < 1 << 30 {
        return isqrt32_bitwise(v);
    }
    // v >> 24 is in 64..256.
    let index = (v >> 24) as usize - 64;
    if index >= ROOT_SEEDS.len() {
        return isqrt32_bitwise(v);
    }
    let mut r = ROOT_SEEDS[index] as u32;
    let mut rem = v - r * r;
    let mut d = 256;
    while d != 0 {
        let step = (2 * r + d) * d;
        if step <= rem {
            rem -= step;
            r += d;
        }
        d >>= 1;
    }
    r
}

/// ⌊√v⌋ for a 32-bit integer from a single-precision estimate: `1/√v` from the exponent-halving
/// bit seed and two Newton steps `y ← y·(c − v/2·y²)` (the second with `c` a little below 3/2,
/// so the estimate `v·y` stays under √v), truncated, then checked by its square: `r` is ⌊√v⌋
/// when `r² ≤ v < (r + 1)²`, else `r + 1` is tried. The estimate is a fraction of a unit below
/// √v (two Newton steps leave about 5·10^-6 relative, 0.3 at the largest root), so one of the
/// two is the root; should neither be, [`isqrt32_newton`] gives it, so the result is ⌊√v⌋
/// whatever the floating point does (tested against every 32-bit input,
/// `float_root_is_exact_everywhere`). About 25 instructions with a hardware FPU (Cortex-M4F),
/// no division.
#[inline]
pub const fn isqrt32_float(v: u32) -> u32 {
    let f = v as f32;
    let h = 0.5 * f;
    let y = f32::from_bits(0x5f37_5a86_u32.wrapping_sub(f.to_bits() >> 1));
    let y = y * (1.5 - h * y * y);
    let y = y * (1.499_998_5 - h * y * y);
    // ⌊√v⌋ ≤ 65535 for any 32-bit v.
    let mut r = (f * y) as u32;
    if r > 65_535 {
        r = 65_535;
    }
    // r² ≤ v < (r + 1)² ⇔ v − r² ≤ 2r, the difference wrapping to a huge value when r² > v.
    if v.wrapping_sub(r * r) <= 2 * r {
        return r;
    }
    r += 1;
    if r <= 65_535 && v.wrapping_sub(r * r) <= 2 * r {
        return r;
    }
    isqrt32_newton(v)
}

/// √v for a non-negative I32F32, as an I16F16 (negative input gives 0).
///
/// The raw I16F16 result is ⌊√bits⌋ of the I32F32's raw bits, computed with a 32-bit square root
/// after shifting the radicand right by an even `2k` so it fits 32 bits: the result is exact
/// (⌊√⌋) for a radicand below 1.0 (2^32 raw) and otherwise at most 2^k raw steps low,
/// a relative error below 2^-15.
#[inline]
pub fn sqrt(v: I32F32) -> I16F16 {
    let bits = v.to_bits();
    if bits <= 0 {
        return I16F16::ZERO;
    }
    let high = (bits >> 32) as u32;
    if high == 0 {
        // Below 2^32: the exact root, below 2^16.
        return I16F16::from_bits(root32(bits as u32) as i32);
    }
    // The smallest even shift that brings the radicand below 2^32 (2 to 32), from the high
    // word alone: its 32 − lz bits rounded up to even (`leading_zeros_nonzero` and
    // `shr_low_word`: no library call on ARMv6-M for the count or the 64-bit shift).
    let shift = (33 - leading_zeros_nonzero(high)) & !1;
    // root < 2^16 and shift / 2 ≤ 16: the product stays below 2^32.
    let root = root32(shr_low_word(bits, shift) as u32) << (shift / 2);
    if root > i32::MAX as u32 {
        I16F16::MAX
    } else {
        I16F16::from_bits(root as i32)
    }
}

/// Normalises raw I16F16 components to a unit vector (raw I16F16), or `None` for a vector
/// shorter than 2^-8.
///
/// The length comes from [`sqrt`]; the components are multiplied by its reciprocal held in
/// I2F30-like precision (`2^46 / length_bits` by [`reciprocal46`], no 64-bit division), so each
/// unit component is
/// within 2 steps of 2^-16 of the exact one.
#[inline]
pub fn normalize_bits(v: [i32; 3]) -> Option<[i32; 3]> {
    let len2 = Vec3::from_bits(v[0], v[1], v[2]).dot_bits(Vec3::from_bits(v[0], v[1], v[2]));
    normalize_by(v, sqrt(I32F32::from_bits(len2)).to_bits())
}

/// Raw I16F16 components divided by their length `len` (raw I16F16, from [`sqrt`]), or `None`
/// when `len` is below 2^-8.
#[inline]
fn normalize_by(v: [i32; 3], len: i32) -> Option<[i32; 3]> {
    if len < 1 << 8 {
        return None;
    }
    let inv = reciprocal46(len as u32);
    if crate::math::NO_WIDE_MULTIPLY {
        // ARMv6-M: a reciprocal below 2^32 (every length over 1/4) in 32-bit multiplies.
        if let Ok(inv) = u32::try_from(inv) {
            let c = |x: i32| (wide_by_unsigned(x, inv) >> 30) as i32;
            return Some([c(v[0]), c(v[1]), c(v[2])]);
        }
    }
    let c = |x: i32| ((x as i64 * inv) >> 30) as i32;
    Some([c(v[0]), c(v[1]), c(v[2])])
}

/// ⌊2^46 / `len`⌋ (1/length in 30 fraction bits for a raw I16F16 length) for `len` in
/// [2^8, 2^31), without a 64-bit division. Above 2^14 (a length over 1/4, every direction the
/// tracer normalises but the shortest) it is the exact quotient from two 16-bit digits of 32-bit
/// divisions (`math::div_rem_below`: about half the instructions of [`reciprocal62`]'s Newton
/// steps). Below, `len` shifted to L in [2^30, 2^31), then [`reciprocal62`] scaled back by the
/// shift: exact at 2^14; under it the low `k − 17` bits of 2^(45 + k) / L are zero, a relative
/// error below 2^-25 (tested), far under the square root's 2^-15.
#[inline]
pub fn reciprocal46(len: u32) -> i64 {
    if len > 1 << 14 {
        if FLOAT_ESTIMATES {
            if let Some(q) = reciprocal46_float(len) {
                return q;
            }
        }
        // 2^46 = 2^14 · 2^32 with 2^14 < len: the quotient fits 32 bits.
        return i64::from(div_rem_below(1 << 14, 0, len).0);
    }
    let k = len.leading_zeros(); // 18..=23, or 1..=17 only at 2^14
    let r = reciprocal62(len << (k - 1)) as i64;
    // 2^46 / len = 2^(45 + k) / L = r · 2^(k − 17).
    if k <= 17 {
        r >> (17 - k)
    } else {
        r << (k - 17)
    }
}

/// ⌊2^46 / `len`⌋ for `len` above 2^14 from a single-precision estimate, or `None` where the
/// estimate's remainder does not fit 32 bits (`len` near 2^30 and above, beyond the lengths the
/// envelope gives). The quotient `2^46 / len` in `f32` is within 2^-23 of the exact one; taken
/// down by more than its error (`q0 − q0/2^22 − 2`, below ⌊2^46 / len⌋), its remainder
/// `2^46 − q0·len` is non-negative and at most about 3·2^23 + 4·len, and
/// `q0 + ⌊remainder / len⌋` is the exact quotient: one 32-bit division instead of
/// `math::div_rem_below`'s two digits. Exact whatever the estimate, since the remainder is checked.
#[inline]
pub fn reciprocal46_float(len: u32) -> Option<i64> {
    const TWO_TO_46: f32 = (1u64 << 46) as f32;
    let q = TWO_TO_46 / len as f32;
    let q0 = q as u32;
    let q0 = q0.wrapping_sub(q0 >> 22).wrapping_sub(2);
    let rem = (1u64 << 46).wrapping_sub(u64::from(q0) * u64::from(len));
    let rem = u32::try_from(rem).ok()?;
    Some(i64::from(q0) + i64::from(rem.checked_div(len)?))
}

/// ⌊2^62 / `l`⌋ for `l` in [2^30, 2^31) (so at most 2^32), exact, without a 64-bit division:
/// 2^62 = 2^30 · 2^32 with 2^30 < `l` makes the quotient fit 32 bits, so it is
/// `math::div_rem_below`'s two 16-bit digits of 32-bit divisions (soft on ARMv6-M, by
/// multiplies); `l` = 2^30 gives 2^32.
#[inline]
pub fn reciprocal62(l: u32) -> u64 {
    if l <= 1 << 30 {
        return 1 << 32;
    }
    u64::from(div_rem_below(1 << 30, 0, l).0)
}

/// ⌊n · 2^16 / d⌋ approximately, for `n` below 2^47 and `d` in (0, 2^34), without a 64-bit
/// division: `d` reduced to 31 significant bits and inverted by [`reciprocal62`], `n` reduced
/// to 32 significant bits, one 32 × 32 → 64-bit product, a shift. Relative error below 2^-25
/// (the reductions truncate by at most 2^-30 and 2^-31, the reciprocal by 2^-32; tested), so
/// within 2 raw steps for a quotient below 2^26 raw (2^10 units).
#[inline]
pub fn ratio16(n: u64, d: u64) -> u64 {
    if n == 0 || d == 0 {
        return 0;
    }
    // d ≈ D · 2^ds with D in [2^30, 2^31); n ≈ N · 2^ns with N below 2^32. (The bit lengths,
    // shifts and the product by `math`'s word forms: no library call on ARMv6-M.)
    let ds = bit_length_u64(d) as i32 - 31;
    // (`n` and `d` are below 2^63, so as `i64` they shift as they would unsigned.)
    let big_d = if ds >= 0 {
        shr_low_word(d as i64, ds as u32) as u32
    } else {
        (d as u32) << -ds
    };
    let ns = (bit_length_u64(n) as i32 - 32).max(0);
    let big_n = shr_low_word(n as i64, ns as u32) as u32;
    // ≈ N · 2^62 / D; the reciprocal is 2^32 only for D = 2^30.
    let product = match u32::try_from(reciprocal62(big_d)) {
        Ok(r) => mul_wide_u32(big_n, r),
        Err(_) => u64::from(big_n) << 32,
    };
    // n · 2^16 / d = N · 2^62 / D · 2^(ns + 16 − 62 − ds).
    let e = ns - ds - 46;
    if e <= 0 {
        if e <= -64 {
            0
        } else {
            shr_u64(product, (-e) as u32)
        }
    } else {
        product.checked_shl(e as u32).unwrap_or(u64::MAX)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec::Vec;

    /// Inputs for the square roots: random values of every length, 0, 1, every perfect square
    /// and its neighbours at each power of 2 and near the top, and the maximum.
    fn root_inputs() -> Vec<u32> {
        let mut rng = crate::test_rng::XorShift64::new(0x3c6e_f372_fe94_f82bu64);
        let mut next = || rng.next_u64();
        let mut v: Vec<u32> = (0..300_000)
            .map(|_| (next() >> 32) as u32 >> (next() % 32))
            .collect();
        let squares = (0..=65_535u32)
            .step_by(97)
            .chain(0..300)
            .chain(65_000..=65_535)
            .chain((0..16).map(|b| 1 << b));
        for r in squares {
            let s = r * r;
            let above = s.wrapping_add(2 * r);
            v.extend([
                s,
                s.wrapping_sub(1),
                s.wrapping_add(1),
                above,
                above.wrapping_add(1),
            ]);
        }
        v.extend([0, 1, 2, 3, u32::MAX, u32::MAX - 1, 1 << 31, (1 << 31) - 1]);
        v
    }

    #[test]
    fn wide_is_the_i64_product() {
        let mut rng = crate::test_rng::XorShift64::new(0xa54f_f53a_5f1d_36f1u64);
        let mut next = || rng.next_u64();
        let edges = [
            0,
            1,
            -1,
            0xFFFF,
            0x1_0000,
            -0x1_0000,
            i32::MAX,
            i32::MIN,
            i32::MIN + 1,
        ];
        let pairs = (0..200_000)
            .map(|_| {
                (
                    (next() as i32) >> (next() % 32),
                    (next() as i32) >> (next() % 32),
                )
            })
            .chain(
                edges
                    .iter()
                    .flat_map(|a| edges.iter().map(move |b| (*a, *b))),
            );
        for (a, b) in pairs {
            assert_eq!(wide_in_halves(a, b), a as i64 * b as i64, "{a} {b}");
            assert_eq!(wide(a, b), a as i64 * b as i64, "{a} {b}");
            let u = b as u32;
            assert_eq!(wide_by_unsigned(a, u), a as i64 * u as i64, "{a} {u}");
        }
    }

    #[test]
    fn table_root_is_the_integer_root() {
        for v in root_inputs() {
            assert_eq!(isqrt32_table(v), isqrt32_newton(v), "{v}");
        }
        // Each seed is the root of its byte's least value.
        for (j, seed) in ROOT_SEEDS.iter().enumerate() {
            let v = (j as u32 + 64) << 24;
            assert_eq!(u32::from(*seed), isqrt32_newton(v), "{v}");
        }
    }

    #[test]
    fn float_root_is_the_integer_root() {
        for v in root_inputs() {
            assert_eq!(isqrt32_float(v), isqrt32_newton(v), "{v}");
            assert_eq!(root32(v), isqrt32_newton(v), "{v}");
        }
    }

    /// Every 32-bit input, the float and table roots and `math::isqrt32` (on the host the
    /// `f64` root) (about two minutes in a release build:
    /// `cargo test -p scanline3d --release --lib float_root_is_exact_everywhere -- --ignored`).
    #[test]
    #[ignore]
    fn float_root_is_exact_everywhere() {
        let mut r = 0u32;
        for v in 0..=u32::MAX {
            // ⌊√v⌋ steps up by one at each square.
            if u64::from(r + 1) * u64::from(r + 1) == u64::from(v) {
                r += 1;
            }
            assert_eq!(isqrt32_float(v), r, "{v}");
            assert_eq!(isqrt32_table(v), r, "{v}");
            assert_eq!(isqrt32(v), r, "{v}");
        }
    }

    /// Every length from 2^14 + 1 to the envelope's largest (2^13·√3 units, below 2^30 raw)
    /// takes the single-precision path, and its quotient is exact (about ten seconds in a
    /// release build: `cargo test -p scanline3d --release --lib float_reciprocal_is_exact_everywhere
    /// -- --ignored`).
    #[test]
    #[ignore]
    fn float_reciprocal_is_exact_everywhere() {
        for len in (1u32 << 14) + 1..(1 << 30) - (1 << 23) {
            let exact = (1u64 << 46) / u64::from(len);
            assert_eq!(reciprocal46_float(len), Some(exact as i64), "{len}");
        }
    }

    #[test]
    fn float_reciprocal_is_the_exact_quotient() {
        let mut rng = crate::test_rng::XorShift64::new(0xbb67_ae85_84ca_a73bu64);
        let mut next = || rng.next_u64();
        let lens = (0..300_000)
            .map(|_| ((next() >> 33) as u32 >> (next() % 17)).max((1 << 14) + 1))
            .chain((1u32 << 14) + 1..1 << 17)
            .chain((14..31).flat_map(|b| [(1u32 << b) - 1, 1 << b, (1 << b) + 1]))
            .chain([
                (1 << 31) - 1,
                (1 << 31) - 2,
                (1 << 30) - (1 << 23),
                46_341,
                65_535,
            ]);
        let mut fell_back = 0;
        for len in lens.filter(|l| *l > 1 << 14) {
            let exact = (1i64 << 46) / i64::from(len);
            match reciprocal46_float(len) {
                Some(q) => assert_eq!(q, exact, "{len}"),
                None => {
                    // Only lengths beyond the envelope's (2^13·√3 units < 2^30 raw).
                    assert!(len > (1 << 30) - (1 << 23), "{len}");
                    fell_back += 1;
                }
            }
            assert_eq!(reciprocal46(len), exact, "{len}");
        }
        assert!(fell_back > 0);
    }

    #[test]
    fn reciprocal46_is_within_its_bound() {
        let lens = (1u32 << 8..1 << 20)
            .step_by(7)
            .chain((1 << 20..1 << 31).step_by(104_729))
            .chain([1 << 8, 1 << 16, 1 << 30, (1 << 31) - 1, 65_535, 65_537]);
        for len in lens {
            let exact = (1i64 << 46) / i64::from(len);
            let got = reciprocal46(len);
            // Low by at most 2^-26 relative, plus one unit for the final truncation.
            assert!(
                got <= exact && exact - got <= (exact >> 26) + 1,
                "{len}: {got} vs {exact}"
            );
        }
    }

    #[test]
    fn reciprocal46_is_the_exact_quotient_from_2_to_the_14() {
        let mut rng = crate::test_rng::XorShift64::new(0x2545_f491_4f6c_dd1du64);
        let mut next = || rng.next_u64();
        let lens = (0..200_000)
            .map(|_| (next() >> 33) as u32)
            .filter(|l| *l >= 1 << 14)
            .chain((1u32 << 14..1 << 16).step_by(3))
            .chain((14..31).flat_map(|b| [(1u32 << b) - 1, 1 << b, (1 << b) + 1]))
            .chain([(1 << 31) - 1, (1 << 31) - 2, 46_341, 65_535, 65_537]);
        for len in lens {
            assert_eq!(reciprocal46(len), (1i64 << 46) / i64::from(len), "{len}");
        }
    }

    #[test]
    fn normalizable_is_whether_normalized_gives_a_vector() {
        let mut rng = crate::test_rng::XorShift64::new(0x9e37_79b9_7f4a_7c15u64);
        let mut next = || rng.next_u64();
        let small = |r: u64| (r % 769) as i32 - 384;
        let mut vectors: Vec<Vec3> = (0..100_000)
            .map(|_| Vec3::from_bits(small(next()), small(next() >> 16), small(next() >> 32)))
            .collect();
        vectors.extend((0..20_000).map(|_| {
            let [a, b, c] = [next(), next(), next()].map(|r| (r >> (40 + r % 24)) as i32);
            Vec3::from_bits(a, -b, c)
        }));
        for c in [0, 1, 255, 256, 257, 1 << 16, -(1 << 16), 1 << 28] {
            vectors.extend([
                Vec3::from_bits(c, 0, 0),
                Vec3::from_bits(0, c, 0),
                Vec3::from_bits(c, c, c),
            ]);
        }
        for v in vectors {
            assert_eq!(v.normalizable(), v.normalized().is_some(), "{v:?}");
        }
    }

    #[test]
    fn narrow_bits_is_the_clamped_shift() {
        let wide = |v: i64| (v >> 16).clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32;
        let mut rng = crate::test_rng::XorShift64::new(0xd1b5_4a32_d192_ed03u64);
        let mut next = || rng.next_u64();
        let edges = (40..63).flat_map(|b| {
            let p = 1i64 << b;
            [p - 1, p, p + 1, -p - 1, -p, -p + 1]
        });
        let values = (0..200_000)
            .map(|_| (next() as i64) >> (next() % 40))
            .chain(edges)
            .chain([0, -1, 1, i64::MAX, i64::MIN, (1 << 47) - 1, -(1 << 47)]);
        for v in values {
            assert_eq!(narrow_bits(v), wide(v), "{v}");
        }
    }

    #[test]
    fn range_free_forms_equal_the_saturating_ones_within_their_bounds() {
        let mut rng = crate::test_rng::XorShift64::new(0x8c3a_72e1_05d4_b96fu64);
        let mut next = || rng.next_u64();
        // Any I16F16 of every magnitude, its extremes included.
        let mut any = move || match next() % 8 {
            0 => [i32::MIN, i32::MAX, 0, -1][(next() % 4) as usize],
            _ => (next() as i32) >> (next() % 32),
        };
        for _ in 0..200_000 {
            // A factor in [−1, 1] times anything but −2^15 stays within ±2^47.
            let unit = any() % (1 << 16);
            let other = any().max(i32::MIN + 1);
            let v = unit as i64 * other as i64;
            assert_eq!(narrow_bits_in_range(v), narrow_bits(v), "{v}");
            assert_eq!(
                mul_shr16_in_words(unit, other),
                narrow_bits(v),
                "{unit} {other}"
            );
            // Any two factors whose product's narrowing fits.
            let (x, y) = (any(), any());
            let xy = x as i64 * y as i64;
            if xy >> 47 == xy >> 63 {
                assert_eq!(mul_shr16_in_words(x, y), narrow_bits(xy), "{x} {y}");
            }
            let (a, b) = (I16F16::from_bits(unit), I16F16::from_bits(other));
            assert_eq!(mul_in_range(a, b), mul(a, b), "{a} {b}");
            let d = Vec3::from_bits(unit, any() % (1 << 16), any() % (1 << 16));
            assert_eq!(d.scale_in_range(b), d.scale(b), "{d:?} {b}");
            // A ray's direction (components up to 2) and any `t`, the largest included.
            let ray = Vec3::from_bits(any() % (2 << 16), any() % (2 << 16), any() % (2 << 16));
            let (origin, t) = (
                Vec3::from_bits(any(), any(), any()),
                I16F16::from_bits(any()),
            );
            assert_eq!(
                origin.along_ray(ray, t),
                origin.along(ray, t),
                "{origin:?} {ray:?} {t}"
            );
        }
    }

    /// Raw I32F32 values: random magnitudes of every size, and the edges of each power of 2.
    fn wide_values() -> Vec<i64> {
        let mut rng = crate::test_rng::XorShift64::new(0x6a09_e667_f3bc_c908u64);
        let mut next = || rng.next_u64();
        let edges = (0..63).flat_map(|b| {
            let p = 1i64 << b;
            [p - 1, p, p + 1, -p - 1, -p, -p + 1]
        });
        (0..200_000)
            .map(|_| (next() as i64) >> (next() % 63))
            .chain(edges)
            .chain([0, i64::MAX, i64::MIN])
            .collect()
    }

    #[test]
    fn narrow_is_the_checked_shift() {
        for v in wide_values() {
            let want = i32::try_from(v >> 16).ok().map(I16F16::from_bits);
            assert_eq!(narrow(I32F32::from_bits(v)), want, "{v}");
        }
    }

    #[test]
    fn sqrt_is_the_64_bit_form() {
        // The form before the high-word shift: 64-bit leading zeros, shift and result.
        let wide = |bits: i64| {
            if bits <= 0 {
                return 0;
            }
            let bits = bits as u64;
            let high = 64 - bits.leading_zeros();
            let shift = if high > 32 { (high - 31) & !1 } else { 0 };
            let shift = if high > 32 && (bits >> shift) > u64::from(u32::MAX) {
                shift + 2
            } else {
                shift
            };
            let root = u64::from(isqrt32((bits >> shift) as u32)) << (shift / 2);
            root.min(i32::MAX as u64) as i32
        };
        for v in wide_values() {
            assert_eq!(sqrt(I32F32::from_bits(v)).to_bits(), wide(v), "{v}");
        }
    }

    #[test]
    fn shifted_wide_products_are_exact() {
        let mut rng = crate::test_rng::XorShift64::new(0x5851_f42d_4c95_7f2du64);
        let edges = [
            0i64,
            1,
            -1,
            i64::MAX,
            i64::MIN,
            1 << 32,
            -(1 << 32),
            u32::MAX as i64,
        ];
        for k in 0..200_000u64 {
            let (x, y) = (rng.next_u64(), rng.next_u64());
            let (a, b) = match k % 3 {
                0 => (x as i64, y as i64),
                1 => ((x as i64) >> (y % 64), (y as i64) >> (x % 64)),
                _ => (edges[(x % 8) as usize], (y as i64) >> (x % 64)),
            };
            let want = ((a as i128 * b as i128) >> 32) as i64;
            assert_eq!(mul_shr32_in_words(a, b), want, "{a} · {b}");
            assert_eq!(mul_shr32(a, b), want, "{a} · {b}");
        }
    }

    #[test]
    fn reciprocal62_is_the_exact_quotient() {
        let mut rng = crate::test_rng::XorShift64::new(0x6a09_e667_f3bc_c908u64);
        let edges = [
            1u32 << 30,
            (1 << 30) + 1,
            (1 << 31) - 1,
            (1 << 31) - 2,
            3 << 29,
        ];
        let random = (0..200_000).map(|_| (1 << 30) | (rng.next_u64() as u32 >> 2));
        for l in edges.into_iter().chain(random) {
            assert_eq!(reciprocal62(l), (1u64 << 62) / u64::from(l), "{l}");
        }
    }

    #[test]
    fn ratio16_is_within_its_bound() {
        let mut rng = crate::test_rng::XorShift64::new(0x1234_5678_9abc_def1u64);
        let mut next = || rng.next_u64();
        for _ in 0..200_000 {
            let n = next() >> (17 + next() % 40);
            let d = (next() >> (30 + next() % 34)).max(1);
            let exact = ((u128::from(n) << 16) / u128::from(d)) as f64;
            let got = ratio16(n, d) as f64;
            assert!(
                (got - exact).abs() <= exact * 2f64.powi(-25) + 1.0,
                "{n} / {d}: {got} vs {exact}"
            );
        }
    }

    #[test]
    fn sqrt_is_within_its_bound() {
        for x in [
            0.0,
            0.25,
            1.0,
            2.0,
            3.0,
            100.0,
            1234.5678,
            3.0 * 8192.0 * 8192.0,
        ] {
            let got = sqrt(I32F32::from_num(x)).to_num::<f64>();
            let want = f64::sqrt(x);
            assert!(
                (got - want).abs() <= want * 2f64.powi(-15) + 2f64.powi(-16),
                "{x}: {got}"
            );
        }
        assert_eq!(sqrt(I32F32::from_num(-4)), I16F16::ZERO);
    }

    #[test]
    fn normalized_has_unit_length() {
        for v in [
            [3.0, 4.0, 0.0],
            [0.01, -0.02, 0.03],
            [4000.0, -4000.0, 4000.0],
        ] {
            let n = Vec3 {
                x: I16F16::from_num(v[0]),
                y: I16F16::from_num(v[1]),
                z: I16F16::from_num(v[2]),
            }
            .normalized()
            .unwrap();
            let len = n.dot(n).to_num::<f64>().sqrt();
            assert!((len - 1.0).abs() < 1e-4, "{v:?}: {len}");
        }
        assert_eq!(Vec3::from_bits(1, 1, 1).normalized(), None);
    }
}
