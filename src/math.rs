//! Math backends and the integer helpers the fixed-point stages share.
//!
//! Floating point appears only in per-frame setup (camera and model matrices, a few dozen
//! operations per frame). That setup calls trigonometry and square roots through a
//! [`MathBackend`], a zero-sized type chosen at compile time: [`Libm`] (accurate, the default)
//! or [`Micromath`] (smaller and faster, a few ULP to ~0.1 % error). Everything per vertex,
//! per triangle and per pixel is integer arithmetic, so the same inputs give bit-identical
//! frames on every target.

/// Trigonometry and square root for per-frame setup, selected at compile time.
///
/// ```
/// use scanline3d::math::{Libm, MathBackend, Micromath};
/// assert!((Libm::sqrt(2.0) - 1.414_213_5).abs() < 1e-6);
/// assert!((Micromath::sqrt(2.0) - 1.414_213_5).abs() < 1e-2);
/// ```
pub trait MathBackend {
    /// The backend's name ("libm", "micromath").
    const NAME: &'static str;
    /// Sine of an angle in radians.
    fn sin(x: f32) -> f32;
    /// Cosine of an angle in radians.
    fn cos(x: f32) -> f32;
    /// Tangent of an angle in radians.
    fn tan(x: f32) -> f32;
    /// Square root; NaN for negative input.
    fn sqrt(x: f32) -> f32;
}

/// The `libm` crate: correctly rounded square root, sub-ULP trigonometry. The default backend.
#[derive(Clone, Copy, Debug, Default)]
pub struct Libm;

impl MathBackend for Libm {
    const NAME: &'static str = "libm";
    fn sin(x: f32) -> f32 {
        libm::sinf(x)
    }
    fn cos(x: f32) -> f32 {
        libm::cosf(x)
    }
    fn tan(x: f32) -> f32 {
        libm::tanf(x)
    }
    fn sqrt(x: f32) -> f32 {
        libm::sqrtf(x)
    }
}

/// The `micromath` crate: fast approximations (smaller code, lower accuracy).
///
/// micromath's square root alone is a bit-trick estimate up to ~6 % off, enough to visibly skew
/// a camera basis, so it is refined here with one Newton step (error below ~0.2 %).
#[derive(Clone, Copy, Debug, Default)]
pub struct Micromath;

impl MathBackend for Micromath {
    const NAME: &'static str = "micromath";
    fn sin(x: f32) -> f32 {
        micromath::F32Ext::sin(x)
    }
    fn cos(x: f32) -> f32 {
        micromath::F32Ext::cos(x)
    }
    fn tan(x: f32) -> f32 {
        micromath::F32Ext::tan(x)
    }
    fn sqrt(x: f32) -> f32 {
        let s = micromath::F32Ext::sqrt(x);
        if s > 0.0 {
            0.5 * (s + x / s)
        } else {
            s
        }
    }
}

/// The core has no 32 × 32 → 64-bit multiply (ARMv6-M, the Arm profile without 32-bit
/// atomics): every `i64` product is a call to `__aeabi_lmul` (about 45 instructions with the
/// call), so products whose operands are known to be narrow are written out in 32-bit
/// multiplies there. Elsewhere the `i64` product is one or two instructions.
pub(crate) const NO_WIDE_MULTIPLY: bool =
    cfg!(all(target_arch = "arm", not(target_has_atomic = "32")));

/// The core divides in software (ARMv6-M, as for [`NO_WIDE_MULTIPLY`]): the library's 32-bit
/// division is a call of about 100–140 instructions, so quotients that a comparison can find
/// are found that way there, and the others by [`div_rem_u32_soft`] or a [`SoftDivisor`]
/// (multiplies, no library call). Elsewhere (Cortex-M3/M4 `sdiv`, RV32 `M`, the host) a
/// division is one instruction.
pub(crate) const NO_HARDWARE_DIVIDE: bool =
    cfg!(all(target_arch = "arm", not(target_has_atomic = "32")));

/// Whether quotients start from a single-precision estimate: on Arm cores with a hardware FPU
/// (the `eabihf` targets, Cortex-M4F and the like), where a conversion, multiply or divide of
/// `f32` is one instruction. The integer corrections after the estimate make every result
/// exactly that of the integer forms, on every target.
pub(crate) const FLOAT_ESTIMATES: bool = cfg!(all(target_arch = "arm", target_abi = "eabihf"));

/// `⌊n / d⌋` for a quotient below 2^32 (`n < d·2^32`) from an `f32` estimate and one 32-bit
/// division of its remainder, or `None` where that remainder does not fit 32 bits (for `n` above
/// about 2^52 or `d` above about 2^29, for a quotient below 2, whose estimate taken down wraps, and
/// for `d = 0`): the caller then divides in integers. The estimate `q` errs relatively by less than
/// 2^-22 (the numerator's two words converted and summed, `d` converted, the quotient: each rounded
/// by 2^-24); taken down to `q0 = q − q/2^21 − 2`, below the exact quotient, its remainder
/// `n − q0·d` is non-negative and below `(⌊n/d⌋/2^20 + 4)·d`, and `q0 + ⌊remainder / d⌋` is the
/// quotient. Exact whatever the estimate gives: a `q0` above the quotient leaves a wrapped
/// remainder of at least 2^33 − 1, which the check turns away (test
/// `float_estimated_division_is_exact`).
#[inline]
pub(crate) fn div_below_float(n: u64, d: u32) -> Option<u32> {
    debug_assert!(
        ((n >> 32) as u32) < d,
        "quotient of {n} / {d} beyond 32 bits"
    );
    const TWO_TO_32: f32 = 4_294_967_296.0;
    let estimate = ((n >> 32) as u32 as f32 * TWO_TO_32 + n as u32 as f32) / d as f32;
    let q0 = estimate as u32; // (saturating; 0 for a NaN)
    let q0 = q0.wrapping_sub(q0 >> 21).wrapping_sub(2);
    let remainder = n.wrapping_sub(u64::from(q0) * u64::from(d));
    let remainder = u32::try_from(remainder).ok()?;
    Some(q0.wrapping_add(remainder.checked_div(d)?))
}

/// `(n / d, n % d)` for 32-bit operands (`d = 0` is taken as 1) from multiplies, for cores
/// without a divider ([`NO_HARDWARE_DIVIDE`]; on every target, tested on the host too): `n < d` by one
/// comparison, quotients 1 and 2 by subtraction, else by a [`SoftDivisor`].
#[inline]
pub(crate) fn div_rem_u32_soft(n: u32, d: u32) -> (u32, u32) {
    if n < d {
        return (0, n);
    }
    // Quotients 1 and 2 (shallow edges' slopes) by subtraction.
    let r = n - d;
    if r < d {
        return (1, r);
    }
    let r2 = r - d;
    if r2 < d {
        return (2, r2);
    }
    SoftDivisor::new(d).div_rem(n)
}

/// A 32-bit divisor `d >= 1` prepared for exact division by multiplies, for cores without a
/// divider ([`NO_HARDWARE_DIVIDE`], where `compiler_builtins`' `u32_div_rem` takes about
/// 35 instructions to normalise and 4–5 a quotient bit, 100–140 a call on the renderer's
/// divisions).
///
/// Preparing: `d` is normalised by five comparisons (`D = d·2^s`, top bit set; no `clz` call),
/// and its top half `Dh = ⌊D / 2^16⌋` (in `[2^15, 2^16)`) gives `a = Dh + 1` and a 16-bit
/// reciprocal `R <= 2^31 / a` ([`reciprocal16`], within a few units of it). Since
/// `D < a·2^16`, `d < a·2^(16−s)`.
///
/// Dividing: each pass estimates the quotient of the remainder `r` (at first `n`) as
/// `e = ⌊⌊r·R / 2^16⌋ / 2^(31−s)⌋` (the product from 16-bit halves), and since
/// `r·R / 2^(47−s) <= r / (a·2^(16−s)) < r / d`, `e·d < r`: the remainder `r − e·d` never
/// wraps and the quotient never overshoots. A pass with `e = 0` (only when `r < 2d`) takes 1.
/// Each pass leaves about `2^-13` of the quotient (the relative errors of `R`, of `a` and of
/// the truncations) plus two, so a 16-bit quotient takes two or three passes, a 32-bit one
/// four. The loop ends when `r < d`: then the sum of the estimates is `⌊n / d⌋` and `r`
/// is `n mod d`, whatever the estimates' quality. Test `soft_division_is_exact`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SoftDivisor {
    d: u32,
    /// `R`, in `[2^15, 2^16)`.
    recip: u32,
    /// `31 − s`.
    shift: u32,
}

impl SoftDivisor {
    /// The divisor `d` (`0` is taken as 1).
    #[inline]
    pub(crate) fn new(d: u32) -> Self {
        let d = d.max(1);
        let (norm, s) = normalize(d);
        SoftDivisor {
            d,
            recip: reciprocal16((norm >> 16) + 1),
            shift: 31 - s,
        }
    }

    /// `(n / d, n % d)`.
    #[inline]
    pub(crate) fn div_rem(&self, n: u32) -> (u32, u32) {
        let (d, recip) = (self.d, self.recip);
        let (mut q, mut r) = (0u32, n);
        while r >= d {
            // ⌊r·R / 2^16⌋ or one less: (2^16 − 1)·R + ((2^16 − 1)·R >> 16) < 2^32.
            let p = (r >> 16) * recip + (((r & 0xFFFF) * recip) >> 16);
            let e = (p >> (self.shift & 31)).max(1);
            q = q.wrapping_add(e);
            r = r.wrapping_sub(e.wrapping_mul(d));
        }
        (q, r)
    }
}

/// `(d·2^s, s)` with the top bit of `d·2^s` set, for `d >= 1` (`d = 0` gives `(0, 31)`), by
/// halving the range five times: inline comparisons, where `leading_zeros` is a call of
/// `__clzsi2` on ARMv6-M.
#[inline]
const fn normalize(d: u32) -> (u32, u32) {
    let (mut x, mut s) = (d, 0);
    if x >> 16 == 0 {
        x <<= 16;
        s = 16;
    }
    if x >> 24 == 0 {
        x <<= 8;
        s += 8;
    }
    if x >> 28 == 0 {
        x <<= 4;
        s += 4;
    }
    if x >> 30 == 0 {
        x <<= 2;
        s += 2;
    }
    if x >> 31 == 0 {
        x <<= 1;
        s += 1;
    }
    (x, s)
}

/// `R <= 2^31 / a` within a few units (in `[2^15, 2^16)`) for `a` in `(2^15, 2^16]`, without a
/// table or a division: the line `x0 = 92,521 − ⌊a·61,681 / 2^16⌋` (`2^15·(48 − 32·t) / 17`
/// for `t = a / 2^16`, the minimax line for `1 / t` on `[1/2, 1]`, within `1/17`), then two
/// Newton steps `x ← x + x·(2^31 − a·x) / 2^31`. A Newton step for `1/a` never lands above it
/// (`x·(2 − a·x) = 1/a − a·(x − 1/a)²`) and every truncation here rounds down, so each step
/// ends at or below `2^31 / a`, the relative error squared: `2^-4.1`, `2^-8.2`, `2^-16.4`.
/// Bits: `a·x0 < 2^31·(1 + 1/17)`, so the first error `2^31 − a·x0` is within `±2^27` and
/// `x0·(e >> 12)` within `±2^31`; the second error is below `2^23`, so `x1·(e >> 7) < 2^32`.
/// Test `reciprocal16_is_close_below`, over every `a`.
#[inline]
fn reciprocal16(a: u32) -> u32 {
    let x0 = 92_521 - ((a * 61_681) >> 16);
    let e0 = (1u32 << 31).wrapping_sub(a.wrapping_mul(x0)) as i32;
    let x1 = (x0 as i32 + ((x0 as i32).wrapping_mul(e0 >> 12) >> 19)) as u32;
    let e1 = (1u32 << 31).wrapping_sub(a.wrapping_mul(x1));
    x1 + ((x1.wrapping_mul(e1 >> 7)) >> 24)
}

