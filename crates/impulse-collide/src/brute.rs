//! Brute-force closest features of two convex polyhedra: the reference V-Clip is tested
//! against, and its fallback should its walk ever exceed its step limit.
//!
//! The distance between disjoint convex polyhedra is attained by a vertex and a face whose
//! polygon contains the vertex's projection, or by two edges (vertex–vertex and vertex–edge
//! pairs are edge–edge pairs at segment ends). So the minimum over all vertex–face pairs with
//! an inside projection and all edge–edge pairs is exact. Penetration is decided independently
//! by the separating-axis test (face normals of both, and cross products of edge pairs). Cost:
//! O(V·F + E·E), fine for tests and rare fallbacks.

use glam::DVec3;
use impulse_geom::{ConvexPolyhedron, Pose};

use crate::feature::{Closest, Feature, FeaturePair};

/// Closest points of segments `p1–q1` and `p2–q2`: the parameters `(s, t)` in [0, 1] and the
/// points `p1 + s(q1 − p1)`, `p2 + t(q2 − p2)`. For parallel segments one closest pair of many
/// is returned. Zero-length segments are handled as points.
pub fn segment_segment(p1: DVec3, q1: DVec3, p2: DVec3, q2: DVec3) -> (f64, f64, DVec3, DVec3) {
    let (d1, d2, r) = (q1 - p1, q2 - p2, p1 - p2);
    let (a, e, f) = (d1.dot(d1), d2.dot(d2), d2.dot(r));
    let (s, t) = if a == 0.0 && e == 0.0 {
        (0.0, 0.0)
    } else if a == 0.0 {
        (0.0, (f / e).clamp(0.0, 1.0))
    } else {
        let c = d1.dot(r);
        if e == 0.0 {
            ((-c / a).clamp(0.0, 1.0), 0.0)
        } else {
            let b = d1.dot(d2);
            let denom = a * e - b * b;
            // Closest point on line 1 to line 2, clamped; parallel lines: any s (take 0).
            let s = if denom > 0.0 {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let t = (b * s + f) / e;
            if t < 0.0 {
                ((-c / a).clamp(0.0, 1.0), 0.0)
            } else if t > 1.0 {
                (((b - c) / a).clamp(0.0, 1.0), 1.0)
            } else {
                (s, t)
            }
        }
    };
    (s, t, p1 + d1 * s, p2 + d2 * t)
}

/// Vertices of `poly` placed at `pose`.
pub(crate) fn world_vertices(poly: &ConvexPolyhedron, pose: &Pose) -> Vec<DVec3> {
    poly.vertices()
        .iter()
        .map(|&v| pose.transform_point(v))
        .collect()
}

/// Gap between the projections of two point sets on `axis` (negative when they overlap).
fn gap_along(va: &[DVec3], vb: &[DVec3], axis: DVec3) -> f64 {
    axis_gap(va, vb, axis).0
}

/// How two point sets lie along `axis`: the larger of `b` beyond `a` (lb − ha) and `a` beyond
/// `b` (la − hb), with the unit normal from `b` toward `a` that goes with it (−axis, axis).
pub(crate) fn axis_gap(va: &[DVec3], vb: &[DVec3], axis: DVec3) -> (f64, DVec3) {
    let span = |vs: &[DVec3]| {
        vs.iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                let x = v.dot(axis);
                (lo.min(x), hi.max(x))
            })
    };
    let ((la, ha), (lb, hb)) = (span(va), span(vb));
    if lb - ha >= la - hb {
        (lb - ha, -axis)
    } else {
        (la - hb, axis)
    }
}

/// Every candidate separating axis of two placed polyhedra: face normals of both, and the
/// cross products of non-parallel edge pairs (parallel pairs add nothing: their separating
/// planes are face planes).
fn sat_axes<'a>(
    a: &'a ConvexPolyhedron,
    pose_a: &'a Pose,
    b: &'a ConvexPolyhedron,
    pose_b: &'a Pose,
    va: &'a [DVec3],
    vb: &'a [DVec3],
) -> impl Iterator<Item = DVec3> + 'a {
    let normals_a = a
        .planes()
        .iter()
        .map(move |p| pose_a.transform_vector(p.normal));
    let normals_b = b
        .planes()
        .iter()
        .map(move |p| pose_b.transform_vector(p.normal));
    let edge_axes = a.edges().iter().flat_map(move |ea| {
        let u = va[ea.head as usize] - va[ea.tail as usize];
        b.edges().iter().filter_map(move |eb| {
            u.cross(vb[eb.head as usize] - vb[eb.tail as usize])
                .try_normalize()
        })
    });
    normals_a.chain(normals_b).chain(edge_axes)
}

