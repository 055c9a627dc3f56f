//! The peer renderers a user would otherwise pick — [`euc`] and [`embedded_3dgfx`] — rendering
//! the same scenes, with the same camera and the same back-face choice, into id images that
//! [`crate::metrics::compare`] judges against the f64 reference exactly as it judges ours.
//!
//! Neither peer has an id output, so each renders per-triangle colours that encode the triangle
//! id and the image is decoded: euc's fragment shader returns the id (carried as a flat `f32`
//! attribute on all three vertices), embedded-3dgfx draws each triangle as its own mesh whose
//! Rgb565 colour is `id + 1` (its solid mode has one colour per mesh; 16 bits hold every
//! corpus id). Depth: euc's depth buffer holds NDC z, converted back to eye distance;
//! embedded-3dgfx's holds `trunc(ndc_z · (far − near) + near)` in 16.16 (negative values
//! saturate to 0), which cannot be turned back into a distance, so its depth image is NaN over
//! surfaces (`metrics::compare` skips NaN depth).
//!
//! Set-up a user does once (mesh conversion, world-space vertices, per-triangle meshes, the
//! camera matrices) is in the `new` functions; the `render_*` functions are one frame.
//!
//! What each peer can and cannot do is data: [`Peer::capabilities`].

use crate::metrics::{self, ErrorBound, Metrics};
use crate::reference::{self, Image};
use crate::scene::{Algorithm, PresetChoice, SceneSpec};
use embedded_3dgfx::pipeline::command_buffer::CommandBuffer;
use embedded_3dgfx::pipeline::renderer::FrameCtx;
use embedded_3dgfx::pipeline::vertex::mesh::{Geometry, K3dMesh, RenderMode};
use embedded_graphics::pixelcolor::raw::{RawData, RawU16};
use embedded_graphics::pixelcolor::Rgb565;
use embedded_graphics::prelude::{DrawTarget, OriginDimensions, Pixel, Size};
use euc::buffer::Buffer2d;
use euc::rasterizer::{BackfaceCullingDisabled, BackfaceCullingEnabled, Triangles};
use euc::{Pipeline, Target};

/// Exact versions these results were measured with (pinned in `sim/Cargo.toml`).
pub const EUC_VERSION: &str = "0.5.3";
/// See [`EUC_VERSION`].
pub const EMBEDDED_3DGFX_VERSION: &str = "0.7.2";

/// A peer renderer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Peer {
    /// `euc`: a software rasterizer with programmable shaders (f32, needs `alloc`).
    Euc,
    /// `embedded-3dgfx`: a `no_std` 3D engine for embedded-graphics displays.
    Embedded3dgfx,
}

/// What a peer does at each step that decides which pixel shows which triangle.
#[derive(Clone, Copy, Debug)]
pub struct Capabilities {
    /// Crate name.
    pub name: &'static str,
    /// Crate version.
    pub version: &'static str,
    /// Clips at the near plane (triangles with vertices behind the eye render correctly).
    pub near_clip: bool,
    /// How the near plane is handled.
    pub near: &'static str,
    /// How the far plane is handled.
    pub far: &'static str,
    /// Depth buffer and test.
    pub depth: &'static str,
    /// Vertex position precision on screen.
    pub sub_pixel: &'static str,
    /// Which pixel centres a triangle covers.
    pub fill_rule: &'static str,
    /// Back-face culling.
    pub back_faces: &'static str,
    /// Per-triangle colours (how the id image is made).
    pub colours: &'static str,
    /// Camera set-up.
    pub camera: &'static str,
}

impl Peer {
    /// Every peer.
    pub const ALL: [Peer; 2] = [Peer::Euc, Peer::Embedded3dgfx];

