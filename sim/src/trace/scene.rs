//! The traced-scene description: the text format of issue 21, parsed into plain f64 data.
//!
//! Both tracers (the f64 reference here in `sim` and the library's fixed-point tracer, fed by
//! `sim export`) read this one structure; nothing else is shared but the camera convention.
//!
//! ```text
//! background R G B                      # 0..1
//! ambient I
//! light point X Y Z I | light directional DX DY DZ I   # D points from the surface to the light
//! material NAME R G B KA KD KR KT IOR    # IOR a number or air|water|glass|dense-glass|diamond
//! checker NAME MAT_A MAT_B SIZE          # a texture for plane and polygon lines
//! sphere CX CY CZ R MAT
//! plane NX NY NZ D MAT                   # points p with n·p + d = 0
//! box X0 Y0 Z0 X1 Y1 Z1 MAT              # axis-aligned, corners (min, max)
//! cylinder X0 Y0 Z0 X1 Y1 Z1 R MAT       # capped
//! cone X0 Y0 Z0 R0 X1 Y1 Z1 R1 MAT       # capped frustum; R1 = 0 is a cone
//! ellipsoid CX CY CZ RX RY RZ MAT
//! polygon MAT X Y Z X Y Z X Y Z ...      # planar, convex or concave (point-in-polygon test)
//! mesh FILE.obj MAT                      # triangles; path relative to the scene file
//! ```
//!
//! Tokens are whitespace-separated; `#` starts a comment. Ids are the index in
//! [`TracedScene::objects`]: one per primitive line in file order, one per triangle of a mesh
//! (in OBJ face order, polygons fan-triangulated). A material must be defined before a line
//! uses it. `background` and `ambient` default to 0 and may appear once each.
//!
//! A checker texture is a material name for `plane` and `polygon` lines (an error on any
//! other): at a hit point p, drop the coordinate of the surface normal's largest axis (the first
//! of equal ones, as the polygon test); the cell of the other two coordinates `(u, v)` is
//! `(floor(u / SIZE), floor(v / SIZE))`, and everything of the material there is `MAT_A`'s when
//! the cell's indices sum to an even number, `MAT_B`'s otherwise ([`TracedScene::material_at`]).
//!
//! Inside and outside: closed primitives and closed meshes have an inside; a plane's or a
//! polygon's outside is the side its normal points to. A polygon's normal follows its vertex
//! order (counter-clockwise seen from outside), as does a mesh triangle's.
//!
//! Bad input is a one-line error `FILE:LINE: what`, which `sim trace` prints with exit status 2.
//!
//! The camera is sim's [`CameraSpec`] (`look_at(eye, target, up)` + `perspective(fovy, W/H,
//! near, far)` as in DESIGN.md, pixels sampled at their centres); [`check_camera`] rejects a
//! degenerate one with a one-line error, and [`primary_ray`] is the ray through a pixel centre.

use crate::reference::{self, V3};
pub use crate::scene::CameraSpec;
use std::path::Path;

/// Most lights a traced scene may have: the shadow image has one bit per light in a byte.
pub const MAX_LIGHTS: usize = 8;
/// Indices of refraction a material may have (the lecture's table spans 1.00 to 2.42).
pub const IOR_RANGE: std::ops::RangeInclusive<f64> = 1.0..=4.0;
/// A polygon is planar when every vertex lies within this fraction of its extent of the plane.
pub const PLANARITY_TOLERANCE: f64 = 1e-6;

/// A traced scene: what the scene file says, in f64, validated.
#[derive(Clone, Debug, PartialEq)]
pub struct TracedScene {
    /// Colour of a ray that hits nothing, each channel in 0..=1.
    pub background: [f64; 3],
    /// Ambient intensity `I` of the local term `KA·C·I`.
    pub ambient: f64,
    /// Lights in file order (light k is bit k of the shadow image).
    pub lights: Vec<TracedLight>,
    /// Materials in file order; [`Surface::Material`] indexes this.
    pub materials: Vec<Material>,
    /// Checker textures in file order; [`Surface::Checker`] indexes this.
    pub checkers: Vec<Checker>,
    /// Objects; the index is the object's id.
    pub objects: Vec<Object>,
}

/// A light with its intensity (no distance falloff).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TracedLight {
    /// Where the light is.
    pub kind: LightKind,
    /// Intensity `I` in `KD·max(0, N·L)·C·I`, ≥ 0.
    pub intensity: f64,
}

/// A point light or a directional one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightKind {
    /// A point light at this position.
    Point(V3),
    /// A light at infinity; the unit vector points from the surface towards the light.
    Directional(V3),
}

