//! Ballistic motion (thesis §2.3.2): a parabola and free tumbling.

use glam::DVec3;
use impulse_geom::Aabb;

use super::{
    ALL_SPACE, MotionError, UNBOUNDED_COEFFICIENTS, finite_scalar, finite_vec, non_negative, pad,
};

/// Ballistic motion (thesis §2.3.2): the centre of mass follows a parabola under a constant
/// acceleration (gravity, plus any constant external force over the mass), the body tumbles
/// freely, and `omega_max` bounds `‖ω‖` over the whole ballistic phase.
///
/// Under a constant external torque τ (not in the thesis), the world angular momentum grows
/// linearly, L(t) = L₀ + τ·t, so ‖ω(t)‖ ≤ ‖L(t)‖/I_min ≤ ω_max + β·t with ω_max = ‖L₀‖/I_min
/// (eq. 2.4) and β = ‖τ‖/I_min ([`Ballistic::with_omega_growth`]).
///
/// State at the current time t0, world frame: `com` (m), `velocity` (m/s), `gravity` (m/s²),
/// `omega_max` (rad/s, from [`omega_max_energy`](super::omega_max_energy) or
/// [`omega_max_energy_world`](super::omega_max_energy_world), recomputed by
/// the caller after every impulse on the body). COM path: `p(τ) = com + v·τ + ½·g·τ²`.
///
/// Optionally ([`Ballistic::with_spin`]) the current angular velocity ω₀ (world) and a bound
/// α_max on ‖ω̇‖ during the flight, which give a second rotational bound that is much tighter
/// for a body spinning about the direction of approach (a top on a table), see
/// [`Ballistic::toi_coefficients_for_gap`].
///
/// Optionally ([`Ballistic::with_acceleration_pad`]) the acceleration is known only to lie
/// within a ball of radius `pad` about `gravity` (a body whose contact load a solver changes
/// from step to step, within bounds): every bound then holds for every path whose
/// acceleration stays in that ball, so it need not be recomputed while the load stays
/// there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ballistic {
    com: DVec3,
    velocity: DVec3,
    gravity: DVec3,
    omega_max: f64,
    /// (ω₀ world, α_max), when known.
    spin: Option<(DVec3, f64)>,
    /// β (rad/s²): ‖ω(t0 + τ)‖ ≤ omega_max + β·τ. Zero for a torque-free body.
    omega_growth: f64,
    /// Radius (m/s²) of the ball of accelerations about `gravity` the bounds cover; zero for
    /// an acceleration known exactly.
    accel_pad: f64,
}

impl Ballistic {
    /// A ballistic motion from its state at t0 (world frame; m, m/s, m/s², rad/s).
    ///
    /// # Errors
    /// [`MotionError::NonFinite`] for a NaN or infinite input; [`MotionError::InvalidParameter`]
    /// for a negative `omega_max`.
    pub fn new(
        com: DVec3,
        velocity: DVec3,
        gravity: DVec3,
        omega_max: f64,
    ) -> Result<Self, MotionError> {
        Ok(Self {
            com: finite_vec("com", com)?,
            velocity: finite_vec("velocity", velocity)?,
            gravity: finite_vec("gravity", gravity)?,
            omega_max: non_negative("omega_max", omega_max)?,
            spin: None,
            omega_growth: 0.0,
            accel_pad: 0.0,
        })
    }

    /// Widens the bounds to every acceleration within `pad` (m/s²) of `gravity`: the centre of
    /// mass's displacement along d̂ over τ is then at most `(v·d̂)·τ + ½·(g·d̂ + pad·|d̂|)·τ²`,
    /// and the swept box grows by ½·pad·Δt² on every axis. A padded motion gets no spin
    /// refinement (it assumes the torque-free ω̇ bound).
    ///
    /// # Errors
    /// [`MotionError::NonFinite`] or [`MotionError::InvalidParameter`] for a NaN, infinite or
    /// negative `pad`.
    pub fn with_acceleration_pad(self, pad: f64) -> Result<Self, MotionError> {
        Ok(Self {
            accel_pad: non_negative("accel_pad", pad)?,
            ..self
        })
    }

