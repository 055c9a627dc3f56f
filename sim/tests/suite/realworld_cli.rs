//! Issue 20 through the `sim` binary: default culling and its overrides, large worlds,
//! empty frames, and what `analyze` and `export` report.

use scanline3d_sim::corpus::{self, real_world};
use scanline3d_sim::world::World;
use std::path::PathBuf;

use crate::run::{scratch as scratch_dir, sim};

fn scratch(name: &str) -> PathBuf {
    scratch_dir(&format!("rw-{name}"))
}

#[test]
fn empty_frames_say_so_and_flags_conflict() {
    let dir = scratch("empty");
    std::fs::write(dir.join("soup.obj"), real_world::soup().to_obj()).unwrap();
    // Looking away from everything.
    let (code, _, stderr) = sim(
        &[
            "render", "soup.obj", "--eye", "0,0,5", "--target", "0,0,10", "--size", "32x32",
        ],
        &dir,
    );
    assert_eq!(code, 0, "{stderr}");
    assert!(stderr.contains("nothing drawn"), "{stderr}");
    let (code, _, stderr) = sim(&["render", "soup.obj", "--size", "32x32"], &dir);
    assert_eq!(code, 0, "{stderr}");
    assert!(!stderr.contains("nothing drawn"), "{stderr}");
    let (code, _, stderr) = sim(&["render", "soup.obj", "--cull", "--no-cull"], &dir);
    assert_eq!(code, 2, "{stderr}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn analyze_reports_winding_and_culling_and_orient_fixes_it() {
    let dir = scratch("winding");
    let mut world = World::from_mesh(&corpus::icosphere(2));
    world.flip(&[3, 17]);
    std::fs::write(dir.join("s.obj"), world.to_obj()).unwrap();
    let args = ["analyze", "s.obj", "--views", "2", "--size", "48x48"];
    let (code, stdout, stderr) = sim(&args, &dir);
    assert_eq!(code, 0, "{stderr}");
    assert!(
        stdout.contains("inconsistently wound: 2 of 320 faces to flip (3, 17)"),
        "{stdout}"
    );
    assert!(stdout.contains("culling: two-sided"), "{stdout}");
    assert!(stderr.contains("faces to flip"), "{stderr}");
    let (code, stdout, stderr) = sim(&[&args[..], &["--orient"]].concat(), &dir);
    assert_eq!(code, 0, "{stderr}");
    assert!(stdout.contains("culling: back faces culled"), "{stdout}");
    // export writes the decision into the budget.
    let (code, _, stderr) = sim(
        &[
            "export", "s.obj", "--orient", "--views", "2", "--size", "48x48", "--out", "s.rs",
        ],
        &dir,
    );
    assert_eq!(code, 0, "{stderr}");
    let src = std::fs::read_to_string(dir.join("s.rs")).unwrap();
    assert!(src.contains("CULL_BACK_FACES: bool = true"), "{src}");
    let (code, _, stderr) = sim(
        &[
            "export", "s.obj", "--views", "2", "--size", "48x48", "--out", "s.rs",
        ],
        &dir,
    );
    assert_eq!(code, 0, "{stderr}");
    let src = std::fs::read_to_string(dir.join("s.rs")).unwrap();
    assert!(src.contains("CULL_BACK_FACES: bool = false"), "{src}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_km_scale_city_renders_with_the_default_command_line() {
    let dir = scratch("city");
    let world = real_world::city();
    std::fs::write(dir.join("city.obj"), world.to_obj()).unwrap();
    let (code, stdout, stderr) = sim(
        &[
            "compare",
            "--scene",
            "city.obj",
            "--eye",
            "-600,900,-600",
            "--target",
            "4000,0,4000",
            "--near",
            "0.1",
            "--far",
            "10000",
            "--preset",
            "exact",
            "--size",
            "96x96",
        ],
        &dir,
    );
    assert_eq!(code, 0, "{stderr}");
    assert!(stdout.contains("real            0"), "{stdout}");
    let (code, _, stderr) = sim(
        &[
            "render",
            "city.obj",
            "--eye",
            "-600,900,-600",
            "--target",
            "4000,0,4000",
            "--near",
            "0.1",
            "--far",
            "10000",
            "--size",
            "64x64",
            "--ids",
            "city.ids",
        ],
        &dir,
    );
    assert_eq!(code, 0, "{stderr}");
    // Ids are the file's face numbers.
    let ids: Vec<i32> = std::fs::read(dir.join("city.ids"))
        .unwrap()
        .chunks(4)
        .map(|c| i32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    assert!(ids.iter().any(|&i| i >= 0));
    assert!(ids.iter().all(|&i| i < world.triangles.len() as i32));
    // analyze picks a view range that fits; export refuses with a pointer to the docs.
    let (code, stdout, stderr) = sim(
        &["analyze", "city.obj", "--views", "1", "--size", "32x32"],
        &dir,
    );
    assert_eq!(code, 0, "{stderr}");
    assert!(stdout.contains("placement:"), "{stdout}");
    let (code, _, stderr) = sim(
        &[
            "export", "city.obj", "--views", "1", "--size", "32x32", "--out", "c.rs",
        ],
        &dir,
    );
    assert_eq!(code, 2);
    assert!(stderr.contains("docs/large-worlds.md"), "{stderr}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn export_uses_the_obj_files_vertex_normals() {
    let dir = scratch("normals");
    let (obj, mtl, _) = real_world::materials_obj();
    std::fs::write(dir.join("box.obj"), obj).unwrap();
    std::fs::write(dir.join("materials.mtl"), mtl).unwrap();
    let (code, _, stderr) = sim(
        &[
            "export",
            "box.obj",
            "--normals",
            "--views",
            "1",
            "--size",
            "32x32",
            "--out",
            "b.rs",
        ],
        &dir,
    );
    assert_eq!(code, 0, "{stderr}");
    let src = std::fs::read_to_string(dir.join("b.rs")).unwrap();
    // (1, 2, 1)/√6 in I16F16 bits: 26755, 53510; area weighting would give 37837 (1/√3).
    assert!(src.contains("26755") && src.contains("53510"), "{src}");
    assert!(!src.contains("37837"), "{src}");
    std::fs::remove_dir_all(&dir).unwrap();
}
