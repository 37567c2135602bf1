//! What a sample's colour is: how the encoder reads the source image at a site.
//!
//! Measured on the dev photographs (MEASUREMENTS.md): the fitted colours give the best
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
/// [`SampleColour::Fitted`] corrects only the stretches that end at or before this many
/// samples (the later ones keep their progressive colours), which bounds the encoder's extra
/// memory to a triangulation of this many samples (about 100 MB).
pub const FIT_SAMPLES: usize = 1 << 18;
/// [`SampleColour::Fitted`] compares renders of at most this many pixels with the image: a
/// larger image is compared at its size divided by the least integer that brings it under
/// (its box means), which bounds the work of a correction.
pub const FIT_PIXELS: usize = 1 << 22;

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
    /// (0-based) averages a box of side `0.4·√(W·H/(k+1))` (`PROGRESSIVE_SCALE`), never
    /// smaller than [`Self::Area`]'s.
    /// Early samples are prefiltered for the sparse preview they belong to.
    Progressive,
    /// [`Self::Progressive`], then corrected stretch by stretch for the Gouraud picture a
    /// decoder draws when the stretch is complete (the encoder's default). The stretches are
    /// the file's levels, with the first level split in halves three times: for L0 = 127,
    /// samples 16..32, 32..64, 64..127, 127..254, 254..508 and so on (the first 16 keep their
    /// progressive colours). Once a stretch has its progressive colours, the encoder renders
    /// the samples so far (Gouraud at the source size) and adds to each of the stretch's
    /// colours `FIT_SHARE` × the mean of (image − render) over a box `FIT_BOX` times the
    /// progressive one: one damped back-projection step towards the colours whose picture
    /// matches the image best. Only the stretches within the first `FIT_SAMPLES` samples are
    /// corrected, and an image above `FIT_PIXELS` pixels is compared at a reduced size, so
    /// that the cost stays bounded.
    ///
    /// The correction is open loop: the render uses the earlier samples' corrected colours,
    /// not their decoded ones, so that it undoes the interpolation's error and not the
    /// quantiser's (which, fed back, put isolated bright dots in flat skies). It needs the
    /// level structure, so `SourceImage::fitted` computes it; `SourceImage::colours`
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
    /// (W+1)×(H+1)×C prefix sums modulo 2^32 (half the memory of exact ones; see
    /// [`SourceImage::box_sum`]).
    sat: Vec<u32>,
}

impl<'a> SourceImage<'a> {
    /// Wraps `pixels` (`width × height × channels`, row-major, interleaved).
    ///
    /// A buffer of another length, or an empty image, is [`crate::Error::InvalidArgument`].
    pub fn new(pixels: &'a [u8], width: u32, height: u32, channels: usize) -> crate::Result<Self> {
        let (w, h, c) = (width as usize, height as usize, channels);
        if w == 0
            || h == 0
            || c == 0
            || w.checked_mul(h).and_then(|p| p.checked_mul(c)) != Some(pixels.len())
        {
            return Err(crate::Error::invalid(
                "pixel buffer",
                format_args!(
                    "{} bytes for a {width}×{height}×{channels} image",
                    pixels.len()
                ),
                "width × height × channels bytes, none of them 0",
            ));
        }
        let mut sat = vec![0u32; (w + 1) * (h + 1) * c];
        match c {
            1 => prefix_sums::<false>(&mut sat, 1, w, h, pixels, &[]),
            2 => prefix_sums::<false>(&mut sat, 2, w, h, pixels, &[]),
            3 => prefix_sums::<false>(&mut sat, 3, w, h, pixels, &[]),
            4 => prefix_sums::<false>(&mut sat, 4, w, h, pixels, &[]),
            _ => prefix_sums::<false>(&mut sat, c, w, h, pixels, &[]),
        }
        Ok(SourceImage {
            pixels,
            width: w,
            height: h,
            channels: c,
            sat,
        })
    }

    fn box_mean(&self, b: (usize, usize, usize, usize), out: &mut Vec<u8>) {
        let n = ((b.2 - b.0) * (b.3 - b.1)) as u64;
        for k in 0..self.channels {
            out.push(((self.box_sum(b, k) + n / 2) / n) as u8);
        }
    }

