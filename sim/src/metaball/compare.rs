//! The library's fixed-point caster on the host, and its comparison with the f64 reference.

use super::reference::Reference;
use super::MetaScene;
use crate::reference::{dot, Image, V3};
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

/// Position error of the caster's ray points per unit of distance from the eye and of the eye
/// from the origin: its camera is set up in f32 (relative errors of a few 2^-24); taken as
/// 2^-20. Its depth output adds 2^-23 of the ray parameter.
pub const CAMERA_ROUNDING: f64 = 1.0 / 1048576.0;

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

/// `scene` at frame 0 seen by `camera` at `side × side`, by the caster and by the reference,
/// compared; `None` for a scene or camera outside the caster's or the reference's envelope.
pub fn check(scene: MetaScene, camera: CameraSpec, side: usize) -> Option<Checked> {
    let reference = camera
        .reference()
        .and_then(|c| Reference::new(&scene, 0, c))
        .ok()?;
    let (fixed, stats) = render_fixed(&scene, 0, &camera, side, side).ok()?;
    let (expected, _) = reference.render(side, side);
    let comparison = compare(&fixed, &expected, &reference);
    Some(Checked {
        scene,
        camera,
        fixed,
        expected,
        reference,
        comparison,
        stats,
    })
}

/// A scene and camera checked against the reference ([`check`]).
pub struct Checked {
    /// The scene.
    pub scene: MetaScene,
    /// The camera.
    pub camera: CameraSpec,
    /// The caster's image.
    pub fixed: Image,
    /// The reference's image.
    pub expected: Image,
    /// The reference.
    pub reference: Reference,
    /// The comparison.
    pub comparison: MetaComparison,
    /// The caster's statistics.
    pub stats: CastStats,
}

impl Checked {
    /// Whether every mismatch is explained: no coverage mismatch off the silhouette and no depth
    /// the stopping rule does not explain.
    pub fn explained(&self) -> bool {
        self.comparison.off_silhouette == 0 && self.comparison.depth_unexplained == 0
    }
}

/// Whether the 3×3 neighbourhood of pixel `(x, y)` holds a silhouette of `image`: a pixel
/// whose coverage differs from `(x, y)`'s.
pub fn near_silhouette(image: &Image, x: usize, y: usize) -> bool {
    let (w, h) = (image.width, image.height);
    let covered = |x: usize, y: usize| image.ids[y * w + x] >= 0;
    let here = covered(x, y);
    (y.saturating_sub(1)..(y + 2).min(h))
        .any(|yy| (x.saturating_sub(1)..(x + 2).min(w)).any(|xx| covered(xx, yy) != here))
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
    /// Pixels covered by both whose depth the caster's stopping rule does not explain (see
    /// [`compare`]).
    pub depth_unexplained: usize,
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
            "coverage mismatches {} ({:.3} %), off the silhouette {}; depth: max error {:.2e}, mean {:.2e}, unexplained {}; PSNR {:.2} dB; id mismatches {}",
            self.coverage_mismatches,
            self.coverage_percent(),
            self.off_silhouette,
            self.max_depth_error,
            self.mean_depth_error,
            self.depth_unexplained,
            self.psnr,
            self.id_mismatches
        )
    }
}

/// Compares the caster's image with the reference's. A depth where both cover is explained
/// when the caster's stopping rule allows it (see [`stop_explained`]).
pub fn compare(fixed: &Image, reference: &Image, reference_scene: &Reference) -> MetaComparison {
    let (w, h) = (reference.width, reference.height);
    let mut m = MetaComparison {
        pixels: w * h,
        ..Default::default()
    };
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
                if !near_silhouette(reference, x, y) {
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
                if !stop_explained(reference_scene, d, t, tf) {
                    m.depth_unexplained += 1;
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

/// Whether the caster's stopping rule explains a hit at `tf` on the ray of direction `d` whose
/// reference surface is at `t`.
///
/// The caster stops where its step `|g| / (L + 2^-16)` falls below [`EPSILON_T`] (the quotient
/// rounds its denominator up by at most 2^-16), so at `tf` the reference's `|g|` must be within
/// `EPSILON_T·(L·(1 + 2^-10) + 2^-16)` (the `2^-10` covers the caster's rounded `L`), plus what
/// rounding the scene into the library's formats ([`MarchPoint::rounding_gain`] times
/// [`Reference::input_rounding`]) and the camera and depth output (`|∇g|` times the point's
/// uncertainty, [`CAMERA_ROUNDING`] of its and the eye's distances plus 2^-23; `L` counts the
/// balls within that of the point, as the caster's may) can move `g`.
/// Where the caster stops beyond the reference's surface, `|g|` must stay in that band at 17
/// points between the two, so no sliver of surface or gap was passed. A hit this explains can
/// still be far in front of the surface where `g` runs almost level with it along the ray.
///
/// [`MarchPoint::rounding_gain`]: super::reference::MarchPoint::rounding_gain
/// [`Reference::input_rounding`]: super::reference::Reference::input_rounding
pub fn stop_explained(reference: &Reference, d: V3, t: f64, tf: f64) -> bool {
    stop_ratio(reference, d, t, tf) <= 1.0
}

/// The largest `|g|` over its allowed band at the points [`stop_explained`] checks: at most 1
/// where the rule explains the hit.
pub fn stop_ratio(reference: &Reference, d: V3, t: f64, tf: f64) -> f64 {
    let epsilon = EPSILON_T.to_num::<f64>();
    let eye = reference.camera.eye;
    let eye_distance = dot(eye, eye).sqrt();
    let length = dot(d, d).sqrt();
    let ratio = |at: f64| {
        // Where the caster's point may be, around the reference's: |d| ≥ 1, so this bounds
        // the uncertainty of the ray parameter too.
        let uncertainty = CAMERA_ROUNDING * (at * length + eye_distance) + 1.0 / 8388608.0;
        let point = reference.march_point(d, at, uncertainty);
        let band = epsilon * (point.lipschitz * (1.0 + 1.0 / 1024.0) + 1.0 / 65536.0)
            + point.rounding_gain * reference.input_rounding
            + point.gradient * uncertainty;
        point.g.abs() / band
    };
    if tf <= t {
        ratio(tf)
    } else {
        (0..=16)
            .map(|k| ratio(t + (tf - t) * f64::from(k) / 16.0))
            .fold(0.0, f64::max)
    }
}
