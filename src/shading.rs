//! Shading models and the span fill (the per-pixel loop of the span z-buffer).
//!
//! A shading model is a type, chosen at compile time: [`Flat`] (Lambert + ambient per face, one
//! precomputed pixel per triangle), [`Unlit`] (one colour per face, the mesh's own, for colours
//! lit ahead of time by [`bake_face_colors`]) or [`Gouraud`] (lit per vertex,
//! colour interpolated across the triangle). Depth is always perspective-correct: the span loop steps `q = near/w`, which
//! is linear in screen space.
//!
//! How Gouraud colour is interpolated is its type parameter, an [`Interpolation`]:
//!
//! | interpolation | per pixel | per segment of `N` pixels | error |
//! |---|---|---|---|
//! | [`Affine`] (default) | 3 adds | — | grows with how steeply the triangle recedes |
//! | [`PerSegment<N>`] | 3 adds | 3 divisions (one evaluation of `PerspectivePlanes`), and one more evaluation at each span's start | affine within each segment of `N` pixels |
//! | [`PerPixel`] | 4 64-bit adds, 3 divisions where a pixel is written | — | rounding only |

use crate::depth::DepthFormat;
use crate::project::ScreenVertex;
use crate::raster::{channel, ColorPlanes, PerspectivePlanes, PixelOrigin, PlaneSolver};
use crate::scene::{Light, Mesh, MeshColors, SceneError, Transform};
use crate::sink::RowPixel;
use core::marker::PhantomData;
use embedded_graphics::pixelcolor::Rgb888;
use fixed::types::I16F16;

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

/// How triangles are coloured. Implemented by [`Flat`], [`Unlit`] and [`Gouraud`] only.
pub trait Shading: sealed::Sealed + Copy + Default {
    /// What each active triangle carries for its span fills.
    type Payload<P: Copy>: Copy;
    /// Whether vertices need lit colours (Gouraud) or one colour per face is enough (flat).
    const PER_VERTEX: bool;
    /// Whether the renderer lights the mesh's colours ([`Flat`], [`Gouraud`]) or takes them
    /// as given ([`Unlit`]: a build with no lighting code at all).
    const LIT: bool;

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
        span: SpanDepth,
        depth: &mut [Z],
        pixels: &mut [P],
    ) -> u32;

    /// Writes the span starting at column `x0` of row `y` without a depth test, for methods
    /// that settle visibility before painting (span sorting, depth sorting); `pixels` is
    /// exactly the span's columns.
    fn paint<P: RowPixel>(payload: &Self::Payload<P>, x0: i32, y: i32, pixels: &mut [P]);
}

/// Flat shading: one Lambert + ambient colour per face.
#[derive(Clone, Copy, Debug, Default)]
pub struct Flat;

/// Flat shading without lighting: one colour per face, the mesh's own colour as given (its
/// per-face colour, its uniform colour, or the colour of the triangle's first vertex), with no
/// Lambert or ambient term. The fill is [`Flat`]'s.
///
/// For static scenes: where an instance's transform and the light do not change, its flat
/// colours are the same in every frame, so they can be lit once, on the host or at start-up,
/// by [`bake_face_colors`]. A mesh with those colours per face, drawn `Unlit`,
/// gives exactly the pixels of the original mesh drawn [`Flat`], and a build that uses only
/// `Unlit` contains no lighting code (no normals, cosines or shading per triangle).
///
/// ```
/// use embedded_graphics::pixelcolor::Rgb888;
/// use fixed::types::I16F16;
/// use scanline3d::arithmetic::Precise;
/// use scanline3d::scene::{Light, Mesh, MeshColors, Transform, Vertex};
/// use scanline3d::shading::bake_face_colors;
///
/// const Z: I16F16 = I16F16::ZERO;
/// static VERTS: [Vertex; 3] = [[Z, Z, Z], [I16F16::ONE, Z, Z], [Z, I16F16::ONE, Z]];
/// static TRIS: [[u16; 3]; 1] = [[0, 1, 2]];
/// let mesh = Mesh::new(&VERTS, &TRIS, MeshColors::Uniform(Rgb888::new(200, 80, 40)), None)?;
/// let light = Light::new([0.0, 0.0, 1.0], 0.25, 0.75)?;
/// let mut baked = [Rgb888::new(0, 0, 0); 1];
/// bake_face_colors::<Precise>(&mesh, &Transform::IDENTITY, &light, &mut baked)?;
/// // Facing the light: ambient + diffuse = 1, the colour itself.
/// assert_eq!(baked, [Rgb888::new(200, 80, 40)]);
/// // Draw `Mesh::new(&VERTS, &TRIS, MeshColors::PerFace(&baked), None)` with `Unlit`.
/// # Ok::<(), scanline3d::scene::SceneError>(())
/// ```
#[derive(Clone, Copy, Debug, Default)]
pub struct Unlit;

