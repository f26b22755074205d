//! Closest features of two convex polyhedra by V-Clip (Mirtich 1998), the successor of the
//! Lin–Canny algorithm of thesis §2.2.
//!
//! Every feature F (vertex, edge, face) of a convex polyhedron has a Voronoi region V(F): the
//! points closer to F than to any other feature. The regions are bounded by planes, each plane
//! shared with a neighbouring feature. Features F_a, F_b with closest points a, b are the
//! closest features of the two bodies exactly when a ∈ V(F_b) and b ∈ V(F_a) (thesis Theorems 1
//! and 2). The walk starts from a cached pair (coherence, §2.2.1), tests each feature of the
//! pair against the other's Voronoi region, and on a violation moves to the neighbour across
//! the violated plane. Instead of testing closest points, V-Clip *clips* an edge against a
//! region and looks at the sign of the distance derivative where the edge leaves it; this is
//! what makes it terminate without numerical tolerances in degenerate configurations (parallel
//! faces and edges, points exactly on region boundaries), and what lets it detect penetration
//! (an edge crossing a face inside the face's region, or a vertex inside the other body) where
//! Lin–Canny would cycle.
//!
//! Plane conventions used below (all unnormalised: only signs and ratios matter):
//! - vertex v / edge to w: `(x − v)·(v − w)`, positive on the vertex's side;
//! - edge e = t→h / its end t: `(x − t)·(h − t)` positive on the edge's side, likewise at h;
//! - edge e / adjacent face f: a plane containing e, perpendicular to f, positive on the edge's
//!   side (away from f's interior); the face's side of the same plane is its negation;
//! - face f: its outward plane, positive above the face.
//!
//! States are V–V, V–E, V–F, E–E and E–F (and their mirrors); F–F never arises. A state that
//! has found the closest features returns them; penetration returns a witness. A step limit
//! guards against floating-point cycles; if it is ever reached the brute-force search
//! ([`crate::brute`]) answers and [`Closest::fallback`] says so.

use glam::DVec3;
use impulse_geom::{ConvexPolyhedron, Pose};

use crate::brute;
use crate::feature::{Closest, Feature, FeaturePair};

/// Fixed part of the step limit of one query. The limit is this plus
/// [`STEP_LIMIT_PER_FEATURE`] times the number of features of both polyhedra; V-Clip needs far
/// fewer steps (each step strictly improves the pair), so reaching it means a floating-point
/// cycle.
pub const STEP_LIMIT_BASE: u32 = 64;

/// Steps allowed per feature of the two polyhedra (see [`STEP_LIMIT_BASE`]).
pub const STEP_LIMIT_PER_FEATURE: u32 = 2;

/// One polyhedron of the pair and the transform of its frame into the other's.
struct Side<'a> {
    poly: &'a ConvexPolyhedron,
    /// Maps this polyhedron's body coordinates into the other polyhedron's body coordinates.
    to_other: Pose,
}

/// The outcome of one state handler, for features of polyhedra P (first) and Q (second).
enum Step {
    /// Move on to this pair (feature of P, feature of Q).
    Continue(Feature, Feature),
    /// Closest features found: closest points on P (P frame) and on Q (Q frame).
    Done(DVec3, DVec3),
    /// The bodies intersect: witness points on P (P frame) and on Q (Q frame).
    Penetrating(DVec3, DVec3),
}

impl Step {
    /// The same outcome with the roles of P and Q exchanged.
    fn swap(self) -> Step {
        match self {
            Step::Continue(p, q) => Step::Continue(q, p),
            Step::Done(p, q) => Step::Done(q, p),
            Step::Penetrating(p, q) => Step::Penetrating(q, p),
        }
    }
}

