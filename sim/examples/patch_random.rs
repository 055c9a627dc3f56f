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
//! of `patch_compare::trimmed_holes_appear_where_the_trim_says`; `patch::compare::coverage`
//! searches a distance over that again finely, for slivers the coarse search steps over). Prints the cases where one
//! does not, or the renderer reports a capped patch, with the largest distance (the search
//! reaches 4 px: 4.000 means "4 px or more"); with a CASE, its model, camera and every
//! mismatched pixel.

use scanline3d_sim::draw::PatchDraw;
use scanline3d_sim::patch::compare::coverage;

const SIDE: usize = 48;

fn main() {
    let arg = |k: usize| std::env::args().nth(k).and_then(|a| a.parse::<u64>().ok());
    let cases = arg(1).unwrap_or(200) as usize;
    let only = arg(2).map(|c| c as usize);
    let mut d = PatchDraw::draws();
    let (mut frames, mut capped, mut beyond) = (0, Vec::new(), Vec::new());
    for case in 0..cases {
        let (model, camera, tolerance) = PatchDraw::case(&mut d, case);
        if only.is_some_and(|o| o != case) {
            continue;
        }
        // Cameras and models the tools refuse (outside the fixed-point envelope) are skipped.
        let Some(c) = coverage(&model, &camera, tolerance, SIDE) else {
            continue;
        };
        frames += 1;
        let rational = model
            .patches
            .iter()
            .any(|p| p.weights.iter().any(|&w| w != 1.0));
        let far = c.farthest();
        if only.is_some() {
            for m in &c.mismatches {
                println!(
                    "  ({}, {}): covered by the {} only, {:.3} px from a change",
                    m.x,
                    m.y,
                    if m.reference_covers {
                        "reference"
                    } else {
                        "fixed renderer"
                    },
                    m.distance
                );
            }
        }
        let over = far > tolerance + 1.0 / 16.0;
        if c.capped {
            capped.push((case, over));
        } else if over {
            beyond.push((case, rational, far - tolerance));
        }
        if c.capped || over || only.is_some() {
            println!(
                "case {case}: {}, tolerance {tolerance} px, {} mismatches, the farthest {far:.3} px from a change{}",
                if rational { "rational" } else { "polynomial" },
                c.mismatches.len(),
                if c.capped { ", capped (reported)" } else { "" }
            );
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
        "{frames} frames; {} with a capped patch (reported; {} of them beyond the tolerance plus 1/16 px); beyond the tolerance plus 1/16 px, not capped: {polynomial} polynomial (up to {p_far:.2} px over), {rational} rational (up to {r_far:.2} px over): {:?}",
        capped.len(),
        capped.iter().filter(|c| c.1).count(),
        beyond.iter().map(|b| b.0).collect::<Vec<_>>()
    );
}
