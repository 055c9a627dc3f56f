//! The precision variants `cargo xtask tradeoff` measures (`docs/tradeoff.md`): the presets of
//! `scanline3d::preset`, and the default with one knob changed, so each knob's own effect shows.

use crate::corpus;
use crate::metrics::{self, ErrorBound, Metrics};
use crate::scene::{DepthChoice, Precision, PresetChoice, SceneSpec, SetupArith, SetupMath};

/// One set of precision choices.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Variant {
    /// Name in the table (a preset's name, or the knob changed).
    pub name: &'static str,
    /// The preset, if this is one.
    pub preset: Option<PresetChoice>,
    /// Its choices.
    pub precision: Precision,
}

const fn preset(p: PresetChoice, name: &'static str, precision: Precision) -> Variant {
    Variant {
        name,
        preset: Some(p),
        precision,
    }
}

/// The library default (`RenderOptions::default()`: 4 sub-pixel bits, precise arithmetic,
/// libm, 32-bit depth) with the choices `precision` changes, or (`"default"`) unchanged.
const fn knob(name: &'static str, precision: Precision) -> Variant {
    Variant {
        name,
        preset: None,
        precision,
    }
}

/// The default's choices.
const DEFAULT: Precision = Precision::bits(4);

const fn choices(sub_bits: u32, arith: SetupArith) -> Precision {
    Precision {
        sub_bits,
        arith,
        ..DEFAULT
    }
}

/// Every variant, in the order of `firmware/examples/tradeoff.rs` (a test keeps the presets' entries
/// equal to `scanline3d::preset`). A knob's name is also its `scanline3d_variant` cfg value with
/// `:` and spaces removed.
pub const VARIANTS: [Variant; 10] = [
    preset(
        PresetChoice::Fast,
        "fast",
        choices(2, SetupArith::NarrowTransform),
    ),
    preset(
        PresetChoice::Balanced,
        "balanced",
        choices(4, SetupArith::Precise),
    ),
    preset(
        PresetChoice::Exact,
        "exact",
        choices(8, SetupArith::Precise),
    ),
    knob("default", DEFAULT),
    knob("bits:0", Precision::bits(0)),
    knob(
        "micromath",
        Precision {
            math: SetupMath::Micromath,
            ..DEFAULT
        },
    ),
    knob("narrow-transform", choices(4, SetupArith::NarrowTransform)),
    knob("reciprocal", choices(4, SetupArith::Reciprocal)),
    knob("narrow-normals", choices(4, SetupArith::NarrowNormals)),
    knob(
        "depth16",
        Precision {
            depth: DepthChoice::Q16,
            ..DEFAULT
        },
    ),
];

/// One variant on one corpus scene and camera, against the f64 reference.
#[derive(Clone, Debug)]
pub struct Accuracy {
    /// Variant name.
    pub variant: &'static str,
    /// Corpus scene.
    pub scene: &'static str,
    /// Camera index.
    pub camera: usize,
    /// Comparison with the reference under the variant's error bound.
    pub metrics: Metrics,
}

/// Every variant on every corpus scene and camera at `w × h` (the reference rendered once per
/// camera); `progress(done, total)` after each camera.
pub fn corpus_accuracy(
    w: usize,
    h: usize,
    progress: impl FnMut(usize, usize),
) -> Result<Vec<Accuracy>, String> {
    let mut out = Vec::new();
    let each = |scene, camera, spec: SceneSpec| {
        let reference = spec.reference()?;
        let ref_image = reference.render(w, h);
        for v in VARIANTS {
            let fixed = spec.render_fixed_settings(
                w,
                h,
                v.precision,
                crate::scene::Algorithm::SpanZBuffer,
            )?;
            let bound = ErrorBound {
                sub_bits: v.precision.sub_bits,
                max_model_coord: spec.max_model_coord(),
                focal_px: reference.camera.focal_px(h),
                arithmetic: v.precision.documented_error(w, h, spec.max_model_coord()),
            };
            out.push(Accuracy {
                variant: v.name,
                scene,
                camera,
                metrics: metrics::compare(&fixed.image, &ref_image, &reference, &bound),
            });
        }
        Ok(())
    };
    corpus::for_each_view(each, progress)?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn preset_variants_are_the_library_presets() {
        for v in VARIANTS {
            if let Some(p) = v.preset {
                assert_eq!((v.name, v.precision), (p.name(), p.precision()));
            }
        }
        assert_eq!(
            VARIANTS.iter().filter(|v| v.preset.is_some()).count(),
            PresetChoice::ALL.len()
        );
    }
}
