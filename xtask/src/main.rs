//! Project tasks. `cargo xtask test` is the one test command (README, `.ci/run`): it installs
//! what it needs on a fresh machine, then checks formatting, lints, tests (debug with overflow
//! checks, and release) and the bare-metal library builds.

use std::io::{BufRead, BufReader};
use std::process::{Command, ExitCode, Stdio};

mod profile;
mod tradeoff;

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

/// The package of the QEMU firmware images (`firmware/`).
const FIRMWARE_PACKAGE: &str = "scanline3d-firmware";

/// A firmware target and the QEMU machine its runner uses (see `.cargo/config.toml`).
const FIRMWARE: [(&str, &str); 3] = [
    ("thumbv7em-none-eabihf", "mps2-an386 (Cortex-M4F)"),
    (
        "thumbv6m-none-eabi",
        "mps2-an385 (Cortex-M3 running v6-M code)",
    ),
    ("riscv32imc-unknown-none-elf", "virt (RV32IMC)"),
];

/// Runs a firmware example on one target under QEMU (the runner in `.cargo/config.toml`)
/// with the given cargo profile, and returns its output.
fn run_example(target: &str, profile: &str, example: &str) -> Result<String, String> {
    let out = cargo()
        .args(["run", "--package", FIRMWARE_PACKAGE, "--profile", profile])
        .args(["--example", example])
        .args(["--target", target])
        .current_dir(root())
        .stderr(Stdio::inherit())
        .output()
        .map_err(|e| format!("{example} on {target}: {e}"))?;
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    if !out.status.success() {
        return Err(format!(
            "{example} on {target} failed ({}):\n{text}",
            out.status
        ));
    }
    Ok(text)
}

/// Frame hashes the host computes for the demo orbit, through the same code as the firmware.
fn host_hashes() -> Result<Vec<u32>, String> {
    use scanline3d_demo as demo;
    let mut ws = Box::new(demo::PanelWorkspace::new(demo::BACKGROUND.into()));
    let instances = demo::instances();
    (0..demo::ORBIT_FRAMES)
        .map(|frame| {
            let scene =
                demo::scene(&instances, frame, demo::ORBIT_FRAMES).map_err(|e| e.to_string())?;
            demo::render_panel_frame(&mut ws, &scene)
                .map(|f| f.hash)
                .map_err(|e| e.to_string())
        })
        .collect()
}

fn firmware() -> Result<(), String> {
    let expected = host_hashes()?;
    for (target, machine) in FIRMWARE {
        step(&format!("firmware on QEMU {machine}, {target}"));
        let first = run_example(target, "firmware", "firmware")?;
        print!("{first}");
        let second = run_example(target, "firmware", "firmware")?;
        if first != second {
            return Err(format!("{target}: two runs printed different output (instruction counts must be deterministic)\n{second}"));
        }
        println!("(second run printed identical output: counts are deterministic)");
        let hashes: Vec<u32> = first
            .lines()
            .filter_map(|l| l.strip_prefix("frame "))
            .filter_map(|l| {
                l.split_whitespace()
                    .nth(2)
                    .and_then(|h| u32::from_str_radix(h, 16).ok())
            })
            .collect();
        if hashes != expected {
            return Err(format!(
                "{target}: frame hashes {hashes:08x?} differ from the host's {expected:08x?}"
            ));
        }
        println!("frame hashes equal the host's: {expected:08x?}");
        sizes(target, &first)?;
        vertex_cache_on_target(target, &first, &expected)?;
    }
    Ok(())
}

/// The hashes of the `frame N hash H ...` lines of firmware output.
fn frame_hashes(output: &str) -> Vec<u32> {
    hashes_of_lines(output, "frame ")
}

/// Mean instructions per frame over the `frame` lines of firmware output.
fn mean_frame_instructions(output: &str) -> f64 {
    let counts: Vec<u64> = output
        .lines()
        .filter_map(|l| l.strip_prefix("frame "))
        .filter_map(|l| {
            let w: Vec<&str> = l.split_whitespace().collect();
            w.windows(2)
                .find(|p| p[0] == "instructions")
                .and_then(|p| p[1].parse().ok())
        })
        .collect();
    counts.iter().sum::<u64>() as f64 / counts.len().max(1) as f64
}

/// The demo firmware again with a vertex cache holding every demo vertex (`--cfg
/// scanline3d_vertex_cache`): the frames must hash the same; prints its cost against the
/// uncached run `uncached` (firmware output) and its renderer RAM.
fn vertex_cache_on_target(target: &str, uncached: &str, expected: &[u32]) -> Result<(), String> {
    step(&format!("firmware with a vertex cache, {target}"));
    run(cargo()
        .args(["rustc", "--package", FIRMWARE_PACKAGE, "--profile", "firmware"])
        .args(["--example", "firmware"])
        .args(["--target", target, "--", "--cfg", "scanline3d_vertex_cache"]))?;
    let elf = root()
        .join("target")
        .join(target)
        .join("firmware/examples/firmware");
    let out = tradeoff::run_on_qemu_with(target, &elf, &[])?;
    let hashes = frame_hashes(&out);
    if hashes != expected {
        return Err(format!(
            "{target} with a vertex cache: frame hashes {hashes:08x?} differ from the host's {expected:08x?}"
        ));
    }
    let (plain, cached) = (
        mean_frame_instructions(uncached),
        mean_frame_instructions(&out),
    );
    println!(
        "vertex cache: the same hashes; {:.2} M instructions per frame against {:.2} M ({:.2}× fewer); renderer RAM {} B against {} B",
        cached / 1e6,
        plain / 1e6,
        plain / cached.max(1.0),
        summary_field(&out, "renderer_ram"),
        summary_field(uncached, "renderer_ram")
    );
    Ok(())
}

/// The lean firmware variants (`firmware/examples/lean_*.rs`), built with the size-optimised `lean`
/// profile.
const LEAN_VARIANTS: [&str; 3] = ["minimal", "full", "baseline"];
/// The scene the lean firmware was exported from, and how many views it was analysed from.
const LEAN_OBJ: &str = "firmware/examples/lean/icosphere80.obj";
const LEAN_VIEWS: usize = 8;
/// The scene of the lean BSP build (`firmware/examples/lean_bsp.rs`), exported with
/// `sim export sim/corpus/cyclic.obj --views 8 --no-cull --bsp`.
const LEAN_BSP_OBJ: &str = "sim/corpus/cyclic.obj";

