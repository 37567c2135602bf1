//! Where everything is and in which order it is coded: bands, blocks, streams and passes
//! (spec/refinement.md §3 and §5).

use super::wavelet::{low_size, Kernel};

/// The largest number of transform levels a file may use.
pub(crate) const MAX_LEVELS: u32 = 15;
/// Side of a block, in coefficients.
pub(crate) const BLOCK: usize = 32;

/// A band's orientation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub(crate) enum Orient {
    /// Low in both directions: the coarsest picture.
    LowLow,
    /// High horizontally, low vertically (vertical edges).
    HighLow,
    /// Low horizontally, high vertically (horizontal edges).
    LowHigh,
    /// High in both directions.
    HighHigh,
}

/// A band: a rectangle of a channel's coefficient plane (Mallat layout).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Band {
    pub x0: usize,
    pub y0: usize,
    pub w: usize,
    pub h: usize,
    pub orient: Orient,
    /// The transform level it comes from (1 = finest; the low-low band has the deepest).
    pub level: u32,
    /// Its stream: 0 for the low-low band, then 1.. from the coarsest details to the finest.
    pub stream: u32,
}

impl Band {
    /// A `w × h` high-high band of the finest level, at the origin (for tests).
    #[cfg(test)]
    pub(crate) fn sized(w: usize, h: usize) -> Band {
        Band {
            x0: 0,
            y0: 0,
            w,
            h,
            orient: Orient::HighHigh,
            level: 1,
            stream: 1,
        }
    }

    pub(crate) fn len(&self) -> usize {
        self.w * self.h
    }

    /// Blocks across and down.
    pub(crate) fn blocks(&self) -> (usize, usize) {
        (self.w.div_ceil(BLOCK), self.h.div_ceil(BLOCK))
    }
}

/// The bands of a `w × h` plane after `levels` levels: the low-low band, then for each level
/// from the coarsest to the finest its high-low, low-high and high-high bands. Empty bands
/// (a dimension of 1 has no high half) are listed too, with a zero side.
pub(crate) fn bands(w: usize, h: usize, levels: u32) -> Vec<Band> {
    let (lw, lh) = low_size(w, h, levels);
    let mut out = vec![Band {
        x0: 0,
        y0: 0,
        w: lw,
        h: lh,
        orient: Orient::LowLow,
        level: levels,
        stream: 0,
    }];
    for level in (1..=levels).rev() {
        let (cw, ch) = low_size(w, h, level - 1);
        let (nw, nh) = low_size(w, h, level);
        let stream = levels - level + 1;
        let band = |x0, y0, w, h, orient| Band {
            x0,
            y0,
            w,
            h,
            orient,
            level,
            stream,
        };
        out.push(band(nw, 0, cw - nw, nh, Orient::HighLow));
        out.push(band(0, nh, nw, ch - nh, Orient::LowHigh));
        out.push(band(nw, nh, cw - nw, ch - nh, Orient::HighHigh));
    }
    out
}

/// Each band's weight, in sixteenths of a bit-plane: 8·log2 of the energy its unit
/// coefficient has in the picture, for levels 1..=15 (index `level − 1`), rounded.
/// `[low-low, high-low and low-high, high-high]`.
const WEIGHTS: [[[i32; MAX_LEVELS as usize]; 3]; 2] = [
    // Reversible 5/3.
    [
        [
            9, 23, 39, 55, 71, 87, 103, 119, 135, 151, 167, 183, 199, 215, 231,
        ],
        [
            1, 11, 25, 40, 56, 72, 88, 104, 120, 136, 152, 168, 184, 200, 216,
        ],
        [
            -8, -2, 11, 26, 41, 57, 73, 89, 105, 121, 137, 153, 169, 185, 201,
        ],
    ],
    // Integer 9/7.
    [
        [6, 14, 21, 27, 34, 40, 46, 53, 59, 66, 72, 79, 85, 92, 98],
        [0, 6, 14, 21, 27, 34, 40, 47, 53, 60, 66, 73, 79, 85, 92],
        [-6, -1, 7, 15, 21, 28, 34, 41, 47, 54, 60, 66, 73, 79, 86],
    ],
];

/// A band's weight (sixteenths of a bit-plane). The low-low band of a transform with no
/// level is the picture itself: weight 0.
pub(crate) fn band_weight(kernel: Kernel, band: &Band) -> i32 {
    if band.level == 0 {
        return 0;
    }
    let k = match kernel {
        Kernel::Reversible53 => 0,
        Kernel::Integer97 => 1,
    };
    let row = match band.orient {
        Orient::LowLow => 0,
        Orient::HighLow | Orient::LowHigh => 1,
        Orient::HighHigh => 2,
    };
    WEIGHTS[k][row][band.level as usize - 1]
}

