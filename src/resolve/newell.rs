//! The Newell–Newell–Sancha depth sort on the shared pipeline.
//!
//! # The algorithm
//!
//! Every visible screen piece of the frame is kept (the [`store`] module: transform, clipping,
//! projection and culling are the shared ones). The work is done in screen space: `x`, `y` in
//! sixteenths of a sub-pixel (the sort's grid, 4 bits below the sub-pixel grid; the snapped
//! vertices lie on it exactly) and `q = near/w` in I2F30 bits. Projection there is
//! orthographic along `q` and the eye is at `q = +∞` (larger `q` is nearer), and a
//! triangle's plane stays a plane, so every plane test below is exact integer arithmetic
//! (`i128`) on the snapped vertices.
//!
//! The pieces are sorted by their farthest depth (smallest `q`), far first. Then the head of
//! the list, `P`, is compared with every other piece `Q` whose depth range reaches `P`'s
//! (`Q`'s smallest `q` at most `P`'s largest). `P` may be drawn before `Q` when
//!
//! 1. their `x` extents are disjoint, or
//! 2. their `y` extents are disjoint, or
//! 3. `P` lies entirely behind `Q`'s plane (on the side away from the eye), or
//! 4. `Q` lies entirely in front of `P`'s plane, or
//! 5. their projections do not overlap (an edge line of one has the other entirely on its
//!    outside: exact edge functions of the snapped triangles).
//!
//! Extents and projections that only touch count as disjoint: with the top-left fill rule two
//! triangles whose interiors are disjoint never cover the same pixel centre. If every `Q`
//! passes, `P` is final and the next piece becomes the head. If `Q` fails but the reversed
//! tests 3 and 4 say `Q` may be drawn before `P`, `Q` is moved to the head of the list and
//! marked. A marked piece that would be moved again closes a cycle: it is split by `P`'s
//! plane (or `P` by its plane, whichever straddles the other), as is `Q` when neither order
//! can be shown (interpenetration). The pieces of a split replace it in the list and the
//! search goes on. Pieces of one original never overlap (its split tree, below, gives each
//! pixel centre to one of them) and are not compared.
//!
//! A piece's plane, in tests 3 and 4 and for splitting, is the plane of the original it is a
//! part of, not the plane through its own rounded vertices: a frame then has only its
//! originals' planes, and a part is never cut again by a plane a rounding away from the one
//! that made it (on random soups such planes made pieces of slivers until the sort ran out
//! of steps).
//!
//! # Splitting and tolerances
//!
//! A piece is cut where its edges cross the other's plane. The new vertices are rounded to
//! the sort's grid (and `q` to an I2F30 step) and shared by the pieces on both sides.
//! Rounded vertices are no longer exactly on the cutting plane, so tests 3 and 4 count
//! a vertex as on a plane when the plane passes through its rounding cell (`±½` in `x`, `y`
//! and `q`): `2·|n·(v − a)| ≤ |n_x| + |n_y| + |n_q|`. The pieces of a split then always pass
//! against the plane that cut them, so no cut is repeated. The price is that a piece may stick
//! out of another's plane by less than that cell and still be drawn behind it: the pixels
//! affected lie within about a thirty-second of a sub-pixel of where the two planes meet,
//! where the depth gap is below the renderer's error bound.
//!
//! A thin piece may be straddled by a plane and still have no part of any area once the cut
//! points are rounded. Its region of the original can hold pixel centres all the same (a
//! sliver along a column of them), so it is not dropped: it is kept whole and *pressed*, the
//! depths of its vertices on the other side of the plane than its centroid moved onto the
//! plane, and ordered as if it lay on its centroid's side ([`SortStats::pressed`]).
//!
//! Likewise a cut whose two cut points round onto one line can leave one side of the plane
//! without a part of any area while that side's exact region holds pixel centres (a sliver one
//! grid unit wide, cut across). Its pixels would go to a part on the other side, ordered
//! there. Then the cut points are rounded apart instead, each to a corner of its grid
//! cell: the nearest pair that keeps them on the plane within the tolerance (their depths are
//! the piece's plane there), keeps every part's orientation and puts those centres in the
//! side's part ([`SortStats::rounded_apart`]). A side whose region holds no centre is still
//! left out ([`SortStats::dropped_slivers`]): a part there would only cost splits.
//!
//! The rounded parts are only used to find the order. What is painted is the original
//! piece, cut by a *split tree*: each split records the screen lines between its parts (the
//! line where the cutting plane crosses the original's plane, through its crossings of the
//! original's edges to 2^−8 sub-pixel, and the diagonal of a four-sided part), and every
//! pixel centre of the original goes to exactly one side of each line. So the parts tile the
//! original exactly, whatever the rounding: no crack where a rounded cut point falls inside
//! an outer edge, no T-junction where a later cut meets an earlier one, and the original's
//! coverage is the span z-buffer's. The cut is not the line through the rounded cut points:
//! across a thin piece those lie a few sub-pixels apart, and the line through them can turn
//! far enough to send pixel centres a pixel away to the wrong side of the plane.
//!
//! # Ties
//!
//! When both orders pass tests 3 or 4 (coplanar pieces, or pieces within the rounding cell of
//! each other's planes) and the projections overlap, the span z-buffer's tie rule decides: the
//! piece whose triangle is activated first (lower first row, then lower id) keeps the pixel,
//! so it is drawn last. A piece already moved once is not moved again for a tie (either order
//! is right up to the rounding cell, and a second move would only close a cycle that no split
//! can break).
//!
//! # Termination
//!
//! Each step of the search outputs the head, moves one piece to the head, or splits one.
//! An unmarked piece is moved at most once, splits are bounded by `PIECES` (each needs a free
//! store entry, and running out is a [`RenderError::Capacity`] error with
//! [`CapacityKind::Pieces`]), and a marked piece that neither splitting plane cuts (a cycle
//! closed by other pieces) is moved again at most `PIECES` times in a frame. When, at one head
//! position, more pieces are moved again than were moved there in all (every piece of the
//! cycle went round once more and no plane of the pair cut the other beyond the rounding
//! cell), the cycle is one of pieces of interpenetrating triangles meeting within that cell:
//! the head is drawn and the search goes on ([`SortStats::cycles_within_rounding`]) instead of
//! re-testing the same cycle until the step limit. On top of that
//! the search takes at most [`step_limit`]`(PIECES)` steps (each scans part of the list),
//! after which the frame fails with [`CapacityKind::SortSteps`] instead of looping. Nothing
//! reaches the sink before the order is complete.
//!
//! # Painting
//!
//! The original pieces go to the shared row walker, each with its split tree as key. On each
//! row the painter divides an original's span at the tree's lines (exact integer arithmetic
//! at the pixel centres) and gives each run the position of its part in the final order.
//! A pixel takes the colour of the latest part in the order that covers it, which is what
//! painting the parts far to near gives, kept as one position per pixel of the row; rows
//! reach the sink one at a time and [`Row::depth`](crate::sink::Row::depth) is empty. A part
//! whose pixels a later part already holds is not written, so `pixels_written` is at most
//! `fragments`. Colours are the original's (its vertex colours rounded to 8 bits a channel).
//!
//! # Memory
//!
//! A [`NewellWorkspace`] holds, in bytes:
//!
//! * `PIECES · 91`: the kept pieces ([`StoredTriangle`], 52), the list (2), a key per piece
//!   (4: its activation rank while sorting, then its position), a mark (1), a bucket link (2),
//!   a split-tree link (4), the piece's original (2) and a split-tree cut (24: two points and
//!   two links);
//! * `2·H` bucket heads, `size_of::<P>()·W + 4·W` for one row of pixels and their positions,
//!   and `ACTIVE` active triangles (about 112 bytes each for flat shading, with the sort key).
//!
//! [`NewellWorkspace::BYTES`] gives the total.

use crate::arithmetic::Arithmetic;
use crate::clip::Clipping;
use crate::depth::DepthRow;
use crate::math::checked_div_euclid_i128;
use crate::options::{RenderOptions, MAX_INSTANCES};
use crate::render::{
    internal, viewport, walk_rows, ActiveTri, Buckets, FinishedRow, Resolve, NO_ENTRY,
};
use crate::resolve::common::{check_sizes, render_whole_target, sort_by_key};
use crate::resolve::store::{self, StoredPieces, StoredTriangle};
use crate::scene::Scene;
use crate::shading::Shading;
use crate::sink::{RowPixel, RowSink};
use crate::stats::{CapacityKind, FrameStats, RenderError};
use core::cmp::Reverse;
use embedded_graphics::pixelcolor::{Rgb888, RgbColor};
use heapless::Vec;

/// Most search steps a frame may take with room for `pieces` pieces: `8 · pieces + 64`. Each
/// step outputs, moves or splits one piece (see the [module docs](self)).
///
/// ```
/// assert_eq!(scanline3d::resolve::newell::step_limit(1024), 8256);
/// ```
pub const fn step_limit(pieces: usize) -> usize {
    8 * pieces + 64
}

