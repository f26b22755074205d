//! Fuzz target: RON scene → world → 200 steps under the penetration monitor (`fuzz_check::check_scene`). A violated invariant is a panic, which
//! libFuzzer reports as a crash and saves under `fuzz/artifacts/scene/`.
#![no_main]
#![forbid(unsafe_code)]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Err(v) = fuzz_check::check_scene(data) {
        panic!("{v}");
    }
});
