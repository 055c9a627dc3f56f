//! `cargo xtask tradeoff`: the speed–accuracy trade of the precision presets and single-knob
//! variations (`scanline3d_sim::tradeoff::VARIANTS`), measured: accuracy against the f64
//! reference on every corpus scene and camera, instructions per frame of the demo orbit on
//! thumbv7em and thumbv6m under QEMU (`firmware/examples/tradeoff.rs`), host time per frame (criterion,
//! `cargo bench --bench tradeoff`) and each preset's flash. Writes `docs/tradeoff.md` and the
//! plot `docs/tradeoff.png` (cost against error, Pareto front marked).

use crate::{
    cargo, criterion_mean_ns_of, first_line, flash_bytes, host_cpu, root, run, step, thousands,
};
use embedded_graphics::mono_font::{ascii::FONT_6X10, MonoTextStyle};
use embedded_graphics::pixelcolor::{Rgb888, RgbColor};
use embedded_graphics::prelude::*;
use embedded_graphics::primitives::{Circle, Line, PrimitiveStyle, Rectangle};
use embedded_graphics::text::Text;
use scanline3d_sim::interpolation::{self, Mode, ModeError};
use scanline3d_sim::tradeoff::{self, Accuracy, VARIANTS};
use std::collections::HashMap;
use std::process::Command;

/// Targets whose instruction counts the table shows.
const TARGETS: [&str; 2] = ["thumbv7em-none-eabihf", "thumbv6m-none-eabi"];
const SIZE: usize = 240;
/// Margin on the measured capacities of the corpus firmware's workspace: the narrow variants
/// move vertices slightly, so a view may file a triangle or two more.
const CORPUS_MARGIN_PERCENT: u32 = 10;

/// `variant frame hash [instructions]` lines of the trade-off example's output.
fn frames(output: &str) -> Vec<(String, u32, u32, Option<u64>)> {
    output
        .lines()
        .filter_map(|l| {
            let w: Vec<&str> = l.split_whitespace().collect();
            if w.first() != Some(&"variant") || w.len() < 8 {
                return None;
            }
            let hash = u32::from_str_radix(w[5], 16).ok()?;
            let instructions = w.get(9).and_then(|v| v.parse().ok());
            Some((w[1].to_string(), w[3].parse().ok()?, hash, instructions))
        })
        .collect()
}

/// `corpus variant scene S view K hash H complete B [instructions N]` lines: ((variant, scene,
/// view), hash, instructions).
type CorpusFrame = ((String, String, usize), u32, Option<u64>);

fn corpus_frames(output: &str) -> Vec<CorpusFrame> {
    output
        .lines()
        .filter_map(|l| {
            let w: Vec<&str> = l.split_whitespace().collect();
            if w.first() != Some(&"corpus") || w.len() < 10 {
                return None;
            }
            let hash = u32::from_str_radix(w[7], 16).ok()?;
            let instructions = w.get(11).and_then(|v| v.parse().ok());
            let key = (w[1].to_string(), w[3].to_string(), w[5].parse().ok()?);
            Some((key, hash, instructions))
        })
        .collect()
}

/// The `--cfg` of the tradeoff firmware that includes the generated corpus (its path in
/// `SCANLINE3D_CORPUS`).
pub(crate) const CORPUS: &str = "scanline3d_corpus";

/// Builds `firmware/examples/EXAMPLE.rs` with the firmware profile for `target` (the host if
/// `None`) with extra `--cfg`s (the example alone is recompiled); with `generated` = (`cfg`,
/// path), also `--cfg cfg` and the environment variable `cfg` in capitals naming the path, for
/// an example that includes generated source from there (the corpus: [`CORPUS`]). Returns the
/// ELF path.
pub(crate) fn build_example_with_cfgs(
    example: &str,
    target: Option<&str>,
    cfgs: &[String],
    generated: Option<(&str, &std::path::Path)>,
) -> Result<std::path::PathBuf, String> {
    let mut cmd = cargo();
    cmd.args([
        "rustc",
        "--package",
        crate::FIRMWARE_PACKAGE,
        "--profile",
        "firmware",
    ]);
    cmd.args(["--example", example]);
    if let Some(t) = target {
        cmd.args(["--target", t]);
    }
    cmd.arg("--");
    for c in cfgs {
        cmd.args(["--cfg", c]);
    }
    if let Some((cfg, path)) = generated {
        cmd.args(["--cfg", cfg]);
        cmd.env(cfg.to_uppercase(), path);
    }
    // A target build shares the target directory of `build_firmware_examples`, whose
    // dependencies are then already compiled for that target and profile.
    if let Some(t) = target {
        cmd.env("CARGO_TARGET_DIR", crate::firmware_target_dir(t));
    }
    run(&mut cmd)?;
    Ok(match target {
        Some(t) => crate::firmware::firmware_elf(t, "firmware", example),
        None => root().join("target/firmware/examples").join(example),
    })
}

