//! Bounding volumes for the fixed tracer: a hierarchy of axis-aligned boxes over the scene's
//! bounded objects, built into caller-provided slices (on the host by `sim export`, which
//! writes it as `static` data, or on the target at start-up) and walked without recursion.
//!
//! Nodes are stored depth first: an inner node's first child follows it, its second child is
//! at `second`; a leaf holds `count` entries of `items` from `first`. Unbounded objects
//! (planes) are not in the tree and are tested by every ray.
//!
//! ## Bit budget
//!
//! A box test computes `(bound − origin) · (1/dir)` per axis: the difference is below 2^13
//! world units (2^29 raw, an `i32`), the reciprocal of a direction component of at least 2^-15
//! (2 raw steps) is at most 2^15 (below 2^31 raw in 16 fraction bits, an `i32`), so the
//! product is one 32 × 32 → 64-bit multiply, below 2^60 with 32 fraction bits: no overflow.
//! Components of 0 or ±2^-16 are treated as parallel to the axis (their drift over a ray
//! shorter than 2^10 units stays inside the boxes' padding [`PAD`]).

use crate::trace::intersect::Ray;
use crate::trace::shape::{Object, Shape};
use crate::trace::vector::{Vec3, MAX_COORD};
use fixed::types::{I16F16, I32F32};

/// How deep a hierarchy may be: the traversal stack's size.
pub const MAX_BVH_DEPTH: usize = 32;
/// How far every node's box extends beyond what it holds: 2^-6 world units, above the box
/// test's rounding (t · 2^-16 for t < 2^10).
pub const PAD: I16F16 = I16F16::from_bits(1 << 10);
/// Most objects in one leaf.
pub const LEAF_SIZE: usize = 8;
/// Centre bins per axis of the surface-area-heuristic build.
const BINS: usize = 16;
/// Cost of one box test against one object test in the surface-area heuristic: on the firmware
/// (thumbv7em, the classic scene) a box test with its share of the walk costs about 120
/// instructions and an object test about 230 (`cargo xtask trace` with two trees solved for
/// both), so 1 : 2.
const BOX_COST: u64 = 1;
/// Cost of one object test.
const OBJECT_COST: u64 = 2;

/// One node: a box and either two children or a range of items.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BvhNode {
    /// Minimum corner of the box around everything below.
    pub min: Vec3,
    /// Maximum corner.
    pub max: Vec3,
    /// Inner node: index of the second child (the first is the next node). Leaf: index of its
    /// first entry in the items.
    pub index: u32,
    /// Leaf: number of items (≥ 1). Inner node: 0.
    pub count: u16,
    /// Inner node: the axis (0, 1, 2) its children were split along (the nearer child is
    /// visited first).
    pub axis: u8,
}

/// Why a hierarchy was not built or not accepted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BvhError {
    /// The node or item buffer is too small (`nodes` needs `2 · objects`, `items` `objects`).
    Capacity,
    /// A node refers outside the node or item arrays, or to a node before itself.
    Malformed,
    /// The tree is deeper than [`MAX_BVH_DEPTH`].
    TooDeep,
}

impl core::fmt::Display for BvhError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            BvhError::Capacity => "the bounding-volume buffers are too small",
            BvhError::Malformed => "a bounding-volume node refers outside the tree",
            BvhError::TooDeep => "the bounding-volume hierarchy is too deep",
        })
    }
}

impl core::error::Error for BvhError {}

/// A bounding-volume hierarchy over a scene's objects, borrowed (it may be `static` data).
#[derive(Clone, Copy, Debug)]
pub struct Bvh<'a> {
    nodes: &'a [BvhNode],
    /// Object ids: the tree's leaves' (`..bounded`), then the unbounded objects'.
    items: &'a [u32],
    bounded: usize,
}

