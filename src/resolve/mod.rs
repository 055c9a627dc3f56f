//! The classic hidden-surface methods on the shared pipeline.
//!
//! Transform, clipping, projection, bucketing by first row and the exact edge walk are the
//! same for every method (see [`crate::render`]); only the step that turns the active
//! triangles' spans into visible pixels differs. [`Workspace`](crate::Workspace) is the span
//! z-buffer (one row of depth). This module adds:
//!
//! | workspace | method | visibility memory | pixels written |
//! |---|---|---|---|
//! | [`BandWorkspace`] | z-buffer over bands of `B` rows (Catmull) | `B·W` depth + `B·W` pixels | every pixel that passes the depth test |
//! | [`ZBufferWorkspace`] | full-frame z-buffer: a band of `H` rows | `H·W` depth + `H·W` pixels | same |
//! | [`SpanSortWorkspace`] | span sorting (Watkins): visible segments from depths at span ends | one row of pixels, a span list; no depth | each pixel once |
//! | [`DepthSortWorkspace`] | depth sort / painter's: far to near by mean depth, overwriting | one row of pixels, a key per triangle; no depth | every covered pixel (overdraw) |
//! | [`NewellWorkspace`] | depth sort (Newell, Newell and Sancha): far to near, overlaps resolved by plane and projection tests, splitting cycles and interpenetration | every kept piece and its order, one row of pixels; no depth | every covered pixel (overdraw) |
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

use crate::arithmetic::Arithmetic;
use crate::clip::Clipping;
use crate::depth::Depth;
use crate::depth::{DepthFormat, DepthRow};
use crate::raster::PixelOrigin;
use crate::render::{
    drive, fill_span, internal, viewport, ActiveTri, FinishedRow, Frame, FrameStats, IdOrder,
    RenderError, RenderOptions, Resolve, MAX_INSTANCES, NO_ENTRY,
};
use crate::scene::Scene;
use crate::shading::Shading;
use crate::sink::{RowPixel, RowSink};
use heapless::{Vec, VecView};

pub mod bsp;
pub mod newell;
pub mod store;
pub mod warnock;
pub use newell::NewellWorkspace;
pub use warnock::WarnockWorkspace;

/// Compile-time checks shared by the workspaces.
const fn check_sizes(w: usize, h: usize, tris: usize) {
    assert!(
        w >= 1 && w <= crate::project::MAX_SCREEN,
        "width must be 1..=2048"
    );
    assert!(
        h >= 1 && h <= crate::project::MAX_SCREEN,
        "height must be 1..=2048"
    );
    assert!(
        tris <= crate::scene::MAX_SCENE_TRIANGLES,
        "TRIS must be at most 65535"
    );
}

/// Swaps `v[a]` and `v[b]`, which the caller knows to be in range (checked again, so that no
/// panic path remains).
fn swap_within<T>(v: &mut [T], a: usize, b: usize) {
    if a < v.len() && b < v.len() {
        v.swap(a, b);
    } else {
        debug_assert!(
            false,
            "internal error: swap of {a} and {b} out of {}",
            v.len()
        );
    }
}

/// Whether `v[a]`'s key is below `v[b]`'s (`false` if either is out of range).
fn key_below<T, K: Ord>(v: &[T], a: usize, b: usize, key: &mut impl FnMut(&T) -> K) -> bool {
    match (v.get(a), v.get(b)) {
        (Some(x), Some(y)) => key(x) < key(y),
        _ => false,
    }
}

/// Sorts `v` by `key`, ascending and unstably, without allocating and without a panic path:
/// insertion sort for up to 16 entries, heapsort (`O(n log n)`) beyond. (The standard
/// `sort_unstable_by_key` keeps a panic for inconsistent orders, which firmware must not link.)
pub(crate) fn sort_by_key<T, K: Ord>(v: &mut [T], mut key: impl FnMut(&T) -> K) {
    let n = v.len();
    if n <= 16 {
        for i in 1..n {
            let mut j = i;
            while j > 0 && key_below(v, j, j - 1, &mut key) {
                swap_within(v, j, j - 1);
                j -= 1;
            }
        }
        return;
    }
    // A max-heap by key, then its top moved to the end of the shrinking heap, `n − 1` times.
    let mut sift_down = |v: &mut [T], mut root: usize, end: usize| loop {
        let mut child = 2 * root + 1;
        if child >= end {
            break;
        }
        if child + 1 < end && key_below(v, child, child + 1, &mut key) {
            child += 1;
        }
        if !key_below(v, root, child, &mut key) {
            break;
        }
        swap_within(v, root, child);
        root = child;
    };
    for root in (0..n / 2).rev() {
        sift_down(v, root, n);
    }
    for end in (1..n).rev() {
        swap_within(v, 0, end);
        sift_down(v, 0, end);
    }
}

