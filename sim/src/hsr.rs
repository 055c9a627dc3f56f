//! The hidden-surface comparison behind `docs/hsr-table.md` (`cargo xtask hsr-table`): the
//! scene parameters and the list of methods, in one place for the firmware
//! (`firmware/examples/hsr_table.rs` includes this file with `#[path]`, so it is `no_std`: `core` and the
//! library only), the bench (`benches/hsr.rs`) and xtask.
//!
//! The scenes are [`crate::meshgen::hsr_scene`] at each level: the same objects tessellated
//! into 100, 2,500 and 60,000 triangles, seen at 240×240 with flat shading, 4 sub-pixel bits
//! and back-face culling, into RGB565 on black.
//!
//! Adding a method takes two lines here: a `method!` declaration and a line in
//! [`for_each`].

use scanline3d::options::RenderOptions;
use scanline3d::scene::{Camera, Instance, Light, Mesh, Scene, SceneError, Transform};
use scanline3d::sink::{RowPixel, RowSink};
use scanline3d::stats::{FrameStats, RenderError};
use scanline3d::Flat;

/// Target width.
pub const WIDTH: usize = 240;
/// Target height.
pub const HEIGHT: usize = 240;
/// Mesh instances per scene: three tori and the ground.
pub const INSTANCES: usize = 4;
/// Warnock's window stack for the target.
const WARNOCK_STACK: usize = scanline3d::resolve::warnock::stack_needed(WIDTH, HEIGHT);

/// One scene size and the capacities its frame needs.
pub struct Level {
    /// Triangles in the scene.
    pub polygons: usize,
    /// Triangles that survive culling and clipping (the span z-buffer's `TRIS`), as measured.
    pub tris: usize,
    /// Triangles (or pieces) crossing one row at most (`ACTIVE`), as measured: the most any
    /// method needs, which is Newell's (its split pieces are separate entries; the span
    /// z-buffer needs 23, 106 and 495).
    pub active: usize,
    /// Screen pieces a splitting method (Newell) keeps: `tris` plus the pieces its splits
    /// add, as measured (`bucketed + pieces_out − pieces_in` of its `sort_stats`).
    pub pieces: usize,
}

/// The three sizes of the lecture's table. The capacities are what the span z-buffer's frame
/// needed (`FrameStats::bucketed`, `peak_active`) and, for `pieces`, Newell's workspace entries
/// (`sim::analyze::newell_needs`); a test (`hsr::every_method_fits_the_table_capacities`)
/// and `cargo xtask hsr-table` fail if a frame does not fit.
pub const LEVELS: [Level; 3] = [
    Level {
        polygons: 100,
        tris: 60,
        active: 34,
        pieces: 108,
    },
    Level {
        polygons: 2500,
        tris: 1309,
        active: 121,
        pieces: 1413,
    },
    Level {
        polygons: 60_000,
        tris: 29_476,
        active: 500,
        pieces: 30_074,
    },
];

/// Camera: eye, target, up, vertical field of view in degrees, near, far.
pub const CAMERA: ([f32; 3], [f32; 3], [f32; 3], f32, f32, f32) = (
    [-1.3, 2.7, 3.5],
    [-0.1, -0.75, -0.3],
    [0.0, 1.0, 0.0],
    50.0,
    0.5,
    20.0,
);

/// The scenes' camera.
pub fn camera() -> Result<Camera, SceneError> {
    let (eye, target, up, fovy, near, far) = CAMERA;
    Camera::look_at(eye, target, up)?.perspective(fovy, near, far)
}

/// The demo's light.
pub fn light() -> Result<Light, SceneError> {
    scanline3d_demo::light()
}

/// The scene's instances over `meshes` (in [`crate::meshgen::hsr_scene`] order, already in
/// world coordinates).
pub fn instances<'a>(meshes: &'a [Mesh<'a>; INSTANCES]) -> [Instance<'a>; INSTANCES] {
    meshes.each_ref().map(|mesh| Instance {
        mesh,
        transform: Transform::IDENTITY,
    })
}

