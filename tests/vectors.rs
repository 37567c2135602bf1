//! The conformance set in `spec/vectors/`: small `.qcs` files and the pictures they decode to.
//!
//! Checked by default. `QCS_REGENERATE=1 cargo test --release --test suite vectors::` rewrites every
//! `.qcs`, the expected PNGs and `spec/vectors/README.md` from the definitions below (do it when
//! the encoder or the reconstruction changes on purpose, then review the diff).
//!
//! For each vector `NAME`: `NAME.qcs`, `NAME.png` (the whole file decoded at the image's size,
//! Gouraud) and `NAME.half.png` (the first ⌊len/2⌋ bytes decoded the same way). A decoder matches
//! when every channel of every pixel is within ±1 of the PNG for the levels' picture, and
//! equal to it for the refinement's (version 3, spec/refinement.md). `NAME.samples.csv` and
//! `NAME.half.samples.csv` list the samples each of the two reads, exactly (site, position,
//! colour): what `spec/reference/qcs_ref.py`, a decoder written from the spec alone, checks.

use image::{DynamicImage, GenericImageView};
use qcs::container::{Coding, Header};
use qcs::sampling::SampleColour;
use qcs::sites::Frame;
use qcs::{DecodeOptions, EncodeOptions, Target};
use std::path::{Path, PathBuf};

/// Largest per-channel difference a conforming decoder may show in the levels' picture (the
/// refinement's is exact).
const TOLERANCE: u8 = 1;

struct Vector {
    name: &'static str,
    what: &'static str,
    image: DynamicImage,
    opts: EncodeOptions,
    /// A file made by hand from the encoder's (see [`garbage_streams`]), instead of it.
    craft: Option<fn(&DynamicImage, &EncodeOptions) -> Vec<u8>>,
}

impl Vector {
    fn bytes(&self) -> Vec<u8> {
        match self.craft {
            Some(f) => f(&self.image, &self.opts),
            None => qcs::encode(&self.image, &self.opts).expect("encode vector"),
        }
    }
}

/// A version-3 file whose levels are the encoder's and whose refinement streams are bytes no
/// encoder writes (0xFF runs and patterns) under a header with 30 bit-planes a channel: what
/// a decoder makes of them is still fixed by the spec (the range decoder's `hi < range`
/// rule, the transform's 32-bit wrap-around, the clamps).
fn garbage_streams(image: &DynamicImage, opts: &EncodeOptions) -> Vec<u8> {
    crafted_refinement(image, opts, 2, 30)
}

/// Like [`garbage_streams`] with one fraction bit (F = 1, which no qcs encoder writes: the
/// coded channels' YCoCg-R then floors, and the picture rounds from 2 fraction bits) and 5
/// bit-planes a channel, so that most pixels stay within 0..=255 and the rounding shows.
fn garbage_streams_f1(image: &DynamicImage, opts: &EncodeOptions) -> Vec<u8> {
    crafted_refinement(image, opts, 1, 5)
}

