//! Vertex stage: fixed-point model→eye transform and Lambert lighting.
//!
//! # Bit budget
//!
//! * Model vertices are I16F16 within ±2^12 ([`MAX_MODEL_COORD`]).
//! * The model-view matrix is composed in `f32` once per frame and converted to I16F16 entries.
//!   Before use, [`ModelView::new`] proves with integers that every transformed vertex of the mesh
//!   satisfies `|x|, |y|, |z| <= 2^14` ([`MAX_EYE_COORD_BITS`]): `sum |m_ij| * max|v| + |t_i|`.
//!   Each product `m_ij * v_j` is then below 2^14 in value (2^46 in I32F32 bits) and the i64 sum
//!   cannot overflow. Eye coordinates are I16F16 with a 2× margin left for clipping.
//! * Lighting uses I2F30 unit vectors and intensities (`1.0 = 2^30`); products of two are below
//!   2^61 and summed three at a time in i64.
//!
//! [`MAX_MODEL_COORD`]: crate::scene::MAX_MODEL_COORD

use crate::math::{
    fit_bits, fixed_from_f32, i16f16_from_f32, mul_wide, zip3, NormalPrecision, NO_WIDE_MULTIPLY,
};
use crate::scene::{Coord, Light, Transform, Vertex};
use embedded_graphics::pixelcolor::{Rgb888, RgbColor};
use fixed::types::{I16F16, I2F30};

/// Largest |eye coordinate| the transform may produce, in I16F16 bits: 2^14 units.
pub const MAX_EYE_COORD_BITS: i64 = 1 << (14 + 16);

/// An eye-space point in I16F16. `w = −z_eye` is the distance in front of the camera.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EyePoint {
    /// Right.
    pub x: I16F16,
    /// Up.
    pub y: I16F16,
    /// Forward distance (−z).
    pub w: I16F16,
}

/// Why a per-frame transform could not be used.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TransformError {
    /// A matrix entry was NaN or infinite.
    NonFinite,
    /// Some vertex would land beyond ±2^14 eye units.
    OutOfEnvelope,
}

impl core::fmt::Display for TransformError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::NonFinite => "the model-view transform is not finite (NaN or infinity)",
            Self::OutOfEnvelope => {
                "a vertex would land beyond the eye-space envelope of ±16384 units (move the \
                 camera closer, or scale or split the model)"
            }
        })
    }
}

/// How precisely vertices are transformed, chosen at compile time (see
/// [`crate::arithmetic::Arithmetic`]).
pub trait TransformPrecision:
    Copy + Default + core::fmt::Debug + PartialEq + Eq + sealed::Sealed + 'static
{
    /// The per-instance transform in the form [`TransformPrecision::apply`] reads.
    type Matrix: Copy + core::fmt::Debug;
    /// Prepares `mv`, made for a mesh whose coordinates are within `max_abs_bits`, once per
    /// instance and frame.
    fn prepare(mv: ModelView, max_abs_bits: i32) -> Self::Matrix;
    /// Transforms a model vertex of the mesh `m` was prepared for.
    fn apply(m: &Self::Matrix, v: &Vertex) -> EyePoint;
}

mod sealed {
    pub trait Sealed {}
    impl Sealed for super::WideTransform {}
    impl Sealed for super::NarrowTransform {}
}

/// I16F16 × I16F16 products summed in `i64` and rounded once (`ModelView::apply`): eye
/// coordinates within 2^-17 units of the exact product of the I16F16 matrix and vertex. The
/// default.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct WideTransform;

/// 15-bit × 16-bit products summed in `i32` (`NarrowModelView`): one 32-bit multiply
/// per product instead of a 64-bit one, for an eye-space error of about 2^-14 of the mesh's
/// extent times the matrix's largest entry (see `NarrowModelView`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NarrowTransform;

impl TransformPrecision for WideTransform {
    type Matrix = ModelView;
    fn prepare(mv: ModelView, _: i32) -> ModelView {
        mv
    }
    #[inline]
    fn apply(mv: &ModelView, v: &Vertex) -> EyePoint {
        mv.apply(v)
    }
}

impl TransformPrecision for NarrowTransform {
    type Matrix = NarrowModelView;
    fn prepare(mv: ModelView, max_abs_bits: i32) -> NarrowModelView {
        NarrowModelView::new(&mv, max_abs_bits)
    }
    #[inline]
    fn apply(m: &NarrowModelView, v: &Vertex) -> EyePoint {
        m.apply(v)
    }
}

/// The model→eye transform of one instance, in I16F16, with the third row negated so that it
/// yields `w = −z` directly.
#[derive(Clone, Copy, Debug)]
pub struct ModelView {
    m: [[I16F16; 3]; 3],
    t: [I16F16; 3],
}

/// A [`ModelView`] narrowed for [`NarrowTransform`]: vertices are shifted right by
/// `vertex_shift` so they fit 16 bits (`|v| <= 2^15` for the mesh's largest coordinate), the
/// matrix entries are rounded to `|m| <= 2^14` by a common `matrix_shift`, so a row's three
/// products sum below `3 · 2^29` in `i32`; the sum is scaled back by `2^(matrix_shift +
/// vertex_shift − 16)` to I16F16. Rounding an entry errs by at most `2^(matrix_shift − 1) <=
/// 2^-14 · max|m|` and truncating a vertex coordinate by less than `2^vertex_shift <= 2^-14 ·
/// max|v|`, so an eye coordinate errs by at most `3 · 2^-13 · max|m| · max|v|` (the largest
/// product) plus one unit of I16F16 rounding: below 4·10^-4 of the mesh's extent for a
/// rotation, and typically far less.
#[derive(Clone, Copy, Debug)]
pub struct NarrowModelView {
    narrow: [[i32; 3]; 3],
    t: [I16F16; 3],
    vertex_shift: u32,
    /// `matrix_shift + vertex_shift − 16`: positive scales up, negative down.
    narrow_scale: i32,
}

