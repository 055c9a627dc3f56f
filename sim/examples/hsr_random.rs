//! Every exact hidden-surface method against the f64 reference on random triangle soups: the
//! differential check `sim/tests/suite/extremes.rs` makes for the span z-buffer, for all of
//! them, at 48×36 and 4 and 8 sub-pixel bits, the reference culling as the scene does.
//!
//! ```sh
//! cargo run --release -p scanline3d-sim --example hsr_random -- [CASES [SEED [CASE]]]
//! ```
//!
//! Prints, per method and precision, the cases with real mismatches (not explained by the
//! documented position bound) or depths beyond the bound, and the methods' errors. With a
//! CASE it shows that case's mismatching pixels against the span z-buffer and the reference,
//! and reduces its triangle list to the fewest triangles that still fail.

use embedded_graphics::pixelcolor::Rgb888;
use scanline3d_sim::draw::Soup;
use scanline3d_sim::metrics::{self, ErrorBound};
use scanline3d_sim::scene::{Algorithm, CameraSpec, LightSpec, MeshData, SceneSpec};
use std::collections::BTreeMap;

const W: usize = 48;
const H: usize = 36;

/// What `algorithm` at `sub_bits` gives on a soup against the reference: (real mismatches,
/// depths beyond the bound), `Err` for a method's error, `None` for a scene the tools refuse.
fn judge(
    vertices: &[[f64; 3]],
    camera: CameraSpec,
    cull: bool,
    sub_bits: u32,
    algorithm: Algorithm,
    show: bool,
) -> Option<Result<(usize, usize), String>> {
    let faces = (0..vertices.len() as u16 / 3)
        .map(|k| [3 * k, 3 * k + 1, 3 * k + 2])
        .collect();
    let mesh = MeshData::new(vertices, faces, Rgb888::new(200, 180, 160)).ok()?;
    let spec = SceneSpec::single(mesh, camera, LightSpec::default(), cull);
    let mut reference = spec.reference().ok()?;
    reference.cull_back_faces = cull;
    let want = reference.render(W, H);
    let bound = ErrorBound {
        sub_bits,
        max_model_coord: spec.max_model_coord(),
        focal_px: reference.camera.focal_px(H),
        arithmetic: Default::default(),
    };
    let got = match spec.render_fixed_with(W, H, sub_bits, algorithm) {
        Ok(got) => got,
        Err(e) => return Some(Err(e)),
    };
    if show {
        let zbuffer = spec
            .render_fixed_with(W, H, sub_bits, Algorithm::SpanZBuffer)
            .ok()?;
        for i in (0..W * H).filter(|i| got.image.ids[*i] != want.ids[*i]) {
            println!(
                "  pixel ({}, {}): {algorithm} id {}, span z-buffer id {}, reference id {}",
                i % W,
                i / W,
                got.image.ids[i],
                zbuffer.image.ids[i],
                want.ids[i]
            );
        }
    }
    let m = metrics::compare(&got.image, &want, &reference, &bound);
    Some(Ok((m.real, m.depth_beyond_bound)))
}

/// The fewest triangles of `vertices` (dropping one at a time) that still fail.
fn reduce(case: &Soup, sub_bits: u32, algorithm: Algorithm) -> Vec<[f64; 3]> {
    let fails = |v: &[[f64; 3]]| {
        matches!(
            judge(v, case.camera, case.cull, sub_bits, algorithm, false),
            Some(Ok((real, beyond))) if real + beyond > 0
        )
    };
    let mut v = case.vertices.clone();
    let mut changed = true;
    while changed {
        changed = false;
        for t in (0..v.len() / 3).rev() {
            let mut fewer = v.clone();
            fewer.drain(3 * t..3 * t + 3);
            if !fewer.is_empty() && fails(&fewer) {
                v = fewer;
                changed = true;
            }
        }
    }
    v
}

fn main() {
    let arg = |k: usize| std::env::args().nth(k).and_then(|a| a.parse::<u64>().ok());
    let cases = arg(1).unwrap_or(120) as usize;
    let seed = arg(2).unwrap_or(1);
    let only = arg(3).map(|c| c as usize);
    let mut d = Soup::draws(seed);
    let mut failures: BTreeMap<String, Vec<usize>> = BTreeMap::new();
    let mut judged = 0;
    for k in 0..cases {
        let case = Soup::draw(&mut d, k);
        if only.is_some_and(|o| o != k) || case.camera.fixed().is_err() {
            continue;
        }
        for sub_bits in [4, 8] {
            for algorithm in Algorithm::ALL.into_iter().filter(|a| a.is_exact()) {
                let show = only.is_some();
                let what = match judge(
                    &case.vertices,
                    case.camera,
                    case.cull,
                    sub_bits,
                    algorithm,
                    show,
                ) {
                    None => continue,
                    Some(Ok((0, 0))) => {
                        judged += 1;
                        continue;
                    }
                    Some(Ok((real, beyond))) => {
                        judged += 1;
                        if show {
                            println!("case {k} {algorithm} S={sub_bits}: {real} real mismatches, {beyond} depths beyond the bound");
                            let v = reduce(&case, sub_bits, algorithm);
                            println!("  fails with {} of its triangles:", v.len() / 3);
                            for (t, tri) in v.chunks(3).enumerate() {
                                println!("    {t}: {tri:?}");
                            }
                            println!("    {:?}, cull {}", case.camera, case.cull);
                        }
                        format!(
                            "{algorithm} S={sub_bits}: real mismatches or depths beyond the bound"
                        )
                    }
                    Some(Err(e)) => format!("{algorithm} S={sub_bits}: {e}"),
                };
                failures.entry(what).or_default().push(k);
            }
        }
    }
    println!("{judged} frames judged ({cases} cases, seed {seed})");
    for (what, cases) in &failures {
        println!("{what}: {} cases {cases:?}", cases.len());
    }
}
