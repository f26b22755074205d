//! The manifold of two convex polyhedra: contact features, and clipping against a face's side
//! planes (module documentation of [`crate::manifold`], steps 1–2; merging and reduction, step
//! 3, are in `reduce`).
//!
//! Clipping is done in `a`'s frame (`b` placed by `pose_a⁻¹·pose_b`) and the points moved to
//! the world at the end, so that bodies far from the origin lose no precision to each other.

use glam::DVec3;
use impulse_geom::{ConvexPolyhedron, Pose};

use super::reduce::{merge, reduce};
use super::{ContactPoint, FACE_MIN_COS, Manifold, POINT_MERGE_FRACTION};
use crate::brute;
use crate::feature::{Feature, FeaturePair};

/// A polyhedron's contact feature along a direction, and its supporting vertex.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Support {
    /// The face, edge or vertex within the tolerance of the support plane.
    pub feature: Feature,
    /// A vertex farthest along the direction.
    pub vertex: u32,
}

/// The merging distance used in clipping against a reference face is at most this fraction
/// of the face's width across (the least distance from its vertices' centroid to an edge's
/// line, seen along the normal): a sliver's face 2.5 cm wide under a tolerance of 1.8 m would
/// otherwise have its corners snapped together. Default `0.1`.
pub const SNAP_WIDTH_FRACTION: f64 = 0.1;

/// Where a hill climb for the supporting vertex starts: a vertex of the warm feature.
fn start_vertex(poly: &ConvexPolyhedron, warm: Feature) -> u32 {
    if !warm.is_valid_for(poly) {
        return 0;
    }
    match warm {
        Feature::Vertex(v) => v,
        Feature::Edge(e) => poly.edge(e).tail,
        Feature::Face(f) => poly.face_vertices(f)[0],
    }
}

/// The contact feature of `poly` along the unit direction `dir` (its own frame): of the
/// vertices within `tolerance` of the support plane (a connected set, found from the
/// supporting vertex by walking edges), the best-aligned face all of whose vertices are among
/// them, that holds the supporting vertex, and whose normal is within [`FACE_MIN_COS`] of
/// `dir`; else the edge among them from the supporting vertex whose lower end is highest;
/// else the supporting vertex. The feature always holds the supporting vertex, so the
/// manifold holds the deepest point (a sliver whose tolerance exceeds its width had a face of
/// three vertices chosen while its fourth lay 0.47 of the tolerance deeper: test
/// `a_slivers_manifold_holds_its_deepest_vertex`). Ties go to the lower index, so the answer
/// does not depend on `warm`.
pub(crate) fn support_feature(
    poly: &ConvexPolyhedron,
    dir: DVec3,
    warm: Feature,
    tolerance: f64,
) -> Support {
    let s = poly.support_from(dir, start_vertex(poly, warm));
    let top = poly.vertex(s).dot(dir);
    let height = |v: u32| poly.vertex(v).dot(dir);
    let near = |v: u32| top - height(v) <= tolerance;
    let mut set = vec![s];
    let mut k = 0;
    while k < set.len() {
        let v = set[k];
        k += 1;
        for &e in poly.vertex_edges(v) {
            let w = poly.edge(e).other_vertex(v);
            if !set.contains(&w) && near(w) {
                set.push(w);
            }
        }
    }
    let mut face: Option<(f64, u32)> = None;
    let mut edge: Option<(f64, u32)> = None;
    for &v in &set {
        for &e in poly.vertex_edges(v) {
            let ed = poly.edge(e);
            // Each face around v once: the one left of the edge oriented away from v. Each
            // edge once: from its tail (both ends must be in the set).
            let f = if ed.tail == v { ed.left } else { ed.right };
            let c = poly.face_plane(f).normal.dot(dir);
            let better = face.is_none_or(|(bc, bf)| c > bc || (c == bc && f < bf));
            let verts = poly.face_vertices(f);
            if c >= FACE_MIN_COS && better && verts.contains(&s) && verts.iter().all(|&w| near(w)) {
                face = Some((c, f));
            }
            if ed.tail != v || face.is_some() {
                continue;
            }
            let low = height(ed.tail).min(height(ed.head));
            let better = edge.is_none_or(|(bl, be)| low > bl || (low == bl && e < be));
            if better && near(ed.head) && (ed.tail == s || ed.head == s) {
                edge = Some((low, e));
            }
        }
    }
    let feature = match (face, edge) {
        (Some((_, f)), _) => Feature::Face(f),
        (None, Some((_, e))) => Feature::Edge(e),
        (None, None) => Feature::Vertex(s),
    };
    Support { feature, vertex: s }
}

