//! Every file of `fuzz/corpus/<target>/` replayed once through its check (the stable half of
//! the fuzzing: CI has no nightly toolchain, so the inputs the fuzzers found or kept are run
//! here as ordinary tests). A corpus file must not break an invariant; seeds from `fixtures/`
//! must moreover be run in full (not refused, not out of bounds), so that the checks are seen
//! to run on real inputs.

use std::path::PathBuf;

use fuzz_check::{Outcome, Violation};

type Check = fn(&[u8]) -> Result<Outcome, Violation>;

/// The targets: directory under `fuzz/corpus/`, its check, and the directory of `fixtures/`
/// its seeds come from.
const TARGETS: [(&str, Check, &str); 5] = [
    ("scene", fuzz_check::check_scene, "scenes"),
    ("obj", fuzz_check::check_mesh, "meshes"),
    ("urdf", fuzz_check::check_urdf, "urdf"),
    ("mechanism", fuzz_check::check_mechanism, "mechanisms"),
    ("part", fuzz_check::check_part, "parts"),
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
    let fixtures = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fixtures");
    for (target, check, seeds) in TARGETS {
        let mut seeded = 0;
        for (file, outcome) in replay(target, check) {
            let name = file.file_name().expect("a file name");
            let seed = fixtures.join(seeds).join(name);
            if seed.is_file() && std::fs::read(&seed).ok() == std::fs::read(&file).ok() {
                seeded += 1;
                assert!(
                    matches!(outcome, Outcome::Checked { .. }),
                    "seed {}: {outcome:?}",
                    file.display()
                );
            }
        }
        assert!(
            seeded > 0,
            "fuzz/corpus/{target} has no seed from fixtures/{seeds}"
        );
    }
}
