//! `qcs sites`: a sampler's sites as CSV.

use anyhow::{bail, Result};
use clap::Args;
use qcs::sites::Quasicrystal;
use std::io::Write;

#[derive(Args, Debug)]
pub struct SitesArgs {
    /// Image width in pixels (1–65535).
    #[arg(long, value_parser = super::parse_side)]
    pub width: u32,
    /// Image height in pixels (1–65535).
    #[arg(long, value_parser = super::parse_side)]
    pub height: u32,
    /// Number of sites.
    #[arg(long, value_parser = super::parse_count)]
    pub count: usize,
    /// Sampling strategy: quasicrystal, periodic, jittered, halton, random, farthest.
    #[arg(long, default_value = "quasicrystal", value_parser = clap::builder::PossibleValuesParser::new(super::SAMPLERS))]
    pub sampler: String,
    /// Seed of the random strategies.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
}

pub fn run(a: SitesArgs, ctx: &super::Ctx) -> Result<()> {
    ctx.limits
        .check_samples(a.count as u64)
        .map_err(qcs::Error::from)?;
    let out = std::io::stdout();
    let mut out = std::io::BufWriter::new(out.lock());
    if a.sampler == "quasicrystal" {
        let q = Quasicrystal::new(a.width, a.height)?;
        writeln!(out, "index,x,y,n0,n1,n2,n3")?;
        for (i, s) in q.first(a.count).iter().enumerate() {
            let [n0, n1, n2, n3] = s.lattice.0;
            writeln!(
                out,
                "{i},{:.6},{:.6},{n0},{n1},{n2},{n3}",
                s.pos[0], s.pos[1]
            )?;
        }
        out.flush()?;
        return Ok(());
    }
    let Some(sampler) = super::sampler_by_name(&a.sampler, a.seed) else {
        bail!(
            "unknown sampler {:?} (quasicrystal, periodic, jittered, halton, random, farthest)",
            a.sampler
        );
    };
    writeln!(out, "index,x,y")?;
    for (i, p) in sampler.sites(a.width, a.height, a.count).iter().enumerate() {
        writeln!(out, "{i},{:.6},{:.6}", p[0], p[1])?;
    }
    out.flush()?;
    Ok(())
}
