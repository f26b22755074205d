//! A link of a multibody (thesis §5.2): its motion is whatever the multibody's dynamics make
//! of it, so no conservative bound is known. The thesis drops the requirement: the swept box
//! and the TOI coefficients come from a second-order model of the link's reference point at the
//! current instant, padded, and a caller that integrates the multibody must **check them
//! afterwards** against the motion it actually saw, and redo the step when they fail (the
//! slack structure and box checks of Figs. 5.3 and 5.4, `impulse-sim`'s hybrid loop).
//!
//! The reference point is any point fixed in the link (the world uses the link frame's origin,
//! where its collision shapes are given); `r_max` and the reach of the coefficients are
//! distances from it.

use glam::DVec3;
use impulse_geom::Aabb;

use super::{MotionError, finite_scalar, finite_vec, pad};

/// Factor on the velocity and acceleration of a link's second-order path in its swept box
/// (thesis §5.2.1: "multiply ṙ(t₀) and r̈(t₀) by 1.1"). Dimensionless; default `1.1`.
pub const LINK_SWEPT_PADDING: f64 = 1.1;

/// Relative padding of a link's TOI coefficients (thesis §5.2.2: `A ← A + 0.2|A|`,
/// `B ← B + 0.2|B|`). Dimensionless; default `0.2`.
pub const LINK_TOI_PADDING: f64 = 0.2;

/// The speeds a link was seen to reach over an integration (Fig. 5.4's componentwise velocity
/// range of its reference point and largest |ω| components), used after a failed prediction:
/// "recompute the offending TOI from the motion now known for the step".
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SeenSpeeds {
    /// Componentwise least velocity of the reference point (m/s).
    pub velocity_min: DVec3,
    /// Componentwise greatest velocity of the reference point (m/s).
    pub velocity_max: DVec3,
    /// Greatest |ω_x|, |ω_y|, |ω_z| (rad/s).
    pub omega_abs_max: DVec3,
    /// The box of the reference point's positions seen (m).
    pub path: Aabb,
}

impl SeenSpeeds {
    /// Fig. 5.4's `k`: the largest speed along `d` (its length scales the result) of any point
    /// within `reach` of the reference point, over the seen states.
    #[must_use]
    pub fn speed_along(&self, d: DVec3, reach: f64) -> f64 {
        let dd = d.length_squared();
        (0..3)
            .map(|c| {
                let v = if d[c] < 0.0 {
                    self.velocity_min[c]
                } else {
                    self.velocity_max[c]
                };
                v * d[c] + reach * self.omega_abs_max[c] * (dd - d[c] * d[c]).max(0.0).sqrt()
            })
            .sum()
    }
}

/// The motion of a multibody link's reference point as the event loop predicts it: position,
/// velocity and acceleration now, angular velocity now, and optionally the speeds seen over a
/// step whose prediction failed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinkMotion {
    origin: DVec3,
    velocity: DVec3,
    acceleration: DVec3,
    omega: DVec3,
    alpha: f64,
    seen: Option<SeenSpeeds>,
}

impl LinkMotion {
    /// A link whose reference point is at `origin` (m) with `velocity` (m/s) and
    /// `acceleration` (m/s², gravity included), turning at `omega` (rad/s), world frame.
    ///
    /// # Errors
    /// [`MotionError::NonFinite`] for a non-finite input.
    pub fn new(
        origin: DVec3,
        velocity: DVec3,
        acceleration: DVec3,
        omega: DVec3,
    ) -> Result<Self, MotionError> {
        Ok(Self {
            origin: finite_vec("origin", origin)?,
            velocity: finite_vec("velocity", velocity)?,
            acceleration: finite_vec("acceleration", acceleration)?,
            omega: finite_vec("omega", omega)?,
            alpha: 0.0,
            seen: None,
        })
    }

