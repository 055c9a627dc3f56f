//! The library's fixed-point patch renderer against the Bezier-clipping reference on random
//! single patches (`draw::PatchDraw`: polynomial, rational and trimmed, at three scales, random
//! cameras, tolerances 0.5 to 2 px), 48×48, flat, two-sided.
//!
//! ```sh
//! cargo run --release -p scanline3d-sim --example patch_random -- [CASES [CASE]]
//! ```
//!
//! A pixel covered by one renderer and not the other should lie within the tolerance plus
//! 1/16 px (the snapped vertices) of a place where the reference's coverage changes (the rule
//! of `patch_compare::trimmed_holes_appear_where_the_trim_says`; a distance over that is
//! searched again finely, for slivers of surface the coarse search steps over). Prints the cases where one
//! does not, or the renderer reports a capped patch, with the largest distance (the search
//! reaches 4 px: 4.000 means "4 px or more"); with a CASE, its model, camera and every
//! mismatched pixel.

use scanline3d_sim::draw::PatchDraw;
use scanline3d_sim::patch::fixed::{render_fixed, PatchShading};
use scanline3d_sim::patch::render::{distance_to_change, distance_to_change_finely, Reference};
use scanline3d_sim::scene::LightSpec;

const SIDE: usize = 48;

fn main() {
    let arg = |k: usize| std::env::args().nth(k).and_then(|a| a.parse::<u64>().ok());
    let cases = arg(1).unwrap_or(200) as usize;
    let only = arg(2).map(|c| c as usize);
    let mut d = PatchDraw::draws();
    let light = LightSpec::default();
    let Ok(light_ref) = light.reference() else {
        panic!("light");
    };
    let (mut frames, mut capped, mut beyond) = (0, Vec::new(), Vec::new());
    for case in 0..cases {
        let (model, camera, tolerance) = PatchDraw::case(&mut d, case);
        if only.is_some_and(|o| o != case) {
            continue;
        }
        // Cameras and models the tools refuse (outside the fixed-point envelope) are skipped.
        let Ok(reference_camera) = camera.reference() else {
            continue;
        };
        let shading = PatchShading::Flat;
        let Ok(fixed) = render_fixed(
            &model,
            &camera,
            &light,
            (SIDE, SIDE),
            tolerance,
            false,
            shading,
        ) else {
            continue;
        };
        let rational = model
            .patches
            .iter()
            .any(|p| p.weights.iter().any(|&w| w != 1.0));
        let reference = Reference::new(model.clone(), reference_camera, light_ref);
        let (want, _) = reference.render(SIDE, SIDE);
        let covered = |x: f64, y: f64| i64::from(reference.cast(x, y, SIDE, SIDE).0.is_some());
        frames += 1;
        let (mut mismatches, mut far) = (0, 0.0f64);
        for i in 0..SIDE * SIDE {
            let (x, y) = (i % SIDE, i / SIDE);
            if (fixed.image.ids[i] >= 0) != (want.ids[i] >= 0) {
                mismatches += 1;
                let centre = (x as f64 + 0.5, y as f64 + 0.5);
                let mut distance = distance_to_change(&covered, centre, 4.0);
                if distance > tolerance + 1.0 / 16.0 {
                    // Look again for a sliver the coarse search stepped over.
                    distance = distance_to_change_finely(&covered, centre, 4.0);
                }
                far = far.max(distance);
                if only.is_some() {
                    println!(
                        "  ({x}, {y}): covered by the {} only, {distance:.3} px from a change",
                        if want.ids[i] >= 0 {
                            "reference"
                        } else {
                            "fixed renderer"
                        }
                    );
                }
            }
        }
        let kind = if rational { "rational" } else { "polynomial" };
        let line = format!(
            "case {case}: {kind}, tolerance {tolerance} px, {mismatches} mismatches, the farthest {far:.3} px from a change{}",
            if fixed.stats.capped > 0 { ", capped (reported)" } else { "" }
        );
        if fixed.stats.capped > 0 {
            capped.push(case);
        } else if far > tolerance + 1.0 / 16.0 {
            beyond.push((case, rational, far - tolerance));
        }
        if fixed.stats.capped > 0 || far > tolerance + 1.0 / 16.0 || only.is_some() {
            println!("{line}");
        }
        if only.is_some() {
            println!("{model:?}\n{camera:?}");
        }
    }
    let over = |r: bool| {
        let v: Vec<f64> = beyond.iter().filter(|b| b.1 == r).map(|b| b.2).collect();
        (v.len(), v.iter().fold(0.0f64, |m, &e| m.max(e)))
    };
    let ((polynomial, p_far), (rational, r_far)) = (over(false), over(true));
    println!(
        "{frames} frames; {} with a capped patch (reported); beyond the tolerance plus 1/16 px, not capped: {polynomial} polynomial (up to {p_far:.2} px over), {rational} rational (up to {r_far:.2} px over): {:?}",
        capped.len(),
        beyond.iter().map(|b| b.0).collect::<Vec<_>>()
    );
}
