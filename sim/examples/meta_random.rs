//! The library's fixed-point metaball caster against the f64 reference on random scenes: the
//! checks `metaball::fixed_caster_matches_reference_on_the_corpus` makes, on 1 to 8 balls
//! (about a fifth of negative density) at four scales, seen by random cameras, 48×48.
//!
//! ```sh
//! cargo run --release -p scanline3d-sim --example meta_random -- [CASES [CASE]]
//! ```
//!
//! Prints the cases with coverage mismatches off the silhouette or depths the caster's stopping
//! rule does not explain (`metaball::compare`); with a CASE, its scene, camera and the pixels
//! whose depths differ by more than 0.01 or are unexplained.

use scanline3d_sim::draw::MetaDraw;
use scanline3d_sim::metaball::compare::{check, stop_ratio};

const SIDE: usize = 48;

fn main() {
    let arg = |k: usize| std::env::args().nth(k).and_then(|a| a.parse::<u64>().ok());
    let cases = arg(1).unwrap_or(200) as usize;
    let only = arg(2).map(|c| c as usize);
    let mut d = MetaDraw::draws();
    let (mut frames, mut failing, mut capped) = (0, Vec::new(), Vec::new());
    for case in 0..cases {
        let (scene, camera) = MetaDraw::case(&mut d, case);
        if only.is_some_and(|o| o != case) {
            continue;
        }
        let Some(c) = check(scene, camera, SIDE) else {
            continue;
        };
        frames += 1;
        if c.stats.capped > 0 {
            capped.push(case);
        }
        if !c.explained() {
            println!("case {case}: {}", c.comparison);
            failing.push(case);
        }
        if only.is_some() {
            println!("{:?}\n{:?}\n{:?}", c.scene, c.camera, c.stats);
            for i in 0..SIDE * SIDE {
                let (x, y) = (i % SIDE, i / SIDE);
                let (t, tf) = (c.expected.depth[i] as f64, c.fixed.depth[i] as f64);
                if (c.expected.ids[i] < 0) != (c.fixed.ids[i] < 0) {
                    println!(
                        "  pixel ({x}, {y}): covered by {} only, depth {}",
                        if c.fixed.ids[i] < 0 {
                            "the reference"
                        } else {
                            "the caster"
                        },
                        c.expected.depth[i].max(c.fixed.depth[i])
                    );
                }
                if c.expected.ids[i] < 0 || c.fixed.ids[i] < 0 {
                    continue;
                }
                let d = c
                    .reference
                    .camera
                    .ray(x as f64 + 0.5, y as f64 + 0.5, SIDE, SIDE);
                let ratio = stop_ratio(&c.reference, d, t, tf);
                if ratio > 1.0 || (t - tf).abs() > 0.01 {
                    println!(
                        "  pixel ({x}, {y}): ids {} {}, depth reference {t}, fixed {tf}, |g| over its band {ratio:.3}",
                        c.expected.ids[i], c.fixed.ids[i]
                    );
                }
            }
        }
    }
    println!(
        "{frames} frames, {} with mismatches off the silhouette or depths the stopping rule does not explain: {failing:?}; {} with a ray capped: {capped:?}",
        failing.len(),
        capped.len()
    );
}
