//! Hybrid mode: primary visibility by a scanline pass over the objects' screen bounds instead of
//! a hierarchy walk per pixel, then the same ray tree as the pure tracer from each pixel's first
//! hit, row by row into the same [`RowSink`]s.
//!
//! Once per frame every object's box ([`bvh::bounds`] padded by [`bvh::PAD`]) is projected onto
//! the screen: the pixel rectangle its eight corners span, widened by [`MARGIN`] pixels (planes,
//! and boxes reaching behind `near / 2`, cover the whole screen; boxes wholly behind it or off
//! screen are dropped). The rectangles are sorted by first row into the caller's `bounds`
//! buffer. Per row an active list (the caller's `active` buffer) holds the rectangles spanning
//! the row; per pixel only the active objects whose columns cover it are intersected, with the
//! pure tracer's intersection code and its order-free tie rule (nearest `t`, then smaller id).
//! A ray through a pixel that hits an object meets it inside the object's padded box, whose
//! projection contains the pixel centre up to the direction's rounding (below 2^-14 radians,
//! far below the margin's pixels), so the candidates include every object the pure tracer
//! could find: the first hit, and so the pixel, is the pure tracer's. Where many rectangles
//! pile up (a dense mesh), a group of a row's columns walks the hierarchy instead, which finds
//! the same first hit at less cost (`walk_groups`).
//!
//! Memory: `bounds` needs one [`ScreenBound`] (12 bytes) per visible object, `active` one per
//! object spanning a row. When either is too small the rows concerned fall back to the pure
//! tracer's primary search (same image, more work) and [`TraceStats::fallback_rows`] counts
//! them; nothing is dropped silently.

use crate::depth::DepthRow;
use crate::math::zip3;
use crate::sink::{Row, RowPixel, RowSink};
use crate::trace::bvh::{self, heap_sort_by_key, PAD};
use crate::trace::row_shadow::{
    ellipsoid_of, padded_box, row_region, row_shadows, shadow_windows, RowShadows, ShadowCandidate,
};
use crate::trace::shape::{Object, Shape};
use crate::trace::tracer::{Nearest, PixelTrace, ShadowCache, TraceError, TraceStats, Tracer};
use crate::trace::vector::Vec3;

/// Pixels added on each side of a projected box: covers the truncation to whole pixels and the
/// rounding of ray directions and of the projection (f32, relative error near 2^-20).
pub const MARGIN: i32 = 2;

/// Groups of columns a row is split into to choose each group's primary search.
const GROUPS: usize = 16;
/// Most active rectangles a row may have for its pixels to scan them: each pixel compares its
/// column with every one (chosen by measuring the method table's traced meshes on thumbv7em;
/// docs/tracing.md).
const MAX_LIVE: usize = 128;
/// Most rectangles reaching into a group of columns for its pixels to test the rectangles
/// covering them rather than walk the hierarchy, whose front-to-back walk skips what lies
/// behind the first hits (measured as [`MAX_LIVE`]).
const MAX_COVER: u16 = 16;

/// The group of columns column `x` of a row `width` pixels wide belongs to.
fn group(x: u16, width: u16) -> usize {
    usize::from(x) * GROUPS / usize::from(width.max(1))
}

/// Per group of columns of a row, whether its primary rays walk the hierarchy instead of
/// testing the row's active rectangles `live` (always when the row could not be `scanned`);
/// `None` when no group does (a row of at most [`MAX_COVER`] rectangles, such as the
/// classic's, at no cost per pixel). Either search finds the same first hit; this only picks
/// the cheaper one.
fn walk_groups(live: &[ScreenBound], width: u16, scanned: bool) -> Option<[bool; GROUPS]> {
    if !scanned || live.len() > MAX_LIVE {
        return Some([true; GROUPS]);
    }
    if live.len() <= usize::from(MAX_COVER) {
        return None;
    }
    let mut cover = [0u16; GROUPS];
    for b in live {
        for c in cover
            .iter_mut()
            .take(group(b.x1, width) + 1)
            .skip(group(b.x0, width))
        {
            *c += 1;
        }
    }
    let walk = cover.map(|c| c > MAX_COVER);
    walk.contains(&true).then_some(walk)
}

/// The pixel rectangle an object may be seen in (inclusive bounds).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ScreenBound {
    /// The object's id.
    pub object: u32,
    /// First column.
    pub x0: u16,
    /// Last column.
    pub x1: u16,
    /// First row.
    pub y0: u16,
    /// Last row.
    pub y1: u16,
}

/// A frame in progress: the sorted bounds, the next one to activate and the active list.
struct Scan<'b> {
    bounds: &'b [ScreenBound],
    /// Every visible object found room in `bounds`.
    complete: bool,
    next: usize,
    active: &'b mut [ScreenBound],
    live: usize,
}