/// The scene over `instances`.
pub fn scene<'a>(instances: &'a [Instance<'a>]) -> Result<Scene<'a>, SceneError> {
    Ok(Scene {
        instances,
        camera: camera()?,
        light: light()?,
    })
}

/// A method's workspace for pixels `P`, as the measurements use it.
pub trait Resolve<P: RowPixel>: Sized {
    /// The workspace's size in bytes.
    const BYTES: usize;
    /// An empty workspace with background `background`.
    fn new(background: P) -> Self;
    /// Renders `scene` with the table's options (default: 4 sub-pixel bits, culling on).
    fn frame<K: RowSink<P>>(
        &mut self,
        scene: &Scene<'_>,
        sink: &mut K,
    ) -> Result<FrameStats, RenderError<K::Error>>;
}

/// A hidden-surface method: its name in the table and its workspace for pixel type `P` and a
/// level's capacities.
pub trait Method {
    /// Name in the table.
    const NAME: &'static str;
    /// The workspace.
    type Ws<P: RowPixel, const TRIS: usize, const ACTIVE: usize, const PIECES: usize>: Resolve<P>;
}

/// Declares a method: `method!(Marker, "name", [consts it uses] WorkspaceType)`, where the
/// workspace type may use `P` and the level's capacities `TRIS`, `ACTIVE` and `PIECES`
/// (listing those it uses) and has the library's workspace API (`new(background)`,
/// `render(&scene, &options, &mut sink)`, `BYTES`).
macro_rules! method {
    ($marker:ident, $name:literal, [$($c:ident),*] $ws:ty) => {
        #[doc = concat!("The `", $name, "` method.")]
        pub struct $marker;
        impl Method for $marker {
            const NAME: &'static str = $name;
            type Ws<P: RowPixel, const TRIS: usize, const ACTIVE: usize, const PIECES: usize> = $ws;
        }
        impl<P: RowPixel, $(const $c: usize),*> Resolve<P> for $ws {
            const BYTES: usize = <$ws>::BYTES;
            fn new(background: P) -> Self {
                <$ws>::new(background)
            }
            fn frame<K: RowSink<P>>(
                &mut self,
                scene: &Scene<'_>,
                sink: &mut K,
            ) -> Result<FrameStats, RenderError<K::Error>> {
                self.render(scene, &RenderOptions::default(), sink)
            }
        }
    };
}

method!(SpanZBuffer, "span-zbuffer", [TRIS, ACTIVE]
    scanline3d::Workspace<P, Flat, WIDTH, HEIGHT, TRIS, ACTIVE, INSTANCES>);
method!(ZBuffer, "zbuffer", [TRIS]
    scanline3d::resolve::ZBufferWorkspace<P, Flat, WIDTH, HEIGHT, TRIS, INSTANCES>);
method!(Band16, "band:16", [TRIS, ACTIVE]
    scanline3d::resolve::BandWorkspace<P, Flat, WIDTH, HEIGHT, 16, TRIS, ACTIVE, INSTANCES>);
method!(SpanSort, "span-sort", [TRIS, ACTIVE]
    scanline3d::resolve::SpanSortWorkspace<P, Flat, WIDTH, HEIGHT, TRIS, ACTIVE, INSTANCES>);
method!(DepthSort, "depth-sort", [TRIS, ACTIVE]
    scanline3d::resolve::DepthSortWorkspace<P, Flat, WIDTH, HEIGHT, TRIS, ACTIVE, INSTANCES>);
// Newell keeps every piece and the pieces it splits (`PIECES`).
method!(Newell, "newell", [PIECES, ACTIVE]
    scanline3d::resolve::NewellWorkspace<P, Flat, WIDTH, HEIGHT, PIECES, ACTIVE, INSTANCES>);
// Warnock keeps every piece (`TRIS`, as no triangle of these scenes is clipped into several),
// a window list of up to one entry per piece, and the window stack the target size needs.
method!(Warnock, "warnock", [TRIS]
    scanline3d::resolve::WarnockWorkspace<P, Flat, WIDTH, HEIGHT, TRIS, TRIS, WARNOCK_STACK, INSTANCES>);

/// Work done for each (method, level): `visit` gets the method and the level's capacities.
pub trait Visit {
    /// Why a visit failed.
    type Error;
    /// Measures method `M` at level `level` (an index into [`LEVELS`]).
    fn visit<M: Method, const TRIS: usize, const ACTIVE: usize, const PIECES: usize>(
        &mut self,
        level: usize,
    ) -> Result<(), Self::Error>;
}

/// Visits every method at every level, in table order; stops at the first error.
pub fn for_each<V: Visit>(v: &mut V) -> Result<(), V::Error> {
    levels::<SpanZBuffer, V>(v)?;
    levels::<ZBuffer, V>(v)?;
    levels::<Band16, V>(v)?;
    levels::<SpanSort, V>(v)?;
    levels::<DepthSort, V>(v)?;
    levels::<Newell, V>(v)?;
    levels::<Warnock, V>(v)?;
    Ok(())
}

fn levels<M: Method, V: Visit>(v: &mut V) -> Result<(), V::Error> {
    v.visit::<M, { LEVELS[0].tris }, { LEVELS[0].active }, { LEVELS[0].pieces }>(0)?;
    v.visit::<M, { LEVELS[1].tris }, { LEVELS[1].active }, { LEVELS[1].pieces }>(1)?;
    v.visit::<M, { LEVELS[2].tris }, { LEVELS[2].active }, { LEVELS[2].pieces }>(2)
}

/// Ray tracing on the table's scenes, the lecture's fourth method: the library's fixed-point
/// tracer ([`scanline3d::trace`]) over every triangle of a level, with a bounding-volume
/// hierarchy built at run time into [`traced::Buffers`] (its cost is reported apart from the
/// frame's), the scenes' camera and, with shadows, their light.
pub mod traced {
    use super::{Scene, CAMERA, HEIGHT, WIDTH};
    use fixed::types::I16F16;
    use scanline3d::scene::MeshColors;
    use scanline3d::sink::{RowPixel, RowSink};
    use scanline3d::trace::bvh::{self, BvhNode};
    use scanline3d::trace::{
        Colour, Light, Material, Object, Scene as TracedScene, ScreenBound, Shape, TraceCamera,
        TraceError, TraceOptions, TraceStats, Tracer, Triangle, Vec3,
    };

    /// What a traced row of the table runs.
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    pub enum Variant {
        /// Primary rays only (no light).
        Primary,
        /// Primary rays and a shadow ray per lit pixel.
        Shadows,
        /// As `Shadows`, primary visibility in hybrid mode (the objects' screen bounds).
        Hybrid,
    }

    impl Variant {
        /// Every variant, in table order.
        pub const ALL: [Variant; 3] = [Variant::Primary, Variant::Shadows, Variant::Hybrid];

        /// The name in the firmware's lines.
        pub fn name(self) -> &'static str {
            match self {
                Variant::Primary => "primary",
                Variant::Shadows => "shadows",
                Variant::Hybrid => "hybrid",
            }
        }
    }

    /// Hybrid mode's buffers: screen bounds and active list, one entry per object each.
    pub type HybridBuffers<'b> = Option<(&'b mut [ScreenBound], &'b mut [ScreenBound])>;

    /// Levels the tracer runs at: the first two. At 60,000 triangles the traced objects (60
    /// bytes each, vertices inline) and their hierarchy need about 7 MB, more than the QEMU
    /// board's 4 MiB of RAM or flash.
    pub const TRACED_LEVELS: usize = 2;
    /// Most triangles a traced level may have.
    pub const CAPACITY: usize = 2_500;
    /// Ray stack entries: the default depth limit (4) plus one.
    pub const STACK: usize = 5;

    /// Objects (one per triangle, in the rasterizers' id order), one material per triangle
    /// (its colour; KA = KD = 1, the light's diffuse level as its intensity) and the
    /// hierarchy's nodes and items.
    pub struct Buffers {
        objects: [Object<'static>; CAPACITY],
        materials: [Material; CAPACITY],
        nodes: [BvhNode; 2 * CAPACITY],
        items: [u32; CAPACITY],
        bounds: [ScreenBound; CAPACITY],
        active: [ScreenBound; CAPACITY],
        len: usize,
        bounded: usize,
        nodes_used: usize,
        items_used: usize,
    }

    fn vec3(v: [I16F16; 3]) -> Vec3 {
        Vec3 {
            x: v[0],
            y: v[1],
            z: v[2],
        }
    }

    fn material(c: embedded_graphics::pixelcolor::Rgb888) -> Result<Material, &'static str> {
        use embedded_graphics::pixelcolor::RgbColor;
        let channel = |v: u8| I16F16::from_num(v) / 255;
        let colour =
            Colour::new([channel(c.r()), channel(c.g()), channel(c.b())]).map_err(|_| "colour")?;
        Material::new(
            colour,
            [I16F16::ONE, I16F16::ONE, I16F16::ZERO, I16F16::ZERO],
            I16F16::ONE,
        )
        .map_err(|_| "material")
    }

    impl Buffers {
        /// Empty buffers (their slots hold a placeholder until [`Buffers::fill`]).
        pub fn new() -> Result<Buffers, &'static str> {
            let one = I16F16::ONE.to_bits();
            let placeholder = Triangle::new([
                Vec3::ZERO,
                Vec3::from_bits(one, 0, 0),
                Vec3::from_bits(0, one, 0),
            ])
            .map_err(|_| "placeholder triangle")?;
            let object = Object {
                shape: Shape::Triangle(placeholder),
                material: 0,
            };
            let node = BvhNode {
                min: Vec3::ZERO,
                max: Vec3::ZERO,
                index: 0,
                count: 0,
                axis: 0,
            };
            Ok(Buffers {
                objects: [object; CAPACITY],
                materials: [material(embedded_graphics::pixelcolor::Rgb888::new(0, 0, 0))?;
                    CAPACITY],
                nodes: [node; 2 * CAPACITY],
                items: [0; CAPACITY],
                bounds: [ScreenBound::default(); CAPACITY],
                active: [ScreenBound::default(); CAPACITY],
                len: 0,
                bounded: 0,
                nodes_used: 0,
                items_used: 0,
            })
        }

        /// Every triangle of `scene` (whose instances must be untransformed, as the table's
        /// are) as a traced object with its flat colour, and the hierarchy over them.
        pub fn fill(&mut self, scene: &Scene<'_>) -> Result<(), &'static str> {
            let mut n = 0;
            for instance in scene.instances {
                if instance.transform != scanline3d::scene::Transform::IDENTITY {
                    return Err("traced scenes take untransformed instances");
                }
                let mesh = instance.mesh;
                let vertices = mesh.vertices();
                for (k, t) in mesh.triangles().iter().enumerate() {
                    let corner = |i: usize| -> Result<Vec3, &'static str> {
                        let v = t.get(i).and_then(|&v| vertices.get(usize::from(v)));
                        v.map(|v| vec3(*v)).ok_or("vertex index")
                    };
                    let colour = match mesh.colors() {
                        MeshColors::Uniform(c) => Some(c),
                        MeshColors::PerFace(c) => c.get(k).copied(),
                        MeshColors::PerVertex(c) => {
                            t.first().and_then(|&v| c.get(usize::from(v))).copied()
                        }
                    }
                    .ok_or("colour index")?;
                    let triangle = Triangle::new([corner(0)?, corner(1)?, corner(2)?])
                        .map_err(|_| "a triangle the tracer rejects")?;
                    let index = u16::try_from(n).map_err(|_| "too many triangles")?;
                    *self.objects.get_mut(n).ok_or("traced CAPACITY exceeded")? = Object {
                        shape: Shape::Triangle(triangle),
                        material: index,
                    };
                    *self
                        .materials
                        .get_mut(n)
                        .ok_or("traced CAPACITY exceeded")? = material(colour)?;
                    n += 1;
                }
            }
            self.len = n;
            let objects = self.objects.get(..n).ok_or("length")?;
            let (nodes, items, bounded) =
                bvh::build(objects, &mut self.nodes, &mut self.items).map_err(|_| "hierarchy")?;
            (self.nodes_used, self.items_used, self.bounded) = (nodes, items, bounded);
            Ok(())
        }

        /// Bytes the filled buffers use for `variant`: objects, materials, nodes and items, and
        /// in hybrid mode the screen bounds and active list.
        pub fn bytes_used(&self, variant: Variant) -> usize {
            let hybrid = if variant == Variant::Hybrid {
                2 * core::mem::size_of::<ScreenBound>()
            } else {
                0
            };
            self.len
                * (core::mem::size_of::<Object<'static>>()
                    + core::mem::size_of::<Material>()
                    + hybrid)
                + self.nodes_used * core::mem::size_of::<BvhNode>()
                + self.items_used * core::mem::size_of::<u32>()
        }

        /// Calls `f` with a tracer over the filled buffers: the table's camera, ambient level
        /// and, but for [`Variant::Primary`], its light (else no light: primary rays only); for
        /// [`Variant::Hybrid`] `f` gets the hybrid mode's buffers too.
        pub fn with_tracer<R>(
            &mut self,
            variant: Variant,
            f: impl FnOnce(&Tracer<'_, '_, STACK>, HybridBuffers<'_>) -> R,
        ) -> Result<R, &'static str> {
            let shadows = variant != Variant::Primary;
            let (eye, target, up, fovy, near, far) = CAMERA;
            let f64s = |v: [f32; 3]| v.map(f64::from);
            let camera = TraceCamera::new(
                f64s(eye),
                f64s(target),
                f64s(up),
                f64::from(fovy),
                f64::from(near),
                f64::from(far),
                WIDTH as u16,
                HEIGHT as u16,
            )
            .map_err(|_| "camera")?;
            let (towards, ambient, diffuse) = scanline3d_demo::LIGHT;
            let towards = towards.map(I16F16::from_num);
            let light = Light::directional(vec3(towards), I16F16::from_num(diffuse))
                .map_err(|_| "light")?;
            let lights = [light];
            let lights = if shadows { &lights[..] } else { &[] };
            let objects = self.objects.get(..self.len).ok_or("length")?;
            let materials = self.materials.get(..self.len).ok_or("length")?;
            let scene = TracedScene::new(
                objects,
                materials,
                lights,
                Colour::new([I16F16::ZERO; 3]).map_err(|_| "background")?,
                I16F16::from_num(ambient),
            )
            .map_err(|_| "traced scene")?
            .with_bvh(
                self.nodes.get(..self.nodes_used).ok_or("nodes")?,
                self.items.get(..self.items_used).ok_or("items")?,
                self.bounded,
            )
            .map_err(|_| "hierarchy rejected")?;
            let tracer = Tracer::<STACK>::new(&scene, &camera, TraceOptions::default());
            let hybrid = match (
                self.bounds.get_mut(..self.len),
                self.active.get_mut(..self.len),
            ) {
                (Some(bounds), Some(active)) if variant == Variant::Hybrid => {
                    Some((bounds, active))
                }
                _ => None,
            };
            Ok(f(&tracer, hybrid))
        }
    }

    /// One traced frame into `sink` through a row of `P` (`background` only fills the row
    /// buffer before the first row is traced), in hybrid mode when given its buffers.
    pub fn frame<P: RowPixel, K: RowSink<P>>(
        tracer: &Tracer<'_, '_, STACK>,
        hybrid: HybridBuffers<'_>,
        background: P,
        sink: &mut K,
    ) -> Result<TraceStats, TraceError<K::Error>> {
        let mut row = [background; WIDTH];
        match hybrid {
            // No shadow candidate buffer: the table's scenes are lit by one light and measured
            // with the hierarchy's shadow rays.
            Some((bounds, active)) => tracer.render_hybrid(bounds, active, &mut [], &mut row, sink),
            None => tracer.render(&mut row, sink),
        }
    }
}
