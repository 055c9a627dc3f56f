//! Polygonization: the isosurface as triangles for the span z-buffer, by marching tetrahedra
//! over a grid of `S × S × S` samples (`S − 1` cells per axis) that spans the influence spheres
//! of the positive balls.
//!
//! Each cell is cut into the six tetrahedra of the Kuhn (Freudenthal) triangulation, which every
//! cell cuts the same way, so neighbouring cells agree on the diagonals of their shared faces.
//! Every edge of that triangulation goes from a grid point to the grid point `+ d`, `d` one of
//! the seven non-zero corner offsets; its crossing is computed once, stored under (grid point,
//! `d`) and looked up by every tetrahedron around the edge, so the mesh is closed: every mesh
//! edge lies in exactly two triangles, wound opposite ways (`tests/suite/metaball_polygonize.rs`).
//!
//! Memory is bounded and does not depend on the scene: the grid is walked one slab of cells at a
//! time, keeping two layers of samples and the crossings of the edges in and between them
//! ([`Polygonizer::BYTES`]); the mesh goes into a [`PolyMesh`] of `V` vertices and `T` triangles,
//! and a full one is an error ([`PolygonizeError`]), never a silently shorter mesh.
//!
//! ## Bit budget
//!
//! Samples of `g = Σ q·f − T` are [`Coord`] (I16F16: `|g|` ≤ 64·64 + 64 = 2^12 + 64 by the scene
//! envelope); grid points, crossings, normals and colours are computed in [`Wide`] (I32F32): a
//! grid point is within ±(64 + 32 + 1) per axis, so `|p − c|²` ≤ 3·194² < 2^17 and, times
//! `1/R²` ≤ 2^8, below 2^25; a gradient term `|q·f'(s)·2(p − c)/R²|` ≤ 64·2.5·2·32·2^8/32 < 2^17
//! per ball, below 2^23 over 64 balls. Mesh vertices are rounded to I16F16, far inside the
//! renderer's ±4096.

use super::cast::quotient;
use super::{field, field_slope, mul, Ball, Blend, Coord, Metaballs, Wide};
use crate::math::zip3;
use crate::scene::{Mesh, MeshColors, SceneError, Vertex};
use embedded_graphics::pixelcolor::Rgb888;

/// No crossing on this edge (both ends on the same side).
const NONE: u16 = u16::MAX;

/// Most samples per axis: cells and vertex indices stay small.
pub const MAX_SAMPLES: usize = 256;

/// The Kuhn triangulation of a cell: corners as bits (x = 1, y = 2, z = 4), each tetrahedron a
/// chain from corner 0 to corner 7 adding one axis at a time.
const TETRAHEDRA: [[u8; 4]; 6] = [
    [0, 1, 3, 7],
    [0, 1, 5, 7],
    [0, 2, 3, 7],
    [0, 2, 6, 7],
    [0, 4, 5, 7],
    [0, 4, 6, 7],
];

/// Why a polygonization stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PolygonizeError {
    /// The grid has fewer than 2 or more than [`MAX_SAMPLES`] samples per axis.
    Grid,
    /// The scene holds more balls than the polygonizer's `N`.
    Balls,
    /// The mesh needs more than `V` vertices (or 65534); the grid crossed so far is dropped.
    Vertices,
    /// The mesh needs more than `T` triangles.
    Triangles,
}

impl core::fmt::Display for PolygonizeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            PolygonizeError::Grid => write!(f, "grid needs 2 to {MAX_SAMPLES} samples per axis"),
            PolygonizeError::Balls => write!(f, "more balls than the polygonizer holds"),
            PolygonizeError::Vertices => write!(f, "mesh vertex capacity exceeded"),
            PolygonizeError::Triangles => write!(f, "mesh triangle capacity exceeded"),
        }
    }
}

impl core::error::Error for PolygonizeError {}

/// What a polygonization did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PolyStats {
    /// Field samples taken (`S³`, or 0 when no ball is positive).
    pub samples: u32,
    /// Grid edges the surface crosses: the mesh's vertices.
    pub vertices: u32,
    /// Triangles.
    pub triangles: u32,
}

