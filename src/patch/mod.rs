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
//! | trim points | [`TrimPoint`] (I16F16) | `[0, 1]` | the parameters' bits; see `trim` for the cut's budget |
//!
//! Parameters `(u, v)` are I16F16 bits in `[0, 2^16]` (exact at grid points `i/2^k`).
//!
//! # Trims
//!
//! Patches may be trimmed by closed polylines in `(u, v)` ([`PatchModel::with_trims`]): a
//! point is drawn when it lies inside an even number of its patch's loops. Tessellation
//! triangles that a trim edge touches are cut in parameter space at the trim's vertices and
//! edges, the new vertices evaluated on the surface, so the hole's edge is as accurate as
//! the tessellation and neighbours stay crack-free; see [`PatchStats::trim_cut`] and
//! [`PatchStats::trim_overflows`].

mod draw;
mod eval;
mod tessellate;
mod trim;

pub use draw::{PatchScene, PatchStats, PatchWorkspace};
pub use trim::{TrimLoop, TrimPoint};

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
    /// A trim loop of patch `patch` has fewer than 3 points, a point outside `[0, 1]²`, a
    /// zero-length edge or points beyond the trim points, or names a patch the model does not
    /// have, or the loops are not in patch order.
    TrimLoop {
        /// Patch index.
        patch: usize,
    },
    /// Two edges of patch `patch`'s trim loops meet (a loop crosses itself or another).
    TrimCrossing {
        /// Patch index.
        patch: usize,
    },
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
            Self::TrimLoop { patch } => write!(
                f,
                "patch {patch}: a trim loop needs 3 or more distinct points in [0, 1]², on a patch of the model, loops in patch order"
            ),
            Self::TrimCrossing { patch } => {
                write!(f, "patch {patch}: trim loop edges cross or meet")
            }
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
    trim_loops: &'a [TrimLoop],
    trim_points: &'a [TrimPoint],
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
            trim_loops: &[],
            trim_points: &[],
        })
    }

    /// The model with trim loops: `loops` (in patch order) index `points`. A point `(u, v)` of
    /// a patch is drawn when it lies inside an even number of that patch's loops. Loops must
    /// be simple and must not meet (checked: O(n²) in the points of a patch).
    ///
    /// ```
    /// # use embedded_graphics::pixelcolor::Rgb888;
    /// # use fixed::types::I16F16;
    /// use scanline3d::patch::{PatchColors, PatchModel, TrimLoop, TrimPoint};
    /// # let mut p = [[I16F16::ZERO; 3]; 16];
    /// # for i in 0..4 {
    /// #     for j in 0..4 {
    /// #         p[4 * i + j] = [I16F16::from_num(i), I16F16::from_num(j), I16F16::ZERO];
    /// #     }
    /// # }
    /// # let points = [p];
    /// let q = |u: f64, v: f64| -> TrimPoint { [I16F16::from_num(u), I16F16::from_num(v)] };
    /// // A square hole in patch 0.
    /// let hole = [q(0.25, 0.25), q(0.75, 0.25), q(0.75, 0.75), q(0.25, 0.75)];
    /// let loops = [TrimLoop { patch: 0, start: 0, len: 4 }];
    /// let model = PatchModel::new(&points, None, PatchColors::Uniform(Rgb888::new(200, 100, 0)))?
    ///     .with_trims(&loops, &hole)?;
    /// # Ok::<(), scanline3d::patch::PatchError>(())
    /// ```
    pub const fn with_trims(
        self,
        loops: &'a [TrimLoop],
        points: &'a [TrimPoint],
    ) -> Result<Self, PatchError> {
        if let Err(e) = trim::check(loops, points, self.points.len()) {
            return Err(e);
        }
        Ok(PatchModel {
            trim_loops: loops,
            trim_points: points,
            ..self
        })
    }

    /// The trim loops, in patch order.
    pub const fn trim_loops(&self) -> &'a [TrimLoop] {
        self.trim_loops
    }

    /// The trim points the loops index.
    pub const fn trim_points(&self) -> &'a [TrimPoint] {
        self.trim_points
    }

    /// The trim loops of patch `index`.
    pub(crate) fn trims(&self, index: usize) -> trim::Trims<'a> {
        let loops = self.trim_loops;
        let first = loops.partition_point(|l| (l.patch as usize) < index);
        let end = loops.partition_point(|l| (l.patch as usize) <= index);
        trim::Trims {
            loops: loops.get(first..end).unwrap_or_default(),
            points: self.trim_points,
        }
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
