//! The integer arithmetic of the set-up stages (transform, projection, lighting), chosen at
//! compile time: one knob per stage, combined by [`Setup`]. The named presets
//! ([`crate::preset`]) pick one of these.

use crate::math::{NarrowNormals, NormalPrecision, WideNormals};
pub use crate::project::{ExactDivision, ProjectionPrecision, Reciprocal};
pub use crate::vertex::{NarrowTransform, TransformPrecision, WideTransform};
use core::marker::PhantomData;

/// The integer arithmetic of the per-vertex and per-triangle set-up, one compile-time choice
/// per stage: how vertices are transformed ([`TransformPrecision`]), divided by `w`
/// ([`ProjectionPrecision`]) and lit ([`NormalPrecision`]). [`Setup`] combines one of each;
/// [`Precise`] is the default of [`RenderOptions`](crate::RenderOptions), [`Quick`] the narrow choice at every
/// stage.
///
/// Pixel-level work (edge walking, depth and colour interpolation) is exact in every
/// arithmetic: the choices move vertices and shades by the bounds each knob documents, never
/// break the fill rule or the watertightness of shared edges (a shared vertex gives the same
/// result in every triangle).
pub trait Arithmetic: Copy + Default + core::fmt::Debug + PartialEq + Eq + 'static {
    /// Transform stage.
    type Transform: TransformPrecision;
    /// Projection stage.
    type Projection: ProjectionPrecision;
    /// Lighting stage.
    type Normals: NormalPrecision;
}

/// The arithmetic made of transform `T`, projection `P` and normals `N`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Setup<T, P, N>(PhantomData<(T, P, N)>);

impl<T: TransformPrecision, P: ProjectionPrecision, N: NormalPrecision> Arithmetic
    for Setup<T, P, N>
{
    type Transform = T;
    type Projection = P;
    type Normals = N;
}

/// Wide arithmetic everywhere: 64-bit transform products, exact division per coordinate,
/// 30-bit normals. The default.
pub type Precise = Setup<WideTransform, ExactDivision, WideNormals>;

/// Wide transform, with the two narrow knobs that cost no measured accuracy on the corpus: one
/// reciprocal per vertex and 15-bit normals (the [`Balanced`](crate::preset::Balanced) preset's arithmetic).
pub type Frugal = Setup<WideTransform, Reciprocal, NarrowNormals>;

/// Narrow arithmetic everywhere: 32-bit transform products, one reciprocal per vertex, 15-bit
/// normals. Vertices move by about 10^-4 of their offsets, shades by far less than a colour
/// step; on cores without 64-bit multiply and divide this removes most of the set-up's cost.
pub type Quick = Setup<NarrowTransform, Reciprocal, NarrowNormals>;
