//! Numerical extremes, each compared with the f64 reference: every mismatch must be explained by
//! the documented position bound (zero real mismatches), plus case-specific checks.

use embedded_graphics::pixelcolor::Rgb888;
use scanline3d_sim::scene::{Algorithm, CameraSpec, LightSpec, MeshData, SceneSpec};
use scanline3d_sim::{accuracy_same_culling, metrics::Metrics};

fn mesh(v: &[[f64; 3]], f: &[[u16; 3]]) -> MeshData {
    MeshData::new(v, f.to_vec(), Rgb888::new(200, 180, 160)).unwrap()
}

/// Renders at 4 and 8 sub-pixel bits and requires zero real mismatches; returns the 4-bit metrics
/// and the fixed-point frame's statistics.
fn check(
    name: &str,
    m: MeshData,
    camera: CameraSpec,
    cull: bool,
    w: usize,
    h: usize,
) -> (Metrics, scanline3d::FrameStats) {
    let spec = SceneSpec::single(m, camera, LightSpec::default(), cull);
    let mut first = None;
    for s in [4, 8] {
        // The renderer alone (these scenes cull where asked, even where culling shows).
        let (metrics, fixed, _) =
            accuracy_same_culling(&spec, w, h, s).unwrap_or_else(|e| panic!("{name}: {e}"));
        println!(
            "{name:28} S={s}: {} mismatches ({:.3} %), real {}, {} drawn",
            metrics.id_mismatches,
            metrics.id_mismatch_percent(),
            metrics.real,
            fixed.stats.activated
        );
        assert_eq!(metrics.real, 0, "{name} S={s}: {metrics}");
        assert_eq!(metrics.depth_beyond_bound, 0, "{name} S={s}: {metrics}");
        first.get_or_insert((metrics, fixed.stats));
    }
    first.unwrap()
}

