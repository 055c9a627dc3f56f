//! Deterministic random draws for the randomized checks (Marsaglia's 64-bit xorshift), so a
//! seed names the cases a test or an example draws, with no dependency.

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
