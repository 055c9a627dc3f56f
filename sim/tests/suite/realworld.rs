//! Issue 20: scenes as users have them. Culling decided from the mesh and the view, worlds
//! beyond the model envelope, OBJ materials and normals, and every method on a random
//! interpenetrating soup (from outside and inside), a scanned-style mesh and a km-scale city.

use scanline3d_sim::analyze::newell_needs;
use scanline3d_sim::corpus::real_world;
use scanline3d_sim::metrics::Metrics;
use scanline3d_sim::scene::{Algorithm, CameraSpec, LightSpec, MeshData, PresetChoice, SceneSpec};
use scanline3d_sim::world::{Culling, Loaded, World};
use scanline3d_sim::{accuracy_preset, accuracy_with};

const W: usize = 240;
const H: usize = 240;

/// The scene `sim render` makes of `world` seen by `camera` with default culling.
fn default_spec(world: World, camera: CameraSpec, culling: Culling) -> SceneSpec {
    let loaded = Loaded::from_world(world, false).unwrap();
    let cull = loaded.culling(culling, &[camera], W as f64 / H as f64).cull;
    SceneSpec {
        instances: loaded.instances,
        camera,
        light: LightSpec::default(),
        cull_back_faces: cull,
    }
}

fn spec_of(mesh: &MeshData, camera: CameraSpec) -> SceneSpec {
    default_spec(World::from_mesh(mesh), camera, Culling::Auto)
}

/// Every method at the default settings (4 sub-pixel bits), then the exact preset, with the
/// host time of each fixed-point render (printed, not checked).
fn table(name: &str, spec: &SceneSpec) -> Vec<(String, Metrics)> {
    let mut rows = Vec::new();
    for a in Algorithm::ALL {
        let start = std::time::Instant::now();
        let (m, fixed, _) = accuracy_with(spec, W, H, 4, a).unwrap();
        let seconds = start.elapsed().as_secs_f64();
        // Pieces drawn: the triangles filed, or for Newell the pieces its splits leave.
        let pieces = if a == Algorithm::Newell {
            let needs = newell_needs(spec, W, H).unwrap();
            format!(
                "{} ({} splits, {} entries, {} steps)",
                needs.pieces_out, needs.splits, needs.entries, needs.steps
            )
        } else {
            fixed.stats.bucketed.to_string()
        };
        println!(
            "| {name} | {a} | {:.3} | {} | {seconds:.2} | {pieces} |",
            m.id_mismatch_percent(),
            m.real,
        );
        rows.push((a.to_string(), m));
    }
    let (m, _, _) =
        accuracy_preset(spec, W, H, PresetChoice::Exact, Algorithm::SpanZBuffer).unwrap();
    println!(
        "| {name} | exact preset | {:.3} | {} | | |",
        m.id_mismatch_percent(),
        m.real
    );
    rows.push(("exact".into(), m));
    rows
}

