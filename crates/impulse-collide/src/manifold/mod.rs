//! Contact manifolds: where two touching convex pieces press on each other, as up to
//! [`MAX_POINTS`] points, each named by the features that produced it.
//!
//! A closest-features query ([`crate::shape::convex_closest`]) gives one pair of closest
//! points. Within the collision envelope (thesis §2.2: closer than ε_c counts as contact) a
//! body resting face down touches along a whole polygon, and a solver that holds it there
//! (sustained contact, thesis §8.1) needs that polygon's corners, the gap at each, and names
//! for them that survive from one step to the next (to carry accumulated impulses over: warm
//! starting). This module computes them from the contact normal `n` (unit, from `a` toward
//! `b`) and a distance tolerance (ε_c scale):
//!
//! 1. **Contact features.** For each polyhedron, the vertices within the tolerance of its
//!    support plane along the normal (`a` along `n`, `b` along `−n`). If a face lies entirely
//!    among them (and faces the normal within [`FACE_MIN_COS`]) the contact feature is the best
//!    aligned such face; else an edge with both ends among them; else the supporting vertex.
//!    A smooth piece (sphere, ellipsoid) has one feature, `Vertex(0)`.
//! 2. **Points.** A face against anything: the other feature (a face polygon, an edge, a
//!    vertex) is clipped against the side planes of the face, the planes through its edges
//!    parallel to the normal (Sutherland–Hodgman for a polygon, the same planes for a segment:
//!    edge–face gives two points); each clipped point lies on the incident feature, and its
//!    partner is its projection along the normal onto the face's plane. When both contact
//!    features are faces, `a`'s face is the reference (a fixed choice, so that the names do
//!    not flicker; the clipped region is the overlap of the two faces either way). Two
//!    parallel edges (within the tolerance over their length): the ends of their common
//!    stretch, two points; any other pair of edges or vertices: their closest points, one
//!    point. A smooth piece: one point, its support point along the normal, paired with that
//!    point moved along the normal onto the other piece's support plane.
//! 3. **Filtering and reduction.** Points whose gap exceeds the tolerance are dropped; points
//!    within [`POINT_MERGE_FRACTION`] of the tolerance of one another (or of the polyhedra's own
//!    precision, [`impulse_geom::ConvexPolyhedron::tolerance`]) are merged, the deeper kept, and
//!    a corner that close outside a side plane is kept where it is rather than cut (so
//!    positions near coincident edges are exact to that distance, and their names do not
//!    depend on rounding). More than [`MAX_POINTS`] are reduced to the four whose convex hull
//!    is largest among the sets of four holding the deepest point (a solver must hold it):
//!    every set is tried up to twelve points, a greedy choice (deepest, farthest from it,
//!    largest triangle, largest hull) with single exchanges beyond. Collinear points keep the
//!    deepest and the two ends. If clipping leaves nothing (a normal inconsistent with the
//!    features), the pair of supporting vertices is the one point.
//!
//! Every point carries `point_a` on `a`'s surface, `point_b` on `b`'s, the signed gap
//! `(point_b − point_a)·n` (negative: overlap), and an id: the [`FeaturePair`] of `a` and `b`
//! that produced it — `(Vertex, Face)` for a corner of one inside the other's face, `(Edge,
//! Edge)` where an edge crosses a side plane, `(Face, Vertex)` the other way round. The ids do
//! not depend on which face was the reference, so they stay the same while a body slides or
//! turns a little; [`match_points`] pairs a new manifold's points
//! with the previous one's by id, and by position when an id is new.
//!
//! Compound shapes (thesis eq. 2.1) give one manifold per touching piece pair
//! ([`shape_manifolds`]).
//!
//! [`crate::patch::near_vertices`] answers a different question for the impulse model (every
//! vertex near the other body, to place one impulse); a manifold is the contact as a
//! contact-constrained solver needs it: the overlap region's corners, with gaps and names.
//!
//! | quantity | what it is | where |
//! |---|---|---|
//! | tolerance | contact distance: features and points within it count (ε_c scale, positive) | parameter |
//! | [`FACE_MIN_COS`] | smallest cosine between a contact face and the normal | constant |
//! | [`POINT_MERGE_FRACTION`] | points closer than this fraction of the tolerance are one | constant |
//! | [`NORMAL_FROM_POINTS_FRACTION`] | closest points farther apart than this fraction of the tolerance give the normal | constant |
//! | [`coherence::MATCH_NORMAL_MIN_COS`] | normals must agree this well for points to match | constant |

