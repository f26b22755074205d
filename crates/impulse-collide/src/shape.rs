//! Collision shapes: sets of convex pieces, and the distance between two of them.
//!
//! A [`Shape`] is one or more convex pieces (exact spheres or convex polyhedra), each placed in
//! the body frame, each with a bounding sphere. A convex body is a shape of one piece; a
//! non-convex body is the union of its convex pieces, and its distance to another body is the
//! minimum over piece pairs (thesis eq. 2.1). The bounding spheres form a two-level hierarchy
//! (the shape's sphere around its pieces' spheres): piece pairs are visited in order of their
//! spheres' gap, and the search stops as soon as that lower bound reaches the best distance
//! found, so only the parts that can matter are examined exactly.

use glam::DVec3;
use impulse_geom::{Aabb, ConvexPolyhedron, Ellipsoid, Pose, Sphere};

use crate::CollideError;
use crate::feature::{Closest, Feature, FeaturePair};
use crate::gjk::{self, SupportBody};
use crate::{point, vclip};

/// Relative difference below which two semi-axes of an ellipsoid count as equal, making it a
/// solid of revolution ([`Shape::symmetry_axis`]): rounding of axes given equal. Default
/// `1e-12`.
pub const REVOLUTION_REL: f64 = 1e-12;

/// A convex piece: an exact sphere or ellipsoid (centred on its frame's origin) or a convex
/// polyhedron.
#[derive(Clone, Debug)]
pub enum Convex {
    /// Exact sphere.
    Sphere(Sphere),
    /// Exact (smooth) ellipsoid, semi-axes along the piece frame's axes.
    Ellipsoid(Ellipsoid),
    /// Convex polyhedron.
    Polyhedron(ConvexPolyhedron),
}

impl Convex {
    /// A bounding sphere in the piece's own frame: (centre, radius).
    fn bounding_sphere(&self) -> (DVec3, f64) {
        match self {
            Convex::Sphere(s) => (DVec3::ZERO, s.radius()),
            Convex::Ellipsoid(e) => (DVec3::ZERO, e.bounding_radius(DVec3::ZERO)),
            Convex::Polyhedron(p) => {
                let c = p.mesh().bounding_box_center();
                (c, p.bounding_radius(c))
            }
        }
    }

    /// Radius of the smallest sphere about `center` (piece frame) containing the piece.
    fn radius_about(&self, center: DVec3) -> f64 {
        match self {
            Convex::Sphere(s) => s.bounding_radius(center),
            Convex::Ellipsoid(e) => e.bounding_radius(center),
            Convex::Polyhedron(p) => p.bounding_radius(center),
        }
    }

    /// Tight bounding box of the piece placed at `pose`.
    fn aabb(&self, pose: &Pose) -> Aabb {
        match self {
            Convex::Sphere(s) => s.aabb(pose),
            Convex::Ellipsoid(e) => e.aabb(pose),
            Convex::Polyhedron(p) => p.aabb(pose),
        }
    }

    /// The piece placed at `pose`, as a support mapping (for GJK).
    pub fn placed<'a>(&'a self, pose: &'a Pose) -> SupportBody<'a> {
        match self {
            Convex::Sphere(s) => SupportBody::Sphere {
                radius: s.radius(),
                center: pose.translation,
            },
            Convex::Ellipsoid(e) => SupportBody::Ellipsoid(e, pose),
            Convex::Polyhedron(p) => SupportBody::Polyhedron(p, pose),
        }
    }

    /// Number of features, for sizing caches and statistics (a smooth piece has one).
    pub fn feature_count(&self) -> usize {
        match self {
            Convex::Sphere(_) | Convex::Ellipsoid(_) => 1,
            Convex::Polyhedron(p) => p.vertices().len() + p.edges().len() + p.face_count(),
        }
    }
}

