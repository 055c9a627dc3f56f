//! `sim render SCENE.meta` (and its alias `sim metaball`): renders a .meta file with each method; bad input is one line on stderr and exit status 2.

use std::process::Command;

fn sim(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_sim"))
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn renders_every_method_with_ids_and_depth() {
    let dir = std::env::temp_dir().join(format!("metaball-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("six.meta");
    std::fs::write(&scene, scanline3d_sim::metaball::SIX_BALLS).unwrap();
    for (command, method) in [
        ("render", "raycast"),
        ("render", "polygonize:16"),
        ("metaball", "reference"),
    ] {
        let png = dir.join(format!("{}.png", method.replace(':', "_")));
        let ids = dir.join(format!("{}.ids", method.replace(':', "_")));
        let out = sim(&[
            command,
            scene.to_str().unwrap(),
            "--frame",
            "3",
            "--method",
            method,
            "--size",
            "48x40",
            "--out",
            png.to_str().unwrap(),
            "--ids",
            ids.to_str().unwrap(),
            "--stats",
            "-",
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(
            stdout.contains(&format!(
                "\"renderer\": \"{}\"",
                method.split(':').next().unwrap()
            )),
            "{stdout}"
        );
        let ids = std::fs::read(&ids).unwrap();
        assert_eq!(ids.len(), 48 * 40 * 4);
        let covered = ids
            .chunks(4)
            .filter(|c| i32::from_le_bytes([c[0], c[1], c[2], c[3]]) >= 0)
            .count();
        assert!(covered > 100, "{method}: {covered} pixels covered");
        assert!(std::fs::metadata(&png).unwrap().len() > 0);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_input_is_one_line_and_status_2() {
    let dir = std::env::temp_dir().join(format!("metaball-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let cases = [
        (
            "threshold 0.5\nmetaball 0 0 0 one 1\n",
            ":2: 'one' is not a finite number",
        ),
        (
            "threshold 0.5\nmetaball 100 0 0 1 1\n",
            "ball 0: centre within",
        ),
    ];
    for (i, (text, want)) in cases.iter().enumerate() {
        let path = dir.join(format!("bad{i}.meta"));
        std::fs::write(&path, text).unwrap();
        let out = sim(&[
            "render",
            path.to_str().unwrap(),
            "--out",
            dir.join("x.png").to_str().unwrap(),
        ]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{stderr}");
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
        assert!(stderr.contains(want), "{stderr}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_method_and_meta_options_on_obj_are_one_line_and_status_2() {
    let dir = std::env::temp_dir().join(format!("metaball-opts-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let meta = dir.join("six.meta");
    std::fs::write(&meta, scanline3d_sim::metaball::SIX_BALLS).unwrap();
    let obj = dir.join("tri.obj");
    std::fs::write(&obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let png = dir.join("x.png");
    let cases = [
        (
            meta.to_str().unwrap(),
            "polygonize:7",
            "polygonize:N with N one of",
        ),
        (obj.to_str().unwrap(), "raycast", "are for .meta scenes"),
    ];
    for (scene, method, want) in cases {
        let out = sim(&[
            "render",
            scene,
            "--method",
            method,
            "--out",
            png.to_str().unwrap(),
        ]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{stderr}");
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
        assert!(stderr.contains(want), "{stderr}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_firmware_scene_is_what_export_writes() {
    let dir = crate::run::scratch("metaball-export");
    // Run from the repository root so the header's command line is the one in the file.
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let out = dir.join("six.rs");
    let (code, stdout, stderr) = crate::run::sim(
        &[
            "export",
            "sim/src/metaball/six.meta",
            "-o",
            out.to_str().unwrap(),
        ],
        &root,
    );
    assert_eq!(code, 0, "{stderr}");
    assert!(stdout.contains("(6 balls, 8 frames)"), "{stdout}");
    let fresh = std::fs::read_to_string(&out).unwrap();
    let committed = std::fs::read_to_string(root.join("demo/src/metaballs/six.rs")).unwrap();
    assert_eq!(
        fresh, committed,
        "regenerate demo/src/metaballs/six.rs with `sim export sim/src/metaball/six.meta -o demo/src/metaballs/six.rs`"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn export_of_bad_input_is_one_line_and_status_2() {
    let dir = crate::run::scratch("metaball-export-bad");
    let cases = [
        (
            "threshold 0.5\nmetaball 0 0 0 one 1\n",
            "bad0.meta:2: 'one' is not a finite number",
        ),
        (
            "threshold 0.5\nmetaball 0 0 0 1 1\nkey 4 100 0 0\n",
            "bad1.meta: ball 0: centre within",
        ),
        (
            "threshold 100\nmetaball 0 0 0 1 1\n",
            "bad2.meta: threshold must be in (0, 64]",
        ),
        (
            "threshold 0.5\nmetaball 0 0 0 1 1\nkey 3 0 0 0\nkey 2 1 0 0\n",
            "bad3.meta:4: key frames must increase",
        ),
    ];
    for (i, (text, want)) in cases.iter().enumerate() {
        std::fs::write(dir.join(format!("bad{i}.meta")), text).unwrap();
        let (code, _, stderr) = crate::run::sim(
            &["export", &format!("bad{i}.meta"), "--out", "bad.rs"],
            &dir,
        );
        assert_eq!(code, 2, "{stderr}");
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
        assert!(stderr.starts_with(&format!("sim: {want}")), "{stderr}");
        assert!(!dir.join("bad.rs").exists(), "case {i} wrote a file");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
