//! The library's fixed-point caster on the host, and its comparison with the f64 reference.

use super::reference::Reference;
use super::MetaScene;
use crate::reference::Image;
use crate::scene::CameraSpec;
use embedded_graphics::pixelcolor::Rgb888;
use embedded_graphics::prelude::RgbColor;
use scanline3d::depth::DepthRow;
use scanline3d::metaball::{CastStats, Caster, MetaCamera, Metaballs, EPSILON_T};
use scanline3d::scene::Light;
use scanline3d::sink::{FnSink, Row, TriangleId};

/// Largest width the host renders with the library caster.
pub const MAX_WIDTH: usize = 640;
/// Most balls the host renders with the library caster.
pub const MAX_BALLS: usize = 64;

/// Depth slack on top of the march's bound: the f32 camera set-up and I32F32 rounding
/// (relative to the eye depth).
pub const DEPTH_SLACK: f64 = 1e-4;

/// The fixed-point caster's image (colour, ids, eye depth) and statistics.
pub fn render_fixed(
    scene: &MetaScene,
    frame: u32,
    camera: &CameraSpec,
    w: usize,
    h: usize,
) -> Result<(Image, CastStats), String> {
    if w > MAX_WIDTH {
        return Err(format!("width {w} over the host caster's {MAX_WIDTH}"));
    }
    let fixed = super::fixed::FixedMeta::new(scene)?;
    let balls = fixed.balls_at(frame);
    let metaballs = Metaballs::new(&balls, fixed.threshold).map_err(|e| e.to_string())?;
    let f = |v: [f64; 3]| v.map(|c| c as f32);
    let cam = MetaCamera::new(
        f(camera.eye),
        f(camera.target),
        f(camera.up),
        camera.fovy as f32,
        camera.near as f32,
        camera.far as f32,
        u16::try_from(w).map_err(|_| "width")?,
        u16::try_from(h).map_err(|_| "height")?,
    )
    .map_err(|e| e.to_string())?;
    let (d, a, di) = scene.light;
    let light = Light::new(f(d), a as f32, di as f32).map_err(|e| e.to_string())?;
    let mut image = Image::background(w, h);
    let near = camera.near;
    let stats = {
        let mut caster: Box<Caster<Rgb888, MAX_WIDTH, MAX_BALLS>> =
            Box::new(Caster::new(Rgb888::BLACK));
        render_rows(
            &mut caster,
            &metaballs,
            &cam,
            &light,
            |y, row: Row<'_, Rgb888>| {
                for (x, p) in row.pixels.iter().take(w).enumerate() {
                    image.color[y * w + x] = [p.r(), p.g(), p.b()];
                }
                if let DepthRow::Q30(q) = row.depth {
                    for (x, q) in q.iter().take(w).enumerate() {
                        if *q > 0 {
                            image.depth[y * w + x] = (near / q.to_num::<f64>()) as f32;
                        }
                    }
                }
            },
        )?
    };
    let mut ids: Box<Caster<TriangleId, MAX_WIDTH, MAX_BALLS>> =
        Box::new(Caster::new(TriangleId::NONE));
    render_rows(
        &mut ids,
        &metaballs,
        &cam,
        &light,
        |y, row: Row<'_, TriangleId>| {
            for (x, p) in row.pixels.iter().take(w).enumerate() {
                image.ids[y * w + x] = p.0;
            }
        },
    )?;
    Ok((image, stats))
}

fn render_rows<P: scanline3d::sink::RowPixel>(
    caster: &mut Caster<P, MAX_WIDTH, MAX_BALLS>,
    scene: &Metaballs<'_>,
    camera: &MetaCamera,
    light: &Light,
    mut each: impl FnMut(usize, Row<'_, P>),
) -> Result<CastStats, String> {
    let mut sink = FnSink(|row: Row<'_, P>| -> Result<(), ()> {
        each(usize::from(row.y), row);
        Ok(())
    });
    caster
        .render(scene, camera, light, &mut sink)
        .map_err(|e| format!("caster: {e:?}"))
}

