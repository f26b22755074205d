//! The full dynamics reference against closed forms, conservation laws and the reduced model.

use core::f64::consts::PI;

use rand::RngExt;

use super::*;
use crate::construct::{ConstructOptions, ReducedModel};
use crate::dynamics::ReducedSim;
use crate::testutil::{floating, hinge_rod, random_mechanism, rng};

/// The hinge's numerical frequency, from zero crossings, within 1 % of the closed form √(k/I).
const FREQUENCY_REL: f64 = 0.01;
/// Energy may not grow by more than this fraction of the largest energy term per step: the
/// Newton tolerance ([`tol::FULL_RESIDUAL_REL`]) times the ~10 momentum-sized terms of a step.
const ENERGY_SLACK: f64 = 1e-9;
/// Momentum drift per step of a free-floating mechanism, relative to its momentum: only the
/// Newton tolerance on the base rows (the world momentum balance is one of the equations).
const MOMENTUM_REL: f64 = 1e-9;
/// Loop closure after any step, relative to the bounding radius (the Newton tolerance).
const CLOSURE_REL: f64 = 1e-9;
/// Small-amplitude agreement with the reduced model: both are backward Euler on the same
/// linearisation when the end effector's twist determines every joint (ndof ≤ 6, `J_E` of full
/// column rank), so their difference is the nonlinearity, O(a²) against a displacement O(a).
/// Quartering the load must cut the relative difference by 4 (slope 1 on a log–log plot of
/// relative error against load); allow the slope in [0.8, 1.2] ...
const SLOPE_BAND: (f64, f64) = (0.8, 1.2);
/// ... and the relative difference at the smaller load (rotations of ~1e-3 rad) below this.
const SMALL_LOAD_REL: f64 = 1e-2;

/// Below this relative difference the two trajectories agree to round-off (a linear
/// mechanism: sliders only), and the slope is not judged.
const EXACT_AGREEMENT: f64 = 1e-10;

#[test]
fn single_hinge_vibrates_at_sqrt_k_over_i() {
    let (c, inertia): (f64, f64) = (1e-2, 0.26);
    let period = 2.0 * PI / (1.0 / c / inertia).sqrt();
    let m = hinge_rod(c, &[]);
    let mut s = FullSim::new(&m, period / 1000.0, FullOptions::default()).unwrap();
    s.config.theta[0] = 1e-2;
    let mut crossings = Vec::new();
    let (mut t, mut prev) = (0.0, s.config.theta[0]);
    let mut steps = 0;
    while crossings.len() < 4 {
        // Four periods of steps at most: a model that does not oscillate fails below.
        steps += 1;
        if steps > 4000 {
            break;
        }
        s.step().unwrap();
        t += s.h;
        let now = s.config.theta[0];
        if prev < 0.0 && now >= 0.0 {
            crossings.push(t - s.h * now / (now - prev));
        }
        prev = now;
    }
    assert_eq!(crossings.len(), 4, "the hinge does not oscillate");
    let measured = (crossings[3] - crossings[0]) / 3.0;
    let err = (measured / period - 1.0).abs();
    println!("full hinge: period {measured:.6} s, √(k/I) gives {period:.6} s, error {err:.2e}");
    assert!(err <= FREQUENCY_REL, "{err}");
}

/// A fixed-base random tree and the bundled loop scenes, set moving by random joint
/// velocities (gravity as the scenes have it, none for the random tree).
fn moving(seed: u64) -> Vec<(Mechanism, Vec<f64>)> {
    let mut rng = rng(seed);
    let mut out = vec![(
        random_mechanism(&mut rng, 6, 0, 2, 3.0).build().unwrap(),
        Vec::new(),
    )];
    for d in [crate::scenes::y_shape(4), crate::scenes::ring(6)] {
        out.push((d.build().unwrap(), Vec::new()));
    }
    for (m, v) in &mut out {
        *v = (0..m.ndof).map(|_| rng.random_range(-1.0..1.0)).collect();
    }
    out
}

