//! `cargo xtask lean`: the size-optimised firmware builds and their frame hashes.

use crate::*;

/// The lean firmware variants (`firmware/examples/lean_*.rs`), built with the size-optimised `lean`
/// profile.
/// `minimal_baked` is `minimal` drawing the scene exported with `--bake-light` (face colours
/// lit on the host) with `Unlit` shading: the same hashes.
pub(crate) const LEAN_VARIANTS: [&str; 4] = ["minimal", "minimal_baked", "full", "baseline"];

/// The scene the lean firmware was exported from, and how many views it was analysed from.
pub(crate) const LEAN_OBJ: &str = "firmware/examples/lean/icosphere80.obj";

pub(crate) const LEAN_VIEWS: usize = 8;

/// The scene of the lean BSP build (`firmware/examples/lean_bsp.rs`), exported with
/// `sim export sim/corpus/cyclic.obj --views 8 --no-cull --bsp`.
pub(crate) const LEAN_BSP_OBJ: &str = "sim/corpus/cyclic.obj";

/// Flash (vector table, code, read-only data, initialised data) of an ELF.
pub(crate) fn flash_bytes(path: &std::path::Path) -> Result<u64, String> {
    let e = elf(path)?;
    Ok(e.sections
        .iter()
        .filter(|s| [".vector_table", ".text", ".rodata", ".data"].contains(&s.0.as_str()))
        .map(|s| s.1 as u64)
        .sum())
}

pub(crate) fn summary_field(output: &str, name: &str) -> u64 {
    output
        .lines()
        .find_map(|l| l.strip_prefix("summary "))
        .and_then(|l| {
            let words: Vec<&str> = l.split_whitespace().collect();
            words
                .windows(2)
                .find(|w| w[0] == name)
                .and_then(|w| w[1].parse().ok())
        })
        .unwrap_or(0)
}

/// `cargo xtask lean`: the lean firmware built with the size-optimised `lean` profile on every
/// target, its frame hashes checked, and its flash and RAM table.
pub(crate) fn lean() -> Result<(), String> {
    step("lean firmware for every target");
    build_firmware_examples("lean", &LEAN_EXAMPLES)?;
    lean_runs("lean", true)
}