/// The box around a shape, or `None` for an unbounded one (a plane).
pub fn bounds(shape: &Shape<'_>) -> Option<(Vec3, Vec3)> {
    let around = |c: Vec3, r: Vec3| Some((c.sub(r), c.add(r)));
    let points = |ps: &[Vec3]| {
        let first = *ps.first()?;
        Some(
            ps.iter()
                .fold((first, first), |(lo, hi), p| (min3(lo, *p), max3(hi, *p))),
        )
    };
    match shape {
        Shape::Sphere(s) => around(
            s.centre,
            Vec3 {
                x: s.radius,
                y: s.radius,
                z: s.radius,
            },
        ),
        Shape::Plane(_) => None,
        Shape::Polygon(p) => points(p.vertices),
        Shape::Triangle(t) => points(&t.vertices),
        Shape::Box(b) => Some((b.min, b.max)),
        Shape::Ellipsoid(e) => around(e.centre, e.radii),
        Shape::Frustum(f) => {
            let top = f.base.along(f.axis, f.height);
            let r = f.r0.max(f.r1);
            let (lo, hi) = points(&[f.base, top])?;
            let pad = Vec3 { x: r, y: r, z: r };
            Some((lo.sub(pad), hi.add(pad)))
        }
    }
}

/// The centre of a box, raw bits (sum halved; no overflow in the envelope).
fn centre(lo: Vec3, hi: Vec3, axis: u8) -> i32 {
    let (a, b) = (lo.bits(), hi.bits());
    let i = usize::from(axis.min(2));
    (a.get(i).copied().unwrap_or(0) >> 1) + (b.get(i).copied().unwrap_or(0) >> 1)
}

/// Builds a hierarchy over the bounded objects of `objects` into `nodes` and `items`.
/// Returns the nodes used, the items used and how many of those are in the tree: `items`
/// holds the tree's object ids in leaf order, then the unbounded objects' ids (tested by every
/// ray). Each node splits where the surface-area heuristic finds it cheapest (binned
/// centres, see `best_split`) or becomes a leaf of at most [`LEAF_SIZE`] objects when that is
/// cheaper; nodes depth first with no gaps; no recursion (a work stack of
/// [`MAX_BVH_DEPTH`] entries). `nodes` needs at most `2 · objects − 1` entries, `items`
/// `objects`.
pub fn build(
    objects: &[Object<'_>],
    nodes: &mut [BvhNode],
    items: &mut [u32],
) -> Result<(usize, usize, usize), BvhError> {
    let mut bounded = 0;
    for (id, o) in objects.iter().enumerate() {
        if bounds(&o.shape).is_some() {
            *items.get_mut(bounded).ok_or(BvhError::Capacity)? = id as u32;
            bounded += 1;
        }
    }
    let mut total = bounded;
    for (id, o) in objects.iter().enumerate() {
        if bounds(&o.shape).is_none() {
            *items.get_mut(total).ok_or(BvhError::Capacity)? = id as u32;
            total += 1;
        }
    }
    if bounded == 0 {
        return Ok((0, total, 0));
    }
    let object_box = |id: u32| {
        objects
            .get(id as usize)
            .and_then(|o| bounds(&o.shape))
            .unwrap_or((Vec3::ZERO, Vec3::ZERO))
    };
    // Work: (parent whose second child this is, item range, depth). The first child is
    // popped right after its parent, so it lands at the parent's index + 1.
    type Work = (Option<usize>, usize, usize, usize);
    let mut work: heapless::Vec<Work, { MAX_BVH_DEPTH + 1 }> = heapless::Vec::new();
    let mut used = 0;
    work.push((None, 0, bounded, 1))
        .map_err(|_| BvhError::TooDeep)?;
    while let Some((parent, start, end, depth)) = work.pop() {
        let node = used;
        used += 1;
        if let Some(p) = parent {
            nodes.get_mut(p).ok_or(BvhError::Capacity)?.index = node as u32;
        }
        let range = items.get_mut(start..end).ok_or(BvhError::Capacity)?;
        let mut lo = Vec3 {
            x: MAX_COORD,
            y: MAX_COORD,
            z: MAX_COORD,
        };
        let mut hi = lo.neg();
        let (mut clo, mut chi) = (lo, hi); // the centres' box
        for id in range.iter() {
            let (a, b) = object_box(*id);
            let c = Vec3::from_bits(centre(a, b, 0), centre(a, b, 1), centre(a, b, 2));
            (lo, hi) = (min3(lo, a), max3(hi, b));
            (clo, chi) = (min3(clo, c), max3(chi, c));
        }
        // Padded by PAD so rounding in the box test (the reciprocal's 2^-16 relative error,
        // times t) cannot reject a ray that meets an object at the box's face.
        let pad = Vec3 {
            x: PAD,
            y: PAD,
            z: PAD,
        };
        let area = half_area(lo, hi);
        let (lo, hi) = (lo.sub(pad), hi.add(pad));
        let slot = nodes.get_mut(node).ok_or(BvhError::Capacity)?;
        let count = end - start;
        // A split must leave parts a median split can still finish within the depth limit.
        let room = (LEAF_SIZE as u64) << (MAX_BVH_DEPTH.saturating_sub(depth + 1)).min(40);
        let split = best_split(range, &object_box, clo, chi)
            .filter(|s| (s.left.max(count - s.left) as u64) <= room);
        let leaf_cost = u128::from(OBJECT_COST) * count as u128 * area;
        let (axis, left) = match split {
            Some(s) if count > LEAF_SIZE || s.cost < leaf_cost => (s.axis, s.left),
            _ if count <= LEAF_SIZE => {
                *slot = BvhNode {
                    min: lo,
                    max: hi,
                    index: start as u32,
                    count: count as u16,
                    axis: 0,
                };
                continue;
            }
            // No useful split by the heuristic (the centres coincide, or a part would be too
            // deep): the median of the centres along their widest axis.
            _ => (widest_axis(clo, chi), count / 2),
        };
        *slot = BvhNode {
            min: lo,
            max: hi,
            index: 0,
            count: 0,
            axis,
        };
        heap_sort_by_key(range, |id| {
            let (a, b) = object_box(id);
            (centre(a, b, axis), id)
        });
        if depth >= MAX_BVH_DEPTH {
            return Err(BvhError::TooDeep);
        }
        let mid = start + left;
        work.push((Some(node), mid, end, depth + 1))
            .map_err(|_| BvhError::TooDeep)?;
        work.push((None, start, mid, depth + 1))
            .map_err(|_| BvhError::TooDeep)?;
    }
    Ok((used, total, bounded))
}

/// The axis (0, 1, 2) along which the box `lo..hi` is widest (the first of equal ones).
fn widest_axis(lo: Vec3, hi: Vec3) -> u8 {
    let extent = hi.sub(lo);
    if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    }
}

