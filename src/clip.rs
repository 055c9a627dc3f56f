//! Clipping in eye space against the near and far planes and a guard band.
//!
//! Near/far clipping makes triangles with vertices behind the eye render correctly. The guard
//! band (8 half-screens around the centre, see [`crate::project`]) exists only for the bit
//! budget: it keeps projected coordinates below 2^22 sub-pixels, so the edge walk never
//! overflows. Its clip edges lie far off-screen and are never visible.
//!
//! Intersections are computed from the (inside, outside) vertex pair in that order, whatever the
//! polygon's winding, so two triangles sharing an edge get bit-identical new vertices and stay
//! watertight. The arithmetic is i128: distances reach 2^56 and coordinate differences 2^31.

use crate::project::Viewport;
use crate::vertex::EyePoint;
use fixed::types::I16F16;
use heapless::Vec;

/// A vertex on its way through clipping: eye position plus colour (channels 0–255, I16F16).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ClipVertex {
    /// Eye-space position.
    pub p: EyePoint,
    /// Colour attribute.
    pub color: [I16F16; 3],
}

/// Most vertices a clipped triangle can have: 3 plus one per clip plane.
pub const MAX_CLIPPED_VERTICES: usize = 9;

/// A convex polygon produced by clipping, in the input winding.
pub type ClipPolygon = Vec<ClipVertex, MAX_CLIPPED_VERTICES>;

/// What clipping did to a triangle.
// The polygon is held inline (no heap) and lives only briefly on the stack.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Clipped {
    /// Entirely inside: use the triangle as it is.
    Inside,
    /// Entirely outside one plane: nothing to draw.
    Outside,
    /// Cut: the remaining convex polygon (at least 3 vertices).
    Polygon(ClipPolygon),
}

fn lerp(a: i32, b: i32, num: i64, den: i64) -> i32 {
    // a + (b - a) · num / den, rounded to nearest; num/den in [0, 1] so the result is between a
    // and b and fits i32.
    let d = b as i128 - a as i128;
    let n = d * num as i128;
    let q = (2 * n + den as i128).div_euclid(2 * den as i128);
    (a as i128 + q) as i32
}

fn intersect(inside: &ClipVertex, d_in: i64, outside: &ClipVertex, d_out: i64) -> ClipVertex {
    let den = d_in - d_out; // d_in >= 0 > d_out, so den > 0 (and < 2^58).
    let f = |a: I16F16, b: I16F16| I16F16::from_bits(lerp(a.to_bits(), b.to_bits(), d_in, den));
    ClipVertex {
        p: EyePoint {
            x: f(inside.p.x, outside.p.x),
            y: f(inside.p.y, outside.p.y),
            w: f(inside.p.w, outside.p.w),
        },
        color: [0, 1, 2].map(|k| f(inside.color[k], outside.color[k])),
    }
}

