//! The span z-buffer's memory, sized at compile time ([`Workspace`]), and the resolver that
//! depth-tests each row's spans against one row of depth.
//!
//! # Memory (sizes in bytes)
//!
//! `4·W` depth row + `size_of::<P>()·W` pixel row + `b·H` bucket heads + `(b + 2)·TRIS` bucket
//! lists (`b` = 2, or 1 with `u8` heads: [`BucketHead`]) + `ACTIVE · size_of` of an active
//! triangle (96 for flat shading with pixels of up to 2 bytes; with larger ones 100 on Arm, 104
//! elsewhere, where the depth walk keeps 64-bit words) + `VERTS ·` [`CachedVertex::BYTES`].
//! See [`Workspace::BYTES`] and [`workspace_bytes_with`].
//!
//! The lean minimal build (240×240, `TRIS` = 29, `ACTIVE` = 11, `u8` heads, flat `Rgb565`):
//! 960 + 480 + 240 + 87 + 11 · 96 bytes, with the background pixel and the active list's
//! length 2,832 on Arm (padded to 4 bytes), 2,840 on RISC-V (padded to 8).

use crate::arithmetic::Arithmetic;
use crate::cache::CachedVertex;
use crate::clip::Clipping;
use crate::depth::Depth;
use crate::depth::DepthFormat;
use crate::options::{RenderOptions, MAX_INSTANCES};
pub use crate::render::BucketHead;
use crate::render::{
    drive, fill_span, viewport, ActiveTri, FinishedRow, Frame, IdOrder, Resolve, ScreenBound, Size,
    Unbounded,
};
use crate::scene::{Scene, MAX_SCENE_TRIANGLES};
use crate::shading::Shading;
use crate::sink::{RowPixel, RowSink};
use crate::stats::{FrameStats, RenderError};
use heapless::{Vec, VecView};

/// The span z-buffer: one row of depth, spans depth-tested as they come.
pub(crate) struct SpanZBuffer<'a, P, Z> {
    depth: &'a mut [Z],
    pixels: &'a mut [P],
    background: P,
    spans: u16,
    /// Columns `[lo, hi)` written since the row was last cleared: only they need clearing
    /// again (the whole row at the start of a frame).
    dirty: (usize, usize),
}

/// `row.fill(value)`, four elements to each loop test. `fill` of a value known only at run
/// time (the background pixel) compiles to one store and one end test per pixel, about three
/// instructions a pixel on Cortex-M; this loop takes about half that.
#[inline]
fn fill_by_fours<T: Copy>(row: &mut [T], value: T) {
    let mut fours = row.chunks_exact_mut(4);
    for four in &mut fours {
        if let [a, b, c, d] = four {
            (*a, *b, *c, *d) = (value, value, value, value);
        }
    }
    for x in fours.into_remainder() {
        *x = value;
    }
}

impl<'a, P: RowPixel, Z: DepthFormat> SpanZBuffer<'a, P, Z> {
    pub(crate) fn new(depth: &'a mut [Z], pixels: &'a mut [P], background: P) -> Self {
        let width = pixels.len();
        SpanZBuffer {
            depth,
            pixels,
            background,
            spans: 0,
            dirty: (0, width),
        }
    }
}

impl<P: RowPixel, S: Shading, Z: DepthFormat> Resolve<P, S> for SpanZBuffer<'_, P, Z> {
    type Key = ();
    fn begin_band(&mut self, _: i32, _: usize) {
        let (lo, hi) = self.dirty;
        if let (Some(d), Some(p)) = (self.depth.get_mut(lo..hi), self.pixels.get_mut(lo..hi)) {
            // The far depth hidden from the optimizer, which would otherwise make the fill a
            // call of `memclr` (the far depth is zero): this loop's paired stores take about
            // half its instructions on Cortex-M4, and fewer on Cortex-M0 and RISC-V too.
            fill_by_fours(d, core::hint::black_box(Z::FAR));
            fill_by_fours(p, self.background);
        } else {
            // Only a clean row (lo > hi: nothing written) has no range to clear.
            debug_assert!(
                lo > hi,
                "internal error: dirty columns {lo}..{hi} out of the row"
            );
        }
        self.dirty = (self.pixels.len(), 0);
        self.spans = 0;
    }
    #[inline(always)]
    fn span(&mut self, t: &ActiveTri<S::Payload<P>>, _: usize, y: i32, l: i32, r: i32) -> u32 {
        self.spans += 1;
        // walk_band clamps spans to [0, width) and passes only non-empty ones.
        self.dirty = (self.dirty.0.min(l as usize), self.dirty.1.max(r as usize));
        fill_span::<P, S, Z, ()>(t, y, l, r, self.depth, self.pixels)
    }
    fn finish_row(&mut self, _: i32) -> FinishedRow<'_, P> {
        FinishedRow {
            pixels: self.pixels,
            depth: Z::row(self.depth),
            spans: self.spans,
            written: 0,
        }
    }
}

