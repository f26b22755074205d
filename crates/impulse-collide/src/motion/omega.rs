//! Bounds on the angular speed and acceleration of a torque-free body (thesis §2.3.3,
//! eqs. 2.4–2.5).

use glam::{DMat3, DVec3};

use super::{
    INERTIA_SYMMETRY_TOLERANCE, JACOBI_MAX_SWEEPS, JACOBI_OFF_DIAGONAL_REL, MotionError,
    finite_scalar, finite_vec,
};

fn check_principal(principal_moments: DVec3, omega: DVec3) -> Result<f64, MotionError> {
    finite_vec("principal moments", principal_moments)?;
    finite_vec("omega", omega)?;
    let i_min = principal_moments.min_element();
    if i_min > 0.0 {
        Ok(i_min)
    } else {
        Err(MotionError::InvalidParameter {
            name: "principal moment of inertia",
            value: i_min,
            requirement: "must be > 0",
        })
    }
}

fn finite_bound(x: f64) -> Result<f64, MotionError> {
    finite_scalar("omega_max (overflow)", x)
}

/// Energy bound on the angular speed of a torque-free body (eq. 2.5; rad/s):
/// `‖ω(t)‖ ≤ √(2E / I_min)`, `2E = I_x·ω_x² + I_y·ω_y² + I_z·ω_z²`.
///
/// `principal_moments` are `(I_x, I_y, I_z)` (kg·m², body principal frame) and `omega_body` the
/// current angular velocity in that frame (rad/s). Rotational kinetic energy is conserved in
/// ballistic flight, and the energy ellipsoid's semi-major axis is `√(2E/I_min)`. Never looser
/// than [`omega_max_momentum`]. Computed with ω scaled by its largest component, so it overflows
/// only if the bound itself does.
///
/// # Errors
/// [`MotionError::NonFinite`] for NaN or infinite input or an overflowing result;
/// [`MotionError::InvalidParameter`] when a principal moment is not positive.
pub fn omega_max_energy(principal_moments: DVec3, omega_body: DVec3) -> Result<f64, MotionError> {
    let i_min = check_principal(principal_moments, omega_body)?;
    let s = omega_body.abs().max_element();
    if s == 0.0 {
        return Ok(0.0);
    }
    let w = omega_body / s;
    let two_e = principal_moments.dot(w * w);
    finite_bound((two_e / i_min).sqrt() * s)
}

/// Bound on the angular acceleration of a torque-free body (rad/s²):
/// `‖ω̇(t)‖ ≤ ‖L‖·ω_max / I_min`, from Euler's equations in world form, I_w·ω̇ = L × ω with L
/// constant, and ω_max the energy bound [`omega_max_energy`]. Same inputs and errors.
///
/// # Errors
/// As [`omega_max_energy`].
pub fn alpha_max_torque_free(
    principal_moments: DVec3,
    omega_body: DVec3,
) -> Result<f64, MotionError> {
    let i_min = check_principal(principal_moments, omega_body)?;
    let omega_max = omega_max_energy(principal_moments, omega_body)?;
    let s = omega_body.abs().max_element();
    if s == 0.0 {
        return Ok(0.0);
    }
    let l = (principal_moments * (omega_body / s)).length() * s;
    finite_bound(l / i_min * omega_max)
}

/// Momentum bound on the angular speed of a torque-free body (eq. 2.4; rad/s):
/// `‖ω(t)‖ ≤ ‖L‖ / I_min = √(I_x²ω_x² + I_y²ω_y² + I_z²ω_z²) / I_min`.
///
/// The bound published in \[MC95b\] (Mirtich & Canny 1995); looser than [`omega_max_energy`]:
/// their ratio (2.6) is `r ∈ [√(I_min/I_max), 1]`. Same inputs and errors.
///
/// # Errors
/// As [`omega_max_energy`].
pub fn omega_max_momentum(principal_moments: DVec3, omega_body: DVec3) -> Result<f64, MotionError> {
    let i_min = check_principal(principal_moments, omega_body)?;
    let s = omega_body.abs().max_element();
    if s == 0.0 {
        return Ok(0.0);
    }
    let l = principal_moments * (omega_body / s);
    finite_bound(l.length() / i_min * s)
}

