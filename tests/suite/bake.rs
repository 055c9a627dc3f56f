//! Face colours lit ahead of time (`shading::bake_face_colors`) and drawn `Unlit` give exactly
//! the frames `Flat` shading draws from the original colours: the demo orbit (its build-time
//! tables and colours baked here for a narrow-normals preset) and corpus meshes.

use embedded_graphics::pixelcolor::Rgb888;
use scanline3d::arithmetic::{Arithmetic, Frugal, Quick};
use scanline3d::clip::Clipping;
use scanline3d::preset::{self, Preset};
use scanline3d::scene::{Instance, Mesh, MeshColors, Scene};
use scanline3d::shading::bake_face_colors;
use scanline3d::sink::HashSink;
use scanline3d::{Flat, RenderOptions, Shading, Unlit, Workspace};
use scanline3d_demo as demo;

/// Per-face colours of every instance of `instances`, baked with arithmetic `A` under `light`.
fn bake_all<A: Arithmetic>(
    instances: &[Instance<'_>],
    light: &scanline3d::scene::Light,
) -> Vec<Vec<Rgb888>> {
    instances
        .iter()
        .map(|inst| {
            let mut out = vec![Rgb888::new(0, 0, 0); inst.mesh.triangles().len()];
            bake_face_colors::<A>(inst.mesh, &inst.transform, light, &mut out).unwrap();
            out
        })
        .collect()
}

/// `instances`' meshes with the per-face colours `colors`.
fn recoloured<'a>(instances: &[Instance<'a>], colors: &'a [Vec<Rgb888>]) -> Vec<Mesh<'a>> {
    instances
        .iter()
        .zip(colors)
        .map(|(inst, c)| {
            let m = inst.mesh;
            Mesh::new(m.vertices(), m.triangles(), MeshColors::PerFace(c), None).unwrap()
        })
        .collect()
}

#[test]
fn the_demos_baked_tables_drawn_unlit_give_the_lit_frames() {
    let mut lit = Box::new(demo::PanelWorkspace::new(demo::BACKGROUND.into()));
    let mut baked = Box::new(demo::BakedPanelWorkspace::<0>::new(demo::BACKGROUND.into()));
    let mut cached = Box::new(demo::BakedPanelWorkspace::<{ demo::PANEL_VERTICES }>::new(
        demo::BACKGROUND.into(),
    ));
    let (plain, tables) = (demo::instances(), demo::baked_instances());
    for frame in 0..demo::ORBIT_FRAMES {
        let scene = demo::scene(&plain, frame, demo::ORBIT_FRAMES).unwrap();
        let want = demo::render_panel_frame(&mut lit, &scene).unwrap();
        let scene = demo::scene(&tables, frame, demo::ORBIT_FRAMES).unwrap();
        let got = demo::render_panel_frame(&mut baked, &scene).unwrap();
        assert_eq!(got, want, "frame {frame}");
        let got = demo::render_panel_frame(&mut cached, &scene).unwrap();
        assert_eq!(got.hash, want.hash, "frame {frame}, vertex cache");
    }
    // The tables are the library's colours for the demo light: baked here, they are equal.
    let light = demo::light().unwrap();
    let colors = bake_all::<scanline3d::arithmetic::Precise>(&plain, &light);
    for (inst, c) in tables.iter().zip(&colors) {
        match inst.mesh.colors() {
            MeshColors::PerFace(t) => assert_eq!(t, &c[..]),
            other => panic!("baked mesh with {other:?}"),
        }
    }
}

/// The hash of `scene` drawn with shading `S` on a 160 × 120 target.
fn frame_hash<S: Shading, const SUB: u32, C: Clipping, A: Arithmetic>(
    scene: &Scene<'_>,
    options: &RenderOptions<SUB, C, A>,
) -> u32 {
    let mut ws: Box<Workspace<Rgb888, S, 160, 120, 10240, 1024, 3>> =
        Box::new(Workspace::new(Rgb888::new(24, 28, 40)));
    let mut sink = HashSink::new();
    let stats = ws.render(scene, options, &mut sink).unwrap();
    assert!(stats.is_complete() && stats.pixels_written > 0);
    sink.hash()
}

