//! Project tasks, one module per command. `cargo xtask test` is the one test command (README,
//! `.ci/run`): it installs what it needs on a fresh machine, then checks formatting, lints,
//! tests (debug with overflow checks, and release), the package, the bare-metal builds, the
//! firmware under QEMU and fuzzes scene input.

use std::io::{BufRead, BufReader};
use std::process::{Command, ExitCode, Stdio};

mod firmware;
mod fuzz;
mod hsr_table;
mod install;
mod lean;
mod package;
mod peers;
mod profile;
mod test;
mod tradeoff;

use firmware::*;
use fuzz::*;
use hsr_table::*;
use install::*;
use lean::*;
use package::*;
use peers::*;
use test::*;

pub(crate) const TARGETS: [&str; 3] = [
    "thumbv6m-none-eabi",
    "thumbv7em-none-eabihf",
    "riscv32imc-unknown-none-elf",
];

pub(crate) fn root() -> std::path::PathBuf {
    let manifest = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    manifest
        .parent()
        .map(|p| p.to_path_buf())
        .unwrap_or(manifest)
}

/// When the xtask started: each step prints the time since, so a long run shows where it is.
static START: std::sync::OnceLock<std::time::Instant> = std::sync::OnceLock::new();

pub(crate) fn step(name: &str) {
    let t = START
        .get_or_init(std::time::Instant::now)
        .elapsed()
        .as_secs();
    println!("\n== xtask [{}:{:02}]: {name}", t / 60, t % 60);
}

pub(crate) fn run(cmd: &mut Command) -> Result<(), String> {
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

pub(crate) fn cargo() -> Command {
    Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
}

/// The `key value` pairs of a line such as `hsr method span-zbuffer polygons 100 ...`.
pub(crate) fn fields(line: &str) -> std::collections::HashMap<&str, &str> {
    let words: Vec<&str> = line.split_whitespace().skip(1).collect();
    words
        .chunks(2)
        .filter(|w| w.len() == 2)
        .map(|w| (w[0], w[1]))
        .collect()
}

/// Mean time (ns) of criterion benchmark `group/function/parameter` from the last run.
pub(crate) fn criterion_mean_ns_of(group: &str, function: &str, parameter: &str) -> Option<f64> {
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| root().join("target"));
    // Criterion replaces characters it does not allow in directory names ("band:16").
    let dir = function.replace(':', "_");
    let path = target.join(format!(
        "criterion/{group}/{dir}/{parameter}/new/estimates.json"
    ));
    let json = std::fs::read_to_string(path).ok()?;
    let mean = &json[json.find("\"mean\"")?..];
    let value = &mean[mean.find("\"point_estimate\":")? + "\"point_estimate\":".len()..];
    let end = value.find([',', '}'])?;
    value[..end].trim().parse().ok()
}

/// The host's CPU model (for the tables' headers).
pub(crate) fn host_cpu() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines().find_map(|l| {
                l.strip_prefix("model name")
                    .map(|v| v.trim_start_matches([' ', '\t', ':']).to_owned())
            })
        })
        .unwrap_or_else(|| "unknown".into())
}

/// `n` with thousands separators, as the README writes figures.
pub(crate) fn thousands(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

pub(crate) fn first_line(cmd: &mut Command) -> String {
    cmd.output()
        .ok()
        .and_then(|o| {
            String::from_utf8_lossy(&o.stdout)
                .lines()
                .next()
                .map(str::to_owned)
        })
        .unwrap_or_else(|| "unknown".into())
}

fn main() -> ExitCode {
    START.get_or_init(std::time::Instant::now);
    let task = std::env::args().nth(1).unwrap_or_default();
    let result = match task.as_str() {
        "test" => test(),
        "firmware" => install().and_then(|_| firmware()),
        "lean" => install().and_then(|_| lean()),
        "package" => install().and_then(|_| package()),
        "peers" => peers(),
        // The trade table and, in the same command, the peers (`docs/peers.md`).
        "tradeoff" => install()
            .and_then(|_| tradeoff::tradeoff())
            .and_then(|_| peers()),
        "profile" => {
            let variant = std::env::args().nth(2).unwrap_or_else(|| "balanced".into());
            install().and_then(|_| profile::profile(&variant))
        }
        // The host renders build whole-frame workspaces (megabytes at 60,000 polygons) by value:
        // give them a thread with room for that.
        "hsr-table" => install().and_then(|_| {
            std::thread::Builder::new()
                .stack_size(512 << 20)
                .spawn(hsr_table)
                .map_err(|e| format!("cannot start the table thread: {e}"))?
                .join()
                .map_err(|_| "the table thread panicked".to_string())?
        }),
        "fuzz" => {
            let seconds = std::env::args()
                .nth(2)
                .and_then(|s| s.parse().ok())
                .unwrap_or(600);
            fuzz(seconds)
        }
        _ => {
            eprintln!(
                "usage: cargo xtask test | firmware | lean | package | hsr-table | peers | tradeoff | profile [VARIANT] | fuzz [SECONDS]"
            );
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
