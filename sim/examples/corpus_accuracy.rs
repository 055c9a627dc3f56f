//! Accuracy of every trade-off variant (the presets, the default and the single knobs) against
//! the f64 reference, summed over every corpus scene and camera at 240×240: the figures a
//! change to the set-up arithmetic must not make worse (mean id mismatches, real mismatches,
//! pixels beyond the depth bound), without the target runs and benchmarks of
//! `cargo xtask tradeoff`.
//!
//! ```sh
//! cargo run --release -p scanline3d-sim --example corpus_accuracy
//! ```

use scanline3d_sim::tradeoff::{corpus_accuracy, VARIANTS};

fn main() -> Result<(), String> {
    let all = corpus_accuracy(240, 240, |done, total| eprint!("\r{done}/{total} views"))?;
    eprintln!();
    println!("| variant | views | id mismatches (pixels) | mean / worst view | real | depth beyond bound | worst colour PSNR | largest channel error |");
    println!("|---|---:|---:|---|---:|---:|---:|---:|");
    for v in VARIANTS {
        let of: Vec<_> = all.iter().filter(|a| a.variant == v.name).collect();
        let views = of.len().max(1) as f64;
        let mean = of
            .iter()
            .map(|a| a.metrics.id_mismatch_percent())
            .sum::<f64>()
            / views;
        let worst = of
            .iter()
            .map(|a| a.metrics.id_mismatch_percent())
            .fold(0.0, f64::max);
        let sum = |f: fn(&scanline3d_sim::metrics::Metrics) -> usize| {
            of.iter().map(|a| f(&a.metrics)).sum::<usize>()
        };
        let psnr = of
            .iter()
            .map(|a| a.metrics.psnr)
            .fold(f64::INFINITY, f64::min);
        let colour = of.iter().map(|a| a.metrics.color_max).max().unwrap_or(0);
        println!(
            "| {} | {} | {} | {mean:.4} % / {worst:.3} % | {} | {} | {psnr:.2} dB | {colour} |",
            v.name,
            of.len(),
            sum(|m| m.id_mismatches),
            sum(|m| m.real),
            sum(|m| m.depth_beyond_bound),
        );
    }
    Ok(())
}
