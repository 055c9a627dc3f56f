//! `cargo xtask firmware`: the demo orbit on QEMU for every target, twice, with hashes, sizes,
//! the vertex-cache variant and the baked variants (face colours lit on the host, `Unlit`).

use crate::*;

/// Runs a firmware example on one target under QEMU (the runner in `.cargo/config.toml`)
/// with the given cargo profile, and returns its output.
pub(crate) fn run_example(target: &str, profile: &str, example: &str) -> Result<String, String> {
    let out = cargo()
        .args(["run", "--package", FIRMWARE_PACKAGE, "--profile", profile])
        .args(["--example", example])
        .args(["--target", target])
        .env("CARGO_TARGET_DIR", firmware_target_dir(target))
        .current_dir(root())
        .stderr(Stdio::inherit())
        .output()
        .map_err(|e| format!("{example} on {target}: {e}"))?;
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    if !out.status.success() {
        return Err(format!(
            "{example} on {target} failed ({}):\n{text}",
            out.status
        ));
    }
    Ok(text)
}

/// Frame hashes the host computes for the demo orbit, through the same code as the firmware.
pub(crate) fn host_hashes() -> Result<Vec<u32>, String> {
    use scanline3d_demo as demo;
    let mut ws = Box::new(demo::PanelWorkspace::new(demo::BACKGROUND.into()));
    let instances = demo::instances();
    (0..demo::ORBIT_FRAMES)
        .map(|frame| {
            let scene =
                demo::scene(&instances, frame, demo::ORBIT_FRAMES).map_err(|e| e.to_string())?;
            demo::render_panel_frame(&mut ws, &scene)
                .map(|f| f.hash)
                .map_err(|e| e.to_string())
        })
        .collect()
}

/// The ELF of firmware example `example` built with `profile` for `target`.
pub(crate) fn firmware_elf(target: &str, profile: &str, example: &str) -> std::path::PathBuf {
    firmware_target_dir(target)
        .join(target)
        .join(profile)
        .join("examples")
        .join(example)
}

pub(crate) fn firmware() -> Result<(), String> {
    let expected = host_hashes()?;
    step("demo firmware for every target (a no-op when built)");
    build_firmware_examples("firmware", &["firmware"])?;
    for (target, machine) in FIRMWARE {
        step(&format!("firmware on QEMU {machine}, {target}"));
        let first = run_example(target, "firmware", "firmware")?;
        print!("{first}");
        let second = run_example(target, "firmware", "firmware")?;
        if first != second {
            return Err(format!("{target}: two runs printed different output (instruction counts must be deterministic)\n{second}"));
        }
        println!("(second run printed identical output: counts are deterministic)");
        let hashes: Vec<u32> = first
            .lines()
            .filter_map(|l| l.strip_prefix("frame "))
            .filter_map(|l| {
                l.split_whitespace()
                    .nth(2)
                    .and_then(|h| u32::from_str_radix(h, 16).ok())
            })
            .collect();
        if hashes != expected {
            return Err(format!(
                "{target}: frame hashes {hashes:08x?} differ from the host's {expected:08x?}"
            ));
        }
        println!("frame hashes equal the host's: {expected:08x?}");
        sizes(target, &first)?;
        let cached = vertex_cache_on_target(target, &first, &expected)?;
        baked_on_target(target, &[], &first, &expected)?;
        baked_on_target(target, &["scanline3d_vertex_cache"], &cached, &expected)?;
    }
    Ok(())
}

/// The demo firmware built with `--cfg` each of `cfgs`: returns its output (every frame's hash
/// checked against `expected`).
fn firmware_variant(target: &str, cfgs: &[&str], expected: &[u32]) -> Result<String, String> {
    let mut cmd = cargo();
    cmd.args([
        "rustc",
        "--package",
        FIRMWARE_PACKAGE,
        "--profile",
        "firmware",
    ])
    .args(["--example", "firmware"])
    .args(["--target", target, "--"]);
    for cfg in cfgs {
        cmd.args(["--cfg", cfg]);
    }
    run(cmd.env("CARGO_TARGET_DIR", firmware_target_dir(target)))?;
    let elf = firmware_elf(target, "firmware", "firmware");
    let out = tradeoff::run_on_qemu_with(target, &elf, &[])?;
    let hashes = frame_hashes(&out);
    if hashes != expected {
        return Err(format!(
            "{target} with {cfgs:?}: frame hashes {hashes:08x?} differ from the host's {expected:08x?}"
        ));
    }
    Ok(out)
}

