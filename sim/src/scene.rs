//! Scene specifications shared by the fixed-point renderer and the float reference: owned mesh
//! data, camera and light parameters, OBJ loading, and rendering to id/depth/colour images.

use crate::bsp::Bsp;
use crate::metrics::ArithmeticError;
use crate::reference::{self, Image};
use embedded_graphics::pixelcolor::{Rgb888, RgbColor};
use fixed::types::I16F16;
use scanline3d::arithmetic::{Arithmetic, Precise, Setup};
use scanline3d::arithmetic::{ExactDivision, Reciprocal};
use scanline3d::arithmetic::{NarrowTransform, WideTransform};
use scanline3d::clip::FrustumClip;
use scanline3d::depth::{Depth16, DepthFormat};
use scanline3d::math::{Libm, MathBackend, Micromath, NarrowNormals, WideNormals};
use scanline3d::options::MAX_INSTANCES;
use scanline3d::preset::{self, Preset};
use scanline3d::resolve::bsp::{BspTree, BspWorkspace};
use scanline3d::resolve::{
    warnock, BandWorkspace, DepthSortWorkspace, NewellWorkspace, SpanSortWorkspace,
    WarnockWorkspace, ZBufferWorkspace,
};
use scanline3d::scene::MAX_SCENE_TRIANGLES;
use scanline3d::scene::{Camera, Instance, Light, Mesh, MeshColors, Scene, Transform, Vertex};
use scanline3d::sink::{FnSink, Row, RowPixel, RowSink, TriangleId};
use scanline3d::{Depth, Flat, FrameStats, RenderOptions, Workspace};
use std::convert::Infallible;
use std::fmt::Debug;
use std::path::Path;

/// Camera parameters (`gluLookAt` + `gluPerspective`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraSpec {
    /// Eye position.
    pub eye: [f64; 3],
    /// Point looked at.
    pub target: [f64; 3],
    /// Up direction.
    pub up: [f64; 3],
    /// Vertical field of view in degrees.
    pub fovy: f64,
    /// Near plane.
    pub near: f64,
    /// Far plane.
    pub far: f64,
}

/// Light parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSpec {
    /// Towards the light (any length).
    pub direction: [f64; 3],
    /// Ambient intensity.
    pub ambient: f64,
    /// Diffuse intensity.
    pub diffuse: f64,
}

impl Default for LightSpec {
    fn default() -> Self {
        LightSpec {
            direction: [-0.45, 0.8, 0.55],
            ambient: 0.25,
            diffuse: 0.75,
        }
    }
}

/// Owned mesh data in the renderer's input format.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshData {
    /// I16F16 model coordinates.
    pub vertices: Vec<Vertex>,
    /// Triangles.
    pub triangles: Vec<[u16; 3]>,
    /// One colour per triangle.
    pub colors: Vec<Rgb888>,
    /// Unit vertex normals (I16F16), for Gouraud shading: from the OBJ file when it has them.
    pub normals: Option<Vec<Vertex>>,
}

impl MeshData {
    /// Mesh from f64 positions (rounded to I16F16) and triangles, with a uniform colour.
    pub fn new(
        positions: &[[f64; 3]],
        triangles: Vec<[u16; 3]>,
        color: Rgb888,
    ) -> Result<Self, String> {
        let vertices = positions
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let c = |v: f64| {
                    I16F16::checked_from_num(v).ok_or_else(|| {
                        format!("vertex {i} coordinate {v} is not a finite number in range")
                    })
                };
                Ok([c(p[0])?, c(p[1])?, c(p[2])?])
            })
            .collect::<Result<Vec<_>, String>>()?;
        let colors = vec![color; triangles.len()];
        let data = MeshData {
            vertices,
            triangles,
            colors,
            normals: None,
        };
        data.mesh()?;
        Ok(data)
    }

    /// The library's view of this data (validated).
    pub fn mesh(&self) -> Result<Mesh<'_>, String> {
        Mesh::new(
            &self.vertices,
            &self.triangles,
            MeshColors::PerFace(&self.colors),
            self.normals.as_deref(),
        )
        .map_err(|e| e.to_string())
    }

    /// Model-space f64 triangles.
    pub fn world_triangles(&self) -> Vec<reference::Triangle> {
        let p = |i: u16| self.vertices[i as usize].map(|c| c.to_num::<f64>());
        self.triangles
            .iter()
            .zip(&self.colors)
            .map(|(t, c)| reference::Triangle {
                v: t.map(p),
                color: [c.r(), c.g(), c.b()].map(f64::from),
            })
            .collect()
    }

    /// Loads an OBJ file: all objects in file order, polygons fan-triangulated
    /// (a b c d -> (a,b,c), (a,c,d)), so triangle ids follow the file's face order.
    pub fn load_obj(path: &Path) -> Result<Self, String> {
        let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
        Self::load_obj_bytes(&bytes, &path.display().to_string())
    }

    /// [`MeshData::load_obj`] from OBJ text in memory; `name` labels error messages. Faces
    /// take the default colour (no `.mtl` file is read); a mesh beyond the model envelope or
    /// 16-bit indices is refused here ([`crate::world::World`] places such meshes in chunks).
    pub fn load_obj_bytes(bytes: &[u8], name: &str) -> Result<Self, String> {
        let world = crate::world::World::load_obj_bytes(bytes, name)?;
        if !world.fits_one_mesh() {
            return Err(format!(
                "{name}: beyond one mesh's envelope (±{} units, 65535 vertices): load it as a World",
                scanline3d::scene::MAX_MODEL_COORD
            ));
        }
        let (mut instances, _) = world.instances()?;
        let mut mesh = instances.pop().ok_or("no mesh")?.mesh;
        mesh.colors = vec![crate::world::DEFAULT_COLOR; mesh.triangles.len()];
        Ok(mesh)
    }

    /// Writes the mesh as OBJ (one `v` per vertex, one `f` per triangle).
    pub fn to_obj(&self) -> String {
        let mut s = String::new();
        for v in &self.vertices {
            s += &format!("v {} {} {}\n", v[0], v[1], v[2]);
        }
        for t in &self.triangles {
            s += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
        }
        s
    }
}

/// A mesh placed in the world.
#[derive(Clone, Debug)]
pub struct MeshInstance {
    /// The mesh.
    pub mesh: MeshData,
    /// Model → world (the renderer composes it in f32; the reference applies it in f64).
    pub transform: Transform,
}

/// Meshes, a camera and a light: what `sim render` takes.
#[derive(Clone, Debug)]
pub struct SceneSpec {
    /// The meshes; triangle ids number them consecutively in this order.
    pub instances: Vec<MeshInstance>,
    /// The camera.
    pub camera: CameraSpec,
    /// The light.
    pub light: LightSpec,
    /// Back-face culling.
    pub cull_back_faces: bool,
}

