//! Where Newell–Newell–Sancha's order differs from the span z-buffer's on the issue-20 scenes
//! (the soup from outside and inside, the scanned-style mesh), at the default 4 sub-pixel
//! bits: its accuracy against the f64 reference, its host time, and the (shown, expected) id
//! pairs of the pixels where its image differs from the span z-buffer's (which has no real
//! mismatches there). Quoted in docs/realworld.md.
//!
//! `cargo run --release -p scanline3d-sim --example newell_pairs`

use scanline3d_sim::accuracy_with;
use scanline3d_sim::corpus::real_world;
use scanline3d_sim::scene::{Algorithm, CameraSpec, LightSpec, MeshData, SceneSpec};
use scanline3d_sim::world::{Culling, Loaded, World};
use std::collections::BTreeMap;

const W: usize = 240;
const H: usize = 240;

/// The scene `sim render` makes of `mesh` seen by `camera` with default culling.
fn spec_of(mesh: &MeshData, camera: CameraSpec) -> Result<SceneSpec, String> {
    let loaded = Loaded::from_world(World::from_mesh(mesh), false)?;
    let cull = loaded
        .culling(Culling::Auto, &[camera], W as f64 / H as f64)
        .cull;
    Ok(SceneSpec {
        instances: loaded.instances,
        camera,
        light: LightSpec::default(),
        cull_back_faces: cull,
    })
}

fn main() -> Result<(), String> {
    let soup = real_world::soup();
    let [outside, inside] = real_world::soup_cameras();
    let scanned = real_world::scanned();
    for (name, spec) in [
        ("soup outside", spec_of(&soup, outside)?),
        ("soup inside", spec_of(&soup, inside)?),
        (
            "scanned",
            spec_of(&scanned, real_world::scanned_cameras()[0])?,
        ),
    ] {
        let start = std::time::Instant::now();
        let (m, newell, _) = accuracy_with(&spec, W, H, 4, Algorithm::Newell)?;
        let seconds = start.elapsed().as_secs_f64();
        let (_, span, _) = accuracy_with(&spec, W, H, 4, Algorithm::SpanZBuffer)?;
        let mut pairs: BTreeMap<(i32, i32), usize> = BTreeMap::new();
        for (&n, &s) in newell.image.ids.iter().zip(&span.image.ids) {
            if n != s {
                *pairs.entry((n, s)).or_default() += 1;
            }
        }
        let mut by_count: Vec<_> = pairs.into_iter().collect();
        by_count.sort_by_key(|&(pair, count)| (std::cmp::Reverse(count), pair));
        println!(
            "{name}: id mismatch {:.3} %, real {}, {seconds:.2} s; pixels differing from the span z-buffer by (newell id, span z-buffer id), most first: {:?}",
            m.id_mismatch_percent(),
            m.real,
            &by_count[..by_count.len().min(8)]
        );
    }
    Ok(())
}