/// Flash (vector table, code, read-only data, initialised data) of an ELF.
fn flash_bytes(path: &std::path::Path) -> Result<u64, String> {
    let e = elf(path)?;
    Ok(e.sections
        .iter()
        .filter(|s| [".vector_table", ".text", ".rodata", ".data"].contains(&s.0.as_str()))
        .map(|s| s.1 as u64)
        .sum())
}

fn summary_field(output: &str, name: &str) -> u64 {
    output
        .lines()
        .find_map(|l| l.strip_prefix("summary "))
        .and_then(|l| {
            let words: Vec<&str> = l.split_whitespace().collect();
            words
                .windows(2)
                .find(|w| w[0] == name)
                .and_then(|w| w[1].parse().ok())
        })
        .unwrap_or(0)
}

/// The lean firmware on every target: frame hashes must equal the host's render of the OBJ the
/// scene was exported from; then flash and RAM of the minimal and full builds, with the
/// renderer's share measured against the renderer-less baseline.
fn lean() -> Result<(), String> {
    use scanline3d_sim::scene::{MeshData, SceneSpec};
    let mesh = MeshData::load_obj(&root().join(LEAN_OBJ))?;
    let base = SceneSpec::single(
        mesh,
        scanline3d_sim::scene::CameraSpec::looking_at([0.0, 0.0, 1.0], [0.0; 3], 50.0, 0.1, 10.0),
        Default::default(),
        true,
    );
    let expected = scanline3d_sim::analyze::default_views(&base, LEAN_VIEWS)?
        .into_iter()
        .map(|camera| {
            SceneSpec {
                camera,
                ..base.clone()
            }
            .panel_hash(240, 240)
        })
        .collect::<Result<Vec<u32>, String>>()?;
    let bsp_base = SceneSpec::single(
        MeshData::load_obj(&root().join(LEAN_BSP_OBJ))?,
        scanline3d_sim::scene::CameraSpec::looking_at([0.0, 0.0, 1.0], [0.0; 3], 50.0, 0.1, 10.0),
        Default::default(),
        false,
    );
    let bsp_expected = scanline3d_sim::analyze::default_views(&bsp_base, LEAN_VIEWS)?
        .into_iter()
        .map(|camera| {
            SceneSpec {
                camera,
                ..bsp_base.clone()
            }
            .panel_hash_with(240, 240, scanline3d_sim::scene::Algorithm::Bsp)
        })
        .collect::<Result<Vec<u32>, String>>()?;
    let mut table = Vec::new();
    let mut bsp_table = Vec::new();
    for (target, machine) in FIRMWARE {
        step(&format!("lean firmware (bsp) on QEMU {machine}, {target}"));
        let out = run_example(target, "lean", "lean_bsp")?;
        print!("{out}");
        if view_hashes(&out) != bsp_expected {
            return Err(format!(
                "lean_bsp on {target}: hashes {:08x?} differ from the host's BSP render of {LEAN_BSP_OBJ}: {bsp_expected:08x?}",
                view_hashes(&out)
            ));
        }
        println!("view hashes equal the host's BSP render of {LEAN_BSP_OBJ}");
        let elf_path = root()
            .join("target")
            .join(target)
            .join("lean/examples/lean_bsp");
        bsp_table.push(format!(
            "| {target} | {} | {} | {} |",
            flash_bytes(&elf_path)?,
            summary_field(&out, "workspace"),
            summary_field(&out, "peak_stack")
        ));
        let mut flash = std::collections::HashMap::new();
        for variant in LEAN_VARIANTS {
            step(&format!(
                "lean firmware ({variant}) on QEMU {machine}, {target}"
            ));
            let out = run_example(target, "lean", &format!("lean_{variant}"))?;
            print!("{out}");
            let hashes = view_hashes(&out);
            if variant != "baseline" {
                if hashes != expected {
                    return Err(format!("lean_{variant} on {target}: hashes {hashes:08x?} differ from the host render of {LEAN_OBJ}: {expected:08x?}"));
                }
                println!("view hashes equal the host render of {LEAN_OBJ}");
            }
            let elf_path = root()
                .join("target")
                .join(target)
                .join(format!("lean/examples/lean_{variant}"));
            flash.insert(variant, (flash_bytes(&elf_path)?, out));
        }
        let (base_flash, base_out) = &flash["baseline"];
        let base_stack = summary_field(base_out, "peak_stack");
        for variant in ["minimal", "full"] {
            let (f, out) = &flash[variant];
            let workspace = summary_field(out, "workspace");
            let stack = summary_field(out, "peak_stack");
            table.push(format!(
                "| {target} | {variant} | {f} | {} | {workspace} | {} |",
                f - base_flash,
                stack.saturating_sub(base_stack)
            ));
        }
    }
    println!("\nlean firmware, {LEAN_OBJ} (80 triangles), 240x240, `lean` profile (opt-level z):");
    println!("| target | build | firmware flash B | renderer flash B (minus baseline) | workspace B | render stack B (peak minus baseline) |");
    println!("|---|---|---|---|---|---|");
    for row in table {
        println!("{row}");
    }
    println!("\nlean BSP firmware, {LEAN_BSP_OBJ} (3 triangles, 7 after splitting), 240x240, `lean` profile:");
    println!("| target | firmware flash B | workspace B | peak stack B (workspace included) |");
    println!("|---|---|---|---|");
    for row in bsp_table {
        println!("{row}");
    }
    Ok(())
}

/// The hashes of the `view N hash H ...` lines of a lean firmware's output.
fn view_hashes(output: &str) -> Vec<u32> {
    hashes_of_lines(output, "view ")
}

/// The hashes (third word, hex) of the output lines starting with `prefix`.
fn hashes_of_lines(output: &str, prefix: &str) -> Vec<u32> {
    output
        .lines()
        .filter_map(|l| l.strip_prefix(prefix))
        .filter_map(|l| {
            l.split_whitespace()
                .nth(2)
                .and_then(|h| u32::from_str_radix(h, 16).ok())
        })
        .collect()
}

