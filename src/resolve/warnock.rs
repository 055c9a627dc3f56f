//! Warnock's area subdivision on the shared pipeline.
//!
//! # The algorithm
//!
//! Every visible screen piece of the frame is kept (the [`store`] module: transform, clipping,
//! projection and culling are the shared ones). Then screen windows (rectangles of pixel
//! centres) are examined, starting with the whole target. For each window, every candidate
//! piece inherited from the parent window is classified by its exact coverage of the window's
//! centres: *disjoint* (covers none), *surrounding* (covers all) or *partial*. Then:
//!
//! 1. no piece is left: the window stays background;
//! 2. one piece is left: its exact coverage inside the window is painted;
//! 3. a surrounding piece is in front of every other piece over the whole window: the window
//!    is filled with it;
//! 4. the window is a single pixel: the nearest piece covering its centre is painted;
//! 5. otherwise the window is split into (up to) four and each quarter is examined the same way
//!    with the pieces that were not disjoint.
//!
//! # Exactly the span z-buffer's frame
//!
//! Coverage is the exact edge walk (`TriangleWalk`) restricted to the window, so the
//! top-left rule and the snapped vertices are those of every other method. Depth is evaluated
//! exactly as the span z-buffer steps it along a row: from `DepthPlane::span_start` at the
//! left end of the piece's span on that row, plus `dq` per pixel (wrapping `i32`). That value
//! is linear in the column along a row, so "in front over the whole window" is decided row by
//! row from the two ends of each overlap, without sampling every pixel; where the linear value
//! leaves the `i32` range (never for real scenes) the window is split instead, and single
//! pixels use the wrapped value itself. Ties follow the renderer's rule: strictly nearer wins;
//! on an exact tie the piece activated first (the triangle with the lower first row, then the
//! lower id) keeps the pixel; depth 0 or less never beats the background. Frames are therefore
//! bit-identical to the span z-buffer's for flat shading (ids and colours). With Gouraud
//! shading the kept pieces carry vertex colours rounded to 8 bits a channel and spans are
//! painted from the window's edge, so colours could differ from the span z-buffer's by
//! rounding (ids cannot); on the demo orbit they are identical (`tests/suite/warnock.rs`).
//!
//! # Memory
//!
//! A [`WarnockWorkspace`] holds, in bytes:
//!
//! * `PIECES · size_of::<StoredTriangle>()` (52): the kept pieces;
//! * `W · H · size_of::<P>()`: the frame buffer (windows finish in no particular row order, so
//!   rows reach the sink only once the whole frame is resolved);
//! * `LIST · 2`: the window index buffer (candidate lists, see below);
//! * `STACK · 16`: the window stack.
//!
//! [`WarnockWorkspace::BYTES`] gives the total. The subdivision is an explicit stack, not
//! recursion: a window is popped, examined and replaced by its quarters. Depth first, at most
//! three quarters per level wait on the stack, so a `w × h` target needs
//! [`stack_needed`]`(w, h)` = `3 · ⌈log2 max(w, h)⌉ + 1` entries (25 for 240 × 240, 34 for
//! 2048); a smaller stack is a [`RenderError::Capacity`] error before anything is drawn.
//!
//! Each window's pieces (those not disjoint from it) go to the index buffer just above the
//! list it inherited, and its quarters share that list. The stack is last-in first-out, so when
//! a window is popped everything above its inherited list is dead and is reused. When the
//! buffer is full, a window's quarters inherit its parent's list unfiltered instead: the frame
//! is the same, only slower (each quarter classifies more pieces). This is counted in
//! [`SubdivisionStats::unfiltered`].
//!
//! # Frame statistics
//!
//! `triangles_in`, `culled`, `clipped`, `rejected`, `unclipped` and `bucketed` are as for the
//! other methods; `activated` is the number of kept pieces; `pixels_written` is the number of
//! pixels painted (each visible pixel exactly once). `spans`, `fragments`, `peak_active` and
//! `peak_spans` have no meaning here and are 0; the subdivision's own counts are in
//! [`WarnockWorkspace::subdivision`]. Nothing is ever dropped: the frame is always complete.

