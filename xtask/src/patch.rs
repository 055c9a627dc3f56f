//! `cargo xtask patch`: the scanline Bezier patch renderer (the Utah teapot from 32 static
//! patches) on QEMU for every target; the frame hashes must equal the host's
//! (`scanline3d_demo::patches`, the same code), and the instructions per frame are printed.
//! `cargo xtask patch-trade`: every flatness tolerance and the triangle meshes of the same
//! accuracy, against the Bezier-clipping reference and on QEMU; the table in
//! `docs/patch-trade.md` and the plot `docs/patch-trade.png`.

use crate::*;
use scanline3d_demo::patches::FIRMWARE_FRAMES as FRAMES;
use scanline3d_sim::patch::trade::{self, Mismatches, OnTarget, TessellatedMesh, TradeRow};

/// The hashes the host computes for the firmware's frames.
fn host_hashes() -> Result<Vec<u32>, String> {
    use scanline3d::sink::HashSink;
    use scanline3d_demo::patches::{self, PanelPatches};
    let mut ws = Box::new(PanelPatches::new(
        embedded_graphics::pixelcolor::Rgb565::new(0, 0, 0),
    ));
    FRAMES
        .iter()
        .map(|&frame| {
            let mut sink = HashSink::new();
            patches::render_frame(&mut ws, frame, &mut sink)?;
            Ok(sink.hash())
        })
        .collect()
}

pub(crate) fn patch() -> Result<(), String> {
    let expected = host_hashes()?;
    step("patch firmware for every target (a no-op when built)");
    build_firmware_examples("firmware", &["patch"])?;
    for (target, machine) in FIRMWARE {
        step(&format!(
            "patch renderer (teapot) on QEMU {machine}, {target}"
        ));
        let out = run_example(target, "firmware", "patch")?;
        print!("{out}");
        let hashes = frame_hashes(&out);
        if hashes != expected {
            return Err(format!(
                "{target}: patch frame hashes {hashes:08x?} differ from the host's {expected:08x?}"
            ));
        }
        println!(
            "patch frame hashes equal the host's: {expected:08x?}; {:.1} M instructions (QEMU) per frame",
            mean_frame_instructions(&out) / 1e6
        );
    }
    Ok(())
}

/// Targets of the trade table.
const TRADE_TARGETS: [&str; 2] = ["thumbv7em-none-eabihf", "thumbv6m-none-eabi"];

/// The host's hashes of the patch firmware's frames at `tolerance`.
fn host_patch_hashes(tolerance: f64) -> Result<Vec<u32>, String> {
    use scanline3d::sink::HashSink;
    use scanline3d_demo::patches::{self, PanelPatches};
    let mut ws = Box::new(PanelPatches::new(
        embedded_graphics::pixelcolor::Rgb565::new(0, 0, 0),
    ));
    let tolerance = scanline3d::patch::Tolerance::from_num(tolerance);
    FRAMES
        .iter()
        .map(|&frame| {
            let mut sink = HashSink::new();
            patches::render_frame_at(&mut ws, frame, tolerance, &mut sink)?;
            Ok(sink.hash())
        })
        .collect()
}

/// The host's hashes of the mesh firmware's frames drawing `mesh`.
fn host_mesh_hashes(mesh: &TessellatedMesh) -> Result<Vec<u32>, String> {
    use scanline3d::sink::HashSink;
    use scanline3d_demo::patches::{self, PanelMesh};
    let vertices = mesh.fixed_vertices();
    let lib = mesh.mesh(&vertices)?;
    std::thread::scope(|scope| {
        std::thread::Builder::new()
            .stack_size(64 << 20)
            .spawn_scoped(scope, || {
                let mut ws = Box::new(PanelMesh::<
                    embedded_graphics::pixelcolor::Rgb565,
                    { scanline3d::scene::MAX_SCENE_TRIANGLES },
                >::new(
                    embedded_graphics::pixelcolor::Rgb565::new(0, 0, 0)
                ));
                FRAMES
                    .iter()
                    .map(|&frame| {
                        let mut sink = HashSink::new();
                        patches::render_mesh_frame(&mut ws, &lib, frame, &mut sink)?;
                        Ok(sink.hash())
                    })
                    .collect::<Result<Vec<u32>, String>>()
            })
            .map_err(|e| format!("cannot start the hash thread: {e}"))?
            .join()
            .map_err(|_| "the hash thread panicked".to_string())?
    })
}

