//! Trim loops: closed polylines in a patch's `(u, v)` domain that cut it by the even-odd rule
//! (a loop cuts a hole, a loop inside that one an island), and the cutting of tessellation
//! triangles by them.
//!
//! A tessellation triangle that no trim edge touches is kept or dropped whole, by the parity
//! of its centroid. One that a trim edge touches is cut, in parameter space:
//!
//! 1. at each trim vertex inside it: a fan of three triangles from that vertex (two, if the
//!    vertex is on an edge), each cut again, until no trim vertex lies inside or on an edge;
//! 2. then every trim edge that meets the triangle crosses it as a chord, boundary to
//!    boundary; chords do not cross (loops are simple and do not meet), so they split the
//!    triangle into convex faces, found by one walk round its boundary with a stack;
//! 3. a face is kept when its centroid is inside an even number of loops.
//!
//! Every new vertex is a trim vertex or the point where a trim edge crosses a triangle edge,
//! computed from the two segments taken in a fixed (lexicographic) order, so both triangles
//! that share an edge cut it at the same bits; the renderer evaluates each new vertex on the
//! surface, so the cut adds no cracks and the trimmed edge follows the surface to within the
//! tessellation's flatness.
//!
//! # Formats and bit budget
//!
//! Trim points are [`TrimPoint`]s, I16F16 in `[0, 1]`: the same bits as the parameters,
//! `[0, 2^16]`. Differences are below 2^17, orientation determinants below 2^35, the
//! numerators of a crossing point below 2^52, all in `i64`. A centroid test scales points by
//! the face's vertex count (at most `TRIM`, below 2^10 in practice; below 2^14 keeps every
//! product under 2^63).
//!
//! # Capacity
//!
//! `TRIM` (a const generic of [`PatchWorkspace`](super::PatchWorkspace)) bounds the work on one
//! tessellation triangle: boundary points of a triangle being cut (its corners and two per
//! chord) and triangles waiting to be cut after fan splits. A triangle that needs more is kept
//! or dropped whole by its centroid and counted in
//! [`PatchStats::trim_overflows`](super::PatchStats::trim_overflows).

use super::tessellate::Uv;
use super::{PatchError, PARAM_ONE};
use fixed::types::I16F16;

/// A trim loop vertex `(u, v)`: I16F16, each within `[0, 1]`.
pub type TrimPoint = [I16F16; 2];

/// One closed trim loop: the model's trim points `start .. start + len` (the last joins the
/// first), on patch `patch`. A model's loops are listed in patch order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TrimLoop {
    /// The patch it trims (index in the model).
    pub patch: u16,
    /// Index of its first point in the model's trim points.
    pub start: u32,
    /// Number of points, at least 3.
    pub len: u32,
}

/// A point in parameter space, I16F16 bits (0 ..= 2^16 inside the domain).
type P = [i64; 2];

/// Twice the signed area of `a b c`: positive when counter-clockwise (`u` right, `v` up).
#[inline]
const fn orient(a: P, b: P, c: P) -> i64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// Whether `r`, collinear with `p q`, lies on the closed segment `p q`.
#[inline]
const fn within(p: P, q: P, r: P) -> bool {
    let (lo_u, hi_u) = if p[0] < q[0] {
        (p[0], q[0])
    } else {
        (q[0], p[0])
    };
    let (lo_v, hi_v) = if p[1] < q[1] {
        (p[1], q[1])
    } else {
        (q[1], p[1])
    };
    r[0] >= lo_u && r[0] <= hi_u && r[1] >= lo_v && r[1] <= hi_v
}

/// Whether the signs are strictly opposite.
#[inline]
const fn opposite(a: i64, b: i64) -> bool {
    (a > 0 && b < 0) || (a < 0 && b > 0)
}

/// Whether the closed segments `a b` and `c d` have a point in common.
const fn segments_meet(a: P, b: P, c: P, d: P) -> bool {
    let (d1, d2) = (orient(c, d, a), orient(c, d, b));
    let (d3, d4) = (orient(a, b, c), orient(a, b, d));
    if opposite(d1, d2) && opposite(d3, d4) {
        return true;
    }
    (d1 == 0 && within(c, d, a))
        || (d2 == 0 && within(c, d, b))
        || (d3 == 0 && within(a, b, c))
        || (d4 == 0 && within(a, b, d))
}

