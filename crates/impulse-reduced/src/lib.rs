//! # impulse-reduced — layer 3 of the `impulse` workspace
//!
//! **Owns** FORK⁻¹S, the first-order reduced compliant models of Andrews, Teichmann and Kry
//! ("Blended linear models for reduced compliant mechanical systems"):
//! - mechanisms of rigid links joined by compliant hinge, slider, ball and 6-DoF weld joints,
//!   branching and merging (closed loops), fixed or free base, chosen end effectors; their
//!   description in RON and a builder ([`MechanismDesc`]), validated into a [`Mechanism`];
//! - the full nonlinear reference of the same mechanisms ([`reference`](mod@reference)): kinematics, exact
//!   Jacobians, linearised constrained statics (the Schur complement at the end effectors) and
//!   nonlinear statics with loop closure;
//! - the construction of the reduced model (§4–5): the chain/split/merge walk
//!   ([`walk`], Algorithm 1, exact for any DAG walkable from the base), truncated SVD with a
//!   rank check ([`linalg`], eq. 9), every rank decision and the conditioning reported
//!   ([`rank`]), coupled compliance, accelerability (the paper's projection
//!   or the exact `J M⁻¹ Jᵀ`), damping and the twist maps ([`construct`]); the wrench maps
//!   (eqs. 15–20, Algorithm 2, [`wrench`]);
//! - reduced dynamics (§6, [`dynamics`]): backward Euler with eq. 23's sign fixed, projected
//!   Gauss–Seidel contact with Coulomb friction against [`obstacle`]s, a free base; internal
//!   links in parallel ([`internal`]);
//! - the model as plain data with its frames and units ([`export`], what
//!   `impulse reduce --compliance` writes); honest step timing ([`timing`]);
//! - blending of several linearisation points (§7, [`blend`]), their automatic choice
//!   ([`select`], beyond the paper), the Fig. 7 study ([`study`]) and the bundled mechanisms
//!   ([`scenes`]).
//!
//! **Must not know** about worlds, scenes, recording or files other than its own `Mechanism(...)`
//! RON. Contact geometry here is only the fixed planes, boxes and height fields an end effector
//! can touch. It depends on `impulse-geom` (SE(3) exp/log, adjoints, twists, wrenches), glam,
//! faer (SVD, eigen, dense solves), rayon (per-link parallel pose updates), serde/ron (the
//! description) and thiserror.
//!
//! Conventions: f64; twists and wrenches linear on top, angular below (Murray, Li & Sastry);
//! ξ is a small body-frame displacement twist (`H_ξ = H·exp(ξ)`, eq. 6), φ a body velocity.
#![forbid(unsafe_code)]

pub mod blend;
mod blend_cache;
pub mod construct;
pub mod convergence;
mod desc;
pub mod dynamics;
mod error;
pub mod export;
pub mod hard_cases;
pub mod internal;
mod lanes;
pub mod linalg;
mod mechanism;
pub mod obstacle;
pub mod rank;
pub mod reference;
pub mod scenes;
pub mod select;
pub mod study;
#[cfg(test)]
mod testutil;
pub mod timing;
pub mod tol;
pub mod walk;
pub mod wrench;

pub use construct::{ConstructOptions, MassModel, ReducedModel};
pub use desc::{BaseDesc, JointDesc, JointKindDesc, LinkDesc, MAX_DOF, MechanismDesc, ShapeDesc};
pub use dynamics::{
    BaseState, ContactParams, MAX_THREADS_PER_CORE, ReducedSim, StepReport, max_threads,
};
pub use error::Error;
pub use export::ModelExport;
pub use linalg::Tsvd;
pub use mechanism::{Direction, Joint, Link, Mechanism, Shape};
pub use obstacle::{HeightField, Obstacle};
pub use rank::{Diagnostics, RankReport, RankWarning};
pub use wrench::WrenchMaps;
