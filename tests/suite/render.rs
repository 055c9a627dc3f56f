//! End-to-end renders compared with the independent f64 ray caster in `common`, plus memory,
//! error and degradation behaviour.

use crate::common;

use common::*;
use embedded_graphics::pixelcolor::{BinaryColor, Gray8, Rgb565, Rgb888, RgbColor};
use scanline3d::cache::{vertex_cache_bytes, CachedVertex};
use scanline3d::clip::NoClip;
use scanline3d::depth::Depth16;
use scanline3d::scene::{Instance, Mesh, MeshColors, Scene, Transform};
use scanline3d::shading::PerPixel;
use scanline3d::sink::{FnSink, HashSink, Row, TriangleId};
use scanline3d::stats::CapacityKind;
use scanline3d::workspace::workspace_bytes;
use scanline3d::Depth;
use scanline3d::{Flat, Gouraud, RenderError, RenderOptions, Workspace};

#[test]
fn interpenetrating_triangles_resolve_per_pixel() {
    // Two triangles crossing each other along x = 0: each is in front on one side.
    let verts = [
        [-1.5, -1.0, -0.8],
        [1.5, -1.0, 0.8],
        [0.0, 1.2, 0.0],
        [-1.5, 1.0, 0.8],
        [0.0, -1.2, 0.0],
        [1.5, 1.0, -0.8],
    ];
    let data = mesh_data(&verts, &[[0, 1, 2], [3, 4, 5]]);
    let mesh = data.mesh().unwrap();
    let cam = CameraSpec::looking_at([0.3, 0.2, 4.0], [0.0; 3], 50.0, 0.5, 20.0);
    let (ids, _) = render_ids::<64, 64, 4>(&[instance(&mesh)], &cam, false);
    let (mismatches, real) = compare(&[&data], &cam, &ids, 64, 64, 4, false);
    assert_eq!(real, 0, "{mismatches} mismatches");
    // Both triangles win somewhere on both sides of the intersection line.
    for id in [0, 1] {
        let left = (0..64 * 64)
            .filter(|&i| ids[i] == id && i % 64 < 28)
            .count();
        let right = (0..64 * 64)
            .filter(|&i| ids[i] == id && i % 64 > 36)
            .count();
        assert!(
            left > 50 && right > 50,
            "triangle {id}: {left} left, {right} right"
        );
    }
}

/// A ground quad under a camera standing on it: some triangles have one or two vertices behind
/// the eye and must be clipped at the near plane, not vanish or explode.
/// A 40×40 ground square as a fan around a vertex just in front of the cameras' feet: with the
/// cameras below, its far corners lie behind the eye, so it crosses the near plane.
fn ground_fan() -> (Vec<[f64; 3]>, Vec<[u16; 3]>) {
    let verts = vec![
        [-20.0, 0.0, 20.0],
        [20.0, 0.0, 20.0],
        [20.0, 0.0, -20.0],
        [-20.0, 0.0, -20.0],
        [0.0, 0.0, 1.0],
    ];
    (verts, vec![[4, 0, 1], [4, 1, 2], [4, 2, 3], [4, 3, 0]])
}

#[test]
fn near_plane_crossing_triangles_render() {
    let (verts, tris) = ground_fan();
    let data = mesh_data(&verts, &tris);
    let mesh = data.mesh().unwrap();
    let cam = CameraSpec::looking_at([0.0, 1.0, 2.0], [0.0, 0.0, -3.0], 70.0, 0.2, 60.0);
    let (ids, stats) = render_ids::<64, 48, 4>(&[instance(&mesh)], &cam, true);
    assert!(stats.clipped >= 2, "{stats:?}");
    let (mismatches, real) = compare(&[&data], &cam, &ids, 64, 48, 4, true);
    assert_eq!(real, 0, "{mismatches} mismatches");
    assert!(ids.iter().filter(|&&i| i >= 0).count() > 64 * 20);
    // One vertex behind the eye and two behind the eye, on a single triangle each.
    for (tri, name) in [
        (
            [[-1.0, -0.5, 1.0], [1.0, -0.5, -3.0], [0.0, 1.0, -3.0]],
            "one",
        ),
        (
            [[-1.0, -1.0, 1.0], [1.0, -1.0, 1.0], [0.0, 1.0, -3.0]],
            "two",
        ),
    ] {
        let data = mesh_data(&tri, &[[0, 1, 2]]);
        let mesh = data.mesh().unwrap();
        let cam = CameraSpec::looking_at([0.0, 0.0, 0.0], [0.0, 0.0, -1.0], 90.0, 0.1, 10.0);
        let (ids, stats) = render_ids::<48, 48, 4>(&[instance(&mesh)], &cam, false);
        assert_eq!(stats.clipped, 1, "{name}");
        let (mismatches, real) = compare(&[&data], &cam, &ids, 48, 48, 4, false);
        assert_eq!(real, 0, "{name}: {mismatches} mismatches");
        assert!(ids.iter().filter(|&&i| i == 0).count() > 100, "{name}");
    }
}

