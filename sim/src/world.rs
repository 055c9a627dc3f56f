//! Scenes as users have them: OBJ data of any size and extent (f64 positions, per-face colours
//! from `usemtl`, optional vertex normals), placed in mesh instances whose model coordinates fit
//! the library's envelope, and the winding analysis that decides whether back-face culling can
//! change the image.
//!
//! Large worlds are built the way firmware builds them (see the library's "Operating envelope"
//! docs): the triangles are split into spatial chunks, each stored relative to its own local
//! origin (the chunk's centre) and scaled by a power of two when its extent needs it, and placed
//! back with an instance [`Transform`]. Model coordinates then stay within ±[`MAX_MODEL_COORD`];
//! the eye-space envelope (±2^14 units around the camera) is the only limit left.

use crate::reference::{cross, dot, V3};
use crate::scene::{CameraSpec, MeshData, MeshInstance};
use embedded_graphics::pixelcolor::Rgb888;
use scanline3d::scene::{Transform, Vertex, MAX_MODEL_COORD, MAX_SCENE_TRIANGLES};
use std::collections::HashMap;
use std::io::{BufRead, Read};
use std::path::Path;

/// Colour of faces without a material (and of OBJ files without materials).
pub const DEFAULT_COLOR: Rgb888 = Rgb888::new(205, 200, 190);

/// Largest half-extent of a chunk's bounding box, in world units, once a scene needs chunks.
///
/// The vertex stage proves `Σ|m_ij|·max|v| + |t_i| ≤ 2^14` per instance; with a rotation
/// `Σ|m_ij| ≤ √3`, so a chunk of this half-extent costs at most 1774 units of the eye-space
/// envelope and any chunk whose centre is within 14,600 units of the eye fits.
pub const CHUNK_HALF_EXTENT: f64 = 1024.0;

/// Largest number of vertices (and triangles) of one chunk: 16-bit indices.
const CHUNK_MAX: usize = MAX_SCENE_TRIANGLES;

/// A triangle mesh as loaded: f64 positions, triangles in file order, one colour per triangle,
/// optional unit normals per position.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct World {
    /// Vertex positions.
    pub positions: Vec<V3>,
    /// Triangles (indices into `positions`), in OBJ face order (ids are these indices).
    pub triangles: Vec<[u32; 3]>,
    /// One colour per triangle.
    pub colors: Vec<Rgb888>,
    /// Unit normal per position, when the file gives normals for every vertex (empty if not).
    pub normals: Vec<V3>,
    /// What was wrong but not fatal (a missing `.mtl` file, an unknown material).
    pub warnings: Vec<String>,
}

/// A [`BufRead`] that reports how many bytes were consumed.
struct Counting<R, F> {
    inner: R,
    consumed: u64,
    report: F,
}

impl<R: Read, F: FnMut(u64)> Read for Counting<R, F> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.consumed += n as u64;
        (self.report)(self.consumed);
        Ok(n)
    }
}

impl<R: BufRead, F: FnMut(u64)> BufRead for Counting<R, F> {
    fn fill_buf(&mut self) -> std::io::Result<&[u8]> {
        self.inner.fill_buf()
    }
    fn consume(&mut self, amt: usize) {
        self.inner.consume(amt);
        self.consumed += amt as u64;
        (self.report)(self.consumed);
    }
}

impl World {
    /// The world of one mesh (its coordinates, triangles and colours).
    pub fn from_mesh(mesh: &MeshData) -> World {
        World {
            positions: mesh
                .vertices
                .iter()
                .map(|v| v.map(|c| c.to_num::<f64>()))
                .collect(),
            triangles: mesh.triangles.iter().map(|t| t.map(u32::from)).collect(),
            colors: mesh.colors.clone(),
            ..World::default()
        }
    }

    /// A world from positions and triangles with one colour per triangle.
    pub fn new(positions: Vec<V3>, triangles: Vec<[u32; 3]>, colors: Vec<Rgb888>) -> World {
        World {
            positions,
            triangles,
            colors,
            ..World::default()
        }
    }

