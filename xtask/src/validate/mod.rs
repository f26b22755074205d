//! `cargo xtask validate [--update] [--case NAME]`: runs the validation cases of
//! [`crate::cases`], judges every metric against its reference, and compares each case with its
//! snapshot in `fixtures/snapshots/`.
//!
//! Output is one aligned table (case, metric, value, reference, tolerance, pass, wall ms, note),
//! the wall time being that of the case's `run` on its first row, then a summary
//! `N metrics, F failed, in T ms`. The command fails when a metric fails its check, a case
//! returns `Err` or panics, or a snapshot is missing or differs; on a full run (no `--case`),
//! also when `fixtures/snapshots/` holds a `.snap` without a case or a leftover `.snap.new`
//! (`--update` deletes those).
//!
//! Snapshot mode: insta reads its update mode from the environment, and changing our own
//! environment is `unsafe` in edition 2024. So [`run`] checks the `INSTA_*` variables it relies
//! on and, unless they already hold, re-runs this executable as a child with them set:
//! `INSTA_UPDATE=no` (compare only: nothing is written) or, with `--update`,
//! `INSTA_UPDATE=always` (new and changed snapshots are written in place); `INSTA_FORCE_PASS=0`,
//! `INSTA_REQUIRE_FULL_MATCH=0` and `INSTA_WORKSPACE_ROOT` pin the rest, and the deprecated
//! variables that would force updates are removed. The outcome never depends on the caller's
//! environment (`CI` set or not), and no `.snap.new` file is ever written. A missing snapshot
//! without `--update` fails with a message to run `cargo xtask validate --update` and review the
//! new file. Rounding of values in snapshots: see [`snapshot`].

#[allow(
    dead_code,
    reason = "`Check` variants and `Metric::new` are built only by the cases in `crate::cases`, \
              unused while that registry is empty"
)]
pub mod case;
pub mod check;
mod snapshot;

use std::any::Any;
use std::collections::BTreeSet;
use std::ffi::OsString;
use std::path::Path;
use std::process::Command;
use std::time::Instant;

use crate::{Result, cases, workspace_root};
use case::Case;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Mutex, PoisonError};

/// Options of `cargo xtask validate`.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Options {
    /// Write new and changed snapshots instead of failing on them.
    pub update: bool,
    /// Run only the case of this name.
    pub case: Option<String>,
}

/// Set in the child process, to detect an environment that did not take.
const CHILD_MARKER: &str = "IMPULSE_XTASK_VALIDATE_CHILD";

/// Runs the validation: in this process when the insta environment is already right, else in a
/// child process with it set (see the module documentation).
pub fn run(options: &Options) -> Result<()> {
    let all = cases::all();
    // Checked here first so that a bad registry or case name is reported once, by this process.
    check_registry(&all)?;
    select(&all, options.case.as_deref())?;
    let root = workspace_root();
    let env = insta_env(options.update, &root);
    let env_holds = env
        .iter()
        .all(|(name, wanted)| std::env::var_os(name).as_ref() == wanted.as_ref());
    if env_holds {
        run_cases(&all, options, &root.join("fixtures").join("snapshots"))
    } else if std::env::var_os(CHILD_MARKER).is_some() {
        Err("the validation child process did not receive its INSTA_* environment".to_owned())
    } else {
        run_child(options, &env)
    }
}

/// The insta environment for a mode: each variable's required value, `None` for unset.
fn insta_env(update: bool, root: &Path) -> Vec<(&'static str, Option<OsString>)> {
    vec![
        (
            "INSTA_UPDATE",
            Some(if update { "always" } else { "no" }.into()),
        ),
        ("INSTA_FORCE_PASS", Some("0".into())),
        ("INSTA_REQUIRE_FULL_MATCH", Some("0".into())),
        ("INSTA_WORKSPACE_ROOT", Some(root.as_os_str().to_owned())),
        ("INSTA_FORCE_UPDATE", None),
        ("INSTA_FORCE_UPDATE_SNAPSHOTS", None),
    ]
}

