//! Random convex hulls against brute force, arbitrary input, and refused input.

use super::*;

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
