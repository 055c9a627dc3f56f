//! `cargo xtask test`: the one test command (README, `.ci/run`).

use crate::*;

/// Environment that makes clippy-driver the compiler of the workspace's own crates, with
/// warnings denied (what `cargo clippy -- -D warnings` sets).
const CLIPPY_WRAPPER: &[(&str, &str)] = &[
    ("RUSTC_WORKSPACE_WRAPPER", "clippy-driver"),
    (
        "CLIPPY_ARGS",
        "-D__CLIPPY_HACKERY__warnings__CLIPPY_HACKERY__",
    ),
];

/// Runs `cargo test` with the given extra arguments and environment variables, echoing its
/// output and summing the per-binary "test result" lines.
fn cargo_test(extra: &[&str], env: &[(&str, &str)], totals: &mut (u64, u64)) -> Result<(), String> {
    let mut cmd = cargo();
    cmd.args(["test", "--workspace"])
        .args(extra)
        .envs(env.iter().copied())
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

/// The xtask built (with `host`) by the debug test run: the test command's second stage.
fn host_xtask() -> std::path::PathBuf {
    std::env::var_os("CARGO_TARGET_DIR")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| root().join("target"))
        .join("debug/xtask")
}

/// The test command's first stage, which needs no host renderer: format, lints, tests, the
/// package and every build. Its debug test run also builds the xtask with `host`, which then
/// runs the second stage ([`test_targets`]) on what was built.
pub(crate) fn test() -> Result<(), String> {
    install()?;
    // The instrumented fuzz build (its own workspace and target directory) runs in the
    // background from the start: test runs, single-threaded link steps and QEMU leave a core
    // free for it.
    step("fuzz target: AFL-instrumented build started in the background");
    let fuzz_build = start_fuzz_build()?;
    step("format");
    run(cargo().args(["fmt", "--all", "--", "--check"]))?;
    step("rustdoc (warnings denied: broken links, missing docs)");
    run(cargo()
        .args(["doc", "--package", "scanline3d", "--no-deps"])
        .env("RUSTDOCFLAGS", "-D warnings"))?;
    // One host test run, the strict one: overflow checks and debug assertions on. The release
    // semantics (both off) are those of the firmware built below, whose frame hashes must
    // equal these host renders on three targets; a release host run would compile the whole
    // workspace again to check little more (no `unsafe`: optimisation cannot change what safe
    // code computes). Clippy lints the workspace while the tests compile: clippy-driver is the
    // compiler of the workspace's crates there (as `cargo clippy` sets it), so the crate graph
    // is not checked once and built again. The benchmarks, which the tests do not build, are
    // then compiled the same way (their dependencies are the tests' dev-dependencies, built).
    // The xtask is built with `host` and `peers` here (for its `dispatch` test, and the peer
    // renderers' tests in sim/tests/peers.rs), and linted with them.
    let mut totals = (0, 0);
    step("tests, debug (overflow checks on), compiled through clippy (warnings denied)");
    cargo_test(&["--features", "xtask/peers"], CLIPPY_WRAPPER, &mut totals)?;
    step("benchmarks compiled through clippy (warnings denied), not run");
    cargo_test(
        &["--benches", "--no-run", "--features", "xtask/peers"],
        CLIPPY_WRAPPER,
        &mut totals,
    )?;
    step("the xtask without the host renderers, through clippy (warnings denied)");
    run(cargo()
        .args(["clippy", "--package", "xtask", "--", "-D", "warnings"])
        .env("CARGO_TARGET_DIR", root().join("target/xtask-lint")))?;
    // Link-time proof that the render path cannot panic: the panic_never example's panic
    // handler calls an undefined symbol, so the link fails if any panic is reachable. It also
    // builds the library for each target: no_std, no allocator. The firmware examples run below
    // are built here too, the three targets side by side.
    step("library for every target: no_std, the panic-never link check, the firmware examples");
    // The lean examples but the renderer-less baseline, which only `cargo xtask lean`'s size
    // table needs.
    let lean = LEAN_EXAMPLES.into_iter().filter(|e| *e != "lean_baseline");
    let examples: Vec<&str> = ["panic_never", "firmware", "trace", "metaball", "patch"]
        .into_iter()
        .chain(lean)
        .collect();
    build_firmware_examples("firmware", &examples)?;
    // The same proof for size-optimised builds (`opt-level = "z"`, the lean profile), which
    // leave closures out of line where the firmware profile inlines them and with them
    // bounds checks the firmware profile proves away. On ARMv6-M, the lean builds' target,
    // only: the three targets take 126 s of the test's 15-minute budget, one about a third.
    step("the panic-never link check again, size-optimised (the lean profile), thumbv6m");
    build_firmware_examples_on(&["thumbv6m-none-eabi"], "lean", &["panic_never"])?;
    package()?;
    finish_fuzz_build(fuzz_build)?;
    step("second stage: the firmware on QEMU against the host's renders, the examples, fuzzing");
    let elapsed = START.get().map_or(0, |s| s.elapsed().as_secs());
    run(Command::new(host_xtask())
        .arg("test-targets")
        .env(CLOCK_OFFSET, elapsed.to_string()))?;
    println!("\nxtask: {} passed, {} failed", totals.0, totals.1);
    Ok(())
}

/// The test command's second stage (`xtask test-targets`, with `host`): the firmware under
/// QEMU with its frame hashes checked against the host's renders, the example crates, and the
/// fuzzer.
#[cfg(feature = "host")]
pub(crate) fn test_targets() -> Result<(), String> {
    // The example crates compile (two jobs) while the firmware runs under QEMU, one core a
    // run, and then the fuzzer, which takes one core; their output interleaves. The lean
    // firmware was built with the `firmware` profile, whose dependencies were built: its hashes
    // are checked here, and `cargo xtask lean` builds it size-optimised for the flash and RAM
    // table.
    let example_builds = std::thread::spawn(examples);
    firmware()?;
    crate::trace::trace()?;
    crate::metaball::metaball()?;
    crate::patch::patch()?;
    lean_runs("firmware", false)?;
    fuzz_built(FUZZ_SECONDS_IN_TEST)?;
    example_builds
        .join()
        .map_err(|_| "the example build thread panicked".to_string())??;
    Ok(())
}