use glam::DVec3;
use impulse_geom::Pose;

use crate::depth;
use crate::feature::{Closest, Feature, FeaturePair};
use crate::shape::{self, Convex, Shape};

mod clearance;
mod clip;
pub mod coherence;
mod reduce;
#[cfg(test)]
pub(crate) mod tests;

pub use clearance::{Outside, convex_outside, piece_sphere_clearance, shape_outside};
pub use coherence::match_points;

/// Most points a manifold keeps: four span a face contact's area, and a contact-constrained
/// solver's cost grows with the points per pair.
pub const MAX_POINTS: usize = 4;

/// Smallest cosine between the outward normal of a contact face and the contact normal
/// (dimensionless, default `0.5`, 60°). A face within the tolerance of the support plane
/// but steeper than this is a sliver at most 2·tolerance/sin 60° wide: it is treated as an
/// edge or a vertex, and projecting along the normal onto its plane stays well conditioned
/// (the projection divides by this cosine).
pub const FACE_MIN_COS: f64 = 0.5;

/// Contact points closer than this fraction of the tolerance to each other are one point, and
/// a point this close outside a side plane counts as on it (dimensionless, default `1e-2`).
/// Coincident corners (a box exactly on a box of the same size) then give one point each, not
/// a cluster of nearly equal ones that a solver would see as redundant constraints; the
/// polyhedra's own precision ([`impulse_geom::ConvexPolyhedron::tolerance`]) is the floor.
pub const POINT_MERGE_FRACTION: f64 = 1e-2;

/// Closest points farther apart than this fraction of the tolerance give the contact normal
/// (their direction); closer, or penetrating, the separating axis gives it
/// ([`crate::depth::separating_axis`]) (dimensionless, default `1e-3`). The direction of two
/// points `d` apart is uncertain by about ε·|x|/d rad (ε the f64 precision, |x| the size of
/// the coordinates): `1e-3` of ε_c keeps that below `1e-9` rad for ε_c down to `1e-4` of the
/// coordinates.
pub const NORMAL_FROM_POINTS_FRACTION: f64 = 1e-3;

/// Why a manifold could not be computed from its input.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ManifoldError {
    /// The tolerance is not finite and positive.
    #[error("the contact tolerance must be finite and positive, not {0}")]
    Tolerance(f64),
    /// The contact normal is zero or not finite.
    #[error("the contact normal must be a finite non-zero vector, not {0}")]
    Normal(DVec3),
    /// A pose is not finite.
    #[error("a pose is not finite")]
    NonFinitePose,
}

/// One contact point of a manifold.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactPoint {
    /// The point on `a`'s surface (world).
    pub point_a: DVec3,
    /// The point on `b`'s surface (world).
    pub point_b: DVec3,
    /// Signed gap along the manifold's normal, `(point_b − point_a)·normal`: positive apart,
    /// negative overlapping.
    pub gap: f64,
    /// The features of `a` and `b` that produced the point: its name from step to step.
    pub id: FeaturePair,
}

impl ContactPoint {
    /// Midway between the two bodies' points (world).
    #[inline]
    pub fn midpoint(&self) -> DVec3 {
        0.5 * (self.point_a + self.point_b)
    }
}

