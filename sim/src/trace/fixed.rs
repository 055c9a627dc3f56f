//! The library's fixed-point tracer on the host: conversion of a [`TracedScene`] into the
//! library's types, frames rendered into id / depth / shadow / colour images, and `sim export`
//! of a traced scene as `static` Rust data for firmware.
//!
//! The conversion goes through the library's validating constructors (so the host and the
//! firmware trace the same bits), rounding every f64 to the nearest I16F16.

use super::scene::{LightKind as SrcLight, Shape as SrcShape, Surface, TracedScene};
use crate::scene::CameraSpec;
use embedded_graphics::pixelcolor::Rgb565;
use fixed::types::I16F16;
use scanline3d::sink::HashSink;
use scanline3d::trace::bvh::{self, BvhNode};
use scanline3d::trace::grid::{self, GridShape};
use scanline3d::trace::shape::{AaBox, Ellipsoid, Facet, Frustum};
use scanline3d::trace::{
    Checker, Colour, Light, LightKind, Material, Object, PixelTrace, Plane, Polygon, Scene,
    ScreenBound, ShadowCache, ShadowCandidate, Shape, Sphere, TraceCamera, TraceOptions,
    TraceStats, Tracer, Triangle, Vec3,
};

/// Ray-stack capacity of the host's fixed tracer: room for `--max-depth` up to 31.
pub const STACK: usize = 32;
/// The deepest `--max-depth` the fixed tracer takes (`STACK − 1`: the stack never overflows).
pub const MAX_DEPTH: u8 = (STACK - 1) as u8;

fn fix(v: f64, what: &str) -> Result<I16F16, String> {
    I16F16::checked_from_num(v).ok_or_else(|| format!("{what} {v} does not fit I16F16"))
}

fn fix3(v: [f64; 3], what: &str) -> Result<Vec3, String> {
    Ok(Vec3 {
        x: fix(v[0], what)?,
        y: fix(v[1], what)?,
        z: fix(v[2], what)?,
    })
}

/// One object before its borrows are made: polygons refer to their vertex list by index.
#[derive(Clone, Debug)]
enum Entry {
    /// A primitive that borrows nothing.
    Owned(Shape<'static>),
    /// A polygon: the index of its vertex list.
    Polygon(usize),
}

/// A traced scene in the library's types, owning what the library's [`Scene`] borrows.
#[derive(Clone, Debug)]
pub struct FixedScene {
    polygons: Vec<Vec<Vec3>>,
    entries: Vec<(Entry, u16)>,
    /// Materials in file order.
    pub materials: Vec<Material>,
    /// Checker textures in file order (an object's material index `materials.len() + k`
    /// names checker k).
    pub checkers: Vec<Checker>,
    /// Lights in file order.
    pub lights: Vec<Light>,
    /// Background colour.
    pub background: Colour,
    /// Ambient level.
    pub ambient: I16F16,
    /// The bounding-volume hierarchy the library built over the objects: nodes, items and how
    /// many items are in the tree.
    pub bvh: (Vec<BvhNode>, Vec<u32>, usize),
    /// The uniform grid the library built over the objects.
    pub grid: GridParts,
}

/// A uniform grid's parts: shape, cell starts, cell items, unbounded objects.
pub type GridParts = (GridShape, Vec<u32>, Vec<u32>, Vec<u32>);

/// Which acceleration structure the fixed tracer uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Accel {
    /// Every ray tests every object.
    None,
    /// The bounding-volume hierarchy.
    Bvh,
    /// The uniform grid (3D-DDA).
    Grid,
}

