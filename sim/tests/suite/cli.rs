//! The `sim` binary end to end: outputs in the documented formats, and one-line errors with exit
//! status 2 on bad input.

use std::path::PathBuf;

use crate::run::{scratch as scratch_dir, sim};

fn scratch(name: &str) -> PathBuf {
    scratch_dir(&format!("cli-{name}"))
}

fn corpus(name: &str) -> String {
    format!("{}/corpus/{name}.obj", env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn render_writes_png_ids_depth_and_stats_in_the_documented_formats() {
    let dir = scratch("render");
    let (code, stdout, stderr) = sim(
        &[
            "render",
            &corpus("cube"),
            "--eye",
            "-3,2,4",
            "--size",
            "64x48",
            "--out",
            "c.png",
            "--ids",
            "c.ids",
            "--depth",
            "c.depth",
            "--stats",
            "c.json",
        ],
        &dir,
    );
    assert_eq!(code, 0, "{stderr}");
    // Statistics go where asked, not to standard output unasked.
    assert!(!stdout.contains("triangles_in"), "{stdout}");
    let stats = std::fs::read_to_string(dir.join("c.json")).unwrap();
    assert!(stats.contains("\"triangles_in\": 12"), "{stats}");
    let ids = std::fs::read(dir.join("c.ids")).unwrap();
    let depth = std::fs::read(dir.join("c.depth")).unwrap();
    assert_eq!((ids.len(), depth.len()), (64 * 48 * 4, 64 * 48 * 4));
    let ids: Vec<i32> = ids
        .chunks(4)
        .map(|c| i32::from_le_bytes(c.try_into().unwrap()))
        .collect();
    let depth: Vec<f32> = depth
        .chunks(4)
        .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
        .collect();
    // Background is -1 with +inf depth; the cube (half-size 1 at distance ~5.4) is in between.
    assert_eq!(ids[0], -1);
    assert!(depth[0].is_infinite());
    let centre = 24 * 64 + 32;
    assert!((0..12).contains(&ids[centre]) && depth[centre] > 3.0 && depth[centre] < 6.0);
    assert_eq!(&std::fs::read(dir.join("c.png")).unwrap()[1..4], b"PNG");
    // The reference renderer writes the same formats, and `compare` reads both.
    let (code, _, stderr) = sim(
        &[
            "render",
            &corpus("cube"),
            "--eye",
            "-3,2,4",
            "--size",
            "64x48",
            "--renderer",
            "reference",
            "--out",
            "r.png",
            "--ids",
            "r.ids",
            "--depth",
            "r.depth",
        ],
        &dir,
    );
    assert_eq!(code, 0, "{stderr}");
    let (code, stdout, _) = sim(
        &[
            "compare", "c.ids", "c.depth", "r.ids", "r.depth", "--size", "64x48",
        ],
        &dir,
    );
    assert_eq!(code, 0);
    assert!(stdout.contains("id mismatches"), "{stdout}");
    let (code, stdout, _) = sim(
        &[
            "compare",
            "--scene",
            &corpus("cube"),
            "--eye",
            "-3,2,4",
            "--size",
            "64x48",
        ],
        &dir,
    );
    assert_eq!(code, 0);
    assert!(stdout.contains("real            0"), "{stdout}");
}

#[test]
fn bad_input_gives_one_line_and_status_2() {
    let dir = scratch("errors");
    std::fs::write(dir.join("badidx.obj"), "v 0 0 0\nv 1 0 0\nf 1 2 7\n").unwrap();
    std::fs::write(
        dir.join("nan.obj"),
        "v 0 0 nan\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    )
    .unwrap();
    std::fs::write(dir.join("junk.obj"), "v 1 2\nf x y z\n").unwrap();
    let cube = corpus("cube");
    let cases: [(&[&str], &str); 8] = [
        (&["render", "missing.obj"], "missing.obj"),
        (&["render", "badidx.obj"], "index"),
        (&["render", "nan.obj"], "NaN"),
        (&["render", "junk.obj"], "junk.obj"),
        (&["render", &cube, "--size", "0x10"], "size"),
        (&["render", &cube, "--eye", "nan,1,2"], "finite"),
        (
            &["render", &cube, "--eye", "0,0,0", "--target", "0,0,0"],
            "eye and target",
        ),
        (&["compare", "a.ids"], "compare needs"),
    ];
    for (args, needle) in cases {
        let (code, _, stderr) = sim(args, &dir);
        assert_eq!(code, 2, "{args:?}: {stderr}");
        assert_eq!(stderr.lines().count(), 1, "{args:?}: {stderr}");
        assert!(
            stderr.starts_with("sim: ") && stderr.contains(needle),
            "{args:?}: {stderr}"
        );
        assert!(!stderr.contains("panicked"));
    }
}

#[test]
fn committed_corpus_files_match_the_generator() {
    for scene in scanline3d_sim::corpus::all() {
        let committed = std::fs::read_to_string(corpus(scene.name)).unwrap();
        assert_eq!(
            committed,
            scene.mesh.to_obj(),
            "sim/corpus/{}.obj is stale: run `sim corpus --out sim/corpus`",
            scene.name
        );
        // Loading renumbers vertices (in order of first use) but keeps triangle order, which is
        // what triangle ids follow, and every coordinate exactly.
        let loaded =
            scanline3d_sim::scene::MeshData::load_obj(std::path::Path::new(&corpus(scene.name)))
                .unwrap();
        let corners = |m: &scanline3d_sim::scene::MeshData| -> Vec<_> {
            m.triangles
                .iter()
                .map(|t| t.map(|i| m.vertices[i as usize]))
                .collect()
        };
        assert_eq!(corners(&loaded), corners(&scene.mesh), "{}", scene.name);
    }
}

#[test]
fn every_algorithm_renders_the_same_ids_where_it_is_exact() {
    let dir = scratch("algorithms");
    let ids = |algorithm: &str| {
        let file = format!("{}.ids", algorithm.replace(':', "-"));
        let args = [
            "render",
            &corpus("interpenetrating"),
            "--eye",
            "0.3,0.2,4",
            "--no-cull",
            "--size",
            "64x48",
            "--ids",
            &file,
            "--algorithm",
            algorithm,
            "--stats",
            "-",
        ];
        let (code, stdout, stderr) = sim(&args, &dir);
        assert_eq!(code, 0, "{algorithm}: {stderr}");
        if algorithm != "raycast" {
            assert!(
                stdout.contains(&format!("\"algorithm\": \"{algorithm}\"")),
                "{stdout}"
            );
        }
        std::fs::read(dir.join(file)).unwrap()
    };
    let span = ids("span-zbuffer");
    for exact in ["zbuffer", "band:4", "span-sort", "bsp", "newell", "warnock"] {
        assert_eq!(ids(exact), span, "{exact}");
    }
    // Depth sort draws the two crossing triangles in one order: wrong on one side.
    assert_ne!(ids("depth-sort"), span);
    assert_eq!(ids("raycast").len(), span.len());
}

#[test]
fn unknown_algorithms_are_one_line_errors() {
    let dir = scratch("bad-algorithm");
    for (bad, says) in [
        ("painter", "unknown algorithm"),
        ("band:3", "band height must be one of"),
    ] {
        let (code, _, stderr) = sim(
            &[
                "render",
                &corpus("cube"),
                "--algorithm",
                bad,
                "--size",
                "8x8",
            ],
            &dir,
        );
        assert_eq!(code, 2, "{bad}: {stderr}");
        assert!(stderr.contains(says), "{bad}: {stderr}");
    }
}

#[test]
fn presets_set_sub_pixel_bits_and_set_up_math_together() {
    let dir = scratch("preset");
    let ids = |preset: &[&str], name: &str| {
        let (code, _, stderr) = sim(
            &[
                &[
                    "render",
                    &corpus("pawn"),
                    "--eye",
                    "-2.2,1.6,3.2",
                    "--size",
                    "96x96",
                ][..],
                preset,
                &["--ids", name, "--stats", &format!("{name}.json")],
            ]
            .concat(),
            &dir,
        );
        assert_eq!(code, 0, "{stderr}");
        let stats = std::fs::read_to_string(dir.join(format!("{name}.json"))).unwrap();
        (std::fs::read(dir.join(name)).unwrap(), stats)
    };
    // Exact is 8 sub-pixel bits with the default (precise) arithmetic and libm set-up.
    let (bits8, _) = ids(&["--sub-pixel-bits", "8"], "bits8.ids");
    let (exact, stats) = ids(&["--preset", "exact"], "exact.ids");
    assert_eq!(bits8, exact);
    assert!(
        stats.contains("\"arithmetic\": \"precise\", \"sub_pixel_bits\": 8"),
        "{stats}"
    );
    // Balanced keeps the default's 4 bits and precise arithmetic; fast is 2 bits, quick.
    let (_, stats) = ids(&["--preset", "balanced"], "balanced.ids");
    assert!(
        stats.contains(
            "\"preset\": \"balanced\", \"arithmetic\": \"precise\", \"sub_pixel_bits\": 4"
        ),
        "{stats}"
    );
    let (default, stats) = ids(&[], "default.ids");
    assert!(
        stats.contains("\"preset\": null, \"arithmetic\": \"precise\""),
        "{stats}"
    );
    let (fast, stats) = ids(&["--preset", "fast"], "fast.ids");
    assert_ne!(fast, default);
    assert!(
        stats.contains(
            "\"preset\": \"fast\", \"arithmetic\": \"narrow transform\", \"sub_pixel_bits\": 2"
        ),
        "{stats}"
    );
    // The narrow arithmetic is built for the span z-buffer only, and says so.
    let (code, _, stderr) = sim(
        &[
            "render",
            &corpus("cube"),
            "--preset",
            "fast",
            "--algorithm",
            "zbuffer",
            "--ids",
            "x.ids",
        ],
        &dir,
    );
    assert_ne!(code, 0);
    assert!(stderr.contains("span-zbuffer only"), "{stderr}");
    // A preset and explicit sub-pixel bits conflict; unknown presets are named.
    for (args, says) in [
        (
            &["--preset", "fast", "--sub-pixel-bits", "2"][..],
            "cannot be used with",
        ),
        (
            &["--preset", "nope"][..],
            "choose one of fast, balanced, exact",
        ),
    ] {
        let (code, _, stderr) = sim(&[&["render", &corpus("cube")][..], args].concat(), &dir);
        assert_eq!(code, 2, "{stderr}");
        assert!(stderr.contains(says), "{stderr}");
    }
}