#[test]
fn without_clipping_crossing_triangles_are_skipped_and_counted_never_drawn_wrong() {
    // The near-plane fan plus a small triangle well inside the view volume (id 4).
    let (mut verts, mut tris) = ground_fan();
    verts.extend([[-0.5, 0.5, -3.0], [0.5, 0.5, -3.0], [0.0, 1.2, -3.0]]);
    tris.push([5, 6, 7]);
    let data = mesh_data(&verts, &tris);
    let mesh = data.mesh().unwrap();
    let cam = CameraSpec::looking_at([0.0, 1.0, 2.0], [0.0, 0.0, -3.0], 70.0, 0.2, 60.0);
    let instances = [instance(&mesh)];
    let clipping = RenderOptions::default().with_back_face_culling(false);
    let (full, fs) = render_ids_with::<64, 48, 4, _>(&instances, &cam, &clipping);
    let (lean, ls) =
        render_ids_with::<64, 48, 4, _>(&instances, &cam, &clipping.with_clipping(NoClip));
    assert!(fs.clipped >= 2 && fs.unclipped == 0, "{fs:?}");
    assert_eq!(ls.clipped, 0);
    assert_eq!(
        ls.unclipped, fs.clipped,
        "every cut triangle is skipped instead"
    );
    // What is drawn is drawn exactly as with clipping; the skipped triangles never appear.
    let ids = |img: &[i32]| {
        let mut v: Vec<i32> = img.iter().copied().filter(|&id| id >= 0).collect();
        v.sort();
        v.dedup();
        v
    };
    for id in ids(&lean) {
        let at = |img: &[i32]| (0..img.len()).filter(|&i| img[i] == id).collect::<Vec<_>>();
        assert_eq!(at(&lean), at(&full), "triangle {id}");
    }
    assert!(ids(&lean).contains(&4));
    assert!(ids(&full).len() > ids(&lean).len());
}

#[test]
fn without_clipping_scenes_that_need_none_render_bit_identically() {
    let mut ws = Box::new(scanline3d_demo::PanelWorkspace::new(Rgb565::new(0, 0, 0)));
    // In some frames the ground crosses the guard band, but only off screen: no visible
    // triangle is cut (`clipped` is 0), so skipping the crossing ones changes nothing.
    let instances = &scanline3d_demo::instances();
    let mut skipped = 0;
    for frame in 0..scanline3d_demo::ORBIT_FRAMES {
        let scene = scanline3d_demo::scene(instances, frame, 8).unwrap();
        let (mut a, mut b) = (HashSink::new(), HashSink::new());
        let sa = ws
            .render(&scene, &RenderOptions::default(), &mut a)
            .unwrap();
        let lean = RenderOptions::default().with_clipping(NoClip);
        let sb = ws.render(&scene, &lean, &mut b).unwrap();
        let (a, b) = (a.hash(), b.hash());
        assert_eq!((sa.clipped, sa.unclipped, sb.clipped), (0, 0, 0));
        assert_eq!(a, b, "frame {frame}");
        assert_eq!(sa.bucketed, sb.bucketed);
        assert_eq!(sa.rejected, sb.rejected + sb.unclipped);
        skipped += sb.unclipped;
    }
    assert!(
        skipped > 0,
        "the orbit should exercise off-screen crossings"
    );
}

#[test]
fn icosphere_matches_reference_at_several_sub_pixel_settings() {
    let sphere = icosphere(2, 1.0);
    let mesh = sphere.mesh().unwrap();
    let cam = CameraSpec::looking_at([1.2, 0.9, 2.6], [0.0; 3], 55.0, 0.5, 10.0);
    let inst = [instance(&mesh)];
    let (ids, _) = render_ids::<64, 64, 2>(&inst, &cam, true);
    assert_eq!(compare(&[&sphere], &cam, &ids, 64, 64, 2, true).1, 0);
    let (ids, _) = render_ids::<64, 64, 4>(&inst, &cam, true);
    assert_eq!(compare(&[&sphere], &cam, &ids, 64, 64, 4, true).1, 0);
    let (ids, _) = render_ids::<64, 64, 8>(&inst, &cam, true);
    assert_eq!(compare(&[&sphere], &cam, &ids, 64, 64, 8, true).1, 0);
}