/// Backward Euler dissipates: the total energy never grows, at small and very large steps,
/// on trees and loops (the loop scenes' closures stay shut meanwhile).
#[test]
fn energy_never_grows_and_loops_stay_closed() {
    for (m, v) in moving(5) {
        for h in [1e-2, 1.0] {
            let mut s = FullSim::new(&m, h, FullOptions::default()).unwrap();
            // Joint velocities compatible with the loops: zero for loop coordinates is not
            // enough, so start from rest displaced instead when there are loops.
            if m.loop_joints.is_empty() {
                s.theta_dot.clone_from(&v);
            } else {
                s.loads = vec![Load {
                    link: m.end_effectors[0],
                    force: DVec3::new(3.0, -2.0, 1.0),
                    torque: DVec3::ZERO,
                }];
                s.step().unwrap();
                s.loads.clear();
            }
            let e0 = s.energy();
            let mut e = e0;
            let scale = e0.abs().max(1e-12);
            for k in 0..15 {
                s.step()
                    .unwrap_or_else(|err| panic!("{} h = {h} step {k}: {err}", m.name));
                let en = s.energy();
                assert!(
                    en <= e + ENERGY_SLACK * scale,
                    "{} h = {h} step {k}: {e} → {en}",
                    m.name
                );
                e = en;
                let poses = s.poses();
                let r = 1.0 + m.bounding_radius();
                for &ji in &m.loop_joints {
                    let gap = loop_residual(&m, &s.config, &poses, ji).to_array();
                    let g = gap.iter().fold(0.0_f64, |a, x| a.max(x.abs()));
                    assert!(g <= CLOSURE_REL * r, "{} loop {ji} open by {g:e}", m.name);
                }
            }
            assert!(e < e0, "{} h = {h}: no dissipation ({e0} → {e})", m.name);
            println!(
                "{} h = {h} s: energy {e0:.4e} → {e:.4e} in 15 steps",
                m.name
            );
        }
    }
}

/// The continuous system conserves energy (no damping, no gravity): backward Euler's loss
/// over a fixed time must be first order in h (halving h halves it) and small. Centrifugal
/// and Coriolis forces (`∂T/∂θ`, the variation of `M`) are exercised by fast spinning joints.
#[test]
fn energy_loss_is_first_order_in_h() {
    let mut rng = rng(77);
    for case in 0..3 {
        let mut m = random_mechanism(&mut rng, 3 + case, 0, 2, 2.0)
            .build()
            .unwrap();
        for j in &mut m.joints {
            j.damping.iter_mut().for_each(|d| *d = 0.0);
        }
        let v: Vec<f64> = (0..m.ndof).map(|_| rng.random_range(-5.0..5.0)).collect();
        let loss = |h: f64| {
            let mut s = FullSim::new(&m, h, FullOptions::default()).unwrap();
            s.theta_dot.clone_from(&v);
            let e0 = s.energy();
            let steps = (ENERGY_HORIZON / h).round() as usize;
            for _ in 0..steps {
                s.step().unwrap();
            }
            (e0 - s.energy()) / e0
        };
        let (l1, l2) = (loss(2e-4), loss(1e-4));
        let ratio = l2 / l1;
        println!(
            "tree {case} (ndof {}): energy loss {l1:.3e} at h, {l2:.3e} at h/2",
            m.ndof
        );
        assert!(l1 > 0.0 && l1 <= ENERGY_LOSS_MAX, "loss {l1:e}");
        assert!(
            (HALVING_BAND.0..=HALVING_BAND.1).contains(&ratio),
            "loss ratio {ratio}: not first order"
        );
    }
}

/// Simulated time of [`energy_loss_is_first_order_in_h`] (s).
const ENERGY_HORIZON: f64 = 0.02;
/// Backward Euler's relative energy loss over the horizon at h = 2e-4 s (≈ h·Σω²·t, the
/// joints turning at up to 5 rad/s over stiff springs of 1e-4–1e-2 compliance, ~1e-2).
const ENERGY_LOSS_MAX: f64 = 0.1;
/// Ratio of the losses at h/2 and h for a first-order method.
const HALVING_BAND: (f64, f64) = (0.4, 0.6);

