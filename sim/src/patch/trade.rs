//! The host half of `cargo xtask patch-trade`: the patch firmware's frames (the teapot of
//! `scanline3d_demo::patches`, turning) against the Bezier-clipping reference, per flatness
//! tolerance; the same teapot tessellated into triangle meshes of increasing density
//! (uniform `(u, v)` grids per patch), measured the same way; the mesh source the mesh
//! firmware variant includes; and the table.
//!
//! Images are id images: the patch renderer's ids are patch indices; a mesh's triangle ids
//! are mapped back to the patch each triangle came from, so both are compared with the
//! reference's patch ids pixel by pixel.

use super::model::{Patch, PatchModel};
use super::render::Reference;
use crate::scene::{CameraSpec, LightSpec};
use fixed::types::I16F16;
use scanline3d::patch::Tolerance;
use scanline3d::scene::{Mesh, MeshColors};
use scanline3d::sink::{FnSink, Row, TriangleId};
use scanline3d_demo::patches as demo;
use std::collections::HashMap;
use std::convert::Infallible;
use std::fmt::Write as _;

/// Flatness tolerances measured (pixels), coarse to fine.
pub const TOLERANCES: [f64; 5] = [4.0, 2.0, 1.0, 0.5, 0.25];
/// Grid cells per patch side of the meshes measured (`n × n` quads, two triangles each).
pub const GRIDS: [usize; 10] = [2, 3, 4, 6, 8, 12, 16, 20, 24, 32];
/// Farthest a coverage mismatch is looked for from the reference's silhouette (pixels).
const SILHOUETTE_LIMIT: usize = 20;

/// The firmware's camera as the host's camera description (`demo::camera`).
pub fn camera() -> CameraSpec {
    CameraSpec {
        eye: [4.5, -6.0, 4.0],
        target: [0.0, 0.0, 1.2],
        up: [0.0, 0.0, 1.0],
        fovy: 45.0,
        near: 0.1,
        far: 100.0,
    }
}

/// `model` turned about z as the firmware turns it at `frame` (control points turned:
/// Bezier patches are affinely invariant, rational ones too).
pub fn turned(model: &PatchModel, frame: u32) -> PatchModel {
    let (s, c) = f64::from(demo::angle(frame)).sin_cos();
    PatchModel {
        patches: model
            .patches
            .iter()
            .map(|p| Patch {
                points: p.points.map(|[x, y, z]| [c * x - s * y, s * x + c * y, z]),
                ..p.clone()
            })
            .collect(),
    }
}

/// One id image with eye depth, row-major, `SIDE × SIDE`.
#[derive(Clone, Debug, PartialEq)]
pub struct Ids {
    /// Patch index per pixel, −1 for background.
    pub ids: Vec<i32>,
    /// Eye depth per pixel (infinite for background).
    pub depth: Vec<f32>,
}

impl Ids {
    fn background(n: usize) -> Ids {
        Ids {
            ids: vec![-1; n],
            depth: vec![f32::INFINITY; n],
        }
    }
}

/// The Bezier-clipping reference's id image of the firmware's `frame`.
pub fn reference(model: &PatchModel, frame: u32) -> Result<Ids, String> {
    let r = Reference::new(
        turned(model, frame),
        camera().reference()?,
        LightSpec::default().reference()?,
    );
    let image = r.render(demo::SIDE, demo::SIDE).0;
    Ok(Ids {
        ids: image.ids,
        depth: image.depth,
    })
}

/// Runs `f` on a thread with room for workspaces built by value in debug builds.
fn on_big_stack<T: Send>(f: impl FnOnce() -> Result<T, String> + Send) -> Result<T, String> {
    std::thread::scope(|scope| {
        std::thread::Builder::new()
            .stack_size(64 << 20)
            .spawn_scoped(scope, f)
            .map_err(|e| format!("cannot start render thread: {e}"))?
            .join()
            .map_err(|_| "render thread panicked".to_string())?
    })
}

/// A sink writing triangle ids mapped through `id_of` and eye depth into `out`.
fn id_sink<'a>(
    out: &'a mut Ids,
    id_of: impl Fn(i32) -> i32 + 'a,
) -> Result<impl FnMut(Row<'_, TriangleId>) -> Result<(), Infallible> + 'a, String> {
    let camera = camera().fixed()?;
    Ok(move |row: Row<'_, TriangleId>| {
        let at = row.y as usize * demo::SIDE;
        for (x, id) in row.pixels.iter().enumerate() {
            let id = if id.0 >= 0 { id_of(id.0) } else { -1 };
            out.ids[at + x] = id;
            out.depth[at + x] = match row.depth.get(x) {
                Some(q) if id >= 0 => camera.eye_distance(q).unwrap_or(f32::INFINITY),
                _ => f32::INFINITY,
            };
        }
        Ok(())
    })
}

