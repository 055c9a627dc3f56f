//! The example scene shared by the panel and window examples: a cube of half-size 1 as static
//! I16F16 data (it stays in flash), validated at compile time.

use embedded_graphics::pixelcolor::Rgb888;
use fixed::types::I16F16;
use scanline3d::scene::{Mesh, MeshColors, Vertex};

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

const fn face(r: u8, g: u8, b: u8) -> [Rgb888; 2] {
    [Rgb888::new(r, g, b), Rgb888::new(r, g, b)]
}

static CUBE_COLORS: [Rgb888; 12] = {
    let f = [
        face(230, 200, 60),
        face(60, 170, 220),
        face(220, 90, 120),
        face(120, 210, 110),
        face(240, 240, 235),
        face(150, 110, 220),
    ];
    let mut out = [Rgb888::new(0, 0, 0); 12];
    let mut i = 0;
    while i < 12 {
        out[i] = f[i / 2][i % 2];
        i += 1;
    }
    out
};

/// Validated at compile time: a bad index or colour count fails the build, not the board.
pub static CUBE: Mesh<'static> = match Mesh::new(
    &CUBE_VERTICES,
    &CUBE_TRIANGLES,
    MeshColors::PerFace(&CUBE_COLORS),
    None,
) {
    Ok(mesh) => mesh,
    Err(_) => panic!("invalid cube mesh"),
};
