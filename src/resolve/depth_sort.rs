//! Depth sort, the painter's algorithm: far to near by mean depth, overwriting.

use crate::arithmetic::Arithmetic;
use crate::clip::Clipping;
use crate::depth::DepthRow;
use crate::options::{RenderOptions, MAX_INSTANCES};
use crate::render::Unbounded;
use crate::render::{drive, viewport, ActiveTri, FinishedRow, Frame, IdOrder, Resolve, NO_ENTRY};
use crate::resolve::common::{check_sizes, render_whole_target};
use crate::scene::Scene;
use crate::shading::Shading;
use crate::sink::{RowPixel, RowSink};
use crate::stats::{FrameStats, RenderError};
use heapless::Vec;

/// Depth sort, the painter's algorithm: triangles are ordered far to near by the mean depth
/// of their vertices and painted in that order, each overwriting what is behind. Rows come out
/// one at a time all the same: the active list is kept in that order, so each row is painted
/// exactly as the whole frame would be. Fast and simple, and wrong where one depth per
/// triangle cannot order two surfaces (interpenetrating or cyclically overlapping triangles,
/// a long triangle beside a short one): the lecture's warning, measured in the tests.
///
/// ```
/// use embedded_graphics::pixelcolor::Rgb565;
/// use scanline3d_demo as demo;
/// use scanline3d::{resolve::DepthSortWorkspace, sink::HashSink, Flat, RenderOptions};
/// let mut ws: Box<DepthSortWorkspace<Rgb565, Flat, 240, 240, 1280, 96>> =
///     Box::new(DepthSortWorkspace::new(Rgb565::new(0, 0, 0)));
/// let instances = demo::instances();
/// let scene = demo::scene(&instances, 0, demo::ORBIT_FRAMES)?;
/// let stats = ws.render(&scene, &RenderOptions::default(), &mut HashSink::new()).unwrap();
/// // Every covered pixel is painted, hidden ones too.
/// assert_eq!(stats.pixels_written, stats.fragments);
/// # Ok::<(), scanline3d::scene::SceneError>(())
/// ```
pub struct DepthSortWorkspace<
    P: RowPixel,
    S: Shading,
    const W: usize,
    const H: usize,
    const TRIS: usize = 1024,
    const ACTIVE: usize = 64,
    const INSTANCES: usize = MAX_INSTANCES,
> {
    pixels: [P; W],
    background: P,
    heads: [u16; H],
    next: [u16; TRIS],
    refs: [u16; TRIS],
    keys: [u32; TRIS],
    active: Vec<ActiveTri<S::Payload<P>, u32>, ACTIVE>,
}

/// The painter's resolver: one row of pixels, spans painted in active-list (depth) order.
pub(crate) struct Painter<'a, P> {
    pub(crate) pixels: &'a mut [P],
    pub(crate) background: P,
    pub(crate) spans: u16,
}

impl<P: RowPixel, S: Shading> Resolve<P, S> for Painter<'_, P> {
    type Key = u32;
    fn begin_band(&mut self, _: i32, _: usize) {
        self.pixels.fill(self.background);
        self.spans = 0;
    }
    #[inline]
    fn span(&mut self, t: &ActiveTri<S::Payload<P>, u32>, _: usize, y: i32, l: i32, r: i32) -> u32 {
        self.spans += 1;
        match self.pixels.get_mut(l as usize..r as usize) {
            Some(out) => {
                S::paint(&t.payload, l, y, out);
                (r - l) as u32
            }
            None => {
                // walk_band clamps spans to the row.
                debug_assert!(false, "internal error: span {l}..{r} out of the row");
                0
            }
        }
    }
    fn finish_row(&mut self, _: i32) -> FinishedRow<'_, P> {
        FinishedRow {
            pixels: self.pixels,
            depth: DepthRow::NONE,
            spans: self.spans,
            written: 0,
        }
    }
}

impl<
        P: RowPixel,
        S: Shading,
        const W: usize,
        const H: usize,
        const TRIS: usize,
        const ACTIVE: usize,
        const INSTANCES: usize,
    > DepthSortWorkspace<P, S, W, H, TRIS, ACTIVE, INSTANCES>
{
    /// Size of this workspace in bytes.
    pub const BYTES: usize = core::mem::size_of::<Self>();

    const VALID: () = check_sizes(W, H, TRIS);

    /// An empty workspace whose background pixels are `background`.
    pub const fn new(background: P) -> Self {
        #[allow(clippy::let_unit_value)]
        let () = Self::VALID;
        DepthSortWorkspace {
            pixels: [background; W],
            background,
            heads: [NO_ENTRY; H],
            next: [NO_ENTRY; TRIS],
            refs: [0; TRIS],
            keys: [0; TRIS],
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
        let (Some(pixels), Some(heads)) =
            (self.pixels.get_mut(..width), self.heads.get_mut(..height))
        else {
            return Err(RenderError::InvalidTarget);
        };
        let frame = Frame {
            heads,
            next: &mut self.next,
            refs: &mut self.refs,
            keys: &mut self.keys,
            active: self.active.as_mut_view(),
            vertices: &mut [],
        };
        let mut resolve = Painter {
            pixels,
            background: self.background,
            spans: 0,
        };
        drive::<P, S, SUB_BITS, C, A, K, INSTANCES, _, _, Unbounded>(
            frame,
            &mut resolve,
            &mut IdOrder,
            scene,
            options,
            &vp,
            sink,
        )
    }
}
