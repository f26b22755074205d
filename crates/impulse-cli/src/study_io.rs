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
