//! What a manifold leaves out: the vertices outside its contact features, as extra points
//! where they lie over the other piece's contact face, and the clearance of the rest.
//!
//! A manifold holds one contact feature per piece (a face, an edge or a vertex, with the
//! points clipped from it). A solver that keeps a turning pair in contact over a step of
//! length h must know that no *other* feature can arrive within it: a polygonal coin rolling
//! on its rim brings the next rim vertex down, a box tipping about an edge brings its far edge
//! down, and a coin lying almost flat on a rim edge has the rest of its rim a few ε_c up
//! (its face is not wholly within the tolerance, so it is not the contact feature).
//!
//! - **Outside points.** A vertex outside its piece's contact feature, within the tolerance
//!   of the other piece's support plane along the normal, and over the other piece's contact
//!   face (its projection along the normal inside that face's polygon), is a vertex–face
//!   point like those clipping gives: `(Vertex, Face)` or `(Face, Vertex)`.
//! - **Clearance.** Every other vertex outside the contact features counts with its
//!   distance along the normal to the other piece's support plane: the whole of the other
//!   piece lies beyond that plane, so this is a lower bound on its distance to it. A step
//!   over which the pair's surfaces approach by less than the clearance brings no feature
//!   into contact that the manifold and its outside points do not hold.
//!
//! Smooth pieces (spheres, ellipsoids) have no features besides the one they touch with:
//! their side contributes nothing. Piece pairs of compound shapes that have no manifold
//! count with the distance between their bounding spheres.

use glam::DVec3;
use impulse_geom::{ConvexPolyhedron, Pose};

use super::{ContactPoint, Manifold};
use crate::feature::{Feature, FeaturePair};
use crate::shape::{Convex, Shape};

/// What a convex pair's manifold leaves out (module documentation).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Outside {
    /// Vertex–face points of vertices outside the contact features, within the tolerance and
    /// over the other piece's contact face.
    pub points: Vec<ContactPoint>,
    /// Lower bound on the distance from every other vertex outside the contact features to
    /// the other piece (`f64::INFINITY` when there is none).
    pub clearance: f64,
}

/// What the manifold `m` of two convex pieces leaves out, with points taken up to
/// `tolerance` (module documentation).
#[must_use]
pub fn convex_outside(
    a: &Convex,
    pose_a: &Pose,
    b: &Convex,
    pose_b: &Pose,
    m: &Manifold,
    tolerance: f64,
) -> Outside {
    let n = m.normal;
    // The support plane of each piece facing the other: `a`'s along n, `b`'s along −n.
    let top_a = a.placed(pose_a).support_point(n).dot(n);
    let low_b = b.placed(pose_b).support_point(-n).dot(n);
    let mut out = Outside {
        points: Vec::new(),
        clearance: f64::INFINITY,
    };
    // A contact feature clipped against the other's face (an edge or a vertex on a face, or
    // either face of two: the manifold is their overlap): its vertices off the other's face
    // are stood for by the points where the features' edges cross.
    let (clip_a, clip_b) = match (m.features.a, m.features.b) {
        (Feature::Face(_), Feature::Face(_)) => (true, true),
        (Feature::Face(_), _) => (false, true),
        (_, Feature::Face(_)) => (true, false),
        _ => (false, false),
    };
    // A vertex of `a` is at least low_b − x·n from `b`'s support plane, one of `b` at least
    // x·n − top_a from `a`'s: each is the other's plane offset less x along its own normal.
    let sides = [
        (
            Side::A,
            a,
            pose_a,
            m.features.a,
            b,
            pose_b,
            m.features.b,
            n,
            low_b,
            clip_a,
        ),
        (
            Side::B,
            b,
            pose_b,
            m.features.b,
            a,
            pose_a,
            m.features.a,
            -n,
            -top_a,
            clip_b,
        ),
    ];
    for (side, own, own_pose, feature, other, other_pose, other_feature, dir, plane, clip) in sides
    {
        let Convex::Polyhedron(p) = own else { continue };
        let face = face_of(other, other_pose, other_feature);
        let held = |v: u32| {
            m.points()
                .iter()
                .any(|q| side.of(&q.id) == Feature::Vertex(v))
        };
        for (v, x) in unheld(p, own_pose, held) {
            let d = plane - x.dot(dir);
            let onto = x + d * dir;
            match face.as_ref().filter(|f| d <= tolerance && f.covers(onto)) {
                Some(f) => out.points.push(side.point(v, x, f.index, onto, d)),
                // A vertex of the clipped contact feature off the other's contact face: the
                // points where the feature crosses the face's side planes stand for it.
                None if clip && in_feature(p, feature, v) => {}
                None => {
                    out.clearance = out.clearance.min(distance_bound(other, other_pose, x, d));
                }
            }
        }
    }
    out.clearance = out.clearance.max(0.0);
    out
}

/// Which piece of the pair a vertex belongs to.
#[derive(Clone, Copy)]
enum Side {
    A,
    B,
}

impl Side {
    /// This side's feature of a point's id.
    fn of(self, id: &FeaturePair) -> Feature {
        match self {
            Side::A => id.a,
            Side::B => id.b,
        }
    }

    /// The vertex–face point of this side's vertex `v` at `x` over the other's face `f`, at
    /// `onto` on it, `gap` apart.
    fn point(self, v: u32, x: DVec3, f: u32, onto: DVec3, gap: f64) -> ContactPoint {
        let (vertex, face) = (Feature::Vertex(v), Feature::Face(f));
        match self {
            Side::A => ContactPoint {
                point_a: x,
                point_b: onto,
                gap,
                id: FeaturePair { a: vertex, b: face },
            },
            Side::B => ContactPoint {
                point_a: onto,
                point_b: x,
                gap,
                id: FeaturePair { a: face, b: vertex },
            },
        }
    }
}

