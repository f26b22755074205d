//! Tests of the collision integration against closed forms, the digest's reference numbers
//! (§17), the p_z reference solver and independent rigid-body bookkeeping.

use super::*;
use crate::body::{Body, ContactFrame, relative_contact_velocity};
use crate::rays::{normal_slope, rays};
use crate::reference::{DEFAULT_REFERENCE_STEPS, reference_resolve};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

fn sym(a: f64, b: f64, c: f64, f: f64, e: f64, d: f64) -> DMat3 {
    DMat3::from_cols(
        DVec3::new(a, f, e),
        DVec3::new(f, b, d),
        DVec3::new(e, d, c),
    )
}

fn cm(k: DMat3) -> CollisionMatrix {
    CollisionMatrix::new(k).unwrap()
}

fn solve(k: DMat3, u0: DVec3, mu: f64, e: f64, law: Restitution) -> Response {
    resolve(&cm(k), u0, mu, e, law, &Settings::default()).unwrap()
}

fn stronge(k: DMat3, u0: DVec3, mu: f64, e: f64) -> Response {
    solve(k, u0, mu, e, Restitution::Stronge)
}

#[track_caller]
fn near(a: f64, b: f64, tol: f64) {
    assert!((a - b).abs() <= tol, "{a} vs {b} (tol {tol})");
}

#[track_caller]
fn near_v(a: DVec3, b: DVec3, tol: f64) {
    assert!((a - b).abs().max_element() <= tol, "{a} vs {b} (tol {tol})");
}

use crate::body::tests::{random_body, unit};

/// A random SPD matrix, condition number up to ~1e3.
fn random_spd(rng: &mut Xoshiro256PlusPlus) -> DMat3 {
    crate::matrix::tests::random_spd(rng)
}

fn random_approach(rng: &mut Xoshiro256PlusPlus) -> DVec3 {
    let mut u = unit(rng) * rng.random_range(0.1..3.0);
    u.z = -u.z.abs().max(1e-3);
    u
}

// ------------------------------------------------------------------ frictionless closed forms

/// Frictionless central collision of two spheres: the textbook 1-D result
/// v₁′ = (m₁v₁ + m₂v₂ + m₂e(v₂ − v₁))/(m₁ + m₂), and the same for body 2, to 1e-12.
#[test]
fn frictionless_central_collision_matches_textbook() {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(61);
    for _ in 0..2000 {
        let (m1, m2) = (
            10f64.powf(rng.random_range(-2.0..2.0)),
            10f64.powf(rng.random_range(-2.0..2.0)),
        );
        let (r1, r2) = (rng.random_range(0.1..2.0), rng.random_range(0.1..2.0));
        let e = rng.random_range(0.0..=1.0);
        let n = unit(&mut rng);
        let v1n = rng.random_range(-3.0..3.0);
        let v2n = v1n + rng.random_range(0.1..3.0); // approaching: u_n = v1n − v2n < 0
        let t = n.any_orthonormal_vector();
        // Tangential velocities and spins are irrelevant without friction.
        let v1 = n * v1n + t * rng.random_range(-1.0..1.0);
        let v2 = n * v2n + t * rng.random_range(-1.0..1.0);
        let (w1, w2) = (unit(&mut rng), unit(&mut rng));
        let i1 = DMat3::IDENTITY * (0.4 * m1 * r1 * r1);
        let i2 = DMat3::IDENTITY * (0.4 * m2 * r2 * r2);
        let frame = ContactFrame::from_normal(n).unwrap();
        // Body 1 is on the +n side of body 2: contact at −r1·n from centre 1, +r2·n from 2.
        let (o1, o2) = (-n * r1, n * r2);
        let k = CollisionMatrix::rigid(
            &Body::moving(m1, i1).unwrap(),
            o1,
            &Body::moving(m2, i2).unwrap(),
            o2,
            &frame,
        )
        .unwrap();
        let u0 = frame.to_contact(relative_contact_velocity(v1, w1, o1, v2, w2, o2));
        let r = resolve(&k, u0, 0.0, e, Restitution::Stronge, &Settings::default()).unwrap();
        assert_eq!(r.kind, ResponseKind::Frictionless);
        let p = r.impulse_world(&frame);
        let (v1a, v2a) = (v1 + p / m1, v2 - p / m2);
        let s = m1 + m2;
        let want1 = (m1 * v1n + m2 * v2n + m2 * e * (v2n - v1n)) / s;
        let want2 = (m1 * v1n + m2 * v2n + m1 * e * (v1n - v2n)) / s;
        let scale = v1n.abs() + v2n.abs();
        near(v1a.dot(n), want1, 1e-12 * scale);
        near(v2a.dot(n), want2, 1e-12 * scale);
        // No tangential impulse.
        assert!((p - n * p.dot(n)).length() <= 1e-12 * p.length());
    }
}

/// Frictionless eccentric collisions of arbitrary rigid bodies: the textbook impulse
/// j = −(1 + e)·u₀·n / (1/m₁ + 1/m₂ + n·[(I₁⁻¹(r₁ × n)) × r₁] + n·[(I₂⁻¹(r₂ × n)) × r₂]),
/// p = j·n, to 1e-12; and on bare K: p = (0, 0, (1+e)(−u_z0)/K_33), u_f = u₀ + p_z·K·e_z,
/// W = −(1 − e²)·u_z0²/(2K_33) (digest test 5).
#[test]
fn frictionless_eccentric_collision_matches_textbook() {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(62);
    for _ in 0..2000 {
        let bodies: Vec<(f64, DMat3)> = (0..2).map(|_| random_body(&mut rng)).collect();
        let ((m1, i1), (m2, i2)) = (bodies[0], bodies[1]);
        let (r1, r2) = (unit(&mut rng) * 1.2, unit(&mut rng) * 0.8);
        let n = unit(&mut rng);
        let frame = ContactFrame::from_normal(n).unwrap();
        let k = CollisionMatrix::rigid(
            &Body::moving(m1, i1).unwrap(),
            r1,
            &Body::moving(m2, i2).unwrap(),
            r2,
            &frame,
        )
        .unwrap();
        let mut u_world = unit(&mut rng);
        if u_world.dot(n) > -0.05 {
            u_world -= n * (u_world.dot(n) + 0.5);
        }
        let e = rng.random_range(0.0..=1.0);
        let r = resolve(
            &k,
            frame.to_contact(u_world),
            0.0,
            e,
            Restitution::Stronge,
            &Settings::default(),
        )
        .unwrap();
        let (i1inv, i2inv) = (i1.inverse(), i2.inverse());
        let denom = 1.0 / m1
            + 1.0 / m2
            + n.dot((i1inv * r1.cross(n)).cross(r1))
            + n.dot((i2inv * r2.cross(n)).cross(r2));
        let j = -(1.0 + e) * u_world.dot(n) / denom;
        let p = r.impulse_world(&frame);
        assert!((p - n * j).length() <= 1e-12 * j.abs(), "{p} vs {}", n * j);
    }
    // Bare K.
    for _ in 0..2000 {
        let k = random_spd(&mut rng);
        let u0 = random_approach(&mut rng);
        let e = rng.random_range(0.0..=1.0);
        let r = stronge(k, u0, 0.0, e);
        let k33 = k.z_axis.z;
        let pz = (1.0 + e) * (-u0.z) / k33;
        near_v(r.impulse, DVec3::new(0.0, 0.0, pz), 1e-12 * pz);
        near_v(r.velocity, u0 + k.z_axis * pz, 1e-12 * u0.length());
        near(r.velocity.z, -e * u0.z, 1e-12 * u0.z.abs());
        let w = -(1.0 - e * e) * u0.z * u0.z / (2.0 * k33);
        let scale = u0.z * u0.z / k33;
        near(r.work, w, 1e-12 * scale);
        near(
            r.compression_work,
            -u0.z * u0.z / (2.0 * k33),
            1e-12 * scale,
        );
        assert_eq!(r.stats.attempts, 0);
    }
}

