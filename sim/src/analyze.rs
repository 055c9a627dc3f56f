//! Scene analysis: what a scene needs from the renderer over a set of views (capacities, RAM,
//! numeric headroom, clipping, accuracy per precision setting). `sim analyze` prints it and
//! `sim export` writes its capacities into the generated budget.

use crate::metrics::Metrics;
use crate::reference::V3;
use crate::scene::{CameraSpec, SceneSpec, SUB_PIXEL_CHOICES};
use embedded_graphics::pixelcolor::Rgb565;
use scanline3d::scene::MAX_EYE_DISTANCE;
use scanline3d::workspace::workspace_bytes;
use scanline3d::{Depth, Flat};
use std::fmt;

/// `count` cameras on a sphere of directions (a Fibonacci lattice) at `distance` from
/// `centre`, each looking at the centre with the given projection.
pub fn sphere_views(
    centre: V3,
    distance: f64,
    count: usize,
    fovy: f64,
    near: f64,
    far: f64,
) -> Vec<CameraSpec> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..count)
        .map(|i| {
            // y from near +1 to near −1, never exactly at a pole.
            let y = 1.0 - (2.0 * i as f64 + 1.0) / count as f64;
            let r = (1.0 - y * y).max(0.0).sqrt();
            let a = golden * i as f64;
            let dir = [r * a.cos(), y, r * a.sin()];
            // Looking straight up or down: +y cannot be "up".
            let up = if y.abs() > 0.99 {
                [0.0, 0.0, 1.0]
            } else {
                [0.0, 1.0, 0.0]
            };
            CameraSpec {
                eye: [0, 1, 2].map(|k| centre[k] + distance * dir[k]),
                target: centre,
                up,
                fovy,
                near,
                far,
            }
        })
        .collect()
}

/// Eye distance and near/far planes for views of a scene of bounding radius `radius`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewRange {
    /// Distance of the eye from the scene's centre.
    pub distance: f64,
    /// Near plane.
    pub near: f64,
    /// Far plane.
    pub far: f64,
}

impl ViewRange {
    /// Given values are kept; the others follow from the scene's size. By default the eye is
    /// at 3 × the radius, near = distance / 20 and far = distance × 4; when that far plane is
    /// beyond the eye-space envelope (2^14 units), far shrinks to just behind the whole scene
    /// (distance + 1.05 × radius), the eye comes closer if even that does not fit, and near is
    /// raised where needed to keep far/near within the library's 2^20.
    pub fn fit(
        radius: f64,
        distance: Option<f64>,
        near: Option<f64>,
        far: Option<f64>,
    ) -> Result<ViewRange, String> {
        let r = radius.max(1e-3);
        let max = MAX_EYE_DISTANCE as f64;
        let behind = 1.05 * r;
        let distance = match distance {
            Some(d) if d > 0.0 => d,
            Some(d) => return Err(format!("distance {d} must be positive")),
            None if 12.0 * r <= max => 3.0 * r,
            None if 3.0 * r + behind <= max => 3.0 * r,
            None if 1.2 * r + behind <= max => max - behind,
            None => {
                return Err(format!(
                    "the scene's radius of {r:.0} units is too large to be seen whole within the eye-space envelope of {max} units: give --eye (with --target) or --distance"
                ))
            }
        };
        let far = far.unwrap_or(if 4.0 * distance <= max {
            4.0 * distance
        } else {
            (distance + behind).min(max)
        });
        let near = near
            .unwrap_or((distance / 20.0).max(far / scanline3d::scene::MAX_FAR_NEAR_RATIO as f64));
        Ok(ViewRange {
            distance,
            near,
            far,
        })
    }
}

/// The default sphere of views for a scene: `count` views at the [`ViewRange`] its size
/// gives (3 × its bounding radius from its centre for scenes that fit), 50° field of view
/// (what `sim analyze` and `sim export` use without camera options).
pub fn default_views(spec: &SceneSpec, count: usize) -> Result<Vec<CameraSpec>, String> {
    let (centre, radius) = bounds(spec)?;
    let r = ViewRange::fit(radius, None, None, None)?;
    Ok(sphere_views(centre, r.distance, count, 50.0, r.near, r.far))
}