/// Half the surface area of the box `lo..hi` in raw units (2^-32 square world units): below
/// 3 · 2^60 for boxes within the envelope, so it and its products with counts fit a `u128`.
fn half_area(lo: Vec3, hi: Vec3) -> u128 {
    let [x, y, z] = hi
        .sub(lo)
        .bits()
        .map(|e| u128::from(e.max(0).unsigned_abs()));
    x * y + y * z + z * x
}

/// The split the surface-area heuristic prefers.
#[derive(Clone, Copy, Debug)]
struct Split {
    /// Axis of the split.
    axis: u8,
    /// Objects on the lower side (the first ones when sorted by centre along `axis`).
    left: usize,
    /// Its cost: `2 · BOX_COST · area + OBJECT_COST · (area_left · left + area_right · right)`,
    /// in half-area units, comparable with a leaf's `OBJECT_COST · count · area`.
    cost: u128,
}

/// The cheapest split of `range` by the surface-area heuristic: per axis the objects' centres
/// fall into [`BINS`] equal bins over the centres' box `clo..chi`, and every boundary between
/// bins is costed with the boxes around the objects on either side. Integer arithmetic only, so
/// the host and the target build the same tree. `None` when the centres coincide.
fn best_split(
    range: &[u32],
    object_box: &impl Fn(u32) -> (Vec3, Vec3),
    clo: Vec3,
    chi: Vec3,
) -> Option<Split> {
    const EMPTY: (Vec3, Vec3, usize) = (
        Vec3 {
            x: MAX_COORD,
            y: MAX_COORD,
            z: MAX_COORD,
        },
        Vec3 {
            x: I16F16::MIN,
            y: I16F16::MIN,
            z: I16F16::MIN,
        },
        0,
    );
    let merge = |(alo, ahi, an): (Vec3, Vec3, usize), (blo, bhi, bn): (Vec3, Vec3, usize)| {
        (min3(alo, blo), max3(ahi, bhi), an + bn)
    };
    let mut best: Option<Split> = None;
    for axis in 0..3u8 {
        let i = usize::from(axis);
        let (c0, c1) = (
            i64::from(clo.bits().get(i).copied().unwrap_or(0)),
            i64::from(chi.bits().get(i).copied().unwrap_or(0)),
        );
        if c1 <= c0 {
            continue;
        }
        let mut bins = [EMPTY; BINS];
        for id in range {
            let (a, b) = object_box(*id);
            // (c − c0) · BINS / (c1 − c0 + 1) lies in 0..BINS: below 2^31 · 2^4, no overflow.
            let k = ((i64::from(centre(a, b, axis)) - c0) * BINS as i64).checked_div(c1 - c0 + 1);
            if let Some(bin) = k
                .and_then(|k| usize::try_from(k).ok())
                .and_then(|k| bins.get_mut(k))
            {
                *bin = merge(*bin, (a, b, 1));
            }
        }
        for cut in 1..BINS {
            let side = |part: &[(Vec3, Vec3, usize)]| part.iter().copied().fold(EMPTY, merge);
            let (l, r) = (
                side(bins.get(..cut).unwrap_or(&[])),
                side(bins.get(cut..).unwrap_or(&[])),
            );
            if l.2 == 0 || r.2 == 0 {
                continue;
            }
            let (node_lo, node_hi) = (min3(l.0, r.0), max3(l.1, r.1));
            let cost = 2 * u128::from(BOX_COST) * half_area(node_lo, node_hi)
                + u128::from(OBJECT_COST)
                    * (half_area(l.0, l.1) * l.2 as u128 + half_area(r.0, r.1) * r.2 as u128);
            if best.is_none_or(|b| cost < b.cost) {
                best = Some(Split {
                    axis,
                    left: l.2,
                    cost,
                });
            }
        }
    }
    best
}