/// A surface material.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// The name lines refer to it by.
    pub name: String,
    /// Colour `C`, each channel in 0..=1.
    pub color: [f64; 3],
    /// Ambient coefficient.
    pub ka: f64,
    /// Diffuse coefficient.
    pub kd: f64,
    /// Reflection coefficient (weight of the reflected ray).
    pub kr: f64,
    /// Transmission coefficient (weight of the refracted ray).
    pub kt: f64,
    /// Index of refraction of the inside, in [`IOR_RANGE`].
    pub ior: f64,
}

/// A checker texture of two materials over a plane or polygon.
#[derive(Clone, Debug, PartialEq)]
pub struct Checker {
    /// The name lines refer to it by (shared with the materials').
    pub name: String,
    /// Material of the cells whose indices sum to an even number (index into
    /// [`TracedScene::materials`]).
    pub a: usize,
    /// Material of the odd cells.
    pub b: usize,
    /// Side of a cell, > 0.
    pub size: f64,
    /// The scene-file line that defined it (1-based).
    pub line: usize,
}

/// What an object's surface is made of.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Surface {
    /// One material: an index into [`TracedScene::materials`].
    Material(usize),
    /// A checker texture: an index into [`TracedScene::checkers`].
    Checker(usize),
}

/// One object: a shape and its surface.
#[derive(Clone, Debug, PartialEq)]
pub struct Object {
    /// The geometry.
    pub shape: Shape,
    /// Its material or checker texture.
    pub surface: Surface,
    /// The scene-file line that made it (1-based).
    pub line: usize,
}

/// The geometry of an object, in world coordinates.
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// Sphere; radius > 0.
    Sphere {
        /// Centre.
        centre: V3,
        /// Radius.
        radius: f64,
    },
    /// The plane `normal·p + d = 0`, normalised (|normal| = 1); outside is where the normal points.
    Plane {
        /// Unit normal.
        normal: V3,
        /// Offset.
        d: f64,
    },
    /// Axis-aligned box; `min < max` on every axis.
    Box {
        /// Minimum corner.
        min: V3,
        /// Maximum corner.
        max: V3,
    },
    /// Capped cylinder along `p0 → p1`; radius > 0, `p0 ≠ p1`.
    Cylinder {
        /// Centre of the first cap.
        p0: V3,
        /// Centre of the second cap.
        p1: V3,
        /// Radius.
        radius: f64,
    },
    /// Capped cone frustum along `p0 → p1` with radius `r0` at `p0` and `r1` at `p1` (both ≥ 0,
    /// not both 0; a zero radius is an apex); `p0 ≠ p1`.
    Cone {
        /// Centre of the first cap.
        p0: V3,
        /// Radius at `p0`.
        r0: f64,
        /// Centre of the second cap.
        p1: V3,
        /// Radius at `p1`.
        r1: f64,
    },
    /// Axis-aligned ellipsoid; radii > 0.
    Ellipsoid {
        /// Centre.
        centre: V3,
        /// Semi-axes along x, y, z.
        radii: V3,
    },
    /// Planar polygon (convex or concave, even-odd rule), at least 3 vertices.
    Polygon {
        /// Vertices in order.
        vertices: Vec<V3>,
        /// Unit normal by Newell's method: counter-clockwise vertices seen from the side it
        /// points to (the outside).
        normal: V3,
    },
    /// A mesh triangle (non-degenerate); its outside is where `(b − a) × (c − a)` points.
    Triangle {
        /// Corners in OBJ order.
        corners: [V3; 3],
    },
}

impl Shape {
    /// The scene-file keyword of this kind of shape (`mesh` triangles say `triangle`).
    pub fn kind(&self) -> &'static str {
        match self {
            Shape::Sphere { .. } => "sphere",
            Shape::Plane { .. } => "plane",
            Shape::Box { .. } => "box",
            Shape::Cylinder { .. } => "cylinder",
            Shape::Cone { .. } => "cone",
            Shape::Ellipsoid { .. } => "ellipsoid",
            Shape::Polygon { .. } => "polygon",
            Shape::Triangle { .. } => "triangle",
        }
    }
}

/// The index of refraction an IOR word names (the lecture's table), or a number.
pub fn ior_by_name(word: &str) -> Option<f64> {
    match word {
        "air" => Some(1.0),
        "water" => Some(1.33),
        "glass" => Some(1.5),
        "dense-glass" => Some(1.7),
        "diamond" => Some(2.42),
        _ => None,
    }
}

