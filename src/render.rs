//! The frame driver: bucket triangles by first row, then walk the rows top to bottom, resolving
//! visibility with a one-row depth buffer (the span z-buffer) and handing each finished row to
//! the sink.
//!
//! # Two passes, per-vertex memory optional
//!
//! Pass 1 transforms, clips, projects and culls every triangle just far enough to know its
//! first row, and files its id in that row's bucket (a linked list threaded through two
//! `u16` arrays: 4 bytes per triangle). Pass 2 walks the rows; when a row's bucket comes up,
//! each triangle in it is transformed again and fully set up (edges, depth plane, shading) into
//! the active list, which holds only the triangles crossing the current row. By default this
//! trades a second transform for not storing transformed vertices; a workspace with a vertex
//! cache (`VERTS > 0`, [`crate::cache`]) transforms and projects each vertex once per frame
//! instead, for [`CachedVertex::BYTES`] per vertex, with the same pixels.

use crate::arithmetic::Arithmetic;
use crate::cache::CachedVertex;
use crate::clip::{ClipVertex, Clipped, Clipping};
use crate::depth::{DepthFormat, DepthRow};
use crate::math::{zip3, NormalPrecision};
use crate::options::RenderOptions;
use crate::project::ProjectionPrecision;
use crate::project::{ScreenVertex, Viewport};
use crate::raster::{
    area_sign, color_channels, depth_planes_fit_i64, first_row_xy, xy, DepthPlane, DepthWalk,
    PlaneSolver, TriangleWalk, WalkDepth, MAX_DRAWN_DEPTH,
};
use crate::scene::{Instance, MeshColors, Scene, MAX_SCENE_TRIANGLES};
use crate::shading::{Shading, SpanDepth};
use crate::sink::{Row, RowPixel, RowSink};
use crate::stats::{CapacityKind, DroppedPiece, FrameStats, RenderError};
use crate::vertex::{shade, Lighting, ModelView, TransformPrecision};
use embedded_graphics::pixelcolor::Rgb888;
use fixed::types::I16F16;
use heapless::{Vec, VecView};

/// A triangle on the active list. `K` is the sort key of depth-sorting methods (`()` for the
/// others, so it costs nothing there).
#[derive(Clone, Copy, Debug)]
pub(crate) struct ActiveTri<T, K = ()> {
    pub(crate) walk: TriangleWalk,
    pub(crate) depth: WalkDepth,
    /// `depth`'s per-pixel step ([`DepthPlane::step`]), kept here rather than in `depth`: the
    /// span loop's, not the walk's.
    pub(crate) depth_step: i32,
    pub(crate) payload: T,
    pub(crate) key: K,
    /// The slot of the next triangle in drawing order, or of the next free slot
    /// ([`ActiveList`]); [`NO_LINK`] at the end.
    link: u16,
}

impl<T, K> ActiveTri<T, K> {
    /// Moves the walk and the depth plane's row to the next row; `false` when the triangle is
    /// finished.
    #[inline(always)]
    fn advance<const SUB: u32>(&mut self) -> bool {
        let more = self.walk.advance::<SUB>();
        self.depth.next_row();
        more
    }
}

/// End of an [`ActiveList`] chain.
const NO_LINK: u16 = u16::MAX;

/// The active triangles in drawing order, as a chain through their slots: a triangle stays in
/// its slot from activation to its last row, and a finished one is unlinked and its slot
/// reused, so none is ever moved (a record is about 100 bytes). The order decides exact depth
/// ties (the triangle drawn first keeps the pixel): activation order, or the sort key's.
struct ActiveList<'a, T, K> {
    slots: &'a mut VecView<ActiveTri<T, K>>,
    head: u16,
    tail: u16,
    /// Slots of finished triangles, chained by their links.
    free: u16,
    live: usize,
}

impl<'a, T, K: SortKey> ActiveList<'a, T, K> {
    fn new(slots: &'a mut VecView<ActiveTri<T, K>>) -> Self {
        slots.clear();
        ActiveList {
            slots,
            head: NO_LINK,
            tail: NO_LINK,
            free: NO_LINK,
            live: 0,
        }
    }

    /// Sets slot `slot`'s link (slots on a chain exist).
    #[inline(always)]
    fn set_link(&mut self, slot: u16, link: u16) {
        match self.slots.get_mut(slot as usize) {
            Some(t) => t.link = link,
            None => debug_assert!(false, "internal error: no active slot {slot}"),
        }
    }

    /// Adds `t` after every triangle on the list (with `K::SORTED`, before the first whose
    /// key is not below its own); `false` if the list is full.
    fn insert(&mut self, mut t: ActiveTri<T, K>) -> bool {
        let (mut prev, mut next) = (self.tail, NO_LINK);
        if K::SORTED {
            // Far to near; among equal keys the one activated first is drawn last.
            (prev, next) = (NO_LINK, self.head);
            while let Some(a) = self.slots.get(next as usize) {
                if a.key >= t.key {
                    break;
                }
                (prev, next) = (next, a.link);
            }
        }
        t.link = next;
        let slot = match self.slots.get_mut(self.free as usize) {
            Some(free) => {
                let slot = self.free;
                self.free = free.link;
                *free = t;
                slot
            }
            None => match u16::try_from(self.slots.len()) {
                Ok(slot) if slot != NO_LINK && self.slots.push(t).is_ok() => slot,
                _ => return false,
            },
        };
        if prev == NO_LINK {
            self.head = slot;
        } else {
            self.set_link(prev, slot);
        }
        if next == NO_LINK {
            self.tail = slot;
        }
        self.live += 1;
        true
    }

    /// Calls `f(triangle, order)` for each triangle in drawing order (`order` counting from 0)
    /// and takes off the list those for which it returns `false`.
    #[inline(always)]
    fn retain(&mut self, mut f: impl FnMut(&mut ActiveTri<T, K>, usize) -> bool) {
        let (mut prev, mut slot, mut order) = (NO_LINK, self.head, 0);
        while let Some(t) = self.slots.get_mut(slot as usize) {
            let next = t.link;
            if f(t, order) {
                order += 1;
                prev = slot;
            } else {
                t.link = self.free;
                self.free = slot;
                self.live -= 1;
                if prev == NO_LINK {
                    self.head = next;
                } else {
                    self.set_link(prev, next);
                }
                if next == NO_LINK {
                    self.tail = prev;
                }
            }
            slot = next;
        }
    }
}

