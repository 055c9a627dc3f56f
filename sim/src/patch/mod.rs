//! Bicubic Bezier patch models on the host: the f64 model and its evaluation ([`model`]), the
//! Newell/Utah `.bpt` text format with this project's extension for weights and trim loops
//! ([`parse`]), and the reference renderer: ray tracing by Bezier clipping ([`clip`],
//! [`render`]); the trade of tolerance against cost and against meshes ([`trade`]). `docs/patches.md` describes the format and the algorithm.

pub mod clip;
pub mod compare;
pub mod fixed;
pub mod model;
pub mod parse;
pub mod render;
pub mod trade;

pub use model::{Patch, PatchModel, TrimLoop};
