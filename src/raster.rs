//! Triangle setup and the exact scanline edge walk.
//!
//! # Rasterization rules
//!
//! * Pixel `(c, r)` is sampled at its centre `(c + ½, r + ½)`; row 0 is the top row.
//! * Fill rule: top-left. A centre exactly on an edge is covered only if that edge is a left edge
//!   or a horizontal top edge. In scanline terms: rows are half-open `[top, bottom)` and each
//!   span is half-open `[left, right)`, where `left` is the first centre at or right of the left
//!   edge and `right` the first centre at or right of the right edge.
//! * Coverage therefore equals the exact edge-function test of the snapped vertices, ties
//!   included: triangles sharing an edge cover every centre along it exactly once.
//!
//! # Exact edge walking
//!
//! Internally coordinates are doubled (`2^-(S+1)` pixel units) so pixel centres, at odd
//! multiples of `2^S`, are integers even with zero sub-pixel bits. An edge is set up with one
//! 32-bit division (its slope as quotient and remainder), pre-stepped to the first centre row
//! below its upper end with comparisons, then walks down one row at a time with that quotient
//! and a remainder (the classic DDA of Bresenham/Pineda, exact rational arithmetic): no drift
//! and no accumulated rounding, whatever the edge's length.
//!
//! # Bit budget
//!
//! Vertices are within ±2^22 sub-pixels ([`crate::project`]), so doubled coordinates are below
//! 2^23 and their differences below 2^24 (i32). Prestep numerators are below 2^49 (i64); the
//! per-row remainder is below `dy < 2^24` and `rem + step < 2^25` (i32). Attribute planes are
//! solved in i128 once per triangle and stepped in i64 (depth) or i32 (colour).

use crate::depth::Depth;
use crate::math::{
    div_below_float, div_rem_u32_soft, floor_div_i64, mul_i64_i32, mul_wide, Divisor32,
    FLOAT_ESTIMATES, NO_HARDWARE_DIVIDE, NO_WIDE_MULTIPLY,
};
use crate::project::ScreenVertex;
use core::cmp::Ordering;
use fixed::types::I16F16;

/// First row (or column) whose centre lies at or after position `p` (doubled units, S bits):
/// `ceil((p − 2^S) / 2^(S+1))`, which is `floor((p + 2^S − 1) / 2^(S+1))`, one shift. In 32
/// bits for `|p| < 2^31 − 2^S`: every doubled vertex coordinate (vertices are within ±2^22
/// sub-pixels, the bit budget above). Test `first_centre_is_the_rounded_up_division`.
#[inline]
fn first_centre_at_or_after<const S: u32>(p_doubled: i32) -> i32 {
    (p_doubled + ((1 << S) - 1)) >> (S + 1)
}

/// One edge, walked down the rows: `x` is the first column whose centre is at or right of the
/// edge on the current row.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EdgeWalk {
    x: i32,
    rem: i32,
    step: i32,
    step_rem: i32,
    dy: i32,
}

impl EdgeWalk {
    /// The edge from `a` to `b` (sub-pixel `(x, y)`, `a.y < b.y`) positioned on `row`.
    /// `None` if the edge is horizontal or upside down.
    pub fn new<const S: u32>(a: (i32, i32), b: (i32, i32), row: i32) -> Option<EdgeWalk> {
        // Doubled differences are below 2^24, so the slope's quotient and remainder take one
        // 32-bit division (a single SDIV; on thumbv6m `floor_div_rem_i32`, by multiplies,
        // which a steep edge skips).
        let dx = 2 * (b.0 - a.0);
        let dy = 2 * (b.1 - a.1);
        if dy <= 0 {
            return None;
        }
        let slope = if NO_HARDWARE_DIVIDE {
            steep_slope(dx, dy)
        } else {
            None
        };
        let (step, step_rem) = match slope {
            Some(s) => s,
            None if NO_HARDWARE_DIVIDE => floor_div_rem_i32(dx, dy),
            None => (dx.div_euclid(dy), dx.rem_euclid(dy)),
        };
        // Edge x at the row centre is ax + t·dx/dy with t = yc − ay.
        let t = (((2 * row as i64) + 1) << S) - 2 * a.1 as i64;
        let placed = if NO_WIDE_MULTIPLY {
            place_narrow::<S>(a.0, t, dx, dy, step, step_rem)
        } else {
            None
        };
        let (x, rem) = match placed {
            Some(p) => p,
            None => place_wide::<S>(a.0, t, dy, step, step_rem),
        };
        Some(EdgeWalk {
            x,
            rem,
            step,
            step_rem,
            dy,
        })
    }

    /// First column whose centre is at or right of the edge on the current row.
    #[inline]
    pub fn column(&self) -> i32 {
        self.x
    }

    /// Moves to the next row.
    #[inline]
    pub fn step(&mut self) {
        self.x = self.x.wrapping_add(self.step);
        self.rem += self.step_rem;
        if self.rem >= self.dy {
            self.rem -= self.dy;
            self.x = self.x.wrapping_add(1);
        }
    }
}

/// The slope `dx / dy` (`dy > 0`) as floor quotient and remainder for a steep edge,
/// `|dx| < dy`, whose quotient is 0 or −1: found by one comparison, without the division
/// (a library call where the core has no divider, [`NO_HARDWARE_DIVIDE`]). `None` for a
/// shallower edge. The same pair as `(dx.div_euclid(dy), dx.rem_euclid(dy))` (test
/// `steep_slope_equals_the_division`).
#[inline]
fn steep_slope(dx: i32, dy: i32) -> Option<(i32, i32)> {
    if dx.unsigned_abs() >= dy.unsigned_abs() {
        None
    } else if dx >= 0 {
        Some((0, dx))
    } else {
        Some((-1, dx + dy))
    }
}

/// `(dx.div_euclid(dy), dx.rem_euclid(dy))` for `dy > 0` by [`div_rem_u32_soft`] on the
/// magnitudes, for the core without a divider ([`NO_HARDWARE_DIVIDE`]). Test
/// `floor_div_rem_i32_equals_the_division`.
#[inline]
fn floor_div_rem_i32(dx: i32, dy: i32) -> (i32, i32) {
    let d = dy.unsigned_abs();
    let (q, r) = div_rem_u32_soft(dx.unsigned_abs(), d);
    if dx >= 0 {
        (q as i32, r as i32)
    } else if r == 0 {
        ((q as i32).wrapping_neg(), 0)
    } else {
        ((q as i32).wrapping_neg().wrapping_sub(1), (d - r) as i32)
    }
}

/// [`EdgeWalk::new`]'s placement on the row `t` (doubled sub-pixels, from `a`'s y to the row's
/// centre) below the edge's upper end `(ax, ·)`, with slope `dx / dy` = `step` + `step_rem / dy`:
/// the first column at or right of the edge and the remainder's high part.
///
/// The first centre `(2c + 1)·2^S` at or right of the edge has c = ceil(num / den), where
/// num = (ax − 2^S)·dy + t·dx and den = dy·2^(S+1). With dx = step·dy + step_rem:
/// num = dy·p + t·step_rem, p = 2·ax − 2^S + t·step. Splitting p = pq·2^(S+1) + pr leaves
/// c = pq + ceil(m' / den) with m' = dy·pr + t·step_rem, and 0 <= m' < 2·den when the row is
/// the first at or below `a` (0 <= t < 2^(S+1)), the case of every triangle walk: the quotient
/// is then 0, 1 or 2, found by comparison instead of a second division. The products fit i64
/// (|t| < 2^34, factors below 2^25); `mul_i64_i32` keeps them off the 64-bit multiply call on
/// ARMv6-M when `t` fits 32 bits, as it does on screen.
#[inline]
fn place_wide<const S: u32>(ax: i32, t: i64, dy: i32, step: i32, step_rem: i32) -> (i32, i32) {
    let p = 2 * ax as i64 - (1i64 << S) + mul_i64_i32(t, step);
    let den = (dy as i64) << (S + 1);
    let m = mul_i64_i32(p & ((1i64 << (S + 1)) - 1), dy) + mul_i64_i32(t, step_rem) + den - 1;
    let (k, r) = if (0..3 * den).contains(&m) {
        // At most two subtractions (no product `k · den`).
        let (mut k, mut r) = (0, m);
        if r >= den {
            r -= den;
            k += 1;
        }
        if r >= den {
            r -= den;
            k += 1;
        }
        (k, r)
    } else {
        (m.div_euclid(den), m.rem_euclid(den))
    };
    (
        ((p >> (S + 1)) + k) as i32,
        // The remainder's low S+1 bits never change while stepping (every increment is a
        // multiple of 2^(S+1)), so only its high part, in [0, dy), is tracked.
        (r >> (S + 1)) as i32,
    )
}

/// [`place_wide`] in 32-bit arithmetic, for the core without a 32 × 32 → 64-bit multiply
/// ([`NO_WIDE_MULTIPLY`], where every `i64` product or comparison is several instructions or
/// a call): `None` unless the row is the first centre row at or below `a`
/// (`0 <= t < 2^(S+1)`) and `|dx|, dy < 2^(28−S)`, `|ax| < 2^28` (every on-screen edge with
/// `S <= 4`). Then `|p| < 2^31` (`|step| <= |dx|`) and `0 <= m' + den − 1 < 3·den < 2^31`,
/// so the same steps in `i32` give the same column and remainder (test
/// `narrow_placement_equals_wide`).
#[inline]
fn place_narrow<const S: u32>(
    ax: i32,
    t: i64,
    dx: i32,
    dy: i32,
    step: i32,
    step_rem: i32,
) -> Option<(i32, i32)> {
    if S > 26 {
        return None;
    }
    let limit = 1u32 << (28 - S);
    let t = i32::try_from(t)
        .ok()
        .filter(|t| (0..1 << (S + 1)).contains(t))?;
    if dx.unsigned_abs() >= limit || dy.unsigned_abs() >= limit || ax.unsigned_abs() >= 1 << 28 {
        return None;
    }
    let p = 2 * ax - (1 << S) + t * step;
    let den = dy << (S + 1);
    let mut r = (p & ((1 << (S + 1)) - 1)) * dy + t * step_rem + den - 1;
    let mut x = p >> (S + 1);
    // 0 <= r < 3·den: at most two subtractions.
    if r >= den {
        r -= den;
        x += 1;
    }
    if r >= den {
        r -= den;
        x += 1;
    }
    Some((x, r >> (S + 1)))
}

/// A triangle being walked row by row: a long edge on one side, two short edges on the other.
#[derive(Clone, Copy, Debug)]
pub struct TriangleWalk {
    /// The left and right edges on the current row: the long edge (top to bottom) on one side,
    /// a short one on the other (kept by side, so a row's span needs no choice).
    left: EdgeWalk,
    right: EdgeWalk,
    /// The lower short edge, set up when the walk reaches `mid_row`.
    lower: [(i32, i32); 2],
    // Rows fit i16: the screen is at most 2048 rows and `mid_row` is clamped to [-1, i16::MAX],
    // which keeps its only use (an equality test while walking from row >= 0) unchanged.
    row: i16,
    mid_row: i16,
    end_row: i16,
    long_is_left: bool,
}

impl TriangleWalk {
    /// Sets up the walk of the triangle `v` (sub-pixel `(x, y)`, any winding) starting at the
    /// first row at or below `min_row`, stopping before `max_row`. `None` if it covers no row
    /// there or has zero area.
    pub fn new<const S: u32>(v: [(i32, i32); 3], min_row: i32, max_row: i32) -> Option<Self> {
        let cross = (v[1].0 as i64 - v[0].0 as i64) * (v[2].1 as i64 - v[0].1 as i64)
            - (v[2].0 as i64 - v[0].0 as i64) * (v[1].1 as i64 - v[0].1 as i64);
        if cross == 0 {
            return None;
        }
        Self::oriented::<S>(v, cross < 0, min_row, max_row)
    }

