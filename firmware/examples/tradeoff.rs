//! Precision trade-off firmware: the demo orbit rendered with one precision preset
//! (`scanline3d::preset`) or single-knob variation of the default, printing each frame's hash
//! and instructions. The variant is chosen at build time, so each firmware image carries only
//! its own code (`cargo rustc --example tradeoff -- --cfg 'scanline3d_variant="fast"'`; the
//! default is `balanced`). On the host the example renders every variant. `cargo xtask
//! tradeoff` builds and runs each variant on thumbv7em and thumbv6m and checks the hashes
//! against the host's. Built with `--cfg scanline3d_corpus` and `SCANLINE3D_CORPUS` naming
//! the file `scanline3d_sim::export::corpus_source` writes (the xtask does both), it also
//! renders every view of every corpus scene.
//!
//! ```sh
//! cargo run --release --example tradeoff --target thumbv6m-none-eabi   # QEMU mps2-an385
//! cargo run --release --example tradeoff                               # host: hashes only
//! ```
//!
//! The host also prints each frame's byte-wise hash (`bytes`, `scanline3d_demo::byte_hash`),
//! the hash the firmware printed before `HashSink` hashed one word a pixel.
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]

use embedded_graphics::pixelcolor::Rgb565;
use scanline3d::arithmetic::Arithmetic;
use scanline3d::clip::FrustumClip;
use scanline3d::depth::{Depth16, DepthFormat};
use scanline3d::math::MathBackend;
use scanline3d::preset::{self, Preset};
use scanline3d::scene::{Camera, Scene, SceneError};
use scanline3d::shading::{Affine, Gouraud, Interpolation, PerPixel, PerSegment};
use scanline3d::sink::HashSink;
use scanline3d::{Depth, Flat, RenderOptions, Shading, Unlit, Workspace};
use scanline3d_demo as demo;
#[cfg(not(target_os = "none"))]
use scanline3d_demo::byte_hash::{ByteHashSink, Tee};

/// The demo's panel workspace with room to spare: the approximate set-up of some variants moves
/// the camera slightly, so the exact capacities `sim analyze --demo` measured may not cover it.
/// Built with `--cfg scanline3d_vertex_cache` (`cargo xtask speed` does both), with a vertex
/// cache holding every demo vertex (the same pixels).
type Ws<Sh, Z> = Workspace<Rgb565, Sh, 240, 240, 640, 80, 3, Z, CACHE>;

/// Vertex cache entries of the demo workspace.
#[cfg(not(scanline3d_vertex_cache))]
const CACHE: usize = 0;
#[cfg(scanline3d_vertex_cache)]
const CACHE: usize = demo::PANEL_VERTICES;

/// A new workspace: boxed on the host (a debug build would need a large main stack), on the
/// stack on targets (no allocator; the variant's frame holds it while it renders).
#[cfg(not(target_os = "none"))]
fn fresh<T>(make: impl FnOnce() -> T) -> Box<T> {
    Box::new(make())
}
#[cfg(target_os = "none")]
fn fresh<T>(make: impl FnOnce() -> T) -> T {
    make()
}

/// One frame's result.
struct Frame {
    hash: u32,
    /// Host only: the same frame's byte-wise hash (`scanline3d_demo::byte_hash`), the one the
    /// firmware printed before the word hash, so `cargo xtask speed` can compare the pixels
    /// with figures saved before it.
    #[cfg(not(target_os = "none"))]
    bytes: u32,
    /// Target only: the host has no instruction counter.
    #[cfg_attr(not(target_os = "none"), allow(dead_code))]
    instructions: u64,
    complete: bool,
    /// Triangles (or clipped pieces) set up for the walk, and pixel centres covered.
    #[cfg_attr(not(target_os = "none"), allow(dead_code))]
    activated: u32,
    #[cfg_attr(not(target_os = "none"), allow(dead_code))]
    fragments: u32,
}

/// Renders one frame of `scene` into the panel model, counting its instructions.
fn frame<
    Sh: Shading,
    const S: u32,
    A: Arithmetic,
    const T: usize,
    const ACT: usize,
    const I: usize,
    Z: DepthFormat,
    const V: usize,