// ---------------------------------------------------------------------------------------------
// Band and full-frame z-buffer

/// A z-buffer over bands of `B` rows: per band, each triangle is walked through the band and
/// depth-tested per pixel, then the band's rows go to the sink. `B = 1` is the span z-buffer
/// ([`Workspace`](crate::Workspace)); `B = H` is the full-frame z-buffer
/// ([`ZBufferWorkspace`]). Between the two, `B` trades depth memory (`B·W·4` bytes) for
/// fewer, longer passes over the active triangles. `ACTIVE` holds the triangles that cross a
/// band boundary (none for `B = H`).
///
/// ```
/// use embedded_graphics::pixelcolor::Rgb565;
/// use scanline3d_demo as demo;
/// use scanline3d::{resolve::BandWorkspace, sink::HashSink, Flat, RenderOptions};
/// let mut ws: Box<BandWorkspace<Rgb565, Flat, 240, 240, 16, 1280, 96>> =
///     Box::new(BandWorkspace::new(Rgb565::new(0, 0, 0)));
/// let instances = demo::instances();
/// let scene = demo::scene(&instances, 0, demo::ORBIT_FRAMES)?;
/// let stats = ws.render(&scene, &RenderOptions::default(), &mut HashSink::new()).unwrap();
/// assert_eq!(stats.rows, 240);
/// # Ok::<(), scanline3d::scene::SceneError>(())
/// ```
pub struct BandWorkspace<
    P: RowPixel,
    S: Shading,
    const W: usize,
    const H: usize,
    const B: usize,
    const TRIS: usize = 1024,
    const ACTIVE: usize = 64,
    const INSTANCES: usize = MAX_INSTANCES,
    Z: DepthFormat = Depth,
> {
    depth: [[Z; W]; B],
    pixels: [[P; W]; B],
    spans: [u16; B],
    background: P,
    heads: [u16; H],
    next: [u16; TRIS],
    refs: [u16; TRIS],
    active: Vec<ActiveTri<S::Payload<P>>, ACTIVE>,
}

/// The full-frame z-buffer: a [`BandWorkspace`] whose band is the whole target, so every
/// triangle is drawn completely when its first row comes and none is kept active.
pub type ZBufferWorkspace<
    P,
    S,
    const W: usize,
    const H: usize,
    const TRIS: usize = 1024,
    const INSTANCES: usize = MAX_INSTANCES,
    Z = Depth,
> = BandWorkspace<P, S, W, H, H, TRIS, 0, INSTANCES, Z>;

/// The band resolver: `B` rows of depth and pixels, rows `y0 ..`.
struct Band<'a, P, Z> {
    depth: &'a mut [Z],
    pixels: &'a mut [P],
    spans: &'a mut [u16],
    background: P,
    width: usize,
    y0: i32,
}

impl<P: RowPixel, Z> Band<'_, P, Z> {
    /// Offset of row `y`'s first column in the band buffers.
    fn row_start(&self, y: i32) -> usize {
        (y - self.y0).max(0) as usize * self.width
    }
}

impl<P: RowPixel, S: Shading, Z: DepthFormat> Resolve<P, S> for Band<'_, P, Z> {
    type Key = ();
    fn band_rows(&self) -> usize {
        self.spans.len()
    }
    fn begin_band(&mut self, y0: i32, _: usize) {
        self.y0 = y0;
        self.depth.fill(Z::FAR);
        self.pixels.fill(self.background);
        self.spans.fill(0);
    }
    #[inline]
    fn span(&mut self, t: &ActiveTri<S::Payload<P>>, _: usize, y: i32, l: i32, r: i32) -> u32 {
        // The row walker hands over rows of the current band only.
        let at = self.row_start(y);
        if let Some(n) = self.spans.get_mut((y - self.y0) as usize) {
            *n += 1;
        } else {
            debug_assert!(false, "internal error: row {y} outside the band");
        }
        let (Some(depth), Some(pixels)) = (
            self.depth.get_mut(at..at + self.width),
            self.pixels.get_mut(at..at + self.width),
        ) else {
            debug_assert!(false, "internal error: row {y} outside the band");
            return 0;
        };
        fill_span::<P, S, Z, ()>(t, y, l, r, depth, pixels)
    }
    fn finish_row(&mut self, y: i32) -> FinishedRow<'_, P> {
        let at = self.row_start(y);
        let rows = at..at + self.width;
        FinishedRow {
            pixels: internal(self.pixels.get(rows.clone()), &[]),
            depth: Z::row(internal(self.depth.get(rows), &[])),
            spans: internal(self.spans.get((y - self.y0) as usize).copied(), 0),
            written: 0,
        }
    }
}