/// Re-runs `validate` with the same options as a child process with `env` applied.
fn run_child(options: &Options, env: &[(&'static str, Option<OsString>)]) -> Result<()> {
    let exe = std::env::current_exe()
        .map_err(|e| format!("cannot find the xtask executable to re-run: {e}"))?;
    let mut command = Command::new(&exe);
    command.arg("validate");
    if options.update {
        command.arg("--update");
    }
    if let Some(name) = &options.case {
        command.args(["--case", name]);
    }
    for (name, value) in env {
        match value {
            Some(value) => command.env(name, value),
            None => command.env_remove(name),
        };
    }
    let status = command
        .env(CHILD_MARKER, "1")
        .status()
        .map_err(|e| format!("could not start {} validate: {e}", exe.display()))?;
    if status.success() {
        Ok(())
    } else {
        // The child has printed the table and its own error.
        Err(format!(
            "validation failed (validate child process: {status})"
        ))
    }
}

/// Counts for the summary line.
#[derive(Default)]
struct Tally {
    metrics: usize,
    failed_metrics: usize,
    failed_cases: usize,
    failed_snapshots: usize,
    written_snapshots: usize,
}

/// Runs the selected cases, prints the table and the summary.
fn run_cases(all: &[Case], options: &Options, snapshot_dir: &Path) -> Result<()> {
    let start = Instant::now();
    let selected = select(all, options.case.as_deref())?;

    // The cases are independent: they run in parallel, then are judged and compared with
    // their snapshots in registry order, so the table and its verdicts do not depend on the
    // thread count. A case's wall time is then measured while others run.
    let outcomes = run_parallel(&selected);
    let mut rows = Vec::new();
    let mut tally = Tally::default();
    for (case, (outcome, seconds)) in selected.into_iter().zip(outcomes) {
        let judged = Judged {
            outcome,
            seconds,
            update: options.update,
        };
        judge_case(case, judged, snapshot_dir, &mut rows, &mut tally);
    }
    let stale = match options.case {
        None => stale_files(snapshot_dir, all, options.update)?,
        Some(_) => Vec::new(),
    };

    print_table(&rows);
    for message in &stale {
        println!("FAIL {message}");
    }
    let failures = tally.failed_metrics + tally.failed_cases + tally.failed_snapshots + stale.len();
    let mut summary = format!(
        "{} metrics, {} failed, in {} ms",
        tally.metrics,
        tally.failed_metrics,
        start.elapsed().as_millis()
    );
    for (count, what) in [
        (tally.failed_cases, "case(s) did not run"),
        (tally.failed_snapshots, "snapshot(s) failed"),
        (stale.len(), "stale snapshot file(s)"),
        (tally.written_snapshots, "snapshot(s) written"),
    ] {
        if count > 0 {
            summary += &format!("; {count} {what}");
        }
    }
    println!("{summary}");
    if failures == 0 {
        Ok(())
    } else {
        Err(format!("validation failed: {summary}"))
    }
}

/// The cases to run: all of them, or the one named `name`.
fn select<'a>(all: &'a [Case], name: Option<&str>) -> Result<Vec<&'a Case>> {
    let Some(name) = name else {
        return Ok(all.iter().collect());
    };
    let selected: Vec<&Case> = all.iter().filter(|c| c.name == name).collect();
    if selected.is_empty() {
        let names: Vec<&str> = all.iter().map(|c| c.name).collect();
        let known = if names.is_empty() {
            "none".to_owned()
        } else {
            names.join(", ")
        };
        return Err(format!(
            "no validation case named `{name}` (cases: {known})"
        ));
    }
    Ok(selected)
}

