//! What a sample's colour is: how the encoder reads the source image at a site.
//!
//! Measured on the dev photographs (see the README): the fitted colours give the best
//! previews at every byte budget and a better full decode than the progressive area mean they
//! start from; the plain area mean gives the best full decode with exact colours.

use crate::reconstruction::{Method, RenderOptions, SampleSet};
use crate::sites::{Frame, Point, Site};

/// Scale of the [`SampleColour::Progressive`] box relative to the site spacing at its first
/// appearance. 0.4 beat 0.5, 0.6, 0.85 and 1.0 at every byte budget from 512 B up on the dev
/// photographs with the predictive coding (within 0.05 dB below), see `examples/rd.rs`.
pub const PROGRESSIVE_SCALE: f64 = 0.4;

/// [`SampleColour::Fitted`]: the side of the box over which the residual is averaged,
/// relative to the [`SampleColour::Progressive`] box, and the share of that mean added. On the
/// dev photographs at quality 50 (`examples/rd.rs`), boxes of 1.5–2.5 and shares of 0.5–1
/// were within 0.05 dB of each other at every budget; 2 and 0.75 were the best overall, and a
/// second correction step did worse than one.
pub const FIT_BOX: f64 = 2.0;
/// See [`FIT_BOX`].
pub const FIT_SHARE: f64 = 0.75;

/// How a site's colour is taken from the source image.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum SampleColour {
    /// The pixel that contains the site.
    Nearest,
    /// Bilinear interpolation between the four nearest pixel centres.
    Bilinear,
    /// Mean over a box of the area one site covers at the final count N
    /// (side `√(W·H/N)` centred on the site).
    Area,
    /// Mean over a box scaled to the area the site covers when it first appears: the k-th site
    /// (0-based) averages a box of side `0.4·√(W·H/(k+1))` ([`PROGRESSIVE_SCALE`]), never
    /// smaller than [`Self::Area`]'s.
    /// Early samples are prefiltered for the sparse preview they belong to.
    Progressive,
    /// [`Self::Progressive`], then corrected stretch by stretch for the Gouraud picture a
    /// decoder draws when the stretch is complete (the encoder's default). The stretches are
    /// the file's levels, with the first level split in halves three times: for L0 = 127,
    /// samples 16..32, 32..64, 64..127, 127..254, 254..508 and so on (the first 16 keep their
    /// progressive colours). Once a stretch has its progressive colours, the encoder renders
    /// the samples so far (Gouraud at the source size) and adds to each of the stretch's
    /// colours [`FIT_SHARE`] × the mean of (image − render) over a box [`FIT_BOX`] times the
    /// progressive one: one damped back-projection step towards the colours whose picture
    /// matches the image best.
    ///
    /// The correction is open loop: the render uses the earlier samples' corrected colours,
    /// not their decoded ones, so that it undoes the interpolation's error and not the
    /// quantiser's (which, fed back, put isolated bright dots in flat skies). It needs the
    /// level structure, so [`SourceImage::fitted`] computes it; [`SourceImage::colours`]
    /// gives the progressive colours for this rule.
    #[default]
    Fitted,
}

/// An image prepared for sampling: interleaved 8-bit channels plus a summed-area table.
///
/// ```
/// use qcs::sampling::{SampleColour, SourceImage};
/// let pixels = vec![10u8, 20, 30, 40]; // 2×2 grey
/// let s = SourceImage::new(&pixels, 2, 2, 1)?;
/// assert_eq!(s.colours(&[[0.5, 0.5]], SampleColour::Nearest, 1), vec![10]);
/// assert_eq!(s.colours(&[[1.0, 1.0]], SampleColour::Bilinear, 1), vec![25]);
/// assert_eq!(s.colours(&[[1.0, 1.0]], SampleColour::Area, 1), vec![25]);
/// assert!(SourceImage::new(&pixels, 3, 2, 1).is_err());
/// # Ok::<(), qcs::Error>(())
/// ```
pub struct SourceImage<'a> {
    pixels: &'a [u8],
    width: usize,
    height: usize,
    channels: usize,
    /// (W+1)×(H+1)×C prefix sums.
    sat: Vec<u64>,
}

