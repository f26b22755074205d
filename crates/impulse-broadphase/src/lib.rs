//! # impulse-broadphase — layer 1 of the `impulse` workspace
//!
//! **Owns** the broad phase of thesis §2.4 (Mirtich 1996): a hierarchical spatial hash table
//! over axis-aligned boxes with several cubic tile sizes.
//! - [`Levels`]: the tile sizes ρ and the resolution rule res(X) of eq. (2.8), built by hand or
//!   from a size range by Lemma 1 / eq. (2.9) ([`levels`]);
//! - [`CoherentHash`]: the coherent variant of §2.4.2 that Impulse uses. It keeps its buckets
//!   and close counters between rounds, so a box that stays in the same cells costs nothing,
//!   and it reports the pairs that became close, which the simulator puts into its collision
//!   heap before integrating ([`coherent`]);
//! - [`StandardHash`]: the non-coherent variant of §2.4.1, rebuilt from scratch each round,
//!   kept as the comparison baseline of Table 2.1 ([`standard`]);
//! - [`WorkCounters`]: deterministic operation counts of both, for tests and benchmarks.
//!
//! **Must not know** bodies, shapes beyond boxes, time, collisions or collision response:
//! boxes come in under caller-chosen `u32` ids, pairs of ids come out. How the boxes were made
//! (swept volumes, §2.4.3) and what is done with close pairs (the collision heap) belong to
//! `impulse-collide` and `impulse-sim`.
//!
//! **Closeness** (Definition 1): boxes X and Y are close iff they overlap a common tile at level
//! min(res(X), res(Y)) — the coarser of their two levels. Every pair of overlapping boxes is
//! close (no false negatives); close boxes need not overlap ([`CoherentHash::overlapping_pairs`]
//! filters them). Theorem 5 bounds how far apart close boxes can be.
//!
//! **Determinism**: all maps use `rustc_hash` (fixed seed); every list returned is sorted, and
//! every pair is returned as `(a, b)` with `a < b`.
//!
//! Units: any consistent length unit; tile sizes and box sizes share it.
#![forbid(unsafe_code)]

pub mod coherent;
mod error;
pub mod levels;
pub mod standard;
mod tiling;
mod work;

pub use coherent::CoherentHash;
pub use error::BroadphaseError;
pub use levels::{DEFAULT_ALPHA, DEFAULT_BETA, Levels, MAX_LEVELS, box_size};
pub use standard::StandardHash;
pub use tiling::{MAX_CELL_INDEX, MAX_CELLS_PER_BOX};
pub use work::WorkCounters;

/// A pair of box ids, smaller id first.
pub type Pair = (u32, u32);

#[cfg(test)]
mod tests;
#[cfg(test)]
mod workload;
