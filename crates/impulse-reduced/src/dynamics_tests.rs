//! Reduced dynamics against analytic references and conservation laws.

use core::f64::consts::PI;

use glam::DVec3;

use super::*;
use crate::construct::{ConstructOptions, ReducedModel};
use crate::desc::{JointDesc, LinkDesc, MechanismDesc, ShapeDesc};
use crate::reference::Configuration;
use crate::testutil::{floating, hinge_rod};

/// The hinge's numerical frequency, from zero crossings, within 1 % of the closed form √(k/I).
const FREQUENCY_REL: f64 = 0.01;
/// Energy may not grow by more than rounding per step.
const ENERGY_ROUNDING: f64 = 1e-12;

fn sim(m: &Mechanism, h: f64) -> ReducedSim {
    let model = ReducedModel::build(
        m,
        &Configuration::rest(m),
        &[],
        &ConstructOptions::default(),
    )
    .unwrap();
    ReducedSim::new(m, model, h).unwrap()
}

#[test]
fn single_hinge_vibrates_at_sqrt_k_over_i() {
    let (c, inertia): (f64, f64) = (1e-2, 0.26);
    let omega = (1.0 / c / inertia).sqrt();
    let period = 2.0 * PI / omega;
    let m = hinge_rod(c, &[0.0]);
    let mut s = sim(&m, period / 2000.0);
    s.xi[5] = 1e-3;
    // Upward zero crossings of the hinge angle, linearly interpolated.
    let mut crossings = Vec::new();
    let mut t = 0.0;
    let mut prev = s.xi[5];
    while crossings.len() < 4 {
        s.step();
        t += s.h;
        let now = s.xi[5];
        if prev < 0.0 && now >= 0.0 {
            crossings.push(t - s.h * now / (now - prev));
        }
        prev = now;
    }
    let measured = (crossings[3] - crossings[0]) / 3.0;
    let err = (measured / period - 1.0).abs();
    println!("hinge: period {measured:.6} s, √(k/I) gives {period:.6} s, relative error {err:.2e}");
    assert!(err <= FREQUENCY_REL, "{err}");
    // Only the hinge's direction moves (rank 1).
    assert_eq!(s.model.rank, 1);
    assert!(s.xi[..5].iter().all(|x| x.abs() < 1e-12));
}

#[test]
fn backward_euler_never_gains_energy() {
    let m = hinge_rod(1e-2, &[0.0]);
    for h in [1e-3, 1e-1, 1.0] {
        let mut s = sim(&m, h);
        s.xi[5] = 1e-2;
        let e0 = s.energy();
        let mut e = e0;
        for _ in 0..200 {
            s.step();
            let en = s.energy();
            assert!(en <= e * (1.0 + ENERGY_ROUNDING), "h = {h}: {e} → {en}");
            e = en;
        }
        println!("h = {h} s: energy {e0:.3e} → {e:.3e} after 200 steps");
        assert!(e < e0);
    }
}

/// Linear momentum of the whole mechanism measured from outside the integrator: every link's
/// mass times the velocity of its centre of mass, by a forward difference over one step of the
/// link poses the simulation reconstructs (base, end effectors by eq. 6, internal links by
/// eq. 22). Returns that momentum and the scale `Σ m_l |v_l|` of the links' own motions.
fn measured_momentum(m: &Mechanism, s: &mut ReducedSim) -> (DVec3, f64) {
    let coms = |s: &ReducedSim| -> Vec<DVec3> {
        let frame = s.base.unwrap().pose * s.model.base_pose.inverse();
        let mut poses: Vec<Pose> = m.links.iter().map(|l| frame * l.rest).collect();
        poses[m.base] = s.base.unwrap().pose;
        for (i, &e) in s.model.end_effectors.iter().enumerate() {
            poses[e] = s.end_effector_pose(i);
        }
        let mut internal = vec![Pose::IDENTITY; s.model.internal.len()];
        s.internal_poses(&mut internal);
        for (k, &l) in s.model.internal.iter().enumerate() {
            poses[l] = internal[k];
        }
        m.links
            .iter()
            .zip(&poses)
            .map(|(l, p)| p.transform_point(l.inertia.com))
            .collect()
    };
    let before = coms(s);
    s.step();
    let after = coms(s);
    let mut p = DVec3::ZERO;
    let mut scale = 0.0;
    for ((l, a), b) in m.links.iter().zip(&before).zip(&after) {
        let v = (*b - *a) / s.h;
        p += v * l.inertia.mass;
        scale += l.inertia.mass * v.length();
    }
    (p, scale)
}

