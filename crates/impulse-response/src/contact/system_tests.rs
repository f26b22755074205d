//! Checks of jointed systems in the contact solver: a system that is one free rigid body
//! (q̇ = (v, ω), J the identity, M⁻¹Jᵀ its inverse mass and inertia) gives exactly the rigid
//! body's solution; on random mechanisms (a random positive-definite M, random link
//! Jacobians), the solution obeys the laws read from the test's own matrices: q̇ changes by
//! M⁻¹·Σ Jₚᵀ p, complementarity, the Coulomb disk, and no kinetic energy gained.

use super::tests::{contact_at, unit};
use super::*;
use glam::DQuat;
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

fn tight() -> SolverSettings {
    SolverSettings {
        max_iterations: 200_000,
        tolerance: 1e-13,
        direct_after: None,
        acceleration: 0,
    }
}

/// A free rigid body written as a system of six generalized velocities (v, ω), world axes.
fn rigid_as_system(body: usize, m: f64, inertia: DMat3, v: DVec3, w: DVec3) -> System {
    let inv = inertia.inverse();
    let e = [DVec3::X, DVec3::Y, DVec3::Z];
    let mut jacobian = Vec::new();
    let mut response = Vec::new();
    for a in e {
        jacobian.push((a, DVec3::ZERO));
        response.push((a / m, DVec3::ZERO));
    }
    for (i, a) in e.into_iter().enumerate() {
        jacobian.push((DVec3::ZERO, a));
        // Δω_i per unit couple about axis j: (I⁻¹)_ij, row i of the symmetric I⁻¹.
        response.push((DVec3::ZERO, inv.row(i)));
    }
    System {
        velocity: vec![v.x, v.y, v.z, w.x, w.y, w.z],
        members: vec![Member {
            body,
            jacobian,
            response,
        }],
    }
}

/// A tumbling box landing on the floor on four corners and a ball resting on it: solved with
/// the box as a rigid body and as a system of six generalized velocities, the impulses and
/// end velocities agree to rounding (the system's path through `system.rs` against the rigid
/// one through eqs. 3.1–3.4).
#[test]
fn a_rigid_body_as_a_system_is_solved_as_the_rigid_body() {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(3);
    for case in 0..50 {
        let m = rng.random_range(0.5..5.0);
        let half = DVec3::new(0.2, 0.1, 0.05);
        let rot = DMat3::from_quat(DQuat::from_axis_angle(unit(&mut rng), 0.3));
        let s = half * half;
        let inertia = rot
            * DMat3::from_diagonal(DVec3::new(s.y + s.z, s.x + s.z, s.x + s.y) * (m / 3.0))
            * rot.transpose();
        let (v, w) = (
            unit(&mut rng) * rng.random_range(0.0..2.0),
            unit(&mut rng) * rng.random_range(0.0..5.0),
        );
        let com = DVec3::new(0.0, 0.0, 0.05);
        let ball = IslandBody {
            body: Body::moving(0.2, DMat3::from_diagonal(DVec3::splat(2e-4))).unwrap(),
            com: DVec3::new(0.05, 0.02, 0.15),
            velocity: DVec3::new(0.1, 0.0, -0.5),
            omega: DVec3::new(0.0, 3.0, 0.0),
        };
        let mu = rng.random_range(0.0..1.2);
        let mut contacts: Vec<Contact> = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
            .iter()
            .map(|&(sx, sy)| {
                contact_at(
                    0,
                    None,
                    DVec3::new(sx * half.x, sy * half.y, 0.0),
                    DVec3::Z,
                    mu,
                )
            })
            .collect();
        contacts.push(Contact {
            target_normal_velocity: 0.01,
            ..contact_at(1, Some(0), DVec3::new(0.05, 0.02, 0.1), DVec3::Z, mu)
        });
        let rigid_box = IslandBody {
            body: Body::moving(m, inertia).unwrap(),
            com,
            velocity: v,
            omega: w,
        };
        let mut rigid = vec![rigid_box, ball];
        let mut c_rigid = contacts.clone();
        solve_contacts(&mut rigid, &mut c_rigid, &tight()).unwrap();

        let member = IslandBody {
            body: Body::Fixed,
            ..rigid_box
        };
        let mut linked = vec![member, ball];
        let mut systems = vec![rigid_as_system(0, m, inertia, v, w)];
        let mut c_linked = contacts.clone();
        solve_island(&mut linked, &mut systems, &mut c_linked, &tight()).unwrap();

        let scale = m * 5.0;
        for (a, b) in c_rigid.iter().zip(&c_linked) {
            assert!(
                (a.impulse - b.impulse).length() < 1e-9 * scale,
                "case {case}: {:?} vs {:?}",
                a.impulse,
                b.impulse
            );
        }
        let q = &systems[0].velocity;
        assert!((DVec3::new(q[0], q[1], q[2]) - rigid[0].velocity).length() < 1e-9 * 5.0);
        assert!((DVec3::new(q[3], q[4], q[5]) - rigid[0].omega).length() < 1e-9 * 50.0);
        // The member's velocity is written back from the system's.
        assert!((linked[0].velocity - rigid[0].velocity).length() < 1e-9 * 5.0);
        assert!((linked[0].omega - rigid[0].omega).length() < 1e-9 * 50.0);
        assert!((linked[1].velocity - rigid[1].velocity).length() < 1e-9 * 5.0);
    }
}

