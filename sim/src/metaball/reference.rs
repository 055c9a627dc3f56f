//! The f64 metaball reference: per ray, the summed field in Bernstein form on every interval
//! where the set of influence spheres crossed is constant, and Bezier clipping for the nearest
//! root.
//!
//! Bezier clipping (Nishita, Sederberg, Kakimoto 1990): the roots of a polynomial in Bernstein
//! form on `[0, 1]` lie where the convex hull of its control points `(k/6, bₖ)` meets the axis,
//! so the interval shrinks to that range; when a clip removes less than [`MIN_CLIP`] (20 %) of
//! it, the interval is split in half and the halves searched nearest first. A root is accepted
//! once its interval is shorter than [`TOLERANCE_T`] in the ray parameter (eye depth); it is
//! then the interval's midpoint, within `TOLERANCE_T / 2` of a zero of the polynomial.

use super::MetaScene;
use crate::reference::{dot, normalize, Camera, Image, Light, V3};
use scanline3d::metaball::FIELD_COEFFICIENTS;

/// Width in eye depth below which a clipped interval is a root.
pub const TOLERANCE_T: f64 = 1e-11;
/// A clip that keeps more than `1 − MIN_CLIP` of its interval is followed by a split.
pub const MIN_CLIP: f64 = 0.2;
const DEGREE: usize = 6;

/// One ball in f64.
#[derive(Clone, Copy, Debug)]
pub struct RefBall {
    /// Centre.
    pub centre: V3,
    /// Radius of influence.
    pub radius: f64,
    /// Density.
    pub density: f64,
    /// 8-bit colour (as the library stores it).
    pub color: [u8; 3],
}

/// A frame of a metaball scene with its camera.
#[derive(Clone, Debug)]
pub struct Reference {
    /// The balls at this frame.
    pub balls: Vec<RefBall>,
    /// `T`.
    pub threshold: f64,
    /// The light.
    pub light: Light,
    /// The camera.
    pub camera: Camera,
    /// How far the library's formats may move any input value: 0 when every radius, density,
    /// centre and the threshold lie on their formats' 2^-16 grid and nothing moves, else 2^-16
    /// (rounding to nearest, centres through I8F24 keys to I16F16).
    pub input_rounding: f64,
}

/// What the fixed-point caster's stopping rule sees at one point of a ray.
#[derive(Clone, Copy, Debug)]
pub struct MarchPoint {
    /// `g = Σ q f − T` there.
    pub g: f64,
    /// `|∇g|` there.
    pub gradient: f64,
    /// The caster's Lipschitz bound there: the sum of `|q|·FIELD_LIPSCHITZ/R·|d|` or, where
    /// smaller, the ray's own `|q|·FIELD_LIPSCHITZ·(1 − s_min)·A·(half + 2^-16)`, over the
    /// balls whose influence interval along the ray may hold `t` in the caster: the sphere
    /// grown by what input rounding can add, the interval widened at each end by the caster's
    /// 2^-16 and the given uncertainty of `t`.
    pub lipschitz: f64,
    /// How far `g` may move per unit of input rounding ([`Reference::input_rounding`]): 1 for
    /// `T`, and per ball `f + |q|·|df/dr|·(√3 + 1)` (its density, then its centre and radius).
    pub rounding_gain: f64,
}

/// The nearest surface point along a ray.
#[derive(Clone, Copy, Debug)]
pub struct MetaHit {
    /// Ray parameter (eye depth, for camera rays).
    pub t: f64,
    /// The ball with the largest `q·f` there.
    pub ball: usize,
    /// Shaded colour.
    pub color: [u8; 3],
}

/// The field `f(s)`, `s = r²/R²`, 0 for `s ≥ 1`.
pub fn field(s: f64) -> f64 {
    if s >= 1.0 {
        return 0.0;
    }
    FIELD_COEFFICIENTS
        .iter()
        .rev()
        .fold(0.0, |acc, c| acc * s + c)
}

fn field_slope(s: f64) -> f64 {
    if s >= 1.0 {
        return 0.0;
    }
    let c = FIELD_COEFFICIENTS;
    c[1] + 2.0 * c[2] * s + 3.0 * c[3] * s * s
}

fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn at(origin: V3, d: V3, t: f64) -> V3 {
    [0, 1, 2].map(|i| origin[i] + t * d[i])
}