/// What one frame's sort did (see [`NewellWorkspace::sort_stats`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SortStats {
    /// Pieces kept from the pipeline (on screen).
    pub pieces_in: u32,
    /// Pieces painted (after splitting).
    pub pieces_out: u32,
    /// Workspace entries the frame used: the kept pieces and every part made by splitting
    /// (an original that is split keeps its entry). `PIECES` must be at least this.
    pub entries: u32,
    /// Pairs compared.
    pub comparisons: u32,
    /// Pieces moved to the head of the list.
    pub moves: u32,
    /// Marked pieces moved again because neither plane of the pair cuts the other.
    pub re_moves: u32,
    /// Pieces split (cyclic overlap or interpenetration).
    pub splits: u32,
    /// Parts of a split that have no screen area once their new vertices are rounded, left
    /// out: their region of the original (which may still hold pixel centres) goes to a
    /// neighbouring part of the same split, and takes that part's place in the order.
    pub dropped_slivers: u32,
    /// Search steps taken.
    pub steps: u32,
    /// Pieces that a plane straddles but whose parts would all have no screen area once
    /// rounded: kept whole, with the depths of the vertices on the minority side moved onto
    /// the plane (the order is then decided as if the piece lay on its centroid's side).
    pub pressed: u32,
    /// Cycles that no plane of their pieces cuts beyond the rounding cell (pieces of
    /// interpenetrating triangles meeting within it), broken by drawing the head first.
    pub cycles_within_rounding: u32,
    /// Cuts whose cut points were rounded apart (to other corners of their cells of the sort's
    /// grid) because, rounded to the nearest, they left one side of the plane without a part
    /// of any area while its region of the piece holds pixel centres.
    pub rounded_apart: u32,
}

/// Depth sort after Newell, Newell and Sancha: pieces are ordered far to near, overlapping
/// depth ranges are resolved with exact plane and projection tests, and cyclic overlap or
/// interpenetration is resolved by splitting. Then the pieces are painted far to near, row by
/// row. Unlike [`DepthSortWorkspace`](crate::resolve::DepthSortWorkspace), the order is right
/// wherever two pieces overlap (see the [module docs](self) for the tests, the splitting, the
/// work bound and the memory).
///
/// * `PIECES`: screen pieces per frame, including those made by splitting (≤ 65535; an
///   original that is split keeps its entry, its parts take new ones);
/// * `ACTIVE`: pieces that may cross one row (more are dropped and reported, as for the
///   other row walkers).
///
/// ```
/// use embedded_graphics::pixelcolor::Rgb565;
/// use scanline3d_demo as demo;
/// use scanline3d::{resolve::NewellWorkspace, sink::HashSink, Flat, RenderOptions};
/// let mut ws: Box<NewellWorkspace<Rgb565, Flat, 240, 240, 1280, 96>> =
///     Box::new(NewellWorkspace::new(Rgb565::new(0, 0, 0)));
/// let instances = demo::instances();
/// let scene = demo::scene(&instances, 0, demo::ORBIT_FRAMES)?;
/// let stats = ws.render(&scene, &RenderOptions::default(), &mut HashSink::new()).unwrap();
/// assert!(stats.is_complete());
/// // A part is not written where a part later in the order already is.
/// assert!(stats.pixels_written <= stats.fragments);
/// assert!(ws.sort_stats().pieces_out >= ws.sort_stats().pieces_in);
/// # Ok::<(), scanline3d::scene::SceneError>(())
/// ```
pub struct NewellWorkspace<
    P: RowPixel,
    S: Shading,
    const W: usize,
    const H: usize,
    const PIECES: usize = 1024,
    const ACTIVE: usize = 64,
    const INSTANCES: usize = MAX_INSTANCES,
> {
    store: [StoredTriangle; PIECES],
    list: [u16; PIECES],
    keys: [u32; PIECES],
    marked: [bool; PIECES],
    next: [u16; PIECES],
    tree: [u32; PIECES],
    origin: [u16; PIECES],
    nodes: [Cut; PIECES],
    heads: [u16; H],
    pixels: [P; W],
    order: [u32; W],
    background: P,
    active: Vec<ActiveTri<S::Payload<P>, u32>, ACTIVE>,
    last: SortStats,
}

impl<
        P: RowPixel,
        S: Shading,
        const W: usize,
        const H: usize,
        const PIECES: usize,
        const ACTIVE: usize,
        const INSTANCES: usize,
    > NewellWorkspace<P, S, W, H, PIECES, ACTIVE, INSTANCES>
{
    /// Size of this workspace in bytes.
    pub const BYTES: usize = core::mem::size_of::<Self>();

    const VALID: () = {
        check_sizes(W, H, 0);
        // Pieces are named by `u16` indices in the list and the buckets, below NO_ENTRY.
        assert!(
            PIECES <= crate::scene::MAX_SCENE_TRIANGLES,
            "PIECES must be at most 65535"
        );
    };

    /// An empty workspace whose background pixels are `background`.
    pub const fn new(background: P) -> Self {
        #[allow(clippy::let_unit_value)]
        let () = Self::VALID;
        NewellWorkspace {
            store: [StoredTriangle::EMPTY; PIECES],
            list: [0; PIECES],
            keys: [0; PIECES],
            marked: [false; PIECES],
            next: [NO_ENTRY; PIECES],
            tree: [0; PIECES],
            origin: [0; PIECES],
            nodes: [Cut::EMPTY; PIECES],
            heads: [NO_ENTRY; H],
            pixels: [background; W],
            order: [0; W],
            background,
            active: Vec::new(),
            last: SortStats {
                pieces_in: 0,
                pieces_out: 0,
                entries: 0,
                comparisons: 0,
                moves: 0,
                re_moves: 0,
                splits: 0,
                dropped_slivers: 0,
                steps: 0,
                pressed: 0,
                cycles_within_rounding: 0,
                rounded_apart: 0,
            },
        }
    }

    /// What the last frame's sort did.
    pub fn sort_stats(&self) -> SortStats {
        self.last
    }

    render_whole_target!();

    /// Renders a `width × height` target (at most `W × H`); see
    /// [`Workspace::render_sized`](crate::Workspace::render_sized). More pieces than `PIECES`
    /// (before or after splitting) or more than [`step_limit`]`(PIECES)` search steps is a
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
        let (Some(pixels), Some(order), Some(heads)) = (
            self.pixels.get_mut(..width),
            self.order.get_mut(..width),
            self.heads.get_mut(..height),
        ) else {
            return Err(RenderError::InvalidTarget);
        };
        let (n, mut stats) = store::collect::<S, SUB_BITS, C, A, K::Error, INSTANCES>(
            scene,
            options,
            &vp,
            &mut self.store,
        )?;
        let collected = n;
        // Each original is a whole tree of one piece until it is split.
        for (i, (t, o)) in self
            .tree
            .iter_mut()
            .zip(&mut self.origin)
            .take(n)
            .enumerate()
        {
            *t = LEAF | i as u32;
            *o = i as u16;
        }
        let mut sort = Sort {
            store: &mut self.store,
            keys: &mut self.keys,
            marked: &mut self.marked,
            list: &mut self.list,
            tree: &mut self.tree,
            origin: &mut self.origin,
            nodes: &mut self.nodes,
            originals: n,
            n,
            grid: Grid {
                sub: SUB_BITS + SORT,
                width: vp.width as i64,
                height: vp.height as i64,
            },
            len: 0,
            cuts: 0,
            stats: SortStats::default(),
        };
        sort.ranks::<SUB_BITS>(vp.width as i32, vp.height as i32);
        // The sort works on a grid `SORT` bits finer than the sub-pixel one (the originals'
        // vertices shifted, exactly), the painter on the originals as they were.
        let to_sort = |t: &mut StoredTriangle| {
            t.x = t.x.map(|x| x << SORT);
            t.y = t.y.map(|y| y << SORT);
        };
        sort.store.iter_mut().take(collected).for_each(to_sort);
        let result = sort.run();
        let from_sort = |t: &mut StoredTriangle| {
            t.x = t.x.map(|x| x >> SORT);
            t.y = t.y.map(|y| y >> SORT);
        };
        sort.store.iter_mut().take(collected).for_each(from_sort);
        let (n, len, cuts) = (sort.n, sort.len, sort.cuts);
        sort.stats.pieces_out = len as u32;
        sort.stats.entries = n as u32;
        self.last = sort.stats;
        result?;

        // Key = position in the final order, from 1 (0: nothing painted yet). (List entries
        // index the store's first `n` pieces, `n <= PIECES`.)
        self.keys.fill(0);
        for (k, &i) in self.list.iter().take(len).enumerate() {
            if let Some(key) = self.keys.get_mut(i as usize) {
                *key = k as u32 + 1;
            } else {
                debug_assert!(false, "internal error: list entry {i} out of the store");
            }
        }
        // The original pieces are walked, with their split trees as keys: the painter finds
        // each pixel's piece in the tree, so split pieces tile their original exactly.
        let originals = internal(self.store.get(..collected), &[]);
        store::bucket(originals, &vp, heads, &mut self.next);
        let pieces = StoredPieces {
            store: originals,
            keys: internal(self.tree.get(..originals.len()), &[]),
        };
        let mut painter = OrderPainter::<P, SUB_BITS> {
            pixels,
            order,
            background: self.background,
            cuts: internal(self.nodes.get(..cuts), &[]),
            positions: internal(self.keys.get(..n), &[]),
            spans: 0,
        };
        let height = heads.len();
        let mut rows = Buckets {
            heads,
            next: &self.next,
            pieces: &pieces,
        };
        walk_rows::<P, S, SUB_BITS, K, _, _>(
            height,
            self.active.as_mut_view(),
            &mut rows,
            &mut painter,
            width as i32,
            sink,
            &mut stats,
        )?;
        Ok(stats)
    }
}

