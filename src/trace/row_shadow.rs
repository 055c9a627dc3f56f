//! Hybrid mode's per-row shadow candidates: once a row's visible objects are known, per light
//! the objects that can block a shadow ray from one of the row's first hits towards it, so the
//! shadow rays of those hits (and of deeper hits in the same region) test a short list instead
//! of walking the hierarchy.
//!
//! The row's first hits lie in the padded boxes of the objects active on the row (the hybrid
//! mode's candidates), so in their union box `B`; so may hits deeper in their ray trees, and
//! every shadow ray that starts inside `B` uses the lists. A shadow ray from a point of `B` runs
//! inside the hull of `B` and a point light `L` (points `L + s·(b − L)`, `b` in `B`, `s` in
//! [0, 1]), or, for a directional light `D`, inside `B` swept along `D` (`b + s·D`, `s ≥ 0`;
//! the ray's direction is `D` itself). An object whose padded box misses that region cannot
//! block such a ray: towards a point light the rounded direction (within 2^-14.2 rad) moves the
//! ray off the segment by at most its length times that, below 2^-7.2 units for the rays up to
//! [`POINT_LIGHT_REACH`] the lists serve, inside the padding [`PAD`] (2^-6) with the hit
//! points' own error (about 2^-12) to spare. The test is exact integer arithmetic on
//! raw I16F16 bits (per axis a range of `s`, intersected as fractions with 64-bit cross
//! products: differences below 2^30 raw, so products below 2^60).
//!
//! Whether a shadow ray is blocked does not depend on the order objects are tested in, so the
//! list gives the hierarchy's answer. Planar objects sharing one plane (the checkered floor's
//! polygons) are grouped: a shadow ray that does not meet the plane within its window skips
//! the whole group, since every planar test starts by meeting its plane
//! (`intersect::meets_plane`). Unbounded objects (planes) are candidates for every light.

use crate::trace::bvh::{self, heap_sort_by_key, PAD};
use crate::trace::intersect::{meets_plane, Ray};
use crate::trace::scene::{LightKind, Scene, TraceCamera, MAX_LIGHTS};
use crate::trace::shape::{Object, Shape};
use crate::trace::vector::Vec3;
use fixed::types::I16F16;

/// Longest shadow ray towards a point light that the lists serve (world units); longer ones walk
/// the hierarchy (see the module's text).
pub const POINT_LIGHT_REACH: I16F16 = I16F16::from_bits(128 << 16);

/// One entry of a light's candidate list (8 bytes; the caller's buffer holds the lists of all
/// lights for one row).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ShadowCandidate {
    /// The object's id.
    pub object: u32,
    /// At the first of two or more consecutive planar objects lying in one plane: how many
    /// there are (a shadow ray that does not meet the plane skips them all); 0 otherwise.
    pub plane_run: u32,
}

/// The candidate lists of one row: light `k`'s list is `candidates[ranges[k].0..ranges[k].1]`,
/// valid for shadow rays starting inside `region` (raw bits, inclusive; `None`: nowhere).
pub(crate) struct RowShadows<'b> {
    candidates: &'b [ShadowCandidate],
    ranges: [(u16, u16); MAX_LIGHTS],
    region: Option<([i32; 3], [i32; 3])>,
    /// The current row's windows, if it has them (set row by row).
    pub(crate) windows: Option<ShadowWindows>,
}

impl<'b> RowShadows<'b> {
    /// Light `k`'s candidates for a shadow ray from `point` towards `light` over `distance`, if
    /// `point` lies in the region they were chosen for (every first hit of the row does, and so
    /// may a deeper hit) and a ray towards a point light is within [`POINT_LIGHT_REACH`].
    pub(crate) fn for_ray(
        &self,
        k: usize,
        light: &LightKind,
        point: Vec3,
        distance: I16F16,
    ) -> Option<&'b [ShadowCandidate]> {
        if matches!(light, LightKind::Point(_)) && distance >= POINT_LIGHT_REACH {
            return None;
        }
        let (lo, hi) = self.region?;
        let p = point.bits();
        if (0..3).any(|i| p[i] < lo[i] || p[i] > hi[i]) {
            return None;
        }
        let (start, end) = *self.ranges.get(k)?;
        self.candidates.get(usize::from(start)..usize::from(end))
    }

    /// The region the lists were built for.
    pub(crate) fn region(&self) -> Region {
        self.region
    }

    /// The row's windows if they serve the first hit of column `x` on object `id`.
    #[inline]
    pub(crate) fn windows_at(&self, x: u16, id: u32) -> Option<&ShadowWindows> {
        self.windows
            .as_ref()
            .filter(|w| w.object == id && x >= w.served.0 && x <= w.served.1)
    }

    /// Light `k`'s list.
    fn list(&self, k: usize) -> &'b [ShadowCandidate] {
        self.ranges
            .get(k)
            .and_then(|&(start, end)| self.candidates.get(usize::from(start)..usize::from(end)))
            .unwrap_or(&[])
    }
}