/// A convex piece placed in a body.
#[derive(Clone, Debug)]
pub struct Piece {
    /// The piece's geometry, in its own frame.
    pub convex: Convex,
    /// The piece's frame in the body frame.
    pub pose: Pose,
    /// Centre of the piece's bounding sphere, body frame.
    pub center: DVec3,
    /// Radius of the piece's bounding sphere.
    pub radius: f64,
}

/// A collision shape: one or more convex pieces in a body frame.
#[derive(Clone, Debug)]
pub struct Shape {
    pieces: Vec<Piece>,
}

impl Shape {
    /// A solid sphere of `radius` centred on the body origin.
    ///
    /// # Errors
    /// [`CollideError::Geom`] unless the radius is finite and positive.
    pub fn sphere(radius: f64) -> Result<Self, CollideError> {
        Ok(Self::convex(Convex::Sphere(Sphere::new(radius)?)))
    }

    /// A solid ellipsoid with `semi_axes` along the body axes, centred on the body origin.
    ///
    /// # Errors
    /// [`CollideError::Geom`] unless every semi-axis is finite and positive.
    pub fn ellipsoid(semi_axes: DVec3) -> Result<Self, CollideError> {
        Ok(Self::convex(Convex::Ellipsoid(Ellipsoid::new(semi_axes)?)))
    }

    /// A convex polyhedron in the body frame.
    pub fn polyhedron(poly: ConvexPolyhedron) -> Self {
        Self::convex(Convex::Polyhedron(poly))
    }

    fn convex(convex: Convex) -> Self {
        let (center, radius) = convex.bounding_sphere();
        Self {
            pieces: vec![Piece {
                convex,
                pose: Pose::IDENTITY,
                center,
                radius,
            }],
        }
    }

    /// A non-convex body as a union of convex pieces, each at a pose in the body frame.
    ///
    /// # Errors
    /// [`CollideError::EmptyCompound`] for no pieces; [`CollideError::NonFinitePose`] naming
    /// the piece whose pose is not finite.
    pub fn compound(parts: Vec<(Pose, Convex)>) -> Result<Self, CollideError> {
        if parts.is_empty() {
            return Err(CollideError::EmptyCompound);
        }
        let mut pieces = Vec::with_capacity(parts.len());
        for (index, (pose, convex)) in parts.into_iter().enumerate() {
            if !pose.is_finite() {
                return Err(CollideError::NonFinitePose { piece: index });
            }
            let (c, radius) = convex.bounding_sphere();
            pieces.push(Piece {
                center: pose.transform_point(c),
                convex,
                pose,
                radius,
            });
        }
        Ok(Self { pieces })
    }

    /// The pieces.
    pub fn pieces(&self) -> &[Piece] {
        &self.pieces
    }

    /// Tight bounding box of the shape placed at `pose`.
    pub fn aabb(&self, pose: &Pose) -> Aabb {
        self.pieces.iter().fold(Aabb::EMPTY, |b, piece| {
            b.union(&piece.convex.aabb(&(*pose * piece.pose)))
        })
    }

    /// How far from `center` (body frame) rotation about it reaches on piece `index`: the
    /// largest distance of a point whose motion can change the piece's distance to anything.
    /// A sphere is the same set whatever it turns about its own centre, so only that centre
    /// counts (|c − center|; zero for a ball about its centre of mass); any other piece counts
    /// its farthest point. This replaces r_max in the rotational term of a time-of-impact
    /// bound (eq. 2.3) for that piece. `None` for an index out of range.
    pub fn rotational_reach(&self, index: usize, center: DVec3) -> Option<f64> {
        let p = self.pieces.get(index)?;
        let local = p.pose.inverse_transform_point(center);
        Some(match &p.convex {
            Convex::Sphere(_) => local.length(),
            c => c.radius_about(local),
        })
    }

