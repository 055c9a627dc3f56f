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

use embedded_graphics::pixelcolor::Rgb565;
use scanline3d::scene::{Camera, Instance, Light, Scene, Transform};
use scanline3d::{Config, Flat, Settings, Storage};

/// Target size (the panel example's ST7789).
const W: usize = 240;
const H: usize = 240;

// The scene: a cube (shared with the panel example).
#[path = "../../shared/cube.rs"]
mod cube;
use cube::CUBE;

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
