//! Marching tetrahedra (`scanline3d::metaball::Polygonizer`): on 24 random scenes the mesh is
//! closed and consistently wound (every edge in exactly two triangles, once each way, so every
//! grid-edge crossing is shared by all the cells around its edge), faces outward, and its
//! vertices lie on the surface.

use embedded_graphics::pixelcolor::Rgb888;
use scanline3d::metaball::{Ball, Coord, Metaballs, PolyMesh, Polygonizer};
use std::collections::HashMap;

type Mesh = PolyMesh<16384, 32768>;

struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
}

fn random_scene(rng: &mut Rng) -> (Vec<Ball>, f32) {
    let n = 1 + (rng.next() * 6.0) as usize;
    let balls = (0..n)
        .map(|i| {
            let centre = [0; 3].map(|_| rng.range(-1.5, 1.5) as f32);
            let radius = rng.range(0.6, 1.6) as f32;
            // One ball in five subtracts (never the first, so something is drawn).
            let density = if i > 0 && rng.next() < 0.2 {
                -rng.range(0.5, 1.5)
            } else {
                rng.range(0.5, 1.5)
            } as f32;
            Ball::new(centre, radius, density, Rgb888::new(200, 100, 50))
        })
        .collect();
    (balls, rng.range(0.2, 0.6) as f32)
}

/// Every directed edge of the mesh once, and its reverse once.
fn assert_closed(mesh: &Mesh, what: &str) {
    let mut directed: HashMap<(u16, u16), u32> = HashMap::new();
    for t in mesh.triangles() {
        assert!(
            t[0] != t[1] && t[1] != t[2] && t[0] != t[2],
            "{what}: {t:?}"
        );
        for k in 0..3 {
            *directed.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
        }
    }
    for (&(a, b), &n) in &directed {
        assert_eq!(n, 1, "{what}: edge {a}→{b} in {n} triangles the same way");
        assert_eq!(
            directed.get(&(b, a)),
            Some(&1),
            "{what}: edge {a}–{b} has no opposite"
        );
    }
    // Every crossing is used (each lies on edges of at least three triangles).
    let mut used = vec![0u32; mesh.vertices().len()];
    for t in mesh.triangles() {
        for &v in t {
            used[v as usize] += 1;
        }
    }
    assert!(
        used.iter().all(|&n| n >= 3),
        "{what}: a vertex in < 3 triangles"
    );
}

fn field(s: f64) -> f64 {
    if s >= 1.0 {
        0.0
    } else {
        1.0 - 22.0 / 9.0 * s + 17.0 / 9.0 * s * s - 4.0 / 9.0 * s * s * s
    }
}

fn g(balls: &[Ball], threshold: f64, p: [f64; 3]) -> f64 {
    balls
        .iter()
        .map(|b| {
            let c = b.centre.map(|c| c.to_num::<f64>());
            let r = b.radius.to_num::<f64>();
            let d2: f64 = (0..3).map(|i| (p[i] - c[i]).powi(2)).sum();
            b.density.to_num::<f64>() * field(d2 / (r * r))
        })
        .sum::<f64>()
        - threshold
}

/// The grid step of `grid` samples per axis over the positive balls' influence spheres
/// (padded by 1/64, as the polygonizer does).
fn grid_step(balls: &[Ball], grid: usize) -> [f64; 3] {
    [0, 1, 2].map(|i| {
        let positive = balls.iter().filter(|b| b.density > 0);
        let (lo, hi) = positive.fold((f64::MAX, f64::MIN), |(lo, hi), b| {
            let (c, r) = (b.centre[i].to_num::<f64>(), b.radius.to_num::<f64>());
            (lo.min(c - r), hi.max(c + r))
        });
        (hi - lo + 2.0 / 64.0) / (grid - 1) as f64
    })
}