use crate::arithmetic::Arithmetic;
use crate::clip::Clipping;
use crate::depth::DepthRow;
use crate::options::{RenderOptions, MAX_INSTANCES};
use crate::project::{ScreenVertex, Viewport};
use crate::raster::{DepthPlane, PlaneSolver, TriangleWalk};
use crate::render::{internal, viewport};
use crate::resolve::common::{check_sizes, render_whole_target};
use crate::resolve::store::{self, StoredTriangle};
use crate::scene::Scene;
use crate::shading::Shading;
use crate::sink::{Row, RowPixel, RowSink};
use crate::stats::{CapacityKind, FrameStats, RenderError};
use core::marker::PhantomData;

/// Entries of the window stack a `width × height` target needs: `3 · ⌈log2 max(w, h)⌉ + 1`
/// (each split leaves at most three quarters waiting while the fourth is examined).
///
/// ```
/// use scanline3d::resolve::warnock::stack_needed;
/// assert_eq!(stack_needed(1, 1), 1);
/// assert_eq!(stack_needed(240, 240), 25);
/// assert_eq!(stack_needed(2048, 16), 34);
/// ```
pub const fn stack_needed(width: usize, height: usize) -> usize {
    let n = if width > height { width } else { height };
    let mut levels = 0;
    while (1usize << levels) < n {
        levels += 1;
    }
    3 * levels + 1
}

/// What one frame's subdivision did (see [`WarnockWorkspace::subdivision`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SubdivisionStats {
    /// Windows examined.
    pub windows: u32,
    /// Windows with exactly one piece, painted with its exact coverage.
    pub single: u32,
    /// Windows filled with a surrounding piece in front of all others.
    pub filled: u32,
    /// Single-pixel windows resolved by comparing depths at the centre.
    pub pixels: u32,
    /// Windows whose quarters inherited the parent's list unfiltered because the index buffer
    /// was full (0 unless `LIST` is too small for the frame; the frame is the same).
    pub unfiltered: u32,
    /// Most stack entries in use at once.
    pub peak_stack: u16,
    /// Most index-buffer entries in use at once.
    pub peak_list: u32,
}

/// A candidate list: entries `start .. start + len` of the index buffer, or, with
/// `start == ALL`, the first `len` kept pieces themselves.
#[derive(Clone, Copy, Debug)]
struct List {
    start: u32,
    len: u32,
}

const ALL: u32 = u32::MAX;

impl List {
    /// Where a window with this inherited list may write its own list.
    fn end(&self) -> usize {
        if self.start == ALL {
            0
        } else {
            self.start as usize + self.len as usize
        }
    }
}

/// A window: pixel centres `[x0, x1) × [y0, y1)` and the pieces it inherits. 16 bytes.
#[derive(Clone, Copy, Debug)]
struct Window {
    x0: u16,
    y0: u16,
    x1: u16,
    y1: u16,
    list: List,
}

impl Window {
    const EMPTY: Window = Window {
        x0: 0,
        y0: 0,
        x1: 0,
        y1: 0,
        list: List { start: 0, len: 0 },
    };
}

/// Warnock's area subdivision: windows of the screen are split until each is empty, covered
/// by one piece in front of all others, holds a single piece, or is one pixel. Renders the same
/// frame as the span z-buffer (see the [module docs](self) for the rules and the memory).
///
/// * `PIECES`: screen pieces kept per frame (a triangle cut by the clipper counts once per
///   piece; ≤ 65535);
/// * `LIST`: index-buffer entries for the windows' piece lists (too few only slows the frame
///   down);
/// * `STACK`: window-stack entries, at least [`stack_needed`]`(width, height)`.
///
/// ```
/// use embedded_graphics::pixelcolor::Rgb565;
/// use scanline3d_demo as demo;
/// use scanline3d::{resolve::WarnockWorkspace, sink::HashSink, Flat, RenderOptions};
/// let mut ws: Box<WarnockWorkspace<Rgb565, Flat, 240, 240, 1280>> =
///     Box::new(WarnockWorkspace::new(Rgb565::new(0, 0, 0)));
/// let instances = demo::instances();
/// let scene = demo::scene(&instances, 0, demo::ORBIT_FRAMES)?;
/// let stats = ws.render(&scene, &RenderOptions::default(), &mut HashSink::new()).unwrap();
/// // Each visible pixel is painted exactly once.
/// assert!(stats.pixels_written <= 240 * 240);
/// assert!(ws.subdivision().windows > 1);
/// # Ok::<(), scanline3d::scene::SceneError>(())
/// ```
pub struct WarnockWorkspace<
    P: RowPixel,
    S: Shading,
    const W: usize,
    const H: usize,
    const PIECES: usize = 1024,
    const LIST: usize = 4096,
    const STACK: usize = 40,
    const INSTANCES: usize = MAX_INSTANCES,