/// `a · b` as `i64`: on cores without a wide multiply ([`NO_WIDE_MULTIPLY`]) from four
/// 32-bit multiplies of 16-bit halves, elsewhere the `i64` multiply (one instruction). The
/// same value either way (test `narrow_products_are_exact`).
#[inline]
pub(crate) fn mul_wide(a: i32, b: i32) -> i64 {
    if NO_WIDE_MULTIPLY {
        mul_wide_in_halves(a, b)
    } else {
        a as i64 * b as i64
    }
}

/// [`mul_wide`] from 32-bit multiplies, on every target (tested on the host too). With
/// `a = ah·2^16 + al` (`ah` signed, `al` in `[0, 2^16)`) and `b` alike, `a·b = ah·bh·2^32 +
/// (ah·bl + al·bh)·2^16 + al·bl`; each of the four products fits 32 bits.
#[inline]
fn mul_wide_in_halves(a: i32, b: i32) -> i64 {
    let (ah, al) = (a >> 16, a & 0xFFFF);
    let (bh, bl) = (b >> 16, b & 0xFFFF);
    let cross = (ah * bl) as i64 + (al * bh) as i64;
    let low = (al as u32 * bl as u32) as i64;
    (((ah * bh) as i64) << 32) + (cross << 16) + low
}

/// `a · b` for two `i64` whose product does not overflow: on cores without a wide multiply
/// ([`NO_WIDE_MULTIPLY`]) [`mul_wide`] when both fit 32 bits (the `i64` multiply is a call
/// there), elsewhere the `i64` multiply. The same value either way (test
/// `narrow_products_are_exact`).
#[inline]
pub(crate) fn mul_i64(a: i64, b: i64) -> i64 {
    match i32::try_from(b) {
        Ok(b) if NO_WIDE_MULTIPLY => mul_i64_i32(a, b),
        _ => a * b,
    }
}

/// `a · b` for an `a` that fits `i64` times `b`, where the product does not overflow: on
/// cores without a wide multiply ([`NO_WIDE_MULTIPLY`]) [`mul_wide`] when `a` fits 32 bits
/// (the `i64` multiply is a call there), elsewhere the `i64` multiply. The same value either
/// way (test `narrow_products_are_exact`).
#[inline]
pub(crate) fn mul_i64_i32(a: i64, b: i32) -> i64 {
    match i32::try_from(a) {
        Ok(a) if NO_WIDE_MULTIPLY => mul_wide(a, b),
        _ => a * b as i64,
    }
}

/// The low word of `v >> s` (arithmetic, `s < 64`), as `(v >> s) as i32`: on cores without a
/// wide multiply ([`NO_WIDE_MULTIPLY`], whose 64-bit shifts by a variable amount are calls)
/// from the two 32-bit words of `v`, elsewhere the 64-bit shift. The same bits either way (test
/// `shifts_in_words_are_exact`).
#[inline]
pub(crate) fn shr_low_word(v: i64, s: u32) -> i32 {
    if NO_WIDE_MULTIPLY {
        shr_low_word_in_words(v, s)
    } else {
        (v >> (s & 63)) as i32
    }
}

/// [`shr_low_word`] in 32-bit shifts, on every target (tested on the host too).
#[inline]
fn shr_low_word_in_words(v: i64, s: u32) -> i32 {
    let (hi, lo) = ((v >> 32) as i32, v as u32);
    let s = s & 63;
    if s >= 32 {
        hi >> (s - 32)
    } else if s == 0 {
        lo as i32
    } else {
        (lo >> s | (hi as u32) << (32 - s)) as i32
    }
}

/// `v >> s` (arithmetic, `s < 64`): on cores without a wide multiply ([`NO_WIDE_MULTIPLY`])
/// from the two 32-bit words of `v`, elsewhere the 64-bit shift. The same value either way
/// (test `shifts_in_words_are_exact`).
#[inline]
pub(crate) fn shr_i64(v: i64, s: u32) -> i64 {
    if NO_WIDE_MULTIPLY {
        shr_i64_in_words(v, s)
    } else {
        v >> (s & 63)
    }
}

/// `v >> s` for `32 <= s < 64`: the high word's shift alone (test
/// `shifts_in_words_are_exact`).
#[inline]
pub(crate) fn shr_i64_high(v: i64, s: u32) -> i64 {
    debug_assert!((32..64).contains(&s), "shr_i64_high by {s}");
    ((v >> 32) as i32 >> (s & 31)) as i64
}

/// [`shr_i64`] in 32-bit shifts, on every target (tested on the host too).
#[inline]
fn shr_i64_in_words(v: i64, s: u32) -> i64 {
    let s = s & 63;
    let hi = (v >> 32) as i32;
    let hi = if s >= 32 { hi >> 31 } else { hi >> s };
    ((hi as i64) << 32) | shr_low_word_in_words(v, s) as u32 as i64
}

/// `v >> s` (logical, `s < 64`): as [`shr_i64`], from the two 32-bit words of `v` on cores
/// without a wide multiply, elsewhere the 64-bit shift. The same value either way (test
/// `shifts_in_words_are_exact`).
#[inline]
pub(crate) fn shr_u64(v: u64, s: u32) -> u64 {
    if NO_WIDE_MULTIPLY {
        shr_u64_in_words(v, s)
    } else {
        v >> (s & 63)
    }
}

/// [`shr_u64`] in 32-bit shifts, on every target (tested on the host too).
#[inline]
fn shr_u64_in_words(v: u64, s: u32) -> u64 {
    let (hi, lo) = ((v >> 32) as u32, v as u32);
    let s = s & 63;
    let (hi, lo) = if s >= 32 {
        (0, hi >> (s - 32))
    } else if s == 0 {
        (hi, lo)
    } else {
        (hi >> s, lo >> s | hi << (32 - s))
    };
    (u64::from(hi) << 32) | u64::from(lo)
}

/// Cosine of the angle between an integer vector `v` of any scale and a unit vector `unit`
/// (I2F30 bits), in I2F30 bits truncated towards zero; `None` for the zero vector.
///
/// One square root and one division: `v · unit / |v|`, with `v` first scaled so that its
/// largest component has 30 bits, which keeps `|v|²` below `3 · 2^60` (fits `u64`) and every
/// truncation (of `v`, of the root, of the quotient) within a few 2^-30. Integer only (exact `isqrt`), so lighting is identical on
/// every target.
pub(crate) fn cosine_i64(v: [i64; 3], unit: [i32; 3]) -> Option<i32> {
    // |s_i| <= 2^30: each fits `i32`, so the products below are 32 × 32 → 64 bits.
    let s = fit_bits(v, 30)?;
    let len = isqrt_u64(s.iter().map(|&c| mul_wide(c, c) as u64).sum());
    if len == 0 {
        return None;
    }
    // |s_i · unit_i| < 2^60 and, by Cauchy–Schwarz, every partial sum is at most
    // |s| · |unit| < 2^61: no overflow, and the quotient is within about ±2^30.
    let dot: i64 = (0..3).map(|k| mul_wide(s[k], unit[k])).sum();
    // `len <= sqrt(3) · 2^30` fits 32 bits and is non-zero here.
    let q = div_rem_u64_u32(dot.unsigned_abs(), len as u32).0 as i32;
    Some(if dot < 0 { -q } else { q })
}

/// The Lambert term `max(0, cos)` of a normal and a unit light direction: bounds `lo <= hi`
/// on it, cheap to compute, and what [`Lambert::exact`] needs to give the term itself from the
/// same values (no second scaling of the normal). Made by [`NormalPrecision::lambert`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Lambert {
    /// Lower bound on the term (I2F30 bits).
    pub lo: i32,
    /// Upper bound on the term (I2F30 bits); equal to `lo` when that is the term.
    pub hi: i32,
    /// The positive dot product of the 30-bit normal and the direction (0 if `lo == hi`).
    dot: u64,
    /// The 30-bit normal's squared length (0 if `lo == hi`).
    square: u64,
}

impl Lambert {
    /// Bounds that are the exact term.
    #[inline]
    fn exactly(term: i32) -> Lambert {
        Lambert {
            lo: term,
            hi: term,
            dot: 0,
            square: 0,
        }
    }

    /// The term between the bounds: `lo` when the bounds are equal, else `⌊dot / ⌊√square⌋⌋`,
    /// which is `cosine_i64`'s quotient for a positive dot product (its root and division
    /// of the same 30-bit vector). Test `lambert_bounds_hold`.
    #[inline]
    pub fn exact(&self) -> i32 {
        if self.lo == self.hi {
            return self.lo;
        }
        // square >= 2^58 (the largest component has 30 bits), so the root is at least 2^29
        // and below sqrt(3)·2^30: it fits 32 bits and is non-zero.
        let len = isqrt_u64(self.square);
        div_rem_u64_u32(self.dot, len as u32).0 as i32
    }
}

/// [`Lambert`] bounds on `cosine_i64(v, unit).max(0)`, without its 64-bit square root and
/// division: `None` for the zero vector, exactly `0` when the dot product is not positive
/// (the cosine is then at most 0), else an interval about `2^-14` of the cosine wide. Lighting
/// uses it to skip the exact cosine when both ends give one colour.
///
/// Why the bounds hold, with `s` the 30-bit vector, `S = |s|² >= 2^58`, `R = ⌊√S⌋`, the dot
/// product `D` in `(0, 2^61)` and the exact result `q = ⌊D / R⌋`: for `S' = ⌊S / 2^30⌋`
/// (at least 2^28, below 2^32) and `r = ⌊√S'⌋` (at least 2^14), `r·2^15 <= R < (r+1)·2^15`.
/// With `Dh = ⌊D / 2^29⌋` (below 2^32) and `A = ⌊Dh / r⌋`: `q < (Dh+1)·2^14 / r <
/// (A + 1)·2^14 + 2^14 / r`, so `q <= (A+1)·2^14`; and `q >= ⌊Dh·2^14 / (r+1)⌋`, where
/// `Dh·2^14 / (r+1) = (Dh / r)·2^14 − (Dh / r)·2^14 / (r+1) > A·2^14 − (A+1)`.
/// `A < 2^32 / 2^14 = 2^18`, so `A·2^14` fits `u32`, and the bounds are taken there
/// (`(A+1)·2^14` saturating, both then capped at `i32::MAX`).
/// Test `lambert_bounds_hold`.
pub(crate) fn lambert_i64(v: [i64; 3], unit: [i32; 3]) -> Option<Lambert> {
    Some(lambert_of_fitted(fit_bits(v, 30)?, unit))
}

/// [`lambert_i64`] of a vector already fitted to 30 bits: `lambert_i64(v, unit)` is
/// `Some(lambert_of_fitted(fit_bits(v, 30)?, unit))`.
#[inline]
fn lambert_of_fitted(s: [i32; 3], unit: [i32; 3]) -> Lambert {
    let dot = mul_wide(s[0], unit[0]) + mul_wide(s[1], unit[1]) + mul_wide(s[2], unit[2]);
    if dot <= 0 {
        return Lambert::exactly(0);
    }
    let square: u64 = s.iter().map(|&c| mul_wide(c, c) as u64).sum();
    // S < 3·2^60, so S' < 3·2^30; r >= 2^14 (S >= 2^58).
    let (square_high, dot_high) = ((square >> 30) as u32, (dot >> 29) as u32);
    let a = if NO_HARDWARE_DIVIDE {
        match root_and_quotient(square_high, dot_high) {
            Some((_, a)) => a,
            // Not met by any tested input (S' >= 2^28 here). Bounds that hold whatever the
            // term: the caller takes the exact one.
            None => {
                return Lambert {
                    lo: 0,
                    hi: i32::MAX,
                    dot: dot as u64,
                    square,
                }
            }
        }
    } else {
        dot_high / isqrt32(square_high).max(1)
    };
    let lo = (a << 14).saturating_sub(a + 1);
    let hi = (a + 1).saturating_mul(1 << 14);
    Lambert {
        lo: lo.min(i32::MAX as u32) as i32,
        hi: hi.min(i32::MAX as u32) as i32,
        dot: dot as u64,
        square,
    }
}

