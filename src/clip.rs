//! Clipping in eye space against the near and far planes and a guard band.
//!
//! Near/far clipping makes triangles with vertices behind the eye render correctly. The guard
//! band (8 half-screens around the centre, see `crate::project`) exists only for the bit
//! budget: it keeps projected coordinates below 2^22 sub-pixels, so the edge walk never
//! overflows. Its clip edges lie far off-screen and are never visible.
//!
//! Intersections are computed from the (inside, outside) vertex pair in that order, whatever the
//! polygon's winding, so two triangles sharing an edge get bit-identical new vertices and stay
//! watertight. Distances reach 2^56 and coordinate differences 2^31: the parameter is a
//! 128-bit quotient, taken by 32-bit digits (`ratio_62`), and the interpolation's products
//! are i128.

use crate::math::div_rem_u64_u32;
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
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Clipped {
    /// Entirely inside: use the triangle as it is.
    Inside,
    /// Entirely outside one plane: nothing to draw.
    Outside,
    /// Cut: the remaining convex polygon (at least 3 vertices) is in the output buffer.
    Polygon,
    /// Crosses a plane but clipping is compiled out ([`NoClip`]): not drawn, and counted in
    /// [`FrameStats::unclipped`](crate::stats::FrameStats::unclipped).
    Skipped,
}

/// The clipping stage, chosen at compile time in
/// [`RenderOptions`](crate::options::RenderOptions): [`FrustumClip`] (the default) or
/// [`NoClip`] for scenes that provably never cross the near, far or guard-band planes, which
/// leaves the clipper (and its 128-bit arithmetic) out of the build.
pub trait Clipping: Copy + Default + core::fmt::Debug + PartialEq + Eq + sealed::Sealed {
    /// Whether this stage can cut triangles.
    const CLIPS: bool;
    /// The buffer a cut triangle's polygon is left in: a [`ClipPolygon`] where triangles are
    /// cut, nothing (no bytes on the stack) for [`NoClip`], which never leaves one.
    type Polygon: Default + AsRef<[ClipVertex]>;
    /// Classifies `tri` and, if it is cut, leaves the remaining polygon in `out`.
    fn clip<const S: u32>(
        vp: &Viewport<S>,
        tri: &[ClipVertex; 3],
        out: &mut Self::Polygon,
    ) -> Clipped;
}

mod sealed {
    pub trait Sealed {}
    impl Sealed for super::FrustumClip {}
    impl Sealed for super::NoClip {}
}

/// Clips against the near and far planes and the guard band ([`clip_triangle`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FrustumClip;

/// No clipping: triangles inside the view volume are drawn exactly as with [`FrustumClip`],
/// triangles entirely outside are rejected, and triangles that cross a plane are skipped and
/// counted ([`Clipped::Skipped`]), never drawn wrongly.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NoClip;

impl Clipping for FrustumClip {
    const CLIPS: bool = true;
    type Polygon = ClipPolygon;
    fn clip<const S: u32>(
        vp: &Viewport<S>,
        tri: &[ClipVertex; 3],
        out: &mut ClipPolygon,
    ) -> Clipped {
        clip_triangle(vp, tri, out)
    }
}

impl Clipping for NoClip {
    const CLIPS: bool = false;
    type Polygon = [ClipVertex; 0];
    fn clip<const S: u32>(
        vp: &Viewport<S>,
        tri: &[ClipVertex; 3],
        _: &mut [ClipVertex; 0],
    ) -> Clipped {
        match classify(vp, tri) {
            Clipped::Polygon => Clipped::Skipped,
            other => other,
        }
    }
}

/// Whether `tri` is inside, outside, or crosses a plane ([`Clipped::Polygon`], with nothing
/// written anywhere).
pub fn classify<const S: u32>(vp: &Viewport<S>, tri: &[ClipVertex; 3]) -> Clipped {
    let d = tri.each_ref().map(|v| vp.clip_distances(&v.p));
    let mut any_out = false;
    for plane in 0..6 {
        let outs = d.iter().filter(|dist| dist[plane] < 0).count();
        if outs == 3 {
            return Clipped::Outside;
        }
        any_out |= outs > 0;
    }
    if any_out {
        Clipped::Polygon
    } else {
        Clipped::Inside
    }
}

/// Fractional bits of the intersection parameter `t = d_in / (d_in − d_out)` in [0, 1].
const T_BITS: u32 = 62;

