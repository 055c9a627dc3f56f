//! Band and full-frame z-buffer: depth-tested bands of `B` rows (`B = H`: the whole frame).

use crate::arithmetic::Arithmetic;
use crate::clip::Clipping;
use crate::depth::Depth;
use crate::depth::DepthFormat;
use crate::options::{RenderOptions, MAX_INSTANCES};
use crate::render::Unbounded;
use crate::render::{
    drive, fill_span, internal, viewport, ActiveTri, FinishedRow, Frame, IdOrder, Resolve, NO_ENTRY,
};
use crate::resolve::common::{check_sizes, render_whole_target};
use crate::scene::Scene;
use crate::shading::Shading;
use crate::sink::{RowPixel, RowSink};
use crate::stats::{FrameStats, RenderError};
use heapless::Vec;

/// A z-buffer over bands of `B` rows: per band, each triangle is walked through the band and
/// depth-tested per pixel, then the band's rows go to the sink. `B = 1` is the span z-buffer
/// ([`Workspace`](crate::Workspace)); `B = H` is the full-frame z-buffer
/// ([`ZBufferWorkspace`]). Between the two, `B` trades depth memory (`B·W·4` bytes) for
/// fewer, longer passes over the active triangles. `ACTIVE` holds the triangles that cross a
/// band boundary (none for `B = H`).
///
/// ```
/// use embedded_graphics::pixelcolor::Rgb565;
/// use scanline3d_demo as demo;
/// use scanline3d::{resolve::BandWorkspace, sink::HashSink, Flat, RenderOptions};
/// let mut ws: Box<BandWorkspace<Rgb565, Flat, 240, 240, 16, 1280, 96>> =
///     Box::new(BandWorkspace::new(Rgb565::new(0, 0, 0)));
/// let instances = demo::instances();
/// let scene = demo::scene(&instances, 0, demo::ORBIT_FRAMES)?;
/// let stats = ws.render(&scene, &RenderOptions::default(), &mut HashSink::new()).unwrap();
/// assert_eq!(stats.rows, 240);
/// # Ok::<(), scanline3d::scene::SceneError>(())
/// ```
pub struct BandWorkspace<
    P: RowPixel,
    S: Shading,
    const W: usize,
    const H: usize,
    const B: usize,
    const TRIS: usize = 1024,
    const ACTIVE: usize = 64,
    const INSTANCES: usize = MAX_INSTANCES,
    Z: DepthFormat = Depth,
> {
    depth: [[Z; W]; B],
    pixels: [[P; W]; B],
    spans: [u16; B],
    background: P,
    heads: [u16; H],
    next: [u16; TRIS],
    refs: [u16; TRIS],
    active: Vec<ActiveTri<S::Payload<P>>, ACTIVE>,
}

/// The full-frame z-buffer: a [`BandWorkspace`] whose band is the whole target, so every
/// triangle is drawn completely when its first row comes and none is kept active.
pub type ZBufferWorkspace<
    P,
    S,
    const W: usize,
    const H: usize,
    const TRIS: usize = 1024,
    const INSTANCES: usize = MAX_INSTANCES,
    Z = Depth,
> = BandWorkspace<P, S, W, H, H, TRIS, 0, INSTANCES, Z>;

/// The band resolver: `B` rows of depth and pixels, rows `y0 ..`.
struct Band<'a, P, Z> {
    depth: &'a mut [Z],
    pixels: &'a mut [P],
    spans: &'a mut [u16],
    background: P,
    width: usize,
    y0: i32,
}

impl<P: RowPixel, Z> Band<'_, P, Z> {
    /// Offset of row `y`'s first column in the band buffers.
    fn row_start(&self, y: i32) -> usize {
        (y - self.y0).max(0) as usize * self.width
    }
}

