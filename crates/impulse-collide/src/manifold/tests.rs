//! Tests of contact manifolds against independent references: closed forms for boxes, spheres
//! and ellipsoids, an independent 2-D intersection of squares, and brute force on random
//! convex hulls.

use super::clip;
use super::*;
use crate::brute;
use crate::motion::testkit::{random_rotation, rng, unit_vector};
use glam::{DQuat, DVec2};
use impulse_geom::{ConvexPolyhedron, Ellipsoid, Sphere, primitives};
use rand::RngExt;

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

/// A box resting on a larger one face to face (just touching, a gap, a small overlap; any
/// yaw; either body first): four points exactly at the small box's bottom corners, each named
/// by its corner and the floor's top face, the floor's point straight below it, the gap the
/// analytic one. Lifted beyond the tolerance: no manifold.
#[test]
fn a_box_on_a_larger_box_is_held_at_its_four_corners() {
    let (fl, pf) = floor();
    let h = DVec3::new(0.1, 0.05, 0.02);
    let bx = cuboid(h);
    let top = face_along(&fl, DVec3::Z);
    for (gap, yaw) in [
        (0.0, 0.0),
        (0.3 * TOL, 0.7),
        (-0.5 * TOL, 2.0),
        (0.9 * TOL, -0.3),
    ] {
        let pb = Pose::new(
            DQuat::from_rotation_z(yaw),
            DVec3::new(0.3, -0.2, h.z + gap),
        );
        let corners: Vec<DVec3> = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
            .iter()
            .map(|&(x, y)| pb.transform_point(DVec3::new(x * h.x, y * h.y, -h.z)))
            .collect();
        for box_first in [true, false] {
            let m = if box_first {
                manifold(&bx, &pb, &fl, &pf)
            } else {
                manifold(&fl, &pf, &bx, &pb)
            }
            .unwrap();
            let sign = if box_first { -1.0 } else { 1.0 };
            assert!((m.normal - sign * DVec3::Z).length() < EXACT, "{m:?}");
            assert_eq!(m.points().len(), 4, "gap {gap} yaw {yaw}: {m:?}");
            let mut seen = Vec::new();
            for p in m.points() {
                let (on_box, on_floor, box_id, floor_id) = if box_first {
                    (p.point_a, p.point_b, p.id.a, p.id.b)
                } else {
                    (p.point_b, p.point_a, p.id.b, p.id.a)
                };
                let k = corners
                    .iter()
                    .position(|c| c.distance(on_box) < EXACT)
                    .unwrap_or_else(|| panic!("{on_box} is no corner: {m:?}"));
                seen.push(k);
                let below = DVec3::new(corners[k].x, corners[k].y, 0.0);
                assert!(on_floor.distance(below) < EXACT, "{on_floor} vs {below}");
                assert!((p.gap - gap).abs() < EXACT, "{} vs {gap}", p.gap);
                assert_eq!(floor_id, top);
                assert!(vertex_at(&bx, &pb, box_id).distance(on_box) < EXACT);
            }
            seen.sort_unstable();
            assert_eq!(seen, [0, 1, 2, 3]);
            if box_first {
                check_ids(&m, &bx, &pb, &fl, &pf, EXACT);
            } else {
                check_ids(&m, &fl, &pf, &bx, &pb, EXACT);
            }
        }
    }
    let high = Pose::from_translation(DVec3::new(0.0, 0.0, h.z + 2.0 * TOL));
    assert!(manifold(&bx, &high, &fl, &pf).is_none());
}

/// The four corners of a square of half side `h` centred at `c`, turned by `yaw`,
/// counter-clockwise.
fn square(c: DVec2, yaw: f64, h: f64) -> Vec<DVec2> {
    let (s, co) = yaw.sin_cos();
    [(-h, -h), (h, -h), (h, h), (-h, h)]
        .iter()
        .map(|&(x, y)| c + DVec2::new(co * x - s * y, s * x + co * y))
        .collect()
}

fn cross2(u: DVec2, v: DVec2) -> f64 {
    u.x * v.y - u.y * v.x
}

fn inside2(poly: &[DVec2], p: DVec2, slack: f64) -> bool {
    (0..poly.len()).all(|k| {
        let (a, b) = (poly[k], poly[(k + 1) % poly.len()]);
        cross2(b - a, p - a) >= -slack * (b - a).length()
    })
}

/// The points sorted counter-clockwise about their centroid (they are in convex position).
fn ccw(mut pts: Vec<DVec2>) -> Vec<DVec2> {
    let c = pts.iter().sum::<DVec2>() / pts.len() as f64;
    pts.sort_by(|p, q| {
        let (a, b) = ((*p - c).to_angle(), (*q - c).to_angle());
        a.total_cmp(&b)
    });
    pts
}

fn shoelace(pts: &[DVec2]) -> f64 {
    0.5 * (0..pts.len())
        .map(|k| cross2(pts[k], pts[(k + 1) % pts.len()]))
        .sum::<f64>()
}

/// The intersection of two convex polygons, independently of any clipping: the corners of
/// each inside the other and the crossings of their edges, in counter-clockwise order.
fn overlap2(p: &[DVec2], q: &[DVec2]) -> Vec<DVec2> {
    let mut pts: Vec<DVec2> = p.iter().copied().filter(|&x| inside2(q, x, 0.0)).collect();
    pts.extend(q.iter().copied().filter(|&x| inside2(p, x, 0.0)));
    for i in 0..p.len() {
        let (a, b) = (p[i], p[(i + 1) % p.len()]);
        for j in 0..q.len() {
            let (c, d) = (q[j], q[(j + 1) % q.len()]);
            let den = cross2(b - a, d - c);
            if den.abs() < 1e-300 {
                continue;
            }
            let t = cross2(c - a, d - c) / den;
            let u = cross2(c - a, b - a) / den;
            if (0.0..=1.0).contains(&t) && (0.0..=1.0).contains(&u) {
                pts.push(a + (b - a) * t);
            }
        }
    }
    let mut unique: Vec<DVec2> = Vec::new();
    for x in pts {
        if unique.iter().all(|u| u.distance(x) > EXACT) {
            unique.push(x);
        }
    }
    if unique.len() < 3 {
        return unique;
    }
    ccw(unique)
}

