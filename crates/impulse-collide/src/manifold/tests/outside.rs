//! What a manifold leaves out ([`convex_outside`]), against closed forms: a box tipped on its
//! edge (the clearance is the height of its far edge), a 16-gon coin lying flat (four corners
//! held, the other twelve outside points at the same gap), an edge overhanging a face and
//! two faces overlapping in part (the crossing points stand for the corners off the other).

use super::*;

/// A box of half extents (a, b, c) standing on the floor at `gap`, turned by `theta` about the
/// y axis through its +x bottom edge.
fn tipped_box(a: f64, b: f64, c: f64, theta: f64, gap: f64) -> (Convex, Pose) {
    let q = DQuat::from_rotation_y(theta);
    // The pivot edge (x = a, z = −c in the box frame) is at (a, 0, gap) in the world.
    let pivot = DVec3::new(a, 0.0, -c);
    let centre = DVec3::new(a, 0.0, gap) - q * pivot;
    (cuboid(DVec3::new(a, b, c)), Pose::new(q, centre))
}

/// The clearance `o` reports is `expected` (a closed form) to [`EXACT`].
fn assert_clearance(o: &Outside, expected: f64, what: &str) {
    assert!(
        (o.clearance - expected).abs() < EXACT,
        "{what}: clearance {} against {expected}",
        o.clearance
    );
}

/// A box tipped by θ on its edge: the manifold holds the edge's two ends; nothing else is
/// within the tolerance, and the clearance is the height of the far bottom edge,
/// gap + 2a·sin θ (the floor's own vertices are all farther).
#[test]
fn a_tipped_box_is_cleared_by_the_height_of_its_far_edge() {
    let (fl, pf) = floor();
    let (a, gap) = (0.01, 0.3 * TOL);
    for theta in [0.05_f64, 0.2, 0.6] {
        let (bx, pb) = tipped_box(a, 0.03, 0.05, theta, gap);
        let m = manifold(&bx, &pb, &fl, &pf).expect("touching");
        assert_eq!(m.points().len(), 2, "θ {theta}: the edge's ends");
        let o = convex_outside(&bx, &pb, &fl, &pf, &m, TOL);
        assert!(o.points.is_empty(), "θ {theta}: {:?}", o.points);
        let expected = gap + 2.0 * a * theta.sin();
        assert_clearance(&o, expected, &format!("θ {theta}"));
    }
}

/// With a tolerance beyond the far edge's height, that edge's ends lie over the floor's face
/// within it: the face is then the contact feature and all four corners are the manifold's
/// (nothing outside); asked of the edge manifold taken at the small tolerance, the far
/// edge's ends are outside points at their heights.
#[test]
fn vertices_within_the_tolerance_over_the_face_are_outside_points() {
    let (fl, pf) = floor();
    let (a, theta, gap) = (0.01, 0.01_f64, 0.2 * TOL);
    let (bx, pb) = tipped_box(a, 0.03, 0.05, theta, gap);
    let m = manifold(&bx, &pb, &fl, &pf).expect("touching");
    let far = gap + 2.0 * a * theta.sin();
    assert!(far > TOL, "the far edge is beyond the manifold's tolerance");
    let o = convex_outside(&bx, &pb, &fl, &pf, &m, 2.0 * far);
    assert_eq!(o.points.len(), 2, "{:?}", o.points);
    for p in &o.points {
        assert!((p.gap - far).abs() < EXACT, "gap {} against {far}", p.gap);
        assert!(
            (p.point_b.z).abs() < EXACT,
            "on the floor's plane: {}",
            p.point_b
        );
        assert!(matches!(p.id.a, Feature::Vertex(_)) && matches!(p.id.b, Feature::Face(_)));
    }
}

