//! Reading inputs in bounded memory: a .qcs file is read a block at a time through a push
//! decoder, which refuses a bad file at its first bad byte, and no more than `--bytes` and
//! `--max-input` allow is ever read.

use super::{is_stdio, Ctx, Refusal};
use anyhow::{Context, Result};
use qcs::container::{FormatError, Header, ParserOptions};
use qcs::StreamDecoder;
use std::io::Read;
use std::path::{Path, PathBuf};

/// Bytes read at a time.
const BLOCK: usize = 64 << 10;

/// A source of bytes: a file, or standard input for `-`; its first bytes can be looked at
/// before it is read.
pub struct Source {
    path: PathBuf,
    head: Vec<u8>,
    /// How much of `head` was read back.
    taken: usize,
    rest: Box<dyn Read>,
    /// A regular file's length.
    len: Option<u64>,
}

impl Source {
    /// The file `p`, or standard input for `-`.
    pub fn open(p: &Path) -> Result<Source> {
        let (rest, len): (Box<dyn Read>, _) = if is_stdio(p) {
            // Unbuffered (`Stdin` reads ahead 8 KiB): what is not read stays in the pipe.
            use std::os::fd::AsFd;
            let fd = (std::io::stdin().as_fd().try_clone_to_owned())
                .context("cannot read standard input")?;
            (Box::new(std::fs::File::from(fd)), None)
        } else {
            let f =
                std::fs::File::open(p).with_context(|| format!("cannot read {}", p.display()))?;
            let len = f.metadata().ok().filter(|m| m.is_file()).map(|m| m.len());
            (Box::new(f), len)
        };
        Ok(Source {
            path: p.to_path_buf(),
            head: Vec::new(),
            taken: 0,
            rest,
            len,
        })
    }

    /// Its first `n` bytes (fewer if it is shorter), read now and kept for the reading.
    pub fn peek(&mut self, n: usize) -> Result<&[u8]> {
        while self.head.len() < n {
            let mut b = vec![0u8; n - self.head.len()];
            match self.rest.read(&mut b) {
                Ok(0) => break,
                Ok(k) => self.head.extend_from_slice(&b[..k]),
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => return Err(e).with_context(|| self.read_error()),
            }
        }
        Ok(&self.head[..n.min(self.head.len())])
    }

    fn read_error(&self) -> String {
        match is_stdio(&self.path) {
            true => "cannot read standard input".to_string(),
            false => format!("cannot read {}", self.path.display()),
        }
    }
}

impl Read for Source {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        if self.taken < self.head.len() {
            let n = buf.len().min(self.head.len() - self.taken);
            buf[..n].copy_from_slice(&self.head[self.taken..self.taken + n]);
            self.taken += n;
            return Ok(n);
        }
        self.rest.read(buf)
    }
}

/// The refusal of an input longer than `--max-input`.
fn too_long(p: &Path, cap: u64) -> anyhow::Error {
    anyhow::Error::new(Refusal::Limit(format!(
        "{} is longer than --max-input {cap} bytes (read no further; --max-input none lifts it)",
        p.display()
    )))
}

/// Reads `src` block by block, at most `budget` bytes, into `bytes`, calling `each` on every
/// block until it says stop; refuses an input longer than `cap`.
fn pump(
    src: Source,
    budget: u64,
    cap: u64,
    bytes: &mut Vec<u8>,
    mut each: impl FnMut(&[u8]) -> Result<bool>,
) -> Result<()> {
    let (p, expected, read_error) = (src.path.clone(), src.len, src.read_error());
    // Never ask the source for more than the budget: a pipe keeps the rest.
    let mut src = src.take(budget);
    // A file within the cap is read into one allocation of its size (or the budget's).
    if let Some(n) = expected.map(|n| n.min(budget)).filter(|&n| n <= cap) {
        bytes.reserve_exact(n as usize);
    }
    let mut block = vec![0u8; BLOCK];
    loop {
        let n = match src.read(&mut block) {
            Ok(0) => return Ok(()),
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(e).context(read_error),
        };
        if (bytes.len() + n) as u64 > cap {
            return Err(too_long(&p, cap));
        }
        if bytes.capacity() < bytes.len() + n {
            // Grow by doubling, but never past the cap.
            let room = (cap - bytes.len() as u64).min(bytes.len().max(BLOCK) as u64);
            bytes.reserve_exact((room as usize).max(n));
        }
        bytes.extend_from_slice(&block[..n]);
        if !each(&block[..n])? {
            return Ok(());
        }
    }
}