fn intersect(inside: &ClipVertex, d_in: i64, outside: &ClipVertex, d_out: i64) -> ClipVertex {
    // d_in >= 0 > d_out, so 0 <= d_in < den < 2^64 and t < 2^62.
    let den = (d_in as i128 - d_out as i128) as u64;
    let t = ratio_62(d_in as u64, den) as i128;
    // a + (b − a)·t, rounded to nearest: |b − a| < 2^32, so the product is below 2^94, and the
    // result lies between a and b.
    let f = |a: I16F16, b: I16F16| {
        let d = b.to_bits() as i128 - a.to_bits() as i128;
        let step = (d * t + (1i128 << (T_BITS - 1))) >> T_BITS;
        I16F16::from_bits((a.to_bits() as i128 + step) as i32)
    };
    ClipVertex {
        p: EyePoint {
            x: f(inside.p.x, outside.p.x),
            y: f(inside.p.y, outside.p.y),
            w: f(inside.p.w, outside.p.w),
        },
        color: [
            f(inside.color[0], outside.color[0]),
            f(inside.color[1], outside.color[1]),
            f(inside.color[2], outside.color[2]),
        ],
    }
}

/// `⌊n · 2^62 / d⌋` for `n < d` (so below 2^62): the intersection parameter, as the 128-bit
/// division gives it. Both normalised so `d` has its top bit set, the numerator is two 64-bit
/// words whose high one is below `d`, and its quotient two 32-bit digits, each estimated by a
/// 64 / 32-bit division ([`div_rem_u64_u32`]) and corrected at most twice (Knuth, Algorithm D;
/// `divlu` in Hacker's Delight). On 32-bit cores the 128-bit division is a loop of a bit an
/// iteration. Test `ratio_62_equals_the_128_bit_division`.
fn ratio_62(n: u64, d: u64) -> u64 {
    const B: u64 = 1 << 32;
    let s = d.leading_zeros() % 64;
    let (v, a) = (d << s, n << s);
    // a·2^62 = (a >> 2)·2^64 + (a & 3)·2^62, and a >> 2 < a < v.
    let (u1, u0) = (a >> 2, (a & 3) << 62);
    let (vn1, vn0) = (v >> 32, v & (B - 1));
    // One quotient digit of (top·2^32 + next) / v, for top < v; and the remainder.
    let digit = |top: u64, next: u64| -> (u64, u64) {
        let (mut q, r) = div_rem_u64_u32(top, vn1 as u32);
        let mut rhat = r as u64;
        while q >= B || q * vn0 > (rhat << 32 | next) {
            q -= 1;
            rhat += vn1;
            if rhat >= B {
                break;
            }
        }
        // The true remainder is below v: the wrapping arithmetic gives it exactly.
        let rem = (top << 32 | next).wrapping_sub(q.wrapping_mul(v));
        (q, rem)
    };
    let (q1, r1) = digit(u1, u0 >> 32);
    let (q0, _) = digit(r1, u0 & (B - 1));
    q1 << 32 | q0
}

