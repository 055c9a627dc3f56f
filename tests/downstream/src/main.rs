//! A minimal firmware that renders one triangle into rows, as a new user's first program would.
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use embedded_graphics::pixelcolor::{Rgb565, Rgb888};
use fixed::types::I16F16;
use scanline3d::scene::{Instance, Light, Mesh, MeshColors, Scene, Transform, Vertex};
use scanline3d::sink::{FnSink, Row};
use scanline3d::{Config, Flat, Settings, Storage};

type Cfg = Settings<Rgb565, Flat>;

const ONE: I16F16 = I16F16::ONE;
static VERTICES: [Vertex; 3] = [
    [I16F16::NEG_ONE, I16F16::NEG_ONE, I16F16::ZERO],
    [ONE, I16F16::NEG_ONE, I16F16::ZERO],
    [I16F16::ZERO, ONE, I16F16::ZERO],
];
static TRIANGLES: [[u16; 3]; 1] = [[0, 1, 2]];
static MESH: Mesh<'static> = match Mesh::new(
    &VERTICES,
    &TRIANGLES,
    MeshColors::Uniform(Rgb888::new(255, 128, 0)),
    None,
) {
    Ok(mesh) => mesh,
    Err(_) => panic!("invalid mesh"),
};

#[entry]
fn main() -> ! {
    let mut lit = 0u32;
    let instances = [Instance {
        mesh: &MESH,
        transform: Transform::IDENTITY,
    }];
    let scene = Cfg::camera([0.0, 0.0, 3.0], [0.0; 3], [0.0, 1.0, 0.0], 60.0, 0.1, 50.0)
        .and_then(|camera| Scene::new(&instances, camera, Light::new([0.3, 0.5, 1.0], 0.2, 0.8)?));
    let mut ws: Storage<Cfg, 64, 48, 4, 4> = Storage::new(Rgb565::new(0, 0, 0));
    let mut panel = FnSink(|row: Row<'_, Rgb565>| -> Result<(), ()> {
        lit += row.pixels.iter().filter(|p| **p != Rgb565::new(0, 0, 0)).count() as u32;
        Ok(())
    });
    if let Ok(scene) = scene {
        let _ = ws.render(&scene, &mut panel);
    }
    loop {
        cortex_m::asm::nop();
        core::hint::black_box(lit);
    }
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    loop {}
}
