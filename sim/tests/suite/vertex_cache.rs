//! The vertex cache changes speed, not pixels: every corpus view and the multi-instance demo
//! orbit, flat and Gouraud, at the default and the quickest arithmetic, render bit-identically
//! (pixels, depth and statistics) with and without a cache, and with one too small for the
//! scene (which falls back to the uncached path and says so).

use embedded_graphics::pixelcolor::Rgb888;
use scanline3d::arithmetic::Arithmetic;
use scanline3d::preset::{Fast, Preset};
use scanline3d::scene::Scene;
use scanline3d::sink::{FnSink, Row};
use scanline3d::{Depth, Flat, FrameStats, Gouraud, RenderOptions, Shading, Workspace};
use scanline3d_demo as demo;
use scanline3d_sim::corpus;

const W: usize = 160;
const H: usize = 120;
const TRIS: usize = 12288;
const ACTIVE: usize = 512;

type Plain<S> = Workspace<Rgb888, S, W, H, TRIS, ACTIVE, 8, Depth>;
type Cached<S> = Workspace<Rgb888, S, W, H, TRIS, ACTIVE, 8, Depth, 8192>;
const SMALL: usize = 7;
type TooSmall<S> = Workspace<Rgb888, S, W, H, TRIS, ACTIVE, 8, Depth, SMALL>;

/// Every pixel and depth of the frame, and its statistics.
struct Frame {
    pixels: Vec<Rgb888>,
    depth: Vec<Option<Depth>>,
    stats: FrameStats,
}

macro_rules! render_with {
    ($ws:ty, $scene:expr, $options:expr) => {{
        let mut ws: Box<$ws> = Box::new(<$ws>::new(Rgb888::new(1, 2, 3)));
        let (mut pixels, mut depth) = (Vec::new(), Vec::new());
        let mut sink = FnSink(|row: Row<'_, Rgb888>| -> Result<(), ()> {
            pixels.extend_from_slice(row.pixels);
            depth.extend((0..row.pixels.len()).map(|x| row.depth.get(x)));
            Ok(())
        });
        let stats = ws.render($scene, $options, &mut sink).expect("renders");
        Frame {
            pixels,
            depth,
            stats,
        }
    }};
}

/// Renders `scene` three ways and checks they agree; returns how many vertices were cached.
fn check<S: Shading, const SUB: u32, A: Arithmetic>(
    what: &str,
    scene: &Scene<'_>,
    options: &RenderOptions<SUB, scanline3d::clip::FrustumClip, A>,
) -> u32 {
    let plain = render_with!(Plain<S>, scene, options);
    let cached = render_with!(Cached<S>, scene, options);
    let small = render_with!(TooSmall<S>, scene, options);
    let vertices: usize = scene
        .instances
        .iter()
        .map(|i| i.mesh.vertices().len())
        .sum();
    assert_eq!(plain.stats.cached_vertices, 0, "{what}");
    assert_eq!(cached.stats.cached_vertices as usize, vertices, "{what}");
    // A cache too small for the scene is not used at all.
    let fits = vertices <= SMALL;
    assert_eq!(
        small.stats.cached_vertices as usize,
        if fits { vertices } else { 0 },
        "{what}"
    );
    for other in [&cached, &small] {
        assert!(plain.pixels == other.pixels, "{what}: pixels differ");
        assert!(plain.depth == other.depth, "{what}: depth differs");
        let stats = FrameStats {
            cached_vertices: 0,
            ..other.stats
        };
        assert_eq!(plain.stats, stats, "{what}");
    }
    cached.stats.cached_vertices
}

#[test]
fn cached_frames_equal_uncached_frames_on_the_corpus() {
    let (mut clipped, mut too_big) = (0, 0);
    corpus::for_each_view(
        |name, camera, spec| {
            spec.with_scene(|scene| {
                let default = RenderOptions::default().with_back_face_culling(spec.cull_back_faces);
                let fast = Fast::options().with_back_face_culling(spec.cull_back_faces);
                let what = format!("{name} camera {camera}");
                check::<Flat, 4, _>(&format!("{what} flat"), scene, &default);
                check::<Gouraud, 4, _>(&format!("{what} gouraud"), scene, &default);
                check::<Flat, 2, _>(&format!("{what} fast"), scene, &fast);
                let stats = render_with!(Plain<Flat>, scene, &default).stats;
                clipped += stats.clipped;
                let vertices: usize = scene
                    .instances
                    .iter()
                    .map(|i| i.mesh.vertices().len())
                    .sum();
                too_big += (vertices > SMALL) as u32;
            })
        },
        |_, _| {},
    )
    .unwrap();
    // The corpus exercises the cache's clipping path, not only whole triangles, and the
    // fallback of a cache too small for the scene.
    assert!(clipped > 0);
    assert!(too_big > 0);
}

#[test]
fn cached_frames_equal_uncached_frames_on_the_demo_orbit() {
    let instances = demo::instances();
    assert!(instances.len() > 1);
    for frame in 0..demo::ORBIT_FRAMES {
        let scene = demo::scene(&instances, frame, demo::ORBIT_FRAMES).unwrap();
        let cached = check::<Flat, 4, _>(
            &format!("demo frame {frame}"),
            &scene,
            &RenderOptions::default(),
        );
        assert!(cached > 0);
    }
}