impl TracedScene {
    /// Reads and parses a scene file (mesh paths are relative to its directory).
    pub fn load(path: &Path) -> Result<Self, String> {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let dir = path.parent().unwrap_or(Path::new("."));
        Self::parse(&text, dir, &path.display().to_string())
    }

    /// Parses scene text; `dir` resolves mesh paths, `name` labels error messages.
    pub fn parse(text: &str, dir: &Path, name: &str) -> Result<Self, String> {
        let mut p = Parser {
            scene: TracedScene {
                background: [0.0; 3],
                ambient: 0.0,
                lights: Vec::new(),
                materials: Vec::new(),
                checkers: Vec::new(),
                objects: Vec::new(),
            },
            seen_background: false,
            seen_ambient: false,
        };
        for (i, raw) in text.lines().enumerate() {
            let content = raw.split('#').next().unwrap_or("");
            let mut tokens = Tokens {
                words: content.split_whitespace().collect(),
                next: 0,
            };
            if tokens.words.is_empty() {
                continue;
            }
            p.line(&mut tokens, i + 1, dir)
                .map_err(|e| format!("{name}:{}: {e}", i + 1))?;
        }
        if i32::try_from(p.scene.objects.len()).is_err() {
            return Err(format!("{name}: more objects than ids (i32) can name"));
        }
        Ok(p.scene)
    }

    /// The material of object `id` at point `p` of its surface: its own, or for a checker
    /// texture the material of the cell `p` lies in.
    pub fn material_at(&self, id: usize, p: V3) -> Option<&Material> {
        self.materials.get(self.material_index_at(id, p)?)
    }

    /// The index in [`TracedScene::materials`] of [`material_at`](Self::material_at).
    pub fn material_index_at(&self, id: usize, p: V3) -> Option<usize> {
        let object = self.objects.get(id)?;
        match object.surface {
            Surface::Material(m) => Some(m),
            Surface::Checker(k) => {
                let checker = self.checkers.get(k)?;
                let normal = match &object.shape {
                    Shape::Plane { normal, .. } | Shape::Polygon { normal, .. } => *normal,
                    _ => return None,
                };
                let (u, v) = match super::intersect::dominant_axis(normal) {
                    0 => (p[1], p[2]),
                    1 => (p[0], p[2]),
                    _ => (p[0], p[1]),
                };
                let cell = |c: f64| (c / checker.size).floor();
                let even = (cell(u) + cell(v)).rem_euclid(2.0) == 0.0;
                Some(if even { checker.a } else { checker.b })
            }
        }
    }

    /// Number of mesh triangles among the objects.
    pub fn triangle_count(&self) -> usize {
        self.objects
            .iter()
            .filter(|o| matches!(o.shape, Shape::Triangle { .. }))
            .count()
    }
}

struct Tokens<'a> {
    words: Vec<&'a str>,
    next: usize,
}

impl<'a> Tokens<'a> {
    fn word(&mut self, what: &str) -> Result<&'a str, String> {
        let w = self
            .words
            .get(self.next)
            .copied()
            .ok_or_else(|| format!("missing {what}"))?;
        self.next += 1;
        Ok(w)
    }
    fn number(&mut self, what: &str) -> Result<f64, String> {
        let w = self.word(what)?;
        let v: f64 = w
            .parse()
            .map_err(|_| format!("{what} '{w}' is not a number"))?;
        if v.is_finite() {
            Ok(v)
        } else {
            Err(format!("{what} '{w}' is not a finite number"))
        }
    }
    fn v3(&mut self, what: &str) -> Result<V3, String> {
        Ok([
            self.number(&format!("{what} x"))?,
            self.number(&format!("{what} y"))?,
            self.number(&format!("{what} z"))?,
        ])
    }
    fn unit(&mut self, what: &str) -> Result<f64, String> {
        let v = self.number(what)?;
        if (0.0..=1.0).contains(&v) {
            Ok(v)
        } else {
            Err(format!("{what} {v} is outside 0..1"))
        }
    }
    fn non_negative(&mut self, what: &str) -> Result<f64, String> {
        let v = self.number(what)?;
        if v >= 0.0 {
            Ok(v)
        } else {
            Err(format!("{what} {v} is negative"))
        }
    }
    fn positive(&mut self, what: &str) -> Result<f64, String> {
        let v = self.number(what)?;
        if v > 0.0 {
            Ok(v)
        } else {
            Err(format!("{what} {v} must be positive"))
        }
    }
    fn rest(&self) -> usize {
        self.words.len() - self.next.min(self.words.len())
    }
    fn end(&self) -> Result<(), String> {
        match self.words.get(self.next) {
            None => Ok(()),
            Some(w) => Err(format!("unexpected '{w}' at the end of the line")),
        }
    }
}