/// `(⌊√x⌋, ⌊n / ⌊√x⌋⌋)` for `x` in `[2^28, 2^32)` from 32-bit multiplies alone, for cores
/// without a divider: on ARMv6-M, in the Lambert bounds of every lit face, about 200
/// instructions fewer than [`isqrt32_bitwise`] and the soft division (corpus heightfield,
/// `docs/speed.md` item 26).
///
/// An estimate `g ≈ 2^31 / √x4` of the reciprocal root of `x4 = x·4^e` in `[2^30, 2^32)` (a
/// line on each half of the range, two Newton steps `g ← g·(3 − u·g²/2^46)/2` on `u = x4 /
/// 2^16`) gives `√x4 ≈ u·g / 2^15`; one Newton step on the residual `x4 − s²` brings that
/// within a unit or two, and the quotient is estimated from `g` and corrected by its remainder
/// alike. Both are then checked exactly (`r² ≤ x < (r+1)²`, `0 ≤ n − a·r < r`) after at most
/// three unit steps each; `None` if either is not reached (never, in the tests: every `x` in
/// range, random numerators), so a result is always exact. Tests `root_and_quotient_are_exact`
/// and, over every `x`, `root_and_quotient_exhaustively`.
#[inline]
pub(crate) fn root_and_quotient(x: u32, n: u32) -> Option<(u32, u32)> {
    if x < 1 << 28 {
        return None;
    }
    let e = u32::from(x < 1 << 30); // x4 = x · 4^e, and ⌊√x⌋ = ⌊⌊√x4⌋ / 2^e⌋
    let x4 = x << (2 * e);
    // u in [2^14, 2^16); g ≈ 2^23 / √u, in (2^15, 2^16]: each half's chord lowered by half its
    // largest gap.
    let u = x4 >> 16;
    let mut g = if u >= 1 << 15 {
        58_895 - ((u * 27_148) >> 16)
    } else {
        83_288 - ((u * 76_781) >> 16)
    };
    for _ in 0..2 {
        // g < 2^16: g² fits; u·(g²/2^16) ≈ 2^30; g·(c/2^16) ≤ 2^16·3·2^14.
        let t = (g * g) >> 16;
        let c = (3u32 << 30).wrapping_sub(u.wrapping_mul(t));
        g = (g.wrapping_mul(c >> 16) >> 15).min(65_535);
    }
    // s ≈ √x4 (u·g < 2^32), then s + (x4 − s²)/(2s) with 1/(2s) ≈ g / 2^32.
    let s = (u * g) >> 15;
    let residual = x4.wrapping_sub(s.wrapping_mul(s)) as i32;
    let mut r4 = s.wrapping_add_signed((residual >> 6).wrapping_mul(g as i32) >> 26);
    // ⌊√x4⌋ < 2^16: r4² fits, and x4 − r4² ≤ 2·r4 says (r4 + 1)² > x4.
    let mut steps = 0;
    while r4 > 65_535 || r4.wrapping_mul(r4) > x4 {
        r4 = r4.wrapping_sub(1);
        steps += 1;
        if steps > 3 {
            return None;
        }
    }
    while x4 - r4 * r4 > 2 * r4 {
        // (Below 2^16: x4 − 65,535² ≤ 2·65,535 ends the loop there.)
        r4 += 1;
        steps += 1;
        if steps > 3 {
            return None;
        }
    }
    let r = r4 >> e;
    // n / r ≈ n·g·2^e / 2^31 (r ≥ 2^14, so the quotient is below 2^18), then by the remainder.
    let a = ((n >> 16) * g) >> (15 - e);
    let rem = n.wrapping_sub(a.wrapping_mul(r)) as i32;
    let mut a = a.wrapping_add_signed((rem >> 8).wrapping_mul(g as i32) >> (23 - e));
    let mut rem = n.wrapping_sub(a.wrapping_mul(r)) as i32;
    let mut steps = 0;
    while rem < 0 || rem as u32 >= r {
        if rem < 0 {
            a = a.wrapping_sub(1);
            rem = rem.wrapping_add(r as i32);
        } else {
            a += 1;
            rem -= r as i32;
        }
        steps += 1;
        if steps > 3 {
            return None;
        }
    }
    Some((r, a))
}

/// `n.div_euclid(d)` (the floor of `n / d`) for `d >= 1` (`d < 1` is taken as 1), through
/// [`div_rem_u64_u32`] when `d` fits 32 bits.
#[inline]
pub(crate) fn floor_div_i64(n: i64, d: i64) -> i64 {
    let d = d.max(1);
    match u32::try_from(d) {
        Ok(d32) => {
            let (q, r) = div_rem_u64_u32(n.unsigned_abs(), d32);
            // |n| <= 2^63 and d >= 1: the quotient of a negative n fits i64 when negated.
            let q = q as i64;
            if n >= 0 {
                q
            } else {
                q.wrapping_neg() - (r != 0) as i64
            }
        }
        Err(_) => n.div_euclid(d),
    }
}

/// `(n / d, n % d)` for a 64-bit `n` and a 32-bit `d >= 1`, exactly as `u64` division, from
/// 32-bit divisions only (Hacker's Delight `divlu`: two 16-bit quotient digits, each estimated
/// from the normalized divisor's top half and corrected at most twice). Cores with a 32-bit
/// divider (Cortex-M3/M4, RV32IM) have none for 64 bits, and `compiler_builtins` builds the
/// 64-bit division from a software 32-bit one: this is several times cheaper there. On cores
/// without any divider (Cortex-M0) its 32-bit divisions are [`div_rem_u32_soft`] and
/// those of [`div_rem_below_with`]'s soft path. A 64-bit core divides natively: the same value.
#[inline]
pub(crate) fn div_rem_u64_u32(n: u64, d: u32) -> (u64, u32) {
    if cfg!(target_pointer_width = "64") {
        let d = u64::from(d.max(1));
        (n / d, (n % d) as u32)
    } else {
        div_rem_u64_u32_in_halves(n, d)
    }
}

/// [`div_rem_u64_u32`] from 32-bit divisions, on every target (tested on the host too).
#[inline]
fn div_rem_u64_u32_in_halves(n: u64, d: u32) -> (u64, u32) {
    let d = d.max(1);
    let (hi, lo) = ((n >> 32) as u32, n as u32);
    // A quotient below 2^32 (a numerator whose high word is below `d`) needs no high step.
    let (q_hi, r_hi) = if hi < d {
        (0, hi)
    } else if NO_HARDWARE_DIVIDE {
        div_rem_u32_soft(hi, d)
    } else {
        (hi / d, hi % d)
    };
    let (q_lo, r) = div_rem_below(r_hi, lo, d);
    (((q_hi as u64) << 32) | q_lo as u64, r)
}

/// `(u1·2^32 + u0) / v` and its remainder for `u1 < v` (so the quotient fits 32 bits).
#[inline]
pub(crate) fn div_rem_below(u1: u32, u0: u32, v: u32) -> (u32, u32) {
    if cfg!(target_pointer_width = "64") {
        // A 64-bit core divides natively: one instruction, the same quotient and remainder.
        let (n, v) = ((u64::from(u1) << 32) | u64::from(u0), u64::from(v.max(1)));
        return ((n / v) as u32, (n % v) as u32);
    }
    div_rem_below_with::<NO_HARDWARE_DIVIDE>(u1, u0, v)
}

/// [`div_rem_below`]'s steps (Knuth, Algorithm D, two 16-bit digits), on every target with
/// either `SOFT` (tested on the host too). With `SOFT` (the core without a divider): [`div_rem_u32_soft`] for a numerator below 2^32, the normalisation by
/// [`normalize`] (no `__clzsi2` call), and each digit's first estimate `⌊top / vn1⌋` from one
/// [`SoftDivisor`] shared by the two digits; else the division instruction and
/// `leading_zeros`. Always inlined: out of line (one copy for `Divisor32::new`'s normalised
/// divisors and for the others) the demo frame on thumbv6m took 2 % more.
#[inline(always)]
fn div_rem_below_with<const SOFT: bool>(u1: u32, u0: u32, v: u32) -> (u32, u32) {
    const B: u32 = 1 << 16;
    if u1 == 0 {
        // The common case (numerator below 2^32): one division.
        if SOFT {
            return div_rem_u32_soft(u0, v);
        }
        let v = v.max(1);
        return (u0 / v, u0 % v);
    }
    // Normalize: the divisor's top bit set (u1 < v, so v > 0 and the shift is below 32).
    let (v, s) = if SOFT {
        normalize(v)
    } else {
        let s = v.leading_zeros();
        (v << s, s)
    };
    // `v`'s top bit is set, so `vn1 >= 2^15` already: or-ing that bit in changes nothing but
    // lets the compiler see it is not zero (no division-by-zero panic path: the panic-never
    // link check).
    let (vn1, vn0) = ((v >> 16) | 0x8000, v & 0xFFFF);
    let un32 = (u1 << s) | if s == 0 { 0 } else { u0 >> (32 - s) };
    let un10 = u0 << s;
    let (un1, un0) = (un10 >> 16, un10 & 0xFFFF);
    let by = SoftDivisor::new(vn1);
    // One 16-bit digit of the quotient of `top·2^16 + next` (`top < v`): the estimate from
    // `vn1 >= 2^15` is at most two too large.
    let digit = |top: u32, next: u32| {
        // (`checked_div`: where this closure is left out of line, as with `opt-level = "z"`,
        // the compiler no longer sees `vn1 >= 2^15`.)
        let mut q = if SOFT {
            by.div_rem(top).0
        } else {
            top.checked_div(vn1).unwrap_or(0)
        };
        let mut rhat = top - q * vn1;
        while q >= B || q * vn0 > (rhat << 16 | next) {
            q -= 1;
            rhat += vn1;
            if rhat >= B {
                break;
            }
        }
        q
    };
    let q1 = digit(un32, un1);
    let un21 = (un32 << 16 | un1).wrapping_sub(q1.wrapping_mul(v));
    let q0 = digit(un21, un0);
    let r = (un21 << 16 | un0).wrapping_sub(q0.wrapping_mul(v)) >> s;
    (q1 << 16 | q0, r)
}

/// `a · b` for unsigned 32-bit factors: on cores without a wide multiply
/// ([`NO_WIDE_MULTIPLY`]) from four 32-bit multiplies of 16-bit halves, elsewhere the `u64`
/// multiply (`umull`). The same value either way (test `narrow_products_are_exact`).
#[inline]
pub(crate) fn mul_wide_u32(a: u32, b: u32) -> u64 {
    if NO_WIDE_MULTIPLY {
        mul_wide_u32_in_halves(a, b)
    } else {
        a as u64 * b as u64
    }
}

