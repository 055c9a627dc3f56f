//! The lean firmware, shared by `lean_minimal`, `lean_full`, `lean_baseline` and `lean_bsp`: renders every
//! view of the exported scene (`examples/lean/scene.rs`, written by `sim export`) into a hashing
//! panel model, with the workspace sized by the exported budget. The shading model and the
//! clipping stage are type parameters, so each example carries only the code its choice needs.

use crate::arch;
use crate::measure::{self, _stack_start};
use crate::scene;
use embedded_graphics::pixelcolor::Rgb565;
use scanline3d::clip::Clipping;
use scanline3d::scene::{Camera, Instance, Light, Scene, Transform};
use scanline3d::sink::HashSink;
use scanline3d::{FrameStats, RenderOptions, Shading};
use semihosting::println;

struct Line {
    hash: u32,
    instructions: u32,
    complete: bool,
    unclipped: u32,
}

fn scene_for<'a>(view: usize, instances: &'a [Instance<'a>]) -> Result<Scene<'a>, &'static str> {
    let (eye, target, up) = *scene::VIEWS.get(view).ok_or("view")?;
    let (fovy, near, far) = scene::PROJECTION;
    let (towards, ambient, diffuse) = scene::LIGHT;
    Ok(Scene {
        instances,
        camera: Camera::look_at(eye, target, up)
            .and_then(|v| v.perspective(fovy, near, far))
            .map_err(|_| "camera")?,
        light: Light::new(towards, ambient, diffuse).map_err(|_| "light")?,
    })
}

/// Renders (or, with `RENDER` false, only builds) every view with the exported budget's
/// span z-buffer workspace. Without rendering the program is the same minus the renderer, so
/// the difference in size between a rendering build and a non-rendering one is the renderer's.
pub fn run<S: Shading, C: Clipping, const RENDER: bool>(
    name: &str,
    clipping: C,
) -> Result<(), &'static str> {
    type Ws<S> = scene::SceneWorkspace<Rgb565, S>;
    run_with::<C, _, RENDER>(
        name,
        clipping,
        Ws::<S>::BYTES,
        || Ws::<S>::new(Rgb565::new(0, 0, 0)),
        |ws, scene, options, sink| ws.render(scene, options, sink).map_err(|_| "render"),
    )
}

/// Renders every view with the workspace `new` makes (`workspace` bytes) and `render`, and
/// prints each view's hash and instruction count, then the variant's memory.
pub fn run_with<C: Clipping, W, const RENDER: bool>(
    name: &str,
    clipping: C,
    workspace: usize,
    new: impl FnOnce() -> W,
    mut render: impl FnMut(
        &mut W,
        &Scene<'_>,
        &RenderOptions<4, C>,
        &mut HashSink,
    ) -> Result<FrameStats, &'static str>,
) -> Result<(), &'static str> {
    arch::start_counter()?;
    measure::calibrate()?;
    let options = RenderOptions::default()
        .with_back_face_culling(scene::CULL_BACK_FACES)
        .with_clipping(clipping);
    let instances = [Instance {
        mesh: &scene::MESH,
        transform: Transform::IDENTITY,
    }];
    let stack_top = &raw const _stack_start as usize;
    measure::paint_stack();
    let mut lines: [Option<Line>; scene::VIEWS.len()] = core::array::from_fn(|_| None);
    {
        let mut ws = new();
        for (view, line) in lines.iter_mut().enumerate() {
            let scene = scene_for(view, &instances)?;
            let mut sink = HashSink::new();
            let mark = arch::start();
            let stats = if RENDER {
                render(&mut ws, &scene, &options, &mut sink)?
            } else {
                core::hint::black_box((&scene, &options, &mut ws, &mut sink));
                Default::default()
            };
            let instructions = arch::instructions(&mark) as u32;
            *line = Some(Line {
                hash: sink.hash(),
                instructions,
                complete: stats.is_complete(),
                unclipped: stats.unclipped,
            });
        }
    }
    let peak_stack = stack_top - measure::stack_low_water();
    for (view, line) in lines.iter().enumerate() {
        let l = line.as_ref().ok_or("missing view")?;
        if RENDER && !l.complete {
            return Err("capacity exceeded: the budget does not cover this view");
        }
        println!(
            "view {} hash {:08x} instructions {} unclipped {}",
            view, l.hash, l.instructions, l.unclipped
        );
    }
    println!(
        "summary variant {} peak_stack {} static_ram {} workspace {}",
        name,
        peak_stack,
        measure::static_ram(),
        workspace
    );
    Ok(())
}

/// Exits QEMU with status 0, or prints the error and exits with 1. (The demo firmware has its
/// own copy: sharing one through `common/measure.rs` changed how LTO inlined the demo's render
/// path and cost 9.5 % more instructions per frame on thumbv7em.)
pub fn exit(result: Result<(), &'static str>) -> ! {
    match result {
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
