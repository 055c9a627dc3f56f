//! Shared test helpers: scene builders, render-to-vectors, and a small independent f64 ray caster
//! (it shares only the camera convention with the renderer, no arithmetic).
#![allow(dead_code)]

use embedded_graphics::pixelcolor::Rgb888;
use fixed::types::I16F16;
use scanline3d::scene::{Camera, Instance, Light, Mesh, MeshColors, Scene, Transform, Vertex};
use scanline3d::sink::{FnSink, Row, TriangleId};
use scanline3d::{Flat, FrameStats, RenderOptions, Workspace};

pub fn fx(v: f64) -> I16F16 {
    I16F16::from_num(v)
}

pub fn vert(p: [f64; 3]) -> Vertex {
    p.map(fx)
}

/// Owned mesh data, borrowed into a `Mesh` with `mesh()`.
pub struct MeshData {
    pub vertices: Vec<Vertex>,
    pub triangles: Vec<[u16; 3]>,
    pub colors: Vec<Rgb888>,
}

impl MeshData {
    pub fn from_f64(vertices: &[[f64; 3]], triangles: &[[u16; 3]]) -> Self {
        let colors = (0..triangles.len())
            .map(|i| Rgb888::new((40 + 37 * i % 200) as u8, (90 + 53 * i % 160) as u8, 200))
            .collect();
        MeshData {
            vertices: vertices.iter().map(|&p| vert(p)).collect(),
            triangles: triangles.to_vec(),
            colors,
        }
    }
    pub fn mesh(&self) -> Mesh<'_> {
        Mesh::new(
            &self.vertices,
            &self.triangles,
            MeshColors::PerFace(&self.colors),
            None,
        )
        .unwrap()
    }
    /// World-space f64 vertices of triangle `t` (the snapped I16F16 model coordinates).
    pub fn world_triangle(&self, t: usize) -> [[f64; 3]; 3] {
        self.triangles[t].map(|i| self.vertices[i as usize].map(|c| c.to_num::<f64>()))
    }
}

