//! `sim render MODEL.bpt --renderer fixed` and `sim export MODEL.bpt` end to end.

use std::path::PathBuf;

use crate::run::{scratch as scratch_dir, sim};

fn scratch(name: &str) -> PathBuf {
    scratch_dir(&format!("patch-{name}"))
}

fn model(name: &str) -> String {
    format!("{}/scenes/patches/{name}.bpt", env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn render_fixed_writes_patch_ids_and_depth() {
    let dir = scratch("render");
    let (code, stdout, stderr) = sim(
        &[
            "render",
            &model("teapot"),
            "--eye",
            "6,-8,5",
            "--target",
            "0,0,1.2",
            "--up",
            "0,0,1",
            "--size",
            "64x48",
            "--tolerance",
            "1",
            "--ids",
            "ids.bin",
            "--depth",
            "depth.bin",
            "--stats",
            "-",
        ],
        &dir,
    );
    assert_eq!(code, 0, "{stderr}");
    assert!(
        stdout.contains("\"renderer\": \"fixed\", \"patches\": 32"),
        "{stdout}"
    );
    assert!(stdout.contains("\"late\": 0"), "{stdout}");
    let ids = std::fs::read(dir.join("ids.bin")).unwrap();
    let depth = std::fs::read(dir.join("depth.bin")).unwrap();
    assert_eq!((ids.len(), depth.len()), (64 * 48 * 4, 64 * 48 * 4));
    let ids: Vec<i32> = ids
        .chunks(4)
        .map(|c| i32::from_le_bytes(c.try_into().unwrap()))
        .collect();
    let depth: Vec<f32> = depth
        .chunks(4)
        .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
        .collect();
    assert!(ids.iter().any(|&i| i >= 0));
    for (id, d) in ids.iter().zip(&depth) {
        assert!((-1..32).contains(id));
        assert_eq!(*id >= 0, d.is_finite(), "{id} {d}");
    }
    assert!(dir.join("frame.png").exists());
}

#[test]
fn export_writes_the_model_as_static_data() {
    let dir = scratch("export");
    let (code, stdout, stderr) = sim(&["export", &model("sphere"), "--out", "sphere.rs"], &dir);
    assert_eq!(code, 0, "{stderr}");
    assert!(stdout.contains("8 patches, rational"), "{stdout}");
    let source = std::fs::read_to_string(dir.join("sphere.rs")).unwrap();
    assert!(source.contains("pub static POINTS: [ControlPoints; 8]"));
    assert!(source.contains("pub static WEIGHTS: [[I16F16; 16]; 8]"));
    assert!(source.contains("Some(&WEIGHTS)"));
}

#[test]
fn export_writes_trim_loops_and_render_draws_them() {
    let dir = scratch("trimmed");
    let (code, stdout, stderr) = sim(&["export", &model("trimmed"), "--out", "trimmed.rs"], &dir);
    assert_eq!(code, 0, "{stderr}");
    assert!(stdout.contains("1 patches, 2 trim loops"), "{stdout}");
    let source = std::fs::read_to_string(dir.join("trimmed.rs")).unwrap();
    assert!(
        source.contains("pub static TRIM_LOOPS: [TrimLoop; 2]"),
        "{source}"
    );
    assert!(source.contains("pub static TRIM_POINTS: [TrimPoint; 35]"));
    assert!(source.contains("m.with_trims(&TRIM_LOOPS, &TRIM_POINTS)"));
    let (code, stdout, stderr) = sim(
        &[
            "render",
            &model("trimmed"),
            "--size",
            "64x64",
            "--tolerance",
            "1",
            "--stats",
            "-",
        ],
        &dir,
    );
    assert_eq!(code, 0, "{stderr}");
    assert!(!stderr.contains("trim"), "{stderr}");
    assert!(stdout.contains("\"trim_overflows\": 0"), "{stdout}");
    assert!(!stdout.contains("\"trim_cut\": 0"), "{stdout}");
}

#[test]
fn the_firmware_teapot_is_what_export_writes() {
    let dir = scratch("teapot");
    // Run from the repository root so the header's command line is the one in the file.
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let out = dir.join("teapot.rs");
    let (code, _, stderr) = sim(
        &[
            "export",
            "sim/scenes/patches/teapot.bpt",
            "--out",
            out.to_str().unwrap(),
        ],
        &root,
    );
    assert_eq!(code, 0, "{stderr}");
    let fresh = std::fs::read_to_string(&out).unwrap();
    let committed = std::fs::read_to_string(root.join("demo/src/patches/teapot.rs")).unwrap();
    assert_eq!(
        fresh, committed,
        "regenerate demo/src/patches/teapot.rs with sim export"
    );
}

#[test]
fn the_library_s_trimmed_sheet_is_what_export_writes() {
    let dir = scratch("trimmed-data");
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let out = dir.join("trimmed_sheet.rs");
    let (code, _, stderr) = sim(
        &[
            "export",
            "sim/scenes/patches/trimmed.bpt",
            "--out",
            out.to_str().unwrap(),
        ],
        &root,
    );
    assert_eq!(code, 0, "{stderr}");
    let fresh = std::fs::read_to_string(&out).unwrap();
    let committed = std::fs::read_to_string(root.join("tests/data/trimmed_sheet.rs")).unwrap();
    assert_eq!(
        fresh, committed,
        "regenerate tests/data/trimmed_sheet.rs with sim export"
    );
}