    /// Short name (bench ids, tables).
    pub fn name(self) -> &'static str {
        match self {
            Peer::Euc => "euc",
            Peer::Embedded3dgfx => "embedded-3dgfx",
        }
    }

    /// What this peer does, read from its source at the pinned version.
    pub fn capabilities(self) -> Capabilities {
        match self {
            Peer::Euc => Capabilities {
                name: "euc",
                version: EUC_VERSION,
                near_clip: false,
                near: "none: vertices are divided by w with no clipping, so a triangle with a \
                       vertex behind the eye gets a mirrored bounding box and is drawn wrongly \
                       or lost; fragments nearer than the near plane are drawn",
                far: "none in the rasterizer; the depth buffer cleared to 1.0 (NDC far) rejects \
                      fragments beyond it",
                depth: "f32 NDC z, perspective-correct, test `z <= stored` (IfLessWrite): \
                        equal depths go to the triangle drawn last",
                sub_pixel: "f32 throughout (no snapping): per-pixel homogeneous barycentrics",
                fill_rule: "none: a centre on an edge is inside both triangles \
                            (inclusive barycentric test), so shared edges are drawn twice",
                back_faces: "optional, by the sign of the NDC-space area (CCW front, as GL)",
                colours: "per-vertex attributes; the id is a flat f32 attribute returned by \
                          the fragment shader",
                camera: "any 4×4 clip matrix from the vertex shader (gluLookAt · gluPerspective \
                         built here)",
            },
            Peer::Embedded3dgfx => Capabilities {
                name: "embedded-3dgfx",
                version: EMBEDDED_3DGFX_VERSION,
                near_clip: true,
                near: "clipped (Sutherland–Hodgman against w = near, then the four side planes)",
                far: "not clipped for solid triangles: geometry beyond the far plane is drawn",
                depth: "u32 z-buffer of trunc(ndc_z · (far − near) + near) · 65536: whole-unit \
                        depth steps per vertex, negative values (the near half of NDC) \
                        saturate to 0, test `z < stored + 128` so near-ties go to the \
                        triangle drawn last",
                sub_pixel: "none: projected vertices are truncated to whole pixels",
                fill_rule: "none: spans are inclusive at both ends and the split row of each \
                            triangle is drawn by both halves (overdraw, fat edges)",
                back_faces: "only with face normals supplied (camera-to-vertex dot normal); \
                             without normals nothing is culled",
                colours: "one colour per mesh in solid mode (per-vertex colours are for point \
                          clouds only), so per-face colours need one mesh per triangle",
                camera: "position, target, vertical fov, near/far; up is fixed to +y (a rolled \
                         camera is set through the public view/vp matrices)",
            },
        }
    }

    /// Renders `spec` at `w × h` into an id image (ids per pixel, −1 background).
    pub fn render(self, spec: &SceneSpec, w: usize, h: usize) -> Result<Image, String> {
        match self {
            Peer::Euc => Ok(EucScene::new(spec, w, h)?.render_ids()),
            Peer::Embedded3dgfx => {
                let scene = E3dScene::new(spec, w, h)?;
                let meshes = scene.id_meshes();
                scene.render_ids(&meshes)
            }
        }
    }
}

type M4 = [[f64; 4]; 4];

fn mul(a: &M4, b: &M4) -> M4 {
    let mut m = [[0.0; 4]; 4];
    for (r, row) in m.iter_mut().enumerate() {
        for (c, v) in row.iter_mut().enumerate() {
            *v = (0..4).map(|k| a[r][k] * b[k][c]).sum();
        }
    }
    m
}

/// `gluPerspective(fovy, w/h, near, far) · gluLookAt(eye, target, up)` in f64.
pub fn clip_matrix(spec: &SceneSpec, w: usize, h: usize) -> Result<M4, String> {
    let c = &spec.camera;
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let f = reference::normalize(sub(c.target, c.eye)).ok_or("eye == target")?;
    let s = reference::normalize(reference::cross(f, c.up)).ok_or("up parallel to view")?;
    let u = reference::cross(s, f);
    let d = reference::dot;
    let view = [
        [s[0], s[1], s[2], -d(s, c.eye)],
        [u[0], u[1], u[2], -d(u, c.eye)],
        [-f[0], -f[1], -f[2], d(f, c.eye)],
        [0.0, 0.0, 0.0, 1.0],
    ];
    let t = 1.0 / (c.fovy.to_radians() / 2.0).tan();
    let aspect = w as f64 / h as f64;
    let (n, fa) = (c.near, c.far);
    let proj = [
        [t / aspect, 0.0, 0.0, 0.0],
        [0.0, t, 0.0, 0.0],
        [0.0, 0.0, (fa + n) / (n - fa), 2.0 * fa * n / (n - fa)],
        [0.0, 0.0, -1.0, 0.0],
    ];
    Ok(mul(&proj, &view))
}

/// World-space triangles of `spec` (instance transforms applied in f64), in id order.
fn world_triangles(spec: &SceneSpec) -> Result<Vec<[[f32; 3]; 3]>, String> {
    Ok(spec
        .reference()?
        .triangles
        .iter()
        .map(|t| t.v.map(|p| p.map(|c| c as f32)))
        .collect())
}