/// Bytes of a workspace by the documented formula (src/render.rs, README), before padding:
/// `depth·W` depth row, `size_of::<P>()·W` pixel row and one background pixel, `2·H` bucket
/// heads, `4·TRIS` bucket lists, `ACTIVE · entry` active triangles and the active list's
/// length (a `usize`).
fn documented_bytes<P>(
    depth: usize,
    w: usize,
    h: usize,
    tris: usize,
    active: usize,
    entry: usize,
) -> usize {
    depth * w
        + std::mem::size_of::<P>() * (w + 1)
        + 2 * h
        + 4 * tris
        + active * entry
        + std::mem::size_of::<usize>()
}

/// Checks `Workspace::BYTES` of each size against the documented formula (`depth` bytes of
/// depth per column, `entry` bytes per active triangle), padded by less than 8 bytes, and
/// against `workspace_bytes`.
macro_rules! check_bytes {
    ($p:ty, $s:ty, $z:ty, $depth:expr, $entry:expr, [$(($w:literal, $h:literal, $t:literal, $a:literal)),* $(,)?]) => {$({
        type Ws = Workspace<$p, $s, $w, $h, $t, $a, 8, $z>;
        let parts = documented_bytes::<$p>($depth, $w, $h, $t, $a, $entry);
        let what = concat!(stringify!($p), ", ", stringify!($s), ", ", stringify!($z), ", ",
            stringify!($w), "x", stringify!($h), ", ", stringify!($t), ", ", stringify!($a));
        assert!(
            (parts..parts + 8).contains(&Ws::BYTES),
            "{what}: BYTES {} for documented {parts}",
            Ws::BYTES
        );
        assert_eq!(Ws::BYTES % 8, 0, "{what}");
        assert_eq!(Ws::BYTES, workspace_bytes::<$p, $s, $z>($w, $h, $t, $a), "{what}");
    })*};
}

#[test]
fn workspace_bytes_follow_the_documented_formula() {
    // Active triangles (host sizes): 96 bytes with flat shading (as documented) and pixels of
    // up to 2 bytes, 104 with 3- and 4-byte pixels (`Rgb888`, `TriangleId`), 144 with affine
    // Gouraud, 208 with perspective-correct Gouraud.
    check_bytes! { Rgb565, Flat, Depth, 4, 96, [(240, 240, 1280, 64), (1, 1, 1, 1), (17, 3, 5, 2)] }
    check_bytes! { Rgb565, Flat, Depth, 4, 96, [(7, 9, 0, 0)] }
    check_bytes! { Rgb888, Flat, Depth, 4, 104, [(320, 240, 1536, 96), (3, 5, 7, 1)] }
    check_bytes! { Gray8, Flat, Depth16, 2, 96, [(240, 240, 1280, 64), (13, 1, 3, 3)] }
    check_bytes! { BinaryColor, Flat, Depth, 4, 96, [(128, 64, 256, 16), (1, 2048, 1, 5)] }
    check_bytes! { TriangleId, Flat, Depth, 4, 104, [(64, 64, 4096, 512), (2048, 1, 9, 1)] }
    check_bytes! { Rgb565, Gouraud, Depth, 4, 144, [(240, 240, 1280, 64), (5, 5, 5, 5)] }
    check_bytes! { Rgb888, Gouraud, Depth16, 2, 144, [(31, 17, 100, 3)] }
    check_bytes! { Rgb565, Gouraud<PerPixel>, Depth, 4, 208, [(240, 240, 1280, 64), (9, 3, 1, 7)] }

    // The vertex cache adds 8 bytes a vertex (README), `vertex_cache_bytes` of them: exactly
    // when that is a multiple of 8, else the total pads once where the sum pads twice.
    assert_eq!(CachedVertex::BYTES, 8);
    let plain = workspace_bytes::<Rgb565, Flat, Depth>(240, 240, 1280, 64);
    type Cached = Workspace<Rgb565, Flat, 240, 240, 1280, 64, 8, Depth, 700>;
    assert_eq!(Cached::BYTES, plain + vertex_cache_bytes(700));
    type Odd = Workspace<Rgb565, Flat, 240, 240, 1280, 64, 8, Depth, 701>;
    let parts = documented_bytes::<Rgb565>(4, 240, 240, 1280, 64, 96) + 701 * 8;
    assert!((parts..parts + 8).contains(&Odd::BYTES), "{}", Odd::BYTES);
    assert!(Odd::BYTES <= plain + vertex_cache_bytes(701));
}