/// [`mul_wide_u32`] from 32-bit multiplies, on every target (tested on the host too):
/// `a·b = ah·bh·2^32 + (ah·bl + al·bh)·2^16 + al·bl`, each product of 16-bit halves.
#[inline]
fn mul_wide_u32_in_halves(a: u32, b: u32) -> u64 {
    let (ah, al) = (a >> 16, a & 0xFFFF);
    let (bh, bl) = (b >> 16, b & 0xFFFF);
    let cross = (ah * bl) as u64 + (al * bh) as u64;
    (((ah * bh) as u64) << 32) + (cross << 16) + (al * bl) as u64
}

/// `a · b` for a signed and an unsigned 32-bit factor, exactly `a as i64 * b as i64`, from four
/// 32-bit multiplies of 16-bit halves (`a`'s high half signed; `al·bh` and `al·bl` unsigned):
/// for ARMv6-M, where the `i64` multiply is a call (tests `wide_is_the_i64_product` in
/// `trace::vector`, `mul_in_words_is_mul` in `metaball`).
#[inline]
pub const fn wide_by_unsigned(a: i32, b: u32) -> i64 {
    let (ah, al) = (a >> 16, (a & 0xFFFF) as u32);
    let (bh, bl) = (b >> 16, b & 0xFFFF);
    let cross = (ah * bl as i32) as i64 + (al * bh) as i64;
    (((ah * bh as i32) as i64) << 32) + (cross << 16) + (al * bl) as i64
}

/// A 32-bit divisor `D >= 1` prepared for several divisions: one reciprocal, then every
/// quotient from multiplies and at most two corrections, exactly `u64` division's quotient and
/// remainder ([`div_rem_u64_u32`]'s). On cores without a divider (Cortex-M0) the reciprocal is
/// the two digits of [`div_rem_below_with`]'s soft path, by multiplies.
///
/// The step is Möller and Granlund's (“Improved division by invariant integers”, 2011,
/// Algorithm 4). Why it is exact, with `β = 2^32`, `d = D·2^s` normalized (`β/2 <= d < β`),
/// `ν = ⌊(β² − 1) / d⌋ = β + v` (`0 <= v < β`) and `U = u1·β + u0` with `u1 < d`:
///
/// - `ν·d <= β² − 1 < ν·d + d`, so `k = β² − ν·d` lies in `[1, d]`; and `ν·u1 + u0 < β²`
///   (as `ν·u1 <= (β² − 1)(d − 1) / d < β² − β`), so it is two words `q1·β + q0`.
/// - The candidate `q̃ = q1 + 1` has the remainder `r̃ = U − q̃·d`, and substituting
///   `q1·β = ν·u1 + u0 − q0` gives `β·r̃ = u1·k + u0·(β − d) + (q0 − β)·d`.
/// - Below: `β·r̃ >= (q0 − β)·d >= −β·d`, so `r̃ >= −d`; and `r̃ = q0 − β` would need
///   `(q0 − β)(β − d) = u1·k + u0·(β − d) >= 0`, whose left side is negative: `r̃ > q0 − β`.
/// - Above: `β·r̃ <= (d − 1)·d + (β − 1)(β − d) + (q0 − β)·d < (β − d)² + q0·d <= M·β`
///   with `M = max(β − d, q0) < β`: `r̃ < M`.
///
/// Only `r = r̃ mod β` is computed (32-bit wrapping, as is `q̃`: the final quotient is below `β`,
/// so its value mod `β` is the value). If `r̃ < 0`, then `r = r̃ + β > q0`: the first
/// correction (`q̃ − 1`, `r + d`) applies and leaves `r̃ + d` in `[0, d)`, the second does not.
/// If `0 <= r̃ <= q0`, the first does not apply and `r̃ < M < β <= 2d`: the second (`q̃ + 1`,
/// `r − d`) applies exactly when `r̃ >= d`. If `r̃ > q0 >= 0`, then `M = β − d`, so
/// `r̃ < β − d <= d`; the first gives `r̃ + d` in `[d, β)` (no wrap) and the second undoes it.
/// In every case the result is `⌊U / d⌋` and `U mod d`.
///
/// A 64-bit `n` is divided as `n·2^s = n2·β² + n1·β + n0` (`n2 < 2^s <= β/2 <= d`): one step for
/// the quotient's high word, one for its low word; `n mod D` is the last remainder `/ 2^s`.
/// Test `reciprocal_division_is_exact`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Divisor32 {
    /// `D·2^shift`, top bit set.
    d: u32,
    /// `⌊(2^64 − 1) / d⌋ − 2^32`.
    v: u32,
    shift: u32,
}

impl Divisor32 {
    /// The divisor `d` (`0` is taken as 1).
    #[inline]
    pub(crate) fn new(d: u32) -> Self {
        let d = d.max(1);
        if NO_HARDWARE_DIVIDE {
            // Normalised by comparisons; the top bit, set, or-ed in to tell the compiler so
            // (`div_rem_below`'s own normalisation then folds away).
            let (d, shift) = normalize(d);
            let d = d | 1 << 31;
            let v = div_rem_below(!d, u32::MAX, d).0;
            return Divisor32 { d, v, shift };
        }
        let shift = d.leading_zeros();
        let d = d << shift;
        // ν − β = ⌊((β − 1 − d)·β + β − 1) / d⌋, a quotient below β (β − 1 − d < d).
        let v = if cfg!(target_pointer_width = "64") {
            (u64::MAX / d as u64) as u32
        } else {
            div_rem_below(!d, u32::MAX, d).0
        };
        Divisor32 { d, v, shift }
    }

    /// `(⌊(u1·2^32 + u0) / d⌋, remainder)` for `u1 < d` (the normalized divisor).
    #[inline]
    fn step(&self, u1: u32, u0: u32) -> (u32, u32) {
        let p = mul_wide_u32(self.v, u1) + (((u1 as u64) << 32) | u0 as u64);
        let (q1, q0) = ((p >> 32) as u32, p as u32);
        let mut q = q1.wrapping_add(1);
        let mut r = u0.wrapping_sub(q.wrapping_mul(self.d));
        if r > q0 {
            q = q.wrapping_sub(1);
            r = r.wrapping_add(self.d);
        }
        if r >= self.d {
            q = q.wrapping_add(1);
            r -= self.d;
        }
        (q, r)
    }

    /// `(n / D, n % D)`, as [`div_rem_u64_u32`]`(n, D)`.
    #[inline]
    pub(crate) fn div_rem(&self, n: u64) -> (u64, u32) {
        let s = self.shift;
        let (hi, lo) = ((n >> 32) as u32, n as u32);
        // n·2^s in three words (32-bit shifts: a 64-bit shift is a call on ARMv6-M).
        let (n2, n1) = if s == 0 {
            (0, hi)
        } else {
            (hi >> (32 - s), hi << s | lo >> (32 - s))
        };
        // A quotient that fits 32 bits (the usual case) needs only the second step.
        let (q_hi, r1) = if n2 == 0 && n1 < self.d {
            (0, n1)
        } else {
            self.step(n2, n1)
        };
        let (q_lo, r) = self.step(r1, lo << s);
        (((q_hi as u64) << 32) | q_lo as u64, r >> s)
    }

    /// `n.div_euclid(D)`, as [`floor_div_i64`]`(n, D)`.
    #[inline]
    pub(crate) fn floor_div(&self, n: i64) -> i64 {
        let (q, r) = self.div_rem(n.unsigned_abs());
        // As in `floor_div_i64`: the quotient of a negative n fits i64 when negated.
        let q = q as i64;
        if n >= 0 {
            q
        } else {
            q.wrapping_neg() - (r != 0) as i64
        }
    }
}

/// ⌊√v⌋ for a 32-bit integer: the double-precision square root where the core has one (x86
/// with SSE2, AArch64: one instruction where Newton's steps take four divisions), else
/// [`isqrt32_newton`] where the target divides 32-bit integers in hardware (Cortex-M3/M4
/// `udiv`, RV32 `M`), [`isqrt32_bitwise`] on ARMv6-M, whose division is a library call. All are
/// exact, so every target gets the same bits: an integer below 2^32 is exact in `f64`, and
/// where it is not a square its root lies at least 2^-17 below the next integer, far more
/// than the correctly rounded root's error (below 2^-36), so the root floors to ⌊√v⌋.
#[inline]
pub fn isqrt32(v: u32) -> u32 {
    if cfg!(any(target_feature = "sse2", target_arch = "aarch64")) {
        libm::sqrt(f64::from(v)) as u32
    } else if cfg!(all(target_arch = "arm", not(target_has_atomic = "32"))) {
        // ARMv6-M is the Arm profile without 32-bit atomics (and without a divider).
        isqrt32_bitwise(v)
    } else {
        isqrt32_newton(v)
    }
}

/// ⌊√v⌋ bit by bit (one step per result bit, no division), starting at `v`'s highest bit.
#[inline]
pub const fn isqrt32_bitwise(v: u32) -> u32 {
    if v == 0 {
        return 0;
    }
    let mut rem = v;
    let mut root = 0u32;
    // The highest power of 4 not above v.
    // (`normalize`'s comparisons: `leading_zeros` is a call on ARMv6-M, the core this serves.)
    let mut bit = 1u32 << ((31 - normalize(v).1) & !1);
    while bit != 0 {
        if rem >= root + bit {
            rem -= root + bit;
            root = (root >> 1) + bit;
        } else {
            root >>= 1;
        }
        bit >>= 2;
    }
    root
}

/// ⌊√v⌋ by Newton's iteration `x ← (x + v/x) / 2` from above: seeded with the tangent to √m
/// at m = 2, on `v`'s leading bits, at most 6.7 % above the root, so three steps reach ⌊√v⌋
/// and a fourth confirms it (from any start at or above ⌊√v⌋ the iterates decrease until
/// the floor).
#[inline]
pub const fn isqrt32_newton(v: u32) -> u32 {
    if v < 2 {
        return v;
    }
    // v = m · 4^e with m in [1, 4): √v ≈ (m + 2) / (2√2) · 2^e, the tangent at m = 2, which
    // lies above √m. 182/512 is 1/(2√2) rounded up; (v >> e) + 2^(e+1) < 2^18, so the
    // product fits; the + 1 covers the truncations.
    let e = (31 - v.leading_zeros()) / 2;
    let mut x = ((((v >> e) + (2u32 << e)) * 182) >> 9) + 1;
    loop {
        // x ≥ ⌊√v⌋ ≥ 1, so the division never meets 0 (said to the compiler, for the
        // panic-never link check).
        let Some(q) = v.checked_div(x) else {
            return 0;
        };
        let y = (x + q) >> 1;
        if y >= x {
            return x;
        }
        x = y;
    }
}

/// `floor(sqrt(n))` for `n < 2^62`, exactly `n.isqrt()`. Where the core has a
/// double-precision square root (x86-64, AArch64) its correctly rounded estimate is within one
/// of the answer and one integer step on each side makes it exact; elsewhere [`isqrt_u62`] in
/// 32-bit operations (on ARMv6-M with its soft division and no library call: 1,012 B less
/// flash than `core`'s `u64::isqrt`, which calls the library's divisions and shifts there).
#[inline]
fn isqrt_u64(n: u64) -> u64 {
    #[cfg(any(target_feature = "sse2", target_arch = "aarch64"))]
    {
        // n < 2^63, so the estimate is below 2^32 and its square cannot overflow.
        let mut r = libm::sqrt(n as f64) as u64;
        while r * r > n {
            r -= 1;
        }
        while (r + 1) * (r + 1) <= n {
            r += 1;
        }
        r
    }
    #[cfg(not(any(target_feature = "sse2", target_arch = "aarch64")))]
    {
        isqrt_u62(n)
    }
}

