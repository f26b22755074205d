//! # impulse-massprops — layer 1 of the `impulse` workspace
//!
//! **Owns** exact mass properties of rigid bodies (Mirtich 1996, thesis chapter 6):
//! - [`VolumeIntegrals`]: the ten volume integrals of a closed polyhedral mesh, reduced by the
//!   divergence theorem to face integrals, by projection to plane integrals and by Green's
//!   theorem to closed-form edge sums, all in one pass over the faces ([`integrals`]);
//! - [`MassProperties`]: mass, centre of mass and inertia tensor about the centre of mass, from
//!   a mesh with a density or a mass, from exact formulas (sphere, box), from point masses, and
//!   for compound bodies (sum of parts); and the principal frame ([`PrincipalFrame`]);
//! - [`PoseAnalysis`]: a part's stable resting poses on a plane from its convex hull and centre
//!   of mass, and the quasi-static and perturbed quasi-static estimates of how often it comes
//!   to rest in each (thesis §7.5, eq. 7.1; [`poses`]); [`stats`]: the error metric and
//!   sample sizes and intervals of pose statistics (eqs. 7.2, 7.3).
//!
//! **Must not know** about bodies, poses over time, collisions, simulation or scene files. It
//! uses `impulse-geom` for meshes and poses and faer for the symmetric eigendecomposition.
//!
//! Units: any consistent set. Mass = density × volume; inertia is mass × length².
#![forbid(unsafe_code)]

pub mod integrals;
pub mod poses;
mod properties;
pub mod stats;

pub use integrals::VolumeIntegrals;
pub use poses::{PoseAnalysis, RestingFacet};
pub use properties::{MassProperties, PrincipalFrame};

use impulse_geom::GeomError;

/// Why mass properties could not be computed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MassError {
    /// The mesh is not a closed, consistently outward-oriented surface with proper faces.
    #[error("invalid mesh: {0}")]
    Mesh(#[from] GeomError),
    /// A density, mass or length is zero, negative or not finite.
    #[error("invalid {name} = {value}: must be finite and > 0")]
    NotPositive {
        /// The parameter's name.
        name: &'static str,
        /// The value given.
        value: f64,
    },
    /// A given centre of mass or inertia tensor is not finite, not symmetric, or violates the
    /// triangle inequality of principal moments.
    #[error("invalid inertia: {reason}")]
    InvalidInertia {
        /// What is wrong.
        reason: String,
    },
    /// A compound body has no parts.
    #[error("a compound body needs at least one part")]
    EmptyCompound,
    /// A part's centre of mass is not inside its convex hull (pose analysis,
    /// [`poses::PoseAnalysis::new`]).
    #[error(
        "the centre of mass ({}, {}, {}) is not inside the part's convex hull: it lies {distance:e} outside the plane of face {face}",
        com[0], com[1], com[2]
    )]
    ComOutsideHull {
        /// The centre of mass (part frame).
        com: [f64; 3],
        /// A hull face it is not inside.
        face: u32,
        /// Its signed distance beyond that face's plane (≥ 0 up to the tolerance).
        distance: f64,
    },
    /// A statistic's argument is out of its domain (a probability outside (0, 1), counts
    /// that do not match).
    #[error("invalid {name}: {reason}")]
    InvalidStatistic {
        /// The argument.
        name: &'static str,
        /// What is wrong.
        reason: String,
    },
    /// The symmetric eigensolver did not converge (only possible for non-finite input).
    #[error("the eigendecomposition of the inertia tensor failed to converge")]
    Eigen,
}

/// Relative tolerances of this crate, each with its reason.
pub mod tol {
    /// Largest asymmetry |I − Iᵀ| allowed in a user-given inertia tensor, relative to its
    /// largest entry; default `1e-9`. Tensors computed here are symmetric by construction.
    pub const INERTIA_SYMMETRY_REL: f64 = 1e-9;

    /// Slack in the triangle inequality `I₁ + I₂ ≥ I₃` of principal moments (and in their
    /// non-negativity), relative to the largest moment; default `1e-9`. A body of zero
    /// thickness (a rod, a disc of point masses) meets the inequality with equality, so the
    /// check must allow rounding on that boundary.
    pub const INERTIA_TRIANGLE_REL: f64 = 1e-9;
}
