//! The oscillator: sinusoidal translation at fixed orientation.

use glam::DVec3;
use impulse_geom::Aabb;

use super::*;

/// Scripted sinusoidal translation at fixed orientation (a vibrating feeder tray):
/// `p(τ) = centre + a·sin(ω·τ + φ)·axis`.
///
/// World frame: `centre` (m), unit `axis`, amplitude `a ≥ 0` (m), angular frequency ω (rad/s),
/// phase φ at t0 (rad, stored in `[0, 2π)`). Velocity `aω·cos(ωτ + φ)·axis`, acceleration
/// `−aω²·sin(ωτ + φ)·axis`.
///
/// Coefficients (every point moves like the COM): with `s = axis·d̂`, the rate along d̂ is
/// `aω·cos(ωτ + φ)·s`, so
/// - linear: speed along d̂ ≤ `a|ω||s|`, giving `(0, a|ω||s|)`;
/// - quadratic: it starts at `v(t0)·d̂ = aω·cos φ·s` and changes at most at `aω²|s|`, giving
///   `(½aω²|s|, aω·cos φ·s)`;
///
/// and the cycler's rule chooses: the two meet at `D* = 2[a|ω||s| − v(t0)·d̂]/|ω|`; quadratic
/// when `D* > gap`, linear otherwise.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Oscillator {
    centre: DVec3,
    axis: DVec3,
    amplitude: f64,
    omega: f64,
    phase: f64,
}

impl Oscillator {
    /// An oscillator along `axis` (normalised here) about `centre`.
    ///
    /// # Errors
    /// [`MotionError::NonFinite`] for NaN or infinite input; [`MotionError::InvalidParameter`]
    /// for a negative amplitude or a zero axis.
    pub fn new(
        centre: DVec3,
        axis: DVec3,
        amplitude: f64,
        omega: f64,
        phase: f64,
    ) -> Result<Self, MotionError> {
        Ok(Self {
            centre: finite_vec("centre", centre)?,
            axis: unit_axis("axis", axis)?,
            amplitude: non_negative("amplitude", amplitude)?,
            omega: finite_scalar("omega", omega)?,
            phase: wrap_angle(finite_scalar("phase", phase)?),
        })
    }

    /// Centre of the oscillation (world, m).
    #[must_use]
    pub fn centre(&self) -> DVec3 {
        self.centre
    }

    /// Unit direction of oscillation (world).
    #[must_use]
    pub fn axis(&self) -> DVec3 {
        self.axis
    }

    /// Amplitude a (m).
    #[must_use]
    pub fn amplitude(&self) -> f64 {
        self.amplitude
    }

    /// Angular frequency ω (rad/s).
    #[must_use]
    pub fn omega(&self) -> f64 {
        self.omega
    }

    /// Phase φ at t0 in `[0, 2π)` (rad).
    #[must_use]
    pub fn phase(&self) -> f64 {
        self.phase
    }

    pub(super) fn linear_coefficients(&self, d_hat: DVec3) -> (f64, f64) {
        let s = self.axis.dot(d_hat).abs();
        (0.0, self.amplitude * self.omega.abs() * s)
    }

    pub(super) fn quadratic_coefficients(&self, d_hat: DVec3) -> (f64, f64) {
        let s = self.axis.dot(d_hat).abs();
        let a = 0.5 * self.amplitude * self.omega * self.omega * s;
        (a, self.com_velocity_at(0.0).dot(d_hat))
    }

    /// TOI coefficients, linear or quadratic by the D* rule (derivation on the type). `r_max`
    /// is not needed (no rotation). A NaN `gap` selects linear; a non-finite `d_hat` gives
    /// [`UNBOUNDED_COEFFICIENTS`].
    #[must_use]
    pub fn toi_coefficients(&self, d_hat: DVec3, gap: f64) -> (f64, f64) {
        if !d_hat.is_finite() {
            return UNBOUNDED_COEFFICIENTS;
        }
        let (_, b_lin) = self.linear_coefficients(d_hat);
        let (a_quad, b_quad) = self.quadratic_coefficients(d_hat);
        select_model(self.omega, b_lin, a_quad, b_quad, gap)
    }

