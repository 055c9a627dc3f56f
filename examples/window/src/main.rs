//! scanline3d on the desktop: a spinning cube rendered row by row into an
//! `embedded-graphics-simulator` window, through the same `DrawTargetSink` a firmware would
//! use with a real `DrawTarget`.
//!
//! ```sh
//! cd examples/window
//! cargo run --release --features window   # needs SDL2 (Debian/Ubuntu: apt install libsdl2-dev)
//! cargo run --release                     # no SDL: renders one frame headless and says how to run
//! ```
//!
//! Close the window, or press Esc or Q, to quit. `EG_SIMULATOR_DUMP=frame.png` (a variable of
//! the simulator) saves the first frame as a PNG and exits, with no window.
//!
//! The `window` feature is off by default so that building this crate, like the repository's
//! tests, never needs SDL.

use embedded_graphics::pixelcolor::{Rgb565, Rgb888};
use fixed::types::I16F16;
use scanline3d::scene::{Camera, Instance, Light, Mesh, MeshColors, Scene, Transform, Vertex};
use scanline3d::{Config, Flat, Settings, Storage};

/// Target size (the panel example's ST7789).
const W: usize = 240;
const H: usize = 240;

// ---- The scene: a cube of half-size 1 as static I16F16 data, as a firmware would keep it. ----

const P: I16F16 = I16F16::ONE;
const N: I16F16 = I16F16::NEG_ONE;

/// Corner `i` has x, y, z negative or positive by bits 0, 1, 2 of `i`.
static CUBE_VERTICES: [Vertex; 8] = [
    [N, N, N],
    [P, N, N],
    [N, P, N],
    [P, P, N],
    [N, N, P],
    [P, N, P],
    [N, P, P],
    [P, P, P],
];

/// Two triangles per face, counter-clockwise seen from outside (back faces are culled).
static CUBE_TRIANGLES: [[u16; 3]; 12] = [
    [4, 5, 7], // +z
    [4, 7, 6],
    [0, 2, 3], // -z
    [0, 3, 1],
    [1, 3, 7], // +x
    [1, 7, 5],
    [0, 4, 6], // -x
    [0, 6, 2],
    [2, 6, 7], // +y
    [2, 7, 3],
    [0, 1, 5], // -y
    [0, 5, 4],
];

/// One colour per face, given for both of its triangles.
static CUBE_COLORS: [Rgb888; 12] = {
    let faces = [
        Rgb888::new(230, 200, 60),
        Rgb888::new(60, 170, 220),
        Rgb888::new(220, 90, 120),
        Rgb888::new(120, 210, 110),
        Rgb888::new(240, 240, 235),
        Rgb888::new(150, 110, 220),
    ];
    let mut out = [Rgb888::new(0, 0, 0); 12];
    let mut i = 0;
    while i < 12 {
        out[i] = faces[i / 2];
        i += 1;
    }
    out
};

/// Validated at compile time: a bad index or colour count fails the build.
static CUBE: Mesh<'static> = match Mesh::new(
    &CUBE_VERTICES,
    &CUBE_TRIANGLES,
    MeshColors::PerFace(&CUBE_COLORS),
    None,
) {
    Ok(mesh) => mesh,
    Err(_) => panic!("invalid cube mesh"),
};

const BACKGROUND: Rgb565 = Rgb565::new(3, 7, 6);

/// Room for all 12 triangles (even with culling off) and every one crossing a row: about 3 KB.
type Ws = Storage<Cfg, W, H, 12, 12>;
/// RGB565 rows, flat shading, the library's reference precision.
type Cfg = Settings<Rgb565, Flat>;

/// Where the animation starts: a pose that shows three faces (the headless frame and the first
/// window frame).
const START_SECONDS: f32 = 1.0;

/// The cube's pose `seconds` into the animation: one 24 s loop, so the angles stay small.
fn spin(seconds: f32) -> Transform {
    let turn = core::f32::consts::TAU * (seconds % 24.0) / 24.0;
    Transform::rotation_y(3.0 * turn).then_after(&Transform::rotation_x(2.0 * turn))
}

/// Camera and light, fixed for the whole animation.
fn view() -> Result<(Camera, Light), scanline3d::scene::SceneError> {
    let camera = Cfg::camera([0.0, 0.0, 5.0], [0.0; 3], [0.0, 1.0, 0.0], 50.0, 0.5, 20.0)?;
    Ok((camera, Light::new([-0.4, 0.7, 0.6], 0.25, 0.75)?))
}

/// Without SDL: one frame, streamed into a closure that counts what it would send, so this
/// build still exercises the scene.
#[cfg(not(feature = "window"))]
fn main() -> Result<(), Box<dyn std::error::Error>> {
    use scanline3d::sink::{FnSink, Row};

    let (camera, light) = view()?;
    let instances = [Instance {
        mesh: &CUBE,
        transform: spin(START_SECONDS),
    }];
    let scene = Scene::new(&instances, camera, light)?;
    let mut ws = Ws::new(BACKGROUND);
    let (mut rows, mut lit) = (0, 0);
    let mut sink = FnSink(
        |row: Row<'_, Rgb565>| -> Result<(), std::convert::Infallible> {
            rows += 1;
            lit += row.pixels.iter().filter(|p| **p != BACKGROUND).count();
            Ok(())
        },
    );
    let stats = ws.render(&scene, &mut sink)?;
    println!(
        "rendered one {W}x{H} frame headless: {rows} rows, {lit} cube pixels, {} of 12 triangles drawn",
        stats.activated
    );
    println!("to watch it spin in a window (needs SDL2, e.g. apt install libsdl2-dev):");
    println!("  cargo run --release --features window");
    Ok(())
}

#[cfg(feature = "window")]
fn main() -> Result<(), Box<dyn std::error::Error>> {
    use embedded_graphics::prelude::Size;
    use embedded_graphics_simulator::{
        sdl2::Keycode, OutputSettingsBuilder, SimulatorDisplay, SimulatorEvent, Window,
    };
    use scanline3d::sink::DrawTargetSink;
    use std::time::Instant;

    let (camera, light) = view()?;
    let mut ws = Ws::new(BACKGROUND);
    let mut display = SimulatorDisplay::<Rgb565>::new(Size::new(W as u32, H as u32));
    // Scaled up so the pixels are visible; max_fps paces the loop inside `update`.
    let settings = OutputSettingsBuilder::new().scale(3).max_fps(60).build();
    let mut window = Window::new("scanline3d: spinning cube", &settings);
    let start = Instant::now();

    loop {
        let instances = [Instance {
            mesh: &CUBE,
            transform: spin(START_SECONDS + start.elapsed().as_secs_f32()),
        }];
        let scene = Scene::new(&instances, camera, light)?;
        // Every row is sent, background included, so the previous frame needs no clearing.
        ws.render(&scene, &mut DrawTargetSink::new(&mut display))?;
        window.update(&display);

        for event in window.events() {
            match event {
                SimulatorEvent::Quit
                | SimulatorEvent::KeyDown {
                    keycode: Keycode::Escape | Keycode::Q,
                    ..
                } => return Ok(()),
                _ => {}
            }
        }
    }
}
