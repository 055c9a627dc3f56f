//! The view the `trace` firmware renders the classic scene from (the corpus camera "front" of
//! `sim/scenes/classic.scene`, see `sim/src/trace/corpus.rs`); `cargo xtask trace` includes
//! this file too and renders the same view with the host's fixed tracer, so the hashes compare
//! the same frame.

/// A camera and image size.
#[derive(Clone, Copy, Debug)]
pub struct View {
    /// Eye position.
    pub eye: [f64; 3],
    /// Point looked at.
    pub target: [f64; 3],
    /// Up direction.
    pub up: [f64; 3],
    /// Vertical field of view, degrees.
    pub fovy: f64,
    /// Near distance.
    pub near: f64,
    /// Far distance.
    pub far: f64,
    /// Width in pixels.
    pub width: u16,
    /// Height in pixels.
    pub height: u16,
}

/// The classic scene at 240×240.
pub const CLASSIC: View = View {
    eye: [0.0, 3.0, 7.0],
    target: [0.0, 0.8, 0.0],
    up: [0.0, 1.0, 0.0],
    fovy: 50.0,
    near: 0.1,
    far: 100.0,
    width: 240,
    height: 240,
};

/// Depth limit of the ray tree.
pub const MAX_DEPTH: u8 = 4;
