//! The library's fixed-point metaball caster against the f64 reference on random scenes: the
//! checks `metaball::fixed_caster_matches_reference_on_the_corpus` makes, on 1 to 8 balls
//! (about a fifth of negative density) at four scales, seen by random cameras, 48×48.
//!
//! ```sh
//! cargo run --release -p scanline3d-sim --example meta_random -- [CASES [CASE]]
//! ```
//!
//! Prints the cases with coverage mismatches off the silhouette or depth errors over the
//! caster's bound (`metaball::compare`); with a CASE, its scene, camera and the pixels whose
//! depths differ by more than 0.01.

use scanline3d_sim::draw::Draw;
use scanline3d_sim::metaball::compare::{compare, render_fixed};
use scanline3d_sim::metaball::reference::Reference;
use scanline3d_sim::metaball::{BallSpec, MetaScene};
use scanline3d_sim::scene::CameraSpec;

const SIDE: usize = 48;

/// Scene and camera of case `case`, at scale 1, 0.1, 10 or 100 (`case % 4`).
fn draw(d: &mut Draw, case: usize) -> (MetaScene, CameraSpec) {
    let scale = [1.0, 0.1, 10.0, 100.0][case % 4];
    let n = 1 + (d.in_range(0.0, 1.0) * 8.0) as usize;
    let balls = (0..n)
        .map(|_| BallSpec {
            centre: d.point(scale),
            radius: d.in_range(0.3, 2.0) * scale,
            density: if d.in_range(0.0, 1.0) < 0.2 {
                -d.in_range(0.3, 1.0)
            } else {
                d.in_range(0.5, 1.5)
            },
            color: [0; 3].map(|_| d.in_range(0.0, 1.0)),
            keys: vec![],
        })
        .collect();
    let scene = MetaScene {
        threshold: d.in_range(0.1, 0.9),
        light: ([0.0, 0.0, 1.0], 0.2, 0.8),
        balls,
    };
    let camera = CameraSpec {
        eye: d.point(5.0 * scale),
        target: d.point(scale),
        up: [0.0, 1.0, 0.0],
        fovy: d.in_range(20.0, 120.0),
        near: d.in_range(0.01, 0.5) * scale,
        far: 20.0 * scale,
    };
    (scene, camera)
}

fn main() {
    let arg = |k: usize| std::env::args().nth(k).and_then(|a| a.parse::<u64>().ok());
    let cases = arg(1).unwrap_or(200) as usize;
    let only = arg(2).map(|c| c as usize);
    let mut d = Draw::new(0x1234_5678_9abc_def1);
    let (mut frames, mut failing) = (0, Vec::new());
    for case in 0..cases {
        let (scene, camera) = draw(&mut d, case);
        if only.is_some_and(|o| o != case) {
            continue;
        }
        // Scenes and cameras the tools refuse (outside the caster's envelope) are skipped.
        let Ok(reference) = camera
            .reference()
            .and_then(|c| Reference::new(&scene, 0, c))
        else {
            continue;
        };
        let Ok((image, _)) = render_fixed(&scene, 0, &camera, SIDE, SIDE) else {
            continue;
        };
        let (expected, _) = reference.render(SIDE, SIDE);
        let m = compare(&image, &expected, &reference);
        frames += 1;
        if m.off_silhouette > 0 || m.depth_over_bound > 0 {
            println!("case {case}: {m}");
            failing.push(case);
        }
        if only.is_some() {
            println!("{scene:?}\n{camera:?}");
            for i in 0..SIDE * SIDE {
                let (t, tf) = (expected.depth[i] as f64, image.depth[i] as f64);
                if expected.ids[i] >= 0 && image.ids[i] >= 0 && (t - tf).abs() > 0.01 {
                    println!(
                        "  pixel ({}, {}): ids {} {}, depth reference {t}, fixed {tf}",
                        i % SIDE,
                        i / SIDE,
                        expected.ids[i],
                        image.ids[i]
                    );
                }
            }
        }
    }
    println!(
        "{frames} frames, {} with mismatches off the silhouette or depths over the bound: {failing:?}",
        failing.len()
    );
}