// ------------------------------------------------------------------ sphere on a plane

/// Digest test 12, general formula: solid sphere on a fixed plane, K = diag(3.5/m, 3.5/m, 1/m):
/// u_z,f = −e·u_z0, p_z = m(1+e)(−u_z0), |u_t,f| = max(0, |u_t0| − 3.5μ(1+e)(−u_z0)) along û_t0,
/// p_t = (2m/7)(u_t,f − u_t0); sticking at p_z* = 2m|u_t0|/(7μ) if that comes first.
fn sphere_expected(m: f64, u0: DVec3, mu: f64, e: f64) -> (DVec3, DVec3, Option<f64>) {
    let ut0 = DVec3::new(u0.x, u0.y, 0.0);
    let s0 = ut0.length();
    let s_f = (s0 - 3.5 * mu * (1.0 + e) * (-u0.z)).max(0.0);
    let utf = if s0 > 0.0 { ut0 * (s_f / s0) } else { ut0 };
    let pz = m * (1.0 + e) * (-u0.z);
    let pt = (utf - ut0) * (2.0 * m / 7.0);
    let stick = 2.0 * m * s0 / (7.0 * mu);
    (
        DVec3::new(pt.x, pt.y, pz),
        DVec3::new(utf.x, utf.y, -e * u0.z),
        (stick < pz).then_some(stick),
    )
}

#[test]
fn sphere_on_plane_matches_analytic_results() {
    let (m, radius) = (2.0, 0.5);
    let i = DMat3::IDENTITY * (0.4 * m * radius * radius);
    let frame = ContactFrame::from_normal(DVec3::Z).unwrap();
    let k = CollisionMatrix::rigid(
        &Body::moving(m, i).unwrap(),
        DVec3::new(0.0, 0.0, -radius),
        &Body::Fixed,
        DVec3::ZERO,
        &frame,
    )
    .unwrap();
    let u0 = DVec3::new(0.6, 0.8, -1.0);
    let s = Settings::default();
    // μ = 0.1, e = 0.5: slides throughout.
    let r = resolve(&k, u0, 0.1, 0.5, Restitution::Stronge, &s).unwrap();
    near_v(r.velocity, DVec3::new(0.285, 0.380, 0.5), 1e-9);
    near_v(r.impulse, DVec3::new(-0.18, -0.24, 3.0), 1e-9);
    near(r.work, -0.97125, 1e-9);
    assert!(r.sticking.is_none());
    // Constant direction, sliding throughout: on the cone's edge (digest test 11).
    near(r.impulse.truncate().length(), 0.1 * r.impulse.z, 1e-12);
    // μ = 0.5: sticks at p_z* = 8/7 during compression (p_mc = 2).
    let r = resolve(&k, u0, 0.5, 0.5, Restitution::Stronge, &s).unwrap();
    near_v(
        r.impulse,
        DVec3::new(-0.6 * 4.0 / 7.0, -0.8 * 4.0 / 7.0, 3.0),
        1e-9,
    );
    assert_eq!((r.velocity.x, r.velocity.y), (0.0, 0.0)); // no chatter residual
    near(r.velocity.z, 0.5, 1e-9);
    near(r.work, -29.0 / 28.0, 1e-9);
    let st = r.sticking.unwrap();
    assert!(st.stable && st.phase == Phase::Compression);
    near(st.normal_impulse, 8.0 / 7.0, 1e-9);
    near(r.max_compression_impulse, 2.0, 1e-9);
    // Independent bookkeeping: the applied impulse brings the body's contact point to rest
    // tangentially (v + ω × r from Newton–Euler).
    let v = u0 + DVec3::new(0.0, 0.0, 0.0);
    let w = DVec3::ZERO;
    let rr = DVec3::new(0.0, 0.0, -radius);
    let v1 = v + r.impulse / m;
    let w1 = w + i.inverse() * rr.cross(r.impulse);
    let uf = v1 + w1.cross(rr);
    assert!(uf.truncate().length() < 1e-12, "{uf}");

    // Random spheres, μ, e: all against the general formula.
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(63);
    for _ in 0..2000 {
        let m = 10f64.powf(rng.random_range(-1.0..1.0));
        let kk = DMat3::from_diagonal(DVec3::new(3.5 / m, 3.5 / m, 1.0 / m));
        let u0 = random_approach(&mut rng);
        let mu = rng.random_range(0.0..1.5);
        let e = rng.random_range(0.0..=1.0);
        let r = stronge(kk, u0, mu, e);
        let (p, u, stick) = sphere_expected(m, u0, mu, e);
        let scale = u0.length();
        near_v(r.velocity, u, 1e-9 * scale);
        near_v(r.impulse, p, 1e-9 * scale * m);
        match (stick, r.sticking) {
            (Some(a), Some(b)) => near(a, b.normal_impulse, 1e-9 * scale * m),
            (None, None) => {}
            (a, b) if mu == 0.0 => assert!(a.is_none() || b.is_none()),
            (a, b) => {
                // Sticking right at the end: the two may disagree only on the boundary.
                let pz = p.z;
                assert!(
                    a.is_some_and(|x| (x - pz).abs() < 1e-9 * pz) || b.is_some(),
                    "{a:?} {b:?}"
                );
            }
        }
    }
}

