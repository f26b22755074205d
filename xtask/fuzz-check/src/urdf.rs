//! URDF → dynamics (`impulse-multibody`, thesis ch. 4).
//!
//! The model is read on a fixed base and evaluated at the state [`state`] gives (joint
//! positions and speeds of order one, inside the joint limits when the model has them).
//! Asserted:
//! - the joint-space mass matrix M(q) (CRBA) is symmetric and positive definite (a Cholesky
//!   factorisation of this crate's own succeeds);
//! - ½·vᵀ·M·v equals the kinetic energy summed over the links' velocities;
//! - forward dynamics (ABA) without torque gives q̈ with M·q̈ + c(q, v) = 0, c the bias
//!   forces (RNEA at q̈ = 0): two algorithms agree;
//! - a simulation of [`DURATION`] (adaptive RK4, the thesis's integrator) keeps the state
//!   finite and does not gain energy (kinetic from M, plus gravity's): URDF joints carry only
//!   damping, friction and limit stops, which take energy away; the integrator's own error is
//!   allowed [`ENERGY_REL`].
//!
//! Out of bounds: more than [`MAX_JOINTS`] joint coordinates, or more than
//! [`MAX_RK_STEPS`] integrator steps (a stiff model: the integrator reports stiffness itself
//! by a step underflow, an error).

use impulse_multibody::{
    AdaptiveRk4, BaseKind, Integrator, Mat, Model, Simulation, Workspace, bias_forces,
    forward_dynamics, mass_matrix, urdf,
};

use crate::{Outcome, Violation};

/// Most joint coordinates of a fuzzed model. `12`.
pub const MAX_JOINTS: usize = 12;
/// Simulated time of the dynamics run (s). `0.2`.
pub const DURATION: f64 = 0.2;
/// The run is checked every this long (s). `0.01`.
pub const CHECK_EVERY: f64 = 0.01;
/// Most integrator steps of the run. `20 000`.
pub const MAX_RK_STEPS: u64 = 20_000;
/// Relative agreement of two algorithms (CRBA against link energies, ABA against RNEA),
/// relative to the scale of the compared terms. `1e-8`.
pub const AGREE_REL: f64 = 1e-8;
/// Energy the run may gain, relative to the scale of the energies seen (initial potential,
/// largest kinetic): the adaptive RK4 at tolerance 1e-8 per step drifts by about 1e-8 over
/// seconds (the crate's measured table in `impulse_multibody::Integrator`). `1e-6`.
pub const ENERGY_REL: f64 = 1e-6;

/// The state a model is evaluated at: q_i = 0.5·sin(i + 1) and v_i = cos(i + 1), clamped
/// into the joint's limits when it has them.
#[must_use]
pub fn state(model: &Model) -> (Vec<f64>, Vec<f64>) {
    let n = model.nv();
    let q = (0..n)
        .map(|i| {
            let q = 0.5 * ((i + 1) as f64).sin();
            match model.limit(i) {
                Some(l) if l.lower <= l.upper => q.clamp(l.lower, l.upper),
                _ => q,
            }
        })
        .collect();
    let v = (0..n).map(|i| ((i + 1) as f64).cos()).collect();
    (q, v)
}

/// Checks one URDF file's bytes (module documentation).
///
/// # Errors
/// The [`Violation`] found.
pub fn check_urdf(bytes: &[u8]) -> Result<Outcome, Violation> {
    let Some(text) = crate::text(bytes) else {
        return Ok(Outcome::Rejected("not UTF-8".into()));
    };
    let model = match urdf::from_str(text, BaseKind::Fixed) {
        Ok(m) => m,
        Err(e) => return Ok(Outcome::Rejected(e.to_string())),
    };
    let n = model.nv();
    if n > MAX_JOINTS {
        return Ok(Outcome::OutOfBounds(format!("{n} joints > {MAX_JOINTS}")));
    }
    let (q, v) = state(&model);
    let mut ws = Workspace::new(&model);
    let m = match matrix(&model, &mut ws, &q) {
        Ok(m) => m,
        Err(e) => return Ok(Outcome::Rejected(e)),
    };
    check_mass_matrix(&m)?;
    if let Err(e) = ws.update_kinematics(&model, &q, &v) {
        return Ok(Outcome::Rejected(e.to_string()));
    }
    let links = ws.kinetic_energy(&model);
    let crba = kinetic(&m, &v);
    if (links - crba).abs() > AGREE_REL * links.abs().max(crba.abs()).max(f64::MIN_POSITIVE) {
        return Err(Violation::Inconsistent(format!(
            "kinetic energy: ½vᵀMv = {crba:e}, over the links {links:e}"
        )));
    }
    check_aba_rnea(&model, &mut ws, &q, &v, &m)?;
    simulate(model, q, v, None)
}

/// The mass matrix at `q`.
fn matrix(model: &Model, ws: &mut Workspace, q: &[f64]) -> Result<Mat<f64>, String> {
    let n = model.nv();
    let mut m = Mat::<f64>::zeros(n, n);
    mass_matrix(model, ws, q, &mut m).map_err(|e| e.to_string())?;
    Ok(m)
}

/// ½·vᵀ·M·v.
fn kinetic(m: &Mat<f64>, v: &[f64]) -> f64 {
    let n = v.len();
    0.5 * (0..n)
        .map(|i| v[i] * (0..n).map(|j| m[(i, j)] * v[j]).sum::<f64>())
        .sum::<f64>()
}

