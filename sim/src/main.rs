//! `sim`: renders scenes on the host exactly as the firmware does, compares with the float
//! reference, and writes PNG, id and depth images.
//!
//! With no subcommand it renders frame 0 of the built-in demo scene (the firmware's data and
//! camera) to `frame.png`, compares it with the reference and prints a short report.

use clap::{Args, Parser, Subcommand, ValueEnum};
use scanline3d_sim::metrics::{self, ErrorBound};
use scanline3d_sim::reference::Image;
use scanline3d_sim::scene::{
    self, Algorithm, CameraSpec, LightSpec, PresetChoice, SceneSpec, SetupArith,
};
use scanline3d_sim::world::{Culling, Loaded};
use scanline3d_sim::{accuracy, accuracy_preset, accuracy_with, analyze, corpus};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Prints a line to stdout, ignoring write errors (a closed pipe, as in `sim corpus | head`,
/// must not turn into a panic).
macro_rules! say {
    ($($arg:tt)*) => {{
        let _ = writeln!(std::io::stdout(), $($arg)*);
    }};
}

#[derive(Parser, Debug)]
#[command(
    name = "sim",
    version,
    about = "Render scenes as the scanline3d firmware does; compare with the f64 reference"
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    /// Output PNG of the default demo render.
    #[arg(long, default_value = "frame.png")]
    out: PathBuf,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Render an OBJ scene, or a Bezier patch model (.bpt), to PNG (and optionally id, depth
    /// and statistics files).
    Render(RenderArgs),
    /// Compare two id/depth image pairs, or re-render a scene with both renderers and compare.
    Compare(CompareArgs),
    /// Report what a scene needs from the renderer over a set of views: capacities, RAM per
    /// buffer, numeric headroom, clipping, and accuracy per sub-pixel setting.
    Analyze(AnalyzeArgs),
    /// Write a scene as Rust source for firmware: static fixed-point arrays and the budget
    /// `analyze` measures (OBJ); a patch model (.bpt), traced scene (.scene) or metaball
    /// scene (.meta) as its static data.
    Export(ExportArgs),
    /// Ray-trace a traced scene (issue 21's text format) to PNG, with optional id, depth and
    /// shadow images.
    Trace(TraceArgs),
    /// Render a metaball scene (.meta): the fixed-point ray caster or the f64 reference
    /// (Bezier clipping), PNG plus optional id, depth and statistics files.
    Metaball(MetaballArgs),
    /// Write the scene corpus as OBJ files (and list its cameras).
    Corpus {
        /// Output directory.
        #[arg(long, default_value = "corpus")]
        out: PathBuf,
    },
}

#[derive(Clone, Copy, Debug, ValueEnum, PartialEq)]
enum Renderer {
    Fixed,
    Reference,
}

/// Which tracer `sim trace` runs.
#[derive(Clone, Copy, Debug, ValueEnum, PartialEq)]
enum TraceRenderer {
    /// The f64 Whitted tracer.
    Reference,
    /// The library's fixed-point tracer (`scanline3d::trace`), what the firmware runs.
    Fixed,
    /// The library's tracer in hybrid mode: primary visibility from the objects' screen
    /// bounds (a scanline pass, no hierarchy walk per pixel), then the same secondary rays.
    Hybrid,
}

/// Which acceleration structure the reference tracer uses.
#[derive(Clone, Copy, Debug, ValueEnum, PartialEq)]
enum TraceAccel {
    /// Test every object.
    None,
    /// Bounding-volume hierarchy.
    Bvh,
    /// Uniform grid walked with 3D-DDA.
    Grid,
    /// Grid whose cells hold a hierarchy.
    Both,
}

#[derive(Args, Debug)]
struct TraceArgs {
    /// The traced scene file.
    scene: PathBuf,
    /// Eye position X,Y,Z.
    #[arg(long, value_parser = vec3, allow_hyphen_values = true)]
    eye: [f64; 3],
    /// Point looked at.
    #[arg(long, value_parser = vec3, allow_hyphen_values = true)]
    target: [f64; 3],
    /// Up direction.
    #[arg(long, value_parser = vec3, allow_hyphen_values = true, default_value = "0,1,0")]
    up: [f64; 3],
    /// Vertical field of view in degrees.
    #[arg(long, value_parser = finite, default_value = "50")]
    fov: f64,
    /// Near plane: primary rays see eye depths in [near, far).
    #[arg(long, value_parser = finite, default_value = "0.1")]
    near: f64,
    /// Far plane.
    #[arg(long, value_parser = finite, default_value = "100")]
    far: f64,
    /// Image size WxH.
    #[arg(long, value_parser = size, default_value = "240x240")]
    size: (usize, usize),
    /// Output PNG.
    #[arg(long, default_value = "trace.png")]
    out: PathBuf,
    /// Primary-hit id image (W×H little-endian i32, −1 = background).
    #[arg(long)]
    ids: Option<PathBuf>,
    /// Primary-hit depth image (W×H little-endian f32 eye depth, +inf = background).
    #[arg(long)]
    depth: Option<PathBuf>,
    /// Shadow image (W×H bytes, bit k set when light k contributes nothing at the primary hit).
    #[arg(long)]
    shadow: Option<PathBuf>,
    /// Which tracer.
    #[arg(long, value_enum, default_value = "reference")]
    renderer: TraceRenderer,
    /// A ray of this depth spawns nothing (the primary ray has depth 0).
    #[arg(long, default_value_t = scanline3d_sim::trace::whitted::DEFAULT_MAX_DEPTH)]
    max_depth: u32,
    /// A secondary ray is traced only if its weight (product of KR/KT along its path) is ≥ W.
    #[arg(long, value_parser = finite, default_value_t = scanline3d_sim::trace::whitted::DEFAULT_THRESHOLD)]
    threshold: f64,
    /// Acceleration structure (same image, different work). The fixed tracer has the
    /// hierarchy and the grid but not their combination: `both` gives it the hierarchy.
    #[arg(long, value_enum, default_value = "both")]
    accel: TraceAccel,
    /// Also trace with every acceleration structure, check the images are identical and print
    /// intersection tests per ray for each.
    #[arg(long)]
    compare_accel: bool,
}

fn vec3(s: &str) -> Result<[f64; 3], String> {
    let parts: Vec<&str> = s.split(',').collect();
    if parts.len() != 3 {
        return Err(format!("expected X,Y,Z, got '{s}'"));
    }
    let mut v = [0.0; 3];
    for (out, p) in v.iter_mut().zip(parts) {
        *out = p
            .trim()
            .parse::<f64>()
            .map_err(|_| format!("'{p}' is not a number"))?;
        if !out.is_finite() {
            return Err(format!("'{p}' is not a finite number"));
        }
    }
    Ok(v)
}

fn finite(s: &str) -> Result<f64, String> {
    let v = s
        .parse::<f64>()
        .map_err(|_| format!("'{s}' is not a number"))?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(format!("'{s}' is not a finite number"))
    }
}

