//! Newell's depth sort against the span z-buffer: the same id image on the demo orbit up to
//! pixels where two surfaces meet, the lecture's hard cases (cyclic overlap,
//! interpenetration), the tie rule for coplanar pieces, and capacity errors.

use embedded_graphics::pixelcolor::Rgb565;
use scanline3d::resolve::NewellWorkspace;
use scanline3d::sink::{FnSink, HashSink, Row, RowPixel, TriangleId};
use scanline3d::stats::CapacityKind;
use scanline3d::{Flat, RenderError, RenderOptions, Workspace};
use scanline3d_demo as demo;
use scanline3d_sim::corpus;
use scanline3d_sim::scene::{LightSpec, SceneSpec};

const W: usize = demo::WIDTH;
const H: usize = demo::HEIGHT;
const TRIS: usize = 1536;
const ACTIVE: usize = 128;

/// Collects rows into an image of `w × h` pixels.
fn image_sink<P: RowPixel>(
    out: &mut [P],
    w: usize,
) -> FnSink<impl FnMut(Row<'_, P>) -> Result<(), ()> + '_> {
    FnSink(move |row: Row<'_, P>| {
        assert_eq!(row.pixels.len(), w);
        assert!(row.complete);
        assert!(row.depth.is_empty());
        out[row.y as usize * w..][..w].copy_from_slice(row.pixels);
        Ok(())
    })
}

/// The span z-buffer's and Newell's id images of `scene`, and Newell's sort statistics.
fn both(
    scene: &scanline3d::scene::Scene<'_>,
    options: &RenderOptions,
) -> (
    Vec<TriangleId>,
    Vec<TriangleId>,
    scanline3d::resolve::newell::SortStats,
) {
    let bg = TriangleId::NONE;
    let mut z = vec![bg; W * H];
    let mut n = vec![bg; W * H];
    let mut zs = Box::new(Workspace::<TriangleId, Flat, W, H, TRIS, ACTIVE>::new(bg));
    let mut zsink = FnSink(|row: Row<'_, TriangleId>| -> Result<(), ()> {
        z[row.y as usize * W..][..W].copy_from_slice(row.pixels);
        Ok(())
    });
    let zstats = zs.render(scene, options, &mut zsink).unwrap();
    assert!(zstats.is_complete());
    let mut ws = Box::new(NewellWorkspace::<TriangleId, Flat, W, H, TRIS, ACTIVE>::new(bg));
    let stats = ws
        .render(scene, options, &mut image_sink(&mut n, W))
        .unwrap();
    assert!(stats.is_complete());
    assert_eq!(stats.rows as usize, H);
    assert_eq!(stats.bucketed, zstats.bucketed);
    // Every covered pixel is painted once at least; a pixel a later piece already holds is
    // not painted again.
    assert!(stats.pixels_written <= stats.fragments);
    assert!(stats.pixels_written as usize >= n.iter().filter(|p| **p != bg).count());
    (z, n, ws.sort_stats())
}

fn differing<P: PartialEq>(a: &[P], b: &[P]) -> usize {
    a.iter().zip(b).filter(|(x, y)| x != y).count()
}

#[test]
fn demo_orbit_ids_equal_the_span_zbuffer_on_99_9_percent() {
    let instances = demo::instances();
    let options = RenderOptions::default();
    for frame in 0..demo::ORBIT_FRAMES {
        let scene = demo::scene(&instances, frame, demo::ORBIT_FRAMES).unwrap();
        let (z, n, sort) = both(&scene, &options);
        let d = differing(&z, &n);
        println!("frame {frame}: {d} of {} ids differ; {sort:?}", W * H);
        assert!(d * 1000 <= W * H, "frame {frame}: {d} ids differ");
    }
}

#[test]
fn cyclic_overlap_and_interpenetration_are_resolved() {
    for scene in corpus::all() {
        if !["cyclic", "interpenetrating", "coplanar"].contains(&scene.name) {
            continue;
        }
        for (k, camera) in scene.cameras.iter().enumerate() {
            let spec = SceneSpec::single(
                scene.mesh.clone(),
                *camera,
                LightSpec::default(),
                scene.cull_back_faces,
            );
            let options = RenderOptions::default().with_back_face_culling(scene.cull_back_faces);
            let (z, n, sort) = spec.with_scene(|s| both(s, &options)).unwrap();
            let mut ids: Vec<i32> = z.iter().map(|i| i.0).filter(|&i| i >= 0).collect();
            ids.sort_unstable();
            ids.dedup();
            assert!(ids.len() >= 2, "{} cam {k}", scene.name);
            let d = differing(&z, &n);
            println!("{} cam {k}: {d} ids differ; {sort:?}", scene.name);
            if scene.name != "coplanar" {
                // Whole triangles cannot be ordered: the sort must split.
                assert!(sort.splits > 0, "{} cam {k}", scene.name);
            }
            assert!(d <= 4, "{} cam {k}: {d} ids differ", scene.name);
        }
    }
}

#[test]
fn too_many_pieces_is_reported_before_any_row() {
    let instances = demo::instances();
    let scene = demo::scene(&instances, 0, demo::ORBIT_FRAMES).unwrap();
    let mut ws = Box::new(NewellWorkspace::<Rgb565, Flat, W, H, 100>::new(
        Rgb565::new(0, 0, 0),
    ));
    let mut rows = 0;
    let mut sink = FnSink(|_: Row<'_, Rgb565>| -> Result<(), ()> {
        rows += 1;
        Ok(())
    });
    let err = ws
        .render(&scene, &RenderOptions::default(), &mut sink)
        .unwrap_err();
    assert!(matches!(
        err,
        RenderError::Capacity {
            what: CapacityKind::Pieces,
            capacity: 100,
            ..
        }
    ));
    assert_eq!(rows, 0);
}

#[test]
fn no_room_for_split_pieces_is_reported() {
    let scene = corpus::all()
        .into_iter()
        .find(|s| s.name == "cyclic")
        .unwrap();
    let spec = SceneSpec::single(
        scene.mesh.clone(),
        scene.cameras[0],
        LightSpec::default(),
        scene.cull_back_faces,
    );
    let options = RenderOptions::default().with_back_face_culling(scene.cull_back_faces);
    // Room for the scene's triangles but not for the pieces a cycle needs.
    assert_eq!(scene.mesh.triangles.len(), 3);
    let mut ws = Box::new(NewellWorkspace::<Rgb565, Flat, W, H, 4>::new(Rgb565::new(
        0, 0, 0,
    )));
    let err = spec
        .with_scene(|s| ws.render(s, &options, &mut HashSink::new()))
        .unwrap()
        .unwrap_err();
    assert!(
        matches!(
            err,
            RenderError::Capacity {
                what: CapacityKind::Pieces,
                capacity: 4,
                ..
            }
        ),
        "{err:?}"
    );
}

#[test]
fn workspace_memory_is_as_documented() {
    type Ws = NewellWorkspace<Rgb565, Flat, 240, 240, 1280, 64>;
    let active = Ws::BYTES - (1280 * 91 + 240 * 2 + 240 * 2 + 240 * 4);
    println!("{} bytes, {} for 64 active", Ws::BYTES, active);
    assert!(active > 64 * 90 && active < 64 * 120, "{}", Ws::BYTES);
}
