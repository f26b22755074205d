//! `cargo xtask fuzz --seconds N [--target NAME]`: every cargo-fuzz target of `fuzz/` for N
//! seconds, one after another (one libFuzzer process, one job: the machines this runs on are
//! shared).
//!
//! The targets are thin wrappers around the checks of `xtask/fuzz-check` (module
//! documentation there); `cargo test` replays `fuzz/corpus/` through the same checks on
//! stable, so this command is not part of `ci`. It needs the nightly toolchain and
//! cargo-fuzz, and says so (with the commands that get them) when either is missing.
//!
//! Each target has a dictionary, `fuzz/dict/<target>.dict` (the keywords of its format, taken
//! from the fixtures): byte mutations alone rarely make a well-formed RON or XML file.
//!
//! New inputs a run finds are written under `fuzz/target/new-corpus/<target>/` (ignored by
//! git), not into `fuzz/corpus/`: the checked-in corpus stays small and chosen (tens of
//! files; minimise with `cargo +nightly fuzz cmin`). A crash (a violated invariant or a
//! panic) is saved by libFuzzer under `fuzz/artifacts/<target>/`; replay it with
//! `cargo +nightly fuzz run <target> <file>`, then keep it as a corpus file and a regression
//! test next to the code it tests.

use std::path::Path;
use std::process::Command;

use crate::{Result, workspace_root};

/// The fuzz targets, in the order they run (names of `fuzz/fuzz_targets/*.rs`).
pub const TARGETS: [&str; 5] = ["scene", "obj", "urdf", "mechanism", "part"];

/// One execution taking longer than this (s) is a hang, reported as a crash. The checks
/// bound their work to well under a second (the `MAX_*` constants of `fuzz-check`). `10`.
pub const TIMEOUT_SECONDS: u32 = 10;

/// Largest memory of the fuzzing process (MB) before libFuzzer reports the input. `2048`.
pub const RSS_LIMIT_MB: u32 = 2048;

/// Options of `cargo xtask fuzz`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Options {
    /// Seconds per target.
    pub seconds: u64,
    /// Only this target (default: all of [`TARGETS`]).
    pub target: Option<String>,
}

/// `rustup run nightly cargo <args>`: the nightly cargo, whatever toolchain runs xtask.
fn nightly_cargo(root: &Path) -> Command {
    let mut c = Command::new("rustup");
    c.args(["run", "nightly", "cargo"]).current_dir(root);
    // The stable cargo that runs xtask sets these for its own build; the nightly one must
    // not inherit them.
    for var in ["CARGO", "RUSTC", "RUSTUP_TOOLCHAIN", "CARGO_MANIFEST_DIR"] {
        c.env_remove(var);
    }
    c
}

/// Checks that the nightly toolchain and cargo-fuzz are there.
fn prerequisites(root: &Path) -> Result<()> {
    let ok = |mut c: Command| c.output().is_ok_and(|o| o.status.success());
    let mut version = nightly_cargo(root);
    version.arg("--version");
    if !ok(version) {
        return Err(
            "`cargo xtask fuzz` needs the nightly toolchain (libFuzzer's coverage \
                    instrumentation is nightly-only): `rustup toolchain install nightly`"
                .to_owned(),
        );
    }
    let mut fuzz = nightly_cargo(root);
    fuzz.args(["fuzz", "--version"]);
    if !ok(fuzz) {
        return Err("`cargo xtask fuzz` needs cargo-fuzz: `cargo install cargo-fuzz`".to_owned());
    }
    Ok(())
}

/// The build options of every fuzz build: optimised with debug assertions and overflow
/// checks, no sanitizer (the crates forbid `unsafe`; AddressSanitizer would only halve the
/// executions per second), 16 codegen units (a build in minutes, not tens of them).
const BUILD: [&str; 6] = ["-O", "-a", "-s", "none", "--codegen-units", "16"];

