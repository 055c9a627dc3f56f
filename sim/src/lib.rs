//! Host tools for scanline3d: the float reference, accuracy metrics, the scene corpus and the
//! scene/image formats the `sim` binary reads and writes.

pub mod corpus;
pub mod fuzz;
pub mod meshgen;
pub mod metrics;
pub mod reference;
pub mod scene;

use metrics::{ErrorBound, Metrics};
use scene::SceneSpec;

/// Renders `spec` with the fixed-point renderer (at `sub_bits`) and the reference, and compares
/// them with the documented error bound.
pub fn accuracy(
    spec: &SceneSpec,
    w: usize,
    h: usize,
    sub_bits: u32,
) -> Result<(Metrics, scene::FixedRender, reference::Image), String> {
    let fixed = spec.render_fixed(w, h, sub_bits)?;
    let reference = spec.reference()?;
    let ref_image = reference.render(w, h);
    let bound = ErrorBound {
        sub_bits,
        max_model_coord: spec.max_model_coord(),
        focal_px: reference.camera.focal_px(h),
    };
    let m = metrics::compare(&fixed.image, &ref_image, &reference, &bound);
    Ok((m, fixed, ref_image))
}
