//! # fuzz-check — layer 5 of the `impulse` workspace
//!
//! **Owns** the invariants the fuzz targets of `fuzz/` assert, as ordinary functions compiled
//! on the stable toolchain: one `check_*` function per input format, taking the raw bytes of
//! one input and returning what became of it ([`Outcome`]) or the invariant it broke
//! ([`Violation`]). The fuzz targets (nightly, cargo-fuzz) are thin wrappers that panic on a
//! violation; `cargo test` replays every corpus file under `fuzz/corpus/` through the same
//! functions, so CI (stable only) checks every input the fuzzers ever kept.
//!
//! - [`check_scene`]: a RON scene → a world → [`scene::STEPS`] steps under the independent
//!   penetration monitor (`impulse_sim::monitor`);
//! - [`check_mesh`]: an OBJ mesh → mass properties and convex hull;
//! - [`check_urdf`]: a URDF model → mass matrix, forward and inverse dynamics, a short
//!   simulation;
//! - [`check_mechanism`]: a FORK⁻¹S `Mechanism(...)` → reduced model → [`mechanism::STEPS`]
//!   steps;
//! - [`check_part`]: a pose-study part file → [`part::DROPS`] drops.
//!
//! Every check bounds the work one input can ask for (bodies, facets, steps, simulated time:
//! named constants in each module) so that one execution stays well under a second; an input
//! over a bound is [`Outcome::OutOfBounds`], not a failure. An input the library refuses with
//! an `Err` is [`Outcome::Rejected`]: clear errors are the contract, panics are not (a panic
//! is the fuzzer's finding by itself).
//!
//! **Must not know** how the library computes what it checks: energies are computed here from
//! the state, penetration is read by the monitor (its own sweep and exact distances), the
//! principal moments by Jacobi rotations of this crate's own.
#![forbid(unsafe_code)]

pub mod energy;
pub mod mechanism;
pub mod mesh;
pub mod part;
pub mod scene;
pub mod urdf;

pub use mechanism::check_mechanism;
pub use mesh::check_mesh;
pub use part::check_part;
pub use scene::check_scene;
pub use urdf::check_urdf;

#[cfg(test)]
mod violations;

/// What became of an input that broke no invariant.
#[derive(Clone, Debug, PartialEq)]
pub enum Outcome {
    /// The library refused it with an error (the message).
    Rejected(String),
    /// It asks for more work than the check's bounds allow, or for something the check does
    /// not cover (the reason).
    OutOfBounds(String),
    /// It was run and every invariant held; `energy_checked` is false when the input has
    /// energy sources the check cannot bound (the module documentation says which).
    Checked {
        /// Whether the energy bound was asserted.
        energy_checked: bool,
    },
}

/// An invariant an input broke: which one and the numbers that show it.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Violation {
    /// A state component is not a finite number.
    #[error("non-finite state: {0}")]
    NotFinite(String),
    /// Energy rose above what the input's sources allow.
    #[error("energy gained: {0}")]
    EnergyGained(String),
    /// Two bodies interpenetrated by more than ε_c (the independent monitor's measure).
    #[error("penetration beyond ε_c: {0}")]
    Penetration(String),
    /// Mass properties that are not those of a physical body.
    #[error("mass properties: {0}")]
    MassProperties(String),
    /// A geometric invariant (hull, volume) failed.
    #[error("geometry: {0}")]
    Geometry(String),
    /// Two computations of one quantity disagree (dynamics identities).
    #[error("inconsistent: {0}")]
    Inconsistent(String),
}

/// The text of an input, or `None` when it is not UTF-8 (every format here is text).
pub(crate) fn text(bytes: &[u8]) -> Option<&str> {
    std::str::from_utf8(bytes).ok()
}

/// Eigenvalues of a symmetric 3×3 matrix, ascending, by cyclic Jacobi rotations (Jacobi 1846;
/// the update of Numerical Recipes §11.1): accurate to a few ulps of the largest eigenvalue
/// however close two of them are, and independent of the library's eigensolver. (The
/// trigonometric closed form of the characteristic cubic was tried first: near a repeated
/// eigenvalue its arccos loses half the digits, and the obj fuzz target's needles, I₂ ≈ I₃,
/// showed a false triangle-inequality violation of 1e-8 of I₃.)
#[must_use]
pub fn symmetric_eigenvalues(m: glam::DMat3) -> [f64; 3] {
    let mut a = [[0.0; 3]; 3];
    for (r, row) in a.iter_mut().enumerate() {
        for (c, x) in row.iter_mut().enumerate() {
            *x = 0.5 * (m.col(c)[r] + m.col(r)[c]);
        }
    }
    for _ in 0..JACOBI_SWEEPS {
        let off = a[0][1].abs() + a[0][2].abs() + a[1][2].abs();
        if off == 0.0 {
            break;
        }
        for (p, q, r) in [(0, 1, 2), (0, 2, 1), (1, 2, 0)] {
            let apq = a[p][q];
            if apq == 0.0 {
                continue;
            }
            let theta = (a[q][q] - a[p][p]) / (2.0 * apq);
            let t = theta.signum() / (theta.abs() + theta.hypot(1.0));
            let c = 1.0 / t.hypot(1.0);
            let s = t * c;
            let tau = s / (1.0 + c);
            a[p][p] -= t * apq;
            a[q][q] += t * apq;
            a[p][q] = 0.0;
            a[q][p] = 0.0;
            let (arp, arq) = (a[r][p], a[r][q]);
            a[r][p] = arp - s * (arq + tau * arp);
            a[r][q] = arq + s * (arp - tau * arq);
            a[p][r] = a[r][p];
            a[q][r] = a[r][q];
        }
    }
    let mut e = [a[0][0], a[1][1], a[2][2]];
    e.sort_by(f64::total_cmp);
    e
}

