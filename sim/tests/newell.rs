//! Newell's depth sort (`scanline3d::resolve::NewellWorkspace`) against the f64
//! reference on the whole corpus (240×240, every camera, 4 and 8 sub-pixel bits), with the
//! thresholds of `hsr.rs` for exact methods: zero real mismatches, at most 0.1 % id mismatches
//! at 8 sub-pixel bits, no depth beyond the bound (the method keeps no depth, so the depth
//! image is NaN over surfaces and the metrics skip it). Printed per scene with
//! `cargo test --release -p scanline3d-sim --test newell -- --nocapture`.

use embedded_graphics::pixelcolor::{Rgb888, RgbColor};
use scanline3d::resolve::NewellWorkspace;
use scanline3d::sink::{FnSink, Row, TriangleId};
use scanline3d::{Flat, RenderOptions};
use scanline3d_sim::corpus;
use scanline3d_sim::metrics::{self, ErrorBound};
use scanline3d_sim::reference::Image;
use scanline3d_sim::scene::{LightSpec, SceneSpec};
use std::convert::Infallible;

const W: usize = 240;
const H: usize = 240;
/// Room for every corpus scene's pieces, and for the pieces crossing one row.
const PIECES: usize = 16384;
const ACTIVE: usize = 1024;

type ColorWs = NewellWorkspace<Rgb888, Flat, W, H, PIECES, ACTIVE>;
type IdWs = NewellWorkspace<TriangleId, Flat, W, H, PIECES, ACTIVE>;

/// Renders `spec` through the Newell workspaces into id, depth (NaN over surfaces) and
/// colour images, as `sim` renders its other methods.
fn render<const S: u32>(spec: &SceneSpec, color_ws: &mut ColorWs, id_ws: &mut IdWs) -> Image {
    let mut image = Image {
        width: W,
        height: H,
        ids: vec![-1; W * H],
        depth: vec![f32::INFINITY; W * H],
        color: vec![[0; 3]; W * H],
    };
    let options = RenderOptions::default()
        .with_back_face_culling(spec.cull_back_faces)
        .with_sub_pixel_bits::<S>();
    spec.with_scene(|scene| {
        let mut sink = FnSink(|row: Row<'_, Rgb888>| -> Result<(), Infallible> {
            for (x, c) in row.pixels.iter().enumerate() {
                image.color[row.y as usize * W + x] = [c.r(), c.g(), c.b()];
            }
            Ok(())
        });
        color_ws.render(scene, &options, &mut sink).unwrap();
        let mut sink = FnSink(|row: Row<'_, TriangleId>| -> Result<(), Infallible> {
            assert!(row.depth.is_empty());
            for (x, id) in row.pixels.iter().enumerate() {
                let at = row.y as usize * W + x;
                image.ids[at] = id.0;
                image.depth[at] = if id.0 >= 0 { f32::NAN } else { f32::INFINITY };
            }
            Ok(())
        });
        id_ws.render(scene, &options, &mut sink).unwrap();
    })
    .unwrap();
    image
}

fn check_corpus() {
    let mut color_ws: Box<ColorWs> = Box::new(ColorWs::new(Rgb888::BLACK));
    let mut id_ws: Box<IdWs> = Box::new(IdWs::new(TriangleId::NONE));
    let mut failures = Vec::new();
    for scene in corpus::all() {
        for (k, camera) in scene.cameras.iter().enumerate() {
            let spec = SceneSpec::single(
                scene.mesh.clone(),
                *camera,
                LightSpec::default(),
                scene.cull_back_faces,
            );
            let reference = spec.reference().unwrap();
            let ref_image = reference.render(W, H);
            for sub_bits in [4, 8] {
                let image = match sub_bits {
                    4 => render::<4>(&spec, &mut color_ws, &mut id_ws),
                    _ => render::<8>(&spec, &mut color_ws, &mut id_ws),
                };
                // The span z-buffer's image of the same scene: Newell's differs only where two
                // surfaces meet (split seams, depth rounding), which the reference explains.
                let zbuffer = spec.render_fixed(W, H, sub_bits).unwrap().image;
                let bound = ErrorBound {
                    sub_bits,
                    max_model_coord: spec.max_model_coord(),
                    focal_px: reference.camera.focal_px(H),
                };
                let m = metrics::compare(&image, &ref_image, &reference, &bound);
                let what = format!("{} cam {k} S={sub_bits} newell", scene.name);
                let differ = (image.ids.iter().zip(&zbuffer.ids))
                    .filter(|(a, b)| a != b)
                    .count();
                println!(
                    "{what:40} {:5} id mismatches ({:.3} %), real {}, {differ} ids differ from the span z-buffer",
                    m.id_mismatches,
                    m.id_mismatch_percent(),
                    m.real
                );
                if m.real > 0 {
                    failures.push(format!("{what}: {} real mismatches", m.real));
                }
                if sub_bits == 8 && m.id_mismatch_percent() > 0.1 {
                    let pc = m.id_mismatch_percent();
                    failures.push(format!("{what}: {pc:.3} % id mismatches"));
                }
                if m.depth_beyond_bound > 0 {
                    let n = m.depth_beyond_bound;
                    failures.push(format!("{what}: {n} pixels beyond the depth bound"));
                }
                if differ * 1000 > W * H {
                    failures.push(format!(
                        "{what}: {differ} ids differ from the span z-buffer"
                    ));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

#[test]
fn newell_against_the_reference() {
    // The workspaces are built by value, which in debug builds goes through the stack.
    std::thread::Builder::new()
        .stack_size(256 << 20)
        .spawn(check_corpus)
        .unwrap()
        .join()
        .unwrap();
}