/// Reduced manifolds keep at least this fraction of the exact overlap area of two squares.
/// The best four of a regular octagon's eight corners keep 1/√2 ≈ 0.707 of it; the largest
/// quadrilateral inscribed in any convex region keeps at least 2/π ≈ 0.637 (the ellipse is the
/// worst case, Sas 1939).
const AREA_KEPT_MIN: f64 = 0.7;

/// A square block on another, turned about the normal and offset: before reduction the
/// clipped polygon is the overlap of the two squares (its corners, from an independent
/// intersection, to within the merging distance); after reduction at most four of its corners,
/// inside both squares, whose hull is the largest of any four corners (brute force over all
/// subsets) and keeps at least [`AREA_KEPT_MIN`] of the area. Turned 45° and centred, the
/// overlap is the regular octagon and exactly 1/√2 of it is kept.
#[test]
fn turned_and_offset_blocks_keep_the_overlap_area() {
    let mut r = rng(12);
    let (hl, thick) = (0.05, 0.025);
    let lower = cuboid(DVec3::new(hl, hl, thick));
    let pl = Pose::from_translation(DVec3::new(0.0, 0.0, -thick));
    let mut worst = f64::INFINITY;
    let (mut worst_corner, mut worst_area) = (0.0f64, 0.0f64);
    let mut worst_vs_best = f64::INFINITY;
    let mut cases = vec![(0.05, std::f64::consts::FRAC_PI_4, DVec2::ZERO)];
    for _ in 0..300 {
        cases.push((
            r.random_range(0.02..0.06),
            r.random_range(0.0..std::f64::consts::FRAC_PI_2),
            DVec2::new(r.random_range(-0.06..0.06), r.random_range(-0.06..0.06)),
        ));
    }
    let mut checked = 0;
    for (k, &(hu, yaw, off)) in cases.iter().enumerate() {
        let exact = overlap2(&square(off, yaw, hu), &square(DVec2::ZERO, 0.0, hl));
        if exact.len() < 3 || shoelace(&exact) < 1e-6 {
            continue;
        }
        checked += 1;
        let upper = cuboid(DVec3::new(hu, hu, thick));
        let pu = Pose::new(DQuat::from_rotation_z(yaw), DVec3::new(off.x, off.y, thick));
        let n = -DVec3::Z;
        let (all, features, snap) = clip::contact_points(
            poly(&upper),
            &pu,
            poly(&lower),
            &pl,
            n,
            FeaturePair::default(),
            TOL,
        )
        .unwrap();
        assert!(matches!(
            (features.a, features.b),
            (Feature::Face(_), Feature::Face(_))
        ));
        let flat: Vec<DVec2> = all.iter().map(|p| p.point_a.truncate()).collect();
        let area = shoelace(&exact);
        // Each clipped point is a corner of the exact overlap, and each corner is one of
        // them; a corner within the merging distance of a side plane is kept where it is,
        // so positions agree to that distance.
        assert_eq!(flat.len(), exact.len(), "case {k}: {flat:?} vs {exact:?}");
        for x in &exact {
            let d = flat
                .iter()
                .map(|y| y.distance(*x))
                .fold(f64::INFINITY, f64::min);
            assert!(d <= snap, "case {k}: corner {x} missed by {d}: {flat:?}");
            worst_corner = worst_corner.max(d);
        }
        let area_error = (shoelace(&ccw(flat)) - area).abs() / area;
        worst_area = worst_area.max(area_error);
        if k == 0 {
            assert_eq!(all.len(), 8, "the octagon");
        }
        let mut reduced = all.clone();
        clip::reduce(&mut reduced, n, snap);
        let m = manifold(&upper, &pu, &lower, &pl).unwrap();
        assert_eq!(m.points(), &reduced[..], "the manifold is the reduced clip");
        check_ids(&m, &upper, &pu, &lower, &pl, snap);
        assert!(m.points().len() <= MAX_POINTS);
        let kept: Vec<DVec2> = m.points().iter().map(|p| p.point_a.truncate()).collect();
        for p in m.points() {
            assert!(p.gap.abs() < EXACT && p.point_b.z.abs() < EXACT);
            let x = p.point_a.truncate();
            assert!(inside2(&square(off, yaw, hu), x, snap));
            assert!(inside2(&square(DVec2::ZERO, 0.0, hl), x, snap));
        }
        let fraction = if kept.len() < 3 {
            0.0
        } else {
            shoelace(&ccw(kept)) / area
        };
        if k == 0 {
            assert!((fraction - std::f64::consts::FRAC_1_SQRT_2).abs() < EXACT);
        }
        worst = worst.min(fraction);
        // The best four corners (brute force over all subsets).
        let xs: Vec<DVec2> = all.iter().map(|p| p.point_a.truncate()).collect();
        let mut best = 0.0f64;
        for i in 0..xs.len() {
            for j in i + 1..xs.len() {
                for k in j + 1..xs.len() {
                    for l in k + 1..xs.len() {
                        best = best.max(shoelace(&ccw(vec![xs[i], xs[j], xs[k], xs[l]])));
                    }
                }
            }
        }
        if xs.len() >= 4 {
            worst_vs_best = worst_vs_best.min(fraction * area / best);
        }
    }
    assert!(checked > 200, "{checked}");
    println!(
        "{checked} overlaps: corners within {worst_corner:.1e} m, area within {worst_area:.1e} \
         (relative) before reduction; at least {worst:.4} of the area kept after, {worst_vs_best:.4} of the best four's"
    );
    assert!(
        worst >= AREA_KEPT_MIN,
        "kept only {worst} of the overlap area"
    );
    assert!(
        worst_vs_best >= 1.0 - EXACT,
        "{worst_vs_best} of the best four's area"
    );
}

