//! Accuracy metrics: comparing a fixed-point render with the float reference, pixel by pixel,
//! and classifying every id/coverage mismatch as *explained* or *real*.
//!
//! # The position error bound
//!
//! The renderer moves geometry by at most
//!
//! ```text
//! ε(w) = √2 · 2^-(S+1)  +  f · E / w  +  2^-12      pixels, at eye depth w
//! ```
//!
//! * `√2 · 2^-(S+1)`: snapping a vertex to S sub-pixel bits moves it by at most half a step per
//!   axis. An edge point is a convex combination of its endpoints, so it moves no more.
//! * `f · E / w`: the eye-space error `E` of the I16F16 transform, seen at depth `w` through
//!   `f` pixels per unit at depth 1. Each of the 12 matrix entries is rounded by ≤ 2^-17, so
//!   a coordinate is off by ≤ 2^-17 · (1 + 3 M) for model coordinates up to `M`, plus the
//!   result's own rounding (2^-17); the f32 composition of the matrix adds ≤ 2^-22 · M. We use
//!   `E = 2^-16 · (1 + 3 M)`, which covers all three.
//! * `2^-12`: projection arithmetic (the 24-bit projection scale, the f32 focal length), below
//!   2^-13 px on a 2048-pixel target.
//!
//! A mismatch at a pixel centre is *explained* when, in exact f64 geometry, the centre lies within
//! `ε` of an edge (including a near/far clip edge) of either candidate triangle, or when both
//! candidates cover it and their depth gap there is within what the bound allows each of them:
//! snapping moves each triangle independently, so each surface shows its true depth at some point
//! within `ε` of the centre, give or take the depth format's resolution. (Coplanar and
//! intersecting surfaces fall under this rule.) Anything else is *real*.

use crate::reference::{self, cross, dot, Image, Scene, V3};

/// The renderer's documented position error, for one render setting and scene.
#[derive(Clone, Copy, Debug)]
pub struct ErrorBound {
    /// Sub-pixel bits.
    pub sub_bits: u32,
    /// Largest |model coordinate|.
    pub max_model_coord: f64,
    /// Pixels per world unit at eye depth 1.
    pub focal_px: f64,
    /// What a narrow set-up arithmetic adds (zero for the precise default).
    pub arithmetic: ArithmeticError,
}

/// The documented error that narrow choices (a set-up arithmetic of
/// `scanline3d::arithmetic::Arithmetic`, a 16-bit depth format) add to the default's, for one scene
/// and screen.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ArithmeticError {
    /// Depth resolution in `q = near / w` beyond the default's (`DepthFormat::RESOLUTION`:
    /// 2^-16 for `depth::Depth16`).
    pub depth_q: f64,
    /// Screen position error in pixels (`project::Reciprocal`: 2^-14 of a vertex's offset from
    /// the screen centre, at most the guard band's corner).
    pub px: f64,
    /// Eye-space error in world units (`vertex::NarrowTransform`: 3 · 2^-13 · max|m| · max|v|,
    /// with max|m| = 1 for the rigid model transforms the corpus and tools use).
    pub eye_units: f64,
}

impl ErrorBound {
    /// `ε(w)` in pixels at eye depth `w`.
    pub fn position_px(&self, w: f64) -> f64 {
        let snap = std::f64::consts::SQRT_2 * 0.5f64.powi(self.sub_bits as i32 + 1);
        snap + self.focal_px * self.eye_units() / w.max(1e-9) + 2f64.powi(-12) + self.arithmetic.px
    }

    /// Eye-space position error `E` of the transform, in world units (see the module docs).
    pub fn eye_units(&self) -> f64 {
        2f64.powi(-16) * (1.0 + 3.0 * self.max_model_coord) + self.arithmetic.eye_units
    }

    /// Relative depth error at eye depth `w` with near plane `near`, not counting the screen
    /// position error (the caller adds the depth change of the surface within `ε`):
    /// * the depth format: `q = near/w` in I2F30 evaluated from an I24F40 plane, ≤ 2^-25
    ///   absolute in q (a generous bound on rounding in set-up, stepping and storage), so
    ///   `Δw/w = Δq/q ≤ 2^-25 · w/near`, plus a narrower format's resolution in `q` the same way;
    /// * the transform moving vertices along the view axis: `E / w`;
    /// * the f32 depth image's own rounding: 2^-24.
    pub fn depth_relative(&self, w: f64, near: f64) -> f64 {
        (2f64.powi(-25) + self.arithmetic.depth_q) * w / near
            + self.eye_units() / w
            + 2f64.powi(-24)
    }
}

