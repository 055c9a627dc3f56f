//! The xtask's command line: an unknown or missing command prints the usage and exits with
//! status 2.

use std::process::Command;

fn xtask(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_xtask"))
        .args(args)
        .output()
        .expect("the xtask binary runs")
}

#[test]
fn unknown_or_missing_command_prints_usage() {
    for args in [&[][..], &["no-such-command"][..]] {
        let out = xtask(args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            stderr.starts_with("usage: cargo xtask test | package |"),
            "{stderr}"
        );
    }
}
