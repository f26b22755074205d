//! # impulse-multibody — layer 2 of the `impulse` workspace
//!
//! **Owns** the dynamics of articulated bodies (Mirtich 1996, thesis chapters 4 and 5.3–5.4,
//! after Featherstone):
//! - the description of a multibody: a tree of links joined by revolute, prismatic and fixed
//!   joints on a fixed or floating base, with joint springs, dampers and friction, and gravity
//!   ([`Model`], [`ModelBuilder`]); URDF import into it ([`urdf`]);
//! - forward dynamics by the articulated-body algorithm in O(n) ([`forward_dynamics`], thesis
//!   Figs. 4.8/4.14 and §4.6), inverse dynamics by recursive Newton–Euler
//!   ([`inverse_dynamics`]) and the joint-space mass matrix by the composite-rigid-body
//!   algorithm ([`mass_matrix`]); kinematics, energies and momentum ([`Workspace`]);
//! - integration: adaptive-step RK4 by step doubling (the thesis's integrator, 11 derivative
//!   evaluations per step), fixed-step RK4 and semi-implicit Euler ([`Integrator`]);
//! - joint controllers at their own rates with zero-order hold, scheduled so the integrator
//!   stops at every update (thesis §5.4): PD, PID, computed torque, user controllers
//!   ([`Simulation`], [`Controller`]);
//! - joint limits as one-sided impulsive stops: a joint reaching its limit is a collision in
//!   joint space, located in time and resolved with the stop's restitution, and a joint that
//!   comes to rest on a stop is held there until its load lifts it off ([`limit`],
//!   [`JointLimit`]);
//! - the multibody collision-response pieces of thesis §5.3: the 3×3 collision matrix K of a
//!   contact point on any link by test impulses through the impulse-space articulated-body
//!   recursion (eq. 5.11 in its corrected form), propagation of a collision impulse through the
//!   tree, and the SVD pseudo-inverse for rank-deficient K ([`ImpulseDynamics`],
//!   [`pseudo_inverse`]).
//!
//! **Must not know** about collision detection, contact search, worlds, scenes or other bodies:
//! a contact point, frame and impulse are inputs here. Putting multibodies into the
//! impulse-based world (hybrid simulation) belongs to a higher layer. It depends on
//! `impulse-geom` (poses, twists, wrenches, spatial inertias), glam, faer (dense solves and the
//! SVD), thiserror and urdf-rs.
//!
//! # Conventions
//!
//! - f64 throughout; SI units in the docs, any consistent set works.
//! - Twists and wrenches pack the **linear part on top, angular below** (`impulse_geom::se3`).
//!   The thesis (Featherstone 1983) writes motion vectors `[ω; v]` and forces `[f; τ]`; see the
//!   module docs of `spatial` (private) for the correspondence: in this packing the spatial
//!   inertia is an ordinary symmetric matrix and the thesis's spatial transpose `x̂'ŷ` is a dot
//!   product.
//! - Link frames are URDF link frames: a moving link's frame sits on its inboard joint axis and
//!   its inertia is a general [`SpatialInertia`](impulse_geom::SpatialInertia) in that frame.
//!   The thesis puts frames at the centre of mass (Def. 3) and uses classical accelerations
//!   (Def. 5), which is why its Coriolis term `ĉ` (Def. 10) carries centripetal terms and its
//!   `Ẑ = [−mg; ω × Iω]` (Def. 13) is valid at the centre of mass only. Here accelerations are
//!   spatial (Featherstone 1987/2008): `ĉ_i = v̂_i × ŝ_i q̇_i` and `Ẑ_i = v̂_i ×* Î_i v̂_i − f_ext`
//!   hold in any body frame, and gravity enters as a fictitious base acceleration `−g`. The
//!   recursions (4.27)–(4.34), (5.6)–(5.10) are unchanged.
//! - Indices: the thesis numbers links 1..n with the ground as link 0 and joint i inboard of
//!   link i (Def. 14, pre-order numbering, Fig. 4.10). Here bodies are numbered 0..n−1 in the
//!   same pre-order; with a floating base, body 0 is the base.
//! - Generalized coordinates (as Pinocchio): `q` has `nq` entries, `v` and `τ` have `nv`. A
//!   fixed base has `nq = nv = n` joint coordinates. A floating base puts first, in `q`, the
//!   base origin's world position and its orientation quaternion `[x, y, z, qx, qy, qz, qw]`,
//!   and, in `v`, the base twist in base coordinates `[vx, vy, vz, ωx, ωy, ωz]` (v = velocity of
//!   the base-frame origin); `τ`'s first six entries are a wrench applied to the base, in base
//!   coordinates. Joint coordinates follow in depth-first (pre-order) order from the root, the
//!   children of a link in the order their joints were added (for URDF: file order).
//!
//! # Example
//!
//! A pendulum hanging from a fixed base, forward dynamics at one state:
//!
//! ```
//! use impulse_geom::{DMat3, DVec3, Pose, SpatialInertia};
//! use impulse_multibody::{BaseKind, JointSpec, ModelBuilder, Workspace, forward_dynamics};
//!
//! let rod = SpatialInertia::new(1.0, DVec3::new(0.5, 0.0, 0.0), DMat3::IDENTITY * 0.01);
//! let mut b = ModelBuilder::new(BaseKind::Fixed);
//! b.gravity(DVec3::new(0.0, -9.81, 0.0))
//!     .link("ground", SpatialInertia::ZERO)
//!     .link("rod", rod)
//!     .joint(JointSpec::revolute("hinge", "ground", "rod", Pose::IDENTITY, DVec3::Z));
//! let model = b.build()?;
//! let mut ws = Workspace::new(&model);
//! let mut qdd = [0.0];
//! forward_dynamics(&model, &mut ws, &[0.0], &[0.0], &[0.0], None, &mut qdd)?;
//! // Horizontal rod: q̈ = −m g c / (I + m c²).
//! assert!((qdd[0] + 9.81 * 0.5 / (0.01 + 0.25)).abs() < 1e-12);
//! # Ok::<(), impulse_multibody::MultibodyError>(())
//! ```
#![forbid(unsafe_code)]

