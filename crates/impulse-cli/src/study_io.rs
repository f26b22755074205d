//! What the study commands (`impulse poses`, `impulse bowling`) share: the `--shard K/N`
//! argument, and their outcome files as JSON.

use std::path::Path;

use impulse_sim::batch::Shard;
use serde::Serialize;
use serde::de::DeserializeOwned;

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
        let file = if path.exists() {
            let text = std::fs::read(&path).map_err(|e| format!("cannot read {shown}: {e}"))?;
            let mut good = 0;
            let mut lines = text.split_inclusive(|&b| b == b'\n').peekable();
            let first = lines.next().unwrap_or_default();
            if first.strip_suffix(b"\n") != Some(header.as_bytes()) {
                return Err(format!(
                    "{shown} holds the runs of another study (another part, settings, seed, \
                     run count or shard): remove it to start this one afresh, or give \
                     another --out"
                ));
            }
            good += first.len();
            let mut n = 1;
            while let Some(line) = lines.next() {
                n += 1;
                let whole = line.ends_with(b"\n");
                match serde_json::from_slice::<T>(line) {
                    Ok(t) if whole => {
                        outcomes.push(t);
                        good += line.len();
                    }
                    _ if lines.peek().is_none() => break,
                    Err(e) => return Err(format!("{shown}: line {n} does not read: {e}")),
                    Ok(_) => unreachable!("only the last line can lack its newline"),
                }
            }
            let file = std::fs::OpenOptions::new()
                .write(true)
                .open(&path)
                .map_err(|e| format!("cannot open {shown}: {e}"))?;
            file.set_len(good as u64)
                .map_err(|e| format!("cannot trim {shown}: {e}"))?;
            let mut file = file;
            std::io::Seek::seek(&mut file, std::io::SeekFrom::End(0))
                .map_err(|e| format!("cannot open {shown}: {e}"))?;
            file
        } else {
            let mut file =
                std::fs::File::create(&path).map_err(|e| format!("cannot create {shown}: {e}"))?;
            writeln!(file, "{header}").map_err(|e| format!("cannot write {shown}: {e}"))?;
            file
        };
        Ok((
            Journal {
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

    /// Removes the journal (its study's file is written).
    pub(crate) fn remove(self) -> Result<(), String> {
        drop(self.file);
        std::fs::remove_file(&self.path)
            .map_err(|e| format!("cannot remove {}: {e}", self.path.display()))
    }
}