/// The encoder's levels, then a 9/7 refinement (L = 2) of fraction bits `f` and `bitplanes`
/// a channel, every pass, in two layers of patterned bytes.
fn crafted_refinement(image: &DynamicImage, opts: &EncodeOptions, f: u8, bitplanes: u8) -> Vec<u8> {
    use qcs::container::{ContainerWriter, PassLimit, RefinementHeader, Wavelet};
    let levels = EncodeOptions {
        target: Target::LevelsOnly,
        ..opts.clone()
    };
    let file = qcs::encode(image, &levels).expect("levels");
    let (mut header, _) = Header::parse(&file).expect("header");
    header.refinement = true;
    let mut dec = qcs::StreamDecoder::new(qcs::Limits::default());
    dec.push(&file).expect("levels decode");
    // The levels' payloads, read back from the file's chunks.
    let info = qcs::container::inspect(&file);
    let mut w = ContainerWriter::new(Vec::new(), &header).expect("writer");
    for level in &info.levels {
        let c = level.chunk.expect("level present");
        let start = c.offset as usize + usize::from(c.index > 0);
        let (len, n) = qcs::container::varint::read(&file[start..], 32)
            .expect("length")
            .expect("complete");
        let from = start + n;
        w.write_level(&file[from..from + len as usize])
            .expect("level");
    }
    let channels = header.layout.channels() as usize;
    let r = RefinementHeader {
        wavelet: Wavelet::Integer97,
        fraction_bits: f,
        levels: 2,
        bitplanes: vec![bitplanes; channels],
        layers: 2,
        limit: PassLimit::Key(i32::MIN),
    };
    let pattern = |len: usize, seed: u8| -> Vec<u8> {
        (0..len)
            .map(|i| match (i / 7) % 3 {
                0 => 0xFF,
                1 => seed.wrapping_mul(i as u8 | 1),
                _ => 0x80 ^ i as u8,
            })
            .collect()
    };
    let (a, b, c) = (pattern(40, 3), pattern(25, 5), pattern(30, 7));
    w.write_layer(&r, &[&a, &b]).expect("layer");
    w.write_layer(&r, &[&c, &[0xFF; 12], &pattern(20, 9)])
        .expect("layer");
    w.finish().expect("finish")
}

fn dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("spec/vectors")
}

/// A deterministic test picture: gradients, a disc and a hard diagonal edge, per channel.
fn pattern(w: u32, h: u32, channels: usize) -> Vec<u8> {
    let mut out = Vec::with_capacity((w * h) as usize * channels);
    for y in 0..h {
        for x in 0..w {
            let (fx, fy) = (x as f64 / w as f64, y as f64 / h as f64);
            let d = ((fx - 0.6).powi(2) + (fy - 0.45).powi(2)).sqrt();
            let disc = d < 0.28;
            let edge = x + 2 * y > w;
            for k in 0..channels {
                let v = match k {
                    0 if disc => 230.0 - 200.0 * d,
                    0 => 40.0 + 180.0 * fx,
                    1 if edge => 200.0 * fy + 30.0,
                    1 => 20.0 + 60.0 * fx,
                    2 => 255.0 * (1.0 - fx) * (0.5 + 0.5 * fy),
                    // Alpha: opaque top-left, fading to a quarter at the bottom right.
                    _ => 255.0 - 190.0 * (fx + fy) / 2.0,
                };
                out.push(v.round().clamp(0.0, 255.0) as u8);
            }
        }
    }
    out
}