/// `floor(sqrt(n))` for `n < 2^62` in 32-bit operations (a larger `n` is taken as
/// `2^62 - 1`): the 32-bit root of `n`'s top bits, then one Newton step and one
/// correction, each step in the forms that need no library call on ARMv6-M
/// ([`bit_length_u64`], [`shr_low_word`], [`div_rem_u64_u32`], [`mul_wide_u32`]). `core`'s
/// `u64::isqrt` works in 64-bit integers throughout, several times the cost on a 32-bit core.
///
/// Why it is exact: with `n >> 2k` below 2^32 and at least 2^30 (`k` chosen so), the root
/// `r0 = isqrt32(n >> 2k) · 2^k` is at most `√n` and at least `2^(15+k)`, and
/// `√n − r0 < 2^k · (√(t+1) − √t + 1) <= 2^k · (1 + 2^-16)` for `t = n >> 2k`. A Newton step
/// `r1 = ⌊(r0 + ⌊n / r0⌋) / 2⌋` from any positive `r0` is at least `⌊√n⌋` (the arithmetic and
/// geometric means), and it exceeds `√n` by at most `(√n − r0)² / (2 · r0)`, below
/// `2^(k−16) · 1.0001 < 1` for `k <= 15` (`n < 2^62`): so `r1` is `⌊√n⌋` or one more, and
/// one comparison of its square settles it. Test `square_root_is_exact`.
#[inline]
#[cfg_attr(
    any(target_feature = "sse2", target_arch = "aarch64"),
    allow(dead_code) // (tested on the host against `u64::isqrt`)
)]
fn isqrt_u62(n: u64) -> u64 {
    let n = n.min((1 << 62) - 1);
    if n >> 32 == 0 {
        return isqrt32(n as u32) as u64;
    }
    // n >= 2^32: `2k` makes `n >> 2k` 31 or 32 bits long (k in 1..=15).
    let bits = bit_length_u64(n);
    let k = (bits - 31) / 2;
    // n < 2^62 is a positive i64, and `n >> 2k` fits 32 bits.
    let r0 = isqrt32(shr_low_word(n as i64, 2 * k) as u32) << k;
    // r0 >= 2^15 (the top bits are at least 2^30), and below 2^31.
    let (q, _) = div_rem_u64_u32(n, r0);
    let r1 = (r0 as u64 + q) >> 1;
    // r1 <= ⌊√n⌋ + 1 <= 2^31: its square fits 64 bits.
    r1 - (mul_wide_u32(r1 as u32, r1 as u32) > n) as u64
}

/// `64 − v.leading_zeros()`: on ARMv6-M, which has no count-leading-zeros instruction (each
/// `leading_zeros` is a call of `__clzsi2`, [`NO_HARDWARE_DIVIDE`]'s cores), by [`normalize`]'s
/// comparisons on the high or the low word; elsewhere the instruction. The same either way
/// (test `bit_length_is_64_minus_leading_zeros`).
#[inline]
pub(crate) fn bit_length_u64(v: u64) -> u32 {
    if NO_HARDWARE_DIVIDE {
        bit_length_u64_in_words(v)
    } else {
        64 - v.leading_zeros()
    }
}

/// `v.leading_zeros()` for `v >= 1`: on ARMv6-M (no count-leading-zeros instruction, as for
/// [`bit_length_u64`]) by [`normalize`]'s comparisons, elsewhere the instruction. The same
/// either way (test `bit_length_is_64_minus_leading_zeros`).
#[inline]
pub(crate) fn leading_zeros_nonzero(v: u32) -> u32 {
    if NO_HARDWARE_DIVIDE {
        normalize(v).1
    } else {
        v.leading_zeros()
    }
}

/// [`bit_length_u64`] from [`normalize`], on every target (tested on the host too).
#[inline]
fn bit_length_u64_in_words(v: u64) -> u32 {
    let (hi, lo) = ((v >> 32) as u32, v as u32);
    if hi != 0 {
        64 - normalize(hi).1
    } else if lo != 0 {
        32 - normalize(lo).1
    } else {
        0
    }
}

/// `v` shifted (left or right, the same for every component) so that its largest component
/// has exactly `bits` significant bits (`2^(bits-1) <= max |c| <= 2^bits`), for `bits <= 30`;
/// `None` for the zero vector. Scaling small vectors up keeps the integer square root of
/// `|v|²`, which truncates, within a relative 2^(1-bits) of the true length.
///
/// The components fit `i32`, so both shifts are taken there: a right shift keeps only the low
/// word of the 64-bit one, and a left shift starts from a component below 2^bits (test
/// `fit_bits_equals_the_64_bit_shifts`).
#[inline]
pub(crate) fn fit_bits(v: [i64; 3], bits: u32) -> Option<[i32; 3]> {
    debug_assert!(bits <= 30, "fit_bits to {bits} bits");
    // The or of the magnitudes has the largest one's length, for less than their maximum.
    let max = v.iter().fold(0, |m, c| m | c.unsigned_abs());
    if max == 0 {
        return None;
    }
    if max >> (bits - 1) == 1 {
        // Already `bits` long (a vector fitted before, such as a face normal under the identity
        // normal matrix): no shift, and no bit length to count (comparisons on ARMv6-M).
        return Some(v.map(|c| c as i32));
    }
    let len = bit_length_u64(max);
    Some(if len > bits {
        // |c >> s| <= 2^bits.
        let s = len - bits;
        v.map(|c| shr_low_word(c, s))
    } else {
        // |c| < 2^len <= 2^bits, and so is the result.
        let s = bits - len;
        v.map(|c| (c as i32) << s)
    })
}

/// `v · 2^frac` rounded to nearest, ties to even, as `i32` bits: `fixed`'s `checked_from_num`
/// for a fixed-point type with `frac` fractional bits (`frac <= 31`), taken from the float's
/// bits with integer operations only (no soft-float calls on cores without an FPU). `None`
/// for NaN, infinities and values whose rounded bits do not fit `i32`. Test
/// `fixed_from_f32_equals_fixed`.
pub(crate) fn fixed_from_f32(v: f32, frac: u32) -> Option<i32> {
    let bits = v.to_bits();
    let exp = (bits >> 23 & 0xFF) as i32;
    if exp == 0xFF {
        return None;
    }
    // |v| = m · 2^(max(exp, 1) − 150): the implicit bit for normal numbers, none for
    // subnormal ones (exp 0).
    let m = if exp == 0 {
        bits & 0x7F_FFFF
    } else {
        bits & 0x7F_FFFF | 0x80_0000
    };
    let shift = exp.max(1) - 150 + frac as i32;
    let magnitude = if shift >= 0 {
        // m < 2^24: up to 8 more bits fit `u32`; a normal m (>= 2^23) shifted 9 or more is
        // beyond 2^31 (and a subnormal one never shifts left for frac <= 31).
        if shift > 8 {
            return None;
        }
        m << shift
    } else {
        let k = shift.unsigned_abs();
        if k > 24 {
            // Below half a unit (m < 2^24 <= 2^(k − 1)): rounds to 0.
            0
        } else {
            // Keep one more bit (the half), and whether anything below it is set.
            let halves = m >> (k - 1);
            let sticky = m & ((1 << (k - 1)) - 1) != 0;
            let q = halves >> 1;
            q + (halves & 1 != 0 && (sticky || q & 1 != 0)) as u32
        }
    };
    if bits >> 31 == 0 {
        i32::try_from(magnitude).ok()
    } else if magnitude <= 1 << 31 {
        // −2^31 fits: its magnitude as `i32` wraps to itself.
        Some((magnitude as i32).wrapping_neg())
    } else {
        None
    }
}

/// `v` as I16F16, rounded to nearest (ties to even) and checked: `I16F16::checked_from_num(v)`
/// without the float operations ([`fixed_from_f32`]).
#[inline]
pub(crate) fn i16f16_from_f32(v: f32) -> Option<fixed::types::I16F16> {
    fixed_from_f32(v, 16).map(fixed::types::I16F16::from_bits)
}

/// How precisely lighting takes the cosine between a normal and the light, chosen at compile
/// time (see [`crate::arithmetic::Arithmetic`]).
pub trait NormalPrecision:
    Copy + Default + core::fmt::Debug + PartialEq + Eq + sealed::Sealed + 'static
{
    /// Cosine between `v` (any non-zero scale) and the unit vector `unit` (I2F30 bits), in
    /// I2F30 bits; `None` for the zero vector.
    fn cosine(v: [i64; 3], unit: [i32; 3]) -> Option<i32>;
    /// Bounds on `cosine(v, unit).max(0)` (the Lambert term), cheaper than it, from which
    /// [`Lambert::exact`] gives the term; `None` for the zero vector.
    fn lambert(v: [i64; 3], unit: [i32; 3]) -> Option<Lambert> {
        Self::cosine(v, unit).map(|c| Lambert::exactly(c.max(0)))
    }
    /// [`Self::lambert`] of `s`, a vector already brought to 30 bits (its largest component
    /// `2^29` to `2^30` in magnitude, as a face normal under the identity normal matrix is):
    /// the same bounds, without fitting it again.
    fn lambert_fitted(s: [i32; 3], unit: [i32; 3]) -> Lambert {
        let zero = Lambert::exactly(0);
        Self::lambert(s.map(i64::from), unit).unwrap_or(zero)
    }
}

mod sealed {
    pub trait Sealed {}
    impl Sealed for super::WideNormals {}
    impl Sealed for super::NarrowNormals {}
}

/// Cosines in 64-bit integers to 30 bits (`cosine_i64`): the default.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct WideNormals;

/// Cosines in 32-bit integers to 15 bits (`cosine_i32`): an error of a few 2^-15, far below
/// one 8-bit colour step, for a fraction of the cost on cores without a 64-bit divider.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NarrowNormals;

impl NormalPrecision for WideNormals {
    #[inline]
    fn cosine(v: [i64; 3], unit: [i32; 3]) -> Option<i32> {
        cosine_i64(v, unit)
    }
    #[inline]
    fn lambert(v: [i64; 3], unit: [i32; 3]) -> Option<Lambert> {
        lambert_i64(v, unit)
    }
    #[inline]
    fn lambert_fitted(s: [i32; 3], unit: [i32; 3]) -> Lambert {
        lambert_of_fitted(s, unit)
    }
}

impl NormalPrecision for NarrowNormals {
    #[inline]
    fn cosine(v: [i64; 3], unit: [i32; 3]) -> Option<i32> {
        cosine_i32(v, unit)
    }
}

/// [`cosine_i64`] to 15 bits in 32-bit arithmetic: `v` is scaled until its largest component
/// has 15 bits (so `|v|²` is below `3 · 2^30`, a `u32`) and `unit` is taken to 15 bits. The result
/// is in I2F30 bits with its low 15 bits zero.
pub(crate) fn cosine_i32(v: [i64; 3], unit: [i32; 3]) -> Option<i32> {
    let s = fit_bits(v, 15)?;
    let square = s.iter().map(|&c| (c * c) as u32).sum::<u32>();
    // Without a divider, core's `isqrt` and `/` are library calls: the bitwise root and the
    // soft division give the same values from shifts and multiplies.
    let len = if NO_HARDWARE_DIVIDE {
        isqrt32_bitwise(square)
    } else {
        square.isqrt()
    };
    if len == 0 {
        return None;
    }
    // |s| < 2^15.8 and |unit >> 15| <= 2^15, so by Cauchy–Schwarz every partial sum of the
    // dot product is below 2^31 (wrapping operations only keep the panic branch out).
    let dot = (0..3).fold(0i32, |acc, k| {
        acc.wrapping_add(s[k].wrapping_mul(unit[k] >> 15))
    });
    let q = if NO_HARDWARE_DIVIDE {
        div_rem_u32_soft(dot.unsigned_abs(), len).0
    } else {
        dot.unsigned_abs() / len
    } as i32;
    Some((if dot < 0 { -q } else { q }) << 15)
}

