//! `cargo xtask ci` on a machine without Chromium and without a way to install it stops at
//! once, naming the program and how to get it (the launcher's promise: before any build).

use std::process::Command;
use std::time::{Duration, Instant};

/// The launcher must answer well within the 10 s a user waits for a missing-program message.
const ANSWER_WITHIN: Duration = Duration::from_secs(10);

/// The programs of a Rust toolchain installed by rustup, as a fresh machine has them.
const TOOLCHAIN: [&str; 7] = [
    "cargo",
    "cargo-fmt",
    "cargo-clippy",
    "rustc",
    "rustfmt",
    "clippy-driver",
    "rustup",
];

/// A directory holding links to the Rust toolchain's programs found on this test's PATH, and
/// nothing else: a machine with only the Rust toolchain.
#[cfg(unix)]
fn toolchain_only(dir: &std::path::Path) {
    std::fs::create_dir_all(dir).unwrap();
    let path = std::env::var_os("PATH").unwrap_or_default();
    for name in TOOLCHAIN {
        if let Some(found) = std::env::split_paths(&path)
            .map(|d| d.join(name))
            .find(|p| p.is_file())
        {
            let link = dir.join(name);
            let _ = std::fs::remove_file(&link);
            std::os::unix::fs::symlink(found, link).unwrap();
        }
    }
}

#[cfg(unix)]
#[test]
fn a_missing_program_without_a_package_manager_stops_in_seconds_with_what_to_run() {
    // PATH holds the Rust toolchain alone: no Chromium, no apt-get, no sudo, no `id` (so not
    // known to be root).
    let empty =
        std::env::temp_dir().join(format!("xtask-launcher-rust-only-{}", std::process::id()));
    toolchain_only(&empty);
    let start = Instant::now();
    let out = Command::new(env!("CARGO_BIN_EXE_xtask-launcher"))
        .arg("ci")
        .env("PATH", &empty)
        .env_remove("CHROMIUM")
        .env_remove("XTASK_NO_INSTALL")
        .output()
        .unwrap();
    let elapsed = start.elapsed();
    let _ = std::fs::remove_dir_all(&empty);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "stderr: {stderr}");
    assert!(elapsed < ANSWER_WITHIN, "took {elapsed:?}");
    assert!(stderr.contains("needs what this machine lacks"), "{stderr}");
    assert!(stderr.contains("- chromium: not found"), "{stderr}");
    assert!(stderr.contains("`apt-get install chromium`"), "{stderr}");
    assert!(stderr.contains("set CHROMIUM to the program"), "{stderr}");
    // The toolchain that runs this test has rustfmt and clippy (`cargo xtask ci` formats and
    // lints with them), and cargo finds its subcommands without PATH: they are not reported.
    assert!(!stderr.contains("- rustfmt"), "{stderr}");
    assert!(!stderr.contains("- clippy"), "{stderr}");
    // Nothing after the check ran: xtask was not built or started.
    assert!(!String::from_utf8_lossy(&out.stdout).contains("==> prerequisites"));
}

#[test]
fn a_program_named_by_its_variable_is_used_when_it_answers_and_refused_when_not() {
    let dir = std::env::temp_dir().join(format!("xtask-launcher-env-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let missing = dir.join("no-such-chromium");
    let out = Command::new(env!("CARGO_BIN_EXE_xtask-launcher"))
        .arg("viewer")
        .env("CHROMIUM", &missing)
        .env("XTASK_NO_INSTALL", "1")
        .output()
        .unwrap();
    let _ = std::fs::remove_dir(&dir);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "stderr: {stderr}");
    assert!(
        stderr.contains(&format!(
            "$CHROMIUM is {}, which does not answer `--version`",
            missing.display()
        )),
        "{stderr}"
    );
}