impl Scan<'_> {
    /// Brings the active list to row `y`; false when it overflowed (the row must fall back).
    /// `changed` is set when the list changed.
    fn advance(&mut self, y: u16, changed: &mut bool) -> bool {
        let before = (self.live, self.next);
        // Drop the rectangles that ended above this row, keeping the rest packed.
        let mut kept = 0;
        for i in 0..self.live {
            if let Some(b) = self.active.get(i).copied() {
                if b.y1 >= y {
                    if let Some(slot) = self.active.get_mut(kept) {
                        *slot = b;
                    }
                    kept += 1;
                }
            }
        }
        self.live = kept;
        while let Some(b) = self.bounds.get(self.next) {
            if b.y0 > y {
                break;
            }
            match self.active.get_mut(self.live) {
                Some(slot) => *slot = *b,
                // Left for a later row; this one falls back.
                None => {
                    *changed = true;
                    return false;
                }
            }
            self.live += 1;
            self.next += 1;
        }
        // Rectangles only leave (fewer live) or enter (a later next).
        *changed = (self.live, self.next) != before;
        self.complete
    }
}

/// The range of `X / Z` over an axis-aligned ellipsoid centred `c` (relative to the eye) with
/// semi-axes `radii`, wholly in front of the eye (`Z = p·forward > 0` on it), where
/// `X = p·axis / |axis|`: the slopes `m` of the two planes `X = m·Z` tangent to it, which
/// solve `(n·c)² = Σ nᵢ² rᵢ²` for `n = axis / |axis| − m·forward`. `None` if rounding left no
/// two roots.
fn tangent_slopes(
    c: [f32; 3],
    radii: [f32; 3],
    axis: [f32; 3],
    forward: [f32; 3],
) -> Option<(f32, f32)> {
    let length = libm::sqrtf(axis.iter().map(|a| a * a).sum());
    let a = axis.map(|v| v / length);
    // Σ_i p_i·q_i·w_i, summed in index order (no indexing: no bounds checks at any opt-level).
    let sum = |p: [f32; 3], q: [f32; 3], w: [f32; 3]| {
        let [t0, t1, t2] = zip3(zip3(p, q, |p, q| p * q), w, |pq, w| pq * w);
        t0 + t1 + t2
    };
    let one = [1.0; 3];
    let (cx, cz) = (sum(a, c, one), sum(forward, c, one));
    let r2 = radii.map(|r| r * r);
    let (saa, sff, saf) = (
        sum(a, a, r2),
        sum(forward, forward, r2),
        sum(a, forward, r2),
    );
    // m²·(cz² − Sff) − 2m·(cx·cz − Saf) + (cx² − Saa) = 0.
    let q = cz * cz - sff;
    let half_b = cx * cz - saf;
    let disc = half_b * half_b - q * (cx * cx - saa);
    if !(q > 0.0 && disc >= 0.0) {
        return None;
    }
    let root = libm::sqrtf(disc);
    Some(((half_b - root) / q, (half_b + root) / q))
}

/// Whether a polygon's outline, projected along `axis` (as the point-in-polygon test sees
/// it), turns one way only: convex (exact, raw bits).
fn convex(vertices: &[Vec3], axis: u8) -> bool {
    let project = |v: &Vec3| {
        let [x, y, z] = v.bits().map(i64::from);
        match axis {
            0 => (y, z),
            1 => (z, x),
            _ => (x, y),
        }
    };
    let n = vertices.len();
    let (mut positive, mut negative) = (false, false);
    // A star turns one way too: a convex outline's edges also change direction along the
    // first axis only twice (zeros skipped).
    let (mut changes, mut last_dx) = (0, 0i64);
    for i in 0..n {
        let (Some(a), Some(b), Some(c)) = (
            vertices.get(i),
            vertices.get((i + 1) % n),
            vertices.get((i + 2) % n),
        ) else {
            return false;
        };
        let ((ax, ay), (bx, by), (cx, cy)) = (project(a), project(b), project(c));
        // Differences below 2^30 raw: the products stay below 2^61.
        let turn = (bx - ax) * (cy - by) - (by - ay) * (cx - bx);
        positive |= turn > 0;
        negative |= turn < 0;
        let dx = bx - ax;
        if dx != 0 {
            if last_dx != 0 && (dx > 0) != (last_dx > 0) {
                changes += 1;
            }
            last_dx = dx;
        }
    }
    // The wrap from the last edge to the first.
    let first_dx = (0..n)
        .filter_map(|i| {
            let (a, b) = (vertices.get(i)?, vertices.get((i + 1) % n)?);
            Some(project(b).0 - project(a).0)
        })
        .find(|dx| *dx != 0)
        .unwrap_or(0);
    if first_dx != 0 && last_dx != 0 && (first_dx > 0) != (last_dx > 0) {
        changes += 1;
    }
    n >= 3 && !(positive && negative) && changes <= 2
}