/// Symmetrises a world inertia tensor and returns it with a lower bound on its smallest
/// eigenvalue (kg·m²), refusing non-finite, asymmetric or non-positive-definite tensors.
fn checked_world_inertia(inertia: DMat3, omega: DVec3) -> Result<(DMat3, f64), MotionError> {
    if !inertia.is_finite() {
        return Err(MotionError::NonFinite {
            name: "world inertia tensor",
        });
    }
    finite_vec("omega", omega)?;
    let t = inertia.transpose();
    let scale = inertia
        .abs()
        .to_cols_array()
        .into_iter()
        .fold(0.0, f64::max);
    let asym = (inertia - t)
        .abs()
        .to_cols_array()
        .into_iter()
        .fold(0.0, f64::max);
    if asym > INERTIA_SYMMETRY_TOLERANCE * scale {
        return Err(MotionError::InvalidParameter {
            name: "world inertia asymmetry (relative)",
            value: asym / scale,
            requirement: "the inertia tensor must be symmetric (see INERTIA_SYMMETRY_TOLERANCE)",
        });
    }
    let sym = (inertia + t) * 0.5;
    let i_min = min_eigenvalue_lower_bound(sym);
    if i_min > 0.0 {
        Ok((sym, i_min))
    } else {
        Err(MotionError::InvalidParameter {
            name: "smallest principal moment of the world inertia tensor",
            value: i_min,
            requirement: "must be > 0 (tensor must be positive definite)",
        })
    }
}

/// Eq. (2.5) from world-frame data: `2E = ω·(I ω)` is the same in every frame, and `I_min` is the
/// smallest eigenvalue of the world inertia tensor (kg·m²; found by Jacobi iteration, as a
/// lower bound). `omega_world` in rad/s; result in rad/s.
///
/// # Errors
/// [`MotionError::NonFinite`] for NaN or infinite input or an overflowing result;
/// [`MotionError::InvalidParameter`] for an asymmetric (beyond
/// [`INERTIA_SYMMETRY_TOLERANCE`]) or non-positive-definite tensor.
pub fn omega_max_energy_world(
    inertia_world: DMat3,
    omega_world: DVec3,
) -> Result<f64, MotionError> {
    let (sym, i_min) = checked_world_inertia(inertia_world, omega_world)?;
    let s = omega_world.abs().max_element();
    if s == 0.0 {
        return Ok(0.0);
    }
    let w = omega_world / s;
    // ω·Iω ≥ I_min·|ω|² > 0 in exact arithmetic; max(0) guards rounding of a tiny ω component.
    let two_e = w.dot(sym * w).max(0.0);
    finite_bound((two_e / i_min).sqrt() * s)
}

/// Eq. (2.4) from world-frame data: `‖L‖ = ‖I ω‖` is frame independent. Same inputs and errors
/// as [`omega_max_energy_world`].
///
/// # Errors
/// As [`omega_max_energy_world`].
pub fn omega_max_momentum_world(
    inertia_world: DMat3,
    omega_world: DVec3,
) -> Result<f64, MotionError> {
    let (sym, i_min) = checked_world_inertia(inertia_world, omega_world)?;
    let s = omega_world.abs().max_element();
    if s == 0.0 {
        return Ok(0.0);
    }
    finite_bound((sym * (omega_world / s)).length() / i_min * s)
}