/// What the patch renderer did for one frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PatchFrame {
    /// Triangles made.
    pub triangles: u32,
    /// Splits refused because the workspace's row buckets were full.
    pub overflows: u32,
    /// Triangles dropped because the active list was full.
    pub dropped: u32,
}

/// The patch firmware's `frame` at `tolerance`, rendered on the host by the same code
/// (`demo::render_frame_at`, the firmware's capacities) into an id image.
pub fn patch_frame(frame: u32, tolerance: f64) -> Result<(Ids, PatchFrame), String> {
    on_big_stack(move || {
        let mut ws = Box::new(demo::PanelPatchesOf::<TriangleId>::new(TriangleId::NONE));
        let mut out = Ids::background(demo::SIDE * demo::SIDE);
        let stats = demo::render_frame_at(
            &mut ws,
            frame,
            Tolerance::from_num(tolerance),
            &mut FnSink(id_sink(&mut out, |id| id)?),
        )?;
        let made = PatchFrame {
            triangles: stats.frame.triangles_in,
            overflows: stats.overflows,
            dropped: stats.frame.dropped,
        };
        Ok((out, made))
    })
}

/// The teapot as a triangle mesh: each patch an `n × n` grid in `(u, v)`, its points on the
/// surface rounded to I16F16 and welded where they are equal (shared edges, collapsed
/// edges), triangles that collapse dropped.
#[derive(Clone, Debug, PartialEq)]
pub struct TessellatedMesh {
    /// Grid cells per patch side.
    pub cells: usize,
    /// I16F16 vertex bits.
    pub vertices: Vec<[i32; 3]>,
    /// Triangles, counter-clockwise seen from the patch's front.
    pub triangles: Vec<[u16; 3]>,
    /// The patch each triangle came from.
    pub patch_of: Vec<u16>,
}

impl TessellatedMesh {
    /// Flash of the mesh as `sim export` stores it: three I16F16 per vertex, three `u16`
    /// per triangle (a uniform colour, no normals).
    pub fn flash_bytes(&self) -> usize {
        12 * self.vertices.len() + 6 * self.triangles.len()
    }

    /// The checked library mesh over `vertices` (from [`TessellatedMesh::fixed_vertices`]).
    pub fn mesh<'a>(&'a self, vertices: &'a [[I16F16; 3]]) -> Result<Mesh<'a>, String> {
        Mesh::new(
            vertices,
            &self.triangles,
            MeshColors::Uniform(super::fixed::PATCH_COLOR),
            None,
        )
        .map_err(|e| format!("the {}-cell mesh: {e}", self.cells))
    }

    /// The vertices as I16F16.
    pub fn fixed_vertices(&self) -> Vec<[I16F16; 3]> {
        self.vertices
            .iter()
            .map(|v| v.map(I16F16::from_bits))
            .collect()
    }
}

/// Tessellates `model` into `n × n` cells per patch (see [`TessellatedMesh`]).
pub fn tessellate(model: &PatchModel, n: usize) -> Result<TessellatedMesh, String> {
    if n == 0 {
        return Err("a grid needs at least one cell per side".into());
    }
    let mut index: HashMap<[i32; 3], u16> = HashMap::new();
    let mut mesh = TessellatedMesh {
        cells: n,
        vertices: Vec::new(),
        triangles: Vec::new(),
        patch_of: Vec::new(),
    };
    for (k, patch) in model.patches.iter().enumerate() {
        let mut grid = Vec::with_capacity((n + 1) * (n + 1));
        for i in 0..=n {
            for j in 0..=n {
                let p = patch.point(i as f64 / n as f64, j as f64 / n as f64);
                let bits = p.map(|c| I16F16::from_num(c).to_bits());
                let next = mesh.vertices.len();
                let id = *index.entry(bits).or_insert_with(|| {
                    mesh.vertices.push(bits);
                    next as u16
                });
                if mesh.vertices.len() > usize::from(u16::MAX) {
                    return Err(format!("{n} cells per patch: more than 65,535 vertices"));
                }
                grid.push(id);
            }
        }
        let at = |i: usize, j: usize| grid[i * (n + 1) + j];
        for i in 0..n {
            for j in 0..n {
                let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                for t in [[a, b, c], [a, c, d]] {
                    if t[0] != t[1] && t[1] != t[2] && t[0] != t[2] {
                        mesh.triangles.push(t);
                        mesh.patch_of.push(k as u16);
                    }
                }
            }
        }
    }
    if mesh.triangles.len() > scanline3d::scene::MAX_SCENE_TRIANGLES {
        return Err(format!(
            "{n} cells per patch: {} triangles, more than a scene holds",
            mesh.triangles.len()
        ));
    }
    Ok(mesh)
}

