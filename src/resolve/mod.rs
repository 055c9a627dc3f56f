//! The classic hidden-surface methods on the shared pipeline.
//!
//! Transform, clipping, projection, bucketing by first row and the exact edge walk are the
//! same for every method (see `crate::render`); only the step that turns the active
//! triangles' spans into visible pixels differs. [`Workspace`](crate::Workspace) is the span
//! z-buffer (one row of depth). This module adds:
//!
//! | workspace | method | visibility memory | pixels written |
//! |---|---|---|---|
//! | [`BandWorkspace`] | z-buffer over bands of `B` rows (Catmull) | `B·W` depth + `B·W` pixels | every pixel that passes the depth test |
//! | [`ZBufferWorkspace`] | full-frame z-buffer: a band of `H` rows | `H·W` depth + `H·W` pixels | same |
//! | [`SpanSortWorkspace`] | span sorting (Watkins): visible segments from depths at span ends | one row of pixels, a span list; no depth | each pixel once |
//! | [`DepthSortWorkspace`] | depth sort / painter's: far to near by mean depth, overwriting | one row of pixels, a key per triangle; no depth | every covered pixel (overdraw) |
//! | [`NewellWorkspace`] | depth sort (Newell, Newell and Sancha): far to near, overlaps resolved by plane and projection tests, splitting cycles and interpenetration | every kept piece, its order and split tree, one row of pixels and of positions; no depth | every covered pixel not yet held by a later piece |
//! | [`bsp::BspWorkspace`] | BSP tree order (Fuchs, Kedem, Naylor): far to near for any eye position, the tree built ahead of time | one row of pixels, a key per triangle, a traversal stack; no depth | every covered pixel (overdraw) |
//! | [`WarnockWorkspace`] | area subdivision (Warnock): windows split until simple | every kept piece, a frame of pixels, a window stack and index buffer; no depth | each pixel once |
//!
//! The z-buffers, span sorting and area subdivision render bit-identical frames to the span z-buffer: they
//! apply the same rule (strictly nearer wins; on an exact tie, the triangle activated first,
//! that is the one whose first row is nearer the top, then the lower id). The depth sort is the
//! fast baseline that is wrong where one mean depth per triangle cannot order two surfaces
//! (interpenetration, cyclic overlap, long surfaces beside short ones).
//!
//! BSP order and Newell's depth sort paint far to near like the depth sort, but are correct:
//! the BSP tree's build split whatever no order could draw, and Newell's sort orders
//! overlapping pieces
//! by exact plane and projection tests and splits cycles and interpenetration. They differ
//! from the span z-buffer only on a few pixels along split seams (see [`bsp`], [`newell`]).
//!
//! Methods without depth memory hand rows to the sink with an empty [`Row::depth`].
//!
//! [`Row::depth`]: crate::sink::Row::depth

pub mod band;
pub mod bsp;
mod common;
pub mod depth_sort;
pub mod newell;
pub mod span_sort;
pub mod store;
pub mod warnock;

pub use band::{BandWorkspace, ZBufferWorkspace};
pub use depth_sort::DepthSortWorkspace;
pub use newell::NewellWorkspace;
pub use span_sort::SpanSortWorkspace;
pub use warnock::WarnockWorkspace;