/// A lower bound on the distance from the world point `x` to the piece `c`: the largest
/// signed distance to its face planes for a polyhedron (exact over a face, less beside
/// one), and the larger of that and `plane`, the distance along the normal to its support
/// plane; only `plane` for a smooth piece.
fn distance_bound(c: &Convex, pose: &Pose, x: DVec3, plane: f64) -> f64 {
    match c {
        Convex::Polyhedron(p) => plane.max(p.max_plane_distance(pose.inverse_transform_point(x))),
        _ => plane,
    }
}

/// What two shapes' manifolds leave out (one manifold per touching piece pair, as from
/// [`super::shape_manifolds`]): each manifold's outside points ([`convex_outside`], in the
/// order of `manifolds`), and the smallest clearance over them and over the piece pairs
/// without a manifold (the distance between their bounding spheres).
#[must_use]
pub fn shape_outside(
    a: &Shape,
    pose_a: &Pose,
    b: &Shape,
    pose_b: &Pose,
    manifolds: &[Manifold],
    tolerance: f64,
) -> (Vec<Vec<ContactPoint>>, f64) {
    let mut points = vec![Vec::new(); manifolds.len()];
    let mut clearance = f64::INFINITY;
    for (i, pa) in a.pieces().iter().enumerate() {
        let wa = *pose_a * pa.pose;
        for (j, pb) in b.pieces().iter().enumerate() {
            let pieces = (i as u32, j as u32);
            match manifolds.iter().position(|m| m.pieces == pieces) {
                Some(k) => {
                    let wb = *pose_b * pb.pose;
                    let o =
                        convex_outside(&pa.convex, &wa, &pb.convex, &wb, &manifolds[k], tolerance);
                    points[k] = o.points;
                    clearance = clearance.min(o.clearance);
                }
                None => {
                    clearance = clearance.min(piece_sphere_clearance(a, pose_a, i, b, pose_b, j));
                }
            }
        }
    }
    (points, clearance)
}

/// The clearance [`shape_outside`] gives piece pair `(i, j)` of two shapes when it holds no
/// manifold: the distance between the pieces' bounding spheres, or 0 where they overlap.
/// (A caller that knows a pair will hold none bounds the clearance by it, before the
/// manifolds are made.)
#[must_use]
pub fn piece_sphere_clearance(
    a: &Shape,
    pose_a: &Pose,
    i: usize,
    b: &Shape,
    pose_b: &Pose,
    j: usize,
) -> f64 {
    let (pa, pb) = (&a.pieces()[i], &b.pieces()[j]);
    let ca = pose_a.transform_point(pa.center);
    let cb = pose_b.transform_point(pb.center);
    (ca.distance(cb) - pa.radius - pb.radius).max(0.0)
}

/// A contact face in world coordinates, for the test of a point over it.
struct Face {
    index: u32,
    corners: Vec<DVec3>,
    normal: DVec3,
    /// Slack of the inside test (length²): the polyhedron's precision times an edge length.
    slack: f64,
}

impl Face {
    /// Whether `x` (on the face's plane, up to the tolerance) lies inside the polygon, seen
    /// along its normal.
    fn covers(&self, x: DVec3) -> bool {
        let k = self.corners.len();
        (0..k).all(|i| {
            let (p, q) = (self.corners[i], self.corners[(i + 1) % k]);
            (q - p).cross(x - p).dot(self.normal) >= -self.slack * (q - p).length()
        })
    }
}

/// The contact face of a piece when its contact feature is a face of a polyhedron.
fn face_of(c: &Convex, pose: &Pose, feature: Feature) -> Option<Face> {
    let (Convex::Polyhedron(p), Feature::Face(f)) = (c, feature) else {
        return None;
    };
    if !feature.is_valid_for(p) {
        return None;
    }
    Some(Face {
        index: f,
        corners: p
            .face_vertices(f)
            .iter()
            .map(|&v| pose.transform_point(p.vertex(v)))
            .collect(),
        normal: pose.transform_vector(p.face_plane(f).normal),
        slack: p.tolerance(),
    })
}

/// A polyhedron's vertices that no point of the manifold holds (`held`), with their world
/// positions: those outside its contact feature, and those of the feature that clipping
/// left out or reduction dropped (a 16-gon face is held by four of its corners).
fn unheld<'a>(
    p: &'a ConvexPolyhedron,
    pose: &'a Pose,
    held: impl Fn(u32) -> bool + 'a,
) -> impl Iterator<Item = (u32, DVec3)> + 'a {
    (0..p.vertices().len() as u32)
        .filter(move |&v| !held(v))
        .map(move |v| (v, pose.transform_point(p.vertex(v))))
}

/// Whether vertex `v` belongs to `feature` (is it, an end of it, or a corner of it).
fn in_feature(p: &ConvexPolyhedron, feature: Feature, v: u32) -> bool {
    if !feature.is_valid_for(p) {
        return false;
    }
    match feature {
        Feature::Vertex(u) => u == v,
        Feature::Edge(e) => {
            let e = p.edge(e);
            e.tail == v || e.head == v
        }
        Feature::Face(f) => p.face_vertices(f).contains(&v),
    }
}
