//! Oriented planes.

use glam::DVec3;

/// The oriented plane `normal · x = offset`, with a unit `normal` pointing to its positive
/// (outer) side.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    /// Unit normal.
    pub normal: DVec3,
    /// Signed distance of the plane from the origin along `normal`.
    pub offset: f64,
}

impl Plane {
    /// The plane through `point` with unit normal `normal` (not re-normalised).
    pub fn from_point_normal(point: DVec3, normal: DVec3) -> Self {
        Self {
            normal,
            offset: normal.dot(point),
        }
    }

    /// Signed distance of `p`: positive on the side the normal points to.
    pub fn signed_distance(&self, p: DVec3) -> f64 {
        self.normal.dot(p) - self.offset
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn signed_distance_matches_geometry() {
        let n = DVec3::new(1.0, 2.0, 2.0) / 3.0;
        let pl = Plane::from_point_normal(DVec3::new(3.0, 0.0, 0.0), n);
        assert!((pl.offset - 1.0).abs() < 1e-15);
        assert!((pl.signed_distance(DVec3::new(3.0, 0.0, 0.0) + 2.0 * n) - 2.0).abs() < 1e-15);
        assert!((pl.signed_distance(DVec3::ZERO) + 1.0).abs() < 1e-15);
    }
}
