//! A study's journal (`OUT.partial`): the runs of a study finished so far, kept as they finish,
//! so that a study stopped (Ctrl-C, a wall-time limit, a kill) and run again does only the
//! runs it had not done — the same file whether `impulse poses` / `impulse bowling` or the
//! Python package runs the study, so either can finish what the other started. And the text of
//! a study's file: pretty JSON with a final newline, what the CLI writes and the Python
//! package returns.

use std::path::{Path, PathBuf};
use std::sync::{Mutex, PoisonError};

use serde::Serialize;
use serde::de::DeserializeOwned;

use super::Shard;

/// The text of a study file: pretty JSON and a final newline.
///
/// # Errors
/// A value that does not serialise (not expected for the study files).
pub fn study_text<T: Serialize>(file: &T) -> Result<String, String> {
    serde_json::to_string_pretty(file)
        .map(|t| t + "\n")
        .map_err(|e| e.to_string())
}

/// A study's journal, `OUT.partial` beside the study's file `OUT`: JSON lines, a header naming the
/// study, then one outcome per finished run, each line written whole as its run finishes. A
/// study stopped by Ctrl-C, a wall-time limit or a kill keeps every run it finished; run again
/// with the same arguments, it reads them back and runs only the others. The journal is
/// removed once the study's file is written.
pub struct Journal {
    /// The study's file, written when the study is whole ([`Journal::finish`]).
    out: PathBuf,
    path: PathBuf,
    file: Mutex<std::fs::File>,
    /// The first error of a write, reported by [`Journal::check`].
    error: Mutex<Option<String>>,
}

impl Journal {
    /// The header line of the journal of `shard` of the study `study` (its file without
    /// outcomes, as JSON) run by `command` (`"impulse bowling"`): the line a journal must
    /// start with for [`Journal::open`] to take its runs.
    ///
    /// # Errors
    /// A study that does not serialise (not expected).
    pub fn header(
        command: &str,
        shard: Shard,
        study: &serde_json::Value,
    ) -> Result<String, String> {
        serde_json::to_string(&serde_json::json!({
            "journal": command,
            "shard": [shard.index, shard.count],
            "study": study,
        }))
        .map_err(|e| e.to_string())
    }

    /// The journal of the study whose file is `out`.
    pub fn path_for(out: &Path) -> PathBuf {
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
    pub fn open<T: DeserializeOwned>(
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
                         run count or shard): remove it to start this one afresh, or write the \
                         study to another file"
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
                file: Mutex::new(file),
                error: Mutex::new(None),
            },
            outcomes,
        ))
    }

    /// Appends one finished run's outcome, as one line written at once.
    pub fn record<T: Serialize>(&self, outcome: &T) {
        use std::io::Write;
        let line = match serde_json::to_string(outcome) {
            Ok(text) => text + "\n",
            Err(e) => return self.fail(e.to_string()),
        };
        let mut file = self.file.lock().unwrap_or_else(PoisonError::into_inner);
        if let Err(e) = file.write_all(line.as_bytes()) {
            self.fail(format!("cannot write {}: {e}", self.path.display()));
        }
    }

    fn fail(&self, message: String) {
        let mut error = self.error.lock().unwrap_or_else(PoisonError::into_inner);
        error.get_or_insert(message);
    }

    /// The first write that failed, if any.
    pub fn check(&self) -> Result<(), String> {
        match &*self.error.lock().unwrap_or_else(PoisonError::into_inner) {
            Some(e) => Err(e.clone()),
            None => Ok(()),
        }
    }

    /// Writes the whole study's `file` ([`study_text`]) to the study's path and removes the
    /// journal.
    pub fn finish<F: Serialize>(self, file: &F) -> Result<(), String> {
        let text = study_text(file)?;
        std::fs::write(&self.out, text)
            .map_err(|e| format!("cannot write {}: {e}", self.out.display()))?;
        drop(self.file);
        std::fs::remove_file(&self.path)
            .map_err(|e| format!("cannot remove {}: {e}", self.path.display()))
    }
}
