//! Output: pixel formats and row sinks.
//!
//! The renderer hands every finished row to a [`RowSink`] exactly once, top to bottom. Adapters:
//! [`DrawTargetSink`] for any embedded-graphics `DrawTarget` (one `fill_contiguous` per row),
//! [`OrderedDither`] for monochrome targets, [`FrameBuffer`] for a frame in RAM and [`FnSink`]
//! for a closure (for example a panel driver that streams the row over SPI).

#[cfg(test)]
use crate::depth::Depth;
use crate::depth::DepthRow;
use embedded_graphics::pixelcolor::raw::RawData;
use embedded_graphics::pixelcolor::{
    BinaryColor, Gray8, GrayColor, PixelColor, Rgb565, Rgb888, RgbColor,
};
use embedded_graphics::prelude::{DrawTarget, Point, Size};
use embedded_graphics::primitives::Rectangle;

/// A pixel the renderer can produce from a shaded colour and the triangle id.
///
/// Implemented for [`Rgb565`], [`Rgb888`], [`Gray8`] (BT.601 luma), [`BinaryColor`] (luma
/// threshold at 128; see [`OrderedDither`] for dithering) and [`TriangleId`] (an id image).
pub trait RowPixel: Copy {
    /// The pixel for a surface of colour `color` belonging to triangle `triangle`.
    fn from_shade(color: Rgb888, triangle: u32) -> Self;
}

/// Luma (BT.601, integer weights summing to 256).
#[inline]
fn luma(c: Rgb888) -> u8 {
    ((77 * c.r() as u32 + 150 * c.g() as u32 + 29 * c.b() as u32) >> 8) as u8
}

impl RowPixel for Rgb888 {
    #[inline]
    fn from_shade(color: Rgb888, _: u32) -> Self {
        color
    }
}

impl RowPixel for Rgb565 {
    #[inline]
    fn from_shade(color: Rgb888, _: u32) -> Self {
        color.into()
    }
}

impl RowPixel for Gray8 {
    #[inline]
    fn from_shade(color: Rgb888, _: u32) -> Self {
        Gray8::new(luma(color))
    }
}

impl RowPixel for BinaryColor {
    #[inline]
    fn from_shade(color: Rgb888, _: u32) -> Self {
        if luma(color) >= 128 {
            BinaryColor::On
        } else {
            BinaryColor::Off
        }
    }
}

/// The id of the triangle that owns a pixel: 0-based over the scene's instances in order,
/// [`TriangleId::NONE`] (−1) for background. Render into `TriangleId` pixels to get an id image.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct TriangleId(pub i32);

impl TriangleId {
    /// Background.
    pub const NONE: TriangleId = TriangleId(-1);
}

impl RowPixel for TriangleId {
    #[inline]
    fn from_shade(_: Rgb888, triangle: u32) -> Self {
        TriangleId(triangle as i32)
    }
}

/// One finished row.
#[derive(Clone, Copy, Debug)]
pub struct Row<'a, P> {
    /// Row index, 0 at the top.
    pub y: u16,
    /// The row's pixels, left to right (length = target width).
    pub pixels: &'a [P],
    /// The row's depth (`near / w`, 0 = background) in the z-buffer's format, same length;
    /// empty for methods that keep no depth.
    pub depth: DepthRow<'a>,
    /// `false` if a triangle piece that spans this row was dropped because the active list was
    /// full (see [`FrameStats::dropped_pieces`](crate::stats::FrameStats::dropped_pieces)).
    pub complete: bool,
}