/// A window that rules out no column.
const EVERY_COLUMN: (u16, u16) = (0, u16::MAX);

/// Extra radius (world units) of a candidate's bounding sphere in [`shadow_windows`]: above
/// the first hit's own error in the rows windows are made for (a direction rounded within
/// 2^-14 rad over at most [`WINDOW_REACH`], divided by at least [`WINDOW_COSINE`]: below 2^-5)
/// and the `f32` estimate's (a few 2^-20 relative).
const WINDOW_PAD: f32 = 0.125;
/// Farthest first hit on the plane (world units from the eye) a row may have for windows.
const WINDOW_REACH: f32 = 64.0;
/// Smallest cosine between a row's rays and the plane's normal for windows: grazing rows
/// move their hits far for a small error of direction.
const WINDOW_COSINE: f32 = 0.125;
/// Columns a window is widened by on each side, for the `f32` roots it is bounded by.
const WINDOW_MARGIN: f32 = 2.0;
/// Most candidates a light may have for a window (a row computes one per candidate): lights
/// with more, such as a mesh's, keep every column.
const MAX_WINDOWED: usize = 16;

/// Hybrid mode's shadow windows for one row: for the first hits the row's rays make on one
/// planar object, per light, the columns whose shadow ray towards the light may meet one of
/// the light's candidates; from the other columns of [`served`](Self::served) no candidate
/// can block it, and the ray is not tested at all.
///
/// The row's rays meet the plane at `p(x) = eye + t(x)·d(x)` with `d(x)` linear in the column
/// `x` and `t(x) = num / k(x)`, `k(x) = normal · d(x)` linear too, so `k(x)·(p(x) − L)` is
/// linear in `x`. A candidate lies in its own sphere (a sphere or an ellipsoid's largest) or
/// in the sphere through its padded box's corners, widened by [`WINDOW_PAD`]; a shadow ray
/// towards a point light `L` meets that sphere only from points inside the cone from `L`
/// tangent to it (the nappe towards it), one along a directional light only from inside the
/// cylinder along it. Both are convex, so the columns whose hits lie inside form an interval,
/// bounded by the roots of a quadratic in `x` (times `k(x)²`) and, for the cone, of a linear
/// one: solved in `f32`, widened by [`WINDOW_MARGIN`] columns. A light's window is the hull
/// of its candidates' (every column when one is unbounded or planar, the hit's own object
/// excepted, which its shadow rays never test, or when it has more than [`MAX_WINDOWED`]). Only a speed-up: a ray outside
/// the window is one the full search finds unblocked, so the pixels are the full search's
/// (test `windows_keep_every_blocker`, and `trace_hybrid` in the sim suite).
#[derive(Clone, Copy, Debug)]
pub(crate) struct ShadowWindows {
    /// The planar object whose first hits the windows are for.
    object: u32,
    /// The columns the windows are for (inclusive).
    served: (u16, u16),
    /// Per light, its window (inclusive; `(1, 0)`: no column).
    windows: [(u16, u16); MAX_LIGHTS],
}

impl ShadowWindows {
    /// Whether no candidate can block the shadow ray towards light `k` from the first hit of
    /// column `x` (one the windows serve, [`RowShadows::windows_at`]).
    #[inline]
    pub(crate) fn clear(&self, k: usize, x: u16) -> bool {
        self.windows
            .get(k)
            .is_some_and(|&(first, last)| x < first || x > last)
    }
}

