//! Named precision presets: each choice that trades accuracy for speed or size, bundled and
//! fixed at compile time so a build pays only for the one it uses.
//!
//! | preset | sub-pixel bits | set-up arithmetic | set-up math | Gouraud interpolation |
//! |---|---|---|---|---|
//! | [`Fast`] | 2 | [`Precise`] but for the transform: 32-bit products ([`NarrowTransform`]) | [`Libm`] | [`Affine`] |
//! | [`Balanced`] | 4 | [`Precise`], as [`RenderOptions::default`] | [`Libm`] | [`PerSegment<16>`](PerSegment) |
//! | [`Exact`] | 8 | [`Precise`]: wide transform, exact division, 30-bit normals | [`Libm`] | [`PerPixel`] |
//!
//! Sub-pixel bits set how finely vertices snap (`2^-S` pixel); the set-up [`Arithmetic`] how
//! vertices are transformed, projected and lit; the math backend how per-frame camera and model
//! matrices are computed; the interpolation how [`Gouraud`](crate::Gouraud) colour follows
//! perspective (`Gouraud<<Exact as Preset>::Interpolation>`). Edge walking and depth are exact
//! integer arithmetic in every preset. The depth format ([`crate::depth`]) is in no preset: the
//! 16-bit one saves RAM (2 bytes per column of the span z-buffer), not time.
//! [`RenderOptions::default`] (4 sub-pixel bits, [`Precise`] arithmetic) is not a preset: it is
//! the exactly rounded reference the conformance tests and tools are built on, and what a
//! build gets without choosing.
//!
//! What each preset costs and how accurate it is are measured, not assumed: `cargo xtask
//! tradeoff` writes `docs/tradeoff.md` (accuracy against the f64 reference on every corpus
//! scene, instructions on thumbv7em and thumbv6m for the demo orbit and every corpus scene, host
//! time, flash), with the default and single-knob variations beside the presets. `Fast` takes
//! fewer instructions per demo frame than the default on thumbv7em, thumbv6m and riscv32imc:
//! its coarser vertices, and on thumbv6m, which multiplies 64-bit integers in software, its
//! 32-bit transform. The other narrow knobs ([`Quick`]'s reciprocal projection and 15-bit
//! normals) measured dearer than the exact forms on thumbv7em and thumbv6m, so no preset takes
//! them. `Balanced` keeps the default's set-up: its exact division and 30-bit normals, written
//! in 32-bit operations, measured cheaper than the reciprocal projection and 15-bit normals
//! ([`Frugal`]) on all three targets, for the same accuracy; it adds perspective-correct
//! Gouraud colour every 16 pixels.
//! [`Micromath`] set-up is in no preset: its camera error moves vertices beyond the sub-pixel
//! error bound (real mismatches) and saves under 1 KB of flash.
//!
//! A preset gives the [`RenderOptions`] and the [`Camera`] of a frame:
//!
//! ```
//! use scanline3d::preset::{Exact, Preset};
//! let options = Exact::options(); // RenderOptions<8>
//! let camera = Exact::camera([0.0, 1.0, 4.0], [0.0; 3], [0.0, 1.0, 0.0], 50.0, 0.5, 20.0)?;
//! # let _ = (options, camera);
//! # Ok::<(), scanline3d::scene::SceneError>(())
//! ```

use crate::arithmetic::{Arithmetic, ExactDivision, NarrowTransform, Precise, Setup};
#[cfg(doc)]
use crate::arithmetic::{Frugal, Quick};
use crate::clip::FrustumClip;
#[cfg(doc)]
use crate::math::Micromath;
use crate::math::{Libm, MathBackend, WideNormals};
use crate::method::Options;
use crate::options::RenderOptions;
use crate::scene::{Camera, SceneError};
use crate::shading::{Affine, Interpolation, PerPixel, PerSegment};

/// A named bundle of precision choices.
pub trait Preset {
    /// The name `sim render --preset` takes.
    const NAME: &'static str;
    /// Sub-pixel bits of [`Preset::Options`].
    const SUB_BITS: u32;
    /// Render options: sub-pixel bits and the clipping stage.
    type Options: Options;
    /// Math backend for per-frame set-up (camera, model rotations).
    type Math: MathBackend;
    /// Integer arithmetic of the per-vertex and per-triangle set-up.
    type Arithmetic: Arithmetic;
    /// How [`Gouraud`](crate::Gouraud) shading interpolates colour.
    type Interpolation: Interpolation;

    /// The preset's render options (back-face culling on, as [`RenderOptions::default`]).
    fn options() -> Self::Options;

    /// A `gluLookAt` · `gluPerspective` camera computed with the preset's math backend.
    fn camera(
        eye: [f32; 3],
        target: [f32; 3],
        up: [f32; 3],
        fovy_degrees: f32,
        near: f32,
        far: f32,
    ) -> Result<Camera, SceneError> {
        Camera::look_at_perspective_with::<Self::Math>(eye, target, up, fovy_degrees, near, far)
    }
}

/// Coarse and cheap: 2 sub-pixel bits, [`FastArithmetic`] (the default's but for 32-bit
/// transform products), [`Libm`] set-up, [`Affine`] Gouraud colour.
#[derive(Clone, Copy, Debug, Default)]
pub struct Fast;