/// All the memory a render needs, sized at compile time.
///
/// * `P`: the pixel type ([`RowPixel`]); `S`: the shading model ([`crate::Flat`] or
///   [`crate::Gouraud`]);
/// * `W × H`: the target size (1..=2048 each);
/// * `TRIS`: triangles that may survive culling in one frame (at most
///   [`MAX_SCENE_TRIANGLES`] = 65,535);
/// * `INSTANCES`: mesh instances a scene may have (their set-up lives on the stack during a
///   render; default [`MAX_INSTANCES`]);
/// * `ACTIVE`: triangles that may cross one row (more are dropped and reported in
///   [`FrameStats::dropped`], [`FrameStats::dropped_pieces`] and [`Row::complete`](crate::sink::Row::complete));
/// * `Z`: the depth format of the row's z-buffer ([`crate::depth`]): [`Depth`] (32-bit, the
///   default) or [`Depth16`](crate::depth::Depth16) (half the depth row, coarser ties);
/// * `VERTS`: vertex cache entries ([`crate::cache`], default 0: none). When the scene's
///   vertices fit, each is transformed and projected once per frame instead of once per
///   triangle and pass: RAM for speed, with the same pixels.
/// * `B`: the type of the row bucket heads ([`BucketHead`]): `u16` (the default) or `u8`,
///   one byte per row instead of two for workspaces with `TRIS` at most 255.
///
/// ```
/// use embedded_graphics::pixelcolor::Rgb565;
/// use scanline3d::{depth::Depth16, Flat, Workspace};
/// type Ws = Workspace<Rgb565, Flat, 240, 240, 1280, 64>;
/// assert!(Ws::BYTES < 16 * 1024);
/// // The same with a 16-bit depth row: 2 bytes less per column.
/// type Ws16 = Workspace<Rgb565, Flat, 240, 240, 1280, 64, 8, Depth16>;
/// assert_eq!(Ws::BYTES - Ws16::BYTES, 2 * 240);
/// ```
pub struct Workspace<
    P: RowPixel,
    S: Shading,
    const W: usize,
    const H: usize,
    const TRIS: usize = 1024,
    const ACTIVE: usize = 64,
    const INSTANCES: usize = MAX_INSTANCES,
    Z: DepthFormat = Depth,
    const VERTS: usize = 0,
    B: BucketHead = u16,
> {
    depth: [Z; W],
    pixels: [P; W],
    background: P,
    heads: [B; H],
    next: [B; TRIS],
    refs: [u16; TRIS],
    active: Vec<ActiveTri<S::Payload<P>>, ACTIVE>,
    vertices: [CachedVertex; VERTS],
}

