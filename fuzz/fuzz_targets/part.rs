//! Fuzz target: part file → 5 drops of the pose study (`fuzz_check::check_part`). A violated invariant is a panic, which
//! libFuzzer reports as a crash and saves under `fuzz/artifacts/part/`.
#![no_main]
#![forbid(unsafe_code)]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Err(v) = fuzz_check::check_part(data) {
        panic!("{v}");
    }
});
