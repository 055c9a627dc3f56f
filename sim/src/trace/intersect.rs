//! Ray–primitive intersection in f64 for every [`Shape`], and each shape's bounding box.
//!
//! Each test returns the nearest ray parameter in the query's [`Span`] with the surface's
//! outward unit normal there (the side a plane or polygon normal points to; for a mesh
//! triangle the side `(b − a) × (c − a)` points to). A closed shape is hit from inside too
//! (the far root), which is how a refracted ray leaves it.

use super::scene::Shape;
use super::vector::{add, along, cross, dot, length, normalize, scale, sub, Ray, Span, V3};

/// A surface point found by a ray: the parameter and the outward unit normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceHit {
    /// Ray parameter.
    pub t: f64,
    /// Outward unit normal at the hit.
    pub normal: V3,
}

/// Keeps the smallest accepted candidate.
struct Nearest {
    span: Span,
    best: Option<SurfaceHit>,
}

impl Nearest {
    fn new(span: Span) -> Self {
        Nearest { span, best: None }
    }
    fn offer(&mut self, t: f64, normal: impl FnOnce() -> Option<V3>) {
        if !self.span.contains(t) || self.best.is_some_and(|b| b.t <= t) {
            return;
        }
        if let Some(normal) = normal() {
            self.best = Some(SurfaceHit { t, normal });
        }
    }
}

/// Real roots of `a t² + b t + c = 0` in ascending order (a linear equation when `a` is 0).
fn roots(a: f64, b: f64, c: f64) -> Vec<f64> {
    if a == 0.0 {
        return if b == 0.0 { vec![] } else { vec![-c / b] };
    }
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 || disc.is_nan() {
        return vec![];
    }
    // The numerically stable pair: no cancellation between −b and the square root.
    let q = -0.5 * (b + b.signum() * disc.sqrt());
    let (t0, t1) = if q == 0.0 { (0.0, 0.0) } else { (q / a, c / q) };
    vec![t0.min(t1), t0.max(t1)]
}

/// The nearest intersection of `ray` with `shape` in `span`.
pub fn intersect(shape: &Shape, ray: &Ray, span: Span) -> Option<SurfaceHit> {
    let mut near = Nearest::new(span);
    let (o, d) = (ray.origin, ray.dir);
    match shape {
        Shape::Sphere { centre, radius } => {
            let oc = sub(o, *centre);
            for t in roots(dot(d, d), 2.0 * dot(oc, d), dot(oc, oc) - radius * radius) {
                near.offer(t, || normalize(sub(ray.at(t), *centre)));
            }
        }
        Shape::Ellipsoid { centre, radii } => {
            // In coordinates scaled by the radii the ellipsoid is the unit sphere.
            let oc = [0, 1, 2].map(|k| (o[k] - centre[k]) / radii[k]);
            let ds = [0, 1, 2].map(|k| d[k] / radii[k]);
            for t in roots(dot(ds, ds), 2.0 * dot(oc, ds), dot(oc, oc) - 1.0) {
                near.offer(t, || {
                    let p = ray.at(t);
                    normalize([0, 1, 2].map(|k| (p[k] - centre[k]) / (radii[k] * radii[k])))
                });
            }
        }
        Shape::Plane { normal, d: offset } => {
            let den = dot(*normal, d);
            if den != 0.0 {
                near.offer(-(dot(*normal, o) + offset) / den, || Some(*normal));
            }
        }
        Shape::Box { min, max } => slab_box(&mut near, ray, *min, *max),
        Shape::Cylinder { p0, p1, radius } => {
            frustum(&mut near, ray, *p0, *radius, *p1, *radius);
        }
        Shape::Cone { p0, r0, p1, r1 } => frustum(&mut near, ray, *p0, *r0, *p1, *r1),
        Shape::Polygon { vertices, normal } => {
            let den = dot(*normal, d);
            if let (Some(v0), true) = (vertices.first(), den != 0.0) {
                let t = dot(*normal, sub(*v0, o)) / den;
                near.offer(t, || {
                    inside_polygon(vertices, *normal, ray.at(t)).then_some(*normal)
                });
            }
        }
        Shape::Triangle { corners } => {
            if let Some(t) = moller_trumbore(corners, ray) {
                near.offer(t, || {
                    normalize(cross(
                        sub(corners[1], corners[0]),
                        sub(corners[2], corners[0]),
                    ))
                });
            }
        }
    }
    near.best
}