/// Whether the segments cross at a point inside both.
#[inline]
fn cross_properly(a: P, b: P, c: P, d: P) -> bool {
    opposite(orient(c, d, a), orient(c, d, b)) && opposite(orient(a, b, c), orient(a, b, d))
}

const fn bits(p: TrimPoint) -> P {
    [p[0].to_bits() as i64, p[1].to_bits() as i64]
}

/// Checks trim loops against a model of `patches` patches: loops in patch order, each of at
/// least 3 points inside `[0, 1]²`, no zero-length edge, no two edges of a loop meeting except
/// adjacent ones at their shared point (and those not folding back), no two loops of a patch
/// meeting.
pub(crate) const fn check(
    loops: &[TrimLoop],
    points: &[TrimPoint],
    patches: usize,
) -> Result<(), PatchError> {
    let one = PARAM_ONE as i64;
    let mut l = 0;
    while l < loops.len() {
        let lp = loops[l];
        let patch = lp.patch as usize;
        if patch >= patches || (l > 0 && loops[l - 1].patch > lp.patch) {
            return Err(PatchError::TrimLoop { patch });
        }
        if lp.len < 3 || lp.start as u64 + lp.len as u64 > points.len() as u64 {
            return Err(PatchError::TrimLoop { patch });
        }
        let mut k = 0;
        while k < lp.len {
            let p = bits(points[(lp.start + k) as usize]);
            let q = bits(points[(lp.start + (k + 1) % lp.len) as usize]);
            if p[0] < 0 || p[0] > one || p[1] < 0 || p[1] > one || (p[0] == q[0] && p[1] == q[1]) {
                return Err(PatchError::TrimLoop { patch });
            }
            k += 1;
        }
        // Against itself and the later loops of its patch.
        let mut m = l;
        while m < loops.len() && loops[m].patch == lp.patch {
            if !loops_apart(loops[l], loops[m], points, l == m) {
                return Err(PatchError::TrimCrossing { patch });
            }
            m += 1;
        }
        l += 1;
    }
    Ok(())
}

/// Whether loops `a` and `b` (the same loop if `same`) meet only where a simple loop's
/// adjacent edges do.
const fn loops_apart(a: TrimLoop, b: TrimLoop, points: &[TrimPoint], same: bool) -> bool {
    let mut i = 0;
    while i < a.len {
        let p0 = bits(points[(a.start + i) as usize]);
        let p1 = bits(points[(a.start + (i + 1) % a.len) as usize]);
        let mut j = if same { i + 1 } else { 0 };
        while j < b.len {
            let q0 = bits(points[(b.start + j) as usize]);
            let q1 = bits(points[(b.start + (j + 1) % b.len) as usize]);
            let next = same && j == i + 1;
            let closing = same && i == 0 && j + 1 == b.len;
            if next || closing {
                // Adjacent: they share one point; they must not run back along each other.
                let (shared, x, y) = if next { (p1, p0, q1) } else { (p0, p1, q0) };
                let o = orient(shared, x, y);
                let dot = (x[0] - shared[0]) * (y[0] - shared[0])
                    + (x[1] - shared[1]) * (y[1] - shared[1]);
                if o == 0 && dot > 0 {
                    return false;
                }
            } else if segments_meet(p0, p1, q0, q1) {
                return false;
            }
            j += 1;
        }
        i += 1;
    }
    true
}

/// The trim loops of one patch.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Trims<'a> {
    pub(crate) loops: &'a [TrimLoop],
    pub(crate) points: &'a [TrimPoint],
}

impl<'a> Trims<'a> {
    /// No trims: the whole patch is kept.
    pub(crate) const NONE: Self = Trims {
        loops: &[],
        points: &[],
    };

    /// Whether the patch is untrimmed.
    pub(crate) fn is_empty(&self) -> bool {
        self.loops.is_empty()
    }

    /// The points of each loop.
    fn each_loop(&self) -> impl Iterator<Item = &'a [TrimPoint]> + 'a {
        let points = self.points;
        self.loops.iter().filter_map(move |lp| {
            let start = lp.start as usize;
            points.get(start..start.checked_add(lp.len as usize)?)
        })
    }