impl<'a> SourceImage<'a> {
    /// Wraps `pixels` (`width × height × channels`, row-major, interleaved).
    ///
    /// A buffer of another length, or an empty image, is [`crate::Error::Parameter`].
    pub fn new(pixels: &'a [u8], width: u32, height: u32, channels: usize) -> crate::Result<Self> {
        let (w, h, c) = (width as usize, height as usize, channels);
        if w == 0
            || h == 0
            || c == 0
            || w.checked_mul(h).and_then(|p| p.checked_mul(c)) != Some(pixels.len())
        {
            return Err(crate::Error::Parameter(format!(
                "pixel buffer of {} bytes for a {width}×{height}×{channels} image",
                pixels.len()
            )));
        }
        let stride = (w + 1) * c;
        let mut sat = vec![0u64; (w + 1) * (h + 1) * c];
        for y in 0..h {
            let mut row = vec![0u64; c];
            for x in 0..w {
                for k in 0..c {
                    row[k] += pixels[(y * w + x) * c + k] as u64;
                    sat[(y + 1) * stride + (x + 1) * c + k] =
                        sat[y * stride + (x + 1) * c + k] + row[k];
                }
            }
        }
        Ok(SourceImage {
            pixels,
            width: w,
            height: h,
            channels: c,
            sat,
        })
    }

    fn box_mean(&self, (x0, y0, x1, y1): (usize, usize, usize, usize), out: &mut Vec<u8>) {
        let stride = (self.width + 1) * self.channels;
        let n = ((x1 - x0) * (y1 - y0)) as u64;
        for k in 0..self.channels {
            let at = |x: usize, y: usize| self.sat[y * stride + x * self.channels + k];
            let s = at(x1, y1) + at(x0, y0) - at(x0, y1) - at(x1, y0);
            out.push(((s + n / 2) / n) as u8);
        }
    }

    fn pixel(&self, x: usize, y: usize, k: usize) -> u8 {
        self.pixels[(y * self.width + x) * self.channels + k]
    }

    /// The colours of `sites` (in sequence order) for a file of `total` samples.
    pub fn colours(&self, sites: &[Point], rule: SampleColour, total: usize) -> Vec<u8> {
        let (w, h) = (self.width as f64, self.height as f64);
        let mut out = Vec::with_capacity(sites.len() * self.channels);
        let final_side = (w * h / total.max(1) as f64).sqrt();
        for (k, p) in sites.iter().enumerate() {
            let ix = (p[0].floor().max(0.0) as usize).min(self.width - 1);
            let iy = (p[1].floor().max(0.0) as usize).min(self.height - 1);
            match rule {
                SampleColour::Nearest => {
                    for c in 0..self.channels {
                        out.push(self.pixel(ix, iy, c));
                    }
                }
                SampleColour::Bilinear => {
                    let fx = (p[0] - 0.5).clamp(0.0, w - 1.0);
                    let fy = (p[1] - 0.5).clamp(0.0, h - 1.0);
                    let (x0, y0) = (fx.floor() as usize, fy.floor() as usize);
                    let (x1, y1) = ((x0 + 1).min(self.width - 1), (y0 + 1).min(self.height - 1));
                    let (tx, ty) = (fx - x0 as f64, fy - y0 as f64);
                    for c in 0..self.channels {
                        let v = (1.0 - ty)
                            * ((1.0 - tx) * self.pixel(x0, y0, c) as f64
                                + tx * self.pixel(x1, y0, c) as f64)
                            + ty * ((1.0 - tx) * self.pixel(x0, y1, c) as f64
                                + tx * self.pixel(x1, y1, c) as f64);
                        out.push(v.round().clamp(0.0, 255.0) as u8);
                    }
                }
                SampleColour::Area => self.box_mean(self.around(*p, final_side), &mut out),
                SampleColour::Progressive | SampleColour::Fitted => {
                    let side = self.progressive_side(k, total);
                    self.box_mean(self.around(*p, side), &mut out);
                }
            }
        }
        out
    }

    /// The side of the [`SampleColour::Progressive`] box of the `k`-th site of `total`.
    fn progressive_side(&self, k: usize, total: usize) -> f64 {
        let area = (self.width * self.height) as f64;
        let final_side = (area / total.max(1) as f64).sqrt();
        (PROGRESSIVE_SCALE * (area / (k + 1) as f64).sqrt()).max(final_side)
    }

    /// The pixels `(x0, y0, x1, y1)` (exclusive ends) of a box of `side` centred on `p`,
    /// within the image and never empty: it holds the pixel containing `p`.
    fn around(&self, p: Point, side: f64) -> (usize, usize, usize, usize) {
        let (w, h) = (self.width as f64, self.height as f64);
        let ix = (p[0].floor().max(0.0) as usize).min(self.width - 1);
        let iy = (p[1].floor().max(0.0) as usize).min(self.height - 1);
        let half = side / 2.0;
        let x0 = ((p[0] - half).round().max(0.0) as usize).min(ix);
        let y0 = ((p[1] - half).round().max(0.0) as usize).min(iy);
        let x1 = ((p[0] + half).round().min(w) as usize).max(ix + 1);
        let y1 = ((p[1] + half).round().min(h) as usize).max(iy + 1);
        (x0, y0, x1, y1)
    }