    /// Box enclosing the COM path between t0 and `t0 + dt` (either order): the path is the
    /// segment `centre + a·sin θ·axis`, so the box spans `sin θ` over the swept phase interval,
    /// including the turning points `sin θ = ±1` reached inside it (the whole segment when
    /// `|ω·dt| ≥ 2π`). Padded by [`SWEPT_BOX_ROUNDING_REL`]. NaN `dt` gives the box of all
    /// space; an infinite `dt` the whole segment.
    #[must_use]
    pub fn swept_com_aabb(&self, dt: f64) -> Aabb {
        if dt.is_nan() {
            return ALL_SPACE;
        }
        let (s_min, s_max) = if dt.is_infinite() {
            (-1.0, 1.0)
        } else {
            let sweep = self.omega * dt;
            let (lo, hi) = if sweep >= 0.0 {
                (self.phase, self.phase + sweep)
            } else {
                (self.phase + sweep, self.phase)
            };
            // sin θ = cos(θ − π/2).
            cos_range(lo - 0.5 * PI, hi - 0.5 * PI)
        };
        let reach = self.axis * self.amplitude;
        let mut b = Aabb::new(self.centre + reach * s_min, self.centre + reach * s_max);
        if dt.is_finite() {
            b = Aabb::from_points([b.min, b.max, self.com_at(0.0), self.com_at(dt)]);
        }
        pad(b, self.centre.abs() + reach.abs())
    }

    /// Centre of mass at `t0 + dt` (world, m).
    #[must_use]
    pub fn com_at(&self, dt: f64) -> DVec3 {
        self.centre + self.axis * (self.amplitude * (self.omega * dt + self.phase).sin())
    }

    /// Centre-of-mass velocity at `t0 + dt` (world, m/s).
    #[must_use]
    pub fn com_velocity_at(&self, dt: f64) -> DVec3 {
        self.axis * (self.amplitude * self.omega * (self.omega * dt + self.phase).cos())
    }

    /// The same motion re-based at `t0 + dt` (phase advanced by `ω·dt`, wrapped to `[0, 2π)`).
    ///
    /// # Errors
    /// [`MotionError::NonFinite`] when `dt` or the new phase is not finite.
    pub fn advance(&self, dt: f64) -> Result<Self, MotionError> {
        finite_scalar("dt", dt)?;
        let phase = finite_scalar("phase", self.phase + self.omega * dt)?;
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
    use glam::DVec3;
    use impulse_geom::Aabb;
    use rand::RngExt;

    #[test]
    fn oscillator_swept_box_covers_turning_points() {
        let centre = DVec3::new(0.5, 1.0, -1.0);
        let axis = DVec3::new(1.0, 2.0, 2.0);
        let (a, w) = (0.3, 2.0);
        // (phase, sweep ω·dt, turning points at π/2 + nπ crossed)
        for (phase, sweep, turns) in [(0.0, 1.0, 0), (1.0, 1.0, 1), (1.0, 4.0, 2), (0.0, 6.0, 2)] {
            let count = (-8..8)
                .filter(|&n| {
                    let t = 0.5 * PI + f64::from(n) * PI;
                    phase < t && t < phase + sweep
                })
                .count();
            assert_eq!(count, turns);
            for (start, signed_w) in [(phase, w), (phase + sweep, -w)] {
                let o = Oscillator::new(centre, axis, a, signed_w, start).unwrap();
                check_swept_box(
                    &o.into(),
                    sweep / w,
                    sampling_slack(a * w * w, sweep / w, 3.0),
                );
            }
        }
        let o = Oscillator::new(centre, axis, a, w, 0.4).unwrap();
        let reach = axis.normalize() * a;
        for dt in [TAU / w, 100.0, f64::INFINITY] {
            let b = o.swept_com_aabb(dt);
            let full = Aabb::new(centre - reach, centre + reach);
            assert!((b.min - full.min).abs().max_element() <= FULL_PATH_TOL);
            assert!((b.max - full.max).abs().max_element() <= FULL_PATH_TOL);
        }
        let mut rng = rng(10);
        for _ in 0..300 {
            let o = Oscillator::new(
                unit_vector(&mut rng) * 3.0,
                unit_vector(&mut rng),
                rng.random_range(0.0..1.0),
                rng.random_range(-20.0..20.0),
                rng.random_range(-10.0..10.0),
            )
            .unwrap();
            let dt = rng.random_range(0.0..1.0);
            let acc = o.amplitude() * o.omega() * o.omega();
            check_swept_box(&o.into(), dt, sampling_slack(acc, dt, 5.0));
        }
        assert_eq!(o.swept_com_aabb(f64::NAN), ALL_SPACE);
    }
}