    /// Every edge of every loop, as point pairs.
    fn edges(&self) -> impl Iterator<Item = (P, P)> + 'a {
        self.each_loop().flat_map(|pts| {
            let next = pts.iter().skip(1).chain(pts.first());
            pts.iter().zip(next).map(|(&a, &b)| (bits(a), bits(b)))
        })
    }

    /// Every loop vertex.
    fn vertices(&self) -> impl Iterator<Item = P> + 'a {
        self.each_loop().flatten().map(|&p| bits(p))
    }

    /// Whether the point `c / n` is kept: inside an even number of loops (crossing number
    /// along `+u`, half-open in `v`, as the f64 reference counts).
    fn kept(&self, c: P, n: i64) -> bool {
        let mut inside = false;
        for (a, b) in self.edges() {
            let (a, b) = ([a[0] * n, a[1] * n], [b[0] * n, b[1] * n]);
            if (a[1] > c[1]) != (b[1] > c[1]) {
                // c[0] < a.u + (c.v − a.v)(b.u − a.u)/(b.v − a.v), without dividing.
                let (lhs, rhs) = ((c[0] - a[0]) * (b[1] - a[1]), (c[1] - a[1]) * (b[0] - a[0]));
                let left = if b[1] > a[1] { lhs < rhs } else { lhs > rhs };
                inside ^= left;
            }
        }
        !inside
    }
}

/// What trimming does to a triangle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Cut {
    /// No trim edge touches it and it is kept.
    Keep,
    /// No trim edge touches it and it is cut away.
    Drop,
    /// Trim edges touch it: [`clip`] it.
    Pieces,
}

/// The sides of `t` in order, `(t₀, t₁)`, `(t₁, t₂)`, `(t₂, t₀)`.
fn sides(t: &[P; 3]) -> [(P, P); 3] {
    let [a, b, c] = *t;
    [(a, b), (b, c), (c, a)]
}

/// The corners' bounding box `(lo, hi)`.
fn bounds(t: &[P; 3]) -> (P, P) {
    let [[u0, v0], [u1, v1], [u2, v2]] = *t;
    (
        [u0.min(u1).min(u2), v0.min(v1).min(v2)],
        [u0.max(u1).max(u2), v0.max(v1).max(v2)],
    )
}

/// Whether segment `a b` lies wholly outside the box `lo..=hi` on one axis.
fn apart(a: P, b: P, lo: P, hi: P) -> bool {
    let ([au, av], [bu, bv]) = (a, b);
    au.max(bu) < lo[0] || au.min(bu) > hi[0] || av.max(bv) < lo[1] || av.min(bv) > hi[1]
}

fn uv(p: Uv) -> P {
    [p[0] as i64, p[1] as i64]
}

fn to_uv(p: P) -> Uv {
    p.map(|c| c.clamp(0, PARAM_ONE as i64) as u32)
}

/// Sum of the corners (the centroid times 3).
fn corner_sum(t: &[P; 3]) -> P {
    let [[u0, v0], [u1, v1], [u2, v2]] = *t;
    [u0 + u1 + u2, v0 + v1 + v2]
}

/// How trimming treats triangle `t` (counter-clockwise in `(u, v)`).
pub(crate) fn classify(trims: &Trims<'_>, t: [Uv; 3]) -> Cut {
    if trims.is_empty() {
        return Cut::Keep;
    }
    let t = t.map(uv);
    let (lo, hi) = bounds(&t);
    let sides = sides(&t);
    let inside = |p: P| sides.iter().all(|&(c, d)| orient(c, d, p) >= 0);
    let touched = trims.edges().any(|(a, b)| {
        !apart(a, b, lo, hi)
            && (inside(a) || inside(b) || sides.iter().any(|&(c, d)| segments_meet(a, b, c, d)))
    });
    if touched {
        Cut::Pieces
    } else if trims.kept(corner_sum(&t), 3) {
        Cut::Keep
    } else {
        Cut::Drop
    }
}

/// `a / b` rounded to nearest (`b > 0`), `None` only if `b` is 0.
fn div_round(a: i64, b: i64) -> Option<i64> {
    (2 * a + b).checked_div_euclid(2 * b)
}