/// The separating-axis measure: the largest gap between the bodies' projections over every
/// candidate axis. Positive: the bodies are separated (by at least this much). Zero or
/// negative: they touch or overlap, and minus the value is the penetration depth (the smallest
/// translation that separates them, which for polyhedra lies along one of these axes).
pub fn sat_separation(
    a: &ConvexPolyhedron,
    pose_a: &Pose,
    b: &ConvexPolyhedron,
    pose_b: &Pose,
) -> f64 {
    let (va, vb) = (world_vertices(a, pose_a), world_vertices(b, pose_b));
    sat_axes(a, pose_a, b, pose_b, &va, &vb)
        .map(|axis| gap_along(&va, &vb, axis))
        .fold(f64::NEG_INFINITY, f64::max)
}

/// The separating-axis measure with its axis: `(separation, normal)`, where `separation` is as
/// [`sat_separation`] and `normal` (world, unit) is the candidate axis attaining it, oriented
/// from `b` toward `a`: translating `a` by `−separation·normal` (when overlapping) makes the
/// two touch. Ties go to the first axis in the order face normals of `a`, of `b`, edge pairs.
pub fn sat_axis(
    a: &ConvexPolyhedron,
    pose_a: &Pose,
    b: &ConvexPolyhedron,
    pose_b: &Pose,
) -> (f64, DVec3) {
    let (va, vb) = (world_vertices(a, pose_a), world_vertices(b, pose_b));
    let mut best = (f64::NEG_INFINITY, DVec3::Z);
    for axis in sat_axes(a, pose_a, b, pose_b, &va, &vb) {
        let (gap, normal) = axis_gap(&va, &vb, axis);
        if gap > best.0 {
            best = (gap, normal);
        }
    }
    best
}

/// Whether no separating axis exists: the polyhedra overlap or touch. Stops at the first
/// separating axis.
pub fn overlaps(a: &ConvexPolyhedron, pose_a: &Pose, b: &ConvexPolyhedron, pose_b: &Pose) -> bool {
    let (va, vb) = (world_vertices(a, pose_a), world_vertices(b, pose_b));
    !sat_axes(a, pose_a, b, pose_b, &va, &vb).any(|axis| gap_along(&va, &vb, axis) > 0.0)
}

