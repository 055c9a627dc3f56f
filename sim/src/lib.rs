//! Host tools for scanline3d: the float reference, accuracy metrics, the scene corpus and the
//! scene/image formats the `sim` binary reads and writes.

// Host-only. On a bare-metal target (where a plain `cargo build --lib --target ...` at the
// workspace root also builds this default member) the crate is empty.
#![cfg_attr(target_os = "none", no_std)]

#[cfg(all(not(target_os = "none"), feature = "tools"))]
pub mod analyze;
#[cfg(not(target_os = "none"))]
pub mod bsp;
#[cfg(not(target_os = "none"))]
pub mod corpus;
#[cfg(not(target_os = "none"))]
pub mod draw;
#[cfg(all(not(target_os = "none"), feature = "tools"))]
pub mod export;
#[cfg(not(target_os = "none"))]
pub mod fuzz;
#[cfg(not(target_os = "none"))]
pub mod hsr;
#[cfg(all(not(target_os = "none"), feature = "tools"))]
pub mod interpolation;
#[cfg(not(target_os = "none"))]
pub use scanline3d_meshgen as meshgen;
// Without `tools` too: the fuzz target feeds metaball scenes through it.
#[cfg(not(target_os = "none"))]
pub mod metaball;
#[cfg(not(target_os = "none"))]
pub mod metrics;
// Without `tools` too: the fuzz target feeds patch models through it.
#[cfg(not(target_os = "none"))]
pub mod patch;
#[cfg(all(not(target_os = "none"), feature = "peers"))]
pub mod peers;
#[cfg(not(target_os = "none"))]
pub mod progress;
#[cfg(not(target_os = "none"))]
pub mod reference;
#[cfg(not(target_os = "none"))]
pub mod scene;
// Without `tools` too: the fuzz target feeds traced scenes through it.
#[cfg(not(target_os = "none"))]
pub mod trace;
#[cfg(all(not(target_os = "none"), feature = "tools"))]
pub mod tradeoff;
#[cfg(not(target_os = "none"))]
pub mod world;

#[cfg(not(target_os = "none"))]
use metrics::{ErrorBound, Metrics};

/// `n` with thousands separators, as the README and the generated tables write figures.
#[cfg(not(target_os = "none"))]
pub fn thousands(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}
#[cfg(not(target_os = "none"))]
use scene::SceneSpec;

#[cfg(not(target_os = "none"))]
/// Renders `spec` with the fixed-point renderer (at `sub_bits`) and the reference, and compares
/// them with the documented error bound.
pub fn accuracy(
    spec: &SceneSpec,
    w: usize,
    h: usize,
    sub_bits: u32,
) -> Result<(Metrics, scene::FixedRender, reference::Image), String> {
    accuracy_with(spec, w, h, sub_bits, scene::Algorithm::SpanZBuffer)
}

#[cfg(not(target_os = "none"))]
/// [`accuracy`] for any hidden-surface method.
pub fn accuracy_with(
    spec: &SceneSpec,
    w: usize,
    h: usize,
    sub_bits: u32,
    algorithm: scene::Algorithm,
) -> Result<(Metrics, scene::FixedRender, reference::Image), String> {
    let fixed = spec.render_fixed_with(w, h, sub_bits, algorithm)?;
    judge(spec, w, h, scene::Precision::bits(sub_bits), fixed)
}

#[cfg(not(target_os = "none"))]
/// [`accuracy`] against a reference that culls back faces exactly when `spec` does: it
/// measures the renderer alone, where [`accuracy`] (whose reference sees every face) also
/// counts the faces that culling wrongly removed.
pub fn accuracy_same_culling(
    spec: &SceneSpec,
    w: usize,
    h: usize,
    sub_bits: u32,
) -> Result<(Metrics, scene::FixedRender, reference::Image), String> {
    accuracy_same_culling_with(spec, w, h, sub_bits, scene::Algorithm::SpanZBuffer)
}

#[cfg(not(target_os = "none"))]
/// [`accuracy_same_culling`] for any hidden-surface method.
pub fn accuracy_same_culling_with(
    spec: &SceneSpec,
    w: usize,
    h: usize,
    sub_bits: u32,
    algorithm: scene::Algorithm,
) -> Result<(Metrics, scene::FixedRender, reference::Image), String> {
    let fixed = spec.render_fixed_with(w, h, sub_bits, algorithm)?;
    let mut reference = spec.reference()?;
    reference.cull_back_faces = spec.cull_back_faces;
    compare_with(
        spec,
        w,
        h,
        scene::Precision::bits(sub_bits),
        fixed,
        reference,
    )
}

#[cfg(not(target_os = "none"))]
/// [`accuracy_with`] with the precision choices of a preset.
pub fn accuracy_preset(
    spec: &SceneSpec,
    w: usize,
    h: usize,
    preset: scene::PresetChoice,
    algorithm: scene::Algorithm,
) -> Result<(Metrics, scene::FixedRender, reference::Image), String> {
    let fixed = spec.render_fixed_preset(w, h, preset, algorithm)?;
    judge(spec, w, h, preset.precision(), fixed)
}

#[cfg(not(target_os = "none"))]
/// Compares a fixed-point render with the reference under the error bound of `precision`.
fn judge(
    spec: &SceneSpec,
    w: usize,
    h: usize,
    precision: scene::Precision,
    fixed: scene::FixedRender,
) -> Result<(Metrics, scene::FixedRender, reference::Image), String> {
    compare_with(spec, w, h, precision, fixed, spec.reference()?)
}

#[cfg(not(target_os = "none"))]
/// Compares a fixed-point render with `reference` under the error bound of `precision`.
fn compare_with(
    spec: &SceneSpec,
    w: usize,
    h: usize,
    precision: scene::Precision,
    fixed: scene::FixedRender,
    reference: reference::Scene,
) -> Result<(Metrics, scene::FixedRender, reference::Image), String> {
    let ref_image = reference.render(w, h);
    let bound = ErrorBound {
        sub_bits: precision.sub_bits,
        max_model_coord: spec.max_model_coord(),
        focal_px: reference.camera.focal_px(h),
        arithmetic: precision.documented_error(w, h, spec.max_model_coord()),
    };
    let m = metrics::compare(&fixed.image, &ref_image, &reference, &bound);
    Ok((m, fixed, ref_image))
}
