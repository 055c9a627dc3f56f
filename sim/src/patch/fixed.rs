//! The f64 patch model converted to the library's fixed-point patches, and `sim render
//! MODEL.bpt --renderer fixed`: the library's scanline patch renderer on the host.

use super::PatchModel;
use crate::reference::Image;
use crate::scene::{CameraSpec, LightSpec};
use embedded_graphics::pixelcolor::{Rgb888, RgbColor};
use fixed::types::I16F16;
use scanline3d::patch::{
    self, ControlPoints, PatchColors, PatchScene, PatchStats, PatchWorkspace, Tolerance, TrimLoop,
    TrimPoint, Weight,
};
use scanline3d::scene::{Light, Transform};
use scanline3d::sink::{FnSink, Row, TriangleId};
use scanline3d::{Flat, Gouraud, RenderOptions, Shading};
use std::convert::Infallible;

/// Largest target the host patch renderer takes (per side).
pub const MAX_SIZE: usize = 1024;
/// Patches and pieces that may wait in row buckets on the host.
const SUBS: usize = 16384;
/// Triangles that may be active at once on the host.
const ACTIVE: usize = 16384;

/// A patch model in the library's formats: I16F16 control points and weights (`None` when
/// every weight is 1), trim loops as I16F16 `(u, v)` points.
#[derive(Clone, Debug, PartialEq)]
pub struct FixedPatches {
    /// Control points, one set of 16 per patch.
    pub points: Vec<ControlPoints>,
    /// Weights, if any patch is rational.
    pub weights: Option<Vec<[Weight; 16]>>,
    /// Trim loops in patch order, indexing `trim_points`.
    pub trim_loops: Vec<TrimLoop>,
    /// The trim loops' points.
    pub trim_points: Vec<TrimPoint>,
}

impl FixedPatches {
    /// Converts `model`, rounding to nearest; coordinates and weights must be inside the
    /// library's envelope ([`patch::MAX_PATCH_COORD`], [`patch::MIN_WEIGHT`]..=[`patch::MAX_WEIGHT`]).
    pub fn new(model: &PatchModel) -> Result<Self, String> {
        let limit = patch::MAX_PATCH_COORD as f64;
        let (lo, hi) = (
            patch::MIN_WEIGHT.to_num::<f64>(),
            patch::MAX_WEIGHT.to_num::<f64>(),
        );
        let mut points = Vec::with_capacity(model.patches.len());
        let mut weights = Vec::with_capacity(model.patches.len());
        for (k, p) in model.patches.iter().enumerate() {
            if p.points
                .iter()
                .flatten()
                .any(|c| !c.is_finite() || c.abs() > limit)
            {
                return Err(format!(
                    "patch {k}: a coordinate is beyond ±{limit}, the fixed-point envelope"
                ));
            }
            if p.weights.iter().any(|w| !(lo..=hi).contains(w)) {
                return Err(format!(
                    "patch {k}: a weight is outside {lo}..={hi}, the fixed-point envelope"
                ));
            }
            points.push(p.points.map(|c| c.map(I16F16::from_num)));
            weights.push(p.weights.map(Weight::from_num));
        }
        let rational = weights.iter().flatten().any(|&w| w != Weight::ONE);
        let mut trim_loops = Vec::new();
        let mut trim_points = Vec::new();
        for (k, p) in model.patches.iter().enumerate() {
            for t in &p.trims {
                let (patch, start, len) = (
                    u16::try_from(k),
                    u32::try_from(trim_points.len()),
                    u32::try_from(t.points.len()),
                );
                let (Ok(patch), Ok(start), Ok(len)) = (patch, start, len) else {
                    return Err(format!("patch {k}: too many patches or trim points"));
                };
                trim_loops.push(TrimLoop { patch, start, len });
                trim_points.extend(t.points.iter().map(|p| p.map(I16F16::from_num)));
            }
        }
        Ok(FixedPatches {
            points,
            weights: rational.then_some(weights),
            trim_loops,
            trim_points,
        })
    }

    /// Patches with trim loops.
    pub fn trimmed(&self) -> usize {
        let mut patches: Vec<u16> = self.trim_loops.iter().map(|l| l.patch).collect();
        patches.dedup();
        patches.len()
    }

    /// The library's checked model, with `colors` (one per patch, or one for all).
    pub fn model<'a>(&'a self, colors: PatchColors<'a>) -> Result<patch::PatchModel<'a>, String> {
        patch::PatchModel::new(&self.points, self.weights.as_deref(), colors)
            .and_then(|m| m.with_trims(&self.trim_loops, &self.trim_points))
            .map_err(|e| format!("{e} (in I16F16)"))
    }
}

