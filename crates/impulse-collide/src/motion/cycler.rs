//! The cycler (thesis §2.5): circular centre-of-mass motion at fixed orientation.

use glam::DVec3;
use impulse_geom::Aabb;

use super::*;

/// Scripted circular motion (thesis §2.5, "cycler"): the centre of mass moves on a circle at a
/// constant angular rate Ω while the orientation stays fixed (ω = 0, so every body point moves
/// like the COM).
///
/// World frame: `p(τ) = centre + r·(cos θ(τ)·e1 + sin θ(τ)·e2)`, `θ(τ) = phase + Ω·τ`, with
/// `centre` (m), orthonormal plane axes `e1`, `e2`, radius `r ≥ 0` (m), rate Ω (rad/s, either
/// sign) and `phase` θ(t0) (rad, stored in `[0, 2π)`). Speed `r·|Ω|`, centripetal acceleration
/// `r·Ω²`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cycler {
    centre: DVec3,
    e1: DVec3,
    e2: DVec3,
    radius: f64,
    rate: f64,
    phase: f64,
}

impl Cycler {
    /// A cycler from its circle (world frame) and its phase at t0.
    ///
    /// `e1` and `e2` must be orthonormal within [`CYCLER_AXES_TOLERANCE`]; they are then
    /// re-orthonormalised.
    ///
    /// # Errors
    /// [`MotionError::NonFinite`] for NaN or infinite input; [`MotionError::InvalidParameter`]
    /// for a negative radius or axes that are not orthonormal.
    pub fn new(
        centre: DVec3,
        e1: DVec3,
        e2: DVec3,
        radius: f64,
        rate: f64,
        phase: f64,
    ) -> Result<Self, MotionError> {
        let centre = finite_vec("centre", centre)?;
        let e1 = finite_vec("e1", e1)?;
        let e2 = finite_vec("e2", e2)?;
        let radius = non_negative("radius", radius)?;
        let rate = finite_scalar("rate", rate)?;
        let phase = finite_scalar("phase", phase)?;
        for (name, value) in [
            ("|e1| - 1", e1.length() - 1.0),
            ("|e2| - 1", e2.length() - 1.0),
            ("e1.e2", e1.dot(e2)),
        ] {
            if value.abs() > CYCLER_AXES_TOLERANCE {
                return Err(MotionError::InvalidParameter {
                    name,
                    value,
                    requirement: "cycler axes must be orthonormal (see CYCLER_AXES_TOLERANCE)",
                });
            }
        }
        let e1 = e1.normalize();
        let e2 = (e2 - e1 * e1.dot(e2)).normalize();
        Ok(Self {
            centre,
            e1,
            e2,
            radius,
            rate,
            phase: wrap_angle(phase),
        })
    }

    /// Centre of the circle (world, m).
    #[must_use]
    pub fn centre(&self) -> DVec3 {
        self.centre
    }

    /// The orthonormal plane axes `(e1, e2)` (world, unit).
    #[must_use]
    pub fn axes(&self) -> (DVec3, DVec3) {
        (self.e1, self.e2)
    }

    /// Radius r (m).
    #[must_use]
    pub fn radius(&self) -> f64 {
        self.radius
    }

    /// Angular rate Ω of the COM around the circle (rad/s; positive from e1 toward e2).
    #[must_use]
    pub fn rate(&self) -> f64 {
        self.rate
    }

    /// Phase θ(t0) in `[0, 2π)` (rad).
    #[must_use]
    pub fn phase(&self) -> f64 {
        self.phase
    }

    /// Linear model (eq. 2.14): the speed is always `r|Ω|`, so `(0, r|Ω|·|d̂|)`.
    pub(super) fn linear_coefficients(&self, d_hat: DVec3) -> (f64, f64) {
        (0.0, self.radius * self.rate.abs() * d_hat.length())
    }