    /// The same prediction for a link whose angular velocity changes at `alpha` (rad/s²): the
    /// rotational travel `r(‖ω‖τ + ½‖α‖τ²)` adds `½ r ‖α‖` to A. The thesis's reference point
    /// is the centre of mass, whose linear acceleration carries most of a swinging link's
    /// motion; a reference point on the joint axis (a pendulum's pivot) has none, and its
    /// link's whole motion is rotation, so the current ω alone predicts too little as soon as
    /// the link swings faster (measured: a pendulum resting by microcollisions failed its
    /// slack at nearly every step without this term).
    ///
    /// # Errors
    /// [`MotionError::NonFinite`] for a non-finite `alpha`.
    pub fn with_angular_acceleration(mut self, alpha: DVec3) -> Result<Self, MotionError> {
        self.alpha = finite_vec("alpha", alpha)?.length();
        Ok(self)
    }

    /// The same prediction, widened by the speeds and path seen over a step whose prediction
    /// failed: the coefficients' speed term is at least what was seen (padded), and the
    /// swept box covers the seen path.
    ///
    /// # Errors
    /// [`MotionError::NonFinite`] for a non-finite input.
    pub fn with_seen(mut self, seen: SeenSpeeds) -> Result<Self, MotionError> {
        finite_vec("velocity_min", seen.velocity_min)?;
        finite_vec("velocity_max", seen.velocity_max)?;
        finite_vec("omega_abs_max", seen.omega_abs_max)?;
        finite_vec("path.min", seen.path.min)?;
        finite_vec("path.max", seen.path.max)?;
        self.seen = Some(seen);
        Ok(self)
    }

    /// The reference point now (m).
    #[must_use]
    pub fn origin(&self) -> DVec3 {
        self.origin
    }

    /// The reference point's acceleration now (m/s², gravity included).
    #[must_use]
    pub fn acceleration(&self) -> DVec3 {
        self.acceleration
    }

    /// TOI coefficients (thesis §5.2.2): `A = ½ (a·d̂ + r ‖α‖ ‖d̂‖)`, `B = v·d̂ + r ‖ω‖ ‖d̂‖`
    /// (the α term is ours: [`LinkMotion::with_angular_acceleration`]), each padded by
    /// [`LINK_TOI_PADDING`] of its magnitude; with seen speeds, `A ≥ 0` and `B` at least the
    /// padded seen speed along d̂ (Fig. 5.4). Not conservative: a prediction the caller must
    /// check. Non-finite `d_hat` or `r_max` give [`super::UNBOUNDED_COEFFICIENTS`].
    #[must_use]
    pub fn toi_coefficients(&self, d_hat: DVec3, r_max: f64) -> (f64, f64) {
        if !(d_hat.is_finite() && r_max.is_finite() && r_max >= 0.0) {
            return super::UNBOUNDED_COEFFICIENTS;
        }
        let a = 0.5 * (self.acceleration.dot(d_hat) + r_max * self.alpha * d_hat.length());
        let b = self.velocity.dot(d_hat) + r_max * self.omega.length() * d_hat.length();
        let (mut a, mut b) = (
            a + LINK_TOI_PADDING * a.abs(),
            b + LINK_TOI_PADDING * b.abs(),
        );
        if let Some(seen) = &self.seen {
            let k = seen.speed_along(d_hat, r_max);
            a = a.max(0.0);
            b = b.max(k + LINK_TOI_PADDING * k.abs());
        }
        (a, b)
    }

    /// Direction-free TOI coefficients `(A, B)`: along every unit direction
    /// [`LinkMotion::toi_coefficients`] with reach at most `r_max` gives no more. `A = ½(|a| +
    /// r‖α‖)`, `B = |v| + r‖ω‖`, padded as there (the padding x ↦ x + 0.2|x| is increasing, and
    /// a·d̂ ≤ |a|); with seen speeds `B` at least `|V| + r·Σ ω_c` (V_c the larger magnitude of
    /// the seen velocity bounds of axis c, ω_c the seen spin bound), which bounds
    /// [`SeenSpeeds::speed_along`] for unit d̂ (Cauchy–Schwarz, and each axis' lever factor is
    /// at most 1). Not conservative, as the directional coefficients are not: a prediction.
    /// Non-finite or negative `r_max` gives [`super::UNBOUNDED_COEFFICIENTS`].
    #[must_use]
    pub fn free_coefficients(&self, r_max: f64) -> (f64, f64) {
        if !(r_max.is_finite() && r_max >= 0.0) {
            return super::UNBOUNDED_COEFFICIENTS;
        }
        let pad = 1.0 + LINK_TOI_PADDING;
        let a = pad * 0.5 * (self.acceleration.length() + r_max * self.alpha.abs());
        let mut b = pad * (self.velocity.length() + r_max * self.omega.length());
        if let Some(seen) = &self.seen {
            let v = seen.velocity_min.abs().max(seen.velocity_max.abs());
            let w = seen.omega_abs_max.abs();
            b = b.max(pad * (v.length() + r_max * (w.x + w.y + w.z)));
        }
        (a, b)
    }

