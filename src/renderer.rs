//! What a user holds: a [`Renderer`] is a configuration ([`Config`]: every precision choice)
//! with the memory of one hidden-surface [`Method`]. [`Storage`] is the renderer of the default
//! method, the span z-buffer, sized by its const generics alone; [`View`] borrows it without the
//! sizes, as heapless' `VecView` borrows a `Vec<T, N>`. Every renderer has the same
//! `render(&scene, &mut sink)` call.
//!
//! A renderer is built by a `const fn`, so it can live in a `static` (a 13 KB workspace is a
//! stack overflow on most microcontrollers), for example through `static_cell`'s
//! `ConstStaticCell`, which hands out the one `&'static mut` without `unsafe`:
//!
//! ```
//! use embedded_graphics::pixelcolor::Rgb565;
//! use scanline3d::{preset, sink::HashSink, Flat, Settings, Storage, View};
//! use static_cell::ConstStaticCell;
//!
//! type Panel = Settings<Rgb565, Flat, preset::Balanced>;
//! // 240×240, room for 1280 triangles after culling and 64 crossing one row.
//! static RENDERER: ConstStaticCell<Storage<Panel, 240, 240, 1280, 64>> =
//!     ConstStaticCell::new(Storage::new(Rgb565::new(3, 6, 5)));
//!
//! // Code that draws takes the view: no sizes to repeat.
//! fn draw(view: &mut View<'_, Panel>, scene: &scanline3d::scene::Scene<'_>) -> u32 {
//!     let mut sink = HashSink::new();
//!     match view.render(scene, &mut sink) {
//!         Ok(stats) if stats.is_complete() => sink.hash(),
//!         _ => 0,
//!     }
//! }
//!
//! let renderer = RENDERER.take();
//! assert!(Storage::<Panel, 240, 240, 1280, 64>::BYTES < 16 * 1024);
//! let instances = scanline3d_demo::instances();
//! let scene = scanline3d_demo::scene(&instances, 0, scanline3d_demo::ORBIT_FRAMES)?;
//! assert_ne!(draw(&mut renderer.as_view(), &scene), 0);
//! # Ok::<(), scanline3d::scene::SceneError>(())
//! ```

use crate::config::Config;
use crate::method::{Method, Options};
use crate::options::MAX_INSTANCES;
use crate::scene::Scene;
use crate::sink::RowSink;
use crate::stats::{FrameStats, RenderError};
use crate::workspace::{SpanView, Workspace};
use core::marker::PhantomData;

/// A configuration `C` with the memory of hidden-surface method `M` (a workspace type of
/// `crate::render` or [`crate::resolve`] whose pixel and shading are `C`'s).
///
/// ```
/// use embedded_graphics::pixelcolor::Rgb565;
/// use scanline3d::{preset, resolve::NewellWorkspace, sink::HashSink, Flat, Renderer, Settings};
///
/// type Cfg = Settings<Rgb565, Flat, preset::Exact>;
/// let mut newell: Box<Renderer<Cfg, NewellWorkspace<Rgb565, Flat, 240, 240, 2048, 96>>> =
///     Box::new(Renderer::with_method(NewellWorkspace::new(Rgb565::new(0, 0, 0))));
/// let instances = scanline3d_demo::instances();
/// let scene = scanline3d_demo::scene(&instances, 0, scanline3d_demo::ORBIT_FRAMES)?;
/// let stats = newell.render(&scene, &mut HashSink::new()).unwrap();
/// assert!(stats.is_complete());
/// # Ok::<(), scanline3d::scene::SceneError>(())
/// ```
pub struct Renderer<C: Config, M> {
    method: M,
    cull_back_faces: bool,
    config: PhantomData<C>,
}

impl<C: Config, M: Method<C::Pixel, Shading = C::Shading>> Renderer<C, M> {
    /// A renderer of method `method`, back-face culling on.
    pub const fn with_method(method: M) -> Self {
        Renderer {
            method,
            cull_back_faces: true,
            config: PhantomData,
        }
    }

    /// The same renderer with back-face culling on or off (off draws both sides: needed for
    /// open meshes and meshes of mixed winding; `sim analyze` says which a mesh needs).
    pub const fn with_back_face_culling(mut self, on: bool) -> Self {
        self.cull_back_faces = on;
        self
    }

    /// Turns back-face culling on or off for the following frames.
    pub fn set_back_face_culling(&mut self, on: bool) {
        self.cull_back_faces = on;
    }

    /// Renders `scene`, handing each row to `sink` once, top to bottom.
    pub fn render<K: RowSink<C::Pixel>>(
        &mut self,
        scene: &Scene<'_>,
        sink: &mut K,
    ) -> Result<FrameStats, RenderError<K::Error>> {
        C::options()
            .with_back_face_culling(self.cull_back_faces)
            .render(&mut self.method, scene, sink)
    }

    /// The method's memory, for what only that method reports (for example Newell's sort
    /// statistics).
    pub fn method(&self) -> &M {
        &self.method
    }
}

/// The span z-buffer renderer of configuration `C`: a `W × H` target, room for `TRIS`
/// triangles after culling per frame, `ACTIVE` crossing one row, and a vertex cache of `VERTS`
/// entries ([`crate::cache`], default none). Its size is [`Renderer::BYTES`]; see
/// [`Workspace`] for each part.
pub type Storage<
    C,
    const W: usize,
    const H: usize,
    const TRIS: usize = 1024,
    const ACTIVE: usize = 64,
    const VERTS: usize = 0,
> = Renderer<
    C,
    Workspace<
        <C as Config>::Pixel,
        <C as Config>::Shading,
        W,
        H,
        TRIS,
        ACTIVE,
        MAX_INSTANCES,
        <C as Config>::Depth,
        VERTS,
    >,
>;

impl<
        C: Config,
        const W: usize,
        const H: usize,
        const TRIS: usize,
        const ACTIVE: usize,
        const VERTS: usize,
    > Storage<C, W, H, TRIS, ACTIVE, VERTS>
{
    /// Size in bytes.
    pub const BYTES: usize = core::mem::size_of::<Self>();

    /// An empty renderer whose background pixels are `background`.
    pub const fn new(background: C::Pixel) -> Self {
        Self::with_method(Workspace::new(background))
    }

    /// The renderer without its sizes in the type.
    pub fn as_view(&mut self) -> View<'_, C> {
        View {
            span: self.method.span_view(),
            cull_back_faces: self.cull_back_faces,
        }
    }
}

/// A span z-buffer renderer of configuration `C` borrowed without its sizes
/// ([`Storage::as_view`](Renderer::as_view)).
pub struct View<'a, C: Config> {
    span: SpanView<'a, C::Pixel, C::Shading, C::Depth, MAX_INSTANCES>,
    cull_back_faces: bool,
}

impl<C: Config> View<'_, C> {
    /// Renders `scene`, handing each row to `sink` once, top to bottom.
    pub fn render<K: RowSink<C::Pixel>>(
        &mut self,
        scene: &Scene<'_>,
        sink: &mut K,
    ) -> Result<FrameStats, RenderError<K::Error>> {
        C::options()
            .with_back_face_culling(self.cull_back_faces)
            .render(&mut self.span, scene, sink)
    }
}
