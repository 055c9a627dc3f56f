//! Animated metaball scenes as static data: each ball's centre at key frames, linear between
//! them, checked once by a `const fn` (so a scene exported by `sim export SCENE.meta` fails the
//! firmware's build, not its frame, when it is outside the envelope).
//!
//! ## Bit budget
//!
//! Key centres are [`KeyCoord`] (I8F24: ±128 with 24 fractional bits, an `i32`), so the
//! interpolated centre, rounded once to [`Coord`] (I16F16), is the exact linear interpolation
//! of the keys rounded to nearest (up to 2^-25 from the `.meta` file's value: the keys' own
//! rounding) rather than an interpolation of already rounded I16F16 keys (up to 1 LSB off).
//! [`Animation::new`] holds every key within ±[`MAX_COORD`](super::MAX_COORD) = 2^30 bits, so a
//! key difference is below 2^31 and its product with a frame offset (a `u32`, below 2^32) below
//! 2^63: the interpolation is exact `i64` arithmetic.

use super::{ball_in_envelope, Ball, Coord, MetaballError, Metaballs, DENSITY_LIMIT, MAX_BALLS};
use crate::math::zip3;
use embedded_graphics::pixelcolor::Rgb888;
use fixed::types::I8F24;

/// Key centres: I8F24 (range ±128, resolution 2^-24; the envelope uses ±64).
pub type KeyCoord = I8F24;

/// [`MAX_COORD`](super::MAX_COORD) as a key coordinate.
const KEY_LIMIT: KeyCoord = KeyCoord::lit("64");

/// A ball's centre at one frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BallKey {
    /// The frame.
    pub frame: u32,
    /// The centre at that frame.
    pub centre: [KeyCoord; 3],
}

/// A ball whose centre moves: linear between keys, the first key's before it and the last
/// key's after it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AnimatedBall<'a> {
    /// Keys in increasing frame order (at least one).
    pub keys: &'a [BallKey],
    /// Radius of influence `R`.
    pub radius: Coord,
    /// Density `q`; negative subtracts.
    pub density: Coord,
    /// Base colour.
    pub color: Rgb888,
}

impl AnimatedBall<'_> {
    /// The ball at `frame`. Exact within [`Animation::new`]'s envelope (see the module's bit
    /// budget); outside it the arithmetic wraps rather than panics.
    pub fn at(&self, frame: u32) -> Ball {
        let mut previous: Option<&BallKey> = None;
        let mut centre = [Coord::ZERO; 3];
        for key in self.keys {
            if key.frame >= frame {
                centre = match previous {
                    Some(p) if key.frame > p.frame => interpolate(
                        p,
                        key,
                        frame.saturating_sub(p.frame),
                        key.frame.saturating_sub(p.frame),
                    ),
                    _ => key.centre.map(round_key),
                };
                return self.ball(centre);
            }
            previous = Some(key);
        }
        if let Some(last) = previous {
            centre = last.centre.map(round_key);
        }
        self.ball(centre)
    }

    fn ball(&self, centre: [Coord; 3]) -> Ball {
        Ball {
            centre,
            radius: self.radius,
            density: self.density,
            color: self.color,
        }
    }
}

/// `a + (b − a)·offset/span` rounded to I16F16 (to nearest, halves up), in exact integers.
fn interpolate(a: &BallKey, b: &BallKey, offset: u32, span: u32) -> [Coord; 3] {
    let span = i64::from(span);
    zip3(a.centre, b.centre, |a, b| {
        let (start, end) = (i64::from(a.to_bits()), i64::from(b.to_bits()));
        let product = (end - start).wrapping_mul(i64::from(offset));
        // product / span = whole + rest / span with 0 ≤ rest < span (span > 0).
        let (whole, rest) = product
            .checked_div_euclid(span)
            .zip(product.checked_rem_euclid(span))
            .unwrap_or((0, 0));
        let bits = start.wrapping_add(whole);
        // bits + rest/span in 2^-24 units = 256·high + low + rest/span; round to 2^-16.
        let (high, low) = (bits >> 8, bits & 0xff);
        let up = low * span + rest >= 128 * span;
        Coord::from_bits((high + i64::from(up)) as i32)
    })
}