impl ModelView {
    /// Composes `view ∘ model` and converts it, checking that a mesh whose coordinates are at
    /// most `max_abs_bits` (I16F16 bits) in magnitude stays inside the eye envelope.
    pub fn new(
        model: &Transform,
        view: &Transform,
        max_abs_bits: i32,
    ) -> Result<Self, TransformError> {
        if !model.is_finite() || !view.is_finite() {
            return Err(TransformError::NonFinite);
        }
        let mv = view.then_after(model);
        let mut m = [[I16F16::ZERO; 3]; 3];
        let mut t = [I16F16::ZERO; 3];
        for r in 0..3 {
            // Negating a float flips its sign bit: exactly `-1.0 * entry`.
            let signed = |entry: f32| if r == 2 { -entry } else { entry };
            let mut bound: i64 = 0;
            for (out, &entry) in m[r].iter_mut().zip(&mv.m[r][..3]) {
                let v = i16f16_from_f32(signed(entry)).ok_or(TransformError::OutOfEnvelope)?;
                *out = v;
                bound += (v.to_bits() as i64).abs() * max_abs_bits as i64;
            }
            let tv = i16f16_from_f32(signed(mv.m[r][3])).ok_or(TransformError::OutOfEnvelope)?;
            t[r] = tv;
            bound += (tv.to_bits() as i64).abs() << 16;
            if bound > MAX_EYE_COORD_BITS << 16 {
                return Err(TransformError::OutOfEnvelope);
            }
        }
        Ok(ModelView { m, t })
    }

    /// Transforms a model vertex (validated mesh, so inside the proven envelope).
    #[inline]
    pub fn apply(&self, v: &Vertex) -> EyePoint {
        if NO_WIDE_MULTIPLY {
            return self.apply_in_words(v);
        }
        let row = |r: usize| {
            let sum = self.m[r][0].to_bits() as i64 * v[0].to_bits() as i64
                + self.m[r][1].to_bits() as i64 * v[1].to_bits() as i64
                + self.m[r][2].to_bits() as i64 * v[2].to_bits() as i64
                + ((self.t[r].to_bits() as i64) << 16);
            // I32F32 -> I16F16, rounding to nearest; the envelope proof bounds the result.
            I16F16::from_bits(((sum + (1 << 15)) >> 16) as i32)
        };
        EyePoint {
            x: row(0),
            y: row(1),
            w: row(2),
        }
    }
}

impl ModelView {
    /// [`ModelView::apply`] from 32-bit multiplies, the same bits (test
    /// `transform_in_words_equals_the_64_bit_one`). With `v = vh·2^16 + vl` and
    /// `m = mh·2^16 + ml` (`vl`, `ml` the unsigned low halves), `m·v = (m·vh + mh·vl)·2^16 +
    /// ml·vl`, so the rounded row `⌊(Σ m·v + t·2^16 + 2^15) / 2^16⌋` is
    /// `Σ (m·vh + mh·vl) + t` plus the carry of the low products `⌊(Σ ml·vl + 2^15) / 2^16⌋`,
    /// taken from their halves so nothing exceeds 32 bits. The high part is summed modulo
    /// 2^32 (wrapping): the row's low 32 bits, as the 64-bit path's `as i32` keeps them.
    #[inline]
    fn apply_in_words(&self, v: &Vertex) -> EyePoint {
        let v = v.map(|c| c.to_bits());
        let row = |r: usize| {
            let mut high = self.t[r].to_bits();
            let (mut carry_high, mut carry_low) = (0u32, 1u32 << 15);
            for (m, &v) in self.m[r].iter().zip(&v) {
                let m = m.to_bits();
                let (vh, vl) = (v >> 16, v as u32 & 0xFFFF);
                let (mh, ml) = (m >> 16, m as u32 & 0xFFFF);
                high = high
                    .wrapping_add(m.wrapping_mul(vh))
                    .wrapping_add(mh.wrapping_mul(vl as i32));
                // ml·vl < 2^32; the three halves' sums stay below 2^18.
                let low = ml * vl;
                carry_high += low >> 16;
                carry_low += low & 0xFFFF;
            }
            I16F16::from_bits(high.wrapping_add((carry_high + (carry_low >> 16)) as i32))
        };
        EyePoint {
            x: row(0),
            y: row(1),
            w: row(2),
        }
    }
}

impl NarrowModelView {
    /// Narrows `mv`, made for a mesh whose coordinates are within `max_abs_bits` (I16F16 bits).
    pub fn new(mv: &ModelView, max_abs_bits: i32) -> Self {
        let bits = |v: u32| 32 - v.leading_zeros();
        let vertex_shift = bits(max_abs_bits.unsigned_abs()).saturating_sub(15);
        let largest =
            mv.m.iter()
                .flatten()
                .map(|e| e.to_bits().unsigned_abs())
                .max();
        let matrix_shift = bits(largest.unwrap_or(0)).saturating_sub(14);
        let narrow = mv.m.map(|row| {
            row.map(|e| {
                let e = e.to_bits() as i64;
                // Round to nearest; |e| < 2^(matrix_shift + 14), so the result is within ±2^14.
                let half = (1i64 << matrix_shift) >> 1;
                ((e + half) >> matrix_shift) as i32
            })
        });
        NarrowModelView {
            narrow,
            t: mv.t,
            vertex_shift,
            narrow_scale: matrix_shift as i32 + vertex_shift as i32 - 16,
        }
    }