/// Bytes of a [`Workspace`] for pixel type `P`, shading `S` and depth format `Z` with the given
/// size and capacities: what `Workspace::<P, S, W, H, TRIS, ACTIVE, INSTANCES, Z>::BYTES` is,
/// computed at run time (for tools such as `sim analyze` that choose the capacities). A vertex
/// cache adds [`crate::cache::vertex_cache_bytes`]; for one-byte bucket heads see
/// [`workspace_bytes_with`].
///
/// ```
/// use embedded_graphics::pixelcolor::Rgb565;
/// use scanline3d::{depth::Depth16, workspace::workspace_bytes, Depth, Flat, Workspace};
/// assert_eq!(
///     workspace_bytes::<Rgb565, Flat, Depth>(240, 240, 100, 12),
///     Workspace::<Rgb565, Flat, 240, 240, 100, 12>::BYTES
/// );
/// assert_eq!(
///     workspace_bytes::<Rgb565, Flat, Depth16>(240, 240, 100, 12),
///     Workspace::<Rgb565, Flat, 240, 240, 100, 12, 8, Depth16>::BYTES
/// );
/// ```
pub const fn workspace_bytes<P: RowPixel, S: Shading, Z: DepthFormat>(
    width: usize,
    height: usize,
    triangles: usize,
    active: usize,
) -> usize {
    workspace_bytes_with::<P, S, Z, u16>(width, height, triangles, active)
}

/// [`workspace_bytes`] for a workspace whose bucket heads and links are `B` ([`BucketHead`]).
///
/// ```
/// use embedded_graphics::pixelcolor::Rgb565;
/// use scanline3d::{workspace::workspace_bytes_with, Depth, Flat, Workspace};
/// type Lean = Workspace<Rgb565, Flat, 240, 240, 29, 11, 1, Depth, 0, u8>;
/// assert_eq!(workspace_bytes_with::<Rgb565, Flat, Depth, u8>(240, 240, 29, 11), Lean::BYTES);
/// ```
pub const fn workspace_bytes_with<P: RowPixel, S: Shading, Z: DepthFormat, B: BucketHead>(
    width: usize,
    height: usize,
    triangles: usize,
    active: usize,
) -> usize {
    use core::mem::{align_of, size_of};
    let entry = size_of::<ActiveTri<S::Payload<P>>>();
    let align = {
        let a = align_of::<ActiveTri<S::Payload<P>>>();
        if a > align_of::<usize>() {
            a
        } else {
            align_of::<usize>()
        }
    };
    // Heads (one per row) and links (one per entry) are `B`; each entry's triangle id is `u16`.
    let unpadded = width * (size_of::<Z>() + size_of::<P>())
        + size_of::<P>()
        + height * size_of::<B>()
        + triangles * (size_of::<B>() + size_of::<u16>())
        + active * entry
        + size_of::<usize>();
    unpadded.div_ceil(align) * align
}