    /// Quadratic model (eq. 2.15): the velocity along d̂ starts at `v(t0)·d̂` and changes at
    /// most at the centripetal rate `rΩ²`, so `(½rΩ²·|d̂|, v(t0)·d̂)`.
    pub(super) fn quadratic_coefficients(&self, d_hat: DVec3) -> (f64, f64) {
        let a = 0.5 * self.radius * self.rate * self.rate * d_hat.length();
        (a, self.com_velocity_at(0.0).dot(d_hat))
    }

    /// TOI coefficients: eq. (2.14) `(0, r|Ω|)` or eq. (2.15) `(½rΩ², v(t0)·d̂)` (speed terms
    /// times `|d̂|`), chosen by the thesis rule: the two bounds are equal at
    /// `D* = 2[r|Ω| − v(t0)·d̂]/|Ω|`; if `D* > gap` (the
    /// current distance to the other body, m) the quadratic one is returned (it is tighter up to
    /// D*), otherwise the linear one. Both are valid bounds for every τ; `r_max` is not needed
    /// (no rotation). A NaN `gap` selects the linear model; a non-finite `d_hat` gives
    /// [`UNBOUNDED_COEFFICIENTS`].
    #[must_use]
    pub fn toi_coefficients(&self, d_hat: DVec3, gap: f64) -> (f64, f64) {
        if !d_hat.is_finite() {
            return UNBOUNDED_COEFFICIENTS;
        }
        let (_, b_lin) = self.linear_coefficients(d_hat);
        let (a_quad, b_quad) = self.quadratic_coefficients(d_hat);
        select_model(self.rate, b_lin, a_quad, b_quad, gap)
    }

    /// Box enclosing the COM arc between t0 and `t0 + dt` (either order): per axis k the
    /// coordinate is `c_k + r·R_k·cos(θ − α_k)` with `R_k = |(e1_k, e2_k)|`,
    /// `α_k = atan2(e2_k, e1_k)`, so the box holds both endpoints and every axis extremum
    /// (`θ = α_k` or `α_k + π`, mod 2π) the arc passes; if `|Ω·dt| ≥ 2π` it is the whole
    /// circle's box. Padded by [`SWEPT_BOX_ROUNDING_REL`]. NaN `dt` gives the box of all space;
    /// an infinite `dt` the whole circle's box.
    #[must_use]
    pub fn swept_com_aabb(&self, dt: f64) -> Aabb {
        if dt.is_nan() {
            return ALL_SPACE;
        }
        let sweep = if dt.is_infinite() {
            f64::INFINITY
        } else {
            self.rate * dt
        };
        let (t_lo, t_hi) = if sweep.is_infinite() {
            (0.0, f64::INFINITY)
        } else if sweep >= 0.0 {
            (self.phase, self.phase + sweep)
        } else {
            (self.phase + sweep, self.phase)
        };
        let mut min = DVec3::ZERO;
        let mut max = DVec3::ZERO;
        for k in 0..3 {
            let (x, y) = (self.e1[k], self.e2[k]);
            let amp = self.radius * x.hypot(y);
            let alpha = y.atan2(x);
            let (c_min, c_max) = cos_range(t_lo - alpha, t_hi - alpha);
            min[k] = self.centre[k] + amp * c_min;
            max[k] = self.centre[k] + amp * c_max;
        }
        let mut b = Aabb { min, max };
        if dt.is_finite() {
            b = Aabb::from_points([b.min, b.max, self.com_at(0.0), self.com_at(dt)]);
        }
        pad(b, self.centre.abs() + DVec3::splat(self.radius))
    }

    /// Centre of mass at `t0 + dt` (world, m).
    #[must_use]
    pub fn com_at(&self, dt: f64) -> DVec3 {
        let (s, c) = (self.phase + self.rate * dt).sin_cos();
        self.centre + (self.e1 * c + self.e2 * s) * self.radius
    }