/// A per-triangle sort key: `u32` for depth sorting, `()` where the order is activation order.
pub(crate) trait SortKey: Copy + Ord {
    /// Whether pass 1 computes keys and activation keeps the active list sorted.
    const SORTED: bool;
    fn from_raw(raw: u32) -> Self;
}

impl SortKey for () {
    const SORTED: bool = false;
    fn from_raw(_: u32) -> Self {}
}

impl SortKey for u32 {
    const SORTED: bool = true;
    fn from_raw(raw: u32) -> Self {
        raw
    }
}

/// The hidden-surface step: what becomes of the spans the active triangles produce. The
/// span z-buffer, band z-buffers, span sorting and depth sorting differ only here; transform,
/// clipping, projection, bucketing and the edge walk are shared.
pub(crate) trait Resolve<P: RowPixel, S: Shading> {
    /// The per-triangle sort key (`()` unless the method sorts by depth).
    type Key: SortKey;
    /// Whether rows are resolved in bands of more than one ([`Self::band_rows`]): a constant,
    /// so row-at-a-time methods leave the band code out of the triangle activation, which a
    /// renderer's row pieces (patches) may call from far from the row loop.
    const BANDED: bool = false;
    /// Rows resolved together: 1 for row-at-a-time methods, `B` for a band z-buffer.
    fn band_rows(&self) -> usize {
        1
    }
    /// Starts rows `y0 .. y0 + rows`: everything background, nothing covered.
    fn begin_band(&mut self, y0: i32, rows: usize);
    /// Takes triangle `t`'s span on row `y`, columns `[l, r)` (on screen, non-empty); `order`
    /// is `t`'s position on the active list (activation order). Returns pixels written now.
    fn span(
        &mut self,
        t: &ActiveTri<S::Payload<P>, Self::Key>,
        order: usize,
        y: i32,
        l: i32,
        r: i32,
    ) -> u32;
    /// Finishes row `y`: its pixels, its depth (empty for methods without depth memory),
    /// the spans it received, and pixels written while finishing.
    fn finish_row(&mut self, y: i32) -> FinishedRow<'_, P>;
}

/// What [`Resolve::finish_row`] hands back.
pub(crate) struct FinishedRow<'a, P> {
    pub(crate) pixels: &'a [P],
    pub(crate) depth: DepthRow<'a>,
    pub(crate) spans: u16,
    pub(crate) written: u32,
}

/// Depth-tests and writes `t`'s span `[l, r)` of row `y` into one row of depth and pixels.
#[inline(always)]
pub(crate) fn fill_span<P: RowPixel, S: Shading, Z: DepthFormat, K>(
    t: &ActiveTri<S::Payload<P>, K>,
    y: i32,
    l: i32,
    r: i32,
    depth: &mut [Z],
    pixels: &mut [P],
) -> u32 {
    // The walk keeps the plane on row `y` (`ActiveTri::advance`).
    debug_assert_eq!(y, t.walk.row(), "internal error: span off the walk's row");
    let (q, dq) = (t.depth.span_start(l), t.depth_step);
    let span = SpanDepth { x0: l, y, q, dq };
    let (l, r) = (l as usize, r as usize);
    // One test for both rows (which then need none of their own), and slices of one length,
    // so the fill's loop counts one of them. `walk_row` passes only non-empty spans (an empty
    // one would fill nothing), so `l < r` is not tested again.
    if r <= depth.len() && r <= pixels.len() {
        if let (Some(d), Some(p)) = (depth.get_mut(l..r), pixels.get_mut(l..r)) {
            return S::fill(&t.payload, span, d, p);
        }
    }
    // walk_band clamps spans to the row and passes only non-empty ones.
    debug_assert!(false, "internal error: span {l}..{r} out of the row");
    0
}

pub(crate) const NO_ENTRY: u16 = u16::MAX;

/// The integer type of a row bucket's head (one per row of the target): `u16`, for any
/// triangle capacity, or `u8`, for workspaces that file at most 255 triangles a frame, whose
/// heads then take one byte per row instead of two.
pub trait BucketHead: Copy + core::fmt::Debug + sealed::Sealed + 'static {
    /// An empty bucket.
    const EMPTY: Self;
    /// Most bucket entries (the workspace's `TRIS`) this type can point to.
    const MAX_ENTRIES: usize;
    /// The entry this head points to, `u16::MAX` for an empty bucket.
    fn entry(self) -> u16;
    /// The head pointing to `entry` (below [`Self::MAX_ENTRIES`], or `u16::MAX` for none).
    fn to(entry: u16) -> Self;
}

mod sealed {
    pub trait Sealed {}
    impl Sealed for u8 {}
    impl Sealed for u16 {}
}

impl BucketHead for u16 {
    const EMPTY: u16 = NO_ENTRY;
    const MAX_ENTRIES: usize = MAX_SCENE_TRIANGLES;
    #[inline(always)]
    fn entry(self) -> u16 {
        self
    }
    #[inline(always)]
    fn to(entry: u16) -> u16 {
        entry
    }
}

impl BucketHead for u8 {
    const EMPTY: u8 = u8::MAX;
    const MAX_ENTRIES: usize = u8::MAX as usize;
    #[inline(always)]
    fn entry(self) -> u16 {
        match self {
            u8::MAX => NO_ENTRY,
            e => e as u16,
        }
    }
    #[inline(always)]
    fn to(entry: u16) -> u8 {
        // Entries stay below MAX_ENTRIES (the workspace's capacity check); NO_ENTRY is EMPTY.
        u8::try_from(entry).unwrap_or(u8::MAX)
    }
}

