//! Fixed geometry an end effector can touch: planes, boxes and height fields, each answering
//! one query — the signed distance of a point and the outward normal there.

use glam::DVec3;
use impulse_geom::Pose;

/// A regular grid of heights `z = f(x, y)` (world), bilinear between samples.
#[derive(Clone, Debug, PartialEq)]
pub struct HeightField {
    /// World (x, y) of sample (0, 0) (m).
    pub origin: [f64; 2],
    /// Grid spacing in x and y (m).
    pub spacing: f64,
    /// Samples along x.
    pub nx: usize,
    /// Samples along y.
    pub ny: usize,
    /// Heights, row-major: `heights[j·nx + i]` at `(origin + (i, j)·spacing)` (m).
    pub heights: Vec<f64>,
}

impl HeightField {
    /// Height and gradient `(∂f/∂x, ∂f/∂y)` at world `(x, y)`, clamped to the grid.
    #[must_use]
    pub fn sample(&self, x: f64, y: f64) -> (f64, [f64; 2]) {
        let fx = ((x - self.origin[0]) / self.spacing).clamp(0.0, (self.nx - 1) as f64);
        let fy = ((y - self.origin[1]) / self.spacing).clamp(0.0, (self.ny - 1) as f64);
        let i = (fx.floor() as usize).min(self.nx.saturating_sub(2));
        let j = (fy.floor() as usize).min(self.ny.saturating_sub(2));
        let (u, v) = (fx - i as f64, fy - j as f64);
        let h = |a: usize, b: usize| self.heights[b * self.nx + a];
        let (h00, h10, h01, h11) = (h(i, j), h(i + 1, j), h(i, j + 1), h(i + 1, j + 1));
        let z =
            h00 * (1.0 - u) * (1.0 - v) + h10 * u * (1.0 - v) + h01 * (1.0 - u) * v + h11 * u * v;
        let dx = ((h10 - h00) * (1.0 - v) + (h11 - h01) * v) / self.spacing;
        let dy = ((h01 - h00) * (1.0 - u) + (h11 - h10) * u) / self.spacing;
        (z, [dx, dy])
    }
}

/// A fixed obstacle.
#[derive(Clone, Debug, PartialEq)]
pub enum Obstacle {
    /// The half-space `n·x ≤ offset` is solid; `normal` is unit, pointing out of the solid.
    Plane {
        /// Outward unit normal (world).
        normal: DVec3,
        /// Offset: the plane is `n·x = offset` (m).
        offset: f64,
    },
    /// A solid box.
    Box {
        /// Box frame (world).
        pose: Pose,
        /// Half extents (m).
        half_extents: DVec3,
    },
    /// Solid below a height field.
    HeightField(HeightField),
}

impl Obstacle {
    /// Signed distance of world point `p` (m; negative inside) and the outward unit normal.
    #[must_use]
    pub fn distance(&self, p: DVec3) -> (f64, DVec3) {
        match self {
            Obstacle::Plane { normal, offset } => (normal.dot(p) - offset, *normal),
            Obstacle::Box { pose, half_extents } => {
                let q = pose.inverse_transform_point(p);
                let d = q.abs() - *half_extents;
                if d.max_element() > 0.0 {
                    // Outside: distance to the closest surface point.
                    let outside = d.max(DVec3::ZERO);
                    let n = (outside * q.signum()).normalize();
                    (outside.length(), pose.transform_vector(n))
                } else {
                    // Inside: the nearest face.
                    let k = if d.x >= d.y && d.x >= d.z {
                        0
                    } else if d.y >= d.z {
                        1
                    } else {
                        2
                    };
                    let mut n = DVec3::ZERO;
                    n[k] = q[k].signum();
                    (d[k], pose.transform_vector(n))
                }
            }
            Obstacle::HeightField(hf) => {
                let (z, g) = hf.sample(p.x, p.y);
                let n = DVec3::new(-g[0], -g[1], 1.0);
                let len = n.length();
                // Vertical gap projected on the normal: exact for a locally planar field.
                ((p.z - z) / len, n / len)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Distances of exactly representable cases are exact up to a few ulp.
    const EXACT: f64 = 1e-14;

    #[test]
    fn distances_and_normals() {
        let plane = Obstacle::Plane {
            normal: DVec3::Z,
            offset: 0.5,
        };
        assert_eq!(plane.distance(DVec3::new(3.0, 1.0, 2.0)), (1.5, DVec3::Z));
        let b = Obstacle::Box {
            pose: Pose::from_translation(DVec3::new(1.0, 0.0, 0.0)),
            half_extents: DVec3::new(1.0, 2.0, 3.0),
        };
        let (d, n) = b.distance(DVec3::new(1.0, 0.0, 4.0));
        assert!((d - 1.0).abs() < EXACT && n == DVec3::Z);
        let (d, n) = b.distance(DVec3::new(1.5, 0.0, 0.0));
        assert!((d + 0.5).abs() < EXACT && n == DVec3::X);
        let (d, _) = b.distance(DVec3::new(3.0, 3.0, 0.0));
        assert!((d - 2f64.sqrt()).abs() < EXACT);
        // A tilted planar height field z = 0.5 x: distance along the normal.
        let hf = HeightField {
            origin: [0.0, 0.0],
            spacing: 1.0,
            nx: 3,
            ny: 3,
            heights: (0..9).map(|k| 0.5 * (k % 3) as f64).collect(),
        };
        let (d, n) = Obstacle::HeightField(hf).distance(DVec3::new(1.3, 0.7, 2.0));
        let plane = Obstacle::Plane {
            normal: DVec3::new(-0.5, 0.0, 1.0).normalize(),
            offset: 0.0,
        };
        let (dp, np) = plane.distance(DVec3::new(1.3, 0.7, 2.0));
        assert!((d - dp).abs() < EXACT && (n - np).length() < EXACT);
    }
}