fn f32s(v: [f64; 3]) -> [f32; 3] {
    v.map(|c| c as f32)
}

impl CameraSpec {
    /// A camera at `eye` looking at `target` with +y up.
    pub fn looking_at(eye: [f64; 3], target: [f64; 3], fovy: f64, near: f64, far: f64) -> Self {
        CameraSpec {
            eye,
            target,
            up: [0.0, 1.0, 0.0],
            fovy,
            near,
            far,
        }
    }

    /// The library camera.
    pub fn fixed(&self) -> Result<Camera, String> {
        self.fixed_with(SetupMath::Libm)
    }

    /// [`Self::fixed`] with set-up computed by `math`.
    pub fn fixed_with(&self, math: SetupMath) -> Result<Camera, String> {
        fn with<M: MathBackend>(c: &CameraSpec) -> Result<Camera, scanline3d::scene::SceneError> {
            Camera::look_at_with::<M>(f32s(c.eye), f32s(c.target), f32s(c.up))
                .and_then(|v| v.perspective_with::<M>(c.fovy as f32, c.near as f32, c.far as f32))
        }
        match math {
            SetupMath::Libm => with::<Libm>(self),
            SetupMath::Micromath => with::<Micromath>(self),
        }
        .map_err(|e| e.to_string())
    }
    /// The reference camera.
    pub fn reference(&self) -> Result<reference::Camera, String> {
        reference::Camera::new(
            self.eye,
            self.target,
            self.up,
            self.fovy,
            self.near,
            self.far,
        )
        .ok_or_else(|| "degenerate camera".to_string())
    }
}

impl LightSpec {
    /// The library's light (f32).
    pub fn fixed(&self) -> Result<Light, String> {
        Light::new(
            f32s(self.direction),
            self.ambient as f32,
            self.diffuse as f32,
        )
        .map_err(|e| e.to_string())
    }
    /// The light for the f64 reference (direction normalised).
    pub fn reference(&self) -> Result<reference::Light, String> {
        let direction = reference::normalize(self.direction).ok_or("light direction is zero")?;
        Ok(reference::Light {
            direction,
            ambient: self.ambient,
            diffuse: self.diffuse,
        })
    }
}

/// Sub-pixel precision choices `sim` offers (the library takes them as a const generic).
pub const SUB_PIXEL_CHOICES: [u32; 4] = [0, 2, 4, 8];

/// A fixed-point render: images plus frame statistics.
#[derive(Clone, Debug)]
pub struct FixedRender {
    /// ids, eye depth and colour.
    pub image: Image,
    /// Statistics of the colour pass.
    pub stats: FrameStats,
}

/// Largest target `sim` renders (the library's limit).
pub const MAX_SIZE: usize = 2048;

impl SceneSpec {
    /// One mesh with the identity transform.
    pub fn single(
        mesh: MeshData,
        camera: CameraSpec,
        light: LightSpec,
        cull_back_faces: bool,
    ) -> Self {
        SceneSpec {
            instances: vec![MeshInstance {
                mesh,
                transform: Transform::IDENTITY,
            }],
            camera,
            light,
            cull_back_faces,
        }
    }

    /// The built-in demo scene at frame `frame` of its orbit, as the firmware renders it.
    pub fn demo(frame: u32) -> Result<Self, String> {
        use scanline3d_demo as demo;
        let instances = demo::instances()
            .iter()
            .map(|inst| {
                let m = inst.mesh;
                let colors = match m.colors() {
                    MeshColors::PerFace(c) => c.to_vec(),
                    MeshColors::Uniform(c) => vec![c; m.triangles().len()],
                    MeshColors::PerVertex(c) => {
                        m.triangles().iter().map(|t| c[t[0] as usize]).collect()
                    }
                };
                MeshInstance {
                    mesh: MeshData {
                        vertices: m.vertices().to_vec(),
                        triangles: m.triangles().to_vec(),
                        colors,
                        normals: None,
                    },
                    transform: inst.transform,
                }
            })
            .collect();
        let (eye, target, up, fovy, near, far) = demo::camera_parameters(frame, demo::ORBIT_FRAMES);
        let f = |v: [f32; 3]| v.map(f64::from);
        let (dir, ambient, diffuse) = demo::LIGHT;
        Ok(SceneSpec {
            instances,
            camera: CameraSpec {
                eye: f(eye),
                target: f(target),
                up: f(up),
                fovy: fovy as f64,
                near: near as f64,
                far: far as f64,
            },
            light: LightSpec {
                direction: f(dir),
                ambient: ambient as f64,
                diffuse: diffuse as f64,
            },
            cull_back_faces: true,
        })
    }

    /// The hidden-surface test scene at `level` ([`crate::hsr`]), with vertices rounded exactly
    /// as `build.rs` rounds the firmware's copy ([`crate::meshgen::fixed_bits`]).
    pub fn hsr(level: usize) -> Result<Self, String> {
        let instances = crate::meshgen::hsr_scene(level)
            .into_iter()
            .map(|((v, triangles), [r, g, b])| MeshInstance {
                mesh: MeshData {
                    vertices: v
                        .iter()
                        .map(|p| p.map(|c| I16F16::from_bits(crate::meshgen::fixed_bits(c))))
                        .collect(),
                    colors: vec![Rgb888::new(r, g, b); triangles.len()],
                    triangles,
                    normals: None,
                },
                transform: Transform::IDENTITY,
            })
            .collect();
        let (eye, target, up, fovy, near, far) = crate::hsr::CAMERA;
        let f = |v: [f32; 3]| v.map(f64::from);
        let (dir, ambient, diffuse) = scanline3d_demo::LIGHT;
        Ok(SceneSpec {
            instances,
            camera: CameraSpec {
                eye: f(eye),
                target: f(target),
                up: f(up),
                fovy: fovy as f64,
                near: near as f64,
                far: far as f64,
            },
            light: LightSpec {
                direction: f(dir),
                ambient: ambient as f64,
                diffuse: diffuse as f64,
            },
            cull_back_faces: true,
        })
    }