fn vectors() -> Vec<Vector> {
    let grey = |w, h| {
        DynamicImage::ImageLuma8(image::GrayImage::from_raw(w, h, pattern(w, h, 1)).unwrap())
    };
    let rgb =
        |w, h| DynamicImage::ImageRgb8(image::RgbImage::from_raw(w, h, pattern(w, h, 3)).unwrap());
    let rgba = |w, h| {
        DynamicImage::ImageRgba8(image::RgbaImage::from_raw(w, h, pattern(w, h, 4)).unwrap())
    };
    let grey_alpha = |w, h| {
        let mut px = pattern(w, h, 4);
        // Grey and the alpha channel of the RGBA pattern.
        px = px.chunks_exact(4).flat_map(|p| [p[0], p[3]]).collect();
        DynamicImage::ImageLumaA8(image::GrayAlphaImage::from_raw(w, h, px).unwrap())
    };
    let base = |n, bits| EncodeOptions {
        target: qcs::Target::LevelsOnly,
        samples: Some(n),
        coding: Coding::Raw { bits },
        first_level: 8,
        colour: SampleColour::Progressive,
        ..Default::default()
    };
    vec![
        Vector {
            name: "grey-8",
            what: "grey, raw 8 bits, default lattice",
            image: grey(32, 24),
            opts: base(120, 8),
            craft: None,
        },
        Vector {
            name: "rgb-8",
            what: "RGB, raw 8 bits, default lattice",
            image: rgb(40, 30),
            opts: base(150, 8),
            craft: None,
        },
        Vector {
            name: "rgba-8",
            what: "RGBA, raw 8 bits, default lattice, alpha gradient",
            image: rgba(32, 32),
            opts: base(128, 8),
            craft: None,
        },
        Vector {
            name: "rgb-5",
            what: "RGB, raw 5 bits (samples straddle bytes), L0 = 5",
            image: rgb(48, 32),
            opts: EncodeOptions {
                first_level: 5,
                ..base(192, 5)
            },
            craft: None,
        },
        Vector {
            name: "rgb-5-frame",
            what: "RGB, raw 5 bits, explicit lattice: root 1.5 px, origin (−7.25, −20.5) px",
            image: rgb(36, 36),
            opts: EncodeOptions {
                frame: Some(Frame {
                    root_len: 0x1_8000,
                    origin: [-(7 << 16) - 0x4000, -(20 << 16) - 0x8000],
                }),
                ..base(160, 5)
            },
            craft: None,
        },
        Vector {
            name: "rgb-predictive-q75",
            what: "RGB, predictive coding (coding 1) at quality 75",
            image: rgb(48, 40),
            opts: EncodeOptions {
                coding: Coding::Predictive {
                    step: qcs::coding::predictive::Params::from_quality(75).step,
                },
                ..base(240, 8)
            },
            craft: None,
        },
        Vector {
            name: "rgb-predictive-defaults",
            what: "RGB, levels only (version 2) at that version's defaults: predictive at quality 75, fitted \
                   colours, 1 sample per 4 px and L0 = 127, so the header leaves both fields out (format byte bit 3)",
            image: rgb(48, 48),
            opts: EncodeOptions {
                target: qcs::Target::LevelsOnly,
                coding: qcs::coding::predictive::Params::from_quality(75).coding(),
                ..Default::default()
            },
            craft: None,
        },
        Vector {
            name: "grey-predictive-lossless",
            what: "grey, predictive coding, lossless samples",
            image: grey(32, 32),
            opts: EncodeOptions {
                coding: Coding::Predictive { step: 1 },
                ..base(128, 8)
            },
            craft: None,
        },
        Vector {
            name: "grey-8-text",
            what: "grey, raw 8 bits, two text chunks after level 0 (one with a UTF-8 value), an \
                   Exif chunk (`e`: orientation 1, big-endian) after the last level",
            image: grey(24, 24),
            opts: EncodeOptions {
                text: vec![
                    ("Title".into(), "qcs conformance".into()),
                    ("Comment".into(), "Penrose — τ = 1.618…".into()),
                ],
                // A TIFF header (MM, 42, IFD at 8) and one IFD: Orientation (0x0112), SHORT, 1.
                exif: Some(vec![
                    0x4d, 0x4d, 0, 42, 0, 0, 0, 8, 0, 1, 0x01, 0x12, 0, 3, 0, 0, 0, 1, 0, 1, 0,
                    0, 0, 0, 0, 0,
                ]),
                ..base(72, 8)
            },
            craft: None,
        },
        Vector {
            name: "grey-8-wide",
            what: "grey, raw 8 bits, 6 samples of a wide image (W > 4·H), L0 = 1: in the half picture \
                   (2 samples) 116 of the 192 pixels are outside the hull (reconstruction.md §5)",
            image: grey(48, 4),
            opts: EncodeOptions {
                first_level: 1,
                ..base(6, 8)
            },
            craft: None,
        },
        Vector {
            name: "rgb-refined-q85",
            what: "version 3 at the encoder's defaults: 64 samples at predictive quality 40 (header defaults \
                   bit), then a 9/7 refinement to quality 85 (a key limit)",
            image: rgb(48, 40),
            opts: EncodeOptions::default(),
            craft: None,
        },
        Vector {
            name: "rgb-refined-size",
            what: "version 3, a refinement cut to fill 700 bytes (a pass count per stream)",
            image: rgb(47, 33),
            opts: EncodeOptions {
                target: Target::Size(700),
                ..Default::default()
            },
            craft: None,
        },
        Vector {
            name: "grey-refined-lossless",
            what: "version 3, lossless: a 5/3 refinement of every bit-plane, F = 0",
            image: grey(37, 23),
            opts: EncodeOptions {
                target: Target::Lossless,
                ..Default::default()
            },
            craft: None,
        },
        Vector {
            name: "rgba-refined-lossless",
            what: "version 3, lossless RGBA (alpha too), odd size",
            image: rgba(29, 21),
            opts: EncodeOptions {
                target: Target::Lossless,
                ..Default::default()
            },
            craft: None,
        },
        Vector {
            name: "grey-alpha-refined-q90",
            what: "version 3, grey+alpha, quality 90 over 20 raw 6-bit samples in levels of 5, 10, 5 \
                   (the header's fields written out)",
            image: grey_alpha(44, 30),
            opts: EncodeOptions {
                target: Target::Quality(90),
                samples: Some(20),
                first_level: 5,
                coding: Coding::Raw { bits: 6 },
                ..Default::default()
            },
            craft: None,
        },
        Vector {
            name: "rgb-refined-blocks",
            what: "version 3, quality 70, 96×80: three transform levels and several 32 × 32 blocks in the finest \
                   bands (their spread order, block contexts, neighbours across blocks)",
            image: rgb(96, 80),
            opts: EncodeOptions {
                target: Target::Quality(70),
                ..Default::default()
            },
            craft: None,
        },
        Vector {
            name: "grey-refined-thin",
            what: "version 3, 1×40: the high halves of rows are empty, so the HL and HH bands are (their \
                   passes count but code nothing)",
            image: grey(1, 40),
            opts: EncodeOptions::default(),
            craft: None,
        },
        Vector {
            name: "rgb-refined-tiny",
            what: "version 3, 3×1: no transform level (L = 0), 3 samples (fewer than the prediction's 4 \
                   neighbours)",
            image: rgb(3, 1),
            opts: EncodeOptions::default(),
            craft: None,
        },
        Vector {
            name: "rgb-refined-garbage",
            what: "made by hand: the encoder's levels, then two layers of bytes no encoder writes under a \
                   header of 30 bit-planes a channel (the range decoder's hi < range rule, the transform's \
                   wrap-around, the clamps)",
            image: rgb(40, 30),
            opts: EncodeOptions {
                target: Target::Quality(50),
                samples: Some(64),
                first_level: 64,
                ..Default::default()
            },
            craft: Some(garbage_streams),
        },
        Vector {
            name: "rgba-refined-f1",
            what: "made by hand: the encoder's levels, then a refinement with one fraction bit (F = 1, \
                   which qcs does not write: YCoCg-R floors in the prediction's coded channels) and two \
                   layers of patterned bytes under 5 bit-planes a channel",
            image: rgba(27, 22),
            opts: EncodeOptions {
                target: Target::Quality(50),
                samples: Some(64),
                first_level: 64,
                ..Default::default()
            },
            craft: Some(garbage_streams_f1),
        },
    ]
}

