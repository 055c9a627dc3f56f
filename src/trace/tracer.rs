//! The fixed-point Whitted tracer: per pixel a primary ray, then the ray tree on an explicit,
//! bounded stack; finished rows go to a [`RowSink`].
//!
//! ## The shading model (the same as `sim`'s f64 reference)
//!
//! A ray's colour is the background if it hits nothing with `t ≥` [`EPSILON`] (primary rays:
//! eye depth in `[near, far)`; of equal `t` the smaller id wins); otherwise the local term `KA·C·ambient + Σ KD·max(0, N·L)·C·I`
//! over the lights whose shadow ray reaches them unblocked (any object hit with
//! `EPSILON ≤ t <` the light's distance blocks it), plus `KR·colour(R)` and `KT·colour(T)`.
//! N faces the incoming ray; `R = d − 2(N·d)N`; `T` follows Snell's law from IOR 1 into the
//! object's IOR when the ray enters it (its outward normal faces the ray) and from the IOR to
//! 1 when it leaves; on total internal reflection `T = R`. The tree ends where the lecture's four
//! rules say: no hit, a diffuse surface (KR = KT = 0), a child's weight (product of KR/KT along
//! its path) below [`TraceOptions::threshold`], or the depth limit
//! [`TraceOptions::max_depth`] (the primary ray has depth 0; a ray at the limit spawns
//! nothing). The pixel is clamped to [0, 1] per channel once, then rounded to 8 bits.
//!
//! ## No recursion
//!
//! Since the model is linear, a ray's contribution is its weight times its local term: the tree
//! is walked depth first with a stack of pending rays, each carrying its weight and depth. Each
//! ray pops one entry and pushes at most two, so `max_depth + 1` entries always suffice; the
//! stack's capacity is the const generic `STACK` of [`Tracer`]. A ray that finds the stack full
//! is not traced: [`TraceStats::dropped_rays`] counts it and the row goes out with
//! `complete: false`.

use crate::depth::DepthRow;
use crate::math::div_rem_u64_u32;
use crate::sink::{Row, RowPixel, RowSink};
use crate::trace::intersect::{reflect, Ray};
use crate::trace::row_shadow::{any_blocks, RowShadows, ShadowCandidate, ShadowWindows};
use crate::trace::scene::{Colour, LightKind, Scene, TraceCamera, MAX_LIGHTS};
use crate::trace::vector::{
    mul, mul_in_range, mul_shr32, narrow_bits, narrow_bits_in_range, sqrt, wide, Vec3,
};
use embedded_graphics::pixelcolor::Rgb888;
use fixed::types::{I16F16, I32F32};

/// The smallest `t` (world units) a secondary or shadow ray accepts, so a ray leaving a surface
/// does not hit it again: 2^-10 ≈ 0.001, above the position error of a hit (a few 2^-16 steps
/// times the distance in units of 2^4; see `vector` and `intersect`).
pub const EPSILON: I16F16 = I16F16::from_bits(1 << 6);

/// Default depth limit of the ray tree.
pub const DEFAULT_MAX_DEPTH: u8 = 4;
/// Default weight threshold: a secondary ray whose weight is below 1/256 is not traced.
pub const DEFAULT_THRESHOLD: I16F16 = I16F16::from_bits(1 << 8);

/// Most objects a scene may have for every ray (primary, reflected, refracted, shadow) to test
/// every object instead of walking the hierarchy: the walk's set-up (the direction's
/// reciprocals) and box tests cost more than a few object tests (the classic's 3 objects:
/// docs/tracing.md). Either search finds the same hit (the nearest-hit rule does not depend on
/// the order) and the same blocker or none.
const FEW_OBJECTS: usize = 4;

/// The termination rules a frame uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TraceOptions {
    /// Depth of the deepest ray that may be traced (the primary ray has depth 0).
    pub max_depth: u8,
    /// Smallest weight of a traced secondary ray.
    pub threshold: I16F16,
}

impl Default for TraceOptions {
    fn default() -> Self {
        TraceOptions {
            max_depth: DEFAULT_MAX_DEPTH,
            threshold: DEFAULT_THRESHOLD,
        }
    }
}

/// What one frame (or pixel) did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TraceStats {
    /// Primary rays.
    pub primary_rays: u32,
    /// Reflected and refracted rays traced.
    pub secondary_rays: u32,
    /// Shadow rays traced (lights with N·L ≤ 0 need none).
    pub shadow_rays: u32,
    /// Ray–primitive intersection tests.
    pub intersection_tests: u32,
    /// Ray–box tests in the bounding-volume hierarchy.
    pub box_tests: u32,
    /// Grid cells visited.
    pub grid_cells: u32,
    /// Secondary rays not traced because the ray stack was full (0 when `STACK > max_depth`).
    pub dropped_rays: u32,
    /// Shadow rays answered by the shadow cache: the object that blocked the previous shadow
    /// ray towards the same light blocked this one too (one test instead of a walk).
    pub shadow_cache_hits: u32,
    /// Hybrid mode: shadow rays from a row's first hits on its plane that the row's shadow
    /// windows found clear (no object can block them: no test).
    pub window_clear_rays: u32,
    /// Hybrid mode: rows whose primary visibility fell back to the pure tracer's search because
    /// the screen-bound buffer or the active list was full (same image, more work).
    pub fallback_rows: u16,
    /// Hybrid mode: rows whose shadow rays all walked the hierarchy instead of the row's
    /// candidate lists, because the candidate buffer was full or a visible object is
    /// unbounded (same image, more work); rows counted in `fallback_rows` are not counted again.
    pub shadow_fallback_rows: u16,
    /// Hybrid mode: primary rays that walked the hierarchy because their row, or their group of
    /// columns, had more screen rectangles than scanning them pays for (same hit).
    pub walked_primary_rays: u32,
    /// Most pending rays on the stack at once.
    pub peak_stack: u16,
    /// Rows handed to the sink.
    pub rows: u16,
}

impl TraceStats {
    /// All rays traced: primary, secondary and shadow.
    pub fn rays(&self) -> u32 {
        self.primary_rays + self.secondary_rays + self.shadow_rays
    }

