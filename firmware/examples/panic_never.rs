//! Link-time proof that the render path cannot panic: this firmware renders the demo scene, and
//! its panic handler calls a function that does not exist. If any panic remains reachable after
//! optimisation, linking fails with an undefined symbol.
//!
//! ```sh
//! cargo build --release --example panic_never --target thumbv7em-none-eabihf
//! cargo build --release --example panic_never --target thumbv6m-none-eabi
//! cargo build --release --example panic_never --target riscv32imc-unknown-none-elf
//! ```
//!
//! `cargo xtask test` builds it for all three targets with the `firmware` profile, and for
//! thumbv6m again with the size-optimised `lean` one (`opt-level = "z"`, which leaves closures
//! out of line, and with them bounds checks, that `opt-level = 3` inlines and proves away; the
//! other two targets link with it too: `cargo build -p scanline3d-firmware --profile lean
//! --example panic_never --target …`). It covers what a firmware frame runs:
//! scene and camera set-up, the vertex stage, clipping, projection, bucketing, the edge walk, the
//! span z-buffer and the row sink, with the default arithmetic and the fast preset's narrow one,
//! and every other hidden-surface method (`scanline3d::resolve`: band and full-frame z-buffer,
//! span sorting, depth sort, Newell's sort, BSP order, Warnock's subdivision) with flat and
//! perspective-correct Gouraud shading, on a 64×48 target so that their memory stays small.
//! It also traces the classic scene with the fixed-point ray tracer (`scanline3d::trace`):
//! scene and camera set-up, every intersection test, shadows, reflection, refraction and the
//! ray stack, with a stack too small for the depth limit so the overflow path is linked too,
//! without and with a bounding-volume hierarchy (exported, and built at run time) and with a
//! uniform grid built at run time, and in hybrid mode (screen bounds, active list, their
//! overflow). And it runs the fixed-point metaball ray caster and the
//! metaball polygonizer with the span z-buffer drawing its mesh (`scanline3d::metaball`), and
//! the scanline Bezier patch renderer (`scanline3d::patch`, flat and Gouraud, with and without
//! culling, with a subdivision buffer that overflows, and with trim loops cut into two
//! patches, once with room to cut them and once with too little).
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(not(target_os = "none"))]
fn main() {
    println!("panic_never is a link-time check: build it for a bare-metal target, e.g.");
    println!("  cargo build --release --example panic_never --target thumbv6m-none-eabi");
}

#[cfg(target_os = "none")]
#[allow(dead_code)]
#[path = "trace/classic.rs"]
mod classic;

#[cfg(target_os = "none")]
#[allow(dead_code)]
#[path = "trace/view.rs"]
mod view;

#[cfg(target_os = "none")]
mod firmware {
    use core::hint::black_box;
    use embedded_graphics::pixelcolor::Rgb565;
    use scanline3d::arithmetic::Quick;
    use scanline3d::depth::Depth16;
    use scanline3d::preset::{Fast, Preset};
    use scanline3d::resolve::bsp::{BspNode, BspTree, BspWorkspace, NO_CHILD};
    use scanline3d::resolve::{
        BandWorkspace, DepthSortWorkspace, NewellWorkspace, SpanSortWorkspace, WarnockWorkspace,
        ZBufferWorkspace,
    };
    use scanline3d::scene::{Instance, Scene, Transform};
    use scanline3d::shading::{Gouraud, PerPixel, PerSegment, Shading};
    use scanline3d::sink::HashSink;
    use scanline3d::{Depth, Flat, RenderOptions, Workspace};
    use scanline3d_demo::{self as demo, PanelWorkspace};

    /// The demo's capacities with another shading and depth format.
    type Ws<Sh, Z> = Workspace<Rgb565, Sh, 240, 240, 640, 80, 3, Z>;

    /// The other hidden-surface methods' target: small, as some keep a frame or every piece.
    const W: usize = 64;
    const H: usize = 48;
    /// Triangles (or pieces) and active triangles: room for the demo orbit.
    const TRIS: usize = 640;
    const ACTIVE: usize = 80;

    /// A BSP tree over the demo cube's 12 triangles: a root with two children (the planes are
    /// not the cube's, which only changes the order, not the code that runs).
    static BSP_NODES: [BspNode; 3] = [
        BspNode {
            plane: [1.0, 0.0, 0.0, 0.0],
            front: 1,
            back: 2,
            first: 0,
            count: 4,
            facing_front: 2,
        },
        BspNode {
            plane: [0.0, 1.0, 0.0, 0.0],
            front: NO_CHILD,
            back: NO_CHILD,
            first: 4,
            count: 4,
            facing_front: 2,
        },
        BspNode {
            plane: [0.0, 0.0, 1.0, 0.0],
            front: NO_CHILD,
            back: NO_CHILD,
            first: 8,
            count: 4,
            facing_front: 2,
        },
    ];

