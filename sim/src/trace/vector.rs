//! The few 3-vector operations the tracer needs, on plain `[f64; 3]`.

pub use crate::reference::{cross, dot, normalize, V3};

/// `a + b`.
pub fn add(a: V3, b: V3) -> V3 {
    [0, 1, 2].map(|k| a[k] + b[k])
}

/// `a − b`.
pub fn sub(a: V3, b: V3) -> V3 {
    [0, 1, 2].map(|k| a[k] - b[k])
}

/// `a · s`.
pub fn scale(a: V3, s: f64) -> V3 {
    a.map(|c| c * s)
}

/// `a + b · s` (a point along a ray).
pub fn along(a: V3, b: V3, s: f64) -> V3 {
    [0, 1, 2].map(|k| a[k] + b[k] * s)
}

/// Euclidean length.
pub fn length(a: V3) -> f64 {
    dot(a, a).sqrt()
}

/// A ray `origin + t · dir`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Where it starts.
    pub origin: V3,
    /// Its direction (unit for secondary rays; view-axis component 1 for primary rays).
    pub dir: V3,
}

impl Ray {
    /// The point at parameter `t`.
    pub fn at(&self, t: f64) -> V3 {
        along(self.origin, self.dir, t)
    }
}

/// The ray parameters a query accepts: `min < t < max`, or `min ≤ t < max` when
/// `min_inclusive` (primary rays: eye depth in [near, far)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Span {
    /// Lower end.
    pub min: f64,
    /// Upper end (exclusive).
    pub max: f64,
    /// Whether `min` itself is accepted.
    pub min_inclusive: bool,
}

impl Span {
    /// `(min, max)`, both ends open.
    pub fn open(min: f64, max: f64) -> Self {
        Span {
            min,
            max,
            min_inclusive: false,
        }
    }

    /// Whether `t` is in the span.
    pub fn contains(&self, t: f64) -> bool {
        let above = if self.min_inclusive {
            t >= self.min
        } else {
            t > self.min
        };
        above && t < self.max
    }

    /// The same span ending at `max` (or earlier).
    pub fn until(&self, max: f64) -> Self {
        Span {
            max: self.max.min(max),
            ..*self
        }
    }
}
