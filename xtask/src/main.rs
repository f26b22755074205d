//! `xtask`: the project automation of `impulse`, run as `cargo xtask <command>`.
//!
//! Layer 5 of `docs/architecture.md`, beside the `impulse` program; nothing depends on it.
//!
//! **Owns**: the one entry point for CI (`ci` runs locally exactly what a CI job runs, so no logic
//! lives in workflow YAML); the validation harness (`validate`: the registry of cases in
//! [`cases`], their references and tolerances, how results are judged, printed and snapshotted in
//! `fixtures/snapshots/`); the packaging check (`package`: every crate under `crates/` can be
//! packaged for crates.io); the layering check (`layering`: crate dependencies against the layer
//! table of `docs/architecture.md`); the fuzzing runs (`fuzz`: the cargo-fuzz targets of `fuzz/`
//! in turn, nightly only; their checks are `fuzz-check`'s).
//!
//! **Must not know**: how any quantity is computed. Cases call the public API of the library
//! crates and compare with independent references; xtask holds no geometry or physics of its
//! own, and no library crate may learn about validation cases or snapshots.
//!
//! Modules: [`ci`] (the step sequence), [`layering`], [`unify`] (the builds CI makes share
//! their dependencies), [`package`], [`python`] (the Python
//! package's build and tests), [`validate`] (harness,
//! checks, snapshots), [`cases`] (the registry). Dependencies are kept minimal: insta and serde_json only; the
//! command line is parsed by hand.

mod bench;
mod bowling;
mod browser;
mod cases;
mod ci;
mod forks;
mod fuzz;
mod layering;
mod package;
// Without the `peers` feature the runner is built (so CI checks it) but has no engine to call.
#[cfg_attr(not(feature = "peers"), allow(dead_code))]
mod peers;
mod plot;
mod poses;
mod python;
mod scale;
mod stacks;
mod unify;
mod validate;
mod viewer;

use std::path::PathBuf;
use std::process::ExitCode;

/// Errors are one human-readable message with its context; xtask only ever prints them.
pub type Result<T> = std::result::Result<T, String>;

/// Usage text, printed by `help` and on a command-line error.
const USAGE: &str = "\
usage: cargo xtask <command>

