//! `cargo xtask profile [VARIANT [cache] [TARGET] [SCENE]]`: where a trade-off variant's frames
//! spend their instructions (with `cache`, rendered with a vertex cache), on thumbv6m unless a
//! TARGET (`thumbv7em-none-eabihf`, ...) is named; the demo orbit, or with a corpus SCENE
//! (`icosphere`, ...) every view of that scene alone (`--cfg scanline3d_corpus_only`) in a
//! workspace sized for it, printing its workspace and the stack's peak too (`cargo xtask
//! scene-ram SCENE` gives the render call's share). QEMU logs every translated block and every
//! block it executes
//! (`-d in_asm,exec,nochain`); the count of each block times its length gives exact
//! instructions per block. Prints the share of compiler built-ins (64-bit multiply and divide,
//! memcpy), the top functions, the top source lines of this repository and the top functions
//! of its sources counted whether inlined or not (an instruction counts for the innermost one
//! it comes from: `PlaneSolver::new` inlined into the set-up is `PlaneSolver::new`), with the
//! built-ins charged to the call site that entered them (`llvm-addr2line`; the release profile
//! keeps debug info). `cargo xtask profile trace [pure|hybrid] [TARGET]` does the same for the
//! traced firmware's frame in one mode (thumbv7em unless a TARGET is named), and also prints per
//! symbol the functions inlined into it (which separates, say, the shadow rays' walk in `shade`
//! from the nearest-hit walk in `nearest`). `cargo xtask profile patch [TARGET]` profiles the
//! patch firmware's teapot frames; `cargo xtask profile firmware [TARGET]` the demo firmware as
//! `cargo xtask firmware` builds it. Any of them with `--blocks PATTERN` also takes apart the
//! symbols whose name contains PATTERN block by block (instructions a frame, where in the
//! sources). The log goes through a named pipe, never to disk.
//!
//! `cargo xtask flash [TARGET] [VARIANT]` is the same attribution for code size: every byte of
//! a lean firmware's code and read-only data charged to the source function it comes from
//! (innermost in this repository's sources, inlined or not; else its symbol), less the
//! renderer-less baseline's bytes of the same function (thumbv6m and `minimal` unless named).

use crate::tradeoff::{build_example_with_cfgs, run_on_qemu_with, CORPUS};
use crate::{root, step};
use std::collections::HashMap;
use std::io::BufRead;
use std::process::Command;

/// The target profiled unless one is named.
pub const DEFAULT_TARGET: &str = "thumbv6m-none-eabi";

