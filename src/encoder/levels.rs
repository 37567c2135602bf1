//! The levels of a file: the sample colours, their coded payloads, and the colours a decoder
//! reads back (which the refinement's prediction starts from).

use crate::coding::predictive::{Params, PredictiveEncoder};
use crate::coding::raw;
use crate::container::{Coding, Header};
use crate::sampling::{SampleColour, SourceImage};
use crate::sites::{fixed_position, Quasicrystal, Site};
use crate::Result;

/// Coded levels.
pub(crate) struct Levels {
    /// Each sample's fixed-point position (spec/format.md, *Positions*).
    pub fixed: Vec<[i64; 2]>,
    /// Each level's payload.
    pub payloads: Vec<Vec<u8>>,
    /// The decoded colours, in the file's layout.
    pub decoded: Vec<u8>,
}

/// Codes the levels `header` describes (its N, L0, coding) of `source`, sampled at the sites of
/// `seq` with the colour rule `colour`.
pub(crate) fn code(
    source: &SourceImage,
    seq: &Quasicrystal,
    header: &Header,
    colour: SampleColour,
) -> Result<Levels> {
    code_sites(seq, header, |sites, total| match colour {
        SampleColour::Fitted => source.fitted(sites, seq.frame(), first_level(header), total),
        rule => {
            let positions: Vec<_> = sites.iter().map(|s| s.pos).collect();
            source.colours(&positions, rule, total)
        }
    })
}

/// [`code`] for the last use of `source`: fitted colours reuse its memory
/// ([`SourceImage::into_fitted`]).
pub(crate) fn code_last(
    source: SourceImage,
    seq: &Quasicrystal,
    header: &Header,
    colour: SampleColour,
) -> Result<Levels> {
    if colour != SampleColour::Fitted {
        return code(&source, seq, header, colour);
    }
    code_sites(seq, header, |sites, total| {
        source.into_fitted(sites, seq.frame(), first_level(header), total)
    })
}

fn first_level(header: &Header) -> usize {
    usize::try_from(header.first_level).unwrap_or(usize::MAX)
}

/// The levels of `header` whose colours `colours(sites, total)` gives.
fn code_sites(
    seq: &Quasicrystal,
    header: &Header,
    colours: impl FnOnce(&[Site], usize) -> Vec<u8>,
) -> Result<Levels> {
    let n = header.total_samples as usize;
    let channels = header.layout.channels() as usize;
    let sites = seq.first(n);
    let frame = seq.frame();
    let fixed: Vec<[i64; 2]> = sites
        .iter()
        .map(|s| fixed_position(&frame, s.lattice))
        .collect();
    let colours = colours(&sites, n);
    let mut predictive = match header.coding {
        Coding::Predictive { step } => Some(PredictiveEncoder::new(
            Params { step },
            channels as u8,
            header.width,
            header.height,
        )?),
        Coding::Raw { .. } => None,
    };
    let mut payloads = Vec::with_capacity(header.level_count() as usize);
    let mut decoded = Vec::with_capacity(colours.len());
    for k in 0..header.level_count() {
        let range = header.level_range(k).expect("level below level_count");
        let (a, b) = (range.start as usize, range.end as usize);
        let values = &colours[a * channels..b * channels];
        payloads.push(match (&header.coding, &mut predictive) {
            (Coding::Raw { bits }, _) => {
                decoded.extend(
                    values
                        .iter()
                        .map(|&v| raw::dequantise(raw::quantise(v, *bits), *bits)),
                );
                raw::pack(values, *bits)?
            }
            (Coding::Predictive { .. }, Some(enc)) => enc.encode_level(&fixed[a..b], values)?,
            (Coding::Predictive { .. }, None) => unreachable!("a predictive encoder was made"),
        });
    }
    if let Some(enc) = &predictive {
        decoded = enc.reconstructed();
    }
    Ok(Levels {
        fixed,
        payloads,
        decoded,
    })
}
