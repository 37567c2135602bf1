//! `qcs eval`: the paper's evaluation of six sampling strategies on images.

use super::Ctx;
use anyhow::{Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct EvalArgs {
    /// Images to evaluate on.
    #[arg(required = true)]
    pub images: Vec<PathBuf>,
    /// Output directory (CSV, plots, panels, index.html).
    #[arg(long)]
    pub out: PathBuf,
    /// Fewer curve points and smaller panels, for a quick look.
    #[arg(long)]
    pub quick: bool,
    /// Seed of the random samplers.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
}

pub fn eval(a: EvalArgs, ctx: &Ctx) -> Result<()> {
    let quiet = ctx.quiet;
    let mut images = Vec::new();
    for p in &a.images {
        let img = super::open_image(p, ctx)?.to_rgb8();
        let name = p
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or("image")
            .to_string();
        images.push((name, img));
    }
    let mut samplers: Vec<Box<dyn qcs_lab::samplers::Sampler + Send + Sync>> =
        vec![super::sampler_by_name("quasicrystal", a.seed).expect("quasicrystal")];
    samplers.extend(qcs_lab::samplers::all(a.seed));
    let mut opts = qcs_lab::eval::EvalOptions::default();
    if a.quick {
        opts.curve_counts = qcs_lab::eval::curve_counts(256, 8192, 12);
        opts.panel_size = 256;
    }
    let bar = if quiet {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(1)
    };
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} {msg}").expect("valid template"),
    );
    let report = qcs_lab::eval::run(&images, &samplers, &a.out, &opts, &mut |p| {
        bar.set_length(p.total as u64);
        bar.set_position(p.done as u64);
        bar.set_message(p.stage.to_string());
    })
    .with_context(|| format!("cannot write the evaluation into {}", a.out.display()))?;
    bar.finish_and_clear();
    if !quiet {
        for c in &report.claims {
            let v = match c.holds {
                Some(true) => "holds",
                Some(false) => "does not hold",
                None => "not checked",
            };
            say!("{v:>14}: {} ({})", c.statement, c.evidence);
        }
        say!("report: {}", a.out.join("index.html").display());
    }
    Ok(())
}