/// Builds the patch firmware with `cfgs` (and generated mesh source) for `target`, runs it,
/// checks its hashes against `expected` and reads its figures.
fn measure(
    target: &str,
    cfgs: &[String],
    mesh: Option<&std::path::Path>,
    expected: &[u32],
) -> Result<OnTarget, String> {
    let elf = crate::tradeoff::build_example_with_cfgs(
        "patch",
        Some(target),
        cfgs,
        mesh.map(|p| ("scanline3d_patch_mesh", p)),
    )?;
    let out = crate::tradeoff::run_on_qemu_with(target, &elf, &[])?;
    let hashes = frame_hashes(&out);
    if hashes != expected {
        return Err(format!(
            "{target} {cfgs:?}: frame hashes {hashes:08x?} differ from the host's {expected:08x?}\n{out}"
        ));
    }
    Ok(OnTarget {
        instructions: mean_frame_instructions(&out),
        peak_active: out
            .lines()
            .filter(|l| l.starts_with("frame "))
            .filter_map(|l| {
                l.split_whitespace()
                    .skip_while(|w| *w != "peak_active")
                    .nth(1)
            })
            .filter_map(|n| n.parse().ok())
            .max()
            .unwrap_or(0),
        workspace: summary_field(&out, "workspace_ram"),
        peak_stack: summary_field(&out, "peak_stack"),
        image: flash_bytes(&elf)?,
    })
}

/// `cargo xtask patch-trade`: the teapot of the patch firmware at every tolerance of
/// [`trade::TOLERANCES`] and as meshes of [`trade::GRIDS`] cells per patch, against the
/// Bezier-clipping reference over the firmware's frames (host, the same code); every tolerance
/// and, for each, the smallest mesh at least as accurate on thumbv7em and thumbv6m under QEMU.
/// Writes `docs/patch-trade.md` and `docs/patch-trade.png`.
pub(crate) fn patch_trade() -> Result<(), String> {
    let tolerances = trade::TOLERANCES;
    let bar = indicatif::ProgressBar::new(
        (FRAMES.len() * (1 + tolerances.len() + trade::GRIDS.len())
            + 2 * TRADE_TARGETS.len() * tolerances.len()) as u64,
    );
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} {msg} ({elapsed})")
            .map_err(|e| e.to_string())?,
    );
    step("the reference, every tolerance and every mesh against it (host)");
    let model = scanline3d_sim::patch::parse::load(&root().join("sim/scenes/patches/teapot.bpt"))?;
    let references = FRAMES
        .iter()
        .map(|&frame| {
            bar.set_message(format!("reference, frame {frame}"));
            let r = trade::reference(&model, frame);
            bar.inc(1);
            r
        })
        .collect::<Result<Vec<_>, String>>()?;
    let side = scanline3d_demo::patches::SIDE;
    let mut patches = Vec::new();
    for tolerance in tolerances {
        bar.set_message(format!("patches at {tolerance} px"));
        let (mut m, mut triangles, mut overflows) = (Mismatches::default(), 0u32, 0u32);
        for (&frame, want) in FRAMES.iter().zip(&references) {
            let (got, made) = trade::patch_frame(frame, tolerance)?;
            if made.dropped > 0 {
                return Err(format!(
                    "{tolerance} px, frame {frame}: {} triangles dropped from the active list",
                    made.dropped
                ));
            }
            m.add(&got, want, side);
            triangles += made.triangles;
            overflows += made.overflows;
            bar.inc(1);
        }
        patches.push((m, f64::from(triangles) / FRAMES.len() as f64, overflows));
    }
    let mut meshes: Vec<(TessellatedMesh, Mismatches)> = Vec::new();
    for cells in trade::GRIDS {
        bar.set_message(format!("mesh {cells}×{cells}"));
        let mesh = trade::tessellate(&model, cells)?;
        let mut m = Mismatches::default();
        for (&frame, want) in FRAMES.iter().zip(&references) {
            m.add(&trade::mesh_frame(&mesh, frame)?, want, side);
            bar.inc(1);
        }
        meshes.push((mesh, m));
    }
    // The meshes to run on the targets: for each tolerance, the smallest as accurate.
    let mut matched: Vec<usize> = patches
        .iter()
        .filter_map(|(m, _, _)| trade::matching_mesh(m, &meshes))
        .filter_map(|(mesh, _)| meshes.iter().position(|(k, _)| k.cells == mesh.cells))
        .collect();
    matched.dedup();
    bar.set_length(bar.length().unwrap_or(0) + (TRADE_TARGETS.len() * matched.len()) as u64);
    step("every tolerance and every matching mesh on QEMU (thumbv7em, thumbv6m)");
    let mut patch_rows = Vec::new();
    for (tolerance, (m, triangles, _)) in tolerances.iter().zip(&patches) {
        let expected = host_patch_hashes(*tolerance)?;
        let cfgs = [format!("scanline3d_patch_tolerance=\"{tolerance}\"")];
        let mut targets = [None; 2];
        for (slot, target) in targets.iter_mut().zip(TRADE_TARGETS) {
            bar.set_message(format!("patches at {tolerance} px: {target}"));
            *slot = Some(measure(target, &cfgs, None, &expected)?);
            bar.inc(1);
        }
        patch_rows.push(TradeRow {
            name: format!("patches, {tolerance} px"),
            accuracy: *m,
            triangles: *triangles,
            data_flash: model.patches.len() * 16 * 3 * 4,
            targets,
        });
    }
    let dir = root().join("target/patch-trade");
    std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let mut mesh_rows = Vec::new();
    for (k, (mesh, m)) in meshes.iter().enumerate() {
        let cells = mesh.cells;
        let mut targets = [None; 2];
        if matched.contains(&k) {
            let path = dir.join(format!("mesh{cells}.rs"));
            std::fs::write(&path, trade::mesh_source(mesh, "cargo xtask patch-trade"))
                .map_err(|e| format!("{}: {e}", path.display()))?;
            let expected = host_mesh_hashes(mesh)?;
            for (slot, target) in targets.iter_mut().zip(TRADE_TARGETS) {
                bar.set_message(format!("mesh {cells}×{cells}: {target}"));
                *slot = Some(measure(target, &[], Some(&path), &expected)?);
                bar.inc(1);
            }
        }
        mesh_rows.push(TradeRow {
            name: format!("mesh {cells}×{cells}"),
            accuracy: *m,
            triangles: mesh.triangles.len() as f64,
            data_flash: mesh.flash_bytes(),
            targets,
        });
    }
    bar.finish_and_clear();
    write_trade(&patch_rows, &patches, &mesh_rows, &meshes)?;
    plot_trade(&patch_rows, &mesh_rows)
}

