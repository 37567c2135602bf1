//! `qcs info`: a .qcs file's header, chunks, levels and CRC status.

use super::input::ReadQcs;
use super::Ctx;
use anyhow::{Context, Result};
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct InfoArgs {
    /// The .qcs file (`-`: standard input).
    pub input: PathBuf,
}

pub fn info(a: InfoArgs, ctx: &Ctx) -> Result<()> {
    let src = super::input::Source::open(&a.input)?;
    let how = ReadQcs {
        budget: None,
        recover: true,
    };
    let input = super::input::read_qcs(src, &how, ctx, |_| Ok(()))?;
    let ins = qcs::container::inspect(&input.bytes);
    match &input.refused {
        None => say!("file: {} ({} bytes)", a.input.display(), ins.file_len),
        Some(_) => say!(
            "file: {} ({} bytes read: reading stopped where it was refused)",
            a.input.display(),
            ins.file_len
        ),
    }
    if let Some(h) = &ins.header {
        say!(
            "version {} ({}), {}×{} {:?}, {} samples, first level {}",
            h.version(),
            if h.refinement {
                "levels, then a refinement"
            } else {
                "levels only"
            },
            h.width,
            h.height,
            h.layout,
            h.total_samples,
            h.first_level
        );
        say!("levels' coding: {}", h.coding);
        match h.lattice {
            Some(l) => say!(
                "lattice: root {} px, origin ({}, {}) px",
                l.root_length as f64 / 65536.0,
                l.origin_x as f64 / 65536.0,
                l.origin_y as f64 / 65536.0
            ),
            None => say!("lattice: default (1 px per root, origin at (-W/2, -H/3))"),
        }
        say!(
            "header: {} bytes, check byte ok (level 0's CRC covers it too)",
            ins.header_len.unwrap_or(0)
        );
    }
    say!(
        "{:>5} {:>5} {:>10} {:>19} {:>9} {:>9}  status",
        "chunk",
        "tag",
        "offset",
        "samples",
        "payload",
        "present"
    );
    for c in &ins.chunks {
        let lvl = c.level.and_then(|k| ins.levels.get(k as usize));
        let samples = lvl.map_or(String::from("-"), |l| {
            format!("{}..{}", l.samples.start, l.samples.end)
        });
        let present = lvl.map_or(String::from("-"), |l| l.payload_present.to_string());
        let status = match &c.status {
            qcs::container::ChunkStatus::Verified => "CRC ok".to_string(),
            qcs::container::ChunkStatus::Truncated => "truncated".to_string(),
            qcs::container::ChunkStatus::Bad(e) => format!("BAD: {e}"),
        };
        say!(
            "{:>5} {:>5} {:>10} {:>19} {:>9} {:>9}  {}",
            c.chunk.index,
            qcs::container::chunk::tag_name(c.chunk.tag),
            c.chunk.offset,
            samples,
            c.payload_len.map_or(String::from("?"), |l| l.to_string()),
            present,
            status
        );
    }
    let missing = ins.levels.iter().filter(|l| l.chunk.is_none()).count();
    if missing > 0 {
        say!("{missing} level(s) not in the file");
    }
    if let (Some(r), Some(at)) = (&ins.refinement, ins.refinement_offset) {
        let wavelet = match r.wavelet {
            qcs::container::Wavelet::Reversible53 => "reversible 5/3",
            qcs::container::Wavelet::Integer97 => "9/7",
        };
        let passes = match &r.limit {
            qcs::container::PassLimit::Key(k) => format!("every pass with key ≥ {k}"),
            qcs::container::PassLimit::Counts(c) => format!("passes per stream {c:?}"),
        };
        say!(
            "refinement: from byte {at} (the levels end there), {} bytes: {wavelet}, {} levels, \
             {} fraction bits, bit-planes {:?}, {passes}",
            ins.refinement_bytes().map_or(0, |r| r.end - r.start),
            r.levels,
            r.fraction_bits,
            r.bitplanes,
        );
        say!(
            "refinement: {} of {} layers verified; bytes per stream {:?}",
            ins.layers_verified,
            r.layers,
            ins.stream_bytes
        );
    }
    for m in &ins.metadata {
        match m {
            qcs::container::Metadata::Icc(p) => say!("ICC profile: {} bytes", p.len()),
            qcs::container::Metadata::Exif(p) => say!("Exif: {} bytes", p.len()),
            qcs::container::Metadata::Text { key, value } => say!("text: {key} = {value}"),
        }
    }
    say!(
        "samples: {} available, {} verified; end: {}",
        ins.samples_available,
        ins.samples_verified,
        ins.end
    );
    match (input.refused, ins.error) {
        (Some(e @ qcs::Error::Limits(_)), _) => Err(e).with_context(|| {
            format!(
                "{} exceeds the limits `qcs decode` applies (--max-pixels, --max-samples \
                 raise them)",
                a.input.display()
            )
        }),
        (Some(e), _) | (None, Some(e)) if ins.header.is_none() => {
            Err(e).with_context(|| format!("{} is not a .qcs file qcs can read", a.input.display()))
        }
        (Some(e), _) | (None, Some(e)) => {
            Err(e).with_context(|| format!("{} is damaged", a.input.display()))
        }
        (None, None) => Ok(()),
    }
}