/// The demo orbit's frames (at 160 × 120) with `options`: baked for its arithmetic, unlit,
/// equal to flat.
fn demo_with<const SUB: u32, C: Clipping, A: Arithmetic>(options: RenderOptions<SUB, C, A>) {
    let plain = demo::instances();
    let light = demo::light().unwrap();
    let colors = bake_all::<A>(&plain, &light);
    let meshes = recoloured(&plain, &colors);
    let baked: Vec<Instance<'_>> = meshes
        .iter()
        .zip(&plain)
        .map(|(mesh, inst)| Instance {
            mesh,
            transform: inst.transform,
        })
        .collect();
    for frame in 0..demo::ORBIT_FRAMES {
        let lit = demo::scene(&plain, frame, demo::ORBIT_FRAMES).unwrap();
        let unlit = demo::scene(&baked, frame, demo::ORBIT_FRAMES).unwrap();
        assert_eq!(
            frame_hash::<Unlit, SUB, C, A>(&unlit, &options),
            frame_hash::<Flat, SUB, C, A>(&lit, &options),
            "frame {frame}"
        );
    }
}

/// Corpus scenes (one closed mesh, one open one drawn two-sided) from each of their cameras.
fn corpus_with<const SUB: u32, C: Clipping, A: Arithmetic>(options: RenderOptions<SUB, C, A>) {
    let scenes = scanline3d_sim::corpus::all();
    for name in ["icosphere", "heightfield", "interpenetrating"] {
        let corpus = scenes.iter().find(|s| s.name == name).unwrap();
        let options = options.with_back_face_culling(corpus.cull_back_faces);
        for (k, camera) in corpus.cameras.iter().enumerate() {
            let spec = scanline3d_sim::scene::SceneSpec::single(
                corpus.mesh.clone(),
                *camera,
                scanline3d_sim::scene::LightSpec::default(),
                corpus.cull_back_faces,
            );
            spec.with_scene(|scene| {
                let colors = bake_all::<A>(scene.instances, &scene.light);
                let meshes = recoloured(scene.instances, &colors);
                let instances = [Instance {
                    mesh: &meshes[0],
                    transform: scene.instances[0].transform,
                }];
                let unlit = Scene {
                    instances: &instances,
                    ..*scene
                };
                let want = frame_hash::<Flat, SUB, C, A>(scene, &options);
                assert_eq!(
                    frame_hash::<Unlit, SUB, C, A>(&unlit, &options),
                    want,
                    "{name} camera {k}"
                );
                // Unbaked colours drawn unlit differ: the test sees the light.
                assert_ne!(frame_hash::<Unlit, SUB, C, A>(scene, &options), want);
            })
            .unwrap();
        }
    }
}

#[test]
fn baked_colours_drawn_unlit_give_the_flat_frames_with_wide_normals() {
    demo_with(RenderOptions::default());
    corpus_with(RenderOptions::default());
}

#[test]
fn baked_colours_drawn_unlit_give_the_flat_frames_with_narrow_normals() {
    // Frugal: 15-bit normals; Quick: narrow arithmetic everywhere, with Fast's 2 sub-pixel bits.
    let frugal = RenderOptions::default().with_arithmetic(Frugal::default());
    demo_with(frugal);
    corpus_with(frugal);
    let quick = <preset::Fast as Preset>::options().with_arithmetic(Quick::default());
    demo_with(quick);
    corpus_with(quick);
}

#[test]
fn baked_colours_drawn_unlit_give_the_flat_frames_of_the_presets() {
    demo_with(<preset::Fast as Preset>::options());
    corpus_with(<preset::Fast as Preset>::options());
    demo_with(<preset::Exact as Preset>::options());
}

#[test]
fn baking_into_a_table_of_the_wrong_length_fails() {
    let light = demo::light().unwrap();
    let mut short = vec![Rgb888::new(0, 0, 0); demo::SPHERE.triangles().len() - 1];
    let err = bake_face_colors::<scanline3d::arithmetic::Precise>(
        &demo::SPHERE,
        &scanline3d::scene::Transform::IDENTITY,
        &light,
        &mut short,
    )
    .unwrap_err();
    assert_eq!(
        err.to_string(),
        "baked face colours: expected 1280 entries, found 1279"
    );
}