> {
    store: [StoredTriangle; PIECES],
    frame: [[P; W]; H],
    background: P,
    list: [u16; LIST],
    stack: [Window; STACK],
    last: SubdivisionStats,
    shading: PhantomData<S>,
}

impl<
        P: RowPixel,
        S: Shading,
        const W: usize,
        const H: usize,
        const PIECES: usize,
        const LIST: usize,
        const STACK: usize,
        const INSTANCES: usize,
    > WarnockWorkspace<P, S, W, H, PIECES, LIST, STACK, INSTANCES>
{
    /// Size of this workspace in bytes.
    pub const BYTES: usize = core::mem::size_of::<Self>();

    const VALID: () = {
        check_sizes(W, H, 0);
        // Pieces are named by `u16` indices in the lists.
        assert!(PIECES <= u16::MAX as usize, "PIECES must be at most 65535");
        assert!(LIST < u32::MAX as usize, "LIST must be below 2^32 - 1");
    };

    /// An empty workspace whose background pixels are `background`.
    pub const fn new(background: P) -> Self {
        #[allow(clippy::let_unit_value)]
        let () = Self::VALID;
        WarnockWorkspace {
            store: [StoredTriangle::EMPTY; PIECES],
            frame: [[background; W]; H],
            background,
            list: [0; LIST],
            stack: [Window::EMPTY; STACK],
            last: SubdivisionStats {
                windows: 0,
                single: 0,
                filled: 0,
                pixels: 0,
                unfiltered: 0,
                peak_stack: 0,
                peak_list: 0,
            },
            shading: PhantomData,
        }
    }

    /// What the last frame's subdivision did.
    pub fn subdivision(&self) -> SubdivisionStats {
        self.last
    }

    render_whole_target!();

    /// Renders a `width × height` target (at most `W × H`); see
    /// [`Workspace::render_sized`](crate::Workspace::render_sized). A stack smaller than
    /// [`stack_needed`]`(width, height)` or more pieces than `PIECES` is a
    /// [`RenderError::Capacity`] error before any row is sent.
    pub fn render_sized<const SUB_BITS: u32, C: Clipping, A: Arithmetic, K: RowSink<P>>(
        &mut self,
        width: usize,
        height: usize,
        scene: &Scene<'_>,
        options: &RenderOptions<SUB_BITS, C, A>,
        sink: &mut K,
    ) -> Result<FrameStats, RenderError<K::Error>> {
        let vp = viewport::<SUB_BITS, K::Error>(width, height, W, H, scene)?;
        let needed = stack_needed(width, height);
        if STACK < needed {
            return Err(RenderError::Capacity {
                what: CapacityKind::WindowStack,
                needed,
                capacity: STACK,
            });
        }
        let (n, mut stats) = store::collect::<S, SUB_BITS, C, A, K::Error, INSTANCES>(
            scene,
            options,
            &vp,
            &mut self.store,
        )?;
        stats.activated = n as u32;
        let frame = self.frame.as_flattened_mut();
        // (`width <= W` and `n <= PIECES`: the viewport and `collect` checked them.)
        for row in frame.chunks_mut(W).take(height) {
            if let Some(row) = row.get_mut(..width) {
                row.fill(self.background);
            } else {
                debug_assert!(false, "internal error: width {width} beyond the frame");
            }
        }
        let mut sub = Subdivision::<P, S, SUB_BITS> {
            store: internal(self.store.get(..n), &[]),
            frame,
            stride: W,
            vp: &vp,
            list: &mut self.list,
            written: 0,
            stats: SubdivisionStats::default(),
            shading: PhantomData,
        };
        let result = sub.run(&mut self.stack, n);
        stats.pixels_written = sub.written;
        self.last = sub.stats;
        result?;

        for (y, row) in self.frame.iter().take(height).enumerate() {
            sink.write_row(Row {
                y: y as u16,
                pixels: internal(row.get(..width), &[]),
                depth: DepthRow::NONE,
                complete: true,
            })
            .map_err(|error| RenderError::Sink {
                row: y as u16,
                error,
            })?;
            stats.rows += 1;
        }
        Ok(stats)
    }
}