impl FixedScene {
    /// Converts `scene`; an object the fixed tracer cannot hold is an error naming its line.
    pub fn new(scene: &TracedScene) -> Result<FixedScene, String> {
        let colour = |c: [f64; 3], what: &str| -> Result<Colour, String> {
            Colour::new([fix(c[0], what)?, fix(c[1], what)?, fix(c[2], what)?])
                .map_err(|e| format!("{what}: {e}"))
        };
        let materials = scene
            .materials
            .iter()
            .map(|m| {
                let what = format!("material {}", m.name);
                Material::new(
                    colour(m.color, &what)?,
                    [
                        fix(m.ka, &what)?,
                        fix(m.kd, &what)?,
                        fix(m.kr, &what)?,
                        fix(m.kt, &what)?,
                    ],
                    fix(m.ior, &what)?,
                )
                .map_err(|e| format!("{what}: {e}"))
            })
            .collect::<Result<Vec<_>, String>>()?;
        let checkers = scene
            .checkers
            .iter()
            .map(|c| {
                let what = format!("line {}: checker {}", c.line, c.name);
                let log2 = c.size.log2();
                let index = |m: usize| {
                    u16::try_from(m).map_err(|_| format!("{what}: too many materials"))
                };
                if log2.fract() != 0.0 || !(-8.0..=8.0).contains(&log2) {
                    return Err(format!(
                        "{what}: size {} is not a power of two from 2^-8 to 2^8 (the fixed tracer's cells are shifts)",
                        c.size
                    ));
                }
                Checker::new(index(c.a)?, index(c.b)?, log2 as i8)
                    .map_err(|e| format!("{what}: {e}"))
            })
            .collect::<Result<Vec<_>, String>>()?;
        let lights = scene
            .lights
            .iter()
            .enumerate()
            .map(|(k, l)| {
                let what = format!("light {k}");
                let i = fix(l.intensity, &what)?;
                match l.kind {
                    SrcLight::Point(p) => Light::point(fix3(p, &what)?, i),
                    SrcLight::Directional(d) => Light::directional(fix3(d, &what)?, i),
                }
                .map_err(|e| format!("{what}: {e}"))
            })
            .collect::<Result<Vec<_>, String>>()?;
        let mut polygons = Vec::new();
        let mut entries = Vec::new();
        for o in &scene.objects {
            let what = format!("line {}: {}", o.line, o.shape.kind());
            let err = |e: scanline3d::trace::ShapeError| format!("{what}: {e}");
            let p = |v: &[f64; 3]| fix3(*v, &what);
            let r = |v: &f64| fix(*v, &what);
            let entry = match &o.shape {
                SrcShape::Sphere { centre, radius } => Entry::Owned(Shape::Sphere(
                    Sphere::new(p(centre)?, r(radius)?).map_err(err)?,
                )),
                SrcShape::Plane { normal, d } => {
                    Entry::Owned(Shape::Plane(Plane::new(p(normal)?, r(d)?).map_err(err)?))
                }
                SrcShape::Box { min, max } => {
                    Entry::Owned(Shape::Box(AaBox::new(p(min)?, p(max)?).map_err(err)?))
                }
                SrcShape::Cylinder { p0, p1, radius } => Entry::Owned(Shape::Frustum(
                    Frustum::cylinder(p(p0)?, p(p1)?, r(radius)?).map_err(err)?,
                )),
                SrcShape::Cone { p0, r0, p1, r1 } => Entry::Owned(Shape::Frustum(
                    Frustum::new(p(p0)?, r(r0)?, p(p1)?, r(r1)?).map_err(err)?,
                )),
                SrcShape::Ellipsoid { centre, radii } => Entry::Owned(Shape::Ellipsoid(
                    Ellipsoid::new(p(centre)?, p(radii)?).map_err(err)?,
                )),
                SrcShape::Polygon { vertices, .. } => {
                    let v = vertices.iter().map(p).collect::<Result<Vec<_>, String>>()?;
                    Polygon::new(&v).map_err(err)?;
                    polygons.push(v);
                    Entry::Polygon(polygons.len() - 1)
                }
                SrcShape::Triangle { corners } => Entry::Owned(Shape::Triangle(
                    Triangle::new([p(&corners[0])?, p(&corners[1])?, p(&corners[2])?])
                        .map_err(err)?,
                )),
            };
            let surface = match o.surface {
                Surface::Material(m) => m,
                Surface::Checker(k) => scene.materials.len() + k,
            };
            let material =
                u16::try_from(surface).map_err(|_| format!("{what}: too many materials"))?;
            entries.push((entry, material));
        }
        let mut fixed = FixedScene {
            polygons,
            entries,
            materials,
            checkers,
            lights,
            background: colour(scene.background, "background")?,
            ambient: fix(scene.ambient, "ambient")?,
            bvh: (Vec::new(), Vec::new(), 0),
            grid: (
                GridShape {
                    min: Vec3::ZERO,
                    cell: I16F16::ONE,
                    dims: [1; 3],
                },
                Vec::new(),
                Vec::new(),
                Vec::new(),
            ),
        };
        let objects = fixed.objects();
        let empty = BvhNode {
            min: Vec3::ZERO,
            max: Vec3::ZERO,
            index: 0,
            count: 0,
            axis: 0,
        };
        let mut nodes = vec![empty; 2 * objects.len()];
        let mut items = vec![0; objects.len()];
        let (used, _, bounded) =
            bvh::build(&objects, &mut nodes, &mut items).map_err(|e| e.to_string())?;
        nodes.truncate(used);
        let grid = grid_over(&objects)?;
        drop(objects);
        fixed.bvh = (nodes, items, bounded);
        fixed.grid = grid;
        Ok(fixed)
    }