/// Receives finished rows, each exactly once, top to bottom.
///
/// If `write_row` fails, rendering stops and the error is returned as
/// [`RenderError::Sink`](crate::stats::RenderError::Sink); rows after it are never sent.
pub trait RowSink<P> {
    /// The sink's error type.
    type Error;
    /// Takes one finished row.
    fn write_row(&mut self, row: Row<'_, P>) -> Result<(), Self::Error>;
}

/// Sends each row to an embedded-graphics [`DrawTarget`] with one `fill_contiguous` call on a
/// one-row rectangle.
///
/// ```
/// use embedded_graphics::mock_display::MockDisplay;
/// use embedded_graphics::pixelcolor::BinaryColor;
/// use scanline3d::{depth::DepthRow, sink::{DrawTargetSink, Row, RowSink}};
/// let mut display = MockDisplay::<BinaryColor>::new();
/// let mut sink = DrawTargetSink::new(&mut display);
/// let pixels = [BinaryColor::On, BinaryColor::Off];
/// sink.write_row(Row { y: 1, pixels: &pixels, depth: DepthRow::NONE, complete: true }).unwrap();
/// display.assert_pattern(&[
///     "  ",
///     "#.",
/// ]);
/// ```
pub struct DrawTargetSink<'a, D> {
    target: &'a mut D,
}

impl<'a, D> DrawTargetSink<'a, D> {
    /// Wraps a draw target.
    pub fn new(target: &'a mut D) -> Self {
        DrawTargetSink { target }
    }
}

fn row_rect(y: u16, width: usize) -> Rectangle {
    Rectangle::new(Point::new(0, y as i32), Size::new(width as u32, 1))
}

impl<D: DrawTarget> RowSink<D::Color> for DrawTargetSink<'_, D> {
    type Error = D::Error;
    fn write_row(&mut self, row: Row<'_, D::Color>) -> Result<(), D::Error> {
        self.target.fill_contiguous(
            &row_rect(row.y, row.pixels.len()),
            row.pixels.iter().copied(),
        )
    }
}

/// Turns [`Gray8`] rows into [`BinaryColor`] with a 4×4 ordered (Bayer) dither, for
/// monochrome displays. No row buffer: pixels are converted as the target consumes them.
pub struct OrderedDither<'a, D> {
    target: &'a mut D,
}

impl<'a, D> OrderedDither<'a, D> {
    /// Wraps a monochrome draw target.
    pub fn new(target: &'a mut D) -> Self {
        OrderedDither { target }
    }
}

/// 4×4 Bayer thresholds scaled to 0..256 (centred in each step).
const BAYER4: [[u8; 4]; 4] = [
    [8, 136, 40, 168],
    [200, 72, 232, 104],
    [56, 184, 24, 152],
    [248, 120, 216, 88],
];

/// Ordered-dither decision for a grey level at `(x, y)`.
pub fn dither(level: u8, x: usize, y: u16) -> BinaryColor {
    let t = BAYER4[(y & 3) as usize][x & 3];
    if level >= t {
        BinaryColor::On
    } else {
        BinaryColor::Off
    }
}

impl<D: DrawTarget<Color = BinaryColor>> RowSink<Gray8> for OrderedDither<'_, D> {
    type Error = D::Error;
    fn write_row(&mut self, row: Row<'_, Gray8>) -> Result<(), D::Error> {
        let y = row.y;
        let pixels = row
            .pixels
            .iter()
            .enumerate()
            .map(|(x, g)| dither(g.luma(), x, y));
        self.target
            .fill_contiguous(&row_rect(y, row.pixels.len()), pixels)
    }
}

/// Errors of [`FrameBuffer`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameBufferError {
    /// The row does not fit the buffer (buffer smaller than the render target).
    OutOfBounds,
}

/// A frame in a caller-provided slice, `width` pixels per row, row-major from the top.
///
/// ```
/// use embedded_graphics::pixelcolor::Gray8;
/// use scanline3d::{depth::DepthRow, sink::{FrameBuffer, Row, RowSink}};
/// let mut pixels = [Gray8::new(0); 6];
/// let mut fb = FrameBuffer::new(&mut pixels, 3);
/// fb.write_row(Row { y: 1, pixels: &[Gray8::new(9); 3], depth: DepthRow::NONE, complete: true }).unwrap();
/// assert_eq!(pixels[3], Gray8::new(9));
/// ```
pub struct FrameBuffer<'a, P> {
    pixels: &'a mut [P],
    width: usize,
}

impl<'a, P> FrameBuffer<'a, P> {
    /// Wraps `pixels` as rows of `width`.
    pub fn new(pixels: &'a mut [P], width: usize) -> Self {
        FrameBuffer { pixels, width }
    }
}

