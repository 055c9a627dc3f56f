//! One type names every choice that changes a renderer's results: pixel format, shading and
//! Gouraud interpolation, depth format, sub-pixel bits, clipping, set-up arithmetic and the
//! camera math. Sizes are not here: they belong to the storage ([`crate::Storage`]).
//!
//! [`Settings`] builds a configuration from a pixel type, a shading kind and a precision
//! [`Preset`]; a type of your own that implements [`Config`] can mix the knobs freely.
//!
//! ```
//! use embedded_graphics::pixelcolor::Rgb565;
//! use scanline3d::{preset, Config, Gouraud, Settings};
//!
//! // Gouraud shading with the Balanced preset: its arithmetic, 4 sub-pixel bits and Gouraud
//! // colour perspective-correct every 16 pixels.
//! type Panel = Settings<Rgb565, Gouraud, preset::Balanced>;
//! let camera = Panel::camera([0.0, 1.0, 4.0], [0.0; 3], [0.0, 1.0, 0.0], 50.0, 0.5, 20.0)?;
//! # let _ = camera;
//! # Ok::<(), scanline3d::scene::SceneError>(())
//! ```
//!
//! A mix no preset offers, here a 16-bit depth row with the default precision:
//!
//! ```
//! use embedded_graphics::pixelcolor::Gray8;
//! use scanline3d::{depth::Depth16, math::Libm, Config, Flat, RenderOptions};
//!
//! struct Oled;
//! impl Config for Oled {
//!     type Pixel = Gray8;
//!     type Shading = Flat;
//!     type Depth = Depth16;
//!     type Options = RenderOptions<4>;
//!     type Math = Libm;
//!     fn options() -> RenderOptions<4> {
//!         RenderOptions::default()
//!     }
//! }
//! ```

use crate::depth::{Depth, DepthFormat};
use crate::math::MathBackend;
use crate::method::Options;
use crate::preset::{Preset, Reference};
use crate::scene::{Camera, SceneError};
use crate::shading::{Flat, Gouraud, Interpolation, Shading, Unlit};
use crate::sink::RowPixel;
use core::marker::PhantomData;

/// Every choice that changes a renderer's results, named once (see the [module](self)).
pub trait Config: 'static {
    /// Pixel format of the rows ([`RowPixel`]).
    type Pixel: RowPixel;
    /// Shading model: [`Flat`], [`Unlit`] or [`Gouraud`] with its interpolation.
    type Shading: Shading;
    /// Depth format of the z-buffer row ([`crate::depth`]).
    type Depth: DepthFormat;
    /// Sub-pixel bits, clipping and set-up arithmetic: a [`crate::RenderOptions`].
    type Options: Options;
    /// Math backend of the per-frame set-up (camera, model rotations).
    type Math: MathBackend;

    /// The options of every frame (back-face culling on; a renderer can turn it off).
    fn options() -> Self::Options;

    /// A `gluLookAt` · `gluPerspective` camera computed with this configuration's math.
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

/// A shading model whose Gouraud interpolation a preset chooses: [`Flat`], [`Unlit`], or [`Gouraud`]
/// (whatever interpolation it names is replaced by the preset's).
pub trait ShadingKind: 'static {
    /// The shading model with interpolation `I`.
    type With<I: Interpolation>: Shading;
}

impl ShadingKind for Flat {
    type With<I: Interpolation> = Flat;
}

impl ShadingKind for Unlit {
    type With<I: Interpolation> = Unlit;
}

impl<J: Interpolation> ShadingKind for Gouraud<J> {
    type With<I: Interpolation> = Gouraud<I>;
}

/// The configuration of pixel type `P`, shading kind `K` ([`Flat`] by default) and precision
/// preset `Pr` ([`Reference`] by default: 4 sub-pixel bits, exactly rounded set-up), with depth
/// format `Z` ([`Depth`], 32-bit, by default).
pub struct Settings<P, K = Flat, Pr = Reference, Z = Depth>(PhantomData<(P, K, Pr, Z)>);

impl<P: RowPixel + 'static, K: ShadingKind, Pr: Preset + 'static, Z: DepthFormat + 'static> Config
    for Settings<P, K, Pr, Z>
{
    type Pixel = P;
    type Shading = K::With<Pr::Interpolation>;
    type Depth = Z;
    type Options = Pr::Options;
    type Math = Pr::Math;

    fn options() -> Pr::Options {
        Pr::options()
    }
}