    /// Calls `f` with this scene as the library sees it (for rendering it through any
    /// workspace). The camera and light are built from the specs as [`Self::render_fixed`]
    /// builds them.
    pub fn with_scene<R>(&self, f: impl FnOnce(&Scene<'_>) -> R) -> Result<R, String> {
        self.with_scene_math(SetupMath::Libm, f)
    }

    /// [`Self::with_scene`] with the camera set up by `math`.
    pub fn with_scene_math<R>(
        &self,
        math: SetupMath,
        f: impl FnOnce(&Scene<'_>) -> R,
    ) -> Result<R, String> {
        let meshes = self.meshes()?;
        let instances = self.library_instances(&meshes);
        let scene = Scene {
            instances: &instances,
            camera: self.camera.fixed_with(math)?,
            light: self.light.fixed()?,
        };
        Ok(f(&scene))
    }

    /// Calls `f` with `instances` (this scene's meshes with other colours, say) under this
    /// scene's camera and light, as the library sees them.
    pub fn with_library_scene<R>(
        &self,
        instances: &[Instance<'_>],
        f: impl FnOnce(&Scene<'_>) -> R,
    ) -> Result<R, String> {
        let scene = Scene {
            instances,
            camera: self.camera.fixed()?,
            light: self.light.fixed()?,
        };
        Ok(f(&scene))
    }

    /// Largest |model coordinate| over all meshes.
    pub fn max_model_coord(&self) -> f64 {
        self.instances
            .iter()
            .flat_map(|i| i.mesh.vertices.iter().flatten())
            .map(|c| c.to_num::<f64>().abs())
            .fold(0.0, f64::max)
    }

    /// The float reference for this scene (transforms applied in f64). It sees every face,
    /// whatever [`Self::cull_back_faces`] says, so a renderer that culls a face that shows is
    /// measured as wrong.
    pub fn reference(&self) -> Result<reference::Scene, String> {
        let mut tris = Vec::new();
        for inst in &self.instances {
            let m = inst.transform.m.map(|row| row.map(f64::from));
            let apply = |p: [f64; 3]| {
                [0, 1, 2].map(|r| m[r][0] * p[0] + m[r][1] * p[1] + m[r][2] * p[2] + m[r][3])
            };
            tris.extend(
                inst.mesh
                    .world_triangles()
                    .into_iter()
                    .map(|t| reference::Triangle {
                        v: t.v.map(apply),
                        ..t
                    }),
            );
        }
        Ok(reference::Scene::new(
            tris,
            self.light.reference()?,
            self.camera.reference()?,
            false,
        ))
    }

    /// Renders with the fixed-point renderer at `sub_bits` (0, 2, 4 or 8) into id, depth and
    /// colour images (an id pass and a colour pass through the same pipeline), with the span
    /// z-buffer.
    pub fn render_fixed(&self, w: usize, h: usize, sub_bits: u32) -> Result<FixedRender, String> {
        self.render_fixed_with(w, h, sub_bits, Algorithm::SpanZBuffer)
    }

    /// [`Self::render_fixed`] with another hidden-surface method. Methods without depth memory
    /// leave the depth image NaN where a surface is shown (there is no depth to report).
    pub fn render_fixed_with(
        &self,
        w: usize,
        h: usize,
        sub_bits: u32,
        algorithm: Algorithm,
    ) -> Result<FixedRender, String> {
        self.render_fixed_settings(w, h, Precision::bits(sub_bits), algorithm)
    }

    /// [`Self::render_fixed_with`] with the precision choices of a preset
    /// (`scanline3d::preset`).
    pub fn render_fixed_preset(
        &self,
        w: usize,
        h: usize,
        preset: PresetChoice,
        algorithm: Algorithm,
    ) -> Result<FixedRender, String> {
        self.render_fixed_settings(w, h, preset.precision(), algorithm)
    }

    /// [`Self::render_fixed_with`] with any precision choices. Narrow arithmetic
    /// ([`SetupArith`] other than `Precise`) is built for the span z-buffer only.
    pub fn render_fixed_settings(
        &self,
        w: usize,
        h: usize,
        precision: Precision,
        algorithm: Algorithm,
    ) -> Result<FixedRender, String> {
        // The host workspaces are large (capacity for 2048×2048 and 65534 triangles) and the
        // library builds them by value, which in debug builds goes through the stack: render on
        // a thread with room for that.
        std::thread::scope(|scope| {
            std::thread::Builder::new()
                .stack_size(256 << 20)
                .spawn_scoped(scope, || {
                    if self.fits_one_pass() {
                        self.render_fixed_on_this_thread(w, h, precision, algorithm)
                    } else {
                        self.render_passes(w, h, precision, algorithm)
                    }
                })
                .map_err(|e| format!("cannot start render thread: {e}"))?
                .join()
                .map_err(|_| "render thread panicked".to_string())?
        })
    }

    /// Whether the library renders the scene in one frame: at most `MAX_INSTANCES` instances
    /// and `MAX_SCENE_TRIANGLES` triangles.
    pub fn fits_one_pass(&self) -> bool {
        self.instances.len() <= MAX_INSTANCES
            && self
                .instances
                .iter()
                .map(|i| i.mesh.triangles.len())
                .sum::<usize>()
                <= MAX_SCENE_TRIANGLES
    }

    /// Whether instance `i` may show in the camera's view: some corner of its bounding box is
    /// between the near and far planes and no side plane of the view has the whole box beyond
    /// it. Instances that cannot show are left out of multi-pass frames (where they would also
    /// cost eye-space envelope they do not need).
    fn may_show(&self, i: &MeshInstance, cam: &reference::Camera, aspect: f64) -> bool {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for v in &i.mesh.vertices {
            for k in 0..3 {
                lo[k] = lo[k].min(v[k].to_num::<f64>());
                hi[k] = hi[k].max(v[k].to_num::<f64>());
            }
        }
        let m = i.transform.m.map(|row| row.map(f64::from));
        let corners: Vec<[f64; 3]> = (0..8)
            .map(|c| {
                let p = [0, 1, 2].map(|k| if c >> k & 1 == 1 { hi[k] } else { lo[k] });
                let w =
                    [0, 1, 2].map(|r| m[r][0] * p[0] + m[r][1] * p[1] + m[r][2] * p[2] + m[r][3]);
                cam.eye_coords(w)
            })
            .collect();
        let ty = (self.camera.fovy.to_radians() / 2.0).tan();
        let tx = ty * aspect;
        let all = |f: &dyn Fn(&[f64; 3]) -> bool| corners.iter().all(f);
        !(all(&|e| e[2] < self.camera.near)
            || all(&|e| e[2] > self.camera.far)
            || all(&|e| e[0] > tx * e[2])
            || all(&|e| e[0] < -tx * e[2])
            || all(&|e| e[1] > ty * e[2])
            || all(&|e| e[1] < -ty * e[2]))
    }

    /// Renders a scene beyond one frame's limits in passes of at most `MAX_INSTANCES`
    /// instances and `MAX_SCENE_TRIANGLES` triangles (leaving out instances that cannot show),
    /// composited per pixel by depth, the earlier pass winning a tie. Only methods that keep
    /// depth can be composited.
    fn render_passes(
        &self,
        w: usize,
        h: usize,
        precision: Precision,
        algorithm: Algorithm,
    ) -> Result<FixedRender, String> {
        if !matches!(
            algorithm,
            Algorithm::SpanZBuffer | Algorithm::ZBuffer | Algorithm::Band(_)
        ) {
            return Err(format!(
                "this scene needs several passes ({} instances, {} triangles; one frame holds {MAX_INSTANCES} and {MAX_SCENE_TRIANGLES}), which only the depth-buffer methods composite, not {algorithm}",
                self.instances.len(),
                self.instances.iter().map(|i| i.mesh.triangles.len()).sum::<usize>()
            ));
        }
        let cam = self.camera.reference()?;
        let aspect = w as f64 / h as f64;
        // Triangle id of each instance's first triangle in the whole scene.
        let mut base = Vec::with_capacity(self.instances.len());
        let mut n = 0usize;
        for i in &self.instances {
            base.push(n);
            n += i.mesh.triangles.len();
        }
        let mut passes: Vec<Vec<usize>> = Vec::new();
        let mut tris = 0usize;
        for (k, inst) in self.instances.iter().enumerate() {
            if !self.may_show(inst, &cam, aspect) {
                continue;
            }
            let t = inst.mesh.triangles.len();
            match passes.last_mut() {
                Some(p) if p.len() < MAX_INSTANCES && tris + t <= MAX_SCENE_TRIANGLES => {
                    p.push(k);
                    tris += t;
                }
                _ => {
                    passes.push(vec![k]);
                    tris = t;
                }
            }
        }
        let mut image = Image {
            width: w,
            height: h,
            ids: vec![-1; w * h],
            depth: vec![f32::INFINITY; w * h],
            color: vec![[0; 3]; w * h],
        };
        let mut stats = FrameStats::default();
        for pass in &passes {
            let spec = SceneSpec {
                instances: pass.iter().map(|&k| self.instances[k].clone()).collect(),
                camera: self.camera,
                light: self.light,
                cull_back_faces: self.cull_back_faces,
            };
            let r = spec.render_fixed_on_this_thread(w, h, precision, algorithm)?;
            // Pass-local id -> scene id.
            let mut starts = Vec::new();
            let mut local = 0usize;
            for &k in pass {
                starts.push((local, base[k]));
                local += self.instances[k].mesh.triangles.len();
            }
            for p in 0..w * h {
                let (id, d) = (r.image.ids[p], r.image.depth[p]);
                // NaN depth (none kept) never wins; an equal depth keeps the earlier pass.
                if id < 0 || d.partial_cmp(&image.depth[p]) != Some(std::cmp::Ordering::Less) {
                    continue;
                }
                let at = starts.partition_point(|s| s.0 <= id as usize) - 1;
                let (first_local, first_scene) = starts[at];
                image.ids[p] = (id as usize - first_local + first_scene) as i32;
                image.depth[p] = d;
                image.color[p] = r.image.color[p];
            }
            let s = r.stats;
            stats.triangles_in += s.triangles_in;
            stats.culled += s.culled;
            stats.clipped += s.clipped;
            stats.rejected += s.rejected;
            stats.bucketed = stats.bucketed.max(s.bucketed);
            stats.activated += s.activated;
            stats.spans += s.spans;
            stats.fragments += s.fragments;
            stats.pixels_written = stats.pixels_written.max(s.pixels_written);
            stats.peak_active = stats.peak_active.max(s.peak_active);
            stats.peak_spans = stats.peak_spans.max(s.peak_spans);
            stats.dropped += s.dropped;
        }
        Ok(FixedRender { image, stats })
    }

    /// The library's view of each instance's mesh (validated).
    fn meshes(&self) -> Result<Vec<Mesh<'_>>, String> {
        self.instances.iter().map(|i| i.mesh.mesh()).collect()
    }

    /// Library instances of `meshes` (from [`Self::meshes`]) with this scene's transforms.
    fn library_instances<'a>(&self, meshes: &'a [Mesh<'a>]) -> Vec<Instance<'a>> {
        meshes
            .iter()
            .zip(&self.instances)
            .map(|(mesh, i)| Instance {
                mesh,
                transform: i.transform,
            })
            .collect()
    }

    /// Hash of the frame as the firmware's hashing panel model receives it: RGB565 rows on a
    /// black background, flat shading, 4 sub-pixel bits ([`scanline3d::sink::HashSink`]).
    /// Firmware that renders the same scene must print the same hash.
    pub fn panel_hash(&self, w: usize, h: usize) -> Result<u32, String> {
        self.panel_hash_with(w, h, Algorithm::SpanZBuffer)
    }

    /// [`panel_hash`](Self::panel_hash) of the frame `algorithm` renders (for BSP, in the order
    /// of the tree [`crate::bsp::build`] makes, which `sim export --bsp` exports).
    pub fn panel_hash_with(&self, w: usize, h: usize, algorithm: Algorithm) -> Result<u32, String> {
        std::thread::scope(|scope| {
            std::thread::Builder::new()
                .stack_size(64 << 20)
                .spawn_scoped(scope, || self.panel_hash_on_this_thread(w, h, algorithm))
                .map_err(|e| format!("cannot start render thread: {e}"))?
                .join()
                .map_err(|_| "render thread panicked".to_string())?
        })
    }

    fn panel_hash_on_this_thread(
        &self,
        w: usize,
        h: usize,
        algorithm: Algorithm,
    ) -> Result<u32, String> {
        use embedded_graphics::pixelcolor::Rgb565;
        let bsp = self.bsp_for(algorithm)?;
        let tree = bsp.as_ref().map(Bsp::tree).transpose()?;
        let meshes = match &bsp {
            Some(b) => vec![b.mesh.mesh()?],
            None => self.meshes()?,
        };
        let instances = self.library_instances(&meshes);
        let scene = Scene {
            instances: &instances,
            camera: self.camera.fixed()?,
            light: self.light.fixed()?,
        };
        let mut sink = scanline3d::sink::HashSink::new();
        let options = RenderOptions::default().with_back_face_culling(self.cull_back_faces);
        let target = Target::new(
            algorithm,
            tree.as_ref(),
            Rgb565::new(0, 0, 0),
            (w, h),
            &mut sink,
        );
        Precise::render(target, &scene, &options)?;
        Ok(sink.hash())
    }

    /// The BSP tree `algorithm` renders with (built here), if it is [`Algorithm::Bsp`].
    fn bsp_for(&self, algorithm: Algorithm) -> Result<Option<Bsp>, String> {
        if algorithm != Algorithm::Bsp {
            return Ok(None);
        }
        let [instance] = self.instances.as_slice() else {
            return Err("bsp renders scenes of one mesh".into());
        };
        crate::bsp::build(&instance.mesh).map(Some)
    }

    fn render_fixed_on_this_thread(
        &self,
        w: usize,
        h: usize,
        precision: Precision,
        algorithm: Algorithm,
    ) -> Result<FixedRender, String> {
        use scanline3d::arithmetic::Quick;
        let p = precision;
        macro_rules! bits {
            ($a:ty) => {
                match precision.sub_bits {
                    0 => self.render_fixed_s::<0, $a>(w, h, p, algorithm),
                    2 => self.render_fixed_s::<2, $a>(w, h, p, algorithm),
                    4 => self.render_fixed_s::<4, $a>(w, h, p, algorithm),
                    8 => self.render_fixed_s::<8, $a>(w, h, p, algorithm),
                    _ => Err(format!(
                        "sub-pixel bits must be one of {SUB_PIXEL_CHOICES:?}"
                    )),
                }
            };
        }
        match precision.arith {
            SetupArith::Precise => bits!(Precise),
            SetupArith::Quick => bits!(Quick),
            SetupArith::Frugal => bits!(scanline3d::arithmetic::Frugal),
            SetupArith::NarrowTransform => {
                bits!(Setup<NarrowTransform, ExactDivision, WideNormals>)
            }
            SetupArith::Reciprocal => bits!(Setup<WideTransform, Reciprocal, WideNormals>),
            SetupArith::NarrowNormals => bits!(Setup<WideTransform, ExactDivision, NarrowNormals>),
        }
    }

    fn render_fixed_s<const S: u32, A: Dispatch>(
        &self,
        w: usize,
        h: usize,
        precision: Precision,
        algorithm: Algorithm,
    ) -> Result<FixedRender, String> {
        let max = algorithm.max_size();
        if w == 0 || h == 0 || w > max || h > max {
            return Err(format!(
                "size {w}x{h} outside 1x1..{max}x{max} for {algorithm}"
            ));
        }
        // BSP order renders the split mesh of a tree built here, then maps ids back.
        let bsp = self.bsp_for(algorithm)?;
        let tree = bsp.as_ref().map(Bsp::tree).transpose()?;
        let meshes = match &bsp {
            Some(b) => vec![b.mesh.mesh()?],
            None => self.meshes()?,
        };
        let instances = self.library_instances(&meshes);
        let camera = self.camera.fixed_with(precision.math)?;
        let scene = Scene {
            instances: &instances,
            camera,
            light: self.light.fixed()?,
        };
        let mut image = Image {
            width: w,
            height: h,
            ids: vec![-1; w * h],
            depth: vec![f32::INFINITY; w * h],
            color: vec![[0; 3]; w * h],
        };
        let options = RenderOptions::default()
            .with_back_face_culling(self.cull_back_faces)
            .with_sub_pixel_bits::<S>()
            .with_arithmetic(A::default());
        let mut target = RgbImage {
            width: w,
            height: h,
            pixels: vec![[0; 3]; w * h],
        };
        let stats = {
            let mut display = scanline3d::sink::DrawTargetSink::new(&mut target);
            let mut sink = FnSink(|row: Row<'_, Rgb888>| {
                scanline3d::sink::RowSink::write_row(&mut display, row)
            });
            let target = Target::new(algorithm, tree.as_ref(), Rgb888::BLACK, (w, h), &mut sink)
                .with_depth(precision.depth);
            A::render(target, &scene, &options)?
        };
        image.color = target.pixels;
        // The id pass also records depth (NaN over surfaces where the method keeps none).
        let mut sink = FnSink(|row: Row<'_, TriangleId>| -> Result<(), Infallible> {
            let at = row.y as usize * w;
            for (x, id) in row.pixels.iter().enumerate() {
                image.ids[at + x] = id.0;
                image.depth[at + x] = match row.depth.get(x) {
                    Some(q) => camera.eye_distance(q).unwrap_or(f32::INFINITY),
                    None if id.0 >= 0 => f32::NAN,
                    None => f32::INFINITY,
                };
            }
            Ok(())
        });
        let target = Target::new(
            algorithm,
            tree.as_ref(),
            TriangleId::NONE,
            (w, h),
            &mut sink,
        )
        .with_depth(precision.depth);
        A::render(target, &scene, &options)?;
        if let Some(b) = &bsp {
            for id in image.ids.iter_mut().filter(|id| **id >= 0) {
                *id = b.origin[*id as usize] as i32;
            }
        }
        Ok(FixedRender { image, stats })
    }
}

/// Math backend of the per-frame set-up (`scanline3d::math`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SetupMath {
    /// [`Libm`]: accurate (the default).
    Libm,
    /// [`Micromath`]: approximate, smaller.
    Micromath,
}

/// Set-up arithmetic (`scanline3d::arithmetic::Arithmetic`), chosen at run time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SetupArith {
    /// [`scanline3d::arithmetic::Precise`]: the default.
    Precise,
    /// [`scanline3d::arithmetic::Quick`]: narrow at every stage.
    Quick,
    /// [`scanline3d::arithmetic::Frugal`]: reciprocal projection and narrow normals.
    Frugal,
    /// Precise but for the transform (`vertex::NarrowTransform`).
    NarrowTransform,
    /// Precise but for the projection (`project::Reciprocal`).
    Reciprocal,
    /// Precise but for the lighting normals (`math::NarrowNormals`).
    NarrowNormals,
}

