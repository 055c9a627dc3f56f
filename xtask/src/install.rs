//! `install`: the rustup targets and components, QEMU and the other tools the test command needs.

use crate::*;

pub(crate) fn install() -> Result<(), String> {
    step("install rustup targets and components (no-op when present)");
    run(Command::new("rustup").args(["target", "add"]).args(TARGETS))?;
    run(Command::new("rustup").args(["component", "add", "rustfmt", "clippy"]))?;
    step(&format!(
        "install the minimum supported Rust ({MSRV}) with thumbv6m-none-eabi (no-op when present)"
    ));
    run(Command::new("rustup").args(["toolchain", "install", MSRV, "--profile", "minimal"]))?;
    run(Command::new("rustup").args(["target", "add", "--toolchain", MSRV, "thumbv6m-none-eabi"]))?;
    step("install QEMU for the firmware runs (no-op when present)");
    // Each emulator the firmware runs need, checked on its own: a machine may have one package
    // (qemu-system-arm) without the other (qemu-system-misc, which holds RISC-V).
    let missing: Vec<&str> = ["qemu-system-arm", "qemu-system-riscv32"]
        .into_iter()
        .filter(|tool| {
            !Command::new(tool)
                .arg("--version")
                .stdout(Stdio::null())
                .status()
                .is_ok_and(|s| s.success())
        })
        .collect();
    if !missing.is_empty() {
        println!("missing: {}", missing.join(", "));
        let root = Command::new("id")
            .arg("-u")
            .output()
            .map(|o| o.stdout == b"0\n")
            .unwrap_or(false);
        let apt = |args: &[&str]| {
            let mut cmd = if root {
                Command::new("apt-get")
            } else {
                let mut c = Command::new("sudo");
                c.arg("apt-get");
                c
            };
            cmd.args(args).env("DEBIAN_FRONTEND", "noninteractive");
            cmd
        };
        run(&mut apt(&["update", "-qq"]))?;
        let install = [
            "install",
            "-y",
            "-qq",
            "qemu-system-arm",
            "qemu-system-misc",
        ];
        if run(&mut apt(&install)).is_err() {
            // Some images carry a newer qemu-utils (from backports) that breaks the release's
            // qemu-system-common: take the release's own qemu-utils with it.
            let codename = std::fs::read_to_string("/etc/os-release")
                .ok()
                .and_then(|s| {
                    s.lines()
                        .find_map(|l| l.strip_prefix("VERSION_CODENAME=").map(str::to_owned))
                })
                .unwrap_or_else(|| "stable".to_owned());
            let utils = format!("qemu-utils/{codename}");
            run(&mut apt(
                &[&install[..], &["--allow-downgrades", &utils]].concat()
            ))?;
        }
    }
    step("install cargo-afl for the fuzzing step (no-op when present)");
    let have_afl = cargo()
        .args(["afl", "--version"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if !have_afl {
        run(cargo().args(["install", "cargo-afl", "--version", "0.18.2", "--locked"]))?;
    }
    Ok(())
}
