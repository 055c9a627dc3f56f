//! Exact pixel patterns, checked with embedded-graphics' MockDisplay (which fails on overdraw).

use crate::common;

use common::*;
use embedded_graphics::mock_display::MockDisplay;
use embedded_graphics::pixelcolor::{BinaryColor, Rgb565, Rgb888, RgbColor};
use embedded_graphics::prelude::*;
use scanline3d::raster::for_each_span;
use scanline3d::scene::{Camera, Instance, Light, Mesh, MeshColors, Scene, Transform};
use scanline3d::sink::{DrawTargetSink, OrderedDither};
use scanline3d::{Flat, RenderOptions, Workspace};

/// Draws the spans of sub-pixel triangles (4 bits) in the given colours.
fn draw(tris: &[([(f64, f64); 3], Rgb565)]) -> MockDisplay<Rgb565> {
    let mut display = MockDisplay::new();
    for &(v, color) in tris {
        let v = v.map(|(x, y)| ((x * 16.0) as i32, (y * 16.0) as i32));
        for_each_span::<4>(v, 8, 8, |r, x0, x1| {
            for c in x0..x1 {
                Pixel(Point::new(c, r), color).draw(&mut display).unwrap();
            }
        });
    }
    display
}

#[test]
fn shared_vertical_edge_through_centres_goes_to_the_right_triangle() {
    // A diamond split by the vertical line x = 2.5, which passes through column 2's centres.
    let left = [(2.5, 0.5), (2.5, 4.5), (0.5, 2.5)];
    let right = [(2.5, 0.5), (4.5, 2.5), (2.5, 4.5)];
    let display = draw(&[(left, Rgb565::RED), (right, Rgb565::GREEN)]);
    // The top vertex's centre (2, 0) lies on a right edge of both triangles: uncovered.
    display.assert_pattern(&[
        "     ", //
        " RG  ", "RRGG ", " RG  ",
    ]);
}

#[test]
fn shared_horizontal_edge_through_centres_goes_to_the_lower_triangle() {
    // A diamond split by the horizontal line y = 2.5 through row 2's centres.
    let upper = [(2.5, 0.5), (4.5, 2.5), (0.5, 2.5)];
    let lower = [(0.5, 2.5), (4.5, 2.5), (2.5, 4.5)];
    let display = draw(&[(upper, Rgb565::RED), (lower, Rgb565::GREEN)]);
    // Row 2's centres are on the upper triangle's bottom edge and the lower one's top edge;
    // (4, 2) is the lower triangle's right vertex: excluded.
    display.assert_pattern(&[
        "     ", //
        " RR  ", "GGGG ", " GG  ",
    ]);
}

#[test]
fn vertex_on_centre_and_sliver() {
    // A one-pixel-wide sliver from (1.5, 0.2) to (1.9, 5.8): covers column 1 where the centre
    // x = 1.5 lies inside.
    let sliver = [(1.5, 0.2), (1.9, 5.8), (1.2, 5.8)];
    let display = draw(&[(sliver, Rgb565::BLUE)]);
    display.assert_pattern(&[" B"; 6]);
}