/// Runs a firmware ELF with the runner `.cargo/config.toml` gives for `target` (QEMU with a
/// deterministic instruction clock); its standard output.
pub(crate) fn run_on_qemu(target: &str, elf: &std::path::Path) -> Result<String, String> {
    run_on_qemu_with(target, elf, &[])
}

/// [`run_on_qemu`] with `extra` QEMU arguments.
pub(crate) fn run_on_qemu_with(
    target: &str,
    elf: &std::path::Path,
    extra: &[&std::ffi::OsStr],
) -> Result<String, String> {
    let config = std::fs::read_to_string(root().join(".cargo/config.toml"))
        .map_err(|e| format!(".cargo/config.toml: {e}"))?;
    let section = format!("[target.{target}]");
    let runner = config
        .split_once(&section)
        .and_then(|(_, rest)| {
            rest.lines()
                .take_while(|l| !l.starts_with("[target"))
                .find_map(|l| l.trim().strip_prefix("runner = "))
        })
        .map(|r| r.trim_matches('"').to_string())
        .ok_or_else(|| format!("no runner for {target} in .cargo/config.toml"))?;
    let mut words = runner.split_whitespace();
    let program = words.next().ok_or("empty runner")?;
    let out = Command::new(program)
        .args(words)
        .arg(elf)
        .args(extra)
        .output()
        .map_err(|e| format!("{program}: {e}"))?;
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    if !out.status.success() {
        return Err(format!("{} on {target} failed:\n{text}", elf.display()));
    }
    Ok(text)
}

/// One variant's figures.
struct Row {
    name: &'static str,
    sub_bits: u32,
    math: &'static str,
    arith: &'static str,
    depth: &'static str,
    preset: bool,
    mean_id: f64,
    worst_id: f64,
    worst_scene: &'static str,
    real: usize,
    depth_beyond: usize,
    min_psnr: f64,
    instructions: Vec<f64>,
    host_ns: Option<f64>,
    flash: Vec<Option<u64>>,
    workspace: Option<u64>,
}