/// Heapsort of `v` by `key`: in place, O(n log n), and without the panic that core's sorts keep
/// for a key that is not a total order (ours are integer tuples).
pub(crate) fn heap_sort_by_key<T: Copy, K: Ord>(v: &mut [T], key: impl Fn(T) -> K) {
    let k = |v: &[T], i: usize| v.get(i).map(|x| key(*x));
    let sift_down = |v: &mut [T], mut root: usize, end: usize| loop {
        let mut child = 2 * root + 1;
        if child >= end {
            break;
        }
        if child + 1 < end && k(v, child) < k(v, child + 1) {
            child += 1;
        }
        if k(v, root) >= k(v, child) {
            break;
        }
        if let Some([first, .., last]) = v.get_mut(root..=child) {
            core::mem::swap(first, last);
        }
        root = child;
    };
    let n = v.len();
    for root in (0..n / 2).rev() {
        sift_down(v, root, n);
    }
    for end in (1..n).rev() {
        if let Some([first, .., last]) = v.get_mut(..=end) {
            core::mem::swap(first, last);
        }
        sift_down(v, 0, end);
    }
}

fn min3(a: Vec3, b: Vec3) -> Vec3 {
    Vec3 {
        x: a.x.min(b.x),
        y: a.y.min(b.y),
        z: a.z.min(b.z),
    }
}

fn max3(a: Vec3, b: Vec3) -> Vec3 {
    Vec3 {
        x: a.x.max(b.x),
        y: a.y.max(b.y),
        z: a.z.max(b.z),
    }
}

impl<'a> Bvh<'a> {
    /// A hierarchy from its nodes and items as [`build`] made them (for example `static` data
    /// from `sim export`), checked: `items` names each of the scene's `objects` objects exactly
    /// once, the first `bounded` of them (the bounded ones) in the tree's leaves; the nodes are
    /// in preorder with every node reachable once; the leaves cover the tree's items exactly;
    /// the depth is at most [`MAX_BVH_DEPTH`].
    pub fn new(
        nodes: &'a [BvhNode],
        items: &'a [u32],
        bounded: usize,
        objects: &[Object<'_>],
    ) -> Result<Bvh<'a>, BvhError> {
        if items.len() != objects.len() || bounded > items.len() {
            return Err(BvhError::Malformed);
        }
        // Each id once: every id names an object on the right side of `bounded`, there are
        // as many ids as objects, and none repeats an earlier one (a quadratic check, run once
        // per scene: 66 objects are 2,145 comparisons, 1,282 about 820,000).
        for (k, id) in items.iter().enumerate() {
            let ok = match objects.get(*id as usize) {
                Some(o) => (k < bounded) == bounds(&o.shape).is_some(),
                None => false,
            };
            if !ok || items.get(..k).is_some_and(|earlier| earlier.contains(id)) {
                return Err(BvhError::Malformed);
            }
        }
        for (i, n) in nodes.iter().enumerate() {
            if n.count == 0 {
                let second = n.index as usize;
                if second <= i + 1 || second >= nodes.len() {
                    return Err(BvhError::Malformed);
                }
            } else if (n.index as usize).saturating_add(usize::from(n.count)) > bounded {
                return Err(BvhError::Malformed);
            }
        }
        if nodes.is_empty() != (bounded == 0) {
            return Err(BvhError::Malformed);
        }
        let bvh = Bvh {
            nodes,
            items,
            bounded,
        };
        bvh.check_layout()?;
        Ok(bvh)
    }

