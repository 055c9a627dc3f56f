//! Precision trade-off firmware: the demo orbit rendered with one precision preset
//! (`scanline3d::preset`) or single-knob variation of the default, printing each frame's hash
//! and instructions. The variant is chosen at build time, so each firmware image carries only
//! its own code (`cargo rustc --example tradeoff -- --cfg 'scanline3d_variant="fast"'`; the
//! default is `balanced`). On the host the example renders every variant. `cargo xtask
//! tradeoff` builds and runs each variant on thumbv7em and thumbv6m and checks the hashes
//! against the host's.
//!
//! ```sh
//! cargo run --release --example tradeoff --target thumbv6m-none-eabi   # QEMU mps2-an385
//! cargo run --release --example tradeoff                               # host: hashes only
//! ```
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]

use embedded_graphics::pixelcolor::Rgb565;
use scanline3d::clip::FrustumClip;
use scanline3d::preset::{self, Arithmetic, Preset};
use scanline3d::scene::{Camera, Scene, SceneError};
use scanline3d::sink::HashSink;
use scanline3d::{demo, Flat, RenderOptions, Workspace};

/// The demo's panel workspace with room to spare: the approximate set-up of some variants moves
/// the camera slightly, so the exact capacities `sim analyze --demo` measured may not cover it.
type Ws = Workspace<Rgb565, Flat, 240, 240, 640, 80, 3>;

/// One frame's result.
struct Frame {
    hash: u32,
    /// Target only: the host has no instruction counter.
    #[cfg_attr(not(target_os = "none"), allow(dead_code))]
    instructions: u64,
    complete: bool,
}

/// Renders the orbit with `options` and cameras computed by `camera`, calling `report` per frame.
fn orbit<const S: u32, A: Arithmetic>(
    ws: &mut Ws,
    options: RenderOptions<S, FrustumClip, A>,
    camera: impl Fn(u32) -> Result<Camera, SceneError>,
    count: &impl Fn() -> Counter,
    mut report: impl FnMut(u32, Frame),
) -> Result<(), &'static str> {
    let instances = demo::instances();
    for frame in 0..demo::ORBIT_FRAMES {
        let scene = Scene {
            instances: &instances,
            camera: camera(frame).map_err(|_| "camera")?,
            light: demo::light().map_err(|_| "light")?,
        };
        let mut sink = HashSink::new();
        let counter = count();
        let stats = ws
            .render(&scene, &options, &mut sink)
            .map_err(|_| "render")?;
        let instructions = counter.stop();
        report(
            frame,
            Frame {
                hash: sink.hash(),
                instructions,
                complete: stats.is_complete(),
            },
        );
    }
    Ok(())
}

fn preset_camera<P: Preset>(frame: u32) -> Result<Camera, SceneError> {
    let (eye, target, up, fovy, near, far) = demo::camera_parameters(frame, demo::ORBIT_FRAMES);
    P::camera(eye, target, up, fovy, near, far)
}

fn math_camera<M: scanline3d::math::MathBackend>(frame: u32) -> Result<Camera, SceneError> {
    let (eye, target, up, fovy, near, far) = demo::camera_parameters(frame, demo::ORBIT_FRAMES);
    Camera::look_at_with::<M>(eye, target, up)?.perspective_with::<M>(fovy, near, far)
}

/// The variant a target build renders (`--cfg scanline3d_variant="NAME"`, default `balanced`):
/// one per firmware image, so each is measured with only its own code, as a product would
/// carry it. The host renders every variant.
const BUILD_VARIANT: &str = if cfg!(scanline3d_variant = "fast") {
    "fast"
} else if cfg!(scanline3d_variant = "exact") {
    "exact"
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

/// The three presets, then the default with one knob changed (those this build renders).
fn variants(
    ws: &mut Ws,
    count: &impl Fn() -> Counter,
    mut report: impl FnMut(&str, u32, Frame),
) -> Result<(), &'static str> {
    use preset::Setup;
    use preset::{Balanced, Exact, Fast};
    use scanline3d::math::{Libm, Micromath, NarrowNormals, WideNormals};
    use scanline3d::project::{ExactDivision, Reciprocal};
    use scanline3d::vertex::{NarrowTransform, WideTransform};
    const FAST: bool = renders(Fast::NAME);
    const BALANCED: bool = renders(Balanced::NAME);
    const EXACT: bool = renders(Exact::NAME);
    const BITS0: bool = renders("bits:0");
    const MICROMATH: bool = renders("micromath");
    const NARROW_TRANSFORM: bool = renders("narrow-transform");
    const RECIPROCAL: bool = renders("reciprocal");
    const NARROW_NORMALS: bool = renders("narrow-normals");
    let default = RenderOptions::default();
    if FAST {
        let camera = preset_camera::<Fast>;
        orbit(ws, Fast::options(), camera, count, |f, l| {
            report(Fast::NAME, f, l)
        })?;
    }
    if BALANCED {
        let camera = preset_camera::<Balanced>;
        orbit(ws, Balanced::options(), camera, count, |f, l| {
            report(Balanced::NAME, f, l)
        })?;
    }
    if EXACT {
        let camera = preset_camera::<Exact>;
        orbit(ws, Exact::options(), camera, count, |f, l| {
            report(Exact::NAME, f, l)
        })?;
    }
    if BITS0 {
        let bits0 = default.with_sub_pixel_bits::<0>();
        orbit(ws, bits0, math_camera::<Libm>, count, |f, l| {
            report("bits:0", f, l)
        })?;
    }
    if MICROMATH {
        orbit(ws, default, math_camera::<Micromath>, count, |f, l| {
            report("micromath", f, l)
        })?;
    }
    let libm = math_camera::<Libm>;
    if NARROW_TRANSFORM {
        let a = Setup::<NarrowTransform, ExactDivision, WideNormals>::default();
        orbit(ws, default.with_arithmetic(a), libm, count, |f, l| {
            report("narrow-transform", f, l)
        })?;
    }
    if RECIPROCAL {
        let a = Setup::<WideTransform, Reciprocal, WideNormals>::default();
        orbit(ws, default.with_arithmetic(a), libm, count, |f, l| {
            report("reciprocal", f, l)
        })?;
    }
    if NARROW_NORMALS {
        let a = Setup::<WideTransform, ExactDivision, NarrowNormals>::default();
        orbit(ws, default.with_arithmetic(a), libm, count, |f, l| {
            report("narrow-normals", f, l)
        })?;
    }
    Ok(())
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
    let mut ws = Box::new(Ws::new(Rgb565::new(0, 0, 0)));
    variants(&mut ws, &|| Counter, |name, frame, f| {
        println!(
            "variant {name} frame {frame} hash {:08x} complete {}",
            f.hash, f.complete
        )
    })
}

#[cfg(target_os = "none")]
#[path = "common/arch.rs"]
mod arch;
#[cfg(target_os = "none")]
#[allow(dead_code)] // only the counter check is used here
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
        let mut ws = Ws::new(Rgb565::new(0, 0, 0));
        let mut complete = true;
        variants(&mut ws, &|| Counter(arch::start()), |name, frame, f| {
            complete &= f.complete;
            println!(
                "variant {} frame {} hash {:08x} complete {} instructions {}",
                name, frame, f.hash, f.complete, f.instructions
            )
        })?;
        println!("summary workspace {}", Ws::BYTES);
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
