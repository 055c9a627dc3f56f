//! Traced primitives in fixed point: what each stores, and constructors that validate it.
//!
//! Every primitive is built from [`I16F16`] input (what `sim export` writes as raw bits) by a
//! constructor that checks the envelope (every point within ±[`MAX_COORD`], radii positive) and
//! precomputes what the intersection test needs (unit normals, squared radii, a polygon's
//! projection axis). Ray–primitive intersection lives in [`crate::trace::intersect`].

use crate::trace::vector::{Vec3, MAX_COORD};
use fixed::types::{I16F16, I32F32};

/// Why a primitive was rejected.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShapeError {
    /// A point lies outside ±[`MAX_COORD`] on some axis.
    OutOfEnvelope,
    /// A radius (or an ellipsoid semi-axis) is not positive, or above [`MAX_COORD`].
    BadRadius,
    /// A plane normal, a cylinder or cone axis, or a polygon's area is (nearly) zero.
    Degenerate,
    /// A polygon has fewer than 3 vertices.
    TooFewVertices,
    /// A polygon's vertices are not on one plane (farther than [`PLANARITY_TOLERANCE`]).
    NotPlanar,
}

impl core::fmt::Display for ShapeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            ShapeError::OutOfEnvelope => "a point is outside the tracer's coordinate envelope",
            ShapeError::BadRadius => "a radius is not positive or is too large",
            ShapeError::Degenerate => "a normal, axis or area is zero",
            ShapeError::TooFewVertices => "a polygon needs at least 3 vertices",
            ShapeError::NotPlanar => "a polygon's vertices are not on one plane",
        })
    }
}

impl core::error::Error for ShapeError {}

/// How far (world units) a polygon vertex may lie off the polygon's plane: 2^-8.
pub const PLANARITY_TOLERANCE: I16F16 = I16F16::from_bits(1 << 8);

fn check_point(p: Vec3) -> Result<Vec3, ShapeError> {
    if p.in_envelope() {
        Ok(p)
    } else {
        Err(ShapeError::OutOfEnvelope)
    }
}

fn check_radius(r: I16F16) -> Result<I16F16, ShapeError> {
    if r > I16F16::ZERO && r <= MAX_COORD {
        Ok(r)
    } else {
        Err(ShapeError::BadRadius)
    }
}

/// A sphere.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sphere {
    /// Centre.
    pub centre: Vec3,
    /// Radius, in (0, [`MAX_COORD`]].
    pub radius: I16F16,
    /// radius², exact.
    pub radius2: I32F32,
}

impl Sphere {
    /// A sphere, or an error for a centre outside the envelope or a bad radius.
    pub fn new(centre: Vec3, radius: I16F16) -> Result<Sphere, ShapeError> {
        let radius = check_radius(radius)?;
        Ok(Sphere {
            centre: check_point(centre)?,
            radius,
            radius2: radius.wide_mul(radius),
        })
    }
}

/// An infinite plane `n·p + d = 0`; its outside is the side `n` points to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Plane {
    /// Unit normal.
    pub normal: Vec3,
    /// Offset `d` for the unit normal.
    pub offset: I16F16,
}

impl Plane {
    /// The plane `n·p + d = 0` (`n` need not be unit: both are divided by its length).
    pub fn new(normal: Vec3, d: I16F16) -> Result<Plane, ShapeError> {
        check_point(normal)?;
        let len = crate::trace::vector::sqrt(normal.dot(normal));
        let normal = normal.normalized().ok_or(ShapeError::Degenerate)?;
        let offset = d.checked_div(len).ok_or(ShapeError::Degenerate)?;
        if offset.abs() > MAX_COORD {
            return Err(ShapeError::OutOfEnvelope);
        }
        Ok(Plane { normal, offset })
    }
}

/// The plane of a polygon or triangle and the axis dropped for the 2D point-in-polygon test.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Facet {
    /// Unit normal (counter-clockwise vertex order seen from the side it points to).
    pub normal: Vec3,
    /// Offset `d` with `normal·p + d = 0` on the plane.
    pub offset: I16F16,
    /// The axis (0 = x, 1 = y, 2 = z) of the normal's largest component: the test projects
    /// onto the other two.
    pub axis: u8,
}

impl Facet {
    /// The plane through `vertices` (Newell's normal, computed in f64 at set-up), checked for
    /// planarity.
    fn new(vertices: &[Vec3]) -> Result<Facet, ShapeError> {
        if vertices.len() < 3 {
            return Err(ShapeError::TooFewVertices);
        }
        let mut n = [0f64; 3];
        for (i, a) in vertices.iter().enumerate() {
            check_point(*a)?;
            let b = vertices
                .get(i + 1)
                .or(vertices.first())
                .ok_or(ShapeError::TooFewVertices)?;
            let (a, b) = (a.bits().map(f64::from), b.bits().map(f64::from));
            n[0] += (a[1] - b[1]) * (a[2] + b[2]);
            n[1] += (a[2] - b[2]) * (a[0] + b[0]);
            n[2] += (a[0] - b[0]) * (a[1] + b[1]);
        }
        // n is twice the area vector, in raw units squared (2^32 per world unit²).
        let len = libm::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if len < 65536.0 {
            return Err(ShapeError::Degenerate); // area below 2^-16 world units²
        }
        let unit = n.map(|c| (c / len * 65536.0) as i32);
        let normal = Vec3::from_bits(unit[0], unit[1], unit[2]);
        let first = *vertices.first().ok_or(ShapeError::TooFewVertices)?;
        let offset =
            crate::trace::vector::narrow(-normal.dot(first)).ok_or(ShapeError::OutOfEnvelope)?;
        let tolerance = I32F32::from(PLANARITY_TOLERANCE);
        for v in vertices {
            if (normal.dot(*v) + I32F32::from(offset)).abs() > tolerance {
                return Err(ShapeError::NotPlanar);
            }
        }
        Ok(Facet {
            normal,
            offset,
            axis: dominant_axis(normal),
        })
    }
}