/// Closest features of `a` at `pose_a` and `b` at `pose_b`, starting from `warm` (the pair the
/// previous query of the same two bodies returned; [`FeaturePair::default`] for a cold start).
/// Features that do not exist on the given polyhedra are replaced by a cold start.
pub fn closest(
    a: &ConvexPolyhedron,
    pose_a: &Pose,
    b: &ConvexPolyhedron,
    pose_b: &Pose,
    warm: FeaturePair,
) -> Closest {
    let side_a = Side {
        poly: a,
        to_other: pose_b.inverse() * *pose_a,
    };
    let side_b = Side {
        poly: b,
        to_other: pose_a.inverse() * *pose_b,
    };
    let (mut fa, mut fb) = if warm.a.is_valid_for(a) && warm.b.is_valid_for(b) {
        (warm.a, warm.b)
    } else {
        (Feature::Vertex(0), Feature::Vertex(0))
    };
    if let (Feature::Face(f), Feature::Face(_)) = (fa, fb) {
        fa = Feature::Vertex(a.face_vertices(f)[0]);
    }
    let features =
        |p: &ConvexPolyhedron| (p.vertices().len() + p.edges().len() + p.face_count()) as u32;
    let limit = STEP_LIMIT_BASE + STEP_LIMIT_PER_FEATURE * (features(a) + features(b));
    for steps in 0..limit {
        let step = match (fa, fb) {
            (Feature::Vertex(x), Feature::Vertex(y)) => vertex_vertex(&side_a, x, &side_b, y),
            (Feature::Vertex(x), Feature::Edge(y)) => vertex_edge(&side_a, x, &side_b, y),
            (Feature::Edge(x), Feature::Vertex(y)) => vertex_edge(&side_b, y, &side_a, x).swap(),
            (Feature::Vertex(x), Feature::Face(y)) => vertex_face(&side_a, x, &side_b, y),
            (Feature::Face(x), Feature::Vertex(y)) => vertex_face(&side_b, y, &side_a, x).swap(),
            (Feature::Edge(x), Feature::Edge(y)) => edge_edge(&side_a, x, &side_b, y),
            (Feature::Edge(x), Feature::Face(y)) => edge_face(&side_a, x, &side_b, y),
            (Feature::Face(x), Feature::Edge(y)) => edge_face(&side_b, y, &side_a, x).swap(),
            // Never produced by a handler; only a cold start could, and it is excluded above.
            (Feature::Face(x), Feature::Face(_)) => {
                Step::Continue(Feature::Vertex(a.face_vertices(x)[0]), fb)
            }
        };
        match step {
            Step::Continue(na, nb) => (fa, fb) = (na, nb),
            Step::Done(pa, pb) | Step::Penetrating(pa, pb) => {
                let (point_a, point_b) = (pose_a.transform_point(pa), pose_b.transform_point(pb));
                let distance = point_a.distance(point_b);
                let penetrating = matches!(step, Step::Penetrating(..)) || distance == 0.0;
                return Closest {
                    distance: if penetrating { 0.0 } else { distance },
                    point_a,
                    point_b,
                    features: FeaturePair { a: fa, b: fb },
                    penetrating,
                    steps,
                    fallback: false,
                };
            }
        }
    }
    Closest {
        steps: limit,
        fallback: true,
        ..brute::closest(a, pose_a, b, pose_b)
    }
}

fn vertex(p: &ConvexPolyhedron, v: u32) -> DVec3 {
    p.vertex(v)
}

fn ends(p: &ConvexPolyhedron, e: u32) -> (DVec3, DVec3) {
    let ed = p.edge(e);
    (p.vertex(ed.tail), p.vertex(ed.head))
}

/// The plane between edge `e` and its face `f`: positive on the edge's side (away from the
/// face's interior), length-scaled by |e|.
fn edge_face_plane(p: &ConvexPolyhedron, e: u32, f: u32, x: DVec3) -> f64 {
    let ed = p.edge(e);
    let (t, h) = ends(p, e);
    let n = p.face_plane(f).normal;
    // The face's interior lies to the left of its loop direction: n × (loop direction).
    // The left face runs t→h, the right face h→t; the edge side is the opposite of interior.
    let away = if f == ed.left {
        (h - t).cross(n)
    } else {
        n.cross(h - t)
    };
    away.dot(x - t)
}

/// Clipping of a segment `o + λ(d − o)`, λ ∈ [0, 1], against a set of planes bounding a
/// Voronoi region (V-Clip's `clipEdge`).
struct Clip {
    lo: f64,
    hi: f64,
    /// The neighbour whose plane clipped the low end.
    lo_n: Option<Feature>,
    /// The neighbour whose plane clipped the high end.
    hi_n: Option<Feature>,
    /// Set when one plane excludes the whole segment (simple exclusion).
    simple: Option<Feature>,
    /// Set when the clipped interval became empty (compound exclusion).
    compound: bool,
}

/// Clips against planes given as (neighbour, value at o, value at d), positive inside.
fn clip(planes: impl Iterator<Item = (Feature, f64, f64)>) -> Clip {
    let mut c = Clip {
        lo: 0.0,
        hi: 1.0,
        lo_n: None,
        hi_n: None,
        simple: None,
        compound: false,
    };
    for (n, d0, d1) in planes {
        if d0 >= 0.0 {
            if d1 >= 0.0 {
                continue;
            }
            let t = d0 / (d0 - d1);
            if t < c.hi {
                c.hi = t;
                c.hi_n = Some(n);
                if c.hi < c.lo {
                    c.compound = true;
                    break;
                }
            }
        } else {
            if d1 < 0.0 {
                c.simple = Some(n);
                c.lo_n = Some(n);
                c.hi_n = Some(n);
                break;
            }
            let t = d0 / (d0 - d1);
            if t > c.lo {
                c.lo = t;
                c.lo_n = Some(n);
                if c.lo > c.hi {
                    c.compound = true;
                    break;
                }
            }
        }
    }
    c
}