/// The RAM budget of issue 2: a 240×240 frame of a 1280-triangle, 642-vertex icosphere in at
/// most 16 KiB of renderer memory (mesh data excluded):
///   depth row 4·240 = 960, Rgb565 row 2·240 = 480, background 2, bucket heads 2·240 = 480,
///   bucket lists 4·1280 = 5120, active list 64 × size_of(active triangle) + length.
#[test]
fn icosphere_frame_fits_16_kib() {
    type Ws = Workspace<Rgb565, Flat, 240, 240, 1280, 64>;
    let fixed_part = 960 + 480 + 480 + 5120;
    println!(
        "workspace {} bytes, active triangle ~{} bytes",
        Ws::BYTES,
        (Ws::BYTES - fixed_part) / 64
    );
    const { assert!(Ws::BYTES <= 16 * 1024) }
    // The sum above with 96-byte active triangles is 13,194; padding to 8 bytes makes
    // docs/design.md's 13,200.
    assert_eq!(fixed_part + 2 + 64 * 96 + 8, 13_194);
    assert_eq!(Ws::BYTES, 13_200);

    let sphere = icosphere(3, 1.0);
    assert_eq!((sphere.vertices.len(), sphere.triangles.len()), (642, 1280));
    let mesh = sphere.mesh().unwrap();
    let instances = [instance(&mesh)];
    let cam = CameraSpec::looking_at([0.0, 0.5, 2.6], [0.0; 3], 60.0, 0.5, 10.0);
    let scene = Scene {
        instances: &instances,
        camera: cam.fixed().unwrap(),
        light: light(),
    };
    let mut ws = Box::new(Ws::new(Rgb565::BLACK));
    let mut rows = 0;
    let stats = ws
        .render(
            &scene,
            &RenderOptions::default(),
            &mut FnSink(|_: Row<'_, Rgb565>| -> Result<(), ()> {
                rows += 1;
                Ok(())
            }),
        )
        .unwrap();
    println!("{stats:?}");
    assert!(stats.is_complete());
    assert_eq!(rows, 240);
    assert_eq!(stats.triangles_in, 1280);
    assert!(stats.culled > 500 && stats.peak_active <= 64);
}

fn one_triangle() -> MeshData {
    mesh_data(
        &[[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [0.0, 1.0, 0.0]],
        &[[0, 1, 2]],
    )
}

/// `instances` seen by [`front_camera`].
fn front_scene<'a>(instances: &'a [Instance<'a>]) -> Scene<'a> {
    Scene {
        instances,
        camera: front_camera().fixed().unwrap(),
        light: light(),
    }
}

fn front_camera() -> CameraSpec {
    CameraSpec::looking_at([0.0, 0.0, 3.0], [0.0; 3], 60.0, 0.5, 10.0)
}

#[test]
fn sink_error_stops_the_frame_at_that_row() {
    let data = one_triangle();
    let mesh = data.mesh().unwrap();
    let instances = [instance(&mesh)];
    let scene = front_scene(&instances);
    let mut ws: Workspace<Rgb565, Flat, 16, 16, 4, 4> = Workspace::new(Rgb565::BLACK);
    let mut seen = Vec::new();
    let mut sink = FnSink(|row: Row<'_, Rgb565>| {
        seen.push(row.y);
        if row.y == 5 {
            Err("bus error")
        } else {
            Ok(())
        }
    });
    let err = ws
        .render(&scene, &RenderOptions::default(), &mut sink)
        .unwrap_err();
    assert_eq!(
        err,
        RenderError::Sink {
            row: 5,
            error: "bus error"
        }
    );
    assert_eq!(seen, [0, 1, 2, 3, 4, 5]);
}

#[test]
fn too_many_triangles_fails_before_any_row() {
    let sphere = icosphere(1, 1.0);
    let mesh = sphere.mesh().unwrap();
    let instances = [instance(&mesh)];
    let scene = front_scene(&instances);
    let mut ws: Workspace<Rgb565, Flat, 32, 32, 8, 8> = Workspace::new(Rgb565::BLACK);
    let mut rows = 0;
    let err = ws
        .render(
            &scene,
            &RenderOptions::default(),
            &mut FnSink(|_: Row<'_, Rgb565>| -> Result<(), ()> {
                rows += 1;
                Ok(())
            }),
        )
        .unwrap_err();
    let RenderError::Capacity {
        what: CapacityKind::Triangles,
        needed,
        capacity: 8,
    } = err
    else {
        panic!("{err:?}")
    };
    assert!(needed > 8 && needed < 80, "{needed}");
    assert_eq!(rows, 0);
}