/// "Gouraud attribute interpolation": each mode's colour error on the corpus and its cost on
/// the demo orbit.
fn gouraud_section(
    line: &mut impl FnMut(String),
    errors: &[ModeError],
    cost: &HashMap<(Mode, &'static str), Demo>,
) {
    line("## Gouraud attribute interpolation".into());
    line(String::new());
    line(format!("`Gouraud<I>` with `I` one of `shading::Affine` (the default), `PerSegment<16>`, `PerSegment<8>` and `PerPixel`; everything else as `RenderOptions::default()`. **Colour error:** every corpus scene from every camera ({} views) at {SIZE}×{SIZE}, each vertex a different colour (`interpolation::vertex_color`), against the f64 reference, which blends the vertex colours by the hit point's barycentric coordinates in space (`reference::Scene::with_vertex_colors`); channel differences over the pixels where both show the same triangle. **Cost:** the demo orbit with Gouraud shading on QEMU, as above (its sphere has vertex normals, so its colours vary across triangles; the corpus carries no vertex colours on firmware); every frame hash equals the host's. **Host time:** criterion (`cargo bench --bench tradeoff`, group `tradeoff-gouraud`), the whole 8-frame orbit, divided by 8.", errors.len() / Mode::ALL.len().max(1)));
    line(String::new());
    line("| interpolation | mean channel error | worst view, mean | worst pixel | worst view PSNR | thumbv7em instr./frame | thumbv6m instr./frame | thumbv6m vs affine | host time per demo frame | flash thumbv7em / thumbv6m | RAM (workspace) |".into());
    line("|---|---|---|---|---|---|---|---|---|---|---|".into());
    let affine_v6m = cost
        .get(&(Mode::Affine, TARGETS[1]))
        .map_or(1.0, |d| d.instructions);
    for mode in Mode::ALL {
        let mine: Vec<&ModeError> = errors.iter().filter(|e| e.mode == mode).collect();
        let mean = mine.iter().map(|e| e.error.mean).sum::<f64>() / mine.len().max(1) as f64;
        let worst_view = mine.iter().map(|e| e.error.mean).fold(0.0, f64::max);
        let worst_pixel = mine.iter().map(|e| e.error.max).max().unwrap_or(0);
        let psnr = mine
            .iter()
            .map(|e| e.error.psnr)
            .fold(f64::INFINITY, f64::min);
        let at = |t: &'static str| cost.get(&(mode, t));
        let instr =
            |t: &'static str| at(t).map_or("n/a".into(), |d| thousands(d.instructions as u64));
        let host = criterion_mean_ns_of("tradeoff-gouraud", mode.name(), "demo-orbit").map_or(
            "n/a".into(),
            |ns| {
                format!(
                    "{:.1} µs",
                    ns / 1000.0 / scanline3d_demo::ORBIT_FRAMES as f64
                )
            },
        );
        line(format!(
            "| {} | {mean:.3} | {worst_view:.3} | {worst_pixel} | {psnr:.1} dB | {} | {} | {} | {host} | {} | {} |",
            mode.name(),
            instr(TARGETS[0]),
            instr(TARGETS[1]),
            at(TARGETS[1]).map_or("n/a".into(), |d| format!("{:.2}×", d.instructions / affine_v6m)),
            match (at(TARGETS[0]), at(TARGETS[1])) {
                (Some(a), Some(b)) => format!("{} / {} B", thousands(a.flash), thousands(b.flash)),
                _ => "n/a".into(),
            },
            at(TARGETS[1]).map_or("n/a".into(), |d| format!("{} B", thousands(d.workspace))),
        ));
    }
}

/// The trade-off example's name for Gouraud shading interpolated by `mode`.
fn gouraud_variant(mode: Mode) -> String {
    format!("gouraud-{}", mode.name())
}

/// The `scanline3d_variant` cfg that builds variant `name` alone.
fn cfg_of(name: &str) -> String {
    format!("scanline3d_variant=\"{}\"", name.replace([':', '-'], ""))
}

/// One variant's demo firmware on one target.
struct Demo {
    /// Mean instructions per frame.
    instructions: f64,
    flash: u64,
    /// Its workspace in bytes.
    workspace: u64,
}

/// Builds the trade-off example with variant `name` alone for `target`, runs it on QEMU and
/// checks its frame hashes against `host_hashes` (the host's for every variant).
fn demo_on_target(
    target: &str,
    name: &str,
    host_hashes: &[(String, u32, u32)],
) -> Result<Demo, String> {
    step(&format!(
        "trade-off firmware, {name} alone, on QEMU: {target}"
    ));
    // The cfg goes to the example alone (the final compilation unit).
    let elf = build_example_with_cfgs("tradeoff", Some(target), &[cfg_of(name)], None)?;
    let flash = flash_bytes(&elf)?;
    let out = run_on_qemu(target, &elf)?;
    let f = frames(&out);
    let hashes: Vec<_> = f.iter().map(|f| (f.0.clone(), f.1, f.2)).collect();
    let host: Vec<_> = host_hashes
        .iter()
        .filter(|h| h.0 == name)
        .cloned()
        .collect();
    if hashes != host {
        return Err(format!(
            "{target}, {name}: frame hashes differ from the host's"
        ));
    }
    let counts: Vec<u64> = f.iter().filter_map(|x| x.3).collect();
    if counts.len() != host.len() || counts.is_empty() {
        return Err(format!("{target}: no counts for {name}"));
    }
    let mean = counts.iter().sum::<u64>() as f64 / counts.len() as f64;
    println!(
        "{} frames, hashes equal the host's, {mean:.0} instructions per frame",
        f.len()
    );
    let workspace = out
        .lines()
        .find_map(|l| l.strip_prefix("summary workspace "))
        .and_then(|v| v.trim().parse().ok())
        .ok_or_else(|| format!("{target}, {name}: no workspace size"))?;
    Ok(Demo {
        instructions: mean,
        flash,
        workspace,
    })
}

/// A progress bar counting corpus cameras.
fn cameras_bar() -> Result<indicatif::ProgressBar, String> {
    let bar = indicatif::ProgressBar::new(0);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} cameras, {elapsed}")
            .map_err(|e| e.to_string())?,
    );
    Ok(bar)
}

