//! Bicubic Bezier patches (polynomial or rational), drawn by the scanline renderer.
//!
//! A [`PatchModel`] borrows its control points (and optional weights) as slices, so a model
//! can live in flash as `static` data (`sim export model.bpt` writes one). A
//! [`PatchWorkspace`] renders it row by row like a mesh: each patch is filed under the first
//! row of its control hull's screen bounds; when that row comes, the patch is tessellated
//! to a tolerance in sub-pixels and its interior is split in parameter space into pieces,
//! each filed under the first row of its own control hull (Lane–Carpenter, Nishita 1991), so
//! triangles are made only as the rows reach them. The triangles go through the mesh path's
//! clipper, edge walk and span z-buffer. Ids are patch indices.
//!
//! # No cracks
//!
//! Every tessellation decision about a patch boundary is made from that boundary's own four
//! control points: its number of segments (a power of two, from their screen-space second
//! differences) and its points (evaluated from the lexicographically smaller end, so both
//! neighbours compute identical bits). The interior grid has its own resolution and is
//! stitched to the boundary points by a zipper of triangles, as tessellation hardware does
//! with edge factors; so patches sharing an edge share its vertices exactly, and the edge
//! walk's fill rule covers every pixel centre along it once.
//!
//! # Formats and envelope
//!
//! | quantity | type | limit | why |
//! |---|---|---|---|
//! | control point coordinates | [`PatchCoord`] (I16F16) | ±[`MAX_PATCH_COORD`] = 4096 | as mesh vertices: the eye envelope of the vertex stage |
//! | weights | [`Weight`] (I16F16) | [`MIN_WEIGHT`] = 1/16 to [`MAX_WEIGHT`] = 16 | homogeneous components below 2^32 in I48F16 bits (`eval`) |
//! | patches | | 1 to [`MAX_PATCHES`] = 65,534 | 16-bit patch indices in the row buckets |
//! | tolerance | [`Tolerance`] (U8F8 pixels) | ≥ 1 sub-pixel (smaller is raised to it) | levels below 2^[`MAX_LEVEL`] segments |
//! | segments per edge or grid side | | 2^[`MAX_LEVEL`] = 64 | 8-bit grid indices; a patch that needs more is drawn at 64 and counted in [`PatchStats::capped`] |
//!
//! Parameters `(u, v)` are I16F16 bits in `[0, 2^16]` (exact at grid points `i/2^k`).

mod draw;
mod eval;
mod tessellate;

pub use draw::{PatchScene, PatchStats, PatchWorkspace};

use embedded_graphics::pixelcolor::Rgb888;
use fixed::types::{I16F16, U8F8};

/// A control point coordinate (model space): I16F16.
pub type PatchCoord = I16F16;
/// A control point weight (rational patches): I16F16, within [`MIN_WEIGHT`]..=[`MAX_WEIGHT`].
pub type Weight = I16F16;
/// The 16 control points of a bicubic patch, row-major: `points[4·i + j]` is `P_ij`, with `u`
/// along `i` and `v` along `j`. The front side is the one `∂S/∂u × ∂S/∂v` points to.
pub type ControlPoints = [[PatchCoord; 3]; 16];
/// The flatness tolerance in pixels: U8F8.
pub type Tolerance = U8F8;

/// Largest |control point coordinate| (as [`MAX_MODEL_COORD`](crate::scene::MAX_MODEL_COORD)).
pub const MAX_PATCH_COORD: i32 = crate::scene::MAX_MODEL_COORD;
/// Smallest weight.
pub const MIN_WEIGHT: Weight = Weight::lit("0.0625");
/// Largest weight.
pub const MAX_WEIGHT: Weight = Weight::lit("16");
/// Most patches in a model (indices are 16-bit, `u16::MAX` ends a bucket list).
pub const MAX_PATCHES: usize = u16::MAX as usize - 1;
/// Most subdivision levels per edge or grid side: at most 2^6 = 64 segments.
pub const MAX_LEVEL: u32 = 6;

/// The parameter value 1 in I16F16 bits.
pub(crate) const PARAM_ONE: u32 = 1 << 16;

/// How a model's patches are coloured.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PatchColors<'a> {
    /// One colour for every patch.
    Uniform(Rgb888),
    /// One colour per patch, in patch order.
    PerPatch(&'a [Rgb888]),
}

/// Why a patch model was rejected.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PatchError {
    /// No patches, or more than [`MAX_PATCHES`].
    PatchCount,
    /// Patch `patch` has a coordinate beyond ±[`MAX_PATCH_COORD`].
    Coordinate {
        /// Patch index.
        patch: usize,
    },
    /// Patch `patch` has a weight outside [`MIN_WEIGHT`]..=[`MAX_WEIGHT`].
    Weight {
        /// Patch index.
        patch: usize,
    },
    /// The weights (or per-patch colours) are not one set per patch.
    Length,
}

