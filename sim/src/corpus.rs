//! The scene corpus: generated meshes with the cameras the accuracy tests use.
//!
//! `sim corpus --out DIR` writes every mesh as OBJ for use with `sim render`; the committed copies
//! under `sim/corpus/` are checked against this generator by a test.

use crate::meshgen;
use crate::scene::{CameraSpec, LightSpec, MeshData, SceneSpec};
use embedded_graphics::pixelcolor::Rgb888;
use std::f64::consts::TAU;

/// One corpus scene.
#[derive(Clone, Debug)]
pub struct CorpusScene {
    /// Short name (also the OBJ file name).
    pub name: &'static str,
    /// What it exercises.
    pub about: &'static str,
    /// The mesh.
    pub mesh: MeshData,
    /// Cameras to render it from.
    pub cameras: Vec<CameraSpec>,
    /// Whether back faces are culled (closed meshes) or drawn (open surfaces).
    pub cull_back_faces: bool,
}

/// Distinct, readable colours per triangle.
fn palette(n: usize) -> Vec<Rgb888> {
    (0..n)
        .map(|i| {
            let h = (i as f64 * 0.618_033_988_75).fract();
            let c = |o: f64| (140.0 + 100.0 * (TAU * (h + o)).cos()).clamp(0.0, 255.0) as u8;
            Rgb888::new(c(0.0), c(1.0 / 3.0), c(2.0 / 3.0))
        })
        .collect()
}

fn mesh(positions: &[[f64; 3]], triangles: Vec<[u16; 3]>) -> MeshData {
    let n = triangles.len();
    let mut m = MeshData::new(positions, triangles, Rgb888::new(200, 200, 200))
        .expect("corpus meshes are valid");
    m.colors = palette(n);
    m
}

fn from_shape((v, f): meshgen::Shape) -> MeshData {
    mesh(&v, f)
}

/// Unit icosphere with `20 · 4^n` triangles.
pub fn icosphere(n: u32) -> MeshData {
    from_shape(meshgen::icosphere(n))
}

/// An `n × n` grid of quads over [-4, 4]² with smooth hills, facing +y.
fn heightfield(n: usize) -> MeshData {
    from_shape(meshgen::grid([n, n], [4.0, 4.0], |x, z| {
        0.6 * (0.9 * x).sin() * (0.7 * z).cos() + 0.25 * (2.3 * x + 1.1 * z).sin()
    }))
}

/// A chess pawn, modelled by revolving a profile (radius, height) around the y axis.
fn pawn() -> MeshData {
    let profile = [
        (0.0, 0.0),
        (0.9, 0.0),
        (0.9, 0.12),
        (0.75, 0.2),
        (0.78, 0.32),
        (0.55, 0.4),
        (0.42, 0.6),
        (0.32, 1.0),
        (0.26, 1.35),
        (0.5, 1.42),
        (0.5, 1.5),
        (0.24, 1.56),
        (0.34, 1.68),
        (0.42, 1.85),
        (0.4, 2.0),
        (0.32, 2.14),
        (0.18, 2.24),
        (0.0, 2.28),
    ];
    let segments = 28;
    let mut v = Vec::new();
    for &(r, y) in &profile {
        for s in 0..segments {
            let a = TAU * s as f64 / segments as f64;
            v.push([r * a.cos(), y - 1.1, -r * a.sin()]);
        }
    }
    let id = |ring: usize, s: usize| (ring * segments + s % segments) as u16;
    let mut f = Vec::new();
    for ring in 0..profile.len() - 1 {
        for s in 0..segments {
            let (a, b, c, d) = (
                id(ring, s),
                id(ring, s + 1),
                id(ring + 1, s + 1),
                id(ring + 1, s),
            );
            // Counter-clockwise from outside; skip the degenerate halves at the poles.
            if profile[ring].0 > 0.0 {
                f.push([a, b, c]);
            }
            if profile[ring + 1].0 > 0.0 {
                f.push([a, c, d]);
            }
        }
    }
    mesh(&v, f)
}