    /// The objects outside the tree (planes), which every ray tests.
    pub fn unbounded(&self) -> &'a [u32] {
        self.items.get(self.bounded..).unwrap_or(&[])
    }

    /// Checks the layout by walking the tree without recursion: the nodes are met in preorder
    /// (each exactly once, so every node is reachable and none shared), the leaves' item
    /// ranges follow one another and cover the tree's items exactly, and the depth is at most
    /// [`MAX_BVH_DEPTH`].
    fn check_layout(&self) -> Result<(), BvhError> {
        let mut stack: heapless::Vec<(usize, usize), { MAX_BVH_DEPTH + 1 }> = heapless::Vec::new();
        let (mut expected, mut next_item) = (0, 0);
        if !self.nodes.is_empty() {
            stack.push((0, 1)).map_err(|_| BvhError::TooDeep)?;
        }
        while let Some((i, depth)) = stack.pop() {
            let n = self.nodes.get(i).ok_or(BvhError::Malformed)?;
            if i != expected || depth > MAX_BVH_DEPTH {
                return Err(if depth > MAX_BVH_DEPTH {
                    BvhError::TooDeep
                } else {
                    BvhError::Malformed
                });
            }
            expected += 1;
            if n.count == 0 {
                // Second child below the first, so the first (i + 1) is met next.
                stack
                    .push((n.index as usize, depth + 1))
                    .map_err(|_| BvhError::TooDeep)?;
                stack
                    .push((i + 1, depth + 1))
                    .map_err(|_| BvhError::TooDeep)?;
            } else {
                if n.index as usize != next_item {
                    return Err(BvhError::Malformed);
                }
                next_item += usize::from(n.count);
            }
        }
        if expected != self.nodes.len() || next_item != self.bounded {
            return Err(BvhError::Malformed);
        }
        Ok(())
    }

    /// Nodes.
    pub fn nodes(&self) -> &'a [BvhNode] {
        self.nodes
    }

    /// Object ids in leaf order.
    pub fn items(&self) -> &'a [u32] {
        self.items
    }

    /// Calls `visit` with each object whose box the ray enters within `[t_min, t_max)`;
    /// `visit` returns the new `t_max` (a nearer hit shrinks the search) or `None` to stop.
    /// Returns the number of box tests.
    #[inline]
    pub fn walk(
        &self,
        ray: &Ray,
        t_min: I16F16,
        mut t_max: I16F16,
        mut visit: impl FnMut(u32, I16F16) -> Option<I16F16>,
    ) -> u32 {
        let inv = RayInverse::new(ray);
        let mut tests = 0;
        let mut stack: heapless::Vec<u32, MAX_BVH_DEPTH> = heapless::Vec::new();
        let mut next = if self.nodes.is_empty() {
            None
        } else {
            Some(0u32)
        };
        while let Some(i) = next.take() {
            if let Some(n) = self.nodes.get(i as usize) {
                tests += 1;
                if inv.enters(n, t_min, t_max) {
                    if n.count == 0 {
                        // Nearer child first: the second if the ray runs down the split axis.
                        let down = match n.axis {
                            0 => ray.dir.x < I16F16::ZERO,
                            1 => ray.dir.y < I16F16::ZERO,
                            _ => ray.dir.z < I16F16::ZERO,
                        };
                        let (near, far) = if down {
                            (n.index, i + 1)
                        } else {
                            (i + 1, n.index)
                        };
                        // The depth check in `new` keeps this within capacity.
                        let _ = stack.push(far);
                        next = Some(near);
                        continue;
                    }
                    let start = n.index as usize;
                    let leaf = self
                        .items
                        .get(start..start + usize::from(n.count))
                        .unwrap_or(&[]);
                    for id in leaf {
                        match visit(*id, t_max) {
                            Some(t) => t_max = t,
                            None => return tests,
                        }
                    }
                }
            }
            next = stack.pop();
        }
        tests
    }
}

