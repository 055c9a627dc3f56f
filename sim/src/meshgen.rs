//! Procedural meshes (f64 positions, counter-clockwise triangles seen from outside).
//!
//! Shared by the library's `build.rs` (which turns them into the demo's static arrays), the
//! corpus and the tests, so each shape is defined once. Plain std code with no dependencies,
//! because `build.rs` includes this file directly.

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

/// An `n × n` grid of quads over [−half, half]² in the x-z plane, facing +y, with heights
/// `height(x, z)`; two triangles per quad, row by row.
pub fn grid(n: usize, half: f64, height: impl Fn(f64, f64) -> f64) -> Shape {
    let mut v = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let s = |k: usize| -half + 2.0 * half * k as f64 / n as f64;
            v.push([s(i), height(s(i), s(j)), s(j)]);
        }
    }
    let id = |i: usize, j: usize| (j * (n + 1) + i) as u16;
    let mut f = Vec::new();
    for j in 0..n {
        for i in 0..n {
            f.push([id(i, j), id(i, j + 1), id(i + 1, j + 1)]);
            f.push([id(i, j), id(i + 1, j + 1), id(i + 1, j)]);
        }
    }
    (v, f)
}
