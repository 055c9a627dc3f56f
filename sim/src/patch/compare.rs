//! The library's patch renderer against the Bezier-clipping reference, pixel by pixel: where
//! the two disagree on coverage, how far that is from where the reference's coverage changes.

use super::fixed::{render_fixed, PatchShading};
use super::render::{distance_to_change, distance_to_change_finely, Reference};
use super::PatchModel;
use crate::scene::{CameraSpec, LightSpec};

/// One coverage mismatch.
#[derive(Clone, Copy, Debug)]
pub struct Mismatch {
    /// Pixel column and row.
    pub x: usize,
    /// Pixel row.
    pub y: usize,
    /// Whether the reference covers it (else the fixed renderer does).
    pub reference_covers: bool,
    /// Distance (px) from its centre to where the reference's coverage changes, 4 px at most.
    pub distance: f64,
}

/// A frame compared ([`coverage`]).
#[derive(Clone, Debug)]
pub struct Coverage {
    /// The mismatches.
    pub mismatches: Vec<Mismatch>,
    /// Whether the renderer reported a capped patch (its flatness not reached).
    pub capped: bool,
}

impl Coverage {
    /// The largest distance of a mismatch from a change of the reference's coverage.
    pub fn farthest(&self) -> f64 {
        self.mismatches
            .iter()
            .map(|m| m.distance)
            .fold(0.0, f64::max)
    }
}

/// `model` seen by `camera` at `side × side`, flat, two-sided, at `tolerance` px, by the
/// fixed renderer and the reference: each coverage mismatch with its distance from a change
/// of the reference's coverage (searched again finely where the coarse search finds none
/// within the tolerance plus 1/16 px, for slivers of a fold seen edge on). `None` for a model
/// or camera the tools refuse.
pub fn coverage(
    model: &PatchModel,
    camera: &CameraSpec,
    tolerance: f64,
    side: usize,
) -> Option<Coverage> {
    let light = LightSpec::default();
    let reference_camera = camera.reference().ok()?;
    let shading = PatchShading::Flat;
    let fixed = render_fixed(
        model,
        camera,
        &light,
        (side, side),
        tolerance,
        false,
        shading,
    )
    .ok()?;
    let reference = Reference::new(model.clone(), reference_camera, light.reference().ok()?);
    let (want, _) = reference.render(side, side);
    let covered = |x: f64, y: f64| i64::from(reference.cast(x, y, side, side).0.is_some());
    let mut mismatches = Vec::new();
    for i in 0..side * side {
        let reference_covers = want.ids[i] >= 0;
        if (fixed.image.ids[i] >= 0) == reference_covers {
            continue;
        }
        let (x, y) = (i % side, i / side);
        let centre = (x as f64 + 0.5, y as f64 + 0.5);
        let mut distance = distance_to_change(&covered, centre, 4.0);
        if distance > tolerance + 1.0 / 16.0 {
            distance = distance_to_change_finely(&covered, centre, 4.0);
        }
        mismatches.push(Mismatch {
            x,
            y,
            reference_covers,
            distance,
        });
    }
    Some(Coverage {
        mismatches,
        capped: fixed.stats.capped > 0,
    })
}