    /// [`TriangleWalk::new`] for a triangle of non-zero area whose signed area
    /// `(v1 − v0) × (v2 − v0)` (x right, y down) is known to be negative (`negative`) or
    /// positive, as [`PlaneSolver`] finds it: the walk takes its orientation from that sign and
    /// the order its sort puts the vertices in, instead of a cross product of its own. The same
    /// walk (test `oriented_walk_equals_new`).
    #[inline]
    pub fn oriented<const S: u32>(
        v: [(i32, i32); 3],
        negative: bool,
        min_row: i32,
        max_row: i32,
    ) -> Option<Self> {
        let mut o = v;
        // Sort by y (stable three-element network), counting the swaps: an odd permutation
        // flips the sign of the area.
        let mut odd = false;
        if o[1].1 < o[0].1 {
            o.swap(0, 1);
            odd = !odd;
        }
        if o[2].1 < o[1].1 {
            o.swap(1, 2);
            odd = !odd;
        }
        if o[1].1 < o[0].1 {
            o.swap(0, 1);
            odd = !odd;
        }
        let [top, mid, bottom] = o;
        // The long edge (top to bottom) is on the left when `(bottom − top) × (mid − top)`, which
        // is `−(mid − top) × (bottom − top)`, is negative: when the sorted order's area is
        // positive, the original's with the permutation's sign.
        let long_is_left = negative == odd;
        let row_of = |y: i32| first_centre_at_or_after::<S>(2 * y);
        let r0 = row_of(top.1).max(min_row);
        let r1 = row_of(mid.1);
        let r2 = row_of(bottom.1).min(max_row);
        if r0 >= r2 {
            return None;
        }
        // r0, r2 are within [0, max_row] and max_row <= 2048.
        let (r0, r1, r2) = (r0 as i16, r1.clamp(-1, i16::MAX as i32) as i16, r2 as i16);
        let long = EdgeWalk::new::<S>(top, bottom, r0 as i32)?;
        let short = if r0 < r1 {
            EdgeWalk::new::<S>(top, mid, r0 as i32)?
        } else {
            EdgeWalk::new::<S>(mid, bottom, r0 as i32)?
        };
        let (left, right) = if long_is_left {
            (long, short)
        } else {
            (short, long)
        };
        Some(TriangleWalk {
            left,
            right,
            lower: [mid, bottom],
            row: r0,
            mid_row: r1,
            end_row: r2,
            long_is_left,
        })
    }

    /// The row the walk is on.
    #[inline]
    pub fn row(&self) -> i32 {
        self.row as i32
    }

    /// The current row's span `[left, right)` in columns (not clipped to the screen; may be empty).
    #[inline]
    pub fn span(&self) -> (i32, i32) {
        (self.left.column(), self.right.column())
    }

    /// The row after the walk's last row.
    #[inline]
    pub fn end_row(&self) -> i32 {
        self.end_row as i32
    }

    /// Moves to the next row; `false` when the triangle is finished.
    #[inline]
    pub fn advance<const S: u32>(&mut self) -> bool {
        // Compared as i32, so no narrowing or widening of the i16 rows between the steps.
        let row = self.row as i32 + 1;
        self.row = row as i16;
        if row >= self.end_row as i32 {
            return false;
        }
        if row == self.mid_row as i32 {
            let (long, short) = if self.long_is_left {
                (&mut self.left, &mut self.right)
            } else {
                (&mut self.right, &mut self.left)
            };
            long.step();
            match EdgeWalk::new::<S>(self.lower[0], self.lower[1], self.row as i32) {
                Some(e) => *short = e,
                None => {
                    self.row = self.end_row;
                    return false;
                }
            }
        } else {
            self.left.step();
            self.right.step();
        }
        true
    }
}

/// Calls `f(row, x0, x1)` for every non-empty span of triangle `v` inside a `width × height`
/// screen, top to bottom. The same walk the renderer uses, exposed for tests and tools.
///
/// ```
/// use scanline3d::raster::for_each_span;
/// // A right triangle with 4 sub-pixel bits: corners (0,0), (4,0), (0,4) in pixels.
/// let mut spans = Vec::new();
/// for_each_span::<4>([(0, 0), (64, 0), (0, 64)], 8, 8, |r, x0, x1| spans.push((r, x0, x1)));
/// // The hypotenuse is a right edge: centres on it, like (3.5, 0.5), are not covered.
/// assert_eq!(spans, [(0, 0, 3), (1, 0, 2), (2, 0, 1)]);
/// ```
#[cfg_attr(not(feature = "internals"), allow(dead_code))] // used by the tests and tools
pub fn for_each_span<const S: u32>(
    v: [(i32, i32); 3],
    width: i32,
    height: i32,
    mut f: impl FnMut(i32, i32, i32),
) {
    let Some(mut walk) = TriangleWalk::new::<S>(v, 0, height) else {
        return;
    };
    loop {
        let (l, r) = walk.span();
        let (l, r) = (l.max(0), r.min(width));
        if l < r {
            f(walk.row(), l, r);
        }
        if !walk.advance::<S>() {
            break;
        }
    }
}

/// An attribute plane `value + dx·(c − c_ref) + dy·(r − r_ref)` over pixel centres, with
/// fractional bits set by the caller's format (depth: I24F40; colour: I48F16).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Plane {
    value: i64,
    dx: i64,
    dy: i64,
}

/// The pixel whose centre is a triangle's plane reference point: the pixel containing vertex 0,
/// so extrapolation distances, and with them gradient rounding errors, stay small.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelOrigin {
    c: i32,
    r: i32,
}

impl PixelOrigin {
    /// The reference pixel `(c, r)`.
    pub const fn new(c: i32, r: i32) -> Self {
        PixelOrigin { c, r }
    }

    /// Value of `plane` at pixel centre `(c, r)`, wrapping (exact when the true value fits).
    #[inline]
    pub fn at(&self, plane: &Plane, c: i32, r: i32) -> i64 {
        plane
            .value
            .wrapping_add(
                plane
                    .dx
                    .wrapping_mul((c as i64).wrapping_sub(self.c as i64)),
            )
            .wrapping_add(
                plane
                    .dy
                    .wrapping_mul((r as i64).wrapping_sub(self.r as i64)),
            )
    }
}

/// Solves attribute planes over one triangle's snapped vertices (setup only, not stored).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PlaneSolver {
    origin: PixelOrigin,
    /// Doubled-unit offset from vertex 0 to the reference centre (in `(−2^S, 2^S]`), and the
    /// two edge vectors (below 2^24 in magnitude: vertices are within ±2^22 sub-pixels).
    to_ref: (i32, i32),
    e1: (i32, i32),
    e2: (i32, i32),
    /// Twice the doubled-unit area, made positive (`flip` remembers the sign).
    area: i64,
    flip: bool,
    sub_bits: u32,
    /// Every edge component below `2^(20 − S)` doubled units ([`PlaneSolver::plane_bounded`]).
    short_edges: bool,
}

impl PlaneSolver {
    /// Geometry shared by all planes of triangle `v`; `None` for zero area.
    ///
    /// In 32 bits but for the area, as [`EdgeWalk::new`]: the doubled edge vectors fit `i32`
    /// for vertices within the bit budget's ±2^22 sub-pixels (any two within 2^30 of each
    /// other), and their cross product is two 32 × 32 → 64-bit products.
    pub fn new<const S: u32>(v: &[ScreenVertex<S>; 3]) -> Option<Self> {
        let [(x0, y0), (x1, y1), (x2, y2)] = [&v[0], &v[1], &v[2]].map(|s| (s.x.0, s.y.0));
        let e1 = (2 * (x1 - x0), 2 * (y1 - y0));
        let e2 = (2 * (x2 - x0), 2 * (y2 - y0));
        let area = mul_wide(e1.0, e2.1) - mul_wide(e2.0, e1.1);
        if area == 0 {
            return None;
        }
        // The reference centre `(2c + 1)·2^S` minus the doubled `x0 = c·2^S + f`: `2^S − 2f`.
        let to_ref = |p: i32| (1 << S) - 2 * (p & ((1 << S) - 1));
        let short_edges = S <= SHORT_EDGE_BITS
            && (e1.0.unsigned_abs()
                | e1.1.unsigned_abs()
                | e2.0.unsigned_abs()
                | e2.1.unsigned_abs())
                < 1 << (SHORT_EDGE_BITS - S.min(SHORT_EDGE_BITS));
        Some(PlaneSolver {
            origin: PixelOrigin {
                c: x0 >> S,
                r: y0 >> S,
            },
            to_ref: (to_ref(x0), to_ref(y0)),
            e1,
            e2,
            area: area.abs(),
            flip: area < 0,
            sub_bits: S,
            short_edges,
        })
    }

    /// The reference pixel of the planes this solver produces.
    pub fn origin(&self) -> PixelOrigin {
        self.origin
    }

    /// Whether the triangle's signed area `(v1 − v0) × (v2 − v0)` (x right, y down) is
    /// negative (a front face), for [`TriangleWalk::oriented`].
    #[inline]
    pub fn negative(&self) -> bool {
        self.flip
    }

    /// Solves the plane through values `f` at the three vertices (raw bits of any format below
    /// 2^32 in magnitude), returning it with `extra` more fractional bits.
    #[inline]
    pub fn plane(&self, f: [i64; 3], extra: u32) -> Plane {
        let (d1, d2) = (f[1] - f[0], f[2] - f[0]);
        if let Some(p) = self.plane_i64(f[0], d1, d2, extra) {
            return p;
        }
        // Gradient per doubled unit = num / area.
        let (e1, e2) = (self.e1_i64(), self.e2_i64());
        let mut num_x = cross_diff(d1, e2.1, d2, e1.1);
        let mut num_y = cross_diff(d2, e1.0, d1, e2.0);
        if self.flip {
            num_x = -num_x;
            num_y = -num_y;
        }
        // `area` is positive by construction; `max(1)` lets the compiler see that wherever this
        // is not inlined, so no division-by-zero panic path exists (the panic-never check).
        let area = self.area.max(1);
        let div = |n: i128| round_div(n, area);
        let px = 1i128 << (self.sub_bits + 1 + extra); // doubled units per pixel, scaled
        let value = ((f[0] as i128) << extra)
            + div((num_x * self.to_ref.0 as i128 + num_y * self.to_ref.1 as i128) << extra);
        let sat = |v: i128| v.clamp(i64::MIN as i128, i64::MAX as i128) as i64;
        Plane {
            value: value as i64,
            dx: sat(div(num_x * px)),
            dy: sat(div(num_y * px)),
        }
    }
}

impl PlaneSolver {
    /// The edge vectors widened, for the general solvers.
    #[inline]
    fn e1_i64(&self) -> (i64, i64) {
        (self.e1.0 as i64, self.e1.1 as i64)
    }

    #[inline]
    fn e2_i64(&self) -> (i64, i64) {
        (self.e2.0 as i64, self.e2.1 as i64)
    }

    /// [`PlaneSolver::plane`] in 64-bit arithmetic, `None` where an intermediate would not fit
    /// (then the 128-bit path decides). Every step is the 128-bit path's own operation on the
    /// same values, checked instead of widened, so a result is the same plane bit for bit; on
    /// 32-bit cores this skips 128-bit multiplies (`__multi3`) for the ordinary triangle, whose
    /// numerators stay below 2^63.
    #[inline]
    fn plane_i64(&self, f0: i64, d1: i64, d2: i64, extra: u32) -> Option<Plane> {
        if let Some(p) = self.plane_bounded(f0, d1, d2, extra) {
            return Some(p);
        }
        self.plane_checked(f0, d1, d2, extra)
    }

    /// [`PlaneSolver::plane_i64`]'s checked steps, one by one.
    #[inline]
    fn plane_checked(&self, f0: i64, d1: i64, d2: i64, extra: u32) -> Option<Plane> {
        let (e1, e2) = (self.e1_i64(), self.e2_i64());
        let mut num_x = cross_diff_i64(d1, e2.1, d2, e1.1)?;
        let mut num_y = cross_diff_i64(d2, e1.0, d1, e2.0)?;
        if self.flip {
            num_x = -num_x;
            num_y = -num_y;
        }
        let div = RoundDivisor::new(self.area);
        let px = 1i64.checked_shl(self.sub_bits + 1 + extra)?;
        let to_ref = num_x
            .checked_mul(self.to_ref.0 as i64)?
            .checked_add(num_y.checked_mul(self.to_ref.1 as i64)?)?;
        let scale = 1i64.checked_shl(extra)?;
        let value = f0
            .checked_mul(scale)?
            .checked_add(div.round_div(to_ref.checked_mul(scale)?)?)?;
        Some(Plane {
            value,
            dx: div.round_div(num_x.checked_mul(px)?)?,
            dy: div.round_div(num_y.checked_mul(px)?)?,
        })
    }

    /// [`PlaneSolver::plane_checked`] without a check per step, for the triangle whose every
    /// step is known to fit (`None` for any other): edges below `2^(20 − S)` doubled units
    /// (`short_edges`: on a 240-pixel screen with 4 sub-pixel bits, every triangle that
    /// reaches no further than about 2,000 pixels), value differences `|d1|, |d2| < 2^30`
    /// (any two depths in `[0, 2^30]`), `|f0| < 2^32` and `extra <= 10`. The same operations
    /// on the same values, wrapping instead of checked; none wraps, so the plane is the same
    /// to the bit. Why, with `E = 2^(20 − S)`:
    ///
    /// * every factor of the cross products fits 31 bits, so `mul_wide` is exact and
    ///   `|num| <= 2·(2^30 − 1)·(E − 1) < 2^(51 − S) − 2^31`;
    /// * `num · 2^(S + 1 + extra) < 2^62 − 2^(S + 42)` (`extra <= 10`), so twice it plus the
    ///   area (below `2·E² <= 2^41`) fits `i64`;
    /// * the offsets to the reference centre are at most `2^S` (`|t| <= 2^S`), so the value's
    ///   numerator `(num_x·t_x + num_y·t_y) · 2^extra` is no larger than the gradients';
    /// * `f0 · 2^extra < 2^42`, plus a quotient below `2^62`, fits.
    ///
    /// This is [`depth_planes_fit_i64`]'s argument, tested per triangle instead of bounded
    /// for a build. Test `bounded_plane_equals_checked_plane`.
    #[inline]
    fn plane_bounded(&self, f0: i64, d1: i64, d2: i64, extra: u32) -> Option<Plane> {
        const D: u64 = 1 << 30;
        if !(self.short_edges
            && extra <= DEPTH_PLANE_EXTRA_BITS
            && d1.unsigned_abs() < D
            && d2.unsigned_abs() < D
            && f0.unsigned_abs() < 1 << 32)
        {
            return None;
        }
        Some(self.plane_within_bounds(f0, d1 as i32, d2 as i32, extra))
    }

