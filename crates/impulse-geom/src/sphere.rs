//! The exact sphere shape.

use glam::DVec3;

use crate::aabb::Aabb;
use crate::error::GeomError;
use crate::pose::Pose;

/// A solid sphere centred at its body frame's origin (which is also its centre of mass).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    radius: f64,
}

impl Sphere {
    /// A sphere of the given radius.
    ///
    /// # Errors
    /// [`GeomError::InvalidParameter`] unless `radius` is finite and positive.
    pub fn new(radius: f64) -> Result<Self, GeomError> {
        if radius.is_finite() && radius > 0.0 {
            Ok(Self { radius })
        } else {
            Err(GeomError::InvalidParameter {
                name: "radius",
                value: radius,
                requirement: "must be finite and > 0",
            })
        }
    }

    /// The radius.
    pub fn radius(&self) -> f64 {
        self.radius
    }

    /// The point of the sphere farthest along `dir` (body frame; `dir` need not be unit; a zero
    /// `dir` gives the centre).
    pub fn support(&self, dir: DVec3) -> DVec3 {
        dir.normalize_or_zero() * self.radius
    }

    /// Bounding box of the sphere placed at `pose` (tight).
    pub fn aabb(&self, pose: &Pose) -> Aabb {
        let c = pose.translation;
        Aabb {
            min: c - DVec3::splat(self.radius),
            max: c + DVec3::splat(self.radius),
        }
    }

    /// Radius of the smallest sphere about `center` (body frame) that contains this sphere.
    pub fn bounding_radius(&self, center: DVec3) -> f64 {
        center.length() + self.radius
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DQuat;

    #[test]
    fn support_aabb_and_validation() {
        let s = Sphere::new(2.0).unwrap();
        assert!(
            s.support(DVec3::new(0.0, 3.0, 4.0))
                .distance(DVec3::new(0.0, 1.2, 1.6))
                < 1e-15
        );
        let pose = Pose::new(DQuat::from_rotation_x(0.7), DVec3::new(1.0, 2.0, 3.0));
        let b = s.aabb(&pose);
        assert_eq!(b.min, DVec3::new(-1.0, 0.0, 1.0));
        assert_eq!(b.max, DVec3::new(3.0, 4.0, 5.0));
        assert_eq!(s.bounding_radius(DVec3::new(3.0, 4.0, 0.0)), 7.0);
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(Sphere::new(bad).is_err());
        }
    }
}