/// Lower bound on the smallest eigenvalue of a symmetric 3×3 matrix by cyclic Jacobi rotations.
///
/// Option A, the closed-form trigonometric solution, loses about √ε relative accuracy when two
/// eigenvalues nearly coincide (acos near ±1); option B, Jacobi, is accurate to ~ε·‖M‖ and its
/// leftover off-diagonal norm bounds the error (Weyl). Chose B. The result is the smallest
/// diagonal entry minus that leftover norm.
fn min_eigenvalue_lower_bound(m: DMat3) -> f64 {
    let mut a = [
        m.x_axis.to_array(),
        m.y_axis.to_array(),
        m.z_axis.to_array(),
    ];
    let frob = |a: &[[f64; 3]; 3]| a.iter().flatten().map(|x| x * x).sum::<f64>().sqrt();
    let off =
        |a: &[[f64; 3]; 3]| (2.0 * (a[0][1].powi(2) + a[0][2].powi(2) + a[1][2].powi(2))).sqrt();
    let total = frob(&a);
    for _ in 0..JACOBI_MAX_SWEEPS {
        if off(&a) <= JACOBI_OFF_DIAGONAL_REL * total {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            let apq = a[p][q];
            if apq == 0.0 {
                continue;
            }
            // Rotation in the (p, q) plane that zeroes a[p][q] (Golub & Van Loan §8.5).
            let theta = (a[q][q] - a[p][p]) / (2.0 * apq);
            let t = theta.signum() / (theta.abs() + theta.hypot(1.0));
            let c = 1.0 / t.hypot(1.0);
            let s = t * c;
            for row in &mut a {
                let (akp, akq) = (row[p], row[q]);
                row[p] = c * akp - s * akq;
                row[q] = s * akp + c * akq;
            }
            let (row_p, row_q) = (a[p], a[q]);
            a[p] = core::array::from_fn(|k| c * row_p[k] - s * row_q[k]);
            a[q] = core::array::from_fn(|k| s * row_p[k] + c * row_q[k]);
            a[p][q] = 0.0;
            a[q][p] = 0.0;
        }
    }
    a[0][0].min(a[1][1]).min(a[2][2]) - off(&a)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::testkit::*;
    use crate::motion::*;
    use glam::{DMat3, DQuat, DVec3};
    use rand::RngExt;

    #[test]
    fn omega_bounds_hold_along_torque_free_trajectories() {
        const CASES: usize = 40;
        let mut rng = rng(77);
        let mut tightest: f64 = 0.0;
        for case in 0..CASES {
            let half = if case == 0 {
                DVec3::new(1.4, 0.1, 0.1)
            } else {
                random_box(&mut rng)
            };
            let inertia = box_inertia(half);
            let w0 = unit_vector(&mut rng) * 10f64.powf(rng.random_range(-1.0..3.0));
            let energy = omega_max_energy(inertia, w0).unwrap();
            let momentum = omega_max_momentum(inertia, w0).unwrap();
            assert!(energy <= momentum * (1.0 + CLOSED_FORM_TOL));
            let start = Tumbler {
                torque: DVec3::ZERO,
                inertia,
                q: DQuat::IDENTITY,
                w: w0,
            };
            let traj = Trajectory::new(half, start, (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO), {
                SPAN_ANGLE / energy
            });
            for s in &traj.states {
                let w = s.w.length();
                assert!(
                    w <= energy * (1.0 + OMEGA_SLACK_REL),
                    "case {case}: |ω| {w} > {energy}"
                );
                tightest = tightest.max(w / energy);
            }
        }
        eprintln!("max |ω(t)| / eq. 2.5 along trajectories: {tightest:.6}");
    }

    /// The ratio (2.6) of the energy bound to the momentum bound.
    fn ratio(i: DVec3, w: DVec3) -> f64 {
        omega_max_energy(i, w).unwrap() / omega_max_momentum(i, w).unwrap()
    }

    #[test]
    fn ratio_of_energy_to_momentum_bound_lies_in_its_range() {
        let mut rng = rng(5);
        for _ in 0..5000 {
            let i = DVec3::new(
                10f64.powf(rng.random_range(-2.0..2.0)),
                10f64.powf(rng.random_range(-2.0..2.0)),
                10f64.powf(rng.random_range(-2.0..2.0)),
            );
            let w = unit_vector(&mut rng) * 10f64.powf(rng.random_range(-3.0..3.0));
            let r = ratio(i, w);
            let lo = (i.min_element() / i.max_element()).sqrt();
            assert!(r >= lo * (1.0 - CLOSED_FORM_TOL) && r <= 1.0 + CLOSED_FORM_TOL);
            // Spin about the min-inertia axis: 1; about the max axis: √(I_min/I_max).
            let min_axis = DVec3::AXES[i.min_position()] * 3.0;
            let max_axis = DVec3::AXES[i.max_position()] * 3.0;
            assert!((ratio(i, min_axis) - 1.0).abs() <= CLOSED_FORM_TOL);
            assert!((ratio(i, max_axis) - lo).abs() <= CLOSED_FORM_TOL * lo);
            // Equal moments (cube, sphere): 1 for any spin.
            assert!((ratio(DVec3::splat(i.x), w) - 1.0).abs() <= CLOSED_FORM_TOL);
        }
    }

    #[test]
    fn world_frame_bounds_equal_body_frame_bounds() {
        let mut rng = rng(11);
        let mut worst: f64 = 0.0;
        for case in 0..4000 {
            let mut moments = DVec3::new(
                10f64.powf(rng.random_range(-3.0..3.0)),
                10f64.powf(rng.random_range(-3.0..3.0)),
                10f64.powf(rng.random_range(-3.0..3.0)),
            );
            // Repeated eigenvalues: the hard case for closed-form eigenvalue formulas.
            match case % 4 {
                0 => moments.y = moments.x,
                1 => moments = DVec3::splat(moments.x),
                2 => moments.y = moments.x * (1.0 + 1e-9),
                _ => {}
            }
            let r = DMat3::from_quat(random_rotation(&mut rng));
            let inertia_world = r * DMat3::from_diagonal(moments) * r.transpose();
            let w_body = unit_vector(&mut rng) * 10f64.powf(rng.random_range(-2.0..3.0));
            let w_world = r * w_body;
            let body = omega_max_energy(moments, w_body).unwrap();
            let world = omega_max_energy_world(inertia_world, w_world).unwrap();
            let body_l = omega_max_momentum(moments, w_body).unwrap();
            let world_l = omega_max_momentum_world(inertia_world, w_world).unwrap();
            // Tensor rounding is relative to the largest moment; the bound scales as
            // √(I_max/I_min), so compare with that factor.
            let cond = moments.max_element() / moments.min_element();
            let rel = (world - body).abs() / body / cond;
            worst = worst.max(rel);
            assert!(rel <= CLOSED_FORM_TOL, "case {case}: {world} vs {body}");
            assert!((world_l - body_l).abs() / body_l / cond <= CLOSED_FORM_TOL);
            // The eigenvalue is a lower bound (to rounding of the tensor itself).
            let lam = min_eigenvalue_lower_bound(inertia_world);
            let err = lam - moments.min_element();
            assert!(
                err <= CLOSED_FORM_TOL * moments.max_element(),
                "{lam} vs {moments}"
            );
        }
        eprintln!("world vs body ω_max, max relative difference / cond: {worst:.2e}");
    }

    #[test]
    fn bad_inertia_and_spin_are_refused() {
        let w = DVec3::new(1.0, 2.0, 3.0);
        let i = DVec3::new(1.0, 2.0, 3.0);
        for bad in [DVec3::new(0.0, 1.0, 1.0), DVec3::new(-1.0, 1.0, 1.0)] {
            assert!(matches!(
                omega_max_energy(bad, w),
                Err(MotionError::InvalidParameter { .. })
            ));
            assert!(omega_max_momentum(bad, w).is_err());
        }
        assert!(matches!(
            omega_max_energy(DVec3::new(f64::NAN, 1.0, 1.0), w),
            Err(MotionError::NonFinite { .. })
        ));
        assert!(omega_max_energy(i, DVec3::new(0.0, f64::INFINITY, 0.0)).is_err());
        assert_eq!(omega_max_energy(i, DVec3::ZERO), Ok(0.0));
        // Huge but finite spin: no intermediate overflow.
        let big = omega_max_energy(DVec3::ONE, DVec3::new(1e200, 0.0, 0.0)).unwrap();
        assert_eq!(big, 1e200);
        assert!(omega_max_energy(DVec3::new(1e-300, 1.0, 1.0), DVec3::Y * 1e300).is_err());
        let sym = DMat3::from_diagonal(i);
        let mut asym = sym;
        asym.x_axis.y += 1e-3;
        assert!(omega_max_energy_world(asym, w).is_err());
        let indefinite = DMat3::from_diagonal(DVec3::new(1.0, -1.0, 2.0));
        assert!(omega_max_energy_world(indefinite, w).is_err());
        let mut nan = sym;
        nan.z_axis.z = f64::NAN;
        assert!(omega_max_energy_world(nan, w).is_err());
        assert!(omega_max_momentum_world(DMat3::ZERO, w).is_err());
    }
}