/// `docs/patch-trade.md`: the table, then per tolerance the patches against the smallest mesh
/// as accurate.
fn write_trade(
    patch_rows: &[TradeRow],
    patches: &[(Mismatches, f64, u32)],
    mesh_rows: &[TradeRow],
    meshes: &[(TessellatedMesh, Mismatches)],
) -> Result<(), String> {
    let side = scanline3d_demo::patches::SIDE;
    let mut md = format!(
        "# Bezier patches against triangle meshes: accuracy and cost per tolerance\n\n{}",
        stamp("cargo xtask patch-trade")
    );
    md += &format!(
        "The Utah teapot of the patch firmware (`firmware/examples/patch.rs`, 32 patches, flat, two-sided, {side}×{side}), at its frames {FRAMES:?} of the turn. \
         **Patches**: the library's scanline patch renderer at each flatness tolerance. **Meshes**: the same teapot tessellated on the host into `n × n` cells per patch \
         (points on the surface at `u, v = i/n`, rounded to I16F16, equal vertices welded, collapsed triangles dropped; `scanline3d_sim::patch::trade::tessellate`), \
         drawn by the mesh path's span z-buffer (`demo::patches::render_mesh_frame`: the same turn, camera and light), triangle ids mapped back to their patch. \
         Both against the f64 Bezier-clipping reference (`sim::patch::render`), pixel by pixel, summed over the three frames ({} pixels): \
         coverage mismatches (covered in one image only), id mismatches (a different patch or coverage), the farthest coverage mismatch from the reference's silhouette \
         (Chebyshev, pixels) and the largest relative eye-depth error where the patch agrees. \
         The host renders run the firmware's code (`scanline3d_demo::patches`); on QEMU every frame hash equals the host's.\n\n\
         **Costs**: triangles per frame (patches: made by the renderer, mean; meshes: in the mesh); data flash: patches 16 control points × 3 I16F16 each (ids are patch \
         indices: no bytes), meshes 3 I16F16 per vertex and 3 `u16` per triangle as `sim export` stores them (a uniform colour; the 33 `u16` triangle ranges that would \
         map triangles to patch ids are not counted); instructions (QEMU, not cycles) per frame, mean over the frames, counted row by row; workspace and peak stack \
         (which includes the workspace) on thumbv7em; firmware image (`.vector_table`, `.text`, `.rodata`, `.data`) on thumbv7em, code included. \
         Meshes are run on the targets only where they match a tolerance (below).\n\n",
        3 * side * side
    );
    md += &trade::table(patch_rows);
    md += &trade::table(mesh_rows)
        .lines()
        .skip(2)
        .fold(String::new(), |s, l| s + l + "\n");
    let overflows: Vec<String> = trade::TOLERANCES
        .iter()
        .zip(patches)
        .filter(|(_, p)| p.2 > 0)
        .map(|(t, p)| format!("{t} px: {}", p.2))
        .collect();
    md += &format!(
        "\nSplits refused because the patch workspace's row buckets (`SUBS` = {}) were full, summed over the frames (the piece is then tessellated whole; the image is the same unless the active list overflows, which did not happen): {}.\n\n",
        scanline3d_demo::patches::SUBS,
        if overflows.is_empty() { "none".to_string() } else { overflows.join(", ") }
    );
    md += "## Against a mesh of the same accuracy\n\n\
           A mesh has **the same accuracy** as the patches at a tolerance when, over the same frames, it has at most as many coverage mismatches **and** at most as many id mismatches against the reference. \
           The mesh compared is the one with the fewest cells per patch (of ";
    md += &format!(
        "{:?}) that does. The issue asks for the patch model's flash at most 1/4 of the mesh's and instructions per frame within 2× of the mesh's.\n\n",
        trade::GRIDS
    );
    md += "| tolerance | mesh of the same accuracy | data flash, patches / mesh | patch data and patch code / mesh data | firmware image, patches / mesh | flash ≤ 1/4 (data; data and code) | thumbv7em instructions, patches / mesh | thumbv6m instructions, patches / mesh | within 2× (thumbv7em, thumbv6m) |\n|---|---|---|---|---|---|---|---|---|\n";
    let yes = |b: bool| if b { "yes" } else { "no" };
    for ((t, p), row) in trade::TOLERANCES.iter().zip(patches).zip(patch_rows) {
        let Some((mesh, _)) = trade::matching_mesh(&p.0, meshes) else {
            md += &format!(
                "| {t} px | none up to {n}×{n} cells per patch | | | | | | | |\n",
                n = trade::GRIDS[trade::GRIDS.len() - 1]
            );
            continue;
        };
        let name = format!("mesh {0}×{0}", mesh.cells);
        let Some(m) = mesh_rows.iter().find(|r| r.name == name) else {
            continue;
        };
        let (Some(a), Some(b)) = (row.targets[0], m.targets[0]) else {
            continue;
        };
        let ratio = |x: f64, y: f64| format!("{:.2}", x / y);
        // The patch firmware's code beyond the mesh firmware's: the difference of the images
        // less the difference of their data.
        let mesh_code = b.image as f64 - m.data_flash as f64;
        let with_code = a.image as f64 - mesh_code;
        let on = |k: usize| match (row.targets[k], m.targets[k]) {
            (Some(x), Some(y)) => (
                ratio(x.instructions, y.instructions),
                x.instructions <= 2.0 * y.instructions,
            ),
            _ => ("—".into(), false),
        };
        let ((v7, ok7), (v6, ok6)) = (on(0), on(1));
        md += &format!(
            "| {t} px | {n}×{n} ({} triangles) | {} / {} B = {} | {} / {} B = {} | {} / {} B = {} | {}; {} | {v7} | {v6} | {}, {} |\n",
            m.triangles,
            thousands(row.data_flash as u64),
            thousands(m.data_flash as u64),
            ratio(row.data_flash as f64, m.data_flash as f64),
            thousands(with_code as u64),
            thousands(m.data_flash as u64),
            ratio(with_code, m.data_flash as f64),
            thousands(a.image),
            thousands(b.image),
            ratio(a.image as f64, b.image as f64),
            yes(4 * row.data_flash <= m.data_flash),
            yes(4.0 * with_code <= m.data_flash as f64),
            yes(ok7),
            yes(ok6),
            n = mesh.cells,
        );
    }
    md += "\n**Patch code**: the patch firmware's image less the mesh firmware's code (its image less its mesh data), so the patch renderer's own code (tessellation, evaluation, row buckets) on top of the control points; the two firmwares share the span z-buffer, runtime and semihosting.\n";
    md += "\nWhere the patch renderer's instructions go: [patch-scanline.md](patch-scanline.md).\n\n![id mismatches against thumbv7em instructions per frame](patch-trade.png)\n";
    let path = root().join("docs/patch-trade.md");
    std::fs::write(&path, md).map_err(|e| format!("{}: {e}", path.display()))?;
    println!("wrote {}", path.display());
    Ok(())
}