impl<P: Copy> RowSink<P> for FrameBuffer<'_, P> {
    type Error = FrameBufferError;
    fn write_row(&mut self, row: Row<'_, P>) -> Result<(), FrameBufferError> {
        let start = row.y as usize * self.width;
        let n = row.pixels.len().min(self.width);
        let dst = self
            .pixels
            .get_mut(start..start + n)
            .ok_or(FrameBufferError::OutOfBounds)?;
        let src = row.pixels.get(..n).ok_or(FrameBufferError::OutOfBounds)?;
        dst.copy_from_slice(src);
        Ok(())
    }
}

/// A closure as a sink.
///
/// ```
/// use embedded_graphics::pixelcolor::Rgb565;
/// use scanline3d::{depth::DepthRow, sink::{FnSink, Row, RowSink}};
/// let mut rows = 0;
/// let mut sink = FnSink(|row: Row<'_, Rgb565>| -> Result<(), ()> { rows += row.y as usize; Ok(()) });
/// sink.write_row(Row { y: 2, pixels: &[], depth: DepthRow::NONE, complete: true }).unwrap();
/// assert_eq!(rows, 2);
/// ```
pub struct FnSink<F>(pub F);

impl<P, E, F: FnMut(Row<'_, P>) -> Result<(), E>> RowSink<P> for FnSink<F> {
    type Error = E;
    fn write_row(&mut self, row: Row<'_, P>) -> Result<(), E> {
        (self.0)(row)
    }
}

/// A frame-buffer-less panel model: hashes the row stream (each pixel's raw value as one 32-bit
/// word, rows in order). Two renders give the same hash when they sent the same pixels in the
/// same order, which is how firmware and host prove bit-identical output.
///
/// Per pixel `h ← (rotl(h, 5) ⊕ raw) · 16777619 (mod 2^32)`, from the FNV-1a offset basis. For a
/// given pixel each step is a bijection of `h` (a rotation, an exclusive or with a constant and
/// a multiplication by an odd number are each invertible), and for a given `h` it is injective
/// in `raw`. So changing any one pixel of a frame changes the state right after that pixel, and
/// the later steps, bijections for the unchanged pixels that follow, carry the difference to
/// the end: **any single-pixel change changes the frame hash** (test
/// `one_changed_pixel_changes_the_hash`). Larger changes collide with a chance of about 2^-32,
/// as for any 32-bit hash. One multiply a pixel, not four as a byte-wise hash: the hash is the
/// measurement's cost, in every instruction count of the firmware.
///
/// ```
/// use embedded_graphics::pixelcolor::Rgb565;
/// use scanline3d::{depth::DepthRow, sink::{HashSink, Row, RowSink}};
/// let mut a = HashSink::new();
/// a.write_row(Row { y: 0, pixels: &[Rgb565::new(1, 2, 3)], depth: DepthRow::NONE, complete: true }).unwrap();
/// let mut b = HashSink::new();
/// b.write_row(Row { y: 0, pixels: &[Rgb565::new(1, 2, 4)], depth: DepthRow::NONE, complete: true }).unwrap();
/// assert_ne!(a.hash(), b.hash());
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HashSink {
    hash: u32,
    rows: u32,
}

impl Default for HashSink {
    fn default() -> Self {
        Self::new()
    }
}

impl HashSink {
    /// An empty stream (the hash starts at FNV-1a's offset basis).
    pub const fn new() -> Self {
        HashSink {
            hash: 0x811c_9dc5,
            rows: 0,
        }
    }
    /// The hash of everything written so far.
    pub const fn hash(&self) -> u32 {
        self.hash
    }
    /// Rows written so far.
    pub const fn rows(&self) -> u32 {
        self.rows
    }
}

/// One pixel's step of [`HashSink`]: a bijection of `h` for each `raw`, injective in `raw` for
/// each `h`.
#[inline(always)]
const fn hash_step(h: u32, raw: u32) -> u32 {
    (h.rotate_left(5) ^ raw).wrapping_mul(0x0100_0193)
}