impl SetupArith {
    /// Name in the trade-off table.
    pub fn name(self) -> &'static str {
        match self {
            SetupArith::Precise => "precise",
            SetupArith::Quick => "quick",
            SetupArith::Frugal => "frugal",
            SetupArith::NarrowTransform => "narrow transform",
            SetupArith::Reciprocal => "reciprocal projection",
            SetupArith::NarrowNormals => "narrow normals",
        }
    }

    /// The error it adds to the precise arithmetic's, as documented in the library, for a
    /// `w × h` screen and a scene whose largest model coordinate is `max_model_coord`.
    pub fn documented_error(self, w: usize, h: usize, max_model_coord: f64) -> ArithmeticError {
        let narrow_transform = matches!(self, SetupArith::Quick | SetupArith::NarrowTransform);
        let reciprocal = matches!(
            self,
            SetupArith::Quick | SetupArith::Frugal | SetupArith::Reciprocal
        );
        // The guard band's corner is 4 screen sizes from the centre in x and y.
        let corner = 4.0 * (w.max(h) as f64) * std::f64::consts::SQRT_2;
        ArithmeticError {
            depth_q: 0.0,
            px: if reciprocal {
                2f64.powi(-14) * corner
            } else {
                0.0
            },
            eye_units: if narrow_transform {
                3.0 * 2f64.powi(-13) * max_model_coord
            } else {
                0.0
            },
        }
    }
}