impl<'s, 'a, const STACK: usize> Tracer<'s, 'a, STACK> {
    /// Writes the screen bounds of the visible objects into `bounds`, sorted by first row;
    /// returns how many were written and whether all fitted.
    pub fn screen_bounds(&self, bounds: &mut [ScreenBound]) -> (usize, bool) {
        let camera = self.camera();
        let (w, h) = (camera.width, camera.height);
        let [corner, right, down, eye] = camera.float_basis();
        let dot = |a: [f32; 3], b: [f32; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        // The view direction: the direction through the image centre.
        let (hw, hh) = (f32::from(w - 1) / 2.0, f32::from(h - 1) / 2.0);
        let forward: [f32; 3] = core::array::from_fn(|i| corner[i] + hw * right[i] + hh * down[i]);
        let (rr, dd) = (dot(right, right), dot(down, down));
        let (cr, cd) = (dot(corner, right), dot(corner, down));
        let near = camera.near.to_num::<f32>() / 2.0;
        let full = (0, w - 1, 0, h - 1);
        // The pixel rectangle of coordinate ranges, widened by the margin; `None` off screen.
        let rect_of = |x: (f32, f32), y: (f32, f32)| {
            // `as` saturates; truncation towards zero is inside the margin.
            let (x0, x1) = (
                (x.0 as i32).saturating_sub(MARGIN),
                (x.1 as i32).saturating_add(MARGIN),
            );
            let (y0, y1) = (
                (y.0 as i32).saturating_sub(MARGIN),
                (y.1 as i32).saturating_add(MARGIN),
            );
            let (wi, hi) = (i32::from(w), i32::from(h));
            (x1 >= 0 && y1 >= 0 && x0 < wi && y0 < hi).then(|| {
                // max/min, not clamp: clamp's check for an empty range would link a panic.
                let clamp = |v: i32, n: i32| v.max(0).min(n - 1) as u16;
                (clamp(x0, wi), clamp(x1, wi), clamp(y0, hi), clamp(y1, hi))
            })
        };
        let mut used = 0;
        let mut complete = true;
        for (id, object) in self.scene().objects.iter().enumerate() {
            // Per axis the range of a seen point's pixel coordinate, and the range of the eye
            // depths of the object's points.
            let extent = match ellipsoid_of(&object.shape) {
                // A sphere or ellipsoid wholly in front: its exact outline (the planes through
                // the eye tangent to it), far inside its box's corners.
                Some((c, radii)) => {
                    let c: [f32; 3] = core::array::from_fn(|i| c[i] - eye[i]);
                    // Half its extent along the view direction: √(Σ forwardᵢ² rᵢ²).
                    let half = libm::sqrtf(
                        (0..3)
                            .map(|i| forward[i] * forward[i] * radii[i] * radii[i])
                            .sum(),
                    );
                    let depth = dot(c, forward);
                    (depth - half > near).then(|| {
                        let outline = |axis: [f32; 3], origin: f32, step: f32| {
                            let (lo, hi) = tangent_slopes(c, radii, axis, forward)?;
                            // A slope m = X / Z is the pixel coordinate (m·|axis| − origin) / step.
                            let n = libm::sqrtf(step);
                            Some(((lo * n - origin) / step, (hi * n - origin) / step))
                        };
                        Some((
                            outline(right, cr, rr)?,
                            outline(down, cd, dd)?,
                            depth - half,
                            depth + half,
                        ))
                    })
                }
                None => None,
            }
            .flatten();
            let rect = match (extent, bvh::bounds(&object.shape)) {
                (_, None) => Some(full),
                (Some((x, y, _, _)), Some(_)) => rect_of(x, y),
                (None, Some((lo, hi))) => {
                    let pad = Vec3 {
                        x: PAD,
                        y: PAD,
                        z: PAD,
                    };
                    let (lo, hi) = (lo.sub(pad).bits(), hi.add(pad).bits());
                    let (mut x, mut y) = ((f32::MAX, f32::MIN), (f32::MAX, f32::MIN));
                    let (mut nearest, mut farthest) = (f32::MAX, f32::MIN);
                    for k in 0..8 {
                        let p: [f32; 3] = core::array::from_fn(|i| {
                            let c = if k & (1 << i) == 0 { lo[i] } else { hi[i] };
                            c as f32 / 65536.0 - eye[i]
                        });
                        let z = dot(p, forward);
                        (nearest, farthest) = (nearest.min(z), farthest.max(z));
                        if z > 0.0 {
                            let (c, r) =
                                ((dot(p, right) / z - cr) / rr, (dot(p, down) / z - cd) / dd);
                            (x, y) = ((x.0.min(c), x.1.max(c)), (y.0.min(r), y.1.max(r)));
                        }
                    }
                    if farthest < near {
                        None
                    } else if nearest < near {
                        Some(full)
                    } else {
                        rect_of(x, y)
                    }
                }
            };
            if let Some((x0, x1, y0, y1)) = rect {
                match bounds.get_mut(used) {
                    Some(slot) => {
                        *slot = ScreenBound {
                            object: id as u32,
                            x0,
                            x1,
                            y0,
                            y1,
                        };
                        used += 1;
                    }
                    None => complete = false,
                }
            }
        }
        if let Some(written) = bounds.get_mut(..used) {
            heap_sort_by_key(written, |b| (b.y0, b.object));
        }
        (used, complete)
    }

    /// The columns of row `y` whose primary rays certainly meet convex polygon `object` inside
    /// its outline when they meet its plane (inclusive; `None`: no such column, or not a convex
    /// polygon wholly in front of the eye). The outline seen on screen is convex, so a pixel is
    /// safe when the pixels two columns and two rows away on each side are inside it: those
    /// corners' rays bound the pixel's ray with its rounding (below 2^-14 rad, a hundredth of
    /// a pixel here) by [`MARGIN`] pixels, and the columns are shrunk by one more for the f32
    /// arithmetic. Rows whose hits are so near that two pixels span less than 2^-8 units (the
    /// hit point's own rounding is near 2^-12) get `None`. Only a speed-up: the other columns
    /// take the full test.
    fn inside_columns(&self, object: &Object<'_>, y: u16) -> Option<(u16, u16)> {
        let Shape::Polygon(polygon) = &object.shape else {
            return None;
        };
        if !convex(polygon.vertices, polygon.facet.axis) {
            return None;
        }
        let camera = self.camera();
        let [corner, right, down, eye] = camera.float_basis();
        let dot = |a: [f32; 3], b: [f32; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let cross = |a: [f32; 3], b: [f32; 3]| {
            [
                a[1] * b[2] - a[2] * b[1],
                a[2] * b[0] - a[0] * b[2],
                a[0] * b[1] - a[1] * b[0],
            ]
        };
        let (w, h) = (f32::from(camera.width), f32::from(camera.height));
        let forward: [f32; 3] = core::array::from_fn(|i| {
            corner[i] + (w - 1.0) / 2.0 * right[i] + (h - 1.0) / 2.0 * down[i]
        });
        let (rr, cr) = (dot(right, right), dot(corner, right));
        let near = camera.near.to_num::<f32>() / 2.0;
        let vertex = |v: &Vec3| -> [f32; 3] {
            let b = v.bits();
            core::array::from_fn(|i| b[i] as f32 / 65536.0 - eye[i])
        };
        if polygon
            .vertices
            .iter()
            .any(|v| dot(vertex(v), forward) <= near)
        {
            return None;
        }
        let row = f32::from(y);
        let (mut lo, mut hi) = (f32::MIN, f32::MAX);
        let mut nearest = f32::MAX;
        for r in [row - 2.0, row + 2.0] {
            // The plane through the eye holding the row's rays, and where it crosses the outline.
            let through: [f32; 3] = core::array::from_fn(|i| corner[i] + r * down[i]);
            let n = cross(right, through);
            let mut columns = [0.0f32; 2];
            let mut crossings = 0;
            let last = polygon.vertices.last()?;
            let mut a = vertex(last);
            let mut sa = dot(n, a);
            for v in polygon.vertices {
                let b = vertex(v);
                let sb = dot(n, b);
                if sa == 0.0 || sb == 0.0 {
                    return None;
                }
                if (sa < 0.0) != (sb < 0.0) {
                    let k = sa / (sa - sb);
                    let p: [f32; 3] = core::array::from_fn(|i| a[i] + k * (b[i] - a[i]));
                    let z = dot(p, forward);
                    nearest = nearest.min(z);
                    *columns.get_mut(crossings)? = (dot(p, right) / z - cr) / rr;
                    crossings += 1;
                }
                (a, sa) = (b, sb);
            }
            if crossings != 2 {
                return None;
            }
            let [c0, c1] = columns;
            (lo, hi) = (lo.max(c0.min(c1)), hi.min(c0.max(c1)));
        }
        // Two pixels at the nearest crossing's depth, in world units (a pixel's ray turns by
        // about |right| radians).
        let span = nearest * 2.0 * libm::sqrtf(rr);
        if span.is_nan() || span < 1.0 / 256.0 {
            return None;
        }
        let margin = (MARGIN + 1) as f32;
        let (first, last) = (libm::ceilf(lo + margin), libm::floorf(hi - margin));
        (first <= last && last >= 0.0 && first < w).then(|| {
            // `as` saturates.
            (first.max(0.0) as u16, last.min(w - 1.0) as u16)
        })
    }

    /// Where the first hits of row `y` on `object` can lie, as a box (raw bits, inclusive):
    /// `None` when unbounded, `Some(None)` when nowhere. A planar object's hits lie where the
    /// row's rays meet its plane: when the rays through the corners of the row widened by a pixel
    /// each way all meet the plane in front of the eye, the row's hits lie in the quadrilateral of
    /// those four points, so its box (widened by `PAD`) is clipped to theirs; otherwise, and for
    /// the other objects, it is the padded box. Only a speed-up: a shadow ray from a point
    /// outside the row's region walks the hierarchy ([`RowShadows::for_ray`]).
    fn row_box(&self, object: &Object<'_>, y: u16) -> Option<Option<([i32; 3], [i32; 3])>> {
        let (lo, hi) = padded_box(object)?;
        let Some((normal, offset)) = object.shape.plane() else {
            return Some(Some((lo, hi)));
        };
        let camera = self.camera();
        let [corner, right, down, eye] = camera.float_basis();
        let n = normal.bits().map(|c| c as f32 / 65536.0);
        let dot = |a: [f32; 3], b: [f32; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        // The plane is n·p + offset = 0; along eye + t·dir, t = −(n·eye + offset) / (n·dir).
        let num = -(dot(n, eye) + offset.to_num::<f32>());
        let (row, last) = (f32::from(y), f32::from(camera.width));
        let (mut a, mut b) = ([f32::MAX; 3], [f32::MIN; 3]);
        for (column, row) in [
            (-1.0, row - 1.0),
            (last, row - 1.0),
            (-1.0, row + 1.0),
            (last, row + 1.0),
        ] {
            let dir: [f32; 3] =
                core::array::from_fn(|i| corner[i] + column * right[i] + row * down[i]);
            let t = num / dot(n, dir);
            // Parallel, behind the eye or not finite: the row may see all of the object.
            if !(t > 0.0 && t < 1.0e4) {
                return Some(Some((lo, hi)));
            }
            for i in 0..3 {
                let p = eye[i] + t * dir[i];
                (a[i], b[i]) = (a[i].min(p), b[i].max(p));
            }
        }
        let pad = PAD.to_bits();
        // `as` saturates; a point's rounding is far inside the pixel of widening and the pad.
        let clo: [i32; 3] =
            core::array::from_fn(|i| ((a[i] * 65536.0) as i32).saturating_sub(pad).max(lo[i]));
        let chi: [i32; 3] =
            core::array::from_fn(|i| ((b[i] * 65536.0) as i32).saturating_add(pad).min(hi[i]));
        Some((0..3).all(|i| clo[i] <= chi[i]).then_some((clo, chi)))
    }

    /// Renders the frame in hybrid mode into `row` (length = the camera's width), handing each
    /// row to `sink`: the same rows as [`render`](Self::render). `bounds` holds the screen
    /// bounds (one per visible object), `active` the rectangles spanning a row; rows they cannot
    /// serve fall back to the pure search ([`TraceStats::fallback_rows`]). `shadow` holds a
    /// row's shadow candidates (at most lights × objects entries); rows it cannot hold walk the
    /// hierarchy for their shadow rays ([`TraceStats::shadow_fallback_rows`]).
    pub fn render_hybrid<P: RowPixel, S: RowSink<P>>(
        &self,
        bounds: &mut [ScreenBound],
        active: &mut [ScreenBound],
        shadow: &mut [ShadowCandidate],
        row: &mut [P],
        sink: &mut S,
    ) -> Result<TraceStats, TraceError<S::Error>> {
        if row.len() != usize::from(self.camera().width) {
            return Err(TraceError::RowLength);
        }
        self.hybrid_frame(
            bounds,
            active,
            shadow,
            &mut (row, sink),
            |(row, _), x, p| {
                if let Some(pixel) = row.get_mut(usize::from(x)) {
                    *pixel = P::from_shade(p.colour, p.id.unwrap_or(u32::MAX));
                }
            },
            |(row, sink), y, complete| {
                sink.write_row(Row {
                    y,
                    pixels: row,
                    depth: DepthRow::NONE,
                    complete,
                })
                .map_err(TraceError::Sink)
            },
        )
    }

    /// The hybrid frame, pixel by pixel: `pixel(context, column, trace)` for each pixel of a
    /// row, then `row_done(context, row, complete)` (`complete`: no ray was dropped on the row).
    /// See [`render_hybrid`](Self::render_hybrid) for the buffers.
    pub fn hybrid_frame<C, E>(
        &self,
        bounds: &mut [ScreenBound],
        active: &mut [ScreenBound],
        shadow: &mut [ShadowCandidate],
        context: &mut C,
        mut pixel: impl FnMut(&mut C, u16, &PixelTrace),
        mut row_done: impl FnMut(&mut C, u16, bool) -> Result<(), E>,
    ) -> Result<TraceStats, E> {
        let (used, complete) = self.screen_bounds(bounds);
        let mut scan = Scan {
            bounds: bounds.get(..used).unwrap_or(&[]),
            complete,
            next: 0,
            active,
            live: 0,
        };
        let scene = self.scene();
        let mut cache = ShadowCache::new();
        let mut stats = TraceStats::default();
        // The shadow lists are rebuilt only when the active list changes (`Some(None)`: this
        // row's could not be built).
        let mut lists: Option<Option<RowShadows<'_>>> = None;
        let with_lists = !shadow.is_empty();
        for y in 0..self.camera().height {
            let dropped_before = stats.dropped_rays;
            let mut changed = false;
            let scanned = scan.advance(y, &mut changed);
            let live = scan.active.get(..scan.live).unwrap_or(&[]);
            if !scanned {
                stats.fallback_rows += 1;
                // The lists name the active set they were built for: rebuilt after a fallback.
                lists = None;
            } else if with_lists {
                // The region changes from row to row where a planar object is active.
                let boxes = live.iter().map(|b| {
                    scene
                        .objects
                        .get(b.object as usize)
                        .and_then(|o| self.row_box(o, y))
                });
                let region = row_region(boxes);
                let same = !changed
                    && lists
                        .as_ref()
                        .is_some_and(|l| l.as_ref().map(RowShadows::region) == region);
                if !same {
                    lists = Some(region.and_then(|region| row_shadows(scene, region, shadow)));
                }
            }
            if let Some(Some(l)) = lists.as_mut() {
                // Windows for the first hits on the row's first planar object (the floor, in
                // most scenes).
                let planar = live.iter().find(|b| {
                    scene
                        .objects
                        .get(b.object as usize)
                        .is_some_and(|o| o.shape.plane().is_some())
                });
                l.windows = planar.and_then(|b| {
                    shadow_windows(scene, self.camera(), l, b.object, (b.x0, b.x1), y)
                });
            }
            let row_lists = lists.as_ref().and_then(Option::as_ref);
            // Per active rectangle (the first four), the columns where its object's outline
            // test is known to pass (empty unless a convex polygon's).
            let mut inside = [(1u16, 0u16); 4];
            if scanned {
                for (slot, b) in inside.iter_mut().zip(live) {
                    if let Some(columns) = scene
                        .objects
                        .get(b.object as usize)
                        .and_then(|o| self.inside_columns(o, y))
                    {
                        *slot = columns;
                    }
                }
            }
            if scanned && row_lists.is_none() {
                stats.shadow_fallback_rows += 1;
            }
            let width = self.camera().width;
            let walk = walk_groups(live, width, scanned);
            for x in 0..width {
                if walk.is_some_and(|w| w.get(group(x, width)).copied().unwrap_or(true)) {
                    let p = self.trace_with(
                        x,
                        y,
                        &mut cache,
                        row_lists,
                        &mut stats,
                        |ray, t_min, t_max, stats| self.nearest(ray, u32::MAX, t_min, t_max, stats),
                    );
                    if scanned {
                        stats.walked_primary_rays += 1;
                    }
                    pixel(context, x, &p);
                    continue;
                }
                if !live.iter().any(|b| b.x0 <= x && x <= b.x1) {
                    // No object can be seen here: the background, without the primary ray
                    // (which would have made no test and spawned nothing).
                    stats.primary_rays += 1;
                    pixel(context, x, &self.background_pixel(x, y));
                    continue;
                }
                let p = self.trace_with(
                    x,
                    y,
                    &mut cache,
                    row_lists,
                    &mut stats,
                    |ray, t_min, t_max, stats| {
                        let mut search = Nearest::new(u32::MAX, t_min, t_max);
                        for (i, b) in live.iter().enumerate() {
                            if b.x0 <= x && x <= b.x1 {
                                let (first, last) = inside.get(i).copied().unwrap_or((1, 0));
                                if first <= x && x <= last {
                                    search.offer_inside_outline(scene, b.object, ray);
                                } else {
                                    search.offer(scene, b.object, ray);
                                }
                            }
                        }
                        search.finish(stats)
                    },
                );
                pixel(context, x, &p);
            }
            row_done(context, y, stats.dropped_rays == dropped_before)?;
            stats.rows += 1;
        }
        Ok(stats)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trace::scene::{Colour, Material, Scene, TraceCamera};
    use crate::trace::shape::{Object, Plane, Shape, Sphere};
    use crate::trace::tracer::TraceOptions;
    use fixed::types::I16F16;

    fn v(x: f64, y: f64, z: f64) -> Vec3 {
        let f = I16F16::from_num;
        Vec3 {
            x: f(x),
            y: f(y),
            z: f(z),
        }
    }

    #[test]
    fn screen_bounds_cover_what_is_seen_and_drop_what_is_behind() {
        let sphere = |c: Vec3| Object {
            shape: Shape::Sphere(Sphere::new(c, I16F16::ONE).unwrap()),
            material: 0,
        };
        let objects = [
            sphere(v(0.0, 0.0, 0.0)),  // in front, centred
            sphere(v(0.0, 0.0, 20.0)), // behind the eye
            sphere(v(40.0, 0.0, 0.0)), // off screen to the right
            Object {
                shape: Shape::Plane(Plane::new(v(0.0, 1.0, 0.0), I16F16::from_num(2)).unwrap()),
                material: 0,
            },
        ];
        let grey = Colour::new([I16F16::from_num(0.5); 3]).unwrap();
        let materials = [Material::new(grey, [I16F16::ONE; 4], I16F16::ONE).unwrap()];
        let scene = Scene::new(&objects, &materials, &[], Colour::BLACK, I16F16::ZERO).unwrap();
        let camera = TraceCamera::new(
            [0.0, 0.0, 5.0],
            [0.0; 3],
            [0.0, 1.0, 0.0],
            60.0,
            0.1,
            100.0,
            40,
            30,
        )
        .unwrap();
        let tracer = Tracer::<4>::new(&scene, &camera, TraceOptions::default());
        let mut bounds = [ScreenBound::default(); 4];
        let (used, complete) = tracer.screen_bounds(&mut bounds);
        assert!(complete);
        assert_eq!(used, 2, "{bounds:?}");
        let ball = bounds.iter().find(|b| b.object == 0).unwrap();
        // The unit sphere at distance 5 under a 60° view 30 pixels high spans about 6 rows
        // around the centre (radius · 15 / (5 · tan 30°) ≈ 5.2 pixels each way).
        assert!(
            ball.x0 <= 14 && ball.x1 >= 25 && ball.y0 <= 9 && ball.y1 >= 20,
            "{ball:?}"
        );
        assert!(ball.x0 >= 8 && ball.x1 <= 31, "{ball:?}");
        let plane = bounds.iter().find(|b| b.object == 3).unwrap();
        assert_eq!((plane.x0, plane.x1, plane.y0, plane.y1), (0, 39, 0, 29));
        // Each pixel the pure tracer sees the sphere in lies inside its rectangle.
        for y in 0..30u16 {
            for x in 0..40u16 {
                if tracer.trace_pixel(x, y).0.id == Some(0) {
                    assert!((ball.x0..=ball.x1).contains(&x) && (ball.y0..=ball.y1).contains(&y));
                }
            }
        }
        let mut small = [ScreenBound::default(); 1];
        assert_eq!(tracer.screen_bounds(&mut small), (1, false));
    }

    /// Runs `check` on the classic's floor (one polygon) seen from its camera at 48 × 48.
    fn with_classic_floor(check: impl FnOnce(&Object<'_>, &Tracer<'_, '_, 4>, &TraceCamera)) {
        use crate::trace::shape::Polygon;
        let floor = [
            v(-4.0, 0.0, -4.0),
            v(-4.0, 0.0, 4.0),
            v(4.0, 0.0, 4.0),
            v(4.0, 0.0, -4.0),
        ];
        let objects = [Object {
            shape: Shape::Polygon(Polygon::new(&floor).unwrap()),
            material: 0,
        }];
        let grey = Colour::new([I16F16::from_num(0.5); 3]).unwrap();
        let materials = [Material::new(grey, [I16F16::ONE; 4], I16F16::ONE).unwrap()];
        let scene = Scene::new(&objects, &materials, &[], Colour::BLACK, I16F16::ZERO).unwrap();
        let camera = TraceCamera::classic(48, 48);
        let tracer = Tracer::<4>::new(&scene, &camera, TraceOptions::default());
        check(&objects[0], &tracer, &camera);
    }

    #[test]
    fn a_rows_hits_on_a_polygon_lie_in_its_row_box() {
        with_classic_floor(|floor, tracer, camera| {
            let (lo, hi) = padded_box(floor).unwrap();
            let (mut hits, mut clipped) = (0, 0);
            for y in 0..48u16 {
                let row = tracer.row_box(floor, y).unwrap();
                if row.is_some_and(|(a, b)| b[2] - a[2] < (hi[2] - lo[2]) / 4) {
                    clipped += 1;
                }
                for x in 0..48u16 {
                    let (dir, _) = camera
                        .pixel_direction(x, y)
                        .normalized_with_length()
                        .unwrap();
                    let ray = crate::trace::Ray {
                        origin: camera.eye,
                        dir,
                    };
                    if let Some(t) = floor.shape.hit(&ray, I16F16::ZERO, I16F16::MAX) {
                        let p = ray.origin.along(dir, t).bits();
                        let (a, b) = row.expect("a row with a hit has a box");
                        assert!((0..3).all(|i| a[i] <= p[i] && p[i] <= b[i]), "{x} {y}");
                        hits += 1;
                    }
                }
            }
            // The floor fills the lower rows, each of which sees a narrow band of it.
            assert!(hits > 500 && clipped > 20, "{hits} {clipped}");
        });
    }

    #[test]
    fn known_inside_columns_pass_the_outline_test() {
        with_classic_floor(|floor, tracer, camera| {
            let t_min = I16F16::from_bits(1);
            let (mut known, mut hits) = (0, 0);
            for y in 0..48u16 {
                let columns = tracer.inside_columns(floor, y);
                for x in 0..48u16 {
                    let (dir, _) = camera
                        .pixel_direction(x, y)
                        .normalized_with_length()
                        .unwrap();
                    let ray = crate::trace::Ray {
                        origin: camera.eye,
                        dir,
                    };
                    let full = floor.shape.hit(&ray, t_min, I16F16::MAX);
                    hits += usize::from(full.is_some());
                    if columns.is_some_and(|(first, last)| (first..=last).contains(&x)) {
                        // The plane's t alone is the full test's answer there.
                        let plane = floor.shape.hit_inside_outline(&ray, t_min, I16F16::MAX);
                        assert!(full.is_some() && plane == full, "{x} {y}");
                        known += 1;
                    }
                }
            }
            // Most of the floor's pixels skip the outline test.
            assert!(known * 2 > hits && hits > 500, "{known} of {hits}");
        });
    }

    #[test]
    fn only_convex_outlines_count_as_convex() {
        let square = [
            v(0.0, 0.0, 0.0),
            v(0.0, 0.0, 1.0),
            v(1.0, 0.0, 1.0),
            v(1.0, 0.0, 0.0),
        ];
        assert!(convex(&square, 1));
        // An L: one turn the other way.
        let l = [
            v(0.0, 0.0, 0.0),
            v(0.0, 0.0, 2.0),
            v(2.0, 0.0, 2.0),
            v(2.0, 0.0, 1.0),
            v(1.0, 0.0, 1.0),
            v(1.0, 0.0, 0.0),
        ];
        assert!(!convex(&l, 1));
        // A pentagram turns one way only but winds twice.
        let star: [Vec3; 5] = core::array::from_fn(|i| {
            let a = (i as f64) * 4.0 * core::f64::consts::PI / 5.0;
            v(a.cos(), 0.0, a.sin())
        });
        assert!(!convex(&star, 1));
    }

    #[test]
    fn groups_walk_where_rectangles_pile_up() {
        let rect = |x0, x1| ScreenBound {
            object: 0,
            x0,
            x1,
            y0: 0,
            y1: 0,
        };
        // 160 columns: groups of 10.
        let mut live = [rect(0, 0); MAX_LIVE + 1];
        for (i, b) in live.iter_mut().enumerate().take(usize::from(MAX_COVER) + 1) {
            // Over groups 1 and 2, the last one over group 3 too.
            *b = rect(
                10 + i as u16 % 2,
                25 + 10 * u16::from(i == usize::from(MAX_COVER)),
            );
        }
        let some = usize::from(MAX_COVER) + 1;
        let walk = walk_groups(&live[..some], 160, true).unwrap();
        assert_eq!(walk[..4], [false, true, true, false]);
        assert!(walk[4..].iter().all(|w| !w));
        assert_eq!(walk_groups(&live[..some - 1], 160, true), None);
        // Over the limit in number but spread out: no group walks.
        let spread: [ScreenBound; 20] = core::array::from_fn(|i| rect(8 * i as u16, 8 * i as u16));
        assert_eq!(walk_groups(&spread, 160, true), None);
        assert_eq!(
            walk_groups(&live, 160, true),
            Some([true; GROUPS]),
            "a long row"
        );
        assert_eq!(
            walk_groups(&[], 160, false),
            Some([true; GROUPS]),
            "not scanned"
        );
        assert_eq!(group(159, 160), GROUPS - 1);
    }

    /// A pile of triangles on the left (its groups walk the hierarchy) and a few on the right
    /// (tested from the rectangles), with a light: every pixel of the hybrid frame is the pure
    /// tracer's, and both searches were taken.
    #[test]
    fn hybrid_frame_with_walked_groups_is_the_pure_frame() {
        use crate::trace::bvh::{self, BvhNode};
        use crate::trace::scene::Light;
        use crate::trace::shape::Triangle;
        let triangle = |x: f64, y: f64, z: f64, s: f64| Object {
            shape: Shape::Triangle(
                Triangle::new([v(x, y, z), v(x + s, y, z), v(x, y + s, z + 0.3)]).unwrap(),
            ),
            material: 0,
        };
        let mut objects = [triangle(0.0, 0.0, 0.0, 1.0); 24];
        for (i, o) in objects.iter_mut().enumerate() {
            let k = i as f64;
            *o = if i < 20 {
                // The pile: overlapping, at depths a tenth apart.
                triangle(-2.5 + 0.05 * k, -1.0 + 0.04 * k, -0.1 * k, 1.5)
            } else {
                triangle(0.8 + 0.3 * (k - 20.0), -0.5, 0.5, 0.6)
            };
        }
        let grey = Colour::new([I16F16::from_num(0.5); 3]).unwrap();
        let materials = [Material::new(grey, [I16F16::ONE; 4], I16F16::ONE).unwrap()];
        let lights = [Light::directional(v(0.3, 1.0, 0.6), I16F16::from_num(0.8)).unwrap()];
        let node = BvhNode {
            min: Vec3::ZERO,
            max: Vec3::ZERO,
            index: 0,
            count: 0,
            axis: 0,
        };
        let mut nodes = [node; 48];
        let mut items = [0u32; 24];
        let (n, m, bounded) = bvh::build(&objects, &mut nodes, &mut items).unwrap();
        let scene = Scene::new(
            &objects,
            &materials,
            &lights,
            Colour::BLACK,
            I16F16::ONE / 4,
        )
        .unwrap()
        .with_bvh(&nodes[..n], &items[..m], bounded)
        .unwrap();
        let camera = TraceCamera::new(
            [0.0, 0.0, 5.0],
            [0.0; 3],
            [0.0, 1.0, 0.0],
            60.0,
            0.1,
            100.0,
            48,
            32,
        )
        .unwrap();
        let tracer = Tracer::<4>::new(&scene, &camera, TraceOptions::default());
        let mut bounds = [ScreenBound::default(); 24];
        let mut active = [ScreenBound::default(); 24];
        let mut shadow = [ShadowCandidate::default(); 24];
        let mut pixels = 0;
        let stats = tracer
            .hybrid_frame(
                &mut bounds,
                &mut active,
                &mut shadow,
                &mut pixels,
                |pixels, x, p| {
                    *pixels += 1;
                    let y = (*pixels - 1) / 48;
                    assert_eq!(*p, tracer.trace_pixel(x, y as u16).0, "({x}, {y})");
                },
                |_, _, _| Ok::<(), ()>(()),
            )
            .unwrap();
        assert_eq!(pixels, 48 * 32);
        assert_eq!(stats.fallback_rows, 0);
        assert!(
            stats.walked_primary_rays > 0 && stats.walked_primary_rays < stats.primary_rays / 2,
            "{stats:?}"
        );
    }
}
