//! Depth formats: how the z-buffer stores the depth of each pixel.
//!
//! Every method computes depth as `q = near / w` in I2F30 ([`Depth`]), stepped across a span
//! from an I24F40 plane: `q` is linear in screen space, so stepping it is perspective-correct.
//! The format only decides what each z-buffer cell keeps, a compile-time choice (the last type
//! parameter of [`Workspace`](crate::Workspace) and
//! [`BandWorkspace`](crate::resolve::BandWorkspace)):
//!
//! | format | bytes per cell | resolution in `q` | eye-depth resolution at distance `w` |
//! |---|---|---|---|
//! | [`Depth`] (I2F30, default) | 4 | 2^-30 | `w² / near · 2^-30` |
//! | [`Depth16`] (U0F16) | 2 | 2^-16 | `w² / near · 2^-16` |
//!
//! [`Depth16`] halves the depth memory (2·W bytes of the span z-buffer's row; W·B of a band or
//! the whole W·H of a full-frame z-buffer) at the price of depth ties between surfaces closer
//! than its resolution; on a tie the surface drawn first keeps the pixel, as with [`Depth`].
//!
//! Why `1/w` and not `z/w`: a perspective `z/w` is `f/(f − n) · (1 − q)`, an affine function
//! of `q`, so in fixed point it is the same ramp with its range stretched by `f/(f − n)`: it
//! would gain under one bit unless the far plane is within a few near-plane distances. `q`
//! needs no far plane and is what the renderer already steps.

use fixed::types::{I2F30, U0F16};

/// Depth as stored in the span z-buffer: `q = near / w` in I2F30.
///
/// `q` is linear in screen space, so interpolating it across a triangle is perspective-correct.
/// It is 1.0 at the near plane and `near/far` at the far plane; larger is nearer; 0 means
/// nothing was drawn. Eye distance is `near / q`.
pub type Depth = I2F30;

mod sealed {
    pub trait Sealed {}
}

/// 16-bit depth: `q = near / w` in U0F16, `q` truncated to 16 fractional bits (so a stored depth
/// is never nearer than the true one), and `q ≥ 1 − 2^-16` (the last 2^-16 before the near
/// plane) saturated to the largest value.
pub type Depth16 = U0F16;

/// A z-buffer cell format. Implemented by [`Depth`] and [`Depth16`] only.
pub trait DepthFormat: sealed::Sealed + Copy + PartialOrd + core::fmt::Debug + 'static {
    /// The background: farther than every surface.
    const FAR: Self;
    /// Bits per cell.
    const BITS: u32;
    /// Rounding of the stored `q` below the exact one, in units of `q`: `2^-BITS` for a narrowed
    /// format, 0 when the cell keeps every bit the span step computes.
    const RESOLUTION: f64;
    /// The cell value of depth `q` (I2F30 bits, as the span fill steps it).
    fn store(q: i32) -> Self;
    /// A row of cells as sinks see it.
    fn row(cells: &[Self]) -> DepthRow<'_>;
}

impl sealed::Sealed for Depth {}
impl sealed::Sealed for Depth16 {}

impl DepthFormat for Depth {
    const FAR: Self = Depth::ZERO;
    const BITS: u32 = 32;
    const RESOLUTION: f64 = 0.0;
    #[inline(always)]
    fn store(q: i32) -> Self {
        Depth::from_bits(q)
    }
    fn row(cells: &[Self]) -> DepthRow<'_> {
        DepthRow::Q30(cells)
    }
}

/// I2F30 fractional bits the 16-bit format drops.
const DROPPED_BITS: u32 = 30 - 16;

impl DepthFormat for Depth16 {
    const FAR: Self = Depth16::ZERO;
    const BITS: u32 = 16;
    const RESOLUTION: f64 = 1.0 / 65536.0;
    #[inline(always)]
    fn store(q: i32) -> Self {
        Depth16::from_bits((q >> DROPPED_BITS).clamp(0, u16::MAX as i32) as u16)
    }
    fn row(cells: &[Self]) -> DepthRow<'_> {
        DepthRow::Q16(cells)
    }
}

/// One row of depth as a sink receives it, in the z-buffer's own format.
#[derive(Clone, Copy, Debug)]
pub enum DepthRow<'a> {
    /// [`Depth`] cells.
    Q30(&'a [Depth]),
    /// [`Depth16`] cells.
    Q16(&'a [Depth16]),
}

impl<'a> DepthRow<'a> {
    /// No depth (methods that keep none, such as span sorting).
    pub const NONE: DepthRow<'static> = DepthRow::Q30(&[]);

    /// Number of cells (the row width, or 0 if the method keeps no depth).
    pub fn len(&self) -> usize {
        match self {
            DepthRow::Q30(d) => d.len(),
            DepthRow::Q16(d) => d.len(),
        }
    }

    /// Whether the row carries no depth.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Depth of column `x` as `q = near / w` ([`Depth`]; 0 = background), `None` past the end.
    ///
    /// ```
    /// use scanline3d::depth::{Depth16, DepthRow};
    /// use scanline3d::Depth;
    /// let cells = [Depth16::from_num(0.25), Depth16::ZERO];
    /// let row = DepthRow::Q16(&cells);
    /// assert_eq!(row.get(0), Some(Depth::from_num(0.25)));
    /// assert_eq!(row.get(2), None);
    /// ```
    pub fn get(&self, x: usize) -> Option<Depth> {
        match self {
            DepthRow::Q30(d) => d.get(x).copied(),
            DepthRow::Q16(d) => d
                .get(x)
                .map(|z| Depth::from_bits((z.to_bits() as i32) << DROPPED_BITS)),
        }
    }
}

impl<'a> From<&'a [Depth]> for DepthRow<'a> {
    fn from(cells: &'a [Depth]) -> Self {
        DepthRow::Q30(cells)
    }
}

impl<'a> From<&'a [Depth16]> for DepthRow<'a> {
    fn from(cells: &'a [Depth16]) -> Self {
        DepthRow::Q16(cells)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sixteen_bit_depth_truncates_keeps_order_and_saturates_at_the_near_plane() {
        let one = 1i32 << 30;
        assert_eq!(Depth16::store(0), Depth16::ZERO);
        assert_eq!(Depth16::store(-5), Depth16::ZERO);
        assert_eq!(Depth16::store(one), Depth16::MAX);
        assert_eq!(Depth16::store(one + 12345), Depth16::MAX);
        assert_eq!(Depth16::store(one / 4), Depth16::from_num(0.25));
        // Truncation: never nearer than the true depth, off by less than 2^-16.
        let mut last = Depth16::ZERO;
        for q in (0..one).step_by(9973) {
            let z = Depth16::store(q);
            let back = DepthRow::Q16(&[z])
                .get(0)
                .map(|d| d.to_bits())
                .unwrap_or(-1);
            assert!(
                back <= q && q - back < 1 << DROPPED_BITS,
                "q {q} stored as {back}"
            );
            assert!(z >= last, "order kept");
            last = z;
        }
    }

    #[test]
    fn full_depth_is_stored_unchanged() {
        for q in [0, 1, 12345, 1 << 29, i32::MAX] {
            assert_eq!(Depth::store(q).to_bits(), q);
        }
        assert_eq!(
            DepthRow::Q30(&[Depth::from_bits(7)])
                .get(0)
                .map(Depth::to_bits),
            Some(7)
        );
        assert!(DepthRow::NONE.is_empty());
    }
}
