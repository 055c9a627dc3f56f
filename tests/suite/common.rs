//! Shared test helpers: scene builders, render-to-ids with row-order checks, and comparison with
//! the f64 reference and the metrics from the tool crate (`sim`).
#![allow(dead_code)]

use embedded_graphics::pixelcolor::Rgb888;
use fixed::types::I16F16;
use scanline3d::clip::Clipping;
use scanline3d::scene::{Instance, Light, Mesh, Scene, Transform, Vertex};
use scanline3d::sink::{FnSink, Row, TriangleId};
use scanline3d::{Flat, FrameStats, RenderOptions, Workspace};
pub use scanline3d_sim::scene::{CameraSpec, MeshData};
use scanline3d_sim::{meshgen, metrics, reference, scene::LightSpec};

pub fn vert(p: [f64; 3]) -> Vertex {
    p.map(I16F16::from_num)
}

/// Mesh data with a distinct colour per triangle.
pub fn mesh_data(positions: &[[f64; 3]], triangles: &[[u16; 3]]) -> MeshData {
    let mut m = MeshData::new(positions, triangles.to_vec(), Rgb888::new(0, 0, 0)).unwrap();
    m.colors = (0..triangles.len())
        .map(|i| Rgb888::new((40 + 37 * i % 200) as u8, (90 + 53 * i % 160) as u8, 200))
        .collect();
    m
}

/// Icosphere of radius `r` with `20 · 4^n` triangles.
pub fn icosphere(n: u32, r: f64) -> MeshData {
    let (v, f) = meshgen::icosphere(n);
    let v: Vec<[f64; 3]> = v.into_iter().map(|p| p.map(|c| c * r)).collect();
    mesh_data(&v, &f)
}

const LIGHT: ([f64; 3], f64, f64) = ([0.4, 0.7, 1.0], 0.25, 0.75);

pub fn light() -> Light {
    Light::new(LIGHT.0.map(|c| c as f32), LIGHT.1 as f32, LIGHT.2 as f32).unwrap()
}

/// Renders triangle ids into a `W × H` vector with sub-pixel bits `S`, checking that rows arrive
/// once each, top to bottom.
pub fn render_ids<const W: usize, const H: usize, const S: u32>(
    instances: &[Instance<'_>],
    cam: &CameraSpec,
    cull: bool,
) -> (Vec<i32>, FrameStats) {
    let options = RenderOptions::default()
        .with_back_face_culling(cull)
        .with_sub_pixel_bits::<S>();
    render_ids_with::<W, H, S, _>(instances, cam, &options)
}

/// [`render_ids`] with any options (such as another clipping stage).
pub fn render_ids_with<const W: usize, const H: usize, const S: u32, C: Clipping>(
    instances: &[Instance<'_>],
    cam: &CameraSpec,
    options: &RenderOptions<S, C>,
) -> (Vec<i32>, FrameStats) {
    let scene = Scene {
        instances,
        camera: cam.fixed().unwrap(),
        light: light(),
    };
    let mut ws: Box<Workspace<TriangleId, Flat, W, H, 4096, 512>> =
        Box::new(Workspace::new(TriangleId::NONE));
    let mut ids = vec![-1i32; W * H];
    let mut next_row = 0u16;
    let mut sink = FnSink(|row: Row<'_, TriangleId>| -> Result<(), ()> {
        assert_eq!(row.y, next_row, "rows must arrive once each, top to bottom");
        next_row += 1;
        for (x, id) in row.pixels.iter().enumerate() {
            ids[row.y as usize * W + x] = id.0;
        }
        Ok(())
    });
    let stats = ws.render(&scene, options, &mut sink).unwrap();
    assert_eq!(stats.rows as usize, H);
    (ids, stats)
}

/// The identity-placed instance of a mesh.
pub fn instance<'a>(mesh: &'a Mesh<'a>) -> Instance<'a> {
    Instance {
        mesh,
        transform: Transform::IDENTITY,
    }
}

/// Screen position (pixels) of a world point, by the reference camera.
pub fn project(cam: &CameraSpec, w: usize, h: usize, p: [f64; 3]) -> Option<[f64; 2]> {
    cam.reference().unwrap().project(p, w, h)
}

/// Compares renderer ids with the f64 reference for meshes placed with the identity transform,
/// classifying mismatches with the documented position bound (`sim`'s metrics). Returns
/// (mismatches, real mismatches).
pub fn compare(
    data: &[&MeshData],
    cam: &CameraSpec,
    ids: &[i32],
    w: usize,
    h: usize,
    s: u32,
    cull: bool,
) -> (usize, usize) {
    let triangles = data.iter().flat_map(|d| d.world_triangles()).collect();
    let light = LightSpec {
        direction: LIGHT.0,
        ambient: LIGHT.1,
        diffuse: LIGHT.2,
    };
    let (direction, ambient, diffuse) = (
        reference::normalize(light.direction).unwrap(),
        light.ambient,
        light.diffuse,
    );
    let scene = reference::Scene::new(
        triangles,
        reference::Light {
            direction,
            ambient,
            diffuse,
        },
        cam.reference().unwrap(),
        cull,
    );
    let wanted = scene.render(w, h);
    // Only ids are compared here (depth and colour are covered by sim's accuracy test).
    let fixed = reference::Image {
        width: w,
        height: h,
        ids: ids.to_vec(),
        depth: wanted.depth.clone(),
        color: wanted.color.clone(),
    };
    let max_model_coord = data
        .iter()
        .flat_map(|d| d.vertices.iter().flatten())
        .map(|c| c.to_num::<f64>().abs())
        .fold(0.0, f64::max);
    let bound = metrics::ErrorBound {
        sub_bits: s,
        max_model_coord,
        focal_px: scene.camera.focal_px(h),
        arithmetic: Default::default(),
    };
    let m = metrics::compare(&fixed, &wanted, &scene, &bound);
    (m.id_mismatches, m.real)
}