pub fn tradeoff() -> Result<(), String> {
    step("the variants against the f64 reference (every corpus scene and camera)");
    let bar = cameras_bar()?;
    let accuracy = tradeoff::corpus_accuracy(SIZE, SIZE, |done, total| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    })?;
    bar.finish();

    step("Gouraud interpolation against the f64 reference (every corpus scene and camera)");
    let bar = cameras_bar()?;
    let interpolation = interpolation::corpus_errors(SIZE, SIZE, |done, total| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    })?;
    bar.finish();

    step("host time per frame (cargo bench --bench tradeoff)");
    run(cargo().args(["bench", "--bench", "tradeoff"]))?;

    step("every corpus scene as firmware data (scanline3d_sim::export::corpus_source)");
    let corpus_dir = root().join("target/tradeoff-corpus");
    std::fs::create_dir_all(&corpus_dir).map_err(|e| e.to_string())?;
    let corpus_file = corpus_dir.join("corpus.rs");
    let corpus = scanline3d_sim::export::corpus_source(SIZE, SIZE, CORPUS_MARGIN_PERCENT)?;
    std::fs::write(&corpus_file, corpus).map_err(|e| e.to_string())?;

    step("host hashes of the trade-off example (demo orbit and corpus)");
    let host_elf = build_example_with_cfgs("tradeoff", None, &[], Some((CORPUS, &corpus_file)))?;
    let host = Command::new(&host_elf)
        .output()
        .map_err(|e| e.to_string())?;
    if !host.status.success() {
        return Err("the trade-off example failed on the host".into());
    }
    let host_out = String::from_utf8_lossy(&host.stdout);
    let host_frames = frames(&host_out);
    let host_corpus = corpus_frames(&host_out);
    let host_hashes: Vec<_> = host_frames
        .iter()
        .map(|f| (f.0.clone(), f.1, f.2))
        .collect();

    let mut instructions: HashMap<(&str, &str), f64> = HashMap::new();
    let mut flash: HashMap<(&str, &str), u64> = HashMap::new();
    let mut workspace: HashMap<&str, u64> = HashMap::new();
    let mut corpus_instructions: HashMap<(&str, &str, String), f64> = HashMap::new();
    for target in TARGETS {
        for v in VARIANTS {
            let demo = demo_on_target(target, v.name, &host_hashes)?;
            instructions.insert((v.name, target), demo.instructions);
            flash.insert((v.name, target), demo.flash);
            workspace.insert(v.name, demo.workspace);
            let variant = cfg_of(v.name);

            // The same variant over every corpus view (a separate image: the corpus data would
            // swamp the flash figure).
            let elf = build_example_with_cfgs(
                "tradeoff",
                Some(target),
                &[variant],
                Some((CORPUS, &corpus_file)),
            )?;
            let out = run_on_qemu(target, &elf)?;
            let mine: Vec<_> = corpus_frames(&out)
                .into_iter()
                .filter(|f| f.0 .0 == v.name)
                .collect();
            let host: Vec<_> = host_corpus.iter().filter(|f| f.0 .0 == v.name).collect();
            let same = mine.len() == host.len()
                && mine
                    .iter()
                    .zip(&host)
                    .all(|(a, b)| a.0 == b.0 && a.1 == b.1);
            if !same || mine.is_empty() {
                return Err(format!(
                    "{target}, {}: corpus hashes differ from the host's",
                    v.name
                ));
            }
            let mut per_scene: HashMap<String, Vec<u64>> = HashMap::new();
            for f in &mine {
                let n =
                    f.2.ok_or_else(|| format!("{target}: no corpus counts for {}", v.name))?;
                per_scene.entry(f.0 .1.clone()).or_default().push(n);
            }
            println!("{} corpus views, hashes equal the host's", mine.len());
            for (scene, counts) in per_scene {
                let mean = counts.iter().sum::<u64>() as f64 / counts.len() as f64;
                corpus_instructions.insert((v.name, target, scene), mean);
            }
        }
    }

    // Gouraud interpolation: the demo orbit only (the corpus carries no vertex colours on
    // firmware).
    let mut gouraud: HashMap<(Mode, &str), Demo> = HashMap::new();
    for target in TARGETS {
        for mode in Mode::ALL {
            let name = gouraud_variant(mode);
            gouraud.insert((mode, target), demo_on_target(target, &name, &host_hashes)?);
        }
    }

    let scenes: Vec<&'static str> = scanline3d_sim::corpus::all()
        .iter()
        .map(|s| s.name)
        .collect();
    let rows: Vec<Row> = VARIANTS
        .iter()
        .map(|v| {
            let mine: Vec<&Accuracy> = accuracy.iter().filter(|a| a.variant == v.name).collect();
            let (worst_id, worst_scene) = mine
                .iter()
                .map(|a| (a.metrics.id_mismatch_percent(), a.scene))
                .fold((0.0, ""), |w, x| if x.0 > w.0 { x } else { w });
            let host: Vec<f64> = scenes
                .iter()
                .filter_map(|s| criterion_mean_ns_of("tradeoff", v.name, s))
                .collect();
            Row {
                name: v.name,
                sub_bits: v.precision.sub_bits,
                arith: v.precision.arith.name(),
                depth: v.precision.depth.name(),
                math: match v.precision.math {
                    scanline3d_sim::scene::SetupMath::Libm => "libm",
                    scanline3d_sim::scene::SetupMath::Micromath => "micromath",
                },
                preset: v.preset.is_some(),
                mean_id: mine
                    .iter()
                    .map(|a| a.metrics.id_mismatch_percent())
                    .sum::<f64>()
                    / mine.len().max(1) as f64,
                worst_id,
                worst_scene,
                real: mine.iter().map(|a| a.metrics.real).sum(),
                depth_beyond: mine.iter().map(|a| a.metrics.depth_beyond_bound).sum(),
                min_psnr: mine
                    .iter()
                    .map(|a| a.metrics.psnr)
                    .fold(f64::INFINITY, f64::min),
                instructions: TARGETS
                    .iter()
                    .map(|t| instructions.get(&(v.name, *t)).copied().unwrap_or(0.0))
                    .collect(),
                host_ns: (host.len() == scenes.len()).then(|| host.iter().sum()),
                flash: TARGETS
                    .iter()
                    .map(|t| flash.get(&(v.name, *t)).copied())
                    .collect(),
                workspace: workspace.get(v.name).copied(),
            }
        })
        .collect();

    // Pareto front over (thumbv6m instructions, mean id mismatches), among variants without
    // real mismatches.
    let v6m = |r: &Row| r.instructions[1];
    let dominated = |r: &Row| {
        rows.iter().any(|o| {
            o.real == 0
                && v6m(o) <= v6m(r)
                && o.mean_id <= r.mean_id
                && (v6m(o) < v6m(r) || o.mean_id < r.mean_id)
        })
    };
    let front: Vec<bool> = rows.iter().map(|r| r.real == 0 && !dominated(r)).collect();

    let exact_v6m = rows
        .iter()
        .find(|r| r.name == "exact")
        .map(v6m)
        .unwrap_or(1.0);
    let mut md = String::new();
    let mut line = |s: String| {
        md.push_str(&s);
        md.push('\n');
    };
    line("# Speed against accuracy: the precision presets".into());
    line(String::new());
    line("Written by `cargo xtask tradeoff`; do not edit by hand. The presets of `scanline3d::preset` (fast, balanced, exact), the library default (`RenderOptions::default()`: 4 sub-pixel bits, precise arithmetic, libm; not a preset) and the default with one knob changed, so that each knob's own effect shows.".into());
    line(String::new());
    line("Set-up arithmetic (`scanline3d::arithmetic::Arithmetic`): *precise* transforms with 64-bit products, divides each coordinate exactly and takes lighting cosines to 30 bits; the narrow choices are 32-bit transform products (*narrow transform*, `vertex::NarrowTransform`, which the fast preset takes), one reciprocal per vertex (*reciprocal projection*, `project::Reciprocal`) and 15-bit normals (*narrow normals*, `math::NarrowNormals`). The three knob rows change one of these alone. Depth format (`scanline3d::depth`): 32-bit `q = near/w` (I2F30) or 16-bit (`Depth16`, U0F16). Each variant is judged under its own documented error bound: sub-pixel snapping plus what its arithmetic and depth format add (`Precision::documented_error`).".into());
    line(String::new());
    line(format!("* **Accuracy:** every corpus scene from every camera ({} views) at {SIZE}×{SIZE} against the f64 reference, each variant judged under its own sub-pixel error bound (`metrics::compare`). Id mismatches: pixels showing another triangle than the reference (mean and worst view); real: mismatches the bound does not explain, summed over all views; depth: pixels beyond their depth bound, summed.", accuracy.len() / VARIANTS.len()));
    line(format!("* **Instructions** (main table): the demo orbit (1420 triangles, 8 frames, mean per frame) on QEMU ({}, `-icount shift=0`): mps2-an386 for thumbv7em (Cortex-M4F), mps2-an385 for thumbv6m. `firmware/examples/tradeoff.rs` is built once per variant, so each image carries only its own code (in one image holding every variant, LLVM inlined each variant differently, and the counts no longer compared like with like); every frame hash equals the host's.", first_line(Command::new("qemu-system-arm").arg("--version"))));
    line(format!("* **Host time:** criterion (`cargo bench --bench tradeoff`), the sum over the corpus scenes (first camera each) of the mean time per frame, on {} ({}).", host_cpu(), first_line(Command::new("rustc").arg("--version"))));
    line("* **Flash:** that variant's trade-off firmware (release profile, demo mesh data included). **RAM:** its demo workspace (`Workspace::BYTES`, 240×240, capacities 640 triangles and 80 active, as the firmware reports it); the render's stack comes on top and is the same for every variant.".into());
    line("* **Pareto front:** variants without real mismatches that no other such variant beats on both thumbv6m instructions and mean id mismatches.".into());
    line(String::new());
    line("| variant | sub-pixel bits | set-up math | set-up arithmetic | depth | id mismatches, mean / worst (scene) | real | depth beyond bound | worst colour PSNR | thumbv7em instr./frame | thumbv6m instr./frame | thumbv6m vs exact | host time, corpus | flash thumbv7em / thumbv6m | RAM (workspace) | Pareto |".into());
    line("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|".into());
    for (r, on_front) in rows.iter().zip(&front) {
        let flash = match (r.flash[0], r.flash[1]) {
            (Some(a), Some(b)) => format!("{} / {} B", thousands(a), thousands(b)),
            _ => "n/a".into(),
        };
        line(format!(
            "| {}{} | {} | {} | {} | {} | {:.3} % / {:.3} % ({}) | {} | {} | {:.1} dB | {} | {} | {:.2}× | {} | {} | {} | {} |",
            if r.preset { "**" } else { "" },
            if r.preset { format!("{}**", r.name) } else { r.name.to_string() },
            r.sub_bits,
            r.math,
            r.arith,
            r.depth,
            r.mean_id,
            r.worst_id,
            r.worst_scene,
            r.real,
            r.depth_beyond,
            r.min_psnr,
            thousands(r.instructions[0] as u64),
            thousands(r.instructions[1] as u64),
            exact_v6m / v6m(r),
            r.host_ns.map_or("n/a".into(), |ns| format!("{:.1} µs", ns / 1000.0)),
            flash,
            r.workspace.map_or("n/a".into(), |b| format!("{} B", thousands(b))),
            if *on_front { "on the front" } else if r.real > 0 { "has real mismatches" } else { "dominated" },
        ));
    }
    line(String::new());
    line("![instructions against id mismatches](tradeoff.png)".into());
    line(String::new());
    gouraud_section(&mut line, &interpolation, &gouraud);
    line(String::new());
    line("Against other renderers (`euc`, `embedded-3dgfx`) on the same scenes and size: [peers.md](peers.md), written by the same command.".into());
    line(String::new());
    line("## Instructions per frame on each corpus scene".into());
    line(String::new());
    line(format!("Every view of every corpus scene rendered by the trade-off firmware built with that scene data (`scanline3d_sim::export::corpus_source`, capacities with a {CORPUS_MARGIN_PERCENT} % margin), one image per variant; mean per view, thumbv6m / thumbv7em, in millions of instructions. Every hash equals the host's."));
    line(String::new());
    let names: Vec<&str> = VARIANTS.iter().map(|v| v.name).collect();
    line(format!(
        "| scene | {} | fast vs exact, thumbv6m |",
        names.join(" | ")
    ));
    line(format!("|---|{}---|", "---|".repeat(names.len())));
    for scene in &scenes {
        let at = |v: &str, t: &str| corpus_instructions.get(&(v, t, scene.to_string())).copied();
        let cells: Vec<String> = names
            .iter()
            .map(|v| match (at(v, TARGETS[1]), at(v, TARGETS[0])) {
                (Some(a), Some(b)) => format!("{:.2} / {:.2}", a / 1e6, b / 1e6),
                _ => "n/a".into(),
            })
            .collect();
        let ratio = match (at("exact", TARGETS[1]), at("fast", TARGETS[1])) {
            (Some(e), Some(f)) if f > 0.0 => format!("{:.2}×", e / f),
            _ => "n/a".into(),
        };
        line(format!("| {scene} | {} | {ratio} |", cells.join(" | ")));
    }
    line(String::new());
    line("## Presets per scene".into());
    line(String::new());
    line("Worst view's id mismatches and the real mismatches summed over views.".into());
    line(String::new());
    let presets: Vec<&str> = VARIANTS
        .iter()
        .filter(|v| v.preset.is_some())
        .map(|v| v.name)
        .collect();
    line(format!("| scene | {} |", presets.join(" | ")));
    line(format!("|---|{}", "---|".repeat(presets.len())));
    for scene in &scenes {
        let cells: Vec<String> = presets
            .iter()
            .map(|p| {
                let of: Vec<&Accuracy> = accuracy
                    .iter()
                    .filter(|a| a.variant == *p && a.scene == *scene)
                    .collect();
                let worst = of
                    .iter()
                    .map(|a| a.metrics.id_mismatch_percent())
                    .fold(0.0, f64::max);
                let real: usize = of.iter().map(|a| a.metrics.real).sum();
                format!("{worst:.3} % / {real} real")
            })
            .collect();
        line(format!("| {scene} | {} |", cells.join(" | ")));
    }
    let path = root().join("docs/tradeoff.md");
    std::fs::write(&path, crate::stamp("cargo xtask tradeoff") + &md)
        .map_err(|e| format!("{}: {e}", path.display()))?;
    println!("wrote {}", path.display());
    plot(&rows, &front)?;
    Ok(())
}