/// Most triangles a measured mesh may have (the host workspace's capacity).
const HOST_TRIS: usize = scanline3d::scene::MAX_SCENE_TRIANGLES;

/// The mesh firmware's `frame` drawing `mesh` (`demo::render_mesh_frame`, the same code),
/// rendered on the host into an id image of patch indices (triangles dropped from a full
/// active list are an error: the image would not be the mesh's).
pub fn mesh_frame(mesh: &TessellatedMesh, frame: u32) -> Result<Ids, String> {
    on_big_stack(move || {
        let vertices = mesh.fixed_vertices();
        let lib = mesh.mesh(&vertices)?;
        let mut ws = Box::new(demo::PanelMesh::<TriangleId, HOST_TRIS>::new(
            TriangleId::NONE,
        ));
        let mut out = Ids::background(demo::SIDE * demo::SIDE);
        let patch_of = |t: i32| mesh.patch_of.get(t as usize).map_or(-1, |&p| i32::from(p));
        let stats = demo::render_mesh_frame(
            &mut ws,
            &lib,
            frame,
            &mut FnSink(id_sink(&mut out, patch_of)?),
        )?;
        if stats.dropped > 0 {
            return Err(format!(
                "the {}-cell mesh, frame {frame}: {} triangles dropped from the active list",
                mesh.cells, stats.dropped
            ));
        }
        Ok(out)
    })
}

/// An image's disagreement with the reference, summed over frames.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Mismatches {
    /// Pixels compared.
    pub pixels: usize,
    /// Pixels covered in one image and not in the other.
    pub coverage: usize,
    /// Pixels whose patch id differs (coverage mismatches included).
    pub ids: usize,
    /// Farthest coverage mismatch from the reference's silhouette: Chebyshev distance in
    /// pixels to the nearest pixel whose reference coverage differs (1 = next to it).
    pub farthest: usize,
    /// Largest relative eye-depth error where both show the same patch.
    pub depth: f64,
}

impl Mismatches {
    /// Adds `got` against `want` (images of the same size).
    pub fn add(&mut self, got: &Ids, want: &Ids, width: usize) {
        let cover: Vec<bool> = want.ids.iter().map(|&i| i >= 0).collect();
        self.pixels += got.ids.len();
        for (i, (&a, &b)) in got.ids.iter().zip(&want.ids).enumerate() {
            if (a >= 0) != (b >= 0) {
                self.coverage += 1;
                self.farthest = self.farthest.max(to_silhouette(&cover, width, i));
            }
            if a != b {
                self.ids += 1;
            } else if a >= 0 {
                let (x, y) = (f64::from(got.depth[i]), f64::from(want.depth[i]));
                self.depth = self.depth.max((x - y).abs() / y);
            }
        }
    }

    /// At least as accurate as `other`: no more coverage and no more id mismatches.
    pub fn as_good_as(&self, other: &Mismatches) -> bool {
        self.coverage <= other.coverage && self.ids <= other.ids
    }

    fn percent(&self, k: usize) -> f64 {
        100.0 * k as f64 / self.pixels.max(1) as f64
    }
}

/// Chebyshev distance (pixels, up to [`SILHOUETTE_LIMIT`]) from pixel `i` to the nearest
/// pixel whose coverage in `cover` differs from `i`'s.
fn to_silhouette(cover: &[bool], width: usize, i: usize) -> usize {
    let height = cover.len() / width.max(1);
    let (x, y) = ((i % width) as isize, (i / width) as isize);
    for r in 1..=SILHOUETTE_LIMIT as isize {
        for dy in -r..=r {
            for dx in -r..=r {
                if dx.abs() != r && dy.abs() != r {
                    continue;
                }
                let (u, v) = (x + dx, y + dy);
                if u < 0 || v < 0 || u >= width as isize || v >= height as isize {
                    continue;
                }
                if cover[v as usize * width + u as usize] != cover[i] {
                    return r as usize;
                }
            }
        }
    }
    SILHOUETTE_LIMIT
}

