//! Tests of contact manifolds against independent references: closed forms for boxes, spheres
//! and ellipsoids, an independent 2-D intersection of squares ([`boxes`]), and brute force on
//! random convex hulls ([`random`]); spheres, ellipsoids and compounds in [`smooth`]. Shared
//! here: the tolerances of the tests, the scenes and the id check.

use super::*;
use super::{clip, reduce};
use crate::brute;
use crate::motion::testkit::{random_rotation, rng, unit_vector};
use glam::{DQuat, DVec2};
use impulse_geom::{ConvexPolyhedron, Ellipsoid, Sphere, primitives};
use rand::RngExt;

mod boxes;
mod outside;
mod random;
mod slivers;
mod smooth;

/// The contact tolerance of these tests (m; ε_c for bodies of 5–20 cm, thesis §2.2).
const TOL: f64 = 1e-4;

/// Agreement with closed forms and brute force (m, or dimensionless for ratios and unit
/// vectors; coordinates of order 0.1–1: a few thousand ulps).
const EXACT: f64 = 1e-12;

/// Agreement of a contact normal with the brute-force closest points' direction (unit
/// vectors, separated by at least [`NORMAL_FROM_POINTS_FRACTION`]·TOL = 1e-7 m: the
/// direction of points known to ~1e-16 m is good to ~1e-9).
const DIRECTION: f64 = 1e-8;

fn cuboid(h: DVec3) -> Convex {
    Convex::Polyhedron(primitives::cuboid(h).unwrap())
}

fn poly(c: &Convex) -> &ConvexPolyhedron {
    match c {
        Convex::Polyhedron(p) => p,
        _ => unreachable!("a polyhedron"),
    }
}

/// A 2 m × 2 m × 0.2 m floor whose top face is the plane z = 0.
fn floor() -> (Convex, Pose) {
    (
        cuboid(DVec3::new(1.0, 1.0, 0.1)),
        Pose::from_translation(DVec3::new(0.0, 0.0, -0.1)),
    )
}

/// The face of `c` whose outward normal is `dir` (body frame).
fn face_along(c: &Convex, dir: DVec3) -> Feature {
    let p = poly(c);
    let f = (0..p.face_count() as u32)
        .find(|&f| p.face_plane(f).normal.dot(dir) > 1.0 - EXACT)
        .unwrap();
    Feature::Face(f)
}

/// The manifold as a simulator would ask for it: closest features cold, then the manifold.
fn manifold(a: &Convex, pa: &Pose, b: &Convex, pb: &Pose) -> Option<Manifold> {
    let c = shape::convex_closest(a, pa, b, pb, FeaturePair::default());
    convex_manifold(a, pa, b, pb, &c, TOL).unwrap()
}

/// The world position of a vertex feature of a placed polyhedron.
fn vertex_at(c: &Convex, pose: &Pose, f: Feature) -> DVec3 {
    let Feature::Vertex(v) = f else {
        panic!("{f:?} is not a vertex")
    };
    pose.transform_point(poly(c).vertex(v))
}

/// How far `x` (world) lies from feature `f` of polyhedron `c` placed at `pose`: the distance
/// to a vertex, to an edge's segment, or to a face's polygon (its plane, and outside its
/// edges).
fn off_feature(c: &Convex, pose: &Pose, f: Feature, x: DVec3) -> f64 {
    let p = poly(c);
    let at = |v: u32| pose.transform_point(p.vertex(v));
    match f {
        Feature::Vertex(v) => at(v).distance(x),
        Feature::Edge(e) => {
            let ed = p.edge(e);
            let (t, h) = (at(ed.tail), at(ed.head));
            let s = ((x - t).dot(h - t) / (h - t).length_squared()).clamp(0.0, 1.0);
            (t + (h - t) * s).distance(x)
        }
        Feature::Face(g) => {
            let m = pose.transform_vector(p.face_plane(g).normal);
            let loop_ = p.face_vertices(g);
            let outside = (0..loop_.len())
                .map(|k| {
                    let (u, w) = (at(loop_[k]), at(loop_[(k + 1) % loop_.len()]));
                    (w - u).cross(m).normalize().dot(x - u)
                })
                .fold(0.0, f64::max);
            outside.max((x - at(loop_[0])).dot(m).abs())
        }
    }
}

/// Every point's id names features that hold it: `point_a` on `id.a` of `a`, `point_b` on
/// `id.b` of `b`, within `slack`; and no two points share an id.
fn check_ids(m: &Manifold, a: &Convex, pa: &Pose, b: &Convex, pb: &Pose, slack: f64) {
    for p in m.points() {
        assert!(
            off_feature(a, pa, p.id.a, p.point_a) <= slack,
            "{:?} does not hold {}: {m:?}",
            p.id.a,
            p.point_a
        );
        assert!(
            off_feature(b, pb, p.id.b, p.point_b) <= slack,
            "{:?} does not hold {}: {m:?}",
            p.id.b,
            p.point_b
        );
    }
    let mut ids: Vec<(Feature, Feature)> = m.points().iter().map(|p| (p.id.a, p.id.b)).collect();
    ids.sort_unstable();
    ids.dedup();
    assert_eq!(ids.len(), m.points().len(), "repeated ids: {m:?}");
}

/// The merging distance the manifold uses for `a` and `b` at the tests' tolerance.
fn snap_of(a: &Convex, b: &Convex) -> f64 {
    (POINT_MERGE_FRACTION * TOL)
        .max(poly(a).tolerance())
        .max(poly(b).tolerance())
}

/// A random convex hull of 6–20 points, 0.2–2 across.
pub(crate) fn random_hull(r: &mut rand::rngs::Xoshiro256PlusPlus) -> ConvexPolyhedron {
    let scale = DVec3::new(
        r.random_range(0.1..1.0),
        r.random_range(0.1..1.0),
        r.random_range(0.1..1.0),
    );
    loop {
        let count = r.random_range(6..=20);
        let pts: Vec<DVec3> = (0..count)
            .map(|_| {
                DVec3::new(
                    r.random_range(-1.0..1.0),
                    r.random_range(-1.0..1.0),
                    r.random_range(-1.0..1.0),
                ) * scale
            })
            .collect();
        if let Ok(p) = ConvexPolyhedron::hull(&pts) {
            return p;
        }
    }
}