fn decode_png(bytes: &[u8]) -> DynamicImage {
    qcs::decode(bytes, &DecodeOptions::default())
        .expect("vector decodes")
        .image
}

/// The other size each vector's whole file is drawn at (`NAME.WxH.png`): wider and less
/// high than the image, so that both rules of refinement.md §8 (*At another size*) and the
/// levels' picture at other pixel centres are checked.
fn other_size(width: u32, height: u32) -> (u32, u32) {
    (width + width / 2 + 1, (2 * height / 3).max(1))
}

/// The whole file decoded at [`other_size`] (the spec's picture, not a thumbnail), and the
/// name of its PNG.
fn decode_at_other_size(name: &str, bytes: &[u8]) -> (String, qcs::DecodedImage) {
    let (h, _) = Header::parse(bytes).expect("own header");
    let (w, h) = other_size(h.width, h.height);
    let opts = DecodeOptions {
        size: Some((w, h)),
        thumbnail: false,
        ..Default::default()
    };
    let decoded = qcs::decode(bytes, &opts).expect("vector decodes");
    (format!("{name}.{w}x{h}.png"), decoded)
}

/// Every sample a decoder reads from `bytes`, as CSV: index, lattice point, position (6
/// decimals), colour channels in the file's layout.
fn samples_csv(bytes: &[u8]) -> String {
    let mut dec = qcs::StreamDecoder::new(qcs::Limits::default());
    dec.push(bytes).expect("vector decodes");
    let c = dec.header().expect("header").layout.channels() as usize;
    let (sites, colours) = dec.samples(u64::MAX);
    let mut out = String::from("index,n0,n1,n2,n3,x,y,colour\n");
    for (i, (s, col)) in sites.iter().zip(colours.chunks_exact(c)).enumerate() {
        let [n0, n1, n2, n3] = s.lattice.0;
        let col: Vec<String> = col.iter().map(u8::to_string).collect();
        out += &format!(
            "{i},{n0},{n1},{n2},{n3},{:.6},{:.6},{}\n",
            s.pos[0],
            s.pos[1],
            col.join(" ")
        );
    }
    out
}