/// `value`, or `fallback` if it is `None`: for look-ups that validation (of meshes, trees and
/// capacities) or the frame's own set-up make infallible, so that `None` is an internal error.
/// Debug builds, the tests among them, stop there; release builds, whose render path must not
/// panic, go on with the fallback.
#[inline(always)]
#[track_caller]
pub(crate) fn internal<T>(value: Option<T>, fallback: T) -> T {
    match value {
        Some(value) => value,
        None => {
            debug_assert!(false, "internal error: a look-up that cannot fail failed");
            fallback
        }
    }
}

/// Buckets and active list as slices, so the driver is not generic over the capacities.
pub(crate) struct Frame<'a, T, K, H = u16> {
    pub(crate) heads: &'a mut [H],
    pub(crate) next: &'a mut [H],
    pub(crate) refs: &'a mut [u16],
    /// One sort key per bucket entry; empty unless `K::SORTED`.
    pub(crate) keys: &'a mut [u32],
    pub(crate) active: &'a mut VecView<ActiveTri<T, K>>,
    /// The vertex cache; empty for workspaces without one.
    pub(crate) vertices: &'a mut [CachedVertex],
}

/// Checks a `width × height` target against a workspace of `max_w × max_h` and builds its
/// viewport.
pub(crate) fn viewport<const SUB: u32, E>(
    width: usize,
    height: usize,
    max_w: usize,
    max_h: usize,
    scene: &Scene<'_>,
) -> Result<Viewport<SUB>, RenderError<E>> {
    if width == 0 || height == 0 || width > max_w || height > max_h {
        return Err(RenderError::InvalidTarget);
    }
    let camera = &scene.camera;
    Viewport::<SUB>::new(width, height, camera.focal(), camera.near(), camera.far())
        .ok_or(RenderError::InvalidTarget)
}

/// Per-instance constants for one frame.
pub(crate) struct InstanceSetup<'a, T: TransformPrecision> {
    instance: &'a Instance<'a>,
    mv: T::Matrix,
    lighting: Lighting,
    first_id: u32,
    /// Index of this instance's first vertex in the frame's vertex cache.
    first_vertex: usize,
}

/// The instances' per-frame constants, lit for shading `S` unless it is [`Unlit`]
/// (`S::LIT`): an unlit build computes no lighting.
///
/// [`Unlit`]: crate::shading::Unlit
fn setup_instances<'a, S: Shading, T: TransformPrecision, E, const N: usize>(
    scene: &'a Scene<'a>,
) -> Result<Vec<InstanceSetup<'a, T>, N>, RenderError<E>> {
    // Triangle ids (and so the u16 ids in the row buckets) must stay below 65,535.
    let triangles = scene.triangle_count();
    if triangles > MAX_SCENE_TRIANGLES {
        return Err(RenderError::TooManyTriangles { triangles });
    }
    let mut out = Vec::new();
    let view = &scene.camera.view().world_to_eye;
    let (mut first_id, mut first_vertex) = (0u32, 0usize);
    for (i, inst) in scene.instances.iter().enumerate() {
        let max_abs_bits = inst.mesh.max_abs_bits();
        let mv = ModelView::new(&inst.transform, view, max_abs_bits)
            .map_err(|error| RenderError::Transform { instance: i, error })?;
        let mv = T::prepare(mv, max_abs_bits);
        let lighting = if S::LIT {
            Lighting::new(&scene.light, &inst.transform)
        } else {
            Lighting::NONE
        };
        let setup = InstanceSetup {
            instance: inst,
            mv,
            lighting,
            first_id,
            first_vertex,
        };
        if out.push(setup).is_err() {
            return Err(RenderError::Capacity {
                what: CapacityKind::Instances,
                needed: scene.instances.len(),
                capacity: N,
            });
        }
        first_id += inst.mesh.triangles().len() as u32;
        first_vertex += inst.mesh.vertices().len();
    }
    Ok(out)
}

/// How pass 1 classified a triangle.
enum Fate {
    Culled,
    Rejected,
    Unclipped,
    Visible { first_row: i32, clipped: bool },
}

/// Where one screen triangle stands after back-face culling and the screen test.
enum Placement {
    /// Zero area.
    Degenerate,
    /// A back face, culled.
    Back,
    /// No pixel centre of the screen in its bounding box.
    Offscreen,
    /// Drawn, starting on this row.
    FirstRow(i32),
}

impl Placement {
    #[inline]
    fn of<const S: u32>(s: &[(i32, i32); 3], vp: &Viewport<S>, cull: bool) -> Self {
        let area = area_sign(s);
        // Front faces have negative area in y-down screen coordinates.
        if area == 0 {
            return Placement::Degenerate;
        }
        if cull && area > 0 {
            return Placement::Back;
        }
        match first_row_xy::<S>(s, vp.width as i32, vp.height as i32) {
            Some(r) => Placement::FirstRow(r),
            None => Placement::Offscreen,
        }
    }
}

