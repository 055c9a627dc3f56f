//! The documented operating envelope: every limit is accepted at the limit and rejected with a
//! specific error just past it. The reasons (bit budgets) are in the README's envelope table and
//! the module docs of `vertex`, `project` and `raster`.

use crate::common;

use common::*;
use embedded_graphics::pixelcolor::{Rgb565, Rgb888};
use fixed::types::I16F16;
use scanline3d::options::MAX_INSTANCES;
use scanline3d::project::{Viewport, MAX_SCREEN};
use scanline3d::resolve::{DepthSortWorkspace, NewellWorkspace, WarnockWorkspace};
use scanline3d::scene::*;
use scanline3d::sink::{FnSink, Row, RowSink, TriangleId};
use scanline3d::stats::CapacityKind;
use scanline3d::vertex::{ModelView, TransformError};
use scanline3d::{Flat, RenderError, RenderOptions, Workspace};

#[test]
fn model_coordinates_up_to_4096() {
    let at = I16F16::from_num(MAX_MODEL_COORD);
    let past = at + I16F16::DELTA;
    let c = MeshColors::Uniform(Rgb888::new(0, 0, 0));
    let z = I16F16::ZERO;
    assert!(Mesh::new(
        &[[at, z, z], [z, at, z], [z, z, -at]],
        &[[0, 1, 2]],
        c,
        None
    )
    .is_ok());
    assert_eq!(
        Mesh::new(
            &[[z, z, z], [past, z, z], [z, at, z]],
            &[[0, 1, 2]],
            c,
            None
        )
        .unwrap_err(),
        SceneError::VertexOutOfEnvelope { vertex: 1 }
    );
}

#[test]
fn eye_coordinates_up_to_2_pow_14() {
    // A mesh reaching 4096 scaled by 4 lands exactly on 2^14; any more is rejected per frame.
    let max = MAX_MODEL_COORD << 16;
    assert!(ModelView::new(&Transform::scale([4.0; 3]), &Transform::IDENTITY, max).is_ok());
    assert_eq!(
        ModelView::new(&Transform::scale([4.001; 3]), &Transform::IDENTITY, max).unwrap_err(),
        TransformError::OutOfEnvelope
    );
    let moved = Transform::translation([0.0, 0.0, 1.0]).then_after(&Transform::scale([4.0; 3]));
    assert_eq!(
        ModelView::new(&moved, &Transform::IDENTITY, max).unwrap_err(),
        TransformError::OutOfEnvelope
    );
}

#[test]
fn screens_up_to_2048_and_sub_pixel_bits_up_to_8() {
    assert!(Viewport::<8>::new(MAX_SCREEN, MAX_SCREEN, 1.0, 0.5, 10.0).is_some());
    assert!(Viewport::<4>::new(MAX_SCREEN + 1, 16, 1.0, 0.5, 10.0).is_none());
    assert!(Viewport::<4>::new(16, MAX_SCREEN + 1, 1.0, 0.5, 10.0).is_none());
    assert!(Viewport::<4>::new(1, 1, 1.0, 0.5, 10.0).is_some());
    assert!(Viewport::<4>::new(0, 1, 1.0, 0.5, 10.0).is_none());
    assert!(Viewport::<9>::new(16, 16, 1.0, 0.5, 10.0).is_none());
}

#[test]
fn near_and_far_limits() {
    let view = Camera::look_at([0.0, 0.0, 5.0], [0.0; 3], [0.0, 1.0, 0.0]).unwrap();
    // near ≥ 2^-8, far ≤ 2^14, far/near ≤ 2^20.
    assert!(view.perspective(60.0, MIN_NEAR, 1.0).is_ok());
    assert_eq!(
        view.perspective(60.0, MIN_NEAR * 0.99, 1.0).unwrap_err(),
        SceneError::DepthRange
    );
    assert!(view.perspective(60.0, 1.0, MAX_EYE_DISTANCE).is_ok());
    assert_eq!(
        view.perspective(60.0, 1.0, MAX_EYE_DISTANCE * 1.001)
            .unwrap_err(),
        SceneError::DepthRange
    );
    let near = MAX_EYE_DISTANCE / MAX_FAR_NEAR_RATIO; // 2^14 / 2^20 = 2^-6
    assert!(view.perspective(60.0, near, MAX_EYE_DISTANCE).is_ok());
    assert_eq!(
        view.perspective(60.0, near * 0.999, MAX_EYE_DISTANCE)
            .unwrap_err(),
        SceneError::DepthRange
    );
}

