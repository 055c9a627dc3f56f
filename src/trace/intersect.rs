//! Ray–primitive intersection in fixed point: the nearest `t` in a window, and the surface normal
//! at a hit.
//!
//! A ray is `origin + t·dir` with `dir` a unit [`Vec3`] and `t` an [`I16F16`] in world units.
//! Each test returns the smallest root `t` with `t_min ≤ t < t_max`; roots outside the I16F16
//! range are no hit. Intermediate products are I32F32 (see the bit budget in
//! [`crate::trace::vector`]). Planes and polygons (the classic scene's floor) check the window
//! on exact products and then divide in 32 bits ([`ratio16`], within 2^-25 relative); the
//! other primitives' quotients are 64-bit integer divisions of raw bits.

use crate::math::{mul_i64, mul_wide_u32};
use crate::trace::shape::{AaBox, Ellipsoid, Facet, Frustum, Plane, Shape, Sphere};
use crate::trace::vector::{
    mul, narrow, narrow_bits, narrow_bits_in_range, ratio16, sqrt, wide, Vec3,
};
use fixed::types::{I16F16, I32F32};

/// A ray: origin and unit direction.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Ray {
    /// Origin.
    pub origin: Vec3,
    /// Unit direction.
    pub dir: Vec3,
}

/// `num / den` for two I32F32 values, as an I16F16, or `None` if `den` is 0 or the quotient is
/// outside the I16F16 range.
#[inline]
fn quotient(num: I32F32, den: I32F32) -> Option<I16F16> {
    let den = den.to_bits();
    if den == 0 {
        return None;
    }
    // num (|num| < 2^47 raw in the envelope) << 16 stays below 2^63.
    let q = num.to_bits().checked_mul(1 << 16)?.checked_div(den)?;
    i32::try_from(q).ok().map(I16F16::from_bits)
}

/// The first of the sorted roots `a ≤ b` inside `[t_min, t_max)`.
#[inline]
fn first_root(a: I16F16, b: I16F16, t_min: I16F16, t_max: I16F16) -> Option<I16F16> {
    [a, b].into_iter().find(|t| *t >= t_min && *t < t_max)
}

fn sphere(s: &Sphere, ray: &Ray, t_min: I16F16, t_max: I16F16) -> Option<I16F16> {
    let oc = ray.origin.sub(s.centre);
    // b = dir·oc ≤ |oc| < 2^14.5: fits I16F16.
    let b = narrow(ray.dir.dot(oc))?;
    // The discriminant b² − (|oc|² − r²) loses |b| · 2^-15 to the rounding of b, which the
    // square root amplifies near a silhouette (a hit 10^-3 off for |b| ≈ 6). For |b| > r it is
    // computed as r² − |q|² instead, q = oc − b·dir the closest approach to the centre:
    // rounding b moves q along dir, leaving |q|² unchanged to first order (error about
    // r · 2^-15). Each form is used where its error is the smaller, so rays leaving the
    // surface (|b| ≤ r) do not meet it again beyond EPSILON.
    let disc = if b.unsigned_abs() <= s.radius.unsigned_abs() {
        I32F32::from_bits(wide(b.to_bits(), b.to_bits())) - (oc.dot(oc) - s.radius2)
    } else {
        // A ray's direction (components at most 1 + 2^-12, a reflected one's) times
        // |b| < 2^14, as it is for an origin in the envelope (|oc| < 2^13.8): no range test.
        let along = if b.to_bits().unsigned_abs() < 1 << 30 {
            ray.dir.scale_in_range(b)
        } else {
            ray.dir.scale(b)
        };
        let q = oc.sub(along);
        s.radius2 - q.dot(q)
    };
    if disc < I32F32::ZERO {
        return None;
    }
    let root = sqrt(disc);
    let nb = b.wrapping_neg();
    first_root(nb.wrapping_sub(root), nb.wrapping_add(root), t_min, t_max)
}

/// `t` in `[t_min, t_max)` where the ray meets the plane `normal·p + offset = 0`, if any.
///
/// The window is checked first, on `t·den = −num` in exact 64-bit products (the same decision
/// as filtering the truncated quotient), so a plane met outside it costs no division; inside
/// it `t` is [`ratio16`] (32-bit reciprocal, within 2^-25 relative), kept in the window. A
/// window starting at or below 0 or a numerator beyond 2^47 raw takes the exact 64-bit
/// quotient instead.
#[inline]
fn plane_t_in(
    normal: Vec3,
    offset: I16F16,
    ray: &Ray,
    t_min: I16F16,
    t_max: I16F16,
) -> Option<I16F16> {
    let num = normal.dot(ray.origin) + I32F32::from(offset);
    let den = normal.dot(ray.dir);
    // t = n / d with d > 0: the signs moved to the numerator.
    let (n, d) = if den < I32F32::ZERO {
        (num.to_bits(), den.to_bits().checked_neg()?)
    } else {
        (num.to_bits().checked_neg()?, den.to_bits())
    };
    if d == 0 {
        return None;
    }
    if t_min > I16F16::ZERO && t_max >= t_min && n.unsigned_abs() < 1 << 47 {
        // d ≤ 2^33 raw (a dot product of two unit vectors) and t ≤ 2^31 raw: the products fit
        // a u64, as does n · 2^16 for |n| < 2^47. A negative n gives t ≤ 0 < t_min.
        let (d, scaled) = (d as u64, (n as u64) << 16);
        let (lo, hi) = (t_min.to_bits() as u32, t_max.to_bits() as u32);
        if n < 0 || scaled < times_below_2_33(lo, d) || scaled >= times_below_2_33(hi, d) {
            return None;
        }
        // Inside the window: t without a 64-bit division (within 2^-25 relative, see
        // `ratio16`), kept inside the window the exact check found.
        let t = ratio16(n as u64, d)
            .max(u64::from(lo))
            .min(u64::from(hi) - 1);
        return Some(I16F16::from_bits(t as i32));
    }
    quotient(-num, den).filter(|t| *t >= t_min && *t < t_max)
}