/// V–V: each vertex must lie in the other's region (inside all its vertex–edge planes).
fn vertex_vertex(p: &Side, v1: u32, q: &Side, v2: u32) -> Step {
    let (x1, x2) = (vertex(p.poly, v1), vertex(q.poly, v2));
    let x2_in_p = q.to_other.transform_point(x2);
    for &g in p.poly.vertex_edges(v1) {
        let w = vertex(p.poly, p.poly.edge(g).other_vertex(v1));
        if (x2_in_p - x1).dot(x1 - w) < 0.0 {
            return Step::Continue(Feature::Edge(g), Feature::Vertex(v2));
        }
    }
    let x1_in_q = p.to_other.transform_point(x1);
    for &g in q.poly.vertex_edges(v2) {
        let w = vertex(q.poly, q.poly.edge(g).other_vertex(v2));
        if (x1_in_q - x2).dot(x2 - w) < 0.0 {
            return Step::Continue(Feature::Vertex(v1), Feature::Edge(g));
        }
    }
    Step::Done(x1, x2)
}

/// V–E: the vertex must lie in the edge's region, and the edge, clipped against the vertex's
/// region, must not leave it in a direction of decreasing distance.
fn vertex_edge(p: &Side, v: u32, q: &Side, e: u32) -> Step {
    let ed = q.poly.edge(e);
    let (t, h) = ends(q.poly, e);
    let u = h - t;
    let xv_q = p.to_other.transform_point(vertex(p.poly, v));
    let stay = Feature::Vertex(v);
    if (xv_q - t).dot(u) < 0.0 {
        return Step::Continue(stay, Feature::Vertex(ed.tail));
    }
    if (xv_q - h).dot(u) > 0.0 {
        return Step::Continue(stay, Feature::Vertex(ed.head));
    }
    for f in [ed.left, ed.right] {
        if edge_face_plane(q.poly, e, f, xv_q) < 0.0 {
            return Step::Continue(stay, Feature::Face(f));
        }
    }
    // Clip E (in P's frame) against V's region.
    let x = vertex(p.poly, v);
    let (o, d) = (q.to_other.transform_point(t), q.to_other.transform_point(h));
    let seg = d - o;
    let planes = p.poly.vertex_edges(v).iter().map(|&g| {
        let n = x - vertex(p.poly, p.poly.edge(g).other_vertex(v));
        (Feature::Edge(g), (o - x).dot(n), (d - x).dot(n))
    });
    let c = clip(planes);
    let edge = Feature::Edge(e);
    if let Some(g) = c.simple {
        return Step::Continue(g, edge);
    }
    // Derivative checks where E leaves V's region: if the distance to V decreases outwards,
    // the closest point lies beyond, and V gives way to the neighbouring edge.
    let slope = |lambda: f64| (o + seg * lambda - x).dot(seg);
    for (n, lambda, outwards) in [(c.lo_n, c.lo, 1.0), (c.hi_n, c.hi, -1.0)] {
        if let Some(n) = n {
            if o + seg * lambda == x {
                return Step::Penetrating(x, xv_q);
            }
            if outwards * slope(lambda) > 0.0 {
                return Step::Continue(n, edge);
            }
        }
    }
    if c.compound {
        // E misses V's region yet neither exit slopes down: only possible when the distance
        // is flat there (a tie); leave through the high end, where it does not rise.
        if let Some(n) = c.hi_n.or(c.lo_n) {
            return Step::Continue(n, edge);
        }
    }
    let s = ((xv_q - t).dot(u) / u.length_squared()).clamp(0.0, 1.0);
    Step::Done(x, t + u * s)
}

/// V–F: the vertex must lie in the face's prism and above it, and no edge at the vertex may
/// lead closer to the face's plane. Below the face plane with no way down is a local minimum:
/// either the vertex is above some other face (move there) or it is inside the body.
fn vertex_face(p: &Side, v: u32, q: &Side, f: u32) -> Step {
    let x = vertex(p.poly, v);
    let xv_q = p.to_other.transform_point(x);
    let stay = Feature::Vertex(v);
    // The most violated side plane (normalised so violations compare as distances).
    let mut worst: Option<(f64, u32)> = None;
    for &g in q.poly.face_edges(f) {
        let (t, h) = ends(q.poly, g);
        let inside = -edge_face_plane(q.poly, g, f, xv_q) / t.distance(h);
        if inside < 0.0 && worst.is_none_or(|(w, _)| inside < w) {
            worst = Some((inside, g));
        }
    }
    if let Some((_, g)) = worst {
        return Step::Continue(stay, Feature::Edge(g));
    }
    let plane = q.poly.face_plane(f);
    let dist = plane.signed_distance(xv_q);
    if dist == 0.0 {
        return Step::Penetrating(x, xv_q);
    }
    for &g in p.poly.vertex_edges(v) {
        let w = p
            .to_other
            .transform_point(vertex(p.poly, p.poly.edge(g).other_vertex(v)));
        let dw = plane.signed_distance(w);
        if (dist > 0.0 && dw < dist) || (dist < 0.0 && dw > dist) {
            return Step::Continue(Feature::Edge(g), Feature::Face(f));
        }
    }
    if dist > 0.0 {
        return Step::Done(x, xv_q - plane.normal * dist);
    }
    let mut best = (dist, f);
    for g in 0..q.poly.face_count() as u32 {
        let dg = q.poly.face_plane(g).signed_distance(xv_q);
        if dg > best.0 {
            best = (dg, g);
        }
    }
    if best.0 > 0.0 {
        return Step::Continue(stay, Feature::Face(best.1));
    }
    Step::Penetrating(x, xv_q)
}

