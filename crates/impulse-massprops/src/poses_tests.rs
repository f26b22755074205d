use std::f64::consts::PI;

use glam::{DQuat, DVec3};
use impulse_geom::ConvexPolyhedron;
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

use super::*;

fn cuboid(x: f64, y: f64, z: f64) -> ConvexPolyhedron {
    let h = DVec3::new(x, y, z) / 2.0;
    let pts: Vec<DVec3> = (0..8)
        .map(|i| {
            DVec3::new(
                if i & 1 == 0 { -h.x } else { h.x },
                if i & 2 == 0 { -h.y } else { h.y },
                if i & 4 == 0 { -h.z } else { h.z },
            )
        })
        .collect();
    ConvexPolyhedron::hull(&pts).unwrap()
}

/// Solid angle of a centred a × b rectangle at distance d (a closed form independent of
/// eq. 7.1's angle sum): Ω = 4·asin(ab / √((a² + 4d²)(b² + 4d²))).
fn rectangle_solid_angle(a: f64, b: f64, d: f64) -> f64 {
    4.0 * (a * b / ((a * a + 4.0 * d * d) * (b * b + 4.0 * d * d)).sqrt()).asin()
}

/// Solid angle of a convex polygon seen from `eye`, over 4π, by the spherical excess
/// Σβ_k − (n − 2)π of its corner angles: a second formula, independent of the library's
/// (Van Oosterom and Strackee's, over a fan of triangles). Well conditioned only for polygons
/// seen large and face-on, as those of the random hulls are.
fn excess_solid_angle(corners: &[DVec3], eye: DVec3) -> f64 {
    let n = corners.len();
    let dirs: Vec<DVec3> = corners.iter().map(|&c| (c - eye).normalize()).collect();
    let mut excess = -((n as f64) - 2.0) * PI;
    for k in 0..n {
        let a = dirs[k];
        let prev = dirs[(k + n - 1) % n];
        let next = dirs[(k + 1) % n];
        let t1 = prev - prev.dot(a) * a;
        let t2 = next - next.dot(a) * a;
        excess += t1.cross(t2).length().atan2(t1.dot(t2));
    }
    excess / (4.0 * PI)
}

