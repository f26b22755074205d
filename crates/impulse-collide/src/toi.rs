//! Conservative time-of-impact (TOI) lower bounds for a pair of convex bodies (thesis §2.3.2).
//!
//! Let c1, c2 be the closest points of two convex bodies at the current time t0, `gap = |c2 −
//! c1|` (m) and `d̂ = (c2 − c1)/gap` (world frame, pointing from body 1 to body 2). By convexity
//! body 1 lies behind the plane through c1 normal to d̂ and body 2 beyond the parallel plane
//! through c2; whichever points finally touch must together close the gap along d̂. If
//! `A1·τ² + B1·τ` bounds how far any point of body 1 moves along +d̂ in time τ, and
//! `A2·τ² + B2·τ` how far any point of body 2 moves along −d̂ (eq. 2.13,
//! [`crate::motion::Motion::toi_coefficients`]), then no contact can happen before the smallest
//! τ > 0 with
//!
//! `(A1 + A2)·τ² + (B1 + B2)·τ = gap`.
//!
//! [`pair_toi`] solves this; [`toi_lower_bound`] also gathers the coefficients. Both return τ
//! **relative to t0** (s); the collision heap stores the absolute time `t0 + τ`.

use glam::DVec3;

use crate::motion::Motion;
pub use crate::root::closing_time;

/// Smallest τ > 0 (s) with `(a1 + a2)·τ² + (b1 + b2)·τ = gap`: the two bodies' coefficients
/// summed, then [`closing_time`] (see there for every case, including non-finite input).
#[must_use]
pub fn pair_toi(gap: f64, (a1, b1): (f64, f64), (a2, b2): (f64, f64)) -> f64 {
    closing_time(gap, a1 + a2, b1 + b2)
}