/// What clipping one edge against the other edge's region decided.
enum EdgeTest {
    /// The other edge lies in this edge's region where it matters.
    Inside,
    /// This edge gives way to the neighbour.
    Update(Feature),
    /// The edges (or an edge and a face) intersect at this point (this edge's frame).
    Penetrating(DVec3),
}

/// Clips the segment `o`–`d` (in `poly`'s frame) against the region of edge `e`: first the
/// planes at its two ends, then the planes to its two faces, with derivative checks at the
/// clipping points (V-Clip's edge–edge subtest).
fn edge_edge_subtest(poly: &ConvexPolyhedron, e: u32, o: DVec3, d: DVec3) -> EdgeTest {
    let ed = poly.edge(e);
    let (t, h) = ends(poly, e);
    let (u, seg) = (h - t, d - o);
    let at = |lambda: f64| o + seg * lambda;
    let (mut lo, mut hi) = (0.0, 1.0);
    let (mut lo_n, mut hi_n): (Option<Feature>, Option<Feature>) = (None, None);
    for (n, d0, d1) in [
        (Feature::Vertex(ed.tail), (o - t).dot(u), (d - t).dot(u)),
        (Feature::Vertex(ed.head), (h - o).dot(u), (h - d).dot(u)),
    ] {
        if d0 < 0.0 {
            if d1 < 0.0 {
                return EdgeTest::Update(n);
            }
            lo = d0 / (d0 - d1);
            lo_n = Some(n);
        } else if d1 < 0.0 {
            hi = d0 / (d0 - d1);
            hi_n = Some(n);
        }
    }
    let (v_lo, v_hi, v_lo_n, v_hi_n) = (lo, hi, lo_n, hi_n);
    // Derivative of the distance to a vertex along the segment at λ: its sign is that of
    // (s(λ) − vertex)·seg.
    let towards_vertex = |v: u32, lambda: f64| (at(lambda) - poly.vertex(v)).dot(seg);
    let mut compound = false;
    for f in [ed.left, ed.right] {
        let (d0, d1) = (
            edge_face_plane(poly, e, f, o),
            edge_face_plane(poly, e, f, d),
        );
        if d0 < 0.0 {
            if d1 < 0.0 {
                // The whole segment lies beyond this face plane; unless the vertex ends
                // already say where to go, the face is the better feature.
                if let Some(Feature::Vertex(v)) = v_lo_n {
                    let der = towards_vertex(v, v_lo);
                    if at(v_lo) == poly.vertex(v) {
                        return EdgeTest::Penetrating(poly.vertex(v));
                    }
                    if der > 0.0 {
                        return EdgeTest::Update(Feature::Vertex(v));
                    }
                }
                if let Some(Feature::Vertex(v)) = v_hi_n {
                    let der = towards_vertex(v, v_hi);
                    if at(v_hi) == poly.vertex(v) {
                        return EdgeTest::Penetrating(poly.vertex(v));
                    }
                    if der < 0.0 {
                        return EdgeTest::Update(Feature::Vertex(v));
                    }
                }
                return EdgeTest::Update(Feature::Face(f));
            }
            let l = d0 / (d0 - d1);
            if l > lo {
                lo = l;
                lo_n = Some(Feature::Face(f));
                if lo > hi {
                    compound = true;
                    break;
                }
            }
        } else if d1 < 0.0 {
            let l = d0 / (d0 - d1);
            if l < hi {
                hi = l;
                hi_n = Some(Feature::Face(f));
                if hi < lo {
                    compound = true;
                    break;
                }
            }
        }
    }
    // Distances of the segment's clip points to a face's plane.
    let face_dists = |f: u32| {
        let plane = poly.face_plane(f);
        (plane.signed_distance(o), plane.signed_distance(d))
    };
    if compound {
        // The segment passes outside the region: pick the side where the distance falls.
        return match (lo_n, hi_n) {
            (Some(Feature::Vertex(v)), _) => {
                if at(lo) == poly.vertex(v) {
                    return EdgeTest::Penetrating(poly.vertex(v));
                }
                let n = if towards_vertex(v, lo) >= 0.0 {
                    lo_n
                } else {
                    hi_n
                };
                n.map_or(EdgeTest::Inside, EdgeTest::Update)
            }
            (_, Some(Feature::Vertex(v))) => {
                if at(hi) == poly.vertex(v) {
                    return EdgeTest::Penetrating(poly.vertex(v));
                }
                let n = if towards_vertex(v, hi) <= 0.0 {
                    hi_n
                } else {
                    lo_n
                };
                n.map_or(EdgeTest::Inside, EdgeTest::Update)
            }
            (Some(Feature::Face(fl)), Some(_)) => {
                let (d0, d1) = face_dists(fl);
                let dmin = d0 + lo * (d1 - d0);
                if dmin == 0.0 {
                    return EdgeTest::Penetrating(at(lo));
                }
                let towards_lo = if dmin > 0.0 { d0 < d1 } else { d0 > d1 };
                let n = if towards_lo { lo_n } else { hi_n };
                n.map_or(EdgeTest::Inside, EdgeTest::Update)
            }
            (Some(n), _) | (None, Some(n)) => EdgeTest::Update(n),
            (None, None) => EdgeTest::Inside,
        };
    }
    // Derivative checks at the clipping points.
    if let Some(n) = lo_n {
        match n {
            Feature::Face(f) => {
                let (d0, d1) = face_dists(f);
                let dmin = d0 + lo * (d1 - d0);
                let dmax = if hi_n.is_some() {
                    d0 + hi * (d1 - d0)
                } else {
                    d1
                };
                if dmin == 0.0 {
                    return EdgeTest::Penetrating(at(lo));
                }
                if (dmin > 0.0 && dmin < dmax) || (dmin < 0.0 && dmin > dmax) {
                    return EdgeTest::Update(n);
                }
            }
            Feature::Vertex(v) => {
                if at(lo) == poly.vertex(v) {
                    return EdgeTest::Penetrating(poly.vertex(v));
                }
                if towards_vertex(v, lo) > 0.0 {
                    return EdgeTest::Update(n);
                }
            }
            Feature::Edge(_) => {}
        }
    }
    if let Some(n) = hi_n {
        match n {
            Feature::Face(f) => {
                let (d0, d1) = face_dists(f);
                let dmin = if lo_n.is_some() {
                    d0 + lo * (d1 - d0)
                } else {
                    d0
                };
                let dmax = d0 + hi * (d1 - d0);
                if dmax == 0.0 {
                    return EdgeTest::Penetrating(at(hi));
                }
                if (dmax > 0.0 && dmax < dmin) || (dmax < 0.0 && dmax > dmin) {
                    return EdgeTest::Update(n);
                }
            }
            Feature::Vertex(v) => {
                if at(hi) == poly.vertex(v) {
                    return EdgeTest::Penetrating(poly.vertex(v));
                }
                if towards_vertex(v, hi) < 0.0 {
                    return EdgeTest::Update(n);
                }
            }
            Feature::Edge(_) => {}
        }
    }
    EdgeTest::Inside
}