struct Parser {
    scene: TracedScene,
    seen_background: bool,
    seen_ambient: bool,
}

impl Parser {
    /// Whether a material or checker of this name exists (they share one namespace).
    fn defined(&self, name: &str) -> bool {
        self.scene.materials.iter().any(|m| m.name == name)
            || self.scene.checkers.iter().any(|c| c.name == name)
    }
}

fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn length(a: V3) -> f64 {
    reference::dot(a, a).sqrt()
}

/// Whether `v` has a finite, non-zero length (false for NaN too).
fn is_proper(v: V3) -> bool {
    let l = length(v);
    l > 0.0 && l.is_finite()
}

impl Parser {
    /// A material or checker name: the surface of an object.
    fn material(&self, t: &mut Tokens) -> Result<Surface, String> {
        let name = t.word("material name")?;
        let scene = &self.scene;
        match scene.materials.iter().position(|m| m.name == name) {
            Some(m) => Ok(Surface::Material(m)),
            None => scene
                .checkers
                .iter()
                .position(|c| c.name == name)
                .map(Surface::Checker)
                .ok_or_else(|| format!("unknown material '{name}'")),
        }
    }

    /// A material name that is not a checker (a checker's cells are plain materials).
    fn plain_material(&self, t: &mut Tokens) -> Result<usize, String> {
        match self.material(t)? {
            Surface::Material(m) => Ok(m),
            Surface::Checker(k) => Err(format!(
                "checker '{}' is not a plain material (a checker's cells are)",
                self.scene.checkers[k].name
            )),
        }
    }

    /// An error when `surface` is a checker and `kind` of line cannot carry one.
    fn check_surface(&self, surface: Surface, kind: &str) -> Result<(), String> {
        match surface {
            Surface::Checker(k) if kind != "plane" && kind != "polygon" => Err(format!(
                "checker '{}' is only for plane and polygon lines, not a {kind}",
                self.scene.checkers[k].name
            )),
            _ => Ok(()),
        }
    }

    fn push(&mut self, shape: Shape, surface: Surface, line: usize) -> Result<(), String> {
        self.check_surface(surface, shape.kind())?;
        self.scene.objects.push(Object {
            shape,
            surface,
            line,
        });
        Ok(())
    }

