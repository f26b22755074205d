//! Batches of independent runs (the drops of a pose study, the throws of a bowling study):
//! shards for a batch scheduler, a random stream per run that depends only on (seed, run
//! index), and running a shard's runs on a thread pool. Whatever the thread count and the
//! shard split, run i sees the same random numbers, so merged shards equal one run bit for
//! bit. A study's journal ([`Journal`]) keeps the runs finished so far, for a stopped study to
//! be finished later by whichever front end (the CLI, Python) runs it again.

use std::str::FromStr;
use std::sync::atomic::{AtomicU64, Ordering};

use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;
use rayon::prelude::*;

use crate::SimError;

mod journal;
pub use journal::{Journal, study_text};

/// SplitMix64's increment (the golden ratio in 64 bits), to mix a seed with a run index.
const GOLDEN_GAMMA: u64 = 0x9E37_79B9_7F4A_7C15;

/// One shard of a study: runs `index`, `index + count`, `index + 2·count`, …
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// This shard, 0 ≤ index < count.
    pub index: u64,
    /// Number of shards, ≥ 1.
    pub count: u64,
}

impl Shard {
    /// The whole study in one shard.
    pub const ALL: Shard = Shard { index: 0, count: 1 };

    /// Whether run `i` is this shard's.
    pub fn owns(&self, i: u64) -> bool {
        i % self.count == self.index
    }

    /// How many of a study's `runs` runs are this shard's.
    pub fn runs_of(&self, runs: u64) -> u64 {
        if self.index >= runs {
            0
        } else {
            (runs - self.index).div_ceil(self.count)
        }
    }
}

impl FromStr for Shard {
    type Err = String;

    /// Parses `K/N` with 0 ≤ K < N.
    fn from_str(s: &str) -> Result<Self, String> {
        let (k, n) = s
            .split_once('/')
            .ok_or_else(|| format!("shard `{s}`: expected K/N, e.g. 0/4"))?;
        let parse = |x: &str, what: &str| {
            x.trim()
                .parse::<u64>()
                .map_err(|e| format!("shard `{s}`: {what} `{x}`: {e}"))
        };
        let (index, count) = (parse(k, "K")?, parse(n, "N")?);
        if count == 0 || index >= count {
            return Err(format!(
                "shard `{s}`: need 0 ≤ K < N (the shards of N are 0/N … {}/N)",
                count.max(1) - 1
            ));
        }
        Ok(Shard { index, count })
    }
}

/// SplitMix64's output function: a well-mixed 64-bit value from `x`.
fn mix(mut x: u64) -> u64 {
    x = x.wrapping_add(GOLDEN_GAMMA);
    x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    x ^ (x >> 31)
}

/// The random stream of run `index` of a study seeded with `seed`.
pub(crate) fn stream(seed: u64, index: u64) -> Xoshiro256PlusPlus {
    Xoshiro256PlusPlus::seed_from_u64(mix(seed) ^ mix(index.wrapping_add(GOLDEN_GAMMA)))
}

/// What a caller follows and steers of a shard's runs ([`crate::poses::run_drops_with`],
/// [`crate::bowling::run_throws_with`]): a study that is
/// stopped (Ctrl-C, a wall-time limit) and run again does only the runs it had not done.
pub struct RunHooks<'a, T> {
    /// Called with the number of runs done (this call's) after each.
    pub progress: &'a (dyn Fn(u64) + Sync),
    /// Whether run `i` was done before (its outcome is kept elsewhere): it is not run.
    pub skip: &'a (dyn Fn(u64) -> bool + Sync),
    /// Whether to stop: once it says so, no further run starts (the runs under way finish).
    pub stop: &'a (dyn Fn() -> bool + Sync),
    /// Called with each run's index and outcome as it finishes (in no particular order): to
    /// record it where a later call finds it.
    pub record: &'a (dyn Fn(u64, &T) + Sync),
}

impl<T> RunHooks<'_, T> {
    /// No skipping, no stopping, no recording.
    pub fn none(progress: &(dyn Fn(u64) + Sync)) -> RunHooks<'_, T> {
        RunHooks {
            progress,
            skip: &|_| false,
            stop: &|| false,
            record: &|_, _| {},
        }
    }
}

/// Runs `run(i)` for the runs `i` of `shard` of a study of `runs` runs on a pool of
/// `threads` worker threads, calling `progress` with the number done after each. Returns
/// the results in index order; an error names the run (`what` and its index).
///
/// # Errors
/// [`SimError::Invalid`] for zero threads or more than [`crate::threads::max_threads`]; the first
/// failing run's error.
#[cfg(test)]
pub(crate) fn run_shard<T: Send>(
    what: &str,
    runs: u64,
    shard: Shard,
    threads: usize,
    progress: &(dyn Fn(u64) + Sync),
    run: impl Fn(u64) -> Result<T, SimError> + Sync,
) -> Result<Vec<T>, SimError> {
    let done = run_shard_with(what, runs, shard, threads, &RunHooks::none(progress), run)?;
    Ok(done.into_iter().map(|(_, t)| t).collect())
}