/// One (method, scene size) of the hidden-surface table, as the host computes it.
struct HsrHost {
    method: &'static str,
    polygons: usize,
    hash: u32,
    stats: scanline3d::FrameStats,
    /// Pixels showing a triangle.
    covered: usize,
    accuracy: scanline3d_sim::metrics::Metrics,
}

/// Renders every (method, level) of `scanline3d_sim::hsr` on the host: the frame hash through
/// the same panel model as the firmware, and an id/depth image compared with the f64 reference.
struct HsrHostRun {
    specs: Vec<scanline3d_sim::scene::SceneSpec>,
    references: Vec<(
        scanline3d_sim::reference::Scene,
        scanline3d_sim::reference::Image,
    )>,
    entries: Vec<HsrHost>,
}

impl scanline3d_sim::hsr::Visit for HsrHostRun {
    type Error = String;
    fn visit<M: scanline3d_sim::hsr::Method, const T: usize, const A: usize, const K: usize>(
        &mut self,
        level: usize,
    ) -> Result<(), String> {
        use embedded_graphics::pixelcolor::{Rgb565, RgbColor};
        use scanline3d::sink::{FnSink, HashSink, Row, TriangleId};
        use scanline3d_sim::hsr::{Resolve, HEIGHT, WIDTH};
        use scanline3d_sim::{metrics, reference::Image};
        let spec = &self.specs[level];
        let mut ws = Box::new(M::Ws::<Rgb565, T, A, K>::new(Rgb565::BLACK));
        let (hash, stats) = spec.with_scene(|scene| {
            let mut sink = HashSink::new();
            let stats = ws.frame(scene, &mut sink).map_err(|e| e.to_string())?;
            Ok::<_, String>((sink.hash(), stats))
        })??;
        if !stats.is_complete() {
            return Err(format!(
                "{} at level {level}: active list overflowed (raise hsr::LEVELS)",
                M::NAME
            ));
        }
        // The same frame as triangle ids and eye depth, for the comparison with the reference.
        let mut ids = Box::new(M::Ws::<TriangleId, T, A, K>::new(TriangleId::NONE));
        let mut image = Image {
            width: WIDTH,
            height: HEIGHT,
            ids: vec![-1; WIDTH * HEIGHT],
            depth: vec![f32::INFINITY; WIDTH * HEIGHT],
            color: vec![[0; 3]; WIDTH * HEIGHT],
        };
        spec.with_scene(|scene| {
            let mut sink = FnSink(|row: Row<'_, TriangleId>| {
                let start = row.y as usize * WIDTH;
                // Methods without depth memory send no depth: NaN over surfaces (not compared).
                for (x, id) in row.pixels.iter().enumerate() {
                    image.ids[start + x] = id.0;
                    image.depth[start + x] = match row.depth.get(x) {
                        Some(q) => scene.camera.eye_distance(q).unwrap_or(f32::INFINITY),
                        None if id.0 >= 0 => f32::NAN,
                        None => f32::INFINITY,
                    };
                }
                Ok::<(), std::convert::Infallible>(())
            });
            ids.frame(scene, &mut sink).map_err(|e| e.to_string())
        })??;
        let (reference, ref_image) = &self.references[level];
        let bound = metrics::ErrorBound {
            sub_bits: 4,
            max_model_coord: spec.max_model_coord(),
            focal_px: reference.camera.focal_px(HEIGHT),
            arithmetic: Default::default(),
        };
        self.entries.push(HsrHost {
            method: M::NAME,
            polygons: scanline3d_sim::hsr::LEVELS[level].polygons,
            hash,
            stats,
            covered: image.ids.iter().filter(|&&id| id >= 0).count(),
            accuracy: metrics::compare(&image, ref_image, reference, &bound),
        });
        Ok(())
    }
}

/// The `key value` pairs of a line such as `hsr method span-zbuffer polygons 100 ...`.
fn fields(line: &str) -> std::collections::HashMap<&str, &str> {
    let words: Vec<&str> = line.split_whitespace().skip(1).collect();
    words
        .chunks(2)
        .filter(|w| w.len() == 2)
        .map(|w| (w[0], w[1]))
        .collect()
}

/// Mean time per frame (ns) from a criterion run of `cargo bench --bench hsr`, if there is one.
fn criterion_mean_ns(method: &str, polygons: usize) -> Option<f64> {
    criterion_mean_ns_of("hsr", method, &polygons.to_string())
}

