//! Command-line definitions (clap) and dispatch; one module per subcommand.

/// `println!` that returns stdout's error (e.g. a pipe closed by `head`) instead of
/// panicking; [`main`] ends quietly on a closed pipe.
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout(), $($arg)*)?
    }};
}

mod codec;
mod render;
mod sites;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// qcs — progressive images on quasicrystal sample sites: any prefix of a file is a picture.
#[derive(Parser, Debug)]
#[command(name = "qcs", version, about, long_about = None)]
pub struct Cli {
    /// Print nothing but errors.
    #[arg(short, long, global = true)]
    pub quiet: bool,
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Encode images (any format the image crate reads) to .qcs.
    #[command(
        after_help = "Examples:\n  qcs encode photo.png photo.qcs\n  qcs encode photo.jpg photo.qcs --samples 20000 --bits 6\n  qcs encode photos/ *.png --out-dir qcs/   (many files in parallel)"
    )]
    Encode(codec::EncodeArgs),
    /// Decode a .qcs file (or a prefix of one) to an image; the format follows the extension.
    #[command(
        after_help = "Examples:\n  qcs decode photo.qcs photo.png\n  qcs decode photo.qcs thumb.png --size 120x80 --method shepard\n  qcs decode photo.qcs cut.png --bytes 2048   (as a cut download would)\n  qcs decode photo.qcs --frames frames/ --every 4096"
    )]
    Decode(codec::DecodeArgs),
    /// Show a .qcs file's header, levels (byte offsets, sample ranges) and CRC status.
    #[command(after_help = "Example:\n  qcs info photo.qcs")]
    Info(codec::InfoArgs),
    /// Print the first N sample sites of a sampler as CSV (index,x,y[,n0,n1,n2,n3]).
    #[command(
        after_help = "Examples:\n  qcs sites --width 512 --height 512 --count 1089\n  qcs sites --width 640 --height 480 --count 500 --sampler halton"
    )]
    Sites(sites::SitesArgs),
    /// Write an animated GIF of a .qcs file sharpening as its bytes arrive (byte count in each frame).
    #[command(
        after_help = "Examples:\n  qcs preview photo.qcs photo.gif\n  qcs preview photo.qcs photo.gif --every 2048 --size 240x160"
    )]
    Preview(codec::PreviewArgs),
    /// Render a .qcs file (or an image sampled by any strategy) in a stylized way.
    #[command(
        after_help = "Examples:\n  qcs render photo.qcs mosaic.png --style mosaic --samples 2000\n  qcs render --sampler halton --samples 4225 photo.png halton.png --style voronoi\n  qcs render photo.qcs spectrum.png --style spectrum"
    )]
    Render(render::RenderArgs),
    /// Reproduce the paper's evaluation of six sampling strategies on images.
    #[command(after_help = "Example:\n  qcs eval photos/*.png --out eval/")]
    Eval(render::EvalArgs),
    /// Encode an image and write previews decoded from growing prefixes of its file.
    #[command(after_help = "Example:\n  qcs demo assets/rocket.png out/")]
    Demo(codec::DemoArgs),
}

/// Whether `e` is stdout's reader having closed the pipe.
fn closed_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

/// Exit codes: 0 success, 1 I/O or other failure, 2 usage (clap), 3 malformed input, 4 limit exceeded.
fn exit_code(e: &anyhow::Error) -> u8 {
    for cause in e.chain() {
        if let Some(q) = cause.downcast_ref::<qcs::Error>() {
            return match q {
                qcs::Error::Format(_) | qcs::Error::NeedMoreData => 3,
                qcs::Error::Limits(_) => 4,
                _ => 1,
            };
        }
        if cause.downcast_ref::<image::ImageError>().is_some() {
            return 3;
        }
    }
    1
}

/// Parses the command line and runs it.
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    let quiet = cli.quiet;
    let r = match cli.command {
        Command::Encode(a) => codec::encode(a, quiet),
        Command::Decode(a) => codec::decode(a, quiet),
        Command::Info(a) => codec::info(a),
        Command::Sites(a) => sites::run(a),
        Command::Demo(a) => codec::demo(a, quiet),
        Command::Preview(a) => codec::preview(a, quiet),
        Command::Render(a) => render::render(a, quiet),
        Command::Eval(a) => render::eval(a, quiet),
    };
    match r {
        Ok(()) => ExitCode::SUCCESS,
        // The reader went away (`qcs sites … | head`): nothing more to say, as for `yes`.
        Err(e) if closed_pipe(&e) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("qcs: error: {e:#}");
            ExitCode::from(exit_code(&e))
        }
    }
}

/// Parses `WxH`.
pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("expected WxH, got {s:?}"))?;
    let w: u32 = w.parse().map_err(|_| format!("bad width in {s:?}"))?;
    let h: u32 = h.parse().map_err(|_| format!("bad height in {s:?}"))?;
    if w == 0 || h == 0 {
        return Err(format!("empty size {s:?}"));
    }
    Ok((w, h))
}

/// A sampler by its CLI name (the quasicrystal included).
pub fn sampler_by_name(
    name: &str,
    seed: u64,
) -> Option<Box<dyn qcs::sites::Sampler + Send + Sync>> {
    if name == "quasicrystal" {
        return Some(Box::new(qcs::sites::Quasicrystal::new(1, 1).ok()?));
    }
    use qcs::sites::strategies::*;
    Some(match name {
        "periodic" => Box::new(Periodic),
        "jittered" => Box::new(Jittered { seed }),
        "halton" => Box::new(Halton),
        "random" => Box::new(Random { seed }),
        "farthest" => Box::new(FarthestPoint { seed }),
        _ => return None,
    })
}
