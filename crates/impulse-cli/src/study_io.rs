//! What the study commands (`impulse poses`, `impulse bowling`) share: the `--shard K/N`
//! argument, and their outcome files as JSON.

use std::path::Path;

use impulse_sim::batch::{Journal, RunHooks, Shard, study_text};
use serde::Serialize;
use serde::de::DeserializeOwned;

use crate::progress::Progress;

/// The shard of `--shard K/N`, or the whole study without it.
pub(crate) fn shard_arg(arg: Option<&str>) -> Result<Shard, String> {
    match arg {
        Some(s) => s.parse::<Shard>().map_err(|e| format!("--shard: {e}")),
        None => Ok(Shard::ALL),
    }
}

/// A study file read back: `what` names it in the error of a file that is not one
/// ("pose study").
pub(crate) fn read_json<T: DeserializeOwned>(path: &Path, what: &str) -> Result<T, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    serde_json::from_str(&text).map_err(|e| format!("{}: not a {what} file: {e}", path.display()))
}

/// A study file written as pretty JSON with a final newline ([`study_text`]).
pub(crate) fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<(), String> {
    let text = study_text(value)?;
    std::fs::write(path, text).map_err(|e| format!("cannot write {}: {e}", path.display()))
}

/// A study's runs done under a journal ([`run_journaled`]).
pub(crate) struct Journaled<T> {
    /// Every run done, read back or run now, in index order.
    pub(crate) outcomes: Vec<T>,
    /// Whether the shard's runs are all done.
    pub(crate) complete: bool,
    /// What the report says of runs read back from the journal, if any.
    pub(crate) resumed: Option<String>,
    /// What the report says of a stop before the end, if any.
    pub(crate) stopped: Option<String>,
    /// The journal, to finish ([`Journal::finish`]) when the shard's runs are all done.
    pub(crate) journal: Option<Journal>,
}

/// What a study command asks of [`run_journaled`].
pub(crate) struct StudyRun<'a> {
    /// The command, in the journal's header and the progress line: `"impulse poses"`.
    pub(crate) command: &'static str,
    /// Its runs, in messages: `"drops"`.
    pub(crate) runs: &'static str,
    /// The study's file without outcomes: with the shard, the journal's header.
    pub(crate) header: serde_json::Value,
    pub(crate) shard: Shard,
    /// The shard's runs.
    pub(crate) mine: u64,
    /// The study's `--out` file, if any.
    pub(crate) out: Option<&'a Path>,
    /// `--max-wall`, checked positive.
    pub(crate) max_wall: Option<f64>,
}

/// Runs a study's shard under its journal ([`Journal`]) when it has an `--out` file: the runs
/// done before are read back and skipped, each finished run is recorded as it finishes, and
/// no run starts after Ctrl-C or the wall-time limit. `run` does the runs with the hooks it is
/// given; `index` reads a run's index.
///
/// # Errors
/// A bad `--max-wall`, the journal's errors, `run`'s.
pub(crate) fn run_journaled<T: Serialize + DeserializeOwned + Send>(
    study: &StudyRun<'_>,
    index: fn(&T) -> u64,
    run: impl FnOnce(&RunHooks<'_, T>) -> Result<Vec<(u64, T)>, String>,
) -> Result<Journaled<T>, String> {
    if let Some(w) = study.max_wall
        && !(w.is_finite() && w > 0.0)
    {
        return Err(format!(
            "--max-wall {w}: must be a positive number of seconds"
        ));
    }
    let journal = match study.out {
        Some(out) => {
            let header = Journal::header(study.command, study.shard, &study.header)?;
            Some(Journal::open::<T>(out, &header)?)
        }
        None => None,
    };
    let (journal, mut outcomes) = match journal {
        Some((j, before)) => (Some(j), before),
        None => (None, Vec::new()),
    };
    outcomes.sort_by_key(index);
    outcomes.dedup_by_key(|t| index(t));
    let resumed = outcomes.len() as u64;
    let before: Vec<u64> = outcomes.iter().map(index).collect();
    let bar = Progress::count(study.command, study.mine, study.runs);
    let progress = |done: u64| bar.set(resumed + done);
    crate::interrupt::install();
    let wall = std::time::Instant::now();
    let stop = || {
        crate::interrupt::requested()
            || study
                .max_wall
                .is_some_and(|w| wall.elapsed().as_secs_f64() >= w)
    };
    let record = |_: u64, t: &T| {
        if let Some(j) = &journal {
            j.record(t);
        }
    };
    let hooks = RunHooks {
        progress: &progress,
        skip: &|i| before.binary_search(&i).is_ok(),
        stop: &stop,
        record: &record,
    };
    let now = run(&hooks)?;
    bar.finish();
    if let Some(j) = &journal {
        j.check()?;
    }
    outcomes.extend(now.into_iter().map(|(_, t)| t));
    outcomes.sort_by_key(index);
    let done = outcomes.len() as u64;
    let complete = done == study.mine;
    let runs = study.runs;
    let stopped = (!complete).then(|| {
        let why = if crate::interrupt::requested() {
            "interrupted (Ctrl-C or SIGTERM)"
        } else {
            "at the wall-time limit (--max-wall)"
        };
        let kept = match study.out {
            Some(out) => format!(
                "they are kept in {}: the same command runs the other {} and writes {}",
                Journal::path_for(out).display(),
                study.mine - done,
                out.display()
            ),
            None => "without --out they are not kept".to_owned(),
        };
        format!(
            "stopped:          {why}, after {done} of {} {runs}; {kept}",
            study.mine
        )
    });
    let resumed = (resumed > 0).then(|| {
        format!(
            "resumed:          {resumed} {runs} read back from {}, {} run now",
            study
                .out
                .map(Journal::path_for)
                .unwrap_or_default()
                .display(),
            done - resumed
        )
    });
    Ok(Journaled {
        outcomes,
        complete,
        resumed,
        stopped,
        journal,
    })
}
