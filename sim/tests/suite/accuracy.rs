//! Every corpus scene, from several cameras, rendered by the fixed-point renderer at its default
//! (4 sub-pixel bits) and most accurate (8) settings and compared with the f64 reference.
//!
//! Thresholds, written once:
//! * zero *real* mismatches at both settings: every difference must be explained by the
//!   documented position error bound or a depth tie (see `metrics`);
//! * at 8 sub-pixel bits, all id mismatches together at most 0.1 % of pixels (a production GL
//!   rasterizer with 8 sub-pixel bits stays under 0.06 % against an f64 ray caster on scenes
//!   like these);
//! * no pixel's depth error beyond its bound (depth format resolution plus the depth change
//!   the position bound allows on that surface).

use scanline3d_sim::{accuracy, corpus, scene::LightSpec, scene::SceneSpec};

const W: usize = 240;
const H: usize = 240;

#[test]
fn corpus_matches_reference() {
    let mut failures = Vec::new();
    for scene in corpus::all() {
        for (k, camera) in scene.cameras.iter().enumerate() {
            let spec = SceneSpec::single(
                scene.mesh.clone(),
                *camera,
                LightSpec::default(),
                scene.cull_back_faces,
            );
            for sub_bits in [4, 8] {
                let (m, fixed, _) = accuracy(&spec, W, H, sub_bits).unwrap();
                println!(
                    "{:16} cam {} S={}: {:5} id mismatches ({:.3} %), explained {} edge + {} depth, real {}, depth max {:.2e}, beyond bound {}, PSNR {:.1} dB, {} drawn",
                    scene.name, k, sub_bits, m.id_mismatches, m.id_mismatch_percent(), m.explained_edge, m.explained_depth, m.real, m.depth_max_rel, m.depth_beyond_bound, m.psnr, fixed.stats.activated
                );
                if m.real > 0 {
                    failures.push(format!(
                        "{} cam {k} S={sub_bits}: {} real mismatches",
                        scene.name, m.real
                    ));
                }
                if sub_bits == 8 && m.id_mismatch_percent() > 0.1 {
                    failures.push(format!(
                        "{} cam {k} S=8: {:.3} % id mismatches",
                        scene.name,
                        m.id_mismatch_percent()
                    ));
                }
                if m.depth_beyond_bound > 0 {
                    failures.push(format!(
                        "{} cam {k} S={sub_bits}: {} pixels beyond the depth bound",
                        scene.name, m.depth_beyond_bound
                    ));
                }
                // The comparison must have something to compare.
                assert!(
                    fixed.image.ids.iter().filter(|&&i| i >= 0).count() > 500,
                    "{} cam {k}: nearly empty",
                    scene.name
                );
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}