/// E–E: each edge, clipped against the other's region, must not leave it towards a smaller
/// distance.
fn edge_edge(p: &Side, e1: u32, q: &Side, e2: u32) -> Step {
    let (t1, h1) = ends(p.poly, e1);
    let (t2, h2) = ends(q.poly, e2);
    match edge_edge_subtest(
        q.poly,
        e2,
        p.to_other.transform_point(t1),
        p.to_other.transform_point(h1),
    ) {
        EdgeTest::Update(n) => return Step::Continue(Feature::Edge(e1), n),
        EdgeTest::Penetrating(x_q) => {
            return Step::Penetrating(q.to_other.transform_point(x_q), x_q);
        }
        EdgeTest::Inside => {}
    }
    let (o, d) = (
        q.to_other.transform_point(t2),
        q.to_other.transform_point(h2),
    );
    match edge_edge_subtest(p.poly, e1, o, d) {
        EdgeTest::Update(n) => return Step::Continue(n, Feature::Edge(e2)),
        EdgeTest::Penetrating(x_p) => {
            return Step::Penetrating(x_p, p.to_other.transform_point(x_p));
        }
        EdgeTest::Inside => {}
    }
    let (_, _, c1, c2) = brute::segment_segment(t1, h1, o, d);
    Step::Done(c1, p.to_other.transform_point(c2))
}

