//! Metaball scenes on the host: the `.meta` text format, the f64 reference (Bezier clipping of
//! the field in Bernstein form) and the comparison with the library's fixed-point caster.
//!
//! ```text
//! threshold T
//! light DX DY DZ AMBIENT DIFFUSE        # D points from the surface to the light
//! metaball CX CY CZ R Q [R G B]         # colour 0..1, default 0.8 0.8 0.8
//! key FRAME CX CY CZ                    # after a metaball: its centre at FRAME
//! ```
//!
//! Ids are the balls in file order. A ball's centre is the `metaball` line's at frame 0 (unless
//! a key sets frame 0), linear between keys and held after the last one.

pub mod compare;
pub mod fixed;
pub mod polygonized;
pub mod reference;

/// A `.meta` scene.
#[derive(Clone, Debug, PartialEq)]
pub struct MetaScene {
    /// The iso-value `T`.
    pub threshold: f64,
    /// Towards the light, ambient, diffuse.
    pub light: ([f64; 3], f64, f64),
    /// The balls in file order.
    pub balls: Vec<BallSpec>,
}

/// One ball of a `.meta` file.
#[derive(Clone, Debug, PartialEq)]
pub struct BallSpec {
    /// Centre at frame 0 (the `metaball` line).
    pub centre: [f64; 3],
    /// Radius of influence `R`.
    pub radius: f64,
    /// Density `q`.
    pub density: f64,
    /// Colour, 0..1 per channel.
    pub color: [f64; 3],
    /// Animation keys `(frame, centre)`, in increasing frame order.
    pub keys: Vec<(u32, [f64; 3])>,
}

impl BallSpec {
    /// Whether the ball has no keys and its centre, radius and density lie on the 2^-16 grid
    /// of the library's formats (so converting it moves nothing).
    pub fn on_fixed_grid(&self) -> bool {
        self.keys.is_empty()
            && self
                .centre
                .iter()
                .chain([&self.radius, &self.density])
                .all(|&v| on_grid(v))
    }

    /// The centre at `frame`.
    pub fn centre_at(&self, frame: u32) -> [f64; 3] {
        let mut keys = self.keys.clone();
        if keys.first().is_none_or(|k| k.0 != 0) {
            keys.insert(0, (0, self.centre));
        }
        let mut previous = keys[0];
        for &key in &keys {
            if key.0 >= frame {
                if key.0 == previous.0 {
                    return key.1;
                }
                let u = f64::from(frame - previous.0) / f64::from(key.0 - previous.0);
                return [0, 1, 2].map(|i| previous.1[i] + u * (key.1[i] - previous.1[i]));
            }
            previous = key;
        }
        previous.1
    }

    /// The colour as 8-bit channels (rounded).
    pub fn color8(&self) -> [u8; 3] {
        self.color.map(|c| (c * 255.0).round() as u8)
    }
}

fn numbers<const K: usize>(fields: &[&str], what: &str) -> Result<[f64; K], String> {
    if fields.len() != K {
        return Err(format!("{what} takes {K} numbers, got {}", fields.len()));
    }
    let mut out = [0.0; K];
    for (o, f) in out.iter_mut().zip(fields) {
        *o = f
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| format!("'{f}' is not a finite number"))?;
    }
    Ok(out)
}

/// Whether `v` is a multiple of 2^-16 (a value I16F16 holds exactly, within its range).
fn on_grid(v: f64) -> bool {
    let scaled = v * 65536.0;
    scaled == scaled.round() && v.abs() < 32768.0
}

impl MetaScene {
    /// Whether the threshold and every ball lie on the library's 2^-16 grid
    /// ([`BallSpec::on_fixed_grid`]).
    pub fn on_fixed_grid(&self) -> bool {
        on_grid(self.threshold) && self.balls.iter().all(BallSpec::on_fixed_grid)
    }