/// How `sim render` shades patches.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PatchShading {
    /// One colour per triangle, from the patch normal at its parameter centroid.
    Flat,
    /// Colours lit per vertex from the patch normals, interpolated.
    Gouraud,
}

/// What [`render_fixed`] returns.
pub struct FixedPatchRender {
    /// Colours, ids (patch indices) and eye depth.
    pub image: Image,
    /// Statistics of the colour pass.
    pub stats: PatchStats,
}

/// The colour every patch gets on the host.
pub const PATCH_COLOR: Rgb888 = Rgb888::new(230, 200, 120);

/// Renders `model` with the library's patch renderer at flatness `tolerance` pixels, 4
/// sub-pixel bits, two-sided unless `cull`.
#[allow(clippy::too_many_arguments)]
pub fn render_fixed(
    model: &PatchModel,
    camera: &CameraSpec,
    light: &LightSpec,
    (w, h): (usize, usize),
    tolerance: f64,
    cull: bool,
    shading: PatchShading,
) -> Result<FixedPatchRender, String> {
    if w == 0 || h == 0 || w > MAX_SIZE || h > MAX_SIZE {
        return Err(format!("patch images are 1..={MAX_SIZE} pixels per side"));
    }
    if !(tolerance.is_finite() && tolerance > 0.0 && tolerance < 256.0) {
        return Err(format!(
            "tolerance {tolerance}: want a number of pixels in (0, 256)"
        ));
    }
    let fixed = FixedPatches::new(model)?;
    let lib = fixed.model(PatchColors::Uniform(PATCH_COLOR))?;
    let f32s = |v: [f64; 3]| v.map(|c| c as f32);
    let scene = PatchScene {
        model: &lib,
        transform: Transform::IDENTITY,
        camera: camera.fixed()?,
        light: Light::new(
            f32s(light.direction),
            light.ambient as f32,
            light.diffuse as f32,
        )
        .map_err(|e| format!("light: {e}"))?,
    };
    let tolerance = Tolerance::from_num(tolerance);
    // The workspaces are large; build them on a thread with room for that in debug builds.
    std::thread::scope(|scope| {
        std::thread::Builder::new()
            .stack_size(256 << 20)
            .spawn_scoped(scope, || match shading {
                PatchShading::Flat => two_passes::<Flat>(&scene, (w, h), tolerance, cull),
                PatchShading::Gouraud => two_passes::<Gouraud>(&scene, (w, h), tolerance, cull),
            })
            .map_err(|e| format!("cannot start render thread: {e}"))?
            .join()
            .map_err(|_| "render thread panicked".to_string())?
    })
}

/// A colour pass and an id pass (with depth).
fn two_passes<S: Shading>(
    scene: &PatchScene<'_>,
    (w, h): (usize, usize),
    tolerance: Tolerance,
    cull: bool,
) -> Result<FixedPatchRender, String> {
    let options = RenderOptions::default().with_back_face_culling(cull);
    let mut image = Image {
        width: w,
        height: h,
        ids: vec![-1; w * h],
        depth: vec![f32::INFINITY; w * h],
        color: vec![[0; 3]; w * h],
    };
    let mut colors: Box<PatchWorkspace<Rgb888, S, MAX_SIZE, MAX_SIZE, SUBS, ACTIVE>> =
        Box::new(PatchWorkspace::new(Rgb888::new(0, 0, 0)));
    let mut sink = FnSink(|row: Row<'_, Rgb888>| -> Result<(), Infallible> {
        let at = row.y as usize * w;
        for (x, c) in row.pixels.iter().enumerate() {
            image.color[at + x] = [c.r(), c.g(), c.b()];
        }
        Ok(())
    });
    let stats = colors
        .render_sized(w, h, scene, &options, tolerance, &mut sink)
        .map_err(|e| e.to_string())?;
    drop(colors);
    let camera = scene.camera;
    let mut ids: Box<PatchWorkspace<TriangleId, S, MAX_SIZE, MAX_SIZE, SUBS, ACTIVE>> =
        Box::new(PatchWorkspace::new(TriangleId::NONE));
    let mut sink = FnSink(|row: Row<'_, TriangleId>| -> Result<(), Infallible> {
        let at = row.y as usize * w;
        for (x, id) in row.pixels.iter().enumerate() {
            image.ids[at + x] = id.0;
            image.depth[at + x] = match row.depth.get(x) {
                Some(q) if id.0 >= 0 => camera.eye_distance(q).unwrap_or(f32::INFINITY),
                _ => f32::INFINITY,
            };
        }
        Ok(())
    });
    ids.render_sized(w, h, scene, &options, tolerance, &mut sink)
        .map_err(|e| e.to_string())?;
    Ok(FixedPatchRender { image, stats })
}