    /// Loads an OBJ file: every object in file order, polygons fan-triangulated; `usemtl`
    /// diffuse colours (`Kd`) of the `.mtl` files it names become face colours. A missing
    /// `.mtl` file or an unknown material is a warning in [`World::warnings`], not an error.
    /// `progress(bytes read, file size)` is called as the file is parsed.
    pub fn load_obj(path: &Path, progress: impl FnMut(u64, u64)) -> Result<World, String> {
        let file = std::fs::File::open(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let size = file.metadata().map(|m| m.len()).unwrap_or(0);
        let dir = path.parent().unwrap_or(Path::new(".")).to_path_buf();
        let mut progress = progress;
        let mut reader = Counting {
            inner: std::io::BufReader::with_capacity(1 << 20, file),
            consumed: 0,
            report: |n| progress(n, size),
        };
        Self::parse(&mut reader, &path.display().to_string(), &|name: &Path| {
            tobj::load_mtl(dir.join(name))
        })
    }

    /// [`World::load_obj`] from OBJ text in memory; `name` labels messages, and no `.mtl`
    /// file can be found (materials fall back to the default colour, with a warning).
    pub fn load_obj_bytes(bytes: &[u8], name: &str) -> Result<World, String> {
        Self::parse(&mut std::io::BufReader::new(bytes), name, &|_: &Path| {
            Err(tobj::LoadError::OpenFileFailed)
        })
    }

    fn parse(
        reader: &mut impl BufRead,
        name: &str,
        load_mtl: &dyn Fn(&Path) -> tobj::MTLLoadResult,
    ) -> Result<World, String> {
        let opts = tobj::LoadOptions {
            triangulate: true,
            // Positions keep the file's numbering; normals have their own indices.
            single_index: false,
            ..Default::default()
        };
        let missing = std::cell::RefCell::new(Vec::new());
        let (models, materials) = tobj::load_obj_buf(reader, &opts, |p| {
            let r = load_mtl(p);
            if r.is_err() {
                missing.borrow_mut().push(p.display().to_string());
            }
            r
        })
        .map_err(|e| format!("{name}: {e}"))?;
        let mut world = World::default();
        for m in missing.into_inner() {
            world.warnings.push(format!(
                "{name}: material library {m} not found: faces keep the default colour"
            ));
        }
        let materials = materials.unwrap_or_default();
        let mut normals_complete = true;
        let mut unknown_material = false;
        for m in &models {
            let mesh = &m.mesh;
            let base = world.positions.len();
            if mesh.positions.len() % 3 != 0 || mesh.indices.len() % 3 != 0 {
                return Err(format!("{name}: malformed mesh '{}'", m.name));
            }
            world
                .positions
                .extend(mesh.positions.chunks(3).map(|p| [p[0], p[1], p[2]]));
            // Normals per position: the (normalised) sum of the normals its corners name, so
            // a position with one normal keeps it and a hard edge is smoothed.
            if mesh.normal_indices.len() == mesh.indices.len() && !mesh.normals.is_empty() {
                let mut sum = vec![[0.0f64; 3]; mesh.positions.len() / 3];
                for (&v, &n) in mesh.indices.iter().zip(&mesh.normal_indices) {
                    let n = mesh.normals.get(3 * n as usize..3 * n as usize + 3);
                    match (sum.get_mut(v as usize), n) {
                        (Some(s), Some(n)) => (0..3).for_each(|k| s[k] += n[k]),
                        _ => return Err(format!("{name}: normal index out of range")),
                    }
                }
                world.normals.extend(
                    sum.into_iter()
                        .map(|s| crate::reference::normalize(s).unwrap_or([0.0; 3])),
                );
            } else {
                normals_complete = false;
            }
            let color = match mesh.material_id.and_then(|i| materials.get(i)) {
                Some(mat) => match mat.diffuse {
                    Some(d) => {
                        let c = |v: f64| (v * 255.0).round().clamp(0.0, 255.0) as u8;
                        Rgb888::new(c(d[0]), c(d[1]), c(d[2]))
                    }
                    None => DEFAULT_COLOR,
                },
                None => {
                    unknown_material |= mesh.material_id.is_some();
                    DEFAULT_COLOR
                }
            };
            for t in mesh.indices.chunks(3) {
                let mut tri = [0u32; 3];
                for (out, &i) in tri.iter_mut().zip(t) {
                    let i = base + i as usize;
                    if i >= world.positions.len() {
                        return Err(format!("{name}: face index {} out of range", i + 1));
                    }
                    *out = i as u32;
                }
                world.triangles.push(tri);
                world.colors.push(color);
            }
        }
        if unknown_material {
            world.warnings.push(format!(
                "{name}: a face uses a material no .mtl file defines"
            ));
        }
        if !normals_complete {
            world.normals.clear();
        }
        if world.triangles.is_empty() {
            return Err(format!("{name}: no faces"));
        }
        for (i, p) in world.positions.iter().enumerate() {
            if let Some(c) = p.iter().find(|c| !c.is_finite()) {
                return Err(format!(
                    "{name}: vertex {i} coordinate {c} is not a finite number"
                ));
            }
        }
        Ok(world)
    }

    /// The mesh as OBJ text (positions as f64, faces in order; colours are not written).
    pub fn to_obj(&self) -> String {
        let mut s = String::new();
        for p in &self.positions {
            s += &format!("v {} {} {}\n", p[0], p[1], p[2]);
        }
        for t in &self.triangles {
            s += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
        }
        s
    }

    /// Largest |coordinate|.
    pub fn max_coord(&self) -> f64 {
        self.positions
            .iter()
            .flatten()
            .map(|c| c.abs())
            .fold(0.0, f64::max)
    }

    /// Whether the mesh fits one instance as it is: coordinates within the model envelope
    /// (after rounding to I16F16) and at most 65,535 vertices and triangles.
    pub fn fits_one_mesh(&self) -> bool {
        self.max_coord() + 1.0 / 65536.0 <= MAX_MODEL_COORD as f64
            && self.positions.len() <= CHUNK_MAX
            && self.triangles.len() <= CHUNK_MAX
    }

    /// Reverses the winding of the faces `flip` (from [`Orientation::flips`]).
    pub fn flip(&mut self, flip: &[usize]) {
        for &f in flip {
            if let Some(t) = self.triangles.get_mut(f) {
                t.swap(1, 2);
            }
        }
    }

    /// The mesh as library instances, and for each triangle of the instances (numbered
    /// consecutively, instance by instance) the file's triangle id.
    ///
    /// A mesh that fits the model envelope and 16-bit indices is one instance with the
    /// identity transform (ids unchanged). Any other is split into spatial chunks of at most
    /// [`CHUNK_HALF_EXTENT`] and 65,535 vertices, each stored around its own centre and placed
    /// with a translation.
    pub fn instances(&self) -> Result<(Vec<MeshInstance>, Vec<u32>), String> {
        let all: Vec<u32> = (0..self.triangles.len() as u32).collect();
        if self.fits_one_mesh() {
            let mesh = self.chunk_mesh(&all, [0.0; 3])?;
            return Ok((
                vec![MeshInstance {
                    mesh,
                    transform: Transform::IDENTITY,
                }],
                all,
            ));
        }
        let mut chunks = Vec::new();
        self.split(all, &mut chunks);
        let mut instances = Vec::with_capacity(chunks.len());
        let mut order = Vec::with_capacity(self.triangles.len());
        for tris in chunks {
            let (lo, hi) = self.bounds(&tris);
            // The origin is rounded to a whole unit so f32 holds it exactly.
            let origin = [0, 1, 2].map(|k| ((lo[k] + hi[k]) / 2.0).round());
            let mesh = self.chunk_mesh(&tris, origin)?;
            instances.push(MeshInstance {
                mesh,
                transform: Transform::translation(origin.map(|c| c as f32)),
            });
            order.extend(tris);
        }
        Ok((instances, order))
    }

    fn bounds(&self, tris: &[u32]) -> (V3, V3) {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for &t in tris {
            for &v in &self.triangles[t as usize] {
                let p = self.positions[v as usize];
                for k in 0..3 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
        }
        (lo, hi)
    }

    /// Splits `tris` at the median centroid of its longest axis until every part is small
    /// enough; parts keep file order inside.
    fn split(&self, tris: Vec<u32>, out: &mut Vec<Vec<u32>>) {
        let (lo, hi) = self.bounds(&tris);
        let extent = [0, 1, 2].map(|k| hi[k] - lo[k]);
        let small = extent.iter().all(|&e| e / 2.0 <= CHUNK_HALF_EXTENT);
        let vertices = 3 * tris.len();
        if (small && vertices <= CHUNK_MAX) || tris.len() <= 1 {
            out.push(tris);
            return;
        }
        let axis = (0..3)
            .max_by(|&a, &b| extent[a].total_cmp(&extent[b]))
            .unwrap_or(0);
        let centroid = |t: u32| -> f64 {
            self.triangles[t as usize]
                .iter()
                .map(|&v| self.positions[v as usize][axis])
                .sum::<f64>()
        };
        let mut keyed: Vec<(f64, u32)> = tris.iter().map(|&t| (centroid(t), t)).collect();
        let mid = keyed.len() / 2;
        keyed.select_nth_unstable_by(mid, |a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let (mut left, mut right): (Vec<u32>, Vec<u32>) = (
            keyed[..mid].iter().map(|k| k.1).collect(),
            keyed[mid..].iter().map(|k| k.1).collect(),
        );
        left.sort_unstable();
        right.sort_unstable();
        self.split(left, out);
        self.split(right, out);
    }

    /// The triangles `tris` as a mesh around `origin` (vertices renumbered in first use).
    fn chunk_mesh(&self, tris: &[u32], origin: V3) -> Result<MeshData, String> {
        let mut index: HashMap<u32, u16> = HashMap::new();
        let mut positions = Vec::new();
        let mut triangles = Vec::with_capacity(tris.len());
        for &t in tris {
            let mut tri = [0u16; 3];
            for (out, &v) in tri.iter_mut().zip(&self.triangles[t as usize]) {
                let next = positions.len();
                *out = *index.entry(v).or_insert_with(|| {
                    let p = self.positions[v as usize];
                    positions.push([0, 1, 2].map(|k| p[k] - origin[k]));
                    next as u16
                });
                if positions.len() > CHUNK_MAX {
                    return Err(format!("a chunk needs more than {CHUNK_MAX} vertices"));
                }
            }
            triangles.push(tri);
        }
        let mut mesh = MeshData::new(&positions, triangles, DEFAULT_COLOR)?;
        mesh.colors = tris.iter().map(|&t| self.colors[t as usize]).collect();
        if !self.normals.is_empty() {
            let order: Vec<u32> = {
                let mut o = vec![0u32; positions.len()];
                for (&v, &i) in &index {
                    o[i as usize] = v;
                }
                o
            };
            mesh.normals = Some(
                order
                    .iter()
                    .map(|&v| to_vertex(self.normals[v as usize]))
                    .collect::<Result<Vec<Vertex>, String>>()?,
            );
        }
        Ok(mesh)
    }

    /// Winding analysis of the mesh (positions welded by exact value).
    pub fn orientation(&self) -> Orientation {
        orientation(&self.positions, &self.triangles)
    }
}

/// An f64 vector as an I16F16 vertex.
fn to_vertex(v: V3) -> Result<Vertex, String> {
    let c = |x: f64| {
        fixed::types::I16F16::checked_from_num(x).ok_or_else(|| format!("normal {x} out of range"))
    };
    Ok([c(v[0])?, c(v[1])?, c(v[2])?])
}

/// Whether a mesh is closed and how its faces are wound.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Orientation {
    /// Triangles analysed (degenerate ones, with two equal corners, are left out).
    pub faces: usize,
    /// Edges used by one face only.
    pub open_edges: usize,
    /// Edges used by more than two faces.
    pub non_manifold_edges: usize,
    /// Whether no consistent winding exists (a Möbius-like surface).
    pub non_orientable: bool,
    /// Faces to flip so that every closed part is wound counter-clockwise from outside and
    /// neighbours agree (ascending; empty when the mesh is consistent and outward already).
    pub flips: Vec<usize>,
}

impl Orientation {
    /// Closed (every edge shared by exactly two faces) and orientable.
    pub fn closed(&self) -> bool {
        self.open_edges == 0 && self.non_manifold_edges == 0 && !self.non_orientable
    }

    /// Closed, with every face wound counter-clockwise from outside.
    pub fn closed_and_outward(&self) -> bool {
        self.closed() && self.flips.is_empty()
    }
}

impl std::fmt::Display for Orientation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if !self.closed() {
            write!(
                f,
                "open: {} boundary edges, {} edges shared by more than two faces{}",
                self.open_edges,
                self.non_manifold_edges,
                if self.non_orientable {
                    ", not orientable"
                } else {
                    ""
                }
            )
        } else if self.flips.is_empty() {
            write!(f, "closed, every face wound counter-clockwise from outside")
        } else {
            let shown: Vec<String> = self.flips.iter().take(12).map(|i| i.to_string()).collect();
            write!(
                f,
                "closed but inconsistently wound: {} of {} faces to flip ({}{}); --orient flips them",
                self.flips.len(),
                self.faces,
                shown.join(", "),
                if self.flips.len() > 12 { ", ..." } else { "" }
            )
        }
    }
}

