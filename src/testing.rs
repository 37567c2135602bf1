//! Helpers shared by the unit tests.

/// A xorshift64 generator (`seed` ≠ 0): deterministic and fast, for picking test cases.
pub(crate) fn xorshift(seed: u64) -> impl FnMut() -> u64 {
    let mut s = seed;
    move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        s
    }
}