    /// Adds `o`'s counts to these (the peak stack is the larger of the two).
    pub fn add(&mut self, o: &TraceStats) {
        self.primary_rays += o.primary_rays;
        self.secondary_rays += o.secondary_rays;
        self.shadow_rays += o.shadow_rays;
        self.intersection_tests += o.intersection_tests;
        self.box_tests += o.box_tests;
        self.grid_cells += o.grid_cells;
        self.dropped_rays += o.dropped_rays;
        self.shadow_cache_hits += o.shadow_cache_hits;
        self.window_clear_rays += o.window_clear_rays;
        self.fallback_rows += o.fallback_rows;
        self.shadow_fallback_rows += o.shadow_fallback_rows;
        self.walked_primary_rays += o.walked_primary_rays;
        self.peak_stack = self.peak_stack.max(o.peak_stack);
    }
}

/// Why a traced frame failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TraceError<E> {
    /// The row buffer's length is not the camera's width.
    RowLength,
    /// The sink refused a row.
    Sink(E),
}

/// What the tracer found at one pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelTrace {
    /// The pixel's colour (clamped, rounded to 8 bits).
    pub colour: Rgb888,
    /// Id of the object the primary ray hit, if any.
    pub id: Option<u32>,
    /// Eye depth of the primary hit.
    pub depth: I16F16,
    /// Bit k set when light k contributes nothing at the primary hit (N·L ≤ 0 or blocked).
    pub shadow: u8,
    /// Index in [`Scene::materials`] of the material at the primary hit (a checker texture's
    /// cell's), if any.
    pub material: Option<u16>,
}

/// A ray waiting on the stack.
#[derive(Clone, Copy, Debug)]
struct Pending {
    ray: Ray,
    weight: I16F16,
    depth: u8,
    /// The object whose surface the ray starts on (`u32::MAX` for a primary ray).
    from: u32,
}

/// The nearest hit along a ray.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Hit {
    t: I16F16,
    object: u32,
}

/// The nearest-hit search over the objects a ray is offered: the smallest `t` wins and equal
/// `t` go to the smaller id (the f64 reference's rule), so the answer does not depend on the
/// order objects are offered in: the hierarchy's, the grid's or the hybrid mode's.
pub(crate) struct Nearest {
    best: Option<Hit>,
    t_min: I16F16,
    t_max: I16F16,
    /// [`limit`](Self::limit), kept up to date when `best` changes rather than recomputed
    /// from it on every offer.
    limit: I16F16,
    from: u32,
    tests: u32,
}

impl Nearest {
    /// A search along a ray starting on object `from` (`u32::MAX`: none) over `[t_min, t_max)`.
    pub(crate) fn new(from: u32, t_min: I16F16, t_max: I16F16) -> Nearest {
        Nearest {
            best: None,
            t_min,
            t_max,
            limit: t_max,
            from,
            tests: 0,
        }
    }

    /// The exclusive bound an object's `t` must stay below to matter: `t_max`, or once
    /// something is hit one step above its `t` (a tie may still win on its id).
    pub(crate) fn limit(&self) -> I16F16 {
        self.limit
    }

    /// Keeps `t` on object `id` if it is nearer (or as near, on a smaller id) than the best.
    #[inline]
    fn keep(&mut self, t: I16F16, id: u32) {
        if self.best.is_none_or(|b| t < b.t || id < b.object) {
            self.best = Some(Hit { t, object: id });
            self.limit = t.saturating_add(I16F16::DELTA).min(self.t_max);
        }
    }

    /// Tests object `id` of `scene` and keeps it if it is nearer; returns the new limit.
    pub(crate) fn offer(&mut self, scene: &Scene<'_>, id: u32, ray: &Ray) -> I16F16 {
        self.tests += 1;
        let limit = self.limit;
        let t = scene.objects.get(id as usize).and_then(|object| {
            if id == self.from {
                object.shape.hit_from_surface(ray, self.t_min, limit)
            } else {
                object.shape.hit(ray, self.t_min, limit)
            }
        });
        if let Some(t) = t {
            self.keep(t, id);
        }
        self.limit
    }

    /// [`offer`](Self::offer) for a primary ray (`from` is none) known to meet planar object
    /// `id` inside its outline if it meets its plane: the point-in-polygon test is skipped.
    pub(crate) fn offer_inside_outline(&mut self, scene: &Scene<'_>, id: u32, ray: &Ray) {
        self.tests += 1;
        let t = scene
            .objects
            .get(id as usize)
            .and_then(|object| object.shape.hit_inside_outline(ray, self.t_min, self.limit));
        if let Some(t) = t {
            self.keep(t, id);
        }
    }

    /// The nearest hit found; adds the tests made to `stats`.
    pub(crate) fn finish(self, stats: &mut TraceStats) -> Option<Hit> {
        stats.intersection_tests += self.tests;
        self.best
    }
}

/// Per light, the object that blocked the last shadow ray towards it (`u32::MAX`: none yet):
/// a shadow ray tests that object first (Haines and Greenberg's shadow cache), and if it blocks
/// the answer is the same "blocked" a full search gives, at one test. It changes no pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ShadowCache([u32; MAX_LIGHTS]);

impl ShadowCache {
    /// An empty cache.
    pub const fn new() -> ShadowCache {
        ShadowCache([u32::MAX; MAX_LIGHTS])
    }
}

impl Default for ShadowCache {
    fn default() -> Self {
        ShadowCache::new()
    }
}

/// A Whitted tracer over one scene and camera whose ray stack holds `STACK` pending rays
/// (`STACK · 36` bytes on the call stack).
#[derive(Clone, Copy, Debug)]
pub struct Tracer<'s, 'a, const STACK: usize> {
    scene: &'s Scene<'a>,
    camera: &'s TraceCamera,
    options: TraceOptions,
}

impl<'s, 'a, const STACK: usize> Tracer<'s, 'a, STACK> {
    /// A tracer for `scene` seen by `camera`.
    pub fn new(scene: &'s Scene<'a>, camera: &'s TraceCamera, options: TraceOptions) -> Self {
        Tracer {
            scene,
            camera,
            options,
        }
    }

