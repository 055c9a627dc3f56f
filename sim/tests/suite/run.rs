//! Running the `sim` binary from the tests: its exit status and output, and a scratch
//! directory per test.

use std::path::{Path, PathBuf};
use std::process::Command;

/// Runs `sim` with `args` in `dir`: (exit status, stdout, stderr).
pub fn sim(args: &[&str], dir: &Path) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_sim"))
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

/// A fresh directory for the test named `name` (unique across the suite).
pub fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("scanline3d-sim-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}