/// Renders `scene` into a 64×64 id image with an active list of `ACTIVE` entries; returns the
/// ids, each row's `complete` flag and the stats.
fn render_with_active<const ACTIVE: usize>(
    scene: &Scene<'_>,
) -> (Vec<i32>, Vec<bool>, scanline3d::FrameStats) {
    let mut ws: Box<Workspace<TriangleId, Flat, 64, 64, 512, ACTIVE>> =
        Box::new(Workspace::new(TriangleId::NONE));
    let (mut ids, mut complete) = (Vec::new(), Vec::new());
    let stats = ws
        .render(
            scene,
            &RenderOptions::default(),
            &mut FnSink(|row: Row<'_, TriangleId>| -> Result<(), ()> {
                ids.extend(row.pixels.iter().map(|p| p.0));
                complete.push(row.complete);
                Ok(())
            }),
        )
        .unwrap();
    (ids, complete, stats)
}

/// Checks a degraded frame against the complete one: only incomplete rows differ, and only
/// where a dropped triangle was visible; the flags and the log agree.
fn check_degraded(
    full: &[i32],
    (ids, complete, s): &(Vec<i32>, Vec<bool>, scanline3d::FrameStats),
) {
    assert!(!s.is_complete());
    assert_eq!(s.rows, 64);
    let logged: Vec<_> = s.dropped_pieces.iter().flatten().collect();
    assert_eq!(
        logged.len(),
        (s.dropped as usize).min(scanline3d::stats::DROP_LOG)
    );
    assert_eq!(s.first_incomplete_row(), Some(logged[0].first_row));
    assert_eq!(
        complete.iter().filter(|c| !**c).count(),
        s.incomplete_rows as usize
    );
    for d in &logged {
        assert!(d.first_row <= d.last_row);
        for r in d.first_row..=d.last_row {
            assert!(
                !complete[r as usize],
                "row {r} lost triangle {} but is flagged complete",
                d.triangle
            );
        }
    }
    let mut differing = 0;
    for (i, (&a, &b)) in full.iter().zip(ids.iter()).enumerate() {
        if a != b {
            differing += 1;
            assert!(!complete[i / 64], "pixel {i} differs in a complete row");
            if s.dropped as usize <= scanline3d::stats::DROP_LOG {
                assert!(
                    logged.iter().any(|d| d.triangle as i32 == a),
                    "pixel {i}: triangle {a} was not dropped"
                );
            }
        }
    }
    assert!(differing > 0);
}

#[test]
fn full_active_list_degrades_deterministically_and_reports_what_was_lost() {
    let sphere = icosphere(2, 1.0);
    let mesh = sphere.mesh().unwrap();
    let instances = [instance(&mesh)];
    let scene = front_scene(&instances);
    let (full, full_complete, full_stats) = render_with_active::<64>(&scene);
    assert!(full_stats.is_complete() && full_complete.iter().all(|c| *c));
    assert_eq!(full_stats.incomplete_rows, 0);
    let peak = full_stats.peak_active;
    assert_eq!(peak, 18, "the scene this test was sized for");

    // One entry short of the peak: a few pieces are lost, each one logged.
    let few = render_with_active::<17>(&scene);
    assert!(
        few.2.dropped as usize <= scanline3d::stats::DROP_LOG,
        "{:?}",
        few.2
    );
    check_degraded(&full, &few);
    // Far too small: many pieces are lost; counts stay exact, the log keeps the first ones.
    let many = render_with_active::<6>(&scene);
    assert!(many.2.dropped as usize > scanline3d::stats::DROP_LOG);
    check_degraded(&full, &many);
    assert_eq!(many, render_with_active::<6>(&scene), "deterministic");
}