/// Most Jacobi sweeps of [`symmetric_eigenvalues`] (a 3×3 matrix converges quadratically, in
/// about five; the cap only bounds a non-finite input). `50`.
pub const JACOBI_SWEEPS: usize = 50;

/// Relative slack of the inertia checks (positive definite, triangle inequality): rounding
/// of the volume integrals (thesis ch. 6) and of the closed-form eigenvalues, both a few
/// hundred ulps of the largest moment at most. `1e-9`.
pub const INERTIA_REL: f64 = 1e-9;

/// Checks that a finite symmetric inertia tensor of a solid of positive volume is that of a
/// physical body: principal moments positive (positive definite) and obeying the triangle
/// inequality I₁ + I₂ ≥ I₃, both within [`INERTIA_REL`] of the largest moment. `what` names it.
///
/// # Errors
/// [`Violation::MassProperties`] naming the moments.
pub fn check_inertia(what: &str, inertia: glam::DMat3) -> Result<(), Violation> {
    if !inertia.is_finite() {
        return Err(Violation::MassProperties(format!(
            "{what}: inertia {inertia} is not finite"
        )));
    }
    let asym = (inertia - inertia.transpose()).abs().to_cols_array();
    let scale = inertia
        .abs()
        .to_cols_array()
        .iter()
        .fold(0.0f64, |a, &b| a.max(b));
    if asym.iter().any(|&x| x > INERTIA_REL * scale) {
        return Err(Violation::MassProperties(format!(
            "{what}: inertia {inertia} is not symmetric"
        )));
    }
    let [i1, i2, i3] = symmetric_eigenvalues(inertia);
    let slack = INERTIA_REL * i3.abs().max(scale);
    // Positive definite up to rounding: a needle's smallest moment, (width/length)² of the
    // largest, can lie below the integrals' rounding (the obj target found I₁ = −1e-12·I₃ on
    // a hull a million times longer than wide).
    if !(i1 > -slack && i3 > 0.0) {
        return Err(Violation::MassProperties(format!(
            "{what}: principal moments {i1:e}, {i2:e}, {i3:e} are not all positive"
        )));
    }
    if i1 + i2 < i3 - slack {
        return Err(Violation::MassProperties(format!(
            "{what}: principal moments {i1:e} + {i2:e} < {i3:e} (triangle inequality)"
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DMat3, DQuat, DVec3};

    /// The Jacobi rotations give the moments of a rotated diagonal tensor back (the reference is
    /// the diagonal itself).
    #[test]
    fn eigenvalues_of_a_rotated_diagonal() {
        let d = DVec3::new(1.0, 2.5, 3.0);
        let r = DMat3::from_quat(DQuat::from_axis_angle(
            DVec3::new(1.0, 2.0, 3.0).normalize(),
            0.7,
        ));
        let m = r * DMat3::from_diagonal(d) * r.transpose();
        let e = symmetric_eigenvalues(m);
        for (got, want) in e.iter().zip([1.0, 2.5, 3.0]) {
            assert!((got - want).abs() < 1e-12, "{e:?}");
        }
    }

    /// A needle's moments, I₁ tiny and I₂ ≈ I₃ (the obj fuzz target's finding): the moments
    /// come back to a few ulps of the largest, so the triangle inequality I₁ + I₂ ≥ I₃ that
    /// holds for the diagonal (the reference) holds for the rotated tensor too.
    #[test]
    fn eigenvalues_of_a_needle_keep_the_triangle_inequality() {
        let d = DVec3::new(8.2e7, 1.5474497e16, 1.5474497e16 + 4.0e7);
        let r = DMat3::from_quat(DQuat::from_axis_angle(
            DVec3::new(0.3, -1.0, 0.2).normalize(),
            1.1,
        ));
        let m = r * DMat3::from_diagonal(d) * r.transpose();
        let e = symmetric_eigenvalues(m);
        for (got, want) in e.iter().zip(d.to_array()) {
            assert!((got - want).abs() <= 16.0 * f64::EPSILON * d.z, "{e:?}");
        }
        assert!(check_inertia("needle", m).is_ok());
    }

    /// The inertia check refuses what is not physical: a negative moment and moments that
    /// break the triangle inequality; it accepts a solid cube's.
    #[test]
    fn inertia_check_refuses_unphysical_tensors() {
        assert!(check_inertia("cube", DMat3::from_diagonal(DVec3::splat(1.0))).is_ok());
        assert!(check_inertia("neg", DMat3::from_diagonal(DVec3::new(-1.0, 2.0, 2.0))).is_err());
        assert!(check_inertia("neg", DMat3::from_diagonal(DVec3::new(-1e-6, 2.0, 2.0))).is_err());
        // Rounding of a needle's smallest moment is not a violation.
        assert!(
            check_inertia("needle", DMat3::from_diagonal(DVec3::new(-1e-12, 2.0, 2.0))).is_ok()
        );
        assert!(check_inertia("tri", DMat3::from_diagonal(DVec3::new(1.0, 1.0, 2.5))).is_err());
        // A rod about its axis: I₁ → 0, I₂ = I₃ satisfies the inequality.
        assert!(check_inertia("rod", DMat3::from_diagonal(DVec3::new(1e-6, 1.0, 1.0))).is_ok());
    }
}
