//! `cargo xtask python` (and the `python` step of `ci`): the `impulse` Python package built and
//! tested in a virtual environment of its own.
//!
//! 1. **The environment**: `target/py-venv`, made with `$PYTHON -m venv` (the launcher finds
//!    Python 3 and installs it where it can, `xtask/launcher/src/prerequisites.rs`) and filled
//!    with `pip install -r crates/impulse-py/requirements-ci.txt` (maturin, NumPy, pytest,
//!    Dask, pinned) from PyPI. A copy of the requirements it was made from is kept inside it;
//!    while they are unchanged it is reused, so only a fresh clone (or changed pins) pays the
//!    download. A new user runs `cargo xtask ci` and gets it without a step of their own;
//!    `rm -rf target/py-venv` starts afresh.
//! 2. **The package**: `maturin develop` in `crates/impulse-py` (a dev-profile build of
//!    the extension, into the workspace's `target/`; maturin sets `PYO3_BUILD_EXTENSION_MODULE`).
//! 3. **The tests**: `python -m pytest crates/impulse-py/tests` with `IMPULSE_CLI` naming the
//!    `impulse` program (built by `cargo test --workspace --no-run`, done already by the test
//!    step: `cargo build -p impulse-cli` would resolve other features and build it again), which
//!    many tests take as their reference.
//!
//! The environment's programs are under `bin/` on Unix and `Scripts/` (with `.exe`) on
//! Windows ([`venv_program`]).

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::{Result, cargo, workspace_root};

/// The virtual environment, relative to the workspace root.
pub const VENV: &str = "target/py-venv";

/// What the environment is made from, relative to the workspace root.
pub const REQUIREMENTS: &str = "crates/impulse-py/requirements-ci.txt";

/// The copy of the requirements an environment was made from, inside it.
const STAMP: &str = "impulse-requirements.txt";

/// The directory of a virtual environment's programs, relative to it, on a Windows or other
/// host.
fn venv_bin_dir(windows: bool) -> &'static str {
    if windows { "Scripts" } else { "bin" }
}

/// The path of program `name` (`"python"`, `"maturin"`) of the virtual environment `venv` on
/// a Windows (`Scripts\NAME.exe`) or other (`bin/NAME`) host; `windows`: `cfg!(windows)`
/// (a parameter so both are tested on either).
pub fn venv_program(venv: &Path, name: &str, windows: bool) -> PathBuf {
    let file = if windows {
        format!("{name}.exe")
    } else {
        name.to_owned()
    };
    venv.join(venv_bin_dir(windows)).join(file)
}

/// Runs the three steps.
pub fn run() -> Result<()> {
    let root = workspace_root();
    let venv = root.join(VENV);
    ensure_venv(&root, &venv)?;
    let windows = cfg!(windows);
    let bin = venv.join(venv_bin_dir(windows));
    let crate_dir = root.join("crates/impulse-py");
    run_step(
        Command::new(venv_program(&venv, "maturin", windows))
            .args(["develop", "--quiet"])
            .env("VIRTUAL_ENV", &venv)
            .env("PATH", path_with(&bin))
            .current_dir(&crate_dir),
        "maturin develop (crates/impulse-py)",
    )?;
    // The `impulse` program as the test step builds it: `cargo build -p impulse-cli` would
    // resolve the CLI's features alone and compile the workspace again (118 s of a fresh
    // `cargo xtask ci`); after the test step this is a no-op.
    run_step(
        Command::new(cargo())
            .args(["test", "--workspace", "--no-run", "--quiet"])
            .current_dir(&root),
        "cargo test --workspace --no-run (the `impulse` program, as the test step built it)",
    )?;
    let target =
        std::env::var_os("CARGO_TARGET_DIR").map_or_else(|| root.join("target"), PathBuf::from);
    run_step(
        Command::new(venv_program(&venv, "python", windows))
            .args(["-m", "pytest", "-q", "-p", "no:cacheprovider"])
            .arg(crate_dir.join("tests"))
            .env(
                "IMPULSE_CLI",
                target
                    .join("debug")
                    .join(format!("impulse{}", std::env::consts::EXE_SUFFIX)),
            )
            .current_dir(&root),
        "pytest crates/impulse-py/tests",
    )
}

