//! Host speed of ours against the peer renderers a user would otherwise pick (`euc`,
//! `embedded-3dgfx`; see `scanline3d_sim::peers`): every corpus scene from its first camera at
//! 240×240, each renderer writing a whole Rgb565 frame. `cargo bench --bench peers`; results
//! under `target/criterion/peers/<renderer>/<scene>/`.
//!
//! * `ours`: the default `Workspace` (span z-buffer, flat shading with Lambert lighting, 4
//!   sub-pixel bits) into a `FrameBuffer` of the whole frame (every row is written).
//! * `ours-cached`: the same with a vertex cache (`VERTS` = 16384): each vertex transformed
//!   and projected once per frame instead of once per triangle and pass; the same pixels.
//! * `ours-exact`: the default `Workspace` with the `Exact` preset (8 sub-pixel bits, exact
//!   set-up arithmetic): our most accurate frame.
//! * `euc`: clear colour and depth buffers, draw the triangle list with per-vertex colours.
//! * `embedded-3dgfx`: clear the frame, record + execute one solid mesh per triangle (its solid
//!   mode has one colour per mesh, so per-face colours, as ours draws them, need that).
//! * `embedded-3dgfx-1mesh`: the same with the whole scene as one mesh in one colour: its
//!   cheapest solid frame, for scale (not the same picture).
//!
//! Set-up a user does once (mesh conversion, meshes, buffers) is outside the timed loop. Frames
//! a peer renders wrongly (see the peers table) are timed all the same: the time is what the
//! user would pay for that wrong frame. Compare as ratios within one run.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use embedded_graphics::pixelcolor::{Rgb565, RgbColor};
use scanline3d::preset::{Exact, Preset};
use scanline3d::sink::FrameBuffer;
use scanline3d::{Depth, Flat, RenderOptions, Workspace};
use scanline3d_sim::corpus;
use scanline3d_sim::peers::{E3dScene, EucScene};
use scanline3d_sim::scene::{LightSpec, SceneSpec};
use std::hint::black_box;
use std::time::Duration;

const W: usize = 240;
const H: usize = 240;

/// Room for the largest corpus scene (10,082 triangles) and 240 slivers crossing one row.
type Ours = Workspace<Rgb565, Flat, W, H, 16384, 1024>;
/// The same with a vertex cache for every corpus scene's vertices (`scanline3d::cache`).
type OursCached = Workspace<Rgb565, Flat, W, H, 16384, 1024, 8, Depth, 16384>;

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("peers");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_millis(1500));
    let mut ours: Box<Ours> = Box::new(Workspace::new(Rgb565::BLACK));
    let mut cached: Box<OursCached> = Box::new(Workspace::new(Rgb565::BLACK));
    let mut frame = vec![Rgb565::BLACK; W * H];
    for scene in corpus::all() {
        let spec = SceneSpec::single(
            scene.mesh.clone(),
            scene.cameras[0],
            LightSpec::default(),
            scene.cull_back_faces,
        );
        let name = scene.name;

        let options = RenderOptions::default().with_back_face_culling(spec.cull_back_faces);
        spec.with_scene(|s| {
            let stats = ours
                .render(s, &options, &mut FrameBuffer::new(&mut frame, W))
                .expect("ours renders the corpus");
            assert!(stats.is_complete(), "{name}: incomplete frame");
            group.bench_function(BenchmarkId::new("ours", name), |b| {
                b.iter(|| {
                    let stats = ours.render(s, &options, &mut FrameBuffer::new(&mut frame, W));
                    black_box(stats.ok());
                })
            });
            let stats = cached
                .render(s, &options, &mut FrameBuffer::new(&mut frame, W))
                .expect("ours renders the corpus");
            assert!(stats.cached_vertices > 0, "{name}: the cache is too small");
            group.bench_function(BenchmarkId::new("ours-cached", name), |b| {
                b.iter(|| {
                    let stats = cached.render(s, &options, &mut FrameBuffer::new(&mut frame, W));
                    black_box(stats.ok());
                })
            });
            let exact = Exact::options().with_back_face_culling(spec.cull_back_faces);
            let stats = ours
                .render(s, &exact, &mut FrameBuffer::new(&mut frame, W))
                .expect("ours renders the corpus");
            assert!(stats.is_complete(), "{name}: incomplete frame");
            group.bench_function(BenchmarkId::new("ours-exact", name), |b| {
                b.iter(|| {
                    let stats = ours.render(s, &exact, &mut FrameBuffer::new(&mut frame, W));
                    black_box(stats.ok());
                })
            });
        })
        .expect("scene");

        let euc = EucScene::new(&spec, W, H).expect("euc set-up");
        let (mut colour, mut depth) = euc.buffers();
        group.bench_function(BenchmarkId::new("euc", name), |b| {
            b.iter(|| {
                euc.render_colours(&mut colour, &mut depth);
                black_box(colour.as_ref()[W * H / 2]);
            })
        });

        let e3d = E3dScene::new(&spec, W, H).expect("embedded-3dgfx set-up");
        let (mut fb, mut z, mut commands) = e3d.buffers();
        for (id, meshes) in [
            ("embedded-3dgfx", e3d.colour_meshes()),
            ("embedded-3dgfx-1mesh", e3d.single_mesh()),
        ] {
            e3d.render_frame(&meshes, &mut fb, &mut z, &mut commands)
                .expect("embedded-3dgfx renders");
            group.bench_function(BenchmarkId::new(id, name), |b| {
                b.iter(|| {
                    black_box(
                        e3d.render_frame(&meshes, &mut fb, &mut z, &mut commands)
                            .ok(),
                    );
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