/// Case names are unique and usable as file names.
fn check_registry(cases: &[Case]) -> Result<()> {
    let mut seen = BTreeSet::new();
    for case in cases {
        let valid = !case.name.is_empty()
            && !case.name.starts_with('.')
            && case
                .name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || "-_.".contains(c));
        if !valid {
            return Err(format!(
                "validation case name `{}` must be non-empty ASCII letters, digits, `-`, `_`, `.`",
                case.name
            ));
        }
        if !seen.insert(case.name) {
            return Err(format!("two validation cases are named `{}`", case.name));
        }
    }
    Ok(())
}

/// One table row: the seven columns, then a free-form note.
struct Row {
    cells: [String; 7],
    note: String,
}

impl Row {
    fn new(case: &str, metric: &str, pass: bool, note: impl Into<String>) -> Self {
        let cells = [
            case,
            metric,
            "",
            "",
            "",
            if pass { "ok" } else { "FAIL" },
            "",
        ];
        Row {
            cells: cells.map(str::to_owned),
            note: note.into(),
        }
    }
}

/// Runs the cases' `run` on `std::thread::available_parallelism` plain threads, each taking
/// the next case not yet taken; returns (outcome, wall seconds) in the order of `cases`. Plain
/// threads rather than rayon tasks: a case that installs its own rayon pools (the determinism
/// case) would otherwise wait inside a rayon worker and run other cases while it waits.
fn run_parallel(cases: &[&Case]) -> Vec<(RunOutcome, f64)> {
    let threads = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .min(cases.len().max(1));
    let next = AtomicUsize::new(0);
    let slots: Vec<Mutex<Option<(RunOutcome, f64)>>> =
        cases.iter().map(|_| Mutex::new(None)).collect();
    std::thread::scope(|scope| {
        for _ in 0..threads {
            scope.spawn(|| {
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some(case) = cases.get(i) else { break };
                    let start = Instant::now();
                    let outcome = std::panic::catch_unwind(|| (case.run)());
                    let done = (outcome, start.elapsed().as_secs_f64());
                    *slots[i].lock().unwrap_or_else(PoisonError::into_inner) = Some(done);
                }
            });
        }
    });
    slots
        .into_iter()
        .map(|slot| {
            slot.into_inner()
                .unwrap_or_else(PoisonError::into_inner)
                .expect("every case index below the count is taken by a thread")
        })
        .collect()
}

/// What a case's `run` gave: its metrics, an error, or a panic's payload.
type RunOutcome = std::thread::Result<Result<Vec<case::Metric>>>;

/// A case's run, ready to be judged.
struct Judged {
    outcome: RunOutcome,
    /// Wall time of the run, s.
    seconds: f64,
    /// Write new and changed snapshots instead of failing on them.
    update: bool,
}

/// Judges one case's run: its metrics' rows, then its snapshot row.
fn judge_case(case: &Case, judged: Judged, dir: &Path, rows: &mut Vec<Row>, tally: &mut Tally) {
    let Judged {
        outcome,
        seconds,
        update,
    } = judged;
    let wall = format!("{:.1}", seconds * 1e3);
    let first = rows.len();

    match outcome {
        Err(payload) => {
            tally.failed_cases += 1;
            let message = format!("panicked: {}", panic_message(payload.as_ref()));
            rows.push(Row::new(case.name, "(run)", false, message));
        }
        Ok(Err(message)) => {
            tally.failed_cases += 1;
            rows.push(Row::new(
                case.name,
                "(run)",
                false,
                format!("error: {message}"),
            ));
        }
        Ok(Ok(metrics)) => {
            let mut names = BTreeSet::new();
            for metric in &metrics {
                let mut verdict = check::evaluate(metric);
                if !names.insert(metric.name.as_str()) {
                    verdict = check::Verdict {
                        pass: false,
                        note: Some("duplicate metric name in this case".to_owned()),
                    };
                }
                tally.metrics += 1;
                tally.failed_metrics += usize::from(!verdict.pass);
                let mut row = Row::new(
                    case.name,
                    &metric.name,
                    verdict.pass,
                    verdict.note.unwrap_or_default(),
                );
                row.cells[2] = check::number(metric.value, metric.check, metric.reference);
                row.cells[3] = check::number(metric.reference, metric.check, metric.reference);
                row.cells[4] = check::tolerance(metric.check);
                rows.push(row);
            }
            let text = snapshot::text(&metrics);
            let row = match snapshot::compare(case, &text, dir, update) {
                snapshot::Outcome::Matches => Row::new(case.name, "(snapshot)", true, ""),
                snapshot::Outcome::Written(what) => {
                    tally.written_snapshots += 1;
                    Row::new(
                        case.name,
                        "(snapshot)",
                        true,
                        format!("{what}: {}.snap", case.name),
                    )
                }
                snapshot::Outcome::Failed(message) => {
                    tally.failed_snapshots += 1;
                    Row::new(case.name, "(snapshot)", false, message)
                }
            };
            rows.push(row);
        }
    }
    rows[first].cells[6] = wall;
}