/// Runs the command (module documentation).
///
/// # Errors
/// A missing prerequisite, a failed build, or the targets that crashed.
pub fn run(options: &Options) -> Result<()> {
    let root = workspace_root();
    prerequisites(&root)?;
    let targets: Vec<&str> = match &options.target {
        Some(t) if TARGETS.contains(&t.as_str()) => vec![t.as_str()],
        Some(t) => {
            return Err(format!(
                "unknown fuzz target `{t}` (targets: {})",
                TARGETS.join(", ")
            ));
        }
        None => TARGETS.to_vec(),
    };
    let mut build = nightly_cargo(&root);
    build.args(["fuzz", "build"]).args(BUILD);
    let status = build
        .status()
        .map_err(|e| format!("could not run `cargo +nightly fuzz build`: {e}"))?;
    if !status.success() {
        return Err(format!("`cargo +nightly fuzz build` failed ({status})"));
    }
    let mut failed = Vec::new();
    for t in targets {
        let fresh = root.join("fuzz/target/new-corpus").join(t);
        std::fs::create_dir_all(&fresh)
            .map_err(|e| format!("cannot create {}: {e}", fresh.display()))?;
        println!("fuzz: {t} for {} s", options.seconds);
        let mut c = nightly_cargo(&root);
        c.args(["fuzz", "run", t])
            .args(BUILD)
            .arg(&fresh)
            .arg(root.join("fuzz/corpus").join(t))
            .arg("--")
            .args(libfuzzer_args(options.seconds));
        let dict = root.join("fuzz/dict").join(format!("{t}.dict"));
        if dict.is_file() {
            c.arg(format!("-dict={}", dict.display()));
        }
        let status = c
            .status()
            .map_err(|e| format!("could not run `cargo +nightly fuzz run {t}`: {e}"))?;
        if !status.success() {
            failed.push(t);
        }
    }
    if failed.is_empty() {
        println!("fuzz: no target crashed");
        Ok(())
    } else {
        Err(format!(
            "fuzz targets that crashed: {} (inputs under fuzz/artifacts/)",
            failed.join(", ")
        ))
    }
}

/// libFuzzer's options for a run of `seconds`.
fn libfuzzer_args(seconds: u64) -> Vec<String> {
    vec![
        format!("-max_total_time={seconds}"),
        format!("-timeout={TIMEOUT_SECONDS}"),
        format!("-rss_limit_mb={RSS_LIMIT_MB}"),
        "-print_final_stats=1".to_owned(),
    ]
}

/// Parses `--seconds N [--target NAME]` (also `--seconds=N`, `--target=NAME`).
///
/// # Errors
/// A usage error.
pub fn parse(args: &[String]) -> Result<Options> {
    let mut options = Options::default();
    let mut seconds = None;
    let mut args = args.iter();
    while let Some(arg) = args.next() {
        let (name, inline) = match arg.split_once('=') {
            Some((n, v)) => (n, Some(v.to_owned())),
            None => (arg.as_str(), None),
        };
        let mut value = || {
            inline
                .clone()
                .or_else(|| args.next().cloned())
                .ok_or_else(|| format!("`{name}` needs a value"))
        };
        match name {
            "--seconds" => {
                let v = value()?;
                seconds = Some(
                    v.parse::<u64>()
                        .ok()
                        .filter(|&s| s > 0)
                        .ok_or_else(|| format!("--seconds {v}: need a whole number > 0"))?,
                );
            }
            "--target" => options.target = Some(value()?),
            _ => return Err(format!("unexpected argument `{arg}` to `fuzz`")),
        }
    }
    options.seconds = seconds.ok_or("`fuzz` needs `--seconds N`")?;
    Ok(options)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(a: &[&str]) -> Vec<String> {
        a.iter().map(|s| (*s).to_owned()).collect()
    }

    #[test]
    fn parses_seconds_and_target() {
        assert_eq!(
            parse(&args(&["--seconds", "60"])),
            Ok(Options {
                seconds: 60,
                target: None
            })
        );
        assert_eq!(
            parse(&args(&["--seconds=5", "--target", "obj"])),
            Ok(Options {
                seconds: 5,
                target: Some("obj".into())
            })
        );
        assert!(parse(&args(&[])).is_err());
        assert!(parse(&args(&["--seconds", "0"])).is_err());
        assert!(parse(&args(&["--seconds", "x"])).is_err());
        assert!(parse(&args(&["--seconds", "5", "--jobs", "2"])).is_err());
    }

    /// Every target named here has its file in fuzz/fuzz_targets/ and its corpus directory.
    #[test]
    fn every_target_has_a_file_and_a_corpus() {
        let root = workspace_root();
        for t in TARGETS {
            assert!(
                root.join(format!("fuzz/fuzz_targets/{t}.rs")).is_file(),
                "{t}"
            );
            assert!(root.join(format!("fuzz/corpus/{t}")).is_dir(), "{t}");
        }
    }
}
