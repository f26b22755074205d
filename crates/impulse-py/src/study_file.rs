//! What the pose and bowling bindings share about a study file: its text as the CLI writes it,
//! and the merge of shard texts by the library's merge.
//!
//! Must not know: which study a file holds (the reader and the merge come from the caller).

use serde::Serialize;

/// The text of a study file, as the CLI writes it: pretty JSON and a final newline.
pub(crate) use impulse_sim::batch::study_text;

/// Reads every shard text with `read` (given the text and its index, for the error), merges
/// the files with `merge`, and returns the merged file's text.
pub(crate) fn merge_texts<T: Serialize, E: std::fmt::Display>(
    studies: &[String],
    read: impl Fn(&str, usize) -> Result<T, String>,
    merge: impl FnOnce(&[T]) -> Result<T, E>,
) -> Result<String, String> {
    let files = studies
        .iter()
        .enumerate()
        .map(|(k, t)| read(t, k))
        .collect::<Result<Vec<_>, _>>()?;
    study_text(&merge(&files).map_err(|e| e.to_string())?)
}