/// Gouraud shading: Lambert + ambient per vertex, colour interpolated across the triangle as
/// `I` says ([`Affine`] by default).
///
/// Vertex normals come from the mesh; a mesh without normals uses its face normal at each
/// vertex (so lighting is flat, but per-vertex colours still blend).
///
/// ```
/// use scanline3d::shading::{Gouraud, PerSegment};
/// // Perspective-correct every 16 pixels, affine between.
/// type Shade = Gouraud<PerSegment<16>>;
/// # let _ = Shade::default();
/// ```
#[derive(Clone, Copy, Debug, Default)]
pub struct Gouraud<I: Interpolation = Affine>(PhantomData<I>);

/// How [`Gouraud`] colour is interpolated. Implemented by [`Affine`], [`PerSegment`] and
/// [`PerPixel`] only.
pub trait Interpolation: sealed::Sealed + Copy + Default + core::fmt::Debug + 'static {
    /// Per-triangle planes.
    type Planes: Copy + core::fmt::Debug;
    /// Position within one span.
    type Cursor;
    /// The planes of triangle `v`.
    fn planes<const S: u32>(solver: &PlaneSolver, v: &[ScreenVertex<S>; 3]) -> Self::Planes;
    /// A cursor at the first of the `len` pixels starting at column `x0` of row `y`.
    fn cursor(
        planes: &Self::Planes,
        origin: &PixelOrigin,
        x0: i32,
        y: i32,
        len: usize,
    ) -> Self::Cursor;
    /// The colour at the cursor.
    fn colour(cursor: &Self::Cursor) -> Rgb888;
    /// Moves the cursor one pixel right.
    fn advance(cursor: &mut Self::Cursor);
}

/// Colour linear in screen space: cheapest, and wrong by as much as the triangle's depth varies
/// (the colour of a receding triangle drifts towards its far vertices).
#[derive(Clone, Copy, Debug, Default)]
pub struct Affine;

/// Perspective-correct colour at every `N`-th pixel of a span (and its last), affine between
/// (`N ≥ 2`; a power of two makes the per-segment step a shift).
#[derive(Clone, Copy, Debug, Default)]
pub struct PerSegment<const N: u32>;

/// Perspective-correct colour at every pixel written.
#[derive(Clone, Copy, Debug, Default)]
pub struct PerPixel;

impl sealed::Sealed for Affine {}
impl<const N: u32> sealed::Sealed for PerSegment<N> {}
impl sealed::Sealed for PerPixel {}

/// I16F16 channels as a colour.
#[inline]
fn rgb(c: &[i32; 3]) -> Rgb888 {
    Rgb888::new(channel(c[0]), channel(c[1]), channel(c[2]))
}

impl Interpolation for Affine {
    type Planes = ColorPlanes;
    /// Channels (I16F16) and their per-pixel steps.
    type Cursor = ([i32; 3], [i32; 3]);
    #[inline]
    fn planes<const S: u32>(solver: &PlaneSolver, v: &[ScreenVertex<S>; 3]) -> ColorPlanes {
        ColorPlanes::new(solver, v)
    }
    #[inline]
    fn cursor(p: &ColorPlanes, origin: &PixelOrigin, x0: i32, y: i32, _: usize) -> Self::Cursor {
        p.span_start(origin, x0, y)
    }
    #[inline]
    fn colour((c, _): &Self::Cursor) -> Rgb888 {
        rgb(c)
    }
    #[inline]
    fn advance((c, dc): &mut Self::Cursor) {
        for k in 0..3 {
            c[k] = c[k].wrapping_add(dc[k]);
        }
    }
}

impl Interpolation for PerPixel {
    type Planes = PerspectivePlanes;
    /// `[c·r, r]` values and their per-pixel steps.
    type Cursor = ([i64; 4], [i64; 4]);
    #[inline]
    fn planes<const S: u32>(solver: &PlaneSolver, v: &[ScreenVertex<S>; 3]) -> Self::Planes {
        PerspectivePlanes::new(solver, v)
    }
    #[inline]
    fn cursor(p: &Self::Planes, origin: &PixelOrigin, x0: i32, y: i32, _: usize) -> Self::Cursor {
        p.span_start(origin, x0, y)
    }
    #[inline]
    fn colour((v, _): &Self::Cursor) -> Rgb888 {
        rgb(&PerspectivePlanes::colour(v))
    }
    #[inline]
    fn advance((v, dv): &mut Self::Cursor) {
        for k in 0..4 {
            v[k] = v[k].wrapping_add(dv[k]);
        }
    }
}