/// Slab test with the face normals of the entry and the exit.
fn slab_box(near: &mut Nearest, ray: &Ray, min: V3, max: V3) {
    let (mut t_in, mut t_out) = (f64::NEG_INFINITY, f64::INFINITY);
    let (mut n_in, mut n_out) = ([0.0; 3], [0.0; 3]);
    for k in 0..3 {
        let (o, d) = (ray.origin[k], ray.dir[k]);
        if d == 0.0 {
            if o < min[k] || o > max[k] {
                return;
            }
            continue;
        }
        let (a, b) = ((min[k] - o) / d, (max[k] - o) / d);
        // Entering through the min face when moving up the axis, the max face otherwise.
        let (enter, exit, sign) = if d > 0.0 { (a, b, -1.0) } else { (b, a, 1.0) };
        if enter > t_in {
            t_in = enter;
            n_in = [0.0; 3];
            n_in[k] = sign;
        }
        if exit < t_out {
            t_out = exit;
            n_out = [0.0; 3];
            n_out[k] = -sign;
        }
    }
    if t_in <= t_out {
        near.offer(t_in, || Some(n_in));
        near.offer(t_out, || Some(n_out));
    }
}

/// A capped frustum along `p0 → p1`, radius `r0` at `p0` and `r1` at `p1` (a cylinder when
/// they are equal, a cone when one is 0).
fn frustum(near: &mut Nearest, ray: &Ray, p0: V3, r0: f64, p1: V3, r1: f64) {
    let axis_v = sub(p1, p0);
    let len = length(axis_v);
    let Some(a) = normalize(axis_v) else {
        return;
    };
    let slope = (r1 - r0) / len;
    let q = sub(ray.origin, p0);
    let (qs, ds) = (dot(q, a), dot(ray.dir, a));
    let q_perp = sub(q, scale(a, qs));
    let d_perp = sub(ray.dir, scale(a, ds));
    // |q⊥ + t d⊥|² = (r0 + slope · (qs + t ds))²
    let (g, h) = (r0 + slope * qs, slope * ds);
    let qa = dot(d_perp, d_perp) - h * h;
    let qb = 2.0 * (dot(q_perp, d_perp) - g * h);
    let qc = dot(q_perp, q_perp) - g * g;
    for t in roots(qa, qb, qc) {
        let s = qs + t * ds;
        if (0.0..=len).contains(&s) && g + h * t >= 0.0 {
            near.offer(t, || {
                // Gradient of |p⊥| − r(s): the radial unit vector tilted by the slope.
                let radial = normalize(along(q_perp, d_perp, t))?;
                normalize(sub(radial, scale(a, slope)))
            });
        }
    }
    if ds != 0.0 {
        for (s, r, outward) in [(0.0, r0, scale(a, -1.0)), (len, r1, a)] {
            if r > 0.0 {
                let t = (s - qs) / ds;
                let off = along(q_perp, d_perp, t);
                if dot(off, off) <= r * r {
                    near.offer(t, || Some(outward));
                }
            }
        }
    }
}

/// The axis (0 = x, 1 = y, 2 = z) of `normal`'s largest component, the first of equal ones:
/// what the point-in-polygon test and a checker texture drop.
pub fn dominant_axis(normal: V3) -> usize {
    let [x, y, z] = normal.map(f64::abs);
    if x >= y && x >= z {
        0
    } else if y >= z {
        1
    } else {
        2
    }
}

/// Even-odd point-in-polygon test of `p` (on the polygon's plane) in the projection that drops
/// the normal's largest axis.
pub fn inside_polygon(vertices: &[V3], normal: V3, p: V3) -> bool {
    let (u, v) = match dominant_axis(normal) {
        0 => (1, 2),
        1 => (2, 0),
        _ => (0, 1),
    };
    let mut inside = false;
    let n = vertices.len();
    for (i, a) in vertices.iter().enumerate() {
        let b = vertices[(i + n - 1) % n];
        // Half-open in v so a vertex on the scan line is counted once.
        if (a[v] > p[v]) != (b[v] > p[v]) {
            let x = a[u] + (p[v] - a[v]) * (b[u] - a[u]) / (b[v] - a[v]);
            if p[u] < x {
                inside = !inside;
            }
        }
    }
    inside
}