/// Per-triangle base colours of `spec`, in id order.
fn triangle_colours(spec: &SceneSpec) -> Vec<[u8; 3]> {
    use embedded_graphics::pixelcolor::RgbColor;
    spec.instances
        .iter()
        .flat_map(|i| i.mesh.colors.iter().map(|c| [c.r(), c.g(), c.b()]))
        .collect()
}

fn rgb565(c: [u8; 3]) -> Rgb565 {
    Rgb565::new(c[0] >> 3, c[1] >> 2, c[2] >> 3)
}

fn empty_image(w: usize, h: usize) -> Image {
    Image {
        width: w,
        height: h,
        ids: vec![-1; w * h],
        depth: vec![f32::INFINITY; w * h],
        color: vec![[0; 3]; w * h],
    }
}

// ---------------------------------------------------------------------------------------------
// euc

/// One euc vertex: world position, the triangle id and its colour (flat: the same on all three).
#[derive(Clone, Copy, Debug)]
pub struct EucVertex {
    pos: [f32; 3],
    id: f32,
    rgb: (f32, f32, f32),
}

/// euc pipeline writing triangle ids.
struct EucIds {
    clip: [[f32; 4]; 4],
}

/// euc pipeline writing Rgb565 colours (raw `u16`), as a user's frame would be.
struct EucColours {
    clip: [[f32; 4]; 4],
}

fn clip4(m: &[[f32; 4]; 4], p: [f32; 3]) -> [f32; 4] {
    [0, 1, 2, 3].map(|r| m[r][0] * p[0] + m[r][1] * p[1] + m[r][2] * p[2] + m[r][3])
}

impl Pipeline for EucIds {
    type Vertex = EucVertex;
    type VsOut = f32;
    type Pixel = i32;
    fn vert(&self, v: &EucVertex) -> ([f32; 4], f32) {
        (clip4(&self.clip, v.pos), v.id)
    }
    fn frag(&self, id: &f32) -> i32 {
        // Interpolating a constant gives it back to within ~1e-3 for ids below 2^14.
        id.round() as i32
    }
}

impl Pipeline for EucColours {
    type Vertex = EucVertex;
    type VsOut = (f32, f32, f32);
    type Pixel = u16;
    fn vert(&self, v: &EucVertex) -> ([f32; 4], (f32, f32, f32)) {
        (clip4(&self.clip, v.pos), v.rgb)
    }
    fn frag(&self, c: &(f32, f32, f32)) -> u16 {
        let q =
            |v: f32, bits: u32| ((v * ((1 << bits) - 1) as f32 + 0.5) as u16).min((1 << bits) - 1);
        (q(c.0, 5) << 11) | (q(c.1, 6) << 5) | q(c.2, 5)
    }
}

/// A scene set up for euc: a non-indexed vertex array (euc 0.5 draws triangle lists) and the
/// clip matrix.
pub struct EucScene {
    vertices: Vec<EucVertex>,
    clip: [[f32; 4]; 4],
    cull: bool,
    width: usize,
    height: usize,
    near: f64,
    far: f64,
}

impl EucScene {
    /// Converts `spec` for a `w × h` target (done once).
    pub fn new(spec: &SceneSpec, w: usize, h: usize) -> Result<Self, String> {
        let clip = clip_matrix(spec, w, h)?.map(|r| r.map(|v| v as f32));
        let colours = triangle_colours(spec);
        let vertices = world_triangles(spec)?
            .iter()
            .zip(&colours)
            .enumerate()
            .flat_map(|(id, (t, c))| {
                let rgb = (
                    c[0] as f32 / 255.0,
                    c[1] as f32 / 255.0,
                    c[2] as f32 / 255.0,
                );
                t.map(|pos| EucVertex {
                    pos,
                    id: id as f32,
                    rgb,
                })
            })
            .collect();
        Ok(EucScene {
            vertices,
            clip,
            cull: spec.cull_back_faces,
            width: w,
            height: h,
            near: spec.camera.near,
            far: spec.camera.far,
        })
    }

    /// A colour buffer and a depth buffer of the right size.
    pub fn buffers(&self) -> (Buffer2d<u16>, Buffer2d<f32>) {
        let size = [self.width, self.height];
        (Buffer2d::new(size, 0), Buffer2d::new(size, 1.0))
    }

