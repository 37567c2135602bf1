//! The lab's integration tests, one binary (one crate to compile and link).

#[path = "eval.rs"]
mod eval;
#[path = "styles.rs"]
mod styles;