    /// Renders `scene` with every workspace of `scanline3d::resolve`, one after another (each
    /// in its own block, so their stack memory can be shared), and `cube`, a one-instance scene
    /// of the demo cube, in BSP order.
    #[inline(never)]
    fn every_method<Sh: Shading>(scene: &Scene<'_>, cube: &Scene<'_>, sink: &mut HashSink) {
        let options = RenderOptions::default();
        let background = Rgb565::new(0, 0, 0);
        {
            let mut ws = BandWorkspace::<Rgb565, Sh, W, H, 8, TRIS, ACTIVE>::new(background);
            black_box(ws.render(scene, &options, sink).is_ok());
        }
        {
            let mut ws = ZBufferWorkspace::<Rgb565, Sh, W, H, TRIS>::new(background);
            black_box(ws.render(scene, &options, sink).is_ok());
        }
        {
            let mut ws = SpanSortWorkspace::<Rgb565, Sh, W, H, TRIS, ACTIVE>::new(background);
            black_box(ws.render(scene, &options, sink).is_ok());
        }
        {
            let mut ws = DepthSortWorkspace::<Rgb565, Sh, W, H, TRIS, ACTIVE>::new(background);
            black_box(ws.render(scene, &options, sink).is_ok());
        }
        {
            let mut ws = NewellWorkspace::<Rgb565, Sh, W, H, TRIS, ACTIVE>::new(background);
            black_box(ws.render(scene, &options, sink).is_ok());
            black_box(ws.sort_stats());
        }
        {
            let mut ws = WarnockWorkspace::<Rgb565, Sh, W, H, TRIS>::new(background);
            black_box(ws.render(scene, &options, sink).is_ok());
            black_box(ws.subdivision());
        }
        {
            // The tree is checked at run time too, from nodes the optimiser cannot see.
            if let Ok(tree) = BspTree::new(black_box(&BSP_NODES), 12) {
                let mut ws = BspWorkspace::<Rgb565, Sh, W, H, 16, 16, 8>::new(background);
                black_box(ws.render(cube, &tree, &options, sink).is_ok());
            }
        }
    }

    /// Traces the classic scene from a camera the optimiser cannot see, with the options and
    /// stack capacity `STACK` given.
    #[inline(never)]
    fn trace<const STACK: usize>(options: scanline3d::trace::TraceOptions, sink: &mut HashSink) {
        use scanline3d::trace::{Scene, TraceCamera, Tracer};
        let v = black_box(super::view::CLASSIC);
        let scene = Scene::textured(
            black_box(&super::classic::OBJECTS),
            &super::classic::MATERIALS,
            black_box(&super::classic::CHECKERS),
            &super::classic::LIGHTS,
            super::classic::BACKGROUND,
            super::classic::AMBIENT,
        );
        let camera = TraceCamera::new(v.eye, v.target, v.up, v.fovy, v.near, v.far, 64, 48);
        if let (Ok(scene), Ok(camera)) = (scene, camera) {
            let mut row = [Rgb565::new(0, 0, 0); W];
            let stats = Tracer::<STACK>::new(&scene, &camera, options).render(&mut row, sink);
            black_box(&stats);
            black_box(Tracer::<STACK>::new(&scene, &camera, options).trace_pixel(3, 4));
            // With the exported bounding-volume hierarchy, and one built here at run time.
            let exported = scene.with_bvh(
                black_box(&super::classic::BVH_NODES),
                &super::classic::BVH_ITEMS,
                black_box(super::classic::BVH_BOUNDED),
            );
            if let Ok(with_bvh) = exported {
                let stats =
                    Tracer::<STACK>::new(&with_bvh, &camera, options).render(&mut row, sink);
                black_box(&stats);
                // Hybrid mode, with room for every object and with buffers that overflow.
                // The shadow candidate lists with room for every object, with too little room
                // and with none.
                use scanline3d::trace::{ScreenBound, ShadowCandidate};
                let mut bounds = [ScreenBound::default(); super::classic::OBJECTS.len()];
                let mut active = [ScreenBound::default(); super::classic::OBJECTS.len()];
                const LISTS: usize = super::classic::LIGHTS.len() * super::classic::OBJECTS.len();
                let mut shadow = [ShadowCandidate::default(); LISTS];
                let n = black_box(super::classic::OBJECTS.len());
                let l = black_box(LISTS);
                for (b, a, c) in [(n, n, l), (n, 2, 3), (2, n, 0)] {
                    let stats = Tracer::<STACK>::new(&with_bvh, &camera, options).render_hybrid(
                        bounds.get_mut(..b).unwrap_or(&mut []),
                        active.get_mut(..a).unwrap_or(&mut []),
                        shadow.get_mut(..c).unwrap_or(&mut []),
                        &mut row,
                        sink,
                    );
                    black_box(&stats);
                }
            }
            let mut nodes = [scanline3d::trace::bvh::BvhNode {
                min: scanline3d::trace::Vec3::ZERO,
                max: scanline3d::trace::Vec3::ZERO,
                index: 0,
                count: 0,
                axis: 0,
            }; 2 * super::classic::OBJECTS.len()];
            let mut items = [0u32; super::classic::OBJECTS.len()];
            if let Ok((used, total, bounded)) =
                scanline3d::trace::bvh::build(scene.objects, &mut nodes, &mut items)
            {
                let built = scene.with_bvh(
                    nodes.get(..used).unwrap_or(&[]),
                    items.get(..total).unwrap_or(&[]),
                    bounded,
                );
                if let Ok(with_bvh) = built {
                    black_box(Tracer::<STACK>::new(&with_bvh, &camera, options).trace_pixel(5, 6));
                }
            }
            // And a uniform grid built at run time.
            use scanline3d::trace::grid::{self, GridShape};
            let corner = |v: i32| scanline3d::trace::Vec3::from_bits(v, v / 2, v);
            let cell = black_box(fixed::types::I16F16::ONE);
            if let Ok(shape) = GridShape::around(corner(-5 << 16), corner(5 << 16), cell) {
                let mut starts = [0u32; 1024];
                let mut items = [0u32; 1024];
                let mut planes = [0u32; 8];
                let built = grid::build(scene.objects, shape, &mut starts, &mut items, &mut planes);
                if let Ok((used, unbounded)) = built {
                    let with_grid = scene.with_grid(
                        shape,
                        starts.get(..=shape.cells()).unwrap_or(&[]),
                        items.get(..used).unwrap_or(&[]),
                        planes.get(..unbounded).unwrap_or(&[]),
                    );
                    if let Ok(with_grid) = with_grid {
                        let stats = Tracer::<STACK>::new(&with_grid, &camera, options)
                            .render(&mut row, sink);
                        black_box(&stats);
                    }
                }
            }
        }
    }