/// Refuses a source whose first bytes are no image format the `image` crate knows, before
/// reading the rest.
pub fn check_image_start(src: &mut Source) -> Result<()> {
    let path = src.path.clone();
    check_image_head(src.peek(64)?, &path)
}

/// Refuses an image whose first bytes `head` are no format the `image` crate knows (and whose
/// extension names none: a TGA has no signature), naming the formats a camera or a phone
/// writes that this build cannot read.
pub fn check_image_head(head: &[u8], path: &std::path::Path) -> Result<()> {
    let Err(e) = image::guess_format(head) else {
        return Ok(());
    };
    let by_name = image::ImageFormat::from_path(path).is_ok_and(|f| f.reading_enabled());
    if by_name && unreadable_format(head).is_none() {
        return Ok(());
    }
    let unreadable = unreadable_format(head).map_or(String::new(), |(name, how)| {
        format!(": {name}, which qcs does not read; convert it to PNG or JPEG first{how}")
    });
    Err(e).with_context(|| format!("cannot read image {}{unreadable}", path.display()))
}

/// Whether the image `r` holds is an animation (a GIF of more than one frame, an APNG, an
/// animated WebP), of which qcs encodes the first frame. No pixel is decoded: a GIF's blocks
/// are skipped through to a second image; an unreadable one is no animation (its decoder
/// will say what is wrong).
pub fn is_animation<R: std::io::BufRead + std::io::Seek>(mut r: R) -> bool {
    use image::ImageFormat as F;
    let Ok(format) = r.fill_buf().map(image::guess_format) else {
        return false;
    };
    match format {
        Ok(F::Gif) => gif_has_two_images(r).unwrap_or(false),
        Ok(F::Png) => {
            image::codecs::png::PngDecoder::new(r).is_ok_and(|d| d.is_apng().unwrap_or(false))
        }
        Ok(F::WebP) => image::codecs::webp::WebPDecoder::new(r).is_ok_and(|d| d.has_animation()),
        _ => false,
    }
}

/// Whether a GIF has a second image descriptor (the GIF89a block structure: a screen
/// descriptor and colour table, then extensions and images, each image's data in sub-blocks).
fn gif_has_two_images(mut r: impl Read) -> std::io::Result<bool> {
    fn skip(r: &mut impl Read, n: u64) -> std::io::Result<()> {
        match std::io::copy(&mut r.take(n), &mut std::io::sink())? {
            k if k == n => Ok(()),
            _ => Err(std::io::ErrorKind::UnexpectedEof.into()),
        }
    }
    fn byte(r: &mut impl Read) -> std::io::Result<u8> {
        let mut b = [0];
        r.read_exact(&mut b).map(|()| b[0])
    }
    /// Skips a colour table if `flags` (a descriptor's packed byte) says one follows.
    fn table(r: &mut impl Read, flags: u8) -> std::io::Result<()> {
        match flags & 0x80 {
            0 => Ok(()),
            _ => skip(r, 3 << ((flags & 7) + 1)),
        }
    }
    fn sub_blocks(r: &mut impl Read) -> std::io::Result<()> {
        loop {
            match byte(r)? {
                0 => return Ok(()),
                n => skip(r, n as u64)?,
            }
        }
    }
    let mut screen = [0; 13];
    r.read_exact(&mut screen)?;
    table(&mut r, screen[10])?;
    let mut images = 0;
    loop {
        match byte(&mut r)? {
            0x2c => {
                images += 1;
                if images == 2 {
                    return Ok(true);
                }
                let mut image = [0; 9];
                r.read_exact(&mut image)?;
                table(&mut r, image[8])?;
                byte(&mut r)?; // the LZW code size
                sub_blocks(&mut r)?;
            }
            0x21 => {
                byte(&mut r)?; // the extension's label
                sub_blocks(&mut r)?;
            }
            _ => return Ok(false), // the trailer (0x3b), or not a GIF
        }
    }
}