/// E–F: the edge is clipped against the face's prism. Missing it entirely sends the face to
/// its boundary feature nearest the edge; crossing the face plane inside it is penetration;
/// otherwise the end where the distance to the plane falls decides the next pair (the face's
/// edge that clipped it, or the edge's vertex). E–F is never a final state.
fn edge_face(p: &Side, e: u32, q: &Side, f: u32) -> Step {
    let ed = p.poly.edge(e);
    let (t, h) = ends(p.poly, e);
    let (o, d) = (p.to_other.transform_point(t), p.to_other.transform_point(h));
    let seg = d - o;
    let (mut lo, mut hi) = (0.0, 1.0);
    let (mut lo_n, mut hi_n): (Option<u32>, Option<u32>) = (None, None);
    let mut chopped = false;
    for &g in q.poly.face_edges(f) {
        let (d0, d1) = (
            -edge_face_plane(q.poly, g, f, o),
            -edge_face_plane(q.poly, g, f, d),
        );
        if d0 >= 0.0 {
            if d1 < 0.0 {
                let l = d0 / (d0 - d1);
                if l < hi {
                    hi = l;
                    hi_n = Some(g);
                }
            }
        } else if d1 < 0.0 {
            chopped = true;
        } else {
            let l = d0 / (d0 - d1);
            if l > lo {
                lo = l;
                lo_n = Some(g);
            }
        }
    }
    let edge = Feature::Edge(e);
    if chopped || lo > hi {
        return Step::Continue(edge, nearest_boundary_feature(q.poly, f, o, d));
    }
    let plane = q.poly.face_plane(f);
    let (d0, d1) = (plane.signed_distance(o), plane.signed_distance(d));
    let dmin = if lo_n.is_some() {
        d0 + lo * (d1 - d0)
    } else {
        d0
    };
    let dmax = if hi_n.is_some() {
        d0 + hi * (d1 - d0)
    } else {
        d1
    };
    let witness = |lambda: f64, dist: f64| {
        let x = o + seg * lambda;
        Step::Penetrating(t + (h - t) * lambda, x - plane.normal * dist)
    };
    if dmin == 0.0 || (dmin < 0.0 && dmax > 0.0) {
        return witness(lo, dmin);
    }
    if dmax == 0.0 || (dmin > 0.0 && dmax < 0.0) {
        return witness(hi, dmax);
    }
    // Both clip points on the same side of the plane: move towards the nearer end.
    if (dmin > 0.0 && d0 <= d1) || (dmin < 0.0 && d0 >= d1) {
        match lo_n {
            Some(g) => Step::Continue(edge, Feature::Edge(g)),
            None => Step::Continue(Feature::Vertex(ed.tail), Feature::Face(f)),
        }
    } else {
        match hi_n {
            Some(g) => Step::Continue(edge, Feature::Edge(g)),
            None => Step::Continue(Feature::Vertex(ed.head), Feature::Face(f)),
        }
    }
}

