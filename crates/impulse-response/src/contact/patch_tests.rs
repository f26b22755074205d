//! Checks of the patch jump (`patch.rs`): the statics of a box on four corners against the
//! lever rule, and two island solves that stalled in a pile of 1000 boxes (stacks of ten
//! tilted boxes, replayed from the run) against plain sweeps run to convergence.

use super::*;
use glam::DMat3;

const G: f64 = 9.81;
const H: f64 = 1e-3;

/// A box on the floor by its four bottom corners, its centre of mass off the middle of the
/// face, struck by one step of gravity: the jump alone stops it, with no friction, and the
/// corners share the weight as the least-norm statics of four supports on a rectangle say
/// (p_k = W/4·(1 + x_c·x_k/a² + y_c·y_k/b²) for corners (±a, ±b) and the centre of mass
/// over (x_c, y_c), W = m·g·h) — the distribution a patch's wrench is spread by.
#[test]
fn a_box_on_four_corners_shares_its_weight_by_the_lever_rule() {
    let (m, a, b, z) = (3.0, 0.3, 0.2, 0.1);
    let (x_c, y_c) = (0.07, -0.05);
    let inertia = DMat3::from_diagonal(DVec3::new(0.02, 0.03, 0.04));
    let mut bodies = [IslandBody {
        body: Body::moving(m, inertia).unwrap(),
        com: DVec3::new(x_c, y_c, z),
        velocity: DVec3::new(0.0, 0.0, -G * H),
        omega: DVec3::ZERO,
    }];
    let corners = [(-a, -b), (a, -b), (a, b), (-a, b)];
    let mut contacts: Vec<Contact> = corners
        .iter()
        .map(|&(x, y)| super::tests::contact_at(0, None, DVec3::new(x, y, 0.0), DVec3::Z, 0.5))
        .collect();
    let of = system::membership(&bodies, &[]).unwrap();
    let rows = prepare(&bodies, &[], &of, &contacts, &SolverSettings::default()).unwrap();
    // Cold: the jump's scale is the iterate's largest impulse, so give it one sweep first.
    for (c, row) in contacts.iter_mut().zip(&rows) {
        sweep_contact(&mut bodies, &mut [], c, row);
    }
    assert!(
        patch::jump(&mut bodies, &mut contacts, &rows, 1),
        "not taken"
    );
    let w = m * G * H;
    for (c, &(x, y)) in contacts.iter().zip(&corners) {
        let lever = w / 4.0 * (1.0 + x_c * x / (a * a) + y_c * y / (b * b));
        assert!(
            (c.impulse.z - lever).abs() < 1e-12 * w,
            "corner ({x}, {y}): {} against {lever}",
            c.impulse.z
        );
        assert!(
            c.impulse.truncate().length() < 1e-12 * w,
            "friction {:?}",
            c.impulse
        );
    }
    let b0 = &bodies[0];
    assert!(
        b0.velocity.length() < 1e-14 && b0.omega.length() < 1e-13,
        "{b0:?}"
    );
}

/// An island solve stored as JSON (`stalled/`): bodies, contacts with their warm starts, and
/// the solver tolerance of the run.
fn stalled(json: &str) -> (Vec<IslandBody>, Vec<Contact>, f64) {
    let doc: serde_json::Value = serde_json::from_str(json).unwrap();
    let v3 = |v: &serde_json::Value| {
        DVec3::new(
            v[0].as_f64().unwrap(),
            v[1].as_f64().unwrap(),
            v[2].as_f64().unwrap(),
        )
    };
    let bodies = doc["bodies"]
        .as_array()
        .unwrap()
        .iter()
        .map(|b| {
            let body = if b["fixed"].as_bool().unwrap() {
                Body::Fixed
            } else {
                let ii: Vec<f64> = b["ii"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|x| x.as_f64().unwrap())
                    .collect();
                Body::Moving {
                    inverse_mass: b["im"].as_f64().unwrap(),
                    inverse_inertia: DMat3::from_cols_slice(&ii),
                }
            };
            IslandBody {
                body,
                com: v3(&b["com"]),
                velocity: v3(&b["v"]),
                omega: v3(&b["w"]),
            }
        })
        .collect();
    let contacts = doc["contacts"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| Contact {
            body1: c["b1"].as_u64().unwrap() as usize,
            body2: c["b2"].as_u64().map(|x| x as usize),
            point: v3(&c["point"]),
            normal: v3(&c["normal"]),
            friction: c["mu"].as_f64().unwrap(),
            target_normal_velocity: c["target"].as_f64().unwrap(),
            velocity_bias: v3(&c["bias"]),
            lever_arms: c["arms"].as_array().map(|a| (v3(&a[0]), v3(&a[1]))),
            impulse: v3(&c["impulse"]),
        })
        .collect();
    (bodies, contacts, doc["tolerance"].as_f64().unwrap())
}

/// Two solves of stacks of ten tilted boxes on four corners each (40 contacts), dumped at
/// t = 0.8 s of the pile of 1000 boxes (`cargo xtask bench --scale`) where they ended at the
/// 200-sweep cap: with the run's settings (a jump after 20 sweeps) each converges within 40
/// sweeps, to the velocities plain sweeps reach after thousands (the independent
/// reference: each side converged to the run's tolerance, so they agree within a few of
/// it). Without the jump the active-set solve diverges on them and the sweeps stop at the
/// cap unconverged.
#[test]
fn stalled_stacks_of_the_pile_converge_after_the_jump() {
    for (name, json) in [
        ("a", include_str!("stalled/stack-10-a.json")),
        ("b", include_str!("stalled/stack-10-b.json")),
    ] {
        let (bodies, contacts, tolerance) = stalled(json);
        let run = SolverSettings {
            max_iterations: 200,
            tolerance,
            direct_after: Some(20),
            acceleration: DEFAULT_ACCELERATION,
        };
        let (mut b1, mut c1) = (bodies.clone(), contacts.clone());
        let report = solve_contacts(&mut b1, &mut c1, &run).unwrap();
        assert!(
            report.converged && report.iterations <= 40 && report.jumped,
            "{name}: {report:?}"
        );
        let plain = SolverSettings {
            max_iterations: 2_000_000,
            direct_after: None,
            acceleration: 0,
            ..run
        };
        let (mut b2, mut c2) = (bodies.clone(), contacts.clone());
        let sweeps = solve_contacts(&mut b2, &mut c2, &plain).unwrap();
        let tight = SolverSettings {
            tolerance: 1e-2 * tolerance,
            ..plain
        };
        let (mut b3, mut c3) = (bodies.clone(), contacts.clone());
        let reference = solve_contacts(&mut b3, &mut c3, &tight).unwrap();
        assert!(
            sweeps.converged && reference.converged && sweeps.iterations > 10 * report.iterations,
            "{name}: {sweeps:?} {reference:?}"
        );
        // Reach of a box of the pile (half-diagonal of a 0.5 m cube).
        let reach = 0.44;
        let off = |bs: &[IslandBody]| {
            bs.iter()
                .zip(&b3)
                .map(|(x, y)| {
                    (x.velocity - y.velocity).length() + (x.omega - y.omega).length() * reach
                })
                .fold(0.0_f64, f64::max)
        };
        let (jumped, swept) = (off(&b1), off(&b2));
        eprintln!(
            "{name}: {} sweeps against {}; off the tight solution by {jumped:.2e} and {swept:.2e}",
            report.iterations, sweeps.iterations
        );
        assert!(jumped < swept, "{name}: {jumped:e} against {swept:e}");
    }
}