    /// Renders the frame row by row into `row` (length = the camera's width), handing each row
    /// to `sink`.
    pub fn render<P: RowPixel, S: RowSink<P>>(
        &self,
        row: &mut [P],
        sink: &mut S,
    ) -> Result<TraceStats, TraceError<S::Error>> {
        if row.len() != usize::from(self.camera.width) {
            return Err(TraceError::RowLength);
        }
        let mut stats = TraceStats::default();
        let mut cache = ShadowCache::new();
        for y in 0..self.camera.height {
            let dropped_before = stats.dropped_rays;
            for (x, pixel) in (0..self.camera.width).zip(row.iter_mut()) {
                let p = self.trace_with(
                    x,
                    y,
                    &mut cache,
                    None,
                    &mut stats,
                    |ray, t_min, t_max, stats| self.nearest(ray, u32::MAX, t_min, t_max, stats),
                );
                *pixel = P::from_shade(p.colour, p.id.unwrap_or(u32::MAX));
            }
            sink.write_row(Row {
                y,
                pixels: row,
                depth: DepthRow::NONE,
                complete: stats.dropped_rays == dropped_before,
            })
            .map_err(TraceError::Sink)?;
            stats.rows += 1;
        }
        Ok(stats)
    }

    /// Traces the pixel (`column`, `row`): its colour, primary id, depth and shadow mask, and
    /// what it cost.
    pub fn trace_pixel(&self, column: u16, row: u16) -> (PixelTrace, TraceStats) {
        self.trace_pixel_cached(column, row, &mut ShadowCache::new())
    }

    /// [`trace_pixel`](Self::trace_pixel) with a shadow cache kept from pixel to pixel (what
    /// [`render`](Self::render) does: same result, fewer tests).
    pub fn trace_pixel_cached(
        &self,
        column: u16,
        row: u16,
        cache: &mut ShadowCache,
    ) -> (PixelTrace, TraceStats) {
        let mut stats = TraceStats::default();
        let p = self.trace_with(
            column,
            row,
            cache,
            None,
            &mut stats,
            |ray, t_min, t_max, stats| self.nearest(ray, u32::MAX, t_min, t_max, stats),
        );
        (p, stats)
    }

    /// The scene traced.
    pub(crate) fn scene(&self) -> &'s Scene<'a> {
        self.scene
    }

