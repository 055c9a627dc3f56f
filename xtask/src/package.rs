//! The library as a user gets it: `cargo publish --dry-run`, a downstream firmware crate built
//! against the packaged crate with its own memory map by the minimum supported Rust version,
//! and the user-facing example crates (RP2040 panel, desktop window).

use crate::*;

/// The minimum supported Rust version: `rust-version` in the library's `Cargo.toml`.
pub(crate) const MSRV: &str = "1.87.0";

/// Where the downstream crate's link address must lie (its memory.x: 64 KiB at 0x0800_0000),
/// proof that our QEMU map was not used.
const DOWNSTREAM_FLASH: std::ops::Range<u32> = 0x0800_0000..0x0801_0000;

pub(crate) fn package() -> Result<(), String> {
    step("cargo publish --dry-run (the library package alone)");
    run(cargo().args([
        "publish",
        "--dry-run",
        "--allow-dirty",
        "--package",
        "scanline3d",
    ]))?;
    downstream()
}

/// The user-facing example crates: the RP2040 panel (built for thumbv6m, clippy as its
/// compiler) and the desktop window (clippy).
pub(crate) fn examples() -> Result<(), String> {
    step("example: RP2040 + ST7789 panel (builds; running needs the board)");
    for example in ["panel-rp2040", "window"] {
        let manifest = root().join(format!("examples/{example}/Cargo.toml"));
        run(cargo()
            .args(["fmt", "--check", "--manifest-path"])
            .arg(manifest))?;
    }
    // One build that is also the clippy pass: clippy-driver compiles the example crate itself
    // (RUSTC_WORKSPACE_WRAPPER, as `cargo clippy` sets it), so its dependencies are compiled
    // once, not once for checking and again for linking.
    let panel = root().join("examples/panel-rp2040/Cargo.toml");
    let examples_target = root().join("target/examples");
    run(cargo()
        .args([
            "build",
            "--release",
            "--target",
            "thumbv6m-none-eabi",
            "--manifest-path",
        ])
        .arg(&panel)
        .env("RUSTC_WORKSPACE_WRAPPER", "clippy-driver")
        .env(
            "CLIPPY_ARGS",
            "-D__CLIPPY_HACKERY__warnings__CLIPPY_HACKERY__",
        )
        .env("CARGO_TARGET_DIR", &examples_target))?;
    step("example: desktop window (without its SDL feature)");
    run(cargo()
        .args(["clippy", "--manifest-path"])
        .arg(root().join("examples/window/Cargo.toml"))
        .args(["--", "-D", "warnings"])
        .env("CARGO_TARGET_DIR", &examples_target))?;
    Ok(())
}

/// Copies `tests/downstream` out of the repository, points it at the packaged library and
/// builds it for thumbv6m with the minimum supported Rust; its entry point must lie in its own
/// flash.
fn downstream() -> Result<(), String> {
    step(&format!(
        "a downstream firmware crate on the packaged library, with its own memory.x, built with the minimum supported Rust ({MSRV})"
    ));
    let version = std::fs::read_to_string(root().join("Cargo.toml"))
        .map_err(|e| e.to_string())?
        .lines()
        .find_map(|l| l.strip_prefix("version = \""))
        .and_then(|v| v.strip_suffix('"'))
        .map(str::to_owned)
        .ok_or("no version in Cargo.toml")?;
    let package = root().join(format!("target/package/scanline3d-{version}"));
    let dir = std::env::temp_dir().join("scanline3d-downstream");
    let src = dir.join("src");
    std::fs::create_dir_all(&src).map_err(|e| e.to_string())?;
    let template = root().join("tests/downstream");
    for file in ["memory.x", "build.rs", "src/main.rs"] {
        std::fs::copy(template.join(file), dir.join(file)).map_err(|e| format!("{file}: {e}"))?;
    }
    let manifest = std::fs::read_to_string(template.join("Cargo.toml"))
        .map_err(|e| e.to_string())?
        .replace("SCANLINE3D_PACKAGE", &package.display().to_string());
    std::fs::write(dir.join("Cargo.toml"), manifest).map_err(|e| e.to_string())?;
    // The versions the workspace was tested with; the crates only the downstream uses resolve
    // afresh.
    std::fs::copy(root().join("Cargo.lock"), dir.join("Cargo.lock"))
        .map_err(|e| format!("Cargo.lock: {e}"))?;
    let status = Command::new("rustup")
        .args(["run", MSRV, "cargo", "build", "--release"])
        .args(["--target", "thumbv6m-none-eabi"])
        .current_dir(&dir)
        .env_remove("CARGO_TARGET_DIR")
        .env_remove("RUSTUP_TOOLCHAIN")
        .env_remove("RUSTC")
        .env_remove("CARGO")
        .status()
        .map_err(|e| e.to_string())?;
    if !status.success() {
        return Err(format!(
            "downstream build in {} failed ({status})",
            dir.display()
        ));
    }
    let elf = dir.join("target/thumbv6m-none-eabi/release/downstream");
    let entry = elf_entry(&elf)?;
    if !DOWNSTREAM_FLASH.contains(&entry) {
        return Err(format!(
            "downstream entry point {entry:#010x} is outside its own flash {DOWNSTREAM_FLASH:#x?}"
        ));
    }
    println!("downstream links at its own flash: entry {entry:#010x}");
    Ok(())
}

/// The entry point of an ELF32 file.
fn elf_entry(path: &std::path::Path) -> Result<u32, String> {
    let d = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    match (d.get(..5), d.get(0x18..0x1c)) {
        (Some(b"\x7fELF\x01"), Some(&[a, b, c, e])) => Ok(u32::from_le_bytes([a, b, c, e])),
        _ => Err(format!("{}: not an ELF32 file", path.display())),
    }
}
