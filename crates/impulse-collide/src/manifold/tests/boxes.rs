//! Boxes and blocks: face on face, turned and offset, tilted onto an edge, balanced on an
//! edge or a vertex, edges cut, crossed and parallel, degenerate contacts, coherence.

use super::*;

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
        reduce::reduce(&mut reduced, n, snap);
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