    /// The camera.
    pub(crate) fn camera(&self) -> &'s TraceCamera {
        self.camera
    }

    /// Traces pixel (`column`, `row`) with `first_hit` finding the primary ray's nearest hit in
    /// `[t_min, t_max)`; everything after the primary hit is the same for every mode, except
    /// that with `row_shadows` the shadow rays starting in the row's region (those from the
    /// primary hit, and from deeper hits that lie there) test the row's candidate lists instead
    /// of walking the hierarchy (same answers). The pixel's counts are added to `stats` (the
    /// frame's, not a pixel's own: no per-pixel record to clear and add up).
    pub(crate) fn trace_with(
        &self,
        column: u16,
        row: u16,
        cache: &mut ShadowCache,
        row_shadows: Option<&RowShadows<'_>>,
        stats: &mut TraceStats,
        mut first_hit: impl FnMut(&Ray, I16F16, I16F16, &mut TraceStats) -> Option<Hit>,
    ) -> PixelTrace {
        stats.primary_rays += 1;
        let mut out = PixelTrace {
            colour: Rgb888::new(0, 0, 0),
            id: None,
            depth: I16F16::ZERO,
            shadow: 0,
            material: None,
        };
        let raw = self.camera.pixel_direction(column, row);
        let Some((dir, len)) = raw.normalized_with_length_inlined() else {
            return out;
        };
        // Eye depth = t / len (the raw direction has unit forward component).
        let primary = Ray {
            origin: self.camera.eye,
            dir,
        };
        let window = (
            mul(self.camera.near, len),
            I16F16::from_bits(narrow_bits(wide(self.camera.far.to_bits(), len.to_bits()))),
        );
        let mut sum = Colour::BLACK;
        let mut stack: heapless::Vec<Pending, STACK> = heapless::Vec::new();
        let mut next = Some((
            Pending {
                ray: primary,
                weight: I16F16::ONE,
                depth: 0,
                from: u32::MAX,
            },
            window,
        ));
        while let Some((ray, (t_min, t_max))) = next.take() {
            let is_primary = ray.depth == 0;
            let hit = if is_primary {
                first_hit(&ray.ray, t_min, t_max, stats)
            } else {
                self.nearest(&ray.ray, ray.from, t_min, t_max, stats)
            };
            match hit {
                None => add_weighted(&mut sum, &self.scene.background, ray.weight),
                Some(hit) => {
                    // The row's shadow windows serve the first hits of its pixels only.
                    let windows = row_shadows
                        .filter(|_| is_primary)
                        .and_then(|r| r.windows_at(column, hit.object))
                        .map(|w| (w, column));
                    let (shadow, material) = self.shade(
                        &ray,
                        hit,
                        windows,
                        &mut sum,
                        &mut stack,
                        cache,
                        row_shadows,
                        stats,
                    );
                    if is_primary {
                        out.id = Some(hit.object);
                        out.depth = hit.t.checked_div(len).unwrap_or(I16F16::MAX);
                        out.shadow = shadow;
                        out.material = material;
                    }
                }
            }
            stats.peak_stack = stats.peak_stack.max(stack.len() as u16);
            next = stack.pop().map(|p| (p, (EPSILON, I16F16::MAX)));
        }
        out.colour = to_rgb888(&sum);
        out
    }

    /// What [`trace_with`](Self::trace_with) gives pixel (`column`, `row`) when its primary ray
    /// is offered no object (hybrid mode, where no screen rectangle covers the pixel): the
    /// background, or black when the direction cannot be normalised, without normalising it.
    /// The ray's cost is one primary ray and nothing else.
    pub(crate) fn background_pixel(&self, column: u16, row: u16) -> PixelTrace {
        let mut sum = Colour::BLACK;
        if self.camera.pixel_direction(column, row).normalizable() {
            add_weighted(&mut sum, &self.scene.background, I16F16::ONE);
        }
        PixelTrace {
            colour: to_rgb888(&sum),
            id: None,
            depth: I16F16::ZERO,
            shadow: 0,
            material: None,
        }
    }

    /// The nearest object along `ray` (which starts on object `from`; `u32::MAX` for a primary
    /// ray) with `t` in `[t_min, t_max)`: through the scene's structure, except that in a scene
    /// of at most [`FEW_OBJECTS`] every ray tests every object.
    pub(crate) fn nearest(
        &self,
        ray: &Ray,
        from: u32,
        t_min: I16F16,
        t_max: I16F16,
        stats: &mut TraceStats,
    ) -> Option<Hit> {
        let scene = self.scene;
        let mut search = Nearest::new(from, t_min, t_max);
        match (&scene.grid, &scene.bvh) {
            (Some(grid), _) => {
                for id in grid.unbounded() {
                    search.offer(scene, *id, ray);
                }
                let limit = search.limit();
                stats.grid_cells += grid.walk(ray, t_min, limit, |id, _| {
                    Some(search.offer(scene, id, ray))
                });
            }
            (None, Some(bvh)) if scene.objects.len() > FEW_OBJECTS => {
                for id in bvh.unbounded() {
                    search.offer(scene, *id, ray);
                }
                let limit = search.limit();
                stats.box_tests += bvh.walk(ray, t_min, limit, |id, _| {
                    Some(search.offer(scene, id, ray))
                });
            }
            // No structure, or a scene of a few objects.
            (None, _) => {
                for id in 0..scene.objects.len() as u32 {
                    search.offer(scene, id, ray);
                }
            }
        }
        search.finish(stats)
    }

    /// Whether object `id` blocks the shadow ray `ray` (which starts on object `from`) in
    /// `[EPSILON, t_max)` ([`Shape::blocks`](crate::trace::Shape::blocks); `t_max` = `I16F16::MAX` for a directional
    /// light).
    // Inlined, as `shade` is (measured alike).
    #[inline(always)]
    fn blocks(&self, id: u32, ray: &Ray, from: u32, t_max: I16F16) -> bool {
        let Some(object) = self.scene.objects.get(id as usize) else {
            return false;
        };
        if id == from {
            object.shape.hit_from_surface(ray, EPSILON, t_max).is_some()
        } else {
            object.shape.blocks(ray, EPSILON, t_max)
        }
    }

    /// Whether any object lies along `ray` (which starts on object `from`) with `t` in
    /// `[EPSILON, t_max)`. `cached` is the light's entry in the shadow cache: tested first, and
    /// set to the blocker found. With `candidates` (hybrid mode, a shadow ray from the row's
    /// region) only those are tested, else the scene's structure is walked.
    fn blocked(
        &self,
        ray: &Ray,
        from: u32,
        t_max: I16F16,
        cached: &mut u32,
        candidates: Option<&[ShadowCandidate]>,
        stats: &mut TraceStats,
    ) -> bool {
        // The cached object is tested only if it names one that can block: with candidates,
        // one of them (any other cannot block this ray).
        let cache_useful = *cached != u32::MAX
            && candidates.is_none_or(|list| list.iter().any(|c| c.object == *cached));
        let mut tests = u32::from(cache_useful);
        if cache_useful && self.blocks(*cached, ray, from, t_max) {
            stats.intersection_tests += tests;
            stats.shadow_cache_hits += 1;
            return true;
        }
        let mut blocker = None;
        let mut blocks = |id: u32| {
            tests += 1;
            let hit = self.blocks(id, ray, from, t_max);
            if hit {
                blocker = Some(id);
            }
            hit
        };
        match (candidates, &self.scene.grid, &self.scene.bvh) {
            (Some(list), _, _) => {
                // Two candidates are known not to block: the cached object, just tested with
                // the same call, and a planar object the ray starts on (never met again).
                let from_planar = self
                    .scene
                    .objects
                    .get(from as usize)
                    .is_some_and(|o| o.shape.plane().is_some());
                let skip = (*cached, if from_planar { from } else { u32::MAX });
                let _ = any_blocks(self.scene, list, ray, EPSILON, t_max, |id| {
                    id != skip.0 && id != skip.1 && blocks(id)
                });
            }
            (None, Some(grid), _) => {
                if !grid.unbounded().iter().any(|id| blocks(*id)) {
                    stats.grid_cells += grid.walk(ray, EPSILON, t_max, |id, limit| {
                        (!blocks(id)).then_some(limit)
                    });
                }
            }
            (None, None, Some(bvh)) if self.scene.objects.len() > FEW_OBJECTS => {
                if !bvh.unbounded().iter().any(|id| blocks(*id)) {
                    stats.box_tests += bvh.walk(ray, EPSILON, t_max, |id, limit| {
                        (!blocks(id)).then_some(limit)
                    });
                }
            }
            (None, None, _) => {
                let _ = (0..self.scene.objects.len() as u32).any(&mut blocks);
            }
        }
        stats.intersection_tests += tests;
        match blocker {
            Some(id) => {
                *cached = id;
                true
            }
            None => false,
        }
    }

    /// Adds the local term at `hit` times the ray's weight to `sum`, pushes the reflected and
    /// refracted rays the rules allow, and returns the shadow mask at the hit and the index of
    /// the material there. `windows`: the row's shadow windows and the pixel's column, when
    /// they serve this hit (a pixel's first hit in hybrid mode, [`RowShadows::windows_at`]).
    // The per-pixel state a ray adds to (colour sum, ray stack, shadow cache, the row's
    // shadow candidates, counts), each borrowed apart.
    #[allow(clippy::too_many_arguments)]
    // Inlined into each frame loop (pure, and the hybrid mode's two): out of line, as the
    // compiler keeps it for several callers, every mode's frame took more instructions
    // (`cargo xtask trace alone`, docs/tracing.md).
    #[inline(always)]
    fn shade(
        &self,
        pending: &Pending,
        hit: Hit,
        windows: Option<(&ShadowWindows, u16)>,
        sum: &mut Colour,
        stack: &mut heapless::Vec<Pending, STACK>,
        cache: &mut ShadowCache,
        row_shadows: Option<&RowShadows<'_>>,
        stats: &mut TraceStats,
    ) -> (u8, Option<u16>) {
        let scene = self.scene;
        let Some(object) = scene.objects.get(hit.object as usize) else {
            return (0, None);
        };
        let ray = &pending.ray;
        let point = ray.origin.along_ray(ray.dir, hit.t);
        let index = scene.material_index_at(object, point);
        let Some(material) = index.and_then(|m| scene.materials.get(usize::from(m))) else {
            return (0, None);
        };
        let outward = object.shape.normal(point);
        // N faces the incoming ray; `entering` when the outward normal does.
        let entering = outward.dot_bits(ray.dir) < 0;
        let normal = if entering { outward } else { outward.neg() };

        let mut diffuse = I16F16::ZERO; // Σ max(0, N·L)·I over unblocked lights
        let mut shadow = 0u8;
        for ((k, light), cached) in scene.lights.iter().enumerate().zip(cache.0.iter_mut()) {
            let (towards, distance) = match light.kind {
                LightKind::Directional(d) => (d, I16F16::MAX),
                LightKind::Point(p) => {
                    let v = p.sub(point);
                    v.normalized_with_length_inlined()
                        .unwrap_or((Vec3::ZERO, I16F16::ZERO))
                }
            };
            // Two unit vectors: |N·L| ≤ 1.
            let nl = I16F16::from_bits(narrow_bits_in_range(normal.dot_bits(towards)));
            let lit = nl > I16F16::ZERO && {
                stats.shadow_rays += 1;
                let shadow_ray = Ray {
                    origin: point,
                    dir: towards,
                };
                // Outside its light's window nothing can block the ray: no test.
                let clear = match windows {
                    Some((w, x)) if w.clear(k, x) => {
                        stats.window_clear_rays += 1;
                        true
                    }
                    _ => false,
                };
                clear || {
                    let candidates =
                        row_shadows.and_then(|r| r.for_ray(k, &light.kind, point, distance));
                    !self.blocked(&shadow_ray, hit.object, distance, cached, candidates, stats)
                }
            };
            if lit {
                // N·L in (0, 1], the intensity at most 8.
                diffuse = diffuse.saturating_add(mul_in_range(nl, light.intensity));
            } else {
                shadow |= 1u8.checked_shl(k as u32).unwrap_or(0);
            }
        }
        // KA and KD at most 8, the ambient level at most 1, the diffuse sum at most 8 a
        // light (8 · MAX_LIGHTS = 64): the factor is at most 520, a colour channel at most 1.
        let factor = mul_in_range(material.ka, scene.ambient)
            .saturating_add(mul_in_range(material.kd, diffuse));
        let local = Colour(material.colour.0.map(|c| mul_in_range(c, factor)));
        add_weighted(sum, &local, pending.weight);

        // A diffuse surface (KR = KT = 0) spawns nothing, as the pushes below would decide:
        // skipped before building the reflected direction (most hits are on the floor).
        let diffuse_only = material.kr == I16F16::ZERO && material.kt == I16F16::ZERO;
        if pending.depth >= self.options.max_depth || diffuse_only {
            return (shadow, index);
        }
        let reflected = reflect(ray.dir, normal);
        let mut push = |k: I16F16, dir: Vec3, stats: &mut TraceStats| {
            let weight = mul(pending.weight, k);
            if k == I16F16::ZERO || weight < self.options.threshold {
                return;
            }
            let child = Pending {
                ray: Ray { origin: point, dir },
                weight,
                depth: pending.depth + 1,
                from: hit.object,
            };
            if stack.push(child).is_ok() {
                stats.secondary_rays += 1;
            } else {
                stats.dropped_rays += 1;
            }
        };
        push(material.kr, reflected, stats);
        if material.kt != I16F16::ZERO {
            let (n1, n2) = if entering {
                (I16F16::ONE, material.ior)
            } else {
                (material.ior, I16F16::ONE)
            };
            let refracted = refract(ray.dir, normal, n1, n2).unwrap_or(reflected);
            push(material.kt, refracted, stats);
        }
        (shadow, index)
    }
}