impl<T: TransformPrecision> InstanceSetup<'_, T> {
    /// Pass 1's short way for a triangle whose three vertices have cached screen positions
    /// (`None` for any other: [`Self::screen_triangles`] decides): the same fate from the
    /// cached positions alone, with no colours, clipping or pieces.
    #[inline(always)]
    fn cached_fate<const S: u32>(
        &self,
        tri: usize,
        cache: &[CachedVertex],
        vp: &Viewport<S>,
        cull: bool,
    ) -> Option<Fate> {
        let &idx = self.instance.mesh.triangles().get(tri)?;
        let s = CachedVertex::positions(self.cached(cache, idx)?)?;
        Some(match Placement::of(&s, vp, cull) {
            Placement::Degenerate | Placement::Offscreen => Fate::Rejected,
            Placement::Back => Fate::Culled,
            Placement::FirstRow(first_row) => Fate::Visible {
                first_row,
                clipped: false,
            },
        })
    }

    fn vertex_colors(&self, tri: usize, idx: [u16; 3]) -> [Rgb888; 3] {
        let mesh = self.instance.mesh;
        let pick = |i: u16| match mesh.colors() {
            MeshColors::Uniform(c) => c,
            // Mesh::new checked both lengths.
            MeshColors::PerFace(c) => internal(c.get(tri).copied(), Rgb888::new(0, 0, 0)),
            MeshColors::PerVertex(c) => internal(c.get(i as usize).copied(), Rgb888::new(0, 0, 0)),
        };
        idx.map(pick)
    }

    /// The flat colour of triangle `tri`: lit, or for [`Unlit`] shading (`S::LIT` false) the
    /// mesh's colour as given.
    ///
    /// [`Unlit`]: crate::shading::Unlit
    #[inline]
    fn face_color<S: Shading, N: NormalPrecision>(&self, tri: usize, idx: [u16; 3]) -> Rgb888 {
        if !S::LIT {
            return self.vertex_colors(tri, idx)[0];
        }
        let verts = self.instance.mesh.vertices();
        let zero = [I16F16::ZERO; 3];
        let v = idx.map(|i| internal(verts.get(i as usize), &zero));
        self.lighting
            .face_color::<N>(self.vertex_colors(tri, idx)[0], v)
    }

    /// The colour attributes of triangle `tri`'s vertices: lit per vertex for Gouraud
    /// (`lit`), else zero (flat shading colours the face instead).
    fn vertex_attributes<A: Arithmetic<Transform = T>>(
        &self,
        tri: usize,
        idx: [u16; 3],
        lit: bool,
    ) -> [[I16F16; 3]; 3] {
        if !lit {
            return [[I16F16::ZERO; 3]; 3];
        }
        let mesh = self.instance.mesh;
        let zero = [I16F16::ZERO; 3];
        let base = self.vertex_colors(tri, idx);
        let intensity = match mesh.normals() {
            Some(n) => idx.map(|i| {
                self.lighting
                    .vertex::<A::Normals>(internal(n.get(i as usize), &zero))
            }),
            None => {
                let verts = mesh.vertices();
                let v = idx.map(|i| internal(verts.get(i as usize), &zero));
                [self.lighting.face::<A::Normals>(v); 3]
            }
        };
        zip3(base, intensity, |b, i| color_channels(shade(b, i)))
    }

    /// Transforms the three vertices `idx` to eye space, with colour attributes `colors`.
    fn clip_vertices<A: Arithmetic<Transform = T>>(
        &self,
        idx: [u16; 3],
        colors: [[I16F16; 3]; 3],
    ) -> [ClipVertex; 3] {
        let verts = self.instance.mesh.vertices();
        let zero = [I16F16::ZERO; 3];
        let v = idx.map(|i| internal(verts.get(i as usize), &zero));
        zip3(v, colors, |p, color| ClipVertex {
            p: A::Transform::apply(&self.mv, p),
            color,
        })
    }

    /// The cache entries of vertices `idx`, if the frame has a vertex cache.
    fn cached<'c>(
        &self,
        cache: &'c [CachedVertex],
        idx: [u16; 3],
    ) -> Option<[&'c CachedVertex; 3]> {
        if cache.is_empty() {
            return None;
        }
        let get = |i: u16| cache.get(self.first_vertex + i as usize);
        let [Some(a), Some(b), Some(c)] = idx.map(get) else {
            // A cache holds every vertex of the scene; without it the triangle is drawn uncached.
            debug_assert!(
                false,
                "internal error: vertices {idx:?} not in the vertex cache"
            );
            return None;
        };
        Some([a, b, c])
    }

    /// Fills this instance's part of the vertex cache: every vertex transformed, clip-tested
    /// and (when inside) projected once, exactly as the uncached path does per triangle.
    fn fill_cache<const S: u32, A: Arithmetic<Transform = T>>(
        &self,
        vp: &Viewport<S>,
        cache: &mut [CachedVertex],
    ) {
        let verts = self.instance.mesh.vertices();
        // The cache was sized for every vertex of the scene.
        debug_assert!(
            cache.len() >= self.first_vertex + verts.len(),
            "internal error: the vertex cache is short"
        );
        let slots = cache.iter_mut().skip(self.first_vertex);
        for (slot, v) in slots.zip(verts) {
            *slot = CachedVertex::new::<S, A::Projection>(vp, A::Transform::apply(&self.mv, v));
        }
    }

    /// Clips and projects triangle `tri`, calling `f` with each visible screen triangle (whose
    /// depths are 0 unless `depth` or the vertex `cache`, when not empty, has them). `filed`:
    /// pass 1 filed this triangle (pass 2 asks), so if its vertices all have cached positions
    /// it is drawn whole without culling and the screen test again (the fate's first row is
    /// then not computed: 0).
    #[allow(clippy::too_many_arguments)]
    fn screen_triangles<const S: u32, C: Clipping, A: Arithmetic<Transform = T>>(
        &self,
        tri: usize,
        cache: &[CachedVertex],
        vp: &Viewport<S>,
        cull: bool,
        lit: bool,
        depth: bool,
        filed: bool,
        mut f: impl FnMut(&[ScreenVertex<S>; 3]),
    ) -> Fate {
        let Some(&idx) = self.instance.mesh.triangles().get(tri) else {
            // Callers pass the mesh's own triangles (a BSP tree's ranges are checked against it).
            debug_assert!(false, "internal error: no triangle {tri}");
            return Fate::Rejected;
        };
        // The colour attributes are made where they are used, so no copy of them stays in this
        // frame (flat shading's are zeros).
        let colors = || self.vertex_attributes::<A>(tri, idx, lit);
        let mut first: Option<i32> = None;
        let mut culled = false;
        // `placed`: pass 1 placed `s` from these same cached positions and filed it.
        let mut emit = |s: &[ScreenVertex<S>; 3], placed: bool| {
            let placement = match placed {
                true => Placement::FirstRow(0),
                false => Placement::of(&s.each_ref().map(xy), vp, cull),
            };
            match placement {
                Placement::Degenerate | Placement::Offscreen => {}
                Placement::Back => culled = true,
                Placement::FirstRow(r) => {
                    first = Some(first.map_or(r, |f| f.min(r)));
                    f(s);
                }
            }
        };
        let project = |c: &ClipVertex| vp.project_as::<A::Projection>(&c.p, c.color, depth);
        let mut polygon = C::Polygon::default();
        let clipped = 'pieces: {
            let cv = match self.cached(cache, idx) {
                Some(c) => {
                    // Three cached positions first (their colours made only then): vertices
                    // with one are inside every plane, so the outcode test could not reject.
                    if CachedVertex::all_projected(c) {
                        emit(&CachedVertex::triangle::<S>(c, colors()), filed);
                        break 'pieces false;
                    }
                    if CachedVertex::all_outside_one_plane(c) {
                        return Fate::Rejected;
                    }
                    // The cache keeps no eye-space points: transform again (same result).
                    self.clip_vertices::<A>(idx, colors())
                }
                None => self.clip_vertices::<A>(idx, colors()),
            };
            match C::clip(vp, &cv, &mut polygon) {
                Clipped::Outside => return Fate::Rejected,
                Clipped::Skipped => return Fate::Unclipped,
                Clipped::Inside => {
                    if let [Some(a), Some(b), Some(c)] = cv.each_ref().map(project) {
                        emit(&[a, b, c], false);
                    }
                    false
                }
                Clipped::Polygon => {
                    // Fan from the first vertex, projecting each vertex once as the fan reaches it.
                    let mut fan = polygon.as_ref().iter().filter_map(project);
                    if let (Some(a), Some(mut b)) = (fan.next(), fan.next()) {
                        for c in fan {
                            emit(&[a, b, c], false);
                            b = c;
                        }
                    }
                    true
                }
            }
        };
        match first {
            Some(first_row) => Fate::Visible { first_row, clipped },
            None if culled => Fate::Culled,
            None => Fate::Rejected,
        }
    }
}

