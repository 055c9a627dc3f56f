//! Ray tracing on the host: the traced-scene description (shared with the library's
//! fixed-point tracer through `sim export`) and the f64 Whitted reference tracer with both
//! accelerations the lecture names.
//!
//! Concerns, one module each: [`scene`] (the text format, the camera), [`vector`] (f64 vector
//! helpers and rays), [`intersect`] (ray–primitive tests and bounding boxes), [`query`]
//! (nearest/any hit with test counters), [`bvh`] (bounding volumes), [`grid`] (space
//! subdivision, 3D-DDA), [`accel`] (choosing one), [`corpus`] (the traced scenes and their cameras), [`whitted`] (the shading model and the ray
//! tree's termination rules) and [`render`] (a frame's images); [`fixed`] runs the library's
//! fixed-point tracer on the same scenes and exports them as firmware data, and [`compare`]
//! tells which of its differences from the reference the position bound explains.

pub mod accel;
pub mod bvh;
pub mod compare;
pub mod corpus;
pub mod fixed;
pub mod grid;
pub mod intersect;
pub mod query;
pub mod render;
pub mod scene;
pub mod vector;
pub mod whitted;
