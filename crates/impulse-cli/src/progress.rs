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
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressState, ProgressStyle};

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
#[derive(Clone, Copy)]
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
    /// Whether the bar is on screen (a terminal).
    shown: AtomicBool,
    /// Wall time of the last plain line (not a terminal).
    last_line: Mutex<f64>,
}

impl Measure {
    /// Where the work is, `pos` of `len`: `12/40 throws`, `t = 1.250 / 5 s`. The bar and the
    /// plain lines say it the same way.
    fn done(self, pos: u64, len: u64) -> String {
        match self {
            Measure::Count(unit) => format!("{pos}/{len} {unit}"),
            Measure::Time(until) => format!("t = {:.3} / {until} s", pos as f64 / TICKS_PER_S),
        }
    }
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
        let template = format!("{{prefix}} [{{bar:{BAR_WIDTH}}}] {{done}}, {{eta}} left");
        // `{done}` is written only when the bar is drawn, from its own position.
        let style = ProgressStyle::with_template(&template)
            .expect("the template is valid")
            .with_key(
                "done",
                move |state: &ProgressState, w: &mut dyn std::fmt::Write| {
                    let pos = state.pos();
                    let _ = w.write_str(&measure.done(pos, state.len().unwrap_or(pos)));
                },
            )
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
            shown: AtomicBool::new(false),
            last_line: Mutex::new(0.0),
        }
    }

    /// `done` pieces of work are done (a count).
    pub(crate) fn set(&self, done: u64) {
        self.update(done);
    }

    /// Simulated time `t` is reached (a run in time).
    pub(crate) fn set_time(&self, t: f64) {
        self.update((t * TICKS_PER_S) as u64);
    }

    fn update(&self, pos: u64) {
        self.bar.set_position(pos);
        if self.terminal && self.shown.load(Ordering::Relaxed) {
            return;
        }
        let wall = self.start.elapsed().as_secs_f64();
        if wall < self.show_after {
            return;
        }
        if self.terminal {
            if !self.shown.swap(true, Ordering::Relaxed) {
                self.bar.set_draw_target(ProgressDrawTarget::stderr());
            }
            return;
        }
        let mut last = self.last_line.lock().unwrap_or_else(|e| e.into_inner());
        if wall - *last >= self.line_every {
            *last = wall;
            eprintln!("{}", self.line(wall));
        }
    }

    /// One plain progress line: where the work is, and the wall time so far.
    fn line(&self, wall: f64) -> String {
        let pos = self.bar.position();
        let len = self.bar.length().unwrap_or(pos).max(1);
        let percent = 100.0 * pos as f64 / len as f64;
        format!(
            "{}: {} ({percent:.0} %, {} wall)",
            self.prefix,
            self.measure.done(pos, len),
            crate::text::duration(wall)
        )
    }

    /// The work is over: the bar stays on screen as it ended; without a terminal, a final line
    /// if the work lasted long enough to show progress.
    pub(crate) fn finish(&self) {
        let wall = self.start.elapsed().as_secs_f64();
        if self.terminal {
            if self.shown.load(Ordering::Relaxed) {
                self.bar.finish();
            }
        } else if wall >= self.show_after {
            eprintln!("{}", self.line(wall));
        }
    }
}