/// Depth format of the z-buffer (`scanline3d::depth`), chosen at run time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DepthChoice {
    /// `scanline3d::Depth`, 32 bits: the default.
    Q30,
    /// `scanline3d::depth::Depth16`, 16 bits.
    Q16,
}

impl DepthChoice {
    /// Name in the trade-off table.
    pub fn name(self) -> &'static str {
        match self {
            DepthChoice::Q30 => "32-bit",
            DepthChoice::Q16 => "16-bit",
        }
    }

    /// Its documented resolution in `q = near / w` (`DepthFormat::RESOLUTION`).
    pub fn resolution(self) -> f64 {
        match self {
            DepthChoice::Q30 => <Depth as DepthFormat>::RESOLUTION,
            DepthChoice::Q16 => <Depth16 as DepthFormat>::RESOLUTION,
        }
    }
}

/// Every precision choice of one render.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Precision {
    /// Sub-pixel bits (0, 2, 4 or 8).
    pub sub_bits: u32,
    /// Per-frame set-up math.
    pub math: SetupMath,
    /// Per-vertex and per-triangle set-up arithmetic.
    pub arith: SetupArith,
    /// Depth format of the z-buffer.
    pub depth: DepthChoice,
}

impl Precision {
    /// The default but for the sub-pixel bits.
    pub const fn bits(sub_bits: u32) -> Precision {
        Precision {
            sub_bits,
            math: SetupMath::Libm,
            arith: SetupArith::Precise,
            depth: DepthChoice::Q30,
        }
    }