/// How a piece meets a window.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Class {
    Disjoint,
    Partial,
    Surrounds,
}

/// A piece set up for depth and paint: its plane and shading payload.
struct Surface<T> {
    plane: DepthPlane,
    payload: T,
}

/// The depth the span z-buffer steps to at column `x` of a span whose walk starts at column
/// `l` on row `y` (spans are clipped to the screen's left edge first), before the `i32`
/// wrap: linear in `x`.
#[inline]
fn stepped(plane: &DepthPlane, l: i32, y: i32, x: i32) -> i64 {
    let l = l.max(0);
    let (q, dq) = plane.span_start(l, y);
    q as i64 + (x - l) as i64 * dq as i64
}

/// Whether a stepped depth is stored without wrapping.
#[inline]
fn fits(q: i64) -> bool {
    q >= i32::MIN as i64 && q <= i32::MAX as i64
}

/// The first column (or row) whose centre is at or after sub-pixel position `p`.
#[inline]
fn centre_at_or_after<const SUB: u32>(p: i32) -> i64 {
    let den = 1i64 << (SUB + 1);
    -((-(2 * p as i64 - (1i64 << SUB))).div_euclid(den))
}

/// The subdivision of one frame.
struct Subdivision<'a, P, S, const SUB: u32> {
    store: &'a [StoredTriangle],
    /// The frame, rows of `stride` pixels.
    frame: &'a mut [P],
    stride: usize,
    vp: &'a Viewport<SUB>,
    list: &'a mut [u16],
    written: u32,
    stats: SubdivisionStats,
    shading: PhantomData<S>,
}

