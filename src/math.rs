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
    // Unsigned division: `len` is known non-zero here, so no panic branch is emitted.
    let q = (dot.unsigned_abs() / len) as i32;
    Some(if dot < 0 { -q } else { q })
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