/// A polygonized surface: positions, outward normals, colours and the largest ball at each
/// vertex, and triangles wound counter-clockwise from outside: [`Self::BYTES`] = `29·V + 6·T`
/// bytes plus two counters (`usize`), rounded up to 4.
pub struct PolyMesh<const V: usize, const T: usize> {
    vertices: [Vertex; V],
    normals: [Vertex; V],
    colors: [Rgb888; V],
    balls: [u8; V],
    triangles: [[u16; 3]; T],
    vertex_count: usize,
    triangle_count: usize,
}

impl<const V: usize, const T: usize> Default for PolyMesh<V, T> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const V: usize, const T: usize> PolyMesh<V, T> {
    /// Size in bytes.
    pub const BYTES: usize = core::mem::size_of::<Self>();

    /// An empty mesh.
    pub const fn new() -> Self {
        PolyMesh {
            vertices: [[Coord::ZERO; 3]; V],
            normals: [[Coord::ZERO; 3]; V],
            colors: [Rgb888::new(0, 0, 0); V],
            balls: [0; V],
            triangles: [[0; 3]; T],
            vertex_count: 0,
            triangle_count: 0,
        }
    }

    /// The vertices (I16F16 world coordinates).
    pub fn vertices(&self) -> &[Vertex] {
        self.vertices.get(..self.vertex_count).unwrap_or(&[])
    }

    /// The triangles, counter-clockwise seen from outside the surface.
    pub fn triangles(&self) -> &[[u16; 3]] {
        self.triangles.get(..self.triangle_count).unwrap_or(&[])
    }

    /// Per vertex: the ball with the largest `q·f` there (its index in the scene).
    pub fn vertex_balls(&self) -> &[u8] {
        self.balls.get(..self.vertex_count).unwrap_or(&[])
    }

    /// The renderer's mesh: per-vertex colours and outward normals (for Gouraud shading).
    pub fn mesh(&self) -> Result<Mesh<'_>, SceneError> {
        let n = self.vertex_count;
        Mesh::new(
            self.vertices(),
            self.triangles(),
            MeshColors::PerVertex(self.colors.get(..n).unwrap_or(&[])),
            Some(self.normals.get(..n).unwrap_or(&[])),
        )
    }

    /// Makes the surface face inward, for an eye inside it: every normal negated and every
    /// triangle wound the other way (back-face culling then keeps the faces seen from inside).
    pub fn turn_inside_out(&mut self) {
        let n = self.vertex_count;
        for normal in self.normals.iter_mut().take(n) {
            *normal = normal.map(|c| c.saturating_neg());
        }
        let t = self.triangle_count;
        for triangle in self.triangles.iter_mut().take(t) {
            triangle.swap(1, 2);
        }
    }

    fn clear(&mut self) {
        self.vertex_count = 0;
        self.triangle_count = 0;
    }

    fn push_vertex(
        &mut self,
        position: Vertex,
        normal: Vertex,
        color: Rgb888,
        ball: u8,
    ) -> Result<u16, PolygonizeError> {
        let index = self.vertex_count;
        let id = u16::try_from(index)
            .ok()
            .filter(|&i| i != NONE)
            .ok_or(PolygonizeError::Vertices)?;
        let (Some(v), Some(n), Some(c), Some(b)) = (
            self.vertices.get_mut(index),
            self.normals.get_mut(index),
            self.colors.get_mut(index),
            self.balls.get_mut(index),
        ) else {
            return Err(PolygonizeError::Vertices);
        };
        (*v, *n, *c, *b) = (position, normal, color, ball);
        self.vertex_count += 1;
        Ok(id)
    }

    fn push_triangle(&mut self, triangle: [u16; 3]) -> Result<(), PolygonizeError> {
        let slot = self
            .triangles
            .get_mut(self.triangle_count)
            .ok_or(PolygonizeError::Triangles)?;
        *slot = triangle;
        self.triangle_count += 1;
        Ok(())
    }
}

/// Per ball and frame, what every sample reuses.
#[derive(Clone, Copy, Debug)]
struct GridBall {
    centre: [Wide; 3],
    radius: Wide,
    inv_r2: Wide,
    density: Wide,
    color: Rgb888,
}