/// `a · d` for `d ≤ 2^33` and a product below 2^64: on ARMv6-M (no 32 × 32 → 64-bit
/// multiply, `math::NO_WIDE_MULTIPLY`) [`times_below_2_33_in_words`], elsewhere the `u64`
/// multiply.
#[inline]
fn times_below_2_33(a: u32, d: u64) -> u64 {
    if crate::math::NO_WIDE_MULTIPLY {
        times_below_2_33_in_words(a, d)
    } else {
        u64::from(a) * d
    }
}

/// [`times_below_2_33`] from `d`'s low word's 32-bit multiplies (`math::mul_wide_u32`) and its
/// high word (at most 2) times `a`, on every target (test
/// `window_products_in_words_are_exact`, on the host too).
#[inline]
fn times_below_2_33_in_words(a: u32, d: u64) -> u64 {
    mul_wide_u32(a, d as u32).wrapping_add(u64::from(a.wrapping_mul((d >> 32) as u32)) << 32)
}

fn plane(p: &Plane, ray: &Ray, t_min: I16F16, t_max: I16F16) -> Option<I16F16> {
    plane_t_in(p.normal, p.offset, ray, t_min, t_max)
}

/// Whether the ray meets the plane `normal·p + offset = 0` at some `t ≥ t_min`, however far:
/// `t·den = −num` compared exactly in 128 bits, no quotient. [`plane_t_in`] decides its
/// window's lower end by the same comparison.
fn plane_met_from(normal: Vec3, offset: I16F16, ray: &Ray, t_min: I16F16) -> bool {
    let num = i128::from((normal.dot(ray.origin) + I32F32::from(offset)).to_bits());
    let den = i128::from(normal.dot(ray.dir).to_bits());
    // t = n / d with d > 0: the signs moved to the numerator.
    let (n, d) = if den < 0 { (num, -den) } else { (-num, den) };
    d != 0 && (n << 16) >= i128::from(t_min.to_bits()) * d
}

/// The two coordinates of `p` other than `axis`, raw I16F16 bits.
#[inline]
fn project(p: Vec3, axis: u8) -> (i64, i64) {
    let [x, y, z] = p.bits();
    match axis {
        0 => (y as i64, z as i64),
        1 => (z as i64, x as i64),
        _ => (x as i64, y as i64),
    }
}

/// Even–odd point-in-polygon test in the facet's projection (crossing number; concave
/// polygons work). Exact: every product is of two raw differences below 2^30.
fn inside(vertices: &[Vec3], axis: u8, p: Vec3) -> bool {
    let (pu, pv) = project(p, axis);
    let mut inside = false;
    let mut prev = match vertices.last() {
        Some(v) => project(*v, axis),
        None => return false,
    };
    for v in vertices {
        let (bu, bv) = project(*v, axis);
        let (au, av) = prev;
        if (av > pv) != (bv > pv) {
            // p is left of the crossing point ⇔ (pu − au)(bv − av) < (pv − av)(bu − au), the
            // inequality flipping when bv < av.
            // (`mul_i64`: 32-bit multiplies on ARMv6-M for differences that fit 32 bits.)
            let lhs = mul_i64(pu - au, bv - av);
            let rhs = mul_i64(pv - av, bu - au);
            if (bv > av && lhs < rhs) || (bv < av && lhs > rhs) {
                inside = !inside;
            }
        }
        prev = (bu, bv);
    }
    inside
}

fn facet(f: &Facet, vertices: &[Vec3], ray: &Ray, t_min: I16F16, t_max: I16F16) -> Option<I16F16> {
    let t = plane_t_in(f.normal, f.offset, ray, t_min, t_max)?;
    inside(vertices, f.axis, ray.origin.along_ray(ray.dir, t)).then_some(t)
}

/// `a / b` for two I16F16 values, saturating to the I16F16 range (±∞ for `b` = 0).
#[inline]
fn div(a: I16F16, b: I16F16) -> I16F16 {
    let (a, b) = (a.to_bits() as i64, b.to_bits() as i64);
    let q = if b == 0 {
        if a < 0 {
            i64::MIN
        } else {
            i64::MAX
        }
    } else {
        (a << 16) / b
    };
    I16F16::from_bits(q.clamp(i32::MIN as i64, i32::MAX as i64) as i32)
}

/// The interval `(t_in, t_out)` in which the ray is inside the box (slab test), if any.
fn box_span(b: &AaBox, ray: &Ray) -> Option<(I16F16, I16F16)> {
    let (mut t_in, mut t_out) = (I16F16::MIN, I16F16::MAX);
    let axes = [
        (ray.origin.x, ray.dir.x, b.min.x, b.max.x),
        (ray.origin.y, ray.dir.y, b.min.y, b.max.y),
        (ray.origin.z, ray.dir.z, b.min.z, b.max.z),
    ];
    for (o, d, lo, hi) in axes {
        if d == I16F16::ZERO {
            if o < lo || o > hi {
                return None;
            }
            continue;
        }
        // A quotient too large for I16F16 saturates: a slab boundary beyond every window.
        let t1 = div(lo.wrapping_sub(o), d);
        let t2 = div(hi.wrapping_sub(o), d);
        let (a, b) = if t1 <= t2 { (t1, t2) } else { (t2, t1) };
        t_in = t_in.max(a);
        t_out = t_out.min(b);
    }
    (t_in <= t_out).then_some((t_in, t_out))
}

/// `v` scaled per axis by `s` (components ≤ 1).
#[inline]
fn scale_axes(v: Vec3, s: Vec3) -> Vec3 {
    let (a, b) = (v.bits(), s.bits());
    let m = |x: i32, y: i32| narrow_bits(x as i64 * y as i64);
    Vec3::from_bits(m(a[0], b[0]), m(a[1], b[1]), m(a[2], b[2]))
}

