//! Shading models and the span fill (the per-pixel loop of the span z-buffer).
//!
//! A shading model is a type, chosen at compile time: [`Flat`] (Lambert + ambient per face, one
//! precomputed pixel per triangle) or [`Gouraud`] (lit per vertex, colour interpolated linearly
//! in screen space). Depth is always perspective-correct: the span loop steps `q = near/w`,
//! which is linear in screen space.

use crate::depth::DepthFormat;
use crate::project::ScreenVertex;
use crate::raster::{channel, ColorPlanes, PixelOrigin, PlaneSolver};
use crate::sink::RowPixel;
use embedded_graphics::pixelcolor::Rgb888;

mod sealed {
    pub trait Sealed {}
}

/// A span to fill: columns `[x0, x0 + len)` of row `y`, starting depth and per-pixel step.
#[derive(Clone, Copy, Debug)]
pub struct SpanDepth {
    /// First column.
    pub x0: i32,
    /// Row.
    pub y: i32,
    /// Depth at the first pixel centre (I2F30 bits).
    pub q: i32,
    /// Depth step per pixel (I2F30 bits).
    pub dq: i32,
}

/// How triangles are coloured. Implemented by [`Flat`] and [`Gouraud`] only.
pub trait Shading: sealed::Sealed + Copy + Default {
    /// What each active triangle carries for its span fills.
    type Payload<P: Copy>: Copy;
    /// Whether vertices need lit colours (Gouraud) or one colour per face is enough (flat).
    const PER_VERTEX: bool;

    /// The payload of a triangle whose lit face colour is `face` (flat) or whose vertices carry
    /// lit colours (Gouraud).
    fn payload<P: RowPixel, const S: u32>(
        face: Rgb888,
        id: u32,
        solver: &PlaneSolver,
        v: &[ScreenVertex<S>; 3],
    ) -> Self::Payload<P>;

    /// Depth-tests and writes one span; `depth` (in format `Z`) and `pixels` are exactly the
    /// span's columns. Returns the number of pixels written.
    fn fill<P: RowPixel, Z: DepthFormat>(
        payload: &Self::Payload<P>,
        origin: &PixelOrigin,
        span: SpanDepth,
        depth: &mut [Z],
        pixels: &mut [P],
    ) -> u32;

    /// Writes the span starting at column `x0` of row `y` without a depth test, for methods
    /// that settle visibility before painting (span sorting, depth sorting); `pixels` is
    /// exactly the span's columns.
    fn paint<P: RowPixel>(
        payload: &Self::Payload<P>,
        origin: &PixelOrigin,
        x0: i32,
        y: i32,
        pixels: &mut [P],
    );
}

/// Flat shading: one Lambert + ambient colour per face.
#[derive(Clone, Copy, Debug, Default)]
pub struct Flat;

/// Gouraud shading: Lambert + ambient per vertex, colour interpolated across the triangle.
///
/// Vertex normals come from the mesh; a mesh without normals uses its face normal at each
/// vertex (so lighting is flat, but per-vertex colours still blend).
#[derive(Clone, Copy, Debug, Default)]
pub struct Gouraud;

impl sealed::Sealed for Flat {}
impl sealed::Sealed for Gouraud {}

impl Shading for Flat {
    type Payload<P: Copy> = P;
    const PER_VERTEX: bool = false;

    #[inline]
    fn payload<P: RowPixel, const S: u32>(
        face: Rgb888,
        id: u32,
        _: &PlaneSolver,
        _: &[ScreenVertex<S>; 3],
    ) -> P {
        P::from_shade(face, id)
    }

    #[inline]
    fn fill<P: RowPixel, Z: DepthFormat>(
        color: &P,
        _: &PixelOrigin,
        span: SpanDepth,
        depth: &mut [Z],
        pixels: &mut [P],
    ) -> u32 {
        let mut q = span.q;
        let mut written = 0;
        for (z, p) in depth.iter_mut().zip(pixels.iter_mut()) {
            // Strictly nearer wins: on an exact tie the surface drawn first keeps the pixel.
            let stored = Z::store(q);
            if stored > *z {
                *z = stored;
                *p = *color;
                written += 1;
            }
            q = q.wrapping_add(span.dq);
        }
        written
    }

    #[inline]
    fn paint<P: RowPixel>(color: &P, _: &PixelOrigin, _: i32, _: i32, pixels: &mut [P]) {
        pixels.fill(*color);
    }
}

/// Per-triangle data for [`Gouraud`].
#[derive(Clone, Copy, Debug)]
pub struct GouraudPayload {
    planes: ColorPlanes,
    id: u32,
}

impl Shading for Gouraud {
    type Payload<P: Copy> = GouraudPayload;
    const PER_VERTEX: bool = true;

    fn payload<P: RowPixel, const S: u32>(
        _: Rgb888,
        id: u32,
        solver: &PlaneSolver,
        v: &[ScreenVertex<S>; 3],
    ) -> GouraudPayload {
        GouraudPayload {
            planes: ColorPlanes::new(solver, v),
            id,
        }
    }

    #[inline]
    fn fill<P: RowPixel, Z: DepthFormat>(
        payload: &GouraudPayload,
        origin: &PixelOrigin,
        span: SpanDepth,
        depth: &mut [Z],
        pixels: &mut [P],
    ) -> u32 {
        let (mut c, dc) = payload.planes.span_start(origin, span.x0, span.y);
        let mut q = span.q;
        let mut written = 0;
        for (z, p) in depth.iter_mut().zip(pixels.iter_mut()) {
            let stored = Z::store(q);
            if stored > *z {
                *z = stored;
                let rgb = Rgb888::new(channel(c[0]), channel(c[1]), channel(c[2]));
                *p = P::from_shade(rgb, payload.id);
                written += 1;
            }
            q = q.wrapping_add(span.dq);
            for k in 0..3 {
                c[k] = c[k].wrapping_add(dc[k]);
            }
        }
        written
    }

    #[inline]
    fn paint<P: RowPixel>(
        payload: &GouraudPayload,
        origin: &PixelOrigin,
        x0: i32,
        y: i32,
        pixels: &mut [P],
    ) {
        let (mut c, dc) = payload.planes.span_start(origin, x0, y);
        for p in pixels.iter_mut() {
            let rgb = Rgb888::new(channel(c[0]), channel(c[1]), channel(c[2]));
            *p = P::from_shade(rgb, payload.id);
            for k in 0..3 {
                c[k] = c[k].wrapping_add(dc[k]);
            }
        }
    }
}