/// The demo firmware with its face colours lit on the host (`--cfg scanline3d_baked`, `Unlit`
/// shading) and `cfgs`: the frames must hash as the lit ones; prints its cost against the lit
/// run `lit` (firmware output, the same `cfgs`). Valid for a static light and static objects.
pub(crate) fn baked_on_target(
    target: &str,
    cfgs: &[&str],
    lit: &str,
    expected: &[u32],
) -> Result<(), String> {
    let label = if cfgs.is_empty() {
        "baked face colours"
    } else {
        "baked face colours with a vertex cache"
    };
    step(&format!("firmware with {label}, {target}"));
    let mut all = vec!["scanline3d_baked"];
    all.extend_from_slice(cfgs);
    let out = firmware_variant(target, &all, expected)?;
    print!("{out}");
    let (lit_mean, baked) = (mean_frame_instructions(lit), mean_frame_instructions(&out));
    println!(
        "{label}: the same hashes; {:.2} M instructions per frame against {:.2} M lit ({:.2}x fewer); peak stack {} B against {} B",
        baked / 1e6,
        lit_mean / 1e6,
        lit_mean / baked.max(1.0),
        summary_field(&out, "peak_stack"),
        summary_field(lit, "peak_stack")
    );
    sizes(target, &out)?;
    Ok(())
}

/// The hashes of the `frame N hash H ...` lines of firmware output.
pub(crate) fn frame_hashes(output: &str) -> Vec<u32> {
    hashes_of_lines(output, "frame ")
}

/// Mean instructions per frame over the `frame` lines of firmware output.
pub(crate) fn mean_frame_instructions(output: &str) -> f64 {
    let counts = frame_instructions(output);
    counts.iter().sum::<u64>() as f64 / counts.len().max(1) as f64
}

/// Each frame's instruction count in firmware output, in frame order.
fn frame_instructions(output: &str) -> Vec<u64> {
    output
        .lines()
        .filter_map(|l| l.strip_prefix("frame "))
        .filter_map(|l| {
            let w: Vec<&str> = l.split_whitespace().collect();
            w.windows(2)
                .find(|p| p[0] == "instructions")
                .and_then(|p| p[1].parse().ok())
        })
        .collect()
}

/// The demo firmware again with a vertex cache holding every demo vertex (`--cfg
/// scanline3d_vertex_cache`): the frames must hash the same; prints its cost against the
/// uncached run `uncached` (firmware output) and its renderer RAM, and returns its output.
pub(crate) fn vertex_cache_on_target(
    target: &str,
    uncached: &str,
    expected: &[u32],
) -> Result<String, String> {
    step(&format!("firmware with a vertex cache, {target}"));
    let out = firmware_variant(target, &["scanline3d_vertex_cache"], expected)?;
    let (plain, cached) = (
        mean_frame_instructions(uncached),
        mean_frame_instructions(&out),
    );
    let frames = frame_instructions(&out);
    let (low, high) = (
        frames.iter().min().copied().unwrap_or(0),
        frames.iter().max().copied().unwrap_or(0),
    );
    println!(
        "vertex cache: the same hashes; {:.2} M instructions per frame (mean {cached:.0}, frames {low}–{high}) against {:.2} M ({:.2}× fewer); renderer RAM {} B against {} B",
        cached / 1e6,
        plain / 1e6,
        plain / cached.max(1.0),
        summary_field(&out, "renderer_ram"),
        summary_field(uncached, "renderer_ram")
    );
    Ok(out)
}

/// An ELF symbol: name, size, type, section index.
pub(crate) type Symbol = (String, u32, u8, u16);

/// Section sizes and symbol attribution of an ELF32 little-endian file.
pub(crate) struct Elf {
    pub(crate) sections: Vec<(String, u32, u32)>, // name, size, flags
    pub(crate) symbols: Vec<Symbol>,
}