/// Finds the instance owning global triangle id `id`.
fn locate<'s, 'a, T: TransformPrecision>(
    setups: &'s [InstanceSetup<'a, T>],
    id: u32,
) -> Option<(&'s InstanceSetup<'a, T>, usize)> {
    setups
        .iter()
        .rev()
        .find(|s| s.first_id <= id)
        .map(|s| (s, (id - s.first_id) as usize))
}

/// The order in which pass 1 visits the scene's triangles.
pub(crate) trait TriangleOrder {
    /// Calls `f(instance, triangle, rank)` for every triangle to draw; `rank` is its place in a
    /// far-to-near drawing order, if this order is one.
    fn visit<'s, T: TransformPrecision, E>(
        &mut self,
        setups: &[InstanceSetup<'s, T>],
        f: impl FnMut(&InstanceSetup<'s, T>, usize, Option<u32>),
    ) -> Result<(), RenderError<E>>;
}

/// Every triangle of every instance, in reverse id order.
pub(crate) struct IdOrder;

impl TriangleOrder for IdOrder {
    #[inline(always)]
    fn visit<'s, T: TransformPrecision, E>(
        &mut self,
        setups: &[InstanceSetup<'s, T>],
        mut f: impl FnMut(&InstanceSetup<'s, T>, usize, Option<u32>),
    ) -> Result<(), RenderError<E>> {
        for setup in setups.iter().rev() {
            for tri in (0..setup.instance.mesh.triangles().len()).rev() {
                f(setup, tri, None);
            }
        }
        Ok(())
    }
}

/// The largest width and height a frame's target can have, known at compile time where the
/// workspace's size is ([`Size`]), else unknown ([`Unbounded`]).
pub(crate) trait ScreenBound {
    /// The larger of the largest width and height.
    const MAX_SIDE: usize;
}

/// No bound known.
pub(crate) struct Unbounded;

impl ScreenBound for Unbounded {
    const MAX_SIDE: usize = usize::MAX;
}

/// Targets at most `W × H` pixels.
pub(crate) struct Size<const W: usize, const H: usize>;

impl<const W: usize, const H: usize> ScreenBound for Size<W, H> {
    const MAX_SIDE: usize = if W > H { W } else { H };
}

/// Renders one frame: pass 1 files triangles in row buckets, pass 2 walks the rows band by band,
/// handing spans to `resolve` and finished rows to `sink`.
pub(crate) fn drive<
    P: RowPixel,
    S: Shading,
    const SUB: u32,
    C: Clipping,
    A: Arithmetic,
    K: RowSink<P>,
    const INSTANCES: usize,
    R: Resolve<P, S>,
    H: BucketHead,
    D: ScreenBound,
>(
    ws: Frame<'_, S::Payload<P>, R::Key, H>,
    resolve: &mut R,
    order: &mut impl TriangleOrder,
    scene: &Scene<'_>,
    options: &RenderOptions<SUB, C, A>,
    vp: &Viewport<SUB>,
    sink: &mut K,
) -> Result<FrameStats, RenderError<K::Error>> {
    let setups = setup_instances::<S, A::Transform, K::Error, INSTANCES>(scene)?;
    let mut stats = FrameStats::default();
    let width = vp.width as i32;
    let capacity = ws.refs.len().min(ws.next.len());
    let sorted = <R::Key as SortKey>::SORTED;

    // The vertex cache, when the workspace has one and the scene's vertices fit it.
    let vertices: usize = setups
        .iter()
        .map(|s| s.instance.mesh.vertices().len())
        .sum();
    let cache: &[CachedVertex] = match ws.vertices.get_mut(..vertices) {
        Some(cache) if vertices > 0 => {
            for setup in &setups {
                setup.fill_cache::<SUB, A>(vp, cache);
            }
            stats.cached_vertices = vertices as u32;
            cache
        }
        _ => &[],
    };

    // Pass 1: file every visible triangle under its first row, in the order `order` gives
    // (reverse id order, which leaves each row's list in ascending id order, as pushing is at
    // the head). Depth sorting also keeps a key per triangle: its rank in `order` if that is a
    // drawing order (BSP), else the mean depth of its (clipped) vertices, larger = nearer.
    ws.heads.fill(H::EMPTY);
    let mut filed = 0usize;
    for setup in &setups {
        stats.triangles_in += setup.instance.mesh.triangles().len() as u32;
    }
    order.visit(&setups, |setup, tri, rank| {
        let (mut q_sum, mut q_count) = (0u64, 0u64);
        // Only a depth sort needs depths in pass 1; the others skip their division.
        let depth = sorted && rank.is_none();
        let cull = options.cull_back_faces;
        let quick = match depth {
            false => setup.cached_fate::<SUB>(tri, cache, vp, cull),
            true => None,
        };
        let fate = quick.unwrap_or_else(|| {
            setup.screen_triangles::<SUB, C, A>(tri, cache, vp, cull, false, depth, false, |s| {
                if depth {
                    q_sum += s.iter().map(|v| v.q.to_bits().max(0) as u64).sum::<u64>();
                    q_count += 3;
                }
            })
        });
        match fate {
            Fate::Culled => stats.culled += 1,
            Fate::Rejected => stats.rejected += 1,
            Fate::Unclipped => stats.unclipped += 1,
            Fate::Visible { first_row, clipped } => {
                stats.clipped += clipped as u32;
                stats.bucketed += 1;
                if filed < capacity {
                    let id = setup.first_id + tri as u32;
                    let row = first_row as usize;
                    // Ids fit 16 bits (at most MAX_SCENE_TRIANGLES triangles, checked by
                    // `setup_instances`), and so do entries (`filed < TRIS <= 65535`), which
                    // stay below NO_ENTRY: nothing is truncated.
                    if let (Some(head), Some(next), Some(r), Ok(id), Ok(entry)) = (
                        ws.heads.get_mut(row),
                        ws.next.get_mut(filed),
                        ws.refs.get_mut(filed),
                        u16::try_from(id),
                        u16::try_from(filed),
                    ) {
                        *r = id;
                        *next = *head;
                        *head = H::to(entry);
                    } else {
                        debug_assert!(false, "internal error: triangle {id} not filed");
                    }
                    if let Some(k) = ws.keys.get_mut(filed) {
                        *k = rank.unwrap_or((q_sum / q_count.max(1)) as u32);
                    } else {
                        // Only methods that do not sort have no keys.
                        debug_assert!(!sorted, "internal error: no sort key for entry {filed}");
                    }
                }
                filed += 1;
            }
        }
    })?;
    if filed > capacity {
        return Err(RenderError::Capacity {
            what: CapacityKind::Triangles,
            needed: filed,
            capacity,
        });
    }

    // Pass 2: the rows, with pieces made by transforming the bucketed triangles again.
    let pieces = MeshPieces {
        setups: &setups,
        refs: ws.refs,
        keys: ws.keys,
        cache,
        vp,
        cull: options.cull_back_faces,
        stages: core::marker::PhantomData::<(C, A, D)>,
    };
    let mut rows = Buckets {
        heads: ws.heads,
        next: ws.next,
        pieces: &pieces,
    };
    let height = ws.heads.len();
    walk_rows::<P, S, SUB, K, R, _>(
        height, ws.active, &mut rows, resolve, width, sink, &mut stats,
    )?;
    Ok(stats)
}

/// What pass 2 activates on each row: the pieces that start there (in any order that is the
/// same from frame to frame).
pub(crate) trait RowPieces<const SUB: u32> {
    /// Whether every piece's depth plane solves in 64 bits ([`DepthPlane::new_i64`]).
    const DEPTH_PLANES_I64: bool = false;
    /// Calls `f(vertices, face colour, triangle id, sort key)` for each screen piece activated
    /// on `row` (rows come in order, each once per frame).
    fn each_row_piece<S: Shading>(
        &mut self,
        row: usize,
        f: impl FnMut(&[ScreenVertex<SUB>; 3], Rgb888, u32, u32),
    );
}

/// Row buckets (heads and links of entry lists) over pieces looked up by entry.
pub(crate) struct Buckets<'a, A, H = u16> {
    pub(crate) heads: &'a [H],
    pub(crate) next: &'a [H],
    pub(crate) pieces: &'a A,
}

impl<const SUB: u32, A: ActivePieces<SUB>, H: BucketHead> RowPieces<SUB> for Buckets<'_, A, H> {
    const DEPTH_PLANES_I64: bool = A::DEPTH_PLANES_I64;
    #[inline(always)]
    fn each_row_piece<S: Shading>(
        &mut self,
        row: usize,
        mut f: impl FnMut(&[ScreenVertex<SUB>; 3], Rgb888, u32, u32),
    ) {
        // Rows are below `height`, entries below the bucket capacity.
        let mut entry = internal(self.heads.get(row).map(|h| h.entry()), NO_ENTRY);
        while entry != NO_ENTRY {
            let e = entry as usize;
            entry = internal(self.next.get(e).map(|n| n.entry()), NO_ENTRY);
            self.pieces.each_piece::<S>(e, &mut f);
        }
    }
}

