//! Checks of the contact solver against analytic references: statics of a resting box and of
//! stacks (each interface carries the weight above it), a block on an incline (sticks below
//! tan θ = μ, slides at g(sin θ − μ cos θ) above), a ball sliding into rolling (slip falls by
//! 7/2·μ g h per step along a fixed direction, then the rolling speed from conservation of
//! angular momentum about the contact point), and, on random islands, the laws the solution
//! must obey (complementarity, the Coulomb disk with friction opposite to slip, no energy
//! gain).

use super::*;
use glam::DQuat;
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

const G: f64 = 9.81;
const H: f64 = 1e-3;

/// Solver settings for the analytic checks: converged far below the figures checked.
fn tight() -> SolverSettings {
    SolverSettings {
        max_iterations: 200_000,
        tolerance: 1e-12,
        direct_after: None,
        acceleration: DEFAULT_ACCELERATION,
    }
}

/// A contact with no warm start, target, bias or lever arms: the plain law.
pub(super) fn contact_at(
    body1: usize,
    body2: Option<usize>,
    point: DVec3,
    normal: DVec3,
    friction: f64,
) -> Contact {
    Contact {
        body1,
        body2,
        point,
        normal,
        friction,
        target_normal_velocity: 0.0,
        velocity_bias: DVec3::ZERO,
        lever_arms: None,
        impulse: DVec3::ZERO,
    }
}

/// A random unit vector (rejection sampling in the unit ball's shell).
pub(super) fn unit(rng: &mut Xoshiro256PlusPlus) -> DVec3 {
    loop {
        let v = DVec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        );
        if v.length() > 0.1 && v.length() < 1.0 {
            return v.normalize();
        }
    }
}

/// A solid box of mass `m` and half extents `half`, axis-aligned, centre `com`, at rest.
fn box_body(m: f64, half: DVec3, com: DVec3) -> (IslandBody, DMat3) {
    let inertia = box_inertia(m, half);
    let body = Body::moving(m, inertia).unwrap();
    (
        IslandBody {
            body,
            com,
            velocity: DVec3::ZERO,
            omega: DVec3::ZERO,
        },
        inertia,
    )
}

fn box_inertia(m: f64, half: DVec3) -> DMat3 {
    let s = half * half;
    DMat3::from_diagonal(DVec3::new(s.y + s.z, s.x + s.z, s.x + s.y) * (m / 3.0))
}

