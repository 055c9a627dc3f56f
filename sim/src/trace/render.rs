//! A whole traced frame: colour, primary ids, eye depth and shadow mask per pixel, in the
//! image formats of DESIGN.md.

use super::accel::{Accel, Structure};
use super::scene::{check_camera, CameraSpec, TracedScene};
use super::whitted::{to_rgb8, Limits, TraceStats, Tracer};

/// A traced frame.
#[derive(Clone, Debug, PartialEq)]
pub struct TracedImage {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Colour per pixel, clamped and rounded (`round(255·c)`).
    pub color: Vec<[u8; 3]>,
    /// Primary-hit object id per pixel, −1 for background.
    pub ids: Vec<i32>,
    /// Eye depth of the primary hit, +inf for background.
    pub depth: Vec<f32>,
    /// Bit k set when light k contributes nothing at the primary hit (N·L ≤ 0 or blocked).
    pub shadow: Vec<u8>,
    /// Index of the material at the primary hit (a checker texture's cell's), −1 for
    /// background.
    pub materials: Vec<i32>,
    /// What tracing did.
    pub stats: TraceStats,
}

/// Traces `scene` through `camera` at `w × h` with the f64 reference tracer.
pub fn render(
    scene: &TracedScene,
    camera: &CameraSpec,
    w: usize,
    h: usize,
    limits: Limits,
    structure: Structure,
) -> Result<TracedImage, String> {
    let cam = check_camera(camera)?;
    limits.check()?;
    if w == 0 || h == 0 {
        return Err(format!("image size {w}x{h} is empty"));
    }
    let accel = Accel::build(scene, structure);
    let tracer = Tracer::new(&accel, limits);
    let n = w * h;
    let mut img = TracedImage {
        width: w,
        height: h,
        color: Vec::with_capacity(n),
        ids: Vec::with_capacity(n),
        depth: Vec::with_capacity(n),
        shadow: Vec::with_capacity(n),
        materials: Vec::with_capacity(n),
        stats: TraceStats::default(),
    };
    for y in 0..h {
        for x in 0..w {
            let p = tracer.pixel(&cam, x, y, w, h, &mut img.stats);
            img.color.push(to_rgb8(p.colour));
            img.ids.push(p.hit.map_or(-1, |hit| hit.id as i32));
            img.depth
                .push(p.hit.map_or(f32::INFINITY, |hit| hit.t as f32));
            img.shadow.push(p.shadow);
            // The hit point exactly as the tracer shaded it (`Ray::at` of the primary ray).
            let material = p.hit.and_then(|hit| {
                let ray = super::vector::Ray {
                    origin: cam.eye,
                    dir: super::scene::primary_ray(&cam, x, y, w, h),
                };
                scene.material_index_at(hit.id, ray.at(hit.t))
            });
            img.materials.push(material.map_or(-1, |m| m as i32));
        }
    }
    Ok(img)
}
