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
use crate::trace::scene::{LightKind, Scene, MAX_LIGHTS};
use crate::trace::shape::Object;
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

    #[test]
    fn the_sweep_along_a_directional_light_is_unbounded() {
        let region = cube([0, 0, 0], 1);
        let up = LightKind::Directional(Vec3::from_bits(0, 1 << 16, 0));
        assert!(sweep_meets(region, &up, cube([0, 1000, 0], 1)));
        assert!(!sweep_meets(region, &up, cube([0, -5, 0], 1)));
        assert!(!sweep_meets(region, &up, cube([5, 50, 0], 1)));
    }
}