    /// The error these choices add to the default's, as the library documents it, for a
    /// `w × h` screen and a scene whose largest model coordinate is `max_model_coord`.
    pub fn documented_error(self, w: usize, h: usize, max_model_coord: f64) -> ArithmeticError {
        ArithmeticError {
            depth_q: self.depth.resolution(),
            ..self.arith.documented_error(w, h, max_model_coord)
        }
    }
}

/// A precision preset of `scanline3d::preset`, chosen at run time (`sim render --preset`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PresetChoice {
    /// [`preset::Fast`].
    Fast,
    /// [`preset::Balanced`].
    Balanced,
    /// [`preset::Exact`].
    Exact,
}

impl PresetChoice {
    /// Every preset, fastest first.
    pub const ALL: [PresetChoice; 3] = [
        PresetChoice::Fast,
        PresetChoice::Balanced,
        PresetChoice::Exact,
    ];

    /// Its name in `scanline3d::preset`.
    pub fn name(self) -> &'static str {
        match self {
            PresetChoice::Fast => preset::Fast::NAME,
            PresetChoice::Balanced => preset::Balanced::NAME,
            PresetChoice::Exact => preset::Exact::NAME,
        }
    }

    /// Its sub-pixel bits.
    pub fn sub_bits(self) -> u32 {
        match self {
            PresetChoice::Fast => preset::Fast::SUB_BITS,
            PresetChoice::Balanced => preset::Balanced::SUB_BITS,
            PresetChoice::Exact => preset::Exact::SUB_BITS,
        }
    }

    /// All its precision choices.
    pub fn precision(self) -> Precision {
        Precision {
            sub_bits: self.sub_bits(),
            math: self.math(),
            arith: self.arith(),
            depth: DepthChoice::Q30,
        }
    }

    /// Its set-up arithmetic.
    pub fn arith(self) -> SetupArith {
        fn of<P: Preset>() -> SetupArith {
            use std::any::TypeId;
            let a = TypeId::of::<P::Arithmetic>();
            if a == TypeId::of::<scanline3d::arithmetic::Precise>() {
                SetupArith::Precise
            } else if a == TypeId::of::<scanline3d::preset::FastArithmetic>() {
                SetupArith::NarrowTransform
            } else {
                unreachable!("presets use Precise arithmetic or Fast's")
            }
        }
        match self {
            PresetChoice::Fast => of::<preset::Fast>(),
            PresetChoice::Balanced => of::<preset::Balanced>(),
            PresetChoice::Exact => of::<preset::Exact>(),
        }
    }

    /// Its set-up math.
    pub fn math(self) -> SetupMath {
        fn of<P: Preset>() -> SetupMath {
            if P::Math::NAME == Micromath::NAME {
                SetupMath::Micromath
            } else {
                SetupMath::Libm
            }
        }
        match self {
            PresetChoice::Fast => of::<preset::Fast>(),
            PresetChoice::Balanced => of::<preset::Balanced>(),
            PresetChoice::Exact => of::<preset::Exact>(),
        }
    }
}

impl std::fmt::Display for PresetChoice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for PresetChoice {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        PresetChoice::ALL
            .into_iter()
            .find(|p| p.name() == s)
            .ok_or_else(|| {
                format!(
                    "unknown preset '{s}'; choose one of {}",
                    preset::NAMES.join(", ")
                )
            })
    }
}

/// A hidden-surface method of the fixed-point pipeline, as `sim render --algorithm` names it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Algorithm {
    /// One row of depth ([`Workspace`]): the default.
    SpanZBuffer,
    /// Full-frame z-buffer ([`ZBufferWorkspace`]).
    ZBuffer,
    /// Z-buffer over bands of this many rows ([`BandWorkspace`]), one of [`BAND_CHOICES`].
    Band(usize),
    /// Painter's algorithm by mean depth ([`DepthSortWorkspace`]).
    DepthSort,
    /// Span sorting, no depth memory ([`SpanSortWorkspace`]).
    SpanSort,
    /// Painter's algorithm in the order of a BSP tree built for the scene's one mesh
    /// ([`BspWorkspace`], tree from [`crate::bsp::build`]).
    Bsp,
    /// Warnock's area subdivision ([`WarnockWorkspace`]).
    Warnock,
    /// Newell–Newell–Sancha depth sort, splitting where needed ([`NewellWorkspace`]).
    Newell,
}

/// Band heights `band:N` accepts (the band is a compile-time capacity).
pub const BAND_CHOICES: [usize; 8] = [1, 2, 4, 8, 16, 32, 64, 128];
/// Largest target of the full-frame z-buffer and Warnock in `sim` (they keep W·H pixels).
pub const ZBUFFER_MAX_SIZE: usize = 1024;

impl Algorithm {
    /// Every method `sim` offers (bands at 16 rows), for tables and tests.
    pub const ALL: [Algorithm; 8] = [
        Algorithm::SpanZBuffer,
        Algorithm::ZBuffer,
        Algorithm::Band(16),
        Algorithm::DepthSort,
        Algorithm::SpanSort,
        Algorithm::Bsp,
        Algorithm::Warnock,
        Algorithm::Newell,
    ];

