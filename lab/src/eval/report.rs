//! The evaluation's numbers, claims, CSV files and `index.html`.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::{method_name, roughness, EvalOptions, PSNR_CAP};
use crate::Result;
use qcs::reconstruction::Method;

/// One measurement: PSNR of `image` rebuilt by `method` from `count` sites of `sampler`.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// Image name as given to [`super::run`].
    pub image: String,
    /// [`crate::samplers::Sampler::name`].
    pub sampler: String,
    /// Reconstruction.
    pub method: Method,
    /// Number of sites.
    pub count: usize,
    /// PSNR in dB (`+∞` when identical).
    pub psnr: f64,
}

/// One statement of the paper, checked against the measurements.
#[derive(Clone, Debug, PartialEq)]
pub struct Claim {
    /// The statement.
    pub statement: String,
    /// `Some(true)` holds, `Some(false)` does not hold, `None` could not be checked
    /// (a sampler or count it needs was not measured).
    pub holds: Option<bool>,
    /// The numbers behind the verdict.
    pub evidence: String,
}

/// Everything [`super::run`] measured and wrote.
#[derive(Clone, Debug)]
pub struct Report {
    /// Every measurement.
    pub rows: Vec<Row>,
    /// The paper's claims with verdicts.
    pub claims: Vec<Claim>,
    /// Files written (panels, tables, plots, `index.html`).
    pub files: Vec<PathBuf>,
    samplers: Vec<String>,
    methods: Vec<Method>,
    table_counts: Vec<usize>,
    images: Vec<String>,
    means: BTreeMap<(String, &'static str, usize), f64>,
}

fn fmt_holds(h: Option<bool>) -> &'static str {
    match h {
        Some(true) => "holds",
        Some(false) => "does not hold",
        None => "not checked",
    }
}

fn legend_colour(k: usize) -> String {
    super::plots::colour_hex(k)
}

fn is_square_count(n: usize) -> bool {
    (0..31).any(|k| ((1usize << k) + 1).pow(2) == n)
}