/// The windows of row `y` for the first hits on planar object `id` in columns `served`, from
/// the row's candidate `lists`; `None` when the row's hits on its plane are too far or too
/// oblique (or the eye lies in the plane), so every shadow ray is tested.
pub(crate) fn shadow_windows(
    scene: &Scene<'_>,
    camera: &TraceCamera,
    lists: &RowShadows<'_>,
    id: u32,
    served: (u16, u16),
    y: u16,
) -> Option<ShadowWindows> {
    let (normal, offset) = scene.objects.get(id as usize)?.shape.plane()?;
    let [corner, right, down, eye] = camera.float_basis();
    let n = normal.bits().map(|c| c as f32 / 65536.0);
    let row = f32::from(y);
    let through: [f32; 3] = core::array::from_fn(|i| corner[i] + row * down[i]);
    let line = RowLine {
        k: (dot(n, through), dot(n, right)),
        num: -(dot(n, eye) + offset.to_num::<f32>()),
        eye,
        through,
        right,
    };
    // A ray meeting the plane in front (t = num / k > 0) has k of num's sign.
    if line.num == 0.0 {
        return None;
    }
    let s = if line.num > 0.0 { 1.0 } else { -1.0 };
    // Checked a column beyond each end of `served`: k (linear, of one sign there) over |d|
    // (convex) is smallest at an end, t·|d| = num·|d| / k largest at one. The hits lie on the
    // segment between the ends' hits.
    let range = (f32::from(served.0) - 1.0, f32::from(served.1) + 1.0);
    let mut ends = [[0.0f32; 3]; 2];
    for (x, end) in [range.0, range.1].into_iter().zip(ends.iter_mut()) {
        let d: [f32; 3] = core::array::from_fn(|i| through[i] + x * right[i]);
        let (k, len) = (s * (line.k.0 + line.k.1 * x), libm::sqrtf(dot(d, d)));
        if !(k >= WINDOW_COSINE * len && s * line.num * len <= WINDOW_REACH * k) {
            return None;
        }
        *end = core::array::from_fn(|i| eye[i] + s * line.num / k * d[i]);
    }
    // The lists name every object that can block a ray from the row's region within reach
    // (`RowShadows::for_ray`), so the windows may leave the others out: the row's first hits
    // on a bounded planar object lie in its row box (`Tracer::row_box`), part of the region,
    // and towards a point light they are within reach when both ends of their segment are
    // (a light out of reach keeps every column).
    let reach = POINT_LIGHT_REACH.to_num::<f32>() - 1.0;
    let mut windows = [EVERY_COLUMN; MAX_LIGHTS];
    for (k, (light, window)) in scene.lights.iter().zip(windows.iter_mut()).enumerate() {
        if let LightKind::Point(p) = light.kind {
            let l = p.bits().map(|c| c as f32 / 65536.0);
            let far = |e: &[f32; 3]| {
                let v: [f32; 3] = core::array::from_fn(|i| e[i] - l[i]);
                dot(v, v) >= reach * reach
            };
            if ends.iter().any(far) {
                continue;
            }
        }
        let list = lists.list(k);
        if list.len() > MAX_WINDOWED {
            continue;
        }
        // The hull of the candidates' windows, the hit's own object left out; one candidate
        // without a window leaves every column.
        let mut hull = Some((u16::MAX, 0u16));
        for c in list.iter().filter(|c| c.object != id) {
            let found = scene
                .objects
                .get(c.object as usize)
                .and_then(|o| candidate_window(&line, &light.kind, o, range));
            hull = match (hull, found) {
                // An empty window (1, 0) leaves the hull as it is.
                (Some(h), Some((first, last))) if first > last => Some(h),
                (Some((a, b)), Some((first, last))) => Some((a.min(first), b.max(last))),
                _ => {
                    hull = None;
                    break;
                }
            };
        }
        *window = match hull {
            Some((first, last)) if first > last => (1, 0),
            Some(found) => found,
            None => EVERY_COLUMN,
        };
    }
    Some(ShadowWindows {
        object: id,
        served,
        windows,
    })
}

/// A row's rays and the plane they meet: `k(x) = k.0 + k.1·x` (the normal's dot product with
/// the direction of column `x`, `through + x·right`) and `num` (`t(x) = num / k(x)`).
struct RowLine {
    k: (f32, f32),
    num: f32,
    eye: [f32; 3],
    through: [f32; 3],
    right: [f32; 3],
}

impl RowLine {
    /// `k(x)·(p(x) − q) = a0 + x·a1` for a point `q`, with `p(x)` column `x`'s hit.
    fn relative(&self, q: [f32; 3]) -> ([f32; 3], [f32; 3]) {
        let (k0, k1, num) = (self.k.0, self.k.1, self.num);
        (
            core::array::from_fn(|i| k0 * (self.eye[i] - q[i]) + num * self.through[i]),
            core::array::from_fn(|i| k1 * (self.eye[i] - q[i]) + num * self.right[i]),
        )
    }
}