/// The refracted direction of unit `d` through a surface with unit normal `n` facing it, from
/// IOR `n1` into `n2` (Snell's law; each IOR in [1, MAX_IOR], as a material's), or `None` on
/// total internal reflection.
pub(crate) fn refract(d: Vec3, n: Vec3, n1: I16F16, n2: I16F16) -> Option<Vec3> {
    let eta = ior_ratio(n1, n2)?;
    // Two unit vectors: |cos θi| ≤ 1; η at most MAX_IOR (4), so |along_n| ≤ 5.
    let cos_i = I16F16::from_bits(narrow_bits_in_range(-d.dot_bits(n)));
    // k = 1 − η²(1 − cos²θi): the squared cosine of the refracted angle.
    let sin2_i = I32F32::ONE - I32F32::from_bits(wide(cos_i.to_bits(), cos_i.to_bits()));
    let eta2 = I32F32::from_bits(wide(eta.to_bits(), eta.to_bits()));
    let k = I32F32::ONE - I32F32::from_bits(mul_shr32(eta2.to_bits(), sin2_i.to_bits()));
    if k < I32F32::ZERO {
        return None;
    }
    let cos_t = sqrt(k);
    let along_n = mul_in_range(eta, cos_i) - cos_t;
    d.scale_in_range(eta)
        .add(n.scale_in_range(along_n))
        .normalized()
}

/// `n1 / n2` exactly as `n1.checked_div(n2)` (truncated; `None` if `n2` is 0 or the quotient
/// overflows), for two positive values (IORs) from 32-bit divisions ([`div_rem_u64_u32`])
/// instead of the 64-bit division's library call; other signs take `checked_div`.
#[inline]
fn ior_ratio(n1: I16F16, n2: I16F16) -> Option<I16F16> {
    let (a, b) = (n1.to_bits(), n2.to_bits());
    if a <= 0 || b <= 0 {
        return n1.checked_div(n2);
    }
    // a · 2^16 / b, both positive: floor = truncation.
    let (q, _) = div_rem_u64_u32((a as u64) << 16, b as u32);
    i32::try_from(q).ok().map(I16F16::from_bits)
}

/// `sum += c · weight`, per channel.
#[inline]
fn add_weighted(sum: &mut Colour, c: &Colour, weight: I16F16) {
    for (s, c) in sum.0.iter_mut().zip(c.0) {
        *s = s.saturating_add(mul(c, weight));
    }
}