/// Which body a reference face belongs to.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Side {
    A,
    B,
}

/// What the boundary from a clipped polygon's corner to the next lies on.
#[derive(Clone, Copy)]
enum On {
    /// An edge of the incident face.
    Incident(u32),
    /// The side plane of an edge of the reference face.
    Reference(u32),
}

/// A corner of the incident polygon while it is clipped: its position (on the incident
/// feature, `a`'s frame), the reference and incident features it comes from, and what its
/// outgoing boundary lies on.
#[derive(Clone, Copy)]
struct Corner {
    p: DVec3,
    reference: Feature,
    incident: Feature,
    next: On,
}

/// A side plane of the reference face: through `origin`, outward unit normal `normal`
/// (perpendicular to the contact normal), for reference edge `edge`.
struct SidePlane {
    origin: DVec3,
    normal: DVec3,
    edge: u32,
}

/// The pair being clipped, in `a`'s frame.
struct Pair<'a> {
    a: &'a ConvexPolyhedron,
    b: &'a ConvexPolyhedron,
    /// `b`'s frame in `a`'s frame.
    rel: Pose,
    /// The contact normal in `a`'s frame (from `a` toward `b`).
    n: DVec3,
    /// Points within this distance are one; a point this far outside a side plane is on it.
    snap: f64,
    tolerance: f64,
}

/// The manifold of polyhedra `a` and `b` along the unit world normal `n` (from `a` toward
/// `b`), or `None` when they are more than `tolerance` apart along it.
pub(crate) fn polyhedra(
    a: &ConvexPolyhedron,
    pose_a: &Pose,
    b: &ConvexPolyhedron,
    pose_b: &Pose,
    n: DVec3,
    warm: FeaturePair,
    tolerance: f64,
) -> Option<Manifold> {
    let (mut points, features, snap) = contact_points(a, pose_a, b, pose_b, n, warm, tolerance)?;
    reduce(&mut points, n, snap);
    Manifold::new(n, features, &points)
}

/// Every contact point of polyhedra `a` and `b` along `n` before reduction (world), the
/// contact features, and the merging distance; `None` when they are more than `tolerance`
/// apart along `n`.
pub(crate) fn contact_points(
    a: &ConvexPolyhedron,
    pose_a: &Pose,
    b: &ConvexPolyhedron,
    pose_b: &Pose,
    n: DVec3,
    warm: FeaturePair,
    tolerance: f64,
) -> Option<(Vec<ContactPoint>, FeaturePair, f64)> {
    let rel = pose_a.inverse() * *pose_b;
    let na = pose_a.inverse_transform_vector(n);
    let sa = support_feature(a, na, warm.a, tolerance);
    let sb = support_feature(b, -pose_b.inverse_transform_vector(n), warm.b, tolerance);
    let (va, vb) = (
        a.vertex(sa.vertex),
        rel.transform_point(b.vertex(sb.vertex)),
    );
    let gap = (vb - va).dot(na);
    if gap.is_nan() || gap > tolerance {
        return None;
    }
    let pair = Pair {
        a,
        b,
        rel,
        n: na,
        snap: (POINT_MERGE_FRACTION * tolerance)
            .max(a.tolerance())
            .max(b.tolerance()),
        tolerance,
    };
    let mut points = match (sa.feature, sb.feature) {
        (Feature::Face(f), other) => pair.against_face(Side::A, f, other),
        (other, Feature::Face(f)) => pair.against_face(Side::B, f, other),
        (fa, fb) => pair.edges(fa, fb),
    };
    points.retain(|p| p.gap <= tolerance);
    merge(&mut points, pair.snap);
    if points.is_empty() {
        // Nothing survived (a normal inconsistent with the features): the supporting
        // vertices, which are on both surfaces and have the pair's gap along the normal.
        points.push(ContactPoint {
            point_a: va,
            point_b: vb,
            gap,
            id: FeaturePair {
                a: Feature::Vertex(sa.vertex),
                b: Feature::Vertex(sb.vertex),
            },
        });
    }
    for p in &mut points {
        p.point_a = pose_a.transform_point(p.point_a);
        p.point_b = pose_a.transform_point(p.point_b);
    }
    let features = FeaturePair {
        a: sa.feature,
        b: sb.feature,
    };
    Some((points, features, pair.snap))
}

