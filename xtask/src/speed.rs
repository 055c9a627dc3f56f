//! `cargo xtask speed LABEL`: instructions per frame, per drawn triangle and per pixel of the
//! default settings (`RenderOptions::default()`, variant `default` of
//! `firmware/examples/tradeoff.rs`) on thumbv7em, thumbv6m and riscv32imc under QEMU, for the
//! demo orbit and every view of every corpus scene. Every frame hash must equal the host's.
//! Each is measured twice: with the default workspace (no vertex cache) and with a vertex cache
//! holding every vertex (`--cfg scanline3d_vertex_cache`). Saves the figures as
//! `docs/speed/LABEL.tsv` and `docs/speed/LABEL-cache.tsv` and rewrites `docs/speed.md` from
//! the saved labels (`before`: the code before issue 19's set-up rework, `after`: the current
//! code). `cargo xtask speed doc` only rewrites `docs/speed.md` from the saved figures.
//!
//! Labels compare their pixels by the byte-wise frame hash (`scanline3d_demo::byte_hash`), the
//! one the firmware printed until `HashSink` hashed one word a pixel: labels saved before that
//! hold it in their `hash` column; later labels hold the firmware's word hash there (equal to
//! the host's) and add `bytes_hash`, the host's byte-wise hash of the same frame.

use crate::tradeoff::{build_example_with_cfgs, run_on_qemu_with};
use crate::{first_line, root, step, thousands};
use std::collections::BTreeMap;
use std::process::Command;

const TARGETS: [&str; 3] = [
    "thumbv7em-none-eabihf",
    "thumbv6m-none-eabi",
    "riscv32imc-unknown-none-elf",
];
const SIZE: usize = 240;
const MARGIN_PERCENT: u32 = 10;
const VARIANT: &str = "default";

/// One frame: (scene, view) -> (hash, instructions, activated, fragments, byte-wise hash (host
/// only)). The demo orbit is scene `demo`, its frames the views.
type Frames = BTreeMap<(String, usize), (u32, u64, u64, u64, Option<u32>)>;

/// The `variant`/`corpus` lines of the trade-off firmware's output for [`VARIANT`].
fn parse(output: &str) -> Frames {
    let mut frames = Frames::new();
    for line in output.lines() {
        let w: Vec<&str> = line.split_whitespace().collect();
        let field = |name: &str| {
            w.windows(2)
                .find(|p| p[0] == name)
                .and_then(|p| p[1].parse::<u64>().ok())
        };
        let hex = |name: &str| {
            w.windows(2)
                .find(|p| p[0] == name)
                .and_then(|p| u32::from_str_radix(p[1], 16).ok())
        };
        let hash = hex("hash");
        let key = match w.first() {
            Some(&"variant") if w.get(1) == Some(&VARIANT) => {
                field("frame").map(|f| ("demo".to_string(), f as usize))
            }
            Some(&"corpus") if w.get(1) == Some(&VARIANT) => w
                .get(3)
                .zip(field("view"))
                .map(|(s, v)| (s.to_string(), v as usize)),
            _ => None,
        };
        if let (Some(key), Some(hash)) = (key, hash) {
            let n = field("instructions").unwrap_or(0);
            let a = field("activated").unwrap_or(0);
            let f = field("fragments").unwrap_or(0);
            frames.insert(key, (hash, n, a, f, hex("bytes")));
        }
    }
    frames
}

fn data_dir() -> std::path::PathBuf {
    root().join("docs/speed")
}

/// Measures the current code and saves it as `docs/speed/LABEL.tsv`, then writes `docs/speed.md`.
pub fn speed(label: &str) -> Result<(), String> {
    if label == "doc" {
        // Only rewrite docs/speed.md from the saved figures.
        return write_doc();
    }
    if label == "before" && data_dir().join("before.tsv").exists() {
        return Err("docs/speed/before.tsv records the code before issue 19's set-up rework; delete it to measure a new baseline".into());
    }
    step("every corpus scene as firmware data (scanline3d_sim::export::corpus_source)");
    let dir = root().join("target/speed-corpus");
    std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
    let corpus_file = dir.join("corpus.rs");
    let corpus = scanline3d_sim::export::corpus_source(SIZE, SIZE, MARGIN_PERCENT)?;
    std::fs::write(&corpus_file, corpus).map_err(|e| e.to_string())?;
    let cfg = format!("scanline3d_variant=\"{VARIANT}\"");
    step("host hashes of the trade-off example");
    let host_elf = build_example_with_cfgs(
        "tradeoff",
        None,
        &[],
        Some((crate::tradeoff::CORPUS, &corpus_file)),
    )?;
    let host_out = Command::new(&host_elf)
        .output()
        .map_err(|e| format!("{}: {e}", host_elf.display()))?;
    let host = parse(&String::from_utf8_lossy(&host_out.stdout));
    for (suffix, cache) in [("", false), ("-cache", true)] {
        let mut cfgs = vec![cfg.clone()];
        if cache {
            cfgs.push("scanline3d_vertex_cache".into());
        }
        measure(&format!("{label}{suffix}"), &cfgs, &corpus_file, &host)?;
    }
    write_doc()
}

