//! Penetration depth and contact normal of two convex pieces that touch or overlap.
//!
//! Closest-feature queries ([`crate::shape::convex_closest`]) report a touching or overlapping
//! pair as distance zero with no direction. A simulator needs two more things then: a contact
//! normal (bodies placed touching at the start, or sunk a little into each other, still have a
//! well-defined one) and how deep the overlap is (to refuse a real overlap, and to measure the
//! promise "never deeper than ε_c" from outside the event loop). Both come from the same
//! minimum-translation question: the smallest translation of the first piece that separates
//! it from the second.
//!
//! | pieces | depth | normal |
//! |---|---|---|
//! | polyhedron–polyhedron | exact: separating-axis test over face normals and the edge pairs that form faces of the Minkowski difference ([`crate::sat::polyhedra_axis`]) | the axis attaining it |
//! | sphere–sphere | exact: `r₁ + r₂ − |c₁ − c₂|` | line of centres |
//! | sphere–polyhedron | exact: `r − δ`, δ the centre's signed distance to the polyhedron ([`crate::point::closest_point`]) | centre to its closest point, or the nearest face's normal when inside |
//! | with an ellipsoid | an upper bound: the least overlap of the support functions over the polyhedral face normals and the line of centres (exact when a face normal is the deepest axis, as for an ellipsoid resting on a face) | the axis attaining it |

use glam::DVec3;
use impulse_geom::Pose;

use crate::feature::Feature;
use crate::point;
use crate::sat;
use crate::shape::{Convex, Shape};

/// How two convex pieces overlap.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Penetration {
    /// Length of the smallest translation of the first piece that separates the two (≥ 0;
    /// zero when they just touch; an upper bound for pairs with an ellipsoid, see the module
    /// documentation).
    pub depth: f64,
    /// Unit contact normal (world), from the second piece toward the first: translating the
    /// first piece by `depth·normal` makes the two touch.
    pub normal: DVec3,
}

/// The penetration of convex pieces `a` and `b` at their poses, or `None` when they are
/// separated (some axis shows a positive gap).
#[must_use]
pub fn convex_penetration(
    a: &Convex,
    pose_a: &Pose,
    b: &Convex,
    pose_b: &Pose,
) -> Option<Penetration> {
    let p = separating_axis(a, pose_a, b, pose_b);
    (p.depth >= 0.0).then_some(p)
}

/// The contact normal of two convex pieces that touch, nearly touch or overlap, with the
/// depth along it (negative: a gap). Unlike the direction between two closest points, which
/// is rounding noise when they are a few ulps apart, this axis is well defined at zero
/// distance: for polyhedra it is the candidate separating axis of largest gap (least overlap).
#[must_use]
pub fn separating_axis(a: &Convex, pose_a: &Pose, b: &Convex, pose_b: &Pose) -> Penetration {
    match (a, b) {
        (Convex::Polyhedron(x), Convex::Polyhedron(y)) => {
            let (separation, normal) = sat::polyhedra_axis(x, pose_a, y, pose_b);
            Penetration {
                depth: -separation,
                normal,
            }
        }
        (Convex::Sphere(x), Convex::Sphere(y)) => {
            let d = pose_a.translation - pose_b.translation;
            Penetration {
                depth: x.radius() + y.radius() - d.length(),
                normal: d.try_normalize().unwrap_or(DVec3::Z),
            }
        }
        (Convex::Sphere(s), Convex::Polyhedron(poly)) => {
            sphere_polyhedron(s.radius(), pose_a.translation, poly, pose_b)
        }
        (Convex::Polyhedron(poly), Convex::Sphere(s)) => {
            let p = sphere_polyhedron(s.radius(), pose_b.translation, poly, pose_a);
            Penetration {
                normal: -p.normal,
                ..p
            }
        }
        (Convex::Ellipsoid(_), _) | (_, Convex::Ellipsoid(_)) => {
            support_overlap(a, pose_a, b, pose_b)
        }
    }
}

/// How far convex pieces `a` and `b` overlap along the unit normal `n` (from `b` toward `a`):
/// `h_b(n) + h_a(−n)`, the highest point of `b` along `n` less the lowest point of `a` (negative:
/// a gap along `n`). Translating `a` by that much along `n` separates them along `n`; along the
/// separating axis it is the penetration depth. O(vertices) for polyhedra.
#[must_use]
pub fn overlap_along(a: &Convex, pose_a: &Pose, b: &Convex, pose_b: &Pose, n: DVec3) -> f64 {
    let (sa, sb) = (a.placed(pose_a), b.placed(pose_b));
    sb.support_point(n).dot(n) - sa.support_point(-n).dot(n)
}