/// A box tilted by θ about its long axis onto the floor: two points at the ends of its low
/// edge (edge on face), at the analytic gap; tilted so little that the whole face is within
/// the tolerance (face on face): four points, the high edge's gap larger by 2·h_y·sin θ, or
/// only the low edge's two when that gap exceeds the tolerance.
#[test]
fn a_tilted_box_rests_on_its_low_edge() {
    let (fl, pf) = floor();
    let h = DVec3::new(0.05, 0.04, 0.02);
    let bx = cuboid(h);
    let top = face_along(&fl, DVec3::Z);
    let rise = |t: f64| 2.0 * h.y * t.sin();
    // θ with 2 h_y sin θ = TOL/2 and 0.9·TOL: the whole face is within the tolerance.
    let (small, within) = ((0.25 * TOL / h.y).asin(), (0.45 * TOL / h.y).asin());
    for (theta, gap) in [
        (0.01, 0.0),
        (0.1, 0.4 * TOL),
        (0.5, -0.3 * TOL),
        (small, 0.2 * TOL),
        (within, 0.5 * TOL),
    ] {
        let q = DQuat::from_rotation_x(theta);
        let (s, c) = theta.sin_cos();
        let centre = DVec3::new(0.1, 0.2, h.y * s + h.z * c + gap);
        let pb = Pose::new(q, centre);
        let m = manifold(&bx, &pb, &fl, &pf).unwrap();
        let low_y = centre.y - h.y * c + h.z * s;
        let mut want = vec![
            (DVec3::new(centre.x - h.x, low_y, gap), gap),
            (DVec3::new(centre.x + h.x, low_y, gap), gap),
        ];
        if rise(theta) <= TOL {
            assert_eq!(m.features.a, face_along(&bx, -DVec3::Z));
            let high_y = centre.y + h.y * c + h.z * s;
            let g = gap + rise(theta);
            if g <= TOL {
                want.push((DVec3::new(centre.x - h.x, high_y, g), g));
                want.push((DVec3::new(centre.x + h.x, high_y, g), g));
            }
        } else {
            assert!(matches!(m.features.a, Feature::Edge(_)), "{m:?}");
        }
        assert_eq!(m.features.b, top);
        assert_eq!(m.points().len(), want.len(), "θ {theta}: {m:?}");
        check_ids(&m, &bx, &pb, &fl, &pf, EXACT);
        for (x, g) in want {
            let p = m
                .points()
                .iter()
                .find(|p| p.point_a.distance(x) < EXACT)
                .unwrap_or_else(|| panic!("θ {theta}: no point at {x}: {m:?}"));
            assert!((p.gap - g).abs() < EXACT, "θ {theta}: {} vs {g}", p.gap);
            assert!(p.point_b.distance(DVec3::new(x.x, x.y, 0.0)) < EXACT);
            assert_eq!(p.id.b, top);
            assert!(vertex_at(&bx, &pb, p.id.a).distance(p.point_a) < EXACT);
        }
    }
}