fn size(s: &str) -> Result<(usize, usize), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("expected WxH, got '{s}'"))?;
    let parse = |v: &str| {
        v.parse::<usize>()
            .map_err(|_| format!("'{v}' is not a size"))
    };
    let (w, h) = (parse(w)?, parse(h)?);
    if w == 0 || h == 0 || w > scene::MAX_SIZE || h > scene::MAX_SIZE {
        return Err(format!(
            "size {w}x{h} must be between 1x1 and {0}x{0}",
            scene::MAX_SIZE
        ));
    }
    Ok((w, h))
}

/// Camera, size and render settings shared by `render` and `compare --scene`.
#[derive(Args, Debug, Clone)]
struct View {
    /// Eye position X,Y,Z (negative numbers are fine: --eye -3,2,1).
    #[arg(long, value_parser = vec3, allow_hyphen_values = true, default_value = "3,2,4")]
    eye: [f64; 3],
    /// Point looked at.
    #[arg(long, value_parser = vec3, allow_hyphen_values = true, default_value = "0,0,0")]
    target: [f64; 3],
    /// Up direction.
    #[arg(long, value_parser = vec3, allow_hyphen_values = true, default_value = "0,1,0")]
    up: [f64; 3],
    /// Vertical field of view in degrees.
    #[arg(long, value_parser = finite, default_value = "50")]
    fov: f64,
    /// Near plane distance.
    #[arg(long, value_parser = finite, default_value = "0.1")]
    near: f64,
    /// Far plane distance.
    #[arg(long, value_parser = finite, default_value = "100")]
    far: f64,
    /// Image size WxH.
    #[arg(long, value_parser = size, default_value = "240x240")]
    size: (usize, usize),
    /// Sub-pixel bits of the fixed-point renderer: 0, 2, 4 (default) or 8.
    #[arg(long, default_value_t = 4)]
    sub_pixel_bits: u32,
    /// Precision preset (scanline3d::preset): fast, balanced or exact. Sets the sub-pixel
    /// bits, the set-up arithmetic and the set-up math together. Without it the renderer uses
    /// the library default (RenderOptions::default(): precise arithmetic, libm). The narrow
    /// arithmetic of fast is built for span-zbuffer only.
    #[arg(long, conflicts_with = "sub_pixel_bits")]
    preset: Option<PresetChoice>,
    #[command(flatten)]
    faces: Faces,
    /// Hidden-surface method: span-zbuffer (default), zbuffer, band:N (N = 1, 2, 4, ..., 128),
    /// depth-sort, newell, bsp, span-sort, warnock, or raycast (the f64 reference ray caster).
    #[arg(long, value_parser = method, default_value = "span-zbuffer")]
    algorithm: Method,
}

impl View {
    /// The sub-pixel bits in effect (the preset's, if one was chosen).
    fn sub_bits(&self) -> u32 {
        self.preset.map_or(self.sub_pixel_bits, |p| p.sub_bits())
    }
}

/// Which faces are drawn.
#[derive(Args, Debug, Clone)]
struct Faces {
    /// Cull back faces. Default: only where culling cannot change the image (a closed mesh
    /// wound counter-clockwise from outside, every eye outside it); otherwise two-sided.
    #[arg(long, conflicts_with = "no_cull")]
    cull: bool,
    /// Draw back faces too, always.
    #[arg(long)]
    no_cull: bool,
    /// Flip the faces of a mesh with inconsistent winding so that every face is wound
    /// counter-clockwise from outside (then culling can apply).
    #[arg(long)]
    orient: bool,
}

impl Faces {
    fn culling(&self) -> Culling {
        Culling::from_flags(self.cull, self.no_cull)
    }
}

/// What `--algorithm` selects: a fixed-point method, or the f64 ray caster.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Method {
    Fixed(Algorithm),
    Raycast,
}

fn method(s: &str) -> Result<Method, String> {
    match s {
        "raycast" => Ok(Method::Raycast),
        _ => s.parse().map(Method::Fixed),
    }
}

#[derive(Args, Debug)]
struct RenderArgs {
    /// The OBJ scene (polygons fan-triangulated in file order), or a .bpt patch model (one id
    /// per patch in file order; the camera and size options apply).
    scene: PathBuf,
    #[command(flatten)]
    view: View,
    /// Output PNG.
    #[arg(long, default_value = "frame.png")]
    out: PathBuf,
    /// Triangle id image (W×H little-endian i32, −1 = background).
    #[arg(long)]
    ids: Option<PathBuf>,
    /// Depth image (W×H little-endian f32 eye depth, +inf = background).
    #[arg(long)]
    depth: Option<PathBuf>,
    /// Statistics as JSON, to this file (`-` for standard output).
    #[arg(long)]
    stats: Option<PathBuf>,
    /// Which renderer.
    #[arg(long, value_enum, default_value = "fixed")]
    renderer: Renderer,
    /// Patch scenes (.bpt), fixed renderer: flatness tolerance in pixels (screen-space
    /// distance between the surface and its triangles, estimated from the control points).
    #[arg(long, default_value_t = 0.5)]
    tolerance: f64,
    /// Patch scenes (.bpt), fixed renderer: Gouraud shading (normals from the patch
    /// derivatives at each vertex) instead of flat.
    #[arg(long)]
    gouraud: bool,
    /// A `.meta` scene: the animation frame.
    #[arg(long)]
    frame: Option<u32>,
    /// A `.meta` scene: raycast (default), polygonize:N (N cells per axis: 8, 12, 16, 20, 24,
    /// 32, 48 or 64) or reference.
    #[arg(long, value_parser = meta_method)]
    method: Option<MetaMethod>,
    /// A `.meta` scene: also write method | reference | mismatch map to this PNG and print the
    /// comparison.
    #[arg(long)]
    beside: Option<PathBuf>,
}

/// How a `.meta` scene is rendered (`--method`).
#[derive(Clone, Copy, Debug, PartialEq)]
enum MetaMethod {
    /// The library's fixed-point ray caster.
    Raycast,
    /// The library's marching tetrahedra on a grid of N cells per axis, drawn by the span
    /// z-buffer.
    Polygonize(usize),
    /// The f64 reference: Bernstein form and Bezier clipping.
    Reference,
}