/// The deepest penetration over the piece pairs of two shapes, with the two piece indices, or
/// `None` when no piece pair touches or overlaps. Piece pairs whose bounding spheres are apart
/// are skipped.
#[must_use]
pub fn shape_penetration(
    a: &Shape,
    pose_a: &Pose,
    b: &Shape,
    pose_b: &Pose,
) -> Option<(Penetration, (usize, usize))> {
    let mut best: Option<(Penetration, (usize, usize))> = None;
    for (i, pa) in a.pieces().iter().enumerate() {
        let (world_a, ca) = (*pose_a * pa.pose, pose_a.transform_point(pa.center));
        for (j, pb) in b.pieces().iter().enumerate() {
            let cb = pose_b.transform_point(pb.center);
            if ca.distance(cb) > pa.radius + pb.radius {
                continue;
            }
            if let Some(p) =
                convex_penetration(&pa.convex, &world_a, &pb.convex, &(*pose_b * pb.pose))
            {
                if best.is_none_or(|(q, _)| p.depth > q.depth) {
                    best = Some((p, (i, j)));
                }
            }
        }
    }
    best
}

/// A sphere of radius `r` centred at `centre` (world) against a polyhedron: exact depth
/// `r − δ`, δ the centre's signed distance to the polyhedron (negative inside).
fn sphere_polyhedron(
    r: f64,
    centre: DVec3,
    poly: &impulse_geom::ConvexPolyhedron,
    pose: &Pose,
) -> Penetration {
    let pc = point::closest_point(poly, pose, centre, Feature::Vertex(0));
    let outward = (centre - pc.point).try_normalize();
    let normal = match (pc.distance > 0.0, outward, pc.feature) {
        (true, Some(n), _) => n,
        // Inside (or exactly on the surface): the nearest face's outward normal.
        (_, _, Feature::Face(f)) => pose.rotation * poly.planes()[f as usize].normal,
        _ => nearest_face_normal(poly, pose, centre),
    };
    Penetration {
        depth: r - pc.distance,
        normal,
    }
}

/// The outward normal (world) of the face whose plane the point is farthest outside of (or
/// least inside of).
fn nearest_face_normal(poly: &impulse_geom::ConvexPolyhedron, pose: &Pose, x: DVec3) -> DVec3 {
    let local = pose.inverse_transform_point(x);
    let best = poly.planes().iter().max_by(|p, q| {
        p.signed_distance(local)
            .total_cmp(&q.signed_distance(local))
    });
    best.map_or(DVec3::Z, |p| pose.rotation * p.normal)
}

