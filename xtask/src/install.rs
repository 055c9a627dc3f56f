//! `install`: the rustup targets and components, QEMU and the other tools the test command needs.

use crate::*;

pub(crate) fn install() -> Result<(), String> {
    step("install rustup targets and components (no-op when present)");
    run(Command::new("rustup").args(["target", "add"]).args(TARGETS))?;
    run(Command::new("rustup").args(["component", "add", "rustfmt", "clippy"]))?;
    step("install QEMU for the firmware runs (no-op when present)");
    let have_qemu = Command::new("qemu-system-arm")
        .arg("--version")
        .stdout(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if !have_qemu {
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
    Ok(())
}