/// The axis (0 = x, 1 = y, 2 = z) of `normal`'s largest component, the first of equal ones:
/// the axis a polygon's point-in-polygon test and a checker texture drop.
pub fn dominant_axis(normal: Vec3) -> u8 {
    let [x, y, z] = normal.bits().map(i32::unsigned_abs);
    if x >= y && x >= z {
        0
    } else if y >= z {
        1
    } else {
        2
    }
}

/// A planar polygon, convex or concave, borrowing its vertices (which may be `static`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Polygon<'a> {
    /// Vertices in order (counter-clockwise seen from outside).
    pub vertices: &'a [Vec3],
    /// Its plane.
    pub facet: Facet,
}

impl<'a> Polygon<'a> {
    /// A polygon, or an error for fewer than 3 vertices, zero area, a vertex off the plane or
    /// outside the envelope.
    pub fn new(vertices: &'a [Vec3]) -> Result<Polygon<'a>, ShapeError> {
        Ok(Polygon {
            facet: Facet::new(vertices)?,
            vertices,
        })
    }
}

/// A triangle (a mesh face), its vertices held inline.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Triangle {
    /// Corners, counter-clockwise seen from outside.
    pub vertices: [Vec3; 3],
    /// Its plane.
    pub facet: Facet,
}

impl Triangle {
    /// A triangle, or an error for zero area or a corner outside the envelope.
    pub fn new(vertices: [Vec3; 3]) -> Result<Triangle, ShapeError> {
        Ok(Triangle {
            facet: Facet::new(&vertices)?,
            vertices,
        })
    }
}

/// An axis-aligned box.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AaBox {
    /// Minimum corner.
    pub min: Vec3,
    /// Maximum corner (greater than `min` on every axis).
    pub max: Vec3,
}

impl AaBox {
    /// A box from its corners (min, max), or an error for a corner outside the envelope or
    /// `min ≥ max` on some axis.
    pub fn new(min: Vec3, max: Vec3) -> Result<AaBox, ShapeError> {
        let (min, max) = (check_point(min)?, check_point(max)?);
        if min.x >= max.x || min.y >= max.y || min.z >= max.z {
            return Err(ShapeError::Degenerate);
        }
        Ok(AaBox { min, max })
    }
}

/// An axis-aligned ellipsoid, traced as a sphere of radius `scale_radius` in coordinates
/// scaled per axis by `scale` = smallest semi-axis / semi-axis (so every factor is ≤ 1 and keeps
/// 16 fraction bits).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Ellipsoid {
    /// Centre.
    pub centre: Vec3,
    /// Semi-axes along x, y, z.
    pub radii: Vec3,
    /// Per-axis factors smallest semi-axis / semi-axis, in (0, 1].
    pub scale: Vec3,
    /// The smallest semi-axis.
    pub scale_radius: I16F16,
}

impl Ellipsoid {
    /// An ellipsoid, or an error for a centre outside the envelope or a bad semi-axis (the
    /// ratio of the largest to the smallest must stay below 2^8).
    pub fn new(centre: Vec3, radii: Vec3) -> Result<Ellipsoid, ShapeError> {
        let (rx, ry, rz) = (
            check_radius(radii.x)?,
            check_radius(radii.y)?,
            check_radius(radii.z)?,
        );
        let small = rx.min(ry).min(rz);
        let factor = |r: I16F16| small.checked_div(r).ok_or(ShapeError::BadRadius);
        let scale = Vec3 {
            x: factor(rx)?,
            y: factor(ry)?,
            z: factor(rz)?,
        };
        if scale
            .x
            .to_bits()
            .min(scale.y.to_bits())
            .min(scale.z.to_bits())
            < 1 << 8
        {
            return Err(ShapeError::BadRadius);
        }
        Ok(Ellipsoid {
            centre: check_point(centre)?,
            radii,
            scale,
            scale_radius: small,
        })
    }
}

/// A capped frustum along `base → base + axis·height` with radius `r0` at the base and `r1`
/// at the top (`r0 = r1`: a capped cylinder; `r1 = 0`: a cone).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Frustum {
    /// Centre of the first cap.
    pub base: Vec3,
    /// Unit axis from the first cap to the second.
    pub axis: Vec3,
    /// Distance between the caps.
    pub height: I16F16,
    /// Radius at the first cap.
    pub r0: I16F16,
    /// Radius at the second cap.
    pub r1: I16F16,
    /// Radius change per unit of height, `(r1 − r0) / height`, at most 2^7 in magnitude.
    pub slope: I16F16,
}