/// The numbers: on the soup from outside and inside and on the scanned-style mesh,
/// with the default command line (culling decided, here two-sided for the soup), every correct
/// method has no real mismatches and at most 2 % id mismatches, and the exact preset at most
/// 0.1 %. Newell–Newell–Sancha included: it must also finish the soup within its capacities,
/// which it used not to (docs/realworld.md).
#[test]
fn hard_scenes_every_method() {
    let soup = real_world::soup();
    let [outside, inside] = real_world::soup_cameras();
    let scanned = real_world::scanned();
    assert!(scanned.triangles.len() >= 3000 && soup.triangles.len() >= 400);
    println!("| scene | method | id mismatch % | real | seconds (host) | pieces drawn |");
    println!("|---|---|---|---|---|---|");
    let mut failures = Vec::new();
    for (name, spec) in [
        ("soup outside", spec_of(&soup, outside)),
        ("soup inside", spec_of(&soup, inside)),
        (
            "scanned",
            spec_of(&scanned, real_world::scanned_cameras()[0]),
        ),
    ] {
        for (method, m) in table(name, &spec) {
            let limit = if method == "exact" { 0.1 } else { 2.0 };
            let correct = method != Algorithm::DepthSort.to_string();
            if correct && (m.real > 0 || m.id_mismatch_percent() > limit) {
                failures.push(format!("{name} {method}: {m}"));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

// ---- 2. Culling that is right by default ----

#[test]
fn open_mesh_with_random_winding_renders_complete_by_default() {
    let mesh = real_world::open_random_winding();
    for cam in real_world::open_cameras() {
        let spec = spec_of(&mesh, cam);
        assert!(!spec.cull_back_faces, "an open mesh is drawn two-sided");
        let (m, _, _) = accuracy_with(&spec, W, H, 4, Algorithm::SpanZBuffer).unwrap();
        assert_eq!(m.real, 0, "{m}");
        assert!(m.id_mismatch_percent() <= 2.0, "{m}");
        // Culling anyway loses about half the faces, and the reference, which sees every
        // face, counts them.
        let culled = SceneSpec {
            cull_back_faces: true,
            ..spec
        };
        let (m, _, _) = accuracy_with(&culled, W, H, 4, Algorithm::SpanZBuffer).unwrap();
        assert!(m.real > 1000, "culling errors must count: {m}");
    }
}

/// An icosphere (closed, counter-clockwise from outside) with the faces `flip` reversed.
fn sphere_with_flips(flip: &[usize]) -> World {
    let mut world = World::from_mesh(&scanline3d_sim::corpus::icosphere(2));
    world.flip(flip);
    world
}

#[test]
fn closed_mesh_with_inconsistent_winding_is_reported_with_the_faces_to_flip() {
    let flipped = [3, 17, 100, 250];
    let world = sphere_with_flips(&flipped);
    let o = world.orientation();
    assert!(o.closed(), "{o}");
    assert_eq!(o.flips, flipped, "{o}");
    assert!(o.to_string().contains("3, 17, 100, 250"), "{o}");
    let cam = CameraSpec::looking_at([2.0, 1.0, 2.5], [0.0; 3], 50.0, 0.1, 20.0);
    let loaded = Loaded::from_world(world.clone(), false).unwrap();
    let d = loaded.culling(Culling::Auto, &[cam], 1.0);
    assert!(!d.cull, "{}", d.reason);
    // Rendered two-sided it is complete; culled as it is, the flipped faces are holes that
    // the reference sees.
    let spec = default_spec(world.clone(), cam, Culling::Auto);
    let (m, _, _) = accuracy_with(&spec, W, H, 4, Algorithm::SpanZBuffer).unwrap();
    assert_eq!(m.real, 0, "{m}");
    let spec = default_spec(world.clone(), cam, Culling::On);
    let (m, _, _) = accuracy_with(&spec, W, H, 4, Algorithm::SpanZBuffer).unwrap();
    assert!(m.real > 0, "{m}");
    // --orient flips them back, and then culling applies and is right.
    let oriented = Loaded::from_world(world, true).unwrap();
    assert!(oriented.world.orientation().closed_and_outward());
    assert!(oriented.culling(Culling::Auto, &[cam], 1.0).cull);
    // A mesh wound inside out throughout is reported whole.
    let all: Vec<usize> = (0..320).collect();
    assert_eq!(sphere_with_flips(&all).orientation().flips, all);
}

#[test]
fn closed_mesh_is_culled_only_with_every_eye_outside_and_clear_of_the_near_plane() {
    let world = sphere_with_flips(&[]);
    let loaded = Loaded::from_world(world, false).unwrap();
    assert!(loaded.orientation.closed_and_outward());
    let cull = |eye: [f64; 3], near: f64| {
        let cam = CameraSpec::looking_at(eye, [0.0, 0.2, 0.0], 50.0, near, 20.0);
        loaded.culling(Culling::Auto, &[cam], 1.0).cull
    };
    assert!(cull([2.0, 1.0, 2.5], 0.1));
    assert!(!cull([0.1, 0.0, 0.2], 0.01), "eye inside");
    assert!(
        !cull([0.0, 0.0, 1.05], 0.1),
        "the near plane cuts the sphere"
    );
    // The soup is open: never culled.
    let soup = Loaded::from_world(World::from_mesh(&real_world::soup()), false).unwrap();
    assert!(!soup.orientation.closed());
    let [outside, _] = real_world::soup_cameras();
    assert!(!soup.culling(Culling::Auto, &[outside], 1.0).cull);
    // --cull and --no-cull override.
    assert!(soup.culling(Culling::On, &[outside], 1.0).cull);
    assert!(!loaded.culling(Culling::Off, &[outside], 1.0).cull);
}

// ---- 1. Worlds beyond the model envelope ----

#[test]
fn km_scale_city_renders_at_near_far_1e5() {
    let world = real_world::city();
    assert!(world.max_coord() > 7900.0 && !world.fits_one_mesh());
    for cam in real_world::city_cameras() {
        assert!(cam.far / cam.near >= 1e5);
        let spec = default_spec(world.clone(), cam, Culling::Auto);
        assert!(spec.instances.len() > 1);
        for i in &spec.instances {
            i.mesh.mesh().unwrap(); // every chunk inside the model envelope
        }
        let (m, fixed, _) =
            accuracy_preset(&spec, W, H, PresetChoice::Exact, Algorithm::SpanZBuffer).unwrap();
        println!(
            "city from {:?} ({} chunks): exact preset {m}",
            cam.eye,
            spec.instances.len()
        );
        let covered = fixed.image.ids.iter().filter(|&&i| i >= 0).count();
        assert!(
            covered > W * H / 10,
            "the city is in view: {covered} pixels"
        );
        assert_eq!(m.real, 0, "{m}");
        assert!(m.id_mismatch_percent() <= 0.1, "{m}");
        let (m, _, _) = accuracy_with(&spec, W, H, 4, Algorithm::SpanZBuffer).unwrap();
        assert_eq!(m.real, 0, "default settings: {m}");
    }
}

#[test]
fn views_of_a_large_world_fit_the_eye_envelope() {
    use scanline3d_sim::analyze::{self, ViewRange};
    let spec = default_spec(
        real_world::city(),
        real_world::city_cameras()[0],
        Culling::Auto,
    );
    let (_, radius) = analyze::bounds(&spec).unwrap();
    let r = ViewRange::fit(radius, None, None, None).unwrap();
    assert!(r.far <= 16384.0 && r.far >= r.distance + radius, "{r:?}");
    assert!(r.far / r.near <= 1048576.0, "{r:?}");
    for cam in analyze::default_views(&spec, 4).unwrap() {
        cam.fixed().unwrap();
    }
    // Small scenes keep the old defaults.
    let r = ViewRange::fit(1.0, None, None, None).unwrap();
    assert_eq!((r.distance, r.near, r.far), (3.0, 0.15, 12.0));
    // Beyond any view of the whole: a clear error.
    assert!(ViewRange::fit(20_000.0, None, None, None).is_err());
}

#[test]
fn scenes_beyond_one_frame_render_in_passes() {
    // 81,920 triangles: more than one frame holds.
    let (v, f) = scanline3d_sim::meshgen::icosphere(6);
    let world = World::new(
        v,
        f.into_iter().map(|t| t.map(u32::from)).collect(),
        vec![scanline3d_sim::world::DEFAULT_COLOR; 81_920],
    );
    assert!(!world.fits_one_mesh());
    let cam = CameraSpec::looking_at([1.6, 0.9, 2.2], [0.0; 3], 45.0, 0.1, 20.0);
    let spec = default_spec(world, cam, Culling::Auto);
    assert!(!spec.fits_one_pass());
    let (m, _, _) = accuracy_with(&spec, W, H, 4, Algorithm::SpanZBuffer).unwrap();
    assert_eq!(m.real, 0, "{m}");
    assert!(m.id_mismatch_percent() <= 2.0, "{m}");
    // Methods without depth cannot be composited: a clear error, not a wrong image.
    let e = spec
        .render_fixed_with(W, H, 4, Algorithm::Warnock)
        .unwrap_err();
    assert!(e.contains("several passes"), "{e}");
}

// ---- 3. OBJ as users have it ----

#[test]
fn obj_materials_become_face_colours_and_normals_are_kept() {
    let (obj, mtl, colors) = real_world::materials_obj();
    let dir = std::env::temp_dir().join(format!("scanline3d-materials-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("box.obj");
    std::fs::write(&path, &obj).unwrap();
    std::fs::write(dir.join("materials.mtl"), &mtl).unwrap();
    let world = World::load_obj(&path, |_, _| {}).unwrap();
    assert!(world.warnings.is_empty(), "{:?}", world.warnings);
    let rgb = |c: [u8; 3]| embedded_graphics::pixelcolor::Rgb888::new(c[0], c[1], c[2]);
    for (k, c) in world.colors.iter().enumerate() {
        assert_eq!(*c, rgb(colors[k / 4]), "face {k}");
    }
    // Normals from the file, one per position, reach the library's mesh.
    assert_eq!(world.normals.len(), world.positions.len());
    let (instances, _) = world.instances().unwrap();
    let normals = instances[0].mesh.normals.as_ref().unwrap();
    let n0 = normals[0].map(|c| c.to_num::<f64>());
    let s = 1.0 / 6f64.sqrt();
    let expected = [s, 2.0 * s, s];
    assert!(
        n0.iter()
            .zip(expected)
            .all(|(c, e)| (c.abs() - e).abs() < 1e-4),
        "{n0:?}"
    );
    // The id image does not depend on the colours.
    let cam = CameraSpec::looking_at([2.0, 1.5, 3.0], [0.0; 3], 50.0, 0.1, 20.0);
    let with = default_spec(world.clone(), cam, Culling::Auto);
    let mut grey = world.clone();
    grey.colors = vec![scanline3d_sim::world::DEFAULT_COLOR; grey.colors.len()];
    let without = default_spec(grey, cam, Culling::Auto);
    let a = with.render_fixed(W, H, 4).unwrap();
    let b = without.render_fixed(W, H, 4).unwrap();
    assert_eq!(a.image.ids, b.image.ids);
    assert_ne!(a.image.color, b.image.color);
    // Without its .mtl file the scene still loads, with a warning.
    std::fs::remove_file(dir.join("materials.mtl")).unwrap();
    let world = World::load_obj(&path, |_, _| {}).unwrap();
    assert!(
        world.warnings.iter().any(|w| w.contains("materials.mtl")),
        "{:?}",
        world.warnings
    );
    assert_eq!(world.triangles.len(), 12);
    std::fs::remove_dir_all(&dir).unwrap();
}

// ---- 5. Watertight BSP splits ----

/// Pixels inside the silhouette of a closed scene (the reference covers the pixel and its
/// eight neighbours) that the fixed-point render leaves empty.
fn holes(fixed: &[i32], reference: &[i32]) -> usize {
    let at = |x: i64, y: i64| reference[(y as usize) * W + x as usize];
    let mut n = 0;
    for y in 1..H as i64 - 1 {
        for x in 1..W as i64 - 1 {
            let inside = (-1..=1).all(|dy| (-1..=1).all(|dx| at(x + dx, y + dy) >= 0));
            n += (inside && fixed[y as usize * W + x as usize] < 0) as usize;
        }
    }
    n
}

#[test]
fn bsp_splits_are_watertight() {
    let mesh = real_world::bsp_split();
    assert!(World::from_mesh(&mesh).orientation().closed());
    let bsp = scanline3d_sim::bsp::build(&mesh).unwrap();
    assert!(bsp.splits >= 200, "split-heavy: {} splits", bsp.splits);
    let soup = real_world::soup();
    let [soup_out, soup_in] = real_world::soup_cameras();
    let [a, b] = real_world::bsp_split_cameras();
    for (spec, closed) in [
        (spec_of(&mesh, a), true),
        (spec_of(&mesh, b), true),
        (spec_of(&soup, soup_out), false),
        (spec_of(&soup, soup_in), false),
    ] {
        let (m, fixed, reference) = accuracy_with(&spec, W, H, 4, Algorithm::Bsp).unwrap();
        assert_eq!(m.real, 0, "{m}");
        if closed {
            assert_eq!(holes(&fixed.image.ids, &reference.ids), 0);
        }
    }
}

// ---- 4. Newell's capacities from the scene ----

/// `analyze` measures what Newell's sort needs over the views (workspace entries, sort steps)
/// and sizes `PIECES` from it, which `export` writes as `NEWELL_PIECES`.
#[test]
fn analyze_measures_what_newell_needs() {
    let scene = scanline3d_sim::corpus::all()
        .into_iter()
        .find(|s| s.name == "cyclic")
        .unwrap();
    let spec = SceneSpec::single(
        scene.mesh.clone(),
        scene.cameras[0],
        LightSpec::default(),
        scene.cull_back_faces,
    );
    let a = scanline3d_sim::analyze::analyze(&spec, &scene.cameras, 64, 64).unwrap();
    assert!(a.newell_error.is_none(), "{:?}", a.newell_error);
    let n = a.newell;
    // The cycle needs splits, and the parts take entries beyond the kept triangles.
    assert!(n.splits > 0, "{n:?}");
    assert!(n.entries as usize > scene.mesh.triangles.len(), "{n:?}");
    for view in &scene.cameras {
        let one = newell_needs(
            &SceneSpec {
                camera: *view,
                ..spec.clone()
            },
            64,
            64,
        )
        .unwrap();
        assert!(
            one.entries <= n.entries && one.steps <= n.steps,
            "{one:?} {n:?}"
        );
    }
    let cap = n.pieces_capacity(0);
    assert!(cap >= n.entries as usize, "{cap} {n:?}");
    assert!(scanline3d::resolve::newell::step_limit(cap) >= n.steps as usize);
    assert!(n.pieces_capacity(50) > cap);
    assert!(a.to_string().contains("sort steps"), "{a}");
}