    /// [`PlaneSolver::plane_bounded`] for three non-negative 32-bit values (depths): their
    /// differences are then exact in `i32`, and the bounds are tested there. The same plane.
    #[inline]
    fn plane_bounded_i32(&self, f: [i32; 3], extra: u32) -> Option<Plane> {
        const D: u32 = 1 << 30;
        let [f0, f1, f2] = f;
        // Non-negative: each difference lies in (−2^31, 2^31).
        if (f0 | f1 | f2) < 0 {
            return None;
        }
        let (d1, d2) = (f1 - f0, f2 - f0);
        if !(self.short_edges
            && extra <= DEPTH_PLANE_EXTRA_BITS
            && d1.unsigned_abs() < D
            && d2.unsigned_abs() < D)
        {
            return None;
        }
        Some(self.plane_within_bounds(f0 as i64, d1, d2, extra))
    }

    /// The bounded solver's arithmetic, for the premise [`PlaneSolver::plane_bounded`] tests.
    #[inline(always)]
    fn plane_within_bounds(&self, f0: i64, d1: i32, d2: i32, extra: u32) -> Plane {
        // Factors below 2^30 (the values) and 2^20 (the edges): exact 32 x 32 -> 64 products.
        let cross = |a: i32, b: i32, c: i32, d: i32| mul_wide(a, b).wrapping_sub(mul_wide(c, d));
        let mut num_x = cross(d1, self.e2.1, d2, self.e1.1);
        let mut num_y = cross(d2, self.e1.0, d1, self.e2.0);
        if self.flip {
            num_x = num_x.wrapping_neg();
            num_y = num_y.wrapping_neg();
        }
        let div = RoundDivisor::new(self.area);
        let px = self.sub_bits + 1 + extra;
        // |to_ref| <= 2^S: products by an i32.
        let to_ref =
            mul_i64_i32(num_x, self.to_ref.0).wrapping_add(mul_i64_i32(num_y, self.to_ref.1));
        Plane {
            value: f0
                .wrapping_shl(extra)
                .wrapping_add(div.round_div_bounded(to_ref.wrapping_shl(extra))),
            dx: div.round_div_bounded(num_x.wrapping_shl(px)),
            dy: div.round_div_bounded(num_y.wrapping_shl(px)),
        }
    }
}

/// [`round_div_i64`] by one divisor `d` several times (a plane's three quotients by its
/// triangle's area): where `2d` fits 32 bits, each quotient by a [`PlaneDivisor`] instead of
/// a 64 / 32-bit division. The same quotients (test `round_divisor_equals_round_div`).
#[derive(Clone, Copy, Debug)]
struct RoundDivisor {
    d: i64,
    by: Option<PlaneDivisor>,
}

impl RoundDivisor {
    /// The divisor `d` (`d < 1` is taken as 1).
    #[inline]
    fn new(d: i64) -> Self {
        let d = d.max(1);
        let by = d
            .checked_mul(2)
            .and_then(|d2| u32::try_from(d2).ok())
            .map(<PlaneDivisor as FloorDivisor>::new);
        RoundDivisor { d, by }
    }

    /// `round_div_i64(n, d)`. Always inlined: as a call it measured slower on thumbv6m and
    /// thumbv7em (docs/speed.md, item 10).
    #[inline(always)]
    fn round_div(&self, n: i64) -> Option<i64> {
        match self.by {
            Some(by) => Some(FloorDivisor::floor_div(
                &by,
                n.checked_mul(2)?.checked_add(self.d)?,
            )),
            None => round_div_i64(n, self.d),
        }
    }

    /// [`RoundDivisor::round_div`] for `|2·n| + d < 2^63` (then nothing is checked: nothing
    /// overflows, and the quotient is the same).
    #[inline(always)]
    fn round_div_bounded(&self, n: i64) -> i64 {
        let num = n.wrapping_mul(2).wrapping_add(self.d);
        match self.by {
            Some(by) => FloorDivisor::floor_div(&by, num),
            None => floor_div_i64(num, self.d.wrapping_mul(2)),
        }
    }
}

/// Floored division of 64-bit numerators by one 32-bit divisor.
trait FloorDivisor: Copy + core::fmt::Debug {
    /// The divisor `d` (at least 1).
    fn new(d: u32) -> Self;
    /// `num.div_euclid(d)`.
    fn floor_div(&self, num: i64) -> i64;
}

impl FloorDivisor for Divisor32 {
    #[inline]
    fn new(d: u32) -> Self {
        Divisor32::new(d)
    }
    #[inline(always)]
    fn floor_div(&self, num: i64) -> i64 {
        Divisor32::floor_div(self, num)
    }
}

/// The divisor itself, for quotients from an `f32` estimate ([`floor_div_by_float`]), and the
/// general division where that gives up: no reciprocal to make.
#[derive(Clone, Copy, Debug)]
#[allow(dead_code)] // (outside the tests, only FPU cores use it)
struct FloatDivisor(u32);

impl FloorDivisor for FloatDivisor {
    #[inline]
    fn new(d: u32) -> Self {
        FloatDivisor(d)
    }
    #[inline]
    fn floor_div(&self, num: i64) -> i64 {
        floor_div_by_float(num, self.0).unwrap_or_else(|| floor_div_i64(num, i64::from(self.0)))
    }
}

/// [`FloatDivisor`] on cores with an FPU ([`FLOAT_ESTIMATES`]: a conversion or division of
/// `f32` is one instruction there), the reciprocal ([`Divisor32`]) elsewhere.
type PlaneDivisor = <Pick<FLOAT_ESTIMATES> as PickDivisor>::Divisor;

/// Chooses [`PlaneDivisor`] and [`WalkDepth`] by a constant.
pub(crate) struct Pick<const B: bool>;

trait PickDivisor {
    type Divisor: FloorDivisor;
}

impl PickDivisor for Pick<true> {
    type Divisor = FloatDivisor;
}

impl PickDivisor for Pick<false> {
    type Divisor = Divisor32;
}

/// `⌊num / d⌋` from an `f32` estimate ([`div_below_float`]) where the quotient's magnitude
/// fits 32 bits, `None` elsewhere and where the estimate gives up (the caller then divides in
/// integers): a negative `num`'s floor is minus the ceiling of `|num| / d`, the floor of
/// `(|num| + d − 1) / d`. (A quotient beyond 32 bits, a sliver's steep gradient, is a few in a
/// hundred: a high word's division here as well measured slower than the fallback.) Test
/// `float_floor_division_is_floor_div`.
#[inline(always)]
fn floor_div_by_float(num: i64, d: u32) -> Option<i64> {
    let magnitude = num.unsigned_abs();
    let rounded_up = match num < 0 {
        true => magnitude.checked_add(u64::from(d.checked_sub(1)?))?,
        false => magnitude,
    };
    if (rounded_up >> 32) as u32 >= d {
        return None;
    }
    let q = i64::from(div_below_float(rounded_up, d)?);
    Some(if num < 0 { -q } else { q })
}

/// [`cross_diff`] where every factor fits 31 bits (`None` otherwise): exact in 64 bits.
#[inline]
fn cross_diff_i64(a: i64, b: i64, c: i64, d: i64) -> Option<i64> {
    const LIMIT: u64 = 1 << 30;
    let small = |v: i64| v.unsigned_abs() < LIMIT;
    (small(a) && small(b) && small(c) && small(d))
        .then(|| mul_wide(a as i32, b as i32) - mul_wide(c as i32, d as i32))
}

/// [`round_div`] in 64 bits, `None` if `2·n + d` does not fit (`d >= 1`).
#[inline]
fn round_div_i64(n: i64, d: i64) -> Option<i64> {
    let d = d.max(1);
    Some(floor_div_i64(
        n.checked_mul(2)?.checked_add(d)?,
        d.checked_mul(2)?,
    ))
}

/// `a·b − c·d`, exactly. When every factor fits 31 bits the products and their difference fit
/// 63, and 64-bit multiplies give the same result as 128-bit ones, much cheaper on 32-bit cores.
#[inline]
fn cross_diff(a: i64, b: i64, c: i64, d: i64) -> i128 {
    match cross_diff_i64(a, b, c, d) {
        Some(v) => v as i128,
        None => a as i128 * b as i128 - c as i128 * d as i128,
    }
}

/// `n / d` rounded to nearest (halves up), for `d >= 1`.
///
/// The numerators of small and medium triangles fit 63 bits, and then a 64-bit division gives
/// the same quotient as a 128-bit one at a fraction of the cost on cores without a 64-bit
/// divider (Cortex-M0: `__aeabi_ldivmod` instead of `__divti3`).
#[inline]
fn round_div(n: i128, d: i64) -> i128 {
    let d = d.max(1);
    let (num, den) = (2 * n + d as i128, 2 * d as i128);
    if let (Ok(num), Ok(den)) = (i64::try_from(num), i64::try_from(den)) {
        return floor_div_i64(num, den) as i128;
    }
    num.div_euclid(den.max(1))
}

/// Whether the depth plane of every triangle drawn on a screen at most `max_side` pixels wide
/// and high with `sub_bits` sub-pixel bits solves in 64 bits ([`DepthPlane::new_i64`]), when
/// its vertices are inside every clip plane and projected with the exact division.
///
/// Why, with `S = sub_bits`, `M = max_side` and `E = 16·M·2^S + 2`, when `E <= 2^(20−S) − 1`
/// (for `S = 4`: `M <= 255`):
///
/// * Inside the guard band a vertex is at most `4·W·2^S` sub-pixels from the screen centre (`W`
///   the width, at most `M`; likewise in y), and its rounded position stays there, so an edge in
///   doubled units is at most `16·M·2^S` (+2 covers an odd size without sub-pixels): `|e| <= E`.
/// * Inside the near and far planes `near <= w <= far`, so the exact depth `⌊near·2^30 / w⌋`
///   lies in `[1, 2^30]` (`far` is within `2^14` units, `near` at least one bit): the
///   differences `d` of the three depths are below 2^30. Every factor of the two cross
///   products is below 2^30, so [`cross_diff_i64`] takes them, and `|num| <= 2·d·E <
///   2^(51 − S)`.
/// * The gradient numerators are `num · 2^(S + 1 + 10)`, below `2^62 − 2^(S+42)`, so twice one
///   plus the area (below `2·E² < 2^41`) fits `i64`; the value's numerator `(num_x·t_x +
///   num_y·t_y) · 2^10`, with the offsets `|t| <= 2^S` to the reference centre, is no larger;
///   the start value `f0 · 2^10 < 2^41` plus a quotient below 2^62 fits too.
///
/// Every checked step of [`PlaneSolver::plane_i64`] therefore succeeds. Test
/// `bounded_depth_planes_solve_in_64_bits`.
pub(crate) const fn depth_planes_fit_i64(max_side: usize, sub_bits: u32) -> bool {
    if sub_bits > crate::project::MAX_SUB_PIXEL_BITS || max_side > crate::project::MAX_SCREEN {
        return false;
    }
    ((16 * max_side) << sub_bits) + 2 < 1 << (20 - sub_bits)
}

/// The depth plane: `q` in I24F40 (40 fractional bits, 10 more than [`Depth`]).
#[derive(Clone, Copy, Debug)]
pub struct DepthPlane {
    origin: PixelOrigin,
    q: Plane,
}

/// Extra fractional bits of the depth plane over [`Depth`].
const DEPTH_PLANE_EXTRA_BITS: u32 = 10;

/// A depth plane's value in [`Depth`] bits, clamped to `[0, i32::MAX]`:
/// `(q >> DEPTH_PLANE_EXTRA_BITS).clamp(0, i32::MAX)`, with the usual case (the value already in
/// range: its high word below `2^(DEPTH_PLANE_EXTRA_BITS − 1)`) tested on one word.
#[inline(always)]
fn clamped_depth(q: i64) -> i32 {
    if (q >> 32) as i32 >> (DEPTH_PLANE_EXTRA_BITS - 1) == 0 {
        (q >> DEPTH_PLANE_EXTRA_BITS) as i32
    } else if q < 0 {
        0
    } else {
        i32::MAX
    }
}