/// The columns of `range` whose hits on the row's plane may have a shadow ray towards `light`
/// that meets `object` ([`ShadowWindows`]); `None`: every column (an unbounded or planar
/// object, a point light inside its sphere, no finite estimate).
fn candidate_window(
    line: &RowLine,
    light: &LightKind,
    object: &Object<'_>,
    range: (f32, f32),
) -> Option<(u16, u16)> {
    if object.shape.plane().is_some() {
        return None;
    }
    // A sphere around the candidate: its own for a sphere or an ellipsoid, else the one
    // through its padded box's corners.
    let (centre, radius) = match ellipsoid_of(&object.shape) {
        Some((centre, radii)) => (centre, radii[0].max(radii[1]).max(radii[2])),
        None => {
            let (lo, hi) = padded_box(object)?;
            let centre: [f32; 3] =
                core::array::from_fn(|i| (lo[i] as f32 + hi[i] as f32) / 131_072.0);
            let half: [f32; 3] =
                core::array::from_fn(|i| (hi[i] as f32 - lo[i] as f32) / 131_072.0);
            (centre, libm::sqrtf(dot(half, half)))
        }
    };
    let r2 = (radius + WINDOW_PAD) * (radius + WINDOW_PAD);
    let s = if line.num > 0.0 { 1.0 } else { -1.0 };
    match light {
        LightKind::Point(p) => {
            let l = p.bits().map(|c| c as f32 / 65536.0);
            let axis: [f32; 3] = core::array::from_fn(|i| centre[i] - l[i]);
            let dist2 = dot(axis, axis);
            // The light inside the sphere (or no finite distance): every column.
            if dist2.is_nan() || dist2 <= r2 {
                return None;
            }
            let cos2 = 1.0 - r2 / dist2;
            let inv = 1.0 / libm::sqrtf(dist2);
            let u = axis.map(|c| c * inv);
            let (a0, a1) = line.relative(l);
            // (w·u)² ≥ cos²·|w|² and s·(w·u) ≥ 0 for w = k·(p − L).
            let (e0, e1) = (dot(a0, u), dot(a1, u));
            let q = [
                e1 * e1 - cos2 * dot(a1, a1),
                2.0 * (e0 * e1 - cos2 * dot(a0, a1)),
                e0 * e0 - cos2 * dot(a0, a0),
            ];
            columns_where(q, Some([s * e0, s * e1]), range)
        }
        LightKind::Directional(dir) => {
            let u = dir.bits().map(|c| c as f32 / 65536.0);
            let (a0, a1) = line.relative(centre);
            let (k0, k1) = line.k;
            // |w|² − (w·u)² ≤ r²·k² for w = k·(p − centre).
            let (e0, e1) = (dot(a0, u), dot(a1, u));
            let q = [
                r2 * k1 * k1 - (dot(a1, a1) - e1 * e1),
                2.0 * (r2 * k0 * k1 - (dot(a0, a1) - e0 * e1)),
                r2 * k0 * k0 - (dot(a0, a0) - e0 * e0),
            ];
            columns_where(q, None, range)
        }
    }
}

fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The columns of `range` where `q[0]·x² + q[1]·x + q[2] ≥ 0` and (with `linear`)
/// `linear[0] + linear[1]·x ≥ 0` hold, widened by [`WINDOW_MARGIN`]: `(1, 0)` when none do,
/// `None` when the coefficients are not finite. The conditions keep their signs between the
/// roots, so a piece between two consecutive roots (or ends) holds where its middle does.
fn columns_where(q: [f32; 3], linear: Option<[f32; 2]>, range: (f32, f32)) -> Option<(u16, u16)> {
    if !q
        .iter()
        .chain(linear.iter().flatten())
        .all(|c| c.is_finite())
    {
        return None;
    }
    let holds = |x: f32| {
        (q[0] * x + q[1]) * x + q[2] >= 0.0 && linear.is_none_or(|l| l[0] + l[1] * x >= 0.0)
    };
    let mut points = [range.0, range.1, range.0, range.0, range.0];
    let mut count = 2;
    let mut add = |x: f32| {
        if x > range.0 && x < range.1 {
            if let Some(slot) = points.get_mut(count) {
                *slot = x;
                count += 1;
            }
        }
    };
    if q[0] != 0.0 {
        let disc = q[1] * q[1] - 4.0 * q[0] * q[2];
        if disc >= 0.0 {
            // The root of the larger magnitude first, the other from the product of the two.
            let t = -0.5 * (q[1] + libm::copysignf(libm::sqrtf(disc), q[1]));
            add(t / q[0]);
            if t != 0.0 {
                add(q[2] / t);
            }
        }
    } else if q[1] != 0.0 {
        add(-q[2] / q[1]);
    }
    if let Some(l) = linear.filter(|l| l[1] != 0.0) {
        add(-l[0] / l[1]);
    }
    let points = points.get_mut(..count).unwrap_or(&mut []);
    // At most five: a bubble sort (no panic path, unlike the library's sorts).
    for _ in 1..points.len() {
        for i in 1..points.len() {
            if let Some([a, b]) = points.get_mut(i - 1..=i) {
                if *b < *a {
                    core::mem::swap(a, b);
                }
            }
        }
    }
    let (mut first, mut last) = (f32::MAX, f32::MIN);
    let mut take = |a: f32, b: f32| (first, last) = (first.min(a), last.max(b));
    for (i, &x) in points.iter().enumerate() {
        if holds(x) {
            take(x, x);
        }
        if let Some(&next) = points.get(i + 1) {
            if holds((x + next) / 2.0) {
                take(x, next);
            }
        }
    }
    if first > last {
        return Some((1, 0));
    }
    // `as` saturates: below 0 gives 0, beyond u16::MAX gives u16::MAX.
    Some((
        libm::floorf(first - WINDOW_MARGIN) as u16,
        libm::ceilf(last + WINDOW_MARGIN) as u16,
    ))
}