/// Files of the snapshot directory that belong to no case: a `.snap` without a case, or any
/// `.snap.new`. With `update`, deletes them; otherwise returns one message per file.
fn stale_files(dir: &Path, cases: &[Case], update: bool) -> Result<Vec<String>> {
    let entries = match std::fs::read_dir(dir) {
        Ok(entries) => entries,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => return Err(format!("cannot list {}: {e}", dir.display())),
    };
    let mut stale = Vec::new();
    for entry in entries {
        let entry = entry.map_err(|e| format!("cannot list {}: {e}", dir.display()))?;
        let name = entry.file_name().to_string_lossy().into_owned();
        let is_stale = if name.ends_with(".snap.new") {
            true
        } else if let Some(stem) = name.strip_suffix(".snap") {
            !cases.iter().any(|c| c.name == stem)
        } else {
            false
        };
        if is_stale {
            stale.push(name);
        }
    }
    stale.sort();
    let mut messages = Vec::new();
    for name in stale {
        let path = dir.join(&name);
        if update {
            std::fs::remove_file(&path)
                .map_err(|e| format!("cannot delete stale {}: {e}", path.display()))?;
            println!("deleted stale {}", path.display());
        } else {
            messages.push(format!(
                "{}: no validation case writes this file; delete it (or run \
                 `cargo xtask validate --update`)",
                path.display()
            ));
        }
    }
    Ok(messages)
}

/// Prints the rows as one aligned table; numbers are right-aligned, the note is not padded.
fn print_table(rows: &[Row]) {
    const HEADER: [&str; 7] = [
        "case",
        "metric",
        "value",
        "reference",
        "tolerance",
        "pass",
        "wall ms",
    ];
    const RIGHT: [bool; 7] = [false, false, true, true, false, false, true];
    let mut widths = HEADER.map(|h| h.chars().count());
    for row in rows {
        for (width, cell) in widths.iter_mut().zip(&row.cells) {
            *width = (*width).max(cell.chars().count());
        }
    }
    let line = |cells: [&str; 7], note: &str| {
        let mut out = String::new();
        for (i, cell) in cells.iter().enumerate() {
            let pad = " ".repeat(widths[i] - cell.chars().count());
            if RIGHT[i] {
                out += &format!("{pad}{cell}  ");
            } else {
                out += &format!("{cell}{pad}  ");
            }
        }
        out += note;
        println!("{}", out.trim_end());
    };
    line(HEADER, "note");
    line(
        widths.map(|w| "-".repeat(w)).each_ref().map(String::as_str),
        "----",
    );
    for row in rows {
        line(row.cells.each_ref().map(String::as_str), &row.note);
    }
}

/// The message of a panic payload (`&str` or `String`, as `panic!` makes them).
pub fn panic_message(payload: &(dyn Any + Send)) -> String {
    if let Some(message) = payload.downcast_ref::<&str>() {
        (*message).to_owned()
    } else if let Some(message) = payload.downcast_ref::<String>() {
        message.clone()
    } else {
        "(no message)".to_owned()
    }
}

