//! Procedural meshes (f64 positions, counter-clockwise triangles seen from outside).
//!
//! Shared by the demo crate's `build.rs` (which turns them into the demo's static arrays), the
//! corpus and the tests, so each shape is defined once. Plain std code with no dependencies, so
//! a build script can use it.

use std::collections::HashMap;

/// Positions and triangles.
pub type Shape = (Vec<[f64; 3]>, Vec<[u16; 3]>);

fn normalize(p: [f64; 3]) -> [f64; 3] {
    let l = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
    p.map(|c| c / l)
}

/// Unit icosphere: the icosahedron's 20 faces, each split in four `subdivisions` times
/// (20 · 4^n triangles; n = 3 gives 1280 triangles and 642 vertices).
pub fn icosphere(subdivisions: u32) -> Shape {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut v: Vec<[f64; 3]> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .into_iter()
    .map(normalize)
    .collect();
    let mut f: Vec<[u16; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut cache: HashMap<(u16, u16), u16> = HashMap::new();
        let mut next = Vec::with_capacity(f.len() * 4);
        for [a, b, c] in f {
            let mut mid = |x: u16, y: u16| {
                *cache.entry((x.min(y), x.max(y))).or_insert_with(|| {
                    let (p, q) = (v[x as usize], v[y as usize]);
                    v.push(normalize([0, 1, 2].map(|k| (p[k] + q[k]) / 2.0)));
                    (v.len() - 1) as u16
                })
            };
            let (ab, bc, ca) = (mid(a, b), mid(b, c), mid(c, a));
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        f = next;
    }
    (v, f)
}

/// Cube of half-size 1, two triangles per face, in the order +z, −z, +x, −x, +y, −y.
pub fn cube() -> Shape {
    let v: Vec<[f64; 3]> = (0..8)
        .map(|i: usize| {
            let (x, y) = ([-1.0, 1.0, 1.0, -1.0][i % 4], [-1.0, -1.0, 1.0, 1.0][i % 4]);
            [x, y, if i < 4 { -1.0 } else { 1.0 }]
        })
        .collect();
    let f = vec![
        [4, 5, 6],
        [4, 6, 7],
        [1, 0, 3],
        [1, 3, 2],
        [5, 1, 2],
        [5, 2, 6],
        [0, 4, 7],
        [0, 7, 3],
        [7, 6, 2],
        [7, 2, 3],
        [0, 1, 5],
        [0, 5, 4],
    ];
    (v, f)
}

/// An `n[0] × n[1]` grid of quads over `[−half[0], half[0]] × [−half[1], half[1]]` in the x-z
/// plane, facing +y, with heights `height(x, z)`; two triangles per quad, row by row.
pub fn grid(n: [usize; 2], half: [f64; 2], height: impl Fn(f64, f64) -> f64) -> Shape {
    let s = |k: usize, axis: usize| -half[axis] + 2.0 * half[axis] * k as f64 / n[axis] as f64;
    let mut v = Vec::new();
    for j in 0..=n[1] {
        for i in 0..=n[0] {
            v.push([s(i, 0), height(s(i, 0), s(j, 1)), s(j, 1)]);
        }
    }
    let id = |i: usize, j: usize| (j * (n[0] + 1) + i) as u16;
    let mut f = Vec::new();
    for j in 0..n[1] {
        for i in 0..n[0] {
            f.push([id(i, j), id(i, j + 1), id(i + 1, j + 1)]);
            f.push([id(i, j), id(i + 1, j + 1), id(i + 1, j)]);
        }
    }
    (v, f)
}

/// Torus around the z axis: `n` segments around the ring of radius `major`, `m` around the tube
/// of radius `minor`; `2·n·m` triangles on `n·m` vertices.
pub fn torus(n: usize, m: usize, major: f64, minor: f64) -> Shape {
    use std::f64::consts::TAU;
    let mut v = Vec::with_capacity(n * m);
    for i in 0..n {
        let u = TAU * i as f64 / n as f64;
        for j in 0..m {
            let w = TAU * j as f64 / m as f64;
            let r = major + minor * w.cos();
            v.push([r * u.cos(), r * u.sin(), minor * w.sin()]);
        }
    }
    let id = |i: usize, j: usize| ((i % n) * m + j % m) as u16;
    let mut f = Vec::with_capacity(2 * n * m);
    for i in 0..n {
        for j in 0..m {
            // Stepping i then j turns counter-clockwise seen from outside the tube.
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            f.extend([[a, b, c], [a, c, d]]);
        }
    }
    (v, f)
}

/// Rotates `shape` by `angle` radians about the x axis, then about the y axis by `yaw`, then
/// moves it by `offset` (a proper rotation, so faces keep their orientation).
fn place(shape: Shape, angle: f64, yaw: f64, offset: [f64; 3]) -> Shape {
    let (v, f) = shape;
    let (sa, ca, sy, cy) = (angle.sin(), angle.cos(), yaw.sin(), yaw.cos());
    let v = v
        .into_iter()
        .map(|[x, y, z]| {
            let (y, z) = (ca * y - sa * z, sa * y + ca * z);
            let (x, z) = (cy * x + sy * z, -sy * x + cy * z);
            [x + offset[0], y + offset[1], z + offset[2]]
        })
        .collect();
    (v, f)
}

/// Polygon counts of the hidden-surface test scenes, as in the lecture's table (Sutherland,
/// Sproull and Schumacker 1974): the same scene, tessellated ever finer.
pub const HSR_POLYGONS: [usize; 3] = [100, 2500, 60_000];

/// Tessellation per level: torus (ring segments, tube segments) and ground (cells in x, z),
/// chosen so that 3 tori + ground have exactly [`HSR_POLYGONS`] triangles, half or more of them
/// on the tori.
const HSR_TESSELLATION: [([usize; 2], [usize; 2]); 3] = [
    ([4, 3], [2, 7]),
    ([20, 10], [25, 26]),
    ([100, 50], [120, 125]),
];

/// An object of a hidden-surface test scene: world-space shape and RGB colour.
pub type HsrObject = (Shape, [u8; 3]);

/// The hidden-surface test scene at `level` (0, 1, 2: [`HSR_POLYGONS`] triangles): a chain of
/// three tori (lying, standing, lying) receding from the camera over a ground plane that the
/// standing one sinks into. Surfaces hide each other, pass through each other's holes and
/// intersect the ground.
pub fn hsr_scene(level: usize) -> Vec<HsrObject> {
    let ([n, m], cells) = HSR_TESSELLATION[level];
    let (major, minor, yaw) = (1.0, 0.28, 0.75f64);
    // Each ring passes through its neighbours' centres, one radius apart along the chain.
    let step = [major * yaw.cos(), 0.0, -major * yaw.sin()];
    let centre = |k: f64| [-1.0 + k * step[0], -0.35, 0.5 + k * step[2]];
    let lying = -std::f64::consts::FRAC_PI_2;
    let ring = |angle, k| place(torus(n, m, major, minor), angle, yaw, centre(k));
    vec![
        (ring(lying, 0.0), [230, 150, 60]),
        (ring(0.0, 1.0), [70, 170, 210]),
        (ring(lying, 2.0), [200, 90, 160]),
        (grid(cells, [4.0, 4.0], |_, _| -1.5), [170, 170, 160]),
    ]
}

/// I16F16 bits of `v`, rounded to nearest (how generated firmware data and host scenes both
/// convert, so they hold identical vertices).
pub fn fixed_bits(v: f64) -> i32 {
    (v * 65536.0).round() as i32
}

/// A small deterministic random generator (SplitMix64), so generated scenes are the same on
/// every machine.
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    /// A generator from `seed`.
    pub fn new(seed: u64) -> Rng {
        Rng(seed)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[lo, hi)`.
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// `n` random triangles in the cube `[−half, half]³`, each a random triangle of edge about
/// `size` around a random centre, randomly wound: a soup whose triangles pass through each
/// other everywhere.
pub fn soup(n: usize, half: f64, size: f64, seed: u64) -> Shape {
    let mut rng = Rng::new(seed);
    let mut v = Vec::with_capacity(3 * n);
    let mut f = Vec::with_capacity(n);
    for k in 0..n {
        let c = [0; 3].map(|_| rng.range(-half, half));
        for _ in 0..3 {
            v.push([0, 1, 2].map(|i| c[i] + rng.range(-size, size)));
        }
        let b = 3 * k as u16;
        f.push([b, b + 1, b + 2]);
    }
    (v, f)
}

/// `shape` with the winding of each triangle reversed with probability one half.
pub fn random_winding((v, f): Shape, seed: u64) -> Shape {
    let mut rng = Rng::new(seed);
    let f = f
        .into_iter()
        .map(|[a, b, c]| {
            if rng.next_u64() & 1 == 1 {
                [a, c, b]
            } else {
                [a, b, c]
            }
        })
        .collect();
    (v, f)
}

/// Boxes on a `blocks × blocks` grid of city blocks covering `[0, extent]²` in x and z (y up),
/// each of random height between `extent / 400` and `extent / 40`: a closed mesh per box, 12
/// triangles each, with vertex coordinates up to `extent`. Box `k` of the grid is boxes
/// `12k..12k+12`.
pub fn city(blocks: usize, extent: f64, seed: u64) -> Vec<Shape> {
    let mut rng = Rng::new(seed);
    let cell = extent / blocks as f64;
    let mut out = Vec::with_capacity(blocks * blocks);
    for j in 0..blocks {
        for i in 0..blocks {
            let street = cell * rng.range(0.15, 0.3);
            let height = rng.range(extent / 400.0, extent / 40.0);
            let (v, f) = cube();
            let (x0, z0) = (i as f64 * cell + street, j as f64 * cell + street);
            let (sx, sz) = ((cell - 2.0 * street) / 2.0, (cell - 2.0 * street) / 2.0);
            let v = v
                .into_iter()
                .map(|[x, y, z]| {
                    [
                        x0 + (x + 1.0) * sx,
                        (y + 1.0) * height / 2.0,
                        z0 + (z + 1.0) * sz,
                    ]
                })
                .collect();
            out.push((v, f));
        }
    }
    out
}

/// A scanned-looking closed surface: an icosphere of `20 · 4^n` triangles with every vertex
/// moved along its normal by smooth bumps plus `noise` of random jitter.
pub fn scanned(subdivisions: u32, noise: f64, seed: u64) -> Shape {
    let (v, f) = icosphere(subdivisions);
    let mut rng = Rng::new(seed);
    let v = v
        .into_iter()
        .map(|p| {
            let bumps = 0.15 * (3.0 * p[0]).sin() * (2.0 * p[1]).cos() + 0.1 * (5.0 * p[2]).sin();
            let r = 1.0 + bumps + rng.range(-noise, noise);
            p.map(|c| c * r)
        })
        .collect();
    (v, f)
}

/// Concatenates shapes into one (indices renumbered, order kept).
pub fn merge(shapes: impl IntoIterator<Item = Shape>) -> Shape {
    let mut v: Vec<[f64; 3]> = Vec::new();
    let mut f = Vec::new();
    for (sv, sf) in shapes {
        let base = v.len() as u16;
        v.extend(sv);
        f.extend(sf.into_iter().map(|t| t.map(|i| i + base)));
    }
    (v, f)
}
