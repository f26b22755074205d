//! The bowling study of thesis §7.4 (Fig. 7.10): straight and hooking throws down a 60 ft
//! lane into ten pins, the pins felled counted against where the ball crossed the pin line,
//! in parallel and shardable like [`crate::poses`].
//!
//! **The alley** ([`AlleyDesc`], a RON file): a fixed lane from the foul line (y = 0)
//! past the head pin (the pin line) to the pit, gutters of circular cross-section with outer
//! walls either side, a pit
//! floor below the deck's end, optional kickbacks, ten pins (solids of revolution from a
//! lathe profile, as a compound of convex frusta) standing on their spots, and the ball.
//!
//! **A throw** releases the ball on the foul line, resting on the lane, with the speed and
//! spin of its kind ([`ThrowKind`]): straight (no spin, along +y) or a right-hander's hook
//! (−12 rad/s about +y, 2° to the right of +y; thesis). The ball slides, curving while it
//! slides, then rolls straight ([`ideal_crossing`] is the ideal model of that path), then
//! meets the pins. The world is polled [`POLL_RATE`] times a second; the ball's crossing of
//! the pin line is interpolated between polls, and the run ends once every pin is at rest or
//! off the deck and the ball is asleep or has left the deck (or
//! [`ThrowSettings::settle_time`] after the crossing). A pin stands ([`pin_stands`]) if its
//! axis is within [`STANDING_TILT`] of vertical and its base is on the deck.
//!
//! **The study**: throws 0, 2, 4, … are straight, 1, 3, 5, … hooks. Each kind's throws are
//! aimed across the window of crossings ([`ThrowSettings::window_width`], 40 cm in the
//! thesis) in equal strata, one throw at a random point of each, the release x set from the
//! ideal model so that the throw would cross at its aim; the measured crossing is what is
//! binned. Throw i's aim depends only on the study (alley, settings, seed, size) and i: any
//! thread count and shard split give the same outcomes, and [`merge`] rebuilds the
//! unsharded file.

mod alley;
mod summary;
mod throw;

pub use alley::{
    APPROACH, AlleyContacts, AlleyDesc, BallDesc, GUTTER_FACETS, GUTTER_WALL_HEIGHT,
    KICKBACK_HEIGHT, KICKBACK_LEAD, MAX_PIN_SIDES, PIN_COUNT, PIT_DEPTH, PIT_LENGTH, PLACE_GAP_REL,
    PinDesc, SLAB,
};
pub use summary::{
    BIN_WIDTH, BinRow, BowlingSummary, HEAD_ON, MAX_BINS, Mean, POCKET, SHOULDERS, band, bins,
    summarize, to_csv,
};
pub use throw::{
    BowlingFile, MAX_THROWS_PER_KIND, ThrowKind, ThrowOutcome, ThrowSettings, ideal_crossing,
    merge, pin_stands, run_throw, run_throws, run_throws_with, throw_scene,
};

/// Polls of a throw's world per simulated second (its scene's frame rate). Default `100`:
/// the ball moves about 6 cm between polls, and its pin-line crossing is interpolated.
pub const POLL_RATE: f64 = 100.0;

/// A pin stands if its axis is within this angle (rad) of vertical. Default `0.175` (10°):
/// a pin tipped further falls unless something holds it (its centre of mass, 14 cm up,
/// passes over the edge of its 5 cm base at about 10°).
pub const STANDING_TILT: f64 = 0.175;

/// A pin stands only if its base's centre is within this height (m) of the deck. Default
/// `0.01`.
pub const STANDING_LIFT: f64 = 0.01;

#[cfg(test)]
mod tests;