impl GridBall {
    const EMPTY: GridBall = GridBall {
        centre: [Wide::ZERO; 3],
        radius: Wide::ZERO,
        inv_r2: Wide::ZERO,
        density: Wide::ZERO,
        color: Rgb888::new(0, 0, 0),
    };

    fn new(ball: &Ball) -> Self {
        let radius = Wide::from(ball.radius);
        GridBall {
            centre: ball.centre.map(Wide::from),
            radius,
            inv_r2: quotient(Wide::ONE, mul(radius, radius)).unwrap_or(Wide::ZERO),
            density: Wide::from(ball.density),
            color: ball.color,
        }
    }

    /// `s = |p − c|²/R²` and `p − c` where `p` is inside the influence sphere.
    #[inline]
    fn at(&self, p: [Wide; 3]) -> Option<(Wide, [Wide; 3])> {
        let offset = zip3(p, self.centre, |p, c| p - c);
        if offset.iter().any(|o| o.abs() >= self.radius) {
            return None;
        }
        let r2 = mul(offset[0], offset[0]) + mul(offset[1], offset[1]) + mul(offset[2], offset[2]);
        let s = mul(r2, self.inv_r2);
        (s < Wide::ONE).then_some((s, offset))
    }
}

/// The sample lattice: grid point `(i, j, k)` is `origin + (i, j, k)·step`.
#[derive(Clone, Copy, Debug)]
struct Lattice {
    origin: [Wide; 3],
    step: [Wide; 3],
}

impl Lattice {
    fn point(&self, index: [usize; 3]) -> [Wide; 3] {
        let steps = zip3(self.step, index, |s, i| s.saturating_mul_int(i as i64));
        zip3(self.origin, steps, |o, s| o + s)
    }
}

/// The polygonizer's memory for a grid of `S` samples per axis and up to `N` balls: two layers
/// of samples and the crossings of the edges in both layers and between them:
/// [`Self::BYTES`] = `28·S² + 56·N` bytes (rounded up to 8), whatever the scene.
pub struct Polygonizer<const S: usize, const N: usize> {
    balls: [GridBall; N],
    /// `g` at the grid points of layers `z` and `z + 1` (by parity of the layer).
    samples: [[[Coord; S]; S]; 2],
    /// Vertex index of the crossing on the in-layer edges `+x`, `+y`, `+x+y` (by parity).
    in_layer: [[[[u16; 3]; S]; S]; 2],
    /// Vertex index of the crossing on the edges to the next layer: `+z`, `+x+z`, `+y+z`, `+x+y+z`.
    between: [[[u16; 4]; S]; S],
}

impl<const S: usize, const N: usize> Default for Polygonizer<S, N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const S: usize, const N: usize> Polygonizer<S, N> {
    /// Size in bytes.
    pub const BYTES: usize = core::mem::size_of::<Self>();

    /// An empty polygonizer.
    pub const fn new() -> Self {
        Polygonizer {
            balls: [GridBall::EMPTY; N],
            samples: [[[Coord::ZERO; S]; S]; 2],
            in_layer: [[[[NONE; 3]; S]; S]; 2],
            between: [[[NONE; 4]; S]; S],
        }
    }

    /// Polygonizes `scene` into `mesh` (replacing what it held).
    pub fn polygonize<const V: usize, const T: usize>(
        &mut self,
        scene: &Metaballs<'_>,
        mesh: &mut PolyMesh<V, T>,
    ) -> Result<PolyStats, PolygonizeError> {
        mesh.clear();
        if !(2..=MAX_SAMPLES).contains(&S) {
            return Err(PolygonizeError::Grid);
        }
        let count = scene.balls().len();
        if count > N {
            return Err(PolygonizeError::Balls);
        }
        for (slot, ball) in self.balls.iter_mut().zip(scene.balls()) {
            *slot = GridBall::new(ball);
        }
        let threshold = Wide::from(scene.threshold());
        let Some(lattice) = lattice::<S>(self.balls.get(..count).unwrap_or(&[])) else {
            return Ok(PolyStats::default());
        };
        let work = Work {
            balls: self.balls.get(..count).unwrap_or(&[]),
            threshold,
            lattice,
        };
        let mut stats = PolyStats::default();
        let [first_samples, _] = &mut self.samples;
        work.sample_layer(0, first_samples);
        let [first_crossings, _] = &mut self.in_layer;
        work.cross_layer(0, first_samples, first_crossings, mesh)?;
        for z in 0..S - 1 {
            let [below, above] = layers(&mut self.samples, z & 1);
            work.sample_layer(z + 1, above);
            let [in_below, in_above] = layers(&mut self.in_layer, z & 1);
            work.cross_layer(z + 1, above, in_above, mesh)?;
            work.cross_between(z, below, above, &mut self.between, mesh)?;
            let cells = Cells {
                samples: [&*below, &*above],
                in_layer: [&*in_below, &*in_above],
                between: &self.between,
            };
            cells.triangulate(mesh)?;
        }
        stats.samples = (S * S * S) as u32;
        stats.vertices = mesh.vertex_count as u32;
        stats.triangles = mesh.triangle_count as u32;
        Ok(stats)
    }
}