/// `num / den` for two I32F32 values as an I16F16, truncated and saturated to the I16F16
/// range, or `None` if `den` is 0. A root beyond the range lies beyond every window, and so
/// does the saturated one.
#[inline]
fn quotient_saturating(num: I32F32, den: I32F32) -> Option<I16F16> {
    let (num, den) = (num.to_bits(), den.to_bits());
    if den == 0 {
        return None;
    }
    // The 64-bit quotient where num · 2^16 fits (the envelope's), else the 128-bit one.
    let q = match num.checked_mul(1 << 16).and_then(|n| n.checked_div(den)) {
        Some(q) => i128::from(q),
        None => (i128::from(num) << 16).checked_div(i128::from(den))?,
    };
    Some(I16F16::from_bits(
        q.clamp(i128::from(i32::MIN), i128::from(i32::MAX)) as i32,
    ))
}

/// What [`quadratic`] found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Roots {
    /// No real root: the quadratic keeps the sign of `A` everywhere.
    None,
    /// The two real roots, sorted, each saturated to the I16F16 range.
    Two(I16F16, I16F16),
    /// `A` is 0, or the values are beyond the arithmetic's range (outside the envelope).
    Unknown,
}

/// The roots of `A t² + 2B t + C = 0` (A, B, C in I32F32). The discriminant `B² − AC` is
/// formed in 128 bits. "No real root" and "a root beyond the I16F16 range" are told apart: a
/// frustum steeper than its side is inside everywhere in the first case, but in the second
/// only on one side of the other root.
///
/// The roots are `q / A` and `C / q` with `q = −B − sign(B)·√(B² − AC)`, whose two terms never
/// cancel: `(−B ± √(B² − AC)) / A` loses the smaller root to cancellation when `AC` is small
/// against `B²`, as for a ray nearly parallel to a cone's side, where `A` is at the size of
/// its own rounding and the quotient turns that error into any root at all.
fn quadratic(a: I32F32, b: I32F32, c: I32F32) -> Roots {
    let Some(disc) = (b.to_bits() as i128 * b.to_bits() as i128)
        .checked_sub(a.to_bits() as i128 * c.to_bits() as i128)
    else {
        return Roots::Unknown;
    };
    if disc < 0 {
        return Roots::None;
    }
    // 64 fraction bits → I32F32.
    let Ok(disc) = i64::try_from(disc >> 32) else {
        return Roots::Unknown;
    };
    let root = I32F32::from(sqrt(I32F32::from_bits(disc)));
    let q = if b >= I32F32::ZERO {
        b.checked_add(root).and_then(I32F32::checked_neg)
    } else {
        root.checked_sub(b)
    };
    let roots = q.and_then(|q| {
        if q == I32F32::ZERO {
            // B = 0 and B² = AC, so C = 0: the double root 0.
            return Some((I16F16::ZERO, I16F16::ZERO));
        }
        let t1 = quotient_saturating(q, a)?;
        let t2 = quotient_saturating(c, q)?;
        Some(if t1 <= t2 { (t1, t2) } else { (t2, t1) })
    });
    match roots {
        Some((t1, t2)) => Roots::Two(t1, t2),
        None => Roots::Unknown,
    }
}

/// Where a ray starts, for the quadratic's value `c` at `t = 0`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Start {
    /// Anywhere: `c` as computed.
    Anywhere,
    /// On the quadric surface itself (the ellipsoid, a frustum's side): `c` is 0. The origin
    /// is a rounded hit point, so the computed `c` is a rounding away from 0, and for a ray
    /// along the surface (an inward cosine of the size of that rounding) it moves the far
    /// root by much more than the rounding, or, positive, takes the discriminant `B² − AC`
    /// below 0 and loses the hit.
    OnQuadric,
    /// On a frustum's cap, inside the side's quadric: `c` at most 0.
    OnCap,
}

fn at_origin(c: I32F32, start: Start) -> I32F32 {
    match start {
        Start::Anywhere => c,
        Start::OnQuadric => I32F32::ZERO,
        Start::OnCap => c.min(I32F32::ZERO),
    }
}

/// The interval in which the ray is inside the ellipsoid: a sphere of radius `scale_radius`
/// in coordinates scaled by `scale`.
fn ellipsoid_span(e: &Ellipsoid, ray: &Ray, start: Start) -> Option<(I16F16, I16F16)> {
    let o = scale_axes(ray.origin.sub(e.centre), e.scale);
    let d = scale_axes(ray.dir, e.scale);
    let r = e.scale_radius;
    let c = at_origin(o.dot(o) - r.wide_mul(r), start);
    match quadratic(d.dot(d), d.dot(o), c) {
        Roots::Two(t1, t2) => Some((t1, t2)),
        Roots::None | Roots::Unknown => None,
    }
}