impl Report {
    pub(super) fn new(rows: Vec<Row>, options: &EvalOptions, samplers: Vec<String>) -> Self {
        let mut sums: BTreeMap<(String, &'static str, usize), (f64, usize)> = BTreeMap::new();
        let mut images = Vec::new();
        for r in &rows {
            if !images.contains(&r.image) {
                images.push(r.image.clone());
            }
            let e = sums
                .entry((r.sampler.clone(), method_name(r.method), r.count))
                .or_insert((0.0, 0));
            e.0 += r.psnr.min(PSNR_CAP);
            e.1 += 1;
        }
        let means = sums
            .into_iter()
            .map(|(k, (s, n))| (k, s / n as f64))
            .collect();
        let mut rep = Report {
            rows,
            claims: Vec::new(),
            files: Vec::new(),
            samplers,
            methods: options.methods.clone(),
            table_counts: options.table_counts.clone(),
            images,
            means,
        };
        rep.claims = rep.check_claims();
        rep
    }

    /// Mean PSNR over the images for `sampler`, `method` and `count`, if measured
    /// (`+∞` counted as [`PSNR_CAP`]).
    pub fn mean(&self, sampler: &str, method: Method, count: usize) -> Option<f64> {
        self.means
            .get(&(sampler.to_string(), method_name(method), count))
            .copied()
    }

    /// The mean curve `(count, PSNR)` of `sampler` under `method`, by increasing count.
    pub fn curve(&self, sampler: &str, method: Method) -> Vec<(usize, f64)> {
        self.means
            .iter()
            .filter(|((s, m, _), _)| s == sampler && *m == method_name(method))
            .map(|((_, _, n), v)| (*n, *v))
            .collect()
    }

    fn has(&self, s: &str) -> bool {
        self.samplers.iter().any(|x| x == s)
    }

    fn rough(&self, s: &str, m: Method) -> Option<f64> {
        let c = self.curve(s, m);
        let x: Vec<f64> = c.iter().map(|p| p.0 as f64).collect();
        let y: Vec<f64> = c.iter().map(|p| p.1).collect();
        roughness(&x, &y)
    }

    fn check_claims(&self) -> Vec<Claim> {
        let mut claims = Vec::new();
        let smooth: Vec<&str> = ["quasicrystal", "farthest"]
            .into_iter()
            .filter(|s| self.has(s))
            .collect();
        let grids: Vec<&str> = ["periodic", "jittered"]
            .into_iter()
            .filter(|s| self.has(s))
            .collect();

        // 1. Smooth refinement.
        {
            let mut ev = String::new();
            let mut holds = Some(true);
            if smooth.len() < 2 || grids.is_empty() {
                holds = None;
            }
            for &m in &self.methods {
                let mut worst_smooth = f64::NEG_INFINITY;
                let mut best_grid = f64::INFINITY;
                for s in smooth.iter().chain(&grids) {
                    match self.rough(s, m) {
                        Some(r) => {
                            let _ = write!(ev, "{} {s} {r:.3} dB; ", method_name(m));
                            if smooth.contains(s) {
                                worst_smooth = worst_smooth.max(r);
                            } else {
                                best_grid = best_grid.min(r);
                            }
                        }
                        None => holds = None,
                    }
                }
                if holds.is_some() && worst_smooth >= best_grid {
                    holds = Some(false);
                }
            }
            claims.push(Claim {
                statement: "Quasicrystal and farthest point sampling refine smoothly: their PSNR-vs-samples \
                            curves are less rough (RMS residual from a cubic in log N) than periodic's and jittered's"
                    .into(),
                holds,
                evidence: ev,
            });
        }

        // 2. Periodic best at square counts; 3. drops between them.
        let squares: Vec<usize> = {
            let mut all: Vec<usize> = self
                .means
                .keys()
                .map(|k| k.2)
                .filter(|&n| is_square_count(n))
                .collect();
            all.sort_unstable();
            all.dedup();
            all
        };
        {
            let mut ev = String::new();
            let mut holds =
                if self.has("periodic") && self.samplers.len() > 1 && !squares.is_empty() {
                    Some(true)
                } else {
                    None
                };
            for &m in &self.methods {
                for &n in &squares {
                    let Some(p) = self.mean("periodic", m, n) else {
                        continue;
                    };
                    let best_other = self
                        .samplers
                        .iter()
                        .filter(|s| *s != "periodic")
                        .filter_map(|s| self.mean(s, m, n).map(|v| (v, s.as_str())))
                        .max_by(|a, b| a.0.total_cmp(&b.0));
                    if let Some((v, s)) = best_other {
                        let _ = write!(
                            ev,
                            "{} N={n}: periodic {p:.2} vs best other {s} {v:.2}; ",
                            method_name(m)
                        );
                        if p < v && holds.is_some() {
                            holds = Some(false);
                        }
                    }
                }
            }
            claims.push(Claim {
                statement: "Periodic sampling is the most accurate at the square counts (2^k+1)²"
                    .into(),
                holds,
                evidence: ev,
            });
        }
        {
            let reference: Vec<&str> = if smooth.is_empty() {
                ["halton"].into_iter().filter(|s| self.has(s)).collect()
            } else {
                smooth.clone()
            };
            let mut ev = String::new();
            let mut holds = if self.has("periodic") && !reference.is_empty() {
                Some(true)
            } else {
                None
            };
            for &m in &self.methods {
                let (mut at_sq, mut between) = (Vec::new(), Vec::new());
                for (n, p) in self.curve("periodic", m) {
                    let refs: Vec<f64> = reference
                        .iter()
                        .filter_map(|s| self.mean(s, m, n))
                        .collect();
                    if refs.len() != reference.len() {
                        continue;
                    }
                    let d = p - refs.iter().sum::<f64>() / refs.len() as f64;
                    if is_square_count(n) {
                        at_sq.push(d);
                    } else {
                        between.push(d);
                    }
                }
                if at_sq.is_empty() || between.is_empty() {
                    holds = None;
                    continue;
                }
                let a = at_sq.iter().sum::<f64>() / at_sq.len() as f64;
                let b = between.iter().sum::<f64>() / between.len() as f64;
                let _ = write!(
                    ev,
                    "{}: periodic − mean({}) = {a:+.2} dB at square counts, {b:+.2} dB between; ",
                    method_name(m),
                    reference.join(", ")
                );
                if a - b < 0.1 && holds.is_some() {
                    holds = Some(false);
                }
            }
            claims.push(Claim {
                statement: "Periodic sampling drops between the square counts (its advantage over the smooth \
                            samplers is at least 0.1 dB larger at square counts than between them)"
                    .into(),
                holds,
                evidence: ev,
            });
        }

        // 4. QC beats jittered, quasirandom and random under Shepard at 4225.
        {
            let mut ev = String::new();
            let qc = self.mean("quasicrystal", Method::Shepard, 4225);
            let mut holds = qc.map(|_| true);
            if let Some(q) = qc {
                let _ = write!(ev, "quasicrystal {q:.2}; ");
                for s in ["jittered", "halton", "random"] {
                    match self.mean(s, Method::Shepard, 4225) {
                        Some(v) => {
                            let _ = write!(ev, "{s} {v:.2}; ");
                            if v >= q {
                                holds = Some(false);
                            }
                        }
                        None => {
                            if holds == Some(true) {
                                holds = None
                            }
                        }
                    }
                }
            } else {
                ev.push_str("quasicrystal not measured at 4225 under Shepard");
            }
            claims.push(Claim {
                statement: "Under Shepard interpolation at 4225 samples, quasicrystal sampling beats jittered, \
                            quasirandom (Halton) and random sampling"
                    .into(),
                holds,
                evidence: ev,
            });
        }

        // 5. FPS at least as accurate as QC.
        {
            let mut ev = String::new();
            let mut holds = None;
            for &m in &self.methods {
                for &n in &self.table_counts {
                    if let (Some(f), Some(q)) =
                        (self.mean("farthest", m, n), self.mean("quasicrystal", m, n))
                    {
                        let _ = write!(
                            ev,
                            "{} N={n}: farthest {f:.2} vs quasicrystal {q:.2}; ",
                            method_name(m)
                        );
                        holds = Some(holds.unwrap_or(true) && f >= q);
                    }
                }
            }
            claims.push(Claim {
                statement:
                    "Farthest point sampling is at least as accurate as quasicrystal sampling \
                            (every table count, every reconstruction)"
                        .into(),
                holds,
                evidence: if ev.is_empty() {
                    "farthest or quasicrystal not measured".into()
                } else {
                    ev
                },
            });
        }
        claims
    }

    pub(super) fn write(&mut self, dir: &Path) -> Result<()> {
        let mut csv = String::from("image,sampler,method,samples,psnr\n");
        for r in &self.rows {
            let _ = writeln!(
                csv,
                "{},{},{},{},{:.4}",
                r.image,
                r.sampler,
                method_name(r.method),
                r.count,
                r.psnr
            );
        }
        self.put(dir, "psnr.csv", &csv)?;

        let mut mean = String::from("sampler,method,samples,mean_psnr\n");
        for ((s, m, n), v) in &self.means {
            let _ = writeln!(mean, "{s},{m},{n},{v:.4}");
        }
        self.put(dir, "mean.csv", &mean)?;

        let mut table = format!("method,samples,{}\n", self.samplers.join(","));
        for &m in &self.methods {
            for &n in &self.table_counts {
                let vals: Vec<String> = self
                    .samplers
                    .iter()
                    .map(|s| {
                        self.mean(s, m, n)
                            .map_or(String::new(), |v| format!("{v:.2}"))
                    })
                    .collect();
                let _ = writeln!(table, "{},{n},{}", method_name(m), vals.join(","));
            }
        }
        self.put(dir, "table.csv", &table)?;

        let mut claims = String::from("claim,verdict,evidence\n");
        for c in &self.claims {
            let _ = writeln!(
                claims,
                "\"{}\",{},\"{}\"",
                c.statement,
                fmt_holds(c.holds),
                c.evidence.replace('"', "'")
            );
        }
        self.put(dir, "claims.csv", &claims)?;

        let plots = self.write_plots(dir)?;
        let html = self.html(&plots);
        self.put(dir, "index.html", &html)?;
        Ok(())
    }

    fn put(&mut self, dir: &Path, name: &str, text: &str) -> Result<()> {
        let path = dir.join(name);
        std::fs::write(&path, text)?;
        self.files.push(path);
        Ok(())
    }

    fn write_plots(&mut self, dir: &Path) -> Result<Vec<String>> {
        let mut names = Vec::new();
        for &m in &self.methods.clone() {
            let series: Vec<(String, Vec<(usize, f64)>)> = self
                .samplers
                .iter()
                .map(|s| (s.clone(), self.curve(s, m)))
                .collect();
            let stem = format!("curve-{}", method_name(m));
            let title = format!(
                "PSNR vs samples, {} (mean of {} images)",
                method_name(m),
                self.images.len()
            );
            let svg = dir.join(format!("{stem}.svg"));
            let png = dir.join(format!("{stem}.png"));
            super::plots::curves(&svg, &png, &title, &series)?;
            self.files.push(svg);
            self.files.push(png);
            names.push(stem);
        }
        Ok(names)
    }

    fn html(&self, plots: &[String]) -> String {
        let esc = |s: &str| {
            s.replace('&', "&amp;")
                .replace('<', "&lt;")
                .replace('>', "&gt;")
        };
        let mut h = String::from(
            "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>qcs evaluation</title>\n<style>\
             body{font-family:sans-serif;margin:2em;max-width:1400px}table{border-collapse:collapse;margin:1em 0}\
             td,th{border:1px solid #aaa;padding:3px 8px;text-align:right}th{background:#eee}td.l{text-align:left}\
             .holds{color:#060}.fails{color:#a00}img{max-width:100%;border:1px solid #ccc}\
             .panels td{text-align:center;vertical-align:top}.panels img{width:256px}</style></head><body>\n\
             <h1>Sampling strategies: evaluation</h1>\n",
        );
        let _ = writeln!(
            h,
            "<p>Images: {}. PSNR over R, G, B (8-bit) of the reconstruction at the source size; \
             mean over images, identical pictures counted as {PSNR_CAP} dB. Numbers in <a href=\"psnr.csv\">psnr.csv</a>, \
             <a href=\"mean.csv\">mean.csv</a>, <a href=\"table.csv\">table.csv</a>, <a href=\"claims.csv\">claims.csv</a>.</p>",
            esc(&self.images.join(", "))
        );
        h.push_str("<h2>PSNR (dB) at the paper's counts</h2>\n");
        for &m in &self.methods {
            let _ = write!(h, "<table><tr><th>{}</th>", method_name(m));
            for s in &self.samplers {
                let _ = write!(h, "<th>{}</th>", esc(s));
            }
            h.push_str("</tr>\n");
            for &n in &self.table_counts {
                let best = self
                    .samplers
                    .iter()
                    .filter_map(|s| self.mean(s, m, n))
                    .fold(f64::NEG_INFINITY, f64::max);
                let _ = write!(h, "<tr><th>{n}</th>");
                for s in &self.samplers {
                    match self.mean(s, m, n) {
                        Some(v) if v == best => {
                            let _ = write!(h, "<td><b>{v:.2}</b></td>");
                        }
                        Some(v) => {
                            let _ = write!(h, "<td>{v:.2}</td>");
                        }
                        None => h.push_str("<td>–</td>"),
                    }
                }
                h.push_str("</tr>\n");
            }
            h.push_str("</table>\n");
        }
        h.push_str("<h2>Claims of the paper</h2>\n<table><tr><th>claim</th><th>verdict</th><th>numbers</th></tr>\n");
        for c in &self.claims {
            let class = match c.holds {
                Some(true) => "holds",
                Some(false) => "fails",
                None => "",
            };
            let _ = writeln!(
                h,
                "<tr><td class=\"l\">{}</td><td class=\"l {class}\">{}</td><td class=\"l\">{}</td></tr>",
                esc(&c.statement),
                fmt_holds(c.holds),
                esc(&c.evidence)
            );
        }
        h.push_str("</table>\n<h2>PSNR vs number of samples</h2>\n");
        if plots.is_empty() {
            h.push_str("<p>(no reconstruction measured)</p>\n");
        } else {
            h.push_str("<p>Colours: ");
            for (k, s) in self.samplers.iter().enumerate() {
                let _ = write!(
                    h,
                    "<b style=\"color:{}\">━ {}</b> ",
                    legend_colour(k),
                    esc(s)
                );
            }
            h.push_str("; grey lines every dB (5 dB on tall ranges), blue lines at the square counts (2^k+1)².</p>\n");
        }
        for p in plots {
            let _ = writeln!(
                h,
                "<p><a href=\"{p}.svg\"><img src=\"{p}.svg\" alt=\"{p}\"></a><br><a href=\"{p}.png\">{p}.png</a> (no labels)</p>"
            );
        }
        h.push_str(
            "<h2>Sample sites, mosaic, Voronoi diagram and Fourier power spectrum</h2>\n\
             <table class=\"panels\"><tr><th>sampler</th><th>sites (dark blue first → light green last)</th>\
             <th>mosaic</th><th>Voronoi</th><th>spectrum</th></tr>\n",
        );
        for s in &self.samplers {
            let s = esc(s);
            let _ = write!(h, "<tr><th>{s}</th>");
            for kind in ["sites", "mosaic", "voronoi", "spectrum"] {
                let _ = write!(h, "<td><a href=\"{s}-{kind}.png\"><img src=\"{s}-{kind}.png\" alt=\"{s} {kind}\"></a></td>");
            }
            h.push_str("</tr>\n");
        }
        h.push_str("</table>\n</body></html>\n");
        h
    }
}
