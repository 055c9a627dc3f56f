//! The fixed-point metaball ray caster: one pixel-centre ray per pixel, rows to a sink.
//!
//! Per ray and ball, `s(t) = A·(t − t_c)² + s_min` (closest approach `t_c`, `s_min` from the
//! cross product, so no cancellation) gives the influence interval `|t − t_c| < √((1 − s_min)/A)`.
//! The march starts at the near plane and steps `|g(t)| / L(t)`, where `g` is the summed field
//! minus `T` and `L` the sum over the balls active at `t` of their slope bounds along the ray,
//! `|q|·FIELD_LIPSCHITZ·|d|/R·(1 − s_min)^{3/2}` (a ray through the edge of a ball's influence
//! sees only a little of its slope); steps stop at the next ball's entry, so `L` bounds `|g'|`
//! over every step and a step never passes a root. The hit is where the step falls below
//! [`EPSILON_T`]. After 16 steps a ray also takes the field's curvature's step (`M` bounding
//! `|g''|`, the parabola `|g| + σ·g'·h − M·h²/2` keeps the sign up to its first root), which
//! near a tangent graze, where `g'` is small, is `√(2|g|/M)` instead of `|g|/L`. A ray still
//! marching after [`MAX_STEPS`] is counted as a miss and reported in [`CastStats::capped`].

use super::{
    field, field_slope, mul, wide_from_f32, Ball, Blend, MetaballError, Metaballs, Wide,
    FIELD_LIPSCHITZ_WIDE,
};
use super::{MAX_COORD, MAX_FAR, MIN_NEAR};
use crate::depth::{Depth, DepthRow};
use crate::math::zip3;
use crate::scene::Light;
use crate::sink::{Row, RowPixel, RowSink};
use embedded_graphics::pixelcolor::{Rgb888, RgbColor};

/// The march stops when a step is shorter than this (eye-depth units, 2^-14): the hit is then
/// at most `EPSILON_T · L / |g'|` in front of the surface (see `docs/metaballs.md`).
pub const EPSILON_T: Wide = Wide::from_bits(1 << (32 - 14));
/// Most march steps per ray.
pub const MAX_STEPS: u32 = 1024;
/// Steps of a ray after which the march also takes the curvature's step
/// ([`Frame::curved_step`]): the rays that need it are the long ones, near tangent grazes.
const CURVED_AFTER: u32 = 16;
/// Densities, `A`, `|g|`, `|g'|` and `M` below this keep the curvature step's products in
/// I32F32 (2^12: `M·|g| < 2^27`, `g'² < 2^24`).
const CURVED_LIMIT: Wide = Wide::from_bits(1 << (32 + 12));
/// `|f''(s)|·4z + 2|f'(s)|` for `0 ≤ z ≤ s < 1` is at most `(44 + 68s − 72s²)/9 ≤ 6.673`, so a
/// ball's `|d²(q·f(s))/dt²|` along a ray, `|q|·A·(|f''|·4A·u² + 2|f'|)`, is at most
/// `|q|·A·6.6875`.
const FIELD_CURVATURE_WIDE: Wide = Wide::lit("6.6875");

/// A perspective camera for the caster (`gluLookAt` + `gluPerspective`, pixel centres at
/// `(c + ½, r + ½)`); the ray direction's component along the view axis is 1, so the ray
/// parameter is the eye depth.
#[derive(Clone, Copy, Debug)]
pub struct MetaCamera {
    eye: [Wide; 3],
    /// Direction through the centre of pixel (0, 0).
    corner: [Wide; 3],
    /// Direction change per column and per row.
    per_column: [Wide; 3],
    per_row: [Wide; 3],
    near: Wide,
    far: Wide,
    width: u16,
    height: u16,
}

