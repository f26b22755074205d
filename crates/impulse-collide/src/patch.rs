//! Where a contact between two convex polyhedra acts: the vertices of each that lie within a
//! tolerance of the other (or inside it).
//!
//! A closest-features query returns one pair of closest points. When two polyhedra meet face
//! to face (a box resting on a floor, one block on another), every point of the overlap of the
//! two faces is as close as any other, and the query's pair is an accident of the walk — often
//! a corner; when they interpenetrate, the query returns only a witness. An impulse applied
//! there makes a body resting flat rock from corner to corner and walk sideways, or misses the
//! corner that is sinking. Within the collision envelope (thesis §2.2: closer than ε_c is
//! contact) the contact is the whole near region, and its vertices are where it can be
//! pressed: [`near_vertices`] finds them, and the simulator takes the centre of those that
//! approach.

use glam::DVec3;
use impulse_geom::{ConvexPolyhedron, Pose};

use crate::feature::Feature;
use crate::point;

/// Every vertex (world) of either polyhedron whose signed distance to the other is at most
/// `tolerance` (inside counts: the distance is negative). `n` is the contact normal (unit,
/// from `b` toward `a`): a vertex of `a` farther along `n` than `b`'s highest point plus the
/// tolerance cannot be near `b` (nor one of `b` below `a`'s lowest), and a vertex outside the
/// other's box grown by `tolerance` neither; only the rest are queried.
#[must_use]
pub fn near_vertices(
    a: &ConvexPolyhedron,
    pose_a: &Pose,
    b: &ConvexPolyhedron,
    pose_b: &Pose,
    n: DVec3,
    tolerance: f64,
) -> Vec<DVec3> {
    let world = |p: &ConvexPolyhedron, pose: &Pose| -> Vec<DVec3> {
        p.vertices()
            .iter()
            .map(|&v| pose.transform_point(v))
            .collect()
    };
    let (va, vb) = (world(a, pose_a), world(b, pose_b));
    let mut out = Vec::new();
    // Vertices `from` of one body near the other (`q` at `pose_q`, vertices `to`); `sign`
    // orients n from the other body toward this one.
    let mut gather =
        |from: &[DVec3], q: &ConvexPolyhedron, pose_q: &Pose, to: &[DVec3], sign: f64| {
            let m = n * sign;
            let top = to
                .iter()
                .map(|w| w.dot(m))
                .fold(f64::NEG_INFINITY, f64::max)
                + tolerance;
            let (lo, hi) = to
                .iter()
                .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &w| {
                    (lo.min(w), hi.max(w))
                });
            let (lo, hi) = (lo - DVec3::splat(tolerance), hi + DVec3::splat(tolerance));
            for &x in from {
                if x.dot(m) > top || x.cmplt(lo).any() || x.cmpgt(hi).any() {
                    continue;
                }
                if point::closest_point(q, pose_q, x, Feature::Vertex(0)).distance <= tolerance {
                    out.push(x);
                }
            }
        };
    gather(&va, b, pose_b, &vb, 1.0);
    gather(&vb, a, pose_a, &va, -1.0);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DQuat;
    use impulse_geom::primitives;

    const TOL: f64 = 1e-4;

    fn floor() -> (ConvexPolyhedron, Pose) {
        (
            primitives::cuboid(DVec3::new(1.0, 1.0, 0.1)).unwrap(),
            Pose::from_translation(DVec3::new(0.0, 0.0, -0.1)),
        )
    }

    fn centroid(points: &[DVec3]) -> DVec3 {
        points.iter().sum::<DVec3>() / points.len() as f64
    }

    /// A box resting flat (just touching, 0.3·tol above, or sunk 0.5·tol): its four bottom
    /// corners, centred straight below its centre, whatever its yaw; the floor's corners are
    /// far away.
    #[test]
    fn a_box_resting_flat_is_held_at_its_face() {
        let (f, pf) = floor();
        let bx = primitives::cuboid(DVec3::new(0.1, 0.05, 0.02)).unwrap();
        for (gap, yaw) in [(0.0, 0.0), (0.3 * TOL, 0.7), (-0.5 * TOL, 2.0)] {
            let c = DVec3::new(0.3, -0.2, 0.02 + gap);
            let pb = Pose::new(DQuat::from_rotation_z(yaw), c);
            let near = near_vertices(&bx, &pb, &f, &pf, DVec3::Z, TOL);
            assert_eq!(near.len(), 4, "gap {gap}");
            let x = centroid(&near);
            let want = DVec3::new(c.x, c.y, gap);
            assert!(
                (x - want).length() < 1e-12,
                "gap {gap} yaw {yaw}: {x} vs {want}"
            );
        }
        let far = Pose::from_translation(DVec3::new(0.0, 0.0, 0.02 + 2.0 * TOL));
        assert!(near_vertices(&bx, &far, &f, &pf, DVec3::Z, TOL).is_empty());
    }

    /// Two equal blocks stacked 1 mm out of line: two corners of each lie over the other (the
    /// overlap spans x ∈ [−0.049, 0.05]), the other two overhang by 1 mm, beyond the tolerance;
    /// their centre is the centre of the shared face.
    #[test]
    fn stacked_blocks_are_held_at_the_shared_face() {
        let bx = primitives::cuboid(DVec3::new(0.05, 0.04, 0.025)).unwrap();
        let lower = Pose::from_translation(DVec3::new(0.0, 0.0, 0.025));
        let upper = Pose::from_translation(DVec3::new(0.001, 0.0, 0.075));
        let near = near_vertices(&bx, &upper, &bx, &lower, DVec3::Z, TOL);
        assert_eq!(near.len(), 4);
        assert!((centroid(&near) - DVec3::new(0.0005, 0.0, 0.05)).length() < 1e-12);
    }

    /// A box tilted onto one corner: that corner alone, also when sunk into the floor (where
    /// a closest-features query gives only a witness); tilted onto an edge: its two ends.
    #[test]
    fn a_corner_or_an_edge_landing() {
        let (f, pf) = floor();
        let bx = primitives::cuboid(DVec3::splat(0.05)).unwrap();
        let q = DQuat::from_rotation_x(0.3) * DQuat::from_rotation_y(0.2);
        let lowest = bx
            .vertices()
            .iter()
            .map(|&v| q * v)
            .min_by(|a, b| a.z.total_cmp(&b.z))
            .unwrap();
        for sink in [0.0, 0.7 * TOL] {
            let pb = Pose::new(q, DVec3::new(0.0, 0.0, -lowest.z - sink));
            let near = near_vertices(&bx, &pb, &f, &pf, DVec3::Z, TOL);
            assert_eq!(near.len(), 1);
            assert!((near[0] - (lowest + pb.translation)).length() < 1e-15);
        }
        let q = DQuat::from_rotation_x(0.3);
        let pb = Pose::new(
            q,
            DVec3::new(0.2, 0.0, 0.05 * (0.3f64.cos() + 0.3f64.sin())),
        );
        let near = near_vertices(&bx, &pb, &f, &pf, DVec3::Z, TOL);
        assert_eq!(near.len(), 2);
        let x = centroid(&near);
        let y = pb.translation.y + (q * DVec3::new(0.0, -0.05, -0.05)).y;
        assert!((x - DVec3::new(0.2, y, 0.0)).length() < 1e-12, "{x}");
    }
}