>(
    ws: &mut Workspace<Rgb565, Sh, 240, 240, T, ACT, I, Z, V>,
    scene: &Scene<'_>,
    options: &RenderOptions<S, FrustumClip, A>,
    count: &impl Fn() -> Counter,
) -> Result<Frame, &'static str> {
    #[cfg(target_os = "none")]
    let mut sink = HashSink::new();
    #[cfg(not(target_os = "none"))]
    let mut sink = Tee(HashSink::new(), ByteHashSink::new());
    let counter = count();
    #[cfg(not(scanline3d_no_render))]
    let stats = ws.render(scene, options, &mut sink).map_err(|_| "render")?;
    #[cfg(scanline3d_no_render)]
    let stats = {
        core::hint::black_box((&mut *ws, scene, options, &mut sink));
        scanline3d::FrameStats::default()
    };
    let instructions = counter.stop();
    #[cfg(target_os = "none")]
    let hash = sink.hash();
    #[cfg(not(target_os = "none"))]
    let hash = sink.0.hash();
    Ok(Frame {
        hash,
        #[cfg(not(target_os = "none"))]
        bytes: sink.1.hash(),
        instructions,
        complete: stats.is_complete(),
        activated: stats.activated,
        fragments: stats.fragments,
    })
}

/// A `gluLookAt` · `gluPerspective` camera computed with math backend `M`.
fn camera<M: MathBackend>(
    (eye, target, up): ([f32; 3], [f32; 3], [f32; 3]),
    (fovy, near, far): (f32, f32, f32),
) -> Result<Camera, SceneError> {
    Camera::look_at_with::<M>(eye, target, up)?.perspective_with::<M>(fovy, near, far)
}

/// What to render with each variant.
trait Renders {
    /// Renders with variant `name`: `options`, the camera computed with `M`, depth format `Z`,
    /// shading `Sh`.
    fn variant<Sh: Shading, const S: u32, A: Arithmetic, M: MathBackend, Z: DepthFormat>(
        &mut self,
        name: &'static str,
        options: RenderOptions<S, FrustumClip, A>,
    ) -> Result<(), &'static str>;
}

/// The demo orbit; `report(variant, frame, result)`.
// Not rendered by a `--cfg scanline3d_corpus_only` profile build.
#[cfg_attr(scanline3d_corpus_only, allow(dead_code))]
struct Orbit<'a, C, R> {
    count: &'a C,
    report: R,
}

impl<C: Fn() -> Counter, R: FnMut(&str, u32, Frame)> Renders for Orbit<'_, C, R> {
    fn variant<Sh: Shading, const S: u32, A: Arithmetic, M: MathBackend, Z: DepthFormat>(
        &mut self,
        name: &'static str,
        options: RenderOptions<S, FrustumClip, A>,
    ) -> Result<(), &'static str> {
        let mut ws = fresh(|| Ws::<Sh, Z>::new(Rgb565::new(0, 0, 0)));
        // Unlit shading draws the demo's baked meshes.
        let instances = if Sh::LIT {
            demo::instances()
        } else {
            demo::baked_instances()
        };
        for f in 0..demo::ORBIT_FRAMES {
            let (eye, target, up, fovy, near, far) = demo::camera_parameters(f, demo::ORBIT_FRAMES);
            let scene = Scene {
                instances: &instances,
                camera: camera::<M>((eye, target, up), (fovy, near, far)).map_err(|_| "camera")?,
                light: demo::light().map_err(|_| "light")?,
            };
            let result = frame(&mut ws, &scene, &options, self.count)?;
            (self.report)(name, f, result);
        }
        Ok(())
    }
}

/// The variant a target build renders (`--cfg scanline3d_variant="NAME"`, default `balanced`):
/// one per firmware image, so each is measured with only its own code, as a product would
/// carry it. The host renders every variant.
const BUILD_VARIANT: &str = if cfg!(scanline3d_variant = "fast") {
    "fast"
} else if cfg!(scanline3d_variant = "exact") {
    "exact"
} else if cfg!(scanline3d_variant = "default") {
    "default"
} else if cfg!(scanline3d_variant = "bits0") {
    "bits:0"
} else if cfg!(scanline3d_variant = "micromath") {
    "micromath"
} else if cfg!(scanline3d_variant = "narrowtransform") {
    "narrow-transform"
} else if cfg!(scanline3d_variant = "reciprocal") {
    "reciprocal"
} else if cfg!(scanline3d_variant = "narrownormals") {
    "narrow-normals"
} else if cfg!(scanline3d_variant = "depth16") {
    "depth16"
} else if cfg!(scanline3d_variant = "gouraudaffine") {
    "gouraud-affine"
} else if cfg!(scanline3d_variant = "gouraudsegments16") {
    "gouraud-segments16"
} else if cfg!(scanline3d_variant = "gouraudsegments8") {
    "gouraud-segments8"
} else if cfg!(scanline3d_variant = "gouraudperpixel") {
    "gouraud-per-pixel"
} else if cfg!(scanline3d_variant = "baked") {
    "baked"
} else {
    "balanced"
};

