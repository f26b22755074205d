//! The thread pools of a world's per-body work and of a study's runs, and the most threads
//! either may ask for.
//!
//! A pool of more threads than the machine has cores only makes its threads wait for one
//! another, and a very large count is a mistake that would otherwise hang while the threads
//! are started (100 000 asked on a 2-core machine did not return within 20 s). Past
//! [`max_threads`] the count is refused before any thread starts.

use crate::error::SimError;

/// Threads a pool may have per core of this machine, at most. Default `4`: more than the
/// per-body work or a study can use, room for a machine whose cores the count it reports
/// understates (hyper-threads, a container's quota).
pub const MAX_THREADS_PER_CORE: usize = 4;

/// The most threads a pool may have on this machine: [`MAX_THREADS_PER_CORE`] times its
/// cores (as `std::thread::available_parallelism` reports them, 1 if it cannot tell).
#[must_use]
pub fn max_threads() -> usize {
    MAX_THREADS_PER_CORE * std::thread::available_parallelism().map_or(1, usize::from)
}

/// A pool of `threads` threads for `what` (a world, a study).
///
/// # Errors
/// [`SimError::Invalid`] for zero threads or more than [`max_threads`], naming the limit;
/// [`SimError::Runtime`] if the pool cannot be built.
pub(crate) fn pool(threads: usize, what: &str) -> Result<rayon::ThreadPool, SimError> {
    let invalid = |problem: String| SimError::Invalid {
        what: what.into(),
        field: "threads".into(),
        problem,
    };
    if threads == 0 {
        return Err(invalid("need at least one thread".into()));
    }
    let most = max_threads();
    if threads > most {
        return Err(invalid(format!(
            "{threads} threads asked, at most {most} on this machine ({MAX_THREADS_PER_CORE} \
             per core): more threads than cores only wait for one another"
        )));
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| SimError::Runtime {
            time: 0.0,
            message: format!("thread pool: {e}"),
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The limit is what the machine reports times the constant, independent of this code's
    /// use of it; one over it is refused with the limit named, at it a pool is built.
    #[test]
    fn a_count_over_the_machine_limit_is_refused_naming_it() {
        let cores = std::thread::available_parallelism().map_or(1, usize::from);
        let most = cores * MAX_THREADS_PER_CORE;
        assert_eq!(max_threads(), most);
        let err = pool(most + 1, "world").unwrap_err().to_string();
        assert!(err.contains(&format!("at most {most}")), "{err}");
        assert!(pool(0, "world").is_err());
        assert_eq!(pool(most, "world").unwrap().current_num_threads(), most);
        let start = std::time::Instant::now();
        assert!(pool(100_000, "world").is_err());
        assert!(start.elapsed() < std::time::Duration::from_secs(1));
    }
}
