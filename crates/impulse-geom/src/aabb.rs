//! Axis-aligned bounding boxes.

use glam::DVec3;

/// An axis-aligned box `[min, max]` (inclusive), in whatever frame its points were given.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Lower corner.
    pub min: DVec3,
    /// Upper corner.
    pub max: DVec3,
}

impl Aabb {
    /// The empty box: the identity of [`Aabb::union`]; it contains and overlaps nothing.
    pub const EMPTY: Aabb = Aabb {
        min: DVec3::INFINITY,
        max: DVec3::NEG_INFINITY,
    };

    /// A box from its corners (component-wise min and max are taken, so the order is free).
    pub fn new(a: DVec3, b: DVec3) -> Self {
        Self {
            min: a.min(b),
            max: a.max(b),
        }
    }

    /// The smallest box containing all `points` ([`Aabb::EMPTY`] if there are none).
    pub fn from_points(points: impl IntoIterator<Item = DVec3>) -> Self {
        points.into_iter().fold(Self::EMPTY, |b, p| Self {
            min: b.min.min(p),
            max: b.max.max(p),
        })
    }

    /// True when the box contains no point.
    pub fn is_empty(&self) -> bool {
        !(self.min.cmple(self.max).all())
    }

    /// The smallest box containing both.
    pub fn union(&self, other: &Aabb) -> Aabb {
        Aabb {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    /// True when the two (closed) boxes share at least one point.
    pub fn overlaps(&self, other: &Aabb) -> bool {
        self.min.cmple(other.max).all() && other.min.cmple(self.max).all()
    }

    /// True when `p` lies in the (closed) box.
    pub fn contains_point(&self, p: DVec3) -> bool {
        self.min.cmple(p).all() && p.cmple(self.max).all()
    }

    /// The box grown by `margin` on every side.
    pub fn expanded(&self, margin: f64) -> Aabb {
        Aabb {
            min: self.min - DVec3::splat(margin),
            max: self.max + DVec3::splat(margin),
        }
    }

    /// Centre point.
    pub fn center(&self) -> DVec3 {
        0.5 * (self.min + self.max)
    }

    /// Half the side lengths.
    pub fn half_extents(&self) -> DVec3 {
        0.5 * (self.max - self.min)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overlap_agrees_with_interval_arithmetic() {
        let a = Aabb::new(DVec3::ZERO, DVec3::ONE);
        let touching = Aabb::new(DVec3::new(1.0, 0.5, 0.5), DVec3::splat(2.0));
        let apart = Aabb::new(DVec3::new(1.0 + 1e-12, 0.0, 0.0), DVec3::splat(2.0));
        assert!(a.overlaps(&touching) && touching.overlaps(&a));
        assert!(!a.overlaps(&apart) && !apart.overlaps(&a));
        assert!(!Aabb::EMPTY.overlaps(&a) && Aabb::EMPTY.is_empty());
        assert_eq!(Aabb::EMPTY.union(&a), a);
        let pts = [DVec3::new(1.0, -2.0, 3.0), DVec3::new(-1.0, 2.0, 0.0)];
        let b = Aabb::from_points(pts);
        assert_eq!(
            b,
            Aabb {
                min: DVec3::new(-1.0, -2.0, 0.0),
                max: DVec3::new(1.0, 2.0, 3.0)
            }
        );
        assert!(pts.iter().all(|&p| b.contains_point(p)));
        assert_eq!(b.expanded(1.0).half_extents(), DVec3::new(2.0, 3.0, 2.5));
    }
}