/// V22's reference, and any box: a box's facet probabilities are its rectangles' solid
/// angles (closed form), every facet is stable, and the pairs of the 1 × 2 × 3 box give the
/// thesis's 64.50 %, 24.27 %, 11.23 %.
#[test]
fn a_box_lands_on_each_face_by_its_solid_angle() {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(22);
    for case in 0..200 {
        let s = if case == 0 {
            DVec3::new(1.0, 2.0, 3.0)
        } else {
            DVec3::new(
                rng.random_range(0.1..3.0),
                rng.random_range(0.1..3.0),
                rng.random_range(0.1..3.0),
            )
        };
        let hull = cuboid(s.x, s.y, s.z);
        let a = PoseAnalysis::new(&hull, DVec3::ZERO).unwrap();
        let q = a.quasi_static();
        assert!((q.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        for f in a.facets() {
            assert!(f.stable, "case {case}: a box rests on every face");
            let axis = f.normal.abs().max_position();
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let want = rectangle_solid_angle(s[u], s[v], s[axis] / 2.0) / (4.0 * PI);
            assert!(
                (f.solid_angle - want).abs() < 1e-13,
                "case {case}: {} against {want}",
                f.solid_angle
            );
            assert!((q[f.face as usize] - want).abs() < 1e-13);
        }
        if case == 0 {
            let pair = |axis: usize| {
                a.facets()
                    .iter()
                    .filter(|f| f.normal.abs().max_position() == axis)
                    .map(|f| q[f.face as usize])
                    .sum::<f64>()
            };
            // The 2 × 3 faces are normal to x, the 1 × 3 to y, the 1 × 2 to z.
            for (axis, thesis) in [(0, 0.6450), (1, 0.2427), (2, 0.1123)] {
                assert!(
                    (pair(axis) - thesis).abs() < 5e-5,
                    "pair {axis}: {}",
                    pair(axis)
                );
            }
        }
    }
}

/// A random convex hull with its centre of mass somewhere inside (a random convex
/// combination of its vertices, so also off-centre).
fn random_part(rng: &mut Xoshiro256PlusPlus) -> (ConvexPolyhedron, DVec3) {
    loop {
        let n = rng.random_range(4..40);
        let stretch = DVec3::new(
            rng.random_range(0.2..2.0),
            rng.random_range(0.2..2.0),
            rng.random_range(0.2..2.0),
        );
        let pts: Vec<DVec3> = (0..n)
            .map(|_| {
                DVec3::new(
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                ) * stretch
            })
            .collect();
        let Ok(hull) = ConvexPolyhedron::hull(&pts) else {
            continue;
        };
        let mut w: Vec<f64> = (0..hull.vertices().len())
            .map(|_| rng.random_range(0.0..1.0_f64).powi(3))
            .collect();
        let total: f64 = w.iter().sum();
        w.iter_mut().for_each(|x| *x /= total);
        let com = hull
            .vertices()
            .iter()
            .zip(&w)
            .map(|(&v, &x)| v * x)
            .sum::<DVec3>();
        // Keep the centre of mass clearly inside: refuse hulls it nearly touches.
        if hull
            .planes()
            .iter()
            .all(|p| p.offset - p.normal.dot(com) > 1e-3)
        {
            return (hull, com);
        }
    }
}

/// Brute force: a point of the facet's plane is inside the facet when the facet's area
/// equals the sum of the triangles from the point to its edges (a test by areas, not by edge
/// lines).
fn inside_by_areas(corners: &[DVec3], p: DVec3) -> bool {
    let n = corners.len();
    let area = |a: DVec3, b: DVec3, c: DVec3| 0.5 * (b - a).cross(c - a).length();
    let facet: f64 = (1..n - 1)
        .map(|k| area(corners[0], corners[k], corners[k + 1]))
        .sum();
    let fan: f64 = (0..n)
        .map(|k| area(p, corners[k], corners[(k + 1) % n]))
        .sum();
    fan <= facet * (1.0 + 1e-9)
}

/// On 1000 random hulls with random centres of mass: the stable set agrees with the
/// brute-force projection test (validation V23's clause), the solid angles agree with the
/// spherical excess of their corner angles and cover the sphere (sum 1), each tip lowers the centre of
/// mass and ends on a stable facet, and the quasi-static shares sum to 1.
#[test]
fn stable_poses_of_random_hulls_agree_with_brute_force() {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(23);
    let mut stable_seen = 0;
    let mut unstable_seen = 0;
    for case in 0..1000 {
        let (hull, com) = random_part(&mut rng);
        let a = PoseAnalysis::new(&hull, com).unwrap();
        let mut total = 0.0;
        for f in a.facets() {
            let c = a.corners(f.face);
            let reference = excess_solid_angle(c, com);
            assert!(
                (f.solid_angle - reference).abs() < 1e-12,
                "case {case} face {}",
                f.face
            );
            total += f.solid_angle;
            let foot = com + f.height * f.normal;
            let brute = inside_by_areas(c, foot);
            // Projections within rounding of an edge may go either way.
            if f.margin.abs() > 1e-9 {
                assert_eq!(
                    f.stable, brute,
                    "case {case} face {}: margin {}",
                    f.face, f.margin
                );
            }
            if f.stable {
                stable_seen += 1;
                assert_eq!(f.rests_on, f.face);
            } else {
                unstable_seen += 1;
                let next = &a.facets()[f.tips_to.unwrap() as usize];
                assert!(
                    next.height < f.height,
                    "case {case}: tipping must lower the centre of mass"
                );
                assert!(a.facets()[f.rests_on as usize].stable);
            }
        }
        assert!(
            (total - 1.0).abs() < 1e-11,
            "case {case}: solid angles sum to {total}"
        );
        assert!((a.quasi_static().iter().sum::<f64>() - 1.0).abs() < 1e-11);
        // The lowest facet is always stable.
        let lowest = a
            .facets()
            .iter()
            .min_by(|x, y| x.height.total_cmp(&y.height))
            .unwrap();
        assert!(lowest.stable, "case {case}");
    }
    assert!(
        stable_seen > 1000 && unstable_seen > 1000,
        "{stable_seen} / {unstable_seen}"
    );
}

/// The perturbed estimate's disk fractions against a brute-force count of grid points of
/// the disk beyond each edge (attributed to the edge their ray from the centre crosses), on
/// random hulls; the shares still sum to 1 and a zero cone gives the quasi-static estimate.
#[test]
fn perturbed_estimate_moves_the_disk_beyond_each_edge() {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(24);
    for case in 0..60 {
        let (hull, com) = random_part(&mut rng);
        let a = PoseAnalysis::new(&hull, com).unwrap();
        assert_eq!(a.perturbed_quasi_static(0.0).unwrap(), a.quasi_static());
        let alpha = rng.random_range(0.05..1.2);
        let p = a.perturbed_quasi_static(alpha).unwrap();
        assert!((p.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        assert!(p.iter().all(|&x| x >= -1e-15));
        for f in a.facets().iter().filter(|f| f.stable) {
            let c = a.corners(f.face);
            let foot = com + f.height * f.normal;
            let radius = f.height * alpha.tan();
            let exact = disk_beyond_edges(c, f.normal, foot, radius);
            // Brute force on a polar-area-uniform grid of the disk.
            let (u, v) = {
                let u = (c[1] - c[0]).normalize();
                (u, f.normal.cross(u))
            };
            let mut count = vec![0usize; c.len()];
            let (nr, nt) = (400, 720);
            for i in 0..nr {
                let r = radius * ((i as f64 + 0.5) / nr as f64).sqrt();
                for j in 0..nt {
                    let t = 2.0 * PI * (j as f64 + 0.5) / nt as f64;
                    let q = foot + r * (t.cos() * u + t.sin() * v);
                    for (k, hits) in count.iter_mut().enumerate() {
                        let (out, d) = edge_line(c, f.normal, k, foot);
                        // Beyond edge k's line, and the ray crosses that line before any other.
                        let along = (q - foot).dot(out);
                        if along > d {
                            let first = (0..c.len()).all(|m| {
                                let (o2, d2) = edge_line(c, f.normal, m, foot);
                                let a2 = (q - foot).dot(o2);
                                a2 <= 0.0 || d / along <= d2 / a2 + 1e-15
                            });
                            if first {
                                *hits += 1;
                            }
                        }
                    }
                }
            }
            for k in 0..c.len() {
                let brute = count[k] as f64 / (nr * nt) as f64;
                assert!(
                    (exact[k] - brute).abs() < 4e-3,
                    "case {case} face {} edge {k}: {} against {brute}",
                    f.face,
                    exact[k]
                );
            }
        }
    }
}

/// The 1 × 2 × 3 box with a 20° cone: standing on a 1 × 2 end (height 1.5), the disk of
/// radius 1.5·tan 20° = 0.546 reaches past both long edges (0.5 away) and not the short ones
/// (1.0 away): each long edge takes the circular segment ρ²·acos(d/ρ) − d·√(ρ² − d²) of the
/// disk, handed to the 2 × 3 face across it; the other faces' disks reach no edge.
#[test]
fn perturbed_estimate_of_the_thesis_box_is_the_circular_segment() {
    let hull = cuboid(1.0, 2.0, 3.0);
    let a = PoseAnalysis::new(&hull, DVec3::ZERO).unwrap();
    let alpha = 20f64.to_radians();
    let q = a.quasi_static();
    let p = a.perturbed_quasi_static(alpha).unwrap();
    let rho = 1.5 * alpha.tan();
    let d: f64 = 0.5;
    let segment =
        (rho * rho * (d / rho).acos() - d * (rho * rho - d * d).sqrt()) / (PI * rho * rho);
    for f in a.facets() {
        let i = f.face as usize;
        match f.normal.abs().max_position() {
            2 => assert!(
                (p[i] - q[i] * (1.0 - 2.0 * segment)).abs() < 1e-14,
                "end face"
            ),
            // Each 2 × 3 face gets one segment from each end face.
            0 => assert!(
                (p[i] - (q[i] + segment * q_end(&a, &q))).abs() < 1e-14,
                "big face"
            ),
            _ => assert!((p[i] - q[i]).abs() < 1e-15, "side face unchanged"),
        }
    }
    fn q_end(a: &PoseAnalysis, q: &[f64]) -> f64 {
        a.facets()
            .iter()
            .filter(|f| f.normal.abs().max_position() == 2)
            .map(|f| q[f.face as usize])
            .sum()
    }
}

/// A part turned slightly off one of its facets is classified by that facet, within the
/// given angle and not beyond it.
#[test]
fn facet_facing_finds_the_facet_under_a_turned_part() {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(25);
    for _ in 0..200 {
        let (hull, com) = random_part(&mut rng);
        let a = PoseAnalysis::new(&hull, com).unwrap();
        let f = &a.facets()[rng.random_range(0..a.facets().len())];
        let turn = DQuat::from_axis_angle(
            f.normal.any_orthonormal_vector(),
            rng.random_range(-1e-3..1e-3),
        );
        let down = turn * f.normal;
        assert_eq!(a.facet_facing(down, 2e-3), Some(f.face));
        assert_eq!(
            a.facet_facing(turn * turn * turn * f.normal, 1e-6)
                .is_none(),
            down.angle_between(f.normal) * 3.0 > 1e-6
        );
    }
}

/// Bad input: a centre of mass outside the hull or on its boundary, a non-finite one, and a
/// cone of 90° or more are refused with errors that say so.
#[test]
fn bad_input_is_refused() {
    let hull = cuboid(1.0, 2.0, 3.0);
    let e = PoseAnalysis::new(&hull, DVec3::new(0.6, 0.0, 0.0)).unwrap_err();
    assert!(
        e.to_string().contains("not inside the part's convex hull"),
        "{e}"
    );
    assert!(PoseAnalysis::new(&hull, DVec3::new(0.5, 0.0, 0.0)).is_err());
    assert!(PoseAnalysis::new(&hull, DVec3::new(f64::NAN, 0.0, 0.0)).is_err());
    let a = PoseAnalysis::new(&hull, DVec3::ZERO).unwrap();
    assert!(a.perturbed_quasi_static(PI / 2.0).is_err());
    assert!(a.perturbed_quasi_static(-0.1).is_err());
    assert!(a.perturbed_quasi_static(f64::NAN).is_err());
}

/// Pose classes: a cube's six faces are one class, the 1 × 2 × 3 box's are three pairs, a
/// regular prism's sides are one class and its ends another, and a random hull (no
/// symmetry) has one facet per class.
#[test]
fn symmetric_facets_form_one_class() {
    let classes = |hull: &ConvexPolyhedron| {
        let mut c: Vec<usize> = PoseAnalysis::new(hull, DVec3::ZERO)
            .unwrap()
            .classes()
            .iter()
            .map(Vec::len)
            .collect();
        c.sort_unstable();
        c
    };
    assert_eq!(classes(&cuboid(2.0, 2.0, 2.0)), vec![6]);
    assert_eq!(classes(&cuboid(1.0, 2.0, 3.0)), vec![2, 2, 2]);
    let prism: Vec<DVec3> = (0..12)
        .flat_map(|k| {
            let a = 2.0 * PI * k as f64 / 12.0;
            [
                DVec3::new(a.cos(), a.sin(), 0.4),
                DVec3::new(a.cos(), a.sin(), -0.4),
            ]
        })
        .collect();
    assert_eq!(
        classes(&ConvexPolyhedron::hull(&prism).unwrap()),
        vec![2, 12]
    );
    // Off-centre centre of mass: the prism's ends differ (heights 0.3 and 0.5).
    let a = PoseAnalysis::new(
        &ConvexPolyhedron::hull(&prism).unwrap(),
        DVec3::new(0.0, 0.0, 0.1),
    )
    .unwrap();
    assert_eq!(a.classes().len(), 3);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(26);
    for _ in 0..50 {
        let (hull, com) = random_part(&mut rng);
        let a = PoseAnalysis::new(&hull, com).unwrap();
        assert!(a.classes().iter().all(|c| c.len() == 1));
        assert_eq!(
            a.classes().iter().map(Vec::len).sum::<usize>(),
            a.stable().len()
        );
    }
}

/// A hull of nine points, one of them on a 1.8 km spike from a 1 cm pebble (the part fuzz
/// target's finding): its facets seen edge-on or tiny from the centre of mass made the
/// spherical excess of their corner angles lose every digit, and the quasi-static shares
/// summed to 0.99987. The solid angles about any interior point cover the sphere exactly, so
/// the reference is 1.
#[test]
fn the_shares_of_a_spiked_hull_sum_to_one() {
    let points = [
        [0.00421, 0.0, 0.000194],
        [-0.001344, 0.001806, 0.005759],
        [-0.003967, 0.006896, 0.001978],
        [-0.11, 0.000232, 18442.0],
        [0.006581, 0.0, 0.000493],
        [-0.001344, 0.001806, 0.005759],
        [-0.003967, 0.06, 0.005759],
        [-0.003967, 0.006896, 0.001987],
        [-0.003135, -1.003786, 0.001134],
    ]
    .map(DVec3::from_array);
    let hull = ConvexPolyhedron::hull(&points).unwrap();
    let com = crate::MassProperties::from_convex(&hull, 1.0).unwrap().com;
    let sum: f64 = PoseAnalysis::new(&hull, com)
        .unwrap()
        .quasi_static()
        .iter()
        .sum();
    assert!((sum - 1.0).abs() < 1e-9, "the shares sum to {sum}");
}