/// A tilted box whose low edge runs off the side of a table: the edge is cut at the table's
/// edge, that point named by the two edges, the other end by the box's corner; a box edge
/// resting across another box's edge (crossed): one point where they cross; along it
/// (parallel, both boxes turned 45° about x): the two ends of their common stretch.
#[test]
fn edges_cut_at_a_side_cross_and_lie_along() {
    let table = cuboid(DVec3::new(0.1, 0.1, 0.05));
    let pt = Pose::from_translation(DVec3::new(0.0, 0.0, -0.05));
    let h = DVec3::new(0.05, 0.04, 0.02);
    let bx = cuboid(h);
    let theta: f64 = 0.3;
    let (s, c) = theta.sin_cos();
    let centre = DVec3::new(0.08, 0.0, h.y * s + h.z * c);
    let pb = Pose::new(DQuat::from_rotation_x(theta), centre);
    let m = manifold(&bx, &pb, &table, &pt).unwrap();
    assert_eq!(m.points().len(), 2, "{m:?}");
    check_ids(&m, &bx, &pb, &table, &pt, EXACT);
    let low_y = -h.y * c + h.z * s;
    for (x, edge_cut) in [(0.03, false), (0.1, true)] {
        let p = m
            .points()
            .iter()
            .find(|p| p.point_a.distance(DVec3::new(x, low_y, 0.0)) < EXACT)
            .unwrap_or_else(|| panic!("no point at x = {x}: {m:?}"));
        assert_eq!(
            edge_cut,
            matches!((p.id.a, p.id.b), (Feature::Edge(_), Feature::Edge(_))),
            "{p:?}"
        );
        assert!(p.gap.abs() < EXACT);
    }
    // Crossed: a cube turned 45° about x (its bottom edge along x) on a cube turned 45°
    // about y (its top edge along y), touching at a gap.
    let cube = cuboid(DVec3::splat(0.05));
    let r2 = 0.05 * 2f64.sqrt();
    let gap = 0.3 * TOL;
    let lower = Pose::new(
        DQuat::from_rotation_y(std::f64::consts::FRAC_PI_4),
        DVec3::new(0.01, 0.0, -r2),
    );
    let upper = Pose::new(
        DQuat::from_rotation_x(std::f64::consts::FRAC_PI_4),
        DVec3::new(0.0, 0.02, r2 + gap),
    );
    let m = manifold(&cube, &upper, &cube, &lower).unwrap();
    assert_eq!(m.points().len(), 1, "{m:?}");
    assert!(matches!(
        (m.features.a, m.features.b),
        (Feature::Edge(_), Feature::Edge(_))
    ));
    let p = m.points()[0];
    assert!(
        p.point_a.distance(DVec3::new(0.01, 0.02, gap)) < EXACT,
        "{p:?}"
    );
    assert!(p.point_b.distance(DVec3::new(0.01, 0.02, 0.0)) < EXACT);
    assert!((p.gap - gap).abs() < EXACT);
    check_ids(&m, &cube, &upper, &cube, &lower, EXACT);
    // Parallel: both turned 45° about x, the upper shifted 0.03 along x: the common stretch
    // x ∈ [−0.02, 0.05].
    let q = DQuat::from_rotation_x(std::f64::consts::FRAC_PI_4);
    let lower = Pose::new(q, DVec3::new(0.0, 0.0, -r2));
    let upper = Pose::new(q, DVec3::new(0.03, 0.0, r2 + gap));
    let m = manifold(&cube, &upper, &cube, &lower).unwrap();
    assert_eq!(m.points().len(), 2, "{m:?}");
    check_ids(&m, &cube, &upper, &cube, &lower, EXACT);
    for x in [-0.02, 0.05] {
        assert!(
            m.points()
                .iter()
                .any(|p| p.point_b.distance(DVec3::new(x, 0.0, 0.0)) < EXACT
                    && (p.gap - gap).abs() < EXACT),
            "{x}: {m:?}"
        );
    }
}

/// A cube balanced on an edge: the edge's two ends; on a vertex (a body diagonal vertical):
/// that vertex alone. Just touching and at a small gap.
#[test]
fn a_cube_balanced_on_an_edge_and_on_a_vertex() {
    let (fl, pf) = floor();
    let h = 0.05;
    let cube = cuboid(DVec3::splat(h));
    for gap in [0.0, 0.5 * TOL] {
        let q = DQuat::from_rotation_y(std::f64::consts::FRAC_PI_4);
        let pb = Pose::new(q, DVec3::new(0.0, 0.1, h * 2f64.sqrt() + gap));
        let m = manifold(&cube, &pb, &fl, &pf).unwrap();
        assert!(matches!(m.features.a, Feature::Edge(_)), "{m:?}");
        assert_eq!(m.points().len(), 2);
        for y in [0.1 - h, 0.1 + h] {
            let x = DVec3::new(0.0, y, gap);
            assert!(
                m.points().iter().any(|p| p.point_a.distance(x) < EXACT
                    && (p.gap - gap).abs() < EXACT
                    && p.point_b.distance(DVec3::new(0.0, y, 0.0)) < EXACT),
                "{x}: {m:?}"
            );
        }
        let corner = DVec3::splat(-h);
        let q = DQuat::from_rotation_arc(corner.normalize(), -DVec3::Z);
        let pb = Pose::new(q, DVec3::new(0.2, 0.0, h * 3f64.sqrt() + gap));
        let m = manifold(&cube, &pb, &fl, &pf).unwrap();
        assert_eq!(m.points().len(), 1, "{m:?}");
        let p = m.points()[0];
        assert!(matches!(m.features.a, Feature::Vertex(_)));
        assert!(
            p.point_a.distance(DVec3::new(0.2, 0.0, gap)) < EXACT,
            "{p:?}"
        );
        assert!(p.point_b.distance(DVec3::new(0.2, 0.0, 0.0)) < EXACT);
        assert!((p.gap - gap).abs() < EXACT);
    }
}

