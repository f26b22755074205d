//! What the study commands (`impulse poses`, `impulse bowling`) share: the `--shard K/N`
//! argument, and their outcome files as JSON.

use std::path::Path;

use impulse_sim::batch::{RunHooks, Shard};
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

/// A study file written as pretty JSON with a final newline.
pub(crate) fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<(), String> {
    let text = serde_json::to_string_pretty(value).map_err(|e| e.to_string())?;
    std::fs::write(path, text + "\n").map_err(|e| format!("cannot write {}: {e}", path.display()))
}

/// A study's journal, `OUT.partial` beside its `--out` file: JSON lines, a header naming the
/// study, then one outcome per finished run, each line written whole as its run finishes. A
/// study stopped by Ctrl-C, a wall-time limit or a kill keeps every run it finished; run again
/// with the same arguments, it reads them back and runs only the others. The journal is
/// removed once the study's file is written.
pub(crate) struct Journal {
    /// The study's file, written when the study is whole ([`Journal::finish`]).
    out: std::path::PathBuf,
    path: std::path::PathBuf,
    file: std::sync::Mutex<std::fs::File>,
    /// The first error of a write, reported by [`Journal::check`].
    error: std::sync::Mutex<Option<String>>,
}

impl Journal {
    /// The journal of the study whose file is `out`.
    pub(crate) fn path_for(out: &Path) -> std::path::PathBuf {
        let mut name = out.as_os_str().to_owned();
        name.push(".partial");
        name.into()
    }

    /// Opens the journal of `out` for the study `header` (one line of JSON), creating it, and
    /// returns the outcomes it holds. A last line cut short by a kill is dropped.
    ///
    /// # Errors
    /// A journal of another study (its header differs), an outcome that does not read, or
    /// the file system's error, each naming the file.
    pub(crate) fn open<T: DeserializeOwned>(
        out: &Path,
        header: &str,
    ) -> Result<(Journal, Vec<T>), String> {
        use std::io::Write;
        let path = Self::path_for(out);
        let shown = path.display();
        let mut outcomes = Vec::new();
        let existing = match std::fs::read(&path) {
            Ok(text) => Some(text),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => None,
            Err(e) => return Err(format!("cannot read {shown}: {e}")),
        };
        // A journal whose header was cut short (killed as it was created) holds nothing.
        let file = match existing.filter(|text| text.contains(&b'\n')) {
            Some(text) => {
                let mut lines = text.split_inclusive(|&b| b == b'\n').peekable();
                let first = lines.next().unwrap_or_default();
                if first.strip_suffix(b"\n") != Some(header.as_bytes()) {
                    return Err(format!(
                        "{shown} holds the runs of another study (another part, settings, seed, \
                         run count or shard): remove it to start this one afresh, or give \
                         another --out"
                    ));
                }
                // The bytes up to the last whole outcome: a last line cut short by a kill
                // (no newline, or not JSON) is dropped.
                let mut good = first.len();
                let mut n = 1;
                while let Some(line) = lines.next() {
                    n += 1;
                    let last = lines.peek().is_none();
                    match serde_json::from_slice::<T>(line) {
                        Ok(t) if line.ends_with(b"\n") => {
                            outcomes.push(t);
                            good += line.len();
                        }
                        _ if last => break,
                        Err(e) => return Err(format!("{shown}: line {n} does not read: {e}")),
                        Ok(_) => return Err(format!("{shown}: line {n} does not end")),
                    }
                }
                let mut file = std::fs::OpenOptions::new()
                    .write(true)
                    .open(&path)
                    .map_err(|e| format!("cannot open {shown}: {e}"))?;
                file.set_len(good as u64)
                    .and_then(|()| std::io::Seek::seek(&mut file, std::io::SeekFrom::End(0)))
                    .map_err(|e| format!("cannot trim {shown}: {e}"))?;
                file
            }
            None => {
                let mut file = std::fs::File::create(&path)
                    .map_err(|e| format!("cannot create {shown}: {e}"))?;
                writeln!(file, "{header}").map_err(|e| format!("cannot write {shown}: {e}"))?;
                file
            }
        };
        Ok((
            Journal {
                out: out.to_path_buf(),
                path,
                file: std::sync::Mutex::new(file),
                error: std::sync::Mutex::new(None),
            },
            outcomes,
        ))
    }

    /// Appends one finished run's outcome, as one line written at once.
    pub(crate) fn record<T: Serialize>(&self, outcome: &T) {
        use std::io::Write;
        let line = match serde_json::to_string(outcome) {
            Ok(text) => text + "\n",
            Err(e) => return self.fail(e.to_string()),
        };
        let mut file = self
            .file
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        if let Err(e) = file.write_all(line.as_bytes()) {
            self.fail(format!("cannot write {}: {e}", self.path.display()));
        }
    }

    fn fail(&self, message: String) {
        let mut error = self
            .error
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        error.get_or_insert(message);
    }

    /// The first write that failed, if any.
    pub(crate) fn check(&self) -> Result<(), String> {
        match &*self
            .error
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
        {
            Some(e) => Err(e.clone()),
            None => Ok(()),
        }
    }

    /// Writes the whole study's `file` to its `--out` path and removes the journal.
    pub(crate) fn finish<F: Serialize>(self, file: &F) -> Result<(), String> {
        write_json(&self.out, file)?;
        drop(self.file);
        std::fs::remove_file(&self.path)
            .map_err(|e| format!("cannot remove {}: {e}", self.path.display()))
    }
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
            let header = serde_json::to_string(&serde_json::json!({
                "journal": study.command,
                "shard": [study.shard.index, study.shard.count],
                "study": study.header,
            }))
            .map_err(|e| e.to_string())?;
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