/// [`Fast`]'s set-up arithmetic: [`Precise`] but for the transform, whose products are 32-bit
/// ([`NarrowTransform`]; vertices move by about 10^-4 of their offsets). With 2 sub-pixel bits
/// it measured cheaper than the default on thumbv7em, thumbv6m and riscv32imc, and cheaper than
/// [`Quick`], whose reciprocal projection and 15-bit normals add instructions there.
pub type FastArithmetic = Setup<NarrowTransform, ExactDivision, WideNormals>;

/// Middle: the default's 4 sub-pixel bits, [`Precise`] arithmetic and [`Libm`] set-up (flat
/// frames are the default's), Gouraud colour perspective-correct every 16 pixels
/// ([`PerSegment<16>`](PerSegment)).
#[derive(Clone, Copy, Debug, Default)]
pub struct Balanced;

/// Finest: 8 sub-pixel bits, [`Precise`] arithmetic, [`Libm`] set-up, [`PerPixel`] Gouraud
/// colour.
#[derive(Clone, Copy, Debug, Default)]
pub struct Exact;

impl Preset for Fast {
    const NAME: &'static str = "fast";
    const SUB_BITS: u32 = 2;
    type Options = RenderOptions<2, FrustumClip, FastArithmetic>;
    type Math = Libm;
    type Arithmetic = FastArithmetic;
    type Interpolation = Affine;
    fn options() -> Self::Options {
        RenderOptions::default()
            .with_sub_pixel_bits::<2>()
            .with_arithmetic(FastArithmetic::default())
    }
}

impl Preset for Balanced {
    const NAME: &'static str = "balanced";
    const SUB_BITS: u32 = 4;
    type Options = RenderOptions<4>;
    type Math = Libm;
    type Arithmetic = Precise;
    type Interpolation = PerSegment<16>;
    fn options() -> Self::Options {
        RenderOptions::default()
    }
}

impl Preset for Exact {
    const NAME: &'static str = "exact";
    const SUB_BITS: u32 = 8;
    type Options = RenderOptions<8, FrustumClip>;
    type Math = Libm;
    type Arithmetic = Precise;
    type Interpolation = PerPixel;
    fn options() -> Self::Options {
        RenderOptions::default().with_sub_pixel_bits::<8>()
    }
}

/// The library's reference precision, what [`RenderOptions::default`] gives: 4 sub-pixel bits,
/// [`Precise`] arithmetic, [`Libm`] set-up, [`Affine`] Gouraud colour. It is the exactly
/// rounded configuration the conformance tests are built on, and the default of
/// [`Settings`](crate::Settings).
#[derive(Clone, Copy, Debug, Default)]
pub struct Reference;

impl Preset for Reference {
    const NAME: &'static str = "reference";
    const SUB_BITS: u32 = 4;
    type Options = RenderOptions<4>;
    type Math = Libm;
    type Arithmetic = Precise;
    type Interpolation = Affine;
    fn options() -> Self::Options {
        RenderOptions::default()
    }
}

/// The presets' names, fastest first.
pub const NAMES: [&str; 3] = [Fast::NAME, Balanced::NAME, Exact::NAME];

#[cfg(test)]
mod tests {
    use super::*;

    fn camera<P: Preset>() -> Camera {
        match P::camera([1.0, 2.0, 3.0], [0.0; 3], [0.0, 1.0, 0.0], 50.0, 0.5, 9.0) {
            Ok(c) => c,
            Err(e) => panic!("{e:?}"),
        }
    }

    #[test]
    fn balanced_has_the_default_bits_and_camera() {
        let d = RenderOptions::default();
        assert_eq!(d.cull_back_faces, Balanced::options().cull_back_faces);
        assert_eq!(RenderOptions::default(), Balanced::options());
        let c = Camera::look_at([1.0, 2.0, 3.0], [0.0; 3], [0.0, 1.0, 0.0])
            .and_then(|v| v.perspective(50.0, 0.5, 9.0));
        assert_eq!(c.map(|c| c.focal()), Ok(camera::<Balanced>().focal()));
    }

    #[test]
    fn presets_differ_in_sub_pixel_bits_and_compute_set_up_with_libm() {
        let exact = 1.0 / libm::tanf(25f32.to_radians());
        assert_eq!(camera::<Fast>().focal(), exact);
        assert_eq!(camera::<Exact>().focal(), exact);
        const { assert!(Fast::SUB_BITS < Balanced::SUB_BITS && Balanced::SUB_BITS < Exact::SUB_BITS) };
        // The options carry the same bits as the constants.
        let bits = |o: &dyn core::any::Any| {
            if o.is::<RenderOptions<2, FrustumClip, FastArithmetic>>() {
                2
            } else if o.is::<RenderOptions<4>>() {
                4
            } else if o.is::<RenderOptions<8>>() {
                8
            } else {
                u32::MAX
            }
        };
        assert_eq!(bits(&Fast::options()), Fast::SUB_BITS);
        assert_eq!(bits(&Balanced::options()), Balanced::SUB_BITS);
        assert_eq!(bits(&Exact::options()), Exact::SUB_BITS);
    }
}