/// Möller–Trumbore, two-sided: the ray parameter of the hit inside the triangle.
fn moller_trumbore(c: &[V3; 3], ray: &Ray) -> Option<f64> {
    let e1 = sub(c[1], c[0]);
    let e2 = sub(c[2], c[0]);
    let p = cross(ray.dir, e2);
    let det = dot(e1, p);
    if det == 0.0 {
        return None;
    }
    let inv = 1.0 / det;
    let s = sub(ray.origin, c[0]);
    let u = dot(s, p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = cross(s, e1);
    let v = dot(ray.dir, q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    Some(dot(e2, q) * inv)
}

/// An axis-aligned bounding box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Minimum corner.
    pub min: V3,
    /// Maximum corner.
    pub max: V3,
}

impl Aabb {
    /// The box holding nothing (the identity of [`Aabb::union`]).
    pub const EMPTY: Aabb = Aabb {
        min: [f64::INFINITY; 3],
        max: [f64::NEG_INFINITY; 3],
    };

    /// The smallest box holding both.
    pub fn union(&self, o: &Aabb) -> Aabb {
        Aabb {
            min: [0, 1, 2].map(|k| self.min[k].min(o.min[k])),
            max: [0, 1, 2].map(|k| self.max[k].max(o.max[k])),
        }
    }

    /// The smallest box holding the points.
    pub fn of_points<'a>(points: impl IntoIterator<Item = &'a V3>) -> Aabb {
        points
            .into_iter()
            .fold(Aabb::EMPTY, |b, p| b.union(&Aabb { min: *p, max: *p }))
    }

    /// Centre point.
    pub fn centre(&self) -> V3 {
        scale(add(self.min, self.max), 0.5)
    }

    /// The parameter range `[enter, exit]` in which the ray is inside the box, clipped to `span`
    /// (`None` when it misses). A zero direction component outside the slab misses.
    pub fn clip(&self, ray: &Ray, span: Span) -> Option<(f64, f64)> {
        let (mut lo, mut hi) = (span.min, span.max);
        for k in 0..3 {
            let (o, d) = (ray.origin[k], ray.dir[k]);
            if d == 0.0 {
                if o < self.min[k] || o > self.max[k] {
                    return None;
                }
                continue;
            }
            let (a, b) = ((self.min[k] - o) / d, (self.max[k] - o) / d);
            lo = lo.max(a.min(b));
            hi = hi.min(a.max(b));
            if lo > hi {
                return None;
            }
        }
        Some((lo, hi))
    }
}