/// Where segment `e` (a triangle edge) and trim edge `s` cross (they cross properly),
/// rounded: computed from both segments in lexicographic order, so it depends on the two
/// segments only, not on which triangle or loop direction asks.
fn crossing(e: (P, P), s: (P, P)) -> P {
    let order = |(a, b): (P, P)| if b < a { (b, a) } else { (a, b) };
    let ((p0, p1), (q0, q1)) = (order(e), order(s));
    let d = [p1[0] - p0[0], p1[1] - p0[1]];
    let f = [q1[0] - q0[0], q1[1] - q0[1]];
    let den = d[0] * f[1] - d[1] * f[0];
    let num = (q0[0] - p0[0]) * f[1] - (q0[1] - p0[1]) * f[0];
    let (num, den) = if den < 0 { (-num, -den) } else { (num, den) };
    let along = |p: i64, d: i64| p + div_round(d * num, den).unwrap_or(0);
    [along(p0[0], d[0]), along(p0[1], d[1])]
}

/// A point on a triangle's boundary: on side `side` (from corner `side` to the next), at
/// `along` (0 at the corner) and `p`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Boundary {
    side: u8,
    along: i64,
    p: P,
}

/// Calls `emit` with each kept face (counter-clockwise, convex, at most `TRIM` points) of
/// triangle `t` (counter-clockwise in `(u, v)`, touched by trim edges); returns how many
/// (sub-)triangles were kept or dropped whole for want of room.
pub(crate) fn clip<const TRIM: usize>(
    trims: &Trims<'_>,
    t: [Uv; 3],
    mut emit: impl FnMut(&[Uv]),
) -> u32 {
    let mut overflows = 0;
    let mut stack = [[[0i64; 2]; 3]; TRIM];
    let mut len = 0;
    let whole = |t: &[P; 3], emit: &mut dyn FnMut(&[Uv])| {
        if trims.kept(corner_sum(t), 3) {
            emit(&t.map(to_uv));
        }
    };
    let push = |stack: &mut [[P; 3]; TRIM], len: &mut usize, t: [P; 3]| -> bool {
        match stack.get_mut(*len) {
            Some(slot) => {
                *slot = t;
                *len += 1;
                true
            }
            None => false,
        }
    };
    if !push(&mut stack, &mut len, t.map(uv)) {
        whole(&t.map(uv), &mut emit);
        return 1;
    }
    while let Some(len_now) = len.checked_sub(1) {
        len = len_now;
        let Some(&t) = stack.get(len) else {
            break;
        };
        let subs = match inner_vertex(trims, &t) {
            Some((v, None)) => [
                Some([v, t[0], t[1]]),
                Some([v, t[1], t[2]]),
                Some([v, t[2], t[0]]),
            ],
            Some((v, Some(side))) => {
                let c = |k: usize| t[(side + k) % 3];
                [Some([v, c(1), c(2)]), Some([v, c(2), c(0)]), None]
            }
            None => {
                if !faces::<TRIM>(trims, &t, &mut emit) {
                    overflows += 1;
                    whole(&t, &mut emit);
                }
                continue;
            }
        };
        for sub in subs.into_iter().flatten() {
            if !push(&mut stack, &mut len, sub) {
                overflows += 1;
                whole(&sub, &mut emit);
            }
        }
    }
    overflows
}

/// The first trim vertex strictly inside `t`, or inside one of its sides (with that side).
fn inner_vertex(trims: &Trims<'_>, t: &[P; 3]) -> Option<(P, Option<usize>)> {
    trims.vertices().find_map(|p| {
        let o = sides(t).map(|(a, b)| orient(a, b, p));
        match o {
            [a, b, c] if a > 0 && b > 0 && c > 0 => Some((p, None)),
            _ => {
                let zeros = o.iter().filter(|&&x| x == 0).count();
                let side = o.iter().position(|&x| x == 0)?;
                (zeros == 1 && o.iter().all(|&x| x >= 0)).then_some((p, Some(side)))
            }
        }
    })
}

