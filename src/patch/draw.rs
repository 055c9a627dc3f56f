//! The patch renderer: patches filed under their first row, tessellated and split as the rows
//! come, their triangles walked by the span z-buffer.
//!
//! # Memory (bytes)
//!
//! `4·W` depth row + `size_of::<P>()·W` pixels + `2·H` bucket heads + `SUBS ·` (an entry and
//! its link, 16) for patches and pieces waiting in buckets + `ACTIVE ·` an active triangle
//! (about 100 for flat shading).
//! See [`PatchWorkspace::BYTES`].

use super::eval::{dehomogenize, Column, Hom, Net, TangentColumn};
use super::tessellate::{self, Levels, ScreenNet, Uv};
use super::trim::{self, Cut};
use super::{PatchModel, Tolerance};
use crate::arithmetic::Arithmetic;
use crate::cache::CachedVertex;
use crate::clip::{ClipVertex, Clipped, Clipping};
use crate::depth::Depth;
use crate::math::{floor_div_i64, mul_i64};
use crate::options::RenderOptions;
use crate::project::{ScreenVertex, Viewport};
use crate::raster::{color_channels, first_row, signed_area, xy, TriangleWalk};
use crate::render::{walk_rows, ActiveTri, RowPieces, NO_ENTRY};
use crate::scene::{Camera, Light, Transform};
use crate::shading::Shading;
use crate::sink::{RowPixel, RowSink};
use crate::stats::{CapacityKind, FrameStats, RenderError};
use crate::vertex::{EyePoint, Lighting, ModelView, TransformPrecision};
use crate::workspace::SpanZBuffer;
use embedded_graphics::pixelcolor::Rgb888;
use fixed::types::I16F16;
use heapless::Vec;

/// A patch model placed in the world and seen by a camera.
#[derive(Clone, Copy, Debug)]
pub struct PatchScene<'a> {
    /// The patches.
    pub model: &'a PatchModel<'a>,
    /// Model to world.
    pub transform: Transform,
    /// The camera.
    pub camera: Camera,
    /// The light.
    pub light: Light,
}

/// What one patch frame did: the triangle pipeline's [`FrameStats`] (its `triangles_in` are
/// the triangles tessellation made) and the patch stages' counts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PatchStats {
    /// The triangle pipeline's statistics.
    pub frame: FrameStats,
    /// Patches whose control hull is off screen, behind the near plane or beyond the far
    /// plane: never tessellated.
    pub patches_culled: u32,
    /// Pieces taken from the row buckets: boundary strips (four per patch) and interior
    /// pieces (each patch's whole interior counts one).
    pub pieces: u32,
    /// Boundary strips and interior pieces dropped because their control hull is off screen.
    pub pieces_culled: u32,
    /// Splits not made because `SUBS` was full: that piece was tessellated at once, so its
    /// triangles wait on the active list longer (the image is the same unless `ACTIVE`
    /// overflows too, which `frame.dropped` reports).
    pub overflows: u32,
    /// Patches drawn coarser than the tolerance asks: some level reached
    /// [`MAX_LEVEL`](super::MAX_LEVEL), or a control point was not in front of the near plane
    /// (drawn at the finest level).
    pub capped: u32,
    /// Triangles that began above the row that made them (the rows above were lost). The
    /// control-hull bound makes this 0; it is counted so a test can hold it to that.
    pub late: u32,
    /// Tessellation triangles that trim edges touch, cut in parameter space.
    pub trim_cut: u32,
    /// Triangles (or parts of one) that needed more than `TRIM` boundary points or waiting
    /// triangles to cut: kept or dropped whole by the parity of their centroid instead.
    pub trim_overflows: u32,
}

/// A patch or a piece of it waiting in a row bucket.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Entry {
    patch: u16,
    work: Work,
}

/// What of a patch an [`Entry`] stands for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Work {
    /// The whole patch, not tessellated yet.
    Patch,
    /// The boundary strip on `side` (the order of [`Levels::edges`]) of a patch tessellated
    /// at these levels: the zipper between that edge and the first inner grid line.
    Side(Levels, u8),
    /// Interior cells of a patch.
    Cells(Piece),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Piece {
    levels: Levels,
    is: [u8; 2],
    js: [u8; 2],
}

const EMPTY: Entry = Entry {
    patch: 0,
    work: Work::Patch,
};

/// Pieces of at most this many cells are tessellated, not split further: a split costs two
/// control-hull bounds (sub-nets by blossoming, 16 transforms and projections each), more than
/// a few triangles. Against 4 cells, 16 took 31 % fewer host instructions for the firmware's
/// teapot frames at 0.5 px; the triangles made earlier wait longer on the active list.
const LEAF_CELLS: u32 = 16;