/// The cuts listed in `NAME.cuts.csv`: every byte around the start of the refinement (its
/// header, first segment table and first stream bytes), and about 40 more spread over the
/// file.
fn cuts(bytes: &[u8]) -> Vec<usize> {
    let len = bytes.len();
    let mut out: Vec<usize> = (0..=len).step_by(len.div_ceil(40).max(1)).collect();
    if let Some(at) = qcs::container::inspect(bytes).refinement_offset {
        let at = at as usize;
        out.extend(at.saturating_sub(4)..=(at + 64).min(len));
    }
    out.push(len);
    out.sort_unstable();
    out.dedup();
    out
}

/// `bytes,samples,refined,crc32` for each cut of [`cuts`]: the samples a decoder reads, whether
/// the picture is the refinement's, and if so the CRC-32 of its pixels (the layout's bytes,
/// row by row), which the refinement fixes exactly.
fn cuts_csv(bytes: &[u8]) -> String {
    let mut out = String::from("bytes,samples,refined,crc32\n");
    for cut in cuts(bytes) {
        let prefix = &bytes[..cut];
        let mut dec = qcs::StreamDecoder::new(qcs::Limits::default());
        let samples = match dec.push(prefix) {
            Ok(()) => dec.samples_available(),
            Err(e) => panic!("cut {cut}: {e}"),
        };
        match qcs::decode(prefix, &DecodeOptions::default()) {
            Ok(d) if d.refined => {
                let crc = crc32fast::hash(d.image.as_bytes());
                out += &format!("{cut},{samples},1,{crc:08x}\n");
            }
            _ => out += &format!("{cut},{samples},0,\n"),
        }
    }
    out
}

fn write_png(path: &Path, img: &DynamicImage) {
    img.save_with_format(path, image::ImageFormat::Png)
        .unwrap_or_else(|e| panic!("writing {}: {e}", path.display()));
}

fn max_diff(a: &DynamicImage, b: &DynamicImage) -> u8 {
    assert_eq!(a.dimensions(), b.dimensions(), "size");
    assert_eq!(a.color(), b.color(), "layout");
    a.as_bytes()
        .iter()
        .zip(b.as_bytes())
        .map(|(x, y)| x.abs_diff(*y))
        .max()
        .unwrap_or(0)
}

