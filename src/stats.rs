//! What a frame reports: its statistics (what was drawn, what capacity dropped) and its errors.

use crate::scene::MAX_SCENE_TRIANGLES;
pub use crate::vertex::TransformError;

/// What one frame did. Counts are of triangles unless named otherwise.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FrameStats {
    /// Triangles in the scene.
    pub triangles_in: u32,
    /// Back faces skipped.
    pub culled: u32,
    /// Triangles that crossed a clip plane and were cut.
    pub clipped: u32,
    /// Triangles outside the view volume or the screen, or of zero area once snapped.
    pub rejected: u32,
    /// Triangles not drawn because they cross a clip plane and the options use
    /// [`NoClip`](crate::clip::NoClip) (0 with [`FrustumClip`](crate::clip::FrustumClip)).
    pub unclipped: u32,
    /// Triangles filed in row buckets.
    pub bucketed: u32,
    /// Vertices transformed into the workspace's vertex cache ([`crate::cache`]) this frame;
    /// 0 when it has none or the scene's vertices do not fit it (the frame is then rendered
    /// uncached, with the same pixels).
    pub cached_vertices: u32,
    /// Triangles (or clipped pieces) set up for the walk.
    pub activated: u32,
    /// Non-empty spans walked.
    pub spans: u32,
    /// Pixel centres covered by spans, before the depth test.
    pub fragments: u32,
    /// Pixels that passed the depth test (a pixel may be written more than once).
    pub pixels_written: u32,
    /// Largest number of triangles active on one row.
    pub peak_active: u16,
    /// Largest number of non-empty spans on one row.
    pub peak_spans: u16,
    /// Triangle pieces not drawn because the active list was full (0 in a complete frame).
    pub dropped: u32,
    /// The first [`DROP_LOG`] pieces dropped, in the order they were dropped (top to bottom):
    /// which triangle lost which rows.
    pub dropped_pieces: [Option<DroppedPiece>; DROP_LOG],
    /// Rows that a dropped piece spans, i.e. rows that may be missing a triangle. Each such
    /// row is also sent with [`Row::complete`](crate::sink::Row::complete) false.
    pub incomplete_rows: u16,
    /// Rows handed to the sink.
    pub rows: u16,
}

/// How many dropped pieces [`FrameStats::dropped_pieces`] records (all are counted).
pub const DROP_LOG: usize = 4;

/// A triangle piece the active list had no room for, and the rows it would have covered.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DroppedPiece {
    /// Global triangle id (the index across the scene's instances, as in [`TriangleId`]).
    ///
    /// [`TriangleId`]: crate::sink::TriangleId
    pub triangle: u32,
    /// First row the piece would have been drawn on.
    pub first_row: u16,
    /// Last row the piece would have been drawn on.
    pub last_row: u16,
}

impl FrameStats {
    /// Whether every triangle was drawn (no capacity degradation).
    pub fn is_complete(&self) -> bool {
        self.dropped == 0
    }

    /// The first row that may be missing a triangle, if any.
    pub fn first_incomplete_row(&self) -> Option<u16> {
        self.dropped_pieces[0].map(|d| d.first_row)
    }
}

/// A buffer that was too small.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CapacityKind {
    /// `TRIS`: triangles that survive culling and clipping, filed in row buckets.
    Triangles,
    /// The workspace's `INSTANCES` (default [`MAX_INSTANCES`](crate::options::MAX_INSTANCES)): mesh instances in the scene.
    Instances,
    /// Screen triangles kept for a whole-frame method (clipped pieces count one each).
    Pieces,
    /// The traversal stack of a BSP tree (`STACK` of a
    /// [`BspWorkspace`](crate::resolve::bsp::BspWorkspace)).
    BspStack,
    /// The window stack of Warnock's area subdivision
    /// ([`WarnockWorkspace`](crate::resolve::WarnockWorkspace)), which depends on the target
    /// size only ([`stack_needed`](crate::resolve::warnock::stack_needed)).
    WindowStack,
    /// The work bound of Newell's depth sort
    /// ([`NewellWorkspace`](crate::resolve::NewellWorkspace)): list steps (outputs, moves and
    /// splits), at most [`newell::step_limit`](crate::resolve::newell::step_limit)`(PIECES)`.
    SortSteps,
    /// Patches waiting in row buckets (`SUBS` of a
    /// [`PatchWorkspace`](crate::patch::PatchWorkspace)): every patch whose control hull is on
    /// screen needs one at the start of a frame.
    Patches,
    /// Room to cut triangles by trim loops (`TRIM` of a
    /// [`PatchWorkspace`](crate::patch::PatchWorkspace)): a workspace with `TRIM` = 0 has
    /// no trim code and cannot draw a model with trim loops (`needed` counts its loops).
    Trims,
}

impl core::fmt::Display for CapacityKind {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::Triangles => "triangles after culling (TRIS)",
            Self::Instances => "mesh instances (INSTANCES)",
            Self::Pieces => "screen pieces (PIECES)",
            Self::BspStack => "BSP traversal stack (STACK)",
            Self::WindowStack => "Warnock window stack (STACK)",
            Self::SortSteps => "Newell sort steps",
            Self::Patches => "patches waiting in row buckets (SUBS)",
            Self::Trims => "trim loops (TRIM = 0 has no trim code)",
        })
    }
}

/// Why a frame could not be rendered.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RenderError<E> {
    /// Target size outside 1..=2048 per side, or a projection scale outside the envelope
    /// (for example a field of view under about 1° on a 2048-pixel target at 8 sub-pixel bits).
    InvalidTarget,
    /// An instance's transform is not finite or moves the mesh outside the eye envelope (±2^14).
    Transform {
        /// Instance index.
        instance: usize,
        /// What was wrong.
        error: TransformError,
    },
    /// The BSP tree was built for another mesh, or the scene does not have exactly one
    /// instance (its mesh) for it.
    TreeMismatch,
    /// The scene's instances hold `triangles` triangles together, more than
    /// [`MAX_SCENE_TRIANGLES`] (65,535; [`Scene::new`](crate::scene::Scene::new) rejects such a scene too). Returned before
    /// any row is sent.
    TooManyTriangles {
        /// Triangles over all instances.
        triangles: usize,
    },
    /// A capacity was exceeded before any row was sent (the sink received nothing).
    Capacity {
        /// Which buffer.
        what: CapacityKind,
        /// How many entries the frame needs.
        needed: usize,
        /// How many the buffer holds.
        capacity: usize,
    },
    /// The sink failed on `row`; rows before it were delivered, none after.
    Sink {
        /// The row that failed.
        row: u16,
        /// The sink's error.
        error: E,
    },
}

impl<E: core::fmt::Debug> core::fmt::Display for RenderError<E> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::InvalidTarget => {
                write!(f, "render target size or projection outside the envelope")
            }
            Self::Transform { instance, error } => {
                write!(f, "instance {instance}: {error}")
            }
            Self::Capacity {
                what,
                needed,
                capacity,
            } => {
                write!(
                    f,
                    "capacity exceeded: {what} needs {needed}, holds {capacity}"
                )
            }
            Self::Sink { row, error } => write!(f, "sink failed on row {row}: {error:?}"),
            Self::TreeMismatch => write!(f, "the BSP tree does not match the scene's mesh"),
            Self::TooManyTriangles { triangles } => write!(
                f,
                "the scene has {triangles} triangles, more than the limit of {MAX_SCENE_TRIANGLES} per frame"
            ),
        }
    }
}

impl<E: core::fmt::Debug> core::error::Error for RenderError<E> {}