    /// Box of the padded second-order path `p + 1.1·v τ + ½·1.1·a τ²` over τ between 0 and
    /// `dt` (thesis §5.2.1; endpoints and the vertex when inside), joined with the seen path
    /// when there is one. Not conservative: a prediction the caller must check.
    #[must_use]
    pub fn swept_com_aabb(&self, dt: f64) -> Aabb {
        if !dt.is_finite() {
            return super::ALL_SPACE;
        }
        let (v, a) = (
            LINK_SWEPT_PADDING * self.velocity,
            LINK_SWEPT_PADDING * self.acceleration,
        );
        let at = |t: f64| self.origin + v * t + a * (0.5 * t * t);
        let (p0, p1) = (self.origin, at(dt));
        let (mut lo, mut hi) = (p0.min(p1), p0.max(p1));
        for k in 0..3 {
            if a[k] != 0.0 {
                let t = -v[k] / a[k];
                if t > 0.0_f64.min(dt) && t < 0.0_f64.max(dt) {
                    let x = at(t)[k];
                    lo[k] = lo[k].min(x);
                    hi[k] = hi[k].max(x);
                }
            }
        }
        let mut b = Aabb { min: lo, max: hi };
        if let Some(seen) = &self.seen {
            b = Aabb {
                min: b.min.min(seen.path.min),
                max: b.max.max(seen.path.max),
            };
        }
        let extent = (v * dt).abs() + (a * (0.5 * dt * dt)).abs();
        pad(b, self.origin.abs() + extent)
    }

    /// The predicted reference point at `t0 + dt` (the unpadded second-order model).
    #[must_use]
    pub fn com_at(&self, dt: f64) -> DVec3 {
        self.origin + self.velocity * dt + self.acceleration * (0.5 * dt * dt)
    }

    /// The predicted velocity at `t0 + dt`.
    #[must_use]
    pub fn com_velocity_at(&self, dt: f64) -> DVec3 {
        self.velocity + self.acceleration * dt
    }