/// A piece's plane in `(x, y, q)`: `s(v) = n·v − d`, oriented so that `n_q > 0` (positive
/// `s` is in front, towards the eye). `tol` is `|n_x| + |n_y| + n_q`: a vertex is on the plane
/// when `2·|s(v)| ≤ tol`, i.e. the plane passes through its rounding cell.
///
/// Bit budget: coordinates are below 2^26 units of the sort's grid ([`SORT`]) and `q` below
/// 2^31, so edge differences are below 2^27 and 2^32, `n` below 2^60 and `s` below 2^89:
/// `i128` holds all of it, and the split interpolation's products (below 2^124).
#[derive(Clone, Copy, Debug)]
struct PlaneEq {
    n: [i128; 3],
    d: i128,
    tol: i128,
}

impl PlaneEq {
    fn of(t: &StoredTriangle) -> Option<PlaneEq> {
        let v = |k: usize| [t.x[k] as i128, t.y[k] as i128, t.q[k] as i128];
        let (a, b, c) = (v(0), v(1), v(2));
        let e1 = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let e2 = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
        let mut n = [
            e1[1] * e2[2] - e1[2] * e2[1],
            e1[2] * e2[0] - e1[0] * e2[2],
            e1[0] * e2[1] - e1[1] * e2[0],
        ];
        if n[2] == 0 {
            return None; // zero screen area
        }
        if n[2] < 0 {
            n = n.map(|c| -c);
        }
        Some(PlaneEq {
            n,
            d: n[0] * a[0] + n[1] * a[1] + n[2] * a[2],
            tol: n[0].abs() + n[1].abs() + n[2],
        })
    }

    /// `s` at vertex `k` (0, 1 or 2) of `t`.
    fn at(&self, t: &StoredTriangle, k: usize) -> i128 {
        let (Some(&x), Some(&y), Some(&q)) = (t.x.get(k), t.y.get(k), t.q.get(k)) else {
            debug_assert!(false, "internal error: no vertex {k}");
            return 0;
        };
        self.at_point(x, y, q)
    }

    /// `s` at the point `(x, y, q)`.
    fn at_point(&self, x: i32, y: i32, q: i32) -> i128 {
        self.n[0] * x as i128 + self.n[1] * y as i128 + self.n[2] * q as i128 - self.d
    }

    /// The `q` of the plane at `(x, y)`, to the nearest I2F30 step.
    fn q_at(&self, x: i32, y: i32) -> i32 {
        let num = self.d - self.n[0] * x as i128 - self.n[1] * y as i128;
        div_round(num, self.n[2]).clamp(i32::MIN as i128, i32::MAX as i128) as i32
    }

    /// Whether all of `t` is behind this plane or on it.
    fn all_behind(&self, t: &StoredTriangle) -> bool {
        (0..3).all(|k| 2 * self.at(t, k) <= self.tol)
    }

    /// Whether all of `t` is in front of this plane or on it.
    fn all_in_front(&self, t: &StoredTriangle) -> bool {
        (0..3).all(|k| 2 * self.at(t, k) >= -self.tol)
    }

    /// Whether `t` has vertices beyond the tolerance on both sides.
    fn straddled_by(&self, t: &StoredTriangle) -> bool {
        !self.all_behind(t) && !self.all_in_front(t)
    }
}

fn min_q(t: &StoredTriangle) -> i32 {
    t.q[0].min(t.q[1]).min(t.q[2])
}

fn max_q(t: &StoredTriangle) -> i32 {
    t.q[0].max(t.q[1]).max(t.q[2])
}

/// Whether the extents `a` and `b` are disjoint or only touch.
fn disjoint(a: &[i32; 3], b: &[i32; 3]) -> bool {
    let (a0, a1) = (a[0].min(a[1]).min(a[2]), a[0].max(a[1]).max(a[2]));
    let (b0, b1) = (b[0].min(b[1]).min(b[2]), b[0].max(b[1]).max(b[2]));
    a1 <= b0 || b1 <= a0
}

/// `run.rotate_right(1)` without its assertion (`1 <= len`), which stays where the call is
/// not inlined (`opt-level = "z"`): the last entry first, the others one place on.
fn rotate_right_by_one(run: &mut [u16]) {
    if let Some(&last) = run.last() {
        let mut carry = last;
        for entry in run.iter_mut() {
            core::mem::swap(entry, &mut carry);
        }
    }
}

/// Whether an edge line of `a` has all of `b` on its outside (or on it).
fn separates(a: &StoredTriangle, b: &StoredTriangle) -> bool {
    let ([x0, x1, x2], [y0, y1, y2]) = (a.x, a.y);
    let (p0, p1, p2) = ((x0, y0), (x1, y1), (x2, y2));
    // Each edge (i, j) with the opposite vertex o.
    [(p0, p1, p2), (p1, p2, p0), (p2, p0, p1)]
        .into_iter()
        .any(|((xi, yi), (xj, yj), (xo, yo))| {
            let (ex, ey) = (xj as i64 - xi as i64, yj as i64 - yi as i64);
            let f = |x: i32, y: i32| ex * (y as i64 - yi as i64) - ey * (x as i64 - xi as i64);
            let inside = f(xo, yo).signum();
            inside != 0 && b.x.iter().zip(&b.y).all(|(&x, &y)| f(x, y) * inside <= 0)
        })
}

/// Whether the projections of `a` and `b` may share a pixel centre (exact: a separating line
/// of two triangles can always be taken through an edge of one of them).
fn projections_overlap(a: &StoredTriangle, b: &StoredTriangle) -> bool {
    !separates(a, b) && !separates(b, a)
}

/// How two pieces must be ordered.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Order {
    /// The head may be drawn before the other.
    HeadFirst,
    /// The other must be drawn before the head.
    OtherFirst,
    /// Neither order can be shown: split.
    Split,
}

/// Rounds `num / den` (with `den > 0`) to the nearest integer, halves up.
fn div_round(num: i128, den: i128) -> i128 {
    // Callers divide by the gap between two plane distances of opposite sign, never 0 and far
    // below 2^126; 0 is the release fallback for that internal error (no panic path).
    match checked_div_euclid_i128(2 * num + den, 2 * den) {
        Some(q) => q,
        None => {
            debug_assert!(false, "internal error: {num} / {den}");
            0
        }
    }
}

/// The search over one frame's pieces.
struct Sort<'a> {
    store: &'a mut [StoredTriangle],
    /// Per piece: its activation rank while sorting (first row of its triangle << 16 | its
    /// index in id order), its position in the order afterwards.
    keys: &'a mut [u32],
    marked: &'a mut [bool],
    list: &'a mut [u16],
    /// Per original piece (the first `originals`): its split tree ([`LEAF`]` | piece`, a cut,
    /// or [`NOTHING`]). Per piece made by a split: where it hangs ([`ROOT`]` | original`, or
    /// `cut << 1 | side`, side 0 for the cut's `pos`).
    tree: &'a mut [u32],
    /// Per piece: the original it is a part of (an original: itself).
    origin: &'a mut [u16],
    /// The cuts made so far are `nodes[..cuts]`.
    nodes: &'a mut [Cut],
    cuts: usize,
    /// The pieces the pipeline kept: they stay in the store unchanged (they are what the
    /// painter walks), their parts go after them.
    originals: usize,
    /// Pieces in the store.
    n: usize,
    /// The screen, for the pixel centres of cut regions.
    grid: Grid,
    /// Pieces in the list.
    len: usize,
    stats: SortStats,
}

