//! `image::open` on a `.qcs` file after one registration call.
//!
//! ```text
//! cargo run --release --example image_open -- assets/rocket.png
//! ```

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "assets/rocket.png".into());
    let qcs_path = std::env::temp_dir().join("qcs-example.qcs");
    std::fs::write(
        &qcs_path,
        qcs::encode(&image::open(&path)?, &Default::default())?,
    )?;

    qcs::register_image_hooks(); // once, at start-up
    let img = image::open(&qcs_path)?; // now any program using `image` reads .qcs
    println!(
        "{}: {}×{} {:?}",
        qcs_path.display(),
        img.width(),
        img.height(),
        img.color()
    );
    img.save(std::env::temp_dir().join("qcs-example.png"))?;
    Ok(())
}