/// `docs/patch-trade.png`: thumbv7em instructions per frame (x, log) against id mismatches
/// (y, % of pixels, log), the patches per tolerance and the meshes measured on the target.
fn plot_trade(patch_rows: &[TradeRow], mesh_rows: &[TradeRow]) -> Result<(), String> {
    use crate::tradeoff::{plot_canvas, PLOT_AREA};
    use embedded_graphics::mono_font::{ascii::FONT_6X10, MonoTextStyle};
    use embedded_graphics::pixelcolor::{Rgb888, RgbColor};
    use embedded_graphics::prelude::*;
    use embedded_graphics::primitives::{Circle, Line, PrimitiveStyle};
    use embedded_graphics::text::Text;
    let mut img = plot_canvas(
        "thumbv7em instructions per frame (QEMU, log scale), teapot at 240x240",
        "id mismatches vs the Bezier-clipping reference (% of pixels, log); red: patches, blue: meshes",
    )?;
    let (left, right, top, bottom) = PLOT_AREA;
    let points: Vec<(f64, f64, String, Rgb888)> = patch_rows
        .iter()
        .map(|r| (r, Rgb888::new(200, 40, 40)))
        .chain(mesh_rows.iter().map(|r| (r, Rgb888::new(30, 90, 200))))
        .filter_map(|(r, colour)| {
            let t = r.targets[0]?;
            let ids = 100.0 * r.accuracy.ids as f64 / r.accuracy.pixels.max(1) as f64;
            Some((
                t.instructions.log10(),
                ids.max(1e-4).log10(),
                // The plot's font is ASCII.
                r.name.replace('×', "x"),
                colour,
            ))
        })
        .collect();
    let bounds = |f: fn(&(f64, f64, String, Rgb888)) -> f64| {
        let lo = points.iter().map(f).fold(f64::INFINITY, f64::min).floor();
        let hi = points
            .iter()
            .map(f)
            .fold(f64::NEG_INFINITY, f64::max)
            .ceil();
        (lo, hi.max(lo + 1.0))
    };
    let ((x0, x1), (y0, y1)) = (bounds(|p| p.0), bounds(|p| p.1));
    let px = |x: f64| left + ((x - x0) / (x1 - x0) * (right - left) as f64) as i32;
    let py = |y: f64| bottom - ((y - y0) / (y1 - y0) * (bottom - top) as f64) as i32;
    let black = PrimitiveStyle::with_stroke(Rgb888::BLACK, 1);
    let text = MonoTextStyle::new(&FONT_6X10, Rgb888::BLACK);
    let e = |_| "drawing failed".to_string();
    // Ticks at 1, 2 and 5 of every decade on both axes.
    let mut decade = x0.min(y0);
    while decade <= x1.max(y1) {
        for m in [1.0, 2.0, 5.0] {
            let v = decade + f64::log10(m);
            if (x0..=x1).contains(&v) {
                Text::new(
                    &format!("{:.0}M", 10f64.powf(v) / 1e6),
                    Point::new(px(v) - 10, bottom + 14),
                    text,
                )
                .draw(&mut img)
                .map_err(e)?;
                Line::new(Point::new(px(v), bottom), Point::new(px(v), bottom - 4))
                    .into_styled(black)
                    .draw(&mut img)
                    .map_err(e)?;
            }
            if (y0..=y1).contains(&v) {
                Text::new(
                    &format!("{}", (10f64.powf(v) * 1e4).round() / 1e4),
                    Point::new(8, py(v) + 3),
                    text,
                )
                .draw(&mut img)
                .map_err(e)?;
                Line::new(Point::new(left, py(v)), Point::new(left + 4, py(v)))
                    .into_styled(black)
                    .draw(&mut img)
                    .map_err(e)?;
            }
        }
        decade += 1.0;
    }
    for (x, y, name, colour) in &points {
        let c = Point::new(px(*x), py(*y));
        Circle::with_center(c, 8)
            .into_styled(PrimitiveStyle::with_fill(*colour))
            .draw(&mut img)
            .map_err(e)?;
        // Labels right of their point, or left of it at the right edge.
        let width = 6 * name.len() as i32;
        let dx = if c.x + 8 + width > right {
            -8 - width
        } else {
            8
        };
        Text::new(
            name,
            c + Point::new(dx, -6),
            MonoTextStyle::new(&FONT_6X10, *colour),
        )
        .draw(&mut img)
        .map_err(e)?;
    }
    let path = root().join("docs/patch-trade.png");
    scanline3d_sim::scene::write_png(&path, img.width, img.height, &img.pixels)?;
    println!("wrote {}", path.display());
    Ok(())
}
