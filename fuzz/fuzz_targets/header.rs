//! cargo-fuzz target `header`: see `qcs::fuzzing::header` for the input layout and the invariants.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    qcs::fuzzing::header(data);
});