    /// The radius of the ball of accelerations about `gravity` the bounds cover (m/s²).
    #[must_use]
    pub fn acceleration_pad(&self) -> f64 {
        self.accel_pad
    }

    /// Lets the angular-speed bound grow linearly with time: ‖ω(t0 + τ)‖ ≤ omega_max + β·τ,
    /// β = `growth` (rad/s²), for a body under a constant external torque τ_ext, where
    /// β = ‖τ_ext‖/I_min and omega_max must then be the momentum bound ‖L₀‖/I_min (eq. 2.4;
    /// the energy bound of eq. 2.5 assumes no torque). A body with growth gets no spin
    /// refinement.
    ///
    /// # Errors
    /// [`MotionError::NonFinite`] or [`MotionError::InvalidParameter`] for a NaN, infinite or
    /// negative `growth`.
    pub fn with_omega_growth(self, growth: f64) -> Result<Self, MotionError> {
        Ok(Self {
            omega_growth: non_negative("omega_growth", growth)?,
            ..self
        })
    }

    /// The growth rate β of the angular-speed bound (rad/s²; zero without torque).
    #[must_use]
    pub fn omega_growth(&self) -> f64 {
        self.omega_growth
    }

    /// Adds the spin refinement: the angular velocity `omega` (world, rad/s) now, and
    /// `alpha_max` (rad/s²) bounding ‖ω̇‖ over the flight. For a torque-free body, L = I_w·ω is
    /// constant, so I_w·ω̇ = L × ω and ‖ω̇‖ ≤ ‖L‖·ω_max / I_min
    /// ([`alpha_max_torque_free`](super::alpha_max_torque_free)).
    ///
    /// # Errors
    /// [`MotionError::NonFinite`] for a NaN or infinite `omega`; [`MotionError::InvalidParameter`]
    /// for a negative or NaN `alpha_max`.
    pub fn with_spin(self, omega: DVec3, alpha_max: f64) -> Result<Self, MotionError> {
        Ok(Self {
            spin: Some((
                finite_vec("omega", omega)?,
                non_negative("alpha_max", alpha_max)?,
            )),
            ..self
        })
    }

    /// Centre of mass at t0 (world, m).
    #[must_use]
    pub fn com(&self) -> DVec3 {
        self.com
    }

    /// Centre-of-mass velocity at t0 (world, m/s).
    #[must_use]
    pub fn velocity(&self) -> DVec3 {
        self.velocity
    }

    /// Gravitational acceleration (world, m/s²).
    #[must_use]
    pub fn gravity(&self) -> DVec3 {
        self.gravity
    }

    /// Bound on `‖ω‖` over the ballistic phase (rad/s).
    #[must_use]
    pub fn omega_max(&self) -> f64 {
        self.omega_max
    }

    /// TOI coefficients (eqs. 2.2, 2.3): the velocity of a body point is `v(t) + ω(t)×r(t)`, so
    /// its speed along d̂ is at most `[v(t0) + g·(t−t0)]·d̂ + r_max·ω_max`; integrating,
    /// `A = ½·g·d̂` and `B = v(t0)·d̂ + r_max·ω_max·|d̂|`. Exact (equality) for a body that does
    /// not rotate (`omega_max = 0`). With a growing ω bound (torque, β > 0) the rotational speed
    /// bound r_max·(ω_max + β·t) adds `½·r_max·β·|d̂|` to `A`, and an acceleration pad
    /// ([`Ballistic::with_acceleration_pad`]) adds `½·pad·|d̂|`.
    #[must_use]
    pub fn toi_coefficients(&self, d_hat: DVec3, r_max: f64) -> (f64, f64) {
        let len = d_hat.length();
        if !(len.is_finite() && r_max >= 0.0 && r_max.is_finite()) {
            return UNBOUNDED_COEFFICIENTS;
        }
        // (2.2), plus the rotational reach of the ω bound's growth under torque: ∫β·t = ½β·τ²,
        // plus the acceleration pad.
        let a = 0.5 * self.gravity.dot(d_hat)
            + 0.5 * self.accel_pad * len
            + 0.5 * r_max * self.omega_growth * len;
        let b = self.velocity.dot(d_hat) + r_max * self.omega_max * len; // (2.3)
        (a, b)
    }

