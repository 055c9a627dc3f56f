//! Project tasks. `cargo xtask test` is the one test command (README, `.ci/run`): it installs
//! what it needs on a fresh machine, then checks formatting, lints, tests (debug with overflow
//! checks, and release) and the bare-metal library builds.

use std::io::{BufRead, BufReader};
use std::process::{Command, ExitCode, Stdio};

const TARGETS: [&str; 3] = [
    "thumbv6m-none-eabi",
    "thumbv7em-none-eabihf",
    "riscv32imc-unknown-none-elf",
];

fn root() -> std::path::PathBuf {
    let manifest = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    manifest
        .parent()
        .map(|p| p.to_path_buf())
        .unwrap_or(manifest)
}

fn step(name: &str) {
    println!("\n== xtask: {name}");
}

fn run(cmd: &mut Command) -> Result<(), String> {
    let shown = format!("{cmd:?}");
    let status = cmd
        .current_dir(root())
        .status()
        .map_err(|e| format!("{shown}: {e}"))?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("{shown} failed ({status})"))
    }
}

fn cargo() -> Command {
    Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
}

/// Runs `cargo test` with the given extra arguments, echoing its output and summing the
/// per-binary "test result" lines.
fn cargo_test(extra: &[&str], totals: &mut (u64, u64)) -> Result<(), String> {
    let mut cmd = cargo();
    cmd.args(["test", "--workspace"])
        .args(extra)
        .current_dir(root());
    cmd.stdout(Stdio::piped());
    let shown = format!("{cmd:?}");
    let mut child = cmd.spawn().map_err(|e| format!("{shown}: {e}"))?;
    if let Some(out) = child.stdout.take() {
        for line in BufReader::new(out).lines().map_while(Result::ok) {
            println!("{line}");
            if let Some(rest) = line.strip_prefix("test result: ") {
                let count = |word: &str| {
                    rest.split(';')
                        .find_map(|part| {
                            part.trim().strip_suffix(word).map(|n| {
                                n.trim()
                                    .trim_start_matches("ok. ")
                                    .trim_start_matches("FAILED. ")
                                    .to_string()
                            })
                        })
                        .and_then(|n| n.parse::<u64>().ok())
                        .unwrap_or(0)
                };
                totals.0 += count(" passed");
                totals.1 += count(" failed");
            }
        }
    }
    let status = child.wait().map_err(|e| format!("{shown}: {e}"))?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("{shown} failed ({status})"))
    }
}

fn install() -> Result<(), String> {
    step("install rustup targets and components (no-op when present)");
    run(Command::new("rustup").args(["target", "add"]).args(TARGETS))?;
    run(Command::new("rustup").args(["component", "add", "rustfmt", "clippy"]))
}

fn test() -> Result<(), String> {
    install()?;
    step("format");
    run(cargo().args(["fmt", "--all", "--", "--check"]))?;
    step("clippy (warnings denied)");
    run(cargo().args([
        "clippy",
        "--workspace",
        "--all-targets",
        "--",
        "-D",
        "warnings",
    ]))?;
    let mut totals = (0, 0);
    step("tests, debug (overflow checks on)");
    cargo_test(&[], &mut totals)?;
    step("tests, release");
    cargo_test(&["--release"], &mut totals)?;
    for target in TARGETS {
        step(&format!("library for {target} (no_std, no allocator)"));
        run(cargo().args([
            "build",
            "--release",
            "--lib",
            "--package",
            "scanline3d",
            "--target",
            target,
        ]))?;
    }
    println!("\nxtask: {} passed, {} failed", totals.0, totals.1);
    Ok(())
}

fn main() -> ExitCode {
    let task = std::env::args().nth(1).unwrap_or_default();
    let result = match task.as_str() {
        "test" => test(),
        _ => {
            eprintln!("usage: cargo xtask test");
            return ExitCode::from(2);
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("xtask: {e}");
            ExitCode::FAILURE
        }
    }
}