impl<
        P: RowPixel,
        S: Shading,
        const W: usize,
        const H: usize,
        const B: usize,
        const TRIS: usize,
        const ACTIVE: usize,
        const INSTANCES: usize,
        Z: DepthFormat,
    > BandWorkspace<P, S, W, H, B, TRIS, ACTIVE, INSTANCES, Z>
{
    /// Size of this workspace in bytes.
    pub const BYTES: usize = core::mem::size_of::<Self>();

    const VALID: () = {
        check_sizes(W, H, TRIS);
        assert!(B >= 1 && B <= H, "the band must be 1..=H rows");
    };

    /// An empty workspace whose background pixels are `background`.
    pub const fn new(background: P) -> Self {
        #[allow(clippy::let_unit_value)]
        let () = Self::VALID;
        BandWorkspace {
            depth: [[Z::FAR; W]; B],
            pixels: [[background; W]; B],
            spans: [0; B],
            background,
            heads: [NO_ENTRY; H],
            next: [NO_ENTRY; TRIS],
            refs: [0; TRIS],
            active: Vec::new(),
        }
    }

    /// Renders `scene`, handing each of the `H` rows to `sink` once, top to bottom.
    pub fn render<const SUB_BITS: u32, C: Clipping, A: Arithmetic, K: RowSink<P>>(
        &mut self,
        scene: &Scene<'_>,
        options: &RenderOptions<SUB_BITS, C, A>,
        sink: &mut K,
    ) -> Result<FrameStats, RenderError<K::Error>> {
        self.render_sized(W, H, scene, options, sink)
    }

    /// Renders a `width × height` target (at most `W × H`); see
    /// [`Workspace::render_sized`](crate::Workspace::render_sized).
    pub fn render_sized<const SUB_BITS: u32, C: Clipping, A: Arithmetic, K: RowSink<P>>(
        &mut self,
        width: usize,
        height: usize,
        scene: &Scene<'_>,
        options: &RenderOptions<SUB_BITS, C, A>,
        sink: &mut K,
    ) -> Result<FrameStats, RenderError<K::Error>> {
        let vp = viewport::<SUB_BITS, K::Error>(width, height, W, H, scene)?;
        let Some(heads) = self.heads.get_mut(..height) else {
            return Err(RenderError::InvalidTarget);
        };
        let rows = B.min(height);
        let (Some(depth), Some(pixels), Some(spans)) = (
            self.depth.as_flattened_mut().get_mut(..rows * width),
            self.pixels.as_flattened_mut().get_mut(..rows * width),
            self.spans.get_mut(..rows),
        ) else {
            return Err(RenderError::InvalidTarget);
        };
        let frame = Frame {
            heads,
            next: &mut self.next,
            refs: &mut self.refs,
            keys: &mut [],
            active: self.active.as_mut_view(),
            vertices: &mut [],
        };
        let mut band = Band {
            depth,
            pixels,
            spans,
            background: self.background,
            width,
            y0: 0,
        };
        drive::<P, S, SUB_BITS, C, A, K, INSTANCES, _>(
            frame,
            &mut band,
            &mut IdOrder,
            scene,
            options,
            &vp,
            sink,
        )
    }
}

// ---------------------------------------------------------------------------------------------
// Span sorting

/// One span on the current row, for span sorting.
#[derive(Clone, Copy, Debug)]
struct SortSpan<T> {
    l: i32,
    r: i32,
    /// Depth at column `l` and per-column step, in [`Depth`] bits.
    q: i64,
    dq: i64,
    /// Position on the active list: on an exact depth tie the lower one wins. The background
    /// is order −1 at depth 0, so it wins ties against surfaces at depth 0 (as a cleared
    /// z-buffer does).
    order: i32,
    payload: T,
    origin: PixelOrigin,
}