    /// TOI coefficients for closing `gap`, the tighter of two bounds on the rotational part of
    /// a point's displacement along d̂. The thesis's (eq. 2.3, [`Ballistic::toi_coefficients`]):
    /// r_max·ω_max·τ. With the spin refinement: a point r moves along d̂ at
    /// (ω × r)·d̂ = r·(d̂ × ω) ≤ r_max·‖d̂ × ω(t)‖ ≤ r_max·(‖d̂ × ω₀‖ + α_max·t), so its
    /// rotational displacement is at most r_max·(‖d̂ × ω₀‖·τ + ½·α_max·τ²): coefficients
    /// `A = ½·g·d̂ + ½·r_max·α_max·|d̂|`, `B = v·d̂ + r_max·‖d̂ × ω₀‖`. Both hold for every τ; the
    /// one whose own time to close `gap` is later is returned (either is conservative).
    #[must_use]
    pub fn toi_coefficients_for_gap(&self, d_hat: DVec3, r_max: f64, gap: f64) -> (f64, f64) {
        let base = self.toi_coefficients(d_hat, r_max);
        let Some((omega, alpha)) = self.spin else {
            return base;
        };
        if self.omega_growth > 0.0 || self.accel_pad > 0.0 {
            return base; // the spin refinement assumes no torque and a known acceleration
        }
        if base == UNBOUNDED_COEFFICIENTS || !gap.is_finite() {
            return base;
        }
        let len = d_hat.length();
        let refined = (
            0.5 * self.gravity.dot(d_hat) + 0.5 * r_max * alpha * len,
            self.velocity.dot(d_hat) + r_max * d_hat.cross(omega).length(),
        );
        if crate::root::closing_time(gap, refined.0, refined.1)
            > crate::root::closing_time(gap, base.0, base.1)
        {
            refined
        } else {
            base
        }
    }

    /// Box enclosing the COM parabola between t0 and `t0 + dt` (either order of the two
    /// times): both endpoints, plus on each axis k with `g_k ≠ 0` the apex
    /// `p_k − v_k²/(2g_k)` when its time `−v_k/g_k` lies strictly between 0 and `dt`. Padded by
    /// [`SWEPT_BOX_ROUNDING_REL`](super::SWEPT_BOX_ROUNDING_REL). A NaN or infinite `dt` gives
    /// the box of all space.
    #[must_use]
    pub fn swept_com_aabb(&self, dt: f64) -> Aabb {
        if !dt.is_finite() {
            return ALL_SPACE;
        }
        let end = self.com_at(dt);
        let mut b = Aabb::new(self.com, end);
        let (lo, hi) = if dt >= 0.0 { (0.0, dt) } else { (dt, 0.0) };
        for k in 0..3 {
            let (p, v, g) = (self.com[k], self.velocity[k], self.gravity[k]);
            if g != 0.0 {
                let t_apex = -v / g;
                if lo < t_apex && t_apex < hi {
                    let apex = p - v * v / (2.0 * g);
                    b.min[k] = b.min[k].min(apex);
                    b.max[k] = b.max[k].max(apex);
                }
            }
        }
        // Any acceleration within the pad moves the centre at most ½·pad·Δt² from the
        // parabola along any axis.
        let spread = 0.5 * self.accel_pad * (dt * dt);
        let b = Aabb {
            min: b.min - DVec3::splat(spread),
            max: b.max + DVec3::splat(spread),
        };
        let scale =
            self.com.abs() + self.velocity.abs() * dt.abs() + 0.5 * self.gravity.abs() * (dt * dt);
        pad(b, scale)
    }

    /// Centre of mass at `t0 + dt` (world, m): `com + v·dt + ½·g·dt²`.
    #[must_use]
    pub fn com_at(&self, dt: f64) -> DVec3 {
        self.com + self.velocity * dt + self.gravity * (0.5 * dt * dt)
    }