/// Both elements of a pair, `first` first, mutably.
fn layers<X>(pair: &mut [X; 2], first: usize) -> [&mut X; 2] {
    let [a, b] = pair;
    if first == 0 {
        [a, b]
    } else {
        [b, a]
    }
}

/// The lattice over the influence spheres of the positive balls (the surface, where
/// `Σ q·f > T > 0`, needs one), padded by 1/64 so the boundary samples are all outside; `None`
/// when no ball is positive.
fn lattice<const S: usize>(balls: &[GridBall]) -> Option<Lattice> {
    let pad = Wide::from_num(1) / 64;
    let mut low = [Wide::MAX; 3];
    let mut high = [Wide::MIN; 3];
    for ball in balls.iter().filter(|b| b.density > Wide::ZERO) {
        for i in 0..3 {
            low[i] = low[i].min(ball.centre[i] - ball.radius - pad);
            high[i] = high[i].max(ball.centre[i] + ball.radius + pad);
        }
    }
    if low[0] > high[0] {
        return None;
    }
    let cells = Wide::from_num(S.saturating_sub(1).max(1) as i32);
    let step = zip3(high, low, |h, l| {
        quotient(h - l, cells).unwrap_or(Wide::ZERO)
    });
    Some(Lattice { origin: low, step })
}

/// A frame's balls and lattice.
#[derive(Clone, Copy)]
struct Work<'a> {
    balls: &'a [GridBall],
    threshold: Wide,
    lattice: Lattice,
}

