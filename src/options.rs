//! The per-frame options of a render: sub-pixel bits, back-face culling, the clipping stage and
//! the set-up arithmetic, each a type or a const generic so a build carries only its choice.

use crate::arithmetic::{Arithmetic, Precise};
use crate::clip::{Clipping, FrustumClip};
pub use crate::project::{MAX_SCREEN, MAX_SUB_PIXEL_BITS};

/// Default for a [`Workspace`](crate::Workspace)'s `INSTANCES`: most mesh instances in one scene. Each costs
/// about 120 bytes of stack during a render (its transform and lighting set-up).
pub const MAX_INSTANCES: usize = 8;

/// Options for one render. `SUB_BITS` is the number of sub-pixel bits vertices snap to
/// (0 to 8; default 4, i.e. 1/16 pixel).
///
/// ```
/// use scanline3d::options::RenderOptions;
/// let default = RenderOptions::default(); // 4 sub-pixel bits, back faces culled
/// let finer: RenderOptions<8> = default.with_sub_pixel_bits::<8>();
/// assert!(finer.cull_back_faces);
/// let both_sides = RenderOptions::default().with_back_face_culling(false);
/// assert!(!both_sides.cull_back_faces);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RenderOptions<
    const SUB_BITS: u32 = 4,
    C: Clipping = FrustumClip,
    A: Arithmetic = Precise,
> {
    /// Skip triangles whose front (counter-clockwise) side faces away from the camera.
    pub cull_back_faces: bool,
    /// The clipping stage (a zero-sized type).
    pub clipping: C,
    /// The set-up arithmetic (a zero-sized type): [`Precise`] by default.
    pub arithmetic: A,
}

impl Default for RenderOptions<4> {
    fn default() -> Self {
        RenderOptions {
            cull_back_faces: true,
            clipping: FrustumClip,
            arithmetic: Precise::default(),
        }
    }
}

impl<const SUB_BITS: u32, C: Clipping, A: Arithmetic> RenderOptions<SUB_BITS, C, A> {
    /// The same options with back-face culling on or off. (Prefer this to a struct literal,
    /// which cannot infer the default `SUB_BITS`.)
    pub const fn with_back_face_culling(self, on: bool) -> Self {
        RenderOptions {
            cull_back_faces: on,
            clipping: self.clipping,
            arithmetic: self.arithmetic,
        }
    }

    /// The same options with another number of sub-pixel bits.
    pub const fn with_sub_pixel_bits<const N: u32>(self) -> RenderOptions<N, C, A> {
        RenderOptions {
            cull_back_faces: self.cull_back_faces,
            clipping: self.clipping,
            arithmetic: self.arithmetic,
        }
    }

    /// The same options with another clipping stage: [`NoClip`](crate::clip::NoClip) compiles the clipper out
    /// for scenes that never need it (`sim analyze` reports whether one does); triangles
    /// that would need it anyway are counted in [`FrameStats::unclipped`](crate::FrameStats::unclipped).
    ///
    /// ```
    /// use scanline3d::{clip::NoClip, RenderOptions};
    /// let lean = RenderOptions::default().with_clipping(NoClip);
    /// assert_eq!(lean.clipping, NoClip);
    /// ```
    pub const fn with_clipping<D: Clipping>(self, clipping: D) -> RenderOptions<SUB_BITS, D, A> {
        RenderOptions {
            cull_back_faces: self.cull_back_faces,
            clipping,
            arithmetic: self.arithmetic,
        }
    }

    /// The same options with another set-up arithmetic ([`crate::arithmetic::Arithmetic`]).
    ///
    /// ```
    /// use scanline3d::arithmetic::{Quick, Setup};
    /// use scanline3d::{arithmetic::{Reciprocal, WideTransform}, math::WideNormals};
    /// let quick = scanline3d::RenderOptions::default().with_arithmetic(Quick::default());
    /// // One knob alone: reciprocal projection, the rest precise.
    /// let one = quick.with_arithmetic(Setup::<WideTransform, Reciprocal, WideNormals>::default());
    /// # let _ = one;
    /// ```
    pub const fn with_arithmetic<B: Arithmetic>(
        self,
        arithmetic: B,
    ) -> RenderOptions<SUB_BITS, C, B> {
        RenderOptions {
            cull_back_faces: self.cull_back_faces,
            clipping: self.clipping,
            arithmetic,
        }
    }
}
