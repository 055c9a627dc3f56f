//! `cargo xtask profile [VARIANT [cache] [TARGET] [SCENE]]`: where a trade-off variant's frames
//! spend their instructions (with `cache`, rendered with a vertex cache), on thumbv6m unless a
//! TARGET (`thumbv7em-none-eabihf`, ...) is named; the demo orbit, or with a corpus SCENE
//! (`icosphere`, ...) every view of that scene alone (`--cfg scanline3d_corpus_only`). QEMU logs every translated block and every block it executes
//! (`-d in_asm,exec,nochain`); the count of each block times its length gives exact
//! instructions per block. Prints the share of compiler built-ins (64-bit multiply and divide,
//! memcpy), the top functions, and the top source lines of this repository, with the
//! built-ins charged to the call site that entered them (`llvm-addr2line`; the release profile
//! keeps debug info).

use crate::tradeoff::{build_example_with_cfgs, run_on_qemu_with, CORPUS};
use crate::{root, step};
use std::collections::HashMap;
use std::io::BufRead;
use std::process::Command;

/// The target profiled unless one is named.
pub const DEFAULT_TARGET: &str = "thumbv6m-none-eabi";

/// The corpus source with `scene` the only entry of `SCENES`.
fn only_scene(source: &str, scene: &str) -> Result<String, String> {
    let entry = format!("CorpusScene {{ name: {scene:?},");
    if !source.contains(&entry) {
        return Err(format!("no corpus scene {scene:?}"));
    }
    Ok(source
        .lines()
        .filter(|l| !l.trim_start().starts_with("CorpusScene { name:") || l.contains(&entry))
        .map(
            |l| match l.strip_prefix("pub static SCENES: [CorpusScene; ") {
                Some(_) => "pub static SCENES: [CorpusScene; 1] = [",
                None => l,
            },
        )
        .collect::<Vec<_>>()
        .join("\n"))
}

/// Function symbols of `elf`: (start, size, name), sorted.
fn symbols(elf: &std::path::Path) -> Result<Vec<(u64, u64, String)>, String> {
    let out = Command::new("llvm-nm")
        .args(["-C", "-S", "--defined-only"])
        .arg(elf)
        .output()
        .map_err(|e| format!("llvm-nm (install llvm): {e}"))?;
    let mut syms: Vec<(u64, u64, String)> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter_map(|l| {
            let p: Vec<&str> = l.splitn(4, ' ').collect();
            let [start, size, kind, name] = p[..] else {
                return None;
            };
            if !kind.eq_ignore_ascii_case("t") {
                return None;
            }
            let start = u64::from_str_radix(start, 16).ok()? & !1;
            Some((start, u64::from_str_radix(size, 16).ok()?, name.to_string()))
        })
        .collect();
    syms.sort();
    Ok(syms)
}

fn name_of(syms: &[(u64, u64, String)], pc: u64) -> &str {
    let i = syms.partition_point(|s| s.0 <= pc);
    match i.checked_sub(1).map(|i| &syms[i]) {
        Some((start, size, name)) if pc < start + size => name,
        _ => "?",
    }
}

fn is_builtin(name: &str) -> bool {
    name.starts_with("__") || name.contains("compiler_builtins")
}

/// The innermost frame of each address that lies in this repository's `src/` or `firmware/examples/`,
/// as `path:line` (`llvm-addr2line -a -i`: an address line, then its inline chain, innermost
/// first).
fn source_lines(elf: &std::path::Path, addrs: &[u64]) -> Result<HashMap<u64, String>, String> {
    let repo = root().to_string_lossy().into_owned() + "/";
    let mut out = HashMap::new();
    for chunk in addrs.chunks(2000) {
        let text = Command::new("llvm-addr2line")
            .args(["-a", "-i", "-e"])
            .arg(elf)
            .args(chunk.iter().map(|a| format!("{a:#x}")))
            .output()
            .map_err(|e| format!("llvm-addr2line (install llvm): {e}"))?
            .stdout;
        let mut current: Option<u64> = None;
        for line in String::from_utf8_lossy(&text).lines() {
            if let Some(hex) = line.strip_prefix("0x") {
                current = u64::from_str_radix(hex, 16).ok();
            } else if let (Some(a), Some(path)) = (current, line.strip_prefix(&repo)) {
                if path.starts_with("src/") || path.starts_with("firmware/examples/") {
                    out.entry(a).or_insert_with(|| path.to_string());
                }
            }
        }
    }
    Ok(out)
}

fn percent(n: u64, total: u64) -> f64 {
    100.0 * n as f64 / total.max(1) as f64
}