/// The padded box of an object, raw I16F16 bits; `None` for an unbounded one.
pub(crate) fn padded_box(object: &Object<'_>) -> Option<([i32; 3], [i32; 3])> {
    let pad = Vec3 {
        x: PAD,
        y: PAD,
        z: PAD,
    };
    bvh::bounds(&object.shape).map(|(lo, hi)| (lo.sub(pad).bits(), hi.add(pad).bits()))
}

/// A sphere's or an ellipsoid's centre and semi-axes widened by [`PAD`] (world units, f32);
/// `None` for the other shapes.
pub(crate) fn ellipsoid_of(shape: &Shape<'_>) -> Option<([f32; 3], [f32; 3])> {
    let (centre, radii) = match shape {
        Shape::Sphere(s) => (s.centre, [s.radius; 3]),
        Shape::Ellipsoid(e) => (e.centre, [e.radii.x, e.radii.y, e.radii.z]),
        _ => return None,
    };
    let f = |v: I16F16| v.saturating_add(PAD).to_num::<f32>();
    Some((centre.bits().map(|c| c as f32 / 65536.0), radii.map(f)))
}

/// A box of raw I16F16 bits (inclusive), `None`: empty.
pub(crate) type Region = Option<([i32; 3], [i32; 3])>;

/// The union of the boxes a row's first hits lie in, one per active object (`None` when the
/// object is unbounded, `Some(None)` when the row sees none of it); `None` when an active
/// object is unbounded: the row's first hits are then not bounded and its shadow rays walk
/// the hierarchy.
pub(crate) fn row_region(boxes: impl Iterator<Item = Option<Region>>) -> Option<Region> {
    let mut region: Region = None;
    for b in boxes {
        let Some((lo, hi)) = b? else { continue };
        region = Some(match region {
            None => (lo, hi),
            Some((a, b)) => (
                core::array::from_fn(|i| a[i].min(lo[i])),
                core::array::from_fn(|i| b[i].max(hi[i])),
            ),
        });
    }
    Some(region)
}

/// Builds the candidate lists for shadow rays starting in `region` (see [`row_region`]) into
/// `out`; `None` when `out` is too small.
pub(crate) fn row_shadows<'b>(
    scene: &Scene<'_>,
    region: Region,
    out: &'b mut [ShadowCandidate],
) -> Option<RowShadows<'b>> {
    let mut ranges = [(0u16, 0u16); MAX_LIGHTS];
    let mut used = 0usize;
    // No visible object: no first hit, no shadow ray; every list stays empty.
    if let Some(region) = region {
        for (light, range) in scene.lights.iter().zip(ranges.iter_mut()) {
            let start = used;
            for (id, object) in scene.objects.iter().enumerate() {
                let candidate = padded_box(object)
                    .is_none_or(|object| sweep_meets(region, &light.kind, object));
                if candidate {
                    let slot = out.get_mut(used)?;
                    *slot = ShadowCandidate {
                        object: id as u32,
                        plane_run: 0,
                    };
                    used += 1;
                }
            }
            let list = out.get_mut(start..used)?;
            group_planes(scene, list);
            *range = (u16::try_from(start).ok()?, u16::try_from(used).ok()?);
        }
    }
    Some(RowShadows {
        candidates: out.get(..used)?,
        ranges,
        region,
        windows: None,
    })
}

/// Sorts `list` so the planar objects lying in one plane are consecutive, and marks each
/// group of two or more at its first entry.
fn group_planes(scene: &Scene<'_>, list: &mut [ShadowCandidate]) {
    let plane = |c: &ShadowCandidate| {
        scene
            .objects
            .get(c.object as usize)
            .and_then(|o| o.shape.plane())
            .map(|(n, d)| (n.bits(), d.to_bits()))
    };
    heap_sort_by_key(list, |c| (plane(&c), c.object));
    let mut start = 0;
    while let Some(first) = list.get(start) {
        let key = plane(first);
        let run = list
            .get(start..)
            .unwrap_or(&[])
            .iter()
            .take_while(|c| key.is_some() && plane(c) == key)
            .count();
        if run >= 2 {
            if let Some(first) = list.get_mut(start) {
                first.plane_run = run as u32;
            }
        }
        start += run.max(1);
    }
}