/// Winding analysis of triangles over `positions` (equal positions are one vertex).
pub fn orientation(positions: &[V3], triangles: &[[u32; 3]]) -> Orientation {
    let mut weld: HashMap<[u64; 3], u32> = HashMap::new();
    let ids: Vec<u32> = positions
        .iter()
        .map(|p| {
            let n = weld.len() as u32;
            // +0.0 and -0.0 are the same point.
            *weld.entry(p.map(|c| (c + 0.0).to_bits())).or_insert(n)
        })
        .collect();
    let faces: Vec<(usize, [u32; 3])> = triangles
        .iter()
        .enumerate()
        .map(|(i, t)| {
            (
                i,
                t.map(|v| ids.get(v as usize).copied().unwrap_or(u32::MAX)),
            )
        })
        .filter(|(_, t)| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
        .collect();
    // Undirected edge -> faces using it, with whether they run low -> high.
    let mut edges: HashMap<(u32, u32), Vec<(usize, bool)>> = HashMap::new();
    for (k, (_, t)) in faces.iter().enumerate() {
        for e in 0..3 {
            let (a, b) = (t[e], t[(e + 1) % 3]);
            edges
                .entry((a.min(b), a.max(b)))
                .or_default()
                .push((k, a < b));
        }
    }
    let mut o = Orientation {
        faces: faces.len(),
        ..Orientation::default()
    };
    let mut neighbours: Vec<Vec<(usize, bool)>> = vec![Vec::new(); faces.len()];
    for users in edges.values() {
        match users.as_slice() {
            [_] => o.open_edges += 1,
            [(f, df), (g, dg)] => {
                // Consistent neighbours run the shared edge in opposite directions: they need
                // the same flip state if they do, opposite ones if they do not.
                let same = df != dg;
                neighbours[*f].push((*g, same));
                neighbours[*g].push((*f, same));
            }
            _ => o.non_manifold_edges += 1,
        }
    }
    // Two-colour each connected part: flip[f] relative to the part's first face.
    let mut flip: Vec<Option<bool>> = vec![None; faces.len()];
    for start in 0..faces.len() {
        if flip[start].is_some() {
            continue;
        }
        flip[start] = Some(false);
        let mut part = vec![start];
        let mut stack = vec![start];
        while let Some(f) = stack.pop() {
            let ff = flip[f].unwrap_or(false);
            for &(g, same) in &neighbours[f] {
                let want = if same { ff } else { !ff };
                match flip[g] {
                    None => {
                        flip[g] = Some(want);
                        part.push(g);
                        stack.push(g);
                    }
                    Some(have) if have != want => o.non_orientable = true,
                    Some(_) => {}
                }
            }
        }
        // Outward: positive signed volume once flipped.
        let signed: f64 = part
            .iter()
            .map(|&f| {
                let t = &triangles[faces[f].0];
                let p = t.map(|v| positions[v as usize]);
                let v = dot(p[0], cross(p[1], p[2]));
                if flip[f] == Some(true) {
                    -v
                } else {
                    v
                }
            })
            .sum();
        if signed < 0.0 {
            for &f in &part {
                flip[f] = flip[f].map(|x| !x);
            }
        }
    }
    o.flips = flip
        .iter()
        .enumerate()
        .filter(|(_, f)| **f == Some(true))
        .map(|(k, _)| faces[k].0)
        .collect();
    o.flips.sort_unstable();
    o
}

/// Generalised winding number of the closed triangle surface around `p` (about 1 inside a
/// counter-clockwise-outward closed mesh, 0 outside): the sum of the signed solid angles of
/// the triangles seen from `p`, over 4π (Van Oosterom and Strackee's formula).
pub fn winding_number(triangles: impl IntoIterator<Item = [V3; 3]>, p: V3) -> f64 {
    let mut total = 0.0;
    for t in triangles {
        let [a, b, c] = t.map(|v| [v[0] - p[0], v[1] - p[1], v[2] - p[2]]);
        let len = |v: V3| dot(v, v).sqrt();
        let (la, lb, lc) = (len(a), len(b), len(c));
        let num = dot(a, cross(b, c));
        let den = la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la;
        total += 2.0 * num.atan2(den);
    }
    total / (4.0 * std::f64::consts::PI)
}

/// Distance from `p` to the triangle `t` (closest point by region, as in Ericson's
/// *Real-Time Collision Detection* §5.1.5).
pub fn distance_to_triangle(p: V3, t: [V3; 3]) -> f64 {
    let sub = |a: V3, b: V3| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let [a, b, c] = t;
    let (ab, ac, ap) = (sub(b, a), sub(c, a), sub(p, a));
    let closest = (|| {
        let (d1, d2) = (dot(ab, ap), dot(ac, ap));
        if d1 <= 0.0 && d2 <= 0.0 {
            return a;
        }
        let bp = sub(p, b);
        let (d3, d4) = (dot(ab, bp), dot(ac, bp));
        if d3 >= 0.0 && d4 <= d3 {
            return b;
        }
        let at = |o: V3, d: V3, s: f64| [o[0] + s * d[0], o[1] + s * d[1], o[2] + s * d[2]];
        let vc = d1 * d4 - d3 * d2;
        if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
            return at(a, ab, d1 / (d1 - d3));
        }
        let cp = sub(p, c);
        let (d5, d6) = (dot(ab, cp), dot(ac, cp));
        if d6 >= 0.0 && d5 <= d6 {
            return c;
        }
        let vb = d5 * d2 - d1 * d6;
        if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
            return at(a, ac, d2 / (d2 - d6));
        }
        let va = d3 * d6 - d5 * d4;
        if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
            return at(b, sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6)));
        }
        let denom = 1.0 / (va + vb + vc);
        let (v, w) = (vb * denom, vc * denom);
        [0, 1, 2].map(|k| a[k] + ab[k] * v + ac[k] * w)
    })();
    let d = sub(p, closest);
    dot(d, d).sqrt()
}