    /// Centre-of-mass velocity at `t0 + dt` (world, m/s): `rΩ·(−sin θ·e1 + cos θ·e2)`.
    #[must_use]
    pub fn com_velocity_at(&self, dt: f64) -> DVec3 {
        let (s, c) = (self.phase + self.rate * dt).sin_cos();
        (self.e2 * c - self.e1 * s) * (self.radius * self.rate)
    }

    /// The same motion re-based at `t0 + dt` (phase advanced by `Ω·dt`, wrapped to `[0, 2π)`).
    ///
    /// # Errors
    /// [`MotionError::NonFinite`] when `dt` or the new phase is not finite.
    pub fn advance(&self, dt: f64) -> Result<Self, MotionError> {
        finite_scalar("dt", dt)?;
        let phase = finite_scalar("phase", self.phase + self.rate * dt)?;
        Ok(Self {
            phase: wrap_angle(phase),
            ..*self
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::testkit::*;
    use core::f64::consts::{PI, TAU};
    use glam::{DQuat, DVec3};
    use impulse_geom::Aabb;
    use rand::RngExt;

    /// Axis extrema (multiples of π/2) strictly inside the phase interval.
    fn extrema_crossed(phase: f64, sweep: f64) -> usize {
        let (lo, hi) = (phase.min(phase + sweep), phase.max(phase + sweep));
        (-20..20)
            .filter(|&n| {
                let t = f64::from(n) * 0.5 * PI;
                lo < t && t < hi
            })
            .count()
    }

    #[test]
    fn cycler_swept_box_covers_arcs_across_axis_extrema() {
        let centre = DVec3::new(1.0, -2.0, 3.0);
        let (r, rate) = (2.0, 1.5);
        // (phase, sweep Ω·dt, number of axis extrema crossed)
        let arcs = [
            (0.2, 1.0, 0),
            (0.2, 1.5, 1),
            (1.4, 2.0, 2),
            (0.1, 4.8, 3),
            (0.3, 6.0, 4),
            (5.9, 1.0, 1), // crosses θ = 2π
        ];
        for (phase, sweep, crossed) in arcs {
            assert_eq!(extrema_crossed(phase, sweep), crossed);
            // The same arc traversed both ways.
            for (start, signed_rate) in [(phase, rate), (phase + sweep, -rate)] {
                let c = Cycler::new(centre, DVec3::X, DVec3::Y, r, signed_rate, start).unwrap();
                let dt = sweep / rate;
                check_swept_box(&c.into(), dt, sampling_slack(r * rate * rate, dt, 10.0));
            }
        }
        // A full turn or more: the whole circle's box.
        let c = Cycler::new(centre, DVec3::X, DVec3::Y, r, rate, 0.7).unwrap();
        for dt in [TAU / rate, 10.0, f64::INFINITY] {
            let b = c.swept_com_aabb(dt);
            let full = Aabb::new(
                centre - DVec3::new(r, r, 0.0),
                centre + DVec3::new(r, r, 0.0),
            );
            assert!((b.min - full.min).abs().max_element() <= FULL_PATH_TOL);
            assert!((b.max - full.max).abs().max_element() <= FULL_PATH_TOL);
        }
        // Tilted planes, random phases and sweeps.
        let mut rng = rng(9);
        for _ in 0..300 {
            let e1 = unit_vector(&mut rng);
            let e2 = e1.any_orthonormal_vector();
            let q = DQuat::from_axis_angle(e1, rng.random_range(0.0..TAU));
            let c = Cycler::new(
                unit_vector(&mut rng) * 5.0,
                e1,
                q * e2,
                rng.random_range(0.0..3.0),
                rng.random_range(-4.0..4.0),
                rng.random_range(-10.0..10.0),
            )
            .unwrap();
            let dt = rng.random_range(0.0..3.0);
            let acc = c.radius() * c.rate() * c.rate();
            check_swept_box(&c.into(), dt, sampling_slack(acc, dt, 10.0));
        }
        assert_eq!(Motion::from(c).swept_com_aabb(f64::NAN), ALL_SPACE);
    }
}