impl<T> SortSpan<T> {
    /// Depth at column `x` exactly as the span z-buffer steps it (wrapping `i32` adds).
    fn depth_at(&self, x: i32) -> i64 {
        (self.q + (x - self.l) as i64 * self.dq) as i32 as i64
    }

    /// Whether `self` is in front of `other` at column `x`.
    fn beats(&self, other: &Self, x: i32) -> bool {
        let (a, b) = (self.depth_at(x), other.depth_at(x));
        a > b || (a == b && self.order < other.order)
    }
}

/// Span sorting (Watkins): each row's spans are collected, then resolved left to right into
/// visible segments by comparing depths at segment ends and splitting where two spans' depths
/// cross. No depth memory at all; each pixel is written once.
///
/// ```
/// use embedded_graphics::pixelcolor::Rgb565;
/// use scanline3d_demo as demo;
/// use scanline3d::{resolve::SpanSortWorkspace, sink::HashSink, Flat, RenderOptions};
/// let mut ws: Box<SpanSortWorkspace<Rgb565, Flat, 240, 240, 1280, 96>> =
///     Box::new(SpanSortWorkspace::new(Rgb565::new(0, 0, 0)));
/// let instances = demo::instances();
/// let scene = demo::scene(&instances, 0, demo::ORBIT_FRAMES)?;
/// let stats = ws.render(&scene, &RenderOptions::default(), &mut HashSink::new()).unwrap();
/// // Each visible pixel is written exactly once.
/// assert!(stats.pixels_written <= 240 * 240);
/// # Ok::<(), scanline3d::scene::SceneError>(())
/// ```
pub struct SpanSortWorkspace<
    P: RowPixel,
    S: Shading,
    const W: usize,
    const H: usize,
    const TRIS: usize = 1024,
    const ACTIVE: usize = 64,
    const INSTANCES: usize = MAX_INSTANCES,
> {
    pixels: [P; W],
    background: P,
    heads: [u16; H],
    next: [u16; TRIS],
    refs: [u16; TRIS],
    active: Vec<ActiveTri<S::Payload<P>>, ACTIVE>,
    spans: Vec<SortSpan<S::Payload<P>>, ACTIVE>,
}

/// The span-sorting resolver.
struct SpanSort<'a, P, T> {
    pixels: &'a mut [P],
    background: P,
    spans: &'a mut VecView<SortSpan<T>>,
}

impl<P: RowPixel, S: Shading> Resolve<P, S> for SpanSort<'_, P, S::Payload<P>> {
    type Key = ();
    fn begin_band(&mut self, _: i32, _: usize) {
        self.pixels.fill(self.background);
        self.spans.clear();
    }
    #[inline]
    fn span(&mut self, t: &ActiveTri<S::Payload<P>>, order: usize, y: i32, l: i32, r: i32) -> u32 {
        let (q, dq) = t.depth.span_start(l, y);
        // At most one span per active triangle, and the list holds as many as the active list.
        let pushed = self.spans.push(SortSpan {
            l,
            r,
            q: q as i64,
            dq: dq as i64,
            order: order as i32,
            payload: t.payload,
            origin: *t.depth.origin(),
        });
        debug_assert!(
            pushed.is_ok(),
            "internal error: more spans than active triangles"
        );
        0
    }
    fn finish_row(&mut self, y: i32) -> FinishedRow<'_, P> {
        let written = sweep::<P, S>(self.spans.as_mut_slice(), y, self.pixels);
        FinishedRow {
            pixels: self.pixels,
            depth: DepthRow::NONE,
            spans: self.spans.len() as u16,
            written,
        }
    }
}

