//! `cargo xtask metaball`: the fixed-point metaball ray caster on QEMU for every target, and
//! the polygonizing build on a 16-cell grid on thumbv7em; the frame hashes must equal the
//! host's (`scanline3d_demo::metaballs`, the same code), and the instructions per frame are
//! printed. `cargo xtask metaball-trade`: every method measured against the reference and on
//! thumbv7em and thumbv6m, the table in `docs/metaballs.md` and the plot
//! `docs/metaball-trade.png`.

use crate::*;

/// Frames the firmware example casts (`firmware/examples/metaball.rs`).
const FRAMES: [u32; 3] = [0, 2, 4];

/// The hashes the host computes for the firmware's frames.
fn host_hashes() -> Result<Vec<u32>, String> {
    use scanline3d::sink::HashSink;
    use scanline3d_demo::metaballs::{self, PanelCaster};
    let mut caster = Box::new(PanelCaster::new(
        embedded_graphics::pixelcolor::Rgb565::new(0, 0, 0),
    ));
    FRAMES
        .iter()
        .map(|&frame| {
            let mut sink = HashSink::new();
            metaballs::render_frame(&mut caster, frame, &mut sink)?;
            Ok(sink.hash())
        })
        .collect()
}

pub(crate) fn metaball() -> Result<(), String> {
    let expected = host_hashes()?;
    step("metaball firmware for every target (a no-op when built)");
    build_firmware_examples("firmware", &["metaball"])?;
    for (target, machine) in FIRMWARE {
        step(&format!("metaball ray caster on QEMU {machine}, {target}"));
        let out = run_example(target, "firmware", "metaball")?;
        print!("{out}");
        let hashes = frame_hashes(&out);
        if hashes != expected {
            return Err(format!(
                "{target}: metaball frame hashes {hashes:08x?} differ from the host's {expected:08x?}"
            ));
        }
        println!(
            "metaball frame hashes equal the host's: {expected:08x?}; {:.1} M instructions (QEMU) per frame",
            mean_frame_instructions(&out) / 1e6
        );
    }
    // One polygonizing build, on one target (each build recompiles the example: ~10 s).
    let (target, cfg) = ("thumbv7em-none-eabihf", "poly16");
    step(&format!(
        "metaball polygonization ({cfg}) on QEMU, {target}"
    ));
    let expected = host_polygonized_hashes(cfg)?;
    let elf = crate::tradeoff::build_example_with_cfgs(
        "metaball",
        Some(target),
        &[format!("scanline3d_meta=\"{cfg}\"")],
        None,
    )?;
    let out = crate::tradeoff::run_on_qemu_with(target, &elf, &[])?;
    print!("{out}");
    let hashes = frame_hashes(&out);
    if hashes != expected {
        return Err(format!(
            "{target}, {cfg}: frame hashes {hashes:08x?} differ from the host's {expected:08x?}"
        ));
    }
    println!(
        "polygonized frame hashes equal the host's: {expected:08x?}; {:.1} M instructions (QEMU) per frame",
        mean_frame_instructions(&out) / 1e6
    );
    Ok(())
}

/// The methods `cargo xtask metaball-trade` measures: name, `--cfg` of the firmware example
/// (none: the ray caster), grid cells per axis (0: ray casting).
const METHODS: [(&str, Option<&str>, usize); 5] = [
    ("raycast", None, 0),
    ("polygonize:8", Some("poly8"), 8),
    ("polygonize:16", Some("poly16"), 16),
    ("polygonize:24", Some("poly24"), 24),
    ("polygonize:32", Some("poly32"), 32),
];

/// Targets of the trade table.
const TRADE_TARGETS: [&str; 2] = ["thumbv7em-none-eabihf", "thumbv6m-none-eabi"];