/// Centre and radius of the scene's bounding sphere (around its bounding-box centre), in world
/// coordinates.
pub fn bounds(spec: &SceneSpec) -> Result<(V3, f64), String> {
    let points: Vec<V3> = spec
        .reference()?
        .triangles
        .iter()
        .flat_map(|t| t.v)
        .collect();
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in &points {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let centre = [0, 1, 2].map(|k| (lo[k] + hi[k]) / 2.0);
    let radius = points
        .iter()
        .map(|p| {
            let d = [0, 1, 2].map(|k| p[k] - centre[k]);
            (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
        })
        .fold(0.0, f64::max);
    Ok((centre, radius))
}

/// Accuracy at one sub-pixel setting, worst over the views.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SettingAccuracy {
    /// Sub-pixel bits.
    pub sub_bits: u32,
    /// Largest id mismatch percentage over the views.
    pub worst_id_mismatch_percent: f64,
    /// Real (unexplained) mismatches summed over the views.
    pub real: usize,
    /// Pixels beyond the depth bound summed over the views.
    pub depth_beyond_bound: usize,
    /// Lowest colour PSNR over the views, dB.
    pub worst_psnr: f64,
    /// Bits left at the top of the `Q(32−S).S` screen coordinates for the furthest projected
    /// vertex (the guard band caps how far that can be).
    pub coordinate_headroom_bits: f64,
}

/// What a scene needs, over all analysed views.
#[derive(Clone, Debug, Default)]
pub struct Analysis {
    /// Target size.
    pub width: usize,
    /// Target size.
    pub height: usize,
    /// Views analysed.
    pub views: usize,
    /// Vertices in the scene.
    pub vertices: usize,
    /// Triangles in the scene.
    pub triangles: usize,
    /// Most triangles filed for drawing (after culling and clipping) in one view: `TRIS`.
    pub max_bucketed: u32,
    /// Most triangle pieces drawn in one view (clipping may split a triangle).
    pub max_drawn: u32,
    /// Fewest triangles filed in one view.
    pub min_bucketed: u32,
    /// Most triangles crossing one row: `ACTIVE`.
    pub peak_active: u16,
    /// Most spans on one row.
    pub peak_spans: u16,
    /// Views in which clipping cut a visible triangle (at the near, far or guard-band planes).
    /// Where it is 0, triangles that cross a plane draw nothing after clipping, so
    /// [`NoClip`](scanline3d::clip::NoClip) gives the same image.
    pub views_clipping: usize,
    /// Most triangles clipped in one view.
    pub max_clipped: u32,
    /// Bits of eye-space headroom: log2(2^14 / largest |eye coordinate|).
    pub eye_headroom_bits: f64,
    /// Bits of depth resolution at the furthest visible point: log2(q_min · 2^30) for the I2F30
    /// depth `q = near / w`.
    pub depth_bits_at_far: f64,
    /// Accuracy and coordinate headroom per sub-pixel setting.
    pub settings: Vec<SettingAccuracy>,
    /// What Newell's depth sort needs over the views (4 sub-pixel bits).
    pub newell: NewellNeeds,
    /// Why Newell's needs could not be measured, if they could not (`newell` is then the
    /// views before).
    pub newell_error: Option<String>,
}

/// What Newell's depth sort (`scanline3d::resolve::NewellWorkspace`) needs, the most over
/// the analysed views.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NewellNeeds {
    /// Workspace entries (kept pieces and the parts of splits): `PIECES`.
    pub entries: u32,
    /// Search steps; the workspace allows `step_limit(PIECES)`.
    pub steps: u32,
    /// Pieces painted.
    pub pieces_out: u32,
    /// Splits.
    pub splits: u32,
}

impl NewellNeeds {
    /// `PIECES` with the margin: room for the entries and for the steps
    /// (`step_limit(PIECES) = 8 · PIECES + 64`), at most 65535.
    pub fn pieces_capacity(&self, margin_percent: u32) -> usize {
        let entries = with_margin(self.entries as usize, margin_percent);
        let steps = with_margin(self.steps as usize, margin_percent);
        let for_steps = steps.saturating_sub(64).div_ceil(8);
        entries
            .max(for_steps)
            .clamp(1, scanline3d::scene::MAX_SCENE_TRIANGLES)
    }
}