impl Pair<'_> {
    /// A body's polyhedron and its placement in `a`'s frame.
    fn body(&self, side: Side) -> (&ConvexPolyhedron, Pose) {
        match side {
            Side::A => (self.a, Pose::IDENTITY),
            Side::B => (self.b, self.rel),
        }
    }

    /// The other body's feature `other` clipped against face `f` of `side`'s body (the
    /// reference), each clipped point paired with its projection along the normal onto the
    /// reference plane.
    fn against_face(&self, side: Side, f: u32, other: Feature) -> Vec<ContactPoint> {
        let (ref_poly, ref_pose) = self.body(side);
        let (inc_side, n_ref) = match side {
            Side::A => (Side::B, self.n),
            Side::B => (Side::A, -self.n),
        };
        let (inc_poly, inc_pose) = self.body(inc_side);
        let loop_ = ref_poly.face_vertices(f);
        let at = |k: usize| ref_pose.transform_point(ref_poly.vertex(loop_[k]));
        let planes: Vec<SidePlane> = ref_poly
            .face_edges(f)
            .iter()
            .enumerate()
            .filter_map(|(k, &e)| {
                let origin = at(k);
                let normal = (at((k + 1) % loop_.len()) - origin)
                    .cross(n_ref)
                    .try_normalize()?;
                Some(SidePlane {
                    origin,
                    normal,
                    edge: e,
                })
            })
            .collect();
        // A face thinner across than the merging distance (a sliver's, where the tolerance is
        // a fraction of its length) would have its corners snapped onto the planes of its
        // opposite edges: the snap is kept below a fraction of its width across.
        let centroid = (0..loop_.len()).map(at).sum::<DVec3>() / loop_.len() as f64;
        let width = planes
            .iter()
            .map(|s| -s.normal.dot(centroid - s.origin))
            .fold(f64::INFINITY, f64::min);
        let snap = self.snap.min(SNAP_WIDTH_FRACTION * width.max(0.0));
        let inc_vertex = |v: u32| inc_pose.transform_point(inc_poly.vertex(v));
        let reference = Feature::Face(f);
        let clipped: Vec<(DVec3, Feature, Feature)> = match other {
            Feature::Vertex(v) => {
                let p = inc_vertex(v);
                let inside = planes.iter().all(|s| s.normal.dot(p - s.origin) <= snap);
                if inside {
                    vec![(p, reference, other)]
                } else {
                    Vec::new()
                }
            }
            Feature::Edge(e) => {
                let ed = inc_poly.edge(e);
                let ends = [
                    (inc_vertex(ed.tail), reference, Feature::Vertex(ed.tail)),
                    (inc_vertex(ed.head), reference, Feature::Vertex(ed.head)),
                ];
                clip_segment(ends, e, &planes, snap)
            }
            Feature::Face(g) => {
                let corners: Vec<Corner> = inc_poly
                    .face_vertices(g)
                    .iter()
                    .zip(inc_poly.face_edges(g))
                    .map(|(&v, &e)| Corner {
                        p: inc_vertex(v),
                        reference,
                        incident: Feature::Vertex(v),
                        next: On::Incident(e),
                    })
                    .collect();
                clip_polygon(corners, ref_poly, g, &planes, snap)
            }
        };
        // Onto the reference plane along n_ref: p + s·n_ref with (p + s·n_ref − o)·m = 0; the
        // face faces n_ref within FACE_MIN_COS, so the division is well conditioned.
        let m = ref_pose.transform_vector(ref_poly.face_plane(f).normal);
        let o = at(0);
        let along = n_ref.dot(m);
        clipped
            .into_iter()
            .map(|(p, rf, inc)| {
                let s = -(p - o).dot(m) / along;
                let on_ref = p + n_ref * s;
                match side {
                    Side::A => ContactPoint {
                        point_a: on_ref,
                        point_b: p,
                        gap: -s,
                        id: FeaturePair { a: rf, b: inc },
                    },
                    Side::B => ContactPoint {
                        point_a: p,
                        point_b: on_ref,
                        gap: -s,
                        id: FeaturePair { a: inc, b: rf },
                    },
                }
            })
            .collect()
    }

    /// Contact features without a face: edges and vertices. Two edges parallel within the
    /// tolerance over their length give the ends of their common stretch; any other pair its
    /// closest points.
    fn edges(&self, fa: Feature, fb: Feature) -> Vec<ContactPoint> {
        let seg = |side: Side, f: Feature| -> (DVec3, DVec3, Feature, Feature) {
            let (poly, pose) = self.body(side);
            let at = |v: u32| pose.transform_point(poly.vertex(v));
            match f {
                Feature::Edge(e) => {
                    let ed = poly.edge(e);
                    (
                        at(ed.tail),
                        at(ed.head),
                        Feature::Vertex(ed.tail),
                        Feature::Vertex(ed.head),
                    )
                }
                Feature::Vertex(v) => (at(v), at(v), f, f),
                // Not reached: faces go to `against_face`.
                Feature::Face(g) => {
                    let v = poly.face_vertices(g)[0];
                    (at(v), at(v), Feature::Vertex(v), Feature::Vertex(v))
                }
            }
        };
        let (a0, a1, a0f, a1f) = seg(Side::A, fa);
        let (b0, b1, b0f, b1f) = seg(Side::B, fb);
        let point = |pa: DVec3, pb: DVec3, a: Feature, b: Feature| ContactPoint {
            point_a: pa,
            point_b: pb,
            gap: (pb - pa).dot(self.n),
            id: FeaturePair { a, b },
        };
        if let (Feature::Edge(_), Feature::Edge(_)) = (fa, fb) {
            let (u, w) = (a1 - a0, b1 - b0);
            let (la, lb) = (u.length(), w.length());
            let (uh, wh) = (u / la, w / lb);
            if uh.cross(wh).length() * la.min(lb) <= self.tolerance {
                // Parallel: the common stretch along a's edge, [lo, hi] in its length.
                let (t0, t1) = ((b0 - a0).dot(uh), (b1 - a0).dot(uh));
                let (lo_b, hi_b) = if t0 <= t1 {
                    ((t0, b0f), (t1, b1f))
                } else {
                    ((t1, b1f), (t0, b0f))
                };
                let on_b = |p: DVec3| b0 + w * ((p - b0).dot(w) / (lb * lb)).clamp(0.0, 1.0);
                let end = |from_a: bool, t: f64, vertex_a: Feature, vertex_b: Feature| {
                    let pa = a0 + uh * t;
                    if from_a {
                        point(pa, on_b(pa), vertex_a, fb)
                    } else {
                        point(pa, on_b(pa), fa, vertex_b)
                    }
                };
                let from_a_lo = lo_b.0 <= self.snap;
                let from_a_hi = hi_b.0 >= la - self.snap;
                let lo = if from_a_lo { 0.0 } else { lo_b.0 };
                let hi = if from_a_hi { la } else { hi_b.0 };
                if hi - lo > self.snap {
                    return vec![
                        end(from_a_lo, lo, a0f, lo_b.1),
                        end(from_a_hi, hi, a1f, hi_b.1),
                    ];
                }
            }
        }
        let (s, t, pa, pb) = brute::segment_segment(a0, a1, b0, b1);
        let name = |f: Feature, x: f64, f0: Feature, f1: Feature| match f {
            Feature::Edge(_) if x <= 0.0 => f0,
            Feature::Edge(_) if x >= 1.0 => f1,
            _ => f,
        };
        vec![point(pa, pb, name(fa, s, a0f, a1f), name(fb, t, b0f, b1f))]
    }
}