impl<
        P: RowPixel,
        S: Shading,
        const W: usize,
        const H: usize,
        const TRIS: usize,
        const ACTIVE: usize,
        const INSTANCES: usize,
        Z: DepthFormat,
        const VERTS: usize,
        B: BucketHead,
    > Workspace<P, S, W, H, TRIS, ACTIVE, INSTANCES, Z, VERTS, B>
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
        assert!(TRIS <= MAX_SCENE_TRIANGLES, "TRIS must be at most 65535");
        assert!(
            TRIS <= B::MAX_ENTRIES,
            "TRIS must fit the bucket heads: at most 255 with u8 heads"
        );
    };

    /// An empty workspace whose background pixels are `background`.
    pub const fn new(background: P) -> Self {
        #[allow(clippy::let_unit_value)]
        let () = Self::VALID;
        Workspace {
            depth: [Z::FAR; W],
            pixels: [background; W],
            background,
            heads: [B::EMPTY; H],
            next: [B::EMPTY; TRIS],
            refs: [0; TRIS],
            active: Vec::new(),
            vertices: [CachedVertex::EMPTY; VERTS],
        }
    }

    /// Renders `scene`, handing each of the `H` rows to `sink` once, top to bottom.
    ///
    /// ```
    /// use embedded_graphics::{mock_display::MockDisplay, pixelcolor::BinaryColor};
    /// use fixed::types::I16F16;
    /// use scanline3d::{scene::*, sink::DrawTargetSink, Flat, RenderOptions, Workspace};
    ///
    /// let v = |x: f32, y: f32| [I16F16::from_num(x), I16F16::from_num(y), I16F16::ZERO];
    /// let verts = [v(-1.0, -1.0), v(1.0, -1.0), v(-1.0, 1.0)];
    /// let tris = [[0u16, 1, 2]];
    /// let mesh = Mesh::new(&verts, &tris, MeshColors::Uniform(embedded_graphics::pixelcolor::Rgb888::new(255, 255, 255)), None)?;
    /// let instances = [Instance { mesh: &mesh, transform: Transform::IDENTITY }];
    /// // At distance 1 with a 90° field of view the triangle's corners land on screen corners.
    /// let camera = Camera::look_at([0.0, 0.0, 1.0], [0.0; 3], [0.0, 1.0, 0.0])?.perspective(90.0, 0.5, 10.0)?;
    /// let scene = Scene { instances: &instances, camera, light: Light::new([0.0, 0.0, 1.0], 0.0, 1.0)? };
    ///
    /// let mut display = MockDisplay::<BinaryColor>::new();
    /// let mut ws: Workspace<BinaryColor, Flat, 8, 8, 4, 4> = Workspace::new(BinaryColor::Off);
    /// let stats = ws.render(&scene, &RenderOptions::default(), &mut DrawTargetSink::new(&mut display)).unwrap();
    /// // The diagonal is the triangle's right edge, so centres on it are not covered.
    /// display.assert_pattern(&[
    ///     "........",
    ///     "#.......",
    ///     "##......",
    ///     "###.....",
    ///     "####....",
    ///     "#####...",
    ///     "######..",
    ///     "#######.",
    /// ]);
    /// assert_eq!(stats.fragments, 28);
    /// # Ok::<(), scanline3d::scene::SceneError>(())
    /// ```
    pub fn render<const SUB_BITS: u32, C: Clipping, A: Arithmetic, K: RowSink<P>>(
        &mut self,
        scene: &Scene<'_>,
        options: &RenderOptions<SUB_BITS, C, A>,
        sink: &mut K,
    ) -> Result<FrameStats, RenderError<K::Error>> {
        self.render_sized(W, H, scene, options, sink)
    }

    /// Renders a `width × height` target (at most `W × H`) with this workspace: rows are
    /// `width` pixels long and there are `height` of them. One workspace can serve several
    /// viewport sizes; a size of zero or beyond `W × H` is [`RenderError::InvalidTarget`].
    ///
    /// ```
    /// use embedded_graphics::pixelcolor::Gray8;
    /// use scanline3d_demo as demo;
    /// use scanline3d::{sink::FnSink, Flat, RenderOptions, Workspace};
    /// let mut ws: Box<Workspace<Gray8, Flat, 320, 240, 1536, 96>> = Box::new(Workspace::new(Gray8::new(0)));
    /// let instances = demo::instances();
    /// let scene = demo::scene(&instances, 0, demo::ORBIT_FRAMES)?;
    /// let mut rows = 0;
    /// let mut sink = FnSink(|row: scanline3d::sink::Row<'_, Gray8>| -> Result<(), ()> {
    ///     assert_eq!(row.pixels.len(), 100);
    ///     rows += 1;
    ///     Ok(())
    /// });
    /// let stats = ws.render_sized(100, 80, &scene, &RenderOptions::default(), &mut sink).unwrap();
    /// assert!(ws.render_sized(321, 80, &scene, &RenderOptions::default(), &mut sink).is_err());
    /// assert_eq!((rows, stats.rows), (80, 80));
    /// # Ok::<(), scanline3d::scene::SceneError>(())
    /// ```
    pub fn render_sized<const SUB_BITS: u32, C: Clipping, A: Arithmetic, K: RowSink<P>>(
        &mut self,
        width: usize,
        height: usize,
        scene: &Scene<'_>,
        options: &RenderOptions<SUB_BITS, C, A>,
        sink: &mut K,
    ) -> Result<FrameStats, RenderError<K::Error>> {
        // The workspace's size bounds the target's: planes may use it ([`Size`]).
        self.span_view()
            .render_bounded::<SUB_BITS, C, A, K, Size<W, H>>(width, height, scene, options, sink)
    }

    /// The workspace as slices, so code that renders through it is not generic over the sizes.
    pub(crate) fn span_view(&mut self) -> SpanView<'_, P, S, Z, INSTANCES, B> {
        SpanView {
            depth: &mut self.depth,
            pixels: &mut self.pixels,
            background: self.background,
            heads: &mut self.heads,
            next: &mut self.next,
            refs: &mut self.refs,
            active: self.active.as_mut_view(),
            vertices: &mut self.vertices,
        }
    }
}