/// The contact of two convex pieces: a normal and one to [`MAX_POINTS`] points.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Manifold {
    /// Unit contact normal (world), from `a` toward `b`.
    pub normal: DVec3,
    /// The contact features of `a` and `b` (see the module documentation, step 1): e.g.
    /// `(Face, Face)` for a box lying flat, `(Edge, Face)` for a box tilted onto an edge.
    pub features: FeaturePair,
    /// Indices of the two pieces in their shapes (`(0, 0)` for a convex pair).
    pub pieces: (u32, u32),
    points: [ContactPoint; MAX_POINTS],
    count: u8,
}

impl Manifold {
    fn new(normal: DVec3, features: FeaturePair, points: &[ContactPoint]) -> Option<Self> {
        let blank = ContactPoint {
            point_a: DVec3::ZERO,
            point_b: DVec3::ZERO,
            gap: 0.0,
            id: FeaturePair::default(),
        };
        let mut out = Self {
            normal,
            features,
            pieces: (0, 0),
            points: [blank; MAX_POINTS],
            count: 0,
        };
        let finite =
            |p: &&ContactPoint| p.point_a.is_finite() && p.point_b.is_finite() && p.gap.is_finite();
        for p in points.iter().filter(finite).take(MAX_POINTS) {
            out.points[out.count as usize] = *p;
            out.count += 1;
        }
        (out.count > 0).then_some(out)
    }

    /// The contact points (one to [`MAX_POINTS`]).
    #[inline]
    pub fn points(&self) -> &[ContactPoint] {
        &self.points[..self.count as usize]
    }

    /// The smallest gap over the points (the deepest point's).
    #[inline]
    pub fn min_gap(&self) -> f64 {
        self.points()
            .iter()
            .map(|p| p.gap)
            .fold(f64::INFINITY, f64::min)
    }
}

fn check(pose_a: &Pose, pose_b: &Pose, tolerance: f64) -> Result<(), ManifoldError> {
    if !(tolerance.is_finite() && tolerance > 0.0) {
        return Err(ManifoldError::Tolerance(tolerance));
    }
    if !(pose_a.is_finite() && pose_b.is_finite()) {
        return Err(ManifoldError::NonFinitePose);
    }
    Ok(())
}

/// The contact normal (unit, world, from `a` toward `b`) of two convex pieces whose
/// closest-features answer is `closest`: the direction between the closest points when they
/// are more than [`NORMAL_FROM_POINTS_FRACTION`] of `tolerance` apart, else (touching,
/// overlapping, or too close for that direction to mean anything) the separating axis
/// ([`crate::depth::separating_axis`], reversed: it points from `b` toward `a`). The latter
/// costs O(E_a·E_b·V) for polyhedra; a caller that tracks a pair can keep the normal last seen
/// at a clear gap and call [`manifold_along`] instead.
#[must_use]
pub fn contact_normal(
    a: &Convex,
    pose_a: &Pose,
    b: &Convex,
    pose_b: &Pose,
    closest: &Closest,
    tolerance: f64,
) -> DVec3 {
    if !closest.penetrating && closest.distance > NORMAL_FROM_POINTS_FRACTION * tolerance {
        if let Some(d) = closest.direction() {
            return d;
        }
    }
    -depth::separating_axis(a, pose_a, b, pose_b).normal
}

/// The manifold of two convex pieces from their closest-features answer `closest` (its
/// features warm-start the search for the contact features), or `None` when they are farther
/// apart than `tolerance` along the contact normal ([`contact_normal`]).
///
/// # Errors
/// [`ManifoldError::Tolerance`] unless `tolerance` is finite and positive;
/// [`ManifoldError::NonFinitePose`] for a non-finite pose.
pub fn convex_manifold(
    a: &Convex,
    pose_a: &Pose,
    b: &Convex,
    pose_b: &Pose,
    closest: &Closest,
    tolerance: f64,
) -> Result<Option<Manifold>, ManifoldError> {
    check(pose_a, pose_b, tolerance)?;
    if !closest.penetrating && closest.distance > tolerance {
        return Ok(None);
    }
    let n = contact_normal(a, pose_a, b, pose_b, closest, tolerance);
    manifold_along(a, pose_a, b, pose_b, n, closest.features, tolerance)
}