impl core::fmt::Display for PatchError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::PatchCount => write!(f, "a patch model holds 1 to {MAX_PATCHES} patches"),
            Self::Coordinate { patch } => write!(
                f,
                "patch {patch}: a control point coordinate is beyond ±{MAX_PATCH_COORD}"
            ),
            Self::Weight { patch } => write!(
                f,
                "patch {patch}: a weight is outside {MIN_WEIGHT}..={MAX_WEIGHT}"
            ),
            Self::Length => write!(f, "weights and colours must be given once per patch"),
        }
    }
}

impl core::error::Error for PatchError {}

/// A checked patch model: control points, optional weights and colours, all borrowed.
///
/// ```
/// use embedded_graphics::pixelcolor::Rgb888;
/// use fixed::types::I16F16;
/// use scanline3d::patch::{PatchColors, PatchModel};
/// // A flat square patch in z = 0.
/// let mut p = [[I16F16::ZERO; 3]; 16];
/// for i in 0..4 {
///     for j in 0..4 {
///         p[4 * i + j] = [I16F16::from_num(i), I16F16::from_num(j), I16F16::ZERO];
///     }
/// }
/// let points = [p];
/// let model = PatchModel::new(&points, None, PatchColors::Uniform(Rgb888::new(200, 100, 0)))?;
/// assert_eq!(model.points().len(), 1);
/// # Ok::<(), scanline3d::patch::PatchError>(())
/// ```
#[derive(Clone, Copy, Debug)]
pub struct PatchModel<'a> {
    points: &'a [ControlPoints],
    weights: Option<&'a [[Weight; 16]]>,
    colors: PatchColors<'a>,
    max_abs_bits: i32,
}

impl<'a> PatchModel<'a> {
    /// Checks the envelope; `weights`, if given, holds one set of 16 per patch (`None`:
    /// polynomial patches, all weights 1).
    pub const fn new(
        points: &'a [ControlPoints],
        weights: Option<&'a [[Weight; 16]]>,
        colors: PatchColors<'a>,
    ) -> Result<Self, PatchError> {
        if points.is_empty() || points.len() > MAX_PATCHES {
            return Err(PatchError::PatchCount);
        }
        if let PatchColors::PerPatch(c) = colors {
            if c.len() != points.len() {
                return Err(PatchError::Length);
            }
        }
        let limit = MAX_PATCH_COORD << 16;
        let mut max_abs_bits = 0;
        let mut p = 0;
        while p < points.len() {
            let mut k = 0;
            while k < 16 {
                let mut c = 0;
                while c < 3 {
                    let bits = points[p][k][c].to_bits();
                    if bits < -limit || bits > limit {
                        return Err(PatchError::Coordinate { patch: p });
                    }
                    let abs = if bits < 0 { -bits } else { bits };
                    if abs > max_abs_bits {
                        max_abs_bits = abs;
                    }
                    c += 1;
                }
                k += 1;
            }
            p += 1;
        }
        if let Some(w) = weights {
            if w.len() != points.len() {
                return Err(PatchError::Length);
            }
            let mut p = 0;
            while p < w.len() {
                let mut k = 0;
                while k < 16 {
                    let bits = w[p][k].to_bits();
                    if bits < MIN_WEIGHT.to_bits() || bits > MAX_WEIGHT.to_bits() {
                        return Err(PatchError::Weight { patch: p });
                    }
                    k += 1;
                }
                p += 1;
            }
        }
        Ok(PatchModel {
            points,
            weights,
            colors,
            // Evaluated points are convex combinations of control points, rounded: a few
            // units of the last bit beyond the largest coordinate at most.
            max_abs_bits: max_abs_bits + 16,
        })
    }

    /// The control points, one set of 16 per patch.
    pub const fn points(&self) -> &'a [ControlPoints] {
        self.points
    }

    /// The weights, if the patches are rational.
    pub const fn weights(&self) -> Option<&'a [[Weight; 16]]> {
        self.weights
    }

    /// The colours.
    pub const fn colors(&self) -> PatchColors<'a> {
        self.colors
    }

    /// The colour of patch `index`.
    pub(crate) fn color(&self, index: usize) -> Rgb888 {
        match self.colors {
            PatchColors::Uniform(c) => c,
            PatchColors::PerPatch(c) => c.get(index).copied().unwrap_or(Rgb888::new(0, 0, 0)),
        }
    }

    /// Largest |coordinate| an evaluated point can have, in I16F16 bits.
    pub(crate) const fn max_abs_bits(&self) -> i32 {
        self.max_abs_bits
    }
}