/// Whether this build renders variant `name` (a constant, so the others are not compiled in).
const fn renders(name: &str) -> bool {
    if cfg!(not(target_os = "none")) {
        return true;
    }
    let (a, b) = (name.as_bytes(), BUILD_VARIANT.as_bytes());
    if a.len() != b.len() {
        return false;
    }
    let mut i = 0;
    while i < a.len() {
        if a[i] != b[i] {
            return false;
        }
        i += 1;
    }
    true
}

/// The three presets, then `RenderOptions::default()` alone and with one knob changed (those
/// this build renders).
fn variants(r: &mut impl Renders) -> Result<(), &'static str> {
    use preset::{Balanced, Exact, Fast};
    use scanline3d::arithmetic::Setup;
    use scanline3d::arithmetic::{ExactDivision, Reciprocal};
    use scanline3d::arithmetic::{NarrowTransform, WideTransform};
    use scanline3d::math::{Libm, Micromath, NarrowNormals, WideNormals};
    type Math<P> = <P as Preset>::Math;
    type Arith<P> = <P as Preset>::Arithmetic;
    let default = RenderOptions::default();
    if renders(Fast::NAME) {
        r.variant::<Flat, 2, Arith<Fast>, Math<Fast>, Depth>(Fast::NAME, Fast::options())?;
    }
    if renders(Balanced::NAME) {
        r.variant::<Flat, 4, Arith<Balanced>, Math<Balanced>, Depth>(
            Balanced::NAME,
            Balanced::options(),
        )?;
    }
    if renders(Exact::NAME) {
        r.variant::<Flat, 8, Arith<Exact>, Math<Exact>, Depth>(Exact::NAME, Exact::options())?;
    }
    if renders("default") {
        r.variant::<Flat, 4, _, Libm, Depth>("default", default)?;
    }
    if renders("bits:0") {
        let bits0 = default.with_sub_pixel_bits::<0>();
        r.variant::<Flat, 0, _, Libm, Depth>("bits:0", bits0)?;
    }
    if renders("micromath") {
        r.variant::<Flat, 4, _, Micromath, Depth>("micromath", default)?;
    }
    if renders("narrow-transform") {
        let a = Setup::<NarrowTransform, ExactDivision, WideNormals>::default();
        r.variant::<Flat, 4, _, Libm, Depth>("narrow-transform", default.with_arithmetic(a))?;
    }
    if renders("reciprocal") {
        let a = Setup::<WideTransform, Reciprocal, WideNormals>::default();
        r.variant::<Flat, 4, _, Libm, Depth>("reciprocal", default.with_arithmetic(a))?;
    }
    if renders("narrow-normals") {
        let a = Setup::<WideTransform, ExactDivision, NarrowNormals>::default();
        r.variant::<Flat, 4, _, Libm, Depth>("narrow-normals", default.with_arithmetic(a))?;
    }
    if renders("depth16") {
        r.variant::<Flat, 4, _, Libm, Depth16>("depth16", default)?;
    }
    // The default drawing face colours lit ahead of time (`Unlit`: the demo's baked meshes,
    // the corpus scenes' `BAKED_MESH`), the same frames for static scenes. Built only when
    // asked for (`cargo xtask profile baked ...`), not on the host.
    if cfg!(scanline3d_variant = "baked") {
        r.variant::<Unlit, 4, _, Libm, Depth>("baked", default)?;
    }
    gouraud::<Affine>(r, "gouraud-affine")?;
    gouraud::<PerSegment<16>>(r, "gouraud-segments16")?;
    gouraud::<PerSegment<8>>(r, "gouraud-segments8")?;
    gouraud::<PerPixel>(r, "gouraud-per-pixel")?;
    Ok(())
}