    /// The sum of channel `k` over the pixels `[x0, x1) × [y0, y1)`. The table's sums wrap
    /// at 2^32, and their difference is the exact sum when that is below 2^32: a box of up to
    /// 2^32 / 255 pixels. A larger one is summed in halves.
    #[inline]
    fn box_sum(&self, (x0, y0, x1, y1): (usize, usize, usize, usize), k: usize) -> u64 {
        if ((x1 - x0) * (y1 - y0)) as u64 * 255 > u32::MAX as u64 {
            return self.box_sum_halves((x0, y0, x1, y1), k);
        }
        let stride = (self.width + 1) * self.channels;
        let at = |x: usize, y: usize| self.sat[y * stride + x * self.channels + k];
        let s = (at(x1, y1).wrapping_add(at(x0, y0)))
            .wrapping_sub(at(x0, y1))
            .wrapping_sub(at(x1, y0));
        s as u64
    }

    /// [`SourceImage::box_sum`] of a box too large for one lookup: the sum of its halves, split
    /// across its longer side.
    #[cold]
    #[inline(never)]
    fn box_sum_halves(&self, (x0, y0, x1, y1): (usize, usize, usize, usize), k: usize) -> u64 {
        if y1 - y0 >= x1 - x0 {
            let ym = (y0 + y1) / 2;
            self.box_sum((x0, y0, x1, ym), k) + self.box_sum((x0, ym, x1, y1), k)
        } else {
            let xm = (x0 + x1) / 2;
            self.box_sum((x0, y0, xm, y1), k) + self.box_sum((xm, y0, x1, y1), k)
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
                SampleColour::Area => {
                    self.box_mean(around(*p, final_side, self.width, self.height), &mut out)
                }
                SampleColour::Progressive | SampleColour::Fitted => {
                    let side = self.progressive_side(k, total);
                    self.box_mean(around(*p, side, self.width, self.height), &mut out);
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
        self.fitted_within(sites, frame, first_level, total, FIT_PIXELS)
    }

    /// [`SourceImage::fitted`] of an image needed no longer: the fit's table of residual sums
    /// takes over the memory of the image's own, which it needs no more once the uncorrected
    /// colours are taken (two such tables, 4 bytes a pixel and channel each, were the encoder's
    /// peak).
    pub(crate) fn into_fitted(
        mut self,
        sites: &[Site],
        frame: Frame,
        first_level: usize,
        total: usize,
    ) -> Vec<u8> {
        let (colours, mut fit) = self.fit_start(sites, total, FIT_PIXELS);
        let sat = std::mem::take(&mut self.sat);
        if fit.f == 1 {
            fit.sat = sat;
        }
        self.fit_levels(sites, frame, first_level, total, colours, fit)
    }

    /// [`SourceImage::fitted`] comparing renders of at most `max_pixels` pixels.
    fn fitted_within(
        &self,
        sites: &[Site],
        frame: Frame,
        first_level: usize,
        total: usize,
        max_pixels: usize,
    ) -> Vec<u8> {
        let (colours, fit) = self.fit_start(sites, total, max_pixels);
        self.fit_levels(sites, frame, first_level, total, colours, fit)
    }

    /// The uncorrected colours of `sites`, and the picture renders are compared with.
    fn fit_start(&self, sites: &[Site], total: usize, max_pixels: usize) -> (Vec<u8>, Fit<'a>) {
        let positions: Vec<Point> = sites.iter().map(|s| s.pos).collect();
        let colours = self.colours(&positions, SampleColour::Progressive, total);
        (colours, Fit::new(self, max_pixels))
    }

    /// `colours` corrected level by level against `fit`: the table of prefix sums is not read.
    fn fit_levels(
        &self,
        sites: &[Site],
        frame: Frame,
        first_level: usize,
        total: usize,
        mut colours: Vec<u8>,
        mut fit: Fit,
    ) -> Vec<u8> {
        let c = self.channels;
        let mut set = SampleSet::new(self.width as u32, self.height as u32, c).with_frame(frame);
        if set.channels() != c {
            return colours; // More than 4 channels: no renderer draws them.
        }
        // The ends of the corrected stretches: the file's level ends, with the first level
        // split in halves three times (L0 = 127: 16, 32, 64, 127, 254, 508, …).
        // Only those within the first FIT_SAMPLES samples.
        let n = sites.len();
        let l0 = first_level.clamp(1, n.max(1));
        let split = (1..=3).rev().map(|d| l0.div_ceil(1 << d));
        let levels = std::iter::successors(Some(l0), |&e| (e < n).then(|| e.saturating_mul(2)));
        let ends = split.chain(levels).map(|e| e.min(n));
        let mut s = 0;
        for e in ends.take_while(|&e| e <= FIT_SAMPLES) {
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
                fit.correct(self, &mut set, s, level, total);
                set.recolour(s, level);
            }
            s = e;
        }
        colours
    }
}

/// The prefix sums modulo 2^32 of `image` (or of `image − drawn` if `RESIDUAL`; `w × h`, `c`
/// channels) into `sat`, `(w + 1) × (h + 1)` entries of `c`: row 0 and column 0 stay 0, every
/// other entry is written. Row by row as slices; callers pass `c` as a constant, so that the
/// loops are specialised (indexing each entry cost 15% of an encode in bounds checks).
#[inline(always)]
fn prefix_sums<const RESIDUAL: bool>(
    sat: &mut [u32],
    c: usize,
    w: usize,
    h: usize,
    image: &[u8],
    drawn: &[u8],
) {
    let stride = (w + 1) * c;
    let mut row = vec![0u32; c];
    for (y, image) in image.chunks_exact(w * c).enumerate().take(h) {
        let drawn = if RESIDUAL { &drawn[y * w * c..(y + 1) * w * c] } else { image };
        let (above, below) = sat.split_at_mut((y + 1) * stride);
        let (above, below) = (&above[y * stride + c..], &mut below[c..stride]);
        row.fill(0);
        let pixels = image.chunks_exact(c).zip(drawn.chunks_exact(c));
        let entries = below.chunks_exact_mut(c).zip(above.chunks_exact(c));
        for ((out, up), (p, d)) in entries.zip(pixels) {
            let values = (p.iter().zip(d)).map(|(&p, &d)| {
                (p as u32).wrapping_sub(if RESIDUAL { d as u32 } else { 0 })
            });
            for (((o, &u), r), v) in out.iter_mut().zip(up).zip(&mut row).zip(values) {
                *r = r.wrapping_add(v);
                *o = u.wrapping_add(*r);
            }
        }
    }
}

/// The pixels `(x0, y0, x1, y1)` (exclusive ends) of a box of `side` centred on `p` in a
/// `w × h` picture, within it and never empty: it holds the pixel containing `p`.
fn around(p: Point, side: f64, w: usize, h: usize) -> (usize, usize, usize, usize) {
    let ix = (p[0].floor().max(0.0) as usize).min(w - 1);
    let iy = (p[1].floor().max(0.0) as usize).min(h - 1);
    let half = side / 2.0;
    let x0 = ((p[0] - half).round().max(0.0) as usize).min(ix);
    let y0 = ((p[1] - half).round().max(0.0) as usize).min(iy);
    let x1 = ((p[0] + half).round().min(w as f64) as usize).max(ix + 1);
    let y1 = ((p[1] + half).round().min(h as f64) as usize).max(iy + 1);
    (x0, y0, x1, y1)
}

/// The picture [`SampleColour::Fitted`] compares renders with: the image itself, or, when it
/// has more than [`FIT_PIXELS`] pixels, its box means over `f × f` blocks for the least
/// integer `f` that brings it under.
struct Fit<'a> {
    pixels: std::borrow::Cow<'a, [u8]>,
    width: usize,
    height: usize,
    /// Source pixels per fitted pixel.
    f: usize,
    /// The residual's prefix sums, kept from one correction to the next: modulo 2^32, as a
    /// box's sum (at most 255 a pixel in magnitude over at most `FIT_PIXELS` pixels, below
    /// 2^31) is exact from them with wrapping arithmetic, read as a signed number.
    sat: Vec<u32>,
}