impl Work<'_> {
    /// `g = Σ q·f − T` at `p`.
    fn g(&self, p: [Wide; 3]) -> Wide {
        self.balls
            .iter()
            .filter_map(|b| b.at(p).map(|(s, _)| mul(b.density, field(s))))
            .fold(-self.threshold, |acc, v| acc + v)
    }

    fn sample_layer<const S: usize>(&self, z: usize, layer: &mut [[Coord; S]; S]) {
        for (y, row) in layer.iter_mut().enumerate() {
            for (x, sample) in row.iter_mut().enumerate() {
                let g = self.g(self.lattice.point([x, y, z]));
                // I32F32 to I16F16, rounded down; |g| < 2^13 by the bit budget.
                *sample = Coord::from_bits((g.to_bits() >> 16) as i32);
            }
        }
    }

    /// The crossings of the edges `+x`, `+y`, `+x+y` within layer `z`.
    fn cross_layer<const S: usize, const V: usize, const T: usize>(
        &self,
        z: usize,
        samples: &[[Coord; S]; S],
        crossings: &mut [[[u16; 3]; S]; S],
        mesh: &mut PolyMesh<V, T>,
    ) -> Result<(), PolygonizeError> {
        for (y, row) in crossings.iter_mut().enumerate() {
            for (x, edges) in row.iter_mut().enumerate() {
                for (edge, d) in edges.iter_mut().zip([1u8, 2, 3]) {
                    let end = [x + usize::from(d & 1), y + usize::from(d >> 1 & 1)];
                    let (Some(a), Some(b)) = (at(samples, x, y), at(samples, end[0], end[1]))
                    else {
                        *edge = NONE;
                        continue;
                    };
                    *edge = self.crossing([x, y, z], d, a, b, mesh)?;
                }
            }
        }
        Ok(())
    }

    /// The crossings of the edges from layer `z` to `z + 1`.
    fn cross_between<const S: usize, const V: usize, const T: usize>(
        &self,
        z: usize,
        below: &[[Coord; S]; S],
        above: &[[Coord; S]; S],
        crossings: &mut [[[u16; 4]; S]; S],
        mesh: &mut PolyMesh<V, T>,
    ) -> Result<(), PolygonizeError> {
        for (y, row) in crossings.iter_mut().enumerate() {
            for (x, edges) in row.iter_mut().enumerate() {
                for (edge, d) in edges.iter_mut().zip([4u8, 5, 6, 7]) {
                    let end = [x + usize::from(d & 1), y + usize::from(d >> 1 & 1)];
                    let (Some(a), Some(b)) = (at(below, x, y), at(above, end[0], end[1])) else {
                        *edge = NONE;
                        continue;
                    };
                    *edge = self.crossing([x, y, z], d, a, b, mesh)?;
                }
            }
        }
        Ok(())
    }

    /// The mesh vertex where the edge from grid point `base` along corner offset `d` crosses the
    /// surface, or [`NONE`]. Inside is `g > 0`.
    fn crossing<const V: usize, const T: usize>(
        &self,
        base: [usize; 3],
        d: u8,
        a: Coord,
        b: Coord,
        mesh: &mut PolyMesh<V, T>,
    ) -> Result<u16, PolygonizeError> {
        if (a > Coord::ZERO) == (b > Coord::ZERO) {
            return Ok(NONE);
        }
        // t = a/(a − b) in [0, 1] as I32F32; a − b ≠ 0 as the signs differ.
        let (a64, b64) = (i64::from(a.to_bits()), i64::from(b.to_bits()));
        let t = Wide::from_bits((a64 << 32).checked_div(a64 - b64).unwrap_or(0));
        let start = self.lattice.point(base);
        let p = zip3(
            zip3(start, self.lattice.step, |s, st| (s, st)),
            [1, 2, 4],
            |(s, st), bit| {
                if d & bit != 0 {
                    s + mul(t, st)
                } else {
                    s
                }
            },
        );
        // Outward: from the inside end towards the outside end, the fallback normal.
        let sign = if a > Coord::ZERO {
            Wide::ONE
        } else {
            -Wide::ONE
        };
        let along = [0, 1, 2].map(|i| if d >> i & 1 == 1 { sign } else { Wide::ZERO });
        let (normal, color, ball) = self.attributes(p, along);
        mesh.push_vertex(p.map(round_coord), normal, color, ball)
    }

    /// The outward normal (`−∇g`, largest component ±1), blended colour and largest ball at `p`.
    fn attributes(&self, p: [Wide; 3], fallback: [Wide; 3]) -> (Vertex, Rgb888, u8) {
        let mut gradient = [Wide::ZERO; 3];
        let mut blend = Blend::new();
        for (index, ball) in self.balls.iter().enumerate() {
            let Some((s, offset)) = ball.at(p) else {
                continue;
            };
            blend.add(mul(ball.density, field(s)), index, ball.color);
            // ∇(q·f(s)) = q·f'(s)·2(p − c)/R².
            let k = mul(mul(ball.density, field_slope(s)), ball.inv_r2) * 2;
            for (g, o) in gradient.iter_mut().zip(offset) {
                *g += mul(k, o);
            }
        }
        let outward = gradient.map(|g| -g);
        let largest = outward.iter().map(|g| g.abs()).max().unwrap_or(Wide::ZERO);
        let normal = match quotient(Wide::ONE, largest) {
            Some(inverse) if largest > Wide::ZERO => outward.map(|g| round_coord(mul(g, inverse))),
            _ => fallback.map(round_coord),
        };
        let (color, ball) = blend.finish(Wide::ONE, self.balls.iter().map(|b| b.color));
        (normal, color, ball)
    }
}

/// I32F32 to I16F16, rounded to nearest (coordinates within the bit budget).
fn round_coord(v: Wide) -> Coord {
    Coord::from_bits(((v.to_bits() + (1 << 15)) >> 16) as i32)
}

