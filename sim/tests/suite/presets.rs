//! The precision presets against the f64 reference on every corpus scene and camera: what
//! `scanline3d::preset` and `docs/tradeoff.md` claim for each.

use scanline3d_sim::tradeoff::{corpus_accuracy, VARIANTS};

#[test]
fn presets_meet_their_accuracy_claims_on_the_corpus() {
    let all = corpus_accuracy(240, 240, |_, _| {}).unwrap();
    assert_eq!(all.len() % VARIANTS.len(), 0);
    let of = |name: &'static str| all.iter().filter(move |a| a.variant == name);
    // Every preset (and the coarsest setting) is free of real mismatches and keeps depth within
    // its bound everywhere.
    // So is each narrow knob, under the error it documents (arithmetic, depth resolution).
    for name in [
        "fast",
        "balanced",
        "exact",
        "default",
        "bits:0",
        "narrow-transform",
        "reciprocal",
        "narrow-normals",
        "depth16",
    ] {
        for a in of(name) {
            let m = &a.metrics;
            assert_eq!(m.real, 0, "{name} on {} camera {}: {m}", a.scene, a.camera);
            assert_eq!(
                m.depth_beyond_bound, 0,
                "{name} on {} camera {}",
                a.scene, a.camera
            );
        }
    }
    // Exact: at most 0.1 % id mismatches on every view.
    for a in of("exact") {
        let p = a.metrics.id_mismatch_percent();
        assert!(
            p <= 0.1,
            "exact on {} camera {}: {p:.3} %",
            a.scene,
            a.camera
        );
    }
    // Each step down in sub-pixel bits costs accuracy: mean id mismatches grow.
    let mean = |name: &'static str| {
        let v: Vec<f64> = of(name).map(|a| a.metrics.id_mismatch_percent()).collect();
        v.iter().sum::<f64>() / v.len() as f64
    };
    assert!(mean("exact") < mean("balanced"));
    assert!(mean("balanced") < mean("fast"));
    assert!(mean("fast") < mean("bits:0"));
    // Micromath set-up is in no preset because its camera error is beyond the error bound.
    assert!(of("micromath").map(|a| a.metrics.real).sum::<usize>() > 0);
}