/// Without external forces the world momentum (linear and angular about the origin, summed
/// over the links from their poses and twists) is constant; under gravity alone its linear
/// part grows by `h m g` per step and the angular part by the gravity moment.
#[test]
fn free_floating_mechanism_conserves_momentum() {
    let mut rng = rng(9);
    for g in [[0.0; 3], [0.0, 0.0, -9.81]] {
        let m = floating(g);
        let mut s = FullSim::new(&m, 1e-2, FullOptions::default()).unwrap();
        s.theta_dot = (0..m.ndof).map(|_| rng.random_range(-3.0..3.0)).collect();
        s.base_twist = Twist::from_array(core::array::from_fn(|_| rng.random_range(-1.0..1.0)));
        let mut p = s.world_momentum();
        let scale = p.f.length().max(p.tau.length());
        let gravity = DVec3::from_array(g) * m.total_mass();
        let mut worst = 0.0_f64;
        for _ in 0..40 {
            // Expected change over the step: gravity's impulse at the centre of mass, taken
            // at the end of the step (backward Euler).
            s.step().unwrap();
            let poses = s.poses();
            let com = m
                .links
                .iter()
                .zip(&poses)
                .map(|(l, p)| p.transform_point(l.inertia.com) * l.inertia.mass)
                .sum::<DVec3>()
                / m.total_mass();
            let impulse = Wrench::new(gravity * s.h, com.cross(gravity * s.h));
            let now = s.world_momentum();
            let d = now - p - impulse;
            worst = worst.max(d.f.length().max(d.tau.length()) / scale);
            p = now;
        }
        println!("floating, g = {g:?}: momentum balance off by at most {worst:e} per step");
        assert!(worst <= MOMENTUM_REL, "{worst:e}");
    }
}

/// Random chains whose end effector's twist determines every joint (ndof ≤ 6).
fn determined_chains(seed: u64) -> Vec<Mechanism> {
    let mut rng = rng(seed);
    let mut out = Vec::new();
    while out.len() < 6 {
        let m = random_mechanism(&mut rng, 1 + out.len() % 3, 0, 1, 2.0)
            .build()
            .unwrap();
        let chain = m.joints_out.iter().all(|o| o.len() <= 1);
        if m.ndof <= 6 && chain && m.end_effectors.len() == 1 {
            out.push(m);
        }
    }
    out
}

/// Largest relative difference of the end effector's world pose, reduced against full, over
/// `steps` steps under body load `w` (held from rest), relative to the largest displacement.
fn trajectory_difference(m: &Mechanism, w: Wrench, h: f64, steps: usize) -> f64 {
    let model = ReducedModel::build(
        m,
        &Configuration::rest(m),
        &[],
        &ConstructOptions::default(),
    )
    .unwrap();
    let rest = model.reference[0];
    let mut red = ReducedSim::new(m, model, h).unwrap();
    red.external = w.to_array().to_vec();
    let mut full = FullSim::new(m, h, FullOptions::default()).unwrap();
    full.loads = vec![Load {
        link: m.end_effectors[0],
        force: rest.transform_vector(w.f),
        torque: rest.transform_vector(w.tau),
    }];
    let r = m.bounding_radius();
    let norm = |x: &Twist| ((x.v / r).length_squared() + x.w.length_squared()).sqrt();
    let (mut diff, mut disp) = (0.0_f64, 0.0_f64);
    for _ in 0..steps {
        red.step();
        full.step().unwrap();
        let pf = full.poses()[m.end_effectors[0]];
        let pr = red.end_effector_pose(0);
        diff = diff.max(norm(&(pf.inverse() * pr).log()));
        disp = disp.max(norm(&(rest.inverse() * pf).log()));
    }
    diff / disp
}

