//! Closest point of a convex polyhedron to a point, and the exact sphere cases.
//!
//! The point walk is V-Clip with one side shrunk to a point (whose Voronoi region is all of
//! space): the polyhedron's feature moves across whichever region plane the point violates,
//! which strictly decreases the distance, until the point lies in the feature's region. A point
//! below a face with no way down is either above some other face (move there) or inside the
//! polyhedron. Spheres reduce to points: a sphere's distance is its centre's minus its radius.

use glam::DVec3;
use impulse_geom::{ConvexPolyhedron, Pose};

use crate::feature::{Closest, Feature, FeaturePair};

/// The closest point of a polyhedron to a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointClosest {
    /// The feature of the polyhedron nearest the point (for a point inside: the face whose
    /// plane is nearest).
    pub feature: Feature,
    /// Nearest point of the polyhedron's surface, world frame.
    pub point: DVec3,
    /// Signed distance: positive outside, negative inside (minus the distance to the nearest
    /// face plane, the penetration depth of the point).
    pub distance: f64,
    /// Feature steps taken.
    pub steps: u32,
}

/// Steps allowed per feature of the polyhedron before the walk gives up and scans every face
/// (a floating-point cycle; each step strictly decreases the distance, so it is not expected).
pub const POINT_STEP_LIMIT_PER_FEATURE: u32 = 2;

/// Closest point of `poly` at `pose` to the world point `x`, warm-started from `warm`.
pub fn closest_point(
    poly: &ConvexPolyhedron,
    pose: &Pose,
    x: DVec3,
    warm: Feature,
) -> PointClosest {
    let p = pose.inverse_transform_point(x);
    let mut f = if warm.is_valid_for(poly) {
        warm
    } else {
        Feature::Vertex(0)
    };
    let features = (poly.vertices().len() + poly.edges().len() + poly.face_count()) as u32;
    let done = |feature, point: DVec3, distance, steps| PointClosest {
        feature,
        point: pose.transform_point(point),
        distance,
        steps,
    };
    for steps in 0..POINT_STEP_LIMIT_PER_FEATURE * features + 8 {
        match f {
            Feature::Vertex(v) => {
                let xv = poly.vertex(v);
                // Outside the vertex's region across the plane to edge g: (p − v)·(w − v) > 0.
                let next =
                    poly.vertex_edges(v).iter().copied().find(|&g| {
                        (p - xv).dot(poly.vertex(poly.edge(g).other_vertex(v)) - xv) > 0.0
                    });
                match next {
                    Some(g) => f = Feature::Edge(g),
                    None => return done(f, xv, p.distance(xv), steps),
                }
            }
            Feature::Edge(e) => {
                let ed = poly.edge(e);
                let (t, h) = (poly.vertex(ed.tail), poly.vertex(ed.head));
                let u = h - t;
                if (p - t).dot(u) < 0.0 {
                    f = Feature::Vertex(ed.tail);
                } else if (p - h).dot(u) > 0.0 {
                    f = Feature::Vertex(ed.head);
                } else if let Some(face) = [ed.left, ed.right].into_iter().find(|&face| {
                    let n = poly.face_plane(face).normal;
                    let away = if face == ed.left {
                        u.cross(n)
                    } else {
                        n.cross(u)
                    };
                    away.dot(p - t) < 0.0
                }) {
                    f = Feature::Face(face);
                } else {
                    let q = t + u * ((p - t).dot(u) / u.length_squared());
                    return done(f, q, p.distance(q), steps);
                }
            }
            Feature::Face(face) => {
                let n = poly.face_plane(face).normal;
                // The most violated side plane, by distance.
                let mut worst: Option<(f64, u32)> = None;
                let loop_ = poly.face_vertices(face);
                for (k, &g) in poly.face_edges(face).iter().enumerate() {
                    let (a, b) = (
                        poly.vertex(loop_[k]),
                        poly.vertex(loop_[(k + 1) % loop_.len()]),
                    );
                    let inward = n.cross(b - a);
                    let d = inward.dot(p - a) / inward.length();
                    if d < 0.0 && worst.is_none_or(|(w, _)| d < w) {
                        worst = Some((d, g));
                    }
                }
                if let Some((_, g)) = worst {
                    f = Feature::Edge(g);
                    continue;
                }
                let h = poly.face_plane(face).signed_distance(p);
                if h >= 0.0 {
                    return done(f, p - n * h, h, steps);
                }
                // Below the face: above another one, or inside.
                let (best, g) = deepest_face(poly, p);
                if best > 0.0 {
                    f = Feature::Face(g);
                } else {
                    let n = poly.face_plane(g).normal;
                    return done(Feature::Face(g), p - n * best, best, steps);
                }
            }
        }
    }
    // Not expected: answer by scanning every feature.
    brute_closest_point(poly, pose, x)
}