/// M is finite, symmetric and positive definite (Cholesky).
pub(crate) fn check_mass_matrix(m: &Mat<f64>) -> Result<(), Violation> {
    let n = m.nrows();
    let scale = (0..n).map(|i| m[(i, i)].abs()).fold(0.0, f64::max);
    for i in 0..n {
        for j in 0..n {
            if !m[(i, j)].is_finite() || (m[(i, j)] - m[(j, i)]).abs() > AGREE_REL * scale {
                return Err(Violation::Inconsistent(format!(
                    "mass matrix not finite and symmetric at ({i}, {j}): {} vs {}",
                    m[(i, j)],
                    m[(j, i)]
                )));
            }
        }
    }
    let mut l = vec![0.0; n * n];
    for j in 0..n {
        let d = m[(j, j)] - (0..j).map(|k| l[j * n + k] * l[j * n + k]).sum::<f64>();
        if d.is_nan() || d <= 0.0 {
            return Err(Violation::MassProperties(format!(
                "mass matrix not positive definite: pivot {j} is {d:e}"
            )));
        }
        let d = d.sqrt();
        l[j * n + j] = d;
        for i in j + 1..n {
            let s = m[(i, j)] - (0..j).map(|k| l[i * n + k] * l[j * n + k]).sum::<f64>();
            l[i * n + j] = s / d;
        }
    }
    Ok(())
}

/// ABA's q̈ at τ = 0 satisfies M·q̈ + c = 0 with c from RNEA.
fn check_aba_rnea(
    model: &Model,
    ws: &mut Workspace,
    q: &[f64],
    v: &[f64],
    m: &Mat<f64>,
) -> Result<(), Violation> {
    let n = model.nv();
    let zero = vec![0.0; n];
    let mut qdd = vec![0.0; n];
    let mut c = vec![0.0; n];
    if forward_dynamics(model, ws, q, v, &zero, None, &mut qdd).is_err()
        || bias_forces(model, ws, q, v, &mut c).is_err()
    {
        return Ok(());
    }
    for i in 0..n {
        let terms: Vec<f64> = (0..n).map(|j| m[(i, j)] * qdd[j]).collect();
        let r = terms.iter().sum::<f64>() + c[i];
        let scale = terms.iter().map(|t| t.abs()).sum::<f64>() + c[i].abs();
        if !r.is_finite() || r.abs() > AGREE_REL * scale.max(f64::MIN_POSITIVE) {
            return Err(Violation::Inconsistent(format!(
                "row {i}: M·q̈ + c = {r:e} (scale {scale:e}); q̈ = {qdd:?}, c = {c:?}"
            )));
        }
    }
    Ok(())
}

/// The energy of the simulation's state: ½·vᵀ·M·v from CRBA plus gravity's potential; with
/// the kinetic part alone.
fn energy(model: &Model, ws: &mut Workspace, q: &[f64], v: &[f64]) -> Option<(f64, f64)> {
    let m = matrix(model, ws, q).ok()?;
    ws.update_kinematics(model, q, v).ok()?;
    let k = kinetic(&m, v);
    Some((k + ws.potential_energy(model), k))
}

/// The run of [`DURATION`] (module documentation); `applied`: joint forces held over the run
/// (an energy source, for the tests that show the check fails when it should).
pub(crate) fn simulate(
    model: Model,
    q: Vec<f64>,
    v: Vec<f64>,
    applied: Option<&[f64]>,
) -> Result<Outcome, Violation> {
    let check_model = model.clone();
    let mut ws = Workspace::new(&check_model);
    let Some((e0, k0)) = energy(&check_model, &mut ws, &q, &v) else {
        return Ok(Outcome::Rejected("energy at the start".into()));
    };
    let mut sim =
        match Simulation::new(model, q, v, Integrator::AdaptiveRk4(AdaptiveRk4::default())) {
            Ok(s) => s,
            Err(e) => return Ok(Outcome::Rejected(e.to_string())),
        };
    if let Some(tau) = applied
        && let Err(e) = sim.set_applied_forces(tau)
    {
        return Ok(Outcome::Rejected(e.to_string()));
    }
    let mut scale = k0 + e0.abs();
    let chunks = (DURATION / CHECK_EVERY).round() as usize;
    for k in 1..=chunks {
        let t = k as f64 * CHECK_EVERY;
        if let Err(e) = sim.run_until(t) {
            return Ok(Outcome::Rejected(format!("at t = {t} s: {e}")));
        }
        if sim.stats().steps > MAX_RK_STEPS {
            return Ok(Outcome::OutOfBounds(format!(
                "more than {MAX_RK_STEPS} integrator steps by t = {t} s"
            )));
        }
        let (q, v) = (sim.q().to_vec(), sim.v().to_vec());
        if !q.iter().chain(&v).all(|x| x.is_finite()) {
            return Err(Violation::NotFinite(format!("t = {t} s: q {q:?}, v {v:?}")));
        }
        let Some((e, kin)) = energy(&check_model, &mut ws, &q, &v) else {
            return Err(Violation::NotFinite(format!("energy at t = {t} s")));
        };
        scale = scale.max(kin + e0.abs());
        if e - e0 > ENERGY_REL * scale {
            return Err(Violation::EnergyGained(format!(
                "t = {t} s: {e:e} J from {e0:e} J (scale {scale:e} J)"
            )));
        }
    }
    Ok(Outcome::Checked {
        energy_checked: true,
    })
}