    /// [`ModelView::apply`] with 32-bit products (error bound above).
    #[inline]
    pub fn apply(&self, v: &Vertex) -> EyePoint {
        let v = v.map(|c| c.to_bits() >> self.vertex_shift);
        let scale = self.narrow_scale;
        let row = |r: usize| {
            let [a, b, c] = self.narrow[r];
            // |a·v0 + b·v1 + c·v2| <= 3 · 2^14 · 2^15 < 2^31.
            let sum = a * v[0] + b * v[1] + c * v[2];
            let scaled = if scale >= 0 {
                sum.wrapping_shl(scale as u32)
            } else {
                let down = scale.unsigned_abs().min(31);
                sum.wrapping_add((1 << down) >> 1) >> down
            };
            I16F16::from_bits(scaled.wrapping_add(self.t[r].to_bits()))
        };
        EyePoint {
            x: row(0),
            y: row(1),
            w: row(2),
        }
    }
}

/// Per-instance lighting constants: light direction and the normal transform, in I2F30.
#[derive(Clone, Copy, Debug)]
pub struct Lighting {
    /// Cofactor matrix of the model's linear part, scaled so its largest entry is ±1 (I2F30
    /// bits). It maps model-space cross products to world-space cross products exactly (up to
    /// scale), which is what a face normal is; `flip` fixes the sign for vertex normals under
    /// mirroring transforms.
    normal_matrix: [[i32; 3]; 3],
    /// `normal_matrix` is the identity (2^30 on the diagonal, as for a model transform with
    /// no rotation or scale): the products it would take leave a normal's direction, and the
    /// bits lighting keeps of it, unchanged ([`Self::normal_to_world`]).
    identity: bool,
    flip: bool,
    direction: [i32; 3],
    ambient: I2F30,
    diffuse: I2F30,
}

/// `v` in I2F30 bits, rounded to nearest (ties to even, as `fixed` rounds) and saturated; NaN
/// gives 0. Written out because `fixed`'s saturating conversion panics on NaN, and the render
/// path must not contain a panic (`examples/panic_never.rs` checks that at link time). The
/// rounding is [`fixed_from_f32`]'s (integer operations on the float's bits, shared with the
/// I16F16 conversions); out of range it saturates by the sign bit, as `as i32` would.
fn q30(v: f32) -> i32 {
    let bits = v.to_bits();
    match fixed_from_f32(v, 30) {
        Some(q) => q,
        // NaN (an all-ones exponent and a non-zero mantissa), tested on the bits: a float
        // comparison would be a soft-float call.
        None if bits & 0x7FFF_FFFF > 0x7F80_0000 => 0,
        None if bits >> 31 != 0 => i32::MIN,
        None => i32::MAX,
    }
}

impl Lighting {
    /// No lighting: what a render with [`Unlit`](crate::shading::Unlit) shading keeps per
    /// instance instead of [`Lighting::new`] (never used to light; every intensity from it is
    /// 0), so that build computes no lighting set-up either.
    pub const NONE: Lighting = Lighting {
        normal_matrix: [[0; 3]; 3],
        identity: false,
        flip: false,
        direction: [0; 3],
        ambient: I2F30::ZERO,
        diffuse: I2F30::ZERO,
    };

    /// Lighting for one instance with the given model transform (finite, checked by the caller).
    pub fn new(light: &Light, model: &Transform) -> Lighting {
        let a = &model.m;
        let cof = |r0: usize, r1: usize, c0: usize, c1: usize| {
            a[r0][c0] * a[r1][c1] - a[r0][c1] * a[r1][c0]
        };
        let c = [
            [cof(1, 2, 1, 2), -cof(1, 2, 0, 2), cof(1, 2, 0, 1)],
            [-cof(0, 2, 1, 2), cof(0, 2, 0, 2), -cof(0, 2, 0, 1)],
            [cof(0, 1, 1, 2), -cof(0, 1, 0, 2), cof(0, 1, 0, 1)],
        ];
        let det = a[0][0] * c[0][0] + a[0][1] * c[0][1] + a[0][2] * c[0][2];
        let max = c.iter().flatten().fold(0.0f32, |m, v| m.max(v.abs()));
        let scale = if max > 0.0 && max.is_finite() {
            1.0 / max
        } else {
            0.0
        };
        let normal_matrix = c.map(|row| row.map(|v| q30(v * scale)));
        // Every entry's difference from the identity's, or-ed (no `memcmp` call).
        let off_identity = (0..3).fold(0, |acc, i| {
            (0..3).fold(acc, |acc, j| {
                let one = if i == j { 1 << 30 } else { 0 };
                acc | (normal_matrix[i][j] ^ one)
            })
        });
        Lighting {
            normal_matrix,
            identity: off_identity == 0,
            flip: det < 0.0,
            direction: light.direction().map(q30),
            ambient: I2F30::from_bits(q30(light.ambient())),
            diffuse: I2F30::from_bits(q30(light.diffuse())),
        }
    }

    /// Intensity of a world-space normal `n` (any non-zero scale).
    fn intensity_of_world_normal<N: NormalPrecision>(&self, n: [i64; 3]) -> I2F30 {
        self.intensity(N::cosine(n, self.direction).unwrap_or(0).max(0))
    }

    /// Intensity for the Lambert term `lambert` (I2F30 bits, at least 0): non-decreasing in it.
    #[inline]
    fn intensity(&self, lambert: i32) -> I2F30 {
        let i = self.ambient.to_bits() as i64 + (mul_wide(self.diffuse.to_bits(), lambert) >> 30);
        I2F30::from_bits(i.clamp(0, 1 << 30) as i32)
    }