/// Total linear momentum may change without contact only by rounding: relative to the
/// links' momentum scale `Σ m_l |v_l|`. The forward difference of a centre of mass at
/// ~0.4 m over h = 1e-3 s carries ~ε·0.4/h ≈ 1e-13 m/s of rounding, 1e-11 of the smallest
/// scale met here (~1e-2 kg·m/s); 1e-9 leaves room and is 8 decades below the 0.12 kg·m/s
/// swing the unfixed base showed.
const MOMENTUM_REL: f64 = 1e-9;

#[test]
fn free_base_conserves_linear_momentum_without_contact() {
    let m = floating([0.0; 3]);
    // Base at rest with the tip displaced and released; then a base moving and spinning.
    for (moving, tip) in [(false, 1e-2), (true, 1e-3)] {
        let mut s = sim(&m, 1e-3);
        let inertia = s.model.base_inertia;
        if moving {
            let b = s.base.as_mut().unwrap();
            b.set_twist(
                &inertia,
                &Twist::new(DVec3::new(0.3, -0.2, 0.1), DVec3::new(1.0, 2.0, -0.5)),
            );
        }
        s.xi[1] = tip;
        let p0 = s.linear_momentum();
        let (mut worst, mut scale) = (0.0_f64, 0.0_f64);
        for _ in 0..2000 {
            let (p, sc) = measured_momentum(&m, &mut s);
            worst = worst.max((p - p0).length());
            scale = scale.max(sc);
        }
        println!(
            "free base (moving {moving}, tip {tip} m): measured Σ m·v deviates from P0 = {p0} \
             by up to {worst:e} kg·m/s (scale Σ m|v| {scale:e})"
        );
        assert!(
            worst <= MOMENTUM_REL * scale,
            "{worst:e} > {MOMENTUM_REL:e} · {scale:e}"
        );
        // The integrator's own momentum is only changed by external impulses.
        assert_eq!(s.linear_momentum(), p0);
    }
    // Under gravity the momentum falls by m g t, exactly up to rounding.
    let g = [0.0, 0.0, -9.81];
    let mut s = sim(&floating(g), 1e-3);
    let mass = s.model.base_inertia.mass;
    for _ in 0..1000 {
        s.step();
    }
    let expect = DVec3::from_array(g) * mass;
    assert!((s.linear_momentum() - expect).length() <= 1e-12 * expect.length());
}

/// A tip on a horizontal arm hinged about y, hanging over a plane: gravity pulls it down.
fn arm_over_plane(friction: f64) -> (Mechanism, ReducedSim) {
    let mut d = MechanismDesc::new("arm");
    d.gravity([0.0, 0.0, -9.81]);
    d.link(LinkDesc::new("base", [0.0; 3]))
        .link(
            LinkDesc::new("tip", [0.5, 0.0, 0.0])
                .mass(1.0, [1e-3; 3])
                .shape(ShapeDesc::Sphere {
                    radius: 0.05,
                    center: [0.0; 3],
                }),
        )
        .joint(
            JointDesc::ball("j", "base", "tip", [0.0; 3])
                .compliance(&[2e-2])
                .damping(&[0.5]),
        )
        .end_effector("tip");
    let m = d.build().unwrap();
    let mut s = sim(&m, 1e-3);
    s.obstacles.push(Obstacle::Plane {
        normal: DVec3::Z,
        offset: -0.06,
    });
    s.contact.friction = friction;
    (m, s)
}