/// Where a [`PerSegment`] interpolation is within a span.
#[derive(Clone, Copy, Debug)]
pub struct SegmentCursor {
    /// `[c·r, r]` at the current segment's end pixel, and per-pixel steps.
    at: [i64; 4],
    dv: [i64; 4],
    /// Channels (I16F16) at the cursor, their step, and their exact values at the segment end.
    c: [i32; 3],
    dc: [i32; 3],
    end: [i32; 3],
    /// Pixels from the cursor to the segment end; pixels of the span after the segment end.
    left: u32,
    rest: u32,
}

impl SegmentCursor {
    /// Starts the segment at the cursor (whose channels are exact): at most `n` pixels long, to
    /// the span's last pixel at the farthest.
    #[inline]
    fn next_segment(&mut self, n: u32) {
        let len = n.min(self.rest);
        if len == 0 {
            // The span's last pixel: nothing beyond it to interpolate towards.
            self.dc = [0; 3];
            self.left = u32::MAX;
            return;
        }
        for k in 0..4 {
            let jump = if len == n {
                self.dv[k].wrapping_mul(n as i64)
            } else {
                self.dv[k].wrapping_mul(len as i64)
            };
            self.at[k] = self.at[k].wrapping_add(jump);
        }
        self.end = PerspectivePlanes::colour(&self.at);
        for k in 0..3 {
            let d = self.end[k].wrapping_sub(self.c[k]);
            self.dc[k] = if len == n {
                d / n as i32
            } else {
                d / len as i32
            };
        }
        self.left = len;
        self.rest -= len;
    }
}

impl<const N: u32> Interpolation for PerSegment<N> {
    type Planes = PerspectivePlanes;
    type Cursor = SegmentCursor;
    #[inline]
    fn planes<const S: u32>(solver: &PlaneSolver, v: &[ScreenVertex<S>; 3]) -> Self::Planes {
        PerspectivePlanes::new(solver, v)
    }
    #[inline]
    fn cursor(p: &Self::Planes, origin: &PixelOrigin, x0: i32, y: i32, len: usize) -> Self::Cursor {
        const { assert!(N >= 2 && N <= 1 << 16, "a segment is 2 to 65536 pixels") };
        let (at, dv) = p.span_start(origin, x0, y);
        let mut cursor = SegmentCursor {
            at,
            dv,
            c: PerspectivePlanes::colour(&at),
            dc: [0; 3],
            end: [0; 3],
            left: 0,
            rest: (len as u32).saturating_sub(1),
        };
        cursor.next_segment(N);
        cursor
    }
    #[inline]
    fn colour(cursor: &SegmentCursor) -> Rgb888 {
        rgb(&cursor.c)
    }
    #[inline]
    fn advance(cursor: &mut SegmentCursor) {
        cursor.left = cursor.left.wrapping_sub(1);
        if cursor.left == 0 {
            cursor.c = cursor.end;
            cursor.next_segment(N);
        } else {
            for k in 0..3 {
                cursor.c[k] = cursor.c[k].wrapping_add(cursor.dc[k]);
            }
        }
    }
}

impl sealed::Sealed for Flat {}
impl sealed::Sealed for Unlit {}
impl<I: Interpolation> sealed::Sealed for Gouraud<I> {}

impl Shading for Flat {
    type Payload<P: Copy> = P;
    const PER_VERTEX: bool = false;
    const LIT: bool = true;

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
        span: SpanDepth,
        depth: &mut [Z],
        pixels: &mut [P],
    ) -> u32 {
        // Armv7-M is the Arm profile with 32-bit atomics (ARMv6-M has none).
        if cfg!(any(
            target_arch = "riscv32",
            all(target_arch = "arm", target_has_atomic = "32")
        )) {
            flat_fill_by_pairs::<_, _, COUNT_REJECTED>(color, span, depth, pixels)
        } else {
            flat_fill::<_, _, COUNT_REJECTED>(color, span, depth, pixels)
        }
    }

    #[inline]
    fn paint<P: RowPixel>(color: &P, _: i32, _: i32, pixels: &mut [P]) {
        pixels.fill(*color);
    }
}

/// Whether [`Flat::fill`] counts the pixels that fail the depth test, in a branch of their own,
/// and returns the span's length less them (ARMv6-M and RISC-V), instead of counting written
/// pixels under the test's condition (Armv7-M and the host). Without conditional execution a
/// written pixel then takes no count: 0.6–1.8 % fewer instructions a demo frame there
/// (docs/speed.md item 37). Armv7-M predicates the count (`it`); there the branch saved 2 %
/// of the demo's frame but cost 0.8 % on the icosphere and the heightfield.
const COUNT_REJECTED: bool = cfg!(any(
    target_arch = "riscv32",
    all(target_arch = "arm", not(target_has_atomic = "32"))
));

