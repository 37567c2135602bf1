//! Image fidelity and curve statistics.

use crate::Result;

/// PSNR in dB between two RGB8 buffers of equal length (interleaved R, G, B):
/// `10·log10(255² / MSE)` with the MSE over all bytes (all pixels, all three
/// channels). Identical buffers give `f64::INFINITY`.
pub fn psnr_bytes(a: &[u8], b: &[u8]) -> Result<f64> {
    if a.len() != b.len() || a.is_empty() {
        return Err(crate::invalid(
            "buffers",
            format_args!("{} and {} bytes", a.len(), b.len()),
            "two of the same non-zero length",
        ));
    }
    let sse: u64 = a
        .iter()
        .zip(b)
        .map(|(&x, &y)| {
            let d = x as i64 - y as i64;
            (d * d) as u64
        })
        .sum();
    if sse == 0 {
        return Ok(f64::INFINITY);
    }
    let mse = sse as f64 / a.len() as f64;
    Ok(10.0 * (255.0 * 255.0 / mse).log10())
}

/// PSNR of two RGB images of the same size; see [`psnr_bytes`].
pub fn psnr(a: &image::RgbImage, b: &image::RgbImage) -> Result<f64> {
    if a.dimensions() != b.dimensions() {
        return Err(crate::invalid(
            "images",
            format_args!("{:?} and {:?}", a.dimensions(), b.dimensions()),
            "two of the same size",
        ));
    }
    psnr_bytes(a.as_raw(), b.as_raw())
}

/// Roughness of a curve: the RMS residual (in the units of `y`) of the
/// least-squares cubic in `log2 x`. A smooth, slowly bending curve scores near 0;
/// a staircase or saw-tooth scores its tooth height.
///
/// Needs at least 5 points with positive `x`; otherwise returns `None`.
pub fn roughness(x: &[f64], y: &[f64]) -> Option<f64> {
    let pts: Vec<(f64, f64)> = x
        .iter()
        .zip(y)
        .filter(|(a, b)| **a > 0.0 && b.is_finite())
        .map(|(a, b)| (a.log2(), *b))
        .collect();
    if pts.len() < 5 {
        return None;
    }
    // Centre and scale t for conditioning.
    let mean = pts.iter().map(|p| p.0).sum::<f64>() / pts.len() as f64;
    let span = pts
        .iter()
        .map(|p| (p.0 - mean).abs())
        .fold(0.0, f64::max)
        .max(1e-12);
    let mut ata = [[0.0f64; 4]; 4];
    let mut aty = [0.0f64; 4];
    for &(t, v) in &pts {
        let t = (t - mean) / span;
        let row = [1.0, t, t * t, t * t * t];
        for i in 0..4 {
            aty[i] += row[i] * v;
            for j in 0..4 {
                ata[i][j] += row[i] * row[j];
            }
        }
    }
    let c = solve4(ata, aty)?;
    let sse: f64 = pts
        .iter()
        .map(|&(t, v)| {
            let t = (t - mean) / span;
            let f = c[0] + c[1] * t + c[2] * t * t + c[3] * t * t * t;
            (v - f).powi(2)
        })
        .sum();
    Some((sse / pts.len() as f64).sqrt())
}

#[allow(clippy::needless_range_loop)]
fn solve4(mut a: [[f64; 4]; 4], mut b: [f64; 4]) -> Option<[f64; 4]> {
    for col in 0..4 {
        let piv = (col..4).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[piv][col].abs() < 1e-12 {
            return None;
        }
        a.swap(col, piv);
        b.swap(col, piv);
        for r in 0..4 {
            if r != col {
                let f = a[r][col] / a[col][col];
                for k in col..4 {
                    a[r][k] -= f * a[col][k];
                }
                b[r] -= f * b[col];
            }
        }
    }
    Some([
        b[0] / a[0][0],
        b[1] / a[1][1],
        b[2] / a[2][2],
        b[3] / a[3][3],
    ])
}

/// Value checks of this file's items, as unit tests rather than doc tests (each doc test is
/// a binary of its own to build, and these teach nothing the prose does not say).
#[cfg(test)]
mod doc_examples {
    #[test]
    fn psnr_bytes_of_known_errors() {
        let a = [0u8, 0, 0, 10, 10, 10];
        let b = [0u8, 0, 0, 10, 10, 12];
        // MSE = 4/6, so PSNR = 10·log10(255²·6/4).
        let want = 10.0 * (255.0f64 * 255.0 * 1.5).log10();
        assert!((crate::eval::psnr_bytes(&a, &b).unwrap() - want).abs() < 1e-12);
        assert_eq!(crate::eval::psnr_bytes(&a, &a).unwrap(), f64::INFINITY);
    }

    #[test]
    fn psnr_of_images() {
        let a = image::RgbImage::from_pixel(4, 4, image::Rgb([100, 100, 100]));
        let b = image::RgbImage::from_pixel(4, 4, image::Rgb([101, 101, 101]));
        assert!((crate::eval::psnr(&a, &b).unwrap() - 48.1308).abs() < 1e-3);
        assert!(crate::eval::psnr(&a, &image::RgbImage::new(2, 2)).is_err());
    }

    #[test]
    fn roughness_of_smooth_and_sawtooth_curves() {
        let x: Vec<f64> = (1..=20).map(|k| (k * 100) as f64).collect();
        let smooth: Vec<f64> = x.iter().map(|v| 3.0 * v.log2()).collect();
        let saw: Vec<f64> = smooth
            .iter()
            .enumerate()
            .map(|(k, v)| v + if k % 2 == 0 { 0.5 } else { -0.5 })
            .collect();
        assert!(crate::eval::roughness(&x, &smooth).unwrap() < 1e-9);
        assert!(crate::eval::roughness(&x, &saw).unwrap() > 0.3);
    }
}
