//! The f64 Whitted tracer: issue 21's shading model and termination rules, exactly.
//!
//! `colour(ray, depth, weight)`:
//! - the nearest hit with `t > EPSILON` ([`EPSILON`]; primary rays instead accept eye depths in
//!   `[near, far)`); no hit → the background;
//! - local term `KA·C·ambient + Σ unblocked lights KD·max(0, N·L)·C·I` (no distance falloff);
//!   a light is blocked when the shadow ray from the hit towards it hits any object with
//!   `EPSILON < t` (and, for a point light, `t <` its distance); in shadow only the ambient term
//!   remains (transparent objects cast full shadows, as in the lecture);
//! - plus `KR·colour(R, depth + 1, weight·KR)` with `R = 2N(N·V) − V`;
//! - plus `KT·colour(T, depth + 1, weight·KT)` with `T` from Snell's law: entering a shape the
//!   ray goes from 1.0 to its IOR, leaving it (hitting the surface from the inside, the side
//!   opposite the outward normal) from its IOR to 1.0; on total internal reflection `T = R`.
//!
//! N is the unit normal turned to face the incoming ray, V the unit vector back along it.
//! The tree ends on the lecture's four rules: no hit; a diffuse surface (KR = KT = 0, nothing to
//! spawn); a secondary ray is traced only if its weight (product of the KR/KT factors along its
//! path) is ≥ the threshold; a ray of depth `max_depth` spawns nothing (the primary ray has
//! depth 0). Defaults: [`DEFAULT_MAX_DEPTH`], [`DEFAULT_THRESHOLD`]. The pixel's colour is
//! clamped to [0, 1] per channel once, at the end, and rounded to 8 bits (`round(255·c)`).
//!
//! Secondary and shadow rays have unit directions, so `t` and `EPSILON` are world distances.

use super::accel::Accel;
use super::query::{Counters, Hit};
use super::scene::{LightKind, TracedScene};
use super::vector::{dot, length, normalize, scale, sub, Ray, Span, V3};
use crate::reference::Camera;

/// Secondary and shadow rays accept hits with `t > EPSILON` (world units): 2⁻¹⁰, exact in
/// fixed point, far above the f64 error of a hit point in scenes of size ~1–100 and below any
/// feature the corpus has.
pub const EPSILON: f64 = 1.0 / 1024.0;
/// Default depth limit: a ray of depth 4 spawns nothing.
pub const DEFAULT_MAX_DEPTH: u32 = 4;
/// Default weight threshold: 2⁻⁸, a ray whose weight is below one 8-bit step is not traced.
pub const DEFAULT_THRESHOLD: f64 = 1.0 / 256.0;

/// Largest depth limit accepted: the f64 tracer recurses once per level, and a deeper tree
/// than this adds nothing an 8-bit pixel can show unless every surface is a perfect mirror.
pub const MAX_DEPTH_LIMIT: u32 = 64;

/// Ray-tree limits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits {
    /// A ray of this depth spawns nothing.
    pub max_depth: u32,
    /// A secondary ray is traced only if its weight is ≥ this.
    pub threshold: f64,
}

impl Limits {
    /// Checks the limits: `max_depth ≤ MAX_DEPTH_LIMIT`, `threshold` finite and ≥ 0.
    pub fn check(&self) -> Result<(), String> {
        if self.max_depth > MAX_DEPTH_LIMIT {
            return Err(format!(
                "max depth {} exceeds {MAX_DEPTH_LIMIT}",
                self.max_depth
            ));
        }
        if !(self.threshold.is_finite() && self.threshold >= 0.0) {
            return Err(format!(
                "threshold {} must be a finite number >= 0",
                self.threshold
            ));
        }
        Ok(())
    }
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            max_depth: DEFAULT_MAX_DEPTH,
            threshold: DEFAULT_THRESHOLD,
        }
    }
}

/// What tracing did: rays by kind, where the ray tree ended, intersection work.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TraceStats {
    /// Primary rays.
    pub primary: u64,
    /// Secondary rays traced, by depth (index 0 unused: the primary rays).
    pub secondary_by_depth: Vec<u64>,
    /// Shadow rays cast (lights with N·L > 0).
    pub shadow: u64,
    /// Rays that hit nothing.
    pub missed: u64,
    /// Secondary rays not traced because the spawning ray had the maximum depth.
    pub cut_by_depth: u64,
    /// Secondary rays not traced because their weight was below the threshold.
    pub cut_by_weight: u64,
    /// Refractions that were total internal reflections.
    pub total_internal_reflections: u64,
    /// Intersection work of primary and secondary rays.
    pub rays: Counters,
    /// Intersection work of shadow rays.
    pub shadows: Counters,
    /// When `Some`, every secondary ray traced, in tracing order (for tests and inspection).
    pub log: Option<Vec<TreeRay>>,
}

