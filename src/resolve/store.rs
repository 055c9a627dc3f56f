//! Whole-frame geometry: every visible screen triangle of a frame, kept for the methods that
//! need them all at once (Warnock's area subdivision, Newell's depth sort), and a way to walk
//! kept triangles row by row through the shared row walker.
//!
//! Screen space with depth `q = near/w` is a projective image of eye space, so a triangle's
//! plane stays a plane in `(x, y, q)`: depth comparisons and splits are exact linear algebra
//! there, and the eye is at `q = +∞` (larger `q` is nearer).

use crate::arithmetic::Arithmetic;
use crate::clip::Clipping;
use crate::depth::Depth;
use crate::options::RenderOptions;
use crate::project::{ScreenVertex, SubPx, Viewport};
use crate::raster::{channel, color_channels, first_row};
use crate::render::{for_each_screen_piece, internal, ActivePieces, NO_ENTRY};
use crate::scene::Scene;
use crate::shading::Shading;
use crate::stats::{CapacityKind, FrameStats, RenderError};
use embedded_graphics::pixelcolor::Rgb888;

/// A visible screen triangle (or clipped piece), as whole-frame methods keep it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StoredTriangle {
    /// Vertex columns in sub-pixels (the bits of `SubPx<S>` for the render's `S`).
    pub x: [i32; 3],
    /// Vertex rows in sub-pixels.
    pub y: [i32; 3],
    /// Vertex depths `q = near/w` (the bits of [`Depth`], I2F30).
    pub q: [i32; 3],
    /// Global triangle id (as in [`TriangleId`](crate::sink::TriangleId)).
    pub id: u32,
    /// Lit colour per vertex, rounded to 8 bits a channel (the face colour three times for
    /// flat shading).
    pub colors: [Rgb888; 3],
}

impl StoredTriangle {
    /// An empty entry (for initialising buffers).
    pub const EMPTY: StoredTriangle = StoredTriangle {
        x: [0; 3],
        y: [0; 3],
        q: [0; 3],
        id: 0,
        colors: [Rgb888::new(0, 0, 0); 3],
    };

    /// Keeps screen piece `v` of triangle `id`.
    pub(crate) fn new<const S: u32>(
        v: &[ScreenVertex<S>; 3],
        face: Rgb888,
        id: u32,
        per_vertex: bool,
    ) -> Self {
        let color = |s: &ScreenVertex<S>| {
            if per_vertex {
                let c = s.color.map(|c| channel(c.to_bits()));
                Rgb888::new(c[0], c[1], c[2])
            } else {
                face
            }
        };
        StoredTriangle {
            x: v.each_ref().map(|s| s.x.0),
            y: v.each_ref().map(|s| s.y.0),
            q: v.each_ref().map(|s| s.q.to_bits()),
            id,
            colors: v.each_ref().map(color),
        }
    }

    /// The screen vertices again, for set-up.
    pub(crate) fn screen<const S: u32>(&self) -> [ScreenVertex<S>; 3] {
        // Destructured rather than indexed: no bounds check to leave a panic path.
        let vertex = |x, y, q, c| ScreenVertex {
            x: SubPx(x),
            y: SubPx(y),
            q: Depth::from_bits(q),
            color: color_channels(c),
        };
        let ([x0, x1, x2], [y0, y1, y2], [q0, q1, q2], [c0, c1, c2]) =
            (self.x, self.y, self.q, self.colors);
        [
            vertex(x0, y0, q0, c0),
            vertex(x1, y1, q1, c1),
            vertex(x2, y2, q2, c2),
        ]
    }

    /// The face colour (vertex 0's colour).
    pub(crate) fn face(&self) -> Rgb888 {
        self.colors[0]
    }
}

impl Default for StoredTriangle {
    fn default() -> Self {
        Self::EMPTY
    }
}

/// Keeps every visible screen piece of `scene` in `store`, in id order. Returns how many and
/// the frame statistics so far; a store too small is an error before anything is drawn.
pub(crate) fn collect<
    S: Shading,
    const SUB: u32,
    C: Clipping,
    A: Arithmetic,
    E,
    const INSTANCES: usize,
>(
    scene: &Scene<'_>,
    options: &RenderOptions<SUB, C, A>,
    vp: &Viewport<SUB>,
    store: &mut [StoredTriangle],
) -> Result<(usize, FrameStats), RenderError<E>> {
    let mut n = 0usize;
    let stats =
        for_each_screen_piece::<S, SUB, C, A, E, INSTANCES>(scene, options, vp, |s, face, id| {
            if let Some(slot) = store.get_mut(n) {
                *slot = StoredTriangle::new(&s, face, id, S::PER_VERTEX);
            }
            n += 1;
        })?;
    if n > store.len() {
        return Err(RenderError::Capacity {
            what: CapacityKind::Pieces,
            needed: n,
            capacity: store.len(),
        });
    }
    Ok((n, stats))
}

/// Files kept pieces in row buckets by first row (threaded through `heads` and `next`, entry =
/// index in `store`), each row's list in index order. Pieces off screen are left out.
pub(crate) fn bucket<const SUB: u32>(
    store: &[StoredTriangle],
    vp: &Viewport<SUB>,
    heads: &mut [u16],
    next: &mut [u16],
) {
    heads.fill(NO_ENTRY);
    let (w, h) = (vp.width as i32, vp.height as i32);
    for (i, t) in store.iter().enumerate().rev() {
        let Some(row) = first_row(&t.screen::<SUB>(), w, h) else {
            continue;
        };
        if let (Some(head), Some(link)) = (heads.get_mut(row as usize), next.get_mut(i)) {
            *link = *head;
            *head = i as u16;
        } else {
            // First rows are on screen; there is a link per kept piece.
            debug_assert!(false, "internal error: piece {i} not filed on row {row}");
        }
    }
}

/// Kept pieces for the row walker: a bucket entry is an index in the store, and its sort key
/// (for painters) is `keys[entry]`.
pub(crate) struct StoredPieces<'a> {
    pub(crate) store: &'a [StoredTriangle],
    pub(crate) keys: &'a [u32],
}

impl<const SUB: u32> ActivePieces<SUB> for StoredPieces<'_> {
    #[inline]
    fn each_piece<S: Shading>(
        &self,
        entry: usize,
        mut f: impl FnMut(&[ScreenVertex<SUB>; 3], Rgb888, u32, u32),
    ) {
        // Entries index the store, which has a key per piece.
        if let Some(t) = self.store.get(entry) {
            let key = internal(self.keys.get(entry).copied(), 0);
            f(&t.screen::<SUB>(), t.face(), t.id, key);
        } else {
            debug_assert!(false, "internal error: no kept piece {entry}");
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use embedded_graphics::pixelcolor::RgbColor;

    #[test]
    fn a_kept_piece_gives_back_its_screen_vertices() {
        let v = [(0, 0, 100), (64, 8, 200), (5, 70, 300)].map(|(x, y, q)| ScreenVertex::<4> {
            x: SubPx(x),
            y: SubPx(y),
            q: Depth::from_bits(q),
            color: color_channels(Rgb888::new(10, 20, 30)),
        });
        let t = StoredTriangle::new(&v, Rgb888::WHITE, 7, true);
        assert_eq!(t.screen::<4>(), v);
        assert_eq!((t.id, t.face()), (7, Rgb888::new(10, 20, 30)));
        let flat = StoredTriangle::new(&v, Rgb888::WHITE, 7, false);
        assert_eq!(flat.colors, [Rgb888::WHITE; 3]);
    }
}
