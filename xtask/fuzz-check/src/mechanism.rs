//! Mechanism file → FORK⁻¹S reduced model → [`STEPS`] steps (`impulse-reduced`).
//!
//! The reduced model is built at rest (no load) and asserted to have symmetric positive
//! semi-definite mass M, stiffness K and damping D (eqs. 9–22 make them Gram-like products;
//! checked by a symmetric eigendecomposition within [`PSD_REL`]). The simulation then starts
//! with end-effector velocities φ_i = [`START_SPEED`]·cos(i + 1), without gravity, external
//! wrenches or obstacles, and takes [`STEPS`] steps of [`STEP`]: the state stays finite, and on
//! a fixed base the energy ½·φᵀMφ + ½·ξᵀKξ (computed here from the state) never rises. Backward
//! Euler (eq. 23 fixed: M(φ' − φ) = −h(Kξ' + Dφ'), ξ' = ξ + hφ') is dissipative for symmetric
//! positive semi-definite M, K and D: E' − E = −h·φ'ᵀDφ' − ½(φ' − φ)ᵀM(φ' − φ) −
//! ½·h²·φ'ᵀKφ' ≤ 0. With a free base the end effectors exchange energy with the base, which
//! this energy leaves out: the energy is not asserted there (finiteness is).
//!
//! Out of bounds: more than [`MAX_LINKS`] links or [`MAX_DOF`] joint coordinates.

use impulse_reduced::reference::Configuration;
use impulse_reduced::{
    BaseDesc, ConstructOptions, Mechanism, MechanismDesc, ReducedModel, ReducedSim,
};

use crate::{Outcome, Violation};

/// Most links of a fuzzed mechanism. `64`.
pub const MAX_LINKS: usize = 64;
/// Most joint coordinates of a fuzzed mechanism. `192`.
pub const MAX_DOF: usize = 192;
/// Steps of the run. `100`.
pub const STEPS: usize = 100;
/// Time step (s). `1e-3`.
pub const STEP: f64 = 1e-3;
/// Scale of the starting end-effector velocities (m/s and rad/s). `0.1`.
pub const START_SPEED: f64 = 0.1;
/// Slack of the positive semi-definite checks: the smallest eigenvalue may be this much of
/// the largest below zero (rounding of the SVDs and products of the construction). `1e-9`.
pub const PSD_REL: f64 = 1e-9;
/// Energy rise allowed per step, relative to the energy at the start (rounding of the
/// factored step; the step itself dissipates). `1e-9`.
pub const ENERGY_REL: f64 = 1e-9;

/// Checks one mechanism file's bytes (module documentation).
///
/// # Errors
/// The [`Violation`] found.
pub fn check_mechanism(bytes: &[u8]) -> Result<Outcome, Violation> {
    let Some(text) = crate::text(bytes) else {
        return Ok(Outcome::Rejected("not UTF-8".into()));
    };
    let desc = match MechanismDesc::from_ron(text) {
        Ok(d) => d,
        Err(e) => return Ok(Outcome::Rejected(e.to_string())),
    };
    if desc.links.len() > MAX_LINKS {
        return Ok(Outcome::OutOfBounds(format!(
            "{} links > {MAX_LINKS}",
            desc.links.len()
        )));
    }
    let m = match desc.build() {
        Ok(m) => m,
        Err(e) => return Ok(Outcome::Rejected(e.to_string())),
    };
    if m.ndof > MAX_DOF {
        return Ok(Outcome::OutOfBounds(format!("{} dof > {MAX_DOF}", m.ndof)));
    }
    let model = match ReducedModel::build(
        &m,
        &Configuration::rest(&m),
        &[],
        &ConstructOptions::default(),
    ) {
        Ok(r) => r,
        Err(e) => return Ok(Outcome::Rejected(e.to_string())),
    };
    check_psd("mass M", &model.mass)?;
    check_psd("stiffness K", &model.stiffness)?;
    check_psd("damping D", &model.damping)?;
    simulate(&m, model)
}

