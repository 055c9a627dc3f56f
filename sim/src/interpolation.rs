//! Gouraud attribute interpolation (`scanline3d::shading::Interpolation`) against the f64
//! reference: every corpus scene, from every camera, with a different colour at each vertex,
//! so that every triangle carries a colour gradient for the interpolation to get right or wrong.

use crate::corpus;
use crate::reference::Image;
use crate::scene::SceneSpec;
use embedded_graphics::pixelcolor::{Rgb888, RgbColor};
use scanline3d::clip::FrustumClip;
use scanline3d::scene::{Instance, Mesh, MeshColors, Scene};
use scanline3d::shading::{Affine, Gouraud, Interpolation, PerPixel, PerSegment};
use scanline3d::sink::{FnSink, Row, RowPixel, TriangleId};
use scanline3d::{RenderOptions, Workspace};
use std::convert::Infallible;

/// An interpolation, chosen at run time.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Mode {
    /// `shading::Affine`.
    Affine,
    /// `shading::PerSegment<16>`.
    Segments16,
    /// `shading::PerSegment<8>`.
    Segments8,
    /// `shading::PerPixel`.
    PerPixel,
}

impl Mode {
    /// Every mode, cheapest first.
    pub const ALL: [Mode; 4] = [
        Mode::Affine,
        Mode::Segments16,
        Mode::Segments8,
        Mode::PerPixel,
    ];

    /// Name in the trade-off table; with `-` removed, the `scanline3d_variant` cfg value of the
    /// trade-off firmware that measures it (`gouraud-` + this).
    pub fn name(self) -> &'static str {
        match self {
            Mode::Affine => "affine",
            Mode::Segments16 => "segments16",
            Mode::Segments8 => "segments8",
            Mode::PerPixel => "per-pixel",
        }
    }
}

/// The colour of vertex `i`: neighbouring vertex numbers get unrelated colours.
pub fn vertex_color(i: usize) -> Rgb888 {
    let h = (i as u32).wrapping_mul(2_654_435_761);
    Rgb888::new((h >> 24) as u8, (h >> 16) as u8, (h >> 8) as u8)
}

/// Colour error of one render where it shows the same triangle as the reference.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ColourError {
    /// Pixels compared (same triangle in both).
    pub pixels: usize,
    /// Mean absolute channel difference.
    pub mean: f64,
    /// Largest channel difference.
    pub max: u8,
    /// PSNR over those pixels, dB (infinite if identical).
    pub psnr: f64,
}

/// Compares the colours of `fixed` with `reference` where both show the same triangle.
pub fn colour_error(fixed: &Image, reference: &Image) -> ColourError {
    let (mut n, mut sum, mut sq, mut max) = (0usize, 0u64, 0u64, 0u8);
    for i in 0..reference.ids.len() {
        if reference.ids[i] < 0 || fixed.ids[i] != reference.ids[i] {
            continue;
        }
        n += 1;
        for k in 0..3 {
            let d = fixed.color[i][k].abs_diff(reference.color[i][k]);
            sum += d as u64;
            sq += d as u64 * d as u64;
            max = max.max(d);
        }
    }
    let samples = (3 * n).max(1) as f64;
    let mse = sq as f64 / samples;
    ColourError {
        pixels: n,
        mean: sum as f64 / samples,
        max,
        psnr: if mse == 0.0 {
            f64::INFINITY
        } else {
            10.0 * (255.0f64 * 255.0 / mse).log10()
        },
    }
}

/// Host capacities: the largest corpus scene, and slivers crossing a row.
type Ws<P, I> = Workspace<P, Gouraud<I>, 240, 240, 16384, 1024>;