/// Columns of cells drawn at a time: two rows of `BLOCK + 1` vertices are on the stack.
const BLOCK: usize = 8;

/// No flat colour (Gouraud shading colours vertices instead).
const BLACK_SIDES: Sides<Rgb888> = Sides {
    front: Rgb888::new(0, 0, 0),
    back: Rgb888::new(0, 0, 0),
};

/// All the memory a patch render needs, sized at compile time.
///
/// * `P`, `S`: pixel type and shading, as for [`Workspace`](crate::Workspace);
/// * `W × H`: the target size (1..=2048 each);
/// * `SUBS`: patches and interior pieces that may wait in row buckets at once: at least the
///   patches on screen (else [`RenderError::Capacity`] before any row is sent); beyond that,
///   more room lets pieces be split finer so their triangles are made nearer their rows.
///   When full, a piece is tessellated whole and [`PatchStats::overflows`] counts it;
/// * `ACTIVE`: triangles that may be on the active list at once (more are dropped and
///   reported, as for meshes);
/// * `TRIM`: room to cut one tessellation triangle by trim loops (boundary points: its corners
///   and two per trim edge crossing it; triangles waiting after splits at trim vertices), on
///   the stack while a trimmed triangle is cut: about `125·TRIM` bytes on a 32-bit target.
///   A triangle that needs more is kept or dropped whole and [`PatchStats::trim_overflows`]
///   counts it. `TRIM` = 0 leaves the trim code out of the build (a firmware whose models
///   have no trims carries none): such a workspace rejects a model with trim loops
///   ([`RenderError::Capacity`] of [`CapacityKind::Trims`]).
pub struct PatchWorkspace<
    P: RowPixel,
    S: Shading,
    const W: usize,
    const H: usize,
    const SUBS: usize = 256,
    const ACTIVE: usize = 256,
    const TRIM: usize = 64,
> {
    depth: [Depth; W],
    pixels: [P; W],
    background: P,
    heads: [u16; H],
    next: [u16; SUBS],
    entries: [Entry; SUBS],
    active: Vec<ActiveTri<S::Payload<P>>, ACTIVE>,
}

impl<
        P: RowPixel,
        S: Shading,
        const W: usize,
        const H: usize,
        const SUBS: usize,
        const ACTIVE: usize,
        const TRIM: usize,
    > PatchWorkspace<P, S, W, H, SUBS, ACTIVE, TRIM>
{
    /// Size of this workspace in bytes.
    pub const BYTES: usize = core::mem::size_of::<Self>();

    const VALID: () = {
        assert!(
            W >= 1 && W <= crate::project::MAX_SCREEN,
            "width must be 1..=2048"
        );
        assert!(
            H >= 1 && H <= crate::project::MAX_SCREEN,
            "height must be 1..=2048"
        );
        assert!(SUBS < NO_ENTRY as usize, "SUBS must be below 65535");
    };

    /// An empty workspace whose background pixels are `background`.
    pub const fn new(background: P) -> Self {
        #[allow(clippy::let_unit_value)]
        let () = Self::VALID;
        PatchWorkspace {
            depth: [Depth::ZERO; W],
            pixels: [background; W],
            background,
            heads: [NO_ENTRY; H],
            next: [NO_ENTRY; SUBS],
            entries: [EMPTY; SUBS],
            active: Vec::new(),
        }
    }

    /// Renders `scene` with flatness `tolerance` (pixels; below one sub-pixel counts as one),
    /// handing each of the `H` rows to `sink` once, top to bottom.
    pub fn render<const SUB: u32, C: Clipping, A: Arithmetic, K: RowSink<P>>(
        &mut self,
        scene: &PatchScene<'_>,
        options: &RenderOptions<SUB, C, A>,
        tolerance: Tolerance,
        sink: &mut K,
    ) -> Result<PatchStats, RenderError<K::Error>> {
        self.render_sized(W, H, scene, options, tolerance, sink)
    }

    /// Renders a `width × height` target (at most `W × H`; else
    /// [`RenderError::InvalidTarget`]), as [`Self::render`] does the whole one.
    pub fn render_sized<const SUB: u32, C: Clipping, A: Arithmetic, K: RowSink<P>>(
        &mut self,
        width: usize,
        height: usize,
        scene: &PatchScene<'_>,
        options: &RenderOptions<SUB, C, A>,
        tolerance: Tolerance,
        sink: &mut K,
    ) -> Result<PatchStats, RenderError<K::Error>> {
        let camera = &scene.camera;
        let (Some(depth), Some(pixels), Some(heads)) = (
            self.depth.get_mut(..width),
            self.pixels.get_mut(..width),
            self.heads.get_mut(..height),
        ) else {
            return Err(RenderError::InvalidTarget);
        };
        let vp = Viewport::<SUB>::new(width, height, camera.focal(), camera.near(), camera.far())
            .ok_or(RenderError::InvalidTarget)?;
        let model = scene.model;
        if TRIM == 0 && !model.trim_loops().is_empty() {
            return Err(RenderError::Capacity {
                what: CapacityKind::Trims,
                needed: model.trim_loops().len(),
                capacity: 0,
            });
        }
        let bits = model.max_abs_bits();
        let mv = ModelView::new(&scene.transform, &camera.view().world_to_eye, bits)
            .map_err(|error| RenderError::Transform { instance: 0, error })?;
        let mut rows = PatchRows::<SUB, C, A, TRIM> {
            model,
            mv: A::Transform::prepare(mv, bits),
            lighting: Lighting::new(&scene.light, &scene.transform),
            vp,
            heads,
            next: &mut self.next,
            entries: &mut self.entries,
            free: 0,
            tolerance: ((tolerance.to_bits() as i64) << SUB >> 8).max(1),
            cull: options.cull_back_faces,
            polygon: C::Polygon::default(),
            stats: PatchStats::default(),
            clipping: core::marker::PhantomData,
        };
        rows.file_patches()?;
        let mut resolve = SpanZBuffer::new(depth, pixels, self.background);
        let mut frame = FrameStats::default();
        walk_rows::<P, S, SUB, K, _, _>(
            height,
            self.active.as_mut_view(),
            &mut rows,
            &mut resolve,
            width as i32,
            sink,
            &mut frame,
        )?;
        let mut stats = rows.stats;
        let counts = stats.frame;
        stats.frame = FrameStats {
            triangles_in: counts.triangles_in,
            culled: counts.culled,
            clipped: counts.clipped,
            rejected: counts.rejected,
            unclipped: counts.unclipped,
            bucketed: counts.bucketed,
            ..frame
        };
        Ok(stats)
    }
}