    /// Model-space normal `n` (any scale) in world space, up to scale: `n` is first brought to
    /// 30 bits, so with the matrix's entries within ±2^30 each product is below 2^60 and each
    /// sum below 3 · 2^60. No normalization here: the cosine divides by the length once.
    fn normal_to_world(&self, n: [i64; 3]) -> Option<[i64; 3]> {
        // |n_k| <= 2^30 fits `i32`: 32 × 32 → 64-bit products.
        let n = fit_bits(n, 30)?;
        if self.identity {
            // The product would be `n · 2^30`, which the cosine's `fit_bits` shifts back to
            // what it makes of `n` itself (a power-of-two scale changes only its shift): nine
            // 64-bit products fewer (four multiplies each on ARMv6-M). Test
            // `identity_normal_matrix_changes_no_bits`.
            return Some(n.map(i64::from));
        }
        Some(
            self.normal_matrix
                .map(|row| (0..3).map(|k| mul_wide(row[k], n[k])).sum()),
        )
    }

    /// Intensity of a face with model-space vertices `v` (counter-clockwise = front), with
    /// the cosine taken at precision `N`.
    pub fn face<N: NormalPrecision>(&self, v: [&Vertex; 3]) -> I2F30 {
        self.cross_product::<N>(face_normal(v))
    }
}

/// The model-space normal of a face with vertices `v` (counter-clockwise = front), not
/// normalized: the cross product of two edges.
///
/// Bit budget: a validated mesh's coordinates are within ±[`MAX_MODEL_COORD`] = 2^12 units,
/// ±2^28 in I16F16 bits, so an edge component is within ±2^29 and fits `i32`; each product
/// of two is at most 2^58 in magnitude (a 32 × 32 → 64-bit [`mul_wide`]) and each difference
/// of two at most 2^59, in `i64`. That is the cross product the `i64` edges gave. (Vertices
/// outside the envelope, which no validated mesh has, wrap in the edge subtraction instead of
/// overflowing the `i64` products; neither is meaningful.) Test `face_normal_at_the_extremes`.
///
/// [`MAX_MODEL_COORD`]: crate::scene::MAX_MODEL_COORD
#[inline]
fn face_normal(v: [&Vertex; 3]) -> [i64; 3] {
    let [a, b, c] = v;
    let d = |p: Coord, q: Coord| q.to_bits().wrapping_sub(p.to_bits());
    let (e1, e2) = (zip3(*a, *b, d), zip3(*a, *c, d));
    if NO_WIDE_MULTIPLY {
        if let Some(n) = short_edge_normal(e1, e2) {
            return n;
        }
    }
    let cross = |a: i32, b: i32, c: i32, d: i32| mul_wide(a, b) - mul_wide(c, d);
    [
        cross(e1[1], e2[2], e1[2], e2[1]),
        cross(e1[2], e2[0], e1[0], e2[2]),
        cross(e1[0], e2[1], e1[1], e2[0]),
    ]
}

/// [`face_normal`] for edges `e1`, `e2` whose components are all below 2^15 in magnitude (half
/// a unit, raw I16F16), `None` for others: each product is then below 2^30 and each
/// difference below 2^31, so one 32-bit multiply each gives the cross product where a 64-bit
/// product takes four (ARMv6-M). The same values (test `short_edge_normal_is_the_cross_product`).
#[inline]
fn short_edge_normal(e1: [i32; 3], e2: [i32; 3]) -> Option<[i64; 3]> {
    let or = e1.iter().chain(&e2).fold(0, |m, c| m | c.unsigned_abs());
    if or >= 1 << 15 {
        return None;
    }
    let cross = |a: i32, b: i32, c: i32, d: i32| (a * b - c * d) as i64;
    Some([
        cross(e1[1], e2[2], e1[2], e2[1]),
        cross(e1[2], e2[0], e1[0], e2[2]),
        cross(e1[0], e2[1], e1[1], e2[0]),
    ])
}

impl Lighting {
    /// `shade(base, self.face::<N>(v))`, mostly without the exact cosine: each channel is a
    /// non-decreasing function of the Lambert term, so where the colours at both ends of
    /// [`NormalPrecision::lambert`] agree, every term between gives that colour, the
    /// exact one included. Else (a colour step inside the bounds, a few faces in a hundred)
    /// the exact term decides ([`crate::math::Lambert::exact`], from the bounds' own values). Test `face_color_equals_the_shaded_face`.
    // Not inlined: in its caller it made the lean minimal build's render stack on thumbv6m
    // 1,264 B instead of 1,192 B, over the 4 KiB RAM budget with the workspace.
    #[inline(never)]
    pub fn face_color<N: NormalPrecision>(&self, base: Rgb888, v: [&Vertex; 3]) -> Rgb888 {
        self.cross_product_color::<N>(base, face_normal(v))
    }

    /// `shade(base, self.cross_product::<N>(n))`, mostly without the exact cosine, as
    /// [`Self::face_color`] (which is this for the face's normal). Test
    /// `cross_product_color_equals_the_shaded_cross_product`.
    #[inline]
    pub fn cross_product_color<N: NormalPrecision>(&self, base: Rgb888, n: [i64; 3]) -> Rgb888 {
        // Not on ARMv6-M, where the lean builds' flash matters more: the second copy of the
        // bounds' code cost 856 B of the lean minimal build for 0.5 % of a demo frame.
        let lambert = if !NO_WIDE_MULTIPLY && self.identity {
            // `normal_to_world` would give `n` fitted to 30 bits, which the Lambert bounds
            // would fit again to the same vector: fitted once here (test
            // `fitted_lambert_is_the_lambert_of_the_fitted_vector`).
            let Some(s) = fit_bits(n, 30) else {
                return shade(base, self.ambient);
            };
            N::lambert_fitted(s, self.direction)
        } else {
            let Some(w) = self.normal_to_world(n) else {
                return shade(base, self.ambient);
            };
            let Some(lambert) = N::lambert(w, self.direction) else {
                return shade(base, self.intensity(0)); // (the exact cosine's zero vector)
            };
            lambert
        };
        let low = shade(base, self.intensity(lambert.lo));
        if lambert.lo == lambert.hi || shade(base, self.intensity(lambert.hi)) == low {
            return low;
        }
        shade(base, self.intensity(lambert.exact()))
    }