// ------------------------------------------------------------------ restitution laws

/// Digest test 8: Newton's law creates energy (+146 % of KE₀) where Stronge's does not.
/// Planar, y decoupled: `K = [[2.1, 0, 1], [0, 1, 0], [1, 0, 0.8]]`, μ = 0.5, e = 1,
/// u₀ = (−1.3, 0, −1). Closed form: sliding with ξ = (0.5, 0, 1), du/dp_z = (2.05, 0, 1.3) until
/// u_x = 0 at p_z = 1.3/2.05; sticking is stable (1/2.1 ≤ 0.5) with du_z/dp_z = σ = 0.8 − 1/2.1.
#[test]
fn newton_creates_energy_stronge_does_not() {
    let k = sym(2.1, 1.0, 0.8, 0.0, 1.0, 0.0);
    let u0 = DVec3::new(-1.3, 0.0, -1.0);
    let (mu, e) = (0.5, 1.0);
    let c = cm(k);
    let ke0 = 0.5 * u0.dot(c.inverse() * u0);
    near(ke0, 0.626471, 5e-7);
    // Closed forms.
    let p_stick: f64 = 1.3 / 2.05;
    let uz_stick = -1.0 + 1.3 * p_stick;
    let sigma: f64 = 0.8 - 1.0 / 2.1;
    let wc = -p_stick + 0.5 * 1.3 * p_stick * p_stick - uz_stick * uz_stick / (2.0 * sigma);
    let uzf = (2.0 * sigma * (-wc)).sqrt();

    let s = stronge(k, u0, mu, e);
    near(s.sticking.unwrap().normal_impulse, p_stick, 1e-12);
    near(s.compression_work, wc, 1e-12);
    near_v(s.velocity, DVec3::new(0.0, 0.0, uzf), 1e-12);
    near_v(s.impulse, c.inverse() * (s.velocity - u0), 1e-11);
    // The digest's numbers.
    near(s.sticking.unwrap().normal_impulse, 0.63415, 5e-6);
    near(uz_stick, -0.17561, 5e-6);
    near(s.max_compression_impulse, 1.17647, 5e-6);
    near(s.compression_work, -0.420373, 5e-7);
    near(s.velocity.z, 0.521768, 5e-7);
    near_v(s.impulse, DVec3::new(-0.708482, 0.0, 2.787812), 5e-7);
    near(s.work, -0.206098, 5e-7);
    near(s.work / ke0, -0.329, 5e-4);
    assert!(s.work < 0.0);
    // Newton: u_z,f = −e·u_z0 = 1 on the same path gives W = +0.917647, +146 %.
    let n = solve(k, u0, mu, e, Restitution::Newton);
    near_v(n.velocity, DVec3::new(0.0, 0.0, 1.0), 1e-12);
    near(n.work, 0.917647, 5e-7);
    near(n.work / ke0, 1.46478, 5e-5);
    assert!(n.work > 1.4 * ke0);
    // And the same gain measured independently from the bodies' point of view: Theorem 11.
    near(c.work_between(u0, n.velocity), n.work, 1e-10);
    // Poisson: p_z,f = 2·p_mc.
    let p = solve(k, u0, mu, e, Restitution::Poisson);
    near(p.velocity.z, 0.380952, 5e-7);
    near(p.impulse.z, 2.352941, 5e-7);
    near(p.impulse.z, 2.0 * p.max_compression_impulse, 1e-12);
    near(p.work, -0.402381, 5e-7);
    // The reference solver agrees on all three.
    for (law, r) in [
        (Restitution::Stronge, &s),
        (Restitution::Newton, &n),
        (Restitution::Poisson, &p),
    ] {
        let rf = reference_resolve(k, u0, mu, e, law, DEFAULT_REFERENCE_STEPS);
        near_v(r.velocity, rf.velocity, 1e-9);
        near_v(r.impulse, rf.impulse, 1e-9);
    }
}

/// Digest test 7 and Theorem 12: at the end W_z = (1 − e²)·W_c; for e = 0 the collision ends
/// at u_z = 0 exactly; always u_z,f ≥ 0 and p_z > 0. Also Theorems 10/11: the work accumulated
/// along the path equals the closed form ½(u_f + u₀)ᵀK⁻¹(u_f − u₀) (digest test 10).
#[test]
fn stronge_termination_and_path_independence() {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(64);
    for i in 0..3000 {
        let k = random_spd(&mut rng);
        let u0 = random_approach(&mut rng);
        let mu = rng.random_range(0.0..1.5);
        let e = if i % 5 == 0 {
            0.0
        } else {
            rng.random_range(0.0..=1.0)
        };
        let r = resolve(
            &cm(k),
            u0,
            mu,
            e,
            Restitution::Stronge,
            &Settings::default(),
        )
        .unwrap_or_else(|err| panic!("{err}: K={k:?} u0={u0:?} mu={mu} e={e}"));
        let c = cm(k);
        let escale = u0.length_squared() / k.z_axis.z;
        near(
            r.normal_work,
            (1.0 - e * e) * r.compression_work,
            1e-9 * escale,
        );
        assert!(r.compression_work < 0.0);
        assert!(r.impulse.z > 0.0);
        assert!(r.velocity.z >= 0.0);
        if e == 0.0 {
            assert_eq!(r.velocity.z, 0.0);
        }
        // ∫u·dp is carried along without its own error control: integration accuracy only.
        near(r.path_work, r.work, 1e-6 * escale);
        near(c.work_between(u0, r.velocity), r.work, 1e-8 * escale);
        assert!(r.work <= 1e-12 * escale, "{}", r.work);
    }
}

