//! Project tasks, one module per command. `cargo xtask test` is the one test command (README,
//! `.ci/run`): it installs what it needs on a fresh machine, then checks formatting, lints,
//! tests (debug with overflow checks, and release), the package, the bare-metal builds, the
//! firmware under QEMU and fuzzes scene input.

use std::io::{BufRead, BufReader};
use std::process::{Command, ExitCode, Stdio};

mod firmware_build;
mod fuzz;
mod install;
mod package;
mod test;

/// Declares modules compiled only with the `host` feature: the commands that render on the host
/// (see Cargo.toml).
macro_rules! host_modules {
    ($($module:ident),*) => { $( #[cfg(feature = "host")] mod $module; )* };
}
host_modules!(
    firmware, hsr_table, lean, metaball, patch, peers, profile, report, speed, trace, tradeoff
);

use firmware_build::*;
use fuzz::*;
use install::*;
use package::*;
use test::*;
#[cfg(feature = "host")]
use {firmware::*, hsr_table::*, lean::*, peers::*, report::*};

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

/// Seconds the test command had run before it started this process (its second stage), so that
/// the steps' times continue the first stage's.
pub(crate) const CLOCK_OFFSET: &str = "XTASK_CLOCK_OFFSET";

pub(crate) fn step(name: &str) {
    let offset: u64 = std::env::var(CLOCK_OFFSET)
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(0);
    let t = offset
        + START
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

/// The commands compiled only with the `host` feature (see Cargo.toml), in the usage line's order.
#[cfg(not(feature = "host"))]
const HOST_TASKS: [&str; 15] = [
    "firmware",
    "trace",
    "metaball",
    "metaball-trade",
    "patch",
    "patch-trade",
    "lean",
    "flash",
    "hsr-table",
    "peers",
    "tradeoff",
    "profile",
    "scene-ram",
    "speed",
    "fuzz",
];

fn main() -> ExitCode {
    START.get_or_init(std::time::Instant::now);
    let task = std::env::args().nth(1).unwrap_or_default();
    let result = match task.as_str() {
        "test" => test(),
        "package" => install().and_then(|_| package()).and_then(|_| examples()),
        _ => match host_task(&task) {
            Some(result) => result,
            None => {
                eprintln!(
                    "usage: cargo xtask test | package | firmware | trace [alone] | metaball | metaball-trade | patch | patch-trade | lean | flash [TARGET] [VARIANT] | hsr-table | peers | tradeoff | profile [VARIANT [cache] [TARGET] [SCENE]] | profile trace [pure|hybrid] [TARGET] | profile patch [TARGET] | profile firmware [TARGET] (each profile [--blocks PATTERN]) | scene-ram SCENE [TARGET...] | speed [before|after|doc] | fuzz [SECONDS]"
                );
                return ExitCode::from(2);
            }
        },
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("xtask: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Without the `host` feature: a host command runs the xtask again with it.
#[cfg(not(feature = "host"))]
fn host_task(task: &str) -> Option<Result<(), String>> {
    HOST_TASKS.contains(&task).then(|| {
        run(cargo()
            .args(["run", "--package", "xtask", "--features", "host", "--"])
            .args(std::env::args().skip(1)))
    })
}

/// The target named in `args` (a triple with `-none-` or `-unknown-`) and the first other
/// argument, each `default_*` when missing.
#[cfg(feature = "host")]
fn target_and_word<'a>(
    args: &'a [String],
    default_target: &'a str,
    default_word: &'a str,
) -> (&'a str, &'a str) {
    let target = args
        .iter()
        .find(|a| a.contains("-none-") || a.contains("-unknown-"))
        .map_or(default_target, String::as_str);
    let word = args
        .iter()
        .find(|a| a.as_str() != target)
        .map_or(default_word, String::as_str);
    (target, word)
}

/// `args` without `--blocks PATTERN` (the profile commands' option), and PATTERN.
#[cfg(feature = "host")]
fn blocks_option(mut args: Vec<String>) -> (Vec<String>, Option<String>) {
    let Some(at) = args.iter().position(|a| a == "--blocks") else {
        return (args, None);
    };
    let pattern = (at + 1 < args.len()).then(|| args.remove(at + 1));
    args.remove(at);
    (args, pattern)
}

/// The commands that render on the host; `test-targets` is the test command's second stage.
#[cfg(feature = "host")]
fn host_task(task: &str) -> Option<Result<(), String>> {
    let result = match task {
        "test-targets" => test_targets(),
        "firmware" => install().and_then(|_| firmware()),
        "trace" if std::env::args().nth(2).as_deref() == Some("alone") => {
            install().and_then(|_| trace::trace_alone())
        }
        "trace" => install().and_then(|_| trace::trace()),
        "lean" => install().and_then(|_| lean()),
        "flash" => {
            let args: Vec<String> = std::env::args().skip(2).collect();
            let (target, variant) = target_and_word(&args, "thumbv6m-none-eabi", "minimal");
            install().and_then(|_| profile::flash(target, variant))
        }
        "metaball" => install().and_then(|_| metaball::metaball()),
        "patch" => install().and_then(|_| patch::patch()),
        "metaball-trade" => install().and_then(|_| metaball::metaball_trade()),
        "patch-trade" => install().and_then(|_| patch::patch_trade()),
        "peers" => peers(),
        // The trade table and, in the same command, the peers (`docs/peers.md`).
        "tradeoff" => install()
            .and_then(|_| tradeoff::tradeoff())
            .and_then(|_| peers()),
        "speed" => {
            let label = std::env::args().nth(2).unwrap_or_else(|| "after".into());
            install().and_then(|_| speed::speed(&label))
        }
        "profile" if std::env::args().nth(2).as_deref() == Some("trace") => {
            let (rest, blocks) = blocks_option(std::env::args().skip(3).collect());
            let (target, mode) = target_and_word(&rest, "thumbv7em-none-eabihf", "pure");
            install().and_then(|_| profile::profile_trace(mode, target, blocks.as_deref()))
        }
        "profile" if std::env::args().nth(2).as_deref() == Some("firmware") => {
            let (rest, blocks) = blocks_option(std::env::args().skip(3).collect());
            let target = rest.first().map_or("thumbv7em-none-eabihf", String::as_str);
            install().and_then(|_| profile::profile_firmware(target, blocks.as_deref()))
        }
        "profile" if std::env::args().nth(2).as_deref() == Some("patch") => {
            let (rest, blocks) = blocks_option(std::env::args().skip(3).collect());
            let target = rest.first().map_or("thumbv7em-none-eabihf", String::as_str);
            install().and_then(|_| profile::profile_patch(target, blocks.as_deref()))
        }
        "profile" => {
            let (args, blocks) = blocks_option(std::env::args().skip(2).collect());
            let variant = args.first().cloned().unwrap_or_else(|| "balanced".into());
            let rest = args.get(1..).unwrap_or_default();
            let cache = rest.iter().any(|a| a == "cache");
            let target = rest
                .iter()
                .find(|a| a.contains("-none-") || a.contains("-unknown-"))
                .map_or(profile::DEFAULT_TARGET, String::as_str);
            let scene = rest
                .iter()
                .find(|a| *a != "cache" && a.as_str() != target)
                .map(String::as_str);
            install()
                .and_then(|_| profile::profile(&variant, cache, target, scene, blocks.as_deref()))
        }
        "scene-ram" => {
            let args: Vec<String> = std::env::args().skip(2).collect();
            let named: Vec<&str> = args
                .iter()
                .filter(|a| a.contains("-none-") || a.contains("-unknown-"))
                .map(String::as_str)
                .collect();
            let targets = if named.is_empty() {
                FIRMWARE.map(|(t, _)| t).to_vec()
            } else {
                named
            };
            match args.iter().find(|a| !targets.contains(&a.as_str())) {
                Some(scene) => install().and_then(|_| profile::scene_ram(scene, &targets)),
                None => Err("scene-ram: name a corpus scene (icosphere, heightfield, ...)".into()),
            }
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
        _ => return None,
    };
    Some(result)
}