/// [`Flat::fill`]'s depth test of one pixel at depth `q`, stepping `q`: strictly nearer wins,
/// so on an exact tie the surface drawn first keeps the pixel. Adds 1 to `count` for a written
/// pixel, or with `REJECTED` ([`COUNT_REJECTED`] in the renderer) for a rejected one.
#[inline(always)]
fn flat_test<P: Copy, Z: DepthFormat, const REJECTED: bool>(
    color: &P,
    q: &mut i32,
    dq: i32,
    z: &mut Z,
    p: &mut P,
    count: &mut u32,
) {
    let stored = Z::store(*q);
    if stored > *z {
        *z = stored;
        *p = *color;
        if !REJECTED {
            *count += 1;
        }
    } else if REJECTED {
        *count += 1;
        // An empty barrier: the compiler would otherwise make the count a select, paid by
        // every pixel.
        core::hint::black_box(());
    }
    *q = q.wrapping_add(dq);
}

/// The pixels written of a span of `n` for which [`flat_test`] counted `count`.
#[inline(always)]
fn written_of<const REJECTED: bool>(n: usize, count: u32) -> u32 {
    if REJECTED {
        (n as u32).wrapping_sub(count)
    } else {
        count
    }
}

/// [`Flat::fill`] one pixel per iteration: on ARMv6-M, where pairs took more instructions,
/// with an empty barrier (unrolled by the compiler, the loop runs out of registers there,
/// docs/speed.md item 12); elsewhere (the host) as the compiler likes.
#[inline(always)]
fn flat_fill<P: Copy, Z: DepthFormat, const REJECTED: bool>(
    color: &P,
    span: SpanDepth,
    depth: &mut [Z],
    pixels: &mut [P],
) -> u32 {
    let (mut q, mut count) = (span.q, 0);
    for (z, p) in depth.iter_mut().zip(pixels.iter_mut()) {
        if cfg!(target_arch = "arm") {
            core::hint::black_box(());
        }
        flat_test::<_, _, REJECTED>(color, &mut q, span.dq, z, p, &mut count);
    }
    written_of::<REJECTED>(depth.len().min(pixels.len()), count)
}

/// [`Flat::fill`] two pixels per iteration, an odd span's first pixel alone: on Armv7-M 10
/// instructions a pixel instead of 11, and fewer than the compiler's four-fold unrolling on
/// RISC-V (docs/speed.md item 36; the empty barrier keeps the compiler from unrolling
/// further, which spills on Cortex-M). The same pixels, depths and count as
/// [`flat_fill`] (test `pairs_fill_as_single_pixels_do`).
#[inline(always)]
fn flat_fill_by_pairs<P: Copy, Z: DepthFormat, const REJECTED: bool>(
    color: &P,
    span: SpanDepth,
    depth: &mut [Z],
    pixels: &mut [P],
) -> u32 {
    let (mut q, mut count) = (span.q, 0);
    let n = depth.len().min(pixels.len());
    let (depth, pixels) = (&mut depth[..n], &mut pixels[..n]);
    // The odd pixel first: after the pairs it cost more (a second exit test, spills).
    let (depth, pixels) = if n & 1 == 1 {
        match (depth.split_first_mut(), pixels.split_first_mut()) {
            (Some((z, zs)), Some((p, ps))) => {
                flat_test::<_, _, REJECTED>(color, &mut q, span.dq, z, p, &mut count);
                (zs, ps)
            }
            _ => return 0,
        }
    } else {
        (depth, pixels)
    };
    for (zs, ps) in depth.chunks_exact_mut(2).zip(pixels.chunks_exact_mut(2)) {
        core::hint::black_box(());
        if let ([z0, z1], [p0, p1]) = (zs, ps) {
            flat_test::<_, _, REJECTED>(color, &mut q, span.dq, z0, p0, &mut count);
            flat_test::<_, _, REJECTED>(color, &mut q, span.dq, z1, p1, &mut count);
        }
    }
    written_of::<REJECTED>(n, count)
}