/// Renders `scene` with Gouraud shading interpolated by `I` into ids and colours.
fn render<I: Interpolation>(
    scene: &Scene<'_>,
    (w, h): (usize, usize),
    cull: bool,
) -> Result<Image, String> {
    let options = RenderOptions::default().with_back_face_culling(cull);
    let mut image = Image {
        width: w,
        height: h,
        ids: vec![-1; w * h],
        depth: vec![f32::NAN; w * h],
        color: vec![[0; 3]; w * h],
    };
    fn pass<P: RowPixel, I: Interpolation>(
        scene: &Scene<'_>,
        (w, h): (usize, usize),
        options: &RenderOptions<4, FrustumClip>,
        background: P,
        mut f: impl FnMut(usize, &[P]),
    ) -> Result<(), String> {
        let mut ws: Box<Ws<P, I>> = Box::new(Workspace::new(background));
        let mut sink = FnSink(|row: Row<'_, P>| -> Result<(), Infallible> {
            f(row.y as usize * w, row.pixels);
            Ok(())
        });
        let stats = ws
            .render_sized(w, h, scene, options, &mut sink)
            .map_err(|e| e.to_string())?;
        if !stats.is_complete() {
            return Err("incomplete frame".into());
        }
        Ok(())
    }
    pass::<TriangleId, I>(scene, (w, h), &options, TriangleId::NONE, |at, row| {
        for (x, id) in row.iter().enumerate() {
            image.ids[at + x] = id.0;
        }
    })?;
    pass::<Rgb888, I>(scene, (w, h), &options, Rgb888::BLACK, |at, row| {
        for (x, c) in row.iter().enumerate() {
            image.color[at + x] = [c.r(), c.g(), c.b()];
        }
    })?;
    Ok(image)
}

/// `spec` rendered with `mode`, vertex colours from [`vertex_color`].
pub fn render_fixed(spec: &SceneSpec, mode: Mode, w: usize, h: usize) -> Result<Image, String> {
    let colors: Vec<Vec<Rgb888>> = spec
        .instances
        .iter()
        .map(|i| (0..i.mesh.vertices.len()).map(vertex_color).collect())
        .collect();
    let meshes = spec
        .instances
        .iter()
        .zip(&colors)
        .map(|(i, c)| {
            Mesh::new(
                &i.mesh.vertices,
                &i.mesh.triangles,
                MeshColors::PerVertex(c),
                None,
            )
            .map_err(|e| e.to_string())
        })
        .collect::<Result<Vec<_>, String>>()?;
    let instances: Vec<Instance<'_>> = meshes
        .iter()
        .zip(&spec.instances)
        .map(|(mesh, i)| Instance {
            mesh,
            transform: i.transform,
        })
        .collect();
    spec.with_library_scene(&instances, |scene| {
        let size = (w, h);
        let cull = spec.cull_back_faces;
        match mode {
            Mode::Affine => render::<Affine>(scene, size, cull),
            Mode::Segments16 => render::<PerSegment<16>>(scene, size, cull),
            Mode::Segments8 => render::<PerSegment<8>>(scene, size, cull),
            Mode::PerPixel => render::<PerPixel>(scene, size, cull),
        }
    })?
}

/// The reference image of `spec` with the vertex colours of [`vertex_color`].
pub fn render_reference(spec: &SceneSpec, w: usize, h: usize) -> Result<Image, String> {
    let mut colors = Vec::new();
    for i in &spec.instances {
        let c = |v: u16| {
            let c = vertex_color(v as usize);
            [c.r(), c.g(), c.b()].map(f64::from)
        };
        colors.extend(i.mesh.triangles.iter().map(|t| t.map(c)));
    }
    Ok(spec.reference()?.with_vertex_colors(colors)?.render(w, h))
}

/// One mode on one corpus scene and camera.
#[derive(Clone, Debug)]
pub struct ModeError {
    /// The interpolation.
    pub mode: Mode,
    /// Corpus scene.
    pub scene: &'static str,
    /// Camera index.
    pub camera: usize,
    /// Its colour error.
    pub error: ColourError,
}

/// Every mode on every corpus scene and camera at `w × h`; `progress(done, total)` after each
/// camera.
pub fn corpus_errors(
    w: usize,
    h: usize,
    progress: impl FnMut(usize, usize),
) -> Result<Vec<ModeError>, String> {
    let mut out = Vec::new();
    let each = |scene, camera, spec: SceneSpec| {
        let reference = render_reference(&spec, w, h)?;
        for mode in Mode::ALL {
            let fixed = render_fixed(&spec, mode, w, h)?;
            out.push(ModeError {
                mode,
                scene,
                camera,
                error: colour_error(&fixed, &reference),
            });
        }
        Ok(())
    };
    corpus::for_each_view(each, progress)?;
    Ok(out)
}