/// Whether `blocks` holds for some candidate of `list` that a shadow ray `ray` with window
/// `[EPSILON, t_max)` can meet (a group whose plane the ray does not meet is skipped).
pub(crate) fn any_blocks(
    scene: &Scene<'_>,
    list: &[ShadowCandidate],
    ray: &Ray,
    t_min: I16F16,
    t_max: I16F16,
    mut blocks: impl FnMut(u32) -> bool,
) -> bool {
    let mut i = 0;
    while let Some(c) = list.get(i) {
        if c.plane_run >= 2 {
            let plane = scene
                .objects
                .get(c.object as usize)
                .and_then(|o| o.shape.plane());
            if plane.is_some_and(|p| !meets_plane(p, ray, t_min, t_max)) {
                i += c.plane_run as usize;
                continue;
            }
        }
        if blocks(c.object) {
            return true;
        }
        i += 1;
    }
    false
}

/// A range of the sweep parameter `s`: `lo ≤ s ≤ hi`, each bound a fraction `n / d` with
/// `d > 0`; `hi = None` is unbounded.
struct Range {
    lo: (i64, i64),
    hi: Option<(i64, i64)>,
}

impl Range {
    /// Adds `s · c ≤ r` (`at_most`) or `s · c ≥ r`; false when it cannot hold.
    fn add(&mut self, c: i64, r: i64, at_most: bool) -> bool {
        // Dividing by a negative c flips the inequality.
        let (n, d, upper) = match c {
            0 => return if at_most { r >= 0 } else { r <= 0 },
            c if c > 0 => (r, c, at_most),
            c => (-r, -c, !at_most),
        };
        if upper {
            if self.hi.is_none_or(|(hn, hd)| n * hd < hn * d) {
                self.hi = Some((n, d));
            }
        } else if n * self.lo.1 > self.lo.0 * d {
            self.lo = (n, d);
        }
        self.hi
            .is_none_or(|(hn, hd)| self.lo.0 * hd <= hn * self.lo.1)
    }
}