/// Whether culling back faces is right, and why.
#[derive(Clone, Debug, PartialEq)]
pub struct CullDecision {
    /// Cull back faces: they cannot show in any of the views.
    pub cull: bool,
    /// Why (one line).
    pub reason: String,
}

/// Decides whether back-face culling can change the image of `triangles` (world space) in
/// any of `views`, given their [`Orientation`]: it cannot when the mesh is closed and wound
/// counter-clockwise from outside, every eye is outside it, and no surface comes near enough
/// the eye to cut the visible part of the near plane (then every ray meets a front face first).
pub fn cull_decision(
    orientation: &Orientation,
    triangles: &[[V3; 3]],
    views: &[CameraSpec],
    aspect: f64,
) -> CullDecision {
    let no = |reason: String| CullDecision {
        cull: false,
        reason,
    };
    if !orientation.closed() {
        return no(format!("two-sided: the mesh is {orientation}"));
    }
    if !orientation.flips.is_empty() {
        return no(format!("two-sided: the mesh is {orientation}"));
    }
    for cam in views {
        let inside = winding_number(triangles.iter().copied(), cam.eye);
        if inside.abs() > 0.5 {
            return no(format!(
                "two-sided: the eye {:?} is inside the closed mesh",
                cam.eye
            ));
        }
        // The near rectangle lies within this distance of the eye.
        let half_h = (cam.fovy.to_radians() / 2.0).tan();
        let reach = cam.near * (1.0 + half_h * half_h * (1.0 + aspect * aspect)).sqrt();
        if triangles
            .iter()
            .any(|&t| distance_to_triangle(cam.eye, t) <= reach)
        {
            return no(format!(
                "two-sided: the near plane of the eye at {:?} cuts the mesh",
                cam.eye
            ));
        }
    }
    CullDecision {
        cull: true,
        reason: "back faces culled: the mesh is closed, wound counter-clockwise from outside, and every eye is outside it".into(),
    }
}