impl<P: RowPixel, S: Shading, Z: DepthFormat> Resolve<P, S> for Band<'_, P, Z> {
    type Key = ();
    const BANDED: bool = true;
    fn band_rows(&self) -> usize {
        self.spans.len()
    }
    fn begin_band(&mut self, y0: i32, _: usize) {
        self.y0 = y0;
        self.depth.fill(Z::FAR);
        self.pixels.fill(self.background);
        self.spans.fill(0);
    }
    #[inline]
    fn span(&mut self, t: &ActiveTri<S::Payload<P>>, _: usize, y: i32, l: i32, r: i32) -> u32 {
        // The row walker hands over rows of the current band only.
        let at = self.row_start(y);
        if let Some(n) = self.spans.get_mut((y - self.y0) as usize) {
            *n += 1;
        } else {
            debug_assert!(false, "internal error: row {y} outside the band");
        }
        let (Some(depth), Some(pixels)) = (
            self.depth.get_mut(at..at + self.width),
            self.pixels.get_mut(at..at + self.width),
        ) else {
            debug_assert!(false, "internal error: row {y} outside the band");
            return 0;
        };
        fill_span::<P, S, Z, ()>(t, y, l, r, depth, pixels)
    }
    fn finish_row(&mut self, y: i32) -> FinishedRow<'_, P> {
        let at = self.row_start(y);
        let rows = at..at + self.width;
        FinishedRow {
            pixels: internal(self.pixels.get(rows.clone()), &[]),
            depth: Z::row(internal(self.depth.get(rows), &[])),
            spans: internal(self.spans.get((y - self.y0) as usize).copied(), 0),
            written: 0,
        }
    }
}

impl<
        P: RowPixel,
        S: Shading,
        const W: usize,
        const H: usize,
        const B: usize,
        const TRIS: usize,
        const ACTIVE: usize,
        const INSTANCES: usize,
        Z: DepthFormat,
    > BandWorkspace<P, S, W, H, B, TRIS, ACTIVE, INSTANCES, Z>
{
    /// Size of this workspace in bytes.
    pub const BYTES: usize = core::mem::size_of::<Self>();

    const VALID: () = {
        check_sizes(W, H, TRIS);
        assert!(B >= 1 && B <= H, "the band must be 1..=H rows");
    };

    /// An empty workspace whose background pixels are `background`.
    pub const fn new(background: P) -> Self {
        #[allow(clippy::let_unit_value)]
        let () = Self::VALID;
        BandWorkspace {
            depth: [[Z::FAR; W]; B],
            pixels: [[background; W]; B],
            spans: [0; B],
            background,
            heads: [NO_ENTRY; H],
            next: [NO_ENTRY; TRIS],
            refs: [0; TRIS],
            active: Vec::new(),
        }
    }

    render_whole_target!();

    /// Renders a `width × height` target (at most `W × H`); see
    /// [`Workspace::render_sized`](crate::Workspace::render_sized).
    pub fn render_sized<const SUB_BITS: u32, C: Clipping, A: Arithmetic, K: RowSink<P>>(
        &mut self,
        width: usize,
        height: usize,
        scene: &Scene<'_>,
        options: &RenderOptions<SUB_BITS, C, A>,
        sink: &mut K,
    ) -> Result<FrameStats, RenderError<K::Error>> {
        let vp = viewport::<SUB_BITS, K::Error>(width, height, W, H, scene)?;
        let Some(heads) = self.heads.get_mut(..height) else {
            return Err(RenderError::InvalidTarget);
        };
        let rows = B.min(height);
        let (Some(depth), Some(pixels), Some(spans)) = (
            self.depth.as_flattened_mut().get_mut(..rows * width),
            self.pixels.as_flattened_mut().get_mut(..rows * width),
            self.spans.get_mut(..rows),
        ) else {
            return Err(RenderError::InvalidTarget);
        };
        let frame = Frame {
            heads,
            next: &mut self.next,
            refs: &mut self.refs,
            keys: &mut [],
            active: self.active.as_mut_view(),
            vertices: &mut [],
        };
        let mut band = Band {
            depth,
            pixels,
            spans,
            background: self.background,
            width,
            y0: 0,
        };
        drive::<P, S, SUB_BITS, C, A, K, INSTANCES, _, _, Unbounded>(
            frame,
            &mut band,
            &mut IdOrder,
            scene,
            options,
            &vp,
            sink,
        )
    }
}