/// The host's hashes of the firmware's frames for a polygonizing build (`cfg` as
/// `firmware/examples/metaball.rs` takes it): the same code, `scanline3d_demo::metaballs`.
fn host_polygonized_hashes(cfg: &str) -> Result<Vec<u32>, String> {
    use scanline3d::sink::HashSink;
    use scanline3d_demo::metaballs::{Poly16, Poly24, Poly32, Poly8};
    macro_rules! hashes {
        ($poly:ty) => {{
            let mut poly: Box<$poly> = Box::new(<$poly>::new(
                embedded_graphics::pixelcolor::Rgb565::new(0, 0, 0),
            ));
            FRAMES
                .iter()
                .map(|&frame| {
                    poly.polygonize(frame)?;
                    let mut sink = HashSink::new();
                    poly.draw(&mut sink)?;
                    Ok(sink.hash())
                })
                .collect::<Result<Vec<u32>, &str>>()
                .map_err(str::to_string)
        }};
    }
    // The panel renderers are built by value (through the stack in debug builds).
    let cfg = cfg.to_string();
    std::thread::Builder::new()
        .stack_size(256 << 20)
        .spawn(move || match cfg.as_str() {
            "poly8" => hashes!(Poly8),
            "poly16" => hashes!(Poly16),
            "poly24" => hashes!(Poly24),
            "poly32" => hashes!(Poly32),
            other => Err(format!("no polygonizing build {other}")),
        })
        .map_err(|e| format!("cannot start the hash thread: {e}"))?
        .join()
        .map_err(|_| "the hash thread panicked".to_string())?
}

/// One method's accuracy over the animation against the reference.
#[derive(Default)]
struct Accuracy {
    coverage_mean: f64,
    coverage_max: f64,
    off_silhouette: usize,
    depth_max: f64,
    depth_mean: f64,
    psnr_min: f64,
    psnr_mean: f64,
    /// Most triangles of a frame (polygonization).
    triangles: u32,
}

/// One method on one target.
struct OnTarget {
    instructions: f64,
    polygonize: f64,
    flash: u64,
    peak_stack: u64,
    renderer_ram: u64,
}

fn mean_of(output: &str, field: &str) -> f64 {
    let values: Vec<f64> = output
        .lines()
        .filter(|l| l.starts_with("frame "))
        .filter_map(|l| {
            let words: Vec<&str> = l.split_whitespace().collect();
            words
                .windows(2)
                .find(|w| w[0] == field)
                .and_then(|w| w[1].parse().ok())
        })
        .collect();
    values.iter().sum::<f64>() / values.len().max(1) as f64
}

/// `cargo xtask metaball-trade`: ray casting and polygonization at several grid sizes, each
/// against the f64 reference over the animation (host, at the firmware's 120×120) and on
/// thumbv7em and thumbv6m under QEMU (instructions per frame, flash, RAM; frame hashes checked
/// against the host's). Writes the table into `docs/metaballs.md` and the plot
/// `docs/metaball-trade.png`.
pub(crate) fn metaball_trade() -> Result<(), String> {
    use scanline3d_sim::metaball::{
        compare::{compare, render_fixed},
        polygonized::render_polygonized,
        reference::Reference,
        MetaScene, SIX_BALLS,
    };
    let side = usize::from(scanline3d_demo::metaballs::SIDE);
    let frames = scanline3d_demo::metaballs::FRAMES;
    let bar = indicatif::ProgressBar::new(
        (METHODS.len() * (frames as usize + TRADE_TARGETS.len())) as u64,
    );
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} {msg} ({elapsed})")
            .map_err(|e| e.to_string())?,
    );
    step("every method against the f64 reference over the animation (host)");
    let scene = MetaScene::parse(SIX_BALLS, "six.meta")?;
    let camera = scanline3d_sim::metaball::corpus()
        .into_iter()
        .find(|c| c.0 == "six")
        .map(|c| c.2)
        .ok_or("no six-ball camera in the corpus")?;
    let references: Vec<_> = (0..frames)
        .map(|frame| {
            let r = Reference::new(&scene, frame, camera.reference()?)?;
            let image = r.render(side, side).0;
            Ok((r, image))
        })
        .collect::<Result<_, String>>()?;
    let mut accuracy = Vec::new();
    for (name, _, cells) in METHODS {
        bar.set_message(format!("{name}: accuracy"));
        let mut a = Accuracy {
            psnr_min: f64::INFINITY,
            ..Accuracy::default()
        };
        for (frame, (reference, expected)) in (0..frames).zip(&references) {
            let image = if cells == 0 {
                render_fixed(&scene, frame, &camera, side, side)?.0
            } else {
                let p = render_polygonized(&scene, frame, &camera, (side, side), cells)?;
                a.triangles = a.triangles.max(p.mesh.triangles);
                p.image
            };
            let m = compare(&image, expected, reference);
            a.coverage_mean += m.coverage_percent() / f64::from(frames);
            a.coverage_max = a.coverage_max.max(m.coverage_percent());
            a.off_silhouette += m.off_silhouette;
            a.depth_max = a.depth_max.max(m.max_depth_error);
            a.depth_mean += m.mean_depth_error / f64::from(frames);
            a.psnr_min = a.psnr_min.min(m.psnr);
            a.psnr_mean += m.psnr / f64::from(frames);
            bar.inc(1);
        }
        accuracy.push(a);
    }
    step("every method on QEMU (thumbv7em, thumbv6m)");
    let mut measured: Vec<Vec<OnTarget>> = Vec::new();
    for (name, cfg, _) in METHODS {
        let expected = match cfg {
            None => host_hashes()?,
            Some(c) => host_polygonized_hashes(c)?,
        };
        let cfgs: Vec<String> = cfg
            .map(|c| format!("scanline3d_meta=\"{c}\""))
            .into_iter()
            .collect();
        let mut row = Vec::new();
        for target in TRADE_TARGETS {
            bar.set_message(format!("{name}: {target}"));
            let elf =
                crate::tradeoff::build_example_with_cfgs("metaball", Some(target), &cfgs, None)?;
            let out = crate::tradeoff::run_on_qemu_with(target, &elf, &[])?;
            let hashes = frame_hashes(&out);
            if hashes != expected {
                return Err(format!(
                    "{target}, {name}: frame hashes {hashes:08x?} differ from the host's {expected:08x?}\n{out}"
                ));
            }
            row.push(OnTarget {
                instructions: mean_of(&out, "instructions"),
                polygonize: mean_of(&out, "polygonize"),
                flash: crate::flash_bytes(&elf)?,
                peak_stack: crate::summary_field(&out, "peak_stack"),
                renderer_ram: crate::summary_field(&out, "renderer_ram")
                    .max(crate::summary_field(&out, "caster_ram")),
            });
            bar.inc(1);
        }
        measured.push(row);
    }
    bar.finish_and_clear();
    write_trade(&accuracy, &measured, side)?;
    plot_trade(&accuracy, &measured)
}