/// The corpus source with `scene` the only entry of `SCENES` and the workspace sized for it.
fn only_scene(source: &str, scene: &str) -> Result<String, String> {
    let entry = format!("CorpusScene {{ name: {scene:?},");
    if !source.contains(&entry) {
        return Err(format!("no corpus scene {scene:?}"));
    }
    // The workspace sized for this scene alone: its own budget (the same margin) and vertex
    // count instead of the largest over the corpus (the constants after `SCENES`).
    let (modules, tail) = source
        .split_once("pub static SCENES: [CorpusScene; ")
        .ok_or("corpus source without `SCENES`")?;
    let module = modules
        .split_once(&format!("pub mod {} {{", scene.replace('-', "_")))
        .map(|(_, m)| m.split_once("\npub mod ").map_or(m, |(m, _)| m))
        .ok_or_else(|| format!("no module for corpus scene {scene:?}"))?;
    let find = |prefix: &str, end: char| -> Result<String, String> {
        module
            .lines()
            .find_map(|l| l.strip_prefix(prefix))
            .and_then(|rest| rest.split(end).next())
            .map(str::to_string)
            .ok_or_else(|| format!("corpus scene {scene:?}: no `{prefix}`"))
    };
    let tris = find("pub const MAX_TRIANGLES: usize = ", ';')?;
    let active = find("pub const MAX_ACTIVE: usize = ", ';')?;
    let vertices = find("pub static VERTICES: [Vertex; ", ']')?;
    let tail = tail
        .lines()
        .map(|l| {
            if l.starts_with("pub const MAX_TRIANGLES: usize = ") {
                format!("pub const MAX_TRIANGLES: usize = {tris};")
            } else if l.starts_with("pub const MAX_ACTIVE: usize = ") {
                format!("pub const MAX_ACTIVE: usize = {active};")
            } else if l.starts_with("pub const MAX_VERTICES: usize = ") {
                format!("pub const MAX_VERTICES: usize = {vertices};")
            } else {
                l.to_string()
            }
        })
        .filter(|l| !l.trim_start().starts_with("CorpusScene { name:") || l.contains(&entry))
        .collect::<Vec<_>>()
        .join("\n");
    // `tail` starts with the rest of the `SCENES` line (its length).
    let tail = tail.split_once('\n').map_or("", |(_, rest)| rest);
    Ok(format!(
        "{modules}pub static SCENES: [CorpusScene; 1] = [\n{tail}\n"
    ))
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
            let size = u64::from_str_radix(size, 16).ok()?;
            // Labels and mapping symbols (`$t`, `$x`, and RISC-V's local `.L0` labels inside
            // functions) have no size: kept, they would hide the function around them.
            (size > 0).then(|| (start, size, name.to_string()))
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

/// Where an executed instruction comes from.
struct Site {
    /// The innermost frame that lies in this repository's `src/` or `firmware/examples/`, as
    /// `path:line` (empty when none does).
    line: String,
    /// The function that frame is in, inlined or not, as [`function_name`] prints it (empty
    /// when none).
    function: String,
    /// Where that function was inlined into its caller, as `path:line` (empty when it was not
    /// inlined there or the caller lies outside this repository).
    called_at: String,
    /// The outermost function inlined at the address (the one called in the symbol's own
    /// body; the symbol itself when nothing is inlined there).
    inlined: String,
}

/// A function's name as the tables print it: no hash, no crate path, no generic arguments,
/// and a trait method under its type (`<Flat as Shading>::fill` is `shading::Flat::fill`).
fn function_name(name: &str) -> String {
    let name = short_name(name).replace("..", "::");
    // `<A as B>::f` → `A::f`.
    let name = match name.strip_prefix('<').and_then(|rest| {
        let mut depth = 1usize;
        let end = rest.char_indices().find_map(|(i, c)| {
            match c {
                '<' => depth += 1,
                '>' => depth -= 1,
                _ => {}
            }
            (depth == 0).then_some(i)
        })?;
        let (inner, tail) = (&rest[..end], &rest[end + 1..]);
        Some(format!("{}{tail}", inner.split(" as ").next().unwrap_or(inner)))
    }) {
        Some(n) => n,
        None => name,
    };
    let mut out = String::new();
    let mut depth = 0usize;
    for c in name.chars() {
        match c {
            '<' => depth += 1,
            '>' => depth = depth.saturating_sub(1),
            _ if depth == 0 => out.push(c),
            _ => {}
        }
    }
    out.replace("scanline3d::", "").replace("_{{closure}}", "{closure}")
}

/// Per address, its [`Site`] (`llvm-addr2line -a -f -i -C`: an address line, then function and
/// `path:line` lines for its inline chain, innermost first).
fn source_lines(elf: &std::path::Path, addrs: &[u64]) -> Result<HashMap<u64, Site>, String> {
    let repo = root().to_string_lossy().into_owned() + "/";
    let mut out: HashMap<u64, Site> = HashMap::new();
    for chunk in addrs.chunks(2000) {
        let text = Command::new("llvm-addr2line")
            .args(["-a", "-f", "-i", "-C", "-e"])
            .arg(elf)
            .args(chunk.iter().map(|a| format!("{a:#x}")))
            .output()
            .map_err(|e| format!("llvm-addr2line (install llvm): {e}"))?
            .stdout;
        let text = String::from_utf8_lossy(&text);
        let mut lines = text.lines().peekable();
        while let Some(line) = lines.next() {
            let Some(a) = line
                .strip_prefix("0x")
                .and_then(|hex| u64::from_str_radix(hex, 16).ok())
            else {
                continue;
            };
            // (function, path:line) pairs up to the next address line.
            let mut chain: Vec<(&str, &str)> = Vec::new();
            while lines.peek().is_some_and(|l| !l.starts_with("0x")) {
                let function = lines.next().unwrap_or_default();
                chain.push((function, lines.next().unwrap_or_default()));
            }
            // The innermost place in our sources, and the function it is in (inlined or not).
            let in_repo = |place: &str| {
                place
                    .strip_prefix(&repo)
                    .filter(|p| p.starts_with("src/") || p.starts_with("firmware/examples/"))
                    .map(str::to_string)
            };
            let ours = chain
                .iter()
                .enumerate()
                .find_map(|(i, (function, place))| in_repo(place).map(|p| (i, p, *function)));
            let called_at = ours
                .as_ref()
                .and_then(|(i, _, _)| chain.get(i + 1))
                .and_then(|(_, place)| in_repo(place))
                .unwrap_or_default();
            let outermost = chain.len().checked_sub(2).or(chain.len().checked_sub(1));
            let inlined = outermost.and_then(|i| chain.get(i)).map_or("?", |c| c.0);
            let (line, function) = ours.map_or((String::new(), String::new()), |(_, p, f)| {
                (p, function_name(f))
            });
            out.insert(
                a,
                Site {
                    line,
                    function,
                    called_at,
                    inlined: inlined.to_string(),
                },
            );
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
    blocks: Option<&str>,
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
    profile_elf(target, &elf, variant, blocks, |l| {
        l.starts_with("variant ") || l.starts_with("corpus ") || l.starts_with("summary ")
    })
}

/// `cargo xtask scene-ram SCENE [TARGET...]`: the renderer's RAM for one corpus scene as a
/// firmware for that scene alone has it (every target unless some are named): the default
/// options with a vertex cache holding every vertex, the workspace sized for the scene, built
/// as `cargo xtask profile default cache TARGET SCENE` builds it. The render call's stack is
/// that image's peak stack less the peak of the same image built without the render call
/// (`--cfg scanline3d_no_render`): what the compiler inlines into the caller's frame counts,
/// as `cargo xtask lean` measures its builds against its baseline. Prints view 0's
/// instructions and each figure.
pub fn scene_ram(scene: &str, targets: &[&str]) -> Result<(), String> {
    let corpus = scanline3d_sim::export::corpus_source(240, 240, 10)?;
    let dir = root().join("target/scene-ram-corpus");
    std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
    let corpus_file = dir.join("corpus.rs");
    std::fs::write(&corpus_file, only_scene(&corpus, scene)?).map_err(|e| e.to_string())?;
    let field = |out: &str, key: &str| -> Result<u64, String> {
        out.lines()
            .filter(|l| l.starts_with("summary ") || l.starts_with("corpus "))
            .find_map(|l| {
                let words: Vec<&str> = l.split_whitespace().collect();
                let at = words.iter().position(|w| *w == key)?;
                words.get(at + 1)?.parse().ok()
            })
            .ok_or_else(|| format!("no `{key}` in the firmware's output:\n{out}"))
    };
    let mut rows = Vec::new();
    for target in targets {
        let mut cfgs = vec![
            "scanline3d_variant=\"default\"".to_string(),
            "scanline3d_vertex_cache".into(),
            "scanline3d_corpus_only".into(),
        ];
        let generated = Some((CORPUS, corpus_file.as_path()));
        step(&format!("corpus scene {scene} alone, default with a vertex cache, {target}"));
        let elf = build_example_with_cfgs("tradeoff", Some(target), &cfgs, generated)?;
        let out = run_on_qemu_with(target, &elf, &[])?;
        print!("{out}");
        let (workspace, peak) = (field(&out, "corpus_workspace")?, field(&out, "peak_stack")?);
        let instructions = field(&out, "instructions")?;
        step(&format!("the same without the render call, {target}"));
        cfgs.push("scanline3d_no_render".into());
        let elf = build_example_with_cfgs("tradeoff", Some(target), &cfgs, generated)?;
        let out = run_on_qemu_with(target, &elf, &[])?;
        print!("{out}");
        let render_stack = peak.saturating_sub(field(&out, "peak_stack")?);
        rows.push(format!(
            "| {target} | {instructions} | {workspace} B | {render_stack} B | {} B |",
            workspace + render_stack
        ));
    }
    println!("\ncorpus scene {scene}, view 0, default options, vertex cache:\n");
    println!("| target | instructions, view 0 | workspace | render call stack | renderer RAM |");
    println!("|---|---:|---:|---:|---:|");
    for row in rows {
        println!("{row}");
    }
    Ok(())
}

/// `cargo xtask profile trace [pure|hybrid] [TARGET]`: the traced firmware's frame in one mode
/// alone (`--cfg scanline3d_trace_only`), profiled like a trade-off variant.
pub fn profile_trace(mode: &str, target: &str, blocks: Option<&str>) -> Result<(), String> {
    if !["pure", "hybrid"].contains(&mode) {
        return Err(format!("trace mode {mode:?}: pure or hybrid"));
    }
    step(&format!(
        "traced firmware, {mode} frame alone, for {target}"
    ));
    let cfgs = [format!("scanline3d_trace_only=\"{mode}\"")];
    let elf = build_example_with_cfgs("trace", Some(target), &cfgs, None)?;
    profile_elf(target, &elf, &format!("trace {mode}"), blocks, |l| {
        l.starts_with("frame ")
    })
}

/// `cargo xtask profile firmware [TARGET]`: the demo firmware's orbit with the vertex cache,
/// built as `cargo xtask firmware` measures it (`--cfg scanline3d_vertex_cache`; thumbv7em
/// unless a TARGET is named), profiled like a trade-off variant.
pub fn profile_firmware(target: &str, blocks: Option<&str>) -> Result<(), String> {
    step(&format!("demo firmware with the vertex cache for {target}"));
    let cfgs = ["scanline3d_vertex_cache".to_string()];
    let elf = build_example_with_cfgs("firmware", Some(target), &cfgs, None)?;
    profile_elf(target, &elf, "firmware", blocks, |l| l.starts_with("frame "))
}

/// `cargo xtask profile patch [TARGET]`: the patch firmware's teapot frames (tolerance
/// 0.5 px), profiled like a trade-off variant (thumbv7em unless a TARGET is named).
pub fn profile_patch(target: &str, blocks: Option<&str>) -> Result<(), String> {
    step(&format!("patch firmware (teapot, 0.5 px) for {target}"));
    let elf = build_example_with_cfgs("patch", Some(target), &[], None)?;
    profile_elf(target, &elf, "patch", blocks, |l| l.starts_with("frame "))
}

/// `cargo xtask flash [TARGET] [VARIANT]`: where the renderer flash of a lean build goes
/// (`cargo xtask lean`'s "renderer flash": the variant's flash less `lean_baseline`'s). Each
/// instruction's bytes (to the next instruction, or to its symbol's end) and each read-only
/// data symbol are charged to a source function as [`source_lines`] names it; the table is
/// per function, the variant's bytes less the baseline's, largest first.
pub fn flash(target: &str, variant: &str) -> Result<(), String> {
    step(&format!("lean firmware ({variant} and baseline) for {target}"));
    crate::firmware_build::build_firmware_examples_on(
        &[target],
        "lean",
        &[&format!("lean_{variant}"), "lean_baseline"],
    )?;
    // The two examples' own functions (`lean_minimal::lean::run`, `lean_baseline::lean::run`)
    // compared under one name.
    let of = |example: &str| -> Result<HashMap<String, i64>, String> {
        let bytes = code_bytes_by_function(&crate::firmware::firmware_elf(target, "lean", example))?;
        let own = format!("{example}::");
        let mut merged: HashMap<String, i64> = HashMap::new();
        for (f, n) in bytes {
            *merged.entry(f.replace(&own, "example::")).or_default() += n;
        }
        Ok(merged)
    };
    let (build, base) = (of(&format!("lean_{variant}"))?, of("lean_baseline")?);
    let mut rows: Vec<(i64, i64, &str)> = build
        .keys()
        .chain(base.keys())
        .collect::<std::collections::BTreeSet<_>>()
        .into_iter()
        .map(|f| {
            let (b, a) = (base.get(f).copied().unwrap_or(0), build.get(f).copied().unwrap_or(0));
            (a - b, a, f.as_str())
        })
        .filter(|r| r.0 != 0)
        .collect();
    rows.sort_by_key(|r| (-r.0, r.2));
    let total: i64 = rows.iter().map(|r| r.0).sum();
    println!(
        "lean_{variant} on {target}: {total} B of code and read-only data more than lean_baseline, by source function (innermost in src/ or firmware/examples/, else the symbol):"
    );
    println!("| function | bytes more than the baseline | bytes in lean_{variant} |");
    println!("|---|---:|---:|");
    for (more, bytes, f) in &rows {
        println!("| {f} | {more} | {bytes} |");
    }
    Ok(())
}

/// Bytes of code (every instruction to the next, or to its symbol's end) and of read-only
/// data symbols, by the function [`source_lines`] charges them to.
fn code_bytes_by_function(elf: &std::path::Path) -> Result<HashMap<String, i64>, String> {
    let syms = symbols(elf)?;
    let listing = Command::new("llvm-objdump")
        .args(["-d", "--no-show-raw-insn"])
        .arg(elf)
        .output()
        .map_err(|e| format!("llvm-objdump (install llvm): {e}"))?
        .stdout;
    let listing = String::from_utf8_lossy(&listing);
    let addrs: Vec<u64> = listing
        .lines()
        .filter_map(|l| {
            let (addr, rest) = l.trim_start().split_once(':')?;
            (!rest.is_empty() && !l.ends_with(">:"))
                .then(|| u64::from_str_radix(addr.trim(), 16).ok())
                .flatten()
        })
        .collect();
    let sites = source_lines(elf, &addrs)?;
    let mut bytes: HashMap<String, i64> = HashMap::new();
    for (k, &a) in addrs.iter().enumerate() {
        let symbol = name_of(&syms, a);
        let end = syms
            .iter()
            .find(|s| s.0 <= a && a < s.0 + s.1)
            .map_or(a, |s| s.0 + s.1);
        let next = addrs.get(k + 1).copied().filter(|&n| n > a && n <= end);
        let size = next.unwrap_or(end).saturating_sub(a) as i64;
        let key = match sites.get(&a) {
            Some(site) if !site.function.is_empty() => site.function.clone(),
            _ => function_name(symbol),
        };
        *bytes.entry(key).or_default() += size;
    }
    // Read-only data (tables, literal strings), by symbol.
    let out = Command::new("llvm-nm")
        .args(["-C", "-S", "--defined-only"])
        .arg(elf)
        .output()
        .map_err(|e| format!("llvm-nm (install llvm): {e}"))?;
    for l in String::from_utf8_lossy(&out.stdout).lines() {
        let p: Vec<&str> = l.splitn(4, ' ').collect();
        if let [_, size, kind, name] = p[..] {
            if kind.eq_ignore_ascii_case("r") {
                let size = i64::from_str_radix(size, 16).unwrap_or(0);
                *bytes.entry(format!("(data) {}", function_name(name))).or_default() += size;
            }
        }
    }
    Ok(bytes)
}

/// What the log says ran: per block and per instruction address, with the built-ins apart.
#[derive(Default)]
struct Counts {
    /// Per translated block, by its first address, the addresses of its instructions.
    blocks: HashMap<u64, Vec<u64>>,
    /// Per block of code other than the built-ins, how many times it ran.
    runs: HashMap<u64, u64>,
    per_function: HashMap<u64, u64>,
    /// Per instruction address outside the built-ins, the instructions executed there and in
    /// the built-ins it called.
    per_site: HashMap<u64, u64>,
    /// Per call site and built-in block, the built-ins' instructions alone.
    builtin_site: HashMap<(u64, u64), u64>,
    total: u64,
    builtin: u64,
}

/// Reads QEMU's `-d in_asm,exec,nochain` log: each executed block's instructions, each charged
/// to its own address, with the built-ins charged to the call site that entered them.
fn count_blocks(log: impl BufRead, syms: &[(u64, u64, String)]) -> Result<Counts, String> {
    // QEMU lists a block when it translates it, before it first runs.
    let mut c = Counts::default();
    let mut builtin_of: HashMap<u64, bool> = HashMap::new();
    let mut caller = 0u64;
    let mut listing: Option<u64> = None;
    for line in log.lines() {
        let line = line.map_err(|e| e.to_string())?;
        if let Some(rest) = line.strip_prefix("Trace ") {
            let Some(pc) = rest
                .split_once('[')
                .and_then(|(_, r)| r.split('/').nth(1))
                .and_then(|pc| u64::from_str_radix(pc, 16).ok())
            else {
                continue;
            };
            let block = c.blocks.get(&pc);
            let len = block.map_or(1, |b| b.len() as u64);
            let last = block.and_then(|b| b.last().copied()).unwrap_or(pc);
            let is_builtin = *builtin_of
                .entry(pc)
                .or_insert_with(|| is_builtin(name_of(syms, pc)));
            c.total += len;
            *c.per_function.entry(pc).or_default() += len;
            if is_builtin {
                c.builtin += len;
                *c.builtin_site.entry((caller, pc)).or_default() += len;
                *c.per_site.entry(caller).or_default() += len;
            } else {
                caller = last;
                *c.runs.entry(pc).or_default() += 1;
            }
        } else if line.starts_with("IN:") || line.trim().is_empty() {
            listing = None;
        } else if let Some(addr) = line
            .strip_prefix("0x")
            .and_then(|l| l.split(':').next())
            .and_then(|a| u64::from_str_radix(a, 16).ok())
        {
            // A block translated again (after a flush) is listed again: its new listing counts.
            let start = *listing.get_or_insert_with(|| {
                c.blocks.insert(addr, Vec::new());
                addr
            });
            c.blocks.entry(start).or_default().push(addr);
        }
    }
    for (pc, runs) in &c.runs {
        for addr in c.blocks.get(pc).map_or(&[*pc][..], Vec::as_slice) {
            *c.per_site.entry(*addr).or_default() += runs;
        }
    }
    Ok(c)
}

/// Runs `elf` on QEMU with every executed block logged into a named pipe that is read as QEMU
/// writes it (no multi-gigabyte file), and prints the output lines `frame_line` picks, the share
/// of compiler built-ins, the top functions, the top source lines, the top functions of our
/// sources (inlined or not) and the functions inlined into each symbol; with `blocks`, also
/// the executed blocks of the symbols whose name contains it ([`print_blocks`]).
fn profile_elf(
    target: &str,
    elf: &std::path::Path,
    what: &str,
    blocks: Option<&str>,
    frame_line: impl Fn(&str) -> bool,
) -> Result<(), String> {
    let fifo = root().join("target/profile-trace.fifo");
    let _ = std::fs::remove_file(&fifo);
    let made = Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .map_err(|e| format!("mkfifo: {e}"))?;
    if !made.success() {
        return Err(format!("mkfifo {} failed", fifo.display()));
    }
    let syms = symbols(elf)?;
    step("run on QEMU, counting every executed block as QEMU logs it");
    let counts = std::thread::scope(|scope| {
        let reader = scope.spawn(|| {
            let file = std::fs::File::open(&fifo).map_err(|e| format!("{}: {e}", fifo.display()))?;
            count_blocks(std::io::BufReader::with_capacity(1 << 20, file), &syms)
        });
        let out = run_on_qemu_with(
            target,
            elf,
            &[
                "-d".as_ref(),
                "in_asm,exec,nochain".as_ref(),
                "-D".as_ref(),
                fifo.as_os_str(),
            ],
        );
        let counts = reader
            .join()
            .map_err(|_| "the log reader panicked".to_string())?;
        Ok::<_, String>((out?, counts?))
    });
    std::fs::remove_file(&fifo).map_err(|e| e.to_string())?;
    let (out, c) = counts?;
    let frame_lines: Vec<&str> = out.lines().filter(|l| frame_line(l)).collect();
    // Each frame's own count (SysTick or minstret, as the firmware reads it).
    for line in &frame_lines {
        println!("{line}");
    }
    // (A `summary` line, printed with the frames, is not one.)
    let frames = frame_lines
        .iter()
        .filter(|l| !l.starts_with("summary "))
        .count();
    let total = c.total;
    println!(
        "\n{frames} frames of `{what}` on {target}: {total} instructions ({} a frame, set-up and output included), {:.1} % of them in compiler built-ins (software 64-bit multiply and divide, memcpy, ...)",
        total / frames.max(1) as u64,
        percent(c.builtin, total)
    );
    let mut functions: HashMap<&str, u64> = HashMap::new();
    for (pc, n) in &c.per_function {
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
    let sites: Vec<u64> = c.per_site.keys().copied().collect();
    let lines = source_lines(elf, &sites)?;
    let mut by_line: HashMap<&str, u64> = HashMap::new();
    let mut by_function: HashMap<&str, u64> = HashMap::new();
    let mut by_inlined: HashMap<String, u64> = HashMap::new();
    let mut by_call: HashMap<String, u64> = HashMap::new();
    for (site, n) in &c.per_site {
        if let Some(s) = lines.get(site).filter(|s| !s.called_at.is_empty()) {
            *by_call
                .entry(format!("{} < {}", s.function, s.called_at))
                .or_default() += n;
        }
        let (line, function, inlined) = lines.get(site).map_or(("", "", "?"), |s| {
            (s.line.as_str(), s.function.as_str(), s.inlined.as_str())
        });
        let (line, function) = if line.is_empty() {
            (
                "(no line in src/ or firmware/examples/)",
                "(no function in src/ or firmware/examples/)",
            )
        } else {
            (line, function)
        };

        *by_line.entry(line).or_default() += n;
        *by_function.entry(function).or_default() += n;
        let symbol = short_name(name_of(&syms, *site));
        *by_inlined
            .entry(format!("{symbol} > {}", short_name(inlined)))
            .or_default() += n;
    }
    let mut by_line: Vec<_> = by_line.into_iter().collect();
    by_line.sort_by_key(|l| std::cmp::Reverse(l.1));
    println!("\nsource lines, with the built-ins they call:");
    for (line, n) in by_line.iter().take(40) {
        println!("{:6.2} %  {line}", percent(*n, total));
    }
    let mut by_function: Vec<_> = by_function.into_iter().collect();
    by_function.sort_by_key(|f| std::cmp::Reverse(f.1));
    println!(
        "\nfunctions of src/ and firmware/examples/, inlined or not (the innermost one an instruction comes from), with the built-ins they call:"
    );
    for (function, n) in by_function.iter().take(40) {
        println!("{:6.2} %  {function}", percent(*n, total));
    }
    let mut by_call: Vec<_> = by_call.into_iter().collect();
    by_call.sort_by_key(|l| std::cmp::Reverse(l.1));
    println!(
        "\nthose functions by the line they were inlined at (function < calling line), with the built-ins they call:"
    );
    for (call, n) in by_call.iter().take(40) {
        println!("{:6.2} %  {call}", percent(*n, total));
    }
    let mut builtin_sites: HashMap<String, u64> = HashMap::new();
    for ((site, pc), n) in &c.builtin_site {
        let (line, inlined) = lines
            .get(site)
            .map_or(("", "?"), |s| (s.line.as_str(), s.inlined.as_str()));
        *builtin_sites
            .entry(format!(
                "{line} ({}): {}",
                short_name(inlined),
                short_name(name_of(&syms, *pc))
            ))
            .or_default() += n;
    }
    let mut builtin_sites: Vec<_> = builtin_sites.into_iter().collect();
    builtin_sites.sort_by_key(|l| std::cmp::Reverse(l.1));
    println!("\nthe built-ins alone, by the source line that called them:");
    for (line, n) in builtin_sites.iter().take(30) {
        println!("{:6.2} %  {line}", percent(*n, total));
    }
    let mut by_inlined: Vec<_> = by_inlined.into_iter().collect();
    by_inlined.sort_by_key(|l| std::cmp::Reverse(l.1));
    println!("\nsymbol > the function inlined into it that the instruction comes from (the outermost inlined call), with the built-ins they call:");
    for (name, n) in by_inlined.iter().take(30) {
        println!("{:6.2} %  {name}", percent(*n, total));
    }
    if let Some(pattern) = blocks {
        print_blocks(&c, &syms, &lines, pattern, frames.max(1) as f64);
    }
    Ok(())
}

/// `--blocks PATTERN`: per symbol whose name contains `pattern`, its instructions a frame
/// (with the built-ins it calls) and its 40 costliest blocks as QEMU translated them (a block:
/// straight-line code entered at its first address; a loop's first iteration can share its
/// entry's block): instructions a frame, runs a frame times length, first address, and the
/// innermost source functions of its instructions (`function @ path:line (instructions)`, the
/// three most common); then the built-ins it called, a frame each. A function's cost taken
/// apart to the branch without a debugger.
fn print_blocks(
    c: &Counts,
    syms: &[(u64, u64, String)],
    lines: &HashMap<u64, Site>,
    pattern: &str,
    frames: f64,
) {
    let mut symbols: HashMap<&str, u64> = HashMap::new();
    for (site, n) in &c.per_site {
        let name = name_of(syms, *site);
        if short_name(name).contains(pattern) {
            *symbols.entry(name).or_default() += n;
        }
    }
    let mut symbols: Vec<_> = symbols.into_iter().collect();
    symbols.sort_by_key(|s| std::cmp::Reverse(s.1));
    if symbols.is_empty() {
        println!("\nno executed symbol's name contains `{pattern}`");
    }
    for (symbol, n) in symbols {
        println!(
            "\n{}: {:.0} instructions a frame, with the built-ins it calls; its costliest blocks:",
            short_name(symbol),
            n as f64 / frames
        );
        let mut blocks: Vec<(f64, f64, usize, u64, String)> = c
            .runs
            .iter()
            .filter(|(pc, _)| name_of(syms, **pc) == symbol)
            .map(|(pc, runs)| {
                let one = [*pc];
                let addrs = c.blocks.get(pc).map_or(&one[..], Vec::as_slice);
                let mut from: HashMap<String, usize> = HashMap::new();
                for a in addrs {
                    if let Some(s) = lines.get(a).filter(|s| !s.line.is_empty()) {
                        *from.entry(format!("{} @ {}", s.function, s.line)).or_default() += 1;
                    }
                }
                let mut from: Vec<_> = from.into_iter().collect();
                from.sort_by(|a, b| b.1.cmp(&a.1).then_with(|| a.0.cmp(&b.0)));
                let source = from
                    .iter()
                    .take(3)
                    .map(|(f, k)| format!("{f} ({k})"))
                    .collect::<Vec<_>>()
                    .join("; ");
                let per_frame = *runs as f64 / frames;
                let len = addrs.len();
                (per_frame * len as f64, per_frame, len, *pc, source)
            })
            .collect();
        blocks.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.3.cmp(&b.3)));
        for (instructions, runs, len, pc, source) in blocks.iter().take(40) {
            println!("{instructions:10.0} = {runs:9.1} x {len:3}  {pc:#x}  {source}");
        }
        // The built-ins' instructions are in the symbol's total, not in its blocks.
        let mut builtins: HashMap<String, u64> = HashMap::new();
        for ((site, pc), n) in &c.builtin_site {
            if name_of(syms, *site) == symbol {
                *builtins.entry(short_name(name_of(syms, *pc))).or_default() += n;
            }
        }
        let mut builtins: Vec<_> = builtins.into_iter().collect();
        builtins.sort_by(|a, b| b.1.cmp(&a.1).then_with(|| a.0.cmp(&b.0)));
        for (name, n) in builtins {
            println!("{:10.0}   in built-in {name}", n as f64 / frames);
        }
    }
}

/// A symbol without its hash and crate path: `Tracer<_>::shade`.
fn short_name(name: &str) -> String {
    let name = name.rsplit_once("::h").map_or(name, |(n, h)| {
        if h.len() == 16 && h.chars().all(|c| c.is_ascii_hexdigit()) {
            n
        } else {
            name
        }
    });
    name.replace("scanline3d::trace::", "")
        .replace("_$LT$", "<")
        .replace("$LT$", "<")
        .replace("$GT$", ">")
        .replace("$u20$", " ")
        .replace("$u7b$", "{")
        .replace("$u7d$", "}")
}

