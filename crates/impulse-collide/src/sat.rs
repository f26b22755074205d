//! The separating-axis search for two convex polyhedra, pruned on the Gauss map.
//!
//! The brute-force search ([`crate::brute::sat_axis`]) tries every face normal and the cross
//! product of every edge pair: O(E_a·E_b·V) work, 2 300 edge pairs of 32 vertices each for two
//! 16-gon coins. Most edge pairs cannot be the answer. For touching or overlapping pieces the
//! least overlap is the distance from the origin to the boundary of the Minkowski difference
//! B − A, attained at a face of it (the nearest boundary point of a polytope seen from inside
//! lies on a face, whose normal attains the distance). The faces of B − A are the faces of
//! each polyhedron and the edge pairs whose arcs on the Gauss map cross: edge e_a joins faces
//! with normals n₁, n₂ (the arc from n₁ to n₂ on the unit sphere), edge e_b's arc is that of
//! −m₁, −m₂ (B enters the difference negated), and only crossing arcs span a face (Gregorius,
//! "The separating axis test between convex polyhedra", GDC 2013). A crossing test costs four
//! dot products; only the few pairs that pass are projected.
//!
//! Each candidate axis is measured as the brute search measures it
//! (`brute::axis_gap`), so the two differ only in the axes they try: the pruning is
//! what their comparison tests.
//!
//! So for touching or overlapping polyhedra [`polyhedra_axis`] returns the brute search's
//! separation and, but for ties between axes that attain it, its axis; for separated ones the
//! separation is a lower bound of the distance, at most the brute search's (both are; neither is
//! the distance when the nearest features of B − A are an edge or a vertex).

use glam::DVec3;
use impulse_geom::{ConvexPolyhedron, Pose};

use crate::brute::{axis_gap, world_vertices};

/// The separating-axis measure with its axis, as [`crate::brute::sat_axis`]: `(separation,
/// normal)`, `separation` the largest gap between the projections over the candidate axes (≤ 0:
/// touching or overlapping, and minus it is the penetration depth), `normal` (world, unit) the
/// axis attaining it, from `b` toward `a`. Candidates are tried in the brute search's order
/// (face normals of `a`, of `b`, edge pairs), ties going to the first.
#[must_use]
pub fn polyhedra_axis(
    a: &ConvexPolyhedron,
    pose_a: &Pose,
    b: &ConvexPolyhedron,
    pose_b: &Pose,
) -> (f64, DVec3) {
    let (va, vb) = (world_vertices(a, pose_a), world_vertices(b, pose_b));
    let normals = |p: &ConvexPolyhedron, pose: &Pose| -> Vec<DVec3> {
        p.planes()
            .iter()
            .map(|pl| pose.transform_vector(pl.normal))
            .collect()
    };
    let (na, nb) = (normals(a, pose_a), normals(b, pose_b));
    let mut best = (f64::NEG_INFINITY, DVec3::Z);
    let mut consider = |axis: DVec3| {
        let (gap, normal) = axis_gap(&va, &vb, axis);
        if gap > best.0 {
            best = (gap, normal);
        }
    };
    for &n in na.iter().chain(&nb) {
        consider(n);
    }
    // Each edge as its direction and its Gauss-map arc: the end normals and their cross
    // product (b's normals negated).
    let arcs = |p: &ConvexPolyhedron, vs: &[DVec3], ns: &[DVec3], sign: f64| -> Vec<Arc> {
        p.edges()
            .iter()
            .map(|e| {
                let (n1, n2) = (sign * ns[e.left as usize], sign * ns[e.right as usize]);
                Arc {
                    direction: vs[e.head as usize] - vs[e.tail as usize],
                    n1,
                    n2,
                    plane: n2.cross(n1),
                }
            })
            .collect()
    };
    let (arcs_a, arcs_b) = (arcs(a, &va, &na, 1.0), arcs(b, &vb, &nb, -1.0));
    for ea in &arcs_a {
        for eb in &arcs_b {
            if ea.crosses(eb) {
                if let Some(axis) = ea.direction.cross(eb.direction).try_normalize() {
                    consider(axis);
                }
            }
        }
    }
    best
}

/// An edge with its arc on the Gauss map.
struct Arc {
    /// Tail to head (world).
    direction: DVec3,
    /// The normals of the edge's faces: the arc runs from `n1` to `n2`.
    n1: DVec3,
    n2: DVec3,
    /// `n2 × n1`, normal to the arc's great circle.
    plane: DVec3,
}