commands:
  ci                                  cargo fmt --check, features, clippy -D warnings, test
                                      --workspace, python, doc, layering, package, validate,
                                      viewer; stops at the first failure
  features                            check that xtask's and impulse-py's own builds give every
                                      dependency the features `cargo test --workspace` gives
                                      it (else CI compiles the workspace twice)
  python                              build the `impulse` Python package (maturin, dev profile)
                                      into target/py-venv (made from
                                      crates/impulse-py/requirements-ci.txt when absent or
                                      out of date) and run its pytest suite
  validate [--update] [--case NAME]   run the validation cases (all, or only NAME), check each
                                      metric against its reference, compare with the snapshots
                                      in fixtures/snapshots/; --update writes the snapshots
  bench [--out DIR] [--case NAME] [--peers]
                                      speed against error: every scene at three accuracy settings
                                      in a release build; prints slowdown next to thesis Table 7.1
                                      and the error; writes bench.csv and one SVG per scene to DIR
                                      (default target/bench); then the stack study of 1–8 blocks
                                      (stacks.csv; alone with --case stacks); --case forks
                                      runs the FORK⁻¹S study alone (Tables 1-2, Fig. 7);
                                      --case poses the pose studies alone (drops/s on 1
                                      and 2 threads, thick coin, thesis parts; poses.csv);
                                      --case bowling the bowling study alone (throws/s on
                                      1 and 2 threads, 320 + 320 throws, about 45 min on
                                      2 cores; bowling.csv, bowling.json);
                                      --peers runs stacks, dominos, ramp, sliding→rolling and
                                      pool break in impulse and rapier3d-f64 side by side
                                      (builds xtask with --features peers; peers.csv, peers.svg)
  bench --scale [--peers] [--only NAME] [--budget SECONDS] [--out DIR]
                                      piles of 27, 216 and 1000 boxes and spheres and a
                                      pyramid of 20 rows: cost against body count on one
                                      thread (1000 boxes also on two, checked bit-identical),
                                      each run judged from its frames (overlap, depth below
                                      the ground, rest, drift); --peers adds rapier at dt
                                      1/60 and 1 ms; a run stops after --budget wall seconds
                                      (default 600); scale.csv, scale.svg, scenes/*.ron
  package                             package every crate under crates/ for crates.io, in
                                      layer order, without uploading or building them
                                      (into target/package-check)
  viewer                              the pages of `impulse run --html` for dominos, pool
                                      break, rattleback and 50 bodies over 30 s, opened in
                                      headless Chromium: no console error, bodies drawn where
                                      the trajectory says, picking, scrubbing, frame rate;
                                      screenshots in target/viewer
  layering                            check crate dependencies against the layer table of
                                      docs/architecture.md
  fuzz --seconds N [--target NAME]    run every cargo-fuzz target of fuzz/ (scene, obj, urdf,
                                      mechanism, part) for N seconds each, one after another;
                                      needs the nightly toolchain and cargo-fuzz (not in ci:
                                      `cargo test` replays fuzz/corpus/ on stable)
  help                                print this message
";

/// A parsed command line.
#[derive(Debug, PartialEq)]
enum Command {
    Ci,
    Validate(validate::Options),
    Bench(bench::Options),
    Layering,
    Features,
    Package,
    Python,
    Viewer,
    Fuzz(fuzz::Options),
    Help,
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let command = match parse_args(&args) {
        Ok(command) => command,
        Err(message) => {
            eprintln!("error: {message}\n\n{USAGE}");
            return ExitCode::from(2);
        }
    };
    let result = match command {
        Command::Ci => ci::run(),
        Command::Validate(options) => validate::run(&options),
        Command::Bench(options) => bench::run_bench(&options),
        Command::Layering => layering::run(),
        Command::Features => unify::run(),
        Command::Package => package::run(),
        Command::Python => python::run(),
        Command::Viewer => viewer::run(),
        Command::Fuzz(options) => fuzz::run(&options),
        Command::Help => {
            print!("{USAGE}");
            Ok(())
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("error: {message}");
            ExitCode::FAILURE
        }
    }
}

/// Parses the arguments after `cargo xtask`; `Err` is a usage error (exit code 2).
fn parse_args(args: &[String]) -> Result<Command> {
    let Some((command, rest)) = args.split_first() else {
        return Err("no command given".to_owned());
    };
    let no_arguments = |command: Command| match rest.first() {
        None => Ok(command),
        Some(arg) => Err(format!("unexpected argument `{arg}`")),
    };
    match command.as_str() {
        "ci" => no_arguments(Command::Ci),
        "layering" => no_arguments(Command::Layering),
        "features" => no_arguments(Command::Features),
        "package" => no_arguments(Command::Package),
        "python" => no_arguments(Command::Python),
        "viewer" => no_arguments(Command::Viewer),
        "help" | "-h" | "--help" => no_arguments(Command::Help),
        "validate" => parse_validate(rest).map(Command::Validate),
        "bench" => parse_bench(rest).map(Command::Bench),
        "fuzz" => fuzz::parse(rest).map(Command::Fuzz),
        other => Err(format!("unknown command `{other}`")),
    }
}

/// Parses `validate [--update] [--case NAME]` (also `--case=NAME`).
fn parse_validate(args: &[String]) -> Result<validate::Options> {
    let mut options = validate::Options::default();
    let mut args = args.iter();
    while let Some(arg) = args.next() {
        let case = match arg.as_str() {
            "--update" => {
                options.update = true;
                continue;
            }
            "--case" => args.next().ok_or("`--case` needs a case name")?.clone(),
            _ => match arg.strip_prefix("--case=") {
                Some(name) => name.to_owned(),
                None => return Err(format!("unexpected argument `{arg}` to `validate`")),
            },
        };
        if options.case.replace(case).is_some() {
            return Err("`--case` given more than once".to_owned());
        }
    }
    Ok(options)
}

/// Parses `bench [--out DIR] [--case NAME] [--in-release] [--peers] [--scale] [--only NAME]
/// [--budget SECONDS]`.
fn parse_bench(args: &[String]) -> Result<bench::Options> {
    let mut options = bench::Options::default();
    let mut args = args.iter();
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--out" => options.out = Some(args.next().ok_or("`--out` needs a directory")?.into()),
            "--case" => {
                options.case = Some(args.next().ok_or("`--case` needs a case name")?.clone())
            }
            "--in-release" => options.in_release = true,
            "--peers" => options.peers = true,
            "--scale" => options.scale = true,
            "--only" => {
                options.only = Some(args.next().ok_or("`--only` needs a scene name")?.clone())
            }
            "--budget" => {
                let value = args.next().ok_or("`--budget` needs seconds")?;
                let budget: f64 = value
                    .parse()
                    .map_err(|_| format!("`--budget {value}`: not a number of seconds"))?;
                if !(budget.is_finite() && budget > 0.0) {
                    return Err(format!(
                        "`--budget {value}`: must be a positive number of seconds"
                    ));
                }
                options.budget = Some(budget);
            }
            _ => return Err(format!("unexpected argument `{arg}` to `bench`")),
        }
    }
    Ok(options)
}

/// The workspace root: the parent of this crate's manifest directory.
pub fn workspace_root() -> PathBuf {
    let manifest_dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    manifest_dir
        .parent()
        .map_or(manifest_dir.clone(), PathBuf::from)
}

/// The cargo to run: `$CARGO` (set by cargo for `cargo run`, hence for `cargo xtask`), else
/// `cargo` from `PATH`.
pub fn cargo() -> std::ffi::OsString {
    std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(args: &[&str]) -> Result<Command> {
        parse_args(&args.iter().map(|a| a.to_string()).collect::<Vec<_>>())
    }

    #[test]
    fn commands_parse() {
        assert_eq!(parse(&["ci"]), Ok(Command::Ci));
        assert_eq!(parse(&["layering"]), Ok(Command::Layering));
        assert_eq!(parse(&["package"]), Ok(Command::Package));
        assert_eq!(parse(&["python"]), Ok(Command::Python));
        assert_eq!(parse(&["help"]), Ok(Command::Help));
        assert_eq!(
            parse(&["validate"]),
            Ok(Command::Validate(validate::Options::default()))
        );
        let expected = validate::Options {
            update: true,
            case: Some("V1".to_owned()),
        };
        assert_eq!(
            parse(&["validate", "--update", "--case", "V1"]),
            Ok(Command::Validate(expected))
        );
        let expected = validate::Options {
            update: false,
            case: Some("V2".to_owned()),
        };
        assert_eq!(
            parse(&["validate", "--case=V2"]),
            Ok(Command::Validate(expected))
        );
    }

    /// `bench --peers` asks for the peer comparison; nothing else does.
    #[test]
    fn bench_peers_parses() {
        let Ok(Command::Bench(options)) = parse(&["bench", "--peers"]) else {
            panic!("bench --peers did not parse");
        };
        assert!(options.peers && !options.in_release);
        let Ok(Command::Bench(options)) = parse(&["bench"]) else {
            panic!("bench did not parse");
        };
        assert!(!options.peers);
    }

    #[test]
    fn bad_command_lines_are_usage_errors() {
        assert!(parse(&[]).is_err());
        assert!(
            parse(&["frobnicate"])
                .unwrap_err()
                .contains("unknown command `frobnicate`")
        );
        assert!(parse(&["ci", "--fast"]).unwrap_err().contains("`--fast`"));
        assert!(
            parse(&["validate", "--case"])
                .unwrap_err()
                .contains("needs a case name")
        );
        assert!(parse(&["validate", "--case", "a", "--case", "b"]).is_err());
        assert!(
            parse(&["validate", "--updat"])
                .unwrap_err()
                .contains("`--updat`")
        );
    }

    #[test]
    fn workspace_root_holds_the_architecture_doc() {
        assert!(workspace_root().join("docs/architecture.md").is_file());
    }
}