/// Digest test 17: whenever the sliding direction is constant throughout (stable sticking from
/// the start, a ray from the start, frictionless, sphere-on-plane), Newton's law holds exactly
/// under Stronge's: u_z,f = −e·u_z0; and then Poisson agrees too.
#[test]
fn constant_direction_obeys_newton() {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(65);
    let (mut n_stick, mut n_ray) = (0, 0);
    for _ in 0..2000 {
        let k = random_spd(&mut rng);
        let mu = rng.random_range(0.01..1.5);
        let e = rng.random_range(0.0..=1.0);
        let uz = -rng.random_range(0.1..3.0);
        let u0 = DVec3::new(0.0, 0.0, uz);
        let r = stronge(k, u0, mu, e);
        near(r.velocity.z, -e * uz, 1e-12 * uz.abs());
        let p = solve(k, u0, mu, e, Restitution::Poisson);
        near_v(p.impulse, r.impulse, 1e-12 * r.impulse.length());
        let st = r.sticking.unwrap();
        assert_eq!(st.normal_impulse, 0.0);
        if st.stable {
            n_stick += 1;
            assert_eq!(r.velocity.truncate(), glam::DVec2::ZERO);
            // p = (1+e)(−u_z0)·(K⁻¹_13, K⁻¹_23, K⁻¹_33) (eq. 3.6).
            let ki = cm(k).inverse().z_axis;
            near_v(
                r.impulse,
                ki * ((1.0 + e) * -uz),
                1e-12 * r.impulse.length(),
            );
        } else {
            n_ray += 1;
            let beta = st.ray.unwrap();
            // The tangential velocity leaves along β.
            if e > 0.0 {
                let ang = r.velocity.y.atan2(r.velocity.x);
                near((ang - beta).sin(), 0.0, 1e-9);
                assert!((ang - beta).cos() > 0.0);
            }
            near(
                r.impulse.truncate().length(),
                mu * r.impulse.z,
                1e-12 * r.impulse.z,
            );
        }
        // Sliding from the start on a ray: constant direction as well.
        let rs = rays(&k, mu);
        for ray in rs.as_slice() {
            if ray.normal_slope < 0.05 * k.z_axis.z {
                continue;
            }
            let (s, c) = ray.theta.sin_cos();
            // Start far out on the ray so a converging one is not reached.
            let u0 = DVec3::new(c * 50.0, s * 50.0, uz);
            let r = stronge(k, u0, mu, e);
            if r.sticking.is_none() {
                near(r.velocity.z, -e * uz, 1e-9 * u0.length());
            }
        }
    }
    assert!(n_stick > 100 && n_ray > 100, "{n_stick} {n_ray}");
}

// ------------------------------------------------------------------ Fig. 3.3 and the θ = π case

/// Digest test 14: Fig. 3.3's K from rest, μ = 0.2 (unstable: leaves along β = −71.113°) and
/// μ = 0.5 (stable), e = 0.5.
#[test]
fn figure_3_3_collisions() {
    let k = sym(8.0, 3.0, 5.0, -2.0, 1.0, -1.0);
    let u0 = DVec3::new(0.0, 0.0, -1.0);
    let r = stronge(k, u0, 0.2, 0.5);
    let st = r.sticking.unwrap();
    assert!(!st.stable);
    near(st.ray.unwrap().to_degrees(), -71.113, 5e-4);
    near(normal_slope(&k, 0.2, st.ray.unwrap()), 4.746027, 5e-7);
    near_v(r.velocity, DVec3::new(0.032745, -0.095708, 0.5), 5e-7);
    near_v(r.impulse, DVec3::new(-0.020462, 0.059807, 0.316054), 5e-7);
    near(r.compression_work, -0.105351, 5e-7);
    near(r.work, -0.082210, 5e-7);
    let rf = reference_resolve(
        k,
        u0,
        0.2,
        0.5,
        Restitution::Stronge,
        DEFAULT_REFERENCE_STEPS,
    );
    near_v(r.velocity, rf.velocity, 1e-9);
    near_v(r.impulse, rf.impulse, 1e-9);

    let r = stronge(k, u0, 0.5, 0.5);
    assert!(r.sticking.unwrap().stable);
    let ki = cm(k).inverse();
    near_v(r.velocity, DVec3::new(0.0, 0.0, 0.5), 1e-12);
    near_v(r.impulse, ki.z_axis * 1.5, 1e-12);
    near_v(r.impulse, DVec3::new(-0.016129, 0.096774, 0.322581), 5e-7);
    near(r.compression_work, -0.5 * ki.z_axis.z, 1e-12);
    near(r.compression_work, -0.107527, 5e-7);
}

/// Digest test 16: `K = [[2,0,−1],[0,3,0],[−1,0,4]]`, μ = 0.3, e = 0.5 from rest: unstable, the
/// only diverging ray is θ = π. Closed form: ξ = (0.3, 0, 1), K·ξ = (−0.4, 0, 3.7), p_z =
/// 1.5/3.7. Starting from u_t = (1e−6, ±1e−6) gives the same result to 1e−6.
#[test]
fn ray_at_180_degrees_collision() {
    let k = sym(2.0, 3.0, 4.0, 0.0, -1.0, 0.0);
    let (mu, e) = (0.3, 0.5);
    let u0 = DVec3::new(0.0, 0.0, -1.0);
    let r = stronge(k, u0, mu, e);
    let pz = 1.5 / 3.7;
    near_v(r.impulse, DVec3::new(0.3 * pz, 0.0, pz), 1e-12);
    near_v(r.velocity, DVec3::new(-0.4 * pz, 0.0, 0.5), 1e-12);
    near_v(r.velocity, DVec3::new(-0.162162, 0.0, 0.5), 5e-7);
    near_v(r.impulse, DVec3::new(0.121622, 0.0, 0.405405), 5e-7);
    near(r.work, -0.111213, 5e-7);
    near(r.impulse.x, mu * r.impulse.z, 1e-12); // on the cone
    near(
        r.sticking.unwrap().ray.unwrap().abs(),
        std::f64::consts::PI,
        1e-12,
    );
    for sy in [1.0, -1.0] {
        let u1 = DVec3::new(1e-6, sy * 1e-6, -1.0);
        let r1 = stronge(k, u1, mu, e);
        near_v(r1.velocity, r.velocity, 1e-6);
        near_v(r1.impulse, r.impulse, 1e-6);
        let rf = reference_resolve(k, u1, mu, e, Restitution::Stronge, DEFAULT_REFERENCE_STEPS);
        near_v(r1.velocity, rf.velocity, 1e-8);
    }
}