fn at<X: Copy, const S: usize>(grid: &[[X; S]; S], x: usize, y: usize) -> Option<X> {
    grid.get(y)?.get(x).copied()
}

/// One slab of cells between two sample layers, with the crossings of all its edges.
struct Cells<'a, const S: usize> {
    samples: [&'a [[Coord; S]; S]; 2],
    in_layer: [&'a [[[u16; 3]; S]; S]; 2],
    between: &'a [[[u16; 4]; S]; S],
}

impl<const S: usize> Cells<'_, S> {
    fn triangulate<const V: usize, const T: usize>(
        &self,
        mesh: &mut PolyMesh<V, T>,
    ) -> Result<(), PolygonizeError> {
        for y in 0..S - 1 {
            for x in 0..S - 1 {
                let inside = [0u8, 1, 2, 3, 4, 5, 6, 7].map(|c| {
                    let [cx, cy, cz] = corner(c);
                    let layer = self.samples.get(cz as usize).copied();
                    layer
                        .and_then(|l| at(l, x + cx as usize, y + cy as usize))
                        .is_some_and(|g| g > Coord::ZERO)
                });
                if inside.iter().all(|&i| i) || inside.iter().all(|&i| !i) {
                    continue;
                }
                for tet in TETRAHEDRA {
                    self.tetrahedron(x, y, tet, inside, mesh)?;
                }
            }
        }
        Ok(())
    }

    fn tetrahedron<const V: usize, const T: usize>(
        &self,
        x: usize,
        y: usize,
        tet: [u8; 4],
        inside: [bool; 8],
        mesh: &mut PolyMesh<V, T>,
    ) -> Result<(), PolygonizeError> {
        let is_in = |c: u8| inside.get(usize::from(c)).copied().unwrap_or(false);
        // The corners inside first, in tetrahedron order, then those outside.
        let mut order = tet
            .iter()
            .copied()
            .filter(|&c| is_in(c))
            .chain(tet.iter().copied().filter(|&c| !is_in(c)));
        let [a, b, c, d] = [(); 4].map(|_| order.next().unwrap_or(0));
        match tet.iter().filter(|&&c| is_in(c)).count() {
            1 => self.triangle(x, y, [[a, b], [a, c], [a, d]], a, mesh),
            3 => self.triangle(x, y, [[a, d], [b, d], [c, d]], a, mesh),
            2 => {
                // Two in (a, b), two out (c, d): the quad ac, ad, bd, bc as two triangles.
                self.triangle(x, y, [[a, c], [a, d], [b, d]], a, mesh)?;
                self.triangle(x, y, [[a, c], [b, d], [b, c]], a, mesh)
            }
            _ => Ok(()),
        }
    }

    /// Emits the triangle through the crossings of three tetrahedron edges (corner pairs),
    /// wound counter-clockwise seen from outside: its normal must point away from the inside
    /// corner `inner`. The winding is decided on the edges' midpoints, in integers: moving the
    /// crossings along their edges never makes these triangles degenerate, so the sign is the
    /// real triangle's.
    fn triangle<const V: usize, const T: usize>(
        &self,
        x: usize,
        y: usize,
        edges: [[u8; 2]; 3],
        inner: u8,
        mesh: &mut PolyMesh<V, T>,
    ) -> Result<(), PolygonizeError> {
        let mid = edges.map(|[p, q]| {
            let (p, q) = (corner(p), corner(q));
            [p[0] + q[0], p[1] + q[1], p[2] + q[2]]
        });
        let [m0, m1, m2] = mid;
        let (e1, e2) = (zip3(m1, m0, |a, b| a - b), zip3(m2, m0, |a, b| a - b));
        let n = [
            e1[1] * e2[2] - e1[2] * e2[1],
            e1[2] * e2[0] - e1[0] * e2[2],
            e1[0] * e2[1] - e1[1] * e2[0],
        ];
        let to_inner = zip3(corner(inner), m0, |c, m| 2 * c - m);
        let [t0, t1, t2] = zip3(n, to_inner, |n, d| n * d);
        let towards_inner = t0 + t1 + t2;
        let mut ids = [NONE; 3];
        for (id, [p, q]) in ids.iter_mut().zip(edges) {
            *id = self.edge(x, y, p, q);
        }
        if ids.contains(&NONE) {
            // Cannot happen: the two ends of each edge are on opposite sides.
            return Err(PolygonizeError::Vertices);
        }
        if towards_inner > 0 {
            ids.swap(1, 2);
        }
        mesh.push_triangle(ids)
    }

    /// The crossing on the cell edge between corners `p` and `q` (one a subset of the other).
    fn edge(&self, x: usize, y: usize, p: u8, q: u8) -> u16 {
        let (low, high) = if p & q == p { (p, q) } else { (q, p) };
        let d = high ^ low;
        let [lx, ly, lz] = corner(low);
        let (gx, gy) = (x + lx as usize, y + ly as usize);
        let found = if d & 4 != 0 {
            at(self.between, gx, gy).and_then(|e| e.get(usize::from(d - 4)).copied())
        } else {
            self.in_layer
                .get(lz as usize)
                .and_then(|layer| at(layer, gx, gy))
                .and_then(|e| e.get(usize::from(d).wrapping_sub(1)).copied())
        };
        found.unwrap_or(NONE)
    }
}