impl Frustum {
    /// A capped cylinder from `p0` to `p1` of radius `r`.
    pub fn cylinder(p0: Vec3, p1: Vec3, r: I16F16) -> Result<Frustum, ShapeError> {
        Frustum::new(p0, r, p1, r)
    }

    /// A capped frustum from `p0` (radius `r0`) to `p1` (radius `r1`); both radii ≥ 0, not both
    /// 0; an error for caps closer than 2^-8 or a slope above 2^7.
    pub fn new(p0: Vec3, r0: I16F16, p1: Vec3, r1: I16F16) -> Result<Frustum, ShapeError> {
        let (p0, p1) = (check_point(p0)?, check_point(p1)?);
        let ok = |r: I16F16| r >= I16F16::ZERO && r <= MAX_COORD;
        if !ok(r0) || !ok(r1) || (r0 == I16F16::ZERO && r1 == I16F16::ZERO) {
            return Err(ShapeError::BadRadius);
        }
        let d = p1.sub(p0);
        let height = crate::trace::vector::sqrt(d.dot(d));
        if height < I16F16::from_bits(1 << 8) {
            return Err(ShapeError::Degenerate);
        }
        let axis = d.normalized().ok_or(ShapeError::Degenerate)?;
        let slope = (r1 - r0)
            .checked_div(height)
            .filter(|k| k.abs() <= I16F16::from_num(128))
            .ok_or(ShapeError::Degenerate)?;
        Ok(Frustum {
            base: p0,
            axis,
            height,
            r0,
            r1,
            slope,
        })
    }
}

/// A traced primitive.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape<'a> {
    /// A sphere.
    Sphere(Sphere),
    /// An infinite plane.
    Plane(Plane),
    /// A planar polygon.
    Polygon(Polygon<'a>),
    /// A triangle.
    Triangle(Triangle),
    /// An axis-aligned box.
    Box(AaBox),
    /// An axis-aligned ellipsoid.
    Ellipsoid(Ellipsoid),
    /// A capped cylinder or cone frustum.
    Frustum(Frustum),
}

impl Shape<'_> {
    /// The axis a checker texture drops on this primitive (its normal's largest, as the
    /// point-in-polygon test), or `None` for a primitive that cannot carry one: only planes and
    /// polygons are textured.
    #[inline]
    pub fn texture_axis(&self) -> Option<u8> {
        match self {
            Shape::Plane(p) => Some(dominant_axis(p.normal)),
            Shape::Polygon(p) => Some(p.facet.axis),
            _ => None,
        }
    }
}

/// A primitive with its surface: a material, or a checker texture of two materials.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Object<'a> {
    /// The primitive.
    pub shape: Shape<'a>,
    /// The surface: an index into [`Scene::materials`](crate::trace::scene::Scene::materials),
    /// or, from `materials.len()` on, `materials.len() + k` for checker k of
    /// [`Scene::checkers`](crate::trace::scene::Scene::checkers).
    pub material: u16,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f32, y: f32, z: f32) -> Vec3 {
        Vec3 {
            x: I16F16::from_num(x),
            y: I16F16::from_num(y),
            z: I16F16::from_num(z),
        }
    }

    #[test]
    fn constructors_reject_bad_input() {
        let one = I16F16::ONE;
        assert_eq!(
            Sphere::new(v(0.0, 0.0, 0.0), I16F16::ZERO),
            Err(ShapeError::BadRadius)
        );
        assert_eq!(
            Sphere::new(v(5000.0, 0.0, 0.0), one),
            Err(ShapeError::OutOfEnvelope)
        );
        assert_eq!(Plane::new(Vec3::ZERO, one), Err(ShapeError::Degenerate));
        let line = [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(2.0, 0.0, 0.0)];
        assert_eq!(Polygon::new(&line).err(), Some(ShapeError::Degenerate));
        assert_eq!(
            Polygon::new(&line[..2]).err(),
            Some(ShapeError::TooFewVertices)
        );
        let bent = [
            v(0.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(1.0, 1.0, 0.0),
            v(0.0, 1.0, 0.5),
        ];
        assert_eq!(Polygon::new(&bent).err(), Some(ShapeError::NotPlanar));
    }

    #[test]
    fn polygon_normal_follows_vertex_order() {
        let square = [
            v(0.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(1.0, 1.0, 0.0),
            v(0.0, 1.0, 0.0),
        ];
        let p = Polygon::new(&square).unwrap();
        assert_eq!(p.facet.normal, v(0.0, 0.0, 1.0));
        assert_eq!(p.facet.axis, 2);
        let plane = Plane::new(v(0.0, 2.0, 0.0), I16F16::from_num(-4)).unwrap();
        assert_eq!(
            (plane.normal, plane.offset),
            (v(0.0, 1.0, 0.0), I16F16::from_num(-2))
        );
    }
}