    fn draw<P: Pipeline<Vertex = EucVertex>>(
        &self,
        p: &P,
        target: &mut impl Target<Item = P::Pixel>,
        depth: &mut Buffer2d<f32>,
    ) {
        if self.cull {
            p.draw::<Triangles<'_, Buffer2d<f32>, BackfaceCullingEnabled>, _>(
                &self.vertices,
                target,
                Some(depth),
            );
        } else {
            p.draw::<Triangles<'_, Buffer2d<f32>, BackfaceCullingDisabled>, _>(
                &self.vertices,
                target,
                Some(depth),
            );
        }
    }

    /// One frame into an Rgb565 colour buffer (cleared here, as a frame loop would).
    pub fn render_colours(&self, colour: &mut Buffer2d<u16>, depth: &mut Buffer2d<f32>) {
        colour.clear(0);
        depth.clear(1.0);
        self.draw(&EucColours { clip: self.clip }, colour, depth);
    }

    /// One frame as an id image; depth from euc's depth buffer (NDC z → eye distance).
    pub fn render_ids(&self) -> Image {
        let size = [self.width, self.height];
        let mut ids = Buffer2d::new(size, -1i32);
        let mut depth = Buffer2d::new(size, 1.0f32);
        self.draw(&EucIds { clip: self.clip }, &mut ids, &mut depth);
        let mut img = empty_image(self.width, self.height);
        img.ids.copy_from_slice(ids.as_ref());
        let (n, f) = (self.near, self.far);
        for (d, (&id, &z)) in img
            .depth
            .iter_mut()
            .zip(ids.as_ref().iter().zip(depth.as_ref()))
        {
            if id >= 0 {
                // z_ndc = (f + n)/(f − n) − 2fn / ((f − n) d)
                *d = (2.0 * f * n / ((f + n) - z as f64 * (f - n))) as f32;
            }
        }
        img
    }
}

// ---------------------------------------------------------------------------------------------
// embedded-3dgfx

/// An Rgb565 frame buffer as an embedded-graphics draw target.
pub struct Frame565 {
    /// Pixels, row-major from the top.
    pub pixels: Vec<Rgb565>,
    width: usize,
    height: usize,
}

impl Frame565 {
    /// A black `w × h` frame.
    pub fn new(w: usize, h: usize) -> Self {
        Frame565 {
            pixels: vec![Rgb565::new(0, 0, 0); w * h],
            width: w,
            height: h,
        }
    }
}

impl OriginDimensions for Frame565 {
    fn size(&self) -> Size {
        Size::new(self.width as u32, self.height as u32)
    }
}

impl DrawTarget for Frame565 {
    type Color = Rgb565;
    type Error = core::convert::Infallible;
    fn draw_iter<I: IntoIterator<Item = Pixel<Rgb565>>>(
        &mut self,
        pixels: I,
    ) -> Result<(), Self::Error> {
        for Pixel(p, c) in pixels {
            if p.x >= 0 && p.y >= 0 && (p.x as usize) < self.width && (p.y as usize) < self.height {
                self.pixels[p.y as usize * self.width + p.x as usize] = c;
            }
        }
        Ok(())
    }
}

/// Command capacity: every corpus triangle, each split into up to six by clipping.
pub const E3D_COMMANDS: usize = 65536;

/// The command buffer embedded-3dgfx records into (boxed: it is large).
pub type E3dCommands = CommandBuffer<E3D_COMMANDS>;

/// A scene set up for embedded-3dgfx: world-space vertices per triangle (each triangle its own
/// mesh, for per-face colours), face normals when back faces are culled, and the engine with
/// its camera.
pub struct E3dScene {
    engine: embedded_3dgfx::engine::K3dengine,
    /// Three world-space vertices per triangle.
    corners: Vec<[f32; 3]>,
    /// Shared-vertex world positions and faces (the one-mesh variant).
    vertices: Vec<[f32; 3]>,
    faces: Vec<[usize; 3]>,
    normals: Vec<[f32; 3]>,
    colours: Vec<Rgb565>,
    cull: bool,
    width: usize,
    height: usize,
}

const ONE_FACE: [[usize; 3]; 1] = [[0, 1, 2]];