fn sub3(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn cross3(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn unit3(a: [f32; 3]) -> Option<[f32; 3]> {
    let l = libm::sqrtf(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    (l > 1e-6 && l.is_finite()).then(|| a.map(|c| c / l))
}
fn wide3(a: [f32; 3]) -> [Wide; 3] {
    a.map(wide_from_f32)
}

impl MetaCamera {
    /// A camera looking from `eye` at `target` on a `width × height` target.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        eye: [f32; 3],
        target: [f32; 3],
        up: [f32; 3],
        fovy_degrees: f32,
        near: f32,
        far: f32,
        width: u16,
        height: u16,
    ) -> Result<Self, MetaballError> {
        let bad = MetaballError::Camera;
        let in_envelope = fovy_degrees > 0.0
            && fovy_degrees <= 120.0
            && near >= MIN_NEAR
            && near < far
            && far <= MAX_FAR
            && (1..=2048).contains(&width)
            && (1..=2048).contains(&height)
            && u32::from(width) <= 4 * u32::from(height)
            && eye.iter().all(|c| c.abs() <= MAX_COORD);
        if !in_envelope {
            return Err(bad);
        }
        let forward = unit3(sub3(target, eye)).ok_or(bad)?;
        let side = unit3(cross3(forward, up)).ok_or(bad)?;
        let up = cross3(side, forward);
        let tan_half = libm::tanf(fovy_degrees.to_radians() / 2.0);
        let (w, h) = (f32::from(width), f32::from(height));
        let sx = 2.0 * tan_half * w / h / w;
        let sy = 2.0 * tan_half / h;
        let x0 = (0.5 / w * 2.0 - 1.0) * tan_half * w / h;
        let y0 = (1.0 - 0.5 / h * 2.0) * tan_half;
        let corner = zip3(zip3(forward, side, |f, s| f + s * x0), up, |fs, u| {
            fs + u * y0
        });
        Ok(MetaCamera {
            eye: wide3(eye),
            corner: wide3(corner),
            per_column: wide3(side.map(|c| c * sx)),
            per_row: wide3(up.map(|c| -c * sy)),
            near: wide_from_f32(near),
            far: wide_from_f32(far),
            width,
            height,
        })
    }

    /// Target width in pixels.
    pub fn width(&self) -> u16 {
        self.width
    }

    /// Target height in pixels.
    pub fn height(&self) -> u16 {
        self.height
    }

    /// The ray direction through the centre of pixel `(column, row)`.
    fn direction(&self, column: u16, row: u16) -> [Wide; 3] {
        let (column, row) = (i64::from(column), i64::from(row));
        let across = zip3(self.corner, self.per_column, |c, s| {
            c + s.saturating_mul_int(column)
        });
        zip3(across, self.per_row, |a, s| a + s.saturating_mul_int(row))
    }
}

/// What a frame did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CastStats {
    /// Rows sent to the sink.
    pub rows: u32,
    /// Pixels whose ray hit the surface.
    pub hits: u32,
    /// March steps over the frame.
    pub steps: u64,
    /// Most steps of one ray.
    pub max_steps: u32,
    /// Rays stopped after [`MAX_STEPS`] and drawn as background.
    pub capped: u32,
    /// The pixel `(column, row)` of the last of those, if any.
    pub last_capped: Option<(u16, u16)>,
}

/// Why a frame stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CastError<E> {
    /// The scene holds more balls than the caster's `N`.
    Capacity,
    /// The camera is wider than the caster's `W`.
    Width,
    /// The sink failed; rows after the failing one were not sent.
    Sink(E),
}

/// Per ball and frame: the values every ray reuses.
#[derive(Clone, Copy, Debug)]
struct FrameBall {
    /// Centre minus eye.
    offset: [Wide; 3],
    r2: Wide,
    inv_r2: Wide,
    density: Wide,
    /// `|q|·FIELD_LIPSCHITZ/R`: the slope bound per unit of ray length.
    slope_bound: Wide,
    color: Rgb888,
}

impl FrameBall {
    const EMPTY: FrameBall = FrameBall {
        offset: [Wide::ZERO; 3],
        r2: Wide::ZERO,
        inv_r2: Wide::ZERO,
        density: Wide::ZERO,
        slope_bound: Wide::ZERO,
        color: Rgb888::BLACK,
    };
}

/// Per ball and ray: the quadratic `s(t)` and its influence interval.
#[derive(Clone, Copy, Debug)]
struct RayBall {
    ball: u8,
    closest: Wide,
    a: Wide,
    s_min: Wide,
    enter: Wide,
    exit: Wide,
    lipschitz: Wide,
}

impl RayBall {
    const EMPTY: RayBall = RayBall {
        ball: 0,
        closest: Wide::ZERO,
        a: Wide::ZERO,
        s_min: Wide::ZERO,
        enter: Wide::ZERO,
        exit: Wide::ZERO,
        lipschitz: Wide::ZERO,
    };

    /// `s(t)`, or `None` outside the influence sphere.
    #[inline]
    fn s(&self, t: Wide) -> Option<Wide> {
        // Inside the (padded) interval A·u² ≤ 1 + 2^-12, so the products stay small.
        if t < self.enter || t >= self.exit {
            return None;
        }
        let u = t - self.closest;
        let s = mul(self.a, mul(u, u)) + self.s_min;
        (s < Wide::ONE).then_some(s)
    }
}

/// Integer square root of `x` (floor). Out of line: the curvature's step would inline two more
/// copies (thumbv7em firmware image 31,420 → 30,816 B, thumbv6m 40,960 → 40,208 B).
#[inline(never)]
fn isqrt(x: u64) -> u64 {
    let mut r = 0u64;
    let mut bit = 1u64 << 62;
    let mut x = x;
    while bit > x {
        bit >>= 2;
    }
    while bit != 0 {
        if x >= r + bit {
            x -= r + bit;
            r = (r >> 1) + bit;
        } else {
            r >>= 1;
        }
        bit >>= 2;
    }
    r
}