fn square_scene<'a>(mesh: &'a Mesh<'a>, instances: &'a mut [Instance<'a>; 1]) -> Scene<'a> {
    instances[0] = Instance {
        mesh,
        transform: Transform::IDENTITY,
    };
    Scene {
        instances: &instances[..],
        // At distance 1 with 90° the plane z = 0 spans [-1, 1]² onto the whole 8×8 screen.
        camera: Camera::look_at([0.0, 0.0, 1.0], [0.0; 3], [0.0, 1.0, 0.0])
            .unwrap()
            .perspective(90.0, 0.5, 10.0)
            .unwrap(),
        light: Light::new([0.0, 0.0, 1.0], 1.0, 0.0).unwrap(),
    }
}

#[test]
fn full_pipeline_square_split_on_the_diagonal() {
    let verts = [
        [-1.0, -1.0, 0.0],
        [1.0, -1.0, 0.0],
        [1.0, 1.0, 0.0],
        [-1.0, 1.0, 0.0],
    ]
    .map(vert);
    let tris = [[0u16, 1, 2], [0, 2, 3]];
    let colors = [Rgb888::RED, Rgb888::GREEN];
    let mesh = Mesh::new(&verts, &tris, MeshColors::PerFace(&colors), None).unwrap();
    let mut inst = [Instance {
        mesh: &mesh,
        transform: Transform::IDENTITY,
    }];
    let scene = square_scene(&mesh, &mut inst);
    let mut display = MockDisplay::<Rgb565>::new();
    let mut ws: Workspace<Rgb565, Flat, 8, 8, 4, 4> = Workspace::new(Rgb565::BLACK);
    let stats = ws
        .render(
            &scene,
            &RenderOptions::default(),
            &mut DrawTargetSink::new(&mut display),
        )
        .unwrap();
    // The diagonal (c + r = 7 centres) is the red triangle's left edge: red owns it.
    display.assert_pattern(&[
        "GGGGGGGR", //
        "GGGGGGRR", "GGGGGRRR", "GGGGRRRR", "GGGRRRRR", "GGRRRRRR", "GRRRRRRR", "RRRRRRRR",
    ]);
    assert_eq!(
        (stats.fragments, stats.pixels_written, stats.activated),
        (64, 64, 2)
    );
}

#[test]
fn back_faces_are_culled_only_when_asked() {
    // Wound clockwise as seen from the camera: a back face.
    let verts = [[-1.0, -1.0, 0.0], [1.0, 1.0, 0.0], [1.0, -1.0, 0.0]].map(vert);
    let tris = [[0u16, 1, 2]];
    let mesh = Mesh::new(&verts, &tris, MeshColors::Uniform(Rgb888::WHITE), None).unwrap();
    let mut inst = [Instance {
        mesh: &mesh,
        transform: Transform::IDENTITY,
    }];
    let scene = square_scene(&mesh, &mut inst);
    let mut ws: Workspace<BinaryColor, Flat, 8, 8, 4, 4> = Workspace::new(BinaryColor::Off);
    let mut display = MockDisplay::new();
    let stats = ws
        .render(
            &scene,
            &RenderOptions::default(),
            &mut DrawTargetSink::new(&mut display),
        )
        .unwrap();
    assert_eq!((stats.culled, stats.fragments), (1, 0));
    let mut display = MockDisplay::new();
    let keep = RenderOptions::default().with_back_face_culling(false);
    let stats = ws
        .render(&scene, &keep, &mut DrawTargetSink::new(&mut display))
        .unwrap();
    assert_eq!(stats.culled, 0);
    // The lower-right half, diagonal included (it is this triangle's left edge).
    display.assert_pattern(&[
        ".......#", //
        "......##", ".....###", "....####", "...#####", "..######", ".#######", "########",
    ]);
}

#[test]
fn ordered_dither_on_a_monochrome_target() {
    // A uniform grey square at 50 %: the 4×4 Bayer pattern shows through, half the pixels on.
    let verts = [
        [-1.0, -1.0, 0.0],
        [1.0, -1.0, 0.0],
        [1.0, 1.0, 0.0],
        [-1.0, 1.0, 0.0],
    ]
    .map(vert);
    let tris = [[0u16, 1, 2], [0, 2, 3]];
    let mesh = Mesh::new(
        &verts,
        &tris,
        MeshColors::Uniform(Rgb888::new(128, 128, 128)),
        None,
    )
    .unwrap();
    let mut inst = [Instance {
        mesh: &mesh,
        transform: Transform::IDENTITY,
    }];
    let scene = square_scene(&mesh, &mut inst);
    let mut ws: Workspace<embedded_graphics::pixelcolor::Gray8, Flat, 8, 8, 4, 4> =
        Workspace::new(embedded_graphics::pixelcolor::Gray8::BLACK);
    let mut display = MockDisplay::<BinaryColor>::new();
    ws.render(
        &scene,
        &RenderOptions::default(),
        &mut OrderedDither::new(&mut display),
    )
    .unwrap();
    display.assert_pattern(&[
        "#.#.#.#.", //
        ".#.#.#.#", "#.#.#.#.", ".#.#.#.#", "#.#.#.#.", ".#.#.#.#", "#.#.#.#.", ".#.#.#.#",
    ]);
}