#[test]
fn end_effector_resting_on_plane_reaches_static_solution() {
    let (m, mut s) = arm_over_plane(0.0);
    for _ in 0..20_000 {
        s.step();
    }
    // Reference: the reduced statics with the contact active and frictionless,
    // ξ = C(w + Gᵀλ), G ξ = −gap₀ (one normal row), solved in closed form.
    let c = &s.model.compliance;
    let f = s.model.reference[0].inverse_transform_vector(DVec3::new(0.0, 0.0, -9.81));
    let w = Wrench::new(f, DVec3::ZERO).to_array();
    // Contact point at rest: the sphere's bottom, body frame (0, 0, −r); normal +z.
    let gdir = Wrench::new(DVec3::Z, DVec3::new(0.0, 0.0, -0.05).cross(DVec3::Z)).to_array();
    // The sphere's bottom is at z = −0.05 at rest, the plane at −0.06: gap 0.01.
    let gap0 = 0.01;
    let cw: Vec<f64> = (0..6)
        .map(|r| (0..6).map(|k| c[(r, k)] * w[k]).sum())
        .collect();
    let cg: Vec<f64> = (0..6)
        .map(|r| (0..6).map(|k| c[(r, k)] * gdir[k]).sum())
        .collect();
    let gcg: f64 = (0..6).map(|r| gdir[r] * cg[r]).sum();
    let gcw: f64 = (0..6).map(|r| gdir[r] * cw[r]).sum();
    let lambda = (-gap0 - gcw) / gcg;
    let expect: Vec<f64> = (0..6).map(|r| cw[r] + cg[r] * lambda).collect();
    let err = (0..6)
        .map(|r| (s.xi[r] - expect[r]).abs())
        .fold(0.0, f64::max);
    let free = cw.iter().fold(0.0_f64, |a, x| a.max(x.abs()));
    println!(
        "resting: λ = {lambda:.4} N, |ξ − ξ_static| = {err:.2e} (free sag {free:.2e}), contacts {}",
        s.step().contacts
    );
    assert!(lambda > 0.0, "the contact must be active in this set-up");
    assert!(err <= 1e-3 * free, "{:?} vs {expect:?}", s.xi);
    let _ = m;
}

/// A 1 kg block (box of half size 0.1 m) on a plane, held by a very soft 6-DoF weld
/// (k = 10⁻³ N/m, negligible), pushed horizontally at its centre by `push` × μ m g.
fn pushed_block(push: f64) -> f64 {
    let (mu, g, time) = (0.5, 9.81, 1.0);
    let mut d = MechanismDesc::new("block");
    d.gravity([0.0, 0.0, -g]);
    d.link(LinkDesc::new("base", [0.0, 0.0, 0.1]))
        .link(
            LinkDesc::new("block", [0.0, 0.0, 0.1])
                .mass(1.0, [1.0 / 150.0; 3])
                .shape(ShapeDesc::Box {
                    half_extents: [0.1; 3],
                    center: [0.0; 3],
                }),
        )
        .joint(JointDesc::weld("soft", "base", "block", [0.0, 0.0, 0.1]).compliance(&[1e3]))
        .end_effector("block");
    let m = d.build().unwrap();
    let mut s = sim(&m, 1e-3);
    s.obstacles.push(Obstacle::Plane {
        normal: DVec3::Z,
        offset: 0.0,
    });
    s.contact.friction = mu;
    s.external[0] = push * mu * g;
    let steps = (time / s.h).round() as usize;
    for _ in 0..steps {
        s.step();
    }
    s.xi[0]
}

#[test]
fn pushed_block_sticks_below_mu_n_and_slides_above() {
    let (mu, g) = (0.5, 9.81);
    let stuck = pushed_block(0.8);
    println!("push 0.8 μN: x(1 s) = {stuck:.3e} m");
    assert!(stuck.abs() < 1e-6, "{stuck}");
    let slid = pushed_block(1.5);
    // Sliding: m ẍ = F − μ m g, from rest: x = ½ (F/m − μ g) t².
    let expect = 0.5 * (1.5 * mu * g - mu * g);
    println!("push 1.5 μN: x(1 s) = {slid:.4} m, analytic {expect:.4} m");
    assert!(
        (slid / expect - 1.0).abs() < SLIDE_REL,
        "{slid} vs {expect}"
    );
}

/// Backward Euler at h = 1 ms against the exact parabola over 1000 steps: O(h) = 0.1 %, plus
/// the soft weld's spring.
const SLIDE_REL: f64 = 0.01;

#[test]
fn error_estimate_grows_with_the_load() {
    // The per-step estimate is zero at rest and grows quadratically with a static load (the
    // reduced statics are exact to first order).
    let m = crate::scenes::y_shape(4).build().unwrap();
    let mut errs = Vec::new();
    for f in [10.0, 20.0, 40.0] {
        let mut s = sim(&m, 1e-3);
        assert!(s.constraint_error(&m) < 1e-15);
        let w = [f, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        let xi: Vec<f64> = (0..12)
            .map(|r| (0..12).map(|c| s.model.compliance[(r, c)] * w[c]).sum())
            .collect();
        s.xi = xi;
        errs.push(s.constraint_error(&m));
    }
    println!("error estimate at 10, 20, 40 N: {errs:?}");
    for k in 0..2 {
        let ratio = errs[k + 1] / errs[k];
        assert!((ratio - 4.0).abs() < 0.2, "{ratio}");
    }
}
