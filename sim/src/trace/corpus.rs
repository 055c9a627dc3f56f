//! The traced-scene corpus: the scene files in `sim/scenes/` with their cameras, so tests,
//! `sim trace` users and xtask can enumerate them.
//!
//! The one generated file, `sim/scenes/icosphere.obj` (1,280 triangles), is meshgen's
//! icosphere written by [`icosphere_obj`]; a test checks the committed file is exactly that,
//! and `cargo test -p scanline3d-sim --lib trace::corpus -- --ignored` rewrites it.

use super::scene::{CameraSpec, TracedScene};
use std::path::PathBuf;

/// One corpus scene.
#[derive(Clone, Debug)]
pub struct CorpusScene {
    /// Short name (the file is `sim/scenes/NAME.scene`).
    pub name: &'static str,
    /// What it shows.
    pub about: &'static str,
    /// Its cameras, each with a short label.
    pub cameras: Vec<(&'static str, CameraSpec)>,
}

impl CorpusScene {
    /// Path of the scene file.
    pub fn path(&self) -> PathBuf {
        scenes_dir().join(format!("{}.scene", self.name))
    }

    /// Reads and parses the scene file.
    pub fn load(&self) -> Result<TracedScene, String> {
        TracedScene::load(&self.path())
    }
}

/// `sim/scenes/`.
pub fn scenes_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

fn camera(eye: [f64; 3], target: [f64; 3], fovy: f64) -> CameraSpec {
    CameraSpec {
        eye,
        target,
        up: [0.0, 1.0, 0.0],
        fovy,
        near: 0.1,
        far: 100.0,
    }
}

/// Every corpus scene.
pub fn all() -> Vec<CorpusScene> {
    vec![
        CorpusScene {
            name: "classic",
            about:
                "mirror sphere and glass sphere over a checker-textured floor polygon, two lights",
            cameras: vec![("front", camera([0.0, 3.0, 7.0], [0.0, 0.8, 0.0], 50.0))],
        },
        CorpusScene {
            name: "classic-polygons",
            about: "the classic with its floor made of 8 x 8 polygons instead of a texture",
            cameras: vec![("front", camera([0.0, 3.0, 7.0], [0.0, 0.8, 0.0], 50.0))],
        },
        CorpusScene {
            name: "checkers",
            about: "checker textures on a plane and on polygons along each axis, cells of 1/4 to 2",
            cameras: vec![("front", camera([1.0, 4.0, 6.0], [-0.5, 0.8, -1.0], 55.0))],
        },
        CorpusScene {
            name: "water",
            about: "water surface (IOR 1.33) with objects under and above it",
            cameras: vec![
                ("above", camera([0.0, 3.0, 5.0], [0.0, -1.0, 0.0], 55.0)),
                ("below", camera([0.0, -1.0, 4.0], [0.0, 0.2, -1.0], 70.0)),
            ],
        },
        CorpusScene {
            name: "diamond",
            about: "diamond (IOR 2.42) cone, frustum and box showing total internal reflection",
            cameras: vec![("front", camera([0.5, 3.5, 5.0], [0.5, 0.8, -0.5], 45.0))],
        },
        CorpusScene {
            name: "primitives",
            about:
                "every primitive type: sphere, plane, box, cylinder, cone, ellipsoid, polygon, mesh",
            cameras: vec![("front", camera([0.0, 3.0, 7.0], [0.0, 0.6, 0.0], 55.0))],
        },
        CorpusScene {
            name: "mesh",
            about: "a 1,280-triangle icosphere mesh and a mirror sphere on a floor",
            cameras: vec![("front", camera([0.5, 2.5, 5.5], [0.5, 1.0, 0.0], 50.0))],
        },
        CorpusScene {
            name: "inside-glass",
            about: "the camera inside a glass sphere looking out at a checkered floor",
            cameras: vec![("inside", camera([0.0, 1.0, 0.0], [0.0, 0.3, -5.0], 70.0))],
        },
    ]
}

/// A corpus scene by name.
pub fn by_name(name: &str) -> Option<CorpusScene> {
    all().into_iter().find(|s| s.name == name)
}

/// Radius and centre of the corpus icosphere.
pub const ICOSPHERE: (f64, [f64; 3]) = (1.2, [0.0, 1.2, 0.0]);

/// `icosphere.obj`: meshgen's icosphere with 3 subdivisions (1,280 triangles), scaled and
/// placed by [`ICOSPHERE`], counter-clockwise seen from outside.
pub fn icosphere_obj() -> String {
    let (positions, triangles) = crate::meshgen::icosphere(3);
    let (radius, centre) = ICOSPHERE;
    let mut out = String::from(
        "# meshgen icosphere(3) scaled by 1.2 at (0, 1.2, 0): scanline3d-sim trace::corpus::icosphere_obj\n",
    );
    for p in &positions {
        let v = [0, 1, 2].map(|k| centre[k] + radius * p[k]);
        out.push_str(&format!("v {} {} {}\n", v[0], v[1], v[2]));
    }
    for t in &triangles {
        out.push_str(&format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_scene_loads_with_good_cameras() {
        for s in all() {
            let scene = s.load().unwrap();
            assert!(
                !scene.objects.is_empty() && !scene.lights.is_empty(),
                "{}",
                s.name
            );
            assert!(!s.cameras.is_empty());
            for (_, c) in &s.cameras {
                super::super::scene::check_camera(c).unwrap();
            }
        }
        let mesh = by_name("mesh").unwrap().load().unwrap();
        assert!(mesh.triangle_count() >= 1000, "{}", mesh.triangle_count());
    }

    #[test]
    fn committed_icosphere_is_the_generated_one() {
        let committed = std::fs::read_to_string(scenes_dir().join("icosphere.obj")).unwrap();
        assert!(
            committed == icosphere_obj(),
            "sim/scenes/icosphere.obj is stale: run the ignored test write_icosphere"
        );
    }

    #[test]
    #[ignore = "rewrites sim/scenes/icosphere.obj"]
    fn write_icosphere() {
        std::fs::write(scenes_dir().join("icosphere.obj"), icosphere_obj()).unwrap();
    }
}