    /// Intensity of a surface whose model-space normal is the cross product `n` of two model
    /// tangents (each component within ±2^62; any non-zero scale), with the cosine taken at
    /// precision `N`. Mirroring needs no sign fix here: the cofactor matrix maps cross products.
    pub fn cross_product<N: NormalPrecision>(&self, n: [i64; 3]) -> I2F30 {
        match self.normal_to_world(n) {
            Some(w) => self.intensity_of_world_normal::<N>(w),
            None => self.ambient,
        }
    }

    /// Intensity at a vertex with model-space normal `n` (any non-zero length), with the
    /// cosine taken at precision `N`.
    pub fn vertex<N: NormalPrecision>(&self, n: &Vertex) -> I2F30 {
        match self.normal_to_world(n.map(|c| c.to_bits() as i64)) {
            Some(w) => {
                let w = if self.flip { w.map(|c| -c) } else { w };
                self.intensity_of_world_normal::<N>(w)
            }
            None => self.ambient,
        }
    }
}

/// `base * intensity` per channel, rounded to nearest.
#[inline]
pub fn shade(base: Rgb888, intensity: I2F30) -> Rgb888 {
    let bits = intensity.to_bits();
    // An intensity in [0, 1], every one lighting gives, in 32-bit multiplies on every target:
    // fewer instructions than 64-bit products and clamps even where a 64-bit product is one.
    if (0..=1 << 30).contains(&bits) {
        return shade_in_words(base, bits as u32);
    }
    let i = bits as i64;
    let ch = |c: u8| (((c as i64 * i) + (1 << 29)) >> 30).clamp(0, 255) as u8;
    Rgb888::new(ch(base.r()), ch(base.g()), ch(base.b()))
}