#[test]
fn vertices_at_the_model_envelope_limit() {
    // ±4096 model units is the limit (2^12); seen from 9000 units away (far plane 16000).
    let l = 4096.0;
    let (m, _) = check(
        "envelope-limit triangle",
        mesh(&[[-l, -l, 0.0], [l, -l, 0.0], [0.0, l, 0.0]], &[[0, 1, 2]]),
        CameraSpec::looking_at([0.0, 0.0, 9000.0], [0.0; 3], 60.0, 10.0, 16000.0),
        true,
        64,
        64,
    );
    assert!(m.pixels > 0);
    // Just past it: rejected when the mesh is built.
    assert!(MeshData::new(
        &[[4096.1, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        vec![[0, 1, 2]],
        Rgb888::new(0, 0, 0)
    )
    .is_err());
}

#[test]
fn triangles_far_larger_than_the_screen() {
    // A ground triangle thousands of pixels across, clipped by the guard band and near plane.
    let (_, stats) = check(
        "huge ground triangle",
        mesh(
            &[
                [-3000.0, 0.0, 3000.0],
                [3000.0, 0.0, 3000.0],
                [0.0, 0.0, -3000.0],
            ],
            &[[0, 1, 2]],
        ),
        CameraSpec::looking_at([0.0, 2.0, 0.0], [0.0, 0.0, -10.0], 70.0, 0.1, 10000.0),
        false,
        96,
        64,
    );
    assert_eq!(stats.clipped, 1);
}

#[test]
fn sub_pixel_triangles_cover_only_the_centres_they_contain() {
    // A 40 × 40 lattice of triangles about 0.3 px across: most contain no centre.
    let mut v = Vec::new();
    let mut f = Vec::new();
    for j in 0..40 {
        for i in 0..40 {
            let (x, y) = (
                -1.0 + 2.0 * i as f64 / 40.0 + 0.013 * j as f64 / 40.0,
                -1.0 + 2.0 * j as f64 / 40.0,
            );
            let k = v.len() as u16;
            v.extend([[x, y, 0.0], [x + 0.011, y, 0.0], [x, y + 0.011, 0.0]]);
            f.push([k, k + 1, k + 2]);
        }
    }
    let (m, stats) = check(
        "sub-pixel triangles",
        mesh(&v, &f),
        CameraSpec::looking_at([0.0, 0.0, 2.5], [0.0; 3], 60.0, 0.5, 10.0),
        true,
        96,
        96,
    );
    // Never a streak: far fewer covered pixels than triangles.
    assert!(stats.fragments < 400, "{stats:?}");
    assert!(m.pixels > 0);
}

#[test]
fn slivers_of_aspect_ratio_ten_thousand() {
    // 2 units long, 0.0002 wide: aspect 10^4, nearly parallel long edges.
    let f: Vec<[u16; 3]> = (0..10).map(|k| [3 * k, 3 * k + 1, 3 * k + 2]).collect();
    let mut v = Vec::new();
    for k in 0..10 {
        let y = -0.9 + 0.2 * k as f64 + 0.0137 * k as f64;
        v.extend([
            [-1.0, y, 0.0],
            [1.0, y + 0.05 * k as f64, 0.0],
            [-1.0, y + 0.0002, 0.0],
        ]);
    }
    check(
        "slivers 1:10^4",
        mesh(&v, &f),
        CameraSpec::looking_at([0.1, 0.05, 3.0], [0.0; 3], 50.0, 0.5, 10.0),
        false,
        128,
        96,
    );
}

#[test]
fn collinear_and_coincident_vertices_draw_nothing() {
    let (m, stats) = check(
        "degenerate triangles",
        mesh(
            &[
                [0.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [2.0, 2.0, 0.0],
                [0.5, 0.5, 0.0],
            ],
            &[[0, 1, 2], [0, 0, 1], [3, 3, 3]],
        ),
        CameraSpec::looking_at([0.0, 0.0, 4.0], [0.0; 3], 60.0, 0.5, 10.0),
        false,
        64,
        64,
    );
    assert_eq!((stats.fragments, m.id_mismatches), (0, 0));
}

#[test]
fn eye_inside_a_closed_mesh_and_on_a_triangle_plane() {
    let (v, f) = scanline3d_sim::meshgen::cube();
    // Inside the cube: with culling every face is a back face; without, the inside is drawn.
    let (_, culled) = check(
        "eye inside cube, culled",
        mesh(&v, &f),
        CameraSpec::looking_at([0.2, 0.1, 0.3], [0.0, 0.0, -1.0], 90.0, 0.05, 10.0),
        true,
        64,
        64,
    );
    assert_eq!(culled.fragments, 0);
    let (_, open) = check(
        "eye inside cube, no culling",
        mesh(&v, &f),
        CameraSpec::looking_at([0.2, 0.1, 0.3], [0.0, 0.0, -1.0], 90.0, 0.05, 10.0),
        false,
        64,
        64,
    );
    assert!(open.fragments as usize == 64 * 64, "{open:?}");
    // Eye exactly in the plane of a triangle: it is seen edge-on and covers nothing.
    let (_, edge_on) = check(
        "eye on triangle plane",
        mesh(
            &[[-1.0, 0.0, -1.0], [1.0, 0.0, -1.0], [0.0, 0.0, -3.0]],
            &[[0, 1, 2]],
        ),
        CameraSpec::looking_at([0.0, 0.0, 0.0], [0.0, 0.0, -2.0], 60.0, 0.1, 10.0),
        false,
        64,
        64,
    );
    assert_eq!(edge_on.fragments, 0);
}

#[test]
fn near_far_ratios_from_ten_to_a_hundred_thousand() {
    // Two parallel squares 0.2% apart in depth near the far plane: occlusion must stay correct.
    for (near, far) in [(1.0, 10.0), (0.1, 100.0), (0.01, 1000.0)] {
        let d = far * 0.8;
        let sq = |z: f64, k: u16| -> (Vec<[f64; 3]>, Vec<[u16; 3]>) {
            let s = d * 0.3;
            (
                vec![[-s, -s, z], [s, -s, z], [s, s, z], [-s, s, z]],
                vec![[k, k + 1, k + 2], [k, k + 2, k + 3]],
            )
        };
        let (mut v, mut f) = sq(-d, 0);
        let (v2, f2) = sq(-d * 0.998, 4);
        v.extend(v2.iter().map(|p| [p[0] * 0.5, p[1] * 0.5, p[2]]));
        f.extend(f2);
        let name = format!("far/near {}", far / near);
        let (m, _) = check(
            &name,
            mesh(&v, &f),
            CameraSpec::looking_at([0.0; 3], [0.0, 0.0, -1.0], 60.0, near, far),
            true,
            64,
            64,
        );
        assert!(m.pixels > 0);
    }
    // 10^5: the nearer square must still win in the middle.
    let (near, far) = (0.01, 1000.0);
    let d = 900.0;
    let v = [
        [-300.0, -300.0, -d],
        [300.0, -300.0, -d],
        [300.0, 300.0, -d],
        [-300.0, 300.0, -d],
        [-100.0, -100.0, -d * 0.998],
        [100.0, -100.0, -d * 0.998],
        [100.0, 100.0, -d * 0.998],
        [-100.0, 100.0, -d * 0.998],
    ];
    let spec = SceneSpec::single(
        mesh(&v, &[[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]]),
        CameraSpec::looking_at([0.0; 3], [0.0, 0.0, -1.0], 60.0, near, far),
        LightSpec::default(),
        true,
    );
    let r = spec.render_fixed(64, 64, 4).unwrap();
    let centre = r.image.ids[32 * 64 + 32];
    assert!(
        centre == 2 || centre == 3,
        "near square must occlude the far one at far/near 1e5, got {centre}"
    );
}

#[test]
fn extreme_fields_of_view_and_screen_shapes() {
    let (v, f) = scanline3d_sim::meshgen::icosphere(2);
    let sphere = mesh(&v, &f);
    check(
        "fov 1 degree",
        sphere.clone(),
        CameraSpec::looking_at([0.0, 0.0, 100.0], [0.0; 3], 1.0, 50.0, 200.0),
        true,
        64,
        64,
    );
    check(
        "fov 170 degrees",
        sphere.clone(),
        CameraSpec::looking_at([0.0, 0.0, 1.5], [0.0; 3], 170.0, 0.1, 10.0),
        true,
        64,
        64,
    );
    // A wide triangle through the centre of view, so every screen shape shows part of it.
    let wide = mesh(
        &[[-60.0, -1.0, 0.0], [60.0, -1.0, 0.0], [0.0, 1.5, 0.0]],
        &[[0, 1, 2]],
    );
    let c = CameraSpec::looking_at([0.5, 0.3, 3.0], [0.0; 3], 50.0, 0.5, 10.0);
    for (w, h) in [(1, 1), (1, 64), (64, 1), (2048, 4)] {
        let (m, stats) = check(&format!("screen {w}x{h}"), wide.clone(), c, false, w, h);
        assert_eq!(m.pixels, w * h);
        assert!(stats.fragments > 0, "screen {w}x{h}: nothing drawn");
    }
}

mod random {
    use super::*;
    use proptest::prelude::*;

    fn point(r: f64) -> impl Strategy<Value = [f64; 3]> {
        [-r..r, -r..r, -r..r]
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

        /// Random triangle soups seen by random cameras, inside the envelope: no panic,
        /// consistent statistics, and every mismatch with the reference explained.
        #[test]
        fn random_scenes_match_the_reference(
            tris in proptest::collection::vec((point(3.0), point(3.0), point(3.0)), 1..40),
            eye in point(8.0),
            target in point(1.0),
            fovy in 20.0f64..120.0,
            near in 0.05f64..0.5,
            cull in any::<bool>(),
        ) {
            let v: Vec<[f64; 3]> = tris.iter().flat_map(|(a, b, c)| [*a, *b, *c]).collect();
            let f: Vec<[u16; 3]> = (0..tris.len() as u16).map(|k| [3 * k, 3 * k + 1, 3 * k + 2]).collect();
            let camera = CameraSpec { eye, target, up: [0.0, 1.0, 0.0], fovy, near, far: 40.0 };
            // Degenerate cameras are rejected with an error (tested elsewhere); skip them here.
            prop_assume!(camera.fixed().is_ok());
            let spec = SceneSpec::single(mesh(&v, &f), camera, LightSpec::default(), cull);
            let (w, h) = (48, 36);
            // The renderer alone: a reference that culls as it does (culling a random soup is
            // a choice the tools no longer make by default).
            let (m, fixed, _) = accuracy_same_culling(&spec, w, h, 4).unwrap();
            let s = fixed.stats;
            prop_assert_eq!(s.rows as usize, h);
            prop_assert_eq!(s.triangles_in as usize, f.len());
            prop_assert_eq!((s.culled + s.rejected + s.bucketed) as usize, f.len());
            prop_assert!(s.pixels_written <= s.fragments && s.is_complete());
            prop_assert_eq!(m.real, 0, "{}", m);
        }
    }
}

/// Newell–Newell–Sancha on a random soup (case 11 of `cargo run --release -p scanline3d-sim
/// --example hsr_random -- 120 1`, reduced to the seven triangles that still failed): large
/// triangles cut by the near plane and by each other's planes into thin pieces. When the
/// split tree cut along the line through a thin piece's two rounded cut points, a few
/// sub-pixels apart, the line turned far enough to send pixel centres of that piece to the
/// wrong side: 3 real mismatches at 8 sub-pixel bits. It now cuts where the planes cross.
#[test]
fn newell_cuts_thin_pieces_where_the_planes_cross() {
    let v = [
        [-10.424058620915133, 2.59274257736827, 13.023100815030325],
        [29.158966440177693, -28.978383598169348, -22.495354107460987],
        [-13.19382525113334, -28.368037138352307, -25.90271042285572],
        [-1.2225550231307274, 16.465211367701215, 8.652132602640314],
        [-13.189278526949863, 17.8584434796741, 20.65808089271269],
        [-22.201558419228437, -12.33020282285915, -19.351351487427518],
        [-22.015545448089334, -12.079037558423561, -3.382272884829966],
        [13.335624745425832, -20.89045730447937, 5.966330939243647],
        [24.134774594127904, 26.221279522129947, 10.231608133418476],
        [-21.910316376836054, -8.136634162898591, 21.59406386776945],
        [-3.5836579245914777, -8.892214401544017, 8.727513795365041],
        [6.9091815857817025, -11.42449134283887, -20.549295478362033],
        [
            -12.893016180244377,
            -11.278857254278595,
            -25.528284937346697,
        ],
        [-6.565538549702836, -0.17752272288822724, 19.143837350654074],
        [-4.440838727611592, 27.369370740986433, 1.7481448635875942],
        [2.5319111669583947, 26.10670776816817, -22.75846600698595],
        [-24.86894126045236, -20.974610955811084, 18.683553883496266],
        [-6.983785126384863, 1.93145407877115, -10.059021780740174],
        [5.886139279448663, 13.224818397778229, 27.10934098097139],
        [-29.323996380651668, 21.667871706566842, -5.193048784537478],
        [-6.57893389059463, -3.715403634463165, -17.817576060014964],
    ];
    let f: Vec<[u16; 3]> = (0..7).map(|k| [3 * k, 3 * k + 1, 3 * k + 2]).collect();
    let camera = CameraSpec {
        eye: [0.9612033181575121, 1.5897476647091366, 2.886062013878476],
        target: [0.3538789750482787, -0.5308222188808918, 0.6150340725457439],
        up: [0.0, 1.0, 0.0],
        fovy: 66.43939892802055,
        near: 0.31799317524250637,
        far: 40.0,
    };
    let spec = SceneSpec::single(mesh(&v, &f), camera, LightSpec::default(), false);
    for s in [4, 8] {
        let (m, fixed, _) =
            scanline3d_sim::accuracy_with(&spec, 48, 36, s, Algorithm::Newell).unwrap();
        println!("S={s}: {m}");
        assert!(m.pixels > 500, "S={s}: the soup fills the frame: {m}");
        assert!(fixed.stats.fragments > 0);
        assert_eq!((m.real, m.depth_beyond_bound), (0, 0), "S={s}: {m}");
    }
}

/// `algorithm` against the f64 reference (culling as the scene does) on the first `cases`
/// random soups of `cargo run --release -p scanline3d-sim --example hsr_random -- CASES
/// SEED`, at 48×36 and 4 and 8 sub-pixel bits: no real mismatch, no depth beyond the bound.
fn matches_the_reference_on_random_soups(seed: u64, cases: usize, algorithm: Algorithm) {
    use scanline3d_sim::draw::Soup;
    let mut d = Soup::draws(seed);
    let mut judged = 0;
    for k in 0..cases {
        let soup = Soup::draw(&mut d, k);
        let faces = (0..soup.vertices.len() as u16 / 3)
            .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
            .collect();
        let m = MeshData::new(&soup.vertices, faces, Rgb888::new(200, 180, 160)).unwrap();
        let spec = SceneSpec::single(m, soup.camera, LightSpec::default(), soup.cull);
        if soup.camera.fixed().is_err() || spec.reference().is_err() {
            continue;
        }
        for s in [4, 8] {
            let (m, _, _) = scanline3d_sim::accuracy_same_culling_with(&spec, 48, 36, s, algorithm)
                .unwrap_or_else(|e| panic!("case {k} S={s}: {e}"));
            assert_eq!(
                (m.real, m.depth_beyond_bound),
                (0, 0),
                "case {k} S={s}: {m}"
            );
            judged += 1;
        }
    }
    assert!(judged >= 3 * cases / 2, "{judged} frames judged");
}

/// Newell–Newell–Sancha on the first 40 soups of seed 1. It fails at case 9 (8 bits) when
/// split trees cut along the rounded cut points, and at case 11 (4 bits) when the plane tests
/// use the planes through the parts' rounded vertices.
#[test]
fn newell_matches_the_reference_on_random_soups() {
    matches_the_reference_on_random_soups(1, 40, Algorithm::Newell);
}

/// BSP order on the first 50 soups of seed 2. It fails at cases 9 and 49 (4 bits) when back
/// faces are culled by the pieces' orientation on screen: a thin piece a split left turns over
/// when its vertices are rounded and shows a triangle that faces away, over what it hides.
#[test]
fn bsp_matches_the_reference_on_random_soups() {
    matches_the_reference_on_random_soups(2, 50, Algorithm::Bsp);
}