/// The faces of `t` (no trim vertex inside it or inside a side) between the trim edges that
/// cross it, the kept ones passed to `emit`; `false` if they need more than `TRIM` points.
fn faces<const TRIM: usize>(trims: &Trims<'_>, t: &[P; 3], emit: &mut dyn FnMut(&[Uv])) -> bool {
    let mut points = [Boundary {
        side: 0,
        along: 0,
        p: [0; 2],
    }; TRIM];
    let mut n = 0;
    let add = |points: &mut [Boundary; TRIM], n: &mut usize, b: Boundary| -> Option<()> {
        *points.get_mut(*n)? = b;
        *n += 1;
        Some(())
    };
    for (side, &p) in t.iter().enumerate() {
        let corner = Boundary {
            side: side as u8,
            along: 0,
            p,
        };
        if add(&mut points, &mut n, corner).is_none() {
            return false;
        }
    }
    // Chords as pairs of boundary points, found edge by trim edge.
    let mut chords = [(0usize, 0usize); TRIM];
    let mut chord_count = 0;
    for (a, b) in trims.edges() {
        let Some((x, y)) = chord(t, (a, b)) else {
            continue;
        };
        let (Some(()), Some(())) = (add(&mut points, &mut n, x), add(&mut points, &mut n, y))
        else {
            return false;
        };
        let Some(slot) = chords.get_mut(chord_count) else {
            return false;
        };
        *slot = (n - 2, n - 1);
        chord_count += 1;
    }
    let (points, chords) = (
        points.get_mut(..n).unwrap_or_default(),
        chords.get_mut(..chord_count).unwrap_or_default(),
    );
    // Boundary order, counter-clockwise from corner 0; equal positions merge.
    let mut order = [0usize; TRIM];
    let order = order.get_mut(..n).unwrap_or_default();
    for (k, o) in order.iter_mut().enumerate() {
        *o = k;
    }
    let key = |k: usize| points.get(k).map(|b| (b.side, b.along));
    sort_by_key(order, |&k| key(k));
    let mut rank = [0usize; TRIM];
    let mut distinct = 0;
    for (pos, &k) in order.iter().enumerate() {
        let new = pos == 0 || key(k) != order.get(pos - 1).and_then(|&j| key(j));
        if new {
            distinct += 1;
        }
        if let Some(r) = rank.get_mut(k) {
            *r = distinct - 1;
        }
    }
    // The distinct boundary points in order.
    let mut ring = [[0i64; 2]; TRIM];
    for (k, b) in points.iter().enumerate() {
        if let Some(slot) = rank.get(k).and_then(|&r| ring.get_mut(r)) {
            *slot = b.p;
        }
    }
    for c in chords.iter_mut() {
        let (i, j) = (
            rank.get(c.0).copied().unwrap_or(0),
            rank.get(c.1).copied().unwrap_or(0),
        );
        *c = (i.min(j), i.max(j));
    }
    // Chords ending at j, innermost (largest i) first.
    sort_by_key(chords, |&(i, j)| (j, core::cmp::Reverse(i)));
    let ring = ring.get(..distinct).unwrap_or_default();
    let mut face = [[0u32; 2]; TRIM];
    let mut emit_face = |indices: &[usize]| {
        let mut count = 0;
        let mut sum = [0i64; 2];
        for (slot, p) in face
            .iter_mut()
            .zip(indices.iter().filter_map(|&i| ring.get(i)))
        {
            *slot = to_uv(*p);
            sum = [sum[0] + p[0], sum[1] + p[1]];
            count += 1;
        }
        if count >= 3 && trims.kept(sum, count as i64) {
            emit(face.get(..count).unwrap_or_default());
        }
    };
    // One walk round the boundary: a chord (i, j) closes the face of the points between i
    // and j not yet closed by an inner chord.
    let mut stack = [0usize; TRIM];
    let mut top = 0;
    let mut previous = None;
    for j in 0..distinct {
        if let Some(slot) = stack.get_mut(top) {
            *slot = j;
            top += 1;
        }
        for &(i, jj) in chords.iter().filter(|&&(_, jj)| jj == j) {
            if previous == Some((i, jj)) || i == jj {
                continue;
            }
            previous = Some((i, jj));
            let Some(from) = stack
                .get(..top)
                .and_then(|s| s.iter().rposition(|&k| k == i))
            else {
                // Crossing chords (invalid loops): this one is skipped.
                continue;
            };
            emit_face(stack.get(from..top).unwrap_or_default());
            // The points between i and j are closed: j follows i.
            top = from + 1;
            if let Some(slot) = stack.get_mut(top) {
                *slot = j;
                top += 1;
            }
        }
    }
    emit_face(stack.get(..top).unwrap_or_default());
    true
}