    /// Parses a `.meta` file; errors are one line, `NAME:LINE: what`.
    pub fn parse(text: &str, name: &str) -> Result<MetaScene, String> {
        let mut threshold = None;
        let mut light = ([0.3, 0.5, 1.0], 0.2, 0.8);
        let mut balls: Vec<BallSpec> = Vec::new();
        for (i, raw) in text.lines().enumerate() {
            let at = |e: String| format!("{name}:{}: {e}", i + 1);
            let line = raw.split('#').next().unwrap_or("");
            let fields: Vec<&str> = line.split_whitespace().collect();
            let Some((&keyword, rest)) = fields.split_first() else {
                continue;
            };
            match keyword {
                "threshold" => {
                    let [t] = numbers::<1>(rest, "threshold").map_err(at)?;
                    if t <= 0.0 {
                        return Err(at("threshold must be positive".into()));
                    }
                    threshold = Some(t);
                }
                "light" => {
                    let [x, y, z, a, d] = numbers::<5>(rest, "light").map_err(at)?;
                    if x == 0.0 && y == 0.0 && z == 0.0 {
                        return Err(at("light direction is zero".into()));
                    }
                    if !(0.0..=1.0).contains(&a) || !(0.0..=1.0).contains(&d) {
                        return Err(at("ambient and diffuse must be within 0..1".into()));
                    }
                    light = ([x, y, z], a, d);
                }
                "metaball" => {
                    let (geometry, color) = match rest.len() {
                        5 => (numbers::<5>(rest, "metaball").map_err(at)?, [0.8; 3]),
                        8 => (
                            numbers::<5>(&rest[..5], "metaball").map_err(at)?,
                            numbers::<3>(&rest[5..], "metaball colour").map_err(at)?,
                        ),
                        n => {
                            return Err(at(format!(
                                "metaball takes CX CY CZ R Q [R G B], got {n} numbers"
                            )))
                        }
                    };
                    let [x, y, z, r, q] = geometry;
                    if r <= 0.0 {
                        return Err(at("radius must be positive".into()));
                    }
                    if color.iter().any(|c| !(0.0..=1.0).contains(c)) {
                        return Err(at("colour channels must be within 0..1".into()));
                    }
                    balls.push(BallSpec {
                        centre: [x, y, z],
                        radius: r,
                        density: q,
                        color,
                        keys: Vec::new(),
                    });
                }
                "key" => {
                    let Some(ball) = balls.last_mut() else {
                        return Err(at("key before any metaball".into()));
                    };
                    let [f, x, y, z] = numbers::<4>(rest, "key").map_err(at)?;
                    if f < 0.0 || f.fract() != 0.0 || f > f64::from(u32::MAX) {
                        return Err(at(format!("key frame '{f}' is not a whole frame number")));
                    }
                    let frame = f as u32;
                    if ball.keys.last().is_some_and(|k| k.0 >= frame) {
                        return Err(at("key frames must increase".into()));
                    }
                    ball.keys.push((frame, [x, y, z]));
                }
                other => return Err(at(format!("unknown keyword '{other}'"))),
            }
        }
        let threshold = threshold.ok_or_else(|| format!("{name}: no 'threshold' line"))?;
        if balls.is_empty() {
            return Err(format!("{name}: no 'metaball' line"));
        }
        Ok(MetaScene {
            threshold,
            light,
            balls,
        })
    }

    /// Reads and parses a `.meta` file.
    pub fn load(path: &std::path::Path) -> Result<MetaScene, String> {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
        MetaScene::parse(&text, &path.display().to_string())
    }
}

/// The test corpus: named scenes with their cameras (single ball, two merging, negative
/// density, grazing, eye inside the surface, and the animated six-ball scene at frame 0).
pub fn corpus() -> Vec<(&'static str, MetaScene, crate::scene::CameraSpec)> {
    corpus_texts()
        .into_iter()
        .map(|(name, text, camera)| {
            let scene = MetaScene::parse(text, name).expect("corpus scene");
            (name, scene, camera)
        })
        .collect()
}

