//! Exact arithmetic for the H2 root lattice: Z\[τ\] and Z\[ζ\], no floating point.