/// The manifold of two convex pieces along a given contact `normal` (world, from `a` toward
/// `b`; normalised here), or `None` when they are farther apart than `tolerance` along it.
/// `warm` (e.g. the pair's last closest features) is where the search for each polyhedron's
/// supporting vertex starts; any value is correct, a near one is fast.
///
/// # Errors
/// [`ManifoldError::Tolerance`], [`ManifoldError::NonFinitePose`], and
/// [`ManifoldError::Normal`] for a zero or non-finite normal.
pub fn manifold_along(
    a: &Convex,
    pose_a: &Pose,
    b: &Convex,
    pose_b: &Pose,
    normal: DVec3,
    warm: FeaturePair,
    tolerance: f64,
) -> Result<Option<Manifold>, ManifoldError> {
    check(pose_a, pose_b, tolerance)?;
    let n = normal
        .try_normalize()
        .ok_or(ManifoldError::Normal(normal))?;
    Ok(match (a, b) {
        (Convex::Polyhedron(x), Convex::Polyhedron(y)) => {
            clip::polyhedra(x, pose_a, y, pose_b, n, warm, tolerance)
        }
        _ => smooth(a, pose_a, b, pose_b, n, warm, tolerance),
    })
}

/// One point for a pair with a sphere or an ellipsoid: each smooth piece's support point along
/// the normal, and for a polyhedron that point moved along the normal onto its support plane.
fn smooth(
    a: &Convex,
    pose_a: &Pose,
    b: &Convex,
    pose_b: &Pose,
    n: DVec3,
    warm: FeaturePair,
    tolerance: f64,
) -> Option<Manifold> {
    let hi_a = a.placed(pose_a).support_point(n);
    let lo_b = b.placed(pose_b).support_point(-n);
    let gap = (lo_b - hi_a).dot(n);
    if gap.is_nan() || gap > tolerance {
        return None;
    }
    let feature = |c: &Convex, pose: &Pose, dir: DVec3, warm: Feature| match c {
        Convex::Polyhedron(p) => {
            clip::support_feature(p, pose.inverse_transform_vector(dir), warm, tolerance).feature
        }
        _ => Feature::Vertex(0),
    };
    let (a_smooth, b_smooth) = (
        !matches!(a, Convex::Polyhedron(_)),
        !matches!(b, Convex::Polyhedron(_)),
    );
    let (point_a, point_b) = match (a_smooth, b_smooth) {
        (true, false) => (hi_a, hi_a + gap * n),
        (false, true) => (lo_b - gap * n, lo_b),
        _ => (hi_a, lo_b),
    };
    let features = FeaturePair {
        a: feature(a, pose_a, n, warm.a),
        b: feature(b, pose_b, -n, warm.b),
    };
    let point = ContactPoint {
        point_a,
        point_b,
        gap,
        id: features,
    };
    Manifold::new(n, features, &[point])
}

/// The warm-start features of every piece pair of two shapes, for [`shape_manifolds`].
#[derive(Clone, Debug, Default)]
pub struct ManifoldCache {
    features: Vec<FeaturePair>,
}

/// One manifold per piece pair of two shapes that touch within `tolerance` (thesis eq. 2.1:
/// the pieces of a non-convex body are convex; each touching pair is a contact of its own),
/// each with its [`Manifold::pieces`]; piece pairs whose bounding spheres are farther apart than
/// `tolerance` are skipped. `cache` keeps each piece pair's closest features between calls.
///
/// # Errors
/// As [`convex_manifold`].
pub fn shape_manifolds(
    a: &Shape,
    pose_a: &Pose,
    b: &Shape,
    pose_b: &Pose,
    tolerance: f64,
    cache: &mut ManifoldCache,
) -> Result<Vec<Manifold>, ManifoldError> {
    pieces_manifolds(a, pose_a, b, pose_b, tolerance, cache, None)
}