/// `S +` the bits of an edge (doubled units) that [`PlaneSolver::plane_bounded`] takes.
const SHORT_EDGE_BITS: u32 = 20;

impl DepthPlane {
    /// Depth plane of triangle `v`; `None` for zero area.
    pub fn new<const S: u32>(solver: &PlaneSolver, v: &[ScreenVertex<S>; 3]) -> Self {
        let f = v.each_ref().map(|s| s.q.to_bits());
        // Depths are non-negative 32-bit values: the bounded solver's premise tested in 32 bits.
        let q = match solver.plane_bounded_i32(f, DEPTH_PLANE_EXTRA_BITS) {
            Some(q) => q,
            None => solver.plane(f.map(i64::from), DEPTH_PLANE_EXTRA_BITS),
        };
        DepthPlane {
            origin: solver.origin(),
            q,
        }
    }

    /// [`DepthPlane::new`] from the 64-bit solver alone ([`PlaneSolver::plane_bounded`]), for a
    /// triangle whose three vertices are inside every clip plane and were projected with the
    /// exact division, on a screen for which [`depth_planes_fit_i64`] holds: there the 64-bit
    /// solver never gives up (proof at [`depth_planes_fit_i64`]), so this is the same plane
    /// and builds that only draw such triangles (`NoClip`, the exact projection, a small
    /// screen) carry no 128-bit arithmetic. Test `bounded_depth_planes_solve_in_64_bits`.
    #[inline]
    pub(crate) fn new_i64<const S: u32>(solver: &PlaneSolver, v: &[ScreenVertex<S>; 3]) -> Self {
        let f = v.each_ref().map(|s| s.q.to_bits() as i64);
        // Edges below `16·max(W, H)·2^S + 2 < 2^(20−S)` and depths in `[1, 2^30]`: the
        // bounded solver's premise, so its checked steps stay out of the build.
        let q = solver
            .plane_bounded(f[0], f[1] - f[0], f[2] - f[0], DEPTH_PLANE_EXTRA_BITS)
            .unwrap_or_else(|| {
                debug_assert!(
                    false,
                    "internal error: a bounded depth plane needs 128 bits"
                );
                Plane {
                    value: 0,
                    dx: 0,
                    dy: 0,
                }
            });
        DepthPlane {
            origin: solver.origin(),
            q,
        }
    }

    /// The plane walked down the rows from row `r` ([`WalkDepth`]).
    #[inline]
    pub(crate) fn walk_from<W: DepthWalk>(&self, r: i32) -> W {
        // `row_q = value − dx·c_ref + dy·(r − r_ref)`, wrapping (mod 2^64) as
        // `PixelOrigin::at` does, so `row_q + dx·c` is its value at `(c, r)` to the bit.
        W::new(self.origin.at(&self.q, 0, r), &self.q)
    }

    /// The per-pixel step of [`DepthPlane::span_start`] (the same on every row).
    #[inline]
    pub fn step(&self) -> i32 {
        depth_step(&self.q)
    }

    /// Start value and per-pixel step, in [`Depth`] bits, for the span starting at `(c, r)`.
    ///
    /// The start is clamped to `[0, i32::MAX]`; the step saturates at ±2^31, which only happens
    /// for triangles too thin to hold two centres in a row, where the step is never used.
    #[inline]
    pub fn span_start(&self, c: i32, r: i32) -> (i32, i32) {
        (
            clamped_depth(self.origin.at(&self.q, c, r)),
            depth_step(&self.q),
        )
    }

    /// Depth at pixel centre `(c, r)` in I2F30, unclamped (for tests).
    #[cfg_attr(not(feature = "internals"), allow(dead_code))] // used by the tests and tools
    pub fn depth_at(&self, c: i32, r: i32) -> Depth {
        let q = self.origin.at(&self.q, c, r) >> DEPTH_PLANE_EXTRA_BITS;
        Depth::from_bits(q.clamp(i32::MIN as i64, i32::MAX as i64) as i32)
    }
}

/// The per-pixel step of depth plane `q` in [`Depth`] bits, saturated at ±2^31.
#[inline]
fn depth_step(q: &Plane) -> i32 {
    // In range (`dx >> 10` fits `i32`) exactly when `dx`'s top 64 − 41 bits are all its sign,
    // which the high word alone shows: one test of one word, as `clamped_depth` does.
    let high = (q.dx >> 32) as i32;
    if high >> (41 - 32) == high >> 31 {
        (q.dx >> DEPTH_PLANE_EXTRA_BITS) as i32
    } else if high < 0 {
        i32::MIN
    } else {
        i32::MAX
    }
}

/// A [`DepthPlane`] walked down a triangle's rows, its value kept at column 0 of the walk's
/// current row so that a span's start takes one product instead of two: [`SplitWalk`] on
/// Arm, [`WideWalk`] elsewhere (on RISC-V the split form measured slower: `cargo xtask
/// profile`, docs/speed.md item 31). The same start either way.
pub(crate) type WalkDepth = <Pick<{ cfg!(target_arch = "arm") }> as PickWalk>::Walk;

/// Chooses [`WalkDepth`] by a constant.
pub(crate) trait PickWalk {
    type Walk: DepthWalk;
}

impl PickWalk for Pick<true> {
    type Walk = SplitWalk;
}

impl PickWalk for Pick<false> {
    type Walk = WideWalk;
}

/// A depth plane walked down the rows ([`WalkDepth`]).
pub(crate) trait DepthWalk: Copy + core::fmt::Debug {
    /// The walk of plane `q` from a row where it is `value` at column 0.
    fn new(value: i64, q: &Plane) -> Self;
    /// Moves one row down.
    fn next_row(&mut self);
    /// [`DepthPlane::span_start`]'s start for the span starting at column `c` (on the screen:
    /// `0 ≤ c < 2^12`) of the current row, at a centre the triangle covers.
    fn span_start(&self, c: i32) -> i32;
}

/// The plane in 64-bit words: `value` at column 0 of the current row.
#[derive(Clone, Copy, Debug)]
pub(crate) struct WideWalk {
    q: Plane,
}

impl DepthWalk for WideWalk {
    #[inline]
    fn new(value: i64, q: &Plane) -> Self {
        WideWalk {
            q: Plane { value, ..*q },
        }
    }

    #[inline]
    fn next_row(&mut self) {
        self.q.value = self.q.value.wrapping_add(self.q.dy);
    }

    #[inline]
    fn span_start(&self, c: i32) -> i32 {
        clamped_depth(self.q.value.wrapping_add(self.q.dx.wrapping_mul(c as i64)))
    }
}

/// The largest vertex depth of a drawn triangle, in [`Depth`] bits: a drawn vertex has
/// `w ≥ near` (inside the near plane), or the clipper made it on the near plane with its `w`
/// rounded to within half an I16F16 unit of `near`; `near` is at least
/// [`MIN_NEAR`](crate::scene::MIN_NEAR) = 256 units, so `q = near · 2^30 / w ≤ 2^30 · 256 /
/// 255 < 2^30 + 2^23`.
pub(crate) const MAX_DRAWN_DEPTH: i32 = (1 << 30) + (1 << 23);

/// The plane's value and column step in 32-bit words, split at its extra bits: `value = hi ·
/// 2^10 + lo`, `dx = dx_hi · 2^10 + dx_lo` (`0 ≤ dx_lo, dy_lo < 2^10`; the high words modulo
/// 2^32, `lo` not carried into `hi` as the rows add `dy_lo`, so after at most 2^12 rows it is
/// below 2^22). Then `⌊(value + dx·c) / 2^10⌋ = hi + dx_hi·c + ⌊(lo + dx_lo·c) / 2^10⌋`, of
/// which 32-bit arithmetic keeps the value modulo 2^32: the depth itself wherever that lies in
/// `[−2^31, 2^31)`. At a span's first pixel, a covered centre, it does: there the plane is
/// within the triangle's vertex depths (`0 ..= MAX_DRAWN_DEPTH`) up to its rounding, a few
/// units. So the start is [`WideWalk`]'s to the bit (tests
/// `walked_span_start_equals_span_start`, `walked_span_start_is_exact_at_covered_centres`)
/// from two 32-bit multiplies instead of a 64-bit product (on ARMv6-M, three multiplies and
/// their carries).
#[derive(Clone, Copy, Debug)]
pub(crate) struct SplitWalk {
    hi: i32,
    lo: u32,
    dx_hi: i32,
    dx_lo: u32,
    dy_hi: i32,
    dy_lo: u32,
}

/// `v` split at the depth plane's extra bits: `(⌊v / 2^10⌋ mod 2^32, v mod 2^10)`.
#[inline]
fn split_extra_bits(v: i64) -> (i32, u32) {
    (
        (v >> DEPTH_PLANE_EXTRA_BITS) as i32,
        (v & ((1 << DEPTH_PLANE_EXTRA_BITS) - 1)) as u32,
    )
}

impl DepthWalk for SplitWalk {
    #[inline]
    fn new(value: i64, q: &Plane) -> Self {
        let ((hi, lo), (dx_hi, dx_lo), (dy_hi, dy_lo)) = (
            split_extra_bits(value),
            split_extra_bits(q.dx),
            split_extra_bits(q.dy),
        );
        SplitWalk {
            hi,
            lo,
            dx_hi,
            dx_lo,
            dy_hi,
            dy_lo,
        }
    }

    #[inline]
    fn next_row(&mut self) {
        self.hi = self.hi.wrapping_add(self.dy_hi);
        self.lo = self.lo.wrapping_add(self.dy_lo);
    }

    #[inline]
    fn span_start(&self, c: i32) -> i32 {
        debug_assert!(
            (0..1 << 12).contains(&c),
            "internal error: span start {c} off the screen"
        );
        let fraction = self.lo.wrapping_add(self.dx_lo.wrapping_mul(c as u32));
        let q = self
            .hi
            .wrapping_add(self.dx_hi.wrapping_mul(c))
            .wrapping_add((fraction >> DEPTH_PLANE_EXTRA_BITS) as i32);
        // (`clamped_depth` of the value in range: only the rounding below a zero vertex
        // depth takes a covered centre out of `[0, i32::MAX]`.)
        q.max(0)
    }
}

/// Three colour-channel planes for Gouraud shading, in I16F16 (channel 0–255 plus fraction).
#[derive(Clone, Copy, Debug)]
pub struct ColorPlanes {
    value: [i32; 3],
    dx: [i32; 3],
    dy: [i32; 3],
}

impl ColorPlanes {
    /// Colour planes of triangle `v` over the geometry `origin`.
    pub fn new<const S: u32>(solver: &PlaneSolver, v: &[ScreenVertex<S>; 3]) -> Self {
        let mut out = ColorPlanes {
            value: [0; 3],
            dx: [0; 3],
            dy: [0; 3],
        };
        for k in 0..3 {
            let p = solver.plane(v.each_ref().map(|s| s.color[k].to_bits() as i64), 0);
            // Channels are within 0..=255 (2^24 bits); a gradient that does not fit i32 belongs
            // to a triangle too thin to hold two centres in a row, so saturation is harmless.
            let sat = |x: i64| x.clamp(i32::MIN as i64, i32::MAX as i64) as i32;
            out.value[k] = sat(p.value);
            out.dx[k] = sat(p.dx);
            out.dy[k] = sat(p.dy);
        }
        out
    }

    /// Channel values (I16F16 bits) at pixel centre `(c, r)` and their per-pixel steps.
    #[inline]
    pub fn span_start(&self, origin: &PixelOrigin, c: i32, r: i32) -> ([i32; 3], [i32; 3]) {
        let mut v = [0i32; 3];
        for (k, out) in v.iter_mut().enumerate() {
            let p = Plane {
                value: self.value[k] as i64,
                dx: self.dx[k] as i64,
                dy: self.dy[k] as i64,
            };
            *out = origin.at(&p, c, r).clamp(0, 255 << 16) as i32;
        }
        (v, self.dx)
    }
}

/// Perspective-correct colour planes (rational linear interpolation): each channel `c`
/// weighted by `r = q / q_max` (`q = near / w` of the vertex, `q_max` the triangle's largest),
/// and `r` itself. Both `c·r` and `r` are linear in screen space, so the channel at a pixel is
/// their quotient, exact up to rounding however steeply the triangle recedes.
///
/// Bit budget: channels enter as I8F4 (`c·2^4 < 2^12`), `r` as an integer `1..=2^15`, so
/// `c·r` with 4 more fractional bits in its plane stays below 2^31 inside the triangle; the `r`
/// plane carries 8 fractional bits (below 2^24). Planes are stepped in `i64`: a sliver's
/// gradient may be far larger than the values themselves. A quotient divides `c·r·2^8` by
/// `r·2^4` (the `r` plane's low 4 bits dropped) in 32 bits: the channel with 4 fractional bits,
/// relative error below `2^-4 / r`, under 2^-14 unless a triangle spans a depth ratio beyond
/// 2^10.
#[derive(Clone, Copy, Debug)]
pub struct PerspectivePlanes {
    /// `[c₀·r, c₁·r, c₂·r, r]`.
    planes: [Plane; 4],
}