/// Digest test 18: the sliding speed can grow during a collision (Fig. 3.3/3.4).
#[test]
fn sliding_speed_can_increase() {
    let k = sym(8.0, 3.0, 5.0, -2.0, 1.0, -1.0);
    let u0 = DVec3::new(0.3, -0.2, -2.0);
    let r = stronge(k, u0, 0.2, 0.7);
    assert!(r.sticking.is_none());
    near_v(r.velocity, DVec3::new(0.162989, -0.408778, 1.402660), 5e-7);
    near_v(r.impulse, DVec3::new(-0.077417, 0.118715, 0.719758), 5e-7);
    near(r.work, -0.269028, 5e-7);
    assert!(r.velocity.truncate().length() > 0.44 && u0.truncate().length() < 0.361);
    let rf = reference_resolve(
        k,
        u0,
        0.2,
        0.7,
        Restitution::Stronge,
        DEFAULT_REFERENCE_STEPS,
    );
    near_v(r.velocity, rf.velocity, 1e-9);
    near_v(r.impulse, rf.impulse, 1e-9);
    let u0 = DVec3::new(1.0, 1.0, -1.0);
    let r = stronge(k, u0, 0.2, 0.7);
    near_v(r.velocity, DVec3::new(1.001292, 0.636928, 0.697123), 5e-7);
    near(r.work, -0.139844, 5e-7);
}

/// Digest test 19 (Theorem 17): the impulse first drives the bodies together
/// (k_z·ξ(θ₀) < 0). The solver integrates in p_z until u_z turns, ends with u_z,f ≥ 0, W ≤ 0,
/// and matches the reference.
#[test]
fn initially_decreasing_normal_velocity() {
    // c − μ·e·cos θ₀ = 0.6 − 1.0 < 0 for θ₀ = 0.
    let k = sym(3.0, 2.0, 0.6, 0.0, 1.0, 0.0);
    let mu = 1.0;
    for u0 in [
        DVec3::new(1.0, 0.0, -0.5),
        DVec3::new(1.0, 0.3, -0.5),
        DVec3::new(2.0, -0.5, -0.1),
    ] {
        let th0 = u0.y.atan2(u0.x);
        assert!(normal_slope(&k, mu, th0) < 0.0);
        for e in [0.0, 0.5, 1.0] {
            let r = stronge(k, u0, mu, e);
            // Either p_z steps, or (u₀ on the converging ray θ = 0) the closed-form approach.
            assert!(r.stats.normal_impulse_steps > 0 || r.stats.ray_approaches > 0);
            assert!(r.velocity.z >= 0.0 && r.work <= 0.0);
            let rf = reference_resolve(k, u0, mu, e, Restitution::Stronge, DEFAULT_REFERENCE_STEPS);
            near_v(r.velocity, rf.velocity, 1e-7);
            near_v(r.impulse, rf.impulse, 1e-7);
        }
    }
}

// ------------------------------------------------------------------ production vs reference

/// Digest tests 20 and 21: on random K, μ, e, u₀ and all three laws, `resolve` matches the
/// simple p_z reference solver to 1e-6 (relative to |u₀| and |p|); Lemma 3 cases (G > 0) never
/// let the extension reach W_f, and G ≤ 0 cases take the fallback and still match.
#[test]
fn production_matches_reference() {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(66);
    let mut worst = 0.0f64;
    let (mut g_neg, mut stable, mut ray, mut slide, mut decreasing, mut recompress) =
        (0, 0, 0, 0, 0, 0);
    for i in 0..400 {
        let k = random_spd(&mut rng);
        let mut u0 = random_approach(&mut rng);
        match i % 8 {
            // From rest tangentially, or nearly: sticking (stable or not) from the start.
            0 => (u0.x, u0.y) = (0.0, 0.0),
            1 => (u0.x, u0.y) = (u0.x * 1e-3, u0.y * 1e-3),
            _ => {}
        }
        let mu = rng.random_range(0.0..1.5);
        let e = rng.random_range(0.0..=1.0);
        let law = [
            Restitution::Stronge,
            Restitution::Stronge,
            Restitution::Poisson,
            Restitution::Newton,
        ][i % 4];
        let r = solve(k, u0, mu, e, law);
        let rf = reference_resolve(k, u0, mu, e, law, 2000);
        assert!(!rf.truncated);
        let du = (r.velocity - rf.velocity).length() / u0.length();
        let dp = (r.impulse - rf.impulse).length() / r.impulse.length();
        worst = worst.max(du).max(dp);
        assert!(
            du < 1e-6 && dp < 1e-6,
            "case {i}: {k} u0={u0} μ={mu} e={e} {law:?}\n{r:?}\n{rf:?}"
        );
        let c = cm(k);
        if c.lemma3_slope(mu) <= 0.0 {
            g_neg += 1;
        } else {
            assert!(!r.stats.extension_reached_final_work, "case {i}");
        }
        if mu > 0.0 && normal_slope(&k, mu, u0.y.atan2(u0.x)) <= 0.0 {
            decreasing += 1;
        }
        if r.stats.compressions > 1 {
            recompress += 1;
        }
        match r.sticking {
            None => slide += 1,
            Some(s) if s.stable => stable += 1,
            Some(_) => ray += 1,
        }
    }
    eprintln!(
        "production vs reference: worst rel. diff {worst:.2e}; sliding {slide}, stable sticking \
         {stable}, ray {ray}; G ≤ 0 {g_neg}; initially decreasing u_z {decreasing}; \
         recompressions {recompress}"
    );
    assert!(g_neg > 10 && stable > 10 && ray > 10 && slide > 10);
}

// ------------------------------------------------------------------ rigid bodies, 10⁵ cases

struct RigidCase {
    m: [f64; 2],
    inertia: [DMat3; 2],
    fixed2: bool,
    r: [DVec3; 2],
    x: [DVec3; 2],
    v: [DVec3; 2],
    w: [DVec3; 2],
    normal: DVec3,
}

impl RigidCase {
    /// Relative contact velocity in the contact frame.
    fn u0(&self, frame: &ContactFrame) -> DVec3 {
        let (v, w, r) = (self.v, self.w, self.r);
        frame.to_contact(relative_contact_velocity(
            v[0], w[0], r[0], v[1], w[1], r[1],
        ))
    }

    /// The collision matrix of the two bodies (the second fixed when `fixed2`).
    fn matrix(&self, frame: &ContactFrame) -> CollisionMatrix {
        let b1 = Body::moving(self.m[0], self.inertia[0]).unwrap();
        let b2 = if self.fixed2 {
            Body::Fixed
        } else {
            Body::moving(self.m[1], self.inertia[1]).unwrap()
        };
        CollisionMatrix::rigid(&b1, self.r[0], &b2, self.r[1], frame).unwrap()
    }
}

