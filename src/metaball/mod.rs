//! Metaballs: an implicit surface `Σ qᵢ·f(rᵢ/Rᵢ) = T`, ray cast per pixel in fixed point.
//!
//! Each ball has a centre, a radius of influence `R`, a density `q` (negative subtracts) and a
//! colour. Its field is the degree-six polynomial in `s = r²/R²`
//!
//! ```text
//! f(s) = 1 − 22/9·s + 17/9·s² − 4/9·s³   for s < 1, 0 beyond,
//! ```
//!
//! the one polynomial in `r²` of degree six in `r` with `f(0) = 1, f'(0) = 0, f(R) = 0,
//! f'(R) = 0, f(R/2) = 1/2` (derivation in the repository's `docs/metaballs.md`). Along a ray
//! `s` is quadratic in the ray parameter, so the summed field is piecewise a polynomial of
//! degree six.
//!
//! [`Caster`] renders a [`Metaballs`] scene row by row into the crate's [`RowSink`](crate::sink::RowSink)s with
//! no frame buffer and no allocation: per pixel, a sphere-tracing march whose step is the
//! field's value over its Lipschitz bound (it never steps over a root), restricted to where the
//! ray crosses influence spheres.
//!
//! ## Scenes from `.meta` files
//!
//! `sim export SCENE.meta -o scene.rs` writes a scene as `static` data: the balls as
//! [`AnimatedBall`]s (centres at key frames in [`KeyCoord`], linear between), the threshold, the
//! frame count, the light, and `ANIMATION`, an [`Animation`] checked by a `const fn` when the
//! firmware is compiled. The firmware includes the file as a module and casts a frame (the
//! same with [`Polygonizer::polygonize`]):
//!
//! ```
//! use embedded_graphics::pixelcolor::{Rgb565, Rgb888};
//! use scanline3d::metaball::{
//!     AnimatedBall, Animation, Ball, BallKey, Caster, Coord, KeyCoord, MetaCamera,
//! };
//! use scanline3d::scene::Light;
//! use scanline3d::sink::HashSink;
//!
//! // What `sim export` writes, shortened: one ball moving from x = −1 to x = 1 in 8 frames.
//! const fn k(x: &str) -> [KeyCoord; 3] {
//!     [KeyCoord::lit(x), KeyCoord::ZERO, KeyCoord::ZERO]
//! }
//! static BALLS: [AnimatedBall<'static>; 1] = [AnimatedBall {
//!     keys: &[
//!         BallKey { frame: 0, centre: k("-1") },
//!         BallKey { frame: 8, centre: k("1") },
//!     ],
//!     radius: Coord::lit("1.5"),
//!     density: Coord::ONE,
//!     color: Rgb888::new(230, 77, 51),
//! }];
//! static ANIMATION: Animation<'static> = match Animation::new(&BALLS, Coord::lit("0.5")) {
//!     Ok(a) => a,
//!     Err(_) => panic!("outside the envelope"),
//! };
//!
//! let mut caster: Caster<Rgb565, 64, 1> = Caster::new(Rgb565::new(0, 0, 0));
//! let up = [0.0, 1.0, 0.0];
//! let camera = MetaCamera::new([0.0, 0.0, 5.0], [0.0; 3], up, 50.0, 0.1, 100.0, 64, 48)?;
//! let light = Light::new([0.4, 0.8, 0.6], 0.2, 0.8)?;
//! let mut balls = [Ball::default(); 1];
//! for frame in 0..8 {
//!     let scene = ANIMATION.frame(frame, &mut balls)?;
//!     let mut panel = HashSink::new();
//!     let stats = caster.render(&scene, &camera, &light, &mut panel).ok();
//!     assert!(stats.is_some_and(|s| s.hits > 0));
//! }
//! # Ok::<(), Box<dyn core::error::Error>>(())
//! ```
//!
//! ## Bit budget
//!
//! Scene data is [`Coord`] (I16F16); everything per ray is [`Wide`] (I32F32, an `i64`).
//! [`Metaballs::new`] enforces the envelope that keeps every product inside I32F32:
//!
//! | quantity | limit | why |
//! |---|---|---|
//! | centre coordinates, eye | ±[`MAX_COORD`] = 64 | eye–centre vector ≤ 2^8 per axis |
//! | radius `R` | [`MIN_RADIUS`] = 1/16 to [`MAX_RADIUS`] = 32 | `1/R²` ≤ 2^8 keeps 16 bits of `s` |
//! | density `|q|`, threshold `T` | ≤ [`MAX_DENSITY`] = 64, `T > 0` | field sum ≤ 64·`N` ≤ 2^12 |
//! | balls | ≤ `N` of the caster, ≤ 64 | field sum and its Lipschitz bound ≤ 2^20 |
//! | ray direction | `1 + tan(fovy/2)·(aspect + 1)` ≤ 16 per axis | `fovy` ≤ 120°, aspect ≤ 4 |
//!
//! With those, `|w × d|` ≤ 2^12 per axis and `|w × d|²` ≤ 3·2^24, below I32F32's 2^31; near ≥ 1/256 and far ≤ [`MAX_FAR`] = 1024 bound the ray parameter.