/// Dense n × n matrices of the random mechanisms (row-major).
struct Dense {
    n: usize,
    a: Vec<f64>,
}

impl Dense {
    fn at(&self, i: usize, j: usize) -> f64 {
        self.a[i * self.n + j]
    }

    /// x with M x = b (Gauss–Jordan with partial pivoting; M positive definite here).
    fn solve(&self, b: &[f64]) -> Vec<f64> {
        let n = self.n;
        let mut m = self.a.clone();
        let mut x = b.to_vec();
        for col in 0..n {
            let piv = (col..n)
                .max_by(|&i, &j| m[i * n + col].abs().total_cmp(&m[j * n + col].abs()))
                .unwrap();
            for k in 0..n {
                m.swap(col * n + k, piv * n + k);
            }
            x.swap(col, piv);
            for i in 0..n {
                if i != col {
                    let f = m[i * n + col] / m[col * n + col];
                    for k in 0..n {
                        m[i * n + k] -= f * m[col * n + k];
                    }
                    x[i] -= f * x[col];
                }
            }
        }
        (0..n).map(|i| x[i] / m[i * n + i]).collect()
    }

    fn quadratic(&self, x: &[f64]) -> f64 {
        (0..self.n)
            .map(|i| x[i] * (0..self.n).map(|j| self.at(i, j) * x[j]).sum::<f64>())
            .sum()
    }
}

/// A random mechanism: n generalized velocities, M = AAᵀ + n·I, `links` members each with a
/// random 6 × n Jacobian, its response M⁻¹Jᵀ from the dense solve.
fn random_system(
    rng: &mut Xoshiro256PlusPlus,
    n: usize,
    members: &[usize],
) -> (System, Dense, Vec<Vec<(DVec3, DVec3)>>) {
    let a: Vec<f64> = (0..n * n).map(|_| rng.random_range(-1.0..1.0)).collect();
    let mut m = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..n {
            m[i * n + j] = (0..n).map(|k| a[i * n + k] * a[j * n + k]).sum::<f64>()
                + if i == j { 0.5 } else { 0.0 };
        }
    }
    let mass = Dense { n, a: m };
    let mut jacobians = Vec::new();
    let mut out = Vec::new();
    for &body in members {
        let jacobian: Vec<(DVec3, DVec3)> = (0..n)
            .map(|_| {
                (
                    unit(rng) * rng.random_range(0.0..1.0),
                    unit(rng) * rng.random_range(0.0..3.0),
                )
            })
            .collect();
        // Column c of Jᵀ (a unit force or couple along one world axis) solved through M.
        let mut response = vec![(DVec3::ZERO, DVec3::ZERO); n];
        for c in 0..6 {
            let rhs: Vec<f64> = jacobian
                .iter()
                .map(|(jv, jw)| if c < 3 { jv[c] } else { jw[c - 3] })
                .collect();
            let x = mass.solve(&rhs);
            for k in 0..n {
                if c < 3 {
                    response[k].0[c] = x[k];
                } else {
                    response[k].1[c - 3] = x[k];
                }
            }
        }
        jacobians.push(jacobian.clone());
        out.push(Member {
            body,
            jacobian,
            response,
        });
    }
    let velocity = (0..n).map(|_| rng.random_range(-3.0..3.0)).collect();
    (
        System {
            velocity,
            members: out,
        },
        mass,
        jacobians,
    )
}

