//! Deterministic operation counts of the hash tables (tests assert on these, not on time).

use std::ops::{Add, AddAssign};

/// Operation counts of a hash table since its last `reset_work()`. They depend only on the
/// sequence of calls, never on timing, so tests can compare the two variants' work exactly.
///
/// Both variants count the same kinds of operation; [`WorkCounters::total`] adds them up.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct WorkCounters {
    /// Per-level tile ranges computed with τ (eq. 2.7): one per level 0..=res per box handled.
    pub cell_ranges: u64,
    /// Hash buckets looked up, written or emptied.
    pub bucket_visits: u64,
    /// Labels read while scanning buckets (for closeness, or to find a label to remove).
    pub label_reads: u64,
    /// Labels written into buckets.
    pub label_writes: u64,
    /// Labels removed from buckets (the standard variant counts the labels it clears when it
    /// rebuilds).
    pub label_removals: u64,
    /// Close-counter increments and decrements (coherent variant), or close-pair records (one
    /// per shared bucket found, standard variant).
    pub counter_changes: u64,
}

impl WorkCounters {
    /// Sum of all counts.
    pub fn total(&self) -> u64 {
        self.cell_ranges
            + self.bucket_visits
            + self.label_reads
            + self.label_writes
            + self.label_removals
            + self.counter_changes
    }
}

impl AddAssign for WorkCounters {
    fn add_assign(&mut self, o: Self) {
        self.cell_ranges += o.cell_ranges;
        self.bucket_visits += o.bucket_visits;
        self.label_reads += o.label_reads;
        self.label_writes += o.label_writes;
        self.label_removals += o.label_removals;
        self.counter_changes += o.counter_changes;
    }
}

impl Add for WorkCounters {
    type Output = Self;
    fn add(mut self, o: Self) -> Self {
        self += o;
        self
    }
}