/// The interval in which the ray is inside the capped frustum: the side's quadratic clipped
/// to the slab between the caps.
fn frustum_span(f: &Frustum, ray: &Ray, start: Start) -> Option<(I16F16, I16F16)> {
    let oc = ray.origin.sub(f.base);
    let so = narrow(oc.dot(f.axis))?; // along the axis
    let sd = narrow(ray.dir.dot(f.axis))?;
    let q = oc.sub(f.axis.scale(so)); // perpendicular parts
    let e = ray.dir.sub(f.axis.scale(sd));
    // Side: |q + t e|² = (m + t·ks)², m = r0 + k·so the radius at the origin's height.
    let m = f.r0.checked_add(mul(f.slope, so))?;
    let ks = mul(f.slope, sd);
    let a = e.dot(e) - ks.wide_mul(ks);
    let b = q.dot(e) - m.wide_mul(ks);
    let c = at_origin(q.dot(q) - m.wide_mul(m), start);
    // Slab between the caps: 0 ≤ so + t·sd ≤ height.
    let (mut t_in, mut t_out) = (I16F16::MIN, I16F16::MAX);
    if sd == I16F16::ZERO {
        if so < I16F16::ZERO || so > f.height {
            return None;
        }
    } else {
        let t1 = div(so.wrapping_neg(), sd);
        let t2 = div(f.height.wrapping_sub(so), sd);
        let (lo, hi) = if t1 <= t2 { (t1, t2) } else { (t2, t1) };
        t_in = lo;
        t_out = hi;
    }
    // Within the slab the radius is ≥ 0 (linear between r0, r1 ≥ 0), so the ray is inside
    // where the side function a t² + 2b t + c ≤ 0; the frustum is convex, so that set meets
    // the slab's interval in an interval.
    if a > I32F32::ZERO {
        let Roots::Two(r1, r2) = quadratic(a, b, c) else {
            return None;
        };
        t_in = t_in.max(r1);
        t_out = t_out.min(r2);
    } else if a < I32F32::ZERO {
        // Steeper than the side: inside outside the roots (everywhere without roots).
        match quadratic(a, b, c) {
            Roots::None => {}
            Roots::Two(r1, r2) => {
                if t_out <= r1 || t_in >= r2 {
                    // The whole slab interval is inside.
                } else if t_in < r1 {
                    t_out = r1;
                } else if t_out > r2 {
                    t_in = r2;
                } else {
                    return None;
                }
            }
            Roots::Unknown => return None,
        }
    } else if b == I32F32::ZERO {
        // Parallel to the side (to the axis, for a cylinder): inside throughout or never.
        if c > I32F32::ZERO {
            return None;
        }
    } else {
        // 2b t + c ≤ 0.
        let t = quotient_saturating(c.checked_neg()?, b.checked_mul_int(2)?)?;
        if b > I32F32::ZERO {
            t_out = t_out.min(t);
        } else {
            t_in = t_in.max(t);
        }
    }
    (t_in <= t_out).then_some((t_in, t_out))
}

impl Shape<'_> {
    /// The nearest `t` in `[t_min, t_max)` where `ray` meets the primitive.
    #[inline]
    pub fn hit(&self, ray: &Ray, t_min: I16F16, t_max: I16F16) -> Option<I16F16> {
        match self {
            Shape::Sphere(s) => sphere(s, ray, t_min, t_max),
            Shape::Plane(p) => plane(p, ray, t_min, t_max),
            Shape::Polygon(p) => facet(&p.facet, p.vertices, ray, t_min, t_max),
            Shape::Triangle(t) => facet(&t.facet, &t.vertices, ray, t_min, t_max),
            Shape::Box(_) | Shape::Ellipsoid(_) | Shape::Frustum(_) => {
                let (t_in, t_out) = self.span(ray, Start::Anywhere)?;
                first_root(t_in, t_out, t_min, t_max)
            }
        }
    }

    /// The interval of `t` in which the ray is inside a closed convex primitive (box,
    /// ellipsoid, frustum); `None` for the others.
    fn span(&self, ray: &Ray, start: Start) -> Option<(I16F16, I16F16)> {
        match self {
            Shape::Box(b) => box_span(b, ray),
            Shape::Ellipsoid(e) => ellipsoid_span(e, ray, start),
            Shape::Frustum(f) => frustum_span(f, ray, start),
            _ => None,
        }
    }

    /// Whether a shadow ray meets the primitive in `[t_min, t_max)`, where `t_max` =
    /// `I16F16::MAX` stands for a ray without end (towards a directional light): an infinite
    /// plane blocks such a ray wherever it meets it, also beyond the I16F16 range of `t`, as a
    /// plane nearly parallel to the light does. A bounded primitive inside the envelope is
    /// met, if at all, well inside that range.
    #[inline]
    pub fn blocks(&self, ray: &Ray, t_min: I16F16, t_max: I16F16) -> bool {
        match self {
            Shape::Plane(p) if t_max == I16F16::MAX => {
                plane_met_from(p.normal, p.offset, ray, t_min)
            }
            _ => self.hit(ray, t_min, t_max).is_some(),
        }
    }

    /// [`hit`](Self::hit) for a ray that starts on this primitive's surface (a secondary or
    /// shadow ray leaving the hit that spawned it): the root at `t = 0` is the origin itself,
    /// not a hit. A plane, polygon or triangle is never met again; a sphere is met again only
    /// by a ray going inwards, at the chord's far end `t = −2·(dir·(origin − centre))`, a box,
    /// ellipsoid or frustum (convex too) at the far end of the ray's span inside it. Exact
    /// where solving the quadratic again would find a spurious root of the size of the hit
    /// point's rounding error divided by the cosine at the surface.
    #[inline]
    pub fn hit_from_surface(&self, ray: &Ray, t_min: I16F16, t_max: I16F16) -> Option<I16F16> {
        match self {
            Shape::Sphere(s) => {
                let b = narrow(ray.dir.dot(ray.origin.sub(s.centre)))?;
                // −2b, or `None` outside the I16F16 range: in 64 bits, since a checked 32-bit
                // product is a 64-bit multiply's library call on ARMv6-M.
                let t = I16F16::from_bits(i32::try_from(-2 * i64::from(b.to_bits())).ok()?);
                (t >= t_min && t < t_max).then_some(t)
            }
            Shape::Plane(_) | Shape::Polygon(_) | Shape::Triangle(_) => None,
            // Convex: a ray leaving the surface outwards never meets it again; one going
            // inwards meets it at the span's far end.
            Shape::Box(_) | Shape::Ellipsoid(_) | Shape::Frustum(_) => {
                let normal = self.normal(ray.origin);
                if normal.dot_bits(ray.dir) >= 0 {
                    return None;
                }
                // The origin lies on the feature whose normal it has.
                let start = match self {
                    Shape::Frustum(f) if normal == f.axis || normal == f.axis.neg() => Start::OnCap,
                    _ => Start::OnQuadric,
                };
                let (_, t_out) = self.span(ray, start)?;
                (t_out >= t_min && t_out < t_max).then_some(t_out)
            }
        }
    }

    /// The outward unit normal at `point` on the surface (for planes and polygons, the side
    /// the normal points to is outside).
    #[inline]
    pub fn normal(&self, point: Vec3) -> Vec3 {
        match self {
            Shape::Sphere(s) => {
                // From a radius of 1/2 a surface point's longest offset is above 2^-2, where
                // `unit` is `normalized`: the shorter test for most spheres.
                let offset = point.sub(s.centre);
                let unit = if s.radius >= I16F16::from_bits(1 << 15) {
                    offset.normalized()
                } else {
                    offset.unit()
                };
                unit.unwrap_or(Vec3::ZERO)
            }
            Shape::Plane(p) => p.normal,
            Shape::Polygon(p) => p.facet.normal,
            Shape::Triangle(t) => t.facet.normal,
            Shape::Box(b) => box_normal(b, point),
            Shape::Ellipsoid(e) => ellipsoid_normal(e, point),
            Shape::Frustum(f) => frustum_normal(f, point),
        }
    }

    /// The plane a planar primitive (plane, polygon, triangle) lies in, as its unit normal and
    /// offset; `None` for the others.
    /// [`hit`](Self::hit) for a ray known to meet a planar shape inside its outline, if it
    /// meets its plane in the window: the plane's `t` without the point-in-polygon test,
    /// exactly what `hit` returns then. Other shapes: `hit`.
    #[inline]
    pub(crate) fn hit_inside_outline(
        &self,
        ray: &Ray,
        t_min: I16F16,
        t_max: I16F16,
    ) -> Option<I16F16> {
        match self.plane() {
            Some((normal, offset)) => plane_t_in(normal, offset, ray, t_min, t_max),
            None => self.hit(ray, t_min, t_max),
        }
    }

    #[inline]
    pub(crate) fn plane(&self) -> Option<(Vec3, I16F16)> {
        match self {
            Shape::Plane(p) => Some((p.normal, p.offset)),
            Shape::Polygon(p) => Some((p.facet.normal, p.facet.offset)),
            Shape::Triangle(t) => Some((t.facet.normal, t.facet.offset)),
            Shape::Box(_) | Shape::Sphere(_) | Shape::Ellipsoid(_) | Shape::Frustum(_) => None,
        }
    }
}