/// The point velocity of a link at `point` (its centre of mass `com`, Jacobian `jac`) at
/// generalized velocity `qd`, and the generalized force of a force `f` there.
fn point_velocity(jac: &[(DVec3, DVec3)], com: DVec3, point: DVec3, qd: &[f64]) -> DVec3 {
    let r = point - com;
    jac.iter()
        .zip(qd)
        .map(|((jv, jw), &q)| (*jv + jw.cross(r)) * q)
        .sum()
}

fn generalized_force(jac: &[(DVec3, DVec3)], com: DVec3, point: DVec3, f: DVec3) -> Vec<f64> {
    let r = point - com;
    jac.iter()
        .map(|(jv, jw)| jv.dot(f) + jw.dot(r.cross(f)))
        .collect()
}

/// 300 random islands of one mechanism (3–7 generalized velocities, two links), one free
/// rigid body and the fixed world: contacts link–world, link–body, and link–link of the one
/// mechanism. Checked with the test's own M and J: M·Δq̇ = Σ Jₚᵀ·p over the contacts (and
/// the rigid body's momentum change is its impulses'), p_n ≥ 0, u_n ≥ 0 and p_n·u_n = 0, the
/// Coulomb disk with sliding friction opposite to slip, and no kinetic energy gained.
#[test]
fn random_mechanisms_obey_the_laws_and_change_by_m_inverse_j_transpose_p() {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(17);
    let (mut converged, mut sliding) = (0, 0);
    for case in 0..300 {
        let n = rng.random_range(3..=7usize);
        let (system, mass, jacs) = random_system(&mut rng, n, &[0, 1]);
        let coms = [unit(&mut rng) * 0.3, unit(&mut rng) * 0.3];
        let (bm, bi) = (
            rng.random_range(0.2..3.0),
            DMat3::from_diagonal(DVec3::new(0.01, 0.02, 0.03)),
        );
        let mut bodies = vec![
            IslandBody {
                body: Body::Fixed,
                com: coms[0],
                velocity: DVec3::ZERO,
                omega: DVec3::ZERO,
            },
            IslandBody {
                body: Body::Fixed,
                com: coms[1],
                velocity: DVec3::ZERO,
                omega: DVec3::ZERO,
            },
            IslandBody {
                body: Body::moving(bm, bi).unwrap(),
                com: unit(&mut rng) * 0.5,
                velocity: unit(&mut rng),
                omega: unit(&mut rng) * 2.0,
            },
        ];
        let pairs = [
            (0, None),
            (1, None),
            (0, Some(2)),
            (2, Some(1)),
            (1, Some(0)),
        ];
        let mut contacts: Vec<Contact> = (0..rng.random_range(1..=6usize))
            .map(|_| {
                let (body1, body2) = pairs[rng.random_range(0..pairs.len())];
                let point = unit(&mut rng) * rng.random_range(0.0..0.5);
                let normal = unit(&mut rng);
                contact_at(body1, body2, point, normal, rng.random_range(0.0..1.5))
            })
            .collect();
        let q0 = system.velocity.clone();
        let (v0, w0) = (bodies[2].velocity, bodies[2].omega);
        let energy = |q: &[f64], v: DVec3, w: DVec3| {
            0.5 * mass.quadratic(q) + 0.5 * bm * v.length_squared() + 0.5 * w.dot(bi * w)
        };
        let before = energy(&q0, v0, w0);
        let mut systems = vec![system];
        let report = solve_island(&mut bodies, &mut systems, &mut contacts, &tight()).unwrap();
        if !report.converged {
            continue;
        }
        converged += 1;
        let q = &systems[0].velocity;
        let after = energy(q, bodies[2].velocity, bodies[2].omega);
        assert!(
            after <= before * (1.0 + 1e-9) + 1e-12,
            "case {case}: {before} → {after}"
        );
        // M·Δq̇ = Σ Jₚᵀ p, and the rigid body's momentum change.
        let mut tau = vec![0.0; n];
        let (mut dp_body, mut dl_body) = (DVec3::ZERO, DVec3::ZERO);
        let velocity_of = |k: usize, point: DVec3| -> DVec3 {
            match k {
                0 | 1 => point_velocity(&jacs[k], coms[k], point, q),
                _ => bodies[2].velocity + bodies[2].omega.cross(point - bodies[2].com),
            }
        };
        for c in &contacts {
            let frame = ContactFrame::from_normal(c.normal).unwrap();
            let p = frame.to_world(c.impulse);
            for (k, sign) in [(Some(c.body1), 1.0), (c.body2, -1.0)] {
                match k {
                    Some(k @ (0 | 1)) => {
                        for (t, g) in tau.iter_mut().zip(generalized_force(
                            &jacs[k],
                            coms[k],
                            c.point,
                            p * sign,
                        )) {
                            *t += g;
                        }
                    }
                    Some(_) => {
                        dp_body += p * sign;
                        dl_body += (c.point - bodies[2].com).cross(p * sign);
                    }
                    None => {}
                }
            }
            // The laws, from velocities computed here.
            let u1 = velocity_of(c.body1, c.point);
            let u2 = c.body2.map_or(DVec3::ZERO, |k| velocity_of(k, c.point));
            let u = frame.to_contact(u1 - u2);
            sliding += usize::from(super::tests::check_laws(case, c, u).0);
        }
        let dq: Vec<f64> = q.iter().zip(&q0).map(|(a, b)| a - b).collect();
        let expect = mass.solve(&tau);
        let scale = 1.0 + expect.iter().map(|x| x.abs()).fold(0.0, f64::max);
        for k in 0..n {
            assert!(
                (dq[k] - expect[k]).abs() < 1e-9 * scale,
                "case {case}: Δq̇[{k}] {} vs M⁻¹Jᵀp {}",
                dq[k],
                expect[k]
            );
        }
        assert!(
            (bodies[2].velocity - v0 - dp_body / bm).length() < 1e-9 * (1.0 + dp_body.length())
        );
        let dw = bi.inverse() * dl_body;
        assert!((bodies[2].omega - w0 - dw).length() < 1e-9 * (1.0 + dw.length()));
    }
    eprintln!("{converged}/300 converged, {sliding} sliding contacts");
    assert!(converged >= 270, "{converged}/300 converged");
    assert!(sliding >= 50, "{sliding} sliding contacts");
}