fn meta_method(s: &str) -> Result<MetaMethod, String> {
    use scanline3d_sim::metaball::polygonized::GRIDS;
    match s {
        "raycast" => Ok(MetaMethod::Raycast),
        "reference" => Ok(MetaMethod::Reference),
        _ => s
            .strip_prefix("polygonize:")
            .and_then(|n| n.parse().ok())
            .filter(|n| GRIDS.contains(n))
            .map(MetaMethod::Polygonize)
            .ok_or_else(|| {
                format!(
                    "'{s}': expected raycast, reference or polygonize:N with N one of {GRIDS:?}"
                )
            }),
    }
}

#[derive(Args, Debug)]
struct MetaballArgs {
    /// The metaball scene (.meta).
    scene: PathBuf,
    /// Animation frame (centres interpolated between keys).
    #[arg(long, default_value_t = 0)]
    frame: u32,
    /// Renderer: raycast, polygonize:N (N cells per axis: 8, 12, 16, 20, 24, 32, 48 or 64) or
    /// reference.
    #[arg(long, value_parser = meta_method, default_value = "raycast")]
    method: MetaMethod,
    /// Eye position X,Y,Z.
    #[arg(long, value_parser = vec3, allow_hyphen_values = true, default_value = "0,1.5,5")]
    eye: [f64; 3],
    /// Point looked at.
    #[arg(long, value_parser = vec3, allow_hyphen_values = true, default_value = "0,0,0")]
    target: [f64; 3],
    /// Up direction.
    #[arg(long, value_parser = vec3, allow_hyphen_values = true, default_value = "0,1,0")]
    up: [f64; 3],
    /// Vertical field of view in degrees.
    #[arg(long, value_parser = finite, default_value = "50")]
    fov: f64,
    /// Near plane distance.
    #[arg(long, value_parser = finite, default_value = "0.1")]
    near: f64,
    /// Far plane distance.
    #[arg(long, value_parser = finite, default_value = "100")]
    far: f64,
    /// Image size WxH.
    #[arg(long, value_parser = size, default_value = "240x240")]
    size: (usize, usize),
    /// Output PNG.
    #[arg(long, default_value = "frame.png")]
    out: PathBuf,
    /// Ball id image (W×H little-endian i32: the ball with the largest q·f at the hit, −1 =
    /// background).
    #[arg(long)]
    ids: Option<PathBuf>,
    /// Depth image (W×H little-endian f32 eye depth, +inf = background).
    #[arg(long)]
    depth: Option<PathBuf>,
    /// Statistics as JSON, to this file (`-` for standard output).
    #[arg(long)]
    stats: Option<PathBuf>,
    /// Also render with the other method and write caster | reference | mismatch map (red:
    /// coverage or id differs) to this PNG, and print the comparison (coverage mismatches,
    /// depth error against its bound, PSNR).
    #[arg(long)]
    beside: Option<PathBuf>,
}

#[derive(Args, Debug)]
struct CompareArgs {
    /// Id and depth files of render A, then of render B: A.ids A.depth B.ids B.depth.
    files: Vec<PathBuf>,
    /// Instead of files: render this OBJ scene with both renderers and compare, classifying
    /// every mismatch.
    #[arg(long)]
    scene: Option<PathBuf>,
    #[command(flatten)]
    view: View,
    /// With --scene: write fixed | reference | mismatches side by side to this PNG.
    #[arg(long)]
    side_by_side: Option<PathBuf>,
}

/// The views `analyze` and `export` look from.
#[derive(Args, Debug, Clone)]
struct Views {
    /// The OBJ scene (or --demo); for `export`, a `.bpt`, traced `.scene` or `.meta` file too.
    scene: Option<PathBuf>,
    /// The built-in demo scene seen from its 8-frame camera orbit (the firmware's views).
    #[arg(long, conflicts_with = "scene")]
    demo: bool,
    /// One view from this eye position instead of a sphere of views.
    #[arg(long, value_parser = vec3, allow_hyphen_values = true)]
    eye: Option<[f64; 3]>,
    /// Point looked at (default: the centre of the scene's bounding box).
    #[arg(long, value_parser = vec3, allow_hyphen_values = true)]
    target: Option<[f64; 3]>,
    /// Up direction for --eye.
    #[arg(long, value_parser = vec3, allow_hyphen_values = true, default_value = "0,1,0")]
    up: [f64; 3],
    /// Number of views on the sphere of directions around the scene.
    #[arg(long, default_value_t = 12)]
    views: usize,
    /// Distance of the sphere of views from the centre (default: 3 × the bounding radius).
    #[arg(long, value_parser = finite)]
    distance: Option<f64>,
    /// Vertical field of view in degrees.
    #[arg(long, value_parser = finite, default_value = "50")]
    fov: f64,
    /// Near plane (default: distance / 20).
    #[arg(long, value_parser = finite)]
    near: Option<f64>,
    /// Far plane (default: distance × 4).
    #[arg(long, value_parser = finite)]
    far: Option<f64>,
    /// Image size WxH.
    #[arg(long, value_parser = size, default_value = "240x240")]
    size: (usize, usize),
    #[command(flatten)]
    faces: Faces,
    /// Safety margin on the capacities, in percent: room for views between the analysed ones
    /// (an overfull frame is still reported in its statistics, never silent).
    #[arg(long, default_value_t = 25)]
    margin: u32,
}

impl Views {
    /// The scene (its camera unused; culling decided for the cameras), the cameras to
    /// analyse, and the loaded OBJ file (none for the demo).
    fn resolve(&self) -> Result<(SceneSpec, Vec<CameraSpec>, Option<Loaded>), String> {
        if self.demo {
            let frames = scanline3d_demo::ORBIT_FRAMES;
            let cams = (0..frames)
                .map(|f| SceneSpec::demo(f).map(|s| s.camera))
                .collect::<Result<Vec<_>, _>>()?;
            return Ok((SceneSpec::demo(0)?, cams, None));
        }
        let path = self.scene.as_ref().ok_or("give an OBJ scene or --demo")?;
        let loaded = Loaded::load(path, self.faces.orient)?;
        let placeholder = CameraSpec::looking_at([0.0, 0.0, 1.0], [0.0; 3], 50.0, 0.1, 100.0);
        let mut spec = SceneSpec {
            instances: loaded.instances.clone(),
            camera: placeholder,
            light: LightSpec::default(),
            cull_back_faces: false,
        };
        let (centre, radius) = analyze::bounds(&spec)?;
        let target = self.target.unwrap_or(centre);
        if self.views == 0 || self.views > 1000 {
            return Err(format!("--views {} must be 1..=1000", self.views));
        }
        let range = analyze::ViewRange::fit(radius, self.distance, self.near, self.far)?;
        let cams = match self.eye {
            Some(eye) => vec![CameraSpec {
                eye,
                target,
                up: self.up,
                fovy: self.fov,
                near: range.near,
                far: range.far,
            }],
            None => analyze::sphere_views(
                target,
                range.distance,
                self.views,
                self.fov,
                range.near,
                range.far,
            ),
        };
        for c in &cams {
            c.fixed()?;
        }
        let (w, h) = self.size;
        let decision = loaded.culling(self.faces.culling(), &cams, w as f64 / h as f64);
        spec.cull_back_faces = decision.cull;
        Ok((spec, cams, Some(loaded)))
    }
}