/// Back-face culling as `sim` is told: decided per scene and views, or forced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Culling {
    /// Cull only where [`cull_decision`] shows it cannot change the image.
    Auto,
    /// Always cull (`--cull`).
    On,
    /// Never cull (`--no-cull`).
    Off,
}

impl Culling {
    /// From the `--cull` and `--no-cull` flags.
    pub fn from_flags(cull: bool, no_cull: bool) -> Culling {
        match (cull, no_cull) {
            (true, _) => Culling::On,
            (_, true) => Culling::Off,
            _ => Culling::Auto,
        }
    }
}

/// An OBJ scene loaded for `sim`: the world, its instances, and its winding.
#[derive(Clone, Debug)]
pub struct Loaded {
    /// The file's mesh (after `--orient`, if asked).
    pub world: World,
    /// The instances that render it ([`World::instances`]).
    pub instances: Vec<MeshInstance>,
    /// File triangle id of each instance triangle.
    pub order: Vec<u32>,
    /// Winding analysis (before `--orient`).
    pub orientation: Orientation,
}

impl Loaded {
    /// Loads `path` with progress on standard error for large files; with `orient`, flips the
    /// faces [`Orientation::flips`] names first. Warnings go to standard error, among them a
    /// closed mesh with inconsistent winding (with the faces to flip) that was not oriented.
    pub fn load(path: &Path, orient: bool) -> Result<Loaded, String> {
        let progress = crate::progress::Progress::start(
            &format!("loading {}", path.display()),
            std::fs::metadata(path).ok().map(|m| m.len()),
        );
        let world = World::load_obj(path, |n, _| progress.set(n));
        progress.finish();
        Self::from_world(world?, orient)
    }

