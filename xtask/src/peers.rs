//! `cargo xtask peers`: ours against the peer renderers (`docs/peers.md`).

use crate::*;

#[cfg(feature = "peers")]
/// `cargo xtask peers`: ours against the peer renderers (`euc`, `embedded-3dgfx`) on the
/// corpus, time per frame from one criterion run (`cargo bench -p scanline3d-sim --features peers --bench peers`) and mismatch
/// against the f64 reference, into `docs/peers.md`.
pub(crate) fn peers() -> Result<(), String> {
    use scanline3d_sim::peers::{self, Peer};
    const SIZE: usize = 240;
    step("criterion: ours and the peers, every corpus scene (cargo bench --bench peers)");
    run(cargo()
        .args([
            "bench",
            "--package",
            "scanline3d-sim",
            "--features",
            "peers",
        ])
        .args(["--bench", "peers"]))?;
    step("ours and the peers against the f64 reference (every corpus scene and camera)");
    let rows = peers::corpus_table(SIZE, SIZE)?;
    let scenes: Vec<&str> = scanline3d_sim::corpus::all()
        .iter()
        .map(|s| s.name)
        .collect();
    let renderers = [
        "ours",
        "ours-cached",
        "ours-exact",
        "euc",
        "embedded-3dgfx",
        "embedded-3dgfx-1mesh",
    ];
    let mut md = String::new();
    let mut line = |s: String| {
        md.push_str(&s);
        md.push('\n');
    };
    line("# Ours against the peer renderers".into());
    line(String::new());
    line("Written by `cargo xtask peers` (also run by `cargo xtask tradeoff`); do not edit by hand. Every corpus scene at 240×240, rendered by".into());
    line(format!(
        "scanline3d's default (`Workspace`: span z-buffer, flat shading, 4 sub-pixel bits; also with a vertex cache, `VERTS` = 16384, which renders the same pixels, and with the `Exact` preset, 8 sub-pixel bits, our most accurate frame) and by the peers a user would otherwise pick: [`euc`](https://crates.io/crates/euc) {} and [`embedded-3dgfx`](https://crates.io/crates/embedded-3dgfx) {}. How the peers are driven (id images through per-triangle colours, cameras, what is set up once) is in `sim/src/peers.rs`.",
        peers::EUC_VERSION,
        peers::EMBEDDED_3DGFX_VERSION
    ));
    line(String::new());
    line(format!(
        "Host: {} ({}). Times: criterion means from `cargo bench -p scanline3d-sim --features peers --bench peers`, one run, camera 0 of each scene, each renderer writing a whole Rgb565 frame; ours also lights every face (Lambert), the peers draw flat colours.",
        host_cpu(),
        first_line(Command::new("rustc").arg("--version"))
    ));
    line(String::new());
    line("## Time per frame".into());
    line(String::new());
    line(format!("Ratios = the peer's time / ours, then / ours with the vertex cache, then / ours with the `Exact` preset (above 1: ours is faster). The vertex cache (`scanline3d::cache`) costs {} bytes per vertex and changes no pixel (`sim/tests/suite/vertex_cache.rs`), so ours-cached has the accuracy of ours below. `embedded-3dgfx` draws one mesh per triangle, the only way it has to give each face its own colour as ours does; `embedded-3dgfx-1mesh` draws the whole scene as one mesh in one colour, its cheapest frame, for scale (not the same picture).", scanline3d::cache::CachedVertex::BYTES));
    line(String::new());
    line(
        "| scene | ours | ours, vertex cache | ours, Exact | euc | embedded-3dgfx | embedded-3dgfx-1mesh |"
            .into(),
    );
    line("|---|---|---|---|---|---|---|".into());
    let mut slower = [Vec::new(), Vec::new(), Vec::new()];
    for scene in &scenes {
        let times: Vec<Option<f64>> = renderers
            .iter()
            .map(|r| criterion_mean_ns_of("peers", r, scene))
            .collect();
        let ours: Vec<f64> = renderers[..3]
            .iter()
            .zip(&times)
            .map(|(r, t)| t.ok_or_else(|| format!("no criterion result for {r}/{scene}")))
            .collect::<Result<_, _>>()?;
        let mut cells: Vec<String> = ours
            .iter()
            .map(|t| format!("{:.1} µs", t / 1000.0))
            .collect();
        for (r, t) in renderers.iter().zip(&times).skip(3) {
            let t = t.ok_or_else(|| format!("no criterion result for {r}/{scene}"))?;
            let ratios: Vec<f64> = ours.iter().map(|o| t / o).collect();
            for (list, ratio) in slower.iter_mut().zip(&ratios) {
                if *ratio < 2.0 {
                    list.push(format!("{r} on {scene}: {ratio:.2}×"));
                }
            }
            let ratios: Vec<String> = ratios.iter().map(|x| format!("{x:.2}×")).collect();
            cells.push(format!("{:.1} µs ({})", t / 1000.0, ratios.join(" · ")));
        }
        line(format!("| {scene} | {} |", cells.join(" | ")));
    }
    line(String::new());
    for (what, list) in [
        "ours",
        "ours with the vertex cache",
        "ours with the `Exact` preset",
    ]
    .iter()
    .zip(&slower)
    {
        if list.is_empty() {
            line(format!(
                "{what}: at least 2× faster than every peer on every scene."
            ));
        } else {
            line(format!(
                "Where {what} is not at least 2× faster (peer time / ours): {}.",
                list.join("; ")
            ));
        }
        line(String::new());
    }
    line("## Accuracy against the f64 reference".into());
    line(String::new());
    line("Every camera of each scene, judged by `metrics::compare` with our default error bound (4 sub-pixel bits) for every renderer. Id mismatches: pixels showing another triangle than the reference (worst camera, percent of the frame); real: mismatches not explained by the bound, summed over cameras; max px: the largest distance from a mismatching pixel centre to an edge of the triangles involved. A peer that cannot render a scene correctly is marked, not dropped.".into());
    line(String::new());
    line("| scene | cameras | renderer | id mismatches (worst) | real | max px |".into());
    line("|---|---|---|---|---|---|".into());
    for scene in &scenes {
        let of_scene: Vec<_> = rows.iter().filter(|r| r.scene == *scene).collect();
        let outcomes = |name: &str| -> Vec<&peers::Outcome> {
            of_scene
                .iter()
                .map(|r| {
                    if name == "ours" {
                        &r.ours
                    } else if name == "ours, Exact" {
                        &r.ours_exact
                    } else {
                        &r.peers
                            .iter()
                            .find(|(p, _)| p.name() == name)
                            .expect("every peer has a row")
                            .1
                    }
                })
                .collect()
        };
        for name in ["ours", "ours, Exact", "euc", "embedded-3dgfx"] {
            let o = outcomes(name);
            let failed: Vec<&str> = o
                .iter()
                .filter_map(|o| o.metrics.as_ref().err().map(String::as_str))
                .collect();
            if let Some(e) = failed.first() {
                line(format!(
                    "| {scene} | {} | {name} | failed: {e} | | |",
                    o.len()
                ));
                continue;
            }
            let m: Vec<_> = o.iter().filter_map(|o| o.metrics.as_ref().ok()).collect();
            let worst = m
                .iter()
                .map(|m| m.id_mismatch_percent())
                .fold(0.0, f64::max);
            let real: usize = m.iter().map(|m| m.real).sum();
            let max_px = o.iter().map(|o| o.max_edge_distance).fold(0.0, f64::max);
            let mark = if real > 0 { " **wrong**" } else { "" };
            line(format!(
                "| {scene} | {} | {name} | {worst:.3} % | {real}{mark} | {max_px:.2} |",
                o.len()
            ));
        }
    }
    line(String::new());
    line("## What each peer does".into());
    line(String::new());
    let caps: Vec<_> = Peer::ALL.iter().map(|p| p.capabilities()).collect();
    line(format!(
        "| | {} |",
        caps.iter()
            .map(|c| format!("{} {}", c.name, c.version))
            .collect::<Vec<_>>()
            .join(" | ")
    ));
    line(format!("|---|{}", "---|".repeat(caps.len())));
    type Field = fn(&peers::Capabilities) -> &'static str;
    let fields: [(&str, Field); 7] = [
        ("near plane", |c| c.near),
        ("far plane", |c| c.far),
        ("depth", |c| c.depth),
        ("sub-pixel precision", |c| c.sub_pixel),
        ("fill rule", |c| c.fill_rule),
        ("back faces", |c| c.back_faces),
        ("colours", |c| c.colours),
    ];
    for (name, get) in fields {
        line(format!(
            "| {name} | {} |",
            caps.iter().map(get).collect::<Vec<_>>().join(" | ")
        ));
    }
    let path = root().join("docs/peers.md");
    std::fs::write(&path, stamp("cargo xtask peers") + &md)
        .map_err(|e| format!("{}: {e}", path.display()))?;
    println!("wrote {}", path.display());
    Ok(())
}

/// Without the `peers` feature the peer renderers are not linked into the xtask: run it again
/// with them (`cargo xtask test` stays free of their build).
#[cfg(not(feature = "peers"))]
pub(crate) fn peers() -> Result<(), String> {
    run(cargo().args([
        "run",
        "--package",
        "xtask",
        "--features",
        "peers",
        "--",
        "peers",
    ]))
}
