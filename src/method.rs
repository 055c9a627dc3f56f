//! Every hidden-surface method behind one call. A [`Method`] is the memory of one method (a
//! workspace type of `crate::render` or [`crate::resolve`]); [`Options`] are the per-frame
//! precision choices a [`Config`](crate::Config) hands it. Together they give every method the
//! same `render(&scene, &mut sink)` call ([`crate::Renderer`]).

use crate::arithmetic::Arithmetic;
use crate::clip::Clipping;
use crate::depth::DepthFormat;
use crate::options::RenderOptions;
use crate::resolve::{
    BandWorkspace, DepthSortWorkspace, NewellWorkspace, SpanSortWorkspace, WarnockWorkspace,
};
use crate::scene::Scene;
use crate::shading::Shading;
use crate::sink::{RowPixel, RowSink};
use crate::stats::{FrameStats, RenderError};
use crate::workspace::{SpanView, Workspace};

/// A hidden-surface method with its memory: renders a scene with given options, every row to
/// a sink once, top to bottom.
pub trait Method<P: RowPixel> {
    /// The shading model the method was sized for.
    type Shading: Shading;

    /// Renders `scene` with `options` (see [`RenderOptions`]).
    fn render_with<const SUB_BITS: u32, C: Clipping, A: Arithmetic, K: RowSink<P>>(
        &mut self,
        scene: &Scene<'_>,
        options: &RenderOptions<SUB_BITS, C, A>,
        sink: &mut K,
    ) -> Result<FrameStats, RenderError<K::Error>>;
}

/// Per-frame options a [`Config`](crate::Config) chooses: [`RenderOptions`] with its sub-pixel
/// bits, clipping and set-up arithmetic. (The trait lets a configuration name them as one
/// type and still reach the const generic they carry.)
pub trait Options: Copy {
    /// Renders `scene` through `method` with these options.
    fn render<P: RowPixel, M: Method<P>, K: RowSink<P>>(
        &self,
        method: &mut M,
        scene: &Scene<'_>,
        sink: &mut K,
    ) -> Result<FrameStats, RenderError<K::Error>>;

    /// The same options with back-face culling on or off.
    fn with_back_face_culling(self, on: bool) -> Self;
}

impl<const SUB_BITS: u32, C: Clipping, A: Arithmetic> Options for RenderOptions<SUB_BITS, C, A> {
    fn render<P: RowPixel, M: Method<P>, K: RowSink<P>>(
        &self,
        method: &mut M,
        scene: &Scene<'_>,
        sink: &mut K,
    ) -> Result<FrameStats, RenderError<K::Error>> {
        method.render_with(scene, self, sink)
    }

    fn with_back_face_culling(self, on: bool) -> Self {
        RenderOptions::with_back_face_culling(self, on)
    }
}

/// Implements [`Method`] for a workspace type whose inherent `render` has the method signature.
macro_rules! method {
    ($ty:ty, [$($generics:tt)*]) => {
        impl<P: RowPixel, S: Shading, $($generics)*> Method<P> for $ty {
            type Shading = S;
            fn render_with<const SUB_BITS: u32, C: Clipping, A: Arithmetic, K: RowSink<P>>(
                &mut self,
                scene: &Scene<'_>,
                options: &RenderOptions<SUB_BITS, C, A>,
                sink: &mut K,
            ) -> Result<FrameStats, RenderError<K::Error>> {
                self.render(scene, options, sink)
            }
        }
    };
}

method!(
    Workspace<P, S, W, H, TRIS, ACTIVE, INSTANCES, Z, VERTS>,
    [const W: usize, const H: usize, const TRIS: usize, const ACTIVE: usize, const INSTANCES: usize, Z: DepthFormat, const VERTS: usize]
);
method!(
    BandWorkspace<P, S, W, H, B, TRIS, ACTIVE, INSTANCES, Z>,
    [const W: usize, const H: usize, const B: usize, const TRIS: usize, const ACTIVE: usize, const INSTANCES: usize, Z: DepthFormat]
);
method!(
    SpanSortWorkspace<P, S, W, H, TRIS, ACTIVE, INSTANCES>,
    [const W: usize, const H: usize, const TRIS: usize, const ACTIVE: usize, const INSTANCES: usize]
);
method!(
    DepthSortWorkspace<P, S, W, H, TRIS, ACTIVE, INSTANCES>,
    [const W: usize, const H: usize, const TRIS: usize, const ACTIVE: usize, const INSTANCES: usize]
);
method!(
    NewellWorkspace<P, S, W, H, PIECES, ACTIVE, INSTANCES>,
    [const W: usize, const H: usize, const PIECES: usize, const ACTIVE: usize, const INSTANCES: usize]
);
method!(
    WarnockWorkspace<P, S, W, H, PIECES, LIST, STACK, INSTANCES>,
    [const W: usize, const H: usize, const PIECES: usize, const LIST: usize, const STACK: usize, const INSTANCES: usize]
);
method!(
    SpanView<'_, P, S, Z, INSTANCES>,
    [Z: DepthFormat, const INSTANCES: usize]
);