/// Bits of the vertex weight `r = q / q_max`.
const WEIGHT_BITS: u32 = 15;

impl PerspectivePlanes {
    /// Perspective planes of triangle `v` over the geometry of `solver`.
    pub fn new<const S: u32>(solver: &PlaneSolver, v: &[ScreenVertex<S>; 3]) -> Self {
        let q = v.each_ref().map(|s| s.q.to_bits().max(0) as i64);
        let q_max = q[0].max(q[1]).max(q[2]).max(1);
        let r = q.map(|q| ((q << WEIGHT_BITS) / q_max).max(1));
        let weighted = |k: usize| {
            core::array::from_fn(|j| {
                let c = (v[j].color[k].to_bits() >> 12).clamp(0, 255 << 4) as i64;
                c * r[j]
            })
        };
        PerspectivePlanes {
            planes: [
                solver.plane(weighted(0), 4),
                solver.plane(weighted(1), 4),
                solver.plane(weighted(2), 4),
                solver.plane(r, 8),
            ],
        }
    }

    /// `[c₀·r, c₁·r, c₂·r, r]` at pixel centre `(c, r)` and their per-pixel steps.
    #[inline]
    pub fn span_start(&self, origin: &PixelOrigin, c: i32, r: i32) -> ([i64; 4], [i64; 4]) {
        (
            self.planes.each_ref().map(|p| origin.at(p, c, r)),
            self.planes.each_ref().map(|p| p.dx),
        )
    }

    /// The channels (I16F16 bits, clamped to 0..=255) of stepped values `v`.
    #[inline]
    pub fn colour(v: &[i64; 4]) -> [i32; 3] {
        let den = (v[3] >> 4).clamp(1, u32::MAX as i64) as u32;
        core::array::from_fn(|k| {
            let c = v[k].clamp(0, u32::MAX as i64) as u32 / den;
            (c.min(255 << 4) as i32) << 12
        })
    }
}

/// Converts an I16F16 channel value to a byte, clamped.
#[inline]
pub fn channel(v: i32) -> u8 {
    (v >> 16).clamp(0, 255) as u8
}

/// `I16F16` colour channels from a byte colour.
pub fn color_channels(c: embedded_graphics::pixelcolor::Rgb888) -> [I16F16; 3] {
    use embedded_graphics::pixelcolor::RgbColor;
    [c.r(), c.g(), c.b()].map(I16F16::from_num)
}

/// Sub-pixel `(x, y)` of a screen vertex.
#[inline]
pub fn xy<const S: u32>(v: &ScreenVertex<S>) -> (i32, i32) {
    (v.x.0, v.y.0)
}

/// Signed doubled area of a screen triangle (y down): negative for front faces (counter-clockwise
/// in the world as seen by the camera).
#[inline]
pub fn signed_area<const S: u32>(v: &[ScreenVertex<S>; 3]) -> i64 {
    signed_area_xy(&v.each_ref().map(xy))
}

/// [`signed_area`] of the sub-pixel positions `(x, y)` of a triangle's vertices.
#[inline]
pub fn signed_area_xy(v: &[(i32, i32); 3]) -> i64 {
    if NO_WIDE_MULTIPLY {
        if let Some(area) = signed_area_in_words(v) {
            return area;
        }
    }
    let [a, b, c] = *v;
    (b.0 as i64 - a.0 as i64) * (c.1 as i64 - a.1 as i64)
        - (c.0 as i64 - a.0 as i64) * (b.1 as i64 - a.1 as i64)
}

/// [`signed_area_xy`] from 32 × 32 → 64-bit products when the edges' differences fit 32 bits
/// (every triangle near the screen), for the core without a wide multiply, where each `i64`
/// product is a call; `None` otherwise. The same value (test `area_in_words_is_the_area`): each
/// product is at most 2^62, their difference below 2^63.
#[inline]
fn signed_area_in_words(v: &[(i32, i32); 3]) -> Option<i64> {
    let [a, b, c] = *v;
    let e1 = (b.0.checked_sub(a.0)?, b.1.checked_sub(a.1)?);
    let e2 = (c.0.checked_sub(a.0)?, c.1.checked_sub(a.1)?);
    Some(mul_wide(e1.0, e2.1) - mul_wide(e2.0, e1.1))
}

/// A value with the sign of [`signed_area_xy`] (negative for a front face, positive for a
/// back face, zero for zero area): the area itself, or on the core without a wide multiply
/// −1, 0 or 1 from [`short_area_sign`] where it answers.
#[inline]
pub fn area_sign(v: &[(i32, i32); 3]) -> i64 {
    if NO_WIDE_MULTIPLY {
        if let Some(sign) = short_area_sign(v) {
            return sign as i64;
        }
    }
    signed_area_xy(v)
}

/// The sign of [`signed_area_xy`] for a triangle whose edges' four differences fit `i16`
/// (every triangle of on-screen positions with up to 2^11 columns and rows at 4 sub-pixel
/// bits), `None` for others: two 32-bit products, each at most 2^30 in magnitude, compared,
/// where [`signed_area_xy`] makes two 64-bit ones (four multiplies each on ARMv6-M). Test
/// `short_area_sign_is_the_areas_sign`.
#[inline]
fn short_area_sign(v: &[(i32, i32); 3]) -> Option<Ordering> {
    let [a, b, c] = *v;
    let d = [
        b.0.wrapping_sub(a.0),
        b.1.wrapping_sub(a.1),
        c.0.wrapping_sub(a.0),
        c.1.wrapping_sub(a.1),
    ];
    // A difference in [−2^15, 2^15) is below 2^16 once offset by 2^15 (a wrapped one is not).
    let offset = d
        .iter()
        .fold(0u32, |acc, &x| acc | x.wrapping_add(1 << 15) as u32);
    (offset < 1 << 16).then(|| (d[0] * d[3]).cmp(&(d[2] * d[1])))
}

/// The first row a triangle's walk would cover on a `width × height` screen, or `None` when
/// its bounding box holds no pixel centre of the screen (by the same half-open rules as the
/// walk, so nothing the walk would draw is rejected). Used by bucketing.
pub fn first_row<const S: u32>(v: &[ScreenVertex<S>; 3], width: i32, height: i32) -> Option<i32> {
    first_row_xy::<S>(&v.each_ref().map(xy), width, height)
}