/// Degenerate input: faces tilted by 1e-12, a block exactly on an equal block (every corner
/// on a corner, also turned by a right angle), a block edge to edge beside another (an
/// overlap of zero area), and a sliver face down: finite points on both surfaces, one per
/// corner, never more than four, no panic.
#[test]
fn degenerate_contacts_give_clean_points() {
    let (fl, pf) = floor();
    let h = DVec3::new(0.05, 0.05, 0.025);
    let bx = cuboid(h);
    let finite = |m: &Manifold| {
        m.points()
            .iter()
            .all(|p| p.point_a.is_finite() && p.point_b.is_finite() && p.gap.is_finite())
            && m.normal.is_finite()
    };
    // Tilted by 1e-12 about x: four corners, gaps within 1e-12·h of zero.
    let pb = Pose::new(DQuat::from_rotation_x(1e-12), DVec3::new(0.0, 0.0, h.z));
    let m = manifold(&bx, &pb, &fl, &pf).unwrap();
    assert!(finite(&m));
    assert_eq!(m.points().len(), 4);
    assert!(m.points().iter().all(|p| p.gap.abs() < EXACT));
    // An equal block exactly on top, also turned by 90°: four points, one per corner, four
    // distinct ids.
    let pl = Pose::from_translation(DVec3::new(0.0, 0.0, -h.z));
    for yaw in [0.0, std::f64::consts::FRAC_PI_2, std::f64::consts::PI] {
        let pu = Pose::new(DQuat::from_rotation_z(yaw), DVec3::new(0.0, 0.0, h.z));
        let m = manifold(&bx, &pu, &bx, &pl).unwrap();
        assert!(finite(&m));
        assert_eq!(m.points().len(), 4, "yaw {yaw}: {m:?}");
        for (x, y) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            let c = DVec3::new(x * h.x, y * h.y, 0.0);
            assert!(
                m.points()
                    .iter()
                    .any(|p| p.point_a.distance(c) < EXACT && p.point_b.distance(c) < EXACT)
            );
        }
        check_ids(&m, &bx, &pu, &bx, &pl, EXACT);
        // Corner on corner: each named by a corner, never by edges crossing at it (which
        // rounding would otherwise decide).
        assert!(m.points().iter().all(|p| matches!(
            (p.id.a, p.id.b),
            (Feature::Vertex(_), Feature::Face(_)) | (Feature::Face(_), Feature::Vertex(_))
        )));
    }
    // Beside it, edge on edge: the faces overlap along a segment only (zero area): its two
    // ends.
    for dx in [2.0 * h.x, 2.0 * h.x * (1.0 - 1e-15)] {
        let pu = Pose::from_translation(DVec3::new(dx, 0.3 * h.y, h.z));
        let m = manifold(&bx, &pu, &bx, &pl).unwrap();
        assert!(finite(&m));
        assert_eq!(m.points().len(), 2, "{m:?}");
        for y in [-0.7 * h.y, h.y] {
            let c = DVec3::new(h.x, y, 0.0);
            assert!(
                m.points().iter().any(|p| p.point_a.distance(c) < EXACT),
                "{c}: {m:?}"
            );
        }
    }
    // A tetrahedron resting on a sliver face (1e-6 wide): its three corners.
    let sliver = Convex::Polyhedron(
        ConvexPolyhedron::hull(&[
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(0.1, 0.0, 0.0),
            DVec3::new(0.05, 1e-6, 0.0),
            DVec3::new(0.03, 0.03, 0.1),
        ])
        .unwrap(),
    );
    for tilt in [0.0, 1e-12] {
        let ps = Pose::new(DQuat::from_rotation_y(tilt), DVec3::ZERO);
        let m = manifold(&sliver, &ps, &fl, &pf).unwrap();
        assert!(finite(&m));
        assert!(!m.points().is_empty() && m.points().len() <= 3, "{m:?}");
        assert!(m.points().iter().all(|p| p.gap.abs() < EXACT));
    }
}