/// Where pass 2 gets the pieces of a bucket entry from.
pub(crate) trait ActivePieces<const SUB: u32> {
    /// Whether every piece's depth plane solves in 64 bits ([`DepthPlane::new_i64`]).
    const DEPTH_PLANES_I64: bool = false;
    /// Calls `f(vertices, face colour, triangle id, sort key)` for each screen piece of bucket
    /// entry `entry` (a clipped triangle may have several).
    fn each_piece<S: Shading>(
        &self,
        entry: usize,
        f: impl FnMut(&[ScreenVertex<SUB>; 3], Rgb888, u32, u32),
    );
}

/// Pieces of mesh triangles, transformed, clipped and projected again on activation.
struct MeshPieces<'a, 's, const SUB: u32, C, A: Arithmetic, D> {
    setups: &'a [InstanceSetup<'s, A::Transform>],
    refs: &'a [u16],
    keys: &'a [u32],
    cache: &'a [CachedVertex],
    vp: &'a Viewport<SUB>,
    cull: bool,
    stages: core::marker::PhantomData<(C, A, D)>,
}

impl<const SUB: u32, C: Clipping, A: Arithmetic, D: ScreenBound> ActivePieces<SUB>
    for MeshPieces<'_, '_, SUB, C, A, D>
{
    /// Without clipping every piece is a triangle inside every clip plane (others are
    /// skipped); projected with the exact division on a bounded screen, its depth plane
    /// solves in 64 bits ([`depth_planes_fit_i64`]).
    const DEPTH_PLANES_I64: bool = !C::CLIPS
        && !<A::Projection as ProjectionPrecision>::RECIPROCAL
        && depth_planes_fit_i64(D::MAX_SIDE, SUB);

    #[inline(always)]
    fn each_piece<S: Shading>(
        &self,
        e: usize,
        mut f: impl FnMut(&[ScreenVertex<SUB>; 3], Rgb888, u32, u32),
    ) {
        // Entries, ids and triangles all come from pass 1 of this frame.
        let Some(&id) = self.refs.get(e) else {
            debug_assert!(false, "internal error: no bucket entry {e}");
            return;
        };
        // Keys exist (one per entry) only for methods that sort.
        let key = if self.keys.is_empty() {
            0
        } else {
            internal(self.keys.get(e).copied(), 0)
        };
        let Some((setup, tri)) = locate(self.setups, id as u32) else {
            debug_assert!(false, "internal error: no instance has triangle {id}");
            return;
        };
        let Some(&idx) = setup.instance.mesh.triangles().get(tri) else {
            debug_assert!(false, "internal error: no triangle {tri} for id {id}");
            return;
        };
        let face = if S::PER_VERTEX {
            Rgb888::new(0, 0, 0)
        } else {
            setup.face_color::<S, A::Normals>(tri, idx)
        };
        let (vp, cache) = (self.vp, self.cache);
        setup.screen_triangles::<SUB, C, A>(
            tri,
            cache,
            vp,
            self.cull,
            S::PER_VERTEX,
            true,
            true,
            |s| f(s, face, id as u32, key),
        );
    }
}