impl Arc {
    /// Whether two arcs (each shorter than a half circle) cross: each arc's end normals lie
    /// on opposite sides of the other's great circle, and the two arcs lie in one hemisphere
    /// (not at antipodes). Arcs on one great circle (parallel edges) do not cross.
    fn crosses(&self, other: &Arc) -> bool {
        let (cba, dba) = (other.n1.dot(self.plane), other.n2.dot(self.plane));
        let (adc, bdc) = (self.n1.dot(other.plane), self.n2.dot(other.plane));
        cba * dba < 0.0 && adc * bdc < 0.0 && cba * bdc > 0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::brute;
    use crate::manifold::tests::random_hull;
    use crate::motion::testkit::{random_rotation, rng, unit_vector};
    use glam::DQuat;
    use impulse_geom::primitives;
    use rand::RngExt;

    /// Agreement with the brute search (m; coordinates of order 1).
    const AGREE_TOL: f64 = 1e-12;

    /// Random hulls at random poses, from deep overlap to apart: where the brute search finds
    /// them touching or overlapping, the same separation to rounding, along an axis that
    /// attains it; where apart, a separation no larger than the brute one and still positive
    /// when an edge pair is not what separates them. Many of the answers are edge pairs (the
    /// pruning is what is tested).
    #[test]
    fn agrees_with_the_brute_search() {
        let mut r = rng(11);
        let (mut overlapping, mut edge_answers) = (0, 0);
        for case in 0..600 {
            let (a, b) = (random_hull(&mut r), random_hull(&mut r));
            let pa = Pose::new(random_rotation(&mut r), DVec3::ZERO);
            let pb = Pose::new(
                random_rotation(&mut r),
                unit_vector(&mut r) * r.random_range(0.0..1.5),
            );
            let (sep, n) = polyhedra_axis(&a, &pa, &b, &pb);
            let (brute_sep, brute_n) = brute::sat_axis(&a, &pa, &b, &pb);
            assert!(sep <= brute_sep + AGREE_TOL, "case {case}");
            if brute_sep > 0.0 {
                continue;
            }
            overlapping += 1;
            assert!(
                (sep - brute_sep).abs() < AGREE_TOL,
                "case {case}: {sep} vs {brute_sep}"
            );
            // The axis attains the separation: b's lowest point along −n less a's highest.
            let along = |p: &ConvexPolyhedron, pose: &Pose, d: DVec3| {
                p.vertices()
                    .iter()
                    .map(|&v| pose.transform_point(v).dot(d))
                    .fold(f64::NEG_INFINITY, f64::max)
            };
            let gap = -along(&b, &pb, n) - along(&a, &pa, -n);
            assert!((gap - sep).abs() < AGREE_TOL, "case {case}: {gap} vs {sep}");
            let face = a
                .planes()
                .iter()
                .map(|p| pa.transform_vector(p.normal))
                .chain(b.planes().iter().map(|p| pb.transform_vector(p.normal)))
                .any(|m| m.cross(brute_n).length() < 1e-9);
            edge_answers += usize::from(!face);
        }
        assert!(overlapping > 200, "{overlapping}");
        assert!(edge_answers > 20, "{edge_answers}");
    }

    /// Two cubes crossed edge on edge (one turned 45° about x, the other 45° about y, their
    /// edges meeting at right angles): the answer is the edge pair's axis, z, with depth the
    /// overlap of the two edges along it.
    #[test]
    fn crossed_cubes_meet_edge_on_edge() {
        let cube = primitives::cuboid(DVec3::splat(0.5)).unwrap();
        let reach = 0.5 * 2f64.sqrt();
        let sink = 0.01;
        let pa = Pose::new(
            DQuat::from_rotation_x(std::f64::consts::FRAC_PI_4),
            DVec3::ZERO,
        );
        let pb = Pose::new(
            DQuat::from_rotation_y(std::f64::consts::FRAC_PI_4),
            DVec3::new(0.0, 0.0, 2.0 * reach - sink),
        );
        let (sep, n) = polyhedra_axis(&cube, &pa, &cube, &pb);
        assert!((sep + sink).abs() < AGREE_TOL, "{sep}");
        assert!((n + DVec3::Z).length() < 1e-12, "{n}");
    }
}