#[derive(Args, Debug)]
struct AnalyzeArgs {
    #[command(flatten)]
    views: Views,
    /// Accuracy goal for the recommendation: worst-view id mismatches in percent (and no real
    /// mismatches).
    #[arg(long, value_parser = finite, default_value = "0.1")]
    goal: f64,
}

#[derive(Args, Debug)]
struct ExportArgs {
    #[command(flatten)]
    views: Views,
    /// Output Rust file.
    #[arg(long, short = 'o')]
    out: PathBuf,
    /// Also export vertex normals: the OBJ file's when it has them, else area-weighted ones
    /// (only Gouraud shading uses them).
    #[arg(long)]
    normals: bool,
    /// Also build a BSP tree and export it (`BSP_TREE`, `SceneBspWorkspace`): the mesh becomes
    /// the tree's split mesh, and the budget is measured for it.
    #[arg(long)]
    bsp: bool,
    /// Light the face colours ahead of time for the scene's light and export them as the
    /// mesh's colour table, for `Unlit` shading (static light and mesh): the same pixels as
    /// `Flat` with the original colours, with no lighting on the target.
    #[arg(long)]
    bake_light: bool,
    /// The preset whose set-up arithmetic (its normals) --bake-light lights with: the firmware's
    /// (default: the default `RenderOptions`, `Precise`).
    #[arg(long, requires = "bake_light")]
    bake_preset: Option<scanline3d_sim::scene::PresetChoice>,
}

fn analyze_command(a: AnalyzeArgs) -> Result<(), String> {
    let (spec, cams, loaded) = a.views.resolve()?;
    let (w, h) = a.views.size;
    let analysis = analyze::analyze(&spec, &cams, w, h)?;
    if let Some(l) = &loaded {
        say!("winding: {}", l.orientation);
        say!(
            "culling: {}",
            l.culling(a.views.faces.culling(), &cams, w as f64 / h as f64)
                .reason
        );
        if l.instances.len() > 1 {
            say!(
                "placement: {} chunks, each around its own origin (coordinates beyond ±{} units or more than 65535 vertices)",
                l.instances.len(),
                scanline3d::scene::MAX_MODEL_COORD
            );
        }
    }
    say!("{analysis}");
    let margin = a.views.margin;
    say!(
        "capacities (margin {margin} %): TRIS = {}, ACTIVE = {}; RAM per buffer:",
        analysis.triangle_capacity(margin),
        analysis.active_capacity(margin)
    );
    for (name, bytes) in analysis.buffers(margin) {
        say!("  {bytes:>7} B  {name}");
    }
    if analysis.newell_error.is_none() {
        say!(
            "newell (margin {margin} %): PIECES = {}",
            analysis.newell.pieces_capacity(margin)
        );
    }
    match analysis.recommended(a.goal) {
        Some(s) => say!(
            "recommended for ≤ {} % id mismatches and no real ones: {} sub-pixel bits",
            a.goal,
            s.sub_bits
        ),
        None => say!(
            "no sub-pixel setting meets ≤ {} % id mismatches with no real ones",
            a.goal
        ),
    }
    Ok(())
}

/// The command line for a generated file's header, without the output path, so the same scene
/// and options always produce the same file.
fn export_command_line() -> String {
    let mut args = std::env::args().skip(1);
    let mut kept = vec!["sim".to_string()];
    while let Some(arg) = args.next() {
        if arg == "--out" || arg == "-o" {
            args.next();
        } else if !arg.starts_with("--out=") && !arg.starts_with("-o") {
            kept.push(arg);
        }
    }
    kept.join(" ")
}

/// `sim export SCENE.scene --out f.rs`: a traced scene as static fixed-point data.
fn export_traced(scene: &std::path::Path, out: &std::path::Path) -> Result<(), String> {
    use scanline3d_sim::trace::{fixed::FixedScene, scene::TracedScene};
    let fixed = FixedScene::new(&TracedScene::load(scene)?)?;
    let source = scanline3d_sim::trace::fixed::export_source(&fixed, &export_command_line());
    let source = scanline3d_sim::export::rustfmt(&source).unwrap_or(source);
    std::fs::write(out, source).map_err(|e| format!("{}: {e}", out.display()))?;
    say!(
        "wrote {} ({} objects, {} materials, {} lights)",
        out.display(),
        fixed.objects().len(),
        fixed.materials.len(),
        fixed.lights.len()
    );
    Ok(())
}

/// `sim export SCENE.meta --out f.rs`: a metaball scene as static fixed-point data.
fn export_metaballs(scene: &std::path::Path, out: &std::path::Path) -> Result<(), String> {
    use scanline3d_sim::metaball::{fixed::FixedMeta, MetaScene};
    let fixed = FixedMeta::new(&MetaScene::load(scene)?)
        .map_err(|e| format!("{}: {e}", scene.display()))?;
    let source = fixed.export_source(&export_command_line());
    let source = scanline3d_sim::export::rustfmt(&source).unwrap_or(source);
    std::fs::write(out, source).map_err(|e| format!("{}: {e}", out.display()))?;
    say!(
        "wrote {} ({} balls, {} frames)",
        out.display(),
        fixed.animated().len(),
        fixed.frames
    );
    Ok(())
}

/// `sim export MODEL.bpt --out f.rs`: a patch model as static fixed-point data.
fn export_patches(scene: &std::path::Path, out: &std::path::Path) -> Result<(), String> {
    use scanline3d_sim::patch::{fixed, parse};
    let fixed = fixed::FixedPatches::new(&parse::load(scene)?)?;
    let source = fixed::export_source(&fixed, fixed::PATCH_COLOR, &export_command_line());
    let source = scanline3d_sim::export::rustfmt(&source).unwrap_or(source);
    std::fs::write(out, source).map_err(|e| format!("{}: {e}", out.display()))?;
    say!(
        "wrote {} ({} patches{}{})",
        out.display(),
        fixed.points.len(),
        if fixed.weights.is_some() {
            ", rational"
        } else {
            ""
        },
        if fixed.trim_loops.is_empty() {
            String::new()
        } else {
            format!(", {} trim loops", fixed.trim_loops.len())
        }
    );
    Ok(())
}

