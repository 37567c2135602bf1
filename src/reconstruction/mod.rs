//! Samples → picture, at any output size and from any prefix.
//!
//! STUB (to be replaced by the reconstruction work): nearest-sample rendering by brute force.

use crate::sites::Point;

/// How a picture is rebuilt from its samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Method {
    /// Linear interpolation over the Delaunay triangulation.
    Gouraud,
    /// Inverse-distance weighting of the 4 nearest samples (power 2).
    Shepard,
    /// Sibson natural-neighbour interpolation.
    Natural,
}

/// A growing set of samples of one source image.
#[derive(Clone, Debug)]
pub struct SampleSet {
    width: u32,
    height: u32,
    channels: usize,
    positions: Vec<Point>,
    colours: Vec<u8>,
}

impl SampleSet {
    /// An empty set for a `width × height` source with `channels` (1, 3 or 4) per colour.
    pub fn new(width: u32, height: u32, channels: usize) -> Self {
        SampleSet {
            width,
            height,
            channels,
            positions: Vec::new(),
            colours: Vec::new(),
        }
    }
    /// Adds one sample (position in source pixels, `channels` colour bytes).
    pub fn push(&mut self, pos: Point, colour: &[u8]) {
        self.positions.push(pos);
        self.colours.extend_from_slice(&colour[..self.channels]);
    }
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.positions.len()
    }
    /// Whether there are no samples.
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }
    /// Renders a `width × height` picture, interleaved, `channels` bytes per pixel.
    pub fn render(&mut self, _method: Method, width: u32, height: u32) -> Vec<u8> {
        let c = self.channels;
        let mut out = vec![0u8; width as usize * height as usize * c];
        if self.positions.is_empty() {
            return out;
        }
        let sx = self.width as f64 / width as f64;
        let sy = self.height as f64 / height as f64;
        for j in 0..height as usize {
            for i in 0..width as usize {
                let p = [(i as f64 + 0.5) * sx, (j as f64 + 0.5) * sy];
                let mut best = (f64::INFINITY, 0);
                for (k, q) in self.positions.iter().enumerate() {
                    let d = (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2);
                    if d < best.0 {
                        best = (d, k);
                    }
                }
                let o = (j * width as usize + i) * c;
                out[o..o + c].copy_from_slice(&self.colours[best.1 * c..best.1 * c + c]);
            }
        }
        out
    }
}

/// One-shot render of `positions` (source pixels) with `colours` (`channels` bytes each).
pub fn render(
    source: (u32, u32),
    channels: usize,
    positions: &[Point],
    colours: &[u8],
    method: Method,
    width: u32,
    height: u32,
) -> Vec<u8> {
    let mut set = SampleSet::new(source.0, source.1, channels);
    for (k, p) in positions.iter().enumerate() {
        set.push(*p, &colours[k * channels..k * channels + channels]);
    }
    set.render(method, width, height)
}