fn regenerate() {
    let mut table = String::new();
    for v in vectors() {
        let bytes = v.bytes();
        let (h, header_len) = Header::parse(&bytes).expect("own header");
        std::fs::write(dir().join(format!("{}.qcs", v.name)), &bytes).expect("write vector");
        write_png(&dir().join(format!("{}.png", v.name)), &decode_png(&bytes));
        write_png(
            &dir().join(format!("{}.half.png", v.name)),
            &decode_png(&bytes[..bytes.len() / 2]),
        );
        let (other, decoded) = decode_at_other_size(v.name, &bytes);
        write_png(&dir().join(other), &decoded.image);
        for (suffix, prefix) in [
            ("samples.csv", bytes.len()),
            ("half.samples.csv", bytes.len() / 2),
        ] {
            let path = dir().join(format!("{}.{suffix}", v.name));
            std::fs::write(path, samples_csv(&bytes[..prefix])).expect("write samples");
        }
        std::fs::write(dir().join(format!("{}.cuts.csv", v.name)), cuts_csv(&bytes))
            .expect("write cuts");
        let coding = match h.coding {
            Coding::Raw { bits } => format!("raw, B = {bits}"),
            Coding::Predictive { step } => format!("predictive, s = {step}"),
        };
        let info = qcs::container::inspect(&bytes);
        let refinement = match (&info.refinement, info.refinement_offset) {
            (Some(r), Some(at)) => format!(
                "{:?} L = {}, F = {}, {} layers, from byte {at}",
                r.wavelet, r.levels, r.fraction_bits, r.layers
            ),
            _ => "—".into(),
        };
        table.push_str(&format!(
            "| `{}` | {} | {}×{} | {:?} | {} | {} | {} | {} | {} | {} | {} |\n",
            v.name,
            h.version(),
            h.width,
            h.height,
            h.layout,
            coding,
            h.total_samples,
            h.first_level,
            h.level_count(),
            header_len,
            refinement,
            bytes.len(),
        ));
        table.push_str(&format!("|   | {} |||||||||||\n", v.what));
    }
    let readme = format!(
        "# Conformance vectors\n\n\
         Small `.qcs` files (spec/format.md, spec/sites.md) and the pictures they decode to.\n\
         Generated by `tests/vectors.rs`; do not edit by hand.\n\n\
         For each `NAME`:\n\n\
         - `NAME.qcs`: the file.\n\
         - `NAME.png`: the whole file decoded at the image's own size (the levels' Gouraud picture,\n  \
           or the refinement's in version 3).\n\
         - `NAME.half.png`: the first ⌊len / 2⌋ bytes decoded the same way (a cut download: the\n  \
           verified levels plus the complete, unverified samples of the partial level chunk, or\n  \
           in version 3 the refinement's picture from the bytes of its streams received).\n\
         - `NAME.WxH.png`: the whole file decoded at another size, W = w + ⌊w/2⌋ + 1 and\n  \
           H = max(1, ⌊2h/3⌋) for a w × h image: the levels' picture at the output's pixel\n  \
           centres (spec/reconstruction.md), or the refinement's resized by both rules of\n  \
           spec/refinement.md §8, *At another size* (larger across, smaller down).\n\
         - `NAME.samples.csv`, `NAME.half.samples.csv`: the samples a decoder reads from the whole\n  \
           file and from its first half, exactly: `index,n0,n1,n2,n3,x,y,colour` (the site's\n  \
           lattice point, its pixel position to 6 decimals, its channels in the file's layout,\n  \
           separated by spaces).\n\
         - `NAME.cuts.csv`: `bytes,samples,refined,crc32` for many prefixes (every byte around\n  \
           the start of a refinement, about 40 more over the file): the samples a decoder\n  \
           reads, whether the picture is the refinement's (1) or the levels' (0), and for the\n  \
           refinement's the CRC-32 (format.md) of its pixels, the layout's bytes row by row.\n\n\
         A decoder conforms when it reads exactly those samples (positions within 10⁻⁵ px) and\n\
         every channel of every pixel is within ±{TOLERANCE} of the PNG for the levels' picture\n\
         (spec/reconstruction.md), and equal to it for the refinement's (spec/refinement.md).\n\
         `spec/reference/` holds a decoder written from the spec alone, which checks itself\n\
         against them.\n\
         The PNGs follow the reference reconstruction, which may still change: regenerate every\n\
         file with one command,\n\n\
         ```\nQCS_REGENERATE=1 cargo test --release --test suite vectors::\n```\n\n\
         and review the diff. `cargo test` checks them otherwise (and that the encoder still\n\
         writes the same bytes). The sample colours are the encoder's choice:\n\
         `SampleColour::Progressive`, but the encoder's default (`SampleColour::Fitted`) in\n\
         `rgb-predictive-defaults` and the version-3 vectors. The files, not the encoder, are the\n\
         reference.\n\n\
         | name | version | size | layout | levels' coding | N | L0 | levels | header bytes | refinement | file bytes |\n\
         |---|---|---|---|---|---|---|---|---|---|---|\n{table}\n\
         The `sites-*.csv` files are the site-sequence vectors of spec/sites.md (not part of this\n\
         set).\n"
    );
    std::fs::write(dir().join("README.md"), readme).expect("write README");
}