pub fn profile(
    variant: &str,
    cache: bool,
    target: &str,
    scene: Option<&str>,
) -> Result<(), String> {
    step(&format!(
        "trade-off firmware, {variant} alone{}, {}, for {target}",
        if cache { ", vertex cache" } else { "" },
        scene.map_or("demo orbit".to_string(), |s| format!("corpus scene {s}"))
    ));
    let mut cfgs = vec![format!(
        "scanline3d_variant=\"{}\"",
        variant.replace([':', '-'], "")
    )];
    if cache {
        cfgs.push("scanline3d_vertex_cache".into());
    }
    let corpus_file = root().join("target/profile-corpus/corpus.rs");
    if let Some(scene) = scene {
        let corpus = scanline3d_sim::export::corpus_source(240, 240, 10)?;
        let dir = root().join("target/profile-corpus");
        std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
        std::fs::write(&corpus_file, only_scene(&corpus, scene)?).map_err(|e| e.to_string())?;
        cfgs.push("scanline3d_corpus_only".into());
    }
    let generated = scene.map(|_| (CORPUS, corpus_file.as_path()));
    let elf = build_example_with_cfgs("tradeoff", Some(target), &cfgs, generated)?;
    let log = root().join("target/profile-trace.log");
    step("run on QEMU, logging every executed block (a few GB, removed afterwards)");
    let out = run_on_qemu_with(
        target,
        &elf,
        &[
            "-d".as_ref(),
            "in_asm,exec,nochain".as_ref(),
            "-D".as_ref(),
            log.as_os_str(),
        ],
    )?;
    let frame_lines: Vec<&str> = out
        .lines()
        .filter(|l| l.starts_with("variant ") || l.starts_with("corpus "))
        .collect();
    // Each frame's own count (SysTick or minstret, as `cargo xtask speed` reads it).
    for line in &frame_lines {
        println!("{line}");
    }
    let frames = frame_lines.len();
    step("count instructions per block, charging built-ins to the call site that entered them");
    let syms = symbols(&elf)?;
    let file = std::fs::File::open(&log).map_err(|e| format!("{}: {e}", log.display()))?;
    // Block start -> (instructions, address of its last instruction); QEMU lists a block when it
    // translates it, before it first runs.
    let mut blocks: HashMap<u64, (u64, u64)> = HashMap::new();
    let mut builtin_of: HashMap<u64, bool> = HashMap::new();
    let mut per_function: HashMap<u64, u64> = HashMap::new();
    let mut per_site: HashMap<u64, u64> = HashMap::new();
    let (mut total, mut builtin, mut caller) = (0u64, 0u64, 0u64);
    let mut listing: Option<u64> = None;
    for line in std::io::BufReader::new(file).lines() {
        let line = line.map_err(|e| e.to_string())?;
        if let Some(rest) = line.strip_prefix("Trace ") {
            let Some(pc) = rest
                .split_once('[')
                .and_then(|(_, r)| r.split('/').nth(1))
                .and_then(|pc| u64::from_str_radix(pc, 16).ok())
            else {
                continue;
            };
            let (len, last) = blocks.get(&pc).copied().unwrap_or((1, pc));
            let is_builtin = *builtin_of
                .entry(pc)
                .or_insert_with(|| is_builtin(name_of(&syms, pc)));
            total += len;
            *per_function.entry(pc).or_default() += len;
            if is_builtin {
                builtin += len;
            } else {
                caller = last;
            }
            *per_site.entry(caller).or_default() += len;
        } else if line.starts_with("IN:") || line.trim().is_empty() {
            listing = None;
        } else if let Some(addr) = line
            .strip_prefix("0x")
            .and_then(|l| l.split(':').next())
            .and_then(|a| u64::from_str_radix(a, 16).ok())
        {
            let start = *listing.get_or_insert(addr);
            let b = blocks.entry(start).or_insert((0, addr));
            *b = (b.0 + 1, addr);
        }
    }
    std::fs::remove_file(&log).map_err(|e| e.to_string())?;
    println!(
        "\n{frames} frames of `{variant}` on {target}: {total} instructions ({} a frame, set-up and output included), {:.1} % of them in compiler built-ins (software 64-bit multiply and divide, memcpy, ...)",
        total / frames.max(1) as u64,
        percent(builtin, total)
    );
    let mut functions: HashMap<&str, u64> = HashMap::new();
    for (pc, n) in &per_function {
        *functions.entry(name_of(&syms, *pc)).or_default() += n;
    }
    let mut functions: Vec<_> = functions.into_iter().collect();
    functions.sort_by_key(|f| std::cmp::Reverse(f.1));
    println!("\nfunctions, own instructions:");
    for (name, n) in functions.iter().take(15) {
        println!(
            "{:6.2} %  {}",
            percent(*n, total),
            &name[..name.len().min(100)]
        );
    }
    let sites: Vec<u64> = per_site.keys().copied().collect();
    let lines = source_lines(&elf, &sites)?;
    let mut by_line: HashMap<&str, u64> = HashMap::new();
    for (site, n) in &per_site {
        let line = lines
            .get(site)
            .map_or("(no line in src/ or firmware/examples/)", String::as_str);
        *by_line.entry(line).or_default() += n;
    }
    let mut by_line: Vec<_> = by_line.into_iter().collect();
    by_line.sort_by_key(|l| std::cmp::Reverse(l.1));
    println!("\nsource lines, with the built-ins they call:");
    for (line, n) in by_line.iter().take(40) {
        println!("{:6.2} %  {line}", percent(*n, total));
    }
    Ok(())
}