/// Every corpus scene with its cameras.
/// Calls `f(scene name, camera index, scene)` for every corpus scene from every camera, with
/// the default light, then `progress(done, total)` (in cameras).
pub fn for_each_view(
    mut f: impl FnMut(&'static str, usize, SceneSpec) -> Result<(), String>,
    mut progress: impl FnMut(usize, usize),
) -> Result<(), String> {
    let scenes = all();
    let total: usize = scenes.iter().map(|s| s.cameras.len()).sum();
    let mut done = 0;
    for scene in &scenes {
        for (k, camera) in scene.cameras.iter().enumerate() {
            let spec = SceneSpec::single(
                scene.mesh.clone(),
                *camera,
                LightSpec::default(),
                scene.cull_back_faces,
            );
            f(scene.name, k, spec)?;
            done += 1;
            progress(done, total);
        }
    }
    Ok(())
}

pub fn all() -> Vec<CorpusScene> {
    let orbit = |r: f64, y: f64, n: usize, fovy: f64| -> Vec<CameraSpec> {
        (0..n)
            .map(|k| {
                let a = 0.4 + TAU * k as f64 / n as f64;
                CameraSpec::looking_at([r * a.sin(), y, r * a.cos()], [0.0; 3], fovy, 0.1, 50.0)
            })
            .collect()
    };
    // Two triangles crossing each other along x = 0.
    let crossing = mesh(
        &[
            [-1.5, -1.0, -0.8],
            [1.5, -1.0, 0.8],
            [0.0, 1.2, 0.0],
            [-1.5, 1.0, 0.8],
            [0.0, -1.2, 0.0],
            [1.5, 1.0, -0.8],
        ],
        vec![[0, 1, 2], [3, 4, 5]],
    );
    // A ground fan the camera stands on, and a wall triangle with vertices behind the eye.
    let near_plane = mesh(
        &[
            [-20.0, 0.0, 20.0],
            [20.0, 0.0, 20.0],
            [20.0, 0.0, -20.0],
            [-20.0, 0.0, -20.0],
            [0.0, 0.0, 1.0],
            [-3.0, -0.5, 4.0],
            [3.0, -0.5, 4.0],
            [0.0, 3.0, -6.0],
        ],
        vec![[4, 0, 1], [4, 1, 2], [4, 2, 3], [4, 3, 0], [5, 6, 7]],
    );
    // 240 slivers fanning out from the centre (aspect ratio about 60).
    let n = 240;
    let mut fan = vec![[0.0, 0.0, 0.0]];
    fan.extend((0..n).map(|k| {
        let a = TAU * k as f64 / n as f64;
        [2.0 * a.cos(), 2.0 * a.sin(), 0.0]
    }));
    let slivers = mesh(
        &fan,
        (0..n)
            .map(|k| [0, 1 + k as u16, 1 + ((k + 1) % n) as u16])
            .collect(),
    );
    // Overlapping coplanar triangles in z = 0 (z-fighting by construction).
    let coplanar = mesh(
        &[
            [-1.5, -1.0, 0.0],
            [1.0, -1.2, 0.0],
            [0.2, 1.4, 0.0],
            [-1.0, 0.8, 0.0],
            [-0.6, -1.4, 0.0],
            [1.6, 0.4, 0.0],
        ],
        vec![[0, 1, 2], [3, 4, 5]],
    );
    // Three long triangles in cyclic overlap: each lies over the next and under the one
    // before, so no order of whole triangles is right (the painter's algorithm's classic
    // failure; their mean depths are equal, too).
    let mut sticks = Vec::new();
    let mut stick_tris = Vec::new();
    for k in 0..3u16 {
        let a = TAU * k as f64 / 3.0;
        let (d, n) = ([a.cos(), a.sin()], [-a.sin(), a.cos()]);
        let (r, half_len, half_width, slope) = (0.5, 1.3, 0.3, 0.3);
        let at = |t: f64, s: f64| {
            [
                r * n[0] + t * d[0] + s * n[0],
                r * n[1] + t * d[1] + s * n[1],
                slope * t,
            ]
        };
        sticks.extend([
            at(-half_len, 0.0),
            at(half_len, -half_width),
            at(half_len, half_width),
        ]);
        stick_tris.push([3 * k, 3 * k + 1, 3 * k + 2]);
    }
    let cyclic = mesh(&sticks, stick_tris);
    vec![
        CorpusScene {
            name: "cube",
            about: "closed box, 12 triangles",
            mesh: from_shape(meshgen::cube()),
            cameras: orbit(4.5, 2.0, 3, 50.0),
            cull_back_faces: true,
        },
        CorpusScene {
            name: "icosphere",
            about: "1280-triangle sphere",
            mesh: icosphere(3),
            cameras: orbit(3.2, 1.0, 3, 55.0),
            cull_back_faces: true,
        },
        CorpusScene {
            name: "interpenetrating",
            about: "two triangles crossing each other",
            mesh: crossing,
            cameras: vec![
                CameraSpec::looking_at([0.3, 0.2, 4.0], [0.0; 3], 50.0, 0.5, 20.0),
                CameraSpec::looking_at([-2.5, 1.5, 3.0], [0.0; 3], 45.0, 0.5, 20.0),
            ],
            cull_back_faces: false,
        },
        CorpusScene {
            name: "heightfield",
            about: "10,082-triangle terrain",
            mesh: heightfield(71),
            cameras: vec![
                CameraSpec::looking_at([0.0, 4.0, 7.0], [0.0, -0.5, 0.0], 55.0, 0.2, 40.0),
                CameraSpec::looking_at([6.0, 1.5, 3.0], [-1.0, 0.0, -1.0], 60.0, 0.2, 40.0),
            ],
            // Open: the second camera sees its underside past the near edge.
            cull_back_faces: false,
        },
        CorpusScene {
            name: "near-plane",
            about: "triangles crossing the near plane, vertices behind the eye",
            mesh: near_plane,
            cameras: vec![
                CameraSpec::looking_at([0.0, 1.0, 2.0], [0.0, 0.0, -3.0], 70.0, 0.2, 60.0),
                CameraSpec::looking_at([0.5, 0.6, 0.5], [0.0, 0.4, -5.0], 80.0, 0.1, 60.0),
            ],
            cull_back_faces: false,
        },
        CorpusScene {
            name: "slivers",
            about: "240 slivers meeting at one vertex",
            mesh: slivers,
            cameras: vec![
                CameraSpec::looking_at([0.0, 0.0, 4.0], [0.0; 3], 60.0, 0.5, 20.0),
                CameraSpec::looking_at([1.0, 1.5, 3.5], [0.0; 3], 50.0, 0.5, 20.0),
            ],
            cull_back_faces: false,
        },
        CorpusScene {
            name: "coplanar",
            about: "overlapping triangles in one plane (exact depth ties)",
            mesh: coplanar,
            // Squarely facing cameras (rolled and moved): every vertex has the same depth, so
            // the tie is exact in both renderers and the documented rule decides.
            cameras: vec![
                CameraSpec::looking_at([0.0, 0.0, 4.0], [0.0; 3], 60.0, 0.5, 20.0),
                CameraSpec {
                    eye: [0.4, -0.2, 3.0],
                    target: [0.4, -0.2, 0.0],
                    up: [0.5, 1.0, 0.0],
                    fovy: 70.0,
                    near: 0.5,
                    far: 20.0,
                },
            ],
            cull_back_faces: false,
        },
        CorpusScene {
            name: "pawn",
            about: "modelled chess pawn (surface of revolution)",
            mesh: pawn(),
            cameras: orbit(4.0, 1.2, 3, 50.0),
            cull_back_faces: true,
        },
        CorpusScene {
            name: "cyclic",
            about: "three triangles in cyclic overlap, no two interpenetrating",
            mesh: cyclic,
            cameras: vec![
                CameraSpec::looking_at([0.0, 0.0, 4.0], [0.0; 3], 45.0, 0.5, 20.0),
                CameraSpec::looking_at([0.4, -0.3, 3.5], [0.0; 3], 50.0, 0.5, 20.0),
            ],
            cull_back_faces: false,
        },
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn corpus_sizes() {
        let all = all();
        let count = |name: &str| {
            all.iter()
                .find(|s| s.name == name)
                .unwrap()
                .mesh
                .triangles
                .len()
        };
        assert_eq!(count("icosphere"), 1280);
        assert!(count("heightfield") >= 10_000);
        assert_eq!(count("slivers"), 240);
        assert!(all.iter().all(|s| s.cameras.len() >= 2));
    }
}

/// Scenes like users bring (issue 20): generated, so every machine has the same ones.
pub mod real_world {
    use super::{mesh, palette};
    use crate::meshgen;
    use crate::scene::{CameraSpec, MeshData};
    use crate::world::World;

    /// 400 random triangles of about 0.5 units in `[−1, 1]³`, randomly wound, passing
    /// through each other everywhere.
    pub fn soup() -> MeshData {
        let (v, f) = meshgen::soup(400, 1.0, 0.5, 20);
        mesh(&v, f)
    }

    /// The soup seen from outside and from inside (the eye amid the triangles).
    pub fn soup_cameras() -> [CameraSpec; 2] {
        [
            CameraSpec::looking_at([1.7, 1.1, 3.4], [0.0; 3], 50.0, 0.1, 20.0),
            CameraSpec::looking_at([0.05, 0.1, 0.2], [0.6, -0.2, -1.0], 70.0, 0.01, 20.0),
        ]
    }

    /// An open terrain (32 × 32 quads, 2048 triangles) with every triangle's winding chosen at
    /// random, as files from the wild often are.
    pub fn open_random_winding() -> MeshData {
        let shape = meshgen::grid([32, 32], [4.0, 4.0], |x, z| {
            0.6 * (0.9 * x).sin() * (0.7 * z).cos()
        });
        let (v, f) = meshgen::random_winding(shape, 7);
        mesh(&v, f)
    }

    /// A camera above the terrain and one below it (open surfaces show their back side).
    pub fn open_cameras() -> [CameraSpec; 2] {
        [
            CameraSpec::looking_at([0.0, 4.0, 7.0], [0.0, -0.5, 0.0], 55.0, 0.2, 40.0),
            CameraSpec::looking_at([2.0, -3.0, 6.0], [0.0, 0.0, 0.0], 55.0, 0.2, 40.0),
        ]
    }

    /// 40 × 40 closed boxes over 8,000 × 8,000 units (19,200 triangles, coordinates up to
    /// 8,000): beyond the model envelope of ±4096.
    pub fn city() -> World {
        let (v, f) = meshgen::merge(meshgen::city(40, 8000.0, 3));
        let n = f.len();
        World::new(
            v,
            f.into_iter().map(|t| t.map(u32::from)).collect(),
            palette(n),
        )
    }

    /// Views of the city at near/far = 10^5: from a rooftop across the whole city, and at
    /// street level down an avenue.
    pub fn city_cameras() -> [CameraSpec; 2] {
        [
            CameraSpec::looking_at(
                [-600.0, 900.0, -600.0],
                [4000.0, 0.0, 4000.0],
                50.0,
                0.1,
                10_000.0,
            ),
            CameraSpec::looking_at(
                [4100.0, 30.0, 200.0],
                [4100.0, 20.0, 7000.0],
                60.0,
                0.1,
                10_000.0,
            ),
        ]
    }

    /// A scanned-looking closed mesh: 5,120 triangles, bumpy with jitter.
    pub fn scanned() -> MeshData {
        let (v, f) = meshgen::scanned(4, 0.01, 11);
        mesh(&v, f)
    }

    /// Cameras around the scanned mesh.
    pub fn scanned_cameras() -> [CameraSpec; 2] {
        [
            CameraSpec::looking_at([2.5, 1.2, 3.0], [0.0; 3], 50.0, 0.1, 20.0),
            CameraSpec::looking_at([-3.2, -0.8, 1.5], [0.0; 3], 45.0, 0.1, 20.0),
        ]
    }

    /// Closed meshes passing through each other (three spheres and two boxes, 264
    /// triangles): a BSP tree must split many of their triangles, and every pixel inside the
    /// union is covered.
    pub fn bsp_split() -> MeshData {
        let sphere = |c: [f64; 3], r: f64| {
            let (v, f) = meshgen::icosphere(1);
            (
                v.into_iter()
                    .map(|p| [0, 1, 2].map(|k| c[k] + r * p[k]))
                    .collect(),
                f,
            )
        };
        let cuboid = |c: [f64; 3], s: [f64; 3], twist: f64| {
            let (v, f) = meshgen::cube();
            let (sn, cs) = twist.sin_cos();
            let v = v
                .into_iter()
                .map(|p| {
                    let [x, y, z] = [0, 1, 2].map(|k| p[k] * s[k]);
                    [c[0] + cs * x + sn * z, c[1] + y, c[2] - sn * x + cs * z]
                })
                .collect();
            (v, f)
        };
        let (v, f) = meshgen::merge([
            sphere([-0.4, 0.0, 0.0], 0.8),
            sphere([0.5, 0.2, 0.1], 0.7),
            sphere([0.0, -0.3, 0.6], 0.5),
            cuboid([0.0, 0.0, 0.0], [1.4, 0.25, 0.3], 0.4),
            cuboid([0.2, 0.3, -0.2], [0.3, 1.2, 0.3], -0.3),
        ]);
        let mut m = mesh(&v, f);
        m.colors = palette(m.triangles.len());
        m
    }

    /// Cameras around the split scene.
    pub fn bsp_split_cameras() -> [CameraSpec; 2] {
        [
            CameraSpec::looking_at([0.8, 1.6, 3.8], [0.0; 3], 50.0, 0.1, 20.0),
            CameraSpec::looking_at([-3.0, -1.0, -2.5], [0.0; 3], 50.0, 0.1, 20.0),
        ]
    }

    /// A cube as OBJ text whose faces use three materials of `materials.mtl` (returned too),
    /// with a vertex normal per corner: `(obj, mtl, Kd colour of each material in face order)`.
    pub fn materials_obj() -> (String, String, [[u8; 3]; 3]) {
        let (v, f) = meshgen::cube();
        let mut obj = String::from("mtllib materials.mtl\n");
        for p in &v {
            obj += &format!("v {} {} {}\n", p[0], p[1], p[2]);
        }
        // Normals leaning towards ±y (not what area weighting gives), so a test can tell them
        // from computed ones.
        for p in &v {
            let n = [p[0], 2.0 * p[1], p[2]];
            let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            obj += &format!("vn {} {} {}\n", n[0] / l, n[1] / l, n[2] / l);
        }
        let names = ["brick", "glass", "roof"];
        for (k, t) in f.iter().enumerate() {
            if k % 4 == 0 {
                obj += &format!("usemtl {}\n", names[k / 4]);
            }
            let c = t.map(|i| i + 1);
            obj += &format!(
                "f {}//{} {}//{} {}//{}\n",
                c[0], c[0], c[1], c[1], c[2], c[2]
            );
        }
        let colors = [[178, 76, 51], [102, 153, 229], [76, 76, 76]];
        let mut mtl = String::new();
        for (name, c) in names.iter().zip(colors) {
            let kd = c.map(|x| x as f64 / 255.0);
            mtl += &format!("newmtl {name}\nKd {} {} {}\n\n", kd[0], kd[1], kd[2]);
        }
        (obj, mtl, colors)
    }
}
