//! Every hidden-surface method against the f64 reference on the whole corpus (240×240, every
//! camera, 4 and 8 sub-pixel bits).
//!
//! * The exact methods (span z-buffer, full and band z-buffers, span sorting) must have zero
//!   real mismatches, and at most 0.1 % id mismatches at 8 sub-pixel bits: the thresholds of
//!   `accuracy.rs`, unchanged.
//! * Simple depth sort is the lecture's fast, wrong-in-cases baseline. It must fail on the
//!   lecture's failure cases (interpenetration, cyclic overlap), where every exact method is
//!   right; its failure rate on the whole corpus is printed
//!   (`cargo test --release -p scanline3d-sim --test suite hsr:: -- --nocapture`).

use scanline3d_sim::corpus;
use scanline3d_sim::metrics::{self, ErrorBound};
use scanline3d_sim::scene::{Algorithm, LightSpec, SceneSpec};

const W: usize = 240;
const H: usize = 240;

/// What one corpus scene gives: report lines, failures of the exact methods, and depth sort's
/// real mismatches and covered pixels at 4 sub-pixel bits.
struct SceneResult {
    name: &'static str,
    lines: Vec<String>,
    failures: Vec<String>,
    depth_sort_real: usize,
    covered: usize,
}

fn check_scene(scene: &corpus::CorpusScene) -> SceneResult {
    let mut r = SceneResult {
        name: scene.name,
        lines: Vec::new(),
        failures: Vec::new(),
        depth_sort_real: 0,
        covered: 0,
    };
    for (k, camera) in scene.cameras.iter().enumerate() {
        let spec = SceneSpec::single(
            scene.mesh.clone(),
            *camera,
            LightSpec::default(),
            scene.cull_back_faces,
        );
        let reference = spec.reference().unwrap();
        let ref_image = reference.render(W, H);
        for sub_bits in [4, 8] {
            let bound = ErrorBound {
                sub_bits,
                max_model_coord: spec.max_model_coord(),
                focal_px: reference.camera.focal_px(H),
                arithmetic: Default::default(),
            };
            for algorithm in Algorithm::ALL {
                let fixed = spec.render_fixed_with(W, H, sub_bits, algorithm).unwrap();
                let m = metrics::compare(&fixed.image, &ref_image, &reference, &bound);
                let what = format!("{} cam {k} S={sub_bits} {algorithm}", scene.name);
                r.lines.push(format!(
                    "{what:40} {:5} id mismatches ({:.3} %), real {}",
                    m.id_mismatches,
                    m.id_mismatch_percent(),
                    m.real
                ));
                if !algorithm.is_exact() {
                    if sub_bits == 4 {
                        r.depth_sort_real += m.real;
                        r.covered += ref_image.ids.iter().filter(|&&i| i >= 0).count();
                    }
                    continue;
                }
                if m.real > 0 {
                    r.failures
                        .push(format!("{what}: {} real mismatches", m.real));
                }
                if sub_bits == 8 && m.id_mismatch_percent() > 0.1 {
                    let pc = m.id_mismatch_percent();
                    r.failures.push(format!("{what}: {pc:.3} % id mismatches"));
                }
                if m.depth_beyond_bound > 0 {
                    let n = m.depth_beyond_bound;
                    r.failures
                        .push(format!("{what}: {n} pixels beyond the depth bound"));
                }
            }
        }
    }
    r
}

#[test]
fn every_method_against_the_reference() {
    // One thread per scene: the scenes are independent, and this is the longest test.
    let scenes = corpus::all();
    let results: Vec<SceneResult> = std::thread::scope(|s| {
        let handles: Vec<_> = scenes
            .iter()
            .map(|scene| s.spawn(move || check_scene(scene)))
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("a scene's thread panicked"))
            .collect()
    });
    let mut failures = Vec::new();
    // Real mismatches of depth sort per scene, summed over cameras, at 4 sub-pixel bits.
    let mut depth_sort_real = std::collections::BTreeMap::new();
    let (mut ds_real, mut ds_pixels) = (0usize, 0usize);
    for r in results {
        for line in &r.lines {
            println!("{line}");
        }
        failures.extend(r.failures);
        depth_sort_real.insert(r.name, r.depth_sort_real);
        ds_real += r.depth_sort_real;
        ds_pixels += r.covered;
    }
    println!("depth sort, real mismatches per scene (all cameras, 4 sub-pixel bits): {depth_sort_real:?}");
    println!(
        "depth sort overall: {ds_real} of {ds_pixels} covered pixels wrong ({:.2} %)",
        100.0 * ds_real as f64 / ds_pixels as f64
    );
    // The lecture's failure cases: one depth per triangle cannot order these.
    for case in ["interpenetrating", "cyclic"] {
        assert!(
            depth_sort_real[case] > 50,
            "depth sort should fail on {case}: {depth_sort_real:?}"
        );
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// The capacities of the lecture's table (`hsr::LEVELS`) hold for every method at every
/// level: `cargo xtask hsr-table` runs these frames on the firmware, where a capacity that no
/// longer fits (Newell's pieces, say, after a change to how it splits) would end the run.
#[test]
fn every_method_fits_the_table_capacities() {
    use embedded_graphics::pixelcolor::{Rgb565, RgbColor};
    use scanline3d::sink::HashSink;
    use scanline3d_sim::hsr::{self, Method, Resolve, Visit};

    struct Fits(Vec<scanline3d_sim::scene::SceneSpec>);
    impl Visit for Fits {
        type Error = String;
        fn visit<M: Method, const T: usize, const A: usize, const K: usize>(
            &mut self,
            level: usize,
        ) -> Result<(), String> {
            let mut ws = Box::new(M::Ws::<Rgb565, T, A, K>::new(Rgb565::BLACK));
            let stats = self.0[level].with_scene(|scene| {
                ws.frame(scene, &mut HashSink::new())
                    .map_err(|e| format!("{} at level {level}: {e}", M::NAME))
            })??;
            if stats.is_complete() {
                Ok(())
            } else {
                Err(format!("{} at level {level}: incomplete frame", M::NAME))
            }
        }
    }
    let specs = (0..hsr::LEVELS.len())
        .map(scanline3d_sim::scene::SceneSpec::hsr)
        .collect::<Result<Vec<_>, String>>()
        .unwrap();
    // The workspaces are built by value (megabytes at the largest level): on a thread with
    // room for them.
    std::thread::Builder::new()
        .stack_size(256 << 20)
        .spawn(move || hsr::for_each(&mut Fits(specs)))
        .unwrap()
        .join()
        .unwrap()
        .unwrap();
}
