//! Samples → picture, at any output size and from any prefix.