/// The caster against the reference, per the measures.
#[derive(Clone, Debug, Default)]
pub struct MetaComparison {
    /// Pixels.
    pub pixels: usize,
    /// Pixels covered by exactly one of the two.
    pub coverage_mismatches: usize,
    /// Of those, pixels with no reference silhouette in their 3×3 neighbourhood.
    pub off_silhouette: usize,
    /// Pixels covered by both.
    pub both: usize,
    /// Largest eye-depth error over pixels covered by both.
    pub max_depth_error: f64,
    /// Mean eye-depth error over pixels covered by both.
    pub mean_depth_error: f64,
    /// Pixels whose depth error exceeds the ray caster's documented bound (see [`compare`]).
    pub depth_over_bound: usize,
    /// Colour PSNR over every pixel and channel (dB).
    pub psnr: f64,
    /// Ids that differ where both cover.
    pub id_mismatches: usize,
}

impl MetaComparison {
    /// Coverage mismatches in percent of the pixels.
    pub fn coverage_percent(&self) -> f64 {
        100.0 * self.coverage_mismatches as f64 / self.pixels.max(1) as f64
    }
}

impl std::fmt::Display for MetaComparison {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "coverage mismatches {} ({:.3} %), off the silhouette {}; depth: max error {:.2e}, mean {:.2e}, over the caster's bound {}; PSNR {:.2} dB; id mismatches {}",
            self.coverage_mismatches,
            self.coverage_percent(),
            self.off_silhouette,
            self.max_depth_error,
            self.mean_depth_error,
            self.depth_over_bound,
            self.psnr,
            self.id_mismatches
        )
    }
}

/// Compares the caster's image with the reference's. The depth bound per pixel is the march's
/// `EPSILON_T · max L / min |g'|` (Lipschitz bound over the field's slope along the ray, both
/// taken between the two depths, sampled at 17 points) plus
/// [`DEPTH_SLACK`] of the depth.
pub fn compare(fixed: &Image, reference: &Image, reference_scene: &Reference) -> MetaComparison {
    let (w, h) = (reference.width, reference.height);
    let mut m = MetaComparison {
        pixels: w * h,
        ..Default::default()
    };
    let covered = |x: usize, y: usize| reference.ids[y * w + x] >= 0;
    let mut squared = 0.0;
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            let (f, r) = (fixed.ids[i] >= 0, reference.ids[i] >= 0);
            for c in 0..3 {
                let e = fixed.color[i][c] as f64 - reference.color[i][c] as f64;
                squared += e * e;
            }
            if f != r {
                m.coverage_mismatches += 1;
                let near_silhouette = (y.saturating_sub(1)..(y + 2).min(h))
                    .any(|yy| (x.saturating_sub(1)..(x + 2).min(w)).any(|xx| covered(xx, yy) != r));
                if !near_silhouette {
                    m.off_silhouette += 1;
                }
            } else if f {
                m.both += 1;
                if fixed.ids[i] != reference.ids[i] {
                    m.id_mismatches += 1;
                }
                let d = reference_scene
                    .camera
                    .ray(x as f64 + 0.5, y as f64 + 0.5, w, h);
                let t = reference.depth[i] as f64;
                let tf = fixed.depth[i] as f64;
                let error = (tf - t).abs();
                m.max_depth_error = m.max_depth_error.max(error);
                m.mean_depth_error += error;
                // Mean value theorem: |g(t_f)| = |g'(ξ)|·|t − t_f| for some ξ between the two,
                // and the march stopped with |g(t_f)| < EPSILON_T·L.
                let (mut slope, mut lipschitz) = (f64::INFINITY, 0.0f64);
                for k in 0..=16 {
                    let hit = reference_scene.hit(d, tf + (t - tf) * k as f64 / 16.0);
                    slope = slope.min(hit.slope);
                    lipschitz = lipschitz.max(hit.lipschitz);
                }
                let bound =
                    EPSILON_T.to_num::<f64>() * lipschitz / slope.max(1e-300) + DEPTH_SLACK * t;
                if error > bound {
                    m.depth_over_bound += 1;
                }
            }
        }
    }
    m.mean_depth_error /= m.both.max(1) as f64;
    let mse = squared / (3 * w * h) as f64;
    m.psnr = if mse == 0.0 {
        f64::INFINITY
    } else {
        10.0 * (255.0f64 * 255.0 / mse).log10()
    };
    m
}
