//! The hidden-surface methods of `scanline3d::resolve` against the span z-buffer: the exact
//! ones (band and full-frame z-buffers, span sorting) must render bit-identical frames, with
//! flat and Gouraud shading, at full and reduced target sizes. Depth sort must paint every
//! covered pixel; its errors are measured against the reference in `sim/tests/suite/hsr.rs`.

use embedded_graphics::pixelcolor::{Rgb565, Rgb888};
use scanline3d::resolve::{BandWorkspace, DepthSortWorkspace, SpanSortWorkspace, ZBufferWorkspace};
use scanline3d::scene::Scene;
use scanline3d::sink::{FnSink, HashSink, Row, TriangleId};
use scanline3d::{Flat, FrameStats, Gouraud, RenderOptions, Shading, Workspace};
use scanline3d_demo as demo;

const W: usize = demo::WIDTH;
const H: usize = demo::HEIGHT;
const TRIS: usize = 1536;
const ACTIVE: usize = 128;

/// Renders with workspace expression `$ws` into a hash, at `w × h`.
macro_rules! hash_of {
    ($ws:expr, $scene:expr, $w:expr, $h:expr) => {{
        let mut sink = HashSink::new();
        let stats = $ws
            .render_sized($w, $h, $scene, &RenderOptions::default(), &mut sink)
            .unwrap();
        (sink.hash(), stats)
    }};
}

fn check_exact_methods<S: Shading>(scene: &Scene<'_>, w: usize, h: usize) {
    let bg = Rgb565::new(3, 6, 5);
    let mut span = Box::new(Workspace::<Rgb565, S, W, H, TRIS, ACTIVE>::new(bg));
    let (expected, base) = hash_of!(span, scene, w, h);
    assert!(base.is_complete() && base.fragments > 10_000);

    let mut band1 = Box::new(BandWorkspace::<Rgb565, S, W, H, 1, TRIS, ACTIVE>::new(bg));
    let mut band7 = Box::new(BandWorkspace::<Rgb565, S, W, H, 7, TRIS, ACTIVE>::new(bg));
    let mut full = Box::new(ZBufferWorkspace::<Rgb565, S, W, H, TRIS>::new(bg));
    let mut sort = Box::new(SpanSortWorkspace::<Rgb565, S, W, H, TRIS, ACTIVE>::new(bg));
    let results: [(&str, (u32, FrameStats)); 4] = [
        ("band:1", hash_of!(band1, scene, w, h)),
        ("band:7", hash_of!(band7, scene, w, h)),
        ("zbuffer", hash_of!(full, scene, w, h)),
        ("span-sort", hash_of!(sort, scene, w, h)),
    ];
    for (name, (hash, stats)) in results {
        assert_eq!(hash, expected, "{name} at {w}x{h}: frame differs");
        assert!(stats.is_complete(), "{name}: {stats:?}");
        // The same triangles are walked, so the same fragments are covered.
        assert_eq!(stats.fragments, base.fragments, "{name}");
        assert_eq!(stats.activated, base.activated, "{name}");
    }
    // Span sorting writes each visible pixel once; the z-buffers also rewrite pixels that a
    // nearer surface later covers.
    let sorted = results[3].1 .1;
    assert!(sorted.pixels_written <= (w * h) as u32);
    assert!(sorted.pixels_written < base.pixels_written);
    // A full-frame z-buffer carries no triangle from band to band.
    assert_eq!(results[2].1 .1.peak_active, 0);
}

#[test]
fn exact_methods_render_the_span_zbuffer_frame_bit_for_bit() {
    let instances = demo::instances();
    for frame in [0, 3, 5] {
        let scene = demo::scene(&instances, frame, demo::ORBIT_FRAMES).unwrap();
        check_exact_methods::<Flat>(&scene, W, H);
        check_exact_methods::<Gouraud>(&scene, W, H);
        check_exact_methods::<Flat>(&scene, 200, 131);
    }
}

/// Records a `TriangleId` row into an id image.
fn record(out: &mut [i32], row: Row<'_, TriangleId>) -> Result<(), ()> {
    for (x, id) in row.pixels.iter().enumerate() {
        out[row.y as usize * W + x] = id.0;
    }
    Ok(())
}

#[test]
fn depth_sort_paints_every_fragment_and_covers_what_the_zbuffer_covers() {
    let instances = demo::instances();
    let scene = demo::scene(&instances, 2, demo::ORBIT_FRAMES).unwrap();
    let options = RenderOptions::default();
    let none = TriangleId::NONE;
    let mut zs = Box::new(Workspace::<TriangleId, Flat, W, H, TRIS, ACTIVE>::new(none));
    let mut ds = Box::new(DepthSortWorkspace::<TriangleId, Flat, W, H, TRIS, ACTIVE>::new(none));
    let (mut z, mut d) = (vec![-2; W * H], vec![-2; W * H]);
    let z_stats = zs
        .render(
            &scene,
            &options,
            &mut FnSink(|row: Row<'_, TriangleId>| record(&mut z, row)),
        )
        .unwrap();
    let d_stats = ds
        .render(
            &scene,
            &options,
            &mut FnSink(|row: Row<'_, TriangleId>| record(&mut d, row)),
        )
        .unwrap();
    assert_eq!(d_stats.pixels_written, d_stats.fragments);
    assert_eq!(d_stats.fragments, z_stats.fragments);
    // Same coverage; the ids may differ where the order by mean depth is wrong.
    let covered = |v: &[i32]| v.iter().map(|&i| i >= 0).collect::<Vec<_>>();
    assert_eq!(covered(&z), covered(&d));
    let differ = z.iter().zip(&d).filter(|(a, b)| a != b).count();
    // A closed, convex-ish scene is what depth sorting handles well: nearly all pixels agree.
    assert!(
        differ * 100 < z.iter().filter(|&&i| i >= 0).count(),
        "{differ} differ"
    );
}

#[test]
fn band_zbuffer_with_a_full_active_list_degrades_like_the_span_zbuffer() {
    // Room for 4 triangles crossing a band boundary: the rest are dropped and reported.
    let instances = demo::instances();
    let scene = demo::scene(&instances, 0, demo::ORBIT_FRAMES).unwrap();
    let mut ws = Box::new(BandWorkspace::<Rgb888, Flat, W, H, 16, TRIS, 4>::new(
        Rgb888::new(0, 0, 0),
    ));
    let mut incomplete = 0;
    let mut sink = FnSink(|row: Row<'_, Rgb888>| -> Result<(), ()> {
        incomplete += !row.complete as u32;
        Ok(())
    });
    let stats = ws
        .render(&scene, &RenderOptions::default(), &mut sink)
        .unwrap();
    assert!(!stats.is_complete());
    assert!(stats.dropped_pieces[0].is_some());
    assert_eq!(incomplete, stats.incomplete_rows as u32);
    assert!(stats.incomplete_rows > 0);
}

#[test]
fn band_memory_grows_by_one_row_of_depth_and_pixels_per_band_row() {
    type Band8 = BandWorkspace<Rgb565, Flat, 240, 240, 8, 1000, 64>;
    type Band1 = BandWorkspace<Rgb565, Flat, 240, 240, 1, 1000, 64>;
    // 7 more rows of 4-byte depth, 2-byte pixels and a 2-byte span count (up to padding).
    let extra = 7 * (240 * (4 + 2) + 2);
    assert!((Band8::BYTES - Band1::BYTES).abs_diff(extra) < 8);
    type Full = ZBufferWorkspace<Rgb565, Flat, 240, 240, 1000>;
    const { assert!(Full::BYTES >= 240 * 240 * (4 + 2)) };
}
