//! Closed forms and near-closed forms of a body's rotation between collisions, for the inertia
//! shapes that have them, and the step-size controller of the numerical integrator
//! (`Body::rotate_numerically`) that serves the rest.
//!
//! - Equal moments, no torque: ω is constant (in `Body::rotate`).
//! - Two equal moments, no torque: the free symmetric top ([`torque_free_axisymmetric`]).
//! - Equal moments under a constant torque τ: ω(t) = ω₀ + (τ/I)·t exactly, and the orientation
//!   by the fourth-order Magnus expansion ([`isotropic_with_torque`]), whose error depends on
//!   how the axis turns, not on how fast the body spins.
//!
//! Must not know: collisions, contacts or the world; a body's moments, ω, τ and an interval
//! in, an orientation and ω out.

use glam::{DQuat, DVec3};

use super::{AdvanceError, ISOTROPIC_INERTIA_REL, MAX_ROTATION_STEPS, MIN_STEP_REL};

/// The symmetry axis of principal moments two of which are equal (within
/// [`ISOTROPIC_INERTIA_REL`] of the largest) and the third not: `(k, I_s, I_p)`, the body
/// axis k of the distinct moment I_s and the equal moment I_p. `None` for three distinct or
/// three equal moments.
pub(super) fn symmetry_axis(moments: DVec3) -> Option<(usize, f64, f64)> {
    let slack = ISOTROPIC_INERTIA_REL * moments.max_element();
    let equal = |a: f64, b: f64| (a - b).abs() <= slack;
    let i = moments.to_array();
    (0..3).find_map(|k| {
        let (a, b) = (i[(k + 1) % 3], i[(k + 2) % 3]);
        (equal(a, b) && !equal(i[k], a)).then_some((k, i[k], 0.5 * (a + b)))
    })
}

/// Torque-free rotation of an axisymmetric body over `dt`, in closed form (Euler's free
/// symmetric top; Goldstein, *Classical Mechanics*, §5.6): with L the constant world angular
/// momentum, e the body's symmetry axis k (moment I_s; the other two I_p), the angular
/// velocity splits as ω = L/I_p + (1/I_s − 1/I_p)·(L·e)·e, and L·e is constant (ė = ω × e =
/// L × e / I_p ⟂ L). The first part is constant in the world, the second constant in the
/// body, so q(t) = exp(t·L/I_p) ⊗ q₀ ⊗ exp(t·(1/I_s − 1/I_p)·(L·e)·e_k): exact to rounding
/// for any time, where the numerical integrator takes about ‖ω‖·t/0.1 steps of 11 derivative
/// evaluations (a spinning bullet). Returns the orientation and ω at `dt`.
pub(super) fn torque_free_axisymmetric(
    q0: DQuat,
    l: DVec3,
    axis: usize,
    i_s: f64,
    i_p: f64,
    dt: f64,
) -> (DQuat, DVec3) {
    let e_body = DVec3::AXES[axis];
    let l_s = l.dot(q0 * e_body);
    let spin_body = e_body * ((1.0 / i_s - 1.0 / i_p) * l_s);
    let precession = l / i_p;
    let q =
        (DQuat::from_scaled_axis(precession * dt) * q0 * DQuat::from_scaled_axis(spin_body * dt))
            .normalize();
    (q, precession + q * spin_body)
}

/// Step-size controller of the step-doubling RK4 (Numerical Recipes' constants: safety 0.9,
/// exponent 1/5, growth at most ×4).
fn grow(step: f64, err: f64, tol: f64) -> f64 {
    const SAFETY: f64 = 0.9;
    const MAX_GROWTH: f64 = 4.0;
    if err == 0.0 {
        return step * MAX_GROWTH;
    }
    step * (SAFETY * (tol / err).powf(0.2)).min(MAX_GROWTH)
}

/// Step-size reduction after a rejected step (at least ×0.1).
fn shrink(step: f64, err: f64, tol: f64) -> f64 {
    const SAFETY: f64 = 0.9;
    const MIN_SHRINK: f64 = 0.1;
    step * (SAFETY * (tol / err).powf(0.25)).max(MIN_SHRINK)
}