    /// The [`SampleColour::Fitted`] colours of `sites`, the first sites (in sequence order)
    /// of a file of `total` samples in the lattice frame `frame`, whose first level holds
    /// `first_level` samples (each later level ends at twice the count, spec/format.md):
    /// see [`SampleColour::Fitted`].
    ///
    /// ```
    /// use qcs::sampling::{SampleColour, SourceImage};
    /// use qcs::sites::Quasicrystal;
    /// let pixels: Vec<u8> = (0..64 * 64).map(|i| (i % 64 * 3 + i / 64) as u8).collect();
    /// let src = SourceImage::new(&pixels, 64, 64, 1)?;
    /// let seq = Quasicrystal::new(64, 64)?;
    /// let sites = seq.first(400);
    /// let pos: Vec<_> = sites.iter().map(|s| s.pos).collect();
    /// let fitted = src.fitted(&sites, seq.frame(), 50, 400);
    /// let progressive = src.colours(&pos, SampleColour::Progressive, 400);
    /// assert_eq!(fitted[..7], progressive[..7]); // the first ⌈50 / 8⌉ are not corrected
    /// assert_ne!(fitted, progressive);
    /// // A flat image needs no correction.
    /// let flat = SourceImage::new(&[77; 64 * 64], 64, 64, 1)?;
    /// assert_eq!(flat.fitted(&sites, seq.frame(), 50, 400), vec![77; 400]);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn fitted(
        &self,
        sites: &[Site],
        frame: Frame,
        first_level: usize,
        total: usize,
    ) -> Vec<u8> {
        let c = self.channels;
        let positions: Vec<Point> = sites.iter().map(|s| s.pos).collect();
        let mut colours = self.colours(&positions, SampleColour::Progressive, total);
        let mut set = SampleSet::new(self.width as u32, self.height as u32, c).with_frame(frame);
        // The ends of the corrected stretches: the file's level ends, with the first level
        // split in halves three times (L0 = 127: 16, 32, 64, 127, 254, 508, …).
        let n = sites.len();
        let l0 = first_level.clamp(1, n.max(1));
        let split = (1..=3).rev().map(|d| l0.div_ceil(1 << d));
        let levels = std::iter::successors(Some(l0), |&e| (e < n).then(|| e.saturating_mul(2)));
        let mut s = 0;
        for e in split.chain(levels).map(|e| e.min(n)) {
            if e <= s {
                continue;
            }
            for (site, colour) in sites[s..e].iter().zip(colours[s * c..].chunks_exact(c)) {
                set.push_site(site, colour);
            }
            if set.len() != e {
                break; // A site the set could not take: leave the rest uncorrected.
            }
            if s > 0 {
                let level = &mut colours[s * c..e * c];
                self.correct(&mut set, s, level, total);
                set.recolour(s, level);
            }
            s = e;
        }
        colours
    }

    /// The correction of [`SampleColour::Fitted`] for the last samples of `set`, the sites
    /// `first..` of a file of `total`, whose colours are `colours` (in the set too).
    fn correct(&self, set: &mut SampleSet, first: usize, colours: &mut [u8], total: usize) {
        let (w, h, c) = (self.width, self.height, self.channels);
        let render = set.render_with(
            Method::Gouraud,
            w as u32,
            h as u32,
            RenderOptions::default(),
        );
        // Prefix sums of the residual, as those of the image in `new`.
        let stride = (w + 1) * c;
        let mut sat = vec![0i64; stride * (h + 1)];
        let mut row = vec![0i64; c];
        for y in 0..h {
            row.fill(0);
            for x in 0..w {
                for k in 0..c {
                    let i = (y * w + x) * c + k;
                    row[k] += self.pixels[i] as i64 - render[i] as i64;
                    sat[(y + 1) * stride + (x + 1) * c + k] =
                        sat[y * stride + (x + 1) * c + k] + row[k];
                }
            }
        }
        for (j, col) in colours.chunks_exact_mut(c).enumerate() {
            let k = first + j;
            let side = FIT_BOX * self.progressive_side(k, total);
            let (x0, y0, x1, y1) = self.around(set.positions()[k], side);
            let n = ((x1 - x0) * (y1 - y0)) as f64;
            for (ch, v) in col.iter_mut().enumerate() {
                let at = |x: usize, y: usize| sat[y * stride + x * c + ch];
                let sum = at(x1, y1) + at(x0, y0) - at(x0, y1) - at(x1, y0);
                *v = (*v as f64 + FIT_SHARE * sum as f64 / n)
                    .round()
                    .clamp(0.0, 255.0) as u8;
            }
        }
    }
}
