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

/// Cosine of the angle between an integer vector `v` of any scale and a unit vector `unit`
/// (I2F30 bits), in I2F30 bits truncated towards zero; `None` for the zero vector.
///
/// One square root and one division: `v · unit / |v|`, with `v` first scaled so that its
/// largest component has 30 bits, which keeps `|v|²` below `3 · 2^60` (fits `u64`) and every
/// truncation (of `v`, of the root, of the quotient) within a few 2^-30. Integer only (exact `isqrt`), so lighting is identical on
/// every target.
pub(crate) fn cosine_i64(v: [i64; 3], unit: [i32; 3]) -> Option<i32> {
    let s = fit_bits(v, 30)?;
    let len = isqrt_u64(s.iter().map(|&c| (c * c) as u64).sum());
    if len == 0 {
        return None;
    }
    // |s_i · unit_i| < 2^60 and, by Cauchy–Schwarz, every partial sum is at most
    // |s| · |unit| < 2^61: no overflow, and the quotient is within about ±2^30.
    let dot: i64 = (0..3).map(|k| s[k] * unit[k] as i64).sum();
    // `len <= sqrt(3) · 2^30` fits 32 bits and is non-zero here.
    let q = div_rem_u64_u32(dot.unsigned_abs(), len as u32).0 as i32;
    Some(if dot < 0 { -q } else { q })
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
/// without any divider (Cortex-M0) each 32-bit division is a call, and the two cost about the
/// same (the icosphere frame within 0.1 %).
#[inline]
pub(crate) fn div_rem_u64_u32(n: u64, d: u32) -> (u64, u32) {
    let d = d.max(1);
    let (hi, lo) = ((n >> 32) as u32, n as u32);
    let (q_hi, r_hi) = (hi / d, hi % d);
    let (q_lo, r) = div_rem_below(r_hi, lo, d);
    (((q_hi as u64) << 32) | q_lo as u64, r)
}

/// `(u1·2^32 + u0) / v` and its remainder for `u1 < v` (so the quotient fits 32 bits).
#[inline]
fn div_rem_below(u1: u32, u0: u32, v: u32) -> (u32, u32) {
    const B: u32 = 1 << 16;
    if u1 == 0 {
        // The common case (numerator below 2^32): one division.
        let v = v.max(1);
        return (u0 / v, u0 % v);
    }
    // Normalize: the divisor's top bit set (u1 < v, so v > 0 and the shift is below 32).
    let s = v.leading_zeros();
    let v = v << s;
    // `v`'s top bit is set, so `vn1 >= 2^15` already: or-ing that bit in changes nothing but
    // lets the compiler see it is not zero (no division-by-zero panic path: the panic-never
    // link check).
    let (vn1, vn0) = ((v >> 16) | 0x8000, v & 0xFFFF);
    let un32 = (u1 << s) | if s == 0 { 0 } else { u0 >> (32 - s) };
    let un10 = u0 << s;
    let (un1, un0) = (un10 >> 16, un10 & 0xFFFF);
    // One 16-bit digit of the quotient of `top·2^16 + next` (`top < v`): the estimate from
    // `vn1 >= 2^15` is at most two too large (Knuth, Algorithm D).
    let digit = |top: u32, next: u32| {
        let mut q = top / vn1;
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

/// `floor(sqrt(n))`, exactly `n.isqrt()`. Where the core has a double-precision square root
/// (x86-64, AArch64) its correctly rounded estimate is within one of the answer and one
/// integer step on each side makes it exact; elsewhere the integer algorithm of `core`.
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
        n.isqrt()
    }
}

/// `v` shifted (left or right, the same for every component) so that its largest component
/// has exactly `bits` significant bits (`2^(bits-1) <= max |c| <= 2^bits`); `None` for the zero
/// vector. Scaling small vectors up keeps the integer square root of `|v|²`, which truncates,
/// within a relative 2^(1-bits) of the true length.
pub(crate) fn fit_bits(v: [i64; 3], bits: u32) -> Option<[i64; 3]> {
    let max = v.iter().map(|c| c.unsigned_abs()).max().unwrap_or(0);
    if max == 0 {
        return None;
    }
    let len = 64 - max.leading_zeros();
    Some(if len > bits {
        v.map(|c| c >> (len - bits))
    } else {
        v.map(|c| c << (bits - len))
    })
}

/// How precisely lighting takes the cosine between a normal and the light, chosen at compile
/// time (see [`crate::arithmetic::Arithmetic`]).
pub trait NormalPrecision:
    Copy + Default + core::fmt::Debug + PartialEq + Eq + sealed::Sealed + 'static
{
    /// Cosine between `v` (any non-zero scale) and the unit vector `unit` (I2F30 bits), in
    /// I2F30 bits; `None` for the zero vector.
    fn cosine(v: [i64; 3], unit: [i32; 3]) -> Option<i32>;
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
    let s = fit_bits(v, 15)?.map(|c| c as i32);
    let len = s.iter().map(|&c| (c * c) as u32).sum::<u32>().isqrt();
    if len == 0 {
        return None;
    }
    // |s| < 2^15.8 and |unit >> 15| <= 2^15, so by Cauchy–Schwarz every partial sum of the
    // dot product is below 2^31 (wrapping operations only keep the panic branch out).
    let dot = (0..3).fold(0i32, |acc, k| {
        acc.wrapping_add(s[k].wrapping_mul(unit[k] >> 15))
    });
    let q = (dot.unsigned_abs() / len) as i32;
    Some((if dot < 0 { -q } else { q }) << 15)
}

#[cfg(test)]
mod tests {
    use super::*;

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
            assert_eq!(div_rem_u64_u32(n, d), want, "{n} / {d}");
        };
        for n in ns {
            for d in ds {
                check(n, d);
            }
        }
        let mut x = 0x9e37_79b9_7f4a_7c15u64;
        for _ in 0..400_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
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
    fn square_root_is_exact() {
        // Perfect squares and their neighbours at every size, and pseudo-random values.
        let mut x = 0x9e37_79b9_7f4a_7c15u64;
        for k in 0..200_000u64 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let root = (k * 20_000 + (x >> 44)) % (1 << 31);
            for n in [
                root * root,
                (root * root).saturating_sub(1),
                root * root + 1,
                x >> 2,
            ] {
                assert_eq!(isqrt_u64(n), n.isqrt(), "sqrt {n}");
            }
        }
    }

    /// Pseudo-random integer vectors at every scale from a few units to 2^62.
    fn vectors(count: usize) -> impl Iterator<Item = [i64; 3]> {
        let mut x = 0x9e37_79b9u64;
        let mut next = move || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
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

    #[test]
    fn backends_agree_roughly() {
        for x in [0.1f32, 0.5, 1.0, 1.3] {
            assert!((Libm::sin(x) - Micromath::sin(x)).abs() < 2e-3);
            assert!((Libm::cos(x) - Micromath::cos(x)).abs() < 2e-3);
            assert!((Libm::tan(x) - Micromath::tan(x)).abs() / Libm::tan(x) < 1e-2);
        }
    }
}