impl Sort<'_> {
    /// Computes every piece's rank (the span z-buffer's activation order) and lists the
    /// pieces that are on screen, far first.
    fn ranks<const SUB: u32>(&mut self, width: i32, height: i32) {
        let n = self.n;
        let mut start = 0;
        while start < n {
            let id = internal(self.store.get(start), &StoredTriangle::EMPTY).id;
            let end = (start..n)
                .find(|&i| self.store.get(i).is_none_or(|t| t.id != id))
                .unwrap_or(n);
            let row =
                |t: &StoredTriangle| crate::raster::first_row(&t.screen::<SUB>(), width, height);
            let first = self
                .store
                .get(start..end)
                .into_iter()
                .flatten()
                .filter_map(row)
                .min();
            for i in start..end {
                let on_screen = self.store.get(i).and_then(row).is_some();
                if let (Some(key), Some(first)) = (self.keys.get_mut(i), first) {
                    *key = (first as u32) << 16 | i as u32;
                }
                if on_screen {
                    if let (Some(slot), Some(mark)) =
                        (self.list.get_mut(self.len), self.marked.get_mut(i))
                    {
                        *slot = i as u16;
                        *mark = false;
                        self.len += 1;
                    } else {
                        // The list and the marks have room for every piece in the store.
                        debug_assert!(false, "internal error: piece {i} not listed");
                    }
                } else if let Some(t) = self.store.get_mut(i) {
                    // Not drawn: make sure no bucket picks it up.
                    *t = StoredTriangle::EMPTY;
                }
            }
            start = end;
        }
        self.stats.pieces_in = self.len as u32;
        let (store, keys) = (&*self.store, &*self.keys);
        if let Some(list) = self.list.get_mut(..self.len) {
            // (Keys are unique: the rank holds the piece's index.)
            sort_by_key(list, |&i| sort_key(store, keys, i));
        }
    }

    // Pieces are named by list entries, which index the store (and its keys and marks).

    fn piece(&self, i: u16) -> &StoredTriangle {
        internal(self.store.get(i as usize), &StoredTriangle::EMPTY)
    }

    fn rank(&self, i: u16) -> u32 {
        internal(self.keys.get(i as usize).copied(), u32::MAX)
    }

    fn is_marked(&self, i: u16) -> bool {
        internal(self.marked.get(i as usize).copied(), false)
    }

    /// The plane of the original `i` is a part of. The plane tests and the cuts use it, not
    /// the plane through a part's rounded vertices: then a frame has only its originals'
    /// planes, a part lies on its original's plane within the rounding cell, and the parts of
    /// a cut are never cut again by a plane a rounding away from the one that made them.
    fn plane(&self, i: u16) -> Option<PlaneEq> {
        let o = internal(self.origin.get(i as usize).copied(), i);
        PlaneEq::of(self.piece(o))
    }

    /// How head `p` and piece `q` (whose depth ranges overlap) must be ordered.
    fn order(&mut self, p: u16, q: u16) -> Order {
        self.stats.comparisons += 1;
        let (pt, qt) = (self.piece(p), self.piece(q));
        if disjoint(&pt.x, &qt.x) || disjoint(&pt.y, &qt.y) {
            return Order::HeadFirst;
        }
        if signed_area(pt) == 0 || signed_area(qt) == 0 {
            return Order::HeadFirst; // a piece of no area covers nothing
        }
        if self.origin.get(p as usize) == self.origin.get(q as usize) {
            // Parts of one original: its split tree gives every pixel centre to one of them.
            return Order::HeadFirst;
        }
        let (Some(pp), Some(qp)) = (self.plane(p), self.plane(q)) else {
            return Order::HeadFirst;
        };
        let head_first = qp.all_behind(pt) || pp.all_in_front(qt);
        let other_first = pp.all_behind(qt) || qp.all_in_front(pt);
        if head_first && !other_first {
            return Order::HeadFirst;
        }
        if !projections_overlap(pt, qt) {
            return Order::HeadFirst;
        }
        match (head_first, other_first) {
            // (Nearly) coplanar: the piece activated first keeps the pixel, so is drawn last.
            // Either order is right up to the rounding cell, so a piece already moved is not
            // moved again for a tie: that would only close a cycle.
            (true, true) if self.rank(p) > self.rank(q) || self.is_marked(q) => Order::HeadFirst,
            (_, true) => Order::OtherFirst,
            _ => Order::Split,
        }
    }

    /// Moves list entry `j` to the head (entry `done`), marking it.
    fn move_to_head(&mut self, done: usize, j: usize, front: &mut usize) {
        // `done <= j < len`, and list entries index the marks.
        // (Rotating only a non-empty run: no panic path.)
        if let Some(run @ [_, ..]) = self.list.get_mut(done..=j) {
            rotate_right_by_one(run);
        } else {
            debug_assert!(
                false,
                "internal error: list run {done}..={j} out of the list"
            );
        }
        match self
            .list
            .get(done)
            .and_then(|&q| self.marked.get_mut(q as usize))
        {
            Some(m) => *m = true,
            None => debug_assert!(false, "internal error: head {done} has no mark"),
        }
        if j >= *front {
            *front += 1;
        }
    }

    /// Runs the search: on success `list[..len]` is the drawing order, far first.
    fn run<E>(&mut self) -> Result<(), RenderError<E>> {
        let limit = step_limit(self.store.len());
        let (mut done, mut front) = (0usize, 0usize);
        // Re-moves since the head position `done` was last reached: (position, count).
        let mut re_moved_at = (usize::MAX, 0usize);
        // `list[done..front]` holds moved pieces in no particular order; `list[front..len]`
        // is sorted far first, so its scan stops at the first piece wholly nearer than P.
        while done < self.len {
            self.stats.steps += 1;
            if self.stats.steps as usize > limit {
                return Err(RenderError::Capacity {
                    what: CapacityKind::SortSteps,
                    needed: limit + 1,
                    capacity: limit,
                });
            }
            let Some(&p) = self.list.get(done) else {
                debug_assert!(false, "internal error: head {done} out of the list");
                break;
            };
            let p_max = max_q(self.piece(p));
            let mut found = None;
            for j in done + 1..self.len {
                let Some(&q) = self.list.get(j) else {
                    debug_assert!(false, "internal error: entry {j} out of the list");
                    break;
                };
                if min_q(self.piece(q)) > p_max {
                    if j >= front {
                        break;
                    }
                    continue;
                }
                match self.order(p, q) {
                    Order::HeadFirst => {}
                    order => {
                        found = Some((j, q, order));
                        break;
                    }
                }
            }
            match found {
                None => {
                    done += 1;
                    front = front.max(done);
                }
                Some((j, q, Order::OtherFirst)) if !self.is_marked(q) => {
                    self.stats.moves += 1;
                    self.move_to_head(done, j, &mut front);
                }
                Some((j, q, order)) => {
                    let (pt, qt) = (*self.piece(p), *self.piece(q));
                    let (pp, qp) = (self.plane(p), self.plane(q));
                    match (pp, qp) {
                        (Some(pp), _) if pp.straddled_by(&qt) => {
                            self.split(j, pp, &mut front)?;
                        }
                        (_, Some(qp)) if qp.straddled_by(&pt) => {
                            self.split(done, qp, &mut front)?;
                        }
                        _ if order == Order::OtherFirst
                            && re_moved_at.0 == done
                            && re_moved_at.1 > front.saturating_sub(done) =>
                        {
                            // Every piece of the cycle has been moved again and no plane of
                            // theirs cuts another beyond the rounding cell: the order among
                            // them is only decided within it. Draw the head now.
                            self.stats.cycles_within_rounding += 1;
                            done += 1;
                            front = front.max(done);
                        }
                        _ if order == Order::OtherFirst => {
                            // A cycle closed by other pieces: move it again (bounded).
                            self.stats.re_moves += 1;
                            re_moved_at = match re_moved_at {
                                (at, n) if at == done => (at, n + 1),
                                _ => (done, 1),
                            };
                            if self.stats.re_moves as usize > self.store.len() {
                                return Err(RenderError::Capacity {
                                    what: CapacityKind::SortSteps,
                                    needed: limit + 1,
                                    capacity: limit,
                                });
                            }
                            self.move_to_head(done, j, &mut front);
                        }
                        // (Not reached: `Split` means each straddles the other's plane.)
                        _ => {
                            done += 1;
                            front = front.max(done);
                        }
                    }
                }
            }
        }
        Ok(())
    }

    /// Splits list entry `at` by `plane`, files its parts in the sorted part of the list and
    /// puts the cut into the split tree in the piece's place.
    fn split<E>(
        &mut self,
        at: usize,
        plane: PlaneEq,
        front: &mut usize,
    ) -> Result<(), RenderError<E>> {
        let Some(&x) = self.list.get(at) else {
            debug_assert!(false, "internal error: entry {at} out of the list");
            return Ok(());
        };
        let t = *self.piece(x);
        let mut parts = cut(&t, &plane);
        if let Some(apart) = round_apart(&t, &plane, &parts, self.grid) {
            self.stats.rounded_apart += 1;
            parts = apart;
        }
        // The split tree cuts the original where the plane crosses the original's plane (the
        // piece's own crossing if the plane misses the original), not along the rounded cut
        // points (see `crossing_line`).
        let origin = internal(self.origin.get(x as usize).copied(), x);
        let ([a, b, _], on_plane) = rotated(&t, &plane);
        // Part 0 lies on the side of the lone vertex `a`, or of `b` when `a` is on the plane.
        let first = if on_plane { b } else { a };
        let side = plane.at(&t, first.k).signum();
        if let Some(line) = crossing_line(self.piece(origin), &plane, side)
            .or_else(|| crossing_line(&t, &plane, side))
        {
            parts.lines[0] = line;
        }
        if parts.parts.iter().all(Option::is_none) {
            // No part keeps any area on the grid, but the piece's region of the original may
            // still hold pixel centres (a sliver along a column of them): dropping it would
            // leave them unpainted. Keep it whole, pressed onto the side of the plane that
            // holds its centroid, so that it is ordered.
            self.stats.pressed += 1;
            parts = Parts {
                parts: [Some(press(&t, &plane)), None, None],
                made: 1,
                lines: parts.lines,
            };
        }
        let count = parts.parts.iter().flatten().count();
        // An original keeps its entry (the painter walks it); a part's entry goes to its
        // first part.
        let reuse = x as usize >= self.originals;
        let extra = count.saturating_sub(reuse as usize);
        let cuts = count.saturating_sub(1);
        if self.n + extra > self.store.len() || self.cuts + cuts > self.nodes.len() {
            return Err(RenderError::Capacity {
                what: CapacityKind::Pieces,
                needed: (self.n + extra).max(self.store.len() + 1),
                capacity: self.store.len(),
            });
        }
        self.stats.splits += 1;
        self.stats.dropped_slivers += (parts.made - count) as u32;
        // Where the piece hangs in its tree (read before its entry is reused).
        let place = if reuse {
            internal(self.tree.get(x as usize).copied(), NOTHING)
        } else {
            ROOT | x as u32
        };
        // Take the piece out of the list.
        if let Some(rest @ [_, ..]) = self.list.get_mut(at..self.len) {
            rest.rotate_left(1);
        } else {
            debug_assert!(false, "internal error: entry {at} out of the list");
        }
        self.len -= 1;
        if at < *front {
            *front -= 1;
        }
        let rank = self.rank(x);
        let mut slot = reuse.then_some(x as usize);
        let mut refs = [None; 3];
        for (r, part) in refs.iter_mut().zip(parts.parts) {
            let Some(part) = part else { continue };
            let i = slot.take().unwrap_or_else(|| {
                self.n += 1;
                self.n - 1
            });
            *r = Some(LEAF | i as u32);
            if let (Some(s), Some(k), Some(m), Some(o)) = (
                self.store.get_mut(i),
                self.keys.get_mut(i),
                self.marked.get_mut(i),
                self.origin.get_mut(i),
            ) {
                *s = part;
                *k = rank;
                *m = false;
                *o = origin;
            } else {
                // The store had room: checked above.
                debug_assert!(false, "internal error: no store entry {i} for a part");
            }
            // File it in the sorted part.
            let (store, keys) = (&*self.store, &*self.keys);
            let key = sort_key(store, keys, i as u16);
            let Some(sorted) = self.list.get(*front..self.len) else {
                debug_assert!(
                    false,
                    "internal error: sorted part {front}.. out of the list"
                );
                continue;
            };
            let pos = *front + sorted.partition_point(|&j| sort_key(store, keys, j) <= key);
            self.len += 1;
            // The list has room for every piece in the store, and the run is not empty.
            if let Some(run @ [_, ..]) = self.list.get_mut(pos..self.len) {
                rotate_right_by_one(run);
                if let Some(first) = run.first_mut() {
                    *first = i as u16;
                }
            } else {
                debug_assert!(false, "internal error: no list room for piece {i}");
            }
        }
        if let Some(s) = slot.and_then(|i| self.store.get_mut(i)) {
            // Every part was a sliver: the piece is gone.
            *s = StoredTriangle::EMPTY;
        }
        // The parts' tree: part 0 | (part 1 | part 2), leaving out cuts with nothing on a side.
        let [r0, r1, r2] = refs;
        let [l0, l1] = parts.lines;
        let rest = self.join(l1, r1, r2);
        let whole = self.join(l0, r0, rest);
        self.hang(whole.unwrap_or(NOTHING), place);
        Ok(())
    }

    /// The tree of `first` and `rest` split by `line` (whose `inside` point is on `first`'s
    /// side): a new cut if both are there, else whichever is.
    fn join(&mut self, line: Line, first: Option<u32>, rest: Option<u32>) -> Option<u32> {
        let (Some(first), Some(rest)) = (first, rest) else {
            return first.or(rest);
        };
        let (pos, neg) = if line.side(line.inside) >= 0 {
            (first, rest)
        } else {
            (rest, first)
        };
        let k = self.cuts;
        let Some(node) = self.nodes.get_mut(k) else {
            // Room for every cut was checked before the split.
            debug_assert!(false, "internal error: no room for cut {k}");
            return Some(first);
        };
        // The sort's fine units to the cut's: `SORT` bits fewer, to the nearest.
        let point = |p: FineXy| {
            p.map(|v| {
                let v = (v + (1 << (SORT - 1))) >> SORT;
                v.clamp(i32::MIN as i64, i32::MAX as i64) as i32
            })
        };
        *node = Cut {
            a: point(line.a),
            b: point(line.b),
            pos,
            neg,
        };
        self.cuts += 1;
        self.hang(pos, (k as u32) << 1);
        self.hang(neg, (k as u32) << 1 | 1);
        Some(k as u32)
    }

    /// Hangs tree `r` at `place` (see [`Sort::tree`]); a piece remembers where it hangs.
    fn hang(&mut self, r: u32, place: u32) {
        let slot = if place == NOTHING {
            None
        } else if place & ROOT != 0 {
            self.tree.get_mut((place & !ROOT) as usize)
        } else {
            self.nodes.get_mut((place >> 1) as usize).map(|c| {
                if place & 1 == 0 {
                    &mut c.pos
                } else {
                    &mut c.neg
                }
            })
        };
        match slot {
            Some(s) => *s = r,
            None => debug_assert!(false, "internal error: no place {place:#x} for {r:#x}"),
        }
        if r != NOTHING && r & LEAF != 0 {
            if let Some(p) = self.tree.get_mut((r & !LEAF) as usize) {
                *p = place;
            }
        }
    }
}

