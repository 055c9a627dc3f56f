//! The animated six-ball metaball scene the firmware ray casts (the same balls and keys as
//! `sim/src/metaball/six.meta`; a host test checks they agree), and its frame on the hashing
//! panel model, called by firmware and host alike.

use embedded_graphics::pixelcolor::{Rgb565, Rgb888};
use scanline3d::metaball::{
    Ball, CastError, CastStats, Caster, Coord, MetaCamera, MetaballError, Metaballs, PolyMesh,
    PolyStats, Polygonizer,
};
use scanline3d::scene::{Camera, Instance, Light, Scene, SceneError, Transform};
use scanline3d::sink::RowSink;
use scanline3d::{FrameStats, Gouraud, RenderOptions, Workspace};

/// Side of the square panel the firmware casts (120: a 240×240 frame costs 4× as many
/// instructions and the test command's time budget is shared).
pub const SIDE: u16 = 120;
/// Frames of the animation loop (keys at 0, 4 and 8 = 0).
pub const FRAMES: u32 = 8;
/// The iso-value.
pub const THRESHOLD: f32 = 0.45;

/// One ball: centre at frame 0, centre at frame 4, radius, density, colour (0..1).
type BallKeys = ([f64; 3], [f64; 3], f64, f64, [f64; 3]);

/// The six balls of `six.meta`.
const BALLS: [BallKeys; 6] = [
    (
        [-1.2, 0.0, 0.0],
        [-0.5, 0.3, 0.2],
        1.1,
        1.0,
        [0.9, 0.3, 0.2],
    ),
    (
        [1.2, 0.0, 0.0],
        [0.5, -0.3, -0.2],
        1.1,
        1.0,
        [0.2, 0.5, 0.9],
    ),
    ([0.0, 1.1, 0.0], [0.2, 0.5, 0.4], 0.9, 1.0, [0.9, 0.8, 0.2]),
    (
        [0.0, -1.1, 0.0],
        [-0.2, -0.5, -0.4],
        0.9,
        1.0,
        [0.3, 0.8, 0.3],
    ),
    ([0.0, 0.0, 1.0], [0.6, 0.6, 0.3], 0.8, 1.0, [0.8, 0.3, 0.8]),
    (
        [0.3, 0.3, 0.3],
        [-0.8, 0.2, 0.5],
        0.7,
        -0.8,
        [1.0, 1.0, 1.0],
    ),
];

/// The balls at `frame` (modulo [`FRAMES`]): centres linear between the keys, in `f64` as the
/// `.meta` reader computes them, then rounded to I16F16.
pub fn balls(frame: u32) -> [Ball; 6] {
    let frame = frame % FRAMES;
    let u = if frame <= 4 {
        frame as f64 / 4.0
    } else {
        (8 - frame) as f64 / 4.0
    };
    BALLS.map(|(a, b, radius, density, color)| {
        let centre = [0, 1, 2].map(|i| (a[i] + u * (b[i] - a[i])) as f32);
        let c8 = color.map(|c| libm::round(c * 255.0) as u8);
        Ball::new(
            centre,
            radius as f32,
            density as f32,
            Rgb888::new(c8[0], c8[1], c8[2]),
        )
    })
}

/// The camera: from (0, 1.5, 5) at the origin, 50° vertical field of view.
pub fn camera() -> Result<MetaCamera, MetaballError> {
    MetaCamera::new(
        [0.0, 1.5, 5.0],
        [0.0; 3],
        [0.0, 1.0, 0.0],
        50.0,
        0.1,
        100.0,
        SIDE,
        SIDE,
    )
}

/// The light of `six.meta`.
pub fn light() -> Result<Light, SceneError> {
    Light::new([0.4, 0.8, 0.6], 0.2, 0.8)
}

/// The caster the firmware uses: RGB565 rows of [`SIDE`] pixels, six balls.
pub type PanelCaster = Caster<Rgb565, { SIDE as usize }, 6>;