/// `√x` for `x ≥ 0` in I32F32 (16 fractional bits exact).
fn sqrt_wide(x: Wide) -> Wide {
    Wide::from_bits((isqrt(x.to_bits().max(0) as u64) << 16) as i64)
}

fn dot(a: [Wide; 3], b: [Wide; 3]) -> Wide {
    mul(a[0], b[0]) + mul(a[1], b[1]) + mul(a[2], b[2])
}

/// The ray caster's memory: one row of pixels and depth, per-frame ball data for up to `N`
/// balls. `W·(size_of::<P>() + 4) + N·48` bytes plus `N·56` bytes of stack per ray.
pub struct Caster<P, const W: usize, const N: usize> {
    pixels: [P; W],
    depth: [Depth; W],
    balls: [FrameBall; N],
    background: P,
}

impl<P: RowPixel, const W: usize, const N: usize> Caster<P, W, N> {
    /// A caster drawing `background` where no ray hits.
    pub const fn new(background: P) -> Self {
        Caster {
            pixels: [background; W],
            depth: [Depth::ZERO; W],
            balls: [FrameBall::EMPTY; N],
            background,
        }
    }

    /// Renders one frame: rows top to bottom to `sink`.
    pub fn render<S: RowSink<P>>(
        &mut self,
        scene: &Metaballs<'_>,
        camera: &MetaCamera,
        light: &Light,
        sink: &mut S,
    ) -> Result<CastStats, CastError<S::Error>> {
        let width = usize::from(camera.width);
        if width > W {
            return Err(CastError::Width);
        }
        let count = scene.balls().len();
        if count > N {
            return Err(CastError::Capacity);
        }
        for (slot, ball) in self.balls.iter_mut().zip(scene.balls()) {
            *slot = frame_ball(ball, camera);
        }
        let frame = Frame {
            balls: self.balls.get(..count).unwrap_or(&[]),
            threshold: Wide::from(scene.threshold()),
            camera,
            light: Lighting::new(light),
        };
        let mut stats = CastStats::default();
        for row in 0..camera.height {
            // Only the camera's columns: a caster may be wider than the frame.
            for (column, (pixel, depth)) in self
                .pixels
                .iter_mut()
                .zip(self.depth.iter_mut())
                .take(width)
                .enumerate()
            {
                let shade = frame.pixel::<N>(column as u16, row, &mut stats);
                match shade {
                    Some(hit) => {
                        *pixel = P::from_shade(hit.color, u32::from(hit.ball));
                        *depth = hit.depth;
                        stats.hits += 1;
                    }
                    None => {
                        *pixel = self.background;
                        *depth = Depth::ZERO;
                    }
                }
            }
            sink.write_row(Row {
                y: row,
                pixels: self.pixels.get(..width).unwrap_or(&[]),
                depth: DepthRow::Q30(self.depth.get(..width).unwrap_or(&[])),
                complete: true,
            })
            .map_err(CastError::Sink)?;
            stats.rows += 1;
        }
        Ok(stats)
    }
}

fn frame_ball(ball: &Ball, camera: &MetaCamera) -> FrameBall {
    let radius = Wide::from(ball.radius);
    let density = Wide::from(ball.density);
    let centre = ball.centre.map(Wide::from);
    FrameBall {
        offset: zip3(centre, camera.eye, |c, e| c - e),
        r2: radius * radius,
        inv_r2: Wide::ONE.checked_div(radius * radius).unwrap_or(Wide::ZERO),
        density,
        slope_bound: (density.abs() * FIELD_LIPSCHITZ_WIDE)
            .checked_div(radius)
            .unwrap_or(Wide::MAX),
        color: ball.color,
    }
}

/// The light in I32F32.
struct Lighting {
    direction: [Wide; 3],
    ambient: Wide,
    diffuse: Wide,
}

impl Lighting {
    fn new(light: &Light) -> Self {
        Lighting {
            direction: wide3(light.direction()),
            ambient: wide_from_f32(light.ambient()),
            diffuse: wide_from_f32(light.diffuse()),
        }
    }
}

/// A shaded hit.
struct Hit {
    color: Rgb888,
    ball: u8,
    depth: Depth,
}

struct Frame<'a> {
    balls: &'a [FrameBall],
    threshold: Wide,
    camera: &'a MetaCamera,
    light: Lighting,
}

/// The field sum minus `T` at `t`, the slope bound of the active balls, the next entry after
/// `t`, and the positive density of the active balls.
struct Sample {
    g: Wide,
    lipschitz: Wide,
    next_entry: Option<Wide>,
    positive: Wide,
}

