//! Progress on stderr when stderr is not a terminal (here a pipe): whole short lines, never a
//! carriage return (a redirected `impulse reduce` used to write one line of `\r` updates), a
//! final line at 100 %, and nothing at all for work shorter than the threshold.
//!
//! The runs are fractions of a second; `IMPULSE_PROGRESS_NOW` (progress.rs) makes them report
//! from the start and at every update, as a run of minutes does at its pace.

mod common;

use std::process::Command;

use common::fixture;

/// A progress line longer than this (characters) is not a line a log reader can read.
const MAX_LINE_CHARS: usize = 100;

/// Runs `impulse` with stderr piped; with `now`, progress from the first update. Returns
/// stderr.
fn stderr_of(args: &[&str], now: bool) -> String {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_impulse"));
    cmd.args(args);
    if now {
        cmd.env("IMPULSE_PROGRESS_NOW", "1");
    } else {
        cmd.env_remove("IMPULSE_PROGRESS_NOW");
    }
    let out = cmd.output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "{stderr}");
    stderr
}

/// Checks a piped run's progress: plain short lines starting with `prefix`, at least two, the
/// last one at 100 %.
fn check_lines(stderr: &str, prefix: &str) {
    assert!(
        !stderr.contains('\r'),
        "carriage returns on a pipe: {stderr:?}"
    );
    let lines: Vec<&str> = stderr.lines().collect();
    for line in &lines {
        assert!(
            line.chars().count() <= MAX_LINE_CHARS,
            "a line of {} characters: {line:?}",
            line.chars().count()
        );
    }
    let progress: Vec<&&str> = lines.iter().filter(|l| l.starts_with(prefix)).collect();
    assert!(progress.len() >= 2, "no progress lines: {stderr:?}");
    let last = progress.last().unwrap();
    assert!(
        last.contains("(100 %"),
        "the last line is not the end: {last:?}"
    );
}

#[test]
fn a_piped_run_writes_whole_short_lines() {
    let stderr = stderr_of(
        &["run", &fixture("scenes/dominos.ron"), "--until", "0.2"],
        true,
    );
    check_lines(&stderr, "impulse run: t = ");
}

#[test]
fn a_piped_reduce_writes_whole_short_lines() {
    // 50 000 steps: the old code wrote `\r` updates whatever stderr was.
    let stderr = stderr_of(
        &[
            "reduce",
            &fixture("mechanisms/y.ron"),
            "--load",
            "a3:100,0,0",
            "--until",
            "0.5",
            "--dt",
            "1e-5",
        ],
        true,
    );
    check_lines(&stderr, "impulse reduce: t = ");
}

#[test]
fn a_piped_study_writes_whole_short_lines() {
    // Drops reported from the study's threads.
    let stderr = stderr_of(
        &[
            "poses",
            &fixture("parts/box-1x2x3.ron"),
            "--drops",
            "6",
            "--max-time",
            "3",
        ],
        true,
    );
    check_lines(&stderr, "impulse poses: ");
}

#[test]
fn a_short_run_shows_no_progress() {
    let stderr = stderr_of(
        &["run", &fixture("scenes/dominos.ron"), "--until", "0.2"],
        false,
    );
    assert_eq!(
        stderr, "",
        "a run of a fraction of a second reported progress"
    );
}
