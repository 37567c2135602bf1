//! The paper's Fig. 7: sites as dots coloured by their place in the sequence.

use image::{Rgb, RgbImage};

use super::{check, Scale};
use crate::Result;
use qcs::sites::Point;

/// Ramp from dark blue (first) to light green (last).
const RAMP: [[f64; 3]; 6] = [
    [8.0, 29.0, 88.0],
    [34.0, 94.0, 168.0],
    [29.0, 145.0, 192.0],
    [65.0, 182.0, 196.0],
    [127.0, 205.0, 187.0],
    [199.0, 233.0, 180.0],
];

/// The colour of position `t ∈ [0, 1]` in the sequence: dark blue at 0, light green at 1.
///
/// ```
/// assert_eq!(qcs_lab::styles::order_colour(0.0), [8, 29, 88]);
/// assert_eq!(qcs_lab::styles::order_colour(1.0), [199, 233, 180]);
/// ```
pub fn order_colour(t: f64) -> [u8; 3] {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let x = t * (RAMP.len() - 1) as f64;
    let k = (x.floor() as usize).min(RAMP.len() - 2);
    let f = x - k as f64;
    let mut c = [0u8; 3];
    for (ch, o) in c.iter_mut().enumerate() {
        *o = (RAMP[k][ch] + f * (RAMP[k + 1][ch] - RAMP[k][ch])).round() as u8;
    }
    c
}

/// Every site as a round dot on white, coloured by its index with
/// [`order_colour`] (later sites drawn on top). The dot radius is 30% of the
/// mean spacing `√(w·h/N)` of the output, at least 1 px.
///
/// ```
/// let sites = [[2.0, 2.0], [7.0, 7.0]];
/// let img = qcs_lab::styles::order(&sites, (10, 10), (10, 10)).unwrap();
/// assert_eq!(img.get_pixel(2, 2).0, [8, 29, 88]);
/// assert_eq!(img.get_pixel(7, 7).0, [199, 233, 180]);
/// assert_eq!(img.get_pixel(0, 9).0, [255, 255, 255]);
/// ```
pub fn order(positions: &[Point], source: (u32, u32), output: (u32, u32)) -> Result<RgbImage> {
    check(positions, None, source, output)?;
    let frame = Scale::new(source, output);
    let mut img = RgbImage::from_pixel(output.0, output.1, Rgb([255, 255, 255]));
    let n = positions.len();
    if n == 0 {
        return Ok(img);
    }
    let r = (0.3 * (output.0 as f64 * output.1 as f64 / n as f64).sqrt()).max(1.0);
    for (k, p) in positions.iter().enumerate() {
        let c = order_colour(if n > 1 {
            k as f64 / (n - 1) as f64
        } else {
            0.0
        });
        let q = frame.to_out(*p);
        let i0 = (q[0] - r).floor().max(0.0) as i64;
        let i1 = (q[0] + r).ceil().min(output.0 as f64 - 1.0) as i64;
        let j0 = (q[1] - r).floor().max(0.0) as i64;
        let j1 = (q[1] + r).ceil().min(output.1 as f64 - 1.0) as i64;
        for j in j0..=j1 {
            for i in i0..=i1 {
                let (dx, dy) = (i as f64 + 0.5 - q[0], j as f64 + 0.5 - q[1]);
                if dx * dx + dy * dy <= r * r {
                    img.put_pixel(i as u32, j as u32, Rgb(c));
                }
            }
        }
    }
    Ok(img)
}