/// A span z-buffer workspace borrowed as slices: its width and height are the lengths of its
/// rows and bucket heads, so nothing here is generic over the sizes.
pub(crate) struct SpanView<'a, P: RowPixel, S: Shading, Z, const INSTANCES: usize, B = u16> {
    depth: &'a mut [Z],
    pixels: &'a mut [P],
    background: P,
    heads: &'a mut [B],
    next: &'a mut [B],
    refs: &'a mut [u16],
    active: &'a mut VecView<ActiveTri<S::Payload<P>>>,
    vertices: &'a mut [CachedVertex],
}

impl<P: RowPixel, S: Shading, Z: DepthFormat, const INSTANCES: usize, B: BucketHead>
    SpanView<'_, P, S, Z, INSTANCES, B>
{
    /// Renders a `width × height` target (at most the workspace's size).
    pub(crate) fn render_sized<const SUB_BITS: u32, C: Clipping, A: Arithmetic, K: RowSink<P>>(
        &mut self,
        width: usize,
        height: usize,
        scene: &Scene<'_>,
        options: &RenderOptions<SUB_BITS, C, A>,
        sink: &mut K,
    ) -> Result<FrameStats, RenderError<K::Error>> {
        self.render_bounded::<SUB_BITS, C, A, K, Unbounded>(width, height, scene, options, sink)
    }

    /// [`SpanView::render_sized`] for a target at most `D::MAX_SIDE` pixels wide and high.
    pub(crate) fn render_bounded<
        const SUB_BITS: u32,
        C: Clipping,
        A: Arithmetic,
        K: RowSink<P>,
        D: ScreenBound,
    >(
        &mut self,
        width: usize,
        height: usize,
        scene: &Scene<'_>,
        options: &RenderOptions<SUB_BITS, C, A>,
        sink: &mut K,
    ) -> Result<FrameStats, RenderError<K::Error>> {
        let vp = viewport::<SUB_BITS, K::Error>(
            width,
            height,
            self.pixels.len(),
            self.heads.len(),
            scene,
        )?;
        let (Some(depth), Some(pixels), Some(heads)) = (
            self.depth.get_mut(..width),
            self.pixels.get_mut(..width),
            self.heads.get_mut(..height),
        ) else {
            return Err(RenderError::InvalidTarget);
        };
        let frame = Frame {
            heads,
            next: self.next,
            refs: self.refs,
            keys: &mut [],
            active: self.active,
            vertices: self.vertices,
        };
        let mut resolve = SpanZBuffer::new(depth, pixels, self.background);
        drive::<P, S, SUB_BITS, C, A, K, INSTANCES, _, _, D>(
            frame,
            &mut resolve,
            &mut IdOrder,
            scene,
            options,
            &vp,
            sink,
        )
    }

    /// Renders the whole target.
    pub(crate) fn render<const SUB_BITS: u32, C: Clipping, A: Arithmetic, K: RowSink<P>>(
        &mut self,
        scene: &Scene<'_>,
        options: &RenderOptions<SUB_BITS, C, A>,
        sink: &mut K,
    ) -> Result<FrameStats, RenderError<K::Error>> {
        let (width, height) = (self.pixels.len(), self.heads.len());
        self.render_sized(width, height, scene, options, sink)
    }
}

#[cfg(test)]
mod tests {
    use super::fill_by_fours;

    #[test]
    fn fill_by_fours_is_fill() {
        // Every remainder of four, every offset into the row, over a row that is not the
        // value to begin with: exactly the slice's elements change, all to the value.
        for len in 0..=13 {
            for start in 0..=3 {
                let mut row = [7u16; 20];
                let mut expected = row;
                expected[start..start + len].fill(0xBEEF);
                fill_by_fours(&mut row[start..start + len], 0xBEEF);
                assert_eq!(row, expected, "len {len} start {start}");
            }
        }
    }
}
