//! Integration tests of the host tool (`sim`), one binary: each module was once its own test
//! target. `peers.rs` stays apart: it needs the `peers` feature.

mod accuracy;
mod cli;
mod export;
mod extremes;
mod hsr;
mod interpolation;
mod metaball;
mod metaball_cli;
mod patch_cli;
mod patch_clip;
mod patch_compare;
mod patch_fixed;
mod patch_fixed_cli;
mod patch_model;
mod presets;
mod realworld;
mod realworld_cli;
mod run;
mod trace;
mod trace_fixed;
mod trace_hybrid;
mod vertex_cache;