    /// The objects, borrowing this scene's polygon vertices.
    pub fn objects(&self) -> Vec<Object<'_>> {
        self.entries
            .iter()
            .map(|(e, material)| Object {
                shape: match e {
                    Entry::Owned(shape) => *shape,
                    Entry::Polygon(i) => Shape::Polygon(
                        Polygon::new(&self.polygons[*i]).expect("validated in FixedScene::new"),
                    ),
                },
                material: *material,
            })
            .collect()
    }

    /// Runs `f` with the library scene and the acceleration structure `accel`.
    pub fn with_scene<R>(
        &self,
        accel: Accel,
        f: impl FnOnce(&Scene<'_>) -> R,
    ) -> Result<R, String> {
        let objects = self.objects();
        let mut scene = Scene::textured(
            &objects,
            &self.materials,
            &self.checkers,
            &self.lights,
            self.background,
            self.ambient,
        )
        .map_err(|e| e.to_string())?;
        match accel {
            Accel::None => {}
            Accel::Bvh => {
                let (nodes, items, bounded) = &self.bvh;
                scene = scene
                    .with_bvh(nodes, items, *bounded)
                    .map_err(|e| e.to_string())?;
            }
            Accel::Grid => {
                let (shape, starts, items, unbounded) = &self.grid;
                scene = scene
                    .with_grid(*shape, starts, items, unbounded)
                    .map_err(|e| e.to_string())?;
            }
        }
        Ok(f(&scene))
    }
}

