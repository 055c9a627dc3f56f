//! The trimmed sheet as `sim export` writes it (`tests/data/trimmed_sheet.rs`: static I16F16
//! control points and trim loops, checked when compiled), drawn by the library: the hole and
//! the island are where the loops put them. (`sim`'s `patch_fixed_cli` checks the file is what
//! the exporter writes; `patch_compare` measures trims against the reference.)

#[path = "../data/trimmed_sheet.rs"]
mod trimmed_sheet;

use scanline3d::patch::{PatchScene, PatchWorkspace, Tolerance};
use scanline3d::scene::{Camera, Light, Transform};
use scanline3d::sink::{FnSink, Row, TriangleId};
use scanline3d::stats::CapacityKind;
use scanline3d::{Flat, RenderError, RenderOptions};

const SIDE: usize = 96;

/// Straight down on the sheet (x = 2u − 1, y = 2v − 1, bulging to z ≈ 0.28): the screen
/// centre is (u, v) = (0.5, 0.5), about 29 pixels per 0.25 of u or v.
fn scene() -> PatchScene<'static> {
    PatchScene {
        model: &trimmed_sheet::MODEL,
        transform: Transform::IDENTITY,
        camera: Camera::look_at([0.0, 0.0, 4.0], [0.0; 3], [0.0, 1.0, 0.0])
            .unwrap()
            .perspective(45.0, 0.1, 100.0)
            .unwrap(),
        light: Light::new([0.3, 0.4, 1.0], 0.2, 0.8).unwrap(),
    }
}

#[test]
fn the_exported_trimmed_sheet_draws_its_hole_and_island() {
    let scene = scene();
    let mut ws: Box<PatchWorkspace<TriangleId, Flat, SIDE, SIDE, 64, 512>> =
        Box::new(PatchWorkspace::new(TriangleId::NONE));
    let mut ids = vec![-1i32; SIDE * SIDE];
    let mut sink = FnSink(|row: Row<'_, TriangleId>| -> Result<(), ()> {
        for (x, id) in row.pixels.iter().enumerate() {
            ids[row.y as usize * SIDE + x] = id.0;
        }
        Ok(())
    });
    let stats = ws
        .render(
            &scene,
            &RenderOptions::default(),
            Tolerance::from_num(0.5),
            &mut sink,
        )
        .unwrap();
    assert!(stats.trim_cut > 0);
    assert_eq!((stats.trim_overflows, stats.late), (0, 0));
    let id = |col: usize, row: usize| ids[row * SIDE + col];
    // The island's middle, (u, v) = (0.5, 0.5).
    assert_eq!(id(48, 48), 0);
    // In the hole, below the island: (0.5, 0.35).
    assert_eq!(id(48, 57), -1);
    // In the hole, beside the island: (0.3, 0.5) and (0.7, 0.5).
    assert_eq!((id(36, 48), id(60, 48)), (-1, -1));
    // Outside the hole: (0.1, 0.5), (0.9, 0.5), (0.5, 0.1).
    assert_eq!((id(24, 48), id(72, 48), id(48, 72)), (0, 0, 0));
}

#[test]
fn a_workspace_without_trim_room_rejects_a_trimmed_model_before_any_row() {
    // TRIM = 0 leaves the trim code out of the build: drawing the sheet's trims is refused,
    // not done wrongly.
    let mut ws: Box<PatchWorkspace<TriangleId, Flat, SIDE, SIDE, 64, 512, 0>> =
        Box::new(PatchWorkspace::new(TriangleId::NONE));
    let mut rows = 0;
    let mut sink = FnSink(|_: Row<'_, TriangleId>| -> Result<(), ()> {
        rows += 1;
        Ok(())
    });
    let result = ws.render(
        &scene(),
        &RenderOptions::default(),
        Tolerance::from_num(0.5),
        &mut sink,
    );
    assert_eq!(
        result,
        Err(RenderError::Capacity {
            what: CapacityKind::Trims,
            needed: trimmed_sheet::MODEL.trim_loops().len(),
            capacity: 0,
        })
    );
    assert_eq!(rows, 0);
}
