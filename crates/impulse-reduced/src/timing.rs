//! Honest step timing (Table 1's µs per step): the mean of the stepping loop alone — the
//! end-effector step and every internal link's pose, as the paper counts a step — timed step
//! by step after a warm-up, so that construction, the first steps' one-time costs (the thread
//! pool starting, first touches of memory) and whatever the caller does between steps
//! (recording, output) are left out. `impulse reduce` and `cargo xtask bench --case forks`
//! both measure with it, so their figures mean the same thing.
//!
//! Each timed step costs two clock reads (~20–50 ns together on Linux), included in the
//! figure: about 1% of the smallest step of the bundled mechanisms.

use std::time::{Duration, Instant};

/// Steps excluded before timing starts (at most a quarter of the run, see
/// [`StepClock::for_run`]): the first step of a run starts the internal links' thread pool
/// (hundreds of µs) and touches the model's memory for the first time.
pub const WARMUP_STEPS: usize = 20;

/// Times the steps of a run after a warm-up.
#[derive(Clone, Debug)]
pub struct StepClock {
    warmup: usize,
    seen: usize,
    timed: usize,
    total: Duration,
    /// Every timed step's duration (µs), for the median.
    each: Vec<f32>,
}

impl StepClock {
    /// A clock that ignores the first `warmup` steps.
    #[must_use]
    pub fn new(warmup: usize) -> Self {
        StepClock {
            warmup,
            seen: 0,
            timed: 0,
            total: Duration::ZERO,
            each: Vec::new(),
        }
    }

    /// A clock for a run of `steps` steps: [`WARMUP_STEPS`] of warm-up, at most a quarter of
    /// the run (so that a short run still times three quarters of its steps).
    #[must_use]
    pub fn for_run(steps: usize) -> Self {
        let mut clock = Self::new(WARMUP_STEPS.min(steps / 4));
        clock.each.reserve(steps);
        clock
    }

    /// Runs one step `f`, timing it unless it is part of the warm-up.
    pub fn step<R>(&mut self, f: impl FnOnce() -> R) -> R {
        self.seen += 1;
        if self.seen <= self.warmup {
            return f();
        }
        let t = Instant::now();
        let r = f();
        let d = t.elapsed();
        self.total += d;
        self.timed += 1;
        self.each.push((d.as_secs_f64() * 1e6) as f32);
        r
    }

    /// Steps timed so far.
    #[must_use]
    pub fn timed(&self) -> usize {
        self.timed
    }

    /// Steps of warm-up.
    #[must_use]
    pub fn warmup(&self) -> usize {
        self.warmup
    }

    /// Median duration of a timed step (µs); `None` before any step was timed. On a shared
    /// machine a step the scheduler interrupts can cost milliseconds and move the mean of a
    /// short run by tens of percent; the median is not moved by a few of them.
    #[must_use]
    pub fn median_us(&self) -> Option<f64> {
        let mut v = self.each.clone();
        v.sort_by(f32::total_cmp);
        v.get(v.len() / 2).map(|&x| f64::from(x))
    }

    /// Mean duration of a timed step (µs); `None` before any step was timed.
    #[must_use]
    pub fn mean_us(&self) -> Option<f64> {
        (self.timed > 0).then(|| self.total.as_secs_f64() * 1e6 / self.timed as f64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The warm-up steps are run but not timed; a run shorter than four warm-ups keeps three
    /// quarters of its steps (counts against the definitions, not durations).
    #[test]
    fn warm_up_steps_are_run_but_not_timed() {
        let mut clock = StepClock::for_run(1000);
        let mut ran = 0;
        for _ in 0..1000 {
            clock.step(|| ran += 1);
        }
        assert_eq!(
            (ran, clock.warmup(), clock.timed()),
            (1000, WARMUP_STEPS, 980)
        );
        assert!(clock.mean_us().is_some() && clock.median_us().is_some());
        let short = StepClock::for_run(40);
        assert_eq!(short.warmup(), 10);
        assert_eq!(StepClock::new(3).mean_us(), None);
        assert_eq!(StepClock::new(3).median_us(), None);
    }
}
