//! cargo-fuzz target `decode`: see `qcs::fuzzing::decode` for the input layout and the invariants.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    qcs::fuzzing::decode(data);
});