/// Clips a triangle against the viewport's six planes. When it is cut, the remaining polygon
/// is left in `out` (a caller-provided buffer, so no polygon is returned by value).
pub fn clip_triangle<const S: u32>(
    vp: &Viewport<S>,
    tri: &[ClipVertex; 3],
    out: &mut ClipPolygon,
) -> Clipped {
    match classify(vp, tri) {
        Clipped::Polygon => {}
        other => return other,
    }
    out.clear();
    for v in tri {
        // Capacity 9 > 3: cannot fail.
        let _ = out.push(*v);
    }
    let mut next: ClipPolygon = Vec::new();
    for plane in 0..6 {
        let n = out.len();
        // `n >= 3` and `plane < 6`, but where this closure is not inlined the compiler cannot
        // see it: checked forms keep the panic paths out (the panic-never link check).
        let dist = |i: usize| {
            let v = i.checked_rem(n).and_then(|k| out.get(k));
            v.map_or(0, |v| {
                vp.clip_distances(&v.p).get(plane).copied().unwrap_or(0)
            })
        };
        if (0..n).all(|i| dist(i) >= 0) {
            continue;
        }
        next.clear();
        let mut dp = dist(n - 1);
        for i in 0..n {
            let dc = dist(i);
            let prev = (i + n - 1).checked_rem(n).and_then(|k| out.get(k));
            let (Some(cur), Some(prev)) = (out.get(i), prev) else {
                continue;
            };
            // Each plane adds at most one vertex to a convex polygon, so 9 slots suffice.
            if dp >= 0 && dc < 0 {
                let _ = next.push(intersect(prev, dp, cur, dc));
            } else if dp < 0 && dc >= 0 {
                let _ = next.push(intersect(cur, dc, prev, dp));
            }
            if dc >= 0 {
                let _ = next.push(*cur);
            }
            dp = dc;
        }
        if next.len() < 3 {
            return Clipped::Outside;
        }
        core::mem::swap(out, &mut next);
    }
    Clipped::Polygon
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

    /// `ratio_62` is the 128-bit division for numerators and divisors of every size, the
    /// extremes included.
    #[test]
    fn ratio_62_equals_the_128_bit_division() {
        let check = |n: u64, d: u64| {
            let want = ((n as u128) << 62) / d as u128;
            assert_eq!(ratio_62(n, d) as u128, want, "n {n} d {d}");
        };
        for d in [
            1,
            2,
            3,
            1 << 31,
            (1 << 32) - 1,
            1 << 32,
            (1 << 32) + 1,
            1 << 57,
            u64::MAX,
        ] {
            for n in [0, 1, d / 2, d.saturating_sub(2), d - 1] {
                if n < d {
                    check(n, d);
                }
            }
        }
        let mut rng = crate::test_rng::XorShift64::new(0x9E37_79B9_7F4A_7C15u64);
        for _ in 0..200_000 {
            let d = (rng.next_u64() >> (rng.next_u64() % 64)).max(1);
            let n = match rng.next_u64() % 4 {
                0 => d - 1,
                1 => d - 1 - (rng.next_u64() % d.min(1 << 20)),
                _ => rng.next_u64() % d,
            };
            check(n, d);
        }
    }

    #[test]
    fn inside_outside_and_near_crossing() {
        let vp = Viewport::<4>::new(64, 64, 1.0, 1.0, 100.0).unwrap();
        let inside = [cv(0.0, 0.0, 5.0), cv(1.0, 0.0, 5.0), cv(0.0, 1.0, 5.0)];
        let mut p = ClipPolygon::new();
        assert_eq!(clip_triangle(&vp, &inside, &mut p), Clipped::Inside);
        let behind = [cv(0.0, 0.0, -5.0), cv(1.0, 0.0, -5.0), cv(0.0, 1.0, -5.0)];
        assert_eq!(clip_triangle(&vp, &behind, &mut p), Clipped::Outside);
        // One vertex behind the eye: the near plane cuts it into a quad.
        let crossing = [cv(0.0, 0.0, -2.0), cv(1.0, 0.0, 5.0), cv(0.0, 1.0, 5.0)];
        assert_eq!(clip_triangle(&vp, &crossing, &mut p), Clipped::Polygon);
        assert_eq!(p.len(), 4);
        for v in &p {
            assert!(v.p.w >= I16F16::from_num(1.0) - I16F16::DELTA);
        }
        // Two vertices behind: a triangle remains.
        let two = [cv(0.0, 0.0, -2.0), cv(1.0, 0.0, -3.0), cv(0.0, 1.0, 5.0)];
        assert_eq!(clip_triangle(&vp, &two, &mut p), Clipped::Polygon);
        assert_eq!(p.len(), 3);
    }

    #[test]
    fn shared_edges_clip_to_identical_vertices() {
        let vp = Viewport::<4>::new(64, 64, 1.0, 1.0, 100.0).unwrap();
        let (a, b) = (cv(-3.0, 1.0, -4.0), cv(2.0, -1.0, 9.0));
        let (mut p1, mut p2) = (ClipPolygon::new(), ClipPolygon::new());
        assert_eq!(
            clip_triangle(&vp, &[a, b, cv(5.0, 5.0, 6.0)], &mut p1),
            Clipped::Polygon
        );
        assert_eq!(
            clip_triangle(&vp, &[b, a, cv(-5.0, -5.0, 7.0)], &mut p2),
            Clipped::Polygon
        );
        let on_near = |p: &ClipPolygon| {
            p.iter()
                .filter(|v| v.p.w.to_bits() <= vp.near.to_bits() + 1)
                .copied()
                .collect::<std::vec::Vec<_>>()
        };
        // The shared edge a-b crosses the near plane once; both get the same new vertex.
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
        let mut p = ClipPolygon::new();
        assert_eq!(clip_triangle(&vp, &huge, &mut p), Clipped::Polygon);
        // Guard band: 8 half-screens = 4·64 px = 4096 sub-pixels either side of the centre
        // (512), give or take a rounding step.
        for v in &p {
            let s = vp.project(&v.p, v.color).unwrap();
            assert!(
                (s.x.0 - 512).abs() <= 4096 + 2 && (s.y.0 - 512).abs() <= 4096 + 2,
                "{s:?}"
            );
        }
    }
}