/// Sorts a short slice by `key`: insertion sort, which (unlike `core`'s sorts) has no panic
/// path for a key that is not a total order.
fn sort_by_key<T: Copy, K: Ord>(s: &mut [T], key: impl Fn(&T) -> K) {
    for i in 1..s.len() {
        let mut j = i;
        while let (Some(&a), Some(&b)) = (s.get(j.wrapping_sub(1)), s.get(j)) {
            if key(&a) <= key(&b) {
                break;
            }
            if let Some(x) = s.get_mut(j - 1) {
                *x = b;
            }
            if let Some(y) = s.get_mut(j) {
                *y = a;
            }
            j -= 1;
        }
    }
}

/// The chord that trim edge `s` makes across `t` (no trim vertex inside `t` or inside one of
/// its sides): its two boundary points, or `None` if it only touches `t` or runs along a side.
fn chord(t: &[P; 3], s: (P, P)) -> Option<(Boundary, Boundary)> {
    let (a, b) = s;
    let (lo, hi) = bounds(t);
    if apart(a, b, lo, hi) {
        return None;
    }
    let mut hits = [None; 2];
    let mut count = 0;
    let mut hit = |h: Boundary| {
        if hits.iter().flatten().any(|x: &Boundary| x.p == h.p) {
            return;
        }
        if let Some(slot) = hits.get_mut(count) {
            *slot = Some(h);
        }
        count += 1;
    };
    for (side, (c, d)) in sides(t).into_iter().enumerate() {
        if orient(a, b, c) == 0 && within(a, b, c) {
            hit(Boundary {
                side: side as u8,
                along: 0,
                p: c,
            });
        } else if cross_properly(a, b, c, d) {
            let p = crossing((c, d), s);
            let along = (p[0] - c[0]) * (d[0] - c[0]) + (p[1] - c[1]) * (d[1] - c[1]);
            let full = (d[0] - c[0]) * (d[0] - c[0]) + (d[1] - c[1]) * (d[1] - c[1]);
            // Rounding can put the point on a corner; it is that corner then.
            let h = if along <= 0 {
                Boundary {
                    side: side as u8,
                    along: 0,
                    p: c,
                }
            } else if along >= full {
                Boundary {
                    side: ((side + 1) % 3) as u8,
                    along: 0,
                    p: d,
                }
            } else {
                Boundary {
                    side: side as u8,
                    along,
                    p,
                }
            };
            hit(h);
        }
    }
    let [Some(x), Some(y)] = hits else {
        return None;
    };
    if count != 2 {
        return None;
    }
    // A chord has its middle strictly inside (not along a side).
    let m = [x.p[0] + y.p[0], x.p[1] + y.p[1]];
    let doubled = t.map(|c| [2 * c[0], 2 * c[1]]);
    (0..3)
        .all(|k| orient(doubled[k], doubled[(k + 1) % 3], m) > 0)
        .then_some((x, y))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec;
    use std::vec::Vec;

    fn q(u: f64, v: f64) -> TrimPoint {
        [I16F16::from_num(u), I16F16::from_num(v)]
    }

    fn uvp(u: f64, v: f64) -> Uv {
        [(u * 65536.0) as u32, (v * 65536.0) as u32]
    }

    fn area(poly: &[Uv]) -> f64 {
        let p: Vec<(f64, f64)> = poly
            .iter()
            .map(|&[u, v]| (u as f64 / 65536.0, v as f64 / 65536.0))
            .collect();
        (0..p.len())
            .map(|k| {
                let (a, b) = (p[k], p[(k + 1) % p.len()]);
                a.0 * b.1 - b.0 * a.1
            })
            .sum::<f64>()
            / 2.0
    }

    /// Even-odd in f64, as the reference counts.
    fn kept_f64(loops: &[Vec<(f64, f64)>], u: f64, v: f64) -> bool {
        let mut inside = false;
        for l in loops {
            for k in 0..l.len() {
                let (a, b) = (l[k], l[(k + 1) % l.len()]);
                if (a.1 > v) != (b.1 > v) && u < a.0 + (v - a.1) / (b.1 - a.1) * (b.0 - a.0) {
                    inside = !inside;
                }
            }
        }
        !inside
    }

    /// A hole (a 12-gon) with an island (a triangle) inside it.
    /// Loops as f64 polylines.
    type Polylines = Vec<Vec<(f64, f64)>>;

    fn model() -> (Vec<TrimLoop>, Vec<TrimPoint>, Polylines) {
        let mut hole: Vec<(f64, f64)> = (0..12)
            .map(|k| {
                let a = k as f64 * std::f64::consts::TAU / 12.0;
                (0.5 + 0.3 * a.cos(), 0.47 + 0.28 * a.sin())
            })
            .collect();
        hole.iter_mut()
            .for_each(|p| *p = (q(p.0, p.1)[0].to_num(), q(p.0, p.1)[1].to_num()));
        let island = vec![(0.4, 0.42), (0.6, 0.4296875), (0.5, 0.6)];
        let f = vec![hole.clone(), island.clone()];
        let points: Vec<TrimPoint> = hole.iter().chain(&island).map(|&(u, v)| q(u, v)).collect();
        let loops = vec![
            TrimLoop {
                patch: 0,
                start: 0,
                len: 12,
            },
            TrimLoop {
                patch: 0,
                start: 12,
                len: 3,
            },
        ];
        (loops, points, f)
    }

    /// Cut triangles cover exactly the kept part of each triangle: areas against sampling.
    #[test]
    fn kept_faces_cover_the_kept_part_of_each_triangle() {
        let (loops, points, f) = model();
        let trims = Trims {
            loops: &loops,
            points: &points,
        };
        let triangles = [
            [uvp(0.0, 0.0), uvp(1.0, 0.0), uvp(0.0, 1.0)],
            [uvp(1.0, 0.0), uvp(1.0, 1.0), uvp(0.0, 1.0)],
            [uvp(0.25, 0.25), uvp(0.75, 0.3), uvp(0.5, 0.75)],
            [uvp(0.45, 0.45), uvp(0.55, 0.45), uvp(0.5, 0.55)],
            [uvp(0.1, 0.1), uvp(0.3, 0.1), uvp(0.1, 0.3)],
        ];
        for t in triangles {
            let mut polys: Vec<Vec<Uv>> = Vec::new();
            let overflows = clip::<64>(&trims, t, |p| polys.push(p.to_vec()));
            assert_eq!(overflows, 0);
            let got: f64 = polys.iter().map(|p| area(p)).sum();
            assert!(polys.iter().all(|p| area(p) > 0.0), "{t:?}");
            // Sample the triangle's bounding box on a fine grid.
            let tf = t.map(|[u, v]| (u as f64 / 65536.0, v as f64 / 65536.0));
            let lo = (
                tf[0].0.min(tf[1].0).min(tf[2].0),
                tf[0].1.min(tf[1].1).min(tf[2].1),
            );
            let hi = (
                tf[0].0.max(tf[1].0).max(tf[2].0),
                tf[0].1.max(tf[1].1).max(tf[2].1),
            );
            let (mut inside, mut kept) = (0usize, 0usize);
            let n = 500;
            for i in 0..n {
                for j in 0..n {
                    let u = lo.0 + (hi.0 - lo.0) * (i as f64 + 0.5) / n as f64;
                    let v = lo.1 + (hi.1 - lo.1) * (j as f64 + 0.5) / n as f64;
                    let o = |a: (f64, f64), b: (f64, f64)| {
                        (b.0 - a.0) * (v - a.1) - (b.1 - a.1) * (u - a.0) >= 0.0
                    };
                    if o(tf[0], tf[1]) && o(tf[1], tf[2]) && o(tf[2], tf[0]) {
                        inside += 1;
                        kept += kept_f64(&f, u, v) as usize;
                    }
                }
            }
            let want = area(&t) * kept as f64 / inside as f64;
            assert!(
                (got - want).abs() < 0.01 * area(&t),
                "{t:?}: {got} against {want}"
            );
            // Every emitted point is inside the triangle.
            for p in polys.iter().flatten() {
                let p = uv(*p);
                let c = t.map(uv);
                assert!((0..3).all(|k| orient(c[k], c[(k + 1) % 3], p) >= -(1 << 17)));
            }
        }
    }

    #[test]
    fn untouched_triangles_are_classified_by_parity() {
        let (loops, points, _) = model();
        let trims = Trims {
            loops: &loops,
            points: &points,
        };
        let far = [uvp(0.0, 0.0), uvp(0.1, 0.0), uvp(0.0, 0.1)];
        assert_eq!(classify(&trims, far), Cut::Keep);
        let in_hole = [uvp(0.3, 0.45), uvp(0.35, 0.45), uvp(0.3, 0.5)];
        assert_eq!(classify(&trims, in_hole), Cut::Drop);
        let on_island = [uvp(0.48, 0.45), uvp(0.52, 0.45), uvp(0.5, 0.5)];
        assert_eq!(classify(&trims, on_island), Cut::Keep);
        let across = [uvp(0.1, 0.4), uvp(0.3, 0.4), uvp(0.2, 0.5)];
        assert_eq!(classify(&trims, across), Cut::Pieces);
    }

    #[test]
    fn a_shared_edge_is_cut_at_the_same_point_from_either_side() {
        let (loops, points, _) = model();
        let trims = Trims {
            loops: &loops,
            points: &points,
        };
        // Two triangles sharing the edge (0.1, 0.2)–(0.4, 0.9).
        let (a, b) = (uvp(0.1, 0.2), uvp(0.4, 0.9));
        let left = [a, b, uvp(0.0, 0.8)];
        let right = [b, a, uvp(0.6, 0.1)];
        let on_edge = |t: [Uv; 3]| {
            let mut found = Vec::new();
            clip::<64>(&trims, t, |p| {
                for &x in p {
                    // Within two units of the edge (crossing points are rounded).
                    let o = orient(uv(a), uv(b), uv(x)) as f64;
                    let d = [0, 1].map(|k| uv(b)[k] as f64 - uv(a)[k] as f64);
                    let near = o.abs() <= 2.0 * (d[0] * d[0] + d[1] * d[1]).sqrt();
                    if near && x != a && x != b {
                        found.push(x);
                    }
                }
            });
            found.sort();
            found.dedup();
            found
        };
        let (l, r) = (on_edge(left), on_edge(right));
        assert!(!l.is_empty());
        assert_eq!(l, r);
    }

    #[test]
    fn too_little_room_degrades_to_whole_triangles_and_says_so() {
        let (loops, points, _) = model();
        let trims = Trims {
            loops: &loops,
            points: &points,
        };
        let t = [uvp(0.0, 0.0), uvp(1.0, 0.0), uvp(0.0, 1.0)];
        let (mut a, mut b) = (Vec::new(), Vec::new());
        let n = clip::<4>(&trims, t, |p| a.push(p.to_vec()));
        let m = clip::<4>(&trims, t, |p| b.push(p.to_vec()));
        assert!(n > 0);
        assert_eq!((n, &a), (m, &b));
    }

    #[test]
    fn bad_loops_are_rejected() {
        let square = [q(0.2, 0.2), q(0.8, 0.2), q(0.8, 0.8), q(0.2, 0.8)];
        let bow = [q(0.2, 0.2), q(0.8, 0.8), q(0.8, 0.2), q(0.2, 0.8)];
        let one = |len| {
            [TrimLoop {
                patch: 0,
                start: 0,
                len,
            }]
        };
        assert_eq!(check(&one(4), &square, 1), Ok(()));
        assert_eq!(
            check(&one(4), &bow, 1),
            Err(PatchError::TrimCrossing { patch: 0 })
        );
        assert_eq!(
            check(&one(2), &square, 1),
            Err(PatchError::TrimLoop { patch: 0 })
        );
        assert_eq!(
            check(&one(5), &square, 1),
            Err(PatchError::TrimLoop { patch: 0 })
        );
        assert_eq!(
            check(&one(4), &square, 0),
            Err(PatchError::TrimLoop { patch: 0 })
        );
        let outside = [q(0.2, 0.2), q(1.5, 0.2), q(0.8, 0.8)];
        assert_eq!(
            check(&one(3), &outside, 1),
            Err(PatchError::TrimLoop { patch: 0 })
        );
        let fold = [q(0.2, 0.2), q(0.8, 0.2), q(0.5, 0.2)];
        assert_eq!(
            check(&one(3), &fold, 1),
            Err(PatchError::TrimCrossing { patch: 0 })
        );
        // Two loops of a patch that meet.
        let two = [
            q(0.2, 0.2),
            q(0.6, 0.2),
            q(0.4, 0.6),
            q(0.5, 0.1),
            q(0.6, 0.5),
            q(0.4, 0.5),
        ];
        let loops = [
            TrimLoop {
                patch: 0,
                start: 0,
                len: 3,
            },
            TrimLoop {
                patch: 0,
                start: 3,
                len: 3,
            },
        ];
        assert_eq!(
            check(&loops, &two, 1),
            Err(PatchError::TrimCrossing { patch: 0 })
        );
    }
}