fn random_rigid_case(rng: &mut Xoshiro256PlusPlus) -> RigidCase {
    let mut m = [0.0; 2];
    let mut inertia = [DMat3::ZERO; 2];
    for b in 0..2 {
        (m[b], inertia[b]) = random_body(rng);
    }
    let fixed2 = rng.random_range(0.0..1.0) < 0.1;
    let contact = DVec3::new(
        rng.random_range(-2.0..2.0),
        rng.random_range(-2.0..2.0),
        rng.random_range(-2.0..2.0),
    );
    let r = [
        unit(rng) * rng.random_range(0.1..1.5),
        unit(rng) * rng.random_range(0.1..1.5),
    ];
    let x = [contact - r[0], contact - r[1]];
    // Speeds scaled so each body's kinetic energy is O(1).
    let s = [1.0 / m[0].sqrt(), 1.0 / m[1].sqrt()];
    let mut v = [unit(rng) * s[0], unit(rng) * s[1]];
    let mut w = [unit(rng) * s[0], unit(rng) * s[1]];
    if fixed2 {
        v[1] = DVec3::ZERO;
        w[1] = DVec3::ZERO;
    }
    let normal = unit(rng);
    // Approaching: if not, reverse every velocity.
    let u = relative_contact_velocity(v[0], w[0], r[0], v[1], w[1], r[1]);
    if u.dot(normal) > 0.0 {
        for i in 0..2 {
            v[i] = -v[i];
            w[i] = -w[i];
        }
    }
    RigidCase {
        m,
        inertia,
        fixed2,
        r,
        x,
        v,
        w,
        normal,
    }
}

fn kinetic(c: &RigidCase, v: &[DVec3; 2], w: &[DVec3; 2]) -> f64 {
    let mut ke = 0.5 * c.m[0] * v[0].length_squared() + 0.5 * w[0].dot(c.inertia[0] * w[0]);
    if !c.fixed2 {
        ke += 0.5 * c.m[1] * v[1].length_squared() + 0.5 * w[1].dot(c.inertia[1] * w[1]);
    }
    ke
}

