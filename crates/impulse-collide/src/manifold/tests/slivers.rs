//! Slivers: hulls far longer than they are thin, resting on a floor with a tolerance that is a
//! fraction of their length (as a pose study scales ε_c to a part's diameter).

use super::*;

/// The part a fuzzer made from the bundled pebble (`fuzz/corpus/part/`, the tall slivers): a
/// 1.8 km apex over a base triangle 10 m long and 2.5 cm wide.
const FUZZED_SLIVER: [[f64; 3]; 5] = [
    [1.004211, 0.000232, 1844.0],
    [0.006581, 0.006272, 5.000198],
    [-0.001344, 0.01806, 0.005759],
    [-10.003966, 0.006896, 0.000993],
    [-1.003135, -0.007572, 0.001134],
];

/// The contact feature a manifold starts from holds the supporting vertex: a face or an edge
/// whose vertices all lie within the tolerance of the support plane but that leaves out the
/// deepest vertex would leave it out of the manifold. 300 placements of the fuzzed sliver and
/// 300 of random slivers (5–8 points, one axis 10³–10⁵ times the others), each turned at
/// random and lowered so that its deepest vertex lies up to half the tolerance (10⁻³ of its
/// diameter) into a floor: the manifold along the floor's normal exists and its deepest gap
/// is the deepest vertex's height, by brute force over the vertices. Before the feature had
/// to hold the supporting vertex, the fuzzed sliver lying on its side kept a face of three
/// vertices while the fourth sank 0.87 m (0.47 of the tolerance) below the floor.
#[test]
fn a_slivers_manifold_holds_its_deepest_vertex() {
    let mut r = rng(23);
    let (mut below, mut checked) = (0, 0);
    for case in 0..600 {
        let hull = if case < 300 {
            ConvexPolyhedron::hull(&FUZZED_SLIVER.map(DVec3::from_array)).unwrap()
        } else {
            let long = 10f64.powf(r.random_range(3.0..5.0));
            let count = r.random_range(5..=8);
            let pts: Vec<DVec3> = (0..count)
                .map(|_| {
                    DVec3::new(
                        r.random_range(-1.0..1.0),
                        r.random_range(-1.0..1.0),
                        r.random_range(-1.0..1.0) * long,
                    )
                })
                .collect();
            match ConvexPolyhedron::hull(&pts) {
                Ok(h) => h,
                Err(_) => continue,
            }
        };
        let vertices: Vec<DVec3> = hull.vertices().to_vec();
        let diameter = vertices
            .iter()
            .flat_map(|a| vertices.iter().map(move |b| a.distance(*b)))
            .fold(0.0, f64::max);
        let tolerance = 1e-3 * diameter;
        // Lying near its side half the time (the long axis nearly level), else any way.
        let rotation = if case % 2 == 0 {
            DQuat::from_rotation_arc(
                DVec3::Z,
                (unit_vector(&mut r) * DVec3::new(1.0, 1.0, 1e-3)).normalize(),
            )
        } else {
            random_rotation(&mut r)
        };
        let lowest = vertices
            .iter()
            .map(|v| (rotation * *v).z)
            .fold(f64::INFINITY, f64::min);
        let depth = r.random_range(0.0..0.5) * tolerance;
        let pose = Pose::new(rotation, DVec3::new(0.0, 0.0, -lowest - depth));
        let deepest = vertices
            .iter()
            .map(|v| pose.transform_point(*v).z)
            .fold(f64::INFINITY, f64::min);
        let floor = cuboid(DVec3::splat(1e6));
        let floor_pose = Pose::from_translation(DVec3::new(0.0, 0.0, -1e6));
        let a = Convex::Polyhedron(hull);
        let m = manifold_along(
            &a,
            &pose,
            &floor,
            &floor_pose,
            -DVec3::Z,
            FeaturePair::default(),
            tolerance,
        )
        .unwrap()
        .unwrap_or_else(|| panic!("case {case}: no manifold"));
        let scale = 1e-9 * diameter;
        assert!(
            (m.min_gap() - deepest).abs() <= scale,
            "case {case}: the manifold's deepest gap {} against the deepest vertex's {deepest} \
             (tolerance {tolerance})",
            m.min_gap()
        );
        below += usize::from(deepest < 0.0);
        checked += 1;
    }
    assert!(
        checked > 500 && below > 400,
        "{checked} checked, {below} below the floor"
    );
}
