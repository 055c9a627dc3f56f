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
//! An entry is compact, [`CachedVertex::BYTES`] = 8 bytes, so that the cache fits beside the
//! rest of the workspace on a microcontroller (a 642-vertex mesh: 5,136 bytes): the snapped
//! screen position as two `i16` (sub-pixel units) and the depth, which is positive for every
//! projected vertex (`near / w` with `w >= near`), in two halves. A set top bit of the depth
//! marks a vertex without a cached position; its `x` then holds the clip outcodes. A vertex
//! whose position does not fit `i16` (or whose depth is not positive) is stored that way, so
//! its triangles take the clipping path, which computes the same position. The eye-space point
//! is not kept: the rare triangles that need clipping transform their vertices again, with the
//! same result.

use crate::math::zip3;
use crate::project::{ProjectionPrecision, ScreenVertex, SubPx, Viewport};
use crate::vertex::EyePoint;
use crate::Depth;
use fixed::types::I16F16;

/// One vertex as the frame sees it: its snapped screen position and depth when it is inside
/// every clip plane (and the position fits `i16`), else which clip planes it is outside.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CachedVertex {
    /// Screen position in sub-pixel units ([`SubPx`] bits); `x` holds the clip outcodes of a
    /// vertex without a cached position (bit `k`: outside plane `k` of
    /// [`Viewport::clip_distances`]).
    x: i16,
    y: i16,
    /// [`Depth`] bits, high and low half (two `u16` keep the entry 2-byte aligned: 8 bytes);
    /// [`NOT_PROJECTED`] set in the high half: no cached position.
    q: [u16; 2],
}

/// Set in the high half of [`CachedVertex::q`] when the vertex has no cached screen position
/// (it is outside a plane, its projection failed or its position does not fit `i16`):
/// triangles using it take the clipping path.
const NOT_PROJECTED: u16 = 0x8000;

impl CachedVertex {
    /// Size of one cache entry in bytes.
    pub const BYTES: usize = core::mem::size_of::<Self>();

    /// An unused entry (its value is never read before the frame fills it).
    pub const EMPTY: Self = CachedVertex {
        x: 0,
        y: 0,
        q: [NOT_PROJECTED, 0],
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
            .fold(0i16, |bits, (k, d)| bits | (((*d < 0) as i16) << k));
        let screen = if outside == 0 {
            vp.project_as::<P>(&eye, [I16F16::ZERO; 3], true)
        } else {
            None
        };
        let cached = screen.and_then(|s| {
            let q = s.q.to_bits();
            (q > 0).then_some(())?;
            Some(CachedVertex {
                x: i16::try_from(s.x.0).ok()?,
                y: i16::try_from(s.y.0).ok()?,
                q: [(q >> 16) as u16, q as u16],
            })
        });
        cached.unwrap_or(CachedVertex {
            x: outside,
            ..Self::EMPTY
        })
    }

    /// Whether this entry has a cached screen position.
    #[inline]
    fn projected(&self) -> bool {
        self.q[0] & NOT_PROJECTED == 0
    }

    /// The clip outcodes (0 for a vertex with a cached position, which is inside every plane).
    #[inline]
    fn outside(&self) -> i16 {
        if self.projected() {
            0
        } else {
            self.x
        }
    }

    /// The screen vertex with colour `color`, if this vertex has one.
    #[inline]
    pub(crate) fn screen<const S: u32>(&self, color: [I16F16; 3]) -> Option<ScreenVertex<S>> {
        self.projected().then(|| self.position(color))
    }

    /// The screen vertex with colour `color` from the entry's fields, which hold one if
    /// [`Self::projected`].
    #[inline]
    fn position<const S: u32>(&self, color: [I16F16; 3]) -> ScreenVertex<S> {
        ScreenVertex {
            x: SubPx(self.x as i32),
            y: SubPx(self.y as i32),
            q: Depth::from_bits((self.q[0] as i32) << 16 | self.q[1] as i32),
            color,
        }
    }

    /// The screen triangle of `v` with vertex colours `colors`, for three entries with a cached
    /// position ([`Self::all_projected`]; built as a value, not an `Option` of one, so it is
    /// written once where the caller keeps it).
    #[inline]
    pub(crate) fn triangle<const S: u32>(
        v: [&Self; 3],
        colors: [[I16F16; 3]; 3],
    ) -> [ScreenVertex<S>; 3] {
        debug_assert!(
            Self::all_projected(v),
            "internal error: a vertex without a position"
        );
        zip3(v, colors, |v, color| v.position(color))
    }

    /// The sub-pixel screen positions `(x, y)` of `v`, if all three have one cached.
    #[inline]
    pub(crate) fn positions(v: [&Self; 3]) -> Option<[(i32, i32); 3]> {
        Self::all_projected(v).then(|| v.map(|c| (c.x as i32, c.y as i32)))
    }

    /// Whether all three of `v` have a cached screen position (so they are inside every clip
    /// plane).
    #[inline]
    pub(crate) fn all_projected(v: [&Self; 3]) -> bool {
        (v[0].q[0] | v[1].q[0] | v[2].q[0]) & NOT_PROJECTED == 0
    }

    /// Whether all of `v` lie outside one clip plane (the triangle is invisible).
    #[inline]
    pub(crate) fn all_outside_one_plane(v: [&Self; 3]) -> bool {
        v[0].outside() & v[1].outside() & v[2].outside() != 0
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
    fn an_entry_is_8_bytes() {
        // Screen x, y (2 × 2), depth (2 × 2).
        assert_eq!(CachedVertex::BYTES, 8);
        assert_eq!(vertex_cache_bytes(731), 5_848);
    }

    #[test]
    fn positions_beyond_i16_are_not_cached() {
        // 2048 pixels wide with 8 sub-pixel bits: the screen's right half is beyond i16.
        let vp = Viewport::<8>::new(2048, 2048, 1.7, 0.5, 50.0).unwrap();
        let right = CachedVertex::new::<8, ExactDivision>(&vp, eye(2.0, 0.0, 5.0));
        assert!(vp
            .project_as::<ExactDivision>(&eye(2.0, 0.0, 5.0), [I16F16::ZERO; 3], true)
            .is_some());
        assert_eq!(right.outside(), 0);
        assert!(right.screen::<8>([I16F16::ZERO; 3]).is_none());
        assert!(!CachedVertex::all_outside_one_plane([&right; 3]));
    }

    #[test]
    fn outside_vertices_have_no_screen_position() {
        let vp = Viewport::<4>::new(240, 240, 1.7, 0.5, 50.0).unwrap();
        let behind = CachedVertex::new::<4, ExactDivision>(&vp, eye(0.0, 0.0, -1.0));
        let far = CachedVertex::new::<4, ExactDivision>(&vp, eye(0.0, 0.0, 80.0));
        let inside = CachedVertex::new::<4, ExactDivision>(&vp, eye(0.0, 0.0, 5.0));
        assert_eq!(behind.outside() & 1, 1);
        assert_eq!(far.outside() & 2, 2);
        assert_eq!(inside.outside(), 0);
        assert!(inside.screen::<4>([I16F16::ZERO; 3]).is_some());
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