/// Rust source of `mesh` for the mesh firmware variant (`firmware/examples/patch.rs` with
/// `--cfg scanline3d_patch_mesh`): `static` I16F16 vertices and `u16` triangles as `sim
/// export` writes them, the checked `MESH` and its `TRIANGLES` count.
pub fn mesh_source(mesh: &TessellatedMesh, command: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "// Generated by `{command}`: the Utah teapot's patches tessellated into {n}×{n} cells each. Do not edit.\n\
         const fn c(bits: i32) -> fixed::types::I16F16 {{\n    fixed::types::I16F16::from_bits(bits)\n}}\n",
        n = mesh.cells
    );
    let _ = writeln!(
        s,
        "static VERTICES: [scanline3d::scene::Vertex; {}] = [",
        mesh.vertices.len()
    );
    for v in &mesh.vertices {
        let _ = writeln!(s, "    [c({}), c({}), c({})],", v[0], v[1], v[2]);
    }
    let _ = writeln!(
        s,
        "];\nstatic TRIANGLE_INDICES: [[u16; 3]; {}] = [",
        mesh.triangles.len()
    );
    for t in &mesh.triangles {
        let _ = writeln!(s, "    [{}, {}, {}],", t[0], t[1], t[2]);
    }
    let color = super::fixed::PATCH_COLOR;
    use embedded_graphics::pixelcolor::RgbColor;
    let _ = writeln!(
        s,
        "];\n/// Triangles of the mesh.\npub const TRIANGLES: usize = {};\n\
         /// The mesh, checked when this file is compiled.\n\
         pub static MESH: scanline3d::scene::Mesh<'static> = match scanline3d::scene::Mesh::new(\n    \
         &VERTICES,\n    &TRIANGLE_INDICES,\n    \
         scanline3d::scene::MeshColors::Uniform(embedded_graphics::pixelcolor::Rgb888::new({}, {}, {})),\n    None,\n) {{\n    \
         Ok(m) => m,\n    Err(_) => panic!(\"invalid tessellated mesh\"),\n}};",
        mesh.triangles.len(),
        color.r(),
        color.g(),
        color.b()
    );
    s
}

/// Figures of one firmware build on one target.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct OnTarget {
    /// Instructions (QEMU) per frame, mean over the firmware's frames.
    pub instructions: f64,
    /// Most triangles on the active list at once, over the frames.
    pub peak_active: u64,
    /// The renderer's workspace (bytes).
    pub workspace: u64,
    /// Peak stack including the workspace (bytes).
    pub peak_stack: u64,
    /// The whole firmware image (bytes).
    pub image: u64,
}

/// One row of the trade table.
#[derive(Clone, Debug, PartialEq)]
pub struct TradeRow {
    /// "patches, 0.5 px" or "mesh 16×16".
    pub name: String,
    /// Accuracy over the measured frames.
    pub accuracy: Mismatches,
    /// Triangles per frame, mean (patches: made by the renderer; mesh: in the mesh).
    pub triangles: f64,
    /// Flash of the model's data (bytes).
    pub data_flash: usize,
    /// thumbv7em and thumbv6m (`None`: not measured).
    pub targets: [Option<OnTarget>; 2],
}

/// The smallest mesh (first of `meshes`, ordered by size) at least as accurate as `patch`.
pub fn matching_mesh<'a>(
    patch: &Mismatches,
    meshes: &'a [(TessellatedMesh, Mismatches)],
) -> Option<&'a (TessellatedMesh, Mismatches)> {
    meshes.iter().find(|(_, m)| m.as_good_as(patch))
}

fn millions(t: &Option<OnTarget>) -> String {
    t.map_or("—".into(), |t| format!("{:.1} M", t.instructions / 1e6))
}

