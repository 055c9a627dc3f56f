//! Integration tests of the library, one binary: each module was once its own test target.
//! Linking one binary instead of one per file keeps `cargo xtask test` inside its budget.

mod bake;
mod bsp_export;
mod common;
mod cover;
mod envelope;
mod firmware_hashes;
mod hostile;
mod hsr_scenes;
mod metaball_firmware;
mod metaball_polygonize;
mod module_graph;
mod newell;
mod patch_cover;
mod patch_firmware;
mod patch_trim;
mod patterns;
mod render;
mod resolve;
mod warnock;
