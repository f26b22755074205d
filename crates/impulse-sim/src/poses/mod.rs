//! Pose statistics of a part dropped on a belt (thesis §7.5, "dynamic simulation"): many
//! independent drops, in parallel and shardable, each run until the part is at rest, its
//! final pose classified by the facet it stands on.
//!
//! A drop is one small world: a fixed belt (the plane z = 0, a large box) and the part,
//! released with its lowest point at [`DropSettings::height`] above the belt and a horizontal
//! exit velocity [`DropSettings::exit_speed`] along x, in the switching contact model. The
//! world is polled [`POLL_RATE`] times a second until the part's island sleeps (at rest: the
//! switching model's sleep test, not a fixed long duration) or [`DropSettings::max_time`]
//! passes. The final orientation is classified by
//! [`impulse_massprops::PoseAnalysis::facet_facing`] within [`FACET_ANGLE`].
//!
//! **Starts** (thesis §7.5). The thesis dropped its first 20 parts from orientations uniform
//! on SO(3) and every later one from a pose drawn from the histogram of the final poses so
//! far (parts on the upper belt are already at rest), turned by up to 1.5° about a random
//! axis (belt vibration). That feedback makes each drop depend on all earlier ones, so it
//! can run neither in parallel nor in shards, and its result depends on the luck of the
//! first drops (a part that mostly lands as it started keeps whatever mix the first 20
//! gave). Here the drops are independent, and two estimates come out of them:
//! - **uniform**: even-numbered drops (every drop with [`DropSettings::belt_fed`] off) start
//!   uniform on SO(3) (Shoemake's method): their final-pose frequencies, with binomial
//!   intervals, are the dynamic counterpart of the quasi-static estimates, which assume the
//!   same start;
//! - **belt-fed**: odd-numbered drops start at rest on each stable facet in turn, turned
//!   about the vertical at random and tilted by up to [`DropSettings::jitter_degrees`]
//!   about a random axis. Their transition frequencies T between stable poses give the
//!   limit of the thesis's feedback loop, the long-run distribution of the chain T
//!   ([`summarize`]), estimated without the feedback's dependence on early drops.
//!
//! Drop i's random stream depends only on (seed, i), so a study's outcomes are the same for
//! any thread count and any shard split. [`run_thesis_feedback`] runs the thesis's own
//! sequential sampling, for comparison.
//!
//! **Shards**: [`Shard`] `K/N` runs drops K, K + N, K + 2N, …, and [`merge`] combines shard
//! files into exactly the file of the unsharded run.

mod part;
mod study;
mod summary;

pub use part::{PartFileDesc, PosePart};
pub use study::{
    DropOutcome, DropSettings, Shard, StudyFile, THESIS_PILOT, drop_scene, merge, run_drops,
    run_drops_with, run_thesis_feedback,
};
pub use summary::{PoseRow, PoseSummary, summarize};

/// The world is polled this many times per simulated second while waiting for the part to
/// sleep (the frame rate of a drop's scene, [`drop_scene`]). Default `20`: the switching model
/// needs an island still for half a second to sleep, so a finer poll would only add calls.
pub const POLL_RATE: f64 = 20.0;

/// A part at rest is on the facet whose normal is within this angle (rad) of straight down;
/// default `0.02` (1.1°). At rest on a flat belt the tilt is at most about ε_c over the part's
/// size (1e-3 with the default ε_c); a part at rest leaning on an edge of something else is
/// not classified.
pub const FACET_ANGLE: f64 = 0.02;

/// Default collision epsilon of a drop, relative to the part's diameter: `1e-3`.
pub const EPSILON_REL: f64 = 1e-3;

#[cfg(test)]
mod tests;