fn mul(a: &[f64], b: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; a.len() + b.len() - 1];
    for (i, x) in a.iter().enumerate() {
        for (j, y) in b.iter().enumerate() {
            out[i + j] += x * y;
        }
    }
    out
}

fn binomial(n: usize, k: usize) -> f64 {
    (0..k).fold(1.0, |acc, i| acc * (n - i) as f64 / (i + 1) as f64)
}

/// Power basis on [0, 1] to Bernstein coefficients.
fn bernstein(power: &[f64; DEGREE + 1]) -> [f64; DEGREE + 1] {
    let mut b = [0.0; DEGREE + 1];
    for (j, bj) in b.iter_mut().enumerate() {
        *bj = (0..=j)
            .map(|i| binomial(j, i) / binomial(DEGREE, i) * power[i])
            .sum();
    }
    b
}

/// Splits Bernstein coefficients at `u` (de Casteljau): (left on [0,u], right on [u,1]).
fn split(b: &[f64; DEGREE + 1], u: f64) -> ([f64; DEGREE + 1], [f64; DEGREE + 1]) {
    let mut work = *b;
    let mut left = [0.0; DEGREE + 1];
    let mut right = [0.0; DEGREE + 1];
    for level in 0..=DEGREE {
        left[level] = work[0];
        right[DEGREE - level] = work[DEGREE - level];
        for k in 0..DEGREE - level {
            work[k] = work[k] * (1.0 - u) + work[k + 1] * u;
        }
    }
    (left, right)
}

/// The range `[u_min, u_max]` where the control polygon's convex hull meets the axis.
fn hull_range(b: &[f64; DEGREE + 1]) -> Option<(f64, f64)> {
    let mut range: Option<(f64, f64)> = None;
    let mut add = |u: f64| {
        range = Some(range.map_or((u, u), |(lo, hi)| (lo.min(u), hi.max(u))));
    };
    for i in 0..=DEGREE {
        let xi = i as f64 / DEGREE as f64;
        if b[i] == 0.0 {
            add(xi);
        }
        for j in i + 1..=DEGREE {
            if (b[i] < 0.0) != (b[j] < 0.0) && b[i] != 0.0 && b[j] != 0.0 {
                let xj = j as f64 / DEGREE as f64;
                add(xi + b[i] / (b[i] - b[j]) * (xj - xi));
            }
        }
    }
    range
}

/// The nearest root in `[lo, hi]` (fractions of the segment of length `span`), Bezier clipping.
fn clip(b: &[f64; DEGREE + 1], lo: f64, hi: f64, span: f64, iterations: &mut u32) -> Option<f64> {
    *iterations += 1;
    if *iterations > 10_000 {
        return None;
    }
    let (u0, u1) = hull_range(b)?;
    let (a, c) = (lo + u0 * (hi - lo), lo + u1 * (hi - lo));
    if (c - a) * span < TOLERANCE_T {
        return Some((a + c) / 2.0);
    }
    if u1 - u0 > 1.0 - MIN_CLIP {
        let (left, right) = split(b, 0.5);
        let mid = (lo + hi) / 2.0;
        return clip(&left, lo, mid, span, iterations)
            .or_else(|| clip(&right, mid, hi, span, iterations));
    }
    let (_, right) = split(b, u0);
    let (inner, _) = split(&right, (u1 - u0) / (1.0 - u0).max(f64::MIN_POSITIVE));
    clip(&inner, a, c, span, iterations)
}

/// The ray's quadratic `s(t) = A t² + B t + C` and influence interval for one ball.
struct RayBall {
    index: usize,
    a: f64,
    closest: f64,
    s_min: f64,
    enter: f64,
    exit: f64,
}

impl Reference {
    /// The scene at `frame` seen by `camera`.
    pub fn new(scene: &MetaScene, frame: u32, camera: Camera) -> Result<Reference, String> {
        let (d, ambient, diffuse) = scene.light;
        let direction = normalize(d).ok_or("light direction is zero")?;
        Ok(Reference {
            balls: scene
                .balls
                .iter()
                .map(|b| RefBall {
                    centre: b.centre_at(frame),
                    radius: b.radius,
                    density: b.density,
                    color: b.color8(),
                })
                .collect(),
            threshold: scene.threshold,
            input_rounding: if scene.on_fixed_grid() {
                0.0
            } else {
                2f64.powi(-16)
            },
            light: Light {
                direction,
                ambient,
                diffuse,
            },
            camera,
        })
    }