#[test]
fn gouraud_interpolates_vertex_colours() {
    let verts = [[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [0.0, 1.0, 0.0]].map(vert);
    let tris = [[0u16, 1, 2]];
    let colors = [Rgb888::RED, Rgb888::GREEN, Rgb888::BLUE];
    let mesh = Mesh::new(&verts, &tris, MeshColors::PerVertex(&colors), None).unwrap();
    let instances = [instance(&mesh)];
    let light = scanline3d::scene::Light::new([0.0, 0.0, 1.0], 1.0, 0.0).unwrap();
    let cam = CameraSpec {
        eye: [0.0, 0.0, 2.0],
        ..front_camera()
    };
    let scene = Scene {
        instances: &instances,
        camera: cam.fixed().unwrap(),
        light,
    };
    let mut ws: Box<Workspace<Rgb888, Gouraud, 33, 33, 4, 4>> =
        Box::new(Workspace::new(Rgb888::BLACK));
    let mut px = vec![Rgb888::BLACK; 33 * 33];
    ws.render(
        &scene,
        &RenderOptions::default(),
        &mut FnSink(|row: Row<'_, Rgb888>| -> Result<(), ()> {
            px[row.y as usize * 33..][..33].copy_from_slice(row.pixels);
            Ok(())
        }),
    )
    .unwrap();
    // The triangle is parallel to the screen, so screen-linear colour is exact barycentric
    // interpolation. Check every covered pixel against the f64 barycentric colour.
    let p = [[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [0.0, 1.0, 0.0]]
        .map(|v| project(&cam, 33, 33, v).unwrap());
    let mut checked = 0;
    for (i, c) in px.iter().enumerate() {
        if *c == Rgb888::BLACK {
            continue;
        }
        let (x, y) = ((i % 33) as f64 + 0.5, (i / 33) as f64 + 0.5);
        let d =
            (p[1][1] - p[2][1]) * (p[0][0] - p[2][0]) + (p[2][0] - p[1][0]) * (p[0][1] - p[2][1]);
        let l0 = ((p[1][1] - p[2][1]) * (x - p[2][0]) + (p[2][0] - p[1][0]) * (y - p[2][1])) / d;
        let l1 = ((p[2][1] - p[0][1]) * (x - p[2][0]) + (p[0][0] - p[2][0]) * (y - p[2][1])) / d;
        let l2 = 1.0 - l0 - l1;
        for (got, want) in [(c.r(), l0), (c.g(), l1), (c.b(), l2)] {
            assert!(
                (got as f64 - 255.0 * want).abs() <= 1.5,
                "pixel {i}: {c:?} vs {l0} {l1} {l2}"
            );
        }
        checked += 1;
    }
    assert!(checked > 200);
}

#[test]
fn instances_number_triangles_consecutively() {
    let data = one_triangle();
    let mesh = data.mesh().unwrap();
    let instances = [
        Instance {
            mesh: &mesh,
            transform: Transform::translation([-1.2, 0.0, 0.0]),
        },
        Instance {
            mesh: &mesh,
            transform: Transform::translation([1.2, 0.0, 0.0])
                .then_after(&Transform::scale([0.5; 3])),
        },
    ];
    let (ids, stats) = render_ids::<48, 32, 4>(&instances, &front_camera(), true);
    assert_eq!(stats.triangles_in, 2);
    assert!(
        ids[16 * 48 + 10] == 0 && ids[16 * 48 + 37] == 1,
        "{} {}",
        ids[16 * 48 + 10],
        ids[16 * 48 + 37]
    );
}

#[test]
fn bad_transforms_are_reported() {
    let data = one_triangle();
    let mesh = data.mesh().unwrap();
    let scene_with = |t: Transform| {
        let instances = [Instance {
            mesh: &mesh,
            transform: t,
        }];
        let scene = Scene {
            instances: &instances,
            camera: front_camera().fixed().unwrap(),
            light: light(),
        };
        let mut ws: Workspace<Rgb565, Flat, 8, 8, 4, 4> = Workspace::new(Rgb565::BLACK);
        ws.render(
            &scene,
            &RenderOptions::default(),
            &mut FnSink(|_: Row<'_, Rgb565>| -> Result<(), ()> { panic!("no row expected") }),
        )
        .map(|_| ())
    };
    use scanline3d::stats::TransformError;
    assert_eq!(
        scene_with(Transform::translation([f32::NAN, 0.0, 0.0])),
        Err(RenderError::Transform {
            instance: 0,
            error: TransformError::NonFinite
        })
    );
    assert_eq!(
        scene_with(Transform::translation([1e6, 0.0, 0.0])),
        Err(RenderError::Transform {
            instance: 0,
            error: TransformError::OutOfEnvelope
        })
    );
}

#[test]
fn micromath_backend_renders_nearly_the_same_image() {
    use scanline3d::math::Micromath;
    use scanline3d::scene::Camera;
    let sphere = icosphere(2, 1.0);
    let mesh = sphere.mesh().unwrap();
    let instances = [instance(&mesh)];
    let render = |camera: Camera| {
        let scene = Scene {
            instances: &instances,
            camera,
            light: light(),
        };
        let mut ws: Box<Workspace<TriangleId, Flat, 64, 64, 512, 64>> =
            Box::new(Workspace::new(TriangleId::NONE));
        let mut ids = Vec::new();
        ws.render(
            &scene,
            &RenderOptions::default(),
            &mut FnSink(|row: Row<'_, TriangleId>| -> Result<(), ()> {
                ids.extend(row.pixels.iter().map(|p| p.0));
                Ok(())
            }),
        )
        .unwrap();
        ids
    };
    let (eye, up) = ([1.0f32, 0.8, 2.7], [0.0f32, 1.0, 0.0]);
    let libm = render(
        Camera::look_at(eye, [0.0; 3], up)
            .unwrap()
            .perspective(55.0, 0.5, 10.0)
            .unwrap(),
    );
    let micro = render(
        Camera::look_at_with::<Micromath>(eye, [0.0; 3], up)
            .unwrap()
            .perspective_with::<Micromath>(55.0, 0.5, 10.0)
            .unwrap(),
    );
    let differ = libm.iter().zip(&micro).filter(|(a, b)| a != b).count();
    println!("micromath vs libm: {differ} of 4096 pixels differ");
    assert!(differ > 0, "the backends are expected to differ slightly");
    assert!(differ < 4096 / 20, "{differ}");
}

#[test]
fn workspace_bytes_matches_the_compiled_layout() {
    use scanline3d::depth::Depth16;
    use scanline3d::options::MAX_INSTANCES;
    use scanline3d::workspace::workspace_bytes;
    use scanline3d::Depth;
    macro_rules! check {
        ($p:ty, $s:ty, $w:literal, $h:literal, $t:literal, $a:literal) => {
            assert_eq!(
                workspace_bytes::<$p, $s, Depth>($w, $h, $t, $a),
                Workspace::<$p, $s, $w, $h, $t, $a>::BYTES,
                stringify!($p, $s, $w, $h, $t, $a)
            );
            assert_eq!(
                workspace_bytes::<$p, $s, Depth16>($w, $h, $t, $a),
                Workspace::<$p, $s, $w, $h, $t, $a, MAX_INSTANCES, Depth16>::BYTES,
                stringify!($p, $s, $w, $h, $t, $a, Depth16)
            );
        };
    }
    check!(Rgb565, Flat, 240, 240, 100, 12);
    check!(Rgb565, Flat, 1, 1, 1, 1);
    // One-byte bucket heads and links: one byte per row and per entry less.
    use scanline3d::workspace::workspace_bytes_with;
    type Lean = Workspace<Rgb565, Flat, 240, 240, 29, 11, 1, Depth, 0, u8>;
    assert_eq!(
        workspace_bytes_with::<Rgb565, Flat, Depth, u8>(240, 240, 29, 11),
        Lean::BYTES
    );
    assert_eq!(
        workspace_bytes::<Rgb565, Flat, Depth>(240, 240, 29, 11) - Lean::BYTES,
        (240 + 29) / 8 * 8
    );
    check!(Rgb565, Flat, 241, 3, 7, 5);
    check!(Rgb888, Gouraud, 240, 240, 640, 64);
    check!(TriangleId, Flat, 64, 63, 511, 9);
    check!(embedded_graphics::pixelcolor::BinaryColor, Flat, 3, 5, 1, 0);
    check!(embedded_graphics::pixelcolor::Gray8, Gouraud, 13, 1, 2, 3);
}

#[test]
fn instance_capacity_is_a_workspace_parameter() {
    let data = one_triangle();
    let mesh = data.mesh().unwrap();
    let instances = [instance(&mesh), instance(&mesh)];
    let scene = front_scene(&instances);
    let mut one: Box<Workspace<TriangleId, Flat, 16, 16, 8, 4, 1>> =
        Box::new(Workspace::new(TriangleId::NONE));
    let rows = std::cell::Cell::new(0);
    let mut sink = FnSink(|_: Row<'_, TriangleId>| -> Result<(), ()> {
        rows.set(rows.get() + 1);
        Ok(())
    });
    assert_eq!(
        one.render(&scene, &RenderOptions::default(), &mut sink),
        Err(RenderError::Capacity {
            what: CapacityKind::Instances,
            needed: 2,
            capacity: 1
        })
    );
    assert_eq!(rows.get(), 0, "nothing is sent before the error");
    let mut two: Box<Workspace<TriangleId, Flat, 16, 16, 8, 4, 2>> =
        Box::new(Workspace::new(TriangleId::NONE));
    let stats = two
        .render(&scene, &RenderOptions::default(), &mut sink)
        .unwrap();
    assert_eq!((stats.triangles_in, rows.get()), (2, 16));
}