/// [`shade`] for an intensity `i` in `[0, 2^30]` in 32-bit multiplies, the same channels:
/// with `i = ih·2^8 + il`, `⌊(c·i + 2^29) / 2^30⌋ = ⌊(c·ih + ⌊(c·il + 2^29) / 2^8⌋) / 2^22⌋`,
/// whose sum stays below 2^31 for `c <= 255`.
#[inline]
fn shade_in_words(base: Rgb888, i: u32) -> Rgb888 {
    let (ih, il) = (i >> 8, i & 0xFF);
    let ch = |c: u8| {
        let c = c as u32;
        ((c * ih + ((c * il + (1 << 29)) >> 8)) >> 22).min(255) as u8
    };
    Rgb888::new(ch(base.r()), ch(base.g()), ch(base.b()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn q30_rounds_exactly_like_f64() {
        let reference = |v: f32| libm::rint(v as f64 * (1u64 << 30) as f64) as i32;
        let mut rng = crate::test_rng::XorShift32::new(0x1234_5678);
        let mut values = std::vec![0.0, -0.0, 0.5, -1.0, 1.999_999_9, 2.0, -2.0, 1e-10, 3.7e-9];
        values.extend([
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::MAX,
            f32::MIN_POSITIVE,
        ]);
        for _ in 0..200_000 {
            // Bit patterns across all exponents, plus values in the useful range.
            let x = rng.next_u32();
            values.push(f32::from_bits(x));
            values.push((x as f32 / u32::MAX as f32) * 4.0 - 2.0);
        }
        for v in values {
            assert_eq!(q30(v), reference(v), "{v:e}");
        }
    }
    use crate::scene::Coord;

    fn v(x: f32, y: f32, z: f32) -> Vertex {
        [Coord::from_num(x), Coord::from_num(y), Coord::from_num(z)]
    }

    #[test]
    fn model_view_matches_float_composition() {
        let model = Transform::rotation_y(0.7).then_after(&Transform::scale([1.5; 3]));
        let view = crate::scene::Camera::look_at([3.0, 2.0, 5.0], [0.0; 3], [0.0, 1.0, 0.0])
            .unwrap()
            .world_to_eye;
        let p = v(0.75, -1.25, 2.0);
        let mv = ModelView::new(
            &model,
            &view,
            p.iter().map(|c| c.to_bits().abs()).max().unwrap(),
        )
        .unwrap();
        let e = mv.apply(&p);
        let f = view.then_after(&model).apply([0.75, -1.25, 2.0]);
        assert!((e.x.to_num::<f32>() - f[0]).abs() < 1e-3);
        assert!((e.y.to_num::<f32>() - f[1]).abs() < 1e-3);
        assert!((e.w.to_num::<f32>() + f[2]).abs() < 1e-3);
    }

    #[test]
    fn transform_in_words_equals_the_64_bit_one() {
        let mut rng = crate::test_rng::XorShift64::new(0x9e37_79b9_7f4a_7c15u64);
        let mut next = |bits: u32| {
            let x = rng.next_u64();
            (x as i64 >> (64 - bits)) as i32
        };
        for case in 0..200_000 {
            // Matrix entries and vertices of every size, up to the model envelope (2^28 bits)
            // and full I16F16 entries, so products near 2^59 and rows of any sign are tried.
            let mb = 1 + (case % 32) as u32;
            let vb = 1 + (case / 32 % 29) as u32;
            let mv = ModelView {
                m: [(); 3].map(|_| [(); 3].map(|_| I16F16::from_bits(next(mb)))),
                t: [(); 3].map(|_| I16F16::from_bits(next(32))),
            };
            let p = [(); 3].map(|_| I16F16::from_bits(next(vb)));
            let want = [0, 1, 2].map(|r| {
                let sum: i128 = (0..3)
                    .map(|k| mv.m[r][k].to_bits() as i128 * p[k].to_bits() as i128)
                    .sum::<i128>()
                    + ((mv.t[r].to_bits() as i128) << 16);
                ((sum + (1 << 15)) >> 16) as i32
            });
            let got = mv.apply_in_words(&p);
            assert_eq!(
                [got.x, got.y, got.w].map(|c| c.to_bits()),
                want,
                "case {case}"
            );
            let wide = mv.apply(&p);
            assert_eq!((wide.x, wide.y, wide.w), (got.x, got.y, got.w));
        }
    }

    #[test]
    fn envelope_is_enforced() {
        let big = Transform::scale([8.0; 3]);
        let ok = ModelView::new(&big, &Transform::IDENTITY, 1000 << 16);
        assert!(ok.is_ok());
        let too_far = ModelView::new(&big, &Transform::IDENTITY, 4096 << 16);
        assert_eq!(too_far.unwrap_err(), TransformError::OutOfEnvelope);
        let nan = Transform::translation([f32::NAN, 0.0, 0.0]);
        assert_eq!(
            ModelView::new(&nan, &Transform::IDENTITY, 1).unwrap_err(),
            TransformError::NonFinite
        );
    }

    #[test]
    fn narrow_transform_stays_within_its_bound() {
        let view = crate::scene::Camera::look_at([3.0, 2.0, 5.0], [0.0; 3], [0.0, 1.0, 0.0])
            .unwrap()
            .world_to_eye;
        let mut rng = crate::test_rng::XorShift32::new(0x2545_f491u32);
        let mut next = |range: f32| {
            let x = rng.next_u32();
            (x as f32 / u32::MAX as f32 * 2.0 - 1.0) * range
        };
        for &(extent, scale) in &[(1.0f32, 1.0f32), (0.01, 3.0), (100.0, 0.5), (1000.0, 2.0)] {
            for _ in 0..50 {
                let model = Transform::rotation_y(next(3.0))
                    .then_after(&Transform::rotation_x(next(3.0)))
                    .then_after(&Transform::scale([scale; 3]));
                let p = v(next(extent), next(extent), next(extent));
                let max = (extent * 65536.0) as i32;
                let mv = ModelView::new(&model, &view, max).unwrap();
                let (wide, narrow) = (mv.apply(&p), NarrowModelView::new(&mv, max).apply(&p));
                // The documented bound, in I16F16 bits.
                let m =
                    mv.m.iter()
                        .flatten()
                        .map(|e| e.to_bits().abs())
                        .max()
                        .unwrap();
                let bound = 3.0 * (m as f64 * max as f64 / 65536.0) / 8192.0 + 1.0;
                for (a, b) in [(wide.x, narrow.x), (wide.y, narrow.y), (wide.w, narrow.w)] {
                    let err = (a.to_bits() as f64 - b.to_bits() as f64).abs();
                    assert!(
                        err <= bound,
                        "extent {extent} scale {scale}: {a} {b} > {bound}"
                    );
                }
            }
        }
    }

    #[test]
    fn narrow_and_wide_normals_light_alike() {
        use crate::math::{NarrowNormals, WideNormals};
        let light = Light::new([0.3, 0.5, 1.0], 0.2, 0.8).unwrap();
        let l = Lighting::new(&light, &Transform::rotation_x(0.4));
        let (a, b) = (v(0.0, 0.0, 0.0), v(1.0, 0.1, 0.0));
        for k in 0..64 {
            let t = k as f32 * 0.1;
            let c = v(libm::cosf(t), libm::sinf(t), 0.5);
            let wide = l.face::<WideNormals>([&a, &b, &c]).to_bits();
            let narrow = l.face::<NarrowNormals>([&a, &b, &c]).to_bits();
            // Well below one 8-bit colour step (2^22 in I2F30 bits).
            assert!((wide - narrow).abs() < 1 << 17, "{t}: {wide} {narrow}");
        }
    }

    #[test]
    fn lambert_face_lighting() {
        use crate::math::WideNormals as W;
        let light = Light::new([0.0, 0.0, 1.0], 0.25, 0.75).unwrap();
        let l = Lighting::new(&light, &Transform::IDENTITY);
        let (a, b, c) = (v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0));
        // Faces +z: full light.
        assert_eq!(l.face::<W>([&a, &b, &c]), I2F30::from_bits(1 << 30));
        // Faces -z: ambient only.
        assert_eq!(l.face::<W>([&a, &c, &b]), I2F30::from_num(0.25));
        // Rotated 60° away: 0.25 + 0.75 * 0.5.
        let r = Lighting::new(&light, &Transform::rotation_x(core::f32::consts::FRAC_PI_3));
        let i: f32 = r.face::<W>([&a, &b, &c]).to_num();
        assert!((i - 0.625).abs() < 1e-5, "{i}");
        // Mirroring z leaves this z = 0 triangle where it is (still facing +z, fully lit) but
        // turns a +z vertex normal into -z.
        let m = Lighting::new(&light, &Transform::scale([1.0, 1.0, -1.0]));
        assert_eq!(m.face::<W>([&a, &b, &c]), I2F30::from_bits(1 << 30));
        assert_eq!(m.vertex::<W>(&v(0.0, 0.0, 1.0)), I2F30::from_num(0.25));
        assert_eq!(m.vertex::<W>(&v(0.0, 0.0, -3.0)), I2F30::from_bits(1 << 30));
    }

    /// The short-edge face normal is the exact cross product wherever it answers, and it
    /// answers exactly when every edge component is below 2^15 (both sides of the bound).
    #[test]
    fn short_edge_normal_is_the_cross_product() {
        let wide = |a: [i32; 3], b: [i32; 3]| {
            let c = |i: usize, j: usize| a[i] as i64 * b[j] as i64 - a[j] as i64 * b[i] as i64;
            [c(1, 2), c(2, 0), c(0, 1)]
        };
        let mut rng = crate::test_rng::XorShift64::new(0x9e37_79b9_7f4a_7c15);
        let edges = [0, 1, -1, (1 << 15) - 1, -(1 << 15) + 1, 1 << 15, -(1 << 15)];
        let mut pick = |k: u64| match k % 4 {
            0 => edges[(rng.next_u64() % edges.len() as u64) as usize],
            _ => (rng.next_u64() as i32) >> (rng.next_u64() % 32),
        };
        let (mut short, mut long) = (0, 0);
        for k in 0..400_000u64 {
            let (a, b) = ([(); 3].map(|_| pick(k)), [(); 3].map(|_| pick(k >> 2)));
            let fits = a.iter().chain(&b).all(|c| c.unsigned_abs() < 1 << 15);
            match short_edge_normal(a, b) {
                Some(n) => {
                    assert_eq!(n, wide(a, b), "{a:?} {b:?}");
                    short += 1;
                }
                None => long += 1,
            }
            assert_eq!(short_edge_normal(a, b).is_some(), fits, "{a:?} {b:?}");
        }
        assert!(short > 10_000 && long > 10_000, "{short} {long}");
    }

    /// The face normal from `i32` edges equals the cross product in `i128` for vertices at
    /// the ends of the model envelope (every corner of the ±2^28-bit cube, and edges of
    /// ±2^29 on every axis), and for random ones inside it.
    #[test]
    fn face_normal_at_the_extremes() {
        use crate::scene::MAX_MODEL_COORD;
        let max = MAX_MODEL_COORD << 16;
        let wide = |v: [&Vertex; 3]| -> [i64; 3] {
            let d =
                |a: &Vertex, b: &Vertex, k: usize| b[k].to_bits() as i128 - a[k].to_bits() as i128;
            let e1 = [0, 1, 2].map(|k| d(v[0], v[1], k));
            let e2 = [0, 1, 2].map(|k| d(v[0], v[2], k));
            let n = [
                e1[1] * e2[2] - e1[2] * e2[1],
                e1[2] * e2[0] - e1[0] * e2[2],
                e1[0] * e2[1] - e1[1] * e2[0],
            ];
            n.map(|c| i64::try_from(c).unwrap())
        };
        let corner =
            |k: u32| [0, 1, 2].map(|a| Coord::from_bits(if k >> a & 1 == 0 { -max } else { max }));
        let mut largest = 0;
        for a in 0..8 {
            for b in 0..8 {
                for c in 0..8 {
                    let v = [corner(a), corner(b), corner(c)];
                    let n = face_normal([&v[0], &v[1], &v[2]]);
                    assert_eq!(n, wide([&v[0], &v[1], &v[2]]), "{a} {b} {c}");
                    largest = largest.max(n.iter().map(|c| c.unsigned_abs()).max().unwrap());
                }
            }
        }
        // Edges of ±2^29 on two axes: the products reach 2^58, and so do the components (a
        // triangle in the cube is at most that large; 2^59 bounds the difference).
        assert_eq!(largest, 1 << 58);
        let mut rng = crate::test_rng::XorShift64::new(0x2545_f491_4f6c_dd1du64);
        for _ in 0..200_000 {
            let v = [(); 3].map(|_| {
                [(); 3].map(|_| {
                    let x = rng.next_u64();
                    let c = (x as i32) >> (x >> 59);
                    Coord::from_bits(c.clamp(-max, max))
                })
            });
            let v = [&v[0], &v[1], &v[2]];
            assert_eq!(face_normal(v), wide(v), "{v:?}");
        }
    }

    #[test]
    fn shade_in_words_equals_shade() {
        let wide = |c: u8, i: u32| (((c as i64 * i as i64) + (1 << 29)) >> 30).clamp(0, 255);
        let mut rng = crate::test_rng::XorShift32::new(0x2545_f491u32);
        for step in 0..400_000u32 {
            let x = rng.next_u32();
            // Every intensity near each channel's rounding points, and random ones.
            let i = match step % 2 {
                0 => x % ((1 << 30) + 1),
                _ => (((x % 256) << 30) / 255 + (x >> 28)).min(1 << 30),
            };
            let base = Rgb888::new(x as u8, (x >> 8) as u8, (step % 256) as u8);
            let got = shade_in_words(base, i);
            let want = [base.r(), base.g(), base.b()].map(|c| wide(c, i) as u8);
            assert_eq!([got.r(), got.g(), got.b()], want, "{base:?} {i}");
        }
        for c in [0u8, 1, 127, 128, 254, 255] {
            for i in [0u32, 1, 1 << 29, (1 << 30) - 1, 1 << 30] {
                let got = shade_in_words(Rgb888::new(c, c, c), i);
                assert_eq!(got.r() as i64, wide(c, i), "{c} {i}");
            }
        }
    }

    /// With the identity normal matrix, skipping its products gives the cosine the same
    /// 30-bit vector, and so every lighting result the same bits: cross products of every
    /// length (powers of two, their neighbours, negative ones that round to -2^30), random ones.
    #[test]
    fn identity_normal_matrix_changes_no_bits() {
        use crate::math::{NarrowNormals, WideNormals};
        let light = Light::new([0.3, -0.8, 0.5], 0.2, 0.7).unwrap();
        let fast = Lighting::new(&light, &Transform::IDENTITY);
        assert!(fast.identity);
        let slow = Lighting {
            identity: false,
            ..fast
        };
        let mut rng = crate::test_rng::XorShift64::new(0x6a09_e667_f3bc_c908u64);
        let mut cases: std::vec::Vec<[i64; 3]> = std::vec::Vec::new();
        for k in 0..62 {
            for m in [(1i64 << k) - 1, 1 << k, (1 << k) + 1] {
                for m in [m, -m] {
                    cases.extend([
                        [m, 0, 0],
                        [1, m, -1],
                        [-3, 5, m],
                        [m, m, -m],
                        [m, -m >> 1, 7],
                    ]);
                }
            }
        }
        for _ in 0..100_000 {
            let mut c = || (rng.next_u64() as i64) >> (rng.next_u64() % 63 + 1);
            cases.push([c(), c(), c()]);
        }
        let base = Rgb888::new(200, 117, 31);
        for n in cases {
            let (f, s) = (fast.normal_to_world(n), slow.normal_to_world(n));
            assert_eq!(
                f.and_then(|w| fit_bits(w, 30)),
                s.and_then(|w| fit_bits(w, 30)),
                "{n:?}"
            );
            assert_eq!(
                fast.cross_product_color::<WideNormals>(base, n),
                slow.cross_product_color::<WideNormals>(base, n),
                "{n:?}"
            );
            assert_eq!(
                fast.cross_product::<NarrowNormals>(n),
                slow.cross_product::<NarrowNormals>(n),
                "{n:?}"
            );
        }
    }

    #[test]
    fn face_color_equals_the_shaded_face() {
        use crate::math::{NarrowNormals, WideNormals};
        let mut rng = crate::test_rng::XorShift32::new(0x9e37_79b9u32);
        let mut next = |range: f32| {
            let x = rng.next_u32();
            (x as f32 / u32::MAX as f32 * 2.0 - 1.0) * range
        };
        let mut exact_needed = 0;
        for case in 0..4_000 {
            let light = Light::new(
                [next(1.0), next(1.0), 1.0],
                next(0.5) + 0.5,
                next(0.5) + 0.5,
            )
            .unwrap();
            let model = Transform::rotation_y(next(3.0))
                .then_after(&Transform::rotation_x(next(3.0)))
                .then_after(&Transform::scale([next(2.0) + 2.5, 1.0, next(0.9) + 1.0]));
            let l = Lighting::new(&light, &model);
            for _ in 0..25 {
                let size = [1.0f32, 0.01, 100.0, 2000.0][case % 4];
                let [a, b, c] = [(); 3].map(|_| v(next(size), next(size), next(size)));
                let c2 = v(a[0].to_num::<f32>() + 1e-3, a[1].to_num(), a[2].to_num());
                for [a, b, c] in [[a, b, c], [a, b, c2]] {
                    let base = Rgb888::new(next(128.0) as u8 + 127, 255, case as u8);
                    let want = shade(base, l.face::<WideNormals>([&a, &b, &c]));
                    assert_eq!(l.face_color::<WideNormals>(base, [&a, &b, &c]), want);
                    let narrow = shade(base, l.face::<NarrowNormals>([&a, &b, &c]));
                    assert_eq!(l.face_color::<NarrowNormals>(base, [&a, &b, &c]), narrow);
                    let w = l.normal_to_world(face_normal([&a, &b, &c]));
                    let bounds = w.and_then(|w| WideNormals::lambert(w, l.direction));
                    if let Some(crate::math::Lambert { lo, hi, .. }) = bounds {
                        exact_needed +=
                            (shade(base, l.intensity(lo)) != shade(base, l.intensity(hi))) as u32;
                    }
                }
            }
        }
        // The bounds decide almost every face (a few in a hundred need the exact cosine).
        assert!(exact_needed < 200_000 / 20, "{exact_needed}");
    }

    #[test]
    fn cross_product_color_equals_the_shaded_cross_product() {
        use crate::math::{NarrowNormals, WideNormals};
        let mut rng = crate::test_rng::XorShift64::new(0x2545_f491_4f6c_dd1du64);
        let mut next = || rng.next_u64();
        for case in 0..20_000u32 {
            let r = |next: &mut dyn FnMut() -> u64| (next() >> 40) as f32 / (1u64 << 24) as f32;
            let light = Light::new(
                [r(&mut next) - 0.5, r(&mut next) - 0.5, 1.0],
                r(&mut next) * 0.5,
                r(&mut next) * 0.5 + 0.5,
            )
            .unwrap();
            let model = Transform::rotation_y(r(&mut next) * 6.0)
                .then_after(&Transform::rotation_x(r(&mut next) * 6.0))
                .then_after(&Transform::scale([r(&mut next) + 0.5, 1.0, 2.0]));
            let l = Lighting::new(&light, &model);
            // Components of every size up to ±2^62, zero and the extremes among them.
            let bits = 1 + case % 62;
            let mut c = || match next() % 16 {
                0 => 0,
                1 => 1 << 62,
                2 => -(1 << 62),
                _ => (next() as i64) >> (63 - bits),
            };
            let n = [c(), c(), c()];
            let base = Rgb888::new(next() as u8, next() as u8, next() as u8);
            let wide = shade(base, l.cross_product::<WideNormals>(n));
            assert_eq!(l.cross_product_color::<WideNormals>(base, n), wide, "{n:?}");
            let narrow = shade(base, l.cross_product::<NarrowNormals>(n));
            assert_eq!(
                l.cross_product_color::<NarrowNormals>(base, n),
                narrow,
                "{n:?}"
            );
        }
    }

    #[test]
    fn shade_scales_channels() {
        let c = shade(Rgb888::new(200, 100, 0), I2F30::from_num(0.5));
        assert_eq!(c, Rgb888::new(100, 50, 0));
        assert_eq!(
            shade(Rgb888::new(255, 255, 255), I2F30::from_bits(1 << 30)),
            Rgb888::WHITE
        );
    }
}