/// How close a piece pair of two shapes comes when it holds no manifold within the tolerance
/// asked ([`shape_manifolds_near`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PieceClearance {
    /// The piece of `a` and the piece of `b`.
    pub pieces: (u32, u32),
    /// Their distance (above the tolerance).
    pub gap: f64,
    /// Unit direction from `a`'s closest point to `b`'s. The distance of two convex pieces is a
    /// convex function of their relative translation, whose gradient this is: under a
    /// translation `x` of `b` relative to `a`, the distance is at least `gap + direction·x`.
    pub direction: DVec3,
}

/// The piece pairs of two shapes that hold no manifold within a tolerance
/// ([`shape_manifolds_near`]): those whose distance was measured, and a lower bound on the
/// distance of the others.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Clearances {
    /// The piece pairs measured (their bounding spheres within the tolerance), each farther
    /// apart than it.
    pub measured: Vec<PieceClearance>,
    /// The least distance of the pieces' bounding spheres over the pairs not measured (a lower
    /// bound on their distance, above the tolerance); `∞` when every pair was measured.
    pub unmeasured: f64,
}

impl Clearances {
    /// Empty: no piece pair.
    pub const NONE: Clearances = Clearances {
        measured: Vec::new(),
        unmeasured: f64::INFINITY,
    };
}

/// [`shape_manifolds`], and in `clear` how close the piece pairs that hold no manifold come:
/// what a caller that holds two compounds by their touching pieces needs to bound how soon
/// another piece pair can touch.
///
/// # Errors
/// As [`convex_manifold`].
pub fn shape_manifolds_near(
    a: &Shape,
    pose_a: &Pose,
    b: &Shape,
    pose_b: &Pose,
    tolerance: f64,
    cache: &mut ManifoldCache,
    clear: &mut Clearances,
) -> Result<Vec<Manifold>, ManifoldError> {
    clear.measured.clear();
    clear.unmeasured = f64::INFINITY;
    pieces_manifolds(a, pose_a, b, pose_b, tolerance, cache, Some(clear))
}

/// [`shape_manifolds_near`], the clearances optional.
fn pieces_manifolds(
    a: &Shape,
    pose_a: &Pose,
    b: &Shape,
    pose_b: &Pose,
    tolerance: f64,
    cache: &mut ManifoldCache,
    mut clear: Option<&mut Clearances>,
) -> Result<Vec<Manifold>, ManifoldError> {
    check(pose_a, pose_b, tolerance)?;
    let (na, nb) = (a.pieces().len(), b.pieces().len());
    if cache.features.len() != na * nb {
        cache.features = vec![FeaturePair::default(); na * nb];
    }
    let mut out = Vec::new();
    for (i, pa) in a.pieces().iter().enumerate() {
        let (wa, ca) = (*pose_a * pa.pose, pose_a.transform_point(pa.center));
        for (j, pb) in b.pieces().iter().enumerate() {
            let cb = pose_b.transform_point(pb.center);
            let spheres = ca.distance(cb) - pa.radius - pb.radius;
            if spheres > tolerance {
                if let Some(c) = clear.as_deref_mut() {
                    c.unmeasured = c.unmeasured.min(spheres);
                }
                continue;
            }
            let wb = *pose_b * pb.pose;
            let slot = &mut cache.features[i * nb + j];
            let c = shape::convex_closest(&pa.convex, &wa, &pb.convex, &wb, *slot);
            *slot = c.features;
            if let Some(mut m) = convex_manifold(&pa.convex, &wa, &pb.convex, &wb, &c, tolerance)? {
                m.pieces = (i as u32, j as u32);
                out.push(m);
            } else if let Some(clear) = clear.as_deref_mut() {
                // No manifold: the pieces are farther apart than the tolerance, so their
                // closest points are apart and give the direction.
                let direction = (c.point_b - c.point_a).normalize_or_zero();
                clear.measured.push(PieceClearance {
                    pieces: (i as u32, j as u32),
                    gap: c.distance,
                    direction,
                });
            }
        }
    }
    Ok(out)
}