impl<'a> Fit<'a> {
    fn new(src: &SourceImage<'a>, max_pixels: usize) -> Self {
        let (w, h) = (src.width, src.height);
        let f = (1..)
            .find(|f| w.div_ceil(*f) * h.div_ceil(*f) <= max_pixels.max(1))
            .expect("f = max(w, h) gives one pixel");
        if f == 1 {
            return Fit {
                pixels: src.pixels.into(),
                width: w,
                height: h,
                f,
                sat: Vec::new(),
            };
        }
        let (fw, fh) = (w.div_ceil(f), h.div_ceil(f));
        let mut pixels = Vec::with_capacity(fw * fh * src.channels);
        for y in 0..fh {
            for x in 0..fw {
                let b = (x * f, y * f, ((x + 1) * f).min(w), ((y + 1) * f).min(h));
                src.box_mean(b, &mut pixels);
            }
        }
        Fit {
            pixels: pixels.into(),
            width: fw,
            height: fh,
            f,
            sat: Vec::new(),
        }
    }

    /// The correction of [`SampleColour::Fitted`] for the last samples of `set`, the sites
    /// `first..` of a file of `total`, whose colours are `colours` (in the set too).
    fn correct(
        &mut self,
        src: &SourceImage,
        set: &mut SampleSet,
        first: usize,
        colours: &mut [u8],
        total: usize,
    ) {
        let (w, h, c) = (self.width, self.height, src.channels);
        // The render's pixel i covers source pixels [i·W/w, (i + 1)·W/w): f each but for the
        // last, which the box means above cut short (a shift of under one fitted pixel).
        let render = set.render_with(
            Method::Gouraud,
            w as u32,
            h as u32,
            RenderOptions::default(),
        );
        // Prefix sums of the residual, as those of the image in `SourceImage::new`.
        let stride = (w + 1) * c;
        self.sat.resize(stride * (h + 1), 0);
        let (sat, pixels) = (&mut self.sat, &self.pixels);
        match c {
            1 => prefix_sums::<true>(sat, 1, w, h, pixels, &render),
            2 => prefix_sums::<true>(sat, 2, w, h, pixels, &render),
            3 => prefix_sums::<true>(sat, 3, w, h, pixels, &render),
            _ => prefix_sums::<true>(sat, 4, w, h, pixels, &render),
        }
        let sat = &self.sat;
        let f = self.f as f64;
        for (j, col) in colours.chunks_exact_mut(c).enumerate() {
            let k = first + j;
            let side = FIT_BOX * src.progressive_side(k, total) / f;
            let p = set.positions()[k];
            let (x0, y0, x1, y1) = around([p[0] / f, p[1] / f], side, w, h);
            let n = ((x1 - x0) * (y1 - y0)) as f64;
            for (ch, v) in col.iter_mut().enumerate() {
                let at = |x: usize, y: usize| sat[y * stride + x * c + ch];
                let sum = (at(x1, y1).wrapping_add(at(x0, y0)))
                    .wrapping_sub(at(x0, y1))
                    .wrapping_sub(at(x1, y0)) as i32;
                *v = (*v as f64 + FIT_SHARE * sum as f64 / n)
                    .round()
                    .clamp(0.0, 255.0) as u8;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sites::Quasicrystal;

    #[test]
    fn box_sums_are_exact_though_the_table_wraps() {
        // Small boxes of noisy images of 1 to 6 channels against sums pixel by pixel.
        let (w, h) = (37, 23);
        for c in 1..=6 {
            let px: Vec<u8> = (0..w * h * c).map(|i| (i * 97 % 251) as u8).collect();
            let src = SourceImage::new(&px, w as u32, h as u32, c).unwrap();
            for (x0, y0, x1, y1) in [
                (0, 0, w, h),
                (3, 4, 5, 20),
                (36, 22, 37, 23),
                (10, 0, 30, 1),
            ] {
                for k in 0..c {
                    let px = &px;
                    let direct: u64 = (y0..y1)
                        .flat_map(|y| (x0..x1).map(move |x| px[(y * w + x) * c + k] as u64))
                        .sum();
                    assert_eq!(src.box_sum((x0, y0, x1, y1), k), direct, "{c} channels");
                }
            }
        }
        // A white image whose sum exceeds 2^32: 4200 × 4200 × 255 = 4.50·10^9.
        let (w, h) = (4200, 4200);
        let px = vec![255u8; w * h];
        let src = SourceImage::new(&px, w as u32, h as u32, 1).unwrap();
        assert_eq!(src.box_sum((0, 0, w, h), 0), 255 * (w * h) as u64);
        assert_eq!(
            src.box_sum((1, 2, w - 3, h - 1), 0),
            255 * ((w - 4) * (h - 3)) as u64
        );
        let mut mean = Vec::new();
        src.box_mean((0, 0, w, h), &mut mean);
        assert_eq!(mean, [255]);
        // Wider than tall: split across its columns (the square ones across their rows).
        assert_eq!(src.box_sum((0, 0, w, 4100), 0), 255 * (w * 4100) as u64);
    }

    #[test]
    fn a_large_image_is_fitted_at_its_block_means() {
        // 5 × 3 grey, at most 6 pixels: blocks of 2 × 2, the last column and row cut short.
        let px: Vec<u8> = (0..15).map(|i| i * 10).collect();
        let src = SourceImage::new(&px, 5, 3, 1).unwrap();
        let fit = Fit::new(&src, 6);
        assert_eq!((fit.width, fit.height, fit.f), (3, 2, 2));
        // (0 + 10 + 50 + 60) / 4 = 30, (40 + 90) / 2 = 65, (100 + 110) / 2 = 105, 140.
        assert_eq!(&fit.pixels[..], &[30, 50, 65, 105, 125, 140]);
        assert_eq!(Fit::new(&src, 15).f, 1);
    }

    #[test]
    fn more_than_four_channels_keep_their_progressive_colours() {
        let px: Vec<u8> = (0..8 * 8 * 5).map(|i| (i * 7 % 256) as u8).collect();
        let src = SourceImage::new(&px, 8, 8, 5).unwrap();
        let seq = Quasicrystal::new(8, 8).unwrap();
        let sites = seq.first(16);
        let pos: Vec<_> = sites.iter().map(|s| s.pos).collect();
        let progressive = src.colours(&pos, SampleColour::Progressive, 16);
        assert_eq!(src.fitted(&sites, seq.frame(), 4, 16), progressive);
    }

    #[test]
    fn fitting_at_half_size_still_draws_every_stretch_closer() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/coffee-150x100.png");
        let img = image::open(path).unwrap().to_rgb8();
        let (w, h) = img.dimensions();
        let n = 2000;
        let seq = Quasicrystal::new(w, h).unwrap();
        let sites = seq.first(n);
        let pos: Vec<_> = sites.iter().map(|s| s.pos).collect();
        let src = SourceImage::new(img.as_raw(), w, h, 3).unwrap();
        let progressive = src.colours(&pos, SampleColour::Progressive, n);
        let half = src.fitted_within(&sites, seq.frame(), 127, n, 75 * 50);
        let full = src.fitted(&sites, seq.frame(), 127, n);
        assert_ne!(half, full);
        // The encoder's way, the residual sums in the image's table: the same colours.
        let own = SourceImage::new(img.as_raw(), w, h, 3).unwrap();
        assert_eq!(own.into_fitted(&sites, seq.frame(), 127, n), full);
        let mse = |colours: &[u8], e: usize| {
            let mut set = SampleSet::new(w, h, 3).with_frame(seq.frame());
            for (s, c) in sites[..e].iter().zip(colours.chunks_exact(3)) {
                set.push_site(s, c);
            }
            let r = set.render(Method::Gouraud, w, h);
            let se: f64 = r
                .iter()
                .zip(img.as_raw())
                .map(|(&a, &b)| (a as f64 - b as f64).powi(2))
                .sum();
            se / r.len() as f64
        };
        for e in [32, 64, 127, 254, 508, 1016, 2000] {
            let (a, b) = (mse(&progressive, e), mse(&half, e));
            assert!(
                b < 0.985 * a,
                "{e} samples: MSE {b:.1} fitted at half size, {a:.1} progressive"
            );
        }
    }
}