/// The bounding box of a shape, or `None` for an unbounded one (a plane).
pub fn bounds(shape: &Shape) -> Option<Aabb> {
    let disk = |c: V3, r: f64, axis: V3| -> Aabb {
        // A disk of radius r perpendicular to the unit axis spans r·√(1 − a_k²) along axis k.
        let ext = axis.map(|a| r * (1.0 - a * a).max(0.0).sqrt());
        Aabb {
            min: sub(c, ext),
            max: add(c, ext),
        }
    };
    let b = match shape {
        Shape::Sphere { centre, radius } => Aabb {
            min: centre.map(|c| c - radius),
            max: centre.map(|c| c + radius),
        },
        Shape::Ellipsoid { centre, radii } => Aabb {
            min: sub(*centre, *radii),
            max: add(*centre, *radii),
        },
        Shape::Plane { .. } => return None,
        Shape::Box { min, max } => Aabb {
            min: *min,
            max: *max,
        },
        Shape::Cylinder { p0, p1, radius } => {
            let a = normalize(sub(*p1, *p0))?;
            disk(*p0, *radius, a).union(&disk(*p1, *radius, a))
        }
        Shape::Cone { p0, r0, p1, r1 } => {
            let a = normalize(sub(*p1, *p0))?;
            disk(*p0, *r0, a).union(&disk(*p1, *r1, a))
        }
        Shape::Polygon { vertices, .. } => Aabb::of_points(vertices),
        Shape::Triangle { corners } => Aabb::of_points(corners),
    };
    // Padded by a relative hair so a surface lying in a box face is never clipped away.
    let pad = 1e-9
        * (1.0
            + b.min
                .iter()
                .chain(&b.max)
                .fold(0.0f64, |m, v| m.max(v.abs())));
    Some(Aabb {
        min: b.min.map(|v| v - pad),
        max: b.max.map(|v| v + pad),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ray(o: V3, d: V3) -> Ray {
        Ray { origin: o, dir: d }
    }
    const ALL: Span = Span {
        min: 1e-9,
        max: f64::INFINITY,
        min_inclusive: false,
    };

    fn hit(shape: &Shape, o: V3, d: V3) -> Option<(f64, V3)> {
        intersect(shape, &ray(o, d), ALL).map(|h| (h.t, h.normal))
    }

    fn close(a: (f64, V3), b: (f64, V3)) -> bool {
        (a.0 - b.0).abs() < 1e-9 && (0..3).all(|k| (a.1[k] - b.1[k]).abs() < 1e-9)
    }

    #[test]
    fn each_shape_from_outside_and_inside() {
        let down = [0.0, 0.0, -1.0];
        let from = [0.0, 0.0, 10.0];
        // (shape, hit from (0, 0, 10) looking down z, hit from the centre looking down z)
        type Case = (Shape, (f64, V3), (f64, V3));
        let cases: Vec<Case> = vec![
            (
                Shape::Sphere {
                    centre: [0.0; 3],
                    radius: 2.0,
                },
                (8.0, [0.0, 0.0, 1.0]),
                (2.0, [0.0, 0.0, -1.0]),
            ),
            (
                Shape::Ellipsoid {
                    centre: [0.0; 3],
                    radii: [1.0, 2.0, 3.0],
                },
                (7.0, [0.0, 0.0, 1.0]),
                (3.0, [0.0, 0.0, -1.0]),
            ),
            (
                Shape::Box {
                    min: [-1.0; 3],
                    max: [1.0; 3],
                },
                (9.0, [0.0, 0.0, 1.0]),
                (1.0, [0.0, 0.0, -1.0]),
            ),
            (
                Shape::Cylinder {
                    p0: [0.0, 0.0, -1.0],
                    p1: [0.0, 0.0, 1.0],
                    radius: 0.5,
                },
                (9.0, [0.0, 0.0, 1.0]),
                (1.0, [0.0, 0.0, -1.0]),
            ),
            (
                Shape::Cone {
                    p0: [0.0, 0.0, -1.0],
                    r0: 1.0,
                    p1: [0.0, 0.0, 1.0],
                    r1: 0.5,
                },
                (9.0, [0.0, 0.0, 1.0]),
                (1.0, [0.0, 0.0, -1.0]),
            ),
        ];
        for (shape, outside, inside) in &cases {
            let o = hit(shape, from, down).unwrap();
            assert!(close(o, *outside), "{shape:?}: {o:?}");
            let i = hit(shape, [0.0; 3], down).unwrap();
            assert!(close(i, *inside), "{shape:?}: {i:?}");
            assert!(hit(shape, from, [0.0, 0.0, 1.0]).is_none());
            assert!(bounds(shape).is_some());
        }
    }

    #[test]
    fn side_walls_of_cylinder_and_cone() {
        let cyl = Shape::Cylinder {
            p0: [0.0, -1.0, 0.0],
            p1: [0.0, 1.0, 0.0],
            radius: 0.5,
        };
        let h = hit(&cyl, [5.0, 0.3, 0.0], [-1.0, 0.0, 0.0]).unwrap();
        assert!(close(h, (4.5, [1.0, 0.0, 0.0])), "{h:?}");
        // Above the cap: misses the wall.
        assert!(hit(&cyl, [5.0, 1.2, 0.0], [-1.0, 0.0, 0.0]).is_none());
        // A cone of half-angle 45°: apex at y = 1, radius 1 at y = 0.
        let cone = Shape::Cone {
            p0: [0.0, 0.0, 0.0],
            r0: 1.0,
            p1: [0.0, 1.0, 0.0],
            r1: 0.0,
        };
        let h = hit(&cone, [5.0, 0.5, 0.0], [-1.0, 0.0, 0.0]).unwrap();
        let s = 0.5f64.sqrt();
        assert!(close(h, (4.5, [s, s, 0.0])), "{h:?}");
        // From below: the base disk.
        let h = hit(&cone, [0.2, -3.0, 0.0], [0.0, 1.0, 0.0]).unwrap();
        assert!(close(h, (3.0, [0.0, -1.0, 0.0])), "{h:?}");
    }

    #[test]
    fn concave_polygon_and_triangle_and_plane() {
        // An L shape in z = 0, counter-clockwise from +z.
        let l = Shape::Polygon {
            vertices: vec![
                [0.0, 0.0, 0.0],
                [2.0, 0.0, 0.0],
                [2.0, 1.0, 0.0],
                [1.0, 1.0, 0.0],
                [1.0, 2.0, 0.0],
                [0.0, 2.0, 0.0],
            ],
            normal: [0.0, 0.0, 1.0],
        };
        let down = [0.0, 0.0, -1.0];
        assert!(hit(&l, [0.5, 1.5, 1.0], down).is_some());
        assert!(hit(&l, [1.5, 0.5, 1.0], down).is_some());
        assert!(hit(&l, [1.5, 1.5, 1.0], down).is_none(), "the notch");
        // From behind: same normal (outward), the caller flips it.
        let h = hit(&l, [0.5, 0.5, -1.0], [0.0, 0.0, 1.0]).unwrap();
        assert!(close(h, (1.0, [0.0, 0.0, 1.0])));
        let tri = Shape::Triangle {
            corners: [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        };
        assert!(close(
            hit(&tri, [0.2, 0.2, 3.0], down).unwrap(),
            (3.0, [0.0, 0.0, 1.0])
        ));
        assert!(hit(&tri, [0.6, 0.6, 3.0], down).is_none());
        let plane = Shape::Plane {
            normal: [0.0, 1.0, 0.0],
            d: 1.0,
        };
        assert!(close(
            hit(&plane, [0.0, 2.0, 0.0], [0.0, -1.0, 0.0]).unwrap(),
            (3.0, [0.0, 1.0, 0.0])
        ));
        assert!(hit(&plane, [0.0, 2.0, 0.0], [1.0, 0.0, 0.0]).is_none());
        assert!(bounds(&plane).is_none());
    }

    #[test]
    fn spans_select_roots() {
        let s = Shape::Sphere {
            centre: [0.0; 3],
            radius: 1.0,
        };
        let r = ray([0.0, 0.0, 5.0], [0.0, 0.0, -1.0]);
        assert_eq!(intersect(&s, &r, Span::open(4.5, 10.0)).unwrap().t, 6.0);
        assert!(intersect(&s, &r, Span::open(0.0, 4.0)).is_none());
        let inclusive = Span {
            min: 4.0,
            max: 10.0,
            min_inclusive: true,
        };
        assert_eq!(intersect(&s, &r, inclusive).unwrap().t, 4.0);
        assert_eq!(intersect(&s, &r, Span::open(4.0, 10.0)).unwrap().t, 6.0);
    }

    #[test]
    fn every_bounded_hit_is_inside_its_box() {
        let shapes = [
            Shape::Cylinder {
                p0: [0.3, -1.0, 0.2],
                p1: [1.0, 1.0, -0.5],
                radius: 0.4,
            },
            Shape::Cone {
                p0: [0.0, -1.0, 0.0],
                r0: 0.8,
                p1: [0.5, 1.0, 0.5],
                r1: 0.1,
            },
            Shape::Ellipsoid {
                centre: [0.1, 0.2, 0.3],
                radii: [0.5, 1.0, 0.7],
            },
        ];
        for shape in &shapes {
            let b = bounds(shape).unwrap();
            let mut hits = 0;
            for i in 0..400 {
                let a = i as f64 * 0.7;
                let o = [3.0 * a.cos(), 1.5 * (a * 0.37).sin(), 3.0 * a.sin()];
                let r = ray(o, sub([0.0, (a * 1.3).sin(), 0.0], o));
                if let Some(h) = intersect(shape, &r, ALL) {
                    hits += 1;
                    let p = r.at(h.t);
                    assert!((0..3).all(|k| p[k] >= b.min[k] - 1e-9 && p[k] <= b.max[k] + 1e-9));
                    assert!(b.clip(&r, ALL).is_some());
                }
            }
            assert!(hits > 50, "{shape:?}: {hits}");
        }
    }
}