    use fixed::types::I16F16;
    use scanline3d::patch::{PatchModel, TrimLoop, TrimPoint};

    const fn q(u: f64, v: f64) -> TrimPoint {
        [
            I16F16::from_bits((u * 65536.0) as i32),
            I16F16::from_bits((v * 65536.0) as i32),
        ]
    }

    /// A square hole with a triangular island in patch 0 of the teapot, a triangle cut from
    /// patch 5.
    static TRIM_POINTS: [TrimPoint; 10] = [
        q(0.2, 0.2),
        q(0.8, 0.2),
        q(0.8, 0.8),
        q(0.2, 0.8),
        q(0.4, 0.4),
        q(0.6, 0.4),
        q(0.5, 0.6),
        q(0.1, 0.1),
        q(0.9, 0.3),
        q(0.3, 0.9),
    ];
    static TRIM_LOOPS: [TrimLoop; 3] = [
        TrimLoop {
            patch: 0,
            start: 0,
            len: 4,
        },
        TrimLoop {
            patch: 0,
            start: 4,
            len: 3,
        },
        TrimLoop {
            patch: 5,
            start: 7,
            len: 3,
        },
    ];
    static TRIMMED_TEAPOT: PatchModel<'static> =
        match demo::patches::MODEL.with_trims(&TRIM_LOOPS, &TRIM_POINTS) {
            Ok(m) => m,
            Err(_) => panic!("invalid trim loops"),
        };

