//! Colours ↔ bits: the colour codings of the format (spec/format.md §Raw coding).
//!
//! [`raw`] is coding 0: every channel value quantised to B bits and packed MSB-first.

pub mod raw;
