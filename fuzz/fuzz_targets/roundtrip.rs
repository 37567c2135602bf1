//! cargo-fuzz target `roundtrip`: see `qcs::fuzzing::roundtrip` for the input layout and the invariants.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    qcs::fuzzing::roundtrip(data);
});