    /// Whether the method is exact by design (all but the simple depth sort).
    pub fn is_exact(self) -> bool {
        self != Algorithm::DepthSort
    }

    fn max_size(self) -> usize {
        match self {
            Algorithm::ZBuffer | Algorithm::Warnock => ZBUFFER_MAX_SIZE,
            _ => MAX_SIZE,
        }
    }
}

impl std::fmt::Display for Algorithm {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Algorithm::SpanZBuffer => write!(f, "span-zbuffer"),
            Algorithm::ZBuffer => write!(f, "zbuffer"),
            Algorithm::Band(n) => write!(f, "band:{n}"),
            Algorithm::DepthSort => write!(f, "depth-sort"),
            Algorithm::SpanSort => write!(f, "span-sort"),
            Algorithm::Bsp => write!(f, "bsp"),
            Algorithm::Warnock => write!(f, "warnock"),
            Algorithm::Newell => write!(f, "newell"),
        }
    }
}

impl std::str::FromStr for Algorithm {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let choices = "span-zbuffer, zbuffer, band:N (N in 1,2,4,...,128), depth-sort, newell, bsp, span-sort, warnock, raycast (the f64 reference)";
        match s {
            "span-zbuffer" => Ok(Algorithm::SpanZBuffer),
            "zbuffer" => Ok(Algorithm::ZBuffer),
            "depth-sort" => Ok(Algorithm::DepthSort),
            "span-sort" => Ok(Algorithm::SpanSort),
            "bsp" => Ok(Algorithm::Bsp),
            "warnock" => Ok(Algorithm::Warnock),
            "newell" => Ok(Algorithm::Newell),
            _ => match s.strip_prefix("band:").map(str::parse::<usize>) {
                Some(Ok(n)) if BAND_CHOICES.contains(&n) => Ok(Algorithm::Band(n)),
                Some(_) => Err(format!("band height must be one of {BAND_CHOICES:?}")),
                None => Err(format!("unknown algorithm '{s}'; choose one of {choices}")),
            },
        }
    }
}

// Host capacities: up to 65534 triangles, 4096 crossing one row.
const TRIS: usize = 65534;
const ACTIVE: usize = 4096;
/// BSP traversal stack: enough for a chain as deep as the largest mesh.
const BSP_STACK: usize = 2 * 65535 + 1;

/// Renders with arithmetic `Self`: every method for the precise default, the span z-buffer
/// alone for the narrow ones (which exist to be measured; this keeps the tools' build small).
trait Dispatch: Arithmetic + 'static {
    fn render<P: RowPixel, const S: u32, K: RowSink<P, Error: Debug>>(
        target: Target<'_, P, K>,
        scene: &Scene<'_>,
        options: &RenderOptions<S, FrustumClip, Self>,
    ) -> Result<FrameStats, String>;
}

/// Where and how a frame is rendered: method, BSP tree (for [`Algorithm::Bsp`]), background,
/// size and sink.
struct Target<'a, P, K> {
    algorithm: Algorithm,
    depth: DepthChoice,
    tree: Option<&'a BspTree<'a>>,
    background: P,
    size: (usize, usize),
    sink: &'a mut K,
}

impl<'a, P, K> Target<'a, P, K> {
    fn new(
        algorithm: Algorithm,
        tree: Option<&'a BspTree<'a>>,
        background: P,
        size: (usize, usize),
        sink: &'a mut K,
    ) -> Self {
        Target {
            algorithm,
            depth: DepthChoice::Q30,
            tree,
            background,
            size,
            sink,
        }
    }

    /// The same with depth format `depth`.
    fn with_depth(self, depth: DepthChoice) -> Self {
        Target { depth, ..self }
    }
}

/// The error for a depth format a method is not built with.
fn depth_unsupported(algorithm: Algorithm) -> String {
    format!(
        "16-bit depth is built for {} and {} only, not {algorithm}",
        Algorithm::SpanZBuffer,
        Algorithm::ZBuffer
    )
}

/// Every method, through the workspace of `algorithm` (built here, with host-sized capacities).
impl Dispatch for Precise {
    fn render<P: RowPixel, const S: u32, K: RowSink<P, Error: Debug>>(
        t: Target<'_, P, K>,
        scene: &Scene<'_>,
        options: &RenderOptions<S>,
    ) -> Result<FrameStats, String> {
        let Target {
            algorithm,
            depth,
            tree,
            background,
            size: (w, h),
            sink,
        } = t;
        const M: usize = MAX_SIZE;
        const Z: usize = ZBUFFER_MAX_SIZE;
        const I: usize = MAX_INSTANCES;
        macro_rules! with {
            ($ws:ty) => {{
                let mut ws: Box<$ws> = Box::new(<$ws>::new(background));
                ws.render_sized(w, h, scene, options, sink)
            }};
        }
        match (depth, algorithm) {
            (DepthChoice::Q30, _) => {}
            (DepthChoice::Q16, Algorithm::SpanZBuffer) => {
                return with!(Workspace<P, Flat, M, M, TRIS, ACTIVE, I, Depth16>)
                    .map_err(|e| e.to_string())
            }
            (DepthChoice::Q16, Algorithm::ZBuffer) => {
                return with!(ZBufferWorkspace<P, Flat, Z, Z, TRIS, I, Depth16>)
                    .map_err(|e| e.to_string())
            }
            (DepthChoice::Q16, _) => return Err(depth_unsupported(algorithm)),
        }
        match algorithm {
            Algorithm::SpanZBuffer => with!(Workspace<P, Flat, M, M, TRIS, ACTIVE>),
            Algorithm::ZBuffer => with!(ZBufferWorkspace<P, Flat, Z, Z, TRIS>),
            Algorithm::Band(1) => with!(BandWorkspace<P, Flat, M, M, 1, TRIS, ACTIVE>),
            Algorithm::Band(2) => with!(BandWorkspace<P, Flat, M, M, 2, TRIS, ACTIVE>),
            Algorithm::Band(4) => with!(BandWorkspace<P, Flat, M, M, 4, TRIS, ACTIVE>),
            Algorithm::Band(8) => with!(BandWorkspace<P, Flat, M, M, 8, TRIS, ACTIVE>),
            Algorithm::Band(16) => with!(BandWorkspace<P, Flat, M, M, 16, TRIS, ACTIVE>),
            Algorithm::Band(32) => with!(BandWorkspace<P, Flat, M, M, 32, TRIS, ACTIVE>),
            Algorithm::Band(64) => with!(BandWorkspace<P, Flat, M, M, 64, TRIS, ACTIVE>),
            Algorithm::Band(128) => with!(BandWorkspace<P, Flat, M, M, 128, TRIS, ACTIVE>),
            Algorithm::Band(n) => {
                return Err(format!(
                    "band height must be one of {BAND_CHOICES:?}, not {n}"
                ))
            }
            Algorithm::DepthSort => with!(DepthSortWorkspace<P, Flat, M, M, TRIS, ACTIVE>),
            Algorithm::SpanSort => with!(SpanSortWorkspace<P, Flat, M, M, TRIS, ACTIVE>),
            Algorithm::Bsp => {
                let tree = tree.ok_or("bsp needs a tree")?;
                type Ws<P> = BspWorkspace<P, Flat, M, M, TRIS, ACTIVE, BSP_STACK>;
                let mut ws: Box<Ws<P>> = Box::new(Ws::new(background));
                ws.render_sized(w, h, scene, tree, options, sink)
            }
            Algorithm::Warnock => {
                const STACK: usize = warnock::stack_needed(Z, Z);
                with!(WarnockWorkspace<P, Flat, Z, Z, TRIS, ACTIVE, STACK>)
            }
            Algorithm::Newell => with!(NewellWorkspace<P, Flat, M, M, TRIS, ACTIVE>),
        }
        .map_err(|e| e.to_string())
    }
}