/// Resolves one row's spans left to right. A segment is a run of columns where the set of
/// spans present does not change; within it, the nearest span at the segment's first column
/// stays nearest until the first column where another span's depth (linear in the column)
/// overtakes it, which is computed exactly. Returns the pixels written.
///
/// The spans are sorted by first column; those present ("live") are kept at the front of the
/// slice, so each segment looks only at the few spans over it, not at the whole row.
fn sweep<P: RowPixel, S: Shading>(
    spans: &mut [SortSpan<S::Payload<P>>],
    y: i32,
    pixels: &mut [P],
) -> u32 {
    // (Ties between spans starting in one column do not matter: `beats` orders any two.)
    sort_by_key(spans, |s| s.l);
    let width = pixels.len() as i32;
    let mut written = 0u32;
    // spans[..live] are present at x, spans[live..next] have ended, spans[next..] start later.
    let (mut live, mut next) = (0usize, 0usize);
    let mut x = spans.first().map_or(width, |s| s.l);
    while x < width {
        while spans.get(next).is_some_and(|s| s.l <= x) {
            swap_within(spans, live, next);
            live += 1;
            next += 1;
        }
        let mut i = 0;
        while i < live {
            if spans.get(i).is_some_and(|s| s.r <= x) {
                live -= 1;
                swap_within(spans, i, live);
            } else {
                i += 1;
            }
        }
        let present = internal(spans.get(..live), &[]);
        // The end of the segment: the first span end or span start after x.
        let mut end = spans.get(next).map_or(width, |s| s.l.min(width));
        let mut front: Option<usize> = None;
        for (k, s) in present.iter().enumerate() {
            end = end.min(s.r);
            if front.is_none_or(|f| present.get(f).is_none_or(|f| s.beats(f, x))) {
                front = Some(k);
            }
        }
        let front = front.filter(|&f| present.get(f).is_some_and(|f| f.depth_at(x) > 0));
        let end = next_change(present, x, end, front);
        if let Some(f) = front.and_then(|f| present.get(f)) {
            if let Some(out) = pixels.get_mut(x as usize..end as usize) {
                S::paint(&f.payload, &f.origin, x, y, out);
                written += (end - x) as u32;
            } else {
                // Spans are clamped to the row and segments end within it.
                debug_assert!(false, "internal error: segment {x}..{end} out of the row");
            }
        }
        // end > x: present spans end after x and the next one starts after it.
        x = end;
    }
    written
}

/// The first column in `(x, end)` where another span in `present` overtakes the one at index
/// `front` (or, for `None`, rises above the background at depth 0); `end` if none does.
///
/// Depths are linear in the column and, inside a triangle, never near the `i32` limits, so
/// the stepped (wrapping) depths equal the exact linear ones used here.
fn next_change<T>(present: &[SortSpan<T>], x: i32, end: i32, front: Option<usize>) -> i32 {
    // The background is order −1 at depth 0 (it wins ties, like a cleared z-buffer).
    let (f_q, f_dq, f_order) = front
        .and_then(|f| present.get(f))
        .map_or((0, 0, -1), |f| (f.depth_at(x), f.dq, f.order));
    let mut change = end;
    for (k, s) in present.iter().enumerate() {
        if Some(k) == front {
            continue;
        }
        // s − front is linear in the column: d0 ≤ 0 at x, then `slope` per column. It can
        // only overtake if the slope is positive.
        let slope = s.dq - f_dq;
        if slope <= 0 {
            continue;
        }
        let need = f_q - s.depth_at(x);
        // Smallest k ≥ 1 with k·slope > need (or ≥ need when s wins ties).
        let k = if s.order < f_order {
            (need + slope - 1) / slope
        } else {
            need / slope + 1
        }
        .max(1);
        change = change.min(x.saturating_add(i32::try_from(k).unwrap_or(i32::MAX)));
    }
    change
}