/// A key coordinate rounded to I16F16 (to nearest, halves up).
fn round_key(c: KeyCoord) -> Coord {
    Coord::from_bits(((i64::from(c.to_bits()) + 128) >> 8) as i32)
}

/// An animated scene: the balls and the threshold, checked.
#[derive(Clone, Copy, Debug)]
pub struct Animation<'a> {
    balls: &'a [AnimatedBall<'a>],
    threshold: Coord,
}

impl<'a> Animation<'a> {
    /// Checks every ball's keys (at least one, frames increasing, centres within
    /// ±[`MAX_COORD`](super::MAX_COORD)), radius and density, and the threshold, as
    /// [`Metaballs::new`] checks a frame's balls; every frame's balls are then inside the
    /// envelope (a centre between keys is between theirs).
    pub const fn new(
        balls: &'a [AnimatedBall<'a>],
        threshold: Coord,
    ) -> Result<Self, MetaballError> {
        if balls.is_empty() || balls.len() > MAX_BALLS {
            return Err(MetaballError::BallCount);
        }
        let mut index = 0;
        while index < balls.len() {
            let ball = &balls[index];
            if ball.keys.is_empty() {
                return Err(MetaballError::Keys { index });
            }
            let mut k = 0;
            while k < ball.keys.len() {
                let key = &ball.keys[k];
                if k > 0 && key.frame <= ball.keys[k - 1].frame {
                    return Err(MetaballError::Keys { index });
                }
                let mut axis = 0;
                while axis < 3 {
                    if key.centre[axis].to_bits().unsigned_abs() > KEY_LIMIT.to_bits() as u32 {
                        return Err(MetaballError::Ball { index });
                    }
                    axis += 1;
                }
                k += 1;
            }
            if !ball_in_envelope([Coord::ZERO; 3], ball.radius, ball.density) {
                return Err(MetaballError::Ball { index });
            }
            index += 1;
        }
        if threshold.to_bits() <= 0 || threshold.to_bits() > DENSITY_LIMIT.to_bits() {
            return Err(MetaballError::Threshold);
        }
        Ok(Animation { balls, threshold })
    }

    /// The balls.
    pub fn balls(&self) -> &'a [AnimatedBall<'a>] {
        self.balls
    }

    /// The threshold `T`.
    pub fn threshold(&self) -> Coord {
        self.threshold
    }

    /// The scene at `frame`: the balls written to the start of `out`, checked as
    /// [`Metaballs::new`] checks them. [`MetaballError::Capacity`] if `out` is shorter than
    /// [`Self::balls`].
    pub fn frame<'b>(
        &self,
        frame: u32,
        out: &'b mut [Ball],
    ) -> Result<Metaballs<'b>, MetaballError> {
        let count = self.balls.len();
        let out = out
            .get_mut(..count)
            .ok_or(MetaballError::Capacity { balls: count })?;
        for (slot, ball) in out.iter_mut().zip(self.balls) {
            *slot = ball.at(frame);
        }
        Metaballs::new(out, self.threshold)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const WHITE: Rgb888 = Rgb888::new(255, 255, 255);

    fn key(frame: u32, centre: [f64; 3]) -> BallKey {
        BallKey {
            frame,
            centre: centre.map(KeyCoord::from_num),
        }
    }

    fn ball(keys: &[BallKey]) -> AnimatedBall<'_> {
        AnimatedBall {
            keys,
            radius: Coord::ONE,
            density: Coord::ONE,
            color: WHITE,
        }
    }

    /// The exact interpolation of the keys' values, rounded to nearest I16F16 bits (halves
    /// up): `(x·n + (y − x)·k) / n` in 2^-24 units, in `i128`.
    fn expected(a: &BallKey, b: &BallKey, frame: u32) -> [i32; 3] {
        let (k, n) = (i128::from(frame - a.frame), i128::from(b.frame - a.frame));
        [0, 1, 2].map(|i| {
            let (x, y) = (
                i128::from(a.centre[i].to_bits()),
                i128::from(b.centre[i].to_bits()),
            );
            (x * n + (y - x) * k + 128 * n).div_euclid(256 * n) as i32
        })
    }

    #[test]
    fn interpolation_is_the_exact_value_rounded_once() {
        let mut rng = crate::test_rng::XorShift64::new(0x9e37_79b9_7f4a_7c15u64);
        let mut next = || rng.next_u64();
        for _ in 0..20_000 {
            let coord = |r: u64| ((r % 2_000_001) as f64 / 1e6 - 1.0) * 63.9;
            let f0 = (next() % 1000) as u32;
            let span = 1 + (next() % 999) as u32;
            let a = key(f0, [coord(next()), coord(next()), coord(next())]);
            let b = key(f0 + span, [coord(next()), coord(next()), coord(next())]);
            let keys = [a, b];
            let frame = f0 + (next() % u64::from(span + 1)) as u32;
            let got = ball(&keys).at(frame).centre.map(|c| c.to_bits());
            assert_eq!(got, expected(&a, &b, frame), "{a:?} {b:?} {frame}");
        }
    }

    #[test]
    fn extreme_keys_and_frames_do_not_overflow() {
        let keys = [
            key(0, [-64.0, 64.0, 0.0]),
            key(u32::MAX, [64.0, -64.0, 0.0]),
        ];
        let b = ball(&keys);
        assert_eq!(b.at(0).centre[0], Coord::from_num(-64));
        assert_eq!(b.at(u32::MAX).centre[0], Coord::from_num(64));
        let middle = b.at(u32::MAX / 2).centre;
        assert!(middle[0].abs() < Coord::from_num(0.001), "{middle:?}");
        assert_eq!(b.at(1234), ball(&keys).at(1234));
    }

    #[test]
    fn held_before_the_first_key_and_after_the_last() {
        let keys = [key(4, [1.0, 2.0, 3.0]), key(8, [5.0, 2.0, 3.0])];
        let b = ball(&keys);
        assert_eq!(b.at(0).centre, b.at(4).centre);
        assert_eq!(b.at(6).centre[0], Coord::from_num(3));
        assert_eq!(b.at(100).centre[0], Coord::from_num(5));
    }

    #[test]
    fn new_checks_keys_and_envelope() {
        let ok = [key(0, [0.0; 3]), key(4, [1.0, 0.0, 0.0])];
        let bad_order = [key(4, [0.0; 3]), key(4, [1.0, 0.0, 0.0])];
        let far = [key(0, [64.5, 0.0, 0.0])];
        let half = Coord::from_num(0.5);
        assert!(Animation::new(&[ball(&ok)], half).is_ok());
        assert_eq!(
            Animation::new(&[ball(&ok), ball(&[])], half).err(),
            Some(MetaballError::Keys { index: 1 })
        );
        assert_eq!(
            Animation::new(&[ball(&bad_order)], half).err(),
            Some(MetaballError::Keys { index: 0 })
        );
        assert_eq!(
            Animation::new(&[ball(&ok), ball(&far)], half).err(),
            Some(MetaballError::Ball { index: 1 })
        );
        let tiny = AnimatedBall {
            radius: Coord::from_num(0.01),
            ..ball(&ok)
        };
        assert_eq!(
            Animation::new(&[tiny], half).err(),
            Some(MetaballError::Ball { index: 0 })
        );
        assert_eq!(
            Animation::new(&[ball(&ok)], Coord::ZERO).err(),
            Some(MetaballError::Threshold)
        );
        assert_eq!(
            Animation::new(&[], half).err(),
            Some(MetaballError::BallCount)
        );
    }

    #[test]
    fn frame_fills_the_scene() {
        let keys = [key(0, [0.0; 3]), key(4, [1.0, 0.0, 0.0])];
        let balls = [ball(&keys), ball(&keys)];
        let animation = Animation::new(&balls, Coord::from_num(0.5)).unwrap();
        let mut out = [Ball::default(); 3];
        let scene = animation.frame(2, &mut out).unwrap();
        assert_eq!(scene.balls().len(), 2);
        assert_eq!(scene.balls()[1].centre[0], Coord::from_num(0.5));
        assert_eq!(
            animation.frame(2, &mut [Ball::default(); 1]).err(),
            Some(MetaballError::Capacity { balls: 2 })
        );
    }
}
