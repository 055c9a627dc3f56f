//! Ray tracing on the host: the traced-scene description (shared with the library's
//! fixed-point tracer through `sim export`) and the f64 Whitted reference tracer.

pub mod fixed;
pub mod scene;