/// A random convex hull of 6–20 points, 0.2–2 across.
fn random_hull(r: &mut rand::rngs::Xoshiro256PlusPlus) -> ConvexPolyhedron {
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

/// Random convex hulls brought to a random gap in [−TOL/2, TOL] (separated or overlapping),
/// half of them face to face (a face of `b` turned against a face of `a`), checked by brute
/// force: every point lies on both surfaces (within the merging distance for a projected
/// point), its gap is `(point_b − point_a)·n` and at least minus the penetration depth (the
/// separating-axis test), the deepest gap is the pair's gap along the normal (from all
/// vertices), the normal is the brute-force closest points' direction (separated) or a
/// least-overlap axis (overlapping), ids name features holding their points and are
/// distinct, and the manifold does not depend on the warm start. Several kinds of contact
/// occur.
#[test]
fn random_hulls_against_brute_force() {
    let mut r = rng(7);
    let mut kinds = std::collections::BTreeSet::new();
    let mut counts = [0usize; MAX_POINTS + 1];
    let (mut worst_excess, mut shallow) = (0.0f64, 0);
    let kind = |f: Feature| match f {
        Feature::Vertex(_) => 'v',
        Feature::Edge(_) => 'e',
        Feature::Face(_) => 'f',
    };
    for case in 0..400 {
        let (a, b) = (random_hull(&mut r), random_hull(&mut r));
        let pa = Pose::new(random_rotation(&mut r), DVec3::ZERO);
        let mut pb = if case % 2 == 0 {
            Pose::new(random_rotation(&mut r), unit_vector(&mut r) * 4.0)
        } else {
            // Face to face: b's face g turned against a's face f, offset a little sideways.
            let f = r.random_range(0..a.face_count() as u32);
            let g = r.random_range(0..b.face_count() as u32);
            let m = pa.rotation * a.face_plane(f).normal;
            let q = DQuat::from_rotation_arc(b.face_plane(g).normal, -m);
            let spin = DQuat::from_axis_angle(m, r.random_range(0.0..6.3));
            let centre = |p: &ConvexPolyhedron, f: u32| {
                p.face_vertices(f)
                    .iter()
                    .map(|&v| p.vertex(v))
                    .sum::<DVec3>()
                    / p.face_vertices(f).len() as f64
            };
            let rot = spin * q;
            let side = unit_vector(&mut r).reject_from(m) * 0.05;
            let t = pa.transform_point(centre(&a, f)) - rot * centre(&b, g) + m * 2.0 + side;
            Pose::new(rot, t)
        };
        let c = brute::closest(&a, &pa, &b, &pb);
        let dir = (c.point_b - c.point_a).normalize();
        let gap = r.random_range(-0.5 * TOL..TOL);
        pb.translation -= dir * (c.distance - gap);
        let (ca, cb) = (Convex::Polyhedron(a.clone()), Convex::Polyhedron(b.clone()));
        let m = manifold(&ca, &pa, &cb, &pb).unwrap();
        let n = m.normal;
        // The same manifold whichever features the search starts from (the last closest
        // features of the pair, or vertex 0): names must not depend on the warm start.
        let warm = shape::convex_closest(&ca, &pa, &cb, &pb, FeaturePair::default()).features;
        for start in [warm, FeaturePair::default()] {
            let again = manifold_along(&ca, &pa, &cb, &pb, n, start, TOL)
                .unwrap()
                .unwrap();
            assert_eq!(again.features, m.features, "case {case}: from {start:?}");
            assert_eq!(again.points().len(), m.points().len());
            for (p, q) in again.points().iter().zip(m.points()) {
                assert_eq!(p.id, q.id, "case {case}: from {start:?}");
                assert!(p.point_a.distance(q.point_a) < EXACT && (p.gap - q.gap).abs() < EXACT);
            }
        }
        let sep = brute::sat_separation(&a, &pa, &b, &pb);
        let world = |p: &ConvexPolyhedron, pose: &Pose| -> Vec<f64> {
            p.vertices()
                .iter()
                .map(|&v| pose.transform_point(v).dot(n))
                .collect()
        };
        let along = world(&b, &pb).into_iter().fold(f64::INFINITY, f64::min)
            - world(&a, &pa).into_iter().fold(f64::NEG_INFINITY, f64::max);
        if sep > NORMAL_FROM_POINTS_FRACTION * TOL {
            let d = brute::closest(&a, &pa, &b, &pb);
            let want = (d.point_b - d.point_a).normalize();
            assert!(
                n.cross(want).length() < DIRECTION && n.dot(want) > 0.0,
                "case {case}: {n} vs {want}"
            );
        } else {
            assert!((along - sep).abs() < EXACT, "case {case}: {along} vs {sep}");
        }
        let on = |p: &ConvexPolyhedron, pose: &Pose, x: DVec3| {
            p.max_plane_distance(pose.inverse_transform_point(x)).abs()
        };
        let slack = POINT_MERGE_FRACTION * TOL + EXACT;
        for p in m.points() {
            assert!(on(&a, &pa, p.point_a) <= slack, "case {case}: {p:?}");
            assert!(on(&b, &pb, p.point_b) <= slack, "case {case}: {p:?}");
            assert!(((p.point_b - p.point_a).dot(n) - p.gap).abs() < EXACT);
            assert!(
                p.gap >= sep.min(0.0) - EXACT,
                "case {case}: {} < {sep}",
                p.gap
            );
            assert!(p.gap <= TOL);
        }
        assert!(
            m.min_gap() >= along - EXACT,
            "case {case}: {} < {along}",
            m.min_gap()
        );
        let excess = m.min_gap() - along;
        worst_excess = worst_excess.max(excess);
        if excess > EXACT {
            shallow += 1;
        }
        check_ids(&m, &ca, &pa, &cb, &pb, snap_of(&ca, &cb));
        kinds.insert((kind(m.features.a), kind(m.features.b)));
        counts[m.points().len()] += 1;
    }
    println!(
        "kinds {kinds:?}, point counts {counts:?}; deepest point above the pair's gap in \
         {shallow} cases, by at most {worst_excess:.2e}"
    );
    assert!(kinds.len() >= 5, "{kinds:?}");
    assert!(counts[1] > 0 && counts[3] + counts[4] > 0, "{counts:?}");
    assert!(worst_excess <= TOL);
}

/// A sphere on the floor (touching, apart, sunk; either order): the point straight below its
/// centre; against a box's edge: the edge point and the sphere's point on the line to it;
/// two spheres: the line of centres.
#[test]
fn spheres_touch_at_one_point() {
    let (fl, pf) = floor();
    let r = 0.1;
    let ball = Convex::Sphere(Sphere::new(r).unwrap());
    let top = face_along(&fl, DVec3::Z);
    for gap in [0.0, 0.5 * TOL, -0.3 * TOL] {
        let c = DVec3::new(0.2, -0.1, r + gap);
        let ps = Pose::from_translation(c);
        for ball_first in [true, false] {
            let m = if ball_first {
                manifold(&ball, &ps, &fl, &pf)
            } else {
                manifold(&fl, &pf, &ball, &ps)
            }
            .unwrap();
            assert_eq!(m.points().len(), 1);
            let p = m.points()[0];
            let (on_ball, on_floor, ids) = if ball_first {
                (p.point_a, p.point_b, (p.id.a, p.id.b))
            } else {
                (p.point_b, p.point_a, (p.id.b, p.id.a))
            };
            assert!(on_ball.distance(DVec3::new(c.x, c.y, gap)) < EXACT, "{m:?}");
            assert!(on_floor.distance(DVec3::new(c.x, c.y, 0.0)) < EXACT);
            assert!((p.gap - gap).abs() < EXACT);
            assert_eq!(ids, (Feature::Vertex(0), top));
        }
    }
    // Against the edge x = z = 0.5 of a unit cube.
    let cube = cuboid(DVec3::splat(0.5));
    let d = DVec3::new(1.0, 0.0, 1.0).normalize();
    let edge_point = DVec3::new(0.5, 0.1, 0.5);
    for gap in [0.0, 0.7 * TOL, -0.2 * TOL] {
        let ps = Pose::from_translation(edge_point + d * (r + gap));
        let m = manifold(&ball, &ps, &cube, &Pose::IDENTITY).unwrap();
        let p = m.points()[0];
        assert!((m.normal + d).length() < EXACT, "{m:?}");
        assert!(p.point_b.distance(edge_point) < EXACT, "{p:?}");
        assert!(p.point_a.distance(edge_point + d * gap) < EXACT);
        assert!((p.gap - gap).abs() < EXACT);
        assert!(matches!(m.features.b, Feature::Edge(_)));
    }
    let m = manifold(
        &ball,
        &Pose::IDENTITY,
        &Convex::Sphere(Sphere::new(0.2).unwrap()),
        &Pose::from_translation(DVec3::new(0.0, 0.3 + 0.5 * TOL, 0.0)),
    )
    .unwrap();
    let p = m.points()[0];
    assert!((p.gap - 0.5 * TOL).abs() < EXACT);
    assert!(p.point_a.distance(DVec3::new(0.0, r, 0.0)) < EXACT);
    assert!(p.point_b.distance(DVec3::new(0.0, r + 0.5 * TOL, 0.0)) < EXACT);
}

/// An ellipsoid resting on the floor, tilted: its lowest point from the closed form (body
/// frame: A²d/|Ad| for the downward direction d, A the semi-axes), the floor's straight below;
/// an ellipsoid against a sphere along its long axis: gap d − a − r.
#[test]
fn ellipsoids_touch_at_one_point() {
    let (fl, pf) = floor();
    let axes = DVec3::new(0.1, 0.03, 0.02);
    let e = Convex::Ellipsoid(Ellipsoid::new(axes).unwrap());
    for (tilt, gap) in [(0.0, 0.0), (0.4, 0.5 * TOL), (1.1, -0.4 * TOL)] {
        let q = DQuat::from_rotation_z(0.3) * DQuat::from_rotation_x(tilt);
        let d = q.inverse() * -DVec3::Z;
        let low = q * (axes * axes * d / (axes * d).length());
        let c = DVec3::new(0.1, 0.05, -low.z + gap);
        let pe = Pose::new(q, c);
        let m = manifold(&e, &pe, &fl, &pf).unwrap();
        let p = m.points()[0];
        assert_eq!(m.points().len(), 1);
        assert!(p.point_a.distance(c + low) < EXACT, "{p:?} vs {}", c + low);
        assert!(
            p.point_b
                .distance(DVec3::new(c.x + low.x, c.y + low.y, 0.0))
                < EXACT
        );
        assert!((p.gap - gap).abs() < EXACT);
    }
    let s = Convex::Sphere(Sphere::new(0.05).unwrap());
    for gap in [0.3 * TOL, -0.3 * TOL] {
        let ps = Pose::from_translation(DVec3::new(0.15 + gap, 0.0, 0.0));
        let m = manifold(&e, &Pose::IDENTITY, &s, &ps).unwrap();
        let p = m.points()[0];
        assert!((p.gap - gap).abs() < EXACT, "{p:?}");
        assert!(p.point_a.distance(DVec3::new(0.1, 0.0, 0.0)) < EXACT);
        assert!(p.point_b.distance(DVec3::new(0.1 + gap, 0.0, 0.0)) < EXACT);
    }
}

/// An L-shaped compound of two bars lying on the floor: one manifold per bar, each its four
/// bottom corners; raised on one end beyond the tolerance, only the other bar's.
#[test]
fn a_compound_has_a_manifold_per_touching_piece() {
    let (fl, pf) = floor();
    let floor_shape = Shape::compound(vec![(pf, fl)]).unwrap();
    let bar = |h: DVec3| cuboid(h);
    let l = Shape::compound(vec![
        (Pose::IDENTITY, bar(DVec3::new(0.2, 0.02, 0.02))),
        (
            Pose::from_translation(DVec3::new(-0.18, 0.12, 0.0)),
            bar(DVec3::new(0.02, 0.1, 0.02)),
        ),
    ])
    .unwrap();
    let mut cache = ManifoldCache::default();
    let pl = Pose::from_translation(DVec3::new(0.0, 0.0, 0.02));
    let ms = shape_manifolds(&l, &pl, &floor_shape, &Pose::IDENTITY, TOL, &mut cache).unwrap();
    assert_eq!(ms.len(), 2);
    assert_eq!((ms[0].pieces, ms[1].pieces), ((0, 0), (1, 0)));
    for m in &ms {
        assert_eq!(m.points().len(), 4);
        assert!(
            m.points()
                .iter()
                .all(|p| p.gap.abs() < EXACT && p.point_a.z.abs() < EXACT)
        );
    }
    // Tilted about the long bar's far end: the upright bar lifts off.
    let q = DQuat::from_rotation_y(0.01);
    let pivot = DVec3::new(0.2, 0.0, 0.0);
    let pt = Pose::new(q, pivot - q * (pivot - DVec3::new(0.0, 0.0, 0.02)));
    let ms = shape_manifolds(&l, &pt, &floor_shape, &Pose::IDENTITY, TOL, &mut cache).unwrap();
    assert_eq!(ms.len(), 1, "{ms:?}");
    assert_eq!(ms[0].pieces, (0, 0));
    assert_eq!(ms[0].points().len(), 2);
}

/// Coherence: a box lying on the floor, a 45°-turned block offset on another (points where
/// edges cross), and a box on its low edge each slide and turn a little between two steps:
/// every new point keeps its old id, is matched to the old point by it, and that old point is
/// the same material point of the moving body (carried by the motion to within 1e-12).
#[test]
fn sliding_and_turning_keeps_the_ids() {
    let (fl, pf) = floor();
    let bx = cuboid(DVec3::new(0.1, 0.05, 0.02));
    let block = cuboid(DVec3::new(0.05, 0.05, 0.025));
    let pl = Pose::from_translation(DVec3::new(0.0, 0.0, -0.025));
    let cases = [
        (
            &bx,
            Pose::new(DQuat::from_rotation_z(0.3), DVec3::new(0.1, 0.0, 0.02)),
            &fl,
            pf,
            4,
        ),
        (
            &block,
            Pose::new(
                DQuat::from_rotation_z(std::f64::consts::FRAC_PI_4),
                DVec3::new(0.03, 0.01, 0.025),
            ),
            &block,
            pl,
            4,
        ),
        (
            &bx,
            Pose::new(
                DQuat::from_rotation_x(0.2),
                DVec3::new(0.0, 0.0, 0.05 * 0.2f64.sin() + 0.02 * 0.2f64.cos()),
            ),
            &fl,
            pf,
            2,
        ),
    ];
    for (k, (a, p0, b, pb, count)) in cases.into_iter().enumerate() {
        let step = Pose::new(DQuat::from_rotation_z(0.01), DVec3::new(1e-3, -5e-4, 0.0));
        // The motion turns about the body's own vertical through its centre.
        let p1 = Pose::new(
            step.rotation * p0.rotation,
            p0.translation + step.translation,
        );
        let m0 = manifold(a, &p0, b, &pb).unwrap();
        let m1 = manifold(a, &p1, b, &pb).unwrap();
        assert_eq!(m0.points().len(), count, "case {k}: {m0:?}");
        assert_eq!(m1.points().len(), count, "case {k}: {m1:?}");
        let matched = match_points(&m0, &m1, TOL);
        for (i, p) in m1.points().iter().enumerate() {
            let j = matched[i].unwrap_or_else(|| panic!("case {k}: point {i} unmatched"));
            let old = m0.points()[j];
            assert_eq!(old.id, p.id, "case {k}");
            if let Feature::Vertex(_) = p.id.a {
                let carried = p1.transform_point(p0.inverse_transform_point(old.point_a));
                assert!(
                    carried.distance(p.point_a) < EXACT,
                    "case {k}: {carried} vs {p:?}"
                );
            }
        }
    }
}

/// Bad input is refused with a typed error, never a panic or NaN.
#[test]
fn bad_input_is_refused() {
    let (fl, pf) = floor();
    let bx = cuboid(DVec3::splat(0.05));
    let pb = Pose::from_translation(DVec3::new(0.0, 0.0, 0.05));
    let c = shape::convex_closest(&bx, &pb, &fl, &pf, FeaturePair::default());
    for t in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(matches!(
            convex_manifold(&bx, &pb, &fl, &pf, &c, t),
            Err(ManifoldError::Tolerance(_))
        ));
    }
    let bad = Pose::from_translation(DVec3::new(f64::NAN, 0.0, 0.0));
    assert_eq!(
        convex_manifold(&bx, &bad, &fl, &pf, &c, TOL),
        Err(ManifoldError::NonFinitePose)
    );
    for n in [DVec3::ZERO, DVec3::NAN] {
        assert!(matches!(
            manifold_along(&bx, &pb, &fl, &pf, n, FeaturePair::default(), TOL),
            Err(ManifoldError::Normal(_))
        ));
    }
    // A normal that makes no sense for the pair (sideways) still gives finite points on both
    // bodies, or none.
    let m = manifold_along(&bx, &pb, &fl, &pf, DVec3::X, FeaturePair::default(), TOL).unwrap();
    assert!(m.is_none_or(|m| {
        m.points()
            .iter()
            .all(|p| p.point_a.is_finite() && p.gap.is_finite())
    }));
}