/// Asserts that `decoded` is the vector PNG `name` (exactly for the refinement's picture,
/// within the tolerance for the levels'), and says by how much it differs.
fn matches_png(name: &str, decoded: &qcs::DecodedImage) -> String {
    let path = dir().join(name);
    let want = image::open(&path)
        .unwrap_or_else(|e| panic!("{}: {e} (QCS_REGENERATE=1 writes it)", path.display()));
    let tolerance = if decoded.refined { 0 } else { TOLERANCE };
    let d = max_diff(&decoded.image, &want);
    assert!(
        d <= tolerance,
        "{}: max channel difference {d} > {tolerance}",
        path.display()
    );
    format!("{name}: max diff {d}")
}

fn regenerating() -> bool {
    std::env::var_os("QCS_REGENERATE").is_some_and(|v| v == "1")
}

#[test]
fn vectors_decode_to_their_samples_and_pngs() {
    if regenerating() {
        regenerate();
    }
    let mut report = Vec::new();
    for v in vectors() {
        let bytes = std::fs::read(dir().join(format!("{}.qcs", v.name)))
            .unwrap_or_else(|e| panic!("{}.qcs: {e} (QCS_REGENERATE=1 writes it)", v.name));
        for (half, prefix) in [("", bytes.len()), ("half.", bytes.len() / 2)] {
            let decoded =
                qcs::decode(&bytes[..prefix], &DecodeOptions::default()).expect("decodes");
            report.push(matches_png(&format!("{}.{half}png", v.name), &decoded));
            let path = dir().join(format!("{}.{half}samples.csv", v.name));
            let want = std::fs::read_to_string(&path)
                .unwrap_or_else(|e| panic!("{}: {e} (QCS_REGENERATE=1 writes it)", path.display()));
            assert!(
                samples_csv(&bytes[..prefix]) == want,
                "{}: the decoder reads other samples now",
                path.display()
            );
        }
        let (other, decoded) = decode_at_other_size(v.name, &bytes);
        report.push(matches_png(&other, &decoded));
        let path = dir().join(format!("{}.cuts.csv", v.name));
        let want = std::fs::read_to_string(&path)
            .unwrap_or_else(|e| panic!("{}: {e} (QCS_REGENERATE=1 writes it)", path.display()));
        assert!(
            cuts_csv(&bytes) == want,
            "{}: another picture or sample count at some cut",
            path.display()
        );
    }
    eprintln!("{}", report.join("\n"));
}

#[test]
fn vectors_are_what_the_encoder_writes() {
    if regenerating() {
        return; // the other test rewrites them
    }
    for v in vectors() {
        let want = std::fs::read(dir().join(format!("{}.qcs", v.name))).expect("vector");
        let got = v.bytes();
        assert!(
            got == want,
            "{}: the encoder writes other bytes now",
            v.name
        );
    }
}

