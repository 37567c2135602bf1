//! cargo-fuzz target `roundtrip`: see `qcs_fuzz_harness::roundtrip` for the input layout and the invariants.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    qcs_fuzz_harness::roundtrip(data);
});