    /// `g(p) = Σ q f − T` at a point.
    pub fn g(&self, p: V3) -> f64 {
        self.balls
            .iter()
            .map(|b| {
                let r = sub(p, b.centre);
                b.density * field(dot(r, r) / (b.radius * b.radius))
            })
            .sum::<f64>()
            - self.threshold
    }

    /// The caster's view of ray parameter `t` along direction `d`, known to within
    /// `uncertainty` (see [`MarchPoint`]).
    pub fn march_point(&self, d: V3, t: f64, uncertainty: f64) -> MarchPoint {
        let pad = 1.0 / 65536.0 + uncertainty;
        // The caster's ball may be this much larger once rounded (radius, and centre by √3).
        let grow = self.input_rounding * (1.0 + 3f64.sqrt());
        let dd = dot(d, d);
        let length = dd.sqrt();
        let p = at(self.camera.eye, d, t);
        let mut gradient = [0.0; 3];
        let mut point = MarchPoint {
            g: self.g(p),
            gradient: 0.0,
            lipschitz: 0.0,
            rounding_gain: 1.0,
        };
        for b in &self.balls {
            let w = sub(b.centre, self.camera.eye);
            let c = crate::reference::cross(w, d);
            let distance2 = dot(c, c) / dd;
            let grown = b.radius + grow;
            let reach = grown * grown - distance2;
            let half = (reach / dd).sqrt();
            let closest = dot(w, d) / dd;
            if reach <= 0.0 || t < closest - half - pad || t >= closest + half + pad {
                continue;
            }
            // The caster's bound along the ray, |q|·FIELD_LIPSCHITZ·(1 − s_min)·A·(half +
            // 2^-16), for the radius as given and as rounding may move it.
            let along = [b.radius - grow, b.radius, grown]
                .iter()
                .map(|&r| {
                    let rest = (1.0 - distance2 / (r * r)).max(0.0);
                    let a = dd / (r * r);
                    let lipschitz = b.density.abs() * scanline3d::metaball::FIELD_LIPSCHITZ;
                    lipschitz * rest * a * ((rest / a).sqrt() + 1.0 / 65536.0)
                })
                .fold(0.0, f64::max);
            let everywhere = b.density.abs() * scanline3d::metaball::FIELD_LIPSCHITZ / b.radius;
            point.lipschitz += (everywhere * length).min(along);
            let r = sub(p, b.centre);
            let r2 = b.radius * b.radius;
            let s = dot(r, r) / r2;
            // ∇(q·f(s)) = q·f'(s)·2r/R²; |df/dr| = |f'(s)|·2|r|/R².
            let k = b.density * field_slope(s) * 2.0 / r2;
            for (g, ri) in gradient.iter_mut().zip(r) {
                *g += k * ri;
            }
            point.rounding_gain += field(s) + k.abs() * dot(r, r).sqrt() * (3f64.sqrt() + 1.0);
        }
        point.gradient = dot(gradient, gradient).sqrt();
        point
    }

    fn ray_balls(&self, d: V3) -> Vec<RayBall> {
        let dd = dot(d, d);
        self.balls
            .iter()
            .enumerate()
            .filter_map(|(index, b)| {
                let w = sub(b.centre, self.camera.eye);
                let closest = dot(w, d) / dd;
                let c = crate::reference::cross(w, d);
                let r2 = b.radius * b.radius;
                let s_min = dot(c, c) / dd / r2;
                (s_min < 1.0).then(|| {
                    let a = dd / r2;
                    let half = ((1.0 - s_min) / a).sqrt();
                    RayBall {
                        index,
                        a,
                        closest,
                        s_min,
                        enter: closest - half,
                        exit: closest + half,
                    }
                })
            })
            .collect()
    }