/// `fixed` as Rust source: `static` I16F16 control points (`POINTS`), weights (`WEIGHTS`, for
/// rational models), trim loops (`TRIM_LOOPS`, `TRIM_POINTS`, for trimmed models) and the
/// checked `MODEL` (checked at compile time), for firmware. `command` goes into the header.
pub fn export_source(fixed: &FixedPatches, color: Rgb888, command: &str) -> String {
    use std::fmt::Write as _;
    let n = fixed.points.len();
    let mut s = String::new();
    let _ = writeln!(
        s,
        "//! Generated by `{command}`: {n} bicubic Bezier patches as static I16F16 data (row-major\n\
         //! control points, `points[4·i + j]` = `P_ij`; ids are patch indices). Do not edit.\n"
    );
    s += "use embedded_graphics::pixelcolor::Rgb888;\nuse fixed::types::I16F16;\n";
    s += if fixed.trim_loops.is_empty() {
        "use scanline3d::patch::{ControlPoints, PatchColors, PatchModel};\n\n"
    } else {
        "use scanline3d::patch::{ControlPoints, PatchColors, PatchModel, TrimLoop, TrimPoint};\n\n"
    };
    s += "const fn c(bits: i32) -> I16F16 {\n    I16F16::from_bits(bits)\n}\n\n";
    let _ = writeln!(
        s,
        "/// Control points, 16 per patch.\npub static POINTS: [ControlPoints; {n}] = ["
    );
    for p in &fixed.points {
        s += "    [\n";
        for q in p {
            let _ = writeln!(
                s,
                "        [c({}), c({}), c({})],",
                q[0].to_bits(),
                q[1].to_bits(),
                q[2].to_bits()
            );
        }
        s += "    ],\n";
    }
    s += "];\n\n";
    let weights = match &fixed.weights {
        Some(w) => {
            let _ = writeln!(
                s,
                "/// Weights, 16 per patch.\npub static WEIGHTS: [[I16F16; 16]; {n}] = ["
            );
            for p in w {
                let bits: Vec<String> = p.iter().map(|w| format!("c({})", w.to_bits())).collect();
                let _ = writeln!(s, "    [{}],", bits.join(", "));
            }
            s += "];\n\n";
            "Some(&WEIGHTS)"
        }
        None => "None",
    };
    let checked = if fixed.trim_loops.is_empty() {
        "Ok(m) => m"
    } else {
        let _ = writeln!(
            s,
            "/// Trim loops (patch, first point, point count), in patch order.\n\
             pub static TRIM_LOOPS: [TrimLoop; {}] = [",
            fixed.trim_loops.len()
        );
        for l in &fixed.trim_loops {
            let _ = writeln!(
                s,
                "    TrimLoop {{ patch: {}, start: {}, len: {} }},",
                l.patch, l.start, l.len
            );
        }
        let _ = writeln!(
            s,
            "];\n\n/// Trim points `(u, v)`, the loops' vertices.\n\
             pub static TRIM_POINTS: [TrimPoint; {}] = [",
            fixed.trim_points.len()
        );
        for p in &fixed.trim_points {
            let _ = writeln!(s, "    [c({}), c({})],", p[0].to_bits(), p[1].to_bits());
        }
        s += "];\n\n";
        "Ok(m) => match m.with_trims(&TRIM_LOOPS, &TRIM_POINTS) {\n        Ok(m) => m,\n        \
         Err(_) => panic!(\"the exported trim loops are invalid\"),\n    }"
    };
    let _ = writeln!(
        s,
        "/// The model, checked when this file is compiled.\n\
         pub static MODEL: PatchModel<'static> = match PatchModel::new(\n    &POINTS,\n    {weights},\n    \
         PatchColors::Uniform(Rgb888::new({}, {}, {})),\n) {{\n    {checked},\n    \
         Err(_) => panic!(\"the exported patches are outside the library's envelope\"),\n}};",
        color.r(),
        color.g(),
        color.b()
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::patch::parse;

    #[test]
    fn the_shipped_models_convert() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/patches");
        for name in ["teapot.bpt", "sphere.bpt", "trimmed.bpt"] {
            let model = parse::load(&dir.join(name)).unwrap();
            let fixed = FixedPatches::new(&model).unwrap();
            assert_eq!(fixed.points.len(), model.patches.len());
            assert_eq!(fixed.weights.is_some(), name == "sphere.bpt");
            assert_eq!(fixed.trimmed(), usize::from(name == "trimmed.bpt"));
            fixed.model(PatchColors::Uniform(PATCH_COLOR)).unwrap();
        }
    }
}
