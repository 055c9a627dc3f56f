//! Deterministic random draws for the randomized checks (Marsaglia's 64-bit xorshift), so a
//! seed names the cases a test or an example draws, with no dependency.

use crate::scene::CameraSpec;

/// A generator of uniform draws.
pub struct Draw(u64);

impl Draw {
    /// A generator from a seed (0 is taken as 1: xorshift's state must not be 0).
    pub fn new(seed: u64) -> Draw {
        Draw(seed.max(1))
    }

    /// A number drawn uniformly from `[lo, hi)`.
    pub fn in_range(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        lo + (hi - lo) * (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    /// A point with every coordinate drawn from `[−r, r)`.
    pub fn point(&mut self, r: f64) -> [f64; 3] {
        [0; 3].map(|_| self.in_range(-r, r))
    }
}

/// A random triangle soup and camera, as the hidden-surface checks draw them
/// (`sim/examples/hsr_random.rs`, `extremes::newell_matches_the_reference_on_random_soups`):
/// 1 to 40 triangles spread over 0.5 to 30 units, so they interpenetrate and cross the near
/// plane, seen from a random eye.
pub struct Soup {
    /// Three vertices a triangle.
    pub vertices: Vec<[f64; 3]>,
    /// The camera.
    pub camera: CameraSpec,
    /// Whether back faces are culled.
    pub cull: bool,
}

impl Soup {
    /// The generator whose draws are the soups of `seed`.
    pub fn draws(seed: u64) -> Draw {
        Draw::new(0x9e37_79b9_7f4a_7c15 ^ seed.wrapping_mul(0x2545_f491_4f6c_dd1d))
    }

    /// The next soup from `d`; `case` (its number) picks the spread.
    pub fn draw(d: &mut Draw, case: usize) -> Soup {
        let triangles = 1 + (d.in_range(0.0, 1.0) * 40.0) as usize;
        let spread = [0.5, 3.0, 3.0, 30.0][case % 4];
        let vertices = (0..3 * triangles).map(|_| d.point(spread)).collect();
        let camera = CameraSpec {
            eye: d.point(8.0),
            target: d.point(1.0),
            up: [0.0, 1.0, 0.0],
            fovy: d.in_range(20.0, 120.0),
            near: d.in_range(0.05, 0.5),
            far: 40.0,
        };
        let cull = d.in_range(0.0, 1.0) < 0.5;
        Soup {
            vertices,
            camera,
            cull,
        }
    }
}
