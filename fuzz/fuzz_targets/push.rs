//! cargo-fuzz target `push`: see `qcs::fuzzing::push` for the input layout and the invariants.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    qcs::fuzzing::push(data);
});