/// Builds and runs the trade-off firmware with `cfgs` on every target; saves `label`.
fn measure(
    label: &str,
    cfgs: &[String],
    corpus_file: &std::path::Path,
    host: &Frames,
) -> Result<(), String> {
    let mut tsv = String::from(
        "target\tscene\tview\thash\tinstructions\tactivated\tfragments\tbytes_hash\n",
    );
    for target in TARGETS {
        step(&format!(
            "{label}: variant {VARIANT}, {cfgs:?}, with the corpus on {target}"
        ));
        let elf = build_example_with_cfgs(
            "tradeoff",
            Some(target),
            cfgs,
            Some((crate::tradeoff::CORPUS, corpus_file)),
        )?;
        let out = run_on_qemu_with(target, &elf, &[])?;
        let frames = parse(&out);
        if frames.is_empty() {
            return Err(format!("{target}: no frames in the output:\n{out}"));
        }
        for (key, f) in &frames {
            let h = host.get(key);
            if h.map(|h| h.0) != Some(f.0) {
                return Err(format!(
                    "{target} {} view {}: hash {:08x}, host {:08x?}",
                    key.0,
                    key.1,
                    f.0,
                    h.map(|h| h.0)
                ));
            }
            // The firmware's frame is the host's (equal word hashes), whose byte-wise hash
            // compares it with labels saved before the word hash.
            let bytes = h
                .and_then(|h| h.4)
                .ok_or(format!("host: no byte-wise hash for {key:?}"))?;
            tsv += &format!(
                "{target}\t{}\t{}\t{:08x}\t{}\t{}\t{}\t{bytes:08x}\n",
                key.0, key.1, f.0, f.1, f.2, f.3
            );
        }
        println!("{} frames, hashes equal the host's", frames.len());
    }
    std::fs::create_dir_all(data_dir()).map_err(|e| e.to_string())?;
    let path = data_dir().join(format!("{label}.tsv"));
    std::fs::write(&path, tsv).map_err(|e| e.to_string())?;
    println!("wrote {}", path.display());
    Ok(())
}

/// (target, scene, view) -> (instructions, activated, fragments) of a saved label.
type Saved = BTreeMap<(String, String, usize), (u64, u64, u64)>;

/// (target, scene, view) -> byte-wise frame hash of a saved label, and whether the label's
/// firmware printed the word hash (then the byte-wise one is the host's, in `bytes_hash`).
fn hashes(label: &str) -> (BTreeMap<(String, String, usize), String>, bool) {
    let text = std::fs::read_to_string(data_dir().join(format!("{label}.tsv"))).unwrap_or_default();
    let word = text
        .lines()
        .next()
        .is_some_and(|header| header.split('\t').any(|c| c == "bytes_hash"));
    let map = text
        .lines()
        .skip(1)
        .filter_map(|line| {
            let w: Vec<&str> = line.split('\t').collect();
            let (key, bytes) = match w[..] {
                [t, s, v, _, _, _, _, b] if word => ((t, s, v), b),
                [t, s, v, h, _, _, _] if !word => ((t, s, v), h),
                _ => return None,
            };
            let (t, s, v) = key;
            Some((
                (t.to_string(), s.to_string(), v.parse().ok()?),
                bytes.to_string(),
            ))
        })
        .collect();
    (map, word)
}

