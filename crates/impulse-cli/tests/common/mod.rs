//! What the end-to-end tests of the `impulse` binary share.

use std::process::Command;

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
