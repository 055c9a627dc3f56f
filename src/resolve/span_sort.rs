//! Span sorting (Watkins): visible segments from the depths at the span ends, no depth memory.

use crate::arithmetic::Arithmetic;
use crate::clip::Clipping;
use crate::depth::DepthRow;
use crate::options::{RenderOptions, MAX_INSTANCES};
use crate::raster::DepthWalk;
use crate::render::Unbounded;
use crate::render::{
    drive, internal, viewport, ActiveTri, FinishedRow, Frame, IdOrder, Resolve, NO_ENTRY,
};
use crate::resolve::common::{check_sizes, render_whole_target, sort_by_key, swap_within};
use crate::scene::Scene;
use crate::shading::Shading;
use crate::sink::{RowPixel, RowSink};
use crate::stats::{FrameStats, RenderError};
use heapless::{Vec, VecView};

/// One span on the current row, for span sorting.
#[derive(Clone, Copy, Debug)]
struct SortSpan<T> {
    l: i32,
    r: i32,
    /// Depth at column `l` and per-column step, in [`Depth`](crate::depth::Depth) bits.
    q: i64,
    dq: i64,
    /// Position on the active list: on an exact depth tie the lower one wins. The background
    /// is order −1 at depth 0, so it wins ties against surfaces at depth 0 (as a cleared
    /// z-buffer does).
    order: i32,
    payload: T,
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
        // Spans come from the walk, on its current row.
        debug_assert_eq!(y, t.walk.row(), "internal error: span off the walk's row");
        let (q, dq) = (t.depth.span_start(l), t.depth_step);
        // At most one span per active triangle, and the list holds as many as the active list.
        let pushed = self.spans.push(SortSpan {
            l,
            r,
            q: q as i64,
            dq: dq as i64,
            order: order as i32,
            payload: t.payload,
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
                S::paint(&f.payload, x, y, out);
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

    render_whole_target!();

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
        drive::<P, S, SUB_BITS, C, A, K, INSTANCES, _, _, Unbounded>(
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
