//! Host speed of whole frames: the demo scene (1420 triangles, 240×240) at each sub-pixel
//! setting, flat and Gouraud, into the hashing panel model. `cargo bench --bench render`.
//!
//! Criterion reports time per frame; compare settings as ratios within one run (absolute times
//! depend on the machine). Target speed is measured as instruction counts under QEMU instead:
//! `cargo xtask firmware`.

use criterion::{criterion_group, criterion_main, Criterion};
use embedded_graphics::pixelcolor::Rgb565;
use scanline3d::sink::HashSink;
use scanline3d::{Flat, Gouraud, RenderOptions, Shading, Workspace};
use scanline3d_demo as demo;
use std::hint::black_box;

type Ws<S> = Workspace<Rgb565, S, { demo::WIDTH }, { demo::HEIGHT }, 1024, 96>;

fn frame<S: Shading, const SUB: u32>(ws: &mut Ws<S>, scene: &scanline3d::scene::Scene<'_>) -> u32 {
    let mut sink = HashSink::new();
    let options = RenderOptions::default().with_sub_pixel_bits::<SUB>();
    let stats = ws.render(scene, &options, &mut sink).unwrap_or_default();
    black_box(stats);
    sink.hash()
}

fn bench(c: &mut Criterion) {
    let instances = demo::instances();
    let scene = demo::scene(&instances, 0, demo::ORBIT_FRAMES).expect("demo scene");
    let mut flat: Box<Ws<Flat>> = Box::new(Workspace::new(demo::BACKGROUND.into()));
    let mut gouraud: Box<Ws<Gouraud>> = Box::new(Workspace::new(demo::BACKGROUND.into()));
    let mut group = c.benchmark_group("demo frame 240x240");
    group.bench_function("flat, 0 sub-pixel bits", |b| {
        b.iter(|| frame::<Flat, 0>(&mut flat, &scene))
    });
    group.bench_function("flat, 2 sub-pixel bits", |b| {
        b.iter(|| frame::<Flat, 2>(&mut flat, &scene))
    });
    group.bench_function("flat, 4 sub-pixel bits (default)", |b| {
        b.iter(|| frame::<Flat, 4>(&mut flat, &scene))
    });
    group.bench_function("flat, 8 sub-pixel bits", |b| {
        b.iter(|| frame::<Flat, 8>(&mut flat, &scene))
    });
    group.bench_function("gouraud, 4 sub-pixel bits", |b| {
        b.iter(|| frame::<Gouraud, 4>(&mut gouraud, &scene))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