/// Walks the rows top to bottom in bands (one row except for band z-buffers): activates each
/// row's bucket through `pieces`, hands the active triangles' spans to `resolve` and the
/// finished rows to `sink`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn walk_rows<
    P: RowPixel,
    S: Shading,
    const SUB: u32,
    K: RowSink<P>,
    R: Resolve<P, S>,
    Q: RowPieces<SUB>,
>(
    height: usize,
    active: &mut VecView<ActiveTri<S::Payload<P>, R::Key>>,
    pieces: &mut Q,
    resolve: &mut R,
    width: i32,
    sink: &mut K,
    stats: &mut FrameStats,
) -> Result<(), RenderError<K::Error>> {
    let band = resolve.band_rows().max(1);
    let mut active = ActiveList::new(active);
    // Last row covered by any dropped piece so far: rows up to it are incomplete.
    let mut lost_until = -1i32;
    let mut y0 = 0usize;
    while y0 < height {
        let y1 = (y0 + band).min(height);
        resolve.begin_band(y0 as i32, y1 - y0);
        if band > 1 {
            // Triangles carried over from earlier bands come first, in activation order.
            active.retain(|t, order| {
                walk_band::<P, S, SUB, R>(t, order, y1 as i32, width, resolve, stats)
            });
        }
        for row in y0..y1 {
            let y = row as i32;
            activate_row::<P, S, SUB, R, Q>(
                pieces,
                row,
                height as i32,
                &mut active,
                resolve,
                (band, y1 as i32),
                width,
                stats,
                &mut lost_until,
            );
            if band == 1 {
                stats.peak_active = stats.peak_active.max(active.live as u16);
                walk_active_row::<P, S, SUB, R>(&mut active, y, width, resolve, stats);
            }
        }
        if band > 1 {
            stats.peak_active = stats.peak_active.max(active.live as u16);
        }

        for row in y0..y1 {
            let y = row as i32;
            let done = resolve.finish_row(y);
            stats.spans += done.spans as u32;
            stats.peak_spans = stats.peak_spans.max(done.spans);
            stats.pixels_written += done.written;
            let complete = y > lost_until;
            stats.incomplete_rows += !complete as u16;
            sink.write_row(Row {
                y: row as u16,
                pixels: done.pixels,
                depth: done.depth,
                complete,
            })
            .map_err(|error| RenderError::Sink {
                row: row as u16,
                error,
            })?;
            stats.rows += 1;
        }
        y0 = y1;
    }
    Ok(())
}

/// Activates row `row`'s pieces: sets up each one's walk, depth plane and payload and puts it
/// on the active list (a band z-buffer draws it into the band first), reporting a piece that
/// finds no room. Always inlined: as a call of its own it saved up to 1 % of the corpus
/// firmware's frames but cost the lean build 1,092 B of flash and 480 B of stack (thumbv6m).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn activate_row<P: RowPixel, S: Shading, const SUB: u32, R: Resolve<P, S>, Q: RowPieces<SUB>>(
    pieces: &mut Q,
    row: usize,
    height: i32,
    active: &mut ActiveList<'_, S::Payload<P>, R::Key>,
    resolve: &mut R,
    (band, y1): (usize, i32),
    width: i32,
    stats: &mut FrameStats,
    lost_until: &mut i32,
) {
    let y = row as i32;
    pieces.each_row_piece::<S>(row, |s, face, id, key| {
        let solver = PlaneSolver::new(s);
        let walk = solver.and_then(|solver| {
            let v = s.each_ref().map(xy);
            TriangleWalk::oriented::<SUB>(v, solver.negative(), y, height)
        });
        let (Some(walk), Some(solver)) = (walk, solver) else {
            // Pieces have screen area and rows from this one on (their bucket is their first
            // row, or the first of their triangle's pieces).
            debug_assert!(false, "internal error: piece of {id} not walkable");
            return;
        };
        let depth = match Q::DEPTH_PLANES_I64 {
            true => DepthPlane::new_i64(&solver, s),
            false => DepthPlane::new(&solver, s),
        };
        // On Arm the walk's span starts take the plane in 32-bit words (`SplitWalk`), exact for
        // vertex depths up to MAX_DRAWN_DEPTH, which every vertex of a drawn triangle has.
        debug_assert!(
            s.iter().all(|v| v.q.to_bits() <= MAX_DRAWN_DEPTH),
            "internal error: a drawn vertex beyond the near plane"
        );
        let mut tri_state = ActiveTri {
            walk,
            depth: depth.walk_from(walk.row()),
            depth_step: depth.step(),
            payload: S::payload::<P, SUB>(face, id, &solver, s),
            key: R::Key::from_raw(key),
            link: NO_LINK,
        };
        let (first_row, last_row) = (tri_state.walk.row(), tri_state.walk.end_row() - 1);
        let kept = if R::BANDED && band > 1 {
            // Band z-buffer: draw it into the band now; keep it only if it reaches the next
            // band (so a full z-buffer keeps nothing).
            let order = active.live;
            !walk_band::<P, S, SUB, R>(&mut tri_state, order, y1, width, resolve, stats)
                || active.insert(tri_state)
        } else {
            active.insert(tri_state)
        };
        if kept {
            stats.activated += 1;
            return;
        }
        // Degrade deterministically: this piece (or its rest) is lost, everything else is
        // drawn.
        let piece = DroppedPiece {
            triangle: id,
            first_row: first_row as u16,
            last_row: last_row as u16,
        };
        if let Some(slot) = stats.dropped_pieces.get_mut(stats.dropped as usize) {
            *slot = Some(piece);
        }
        stats.dropped += 1;
        *lost_until = (*lost_until).max(last_row);
    });
}