/// Ids and depth of `scene` at 96×96 with depth format `Z`, from a span z-buffer or (`full`) a
/// full-frame z-buffer.
fn ids_and_depth<Z: scanline3d::depth::DepthFormat>(
    scene: &Scene<'_>,
    full: bool,
) -> (Vec<i32>, Vec<i32>) {
    use scanline3d::options::MAX_INSTANCES;
    use scanline3d::resolve::ZBufferWorkspace;
    let (mut ids, mut depth) = (Vec::new(), Vec::new());
    let mut sink = FnSink(|row: Row<'_, TriangleId>| -> Result<(), ()> {
        ids.extend(row.pixels.iter().map(|p| p.0));
        depth.extend((0..row.pixels.len()).map(|x| row.depth.get(x).map_or(-1, |q| q.to_bits())));
        Ok(())
    });
    let options = RenderOptions::default();
    let stats = if full {
        type Ws<Z> = ZBufferWorkspace<TriangleId, Flat, 96, 96, 1536, MAX_INSTANCES, Z>;
        let mut ws: Box<Ws<Z>> = Box::new(Ws::new(TriangleId::NONE));
        ws.render(scene, &options, &mut sink)
    } else {
        type Ws<Z> = Workspace<TriangleId, Flat, 96, 96, 1536, 96, MAX_INSTANCES, Z>;
        let mut ws: Box<Ws<Z>> = Box::new(Ws::new(TriangleId::NONE));
        ws.render(scene, &options, &mut sink)
    };
    assert!(stats.unwrap().is_complete());
    (ids, depth)
}