mod animation;
mod cast;
mod polygonize;

pub use animation::{AnimatedBall, Animation, BallKey, KeyCoord};
pub use cast::{CastError, CastStats, Caster, MetaCamera, EPSILON_T, MAX_STEPS};
pub use polygonize::{PolyMesh, PolyStats, PolygonizeError, Polygonizer, MAX_SAMPLES};

use crate::math::{mul_wide_u32, wide_by_unsigned, NO_WIDE_MULTIPLY};
use cast::quotient;
use embedded_graphics::pixelcolor::{Rgb888, RgbColor};
use fixed::types::{I16F16, I32F32};

/// Scene coordinates, radii, densities and the threshold: I16F16.
pub type Coord = I16F16;
/// Per-ray arithmetic: I32F32 (an `i64`; 31 integer bits for the products in the bit budget).
pub type Wide = I32F32;

/// Largest centre or eye coordinate (absolute value).
pub const MAX_COORD: f32 = 64.0;
/// Smallest radius of influence.
pub const MIN_RADIUS: f32 = 1.0 / 16.0;
/// Largest radius of influence.
pub const MAX_RADIUS: f32 = 32.0;
/// Largest density magnitude and threshold.
pub const MAX_DENSITY: f32 = 64.0;
/// Farthest far plane (eye depth).
pub const MAX_FAR: f32 = 1024.0;
/// Nearest near plane (eye depth).
pub const MIN_NEAR: f32 = 1.0 / 256.0;
/// Most balls in a scene.
pub const MAX_BALLS: usize = 64;

/// [`MAX_COORD`] in I16F16 (exact; a test checks), for the `const` checks.
const COORD_LIMIT: Coord = Coord::lit("64");
/// [`MAX_DENSITY`] in I16F16 (exact).
const DENSITY_LIMIT: Coord = Coord::lit("64");
/// [`MIN_RADIUS`] in I16F16 (exact).
const RADIUS_MIN: Coord = Coord::lit("0.0625");
/// [`MAX_RADIUS`] in I16F16 (exact).
const RADIUS_MAX: Coord = Coord::lit("32");

/// Whether a ball is inside the envelope of the module's bit budget (centre, radius, density).
const fn ball_in_envelope(centre: [Coord; 3], radius: Coord, density: Coord) -> bool {
    let limit = COORD_LIMIT.to_bits().unsigned_abs();
    let centre_ok = centre[0].to_bits().unsigned_abs() <= limit
        && centre[1].to_bits().unsigned_abs() <= limit
        && centre[2].to_bits().unsigned_abs() <= limit;
    let radius_ok =
        radius.to_bits() >= RADIUS_MIN.to_bits() && radius.to_bits() <= RADIUS_MAX.to_bits();
    centre_ok
        && radius_ok
        && density.to_bits().unsigned_abs() <= DENSITY_LIMIT.to_bits().unsigned_abs()
}

/// The field polynomial's coefficients in `s = r²/R²`, lowest power first: `f(s) = Σ cₖ sᵏ`.
pub const FIELD_COEFFICIENTS: [f64; 4] = [1.0, -22.0 / 9.0, 17.0 / 9.0, -4.0 / 9.0];

