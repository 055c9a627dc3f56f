use scanline3d::resolve::NewellWorkspace;
use scanline3d::sink::{FnSink, Row, TriangleId};
use scanline3d::{Flat, RenderOptions};
use scanline3d_sim::corpus::real_world;
use scanline3d_sim::scene::{LightSpec, SceneSpec};

#[test]
fn probe() {
    std::thread::Builder::new()
        .stack_size(512 << 20)
        .spawn(|| {
            for n in [50usize, 100, 200, 400] {
                let mut m = real_world::soup();
                m.triangles.truncate(n);
                m.colors.truncate(n);
                for cam in real_world::soup_cameras() {
                    let spec = SceneSpec::single(m.clone(), cam, LightSpec::default(), false);
                    spec.with_scene(|scene| {
                        let mut ws: Box<NewellWorkspace<TriangleId, Flat, 240, 240, 65534, 4096>> =
                            Box::new(NewellWorkspace::new(TriangleId::NONE));
                        let mut sink = FnSink(
                            |_r: Row<'_, TriangleId>| -> Result<(), core::convert::Infallible> {
                                Ok(())
                            },
                        );
                        let r = ws.render(
                            scene,
                            &RenderOptions::default().with_back_face_culling(false),
                            &mut sink,
                        );
                        println!(
                            "n {n}: {:?} {:?}",
                            r.map(|_| ()).map_err(|e| e.to_string()),
                            ws.sort_stats()
                        );
                    })
                    .unwrap();
                }
            }
        })
        .unwrap()
        .join()
        .unwrap();
}