/// Where a control hull lies.
enum Hull {
    /// Off screen, behind the near plane or beyond the far plane.
    Culled,
    /// No triangle of the surface inside starts above this row.
    FirstRow(usize),
}

/// The frame's patch state: what pass 2 activates row by row.
struct PatchRows<'a, 'm, const SUB: u32, C: Clipping, A: Arithmetic, const TRIM: usize> {
    model: &'m PatchModel<'m>,
    mv: <A::Transform as TransformPrecision>::Matrix,
    lighting: Lighting,
    vp: Viewport<SUB>,
    heads: &'a mut [u16],
    next: &'a mut [u16],
    entries: &'a mut [Entry],
    /// Head of the free-entry list (threaded through `next`).
    free: u16,
    /// Flatness tolerance in sub-pixels.
    tolerance: i64,
    cull: bool,
    polygon: C::Polygon,
    stats: PatchStats,
    clipping: core::marker::PhantomData<C>,
}

impl<'m, const SUB: u32, C: Clipping, A: Arithmetic, const TRIM: usize>
    PatchRows<'_, 'm, SUB, C, A, TRIM>
{
    /// Pass 1: every patch whose control hull is on screen goes into the bucket of the hull's
    /// first row, in reverse order so each bucket lists patches in ascending order.
    fn file_patches<E>(&mut self) -> Result<(), RenderError<E>> {
        self.heads.fill(NO_ENTRY);
        let capacity = self.next.len();
        for (k, link) in self.next.iter_mut().enumerate() {
            *link = if k + 1 < capacity {
                (k + 1) as u16
            } else {
                NO_ENTRY
            };
        }
        self.free = if capacity > 0 { 0 } else { NO_ENTRY };
        let count = self.model.points().len();
        let mut needed = 0;
        for patch in (0..count).rev() {
            match self.hull(&Net::of(self.model, patch)) {
                Hull::Culled => self.stats.patches_culled += 1,
                Hull::FirstRow(row) => {
                    needed += 1;
                    let entry = Entry {
                        // Below MAX_PATCHES, checked by PatchModel::new.
                        patch: patch as u16,
                        work: Work::Patch,
                    };
                    // Filing fails only when full; the error below reports it.
                    let _ = self.file(entry, row);
                }
            }
        }
        if needed > capacity {
            return Err(RenderError::Capacity {
                what: CapacityKind::Patches,
                needed,
                capacity,
            });
        }
        Ok(())
    }

    /// Puts `entry` in `row`'s bucket; `false` if no entry is free.
    fn file(&mut self, entry: Entry, row: usize) -> bool {
        let slot = self.free;
        let (Some(e), Some(link), Some(head)) = (
            self.entries.get_mut(slot as usize),
            self.next.get_mut(slot as usize),
            self.heads.get_mut(row),
        ) else {
            return false;
        };
        *e = entry;
        self.free = *link;
        *link = *head;
        *head = slot;
        true
    }

    /// Takes the first entry of `row`'s bucket, freeing its slot.
    fn take(&mut self, row: usize) -> Option<Entry> {
        let head = self.heads.get_mut(row)?;
        let slot = *head;
        let (Some(&entry), Some(link)) = (
            self.entries.get(slot as usize),
            self.next.get_mut(slot as usize),
        ) else {
            return None;
        };
        *head = *link;
        *link = self.free;
        self.free = slot;
        Some(entry)
    }

    /// The trim loops of `patch`: none without room to cut (`TRIM` = 0, whose workspace
    /// rejects trimmed models), so the trim code is left out of such a build.
    fn trims(&self, patch: u16) -> trim::Trims<'m> {
        if TRIM == 0 {
            return trim::Trims::NONE;
        }
        self.model.trims(patch as usize)
    }

    /// A model point in eye space.
    #[inline]
    fn eye(&self, h: Hom) -> EyePoint {
        A::Transform::apply(&self.mv, &dehomogenize(h))
    }

    /// Screen position (sub-pixels, unrounded range) of an eye point in front of the near
    /// plane; `None` otherwise.
    fn screen(&self, p: &EyePoint) -> Option<[i64; 2]> {
        let d = self.vp.clip_distances(p);
        if d[0] <= 0 {
            return None;
        }
        let w = p.w.to_bits() as i64;
        // The guard planes are g·w ± n: their difference gives n = ax·x (or ay·y) exactly.
        let (nx, ny) = ((d[2] - d[3]) / 2, (d[5] - d[4]) / 2);
        let cx = (self.vp.width as i64) << SUB;
        let cy = (self.vp.height as i64) << SUB;
        // w > near > 0 here, so `floor_div_i64` is `div_euclid` (by 32-bit divisions).
        let div = |n: i64| floor_div_i64(n, 2 * w);
        Some([div(mul_i64(cx, w) + 2 * nx), div(mul_i64(cy, w) - 2 * ny)])
    }

    /// The projected control points of `net`.
    fn screen_net(&self, net: &Net) -> ScreenNet {
        ScreenNet {
            points: net.h.map(|h| self.screen(&self.eye(h))),
            weights: net.h.map(|h| h[3]),
        }
    }

    /// Where the control hull of `net` lies (the surface is inside it: positive weights).
    fn hull(&self, net: &Net) -> Hull {
        let eye = net.h.map(|h| self.eye(h));
        let (near, far) = (self.vp.near, self.vp.far);
        if eye.iter().all(|p| p.w < near) || eye.iter().all(|p| p.w > far) {
            return Hull::Culled;
        }
        let mut lo = [i64::MAX; 2];
        let mut hi = [i64::MIN; 2];
        for p in &eye {
            let Some(s) = self.screen(p) else {
                // Crossing the near plane: no screen bound, so from the top.
                return Hull::FirstRow(0);
            };
            for k in 0..2 {
                lo[k] = lo[k].min(s[k]);
                hi[k] = hi[k].max(s[k]);
            }
        }
        let size = [self.vp.width as i64, self.vp.height as i64].map(|n| n << SUB);
        if hi[0] < 0 || hi[1] < 0 || lo[0] > size[0] || lo[1] > size[1] {
            return Hull::Culled;
        }
        // One row of margin for the rounding of evaluated points and projection.
        let row = (lo[1] >> SUB) - 1;
        Hull::FirstRow(row.min(self.vp.height as i64 - 1).max(0) as usize)
    }

    /// The colours of a surface of `patch`'s colour with normal `n` (model space), lit on
    /// its front and, drawn two-sided, on its back (the normal reversed). Out of line: once
    /// per cell or boundary triangle, beside many more evaluations.
    #[inline(never)]
    fn lit(&self, patch: u16, n: Option<[i64; 3]>) -> Sides<Rgb888> {
        let base = self.model.color(patch as usize);
        let n = n.unwrap_or([0; 3]);
        let color = |n| {
            self.lighting
                .cross_product_color::<<A as Arithmetic>::Normals>(base, n)
        };
        let front = color(n);
        let back = if self.cull {
            front
        } else {
            color(n.map(|c| c.saturating_neg()))
        };
        Sides { front, back }
    }

    /// The flat colours of `patch` with its normal at `(u, v)` (black for Gouraud, which
    /// colours vertices instead; the patch's colour on both sides, unlit, for
    /// [`Unlit`](crate::shading::Unlit)).
    fn face<S: Shading>(&self, patch: u16, net: &Net, [u, v]: Uv) -> Sides<Rgb888> {
        if S::PER_VERTEX {
            return BLACK_SIDES;
        }
        if !S::LIT {
            let base = self.model.color(patch as usize);
            return Sides {
                front: base,
                back: base,
            };
        }
        self.lit(patch, net.normal(u, v))
    }

    /// The surface point at `(u, v)` in eye space, lit there for Gouraud shading.
    fn vertex<S: Shading>(&self, patch: u16, net: &Net, [u, v]: Uv) -> Vertex {
        let normal = S::PER_VERTEX.then(|| net.normal(u, v));
        self.vertex_at::<S>(patch, net.point(u, v), normal)
    }

    /// The vertex at surface point `h` with normal `normal` there (`None` for flat shading,
    /// `Some(None)` where the normal vanishes).
    #[inline]
    fn vertex_at<S: Shading>(
        &self,
        patch: u16,
        h: Hom,
        normal: Option<Option<[i64; 3]>>,
    ) -> Vertex {
        let color = match normal {
            Some(n) if S::PER_VERTEX => {
                let lit = self.lit(patch, n);
                Sides {
                    front: color_channels(lit.front),
                    back: color_channels(lit.back),
                }
            }
            _ => Sides {
                front: [I16F16::ZERO; 3],
                back: [I16F16::ZERO; 3],
            },
        };
        let p = self.eye(h);
        Vertex {
            p,
            screen: CachedVertex::new::<SUB, A::Projection>(&self.vp, p),
            color,
        }
    }

    /// Draws the boundary strip on `side` of `patch`: the zipper's triangles in order, each
    /// sharing two vertices with the one before, so each vertex is evaluated once.
    fn side<S: Shading>(
        &mut self,
        patch: u16,
        net: &Net,
        levels: &Levels,
        side: usize,
        row: usize,
        f: &mut impl FnMut(&[ScreenVertex<SUB>; 3], Rgb888, u32, u32),
    ) {
        self.stats.pieces += 1;
        let mut recent: [Option<(Uv, Vertex)>; 4] = [None; 4];
        let mut next = 0;
        tessellate::border(levels, side, |uv| {
            let cv = uv.map(|p| {
                if let Some((_, v)) = recent.iter().flatten().find(|(q, _)| *q == p) {
                    return *v;
                }
                let v = self.vertex::<S>(patch, net, p);
                if let Some(slot) = recent.get_mut(next % 4) {
                    *slot = Some((p, v));
                }
                next += 1;
                v
            });
            self.triangle::<S>(patch, net, uv, cv, row, f)
        });
    }

    /// Draws what the trims keep of triangle `uv` of `patch` (control net `net`, its vertices
    /// `cv`) ([`Self::draw`]), flat-shaded with the normal at its parameter centroid.
    fn triangle<S: Shading>(
        &mut self,
        patch: u16,
        net: &Net,
        uv: [Uv; 3],
        cv: [Vertex; 3],
        row: usize,
        f: &mut impl FnMut(&[ScreenVertex<SUB>; 3], Rgb888, u32, u32),
    ) {
        let trims = self.trims(patch);
        let cut = trim::classify(&trims, uv);
        if cut == Cut::Drop {
            return;
        }
        let mid = |k: usize| uv.iter().map(|p| p[k]).sum::<u32>() / 3;
        let face = self.face::<S>(patch, net, [mid(0), mid(1)]);
        if cut == Cut::Pieces {
            self.trimmed::<S>(patch, net, uv, face, row, f);
            return;
        }
        self.draw(patch, cv.each_ref(), face, row, f);
    }

    /// Draws the parts of triangle `uv` of `patch` that its trims keep: faces cut in
    /// parameter space ([`trim::clip`]), their vertices evaluated on the surface, each face
    /// a fan of triangles with the whole triangle's flat colours `face`.
    #[inline(never)]
    fn trimmed<S: Shading>(
        &mut self,
        patch: u16,
        net: &Net,
        uv: [Uv; 3],
        face: Sides<Rgb888>,
        row: usize,
        f: &mut impl FnMut(&[ScreenVertex<SUB>; 3], Rgb888, u32, u32),
    ) {
        self.stats.trim_cut += 1;
        let trims = self.trims(patch);
        let overflows = trim::clip::<TRIM>(&trims, uv, |polygon| {
            let Some((&first, rest)) = polygon.split_first() else {
                return;
            };
            let apex = self.vertex::<S>(patch, net, first);
            let mut previous: Option<(Uv, Vertex)> = None;
            for &p in rest {
                let v = self.vertex::<S>(patch, net, p);
                if let Some((q, w)) = previous {
                    // Collinear in (u, v): no area to draw.
                    if tessellate::area2(first, q, p) != 0 {
                        self.draw(patch, [&apex, &w, &v], face, row, f);
                    }
                }
                previous = Some((p, v));
            }
        });
        self.stats.trim_overflows += overflows;
    }

    /// Draws interior cells `is × js`, in blocks of at most [`BLOCK`] columns.
    fn cells<S: Shading>(
        &mut self,
        patch: u16,
        net: &Net,
        piece: Piece,
        row: usize,
        f: &mut impl FnMut(&[ScreenVertex<SUB>; 3], Rgb888, u32, u32),
    ) {
        let Piece { levels, is, js } = piece;
        let mut first = is[0];
        while first < is[1] {
            let last = first.saturating_add(BLOCK as u8).min(is[1]);
            self.block::<S>(patch, net, levels, [first, last], js, row, f);
            first = last;
        }
    }

    /// Draws interior cells `is × js` (`is` at most [`BLOCK`] columns), each grid point
    /// evaluated once (two rows of points at a time) on its column's curve, each cell
    /// flat-shaded with the normal at its centre, on its centre column's curve.
    #[allow(clippy::too_many_arguments)]
    fn block<S: Shading>(
        &mut self,
        patch: u16,
        net: &Net,
        levels: Levels,
        is: [u8; 2],
        js: [u8; 2],
        row: usize,
        f: &mut impl FnMut(&[ScreenVertex<SUB>; 3], Rgb888, u32, u32),
    ) {
        let u = |i: u8| tessellate::grid(i as u32, levels.u);
        let v = |j: u8| tessellate::grid(j as u32, levels.v);
        let at = |i: u8, j: u8| [u(i), v(j)];
        // Interior points only (0 < u, v < 1), where `Net::point` evaluates on columns too.
        // Each column pushed as made: written once, not copied through an iterator.
        let mut columns: Vec<Column, { BLOCK + 1 }> = Vec::new();
        // Gouraud: tangents along each column, for vertex normals; flat: along each column
        // of cell centres, for face normals.
        let mut tangents: Vec<TangentColumn, { BLOCK + 1 }> = Vec::new();
        let mut centres: Vec<TangentColumn, BLOCK> = Vec::new();
        // (Room for the block's columns: the pushes never fail.)
        for i in is[0]..=is[1] {
            let _ = columns.push(net.column(u(i)));
            if S::PER_VERTEX {
                let _ = tangents.push(net.tangent_column(u(i)));
            } else if i < is[1] {
                let _ = centres.push(net.tangent_column((u(i) + u(i + 1)) / 2));
            }
        }
        // Row `j`'s points, written in place (rows of vertices are not copied).
        let points = |this: &Self, row: &mut Vec<Vertex, { BLOCK + 1 }>, j: u8| {
            row.clear();
            for (k, (column, i)) in columns.iter().zip(is[0]..=is[1]).enumerate() {
                let n = S::PER_VERTEX.then(|| {
                    let t = tangents.get(k).and_then(|t| t.normal(v(j)));
                    t.or_else(|| net.normal(u(i), v(j)))
                });
                let _ = row.push(this.vertex_at::<S>(patch, column.point(v(j)), n));
            }
        };
        let trims = self.trims(patch);
        let (mut first, mut second) = (Vec::new(), Vec::new());
        let (mut below, mut above) = (&mut first, &mut second);
        points(self, below, js[0]);
        for j in js[0]..js[1] {
            points(self, above, j + 1);
            for (k, i) in (is[0]..is[1]).enumerate() {
                let (Some(a), Some(b), Some(c), Some(d)) = (
                    below.get(k),
                    below.get(k + 1),
                    above.get(k + 1),
                    above.get(k),
                ) else {
                    break;
                };
                let corners = [a, b, c, d];
                let face = match centres.get(k) {
                    Some(t) => {
                        let (uc, vc) = ((u(i) + u(i + 1)) / 2, (v(j) + v(j + 1)) / 2);
                        self.lit(patch, t.normal(vc).or_else(|| net.normal(uc, vc)))
                    }
                    None => BLACK_SIDES,
                };
                let corner_uv = [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)];
                for t in tessellate::CELL_TRIANGLES {
                    let uv = t.map(|k| corner_uv.get(k).copied().unwrap_or([0; 2]));
                    match trim::classify(&trims, uv) {
                        Cut::Keep => {
                            let cv = t.map(|k| corners.get(k).copied().unwrap_or(a));
                            self.draw(patch, cv, face, row, f);
                        }
                        Cut::Drop => {}
                        Cut::Pieces => self.trimmed::<S>(patch, net, uv, face, row, f),
                    }
                }
            }
            core::mem::swap(&mut below, &mut above);
        }
    }

    /// Clips and projects triangle `t` of `patch` and hands each screen piece to `f` (pieces
    /// starting on or below `row`), with the colours of the side it shows.
    fn draw(
        &mut self,
        patch: u16,
        t: [&Vertex; 3],
        face: Sides<Rgb888>,
        row: usize,
        f: &mut impl FnMut(&[ScreenVertex<SUB>; 3], Rgb888, u32, u32),
    ) {
        // Borrowed field by field, not copied: this runs once per triangle.
        let (vp, cull, stats) = (&self.vp, self.cull, &mut self.stats);
        stats.frame.triangles_in += 1;
        let mut emit = |s: [ScreenVertex<SUB>; 3], area: i64, face, stats: &mut PatchStats| {
            // Front faces have negative area in y-down screen coordinates.
            if area == 0 {
                return;
            }
            if cull && area > 0 {
                stats.frame.culled += 1;
                return;
            }
            let (w, h) = (vp.width as i32, vp.height as i32);
            let Some(first) = first_row(&s, w, h) else {
                return;
            };
            if (first as usize) < row {
                stats.late += 1;
                if TriangleWalk::new::<SUB>(s.each_ref().map(xy), row as i32, h).is_none() {
                    return;
                }
            }
            stats.frame.bucketed += 1;
            f(&s, face, patch as u32, 0);
        };
        // The side shown is the one the snapped triangle turns to the camera, as the
        // rasterizer and culling see it: at a silhouette the triangles are edge-on, and a side
        // found in eye space can disagree there (test
        // `fixed_renderer_against_the_reference_at_half_a_pixel`, the sphere's rim).
        let shown = |mut s: [ScreenVertex<SUB>; 3]| {
            let area = signed_area(&s);
            if area <= 0 {
                return (s, area, face.front);
            }
            for (s, v) in s.iter_mut().zip(t) {
                s.color = v.color.back;
            }
            (s, area, face.back)
        };
        // Inside every clip plane: the screen positions projected once per vertex, as the
        // clipper's path below would project them.
        if let [Some(a), Some(b), Some(c)] = t.map(|v| v.screen.screen::<SUB>(v.color.front)) {
            let (s, area, face) = shown([a, b, c]);
            emit(s, area, face, stats);
            return;
        }
        let project = |c: &ClipVertex| vp.project_as::<A::Projection>(&c.p, c.color, true);
        let clip_vertices = |back: bool| {
            t.map(|v| ClipVertex {
                p: v.p,
                color: if back { v.color.back } else { v.color.front },
            })
        };
        // A cut triangle is clipped with its front colours first; if the polygon turns its
        // back to the camera (a planar polygon in front of the eye: its fan turns one way,
        // the first triangle with area says which), once more with the back's (the clipper
        // interpolates them). One call site, so the clipper is not inlined twice.
        let mut colors_of_back = false;
        loop {
            match C::clip(vp, &clip_vertices(colors_of_back), &mut self.polygon) {
                Clipped::Outside => stats.frame.rejected += 1,
                Clipped::Skipped => stats.frame.unclipped += 1,
                Clipped::Inside => {
                    let projected = clip_vertices(false).each_ref().map(project);
                    if let [Some(a), Some(b), Some(c)] = projected {
                        let (s, area, face) = shown([a, b, c]);
                        emit(s, area, face, stats);
                    }
                }
                Clipped::Polygon => {
                    let back = fan_turns_back(self.polygon.as_ref(), project);
                    if back && !cull && !colors_of_back {
                        colors_of_back = true;
                        continue;
                    }
                    stats.frame.clipped += 1;
                    let face = if back { face.back } else { face.front };
                    let mut fan = self.polygon.as_ref().iter().filter_map(project);
                    if let (Some(a), Some(mut b)) = (fan.next(), fan.next()) {
                        for c in fan {
                            emit([a, b, c], signed_area(&[a, b, c]), face, stats);
                            b = c;
                        }
                    }
                }
            }
            return;
        }
    }

    /// A whole patch's first row has come: choose its levels, file each side of its boundary
    /// ring under the first row of that strip's control hull and hand its interior on as a
    /// piece.
    fn patch<S: Shading>(
        &mut self,
        patch: u16,
        net: &Net,
        row: usize,
        f: &mut impl FnMut(&[ScreenVertex<SUB>; 3], Rgb888, u32, u32),
    ) {
        let levels = tessellate::levels(&self.screen_net(net), self.tolerance);
        self.stats.capped += levels.capped as u32;
        for side in 0..4 {
            let (u, v) = tessellate::strip(&levels, side);
            let work = Work::Side(levels, side as u8);
            self.file_or_draw::<S>(patch, net, net.piece(u, v), work, row, f);
        }
        let (is, js) = tessellate::interior(&levels);
        if is[0] < is[1] && js[0] < js[1] {
            self.piece::<S>(patch, net, Piece { levels, is, js }, row, f);
        }
    }

    /// An interior piece whose row has come: tessellate it if small, else split it in two
    /// and file each half under its own control hull's first row (this row if it starts
    /// here).
    fn piece<S: Shading>(
        &mut self,
        patch: u16,
        net: &Net,
        piece: Piece,
        row: usize,
        f: &mut impl FnMut(&[ScreenVertex<SUB>; 3], Rgb888, u32, u32),
    ) {
        self.stats.pieces += 1;
        let Piece { levels, is, js } = piece;
        let (ni, nj) = ((is[1] - is[0]) as u32, (js[1] - js[0]) as u32);
        if ni * nj <= LEAF_CELLS {
            self.cells::<S>(patch, net, piece, row, f);
            return;
        }
        let halves = if ni >= nj {
            let mid = is[0] + (ni / 2) as u8;
            [([is[0], mid], js), ([mid, is[1]], js)]
        } else {
            let mid = js[0] + (nj / 2) as u8;
            [(is, [js[0], mid]), (is, [mid, js[1]])]
        };
        for (is, js) in halves {
            let half = Piece { levels, is, js };
            let range = |r: [u8; 2], level: u8| r.map(|k| tessellate::grid(k as u32, level));
            let sub = net.piece(range(is, levels.u), range(js, levels.v));
            self.file_or_draw::<S>(patch, net, sub, Work::Cells(half), row, f);
        }
    }

    /// Files `work` (a part of `patch` whose control net is `sub`) under the first row of
    /// `sub`'s control hull (this row if it starts here); drops it if the hull is off screen,
    /// draws it now if no entry is free.
    #[inline(never)]
    fn file_or_draw<S: Shading>(
        &mut self,
        patch: u16,
        net: &Net,
        sub: Net,
        work: Work,
        row: usize,
        f: &mut impl FnMut(&[ScreenVertex<SUB>; 3], Rgb888, u32, u32),
    ) {
        let first = match self.hull(&sub) {
            Hull::Culled => {
                self.stats.pieces_culled += 1;
                return;
            }
            Hull::FirstRow(first) => first.max(row),
        };
        if !self.file(Entry { patch, work }, first) {
            self.stats.overflows += 1;
            self.work::<S>(patch, net, work, row, f);
        }
    }

    /// Does `work` of `patch` (control net `net`) now, at `row`.
    fn work<S: Shading>(
        &mut self,
        patch: u16,
        net: &Net,
        work: Work,
        row: usize,
        f: &mut impl FnMut(&[ScreenVertex<SUB>; 3], Rgb888, u32, u32),
    ) {
        match work {
            Work::Patch => self.patch::<S>(patch, net, row, f),
            Work::Side(levels, side) => self.side::<S>(patch, net, &levels, side as usize, row, f),
            // Filed halves are split further when their row comes; overflowed ones not.
            Work::Cells(piece) => self.cells::<S>(patch, net, piece, row, f),
        }
    }
}

