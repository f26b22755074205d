//! Fuzz target: OBJ → mass properties and convex hull (`fuzz_check::check_mesh`). A violated invariant is a panic, which
//! libFuzzer reports as a crash and saves under `fuzz/artifacts/obj/`.
#![no_main]
#![forbid(unsafe_code)]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Err(v) = fuzz_check::check_mesh(data) {
        panic!("{v}");
    }
});