/// Whether `ray` meets the plane (unit normal, offset) at some `t` in `[t_min, t_max)`: the
/// first step of every planar primitive's test, so a ray that does not meet a plane meets no
/// plane, polygon or triangle lying in it (same normal and offset, bit for bit).
#[inline]
pub(crate) fn meets_plane(plane: (Vec3, I16F16), ray: &Ray, t_min: I16F16, t_max: I16F16) -> bool {
    if t_max == I16F16::MAX {
        // A ray without end, as in `Shape::blocks`: an infinite plane among the group blocks
        // it beyond the range of `t` too.
        return plane_met_from(plane.0, plane.1, ray, t_min);
    }
    plane_t_in(plane.0, plane.1, ray, t_min, t_max).is_some()
}

/// The outward normal of the box face nearest `p`.
fn box_normal(b: &AaBox, p: Vec3) -> Vec3 {
    let one = I16F16::ONE;
    let faces = [
        (
            p.x - b.min.x,
            Vec3 {
                x: -one,
                ..Vec3::ZERO
            },
        ),
        (
            b.max.x - p.x,
            Vec3 {
                x: one,
                ..Vec3::ZERO
            },
        ),
        (
            p.y - b.min.y,
            Vec3 {
                y: -one,
                ..Vec3::ZERO
            },
        ),
        (
            b.max.y - p.y,
            Vec3 {
                y: one,
                ..Vec3::ZERO
            },
        ),
        (
            p.z - b.min.z,
            Vec3 {
                z: -one,
                ..Vec3::ZERO
            },
        ),
        (
            b.max.z - p.z,
            Vec3 {
                z: one,
                ..Vec3::ZERO
            },
        ),
    ];
    faces
        .into_iter()
        .min_by_key(|(d, _)| d.unsigned_abs())
        .map_or(Vec3::ZERO, |(_, n)| n)
}

/// The outward unit normal of the ellipsoid at `p`: ∇ of Σ (d_i · scale_i)², `d = p − centre`,
/// proportional to `d_i · scale_i²`. The products are exact (48 fraction bits; `|d_i| < 2^30`
/// raw inside the envelope and `scale_i ≤ 1`, so below 2^62), then shifted alike to a longest
/// component of 23 bits: `scale_i²` reaches 2^-16 on a thin ellipsoid, where products rounded
/// to I16F16 left too few bits, or none, near the tips of its long axes.
fn ellipsoid_normal(e: &Ellipsoid, p: Vec3) -> Vec3 {
    let ([dx, dy, dz], [sx, sy, sz]) = (p.sub(e.centre).bits(), e.scale.bits());
    let g = [(dx, sx), (dy, sy), (dz, sz)].map(|(d, s)| wide(d, s).wrapping_mul(i64::from(s)));
    let [gx, gy, gz] = g.map(i64::unsigned_abs);
    let longest = gx.max(gy).max(gz);
    if longest == 0 {
        return Vec3::ZERO;
    }
    let bits = 64 - longest.leading_zeros();
    let [x, y, z] = g.map(|c| {
        if bits > 23 {
            (c >> (bits - 23)) as i32
        } else {
            (c << (23 - bits)) as i32
        }
    });
    Vec3::from_bits(x, y, z).normalized().unwrap_or(Vec3::ZERO)
}