    /// [`Loaded::load`] for a world in memory.
    pub fn from_world(mut world: World, orient: bool) -> Result<Loaded, String> {
        for w in &world.warnings {
            eprintln!("sim: warning: {w}");
        }
        let orientation = world.orientation();
        if orient {
            world.flip(&orientation.flips);
        } else if orientation.closed() && !orientation.flips.is_empty() {
            eprintln!("sim: warning: the mesh is {orientation}");
        }
        let (instances, order) = world.instances()?;
        Ok(Loaded {
            world,
            instances,
            order,
            orientation,
        })
    }

    /// The file's triangles in world space.
    pub fn triangles(&self) -> Vec<[V3; 3]> {
        self.world
            .triangles
            .iter()
            .map(|t| t.map(|v| self.world.positions[v as usize]))
            .collect()
    }

    /// Whether to cull, and why, for `views` at aspect ratio `aspect`.
    pub fn culling(&self, culling: Culling, views: &[CameraSpec], aspect: f64) -> CullDecision {
        let orientation = if self.orientation.flips.is_empty() {
            self.orientation.clone()
        } else {
            // Oriented on loading, or not: what the faces are now.
            self.world.orientation()
        };
        match culling {
            Culling::On => CullDecision {
                cull: true,
                reason: "back faces culled (--cull)".into(),
            },
            Culling::Off => CullDecision {
                cull: false,
                reason: "two-sided (--no-cull)".into(),
            },
            Culling::Auto => cull_decision(&orientation, &self.triangles(), views, aspect),
        }
    }

    /// Maps instance triangle ids (as renders report them) to the file's ids.
    pub fn file_ids(&self, ids: &mut [i32]) {
        for id in ids.iter_mut().filter(|id| **id >= 0) {
            *id = self.order.get(*id as usize).map_or(-1, |&o| o as i32);
        }
    }
}