fn load(label: &str) -> Option<Saved> {
    let text = std::fs::read_to_string(data_dir().join(format!("{label}.tsv"))).ok()?;
    let mut out = Saved::new();
    for line in text.lines().skip(1) {
        let w: Vec<&str> = line.split('\t').collect();
        // Labels saved with the word hash have one more column (`bytes_hash`).
        let (&[t, s, v, _, n, a, f] | &[t, s, v, _, n, a, f, _]) = &w[..] else {
            continue;
        };
        out.insert(
            (t.to_string(), s.to_string(), v.parse().ok()?),
            (n.parse().ok()?, a.parse().ok()?, f.parse().ok()?),
        );
    }
    Some(out)
}

/// Sums of (instructions, activated, fragments) and the view count of `scene` on `target`,
/// restricted to `view` if given.
fn sum(
    saved: &Saved,
    target: &str,
    scene: &str,
    view: Option<usize>,
) -> Option<(u64, u64, u64, u64)> {
    let mut s = (0, 0, 0, 0);
    for ((t, sc, v), (n, a, f)) in saved {
        if t == target && sc == scene && view.is_none_or(|k| k == *v) {
            s = (s.0 + n, s.1 + a, s.2 + f, s.3 + 1);
        }
    }
    (s.3 > 0).then_some(s)
}

/// `"a", "b" and "c"`.
fn list(items: &[String]) -> String {
    match items {
        [] => String::new(),
        [one] => one.clone(),
        [rest @ .., last] => format!("{} and {last}", rest.join(", ")),
    }
}

fn millions(n: f64) -> String {
    format!("{:.2}", n / 1e6)
}

/// The saved labels, in table order, with their column titles.
const LABELS: [(&str, &str); 8] = [
    ("before", "before"),
    ("before-cache", "before, cache"),
    // The first set-up rework with the 8-byte vertex cache (main at 717759d), kept to show
    // what each later step gained.
    ("rework1-cache", "first rework, cache"),
    // The second rework (32-bit divisions, main at 924d071), before pass 1's and pass 2's
    // short ways for triangles with cached screen positions.
    ("rework2-cache", "second rework, cache"),
    // The third rework (pass 1's and pass 2's short ways, main at cfdca08), before the
    // exact 32-bit square root in lighting and one bounds test per span.
    ("rework3-cache", "third rework, cache"),
    // The fourth rework (32-bit square root in lighting, one bounds test per span; main at
    // 9c693b4), the last figures measured with the byte-wise frame hash.
    ("rework4-cache", "fourth rework, cache"),
    ("after", "after"),
    ("after-cache", "after, cache"),
];

