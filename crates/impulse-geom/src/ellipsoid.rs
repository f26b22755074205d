//! The exact (smooth) ellipsoid shape.
//!
//! A smooth body has no features to walk: distance queries on it use its support mapping
//! ([`Ellipsoid::support`]), which is exact in closed form.

use glam::{DMat3, DVec3};

use crate::aabb::Aabb;
use crate::error::GeomError;
use crate::pose::Pose;

/// A solid ellipsoid centred at its frame's origin with semi-axes along the frame's x, y and z
/// axes: the points with (x/a)² + (y/b)² + (z/c)² ≤ 1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ellipsoid {
    semi_axes: DVec3,
}

impl Ellipsoid {
    /// An ellipsoid with the given semi-axes (a, b, c).
    ///
    /// # Errors
    /// [`GeomError::InvalidParameter`] unless every semi-axis is finite and positive.
    pub fn new(semi_axes: DVec3) -> Result<Self, GeomError> {
        for (name, value) in [
            ("semi_axes.x", semi_axes.x),
            ("semi_axes.y", semi_axes.y),
            ("semi_axes.z", semi_axes.z),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(GeomError::InvalidParameter {
                    name,
                    value,
                    requirement: "must be finite and > 0",
                });
            }
        }
        Ok(Self { semi_axes })
    }

    /// The semi-axes (a, b, c).
    pub fn semi_axes(&self) -> DVec3 {
        self.semi_axes
    }

    /// The point of the ellipsoid farthest along `dir` (frame coordinates; `dir` need not be
    /// unit; a zero `dir` gives the centre): x = S²d / |Sd| with S = diag(a, b, c).
    pub fn support(&self, dir: DVec3) -> DVec3 {
        let sd = self.semi_axes * dir;
        let len = sd.length();
        if len > 0.0 && len.is_finite() {
            self.semi_axes * sd / len
        } else {
            DVec3::ZERO
        }
    }

    /// The outward unit normal at (or, for any other point, the gradient direction of the
    /// ellipsoid's implicit function through) `point`, frame coordinates; zero at the centre.
    pub fn normal_at(&self, point: DVec3) -> DVec3 {
        (point / (self.semi_axes * self.semi_axes)).normalize_or_zero()
    }

    /// The implicit function (x/a)² + (y/b)² + (z/c)² − 1: negative inside, zero on the
    /// surface, positive outside (frame coordinates).
    pub fn implicit(&self, point: DVec3) -> f64 {
        (point / self.semi_axes).length_squared() - 1.0
    }

    /// Bounding box of the ellipsoid placed at `pose` (tight): along world axis i the half
    /// extent is √(Σ_j (R_ij s_j)²).
    pub fn aabb(&self, pose: &Pose) -> Aabb {
        let r = DMat3::from_quat(pose.rotation);
        let scaled = DMat3::from_cols(
            r.x_axis * self.semi_axes.x,
            r.y_axis * self.semi_axes.y,
            r.z_axis * self.semi_axes.z,
        );
        let t = scaled.transpose();
        let half = DVec3::new(t.x_axis.length(), t.y_axis.length(), t.z_axis.length());
        let c = pose.translation;
        Aabb {
            min: c - half,
            max: c + half,
        }
    }

    /// Radius of a sphere about `center` (frame coordinates) that contains the ellipsoid:
    /// |center| + the largest semi-axis (exact when `center` is the origin, an upper bound
    /// otherwise).
    pub fn bounding_radius(&self, center: DVec3) -> f64 {
        center.length() + self.semi_axes.max_element()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DQuat;

    /// Support points lie on the surface, maximise the projection among sampled surface points,
    /// and have the query direction as their normal.
    #[test]
    fn support_is_the_maximiser_on_the_surface() {
        let e = Ellipsoid::new(DVec3::new(3.0, 2.0, 0.5)).unwrap();
        let surface: Vec<DVec3> = (0..200)
            .flat_map(|i| {
                let theta = std::f64::consts::PI * (i as f64 + 0.5) / 200.0;
                (0..400).map(move |j| {
                    let phi = 2.0 * std::f64::consts::PI * j as f64 / 400.0;
                    DVec3::new(
                        theta.sin() * phi.cos(),
                        theta.sin() * phi.sin(),
                        theta.cos(),
                    ) * DVec3::new(3.0, 2.0, 0.5)
                })
            })
            .collect();
        for d in [
            DVec3::X,
            DVec3::new(1.0, 1.0, 1.0),
            DVec3::new(-0.3, 2.0, -5.0),
            DVec3::new(0.0, -1.0, 1e-9),
        ] {
            let s = e.support(d);
            assert!(e.implicit(s).abs() < 1e-14);
            let best = surface.iter().map(|p| p.dot(d)).fold(f64::MIN, f64::max);
            assert!(s.dot(d) >= best - 1e-12, "{d}");
            // Relative to the sampling: within the grid's resolution of the true maximum.
            assert!(s.dot(d) - best < 2e-3 * d.length() * 3.0, "{d}");
            assert!(e.normal_at(s).distance(d.normalize()) < 1e-12);
        }
        assert_eq!(e.support(DVec3::ZERO), DVec3::ZERO);
    }

    /// The box bounds the placed surface and touches it on every side (support points).
    #[test]
    fn aabb_is_tight_and_validation_names_the_axis() {
        let e = Ellipsoid::new(DVec3::new(3.0, 2.0, 0.5)).unwrap();
        let pose = Pose::new(
            DQuat::from_euler(glam::EulerRot::XYZ, 0.3, -1.1, 2.0),
            DVec3::new(1.0, -2.0, 0.5),
        );
        let b = e.aabb(&pose);
        for axis in [DVec3::X, DVec3::Y, DVec3::Z] {
            let local = pose.rotation.inverse() * axis;
            let hi = pose.transform_point(e.support(local)).dot(axis);
            let lo = pose.transform_point(e.support(-local)).dot(axis);
            assert!((hi - b.max.dot(axis)).abs() < 1e-12);
            assert!((lo - b.min.dot(axis)).abs() < 1e-12);
        }
        assert_eq!(e.bounding_radius(DVec3::ZERO), 3.0);
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            match Ellipsoid::new(DVec3::new(1.0, bad, 1.0)) {
                Err(GeomError::InvalidParameter { name, .. }) => assert_eq!(name, "semi_axes.y"),
                other => panic!("{other:?}"),
            }
        }
    }
}
