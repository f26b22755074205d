//! The spinner: rotation about a fixed axis through a fixed centre of mass.

use glam::{DQuat, DVec3};
use impulse_geom::Aabb;
use impulse_geom::se3::so3_exp;

use super::*;

/// Scripted rotation about a fixed axis through a fixed centre of mass (a spinning platter or
/// turntable): angular velocity `Ω·axis` is constant, the COM does not move.
///
/// World frame: `com` (m), unit `axis`, rate Ω (rad/s, right-handed about `axis`).
///
/// Coefficients: a body point at offset `r` from the COM moves on a circle about the axis with
/// velocity `Ω·axis × r`, which is perpendicular to the axis and of length `|Ω|·ρ`, where ρ,
/// the point's distance from the axis, is at most `|r| ≤ r_max`. Its rate along d̂ is therefore
/// `(Ω·axis × r)·d̂⊥ ≤ |Ω|·r_max·|d̂⊥|`, where `d̂⊥ = d̂ − (d̂·axis)·axis`; integrating,
/// `A = 0`, `B = |Ω|·r_max·|d̂⊥|`. (A quadratic model like the cycler's does not help here:
/// without the body's shape the worst initial rate along d̂ is already `|Ω|·r_max·|d̂⊥|`.)
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spinner {
    com: DVec3,
    axis: DVec3,
    rate: f64,
}

impl Spinner {
    /// A spinner about `axis` (normalised here) through `com`, at `rate` rad/s.
    ///
    /// # Errors
    /// [`MotionError::NonFinite`] for NaN or infinite input; [`MotionError::InvalidParameter`]
    /// for a zero axis.
    pub fn new(com: DVec3, axis: DVec3, rate: f64) -> Result<Self, MotionError> {
        Ok(Self {
            com: finite_vec("com", com)?,
            axis: unit_axis("axis", axis)?,
            rate: finite_scalar("rate", rate)?,
        })
    }

    /// The fixed centre of mass (world, m).
    #[must_use]
    pub fn com(&self) -> DVec3 {
        self.com
    }

    /// Unit rotation axis (world).
    #[must_use]
    pub fn axis(&self) -> DVec3 {
        self.axis
    }

    /// Rotation rate about [`Spinner::axis`] (rad/s).
    #[must_use]
    pub fn rate(&self) -> f64 {
        self.rate
    }

    /// The rotation the body undergoes between t0 and `t0 + dt` (world frame, about the COM):
    /// new orientation = `rotation_over(dt) * old orientation`.
    #[must_use]
    pub fn rotation_over(&self, dt: f64) -> DQuat {
        so3_exp(self.axis * (self.rate * dt))
    }

    /// TOI coefficients `(0, |Ω|·r_max·|d̂⊥|)` (derivation on the type). A NaN, negative or
    /// infinite `r_max`, or a non-finite `d_hat`, gives [`UNBOUNDED_COEFFICIENTS`].
    #[must_use]
    pub fn toi_coefficients(&self, d_hat: DVec3, r_max: f64) -> (f64, f64) {
        if !(d_hat.is_finite() && r_max >= 0.0 && r_max.is_finite()) {
            return UNBOUNDED_COEFFICIENTS;
        }
        let d_perp = d_hat - self.axis * self.axis.dot(d_hat);
        (0.0, self.rate.abs() * r_max * d_perp.length())
    }

    /// The COM does not move: the point box at `com`. The caller grows it by `r_max`, which
    /// bounds the whole swept body (every point stays within r_max of the COM).
    #[must_use]
    pub fn swept_com_aabb(&self, _dt: f64) -> Aabb {
        Aabb::new(self.com, self.com)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::testkit::*;
    use core::f64::consts::TAU;
    use glam::DVec3;
    use impulse_geom::Aabb;
    use rand::RngExt;

    /// Rodrigues' rotation of `r` about unit `k` by `theta` (independent of `so3_exp`).
    fn rodrigues(k: DVec3, theta: f64, r: DVec3) -> DVec3 {
        let (s, c) = theta.sin_cos();
        r * c + k.cross(r) * s + k * (k.dot(r) * (1.0 - c))
    }

    #[test]
    fn spinner_bound_holds_for_points_within_r_max() {
        let mut rng = rng(31);
        let mut worst: f64 = 0.0;
        for _ in 0..200 {
            let axis = unit_vector(&mut rng);
            let rate = rng.random_range(-50.0..50.0);
            let com = unit_vector(&mut rng) * 2.0;
            let s = Spinner::new(com, axis * 3.0, rate).unwrap();
            let r_max = rng.random_range(0.1..2.0);
            let points: Vec<DVec3> = (0..16)
                .map(|i| {
                    unit_vector(&mut rng)
                        * if i < 8 {
                            r_max
                        } else {
                            rng.random_range(0.0..r_max)
                        }
                })
                .collect();
            let d = unit_vector(&mut rng);
            let (a, b) = Motion::from(s).toi_coefficients(d, r_max, 1.0);
            assert_eq!(a, 0.0);
            let span = 2.0 * TAU / rate.abs();
            for k in 1..=1000 {
                let tau = span * f64::from(k) / 1000.0;
                for &r in &points {
                    let disp = (rodrigues(axis, rate * tau, r) - r).dot(d);
                    assert!(disp <= b * tau + BOUND_SLACK_REL * r_max);
                    if b * tau > RATIO_FLOOR_REL * r_max {
                        worst = worst.max(disp / (b * tau));
                    }
                    // The rotation the type reports agrees with Rodrigues.
                    if k % 100 == 0 {
                        let q = s.rotation_over(tau);
                        assert!(
                            (q * r - rodrigues(axis, rate * tau, r)).length()
                                <= CLOSED_FORM_TOL * r_max
                        );
                    }
                }
            }
            assert_eq!(Motion::from(s).swept_com_aabb(5.0), Aabb::new(com, com));
        }
        // Spinning about the direction of approach moves no point along it.
        let s = Spinner::new(DVec3::ZERO, DVec3::Z, 100.0).unwrap();
        assert_eq!(s.toi_coefficients(DVec3::Z, 1.0), (0.0, 0.0));
        eprintln!("spinner: max displacement / bound {worst:.4}");
    }
}
