//! Building the firmware examples for every target: what the test command's first stage needs
//! of the firmware, without the host renderers (`cargo xtask firmware` and the others run them).

use crate::*;

/// The package of the QEMU firmware images (`firmware/`).
pub(crate) const FIRMWARE_PACKAGE: &str = "scanline3d-firmware";

/// A firmware target and the QEMU machine its runner uses (see `.cargo/config.toml`).
pub(crate) const FIRMWARE: [(&str, &str); 3] = [
    ("thumbv7em-none-eabihf", "mps2-an386 (Cortex-M4F)"),
    (
        "thumbv6m-none-eabi",
        "mps2-an385 (Cortex-M3 running v6-M code)",
    ),
    ("riscv32imc-unknown-none-elf", "virt (RV32IMC)"),
];

/// The cargo target directory of the `cargo xtask test` firmware builds for `target`: one per
/// target, so that the three targets build side by side. (One cargo invocation for several
/// targets would unify the features of their target-specific dependencies, such as
/// critical-section's restore state.)
pub(crate) fn firmware_target_dir(target: &str) -> std::path::PathBuf {
    root().join("target/firmware-builds").join(target)
}

/// The lean firmware examples, as `cargo build --example` names them.
pub(crate) const LEAN_EXAMPLES: [&str; 5] = [
    "lean_bsp",
    "lean_minimal",
    "lean_minimal_baked",
    "lean_full",
    "lean_baseline",
];

/// Builds firmware examples with `profile` for every target, the targets in parallel: each
/// build ends in a single-threaded link-time optimisation, so one cargo per target keeps both
/// cores busy. Each build's output goes to a log beside its target directory, shown if it fails.
pub(crate) fn build_firmware_examples(profile: &str, examples: &[&str]) -> Result<(), String> {
    build_firmware_examples_on(&FIRMWARE.map(|(target, _)| target), profile, examples)
}

/// [`build_firmware_examples`] for some of the targets.
pub(crate) fn build_firmware_examples_on(
    targets: &[&str],
    profile: &str,
    examples: &[&str],
) -> Result<(), String> {
    let started = std::time::Instant::now();
    let mut builds = Vec::new();
    for &target in targets {
        let dir = firmware_target_dir(target);
        std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        let log_path = dir.with_extension("log");
        let log =
            std::fs::File::create(&log_path).map_err(|e| format!("{}: {e}", log_path.display()))?;
        let err = log.try_clone().map_err(|e| e.to_string())?;
        let mut cmd = cargo();
        cmd.args(["build", "--package", FIRMWARE_PACKAGE, "--profile", profile]);
        for example in examples {
            cmd.args(["--example", example]);
        }
        cmd.args(["--target", target])
            .env("CARGO_TARGET_DIR", &dir)
            .current_dir(root())
            .stdout(log)
            .stderr(err);
        let child = cmd.spawn().map_err(|e| format!("cargo build: {e}"))?;
        builds.push((target, log_path, child));
    }
    let mut failed = Vec::new();
    for (target, log_path, mut child) in builds {
        let status = child.wait().map_err(|e| format!("cargo build: {e}"))?;
        println!(
            "{target}: {} built with profile {profile} ({status}) after {} s",
            examples.join(", "),
            started.elapsed().as_secs()
        );
        if !status.success() {
            let log = std::fs::read_to_string(&log_path).unwrap_or_default();
            println!("{log}");
            failed.push(target);
        }
    }
    if failed.is_empty() {
        Ok(())
    } else {
        Err(format!("firmware build failed for {}", failed.join(", ")))
    }
}