    fn line(&mut self, t: &mut Tokens, line: usize, dir: &Path) -> Result<(), String> {
        let keyword = t.word("keyword")?;
        match keyword {
            "background" => {
                if std::mem::replace(&mut self.seen_background, true) {
                    return Err("second background line".into());
                }
                self.scene.background = [t.unit("red")?, t.unit("green")?, t.unit("blue")?];
            }
            "ambient" => {
                if std::mem::replace(&mut self.seen_ambient, true) {
                    return Err("second ambient line".into());
                }
                self.scene.ambient = t.non_negative("ambient intensity")?;
            }
            "light" => {
                if self.scene.lights.len() == MAX_LIGHTS {
                    return Err(format!(
                        "more than {MAX_LIGHTS} lights (the shadow image has one bit per light)"
                    ));
                }
                let kind = match t.word("light kind (point or directional)")? {
                    "point" => LightKind::Point(t.v3("light position")?),
                    "directional" => {
                        let d = t.v3("light direction")?;
                        LightKind::Directional(
                            reference::normalize(d).ok_or("light direction is zero")?,
                        )
                    }
                    k => return Err(format!("unknown light kind '{k}' (point or directional)")),
                };
                let intensity = t.non_negative("light intensity")?;
                self.scene.lights.push(TracedLight { kind, intensity });
            }
            "material" => {
                let name = t.word("material name")?;
                if self.defined(name) {
                    return Err(format!("material '{name}' defined twice"));
                }
                let color = [t.unit("red")?, t.unit("green")?, t.unit("blue")?];
                let ka = t.non_negative("KA")?;
                let kd = t.non_negative("KD")?;
                let kr = t.non_negative("KR")?;
                let kt = t.non_negative("KT")?;
                let word = t.word("IOR")?;
                let ior = match ior_by_name(word) {
                    Some(v) => v,
                    None => {
                        t.next -= 1;
                        t.number("IOR")?
                    }
                };
                if !IOR_RANGE.contains(&ior) {
                    return Err(format!(
                        "IOR {ior} is outside {}..{}",
                        IOR_RANGE.start(),
                        IOR_RANGE.end()
                    ));
                }
                self.scene.materials.push(Material {
                    name: name.to_string(),
                    color,
                    ka,
                    kd,
                    kr,
                    kt,
                    ior,
                });
            }
            "checker" => {
                let name = t.word("checker name")?;
                if self.defined(name) {
                    return Err(format!("material '{name}' defined twice"));
                }
                let a = self.plain_material(t)?;
                let b = self.plain_material(t)?;
                let size = t.positive("checker size")?;
                self.scene.checkers.push(Checker {
                    name: name.to_string(),
                    a,
                    b,
                    size,
                    line,
                });
            }
            "sphere" => {
                let centre = t.v3("centre")?;
                let radius = t.positive("radius")?;
                let m = self.material(t)?;
                self.push(Shape::Sphere { centre, radius }, m, line)?;
            }
            "plane" => {
                let n = t.v3("normal")?;
                let d = t.number("d")?;
                let m = self.material(t)?;
                let len = length(n);
                if !is_proper(n) {
                    return Err("plane normal is zero".into());
                }
                let normal = n.map(|c| c / len);
                self.push(Shape::Plane { normal, d: d / len }, m, line)?;
            }
            "box" => {
                let min = t.v3("min corner")?;
                let max = t.v3("max corner")?;
                let m = self.material(t)?;
                if (0..3).any(|k| min[k] >= max[k]) {
                    return Err(
                        "box corners must be (min, max) with min < max on every axis".into(),
                    );
                }
                self.push(Shape::Box { min, max }, m, line)?;
            }
            "cylinder" => {
                let p0 = t.v3("first cap centre")?;
                let p1 = t.v3("second cap centre")?;
                let radius = t.positive("radius")?;
                let m = self.material(t)?;
                if !is_proper(sub(p1, p0)) {
                    return Err("cylinder axis has zero length".into());
                }
                self.push(Shape::Cylinder { p0, p1, radius }, m, line)?;
            }
            "cone" => {
                let p0 = t.v3("first cap centre")?;
                let r0 = t.non_negative("first radius")?;
                let p1 = t.v3("second cap centre")?;
                let r1 = t.non_negative("second radius")?;
                let m = self.material(t)?;
                if !is_proper(sub(p1, p0)) {
                    return Err("cone axis has zero length".into());
                }
                if r0 == 0.0 && r1 == 0.0 {
                    return Err("cone radii are both zero".into());
                }
                self.push(Shape::Cone { p0, r0, p1, r1 }, m, line)?;
            }
            "ellipsoid" => {
                let centre = t.v3("centre")?;
                let radii = [
                    t.positive("x radius")?,
                    t.positive("y radius")?,
                    t.positive("z radius")?,
                ];
                let m = self.material(t)?;
                self.push(Shape::Ellipsoid { centre, radii }, m, line)?;
            }
            "polygon" => {
                let m = self.material(t)?;
                let n = t.rest();
                if !n.is_multiple_of(3) {
                    return Err(format!(
                        "polygon has {n} coordinates: missing number (3 per vertex)"
                    ));
                }
                let mut vertices = Vec::with_capacity(n / 3);
                for k in 0..n / 3 {
                    vertices.push(t.v3(&format!("vertex {}", k + 1))?);
                }
                let normal = polygon_normal(&vertices)?;
                self.push(Shape::Polygon { vertices, normal }, m, line)?;
            }
            "mesh" => {
                let file = t.word("mesh file")?;
                let m = self.material(t)?;
                t.end()?;
                self.check_surface(m, "mesh")?;
                for corners in load_mesh(&dir.join(file))? {
                    self.push(Shape::Triangle { corners }, m, line)?;
                }
            }
            k => return Err(format!("unknown keyword '{k}'")),
        }
        t.end()
    }
}

/// Newell's normal of a planar polygon, checked: ≥ 3 vertices, non-zero area, planar.
fn polygon_normal(vertices: &[V3]) -> Result<V3, String> {
    if vertices.len() < 3 {
        return Err(format!(
            "degenerate polygon: {} vertices (at least 3)",
            vertices.len()
        ));
    }
    let mut n = [0.0; 3];
    for (k, a) in vertices.iter().enumerate() {
        let b = vertices[(k + 1) % vertices.len()];
        n[0] += (a[1] - b[1]) * (a[2] + b[2]);
        n[1] += (a[2] - b[2]) * (a[0] + b[0]);
        n[2] += (a[0] - b[0]) * (a[1] + b[1]);
    }
    let extent = vertices
        .iter()
        .map(|v| length(sub(*v, vertices[0])))
        .fold(0.0, f64::max);
    let normal = match reference::normalize(n) {
        Some(u) if length(n) > 1e-12 * extent * extent => u,
        _ => return Err("degenerate polygon: zero area".into()),
    };
    let d = -reference::dot(normal, vertices[0]);
    for (k, v) in vertices.iter().enumerate() {
        let off = (reference::dot(normal, *v) + d).abs();
        if off > PLANARITY_TOLERANCE * extent {
            return Err(format!(
                "polygon is not planar: vertex {} is {off:.3e} off its plane",
                k + 1
            ));
        }
    }
    Ok(normal)
}

