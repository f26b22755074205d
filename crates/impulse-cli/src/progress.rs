//! Progress of the long commands on stderr, one way for all of them (`impulse run`, `bowling`,
//! `poses`, `reduce`).
//!
//! On a terminal, an [`indicatif`] bar (position, length, time left) once the work has lasted
//! [`SHOW_AFTER_S`]; when stderr is not a terminal (a log file, a pipe, CI), whole plain lines
//! at most every [`LINE_EVERY_S`] and one final line, never a carriage return: a redirected run
//! used to write one line of thousands of `\r`-separated updates.
//!
//! [`Progress`] is `Sync`: the parallel studies report from several threads through `&Progress`.

use std::io::IsTerminal as _;
use std::sync::Mutex;
use std::time::Instant;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// Work shorter than this (wall seconds) shows no progress at all.
pub(crate) const SHOW_AFTER_S: f64 = 2.0;
/// When stderr is not a terminal, a progress line is written at most this often (wall seconds).
pub(crate) const LINE_EVERY_S: f64 = 10.0;
/// Positions per simulated second of a run measured in time: the bar counts milliseconds.
const TICKS_PER_S: f64 = 1000.0;
/// Width of the bar on a terminal (characters).
const BAR_WIDTH: usize = 30;
/// Set (to anything) in tests: progress from the first update, and a line at every update, so
/// that a run of a fraction of a second shows what a long one writes.
pub(crate) const NOW_VAR: &str = "IMPULSE_PROGRESS_NOW";

/// What the work is counted in.
enum Measure {
    /// Whole pieces of work (`unit`: "throws", "drops").
    Count(&'static str),
    /// Simulated time up to `until` seconds.
    Time(f64),
}

/// The progress of one piece of long work.
pub(crate) struct Progress {
    /// Drawn only on a terminal, and only once the work has lasted [`SHOW_AFTER_S`].
    bar: ProgressBar,
    /// Whether stderr is a terminal (else plain lines).
    terminal: bool,
    /// Named first on every line (`impulse run`).
    prefix: &'static str,
    measure: Measure,
    start: Instant,
    /// Thresholds in force (the constants, or zero under [`NOW_VAR`]).
    show_after: f64,
    line_every: f64,
    /// Wall time of the last plain line, and whether the bar or a line was shown.
    state: Mutex<(f64, bool)>,
}

impl Progress {
    /// Progress through `len` pieces of work named `unit` ("throws").
    pub(crate) fn count(prefix: &'static str, len: u64, unit: &'static str) -> Self {
        Self::new(prefix, len, Measure::Count(unit))
    }

    /// Progress through simulated time up to `until` seconds.
    pub(crate) fn time(prefix: &'static str, until: f64) -> Self {
        Self::new(
            prefix,
            (until * TICKS_PER_S).ceil() as u64,
            Measure::Time(until),
        )
    }

    fn new(prefix: &'static str, len: u64, measure: Measure) -> Self {
        let template = match measure {
            Measure::Count(unit) => {
                format!("{{prefix}} [{{bar:{BAR_WIDTH}}}] {{pos}}/{{len}} {unit}, {{eta}} left")
            }
            Measure::Time(_) => {
                format!("{{prefix}} [{{bar:{BAR_WIDTH}}}] {{msg}}, {{eta}} left")
            }
        };
        let style = ProgressStyle::with_template(&template)
            .expect("the template is valid")
            .progress_chars("=> ");
        let bar = ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::hidden())
            .with_style(style)
            .with_prefix(prefix);
        let now = std::env::var_os(NOW_VAR).is_some();
        Progress {
            bar,
            terminal: std::io::stderr().is_terminal(),
            prefix,
            measure,
            start: Instant::now(),
            show_after: if now { 0.0 } else { SHOW_AFTER_S },
            line_every: if now { 0.0 } else { LINE_EVERY_S },
            state: Mutex::new((0.0, false)),
        }
    }

    /// `done` pieces of work are done (a count).
    pub(crate) fn set(&self, done: u64) {
        self.update(done, None);
    }

    /// Simulated time `t` is reached (a run in time).
    pub(crate) fn set_time(&self, t: f64) {
        self.update((t * TICKS_PER_S) as u64, Some(t));
    }

    fn update(&self, pos: u64, t: Option<f64>) {
        if let (Some(t), Measure::Time(until)) = (t, &self.measure) {
            self.bar.set_message(format!("t = {t:.3} / {until} s"));
        }
        self.bar.set_position(pos);
        let wall = self.start.elapsed().as_secs_f64();
        if wall < self.show_after {
            return;
        }
        let mut state = self.state.lock().unwrap_or_else(|e| e.into_inner());
        if self.terminal {
            if !state.1 {
                state.1 = true;
                self.bar.set_draw_target(ProgressDrawTarget::stderr());
            }
        } else if wall - state.0 >= self.line_every {
            state.0 = wall;
            state.1 = true;
            eprintln!("{}", self.line(wall));
        }
    }

    /// One plain progress line: where the work is, and the wall time so far.
    fn line(&self, wall: f64) -> String {
        let pos = self.bar.position();
        let len = self.bar.length().unwrap_or(pos).max(1);
        let percent = 100.0 * pos as f64 / len as f64;
        let done = match self.measure {
            Measure::Count(unit) => format!("{pos}/{len} {unit}"),
            Measure::Time(until) => format!("t = {:.3} / {until} s", pos as f64 / TICKS_PER_S),
        };
        format!(
            "{}: {done} ({percent:.0} %, {} wall)",
            self.prefix,
            crate::text::duration(wall)
        )
    }

    /// The work is over: the bar stays on screen as it ended; without a terminal, a final line
    /// if the work lasted long enough to show progress.
    pub(crate) fn finish(&self) {
        let wall = self.start.elapsed().as_secs_f64();
        let state = self.state.lock().unwrap_or_else(|e| e.into_inner());
        if self.terminal {
            if state.1 {
                self.bar.finish();
            }
        } else if wall >= self.show_after {
            eprintln!("{}", self.line(wall));
        }
    }
}