/// Results of comparing a render with the reference.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Metrics {
    /// Pixels compared.
    pub pixels: usize,
    /// Pixels covered in one image and background in the other.
    pub coverage_mismatches: usize,
    /// Pixels whose ids differ (coverage mismatches included).
    pub id_mismatches: usize,
    /// Mismatches explained by an edge within the position bound.
    pub explained_edge: usize,
    /// Mismatches explained by a depth tie or crossing within the bound.
    pub explained_depth: usize,
    /// Mismatches not explained.
    pub real: usize,
    /// Largest relative depth error where both images show the same triangle.
    pub depth_max_rel: f64,
    /// Mean relative depth error there.
    pub depth_mean_rel: f64,
    /// Pixels whose depth error exceeds the per-pixel bound (format + position error).
    pub depth_beyond_bound: usize,
    /// Largest colour channel difference over all pixels.
    pub color_max: u8,
    /// Colour PSNR in dB over all pixels (infinite for identical images).
    pub psnr: f64,
}

impl Metrics {
    /// Id mismatches as a percentage of pixels.
    pub fn id_mismatch_percent(&self) -> f64 {
        100.0 * self.id_mismatches as f64 / self.pixels.max(1) as f64
    }
}

impl std::fmt::Display for Metrics {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "pixels            {}", self.pixels)?;
        writeln!(
            f,
            "id mismatches     {} ({:.3} %), of which coverage {}",
            self.id_mismatches,
            self.id_mismatch_percent(),
            self.coverage_mismatches
        )?;
        writeln!(
            f,
            "  explained       {} at edges, {} by depth ties/crossings",
            self.explained_edge, self.explained_depth
        )?;
        writeln!(f, "  real            {}", self.real)?;
        writeln!(
            f,
            "depth error       max {:.3e}, mean {:.3e} (relative); {} pixels beyond bound",
            self.depth_max_rel, self.depth_mean_rel, self.depth_beyond_bound
        )?;
        write!(
            f,
            "colour            max channel difference {}, PSNR {:.2} dB",
            self.color_max, self.psnr
        )
    }
}

/// Compares id and depth images only (no scene, so no classification).
pub fn compare_images(a: &Image, b: &Image) -> Metrics {
    let mut m = Metrics {
        pixels: a.ids.len(),
        ..Metrics::default()
    };
    let (mut sum, mut n) = (0.0, 0usize);
    for i in 0..a.ids.len().min(b.ids.len()) {
        let (fa, fb) = (a.ids[i], b.ids[i]);
        if fa != fb {
            m.id_mismatches += 1;
            m.coverage_mismatches += ((fa >= 0) != (fb >= 0)) as usize;
        } else if fa >= 0 && !a.depth[i].is_nan() && !b.depth[i].is_nan() {
            // (NaN: a method without depth memory has no depth to compare.)
            let (da, db) = (a.depth[i] as f64, b.depth[i] as f64);
            let rel = (da - db).abs() / db;
            m.depth_max_rel = m.depth_max_rel.max(rel);
            sum += rel;
            n += 1;
        }
    }
    m.depth_mean_rel = if n > 0 { sum / n as f64 } else { 0.0 };
    let mut sq = 0.0;
    for (ca, cb) in a.color.iter().zip(&b.color) {
        for k in 0..3 {
            let d = ca[k].abs_diff(cb[k]);
            m.color_max = m.color_max.max(d);
            sq += (d as f64) * (d as f64);
        }
    }
    let mse = sq / (3 * a.color.len().max(1)) as f64;
    m.psnr = if mse == 0.0 {
        f64::INFINITY
    } else {
        10.0 * (255.0f64 * 255.0 / mse).log10()
    };
    m
}

fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn segment_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let ab = [b[0] - a[0], b[1] - a[1]];
    let ap = [p[0] - a[0], p[1] - a[1]];
    let len2 = ab[0] * ab[0] + ab[1] * ab[1];
    let t = if len2 > 0.0 {
        ((ap[0] * ab[0] + ap[1] * ab[1]) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let d = [ap[0] - t * ab[0], ap[1] - t * ab[1]];
    (d[0] * d[0] + d[1] * d[1]).sqrt()
}

/// Distance from screen point `p` to the outline of triangle `t`'s visible projection.
fn edge_distance(scene: &Scene, t: i32, p: [f64; 2], w: usize, h: usize) -> f64 {
    if t < 0 {
        return f64::INFINITY;
    }
    let poly = scene.screen_polygon(t as usize, w, h);
    (0..poly.len())
        .map(|i| segment_distance(p, poly[i], poly[(i + 1) % poly.len()]))
        .fold(f64::INFINITY, f64::min)
}

/// Eye depth of the (infinite) plane of triangle `t` along the ray through screen point `p`.
fn plane_depth(scene: &Scene, t: i32, p: [f64; 2], w: usize, h: usize) -> Option<f64> {
    let tri = scene.triangles.get(usize::try_from(t).ok()?)?;
    let n = cross(sub(tri.v[1], tri.v[0]), sub(tri.v[2], tri.v[0]));
    let dir = scene.camera.ray(p[0], p[1], w, h);
    let denom = dot(n, dir);
    if denom == 0.0 {
        return None;
    }
    Some(dot(n, sub(tri.v[0], scene.camera.eye)) / denom)
}

/// Compares a fixed-point render with the reference rendered from `scene`, classifying each
/// mismatch with `bound`.
pub fn compare(
    fixed: &Image,
    reference: &Image,
    scene: &reference::Scene,
    bound: &ErrorBound,
) -> Metrics {
    let mut m = compare_images(fixed, reference);
    let (w, h) = (reference.width, reference.height);
    let near = scene.camera.near;
    // Eight points at 1.1 ε: for a function linear in screen space (q, or an edge function) the
    // extremes over the disc of radius ε are never beyond these (1.1 · cos 22.5° > 1).
    let ring = |p: [f64; 2], eps: f64| {
        (0..8).map(move |k| {
            let a = k as f64 * std::f64::consts::FRAC_PI_4;
            [p[0] + 1.1 * eps * a.cos(), p[1] + 1.1 * eps * a.sin()]
        })
    };
    for i in 0..reference.ids.len() {
        let (f, r) = (fixed.ids[i], reference.ids[i]);
        let p = [(i % w) as f64 + 0.5, (i / w) as f64 + 0.5];
        if f == r {
            // Depth check against the per-pixel bound: the format's resolution plus how far the
            // surface's depth moves within the position bound (a steep surface moves a lot).
            // Methods without depth memory report NaN: nothing to check.
            if f >= 0 && !fixed.depth[i].is_nan() {
                let (df, dr) = (fixed.depth[i] as f64, reference.depth[i] as f64);
                let eps = bound.position_px(dr);
                let slope = ring(p, eps)
                    .filter_map(|q| plane_depth(scene, r, q, w, h))
                    .map(|d| (d - dr).abs())
                    .fold(0.0, f64::max);
                if (df - dr).abs() > dr * bound.depth_relative(dr, near) + slope {
                    m.depth_beyond_bound += 1;
                }
            }
            continue;
        }
        // The depth at which to evaluate the bound: the nearest surface either image shows.
        let depth = [fixed.depth[i], reference.depth[i]]
            .iter()
            .map(|&d| d as f64)
            .filter(|d| d.is_finite())
            .fold(f64::INFINITY, f64::min);
        let eps = bound.position_px(if depth.is_finite() { depth } else { near });
        if edge_distance(scene, f, p, w, h) <= eps || edge_distance(scene, r, p, w, h) <= eps {
            m.explained_edge += 1;
            continue;
        }
        // Two surfaces at the centre. Each triangle's vertices snap independently, so each
        // renderer surface shows, at this centre, its true depth at some point within ε: its
        // depth can be off by as much as its own depth changes within ε (plus the format's
        // resolution). Explained if the true gap is within the sum of both surfaces' allowances.
        let explained = match (
            plane_depth(scene, f, p, w, h),
            plane_depth(scene, r, p, w, h),
        ) {
            (Some(df), Some(dr)) if f >= 0 && r >= 0 => {
                let wobble = |t: i32, d: f64| {
                    ring(p, eps)
                        .filter_map(|q| plane_depth(scene, t, q, w, h))
                        .map(|x| (x - d).abs())
                        .fold(0.0, f64::max)
                        + d * bound.depth_relative(d, near)
                };
                (df - dr).abs() <= wobble(f, df) + wobble(r, dr)
            }
            _ => false,
        };
        if explained {
            m.explained_depth += 1;
        } else {
            m.real += 1;
        }
    }
    m
}
