//! What the measuring examples share.

use std::path::PathBuf;

/// The PNG files, sorted, of the folder given as the first argument (default
/// `../shared/corpus/dev`).
pub fn photo_paths() -> std::io::Result<Vec<PathBuf>> {
    let dir = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "../shared/corpus/dev".into());
    let mut paths: Vec<_> = std::fs::read_dir(&dir)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "png"))
        .collect();
    paths.sort();
    Ok(paths)
}
