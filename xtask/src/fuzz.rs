//! `cargo xtask fuzz SECONDS`: coverage-guided fuzzing of scene input.

use crate::*;

/// Length of the bounded fuzzing session inside `cargo xtask test`.
#[cfg(feature = "host")]
pub(crate) const FUZZ_SECONDS_IN_TEST: u32 = 60;

/// Coverage-guided fuzzing of scene/OBJ input with AFL++ (`cargo afl`, stable Rust) for
/// `seconds`, seeded with the corpus. Fails on any crash or hang.
#[cfg(feature = "host")]
pub(crate) fn fuzz(seconds: u32) -> Result<(), String> {
    finish_fuzz_build(start_fuzz_build()?)?;
    fuzz_built(seconds)
}

/// Starts building the AFL-instrumented fuzz target in the background (its own workspace and
/// target directory, so it runs beside other builds; output in `target/fuzz-build.log`).
pub(crate) fn start_fuzz_build() -> Result<std::process::Child, String> {
    // Builds AFL++'s runtime for this rustc once; it refuses (harmlessly) when already built.
    let _ = cargo()
        .args(["afl", "config", "--build"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status();
    std::fs::create_dir_all(root().join("target")).map_err(|e| e.to_string())?;
    let log = std::fs::File::create(root().join("target/fuzz-build.log"))
        .map_err(|e| format!("target/fuzz-build.log: {e}"))?;
    let err = log.try_clone().map_err(|e| e.to_string())?;
    cargo()
        .args([
            "afl",
            "build",
            "--release",
            "--locked",
            "--manifest-path",
            "fuzz/Cargo.toml",
        ])
        // cargo-afl compiles every crate as one codegen unit with coverage instrumentation;
        // at its default opt-level 3 the sim crate alone takes minutes. Level 1 builds several
        // times faster and still executes thousands of inputs per second.
        .env("AFL_OPT_LEVEL", "1")
        .current_dir(root())
        .stdout(log)
        .stderr(err)
        .spawn()
        .map_err(|e| format!("cargo afl build: {e}"))
}

/// Waits for the fuzz target `build` started, and shows its log if it failed.
pub(crate) fn finish_fuzz_build(mut build: std::process::Child) -> Result<(), String> {
    let status = build.wait().map_err(|e| format!("cargo afl build: {e}"))?;
    if status.success() {
        Ok(())
    } else {
        let log = std::fs::read_to_string(root().join("target/fuzz-build.log")).unwrap_or_default();
        Err(format!("cargo afl build failed ({status}):\n{log}"))
    }
}

/// Fuzzes the built fuzz target for `seconds`, seeded with the corpus.
#[cfg(feature = "host")]
pub(crate) fn fuzz_built(seconds: u32) -> Result<(), String> {
    step(&format!(
        "fuzz scene input for {seconds} s (AFL++ via cargo afl)"
    ));
    let dir = root().join("target/fuzz");
    let _ = std::fs::remove_dir_all(&dir);
    let seeds = dir.join("seeds");
    std::fs::create_dir_all(&seeds).map_err(|e| e.to_string())?;
    for (i, seed) in scanline3d_sim::fuzz::seeds().iter().enumerate() {
        std::fs::write(seeds.join(format!("seed{i}")), seed).map_err(|e| e.to_string())?;
    }
    let binary = root().join("fuzz/target/release/scanline3d-fuzz");
    let out = dir.join("out");
    run(cargo()
        .args(["afl", "fuzz", "-i"])
        .arg(&seeds)
        .arg("-o")
        .arg(&out)
        .args(["-V", &seconds.to_string()])
        .arg(&binary)
        .env("AFL_NO_UI", "1")
        .env("AFL_SKIP_CPUFREQ", "1")
        .env("AFL_I_DONT_CARE_ABOUT_MISSING_CRASHES", "1")
        .stdout(Stdio::null()))?;
    let stats = std::fs::read_to_string(out.join("default/fuzzer_stats"))
        .map_err(|e| format!("fuzzer_stats: {e}"))?;
    let field = |name: &str| {
        stats
            .lines()
            .find_map(|l| {
                l.split_once(':')
                    .filter(|(k, _)| k.trim() == name)
                    .map(|(_, v)| v.trim().to_string())
            })
            .unwrap_or_default()
    };
    println!(
        "fuzz: {} executions in {} s ({} per second), {} paths, coverage {}, {} crashes, {} hangs",
        field("execs_done"),
        seconds,
        field("execs_per_sec"),
        field("corpus_count"),
        field("bitmap_cvg"),
        field("saved_crashes"),
        field("saved_hangs")
    );
    if field("saved_crashes") != "0" || field("saved_hangs") != "0" {
        return Err(format!(
            "fuzzing found crashes or hangs: see {}",
            out.join("default").display()
        ));
    }
    Ok(())
}
