//! # impulse-collide — layer 2 of the `impulse` workspace
//!
//! **Owns** the narrow phase of collision detection (thesis chapter 2):
//! - closest features of two convex polyhedra with coherence: V-Clip, Mirtich's robust
//!   successor of Lin–Canny, which always terminates and reports penetration instead of cycling
//!   ([`vclip`]); exact sphere–sphere and sphere–polyhedron distances ([`point`]); exact
//!   (smooth) ellipsoids against any convex piece by GJK on support mappings ([`gjk`]);
//!   non-convex bodies as sets of convex pieces (eq. 2.1) with a bounding hierarchy
//!   ([`shape`]);
//! - brute-force references for all of these ([`brute`]);
//! - what a distance-zero query cannot say: the penetration depth and contact normal of
//!   pieces that touch or overlap ([`depth`], by the separating-axis search pruned on the
//!   Gauss map, [`sat`]), and the near vertices of a face-on contact
//!   ([`patch`]);
//! - contact manifolds of touching pieces: up to four points from the closest features (face
//!   clipping, edge and vertex contacts, smooth pieces), each named by the features that
//!   produced it, and their matching from one step to the next ([`manifold`]);
//! - time-of-impact lower bounds: the two routines every motion type supplies (swept box of the
//!   centre of mass, TOI coefficients; eqs. 2.2–2.5, 2.13–2.15, and for ballistic bodies a
//!   tighter spin bound from the current ω and ‖ω̇‖ ≤ ‖L‖·ω_max/I_min) for fixed, ballistic,
//!   cycler, spinner and oscillator bodies ([`motion`]), the pair bound ([`toi`]) and its
//!   quadratic root ([`root`]), and the event loop's scheduling policy built on it — targets
//!   inside the ε_c envelope, the gap floor, separating pairs, pruning ([`schedule`]);
//! - the collision heap: pairs keyed by their TOI bound, with re-keying and the hysteresis rule
//!   of §2.4.3 ([`heap`]).
//!
//! **Must not know** about collision response, worlds, time stepping or threads: queries take
//! shapes and poses and return distances, points and features.
#![forbid(unsafe_code)]

pub mod brute;
#[cfg(test)]
mod conservative;
pub mod depth;
pub mod feature;
pub mod gjk;
pub mod heap;
pub mod manifold;
pub mod motion;
pub mod patch;
pub mod point;
pub mod root;
pub mod sat;
pub mod schedule;
pub mod shape;
pub mod toi;
pub mod vclip;

pub use feature::{Closest, Feature, FeaturePair};
pub use heap::{CollisionHeap, HeapError};
pub use motion::{Motion, MotionError};
pub use shape::{Convex, PairCache, Piece, Shape, ShapeClosest};

use impulse_geom::GeomError;

/// Why a collision shape or query input was refused.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CollideError {
    /// Invalid geometry (e.g. a sphere radius that is not positive).
    #[error(transparent)]
    Geom(#[from] GeomError),
    /// A compound shape with no pieces.
    #[error("a compound shape needs at least one convex piece")]
    EmptyCompound,
    /// A piece placed with a NaN or infinite pose.
    #[error("piece {piece} of the compound has a non-finite pose")]
    NonFinitePose {
        /// Index of the piece.
        piece: usize,
    },
}