fn export_command(a: ExportArgs) -> Result<(), String> {
    if let Some(scene) =
        (a.views.scene.as_ref()).filter(|p| p.extension().is_some_and(|e| e == "bpt"))
    {
        return export_patches(scene, &a.out);
    }
    if let Some(scene) =
        (a.views.scene.as_ref()).filter(|p| p.extension().is_some_and(|e| e == "scene"))
    {
        return export_traced(scene, &a.out);
    }
    if let Some(scene) =
        (a.views.scene.as_ref()).filter(|p| p.extension().is_some_and(|e| e == "meta"))
    {
        return export_metaballs(scene, &a.out);
    }
    if a.views.demo {
        return Err("export takes an OBJ scene (the demo is already built in)".into());
    }
    let (mut spec, cams, _) = a.views.resolve()?;
    if spec.instances.len() > 1 {
        return Err(format!(
            "export writes one mesh, and this scene is placed in {} chunks (coordinates beyond ±{} units or more than 65535 vertices): see docs/large-worlds.md for building such a world on firmware",
            spec.instances.len(),
            scanline3d::scene::MAX_MODEL_COORD
        ));
    }
    let bsp = if a.bsp {
        let b = scanline3d_sim::bsp::build(&spec.instances[0].mesh)?;
        spec.instances[0].mesh = b.mesh.clone();
        Some(b)
    } else {
        None
    };
    let (w, h) = a.views.size;
    let analysis = analyze::analyze(&spec, &cams, w, h)?;
    let command = export_command_line();
    let export = scanline3d_sim::export::Export {
        mesh: &spec.instances[0].mesh,
        analysis: &analysis,
        views: &cams,
        light: spec.light,
        cull_back_faces: spec.cull_back_faces,
        margin_percent: a.views.margin,
        normals: a.normals,
        command,
        bsp: bsp.as_ref(),
        bake_light: a.bake_light.then(|| {
            a.bake_preset
                .map_or(scanline3d_sim::scene::SetupArith::Precise, |p| p.arith())
        }),
    };
    let source = export.source()?;
    let source = scanline3d_sim::export::rustfmt(&source).unwrap_or_else(|| {
        let _ = writeln!(
            std::io::stderr(),
            "sim: rustfmt not found or failed: {} is valid but not formatted",
            a.out.display()
        );
        source
    });
    std::fs::write(&a.out, source).map_err(|e| format!("{}: {e}", a.out.display()))?;
    say!(
        "wrote {} ({} vertices, {} triangles, TRIS = {}, ACTIVE = {}, clipping {})",
        a.out.display(),
        analysis.vertices,
        analysis.triangles,
        analysis.triangle_capacity(a.views.margin),
        analysis.active_capacity(a.views.margin),
        if analysis.views_clipping > 0 {
            "needed"
        } else {
            "never needed"
        }
    );
    Ok(())
}

/// The scene of an OBJ file seen with `v`, culling decided for that view, and the loaded file.
fn spec_from(path: &Path, v: &View) -> Result<(SceneSpec, Loaded), String> {
    let loaded = Loaded::load(path, v.faces.orient)?;
    let camera = CameraSpec {
        eye: v.eye,
        target: v.target,
        up: v.up,
        fovy: v.fov,
        near: v.near,
        far: v.far,
    };
    // Validate the camera with the library's rules (one clear message instead of a bad image).
    camera.fixed()?;
    let (w, h) = v.size;
    let decision = loaded.culling(v.faces.culling(), &[camera], w as f64 / h as f64);
    let spec = SceneSpec {
        instances: loaded.instances.clone(),
        camera,
        light: LightSpec::default(),
        cull_back_faces: decision.cull,
    };
    Ok((spec, loaded))
}

/// Says on standard error when a frame shows nothing at all.
fn report_empty(ids: &[i32], camera: &CameraSpec) {
    if ids.iter().all(|&i| i < 0) {
        let _ = writeln!(
            std::io::stderr(),
            "sim: nothing drawn: no surface between near {} and far {} in view of the eye at {:?} (inside or beyond everything?)",
            camera.near, camera.far, camera.eye
        );
    }
}

fn render(a: RenderArgs) -> Result<(), String> {
    if a.scene.extension().is_some_and(|e| e == "meta") {
        let v = a.view;
        return metaball_command(MetaballArgs {
            scene: a.scene,
            frame: a.frame.unwrap_or(0),
            method: a.method.unwrap_or(MetaMethod::Raycast),
            eye: v.eye,
            target: v.target,
            up: v.up,
            fov: v.fov,
            near: v.near,
            far: v.far,
            size: v.size,
            out: a.out,
            ids: a.ids,
            depth: a.depth,
            stats: a.stats,
            beside: a.beside,
        });
    }
    if a.frame.is_some() || a.method.is_some() || a.beside.is_some() {
        return Err("--frame, --method and --beside are for .meta scenes".into());
    }
    if a.scene
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("bpt"))
    {
        return render_patches(a);
    }
    let (spec, loaded) = spec_from(&a.scene, &a.view)?;
    let (w, h) = a.view.size;
    let renderer = match (a.renderer, a.view.algorithm) {
        (Renderer::Reference, _) | (_, Method::Raycast) => None,
        (Renderer::Fixed, Method::Fixed(algorithm)) => Some(algorithm),
    };
    let (mut image, stats_json) = match renderer {
        Some(algorithm) => {
            let r = match a.view.preset {
                Some(p) => spec.render_fixed_preset(w, h, p, algorithm)?,
                None => spec.render_fixed_with(w, h, a.view.sub_pixel_bits, algorithm)?,
            };
            let s = r.stats;
            let preset = a
                .view
                .preset
                .map_or("null".to_string(), |p| format!("\"{p}\""));
            let arithmetic = a
                .view
                .preset
                .map_or(SetupArith::Precise, |p| p.arith())
                .name();
            let json = format!(
                "{{\"renderer\": \"fixed\", \"algorithm\": \"{algorithm}\", \"preset\": {preset}, \"arithmetic\": \"{arithmetic}\", \"sub_pixel_bits\": {}, \"width\": {w}, \"height\": {h}, \"triangles_in\": {}, \"culled\": {}, \"clipped\": {}, \"rejected\": {}, \"drawn\": {}, \"spans\": {}, \"fragments\": {}, \"pixels_written\": {}, \"peak_active\": {}, \"dropped\": {}}}\n",
                a.view.sub_bits(), s.triangles_in, s.culled, s.clipped, s.rejected, s.activated, s.spans, s.fragments, s.pixels_written, s.peak_active, s.dropped
            );
            (r.image, json)
        }
        None => {
            let start = std::time::Instant::now();
            let img = spec.reference()?.render(w, h);
            let covered = img.ids.iter().filter(|&&i| i >= 0).count();
            let json = format!(
                "{{\"renderer\": \"reference\", \"width\": {w}, \"height\": {h}, \"triangles_in\": {}, \"covered_pixels\": {covered}, \"seconds\": {:.3}}}\n",
                spec.instances.iter().map(|i| i.mesh.triangles.len()).sum::<usize>(),
                start.elapsed().as_secs_f64()
            );
            (img, json)
        }
    };
    report_empty(&image.ids, &spec.camera);
    loaded.file_ids(&mut image.ids);
    write_outputs(
        &a.out,
        &image,
        a.ids.as_deref(),
        a.depth.as_deref(),
        a.stats.as_deref(),
        &stats_json,
    )
}