impl Frame<'_> {
    fn pixel<const N: usize>(&self, column: u16, row: u16, stats: &mut CastStats) -> Option<Hit> {
        let d = self.camera.direction(column, row);
        let dd = dot(d, d);
        let length = sqrt_wide(dd);
        let inv_dd = reciprocal(dd)?;
        let mut rays = [RayBall::EMPTY; N];
        let mut count = 0usize;
        for (index, ball) in self.balls.iter().enumerate() {
            if let Some(ray) = ray_ball(ball, index, d, dd, inv_dd, length) {
                if let Some(slot) = rays.get_mut(count) {
                    *slot = ray;
                    count += 1;
                }
            }
        }
        let rays = rays.get(..count).unwrap_or(&[]);
        let mut t = self.camera.near;
        let first = self.sample(rays, t);
        let inside = first.g > Wide::ZERO;
        let mut steps = 0u32;
        let mut found = false;
        while steps < MAX_STEPS && t <= self.camera.far {
            let s = self.sample(rays, t);
            if (s.g > Wide::ZERO) != inside || s.g == Wide::ZERO {
                found = true;
                break;
            }
            steps += 1;
            // Outside with too little positive density active: nothing until the next entry.
            if !inside && s.positive <= self.threshold {
                match s.next_entry {
                    Some(next) => {
                        t = next;
                        continue;
                    }
                    None => break,
                }
            }
            let mut safe = quotient(s.g.abs(), s.lipschitz).unwrap_or(Wide::MAX);
            if safe < EPSILON_T {
                found = true;
                break;
            }
            if steps > CURVED_AFTER {
                safe = safe.max(self.curved_step(rays, t, s.g));
            }
            // Stopping at the next entry keeps that ball's slope out of this step.
            let step = s.next_entry.map_or(safe, |next| safe.min(next - t));
            t = t.saturating_add(step);
        }
        stats.steps += u64::from(steps);
        stats.max_steps = stats.max_steps.max(steps);
        if !found {
            if steps >= MAX_STEPS {
                stats.capped += 1;
                stats.last_capped = Some((column, row));
            }
            return None;
        }
        if t > self.camera.far {
            return None;
        }
        self.shade(rays, d, t, inside)
    }

    fn sample(&self, rays: &[RayBall], t: Wide) -> Sample {
        let mut sample = Sample {
            g: -self.threshold,
            lipschitz: Wide::ZERO,
            next_entry: None,
            positive: Wide::ZERO,
        };
        for ray in rays {
            if ray.enter > t {
                sample.next_entry = Some(sample.next_entry.map_or(ray.enter, |n| n.min(ray.enter)));
                continue;
            }
            if ray.exit <= t {
                continue;
            }
            let Some(ball) = self.balls.get(usize::from(ray.ball)) else {
                continue;
            };
            sample.lipschitz += ray.lipschitz;
            if ball.density > Wide::ZERO {
                sample.positive += ball.density;
            }
            if let Some(s) = ray.s(t) {
                sample.g += mul(ball.density, field(s));
            }
        }
        sample
    }

    /// A step from `t` (field value `g`) that passes no root by the field's curvature: with
    /// `σ = sign(g)`, `σ·g(t + h) ≥ |g| + σ·g'·h − M·h²/2` (Taylor, `M` bounding `|g''|` over
    /// the active balls, `g` being C¹ where a ball's influence ends), so no root lies before the
    /// parabola's first root `h = (σg' + √(g'² + 2M|g|))/M = 2|g|/(√(g'² + 2M|g|) − σg')`.
    /// Every rounding makes `h` smaller; 0 where the bound does not fit the formats. Near a
    /// tangent graze (`g' ≈ 0`) this is `√(2|g|/M)`, far longer than `|g|/L`.
    fn curved_step(&self, rays: &[RayBall], t: Wide, g: Wide) -> Wide {
        let (mut slope, mut curvature, mut count) = (Wide::ZERO, Wide::ZERO, 0i64);
        for ray in rays {
            if ray.enter > t || ray.exit <= t {
                continue;
            }
            let Some(ball) = self.balls.get(usize::from(ray.ball)) else {
                continue;
            };
            count += 1;
            let density = ball.density.abs();
            if density >= CURVED_LIMIT || ray.a >= CURVED_LIMIT {
                return Wide::ZERO;
            }
            // Rounded up by one step of the product's truncation. Each term is below 2^27, so
            // stopping once the sum reaches 2^12 keeps it from wrapping.
            curvature += mul(mul(density, ray.a), FIELD_CURVATURE_WIDE) + Wide::DELTA;
            if curvature >= CURVED_LIMIT {
                return Wide::ZERO;
            }
            if let Some(s) = ray.s(t) {
                // d(q·f(s))/dt = q·f'(s)·2A·u.
                let au = mul(ray.a, t - ray.closest);
                slope += mul(mul(ball.density, field_slope(s)), au + au);
            }
        }
        // What the products' truncations can move g' and g by, per ball, with room to spare.
        let (slope_slack, g_slack) = (
            Wide::from_bits(count << (32 - 14)),
            Wide::from_bits(count << (32 - 24)),
        );
        let magnitude = g.abs() - g_slack;
        let sigma_slope = if g > Wide::ZERO { slope } else { -slope };
        if magnitude <= Wide::ZERO || magnitude >= CURVED_LIMIT || slope.abs() >= CURVED_LIMIT {
            return Wide::ZERO;
        }
        let two_m_g = mul(curvature, magnitude) * 2;
        let step = if sigma_slope >= slope_slack {
            // Moving away from the surface: (σg' + √(g'² + 2M|g|))/M, each part rounded down.
            let away = sigma_slope - slope_slack;
            quotient(away + sqrt_wide(mul(away, away) + two_m_g), curvature)
        } else {
            // Towards it: 2|g|/(√(g'² + 2M|g|) − σg'), the denominator rounded up.
            let towards = slope_slack - sigma_slope;
            let largest = slope.abs() + slope_slack;
            let root = sqrt_wide(mul(largest, largest) + two_m_g + Wide::from_bits(4))
                + Wide::from_bits(1 << 16);
            quotient(magnitude * 2, root + towards)
        };
        step.unwrap_or(Wide::ZERO).max(Wide::ZERO)
    }

    fn shade(&self, rays: &[RayBall], d: [Wide; 3], t: Wide, inside: bool) -> Option<Hit> {
        let mut gradient = [Wide::ZERO; 3];
        let mut blend = Blend::new();
        for ray in rays {
            let (Some(ball), Some(s)) = (self.balls.get(usize::from(ray.ball)), ray.s(t)) else {
                continue;
            };
            blend.add(ball.density * field(s), usize::from(ray.ball), ball.color);
            // ∇(q·f(s)) = q·f'(s)·2(p − c)/R², p − c = t·d − offset.
            let k = ball.density * field_slope(s) * ball.inv_r2 * Wide::from_num(2);
            for (g, (di, oi)) in gradient.iter_mut().zip(d.iter().zip(ball.offset)) {
                *g += k * (t * *di - oi);
            }
        }
        let largest = gradient.iter().map(|g| g.abs()).max().unwrap_or(Wide::ZERO);
        let mut intensity = self.light.ambient;
        if largest > Wide::ZERO {
            // The outward normal is −∇g; seen from inside the surface, +∇g faces the eye.
            let inv_largest = quotient(Wide::ONE, largest).unwrap_or(Wide::ZERO);
            let n = gradient.map(|g| g * inv_largest);
            let length = sqrt_wide(dot(n, n));
            let mut n_dot_l = quotient(dot(n, self.light.direction), length).unwrap_or(Wide::ZERO);
            if !inside {
                n_dot_l = -n_dot_l;
            }
            if n_dot_l > Wide::ZERO {
                intensity += self.light.diffuse * n_dot_l;
            }
        }
        let (color, ball) =
            blend.finish(intensity.min(Wide::ONE), self.balls.iter().map(|b| b.color));
        let depth = depth_at(self.camera.near, t);
        Some(Hit { color, ball, depth })
    }
}