/// Rotation over `dt` of a body with equal principal moments under a constant torque: the
/// world angular velocity is ω(t) = a + b·t exactly (a = ω₀, b = τ/I), and the orientation
/// follows R' = [ω(t)]×·R. Each step of length h takes the first two terms of the Magnus
/// expansion (Iserles & Nørsett, 1999; for linear ω the third is O(h⁵), its h⁴ part cancels):
/// R(h) = exp([θ]×)·R(0), θ = h·a + ½h²·b − (h³/12)·a × b, with a the step's initial ω. The
/// second term vanishes when τ ∥ ω (a fixed axis, exact); otherwise the local error grows as
/// h⁵·|a|²·|b|, so a ball rolling at 100 rad/s under its friction torque takes one step per
/// millisecond where the Runge–Kutta integrator, whose error grows as (h·|ω|)⁵, took about 25.
/// Step doubling against `tolerance` (on the quaternion, as for the integrator), at most
/// [`MAGNUS_MAX_TURN`] radians a step. Returns the orientation and ω at `dt`.
pub(super) fn isotropic_with_torque(
    q0: DQuat,
    omega0: DVec3,
    b: DVec3,
    dt: f64,
    tolerance: f64,
) -> Result<(DQuat, DVec3), AdvanceError> {
    let magnus = |q: DQuat, a: DVec3, h: f64| {
        let theta = a * h + b * (0.5 * h * h) - a.cross(b) * (h * h * h / 12.0);
        DQuat::from_scaled_axis(theta) * q
    };
    let speed = omega0.length().max((omega0 + b * dt).length());
    let max_step = MAGNUS_MAX_TURN / speed.max(f64::MIN_POSITIVE);
    let advance = |q: DQuat, t: f64, h: f64| magnus(q, omega0 + b * t, h);
    let (q, _) = step_doubling(
        q0,
        dt,
        dt.min(max_step),
        max_step,
        tolerance,
        advance,
        false,
    )?;
    Ok((q, omega0 + b * dt))
}

/// Advances `q0` over `dt` by `advance(q, t, h)` (one step of length h from time t), in steps
/// whose local error, estimated by step doubling (one step against two half steps), stays
/// within `tolerance`; starts at `h` and never steps longer than `max_step`. `extrapolate`
/// takes the fifth-order local extrapolation of a fourth-order method (Runge–Kutta);
/// otherwise the two half steps are kept. Returns the orientation and the step length to
/// start the next call with.
pub(super) fn step_doubling(
    q0: DQuat,
    dt: f64,
    mut h: f64,
    max_step: f64,
    tolerance: f64,
    advance: impl Fn(DQuat, f64, f64) -> DQuat,
    extrapolate: bool,
) -> Result<(DQuat, f64), AdvanceError> {
    let h_min = dt * MIN_STEP_REL;
    let (mut t, mut q) = (0.0, q0);
    let mut steps = 0;
    while t < dt {
        steps += 1;
        if steps > MAX_ROTATION_STEPS {
            return Err(AdvanceError::TooManySteps);
        }
        let last = h >= dt - t;
        let step = if last { dt - t } else { h };
        let full = advance(q, t, step);
        let half = advance(advance(q, t, 0.5 * step), t + 0.5 * step, 0.5 * step);
        let err = (half - full).length();
        if !err.is_finite() {
            return Err(AdvanceError::NonFinite);
        }
        if err <= tolerance || step <= h_min {
            // Back onto the unit sphere.
            q = if extrapolate {
                (half + (half - full) * (1.0 / 15.0)).normalize()
            } else {
                half.normalize()
            };
            t = if last { dt } else { t + step };
            if !last || step >= h {
                h = grow(step, err, tolerance).min(max_step);
            }
        } else {
            h = shrink(step, err, tolerance).max(h_min);
        }
    }
    Ok((q, h))
}

/// Largest rotation of one Magnus step (radians); the expansion converges for steps turning
/// less than π. Default `1.0`.
pub const MAGNUS_MAX_TURN: f64 = 1.0;
