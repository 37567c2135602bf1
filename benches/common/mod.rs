//! What the benches share: the bundled photograph at the benches' size, and thread pools.
//! (A directory module, so cargo does not take it for a bench of its own.)

use image::{imageops::FilterType, RgbImage};

/// Side of the square test picture: 1024 × 1024, about a megapixel.
pub const SIDE: u32 = 1024;

/// `assets/rocket.png` resized to `SIDE × SIDE` (Triangle filter).
pub fn photo() -> RgbImage {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/rocket.png");
    let img = image::open(path).expect("assets/rocket.png").to_rgb8();
    image::imageops::resize(&img, SIDE, SIDE, FilterType::Triangle)
}

/// A rayon pool of `threads` threads (1 for the one-core figures).
#[allow(dead_code)] // each bench compiles this module on its own; not all use the pools
pub fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool")
}
