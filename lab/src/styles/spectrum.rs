//! Fourier power spectrum of a site set (the paper's Fig. 9).

use image::{GrayImage, Luma};
use rustfft::{num_complex::Complex, FftPlanner};

use super::check;
use crate::Result;
use qcs::sites::Point;

/// Largest spectrum grid side accepted.
const MAX_N: usize = 2048;

/// The power spectrum `|F(u, v)|² / N` of the sites splatted into an `n × n`
/// grid, DC centred: entry `(v + n/2) mod n` row, `(u + n/2) mod n` column, row-major.
///
/// Each site adds 1 to the grid cell `(⌊x·n/W⌋, ⌊y·n/H⌋)` (so the grid has one
/// cell per source pixel when `n = W = H`); the 2D FFT (`rustfft`) of that grid
/// gives `F`. Dividing by the site count `N` makes white noise average 1 and the DC
/// value equal `N`. Frequencies are in cycles per image. `n` must be in `2..=2048`.
///
/// ```
/// let p = qcs_lab::styles::power_spectrum(&[[0.5, 0.5], [5.5, 3.5]], (8, 8), 8).unwrap();
/// assert!((p[4 * 8 + 4] - 2.0).abs() < 1e-9); // DC = N
/// ```
pub fn power_spectrum(positions: &[Point], source: (u32, u32), n: usize) -> Result<Vec<f64>> {
    check(positions, None, source, (1, 1))?;
    if !(2..=MAX_N).contains(&n) {
        return Err(crate::invalid("spectrum size", n, format!("2..={MAX_N}")));
    }
    let mut grid = vec![Complex::new(0.0f64, 0.0); n * n];
    for p in positions {
        let i = ((p[0] / source.0 as f64 * n as f64).floor()).clamp(0.0, (n - 1) as f64) as usize;
        let j = ((p[1] / source.1 as f64 * n as f64).floor()).clamp(0.0, (n - 1) as f64) as usize;
        grid[j * n + i].re += 1.0;
    }
    let fft = FftPlanner::new().plan_fft_forward(n);
    for row in grid.chunks_exact_mut(n) {
        fft.process(row);
    }
    let mut column = vec![Complex::new(0.0, 0.0); n];
    for i in 0..n {
        for j in 0..n {
            column[j] = grid[j * n + i];
        }
        fft.process(&mut column);
        for j in 0..n {
            grid[j * n + i] = column[j];
        }
    }
    let norm = positions.len().max(1) as f64;
    let half = n / 2;
    let mut out = vec![0.0; n * n];
    for v in 0..n {
        for u in 0..n {
            let (su, sv) = ((u + half) % n, (v + half) % n);
            out[sv * n + su] = grid[v * n + u].norm_sqr() / norm;
        }
    }
    Ok(out)
}

/// The power spectrum as an `n × n` greyscale picture, DC at the centre
/// (`(n/2, n/2)`), brightness `log(1 + P) / log(1 + P_max)` with `P_max` the largest
/// non-DC value (the DC spike saturates to white). See [`power_spectrum`].
///
/// ```
/// use qcs_lab::samplers::{Sampler, Random};
/// let img = qcs_lab::styles::spectrum(&Random { seed: 1 }.sites(64, 64, 500), (64, 64), 64).unwrap();
/// assert_eq!(img.get_pixel(32, 32).0, [255]);
/// ```
pub fn spectrum(positions: &[Point], source: (u32, u32), n: usize) -> Result<GrayImage> {
    let p = power_spectrum(positions, source, n)?;
    let dc = (n / 2) * n + n / 2;
    let max = p
        .iter()
        .enumerate()
        .filter(|&(k, _)| k != dc)
        .map(|(_, &v)| v)
        .fold(0.0f64, f64::max);
    let scale = (1.0 + max).ln();
    let size = n as u32;
    Ok(GrayImage::from_fn(size, size, |i, j| {
        let v = p[j as usize * n + i as usize];
        let t = if scale > 0.0 {
            (1.0 + v).ln() / scale
        } else {
            0.0
        };
        Luma([(t.clamp(0.0, 1.0) * 255.0).round() as u8])
    }))
}
