//! The frame hash the project recorded before [`HashSink`] hashed one 32-bit word a pixel:
//! 32-bit FNV-1a over each pixel's raw value as 4 little-endian bytes. Frame hashes recorded
//! with it (the "before" figures of `docs/speed/`, old constants) are checked against the same
//! render through [`Tee`]: equal byte-wise hashes mean the pixels did not change, and the
//! [`HashSink`] beside it gives the hash the firmware prints now.
//!
//! ```
//! use embedded_graphics::pixelcolor::Rgb565;
//! use scanline3d::{depth::DepthRow, sink::{HashSink, Row, RowSink}};
//! use scanline3d_demo::byte_hash::{ByteHashSink, Tee};
//! let mut both = Tee(HashSink::new(), ByteHashSink::new());
//! let row = Row { y: 0, pixels: &[Rgb565::new(1, 2, 3)], depth: DepthRow::NONE, complete: true };
//! both.write_row(row).unwrap();
//! assert_ne!(both.0.hash(), both.1.hash());
//! ```

use core::convert::Infallible;
use embedded_graphics::pixelcolor::raw::RawData;
use embedded_graphics::pixelcolor::PixelColor;
use scanline3d::sink::{Row, RowSink};

#[cfg(doc)]
use scanline3d::sink::HashSink;

/// 32-bit FNV-1a over every pixel's raw value as 4 little-endian bytes, rows in order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ByteHashSink {
    hash: u32,
}

impl Default for ByteHashSink {
    fn default() -> Self {
        Self::new()
    }
}

impl ByteHashSink {
    /// An empty stream (FNV-1a's offset basis).
    pub const fn new() -> Self {
        ByteHashSink { hash: 0x811c_9dc5 }
    }
    /// The hash of everything written so far.
    pub const fn hash(&self) -> u32 {
        self.hash
    }
}

impl<P> RowSink<P> for ByteHashSink
where
    P: PixelColor + Into<P::Raw>,
    <P::Raw as RawData>::Storage: Into<u32>,
{
    type Error = Infallible;
    fn write_row(&mut self, row: Row<'_, P>) -> Result<(), Infallible> {
        for &p in row.pixels {
            let raw: u32 = p.into().into_inner().into();
            for byte in raw.to_le_bytes() {
                self.hash = (self.hash ^ byte as u32).wrapping_mul(0x0100_0193);
            }
        }
        Ok(())
    }
}

/// Two sinks fed the same rows (the first's error stops the second).
#[derive(Clone, Copy, Debug, Default)]
pub struct Tee<A, B>(pub A, pub B);

impl<P: Copy, A: RowSink<P>, B: RowSink<P, Error = A::Error>> RowSink<P> for Tee<A, B> {
    type Error = A::Error;
    fn write_row(&mut self, row: Row<'_, P>) -> Result<(), A::Error> {
        self.0.write_row(row)?;
        self.1.write_row(row)
    }
}
