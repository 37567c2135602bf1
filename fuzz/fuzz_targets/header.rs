//! cargo-fuzz target `header`: see `qcs_fuzz_harness::header` for the input layout and the invariants.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    qcs_fuzz_harness::header(data);
});