/// The outward normal of the frustum's cap or side nearest `p`.
fn frustum_normal(f: &Frustum, p: Vec3) -> Vec3 {
    let oc = p.sub(f.base);
    let s = narrow(oc.dot(f.axis)).unwrap_or(I16F16::ZERO);
    let radial = oc.sub(f.axis.scale(s));
    let r = sqrt(radial.dot(radial));
    let side = r
        .wrapping_sub(f.r0.saturating_add(mul(f.slope, s)))
        .unsigned_abs();
    let (bottom, top) = (s.unsigned_abs(), f.height.wrapping_sub(s).unsigned_abs());
    if bottom <= top && bottom < side {
        f.axis.neg()
    } else if top < side {
        f.axis
    } else {
        // (radial unit − slope · axis), normalised.
        radial
            .unit()
            .map(|u| u.sub(f.axis.scale(f.slope)))
            .and_then(Vec3::normalized)
            .unwrap_or(Vec3::ZERO)
    }
}

/// `a − 2(a·n)n`: the unit vector `a` (a ray's direction) mirrored about the plane with unit
/// normal `n`.
#[inline]
pub(crate) fn reflect(a: Vec3, n: Vec3) -> Vec3 {
    // Two unit vectors: |a·n| ≤ 1, |k| ≤ 2.
    let k = narrow_bits_in_range(a.dot_bits(n)).wrapping_mul(2);
    a.sub(n.scale_in_range(I16F16::from_bits(k)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trace::shape::{Polygon, Triangle};

    fn v(x: f32, y: f32, z: f32) -> Vec3 {
        Vec3 {
            x: I16F16::from_num(x),
            y: I16F16::from_num(y),
            z: I16F16::from_num(z),
        }
    }
    const FAR: I16F16 = I16F16::MAX;

    #[test]
    fn window_products_in_words_are_exact() {
        let mut rng = crate::test_rng::XorShift64::new(0x9b05_688c_2b3e_6c1fu64);
        let edges = [0u64, 1, u32::MAX as u64, 1 << 32, (1 << 33) - 1, 1 << 33];
        for k in 0..200_000u64 {
            let (x, y) = (rng.next_u64(), rng.next_u64());
            // t below 2^31 raw, d at most 2^33: the product fits a u64.
            let a = (x as u32) >> 1 >> (y % 32);
            let d = if k % 4 == 0 {
                edges[(y % 6) as usize]
            } else {
                (y >> 31) >> (x % 34)
            };
            assert_eq!(
                times_below_2_33_in_words(a, d),
                u64::from(a) * d,
                "{a} · {d}"
            );
            assert_eq!(times_below_2_33(a, d), u64::from(a) * d, "{a} · {d}");
        }
    }

    #[test]
    fn sphere_roots() {
        let s = Shape::Sphere(Sphere::new(v(0.0, 0.0, -5.0), I16F16::ONE).unwrap());
        let ray = Ray {
            origin: Vec3::ZERO,
            dir: v(0.0, 0.0, -1.0),
        };
        assert_eq!(s.hit(&ray, I16F16::ZERO, FAR), Some(I16F16::from_num(4)));
        // From inside, the far root.
        assert_eq!(
            s.hit(&ray, I16F16::from_num(4.5), FAR),
            Some(I16F16::from_num(6))
        );
        assert_eq!(s.hit(&ray, I16F16::ZERO, I16F16::from_num(4)), None);
        let miss = Ray {
            origin: v(1.01, 0.0, 0.0),
            dir: v(0.0, 0.0, -1.0),
        };
        assert_eq!(s.hit(&miss, I16F16::ZERO, FAR), None);
    }

    #[test]
    fn concave_polygon_and_triangle() {
        // An L shape: the notch at (1.5, 1.5) is outside.
        let l = [
            v(0.0, 0.0, 0.0),
            v(2.0, 0.0, 0.0),
            v(2.0, 1.0, 0.0),
            v(1.0, 1.0, 0.0),
            v(1.0, 2.0, 0.0),
            v(0.0, 2.0, 0.0),
        ];
        let poly = Shape::Polygon(Polygon::new(&l).unwrap());
        let down = |x, y| Ray {
            origin: v(x, y, 3.0),
            dir: v(0.0, 0.0, -1.0),
        };
        assert_eq!(
            poly.hit(&down(0.5, 1.5), I16F16::ZERO, FAR),
            Some(I16F16::from_num(3))
        );
        assert_eq!(
            poly.hit(&down(1.5, 0.5), I16F16::ZERO, FAR),
            Some(I16F16::from_num(3))
        );
        assert_eq!(poly.hit(&down(1.5, 1.5), I16F16::ZERO, FAR), None);
        assert_eq!(poly.hit(&down(2.5, 0.5), I16F16::ZERO, FAR), None);
        let tri = Shape::Triangle(Triangle::new([l[0], l[1], l[5]]).unwrap());
        assert!(tri.hit(&down(0.4, 0.4), I16F16::ZERO, FAR).is_some());
        assert!(tri.hit(&down(1.1, 1.1), I16F16::ZERO, FAR).is_none());
    }

    /// Rays parallel to a frustum's side, just outside it or just inside, the case where the
    /// side's quadratic coefficient `A` is at the size of its own rounding: outside they miss
    /// (once a root beyond the I16F16 range read as "no root" and the whole slab as inside),
    /// inside they hit. Frusta narrowing and widening, lines around the axis, offsets from
    /// 2^-6 to 2 units.
    #[test]
    fn rays_along_a_frustums_side_hit_only_inside_it() {
        let mut checked = 0;
        for (r0, r1) in [(2.0f32, 1.0f32), (1.0, 2.0), (4.0, 0.0), (0.5, 3.5)] {
            let frustum = Frustum::new(v(0.0, 0.0, 0.0), f(r0), v(0.0, 2.0, 0.0), f(r1)).unwrap();
            let shape = Shape::Frustum(frustum);
            for k in 0..12 {
                let angle = k as f32 * core::f32::consts::TAU / 12.0;
                let (c, s) = (libm::cosf(angle), libm::sinf(angle));
                // The side's line from radius r0 at y = 0 to r1 at y = 2, its unit direction
                // and the outward normal in its plane through the axis.
                let (dr, len) = (r1 - r0, libm::sqrtf((r1 - r0) * (r1 - r0) + 4.0));
                let g = [dr * c / len, 2.0 / len, dr * s / len];
                let n = [2.0 * c / len, -dr / len, 2.0 * s / len];
                for offset in [-1.0 / 64.0, -0.1, -0.5, 1.0 / 64.0, 0.01, 0.1, 2.0] {
                    // Along the line at mid-height, pushed `offset` along the normal, from ten
                    // units back.
                    let mid = [(r0 + r1) / 2.0 * c, 1.0, (r0 + r1) / 2.0 * s];
                    let o: [f32; 3] =
                        core::array::from_fn(|i| mid[i] + offset * n[i] - 10.0 * g[i]);
                    let ray = Ray {
                        origin: v(o[0], o[1], o[2]),
                        dir: v(g[0], g[1], g[2]).normalized().unwrap(),
                    };
                    let hit = shape.hit(&ray, I16F16::ZERO, FAR);
                    assert_eq!(
                        hit.is_some(),
                        offset < 0.0,
                        "{r0} {r1} {angle} {offset}: {hit:?}"
                    );
                    checked += 1;
                }
            }
        }
        assert_eq!(checked, 4 * 12 * 7);
    }

    /// The stable roots against f64, for quadratics from balanced to nearly linear (`A` a
    /// millionth of `B`), with and without real roots: a root within range agrees to a few
    /// steps of 2^-16 relative to its size, one beyond it is saturated, and "no real root" is
    /// only said where there is none.
    #[test]
    fn quadratic_roots_are_stable() {
        let mut rng = crate::test_rng::XorShift64::new(0x5851_f42d_4c95_7f2du64);
        let mut unit = || (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0;
        let (mut two, mut none) = (0, 0);
        for i in 0..20_000 {
            let a = unit() * [1.0, 1e-3, 1e-6][i % 3];
            let (b, c) = (unit() * 200.0, unit() * 20_000.0);
            let fx = |x: f64| I32F32::from_num(x);
            let (fa, fb, fc) = (fx(a), fx(b), fx(c));
            if fa == I32F32::ZERO {
                continue;
            }
            let (a, b, c) = (fa.to_num::<f64>(), fb.to_num::<f64>(), fc.to_num::<f64>());
            let disc = b * b - a * c;
            match quadratic(fa, fb, fc) {
                Roots::Two(t1, t2) => {
                    assert!(disc >= -1e-6 * b * b, "{a} {b} {c}: no real root expected");
                    let s = libm::sqrt(disc.max(0.0));
                    let q = if b >= 0.0 { -b - s } else { s - b };
                    let (mut e1, mut e2) = (q / a, c / q);
                    if e1 > e2 {
                        (e1, e2) = (e2, e1);
                    }
                    for (got, want) in [(t1, e1), (t2, e2)] {
                        let got = got.to_num::<f64>();
                        if want.abs() < 32_000.0 {
                            let tol = 1e-3 + want.abs() * 1e-4;
                            assert!((got - want).abs() <= tol, "{a} {b} {c}: {got} vs {want}");
                        } else {
                            assert_eq!(got.signum(), want.signum(), "{a} {b} {c}");
                            assert!(got.abs() > 32_000.0, "{a} {b} {c}: {got} vs {want}");
                        }
                    }
                    two += 1;
                }
                Roots::None => {
                    assert!(disc < 0.0, "{a} {b} {c}");
                    none += 1;
                }
                Roots::Unknown => panic!("{a} {b} {c}: inside the range"),
            }
        }
        assert!(two > 10_000 && none > 1_000, "{two} {none}");
    }

    fn f(x: f32) -> I16F16 {
        I16F16::from_num(x)
    }

    #[test]
    fn reflection_mirrors() {
        let r = reflect(v(0.6, -0.8, 0.0), v(0.0, 1.0, 0.0));
        assert_eq!(r, v(0.6, 0.8, 0.0));
    }

    /// A ray leaving a convex surface inwards meets it again at the chord's far end, however
    /// close to the surface it runs. The origin is a rounded point of the side, so the side's
    /// quadratic at `t = 0` comes out a rounding away from 0; positive, with an inward cosine
    /// of 2^-13 its discriminant went below 0 and the hit was lost (a light inside a cylinder
    /// or cone shone through its wall).
    #[test]
    fn grazing_rays_from_inside_meet_the_surface_again() {
        let radius = 100.0f64;
        let cylinder = Shape::Frustum(
            Frustum::cylinder(v(0.0, -50.0, 0.0), v(0.0, 50.0, 0.0), f(radius as f32)).unwrap(),
        );
        let ellipsoid =
            Shape::Ellipsoid(Ellipsoid::new(v(0.0, 0.0, 0.0), v(100.0, 60.0, 100.0)).unwrap());
        let mut checked = 0;
        for shape in [cylinder, ellipsoid] {
            for k in 0..48 {
                let phi = k as f64 * core::f64::consts::TAU / 48.0 + 0.1;
                let (c, s) = (libm::cos(phi), libm::sin(phi));
                for sin_in in [1.0 / 8192.0, 1.0 / 2048.0, 1.0 / 512.0] {
                    let cos_t = libm::sqrt(1.0 - sin_in * sin_in);
                    // In the plane y = 0, where both are circles of radius 100: along the
                    // tangent, turned inwards by `sin_in`.
                    let dir = [-s * cos_t - c * sin_in, 0.0, c * cos_t - s * sin_in];
                    let ray = Ray {
                        origin: v((radius * c) as f32, 0.0, (radius * s) as f32),
                        dir: v(dir[0] as f32, 0.0, dir[2] as f32).normalized().unwrap(),
                    };
                    let chord = 2.0 * radius * sin_in;
                    let t = shape
                        .hit_from_surface(&ray, crate::trace::tracer::EPSILON, FAR)
                        .unwrap_or_else(|| panic!("{shape:?} {phi} {sin_in}: no hit"));
                    let t = t.to_num::<f64>();
                    assert!(
                        (t - chord).abs() <= 0.01 * chord + 0.01,
                        "{shape:?} {phi} {sin_in}: t {t}, chord {chord}"
                    );
                    checked += 1;
                }
            }
        }
        assert_eq!(checked, 2 * 48 * 3);
    }

    /// Every normal of a thin ellipsoid (axes 0.037 to 0.763, and 0.02 to 5), of a sphere of
    /// radius 2^-10 and of a cone near its apex is a unit vector along the exact gradient at the
    /// (rounded) point. The ellipsoid's gradient, formed from I16F16 products, was shorter
    /// than 2^-8 near the tips of its long axes and had no direction (a zero normal: unlit,
    /// and mirrored as if by nothing); the sphere's offset and the cone's radial part too.
    #[test]
    fn normals_of_small_and_thin_shapes_are_unit_vectors_along_the_gradient() {
        let ellipsoids = [
            [0.037f64, 0.479, 0.763],
            [0.02, 2.0, 5.0],
            [2.0 / 1024.0; 3],
        ];
        let mut checked = 0;
        for r in ellipsoids {
            let e =
                Ellipsoid::new(v(0.0, 0.0, 0.0), v(r[0] as f32, r[1] as f32, r[2] as f32)).unwrap();
            let shapes = [
                Shape::Ellipsoid(e),
                Shape::Sphere(Sphere::new(v(0.0, 0.0, 0.0), f(r[0] as f32)).unwrap()),
            ];
            for (i, shape) in shapes.into_iter().enumerate() {
                let radii = if i == 0 { r } else { [r[0]; 3] };
                for a in 0..16 {
                    for b in 1..16 {
                        let (theta, phi) = (
                            b as f64 * core::f64::consts::PI / 16.0,
                            a as f64 * core::f64::consts::TAU / 16.0,
                        );
                        let p = [
                            radii[0] * libm::sin(theta) * libm::cos(phi),
                            radii[1] * libm::sin(theta) * libm::sin(phi),
                            radii[2] * libm::cos(theta),
                        ];
                        let point = v(p[0] as f32, p[1] as f32, p[2] as f32);
                        let q = [point.x, point.y, point.z].map(|c| c.to_num::<f64>());
                        let g: [f64; 3] = core::array::from_fn(|k| q[k] / (radii[k] * radii[k]));
                        let n = shape.normal(point);
                        let n = [n.x, n.y, n.z].map(|c| c.to_num::<f64>());
                        let len = libm::sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
                        let cos = (n[0] * g[0] + n[1] * g[1] + n[2] * g[2]) / len;
                        assert!(
                            cos > 0.9999,
                            "{shape:?} at {q:?}: normal {n:?}, gradient {g:?}"
                        );
                        checked += 1;
                    }
                }
            }
        }
        // A cone of radius 1 narrowing to 0 over 2 units, at heights up to 2^-10 below the apex.
        let cone = Shape::Frustum(
            Frustum::new(v(0.0, 0.0, 0.0), f(1.0), v(0.0, 2.0, 0.0), f(0.0)).unwrap(),
        );
        for k in 0..16 {
            let phi = k as f64 * core::f64::consts::TAU / 16.0;
            for depth in [1.0 / 1024.0, 1.0 / 256.0, 1.0 / 64.0] {
                let r = depth / 2.0;
                let point = v(
                    (r * libm::cos(phi)) as f32,
                    (2.0 - depth) as f32,
                    (r * libm::sin(phi)) as f32,
                );
                let n = cone.normal(point);
                let n = [n.x, n.y, n.z].map(|c| c.to_num::<f64>());
                // The side's outward normal: (2·radial unit, 1, …) / √5.
                let exact =
                    [2.0 * libm::cos(phi), 1.0, 2.0 * libm::sin(phi)].map(|c| c / libm::sqrt(5.0));
                let cos = n[0] * exact[0] + n[1] * exact[1] + n[2] * exact[2];
                assert!(
                    cos > 0.999,
                    "cone at {phi} {depth}: normal {n:?}, exact {exact:?}"
                );
                checked += 1;
            }
        }
        assert_eq!(checked, 3 * 2 * 16 * 15 + 16 * 3);
    }

    /// A shadow ray towards a directional light has no end: an infinite plane it meets blocks
    /// it, also where `t` is beyond the I16F16 range (a plane nearly parallel to the light),
    /// which `hit` cannot report. The coplanar group test agrees.
    #[test]
    fn a_plane_blocks_a_ray_without_end_however_far() {
        let plane = Shape::Plane(Plane::new(v(0.0, 1.0, 0.0), f(0.0)).unwrap());
        let eps = crate::trace::tracer::EPSILON;
        for (dy, meets) in [
            (-1.0f32 / 65536.0, true),
            (-1.0 / 8192.0, true),
            (-0.5, true),
            (1.0 / 65536.0, false),
            (0.0, false),
        ] {
            let ray = Ray {
                origin: v(0.0, 1.0, 0.0),
                dir: Vec3 {
                    x: I16F16::ONE,
                    y: f(dy),
                    z: I16F16::ZERO,
                },
            };
            // Met at t = 1 / |dy|: up to 65,536, beyond the range from 2^-15 on.
            assert_eq!(plane.blocks(&ray, eps, FAR), meets, "{dy}");
            assert_eq!(
                meets_plane(plane.plane().unwrap(), &ray, eps, FAR),
                meets,
                "{dy}"
            );
            let in_range = meets && dy < -1.0 / 32768.0;
            assert_eq!(plane.hit(&ray, eps, FAR).is_some(), in_range, "{dy}");
            // A ray with an end is blocked only before it.
            assert_eq!(
                plane.blocks(&ray, eps, f(100.0)),
                meets && dy <= -0.01,
                "{dy}"
            );
        }
    }
}
