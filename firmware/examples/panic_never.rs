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
//! `cargo xtask test` builds it for all three targets. It covers what a firmware frame runs:
//! scene and camera set-up, the vertex stage, clipping, projection, bucketing, the edge walk, the
//! span z-buffer and the row sink, with the default arithmetic and the fast preset's narrow one.
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(not(target_os = "none"))]
fn main() {
    println!("panic_never is a link-time check: build it for a bare-metal target, e.g.");
    println!("  cargo build --release --example panic_never --target thumbv6m-none-eabi");
}

#[cfg(target_os = "none")]
mod firmware {
    use embedded_graphics::pixelcolor::Rgb565;
    use scanline3d::depth::Depth16;
    use scanline3d::preset::{Fast, Preset};
    use scanline3d::shading::{Gouraud, PerPixel, PerSegment};
    use scanline3d::{Depth, Flat, RenderOptions, Workspace};
    use scanline3d_demo::{self as demo, PanelWorkspace};

    /// The demo's capacities with another shading and depth format.
    type Ws<Sh, Z> = Workspace<Rgb565, Sh, 240, 240, 640, 80, 3, Z>;

    #[cfg_attr(target_arch = "arm", cortex_m_rt::entry)]
    #[cfg_attr(target_arch = "riscv32", riscv_rt::entry)]
    fn main() -> ! {
        let mut ws = PanelWorkspace::new(demo::BACKGROUND.into());
        let mut segments = Ws::<Gouraud<PerSegment<16>>, Depth16>::new(Rgb565::new(0, 0, 0));
        let mut per_pixel = Ws::<Gouraud<PerPixel>, Depth>::new(Rgb565::new(0, 0, 0));
        let mut cached =
            Workspace::<Rgb565, Flat, 240, 240, 640, 80, 3, Depth, 1024>::new(Rgb565::new(0, 0, 0));
        let instances = demo::instances();
        let mut frame = 0;
        loop {
            if let Ok(scene) = demo::scene(&instances, frame, demo::ORBIT_FRAMES) {
                let out = demo::render_panel_frame(&mut ws, &scene);
                core::hint::black_box(&out);
                // The narrow set-up arithmetic of the fast preset, too.
                let mut sink = scanline3d::sink::HashSink::new();
                let quick = ws.render(&scene, &Fast::options(), &mut sink);
                core::hint::black_box((&quick, sink.hash()));
                // Perspective-correct Gouraud, per segment with 16-bit depth and per pixel.
                let options = RenderOptions::default();
                let a = segments.render(&scene, &options, &mut sink);
                let b = per_pixel.render(&scene, &options, &mut sink);
                core::hint::black_box((&a, &b, sink.hash()));
                // With a vertex cache.
                let c = cached.render(&scene, &options, &mut sink);
                core::hint::black_box((&c, sink.hash()));
            }
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