mod collision;
mod control;
mod dynamics;
mod error;
pub mod held;
mod integrate;
pub mod limit;
mod model;
mod spatial;
mod travel;
pub mod urdf;

#[cfg(test)]
mod testutil;

pub use collision::{ImpulseDynamics, PseudoInverse, pseudo_inverse};
pub use control::{
    ComputedTorque, ControlInput, Controller, ControllerClone, ControllerId, JointPd, JointPid,
    Simulation,
};
pub use dynamics::{Workspace, bias_forces, forward_dynamics, inverse_dynamics, mass_matrix};
pub use error::MultibodyError;
/// The dense matrix type of [`mass_matrix`] (faer's), re-exported so callers need no faer
/// dependency of their own.
pub use faer::Mat;
pub use integrate::{AdaptiveRk4, Integrator, IntegratorStats};
pub use limit::{JointLimit, LimitStats};
pub use model::{BaseKind, JointPassive, JointSpec, JointType, LinkId, Model, ModelBuilder};
pub use travel::{LinkKinematics, LinkTravel, TravelSample};

/// Numerical tolerances of this crate, each with its reason.
pub mod tol {
    /// Cholesky pivot threshold for symmetric positive definite 6×6 solves (floating-base
    /// articulated inertia, eq. `â_1 = −(Î_1^A)^{-1} Ẑ_1^A`), relative to the largest diagonal
    /// entry. Validated models have positive definite inertias whose pivots are far above
    /// round-off; `1e-14` only rejects matrices that are singular to working precision (a
    /// pivot of round-off size, ~`6ε·scale`).
    pub const SPD_PIVOT_REL: f64 = 1e-14;

    /// Smallest eigenvalue of a moving body's rotational inertia about its centre of mass,
    /// relative to the largest, below which the inertia counts as not positive definite
    /// (articulated inertias would be singular: `D_i = ŝ'Î^Aŝ` can vanish, thesis digest §4
    /// case 5). `1e-12` accepts thin rods of aspect ratio up to ~10⁶ while rejecting exact
    /// zeros that round-off turns into ±1e-16.
    pub const INERTIA_PD_REL: f64 = 1e-12;

    /// Largest asymmetry `|I − Iᵀ|` of a given rotational inertia, relative to its largest
    /// entry. URDF gives only six numbers (symmetric by construction); builder input that is
    /// less symmetric than this is a data error.
    pub const INERTIA_SYMMETRY_REL: f64 = 1e-9;

    /// Smallest accepted length of a joint axis before normalisation (in the axis's own units,
    /// usually a unit vector). Shorter axes, including the zero vector, are rejected: their
    /// direction would be dominated by rounding.
    pub const AXIS_MIN_NORM: f64 = 1e-9;

    /// Default relative singular-value cutoff of [`crate::pseudo_inverse`]: singular values
    /// below `PINV_REL_CUTOFF · σ_max` are treated as zero. K is computed to ~1e-15 relative,
    /// so a structural zero shows up as ~1e-16·σ_max; physical singular values of real
    /// mechanisms are many decades above 1e-10·σ_max (the digest's suggestion).
    pub const PINV_REL_CUTOFF: f64 = 1e-10;
}