/// The trade table (markdown): one row per entry of `rows`.
pub fn table(rows: &[TradeRow]) -> String {
    let mut md = String::from(
        "| model | coverage mismatches | id mismatches | farthest from the silhouette (px) | depth error, max relative | triangles per frame | data flash | thumbv7em instructions/frame | thumbv6m instructions/frame | peak active | workspace | peak stack (with workspace) | firmware image |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let a = &r.accuracy;
        let ram = |f: fn(&OnTarget) -> u64| {
            r.targets[0].map_or("—".into(), |t| format!("{} B", crate::thousands(f(&t))))
        };
        let _ = writeln!(
            md,
            "| {} | {:.3} % ({}) | {:.3} % ({}) | {} | {:.2e} | {:.0} | {} B | {} | {} | {} | {} | {} | {} |",
            r.name,
            a.percent(a.coverage),
            a.coverage,
            a.percent(a.ids),
            a.ids,
            a.farthest,
            a.depth,
            r.triangles,
            crate::thousands(r.data_flash as u64),
            millions(&r.targets[0]),
            millions(&r.targets[1]),
            r.targets[0].map_or("—".into(), |t| t.peak_active.to_string()),
            ram(|t| t.workspace),
            ram(|t| t.peak_stack),
            ram(|t| t.image),
        );
    }
    md
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::patch::parse;

    fn teapot() -> PatchModel {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/patches/teapot.bpt");
        parse::load(&path).unwrap()
    }

    #[test]
    fn tessellation_welds_shared_edges_and_drops_collapsed_triangles() {
        let model = teapot();
        let mesh = tessellate(&model, 2).unwrap();
        // 32 patches of 2×2 cells: 256 triangles, less those on the 8 collapsed edges (one
        // per collapsed edge cell: 2 cells × 8 patches).
        assert_eq!(mesh.triangles.len(), 256 - 16);
        assert!(
            mesh.vertices.len() < 32 * 9,
            "{} vertices",
            mesh.vertices.len()
        );
        assert_eq!(mesh.patch_of.len(), mesh.triangles.len());
        assert_eq!(mesh.flash_bytes(), 12 * mesh.vertices.len() + 6 * 240);
        mesh.mesh(&mesh.fixed_vertices()).unwrap();
        assert!(tessellate(&model, 0).is_err());
    }

    #[test]
    fn mismatches_count_coverage_ids_and_distance() {
        let want = Ids {
            ids: vec![-1, 0, 0, 1, -1, -1],
            depth: vec![f32::INFINITY, 2.0, 2.0, 2.0, f32::INFINITY, f32::INFINITY],
        };
        let got = Ids {
            ids: vec![-1, 0, 1, 1, 1, -1],
            depth: vec![f32::INFINITY, 2.2, 2.0, 2.0, 3.0, f32::INFINITY],
        };
        let mut m = Mismatches::default();
        m.add(&got, &want, 6);
        assert_eq!((m.pixels, m.coverage, m.ids, m.farthest), (6, 1, 2, 1));
        assert!((m.depth - 0.1).abs() < 1e-6, "{}", m.depth);
        assert!(!m.as_good_as(&Mismatches::default()));
        assert!(Mismatches::default().as_good_as(&m));
    }

    #[test]
    fn the_table_maker_writes_one_row_per_entry_and_picks_the_smallest_equal_mesh() {
        let patch = Mismatches {
            pixels: 100,
            coverage: 2,
            ids: 5,
            farthest: 1,
            depth: 0.01,
        };
        let model = teapot();
        let coarse = (
            tessellate(&model, 2).unwrap(),
            Mismatches {
                coverage: 9,
                ids: 20,
                ..patch
            },
        );
        let fine = (
            tessellate(&model, 3).unwrap(),
            Mismatches {
                coverage: 1,
                ids: 5,
                ..patch
            },
        );
        let meshes = [coarse, fine];
        let picked = matching_mesh(&patch, &meshes).unwrap();
        assert_eq!(picked.0.cells, 3);
        let on = OnTarget {
            instructions: 2.5e6,
            peak_active: 99,
            workspace: 1234,
            peak_stack: 5678,
            image: 40000,
        };
        let rows = [
            TradeRow {
                name: "patches, 0.5 px".into(),
                accuracy: patch,
                triangles: 100.0,
                data_flash: 6144,
                targets: [Some(on), None],
            },
            TradeRow {
                name: "mesh 3×3".into(),
                accuracy: picked.1,
                triangles: picked.0.triangles.len() as f64,
                data_flash: picked.0.flash_bytes(),
                targets: [None, None],
            },
        ];
        let md = table(&rows);
        let lines: Vec<&str> = md.lines().collect();
        assert_eq!(lines.len(), 4);
        assert_eq!(
            lines[2],
            "| patches, 0.5 px | 2.000 % (2) | 5.000 % (5) | 1 | 1.00e-2 | 100 | 6,144 B | 2.5 M | — | 99 | 1,234 B | 5,678 B | 40,000 B |"
        );
        assert!(lines[3].starts_with("| mesh 3×3 | 1.000 % (1) | 5.000 % (5) |"));
    }
}