/// The kind of a pass over a band's bit-plane, in coding order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub(crate) enum PassKind {
    /// Insignificant coefficients with a significant neighbour.
    Propagation,
    /// Coefficients significant before this bit-plane.
    Refinement,
    /// The rest.
    Cleanup,
}

impl PassKind {
    /// How much later than a propagation pass of the same bit-plane the pass comes
    /// (sixteenths of a bit-plane).
    pub(crate) fn delay(self) -> i32 {
        match self {
            PassKind::Propagation => 0,
            PassKind::Refinement | PassKind::Cleanup => 8,
        }
    }
}

/// A pass's priority: higher first (sixteenths of a bit-plane).
pub(crate) fn key(
    kernel: Kernel,
    band: &Band,
    channel_weight: i32,
    bitplane: u8,
    kind: PassKind,
) -> i32 {
    16 * bitplane as i32 + band_weight(kernel, band) + channel_weight - kind.delay()
}

/// One pass: a bit-plane of a band of a channel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Pass {
    pub channel: u8,
    /// Index into [`bands`].
    pub band: u16,
    pub bitplane: u8,
    pub kind: PassKind,
}

/// The passes of each stream, in coding order. `top[c]` is channel c's number of bit-planes
/// and `channel_weight[c]` its weight (sixteenths of a bit-plane).
pub(crate) fn passes(
    kernel: Kernel,
    bands: &[Band],
    top: &[u8],
    channel_weight: &[i32],
) -> Vec<Vec<Pass>> {
    let streams = bands.iter().map(|b| b.stream).max().map_or(0, |s| s + 1);
    let mut out: Vec<Vec<(i32, Pass)>> = vec![Vec::new(); streams as usize];
    for (bi, band) in bands.iter().enumerate() {
        for (c, (&t, &cw)) in top.iter().zip(channel_weight).enumerate() {
            let w = band_weight(kernel, band) + cw;
            for p in (0..t).rev() {
                for kind in [
                    PassKind::Propagation,
                    PassKind::Refinement,
                    PassKind::Cleanup,
                ] {
                    let key = 16 * p as i32 + w - kind.delay();
                    debug_assert_eq!(key, self::key(kernel, band, cw, p, kind));
                    out[band.stream as usize].push((
                        key,
                        Pass {
                            channel: c as u8,
                            band: bi as u16,
                            bitplane: p,
                            kind,
                        },
                    ));
                }
            }
        }
    }
    out.into_iter()
        .map(|mut v| {
            // Highest key first; then the kind, the band and the channel, all ascending.
            v.sort_by_key(|&(key, p)| (-key, p.kind, p.band, p.channel));
            v.into_iter().map(|(_, p)| p).collect()
        })
        .collect()
}