/// The lean firmware on every target, built beforehand with `profile`: frame hashes must equal
/// the host's render of the OBJ the scene was exported from. `with_table` also prints the flash
/// and RAM of the minimal and full builds, with the renderer's share measured against the
/// renderer-less baseline (meaningful for the `lean` profile only: the test command checks the
/// hashes of a `firmware`-profile build, whose dependencies it has already built, and neither
/// builds nor runs the baseline, which renders nothing).
pub(crate) fn lean_runs(profile: &str, with_table: bool) -> Result<(), String> {
    use scanline3d_sim::scene::{MeshData, SceneSpec};
    let mesh = MeshData::load_obj(&root().join(LEAN_OBJ))?;
    let base = SceneSpec::single(
        mesh,
        scanline3d_sim::scene::CameraSpec::looking_at([0.0, 0.0, 1.0], [0.0; 3], 50.0, 0.1, 10.0),
        Default::default(),
        true,
    );
    let expected = scanline3d_sim::analyze::default_views(&base, LEAN_VIEWS)?
        .into_iter()
        .map(|camera| {
            SceneSpec {
                camera,
                ..base.clone()
            }
            .panel_hash(240, 240)
        })
        .collect::<Result<Vec<u32>, String>>()?;
    let bsp_base = SceneSpec::single(
        MeshData::load_obj(&root().join(LEAN_BSP_OBJ))?,
        scanline3d_sim::scene::CameraSpec::looking_at([0.0, 0.0, 1.0], [0.0; 3], 50.0, 0.1, 10.0),
        Default::default(),
        false,
    );
    let bsp_expected = scanline3d_sim::analyze::default_views(&bsp_base, LEAN_VIEWS)?
        .into_iter()
        .map(|camera| {
            SceneSpec {
                camera,
                ..bsp_base.clone()
            }
            .panel_hash_with(240, 240, scanline3d_sim::scene::Algorithm::Bsp)
        })
        .collect::<Result<Vec<u32>, String>>()?;
    let mut table = Vec::new();
    let mut bsp_table = Vec::new();
    for (target, machine) in FIRMWARE {
        step(&format!("lean firmware (bsp) on QEMU {machine}, {target}"));
        let out = run_example(target, profile, "lean_bsp")?;
        print!("{out}");
        if view_hashes(&out) != bsp_expected {
            return Err(format!(
                "lean_bsp on {target}: hashes {:08x?} differ from the host's BSP render of {LEAN_BSP_OBJ}: {bsp_expected:08x?}",
                view_hashes(&out)
            ));
        }
        println!("view hashes equal the host's BSP render of {LEAN_BSP_OBJ}");
        let elf_path = firmware_elf(target, profile, "lean_bsp");
        bsp_table.push(format!(
            "| {target} | {} | {} | {} |",
            flash_bytes(&elf_path)?,
            summary_field(&out, "workspace"),
            summary_field(&out, "peak_stack")
        ));
        let mut flash = std::collections::HashMap::new();
        for variant in LEAN_VARIANTS
            .into_iter()
            .filter(|v| with_table || *v != "baseline")
        {
            step(&format!(
                "lean firmware ({variant}) on QEMU {machine}, {target}"
            ));
            let out = run_example(target, profile, &format!("lean_{variant}"))?;
            print!("{out}");
            let hashes = view_hashes(&out);
            if variant != "baseline" {
                if hashes != expected {
                    return Err(format!("lean_{variant} on {target}: hashes {hashes:08x?} differ from the host render of {LEAN_OBJ}: {expected:08x?}"));
                }
                println!("view hashes equal the host render of {LEAN_OBJ}");
            }
            let elf_path = firmware_elf(target, profile, &format!("lean_{variant}"));
            flash.insert(variant, (flash_bytes(&elf_path)?, out));
        }
        if !with_table {
            continue;
        }
        let (base_flash, base_out) = &flash["baseline"];
        let base_stack = summary_field(base_out, "peak_stack");
        for variant in ["minimal", "minimal_baked", "full"] {
            let (f, out) = &flash[variant];
            let workspace = summary_field(out, "workspace");
            let stack = summary_field(out, "peak_stack");
            table.push(format!(
                "| {target} | {variant} | {f} | {} | {workspace} | {} |",
                f - base_flash,
                stack.saturating_sub(base_stack)
            ));
        }
    }
    if !with_table {
        return Ok(());
    }
    println!("\nlean firmware, {LEAN_OBJ} (80 triangles), 240x240, `lean` profile (opt-level z):");
    println!("| target | build | firmware flash B | renderer flash B (minus baseline) | workspace B | render stack B (peak minus baseline) |");
    println!("|---|---|---|---|---|---|");
    for row in table {
        println!("{row}");
    }
    println!("\nlean BSP firmware, {LEAN_BSP_OBJ} (3 triangles, 7 after splitting), 240x240, `lean` profile:");
    println!("| target | firmware flash B | workspace B | peak stack B (workspace included) |");
    println!("|---|---|---|---|");
    for row in bsp_table {
        println!("{row}");
    }
    Ok(())
}

/// The hashes of the `view N hash H ...` lines of a lean firmware's output.
pub(crate) fn view_hashes(output: &str) -> Vec<u32> {
    hashes_of_lines(output, "view ")
}

/// The hashes (third word, hex) of the output lines starting with `prefix`.
pub(crate) fn hashes_of_lines(output: &str, prefix: &str) -> Vec<u32> {
    output
        .lines()
        .filter_map(|l| l.strip_prefix(prefix))
        .filter_map(|l| {
            l.split_whitespace()
                .nth(2)
                .and_then(|h| u32::from_str_radix(h, 16).ok())
        })
        .collect()
}
