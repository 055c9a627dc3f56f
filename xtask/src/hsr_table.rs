//! `cargo xtask hsr-table`: every hidden-surface method on the test scenes, host and firmware,
//! written to `docs/hsr-table.md`.

use crate::*;

/// One (method, scene size) of the hidden-surface table, as the host computes it.
pub(crate) struct HsrHost {
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
pub(crate) struct HsrHostRun {
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

/// One traced (variant, level) as the host computes it: the frame hash and the id image against
/// the f64 reference (time per frame comes from the host run of the `hsr_table` example).
pub(crate) struct TracedHost {
    variant: &'static str,
    polygons: usize,
    hash: u32,
    accuracy: scanline3d_sim::metrics::Metrics,
}

/// The fixed-point tracer on the host at every traced level, primary rays only and with
/// shadows, through the same code as the firmware (`scanline3d_sim::hsr::traced`).
fn traced_on_host(run: &HsrHostRun) -> Result<Vec<TracedHost>, String> {
    use embedded_graphics::pixelcolor::{Rgb565, RgbColor};
    use scanline3d::sink::{FnSink, HashSink, Row, TriangleId};
    use scanline3d_sim::hsr::{self, traced, HEIGHT, WIDTH};
    use scanline3d_sim::{metrics, reference::Image};
    let mut out = Vec::new();
    for level in 0..traced::TRACED_LEVELS {
        let spec = &run.specs[level];
        let mut buffers = Box::new(traced::Buffers::new()?);
        spec.with_scene(|scene| buffers.fill(scene))??;
        for v in traced::Variant::ALL {
            let (variant, mut sink) = (v.name(), HashSink::new());
            buffers
                .with_tracer(v, |t, h| traced::frame(t, h, Rgb565::BLACK, &mut sink))?
                .map_err(|e| format!("traced frame: {e:?}"))?;
            let mut image = Image {
                width: WIDTH,
                height: HEIGHT,
                ids: vec![-1; WIDTH * HEIGHT],
                depth: vec![f32::INFINITY; WIDTH * HEIGHT],
                color: vec![[0; 3]; WIDTH * HEIGHT],
            };
            let mut ids = FnSink(|row: Row<'_, TriangleId>| {
                let start = row.y as usize * WIDTH;
                // The tracer sends no depth row: NaN over surfaces (not compared).
                for (x, id) in row.pixels.iter().enumerate() {
                    image.ids[start + x] = id.0;
                    image.depth[start + x] = if id.0 >= 0 { f32::NAN } else { f32::INFINITY };
                }
                Ok::<(), std::convert::Infallible>(())
            });
            buffers
                .with_tracer(v, |t, h| traced::frame(t, h, TriangleId::NONE, &mut ids))?
                .map_err(|e| format!("traced id frame: {e:?}"))?;
            let (reference, ref_image) = &run.references[level];
            let bound = metrics::ErrorBound {
                sub_bits: 4,
                max_model_coord: spec.max_model_coord(),
                focal_px: reference.camera.focal_px(HEIGHT),
                arithmetic: Default::default(),
            };
            out.push(TracedHost {
                variant,
                polygons: hsr::LEVELS[level].polygons,
                hash: sink.hash(),
                accuracy: metrics::compare(&image, ref_image, reference, &bound),
            });
        }
    }
    Ok(out)
}

/// Mean time per frame (ns) from a criterion run of `cargo bench --bench hsr`, if there is one.
pub(crate) fn criterion_mean_ns(method: &str, polygons: usize) -> Option<f64> {
    criterion_mean_ns_of("hsr", method, &polygons.to_string())
}

/// `cargo xtask hsr-table`: the lecture's relative computation times of hidden-surface methods,
/// measured as instructions per frame on QEMU, with RAM and accuracy, into `docs/hsr-table.md`.
pub(crate) fn hsr_table() -> Result<(), String> {
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

    step("hidden-surface table: the fixed-point tracer on the host");
    let traced = traced_on_host(&host)?;

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

    // Host time: criterion if `cargo bench --bench hsr` has run, else the example's own loop;
    // the tracer's always from that loop (it has no criterion bench).
    step("hidden-surface table: timing loop on the host");
    let out = cargo()
        .args([
            "run",
            "--package",
            FIRMWARE_PACKAGE,
            "--profile",
            "firmware",
        ])
        .args(["--example", "hsr_table"])
        .current_dir(root())
        .stderr(Stdio::inherit())
        .output()
        .map_err(|e| format!("hsr_table on the host: {e}"))?;
    let host_text = String::from_utf8_lossy(&out.stdout).into_owned();
    print!("{host_text}");
    let host_lines: Vec<_> = host_text
        .lines()
        .filter(|l| l.starts_with("host "))
        .map(fields)
        .collect();
    let loop_ns = |key: &str, name: &str, polygons: usize| -> Option<f64> {
        let polygons = polygons.to_string();
        host_lines
            .iter()
            .find(|f| f.get(key) == Some(&name) && f.get("polygons") == Some(&polygons.as_str()))
            .and_then(|f| f.get("ns_per_frame")?.parse().ok())
    };
    let mut times: Vec<Option<f64>> = host
        .entries
        .iter()
        .map(|e| criterion_mean_ns(e.method, e.polygons))
        .collect();
    let timing = if times.iter().all(Option::is_some) {
        "criterion (`cargo bench --bench hsr`, mean)".to_string()
    } else {
        for (t, e) in times.iter_mut().zip(&host.entries) {
            *t = loop_ns("method", e.method, e.polygons);
        }
        "in-process timing loop (`cargo run --profile firmware -p scanline3d-firmware --example hsr_table` on the host, about 0.3 s per entry; less reliable than criterion)".to_string()
    };
    let traced_ns = |t: &TracedHost| loop_ns("variant", t.variant, t.polygons);

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
    // The tracer's lines: (host entry, firmware fields), hashes checked.
    let traced_lines: Vec<_> = first
        .lines()
        .filter(|l| l.starts_with("trace "))
        .map(fields)
        .collect();
    let mut traced_rows = Vec::new();
    for t in &traced {
        let polygons = t.polygons.to_string();
        let f = traced_lines
            .iter()
            .find(|f| {
                f.get("variant") == Some(&t.variant)
                    && f.get("polygons") == Some(&polygons.as_str())
            })
            .ok_or_else(|| {
                format!(
                    "firmware printed no trace line for {} at {}",
                    t.variant, t.polygons
                )
            })?;
        let hash = f.get("hash").and_then(|h| u32::from_str_radix(h, 16).ok());
        if hash != Some(t.hash) {
            return Err(format!(
                "traced {} at {} polygons: firmware hash {hash:08x?} differs from the host's {:08x}",
                t.variant, t.polygons, t.hash
            ));
        }
        traced_rows.push((t, f));
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
    for variant in scanline3d_sim::hsr::traced::Variant::ALL.map(|v| v.name()) {
        let mut cells = Vec::new();
        for level in hsr::LEVELS.iter() {
            let found = traced_rows
                .iter()
                .find(|(t, _)| t.variant == variant && t.polygons == level.polygons);
            cells.push(match found {
                Some((_, f)) => format!("{:.1}", number(f, "instructions")? as f64 / smallest),
                None => "does not fit".to_string(),
            });
        }
        line(format!(
            "| **scanline3d: {}** | {} |",
            traced_name(variant),
            cells.join(" | ")
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
    for (t, f) in &traced_rows {
        let (bytes, stack) = (number(f, "scene_bytes")?, number(f, "render_stack")?);
        line(format!(
            "| {} | {} | {} | {} | n/a: rays, not triangles | n/a | {} B | {} B | {} B | {:.3} % | {} |",
            traced_name(t.variant),
            thousands(t.polygons as u64),
            thousands(number(f, "instructions")?),
            micros(traced_ns(t)),
            thousands(bytes),
            thousands(stack),
            thousands(bytes + stack),
            t.accuracy.id_mismatch_percent(),
            t.accuracy.real
        ));
    }
    line(String::new());
    line("* **Instructions per frame:** the render call alone, counted on the firmware (`firmware/examples/hsr_table.rs`). **Triangles drawn:** set up for the row walk after culling and clipping. **Depth complexity:** fragments (pixel centres covered before the depth test) per pixel showing a triangle.".into());
    line("* **Workspace** is the method's `BYTES`, sized for the scene (`hsr::LEVELS`: triangles after culling, triangles per row); **render call stack** is the peak stack of the render call, measured by painting; **RAM** is their sum (the scene itself is in flash).".into());
    line(format!("* **Ray tracing** is the library's fixed-point tracer (`scanline3d::trace`, [tracing.md](tracing.md)) over every triangle of the scene, no back faces culled, with a bounding-volume hierarchy: *ray casting* traces primary rays only (no light, so ambient colour), *with shadows* adds the light as a shadow ray per lit pixel and Lambert shading, *hybrid mode* finds the primary hits from the triangles' screen bounds instead of a hierarchy walk per pixel, but in the groups of a row's columns where more than 16 rectangles pile up (or in rows with more than 128) the primary rays walk the hierarchy, which is cheaper there, its shadow rays still walking the hierarchy (no per-row shadow candidate lists: over thousands of small triangles a row's lists would be long; same frame hash; [tracing.md](tracing.md)). Its **workspace** column holds the traced objects (60 B per triangle, vertices inline), a material per triangle and the hierarchy (in hybrid mode also 24 B per triangle of screen bounds and active list), built at run time in {} instructions at 2,500 polygons (not in the frame's count; `sim export` can build it on the host instead). At 60,000 polygons those would need about 7 MB, more than the QEMU board's 4 MiB of RAM or flash, so that level is not traced.", traced_rows.iter().find(|(t, _)| t.polygons == 2500).map_or(Ok("n/a".to_string()), |(_, f)| number(f, "build_instructions").map(thousands))?));
    line("* **Id mismatches** are pixels whose triangle differs from the f64 ray-cast reference (`scanline3d_sim::metrics::compare`, host render through the same method); **real** ones are those not explained by the documented position error bound or a depth tie.".into());
    qualitative(
        &mut line,
        &host,
        &instructions,
        &times,
        &firmware_of,
        &number,
        &ray_ns,
        &traced_rows,
        &traced_ns,
    )?;
    let path = root().join("docs/hsr-table.md");
    std::fs::write(&path, stamp("cargo xtask hsr-table") + &md)
        .map_err(|e| format!("{}: {e}", path.display()))?;
    println!("\nwrote {}", path.display());
    Ok(())
}

/// Where each method's own code is (the shared pipeline is not counted): file, and the lines
/// from the first containing `from` up to the first after it containing `to` (`""`: to the
/// end or the tests).
pub(crate) type CodeRange = (&'static str, &'static str, &'static str);

pub(crate) const METHOD_CODE: [(&str, &[CodeRange]); 10] = [
    (
        "span-zbuffer",
        &[(
            "src/workspace.rs",
            "/// The span z-buffer: one row of depth",
            "pub struct Workspace<",
        )],
    ),
    ("zbuffer", &[("src/resolve/band.rs", "", "")]),
    ("band:16", &[("src/resolve/band.rs", "", "")]),
    ("span-sort", &[("src/resolve/span_sort.rs", "", "")]),
    ("depth-sort", &[("src/resolve/depth_sort.rs", "", "")]),
    (
        "bsp",
        &[("src/resolve/bsp.rs", "", ""), ("sim/src/bsp.rs", "", "")],
    ),
    ("newell", &[("src/resolve/newell.rs", "", "")]),
    ("warnock", &[("src/resolve/warnock.rs", "", "")]),
    ("ray casting", &[("sim/src/reference.rs", "", "")]),
    (
        "ray tracing",
        &[
            ("src/trace/tracer.rs", "", ""),
            ("src/trace/intersect.rs", "", ""),
            ("src/trace/bvh.rs", "", ""),
        ],
    ),
];

/// A host time in µs, or n/a.
fn micros(ns: Option<f64>) -> String {
    ns.map_or("n/a".into(), |ns| format!("{:.1} µs", ns / 1000.0))
}

/// The table's name of a traced variant.
fn traced_name(variant: &str) -> &'static str {
    match variant {
        "shadows" => "ray tracing with shadows",
        "hybrid" => "ray tracing with shadows, hybrid mode",
        _ => "ray casting",
    }
}

/// [`code_lines`], or an error naming the method whose code [`METHOD_CODE`] no longer finds.
fn code_lines_or_err(method: &str) -> Result<usize, String> {
    code_lines(method).ok_or_else(|| {
        format!("xtask METHOD_CODE: the code of {method} is not where it says (moved or renamed?)")
    })
}

/// Lines of code (not blank, not comments) of a method, as [`METHOD_CODE`] locates it.
pub(crate) fn code_lines(method: &str) -> Option<usize> {
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
pub(crate) fn qualitative<'f>(
    line: &mut impl FnMut(String),
    host: &HsrHostRun,
    instructions: &[u64],
    times: &[Option<f64>],
    firmware_of: &impl Fn(&HsrHost) -> Option<&'f std::collections::HashMap<&'f str, &'f str>>,
    number: &impl Fn(&std::collections::HashMap<&str, &str>, &str) -> Result<u64, String>,
    ray_ns: &[f64],
    traced: &[(&TracedHost, &std::collections::HashMap<&str, &str>)],
    traced_ns: &impl Fn(&TracedHost) -> Option<f64>,
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
            code_lines_or_err(e.method)?,
        ));
    }
    for (t, f) in traced.iter().filter(|(t, _)| t.polygons == polygons) {
        let i = number(f, "instructions")?;
        line(format!(
            "| {} | {} ({:.1}×) | {} | {} B | {} | {} | triangles, spheres, planes, boxes, cylinders, cones, ellipsoids, polygons |",
            traced_name(t.variant),
            thousands(i),
            i as f64 / fastest,
            micros(traced_ns(t)),
            thousands(number(f, "scene_bytes")? + number(f, "render_stack")?),
            code_lines_or_err("ray tracing")?,
            if t.variant != "primary" { "yes: shadows here; reflection and refraction on the same code path (classic scene: [tracing.md](tracing.md))" } else { "yes, with secondary rays (not traced here)" },
        ));
    }
    line(format!(
        "| ray casting (f64 reference, host only) | n/a (f64, not on the targets) | {:.1} µs (one frame, `std::time::Instant`, in xtask's unoptimised build) | host heap (BVH over all triangles) | {} | primary rays only (the f64 Whitted tracer is `sim trace`) | triangles, spheres, planes |",
        ray_ns.get(level).copied().unwrap_or(0.0) / 1000.0,
        code_lines_or_err("ray casting")?,
    ));
    line(String::new());
    line("* **Procedure** counts non-blank, non-comment lines of the method's own code, without the shared pipeline (transform, clipping, projection, edge walk) and without tests: `xtask` `METHOD_CODE` says which lines. The BSP count includes its host-side tree builder.".into());
    Ok(())
}