impl<P> RowSink<P> for HashSink
where
    P: PixelColor + Into<P::Raw>,
    <P::Raw as RawData>::Storage: Into<u32>,
{
    type Error = core::convert::Infallible;
    fn write_row(&mut self, row: Row<'_, P>) -> Result<(), Self::Error> {
        let mut h = self.hash;
        for &p in row.pixels {
            let raw: u32 = p.into().into_inner().into();
            h = hash_step(h, raw);
        }
        self.hash = h;
        self.rows += 1;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use embedded_graphics::pixelcolor::raw::RawU16;

    #[test]
    fn pixel_conversions() {
        let c = Rgb888::new(255, 0, 0);
        assert_eq!(Rgb565::from_shade(c, 0), Rgb565::RED);
        assert_eq!(Gray8::from_shade(Rgb888::WHITE, 0), Gray8::new(255));
        assert_eq!(BinaryColor::from_shade(Rgb888::WHITE, 0), BinaryColor::On);
        assert_eq!(
            BinaryColor::from_shade(Rgb888::new(60, 60, 60), 0),
            BinaryColor::Off
        );
        assert_eq!(TriangleId::from_shade(c, 7), TriangleId(7));
    }

    #[test]
    fn dither_density_follows_level() {
        for level in [0u8, 64, 128, 192, 255] {
            let on = (0..4)
                .flat_map(|y| (0..4).map(move |x| dither(level, x, y)))
                .filter(|c| *c == BinaryColor::On)
                .count();
            assert_eq!(on, (level as usize * 16 + 128) / 256, "level {level}");
        }
    }

    /// The inverse of [`hash_step`] for a given pixel: the step is a bijection of the state.
    fn unstep(h: u32, raw: u32) -> u32 {
        // 0x0100_0193 · 0x359c_449b ≡ 1 (mod 2^32).
        (h.wrapping_mul(0x359c_449b) ^ raw).rotate_right(5)
    }

    #[test]
    fn each_step_is_a_bijection_of_the_state() {
        assert_eq!(0x0100_0193u32.wrapping_mul(0x359c_449b), 1);
        let mut x = 0x1234_5678u32;
        for _ in 0..100_000 {
            x = x.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            let (h, raw) = (x, x.rotate_left(13) ^ 0x9e37_79b9);
            assert_eq!(unstep(hash_step(h, raw), raw), h);
            assert_eq!(hash_step(unstep(h, raw), raw), h);
        }
    }

    fn hash_rows(rows: &[&[Rgb565]]) -> u32 {
        let mut sink = HashSink::new();
        for (y, pixels) in rows.iter().enumerate() {
            let row = Row {
                y: y as u16,
                pixels,
                depth: DepthRow::NONE,
                complete: true,
            };
            let Ok(()) = sink.write_row(row);
        }
        assert_eq!(sink.rows(), rows.len() as u32);
        sink.hash()
    }

    #[test]
    fn one_changed_pixel_changes_the_hash() {
        // Two rows of 6; every pixel of the first row in turn takes each of the 65,536 Rgb565
        // values, and the frame's hash differs exactly when the pixel does.
        let px = |raw: u16| Rgb565::from(RawU16::new(raw));
        let base = [0, 1, 0xffff, 0x8000, 0x1234, 0].map(px);
        let second = [0x0f0f, 0xf0f0, 7].map(px);
        let h0 = hash_rows(&[&base, &second]);
        for i in 0..base.len() {
            let mut row = base;
            for raw in 0..=u16::MAX {
                row[i] = px(raw);
                let h = hash_rows(&[&row, &second]);
                assert_eq!(h == h0, row == base, "pixel {i} = {raw:#06x}");
            }
        }
        // A change in the last pixel of the frame.
        let mut last = second;
        last[2] = px(8);
        assert_ne!(hash_rows(&[&base, &last]), h0);
    }

    #[test]
    fn frame_buffer_rejects_rows_outside() {
        let mut px = [0u8; 4];
        let mut fb = FrameBuffer::new(&mut px, 2);
        let row = Row {
            y: 2,
            pixels: &[1u8, 2],
            depth: DepthRow::Q30(&[Depth::ZERO; 2]),
            complete: true,
        };
        assert_eq!(fb.write_row(row), Err(FrameBufferError::OutOfBounds));
    }
}