/// The ray's quadratic for one ball, or `None` if the ray misses its influence sphere.
/// `inv_dd = 1/|d|²` is the ray's one division.
fn ray_ball(
    ball: &FrameBall,
    index: usize,
    d: [Wide; 3],
    dd: Wide,
    inv_dd: Wide,
    length: Wide,
) -> Option<RayBall> {
    let w = ball.offset;
    let closest = mul(dot(w, d), inv_dd);
    let cross = [
        mul(w[1], d[2]) - mul(w[2], d[1]),
        mul(w[2], d[0]) - mul(w[0], d[2]),
        mul(w[0], d[1]) - mul(w[1], d[0]),
    ];
    let s_min = mul(mul(dot(cross, cross), inv_dd), ball.inv_r2);
    if s_min >= Wide::ONE {
        return None;
    }
    let a = mul(dd, ball.inv_r2);
    // (1 − s_min)/A = (1 − s_min)·R²/|d|²; padded by 2^-16 so the rounding of the square root
    // never shortens the interval.
    let half = sqrt_wide(mul(mul(Wide::ONE - s_min, ball.r2), inv_dd)) + Wide::from_bits(1 << 16);
    // Along the ray, s = s_min + A·u² (u = t − t_c) and |d(q·f)/dt| = |q|·|f'(s)|·2A|u|. With
    // s = s_min + (1 − s_min)·z, z ∈ [0, 1), that is |q|·√A·(1 − s_min)^{3/2} times
    // (1 − z)(22/9 − 12/9·s)·2√z, largest at s_min = 0, where it is |df/dr|·R: so the ray's own
    // bound is the ball's times (1 − s_min)^{3/2}, here (1 − s_min)·A·half with the padded half
    // (≥ √((1 − s_min)/A)). Far below the ball's bound for a ray through the edge of its
    // influence.
    let along = mul(
        mul(ball.density.abs(), FIELD_LIPSCHITZ_WIDE),
        mul(mul(Wide::ONE - s_min, a), half),
    );
    Some(RayBall {
        ball: u8::try_from(index).ok()?,
        closest,
        a,
        s_min,
        enter: closest - half,
        exit: closest + half,
        lipschitz: (ball.slope_bound * length).min(along),
    })
}

