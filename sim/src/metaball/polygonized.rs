//! The library's marching-tetrahedra polygonizer on the host: the frame's balls turned into a
//! closed mesh (`scanline3d::metaball::Polygonizer`) and drawn by the span z-buffer with
//! Gouraud shading, into the same images as the caster and the reference.

use super::MetaScene;
use crate::reference::Image;
use crate::scene::CameraSpec;
use embedded_graphics::pixelcolor::Rgb888;
use embedded_graphics::prelude::RgbColor;
use scanline3d::metaball::{Metaballs, PolyMesh, PolyStats, Polygonizer};
use scanline3d::scene::{Instance, Light, Scene, Transform};
use scanline3d::sink::{FnSink, Row, RowPixel, TriangleId};
use scanline3d::{FrameStats, Gouraud, RenderOptions, Workspace};
use std::convert::Infallible;

/// The grid sizes `--method polygonize:N` offers (cells per axis).
pub const GRIDS: [usize; 8] = [8, 12, 16, 20, 24, 32, 48, 64];

/// Largest side of the host image.
const MAX_SIDE: usize = 640;
/// Mesh capacity on the host (vertices; triangles).
const VERTICES: usize = 65_534;
const TRIANGLES: usize = 65_535;
/// Triangles crossing one row.
const ACTIVE: usize = 1024;

type HostMesh = PolyMesh<VERTICES, TRIANGLES>;
type HostWorkspace<P> = Workspace<P, Gouraud, MAX_SIDE, MAX_SIDE, TRIANGLES, ACTIVE>;

/// A polygonized frame: the image, what the polygonizer made and what the renderer did.
#[derive(Clone, Debug)]
pub struct Polygonized {
    /// Colour, ids (the ball with the largest `q·f` at the triangle's first vertex) and depth.
    pub image: Image,
    /// Vertices and triangles.
    pub mesh: PolyStats,
    /// The span z-buffer's frame statistics (colour pass).
    pub frame: FrameStats,
}

/// Polygonizes `frame` of `scene` on a grid of `cells` per axis (one of [`GRIDS`]) and renders
/// it, back faces culled (the mesh turned inside out when the eye is inside the surface).
pub fn render_polygonized(
    scene: &MetaScene,
    frame: u32,
    camera: &CameraSpec,
    (w, h): (usize, usize),
    cells: usize,
) -> Result<Polygonized, String> {
    if w > MAX_SIDE || h > MAX_SIDE {
        return Err(format!(
            "size {w}x{h} over the host's {MAX_SIDE}x{MAX_SIDE}"
        ));
    }
    // The mesh and workspaces are built by value (through the stack in debug builds).
    std::thread::scope(|scope| {
        std::thread::Builder::new()
            .stack_size(512 << 20)
            .spawn_scoped(scope, || {
                macro_rules! grid {
                    ($($n:literal),*) => {
                        match cells {
                            $($n => render_grid::<{ $n + 1 }>(scene, frame, camera, w, h),)*
                            _ => Err(format!("polygonize:{cells}: the grid is one of {GRIDS:?} cells per axis")),
                        }
                    };
                }
                grid!(8, 12, 16, 20, 24, 32, 48, 64)
            })
            .map_err(|e| format!("cannot start render thread: {e}"))?
            .join()
            .map_err(|_| "render thread panicked".to_string())?
    })
}

fn render_grid<const S: usize>(
    scene: &MetaScene,
    frame: u32,
    camera: &CameraSpec,
    w: usize,
    h: usize,
) -> Result<Polygonized, String> {
    let fixed = super::fixed::FixedMeta::new(scene)?;
    let balls = fixed.balls_at(frame);
    let metaballs = Metaballs::new(&balls, fixed.threshold).map_err(|e| e.to_string())?;
    let mut mesh: Box<HostMesh> = Box::default();
    let mut grid: Box<Polygonizer<S, { super::compare::MAX_BALLS }>> = Box::default();
    let stats = grid
        .polygonize(&metaballs, &mut mesh)
        .map_err(|e| format!("polygonize: {e}"))?;
    let eye_inside =
        super::reference::Reference::new(scene, frame, camera.reference()?)?.g(camera.eye) > 0.0;
    if eye_inside {
        mesh.turn_inside_out();
    }
    let library_mesh = mesh.mesh().map_err(|e| e.to_string())?;
    let instances = [Instance {
        mesh: &library_mesh,
        transform: Transform::IDENTITY,
    }];
    let (d, a, di) = scene.light;
    let f = |v: [f64; 3]| v.map(|c| c as f32);
    let library_camera = camera.fixed()?;
    let library_scene = Scene::new(
        &instances,
        library_camera,
        Light::new(f(d), a as f32, di as f32).map_err(|e| e.to_string())?,
    )
    .map_err(|e| e.to_string())?;
    let eye_inside =
        super::reference::Reference::new(scene, frame, camera.reference()?)?.g(camera.eye) > 0.0;
    let options = RenderOptions::default().with_back_face_culling(!eye_inside);
    let mut image = Image::background(w, h);
    let frame_stats = draw(
        Rgb888::BLACK,
        &library_scene,
        &options,
        w,
        h,
        |y, row: Row<'_, Rgb888>| {
            for (x, p) in row.pixels.iter().enumerate() {
                image.color[y * w + x] = [p.r(), p.g(), p.b()];
            }
        },
    )?;
    let vertex_balls = mesh.vertex_balls();
    let triangles = mesh.triangles();
    draw(
        TriangleId::NONE,
        &library_scene,
        &options,
        w,
        h,
        |y, row: Row<'_, TriangleId>| {
            for (x, id) in row.pixels.iter().enumerate() {
                let ball = usize::try_from(id.0)
                    .ok()
                    .and_then(|t| triangles.get(t))
                    .and_then(|t| vertex_balls.get(usize::from(t[0])));
                image.ids[y * w + x] = ball.map_or(-1, |&b| i32::from(b));
                if let Some(q) = row.depth.get(x) {
                    image.depth[y * w + x] =
                        library_camera.eye_distance(q).unwrap_or(f32::INFINITY);
                }
            }
        },
    )?;
    Ok(Polygonized {
        image,
        mesh: stats,
        frame: frame_stats,
    })
}

fn draw<P: RowPixel>(
    background: P,
    scene: &Scene<'_>,
    options: &RenderOptions,
    w: usize,
    h: usize,
    mut each: impl FnMut(usize, Row<'_, P>),
) -> Result<FrameStats, String> {
    let mut workspace: Box<HostWorkspace<P>> = Box::new(Workspace::new(background));
    let mut sink = FnSink(|row: Row<'_, P>| -> Result<(), Infallible> {
        each(usize::from(row.y), row);
        Ok(())
    });
    let stats = workspace
        .render_sized(w, h, scene, options, &mut sink)
        .map_err(|e| format!("span z-buffer: {e:?}"))?;
    if !stats.is_complete() {
        return Err(format!("span z-buffer: incomplete frame {stats:?}"));
    }
    Ok(stats)
}