#[test]
fn vectors_cover_what_the_set_promises() {
    use qcs::container::{inspect, Layout, Metadata};
    let mut layouts = Vec::new();
    let (mut bits5, mut bits8, mut frame, mut text, mut exif) = (false, false, false, false, false);
    // Refinements: lossy (9/7) and lossless (5/3), a key limit and counts, all four layouts,
    // and a half picture drawn by the refinement from part of its streams.
    let (mut lossy, mut lossless, mut by_key, mut by_count, mut half_refined) =
        (false, false, false, false, false);
    let mut refined_layouts = Vec::new();
    // Every fraction bit count the format allows (refinement.md §1: 0..=3).
    let mut fractions = [false; 4];
    // Headers with the format byte's defaults bit and without it.
    let mut defaults = [false; 2];
    for v in vectors() {
        let bytes = std::fs::read(dir().join(format!("{}.qcs", v.name))).expect("vector");
        assert!(bytes.len() < 8192, "{}: keep vectors tiny", v.name);
        let ins = inspect(&bytes);
        assert!(ins.error.is_none(), "{}: {:?}", v.name, ins.error);
        let h = ins.header.expect("header");
        assert!(h.width <= 96 && h.height <= 96);
        assert_eq!(
            ins.samples_verified, h.total_samples,
            "{}: complete",
            v.name
        );
        layouts.push(h.layout);
        defaults[usize::from(bytes[2] & 0x08 != 0)] = true;
        if let Some(r) = &ins.refinement {
            assert_eq!(ins.layers_verified, r.layers, "{}: complete", v.name);
            refined_layouts.push(h.layout);
            lossy |= r.wavelet == qcs::container::Wavelet::Integer97;
            fractions[usize::from(r.fraction_bits)] = true;
            lossless |= r.wavelet == qcs::container::Wavelet::Reversible53;
            by_key |= matches!(r.limit, qcs::container::PassLimit::Key(_));
            by_count |= matches!(r.limit, qcs::container::PassLimit::Counts(_));
            let half = qcs::decode(&bytes[..bytes.len() / 2], &DecodeOptions::default())
                .expect("half decodes");
            half_refined |= half.refined;
        }
        bits5 |= h.coding == Coding::Raw { bits: 5 };
        bits8 |= h.coding == Coding::Raw { bits: 8 };
        frame |= h.lattice.is_some();
        text |= ins
            .metadata
            .iter()
            .any(|m| matches!(m, Metadata::Text { .. }));
        exif |= ins.metadata.iter().any(|m| matches!(m, Metadata::Exif(_)));
    }
    for l in [Layout::Grey, Layout::Rgb, Layout::Rgba] {
        assert!(layouts.contains(&l), "{l:?} missing");
    }
    assert!(bits5 && bits8 && frame && text && exif && defaults == [true; 2]);
    for l in [Layout::Grey, Layout::GreyAlpha, Layout::Rgb, Layout::Rgba] {
        assert!(
            refined_layouts.contains(&l),
            "{l:?} missing among the refined"
        );
    }
    assert!(lossy && lossless && by_key && by_count && half_refined);
    assert_eq!(fractions, [true; 4], "F = 0..=3 (refinement.md §1)");
}

/// The decoder written from the spec alone (`spec/reference/qcs_ref.py`) reads exactly the
/// samples listed for every vector, whole and cut, and the site vectors' sites. Needs
/// `python3`; where it is missing the test says so and passes.
#[test]
fn a_decoder_written_from_the_spec_alone_agrees() {
    let has_python = std::process::Command::new("python3")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    if !has_python {
        eprintln!("skipped: python3 not found (spec/reference/check.sh needs it)");
        return;
    }
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("spec/reference/check.sh");
    let out = std::process::Command::new("sh")
        .arg(&script)
        .output()
        .expect("sh runs");
    let report = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success() && report.contains("PASS") && !report.contains("FAIL"),
        "{report}{}",
        String::from_utf8_lossy(&out.stderr)
    );
}
