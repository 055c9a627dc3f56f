//! Hostile input: every bad input gets a specific error, and the sink never sees a garbage row.

use crate::common;

use common::*;
use embedded_graphics::pixelcolor::{Rgb565, Rgb888};
use scanline3d::math::Micromath;
use scanline3d::scene::{Camera, Instance, Mesh, MeshColors, Scene, SceneError, Transform};
use scanline3d::sink::{FnSink, Row};
use scanline3d::stats::CapacityKind;
use scanline3d::{Flat, RenderError, RenderOptions, Workspace};

#[test]
fn bad_cameras_and_lights_get_specific_errors() {
    let up = [0.0, 1.0, 0.0];
    let look = |eye: [f32; 3], target: [f32; 3], up: [f32; 3]| {
        Camera::look_at(eye, target, up).map(|_| ())
    };
    assert_eq!(
        look([f32::INFINITY, 0.0, 0.0], [0.0; 3], up),
        Err(SceneError::NonFinite { what: "camera eye" })
    );
    assert_eq!(
        look([0.0, 0.0, 1.0], [0.0, f32::NAN, 0.0], up),
        Err(SceneError::NonFinite {
            what: "camera target"
        })
    );
    assert_eq!(
        look([0.0; 3], [0.0; 3], up),
        Err(SceneError::EyeEqualsTarget)
    );
    assert_eq!(
        look([0.0; 3], [0.0, 0.0, -1.0], [0.0; 3]),
        Err(SceneError::DegenerateUp)
    );
    // Looking straight along the up vector.
    assert_eq!(
        look([0.0; 3], [0.0, 3.0, 0.0], up),
        Err(SceneError::DegenerateUp)
    );
    let view = Camera::look_at([0.0, 0.0, 5.0], [0.0; 3], up).unwrap();
    for (fov, near, far, err) in [
        (0.0, 0.1, 10.0, SceneError::FieldOfView),
        (180.0, 0.1, 10.0, SceneError::FieldOfView),
        (200.0, 0.1, 10.0, SceneError::FieldOfView),
        (60.0, 0.0, 10.0, SceneError::DepthRange),
        (60.0, -1.0, 10.0, SceneError::DepthRange),
        (60.0, 10.0, 10.0, SceneError::DepthRange),
        (60.0, 10.0, 5.0, SceneError::DepthRange),
        (60.0, f32::NAN, 5.0, SceneError::NonFinite { what: "near" }),
    ] {
        assert_eq!(
            view.perspective(fov, near, far).map(|_| ()),
            Err(err),
            "fov {fov} near {near} far {far}"
        );
    }
    assert_eq!(
        scanline3d::scene::Light::new([f32::INFINITY, 0.0, 0.0], 0.2, 0.8).map(|_| ()),
        Err(SceneError::NonFinite {
            what: "light direction"
        })
    );
}

#[test]
fn bad_meshes_get_specific_errors() {
    let v = [
        vert([0.0, 0.0, 0.0]),
        vert([1.0, 0.0, 0.0]),
        vert([0.0, 1.0, 0.0]),
    ];
    let c = MeshColors::Uniform(Rgb888::new(1, 2, 3));
    assert!(matches!(
        Mesh::new(&v, &[[0, 1, 9]], c, None),
        Err(SceneError::IndexOutOfRange {
            triangle: 0,
            index: 9,
            vertex_count: 3
        })
    ));
    let far = [
        vert([0.0, 0.0, 0.0]),
        vert([4097.0, 0.0, 0.0]),
        vert([0.0, 1.0, 0.0]),
    ];
    assert!(matches!(
        Mesh::new(&far, &[[0, 1, 2]], c, None),
        Err(SceneError::VertexOutOfEnvelope { vertex: 1 })
    ));
}

fn count_rows<P: scanline3d::sink::RowPixel>(
    rows: &mut Vec<u16>,
) -> FnSink<impl FnMut(Row<'_, P>) -> Result<(), ()> + '_> {
    FnSink(move |row: Row<'_, P>| {
        rows.push(row.y);
        Ok(())
    })
}