/// `docs/speed.md` from the saved labels.
fn write_doc() -> Result<(), String> {
    let saved: Vec<(&str, Saved)> = LABELS
        .iter()
        .filter_map(|(label, title)| load(label).map(|s| (*title, s)))
        .collect();
    let before = &saved
        .first()
        .filter(|s| s.0 == "before")
        .ok_or("docs/speed/before.tsv missing")?
        .1;
    let mut scenes: Vec<(String, Option<usize>)> = vec![("demo".into(), None)];
    // The targets name two single views.
    scenes.push(("icosphere".into(), Some(0)));
    scenes.push(("heightfield".into(), Some(0)));
    for (_, s, _) in before.keys() {
        if s != "demo" && !scenes.iter().any(|x| &x.0 == s && x.1.is_none()) {
            scenes.push((s.clone(), None));
        }
    }
    let mut md = String::new();
    md += "# Speed of the default settings on the targets\n\n";
    md += &format!(
        "Generated by `cargo xtask speed after` (and once, on the code before issue 19's set-up rework, `cargo xtask speed before`); the figures are saved in `docs/speed/*.tsv`. Variant `default` of the trade-off firmware (`firmware/examples/tradeoff.rs`: `RenderOptions::default()`, flat shading, {SIZE}×{SIZE}, span z-buffer, back faces culled as each corpus scene says), built with the `firmware` profile and the corpus exported by `scanline3d_sim::export::corpus_source({SIZE}, {SIZE}, {MARGIN_PERCENT})`, with the default workspace and again with a vertex cache holding every vertex (`--cfg scanline3d_vertex_cache`, columns \"cache\"; the same pixels); run under QEMU with `-icount shift=0` (thumbv7em: mps2-an386 Cortex-M4, thumbv6m: mps2-an385, riscv32imc: virt). Figures are **instructions (QEMU), not cycles**; every frame hash equals the host's. {}.\n\n",
        first_line(Command::new("rustc").arg("--version"))
    );
    let (base, _) = hashes("before");
    let (mut byte_titles, mut word_titles) = (Vec::new(), Vec::new());
    let mut lines = String::new();
    for (label, title) in LABELS {
        let (other, word) = hashes(label);
        if other.is_empty() {
            continue;
        }
        match word {
            true => word_titles.push(format!("\"{title}\"")),
            false => byte_titles.push(format!("\"{title}\"")),
        }
        if label == "before" {
            continue;
        }
        let same = other
            .iter()
            .filter(|(k, h)| base.get(*k) == Some(*h))
            .count();
        lines += &format!(
            "Byte-wise frame hashes of \"{title}\" equal to \"before\": {same} of {} frames (demo orbit and every corpus view, three targets).\n\n",
            other.len()
        );
    }
    md += &format!(
        "Frames are compared by their byte-wise hash (32-bit FNV-1a over each pixel's raw value as 4 bytes, `scanline3d_demo::byte_hash`), which the firmware printed for {}.",
        list(&byte_titles)
    );
    if !word_titles.is_empty() {
        md += &format!(
            " For {} it printed the frame hash of `HashSink`, one 32-bit word a pixel (equal to the host's for every frame), and the host hashed the same frame byte-wise as well (`bytes` in the trade-off example's host output, column `bytes_hash` of the saved figures).",
            list(&word_titles)
        );
    }
    md += "\n\n";
    md += &lines;
    md += "Per frame: mean over the views (demo: the 8 orbit frames), in millions. Per triangle: instructions divided by the triangles (and clipped pieces) set up for the walk (`FrameStats::activated`); per pixel: divided by the pixel centres covered by spans (`FrameStats::fragments`). Both divide the whole frame's count, so they are ratios, not the cost of one stage.\n\n";
    let titles: Vec<&str> = saved.iter().map(|s| s.0).collect();
    let header = |what: &str| {
        let cols: Vec<String> = titles.iter().map(|t| format!("{what}, {t}")).collect();
        format!("| {} |", cols.join(" | "))
    };
    let rule = "---:|".repeat(titles.len());
    md += "## Instructions per frame\n\n";
    md += &format!(
        "| scene | target {} last / before |\n|---|---|{rule}---:|\n",
        header("M")
    );
    let mut per = String::from("## Instructions per drawn triangle and per pixel\n\n");
    per += &format!(
        "| scene | target {} {}\n|---|---|{rule}{rule}\n",
        header("per triangle"),
        header("per pixel").trim_start_matches('|')
    );
    for (scene, view) in &scenes {
        for target in TARGETS {
            let sums: Vec<Option<(u64, u64, u64, u64)>> = saved
                .iter()
                .map(|(_, s)| sum(s, target, scene, *view))
                .collect();
            let Some(Some(b)) = sums.first().copied() else {
                continue;
            };
            let name = match view {
                Some(v) => format!("{scene}, view {v}"),
                None if scene == "demo" => "demo orbit".into(),
                None => format!("{scene} (mean of {} views)", b.3),
            };
            let per_frame = |s: (u64, u64, u64, u64)| s.0 as f64 / s.3 as f64;
            let cells = |f: &dyn Fn((u64, u64, u64, u64)) -> String| {
                sums.iter()
                    .map(|s| s.map_or("–".to_string(), f))
                    .collect::<Vec<_>>()
                    .join(" | ")
            };
            let last = sums.iter().rev().flatten().next().copied().unwrap_or(b);
            md += &format!(
                "| {name} | {target} | {} | {:.2} |\n",
                cells(&|s| millions(per_frame(s))),
                per_frame(last) / per_frame(b)
            );
            per += &format!(
                "| {name} | {target} | {} | {} |\n",
                cells(&|s| thousands(s.0 / s.1.max(1))),
                cells(&|s| format!("{:.1}", s.0 as f64 / s.2.max(1) as f64)),
            );
        }
    }
    md += "\n";
    md += &per;
    let path = root().join("docs/speed.md");
    let old = std::fs::read_to_string(&path).unwrap_or_default();
    // Keep the hand-written notes below the generated table.
    const MARK: &str = "\n<!-- notes: kept by `cargo xtask speed` -->\n";
    if let Some((_, notes)) = old.split_once(MARK) {
        md += MARK;
        md += notes;
    }
    std::fs::write(&path, md).map_err(|e| e.to_string())?;
    println!("wrote {}", path.display());
    Ok(())
}
