//! Colours ↔ bits: the colour codings of the format.
