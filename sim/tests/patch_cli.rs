//! `sim render MODEL.bpt --renderer reference`: ids are patch indices in file order, depth is
//! eye depth; bad models are one line on stderr and exit status 2.

use std::path::{Path, PathBuf};
use std::process::Command;

fn sim(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_sim"))
        .args(args)
        .output()
        .unwrap()
}

fn models() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/patches")
}

fn words(path: &Path) -> Vec<[u8; 4]> {
    std::fs::read(path)
        .unwrap()
        .chunks(4)
        .map(|c| [c[0], c[1], c[2], c[3]])
        .collect()
}

#[test]
fn renders_the_sphere_with_ids_depth_and_stats() {
    let dir = std::env::temp_dir().join(format!("patch-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (png, ids, depth) = (dir.join("s.png"), dir.join("s.ids"), dir.join("s.depth"));
    let out = sim(&[
        "render",
        models().join("sphere.bpt").to_str().unwrap(),
        "--renderer",
        "reference",
        "--eye",
        "0,0,3",
        "--size",
        "40x30",
        "--out",
        png.to_str().unwrap(),
        "--ids",
        ids.to_str().unwrap(),
        "--depth",
        depth.to_str().unwrap(),
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
        stdout.contains("\"renderer\": \"reference\", \"patches\": 8"),
        "{stdout}"
    );
    let ids: Vec<i32> = words(&ids).into_iter().map(i32::from_le_bytes).collect();
    let depth: Vec<f32> = words(&depth).into_iter().map(f32::from_le_bytes).collect();
    assert_eq!((ids.len(), depth.len()), (40 * 30, 40 * 30));
    // Seen from +z the front four octants (z > 0) are visible: ids 0..8, and the centre
    // pixel's eye depth is 3 − 1 = 2 (the ray through it is slightly off the axis).
    assert!(ids.iter().all(|&i| (-1..8).contains(&i)));
    let centre = 15 * 40 + 20;
    assert!(
        ids[centre] >= 0 && (depth[centre] - 2.0).abs() < 1e-3,
        "{}",
        depth[centre]
    );
    for (i, z) in ids.iter().zip(&depth) {
        assert_eq!(*i >= 0, z.is_finite());
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_models_are_one_line_and_status_2() {
    let dir = std::env::temp_dir().join(format!("patch-cli-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let patch = |extra: &str| {
        let mut s = String::from("1\n3 3\n");
        for i in 0..16 {
            s += &format!("{} {} 0\n", i / 4, i % 4);
        }
        s + extra
    };
    let cases = [
        (
            "count.bpt",
            patch("").replacen('1', "2", 1),
            "count.bpt:18: file ends where patch 2 of 2",
        ),
        (
            "nan.bpt",
            patch("").replace("1 2 0", "1 2 nan"),
            "nan.bpt:9: patch 1 of 1: control point 7 z",
        ),
        (
            "weight.bpt",
            patch("weights 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 0\n"),
            "weight.bpt:19: patch 1 of 1: weight 16 is 0",
        ),
        (
            "trim.bpt",
            patch("trim 4 0.1 0.1 0.9 0.9 0.9 0.1 0.1 0.9\n"),
            "trim.bpt:19: patch 1 of 1: trim loop edges 1 and 3 cross",
        ),
    ];
    for (name, text, want) in cases {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        let out = sim(&[
            "render",
            path.to_str().unwrap(),
            "--renderer",
            "reference",
            "--out",
            dir.join("x.png").to_str().unwrap(),
        ]);
        assert_eq!(out.status.code(), Some(2), "{name}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.contains(want), "{err}\nwant {want}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
