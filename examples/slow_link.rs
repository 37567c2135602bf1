//! Streams a `.qcs` file through a simulated slow link and prints, for each preview, the bytes
//! received and its PSNR against the original image.
//!
//! ```text
//! cargo run --release --example slow_link -- assets/rocket.png [BYTES_PER_TICK]
//! ```

use qcs::{EncodeOptions, Method, StreamDecoder};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = args.next().unwrap_or_else(|| "assets/rocket.png".into());
    let per_tick: usize = args.next().map(|s| s.parse()).transpose()?.unwrap_or(1500);
    let original = image::open(&path)?;
    let bytes = qcs::encode(&original, &EncodeOptions::default())?;
    let reference = original.to_rgb8();
    let (w, h) = reference.dimensions();
    println!("{path}: {} bytes, {} per tick", bytes.len(), per_tick);
    println!(
        "{:>6} {:>9} {:>8} {:>8}  kind",
        "tick", "bytes", "samples", "PSNR dB"
    );
    let mut decoder = StreamDecoder::new(qcs::Limits::default());
    for (tick, chunk) in bytes.chunks(per_tick.max(1)).enumerate() {
        decoder.push(chunk)?; // bytes arrive
        if decoder.header().is_none() {
            continue;
        }
        let picture = decoder.render(Method::Gouraud, w, h)?; // a preview at any moment
        let psnr = qcs_lab::eval::psnr(&reference, &picture.decoded().image.to_rgb8())?;
        println!(
            "{:>6} {:>9} {:>8} {:>8.2}  {}",
            tick + 1,
            ((tick + 1) * per_tick).min(bytes.len()),
            picture.decoded().samples_used,
            psnr,
            if picture.is_final() {
                "final"
            } else {
                "preview"
            }
        );
    }
    Ok(())
}