impl<
        P: RowPixel,
        S: Shading,
        const W: usize,
        const H: usize,
        const TRIS: usize,
        const ACTIVE: usize,
        const INSTANCES: usize,
    > SpanSortWorkspace<P, S, W, H, TRIS, ACTIVE, INSTANCES>
{
    /// Size of this workspace in bytes.
    pub const BYTES: usize = core::mem::size_of::<Self>();

    const VALID: () = check_sizes(W, H, TRIS);

    /// An empty workspace whose background pixels are `background`.
    pub const fn new(background: P) -> Self {
        #[allow(clippy::let_unit_value)]
        let () = Self::VALID;
        SpanSortWorkspace {
            pixels: [background; W],
            background,
            heads: [NO_ENTRY; H],
            next: [NO_ENTRY; TRIS],
            refs: [0; TRIS],
            active: Vec::new(),
            spans: Vec::new(),
        }
    }

    /// Renders `scene`, handing each of the `H` rows to `sink` once, top to bottom.
    pub fn render<const SUB_BITS: u32, C: Clipping, A: Arithmetic, K: RowSink<P>>(
        &mut self,
        scene: &Scene<'_>,
        options: &RenderOptions<SUB_BITS, C, A>,
        sink: &mut K,
    ) -> Result<FrameStats, RenderError<K::Error>> {
        self.render_sized(W, H, scene, options, sink)
    }

    /// Renders a `width × height` target (at most `W × H`); see
    /// [`Workspace::render_sized`](crate::Workspace::render_sized).
    pub fn render_sized<const SUB_BITS: u32, C: Clipping, A: Arithmetic, K: RowSink<P>>(
        &mut self,
        width: usize,
        height: usize,
        scene: &Scene<'_>,
        options: &RenderOptions<SUB_BITS, C, A>,
        sink: &mut K,
    ) -> Result<FrameStats, RenderError<K::Error>> {
        let vp = viewport::<SUB_BITS, K::Error>(width, height, W, H, scene)?;
        let (Some(pixels), Some(heads)) =
            (self.pixels.get_mut(..width), self.heads.get_mut(..height))
        else {
            return Err(RenderError::InvalidTarget);
        };
        let frame = Frame {
            heads,
            next: &mut self.next,
            refs: &mut self.refs,
            keys: &mut [],
            active: self.active.as_mut_view(),
            vertices: &mut [],
        };
        let mut resolve = SpanSort {
            pixels,
            background: self.background,
            spans: self.spans.as_mut_view(),
        };
        drive::<P, S, SUB_BITS, C, A, K, INSTANCES, _>(
            frame,
            &mut resolve,
            &mut IdOrder,
            scene,
            options,
            &vp,
            sink,
        )
    }
}

// ---------------------------------------------------------------------------------------------
// Depth sort

/// Depth sort, the painter's algorithm: triangles are ordered far to near by the mean depth
/// of their vertices and painted in that order, each overwriting what is behind. Rows come out
/// one at a time all the same: the active list is kept in that order, so each row is painted
/// exactly as the whole frame would be. Fast and simple, and wrong where one depth per
/// triangle cannot order two surfaces (interpenetrating or cyclically overlapping triangles,
/// a long triangle beside a short one): the lecture's warning, measured in the tests.
///
/// ```
/// use embedded_graphics::pixelcolor::Rgb565;
/// use scanline3d_demo as demo;
/// use scanline3d::{resolve::DepthSortWorkspace, sink::HashSink, Flat, RenderOptions};
/// let mut ws: Box<DepthSortWorkspace<Rgb565, Flat, 240, 240, 1280, 96>> =
///     Box::new(DepthSortWorkspace::new(Rgb565::new(0, 0, 0)));
/// let instances = demo::instances();
/// let scene = demo::scene(&instances, 0, demo::ORBIT_FRAMES)?;
/// let stats = ws.render(&scene, &RenderOptions::default(), &mut HashSink::new()).unwrap();
/// // Every covered pixel is painted, hidden ones too.
/// assert_eq!(stats.pixels_written, stats.fragments);
/// # Ok::<(), scanline3d::scene::SceneError>(())
/// ```
pub struct DepthSortWorkspace<
    P: RowPixel,
    S: Shading,
    const W: usize,
    const H: usize,
    const TRIS: usize = 1024,
    const ACTIVE: usize = 64,
    const INSTANCES: usize = MAX_INSTANCES,
> {
    pixels: [P; W],
    background: P,
    heads: [u16; H],
    next: [u16; TRIS],
    refs: [u16; TRIS],
    keys: [u32; TRIS],
    active: Vec<ActiveTri<S::Payload<P>, u32>, ACTIVE>,
}

/// The painter's resolver: one row of pixels, spans painted in active-list (depth) order.
struct Painter<'a, P> {
    pixels: &'a mut [P],
    background: P,
    spans: u16,
}