/// Malformed systems are refused by name, and nothing changes.
#[test]
fn malformed_systems_are_refused_and_change_nothing() {
    let body = IslandBody {
        body: Body::Fixed,
        com: DVec3::ZERO,
        velocity: DVec3::ZERO,
        omega: DVec3::ZERO,
    };
    let contact = contact_at(0, None, DVec3::ZERO, DVec3::Z, 0.5);
    let good = rigid_as_system(
        0,
        1.0,
        DMat3::IDENTITY,
        DVec3::new(0.0, 0.0, -1.0),
        DVec3::ZERO,
    );
    let mut short = good.clone();
    short.members[0].jacobian.pop();
    let mut nan = good.clone();
    nan.velocity[2] = f64::NAN;
    let mut out_of_range = good.clone();
    out_of_range.members[0].body = 3;
    let mut twice = good.clone();
    twice.members.push(twice.members[0].clone());
    for (what, system, rigid) in [
        ("short Jacobian", short, false),
        ("NaN velocity", nan, false),
        ("body out of range", out_of_range, false),
        ("member twice", twice, false),
        ("member not fixed", good.clone(), true),
    ] {
        let mut bodies = vec![if rigid {
            IslandBody {
                body: Body::moving(1.0, DMat3::IDENTITY).unwrap(),
                ..body
            }
        } else {
            body
        }];
        // Compared as printed: a NaN is not equal to itself.
        let before = format!("{:?}", (bodies.clone(), system.clone()));
        let mut systems = vec![system];
        let mut contacts = vec![contact];
        let result = solve_island(&mut bodies, &mut systems, &mut contacts, &tight());
        assert!(result.is_err(), "{what}: {result:?}");
        assert_eq!(
            format!("{:?}", (bodies, systems[0].clone())),
            before,
            "{what}"
        );
        assert_eq!(contacts, vec![contact], "{what}");
    }
    // And the good one stops the fall.
    let mut bodies = vec![body];
    let mut systems = vec![good];
    let mut contacts = vec![contact];
    solve_island(&mut bodies, &mut systems, &mut contacts, &tight()).unwrap();
    assert!(systems[0].velocity[2].abs() < 1e-12);
    assert!((contacts[0].impulse.z - 1.0).abs() < 1e-12);
}