/// A split-tree reference to a piece: `LEAF | index` (else the index of a [`Cut`]).
const LEAF: u32 = 1 << 31;
/// A split-tree reference to nothing: parts that all rounded to no area.
const NOTHING: u32 = u32::MAX;
/// Where a piece hangs when it is a whole tree: `ROOT | original`.
const ROOT: u32 = 1 << 31;

/// A line through two screen points and a point off it, in fine units ([`FineXy`]).
#[derive(Clone, Copy, Debug)]
struct Line {
    a: FineXy,
    b: FineXy,
    inside: FineXy,
}

impl Line {
    /// The line through the grid points of `a` and `b`, `inside` off it.
    fn through(a: &Vertex, b: &Vertex, inside: &Vertex) -> Line {
        Line {
            a: a.fine(),
            b: b.fine(),
            inside: inside.fine(),
        }
    }

    /// `(b − a) × (p − a)`: its sign says on which side of the line `p` is.
    fn side(&self, p: FineXy) -> i128 {
        let d = |k: usize| self.b[k] as i128 - self.a[k] as i128;
        let from = |k: usize| p[k] as i128 - self.a[k] as i128;
        d(0) * from(1) - d(1) * from(0)
    }
}

/// The line where `plane` cuts the plane of `o`: through the points where it crosses `o`'s
/// edges (or passes through its vertices), each within half a fine unit, with `inside` a
/// vertex of `o` on the side of `plane` whose sign is `side`. `None` if the plane does not
/// cross `o` with a vertex on that side.
///
/// A split tree cuts with this line, not with the line through the rounded cut points: two
/// rounded points close together (a cut across a thin piece) give a line whose direction is
/// off by up to a grid unit over their distance, which sends pixel centres far along it to
/// the wrong part.
fn crossing_line(o: &StoredTriangle, plane: &PlaneEq, side: i128) -> Option<Line> {
    let v = [0, 1, 2].map(|k| Vertex::of(o, k));
    let s = [0, 1, 2].map(|k| plane.at(o, k));
    let mut points: [Option<FineXy>; 2] = [None; 2];
    for k in 0..3 {
        let (u, su) = (v.get(k)?, *s.get(k)?);
        let (w, sw) = (v.get((k + 1) % 3)?, *s.get((k + 1) % 3)?);
        let point = if su == 0 {
            u.fine()
        } else if su.signum() * sw.signum() < 0 {
            u.toward_fine(w, su, su - sw)
        } else {
            continue;
        };
        match points {
            [None, _] => points[0] = Some(point),
            [Some(first), None] if first != point => points[1] = Some(point),
            _ => {}
        }
    }
    let inside =
        (0..3).find(|&k| side != 0 && s.get(k).map(|s| s.signum()) == Some(side.signum()))?;
    let line = Line {
        a: points[0]?,
        b: points[1]?,
        inside: v.get(inside)?.fine(),
    };
    (line.side(line.inside) != 0).then_some(line)
}

/// A node of a split tree: the original piece's region is cut by the line through `a` and `b`
/// (points in sub-pixels · 2^[`FINE`], below 2^30 for coordinates below 2^22 sub-pixels);
/// pixel centres `p` where `(b − a) × (p − a) ≥ 0` go to `pos`, the others to `neg` (each a
/// [`LEAF`] piece, another cut or [`NOTHING`]). Every pixel centre of the original goes to
/// exactly one leaf, whatever the rounding of the cut points, so the parts of a split tile the
/// original without cracks or overlap.
#[derive(Clone, Copy, Debug)]
struct Cut {
    a: [i32; 2],
    b: [i32; 2],
    pos: u32,
    neg: u32,
}

impl Cut {
    const EMPTY: Cut = Cut {
        a: [0; 2],
        b: [0; 2],
        pos: NOTHING,
        neg: NOTHING,
    };