impl E3dScene {
    /// Converts `spec` for a `w × h` target (done once).
    pub fn new(spec: &SceneSpec, w: usize, h: usize) -> Result<Self, String> {
        let (wu, hu) = (u16::try_from(w), u16::try_from(h));
        let (Ok(wu), Ok(hu)) = (wu, hu) else {
            return Err("size beyond u16".into());
        };
        let tris = world_triangles(spec)?;
        let corners: Vec<[f32; 3]> = tris.iter().flatten().copied().collect();
        let normals = tris
            .iter()
            .map(|t| Geometry::calculate_face_normal(&t[0], &t[1], &t[2]))
            .collect();
        let vertices = corners.clone();
        let faces = (0..tris.len())
            .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
            .collect();
        let mut engine = embedded_3dgfx::engine::K3dengine::new(wu, hu);
        let c = &spec.camera;
        let p = |v: [f64; 3]| nalgebra::Point3::new(v[0] as f32, v[1] as f32, v[2] as f32);
        engine.camera.set_fovy(c.fovy.to_radians() as f32);
        engine.camera.set_near_far(c.near as f32, c.far as f32);
        engine.camera.set_position(p(c.eye));
        engine.camera.set_target(p(c.target));
        let up = reference::normalize(c.up).ok_or("zero up")?;
        if up != [0.0, 1.0, 0.0] {
            // No up vector in its camera API: set the public matrices it renders with.
            let m = clip_matrix(spec, w, h)?;
            let m = nalgebra::Matrix4::from_fn(|r, col| m[r][col] as f32);
            let proj = nalgebra::Perspective3::new(
                w as f32 / h as f32,
                c.fovy.to_radians() as f32,
                c.near as f32,
                c.far as f32,
            )
            .to_homogeneous();
            engine.camera.view_matrix = proj.try_inverse().ok_or("projection")? * m;
            engine.camera.vp_matrix = m;
        }
        Ok(E3dScene {
            engine,
            corners,
            vertices,
            faces,
            normals,
            colours: triangle_colours(spec).into_iter().map(rgb565).collect(),
            cull: spec.cull_back_faces,
            width: w,
            height: h,
        })
    }

    fn mesh<'a>(&self, geometry: Geometry<'a>, colour: Rgb565) -> K3dMesh<'a> {
        let mut m = K3dMesh::new(geometry);
        m.set_render_mode(RenderMode::Solid);
        m.set_color(colour);
        m
    }

    fn triangle_meshes(&self, colour: impl Fn(usize) -> Rgb565) -> Vec<K3dMesh<'_>> {
        (0..self.corners.len() / 3)
            .map(|i| {
                let mut g = Geometry::new(&self.corners[3 * i..3 * i + 3], &ONE_FACE);
                if self.cull {
                    // Its solid mode culls back faces only when given normals.
                    g.normals = &self.normals[i..i + 1];
                }
                self.mesh(g, colour(i))
            })
            .collect()
    }

    /// One mesh per triangle, coloured `id + 1` (raw Rgb565), for the id image.
    pub fn id_meshes(&self) -> Vec<K3dMesh<'_>> {
        self.triangle_meshes(|i| Rgb565::from(RawU16::new(i as u16 + 1)))
    }

    /// One mesh per triangle in the triangle's colour: per-face colours, as ours draws them.
    pub fn colour_meshes(&self) -> Vec<K3dMesh<'_>> {
        self.triangle_meshes(|i| self.colours[i])
    }

    /// The whole scene as one mesh in one colour (what its solid mode draws cheapest).
    pub fn single_mesh(&self) -> Vec<K3dMesh<'_>> {
        let mut g = Geometry::new(&self.vertices, &self.faces);
        if self.cull {
            g.normals = &self.normals;
        }
        vec![self.mesh(
            g,
            self.colours
                .first()
                .copied()
                .unwrap_or(Rgb565::new(31, 63, 31)),
        )]
    }

    /// A frame, a z-buffer and a command buffer of the right size.
    pub fn buffers(&self) -> (Frame565, Vec<embedded_3dgfx::ZDepth>, Box<E3dCommands>) {
        (
            Frame565::new(self.width, self.height),
            vec![embedded_3dgfx::Z_MAX_VALUE; self.width * self.height],
            Box::new(CommandBuffer::new()),
        )
    }

    /// One frame (record + execute) into `frame`, cleared to black first.
    pub fn render_frame(
        &self,
        meshes: &[K3dMesh<'_>],
        frame: &mut Frame565,
        zbuffer: &mut [embedded_3dgfx::ZDepth],
        commands: &mut E3dCommands,
    ) -> Result<(), String> {
        frame.pixels.fill(Rgb565::new(0, 0, 0));
        self.engine
            .record(meshes.iter(), commands, None)
            .map_err(|e| format!("embedded-3dgfx record: {e:?}"))?;
        let mut ctx = FrameCtx {
            zbuffer,
            width: self.width,
            height: self.height,
        };
        self.engine
            .execute(frame, &mut ctx, commands, None)
            .map_err(|e| format!("embedded-3dgfx execute: {e:?}"))?;
        Ok(())
    }

    /// One frame of [`Self::id_meshes`] decoded into an id image (depth NaN over surfaces).
    pub fn render_ids(&self, meshes: &[K3dMesh<'_>]) -> Result<Image, String> {
        let (mut frame, mut z, mut commands) = self.buffers();
        self.render_frame(meshes, &mut frame, &mut z, &mut commands)?;
        let mut img = empty_image(self.width, self.height);
        for (k, c) in frame.pixels.iter().enumerate() {
            let raw = RawU16::from(*c).into_inner() as i32;
            img.ids[k] = raw - 1;
            if raw > 0 {
                img.depth[k] = f32::NAN;
            }
        }
        Ok(img)
    }
}

// ---------------------------------------------------------------------------------------------
// Comparison

/// The yardstick for *real* mismatches: our renderer's documented error bound at its default
/// (4 sub-pixel bits), for this scene. The same bound judges ours and the peers.
pub fn bound(spec: &SceneSpec, reference: &reference::Scene, h: usize) -> ErrorBound {
    ErrorBound {
        sub_bits: 4,
        max_model_coord: spec.max_model_coord(),
        focal_px: reference.camera.focal_px(h),
        arithmetic: Default::default(),
    }
}

/// One renderer's result on one scene.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// Comparison with the reference (`Err`: the renderer failed or panicked).
    pub metrics: Result<Metrics, String>,
    /// Pixels the renderer covered.
    pub covered: usize,
    /// Largest distance (pixels) from a mismatching pixel centre to an edge of the reference
    /// triangle or the renderer's triangle there (0 without mismatches).
    pub max_edge_distance: f64,
}