    /// The symmetry axis of piece `index` when it is a solid of revolution other than a
    /// sphere (an ellipsoid with two equal semi-axes, to [`REVOLUTION_REL`]): the axis (unit,
    /// body frame) and a point on it (the piece's centre, body frame). Turning about that
    /// axis leaves the piece the same set, so it moves nothing the piece can touch: a wheel
    /// rolling turns about it. `None` for any other piece, or an index out of range.
    pub fn symmetry_axis(&self, index: usize) -> Option<(DVec3, DVec3)> {
        let p = self.pieces.get(index)?;
        let Convex::Ellipsoid(e) = &p.convex else {
            return None;
        };
        let s = e.semi_axes();
        let same = |a: f64, b: f64| (a - b).abs() <= REVOLUTION_REL * a.max(b);
        let local = if same(s.x, s.y) && !same(s.y, s.z) {
            DVec3::Z
        } else if same(s.y, s.z) && !same(s.z, s.x) {
            DVec3::X
        } else if same(s.z, s.x) && !same(s.x, s.y) {
            DVec3::Y
        } else {
            return None;
        };
        Some((p.pose.rotation * local, p.pose.translation))
    }

    /// Radius of the smallest sphere about `center` (body frame) containing the shape: r_max
    /// of thesis §2.3.2 when `center` is the centre of mass.
    pub fn bounding_radius(&self, center: DVec3) -> f64 {
        self.pieces
            .iter()
            .map(|p| {
                p.convex
                    .radius_about(p.pose.inverse_transform_point(center))
            })
            .fold(0.0, f64::max)
    }
}

/// Distance between two convex pieces placed in the world, warm-started from `warm`: exact
/// formulas for spheres, V-Clip for polyhedra, GJK for any pair with an ellipsoid.
pub fn convex_closest(
    a: &Convex,
    pose_a: &Pose,
    b: &Convex,
    pose_b: &Pose,
    warm: FeaturePair,
) -> Closest {
    match (a, b) {
        (Convex::Ellipsoid(_), _) | (_, Convex::Ellipsoid(_)) => {
            gjk::closest(&a.placed(pose_a), &b.placed(pose_b), warm)
        }
        (Convex::Sphere(sa), Convex::Sphere(sb)) => point::sphere_sphere(
            sa.radius(),
            pose_a.translation,
            sb.radius(),
            pose_b.translation,
        ),
        (Convex::Sphere(s), Convex::Polyhedron(p)) => {
            point::sphere_polyhedron(s.radius(), pose_a.translation, p, pose_b, warm.b)
        }
        (Convex::Polyhedron(p), Convex::Sphere(s)) => {
            let c = point::sphere_polyhedron(s.radius(), pose_b.translation, p, pose_a, warm.a);
            Closest {
                point_a: c.point_b,
                point_b: c.point_a,
                features: FeaturePair {
                    a: c.features.b,
                    b: c.features.a,
                },
                ..c
            }
        }
        (Convex::Polyhedron(pa), Convex::Polyhedron(pb)) => {
            vclip::closest(pa, pose_a, pb, pose_b, warm)
        }
    }
}

/// The cached closest features of every piece pair of two shapes (coherence).
#[derive(Clone, Debug, Default)]
pub struct PairCache {
    features: Vec<FeaturePair>,
}

impl PairCache {
    fn slot(&mut self, i: usize, j: usize, nb: usize, len: usize) -> &mut FeaturePair {
        if self.features.len() != len {
            self.features = vec![FeaturePair::default(); len];
        }
        &mut self.features[i * nb + j]
    }
}

/// The distance between two shapes and where it is attained.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShapeClosest {
    /// The closest pair of pieces' answer (world frame). Penetrating if any pair penetrates.
    pub closest: Closest,
    /// Indices of the piece of each shape attaining it.
    pub pieces: (u32, u32),
    /// Piece pairs examined exactly.
    pub tested: u32,
    /// Piece pairs skipped because their bounding spheres were farther than the best distance.
    pub pruned: u32,
}

