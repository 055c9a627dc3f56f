//! Host speed of the precision variants (`docs/tradeoff.md`): every variant of
//! `scanline3d_sim::tradeoff::VARIANTS` on every corpus scene from its first camera, at 240×240,
//! into the hashing panel model; and each Gouraud interpolation mode on the demo orbit (whose
//! instructions the same table counts). `cargo bench --bench tradeoff`; `cargo xtask tradeoff`
//! reads `target/criterion/tradeoff/<variant>/<scene>/new/estimates.json` and
//! `target/criterion/tradeoff-gouraud/<mode>/demo-orbit/new/estimates.json`.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use embedded_graphics::pixelcolor::{Rgb565, RgbColor};
use scanline3d::arithmetic::{Arithmetic, Precise, Setup};
use scanline3d::arithmetic::{ExactDivision, Reciprocal};
use scanline3d::arithmetic::{NarrowTransform, WideTransform};
use scanline3d::depth::{Depth16, DepthFormat};
use scanline3d::math::{NarrowNormals, WideNormals};
use scanline3d::options::MAX_INSTANCES;
use scanline3d::scene::Scene;
use scanline3d::shading::{Affine, Interpolation, PerPixel, PerSegment};
use scanline3d::sink::HashSink;
use scanline3d::{Depth, Flat, Gouraud, RenderOptions, Workspace};
use scanline3d_demo as demo;
use scanline3d_sim::corpus;
use scanline3d_sim::interpolation::Mode;
use scanline3d_sim::scene::{DepthChoice, LightSpec, SceneSpec, SetupArith};
use scanline3d_sim::tradeoff::VARIANTS;
use std::hint::black_box;
use std::time::Duration;

/// Room for the largest corpus scene (10,082 triangles) and 240 slivers crossing one row.
type Ws<Z> = Workspace<Rgb565, Flat, 240, 240, 16384, 1024, MAX_INSTANCES, Z>;

type Group<'c> = criterion::BenchmarkGroup<'c, criterion::measurement::WallTime>;

fn time<const S: u32, A: Arithmetic, Z: DepthFormat>(
    group: &mut Group<'_>,
    (variant, scene_name): (&str, &str),
    ws: &mut Ws<Z>,
    scene: &Scene<'_>,
    cull: bool,
) {
    let options = RenderOptions::default()
        .with_back_face_culling(cull)
        .with_sub_pixel_bits::<S>()
        .with_arithmetic(A::default());
    let first = ws.render(scene, &options, &mut HashSink::new());
    assert!(
        first.is_ok_and(|s| s.is_complete()),
        "{variant} on {scene_name}: incomplete frame"
    );
    group.bench_function(BenchmarkId::new(variant, scene_name), |b| {
        b.iter(|| {
            let mut sink = HashSink::new();
            black_box(ws.render(scene, &options, &mut sink).ok());
            sink.hash()
        })
    });
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("tradeoff");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_millis(1000));
    let mut ws: Box<Ws<Depth>> = Box::new(Workspace::new(Rgb565::BLACK));
    let mut ws16: Box<Ws<Depth16>> = Box::new(Workspace::new(Rgb565::BLACK));
    for scene in corpus::all() {
        let spec = SceneSpec::single(
            scene.mesh.clone(),
            scene.cameras[0],
            LightSpec::default(),
            scene.cull_back_faces,
        );
        for v in VARIANTS {
            let id = (v.name, scene.name);
            let cull = spec.cull_back_faces;
            let p = v.precision;
            spec.with_scene_math(p.math, |s| match (p.sub_bits, p.arith) {
                _ if p.depth == DepthChoice::Q16 => {
                    assert_eq!((p.sub_bits, p.arith), (4, SetupArith::Precise));
                    time::<4, Precise, Depth16>(&mut group, id, &mut ws16, s, cull)
                }
                (0, SetupArith::Precise) => time::<0, Precise, _>(&mut group, id, &mut ws, s, cull),
                (2, SetupArith::NarrowTransform) => {
                    type A = Setup<NarrowTransform, ExactDivision, WideNormals>;
                    time::<2, A, _>(&mut group, id, &mut ws, s, cull)
                }
                (4, SetupArith::Precise) => time::<4, Precise, _>(&mut group, id, &mut ws, s, cull),
                (8, SetupArith::Precise) => time::<8, Precise, _>(&mut group, id, &mut ws, s, cull),
                (4, SetupArith::NarrowTransform) => {
                    type A = Setup<NarrowTransform, ExactDivision, WideNormals>;
                    time::<4, A, _>(&mut group, id, &mut ws, s, cull)
                }
                (4, SetupArith::Reciprocal) => {
                    type A = Setup<WideTransform, Reciprocal, WideNormals>;
                    time::<4, A, _>(&mut group, id, &mut ws, s, cull)
                }
                (4, SetupArith::NarrowNormals) => {
                    type A = Setup<WideTransform, ExactDivision, NarrowNormals>;
                    time::<4, A, _>(&mut group, id, &mut ws, s, cull)
                }
                other => panic!("no benchmark for {other:?}"),
            })
            .expect("corpus scene");
        }
    }
    group.finish();
}

/// One demo orbit (every frame) with `Gouraud<I>`, as `firmware/examples/tradeoff.rs` renders it on the
/// targets.
fn time_gouraud<I: Interpolation>(group: &mut Group<'_>, mode: Mode) {
    type GouraudWs<I> =
        Workspace<Rgb565, Gouraud<I>, 240, 240, 640, 80, { demo::PANEL_INSTANCES }, Depth>;
    let mut ws: Box<GouraudWs<I>> = Box::new(Workspace::new(Rgb565::BLACK));
    let instances = demo::instances();
    let scenes: Vec<Scene<'_>> = (0..demo::ORBIT_FRAMES)
        .map(|f| demo::scene(&instances, f, demo::ORBIT_FRAMES).expect("demo scene"))
        .collect();
    let options = RenderOptions::default();
    group.bench_function(BenchmarkId::new(mode.name(), "demo-orbit"), |b| {
        b.iter(|| {
            let mut sink = HashSink::new();
            for scene in &scenes {
                black_box(ws.render(scene, &options, &mut sink).ok());
            }
            sink.hash()
        })
    });
}

fn bench_gouraud(c: &mut Criterion) {
    let mut group = c.benchmark_group("tradeoff-gouraud");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_millis(1000));
    for mode in Mode::ALL {
        match mode {
            Mode::Affine => time_gouraud::<Affine>(&mut group, mode),
            Mode::Segments16 => time_gouraud::<PerSegment<16>>(&mut group, mode),
            Mode::Segments8 => time_gouraud::<PerSegment<8>>(&mut group, mode),
            Mode::PerPixel => time_gouraud::<PerPixel>(&mut group, mode),
        }
    }
    group.finish();
}

criterion_group!(benches, bench, bench_gouraud);
criterion_main!(benches);