/// A contact's collision matrix on links (the solver's step sizes) equals the contact
/// velocity's response to unit impulses, measured by applying them: for a link against the
/// world, a link against a rigid body, and two links of one mechanism (whose coupling terms a
/// sum of the two sides' matrices would miss).
#[test]
fn the_collision_matrix_of_a_link_contact_is_its_velocity_response() {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(5);
    for case in 0..100 {
        let n = rng.random_range(2..=7usize);
        let (system, _, _) = random_system(&mut rng, n, &[0, 1]);
        let mut bodies: Vec<IslandBody> = (0..2)
            .map(|_| IslandBody {
                body: Body::Fixed,
                com: unit(&mut rng) * 0.3,
                velocity: DVec3::ZERO,
                omega: DVec3::ZERO,
            })
            .collect();
        bodies.push(IslandBody {
            body: Body::moving(1.5, DMat3::from_diagonal(DVec3::new(0.01, 0.02, 0.03))).unwrap(),
            com: unit(&mut rng) * 0.5,
            velocity: DVec3::ZERO,
            omega: DVec3::ZERO,
        });
        let systems = vec![system];
        let of = system::membership(&bodies, &systems).unwrap();
        for (body1, body2) in [(0, None), (0, Some(2)), (1, Some(0))] {
            let point = unit(&mut rng) * 0.4;
            let c = contact_at(body1, body2, point, unit(&mut rng), 0.5);
            let row = prepare_row(&bodies, &systems, &of, &c).unwrap();
            let links = row.links.as_ref().unwrap();
            for (j, e) in [DVec3::X, DVec3::Y, DVec3::Z].into_iter().enumerate() {
                let (mut s, mut b) = (systems.clone(), bodies.clone());
                let u0 = contact_velocity(&b, &c, &row) + links.velocity(&s);
                apply(&mut b, &c, &row, e);
                links.apply(&mut s, e);
                let du = contact_velocity(&b, &c, &row) + links.velocity(&s) - u0;
                let col = row.k.col(j);
                assert!(
                    (du - col).length() < 1e-10 * (1.0 + col.length()),
                    "case {case}, {body1}/{body2:?}, axis {j}: Δu {du:?}, K {col:?}"
                );
            }
        }
    }
}