    /// The prediction re-based at `t0 + dt` (seen speeds belong to the step that saw them and
    /// are dropped).
    ///
    /// # Errors
    /// [`MotionError::NonFinite`] for a non-finite `dt` or result.
    pub fn advance(&self, dt: f64) -> Result<Self, MotionError> {
        finite_scalar("dt", dt)?;
        let mut m = Self::new(
            self.com_at(dt),
            self.com_velocity_at(dt),
            self.acceleration,
            self.omega,
        )?;
        m.alpha = self.alpha;
        Ok(m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::testkit::{rng, unit_vector};
    use rand::RngExt;

    fn random(r: &mut rand::rngs::Xoshiro256PlusPlus) -> LinkMotion {
        let mut v = || {
            DVec3::new(
                r.random_range(-3.0..3.0),
                r.random_range(-3.0..3.0),
                r.random_range(-3.0..3.0),
            )
        };
        LinkMotion::new(v(), v(), v() * 4.0, v()).unwrap()
    }

    /// The box holds the padded path's points sampled densely (brute force).
    #[test]
    fn swept_boxes_hold_the_sampled_padded_path() {
        let mut r = rng(7);
        for _ in 0..2000 {
            let m = random(&mut r);
            let dt = r.random_range(-0.5..0.5);
            let b = m.swept_com_aabb(dt);
            for k in 0..=200 {
                let t = dt * f64::from(k) / 200.0;
                let padded = m.origin
                    + LINK_SWEPT_PADDING * (m.velocity * t + m.acceleration * (0.5 * t * t));
                assert!(
                    b.contains_point(padded),
                    "{m:?} dt {dt} t {t}: {padded} not in {b:?}"
                );
            }
        }
    }

    /// The coefficients are the thesis's, padded: along d̂, the model's own path (second order,
    /// rotation at the current ω) never travels farther than the bound.
    #[test]
    fn coefficients_bound_the_models_own_travel() {
        let mut r = rng(8);
        for _ in 0..2000 {
            let m = random(&mut r);
            let d = unit_vector(&mut r);
            let reach = r.random_range(0.0..1.0);
            let (a, b) = m.toi_coefficients(d, reach);
            let rot = reach * m.omega.length();
            for k in 1..=100 {
                let t = 0.5 * f64::from(k) / 100.0;
                let travel = (m.com_at(t) - m.origin).dot(d) + rot * t;
                assert!(travel <= a * t * t + b * t + 1e-12, "{m:?}");
            }
            // Padding is 20 % of each term's magnitude.
            let (a0, b0) = (0.5 * m.acceleration.dot(d), m.velocity.dot(d) + rot);
            assert!((a - (a0 + 0.2 * a0.abs())).abs() < 1e-12);
            assert!((b - (b0 + 0.2 * b0.abs())).abs() < 1e-12);
        }
    }

    /// The direction-free coefficients bound the directional ones along every direction
    /// (without and with seen speeds, any reach up to theirs), and are no looser than the
    /// largest directional ones found along the acceleration, the velocity and 400 random
    /// directions by more than the seen spin's axis sum allows (A within 1 %, B within a
    /// factor 1.8).
    #[test]
    fn free_coefficients_bound_every_direction() {
        let mut r = rng(10);
        for case in 0..400 {
            let mut m = random(&mut r);
            if case % 2 == 1 {
                let lo = DVec3::new(
                    r.random_range(-4.0..0.0),
                    r.random_range(-4.0..0.0),
                    r.random_range(-4.0..0.0),
                );
                m = m
                    .with_seen(SeenSpeeds {
                        velocity_min: lo,
                        velocity_max: lo + DVec3::new(1.0, 2.0, 3.0),
                        omega_abs_max: DVec3::new(2.0, 0.5, 5.0),
                        path: Aabb {
                            min: DVec3::splat(-9.0),
                            max: DVec3::splat(9.0),
                        },
                    })
                    .unwrap();
            }
            let reach = r.random_range(0.0..1.0);
            let (fa, fb) = m.free_coefficients(reach);
            let (mut ma, mut mb) = (f64::NEG_INFINITY, f64::NEG_INFINITY);
            for k in 0..402 {
                // Two of the directions: along the acceleration and along the velocity.
                let d = match k {
                    0 => m.acceleration.normalize(),
                    1 => m.velocity.normalize(),
                    _ => unit_vector(&mut r),
                };
                let piece_reach = reach * r.random_range(0.0..=1.0);
                let (a, b) = m.toi_coefficients(d, piece_reach);
                assert!(
                    a <= fa * (1.0 + 1e-12) && b <= fb * (1.0 + 1e-12),
                    "{m:?} {d}"
                );
                let (a, b) = m.toi_coefficients(d, reach);
                (ma, mb) = (ma.max(a), mb.max(b));
            }
            assert!(fa <= 1.01 * ma + 1e-12, "A {fa} against sampled {ma}");
            assert!(fb <= 1.8 * mb + 1e-12, "B {fb} against sampled {mb}");
        }
    }

    /// Seen speeds raise B to the padded seen speed along d̂ (brute force over the corners of
    /// the seen velocity box and rotations about each axis) and the box to the seen path.
    #[test]
    fn seen_speeds_widen_the_prediction() {
        let mut r = rng(9);
        for _ in 0..500 {
            let m = random(&mut r);
            let lo = DVec3::new(-4.0, -1.0, 0.5);
            let seen = SeenSpeeds {
                velocity_min: lo,
                velocity_max: lo + DVec3::new(1.0, 2.0, 3.0),
                omega_abs_max: DVec3::new(2.0, 0.0, 5.0),
                path: Aabb {
                    min: DVec3::splat(-9.0),
                    max: DVec3::splat(9.0),
                },
            };
            let w = m.with_seen(seen).unwrap();
            let d = unit_vector(&mut r);
            let reach = 0.3;
            let (a, b) = w.toi_coefficients(d, reach);
            assert!(a >= 0.0);
            // Brute force: the largest (v + ω × arm)·d over the box's corners, per-axis ω
            // within its bound, arms of length `reach`.
            let mut best = f64::NEG_INFINITY;
            for corner in 0..8 {
                let v = DVec3::new(
                    if corner & 1 == 0 {
                        seen.velocity_min.x
                    } else {
                        seen.velocity_max.x
                    },
                    if corner & 2 == 0 {
                        seen.velocity_min.y
                    } else {
                        seen.velocity_max.y
                    },
                    if corner & 4 == 0 {
                        seen.velocity_min.z
                    } else {
                        seen.velocity_max.z
                    },
                );
                for _ in 0..50 {
                    let arm = unit_vector(&mut r) * reach;
                    let om = DVec3::new(
                        r.random_range(-1.0..=1.0) * seen.omega_abs_max.x,
                        r.random_range(-1.0..=1.0) * seen.omega_abs_max.y,
                        r.random_range(-1.0..=1.0) * seen.omega_abs_max.z,
                    );
                    best = best.max((v + om.cross(arm)).dot(d));
                }
            }
            assert!(b >= best - 1e-12, "B {b} below a seen speed {best}");
            let bx = w.swept_com_aabb(0.01);
            assert!(bx.contains_point(DVec3::splat(8.9)) && bx.contains_point(DVec3::splat(-8.9)));
        }
    }

    /// With an angular acceleration, A grows by ½ r ‖α‖ (padded): a link turning from rest
    /// about its reference point travels r(1 − cos(½ α τ²)) ≤ ½ r α τ², within the bound.
    #[test]
    fn angular_acceleration_raises_the_quadratic_term() {
        let alpha = DVec3::new(0.0, 30.0, 0.0);
        let m = LinkMotion::new(DVec3::ZERO, DVec3::ZERO, DVec3::ZERO, DVec3::ZERO)
            .unwrap()
            .with_angular_acceleration(alpha)
            .unwrap();
        let r = 0.5;
        let (a, b) = m.toi_coefficients(DVec3::Z, r);
        assert!((a - 1.2 * 0.5 * r * 30.0).abs() < 1e-12 && b == 0.0);
        // A point at distance r on the x axis, turning about y from rest: its z travel.
        for k in 1..=50 {
            let t = 0.01 * f64::from(k);
            let angle = 0.5 * 30.0 * t * t;
            assert!(r * angle.sin() <= a * t * t + 1e-12);
        }
        assert!(
            LinkMotion::new(DVec3::ZERO, DVec3::ZERO, DVec3::ZERO, DVec3::ZERO)
                .unwrap()
                .with_angular_acceleration(DVec3::NAN)
                .is_err()
        );
    }

    #[test]
    fn bad_input_is_refused_or_unbounded() {
        assert!(LinkMotion::new(DVec3::NAN, DVec3::ZERO, DVec3::ZERO, DVec3::ZERO).is_err());
        let m = LinkMotion::new(DVec3::ZERO, DVec3::X, DVec3::ZERO, DVec3::Z).unwrap();
        assert_eq!(
            m.toi_coefficients(DVec3::NAN, 1.0),
            super::super::UNBOUNDED_COEFFICIENTS
        );
        assert_eq!(
            m.toi_coefficients(DVec3::X, -1.0),
            super::super::UNBOUNDED_COEFFICIENTS
        );
        assert!(m.advance(f64::NAN).is_err());
    }
}