/// ≥ 10⁵ random rigid-body collisions (mass ratios 1e-4…1e4, inertia ratios to 1:100, random
/// offsets and normals, 10 % against a fixed body, μ ∈ [0, 2], e ∈ [0, 1] with exact 0 and 1
/// and μ = 0 and u_t0 = 0 mixed in). Independent rigid-body check: apply ±p to the bodies by
/// Newton–Euler (inertia inverted here) and measure: kinetic energy never increases beyond
/// 1e-12 relative; linear and angular momentum conserved to rounding; the final normal
/// relative velocity recomputed from the bodies is ≥ −1e-12·(velocity scale); |p_t| ≤ μ·p_z
/// to rounding; bounded step counts (max and mean printed).
#[test]
fn random_rigid_collisions() {
    const CASES: usize = 100_000;
    /// Relative tolerance on the recomputed final normal velocity (rounding of v + ω × r).
    const SEPARATION_TOL_REL: f64 = 1e-12;
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(67);
    let s = Settings::default();
    let (mut max_gain, mut max_gain_rel_collision) = (f64::NEG_INFINITY, f64::NEG_INFINITY);
    let mut max_w_rel = f64::NEG_INFINITY;
    let (mut max_dp, mut max_dl, mut max_cone, mut min_uz) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    let (mut max_grazing_gain, mut grazing_n) = (0.0f64, 0u32);
    let (mut max_steps, mut sum_steps, mut max_evals) = (0usize, 0usize, 0usize);
    let (mut g_neg, mut decreasing, mut stuck, mut rays_n, mut recompress, mut pz_used) =
        (0, 0, 0, 0, 0, 0);
    let mut done = 0;
    let start = std::time::Instant::now();
    while done < CASES {
        let mut c = random_rigid_case(&mut rng);
        let mu = match rng.random_range(0..10) {
            0 => 0.0,
            _ => rng.random_range(0.0..2.0),
        };
        let e = match rng.random_range(0..10) {
            0 => 0.0,
            1 => 1.0,
            _ => rng.random_range(0.0..=1.0),
        };
        let frame = ContactFrame::from_normal(c.normal).unwrap();
        if rng.random_range(0..20) == 0 {
            // u_t0 = 0 exactly (to rounding): shift body 1 by the tangential part.
            let u = relative_contact_velocity(c.v[0], c.w[0], c.r[0], c.v[1], c.w[1], c.r[1]);
            c.v[0] -= u - c.normal * u.dot(c.normal);
        }
        let grazing = rng.random_range(0..20) == 0;
        if grazing {
            // A grazing contact (resting contact in a simulation): the normal approach is
            // 1e-6 … 1e-15 of the sliding speed. Shift body 1 along the normal.
            let u = relative_contact_velocity(c.v[0], c.w[0], c.r[0], c.v[1], c.w[1], c.r[1]);
            let un = u.dot(c.normal);
            let target = -u.length() * 10f64.powf(-rng.random_range(6.0..15.0));
            c.v[0] += c.normal * (target - un);
        }
        let u0 = c.u0(&frame);
        if u0.z.is_nan() || u0.z >= 0.0 || (!grazing && u0.z >= -1e-6 * u0.length()) {
            continue;
        }
        let k = c.matrix(&frame);
        let res = resolve(&k, u0, mu, e, Restitution::Stronge, &s)
            .unwrap_or_else(|err| panic!("case {done}: {err}; K={} u0={u0} μ={mu} e={e}", k.k()));
        done += 1;
        // Bookkeeping of the algorithm.
        max_steps = max_steps.max(res.stats.attempts);
        sum_steps += res.stats.attempts;
        max_evals = max_evals.max(res.stats.evaluations);
        if k.lemma3_slope(mu) <= 0.0 {
            g_neg += 1;
        } else {
            // Lemma 3: the extension never reaches the final normal work by itself.
            assert!(!res.stats.extension_reached_final_work);
        }
        if mu > 0.0
            && u0.truncate().length() > 0.0
            && normal_slope(&k.k(), mu, u0.y.atan2(u0.x)) <= 0.0
        {
            decreasing += 1;
        }
        match res.sticking {
            Some(st) if st.stable => stuck += 1,
            Some(_) => rays_n += 1,
            None => {}
        }
        if res.stats.compressions > 1 {
            recompress += 1;
        }
        if res.stats.normal_impulse_steps > 0 {
            pz_used += 1;
        }
        // Friction cone, in the collision frame.
        let p = res.impulse;
        let excess = p.truncate().length() - mu * p.z;
        max_cone = max_cone.max(excess / p.length());
        assert!(excess <= 1e-14 * p.length(), "cone: {p} μ={mu}");
        // Independent rigid-body check.
        let pw = frame.to_world(p);
        let (i1, i2) = (c.inertia[0].inverse(), c.inertia[1].inverse());
        let mut v = c.v;
        let mut w = c.w;
        v[0] += pw / c.m[0];
        w[0] += i1 * c.r[0].cross(pw);
        if !c.fixed2 {
            v[1] += -pw / c.m[1];
            w[1] += i2 * c.r[1].cross(-pw);
        }
        let ke0 = kinetic(&c, &c.v, &c.w);
        let ke1 = kinetic(&c, &v, &w);
        let gain = (ke1 - ke0) / ke0;
        max_gain = max_gain.max(gain);
        // The same change summed body by body (m·v·Δv + ½m|Δv|² + ω·IΔω + ½ΔωᵀIΔω), which
        // avoids the cancellation of the bulk motion's energy, relative to the energy of the
        // relative motion at the contact, ½u₀ᵀK⁻¹u₀.
        let mut dke = 0.0;
        for b in 0..if c.fixed2 { 1 } else { 2 } {
            let (dv, dw) = (v[b] - c.v[b], w[b] - c.w[b]);
            dke += c.m[b] * (c.v[b].dot(dv) + 0.5 * dv.length_squared())
                + c.w[b].dot(c.inertia[b] * dw)
                + 0.5 * dw.dot(c.inertia[b] * dw);
        }
        let e_rel = 0.5 * u0.dot(k.inverse() * u0);
        max_w_rel = max_w_rel.max(res.work / e_rel);
        if grazing {
            // The relative motion's energy is ~1e-20 of the bodies' here: judged against
            // the total kinetic energy below (and the algorithm's own W must not be positive).
            max_grazing_gain = max_grazing_gain.max(dke / e_rel);
            assert!(
                res.work <= 1e-9 * e_rel,
                "grazing: W = {:e} of e_rel",
                res.work / e_rel
            );
            grazing_n += 1;
        } else {
            max_gain_rel_collision = max_gain_rel_collision.max(dke / e_rel);
        }
        assert!(
            grazing || dke <= 1e-9 * e_rel,
            "energy gain {:e} of ½u₀ᵀK⁻¹u₀; K={:?} u0={u0:?} μ={mu} e={e} grazing {grazing} p={p} kind {:?} sticking {:?}",
            dke / e_rel,
            k.k().to_cols_array(),
            res.kind,
            res.sticking
        );
        assert!(
            gain <= 1e-12,
            "energy gain {gain:e}: K={} u0={u0} μ={mu} e={e}",
            k.k()
        );
        let uf = relative_contact_velocity(v[0], w[0], c.r[0], v[1], w[1], c.r[1]);
        let vscale = c.v[0].length()
            + c.w[0].length() * c.r[0].length()
            + c.v[1].length()
            + c.w[1].length() * c.r[1].length()
            + uf.length();
        let uzf = uf.dot(c.normal) / vscale;
        min_uz = min_uz.min(uzf);
        assert!(uzf >= -SEPARATION_TOL_REL, "u_z,f = {uzf:e}");
        if !c.fixed2 {
            let mom = |v: &[DVec3; 2]| v[0] * c.m[0] + v[1] * c.m[1];
            let ang = |v: &[DVec3; 2], w: &[DVec3; 2]| {
                c.x[0].cross(v[0] * c.m[0])
                    + c.inertia[0] * w[0]
                    + c.x[1].cross(v[1] * c.m[1])
                    + c.inertia[1] * w[1]
            };
            let pscale = (c.v[0] * c.m[0]).length() + (c.v[1] * c.m[1]).length() + pw.length();
            let dp = (mom(&v) - mom(&c.v)).length() / pscale;
            let lscale = pscale * (c.x[0].length() + c.x[1].length() + 1.0)
                + (c.inertia[0] * c.w[0]).length()
                + (c.inertia[1] * c.w[1]).length();
            let dl = (ang(&v, &w) - ang(&c.v, &c.w)).length() / lscale;
            max_dp = max_dp.max(dp);
            max_dl = max_dl.max(dl);
            assert!(dp < 1e-15 && dl < 1e-14, "momentum: {dp:e} {dl:e}");
        }
    }
    let mean = sum_steps as f64 / CASES as f64;
    eprintln!(
        "{CASES} random rigid collisions in {:.1?}: steps (RK attempts) max {max_steps}, mean \
         {mean:.2}; max RHS evaluations {max_evals}; max KE gain {max_gain:.2e} of total KE, \
         {max_gain_rel_collision:.2e} of the relative-motion energy ½u₀ᵀK⁻¹u₀ (body by body; \
         {grazing_n} grazing cases, judged on total KE, reach {max_grazing_gain:.2e} of it), \
         algorithm's W = u₀·p + ½pᵀKp at most {max_w_rel:.2e} of it; max |ΔP| \
         {max_dp:.2e}, max |ΔL| {max_dl:.2e} (relative); min u_z,f {min_uz:.2e} (relative); max \
         cone excess {max_cone:.2e}; Lemma 3 violated (G ≤ 0) {g_neg}; initially decreasing u_z \
         {decreasing}; stable sticking {stuck}; diverging ray {rays_n}; recompressions \
         {recompress}; p_z steps used in {pz_used}",
        start.elapsed()
    );
    assert!(max_steps < tol::MAX_STEPS);
    assert!(g_neg > 1000 && decreasing > 100, "{g_neg} {decreasing}");
}