/// Distance between shapes `a` and `b` (thesis eq. 2.1: the minimum over piece pairs), using
/// and updating `cache`.
pub fn closest(
    a: &Shape,
    pose_a: &Pose,
    b: &Shape,
    pose_b: &Pose,
    cache: &mut PairCache,
) -> ShapeClosest {
    let (na, nb) = (a.pieces.len(), b.pieces.len());
    // Lower bounds from the bounding spheres, visited smallest first.
    let mut order: Vec<(f64, usize, usize)> = Vec::with_capacity(na * nb);
    for (i, pa) in a.pieces.iter().enumerate() {
        let ca = pose_a.transform_point(pa.center);
        for (j, pb) in b.pieces.iter().enumerate() {
            let lb = ca.distance(pose_b.transform_point(pb.center)) - pa.radius - pb.radius;
            order.push((lb, i, j));
        }
    }
    order.sort_by(|x, y| x.0.total_cmp(&y.0).then((x.1, x.2).cmp(&(y.1, y.2))));
    let mut best: Option<ShapeClosest> = None;
    let mut tested = 0;
    for (k, &(lb, i, j)) in order.iter().enumerate() {
        if let Some(b) = &best {
            if b.closest.penetrating || lb >= b.closest.distance {
                let mut out = *b;
                out.tested = tested;
                out.pruned = (order.len() - k) as u32;
                return out;
            }
        }
        let (pa, pb) = (&a.pieces[i], &b.pieces[j]);
        let slot = cache.slot(i, j, nb, na * nb);
        let c = convex_closest(
            &pa.convex,
            &(*pose_a * pa.pose),
            &pb.convex,
            &(*pose_b * pb.pose),
            *slot,
        );
        *slot = c.features;
        tested += 1;
        let better = match &best {
            None => true,
            Some(b) => c.penetrating || c.distance < b.closest.distance,
        };
        if better {
            best = Some(ShapeClosest {
                closest: c,
                pieces: (i as u32, j as u32),
                tested,
                pruned: 0,
            });
        }
    }
    let mut out = best.unwrap_or(ShapeClosest {
        closest: Closest {
            distance: f64::INFINITY,
            point_a: pose_a.translation,
            point_b: pose_b.translation,
            features: FeaturePair {
                a: Feature::Vertex(0),
                b: Feature::Vertex(0),
            },
            penetrating: false,
            steps: 0,
            fallback: false,
        },
        pieces: (0, 0),
        tested: 0,
        pruned: 0,
    });
    out.tested = tested;
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::brute;
    use glam::DQuat;
    use impulse_geom::primitives;
    use rand::rngs::Xoshiro256PlusPlus;
    use rand::{RngExt, SeedableRng};

    const DISTANCE_REL: f64 = 1e-9;

    fn l_shape() -> Shape {
        let bar = |h: DVec3| Convex::Polyhedron(primitives::cuboid(h).unwrap());
        Shape::compound(vec![
            (
                Pose::from_translation(DVec3::new(0.0, 0.0, 0.0)),
                bar(DVec3::new(1.0, 0.2, 0.2)),
            ),
            (
                Pose::from_translation(DVec3::new(-0.8, 0.7, 0.0)),
                bar(DVec3::new(0.2, 0.5, 0.2)),
            ),
            (
                Pose::from_translation(DVec3::new(0.9, 0.5, 0.0)),
                Convex::Sphere(Sphere::new(0.3).unwrap()),
            ),
        ])
        .unwrap()
    }

    #[test]
    fn compound_distance_is_the_minimum_over_piece_pairs() {
        let mut r = Xoshiro256PlusPlus::seed_from_u64(21);
        let l = l_shape();
        let cube = Shape::polyhedron(primitives::cuboid(DVec3::splat(0.3)).unwrap());
        let mut cache = PairCache::default();
        let mut pruned = 0;
        for _ in 0..2_000 {
            let q = DQuat::from_euler(
                glam::EulerRot::XYZ,
                r.random::<f64>() * 6.3,
                r.random::<f64>() * 6.3,
                r.random::<f64>() * 6.3,
            );
            let pb = Pose::new(
                q,
                (DVec3::new(r.random(), r.random(), r.random()) - 0.5) * 4.0,
            );
            let got = closest(&l, &Pose::IDENTITY, &cube, &pb, &mut cache);
            pruned += got.pruned;
            // Reference: every piece pair by brute force (spheres via the point distance).
            let mut want = f64::INFINITY;
            let mut any_overlap = false;
            let Convex::Polyhedron(c) = &cube.pieces()[0].convex else {
                unreachable!()
            };
            for p in l.pieces() {
                let d = match &p.convex {
                    Convex::Polyhedron(poly) => {
                        let b = brute::closest(poly, &p.pose, c, &pb);
                        any_overlap |= b.penetrating;
                        b.distance
                    }
                    Convex::Sphere(s) => {
                        let b = point::brute_closest_point(c, &pb, p.pose.translation);
                        any_overlap |= b.distance <= s.radius();
                        (b.distance - s.radius()).max(0.0)
                    }
                    Convex::Ellipsoid(_) => unreachable!("the L shape has no ellipsoid"),
                };
                want = want.min(d);
            }
            if any_overlap {
                assert!(got.closest.penetrating || got.closest.distance <= DISTANCE_REL);
            } else {
                assert!(
                    (got.closest.distance - want).abs() <= DISTANCE_REL * 3.0,
                    "{} vs {want}",
                    got.closest.distance
                );
                assert!(
                    (got.closest.point_a.distance(got.closest.point_b) - want).abs()
                        <= DISTANCE_REL * 3.0
                );
            }
        }
        assert!(
            pruned > 1_000,
            "the hierarchy pruned only {pruned} piece pairs"
        );
    }

    #[test]
    fn bounds_and_errors() {
        let l = l_shape();
        let pose = Pose::new(DQuat::from_rotation_z(0.4), DVec3::new(1.0, 2.0, 3.0));
        let b = l.aabb(&pose);
        for p in l.pieces() {
            if let Convex::Polyhedron(poly) = &p.convex {
                for &v in poly.vertices() {
                    assert!(
                        b.expanded(1e-12)
                            .contains_point(pose.transform_point(p.pose.transform_point(v)))
                    );
                }
            }
        }
        // r_max about the body origin: the upright bar's far corner (−1.0, 1.2, ±0.2) at √2.48
        // beats the long bar's corners (√1.08) and the sphere (√1.06 + 0.3).
        assert!((l.bounding_radius(DVec3::ZERO) - 2.48f64.sqrt()).abs() < 1e-12);
        // Rotational reach: the sphere piece (centre (0.9, 0.5, 0)) only by its centre; the
        // long bar by its far corner (1, 0.2, 0.2).
        let c = DVec3::ZERO;
        assert!((l.rotational_reach(2, c).unwrap() - 1.06f64.sqrt()).abs() < 1e-12);
        assert!((l.rotational_reach(0, c).unwrap() - 1.08f64.sqrt()).abs() < 1e-12);
        assert_eq!(
            Shape::sphere(0.3).unwrap().rotational_reach(0, c),
            Some(0.0)
        );
        assert_eq!(l.rotational_reach(3, c), None);
        assert!(matches!(
            Shape::compound(vec![]),
            Err(CollideError::EmptyCompound)
        ));
        let bad = Pose {
            rotation: DQuat::IDENTITY,
            translation: DVec3::NAN,
        };
        assert!(matches!(
            Shape::compound(vec![(bad, Convex::Sphere(Sphere::new(1.0).unwrap()))]),
            Err(CollideError::NonFinitePose { piece: 0 })
        ));
        assert!(Shape::sphere(-1.0).is_err());
    }
}