/// Lower bound on the time of impact (s after t0) of two convex bodies whose closest points are
/// `gap` (m) apart along `d_hat` (world frame, unit, **from body 1 toward body 2**).
///
/// Body 1's coefficients are taken along `+d_hat`, body 2's along `−d_hat` (thesis §2.3.2), each
/// with its own `r_max` (m, largest distance of a body point from its centre of mass) and the
/// shared `gap` (for the cycler/oscillator model choice); the sum is solved by [`pair_toi`].
/// For two ballistic bodies under the same gravity the `A` terms cancel exactly and the equation
/// is linear. Invalid inputs follow [`crate::motion::Motion::toi_coefficients`] and
/// [`pair_toi`]: they give 0 (check immediately), never a panic.
#[must_use]
pub fn toi_lower_bound(
    gap: f64,
    d_hat: DVec3,
    motion_1: &Motion,
    r_max_1: f64,
    motion_2: &Motion,
    r_max_2: f64,
) -> f64 {
    let c1 = motion_1.toi_coefficients(d_hat, r_max_1, gap);
    let c2 = motion_2.toi_coefficients(-d_hat, r_max_2, gap);
    pair_toi(gap, c1, c2)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::testkit::{
        Trajectory, Tumbler, box_inertia, random_rotation, rng, unit_vector,
    };
    use crate::motion::{Ballistic, omega_max_energy};
    use rand::RngExt;

    /// Closed-form cases whose bound is exact: a few ulps of the result.
    const EXACT_REL: f64 = 4.0 * f64::EPSILON;
    /// Slack of "TOI ≤ true contact time", relative: RK4 reference error (~1e-12).
    const CONSERVATIVE_SLACK_REL: f64 = 1e-9;
    /// Collision epsilon ε_c of the one-sided iterations, relative to the box's r_max.
    const EPS_C_REL: f64 = 1e-3;
    /// Bisection steps refining the true contact time between two grid samples.
    const CONTACT_BISECTIONS: usize = 60;
    /// Free-fall check: the block's face is at the floor at the computed τ, relative to the
    /// height (rounding of √ and of the parabola).
    const FALL_POSITION_TOL_REL: f64 = 1e-12;
    /// Upper limit on checks of one one-sided iteration (termination check).
    const MAX_CHECKS: usize = 20_000;

    #[test]
    fn root_selection_covers_every_case() {
        let inf = f64::INFINITY;
        // a > 0: one positive root, whatever b.
        assert_eq!(pair_toi(2.0, (1.0, 1.0), (0.0, 0.0)), 1.0); // τ² + τ = 2
        assert_eq!(pair_toi(2.0, (1.0, -1.0), (0.0, 0.0)), 2.0); // τ² − τ = 2
        assert_eq!(pair_toi(4.0, (1.0, 0.0), (0.0, 0.0)), 2.0);
        // a = 0.
        assert_eq!(pair_toi(3.0, (0.0, 1.5), (0.0, 0.0)), 2.0);
        assert_eq!(pair_toi(3.0, (0.0, 0.0), (0.0, 0.0)), inf);
        assert_eq!(pair_toi(3.0, (0.0, -1.0), (0.0, 0.0)), inf);
        // a < 0 with real roots 1 and 3 (−τ² + 4τ = 3): the smaller one.
        assert_eq!(pair_toi(3.0, (-1.0, 4.0), (0.0, 0.0)), 1.0);
        // a < 0, double root τ = 2 (−τ² + 4τ = 4).
        assert_eq!(pair_toi(4.0, (-1.0, 4.0), (0.0, 0.0)), 2.0);
        // a < 0, the bound peaks below the gap; a < 0 and b ≤ 0.
        assert_eq!(pair_toi(5.0, (-1.0, 4.0), (0.0, 0.0)), inf);
        assert_eq!(pair_toi(1.0, (-1.0, 0.0), (0.0, 0.0)), inf);
        assert_eq!(pair_toi(1.0, (-1.0, -2.0), (0.0, 0.0)), inf);
        // Separating pair, gravity cancelling: ∞.
        assert_eq!(pair_toi(1.0, (4.9, -1.0), (-4.9, -0.5)), inf);
        // Gap ≤ 0: check now.
        assert_eq!(pair_toi(0.0, (1.0, 1.0), (0.0, 0.0)), 0.0);
        assert_eq!(pair_toi(-1e-9, (-1.0, -1.0), (0.0, 0.0)), 0.0);
        // Coefficients are summed.
        assert_eq!(pair_toi(2.0, (0.25, 0.5), (0.75, 0.5)), 1.0);
        // Non-finite input: NaN or an unbounded motion → 0; infinitely far or receding → ∞.
        assert_eq!(pair_toi(f64::NAN, (1.0, 1.0), (0.0, 0.0)), 0.0);
        assert_eq!(pair_toi(1.0, (f64::NAN, 1.0), (0.0, 0.0)), 0.0);
        assert_eq!(pair_toi(1.0, (0.0, inf), (0.0, -1.0)), 0.0);
        assert_eq!(pair_toi(1.0, (inf, -inf), (0.0, 0.0)), 0.0);
        assert_eq!(pair_toi(inf, (1.0, 1.0), (0.0, 0.0)), inf);
        assert_eq!(pair_toi(1.0, (1.0, -inf), (0.0, 0.0)), inf);
        assert_eq!(pair_toi(1.0, (f64::MAX, 0.0), (f64::MAX, 0.0)), 0.0); // a overflows to +∞
    }

    fn resting(com: DVec3, velocity: DVec3, g: DVec3) -> Motion {
        Ballistic::new(com, velocity, g, 0.0).unwrap().into()
    }

    #[test]
    fn exact_cases_give_the_true_contact_time() {
        let floor = Motion::fixed(DVec3::ZERO).unwrap();
        let half = 0.5;
        let r_max = half * 3f64.sqrt();
        // A block released at rest with its lower face at height h: free fall, √(2h/g).
        for (h, g) in [(1.0, 9.81), (1e-3, 9.81), (250.0, 1.62), (1e-9, 9.81)] {
            let block = resting(
                DVec3::new(0.3, -0.2, h + half),
                DVec3::ZERO,
                DVec3::new(0.0, 0.0, -g),
            );
            let tau = toi_lower_bound(h, DVec3::NEG_Z, &block, r_max, &floor, 0.0);
            let want = (2.0 * h / g).sqrt();
            assert!(
                (tau - want).abs() <= EXACT_REL * want,
                "h {h}: {tau} vs {want}"
            );
            assert!((block.com_at(tau).z - half).abs() <= FALL_POSITION_TOL_REL * (h + 1.0));
        }
        // A cube sliding at v straight at a wall, gravity along the wall: d / v.
        for (d, v) in [(2.0, 3.0), (1e-6, 40.0), (30.0, 1e-3)] {
            let cube = resting(
                DVec3::new(-d - half, 0.0, 1.0),
                DVec3::X * v,
                DVec3::new(0.0, 0.0, -9.81),
            );
            let tau = toi_lower_bound(d, DVec3::X, &cube, r_max, &floor, 0.0);
            assert!((tau - d / v).abs() <= EXACT_REL * (d / v));
        }
        // Two ballistic cubes approaching face to face, any gravity: A cancels exactly.
        let mut rng = rng(12);
        for _ in 0..1000 {
            let n = unit_vector(&mut rng);
            let g = unit_vector(&mut rng) * 9.81;
            let (v1, v2) = (rng.random_range(0.1..10.0), rng.random_range(0.1..10.0));
            let d = rng.random_range(1e-4..5.0);
            let side = n.any_orthonormal_vector() * rng.random_range(-1.0..1.0);
            let c1 = resting(DVec3::ZERO, n * v1 + side, g);
            let c2 = resting(n * (d + 2.0 * half), -n * v2 + side, g);
            let (a1, b1) = c1.toi_coefficients(n, r_max, d);
            let (a2, b2) = c2.toi_coefficients(-n, r_max, d);
            assert_eq!(a1 + a2, 0.0);
            let tau = toi_lower_bound(d, n, &c1, r_max, &c2, r_max);
            let want = d / (v1 + v2);
            assert!(
                (tau - want).abs() <= EXACT_REL * want,
                "{tau} vs {want} (b {b1} {b2})"
            );
        }
    }

    /// One-sided iteration (§2.3) on a tumbling box against another body whose distance and
    /// direction at time t are given by `probe`; checks every estimate stays at or before the
    /// true first contact, found by dense sampling and bisection. Returns (checks, last t /
    /// true t), or `None` when there is no contact within the span.
    fn one_sided_iteration(
        traj: &Trajectory,
        omega_max: f64,
        other: &dyn Fn(f64) -> (Motion, f64),
        probe: &dyn Fn(f64, &Tumbler) -> (f64, DVec3),
    ) -> Option<(usize, f64)> {
        let dist = |t: f64| probe(t, &traj.state_at(t)).0;
        let k =
            (0..traj.states.len()).find(|&k| probe(k as f64 * traj.h, &traj.states[k]).0 <= 0.0)?;
        assert!(k > 0, "starts in contact");
        let (mut lo, mut hi) = ((k - 1) as f64 * traj.h, k as f64 * traj.h);
        for _ in 0..CONTACT_BISECTIONS {
            let mid = 0.5 * (lo + hi);
            if dist(mid) > 0.0 { lo = mid } else { hi = mid }
        }
        let t_true = lo;
        let r_max = traj.half.length();
        let eps_c = EPS_C_REL * r_max;
        let mut t = 0.0;
        for checks in 1..=MAX_CHECKS {
            let (gap, d_hat) = probe(t, &traj.state_at(t));
            if gap < eps_c {
                return Some((checks, t / t_true));
            }
            let me: Motion =
                Ballistic::new(traj.com_at(t), traj.v0 + traj.g * t, traj.g, omega_max)
                    .unwrap()
                    .into();
            let (them, r_them) = other(t);
            let tau = toi_lower_bound(gap, d_hat, &me, r_max, &them, r_them);
            assert!(tau > 0.0);
            t += tau;
            assert!(
                t <= t_true * (1.0 + CONSERVATIVE_SLACK_REL),
                "TOI {t} after contact {t_true}"
            );
        }
        panic!("no convergence in {MAX_CHECKS} checks");
    }

    fn tumbling_box(
        rng: &mut rand::rngs::Xoshiro256PlusPlus,
        com0: DVec3,
        v0: DVec3,
        g: DVec3,
        span: f64,
    ) -> (Trajectory, f64) {
        let half = DVec3::new(
            rng.random_range(0.1..1.0),
            rng.random_range(0.1..1.0),
            rng.random_range(0.1..1.0),
        );
        let inertia = box_inertia(half);
        let w = unit_vector(rng) * 10f64.powf(rng.random_range(-1.0..2.0));
        let start = Tumbler {
            torque: DVec3::ZERO,
            inertia,
            q: random_rotation(rng),
            w,
        };
        (
            Trajectory::new(half, start, (com0, v0, g), span),
            omega_max_energy(inertia, w).unwrap(),
        )
    }

    #[test]
    fn estimates_never_pass_the_contact_of_a_tumbling_box_with_a_floor_or_ramp() {
        let mut rng = rng(99);
        let g = DVec3::new(0.0, 0.0, -9.81);
        let (mut hits, mut total_checks, mut closest) = (0, 0, 1.0f64);
        for case in 0..60 {
            // Floor for even cases, a ramp tilted up to 40° otherwise; both through the origin.
            let n = if case % 2 == 0 {
                DVec3::Z
            } else {
                tilted_normal(unit_vector(&mut rng), rng.random_range(0.0..0.7))
            };
            let height = rng.random_range(0.5..3.0) + 1.8;
            let v0 = unit_vector(&mut rng) * rng.random_range(0.0..3.0);
            let (traj, omega_max) = tumbling_box(&mut rng, n * height, v0, g, 2.0);
            let floor = Motion::fixed(DVec3::ZERO).unwrap();
            let probe = |t: f64, s: &Tumbler| {
                let lowest = traj
                    .vertices(traj.com_at(t), s.q)
                    .iter()
                    .map(|v| v.dot(n))
                    .fold(f64::INFINITY, f64::min);
                (lowest, -n)
            };
            if let Some((checks, ratio)) =
                one_sided_iteration(&traj, omega_max, &|_| (floor, 0.0), &probe)
            {
                hits += 1;
                total_checks += checks;
                closest = closest.min(ratio);
            }
        }
        assert!(hits >= 50, "{hits}");
        eprintln!(
            "box vs floor/ramp: {hits} contacts, {:.1} checks each on average, \
             last estimate / true contact time ≥ {closest:.6}",
            total_checks as f64 / f64::from(hits)
        );
    }

    /// +z tilted by `angle` (rad) about a horizontal axis derived from `hint`.
    fn tilted_normal(hint: DVec3, angle: f64) -> DVec3 {
        let axis = hint.cross(DVec3::Z).try_normalize().unwrap_or(DVec3::X);
        glam::DQuat::from_axis_angle(axis, angle) * DVec3::Z
    }

    #[test]
    fn estimates_never_pass_the_contact_of_a_tumbling_box_with_a_ball() {
        let mut rng = rng(123);
        let (mut hits, mut total_checks) = (0, 0);
        for case in 0..60 {
            let g = if case % 3 == 0 {
                DVec3::ZERO
            } else {
                unit_vector(&mut rng) * 9.81
            };
            let v_box = unit_vector(&mut rng) * rng.random_range(0.0..1.0);
            let (traj, omega_box) = tumbling_box(&mut rng, DVec3::ZERO, v_box, g, 1.5);
            let radius = rng.random_range(0.05..0.8);
            let dir = unit_vector(&mut rng);
            let c0 = dir * (traj.half.length() + radius + rng.random_range(0.2..3.0));
            let speed = rng.random_range(2.0..8.0);
            let u = -dir * speed + dir.any_orthonormal_vector() * rng.random_range(-1.0..1.0);
            let spin_ball = rng.random_range(0.0..50.0);
            let ball_at = move |t: f64| c0 + u * t + g * (0.5 * t * t);
            let other = |t: f64| {
                let m: Motion = Ballistic::new(ball_at(t), u + g * t, g, spin_ball)
                    .unwrap()
                    .into();
                (m, radius)
            };
            let probe = |t: f64, s: &Tumbler| {
                let com = traj.com_at(t);
                let local = s.q.inverse() * (ball_at(t) - com);
                let nearest = local.clamp(-traj.half, traj.half);
                let offset = local - nearest;
                let len = offset.length();
                if len == 0.0 {
                    (-radius, DVec3::Z) // centre inside the box: penetrating
                } else {
                    (len - radius, s.q * (offset / len))
                }
            };
            if let Some((checks, _)) = one_sided_iteration(&traj, omega_box, &other, &probe) {
                hits += 1;
                total_checks += checks;
            }
        }
        assert!(hits >= 30, "{hits}");
        eprintln!(
            "box vs ball: {hits} contacts, {:.1} checks each on average",
            total_checks as f64 / f64::from(hits)
        );
    }
}