/// The default with Gouraud shading interpolated by `I` (the demo only: the corpus carries no
/// vertex colours on firmware), if this build renders `name`.
fn gouraud<I: Interpolation>(r: &mut impl Renders, name: &'static str) -> Result<(), &'static str> {
    if renders(name) {
        r.variant::<Gouraud<I>, 4, _, scanline3d::math::Libm, Depth>(
            name,
            RenderOptions::default(),
        )?;
    }
    Ok(())
}

/// Every view of every corpus scene, when built with `--cfg scanline3d_corpus` and the file
/// `scanline3d_sim::export::corpus_source` wrote at `SCANLINE3D_CORPUS` (`cargo xtask tradeoff`
/// does both); `report(variant, scene, view, result)`.
#[cfg(scanline3d_corpus)]
mod corpus_views {
    use super::*;
    use scanline3d::scene::{Instance, Light, Transform};

    // MAX_VERTICES is used only with a vertex cache.
    #[allow(clippy::all, missing_docs, dead_code)]
    pub mod corpus {
        include!(env!("SCANLINE3D_CORPUS"));
    }

    /// A workspace for the largest corpus scene (with `--cfg scanline3d_vertex_cache`, a vertex
    /// cache for the largest mesh).
    type CorpusWs<Sh, Z> = Workspace<
        Rgb565,
        Sh,
        240,
        240,
        { corpus::MAX_TRIANGLES },
        { corpus::MAX_ACTIVE },
        1,
        Z,
        CORPUS_CACHE,
    >;

    #[cfg(not(scanline3d_vertex_cache))]
    const CORPUS_CACHE: usize = 0;
    #[cfg(scanline3d_vertex_cache)]
    const CORPUS_CACHE: usize = corpus::MAX_VERTICES;

    /// The mesh scene `s` draws with shading `Sh`: for `Unlit` (the `baked` variant), the
    /// face colours baked for the scene's light.
    fn mesh_for<Sh: Shading>(s: &corpus::CorpusScene) -> &'static scanline3d::scene::Mesh<'static> {
        #[cfg(scanline3d_variant = "baked")]
        if !Sh::LIT {
            return s.baked;
        }
        s.mesh
    }

    pub struct Views<'a, C, R> {
        pub count: &'a C,
        pub report: R,
    }

    impl<C: Fn() -> Counter, R: FnMut(&str, &str, usize, Frame)> Renders for Views<'_, C, R> {
        fn variant<Sh: Shading, const S: u32, A: Arithmetic, M: MathBackend, Z: DepthFormat>(
            &mut self,
            name: &'static str,
            options: RenderOptions<S, FrustumClip, A>,
        ) -> Result<(), &'static str> {
            let mut ws = fresh(|| CorpusWs::<Sh, Z>::new(Rgb565::new(0, 0, 0)));
            // A scene rendered alone (`cargo xtask profile VARIANT [cache] TARGET SCENE`, its
            // workspace sized for it) reports its workspace and the stack's peak, which holds
            // the workspace, the render call's stack and the firmware's own frames (no static
            // RAM); `cargo xtask scene-ram` takes the render call's share against a build
            // without it (`--cfg scanline3d_no_render`).
            #[cfg(all(target_os = "none", scanline3d_corpus_only))]
            let painted_bottom = measure::paint_stack();
            for s in &corpus::SCENES {
                let instances = [Instance {
                    mesh: mesh_for::<Sh>(s),
                    transform: Transform::IDENTITY,
                }];
                let (towards, ambient, diffuse) = s.light;
                let light = Light::new(towards, ambient, diffuse).map_err(|_| "light")?;
                let options = options.with_back_face_culling(s.cull_back_faces);
                for (k, (&view, &projection)) in s.views.iter().zip(s.projections).enumerate() {
                    let scene = Scene {
                        instances: &instances,
                        camera: camera::<M>(view, projection).map_err(|_| "camera")?,
                        light,
                    };
                    let result = frame(&mut ws, &scene, &options, self.count)?;
                    (self.report)(name, s.name, k, result);
                }
            }
            #[cfg(all(target_os = "none", scanline3d_corpus_only))]
            {
                let low_water = measure::stack_low_water();
                if low_water <= painted_bottom + 256 {
                    return Err("the render call's stack went below the painted stack");
                }
                semihosting::println!(
                    "summary corpus_workspace {} peak_stack {}",
                    CorpusWs::<Sh, Z>::BYTES,
                    &raw const measure::_stack_start as usize - low_water
                );
            }
            Ok(())
        }
    }
}