impl<P: RowPixel, S: Shading, const SUB: u32> Subdivision<'_, P, S, SUB> {
    /// Runs the subdivision over the whole target with the first `n` kept pieces.
    fn run<E>(&mut self, stack: &mut [Window], n: usize) -> Result<(), RenderError<E>> {
        let capacity = stack.len();
        let needed = stack_needed(self.vp.width as usize, self.vp.height as usize);
        // (Not reached when the stack holds `needed` entries, which the caller checks.)
        let overflow = || RenderError::Capacity {
            what: CapacityKind::WindowStack,
            needed,
            capacity,
        };
        let root = Window {
            x0: 0,
            y0: 0,
            x1: self.vp.width,
            y1: self.vp.height,
            list: List {
                start: ALL,
                len: n as u32,
            },
        };
        let Some(slot) = stack.first_mut() else {
            return Err(overflow());
        };
        *slot = root;
        let mut depth = 1usize;
        while depth > 0 {
            depth -= 1;
            let Some(&win) = stack.get(depth) else {
                debug_assert!(false, "internal error: window {depth} beyond the stack");
                break;
            };
            let Some(children) = self.examine(&win) else {
                continue;
            };
            // Split in halves along each side longer than one pixel; push in reverse so the
            // top-left quarter is examined first.
            let (mx, my) = ((win.x0 + win.x1) / 2, (win.y0 + win.y1) / 2);
            let xs = if win.x1 - win.x0 > 1 {
                [(win.x0, mx), (mx, win.x1)]
            } else {
                [(win.x0, win.x1), (0, 0)]
            };
            let ys = if win.y1 - win.y0 > 1 {
                [(win.y0, my), (my, win.y1)]
            } else {
                [(win.y0, win.y1), (0, 0)]
            };
            for &(y0, y1) in ys.iter().rev() {
                for &(x0, x1) in xs.iter().rev() {
                    if x0 >= x1 || y0 >= y1 {
                        continue;
                    }
                    let Some(slot) = stack.get_mut(depth) else {
                        return Err(overflow());
                    };
                    *slot = Window {
                        x0,
                        y0,
                        x1,
                        y1,
                        list: children,
                    };
                    depth += 1;
                }
            }
            self.stats.peak_stack = self.stats.peak_stack.max(depth as u16);
        }
        Ok(())
    }

    /// The `k`-th piece of list `list`.
    #[inline]
    fn entry(&self, list: &List, k: u32) -> Option<usize> {
        if list.start == ALL {
            Some(k as usize)
        } else {
            let at = list.start as usize + k as usize;
            self.list.get(at).map(|&i| i as usize)
        }
    }

    /// Examines window `win`: paints it if it is simple enough, else returns the list its
    /// quarters inherit.
    fn examine(&mut self, win: &Window) -> Option<List> {
        self.stats.windows += 1;
        // Filter the inherited list into the index buffer right above it (everything above it
        // is dead: the stack is last-in first-out).
        let top = win.list.end();
        let (mut kept, mut full) = (0usize, false);
        let (mut relevant, mut only) = (0u32, 0usize);
        let mut front: Option<(usize, i32)> = None;
        // Lists name kept pieces and lie within the index buffer (see `entry`).
        for k in 0..win.list.len {
            let Some(i) = self.entry(&win.list, k) else {
                debug_assert!(false, "internal error: list entry {k} out of the buffer");
                break;
            };
            let Some(t) = self.store.get(i) else {
                debug_assert!(false, "internal error: no kept piece {i}");
                continue;
            };
            let class = classify::<SUB>(t, win);
            if class == Class::Disjoint {
                continue;
            }
            relevant += 1;
            only = i;
            match self.list.get_mut(top + kept) {
                Some(slot) if !full => {
                    *slot = i as u16;
                    kept += 1;
                }
                _ => full = true,
            }
            if class == Class::Surrounds {
                // Only the surrounder nearest at the window's first pixel can be in front
                // over the whole window.
                if let Some(q) = self.depth_at(i, win.x0 as i32, win.y0 as i32) {
                    if front.is_none_or(|(f, fq)| self.beats(i, q, f, fq)) {
                        front = Some((i, q));
                    }
                }
            }
        }
        let list = if full {
            self.stats.unfiltered += 1;
            win.list
        } else {
            self.stats.peak_list = self.stats.peak_list.max((top + kept) as u32);
            List {
                start: top as u32,
                len: kept as u32,
            }
        };
        match relevant {
            0 => return None,
            1 => {
                self.stats.single += 1;
                self.paint_coverage(only, win);
                return None;
            }
            _ => {}
        }
        if win.x1 - win.x0 == 1 && win.y1 - win.y0 == 1 {
            self.stats.pixels += 1;
            self.resolve_pixel(&list, win.x0 as i32, win.y0 as i32);
            return None;
        }
        if let Some((c, _)) = front {
            if self.in_front_of_all(c, &list, win) {
                self.stats.filled += 1;
                self.paint_coverage(c, win);
                return None;
            }
        }
        Some(list)
    }

    /// Depth plane and paint payload of piece `i`.
    fn surface(&self, i: usize) -> Option<Surface<S::Payload<P>>> {
        let t = self.store.get(i)?;
        let v: [ScreenVertex<SUB>; 3] = t.screen();
        let solver = PlaneSolver::new(&v)?;
        Some(Surface {
            plane: DepthPlane::new(&solver, &v),
            payload: S::payload::<P, SUB>(t.face(), t.id, &solver, &v),
        })
    }

    /// The wrapped stepped depth of piece `i` at pixel `(x, y)`, if it covers that centre.
    fn depth_at(&self, i: usize, x: i32, y: i32) -> Option<i32> {
        let t = self.store.get(i)?;
        let walk = TriangleWalk::new::<SUB>(xy(t), y, y + 1)?;
        let (l, r) = walk.span();
        if walk.row() != y || x < l || x >= r {
            return None;
        }
        let v: [ScreenVertex<SUB>; 3] = t.screen();
        let plane = DepthPlane::new(&PlaneSolver::new(&v)?, &v);
        Some(stepped(&plane, l, y, x) as i32)
    }

    /// The span z-buffer's activation order of piece `i`: its triangle's first row (the first
    /// row of any of its pieces), then the piece's position in the store (id order).
    fn order(&self, i: usize) -> (i32, usize) {
        let Some(id) = self.store.get(i).map(|t| t.id) else {
            debug_assert!(false, "internal error: no kept piece {i}");
            return (i32::MAX, i);
        };
        let (w, h) = (self.vp.width as i32, self.vp.height as i32);
        // A clipped triangle's pieces are kept next to each other.
        let first = (0..i)
            .rev()
            .map_while(|j| self.store.get(j).filter(|t| t.id == id))
            .chain(
                self.store
                    .get(i..)
                    .into_iter()
                    .flatten()
                    .take_while(|t| t.id == id),
            )
            .filter_map(|t| crate::raster::first_row(&t.screen::<SUB>(), w, h))
            .min()
            .unwrap_or(i32::MAX);
        (first, i)
    }

    /// Whether piece `a` at depth `qa` keeps a pixel against piece `b` at depth `qb`.
    fn beats(&self, a: usize, qa: i32, b: usize, qb: i32) -> bool {
        qa > qb || (qa == qb && self.order(a) < self.order(b))
    }

    /// Whether surrounding piece `c` keeps every pixel of `win` that any other piece of `list`
    /// covers. Both depths are linear along a row, so the two ends of each overlap decide.
    fn in_front_of_all(&self, c: usize, list: &List, win: &Window) -> bool {
        // Kept pieces have screen area, so each has a surface.
        let (Some(ct), Some(cs)) = (self.store.get(c), self.surface(c)) else {
            debug_assert!(false, "internal error: no surface for kept piece {c}");
            return false;
        };
        let (x0, x1, y1) = (win.x0 as i32, win.x1 as i32, win.y1 as i32);
        for k in 0..list.len {
            let Some(i) = self.entry(list, k) else {
                debug_assert!(false, "internal error: list entry {k} out of the buffer");
                return false;
            };
            let Some(t) = self.store.get(i) else {
                debug_assert!(false, "internal error: no kept piece {i}");
                continue;
            };
            if i == c {
                continue;
            }
            let Some(mut walk) = TriangleWalk::new::<SUB>(xy(t), win.y0 as i32, y1) else {
                continue;
            };
            let Some(mut cw) = TriangleWalk::new::<SUB>(xy(ct), walk.row(), y1) else {
                return false;
            };
            let Some(ts) = self.surface(i) else {
                debug_assert!(false, "internal error: no surface for kept piece {i}");
                continue;
            };
            loop {
                let y = walk.row();
                let (l, r) = walk.span();
                let (a, b) = (l.max(x0), r.min(x1));
                if a < b {
                    let (cl, _) = cw.span();
                    for x in [a, b - 1] {
                        let (qc, qt) = (stepped(&cs.plane, cl, y, x), stepped(&ts.plane, l, y, x));
                        if !fits(qc) || !fits(qt) || !self.beats(c, qc as i32, i, qt as i32) {
                            return false;
                        }
                    }
                }
                if !walk.advance::<SUB>() {
                    break;
                }
                if !cw.advance::<SUB>() || cw.row() != walk.row() {
                    return false;
                }
            }
        }
        true
    }

    /// Paints piece `i`'s exact coverage of window `win` (where its depth is above 0).
    fn paint_coverage(&mut self, i: usize, win: &Window) {
        let (Some(t), Some(s)) = (self.store.get(i), self.surface(i)) else {
            debug_assert!(false, "internal error: no surface for kept piece {i}");
            return;
        };
        // The piece meets the window, which `classify` found with this very walk.
        let Some(mut walk) = TriangleWalk::new::<SUB>(xy(t), win.y0 as i32, win.y1 as i32) else {
            debug_assert!(
                false,
                "internal error: piece {i} misses the window it meets"
            );
            return;
        };
        loop {
            let (l, r) = walk.span();
            let (a, b) = (l.max(win.x0 as i32), r.min(win.x1 as i32));
            if a < b {
                self.paint_run(&s, walk.row(), l, a, b);
            }
            if !walk.advance::<SUB>() {
                break;
            }
        }
    }

    /// Paints columns `[a, b)` of row `y` with surface `s`, whose span on that row starts at
    /// column `l`, except where its stepped depth is 0 or below (the background wins there).
    fn paint_run(&mut self, s: &Surface<S::Payload<P>>, y: i32, l: i32, a: i32, b: i32) {
        let (qa, qb) = (stepped(&s.plane, l, y, a), stepped(&s.plane, l, y, b - 1));
        if qa > 0 && qb > 0 && fits(qa) && fits(qb) {
            self.paint(s, y, a, b);
            return;
        }
        // Rare (depth at or below 0, or wrapping): pixel by pixel, as the z-buffer does.
        let mut x = a;
        while x < b {
            let shown = |x: i32| stepped(&s.plane, l, y, x) as i32 > 0;
            if !shown(x) {
                x += 1;
                continue;
            }
            let start = x;
            while x < b && shown(x) {
                x += 1;
            }
            self.paint(s, y, start, x);
        }
    }

    /// Writes columns `[a, b)` of row `y` (on screen, non-empty).
    fn paint(&mut self, s: &Surface<S::Payload<P>>, y: i32, a: i32, b: i32) {
        let at = y as usize * self.stride;
        if let Some(out) = self.frame.get_mut(at + a as usize..at + b as usize) {
            S::paint(&s.payload, a, y, out);
            self.written += (b - a) as u32;
        } else {
            debug_assert!(
                false,
                "internal error: run {a}..{b} of row {y} out of the frame"
            );
        }
    }

    /// Paints pixel `(x, y)` with the nearest piece of `list` covering its centre.
    fn resolve_pixel(&mut self, list: &List, x: i32, y: i32) {
        let mut best: Option<(usize, i32)> = None;
        for k in 0..list.len {
            let Some(i) = self.entry(list, k) else {
                debug_assert!(false, "internal error: list entry {k} out of the buffer");
                break;
            };
            // A depth of 0 or below never beats the background (a cleared z-buffer).
            let Some(q) = self.depth_at(i, x, y).filter(|&q| q > 0) else {
                continue;
            };
            if best.is_none_or(|(b, bq)| self.beats(i, q, b, bq)) {
                best = Some((i, q));
            }
        }
        if let Some((i, _)) = best {
            match self.surface(i) {
                Some(s) => self.paint(&s, y, x, x + 1),
                None => debug_assert!(false, "internal error: no surface for kept piece {i}"),
            }
        }
    }
}