    #[cfg_attr(target_arch = "arm", cortex_m_rt::entry)]
    #[cfg_attr(target_arch = "riscv32", riscv_rt::entry)]
    fn main() -> ! {
        let mut ws = PanelWorkspace::new(demo::BACKGROUND.into());
        let mut segments = Ws::<Gouraud<PerSegment<16>>, Depth16>::new(Rgb565::new(0, 0, 0));
        let mut per_pixel = Ws::<Gouraud<PerPixel>, Depth>::new(Rgb565::new(0, 0, 0));
        let mut cached =
            Workspace::<Rgb565, Flat, 240, 240, 640, 80, 3, Depth, 1024>::new(Rgb565::new(0, 0, 0));
        let mut metaballs = demo::metaballs::PanelCaster::new(Rgb565::new(0, 0, 0));
        let mut patches = demo::patches::PanelPatches::new(Rgb565::new(0, 0, 0));
        let mut small_patches =
            scanline3d::patch::PatchWorkspace::<Rgb565, Gouraud<PerPixel>, 64, 48, 40, 64>::new(
                Rgb565::new(0, 0, 0),
            );
        let mut polygonized = demo::metaballs::Poly8::new(Rgb565::new(0, 0, 0));
        let mut trimmed_patches = scanline3d::patch::PatchWorkspace::<
            Rgb565,
            Gouraud<PerPixel>,
            64,
            48,
            40,
            64,
            16,
        >::new(Rgb565::new(0, 0, 0));
        let mut cramped_patches =
            scanline3d::patch::PatchWorkspace::<Rgb565, Flat, 64, 48, 40, 64, 4>::new(Rgb565::new(
                0, 0, 0,
            ));
        let instances = demo::instances();
        let mut frame = 0;
        loop {
            // The fixed-point metaball ray caster.
            let mut sink = scanline3d::sink::HashSink::new();
            let cast = demo::metaballs::render_frame(&mut metaballs, black_box(frame), &mut sink);
            core::hint::black_box((&cast, sink.hash()));
            // The metaball polygonizer (marching tetrahedra) and its mesh drawn.
            let mesh = polygonized.polygonize(black_box(frame));
            let drawn = polygonized.draw(&mut sink);
            core::hint::black_box((&mesh, &drawn, sink.hash()));
            if let Ok(scene) = demo::scene(&instances, frame, demo::ORBIT_FRAMES) {
                let out = demo::render_panel_frame(&mut ws, &scene);
                core::hint::black_box(&out);
                // The fast preset's set-up arithmetic, and the narrow one at every stage.
                let mut sink = scanline3d::sink::HashSink::new();
                let fast = ws.render(&scene, &Fast::options(), &mut sink);
                core::hint::black_box((&fast, sink.hash()));
                let quick = Fast::options().with_arithmetic(Quick::default());
                let quick = ws.render(&scene, &quick, &mut sink);
                core::hint::black_box((&quick, sink.hash()));
                // Perspective-correct Gouraud, per segment with 16-bit depth and per pixel.
                let options = RenderOptions::default();
                let a = segments.render(&scene, &options, &mut sink);
                let b = per_pixel.render(&scene, &options, &mut sink);
                core::hint::black_box((&a, &b, sink.hash()));
                // With a vertex cache.
                let c = cached.render(&scene, &options, &mut sink);
                core::hint::black_box((&c, sink.hash()));
                // The other hidden-surface methods, with flat and Gouraud shading.
                let cube = [Instance {
                    mesh: &demo::CUBE,
                    transform: Transform::IDENTITY,
                }];
                if let Ok(cube) = Scene::new(black_box(&cube), scene.camera, scene.light) {
                    every_method::<Flat>(&scene, &cube, &mut sink);
                    every_method::<Gouraud<PerPixel>>(&scene, &cube, &mut sink);
                    core::hint::black_box(sink.hash());
                }
            }
            // The scanline Bezier patch renderer: the teapot, flat and two-sided, and Gouraud
            // with back faces culled in a small workspace whose subdivision buffer overflows.
            let mut sink = scanline3d::sink::HashSink::new();
            let drawn = demo::patches::render_frame(&mut patches, black_box(frame), &mut sink);
            core::hint::black_box((&drawn, sink.hash()));
            if let Ok(scene) = demo::patches::scene(black_box(frame)) {
                let options = RenderOptions::default().with_back_face_culling(true);
                let tolerance = black_box(scanline3d::patch::Tolerance::ONE);
                let small = small_patches.render(&scene, &options, tolerance, &mut sink);
                core::hint::black_box((&small, sink.hash()));
                // Trimmed, with room to cut and with too little.
                let trimmed = scanline3d::patch::PatchScene {
                    model: black_box(&TRIMMED_TEAPOT),
                    ..scene
                };
                let options = RenderOptions::default();
                let cut = trimmed_patches.render(&trimmed, &options, tolerance, &mut sink);
                let cramped = cramped_patches.render(&trimmed, &options, tolerance, &mut sink);
                core::hint::black_box((&cut, &cramped, sink.hash()));
            }
            // The fixed-point tracer, with room for its ray tree and with too little.
            let options = black_box(scanline3d::trace::TraceOptions::default());
            let mut sink = scanline3d::sink::HashSink::new();
            trace::<5>(options, &mut sink);
            trace::<2>(options, &mut sink);
            black_box(sink.hash());
            frame = frame.wrapping_add(1);
        }
    }

    #[panic_handler]
    fn panic(_: &core::panic::PanicInfo) -> ! {
        extern "C" {
            /// Deliberately undefined: referencing it makes any reachable panic a link error.
            fn scanline3d_render_path_can_panic() -> !;
        }
        // SAFETY: never called when linking succeeds; the symbol does not exist.
        unsafe { scanline3d_render_path_can_panic() }
    }
}