/// `1/x` for `x > 2^-31` to within 2^-31 (one unsigned 64-bit division, rounding down): the
/// ray's `1/|d|²`, which sets every ball's closest approach along the ray, so an error here
/// moves the whole surface along the ray (with [`quotient`]'s 2^-16, up to 1.5·10⁻⁵ of the
/// depth, much more where the ray grazes it).
fn reciprocal(x: Wide) -> Option<Wide> {
    let bits = u64::try_from(x.to_bits()).ok()?;
    let q = (1u64 << 63).checked_div(bits)?;
    i64::try_from(q).ok()?.checked_mul(2).map(Wide::from_bits)
}

/// The depth format's `near / t` (`t ≥ near`, both below 2^10) to within 2^-30 plus 2^-23 of
/// `t`: one unsigned 64-bit division, `t` keeping 23 fractional bits ([`quotient`]'s 16 would
/// report the hit up to 2^-16 deeper than it is).
fn depth_at(near: Wide, t: Wide) -> Depth {
    let numerator = u64::try_from(near.to_bits())
        .ok()
        .and_then(|n| n.checked_mul(1 << 21));
    let denominator = u64::try_from(t.to_bits() >> 9).ok();
    match (numerator, denominator) {
        (Some(n), Some(d)) => n.checked_div(d).map_or(Depth::ZERO, |q| {
            Depth::from_bits(i32::try_from(q).unwrap_or(i32::MAX))
        }),
        _ => Depth::ZERO,
    }
}