const BEGIN: &str = "<!-- metaball-trade: begin (cargo xtask metaball-trade writes this part) -->";
const END: &str = "<!-- metaball-trade: end -->";

fn write_trade(
    accuracy: &[Accuracy],
    measured: &[Vec<OnTarget>],
    side: usize,
) -> Result<(), String> {
    let mut md = format!(
        "{BEGIN}\n\n{}\nAccuracy: the six-ball animation, frames 0–7, at the firmware's {side}×{side}, against the f64 reference (`sim render six.meta --method M --beside`). Instructions (QEMU, not cycles): mean of the firmware's frames 0, 2, 4 (`firmware/examples/metaball.rs`, hashes equal to the host's); for polygonization, the part spent polygonizing in brackets. RAM: the method's memory (caster, or polygonizer + mesh + span z-buffer) and the peak stack including it (thumbv7em). Flash: the whole firmware image (thumbv7em).\n\n",
        crate::stamp("cargo xtask metaball-trade")
    );
    md += "| method | coverage mismatches mean / max | off silhouette | depth error mean / max | PSNR min / mean | triangles | thumbv7em instructions/frame | thumbv6m instructions/frame | method RAM | peak stack | flash |\n|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (((name, _, cells), a), m) in METHODS.iter().zip(accuracy).zip(measured) {
        let instr = |t: &OnTarget| {
            if *cells == 0 {
                format!("{:.1} M", t.instructions / 1e6)
            } else {
                format!(
                    "{:.1} M ({:.1} M)",
                    t.instructions / 1e6,
                    t.polygonize / 1e6
                )
            }
        };
        md += &format!(
            "| {name} | {:.3} % / {:.3} % | {} | {:.2e} / {:.2e} | {:.1} / {:.1} dB | {} | {} | {} | {} B | {} B | {} B |\n",
            a.coverage_mean,
            a.coverage_max,
            a.off_silhouette,
            a.depth_mean,
            a.depth_max,
            a.psnr_min,
            a.psnr_mean,
            if *cells == 0 { "—".to_string() } else { a.triangles.to_string() },
            instr(&m[0]),
            instr(&m[1]),
            crate::thousands(m[0].renderer_ram),
            crate::thousands(m[0].peak_stack),
            crate::thousands(m[0].flash),
        );
    }
    md +=
        &format!("\n![PSNR against thumbv6m instructions per frame](metaball-trade.png)\n\n{END}");
    let path = root().join("docs/metaballs.md");
    let doc = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    let (Some(start), Some(end)) = (doc.find(BEGIN), doc.find(END)) else {
        return Err(format!("{}: no metaball-trade markers", path.display()));
    };
    let doc = format!("{}{md}{}", &doc[..start], &doc[end + END.len()..]);
    std::fs::write(&path, doc).map_err(|e| format!("{}: {e}", path.display()))?;
    println!("wrote {}", path.display());
    Ok(())
}

