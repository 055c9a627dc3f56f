//! Gouraud interpolation modes against the f64 reference on every corpus scene and camera, with
//! a different colour at each vertex (`docs/tradeoff.md`, "Gouraud attribute interpolation").

use scanline3d_sim::interpolation::{corpus_errors, Mode};

#[test]
fn perspective_correct_modes_approach_the_reference_and_affine_does_not() {
    let all = corpus_errors(240, 240, |_, _| {}).unwrap();
    let of = |m: Mode| all.iter().filter(move |e| e.mode == m);
    let mean = |m: Mode| of(m).map(|e| e.error.mean).sum::<f64>() / of(m).count() as f64;
    let worst = |m: Mode| of(m).map(|e| e.error.max).max().unwrap_or(0);
    for m in Mode::ALL {
        println!(
            "{:>10}: mean channel error {:.3}, worst {}",
            m.name(),
            mean(m),
            worst(m)
        );
    }
    // Per pixel, what is left is rounding: lit vertex colours rounded to bytes, channels
    // truncated to bytes (half a unit on average), sub-pixel snapping moving tiny triangles'
    // gradients a little.
    assert!(mean(Mode::PerPixel) < 0.6, "{}", mean(Mode::PerPixel));
    // Segments are exact at their ends and affine between: a little worse, by segment length.
    assert!(mean(Mode::PerPixel) <= mean(Mode::Segments8));
    assert!(mean(Mode::Segments8) <= mean(Mode::Segments16));
    assert!(mean(Mode::Segments16) < 0.6, "{}", mean(Mode::Segments16));
    // Affine drifts wherever a triangle recedes: several times the error on average.
    assert!(mean(Mode::Affine) > 5.0 * mean(Mode::PerPixel));
    assert!(worst(Mode::PerPixel) <= worst(Mode::Affine));
    // Per view, perspective correction never makes the picture worse.
    for e in of(Mode::PerPixel) {
        let affine = of(Mode::Affine)
            .find(|a| a.scene == e.scene && a.camera == e.camera)
            .map(|a| a.error.mean);
        assert!(
            affine.is_some_and(|a| e.error.mean <= a + 0.01),
            "{} camera {}: per pixel {:?}, affine {affine:?}",
            e.scene,
            e.camera,
            e.error
        );
    }
}