    /// On row `y`, the side of column `x`'s centre (`true`: `pos`) and the first column after
    /// `x` where the side changes, if any (sub-pixel bits `SUB`). Exact: the side is a linear
    /// function `A·x + B` of the column, in `i128` (`|A| < 2^49`, `|B| < 2^66`).
    fn side_and_end<const SUB: u32>(&self, x: i32, y: i32) -> (bool, Option<i128>) {
        let (dx, dy) = (
            self.b[0] as i128 - self.a[0] as i128,
            self.b[1] as i128 - self.a[1] as i128,
        );
        // Doubled coordinates: a centre is at (2c + 1) · 2^(SUB + FINE) halves.
        let bits = SUB + FINE;
        let cx = |c: i128| ((2 * c + 1) << bits) - 2 * self.a[0] as i128;
        let cy = ((2 * y as i128 + 1) << bits) - 2 * self.a[1] as i128;
        let slope = -(dy << (bits + 1));
        let at0 = dx * cy - dy * cx(0);
        let here = slope * x as i128 + at0;
        // (Checked divisions: the divisor is positive, so `None` only stands for no change.)
        if here >= 0 {
            // First column with slope·c + at0 < 0.
            let first = checked_div_euclid_i128(at0, -slope).map(|c| c + 1);
            (true, first.filter(|_| slope < 0))
        } else {
            // First column with slope·c + at0 ≥ 0.
            let first = checked_div_euclid_i128(at0, slope).map(|c| -c);
            (false, first.filter(|_| slope > 0))
        }
    }
}

/// Newell's painter: the walked pieces are the originals, each with its split tree; each
/// pixel gets the colour of the piece latest in the order that covers it. That is what
/// painting the pieces far to near gives, row by row, without walking the pieces themselves.
struct OrderPainter<'a, P, const SUB: u32> {
    pixels: &'a mut [P],
    /// Per pixel: the position (from 1) of the piece painted there, 0 for none.
    order: &'a mut [u32],
    background: P,
    cuts: &'a [Cut],
    /// Per piece: its position in the order, from 1.
    positions: &'a [u32],
    spans: u16,
}

impl<P: RowPixel, const SUB: u32> OrderPainter<'_, P, SUB> {
    /// The piece of `tree` whose region holds column `x` of row `y`, and the first column
    /// (at most `end`) where the leaf changes.
    fn leaf(&self, tree: u32, x: i32, y: i32, end: i32) -> (u32, i32) {
        let (mut r, mut end) = (tree, end);
        // A tree has at most one cut per node: a walk longer than that is an internal error.
        for _ in 0..=self.cuts.len() {
            if r == NOTHING || r & LEAF != 0 {
                return (r, end);
            }
            let Some(cut) = self.cuts.get(r as usize) else {
                break;
            };
            let (pos, change) = cut.side_and_end::<SUB>(x, y);
            if let Some(c) = change {
                // (`max`/`min` rather than `clamp`, which keeps a panic path.)
                end = end.min(c.max(x as i128 + 1).min(i32::MAX as i128) as i32);
            }
            r = if pos { cut.pos } else { cut.neg };
        }
        debug_assert!(false, "internal error: split tree {tree:#x} has no leaf");
        (NOTHING, end)
    }
}