/// Corner bits to offsets `[x, y, z]`.
fn corner(c: u8) -> [i32; 3] {
    [
        i32::from(c & 1),
        i32::from(c >> 1 & 1),
        i32::from(c >> 2 & 1),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tetrahedra_fill_the_cell_and_share_faces() {
        // Six tetrahedra of volume 1/6 each, all positively oriented chains 0 → 7.
        for tet in TETRAHEDRA {
            let [a, b, c, d] = tet.map(corner);
            let e = [b, c, d].map(|p| [0, 1, 2].map(|i| p[i] - a[i]));
            let det = e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1])
                - e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0])
                + e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0]);
            assert_eq!(det.abs(), 1, "{tet:?}");
            // Every edge joins a corner to a superset corner: it has a (grid point, offset) name.
            for i in 0..4 {
                for j in i + 1..4 {
                    assert_eq!(tet[i] & tet[j], tet[i]);
                }
            }
        }
    }

    #[test]
    fn memory_is_as_documented() {
        assert_eq!(
            Polygonizer::<17, 6>::BYTES,
            (28 * 17 * 17 + 56 * 6usize).next_multiple_of(8)
        );
        assert_eq!(
            Polygonizer::<33, 1>::BYTES,
            (28 * 33 * 33 + 56usize).next_multiple_of(8)
        );
        let counters = 2 * core::mem::size_of::<usize>();
        for (bytes, v, t) in [
            (PolyMesh::<2048, 4096>::BYTES, 2048, 4096),
            (PolyMesh::<5, 3>::BYTES, 5, 3),
        ] {
            assert_eq!(
                bytes,
                (29 * v + 6 * t + counters).next_multiple_of(counters / 2)
            );
        }
    }

    #[test]
    fn grid_size_and_capacity_errors() {
        let ball = [Ball::new([0.0; 3], 1.0, 1.0, Rgb888::new(1, 2, 3))];
        let scene = Metaballs::new(&ball, Coord::from_num(0.5)).unwrap();
        let mut mesh: PolyMesh<4, 4> = PolyMesh::new();
        assert_eq!(
            Polygonizer::<1, 1>::new().polygonize(&scene, &mut mesh),
            Err(PolygonizeError::Grid)
        );
        assert_eq!(
            Polygonizer::<8, 1>::new().polygonize(&scene, &mut mesh),
            Err(PolygonizeError::Vertices)
        );
        let mut roomy: PolyMesh<1024, 4> = PolyMesh::new();
        assert_eq!(
            Polygonizer::<8, 1>::new().polygonize(&scene, &mut roomy),
            Err(PolygonizeError::Triangles)
        );
        let two = [ball[0]; 2];
        let scene = Metaballs::new(&two, Coord::from_num(0.5)).unwrap();
        assert_eq!(
            Polygonizer::<8, 1>::new().polygonize(&scene, &mut roomy),
            Err(PolygonizeError::Balls)
        );
    }
}