/// The face whose plane the point is farthest above (largest signed distance), and that
/// distance.
fn deepest_face(poly: &ConvexPolyhedron, p: DVec3) -> (f64, u32) {
    (0..poly.face_count() as u32)
        .map(|g| (poly.face_plane(g).signed_distance(p), g))
        .fold(
            (f64::NEG_INFINITY, 0),
            |best, c| if c.0 > best.0 { c } else { best },
        )
}

/// Closest point by scanning every face, edge and vertex: the reference for tests and the
/// fallback of [`closest_point`].
pub fn brute_closest_point(poly: &ConvexPolyhedron, pose: &Pose, x: DVec3) -> PointClosest {
    let p = pose.inverse_transform_point(x);
    let (depth, g) = deepest_face(poly, p);
    let at = |feature, q: DVec3, distance| PointClosest {
        feature,
        point: pose.transform_point(q),
        distance,
        steps: 0,
    };
    if depth <= 0.0 {
        let n = poly.face_plane(g).normal;
        return at(Feature::Face(g), p - n * depth, depth);
    }
    let mut best = at(Feature::Vertex(0), poly.vertex(0), f64::INFINITY);
    for (v, &xv) in poly.vertices().iter().enumerate() {
        if p.distance(xv) < best.distance {
            best = at(Feature::Vertex(v as u32), xv, p.distance(xv));
        }
    }
    for (e, ed) in poly.edges().iter().enumerate() {
        let (t, h) = (poly.vertex(ed.tail), poly.vertex(ed.head));
        let s = (p - t).dot(h - t) / (h - t).length_squared();
        if s > 0.0 && s < 1.0 {
            let q = t + (h - t) * s;
            if p.distance(q) < best.distance {
                best = at(Feature::Edge(e as u32), q, p.distance(q));
            }
        }
    }
    for face in 0..poly.face_count() as u32 {
        let plane = poly.face_plane(face);
        let h = plane.signed_distance(p);
        let q = p - plane.normal * h;
        let loop_ = poly.face_vertices(face);
        let inside = (0..loop_.len()).all(|k| {
            let (a, b) = (
                poly.vertex(loop_[k]),
                poly.vertex(loop_[(k + 1) % loop_.len()]),
            );
            plane.normal.cross(b - a).dot(q - a) >= 0.0
        });
        if inside && h >= 0.0 && h < best.distance {
            best = at(Feature::Face(face), q, h);
        }
    }
    best
}

/// Two spheres of radii `ra`, `rb` centred at `ca`, `cb` (world frame). Each sphere's only
/// feature is reported as `Feature::Vertex(0)`.
pub fn sphere_sphere(ra: f64, ca: DVec3, rb: f64, cb: DVec3) -> Closest {
    let d = cb - ca;
    let len = d.length();
    let n = if len > 0.0 { d / len } else { DVec3::X };
    let gap = len - ra - rb;
    let penetrating = gap <= 0.0;
    Closest {
        distance: gap.max(0.0),
        point_a: ca + n * ra,
        point_b: cb - n * rb,
        features: FeaturePair::default(),
        penetrating,
        steps: 0,
        fallback: false,
    }
}

