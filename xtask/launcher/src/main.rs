//! `cargo xtask`: the entry point of the project's automation.
//!
//! The `xtask` alias (`.cargo/config.toml`) runs this small program, not `xtask` itself.
//! It has no dependencies, so on a fresh clone it is built in about a second; it then checks
//! that the machine has what the subcommand needs beyond the Rust toolchain
//! ([`prerequisites::PREREQUISITES`]: rustfmt and clippy for `ci`, Chromium for `ci` and
//! `viewer`, Python 3 for `ci` and `python`), installs what is missing where it can (a system package as root or with sudo
//! that asks no password; a rustup component), and otherwise stops with a message naming the
//! program, why it is needed and the command that gets it — all before the minutes that
//! building `xtask` and the workspace take. Then it runs `cargo run -p xtask -- <args>` with
//! the programs it found in their environment variables (`CHROMIUM`, `PYTHON`).
//!
//! For `ci` it also sets `CARGO_INCREMENTAL=0` (unless the caller set it): CI builds from a
//! fresh clone, where incremental caches are only written, never read, and they are the largest
//! part of the target directory (2.3 of 4.8 GB in a fresh `cargo xtask ci`), enough to fill a
//! small disk; set `CARGO_INCREMENTAL=1` to keep them.
//!
//! `XTASK_NO_INSTALL=1` turns installing off: missing programs are reported with the commands
//! that would get them.
//!
//! Owns: the list of prerequisites, how to find and install them. Must not know: the checks
//! themselves (they are `xtask`'s).

mod prerequisites;

use std::ffi::OsString;
use std::path::PathBuf;
use std::process::{Command, ExitCode};
use std::time::Instant;

use prerequisites::{Host, Plan, Prerequisite, Probe};

/// Set (to anything but `0` or nothing) to report missing programs without installing them.
const NO_INSTALL: &str = "XTASK_NO_INSTALL";

/// The subcommands built without incremental caches unless `CARGO_INCREMENTAL` says otherwise
/// (see the crate documentation).
const NOT_INCREMENTAL: &[&str] = &["ci"];

fn main() -> ExitCode {
    let args: Vec<OsString> = std::env::args_os().skip(1).collect();
    let subcommand = args.first().and_then(|a| a.to_str()).unwrap_or_default();
    let cargo = cargo();
    let needed: Vec<&Prerequisite> = prerequisites::needed_by(subcommand).collect();
    let env = if needed.is_empty() {
        Vec::new()
    } else {
        match ensure(subcommand, &needed, &cargo) {
            Ok(env) => env,
            Err(message) => {
                eprintln!("error: {message}");
                return ExitCode::FAILURE;
            }
        }
    };
    let mut command = Command::new(&cargo);
    if NOT_INCREMENTAL.contains(&subcommand) && std::env::var_os("CARGO_INCREMENTAL").is_none() {
        command.env("CARGO_INCREMENTAL", "0");
    }
    let status = command
        .current_dir(workspace_root())
        .args(["run", "--quiet", "--package", "xtask", "--"])
        .args(&args)
        .envs(env)
        .status();
    match status {
        Ok(status) => status
            .code()
            .and_then(|code| u8::try_from(code).ok())
            .map_or(ExitCode::FAILURE, ExitCode::from),
        Err(e) => {
            eprintln!("error: could not run `cargo run -p xtask`: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Finds every prerequisite in `needed`, installing the missing ones where it can. `Ok` holds
/// the environment variables that tell `xtask` where the programs are; `Err` names every
/// prerequisite still missing, why it is needed and how to get it.
fn ensure(
    subcommand: &str,
    needed: &[&Prerequisite],
    cargo: &std::path::Path,
) -> Result<Vec<(&'static str, PathBuf)>, String> {
    let start = Instant::now();
    let may_install = std::env::var_os(NO_INSTALL).is_none_or(|v| v.is_empty() || v == "0");
    let mut host = None;
    let mut env = Vec::new();
    let mut found = Vec::new();
    let mut failures = Vec::new();
    for &prerequisite in needed {
        let located = match prerequisites::find(prerequisite, cargo) {
            Ok(path) => Ok(path),
            Err(why) => {
                let host = host.get_or_insert_with(Host::detect);
                install(prerequisite, &why, host, may_install, cargo)
            }
        };
        match located {
            Ok(path) => {
                if let (Probe::Program { env: var, .. }, Some(path)) = (&prerequisite.probe, path) {
                    found.push(format!("{} ({})", prerequisite.name, path.display()));
                    env.push((*var, path));
                } else {
                    found.push(prerequisite.name.to_owned());
                }
            }
            Err(message) => failures.push(message),
        }
    }
    if failures.is_empty() {
        println!(
            "==> prerequisites of `{subcommand}`: {} ({:.1} s)",
            found.join(", "),
            start.elapsed().as_secs_f64()
        );
        Ok(env)
    } else {
        Err(format!(
            "`cargo xtask {subcommand}` needs what this machine lacks (checked in {:.1} s, \
             before building anything):\n  - {}",
            start.elapsed().as_secs_f64(),
            failures.join("\n  - ")
        ))
    }
}

/// Installs a missing prerequisite if `host` allows it and `may_install`, then finds it again.
/// `Err` is the whole message for the user: what is missing, why it is needed, how to get it.
fn install(
    prerequisite: &Prerequisite,
    why: &str,
    host: &Host,
    may_install: bool,
    cargo: &std::path::Path,
) -> Result<Option<PathBuf>, String> {
    let name = prerequisite.name;
    let purpose = prerequisite.purpose;
    let or_env = match &prerequisite.probe {
        Probe::Program { env, .. } => format!(" Or set {env} to the program."),
        Probe::CargoSubcommand(_) => String::new(),
    };
    match prerequisites::plan(prerequisite, host) {
        Plan::Manual(how) => Err(format!("{name}: {why}; {purpose}. {how}.{or_env}")),
        Plan::Run(cmds) if !may_install => {
            let shown: Vec<String> = cmds.iter().map(|c| c.shown()).collect();
            Err(format!(
                "{name}: {why}; {purpose}. Install it with `{}` ({NO_INSTALL} is set, so \
                 cargo xtask did not).{or_env}",
                shown.join(" && ")
            ))
        }
        Plan::Run(cmds) => {
            println!("==> {name}: {why}; {purpose}. Installing it:");
            for cmd in &cmds {
                println!("==> {}", cmd.shown());
                cmd.run().map_err(|e| {
                    format!("{name}: {why}; {purpose}. Installing it failed: {e}.{or_env}")
                })?;
            }
            prerequisites::find(prerequisite, cargo).map_err(|again| {
                format!("{name}: installed, but still {again}; {purpose}.{or_env}")
            })
        }
    }
}

/// The cargo that runs us (`$CARGO`, set by `cargo run`), else `cargo` on `PATH`.
fn cargo() -> PathBuf {
    std::env::var_os("CARGO").map_or_else(|| PathBuf::from("cargo"), PathBuf::from)
}

/// The workspace root: two levels above this crate's manifest directory (`xtask/launcher`).
fn workspace_root() -> PathBuf {
    let manifest_dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    manifest_dir
        .ancestors()
        .nth(2)
        .map_or(manifest_dir.clone(), PathBuf::from)
}
