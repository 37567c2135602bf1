//! Measurements on the dev photographs (ignored tests: `cargo test --release --lib
//! refinement::lab -- --ignored --nocapture`; `QCS_CORPUS` names the folder).

use super::encode::cut_at;
use super::picture::{picture, to_planes, Source};
use super::schedule::Pass;
use super::wavelet::{forward, low_size, Kernel};
use super::*;
use crate::sites::{fixed_position, Quasicrystal};

/// The first `n` samples of a `w × h` file's levels: their fixed positions and decoded colours.
fn level_samples(file: &[u8], n: u64, w: usize, h: usize) -> (Vec<[i64; 2]>, Vec<u8>) {
    let mut dec = crate::StreamDecoder::new(crate::Limits::default());
    dec.push(file).unwrap();
    let (sites, colours) = dec.samples(n);
    let seq = Quasicrystal::new(w as u32, h as u32).unwrap();
    let positions = (sites.iter())
        .map(|s| fixed_position(&seq.frame(), s.lattice))
        .collect();
    (positions, colours.to_vec())
}

fn corpus() -> Vec<std::path::PathBuf> {
    let dir = std::env::var("QCS_CORPUS").unwrap_or_else(|_| "../shared/corpus/dev".into());
    let mut v: Vec<_> = std::fs::read_dir(dir)
        .map(|d| d.filter_map(|e| e.ok().map(|e| e.path())).collect())
        .unwrap_or_default();
    v.retain(|p| p.extension().is_some_and(|e| e == "png"));
    v.sort();
    v
}

fn psnr(a: &[u8], b: &[u8]) -> f64 {
    let se: f64 = a
        .iter()
        .zip(b)
        .map(|(&x, &y)| (x as f64 - y as f64).powi(2))
        .sum();
    let mse = se / a.len() as f64;
    if mse == 0.0 {
        100.0
    } else {
        10.0 * (255.0f64 * 255.0 / mse).log10()
    }
}

/// Linear weight of each pass's band and channel, the lab's planes having 2 fraction bits.
fn pass_weights(layout: &Layout, passes: &[Pass]) -> Vec<f64> {
    encode::pass_weights(layout, 2, passes)
}