impl<P: RowPixel, S: Shading, const SUB: u32> Resolve<P, S> for OrderPainter<'_, P, SUB> {
    type Key = u32;
    fn begin_band(&mut self, _: i32, _: usize) {
        self.pixels.fill(self.background);
        self.order.fill(0);
        self.spans = 0;
    }
    fn span(&mut self, t: &ActiveTri<S::Payload<P>, u32>, _: usize, y: i32, l: i32, r: i32) -> u32 {
        self.spans += 1;
        let mut written = 0;
        let mut x = l;
        while x < r {
            let (leaf, end) = self.leaf(t.key, x, y, r);
            let key = if leaf == NOTHING {
                0
            } else {
                internal(self.positions.get((leaf & !LEAF) as usize).copied(), 0)
            };
            // Paint the runs of `x..end` not yet painted by a later piece.
            let (Some(pixels), Some(order)) = (
                self.pixels.get_mut(x as usize..end as usize),
                self.order.get_mut(x as usize..end as usize),
            ) else {
                // walk_band clamps spans to the row, and `x < end <= r`.
                debug_assert!(false, "internal error: span {x}..{end} out of the row");
                return written;
            };
            let mut i = 0;
            while i < order.len() {
                let start = i;
                while order.get(i).is_some_and(|&o| o < key) {
                    i += 1;
                }
                if let (Some(run), Some(o)) = (pixels.get_mut(start..i), order.get_mut(start..i)) {
                    if !run.is_empty() {
                        o.fill(key);
                        S::paint(&t.payload, x + start as i32, y, run);
                        written += run.len() as u32;
                    }
                }
                i += 1;
            }
            x = end;
        }
        written
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

/// The sorted part's order: farthest point first; on a tie the later-activated piece first.
fn sort_key(store: &[StoredTriangle], keys: &[u32], i: u16) -> (i32, Reverse<u32>) {
    // List entries index the store and its keys.
    let q = internal(store.get(i as usize).map(min_q), i32::MAX);
    (q, Reverse(internal(keys.get(i as usize).copied(), 0)))
}

/// What [`cut`] makes of a piece.
struct Parts {
    /// Up to three triangles of the piece's orientation, each on one side of the plane
    /// (within the rounding tolerance); parts of zero screen area are left out (`None`).
    parts: [Option<StoredTriangle>; 3],
    /// How many parts the cut made (2 or 3).
    made: usize,
    /// The lines between them: `lines[0]` has part 0 on its `inside` and parts 1 and 2 on the
    /// other side, `lines[1]` (if any) separates part 1 (inside) from part 2.
    lines: [Line; 2],
}

/// Cuts `t` by `plane` (see [`Parts`]), the cut points rounded to the nearest grid point.
fn cut(t: &StoredTriangle, plane: &PlaneEq) -> Parts {
    let (v, on_plane) = rotated(t, plane);
    assemble(t, &v, on_plane, nearest_points(t, plane, &v, on_plane))
}

/// Where `plane` crosses the edges of `t` (vertices `[a, b, c]` [`rotated`]), rounded to the
/// nearest grid point: on `bc` (twice) when `a` is on the plane, else on `ab` and `ac`.
fn nearest_points(
    t: &StoredTriangle,
    plane: &PlaneEq,
    [a, b, c]: &[Vertex; 3],
    on_plane: bool,
) -> [Vertex; 2] {
    let at = |u: &Vertex, w: &Vertex| {
        let (su, sw) = (plane.at(t, u.k), plane.at(t, w.k));
        u.toward(w, su, su - sw)
    };
    if on_plane {
        let i = at(b, c);
        [i, i]
    } else {
        [at(a, b), at(a, c)]
    }
}

/// `t`'s vertices rotated so that the first is the odd one out: the vertex on `plane` when
/// one is (then `true`), else the one alone on its side.
fn rotated(t: &StoredTriangle, plane: &PlaneEq) -> ([Vertex; 3], bool) {
    let s = [0, 1, 2].map(|k| plane.at(t, k).signum());
    let lead = if let Some(z) = (0..3).find(|&k| s[k] == 0) {
        z
    } else {
        // The plane straddles `t`: its signs are +1 and −1, and two of the three agree.
        internal((0..3).find(|&k| s[(k + 1) % 3] == s[(k + 2) % 3]), 0)
    };
    let on_plane = s.get(lead).is_some_and(|&s| s == 0);
    ([0, 1, 2].map(|k| Vertex::of(t, (lead + k) % 3)), on_plane)
}

/// The parts of `t`, whose vertices `[a, b, c]` are [`rotated`], for the cut points `points`:
/// one point on `bc` (given twice) when `a` is on the plane, else points on `ab` and `ac`.
fn assemble(
    t: &StoredTriangle,
    [a, b, c]: &[Vertex; 3],
    on_plane: bool,
    points: [Vertex; 2],
) -> Parts {
    let tri = |p: [Vertex; 3]| make(t, p);
    let line = Line::through;
    let [i1, i2] = points;
    if on_plane {
        // b and c lie on opposite sides.
        let l = line(a, &i1, b);
        Parts {
            parts: [tri([*a, *b, i1]), tri([*a, i1, *c]), None],
            made: 2,
            lines: [l, l],
        }
    } else {
        Parts {
            parts: [tri([*a, i1, i2]), tri([i1, *b, *c]), tri([i1, *c, i2])],
            made: 3,
            lines: [line(&i1, &i2, a), line(&i1, c, b)],
        }
    }
}

/// Bits below the sub-pixel grid of the sort's grid: pieces' vertices are in sub-pixels · 2^4
/// while sorting, so rounding a cut point moves it by at most 1/32 of a sub-pixel per axis
/// (and the plane tests' tolerance cell is as small). Coordinates below 2^22 sub-pixels are
/// below 2^26 there.
const SORT: u32 = 4;

/// Bits below the sort's grid at which [`round_apart`] places the exact cut points and
/// [`crossing_line`] finds a split tree's line (a [`Cut`] keeps it [`SORT`] bits coarser, in
/// sub-pixels · 2^8): a [`FineXy`] is sort units · 2^8. Coordinates below 2^26 sort units stay
/// below 2^34 (their cross products below 2^71, taken in `i128`), and the interpolation's
/// products below 2^123.
const FINE: u32 = 8;

/// A screen point in sort units · 2^[`FINE`].
type FineXy = [i64; 2];

/// The screen a frame is sorted for: its bits below the pixel (sub-pixel and [`SORT`] bits)
/// and size in pixels.
#[derive(Clone, Copy, Debug)]
struct Grid {
    sub: u32,
    width: i64,
    height: i64,
}

/// When `parts` (the nearest rounding of a cut of `t` by `plane`) leaves one side of the plane
/// without a part of any area while that side's exact region of `t` holds pixel centres, the
/// same cut with its cut points rounded apart, each to a corner of the grid cell that
/// holds it, so that the side keeps a part whose region in the split tree holds those centres.
/// Of the corners, the nearest pair (summed squared distance) that keeps every cut point on
/// the plane within its tolerance (its depth taken from `t`'s plane), every part's
/// orientation and the dividing line between `t`'s vertices on the two sides, and that puts
/// every such centre on the lost side's part. `None` if no side is lost, its region holds
/// no centre, or no pair of corners does all that.
fn round_apart(t: &StoredTriangle, plane: &PlaneEq, parts: &Parts, grid: Grid) -> Option<Parts> {
    let (v, on_plane) = rotated(t, plane);
    let [a, b, c] = &v;
    let none = parts.parts.each_ref().map(Option::is_none);
    let fine = Vertex::fine;
    let exact = |u: &Vertex, w: &Vertex| {
        let (su, sw) = (plane.at(t, u.k), plane.at(t, w.k));
        u.toward_fine(w, su, su - sw)
    };
    let (e1, e2) = if on_plane {
        let e = exact(b, c);
        (e, e)
    } else {
        (exact(a, b), exact(a, c))
    };
    // The lost side: its exact region, whether its part lies on the `inside` of the first
    // dividing line, and which parts may stand for it.
    let (tri, quad);
    let (region, inside, lost): (&[FineXy], bool, [bool; 3]) = match (on_plane, none) {
        (true, [true, false, _]) => {
            tri = [fine(a), fine(b), e1];
            (&tri, true, [true, false, false])
        }
        (true, [false, true, _]) => {
            tri = [fine(a), e1, fine(c)];
            (&tri, false, [false, true, false])
        }
        (false, [true, p1, p2]) if !(p1 && p2) => {
            tri = [fine(a), e1, e2];
            (&tri, true, [true, false, false])
        }
        (false, [false, true, true]) => {
            quad = [e1, fine(b), fine(c), e2];
            (&quad, false, [false, true, true])
        }
        _ => return None,
    };
    if for_each_centre(region, grid, |_| false) {
        return None; // no pixel centre to keep
    }
    let own = PlaneEq::of(t)?;
    let orientation = signed_area(t).signum();
    let nearest = nearest_points(t, plane, &v, on_plane);
    // Only positions change (colours stay the nearest rounding's); depths are `t`'s there.
    let moved = |p: &[i32; 2], like: &Vertex| Vertex {
        x: p[0],
        y: p[1],
        q: own.q_at(p[0], p[1]),
        ..*like
    };
    let (cells1, cells2) = (corners(e1), corners(e2));
    let mut best: Option<(i128, Parts)> = None;
    for (k1, p1) in cells1.iter().enumerate() {
        // With one cut point (`a` on the plane) both stand for it.
        let (skip, take) = if on_plane { (k1, 1) } else { (0, 4) };
        for p2 in cells2.iter().skip(skip).take(take) {
            let [n1, n2] = &nearest;
            let points = [moved(p1, n1), moved(p2, n2)];
            if points
                .iter()
                .any(|m| 2 * plane.at_point(m.x, m.y, m.q).abs() > plane.tol)
            {
                continue;
            }
            let candidate = assemble(t, &v, on_plane, points);
            let kept = candidate
                .parts
                .iter()
                .zip(lost)
                .any(|(p, l)| l && p.is_some());
            let oriented = candidate
                .parts
                .iter()
                .flatten()
                .all(|p| signed_area(p).signum() == orientation);
            let [l0, _] = candidate.lines;
            let side = |u: &Vertex| l0.side(u.fine()).signum();
            let separates = if on_plane {
                side(b) * side(c) < 0
            } else {
                side(a) != 0 && side(b) == -side(a) && side(c) == -side(a)
            };
            if !(kept && oriented && separates) {
                continue;
            }
            let on_inside = |p: FineXy| (l0.side(p) >= 0) == (l0.side(l0.inside) >= 0);
            if !for_each_centre(region, grid, |p| on_inside(p) == inside) {
                continue;
            }
            let d = |p: &[i32; 2], e: FineXy| {
                let ([px, py], [ex, ey]) = (*p, e);
                let (dx, dy) = (
                    (((px as i64) << FINE) - ex) as i128,
                    (((py as i64) << FINE) - ey) as i128,
                );
                dx * dx + dy * dy
            };
            let distance = d(p1, e1) + d(p2, e2);
            if best.as_ref().is_none_or(|(bd, _)| distance < *bd) {
                best = Some((distance, candidate));
            }
        }
    }
    best.map(|(_, p)| p)
}

/// The four grid points around `e` (corners of its grid cell; repeated when `e` is on
/// a grid line).
fn corners(e: FineXy) -> [[i32; 2]; 4] {
    let down = |v: i64| (v >> FINE).clamp(i32::MIN as i64, i32::MAX as i64) as i32;
    let up = |v: i64| (-((-v) >> FINE)).clamp(i32::MIN as i64, i32::MAX as i64) as i32;
    let [x, y] = e;
    [
        [down(x), down(y)],
        [up(x), down(y)],
        [down(x), up(y)],
        [up(x), up(y)],
    ]
}

/// Twice the signed screen area of `t` (positive counter-clockwise in `x`, `y`).
fn signed_area(t: &StoredTriangle) -> i64 {
    let d = |v: &[i32; 3], k: usize| v[k] as i64 - v[0] as i64;
    d(&t.x, 1) * d(&t.y, 2) - d(&t.y, 1) * d(&t.x, 2)
}

/// Calls `f` with each pixel centre (on the screen of `grid`) strictly inside the convex
/// polygon `region`, row by row, until `f` returns `false`; `true` if it never did. The work
/// is the rows the region spans plus, per row, the columns between its edges there.
fn for_each_centre(region: &[FineXy], grid: Grid, mut f: impl FnMut(FineXy) -> bool) -> bool {
    let shift = grid.sub + FINE;
    let half = 1i64 << (shift - 1);
    // First pixel whose centre is at or after `v` / last whose centre is at or before `v`.
    let first = |v: i64| -((half - v).wrapping_shr(shift));
    let last = |v: i64| (v - half).wrapping_shr(shift);
    let centre = |i: i64| (i << shift) + half;
    let edges = || {
        region
            .iter()
            .zip(region.iter().cycle().skip(1))
            .map(|(p, q)| (*p, *q))
    };
    let cross = |p: FineXy, q: FineXy, r: FineXy| {
        (q[0] - p[0]) as i128 * (r[1] - p[1]) as i128
            - (q[1] - p[1]) as i128 * (r[0] - p[0]) as i128
    };
    let orientation: i128 = edges()
        .map(|(p, q)| cross([0, 0], p, q))
        .sum::<i128>()
        .signum();
    let inside =
        |r: FineXy| orientation != 0 && edges().all(|(p, q)| cross(p, q, r) * orientation > 0);
    let (y0, y1) = region
        .iter()
        .fold((i64::MAX, i64::MIN), |(l, h), p| (l.min(p[1]), h.max(p[1])));
    for row in first(y0).max(0)..=last(y1).min(grid.height - 1) {
        let y = centre(row);
        // The region's extent on this row, rounded outwards.
        let (mut x0, mut x1) = (i64::MAX, i64::MIN);
        for (p, q) in edges() {
            if (p[1] - y) * (q[1] - y) > 0 {
                continue;
            }
            let (lo, hi) = if p[1] == q[1] {
                (p[0].min(q[0]), p[0].max(q[0]))
            } else {
                let (num, den) = (
                    (y - p[1]) as i128 * (q[0] - p[0]) as i128,
                    (q[1] - p[1]) as i128,
                );
                let (num, den) = if den < 0 { (-num, -den) } else { (num, den) };
                let floor = checked_div_euclid_i128(num, den).unwrap_or(0) as i64;
                (p[0] + floor, p[0] + floor + 1)
            };
            x0 = x0.min(lo);
            x1 = x1.max(hi);
        }
        if x0 > x1 {
            continue; // (no edge reaches the row: not for a row within the region's extent)
        }
        for col in first(x0).max(0)..=last(x1).min(grid.width - 1) {
            let p = [centre(col), y];
            if inside(p) && !f(p) {
                return false;
            }
        }
    }
    true
}

/// `t` with the depths of its vertices on the other side of `plane` than its centroid moved
/// onto the plane (to the nearest I2F30 step), so that `plane` no longer straddles it.
fn press(t: &StoredTriangle, plane: &PlaneEq) -> StoredTriangle {
    let s = [0, 1, 2].map(|k| plane.at(t, k));
    let front = s.iter().sum::<i128>() >= 0;
    let mut q = t.q;
    for (q, s) in q.iter_mut().zip(s) {
        if (s < 0) == front {
            // `s` changes by `n_q` per step of `q`: the rounded step leaves `2·|s| <= n_q`,
            // within the plane's tolerance.
            let moved = *q as i128 - div_round(s, plane.n[2]);
            *q = moved.clamp(i32::MIN as i128, i32::MAX as i128) as i32;
        }
    }
    StoredTriangle { q, ..*t }
}

/// A vertex of a piece being cut: position, depth and colour.
#[derive(Clone, Copy, Debug)]
struct Vertex {
    k: usize,
    x: i32,
    y: i32,
    q: i32,
    color: Rgb888,
}

impl Vertex {
    /// The vertex's grid point in fine units.
    fn fine(&self) -> FineXy {
        [(self.x as i64) << FINE, (self.y as i64) << FINE]
    }

    fn of(t: &StoredTriangle, k: usize) -> Vertex {
        // Checked lookups: `k` is below 3 at every call, which `opt-level = "z"` cannot see.
        Vertex {
            k,
            x: t.x.get(k).copied().unwrap_or(0),
            y: t.y.get(k).copied().unwrap_or(0),
            q: t.q.get(k).copied().unwrap_or(0),
            color: t.colors.get(k).copied().unwrap_or(Rgb888::BLACK),
        }
    }

    /// The screen position `num/den` of the way from `self` to `w`, in fine units
    /// ([`FineXy`], rounded to the nearest).
    fn toward_fine(&self, w: &Vertex, num: i128, den: i128) -> FineXy {
        let (num, den) = if den < 0 { (-num, -den) } else { (num, den) };
        let lerp = |a: i32, b: i32| {
            let along = div_round(((b as i128 - a as i128) << FINE) * num, den);
            ((a as i128) << FINE) + along
        };
        let clamp = |v: i128| v.clamp(i64::MIN as i128, i64::MAX as i128) as i64;
        [clamp(lerp(self.x, w.x)), clamp(lerp(self.y, w.y))]
    }

    /// The point `num/den` of the way from `self` to `w` (`0 < num/den < 1`), rounded to the
    /// sub-pixel grid, the I2F30 step and whole colour steps.
    fn toward(&self, w: &Vertex, num: i128, den: i128) -> Vertex {
        let (num, den) = if den < 0 { (-num, -den) } else { (num, den) };
        let lerp = |a: i32, b: i32| a as i128 + div_round((b as i128 - a as i128) * num, den);
        let clamp = |v: i128| v.clamp(i32::MIN as i128, i32::MAX as i128) as i32;
        let channel = |a: u8, b: u8| lerp(a as i32, b as i32).clamp(0, 255) as u8;
        Vertex {
            k: self.k,
            x: clamp(lerp(self.x, w.x)),
            y: clamp(lerp(self.y, w.y)),
            q: clamp(lerp(self.q, w.q)),
            color: Rgb888::new(
                channel(self.color.r(), w.color.r()),
                channel(self.color.g(), w.color.g()),
                channel(self.color.b(), w.color.b()),
            ),
        }
    }
}

/// The part of `t` with vertices `p`, or `None` if it has no screen area.
fn make(t: &StoredTriangle, p: [Vertex; 3]) -> Option<StoredTriangle> {
    let part = StoredTriangle {
        x: p.map(|v| v.x),
        y: p.map(|v| v.y),
        q: p.map(|v| v.q),
        id: t.id,
        colors: p.map(|v| v.color),
    };
    PlaneEq::of(&part).map(|_| part)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri(x: [i32; 3], y: [i32; 3], q: [i32; 3]) -> StoredTriangle {
        StoredTriangle {
            x,
            y,
            q,
            ..StoredTriangle::EMPTY
        }
    }

    #[test]
    fn a_cut_keeps_each_part_on_one_side_and_shares_the_cut() {
        // A triangle facing the eye at q = 1000, cut by a steep plane through x = 50.
        let t = tri([0, 100, 0], [0, 50, 100], [1000; 3]);
        let cutter = tri([50, 51, 50], [0, 50, 100], [0, 5000, 10]);
        let plane = PlaneEq::of(&cutter).unwrap();
        assert!(plane.straddled_by(&t));
        let Parts { parts, made, .. } = cut(&t, &plane);
        assert_eq!((parts.iter().flatten().count(), made), (3, 3));
        let area = |p: &StoredTriangle| PlaneEq::of(p).unwrap().n[2];
        let total: i128 = parts.iter().flatten().map(area).sum();
        // Up to rounding of the two cut points, the parts tile the triangle.
        assert!((total - area(&t)).abs() <= 200, "{total} vs {}", area(&t));
        for p in parts.iter().flatten() {
            assert!(!plane.straddled_by(p), "{p:?}");
        }
    }

    #[test]
    fn a_side_whose_cut_points_round_together_keeps_its_pixel_centres() {
        // The sliver of the soup seen from outside (docs/realworld.md): one sub-pixel wide,
        // cut about 55 % along by a steep plane, both cut points round to (2272, 1603), so the
        // apex's side has no area once rounded, yet its exact region holds the centre of
        // pixel (141, 99) at 4 sub-pixel bits.
        let t = tri(
            [2110, 2404, 2404],
            [1384, 1782, 1781],
            [32920895, 34271487, 34263591],
        );
        let cutter = tri([1772, 2772, 2272], [1403, 1803, 1604], [0, 0, 1 << 29]);
        let plane = PlaneEq::of(&cutter).unwrap();
        assert!(plane.straddled_by(&t));
        let nearest = cut(&t, &plane);
        assert!(nearest.parts[0].is_none() && nearest.parts[1].is_some());
        let grid = Grid {
            sub: 4,
            width: 240,
            height: 240,
        };
        let apart = round_apart(&t, &plane, &nearest, grid).expect("rounded apart");
        assert!(apart.parts[0].is_some(), "the apex's side keeps a part");
        let line = apart.lines[0];
        let centre: FineXy = [2264 << FINE, 1592 << FINE];
        let inside = line.side(line.inside) >= 0;
        assert_eq!(line.side(centre) >= 0, inside, "and the centre goes to it");
        for p in apart.parts.iter().flatten() {
            assert!(!plane.straddled_by(p), "{p:?}");
        }
        // Off the screen there is no centre to keep.
        let small = Grid { width: 100, ..grid };
        assert!(round_apart(&t, &plane, &nearest, small).is_none());
        // A cut that leaves both sides a part is kept as it is.
        let wide = tri([0, 100, 0], [0, 50, 100], [1000; 3]);
        let steep = PlaneEq::of(&tri([50, 51, 50], [0, 50, 100], [0, 5000, 10])).unwrap();
        assert!(round_apart(&wide, &steep, &cut(&wide, &steep), grid).is_none());
    }

    #[test]
    fn a_cut_sends_each_pixel_centre_to_one_side_and_finds_where_it_changes() {
        // Lines at various slopes through points in fine units (4 sub-pixel bits), against
        // the sign of the cross product at each centre of a row.
        for (a, b) in [
            ([3, 5], [200, 90]),
            ([40, 0], [41, 300]),
            ([0, 17], [150, 17]),
            ([100, 8], [20, 250]),
            ([64, 0], [64, 99]),
        ]
        .map(|(a, b): ([i32; 2], [i32; 2])| (a.map(|v| v << FINE), b.map(|v| v << FINE)))
        .into_iter()
        .chain([
            ([1000, 1337], [851_000, 9_001]),
            ([-77, 4_100], [3, 976_543]),
        ]) {
            let cut = Cut { a, b, ..Cut::EMPTY };
            let side = |c: i32, y: i32| {
                let fine = |p: [i32; 2]| p.map(i64::from);
                let line = Line {
                    a: fine(a),
                    b: fine(b),
                    inside: fine(a),
                };
                let centre = |c: i32| ((c * 16 + 8) as i64) << FINE;
                line.side([centre(c), centre(y)]) >= 0
            };
            for y in 0..16 {
                for x in 0..20 {
                    let (pos, change) = cut.side_and_end::<4>(x, y);
                    assert_eq!(pos, side(x, y), "{a:?} {b:?} at {x}, {y}");
                    let first = (x + 1..200).find(|&c| side(c, y) != pos);
                    let change = change.map(|c| c.max(x as i128 + 1) as i32);
                    assert_eq!(
                        change.filter(|&c| c < 200),
                        first,
                        "{a:?} {b:?} at {x}, {y}"
                    );
                }
            }
        }
    }

    #[test]
    fn touching_projections_do_not_overlap() {
        let a = tri([0, 16, 0], [0, 0, 16], [1; 3]);
        let b = tri([16, 16, 0], [0, 16, 16], [1; 3]);
        assert!(!projections_overlap(&a, &b));
        let c = tri([4, 24, 4], [4, 4, 24], [1; 3]);
        assert!(!projections_overlap(
            &a,
            &tri([8, 24, 8], [8, 8, 24], [1; 3])
        )); // a corner touches
        assert!(projections_overlap(&a, &c));
    }
}
