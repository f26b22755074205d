//! Fuzz target: mechanism file → reduced model → 100 steps (`fuzz_check::check_mechanism`). A violated invariant is a panic, which
//! libFuzzer reports as a crash and saves under `fuzz/artifacts/mechanism/`.
#![no_main]
#![forbid(unsafe_code)]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Err(v) = fuzz_check::check_mechanism(data) {
        panic!("{v}");
    }
});