/// `sim render MODEL.bpt`: a Bezier patch model (docs/patches.md); ids are patch indices in
/// file order. Only the camera and size options of `View` apply, and `--cull` to the fixed
/// renderer (two-sided without it).
fn render_patches(a: RenderArgs) -> Result<(), String> {
    use scanline3d_sim::patch::{fixed, parse, render::Reference};
    let model = parse::load(&a.scene)?;
    let v = &a.view;
    let camera = CameraSpec {
        eye: v.eye,
        target: v.target,
        up: v.up,
        fovy: v.fov,
        near: v.near,
        far: v.far,
    };
    camera.fixed()?;
    let (w, h) = v.size;
    let (image, stats_json) = match a.renderer {
        Renderer::Fixed => {
            let shading = if a.gouraud {
                fixed::PatchShading::Gouraud
            } else {
                fixed::PatchShading::Flat
            };
            let light = LightSpec::default();
            let r = fixed::render_fixed(
                &model,
                &camera,
                &light,
                (w, h),
                a.tolerance,
                v.faces.cull,
                shading,
            )?;
            let s = r.stats;
            let f = s.frame;
            let json = format!(
                "{{\"renderer\": \"fixed\", \"patches\": {}, \"tolerance\": {}, \"width\": {w}, \"height\": {h}, \"triangles\": {}, \"patches_culled\": {}, \"pieces\": {}, \"pieces_culled\": {}, \"overflows\": {}, \"capped\": {}, \"late\": {}, \"trim_cut\": {}, \"trim_overflows\": {}, \"culled\": {}, \"clipped\": {}, \"drawn\": {}, \"fragments\": {}, \"peak_active\": {}, \"dropped\": {}}}\n",
                model.patches.len(), a.tolerance, f.triangles_in, s.patches_culled, s.pieces, s.pieces_culled, s.overflows, s.capped, s.late, s.trim_cut, s.trim_overflows, f.culled, f.clipped, f.activated, f.fragments, f.peak_active, f.dropped
            );
            (r.image, json)
        }
        Renderer::Reference => {
            let start = std::time::Instant::now();
            let patches = model.patches.len();
            let reference = Reference::new(
                model,
                camera.reference()?,
                LightSpec::default().reference()?,
            );
            let (image, s) = reference.render(w, h);
            let json = format!(
                "{{\"renderer\": \"reference\", \"patches\": {patches}, \"width\": {w}, \"height\": {h}, \"hits\": {}, \"clip_rounds_mean\": {:.3}, \"clip_rounds_max\": {}, \"rays_split\": {}, \"capped\": {}, \"seconds\": {:.3}}}\n",
                s.hits,
                s.mean_rounds(),
                s.max_rounds,
                s.rays_split,
                s.capped,
                start.elapsed().as_secs_f64()
            );
            (image, json)
        }
    };
    report_empty(&image.ids, &camera);
    write_outputs(
        &a.out,
        &image,
        a.ids.as_deref(),
        a.depth.as_deref(),
        a.stats.as_deref(),
        &stats_json,
    )
}

/// `sim trace --compare-accel`: traces with every acceleration structure, checks the images
/// agree and prints the intersection work per ray of each.
fn compare_structures(
    traced: &scanline3d_sim::trace::scene::TracedScene,
    camera: &CameraSpec,
    (w, h): (usize, usize),
    limits: scanline3d_sim::trace::whitted::Limits,
) -> Result<(), String> {
    use scanline3d_sim::trace::{accel::Structure, render::render};
    say!("structure  object tests/ray  box tests/ray  cells/ray  (per traced or shadow ray)");
    let brute = render(traced, camera, w, h, limits, Structure::None)?;
    let base = brute.stats.tests_per_ray();
    for s in Structure::ALL {
        let other = render(traced, camera, w, h, limits, s)?;
        let st = &other.stats;
        let rays = (st.traced_rays() + st.shadow).max(1) as f64;
        let boxes = (st.rays.box_tests + st.shadows.box_tests) as f64 / rays;
        let cells = (st.rays.cells + st.shadows.cells) as f64 / rays;
        let per_ray = st.tests_per_ray();
        say!(
            "{:<9}  {per_ray:>15.2}  {boxes:>13.2}  {cells:>9.2}  ({:.1}x fewer tests)",
            s.name(),
            base / per_ray.max(f64::MIN_POSITIVE)
        );
        if (&other.ids, &other.color, &other.shadow) != (&brute.ids, &brute.color, &brute.shadow) {
            return Err(format!(
                "{} gives a different image than brute force",
                s.name()
            ));
        }
    }
    say!("every structure gives the same colour, id and shadow images");
    Ok(())
}