/// Lights `mesh`'s faces ahead of time: writes to `out[t]` the colour [`Flat`] shading gives
/// triangle `t` of `mesh` drawn with model transform `transform` under `light`, with the
/// normals of arithmetic `A` (a preset's [`Arithmetic`], e.g. [`Precise`], the default, or
/// `<preset::Balanced as Preset>::Arithmetic`). Exactly the renderer's colours: the same
/// lighting code, so no rounding differs.
///
/// A mesh with these colours per face ([`MeshColors::PerFace`]) drawn with [`Unlit`] shading,
/// the same transform, camera and arithmetic, gives exactly the pixels of `mesh` drawn [`Flat`].
/// Only for instances whose transform and light stay as baked: the colours do not follow a
/// moving light or a rotating object (a camera may move freely). No allocation; `out` is
/// typically a `static` table on the host (`sim export --bake-light`) or a buffer filled at
/// start-up.
///
/// Fails with [`SceneError::CountMismatch`] (`"baked face colours"`) if `out` does not hold
/// exactly one colour per triangle, or [`SceneError::NonFinite`] if `transform` is not finite.
///
/// [`Arithmetic`]: crate::arithmetic::Arithmetic
/// [`Precise`]: crate::arithmetic::Precise
pub fn bake_face_colors<A: crate::arithmetic::Arithmetic>(
    mesh: &Mesh<'_>,
    transform: &Transform,
    light: &Light,
    out: &mut [Rgb888],
) -> Result<(), SceneError> {
    let triangles = mesh.triangles();
    if out.len() != triangles.len() {
        return Err(SceneError::CountMismatch {
            what: "baked face colours",
            expected: triangles.len(),
            found: out.len(),
        });
    }
    if transform.m.iter().flatten().any(|v| !v.is_finite()) {
        return Err(SceneError::NonFinite {
            what: "model transform",
        });
    }
    let lighting = crate::vertex::Lighting::new(light, transform);
    let verts = mesh.vertices();
    let zero = [I16F16::ZERO; 3];
    let black = Rgb888::new(0, 0, 0);
    for (t, (idx, slot)) in triangles.iter().zip(out.iter_mut()).enumerate() {
        // Mesh::new checked every index and colour count.
        let base = match mesh.colors() {
            MeshColors::Uniform(c) => c,
            MeshColors::PerFace(c) => c.get(t).copied().unwrap_or(black),
            MeshColors::PerVertex(c) => c.get(idx[0] as usize).copied().unwrap_or(black),
        };
        let v = idx.map(|i| verts.get(i as usize).unwrap_or(&zero));
        *slot = lighting.face_color::<A::Normals>(base, v);
    }
    Ok(())
}

/// [`Flat`]'s payload, fill and paint: only the face colour differs (the renderer does not
/// light it).
impl Shading for Unlit {
    type Payload<P: Copy> = P;
    const PER_VERTEX: bool = false;
    const LIT: bool = false;

    #[inline]
    fn payload<P: RowPixel, const S: u32>(
        face: Rgb888,
        id: u32,
        solver: &PlaneSolver,
        v: &[ScreenVertex<S>; 3],
    ) -> P {
        Flat::payload::<P, S>(face, id, solver, v)
    }

    #[inline]
    fn fill<P: RowPixel, Z: DepthFormat>(
        color: &P,
        span: SpanDepth,
        depth: &mut [Z],
        pixels: &mut [P],
    ) -> u32 {
        Flat::fill(color, span, depth, pixels)
    }

    #[inline]
    fn paint<P: RowPixel>(color: &P, x0: i32, y: i32, pixels: &mut [P]) {
        Flat::paint(color, x0, y, pixels)
    }
}

/// Per-triangle data for [`Gouraud`]: the colour planes and the pixel they are relative to
/// (kept here, not with the depth, so flat triangles do not carry it).
#[derive(Clone, Copy, Debug)]
pub struct GouraudPayload<T> {
    planes: T,
    origin: PixelOrigin,
    id: u32,
}

impl<I: Interpolation> Shading for Gouraud<I> {
    type Payload<P: Copy> = GouraudPayload<I::Planes>;
    const PER_VERTEX: bool = true;
    const LIT: bool = true;

    fn payload<P: RowPixel, const S: u32>(
        _: Rgb888,
        id: u32,
        solver: &PlaneSolver,
        v: &[ScreenVertex<S>; 3],
    ) -> Self::Payload<P> {
        GouraudPayload {
            planes: I::planes(solver, v),
            origin: solver.origin(),
            id,
        }
    }

    #[inline]
    fn fill<P: RowPixel, Z: DepthFormat>(
        payload: &Self::Payload<P>,
        span: SpanDepth,
        depth: &mut [Z],
        pixels: &mut [P],
    ) -> u32 {
        let mut c = I::cursor(
            &payload.planes,
            &payload.origin,
            span.x0,
            span.y,
            depth.len(),
        );
        let mut q = span.q;
        let mut written = 0;
        for (z, p) in depth.iter_mut().zip(pixels.iter_mut()) {
            let stored = Z::store(q);
            if stored > *z {
                *z = stored;
                *p = P::from_shade(I::colour(&c), payload.id);
                written += 1;
            }
            q = q.wrapping_add(span.dq);
            I::advance(&mut c);
        }
        written
    }