/// `max |df/dr|·R` over `0 ≤ r ≤ R` (1.58343 at `r ≈ 0.5035 R`), rounded up to 51/32: the field's Lipschitz
/// constant in units of `1/R`.
pub const FIELD_LIPSCHITZ: f64 = 1.59375;

/// [`FIELD_LIPSCHITZ`] in I32F32 (exact: 51/32).
const FIELD_LIPSCHITZ_WIDE: Wide = Wide::lit("1.59375");

/// One ball (the default: all zero, black; outside the envelope until set).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Ball {
    /// Centre (world).
    pub centre: [Coord; 3],
    /// Radius of influence `R`: the field is 0 from here on.
    pub radius: Coord,
    /// Density `q`; negative subtracts.
    pub density: Coord,
    /// Base colour.
    pub color: Rgb888,
}

impl Ball {
    /// A ball from `f32` values (converted to I16F16, rounding to nearest; out-of-range values
    /// saturate and NaN becomes 0, so [`Metaballs::new`] rejects them or sees a valid number).
    pub fn new(centre: [f32; 3], radius: f32, density: f32, color: Rgb888) -> Self {
        Ball {
            centre: centre.map(coord_from_f32),
            radius: coord_from_f32(radius),
            density: coord_from_f32(density),
            color,
        }
    }
}

/// `f32` to I16F16 without a panic path (`saturating_from_num` panics on NaN).
fn coord_from_f32(v: f32) -> Coord {
    Coord::checked_from_num(v).unwrap_or(if v > 0.0 {
        Coord::MAX
    } else if v < 0.0 {
        Coord::MIN
    } else {
        Coord::ZERO
    })
}

/// `f32` to I32F32 without a panic path (`saturating_from_num` panics on NaN).
pub(crate) fn wide_from_f32(v: f32) -> Wide {
    Wide::checked_from_num(v).unwrap_or(if v > 0.0 {
        Wide::MAX
    } else if v < 0.0 {
        Wide::MIN
    } else {
        Wide::ZERO
    })
}

/// Why a metaball scene was rejected.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MetaballError {
    /// No balls, or more than [`MAX_BALLS`].
    BallCount,
    /// Ball `index` is outside the envelope (centre, radius or density).
    Ball {
        /// Index of the ball in the slice.
        index: usize,
    },
    /// The threshold is not in `(0, MAX_DENSITY]`.
    Threshold,
    /// Ball `index` of an [`Animation`] has no keys, or key frames that do not increase.
    Keys {
        /// Index of the ball in the slice.
        index: usize,
    },
    /// The slice given to [`Animation::frame`] is shorter than the animation's `balls`.
    Capacity {
        /// Balls in the animation.
        balls: usize,
    },
    /// A degenerate camera (eye = target, up along the view), a field of view outside
    /// (0°, 120°], near/far outside [`MIN_NEAR`]..[`MAX_FAR`], a target wider than 4:1 or
    /// larger than 2048 per side, or an eye outside ±[`MAX_COORD`].
    Camera,
}

impl core::fmt::Display for MetaballError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            MetaballError::BallCount => write!(f, "a metaball scene holds 1 to {MAX_BALLS} balls"),
            MetaballError::Ball { index } => write!(
                f,
                "ball {index}: centre within ±{MAX_COORD}, radius {MIN_RADIUS}..{MAX_RADIUS}, |density| ≤ {MAX_DENSITY}"
            ),
            MetaballError::Threshold => write!(f, "threshold must be in (0, {MAX_DENSITY}]"),
            MetaballError::Keys { index } => {
                write!(f, "ball {index}: keys must be one or more, in increasing frame order")
            }
            MetaballError::Capacity { balls } => write!(f, "room for fewer than {balls} balls"),
            MetaballError::Camera => write!(f, "camera outside the metaball caster's envelope"),
        }
    }
}

impl core::error::Error for MetaballError {}

/// A checked metaball scene: balls borrowed (from flash or a frame's stack) and the threshold.
#[derive(Clone, Copy, Debug)]
pub struct Metaballs<'a> {
    balls: &'a [Ball],
    threshold: Coord,
}