    /// Centre-of-mass velocity at `t0 + dt` (world, m/s): `v + g·dt`.
    #[must_use]
    pub fn com_velocity_at(&self, dt: f64) -> DVec3 {
        self.velocity + self.gravity * dt
    }

    /// The same motion re-based at `t0 + dt` (COM and velocity advanced; gravity and
    /// `omega_max` kept, since the ω bound holds for the whole ballistic phase).
    ///
    /// # Errors
    /// [`MotionError::NonFinite`] when `dt` is not finite or the advanced state overflows.
    pub fn advance(&self, dt: f64) -> Result<Self, MotionError> {
        finite_scalar("dt", dt)?;
        // Under torque the bound at the new t0 has grown by β·|dt|.
        let omega_max = self.omega_max + self.omega_growth * dt.abs();
        Self::new(
            self.com_at(dt),
            self.com_velocity_at(dt),
            self.gravity,
            omega_max,
        )?
        .with_omega_growth(self.omega_growth)?
        .with_acceleration_pad(self.accel_pad)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::testkit::*;
    use crate::motion::*;
    use glam::DVec3;
    use impulse_geom::Aabb;
    use rand::RngExt;

    /// The spin refinement: for directions near the spin axis (where it is chosen) and random
    /// ones, the coefficients returned for a small gap bound every vertex's displacement over a
    /// tumbling box's trajectory (RK4 reference), and near the axis they are tighter than
    /// eq. 2.3.
    #[test]
    fn spin_refined_coefficients_bound_every_vertex() {
        const CASES: usize = 32;
        let mut rng = rng(77);
        let (mut refined_used, mut checked) = (0, 0);
        for case in 0..CASES {
            let half = random_box(&mut rng);
            let inertia = box_inertia(half);
            let (start, v0, g) = random_launch(&mut rng, case, inertia, 2.0, 0.5);
            let w0 = start.w;
            let omega_max = omega_max_energy(inertia, w0).unwrap();
            let alpha = alpha_max_torque_free(inertia, w0).unwrap();
            let w_world = start.q * w0;
            let motion = Motion::from(
                Ballistic::new(DVec3::ZERO, v0, g, omega_max)
                    .unwrap()
                    .with_spin(w_world, alpha)
                    .unwrap(),
            );
            let r_max = half.length();
            let dirs: Vec<DVec3> = (0..12)
                .map(|k| {
                    if k < 6 {
                        (w_world.normalize() + unit_vector(&mut rng) * 0.05 * k as f64).normalize()
                    } else {
                        unit_vector(&mut rng)
                    }
                })
                .collect();
            let gap = 1e-4 * r_max;
            let coeffs: Vec<(f64, f64)> = dirs
                .iter()
                .map(|&d| motion.toi_coefficients(d, r_max, gap))
                .collect();
            let Motion::Ballistic(b) = motion else {
                unreachable!()
            };
            for (&d, &c) in dirs.iter().zip(&coeffs) {
                if c != b.toi_coefficients(d, r_max) {
                    refined_used += 1;
                    assert!(
                        crate::root::closing_time(gap, c.0, c.1) > {
                            let base = b.toi_coefficients(d, r_max);
                            crate::root::closing_time(gap, base.0, base.1)
                        }
                    );
                }
            }
            let traj = Trajectory::new(half, start, (DVec3::ZERO, v0, g), SPAN_ANGLE / omega_max);
            let v_start = traj.vertices(DVec3::ZERO, start.q);
            for (k, s) in traj.states.iter().enumerate().skip(1) {
                let tau = k as f64 * traj.h;
                let verts = traj.vertices(traj.com_at(tau), s.q);
                let scale = r_max + v0.length() * tau + g.length() * tau * tau;
                for (&d, &(a, b)) in dirs.iter().zip(&coeffs) {
                    let bound = a * tau * tau + b * tau;
                    for (x, x0) in verts.iter().zip(&v_start) {
                        checked += 1;
                        let disp = (*x - *x0).dot(d);
                        assert!(
                            disp <= bound + BOUND_SLACK_REL * scale,
                            "case {case} τ {tau}: displacement {disp} > bound {bound}"
                        );
                    }
                }
            }
        }
        assert!(
            refined_used >= CASES * 3,
            "refinement chosen {refined_used} times"
        );
        eprintln!(
            "spin refinement chosen for {refined_used} of {} directions; {checked} vertex checks",
            CASES * 12
        );
    }

    /// A padded motion bounds every path whose acceleration stays in its ball, even one whose
    /// acceleration changes at every sub-step (a load a solver resets each step): the
    /// displacement along d̂ stays under `A·τ² + B·τ` and the centre inside the swept box, and
    /// a path pushed along d̂ at the pad's rim the whole time meets the bound (it is tight).
    #[test]
    fn an_acceleration_pad_covers_every_acceleration_in_its_ball() {
        const CASES: usize = 200;
        const SUBSTEPS: usize = 64;
        let mut rng = rng(31);
        for case in 0..CASES {
            let g =
                DVec3::new(0.0, 0.0, -9.81) + unit_vector(&mut rng) * rng.random_range(0.0..5.0);
            let pad = rng.random_range(0.05..5.0);
            let v0 = unit_vector(&mut rng) * rng.random_range(0.0..2.0);
            let m = Ballistic::new(DVec3::ZERO, v0, g, 0.0)
                .unwrap()
                .with_acceleration_pad(pad)
                .unwrap();
            let d = unit_vector(&mut rng);
            let (a, b) = m.toi_coefficients(d, 0.0);
            let span = rng.random_range(0.01..0.5);
            let swept = m.swept_com_aabb(span);
            let h = span / SUBSTEPS as f64;
            let (mut x, mut v) = (DVec3::ZERO, v0);
            let (mut rim, mut rim_v) = (0.0, v0.dot(d));
            for k in 0..SUBSTEPS {
                let push = if k % 3 == 0 {
                    d
                } else {
                    unit_vector(&mut rng) * rng.random_range(0.0..1.0)
                };
                let acc = g + push * pad;
                x += v * h + acc * (0.5 * h * h);
                v += acc * h;
                rim += rim_v * h + 0.5 * (g.dot(d) + pad) * h * h;
                rim_v += (g.dot(d) + pad) * h;
                let tau = (k + 1) as f64 * h;
                let bound = a * tau * tau + b * tau;
                let slack = 1e-12 * (1.0 + bound.abs());
                assert!(
                    x.dot(d) <= bound + slack,
                    "case {case} τ {tau}: {} > {bound}",
                    x.dot(d)
                );
                assert!(
                    (rim - bound).abs() <= 1e-9 * (1.0 + bound.abs()),
                    "case {case}: not tight"
                );
                let inside =
                    (0..3).all(|i| swept.min[i] <= x[i] + slack && x[i] <= swept.max[i] + slack);
                assert!(inside, "case {case}: {x} outside {swept:?}");
            }
        }
        // Without the pad the coefficients are the thesis's (eq. 2.2).
        let plain = Ballistic::new(DVec3::ZERO, DVec3::X, DVec3::NEG_Z, 0.0).unwrap();
        assert_eq!(plain.toi_coefficients(DVec3::NEG_Z, 0.0), (0.5, 0.0));
        let padded = plain.with_acceleration_pad(2.0).unwrap();
        assert_eq!(padded.toi_coefficients(DVec3::NEG_Z, 0.0), (1.5, 0.0));
        assert!(plain.with_acceleration_pad(-1.0).is_err());
        assert!(plain.with_acceleration_pad(f64::NAN).is_err());
    }

    #[test]
    fn ballistic_coefficients_bound_every_vertex_of_a_tumbling_box() {
        const CASES: usize = 48;
        const DIRECTIONS: usize = 12;
        let mut rng = rng(2024);
        let mut worst_rot_ratio: f64 = 0.0;
        let mut worst_total_ratio: f64 = 0.0;
        let mut max_inertia_ratio: f64 = 0.0;
        let mut max_drift: f64 = 0.0;
        for case in 0..CASES {
            let half = match case {
                0 => DVec3::splat(0.5),         // cube
                1 => DVec3::new(1.4, 0.1, 0.1), // rod, ratio 98.5
                _ => random_box(&mut rng),
            };
            let inertia = box_inertia(half);
            max_inertia_ratio =
                max_inertia_ratio.max(inertia.max_element() / inertia.min_element());
            let (start, v0, g) = random_launch(&mut rng, case, inertia, 3.0, 5.0);
            let w0 = start.w;
            let omega_max = omega_max_energy(inertia, w0).unwrap();
            let traj = Trajectory::new(half, start, (DVec3::ZERO, v0, g), SPAN_ANGLE / omega_max);
            let motion = Motion::from(Ballistic::new(DVec3::ZERO, v0, g, omega_max).unwrap());
            let r_max = half.length();
            let dirs: Vec<DVec3> = (0..DIRECTIONS).map(|_| unit_vector(&mut rng)).collect();
            let coeffs: Vec<(f64, f64)> = dirs
                .iter()
                .map(|&d| motion.toi_coefficients(d, r_max, 1.0))
                .collect();
            let v_start = traj.vertices(DVec3::ZERO, start.q);
            let (e0, l0) = (start.energy2(), start.momentum_world());
            for (k, s) in traj.states.iter().enumerate().skip(1) {
                let tau = k as f64 * traj.h;
                max_drift = max_drift
                    .max((s.energy2() - e0).abs() / e0)
                    .max((s.momentum_world() - l0).length() / l0.length());
                let com = traj.com_at(tau);
                let verts = traj.vertices(com, s.q);
                let rot_bound = r_max * omega_max * tau;
                let scale = r_max + v0.length() * tau + g.length() * tau * tau;
                for (&d, &(a, b)) in dirs.iter().zip(&coeffs) {
                    let bound = a * tau * tau + b * tau;
                    for (x, x0) in verts.iter().zip(&v_start) {
                        let disp = (*x - *x0).dot(d);
                        assert!(
                            disp <= bound + BOUND_SLACK_REL * scale,
                            "case {case} τ {tau}: displacement {disp} > bound {bound}"
                        );
                        let rot = disp - (com.dot(d));
                        worst_rot_ratio = worst_rot_ratio.max(rot / rot_bound);
                        if bound > RATIO_FLOOR_REL * r_max {
                            worst_total_ratio = worst_total_ratio.max(disp / bound);
                        }
                    }
                }
            }
        }
        assert!(max_drift <= CONSERVATION_TOL, "RK4 drift {max_drift}");
        assert!(max_inertia_ratio > 90.0);
        assert!(worst_rot_ratio <= 1.0 + BOUND_SLACK_REL);
        eprintln!(
            "ballistic bound: max rotational displacement / (r_max·ω_max·τ) = \
             {worst_rot_ratio:.4}, \
             max displacement / bound = {worst_total_ratio:.4}, max RK4 drift = {max_drift:.2e}, \
             max inertia ratio = {max_inertia_ratio:.1}"
        );
    }

    #[test]
    fn ballistic_swept_box_includes_the_apex() {
        let g = DVec3::new(0.0, 0.0, -9.81);
        let throw =
            Motion::from(Ballistic::new(DVec3::ZERO, DVec3::new(1.0, 0.5, 5.0), g, 3.0).unwrap());
        let dt = 1.0; // apex at 5/9.81 ≈ 0.51 s
        let b = check_swept_box(&throw, dt, sampling_slack(9.81, dt, 10.0));
        let apex = throw.com_at(5.0 / 9.81);
        assert!(b.contains_point(apex));
        // Without the apex, the box of the endpoints alone misses the top of the throw.
        let endpoints_only =
            Aabb::new(throw.com_at(0.0), throw.com_at(dt)).expanded(ENDPOINT_BOX_MARGIN);
        assert!(!endpoints_only.contains_point(apex));
        // Apex outside the interval: endpoints suffice; negative dt covers [t0 + dt, t0].
        check_swept_box(&throw, 0.3, sampling_slack(9.81, 0.3, 10.0));
        check_swept_box(&throw, -0.7, sampling_slack(9.81, 0.7, 10.0));
        let mut rng = rng(3);
        for _ in 0..300 {
            let m = Motion::from(
                Ballistic::new(
                    unit_vector(&mut rng) * rng.random_range(0.0..100.0),
                    unit_vector(&mut rng) * rng.random_range(0.0..20.0),
                    unit_vector(&mut rng) * rng.random_range(0.0..20.0),
                    0.0,
                )
                .unwrap(),
            );
            let dt = rng.random_range(0.0..4.0);
            check_swept_box(&m, dt, sampling_slack(20.0, dt, 500.0));
        }
        assert_eq!(throw.swept_com_aabb(f64::NAN), ALL_SPACE);
        assert_eq!(throw.swept_com_aabb(f64::INFINITY), ALL_SPACE);
    }

    /// Under a constant external torque the momentum bound grows linearly (‖ω‖ ≤ ‖L₀ + τt‖ /
    /// I_min): the coefficients with that growth bound every vertex of a box spun up by a
    /// random torque (RK4 reference with the torque), and without the growth they do not.
    #[test]
    fn torque_growth_coefficients_bound_every_vertex() {
        const CASES: usize = 24;
        const DIRECTIONS: usize = 12;
        let mut rng = rng(2025);
        let mut violated_without_growth = 0;
        for case in 0..CASES {
            let half = random_box(&mut rng);
            let inertia = box_inertia(half);
            let (mut start, v0, g) = random_launch(&mut rng, case, inertia, 1.0, 5.0);
            let i_min = inertia.min_element();
            // Torque large enough to change ω by ~10 rad/s over the span.
            start.torque = unit_vector(&mut rng) * (i_min * rng.random_range(1.0..20.0));
            let w_max = omega_max_momentum(inertia, start.w).unwrap();
            let beta = start.torque.length() / i_min;
            let span = 2.0;
            let traj = Trajectory::new(half, start, (DVec3::ZERO, v0, g), span);
            let plain = Ballistic::new(DVec3::ZERO, v0, g, w_max).unwrap();
            let grown = Motion::from(plain.with_omega_growth(beta).unwrap());
            let plain = Motion::from(plain);
            let r_max = half.length();
            let v_start = traj.vertices(DVec3::ZERO, start.q);
            let dirs: Vec<DVec3> = (0..DIRECTIONS).map(|_| unit_vector(&mut rng)).collect();
            for (k, s) in traj.states.iter().enumerate().skip(1) {
                let tau = k as f64 * traj.h;
                let verts = traj.vertices(traj.com_at(tau), s.q);
                let scale = r_max + v0.length() * tau + g.length() * tau * tau;
                for &d in &dirs {
                    let (a, b) = grown.toi_coefficients(d, r_max, 1.0);
                    let (pa, pb) = plain.toi_coefficients(d, r_max, 1.0);
                    for (x, x0) in verts.iter().zip(&v_start) {
                        let disp = (*x - *x0).dot(d);
                        assert!(
                            disp <= a * tau * tau + b * tau + BOUND_SLACK_REL * scale,
                            "case {case} τ {tau}: displacement {disp} above the torque bound"
                        );
                        if disp > pa * tau * tau + pb * tau + BOUND_SLACK_REL * scale {
                            violated_without_growth += 1;
                        }
                    }
                }
            }
            // Re-basing keeps the bound valid: the advanced motion's ω bound has grown.
            let Motion::Ballistic(b) = grown.advance(0.5).unwrap() else {
                unreachable!()
            };
            assert!((b.omega_max() - (w_max + 0.5 * beta)).abs() <= 1e-12 * b.omega_max());
        }
        assert!(
            violated_without_growth > 0,
            "the torque never outran the plain bound"
        );
        eprintln!("torque: {violated_without_growth} vertex samples beat the bound without growth");
    }
}