/// A sphere of `radius` centred at world point `center` (first body) and a polyhedron (second
/// body). The sphere's feature is `Feature::Vertex(0)`; `warm` is the polyhedron's cached
/// feature.
pub fn sphere_polyhedron(
    radius: f64,
    center: DVec3,
    poly: &ConvexPolyhedron,
    pose: &Pose,
    warm: Feature,
) -> Closest {
    let c = closest_point(poly, pose, center, warm);
    // Outward direction from the polyhedron towards the centre (inside: the nearest face's
    // normal, so the witness point on the sphere lies towards that face).
    let n = if c.distance > 0.0 {
        (center - c.point) / c.distance
    } else {
        match c.feature {
            Feature::Face(f) => pose.transform_vector(poly.face_plane(f).normal),
            _ => DVec3::X,
        }
    };
    let gap = c.distance - radius;
    Closest {
        distance: gap.max(0.0),
        point_a: center - n * radius,
        point_b: c.point,
        features: FeaturePair {
            a: Feature::Vertex(0),
            b: c.feature,
        },
        penetrating: gap <= 0.0,
        steps: c.steps,
        fallback: false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DQuat;
    use impulse_geom::primitives;
    use rand::rngs::Xoshiro256PlusPlus;
    use rand::{RngExt, SeedableRng};

    const DISTANCE_REL: f64 = 1e-9;

    #[test]
    fn point_walk_matches_brute_force_inside_and_out() {
        let mut r = Xoshiro256PlusPlus::seed_from_u64(9);
        let mut polys = vec![
            primitives::cuboid(DVec3::new(0.5, 1.0, 0.2)).unwrap(),
            primitives::geodesic_sphere(3, 1.0).unwrap(),
            primitives::regular_prism(5, 1.0, 0.3).unwrap(),
        ];
        for _ in 0..5 {
            let pts: Vec<DVec3> = (0..30)
                .map(|_| DVec3::new(r.random(), r.random(), r.random()) - 0.5)
                .collect();
            polys.push(ConvexPolyhedron::hull(&pts).unwrap());
        }
        let mut warm = Feature::Vertex(0);
        let mut inside = 0;
        for i in 0..20_000 {
            let poly = &polys[i % polys.len()];
            let pose = Pose::new(
                DQuat::from_rotation_y(i as f64 * 0.37) * DQuat::from_rotation_x(i as f64 * 0.11),
                DVec3::new(3.0, -1.0, 2.0),
            );
            let x = pose.translation + (DVec3::new(r.random(), r.random(), r.random()) - 0.5) * 4.0;
            let c = closest_point(poly, &pose, x, warm);
            let b = brute_closest_point(poly, &pose, x);
            let scale = poly.mesh().diameter();
            assert!(
                (c.distance - b.distance).abs() <= DISTANCE_REL * scale,
                "{} vs {}",
                c.distance,
                b.distance
            );
            if b.distance > 0.0 {
                assert!(c.point.distance(x) - c.distance <= DISTANCE_REL * scale);
            } else {
                inside += 1;
            }
            warm = if i % 3 == 0 {
                Feature::Vertex(0)
            } else {
                c.feature
            };
            if !warm.is_valid_for(&polys[(i + 1) % polys.len()]) {
                warm = Feature::Vertex(0);
            }
        }
        assert!(inside > 200, "{inside} points inside");
    }

    #[test]
    fn spheres_against_closed_forms() {
        let c = sphere_sphere(1.0, DVec3::ZERO, 0.5, DVec3::new(3.0, 4.0, 0.0));
        assert!((c.distance - 3.5).abs() < 1e-15 && !c.penetrating);
        assert!(c.point_a.distance(DVec3::new(0.6, 0.8, 0.0)) < 1e-15);
        assert!(sphere_sphere(1.0, DVec3::ZERO, 1.0, DVec3::X).penetrating);
        // A sphere over the middle of a box's top face: gap = height − half height − radius.
        let cube = primitives::cuboid(DVec3::splat(0.5)).unwrap();
        let c = sphere_polyhedron(
            0.25,
            DVec3::new(0.1, 0.2, 1.0),
            &cube,
            &Pose::IDENTITY,
            Feature::Vertex(0),
        );
        assert!((c.distance - 0.25).abs() < 1e-15 && matches!(c.features.b, Feature::Face(_)));
        // Off a corner: the gap is measured to the vertex.
        let centre = DVec3::splat(0.5) + DVec3::ONE.normalize() * 2.0;
        let c = sphere_polyhedron(0.5, centre, &cube, &Pose::IDENTITY, Feature::Face(0));
        assert!((c.distance - 1.5).abs() < 1e-14 && matches!(c.features.b, Feature::Vertex(_)));
        // Centre inside: penetrating.
        assert!(
            sphere_polyhedron(
                0.1,
                DVec3::splat(0.2),
                &cube,
                &Pose::IDENTITY,
                Feature::Vertex(0)
            )
            .penetrating
        );
    }
}