/// Why a secondary ray was spawned.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Spawn {
    /// `R = 2N(N·V) − V`, weight KR.
    Reflection,
    /// `T` by Snell's law, weight KT.
    Refraction,
    /// The refracted ray of a total internal reflection: `T = R`, weight KT.
    TotalInternalReflection,
}

/// One secondary ray of the ray tree.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TreeRay {
    /// Its depth (the primary ray has 0).
    pub depth: u32,
    /// Its weight: the product of the KR/KT factors along its path.
    pub weight: f64,
    /// The ray (unit direction).
    pub ray: Ray,
    /// Why it was spawned.
    pub spawn: Spawn,
}

impl TraceStats {
    /// Primary plus secondary rays (shadow rays not included).
    pub fn traced_rays(&self) -> u64 {
        self.primary + self.secondary_by_depth.iter().sum::<u64>()
    }

    /// Exact intersection tests per traced ray, shadow rays included in both counts.
    pub fn tests_per_ray(&self) -> f64 {
        let rays = self.traced_rays() + self.shadow;
        (self.rays.object_tests + self.shadows.object_tests) as f64 / rays.max(1) as f64
    }
}

/// One traced pixel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pixel {
    /// Colour before clamping.
    pub colour: [f64; 3],
    /// The primary hit, if any.
    pub hit: Option<Hit>,
    /// Bit k set when light k contributes nothing at the primary hit (0 without a hit).
    pub shadow: u8,
}

/// The Whitted tracer over one scene and acceleration structure.
pub struct Tracer<'a> {
    scene: &'a TracedScene,
    accel: &'a Accel<'a>,
    limits: Limits,
}

/// A light as seen from a surface point.
struct LightRay {
    /// Unit vector towards the light.
    l: V3,
    /// Distance to the light (infinite for a directional one).
    distance: f64,
}

impl<'a> Tracer<'a> {
    /// A tracer with these limits.
    pub fn new(accel: &'a Accel<'a>, limits: Limits) -> Self {
        Tracer {
            scene: accel.scene(),
            accel,
            limits,
        }
    }

    /// Traces the primary ray through the centre of pixel (`x`, `y`).
    pub fn pixel(
        &self,
        camera: &Camera,
        x: usize,
        y: usize,
        w: usize,
        h: usize,
        stats: &mut TraceStats,
    ) -> Pixel {
        let ray = Ray {
            origin: camera.eye,
            dir: super::scene::primary_ray(camera, x, y, w, h),
        };
        // The direction's view-axis component is 1, so t is the eye depth.
        let span = Span {
            min: camera.near,
            max: camera.far,
            min_inclusive: true,
        };
        stats.primary += 1;
        let Some(hit) = self.accel.nearest(ray, span, &mut stats.rays) else {
            stats.missed += 1;
            return Pixel {
                colour: self.scene.background,
                hit: None,
                shadow: 0,
            };
        };
        let (colour, shadow) = self.shade(&ray, &hit, 0, 1.0, stats);
        Pixel {
            colour,
            hit: Some(hit),
            shadow,
        }
    }

    /// `colour(ray, depth, weight)` of a secondary ray (unit direction, `t > EPSILON`).
    pub fn colour(&self, ray: &Ray, depth: u32, weight: f64, stats: &mut TraceStats) -> [f64; 3] {
        let span = Span::open(EPSILON, f64::INFINITY);
        match self.accel.nearest(*ray, span, &mut stats.rays) {
            None => {
                stats.missed += 1;
                self.scene.background
            }
            Some(hit) => self.shade(ray, &hit, depth, weight, stats).0,
        }
    }

    fn light_ray(&self, kind: &LightKind, p: V3) -> Option<LightRay> {
        match kind {
            LightKind::Directional(d) => Some(LightRay {
                l: *d,
                distance: f64::INFINITY,
            }),
            LightKind::Point(pos) => {
                let to = sub(*pos, p);
                Some(LightRay {
                    l: normalize(to)?,
                    distance: length(to),
                })
            }
        }
    }