/// Casts `frame` into `sink` (the firmware and the host hash the rows with
/// [`HashSink`](scanline3d::sink::HashSink): equal hashes mean bit-identical frames).
pub fn render_frame<S: RowSink<Rgb565>>(
    caster: &mut PanelCaster,
    frame: u32,
    sink: &mut S,
) -> Result<CastStats, &'static str> {
    let balls = balls(frame);
    let scene = Metaballs::new(&balls, Coord::from_num(THRESHOLD)).map_err(|_| "balls")?;
    let camera = camera().map_err(|_| "camera")?;
    let light = light().map_err(|_| "light")?;
    caster
        .render(&scene, &camera, &light, sink)
        .map_err(|_: CastError<S::Error>| "cast")
}

/// The same animation polygonized: marching tetrahedra on a grid of `S` samples per axis (`S − 1`
/// cells) into a mesh of up to `V` vertices and `T` triangles, drawn by the span z-buffer
/// (Gouraud, RGB565 rows of [`SIDE`] pixels, room for `TRIS` triangles after culling, `ACTIVE`
/// per row).
pub struct PanelPolygonizer<
    const S: usize,
    const V: usize,
    const T: usize,
    const TRIS: usize,
    const ACTIVE: usize,
> {
    grid: Polygonizer<S, 6>,
    mesh: PolyMesh<V, T>,
    workspace: Workspace<Rgb565, Gouraud, { SIDE as usize }, { SIDE as usize }, TRIS, ACTIVE>,
}

/// The grids the firmware measures (`cargo xtask metaball-trade`), sized for the animation's
/// largest frame with about 25 % to spare: 8, 16, 24 and 32 cells per axis.
pub type Poly8 = PanelPolygonizer<9, 512, 1024, 512, 64>;
/// 16 cells per axis.
pub type Poly16 = PanelPolygonizer<17, 2048, 4096, 2048, 128>;
/// 24 cells per axis.
pub type Poly24 = PanelPolygonizer<25, 4608, 9216, 4608, 192>;
/// 32 cells per axis.
pub type Poly32 = PanelPolygonizer<33, 8192, 16384, 8192, 256>;

impl<const S: usize, const V: usize, const T: usize, const TRIS: usize, const ACTIVE: usize>
    PanelPolygonizer<S, V, T, TRIS, ACTIVE>
{
    /// Size in bytes: polygonizer, mesh and span z-buffer.
    pub const BYTES: usize = core::mem::size_of::<Self>();

    /// Empty, drawing `background` where no surface is.
    pub const fn new(background: Rgb565) -> Self {
        PanelPolygonizer {
            grid: Polygonizer::new(),
            mesh: PolyMesh::new(),
            workspace: Workspace::new(background),
        }
    }

    /// Polygonizes `frame` (replacing the previous frame's mesh).
    pub fn polygonize(&mut self, frame: u32) -> Result<PolyStats, &'static str> {
        let balls = balls(frame);
        let scene = Metaballs::new(&balls, Coord::from_num(THRESHOLD)).map_err(|_| "balls")?;
        self.grid
            .polygonize(&scene, &mut self.mesh)
            .map_err(|_| "polygonize")
    }

    /// Draws the mesh of the last [`Self::polygonize`] into `sink` from [`camera`]'s view.
    pub fn draw<K: RowSink<Rgb565>>(&mut self, sink: &mut K) -> Result<FrameStats, &'static str> {
        let mesh = self.mesh.mesh().map_err(|_| "mesh")?;
        let instances = [Instance {
            mesh: &mesh,
            transform: Transform::IDENTITY,
        }];
        let camera = Camera::look_at([0.0, 1.5, 5.0], [0.0; 3], [0.0, 1.0, 0.0])
            .and_then(|view| view.perspective(50.0, 0.1, 100.0))
            .map_err(|_| "camera")?;
        let scene =
            Scene::new(&instances, camera, light().map_err(|_| "light")?).map_err(|_| "scene")?;
        let stats = self
            .workspace
            .render(&scene, &RenderOptions::default(), sink)
            .map_err(|_| "render")?;
        if stats.is_complete() {
            Ok(stats)
        } else {
            Err("workspace full")
        }
    }
}