/// A ray's origin and the reciprocals of its direction, for box tests (shared with the grid).
pub(crate) struct RayInverse {
    origin: [i64; 3],
    /// 1/dir per axis in 16 fraction bits (|value| < 2^32 raw), truncated (relative error
    /// below 2^-16); `None` for a zero component.
    inv: [Option<i64>; 3],
    /// The origin's raw I16F16 bits, for the hierarchy's 32-bit box test.
    origin32: [i32; 3],
    /// The same reciprocals where they fit an `i32` (every component of at least 2 raw steps);
    /// 0 for a component of 0 or ±1 raw step, which the 32-bit box test treats as parallel to
    /// the axis: over a ray shorter than 2^10 units such a component moves the ray less than
    /// 2^10 · 2^-16 = 2^-6 units, which the boxes' padding [`PAD`] absorbs.
    inv32: [i32; 3],
}

impl RayInverse {
    pub(crate) fn new(ray: &Ray) -> RayInverse {
        let d = ray.dir.bits();
        // One 32-bit division per axis (2^32 − 1 for 2^32: a relative error of 2^-32).
        let inv = d.map(|c| {
            let q = i64::from(u32::MAX.checked_div(c.unsigned_abs())?);
            Some(if c < 0 { -q } else { q })
        });
        RayInverse {
            origin: ray.origin.bits().map(i64::from),
            inv32: inv.map(|q| q.and_then(|q| i32::try_from(q).ok()).unwrap_or(0)),
            origin32: ray.origin.bits(),
            inv,
        }
    }

    /// The reciprocal of the direction's component `axis` (16 fraction bits), if not 0.
    pub(crate) fn reciprocal(&self, axis: usize) -> Option<i64> {
        self.inv.get(axis).copied().flatten()
    }

    /// Whether the ray is inside the node's box for some `t` in `[t_min, t_max)`: the slab
    /// test in 32-bit operands. Per axis `(bound − origin) · (1/dir)` is one 32 × 32 → 64-bit
    /// multiply (the difference is below 2^29 raw in the envelope, the reciprocal below 2^31),
    /// the nearer bound chosen by the reciprocal's sign instead of sorting the two times; the
    /// times are the same 32-fraction-bit values [`span`](Self::span) computes (which the grid
    /// uses), so the same boxes pass except for the axes treated as parallel (see `inv32`).
    #[inline]
    fn enters(&self, n: &BvhNode, t_min: I16F16, t_max: I16F16) -> bool {
        let mut lo = i64::from(t_min.to_bits()) << 16;
        let mut hi = i64::from(t_max.to_bits()) << 16;
        // Written out per axis: an iterator over the arrays kept its state in memory.
        let mut slab = |o: i32, inv: i32, a: i32, b: i32| {
            if inv == 0 {
                return o >= a && o <= b;
            }
            let (near, far) = if inv > 0 { (a, b) } else { (b, a) };
            let inv = i64::from(inv);
            lo = lo.max(i64::from(near.wrapping_sub(o)) * inv);
            hi = hi.min(i64::from(far.wrapping_sub(o)) * inv);
            lo <= hi
        };
        let ([ox, oy, oz], [ix, iy, iz]) = (self.origin32, self.inv32);
        let ([ax, ay, az], [bx, by, bz]) = (n.min.bits(), n.max.bits());
        // Each slab ends the test as soon as the interval is empty.
        slab(ox, ix, ax, bx) && slab(oy, iy, ay, by) && slab(oz, iz, az, bz)
    }

    /// The interval of `t` (32 fraction bits) within `[t_min, t_max]` in which the ray is
    /// inside the box `min..max` (raw I16F16 bits), if any.
    #[inline]
    pub(crate) fn span(
        &self,
        min: [i32; 3],
        max: [i64; 3],
        t_min: I16F16,
        t_max: I16F16,
    ) -> Option<(i64, i64)> {
        let (mut lo, mut hi) = (I32F32::from(t_min).to_bits(), I32F32::from(t_max).to_bits());
        let slabs = self
            .origin
            .iter()
            .zip(&self.inv)
            .zip(min.into_iter().zip(max));
        for ((&o, inv), (a, b)) in slabs {
            let a = i64::from(a);
            match *inv {
                None => {
                    if o < a || o > b {
                        return None;
                    }
                }
                Some(inv) => {
                    let (t1, t2) = ((a - o) * inv, (b - o) * inv);
                    let (near, far) = if t1 <= t2 { (t1, t2) } else { (t2, t1) };
                    lo = lo.max(near);
                    hi = hi.min(far);
                }
            }
        }
        (lo <= hi).then_some((lo, hi))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trace::shape::{Plane, Sphere};
    use std::vec::Vec;

    fn sphere(x: i32) -> Object<'static> {
        let c = Vec3::from_bits(x << 16, 0, 0);
        Object {
            shape: Shape::Sphere(Sphere::new(c, I16F16::from_num(0.4)).unwrap()),
            material: 0,
        }
    }

