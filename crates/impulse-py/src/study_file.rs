//! What the pose and bowling bindings share about a study file: its text as the CLI writes it,
//! the merge of shard texts by the library's merge, and a shard run under the CLI's journal
//! (`impulse_sim::batch::Journal`), so that a stopped or killed shard is resumed.
//!
//! Must not know: which study a file holds (the reader, the merge, the runs and the outcomes'
//! indices come from the caller).

use std::path::Path;
use std::time::Instant;

use impulse_sim::batch::{Journal, RunHooks, Shard};
use serde::Serialize;
use serde::de::DeserializeOwned;

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

/// A study's shard as [`run_kept`] runs it.
pub(crate) struct Kept<'a> {
    /// The CLI command whose journal this is (`"impulse poses"`): in the journal's header, so
    /// that the CLI and the package resume each other's shards.
    pub(crate) command: &'static str,
    /// The runs, in messages (`"drops"`).
    pub(crate) runs: &'static str,
    pub(crate) shard: Shard,
    /// Runs of the whole study (every shard).
    pub(crate) total: u64,
    /// The shard's file; `None`: nothing is kept.
    pub(crate) out: Option<&'a Path>,
    /// No run starts after this many seconds of wall-clock time (checked positive).
    pub(crate) max_wall: Option<f64>,
}

/// How [`run_kept`] reaches a study file's outcomes and an outcome's index.
pub(crate) struct Outcomes<F, T> {
    pub(crate) of: fn(&mut F) -> &mut Vec<T>,
    pub(crate) index: fn(&T) -> u64,
}

/// Runs the shard `study` of `file` (a study file without outcomes) and returns the file with
/// the shard's outcomes in index order. With `out`, as the CLI's `--out OUT`: the runs its
/// journal `OUT.partial` holds are read back and not run again, each run is recorded there as
/// it finishes, none starts once `max_wall` has passed, and when the shard is whole `out` is
/// written and the journal removed. And, for a study re-run after it was killed (a Dask task
/// run again), an `out` that already holds this shard's whole file (the same study, shard and
/// runs) with no journal beside it is returned as it is, without running anything.
///
/// # Errors
/// A stop before the end (naming how many runs were kept, and where), the journal's errors,
/// `run`'s.
pub(crate) fn run_kept<F, T>(
    study: &Kept<'_>,
    mut file: F,
    outcomes: &Outcomes<F, T>,
    run: impl FnOnce(&RunHooks<'_, T>) -> Result<Vec<(u64, T)>, String>,
) -> Result<F, String>
where
    F: Serialize + DeserializeOwned,
    T: Serialize + DeserializeOwned + Send,
{
    let mine = study.shard.runs_of(study.total);
    let journal = match study.out {
        Some(out) => {
            let header = serde_json::to_value(&file).map_err(|e| e.to_string())?;
            if let Some(done) = finished(out, &header, study, outcomes) {
                return Ok(done);
            }
            let header = Journal::header(study.command, study.shard, &header)?;
            Some(Journal::open::<T>(out, &header)?)
        }
        None => None,
    };
    let (journal, mut kept) = match journal {
        Some((j, before)) => (Some(j), before),
        None => (None, Vec::new()),
    };
    let index = outcomes.index;
    kept.sort_by_key(index);
    kept.dedup_by_key(|t| index(t));
    let before: Vec<u64> = kept.iter().map(index).collect();
    let wall = Instant::now();
    let record = |_: u64, t: &T| {
        if let Some(j) = &journal {
            j.record(t);
        }
    };
    let hooks = RunHooks {
        progress: &|_| {},
        skip: &|i| before.binary_search(&i).is_ok(),
        stop: &|| {
            study
                .max_wall
                .is_some_and(|w| wall.elapsed().as_secs_f64() >= w)
        },
        record: &record,
    };
    let now = run(&hooks)?;
    if let Some(j) = &journal {
        j.check()?;
    }
    kept.extend(now.into_iter().map(|(_, t)| t));
    kept.sort_by_key(index);
    let done = kept.len() as u64;
    *(outcomes.of)(&mut file) = kept;
    if done < mine {
        let where_ = match study.out {
            Some(out) => format!(
                "they are kept in {}: the same call runs the other {} and writes {}",
                Journal::path_for(out).display(),
                mine - done,
                out.display()
            ),
            None => "without `out` they are not kept".to_owned(),
        };
        return Err(format!(
            "stopped at the wall-time limit (max_wall), after {done} of {mine} {}; {where_}",
            study.runs
        ));
    }
    if let Some(j) = journal {
        j.finish(&file)?;
    }
    Ok(file)
}

/// The shard's whole file at `out`, if `out` holds one of the study `header` (the file
/// without outcomes, as JSON) with exactly the shard's runs and no journal is beside it.
fn finished<F, T>(
    out: &Path,
    header: &serde_json::Value,
    study: &Kept<'_>,
    o: &Outcomes<F, T>,
) -> Option<F>
where
    F: Serialize + DeserializeOwned,
{
    if Journal::path_for(out).exists() {
        return None;
    }
    let text = std::fs::read_to_string(out).ok()?;
    let mut file: F = serde_json::from_str(&text).ok()?;
    let runs = std::mem::take((o.of)(&mut file));
    if serde_json::to_value(&file).ok()? != *header {
        return None;
    }
    let mut expected = (study.shard.index..study.total).step_by(study.shard.count as usize);
    let whole =
        runs.iter().all(|t| expected.next() == Some((o.index)(t))) && expected.next().is_none();
    *(o.of)(&mut file) = runs;
    whole.then_some(file)
}
