//! # impulse-massprops — layer 1 of the `impulse` workspace
//!
//! **Owns** exact mass properties of rigid bodies (Mirtich 1996, thesis chapter 6):
//! - [`VolumeIntegrals`]: the ten volume integrals of a closed polyhedral mesh, reduced by the
//!   divergence theorem to face integrals, by projection to plane integrals and by Green's
//!   theorem to closed-form edge sums, all in one pass over the faces ([`integrals`]);
//! - [`MassProperties`]: mass, centre of mass and inertia tensor about the centre of mass, from
//!   a mesh with a density or a mass, from exact formulas (sphere, box), from point masses, and
//!   for compound bodies (sum of parts); and the principal frame ([`PrincipalFrame`]).
//!
//! **Must not know** about bodies, poses over time, collisions, simulation or scene files. It
//! uses `impulse-geom` for meshes and poses and faer for the symmetric eigendecomposition.
//!
//! Units: any consistent set. Mass = density × volume; inertia is mass × length².
#![forbid(unsafe_code)]

pub mod integrals;
mod properties;

pub use integrals::VolumeIntegrals;
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
