//! The vertex cache: per-vertex memory for one frame, RAM traded for speed.
//!
//! Without it the renderer keeps nothing per vertex: a vertex shared by six triangles is
//! transformed, clip-tested and projected six times in pass 1 and again in pass 2 (see
//! `crate::render`). A [`Workspace`](crate::Workspace) with `VERTS > 0` instead does that
//! once per vertex at the start of the frame, when the scene's vertices (all instances
//! together) fit; triangles whose three vertices are inside every clip plane then take their
//! screen vertices from the cache, and the others are clipped from the cached eye-space points.
//!
//! The cached values are exactly what the uncached path computes (the same transform, clip
//! distances and projection), so a frame is bit-identical with or without the cache. A scene
//! with more vertices than `VERTS` is rendered uncached, also bit-identically, and says so in
//! [`FrameStats::cached_vertices`](crate::FrameStats::cached_vertices) (0).
//!
//! Each entry is [`CachedVertex::BYTES`] bytes: on a microcontroller a 642-vertex mesh costs
//! about 18 KiB, on a host it is nothing.

use crate::project::{ProjectionPrecision, ScreenVertex, SubPx, Viewport};
use crate::vertex::EyePoint;
use crate::Depth;
use fixed::types::I16F16;

/// One vertex as the frame sees it: eye-space position, which clip planes it is outside, and
/// (when inside all of them) its snapped screen position and depth.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CachedVertex {
    pub(crate) eye: EyePoint,
    /// Bit `k` set: outside clip plane `k` of [`Viewport::clip_distances`]. [`NOT_PROJECTED`]
    /// marks a vertex without a screen position.
    pub(crate) outside: u8,
    x: i32,
    y: i32,
    q: Depth,
}

/// Set in [`CachedVertex::outside`] when the vertex has no screen position (it is outside a
/// plane, or its projection failed): triangles using it take the clipping path.
const NOT_PROJECTED: u8 = 0x80;

impl CachedVertex {
    /// Size of one cache entry in bytes.
    pub const BYTES: usize = core::mem::size_of::<Self>();

    /// An unused entry (its value is never read before the frame fills it).
    pub const EMPTY: Self = CachedVertex {
        eye: EyePoint {
            x: I16F16::ZERO,
            y: I16F16::ZERO,
            w: I16F16::ZERO,
        },
        outside: NOT_PROJECTED,
        x: 0,
        y: 0,
        q: Depth::ZERO,
    };

    /// Clip-tests and (when inside) projects eye-space point `eye` at precision `P`.
    #[inline]
    pub(crate) fn new<const S: u32, P: ProjectionPrecision>(
        vp: &Viewport<S>,
        eye: EyePoint,
    ) -> Self {
        let outside = vp
            .clip_distances(&eye)
            .iter()
            .enumerate()
            .fold(0u8, |bits, (k, d)| bits | (((*d < 0) as u8) << k));
        let screen = if outside == 0 {
            vp.project_as::<P>(&eye, [I16F16::ZERO; 3], true)
        } else {
            None
        };
        match screen {
            Some(s) => CachedVertex {
                eye,
                outside,
                x: s.x.0,
                y: s.y.0,
                q: s.q,
            },
            None => CachedVertex {
                eye,
                outside: outside | NOT_PROJECTED,
                ..Self::EMPTY
            },
        }
    }

    /// The screen vertex with colour `color`, if this vertex has one.
    #[inline]
    pub(crate) fn screen<const S: u32>(&self, color: [I16F16; 3]) -> Option<ScreenVertex<S>> {
        (self.outside == 0).then_some(ScreenVertex {
            x: SubPx(self.x),
            y: SubPx(self.y),
            q: self.q,
            color,
        })
    }

    /// Whether all of `v` lie outside one clip plane (the triangle is invisible).
    #[inline]
    pub(crate) fn all_outside_one_plane(v: [&Self; 3]) -> bool {
        v[0].outside & v[1].outside & v[2].outside & !NOT_PROJECTED != 0
    }
}

/// Bytes of a vertex cache of `vertices` entries (the `VERTS` of a
/// [`Workspace`](crate::Workspace)), on top of [`crate::workspace::workspace_bytes`].
///
/// ```
/// use embedded_graphics::pixelcolor::Rgb565;
/// use scanline3d::{cache::vertex_cache_bytes, workspace::workspace_bytes, Depth, Flat, Workspace};
/// type Cached = Workspace<Rgb565, Flat, 240, 240, 1280, 64, 8, Depth, 700>;
/// let plain = workspace_bytes::<Rgb565, Flat, Depth>(240, 240, 1280, 64);
/// assert_eq!(Cached::BYTES, plain + vertex_cache_bytes(700));
/// ```
pub const fn vertex_cache_bytes(vertices: usize) -> usize {
    vertices * CachedVertex::BYTES
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::project::tests::eye;
    use crate::project::{ExactDivision, Reciprocal};

    #[test]
    fn entries_match_the_uncached_projection() {
        let vp = Viewport::<4>::new(240, 240, 1.7, 0.5, 50.0).unwrap();
        let c = [I16F16::from_num(7); 3];
        for (x, y, w) in [(0.0, 0.0, 5.0), (2.0, -1.5, 3.0), (-0.3, 0.2, 0.6)] {
            let p = eye(x, y, w);
            let exact = CachedVertex::new::<4, ExactDivision>(&vp, p);
            assert_eq!(
                exact.screen::<4>(c),
                vp.project_as::<ExactDivision>(&p, c, true)
            );
            let quick = CachedVertex::new::<4, Reciprocal>(&vp, p);
            assert_eq!(
                quick.screen::<4>(c),
                vp.project_as::<Reciprocal>(&p, c, true)
            );
        }
    }

    #[test]
    fn an_entry_is_28_bytes() {
        // Eye point (3 × 4), outcodes (1), screen x, y and depth (3 × 4), padded to 4.
        assert_eq!(CachedVertex::BYTES, 28);
        assert_eq!(vertex_cache_bytes(731), 20_468);
    }

    #[test]
    fn outside_vertices_have_no_screen_position() {
        let vp = Viewport::<4>::new(240, 240, 1.7, 0.5, 50.0).unwrap();
        let behind = CachedVertex::new::<4, ExactDivision>(&vp, eye(0.0, 0.0, -1.0));
        let far = CachedVertex::new::<4, ExactDivision>(&vp, eye(0.0, 0.0, 80.0));
        let inside = CachedVertex::new::<4, ExactDivision>(&vp, eye(0.0, 0.0, 5.0));
        assert_eq!(behind.outside & 1, 1);
        assert_eq!(far.outside & 2, 2);
        assert_eq!(inside.outside, 0);
        assert!(behind.screen::<4>([I16F16::ZERO; 3]).is_none());
        assert!(CachedVertex::all_outside_one_plane([&behind; 3]));
        assert!(!CachedVertex::all_outside_one_plane([
            &behind, &far, &behind
        ]));
        assert!(!CachedVertex::all_outside_one_plane([
            &inside, &behind, &behind
        ]));
        // An unused entry never passes for an inside one.
        assert!(CachedVertex::EMPTY.screen::<4>([I16F16::ZERO; 3]).is_none());
    }
}
