//! `sim metaball`: renders a .meta file; bad input is one line on stderr and exit status 2.

use std::process::Command;

fn sim(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_sim"))
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn renders_both_methods_with_ids_and_depth() {
    let dir = std::env::temp_dir().join(format!("metaball-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("six.meta");
    std::fs::write(&scene, scanline3d_sim::metaball::SIX_BALLS).unwrap();
    for method in ["raycast", "reference"] {
        let png = dir.join(format!("{method}.png"));
        let ids = dir.join(format!("{method}.ids"));
        let out = sim(&[
            "metaball",
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
            stdout.contains(&format!("\"renderer\": \"{method}\"")),
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
            "metaball",
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