/// A grid of about 4 cubic cells per bounded object over their common box.
fn grid_over(objects: &[Object<'_>]) -> Result<GridParts, String> {
    let boxes: Vec<_> = objects
        .iter()
        .filter_map(|o| bvh::bounds(&o.shape))
        .collect();
    let (lo, hi) = boxes
        .iter()
        .fold(([f64::MAX; 3], [f64::MIN; 3]), |(lo, hi), (a, b)| {
            let (a, b) = (a.bits().map(f64::from), b.bits().map(f64::from));
            (
                [lo[0].min(a[0]), lo[1].min(a[1]), lo[2].min(a[2])],
                [hi[0].max(b[0]), hi[1].max(b[1]), hi[2].max(b[2])],
            )
        });
    let raw = |v: [f64; 3]| Vec3::from_bits(v[0] as i32, v[1] as i32, v[2] as i32);
    let (lo, hi) = if boxes.is_empty() {
        (Vec3::ZERO, Vec3::ZERO)
    } else {
        (raw(lo), raw(hi))
    };
    let extent = [hi.x - lo.x, hi.y - lo.y, hi.z - lo.z].map(|e| e.to_num::<f64>().max(1e-3));
    // Cell volume = box volume / (4 · objects), each axis at least 1/64 of the longest.
    let longest = extent.iter().cloned().fold(0.0, f64::max);
    let volume: f64 = extent.iter().map(|e| e.max(longest / 64.0)).product();
    let cell = (volume / (4.0 * boxes.len().max(1) as f64))
        .cbrt()
        .max(longest / 64.0);
    let shape = GridShape::around(lo, hi, fix(cell, "grid cell")?).map_err(|e| e.to_string())?;
    let mut starts = vec![0; shape.cells() + 1];
    let mut unbounded = vec![0; objects.len()];
    // Count first with room for every pair, then trim.
    let mut items = vec![0; boxes.len() * 64 + 64];
    let (used, planes) = loop {
        match grid::build(objects, shape, &mut starts, &mut items, &mut unbounded) {
            Ok(r) => break r,
            Err(scanline3d::trace::grid::GridError::Capacity) => items.resize(items.len() * 4, 0),
            Err(e) => return Err(e.to_string()),
        }
    };
    items.truncate(used);
    unbounded.truncate(planes);
    Ok((shape, starts, items, unbounded))
}

/// The library camera for `camera` at `w × h`.
pub fn camera(camera: &CameraSpec, w: usize, h: usize) -> Result<TraceCamera, String> {
    let size = |n: usize| u16::try_from(n).map_err(|_| format!("size {n} is too large"));
    TraceCamera::new(
        camera.eye,
        camera.target,
        camera.up,
        camera.fovy,
        camera.near,
        camera.far,
        size(w)?,
        size(h)?,
    )
    .map_err(|e| e.to_string())
}

/// The tracer's options, or an error for a depth limit the host's stack cannot hold or a
/// threshold that does not fit.
pub fn options(max_depth: u32, threshold: f64) -> Result<TraceOptions, String> {
    let max_depth = u8::try_from(max_depth)
        .ok()
        .filter(|d| *d <= MAX_DEPTH)
        .ok_or_else(|| {
            format!("--max-depth {max_depth} is above the fixed tracer's {MAX_DEPTH}")
        })?;
    Ok(TraceOptions {
        max_depth,
        threshold: fix(threshold, "--threshold")?,
    })
}

/// A frame of the fixed tracer, in the images of `sim trace`.
#[derive(Clone, Debug)]
pub struct FixedFrame {
    /// Width.
    pub width: usize,
    /// Height.
    pub height: usize,
    /// RGB8 colour, row-major from the top.
    pub colour: Vec<[u8; 3]>,
    /// Primary id, −1 = background.
    pub ids: Vec<i32>,
    /// Eye depth of the primary hit, +inf = background.
    pub depth: Vec<f32>,
    /// Bit k set when light k contributes nothing at the primary hit.
    pub shadow: Vec<u8>,
    /// Index of the material at the primary hit (a checker texture's cell's), −1 for
    /// background.
    pub materials: Vec<i32>,
    /// What the frame cost.
    pub stats: TraceStats,
}

/// Traces every pixel of `scene` from `cam` at `w × h`: the pure tracer, or with `hybrid` the
/// hybrid mode (primary visibility from the objects' screen bounds, see
/// [`scanline3d::trace::hybrid`]); secondary rays use `accel` either way.
pub fn render(
    scene: &FixedScene,
    cam: &CameraSpec,
    w: usize,
    h: usize,
    options: TraceOptions,
    accel: Accel,
    hybrid: bool,
) -> Result<FixedFrame, String> {
    let camera = camera(cam, w, h)?;
    let count = scene.entries.len();
    scene.with_scene(accel, |scene| {
        let tracer = Tracer::<STACK>::new(scene, &camera, options);
        let mut frame = FixedFrame {
            width: w,
            height: h,
            colour: Vec::with_capacity(w * h),
            ids: Vec::with_capacity(w * h),
            depth: Vec::with_capacity(w * h),
            shadow: Vec::with_capacity(w * h),
            materials: Vec::with_capacity(w * h),
            stats: TraceStats::default(),
        };
        let push = |frame: &mut FixedFrame, p: &PixelTrace| {
            frame
                .colour
                .push([p.colour.r(), p.colour.g(), p.colour.b()]);
            frame.ids.push(p.id.map_or(-1, |i| i as i32));
            frame
                .depth
                .push(p.id.map_or(f32::INFINITY, |_| p.depth.to_num::<f32>()));
            frame.shadow.push(p.shadow);
            frame.materials.push(p.material.map_or(-1, i32::from));
        };
        if hybrid {
            let mut bounds = vec![ScreenBound::default(); count];
            let mut active = vec![ScreenBound::default(); count];
            let mut shadow = vec![ShadowCandidate::default(); scene.lights.len() * count];
            let stats = tracer.hybrid_frame(
                &mut bounds,
                &mut active,
                &mut shadow,
                &mut frame,
                |frame, _, p| push(frame, p),
                |_, _, _| Ok::<(), std::convert::Infallible>(()),
            );
            frame.stats = match stats {
                Ok(stats) => stats,
                Err(never) => match never {},
            };
            return frame;
        }
        let mut cache = ShadowCache::new();
        let mut total = TraceStats::default();
        for y in 0..h as u16 {
            for x in 0..w as u16 {
                let (p, s) = tracer.trace_pixel_cached(x, y, &mut cache);
                total.add(&s);
                push(&mut frame, &p);
            }
        }
        total.rows = h as u16;
        frame.stats = total;
        frame
    })
}

/// The frame hash the firmware prints: the tracer's rows in [`Rgb565`] through a
/// [`HashSink`], and the frame's statistics (with the hierarchy, as the firmware), by the pure
/// tracer or with `hybrid` in hybrid mode.
pub fn frame_hash(
    scene: &FixedScene,
    cam: &CameraSpec,
    w: usize,
    h: usize,
    options: TraceOptions,
    hybrid: bool,
) -> Result<(u32, TraceStats), String> {
    let camera = camera(cam, w, h)?;
    let count = scene.entries.len();
    scene.with_scene(Accel::Bvh, |scene| {
        let mut row = vec![Rgb565::new(0, 0, 0); w];
        let mut sink = HashSink::new();
        let tracer = Tracer::<STACK>::new(scene, &camera, options);
        let stats = if hybrid {
            let mut bounds = vec![ScreenBound::default(); count];
            let mut active = vec![ScreenBound::default(); count];
            let mut shadow = vec![ShadowCandidate::default(); scene.lights.len() * count];
            tracer.render_hybrid(&mut bounds, &mut active, &mut shadow, &mut row, &mut sink)
        } else {
            tracer.render(&mut row, &mut sink)
        };
        stats
            .map(|stats| (sink.hash(), stats))
            .map_err(|e| format!("{e:?}"))
    })?
}

use embedded_graphics::pixelcolor::RgbColor;

fn bits(v: I16F16) -> String {
    format!("I16F16::from_bits({})", v.to_bits())
}

fn vec3(v: Vec3) -> String {
    let [x, y, z] = v.bits();
    format!("Vec3::from_bits({x}, {y}, {z})")
}

fn facet(f: &Facet) -> String {
    format!(
        "Facet {{ normal: {}, offset: {}, axis: {} }}",
        vec3(f.normal),
        bits(f.offset),
        f.axis
    )
}

fn colour(c: Colour) -> String {
    format!(
        "Colour([{}, {}, {}])",
        bits(c.0[0]),
        bits(c.0[1]),
        bits(c.0[2])
    )
}

/// Rust source with the scene as `static` data (`OBJECTS`, `MATERIALS`, `CHECKERS`, `LIGHTS`,
/// `BACKGROUND`, `AMBIENT`, and each polygon's vertices): every value is the raw bits the
/// library's constructors produced on the host, so nothing is parsed or validated again on the
/// target except by [`Scene::textured`].
pub fn export_source(scene: &FixedScene, command: &str) -> String {
    let mut s = format!(
        "//! A traced scene as static fixed-point data for `scanline3d::trace`.\n//!\n//! Generated by `{command}`; do not edit.\n\n\
         use fixed::types::I16F16;\n\
         #[allow(unused_imports)]\n\
         use scanline3d::trace::shape::{{AaBox, Ellipsoid, Facet, Frustum}};\n\
         #[allow(unused_imports)]\n\
         use scanline3d::trace::{{Checker, Colour, Light, LightKind, Material, Object, Plane, Polygon, Shape, Sphere, Triangle, Vec3}};\n\n"
    );
    for (i, p) in scene.polygons.iter().enumerate() {
        s += &format!(
            "/// Vertices of polygon {i}.\npub static POLYGON_{i}: [Vec3; {}] = [{}];\n",
            p.len(),
            p.iter().map(|v| vec3(*v)).collect::<Vec<_>>().join(", ")
        );
    }
    let objects = scene.objects();
    s += &format!(
        "\n/// The objects; an object's id is its index.\npub static OBJECTS: [Object<'static>; {}] = [\n",
        objects.len()
    );
    let mut polygon = 0;
    for o in &objects {
        let shape = match &o.shape {
            Shape::Sphere(sp) => format!(
                "Shape::Sphere(Sphere {{ centre: {}, radius: {}, radius2: fixed::types::I32F32::from_bits({}) }})",
                vec3(sp.centre),
                bits(sp.radius),
                sp.radius2.to_bits()
            ),
            Shape::Plane(p) => format!(
                "Shape::Plane(Plane {{ normal: {}, offset: {} }})",
                vec3(p.normal),
                bits(p.offset)
            ),
            Shape::Polygon(p) => {
                polygon += 1;
                format!(
                    "Shape::Polygon(Polygon {{ vertices: &POLYGON_{}, facet: {} }})",
                    polygon - 1,
                    facet(&p.facet)
                )
            }
            Shape::Triangle(t) => format!(
                "Shape::Triangle(Triangle {{ vertices: [{}], facet: {} }})",
                t.vertices.map(vec3).join(", "),
                facet(&t.facet)
            ),
                    Shape::Box(b) => format!(
                "Shape::Box(AaBox {{ min: {}, max: {} }})",
                vec3(b.min),
                vec3(b.max)
            ),
            Shape::Ellipsoid(e) => format!(
                "Shape::Ellipsoid(Ellipsoid {{ centre: {}, radii: {}, scale: {}, scale_radius: {} }})",
                vec3(e.centre),
                vec3(e.radii),
                vec3(e.scale),
                bits(e.scale_radius)
            ),
            Shape::Frustum(f) => format!(
                "Shape::Frustum(Frustum {{ base: {}, axis: {}, height: {}, r0: {}, r1: {}, slope: {} }})",
                vec3(f.base),
                vec3(f.axis),
                bits(f.height),
                bits(f.r0),
                bits(f.r1),
                bits(f.slope)
            ),
        };
        s += &format!(
            "    Object {{ shape: {shape}, material: {} }},\n",
            o.material
        );
    }
    s += "];\n\n";
    s += &format!(
        "/// Materials.\npub static MATERIALS: [Material; {}] = [\n",
        scene.materials.len()
    );
    for m in &scene.materials {
        s += &format!(
            "    Material {{ colour: {}, ka: {}, kd: {}, kr: {}, kt: {}, ior: {} }},\n",
            colour(m.colour),
            bits(m.ka),
            bits(m.kd),
            bits(m.kr),
            bits(m.kt),
            bits(m.ior)
        );
    }
    s += "];\n\n";
    s += &format!(
        "/// Checker textures; an object's material `MATERIALS.len() + k` is checker k.\npub static CHECKERS: [Checker; {}] = [\n",
        scene.checkers.len()
    );
    for c in &scene.checkers {
        s += &format!(
            "    Checker {{ a: {}, b: {}, shift: {} }},\n",
            c.a, c.b, c.shift
        );
    }
    s += "];\n\n";
    s += &format!(
        "/// Lights; light k is bit k of a shadow mask.\npub static LIGHTS: [Light; {}] = [\n",
        scene.lights.len()
    );
    for l in &scene.lights {
        let kind = match l.kind {
            LightKind::Point(p) => format!("LightKind::Point({})", vec3(p)),
            LightKind::Directional(d) => format!("LightKind::Directional({})", vec3(d)),
        };
        s += &format!(
            "    Light {{ kind: {kind}, intensity: {} }},\n",
            bits(l.intensity)
        );
    }
    s += "];\n\n";
    let (nodes, items, bounded) = &scene.bvh;
    s += &format!(
        "/// The bounding-volume hierarchy's nodes ([`scanline3d::trace::bvh`]).\npub static BVH_NODES: [scanline3d::trace::bvh::BvhNode; {}] = [\n",
        nodes.len()
    );
    for n in nodes {
        s += &format!(
            "    scanline3d::trace::bvh::BvhNode {{ min: {}, max: {}, index: {}, count: {}, axis: {} }},\n",
            vec3(n.min),
            vec3(n.max),
            n.index,
            n.count,
            n.axis
        );
    }
    s += &format!(
        "];\n\n/// Object ids in leaf order, then the unbounded objects'.\npub static BVH_ITEMS: [u32; {}] = {:?};\n\n/// How many of `BVH_ITEMS` are in the tree.\npub const BVH_BOUNDED: usize = {bounded};\n\n",
        items.len(),
        items
    );
    s += &format!(
        "/// Background colour.\npub const BACKGROUND: Colour = {};\n/// Ambient level.\npub const AMBIENT: I16F16 = {};\n",
        colour(scene.background),
        bits(scene.ambient)
    );
    s
}