impl<'a> Metaballs<'a> {
    /// Checks the envelope of the module's bit budget.
    pub fn new(balls: &'a [Ball], threshold: Coord) -> Result<Self, MetaballError> {
        if balls.is_empty() || balls.len() > MAX_BALLS {
            return Err(MetaballError::BallCount);
        }
        for (index, b) in balls.iter().enumerate() {
            if !ball_in_envelope(b.centre, b.radius, b.density) {
                return Err(MetaballError::Ball { index });
            }
        }
        if threshold <= Coord::ZERO || threshold > DENSITY_LIMIT {
            return Err(MetaballError::Threshold);
        }
        Ok(Metaballs { balls, threshold })
    }

    /// The balls.
    pub fn balls(&self) -> &'a [Ball] {
        self.balls
    }

    /// The threshold `T`.
    pub fn threshold(&self) -> Coord {
        self.threshold
    }
}

/// The I32F32 product, rounded down as `fixed`'s `*` rounds it, from 32×32-bit partial
/// products: `fixed` widens I32F32 products to `i128`, a slow library call on 32-bit targets.
/// Wraps where `*` would overflow; the module's bit budget keeps every product in range.
#[inline(always)]
pub(crate) fn mul(a: Wide, b: Wide) -> Wide {
    if NO_WIDE_MULTIPLY {
        return Wide::from_bits(mul_in_words(a.to_bits(), b.to_bits()));
    }
    let (a, b) = (a.to_bits(), b.to_bits());
    let (a_high, a_low) = (a >> 32, i64::from(a as u32));
    let (b_high, b_low) = (b >> 32, i64::from(b as u32));
    // a·b = a_high·b_high·2^64 + (a_high·b_low + a_low·b_high)·2^32 + a_low·b_low.
    let low = ((a_low as u64).wrapping_mul(b_low as u64) >> 32) as i64;
    Wide::from_bits(
        (a_high.wrapping_mul(b_high) << 32)
            .wrapping_add(a_high.wrapping_mul(b_low))
            .wrapping_add(a_low.wrapping_mul(b_high))
            .wrapping_add(low),
    )
}

/// [`mul`]'s bits from 32 × 32-bit products, for cores without a 32 × 32 → 64-bit multiply
/// (ARMv6-M, where each of [`mul`]'s four `i64` products is a library call): `ah·bh` only for
/// its low word (shifted out of `i64` otherwise), `ah·bl` and `bh·al` as signed by unsigned
/// products, `al·bl` for its high word, each in 16-bit halves. The same bits (test
/// `mul_in_words_is_mul`).
#[inline(always)]
fn mul_in_words(a: i64, b: i64) -> i64 {
    let (ah, al) = ((a >> 32) as i32, a as u32);
    let (bh, bl) = ((b >> 32) as i32, b as u32);
    let low = (mul_wide_u32(al, bl) >> 32) as i64;
    let cross = wide_by_unsigned(ah, bl).wrapping_add(wide_by_unsigned(bh, al));
    (i64::from(ah.wrapping_mul(bh)) << 32)
        .wrapping_add(cross)
        .wrapping_add(low)
}

/// `f(s)` in I32F32 for `0 ≤ s < 1` (Horner; every partial sum within ±3).
#[inline]
fn field(s: Wide) -> Wide {
    let c = field_coefficients();
    mul(mul(mul(c[3], s) + c[2], s) + c[1], s) + c[0]
}

/// `df/ds` in I32F32 for `0 ≤ s < 1`.
#[inline]
fn field_slope(s: Wide) -> Wide {
    let c = field_coefficients();
    mul(
        mul(c[3], Wide::from_num(3) * s) + c[2] * Wide::from_num(2),
        s,
    ) + c[1]
}

/// [`FIELD_COEFFICIENTS`] in I32F32. A `const`, so the literals are parsed at compile time
/// (`lit` in a plain function body would parse them on every call).
const FIELD_WIDE: [Wide; 4] = [
    Wide::ONE,
    Wide::lit("-2.444444444444444444"),
    Wide::lit("1.888888888888888889"),
    Wide::lit("-0.444444444444444444"),
];