    /// The local term at surface point `p` of object `id` with normal `n` (facing the viewer):
    /// `KA·C·ambient + Σ unblocked lights KD·max(0, N·L)·C·I`, and the shadow bits (bit k set
    /// when light k contributes nothing: N·L ≤ 0 or a shadow ray is blocked).
    pub fn local(&self, id: usize, p: V3, n: V3, stats: &mut TraceStats) -> ([f64; 3], u8) {
        let Some(m) = self.scene.material_at(id, p) else {
            return (self.scene.background, 0);
        };
        let mut c = m.color.map(|ch| m.ka * ch * self.scene.ambient);
        let mut bits = 0u8;
        for (k, light) in self.scene.lights.iter().enumerate() {
            let lit = self.light_ray(&light.kind, p).and_then(|lr| {
                let cos = dot(n, lr.l);
                if cos <= 0.0 {
                    return None;
                }
                stats.shadow += 1;
                let shadow_ray = Ray {
                    origin: p,
                    dir: lr.l,
                };
                let span = Span::open(EPSILON, lr.distance);
                (!self.accel.blocked(shadow_ray, span, &mut stats.shadows)).then_some(cos)
            });
            match lit {
                Some(cos) => {
                    for (ch, base) in c.iter_mut().zip(m.color) {
                        *ch += m.kd * cos * base * light.intensity;
                    }
                }
                None => bits |= 1 << k,
            }
        }
        (c, bits)
    }

    /// The colour at `hit` of `ray` (depth `depth`, weight `weight`) and the shadow bits there.
    fn shade(
        &self,
        ray: &Ray,
        hit: &Hit,
        depth: u32,
        weight: f64,
        stats: &mut TraceStats,
    ) -> ([f64; 3], u8) {
        let p = ray.at(hit.t);
        let (Some(m), Some(d)) = (self.scene.material_at(hit.id, p), normalize(ray.dir)) else {
            return (self.scene.background, 0);
        };
        let v = scale(d, -1.0);
        // Leaving the shape when the ray meets the surface from the side opposite its normal.
        let leaving = dot(hit.normal, d) > 0.0;
        let n = if leaving {
            scale(hit.normal, -1.0)
        } else {
            hit.normal
        };
        let (mut c, bits) = self.local(hit.id, p, n, stats);
        let cos_i = dot(n, v);
        let r = sub(scale(n, 2.0 * cos_i), v);
        let (n1, n2) = if leaving { (m.ior, 1.0) } else { (1.0, m.ior) };
        let eta = n1 / n2;
        let k = 1.0 - eta * eta * (1.0 - cos_i * cos_i);
        let t = if k < 0.0 {
            None
        } else {
            normalize(sub(scale(v, -eta), scale(n, -(eta * cos_i - k.sqrt()))))
        };
        let refraction = match t {
            Some(t) => (t, Spawn::Refraction),
            None => (r, Spawn::TotalInternalReflection),
        };
        for (coefficient, (dir, spawn)) in [(m.kr, (r, Spawn::Reflection)), (m.kt, refraction)] {
            if coefficient == 0.0 {
                continue;
            }
            if depth >= self.limits.max_depth {
                stats.cut_by_depth += 1;
                continue;
            }
            let child_weight = weight * coefficient;
            if child_weight < self.limits.threshold {
                stats.cut_by_weight += 1;
                continue;
            }
            if spawn == Spawn::TotalInternalReflection {
                stats.total_internal_reflections += 1;
            }
            let child = depth as usize + 1;
            if stats.secondary_by_depth.len() <= child {
                stats.secondary_by_depth.resize(child + 1, 0);
            }
            stats.secondary_by_depth[child] += 1;
            let ray = Ray { origin: p, dir };
            if let Some(log) = stats.log.as_mut() {
                log.push(TreeRay {
                    depth: depth + 1,
                    weight: child_weight,
                    ray,
                    spawn,
                });
            }
            let sub_colour = self.colour(&ray, depth + 1, child_weight, stats);
            for (ch, s) in c.iter_mut().zip(sub_colour) {
                *ch += coefficient * s;
            }
        }
        (c, bits)
    }
}

/// Clamps a colour to [0, 1] per channel and rounds it to 8 bits.
pub fn to_rgb8(c: [f64; 3]) -> [u8; 3] {
    c.map(|v| (255.0 * v.clamp(0.0, 1.0)).round() as u8)
}