/// [`corpus`] as the scene files' text (what the fuzzer is seeded with).
pub fn corpus_texts() -> Vec<(&'static str, &'static str, crate::scene::CameraSpec)> {
    let camera = |eye: [f64; 3], target: [f64; 3]| crate::scene::CameraSpec {
        eye,
        target,
        up: [0.0, 1.0, 0.0],
        fovy: 50.0,
        near: 0.1,
        far: 100.0,
    };
    vec![
        (
            "single",
            "threshold 0.5\nmetaball 0 0 0 1.5 1 0.9 0.5 0.2\n",
            camera([0.0, 0.0, 4.0], [0.0; 3]),
        ),
        (
            "merging",
            "threshold 0.4\nmetaball -0.7 0 0 1.2 1 0.9 0.2 0.2\nmetaball 0.7 0.1 0 1.2 1 0.2 0.4 0.9\n",
            camera([0.5, 1.0, 4.0], [0.0; 3]),
        ),
        (
            "negative",
            "threshold 0.3\nmetaball 0 0 0 1.6 1 0.3 0.8 0.3\nmetaball 0.6 0.4 0.8 0.9 -1.5 1 1 1\n",
            camera([1.5, 1.5, 3.5], [0.0; 3]),
        ),
        (
            "grazing",
            "threshold 0.5\nmetaball 0 0 0 1 1\nmetaball 1.05 0 0 1 1 0.2 0.9 0.9\nmetaball 0 0 -3 1 1 0.9 0.9 0.2\n",
            // Nearly along the line of centres: rays skim both surfaces.
            camera([0.6, 0.05, 6.0], [0.55, 0.0, 0.0]),
        ),
        (
            "inside",
            "threshold 0.3\nlight 0.2 1 0.3 0.3 0.7\nmetaball 0 0 0 3 1 0.6 0.7 0.9\nmetaball 1.2 0.5 -1.5 1.2 -1 1 1 1\n",
            camera([0.0, 0.0, 0.5], [0.5, 0.2, -2.0]),
        ),
        ("six", SIX_BALLS, camera([0.0, 1.5, 5.0], [0.0; 3])),
    ]
}

/// The animated six-ball scene the firmware draws (8 frames of keys).
pub const SIX_BALLS: &str = include_str!("six.meta");

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_and_animates() {
        let s = MetaScene::parse(
            "threshold 0.5\nlight 0 0 1 0.1 0.9\nmetaball 0 0 0 1 1  # comment\nkey 10 1 0 0\nmetaball 1 1 1 2 -0.5 1 0 0\n",
            "t",
        )
        .unwrap();
        assert_eq!(s.balls.len(), 2);
        assert_eq!(s.balls[0].centre_at(5), [0.5, 0.0, 0.0]);
        assert_eq!(s.balls[0].centre_at(20), [1.0, 0.0, 0.0]);
        assert_eq!(s.balls[1].centre_at(7), [1.0, 1.0, 1.0]);
        assert_eq!(s.balls[1].color, [1.0, 0.0, 0.0]);
        assert_eq!(s.balls[0].color, [0.8; 3]);
    }

    #[test]
    fn errors_name_the_line() {
        let cases = [
            ("threshold 0.5\nmetaball 0 0 0 1\n", "t:2: metaball takes"),
            ("threshold x\n", "t:1: 'x' is not a finite number"),
            ("threshold 1\nkey 1 0 0 0\n", "t:2: key before any metaball"),
            (
                "threshold 1\nmetaball 0 0 0 1 1\nkey 2 0 0 0\nkey 2 1 1 1\n",
                "t:4: key frames must increase",
            ),
            (
                "threshold 1\nsphere 0 0 0 1\n",
                "t:2: unknown keyword 'sphere'",
            ),
            ("metaball 0 0 0 1 1\n", "t: no 'threshold' line"),
            (
                "threshold 1\nmetaball 0 0 0 -1 1\n",
                "t:2: radius must be positive",
            ),
        ];
        for (text, want) in cases {
            let e = MetaScene::parse(text, "t").unwrap_err();
            assert!(e.starts_with(want) && !e.contains('\n'), "{e}");
        }
    }
}