impl<P: RowPixel, S: Shading> Resolve<P, S> for Painter<'_, P> {
    type Key = u32;
    fn begin_band(&mut self, _: i32, _: usize) {
        self.pixels.fill(self.background);
        self.spans = 0;
    }
    #[inline]
    fn span(&mut self, t: &ActiveTri<S::Payload<P>, u32>, _: usize, y: i32, l: i32, r: i32) -> u32 {
        self.spans += 1;
        match self.pixels.get_mut(l as usize..r as usize) {
            Some(out) => {
                S::paint(&t.payload, t.depth.origin(), l, y, out);
                (r - l) as u32
            }
            None => {
                // walk_band clamps spans to the row.
                debug_assert!(false, "internal error: span {l}..{r} out of the row");
                0
            }
        }
    }
    fn finish_row(&mut self, _: i32) -> FinishedRow<'_, P> {
        FinishedRow {
            pixels: self.pixels,
            depth: DepthRow::NONE,
            spans: self.spans,
            written: 0,
        }
    }
}

impl<
        P: RowPixel,
        S: Shading,
        const W: usize,
        const H: usize,
        const TRIS: usize,
        const ACTIVE: usize,
        const INSTANCES: usize,
    > DepthSortWorkspace<P, S, W, H, TRIS, ACTIVE, INSTANCES>
{
    /// Size of this workspace in bytes.
    pub const BYTES: usize = core::mem::size_of::<Self>();

    const VALID: () = check_sizes(W, H, TRIS);

    /// An empty workspace whose background pixels are `background`.
    pub const fn new(background: P) -> Self {
        #[allow(clippy::let_unit_value)]
        let () = Self::VALID;
        DepthSortWorkspace {
            pixels: [background; W],
            background,
            heads: [NO_ENTRY; H],
            next: [NO_ENTRY; TRIS],
            refs: [0; TRIS],
            keys: [0; TRIS],
            active: Vec::new(),
        }
    }

    /// Renders `scene`, handing each of the `H` rows to `sink` once, top to bottom.
    pub fn render<const SUB_BITS: u32, C: Clipping, A: Arithmetic, K: RowSink<P>>(
        &mut self,
        scene: &Scene<'_>,
        options: &RenderOptions<SUB_BITS, C, A>,
        sink: &mut K,
    ) -> Result<FrameStats, RenderError<K::Error>> {
        self.render_sized(W, H, scene, options, sink)
    }

    /// Renders a `width × height` target (at most `W × H`); see
    /// [`Workspace::render_sized`](crate::Workspace::render_sized).
    pub fn render_sized<const SUB_BITS: u32, C: Clipping, A: Arithmetic, K: RowSink<P>>(
        &mut self,
        width: usize,
        height: usize,
        scene: &Scene<'_>,
        options: &RenderOptions<SUB_BITS, C, A>,
        sink: &mut K,
    ) -> Result<FrameStats, RenderError<K::Error>> {
        let vp = viewport::<SUB_BITS, K::Error>(width, height, W, H, scene)?;
        let (Some(pixels), Some(heads)) =
            (self.pixels.get_mut(..width), self.heads.get_mut(..height))
        else {
            return Err(RenderError::InvalidTarget);
        };
        let frame = Frame {
            heads,
            next: &mut self.next,
            refs: &mut self.refs,
            keys: &mut self.keys,
            active: self.active.as_mut_view(),
            vertices: &mut [],
        };
        let mut resolve = Painter {
            pixels,
            background: self.background,
            spans: 0,
        };
        drive::<P, S, SUB_BITS, C, A, K, INSTANCES, _>(
            frame,
            &mut resolve,
            &mut IdOrder,
            scene,
            options,
            &vp,
            sink,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec::Vec;

    #[test]
    fn the_panic_free_sort_sorts_like_the_standard_one() {
        // Lengths on both sides of the switch to heapsort, with and without repeated keys.
        let mut seed = 0x2545_f491_u32;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 17;
            seed ^= seed << 5;
            seed
        };
        for len in (0..=40).chain([255, 1000]) {
            for range in [4, 1 << 20] {
                let v: Vec<(u32, usize)> = (0..len).map(|i| (next() % range, i)).collect();
                let mut ours = v.clone();
                sort_by_key(&mut ours, |p| p.0);
                let mut theirs = v.clone();
                theirs.sort_by_key(|p| p.0);
                // The same keys in order, and the same entries (unstable: ties in any order).
                assert!(ours.windows(2).all(|w| w[0].0 <= w[1].0), "{len}");
                assert_eq!(
                    ours.iter().map(|p| p.0).collect::<Vec<_>>(),
                    theirs.iter().map(|p| p.0).collect::<Vec<_>>()
                );
                ours.sort();
                theirs.sort();
                assert_eq!(ours, theirs, "{len}");
            }
        }
    }
}
