//! Where the Bezier-clipping reference splits regions: for the documented views of the sphere
//! and the teapot at 240×240, the rays that needed a split, sorted by where their pixel lies
//! in the reference image (within 2 px of the silhouette, within 2 px of a boundary between
//! visible patches, or neither), and for the last group whether the split happened on the
//! visible patch itself. Figures quoted in `docs/patches.md`.
//!
//! ```sh
//! cargo run --release -p scanline3d-sim --example patch_splits
//! ```

use scanline3d_sim::patch::{clip, parse, render::Reference};
use scanline3d_sim::scene::{CameraSpec, LightSpec};

const W: usize = 240;
const H: usize = 240;

fn main() -> Result<(), String> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/patches");
    let views = [
        (
            "sphere.bpt",
            [2.0, 1.5, 2.5],
            [0.0; 3],
            [0.0, 1.0, 0.0],
            50.0,
        ),
        (
            "teapot.bpt",
            [2.0, 7.0, 4.5],
            [0.2, 0.0, 1.3],
            [0.0, 0.0, 1.0],
            40.0,
        ),
    ];
    for (name, eye, target, up, fovy) in views {
        let camera = CameraSpec {
            eye,
            target,
            up,
            fovy,
            near: 0.1,
            far: 100.0,
        };
        let model = parse::load(&dir.join(name))?;
        let r = Reference::new(
            model,
            camera.reference()?,
            LightSpec::default().reference()?,
        );
        let (image, stats) = r.render(W, H);
        let (mut silhouette, mut boundary, mut interior, mut on_visible) = (0, 0, 0, 0);
        for y in 0..H {
            for x in 0..W {
                let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
                let (hit, s) = r.cast(px, py, W, H);
                if s.splits == 0 {
                    continue;
                }
                let id = image.ids[y * W + x];
                let around = (y.saturating_sub(2)..(y + 3).min(H))
                    .flat_map(|yy| (x.saturating_sub(2)..(x + 3).min(W)).map(move |xx| (xx, yy)))
                    .map(|(xx, yy)| image.ids[yy * W + xx]);
                let (mut sil, mut edge) = (false, false);
                for other in around {
                    sil |= (other >= 0) != (id >= 0);
                    edge |= other >= 0 && id >= 0 && other != id;
                }
                if sil {
                    silhouette += 1;
                } else if edge {
                    boundary += 1;
                } else {
                    interior += 1;
                    if let Some(hit) = hit {
                        let mut own = clip::ClipStats::default();
                        let ray = r.camera.ray(px, py, W, H);
                        clip::roots(&r.model.patches[hit.patch], r.camera.eye, ray, &mut own);
                        on_visible += u32::from(own.splits > 0);
                    }
                }
            }
        }
        println!(
            "{name}, eye {eye:?}: {} rays split; within 2 px of the silhouette {silhouette}, of a visible patch boundary {boundary}, neither {interior} (of which the visible patch itself split {on_visible})",
            stats.rays_split
        );
    }
    Ok(())
}