/// The edge or vertex of face `f`'s boundary nearest the segment `o`–`d` (in the face's frame).
fn nearest_boundary_feature(poly: &ConvexPolyhedron, f: u32, o: DVec3, d: DVec3) -> Feature {
    let mut best = (f64::INFINITY, Feature::Face(f));
    for &g in poly.face_edges(f) {
        let ed = poly.edge(g);
        let (t, h) = ends(poly, g);
        let (_, s, a, b) = brute::segment_segment(o, d, t, h);
        let dist = a.distance_squared(b);
        if dist < best.0 {
            let feature = match s {
                s if s <= 0.0 => Feature::Vertex(ed.tail),
                s if s >= 1.0 => Feature::Vertex(ed.head),
                _ => Feature::Edge(g),
            };
            best = (dist, feature);
        }
    }
    best.1
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DQuat;
    use impulse_geom::primitives;
    use rand::rngs::Xoshiro256PlusPlus;
    use rand::{RngExt, SeedableRng};

    /// Agreement with the brute-force distance, relative to the bodies' size (also how near to
    /// touching a pair may be reported either way): both are exact, so only rounding separates
    /// them.
    const DISTANCE_REL: f64 = 1e-9;

    fn rng(seed: u64) -> Xoshiro256PlusPlus {
        Xoshiro256PlusPlus::seed_from_u64(seed)
    }

    fn unit(r: &mut Xoshiro256PlusPlus) -> DVec3 {
        loop {
            let v = DVec3::new(r.random(), r.random(), r.random()) * 2.0 - DVec3::ONE;
            if (1e-4..1.0).contains(&v.length_squared()) {
                return v.normalize();
            }
        }
    }

    fn rotation(r: &mut Xoshiro256PlusPlus) -> DQuat {
        DQuat::from_axis_angle(unit(r), r.random::<f64>() * std::f64::consts::TAU)
    }

    /// A pool of shapes: random hulls of 4–40 points in stretched boxes and balls, plus boxes,
    /// prisms and geodesic spheres (which have parallel faces and many coplanar vertices).
    fn shapes(r: &mut Xoshiro256PlusPlus) -> Vec<ConvexPolyhedron> {
        let mut out = Vec::new();
        for k in 0..24 {
            let n = 4 + (r.random::<f64>() * 37.0) as usize;
            let scale = DVec3::new(
                0.3 + r.random::<f64>(),
                0.3 + r.random::<f64>(),
                0.3 + r.random::<f64>(),
            );
            let pts: Vec<DVec3> = (0..n)
                .map(|_| {
                    if k % 2 == 0 {
                        unit(r) * scale
                    } else {
                        (DVec3::new(r.random(), r.random(), r.random()) - 0.5) * scale
                    }
                })
                .collect();
            if let Ok(h) = ConvexPolyhedron::hull(&pts) {
                out.push(h);
            }
        }
        out.push(primitives::cuboid(DVec3::new(0.5, 0.3, 0.8)).unwrap());
        out.push(primitives::cuboid(DVec3::splat(0.5)).unwrap());
        out.push(primitives::regular_prism(6, 0.6, 0.2).unwrap());
        out.push(primitives::regular_prism(3, 0.6, 0.9).unwrap());
        out.push(primitives::geodesic_sphere(2, 0.7).unwrap());
        out
    }

    fn size(p: &ConvexPolyhedron) -> f64 {
        p.mesh().diameter()
    }

    /// Checks one query against the brute force; returns whether V-Clip said penetrating.
    fn check(
        a: &ConvexPolyhedron,
        pa: &Pose,
        b: &ConvexPolyhedron,
        pb: &Pose,
        warm: FeaturePair,
    ) -> Closest {
        let c = closest(a, pa, b, pb, warm);
        let r = brute::closest(a, pa, b, pb);
        let scale = size(a).max(size(b));
        assert!(!c.fallback, "step limit reached");
        if r.penetrating {
            // Touching to rounding may come out either way; a real overlap must be reported.
            let depth = -brute::sat_separation(a, pa, b, pb);
            assert!(
                c.penetrating
                    || (depth <= DISTANCE_REL * scale && c.distance <= DISTANCE_REL * scale),
                "V-Clip missed a penetration {depth:e} deep (distance {:e})",
                c.distance
            );
        } else if c.penetrating {
            assert!(
                r.distance <= DISTANCE_REL * scale,
                "V-Clip reports penetration at distance {}",
                r.distance
            );
        } else {
            assert!(
                (c.distance - r.distance).abs() <= DISTANCE_REL * scale,
                "distance {} vs brute force {}",
                c.distance,
                r.distance
            );
            // The points are on the bodies and realise the distance.
            assert!((c.point_a.distance(c.point_b) - c.distance).abs() <= DISTANCE_REL * scale);
            let on = |p: &ConvexPolyhedron, pose: &Pose, x: DVec3| {
                p.max_plane_distance(pose.inverse_transform_point(x)).abs() <= DISTANCE_REL * scale
            };
            assert!(
                on(a, pa, c.point_a) && on(b, pb, c.point_b),
                "closest points are not on the surfaces"
            );
        }
        c
    }

    #[test]
    fn ten_thousand_random_pairs_match_brute_force() {
        let mut r = rng(3);
        let pool = shapes(&mut r);
        let (mut penetrating, mut warm_steps, mut cold_steps) = (0, 0u64, 0u64);
        let mut cache = FeaturePair::default();
        for i in 0..10_000 {
            let (a, b) = (&pool[i % pool.len()], &pool[(i * 7 + 3) % pool.len()]);
            let pa = Pose::new(
                rotation(&mut r),
                (DVec3::new(r.random(), r.random(), r.random()) - 0.5) * 10.0,
            );
            // Gaps from deep overlap to two body sizes; a tenth of them within 1e-3 of contact.
            let reach = 0.5 * (size(a) + size(b));
            let gap = if i % 10 == 0 {
                (r.random::<f64>() - 0.5) * 2e-3
            } else {
                (r.random::<f64>() * 2.4 - 0.4) * reach
            };
            let pb = Pose::new(
                rotation(&mut r),
                pa.translation + unit(&mut r) * (0.5 * reach + gap),
            );
            let cold = check(a, &pa, b, &pb, FeaturePair::default());
            penetrating += cold.penetrating as u32;
            cold_steps += u64::from(cold.steps);
            // The same query from an unrelated cached pair must give the same answer.
            let warm = check(a, &pa, b, &pb, cache);
            warm_steps += u64::from(warm.steps);
            cache = warm.features;
            if !cache.a.is_valid_for(b) || !cache.b.is_valid_for(a) {
                cache = FeaturePair::default();
            }
        }
        // Both outcomes are well represented.
        assert!(
            (1_000..9_000).contains(&penetrating),
            "{penetrating} penetrating"
        );
        eprintln!(
            "cold steps/query {:.2}, stale-cache steps/query {:.2}",
            cold_steps as f64 / 1e4,
            warm_steps as f64 / 1e4
        );
    }

    #[test]
    fn degenerate_configurations_terminate_with_the_right_answer() {
        let cube = primitives::cuboid(DVec3::splat(0.5)).unwrap();
        let flat = primitives::cuboid(DVec3::new(1.0, 1.0, 0.1)).unwrap();
        let prism = primitives::regular_prism(4, 0.5 * 2f64.sqrt(), 0.5).unwrap();
        let cases: Vec<(&ConvexPolyhedron, Pose, &ConvexPolyhedron, Pose)> = vec![
            // Face on face, parallel, aligned and offset sideways; exactly touching; overlapping.
            (
                &cube,
                Pose::IDENTITY,
                &cube,
                Pose::from_translation(DVec3::new(1.2, 0.0, 0.0)),
            ),
            (
                &cube,
                Pose::IDENTITY,
                &cube,
                Pose::from_translation(DVec3::new(1.2, 0.5, 0.5)),
            ),
            (
                &cube,
                Pose::IDENTITY,
                &cube,
                Pose::from_translation(DVec3::new(1.2, 0.3, -0.7)),
            ),
            (
                &cube,
                Pose::IDENTITY,
                &cube,
                Pose::from_translation(DVec3::new(1.0, 0.2, 0.1)),
            ),
            (
                &cube,
                Pose::IDENTITY,
                &cube,
                Pose::from_translation(DVec3::new(0.9, 0.2, 0.1)),
            ),
            // Corner to corner along the diagonal: the vertices sit on Voronoi planes.
            (
                &cube,
                Pose::IDENTITY,
                &cube,
                Pose::from_translation(DVec3::splat(1.3)),
            ),
            (
                &cube,
                Pose::IDENTITY,
                &cube,
                Pose::from_translation(DVec3::new(1.3, 1.0, 0.0)),
            ),
            // Edge parallel to a face; edge parallel to an edge.
            (
                &cube,
                Pose::from_rotation(DQuat::from_rotation_z(std::f64::consts::FRAC_PI_4)),
                &flat,
                Pose::from_translation(DVec3::new(0.2, 0.1, -1.0)),
            ),
            (
                &cube,
                Pose::IDENTITY,
                &cube,
                Pose::new(
                    DQuat::from_rotation_x(std::f64::consts::FRAC_PI_4),
                    DVec3::new(1.1, 0.0, 0.9),
                ),
            ),
            // The same shape as a prism (a box whose vertical faces are rotated 45°).
            (
                &prism,
                Pose::IDENTITY,
                &cube,
                Pose::from_translation(DVec3::new(0.0, 0.0, 1.05)),
            ),
            (
                &prism,
                Pose::IDENTITY,
                &prism,
                Pose::from_translation(DVec3::new(0.0, 0.0, 1.0)),
            ),
            // A flat plate under a cube resting on it, and a cube standing on its edge.
            (
                &flat,
                Pose::IDENTITY,
                &cube,
                Pose::from_translation(DVec3::new(0.3, -0.2, 0.6 + 1e-9)),
            ),
            (
                &flat,
                Pose::IDENTITY,
                &cube,
                Pose::new(
                    DQuat::from_rotation_x(std::f64::consts::FRAC_PI_4),
                    DVec3::new(0.0, 0.0, 0.1 + 0.5 * 2f64.sqrt() + 1e-6),
                ),
            ),
        ];
        // Every starting pair (all feature combinations of a few indices) must end the same.
        for (a, pa, b, pb) in &cases {
            let starts = [
                Feature::Vertex(0),
                Feature::Vertex(3),
                Feature::Edge(0),
                Feature::Edge(5),
                Feature::Face(0),
                Feature::Face(2),
            ];
            for &fa in &starts {
                for &fb in &starts {
                    check(a, pa, b, pb, FeaturePair { a: fa, b: fb });
                }
            }
        }
    }

    #[test]
    fn coherent_queries_take_fewer_steps_than_cold_ones() {
        // A geodesic sphere circling a fixed cube: consecutive queries warm-started from the
        // previous answer need few feature steps; cold ones walk from vertex 0 every time.
        let cube = primitives::cuboid(DVec3::splat(0.5)).unwrap();
        let ball = primitives::geodesic_sphere(4, 0.4).unwrap();
        let (mut warm, mut cold, mut cache) = (0u32, 0u32, FeaturePair::default());
        for i in 0..720 {
            let ang = (i as f64).to_radians();
            let pb = Pose::new(
                DQuat::from_rotation_y(2.0 * ang),
                DVec3::new(1.2 * ang.cos(), 0.3, 1.2 * ang.sin()),
            );
            let w = check(&cube, &Pose::IDENTITY, &ball, &pb, cache);
            cache = w.features;
            warm += w.steps;
            cold += closest(&cube, &Pose::IDENTITY, &ball, &pb, FeaturePair::default()).steps;
        }
        assert!(warm * 5 < cold, "warm {warm} vs cold {cold} steps");
    }
}
