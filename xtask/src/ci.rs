//! `cargo xtask ci`: every check a CI job runs, in order, stopping at the first failure.
//!
//! The steps are: `cargo fmt --all -- --check`; `features` (the builds CI makes give every
//! dependency the same features, so the workspace is compiled once: [`crate::unify`]); `cargo clippy --workspace --all-targets -- -D
//! warnings`; `cargo test --workspace` (explicitly the whole workspace: the default members
//! leave out xtask, whose own tests must run too); `python` (the `impulse` Python package built
//! with maturin into `target/py-venv` and its pytest suite run: [`crate::python`]); `cargo doc --workspace --no-deps` with
//! `RUSTDOCFLAGS=-D warnings` (broken intra-doc links fail); the layering check, the packaging
//! check (every crate under `crates/` packaged for crates.io in layer order, without building the
//! packages: see [`crate::package`] for what is checked and why), `validate` and `viewer`
//! (the replay pages in headless Chromium: [`crate::viewer`]), all four in-process. Each step prints a heading, then its wall time; a summary line
//! ends the run.

use std::process::Command;
use std::time::{Duration, Instant};

use crate::{Result, cargo, layering, package, python, unify, validate, viewer, workspace_root};

/// One step of the sequence.
enum Step {
    /// `cargo <args>`, run in the workspace root with inherited output.
    Cargo(&'static [&'static str]),
    /// The same with environment variables set: (args, [(name, value)]).
    CargoEnv(
        &'static [&'static str],
        &'static [(&'static str, &'static str)],
    ),
    /// A check of this crate, run in this process: (name, check).
    InProcess(&'static str, fn() -> Result<()>),
}

impl Step {
    /// The heading printed before the step runs.
    fn title(&self) -> String {
        match self {
            Step::Cargo(args) => format!("cargo {}", args.join(" ")),
            Step::CargoEnv(args, env) => {
                let vars: Vec<String> = env.iter().map(|(k, v)| format!("{k}='{v}'")).collect();
                format!("{} cargo {}", vars.join(" "), args.join(" "))
            }
            Step::InProcess(name, _) => (*name).to_owned(),
        }
    }

    /// Runs the step.
    fn run(&self) -> Result<()> {
        match self {
            Step::Cargo(args) => cargo_step(args, &[]),
            Step::CargoEnv(args, env) => cargo_step(args, env),
            Step::InProcess(_, run) => run(),
        }
    }
}

/// The steps, in the order they run.
const STEPS: &[Step] = &[
    Step::Cargo(&["fmt", "--all", "--", "--check"]),
    Step::InProcess("features", unify::run),
    Step::Cargo(&[
        "clippy",
        "--workspace",
        "--all-targets",
        "--",
        "-D",
        "warnings",
    ]),
    Step::Cargo(&["test", "--workspace"]),
    Step::InProcess("python", python::run),
    Step::CargoEnv(
        &["doc", "--workspace", "--no-deps"],
        &[("RUSTDOCFLAGS", "-D warnings")],
    ),
    Step::InProcess("layering", layering::run),
    Step::InProcess("package", package::run),
    Step::InProcess("validate", || validate::run(&validate::Options::default())),
    Step::InProcess("viewer", viewer::run),
];

/// Runs every step; `Err` names the step that failed and why.
pub fn run() -> Result<()> {
    let start = Instant::now();
    let mut timings = Vec::new();
    for step in STEPS {
        let title = step.title();
        println!("\n==> {title}");
        let step_start = Instant::now();
        let result = step.run();
        let elapsed = step_start.elapsed();
        match result {
            Ok(()) => {
                println!("==> ok: {title} ({})", seconds(elapsed));
                timings.push((title, elapsed));
            }
            Err(message) => {
                println!("==> FAILED: {title} ({})", seconds(elapsed));
                return Err(format!(
                    "ci failed at `{title}` after {} in total: {message}",
                    seconds(start.elapsed())
                ));
            }
        }
    }
    println!("\nci summary:");
    for (title, elapsed) in &timings {
        println!("  {:>9}  {title}", seconds(*elapsed));
    }
    println!(
        "ci: all {} steps passed in {}",
        STEPS.len(),
        seconds(start.elapsed())
    );
    Ok(())
}

/// Runs `cargo <args>` in the workspace root with inherited output.
fn cargo_step(args: &[&str], env: &[(&str, &str)]) -> Result<()> {
    let shown = format!("cargo {}", args.join(" "));
    let status = Command::new(cargo())
        .args(args)
        .envs(env.iter().copied())
        .current_dir(workspace_root())
        .status()
        .map_err(|e| format!("could not start `{shown}`: {e}"))?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("`{shown}` failed ({status})"))
    }
}

/// A duration as seconds with one decimal, e.g. `12.3 s`.
fn seconds(duration: Duration) -> String {
    format!("{:.1} s", duration.as_secs_f64())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_run_in_the_documented_order() {
        let titles: Vec<String> = STEPS.iter().map(Step::title).collect();
        assert_eq!(
            titles,
            [
                "cargo fmt --all -- --check",
                "features",
                "cargo clippy --workspace --all-targets -- -D warnings",
                "cargo test --workspace",
                "python",
                "RUSTDOCFLAGS='-D warnings' cargo doc --workspace --no-deps",
                "layering",
                "package",
                "validate",
                "viewer",
            ]
        );
    }

    #[test]
    fn durations_print_in_seconds() {
        assert_eq!(seconds(Duration::from_millis(12_345)), "12.3 s");
    }
}