#[cfg(test)]
mod tests {
    use super::case::{Check, Metric};
    use super::*;

    /// Runs one case as `run_cases` does (on the parallel runner), then judges it.
    fn run_case(case: &Case, update: bool, dir: &Path, rows: &mut Vec<Row>, tally: &mut Tally) {
        let (outcome, seconds) = run_parallel(&[case]).pop().expect("one case, one outcome");
        let judged = Judged {
            outcome,
            seconds,
            update,
        };
        judge_case(case, judged, dir, rows, tally);
    }

    fn no_metrics() -> std::result::Result<Vec<Metric>, String> {
        Ok(Vec::new())
    }

    fn case(name: &'static str) -> Case {
        Case {
            name,
            description: "test",
            run: Box::new(no_metrics),
        }
    }

    #[test]
    fn registry_rejects_bad_and_duplicate_names() {
        assert!(check_registry(&[case("V1-table-6.1"), case("V2_b")]).is_ok());
        assert!(
            check_registry(&[case("V1"), case("V1")])
                .unwrap_err()
                .contains("two")
        );
        for bad in ["", "a/b", ".hidden", "a b"] {
            assert!(check_registry(&[case(bad)]).is_err(), "{bad:?}");
        }
    }

    #[test]
    fn the_real_registry_is_valid() {
        check_registry(&cases::all()).unwrap();
    }

    #[test]
    fn a_failing_case_fails_its_rows() {
        fn failing() -> std::result::Result<Vec<Metric>, String> {
            Err("mesh is open".to_owned())
        }
        fn bad_metrics() -> std::result::Result<Vec<Metric>, String> {
            Ok(vec![
                Metric::new("a", 1.0, 1.0, Check::Exact),
                Metric::new("b", 1.0, 2.0, Check::Abs(0.5)),
                Metric::new("a", 1.0, 1.0, Check::Exact),
            ])
        }
        let dir = std::env::temp_dir().join("xtask-validate-test-no-snapshots");
        let mut rows = Vec::new();
        let mut tally = Tally::default();
        let failing = Case {
            name: "failing",
            description: "d",
            run: Box::new(failing),
        };
        run_case(&failing, false, &dir, &mut rows, &mut tally);
        assert_eq!((rows.len(), tally.failed_cases), (1, 1));
        assert_eq!(rows[0].note, "error: mesh is open");

        let mut rows = Vec::new();
        let mut tally = Tally::default();
        let bad = Case {
            name: "bad",
            description: "d",
            run: Box::new(bad_metrics),
        };
        run_case(&bad, false, &dir, &mut rows, &mut tally);
        let pass: Vec<&str> = rows.iter().map(|r| r.cells[5].as_str()).collect();
        assert_eq!(pass, ["ok", "FAIL", "FAIL", "FAIL"]);
        assert_eq!(
            (tally.metrics, tally.failed_metrics, tally.failed_snapshots),
            (3, 2, 1)
        );
        assert!(rows[3].note.contains("cargo xtask validate --update"));
        assert!(!rows[0].cells[6].is_empty() && rows[1].cells[6].is_empty());
    }

    #[test]
    fn insta_environment_pins_the_update_mode() {
        let root = Path::new("/ws");
        let get = |update, name| {
            insta_env(update, root)
                .into_iter()
                .find(|(n, _)| *n == name)
                .and_then(|(_, v)| v)
        };
        assert_eq!(get(false, "INSTA_UPDATE"), Some("no".into()));
        assert_eq!(get(true, "INSTA_UPDATE"), Some("always".into()));
        assert_eq!(get(true, "INSTA_FORCE_PASS"), Some("0".into()));
        assert_eq!(get(true, "INSTA_FORCE_UPDATE"), None);
    }
}