/// The triangles of an OBJ file in face order, polygons fan-triangulated, positions in f64.
fn load_mesh(path: &Path) -> Result<Vec<[V3; 3]>, String> {
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ..Default::default()
    };
    let (models, _) =
        tobj::load_obj(path, &opts).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut out = Vec::new();
    for m in &models {
        let pos = &m.mesh.positions;
        let vertex = |i: u32| -> Result<V3, String> {
            let k = i as usize * 3;
            match pos.get(k..k + 3) {
                Some(p) if p.iter().all(|c| c.is_finite()) => Ok([p[0], p[1], p[2]]),
                Some(_) => Err(format!(
                    "{}: vertex {} is not finite",
                    path.display(),
                    i + 1
                )),
                None => Err(format!(
                    "{}: face index {} out of range",
                    path.display(),
                    i + 1
                )),
            }
        };
        for f in m.mesh.indices.chunks(3) {
            let &[a, b, c] = f else {
                return Err(format!("{}: malformed face", path.display()));
            };
            let corners = [vertex(a)?, vertex(b)?, vertex(c)?];
            let n = reference::cross(sub(corners[1], corners[0]), sub(corners[2], corners[0]));
            if !is_proper(n) {
                return Err(format!(
                    "{}: face {} is degenerate (zero area)",
                    path.display(),
                    out.len() + 1
                ));
            }
            out.push(corners);
        }
    }
    if out.is_empty() {
        return Err(format!("{}: no faces", path.display()));
    }
    Ok(out)
}

/// Checks a camera: finite numbers, eye ≠ target, up not parallel to the view, 0 < fovy < 180,
/// 0 < near < far. One line naming the problem otherwise.
pub fn check_camera(c: &CameraSpec) -> Result<reference::Camera, String> {
    let all = [c.eye, c.target, c.up].concat();
    if all
        .iter()
        .chain([&c.fovy, &c.near, &c.far])
        .any(|v| !v.is_finite())
    {
        return Err("camera numbers must be finite".into());
    }
    let view = sub(c.target, c.eye);
    if !is_proper(view) {
        return Err("camera eye and target are the same point".into());
    }
    // The sine of the angle between up and the view direction.
    let sine = match (reference::normalize(view), reference::normalize(c.up)) {
        (Some(v), Some(u)) => length(reference::cross(v, u)),
        _ => 0.0,
    };
    if sine <= 1e-12 {
        return Err("camera up is zero or parallel to the view direction".into());
    }
    if !(c.fovy > 0.0 && c.fovy < 180.0) {
        return Err(format!(
            "field of view {} must be in (0, 180) degrees",
            c.fovy
        ));
    }
    if !(c.near > 0.0 && c.near < c.far) {
        return Err(format!(
            "near {} and far {} must satisfy 0 < near < far",
            c.near, c.far
        ));
    }
    c.reference()
}