/// One corpus scene and camera: ours and every peer against the reference.
#[derive(Clone, Debug)]
pub struct Row {
    /// Corpus scene name.
    pub scene: &'static str,
    /// Camera index.
    pub camera: usize,
    /// Pixels the reference covers.
    pub reference_covered: usize,
    /// Ours: the default span z-buffer at 4 sub-pixel bits, as `accuracy` computes it.
    pub ours: Outcome,
    /// Ours with the `Exact` preset (8 sub-pixel bits), our most accurate frame.
    pub ours_exact: Outcome,
    /// Each peer, in [`Peer::ALL`] order.
    pub peers: Vec<(Peer, Outcome)>,
}

fn covered(img: &Image) -> usize {
    img.ids.iter().filter(|&&i| i >= 0).count()
}

fn segment_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let ab = [b[0] - a[0], b[1] - a[1]];
    let ap = [p[0] - a[0], p[1] - a[1]];
    let len2 = ab[0] * ab[0] + ab[1] * ab[1];
    let t = if len2 > 0.0 {
        ((ap[0] * ab[0] + ap[1] * ab[1]) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (ap[0] - t * ab[0]).hypot(ap[1] - t * ab[1])
}

/// Largest distance from a mismatching pixel centre of `img` to the outline (clipped, projected)
/// of the nearer of the two triangles involved.
pub fn max_edge_distance(img: &Image, reference: &Image, scene: &reference::Scene) -> f64 {
    let (w, h) = (reference.width, reference.height);
    let outline = |t: i32, p: [f64; 2]| {
        if t < 0 || t as usize >= scene.triangles.len() {
            return f64::INFINITY;
        }
        let poly = scene.screen_polygon(t as usize, w, h);
        (0..poly.len())
            .map(|i| segment_distance(p, poly[i], poly[(i + 1) % poly.len()]))
            .fold(f64::INFINITY, f64::min)
    };
    let mut worst: f64 = 0.0;
    for i in 0..reference.ids.len() {
        let (a, b) = (img.ids[i], reference.ids[i]);
        if a != b {
            let p = [(i % w) as f64 + 0.5, (i / w) as f64 + 0.5];
            worst = worst.max(outline(a, p).min(outline(b, p)));
        }
    }
    worst
}

fn outcome(
    img: Result<Image, String>,
    reference: &Image,
    scene: &reference::Scene,
    bound: &ErrorBound,
) -> Outcome {
    match img {
        Ok(img) => Outcome {
            metrics: Ok(metrics::compare(&img, reference, scene, bound)),
            covered: covered(&img),
            max_edge_distance: max_edge_distance(&img, reference, scene),
        },
        Err(e) => Outcome {
            metrics: Err(e),
            covered: 0,
            max_edge_distance: f64::INFINITY,
        },
    }
}

/// Renders with `peer`, turning a panic inside the peer into an error (a row, not a crash).
pub fn render_caught(peer: Peer, spec: &SceneSpec, w: usize, h: usize) -> Result<Image, String> {
    // The command buffer is large: render on a thread with room for it in debug builds.
    std::thread::scope(|s| {
        std::thread::Builder::new()
            .stack_size(64 << 20)
            .spawn_scoped(s, || peer.render(spec, w, h))
            .map_err(|e| format!("cannot start render thread: {e}"))?
            .join()
            .map_err(|p| {
                let msg = p
                    .downcast_ref::<&str>()
                    .map(|s| s.to_string())
                    .or_else(|| p.downcast_ref::<String>().cloned())
                    .unwrap_or_default();
                format!("{} panicked: {msg}", peer.name())
            })?
    })
}

/// Ours and every peer on `spec` at `w × h`, against the reference.
pub fn compare_scene(
    name: &'static str,
    camera: usize,
    spec: &SceneSpec,
    w: usize,
    h: usize,
) -> Result<Row, String> {
    let reference = spec.reference()?;
    let ref_img = reference.render(w, h);
    let b = bound(spec, &reference, h);
    let ours = outcome(
        spec.render_fixed(w, h, 4).map(|r| r.image),
        &ref_img,
        &reference,
        &b,
    );
    let ours_exact = outcome(
        spec.render_fixed_preset(w, h, PresetChoice::Exact, Algorithm::SpanZBuffer)
            .map(|r| r.image),
        &ref_img,
        &reference,
        &b,
    );
    let peers = Peer::ALL
        .iter()
        .map(|&p| {
            (
                p,
                outcome(render_caught(p, spec, w, h), &ref_img, &reference, &b),
            )
        })
        .collect();
    Ok(Row {
        scene: name,
        camera,
        reference_covered: covered(&ref_img),
        ours,
        ours_exact,
        peers,
    })
}

/// Every corpus scene from every camera (default light, the scene's culling choice): ours and
/// every peer against the reference at `w × h`.
pub fn corpus_table(w: usize, h: usize) -> Result<Vec<Row>, String> {
    let mut rows = Vec::new();
    for scene in crate::corpus::all() {
        for (k, camera) in scene.cameras.iter().enumerate() {
            let spec = SceneSpec::single(
                scene.mesh.clone(),
                *camera,
                crate::scene::LightSpec::default(),
                scene.cull_back_faces,
            );
            rows.push(compare_scene(scene.name, k, &spec, w, h)?);
        }
    }
    Ok(rows)
}

/// The table as text: one line per scene, camera and renderer.
pub fn format_table(rows: &[Row]) -> String {
    let mut s = format!(
        "{:17} {:>3} {:15} {:>9} {:>7} {:>6} {:>8} {:>8} {:>7} {:>9}\n",
        "scene",
        "cam",
        "renderer",
        "id mism.",
        "%",
        "real",
        "covered",
        "ref cov",
        "max px",
        "depth rel"
    );
    for r in rows {
        let all = [("ours", &r.ours), ("ours-exact", &r.ours_exact)]
            .into_iter()
            .chain(r.peers.iter().map(|(p, o)| (p.name(), o)));
        for (name, o) in all {
            match &o.metrics {
                Ok(m) => {
                    s += &format!(
                        "{:17} {:>3} {:15} {:>9} {:>7.3} {:>6} {:>8} {:>8} {:>7.2} {:>9.2e}\n",
                        r.scene,
                        r.camera,
                        name,
                        m.id_mismatches,
                        m.id_mismatch_percent(),
                        m.real,
                        o.covered,
                        r.reference_covered,
                        o.max_edge_distance,
                        m.depth_max_rel
                    )
                }
                Err(e) => s += &format!("{:17} {:>3} {:15} FAILED: {e}\n", r.scene, r.camera, name),
            }
        }
    }
    s
}
