//! Every integration test, in one binary: one crate to compile and link instead of one per
//! file (most of what `cargo test` costs from a fresh clone is building). Each file of
//! `tests/` is a module here, and runs as `cargo test --test suite FILE::`; a new file is
//! added below ([`every_test_file_is_a_module`] fails until it is).

#[path = "cells.rs"]
mod cells;
#[path = "codec.rs"]
mod codec;
#[path = "container.rs"]
mod container;
#[path = "rate.rs"]
mod rate;
#[path = "reconstruction.rs"]
mod reconstruction;
#[path = "refinement.rs"]
mod refinement;
#[path = "robustness.rs"]
mod robustness;
#[path = "sites.rs"]
mod sites;
#[path = "streaming.rs"]
mod streaming;
#[path = "vectors.rs"]
mod vectors;

/// A file in `tests/` that is not a module above would never run (`autotests = false`).
#[test]
fn every_test_file_is_a_module() {
    let here = include_str!("suite.rs");
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests");
    for entry in std::fs::read_dir(&dir).expect("tests/") {
        let name = entry
            .expect("entry")
            .file_name()
            .to_string_lossy()
            .into_owned();
        if let Some(stem) = name.strip_suffix(".rs").filter(|&s| s != "suite") {
            let line = format!("#[path = \"{stem}.rs\"]\nmod {stem};");
            assert!(
                here.contains(&line),
                "tests/{name} is not in tests/suite.rs"
            );
        }
    }
}