/// `numerator / denominator` for a positive denominator in one `i64` division (I32F32's own
/// division widens to `i128`, a slow library call on the targets): the denominator keeps 16
/// fractional bits and is rounded up, so the quotient's magnitude never exceeds the exact one
/// (the march's step stays safe); relative error ≤ 2^-16 / denominator. `None` for a
/// denominator below 2^-16 or `|numerator| ≥ 2^15` (the field sum is below 2^12, normals ≤ 1).
pub(super) fn quotient(numerator: Wide, denominator: Wide) -> Option<Wide> {
    let den = (denominator.to_bits() >> 16) + 1;
    if den <= 1 {
        return None;
    }
    numerator
        .to_bits()
        .checked_mul(1 << 16)?
        .checked_div(den)
        .map(Wide::from_bits)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sink::HashSink;
    use crate::test_rng::XorShift64;

    fn unit(rng: &mut XorShift64) -> f64 {
        (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    #[test]
    fn reciprocal_is_within_2_pow_minus_31() {
        let mut rng = XorShift64::new(0x9e37_79b9_7f4a_7c15);
        for _ in 0..10_000 {
            let x = Wide::from_num(1.0 + 3.0 * unit(&mut rng));
            let exact = 1.0 / x.to_num::<f64>();
            let got = reciprocal(x).map(|r| r.to_num::<f64>());
            assert!(
                got.is_some_and(|r| (r - exact).abs() <= 2f64.powi(-31)),
                "{x}"
            );
        }
        assert_eq!(reciprocal(Wide::ZERO), None);
        assert_eq!(reciprocal(Wide::from_num(-1)), None);
    }

    #[test]
    fn depth_gives_back_the_ray_parameter_within_2_pow_minus_23() {
        let mut rng = XorShift64::new(0x2545_f491_4f6c_dd1d);
        for _ in 0..10_000 {
            let near = 1.0 / 256.0 + unit(&mut rng) * 4.0;
            let t = near * (1.0 + 15.0 * unit(&mut rng));
            let (near_w, t_w) = (Wide::from_num(near), Wide::from_num(t));
            let (near, t) = (near_w.to_num::<f64>(), t_w.to_num::<f64>());
            let depth = depth_at(near_w, t_w).to_num::<f64>();
            // The Q30 output's own step, 2^-30 of the depth, is t²/near·2^-30 in t.
            let allowed = 2f64.powi(-23) + t * t / near * 2f64.powi(-30);
            assert!((near / depth - t).abs() <= allowed, "near {near} t {t}");
        }
    }

    /// A 64×64 camera 6 units from the origin, looking at it.
    fn test_camera() -> MetaCamera {
        let camera = MetaCamera::new(
            [0.0, 0.0, 6.0],
            [0.0; 3],
            [0.0, 1.0, 0.0],
            60.0,
            0.1,
            20.0,
            64,
            64,
        );
        let Ok(camera) = camera else {
            panic!("camera");
        };
        camera
    }

    /// A light from the eye's side.
    fn test_light() -> Light {
        let Ok(light) = Light::new([0.0, 0.0, 1.0], 0.2, 0.8) else {
            panic!("light");
        };
        light
    }

    /// The bound along the ray never falls below the slope it bounds, sampled on random rays
    /// through random balls, the edge of their influence included.
    #[test]
    fn lipschitz_along_the_ray_bounds_its_slope() {
        let mut rng = XorShift64::new(0x1234_5678_9abc_def1);
        let camera = test_camera();
        let mut tested = 0;
        for _ in 0..2_000 {
            let mut r = || unit(&mut rng) as f32;
            let centre = [4.0 * r() - 2.0, 4.0 * r() - 2.0, 4.0 * r() - 2.0];
            let ball = Ball::new(centre, 0.2 + 2.0 * r(), 3.0 * r() - 1.5, Rgb888::BLACK);
            let (column, row) = ((r() * 64.0) as u16, (r() * 64.0) as u16);
            let frame = frame_ball(&ball, &camera);
            let d = camera.direction(column, row);
            let dd = dot(d, d);
            let (Some(inv_dd), length) = (reciprocal(dd), sqrt_wide(dd)) else {
                panic!("direction");
            };
            let Some(ray) = ray_ball(&frame, 0, d, dd, inv_dd, length) else {
                continue;
            };
            tested += 1;
            let (enter, exit) = (ray.enter.to_num::<f64>(), ray.exit.to_num::<f64>());
            let q = frame.density.to_num::<f64>();
            let h = |t: f64| {
                let s = ray.a.to_num::<f64>() * (t - ray.closest.to_num::<f64>()).powi(2)
                    + ray.s_min.to_num::<f64>();
                if s >= 1.0 {
                    0.0
                } else {
                    q * (1.0 - s) * (1.0 - s) * (1.0 - 4.0 / 9.0 * s)
                }
            };
            let step = (exit - enter) / 512.0;
            for k in 0..512 {
                let t = enter + step * k as f64;
                let slope = (h(t + step) - h(t)).abs() / step;
                assert!(
                    slope <= ray.lipschitz.to_num::<f64>() * 1.0001,
                    "slope {slope} over {} ({ball:?}, pixel {column} {row})",
                    ray.lipschitz
                );
            }
        }
        assert!(tested > 200, "{tested}");
    }

    /// `|f''(s)|·4z + 2|f'(s)|` over `0 ≤ z ≤ s ≤ 1` stays below the curvature constant, which
    /// is not far above its largest value.
    #[test]
    fn field_curvature_constant_bounds_the_second_derivative() {
        let bound = FIELD_CURVATURE_WIDE.to_num::<f64>();
        let mut largest = 0.0f64;
        for i in 0..=1000 {
            let s = f64::from(i) / 1000.0;
            let (f1, f2) = ((1.0 - s) * (22.0 - 12.0 * s) / 9.0, (34.0 - 24.0 * s) / 9.0);
            for j in 0..=100 {
                let z = s * f64::from(j) / 100.0;
                largest = largest.max(f2 * 4.0 * z + 2.0 * f1);
            }
        }
        assert!(largest <= bound && largest > bound - 0.02, "{largest}");
    }

    /// The curvature's step never passes a root of the field along the ray: on random rays
    /// through random balls, sampled finely from random points, the field keeps its sign over
    /// every step taken, and near tangent grazes it steps much further than `|g| / L`.
    #[test]
    fn curved_step_passes_no_root() {
        let mut rng = XorShift64::new(0x0f1e_2d3c_4b5a_6978);
        let camera = test_camera();
        let light = test_light();
        let (mut steps, mut longer) = (0, 0);
        for _ in 0..400 {
            let mut r = || unit(&mut rng) as f32;
            let balls: [Ball; 3] = core::array::from_fn(|_| {
                let centre = [3.0 * r() - 1.5, 3.0 * r() - 1.5, 3.0 * r() - 1.5];
                Ball::new(centre, 0.3 + 1.5 * r(), 2.5 * r() - 0.5, Rgb888::BLACK)
            });
            let threshold = Wide::from_num(0.1 + 0.5 * r());
            let (column, row) = ((r() * 64.0) as u16, (r() * 64.0) as u16);
            let frame_balls = balls.map(|b| frame_ball(&b, &camera));
            let frame = Frame {
                balls: &frame_balls,
                threshold,
                camera: &camera,
                light: Lighting::new(&light),
            };
            let d = camera.direction(column, row);
            let dd = dot(d, d);
            let (Some(inv_dd), length) = (reciprocal(dd), sqrt_wide(dd)) else {
                panic!("direction");
            };
            let mut rays = [RayBall::EMPTY; 3];
            let mut count = 0;
            for (k, b) in frame_balls.iter().enumerate() {
                if let Some(ray) = ray_ball(b, k, d, dd, inv_dd, length) {
                    rays[count] = ray;
                    count += 1;
                }
            }
            let rays = &rays[..count];
            for k in 0..20 {
                // A point inside one of the ray's influence intervals.
                let Some(ray) = rays.get(k % rays.len().max(1)) else {
                    break;
                };
                let t = ray.enter + mul(ray.exit - ray.enter, Wide::from_num(unit(&mut rng)));
                let sample = frame.sample(rays, t);
                let mut h = frame.curved_step(rays, t, sample.g);
                if let Some(next) = sample.next_entry {
                    h = h.min(next - t);
                }
                if h <= Wide::ZERO {
                    continue;
                }
                steps += 1;
                let linear = quotient(sample.g.abs(), sample.lipschitz).unwrap_or(Wide::MAX);
                if h > linear.saturating_mul(Wide::from_num(4)) {
                    longer += 1;
                }
                for k in 1..=256 {
                    let u = t + mul(h, Wide::from_num(f64::from(k) / 256.0));
                    let g = frame.sample(rays, u).g;
                    assert!(
                        g.signum() == sample.g.signum() || g.abs() < Wide::from_num(1e-6),
                        "g {} at t {t} became {g} at {u} (step {h})",
                        sample.g
                    );
                }
            }
        }
        // The sign check above is the test; these make sure it saw many steps, some far
        // longer than the slope's (2,100 and 66 when written).
        assert!(
            steps > 1500 && longer > 30,
            "{steps} steps, {longer} longer"
        );
    }

    /// A ray passing 1/1000 outside a lone ball's surface: at its closest approach the field is
    /// flat along the ray, so the curvature's step is many times the slope's.
    #[test]
    fn curved_step_crosses_a_tangent_graze() {
        let camera = test_camera();
        let d = camera.direction(32, 32).map(|c| c.to_num::<f64>());
        let length = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        let unit_d = d.map(|c| c / length);
        // A unit vector across the ray, in the x-z plane.
        let across = [unit_d[2], 0.0, -unit_d[0]];
        let across_length = (across[0] * across[0] + across[2] * across[2]).sqrt();
        // R = 2, q = 1, T = 1/2: the surface is the unit sphere (f(1/4) = 1/2).
        let centre: [f32; 3] = core::array::from_fn(|i| {
            ([0.0, 0.0, 6.0][i] + 6.0 * unit_d[i] + 1.001 * across[i] / across_length) as f32
        });
        let balls = [frame_ball(
            &Ball::new(centre, 2.0, 1.0, Rgb888::BLACK),
            &camera,
        )];
        let light = test_light();
        let frame = Frame {
            balls: &balls,
            threshold: Wide::from_num(0.5),
            camera: &camera,
            light: Lighting::new(&light),
        };
        let dw = camera.direction(32, 32);
        let dd = dot(dw, dw);
        let (Some(inv_dd), root) = (reciprocal(dd), sqrt_wide(dd)) else {
            panic!("direction");
        };
        let Some(ray) = ray_ball(&balls[0], 0, dw, dd, inv_dd, root) else {
            panic!("the ray misses the ball's influence");
        };
        let rays = [ray];
        let sample = frame.sample(&rays, ray.closest);
        assert!(sample.g < Wide::ZERO, "{}", sample.g);
        let linear = quotient(sample.g.abs(), sample.lipschitz).unwrap_or(Wide::ZERO);
        let curved = frame.curved_step(&rays, ray.closest, sample.g);
        assert!(linear >= EPSILON_T, "{linear}");
        assert!(curved > linear * 10, "curved {curved}, linear {linear}");
        for k in 1..=256 {
            let u = ray.closest + mul(curved, Wide::from_num(f64::from(k) / 256.0));
            assert!(frame.sample(&rays, u).g < Wide::ZERO, "root passed at {u}");
        }
    }

    /// A caster wider than the camera casts the camera's columns only.
    #[test]
    fn a_wider_caster_casts_the_same_frame() {
        let balls = [
            Ball::new([0.0, 0.0, 0.0], 1.5, 1.0, Rgb888::RED),
            Ball::new([0.8, 0.3, 0.0], 1.0, 0.8, Rgb888::GREEN),
        ];
        let (Ok(scene), Ok(camera), Ok(light)) = (
            Metaballs::new(&balls, crate::metaball::Coord::from_num(0.5)),
            MetaCamera::new(
                [0.0, 0.5, 5.0],
                [0.0; 3],
                [0.0, 1.0, 0.0],
                45.0,
                0.1,
                20.0,
                16,
                16,
            ),
            Light::new([0.0, 0.0, 1.0], 0.2, 0.8),
        ) else {
            panic!("scene");
        };
        let render = |caster: &mut dyn FnMut(&mut HashSink) -> CastStats| {
            let mut sink = HashSink::new();
            let stats = caster(&mut sink);
            (stats, sink.hash())
        };
        let mut narrow = Caster::<Rgb888, 16, 2>::new(Rgb888::BLACK);
        let mut wide = Caster::<Rgb888, 64, 2>::new(Rgb888::BLACK);
        let a = render(&mut |s| {
            narrow
                .render(&scene, &camera, &light, s)
                .unwrap_or_default()
        });
        let b = render(&mut |s| wide.render(&scene, &camera, &light, s).unwrap_or_default());
        assert!(a.0.hits > 20 && a.0.hits <= 256, "{:?}", a.0);
        assert_eq!(a, b);
    }
}