/// The primary ray through the centre of pixel (column `x`, row `y`) of a `w × h` image: origin
/// the eye, direction scaled so its component along the view axis is 1 (so the ray parameter
/// is the eye depth, and [near, far) bounds it directly).
pub fn primary_ray(camera: &reference::Camera, x: usize, y: usize, w: usize, h: usize) -> V3 {
    camera.ray(x as f64 + 0.5, y as f64 + 0.5, w, h)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<TracedScene, String> {
        TracedScene::parse(text, Path::new("."), "t.scene")
    }

    const GOOD: &str = "\
# every line kind
background 0.1 0.2 0.3
ambient 0.2
light point 0 5 0 0.8
light directional 0 2 0 0.5   # normalised on reading
material red 1 0 0 0.2 0.8 0 0 1
material glass 1 1 1 0 0 0.1 0.9 glass
material gem 1 1 1 0 0 0.1 0.9 diamond
sphere 0 0 -5 1 red
plane 0 2 0 2 red
box -1 -1 -1 1 1 1 glass
cylinder 0 0 0 0 1 0 0.5 red
cone 0 0 0 1 0 2 0 0 gem
ellipsoid 0 0 0 1 2 3 red
polygon red 0 0 0 2 0 0 2 2 0 1 1 0 0 2 0
";

    #[test]
    fn every_line_kind_parses() {
        let s = parse(GOOD).unwrap();
        assert_eq!(s.background, [0.1, 0.2, 0.3]);
        assert_eq!(s.ambient, 0.2);
        assert_eq!(s.lights.len(), 2);
        assert_eq!(s.lights[1].kind, LightKind::Directional([0.0, 1.0, 0.0]));
        assert_eq!(s.materials[1].ior, 1.5);
        assert_eq!(s.materials[2].ior, 2.42);
        let kinds: Vec<_> = s.objects.iter().map(|o| o.shape.kind()).collect();
        assert_eq!(
            kinds,
            [
                "sphere",
                "plane",
                "box",
                "cylinder",
                "cone",
                "ellipsoid",
                "polygon"
            ]
        );
        // The plane is normalised: 2y + 2 = 0 is y = -1.
        assert_eq!(
            s.objects[1].shape,
            Shape::Plane {
                normal: [0.0, 1.0, 0.0],
                d: 1.0
            }
        );
        // Concave polygon, counter-clockwise seen from +z.
        match &s.objects[6].shape {
            Shape::Polygon { vertices, normal } => {
                assert_eq!(vertices.len(), 5);
                assert_eq!(*normal, [0.0, 0.0, 1.0]);
            }
            other => panic!("{other:?}"),
        }
        assert_eq!(s.objects[6].line, 15);
        assert_eq!(s.material_at(2, [0.0; 3]).unwrap().name, "glass");
    }

    #[test]
    fn checker_lines_parse() {
        let s = parse(
            "material a 1 1 1 0 1 0 0 1\nmaterial b 0 0 0 0 1 0 0 1\nchecker c b a 0.25\n\
             plane 0 1 0 0 c\npolygon a 0 0 0 1 0 0 0 1 0\n",
        )
        .unwrap();
        assert_eq!(
            s.checkers,
            [Checker {
                name: "c".into(),
                a: 1,
                b: 0,
                size: 0.25,
                line: 3
            }]
        );
        assert_eq!(s.objects[0].surface, Surface::Checker(0));
        assert_eq!(s.objects[1].surface, Surface::Material(0));
        assert_eq!(s.material_at(0, [0.1, 0.0, 0.1]).unwrap().name, "b");
        assert_eq!(s.material_at(0, [0.3, 0.0, 0.1]).unwrap().name, "a");
    }

    #[test]
    fn bad_input_is_one_line_naming_the_line() {
        let head = "material m 1 1 1 0 1 0 0 1\n";
        let cases = [
            ("frobnicate 1 2 3", "unknown keyword 'frobnicate'"),
            ("sphere 0 0 0 m", "radius 'm' is not a number"),
            ("sphere 0 0 0", "missing radius"),
            ("sphere 0 0 0 1", "missing material name"),
            ("sphere 0 NaN 0 1 m", "not a finite number"),
            ("sphere 0 0 0 -1 m", "radius -1 must be positive"),
            ("sphere 0 0 0 1 nope", "unknown material 'nope'"),
            ("sphere 0 0 0 1 m extra", "unexpected 'extra'"),
            (
                "polygon m 0 0 0 1 0 0 2 0 0",
                "degenerate polygon: zero area",
            ),
            ("polygon m 0 0 0 1 0 0", "degenerate polygon: 2 vertices"),
            ("polygon m 0 0 0 1 0 0 1 1", "missing number"),
            ("polygon m 0 0 0 1 0 0 1 1 0 0 1 1", "not planar"),
            ("box 1 0 0 0 1 1 m", "min < max"),
            ("cylinder 0 0 0 0 0 0 1 m", "zero length"),
            ("cone 0 0 0 0 0 1 0 0 m", "both zero"),
            ("ellipsoid 0 0 0 1 0 1 m", "y radius 0 must be positive"),
            ("plane 0 0 0 1 m", "plane normal is zero"),
            ("light spot 0 0 0 1", "unknown light kind 'spot'"),
            ("light directional 0 0 0 1", "light direction is zero"),
            ("material m 1 1 1 0 1 0 0 1", "defined twice"),
            ("material q 1 1 1 0 1 0 0 unobtainium", "IOR 'unobtainium'"),
            ("material q 1 1 1 0 1 0 0 0.5", "IOR 0.5 is outside"),
            ("material q 2 1 1 0 1 0 0 1", "red 2 is outside 0..1"),
            ("material q 1 1 1 -1 1 0 0 1", "KA -1 is negative"),
            ("background 0 0 0\nbackground 0 0 0", "second background"),
            ("mesh missing.obj m", "missing.obj"),
            ("checker c m nope 1", "unknown material 'nope'"),
            ("checker c m m 0", "checker size 0 must be positive"),
            ("checker c m m -2", "checker size -2 must be positive"),
            ("checker c m m x", "checker size 'x' is not a number"),
            ("checker c m m", "missing checker size"),
            ("checker c m m inf", "not a finite number"),
            ("checker m m m 1", "'m' defined twice"),
            ("checker c m m 1 extra", "unexpected 'extra'"),
            (
                "checker c m m 1\nmaterial c 1 1 1 0 1 0 0 1",
                "'c' defined twice",
            ),
            (
                "checker c m m 1\nchecker d c m 1",
                "'c' is not a plain material",
            ),
            (
                "checker c m m 1\nsphere 0 0 0 1 c",
                "only for plane and polygon lines, not a sphere",
            ),
            ("checker c m m 1\nbox 0 0 0 1 1 1 c", "not a box"),
            ("checker c m m 1\nmesh missing.obj c", "not a mesh"),
        ];
        for (body, want) in cases {
            let err = parse(&format!("{head}\n# comment\n{body}\n")).unwrap_err();
            assert!(!err.contains('\n'), "{err}");
            let line = 4 + body.lines().count() - 1;
            assert!(
                err.starts_with(&format!("t.scene:{line}: ")) && err.contains(want),
                "{body}: {err}"
            );
        }
        let nine = "light point 0 0 0 1\n".repeat(9);
        assert!(parse(&nine)
            .unwrap_err()
            .starts_with("t.scene:9: more than 8"));
    }

    #[test]
    fn mesh_gives_one_object_per_triangle_in_face_order() {
        let dir = std::env::temp_dir().join(format!("trace-scene-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(
            dir.join("quad.obj"),
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n",
        )
        .unwrap();
        std::fs::write(dir.join("flat.obj"), "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n").unwrap();
        let text = "material m 1 1 1 0 1 0 0 1\nsphere 0 0 0 1 m\nmesh quad.obj m\n";
        let s = TracedScene::parse(text, &dir, "t.scene").unwrap();
        assert_eq!(s.objects.len(), 3);
        assert_eq!(s.triangle_count(), 2);
        let tri = |k: usize| match &s.objects[k].shape {
            Shape::Triangle { corners } => *corners,
            other => panic!("{other:?}"),
        };
        // Fan triangulation: (a, b, c), (a, c, d).
        assert_eq!(tri(1), [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]]);
        assert_eq!(tri(2), [[0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]]);
        let err = TracedScene::parse("material m 1 1 1 0 1 0 0 1\nmesh flat.obj m\n", &dir, "t")
            .unwrap_err();
        assert!(
            err.starts_with("t:2: ") && err.contains("degenerate"),
            "{err}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn cameras_are_checked() {
        let good = CameraSpec {
            eye: [0.0, 0.0, 5.0],
            target: [0.0; 3],
            up: [0.0, 1.0, 0.0],
            fovy: 60.0,
            near: 0.1,
            far: 100.0,
        };
        let cam = check_camera(&good).unwrap();
        // The centre pixel's ray of an odd-sized image looks straight at the target, depth-scaled.
        let d = primary_ray(&cam, 1, 1, 3, 3);
        assert!((d[0]).abs() < 1e-12 && (d[1]).abs() < 1e-12 && (d[2] + 1.0).abs() < 1e-12);
        let bad = [
            (
                CameraSpec {
                    eye: [0.0; 3],
                    ..good
                },
                "same point",
            ),
            (
                CameraSpec {
                    up: [0.0, 0.0, 1.0],
                    ..good
                },
                "parallel",
            ),
            (
                CameraSpec {
                    fovy: 180.0,
                    ..good
                },
                "field of view",
            ),
            (CameraSpec { near: 0.0, ..good }, "near"),
            (CameraSpec { far: 0.05, ..good }, "near"),
            (
                CameraSpec {
                    fovy: f64::NAN,
                    ..good
                },
                "finite",
            ),
        ];
        for (c, want) in bad {
            let e = check_camera(&c).unwrap_err();
            assert!(e.contains(want) && !e.contains('\n'), "{e}");
        }
    }
}