/// An upper bound on the penetration depth of two convex pieces: the smallest overlap of their
/// projections, `h_A(u) + h_B(−u)`, over the candidate axes u (the face normals of polyhedral
/// pieces and the line of centres). Exact when the deepest axis is a face normal.
fn support_overlap(a: &Convex, pose_a: &Pose, b: &Convex, pose_b: &Pose) -> Penetration {
    let (sa, sb) = (a.placed(pose_a), b.placed(pose_b));
    let mut axes: Vec<DVec3> = Vec::new();
    for (c, pose) in [(a, pose_a), (b, pose_b)] {
        if let Convex::Polyhedron(p) = c {
            axes.extend(p.planes().iter().map(|pl| pose.rotation * pl.normal));
        }
    }
    if let Some(u) = (pose_b.translation - pose_a.translation).try_normalize() {
        axes.push(u);
    }
    if axes.is_empty() {
        axes.push(DVec3::Z);
    }
    // Overlap along u: how far a reaches beyond b's near side; moving a by −overlap·u parts them.
    let overlap = |u: DVec3| sa.support_point(u).dot(u) - sb.support_point(-u).dot(u);
    let (depth, u) = axes
        .into_iter()
        .flat_map(|u| [u, -u])
        .map(|u| (overlap(u), u))
        .fold((f64::INFINITY, DVec3::Z), |best, x| {
            if x.0 < best.0 { x } else { best }
        });
    Penetration { depth, normal: -u }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::brute;
    use crate::motion::testkit::{random_rotation, rng, unit_vector};
    use glam::DQuat;
    use impulse_geom::{Ellipsoid, Sphere, primitives};
    use rand::RngExt;

    /// Agreement of exact depths with their closed forms (m; coordinates of order 1).
    const EXACT_TOL: f64 = 1e-12;

    fn cuboid(h: DVec3) -> Convex {
        Convex::Polyhedron(primitives::cuboid(h).unwrap())
    }

    /// A box sunk δ into a floor, face on: depth δ, normal +z; exactly touching: depth 0, still
    /// with the normal; lifted: none.
    #[test]
    fn a_box_sunk_into_a_floor() {
        let floor = cuboid(DVec3::new(1.0, 1.0, 0.1));
        let pf = Pose::from_translation(DVec3::new(0.0, 0.0, -0.1));
        let b = cuboid(DVec3::new(0.1, 0.2, 0.05));
        for sink in [0.0, 1e-9, 1e-3, 0.04] {
            let pb = Pose::new(
                DQuat::from_rotation_z(0.4),
                DVec3::new(0.2, -0.3, 0.05 - sink),
            );
            let p = convex_penetration(&b, &pb, &floor, &pf).unwrap();
            assert!((p.depth - sink).abs() < EXACT_TOL, "{sink}: {p:?}");
            assert!((p.normal - DVec3::Z).length() < 1e-12, "{p:?}");
            let q = convex_penetration(&floor, &pf, &b, &pb).unwrap();
            assert!((q.normal + DVec3::Z).length() < 1e-12, "{q:?}");
        }
        let lifted = Pose::from_translation(DVec3::new(0.0, 0.0, 0.0501));
        assert!(convex_penetration(&b, &lifted, &floor, &pf).is_none());
    }

    /// Random overlapping boxes: the reported translation is the least one among many random
    /// directions (moving by depth·normal, plus a hair, separates them; moving by 0.999 of the
    /// separating distance along any other random direction does not beat it).
    #[test]
    fn polyhedron_depth_is_the_minimum_translation() {
        let mut rng = rng(5);
        let mut checked = 0;
        for _ in 0..300 {
            let (ha, hb) = (
                DVec3::new(
                    rng.random_range(0.1..1.0),
                    rng.random_range(0.1..1.0),
                    rng.random_range(0.1..1.0),
                ),
                DVec3::new(
                    rng.random_range(0.1..1.0),
                    rng.random_range(0.1..1.0),
                    rng.random_range(0.1..1.0),
                ),
            );
            let (a, b) = (
                primitives::cuboid(ha).unwrap(),
                primitives::cuboid(hb).unwrap(),
            );
            let pa = Pose::new(
                random_rotation(&mut rng),
                unit_vector(&mut rng) * rng.random_range(0.0..1.0),
            );
            let pb = Pose::new(random_rotation(&mut rng), DVec3::ZERO);
            let Some(p) = convex_penetration(
                &Convex::Polyhedron(a.clone()),
                &pa,
                &Convex::Polyhedron(b.clone()),
                &pb,
            ) else {
                assert!(!brute::overlaps(&a, &pa, &b, &pb));
                continue;
            };
            checked += 1;
            let moved = |d: DVec3| Pose::new(pa.rotation, pa.translation + d);
            let hair = 1e-9;
            assert!(!brute::overlaps(
                &a,
                &moved(p.normal * (p.depth + hair)),
                &b,
                &pb
            ));
            assert!(
                brute::overlaps(&a, &moved(p.normal * (p.depth - hair).max(0.0)), &b, &pb)
                    || p.depth < hair
            );
            for _ in 0..20 {
                let u = unit_vector(&mut rng);
                assert!(
                    brute::overlaps(&a, &moved(u * (0.999 * p.depth)), &b, &pb),
                    "a shorter way out along {u}"
                );
            }
        }
        assert!(checked > 100, "{checked}");
    }

    /// Sphere against a box: centre outside near an edge (exact distance to the edge), inside
    /// near a face (exact plane distance), and the two sphere orders agree.
    #[test]
    fn sphere_against_a_box() {
        let bx = cuboid(DVec3::splat(0.5));
        let s = Convex::Sphere(Sphere::new(0.2).unwrap());
        let pb = Pose::IDENTITY;
        // Outside, near the edge x = z = 0.5: distance √2·0.1.
        let c = DVec3::new(0.6, 0.0, 0.6);
        let p = convex_penetration(&s, &Pose::from_translation(c), &bx, &pb).unwrap();
        assert!(
            (p.depth - (0.2 - 0.1 * 2f64.sqrt())).abs() < EXACT_TOL,
            "{p:?}"
        );
        assert!((p.normal - DVec3::new(1.0, 0.0, 1.0).normalize()).length() < 1e-12);
        // Inside, 0.1 below the top face.
        let c = DVec3::new(0.1, 0.0, 0.4);
        let p = convex_penetration(&s, &Pose::from_translation(c), &bx, &pb).unwrap();
        assert!((p.depth - 0.3).abs() < EXACT_TOL, "{p:?}");
        assert!((p.normal - DVec3::Z).length() < 1e-12);
        let q = convex_penetration(&bx, &pb, &s, &Pose::from_translation(c)).unwrap();
        assert_eq!(q.depth, p.depth);
        assert_eq!(q.normal, -p.normal);
        // Spheres: line of centres.
        let p = convex_penetration(
            &s,
            &Pose::from_translation(DVec3::X * 0.3),
            &s,
            &Pose::IDENTITY,
        )
        .unwrap();
        assert!((p.depth - 0.1).abs() < EXACT_TOL && (p.normal - DVec3::X).length() < 1e-15);
    }

    /// An ellipsoid sunk into a box face: exactly the sinking (the face normal is a candidate
    /// axis); an ellipsoid and a sphere overlapping along the ellipsoid's long axis: a + r − d.
    #[test]
    fn ellipsoid_depths() {
        let e = Convex::Ellipsoid(Ellipsoid::new(DVec3::new(0.1, 0.03, 0.02)).unwrap());
        let table = cuboid(DVec3::new(0.6, 0.6, 0.02));
        let pt = Pose::from_translation(DVec3::new(0.0, 0.0, -0.02));
        for sink in [0.0, 1e-6, 3e-3] {
            let pe = Pose::new(
                DQuat::from_rotation_z(0.7),
                DVec3::new(0.05, -0.1, 0.02 - sink),
            );
            let p = convex_penetration(&e, &pe, &table, &pt).unwrap();
            assert!((p.depth - sink).abs() < 1e-15, "{p:?} vs {sink}");
            assert!((p.normal - DVec3::Z).length() < 1e-15);
        }
        let s = Convex::Sphere(Sphere::new(0.05).unwrap());
        let ps = Pose::from_translation(DVec3::new(0.14, 0.0, 0.0));
        let p = convex_penetration(&e, &Pose::IDENTITY, &s, &ps).unwrap();
        assert!((p.depth - 0.01).abs() < 1e-15, "{p:?}");
        assert!((p.normal + DVec3::X).length() < 1e-15);
    }

    /// Overlap along a given normal: exact along the separating axis, and an upper bound of
    /// the depth along any other.
    #[test]
    fn overlap_along_a_normal() {
        let floor = cuboid(DVec3::new(1.0, 1.0, 0.1));
        let pf = Pose::from_translation(DVec3::new(0.0, 0.0, -0.1));
        let b = cuboid(DVec3::new(0.1, 0.2, 0.05));
        let pb = Pose::from_translation(DVec3::new(0.0, 0.0, 0.05 - 1e-3));
        assert!((overlap_along(&b, &pb, &floor, &pf, DVec3::Z) - 1e-3).abs() < EXACT_TOL);
        let tilted = DVec3::new(0.1, 0.0, 1.0).normalize();
        assert!(overlap_along(&b, &pb, &floor, &pf, tilted) > 1e-3);
        let lifted = Pose::from_translation(DVec3::new(0.0, 0.0, 0.06));
        assert!((overlap_along(&b, &lifted, &floor, &pf, DVec3::Z) + 0.01).abs() < EXACT_TOL);
    }

    /// Compound shapes: the deepest piece pair wins and is named.
    #[test]
    fn the_deepest_piece_pair_of_two_shapes() {
        let hammer = Shape::compound(vec![
            (Pose::IDENTITY, cuboid(DVec3::new(0.1, 0.01, 0.01))),
            (
                Pose::from_translation(DVec3::X * 0.1),
                cuboid(DVec3::splat(0.03)),
            ),
        ])
        .unwrap();
        let floor = Shape::polyhedron(primitives::cuboid(DVec3::new(1.0, 1.0, 0.1)).unwrap());
        let pf = Pose::from_translation(DVec3::new(0.0, 0.0, -0.1));
        // Head 5 mm into the floor, handle 5 mm above it... the head is 2 cm taller.
        let ph = Pose::from_translation(DVec3::new(0.0, 0.0, 0.025));
        let (p, pieces) = shape_penetration(&hammer, &ph, &floor, &pf).unwrap();
        assert_eq!(pieces, (1, 0));
        assert!((p.depth - 0.005).abs() < EXACT_TOL, "{p:?}");
        let high = Pose::from_translation(DVec3::new(0.0, 0.0, 0.04));
        assert!(shape_penetration(&hammer, &high, &floor, &pf).is_none());
    }
}
