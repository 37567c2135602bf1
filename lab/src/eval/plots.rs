//! PSNR-vs-samples plots with `plotters`, as SVG and PNG, their text in a bundled font
//! (`assets/fonts/`: a subset of DejaVu Sans, printable ASCII and a few signs).

use std::path::Path;

use plotters::prelude::*;

use crate::{Error, Result};

/// Series colours, in sampler order (shared by the SVG legend and the PNG).
pub(crate) const PALETTE: [RGBColor; 8] = [
    RGBColor(214, 39, 40),
    RGBColor(31, 119, 180),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
];

/// The series colour of sampler number `k`, as `#rrggbb` (for the HTML legend).
pub(crate) fn colour_hex(k: usize) -> String {
    let RGBColor(r, g, b) = PALETTE[k % PALETTE.len()];
    format!("#{r:02x}{g:02x}{b:02x}")
}

/// The font the plots' text is drawn in (plotters' bitmap backend has no font of its own).
static FONT: &[u8] = include_bytes!("../../../assets/fonts/DejaVuSans-subset.ttf");

/// Registers [`FONT`] as plotters' "sans-serif", once.
fn register_font() -> Result<()> {
    static ONCE: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    let ok = *ONCE.get_or_init(|| {
        plotters::style::register_font("sans-serif", FontStyle::Normal, FONT).is_ok()
    });
    match ok {
        true => Ok(()),
        false => Err(err("the bundled font cannot be read")),
    }
}

fn err<E: std::fmt::Display>(e: E) -> Error {
    Error::Io(std::io::Error::other(format!("plot: {e}")))
}

fn bounds(series: &[(String, Vec<(usize, f64)>)]) -> Option<(f64, f64, f64, f64)> {
    let pts: Vec<(f64, f64)> = series
        .iter()
        .flat_map(|(_, c)| c.iter().map(|&(n, p)| (n as f64, p)))
        .filter(|p| p.0 > 0.0 && p.1.is_finite())
        .collect();
    if pts.is_empty() {
        return None;
    }
    let x0 = pts.iter().map(|p| p.0).fold(f64::INFINITY, f64::min);
    let x1 = pts
        .iter()
        .map(|p| p.0)
        .fold(f64::NEG_INFINITY, f64::max)
        .max(x0 * 1.01);
    let y0 = pts.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
    let y1 = pts
        .iter()
        .map(|p| p.1)
        .fold(f64::NEG_INFINITY, f64::max)
        .max(y0 + 0.1);
    let pad = (y1 - y0) * 0.05;
    Some((x0, x1, y0 - pad, y1 + pad))
}

fn draw<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    title: &str,
    series: &[(String, Vec<(usize, f64)>)],
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(err)?;
    let Some((x0, x1, y0, y1)) = bounds(series) else {
        return root.present().map_err(err);
    };
    let mut chart = ChartBuilder::on(&root)
        .margin(15)
        .caption(title, ("sans-serif", 20))
        .x_label_area_size(40)
        .y_label_area_size(55)
        .build_cartesian_2d((x0..x1).log_scale(), y0..y1)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("samples")
        .y_desc("PSNR (dB)")
        .x_label_formatter(&|v| format!("{v:.0}"))
        .draw()
        .map_err(err)?;
    // Guides drawn as data: every whole dB (every 5 dB on tall ranges) and the square
    // counts (2^k+1)².
    let grey = RGBColor(215, 215, 215);
    let step = if y1 - y0 > 20.0 { 5.0 } else { 1.0 };
    let mut y = (y0 / step).ceil() * step;
    while y <= y1 {
        chart
            .draw_series(LineSeries::new([(x0, y), (x1, y)], grey))
            .map_err(err)?;
        y += step;
    }
    for k in 0..16 {
        let sq = (((1u64 << k) + 1) * ((1u64 << k) + 1)) as f64;
        if sq >= x0 && sq <= x1 {
            chart
                .draw_series(LineSeries::new(
                    [(sq, y0), (sq, y1)],
                    RGBColor(180, 180, 230),
                ))
                .map_err(err)?;
        }
    }
    for (k, (name, curve)) in series.iter().enumerate() {
        let colour = PALETTE[k % PALETTE.len()];
        let pts: Vec<(f64, f64)> = curve.iter().map(|&(n, p)| (n as f64, p)).collect();
        let s = chart
            .draw_series(LineSeries::new(pts.clone(), colour.stroke_width(2)))
            .map_err(err)?;
        s.label(name.as_str()).legend(move |(x, y)| {
            PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
        });
        chart
            .draw_series(pts.iter().map(|&p| Circle::new(p, 2, colour.filled())))
            .map_err(err)?;
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .position(SeriesLabelPosition::LowerRight)
        .draw()
        .map_err(err)?;
    root.present().map_err(err)
}

/// Writes the curves as an SVG and as a PNG, each with title, axes labels, ticks and
/// legend, grey lines at whole dB and blue lines at the square counts.
pub(crate) fn curves(
    svg: &Path,
    png: &Path,
    title: &str,
    series: &[(String, Vec<(usize, f64)>)],
) -> Result<()> {
    register_font()?;
    draw(
        SVGBackend::new(svg, (900, 560)).into_drawing_area(),
        title,
        series,
    )?;
    // Draw into a buffer and save with `image` 0.25 (plotters' own encoder would pull image 0.24).
    let mut buf = vec![255u8; 900 * 560 * 3];
    draw(
        BitMapBackend::with_buffer(&mut buf, (900, 560)).into_drawing_area(),
        title,
        series,
    )?;
    image::RgbImage::from_raw(900, 560, buf)
        .expect("the buffer is 900 × 560 × 3 bytes")
        .save(png)
        .map_err(|e| crate::Error::Io(std::io::Error::other(e)))?;
    Ok(())
}
