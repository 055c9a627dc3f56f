//! The hidden-surface test scenes of `docs/hsr-table.md`: the firmware's generated copy has the
//! polygon counts the table claims and holds exactly the data the host tools render.

use scanline3d::scene::MeshColors;
use scanline3d_demo::hsr::HSR_MESHES;
use scanline3d_sim::{hsr, meshgen, scene::SceneSpec};

#[test]
fn scene_sizes_match_the_table() {
    for (level, meshes) in HSR_MESHES.iter().enumerate() {
        let n: usize = meshes.iter().map(|m| m.triangles().len()).sum();
        assert_eq!(n, meshgen::HSR_POLYGONS[level]);
        assert_eq!(n, hsr::LEVELS[level].polygons);
    }
    assert_eq!(meshgen::HSR_POLYGONS, [100, 2500, 60_000]);
}

#[test]
fn firmware_data_equals_host_scenes() {
    for (level, meshes) in HSR_MESHES.iter().enumerate() {
        let spec = SceneSpec::hsr(level).unwrap();
        assert_eq!(spec.instances.len(), meshes.len());
        for (m, i) in meshes.iter().zip(&spec.instances) {
            assert_eq!(m.vertices(), &i.mesh.vertices[..], "level {level}");
            assert_eq!(m.triangles(), &i.mesh.triangles[..], "level {level}");
            let MeshColors::PerFace(c) = m.colors() else {
                panic!("per-face colours expected")
            };
            assert_eq!(c, &i.mesh.colors[..], "level {level}");
        }
    }
}