/// The narrow arithmetics: span z-buffer only.
macro_rules! span_zbuffer_only {
    ($($a:ty),*) => {$(
        impl Dispatch for $a {
            fn render<P: RowPixel, const S: u32, K: RowSink<P, Error: Debug>>(
                t: Target<'_, P, K>,
                scene: &Scene<'_>,
                options: &RenderOptions<S, FrustumClip, Self>,
            ) -> Result<FrameStats, String> {
                let Target { algorithm, depth, background, size: (w, h), sink, .. } = t;
                if algorithm != Algorithm::SpanZBuffer {
                    return Err(format!(
                        "narrow set-up arithmetic is built for {} only",
                        Algorithm::SpanZBuffer
                    ));
                }
                type Ws<P, Z> =
                    Workspace<P, Flat, MAX_SIZE, MAX_SIZE, TRIS, ACTIVE, MAX_INSTANCES, Z>;
                match depth {
                    DepthChoice::Q30 => {
                        let mut ws: Box<Ws<P, Depth>> = Box::new(Ws::new(background));
                        ws.render_sized(w, h, scene, options, sink)
                    }
                    DepthChoice::Q16 => {
                        let mut ws: Box<Ws<P, Depth16>> = Box::new(Ws::new(background));
                        ws.render_sized(w, h, scene, options, sink)
                    }
                }
                .map_err(|e| e.to_string())
            }
        }
    )*};
}

span_zbuffer_only!(
    scanline3d::arithmetic::Quick,
    scanline3d::arithmetic::Frugal,
    Setup<NarrowTransform, ExactDivision, WideNormals>,
    Setup<WideTransform, Reciprocal, WideNormals>,
    Setup<WideTransform, ExactDivision, NarrowNormals>
);

/// An RGB image as an embedded-graphics `DrawTarget`: the colour pass reaches it through
/// [`scanline3d::sink::DrawTargetSink`], the same path a display takes on firmware.
pub struct RgbImage {
    /// Width.
    pub width: usize,
    /// Height.
    pub height: usize,
    /// Pixels, row-major from the top.
    pub pixels: Vec<[u8; 3]>,
}

impl embedded_graphics::geometry::OriginDimensions for RgbImage {
    fn size(&self) -> embedded_graphics::geometry::Size {
        embedded_graphics::geometry::Size::new(self.width as u32, self.height as u32)
    }
}

impl embedded_graphics::draw_target::DrawTarget for RgbImage {
    type Color = Rgb888;
    type Error = std::convert::Infallible;
    fn draw_iter<I: IntoIterator<Item = embedded_graphics::Pixel<Rgb888>>>(
        &mut self,
        pixels: I,
    ) -> Result<(), Self::Error> {
        for embedded_graphics::Pixel(p, c) in pixels {
            if p.x >= 0 && p.y >= 0 && (p.x as usize) < self.width && (p.y as usize) < self.height {
                self.pixels[p.y as usize * self.width + p.x as usize] = [c.r(), c.g(), c.b()];
            }
        }
        Ok(())
    }
}

/// Writes an RGB image as PNG.
pub fn write_png(path: &Path, w: usize, h: usize, rgb: &[[u8; 3]]) -> Result<(), String> {
    let file = std::fs::File::create(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), w as u32, h as u32);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let data: Vec<u8> = rgb.iter().flatten().copied().collect();
    encoder
        .write_header()
        .and_then(|mut wr| wr.write_image_data(&data))
        .map_err(|e| format!("{}: {e}", path.display()))
}

/// Writes an id image: W×H little-endian i32, row-major from the top, −1 = background.
pub fn write_ids(path: &Path, ids: &[i32]) -> Result<(), String> {
    let bytes: Vec<u8> = ids.iter().flat_map(|v| v.to_le_bytes()).collect();
    std::fs::write(path, bytes).map_err(|e| format!("{}: {e}", path.display()))
}

/// Writes a depth image: W×H little-endian f32 eye depth, +inf = background.
pub fn write_depth(path: &Path, depth: &[f32]) -> Result<(), String> {
    let bytes: Vec<u8> = depth.iter().flat_map(|v| v.to_le_bytes()).collect();
    std::fs::write(path, bytes).map_err(|e| format!("{}: {e}", path.display()))
}

fn read_words(path: &Path, n: usize) -> Result<Vec<[u8; 4]>, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    if bytes.len() != 4 * n {
        return Err(format!(
            "{}: expected {} bytes for the given size, found {}",
            path.display(),
            4 * n,
            bytes.len()
        ));
    }
    Ok(bytes.chunks(4).map(|c| [c[0], c[1], c[2], c[3]]).collect())
}

/// Reads an id image of `n` pixels.
pub fn read_ids(path: &Path, n: usize) -> Result<Vec<i32>, String> {
    Ok(read_words(path, n)?
        .into_iter()
        .map(i32::from_le_bytes)
        .collect())
}

/// Reads a depth image of `n` pixels.
pub fn read_depth(path: &Path, n: usize) -> Result<Vec<f32>, String> {
    Ok(read_words(path, n)?
        .into_iter()
        .map(f32::from_le_bytes)
        .collect())
}

/// The shortest literal that parses back to exactly `v as f32` (the value the host uses), for
/// the exports' Rust source.
pub(crate) fn f32_literal(v: f64) -> String {
    let s = format!("{:?}", v as f32);
    if s.contains('.') || s.contains('e') {
        s
    } else {
        format!("{s}.0")
    }
}