/// Clamps each channel to [0, 1] and rounds `255·c` to nearest.
#[inline]
fn to_rgb888(c: &Colour) -> Rgb888 {
    // On Armv7-M clamped to 2^16 − 1 raw rather than 2^16 (1.0): both round to 255, and the
    // narrower clamp is one `usat` there (elsewhere it compiles to no fewer instructions).
    const MAX: i32 = if cfg!(target_arch = "arm") && !crate::math::NO_WIDE_MULTIPLY {
        0xFFFF
    } else {
        1 << 16
    };
    let [r, g, b] =
        c.0.map(|v| ((v.to_bits().clamp(0, MAX) as u32 * 255 + (1 << 15)) >> 16) as u8);
    Rgb888::new(r, g, b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn channels_round_as_the_clamp_to_one_does() {
        let one = |v: i32| ((v.clamp(0, 1 << 16) as u32 * 255 + (1 << 15)) >> 16) as u8;
        // The Armv7-M form's clamp, checked here on the host.
        let below_one = |v: i32| ((v.clamp(0, 0xFFFF) as u32 * 255 + (1 << 15)) >> 16) as u8;
        let values = (-70_000..70_000).chain([i32::MIN, i32::MAX, 1 << 20, -(1 << 20)]);
        for v in values {
            let c = I16F16::from_bits(v);
            let got = to_rgb888(&Colour([c, c, c]));
            assert_eq!(got, Rgb888::new(one(v), one(v), one(v)), "{v}");
            assert_eq!(below_one(v), one(v), "{v}");
        }
    }

    fn v(x: f32, y: f32, z: f32) -> Vec3 {
        Vec3 {
            x: I16F16::from_num(x),
            y: I16F16::from_num(y),
            z: I16F16::from_num(z),
        }
    }

    use crate::trace::scene::{Light, Material, TraceCamera};
    use crate::trace::shape::{
        AaBox, Ellipsoid, Frustum, Object, Plane, Polygon, Shape, Sphere, Triangle,
    };

    fn f(x: f64) -> I16F16 {
        I16F16::from_num(x)
    }

    fn material(kr: f64, kt: f64) -> Material {
        let grey = Colour::new([f(0.5); 3]).unwrap();
        Material::new(grey, [f(0.2), f(0.8), f(kr), f(kt)], f(1.5)).unwrap()
    }

    /// Two facing mirrors (planes z = ±1, facing each other) seen by a camera between them
    /// looking down −z: every ray reflects forever unless a rule stops it.
    fn mirrors(kr: f64, options: TraceOptions) -> TraceStats {
        let objects = [
            Object {
                shape: Shape::Plane(Plane::new(v(0.0, 0.0, 1.0), f(1.0)).unwrap()),
                material: 0,
            },
            Object {
                shape: Shape::Plane(Plane::new(v(0.0, 0.0, -1.0), f(1.0)).unwrap()),
                material: 0,
            },
        ];
        let materials = [material(kr, 0.0)];
        let scene = Scene::new(&objects, &materials, &[], Colour::BLACK, f(0.5)).unwrap();
        let camera = TraceCamera::new(
            [0.0; 3],
            [0.0, 0.0, -1.0],
            [0.0, 1.0, 0.0],
            10.0,
            0.1,
            10.0,
            1,
            1,
        )
        .unwrap();
        Tracer::<8>::new(&scene, &camera, options)
            .trace_pixel(0, 0)
            .1
    }

    #[test]
    fn background_pixel_is_the_traced_miss() {
        let materials = [material(0.0, 0.0)];
        let sky = Colour::new([f(0.25), f(0.35), f(0.55)]).unwrap();
        let scene = Scene::new(&[], &materials, &[], sky, f(0.5)).unwrap();
        let mut camera = TraceCamera::new(
            [0.0; 3],
            [0.0, 0.0, -1.0],
            [0.0, 1.0, 0.0],
            50.0,
            0.1,
            10.0,
            8,
            6,
        )
        .unwrap();
        for degenerate in [false, true] {
            if degenerate {
                // Directions too short to normalise in the first rows: black, not the sky.
                use fixed::types::I8F24;
                camera.corner = [I8F24::ZERO; 3];
                camera.right = [I8F24::ZERO; 3];
                camera.down = [I8F24::from_bits(1 << 14), I8F24::ZERO, I8F24::ZERO];
            }
            let tracer = Tracer::<4>::new(&scene, &camera, TraceOptions::default());
            let mut colours = std::vec::Vec::new();
            for (x, y) in (0..8).flat_map(|x| (0..6).map(move |y| (x, y))) {
                let p = tracer.background_pixel(x, y);
                let one_ray = TraceStats {
                    primary_rays: 1,
                    ..TraceStats::default()
                };
                assert_eq!((p, one_ray), tracer.trace_pixel(x, y), "({x}, {y})");
                colours.push(p.colour);
            }
            // Both cases are met: the sky everywhere, or black rows then the sky.
            let black = colours
                .iter()
                .filter(|c| **c == Rgb888::new(0, 0, 0))
                .count();
            assert_eq!(black > 0, degenerate);
            assert!(black < colours.len());
        }
    }

    #[test]
    fn ior_ratio_is_checked_div() {
        let mut rng = crate::test_rng::XorShift64::new(0x853c_49e6_748f_ea9bu64);
        let mut next = || rng.next_u64();
        let mut pairs: std::vec::Vec<(i32, i32)> = (0..200_000)
            .map(|_| {
                let (a, b) = (next(), next());
                ((a >> (33 + a % 31)) as i32, (b >> (33 + b % 31)) as i32)
            })
            .collect();
        let edges = [
            0,
            1,
            2,
            1 << 16,
            3 << 15,
            4 << 16,
            i32::MAX,
            i32::MIN,
            -1,
            -(1 << 16),
        ];
        pairs.extend(
            edges
                .iter()
                .flat_map(|a| edges.iter().map(move |b| (*a, *b))),
        );
        for (a, b) in pairs {
            let (a, b) = (I16F16::from_bits(a), I16F16::from_bits(b));
            assert_eq!(ior_ratio(a, b), a.checked_div(b), "{a} / {b}");
        }
    }

    #[test]
    fn the_depth_limit_ends_the_ray_tree() {
        for max_depth in [0, 1, 3, 7] {
            let s = mirrors(
                1.0,
                TraceOptions {
                    max_depth,
                    threshold: I16F16::ZERO,
                },
            );
            assert_eq!(
                s.secondary_rays,
                u32::from(max_depth),
                "depth limit {max_depth}"
            );
            assert_eq!(s.dropped_rays, 0);
        }
    }

    #[test]
    fn a_weight_below_the_threshold_ends_the_ray_tree() {
        // Weights 0.5, 0.25, 0.125, …: with threshold 0.2 two reflections are traced.
        let s = mirrors(
            0.5,
            TraceOptions {
                max_depth: 7,
                threshold: f(0.2),
            },
        );
        assert_eq!(s.secondary_rays, 2);
        // A diffuse surface spawns nothing.
        assert_eq!(mirrors(0.0, TraceOptions::default()).secondary_rays, 0);
    }

    #[test]
    fn a_full_ray_stack_is_reported() {
        // A glass slab (KR and KT) between the camera and the floor branches at every hit.
        let objects = [
            Object {
                shape: Shape::Box(AaBox::new(v(-5.0, -0.5, -5.0), v(5.0, 0.5, 5.0)).unwrap()),
                material: 0,
            },
            Object {
                shape: Shape::Plane(Plane::new(v(0.0, 1.0, 0.0), f(3.0)).unwrap()),
                material: 0,
            },
        ];
        let materials = [material(0.3, 0.7)];
        let scene = Scene::new(&objects, &materials, &[], Colour::BLACK, f(0.5)).unwrap();
        let camera = TraceCamera::new(
            [0.0, 3.0, 0.0],
            [0.0; 3],
            [0.0, 0.0, -1.0],
            10.0,
            0.1,
            10.0,
            2,
            2,
        )
        .unwrap();
        let options = TraceOptions {
            max_depth: 4,
            threshold: I16F16::ZERO,
        };
        let roomy = Tracer::<5>::new(&scene, &camera, options);
        let (_, s) = roomy.trace_pixel(0, 0);
        assert_eq!((s.dropped_rays, s.peak_stack), (0, 4));
        let tight = Tracer::<2>::new(&scene, &camera, options);
        assert!(tight.trace_pixel(0, 0).1.dropped_rays > 0);
        let mut rows = [true; 2];
        let mut sink = crate::sink::FnSink(|row: crate::sink::Row<'_, Rgb888>| -> Result<(), ()> {
            rows[usize::from(row.y)] = row.complete;
            Ok(())
        });
        let stats = tight
            .render(&mut [Rgb888::new(0, 0, 0); 2], &mut sink)
            .unwrap();
        let wrong_row = tight.render(&mut [Rgb888::new(0, 0, 0); 3], &mut sink);
        assert_eq!(wrong_row, Err(TraceError::RowLength));
        assert!(stats.dropped_rays > 0);
        assert_eq!(rows, [false, false], "rows that lost rays say so");
    }

    #[test]
    fn every_primitive_casts_a_shadow() {
        // The floor y = 0 seen from above at the origin; the light comes from (1, 1, 0), so
        // an object around (1.5, 1.5, 0) shadows the origin without being seen from the camera.
        let c = v(1.5, 1.5, 0.0);
        let square = [
            v(1.2, 1.8, -0.3),
            v(1.8, 1.2, -0.3),
            v(1.8, 1.2, 0.3),
            v(1.2, 1.8, 0.3),
        ];
        let blockers = [
            Shape::Sphere(Sphere::new(c, f(0.3)).unwrap()),
            Shape::Box(AaBox::new(v(1.3, 1.3, -0.2), v(1.7, 1.7, 0.2)).unwrap()),
            Shape::Frustum(Frustum::cylinder(v(1.5, 1.5, -0.5), v(1.5, 1.5, 0.5), f(0.3)).unwrap()),
            Shape::Frustum(
                Frustum::new(v(1.5, 1.2, 0.0), f(0.4), v(1.5, 1.9, 0.0), f(0.0)).unwrap(),
            ),
            Shape::Ellipsoid(Ellipsoid::new(c, v(0.3, 0.4, 0.2)).unwrap()),
            Shape::Polygon(Polygon::new(&square).unwrap()),
            Shape::Triangle(Triangle::new([square[0], square[1], square[2]]).unwrap()),
        ];
        let floor = Object {
            shape: Shape::Plane(Plane::new(v(0.0, 1.0, 0.0), f(0.0)).unwrap()),
            material: 0,
        };
        let materials = [material(0.0, 0.0)];
        let lights = [Light::directional(v(1.0, 1.0, 0.0), f(1.0)).unwrap()];
        let camera = TraceCamera::new(
            [0.0, 0.5, 0.0001],
            [0.0; 3],
            [0.0, 0.0, -1.0],
            1.0,
            0.1,
            10.0,
            1,
            1,
        )
        .unwrap();
        let lit = |objects: &[Object<'_>]| {
            let scene = Scene::new(objects, &materials, &lights, Colour::BLACK, f(0.2)).unwrap();
            let (p, _) =
                Tracer::<5>::new(&scene, &camera, TraceOptions::default()).trace_pixel(0, 0);
            assert_eq!(p.id, Some(0), "the floor is seen");
            p.shadow
        };
        assert_eq!(lit(&[floor]), 0);
        for b in blockers {
            assert_eq!(
                lit(&[
                    floor,
                    Object {
                        shape: b,
                        material: 0
                    }
                ]),
                1,
                "{b:?}"
            );
        }
    }

    #[test]
    fn a_checker_cell_gives_every_coefficient() {
        // The floor y = 0 with cells of 1 unit: diffuse (even) and mirror (odd) materials.
        use crate::trace::scene::Checker;
        let objects = [Object {
            shape: Shape::Plane(Plane::new(v(0.0, 1.0, 0.0), f(0.0)).unwrap()),
            material: 2,
        }];
        let materials = [material(0.0, 0.0), material(0.5, 0.0)];
        let checkers = [Checker::new(0, 1, 0).unwrap()];
        let scene =
            Scene::textured(&objects, &materials, &checkers, &[], Colour::BLACK, f(0.5)).unwrap();
        let down = |x: f64| {
            let camera = TraceCamera::new(
                [x, 1.0, -0.5],
                [x, 0.0, -0.5],
                [0.0, 0.0, -1.0],
                1.0,
                0.1,
                10.0,
                1,
                1,
            )
            .unwrap();
            let (p, s) =
                Tracer::<5>::new(&scene, &camera, TraceOptions::default()).trace_pixel(0, 0);
            (p.material, s.secondary_rays)
        };
        // (0.5, −0.5) is cell (0, −1), odd: the mirror; (−0.5, −0.5) is (−1, −1), even.
        assert_eq!(down(0.5), (Some(1), 1));
        assert_eq!(down(-0.5), (Some(0), 0));
        assert_eq!(down(1.5), (Some(0), 0));
    }

    #[test]
    fn snell_and_total_internal_reflection() {
        let n = v(0.0, 1.0, 0.0);
        let d = v(0.6, -0.8, 0.0); // sin θi = 0.6
        let glass = I16F16::from_num(1.5);
        let t = refract(d, n, I16F16::ONE, glass).unwrap();
        assert!((t.x.to_num::<f64>() - 0.4).abs() < 1e-3, "{t:?}"); // sin θt = 0.6 / 1.5
                                                                    // Leaving diamond at sin θi = 0.6 > 1/2.42: total internal reflection.
        assert_eq!(refract(d, n, I16F16::from_num(2.42), I16F16::ONE), None);
        // Straight through at normal incidence.
        assert_eq!(
            refract(v(0.0, -1.0, 0.0), n, I16F16::ONE, glass),
            Some(v(0.0, -1.0, 0.0))
        );
    }

    /// The limit kept by `Nearest::keep` is the one recomputed from the best hit (the form it
    /// replaced), over random offers below the limit (as every test returns) and at the ends
    /// of the range.
    #[test]
    fn kept_limit_is_the_recomputed_one() {
        let mut rng = crate::test_rng::XorShift64::new(0x2545_f491_4f6c_dd1du64);
        let mut next = || rng.next_u64();
        let recomputed = |n: &Nearest| {
            n.best
                .map_or(n.t_max, |b| b.t.saturating_add(I16F16::DELTA).min(n.t_max))
        };
        for round in 0..20_000 {
            let t_max = match round % 4 {
                0 => I16F16::MAX,
                _ => I16F16::from_bits((next() >> 33) as i32 + 2),
            };
            let t_min = I16F16::from_bits((next() % 4) as i32);
            let mut n = Nearest::new(u32::MAX, t_min, t_max);
            assert_eq!(n.limit(), recomputed(&n));
            for _ in 0..(next() % 6) {
                let span = (n.limit().to_bits() - t_min.to_bits()).max(1) as u64;
                let t = match next() % 8 {
                    // Just below the limit: a tie with the best hit, or the top of the range.
                    0 => n.limit().to_bits() - 1,
                    _ => t_min.to_bits() + (next() % span) as i32,
                };
                let t = I16F16::from_bits(t.max(t_min.to_bits()));
                n.keep(t, (next() % 5) as u32);
                assert_eq!(n.limit(), recomputed(&n), "round {round}");
            }
        }
    }

    /// In a scene of a few objects a ray tests every object instead of walking the hierarchy:
    /// the same nearest hit as the walk, from every object's surface.
    #[test]
    fn few_objects_find_the_walks_hit() {
        use crate::trace::bvh::{self, BvhNode};
        let floor = [
            v(-4.0, 0.0, -4.0),
            v(-4.0, 0.0, 4.0),
            v(4.0, 0.0, 4.0),
            v(4.0, 0.0, -4.0),
        ];
        let objects = [
            Object {
                shape: Shape::Sphere(Sphere::new(v(-1.1, 1.0, -0.5), f(1.0)).unwrap()),
                material: 0,
            },
            Object {
                shape: Shape::Sphere(Sphere::new(v(1.2, 0.9, 1.0), f(0.9)).unwrap()),
                material: 0,
            },
            Object {
                shape: Shape::Polygon(Polygon::new(&floor).unwrap()),
                material: 0,
            },
        ];
        assert!(objects.len() <= FEW_OBJECTS);
        let node = BvhNode {
            min: Vec3::ZERO,
            max: Vec3::ZERO,
            index: 0,
            count: 0,
            axis: 0,
        };
        let (mut nodes, mut items) = ([node; 8], [0u32; 3]);
        let (n, m, bounded) = bvh::build(&objects, &mut nodes, &mut items).unwrap();
        let materials = [material(0.5, 0.5)];
        let scene = Scene::new(&objects, &materials, &[], Colour::BLACK, f(0.5))
            .unwrap()
            .with_bvh(&nodes[..n], &items[..m], bounded)
            .unwrap();
        let camera = TraceCamera::new(
            [0.0, 3.0, 7.0],
            [0.0; 3],
            [0.0, 1.0, 0.0],
            50.0,
            0.1,
            100.0,
            1,
            1,
        )
        .unwrap();
        let tracer = Tracer::<5>::new(&scene, &camera, TraceOptions::default());
        let bvh = scene.bvh.as_ref().unwrap();
        let mut rng = crate::test_rng::XorShift64::new(0x2545_f491_4f6c_dd1du64);
        let mut next = || {
            let x = rng.next_u64();
            (x >> 40) as f32 / (1u32 << 24) as f32 * 2.0 - 1.0
        };
        let mut hits = 0;
        for k in 0..20_000 {
            let from = k % 3;
            // A point on object `from`'s surface (the floor's, or a sphere's along a direction).
            let origin = match from {
                2 => v(4.0 * next(), 0.0, 4.0 * next()),
                _ => {
                    let Shape::Sphere(s) = objects[from as usize].shape else {
                        unreachable!()
                    };
                    let d = v(next(), next(), next()).normalized().unwrap();
                    s.centre.along(d, s.radius)
                }
            };
            let Some(dir) = v(next(), next(), next()).normalized() else {
                continue;
            };
            let ray = Ray { origin, dir };
            let mut stats = TraceStats::default();
            let few = tracer.nearest(&ray, from, EPSILON, I16F16::MAX, &mut stats);
            assert_eq!((stats.box_tests, stats.intersection_tests), (0, 3));
            let mut walk = Nearest::new(from, EPSILON, I16F16::MAX);
            bvh.walk(&ray, EPSILON, I16F16::MAX, |id, _| {
                Some(walk.offer(&scene, id, &ray))
            });
            let walked = walk.finish(&mut stats);
            assert_eq!(
                few.map(|h| (h.t, h.object)),
                walked.map(|h| (h.t, h.object)),
                "{ray:?} from {from}"
            );
            hits += usize::from(few.is_some());
        }
        assert!(hits > 5_000, "{hits}");
    }

    #[test]
    fn rounding_of_the_final_colour() {
        let c = Colour([
            I16F16::from_num(-0.5),
            I16F16::from_num(0.5),
            I16F16::from_num(3),
        ]);
        assert_eq!(to_rgb888(&c), Rgb888::new(0, 128, 255));
    }
}