/// Arbitrary input: random hulls and boxes, far from the origin or not, at random poses close
/// together, with random normals (most inconsistent with the pair) and random tolerances:
/// never a panic, a NaN, more than four points, or a point beyond the tolerance; every point
/// on both surfaces (within the merging distance).
#[test]
fn arbitrary_normals_never_panic_or_give_nan() {
    let mut r = rng(99);
    let (mut some, mut worst) = (0, 0.0f64);
    for case in 0..2_000 {
        let a = random_hull(&mut r);
        let b = if case % 3 == 0 {
            primitives::cuboid(DVec3::new(0.3, 0.2, 1e-3)).unwrap()
        } else {
            random_hull(&mut r)
        };
        let far = if case % 5 == 0 { 1e6 } else { 0.0 };
        let origin = unit_vector(&mut r) * far;
        let pa = Pose::new(random_rotation(&mut r), origin);
        let pb = Pose::new(
            random_rotation(&mut r),
            origin + unit_vector(&mut r) * r.random_range(0.0..1.5),
        );
        let n = match case % 4 {
            0 => DVec3::new(1e-300, 0.0, 0.0),
            _ => unit_vector(&mut r),
        };
        let tol = 10f64.powf(r.random_range(-8.0..-1.0));
        let (ca, cb) = (Convex::Polyhedron(a.clone()), Convex::Polyhedron(b.clone()));
        let got = manifold_along(&ca, &pa, &cb, &pb, n, FeaturePair::default(), tol);
        let Ok(Some(m)) = got else {
            assert!(
                matches!(got, Ok(None) | Err(ManifoldError::Normal(_))),
                "{got:?}"
            );
            continue;
        };
        some += 1;
        assert!(m.normal.is_finite() && (m.normal.length() - 1.0).abs() < EXACT);
        assert!(!m.points().is_empty() && m.points().len() <= MAX_POINTS);
        let slack = (POINT_MERGE_FRACTION * tol)
            .max(a.tolerance())
            .max(b.tolerance())
            + f64::EPSILON * far;
        for p in m.points() {
            assert!(p.point_a.is_finite() && p.point_b.is_finite() && p.gap <= tol);
            let on = |q: &ConvexPolyhedron, pose: &Pose, x: DVec3| {
                q.max_plane_distance(pose.inverse_transform_point(x)).abs()
            };
            worst = worst.max(on(&a, &pa, p.point_a) / slack);
            worst = worst.max(on(&b, &pb, p.point_b) / slack);
        }
    }
    println!("{some} manifolds; points off their surfaces by at most {worst:.3} merging distances");
    assert!(worst <= 1.0, "{worst}");
    assert!(some > 200, "{some}");
}