/// Sub-pixel `(x, y)` of a kept piece's vertices.
#[inline]
fn xy(t: &StoredTriangle) -> [(i32, i32); 3] {
    let ([x0, x1, x2], [y0, y1, y2]) = (t.x, t.y);
    [(x0, y0), (x1, y1), (x2, y2)]
}

/// How piece `t` meets window `win`, by the exact coverage of the window's centres.
fn classify<const SUB: u32>(t: &StoredTriangle, win: &Window) -> Class {
    let (x0, x1) = (win.x0 as i32, win.x1 as i32);
    // Bounding box first (most pieces of a window miss most of its quarters): the columns
    // the walk can cover lie in [first(min x), first(max x)), the rows likewise.
    let outside = |v: &[i32; 3], from: u16, to: u16| {
        let (lo, hi) = v
            .iter()
            .fold((i32::MAX, i32::MIN), |(l, h), &x| (l.min(x), h.max(x)));
        centre_at_or_after::<SUB>(hi) <= from as i64 || centre_at_or_after::<SUB>(lo) >= to as i64
    };
    if outside(&t.x, win.x0, win.x1) || outside(&t.y, win.y0, win.y1) {
        return Class::Disjoint;
    }
    let Some(mut walk) = TriangleWalk::new::<SUB>(xy(t), win.y0 as i32, win.y1 as i32) else {
        return Class::Disjoint;
    };
    let mut rows = 0;
    let mut all = walk.row() == win.y0 as i32;
    let mut any = false;
    loop {
        let (l, r) = walk.span();
        any |= l.max(x0) < r.min(x1);
        all &= l <= x0 && r >= x1;
        if any && !all {
            return Class::Partial;
        }
        rows += 1;
        if !walk.advance::<SUB>() {
            break;
        }
    }
    if all && rows == (win.y1 - win.y0) as i32 {
        Class::Surrounds
    } else if any {
        Class::Partial
    } else {
        Class::Disjoint
    }
}