/// Formats `image` does not read, known by their first bytes, with a way to convert them.
fn unreadable_format(head: &[u8]) -> Option<(&'static str, &'static str)> {
    // ISO base media files: a box size, `ftyp`, then the major brand.
    let brand = head
        .get(4..12)
        .filter(|b| b.starts_with(b"ftyp"))
        .map(|b| &b[4..]);
    match brand {
        Some(b"heic" | b"heix" | b"hevc" | b"hevx" | b"heim" | b"heis" | b"mif1" | b"msf1") => {
            Some((
                "a HEIF/HEIC photo",
                " (heif-convert IN OUT.jpg, from libheif)",
            ))
        }
        Some(b"avif" | b"avis") => Some(("an AVIF picture", " (avifdec IN OUT.png)")),
        _ if head.starts_with(&[0xff, 0x0a]) || head.starts_with(b"\0\0\0\x0cJXL ") => {
            Some(("a JPEG XL picture", " (djxl IN OUT.png)"))
        }
        _ if head.starts_with(b"\0\0\0\x0cjP  ") || head.starts_with(&[0xff, 0x4f, 0xff, 0x51]) => {
            Some(("a JPEG 2000 picture", " (opj_decompress -i IN -o OUT.png)"))
        }
        _ => None,
    }
}

/// The bytes of a file (or of standard input for `-`) to its end, refusing one longer than
/// `--max-input` having read no more.
pub fn read_all(src: Source, ctx: &Ctx) -> Result<Vec<u8>> {
    let mut bytes = Vec::new();
    pump(src, u64::MAX, ctx.max_input, &mut bytes, |_| Ok(true))?;
    Ok(bytes)
}

/// A .qcs input as read: its bytes and what the push decoder found in them.
pub struct QcsInput {
    /// Every byte read: the whole input, or its first `--bytes`, or up to where it was refused.
    pub bytes: Vec<u8>,
    /// The header, if the bytes hold it whole.
    pub header: Option<Header>,
    /// With `recover`, the damage that stopped the reading (everything verified before it is
    /// kept).
    pub damage: Option<FormatError>,
    /// The error that refused the file, if any (a format error, a limit): reading stopped
    /// there. `bytes` still holds what was read, for `qcs info`.
    pub refused: Option<qcs::Error>,
}

impl QcsInput {
    /// The bytes, or the refusal.
    pub fn ok(self) -> Result<Self, qcs::Error> {
        match self.refused {
            Some(e) => Err(e),
            None => Ok(self),
        }
    }
}

/// How to read a .qcs input.
pub struct ReadQcs {
    /// `--bytes`: read no more than this.
    pub budget: Option<u64>,
    /// `--recover`: a damaged chunk stops the reading, and what was verified before it is
    /// kept (see [`QcsInput::damage`]); without, the damage refuses the file.
    pub recover: bool,
}

/// Reads a .qcs file (standard input for `-`) a block at a time through a push decoder: a
/// file is refused at the block that breaks the format or a limit (the limits of `ctx`),
/// before the rest is read; `on_header` runs once the header is whole, before the rest is
/// read, to check what the header implies (an output size, the samples to decode). Reading
/// stops at `--bytes`, and an input longer than `--max-input` is refused.
///
/// The push decoder decodes no colours (`max_samples(0)`): it checks the header (the
/// limits on the image, the lattice frame), every chunk's CRC and the metadata limit.
pub fn read_qcs(
    src: Source,
    how: &ReadQcs,
    ctx: &Ctx,
    mut on_header: impl FnMut(&Header) -> Result<()>,
) -> Result<QcsInput> {
    let opts = ParserOptions {
        limits: ctx.limits.clone(),
        recover: how.recover,
        max_samples: Some(0),
    };
    let mut gate = StreamDecoder::with_options(opts);
    let mut bytes = Vec::new();
    let mut refused = None;
    let mut header_seen = false;
    let mut header_err = None;
    pump(
        src,
        how.budget.unwrap_or(u64::MAX),
        ctx.max_input,
        &mut bytes,
        |block| {
            if let Err(e) = gate.push(block) {
                refused = Some(e);
                return Ok(false);
            }
            if let (false, Some(h)) = (header_seen, gate.header()) {
                header_seen = true;
                if let Err(e) = on_header(h) {
                    header_err = Some(e);
                    return Ok(false);
                }
            }
            Ok(gate.stopped().is_none())
        },
    )?;
    if let Some(e) = header_err {
        return Err(e);
    }
    Ok(QcsInput {
        bytes,
        header: gate.header().cloned(),
        damage: gate.stopped().cloned(),
        refused,
    })
}

/// The samples a decode that stops at sample `k` decodes: every sample of the levels that
/// start before `k` (what `ParserOptions::max_samples` checks against the limits).
pub fn samples_of_levels_before(h: &Header, k: u64) -> u64 {
    (0..h.level_count())
        .map_while(|l| h.level_range(l))
        .take_while(|r| r.start < k)
        .last()
        .map_or(0, |r| r.end)
}