pub(crate) fn elf(path: &std::path::Path) -> Result<Elf, String> {
    let d = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let u16_at = |o: usize| {
        d.get(o..o + 2)
            .map(|b| u16::from_le_bytes([b[0], b[1]]))
            .unwrap_or(0)
    };
    let u32_at = |o: usize| {
        d.get(o..o + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .unwrap_or(0)
    };
    if d.get(..5) != Some(b"\x7fELF\x01") {
        return Err(format!("{}: not an ELF32 file", path.display()));
    }
    let (shoff, shentsize, shnum, shstrndx) = (
        u32_at(0x20) as usize,
        u16_at(0x2e) as usize,
        u16_at(0x30) as usize,
        u16_at(0x32) as usize,
    );
    let sh = |i: usize| shoff + i * shentsize;
    let str_at = |table: usize, off: usize| -> String {
        let start = table + off;
        let end = d[start..]
            .iter()
            .position(|&b| b == 0)
            .map_or(start, |n| start + n);
        String::from_utf8_lossy(&d[start..end]).into_owned()
    };
    let names = u32_at(sh(shstrndx) + 0x10) as usize;
    let mut sections = Vec::new();
    let mut symbols = Vec::new();
    for i in 0..shnum {
        let h = sh(i);
        let (name, kind, flags, offset, size, link) = (
            u32_at(h) as usize,
            u32_at(h + 4),
            u32_at(h + 8),
            u32_at(h + 0x10) as usize,
            u32_at(h + 0x14),
            u32_at(h + 0x18) as usize,
        );
        sections.push((str_at(names, name), size, flags));
        if kind == 2 {
            // SHT_SYMTAB: 16-byte entries; names in the linked string table.
            let strtab = u32_at(sh(link) + 0x10) as usize;
            for e in (offset..offset + size as usize).step_by(16) {
                let name = str_at(strtab, u32_at(e) as usize);
                symbols.push((
                    name,
                    u32_at(e + 8),
                    d.get(e + 12).copied().unwrap_or(0) & 0xf,
                    u16_at(e + 14),
                ));
            }
        }
    }
    Ok(Elf { sections, symbols })
}

/// Prints flash and RAM of the firmware for `target`, and how much of the flash is the library.
pub(crate) fn sizes(target: &str, firmware_output: &str) -> Result<(), String> {
    let path = firmware_elf(target, "firmware", "firmware");
    let e = elf(&path)?;
    let size = |n: &str| {
        e.sections
            .iter()
            .filter(|s| s.0 == n)
            .map(|s| s.1 as u64)
            .sum::<u64>()
    };
    let (text, rodata, data, bss, vectors) = (
        size(".text"),
        size(".rodata"),
        size(".data"),
        size(".bss"),
        size(".vector_table"),
    );
    let text_index = e
        .sections
        .iter()
        .position(|s| s.0 == ".text")
        .unwrap_or(usize::MAX) as u16;
    let rodata_index = e
        .sections
        .iter()
        .position(|s| s.0 == ".rodata")
        .unwrap_or(usize::MAX) as u16;
    let sum = |pred: &dyn Fn(&Symbol) -> bool| {
        e.symbols
            .iter()
            .filter(|s| pred(s))
            .map(|s| s.1 as u64)
            .sum::<u64>()
    };
    let ours = |s: &Symbol| s.0.contains("scanline3d");
    let lib_code = sum(&|s| s.3 == text_index && ours(s) && !s.0.contains("firmware"));
    let builtins =
        sum(&|s| s.3 == text_index && (s.0.starts_with("__") || s.0.contains("compiler_builtins")));
    let mesh_data = sum(&|s| s.3 == rodata_index && ours(s) && s.0.contains("demo"));
    let stack = firmware_output
        .lines()
        .find_map(|l| l.strip_prefix("summary peak_stack "))
        .and_then(|l| l.split_whitespace().next())
        .and_then(|n| n.parse::<u64>().ok())
        .unwrap_or(0);
    println!("sizes {target}: flash {} bytes (.vector_table {vectors} + .text {text} + .rodata {rodata} + .data {data})", vectors + text + rodata + data);
    println!("sizes {target}: of which library code {lib_code}, compiler builtins {builtins}, demo mesh data {mesh_data}");
    println!("sizes {target}: RAM {} bytes (.data {data} + .bss {bss} + measured peak stack {stack}, workspace included)", data + bss + stack);
    Ok(())
}