/// Mean time (ns) of criterion benchmark `group/function/parameter` from the last run.
fn criterion_mean_ns_of(group: &str, function: &str, parameter: &str) -> Option<f64> {
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
fn host_cpu() -> String {
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

#[cfg(feature = "peers")]
/// `cargo xtask peers`: ours against the peer renderers (`euc`, `embedded-3dgfx`) on the
/// corpus, time per frame from one criterion run (`cargo bench -p scanline3d-sim --features peers --bench peers`) and mismatch
/// against the f64 reference, into `docs/peers.md`.
fn peers() -> Result<(), String> {
    use scanline3d_sim::peers::{self, Peer};
    const SIZE: usize = 240;
    step("criterion: ours and the peers, every corpus scene (cargo bench --bench peers)");
    run(cargo().args(["bench", "--package", "scanline3d-sim", "--features", "peers"]).args(["--bench", "peers"]))?;
    step("ours and the peers against the f64 reference (every corpus scene and camera)");
    let rows = peers::corpus_table(SIZE, SIZE)?;
    let scenes: Vec<&str> = scanline3d_sim::corpus::all()
        .iter()
        .map(|s| s.name)
        .collect();
    let renderers = [
        "ours",
        "ours-cached",
        "ours-exact",
        "euc",
        "embedded-3dgfx",
        "embedded-3dgfx-1mesh",
    ];
    let mut md = String::new();
    let mut line = |s: String| {
        md.push_str(&s);
        md.push('\n');
    };
    line("# Ours against the peer renderers".into());
    line(String::new());
    line("Written by `cargo xtask peers` (also run by `cargo xtask tradeoff`); do not edit by hand. Every corpus scene at 240×240, rendered by".into());
    line(format!(
        "scanline3d's default (`Workspace`: span z-buffer, flat shading, 4 sub-pixel bits; also with a vertex cache, `VERTS` = 16384, which renders the same pixels, and with the `Exact` preset, 8 sub-pixel bits, our most accurate frame) and by the peers a user would otherwise pick: [`euc`](https://crates.io/crates/euc) {} and [`embedded-3dgfx`](https://crates.io/crates/embedded-3dgfx) {}. How the peers are driven (id images through per-triangle colours, cameras, what is set up once) is in `sim/src/peers.rs`.",
        peers::EUC_VERSION,
        peers::EMBEDDED_3DGFX_VERSION
    ));
    line(String::new());
    line(format!(
        "Host: {} ({}). Times: criterion means from `cargo bench -p scanline3d-sim --features peers --bench peers`, one run, camera 0 of each scene, each renderer writing a whole Rgb565 frame; ours also lights every face (Lambert), the peers draw flat colours.",
        host_cpu(),
        first_line(Command::new("rustc").arg("--version"))
    ));
    line(String::new());
    line("## Time per frame".into());
    line(String::new());
    line("Ratios = the peer's time / ours, then / ours with the vertex cache, then / ours with the `Exact` preset (above 1: ours is faster). The vertex cache (`scanline3d::cache`) costs 28 bytes per vertex and changes no pixel (`sim/tests/vertex_cache.rs`), so ours-cached has the accuracy of ours below. `embedded-3dgfx` draws one mesh per triangle, the only way it has to give each face its own colour as ours does; `embedded-3dgfx-1mesh` draws the whole scene as one mesh in one colour, its cheapest frame, for scale (not the same picture).".into());
    line(String::new());
    line(
        "| scene | ours | ours, vertex cache | ours, Exact | euc | embedded-3dgfx | embedded-3dgfx-1mesh |"
            .into(),
    );
    line("|---|---|---|---|---|---|---|".into());
    let mut slower = [Vec::new(), Vec::new(), Vec::new()];
    for scene in &scenes {
        let times: Vec<Option<f64>> = renderers
            .iter()
            .map(|r| criterion_mean_ns_of("peers", r, scene))
            .collect();
        let ours: Vec<f64> = renderers[..3]
            .iter()
            .zip(&times)
            .map(|(r, t)| t.ok_or_else(|| format!("no criterion result for {r}/{scene}")))
            .collect::<Result<_, _>>()?;
        let mut cells: Vec<String> = ours
            .iter()
            .map(|t| format!("{:.1} µs", t / 1000.0))
            .collect();
        for (r, t) in renderers.iter().zip(&times).skip(3) {
            let t = t.ok_or_else(|| format!("no criterion result for {r}/{scene}"))?;
            let ratios: Vec<f64> = ours.iter().map(|o| t / o).collect();
            for (list, ratio) in slower.iter_mut().zip(&ratios) {
                if *ratio < 2.0 {
                    list.push(format!("{r} on {scene}: {ratio:.2}×"));
                }
            }
            let ratios: Vec<String> = ratios.iter().map(|x| format!("{x:.2}×")).collect();
            cells.push(format!("{:.1} µs ({})", t / 1000.0, ratios.join(" · ")));
        }
        line(format!("| {scene} | {} |", cells.join(" | ")));
    }
    line(String::new());
    for (what, list) in [
        "ours",
        "ours with the vertex cache",
        "ours with the `Exact` preset",
    ]
    .iter()
    .zip(&slower)
    {
        if list.is_empty() {
            line(format!(
                "{what}: at least 2× faster than every peer on every scene."
            ));
        } else {
            line(format!(
                "Where {what} is not at least 2× faster (peer time / ours): {}.",
                list.join("; ")
            ));
        }
        line(String::new());
    }
    line("## Accuracy against the f64 reference".into());
    line(String::new());
    line("Every camera of each scene, judged by `metrics::compare` with our default error bound (4 sub-pixel bits) for every renderer. Id mismatches: pixels showing another triangle than the reference (worst camera, percent of the frame); real: mismatches not explained by the bound, summed over cameras; max px: the largest distance from a mismatching pixel centre to an edge of the triangles involved. A peer that cannot render a scene correctly is marked, not dropped.".into());
    line(String::new());
    line("| scene | cameras | renderer | id mismatches (worst) | real | max px |".into());
    line("|---|---|---|---|---|---|".into());
    for scene in &scenes {
        let of_scene: Vec<_> = rows.iter().filter(|r| r.scene == *scene).collect();
        let outcomes = |name: &str| -> Vec<&peers::Outcome> {
            of_scene
                .iter()
                .map(|r| {
                    if name == "ours" {
                        &r.ours
                    } else if name == "ours, Exact" {
                        &r.ours_exact
                    } else {
                        &r.peers
                            .iter()
                            .find(|(p, _)| p.name() == name)
                            .expect("every peer has a row")
                            .1
                    }
                })
                .collect()
        };
        for name in ["ours", "ours, Exact", "euc", "embedded-3dgfx"] {
            let o = outcomes(name);
            let failed: Vec<&str> = o
                .iter()
                .filter_map(|o| o.metrics.as_ref().err().map(String::as_str))
                .collect();
            if let Some(e) = failed.first() {
                line(format!(
                    "| {scene} | {} | {name} | failed: {e} | | |",
                    o.len()
                ));
                continue;
            }
            let m: Vec<_> = o.iter().filter_map(|o| o.metrics.as_ref().ok()).collect();
            let worst = m
                .iter()
                .map(|m| m.id_mismatch_percent())
                .fold(0.0, f64::max);
            let real: usize = m.iter().map(|m| m.real).sum();
            let max_px = o.iter().map(|o| o.max_edge_distance).fold(0.0, f64::max);
            let mark = if real > 0 { " **wrong**" } else { "" };
            line(format!(
                "| {scene} | {} | {name} | {worst:.3} % | {real}{mark} | {max_px:.2} |",
                o.len()
            ));
        }
    }
    line(String::new());
    line("## What each peer does".into());
    line(String::new());
    let caps: Vec<_> = Peer::ALL.iter().map(|p| p.capabilities()).collect();
    line(format!(
        "| | {} |",
        caps.iter()
            .map(|c| format!("{} {}", c.name, c.version))
            .collect::<Vec<_>>()
            .join(" | ")
    ));
    line(format!("|---|{}", "---|".repeat(caps.len())));
    type Field = fn(&peers::Capabilities) -> &'static str;
    let fields: [(&str, Field); 7] = [
        ("near plane", |c| c.near),
        ("far plane", |c| c.far),
        ("depth", |c| c.depth),
        ("sub-pixel precision", |c| c.sub_pixel),
        ("fill rule", |c| c.fill_rule),
        ("back faces", |c| c.back_faces),
        ("colours", |c| c.colours),
    ];
    for (name, get) in fields {
        line(format!(
            "| {name} | {} |",
            caps.iter().map(get).collect::<Vec<_>>().join(" | ")
        ));
    }
    let path = root().join("docs/peers.md");
    std::fs::write(&path, md).map_err(|e| format!("{}: {e}", path.display()))?;
    println!("wrote {}", path.display());
    Ok(())
}

/// `n` with thousands separators, as the README writes figures.
fn thousands(n: u64) -> String {
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

fn first_line(cmd: &mut Command) -> String {
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

/// `cargo xtask hsr-table`: the lecture's relative computation times of hidden-surface methods,
/// measured as instructions per frame on QEMU, with RAM and accuracy, into `docs/hsr-table.md`.
fn hsr_table() -> Result<(), String> {
    use scanline3d_sim::hsr;
    const TARGET: &str = "thumbv7em-none-eabihf";
    step("hidden-surface table: host frames and comparison with the f64 reference");
    let specs = (0..hsr::LEVELS.len())
        .map(scanline3d_sim::scene::SceneSpec::hsr)
        .collect::<Result<Vec<_>, String>>()?;
    let references = specs
        .iter()
        .map(|s| {
            let r = s.reference()?;
            let image = r.render(hsr::WIDTH, hsr::HEIGHT);
            Ok((r, image))
        })
        .collect::<Result<Vec<_>, String>>()?;
    let mut host = HsrHostRun {
        specs,
        references,
        entries: Vec::new(),
    };
    hsr::for_each(&mut host)?;
    // Ray casting (the f64 reference, host only): time per frame, one frame per level after
    // one warm-up, labelled as such in the doc.
    let ray_ns: Vec<f64> = host
        .specs
        .iter()
        .map(|spec| {
            let scene = spec.reference()?;
            let _ = scene.render(hsr::WIDTH, hsr::HEIGHT);
            let start = std::time::Instant::now();
            let _ = scene.render(hsr::WIDTH, hsr::HEIGHT);
            Ok(start.elapsed().as_nanos() as f64)
        })
        .collect::<Result<_, String>>()?;

    step(&format!(
        "hidden-surface table: firmware on QEMU mps2-an386, {TARGET}"
    ));
    // One run: the frames take minutes under QEMU; determinism of the counts is checked run by
    // run on the demo firmware (`cargo xtask firmware`), and the hashes below on this one.
    let first = run_example(TARGET, "firmware", "hsr_table")?;
    print!("{first}");
    let firmware: Vec<_> = first
        .lines()
        .filter(|l| l.starts_with("hsr "))
        .map(fields)
        .collect();
    let firmware_of = |e: &HsrHost| {
        let polygons = e.polygons.to_string();
        firmware.iter().find(|f| {
            f.get("method") == Some(&e.method) && f.get("polygons") == Some(&polygons.as_str())
        })
    };
    let number = |f: &std::collections::HashMap<&str, &str>, k: &str| -> Result<u64, String> {
        f.get(k)
            .and_then(|v| v.parse().ok())
            .ok_or_else(|| format!("firmware line lacks {k}"))
    };

    // Host time: criterion if `cargo bench --bench hsr` has run, else the example's own loop.
    let mut times: Vec<Option<f64>> = host
        .entries
        .iter()
        .map(|e| criterion_mean_ns(e.method, e.polygons))
        .collect();
    let timing = if times.iter().all(Option::is_some) {
        "criterion (`cargo bench --bench hsr`, mean)".to_string()
    } else {
        step("hidden-surface table: no criterion results, timing loop on the host");
        let out = cargo()
            .args(["run", "--package", FIRMWARE_PACKAGE, "--profile", "firmware"])
            .args(["--example", "hsr_table"])
            .current_dir(root())
            .stderr(Stdio::inherit())
            .output()
            .map_err(|e| format!("hsr_table on the host: {e}"))?;
        let text = String::from_utf8_lossy(&out.stdout).into_owned();
        print!("{text}");
        let lines: Vec<_> = text
            .lines()
            .filter(|l| l.starts_with("host "))
            .map(fields)
            .collect();
        for (t, e) in times.iter_mut().zip(&host.entries) {
            let polygons = e.polygons.to_string();
            *t = lines
                .iter()
                .find(|f| {
                    f.get("method") == Some(&e.method)
                        && f.get("polygons") == Some(&polygons.as_str())
                })
                .and_then(|f| f.get("ns_per_frame")?.parse().ok());
        }
        "in-process timing loop (`cargo run --profile firmware -p scanline3d-firmware --example hsr_table` on the host, about 0.3 s per entry; less reliable than criterion)".to_string()
    };

    let mut instructions = Vec::new();
    for e in &host.entries {
        let f = firmware_of(e).ok_or_else(|| {
            format!(
                "firmware printed no line for {} at {}",
                e.method, e.polygons
            )
        })?;
        let hash = f.get("hash").and_then(|h| u32::from_str_radix(h, 16).ok());
        if hash != Some(e.hash) {
            return Err(format!(
                "{} at {} polygons: firmware hash {hash:08x?} differs from the host's {:08x}",
                e.method, e.polygons, e.hash
            ));
        }
        instructions.push(number(f, "instructions")?);
    }
    println!("firmware frame hashes equal the host's");
    let smallest = instructions.iter().copied().min().unwrap_or(1).max(1) as f64;

    let lecture = [
        ("depth sort", [1, 10, 507]),
        ("z-buffer", [54, 54, 54]),
        ("scan line", [5, 21, 100]),
        ("Warnock area subdivision", [11, 64, 307]),
    ];
    let levels = hsr::LEVELS.len();
    let group = |v: &[String]| v.chunks(levels).map(|c| c.to_vec()).collect::<Vec<_>>();
    let relative: Vec<String> = instructions
        .iter()
        .map(|&i| format!("{:.1}", i as f64 / smallest))
        .collect();
    let qemu = first_line(Command::new("qemu-system-arm").arg("--version"));
    let rustc = first_line(Command::new("rustc").arg("--version"));
    let cpu = host_cpu();

    let mut md = String::new();
    let mut line = |s: String| {
        md.push_str(&s);
        md.push('\n');
    };
    line("# Hidden-surface methods: relative computation time".into());
    line(String::new());
    line("Written by `cargo xtask hsr-table`; do not edit by hand. The lecture".into());
    line("(`hidden-surface-removal.md`, 計算時間の比較, after Sutherland, Sproull and Schumacker 1974)".into());
    line("compares hidden-surface methods on scenes whose polygons shrink as their number grows. Here".into());
    line("every method runs on scanline3d's one fixed-point pipeline (transform, clip, project, edge".into());
    line("walk) and differs only in how it resolves visibility.".into());
    line(String::new());
    line(format!("* **Target:** {TARGET}, QEMU mps2-an386 (Cortex-M4F), `-icount shift=0` (1 instruction per ns, deterministic), release profile; {qemu}; {rustc}."));
    line(
        "* **Command:** `cargo xtask hsr-table` (host time: run `cargo bench --bench hsr` first)."
            .into(),
    );
    line(format!("* **Host time:** {timing}, on {cpu}."));
    line(format!(
        "* **Scenes:** `meshgen/src/lib.rs` `hsr_scene`: a chain of three interlocked tori over a ground plane that one of them sinks into, tessellated into {} triangles; {}×{}, RGB565 on black, flat shading, 4 sub-pixel bits, back-face culling, one frame from a fixed camera. The firmware renders static arrays generated from the same code (`demo/build.rs`); its frame hashes equal the host's.",
        hsr::LEVELS.iter().map(|l| thousands(l.polygons as u64)).collect::<Vec<_>>().join(", "),
        hsr::WIDTH,
        hsr::HEIGHT
    ));
    line(String::new());
    line("## Relative computation time (smallest entry = 1)".into());
    line(String::new());
    line(format!(
        "| method | {} |",
        hsr::LEVELS
            .iter()
            .map(|l| format!("{} polygons", thousands(l.polygons as u64)))
            .collect::<Vec<_>>()
            .join(" | ")
    ));
    line(format!("|---|{}", "---|".repeat(levels)));
    for (name, v) in lecture {
        line(format!(
            "| lecture: {name} | {} |",
            v.map(|x| x.to_string()).join(" | ")
        ));
    }
    for (k, row) in group(&relative).iter().enumerate() {
        line(format!(
            "| **scanline3d: {}** | {} |",
            host.entries[k * levels].method,
            row.join(" | ")
        ));
    }
    line(String::new());
    line(
        "The lecture's figures are 1974 estimates for its own scenes and machines; ours are".into(),
    );
    line("instructions per frame, normalised to our smallest entry.".into());
    line(String::new());
    line("## Measurements".into());
    line(String::new());
    line("| method | polygons | instructions per frame | host time per frame | triangles drawn | depth complexity | workspace | render call stack | RAM | id mismatches | real mismatches |".into());
    line("|---|---|---|---|---|---|---|---|---|---|---|".into());
    for ((e, i), t) in host.entries.iter().zip(&instructions).zip(&times) {
        let f = firmware_of(e).ok_or("missing firmware line")?;
        let (bytes, stack) = (number(f, "workspace_bytes")?, number(f, "render_stack")?);
        let time = t.map_or("n/a".into(), |ns| format!("{:.1} µs", ns / 1000.0));
        line(format!(
            "| {} | {} | {} | {time} | {} | {:.2} | {} B | {} B | {} B | {:.3} % | {} |",
            e.method,
            thousands(e.polygons as u64),
            thousands(*i),
            thousands(e.stats.activated as u64),
            e.stats.fragments as f64 / e.covered.max(1) as f64,
            thousands(bytes),
            thousands(stack),
            thousands(bytes + stack),
            e.accuracy.id_mismatch_percent(),
            e.accuracy.real
        ));
    }
    line(String::new());
    line("* **Instructions per frame:** the render call alone, counted on the firmware (`firmware/examples/hsr_table.rs`). **Triangles drawn:** set up for the row walk after culling and clipping. **Depth complexity:** fragments (pixel centres covered before the depth test) per pixel showing a triangle.".into());
    line("* **Workspace** is the method's `BYTES`, sized for the scene (`hsr::LEVELS`: triangles after culling, triangles per row); **render call stack** is the peak stack of the render call, measured by painting; **RAM** is their sum (the scene itself is in flash).".into());
    line("* **Id mismatches** are pixels whose triangle differs from the f64 ray-cast reference (`scanline3d_sim::metrics::compare`, host render through the same method); **real** ones are those not explained by the documented position error bound or a depth tie.".into());
    qualitative(
        &mut line,
        &host,
        &instructions,
        &times,
        &firmware_of,
        &number,
        &ray_ns,
    )?;
    let path = root().join("docs/hsr-table.md");
    std::fs::write(&path, md).map_err(|e| format!("{}: {e}", path.display()))?;
    println!("\nwrote {}", path.display());
    Ok(())
}

/// Where each method's own code is (the shared pipeline is not counted): file, and the lines
/// from the first containing `from` up to the first after it containing `to` (`""`: to the
/// end or the tests).
type CodeRange = (&'static str, &'static str, &'static str);
const METHOD_CODE: [(&str, &[CodeRange]); 9] = [
    (
        "span-zbuffer",
        &[(
            "src/render.rs",
            "/// The span z-buffer: one row of depth",
            "/// Checks a `width",
        )],
    ),
    (
        "zbuffer",
        &[(
            "src/resolve/mod.rs",
            "// Band and full-frame z-buffer",
            "// Span sorting",
        )],
    ),
    (
        "band:16",
        &[(
            "src/resolve/mod.rs",
            "// Band and full-frame z-buffer",
            "// Span sorting",
        )],
    ),
    (
        "span-sort",
        &[("src/resolve/mod.rs", "// Span sorting", "// Depth sort")],
    ),
    ("depth-sort", &[("src/resolve/mod.rs", "// Depth sort", "")]),
    (
        "bsp",
        &[("src/resolve/bsp.rs", "", ""), ("sim/src/bsp.rs", "", "")],
    ),
    ("newell", &[("src/resolve/newell.rs", "", "")]),
    ("warnock", &[("src/resolve/warnock.rs", "", "")]),
    ("ray casting", &[("sim/src/reference.rs", "", "")]),
];

/// Lines of code (not blank, not comments) of a method, as [`METHOD_CODE`] locates it.
fn code_lines(method: &str) -> Option<usize> {
    let (_, parts) = METHOD_CODE.iter().find(|(m, _)| *m == method)?;
    let mut total = 0;
    for (file, from, to) in parts.iter() {
        let text = std::fs::read_to_string(root().join(file)).ok()?;
        let lines: Vec<&str> = text.lines().collect();
        let start = if from.is_empty() {
            0
        } else {
            lines.iter().position(|l| l.contains(from))?
        };
        let end = lines[start + 1..]
            .iter()
            .position(|l| (!to.is_empty() && l.contains(to)) || l.starts_with("#[cfg(test)]"))
            .map_or(lines.len(), |k| start + 1 + k);
        total += lines[start..end]
            .iter()
            .map(|l| l.trim())
            .filter(|l| !l.is_empty() && !l.starts_with("//"))
            .count();
    }
    Some(total)
}

/// The lecture's qualitative comparison (speed, memory, complexity, reflection/refraction,
/// object types), with each adjective replaced by a measurement.
#[allow(clippy::too_many_arguments)]
fn qualitative<'f>(
    line: &mut impl FnMut(String),
    host: &HsrHostRun,
    instructions: &[u64],
    times: &[Option<f64>],
    firmware_of: &impl Fn(&HsrHost) -> Option<&'f std::collections::HashMap<&'f str, &'f str>>,
    number: &impl Fn(&std::collections::HashMap<&str, &str>, &str) -> Result<u64, String>,
    ray_ns: &[f64],
) -> Result<(), String> {
    use scanline3d_sim::hsr;
    let level = 1; // 2,500 polygons
    let polygons = hsr::LEVELS[level].polygons;
    let rows: Vec<usize> = (0..host.entries.len())
        .filter(|&k| host.entries[k].polygons == polygons)
        .collect();
    let fastest = rows
        .iter()
        .map(|&k| instructions[k])
        .min()
        .unwrap_or(1)
        .max(1) as f64;
    line(String::new());
    line("## The lecture's qualitative comparison, measured".into());
    line(String::new());
    line("The lecture rates z-buffer, scan line and ray tracing as 速度 (speed) やや速 / 速 / 遅, memory 多 / 少 / 少, 手順 (procedure) 単純 / 複雑 / 単純, 反射・屈折 (reflection, refraction) 困難 / 困難 / 容易, and ray tracing alone as not limited to polygons. Here each adjective is a measurement at".into());
    line(format!(
        "{} polygons (same scene, target and options as above):",
        thousands(polygons as u64)
    ));
    line(String::new());
    line("| method | speed: instructions per frame (× fastest) | host time per frame | memory: RAM | procedure: lines of its own code | reflection / refraction | objects |".into());
    line("|---|---|---|---|---|---|---|".into());
    for &k in &rows {
        let e = &host.entries[k];
        let f = firmware_of(e).ok_or("missing firmware line")?;
        let ram = number(f, "workspace_bytes")? + number(f, "render_stack")?;
        line(format!(
            "| {} | {} ({:.1}×) | {} | {} B | {} | no: one surface per pixel | triangles |",
            e.method,
            thousands(instructions[k]),
            instructions[k] as f64 / fastest,
            times[k].map_or("n/a".into(), |ns| format!("{:.1} µs", ns / 1000.0)),
            thousands(ram),
            code_lines(e.method).map_or("n/a".into(), |n| n.to_string()),
        ));
    }
    line(format!(
        "| ray casting (f64 reference, host only) | n/a (f64, not on the targets) | {:.1} µs (one frame, `std::time::Instant`) | host heap (BVH over all triangles) | {} | not yet: primary rays only; secondary rays are the ray tracer's job | triangles, spheres, planes |",
        ray_ns.get(level).copied().unwrap_or(0.0) / 1000.0,
        code_lines("ray casting").map_or("n/a".into(), |n| n.to_string()),
    ));
    line(String::new());
    line("* **Procedure** counts non-blank, non-comment lines of the method's own code, without the shared pipeline (transform, clipping, projection, edge walk) and without tests: `xtask` `METHOD_CODE` says which lines. The BSP count includes its host-side tree builder.".into());
    Ok(())
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
        run(cargo().args(["build", "--release", "--package", "scanline3d", "--lib", "--target", target]))?;
    }
    for target in TARGETS {
        // Link-time proof that the render path cannot panic: the example's panic handler calls
        // an undefined symbol, so the link fails if any panic is reachable.
        step(&format!("panic-never link check for {target}"));
        run(cargo().args([
            "build",
            "--package",
            FIRMWARE_PACKAGE,
            "--profile",
            "firmware",
            "--example",
            "panic_never",
            "--target",
            target,
        ]))?;
    }
    firmware()?;
    lean()?;
    fuzz(FUZZ_SECONDS_IN_TEST)?;
    println!("\nxtask: {} passed, {} failed", totals.0, totals.1);
    Ok(())
}

/// Length of the bounded fuzzing session inside `cargo xtask test`.
const FUZZ_SECONDS_IN_TEST: u32 = 60;

/// Coverage-guided fuzzing of scene/OBJ input with AFL++ (`cargo afl`, stable Rust) for
/// `seconds`, seeded with the corpus. Fails on any crash or hang.
fn fuzz(seconds: u32) -> Result<(), String> {
    step(&format!(
        "fuzz scene input for {seconds} s (AFL++ via cargo afl)"
    ));
    let have_afl = cargo()
        .args(["afl", "--version"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if !have_afl {
        run(cargo().args(["install", "cargo-afl", "--version", "0.18.2", "--locked"]))?;
    }
    // Builds AFL++'s runtime for this rustc once; it refuses (harmlessly) when already built.
    let _ = cargo()
        .args(["afl", "config", "--build"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status();
    run(cargo().args([
        "afl",
        "build",
        "--release",
        "--manifest-path",
        "fuzz/Cargo.toml",
    ]))?;
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

fn main() -> ExitCode {
    let task = std::env::args().nth(1).unwrap_or_default();
    let result = match task.as_str() {
        "test" => test(),
        "firmware" => install().and_then(|_| firmware()),
        "lean" => install().and_then(|_| lean()),
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
                "usage: cargo xtask test | firmware | lean | hsr-table | peers | tradeoff | profile [VARIANT] | fuzz [SECONDS]"
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

/// An ELF symbol: name, size, type, section index.
type Symbol = (String, u32, u8, u16);

/// Section sizes and symbol attribution of an ELF32 little-endian file.
struct Elf {
    sections: Vec<(String, u32, u32)>, // name, size, flags
    symbols: Vec<Symbol>,
}

fn elf(path: &std::path::Path) -> Result<Elf, String> {
    let d = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let u16_at = |o: usize| {
        d.get(o..o + 2)
            .map(|b| u16::from_le_bytes([b[0], b[1]]))
            .unwrap_or(0)
    };
    let u32_at = |o: usize| {
        d.get(o..o + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .unwrap_or(0)
    };
    if d.get(..5) != Some(b"\x7fELF\x01") {
        return Err(format!("{}: not an ELF32 file", path.display()));
    }
    let (shoff, shentsize, shnum, shstrndx) = (
        u32_at(0x20) as usize,
        u16_at(0x2e) as usize,
        u16_at(0x30) as usize,
        u16_at(0x32) as usize,
    );
    let sh = |i: usize| shoff + i * shentsize;
    let str_at = |table: usize, off: usize| -> String {
        let start = table + off;
        let end = d[start..]
            .iter()
            .position(|&b| b == 0)
            .map_or(start, |n| start + n);
        String::from_utf8_lossy(&d[start..end]).into_owned()
    };
    let names = u32_at(sh(shstrndx) + 0x10) as usize;
    let mut sections = Vec::new();
    let mut symbols = Vec::new();
    for i in 0..shnum {
        let h = sh(i);
        let (name, kind, flags, offset, size, link) = (
            u32_at(h) as usize,
            u32_at(h + 4),
            u32_at(h + 8),
            u32_at(h + 0x10) as usize,
            u32_at(h + 0x14),
            u32_at(h + 0x18) as usize,
        );
        sections.push((str_at(names, name), size, flags));
        if kind == 2 {
            // SHT_SYMTAB: 16-byte entries; names in the linked string table.
            let strtab = u32_at(sh(link) + 0x10) as usize;
            for e in (offset..offset + size as usize).step_by(16) {
                let name = str_at(strtab, u32_at(e) as usize);
                symbols.push((
                    name,
                    u32_at(e + 8),
                    d.get(e + 12).copied().unwrap_or(0) & 0xf,
                    u16_at(e + 14),
                ));
            }
        }
    }
    Ok(Elf { sections, symbols })
}

/// Prints flash and RAM of the firmware for `target`, and how much of the flash is the library.
fn sizes(target: &str, firmware_output: &str) -> Result<(), String> {
    let path = root()
        .join("target")
        .join(target)
        .join("firmware/examples/firmware");
    let e = elf(&path)?;
    let size = |n: &str| {
        e.sections
            .iter()
            .filter(|s| s.0 == n)
            .map(|s| s.1 as u64)
            .sum::<u64>()
    };
    let (text, rodata, data, bss, vectors) = (
        size(".text"),
        size(".rodata"),
        size(".data"),
        size(".bss"),
        size(".vector_table"),
    );
    let text_index = e
        .sections
        .iter()
        .position(|s| s.0 == ".text")
        .unwrap_or(usize::MAX) as u16;
    let rodata_index = e
        .sections
        .iter()
        .position(|s| s.0 == ".rodata")
        .unwrap_or(usize::MAX) as u16;
    let sum = |pred: &dyn Fn(&Symbol) -> bool| {
        e.symbols
            .iter()
            .filter(|s| pred(s))
            .map(|s| s.1 as u64)
            .sum::<u64>()
    };
    let ours = |s: &Symbol| s.0.contains("scanline3d");
    let lib_code = sum(&|s| s.3 == text_index && ours(s) && !s.0.contains("firmware"));
    let builtins =
        sum(&|s| s.3 == text_index && (s.0.starts_with("__") || s.0.contains("compiler_builtins")));
    let mesh_data = sum(&|s| s.3 == rodata_index && ours(s) && s.0.contains("demo"));
    let stack = firmware_output
        .lines()
        .find_map(|l| l.strip_prefix("summary peak_stack "))
        .and_then(|l| l.split_whitespace().next())
        .and_then(|n| n.parse::<u64>().ok())
        .unwrap_or(0);
    println!("sizes {target}: flash {} bytes (.vector_table {vectors} + .text {text} + .rodata {rodata} + .data {data})", vectors + text + rodata + data);
    println!("sizes {target}: of which library code {lib_code}, compiler builtins {builtins}, demo mesh data {mesh_data}");
    println!("sizes {target}: RAM {} bytes (.data {data} + .bss {bss} + measured peak stack {stack}, workspace included)", data + bss + stack);
    Ok(())
}

/// Without the `peers` feature the peer renderers are not linked into the xtask: run it again
/// with them (`cargo xtask test` stays free of their build).
#[cfg(not(feature = "peers"))]
fn peers() -> Result<(), String> {
    run(cargo().args(["run", "--package", "xtask", "--features", "peers", "--", "peers"]))
}