/// The blocks of a band in coding order: by the bit-reversed Morton index of their position,
/// so that the first blocks of a pass are spread over the whole band.
pub(crate) fn block_order(band: &Band) -> Vec<(u32, u32)> {
    let (bw, bh) = band.blocks();
    let side = bw.max(bh).max(1).next_power_of_two();
    let bits = 2 * side.trailing_zeros();
    let mut out = Vec::with_capacity(bw * bh);
    for t in 0..(side * side) as u64 {
        let m = if bits == 0 {
            0
        } else {
            t.reverse_bits() >> (64 - bits)
        };
        let (mut x, mut y) = (0u32, 0u32);
        for b in 0..side.trailing_zeros() {
            x |= (((m >> (2 * b)) & 1) as u32) << b;
            y |= (((m >> (2 * b + 1)) & 1) as u32) << b;
        }
        if (x as usize) < bw && (y as usize) < bh {
            out.push((x, y));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bands_tile_the_plane() {
        for (w, h, levels) in [(1, 1, 0), (1, 1, 3), (37, 5, 4), (768, 480, 6), (2, 3, 2)] {
            let bs = bands(w, h, levels);
            assert_eq!(bs.len(), 1 + 3 * levels as usize);
            let mut seen = vec![0u8; w * h];
            for b in &bs {
                for y in b.y0..b.y0 + b.h {
                    for x in b.x0..b.x0 + b.w {
                        seen[y * w + x] += 1;
                    }
                }
            }
            assert!(seen.iter().all(|&s| s == 1), "{w}x{h} levels {levels}");
        }
    }

    #[test]
    fn the_weight_table_is_the_transform_s() {
        // Recompute the table from the lifting steps (in floating point, without rounding):
        // 8·log2 of the energy of the picture of a unit coefficient, far from the edges.
        fn inverse_1d(kernel: Kernel, x: &mut [f64]) {
            let n = x.len();
            let (nl, nh) = (n.div_ceil(2), n / 2);
            let (mut s, mut d) = (x[..nl].to_vec(), x[nl..].to_vec());
            let steps: Vec<(bool, f64)> = match kernel {
                Kernel::Reversible53 => vec![(false, -0.5), (true, 0.25)],
                Kernel::Integer97 => super::super::wavelet::W97
                    .iter()
                    .enumerate()
                    .map(|(i, &c)| (i % 2 == 1, c as f64 / 4096.0))
                    .collect(),
            };
            for &(update, c) in steps.iter().rev() {
                if update {
                    for i in 0..nl {
                        s[i] -= c * (d[i.saturating_sub(1)] + d[i.min(nh - 1)]);
                    }
                } else {
                    for i in 0..nh {
                        d[i] -= c * (s[i] + s[(i + 1).min(nl - 1)]);
                    }
                }
            }
            for i in 0..nl {
                x[2 * i] = s[i];
            }
            for i in 0..nh {
                x[2 * i + 1] = d[i];
            }
        }
        fn gain(kernel: Kernel, level: u32, high: bool) -> f64 {
            let n = 32usize << level;
            let low = n >> level;
            let mut x = vec![0.0; n];
            x[if high { low + low / 2 } else { low / 2 }] = 1.0;
            for l in (0..level).rev() {
                inverse_1d(kernel, &mut x[..n >> l]);
            }
            x.iter().map(|v| v * v).sum()
        }
        for kernel in [Kernel::Reversible53, Kernel::Integer97] {
            for level in 1..=MAX_LEVELS {
                let (lo, hi) = (gain(kernel, level, false), gain(kernel, level, true));
                for (orient, g) in [
                    (Orient::LowLow, lo * lo),
                    (Orient::HighLow, hi * lo),
                    (Orient::HighHigh, hi * hi),
                ] {
                    let band = Band {
                        x0: 0,
                        y0: 0,
                        w: 1,
                        h: 1,
                        orient,
                        level,
                        stream: 0,
                    };
                    let want = (8.0 * g.log2()).round() as i32;
                    assert_eq!(
                        band_weight(kernel, &band),
                        want,
                        "{kernel:?} {orient:?} {level}"
                    );
                }
            }
        }
    }

    #[test]
    fn blocks_are_each_visited_once_and_spread() {
        for (w, h) in [(1, 1), (32, 32), (33, 1), (100, 70), (1000, 40)] {
            let band = Band::sized(w, h);
            let order = block_order(&band);
            let (bw, bh) = band.blocks();
            assert_eq!(order.len(), bw * bh);
            let mut seen = std::collections::HashSet::new();
            assert!(order.iter().all(|b| seen.insert(*b)));
        }
        // The first four blocks of a 4 × 4 grid are one in each quadrant.
        let band = Band::sized(128, 128);
        assert_eq!(&block_order(&band)[..4], &[(0, 0), (0, 2), (2, 0), (2, 2)]);
    }

    #[test]
    fn passes_follow_their_keys() {
        let bs = bands(64, 48, 3);
        let ps = passes(Kernel::Integer97, &bs, &[10, 9, 9], &[13, -8, -3]);
        assert_eq!(ps.len(), 4);
        // Every band, channel and bit-plane has its three passes, in its stream.
        let total: usize = ps.iter().map(Vec::len).sum();
        assert_eq!(total, bs.len() * 3 * (10 + 9 + 9));
        for (s, stream) in ps.iter().enumerate() {
            assert!(stream
                .iter()
                .all(|p| bs[p.band as usize].stream == s as u32));
            // Within a band and channel, bit-planes go down and kinds go in order.
            for pair in stream.windows(2) {
                let (a, b) = (pair[0], pair[1]);
                if a.band == b.band && a.channel == b.channel {
                    let rank = |p: Pass| 3 * p.bitplane as i32 - p.kind as i32;
                    assert!(rank(a) > rank(b), "{a:?} before {b:?}");
                }
            }
        }
    }
}
