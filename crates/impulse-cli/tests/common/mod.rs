//! What the end-to-end tests of the `impulse` binary share.
// Each test binary uses part of this module.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Command;

/// The path of `path` under the workspace's `fixtures/`.
pub fn fixture(path: &str) -> String {
    format!("{}/../../fixtures/{path}", env!("CARGO_MANIFEST_DIR"))
}

/// A directory of its own under the system's temp dir (unique to this process and `name`),
/// removed with everything a test wrote in it when dropped, also when the test fails: a test
/// run leaves nothing behind.
pub struct Scratch(PathBuf);

impl Scratch {
    /// Creates the directory `impulse-<name>-<pid>` in the temp dir.
    pub fn new(name: &str) -> Self {
        let dir = std::env::temp_dir().join(format!("impulse-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        Scratch(dir)
    }
}

impl std::ops::Deref for Scratch {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// The outcome of one run of the binary.
pub struct Output {
    /// Exit status was success.
    pub ok: bool,
    /// Standard output parsed as JSON, when it is JSON.
    pub json: Option<serde_json::Value>,
    /// Standard error, as text.
    pub stderr: String,
}

/// Runs `impulse` with `args`.
pub fn impulse(args: &[&str]) -> Output {
    let out = Command::new(env!("CARGO_BIN_EXE_impulse"))
        .args(args)
        .output()
        .unwrap();
    Output {
        ok: out.status.success(),
        json: serde_json::from_slice(&out.stdout).ok(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    }
}

/// Runs `impulse` with `args`: (exit status was success, standard output, standard error),
/// as text.
pub fn impulse_text(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_impulse"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// The lines of `stdout` from the first that starts with `first` on: a report's figures,
/// without the run's wall time and shard lines above them.
pub fn lines_from(stdout: &str, first: &str) -> String {
    stdout
        .lines()
        .skip_while(|l| !l.starts_with(first))
        .collect::<Vec<_>>()
        .join("\n")
}