/// The rare Lemma-3-violating collisions whose u_z falls back to 0 during restitution (second
/// compression, \[not in the thesis\]: W_c is taken at the last maximum compression) agree with
/// the reference solver, which implements that rule independently.
#[test]
fn recompression_matches_reference() {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(69);
    let s = Settings::default();
    let mut found = 0;
    for _ in 0..200_000 {
        let c = random_rigid_case(&mut rng);
        let mu = rng.random_range(1.0..2.0);
        let e = rng.random_range(0.0..=1.0);
        let frame = ContactFrame::from_normal(c.normal).unwrap();
        let u0 = c.u0(&frame);
        if u0.z.is_nan() || u0.z >= -1e-6 * u0.length() {
            continue;
        }
        let k = c.matrix(&frame);
        if k.lemma3_slope(mu) > 0.0 {
            continue;
        }
        let r = resolve(&k, u0, mu, e, Restitution::Stronge, &s).unwrap();
        if r.stats.compressions < 2 {
            continue;
        }
        found += 1;
        let rf = reference_resolve(
            k.k(),
            u0,
            mu,
            e,
            Restitution::Stronge,
            DEFAULT_REFERENCE_STEPS,
        );
        assert!(!rf.truncated);
        near_v(r.velocity, rf.velocity, 1e-6 * u0.length());
        near_v(r.impulse, rf.impulse, 1e-6 * r.impulse.length());
        near(
            r.compression_work,
            rf.compression_work,
            1e-6 * r.compression_work.abs(),
        );
        if found == 5 {
            break;
        }
    }
    assert!(found >= 3, "only {found} recompression cases found");
}

// ------------------------------------------------------------------ singular K, errors, trace

/// A rank-2 K (a planar mechanism: the y direction cannot move) with u_y0 = 0 gives the same
/// collision as any full-rank K with the same x–z block and a decoupled y; with u_y0 ≠ 0 the
/// y velocity never changes.
#[test]
fn singular_planar_k_matches_full_rank_planar_problem() {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(68);
    let mut n = 0;
    while n < 300 {
        let (a, c): (f64, f64) = (rng.random_range(0.2..3.0), rng.random_range(0.2..3.0));
        let e_ = rng.random_range(-1.0..1.0) * (a * c).sqrt() * 0.95;
        let singular = sym(a, 0.0, c, 0.0, e_, 0.0);
        let full = sym(a, rng.random_range(0.5..2.0), c, 0.0, e_, 0.0);
        let Ok(cs) = CollisionMatrix::new(singular) else {
            continue;
        };
        assert_eq!(cs.rank(), 2);
        n += 1;
        let mu = rng.random_range(0.0..1.5);
        let e = rng.random_range(0.0..=1.0);
        let u0 = DVec3::new(
            rng.random_range(-2.0..2.0),
            0.0,
            -rng.random_range(0.1..2.0),
        );
        let s = Settings::default();
        let r1 = resolve(&cs, u0, mu, e, Restitution::Stronge, &s).unwrap();
        let r2 = stronge(full, u0, mu, e);
        near_v(r1.velocity, r2.velocity, 1e-9 * u0.length());
        near_v(r1.impulse, r2.impulse, 1e-9 * r2.impulse.length());
        assert_eq!(r1.sticking.is_some(), r2.sticking.is_some());
        // Out-of-plane sliding: u_y cannot change.
        let u0y = DVec3::new(u0.x, 0.7, u0.z);
        let r3 = resolve(&cs, u0y, mu, e, Restitution::Stronge, &s).unwrap();
        near(r3.velocity.y, 0.7, 1e-12);
        assert!(r3.velocity.z >= 0.0 && r3.work <= 1e-12);
        assert!(r3.impulse.truncate().length() <= mu * r3.impulse.z * (1.0 + 1e-12) + 1e-15);
    }
}

#[test]
fn bad_input_is_refused_with_typed_errors() {
    let c = cm(DMat3::IDENTITY);
    let s = Settings::default();
    let u0 = DVec3::new(0.1, 0.0, -1.0);
    let law = Restitution::Stronge;
    assert!(matches!(
        resolve(&c, DVec3::new(0.0, 0.0, 0.5), 0.3, 0.5, law, &s),
        Err(ResponseError::NotApproaching { .. })
    ));
    assert!(matches!(
        resolve(&c, DVec3::new(0.0, 0.0, 0.0), 0.3, 0.5, law, &s),
        Err(ResponseError::NotApproaching { .. })
    ));
    assert!(matches!(
        resolve(&c, DVec3::new(f64::NAN, 0.0, -1.0), 0.3, 0.5, law, &s),
        Err(ResponseError::NonFinite { .. })
    ));
    for mu in [-0.1, f64::NAN, f64::INFINITY] {
        assert!(matches!(
            resolve(&c, u0, mu, 0.5, law, &s),
            Err(ResponseError::InvalidParameter { .. })
        ));
    }
    for e in [-0.1, 1.1, f64::NAN] {
        assert!(matches!(
            resolve(&c, u0, 0.3, e, law, &s),
            Err(ResponseError::InvalidParameter { .. })
        ));
    }
    let bad = Settings { rtol: 0.0, ..s };
    assert!(matches!(
        resolve(&c, u0, 0.3, 0.5, law, &bad),
        Err(ResponseError::InvalidParameter { .. })
    ));
    // The step cap is reported, never a hang.
    let k = sym(8.0, 3.0, 5.0, -2.0, 1.0, -1.0);
    let capped = Settings { max_steps: 3, ..s };
    assert_eq!(
        resolve(&cm(k), DVec3::new(0.3, -0.2, -2.0), 0.2, 0.7, law, &capped),
        Err(ResponseError::StepLimit { limit: 3 })
    );
}

/// The trace is recorded only when asked, is monotone in p_z, and goes through the phases in
/// order.
#[test]
fn trace_is_optional_and_ordered() {
    let k = sym(8.0, 3.0, 5.0, -2.0, 1.0, -1.0);
    let u0 = DVec3::new(1.0, 1.0, -1.0);
    let plain = stronge(k, u0, 0.2, 0.7);
    assert!(plain.trace.is_none());
    let s = Settings {
        record_trace: true,
        ..Settings::default()
    };
    let r = resolve(&cm(k), u0, 0.2, 0.7, Restitution::Stronge, &s).unwrap();
    assert_eq!(r.impulse, plain.impulse);
    let t = r.trace.unwrap();
    assert!(t.len() >= r.stats.accepted);
    let rank = |p: Phase| match p {
        Phase::Compression => 0,
        Phase::Extension => 1,
        Phase::Restitution => 2,
    };
    for w in t.windows(2) {
        assert!(w[1].normal_impulse >= w[0].normal_impulse);
        assert!(rank(w[1].phase) >= rank(w[0].phase));
    }
    assert!(t.iter().any(|s| s.parameter == Parameter::NormalVelocity));
    assert!(t.iter().any(|s| s.parameter == Parameter::NormalWork));
    assert!(t.iter().any(|s| s.phase == Phase::Extension));
    let last = t.last().unwrap();
    assert_eq!(last.velocity, r.velocity);
}