    const EMPTY: BvhNode = BvhNode {
        min: Vec3::ZERO,
        max: Vec3::ZERO,
        index: 0,
        count: 0,
        axis: 0,
    };

    #[test]
    fn heap_sort_sorts() {
        let mut v: Vec<u32> = (0..200).map(|i| (i * 7919) % 211).collect();
        heap_sort_by_key(&mut v, |x| x);
        assert!(v.windows(2).all(|w| w[0] <= w[1]));
    }

    #[test]
    fn build_then_walk_finds_every_object_on_the_ray() {
        // 20 spheres on the x axis and a plane; a ray along x meets them all.
        let mut objects: Vec<Object<'static>> = (0..20).map(|i| sphere(i - 10)).collect();
        objects.insert(
            7,
            Object {
                shape: Shape::Plane(
                    Plane::new(Vec3::from_bits(0, 1 << 16, 0), I16F16::from_num(5)).unwrap(),
                ),
                material: 0,
            },
        );
        let mut nodes = [EMPTY; 42];
        let mut items = [0u32; 21];
        let (used, total, bounded) = build(&objects, &mut nodes, &mut items).unwrap();
        assert_eq!((total, bounded), (21, 20));
        assert!(used < 2 * bounded);
        let bvh = Bvh::new(&nodes[..used], &items, bounded, &objects).unwrap();
        assert_eq!(bvh.unbounded(), [7]);
        let ray = Ray {
            origin: Vec3::from_bits(-20 << 16, 0, 0),
            dir: Vec3::from_bits(1 << 16, 0, 0),
        };
        let mut seen = Vec::new();
        bvh.walk(&ray, I16F16::ZERO, I16F16::MAX, |id, t| {
            seen.push(id);
            Some(t)
        });
        seen.sort();
        let mut want: Vec<u32> = (0..21).filter(|i| *i != 7).collect();
        want.sort();
        assert_eq!(seen, want);
        // A ray far off the axis enters no box beyond the root.
        let miss = Ray {
            origin: Vec3::from_bits(-20 << 16, 5 << 16, 0),
            dir: Vec3::from_bits(1 << 16, 0, 0),
        };
        let mut any = false;
        assert_eq!(
            bvh.walk(&miss, I16F16::ZERO, I16F16::MAX, |_, t| {
                any = true;
                Some(t)
            }),
            1
        );
        assert!(!any);
    }

    #[test]
    fn malformed_hierarchies_are_rejected() {
        let objects: Vec<Object<'static>> = (0..4).map(sphere).collect();
        let mut nodes = [EMPTY; 8];
        let mut items = [0u32; 4];
        let (used, _, bounded) = build(&objects, &mut nodes, &mut items).unwrap();
        assert!(Bvh::new(&nodes[..used], &items, bounded, &objects).is_ok());
        let mut twice = items;
        twice[1] = twice[0];
        assert_eq!(
            Bvh::new(&nodes[..used], &twice, bounded, &objects).err(),
            Some(BvhError::Malformed)
        );
        let mut backwards = nodes;
        backwards[0].index = 0;
        assert_eq!(
            Bvh::new(&backwards[..used], &items, bounded, &objects).err(),
            Some(BvhError::Malformed)
        );
        assert_eq!(
            Bvh::new(&nodes[..used], &items[..3], bounded, &objects).err(),
            Some(BvhError::Malformed)
        );
        assert_eq!(
            build(&objects, &mut nodes[..2], &mut items).err(),
            Some(BvhError::Capacity)
        );
        // A leaf that no longer covers its items would leave an object untested: rejected.
        let mut short = nodes;
        let leaf = short[..used].iter().position(|n| n.count == 2).unwrap();
        short[leaf].count = 1;
        assert_eq!(
            Bvh::new(&short[..used], &items, bounded, &objects).err(),
            Some(BvhError::Malformed)
        );
    }
}
