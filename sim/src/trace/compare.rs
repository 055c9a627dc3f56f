//! The fixed-point tracer against the f64 tracer, pixel by pixel: which primary-id and
//! shadow-mask mismatches the position bound explains (docs/tracing.md, "Against the f64
//! tracer").

use super::accel::Structure;
use super::fixed;
use super::render;
use super::scene::TracedScene;
use super::whitted::Limits;
use crate::scene::CameraSpec;
use std::path::Path;

/// Whether `value` at pixel `i` of `reference` is explained: some pixel within one pixel of
/// `i` in the reference has a different value from the reference's own at `i` (an edge is
/// within the position bound).
pub fn near_edge<T: PartialEq + Copy>(reference: &[T], w: usize, h: usize, i: usize) -> bool {
    let (x, y) = ((i % w) as i64, (i / w) as i64);
    (-1..=1).any(|dy| {
        (-1..=1).any(|dx| {
            let (nx, ny) = (x + dx, y + dy);
            nx >= 0
                && ny >= 0
                && (nx as usize) < w
                && (ny as usize) < h
                && reference[ny as usize * w + nx as usize] != reference[i]
        })
    })
}

/// Pixels (row-major indices) where the two tracers disagree and no edge of the reference
/// explains it.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Unexplained {
    /// Primary ids.
    pub ids: Vec<usize>,
    /// Shadow masks, where the primary ids agree.
    pub shadows: Vec<usize>,
}

/// Traces scene `text` from `cam` at `side × side` with both tracers (the fixed one testing
/// every object) and returns the unexplained mismatches; `None` for a scene the format, the
/// fixed-point envelope or the camera refuses.
pub fn unexplained(
    text: &str,
    cam: &CameraSpec,
    side: usize,
    limits: Limits,
) -> Option<Unexplained> {
    let traced = TracedScene::parse(text, Path::new("."), "random").ok()?;
    let scene = fixed::FixedScene::new(&traced).ok()?;
    let options = fixed::options(limits.max_depth, limits.threshold).ok()?;
    let ours = fixed::render(&scene, cam, side, side, options, fixed::Accel::None, false).ok()?;
    let reference = render::render(&traced, cam, side, side, limits, Structure::None).ok()?;
    let mut out = Unexplained::default();
    for i in 0..side * side {
        if ours.ids[i] != reference.ids[i] {
            if !near_edge(&reference.ids, side, side, i) {
                out.ids.push(i);
            }
        } else if ours.shadow[i] != reference.shadow[i]
            && !near_edge(&reference.shadow, side, side, i)
        {
            out.shadows.push(i);
        }
    }
    Some(out)
}