/// Whether an environment made from `stamp` (its copy of the requirements; `None` when there
/// is none) serves `requirements`.
pub fn venv_is_current(stamp: Option<&str>, requirements: &str) -> bool {
    stamp.is_some_and(|s| s == requirements)
}

/// Makes the environment unless one made from the same requirements is there.
fn ensure_venv(root: &Path, venv: &Path) -> Result<()> {
    let req_path = root.join(REQUIREMENTS);
    let requirements = std::fs::read_to_string(&req_path)
        .map_err(|e| format!("cannot read {}: {e}", req_path.display()))?;
    let stamp = std::fs::read_to_string(venv.join(STAMP)).ok();
    let python_in_venv = venv_program(venv, "python", cfg!(windows));
    if python_in_venv.is_file() && venv_is_current(stamp.as_deref(), &requirements) {
        println!("python: reusing {VENV} (made from the same {REQUIREMENTS})");
        return Ok(());
    }
    println!("python: making {VENV} from {REQUIREMENTS} (downloads from PyPI)");
    if venv.exists() {
        std::fs::remove_dir_all(venv)
            .map_err(|e| format!("cannot remove the old {}: {e}", venv.display()))?;
    }
    let python = std::env::var_os("PYTHON").unwrap_or_else(|| "python3".into());
    run_step(
        Command::new(&python).args(["-m", "venv"]).arg(venv),
        &format!(
            "{} -m venv {VENV} (on Debian and Ubuntu the venv module is the package \
             python3-venv: `apt-get install python3-venv`)",
            python.to_string_lossy()
        ),
    )?;
    run_step(
        Command::new(&python_in_venv)
            .args([
                "-m",
                "pip",
                "install",
                "--quiet",
                "--disable-pip-version-check",
                "-r",
            ])
            .arg(&req_path),
        &format!("pip install -r {REQUIREMENTS}"),
    )?;
    std::fs::write(venv.join(STAMP), requirements)
        .map_err(|e| format!("cannot write {}: {e}", venv.join(STAMP).display()))
}

/// `PATH` with `dir` in front (maturin looks for the environment's `python` on it).
fn path_with(dir: &Path) -> std::ffi::OsString {
    let mut paths = vec![dir.to_path_buf()];
    if let Some(old) = std::env::var_os("PATH") {
        paths.extend(std::env::split_paths(&old));
    }
    std::env::join_paths(paths).unwrap_or_else(|_| dir.as_os_str().to_owned())
}

/// Runs a command with inherited output, then prints its wall time; `Err` names it (`shown`)
/// and how it failed.
fn run_step(cmd: &mut Command, shown: &str) -> Result<()> {
    println!("==> {shown}");
    let start = std::time::Instant::now();
    let status = cmd
        .status()
        .map_err(|e| format!("could not start `{shown}`: {e}"))?;
    println!("    ({:.1} s)", start.elapsed().as_secs_f64());
    if status.success() {
        Ok(())
    } else {
        Err(format!("`{shown}` failed ({status})"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_environment_is_reused_only_for_the_same_requirements() {
        let req = "maturin==1.16.0\nnumpy==2.4.6\n";
        assert!(venv_is_current(Some(req), req));
        assert!(!venv_is_current(
            Some("maturin==1.15.0\nnumpy==2.4.6\n"),
            req
        ));
        assert!(!venv_is_current(None, req));
    }

    #[test]
    fn programs_are_under_bin_on_unix_and_scripts_with_exe_on_windows() {
        let venv = Path::new("target").join("py-venv");
        assert_eq!(
            venv_program(&venv, "python", false),
            venv.join("bin").join("python")
        );
        assert_eq!(
            venv_program(&venv, "python", true),
            venv.join("Scripts").join("python.exe")
        );
        assert_eq!(
            venv_program(&venv, "maturin", true),
            venv.join("Scripts").join("maturin.exe")
        );
        // This host's choice is the cfg's.
        let here = venv_program(&venv, "python", cfg!(windows));
        assert_eq!(here.ends_with("Scripts/python.exe"), cfg!(windows));
    }

    #[test]
    fn the_requirements_pin_what_the_step_runs() {
        let text = std::fs::read_to_string(workspace_root().join(REQUIREMENTS)).unwrap();
        for needed in ["maturin==", "numpy==", "pytest==", "dask[distributed]=="] {
            assert!(
                text.lines().any(|l| l.starts_with(needed)),
                "{REQUIREMENTS} pins no {needed}"
            );
        }
    }
}