#[test]
fn empty_meshes_and_scenes_render_background_rows() {
    let empty = Mesh::new(&[], &[], MeshColors::Uniform(Rgb888::new(0, 0, 0)), None).unwrap();
    let cam = CameraSpec::looking_at([0.0, 0.0, 3.0], [0.0; 3], 60.0, 0.5, 10.0);
    for instances in [
        &[][..],
        &[Instance {
            mesh: &empty,
            transform: Transform::IDENTITY,
        }][..],
    ] {
        let scene = Scene {
            instances,
            camera: cam.fixed().unwrap(),
            light: light(),
        };
        let mut ws: Workspace<Rgb565, Flat, 8, 6, 4, 4> = Workspace::new(Rgb565::new(1, 2, 3));
        let mut rows = Vec::new();
        let mut sink = FnSink(|row: Row<'_, Rgb565>| -> Result<(), ()> {
            assert!(row.pixels.iter().all(|p| *p == Rgb565::new(1, 2, 3)));
            rows.push(row.y);
            Ok(())
        });
        let stats = ws
            .render(&scene, &RenderOptions::default(), &mut sink)
            .unwrap();
        assert_eq!((stats.triangles_in, stats.fragments), (0, 0));
        assert_eq!(rows, [0, 1, 2, 3, 4, 5]);
    }
}

#[test]
fn capacity_and_instance_overflow_fail_before_any_row() {
    let data = icosphere(1, 1.0);
    let mesh = data.mesh().unwrap();
    let cam = CameraSpec::looking_at([0.0, 0.0, 3.0], [0.0; 3], 60.0, 0.5, 10.0);
    let nine: Vec<Instance<'_>> = (0..9).map(|_| instance(&mesh)).collect();
    let scene = Scene {
        instances: &nine,
        camera: cam.fixed().unwrap(),
        light: light(),
    };
    let mut ws: Box<Workspace<Rgb565, Flat, 16, 16, 1024, 64>> =
        Box::new(Workspace::new(Rgb565::new(0, 0, 0)));
    let mut rows = Vec::new();
    let err = ws
        .render(
            &scene,
            &RenderOptions::default(),
            &mut count_rows(&mut rows),
        )
        .unwrap_err();
    assert_eq!(
        err,
        RenderError::Capacity {
            what: CapacityKind::Instances,
            needed: 9,
            capacity: 8
        }
    );
    assert!(rows.is_empty());
}

#[test]
fn accumulated_micromath_rotation_stays_rigid_when_reorthonormalised() {
    // 5000 frames of a small rotation accumulated by multiplication with the approximate
    // backend. Unchecked, the product drifts; re-orthonormalised each frame it stays a rotation,
    // the mesh stays inside the envelope, and frames keep rendering.
    let step = Transform::rotation_y_with::<Micromath>(0.013)
        .then_after(&Transform::rotation_x_with::<Micromath>(0.007));
    let (mut drifting, mut rigid) = (Transform::IDENTITY, Transform::IDENTITY);
    for _ in 0..5000 {
        drifting = step.then_after(&drifting);
        rigid = step.then_after(&rigid).orthonormalized_with::<Micromath>();
    }
    let scale = |t: &Transform| {
        let p = t.apply([1.0, 0.0, 0.0]);
        (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt()
    };
    println!(
        "after 5000 frames: drifting scale {}, re-orthonormalised scale {}",
        scale(&drifting),
        scale(&rigid)
    );
    assert!((scale(&rigid) - 1.0).abs() < 1e-3, "{}", scale(&rigid));
    let data = icosphere(2, 1.0);
    let mesh = data.mesh().unwrap();
    let cam = CameraSpec::looking_at([0.0, 0.0, 3.0], [0.0; 3], 60.0, 0.5, 10.0);
    let instances = [Instance {
        mesh: &mesh,
        transform: rigid,
    }];
    let scene = Scene {
        instances: &instances,
        camera: cam.fixed().unwrap(),
        light: light(),
    };
    let mut ws: Box<Workspace<Rgb565, Flat, 48, 48, 512, 64>> =
        Box::new(Workspace::new(Rgb565::new(0, 0, 0)));
    let mut rows = Vec::new();
    let stats = ws
        .render(
            &scene,
            &RenderOptions::default(),
            &mut count_rows(&mut rows),
        )
        .unwrap();
    // A unit sphere at distance 3 with a 60° field of view covers about a third of the frame.
    assert!(
        stats.is_complete() && stats.fragments > 400 && stats.fragments < 900,
        "{stats:?}"
    );
}
