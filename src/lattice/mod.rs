//! Exact arithmetic for the H2 root lattice: Z\[τ\] and Z\[ζ\], and the cut-and-project
//! enumeration. Floating point here only proposes candidates; membership and order are
//! decided with integers.

mod cut_and_project;
mod cyclotomic;
mod golden;
mod incircle;

pub use cut_and_project::{disk_candidates, one_d};
pub use cyclotomic::{decagon_forms, sign_plus_sin72, zeta_f64, ZZeta, SIN72};
pub use golden::{order_key, ZTau, TAU};
pub(crate) use incircle::incircle_exact;
pub use incircle::{
    incircle, incircle_value, orient, orient_value, within_exact_limit, EXACT_LIMIT,
};