fn trace(a: TraceArgs) -> Result<(), String> {
    use scanline3d_sim::trace::{accel::Structure, render, scene::TracedScene, whitted::Limits};
    let traced = TracedScene::load(&a.scene)?;
    let camera = CameraSpec {
        eye: a.eye,
        target: a.target,
        up: a.up,
        fovy: a.fov,
        near: a.near,
        far: a.far,
    };
    let limits = Limits {
        max_depth: a.max_depth,
        threshold: a.threshold,
    };
    if a.compare_accel {
        compare_structures(&traced, &camera, a.size, limits)?;
    }
    let structure = match a.accel {
        TraceAccel::None => Structure::None,
        TraceAccel::Bvh => Structure::Bvh,
        TraceAccel::Grid => Structure::Grid,
        TraceAccel::Both => Structure::Both,
    };
    let (w, h) = a.size;
    let (color, ids, depth, shadow, summary) = match a.renderer {
        TraceRenderer::Reference => {
            let image = render::render(&traced, &camera, w, h, limits, structure)?;
            let s = &image.stats;
            let summary = format!(
                "{} objects, {} lights; rays: {} primary, {} secondary, {} shadow; tests per ray ({}): {:.2}; ray tree cut by depth {}, by weight {}; {} total internal reflections",
                traced.objects.len(),
                traced.lights.len(),
                s.primary,
                s.traced_rays() - s.primary,
                s.shadow,
                structure.name(),
                s.tests_per_ray(),
                s.cut_by_depth,
                s.cut_by_weight,
                s.total_internal_reflections
            );
            (image.color, image.ids, image.depth, image.shadow, summary)
        }
        TraceRenderer::Fixed | TraceRenderer::Hybrid => {
            use scanline3d_sim::trace::fixed;
            let hybrid = a.renderer == TraceRenderer::Hybrid;
            let scene = fixed::FixedScene::new(&traced)?;
            let f = fixed::render(
                &scene,
                &camera,
                w,
                h,
                fixed::options(a.max_depth, a.threshold)?,
                match a.accel {
                    TraceAccel::None => fixed::Accel::None,
                    TraceAccel::Bvh | TraceAccel::Both => fixed::Accel::Bvh,
                    TraceAccel::Grid => fixed::Accel::Grid,
                },
                hybrid,
            )?;
            let s = &f.stats;
            let summary = format!(
                "{} objects, {} lights; fixed-point tracer{}: rays: {} primary, {} secondary, {} shadow ({} answered by the shadow cache, {} by the row's shadow windows); tests per ray ({:?}): {:.2} objects, {:.2} boxes, {:.2} grid cells; {} rays dropped (stack full); {} rows fell back to the pure primary search",
                traced.objects.len(),
                traced.lights.len(),
                if hybrid { " (hybrid)" } else { "" },
                s.primary_rays,
                s.secondary_rays,
                s.shadow_rays,
                s.shadow_cache_hits,
                s.window_clear_rays,
                a.accel,
                f64::from(s.intersection_tests) / f64::from(s.rays().max(1)),
                f64::from(s.box_tests) / f64::from(s.rays().max(1)),
                f64::from(s.grid_cells) / f64::from(s.rays().max(1)),
                s.dropped_rays,
                s.fallback_rows
            );
            (f.colour, f.ids, f.depth, f.shadow, summary)
        }
    };
    scene::write_png(&a.out, w, h, &color)?;
    say!("wrote {}", a.out.display());
    if let Some(p) = &a.ids {
        scene::write_ids(p, &ids)?;
        say!("wrote {}", p.display());
    }
    if let Some(p) = &a.depth {
        scene::write_depth(p, &depth)?;
        say!("wrote {}", p.display());
    }
    if let Some(p) = &a.shadow {
        std::fs::write(p, &shadow).map_err(|e| format!("{}: {e}", p.display()))?;
        say!("wrote {}", p.display());
    }
    say!("{summary}");
    Ok(())
}

fn metaball_command(a: MetaballArgs) -> Result<(), String> {
    use scanline3d_sim::metaball::polygonized::render_polygonized;
    use scanline3d_sim::metaball::{
        compare::render_fixed, fixed::FixedMeta, reference::Reference, MetaScene,
    };
    let scene = MetaScene::load(&a.scene)?;
    FixedMeta::new(&scene).map_err(|e| format!("{}: {e}", a.scene.display()))?;
    let camera = CameraSpec {
        eye: a.eye,
        target: a.target,
        up: a.up,
        fovy: a.fov,
        near: a.near,
        far: a.far,
    };
    let (w, h) = a.size;
    let start = std::time::Instant::now();
    let (image, json) = match a.method {
        MetaMethod::Raycast => {
            let (image, s) = render_fixed(&scene, a.frame, &camera, w, h)?;
            let json = format!(
                "{{\"renderer\": \"raycast\", \"frame\": {}, \"width\": {w}, \"height\": {h}, \"hits\": {}, \"steps\": {}, \"max_steps\": {}, \"capped\": {}}}\n",
                a.frame, s.hits, s.steps, s.max_steps, s.capped
            );
            (image, json)
        }
        MetaMethod::Polygonize(cells) => {
            let p = render_polygonized(&scene, a.frame, &camera, (w, h), cells)?;
            let json = format!(
                "{{\"renderer\": \"polygonize\", \"cells\": {cells}, \"frame\": {}, \"width\": {w}, \"height\": {h}, \"vertices\": {}, \"triangles\": {}, \"culled\": {}, \"pixels_written\": {}}}\n",
                a.frame, p.mesh.vertices, p.mesh.triangles, p.frame.culled, p.frame.pixels_written
            );
            (p.image, json)
        }
        MetaMethod::Reference => {
            let reference = Reference::new(&scene, a.frame, camera.reference()?)?;
            let (image, iterations) = reference.render(w, h);
            let mean = iterations.iter().map(|&i| f64::from(i)).sum::<f64>()
                / iterations.len().max(1) as f64;
            let json = format!(
                "{{\"renderer\": \"reference\", \"frame\": {}, \"width\": {w}, \"height\": {h}, \"hits\": {}, \"clipping_iterations_mean\": {mean:.3}, \"clipping_iterations_max\": {}, \"seconds\": {:.3}}}\n",
                a.frame,
                image.ids.iter().filter(|&&i| i >= 0).count(),
                iterations.iter().max().copied().unwrap_or(0),
                start.elapsed().as_secs_f64()
            );
            (image, json)
        }
    };
    if let Some(path) = &a.beside {
        let reference = Reference::new(&scene, a.frame, camera.reference()?)?;
        let (caster, expected) = match a.method {
            MetaMethod::Raycast | MetaMethod::Polygonize(_) => {
                (image.clone(), reference.render(w, h).0)
            }
            MetaMethod::Reference => (
                render_fixed(&scene, a.frame, &camera, w, h)?.0,
                image.clone(),
            ),
        };
        side_by_side(path, &caster, &expected)?;
        say!("wrote {}", path.display());
        say!(
            "{}",
            scanline3d_sim::metaball::compare::compare(&caster, &expected, &reference)
        );
    }
    write_outputs(
        &a.out,
        &image,
        a.ids.as_deref(),
        a.depth.as_deref(),
        a.stats.as_deref(),
        &json,
    )
}

/// Writes a rendered image as PNG, and optionally its id and depth images and its statistics
/// (`-` for standard output), saying what it wrote.
fn write_outputs(
    out: &Path,
    image: &Image,
    ids: Option<&Path>,
    depth: Option<&Path>,
    stats: Option<&Path>,
    stats_json: &str,
) -> Result<(), String> {
    scene::write_png(out, image.width, image.height, &image.color)?;
    say!("wrote {}", out.display());
    if let Some(p) = ids {
        scene::write_ids(p, &image.ids)?;
        say!("wrote {}", p.display());
    }
    if let Some(p) = depth {
        scene::write_depth(p, &image.depth)?;
        say!("wrote {}", p.display());
    }
    match stats {
        Some(p) if p.as_os_str() == "-" => {
            let _ = std::io::stdout().write_all(stats_json.as_bytes());
        }
        Some(p) => {
            std::fs::write(p, stats_json).map_err(|e| format!("{}: {e}", p.display()))?;
            say!("wrote {}", p.display());
        }
        None => {}
    }
    Ok(())
}