/// The plot area of [`plot_canvas`]: left, right, top, bottom.
pub(crate) const PLOT_AREA: (i32, i32, i32, i32) = (70, 610, 30, 350);

/// A white 640×400 plot: the frame of [`PLOT_AREA`], `x_label` under it and `y_label` above it.
pub(crate) fn plot_canvas(
    x_label: &str,
    y_label: &str,
) -> Result<scanline3d_sim::scene::RgbImage, String> {
    let (w, h) = (640usize, 400usize);
    let mut img = scanline3d_sim::scene::RgbImage {
        width: w,
        height: h,
        pixels: vec![[255; 3]; w * h],
    };
    let (left, right, top, bottom) = PLOT_AREA;
    let text = MonoTextStyle::new(&FONT_6X10, Rgb888::BLACK);
    let e = |_| "drawing failed".to_string();
    Rectangle::with_corners(Point::new(left, top), Point::new(right, bottom))
        .into_styled(PrimitiveStyle::with_stroke(Rgb888::BLACK, 1))
        .draw(&mut img)
        .map_err(e)?;
    let x_at = left + (right - left - 6 * x_label.len() as i32) / 2;
    Text::new(x_label, Point::new(x_at, 385), text)
        .draw(&mut img)
        .map_err(e)?;
    Text::new(y_label, Point::new(left, 20), text)
        .draw(&mut img)
        .map_err(e)?;
    Ok(img)
}