#[test]
fn random_scenes_give_closed_consistently_wound_meshes() {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let mut mesh: Box<Mesh> = Box::default();
    let mut small: Box<Polygonizer<9, 8>> = Box::default();
    let mut large: Box<Polygonizer<25, 8>> = Box::default();
    let mut triangles = 0;
    for scene_index in 0..24 {
        let (balls, threshold) = random_scene(&mut rng);
        let scene = Metaballs::new(&balls, Coord::from_num(threshold)).unwrap();
        for grid in [9, 25] {
            let stats = if grid == 9 {
                small.polygonize(&scene, &mut mesh)
            } else {
                large.polygonize(&scene, &mut mesh)
            }
            .unwrap();
            let what = format!("scene {scene_index}, grid {grid}");
            assert_eq!(stats.vertices as usize, mesh.vertices().len(), "{what}");
            assert_eq!(stats.triangles as usize, mesh.triangles().len(), "{what}");
            assert_closed(&mesh, &what);
            assert!(mesh.mesh().is_ok(), "{what}");
            triangles += mesh.triangles().len();
            // Each vertex lies on a grid edge whose ends are on opposite sides: along one of
            // the seven edge directions, g changes sign within one edge length of it.
            let step = grid_step(&balls, grid);
            for v in mesh.vertices() {
                let p = v.map(|c| c.to_num::<f64>());
                let changes = (1..8).any(|d: usize| {
                    let e = [0, 1, 2].map(|i| if d >> i & 1 == 1 { step[i] } else { 0.0 });
                    let along = |u: f64| {
                        g(
                            &balls,
                            f64::from(threshold),
                            [0, 1, 2].map(|i| p[i] + u * e[i]),
                        )
                    };
                    let values: Vec<f64> = (-16..=16).map(|k| along(k as f64 / 16.0)).collect();
                    values.iter().any(|&x| x > 0.0) && values.iter().any(|&x| x <= 0.0)
                });
                assert!(changes, "{what}: {p:?}");
            }
        }
    }
    assert!(triangles > 10_000, "{triangles}");
}

#[test]
fn single_ball_is_a_sphere_facing_out() {
    // q = 1, T = 0.5: the surface is the sphere r = R/2.
    let balls = [Ball::new(
        [0.25, -0.5, 0.125],
        2.0,
        1.0,
        Rgb888::new(9, 9, 9),
    )];
    let scene = Metaballs::new(&balls, Coord::from_num(0.5)).unwrap();
    let mut mesh: Box<Mesh> = Box::default();
    let mut grid: Box<Polygonizer<33, 1>> = Box::default();
    grid.polygonize(&scene, &mut mesh).unwrap();
    assert_closed(&mesh, "sphere");
    let centre = [0.25, -0.5, 0.125];
    let p = |i: u16| mesh.vertices()[i as usize].map(|c| c.to_num::<f64>() - 0.0);
    // Grid step 4.03/32: linear interpolation keeps vertices within a few % of the radius.
    for v in mesh.vertices() {
        let r = (0..3)
            .map(|i| (v[i].to_num::<f64>() - centre[i]).powi(2))
            .sum::<f64>()
            .sqrt();
        assert!((r - 1.0).abs() < 0.02, "{r}");
    }
    // Outward winding: the signed volume is positive and close to the sphere's.
    let mut volume = 0.0;
    for t in mesh.triangles() {
        let [a, b, c] = t.map(|i| {
            let v = p(i);
            [v[0] - centre[0], v[1] - centre[1], v[2] - centre[2]]
        });
        volume += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
            + a[2] * (b[0] * c[1] - b[1] * c[0]))
            / 6.0;
    }
    let sphere = 4.0 / 3.0 * std::f64::consts::PI;
    assert!((volume / sphere - 1.0).abs() < 0.03, "{volume}");
    // Normals point outward: along the vertex's offset from the centre.
    for (v, n) in mesh
        .vertices()
        .iter()
        .zip(mesh.mesh().unwrap().normals().unwrap())
    {
        let dot: f64 = (0..3)
            .map(|i| (v[i].to_num::<f64>() - centre[i]) * n[i].to_num::<f64>())
            .sum();
        assert!(dot > 0.0);
    }
}