/// Clips a segment (two ends: point, reference feature, incident feature) of incident edge
/// `e` against the side planes; a clipped end is named by the reference edge whose plane cut
/// it and `e`. An end less than `snap` outside a plane is not cut.
fn clip_segment(
    mut ends: [(DVec3, Feature, Feature); 2],
    e: u32,
    planes: &[SidePlane],
    snap: f64,
) -> Vec<(DVec3, Feature, Feature)> {
    for s in planes {
        let (d0, d1) = (
            s.normal.dot(ends[0].0 - s.origin),
            s.normal.dot(ends[1].0 - s.origin),
        );
        let (in0, in1) = (d0 <= snap, d1 <= snap);
        match (in0, in1) {
            (false, false) => return Vec::new(),
            (true, true) => continue,
            _ => {
                // d0 ≠ d1 here (one is ≤ snap, the other > snap).
                let t = (d0 / (d0 - d1)).clamp(0.0, 1.0);
                let x = ends[0].0 + (ends[1].0 - ends[0].0) * t;
                let k = usize::from(in0);
                ends[k] = (x, Feature::Edge(s.edge), Feature::Edge(e));
            }
        }
    }
    ends.to_vec()
}

/// Sutherland–Hodgman: the incident polygon (face `g` of the incident body, corners in loop
/// order) clipped by each side plane in turn. A corner less than `snap` outside a plane is
/// kept as it is (no new point beside it); a new corner where an incident edge leaves or
/// enters is named (reference edge, incident edge), and one where the boundary running along
/// a side plane meets the next plane is named (the reference vertex between the two edges,
/// incident face `g`).
fn clip_polygon(
    mut poly: Vec<Corner>,
    ref_poly: &ConvexPolyhedron,
    g: u32,
    planes: &[SidePlane],
    snap: f64,
) -> Vec<(DVec3, Feature, Feature)> {
    let name = |on: On, r: u32| -> (Feature, Feature) {
        match on {
            On::Incident(e) => (Feature::Edge(r), Feature::Edge(e)),
            On::Reference(q) => {
                let (eq, er) = (ref_poly.edge(q), ref_poly.edge(r));
                let shared = [eq.tail, eq.head]
                    .into_iter()
                    .find(|&v| v == er.tail || v == er.head);
                (
                    shared.map_or(Feature::Edge(r), Feature::Vertex),
                    Feature::Face(g),
                )
            }
        }
    };
    for s in planes {
        if poly.is_empty() {
            break;
        }
        let d: Vec<f64> = poly.iter().map(|c| s.normal.dot(c.p - s.origin)).collect();
        let mut out = Vec::with_capacity(poly.len() + 1);
        for i in 0..poly.len() {
            let j = (i + 1) % poly.len();
            let (cur, nxt) = (poly[i], poly[j]);
            let (dc, dn) = (d[i], d[j]);
            let at = |dc: f64, dn: f64| {
                let t = (dc / (dc - dn)).clamp(0.0, 1.0);
                cur.p + (nxt.p - cur.p) * t
            };
            match (dc <= snap, dn <= snap) {
                (true, true) => out.push(cur),
                (true, false) => {
                    if dc >= -snap {
                        // On the plane: it is where the polygon leaves.
                        out.push(Corner {
                            next: On::Reference(s.edge),
                            ..cur
                        });
                    } else {
                        out.push(cur);
                        let (reference, incident) = name(cur.next, s.edge);
                        out.push(Corner {
                            p: at(dc, dn),
                            reference,
                            incident,
                            next: On::Reference(s.edge),
                        });
                    }
                }
                (false, true) => {
                    if dn < -snap {
                        let (reference, incident) = name(cur.next, s.edge);
                        out.push(Corner {
                            p: at(dc, dn),
                            reference,
                            incident,
                            next: cur.next,
                        });
                    }
                }
                (false, false) => {}
            }
        }
        poly = out;
    }
    poly.into_iter()
        .map(|c| (c.p, c.reference, c.incident))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use impulse_geom::primitives;

    /// The contact feature does not depend on where the search starts: a box's bottom face,
    /// tilted within the tolerance, from every vertex; tilted beyond it, its low edge; a
    /// corner down, the corner.
    #[test]
    fn contact_features_do_not_depend_on_the_warm_start() {
        let bx = primitives::cuboid(DVec3::new(0.1, 0.05, 0.02)).unwrap();
        let tol = 1e-4;
        let bottom = (0..bx.face_count() as u32)
            .find(|&f| bx.face_plane(f).normal.z < -0.5)
            .unwrap();
        for (tilt, want) in [(0.2 * tol / 0.1, Some(bottom)), (3.0 * tol / 0.1, None)] {
            let dir = glam::DQuat::from_rotation_y(tilt) * -DVec3::Z;
            let mut seen = Vec::new();
            for v in 0..bx.vertices().len() as u32 {
                seen.push(support_feature(&bx, dir, Feature::Vertex(v), tol).feature);
            }
            seen.dedup();
            assert_eq!(seen.len(), 1, "{seen:?}");
            match want {
                Some(f) => assert_eq!(seen[0], Feature::Face(f)),
                None => assert!(matches!(seen[0], Feature::Edge(_)), "{seen:?}"),
            }
        }
        let dir = DVec3::new(1.0, 1.0, 1.0).normalize();
        let f = support_feature(&bx, dir, Feature::Vertex(0), tol).feature;
        assert_eq!(f, Feature::Vertex(bx.support(dir)));
    }

    /// A sliver face (1e-6 wide) seen edge-on lies within the tolerance of the support plane
    /// but faces away from the direction by 90°: it is an edge contact, not a face one (no
    /// projection onto its plane along the direction exists).
    #[test]
    fn a_face_seen_edge_on_is_an_edge() {
        let sliver = ConvexPolyhedron::hull(&[
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(0.1, 0.0, 0.0),
            DVec3::new(0.05, 1e-6, 0.0),
            DVec3::new(0.03, 0.03, 0.1),
        ])
        .unwrap();
        let f = support_feature(&sliver, -DVec3::Y, Feature::Vertex(0), 1e-4).feature;
        let Feature::Edge(e) = f else { panic!("{f:?}") };
        let ed = sliver.edge(e);
        assert_eq!(sliver.vertex(ed.tail).y + sliver.vertex(ed.head).y, 0.0);
    }
}
