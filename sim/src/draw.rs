//! Deterministic random draws for the randomized checks (Marsaglia's 64-bit xorshift), so a
//! seed names the cases a test or an example draws, with no dependency.

#[cfg(feature = "tools")]
use crate::metaball::{BallSpec, MetaScene};
#[cfg(feature = "tools")]
use crate::patch::{Patch, PatchModel, TrimLoop};
use crate::scene::CameraSpec;
#[cfg(feature = "tools")]
use crate::trace::{fixed::FixedScene, scene::TracedScene};
#[cfg(feature = "tools")]
use std::path::Path;

/// A generator of uniform draws.
pub struct Draw(u64);

impl Draw {
    /// A generator from a seed (0 is taken as 1: xorshift's state must not be 0).
    pub fn new(seed: u64) -> Draw {
        Draw(seed.max(1))
    }

    /// A number drawn uniformly from `[lo, hi)`.
    pub fn in_range(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        lo + (hi - lo) * (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    /// A point with every coordinate drawn from `[−r, r)`.
    pub fn point(&mut self, r: f64) -> [f64; 3] {
        [0; 3].map(|_| self.in_range(-r, r))
    }
}

/// A random triangle soup and camera, as the hidden-surface checks draw them
/// (`sim/examples/hsr_random.rs`, `extremes::newell_matches_the_reference_on_random_soups`):
/// 1 to 40 triangles spread over 0.5 to 30 units, so they interpenetrate and cross the near
/// plane, seen from a random eye.
pub struct Soup {
    /// Three vertices a triangle.
    pub vertices: Vec<[f64; 3]>,
    /// The camera.
    pub camera: CameraSpec,
    /// Whether back faces are culled.
    pub cull: bool,
}

impl Soup {
    /// The generator whose draws are the soups of `seed`.
    pub fn draws(seed: u64) -> Draw {
        Draw::new(0x9e37_79b9_7f4a_7c15 ^ seed.wrapping_mul(0x2545_f491_4f6c_dd1d))
    }

    /// The next soup from `d`; `case` (its number) picks the spread.
    pub fn draw(d: &mut Draw, case: usize) -> Soup {
        let triangles = 1 + (d.in_range(0.0, 1.0) * 40.0) as usize;
        let spread = [0.5, 3.0, 3.0, 30.0][case % 4];
        let vertices = (0..3 * triangles).map(|_| d.point(spread)).collect();
        let camera = CameraSpec {
            eye: d.point(8.0),
            target: d.point(1.0),
            up: [0.0, 1.0, 0.0],
            fovy: d.in_range(20.0, 120.0),
            near: d.in_range(0.05, 0.5),
            far: 40.0,
        };
        let cull = d.in_range(0.0, 1.0) < 0.5;
        Soup {
            vertices,
            camera,
            cull,
        }
    }
}

/// Random traced scenes, as `trace_hybrid::every_search_gives_the_same_frame_on_random_scenes`
/// and `trace_fixed::fixed_tracer_matches_the_reference_on_random_scenes` draw them
/// (`sim/examples/trace_random.rs` for more): up to 7 objects of every primitive, sizes from a
/// unit to the envelope's 2,000 (`case % 4` picks the scale), every material kind and IOR,
/// point and directional lights.
#[cfg(feature = "tools")]
pub struct TracedDraw;

#[cfg(feature = "tools")]
impl TracedDraw {
    /// The scene text of case `case` (some are refused by the format or the fixed-point
    /// envelope: the draws do not check).
    pub fn scene(d: &mut Draw, case: usize) -> String {
        let scale = [1.0, 10.0, 100.0, 2000.0][case % 4];
        let xyz = |p: [f64; 3]| format!("{} {} {}", p[0], p[1], p[2]);
        let unit = |d: &mut Draw| d.in_range(0.0, 1.0);
        let mut text = format!(
            "background {} {} {}\nambient {}\n",
            unit(d),
            unit(d),
            unit(d),
            unit(d)
        );
        for k in 0..(case / 4) % 3 {
            let intensity = d.in_range(0.0, 2.0);
            text += &if k % 2 == 0 {
                format!("light point {} {intensity}\n", xyz(d.point(scale)))
            } else {
                format!("light directional {} {intensity}\n", xyz(d.point(1.0)))
            };
        }
        for (m, ior) in ["air", "water", "diamond"].iter().enumerate() {
            let k: Vec<String> = (0..7).map(|_| unit(d).to_string()).collect();
            text += &format!("material m{m} {} {ior}\n", k.join(" "));
        }
        for object in 0..1 + (case / 12) % 7 {
            let m = format!("m{}", object % 3);
            let (a, b) = (d.point(scale), d.point(scale));
            let mut size = || d.in_range(0.001, scale);
            text += &match (case + object) % 7 {
                0 => format!("sphere {} {} {m}\n", xyz(a), size()),
                1 => format!("plane {} {} {m}\n", xyz(b.map(|c| c / scale)), a[0]),
                2 => {
                    let far = [a[0] + size(), a[1] + size(), a[2] + size()];
                    format!("box {} {} {m}\n", xyz(a), xyz(far))
                }
                3 => format!("cylinder {} {} {} {m}\n", xyz(a), xyz(b), size()),
                4 => format!("cone {} {} {} {} {m}\n", xyz(a), size(), xyz(b), size()),
                5 => format!(
                    "ellipsoid {} {} {} {} {m}\n",
                    xyz(a),
                    size(),
                    size(),
                    size()
                ),
                _ => {
                    let r = size();
                    let corners: String = (0..5)
                        .map(|k| {
                            let t = k as f64 * std::f64::consts::TAU / 5.0;
                            format!(" {}", xyz([a[0] + r * t.cos(), a[1], a[2] - r * t.sin()]))
                        })
                        .collect();
                    format!("polygon {m}{corners}\n")
                }
            };
        }
        text
    }

    /// Case `case`: its scene text and a camera, or `None` for a scene the format or the
    /// fixed-point envelope refuses (for which no camera is drawn).
    pub fn case(d: &mut Draw, case: usize) -> Option<(String, CameraSpec)> {
        let text = Self::scene(d, case);
        let traced = TracedScene::parse(&text, Path::new("."), "random").ok()?;
        FixedScene::new(&traced).ok()?;
        Some((text, Self::camera(d, case)))
    }

    /// Case `case` of scenes like the classic: a square polygon floor (tilted up to about
    /// 45°), up to four bounded objects of every kind above it, one to three lights (point and
    /// directional) and a camera looking down at it; `None` as for [`Self::case`]. The scene
    /// the hybrid mode's shadow windows are for (`ShadowWindows` in the library).
    pub fn floor_case(d: &mut Draw, case: usize) -> Option<(String, CameraSpec)> {
        let scale = [1.0, 4.0, 16.0, 60.0][case % 4];
        let xyz = |p: [f64; 3]| format!("{} {} {}", p[0], p[1], p[2]);
        let unit = |d: &mut Draw| d.in_range(0.0, 1.0);
        // The floor's normal (up, tilted at most about 45°) and two axes in its plane.
        let tilt = [d.in_range(-0.7, 0.7), 1.0, d.in_range(-0.7, 0.7)];
        let len = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        let n = tilt.map(|c| c / len(tilt));
        let a = {
            let v = [n[1], -n[0], 0.0];
            v.map(|c| c / len(v))
        };
        let b = [
            n[1] * a[2] - n[2] * a[1],
            n[2] * a[0] - n[0] * a[2],
            n[0] * a[1] - n[1] * a[0],
        ];
        let at = |u: f64, v: f64, h: f64| -> [f64; 3] {
            std::array::from_fn(|i| scale * (u * a[i] + v * b[i] + h * n[i]))
        };
        let mut text = format!("background 0.2 0.3 0.5\nambient {}\n", unit(d) * 0.5);
        for k in 0..1 + case % 3 {
            let intensity = d.in_range(0.2, 1.0);
            let (u, v, h) = (
                d.in_range(-1.5, 1.5),
                d.in_range(-1.5, 1.5),
                d.in_range(0.5, 3.0),
            );
            text += &if (case / 3 + k) % 3 == 2 {
                let dir = [u, v, h];
                format!(
                    "light directional {} {intensity}\n",
                    xyz(at(u, v, h).map(|c| c / scale / len(dir)))
                )
            } else {
                format!("light point {} {intensity}\n", xyz(at(u, v, h)))
            };
        }
        for (m, (kr, kt)) in [(0.0, 0.0), (0.8, 0.0), (0.1, 0.85)].iter().enumerate() {
            text += &format!("material m{m} 0.9 0.5 0.3 0.3 0.7 {kr} {kt} glass\n");
        }
        text += "checker floor m0 m1 1\n";
        // Counter-clockwise seen from the side n points to.
        let corners: Vec<String> = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
            .iter()
            .map(|&(u, v)| xyz(at(u, v, 0.0)))
            .collect();
        text += &format!("polygon floor {}\n", corners.join(" "));
        for object in 0..1 + (case / 4) % 4 {
            let m = format!("m{}", object % 3);
            let (u, v) = (d.in_range(-1.0, 1.0), d.in_range(-1.0, 1.0));
            let r = d.in_range(0.05, 0.4);
            let c = at(u, v, r + d.in_range(0.0, 1.0));
            let s = r * scale;
            text += &match (case + object) % 5 {
                0 => format!("sphere {} {s} {m}\n", xyz(c)),
                1 => format!("ellipsoid {} {s} {} {} {m}\n", xyz(c), s * 0.5, s * 1.5),
                2 => format!(
                    "box {} {} {m}\n",
                    xyz(c.map(|x| x - s)),
                    xyz(c.map(|x| x + s))
                ),
                3 => format!(
                    "cylinder {} {} {} {m}\n",
                    xyz(c),
                    xyz(at(u, v, 2.0 * r)),
                    s * 0.7
                ),
                _ => format!(
                    "cone {} {s} {} 0 {m}\n",
                    xyz(c),
                    xyz(at(u, v + 0.2, 3.0 * r))
                ),
            };
        }
        let traced = TracedScene::parse(&text, Path::new("."), "random").ok()?;
        FixedScene::new(&traced).ok()?;
        let (u, v, h) = (
            d.in_range(-2.0, 2.0),
            d.in_range(-2.0, 2.0),
            d.in_range(0.4, 3.0),
        );
        let camera = CameraSpec {
            eye: at(u, v, h),
            target: at(d.in_range(-0.3, 0.3), d.in_range(-0.3, 0.3), 0.0),
            up: n,
            fovy: d.in_range(20.0, 90.0),
            near: 0.01 * scale,
            far: 20.0 * scale,
        };
        Some((text, camera))
    }

    /// A random camera for case `case`, at its scale.
    pub fn camera(d: &mut Draw, case: usize) -> CameraSpec {
        let scale = [1.0, 10.0, 100.0, 2000.0][case % 4];
        CameraSpec {
            eye: d.point(scale),
            target: d.point(scale),
            up: [0.0, 1.0, 0.0],
            fovy: d.in_range(5.0, 150.0),
            near: d.in_range(0.01, 1.0),
            far: d.in_range(2.0, 4.0 * scale),
        }
    }
}

/// Random metaball scenes and cameras for the fixed caster against the f64 reference
/// (`sim/examples/meta_random.rs`): 1 to 8 balls, about a fifth of negative density, at scale
/// 1, 0.1, 10 or 100 (`case % 4`), random cameras. Cases with `(case / 4) % 2 == 1` are snapped
/// to the library's 2^-16 grid ([`MetaScene::on_fixed_grid`]), so the comparison allows no
/// input rounding there.
#[cfg(feature = "tools")]
pub struct MetaDraw;

#[cfg(feature = "tools")]
impl MetaDraw {
    /// The generator whose draws are the cases `sim/examples/meta_random.rs` and the suite's
    /// random test check.
    pub fn draws() -> Draw {
        Draw::new(0x1234_5678_9abc_def1)
    }

    /// Case `case`'s scene and camera (some lie outside the caster's envelope: the draws do not
    /// check).
    pub fn case(d: &mut Draw, case: usize) -> (MetaScene, CameraSpec) {
        let scale = [1.0, 0.1, 10.0, 100.0][case % 4];
        let n = 1 + (d.in_range(0.0, 1.0) * 8.0) as usize;
        let balls = (0..n)
            .map(|_| BallSpec {
                centre: d.point(scale),
                radius: d.in_range(0.3, 2.0) * scale,
                density: if d.in_range(0.0, 1.0) < 0.2 {
                    -d.in_range(0.3, 1.0)
                } else {
                    d.in_range(0.5, 1.5)
                },
                color: [0; 3].map(|_| d.in_range(0.0, 1.0)),
                keys: vec![],
            })
            .collect();
        let mut scene = MetaScene {
            threshold: d.in_range(0.1, 0.9),
            light: ([0.0, 0.0, 1.0], 0.2, 0.8),
            balls,
        };
        let camera = CameraSpec {
            eye: d.point(5.0 * scale),
            target: d.point(scale),
            up: [0.0, 1.0, 0.0],
            fovy: d.in_range(20.0, 120.0),
            near: d.in_range(0.01, 0.5) * scale,
            far: 20.0 * scale,
        };
        if (case / 4) % 2 == 1 {
            let snap = |v: f64| (v * 65536.0).round() / 65536.0;
            scene.threshold = snap(scene.threshold);
            for ball in &mut scene.balls {
                ball.centre = ball.centre.map(snap);
                ball.radius = snap(ball.radius);
                ball.density = snap(ball.density);
            }
        }
        (scene, camera)
    }
}

/// Random single bicubic patches for the fixed patch renderer against the Bezier-clipping
/// reference (`sim/examples/patch_random.rs`): a 4×4 net over a square, its points jittered
/// in the plane by up to 0.6 of the spacing and lifted by up to 2, at scale 1, 0.05 or 20
/// (`case % 3`); rational with weights 0.2–5 when `(case / 3) % 3 == 1`, with a trim hole
/// (a regular polygon of 3 to 8 sides) when `(case / 3) % 4 == 2`; random cameras; tolerance
/// 0.5, 1 or 2 px (`(case / 2) % 3`).
#[cfg(feature = "tools")]
pub struct PatchDraw;

#[cfg(feature = "tools")]
impl PatchDraw {
    /// The generator whose draws are the cases of `sim/examples/patch_random.rs`.
    pub fn draws() -> Draw {
        Draw::new(0x0005_eed0_f9a7_c4e5)
    }

    /// Case `case`: the model, a camera and the tolerance in pixels.
    pub fn case(d: &mut Draw, case: usize) -> (PatchModel, CameraSpec, f64) {
        let scale = [1.0, 0.05, 20.0][case % 3];
        let (bump, jitter) = (d.in_range(0.0, 2.0), d.in_range(0.0, 0.6));
        let mut points = [[0.0; 3]; 16];
        for (k, p) in points.iter_mut().enumerate() {
            let (i, j) = ((k / 4) as f64, (k % 4) as f64);
            *p = [
                (i / 1.5 - 1.0 + d.in_range(-jitter, jitter)) * scale,
                (j / 1.5 - 1.0 + d.in_range(-jitter, jitter)) * scale,
                d.in_range(-bump, bump) * scale,
            ];
        }
        let rational = (case / 3) % 3 == 1;
        let weights = [0; 16].map(|_| if rational { d.in_range(0.2, 5.0) } else { 1.0 });
        let mut trims = vec![];
        if (case / 3) % 4 == 2 {
            let (cu, cv, r) = (
                d.in_range(0.3, 0.7),
                d.in_range(0.3, 0.7),
                d.in_range(0.1, 0.25),
            );
            let n = 3 + d.in_range(0.0, 6.0) as usize;
            let points = (0..n)
                .map(|k| {
                    let a = k as f64 * std::f64::consts::TAU / n as f64;
                    [cu + r * a.cos(), cv + r * a.sin()]
                })
                .collect();
            trims.push(TrimLoop { points });
        }
        let model = PatchModel {
            patches: vec![Patch {
                points,
                weights,
                trims,
            }],
        };
        let camera = CameraSpec {
            eye: d.point(4.0 * scale),
            target: d.point(0.5 * scale),
            up: [0.0, 1.0, 0.0],
            fovy: d.in_range(20.0, 100.0),
            near: d.in_range(0.01, 0.5) * scale,
            far: 100.0 * scale,
        };
        (model, camera, [0.5, 1.0, 2.0][(case / 2) % 3])
    }
}
