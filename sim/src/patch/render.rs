//! The reference image of a patch model: one ray per pixel centre, intersected with every
//! patch whose control-hull box it enters by Bezier clipping ([`super::clip`]); the nearest
//! kept hit within `[near, far]` in eye depth gives the pixel's id (the patch index in file
//! order), eye depth and colour.
//!
//! Colour is [`BASE_COLOR`] times the light's intensity for the exact surface normal at the
//! hit, turned towards the eye (patches are lit two-sided, as the fixed renderer lights them):
//! the limit that flat and Gouraud shading of finer and finer triangles approach.

use super::clip::{self, ClipStats};
use super::model::PatchModel;
use crate::reference::{dot, Camera, Image, Light, V3};

/// The base colour of every patch (0–255 per channel): the fixed renderer's
/// `fixed::PATCH_COLOR`, so the two images compare (a test checks they agree).
pub const BASE_COLOR: [f64; 3] = [230.0, 200.0, 120.0];

/// The nearest point where a ray meets the model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PatchHit {
    /// Patch index in file order.
    pub patch: usize,
    /// Patch parameter `u`.
    pub u: f64,
    /// Patch parameter `v`.
    pub v: f64,
    /// Ray parameter (the eye depth, for camera rays).
    pub t: f64,
    /// The hit point.
    pub point: V3,
    /// Unit normal `∂P/∂u × ∂P/∂v` (not turned towards the eye); `None` where the patch is
    /// degenerate in every direction.
    pub normal: Option<V3>,
}

/// Work done rendering one image.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RenderStats {
    /// Rays cast (pixels).
    pub rays: u64,
    /// Rays that hit the model.
    pub hits: u64,
    /// Clip rounds summed over all rays and patches.
    pub rounds: u64,
    /// The most clip rounds one ray needed (over all patches it was tested against).
    pub max_rounds: u32,
    /// Rays for which at least one region was split.
    pub rays_split: u64,
    /// Ray/patch searches stopped by [`clip::MAX_ROUNDS`].
    pub capped: u64,
}

impl RenderStats {
    /// Mean clip rounds per ray.
    pub fn mean_rounds(&self) -> f64 {
        self.rounds as f64 / self.rays.max(1) as f64
    }
}

/// A patch model with its camera and light, ready to ray trace.
#[derive(Clone, Debug)]
pub struct Reference {
    /// The model.
    pub model: PatchModel,
    /// The camera.
    pub camera: Camera,
    /// The light.
    pub light: Light,
    /// Per patch, the box around its control points (the patch lies inside).
    boxes: Vec<(V3, V3)>,
}

/// The ray parameters where `origin + t·dir` is inside the box, clamped to `[t0, t1]`.
fn box_span(origin: V3, dir: V3, (lo, hi): (V3, V3), (t0, t1): (f64, f64)) -> Option<(f64, f64)> {
    let (mut a, mut b) = (t0, t1);
    for k in 0..3 {
        if dir[k] == 0.0 {
            if origin[k] < lo[k] || origin[k] > hi[k] {
                return None;
            }
            continue;
        }
        let (p, q) = ((lo[k] - origin[k]) / dir[k], (hi[k] - origin[k]) / dir[k]);
        a = a.max(p.min(q));
        b = b.min(p.max(q));
    }
    (a <= b).then_some((a, b))
}

impl Reference {
    /// The model seen by `camera` under `light`.
    pub fn new(model: PatchModel, camera: Camera, light: Light) -> Reference {
        let boxes = model.patches.iter().map(|p| p.bounds()).collect();
        Reference {
            model,
            camera,
            light,
            boxes,
        }
    }

    /// The nearest hit along `origin + t·dir` with `t` in `range`, and the clipping work.
    /// Ties in `t` go to the lower patch index.
    pub fn trace(&self, origin: V3, dir: V3, range: (f64, f64)) -> (Option<PatchHit>, ClipStats) {
        let mut stats = ClipStats::default();
        let mut best: Option<PatchHit> = None;
        for (k, (patch, b)) in self.model.patches.iter().zip(&self.boxes).enumerate() {
            let limit = best.map_or(range.1, |h| h.t);
            // A small margin: the box is exact, but the slab arithmetic rounds.
            let slack = 1e-9 * (1.0 + limit.abs());
            if box_span(origin, dir, *b, (range.0 - slack, limit + slack)).is_none() {
                continue;
            }
            if let Some(r) = clip::nearest(patch, origin, dir, (range.0, limit), &mut stats) {
                if best.is_none_or(|h| r.t < h.t) {
                    best = Some(PatchHit {
                        patch: k,
                        u: r.u,
                        v: r.v,
                        t: r.t,
                        point: patch.point(r.u, r.v),
                        normal: patch.normal(r.u, r.v),
                    });
                }
            }
        }
        (best, stats)
    }

    /// The camera ray through screen point `(x, y)` of a `w × h` image: the nearest hit at an
    /// eye depth within `[near, far]`.
    pub fn cast(&self, x: f64, y: f64, w: usize, h: usize) -> (Option<PatchHit>, ClipStats) {
        let dir = self.camera.ray(x, y, w, h);
        self.trace(self.camera.eye, dir, (self.camera.near, self.camera.far))
    }