/// Clips a triangle against the viewport's six planes.
pub fn clip_triangle<const S: u32>(vp: &Viewport<S>, tri: &[ClipVertex; 3]) -> Clipped {
    let d = tri.each_ref().map(|v| vp.clip_distances(&v.p));
    let mut any_out = false;
    for plane in 0..6 {
        let outs = d.iter().filter(|dist| dist[plane] < 0).count();
        if outs == 3 {
            return Clipped::Outside;
        }
        any_out |= outs > 0;
    }
    if !any_out {
        return Clipped::Inside;
    }
    let mut poly: ClipPolygon = Vec::new();
    for v in tri {
        // Capacity 9 > 3: cannot fail.
        let _ = poly.push(*v);
    }
    for plane in 0..6 {
        let mut next: ClipPolygon = Vec::new();
        let n = poly.len();
        let dist: Vec<i64, MAX_CLIPPED_VERTICES> = poly
            .iter()
            .map(|v| vp.clip_distances(&v.p)[plane])
            .collect();
        if dist.iter().all(|&x| x >= 0) {
            continue;
        }
        for i in 0..n {
            let (Some(cur), Some(prev)) = (poly.get(i), poly.get((i + n - 1) % n)) else {
                continue;
            };
            let (dc, dp) = (
                dist.get(i).copied().unwrap_or(0),
                dist.get((i + n - 1) % n).copied().unwrap_or(0),
            );
            // Each plane adds at most one vertex to a convex polygon, so 9 slots suffice.
            if dp >= 0 && dc < 0 {
                let _ = next.push(intersect(prev, dp, cur, dc));
            } else if dp < 0 && dc >= 0 {
                let _ = next.push(intersect(cur, dc, prev, dp));
            }
            if dc >= 0 {
                let _ = next.push(*cur);
            }
        }
        if next.len() < 3 {
            return Clipped::Outside;
        }
        poly = next;
    }
    Clipped::Polygon(poly)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cv(x: f32, y: f32, w: f32) -> ClipVertex {
        ClipVertex {
            p: EyePoint {
                x: I16F16::from_num(x),
                y: I16F16::from_num(y),
                w: I16F16::from_num(w),
            },
            color: [I16F16::ZERO; 3],
        }
    }

    #[test]
    fn inside_outside_and_near_crossing() {
        let vp = Viewport::<4>::new(64, 64, 1.0, 1.0, 100.0).unwrap();
        let inside = [cv(0.0, 0.0, 5.0), cv(1.0, 0.0, 5.0), cv(0.0, 1.0, 5.0)];
        assert_eq!(clip_triangle(&vp, &inside), Clipped::Inside);
        let behind = [cv(0.0, 0.0, -5.0), cv(1.0, 0.0, -5.0), cv(0.0, 1.0, -5.0)];
        assert_eq!(clip_triangle(&vp, &behind), Clipped::Outside);
        // One vertex behind the eye: the near plane cuts it into a quad.
        let crossing = [cv(0.0, 0.0, -2.0), cv(1.0, 0.0, 5.0), cv(0.0, 1.0, 5.0)];
        let Clipped::Polygon(p) = clip_triangle(&vp, &crossing) else {
            panic!()
        };
        assert_eq!(p.len(), 4);
        for v in &p {
            assert!(v.p.w >= I16F16::from_num(1.0) - I16F16::DELTA);
        }
        // Two vertices behind: a triangle remains.
        let two = [cv(0.0, 0.0, -2.0), cv(1.0, 0.0, -3.0), cv(0.0, 1.0, 5.0)];
        let Clipped::Polygon(p) = clip_triangle(&vp, &two) else {
            panic!()
        };
        assert_eq!(p.len(), 3);
    }

    #[test]
    fn shared_edges_clip_to_identical_vertices() {
        let vp = Viewport::<4>::new(64, 64, 1.0, 1.0, 100.0).unwrap();
        let (a, b) = (cv(-3.0, 1.0, -4.0), cv(2.0, -1.0, 9.0));
        let t1 = [a, b, cv(5.0, 5.0, 6.0)];
        let t2 = [b, a, cv(-5.0, -5.0, 7.0)];
        let (Clipped::Polygon(p1), Clipped::Polygon(p2)) =
            (clip_triangle(&vp, &t1), clip_triangle(&vp, &t2))
        else {
            panic!()
        };
        let on_near = |p: &ClipPolygon| {
            p.iter()
                .filter(|v| v.p.w.to_bits() <= vp.near.to_bits() + 1)
                .copied()
                .collect::<std::vec::Vec<_>>()
        };
        let shared: std::vec::Vec<_> = on_near(&p1)
            .into_iter()
            .filter(|v| on_near(&p2).contains(v))
            .collect();
        assert_eq!(shared.len(), 1, "{p1:?} {p2:?}");
    }

    #[test]
    fn guard_band_clips_huge_triangles() {
        let vp = Viewport::<4>::new(64, 64, 1.0, 1.0, 100.0).unwrap();
        let huge = [
            cv(-4000.0, -4000.0, 10.0),
            cv(4000.0, -4000.0, 10.0),
            cv(0.0, 4000.0, 10.0),
        ];
        let Clipped::Polygon(p) = clip_triangle(&vp, &huge) else {
            panic!()
        };
        for v in &p {
            assert!(vp
                .clip_distances(&v.p)
                .iter()
                .all(|&d| d >= -(1 << 40) / (1 << 20)));
            let s = vp.project(&v.p, v.color).unwrap();
            assert!(s.x.0.abs() < 1 << 22 && s.y.0.abs() < 1 << 22);
        }
    }
}