/// What Newell's sort needs for `spec` seen by its camera at `w × h` and 4 sub-pixel bits,
/// measured with the largest workspace (`PIECES` = 65535).
pub fn newell_needs(spec: &SceneSpec, w: usize, h: usize) -> Result<NewellNeeds, String> {
    use crate::scene::MAX_SIZE;
    use scanline3d::resolve::NewellWorkspace;
    use scanline3d::sink::{FnSink, Row, TriangleId};
    type Ws = NewellWorkspace<TriangleId, Flat, MAX_SIZE, MAX_SIZE, 65535, 4096>;
    let options = scanline3d::RenderOptions::default().with_back_face_culling(spec.cull_back_faces);
    // The workspace is built by value (megabytes): on a thread with room for it.
    std::thread::scope(|scope| {
        std::thread::Builder::new()
            .stack_size(256 << 20)
            .spawn_scoped(scope, || {
                let mut ws: Box<Ws> = Box::new(Ws::new(TriangleId::NONE));
                spec.with_scene(|scene| {
                    let mut rows = FnSink(|_: Row<'_, TriangleId>| -> Result<(), ()> { Ok(()) });
                    ws.render_sized(w, h, scene, &options, &mut rows)
                        .map_err(|e| format!("newell: {e:?}"))
                })??;
                let s = ws.sort_stats();
                Ok(NewellNeeds {
                    entries: s.entries,
                    steps: s.steps,
                    pieces_out: s.pieces_out,
                    splits: s.splits,
                })
            })
            .map_err(|e| format!("cannot start render thread: {e}"))?
            .join()
            .map_err(|_| "render thread panicked".to_string())?
    })
}

/// Capacities with a safety margin in percent (rounded up; at least the measured value).
pub fn with_margin(value: usize, margin_percent: u32) -> usize {
    (value * (100 + margin_percent as usize)).div_ceil(100)
}

impl Analysis {
    /// `TRIS` with the margin.
    pub fn triangle_capacity(&self, margin_percent: u32) -> usize {
        with_margin(self.max_bucketed as usize, margin_percent).max(1)
    }

    /// `ACTIVE` with the margin.
    pub fn active_capacity(&self, margin_percent: u32) -> usize {
        with_margin(self.peak_active as usize, margin_percent).max(1)
    }

    /// RAM of each renderer buffer for a flat-shaded RGB565 target: (name, bytes).
    pub fn buffers(&self, margin_percent: u32) -> Vec<(String, usize)> {
        let (w, h) = (self.width, self.height);
        let (tris, active) = (
            self.triangle_capacity(margin_percent),
            self.active_capacity(margin_percent),
        );
        let entry = workspace_bytes::<Rgb565, Flat, Depth>(w, h, 0, 1)
            - workspace_bytes::<Rgb565, Flat, Depth>(w, h, 0, 0);
        vec![
            (format!("depth row ({w} × 4 B)"), 4 * w),
            (format!("pixel row ({w} × 2 B, RGB565)"), 2 * w),
            (format!("row bucket heads ({h} × 2 B)"), 2 * h),
            (format!("bucket lists (TRIS = {tris} × 4 B)"), 4 * tris),
            (
                format!("active list (ACTIVE = {active} × {entry} B, flat)"),
                active * entry,
            ),
            (
                "workspace total (Workspace::BYTES)".to_string(),
                workspace_bytes::<Rgb565, Flat, Depth>(w, h, tris, active),
            ),
        ]
    }

    /// The lowest sub-pixel setting that meets the goal (worst-view id mismatches at most
    /// `goal_percent`, no real mismatches), if any.
    pub fn recommended(&self, goal_percent: f64) -> Option<&SettingAccuracy> {
        self.settings
            .iter()
            .find(|s| s.real == 0 && s.worst_id_mismatch_percent <= goal_percent)
    }
}

/// Analyses `spec`'s meshes (its camera is ignored) from each of `views` at `w × h`.
pub fn analyze(
    spec: &SceneSpec,
    views: &[CameraSpec],
    w: usize,
    h: usize,
) -> Result<Analysis, String> {
    if views.is_empty() {
        return Err("no views to analyse".into());
    }
    let mut a = Analysis {
        width: w,
        height: h,
        views: views.len(),
        vertices: spec.instances.iter().map(|i| i.mesh.vertices.len()).sum(),
        triangles: spec.instances.iter().map(|i| i.mesh.triangles.len()).sum(),
        min_bucketed: u32::MAX,
        eye_headroom_bits: f64::INFINITY,
        depth_bits_at_far: f64::INFINITY,
        ..Default::default()
    };
    let mut settings: Vec<SettingAccuracy> = SUB_PIXEL_CHOICES
        .iter()
        .map(|&s| SettingAccuracy {
            sub_bits: s,
            worst_psnr: f64::INFINITY,
            coordinate_headroom_bits: f64::INFINITY,
            ..Default::default()
        })
        .collect();
    let guard_px = scanline3d::project::GUARD_BAND_HALF_SCREENS as f64 * w.max(h) as f64 / 2.0;
    for cam in views {
        cam.fixed()?;
        let view = SceneSpec {
            camera: *cam,
            ..spec.clone()
        };
        let reference = view.reference()?;
        if a.newell_error.is_none() {
            match newell_needs(&view, w, h) {
                Ok(n) => {
                    let needs = &mut a.newell;
                    needs.entries = needs.entries.max(n.entries);
                    needs.steps = needs.steps.max(n.steps);
                    needs.pieces_out = needs.pieces_out.max(n.pieces_out);
                    needs.splits = needs.splits.max(n.splits);
                }
                Err(e) => a.newell_error = Some(e),
            }
        }
        // Numeric headroom from the vertices themselves.
        let mut eye_max: f64 = 0.0;
        let mut screen_max: f64 = 0.0;
        for p in reference.triangles.iter().flat_map(|t| t.v) {
            let e = reference.camera.eye_coords(p);
            eye_max = eye_max.max(e[0].abs()).max(e[1].abs()).max(e[2].abs());
            if e[2] >= cam.near {
                if let Some([x, y]) = reference.camera.project(p, w, h) {
                    let off = (x - w as f64 / 2.0).abs().max((y - h as f64 / 2.0).abs());
                    screen_max = screen_max.max(off.min(guard_px));
                }
            }
        }
        a.eye_headroom_bits = a
            .eye_headroom_bits
            .min((MAX_EYE_DISTANCE as f64 / eye_max.max(f64::MIN_POSITIVE)).log2());
        for (setting, sa) in SUB_PIXEL_CHOICES.iter().zip(settings.iter_mut()) {
            let (m, fixed, _): (Metrics, _, _) = crate::accuracy(&view, w, h, *setting)?;
            let s = fixed.stats;
            a.max_bucketed = a.max_bucketed.max(s.bucketed);
            a.min_bucketed = a.min_bucketed.min(s.bucketed);
            a.max_drawn = a.max_drawn.max(s.activated);
            a.peak_active = a.peak_active.max(s.peak_active);
            a.peak_spans = a.peak_spans.max(s.peak_spans);
            a.max_clipped = a.max_clipped.max(s.clipped);
            sa.worst_id_mismatch_percent =
                sa.worst_id_mismatch_percent.max(m.id_mismatch_percent());
            sa.real += m.real;
            sa.depth_beyond_bound += m.depth_beyond_bound;
            sa.worst_psnr = sa.worst_psnr.min(m.psnr);
            let used = (screen_max.max(1.0) * (1u64 << setting) as f64).log2();
            sa.coordinate_headroom_bits = sa.coordinate_headroom_bits.min(31.0 - used);
            if *setting == 4 {
                a.views_clipping += (s.clipped > 0) as usize;
                let far_w = fixed
                    .image
                    .depth
                    .iter()
                    .copied()
                    .filter(|d| d.is_finite())
                    .fold(0.0f32, f32::max) as f64;
                if far_w > 0.0 {
                    a.depth_bits_at_far = a.depth_bits_at_far.min(30.0 + (cam.near / far_w).log2());
                }
            }
        }
    }
    a.settings = settings;
    Ok(a)
}

impl fmt::Display for Analysis {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "scene: {} vertices, {} triangles; {} view(s) at {}x{}",
            self.vertices, self.triangles, self.views, self.width, self.height
        )?;
        writeln!(
            f,
            "triangles after culling and clipping: {} to {} per view ({} pieces drawn at most)",
            self.min_bucketed, self.max_bucketed, self.max_drawn
        )?;
        writeln!(
            f,
            "per row: at most {} active triangles, {} spans",
            self.peak_active, self.peak_spans
        )?;
        match (&self.newell_error, &self.newell) {
            (None, n) => writeln!(
                f,
                "newell (4 sub-pixel bits): at most {} workspace entries, {} sort steps, {} splits, {} pieces painted per view",
                n.entries, n.steps, n.splits, n.pieces_out
            )?,
            (Some(e), _) => writeln!(f, "newell: not measured ({e})")?,
        }
        if self.views_clipping == 0 {
            writeln!(
                f,
                "clipping: cuts no visible triangle in these views, so RenderOptions::with_clipping(NoClip) renders them identically"
            )?;
        } else {
            writeln!(
                f,
                "clipping: needed in {} of {} views (up to {} triangles per view): keep FrustumClip",
                self.views_clipping, self.views, self.max_clipped
            )?;
        }
        writeln!(
            f,
            "headroom: eye space {:.1} bits below the 2^14 envelope; depth q = near/w keeps {:.1} bits at the furthest visible point",
            self.eye_headroom_bits, self.depth_bits_at_far
        )?;
        writeln!(f, "per sub-pixel setting (worst view; every setting costs the same per frame, fewer bits leave more coordinate headroom):")?;
        writeln!(
            f,
            "  bits | id mismatch % | real | depth beyond bound | PSNR dB | coordinate headroom bits"
        )?;
        for s in &self.settings {
            writeln!(
                f,
                "  {:>4} | {:>13.3} | {:>4} | {:>18} | {:>7.2} | {:>5.1}",
                s.sub_bits,
                s.worst_id_mismatch_percent,
                s.real,
                s.depth_beyond_bound,
                s.worst_psnr,
                s.coordinate_headroom_bits
            )?;
        }
        Ok(())
    }
}
