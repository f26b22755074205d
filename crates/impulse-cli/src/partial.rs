//! An output file written as a run goes: into `FILE.partial` beside it, renamed to `FILE`
//! (after an fsync) only when the run ends well, so that a failed or killed run never leaves
//! half a file under the user's name (`--events`, `--joints`).

use std::io::Write;
use std::path::{Path, PathBuf};

/// `FILE.partial` being written, to be renamed `FILE`.
pub struct PartialFile {
    file: std::io::BufWriter<std::fs::File>,
    partial: PathBuf,
    out: PathBuf,
}

impl PartialFile {
    /// Creates `out`'s temporary file and writes `head` (the format's header); `flag` names
    /// the option in errors.
    pub fn create(flag: &str, out: &Path, head: &str) -> Result<Self, String> {
        let mut name = out.file_name().unwrap_or_default().to_os_string();
        name.push(".partial");
        let partial = out.with_file_name(name);
        let cannot = |e: std::io::Error| format!("{flag}: cannot write {}: {e}", partial.display());
        let mut file = std::io::BufWriter::new(std::fs::File::create(&partial).map_err(cannot)?);
        file.write_all(head.as_bytes()).map_err(cannot)?;
        Ok(Self {
            file,
            partial,
            out: out.to_path_buf(),
        })
    }

    /// The writer.
    pub fn writer(&mut self) -> &mut impl Write {
        &mut self.file
    }

    /// The temporary file's path (for error messages).
    pub fn partial(&self) -> &Path {
        &self.partial
    }

    /// Writes `tail` (what closes the format: a JSON array's bracket), flushes, syncs and
    /// gives the file its name.
    pub fn finish(mut self, tail: &[u8]) -> Result<(), String> {
        let cannot = |e: std::io::Error| format!("cannot write {}: {e}", self.out.display());
        self.file.write_all(tail).map_err(cannot)?;
        let file = self.file.into_inner().map_err(|e| cannot(e.into_error()))?;
        file.sync_all().map_err(cannot)?;
        std::fs::rename(&self.partial, &self.out).map_err(cannot)
    }

    /// Removes the temporary file of a run that failed.
    pub fn abandon(self) {
        let _ = std::fs::remove_file(&self.partial);
    }
}

/// Whether `out` names a JSON file (else CSV); refuses any other ending, naming `flag`.
pub fn is_json(flag: &str, out: &Path) -> Result<bool, String> {
    match out.extension().and_then(|e| e.to_str()) {
        Some("csv") => Ok(false),
        Some("json") => Ok(true),
        _ => Err(format!(
            "{flag} {}: the file name must end in .csv or .json",
            out.display()
        )),
    }
}