/// Host: the same frames, hashes only (`cargo xtask tradeoff` compares them with the targets').
#[cfg(not(target_os = "none"))]
struct Counter;
#[cfg(not(target_os = "none"))]
impl Counter {
    fn stop(self) -> u64 {
        0
    }
}

#[cfg(not(target_os = "none"))]
fn main() -> Result<(), &'static str> {
    variants(&mut Orbit {
        count: &|| Counter,
        report: |name: &str, frame, f: Frame| {
            println!(
                "variant {name} frame {frame} hash {:08x} complete {} bytes {:08x}",
                f.hash, f.complete, f.bytes
            )
        },
    })?;
    #[cfg(scanline3d_corpus)]
    {
        variants(&mut corpus_views::Views {
            count: &|| Counter,
            report: |name: &str, scene: &str, view, f: Frame| {
                println!(
                    "corpus {name} scene {scene} view {view} hash {:08x} complete {} bytes {:08x}",
                    f.hash, f.complete, f.bytes
                )
            },
        })?;
    }
    Ok(())
}

#[cfg(target_os = "none")]
#[path = "common/arch.rs"]
mod arch;
#[cfg(target_os = "none")]
#[allow(dead_code)] // the counter check, and the stack of a scene rendered alone
#[path = "common/measure.rs"]
mod measure;

/// Target: instructions between `start` and `stop` (`-icount shift=0`).
#[cfg(target_os = "none")]
struct Counter(arch::Mark);
#[cfg(target_os = "none")]
impl Counter {
    fn stop(self) -> u64 {
        arch::instructions(&self.0)
    }
}

#[cfg(target_os = "none")]
mod firmware {
    use super::*;
    use semihosting::println;

    fn run() -> Result<(), &'static str> {
        arch::start_counter()?;
        measure::calibrate()?;
        let mut complete = true;
        // `cargo xtask profile` with a scene renders that corpus scene alone.
        #[cfg(not(scanline3d_corpus_only))]
        {
            variants(&mut Orbit {
                count: &|| Counter(arch::start()),
                report: |name: &str, frame, f: Frame| {
                    complete &= f.complete;
                    println!(
                        "variant {} frame {} hash {:08x} complete {} instructions {} activated {} fragments {}",
                        name, frame, f.hash, f.complete, f.instructions, f.activated, f.fragments
                    )
                },
            })?;
        }
        #[cfg(scanline3d_corpus)]
        {
            variants(&mut corpus_views::Views {
                count: &|| Counter(arch::start()),
                report: |name: &str, scene: &str, view, f: Frame| {
                    complete &= f.complete;
                    println!(
                        "corpus {} scene {} view {} hash {:08x} complete {} instructions {} activated {} fragments {}",
                        name, scene, view, f.hash, f.complete, f.instructions, f.activated, f.fragments
                    )
                },
            })?;
        }
        // The one variant this image renders: its demo workspace.
        let workspace = if renders("depth16") {
            Ws::<Flat, Depth16>::BYTES
        } else if renders("gouraud-affine") {
            Ws::<Gouraud<Affine>, Depth>::BYTES
        } else if BUILD_VARIANT.starts_with("gouraud") {
            Ws::<Gouraud<PerPixel>, Depth>::BYTES
        } else {
            Ws::<Flat, Depth>::BYTES
        };
        println!("summary workspace {}", workspace);
        if complete {
            Ok(())
        } else {
            Err("a frame overflowed the workspace")
        }
    }

    pub fn main() -> ! {
        match run() {
            Ok(()) => semihosting::process::exit(0),
            Err(e) => {
                println!("error: {}", e);
                semihosting::process::exit(1)
            }
        }
    }

    #[panic_handler]
    fn panic(info: &core::panic::PanicInfo) -> ! {
        println!("panic: {}", info);
        semihosting::process::exit(1)
    }
}