/// At small amplitude the reduced model's end-effector trajectory is the full model's: the
/// difference shrinks like the load (second order against first).
#[test]
fn reduced_model_follows_the_full_model_at_small_amplitude() {
    let mut rng = rng(12);
    for m in determined_chains(31) {
        let dir = Wrench::from_array(core::array::from_fn(|_| rng.random_range(-1.0..1.0)));
        // A load that turns the chain by ~1e-2 rad at the larger amplitude.
        let model =
            ReducedModel::build(&m, &Configuration::rest(&m), &[], &Default::default()).unwrap();
        let c = crate::linalg::max_abs(model.compliance.as_ref());
        let a = 1e-2 / c;
        let (e1, e2) = (
            trajectory_difference(&m, dir * a, 2e-3, 150),
            trajectory_difference(&m, dir * (a / 4.0), 2e-3, 150),
        );
        if e1 <= EXACT_AGREEMENT {
            // Sliders only: the full model is linear too, the two agree to round-off.
            println!(
                "{} links, ndof {}: agree to {e1:.1e}",
                m.links.len(),
                m.ndof
            );
            continue;
        }
        let slope = (e1 / e2).ln() / 4f64.ln();
        println!(
            "{} links, ndof {}: relative difference {e1:.2e} → {e2:.2e} (slope {slope:.2})",
            m.links.len(),
            m.ndof
        );
        assert!(e2 <= SMALL_LOAD_REL, "{e2:e}");
        assert!(
            (SLOPE_BAND.0..=SLOPE_BAND.1).contains(&slope),
            "slope {slope}: not the nonlinearity alone"
        );
    }
}

#[test]
fn bad_input_is_an_error() {
    let m = hinge_rod(1e-2, &[]);
    assert!(FullSim::new(&m, 0.0, FullOptions::default()).is_err());
    assert!(FullSim::new(&m, f64::NAN, FullOptions::default()).is_err());
    let mut s = FullSim::new(&m, 1e-3, FullOptions::default()).unwrap();
    s.loads = vec![Load {
        link: 7,
        force: DVec3::X,
        torque: DVec3::ZERO,
    }];
    assert!(s.step().is_err());
    s.loads.clear();
    s.theta_dot[0] = f64::NAN;
    assert!(s.step().is_err());
}

/// Tolerance of the articulated-body solve against a dense LU of `M + diag(arm)`, relative to
/// the largest component of the solution.
const ARTICULATED_REL: f64 = 1e-9;

/// The O(n) articulated-body solve of the Newton tangent equals the dense solve with the CRBA
/// mass matrix, on random trees at random configurations and on helices up to 150 links (deep
/// chains are where round-off in the articulated inertias grows).
#[test]
fn articulated_solve_matches_dense() {
    let mut rng = rng(44);
    let mut mechs: Vec<Mechanism> = (0..20)
        .map(|k| {
            random_mechanism(&mut rng, 2 + k, 0, 3, 4.0)
                .build()
                .unwrap()
        })
        .collect();
    for n in [5, 20, 50, 100, 150] {
        mechs.push(crate::scenes::helix(n).build().unwrap());
    }
    for m in &mechs {
        let mut s = FullSim::new(m, 1e-3, FullOptions::default()).unwrap();
        s.config.theta = (0..m.ndof).map(|_| rng.random_range(-0.3..0.3)).collect();
        let k = s.kinematics(&s.config, &s.theta_dot, &s.base_twist);
        let arm: Vec<f64> = m
            .joints
            .iter()
            .flat_map(|j| j.compliance.iter().map(|c| 1e-6 / c))
            .collect();
        let tau: Vec<f64> = (0..m.ndof).map(|_| rng.random_range(-1.0..1.0)).collect();
        let x = s.articulated_solve(&k, &arm, &tau).unwrap();
        let mut a = s.mass_matrix(&k);
        for (i, v) in arm.iter().enumerate() {
            a[(i, i)] += v;
        }
        let rhs = Mat::from_fn(m.ndof, 1, |i, _| tau[i]);
        let y = a.partial_piv_lu().solve(&rhs);
        let size = (0..m.ndof).fold(0.0_f64, |acc, i| acc.max(y[(i, 0)].abs()));
        let err = (0..m.ndof).fold(0.0_f64, |acc, i| acc.max((x[i] - y[(i, 0)]).abs())) / size;
        let res = |v: &dyn Fn(usize) -> f64| -> f64 {
            (0..m.ndof)
                .map(|i| ((0..m.ndof).map(|c| a[(i, c)] * v(c)).sum::<f64>() - tau[i]).abs())
                .fold(0.0, f64::max)
        };
        println!(
            "{} (ndof {}): articulated vs dense {err:e}; residuals {:e} {:e}",
            m.name,
            m.ndof,
            res(&|c| x[c]),
            res(&|c| y[(c, 0)])
        );
        assert!(err <= ARTICULATED_REL, "{}: {err:e}", m.name);
    }
}
