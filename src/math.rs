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

/// Unit vector in I2F30 (components as raw bits, `1.0 = 1 << 30`) pointing along an integer
/// vector of any scale. `None` for the zero vector.
///
/// Integer only (exact `isqrt`), so normals are identical on every target. The input is first
/// shifted right until every component fits in 30 bits, which keeps the squared length below
/// `3 * 2^60` (fits `u64`) while losing at most 2^-29 of relative precision.
pub(crate) fn normalize_i64(v: [i64; 3]) -> Option<[i32; 3]> {
    let s = fit_bits(v, 30)?;
    let len_sq: u64 = s.iter().map(|&c| (c * c) as u64).sum();
    let len = isqrt_u64(len_sq);
    if len == 0 {
        return None;
    }
    // One division for the three components: each quotient is exactly `(c << 30) / len`
    // (truncated towards zero), as three divisions would give. |s_i| <= len, so each is within
    // ±2^30 and fits i32.
    let inv = u64::MAX / len;
    Some(s.map(|c| {
        let q = div_with_inverse(c.unsigned_abs() << 30, len, inv) as i64;
        (if c < 0 { -q } else { q }) as i32
    }))
}

/// `floor(n / d)` for `1 <= d` and `n < 2^62`, given `inv = floor((2^64 − 1) / d)`: the
/// product estimate `n · inv / 2^64` is at most 2 below the quotient (`d · inv > 2^64 − 1 − d`
/// and `n / d < 2^62`), and the remainder corrects it exactly.
#[inline]
fn div_with_inverse(n: u64, d: u64, inv: u64) -> u64 {
    let mut q = ((n as u128 * inv as u128) >> 64) as u64;
    let mut r = n.wrapping_sub(q.wrapping_mul(d));
    while r >= d {
        q = q.wrapping_add(1);
        r -= d;
    }
    q
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

/// `v` shifted right (the same for every component) until each fits `bits` bits (`|c| <=
/// 2^bits`); `None` for the zero vector.
fn fit_bits(v: [i64; 3], bits: u32) -> Option<[i64; 3]> {
    let max = v.iter().map(|c| c.unsigned_abs()).max().unwrap_or(0);
    if max == 0 {
        return None;
    }
    let shift = (64 - max.leading_zeros()).saturating_sub(bits);
    Some(v.map(|c| c >> shift))
}

/// How precisely lighting normalizes normals, chosen at compile time (see
/// [`crate::preset::Arithmetic`]).
pub trait NormalPrecision:
    Copy + Default + core::fmt::Debug + PartialEq + Eq + sealed::Sealed + 'static
{
    /// Unit vector in I2F30 bits along `v`; `None` for the zero vector.
    fn normalize(v: [i64; 3]) -> Option<[i32; 3]>;
}

mod sealed {
    pub trait Sealed {}
    impl Sealed for super::WideNormals {}
    impl Sealed for super::NarrowNormals {}
}

/// Normals normalized in 64-bit integers to 30 bits (`normalize_i64`): the default.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct WideNormals;

/// Normals normalized in 32-bit integers to 15 bits (`normalize_i32`): a direction error
/// below 2^-13 rad, far below one 8-bit colour step, for a fraction of the cost on cores
/// without a 64-bit divider.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NarrowNormals;

impl NormalPrecision for WideNormals {
    #[inline]
    fn normalize(v: [i64; 3]) -> Option<[i32; 3]> {
        normalize_i64(v)
    }
}

impl NormalPrecision for NarrowNormals {
    #[inline]
    fn normalize(v: [i64; 3]) -> Option<[i32; 3]> {
        normalize_i32(v)
    }
}

/// [`normalize_i64`] to 15 bits in 32-bit arithmetic: the input is shifted until every
/// component fits 15 bits (so the squared length is below `3 * 2^30`, a `u32`), and each
/// component is divided in `i32` (`|c| << 15 <= 2^30`). The result is in I2F30 bits with its
/// low 15 bits zero.
pub(crate) fn normalize_i32(v: [i64; 3]) -> Option<[i32; 3]> {
    // Each component is now within ±2^15.
    let s = fit_bits(v, 15)?.map(|c| c as i32);
    let len_sq: u32 = s.iter().map(|&c| (c * c) as u32).sum();
    let len = len_sq.isqrt() as i32;
    if len == 0 {
        return None;
    }
    Some(s.map(|c| (c << 15).wrapping_div(len) << 15))
}

/// Dot product of two I2F30 vectors, result in I2F30 bits (each product is below 2^61).
#[inline]
pub(crate) fn dot_q30(a: [i32; 3], b: [i32; 3]) -> i32 {
    let sum: i64 = (0..3).map(|i| a[i] as i64 * b[i] as i64).sum();
    (sum >> 30) as i32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn square_root_and_division_are_exact() {
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
            let d = (x >> (x % 33)).max(1) % (1 << 31) + 1;
            let n = (x >> 2) ^ k;
            assert_eq!(div_with_inverse(n, d, u64::MAX / d), n / d, "{n} / {d}");
        }
        for d in [1u64, 2, 3, (1 << 31) - 1, 1 << 31] {
            for n in [0u64, 1, d - 1, d, d + 1, (1 << 62) - 1] {
                assert_eq!(div_with_inverse(n, d, u64::MAX / d), n / d, "{n} / {d}");
            }
        }
    }

    #[test]
    fn normalize_gives_unit_length_at_every_scale() {
        for scale in [1i64, 3, 1 << 20, 1 << 40, (1 << 55) + 12345] {
            let n = normalize_i64([3 * scale, -4 * scale, 0]).unwrap();
            let len_sq: i64 = n.iter().map(|&c| c as i64 * c as i64).sum();
            let one = 1i64 << 60;
            assert!((len_sq - one).abs() < one >> 26, "scale {scale}: {n:?}");
            assert!((n[0] as i64 - (3 << 30) / 5).abs() <= 2);
        }
        assert_eq!(normalize_i64([0, 0, 0]), None);
    }

    #[test]
    fn narrow_normals_are_unit_to_15_bits_and_agree_with_wide() {
        let mut x = 0x9e37_79b9u64;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x as i64) >> (x % 40) as u32
        };
        for _ in 0..2000 {
            let v = [next(), next(), next()];
            let (Some(wide), Some(narrow)) = (normalize_i64(v), normalize_i32(v)) else {
                assert_eq!(normalize_i32(v), None, "{v:?}");
                continue;
            };
            for k in 0..3 {
                // 15-bit truncation of the input and of the quotient: a few 2^-15 at most.
                let diff = (wide[k] as i64 - narrow[k] as i64).abs();
                assert!(diff <= 4 << 15, "{v:?}: {wide:?} {narrow:?}");
            }
        }
        assert_eq!(normalize_i32([0, 0, 0]), None);
        assert_eq!(normalize_i32([0, -7, 0]), Some([0, -(1 << 30), 0]));
        assert_eq!(
            normalize_i32([i64::MIN + 1, 0, 0]),
            Some([-(1 << 30), 0, 0])
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