/// fixed | reference | mismatch map (red: real, yellow: explained) as one PNG.
fn side_by_side(path: &Path, fixed: &Image, reference: &Image) -> Result<(), String> {
    let (w, h) = (fixed.width, fixed.height);
    let mut out = vec![[255u8; 3]; (3 * w + 8) * h];
    let stride = 3 * w + 8;
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            out[y * stride + x] = fixed.color[i];
            out[y * stride + w + 4 + x] = reference.color[i];
            let grey = (reference.color[i].iter().map(|&c| c as u32).sum::<u32>() / 6) as u8;
            out[y * stride + 2 * w + 8 + x] = if fixed.ids[i] != reference.ids[i] {
                [255, 200, 0]
            } else {
                [grey; 3]
            };
        }
    }
    scene::write_png(path, stride, h, &out)
}

fn compare(a: CompareArgs) -> Result<(), String> {
    let (w, h) = a.view.size;
    if let Some(path) = &a.scene {
        let (spec, _) = spec_from(path, &a.view)?;
        let Method::Fixed(algorithm) = a.view.algorithm else {
            return Err("raycast is the reference itself: choose a fixed-point --algorithm".into());
        };
        let (m, fixed, reference) = match a.view.preset {
            Some(p) => accuracy_preset(&spec, w, h, p, algorithm)?,
            None => accuracy_with(&spec, w, h, a.view.sub_pixel_bits, algorithm)?,
        };
        let preset = a
            .view
            .preset
            .map_or(String::new(), |p| format!(" (preset {p})"));
        say!(
            "{} at {w}x{h}, {} sub-pixel bits{preset}, {algorithm}, fixed-point vs f64 reference:",
            path.display(),
            a.view.sub_bits()
        );
        report_empty(&reference.ids, &spec.camera);
        say!("{m}");
        if let Some(p) = &a.side_by_side {
            side_by_side(p, &fixed.image, &reference)?;
            say!("wrote {}", p.display());
        }
        return Ok(());
    }
    let [a_ids, a_depth, b_ids, b_depth] = a.files.as_slice() else {
        return Err("compare needs A.ids A.depth B.ids B.depth (or --scene SCENE.obj)".into());
    };
    let n = w * h;
    let load = |ids: &Path, depth: &Path| -> Result<Image, String> {
        Ok(Image {
            width: w,
            height: h,
            ids: scene::read_ids(ids, n)?,
            depth: scene::read_depth(depth, n)?,
            color: vec![[0; 3]; n],
        })
    };
    let (ia, ib) = (load(a_ids, a_depth)?, load(b_ids, b_depth)?);
    let m = metrics::compare_images(&ia, &ib);
    say!(
        "{w}x{h} pixels: {} id mismatches ({:.3} %), {} coverage mismatches",
        m.id_mismatches,
        m.id_mismatch_percent(),
        m.coverage_mismatches
    );
    say!(
        "depth error where ids agree: max {:.3e}, mean {:.3e} (relative)",
        m.depth_max_rel,
        m.depth_mean_rel
    );
    say!("(classifying mismatches needs the scene: use --scene SCENE.obj with the same camera)");
    Ok(())
}

fn write_corpus(out: &Path) -> Result<(), String> {
    std::fs::create_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
    for s in corpus::all() {
        let path = out.join(format!("{}.obj", s.name));
        std::fs::write(&path, s.mesh.to_obj()).map_err(|e| format!("{}: {e}", path.display()))?;
        say!(
            "{} ({} triangles): {}",
            path.display(),
            s.mesh.triangles.len(),
            s.about
        );
        for c in &s.cameras {
            let v = |p: [f64; 3]| format!("{},{},{}", p[0], p[1], p[2]);
            say!(
                "  sim render {} --eye {} --target {} --up {} --fov {} --near {} --far {}{}",
                path.display(),
                v(c.eye),
                v(c.target),
                v(c.up),
                c.fovy,
                c.near,
                c.far,
                if s.cull_back_faces { "" } else { " --no-cull" }
            );
        }
    }
    Ok(())
}

/// The default job: the demo frame, as the firmware renders it, and its accuracy.
fn demo(out: &Path) -> Result<(), String> {
    let spec = SceneSpec::demo(0)?;
    let (w, h) = (scanline3d_demo::WIDTH, scanline3d_demo::HEIGHT);
    let (m, fixed, _) = accuracy(&spec, w, h, 4)?;
    scene::write_png(out, w, h, &fixed.image.color)?;
    let s = fixed.stats;
    say!(
        "wrote {} ({w}x{h}, demo frame 0, flat shading, 4 sub-pixel bits)",
        out.display()
    );
    say!(
        "triangles: {} in, {} culled, {} clipped, {} rejected, {} drawn (peak {} active per row)",
        s.triangles_in,
        s.culled,
        s.clipped,
        s.rejected,
        s.activated,
        s.peak_active
    );
    say!(
        "pixels: {} spans, {} fragments, {} written",
        s.spans,
        s.fragments,
        s.pixels_written
    );
    say!(
        "against the f64 reference (position bound at depth 4: {:.4} px):",
        ErrorBound {
            sub_bits: 4,
            max_model_coord: spec.max_model_coord(),
            focal_px: spec.reference()?.camera.focal_px(h),
            arithmetic: Default::default(),
        }
        .position_px(4.0)
    );
    say!("{m}");
    Ok(())
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e)
            if matches!(
                e.kind(),
                clap::error::ErrorKind::DisplayHelp | clap::error::ErrorKind::DisplayVersion
            ) =>
        {
            let _ = e.print();
            return ExitCode::SUCCESS;
        }
        Err(e) => {
            // One line naming the problem (clap's first line), status 2.
            let text = e.render().to_string();
            let line = text
                .lines()
                .next()
                .unwrap_or("invalid arguments")
                .trim_start_matches("error: ");
            let _ = writeln!(std::io::stderr(), "sim: {line}");
            return ExitCode::from(2);
        }
    };
    let result = match cli.command {
        None => demo(&cli.out),
        Some(Command::Render(a)) => render(a),
        Some(Command::Compare(a)) => compare(a),
        Some(Command::Analyze(a)) => analyze_command(a),
        Some(Command::Export(a)) => export_command(a),
        Some(Command::Metaball(a)) => metaball_command(a),
        Some(Command::Trace(a)) => trace(a),
        Some(Command::Corpus { out }) => write_corpus(&out),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            let _ = writeln!(std::io::stderr(), "sim: {e}");
            ExitCode::from(2)
        }
    }
}
