//! `sim analyze` and `sim export`: the demo's budget, and the lean firmware scene round trip
//! (OBJ → generated Rust → render) against the host render of the same OBJ.

use scanline3d_sim::analyze;
use scanline3d_sim::meshgen;
use scanline3d_sim::scene::{MeshData, SceneSpec};
use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The lean firmware's scene: an 80-triangle icosphere.
const LEAN_OBJ: &str = "firmware/examples/lean/icosphere80.obj";
const LEAN_RS: &str = "firmware/examples/lean/scene.rs";
/// The export command for it (run from the repository root).
/// Margin 0: the lean builds measure the smallest workspace that renders these views.
const LEAN_EXPORT: &[&str] = &["export", LEAN_OBJ, "--views", "8", "--margin", "0"];
/// The lean baked firmware's scene: the same, its face colours lit ahead of time (`Unlit`).
const BAKED_RS: &str = "firmware/examples/lean/scene_baked.rs";
const BAKED_EXPORT: &[&str] = &[
    "export",
    LEAN_OBJ,
    "--views",
    "8",
    "--margin",
    "0",
    "--bake-light",
];
/// The lean BSP firmware's scene: the cyclic-overlap corpus scene with its BSP tree.
const BSP_RS: &str = "firmware/examples/lean/cyclic_bsp.rs";
const BSP_EXPORT: &[&str] = &[
    "export",
    "sim/corpus/cyclic.obj",
    "--views",
    "8",
    "--no-cull",
    "--bsp",
    "--margin",
    "0",
];

#[test]
fn demo_workspace_has_exactly_the_capacities_analyze_measures() {
    let cams: Vec<_> = (0..scanline3d_demo::ORBIT_FRAMES)
        .map(|f| SceneSpec::demo(f).unwrap().camera)
        .collect();
    let a = analyze::analyze(&SceneSpec::demo(0).unwrap(), &cams, 240, 240).unwrap();
    assert_eq!(a.triangle_capacity(0), scanline3d_demo::PANEL_TRIANGLES);
    assert_eq!(a.active_capacity(0), scanline3d_demo::PANEL_ACTIVE);
    assert_eq!(a.views_clipping, 0);
    let total = a.buffers(0).last().unwrap().1;
    assert_eq!(total, scanline3d_demo::PanelWorkspace::BYTES);
    // Every setting is free of real mismatches; 8 bits is the only one under 0.1 %.
    assert!(a.settings.iter().all(|s| s.real == 0));
    assert_eq!(a.recommended(0.1).unwrap().sub_bits, 8);
    assert_eq!(a.recommended(1.0).unwrap().sub_bits, 2);
}

#[test]
fn lean_obj_is_the_generated_icosphere() {
    let (positions, triangles) = meshgen::icosphere(1);
    let obj = MeshData::new(&positions, triangles, Default::default())
        .unwrap()
        .to_obj();
    let path = root().join(LEAN_OBJ);
    if std::env::var_os("SCANLINE3D_BLESS").is_some() {
        std::fs::write(&path, &obj).unwrap();
    }
    assert_eq!(std::fs::read_to_string(path).unwrap(), obj);
}

#[test]
fn export_regenerates_the_committed_lean_scenes_and_they_are_rustfmt_clean() {
    for (i, (args, committed)) in [
        (LEAN_EXPORT, LEAN_RS),
        (BAKED_EXPORT, BAKED_RS),
        (BSP_EXPORT, BSP_RS),
    ]
    .into_iter()
    .enumerate()
    {
        let dir =
            std::env::temp_dir().join(format!("scanline3d-export-{}-{i}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let out = dir.join("scene.rs");
        let status = Command::new(env!("CARGO_BIN_EXE_sim"))
            .args(args)
            .arg("--out")
            .arg(&out)
            .current_dir(root())
            .output()
            .unwrap();
        assert!(status.status.success(), "{status:?}");
        let generated = std::fs::read_to_string(&out).unwrap();
        let path = root().join(committed);
        if std::env::var_os("SCANLINE3D_BLESS").is_some() {
            std::fs::write(&path, &generated).unwrap();
        }
        assert_eq!(
            std::fs::read_to_string(&path).unwrap(),
            generated,
            "regenerate with: cargo run -p scanline3d-sim --bin sim -- {} --out {committed}",
            args.join(" ")
        );
        let fmt = Command::new("rustfmt")
            .args(["--edition", "2021", "--check"])
            .arg(&out)
            .output()
            .expect("rustfmt (installed by `cargo xtask test`)");
        assert!(
            fmt.status.success(),
            "{}",
            String::from_utf8_lossy(&fmt.stdout)
        );
        let _ = std::fs::remove_dir_all(dir);
    }
}

#[test]
fn bad_export_input_is_one_clear_error() {
    let run = |args: &[&str]| {
        let o = Command::new(env!("CARGO_BIN_EXE_sim"))
            .args(args)
            .current_dir(root())
            .output()
            .unwrap();
        (
            o.status.code(),
            String::from_utf8_lossy(&o.stderr).into_owned(),
        )
    };
    let (code, err) = run(&["export", "no-such.obj", "--out", "x.rs"]);
    assert_eq!(code, Some(2));
    assert!(
        err.starts_with("sim: no-such.obj") && err.lines().count() == 1,
        "{err}"
    );
    let (code, err) = run(&["export", "--demo", "--out", "x.rs"]);
    assert_eq!(code, Some(2));
    assert!(err.contains("OBJ"), "{err}");
    let (code, err) = run(&["analyze", LEAN_OBJ, "--views", "0"]);
    assert_eq!(code, Some(2));
    assert!(err.contains("--views"), "{err}");
    // Baked colours are for Unlit shading: normals would let Gouraud light them again.
    let (code, err) = run(&[
        "export",
        LEAN_OBJ,
        "--views",
        "2",
        "--bake-light",
        "--normals",
        "--out",
        "x.rs",
    ]);
    assert_eq!(code, Some(2));
    assert!(
        err.contains("--bake-light") && err.lines().count() == 1,
        "{err}"
    );
}

/// `--bake-light` with a narrow-normals preset writes the colours `Flat` gives with that
/// preset's arithmetic (`export::baked_colors`), which differ from the default's somewhere on
/// the heightfield, and each equals the library's own bake.
#[test]
fn baked_colours_follow_the_preset_s_normals() {
    use scanline3d_sim::export::baked_colors;
    use scanline3d_sim::scene::{LightSpec, SetupArith};
    let scene = scanline3d_sim::corpus::all()
        .into_iter()
        .find(|s| s.name == "heightfield")
        .unwrap();
    let light = LightSpec::default();
    let wide = baked_colors(&scene.mesh, &light, SetupArith::Precise).unwrap();
    let narrow = baked_colors(&scene.mesh, &light, SetupArith::Frugal).unwrap();
    assert_eq!(wide.len(), scene.mesh.triangles.len());
    assert_ne!(wide, narrow);
    let mut own = vec![Default::default(); wide.len()];
    scanline3d::shading::bake_face_colors::<scanline3d::arithmetic::Frugal>(
        &scene.mesh.mesh().unwrap(),
        &scanline3d::scene::Transform::IDENTITY,
        &light.fixed().unwrap(),
        &mut own,
    )
    .unwrap();
    assert_eq!(own, narrow);
}