#[test]
fn up_to_eight_instances() {
    let data = icosphere(0, 0.2);
    let mesh = data.mesh().unwrap();
    let cam = CameraSpec::looking_at([0.0, 0.0, 3.0], [0.0; 3], 60.0, 0.5, 10.0);
    let render = |n: usize| {
        let instances: Vec<Instance<'_>> = (0..n)
            .map(|k| Instance {
                mesh: &mesh,
                transform: Transform::translation([k as f32 * 0.3 - 1.0, 0.0, 0.0]),
            })
            .collect();
        let scene = Scene {
            instances: &instances,
            camera: cam.fixed().unwrap(),
            light: light(),
        };
        let mut ws: Box<Workspace<Rgb565, Flat, 32, 32, 512, 64>> =
            Box::new(Workspace::new(Rgb565::new(0, 0, 0)));
        ws.render(
            &scene,
            &RenderOptions::default(),
            &mut FnSink(|_: Row<'_, Rgb565>| -> Result<(), ()> { Ok(()) }),
        )
    };
    assert_eq!(
        render(MAX_INSTANCES).unwrap().triangles_in as usize,
        20 * MAX_INSTANCES
    );
    assert_eq!(
        render(MAX_INSTANCES + 1).unwrap_err(),
        RenderError::Capacity {
            what: CapacityKind::Instances,
            needed: 9,
            capacity: 8
        }
    );
}

#[test]
fn depth_keeps_order_at_the_far_near_limit() {
    // far/near = 2^20: q at the far plane is 2^-20, still 2^10 steps of I2F30. Two squares 0.5 %
    // apart just inside the far plane must keep their order.
    let (near, far) = (1.0 / 64.0, 16384.0);
    // Model coordinates stay within ±4096; the instance moves them out to 12000–16000 units.
    let sq = |z: f64, s: f64| [[-s, -s, z], [s, -s, z], [s, s, z], [-s, s, z]];
    let mut v = sq(-4000.0, 4000.0).to_vec();
    v.extend(sq(-3920.0, 1300.0)); // 16000 · 0.995 = 15920 from the eye
    let data = mesh_data(&v, &[[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]]);
    let mesh = data.mesh().unwrap();
    let cam = CameraSpec {
        eye: [0.0; 3],
        target: [0.0, 0.0, -1.0],
        up: [0.0, 1.0, 0.0],
        fovy: 60.0,
        near,
        far,
    };
    let placed = Instance {
        mesh: &mesh,
        transform: Transform::translation([0.0, 0.0, -12000.0]),
    };
    let (ids, _) = render_ids::<32, 32, 4>(&[placed], &cam, true);
    assert!(
        ids[16 * 32 + 16] >= 2,
        "the nearer square must win in the middle: {}",
        ids[16 * 32 + 16]
    );
    // The far square spans ±6.9 px around the centre, the near one ±2.3 px: 6 px above the
    // centre only the far square shows.
    assert!(
        ids[10 * 32 + 16] == 0 || ids[10 * 32 + 16] == 1,
        "the far square shows around it: {}",
        ids[10 * 32 + 16]
    );
}

/// The triangle (−1, −1), (1, −1), (0, 1) in z = 0, `count` times: front-facing seen from +z,
/// or back-facing (culled) if `front` is false.
fn repeated_triangle(count: usize, front: bool) -> (Vec<Vertex>, Vec<[u16; 3]>) {
    let vertices = vec![
        vert([-1.0, -1.0, 0.0]),
        vert([1.0, -1.0, 0.0]),
        vert([0.0, 1.0, 0.0]),
    ];
    let winding = if front { [0, 1, 2] } else { [0, 2, 1] };
    (vertices, vec![winding; count])
}

/// The instances seen from (0, 0, 3), as a struct literal (not checked by `Scene::new`).
fn scene_of<'a>(instances: &'a [Instance<'a>]) -> Scene<'a> {
    Scene {
        instances,
        camera: Camera::look_at([0.0, 0.0, 3.0], [0.0; 3], [0.0, 1.0, 0.0])
            .unwrap()
            .perspective(60.0, 0.5, 10.0)
            .unwrap(),
        light: light(),
    }
}

/// An id image, row by row.
#[derive(Default)]
struct IdImage(Vec<i32>);

impl RowSink<TriangleId> for IdImage {
    type Error = ();
    fn write_row(&mut self, row: Row<'_, TriangleId>) -> Result<(), ()> {
        self.0.extend(row.pixels.iter().map(|p| p.0));
        Ok(())
    }
}

#[test]
fn up_to_65535_triangles_per_scene() {
    assert_eq!(MAX_SCENE_TRIANGLES, 65_535);
    let color = MeshColors::Uniform(Rgb888::new(200, 200, 200));
    // 65,534 culled triangles and one visible one, whose id is the largest a scene may have.
    let (v, t) = repeated_triangle(MAX_SCENE_TRIANGLES - 1, false);
    let hidden = Mesh::new(&v, &t, color, None).unwrap();
    let (v1, t1) = repeated_triangle(1, true);
    let shown = Mesh::new(&v1, &t1, color, None).unwrap();
    let place = |mesh| Instance {
        mesh,
        transform: Transform::IDENTITY,
    };
    let at_limit = [place(&hidden), place(&shown)];
    let past_limit = [place(&hidden), place(&shown), place(&shown)];
    // Far past it: the visible triangle's id would wrap to one of the culled ones in 16 bits.
    let wrapped = [place(&hidden), place(&hidden), place(&shown)];

    // Scene::new checks the total.
    let light = light();
    let camera = scene_of(&[]).camera;
    assert_eq!(
        Scene::new(&at_limit, camera, light)
            .unwrap()
            .triangle_count(),
        65_535
    );
    let err = Scene::new(&past_limit, camera, light).unwrap_err();
    assert_eq!(err, SceneError::TooManyTriangles { triangles: 65_536 });
    assert_eq!(
        err.to_string(),
        "the scene has 65536 triangles, more than the limit of 65535 per frame"
    );
    assert_eq!(
        Scene::new(&wrapped, camera, light).unwrap_err(),
        SceneError::TooManyTriangles { triangles: 131_069 }
    );

    // So does every render of a scene built as a struct literal, before any row is sent.
    let options = RenderOptions::default();
    let mut ws: Box<Workspace<TriangleId, Flat, 8, 8, 4, 4>> =
        Box::new(Workspace::new(TriangleId::NONE));
    let mut image = IdImage::default();
    let stats = ws
        .render(&scene_of(&at_limit), &options, &mut image)
        .unwrap();
    assert_eq!(
        (stats.triangles_in, stats.culled, stats.bucketed),
        (65_535, 65_534, 1)
    );
    assert_eq!(image.0.len(), 64);
    assert_eq!(image.0[4 * 8 + 4], 65_534, "the last id is drawn as itself");
    for instances in [&past_limit[..], &wrapped[..]] {
        let mut image = IdImage::default();
        let triangles = scene_of(instances).triangle_count();
        assert_eq!(
            ws.render(&scene_of(instances), &options, &mut image),
            Err(RenderError::TooManyTriangles { triangles })
        );
        assert!(image.0.is_empty(), "no row may be sent");
    }
    assert_eq!(
        RenderError::<()>::TooManyTriangles { triangles: 65_536 }.to_string(),
        "the scene has 65536 triangles, more than the limit of 65535 per frame"
    );

    // The other methods' set-up: a painter's order (bucketed ids), and the whole-frame methods
    // (kept pieces).
    let mut sorted: Box<DepthSortWorkspace<TriangleId, Flat, 8, 8, 4, 4>> =
        Box::new(DepthSortWorkspace::new(TriangleId::NONE));
    let mut newell: Box<NewellWorkspace<TriangleId, Flat, 8, 8, 4, 4>> =
        Box::new(NewellWorkspace::new(TriangleId::NONE));
    let mut warnock: Box<WarnockWorkspace<TriangleId, Flat, 8, 8, 4, 64>> =
        Box::new(WarnockWorkspace::new(TriangleId::NONE));
    for instances in [&at_limit[..], &past_limit[..]] {
        let scene = scene_of(instances);
        let triangles = scene.triangle_count();
        let results = [
            (
                "depth sort",
                sorted.render(&scene, &options, &mut IdImage::default()),
            ),
            (
                "newell",
                newell.render(&scene, &options, &mut IdImage::default()),
            ),
            (
                "warnock",
                warnock.render(&scene, &options, &mut IdImage::default()),
            ),
        ];
        for (name, result) in results {
            if triangles <= MAX_SCENE_TRIANGLES {
                assert_eq!(result.map(|s| s.bucketed), Ok(1), "{name}");
            } else {
                assert_eq!(
                    result,
                    Err(RenderError::TooManyTriangles { triangles }),
                    "{name}"
                );
            }
        }
    }
}

#[test]
fn up_to_65535_bucketed_triangles() {
    // TRIS at its limit: 65,535 visible triangles are filed, the last in bucket entry 65,534,
    // right below the end-of-list mark, and every entry is reached (activated or, with room for
    // 8, dropped).
    let (v, t) = repeated_triangle(MAX_SCENE_TRIANGLES, true);
    let mesh = Mesh::new(&v, &t, MeshColors::Uniform(Rgb888::new(1, 2, 3)), None).unwrap();
    let instances = [instance(&mesh)];
    let mut ws: Box<Workspace<TriangleId, Flat, 8, 8, 65_535, 8>> =
        Box::new(Workspace::new(TriangleId::NONE));
    let mut image = IdImage::default();
    let stats = ws
        .render(&scene_of(&instances), &RenderOptions::default(), &mut image)
        .unwrap();
    assert_eq!(stats.bucketed, 65_535);
    assert_eq!(stats.activated + stats.dropped, 65_535);
    assert_eq!(stats.activated, 8);
    // Coplanar ties go to the triangle activated first: the lowest id.
    assert_eq!(image.0[4 * 8 + 4], 0);
}
