//! The fixed-point tracer against the f64 tracer on random traced scenes: the check
//! `trace_fixed::fixed_tracer_matches_the_reference_on_random_scenes` makes on the first 1,200
//! scenes of seed 0, for any number and seed.
//!
//! ```sh
//! cargo run --release -p scanline3d-sim --example trace_random -- [CASES [SEED [CASE]]]
//! ```
//!
//! Prints the cases with primary-id or shadow-mask mismatches that no edge of the reference
//! explains (24×24, no structure, the case's depth limit); with a CASE, its scene, camera and
//! pixels.

use scanline3d_sim::draw::{Draw, TracedDraw};
use scanline3d_sim::trace::{compare, whitted::Limits};

const SIDE: usize = 24;

fn main() {
    let arg = |k: usize| std::env::args().nth(k).and_then(|a| a.parse::<u64>().ok());
    let cases = arg(1).unwrap_or(3000) as usize;
    let seed = arg(2).unwrap_or(0);
    let only = arg(3).map(|c| c as usize);
    let mut d = Draw::new(0x2545_f491_4f6c_dd1d ^ seed.wrapping_mul(0x9e37_79b9_7f4a_7c15));
    let (mut frames, mut failing) = (0, Vec::new());
    for case in 0..cases {
        let Some((text, cam)) = TracedDraw::case(&mut d, case) else {
            continue;
        };
        if only.is_some_and(|o| o != case) {
            continue;
        }
        let limits = Limits {
            max_depth: 1 + (case % 5) as u32,
            threshold: 1.0 / 256.0,
        };
        let Some(u) = compare::unexplained(&text, &cam, SIDE, limits) else {
            continue;
        };
        frames += 1;
        if u != compare::Unexplained::default() {
            println!(
                "case {case}: {} ids, {} shadow masks unexplained",
                u.ids.len(),
                u.shadows.len()
            );
            failing.push(case);
        }
        if only.is_some() {
            println!("{text}{cam:?}");
            for (what, pixels) in [("id", &u.ids), ("shadow", &u.shadows)] {
                for i in pixels {
                    println!("  {what} mismatch at pixel ({}, {})", i % SIDE, i / SIDE);
                }
            }
        }
    }
    println!(
        "{frames} frames (seed {seed}), {} with unexplained mismatches: {failing:?}",
        failing.len()
    );
}