    /// The lit colour of a hit seen along `dir`.
    pub fn shade(&self, hit: &PatchHit, dir: V3) -> [u8; 3] {
        let i = hit.normal.map_or(self.light.ambient, |n| {
            let facing = if dot(n, dir) > 0.0 { n.map(|c| -c) } else { n };
            self.light.intensity(facing)
        });
        BASE_COLOR.map(|c| (c * i).round().clamp(0.0, 255.0) as u8)
    }

    /// Renders every pixel centre of a `w × h` image (rows shared among the machine's cores;
    /// the result does not depend on how).
    pub fn render(&self, w: usize, h: usize) -> (Image, RenderStats) {
        let mut img = Image {
            width: w,
            height: h,
            ids: vec![-1; w * h],
            depth: vec![f32::INFINITY; w * h],
            color: vec![[0; 3]; w * h],
        };
        let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
        let rows_per = h.div_ceil(threads).max(1);
        let parts: Vec<RenderStats> = std::thread::scope(|scope| {
            let workers: Vec<_> = img
                .ids
                .chunks_mut(rows_per * w)
                .zip(img.depth.chunks_mut(rows_per * w))
                .zip(img.color.chunks_mut(rows_per * w))
                .enumerate()
                .map(|(k, ((ids, depth), color))| {
                    scope.spawn(move || self.render_rows(k * rows_per, w, h, ids, depth, color))
                })
                .collect();
            workers
                .into_iter()
                .map(|t| t.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
                .collect()
        });
        let mut stats = RenderStats::default();
        for p in parts {
            stats.rays += p.rays;
            stats.hits += p.hits;
            stats.rounds += p.rounds;
            stats.max_rounds = stats.max_rounds.max(p.max_rounds);
            stats.rays_split += p.rays_split;
            stats.capped += p.capped;
        }
        (img, stats)
    }

    /// Renders the rows from `first` on into the given slices of the image.
    fn render_rows(
        &self,
        first: usize,
        w: usize,
        h: usize,
        ids: &mut [i32],
        depth: &mut [f32],
        color: &mut [[u8; 3]],
    ) -> RenderStats {
        let mut stats = RenderStats::default();
        for (i, ((id, z), rgb)) in ids.iter_mut().zip(depth).zip(color).enumerate() {
            let (x, y) = ((i % w) as f64 + 0.5, (first + i / w) as f64 + 0.5);
            let (hit, s) = self.cast(x, y, w, h);
            stats.rays += 1;
            stats.rounds += u64::from(s.rounds);
            stats.max_rounds = stats.max_rounds.max(s.rounds);
            stats.rays_split += u64::from(s.splits > 0);
            stats.capped += u64::from(s.capped);
            if let Some(hit) = hit {
                stats.hits += 1;
                *id = hit.patch as i32;
                *z = hit.t as f32;
                *rgb = self.shade(&hit, self.camera.ray(x, y, w, h));
            }
        }
        stats
    }
}

/// Distance (pixels) from screen point `(x, y)` to the nearest point where `class` (a
/// function of the reference's hit at a screen point) changes, searched in 16 directions out
/// to `reach` pixels in steps of 1/4 px and refined by bisection to 1/1000 px; `reach` if none
/// is found. An upper bound up to the angular resolution (about 2 %), and a change thinner
/// than a step can be stepped over, which also errs long ([`distance_to_change_finely`]).
pub fn distance_to_change(class: &dyn Fn(f64, f64) -> i64, centre: (f64, f64), reach: f64) -> f64 {
    search_change(class, centre, reach, 16, 0.25)
}

/// [`distance_to_change`] in 64 directions and steps of 1/32 px: finds slivers of surface
/// (a fold seen edge on) down to about 1/32 px wide, at 16 to 32 times the cost.
pub fn distance_to_change_finely(
    class: &dyn Fn(f64, f64) -> i64,
    centre: (f64, f64),
    reach: f64,
) -> f64 {
    search_change(class, centre, reach, 64, 1.0 / 32.0)
}

fn search_change(
    class: &dyn Fn(f64, f64) -> i64,
    (x, y): (f64, f64),
    reach: f64,
    directions: u32,
    step_length: f64,
) -> f64 {
    let here = class(x, y);
    let mut best = reach;
    for k in 0..directions {
        let a = f64::from(k) * std::f64::consts::TAU / f64::from(directions);
        let (dx, dy) = (a.cos(), a.sin());
        // March outwards to the first change, then bisect.
        let mut inside = 0.0;
        let mut step = step_length;
        while step <= best {
            if class(x + dx * step, y + dy * step) != here {
                let mut outside = step;
                while outside - inside > 1e-3 {
                    let mid = (inside + outside) / 2.0;
                    if class(x + dx * mid, y + dy * mid) == here {
                        inside = mid;
                    } else {
                        outside = mid;
                    }
                }
                best = best.min(outside);
                break;
            }
            inside = step;
            step += step_length;
        }
    }
    best
}