/// Runs `run(i)` for the runs `i` of `shard` of a study of `runs` runs on a pool of
/// `threads` worker threads, steered by `hooks`: the runs it skips are not run, none starts
/// once it is asked to stop; returns the runs done, (index, outcome) in index order; an error
/// names the run (`what` and its index).
///
/// # Errors
/// [`SimError::Invalid`] for zero threads or more than [`crate::threads::max_threads`]; the first
/// failing run's error.
pub(crate) fn run_shard_with<T: Send>(
    what: &str,
    runs: u64,
    shard: Shard,
    threads: usize,
    hooks: &RunHooks<'_, T>,
    run: impl Fn(u64) -> Result<T, SimError> + Sync,
) -> Result<Vec<(u64, T)>, SimError> {
    let pool = crate::threads::pool(threads, "study")?;
    let done = AtomicU64::new(0);
    let outcomes: Result<Vec<Option<(u64, T)>>, SimError> = pool.install(|| {
        (0..shard.runs_of(runs))
            .into_par_iter()
            .map(|j| shard.index + j * shard.count)
            .map(|i| {
                if (hooks.skip)(i) || (hooks.stop)() {
                    return Ok(None);
                }
                let out = run(i).map_err(|e| SimError::Runtime {
                    time: 0.0,
                    message: format!("{what} {i}: {e}"),
                })?;
                (hooks.record)(i, &out);
                (hooks.progress)(done.fetch_add(1, Ordering::Relaxed) + 1);
                Ok(Some((i, out)))
            })
            .collect()
    });
    Ok(outcomes?.into_iter().flatten().collect())
}

/// A study's file as [`merge`] sees it: a header that shard files of one study share, and
/// outcomes indexed by run.
pub(crate) trait StudyFile: Clone {
    /// One run's outcome.
    type Run: Clone;
    /// The files, in error messages: `"pose study files"`.
    const FILES: &'static str;
    /// One run, in error messages: `"drop"`.
    const RUN: &'static str;
    /// What the header holds, in error messages.
    const HEADER: &'static str;
    /// Whether `other` is a file of the same study (equal headers).
    fn same_study(&self, other: &Self) -> bool;
    /// Checks the header of a file read back.
    fn check_header(&self) -> Result<(), SimError> {
        Ok(())
    }
    /// Runs of the whole study.
    fn runs(&self) -> u64;
    /// This file's outcomes.
    fn outcomes(&self) -> &[Self::Run];
    /// A run's index in the study.
    fn index(run: &Self::Run) -> u64;
    /// This file's header with `outcomes`.
    fn with_outcomes(&self, outcomes: Vec<Self::Run>) -> Self;
}

/// Merges shard files of one study into the file of the whole study, outcomes in index
/// order.
///
/// # Errors
/// [`SimError::Invalid`] when there are no files, the files are of different studies, a run
/// is beyond the study or in two files.
pub(crate) fn merge<F: StudyFile>(files: &[F]) -> Result<F, SimError> {
    let bad = |problem: String| SimError::Invalid {
        what: F::FILES.into(),
        field: "merge".into(),
        problem,
    };
    let first = files
        .first()
        .ok_or_else(|| bad("no files to merge".into()))?;
    if let Some(k) = files.iter().position(|f| !f.same_study(first)) {
        return Err(bad(format!(
            "file {k} is of another study ({} differ from file 0)",
            F::HEADER
        )));
    }
    first.check_header()?;
    let (runs, run) = (first.runs(), F::RUN);
    let mut all: Vec<F::Run> = files.iter().flat_map(|f| f.outcomes()).cloned().collect();
    if let Some(o) = all.iter().find(|o| F::index(o) >= runs) {
        return Err(bad(format!(
            "{run} {} is beyond the study's {runs} {run}s",
            F::index(o)
        )));
    }
    all.sort_by_key(F::index);
    if let Some(w) = all.windows(2).find(|w| F::index(&w[0]) == F::index(&w[1])) {
        return Err(bad(format!("{run} {} is in two files", F::index(&w[0]))));
    }
    Ok(first.with_outcomes(all))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_partition_the_runs() {
        // Brute force: every run of a study is in exactly one shard, and the counts agree.
        for runs in [0u64, 1, 7, 20] {
            for count in 1..6u64 {
                let mut seen = vec![0; runs as usize];
                for index in 0..count {
                    let s = Shard { index, count };
                    let mine: Vec<u64> = (0..runs).filter(|&i| s.owns(i)).collect();
                    assert_eq!(mine.len() as u64, s.runs_of(runs));
                    for i in mine {
                        seen[i as usize] += 1;
                    }
                }
                assert!(seen.iter().all(|&c| c == 1), "{runs} runs, {count} shards");
            }
        }
    }

    #[test]
    fn results_do_not_depend_on_threads_or_shards() {
        use rand::RngExt;
        let one = |i: u64| Ok(stream(7, i).random::<u64>());
        let all = run_shard("run", 9, Shard::ALL, 1, &|_| {}, one).unwrap();
        let two = run_shard("run", 9, Shard::ALL, 2, &|_| {}, one).unwrap();
        assert_eq!(all, two);
        let mut merged: Vec<(u64, u64)> = (0..3)
            .flat_map(|index| {
                let s = Shard { index, count: 3 };
                let r = run_shard("run", 9, s, 2, &|_| {}, one).unwrap();
                (0..9).filter(move |&i| s.owns(i)).zip(r)
            })
            .collect();
        merged.sort();
        assert_eq!(merged.into_iter().map(|(_, v)| v).collect::<Vec<_>>(), all);
        // Distinct runs get distinct streams.
        assert_ne!(all[0], all[1]);
        assert!(run_shard("run", 9, Shard::ALL, 0, &|_| {}, one).is_err());
    }
}