    /// The nearest zero of `g` along `eye + t·d` for `t` in `[t0, t1]`, and the Bezier clipping
    /// iterations (clips and splits) it took.
    pub fn nearest_root(&self, d: V3, t0: f64, t1: f64) -> (Option<f64>, u32) {
        let rays = self.ray_balls(d);
        let mut events: Vec<f64> = rays
            .iter()
            .flat_map(|r| [r.enter, r.exit])
            .filter(|&t| t > t0 && t < t1)
            .collect();
        events.push(t0);
        events.push(t1);
        events.sort_by(f64::total_cmp);
        let mut iterations = 0;
        for seg in events.windows(2) {
            let (a, b) = (seg[0], seg[1]);
            if b <= a {
                continue;
            }
            let mid = (a + b) / 2.0;
            let span = b - a;
            // g on the segment as a polynomial in u ∈ [0, 1], t = a + u·span.
            let mut power = [0.0; DEGREE + 1];
            power[0] = -self.threshold;
            for r in rays.iter().filter(|r| r.enter <= mid && mid < r.exit) {
                let q = self.balls[r.index].density;
                let o = a - r.closest;
                let s = [
                    r.a * o * o + r.s_min,
                    2.0 * r.a * o * span,
                    r.a * span * span,
                ];
                let mut s_power = vec![1.0];
                for (k, c) in FIELD_COEFFICIENTS.iter().enumerate() {
                    if k > 0 {
                        s_power = mul(&s_power, &s);
                    }
                    for (p, x) in power.iter_mut().zip(&s_power) {
                        *p += q * c * x;
                    }
                }
            }
            let b = bernstein(&power);
            if let Some(u) = clip(&b, 0.0, 1.0, span, &mut iterations) {
                return (Some(a + u * span), iterations);
            }
        }
        (None, iterations)
    }

    /// Shading and ids at ray parameter `t` of direction `d`, as the caster does them.
    pub fn hit(&self, d: V3, t: f64) -> MetaHit {
        let p = at(self.camera.eye, d, t);
        let inside = self.g(at(self.camera.eye, d, self.camera.near)) > 0.0;
        let mut gradient = [0.0; 3];
        let (mut best, mut ball) = (f64::NEG_INFINITY, 0);
        let (mut weight, mut rgb) = (0.0, [0.0; 3]);
        for (i, b) in self.balls.iter().enumerate() {
            let r = sub(p, b.centre);
            let r2 = b.radius * b.radius;
            let s = dot(r, r) / r2;
            if s >= 1.0 {
                continue;
            }
            let contribution = b.density * field(s);
            if contribution > best {
                (best, ball) = (contribution, i);
            }
            if contribution > 0.0 {
                weight += contribution;
                for (acc, c) in rgb.iter_mut().zip(b.color) {
                    *acc += contribution * c as f64;
                }
            }
            let k = b.density * field_slope(s) * 2.0 / r2;
            for (g, ri) in gradient.iter_mut().zip(r) {
                *g += k * ri;
            }
        }
        let mut intensity = self.light.ambient;
        if let Some(n) = normalize(gradient) {
            // Outward normal −∇g; from inside the surface +∇g faces the eye.
            let n_dot_l = if inside { 1.0 } else { -1.0 } * dot(n, self.light.direction);
            intensity += self.light.diffuse * n_dot_l.max(0.0);
        }
        let intensity = intensity.min(1.0);
        let base = if weight > 0.0 {
            rgb.map(|c| c / weight)
        } else {
            self.balls[ball].color.map(f64::from)
        };
        MetaHit {
            t,
            ball,
            color: base.map(|c| (c * intensity).round().clamp(0.0, 255.0) as u8),
        }
    }

    /// Casts the ray through pixel centre `(x, y)` of a `w × h` image.
    pub fn cast(&self, x: f64, y: f64, w: usize, h: usize) -> (Option<MetaHit>, u32) {
        let d = self.camera.ray(x, y, w, h);
        let (root, iterations) = self.nearest_root(d, self.camera.near, self.camera.far);
        (root.map(|t| self.hit(d, t)), iterations)
    }

    /// Renders every pixel centre; also returns the Bezier clipping iterations per ray.
    pub fn render(&self, w: usize, h: usize) -> (Image, Vec<u32>) {
        let mut image = Image {
            width: w,
            height: h,
            ids: vec![-1; w * h],
            depth: vec![f32::INFINITY; w * h],
            color: vec![[0; 3]; w * h],
        };
        let mut iterations = Vec::with_capacity(w * h);
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                let (hit, n) = self.cast(x as f64 + 0.5, y as f64 + 0.5, w, h);
                iterations.push(n);
                if let Some(hit) = hit {
                    image.ids[i] = hit.ball as i32;
                    image.depth[i] = hit.t as f32;
                    image.color[i] = hit.color;
                }
            }
        }
        (image, iterations)
    }
}