/// Whether the box `object` (raw bits, inclusive) meets the region shadow rays from the box
/// `region` towards `light` run in (see the module's text).
fn sweep_meets(
    region: ([i32; 3], [i32; 3]),
    light: &LightKind,
    object: ([i32; 3], [i32; 3]),
) -> bool {
    let ((b0, b1), (o0, o1)) = (region, object);
    let w = |v: i32| i64::from(v);
    match light {
        LightKind::Point(p) => {
            // L + s·(b − L), s in [0, 1]: per axis s·(B0 − L) ≤ O1 − L and s·(B1 − L) ≥ O0 − L.
            let l = p.bits();
            let mut s = Range {
                lo: (0, 1),
                hi: Some((1, 1)),
            };
            (0..3).all(|i| {
                s.add(w(b0[i]) - w(l[i]), w(o1[i]) - w(l[i]), true)
                    && s.add(w(b1[i]) - w(l[i]), w(o0[i]) - w(l[i]), false)
            })
        }
        LightKind::Directional(d) => {
            // b + s·D, s ≥ 0: per axis s·D ≤ O1 − B0 and s·D ≥ O0 − B1.
            let d = d.bits();
            let mut s = Range {
                lo: (0, 1),
                hi: None,
            };
            (0..3).all(|i| {
                s.add(w(d[i]), w(o1[i]) - w(b0[i]), true)
                    && s.add(w(d[i]), w(o0[i]) - w(b1[i]), false)
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube(c: [i32; 3], half: i32) -> ([i32; 3], [i32; 3]) {
        let f = |v: i32| v << 16;
        (c.map(|v| f(v - half)), c.map(|v| f(v + half)))
    }

    #[test]
    fn the_sweep_towards_a_point_light_is_the_hull() {
        // Region around the origin, light at (0, 10, 0).
        let region = cube([0, 0, 0], 1);
        let light = LightKind::Point(Vec3::from_bits(0, 10 << 16, 0));
        // Between the region and the light: inside the hull.
        assert!(sweep_meets(region, &light, cube([0, 5, 0], 1)));
        // Beside the hull's narrow end near the light: out.
        assert!(!sweep_meets(region, &light, cube([3, 8, 0], 1)));
        // Beside the region, level with it: out; overlapping it: in.
        assert!(!sweep_meets(region, &light, cube([4, 0, 0], 1)));
        assert!(sweep_meets(region, &light, cube([2, 0, 0], 1)));
        // Beyond the light: out.
        assert!(!sweep_meets(region, &light, cube([0, 13, 0], 1)));
        // Near the wide end, just inside the slanted side (x ≤ 1 − y/10 at y = 2: 0.8).
        let thin = |x0: f64| {
            let f = |v: f64| (v * 65536.0) as i32;
            ([f(x0), f(1.9), f(-0.1)], [f(x0 + 0.1), f(2.1), f(0.1)])
        };
        assert!(sweep_meets(region, &light, thin(0.75)));
        assert!(!sweep_meets(region, &light, thin(0.95)));
    }

    #[test]
    fn coplanar_candidates_are_grouped_and_skipped_together() {
        use crate::trace::scene::{Colour, Material};
        use crate::trace::shape::{Shape, Sphere, Triangle};
        let v = |x: i32, y: i32, z: i32| Vec3::from_bits(x << 16, y << 16, z << 16);
        // Two floor triangles in y = 0 around a sphere, and a third triangle in y = 0 too.
        let tri = |x: i32| Object {
            shape: Shape::Triangle(
                Triangle::new([v(x, 0, 0), v(x + 1, 0, 0), v(x, 0, -1)]).unwrap(),
            ),
            material: 0,
        };
        let objects = [
            tri(0),
            Object {
                shape: Shape::Sphere(Sphere::new(v(0, 3, 0), I16F16::ONE).unwrap()),
                material: 0,
            },
            tri(2),
            tri(4),
        ];
        let grey = Colour::new([I16F16::ONE; 3]).unwrap();
        let materials = [Material::new(grey, [I16F16::ONE; 4], I16F16::ONE).unwrap()];
        let scene = Scene::new(&objects, &materials, &[], Colour::BLACK, I16F16::ZERO).unwrap();
        let mut list: [ShadowCandidate; 4] = core::array::from_fn(|i| ShadowCandidate {
            object: i as u32,
            plane_run: 0,
        });
        group_planes(&scene, &mut list);
        // The sphere first (no plane), then the three triangles as one group.
        let order = list.map(|c| (c.object, c.plane_run));
        assert_eq!(order, [(1, 0), (0, 3), (2, 0), (3, 0)]);
        let tested = |ray: &Ray| {
            let mut seen = [false; 4];
            let blocked = any_blocks(
                &scene,
                &list,
                ray,
                I16F16::from_bits(64),
                I16F16::MAX,
                |id| {
                    seen[id as usize] = true;
                    false
                },
            );
            assert!(!blocked);
            seen
        };
        // Leaving the floor upwards: the group is skipped, the sphere tested.
        let up = Ray {
            origin: Vec3::from_bits(1 << 15, 0, -(1 << 14)),
            dir: v(0, 1, 0),
        };
        assert_eq!(tested(&up), [false, true, false, false]);
        // From above, down through the floor: every member is tested.
        let down = Ray {
            origin: v(3, 2, 0),
            dir: Vec3::from_bits(0, -(1 << 16), 0),
        };
        assert_eq!(tested(&down), [true, true, true, true]);
    }

    #[test]
    fn lists_serve_rays_from_their_region_within_reach() {
        let candidates = [ShadowCandidate::default(); 2];
        let mut ranges = [(0, 0); MAX_LIGHTS];
        ranges[0] = (0, 2);
        let rows = RowShadows {
            candidates: &candidates,
            ranges,
            region: Some(cube([0, 0, 0], 1)),
            windows: None,
        };
        let point = LightKind::Point(Vec3::from_bits(0, 10 << 16, 0));
        let up = LightKind::Directional(Vec3::from_bits(0, 1 << 16, 0));
        let inside = Vec3::from_bits(1 << 15, 0, 0);
        let near = I16F16::from_num(9);
        assert_eq!(
            rows.for_ray(0, &point, inside, near).map(<[_]>::len),
            Some(2)
        );
        assert_eq!(
            rows.for_ray(0, &up, inside, I16F16::MAX).map(<[_]>::len),
            Some(2)
        );
        // Outside the region, beyond the reach of a point light's list, an unknown light.
        let outside = Vec3::from_bits(3 << 16, 0, 0);
        assert_eq!(rows.for_ray(0, &point, outside, near), None);
        assert_eq!(rows.for_ray(0, &point, inside, POINT_LIGHT_REACH), None);
        assert_eq!(rows.for_ray(MAX_LIGHTS, &up, inside, near), None);
    }

    /// The classic scene's floor, spheres and lights (`sim/scenes/classic.scene`) plus a
    /// directional light, at 240×240 from above: per pixel whose first hit is on the floor,
    /// a shadow ray towards a light that some candidate blocks is in the light's window, and
    /// the windows leave most of the unblocked rays out.
    #[test]
    fn windows_keep_every_blocker() {
        use crate::trace::scene::{Colour, Light, Material};
        use crate::trace::shape::{Polygon, Sphere};
        use crate::trace::tracer::EPSILON;
        let v = |x: f64, y: f64, z: f64| {
            let f = |c: f64| I16F16::from_num(c);
            Vec3 {
                x: f(x),
                y: f(y),
                z: f(z),
            }
        };
        let floor = [
            v(-4.0, 0.0, -4.0),
            v(-4.0, 0.0, 4.0),
            v(4.0, 0.0, 4.0),
            v(4.0, 0.0, -4.0),
        ];
        let sphere = |c: Vec3, r: f64| Object {
            shape: Shape::Sphere(Sphere::new(c, I16F16::from_num(r)).unwrap()),
            material: 0,
        };
        let objects = [
            sphere(v(-1.1, 1.0, -0.5), 1.0),
            sphere(v(1.2, 0.9, 1.0), 0.9),
            Object {
                shape: Shape::Polygon(Polygon::new(&floor).unwrap()),
                material: 0,
            },
        ];
        let intensity = I16F16::from_num(0.5);
        let lights = [
            Light::point(v(-4.0, 7.0, 5.0), intensity).unwrap(),
            Light::point(v(5.0, 6.0, -2.0), intensity).unwrap(),
            Light::directional(v(0.6, 0.8, 0.0), intensity).unwrap(),
        ];
        let grey = Colour::new([I16F16::from_num(0.5); 3]).unwrap();
        let materials = [Material::new(grey, [I16F16::ONE; 4], I16F16::ONE).unwrap()];
        let scene = Scene::new(&objects, &materials, &lights, Colour::BLACK, I16F16::ZERO).unwrap();
        let (w, h) = (240, 240);
        let camera = TraceCamera::classic(w, h);
        let mut out = [ShadowCandidate::default(); 3 * 3];
        let lists = row_shadows(&scene, Some(cube([0, 0, 0], 8)), &mut out).unwrap();
        let floor = &objects[2];
        let (mut rays, mut clear, mut blocked, mut unwindowed) = (0, 0, 0, 0);
        for y in 0..h {
            let windows = shadow_windows(&scene, &camera, &lists, 2, (0, w - 1), y);
            let mut seen = false;
            for x in 0..w {
                let Some(dir) = camera.pixel_direction(x, y).normalized() else {
                    continue;
                };
                let primary = Ray {
                    origin: camera.eye,
                    dir,
                };
                let Some(t) = floor.shape.hit(&primary, EPSILON, I16F16::MAX) else {
                    continue;
                };
                let point = camera.eye.along(dir, t);
                seen = true;
                let Some(windows) = &windows else {
                    continue;
                };
                for (k, light) in lights.iter().enumerate() {
                    let (towards, distance) = match light.kind {
                        LightKind::Directional(d) => (d, I16F16::MAX),
                        LightKind::Point(p) => p.sub(point).normalized_with_length().unwrap(),
                    };
                    let ray = Ray {
                        origin: point,
                        dir: towards,
                    };
                    let blocks = lists.list(k).iter().filter(|c| c.object != 2).any(|c| {
                        objects[c.object as usize]
                            .shape
                            .blocks(&ray, EPSILON, distance)
                    });
                    rays += 1;
                    blocked += u32::from(blocks);
                    if windows.clear(k, x) {
                        clear += 1;
                        assert!(!blocks, "({x}, {y}) light {k}: blocked outside the window");
                    }
                }
            }
            unwindowed += u32::from(seen && windows.is_none());
        }
        assert_eq!(unwindowed, 0, "rows that see the floor without windows");
        assert!(blocked > 1_000, "{blocked} blocked");
        assert!(
            clear * 10 > (rays - blocked) * 6,
            "{clear} of {rays} rays clear, {blocked} blocked"
        );
    }

    #[test]
    fn the_sweep_along_a_directional_light_is_unbounded() {
        let region = cube([0, 0, 0], 1);
        let up = LightKind::Directional(Vec3::from_bits(0, 1 << 16, 0));
        assert!(sweep_meets(region, &up, cube([0, 1000, 0], 1)));
        assert!(!sweep_meets(region, &up, cube([0, -5, 0], 1)));
        assert!(!sweep_meets(region, &up, cube([5, 50, 0], 1)));
    }
}