/// [`first_row`] of the sub-pixel positions `(x, y)` of a triangle's vertices.
#[inline]
pub fn first_row_xy<const S: u32>(v: &[(i32, i32); 3], width: i32, height: i32) -> Option<i32> {
    let range = |k: fn(&(i32, i32)) -> i32, limit: i32| {
        let (lo, hi) = v
            .iter()
            .map(k)
            .fold((i32::MAX, i32::MIN), |(l, h), x| (l.min(x), h.max(x)));
        let first = first_centre_at_or_after::<S>(2 * lo).max(0);
        let end = first_centre_at_or_after::<S>(2 * hi).min(limit);
        (first < end).then_some(first)
    };
    range(|p| p.0, width)?;
    range(|p| p.1, height)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 64-bit fast paths give exactly the 128-bit results, on both sides of their limits.
    #[test]
    fn fast_paths_equal_wide_arithmetic() {
        let wide_div = |n: i128, d: i64| (2 * n + d as i128).div_euclid(2 * d as i128);
        let edges = [
            0i128,
            1,
            -1,
            i64::MAX as i128 / 2 - 1,
            i64::MAX as i128 / 2,
            i64::MAX as i128 / 2 + 1,
            i64::MIN as i128 / 2,
            i64::MIN as i128 / 2 - 1,
            i64::MAX as i128,
            (i64::MAX as i128) << 3,
            -(1i128 << 100),
        ];
        let dens = [
            1i64,
            2,
            3,
            7,
            1 << 20,
            (1 << 40) + 1,
            i64::MAX / 2,
            i64::MAX / 2 + 1,
        ];
        let mut rng = crate::test_rng::XorShift64::new(0x9E37_79B9_7F4A_7C15u64);
        let mut next = || rng.next_u64();
        for &d in &dens {
            for &n in &edges {
                for n in [n, -n, n + 1, n - 1] {
                    assert_eq!(round_div(n, d), wide_div(n, d), "{n} / {d}");
                }
            }
            for _ in 0..2000 {
                let n = (next() as i64 >> (next() % 64)) as i128;
                assert_eq!(round_div(n, d), wide_div(n, d), "{n} / {d}");
            }
        }
        let limit = 1i64 << 30;
        let factors = [
            0,
            1,
            -1,
            limit - 1,
            -(limit - 1),
            limit,
            -limit,
            i64::MAX >> 20,
        ];
        let wide = |a: i64, b: i64, c: i64, d: i64| a as i128 * b as i128 - c as i128 * d as i128;
        for a in factors {
            for b in factors {
                for (c, d) in [(b, a), (limit - 1, -(limit - 1)), (-limit, limit), (3, 5)] {
                    assert_eq!(cross_diff(a, b, c, d), wide(a, b, c, d));
                }
            }
        }
        for _ in 0..20000 {
            let f = |v: u64| (v as i64) >> (v % 40 + 24);
            let (a, b, c, d) = (f(next()), f(next()), f(next()), f(next()));
            assert_eq!(cross_diff(a, b, c, d), wide(a, b, c, d), "{a} {b} {c} {d}");
        }
    }

    /// One reciprocal of the area gives every quotient `round_div_i64` gives, `None` included.
    #[test]
    fn round_divisor_equals_round_div() {
        let mut rng = crate::test_rng::XorShift64::new(0x2545_F491_4F6C_DD1Du64);
        let mut next = move || rng.next_u64();
        let areas = [
            i64::MIN,
            -1,
            0,
            1,
            2,
            3,
            (1 << 31) - 1,
            1 << 31,
            (1 << 31) + 1,
            i64::MAX / 2,
            i64::MAX,
        ];
        let numerators = [
            i64::MIN,
            i64::MIN + 1,
            i64::MIN / 2,
            i64::MIN / 2 - 1,
            -1,
            0,
            1,
            i64::MAX / 2 - 1,
            i64::MAX / 2,
            i64::MAX / 2 + 1,
            i64::MAX,
        ];
        let check = |n: i64, d: i64| {
            assert_eq!(
                RoundDivisor::new(d).round_div(n),
                round_div_i64(n, d),
                "{n} / {d}"
            );
        };
        for d in areas {
            for n in numerators {
                check(n, d);
                // Halves: numerators whose quotient is exactly k + ½ or just either side.
                for k in [-3i64, 0, 5] {
                    let half = k.wrapping_mul(d).wrapping_add(d / 2);
                    for n in [half - 1, half, half + 1] {
                        check(n, d);
                    }
                }
            }
        }
        for _ in 0..200_000 {
            // Twice an area from 1 to 2^33 (both sides of the reciprocal's limit), numerators
            // of every size and sign.
            let d = (next() >> (next() % 64).max(31)) as i64;
            let n = (next() as i64) >> (next() % 64);
            check(n, d);
            check(n.wrapping_mul(d) / 2, d);
        }
    }

    /// A random triangle with 4 sub-pixel bits and zero depths, its coordinates from a pixel's
    /// worth to the guard band's ±2^22 sub-pixels.
    fn random_triangle(next: &mut impl FnMut() -> u64) -> [ScreenVertex<4>; 3] {
        let span = 1i64 << (4 + next() % 19);
        let mut coord = || (next() % (2 * span as u64)) as i64 - span;
        core::array::from_fn(|_| ScreenVertex {
            x: crate::project::SubPx(coord() as i32),
            y: crate::project::SubPx(coord() as i32),
            q: Depth::ZERO,
            color: [I16F16::ZERO; 3],
        })
    }

    /// `plane` (64-bit where every step fits, else 128-bit) equals the plane computed wholly in
    /// 128 bits, for small, large and extreme triangles and values, with and without extra bits.
    #[test]
    fn plane_equals_the_128_bit_plane() {
        fn wide(s: &PlaneSolver, f: [i64; 3], extra: u32) -> Plane {
            let (d1, d2) = (f[1] as i128 - f[0] as i128, f[2] as i128 - f[0] as i128);
            let (e1, e2) = (
                (s.e1.0 as i128, s.e1.1 as i128),
                (s.e2.0 as i128, s.e2.1 as i128),
            );
            let sign = if s.flip { -1 } else { 1 };
            let nx = sign * (d1 * e2.1 - d2 * e1.1);
            let ny = sign * (d2 * e1.0 - d1 * e2.0);
            let area = s.area as i128;
            let div = |n: i128| (2 * n + area).div_euclid(2 * area);
            let px = 1i128 << (s.sub_bits + 1 + extra);
            let value = ((f[0] as i128) << extra)
                + div((nx * s.to_ref.0 as i128 + ny * s.to_ref.1 as i128) << extra);
            let sat = |v: i128| v.clamp(i64::MIN as i128, i64::MAX as i128) as i64;
            Plane {
                value: value as i64,
                dx: sat(div(nx * px)),
                dy: sat(div(ny * px)),
            }
        }
        let mut rng = crate::test_rng::XorShift64::new(0x5851_F42D_4C95_7F2Du64);
        let mut next = move || rng.next_u64();
        let mut fast = 0;
        for i in 0..20_000 {
            let v = random_triangle(&mut next);
            let Some(s) = PlaneSolver::new(&v) else {
                continue;
            };
            // Values up to 2^32 in magnitude (the documented limit), most of them depths.
            let bits = if i % 2 == 0 { 31 } else { 1 + next() % 32 };
            let mut value = || (next() >> (64 - bits)) as i64 - (1i64 << (bits - 1));
            let f = [value(), value(), value()];
            for extra in [0, DEPTH_PLANE_EXTRA_BITS] {
                fast += s.plane_i64(f[0], f[1] - f[0], f[2] - f[0], extra).is_some() as u32;
                assert_eq!(s.plane(f, extra), wide(&s, f, extra), "{v:?} {f:?} {extra}");
            }
        }
        // Both paths were taken.
        assert!(fast > 1000 && fast < 39_000, "{fast}");
    }

    /// The walk oriented by the solver's sign is `TriangleWalk::new`'s: random triangles from a
    /// pixel to the guard band, every vertex order (both windings, ties in y), walked to the
    /// end and compared row by row.
    #[test]
    fn oriented_walk_equals_new() {
        let mut rng = crate::test_rng::XorShift64::new(0x3C6E_F372_FE94_F82B);
        let mut next = move || rng.next_u64();
        let mut walked = 0;
        for i in 0..40_000 {
            let span = 1i64 << (3 + next() % 12);
            let mut coord = || ((next() % (2 * span as u64)) as i64 - span / 2) as i32;
            let mut v = [(coord(), coord()), (coord(), coord()), (coord(), coord())];
            if i % 4 == 0 {
                v[1].1 = v[0].1; // a horizontal edge
            }
            let sv: [ScreenVertex<4>; 3] = v.map(|(x, y)| ScreenVertex {
                x: crate::project::SubPx(x),
                y: crate::project::SubPx(y),
                q: Depth::ZERO,
                color: [I16F16::ZERO; 3],
            });
            let solver = PlaneSolver::new(&sv);
            let min_row = (next() % 8) as i32;
            let a = TriangleWalk::new::<4>(v, min_row, 300);
            let b = solver.and_then(|s| TriangleWalk::oriented::<4>(v, s.negative(), min_row, 300));
            assert_eq!(a.is_some(), b.is_some(), "{v:?}");
            let (Some(mut a), Some(mut b)) = (a, b) else {
                continue;
            };
            // The orientation as the walk found it before: the cross product of its sorted
            // vertices.
            let mut o = v;
            o.sort_by_key(|p| p.1);
            let [t, m, b_] = o.map(|(x, y)| (x as i64, y as i64));
            let cross = (b_.0 - t.0) * (m.1 - t.1) - (b_.1 - t.1) * (m.0 - t.0);
            assert_eq!(b.long_is_left, cross < 0, "{v:?}");
            walked += 1;
            loop {
                assert_eq!((a.row(), a.span()), (b.row(), b.span()), "{v:?}");
                let (more_a, more_b) = (a.advance::<4>(), b.advance::<4>());
                assert_eq!(more_a, more_b, "{v:?}");
                if !more_a {
                    break;
                }
            }
        }
        assert!(walked > 10_000, "{walked}");
    }

    /// The bounded solver with its premise tested in 32 bits gives `plane_bounded`'s plane for
    /// non-negative values, and declines exactly where that does or a value is negative.
    #[test]
    fn bounded_plane_from_32_bit_values_equals_the_bounded_plane() {
        let mut rng = crate::test_rng::XorShift64::new(0x0DDB_1A5E_5BAD_5EEDu64);
        let mut next = move || rng.next_u64();
        let (mut solved, mut declined) = (0, 0);
        for _ in 0..50_000 {
            let v = random_triangle(&mut next);
            let Some(s) = PlaneSolver::new(&v) else {
                continue;
            };
            let mut value = || match next() % 8 {
                0 => (next() as i32).min(-1),
                1 => i32::MAX - (next() % 4) as i32,
                2 => (1 << 30) + (next() % 4) as i32 - 2,
                _ => (next() >> (34 + next() % 30)) as i32,
            };
            let f = [value(), value(), value()];
            for extra in [0, DEPTH_PLANE_EXTRA_BITS, DEPTH_PLANE_EXTRA_BITS + 1] {
                let got = s.plane_bounded_i32(f, extra);
                let want = if f.iter().all(|&q| q >= 0) {
                    let f0 = f[0] as i64;
                    s.plane_bounded(f0, f[1] as i64 - f0, f[2] as i64 - f0, extra)
                } else {
                    None
                };
                assert_eq!(got, want, "{v:?} {f:?} {extra}");
                if let Some(p) = got {
                    assert_eq!(p, s.plane(f.map(i64::from), extra), "{v:?} {f:?} {extra}");
                }
                solved += got.is_some() as u32;
                declined += got.is_none() as u32;
            }
        }
        assert!(solved > 10_000 && declined > 10_000, "{solved} {declined}");
    }

    /// `plane_bounded` takes every triangle and value it may, and gives `plane_checked`'s
    /// plane for each: edges up to its limit (and just past it), values up to `2^32` apart
    /// from `f0` and differences up to `2^30` (and just past both), both signs of the area.
    #[test]
    fn bounded_plane_equals_checked_plane() {
        fn run<const S: u32>(cases: u32, seed: u64) -> (u32, u32) {
            let mut rng = crate::test_rng::XorShift64::new(seed);
            let mut next = move || rng.next_u64();
            let (mut bounded, mut refused) = (0, 0);
            // Half an edge limit, in sub-pixels (doubled units are twice them).
            let half = 1i64 << (SHORT_EDGE_BITS - S - 1);
            for i in 0..cases {
                // Edges from a pixel to just past the limit.
                let reach = match i % 4 {
                    0 => half + 2,
                    1 => half,
                    _ => {
                        1i64 << (S
                            + (next() % u64::from(SHORT_EDGE_BITS - 2 * S.min(8)).max(1)) as u32)
                    }
                };
                let base = (next() % (1 << 20)) as i64 - (1 << 19);
                let mut coord = || base + (next() % (reach as u64 + 1)) as i64 - reach / 2;
                let v: [ScreenVertex<S>; 3] = core::array::from_fn(|_| ScreenVertex {
                    x: crate::project::SubPx(coord() as i32),
                    y: crate::project::SubPx(coord() as i32),
                    q: Depth::ZERO,
                    color: [I16F16::ZERO; 3],
                });
                let Some(s) = PlaneSolver::new(&v) else {
                    continue;
                };
                let value = |r: u64, bits: u32| (r >> (64 - bits)) as i64 - (1i64 << (bits - 1));
                let f0 = match i % 3 {
                    0 => value(next(), 33),
                    1 => (1 << 32) - 1 - (next() % 2) as i64,
                    _ => value(next(), 31),
                };
                let mut diff = || match next() % 4 {
                    0 => (1 << 30) - 1 + (next() % 2) as i64,
                    1 => -(1 << 30) + (next() % 2) as i64,
                    _ => value(next(), 31),
                };
                let (d1, d2) = (diff(), diff());
                for extra in [0, 5, DEPTH_PLANE_EXTRA_BITS, DEPTH_PLANE_EXTRA_BITS + 1] {
                    match s.plane_bounded(f0, d1, d2, extra) {
                        Some(p) => {
                            bounded += 1;
                            assert!(s.short_edges && extra <= DEPTH_PLANE_EXTRA_BITS);
                            assert!(d1.abs() < 1 << 30 && d2.abs() < 1 << 30 && f0.abs() < 1 << 32);
                            assert_eq!(
                                Some(p),
                                s.plane_checked(f0, d1, d2, extra),
                                "{v:?} {f0} {d1} {d2} {extra}"
                            );
                        }
                        None => refused += 1,
                    }
                }
            }
            (bounded, refused)
        }
        for (bounded, refused) in [
            run::<0>(30_000, 0x9E37_79B9_7F4A_7C15),
            run::<4>(60_000, 0xD1B5_4A32_D192_ED03),
            run::<8>(30_000, 0x8CB9_2BA7_2F3D_8DD7),
        ] {
            assert!(bounded > 10_000 && refused > 10_000, "{bounded} {refused}");
        }
    }

    /// Depth planes of triangles inside the clip planes of a screen for which
    /// `depth_planes_fit_i64` holds solve in 64 bits, and `DepthPlane::new_i64` gives
    /// `DepthPlane::new`'s plane: vertices at the corners and edges of the guard band with the
    /// nearest and farthest depths (every combination for three vertices, at several
    /// sub-pixel offsets), and random eye points inside every plane, projected exactly.
    #[test]
    fn bounded_depth_planes_solve_in_64_bits() {
        assert!(depth_planes_fit_i64(240, 4) && depth_planes_fit_i64(255, 4));
        assert!(!depth_planes_fit_i64(256, 4) && !depth_planes_fit_i64(240, 5));
        assert!(depth_planes_fit_i64(1023, 3) && !depth_planes_fit_i64(1024, 3));
        assert!(!depth_planes_fit_i64(usize::MAX, 0) && !depth_planes_fit_i64(1, 9));
        fn check<const S: u32>(v: &[ScreenVertex<S>; 3]) -> bool {
            let Some(s) = PlaneSolver::new(v) else {
                return false;
            };
            let f = v.each_ref().map(|s| s.q.to_bits() as i64);
            let fast = s.plane_i64(f[0], f[1] - f[0], f[2] - f[0], DEPTH_PLANE_EXTRA_BITS);
            assert_eq!(fast, Some(s.plane(f, DEPTH_PLANE_EXTRA_BITS)), "{v:?}");
            // `new_i64` takes the bounded solver: its premise holds here.
            let bounded = s.plane_bounded(f[0], f[1] - f[0], f[2] - f[0], DEPTH_PLANE_EXTRA_BITS);
            assert_eq!(bounded, fast, "{v:?}");
            let (a, b) = (DepthPlane::new_i64(&s, v), DepthPlane::new(&s, v));
            assert_eq!((a.origin, a.q), (b.origin, b.q));
            true
        }
        // The largest bounded screens: the guard band reaches 4 screens beyond each side.
        fn corners<const S: u32>(side: i32) -> usize {
            let (centre, guard) = ((side << S) / 2, (4 * side) << S);
            let xs = [
                centre - guard,
                centre - guard + 5,
                centre,
                centre + guard - 3,
                centre + guard,
            ];
            let qs = [1, 1 << 30, 1 << 10];
            let points: std::vec::Vec<ScreenVertex<S>> = xs
                .iter()
                .flat_map(|&x| xs.iter().map(move |&y| (x, y)))
                .flat_map(|(x, y)| {
                    qs.iter().map(move |&q| ScreenVertex {
                        x: crate::project::SubPx(x),
                        y: crate::project::SubPx(y),
                        q: Depth::from_bits(q),
                        color: [I16F16::ZERO; 3],
                    })
                })
                .collect();
            let mut solved = 0;
            for a in &points {
                for b in &points {
                    for c in points.iter().step_by(2) {
                        solved += check(&[*a, *b, *c]) as usize;
                    }
                }
            }
            solved
        }
        assert!(corners::<4>(255) > 100_000);
        assert!(corners::<3>(1023) > 100_000);
        assert!(corners::<0>(255) > 100_000);
        // Eye points inside every plane, projected exactly, on a 255-pixel screen.
        let vp = crate::project::Viewport::<4>::new(255, 255, 1.0, 1.0 / 256.0, 16384.0).unwrap();
        let mut rng = crate::test_rng::XorShift64::new(0x9E37_79B9_7F4A_7C15u64);
        let mut next = move || rng.next_u64();
        let mut drawn = 0;
        while drawn < 20_000 {
            let v: [Option<ScreenVertex<4>>; 3] = core::array::from_fn(|_| {
                let w = (next() % (1 << 30)) as i32 + 1;
                // Up to 8·w either way: beyond the guard band's 4 screens (at this focal).
                let off = |r: u64| ((((r % (1 << 35)) as i64 - (1 << 34)) >> 4) * w as i64) >> 27;
                let p = crate::vertex::EyePoint {
                    x: I16F16::from_bits(off(next()).clamp(i32::MIN as i64, i32::MAX as i64) as i32),
                    y: I16F16::from_bits(off(next()).clamp(i32::MIN as i64, i32::MAX as i64) as i32),
                    w: I16F16::from_bits(w),
                };
                let inside = vp.clip_distances(&p).iter().all(|&d| d >= 0);
                inside.then(|| vp.project(&p, [I16F16::ZERO; 3])).flatten()
            });
            if let [Some(a), Some(b), Some(c)] = v {
                drawn += check(&[a, b, c]) as usize;
            }
        }
    }

    /// The edge set-up (one 32-bit division, comparisons for the first row) places and steps
    /// the edge exactly: on every row, `column()` is the smallest c whose centre is at or right
    /// of the edge, found here by the exact cross-product test, for rows next to `a`, far below
    /// it and above it, with each sub-pixel precision.
    #[test]
    fn edge_walk_matches_exact_columns() {
        fn check<const S: u32>(a: (i32, i32), b: (i32, i32), row: i32) {
            let Some(mut e) = EdgeWalk::new::<S>(a, b, row) else {
                assert!(b.1 <= a.1);
                return;
            };
            // Centre c is at or right of the edge on row r iff
            // (xc − ax)·dy >= (yc − ay)·dx (dy > 0), all in doubled units.
            let at_or_right = |c: i64, r: i64| {
                let (xc, yc) = ((2 * c + 1) << S, (2 * r + 1) << S);
                let (ax, ay) = (2 * a.0 as i64, 2 * a.1 as i64);
                let (dx, dy) = (2 * (b.0 - a.0) as i64, 2 * (b.1 - a.1) as i64);
                (xc - ax) * dy >= (yc - ay) * dx
            };
            for r in row..row + 5 {
                let c = e.column() as i64;
                assert!(
                    at_or_right(c, r as i64),
                    "{a:?} {b:?} row {r}: {c} left of edge"
                );
                assert!(
                    !at_or_right(c - 1, r as i64),
                    "{a:?} {b:?} row {r}: {c} not first"
                );
                e.step();
            }
        }
        let mut rng = crate::test_rng::XorShift64::new(0x2545_F491_4F6C_DD1Du64);
        let mut next = || rng.next_u64();
        let lim = 1i64 << 22;
        for i in 0..40_000 {
            // Coordinates from tiny to the ±2^22 limit.
            let shift = (next() % 23) as u32;
            let mut coord = || ((next() as i64).rem_euclid(2 * lim) - lim) as i32 >> shift;
            let a = (coord(), coord());
            let b = (coord(), coord().max(a.1));
            let first = |s: u32| (a.1 as i64 >> s) as i32;
            let offset = match i % 4 {
                0 | 1 => 0,
                2 => (next() % 1000) as i32,
                _ => -((next() % 1000) as i32),
            };
            check::<0>(a, b, first(0) + offset);
            check::<4>(a, b, first(4) + offset);
            check::<8>(a, b, first(8) + offset);
        }
    }

    #[test]
    fn clamped_depth_and_depth_step_equal_the_clamps() {
        let mut rng = crate::test_rng::XorShift64::new(0x2545_f491_4f6c_dd1d);
        // Around every boundary of the range and of the high-word test, then at random
        // magnitudes.
        let edges = [
            0i64,
            1 << 41,
            1 << 40,
            1 << 32,
            1 << 31,
            1 << 10,
            i64::MAX,
            i64::MIN,
        ];
        let mut values = std::vec::Vec::new();
        for e in edges {
            for d in -1025i64..=1025 {
                values.extend([e.wrapping_add(d), e.wrapping_neg().wrapping_add(d)]);
            }
        }
        for _ in 0..200_000 {
            values.push(rng.next_u64() as i64 >> (rng.next_u64() % 64));
        }
        for q in values {
            let expected = (q >> DEPTH_PLANE_EXTRA_BITS).clamp(0, i32::MAX as i64) as i32;
            assert_eq!(clamped_depth(q), expected, "{q}");
            // The per-pixel step saturates at both ends, tested on its high word the same way.
            let plane = Plane {
                value: 0,
                dx: q,
                dy: 0,
            };
            let step = (q >> DEPTH_PLANE_EXTRA_BITS).clamp(i32::MIN as i64, i32::MAX as i64);
            assert_eq!(depth_step(&plane), step as i32, "{q}");
        }
    }

    /// The first centre at or after `p` is `ceil((p − 2^S) / 2^(S+1))` computed in 64 bits, for
    /// every doubled position near zero, near the guard band's ±2^23 and near the 32-bit
    /// envelope's ends, at 0, 1, 4 and 8 sub-pixel bits.
    #[test]
    fn first_centre_is_the_rounded_up_division() {
        fn check<const S: u32>() {
            let limit = i32::MAX - (1 << S);
            let around = |c: i32| (-600..=600).map(move |d: i32| c.saturating_add(d));
            let points = around(0)
                .chain(around(1 << 23))
                .chain(around(-(1 << 23)))
                .chain(around(limit - 600))
                .chain(around(-limit + 600));
            for p in points.filter(|p| p.unsigned_abs() <= limit as u32) {
                let den = 1i64 << (S + 1);
                let want = -((-(p as i64 - (1i64 << S))).div_euclid(den));
                assert_eq!(first_centre_at_or_after::<S>(p) as i64, want, "S {S} p {p}");
            }
        }
        check::<0>();
        check::<1>();
        check::<4>();
        check::<8>();
    }

    /// The steep slope's quotient and remainder are the division's, for every `|dx| < dy`, and
    /// it declines every shallower edge.
    #[test]
    fn steep_slope_equals_the_division() {
        let mut rng = crate::test_rng::XorShift64::new(0x9e37_79b9_7f4a_7c15u64);
        let mut next = || rng.next_u64();
        let mut pairs = std::vec![
            (0, 1),
            (-1, 2),
            (1, 2),
            (-2, 2),
            (2, 2),
            (i32::MIN + 1, i32::MAX)
        ];
        for _ in 0..100_000 {
            let shift = (next() % 31) as u32;
            let dy = ((next() as u32 >> 1) >> shift).max(1) as i32;
            let dx = (next() as i32) >> (next() % 32);
            pairs.push((dx, dy));
            pairs.push((dx % dy, dy));
        }
        for (dx, dy) in pairs {
            match steep_slope(dx, dy) {
                Some(s) => {
                    assert!(dx.unsigned_abs() < dy as u32, "{dx} / {dy}");
                    assert_eq!(s, (dx.div_euclid(dy), dx.rem_euclid(dy)), "{dx} / {dy}");
                }
                None => assert!(dx.unsigned_abs() >= dy as u32, "{dx} / {dy}"),
            }
        }
    }

    #[test]
    fn floor_div_rem_i32_equals_the_division() {
        let mut rng = crate::test_rng::XorShift64::new(0x9e37_79b9_7f4a_7c15u64);
        let mut next = || rng.next_u64();
        let mut pairs = std::vec![
            (i32::MIN, 1),
            (i32::MIN, 2),
            (i32::MIN, 3),
            (i32::MIN, i32::MAX)
        ];
        for dy in [1, 2, 3, 1 << 30, i32::MAX] {
            for dx in [
                0,
                1,
                -1,
                dy,
                -dy,
                dy - 1,
                1 - dy,
                dy.wrapping_add(1),
                (-dy).wrapping_sub(1),
                i32::MAX,
                i32::MIN + 1,
            ] {
                pairs.push((dx, dy));
            }
        }
        for _ in 0..1_000_000 {
            let dy = ((next() as u32 >> 1) >> (next() % 31)).max(1) as i32;
            let dx = (next() as i32) >> (next() % 32);
            pairs.push((dx, dy));
            pairs.push((dx.wrapping_sub(dx % dy), dy));
        }
        for (dx, dy) in pairs {
            let want = (dx.div_euclid(dy), dx.rem_euclid(dy));
            assert_eq!(floor_div_rem_i32(dx, dy), want, "{dx} / {dy}");
        }
    }

    /// The 32-bit placement gives the 64-bit one's column and remainder wherever it applies,
    /// on random edges and on its limits, and applies to every edge of the bit budget
    /// (coordinates within ±2^22) on its first row with 4 sub-pixel bits.
    #[test]
    fn narrow_placement_equals_wide() {
        fn check<const S: u32>(ax: i32, t: i64, dx: i32, dy: i32) -> bool {
            let (step, step_rem) = (dx.div_euclid(dy), dx.rem_euclid(dy));
            let wide = place_wide::<S>(ax, t, dy, step, step_rem);
            match place_narrow::<S>(ax, t, dx, dy, step, step_rem) {
                Some(narrow) => {
                    assert_eq!(narrow, wide, "S {S} ax {ax} t {t} dx {dx} dy {dy}");
                    true
                }
                None => false,
            }
        }
        let mut rng = crate::test_rng::XorShift64::new(0x2545_f491_4f6c_dd1du64);
        let mut next = || rng.next_u64();
        // The limits: |dx|, dy up to 2^(28−S) − 1, |ax| up to 2^28 − 1, t at both ends.
        for s in [0u32, 4, 8] {
            let limit = (1i32 << (28 - s)) - 1;
            for ax in [-(1 << 28) + 1, -1, 0, 1, (1 << 28) - 1] {
                for dx in [-limit, -limit + 1, -1, 0, 1, limit - 1, limit] {
                    for dy in [1, 2, limit - 1, limit] {
                        for t in [0, 1, (1i64 << (s + 1)) - 1] {
                            let applied = match s {
                                0 => check::<0>(ax, t, dx, dy),
                                4 => check::<4>(ax, t, dx, dy),
                                _ => check::<8>(ax, t, dx, dy),
                            };
                            assert!(applied, "S {s} ax {ax} t {t} dx {dx} dy {dy}");
                        }
                    }
                }
            }
            // Just outside: declined.
            assert!(!check::<4>(0, 32, 2, 2));
            assert!(!check::<4>(0, -1, 2, 2));
            assert!(!check::<4>(0, 0, 1 << 24, 2));
            assert!(!check::<4>(0, 0, 2, 1 << 24));
            assert!(!check::<4>(1 << 28, 0, 2, 2));
        }
        let lim = 1i64 << 22;
        for i in 0..200_000 {
            // Edges of the bit budget, from tiny to the ±2^22 limit, on the first row below
            // their upper end (or, one time in four, any row, where the wide path may decide).
            let shift = (next() % 23) as u32;
            let mut coord = || ((next() as i64).rem_euclid(2 * lim) - lim) as i32 >> shift;
            let a = (coord(), coord());
            let b = (coord(), coord());
            let (dx, dy) = (2 * (b.0 - a.0), 2 * (b.1 - a.1));
            if dy <= 0 {
                continue;
            }
            let t = if i % 4 == 3 {
                // Any row on or off screen: |t| < 2^34, the wide placement's bound.
                (next() as i64) >> (30 + next() % 34)
            } else {
                (next() % 32) as i64
            };
            let applied = check::<4>(a.0, t, dx, dy);
            assert!(applied || i % 4 == 3, "ax {} t {t} dx {dx} dy {dy}", a.0);
            check::<0>(a.0, t % 2, dx, dy);
            check::<8>(a.0, (next() % 512) as i64, dx, dy);
        }
    }

    use std::vec::Vec;

    /// Independent reference: exact edge functions with the top-left tie rule.
    fn covers(v: [(i64, i64); 3], s: u32, c: i64, r: i64) -> bool {
        let (px, py) = ((2 * c + 1) << s, (2 * r + 1) << s);
        let v = v.map(|(x, y)| (2 * x, 2 * y));
        let area = (v[1].0 - v[0].0) * (v[2].1 - v[0].1) - (v[2].0 - v[0].0) * (v[1].1 - v[0].1);
        if area == 0 {
            return false;
        }
        for i in 0..3 {
            let (a, b) = if area > 0 {
                (v[i], v[(i + 1) % 3])
            } else {
                (v[(i + 1) % 3], v[i])
            };
            // With area > 0 in y-down coordinates the interior is where e > 0 for edges a→b.
            let e = (b.0 - a.0) * (py - a.1) - (b.1 - a.1) * (px - a.0);
            if e < 0 {
                return false;
            }
            if e == 0 {
                // Top edge: horizontal with the interior below (y-down), which for e > 0 inside
                // means b.x > a.x. Left edge: interior to its right, which means it goes up.
                let top = a.1 == b.1 && b.0 > a.0;
                let left = b.1 < a.1;
                if !(top || left) {
                    return false;
                }
            }
        }
        true
    }

    fn raster(v: [(i32, i32); 3], s: u32, w: i32, h: i32) -> Vec<(i32, i32)> {
        let mut out = Vec::new();
        let f = |r: i32, x0: i32, x1: i32| {
            for c in x0..x1 {
                out.push((c, r));
            }
        };
        match s {
            0 => for_each_span::<0>(v, w, h, f),
            2 => for_each_span::<2>(v, w, h, f),
            4 => for_each_span::<4>(v, w, h, f),
            8 => for_each_span::<8>(v, w, h, f),
            _ => unreachable!(),
        }
        out
    }

    fn reference(v: [(i32, i32); 3], s: u32, w: i32, h: i32) -> Vec<(i32, i32)> {
        let v64 = v.map(|(x, y)| (x as i64, y as i64));
        let mut out = Vec::new();
        for r in 0..h {
            for c in 0..w {
                if covers(v64, s, c as i64, r as i64) {
                    out.push((c, r));
                }
            }
        }
        out
    }

    #[test]
    fn reference_tie_rule_agrees_with_known_cases() {
        // Square (0,0)-(2,2) pixels split on the diagonal, S = 0: vertices at pixel corners.
        let a = [(0, 0), (2, 0), (0, 2)];
        let b = [(2, 0), (2, 2), (0, 2)];
        // The diagonal is a right edge of `a` and a left edge of `b`: its centres go to `b`.
        assert_eq!(reference(a, 0, 4, 4), [(0, 0)]);
        assert_eq!(reference(b, 0, 4, 4), [(1, 0), (0, 1), (1, 1)]);
    }

    #[test]
    fn walk_equals_edge_functions_on_tricky_triangles() {
        let cases: &[[(i32, i32); 3]] = &[
            [(8, 8), (40, 8), (8, 40)],      // flat top, vertices on centres (S = 4)
            [(8, 8), (40, 40), (8, 40)],     // flat bottom
            [(3, -20), (90, 33), (-17, 71)], // general, partly off-screen
            [(24, 24), (25, 120), (26, 24)], // sliver
            [(0, 0), (100, 1), (200, 2)],    // collinear
            [(56, 8), (8, 56), (104, 104)],  // edges through centres
            [(-500, -500), (900, 10), (10, 900)],
        ];
        for &v in cases {
            for s in [0u32, 2, 4, 8] {
                let scaled = v.map(|(x, y)| (x << s >> 2, y << s >> 2));
                assert_eq!(
                    raster(scaled, s, 12, 12),
                    reference(scaled, s, 12, 12),
                    "{scaled:?} S={s}"
                );
            }
        }
    }

    #[test]
    fn depth_plane_interpolates_vertex_values() {
        use crate::project::SubPx;
        let sv = |x: i32, y: i32, q: f32| ScreenVertex::<4> {
            x: SubPx(x),
            y: SubPx(y),
            q: Depth::from_num(q),
            color: [I16F16::ZERO; 3],
        };
        // Vertices on pixel centres so the plane is sampled exactly there.
        let v = [sv(8, 8, 0.5), sv(8 + 160, 8, 0.25), sv(8, 8 + 160, 1.0)];
        let p = DepthPlane::new(&PlaneSolver::new(&v).unwrap(), &v);
        let walk: WalkDepth = p.walk_from(3);
        assert_eq!((walk.span_start(2), p.step()), p.span_start(2, 3));
        assert_eq!(p.depth_at(0, 0), Depth::from_num(0.5));
        assert!((p.depth_at(10, 0).to_num::<f64>() - 0.25).abs() < 1e-8);
        assert!((p.depth_at(0, 10).to_num::<f64>() - 1.0).abs() < 1e-8);
        assert!((p.depth_at(5, 5).to_num::<f64>() - 0.625).abs() < 1e-8);
        let (q, dq) = p.span_start(2, 3);
        assert!((q as f64 / (1u64 << 30) as f64 - (0.5 - 0.05 + 0.15)).abs() < 1e-8);
        assert!((dq as f64 / (1u64 << 30) as f64 + 0.025).abs() < 1e-8);
    }

    /// `floor_div_by_float` is the floored division (`floor_div_i64`) or `None`, for numerators
    /// of both signs and every length, and answers every division its estimate covers (a
    /// quotient's magnitude from 2 to 2^32, `|num| < 2^50`, `d < 2^29`); `FloatDivisor`, with
    /// the general division behind it, is always the floor.
    #[test]
    fn float_floor_division_is_floor_div() {
        let mut rng = crate::test_rng::XorShift64::new(0x2545_f491_4f6c_dd1du64);
        for k in 0..1_000_000u32 {
            let x = rng.next_u64();
            let d = ((x as u32) >> ((x >> 32) % 32)).max(1);
            let num = match k % 4 {
                // Around multiples of d, on both sides of zero.
                0 => (rng.next_u64() % (1 << 40)) as i64 / d as i64 * d as i64 - (k as i64 % 3),
                _ => (rng.next_u64() as i64) >> ((x >> 40) % 64),
            };
            let got = floor_div_by_float(num, d);
            // With the fallback, the FPU cores' plane divisor: always the floor.
            let floored = FloorDivisor::floor_div(&FloatDivisor(d), num);
            assert_eq!(floored, num.div_euclid(d as i64), "{num} / {d}");
            if let Some(q) = got {
                assert_eq!(q, floor_div_i64(num, d as i64), "{num} / {d}");
            } else {
                let magnitude = num.unsigned_abs();
                let quotient = magnitude / d as u64;
                let covered =
                    magnitude < 1 << 50 && d < 1 << 29 && (2..1 << 32).contains(&quotient);
                assert!(!covered, "{num} / {d} given up");
            }
        }
        assert_eq!(floor_div_by_float(-6, 2), Some(-3));
        assert_eq!(floor_div_by_float(-7, 2), Some(-4));
        assert_eq!(floor_div_by_float(i64::MIN, 1), None);
        assert_eq!(floor_div_by_float(5, 0), None);
    }

    /// The walked span start is [`DepthPlane::span_start`]'s: [`WideWalk`]'s everywhere,
    /// [`SplitWalk`]'s wherever the plane's depth lies in `[−2^31, 2^31)`. Planes of any value
    /// and gradients (wrapping included), stepped down 40 rows from a random first row, at
    /// random columns (for the split walk, those whose depth is out of range counted, not
    /// compared).
    #[test]
    fn walked_span_start_equals_span_start() {
        let mut rng = crate::test_rng::XorShift64::new(0x2545_f491_4f6c_dd1du64);
        let mut next = || rng.next_u64();
        let (mut compared, mut outside) = (0, 0);
        for case in 0..5_000 {
            let r = next();
            let scale = (r % 64) as u32;
            let small = |v: u64| (v as i64) >> (63 - scale.min(62));
            let q = Plane {
                value: small(next()),
                dx: small(next()),
                dy: small(next()),
            };
            let origin =
                PixelOrigin::new((next() % 4096) as i32 - 2048, (next() % 4096) as i32 - 2048);
            let first = (next() % 2048) as i32;
            let plane = DepthPlane { origin, q };
            let mut wide: WideWalk = plane.walk_from(first);
            let mut split: SplitWalk = plane.walk_from(first);
            for row in first..first + 40 {
                for _ in 0..4 {
                    let c = (next() % 2048) as i32;
                    let want = plane.span_start(c, row).0;
                    // The 64-bit walk everywhere, the split one where the depth is in range.
                    assert_eq!(wide.span_start(c), want, "case {case} row {row} column {c}");
                    let depth = origin.at(&q, c, row) >> DEPTH_PLANE_EXTRA_BITS;
                    if (i32::MIN as i64..=i32::MAX as i64).contains(&depth) {
                        assert_eq!(
                            split.span_start(c),
                            want,
                            "case {case} row {row} column {c}"
                        );
                        compared += 1;
                    } else {
                        outside += 1;
                    }
                }
                wide.next_row();
                split.next_row();
            }
        }
        // Most planes here are in range at most columns; many are far outside.
        assert!(
            compared > 400_000 && outside > 100_000,
            "{compared} {outside}"
        );
    }

    /// The premise of [`SplitWalk`] on real triangles: on every row, at covered centres (each
    /// span's ends and middle), the walked start equals the 64-bit one, for vertex depths at the extremes a drawn
    /// triangle can have (0, 1, `MAX_DRAWN_DEPTH`, mixed), slivers and triangles reaching
    /// far off the screen included.
    #[test]
    fn walked_span_start_is_exact_at_covered_centres() {
        let mut rng = crate::test_rng::XorShift64::new(0x3C6E_F372_FE94_F82B);
        let mut next = move || rng.next_u64();
        let depths = [
            0,
            1,
            2,
            1 << 20,
            1 << 29,
            1 << 30,
            MAX_DRAWN_DEPTH - 1,
            MAX_DRAWN_DEPTH,
        ];
        let mut spans = 0;
        for i in 0..20_000 {
            let span = 1i64 << (3 + next() % 14);
            let mut coord = || ((next() % (2 * span as u64)) as i64 - span / 2) as i32;
            let mut v = [(coord(), coord()), (coord(), coord()), (coord(), coord())];
            if i % 5 == 0 {
                v[2] = (v[0].0 + 1, v[1].1); // a sliver
            }
            let sv: [ScreenVertex<4>; 3] = v.map(|(x, y)| ScreenVertex {
                x: crate::project::SubPx(x),
                y: crate::project::SubPx(y),
                q: Depth::from_bits(if i % 2 == 0 {
                    depths[(next() % depths.len() as u64) as usize]
                } else {
                    (next() % (MAX_DRAWN_DEPTH as u64 + 1)) as i32
                }),
                color: [I16F16::ZERO; 3],
            });
            let (Some(solver), Some(mut walk)) =
                (PlaneSolver::new(&sv), TriangleWalk::new::<4>(v, 0, 2048))
            else {
                continue;
            };
            let plane = DepthPlane::new(&solver, &sv);
            let mut depth: SplitWalk = plane.walk_from(walk.row());
            loop {
                let (l, r) = walk.span();
                let (l, r) = (l.max(0), r.min(2048));
                if l < r {
                    let row = walk.row();
                    for c in [l, (l + r) / 2, r - 1] {
                        assert_eq!(depth.span_start(c), plane.span_start(c, row).0, "{sv:?}");
                    }
                    spans += 1;
                }
                depth.next_row();
                if !walk.advance::<4>() {
                    break;
                }
            }
        }
        assert!(spans > 100_000, "{spans}");
    }

    #[test]
    fn area_in_words_is_the_area() {
        let mut rng = crate::test_rng::XorShift64::new(0x5851_f42d_4c95_7f2du64);
        let wide = |v: &[(i32, i32); 3]| {
            let [a, b, c] = v.map(|(x, y)| (x as i64, y as i64));
            (b.0 - a.0) * (c.1 - a.1) - (c.0 - a.0) * (b.1 - a.1)
        };
        // Coordinates within ±2^30, where the `i64` form cannot overflow; differences up to
        // 2^31, so both sides of the 32-bit check are met.
        let edges = [0, 1, -1, (1 << 30) - 1, 1 << 30, -(1 << 30), 3840, -3840];
        let mut seen = (0, 0);
        for k in 0..200_000u32 {
            let x = rng.next_u64();
            let p = |i: u32| match (k + i / 4) % 3 {
                0 => (x >> (i * 5)) as i32 >> (1 + x % 30),
                1 => edges[((x >> (i * 3)) % 8) as usize],
                _ => ((x >> (i * 7)) as i32 % 4000) - 200,
            };
            let v = [(p(0), p(1)), (p(2), p(3)), (p(4), p(5))];
            let fits = |p: i32, q: i32| p.checked_sub(q).is_some();
            let narrow = fits(v[1].0, v[0].0)
                && fits(v[1].1, v[0].1)
                && fits(v[2].0, v[0].0)
                && fits(v[2].1, v[0].1);
            match signed_area_in_words(&v) {
                Some(area) => {
                    assert_eq!(area, wide(&v), "{v:?}");
                    seen.0 += 1;
                }
                None => {
                    assert!(!narrow, "{v:?}");
                    seen.1 += 1;
                }
            }
            assert_eq!(signed_area_xy(&v), wide(&v), "{v:?}");
        }
        // Both paths taken often.
        assert!(seen.0 > 100_000 && seen.1 > 1_000, "{seen:?}");
    }

    #[test]
    fn short_area_sign_is_the_areas_sign() {
        let mut rng = crate::test_rng::XorShift64::new(0x0a4e_a519_0000_0001);
        let edges = [0, 1, -1, 32_767, -32_768, 16_384, -16_384, 3840];
        let mut short = 0;
        for k in 0..200_000u32 {
            let x = rng.next_u64();
            let p = |i: u32| match (k + i / 4) % 3 {
                0 => (x >> (i * 5)) as i16 as i32,
                1 => edges[((x >> (i * 3)) % 8) as usize],
                _ => ((x >> (i * 7)) as i32 % 4000) - 200,
            };
            let v = [(p(0), p(1)), (p(2), p(3)), (p(4), p(5))];
            let [a, b, c] = v;
            let fits = |p: i32, q: i32| i16::try_from(p - q).is_ok();
            let fit = fits(b.0, a.0) && fits(b.1, a.1) && fits(c.0, a.0) && fits(c.1, a.1);
            let sign = signed_area_xy(&v).cmp(&0);
            assert_eq!(short_area_sign(&v), fit.then_some(sign), "{v:?}");
            assert_eq!(area_sign(&v).cmp(&0), sign, "{v:?}");
            short += fit as u32;
        }
        // Both answers are met, and a degenerate triangle.
        assert_eq!(
            short_area_sign(&[(5, 5), (5, 5), (9, -3)]),
            Some(Ordering::Equal)
        );
        assert!(short > 50_000 && short < 190_000, "{short}");
    }
}
