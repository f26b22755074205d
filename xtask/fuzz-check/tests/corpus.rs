//! Every file of `fuzz/corpus/<target>/` replayed once through its check (the stable half of
//! the fuzzing: CI has no nightly toolchain, so the inputs the fuzzers found or kept are run
//! here as ordinary tests). A corpus file must not break an invariant; seeds from `fixtures/`
//! must moreover be run in full (not refused, not out of bounds), so that the checks are seen
//! to run on real inputs.

use std::path::PathBuf;

use fuzz_check::{Outcome, Violation};

type Check = fn(&[u8]) -> Result<Outcome, Violation>;

/// The targets: directory under `fuzz/corpus/` and its check.
const TARGETS: [(&str, Check); 5] = [
    ("scene", fuzz_check::check_scene),
    ("obj", fuzz_check::check_mesh),
    ("urdf", fuzz_check::check_urdf),
    ("mechanism", fuzz_check::check_mechanism),
    ("part", fuzz_check::check_part),
];

fn corpus(target: &str) -> Vec<PathBuf> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fuzz/corpus")
        .join(target);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("directory entry").path())
        .filter(|p| p.is_file())
        .collect();
    files.sort();
    files
}

/// Runs every corpus file of `target`; prints each outcome (`--nocapture` shows them).
fn replay(target: &str, check: Check) -> Vec<(PathBuf, Outcome)> {
    let files = corpus(target);
    assert!(!files.is_empty(), "fuzz/corpus/{target} is empty");
    files
        .into_iter()
        .map(|f| {
            let bytes = std::fs::read(&f).expect("readable corpus file");
            let start = std::time::Instant::now();
            match check(&bytes) {
                Ok(o) => {
                    println!(
                        "{target} {} {:?} {:.3}s",
                        f.display(),
                        o,
                        start.elapsed().as_secs_f64()
                    );
                    (f, o)
                }
                Err(v) => panic!("{}: {v}", f.display()),
            }
        })
        .collect()
}

#[test]
fn every_corpus_file_keeps_the_invariants() {
    for (target, check) in TARGETS {
        replay(target, check);
    }
}