#[test]
fn sixteen_bit_depth_differs_from_32_bit_only_by_its_resolution() {
    use scanline3d::depth::Depth16;
    use scanline3d::Depth;
    let instances = scanline3d_demo::instances();
    for frame in 0..8 {
        let scene = scanline3d_demo::scene(&instances, frame, 8).unwrap();
        let (ids32, depth32) = ids_and_depth::<Depth>(&scene, false);
        let (ids16, depth16) = ids_and_depth::<Depth16>(&scene, false);
        // The full-frame z-buffer with 16-bit cells settles ties exactly as the span z-buffer.
        let full16 = ids_and_depth::<Depth16>(&scene, true);
        assert_eq!((&ids16, &depth16), (&full16.0, &full16.1));
        // The demo has no surfaces within 2^-16 of each other in q: the same ids everywhere,
        // each depth the 32-bit one truncated to 16 fractional bits.
        assert_eq!(ids32, ids16, "frame {frame}");
        for (q, z) in depth32.iter().zip(&depth16) {
            assert!(z <= q && q - z < 1 << 14, "{q} stored as {z}");
            assert_eq!(z & ((1 << 14) - 1), 0);
        }
    }
}

#[test]
fn sixteen_bit_depth_gives_surfaces_closer_than_its_resolution_to_the_first_drawn() {
    use scanline3d::depth::Depth16;
    use scanline3d::Depth;
    // Two squares facing the camera 5·10^-5 apart at distance 3: Δq ≈ 2.8·10^-6, far below
    // 2^-16 ≈ 1.5·10^-5 but far above 2^-30. The far square (ids 0, 1) is drawn first.
    let square = |z: f64| {
        [
            [-1.0, -1.0, z],
            [1.0, -1.0, z],
            [1.0, 1.0, z],
            [-1.0, 1.0, z],
        ]
    };
    let (far, near) = (square(0.0), square(0.00005));
    let positions: Vec<[f64; 3]> = far.iter().chain(&near).copied().collect();
    let data = mesh_data(&positions, &[[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]]);
    let mesh = data.mesh().unwrap();
    let instances = [instance(&mesh)];
    let scene = front_scene(&instances);
    let count = |ids: &[i32], which: [i32; 2]| ids.iter().filter(|i| which.contains(i)).count();
    let (ids32, _) = ids_and_depth::<Depth>(&scene, false);
    let (ids16, _) = ids_and_depth::<Depth16>(&scene, false);
    let covered = count(&ids32, [0, 1]) + count(&ids32, [2, 3]);
    assert!(covered > 1000);
    assert_eq!(
        count(&ids32, [2, 3]),
        covered,
        "32 bits resolve the gap everywhere"
    );
    // 16 bits: q is constant over each square (they face the camera), 2^16 · q = 10922.67 and
    // 10922.85, both cell 10922: a tie at every pixel, and the far square, drawn first, keeps it.
    assert_eq!(count(&ids16, [0, 1]), covered);
}