/// [`FIELD_COEFFICIENTS`] in I32F32.
#[inline(always)]
fn field_coefficients() -> [Wide; 4] {
    FIELD_WIDE
}

/// The colour and id at a surface point: the colours of the balls with positive `q·f` there,
/// weighted by it, and the ball with the largest `q·f`.
pub(crate) struct Blend {
    best: (Wide, u8),
    weight: Wide,
    rgb: [Wide; 3],
}

impl Blend {
    pub(crate) fn new() -> Self {
        Blend {
            best: (Wide::MIN, 0),
            weight: Wide::ZERO,
            rgb: [Wide::ZERO; 3],
        }
    }

    /// Adds ball `index`'s `q·f` and colour.
    pub(crate) fn add(&mut self, contribution: Wide, index: usize, color: Rgb888) {
        if contribution > self.best.0 {
            self.best = (contribution, u8::try_from(index).unwrap_or(u8::MAX));
        }
        if contribution > Wide::ZERO {
            self.weight += contribution;
            for (acc, channel) in self.rgb.iter_mut().zip([color.r(), color.g(), color.b()]) {
                *acc += contribution.saturating_mul_int(i64::from(channel));
            }
        }
    }

    /// The blended colour times `intensity` (at most 1) and the largest ball; `colors` are the
    /// balls' colours, for a point with no positive contribution (the largest ball's then).
    pub(crate) fn finish(
        &self,
        intensity: Wide,
        mut colors: impl Iterator<Item = Rgb888>,
    ) -> (Rgb888, u8) {
        let fallback = colors
            .nth(usize::from(self.best.1))
            .unwrap_or(Rgb888::BLACK);
        let inv_weight = quotient(Wide::ONE, self.weight);
        let channel = |i: usize, fallback: u8| -> u8 {
            let base = self
                .rgb
                .get(i)
                .zip(inv_weight)
                .map(|(acc, inv)| *acc * inv)
                .unwrap_or(Wide::from_num(fallback));
            let v = (base * intensity).round().to_num::<i64>();
            v.clamp(0, 255) as u8
        };
        let color = Rgb888::new(
            channel(0, fallback.r()),
            channel(1, fallback.g()),
            channel(2, fallback.b()),
        );
        (color, self.best.1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn f64_field(s: f64) -> f64 {
        FIELD_COEFFICIENTS
            .iter()
            .rev()
            .fold(0.0, |acc, c| acc * s + c)
    }

    #[test]
    fn five_conditions() {
        // f(0) = 1, f(R) = 0, f(R/2) = 1/2 (s = 1/4); f'(0) = 0 holds for any polynomial in r²;
        // f'(R) = df/ds · 2r/R² = 0 needs df/ds(1) = 0.
        assert!((f64_field(0.0) - 1.0).abs() < 1e-15);
        assert!(f64_field(1.0).abs() < 1e-15);
        assert!((f64_field(0.25) - 0.5).abs() < 1e-15);
        let slope1 =
            FIELD_COEFFICIENTS[1] + 2.0 * FIELD_COEFFICIENTS[2] + 3.0 * FIELD_COEFFICIENTS[3];
        assert!(slope1.abs() < 1e-15);
    }

    #[test]
    fn lipschitz_constant_bounds_the_slope() {
        assert_eq!(FIELD_LIPSCHITZ_WIDE.to_num::<f64>(), FIELD_LIPSCHITZ);
        let mut max = 0.0f64;
        for i in 0..=100_000 {
            let x = i as f64 / 100_000.0;
            let s = x * x;
            let dfds = FIELD_COEFFICIENTS[1]
                + 2.0 * FIELD_COEFFICIENTS[2] * s
                + 3.0 * FIELD_COEFFICIENTS[3] * s * s;
            max = max.max((dfds * 2.0 * x).abs());
        }
        assert!(
            max <= FIELD_LIPSCHITZ && max > FIELD_LIPSCHITZ - 0.02,
            "{max}"
        );
    }

    #[test]
    fn fixed_field_matches_f64() {
        for i in 0..=64 {
            let s = i as f64 / 64.0;
            let fx = field(Wide::from_num(s)).to_num::<f64>();
            assert!((fx - f64_field(s)).abs() < 1e-8, "{s}");
            let dfds = FIELD_COEFFICIENTS[1]
                + 2.0 * FIELD_COEFFICIENTS[2] * s
                + 3.0 * FIELD_COEFFICIENTS[3] * s * s;
            assert!((field_slope(Wide::from_num(s)).to_num::<f64>() - dfds).abs() < 1e-8);
        }
    }

    #[test]
    fn mul_in_words_is_mul() {
        // `mul` without the ARMv6-M branch: the four i64 products, wrapping.
        fn wide(a: i64, b: i64) -> i64 {
            let (ah, al) = (a >> 32, i64::from(a as u32));
            let (bh, bl) = (b >> 32, i64::from(b as u32));
            let low = ((al as u64).wrapping_mul(bl as u64) >> 32) as i64;
            (ah.wrapping_mul(bh) << 32)
                .wrapping_add(ah.wrapping_mul(bl))
                .wrapping_add(al.wrapping_mul(bh))
                .wrapping_add(low)
        }
        let mut rng = crate::test_rng::XorShift64::new(0x0f1e_2d3c_4b5a_6978u64);
        let edges = [
            0,
            1,
            -1,
            i64::MAX,
            i64::MIN,
            u32::MAX as i64,
            -(1i64 << 32),
            1 << 32,
        ];
        for a in edges {
            for b in edges {
                assert_eq!(mul_in_words(a, b), wide(a, b), "{a} × {b}");
            }
        }
        for k in 0..400_000u32 {
            let x = rng.next_u64();
            let a = (x as i64) >> (k % 64);
            let b = (rng.next_u64() as i64) >> (x % 64);
            assert_eq!(mul_in_words(a, b), wide(a, b), "{a} × {b}");
            assert_eq!(
                mul(Wide::from_bits(a), Wide::from_bits(b)).to_bits(),
                wide(a, b)
            );
        }
    }

    #[test]
    fn mul_is_fixeds_product() {
        let mut rng = crate::test_rng::XorShift64::new(0x1234_5678_9abc_def1u64);
        let mut next = || {
            let x = rng.next_u64();
            // Magnitudes from 2^-32 to 2^15, both signs.
            (x as i64) >> (x % 48)
        };
        for _ in 0..100_000 {
            let (a, b) = (Wide::from_bits(next()), Wide::from_bits(next()));
            if let Some(exact) = a.checked_mul(b) {
                assert_eq!(mul(a, b), exact, "{a} × {b}");
            }
        }
    }

    #[test]
    fn const_limits_are_the_documented_ones() {
        assert_eq!(COORD_LIMIT, Coord::from_num(MAX_COORD));
        assert_eq!(DENSITY_LIMIT, Coord::from_num(MAX_DENSITY));
        assert_eq!(RADIUS_MIN, Coord::from_num(MIN_RADIUS));
        assert_eq!(RADIUS_MAX, Coord::from_num(MAX_RADIUS));
    }

    #[test]
    fn envelope_is_checked() {
        let ok = Ball::new([0.0; 3], 1.0, 1.0, Rgb888::new(1, 2, 3));
        assert!(Metaballs::new(&[ok], Coord::from_num(0.5)).is_ok());
        assert_eq!(
            Metaballs::new(&[], Coord::ONE).err(),
            Some(MetaballError::BallCount)
        );
        let far = Ball::new([65.0, 0.0, 0.0], 1.0, 1.0, Rgb888::new(1, 2, 3));
        assert_eq!(
            Metaballs::new(&[ok, far], Coord::ONE).err(),
            Some(MetaballError::Ball { index: 1 })
        );
        let tiny = Ball::new([0.0; 3], 0.01, 1.0, Rgb888::new(1, 2, 3));
        assert_eq!(
            Metaballs::new(&[tiny], Coord::ONE).err(),
            Some(MetaballError::Ball { index: 0 })
        );
        assert_eq!(
            Metaballs::new(&[ok], Coord::ZERO).err(),
            Some(MetaballError::Threshold)
        );
    }
}