/// `n.checked_div_euclid(d)` for `i128` from `checked_div` and `checked_rem` (the same values):
/// the standard method calls `div_euclid`, whose own panic path stays wherever that call is
/// not inlined, as with `opt-level = "z"`.
pub(crate) fn checked_div_euclid_i128(n: i128, d: i128) -> Option<i128> {
    let (q, r) = (n.checked_div(d)?, n.checked_rem(d)?);
    Some(match (r < 0, d > 0) {
        (true, true) => q - 1,
        (true, false) => q + 1,
        (false, _) => q,
    })
}

/// `[f(a₀, b₀), f(a₁, b₁), f(a₂, b₂)]`. The same as `[0, 1, 2].map(|k| f(a[k], b[k]))` without
/// indexing: where the optimiser keeps such a closure out of line (`opt-level = "z"` does), the
/// index is a run-time value and each `a[k]` keeps a bounds check, a panic path the render path
/// must not have (the panic-never link check builds with both optimisation levels).
#[inline(always)]
pub(crate) fn zip3<A, B, C>(a: [A; 3], b: [B; 3], mut f: impl FnMut(A, B) -> C) -> [C; 3] {
    let ([a0, a1, a2], [b0, b1, b2]) = (a, b);
    [f(a0, b0), f(a1, b1), f(a2, b2)]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checked_div_euclid_i128_is_the_standard_one() {
        let mut rng = crate::test_rng::XorShift64::new(0x5bd1_e995_1234_5678);
        let edges = [
            i128::MIN,
            i128::MIN + 1,
            -7,
            -2,
            -1,
            0,
            1,
            2,
            7,
            i128::MAX - 1,
            i128::MAX,
        ];
        let mut values: std::vec::Vec<i128> = edges.to_vec();
        for _ in 0..2_000 {
            let wide = i128::from(rng.next_u64()) << 64 | i128::from(rng.next_u64());
            values.push(wide >> (rng.next_u64() % 127));
        }
        for &n in &values {
            for &d in values.iter().step_by(7).chain(&edges) {
                assert_eq!(
                    checked_div_euclid_i128(n, d),
                    n.checked_div_euclid(d),
                    "{n} / {d}"
                );
            }
        }
    }

    #[test]
    fn zip3_pairs_in_order() {
        let mut calls = std::vec::Vec::new();
        let out = zip3([1, 2, 3], [10, 20, 30], |a, b| {
            calls.push(a);
            a * b
        });
        assert_eq!((out, calls.as_slice()), ([10, 40, 90], &[1, 2, 3][..]));
    }

    #[test]
    fn isqrt32_is_floor_sqrt() {
        // Every v below 2^20, every square and its neighbours, and a stride through the rest.
        let squares = (0u64..=65535).flat_map(|r| [r * r, (r * r).saturating_sub(1), r * r + 1]);
        let spread = (0u64..1 << 20)
            .chain(squares)
            .chain((0..1u64 << 32).step_by(9973));
        for v in spread.chain([u32::MAX as u64, 1 << 30, (1 << 31) + 12345]) {
            let v = v as u32;
            for (name, r) in [
                ("newton", isqrt32_newton(v)),
                ("bitwise", isqrt32_bitwise(v)),
                ("isqrt32", isqrt32(v)),
            ] {
                let r = r as u64;
                assert!(
                    r * r <= v as u64 && (r + 1) * (r + 1) > v as u64,
                    "{name} {v}"
                );
            }
        }
    }

    #[test]
    fn narrow_products_are_exact() {
        let mut rng = crate::test_rng::XorShift64::new(0x2545_f491_4f6c_dd1du64);
        let edges = [0i64, 1, -1, i64::MAX, i64::MIN, u32::MAX as i64, -(1 << 32)];
        assert_eq!(mul_wide_in_halves(i32::MIN, i32::MIN), 1 << 62);
        for k in 0..400_000u64 {
            let x = rng.next_u64();
            let a = match k % 4 {
                0 => x as i64,
                1 => (x as i64) >> (x % 64),
                _ => edges[(k / 4 % 7) as usize].wrapping_add((x >> 60) as i64 - 8),
            };
            let (c, d) = ((x >> 32) as i32, (a as i32) >> (x % 32));
            for (c, d) in [(c, d), (c, i32::MIN), (i32::MIN, d), (i32::MAX, d), (c, -1)] {
                let want = c as i64 * d as i64;
                assert_eq!(mul_wide_in_halves(c, d), want, "{c} * {d}");
                assert_eq!(mul_wide(c, d), want, "{c} * {d}");
                let (c, d) = (c as u32, d as u32);
                let want = c as u64 * d as u64;
                assert_eq!(mul_wide_u32_in_halves(c, d), want, "{c} * {d}");
                assert_eq!(mul_wide_u32(c, d), want, "{c} * {d}");
            }
            let b = d;
            // Factors on both sides of 2^31 whose products fit i64.
            for a in [
                a >> 32,
                a >> (x % 32 + 32),
                c as i64,
                (a >> 33) + i32::MAX as i64,
            ] {
                assert_eq!(mul_i64_i32(a, b), a * b as i64, "{a} * {b}");
                // Either factor wider than 32 bits, or both within.
                assert_eq!(mul_i64(a, b as i64), a * b as i64, "{a} * {b}");
                assert_eq!(mul_i64(b as i64, a), a * b as i64, "{b} * {a}");
            }
        }
    }

    #[test]
    fn bit_length_is_64_minus_leading_zeros() {
        let mut rng = crate::test_rng::XorShift64::new(0x2d35_8dcc_aa6c_78a5u64);
        for k in 0..64 {
            for v in [
                1u64 << k,
                (1u64 << k) - 1,
                (1u64 << k) + 1,
                u64::MAX >> k,
                0,
            ] {
                assert_eq!(bit_length_u64_in_words(v), 64 - v.leading_zeros(), "{v}");
                assert_eq!(bit_length_u64(v), 64 - v.leading_zeros(), "{v}");
            }
        }
        for _ in 0..100_000 {
            let x = rng.next_u64();
            let v = x >> (x % 64);
            assert_eq!(bit_length_u64_in_words(v), 64 - v.leading_zeros(), "{v}");
            // `leading_zeros_nonzero`'s ARMv6-M form, on 32-bit values of every length.
            let w = (v as u32).max(1);
            assert_eq!(normalize(w).1, w.leading_zeros(), "{w}");
            assert_eq!(leading_zeros_nonzero(w), w.leading_zeros(), "{w}");
        }
    }

    #[test]
    fn shifts_in_words_are_exact() {
        let mut rng = crate::test_rng::XorShift64::new(0x9e37_79b9_7f4a_7c15u64);
        let edges = [
            0i64,
            1,
            -1,
            i64::MAX,
            i64::MIN,
            u32::MAX as i64,
            -(1 << 32),
            1 << 31,
        ];
        for k in 0..100_000u64 {
            let x = rng.next_u64();
            let v = match k % 3 {
                0 => x as i64,
                1 => (x as i64) >> (x % 64),
                _ => edges[(k / 3 % 8) as usize].wrapping_add((x >> 60) as i64 - 8),
            };
            for s in 0..64 {
                assert_eq!(shr_low_word_in_words(v, s), (v >> s) as i32, "{v} >> {s}");
                assert_eq!(shr_low_word(v, s), (v >> s) as i32, "{v} >> {s}");
                assert_eq!(shr_i64_in_words(v, s), v >> s, "{v} >> {s}");
                assert_eq!(shr_i64(v, s), v >> s, "{v} >> {s}");
                if s >= 32 {
                    assert_eq!(shr_i64_high(v, s), v >> s, "{v} >> {s}");
                }
                let u = v as u64;
                assert_eq!(shr_u64_in_words(u, s), u >> s, "{u} >> {s}");
                assert_eq!(shr_u64(u, s), u >> s, "{u} >> {s}");
            }
        }
    }

    #[test]
    fn division_by_32_bits_is_exact() {
        let ns = [
            0u64,
            1,
            2,
            u32::MAX as u64,
            1 << 32,
            (1 << 32) + 1,
            u64::MAX,
            u64::MAX - 1,
        ];
        let ds = [
            1u32,
            2,
            3,
            0xFFFF,
            0x1_0000,
            0x8000_0000,
            0x8000_0001,
            u32::MAX,
        ];
        let check = |n: u64, d: u32| {
            let want = (n / d as u64, (n % d as u64) as u32);
            assert_eq!(div_rem_u64_u32_in_halves(n, d), want, "{n} / {d}");
            assert_eq!(div_rem_u64_u32(n, d), want, "{n} / {d}");
            // The low word's division as each 32-bit core does it: without a divider, with
            // one (the host's own `div_rem_below` divides `u64`).
            let (hi, lo) = ((n >> 32) as u32, n as u32);
            let r_hi = hi % d;
            let want_lo = (want.0 as u32, want.1);
            assert_eq!(
                div_rem_below_with::<true>(r_hi, lo, d),
                want_lo,
                "{n} / {d}"
            );
            assert_eq!(
                div_rem_below_with::<false>(r_hi, lo, d),
                want_lo,
                "{n} / {d}"
            );
            assert_eq!(div_rem_below(r_hi, lo, d), want_lo, "{n} / {d}");
        };
        for n in ns {
            for d in ds {
                check(n, d);
            }
        }
        let mut rng = crate::test_rng::XorShift64::new(0x9e37_79b9_7f4a_7c15u64);
        for _ in 0..400_000 {
            let x = rng.next_u64();
            let n = x >> (x % 64);
            let d = ((x >> 7) as u32) >> ((x >> 40) % 32);
            check(n, d.max(1));
            // Quotients at the digit boundaries: n = q·d + r with chosen q.
            let q = (x >> 20) & 0xFFFF_FFFF;
            check(q * d.max(1) as u64 + (x % d.max(1) as u64), d.max(1));
            let (n, d) = (x as i64 >> (x % 63), (x >> 11) as i64 >> ((x >> 50) % 63));
            assert_eq!(
                floor_div_i64(n, d.max(1)),
                n.div_euclid(d.max(1)),
                "{n} / {d}"
            );
        }
        for n in [i64::MIN, i64::MIN + 1, -1, 0, 1, i64::MAX] {
            for d in [1i64, 2, 3, u32::MAX as i64, 1 << 32, i64::MAX] {
                assert_eq!(floor_div_i64(n, d), n.div_euclid(d), "{n} / {d}");
            }
        }
    }

    #[test]
    fn reciprocal16_is_close_below() {
        for a in (1u32 << 15) + 1..=1 << 16 {
            let (r, exact) = (reciprocal16(a) as u64, (1u64 << 31) / a as u64);
            assert!(r <= exact && r + 4 >= exact, "{a}: {r} vs {exact}");
            assert!(r < 1 << 16, "{a}: {r}");
        }
    }

    #[test]
    fn normalize_sets_the_top_bit() {
        for s in 0..32 {
            for d in [1u32 << s, (1 << s) | 1, ((1u64 << (s + 1)) - 1) as u32] {
                assert_eq!(
                    normalize(d),
                    (d << d.leading_zeros(), d.leading_zeros()),
                    "{d}"
                );
            }
        }
    }

    /// Quotient and remainder of `div_rem_u32_soft` and of a `SoftDivisor` against `/` and `%`.
    fn check_soft(n: u32, d: u32) {
        let want = (n / d, n % d);
        assert_eq!(div_rem_u32_soft(n, d), want, "{n} / {d}");
        assert_eq!(SoftDivisor::new(d).div_rem(n), want, "{n} / {d}");
    }

    #[test]
    fn soft_division_is_exact() {
        let mut ds = std::vec![
            1u32,
            2,
            3,
            5,
            7,
            10,
            0xFFFF,
            0x1_0001,
            u32::MAX,
            u32::MAX - 1
        ];
        for s in 0..32 {
            let p = 1u32 << s;
            ds.extend([p, p - 1, p.wrapping_add(1), p | (p >> 1), p + (p >> 9)]);
        }
        ds.retain(|&d| d != 0);
        for &d in &ds {
            let mut ns = std::vec![
                0u32,
                1,
                2,
                u32::MAX,
                u32::MAX - 1,
                d,
                d - 1,
                d.wrapping_add(1)
            ];
            for k in [
                2u32,
                3,
                7,
                100,
                0xFFFF,
                0x1_0000,
                0x1_0001,
                0x7FFF_FFFF,
                u32::MAX,
            ] {
                if let Some(kd) = k.checked_mul(d) {
                    ns.extend([kd, kd - 1, kd.wrapping_add(1), kd.wrapping_add(d - 1)]);
                }
            }
            for n in ns {
                check_soft(n, d);
            }
        }
        assert_eq!(div_rem_u32_soft(12345, 0), (12345, 0));
        let mut rng = crate::test_rng::XorShift64::new(0x2545_f491_4f6c_dd1d);
        for _ in 0..4_000_000 {
            let x = rng.next_u64();
            // Any width of either operand, and quotients of every length with any remainder.
            let n = (x as u32) >> ((x >> 32) % 32);
            let d = (((x >> 37) as u32) >> ((x >> 59) % 32)).max(1);
            check_soft(n, d);
            let q = (x >> 40) as u32 >> ((x >> 35) % 24);
            if let Some(n) = q.checked_mul(d).and_then(|qd| qd.checked_add(n % d)) {
                check_soft(n, d);
            }
        }
    }

    /// Every divisor below 2^12 and every divisor's top-16-bit class (`d = h·2^16 + low` for
    /// every `h` with a few `low`), each against 4,100 numerators spread over `u32` and those
    /// numerators' multiples of `d`; every numerator below 2^28 for three divisors. Ignored:
    /// 17 s (`cargo test -p scanline3d --release --lib soft_division -- --ignored`).
    #[test]
    #[ignore]
    fn soft_division_is_exact_exhaustively() {
        let small = 1u32..1 << 12;
        let classes =
            (1u32..1 << 16).flat_map(|h| [h << 16, (h << 16) | 0xFFFF, (h << 16) | 0x8001]);
        for d in small.chain(classes) {
            for n in (0..=u32::MAX)
                .step_by(1_048_573)
                .chain([u32::MAX, d - 1, d])
            {
                check_soft(n, d);
                check_soft(n.wrapping_sub(n % d), d);
            }
        }
        // Every numerator below 2^28 for a few divisors.
        for d in [3u32, 0xFFFF, 0x8001] {
            for n in 0..1 << 28 {
                assert_eq!(div_rem_u32_soft(n, d), (n / d, n % d), "{n} / {d}");
            }
        }
    }

    /// `root_and_quotient` against `isqrt` and `/`: every power of two and its neighbours in
    /// range, the ends, random roots with numerators of every size; and the estimate path
    /// answers every one (no `None`), which is what makes it the cheaper one.
    #[test]
    fn root_and_quotient_are_exact() {
        let mut rng = crate::test_rng::XorShift64::new(0x3c6e_f372_fe94_f82bu64);
        let mut xs: std::vec::Vec<u32> = (28..32)
            .flat_map(|b| [(1u32 << b) - 1, 1 << b, (1 << b) + 1])
            .chain([u32::MAX, u32::MAX - 1, 3 << 30])
            .chain(
                (1u32 << 14..=65_535)
                    .step_by(7)
                    .flat_map(|r| [r * r, r * r - 1, r * r + 2 * r]),
            )
            .filter(|&x| x >= 1 << 28)
            .collect();
        for _ in 0..300_000 {
            // Uniform over [2^28, 2^32), and as many below 2^30 (the shifted half).
            let x = (rng.next_u64() as u32) >> (rng.next_u64() % 4);
            xs.push(x.max(1 << 28));
        }
        assert_eq!(root_and_quotient((1 << 28) - 1, 5), None);
        for x in xs {
            let r = x.isqrt();
            let n = rng.next_u64() as u32;
            for n in [n, n >> (n % 32), 0, u32::MAX, r - 1, r, r * (n % 1000)] {
                assert_eq!(root_and_quotient(x, n), Some((r, n / r)), "{x} {n}");
            }
        }
    }

    /// Every `x` the root takes, each with a numerator near a multiple of the root: about three
    /// minutes (`cargo test -p scanline3d --release --lib root_and_quotient -- --ignored`).
    #[test]
    #[ignore]
    fn root_and_quotient_exhaustively() {
        for x in 1u32 << 28..=u32::MAX {
            let r = x.isqrt();
            let n = x.rotate_left(7);
            let n = n - n % r + (x % 3).saturating_sub(1) * (r - 1);
            assert_eq!(root_and_quotient(x, n), Some((r, n / r)), "{x} {n}");
        }
    }

    /// `div_below_float` gives the quotient or `None`, never another value, for every divisor
    /// class and numerator below `d·2^32`; and gives it (`Some`) wherever the error bound says
    /// the remainder fits (`n < 2^50`, `d < 2^29`, a quotient of at least 2), the depth's
    /// numerators `near·2^30` included.
    #[test]
    fn float_estimated_division_is_exact() {
        let mut rng = crate::test_rng::XorShift64::new(0x5851_f42d_4c95_7f2du64);
        // Divisions the bound covers: each must be answered, and there must be many.
        let mut covered = 0u32;
        let mut check = |n: u64, d: u32| {
            let want = n / d as u64;
            let got = div_below_float(n, d);
            if let Some(q) = got {
                assert_eq!(q as u64, want, "{n} / {d}");
            }
            if n < 1 << 50 && d < 1 << 29 && want >= 2 {
                assert!(got.is_some(), "{n} / {d} given up");
                covered += 1;
            }
        };
        let ds = [
            1u32,
            2,
            3,
            255,
            0xFFFF,
            1 << 20,
            (1 << 29) - 1,
            1 << 31,
            u32::MAX,
        ];
        for d in ds {
            let top = (d as u64) << 32;
            for n in [
                0,
                1,
                d as u64 - 1,
                d as u64,
                top / 3,
                top - d as u64,
                top - 1,
            ] {
                check(n, d);
            }
        }
        for _ in 0..1_000_000 {
            let x = rng.next_u64();
            let d = ((x as u32) >> ((x >> 32) % 32)).max(1);
            // Numerators of every length up to the quotient's limit.
            let n = rng.next_u64() >> ((x >> 40) % 64);
            let n = n % ((d as u64) << 32);
            check(n, d);
        }
        // The vertex depth's divisions: `near·2^30 / w` for `w` from `near / 4` up.
        for _ in 0..200_000 {
            let x = rng.next_u64();
            let near = ((x as u32) >> (12 + (x >> 32) % 20)).max(1);
            let w = (near / 4 + 1).saturating_add((x >> 40) as u32 >> ((x >> 36) % 16));
            let n = (near as u64) << 30;
            if n >> 32 < w as u64 {
                check(n, w);
            }
        }
        assert!(covered > 300_000, "{covered} covered divisions");
    }

    #[test]
    fn reciprocal_division_is_exact() {
        let ns = [
            0u64,
            1,
            2,
            u32::MAX as u64,
            1 << 32,
            (1 << 32) + 1,
            1 << 63,
            u64::MAX,
            u64::MAX - 1,
        ];
        let ds = [
            1u32,
            2,
            3,
            7,
            0xFFFF,
            0x1_0000,
            0x7FFF_FFFF,
            0x8000_0000,
            0x8000_0001,
            u32::MAX - 1,
            u32::MAX,
        ];
        let check = |n: u64, by: &Divisor32, d: u32| {
            let want = (n / d as u64, (n % d as u64) as u32);
            assert_eq!(by.div_rem(n), want, "{n} / {d}");
            let n = n as i64;
            assert_eq!(by.floor_div(n), n.div_euclid(d as i64), "{n} / {d}");
            assert_eq!(by.floor_div(n), floor_div_i64(n, d as i64), "{n} / {d}");
        };
        for d in ds {
            let by = Divisor32::new(d);
            for n in ns {
                // Each boundary, and multiples of d and their neighbours near it.
                for n in [
                    n,
                    n.wrapping_sub(n % d as u64),
                    n.wrapping_sub(n % d as u64 + 1),
                ] {
                    check(n, &by, d);
                }
            }
        }
        assert_eq!(Divisor32::new(0).div_rem(12345), (12345, 0));
        let mut rng = crate::test_rng::XorShift64::new(0x9e37_79b9_7f4a_7c15u64);
        for _ in 0..400_000 {
            let x = rng.next_u64();
            let d = (((x >> 7) as u32) >> ((x >> 40) % 32)).max(1);
            let by = Divisor32::new(d);
            // The 32-bit targets' reciprocal (the host divides `u64`), with and without a
            // divider.
            assert_eq!(div_rem_below(!by.d, u32::MAX, by.d).0, by.v, "{d}");
            assert_eq!(
                div_rem_below_with::<true>(!by.d, u32::MAX, by.d).0,
                by.v,
                "{d}"
            );
            check(x >> (x % 64), &by, d);
            // Quotients and remainders at the word boundaries: n = q·d + r with chosen q, r.
            let q = (x >> 20) & 0xFFFF_FFFF;
            for r in [0, 1, d - 1, (x % d as u64) as u32] {
                check(q * d as u64 + r as u64, &by, d);
                check(
                    (q << 32).wrapping_mul(d as u64).wrapping_add(r as u64),
                    &by,
                    d,
                );
            }
            // Divisors of the depth plane (twice a triangle's area) and the projection (2w).
            let small = ((x >> 33) as u32 % (1 << ((x >> 1) % 24 + 1))).max(1) * 2;
            check(x >> (x % 64), &Divisor32::new(small), small);
        }
    }

    /// `fit_bits` gives the components the 64-bit shifts it replaced gave: every length of
    /// the largest component (powers of two and their neighbours, either sign, each in any
    /// place), and random vectors, to 15 and 30 bits.
    #[test]
    fn fit_bits_equals_the_64_bit_shifts() {
        let wide = |v: [i64; 3], bits: u32| -> Option<[i32; 3]> {
            let max = v.iter().fold(0, |m, c| m | c.unsigned_abs());
            if max == 0 {
                return None;
            }
            let len = 64 - max.leading_zeros();
            let v = if len > bits {
                v.map(|c| c >> (len - bits))
            } else {
                v.map(|c| c << (bits - len))
            };
            Some(v.map(|c| c as i32))
        };
        let mut rng = crate::test_rng::XorShift64::new(0x2545_f491_4f6c_dd1du64);
        let mut next = || rng.next_u64();
        for bits in [15, 30] {
            assert_eq!(fit_bits([0; 3], bits), None);
            for k in 0..63 {
                for m in [(1i64 << k) - 1, 1 << k, (1 << k) + 1] {
                    for m in [m, -m, i64::MIN, i64::MAX] {
                        for v in [
                            [m, 0, 0],
                            [1, m, -1],
                            [-3, 5, m],
                            [m, m, m],
                            [m, m.wrapping_neg(), m >> 1],
                        ] {
                            assert_eq!(fit_bits(v, bits), wide(v, bits), "{v:?} to {bits}");
                        }
                    }
                }
            }
            for _ in 0..300_000 {
                let v = [0; 3].map(|_| (next() as i64) >> (next() % 64));
                assert_eq!(fit_bits(v, bits), wide(v, bits), "{v:?} to {bits}");
            }
        }
    }

    #[test]
    fn square_root_is_exact() {
        // Perfect squares and their neighbours at every size, and pseudo-random values.
        let mut rng = crate::test_rng::XorShift64::new(0x9e37_79b9_7f4a_7c15u64);
        for k in 0..200_000u64 {
            let x = rng.next_u64();
            let root = (k * 20_000 + (x >> 44)) % (1 << 31);
            for n in [
                root * root,
                (root * root).saturating_sub(1),
                root * root + 1,
                x >> 2,
            ] {
                assert_eq!(isqrt_u64(n), n.isqrt(), "sqrt {n}");
                // (root < 2^31, so every n here but `x >> 2` is below 2^62.)
                let m = n.min((1 << 62) - 1);
                assert_eq!(isqrt_u62(m), m.isqrt(), "32-bit sqrt {m}");
            }
            // The lighting's range, [2^58, 3 · 2^60) (`cosine_i64`).
            let n = (1 << 58) + (x >> 2) % (11 << 58);
            assert_eq!(isqrt_u62(n), n.isqrt(), "32-bit sqrt {n}");
        }
        // Every shift `k` and the ends of each: powers of two and their neighbours.
        for j in 0..62 {
            let p = 1u64 << j;
            for n in [p - 1, p, p + 1, (p - 1) | p, ((1 << 62) - 1) >> (j & !1)] {
                assert_eq!(isqrt_u62(n), n.isqrt(), "32-bit sqrt {n}");
            }
        }
        assert_eq!(isqrt_u62(u64::MAX), ((1u64 << 62) - 1).isqrt());
    }

    /// Pseudo-random integer vectors at every scale from a few units to 2^62.
    fn vectors(count: usize) -> impl Iterator<Item = [i64; 3]> {
        let mut rng = crate::test_rng::XorShift64::new(0x9e37_79b9u64);
        let mut next = move || {
            let x = rng.next_u64();
            (x as i64) >> (x % 62) as u32
        };
        (0..count).map(move |_| [next(), next(), next()])
    }

    /// `unit` as an I2F30 vector of length 1 (rounded), and the exact cosine in f64.
    fn exact(v: [i64; 3], d: [f64; 3]) -> ([i32; 3], f64) {
        let len = d.iter().map(|c| c * c).sum::<f64>().sqrt();
        let unit = d.map(|c| (c / len * (1u64 << 30) as f64).round() as i32);
        let u = unit.map(|c| c as f64 / (1u64 << 30) as f64);
        let vf = v.map(|c| c as f64);
        let vlen = vf.iter().map(|c| c * c).sum::<f64>().sqrt();
        (unit, (0..3).map(|k| vf[k] * u[k]).sum::<f64>() / vlen)
    }

    /// The lighting's shades do not depend on how the root and the scaling are computed:
    /// `cosine_i64` equals the formula in plain 64-bit operations (`u64::isqrt`, `/`).
    #[test]
    fn cosine_equals_the_64_bit_formula() {
        let dirs = [[0.3, -0.5, 0.8], [1.0, 0.0, 0.0], [-0.2, -0.9, -0.1]];
        for (i, v) in vectors(200_000).enumerate() {
            let (unit, _) = exact(v, dirs[i % 3]);
            let max = v.iter().map(|c| c.unsigned_abs()).max().unwrap();
            let want = (max != 0).then(|| {
                let len = 64 - max.leading_zeros();
                let s = v.map(|c| {
                    if len > 30 {
                        c >> (len - 30)
                    } else {
                        c << (30 - len)
                    }
                });
                let root = s.iter().map(|&c| (c * c) as u64).sum::<u64>().isqrt();
                let dot: i64 = (0..3).map(|k| s[k] * unit[k] as i64).sum();
                let q = (dot.unsigned_abs() / root) as i32;
                if dot < 0 {
                    -q
                } else {
                    q
                }
            });
            assert_eq!(cosine_i64(v, unit), want, "{v:?}");
        }
    }

    #[test]
    fn lambert_bounds_hold() {
        let dirs = [
            [0.3, -0.5, 0.8],
            [1.0, 0.0, 0.0],
            [-0.2, -0.9, -0.1],
            [0.0, 0.0, 1.0],
        ];
        let mut widest = 0;
        for (i, v) in vectors(400_000).enumerate() {
            let (unit, _) = exact(v, dirs[i % 4]);
            // Near the light too: v close to the unit vector, where the cosine is near 1.
            let near = [0, 1, 2].map(|k| ((unit[k] as i64) << (i % 30)) ^ (v[k] & 0xFFF));
            for v in [v, near] {
                let want = cosine_i64(v, unit).map(|c| c.max(0));
                let got = lambert_i64(v, unit);
                match (want, got) {
                    (Some(q), Some(l)) => {
                        let (lo, hi) = (l.lo, l.hi);
                        assert!(lo <= q && q <= hi, "{v:?}: {q} not in {lo}..={hi}");
                        // The exact term from the bounds' own values.
                        assert_eq!(l.exact(), q, "{v:?}");
                        assert_eq!(WideNormals::lambert(v, unit), Some(l));
                        let narrow = cosine_i32(v, unit).map(|c| c.max(0));
                        let n = NarrowNormals::lambert(v, unit);
                        assert_eq!(
                            n.map(|n| (n.lo, n.hi, n.exact())),
                            narrow.map(|c| (c, c, c))
                        );
                        widest = widest.max(hi - lo);
                    }
                    (None, None) => {}
                    _ => panic!("{v:?}: {want:?} {got:?}"),
                }
            }
        }
        // About 2^-14 of the largest cosine (2^30), as documented.
        assert!(widest <= 5 << 16, "{widest}");
    }

    /// Lighting under the identity normal matrix fits a face normal once: the wide bounds of
    /// the fitted vector are those of any vector it was fitted from, and at both precisions
    /// `lambert_fitted` gives what `lambert` gives for the fitted vector, which is what
    /// `normal_to_world` hands it under that matrix.
    #[test]
    fn fitted_lambert_is_the_lambert_of_the_fitted_vector() {
        let dirs = [[0.3, -0.5, 0.8], [1.0, 0.0, 0.0], [-0.2, -0.9, -0.1]];
        let mut lit = 0;
        for (i, v) in vectors(200_000).enumerate() {
            let (unit, _) = exact(v, dirs[i % 3]);
            let Some(s) = fit_bits(v, 30) else {
                assert_eq!(lambert_i64(v, unit), None);
                continue;
            };
            let wide = WideNormals::lambert(v, unit);
            assert_eq!(Some(WideNormals::lambert_fitted(s, unit)), wide, "{v:?}");
            assert_eq!(lambert_i64(s.map(i64::from), unit), wide, "{v:?}");
            let narrow = NarrowNormals::lambert(s.map(i64::from), unit);
            assert_eq!(
                Some(NarrowNormals::lambert_fitted(s, unit)),
                narrow,
                "{v:?}"
            );
            lit += usize::from(wide.is_some_and(|l| l.hi > 0));
        }
        assert!(lit > 50_000, "{lit}");
    }

    #[test]
    fn cosines_match_f64_at_every_scale() {
        let dirs = [[0.3, -0.5, 0.8], [1.0, 0.0, 0.0], [-0.2, -0.9, -0.1]];
        for (i, v) in vectors(20_000).enumerate() {
            let (unit, want) = exact(v, dirs[i % 3]);
            let one = (1u64 << 30) as f64;
            let (Some(wide), Some(narrow)) = (cosine_i64(v, unit), cosine_i32(v, unit)) else {
                assert_eq!(v, [0; 3]);
                continue;
            };
            // Wide: truncating `v` to 30 bits, its root and the quotient; the worst seen here
            // is 3.0 units of 2^-30.
            let wide_err = (wide as f64 / one - want).abs();
            assert!(wide_err < 4.0 / one, "{v:?}: {wide} vs {want}");
            // Narrow: the same at 15 bits, plus `unit >> 15`; the worst seen is 3.3 units of
            // 2^-15.
            let narrow_err = (narrow as f64 / one - want).abs();
            assert!(narrow_err < 4.0 / 32768.0, "{v:?}: {narrow} vs {want}");
            assert_eq!(narrow & 0x7fff, 0);
        }
        assert_eq!(cosine_i64([0; 3], [1 << 30, 0, 0]), None);
        assert_eq!(cosine_i32([0; 3], [1 << 30, 0, 0]), None);
        assert_eq!(cosine_i32([0, -7, 0], [0, -(1 << 30), 0]), Some(1 << 30));
        assert_eq!(
            cosine_i64([i64::MIN + 1, 0, 0], [1 << 30, 0, 0]),
            Some(-(1 << 30))
        );
        assert_eq!(
            cosine_i32([i64::MIN + 1, 0, 0], [1 << 30, 0, 0]),
            Some(-(1 << 30))
        );
    }

    /// `fixed_from_f32` equals `fixed`'s checked conversion for 16 and 30 fractional bits
    /// (and 0 and 31): every exponent, the rounding ties and their neighbours, the ends of the
    /// range, zeros, subnormals, infinities and NaN.
    #[test]
    fn fixed_from_f32_equals_fixed() {
        use fixed::types::{I16F16, I1F31, I2F30, I32F0};
        let check = |v: f32| {
            let want = [
                I32F0::checked_from_num(v).map(|x| x.to_bits()),
                I16F16::checked_from_num(v).map(|x| x.to_bits()),
                I2F30::checked_from_num(v).map(|x| x.to_bits()),
                I1F31::checked_from_num(v).map(|x| x.to_bits()),
            ];
            let got = [0, 16, 30, 31].map(|frac| fixed_from_f32(v, frac));
            assert_eq!(got, want, "{v:e} ({:#x})", v.to_bits());
            assert_eq!(i16f16_from_f32(v), I16F16::checked_from_num(v), "{v:e}");
        };
        let mut specials = std::vec![
            0.0f32,
            -0.0,
            f32::NAN,
            -f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::MAX,
            f32::MIN,
            f32::MIN_POSITIVE,
            f32::from_bits(1),
            f32::from_bits(0x80_0001),
            32768.0,
            -32768.0,
            32767.99,
            -32768.01,
            2.0,
            -2.0,
            1.0,
            -1.0,
            2147483648.0,
            -2147483648.0,
        ];
        // Ties at every scale: (2j + 1)·2^-(frac + 1) and neighbours, for each fraction size.
        for frac in [0i32, 16, 30, 31] {
            for e in -40i32..40 {
                for j in [0u32, 1, 2, 3, 0x7F_FFFF, 0xFF_FFFF] {
                    let t = (2 * j + 1) as f32 * libm::exp2f((e - frac - 1) as f32);
                    for v in [t, -t] {
                        specials.extend([v, f32::from_bits(v.to_bits() + 1)]);
                        specials.push(f32::from_bits(v.to_bits().wrapping_sub(1)));
                    }
                }
            }
        }
        for v in specials {
            check(v);
        }
        // Every exponent with random mantissas.
        let mut rng = crate::test_rng::XorShift32::new(0x2545_f491u32);
        for _ in 0..1_000_000 {
            let x = rng.next_u32();
            check(f32::from_bits(x));
            // Concentrated on the exponents that matter (|v| from 2^-33 to 2^33).
            let near = (x & 0x807F_FFFF) | ((94 + (x >> 23) % 67) << 23);
            check(f32::from_bits(near));
        }
    }

    #[test]
    fn backends_agree_roughly() {
        for x in [0.1f32, 0.5, 1.0, 1.3] {
            assert!((Libm::sin(x) - Micromath::sin(x)).abs() < 2e-3);
            assert!((Libm::cos(x) - Micromath::cos(x)).abs() < 2e-3);
            assert!((Libm::tan(x) - Micromath::tan(x)).abs() / Libm::tan(x) < 1e-2);
        }
    }
}