/// Walks triangle `t` down to row `y1` (exclusive), handing each on-screen span to `resolve`.
/// Returns whether the triangle continues below `y1`.
#[inline(always)]
fn walk_band<P: RowPixel, S: Shading, const SUB: u32, R: Resolve<P, S>>(
    t: &mut ActiveTri<S::Payload<P>, R::Key>,
    order: usize,
    y1: i32,
    width: i32,
    resolve: &mut R,
    stats: &mut FrameStats,
) -> bool {
    loop {
        let y = t.walk.row();
        if y >= y1 {
            return true; // (a clipped piece may start below the band)
        }
        let (l, r) = t.walk.span();
        let (l, r) = (l.max(0), r.min(width));
        if l < r {
            stats.fragments += (r - l) as u32;
            stats.pixels_written += resolve.span(t, order, y, l, r);
        }
        if !t.advance::<SUB>() {
            return false;
        }
    }
}

/// Hands row `y`'s spans of every active triangle to `resolve` and steps them, taking finished
/// ones off the list. Not inlined: the row loop then keeps its counters and the walk in
/// registers instead of sharing them with the whole frame's set-up (on Cortex-M4 the inlined
/// loop spilled them to the stack frame).
#[inline(never)]
fn walk_active_row<P: RowPixel, S: Shading, const SUB: u32, R: Resolve<P, S>>(
    active: &mut ActiveList<'_, S::Payload<P>, R::Key>,
    y: i32,
    width: i32,
    resolve: &mut R,
    stats: &mut FrameStats,
) {
    let mut counts = SpanCounts::default();
    active.retain(|t, order| walk_row::<P, S, SUB, R>(t, order, y, width, resolve, &mut counts));
    stats.fragments += counts.fragments;
    stats.pixels_written += counts.written;
}

/// Fragments (pixels of spans on the screen) and pixels written on one row.
#[derive(Default)]
struct SpanCounts {
    fragments: u32,
    written: u32,
}

/// [`walk_band`] for a band of the one row `y`, which every live triangle has reached: its
/// span there, if it is on the row, and one step, with one row test instead of the band
/// loop's two. Returns whether the triangle continues below `y`.
#[inline(always)]
fn walk_row<P: RowPixel, S: Shading, const SUB: u32, R: Resolve<P, S>>(
    t: &mut ActiveTri<S::Payload<P>, R::Key>,
    order: usize,
    y: i32,
    width: i32,
    resolve: &mut R,
    counts: &mut SpanCounts,
) -> bool {
    let row = t.walk.row();
    if row > y {
        return true; // (a clipped piece may start below the row)
    }
    let (l, r) = t.walk.span();
    let (l, r) = (l.max(0), r.min(width));
    if l < r {
        counts.fragments += (r - l) as u32;
        counts.written += resolve.span(t, order, row, l, r);
    }
    t.advance::<SUB>()
}

/// Transforms, clips, projects and culls every triangle of `scene` (lit per vertex if `S`
/// needs it) and calls `f(vertices, face colour, id)` for each visible screen piece, in id
/// order: the set-up of whole-frame methods, which keep every piece.
pub(crate) fn for_each_screen_piece<
    S: Shading,
    const SUB: u32,
    C: Clipping,
    A: Arithmetic,
    E,
    const INSTANCES: usize,
>(
    scene: &Scene<'_>,
    options: &RenderOptions<SUB, C, A>,
    vp: &Viewport<SUB>,
    mut f: impl FnMut([ScreenVertex<SUB>; 3], Rgb888, u32),
) -> Result<FrameStats, RenderError<E>> {
    let setups = setup_instances::<S, A::Transform, E, INSTANCES>(scene)?;
    let mut stats = FrameStats::default();
    for setup in &setups {
        let triangles = setup.instance.mesh.triangles();
        stats.triangles_in += triangles.len() as u32;
        for (tri, &idx) in triangles.iter().enumerate() {
            let id = setup.first_id + tri as u32;
            let face = if S::PER_VERTEX {
                Rgb888::new(0, 0, 0)
            } else {
                setup.face_color::<S, A::Normals>(tri, idx)
            };
            let fate = setup.screen_triangles::<SUB, C, A>(
                tri,
                &[],
                vp,
                options.cull_back_faces,
                S::PER_VERTEX,
                true,
                false,
                |s| f(*s, face, id),
            );
            match fate {
                Fate::Culled => stats.culled += 1,
                Fate::Rejected => stats.rejected += 1,
                Fate::Unclipped => stats.unclipped += 1,
                Fate::Visible { clipped, .. } => {
                    stats.clipped += clipped as u32;
                    stats.bucketed += 1;
                }
            }
        }
    }
    Ok(stats)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_internal_look_up_passes_its_value_through() {
        assert_eq!(internal(Some(7u8), 0), 7);
    }

    #[test]
    #[cfg(debug_assertions)]
    #[should_panic(expected = "internal error")]
    fn a_failed_internal_look_up_stops_a_debug_build() {
        internal::<u8>(None, 0);
    }

    #[test]
    #[cfg(not(debug_assertions))]
    fn a_failed_internal_look_up_falls_back_in_release() {
        assert_eq!(internal::<u8>(None, 9), 9);
    }
}