/// A 16-gon coin lying flat: the manifold keeps four of its sixteen bottom corners; the
/// other twelve are outside points, each at the coin's gap (a closed form: the face is
/// parallel to the floor).
#[test]
fn a_flat_coin_leaves_twelve_corners_to_the_outside_points() {
    let (fl, pf) = floor();
    let (r, h, gap) = (0.012, 0.000875, 0.3 * TOL);
    let coin = Convex::Polyhedron(impulse_geom::primitives::regular_prism(16, r, h).unwrap());
    let pc = Pose::from_translation(DVec3::new(0.1, -0.2, h + gap));
    let m = manifold(&coin, &pc, &fl, &pf).expect("touching");
    assert_eq!(m.points().len(), MAX_POINTS);
    let o = convex_outside(&coin, &pc, &fl, &pf, &m, TOL);
    assert_eq!(o.points.len(), 12, "{:?}", o.points);
    for p in &o.points {
        assert!((p.gap - gap).abs() < EXACT, "gap {}", p.gap);
    }
    // Every bottom corner is either a manifold point or an outside point, once.
    let mut corners: Vec<u32> = m
        .points()
        .iter()
        .chain(&o.points)
        .map(|p| match p.id.a {
            Feature::Vertex(v) => v,
            other => panic!("a corner point, not {other:?}"),
        })
        .collect();
    corners.sort_unstable();
    corners.dedup();
    assert_eq!(corners.len(), 16);
    // The top corners are the clearance: 2h above the floor, plus the gap.
    assert_clearance(&o, 2.0 * h + gap, "coin");
}

/// A bar lying across a narrower block on one of its edges (the bar turned 45° about its
/// long axis), overhanging each side by 1 mm: clipping cuts the bar's edge at the block's side
/// planes, and the edge's ends beyond them (1 mm beside the block) are not counted: the
/// crossing points stand for them. The nearest counted vertices are the ends of the bar's
/// two side edges, h·√2 + gap above the block's top, nearer than the block's top corners,
/// (w + z_c)/√2 − h from the bar's lower faces.
#[test]
fn an_overhanging_edge_is_stood_for_by_its_clipped_points() {
    let w = 0.02;
    let block = cuboid(DVec3::new(w, w, w));
    let pblock = Pose::from_translation(DVec3::new(0.0, 0.0, -w));
    let half = 0.005;
    let q = DQuat::from_rotation_x(std::f64::consts::FRAC_PI_4);
    let gap = 0.3 * TOL;
    let zc = half * 2f64.sqrt() + gap;
    let bar = cuboid(DVec3::new(w + 0.001, half, half));
    let pbar = Pose::new(q, DVec3::new(0.0, 0.0, zc));
    let m = manifold(&bar, &pbar, &block, &pblock).expect("touching");
    assert_eq!(m.points().len(), 2);
    assert!(
        m.points()
            .iter()
            .all(|p| matches!(p.id.a, Feature::Edge(_)))
    );
    let o = convex_outside(&bar, &pbar, &block, &pblock, &m, TOL);
    assert!(o.points.is_empty());
    let expected = (half * 2f64.sqrt() + gap).min((w + zc) / 2f64.sqrt() - half);
    assert_clearance(&o, expected, "bar");
}

/// A small cube standing on a big one, face on face: the manifold is the overlap of the two
/// faces, whose crossing points stand for the corners of either face off the other (the big
/// one's top corners, 5 mm beside the small cube when it stands near a corner), so the
/// clearance is the small cube's top face, 2s + gap up, wherever it stands on the big one.
#[test]
fn face_on_face_the_corners_off_the_overlap_are_stood_for() {
    let big = cuboid(DVec3::new(0.05, 0.05, 0.05));
    let pbig = Pose::from_translation(DVec3::new(0.0, 0.0, -0.05));
    let s = 0.01;
    let small = cuboid(DVec3::new(s, s, s));
    let gap = 0.3 * TOL;
    // Standing near a corner, in the middle, and overhanging the big one's +x side.
    for (x, y) in [(0.035, 0.035), (0.0, 0.0), (0.055, -0.02)] {
        let psmall = Pose::from_translation(DVec3::new(x, y, s + gap));
        let m = manifold(&big, &pbig, &small, &psmall).expect("touching");
        let o = convex_outside(&big, &pbig, &small, &psmall, &m, TOL);
        assert!(o.points.is_empty(), "at ({x}, {y}): {:?}", o.points);
        let expected = 2.0 * s + gap;
        assert_clearance(&o, expected, &format!("at ({x}, {y})"));
    }
}
