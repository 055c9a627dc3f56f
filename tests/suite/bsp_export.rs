//! The BSP tree `sim export --bsp` writes as `static` data (`firmware/examples/lean/cyclic_bsp.rs`, the
//! lecture's cyclic-overlap case) renders on the host exactly as `sim`'s BSP method renders the
//! OBJ it came from: the same frames the lean BSP firmware must print under QEMU.

#[path = "../../firmware/examples/lean/cyclic_bsp.rs"]
mod scene;

use embedded_graphics::pixelcolor::Rgb565;
use scanline3d::scene::{Camera, Instance, Light, Scene, Transform};
use scanline3d::sink::HashSink;
use scanline3d::{Flat, RenderOptions};
use scanline3d_sim::scene::{Algorithm, CameraSpec, MeshData, SceneSpec};

#[test]
fn exported_tree_renders_every_view_as_the_host_bsp_does() {
    let obj = MeshData::load_obj(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("sim/corpus/cyclic.obj"),
    )
    .unwrap();
    assert_eq!(scene::BSP_TREE.triangles(), scene::TRIANGLES.len());
    assert!(
        scene::TRIANGLES.len() > obj.triangles.len(),
        "the cyclic case must be split"
    );
    let instances = [Instance {
        mesh: &scene::MESH,
        transform: Transform::IDENTITY,
    }];
    let (fovy, near, far) = scene::PROJECTION;
    let (towards, ambient, diffuse) = scene::LIGHT;
    let options = RenderOptions::default().with_back_face_culling(scene::CULL_BACK_FACES);
    let mut ws = Box::new(scene::SceneBspWorkspace::<Rgb565, Flat>::new(Rgb565::new(
        0, 0, 0,
    )));
    let mut hashes = Vec::new();
    for (eye, target, up) in scene::VIEWS {
        let frame = Scene {
            instances: &instances,
            camera: Camera::look_at(eye, target, up)
                .unwrap()
                .perspective(fovy, near, far)
                .unwrap(),
            light: Light::new(towards, ambient, diffuse).unwrap(),
        };
        let mut sink = HashSink::new();
        let stats = ws
            .render(&frame, &scene::BSP_TREE, &options, &mut sink)
            .unwrap();
        assert!(stats.is_complete());
        assert!(stats.activated > 0);
        let spec = SceneSpec::single(
            obj.clone(),
            CameraSpec {
                eye: eye.map(f64::from),
                target: target.map(f64::from),
                up: up.map(f64::from),
                fovy: fovy.into(),
                near: near.into(),
                far: far.into(),
            },
            Default::default(),
            scene::CULL_BACK_FACES,
        );
        let host = spec
            .panel_hash_with(scene::WIDTH, scene::HEIGHT, Algorithm::Bsp)
            .unwrap();
        assert_eq!(sink.hash(), host);
        hashes.push(host);
    }
    // Eight different views, not eight empty frames.
    hashes.sort_unstable();
    hashes.dedup();
    assert_eq!(hashes.len(), scene::VIEWS.len());
}