/// Four contacts at the corners of the face z = `z` of a box of half extents `half` centred
/// over (x, y) = `com`, normal +z, between `upper` and `lower` (None: the floor).
fn face_contacts(
    com: DVec3,
    half: DVec3,
    z: f64,
    upper: usize,
    lower: Option<usize>,
    mu: f64,
) -> Vec<Contact> {
    [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
        .iter()
        .map(|&(sx, sy)| {
            let point = DVec3::new(com.x + sx * half.x, com.y + sy * half.y, z);
            contact_at(upper, lower, point, DVec3::Z, mu)
        })
        .collect()
}

/// Σ p_n of contacts `range`.
/// `n` boxes of mass `m` and half extents `half` stacked on the fixed ground from z = 0, at
/// rest, with four corner contacts a face of friction `mu` (box k on box k − 1, the first on
/// the ground).
fn box_stack(m: f64, half: DVec3, n: usize, mu: f64) -> (Vec<IslandBody>, Vec<Contact>) {
    let mut bodies = Vec::new();
    let mut contacts = Vec::new();
    for k in 0..n {
        let com = DVec3::new(0.0, 0.0, (2 * k + 1) as f64 * half.z);
        bodies.push(box_body(m, half, com).0);
        contacts.extend(face_contacts(
            com,
            half,
            com.z - half.z,
            k,
            k.checked_sub(1),
            mu,
        ));
    }
    (bodies, contacts)
}

/// A stack of [`box_stack`] after one step's solve: every block stopped (‖v‖ < 1e-7 m/s) and
/// every interface carrying the weight above it over the step (statics), to 1e-6.
fn assert_stack_stopped_and_carried(
    bodies: &[IslandBody],
    contacts: &[Contact],
    m: f64,
    what: &str,
) {
    let n = bodies.len();
    for (k, b) in bodies.iter().enumerate() {
        assert!(
            b.velocity.length() < 1e-7,
            "{what} block {k}: {:?}",
            b.velocity
        );
        let carried = normal_sum(&contacts[4 * k..4 * k + 4]);
        let above = (n - k) as f64 * m * G * H;
        assert!(
            (carried - above).abs() < 1e-6 * above,
            "{what} interface {k}: {carried} vs {above}"
        );
    }
}

fn normal_sum(contacts: &[Contact]) -> f64 {
    contacts.iter().map(|c| c.impulse.z).sum()
}

fn kinetic_energy(bodies: &[IslandBody], inertias: &[DMat3], masses: &[f64]) -> f64 {
    bodies
        .iter()
        .zip(inertias.iter().zip(masses))
        .map(|(b, (i, &m))| 0.5 * m * b.velocity.length_squared() + 0.5 * b.omega.dot(*i * b.omega))
        .sum()
}

#[test]
fn resting_box_carries_its_weight_and_stops() {
    let (m, half) = (2.0, DVec3::new(0.3, 0.2, 0.1));
    let (mut b, _) = box_body(m, half, DVec3::new(0.0, 0.0, half.z));
    b.velocity.z = -G * H; // gravity over one step
    let mut bodies = [b];
    let mut contacts = face_contacts(bodies[0].com, half, 0.0, 0, None, 0.5);
    let report = solve_contacts(&mut bodies, &mut contacts, &tight()).unwrap();
    assert!(report.converged, "{report:?}");
    assert!(
        bodies[0].velocity.length() < 1e-11,
        "{:?}",
        bodies[0].velocity
    );
    assert!(bodies[0].omega.length() < 1e-10, "{:?}", bodies[0].omega);
    // Momentum: the contacts' total impulse is m·Δv = m g h ẑ. How the four corners share it
    // is statically indeterminate (their friction may hold a self-cancelling prestress); each
    // stays in its cone.
    let weight = m * G * H;
    let total: DVec3 = contacts.iter().map(|c| c.frame_impulse_world()).sum();
    assert!(
        (total - DVec3::new(0.0, 0.0, weight)).length() < 1e-9 * weight,
        "{total:?}"
    );
    for c in &contacts {
        assert!(c.impulse.z >= 0.0);
        assert!(c.impulse.truncate().length() <= c.friction * c.impulse.z * (1.0 + 1e-12));
    }
}

/// A stack of `n` blocks resting on the floor, each kicked by one step of gravity: afterwards
/// every block is at rest and the interface below block k carries the weight of the n − k
/// blocks above it (statics, independent of how the 4 corners share it).
#[test]
fn stack_interfaces_carry_the_weight_above() {
    let (m, half) = (1.5, DVec3::new(0.1, 0.075, 0.05));
    for n in [2usize, 4, 8] {
        let mut bodies = Vec::new();
        let mut contacts = Vec::new();
        for k in 0..n {
            let com = DVec3::new(0.0, 0.0, (2 * k + 1) as f64 * half.z);
            let (mut b, _) = box_body(m, half, com);
            b.velocity.z = -G * H;
            bodies.push(b);
            let lower = k.checked_sub(1);
            contacts.extend(face_contacts(com, half, com.z - half.z, k, lower, 0.6));
        }
        let report = solve_contacts(&mut bodies, &mut contacts, &tight()).unwrap();
        assert!(report.converged, "n = {n}: {report:?}");
        eprintln!("stack of {n}: {} sweeps to 1e-12 m/s", report.iterations);
        for (k, b) in bodies.iter().enumerate() {
            assert!(
                b.velocity.length() < 1e-9,
                "n {n} block {k}: {:?}",
                b.velocity
            );
            assert!(b.omega.length() < 1e-8, "n {n} block {k}: {:?}", b.omega);
            let carried = normal_sum(&contacts[4 * k..4 * k + 4]);
            let above = (n - k) as f64 * m * G * H;
            assert!(
                (carried - above).abs() < 1e-8 * above,
                "n {n} interface {k}: {carried} vs {above}"
            );
        }
    }
}

/// A block at rest on a plane tilted by θ (gravity turned instead): with μ = 0.5 it sticks
/// for tan θ = 0.4, friction holding m g sin θ; for tan θ = 0.7 it slides at
/// a = g (sin θ − μ cos θ) without turning, step after step.
#[test]
fn block_on_incline_sticks_below_and_slides_above_tan_theta() {
    let (m, half, mu) = (3.0, DVec3::new(0.3, 0.2, 0.1), 0.5);
    for tan in [0.4_f64, 0.7] {
        let theta = tan.atan();
        let gravity = G * DVec3::new(theta.sin(), 0.0, -theta.cos());
        let (b, _) = box_body(m, half, DVec3::new(0.0, 0.0, half.z));
        let mut bodies = [b];
        let mut contacts = face_contacts(bodies[0].com, half, 0.0, 0, None, mu);
        let a = if tan < mu {
            0.0
        } else {
            G * (theta.sin() - mu * theta.cos())
        };
        for step in 1..=50 {
            bodies[0].velocity += gravity * H;
            let report = solve_contacts(&mut bodies, &mut contacts, &tight()).unwrap();
            assert!(report.converged, "tan {tan} step {step}: {report:?}");
            let v = bodies[0].velocity;
            let expected = a * H * step as f64;
            assert!(
                (v.x - expected).abs() < 1e-10,
                "tan {tan} step {step}: {v:?}"
            );
            assert!(v.y.abs() < 1e-12 && v.z.abs() < 1e-10, "{v:?}");
            assert!(bodies[0].omega.length() < 1e-9, "{:?}", bodies[0].omega);
        }
        let friction: f64 = contacts.iter().map(|c| c.frame_impulse_world().x).sum();
        let expected = if tan < mu {
            -m * G * theta.sin() * H
        } else {
            -mu * m * G * theta.cos() * H
        };
        assert!(
            (friction - expected).abs() < 1e-9 * expected.abs(),
            "tan {tan}"
        );
    }
}

impl Contact {
    /// This contact's impulse in world axes (test helper).
    fn frame_impulse_world(&self) -> DVec3 {
        ContactFrame::from_normal(self.normal)
            .unwrap()
            .to_world(self.impulse)
    }
}

/// 200 random balls (radius, μ, g, launch velocity in any horizontal direction, any spin)
/// sliding on a floor: the slip s = v + ω × (−r ẑ) falls by exactly 7/2·μ g h per step along
/// its initial direction, the ball rolls from the step t* = |s₀|/(7/2 μ g) falls in, with the
/// rolling velocity given by conservation of the angular momentum about the contact point,
/// L = I ω + m r ẑ × v (friction and the normal force act at the contact, gravity along ẑ
/// through the centre), and the spin about the vertical untouched.
#[test]
fn random_balls_slide_into_rolling_as_the_closed_form_says() {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(7);
    for case in 0..200 {
        let r = rng.random_range(0.01..0.3);
        let m = rng.random_range(0.1..10.0);
        let mu = rng.random_range(0.05..1.0);
        let g = rng.random_range(1.0..20.0);
        let dir = rng.random_range(0.0..std::f64::consts::TAU);
        let v0 = DVec3::new(dir.cos(), dir.sin(), 0.0) * rng.random_range(0.1..5.0);
        let omega0 = DVec3::new(
            rng.random_range(-30.0..30.0),
            rng.random_range(-30.0..30.0),
            rng.random_range(-30.0..30.0),
        ) * (0.1 / r);
        let i = 0.4 * m * r * r;
        let body = Body::moving(m, DMat3::from_diagonal(DVec3::splat(i))).unwrap();
        let mut bodies = [IslandBody {
            body,
            com: DVec3::new(0.0, 0.0, r),
            velocity: v0,
            omega: omega0,
        }];
        let mut contacts = [Contact {
            body1: 0,
            body2: None,
            point: DVec3::ZERO,
            normal: DVec3::Z,
            friction: mu,
            target_normal_velocity: 0.0,
            velocity_bias: DVec3::ZERO,
            lever_arms: None,
            impulse: DVec3::ZERO,
        }];
        let slip = |b: &IslandBody| b.velocity + b.omega.cross(DVec3::new(0.0, 0.0, -r));
        let s0 = slip(&bodies[0]);
        let rate = 3.5 * mu * g * H; // slip lost per step
        let t_star = s0.length() / (3.5 * mu * g);
        let l_h = {
            let l = i * omega0 + m * r * DVec3::Z.cross(v0);
            DVec3::new(l.x, l.y, 0.0)
        };
        let omega_star = l_h / (i + m * r * r);
        let v_star = r * omega_star.cross(DVec3::Z);
        let scale = v0.length() + r * omega0.length();
        let mut rolled_at = None;
        let steps = (t_star / H).ceil() as usize + 3;
        for step in 1..=steps {
            bodies[0].velocity.z -= g * H;
            let report = solve_contacts(&mut bodies, &mut contacts, &tight()).unwrap();
            assert!(report.converged, "case {case} step {step}: {report:?}");
            let s = slip(&bodies[0]);
            assert!(s.z.abs() < 1e-10 * scale, "case {case}: {s:?}");
            let expected = s0.length() - rate * step as f64;
            if expected > 0.0 {
                assert!(
                    (s.length() - expected).abs() < 1e-9 * scale,
                    "case {case} step {step}: slip {} vs {expected}",
                    s.length()
                );
                assert!(
                    s.normalize().dot(s0.normalize()) > 1.0 - 1e-9,
                    "case {case}"
                );
            } else {
                assert!(s.length() < 1e-9 * scale, "case {case} step {step}: {s:?}");
                rolled_at.get_or_insert(step);
            }
        }
        let k = rolled_at.unwrap_or_else(|| panic!("case {case}: never rolls"));
        assert!(
            (k as f64 * H - t_star).abs() <= H,
            "case {case}: {k} vs {t_star}"
        );
        let b = &bodies[0];
        let v_h = DVec3::new(b.velocity.x, b.velocity.y, 0.0);
        assert!(
            (v_h - v_star).length() < 1e-9 * scale,
            "case {case}: {v_h:?} vs {v_star:?}"
        );
        assert!(
            (b.omega.z - omega0.z).abs() < 1e-12 * scale / r,
            "case {case}"
        );
    }
}

/// A random island: 2–5 bodies of random mass and turned inertia, 1–10 contacts between
/// random pairs or with the world, random normals, points, velocities and μ.
fn random_island(
    rng: &mut Xoshiro256PlusPlus,
) -> (Vec<IslandBody>, Vec<DMat3>, Vec<f64>, Vec<Contact>) {
    let n = rng.random_range(2..=5usize);
    let mut bodies = Vec::new();
    let mut inertias = Vec::new();
    let mut masses = Vec::new();
    for _ in 0..n {
        let m = rng.random_range(0.1..10.0);
        let half = DVec3::new(
            rng.random_range(0.02..0.5),
            rng.random_range(0.02..0.5),
            rng.random_range(0.02..0.5),
        );
        let rot = DMat3::from_quat(DQuat::from_axis_angle(
            unit(rng),
            rng.random_range(0.0..3.0),
        ));
        let inertia = rot * box_inertia(m, half) * rot.transpose();
        let inertia = 0.5 * (inertia + inertia.transpose());
        bodies.push(IslandBody {
            body: Body::moving(m, inertia).unwrap(),
            com: unit(rng) * rng.random_range(0.0..1.0),
            velocity: unit(rng) * rng.random_range(0.0..3.0),
            omega: unit(rng) * rng.random_range(0.0..10.0),
        });
        inertias.push(inertia);
        masses.push(m);
    }
    let contacts = (0..rng.random_range(1..=10usize))
        .map(|_| {
            let body1 = rng.random_range(0..n);
            let body2 = if rng.random_range(0..3u32) == 0 {
                None
            } else {
                let j = rng.random_range(0..n - 1);
                Some(if j >= body1 { j + 1 } else { j })
            };
            let point = unit(rng) * rng.random_range(0.0..1.0);
            let normal = unit(rng);
            contact_at(body1, body2, point, normal, rng.random_range(0.0..1.5))
        })
        .collect();
    (bodies, inertias, masses, contacts)
}

/// The solution's laws on 500 random islands: p_n ≥ 0 and u_n ≥ 0 with p_n·u_n = 0; ‖p_t‖ ≤
/// μ p_n; where a contact slides, p_t = −μ p_n u_t/‖u_t‖ (Coulomb, maximal dissipation);
/// where it sticks, u_t = 0; and the kinetic energy does not rise. Plain and accelerated
/// sweeps (`anderson.rs`) alike: acceleration changes the path, not the law.
#[test]
fn random_islands_obey_complementarity_coulomb_and_dissipation() {
    for acceleration in [0, DEFAULT_ACCELERATION] {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(11);
        let settings = SolverSettings {
            max_iterations: 100_000,
            tolerance: 1e-13,
            direct_after: None,
            acceleration,
        };
        let (mut converged, mut sliding, mut sticking) = (0, 0, 0);
        for case in 0..500 {
            let (mut bodies, inertias, masses, mut contacts) = random_island(&mut rng);
            let before = kinetic_energy(&bodies, &inertias, &masses);
            let report = solve_contacts(&mut bodies, &mut contacts, &settings).unwrap();
            if !report.converged {
                continue;
            }
            converged += 1;
            let after = kinetic_energy(&bodies, &inertias, &masses);
            assert!(
                after <= before * (1.0 + 1e-9),
                "memory {acceleration} case {case}: {before} → {after}"
            );
            for c in &contacts {
                let row = prepare_row(&bodies, &[], &vec![None; bodies.len()], c).unwrap();
                let u = contact_velocity(&bodies, c, &row);
                let (slides, sticks) = check_laws(case, c, u);
                sliding += usize::from(slides);
                sticking += usize::from(sticks);
            }
        }
        eprintln!(
            "memory {acceleration}: {converged}/500 converged; {sliding} sliding, {sticking} sticking contacts"
        );
        assert!(
            converged >= 450,
            "memory {acceleration}: {converged}/500 converged"
        );
        assert!(
            sliding >= 50 && sticking >= 50,
            "memory {acceleration}: {sliding} sliding, {sticking} sticking"
        );
    }
}

/// Anderson acceleration reaches the same solution in far fewer sweeps where plain sweeps
/// creep: a cold-started stack of 8 boxes (four corner contacts a face, μ 0.6) under one
/// step of gravity. The reference is statics, independent of any solver: every interface
/// carries the weight above it and every box ends at rest. Plain sweeps need more than
/// `PLAIN_AT_LEAST` sweeps; accelerated ones fewer than a quarter of those.
#[test]
fn acceleration_reaches_the_stack_solution_in_fewer_sweeps() {
    const PLAIN_AT_LEAST: usize = 400;
    let (m, half, n) = (1.5, DVec3::new(0.1, 0.075, 0.05), 8);
    let (mut bodies, contacts) = box_stack(m, half, n, 0.6);
    for b in &mut bodies {
        b.velocity.z -= G * H;
    }
    let mut sweeps = Vec::new();
    for acceleration in [0, DEFAULT_ACCELERATION] {
        let (mut bodies, mut contacts) = (bodies.clone(), contacts.clone());
        let settings = SolverSettings {
            max_iterations: 100_000,
            tolerance: 1e-9,
            direct_after: None,
            acceleration,
        };
        let report = solve_contacts(&mut bodies, &mut contacts, &settings).unwrap();
        assert!(report.converged, "memory {acceleration}: {report:?}");
        for (k, b) in bodies.iter().enumerate() {
            assert!(
                b.omega.length() < 1e-6,
                "memory {acceleration} block {k}: {:?}",
                b.omega
            );
        }
        assert_stack_stopped_and_carried(&bodies, &contacts, m, &format!("memory {acceleration}"));
        sweeps.push(report.iterations);
    }
    eprintln!(
        "stack of {n}: plain {} sweeps, accelerated {}",
        sweeps[0], sweeps[1]
    );
    assert!(sweeps[0] > PLAIN_AT_LEAST, "plain: {sweeps:?}");
    assert!(4 * sweeps[1] < sweeps[0], "plain, accelerated: {sweeps:?}");
}

/// Warm-started from its own solution, a resting stack is solved in one sweep and keeps it.
#[test]
fn warm_start_from_the_solution_takes_one_sweep() {
    let (m, half) = (1.0, DVec3::new(0.1, 0.1, 0.05));
    let (mut bodies, mut contacts) = box_stack(m, half, 6, 0.5);
    let kick = |bodies: &mut Vec<IslandBody>| {
        for b in bodies.iter_mut() {
            b.velocity = DVec3::new(0.0, 0.0, -G * H);
            b.omega = DVec3::ZERO;
        }
    };
    kick(&mut bodies);
    let cold = solve_contacts(&mut bodies, &mut contacts, &tight()).unwrap();
    let solution: Vec<DVec3> = contacts.iter().map(|c| c.impulse).collect();
    kick(&mut bodies);
    let warm = solve_contacts(&mut bodies, &mut contacts, &tight()).unwrap();
    assert!(cold.iterations > 10, "{cold:?}");
    assert_eq!(warm.iterations, 1, "{warm:?}");
    // One sweep within the tolerance moves an impulse by at most tolerance/K_nn ≤ tolerance·m.
    for (c, p) in contacts.iter().zip(&solution) {
        assert!(
            (c.impulse - *p).length() <= 2.0 * tight().tolerance * m,
            "{c:?} vs {p:?}"
        );
    }
}

#[test]
fn bad_input_is_refused_and_changes_nothing() {
    let half = DVec3::splat(0.1);
    let (b, _) = box_body(1.0, half, DVec3::new(0.0, 0.0, 0.1));
    let good = face_contacts(b.com, half, 0.0, 0, None, 0.5)[0];
    let fixed = IslandBody {
        body: Body::Fixed,
        ..b
    };
    let cases: Vec<(Vec<IslandBody>, Contact, SolverSettings, &str)> = vec![
        (vec![b], Contact { body1: 3, ..good }, tight(), "index"),
        (
            vec![b, b],
            Contact {
                body2: Some(0),
                ..good
            },
            tight(),
            "body2",
        ),
        (
            vec![b],
            Contact {
                friction: -0.1,
                ..good
            },
            tight(),
            "friction",
        ),
        (
            vec![b],
            Contact {
                friction: f64::NAN,
                ..good
            },
            tight(),
            "friction",
        ),
        (
            vec![b],
            Contact {
                point: DVec3::NAN,
                ..good
            },
            tight(),
            "point",
        ),
        (
            vec![b],
            Contact {
                normal: DVec3::ZERO,
                ..good
            },
            tight(),
            "normal",
        ),
        (
            vec![b],
            Contact {
                target_normal_velocity: f64::INFINITY,
                velocity_bias: DVec3::ZERO,
                lever_arms: None,
                ..good
            },
            tight(),
            "target",
        ),
        (vec![fixed], good, tight(), "two fixed"),
        (
            vec![b],
            good,
            SolverSettings {
                tolerance: 0.0,
                ..tight()
            },
            "tolerance",
        ),
        (
            vec![b],
            good,
            SolverSettings {
                max_iterations: 0,
                ..tight()
            },
            "iterations",
        ),
        (
            vec![IslandBody {
                velocity: DVec3::NAN,
                ..b
            }],
            good,
            tight(),
            "velocity",
        ),
    ];
    for (mut bodies, contact, settings, what) in cases {
        let before = bodies.clone();
        let mut contacts = [contact];
        let result = solve_contacts(&mut bodies, &mut contacts, &settings);
        assert!(result.is_err(), "{what}: {result:?}");
        // Debug text, so that NaN inputs compare equal to themselves.
        assert_eq!(format!("{bodies:?}"), format!("{before:?}"), "{what}");
        assert_eq!(
            format!("{:?}", contacts[0]),
            format!("{contact:?}"),
            "{what}"
        );
    }
}

/// The direct solve settles tall stacks that sweeps alone cannot: from a cold start, stacks
/// of 8 and 16 (by the patch jump, `patch.rs`: 48 and 96 unknowns) and of 32 (too many
/// unknowns for the jump: by the active-set solve, `direct.rs`) converge to 1e-9 m/s within
/// 200 sweeps (sweeps alone: not within 200), every interface carrying the weight above it;
/// the next step, warm started, takes one sweep.
#[test]
fn direct_solve_settles_tall_stacks() {
    let (m, half) = (1.5, DVec3::new(0.1, 0.075, 0.05));
    let settings = SolverSettings {
        max_iterations: 200,
        tolerance: 1e-9,
        direct_after: Some(20),
        acceleration: 0,
    };
    for n in [8usize, 16, 32] {
        let mut bodies = Vec::new();
        let mut contacts = Vec::new();
        for k in 0..n {
            let com = DVec3::new(0.0, 0.0, (2 * k + 1) as f64 * half.z);
            let (b, _) = box_body(m, half, com);
            bodies.push(b);
            let lower = k.checked_sub(1);
            contacts.extend(face_contacts(com, half, com.z - half.z, k, lower, 0.6));
        }
        for b in &mut bodies {
            b.velocity.z -= G * H;
        }
        let report = solve_contacts(&mut bodies, &mut contacts, &settings).unwrap();
        assert!(
            report.converged && (report.direct || report.jumped) && report.direct_tried,
            "n = {n}: {report:?}"
        );
        assert_stack_stopped_and_carried(&bodies, &contacts, m, &format!("n {n}"));
        // The next step, warm started from that solution, needs one sweep.
        for b in &mut bodies {
            b.velocity.z -= G * H;
        }
        let warm = solve_contacts(&mut bodies, &mut contacts, &settings).unwrap();
        assert!(
            warm.converged && warm.iterations == 1 && !warm.direct_tried,
            "n {n}: {warm:?}"
        );
        let plain = SolverSettings {
            direct_after: None,
            ..settings
        };
        let mut cold: Vec<Contact> = contacts
            .iter()
            .map(|c| Contact {
                impulse: DVec3::ZERO,
                ..*c
            })
            .collect();
        let mut still: Vec<IslandBody> = bodies
            .iter()
            .map(|b| IslandBody {
                velocity: DVec3::new(0.0, 0.0, -G * H),
                omega: DVec3::ZERO,
                ..*b
            })
            .collect();
        let sweeps = solve_contacts(&mut still, &mut cold, &plain).unwrap();
        assert!(
            !sweeps.converged && !sweeps.direct_tried,
            "n {n}: sweeps alone converged: {sweeps:?}"
        );
    }
}

/// The direct solve predicts the velocities its impulses produce: accepted after one sweep
/// on 500 random islands, its solution meets the laws it was checked against, so the next
/// sweep moves little — a sliding contact's friction may point up to the angle of
/// `SLIDE_DIRECTION_COS` (0.014 rad) off its slip, which that sweep turns (measured: 1e-3 of
/// the velocity scale at worst). Before the classes' forced changes entered its system (a
/// contact that stops pressing drops its impulse, a sliding one has its friction put on the
/// rim), the sweep after an accepted solve moved velocities by 1.1 times that scale.
#[test]
fn an_accepted_direct_solve_is_where_the_sweeps_stay() {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(23);
    let settings = SolverSettings {
        max_iterations: 2,
        tolerance: 1e-12,
        direct_after: Some(1),
        acceleration: 0,
    };
    let (mut accepted, mut worst) = (0, 0.0_f64);
    for _ in 0..500 {
        let (mut bodies, _, _, mut contacts) = random_island(&mut rng);
        let report = solve_contacts(&mut bodies, &mut contacts, &settings).unwrap();
        if report.direct {
            accepted += 1;
            // Velocities up to 3 m/s and 10 rad/s at lever arms up to 2 m: a scale of 23 m/s.
            worst = worst.max(report.residual / 23.0);
        }
    }
    eprintln!("{accepted} accepted; worst relative residual after {worst:e}");
    assert!(accepted >= 100, "{accepted} accepted");
    assert!(worst < 1e-2, "worst relative residual {worst:e}");
}

/// A velocity bias b moves the contact law to u + b: a box pressed on the floor by one step
/// of gravity, every corner biased by the same b, ends moving at −b when friction holds it
/// (its normal speed −b_n, its tangential −b_t), and when friction cannot (μ below
/// |b_t|/(g·h − b_n)) slides with the tangential speed friction's full disk allows,
/// μ·(g·h − b_n), against b_t (opposite to the slip u_t + b_t); it does not turn either way.
#[test]
fn a_velocity_bias_moves_the_law_to_u_plus_b() {
    let (m, half) = (2.0, DVec3::new(0.3, 0.2, 0.05));
    let b = DVec3::new(0.002, -0.001, 0.003);
    for mu in [0.5, 0.1] {
        let (mut body, _) = box_body(m, half, DVec3::new(0.0, 0.0, half.z));
        body.velocity.z = -G * H;
        let mut bodies = [body];
        let mut contacts = face_contacts(bodies[0].com, half, 0.0, 0, None, mu);
        for c in &mut contacts {
            c.velocity_bias = b;
        }
        let report = solve_contacts(&mut bodies, &mut contacts, &tight()).unwrap();
        assert!(report.converged, "{report:?}");
        let (v, w) = (bodies[0].velocity, bodies[0].omega);
        let bt = DVec3::new(b.x, b.y, 0.0);
        let sticks = bt.length() <= mu * (G * H - b.z);
        let expected_t = if sticks {
            -bt
        } else {
            -bt.normalize() * mu * (G * H - b.z)
        };
        assert!((v.z + b.z).abs() < 1e-10, "μ {mu}: normal speed {}", v.z);
        assert!(
            (v.truncate() - expected_t.truncate()).length() < 1e-9,
            "μ {mu} (sticks: {sticks}): {v} against {expected_t}"
        );
        assert!(w.length() < 1e-9, "μ {mu}: turns at {w}");
    }
}

/// Explicit lever arms replace `point − com`: a box moving down and sideways meets the floor
/// at one corner whose impulse is declared to act at another arm r. The solution stops the
/// velocity of the point at r (v + ω×r = 0, friction holds), and the box's momentum and
/// angular momentum about its centre change by P and r × P, read from its velocities.
#[test]
fn explicit_lever_arms_are_where_the_impulse_acts() {
    let (m, half) = (2.0, DVec3::new(0.3, 0.2, 0.1));
    let (mut body, inertia) = box_body(m, half, DVec3::new(0.0, 0.0, half.z));
    body.velocity = DVec3::new(0.05, -0.02, -0.3);
    let v0 = body.velocity;
    let mut bodies = [body];
    let arm = DVec3::new(0.25, -0.15, -0.12);
    let mut contacts = vec![Contact {
        body1: 0,
        body2: None,
        point: DVec3::new(half.x, half.y, 0.0),
        normal: DVec3::Z,
        friction: 10.0,
        target_normal_velocity: 0.0,
        velocity_bias: DVec3::ZERO,
        lever_arms: Some((arm, DVec3::ZERO)),
        impulse: DVec3::ZERO,
    }];
    let report = solve_contacts(&mut bodies, &mut contacts, &tight()).unwrap();
    assert!(report.converged, "{report:?}");
    let (v, w) = (bodies[0].velocity, bodies[0].omega);
    let at_arm = v + w.cross(arm);
    assert!(
        at_arm.length() < 1e-10,
        "the point at the arm moves at {at_arm}"
    );
    let p = m * (v - v0);
    let dl = inertia * w;
    assert!(
        (dl - arm.cross(p)).length() < 1e-10,
        "ΔL {dl} against r × P {}",
        arm.cross(p)
    );
    assert!(p.z > 0.0, "the floor pushes up: {p}");
}

/// A box resting on a scripted platform (a [`Body::Fixed`] island body that moves and turns):
/// the platform's velocity is untouched by the solve (infinite mass), and the box's corners,
/// sticking, end with the platform's velocity at each corner, v + ω × r measured here from
/// the two bodies' final velocities.
#[test]
fn a_moving_fixed_body_carries_a_sticking_box_and_is_not_moved() {
    let half = DVec3::new(0.1, 0.1, 0.05);
    let (mut box1, _) = box_body(2.0, half, DVec3::new(0.0, 0.0, half.z));
    box1.velocity.z -= G * H;
    let platform = IslandBody {
        body: Body::Fixed,
        com: DVec3::new(0.3, -0.2, -0.1),
        velocity: DVec3::new(2e-3, -1e-3, 0.0),
        omega: DVec3::new(0.0, 0.0, 5e-3),
    };
    let mut bodies = vec![box1, platform];
    let mut contacts = face_contacts(DVec3::ZERO, half, 0.0, 0, Some(1), 2.0);
    let report = solve_contacts(&mut bodies, &mut contacts, &tight()).unwrap();
    assert!(report.converged);
    assert_eq!(bodies[1], platform, "the fixed body must not move");
    for c in &contacts {
        let u = (bodies[0].velocity + bodies[0].omega.cross(c.point - bodies[0].com))
            - (platform.velocity + platform.omega.cross(c.point - platform.com));
        assert!(u.length() < 1e-9, "corner {:?} slips at {u:?}", c.point);
        assert!(c.impulse.z > 0.0, "every corner presses");
    }
}

/// Asserts a solved contact's laws from its relative velocity `u` (contact frame, after the
/// solve): p_n ≥ 0 and u_n ≥ 0 with p_n·u_n = 0, ‖p_t‖ ≤ μ p_n, sliding friction opposite to
/// the slip on the disk's rim (Coulomb, maximal dissipation), no slip where it sticks inside.
/// Returns whether it slides and whether it sticks (for counting).
pub(super) fn check_laws(case: usize, c: &Contact, u: DVec3) -> (bool, bool) {
    let p = c.impulse;
    let scale = 1e-7 * (1.0 + u.length());
    assert!(p.z >= 0.0 && u.z >= -scale, "case {case}: p {p:?} u {u:?}");
    assert!(
        p.z * u.z <= scale * p.z.max(1e-12),
        "case {case}: p {p:?} u {u:?}"
    );
    let (p_t, u_t) = (DVec2::new(p.x, p.y), DVec2::new(u.x, u.y));
    assert!(
        p_t.length() <= c.friction * p.z * (1.0 + 1e-12) + 1e-15,
        "case {case}"
    );
    if u_t.length() > 1e-6 && p.z > 1e-9 {
        let coulomb = -c.friction * p.z * u_t / u_t.length();
        assert!(
            (p_t - coulomb).length() <= 1e-6 * c.friction * p.z + 1e-12,
            "case {case}: p_t {p_t:?} vs Coulomb {coulomb:?}"
        );
        (true, false)
    } else if p.z > 1e-9 && p_t.length() < c.friction * p.z * (1.0 - 1e-6) {
        assert!(
            u_t.length() < 1e-7,
            "case {case}: sticking with u_t {u_t:?}"
        );
        (false, true)
    } else {
        (false, false)
    }
}