#[test]
#[ignore]
fn rate_distortion() {
    let budgets_bpp = [0.1, 0.25, 0.5, 1.0, 2.0];
    let levels: u32 = std::env::var("LEVELS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(6);
    let mut sums = vec![0.0; budgets_bpp.len()];
    let files = corpus();
    for path in &files {
        let img = image::open(path).unwrap().to_rgb8();
        let (w, h) = (img.width() as usize, img.height() as usize);
        let px = img.as_raw();
        let frac = 2;
        let mut planes = to_planes(px, 3, frac);
        for p in &mut planes {
            forward(Kernel::Integer97, p, w, h, levels);
        }
        let layout = Layout {
            width: w,
            height: h,
            channels: 3,
            kernel: Kernel::Integer97,
            levels,
            top: planes.iter().map(|p| bitplanes(p)).collect(),
        };
        let states = layout.stream_states(Some(&planes));
        let coded: Vec<CodedStream> = states
            .into_iter()
            .map(|mut st| {
                let ws = pass_weights(&layout, &st.passes);
                let n = st.passes.len();
                encode_stream(&mut st, n, &ws)
            })
            .collect();
        let (lw, lh) = low_size(w, h, levels);
        let prediction = vec![vec![0; lw * lh]; 3];
        let src = Source {
            width: w,
            height: h,
            channels: 3,
            kernel: Kernel::Integer97,
            levels,
            frac,
            prediction: &prediction,
        };
        let mut row = Vec::new();
        for (bi, &bpp) in budgets_bpp.iter().enumerate() {
            let budget = bpp * (w * h) as f64 / 8.0;
            // Bisect λ (log scale) for the largest total within the budget.
            let (mut lo, mut hi) = (1e-6f64, 1e9f64);
            for _ in 0..60 {
                let mid = (lo * hi).sqrt();
                let total: usize = coded
                    .iter()
                    .map(|c| {
                        let k = cut_at(c, mid);
                        if k == 0 {
                            0
                        } else {
                            c.pass_end[k - 1]
                        }
                    })
                    .sum();
                if total as f64 > budget {
                    lo = mid
                } else {
                    hi = mid
                }
            }
            let by_key = std::env::var("BYKEY").is_ok();
            let keys: Vec<Vec<i32>> = layout
                .stream_states(None)
                .iter()
                .map(|st| {
                    let (_, cw) = channel_classes(3);
                    let bands = layout.bands();
                    st.passes
                        .iter()
                        .map(|p| {
                            schedule::key(
                                layout.kernel,
                                &bands[p.band as usize],
                                cw[p.channel as usize],
                                p.bitplane,
                                p.kind,
                            )
                        })
                        .collect()
                })
                .collect();
            let cut_key = |k: i32| -> Vec<usize> {
                keys.iter()
                    .map(|ks| ks.iter().take_while(|&&x| x >= k).count())
                    .collect()
            };
            let cuts: Vec<usize> = if by_key {
                let mut best = cut_key(i32::MAX);
                for k in (-200..800).rev() {
                    let c = cut_key(k);
                    let total: usize = coded
                        .iter()
                        .zip(&c)
                        .map(|(s, &n)| if n == 0 { 0 } else { s.pass_end[n - 1] })
                        .sum();
                    if total as f64 > budget {
                        break;
                    }
                    best = c;
                }
                best
            } else {
                coded.iter().map(|c| cut_at(c, hi)).collect()
            };
            let mut decs: Vec<StreamDecoder> = layout
                .stream_states(None)
                .into_iter()
                .zip(&coded)
                .zip(&cuts)
                .map(|((st, c), &k)| {
                    let mut d = StreamDecoder::new(st, k);
                    let end = if k == 0 { 0 } else { c.pass_end[k - 1] };
                    d.advance(&c.bytes[..end]);
                    d
                })
                .collect();
            let refs: Vec<Option<&bitplane::StreamState>> =
                decs.iter_mut().map(|d| Some(&d.state)).collect();
            let pic = picture(&src, &refs, 0);
            let v = psnr(&pic, px);
            row.push(v);
            sums[bi] += v;
        }
        println!(
            "{}: {}",
            path.display(),
            row.iter()
                .map(|v| format!("{v:.2}"))
                .collect::<Vec<_>>()
                .join(" ")
        );
    }
    println!(
        "mean: {}",
        sums.iter()
            .map(|v| format!("{:.2}", v / files.len() as f64))
            .collect::<Vec<_>>()
            .join(" ")
    );
    println!("J2K:  25.16 27.97 30.75 34.31 38.72");
}

/// Levels + refinement: PSNR at byte budgets for several choices of where the levels stop.
#[test]
#[ignore]
fn base_choice() {
    use crate::coding::predictive::Params;
    let budgets = [32usize, 64, 128, 256, 512, 1024, 2048, 4096, 8192];
    let cands: Vec<(u64, u64, u8)> = vec![
        (16, 16, 40),
        (32, 32, 40),
        (64, 64, 40),
        (127, 127, 40),
        (127, 127, 25),
        (127, 381, 40),
        (64, 192, 40),
        (32, 96, 40),
    ];
    let levels: u32 = std::env::var("LEVELS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(6);
    let files = corpus();
    let mut sums = vec![vec![0.0; budgets.len() + 2]; cands.len()];
    for path in &files {
        let img = image::open(path).unwrap().to_rgb8();
        let (w, h) = (img.width() as usize, img.height() as usize);
        let px = img.as_raw().clone();
        let dynimg = image::DynamicImage::ImageRgb8(img.clone());
        for (ci, &(l0, n, q)) in cands.iter().enumerate() {
            let opts = crate::EncodeOptions {
                samples: Some(n),
                first_level: l0,
                coding: Params::from_quality(q).coding(),
                ..Default::default()
            };
            let file = crate::encode(&dynimg, &opts).unwrap();
            let b0 = file.len() + 16; // the refinement's header and first layer's framing
            let (positions, colours) = level_samples(&file, n, w, h);
            let frac = 2;
            let kernel = Kernel::Integer97;
            let pred =
                super::predict::low_band(&positions, &colours, 3, w, h, kernel, levels, frac);
            let mut planes = to_planes(&px, 3, frac);
            let (lw, lh) = low_size(w, h, levels);
            for (c, p) in planes.iter_mut().enumerate() {
                forward(kernel, p, w, h, levels);
                for y in 0..lh {
                    for x in 0..lw {
                        p[y * w + x] -= pred[c][y * lw + x];
                    }
                }
            }
            let layout = Layout {
                width: w,
                height: h,
                channels: 3,
                kernel,
                levels,
                top: planes.iter().map(|p| bitplanes(p)).collect(),
            };
            let coded: Vec<CodedStream> = layout
                .stream_states(Some(&planes))
                .into_iter()
                .map(|mut st| {
                    let ws = pass_weights(&layout, &st.passes);
                    let n = st.passes.len();
                    encode_stream(&mut st, n, &ws)
                })
                .collect();
            let src = Source {
                width: w,
                height: h,
                channels: 3,
                kernel,
                levels,
                frac,
                prediction: &pred,
            };
            let at = |budget: usize| -> f64 {
                if budget < b0 {
                    let d = crate::decode(
                        &file,
                        &crate::DecodeOptions {
                            max_bytes: Some(budget),
                            ..Default::default()
                        },
                    )
                    .unwrap();
                    return psnr(&d.image.to_rgb8().into_raw(), &px);
                }
                let budget = (budget - b0) as f64;
                let (mut lo, mut hi) = (1e-6f64, 1e12f64);
                for _ in 0..80 {
                    let mid = (lo * hi).sqrt();
                    let total: usize = coded
                        .iter()
                        .map(|c| {
                            let k = cut_at(c, mid);
                            if k == 0 {
                                0
                            } else {
                                c.pass_end[k - 1]
                            }
                        })
                        .sum();
                    if total as f64 > budget {
                        lo = mid
                    } else {
                        hi = mid
                    }
                }
                let mut decs: Vec<StreamDecoder> = layout
                    .stream_states(None)
                    .into_iter()
                    .zip(&coded)
                    .map(|(st, c)| {
                        let k = cut_at(c, hi);
                        let mut d = StreamDecoder::new(st, k);
                        d.advance(&c.bytes[..if k == 0 { 0 } else { c.pass_end[k - 1] }]);
                        d
                    })
                    .collect();
                let refs: Vec<Option<&bitplane::StreamState>> =
                    decs.iter_mut().map(|d| Some(&d.state)).collect();
                psnr(&picture(&src, &refs, 0), &px)
            };
            for (bi, &b) in budgets.iter().enumerate() {
                sums[ci][bi] += at(b);
            }
            sums[ci][budgets.len()] += at((0.25 * (w * h) as f64 / 8.0) as usize);
            sums[ci][budgets.len() + 1] += at((1.0 * (w * h) as f64 / 8.0) as usize);
        }
    }
    println!("L0 N q | 32 64 128 256 512 1K 2K 4K 8K | 0.25bpp 1bpp");
    for (ci, c) in cands.iter().enumerate() {
        println!(
            "{c:?}: {}",
            sums[ci]
                .iter()
                .map(|v| format!("{:.2}", v / files.len() as f64))
                .collect::<Vec<_>>()
                .join(" ")
        );
    }
}

/// Pictures at 1/2 … 1/16 of the image size against `image`'s area-averaged downscale.
#[test]
#[ignore]
fn thumbnails() {
    let files = corpus();
    for f in [2u32, 3, 4, 6, 8, 12, 16] {
        let mut sum = 0.0;
        for path in &files {
            let img = image::open(path).unwrap();
            let bytes = crate::encode(&img, &Default::default()).unwrap();
            let (w, h) = (img.width() / f, img.height() / f);
            let want = img.thumbnail_exact(w, h).to_rgb8();
            let got = crate::decode(&bytes, &crate::DecodeOptions::thumbnail(w, h)).unwrap();
            sum += psnr(got.image.to_rgb8().as_raw(), want.as_raw());
        }
        println!("1/{f}: {:.2}", sum / files.len() as f64);
    }
}

/// The refinement's first picture (its prediction alone) against the levels' Gouraud picture
/// of the same samples, for several predictors.
#[test]
#[ignore]
fn start_pictures() {
    use crate::coding::predictive::Params;
    let n: u64 = std::env::var("N")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(64);
    let mut sums = [0.0f64; 4];
    let files = corpus();
    for path in &files {
        let img = image::open(path).unwrap().to_rgb8();
        let (w, h) = (img.width() as usize, img.height() as usize);
        let px = img.as_raw().clone();
        let opts = crate::EncodeOptions {
            target: crate::Target::LevelsOnly,
            samples: Some(n),
            first_level: n,
            coding: Params::from_quality(40).coding(),
            ..Default::default()
        };
        let file = crate::encode(&image::DynamicImage::ImageRgb8(img.clone()), &opts).unwrap();
        let gouraud = crate::decode(&file, &Default::default())
            .unwrap()
            .image
            .to_rgb8()
            .into_raw();
        let (positions, colours) = level_samples(&file, n, w, h);
        let mut row = vec![psnr(&gouraud, &px)];
        for levels in [5u32, 4, 3] {
            let levels = levels.min(super::encode::default_levels(w as u32, h as u32));
            let pred = super::predict::low_band(
                &positions,
                &colours,
                3,
                w,
                h,
                Kernel::Integer97,
                levels,
                2,
            );
            let src = Source {
                width: w,
                height: h,
                channels: 3,
                kernel: Kernel::Integer97,
                levels,
                frac: 2,
                prediction: &pred,
            };
            let streams: Vec<Option<&bitplane::StreamState>> = vec![None; levels as usize + 1];
            row.push(psnr(&picture(&src, &streams, 0), &px));
        }
        for (s, v) in sums.iter_mut().zip(&row) {
            *s += v;
        }
        println!(
            "{}: gouraud {:.2} start L5/4/3 {:.2} {:.2} {:.2}",
            path.display(),
            row[0],
            row[1],
            row[2],
            row[3]
        );
    }
    println!(
        "mean: {}",
        sums.iter()
            .map(|v| format!("{:.2}", v / files.len() as f64))
            .collect::<Vec<_>>()
            .join(" ")
    );
}