    #[inline]
    fn paint<P: RowPixel>(payload: &Self::Payload<P>, x0: i32, y: i32, pixels: &mut [P]) {
        let mut c = I::cursor(&payload.planes, &payload.origin, x0, y, pixels.len());
        for p in pixels.iter_mut() {
            *p = P::from_shade(I::colour(&c), payload.id);
            I::advance(&mut c);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::depth::Depth;
    use crate::project::SubPx;
    use fixed::types::I16F16;
    use std::vec::Vec;

    /// `flat_fill_by_pairs` (the Armv7-M and RISC-V fill) writes the pixels, depths and count
    /// the one-pixel loop does, for every span length from 0 to 19 (odd and even), over rows
    /// holding nearer, farther and exactly equal depths, in both depth formats.
    #[test]
    fn pairs_fill_as_single_pixels_do() {
        fn check<Z: DepthFormat + PartialEq + core::fmt::Debug>(next: &mut impl FnMut() -> u64) {
            for case in 0..4_000 {
                let n = case % 20;
                let span = SpanDepth {
                    x0: 0,
                    y: 0,
                    q: (next() >> 34) as i32,
                    dq: (next() >> 44) as i32 - (1 << 19),
                };
                // Rows around the span's depths, so that both outcomes and ties occur.
                let row: Vec<Z> = (0..n)
                    .map(|k| {
                        let q = span.q.wrapping_add(span.dq.wrapping_mul(k));
                        match next() % 3 {
                            0 => Z::store(q),
                            1 => Z::store(q.saturating_add((next() % 4096) as i32)),
                            _ => Z::store(q.saturating_sub((next() % 4096) as i32)),
                        }
                    })
                    .collect();
                let pixels: Vec<u16> = (0..n).map(|k| k as u16).collect();
                let (mut z1, mut p1) = (row.clone(), pixels.clone());
                let (mut z2, mut p2) = (row, pixels);
                let colour = 0xBEEF_u16;
                // Pixels nearer than the row's cell: exactly those are written and counted.
                let nearer = (0..n)
                    .filter(|&k| {
                        let q = span.q.wrapping_add(span.dq.wrapping_mul(k));
                        Z::store(q) > z1[k as usize]
                    })
                    .count() as u32;
                let (mut z3, mut p3) = (z1.clone(), p1.clone());
                let (mut z4, mut p4) = (z1.clone(), p1.clone());
                let single = flat_fill::<_, _, false>(&colour, span, &mut z1, &mut p1);
                let pairs = flat_fill_by_pairs::<_, _, false>(&colour, span, &mut z2, &mut p2);
                assert_eq!(single, nearer, "case {case}");
                assert_eq!((pairs, &z2, &p2), (single, &z1, &p1), "case {case}");
                // Counting the rejected pixels instead: the same.
                let single = flat_fill::<_, _, true>(&colour, span, &mut z3, &mut p3);
                let pairs = flat_fill_by_pairs::<_, _, true>(&colour, span, &mut z4, &mut p4);
                assert_eq!((single, &z3, &p3), (nearer, &z1, &p1), "case {case}");
                assert_eq!((pairs, &z4, &p4), (nearer, &z1, &p1), "case {case}");
            }
        }
        let mut rng = crate::test_rng::XorShift64::new(0x9e37_79b9_7f4a_7c15);
        let mut next = || rng.next_u64();
        check::<Depth>(&mut next);
        check::<crate::depth::Depth16>(&mut next);
    }

    /// A triangle receding steeply to the right: vertex depths `q` 1.0 on the left and 0.05 on
    /// the right (20× farther), red left, blue right. Screen positions in pixels at 4 sub-bits.
    fn receding() -> [ScreenVertex<4>; 3] {
        let v = |x: i32, y: i32, q: f64, c: [u8; 3]| ScreenVertex::<4> {
            x: SubPx(x << 4),
            y: SubPx(y << 4),
            q: Depth::from_num(q),
            color: c.map(I16F16::from_num),
        };
        [
            v(0, 0, 1.0, [255, 0, 0]),
            v(0, 64, 1.0, [255, 0, 0]),
            v(200, 32, 0.05, [0, 0, 255]),
        ]
    }

    /// The perspective-correct red channel at pixel centre `(c, r)`: screen barycentrics
    /// weighted by `q` (Heckbert and Moreton).
    fn exact_red(v: &[ScreenVertex<4>; 3], c: i32, r: i32) -> f64 {
        let p = |s: &ScreenVertex<4>| (s.x.0 as f64 / 16.0, s.y.0 as f64 / 16.0);
        let (a, b, d) = (p(&v[0]), p(&v[1]), p(&v[2]));
        let (x, y) = (c as f64 + 0.5, r as f64 + 0.5);
        let area = (b.0 - a.0) * (d.1 - a.1) - (d.0 - a.0) * (b.1 - a.1);
        let w1 = ((x - a.0) * (d.1 - a.1) - (d.0 - a.0) * (y - a.1)) / area;
        let w2 = ((b.0 - a.0) * (y - a.1) - (x - a.0) * (b.1 - a.1)) / area;
        let bary = [1.0 - w1 - w2, w1, w2];
        let q: Vec<f64> = v.iter().map(|s| s.q.to_num::<f64>()).collect();
        let red: Vec<f64> = v.iter().map(|s| s.color[0].to_num::<f64>()).collect();
        let num: f64 = (0..3).map(|k| bary[k] * q[k] * red[k]).sum();
        let den: f64 = (0..3).map(|k| bary[k] * q[k]).sum();
        num / den
    }

    /// Red channel of row 32, columns 0..180, filled with Gouraud<I>; and its worst error
    /// against the perspective-correct value.
    fn worst_red_error<I: Interpolation>() -> f64 {
        let v = receding();
        let solver = PlaneSolver::new(&v).unwrap();
        let payload = Gouraud::<I>::payload::<Rgb888, 4>(Rgb888::new(0, 0, 0), 0, &solver, &v);
        let mut depth = [Depth::ZERO; 180];
        let mut pixels = [Rgb888::new(0, 0, 0); 180];
        let span = SpanDepth {
            x0: 0,
            y: 32,
            q: 1,
            dq: 0,
        };
        let written = Gouraud::<I>::fill(&payload, span, &mut depth, &mut pixels);
        assert_eq!(written, 180);
        let mut painted = [Rgb888::new(0, 0, 0); 180];
        Gouraud::<I>::paint(&payload, 0, 32, &mut painted);
        assert_eq!(pixels, painted, "fill and paint interpolate alike");
        use embedded_graphics::pixelcolor::RgbColor;
        (0..180)
            .map(|c| (pixels[c].r() as f64 - exact_red(&v, c as i32, 32)).abs())
            .fold(0.0, f64::max)
    }

    #[test]
    fn perspective_correct_interpolation_follows_depth_and_affine_does_not() {
        let affine = worst_red_error::<Affine>();
        let per_pixel = worst_red_error::<PerPixel>();
        let per_8 = worst_red_error::<PerSegment<8>>();
        let per_32 = worst_red_error::<PerSegment<32>>();
        std::println!("worst red error: affine {affine}, per pixel {per_pixel}, segments of 8 {per_8}, of 32 {per_32}");
        // Per pixel: the 8-bit channel's truncation and plane rounding only.
        assert!(per_pixel <= 1.5, "per pixel {per_pixel}");
        // Segments: exact at their ends, affine between, so error grows with their length.
        assert!(per_pixel <= per_8 && per_8 <= per_32 && per_32 < affine);
        assert!(per_8 < 6.0, "segments of 8: {per_8}");
        // Affine is off by most of the channel's range where the triangle recedes.
        assert!(affine > 100.0, "affine {affine}");
    }

    #[test]
    fn segments_end_on_the_spans_last_pixel() {
        // Spans of every length up to 40 pixels: segment arithmetic never steps past the end
        // (the last pixel is exact) and fill and paint agree.
        let v = receding();
        let solver = PlaneSolver::new(&v).unwrap();
        let payload =
            Gouraud::<PerSegment<16>>::payload::<Rgb888, 4>(Rgb888::new(0, 0, 0), 0, &solver, &v);
        let exact = Gouraud::<PerPixel>::payload::<Rgb888, 4>(Rgb888::new(0, 0, 0), 0, &solver, &v);
        for len in 1..=40usize {
            let mut seg = [Rgb888::new(0, 0, 0); 40];
            let mut one = [Rgb888::new(0, 0, 0); 40];
            Gouraud::<PerSegment<16>>::paint(&payload, 10, 30, &mut seg[..len]);
            Gouraud::<PerPixel>::paint(&exact, 10, 30, &mut one[..len]);
            assert_eq!(seg[0], one[0], "first pixel exact, length {len}");
            assert_eq!(seg[len - 1], one[len - 1], "last pixel exact, length {len}");
            if len > 16 {
                assert_eq!(seg[16], one[16], "segment boundary exact, length {len}");
            }
        }
    }

    /// A random closed-ish mesh: `n` triangles over 24 vertices scattered in ±1.5 (either
    /// winding, so some faces are back faces, some lit from behind).
    fn random_mesh_data(
        seed: u64,
    ) -> (std::vec::Vec<crate::scene::Vertex>, std::vec::Vec<[u16; 3]>) {
        let mut rng = crate::test_rng::XorShift64::new(seed);
        let mut coord = || I16F16::from_bits((rng.next_u64() % (3 << 16)) as i32 - (3 << 15));
        let verts: std::vec::Vec<crate::scene::Vertex> =
            (0..24).map(|_| [coord(), coord(), coord()]).collect();
        let mut rng = crate::test_rng::XorShift64::new(seed ^ 0x5555);
        let tris = (0..60)
            .map(|_| [(); 3].map(|_| (rng.next_u64() % 24) as u16))
            .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
            .collect();
        (verts, tris)
    }

    /// The hash of `mesh` drawn with shading `S`, arithmetic `A` and transform `transform`
    /// from a few cameras.
    fn hashes<S: crate::Shading, A: crate::arithmetic::Arithmetic>(
        mesh: &Mesh<'_>,
        transform: Transform,
        light: Light,
    ) -> std::vec::Vec<u32> {
        use crate::sink::HashSink;
        let instances = [crate::scene::Instance { mesh, transform }];
        let mut ws: std::boxed::Box<crate::Workspace<Rgb888, S, 64, 48, 64, 64, 1>> =
            std::boxed::Box::new(crate::Workspace::new(Rgb888::new(1, 2, 3)));
        let options = crate::RenderOptions::default().with_arithmetic(A::default());
        [[0.0, 0.5, 4.0], [3.0, -1.0, 2.0], [-2.0, 2.5, -3.0]]
            .iter()
            .map(|&eye| {
                let camera = crate::scene::Camera::look_at(eye, [0.0; 3], [0.0, 1.0, 0.0])
                    .unwrap()
                    .perspective(60.0, 0.5, 20.0)
                    .unwrap();
                let scene = crate::scene::Scene::new(&instances, camera, light).unwrap();
                let mut sink = HashSink::new();
                ws.render(&scene, &options, &mut sink).unwrap();
                sink.hash()
            })
            .collect()
    }

    /// Baked colours drawn `Unlit` give `Flat`'s frames, for each colour source and two
    /// normal precisions.
    fn baked_equals_flat<A: crate::arithmetic::Arithmetic>() {
        let light = Light::new([-0.45, 0.8, 0.55], 0.25, 0.75).unwrap();
        let transform = Transform::translation([0.2, -0.1, 0.3])
            .then_after(&Transform::rotation_y(0.7))
            .then_after(&Transform::scale([1.2, 0.8, -1.0]));
        for seed in 1..=4u64 {
            let (verts, tris) = random_mesh_data(seed);
            let face: std::vec::Vec<Rgb888> = (0..tris.len())
                .map(|t| Rgb888::new((t as u8).wrapping_mul(7), (t as u8).wrapping_mul(3), 90))
                .collect();
            let vertex: std::vec::Vec<Rgb888> = (0..verts.len())
                .map(|v| Rgb888::new(200, (v as u8).wrapping_mul(10), 255 - v as u8))
                .collect();
            for colors in [
                MeshColors::Uniform(Rgb888::new(180, 140, 60)),
                MeshColors::PerFace(&face),
                MeshColors::PerVertex(&vertex),
            ] {
                let mesh = Mesh::new(&verts, &tris, colors, None).unwrap();
                let mut baked = std::vec![Rgb888::new(0, 0, 0); tris.len()];
                bake_face_colors::<A>(&mesh, &transform, &light, &mut baked).unwrap();
                let unlit = Mesh::new(&verts, &tris, MeshColors::PerFace(&baked), None).unwrap();
                let want = hashes::<crate::Flat, A>(&mesh, transform, light);
                let got = hashes::<crate::Unlit, A>(&unlit, transform, light);
                assert_eq!(got, want, "seed {seed}, {colors:?}");
                // The light mattered: unbaked colours drawn unlit give other frames.
                assert_ne!(hashes::<crate::Unlit, A>(&mesh, transform, light), want);
            }
        }
    }

    #[test]
    fn baked_colours_drawn_unlit_equal_flat_shading() {
        baked_equals_flat::<crate::arithmetic::Precise>();
        baked_equals_flat::<crate::arithmetic::Quick>();
    }

    #[test]
    fn baking_needs_one_colour_per_triangle() {
        let (verts, tris) = random_mesh_data(9);
        let mesh = Mesh::new(
            &verts,
            &tris,
            MeshColors::Uniform(Rgb888::new(9, 9, 9)),
            None,
        )
        .unwrap();
        let light = Light::new([0.0, 0.0, 1.0], 0.2, 0.8).unwrap();
        for len in [0, tris.len() - 1, tris.len() + 1] {
            let mut out = std::vec![Rgb888::new(0, 0, 0); len];
            assert_eq!(
                bake_face_colors::<crate::arithmetic::Precise>(
                    &mesh,
                    &Transform::IDENTITY,
                    &light,
                    &mut out
                ),
                Err(SceneError::CountMismatch {
                    what: "baked face colours",
                    expected: tris.len(),
                    found: len,
                })
            );
        }
        let mut nan = Transform::IDENTITY;
        nan.m[1][2] = f32::NAN;
        let mut out = std::vec![Rgb888::new(0, 0, 0); tris.len()];
        assert!(matches!(
            bake_face_colors::<crate::arithmetic::Precise>(&mesh, &nan, &light, &mut out),
            Err(SceneError::NonFinite { .. })
        ));
    }
}
