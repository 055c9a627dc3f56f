//! Host speed of the hidden-surface comparison (`docs/hsr-table.md`): every method of
//! `scanline3d_sim::hsr` on the 100, 2,500 and 60,000-triangle scenes, into the hashing panel
//! model. `cargo bench --bench hsr`; `cargo xtask hsr-table` reads the results from
//! `target/criterion/hsr/<method>/<polygons>/new/estimates.json`.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use embedded_graphics::pixelcolor::{Rgb565, RgbColor};
use scanline3d::sink::HashSink;
use scanline3d_sim::hsr::{self, Method, Resolve, Visit};
use scanline3d_sim::scene::SceneSpec;
use std::hint::black_box;

struct Bench<'a, 'c>(&'a mut criterion::BenchmarkGroup<'c, criterion::measurement::WallTime>);

impl Visit for Bench<'_, '_> {
    type Error = String;
    fn visit<M: Method, const T: usize, const A: usize, const K: usize>(
        &mut self,
        level: usize,
    ) -> Result<(), String> {
        let mut ws = Box::new(M::Ws::<Rgb565, T, A, K>::new(Rgb565::BLACK));
        let id = BenchmarkId::new(M::NAME, hsr::LEVELS[level].polygons);
        SceneSpec::hsr(level)?.with_scene(|scene| {
            // Time only frames that render completely (a capacity error returns early).
            let first = ws
                .frame(scene, &mut HashSink::new())
                .map_err(|e| format!("{} at level {level}: {e}", M::NAME))?;
            if !first.is_complete() {
                return Err(format!("{} at level {level}: incomplete frame", M::NAME));
            }
            self.0.bench_function(id, |b| {
                b.iter(|| {
                    let mut sink = HashSink::new();
                    black_box(ws.frame(scene, &mut sink).ok());
                    sink.hash()
                })
            });
            Ok(())
        })?
    }
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("hsr");
    // A 60,000-triangle frame takes milliseconds: fewer samples keep the run short.
    group.sample_size(20);
    if let Err(e) = hsr::for_each(&mut Bench(&mut group)) {
        panic!("hsr bench: {e}");
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