/// `docs/metaball-trade.png`: thumbv6m instructions per frame (x, log) against the worst
/// frame's PSNR (y), one point per method.
fn plot_trade(accuracy: &[Accuracy], measured: &[Vec<OnTarget>]) -> Result<(), String> {
    use crate::tradeoff::{plot_canvas, PLOT_AREA};
    use embedded_graphics::mono_font::{ascii::FONT_6X10, MonoTextStyle};
    use embedded_graphics::pixelcolor::{Rgb888, RgbColor};
    use embedded_graphics::prelude::*;
    use embedded_graphics::primitives::{Circle, Line, PrimitiveStyle};
    use embedded_graphics::text::Text;
    let mut img = plot_canvas(
        "thumbv6m instructions per frame (QEMU, log scale), six balls at 120x120",
        "PSNR of the worst animation frame vs the f64 reference (dB)",
    )?;
    let (left, right, top, bottom) = PLOT_AREA;
    let xs: Vec<f64> = measured.iter().map(|m| m[1].instructions.log10()).collect();
    let ys: Vec<f64> = accuracy.iter().map(|a| a.psnr_min).collect();
    let (x0, x1) = (
        xs.iter().copied().fold(f64::INFINITY, f64::min).floor(),
        xs.iter().copied().fold(f64::NEG_INFINITY, f64::max).ceil(),
    );
    let (y0, y1) = (
        (ys.iter().copied().fold(f64::INFINITY, f64::min) / 5.0).floor() * 5.0,
        (ys.iter().copied().fold(f64::NEG_INFINITY, f64::max) / 5.0).ceil() * 5.0,
    );
    let px = |x: f64| left + ((x - x0) / (x1 - x0).max(1e-9) * (right - left) as f64) as i32;
    let py = |y: f64| bottom - ((y - y0) / (y1 - y0).max(1e-9) * (bottom - top) as f64) as i32;
    let black = PrimitiveStyle::with_stroke(Rgb888::BLACK, 1);
    let text = MonoTextStyle::new(&FONT_6X10, Rgb888::BLACK);
    let e = |_| "drawing failed".to_string();
    let mut decade = x0;
    while decade <= x1 {
        for m in [1.0, 2.0, 5.0] {
            let x = decade + f64::log10(m);
            if x > x1 {
                break;
            }
            Text::new(
                &format!("{:.0}M", 10f64.powf(x) / 1e6),
                Point::new(px(x) - 10, bottom + 14),
                text,
            )
            .draw(&mut img)
            .map_err(e)?;
            Line::new(Point::new(px(x), bottom), Point::new(px(x), bottom - 4))
                .into_styled(black)
                .draw(&mut img)
                .map_err(e)?;
        }
        decade += 1.0;
    }
    let mut y = y0;
    while y <= y1 {
        Text::new(&format!("{y:.0}"), Point::new(40, py(y) + 3), text)
            .draw(&mut img)
            .map_err(e)?;
        Line::new(Point::new(left, py(y)), Point::new(left + 4, py(y)))
            .into_styled(black)
            .draw(&mut img)
            .map_err(e)?;
        y += 5.0;
    }
    for (i, (name, _, cells)) in METHODS.iter().enumerate() {
        let colour = if *cells == 0 {
            Rgb888::new(200, 40, 40)
        } else {
            Rgb888::new(30, 90, 200)
        };
        let c = Point::new(px(xs[i]), py(ys[i]));
        Circle::with_center(c, 8)
            .into_styled(PrimitiveStyle::with_fill(colour))
            .draw(&mut img)
            .map_err(e)?;
        Text::new(
            name,
            c + Point::new(8, -6),
            MonoTextStyle::new(&FONT_6X10, colour),
        )
        .draw(&mut img)
        .map_err(e)?;
    }
    let path = root().join("docs/metaball-trade.png");
    scanline3d_sim::scene::write_png(&path, img.width, img.height, &img.pixels)?;
    println!("wrote {}", path.display());
    Ok(())
}