/// `docs/tradeoff.png`: thumbv6m instructions per frame (x) against mean id mismatches (y, log
/// scale), one point per variant, the Pareto front joined.
fn plot(rows: &[Row], front: &[bool]) -> Result<(), String> {
    let mut img = plot_canvas(
        "thumbv6m instructions per frame (demo orbit, QEMU)",
        "mean id mismatches vs f64 reference (%, log)",
    )?;
    let (w, h) = (img.width, img.height);
    let (left, right, top, bottom) = PLOT_AREA;
    let xs: Vec<f64> = rows.iter().map(|r| r.instructions[1]).collect();
    let ys: Vec<f64> = rows.iter().map(|r| r.mean_id.max(1e-4).log10()).collect();
    let (x0, x1) = (
        xs.iter().copied().fold(f64::INFINITY, f64::min) * 0.98,
        xs.iter().copied().fold(0.0, f64::max) * 1.02,
    );
    let (y0, y1) = (
        ys.iter().copied().fold(f64::INFINITY, f64::min).floor(),
        ys.iter().copied().fold(f64::NEG_INFINITY, f64::max).ceil(),
    );
    let px = |x: f64| left + ((x - x0) / (x1 - x0) * (right - left) as f64) as i32;
    let py = |y: f64| bottom - ((y - y0) / (y1 - y0).max(1e-9) * (bottom - top) as f64) as i32;
    let black = PrimitiveStyle::with_stroke(Rgb888::BLACK, 1);
    let text = MonoTextStyle::new(&FONT_6X10, Rgb888::BLACK);
    let e = |_| "drawing failed".to_string();
    for k in 0..=4 {
        let x = x0 + (x1 - x0) * k as f64 / 4.0;
        Text::new(
            &format!("{:.2}M", x / 1e6),
            Point::new(px(x) - 15, bottom + 14),
            text,
        )
        .draw(&mut img)
        .map_err(e)?;
    }
    let mut d = y0;
    while d <= y1 {
        Text::new(
            &format!("{}", 10f64.powf(d)),
            Point::new(8, py(d) + 3),
            text,
        )
        .draw(&mut img)
        .map_err(e)?;
        Line::new(Point::new(left, py(d)), Point::new(left + 4, py(d)))
            .into_styled(black)
            .draw(&mut img)
            .map_err(e)?;
        d += 1.0;
    }
    let mut on: Vec<(i32, i32)> = rows
        .iter()
        .enumerate()
        .filter(|(i, _)| front[*i])
        .map(|(i, _)| (px(xs[i]), py(ys[i])))
        .collect();
    on.sort();
    let green = PrimitiveStyle::with_stroke(Rgb888::new(30, 150, 60), 2);
    for pair in on.windows(2) {
        Line::new(
            Point::new(pair[0].0, pair[0].1),
            Point::new(pair[1].0, pair[1].1),
        )
        .into_styled(green)
        .draw(&mut img)
        .map_err(e)?;
    }
    // Labels are moved up or down until they clear the ones already placed.
    let mut placed: Vec<Rectangle> = Vec::new();
    for (i, r) in rows.iter().enumerate() {
        let colour = if front[i] {
            Rgb888::new(30, 150, 60)
        } else if r.real > 0 {
            Rgb888::new(200, 40, 40)
        } else {
            Rgb888::new(120, 120, 120)
        };
        let c = Point::new(px(xs[i]), py(ys[i]));
        Circle::with_center(c, if r.preset { 9 } else { 6 })
            .into_styled(PrimitiveStyle::with_fill(colour))
            .draw(&mut img)
            .map_err(e)?;
        let size = Size::new(6 * r.name.len() as u32, 10);
        let clear = |at: Point| {
            let b = Rectangle::new(at - Point::new(0, 8), size);
            !placed.iter().any(|p| !p.intersection(&b).is_zero_sized())
        };
        let at = [-4, 8, -16, 20, -28, 32]
            .iter()
            .map(|&dy| c + Point::new(7, dy))
            .find(|&at| clear(at))
            .unwrap_or(c + Point::new(7, -4));
        placed.push(Rectangle::new(at - Point::new(0, 8), size));
        Text::new(r.name, at, MonoTextStyle::new(&FONT_6X10, colour))
            .draw(&mut img)
            .map_err(e)?;
    }
    Text::new(
        "green: Pareto front; red: real mismatches; grey: dominated; large: preset",
        Point::new(left + 10, bottom - 8),
        text,
    )
    .draw(&mut img)
    .map_err(e)?;
    let path = root().join("docs/tradeoff.png");
    scanline3d_sim::scene::write_png(&path, w, h, &img.pixels)?;
    println!("wrote {}", path.display());
    Ok(())
}