/// The run of [`STEPS`] steps (module documentation).
pub(crate) fn simulate(m: &Mechanism, model: ReducedModel) -> Result<Outcome, Violation> {
    let fixed = matches!(m.base_kind, BaseDesc::Fixed);
    let mut sim = match ReducedSim::new(m, model, STEP) {
        Ok(s) => s,
        Err(e) => return Ok(Outcome::Rejected(e.to_string())),
    };
    if let Err(e) = sim.set_threads(1) {
        return Ok(Outcome::Rejected(e.to_string()));
    }
    sim.gravity = glam::DVec3::ZERO;
    for (i, p) in sim.phi.iter_mut().enumerate() {
        *p = START_SPEED * ((i + 1) as f64).cos();
    }
    let e0 = energy(&sim);
    let mut last = e0;
    let mut internal = vec![impulse_geom::Pose::IDENTITY; sim.model.internal.len()];
    for k in 1..=STEPS {
        sim.step();
        sim.internal_poses(&mut internal);
        let state_ok = sim.xi.iter().chain(&sim.phi).all(|x| x.is_finite())
            && (0..sim.model.end_effectors.len())
                .map(|i| sim.end_effector_pose(i))
                .chain(internal.iter().copied())
                .all(|p| p.translation.is_finite() && p.rotation.is_finite());
        if !state_ok {
            return Err(Violation::NotFinite(format!("step {k}: ξ {:?}", sim.xi)));
        }
        let e = energy(&sim);
        if fixed && e > last + ENERGY_REL * e0 {
            return Err(Violation::EnergyGained(format!(
                "step {k}: {e:e} J after {last:e} J (start {e0:e} J)"
            )));
        }
        last = e;
    }
    Ok(Outcome::Checked {
        energy_checked: fixed,
    })
}

/// ½·φᵀMφ + ½·ξᵀKξ, from the simulation's state and model.
fn energy(sim: &ReducedSim) -> f64 {
    let quad = |m: &faer::Mat<f64>, x: &[f64]| -> f64 {
        (0..x.len())
            .map(|i| x[i] * (0..x.len()).map(|j| m[(i, j)] * x[j]).sum::<f64>())
            .sum::<f64>()
    };
    0.5 * quad(&sim.model.mass, &sim.phi) + 0.5 * quad(&sim.model.stiffness, &sim.xi)
}

/// `m` is finite, symmetric and positive semi-definite within [`PSD_REL`].
pub(crate) fn check_psd(what: &str, m: &faer::Mat<f64>) -> Result<(), Violation> {
    let n = m.nrows();
    let mut scale: f64 = 0.0;
    for i in 0..n {
        for j in 0..n {
            if !m[(i, j)].is_finite() {
                return Err(Violation::NotFinite(format!("{what} at ({i}, {j})")));
            }
            scale = scale.max(m[(i, j)].abs());
        }
    }
    for i in 0..n {
        for j in 0..i {
            if (m[(i, j)] - m[(j, i)]).abs() > PSD_REL * scale {
                return Err(Violation::Inconsistent(format!(
                    "{what} is not symmetric at ({i}, {j}): {} vs {}",
                    m[(i, j)],
                    m[(j, i)]
                )));
            }
        }
    }
    if n == 0 || scale == 0.0 {
        return Ok(());
    }
    let Ok(values) = m.self_adjoint_eigenvalues(faer::Side::Lower) else {
        return Err(Violation::Inconsistent(format!(
            "{what}: no eigendecomposition"
        )));
    };
    let (lo, hi) = values.iter().fold((f64::INFINITY, 0.0f64), |(a, b), &x| {
        (a.min(x), b.max(x.abs()))
    });
    if lo < -PSD_REL * hi {
        return Err(Violation::MassProperties(format!(
            "{what} is not positive semi-definite: eigenvalue {lo:e} (largest {hi:e})"
        )));
    }
    Ok(())
}