/// Icosphere of radius `r`: 20 · 4^subdivisions triangles, counter-clockwise seen from outside.
pub fn icosphere(subdivisions: u32, r: f64) -> MeshData {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut v: Vec<[f64; 3]> = vec![
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
    ];
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
    let norm = |p: [f64; 3]| {
        let l = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        p.map(|c| c / l)
    };
    v = v.into_iter().map(norm).collect();
    for _ in 0..subdivisions {
        let mut cache = std::collections::HashMap::new();
        let mut mid = |a: u16, b: u16, v: &mut Vec<[f64; 3]>| -> u16 {
            let key = (a.min(b), a.max(b));
            *cache.entry(key).or_insert_with(|| {
                let (p, q) = (v[a as usize], v[b as usize]);
                v.push(norm([
                    (p[0] + q[0]) / 2.0,
                    (p[1] + q[1]) / 2.0,
                    (p[2] + q[2]) / 2.0,
                ]));
                (v.len() - 1) as u16
            })
        };
        let mut nf = Vec::new();
        for [a, b, c] in f {
            let (ab, bc, ca) = (mid(a, b, &mut v), mid(b, c, &mut v), mid(c, a, &mut v));
            nf.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        f = nf;
    }
    let v: Vec<[f64; 3]> = v.into_iter().map(|p| p.map(|c| c * r)).collect();
    MeshData::from_f64(&v, &f)
}

#[derive(Clone, Copy, Debug)]
pub struct CameraSpec {
    pub eye: [f64; 3],
    pub target: [f64; 3],
    pub up: [f64; 3],
    pub fovy: f64,
    pub near: f64,
    pub far: f64,
}

impl CameraSpec {
    pub fn camera(&self) -> Camera {
        let f = |v: [f64; 3]| v.map(|c| c as f32);
        Camera::look_at(f(self.eye), f(self.target), f(self.up))
            .unwrap()
            .perspective(self.fovy as f32, self.near as f32, self.far as f32)
            .unwrap()
    }
}

pub fn light() -> Light {
    Light::new([0.4, 0.7, 1.0], 0.25, 0.75).unwrap()
}

/// Renders triangle ids into a `W × H` vector with sub-pixel bits `S`, checking row order.
pub fn render_ids<const W: usize, const H: usize, const S: u32>(
    instances: &[Instance<'_>],
    cam: &CameraSpec,
    cull: bool,
) -> (Vec<i32>, FrameStats) {
    let scene = Scene {
        instances,
        camera: cam.camera(),
        light: light(),
    };
    let mut ws: Box<Workspace<TriangleId, Flat, W, H, 4096, 512>> =
        Box::new(Workspace::new(TriangleId::NONE));
    let mut ids = vec![-1i32; W * H];
    let mut next_row = 0u16;
    let mut sink = FnSink(|row: Row<'_, TriangleId>| -> Result<(), ()> {
        assert_eq!(row.y, next_row, "rows must arrive once each, top to bottom");
        next_row += 1;
        for (x, id) in row.pixels.iter().enumerate() {
            ids[row.y as usize * W + x] = id.0;
        }
        Ok(())
    });
    let options = RenderOptions::default()
        .with_back_face_culling(cull)
        .with_sub_pixel_bits::<S>();
    let stats = ws.render(&scene, &options, &mut sink).unwrap();
    assert_eq!(stats.rows as usize, H);
    (ids, stats)
}

/// The identity-placed instance of a mesh.
pub fn instance<'a>(mesh: &'a Mesh<'a>) -> Instance<'a> {
    Instance {
        mesh,
        transform: Transform::IDENTITY,
    }
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn normalize(a: [f64; 3]) -> [f64; 3] {
    let l = dot(a, a).sqrt();
    a.map(|c| c / l)
}

/// A ray-cast hit: triangle index, eye depth, and the distance in pixels from the pixel centre
/// to the nearest edge of the hit triangle's projection (for edge-ambiguity classification).
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    pub id: i32,
    pub depth: f64,
}

/// Ray-casts world triangles through pixel centres (f64, Möller–Trumbore), culling back faces
/// if asked and honouring the near and far planes (measured along the view axis).
pub fn raycast(
    tris: &[[[f64; 3]; 3]],
    cam: &CameraSpec,
    w: usize,
    h: usize,
    cull: bool,
) -> Vec<Option<Hit>> {
    (0..w * h)
        .map(|i| {
            cast(
                tris,
                cam,
                w,
                h,
                (i % w) as f64 + 0.5,
                (i / w) as f64 + 0.5,
                cull,
            )
        })
        .collect()
}

/// Ray-casts through screen position `(x, y)` in pixels.
pub fn cast(
    tris: &[[[f64; 3]; 3]],
    cam: &CameraSpec,
    w: usize,
    h: usize,
    x: f64,
    y: f64,
    cull: bool,
) -> Option<Hit> {
    let forward = normalize(sub(cam.target, cam.eye));
    let side = normalize(cross(forward, cam.up));
    let up = cross(side, forward);
    let tan = (cam.fovy.to_radians() / 2.0).tan();
    let aspect = w as f64 / h as f64;
    let sx = (x / w as f64 * 2.0 - 1.0) * tan * aspect;
    let sy = (1.0 - y / h as f64 * 2.0) * tan;
    let dir = [0, 1, 2].map(|k| forward[k] + sx * side[k] + sy * up[k]);
    let mut best: Option<Hit> = None;
    for (id, t) in tris.iter().enumerate() {
        let e1 = sub(t[1], t[0]);
        let e2 = sub(t[2], t[0]);
        let n = cross(e1, e2);
        if cull && dot(n, sub(cam.eye, t[0])) <= 0.0 {
            continue;
        }
        let p = cross(dir, e2);
        let det = dot(e1, p);
        if det.abs() < 1e-300 {
            continue;
        }
        let s = sub(cam.eye, t[0]);
        let u = dot(s, p) / det;
        let q = cross(s, e1);
        let v = dot(dir, q) / det;
        if u < 0.0 || v < 0.0 || u + v > 1.0 {
            continue;
        }
        // dir has unit component along the view axis, so the ray parameter is the eye depth.
        let depth = dot(e2, q) / det;
        if depth < cam.near || depth > cam.far {
            continue;
        }
        if best.is_none_or(|b| depth < b.depth) {
            best = Some(Hit {
                id: id as i32,
                depth,
            });
        }
    }
    best
}

/// Distance in pixels from the centre of pixel `(c, r)` to the projection of segment `a`–`b`
/// (world points in front of the camera), for classifying edge-ambiguous pixels.
pub fn project(cam: &CameraSpec, w: usize, h: usize, p: [f64; 3]) -> Option<[f64; 2]> {
    let forward = normalize(sub(cam.target, cam.eye));
    let side = normalize(cross(forward, cam.up));
    let up = cross(side, forward);
    let d = sub(p, cam.eye);
    let z = dot(d, forward);
    if z <= 1e-9 {
        return None;
    }
    let tan = (cam.fovy.to_radians() / 2.0).tan();
    let aspect = w as f64 / h as f64;
    let x = dot(d, side) / z / (tan * aspect);
    let y = dot(d, up) / z / tan;
    Some([(x + 1.0) / 2.0 * w as f64, (1.0 - y) / 2.0 * h as f64])
}

pub fn segment_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let ab = [b[0] - a[0], b[1] - a[1]];
    let ap = [p[0] - a[0], p[1] - a[1]];
    let len2 = ab[0] * ab[0] + ab[1] * ab[1];
    let t = if len2 > 0.0 {
        ((ap[0] * ab[0] + ap[1] * ab[1]) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let d = [ap[0] - t * ab[0], ap[1] - t * ab[1]];
    (d[0] * d[0] + d[1] * d[1]).sqrt()
}
