//! Fuzz target: URDF → mass matrix, dynamics, a short simulation (`fuzz_check::check_urdf`). A violated invariant is a panic, which
//! libFuzzer reports as a crash and saves under `fuzz/artifacts/urdf/`.
#![no_main]
#![forbid(unsafe_code)]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Err(v) = fuzz_check::check_urdf(data) {
        panic!("{v}");
    }
});