/// Closest features by exhaustive search (see the module documentation). `steps` is 0 and
/// `fallback` false in the result.
pub fn closest(
    a: &ConvexPolyhedron,
    pose_a: &Pose,
    b: &ConvexPolyhedron,
    pose_b: &Pose,
) -> Closest {
    let (va, vb) = (world_vertices(a, pose_a), world_vertices(b, pose_b));
    let penetrating = overlaps(a, pose_a, b, pose_b);
    let mut best = Closest {
        distance: f64::INFINITY,
        point_a: va[0],
        point_b: vb[0],
        features: FeaturePair::default(),
        penetrating,
        steps: 0,
        fallback: false,
    };
    let mut consider = |d: f64, pa: DVec3, pb: DVec3, fa: Feature, fb: Feature| {
        if d < best.distance {
            best.distance = d;
            best.point_a = pa;
            best.point_b = pb;
            best.features = FeaturePair { a: fa, b: fb };
        }
    };
    // Vertex of one against face of the other, when the projection falls inside the face.
    let vertex_face = |v: DVec3, poly: &ConvexPolyhedron, pose: &Pose, vs: &[DVec3], f: u32| {
        let n = pose.transform_vector(poly.face_plane(f).normal);
        let loop_ = poly.face_vertices(f);
        let origin = vs[loop_[0] as usize];
        let inside = (0..loop_.len()).all(|k| {
            let (p, q) = (
                vs[loop_[k] as usize],
                vs[loop_[(k + 1) % loop_.len()] as usize],
            );
            n.cross(q - p).dot(v - p) >= 0.0
        });
        inside.then(|| {
            let h = (v - origin).dot(n);
            (h.abs(), v - n * h)
        })
    };
    for (i, &v) in va.iter().enumerate() {
        for f in 0..b.face_count() as u32 {
            if let Some((d, p)) = vertex_face(v, b, pose_b, &vb, f) {
                consider(d, v, p, Feature::Vertex(i as u32), Feature::Face(f));
            }
        }
    }
    for (i, &v) in vb.iter().enumerate() {
        for f in 0..a.face_count() as u32 {
            if let Some((d, p)) = vertex_face(v, a, pose_a, &va, f) {
                consider(d, p, v, Feature::Face(f), Feature::Vertex(i as u32));
            }
        }
    }
    // Edge pairs; a segment end is the vertex, not the edge.
    let end = |e: u32, tail: u32, head: u32, s: f64| match s {
        s if s <= 0.0 => Feature::Vertex(tail),
        s if s >= 1.0 => Feature::Vertex(head),
        _ => Feature::Edge(e),
    };
    for (i, ea) in a.edges().iter().enumerate() {
        for (j, eb) in b.edges().iter().enumerate() {
            let (s, t, pa, pb) = segment_segment(
                va[ea.tail as usize],
                va[ea.head as usize],
                vb[eb.tail as usize],
                vb[eb.head as usize],
            );
            consider(
                pa.distance(pb),
                pa,
                pb,
                end(i as u32, ea.tail, ea.head, s),
                end(j as u32, eb.tail, eb.head, t),
            );
        }
    }
    if penetrating {
        best.distance = 0.0;
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use impulse_geom::primitives;

    #[test]
    fn segments_closest_points_against_closed_forms() {
        // Skew perpendicular segments, crossing over each other at distance 2.
        let (s, t, a, b) = segment_segment(
            DVec3::new(-1.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, -1.0, 2.0),
            DVec3::new(0.0, 1.0, 2.0),
        );
        assert_eq!((s, t), (0.5, 0.5));
        assert_eq!(a.distance(b), 2.0);
        // Parallel, overlapping in projection: distance is the line distance 1.
        let (_, _, a, b) = segment_segment(
            DVec3::ZERO,
            DVec3::X * 2.0,
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(3.0, 1.0, 0.0),
        );
        assert!((a.distance(b) - 1.0).abs() < 1e-15);
        // Collinear, disjoint: gap between the nearer ends.
        let (s, t, _, _) = segment_segment(DVec3::ZERO, DVec3::X, DVec3::X * 3.0, DVec3::X * 5.0);
        assert_eq!((s, t), (1.0, 0.0));
    }

    #[test]
    fn boxes_apart_and_overlapping() {
        let cube = primitives::cuboid(DVec3::splat(0.5)).unwrap();
        let a = Pose::IDENTITY;
        let b = Pose::from_translation(DVec3::new(1.25, 0.1, -0.2));
        let c = closest(&cube, &a, &cube, &b);
        assert!(!c.penetrating);
        assert!((c.distance - 0.25).abs() < 1e-15);
        let b = Pose::from_translation(DVec3::new(0.75, 0.1, -0.2));
        assert!(closest(&cube, &a, &cube, &b).penetrating);
        // A cube turned 45° about z shows an edge to a cube turned 45° about x, which shows
        // a face: the gap is between that edge and that face.
        let qa = glam::DQuat::from_rotation_z(std::f64::consts::FRAC_PI_4);
        let qb = glam::DQuat::from_rotation_x(std::f64::consts::FRAC_PI_4);
        let h = 0.5 * 2f64.sqrt();
        let c = closest(
            &cube,
            &Pose::new(qa, DVec3::ZERO),
            &cube,
            &Pose::new(qb, DVec3::new(h + 0.5 + 0.3, 0.0, 0.0)),
        );
        // A's vertical edge (x = h) faces B's −x face (x = h + 0.3), parallel to it.
        assert!((c.distance - 0.3).abs() < 1e-14, "{}", c.distance);
    }
}