impl<const SUB: u32, C: Clipping, A: Arithmetic, const TRIM: usize> RowPieces<SUB>
    for PatchRows<'_, '_, SUB, C, A, TRIM>
{
    fn each_row_piece<S: Shading>(
        &mut self,
        row: usize,
        mut f: impl FnMut(&[ScreenVertex<SUB>; 3], Rgb888, u32, u32),
    ) {
        // Pieces filed under this row while it is processed are taken in the same loop.
        while let Some(Entry { patch, work }) = self.take(row) {
            let net = Net::of(self.model, patch as usize);
            match work {
                Work::Cells(piece) => self.piece::<S>(patch, &net, piece, row, &mut f),
                _ => self.work::<S>(patch, &net, work, row, &mut f),
            }
        }
    }
}

/// Something with a value for each side of the surface.
#[derive(Clone, Copy, Debug)]
struct Sides<T> {
    front: T,
    back: T,
}

/// A tessellation vertex: its eye-space point, its screen position if it is inside every
/// clip plane, and its (Gouraud) colours for either side.
#[derive(Clone, Copy, Debug)]
struct Vertex {
    p: EyePoint,
    screen: CachedVertex,
    color: Sides<[I16F16; 3]>,
}

/// Whether the first triangle with area of the fan of `polygon`, projected by `project`,
/// turns its back to the camera (positive area in y-down screen coordinates).
fn fan_turns_back<const SUB: u32>(
    polygon: &[ClipVertex],
    project: impl Fn(&ClipVertex) -> Option<ScreenVertex<SUB>>,
) -> bool {
    let mut fan = polygon.iter().filter_map(project);
    let (Some(a), Some(mut b)) = (fan.next(), fan.next()) else {
        return false;
    };
    for c in fan {
        let area = signed_area(&[a, b, c]);
        if area != 0 {
            return area > 0;
        }
        b = c;
    }
    false
}
