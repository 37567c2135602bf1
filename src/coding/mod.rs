//! Colours ↔ bits: the colour codings of the format (spec/format.md §Codings).
//!
//! [`raw`] is coding 0: every channel value quantised to B bits and packed MSB-first.
//! [`predictive`] is coding 1: closed-loop prediction from earlier samples, quantised residuals,
//! coded with the adaptive binary range coder of [`range`].

pub mod predictive;
pub mod range;
pub mod raw;
