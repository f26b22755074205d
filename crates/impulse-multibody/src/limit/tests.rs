//! Tests of joint stops, each against a closed form or a conservation law.

use glam::{DMat3, DVec3};
use impulse_geom::{Pose, SpatialInertia};
use rand::RngExt;

use super::*;
use crate::Simulation;
use crate::integrate::{AdaptiveRk4, Integrator};
use crate::model::{BaseKind, JointSpec, ModelBuilder};
use crate::testutil::rng;

const G: f64 = 9.81;
/// Energies against their closed forms, relative to m·g·c: the integrator's tolerance
/// (1e-11 per step) over a few thousand steps, and the stop located to 1e-12 s.
const ENERGY_REL: f64 = 1e-8;
/// Coordinates against polynomial closed forms (RK4 is exact for them, up to rounding and
/// the located instant).
const EXACT: f64 = 1e-9;

fn tight() -> Integrator {
    Integrator::AdaptiveRk4(AdaptiveRk4 {
        rel_tol: 1e-11,
        abs_tol: 1e-11,
        ..AdaptiveRk4::default()
    })
}

/// A rod of mass `m` whose centre of mass is `c` out along x, hinged about z at the origin,
/// gravity −y: at q = 0 it lies horizontal, q < 0 swings it down.
fn arm(m: f64, c: f64, limit: JointLimit) -> (crate::Model, f64) {
    let i_c = 0.02;
    let mut b = ModelBuilder::new(BaseKind::Fixed);
    b.gravity(DVec3::new(0.0, -G, 0.0))
        .link("ground", SpatialInertia::ZERO)
        .link(
            "arm",
            SpatialInertia::new(m, DVec3::new(c, 0.0, 0.0), DMat3::IDENTITY * i_c),
        )
        .joint(
            JointSpec::revolute("hinge", "ground", "arm", Pose::IDENTITY, DVec3::Z)
                .with_limit(limit),
        );
    (b.build().unwrap(), i_c + m * c * c)
}

/// A mass on a vertical prismatic joint with a stop at q = 0 below it.
fn slider(m: f64, e: f64) -> crate::Model {
    let mut b = ModelBuilder::new(BaseKind::Fixed);
    b.gravity(DVec3::new(0.0, 0.0, -G))
        .link("ground", SpatialInertia::ZERO)
        .link(
            "piston",
            SpatialInertia::new(m, DVec3::ZERO, DMat3::IDENTITY * m),
        )
        .joint(
            JointSpec::prismatic("slide", "ground", "piston", Pose::IDENTITY, DVec3::Z)
                .with_limit(JointLimit::new(0.0, f64::INFINITY, e)),
        );
    b.build().unwrap()
}

#[test]
fn a_pendulum_dropped_onto_its_stop_rebounds_with_its_restitution_and_never_passes_it() {
    let (m, c, q_stop, e) = (1.5, 0.4, -0.8, 0.6);
    let (model, _) = arm(m, c, JointLimit::new(q_stop, 1.0, e));
    let mut sim = Simulation::new(model, vec![0.0], vec![0.0], tight()).unwrap();
    let scale = m * G * c;
    // Released at rest, horizontal: E = 0 (potential m·g·c·sin q). After the stop the
    // kinetic energy is e² of what it was at the stop, −m·g·c·sin q_stop:
    // E = m·g·c·sin q_stop·(1 − e²).
    let after = scale * q_stop.sin() * (1.0 - e * e);
    let mut lowest = f64::INFINITY;
    let mut checked = 0;
    for k in 1..=20_000 {
        sim.run_until(k as f64 * 1e-4).unwrap();
        lowest = lowest.min(sim.q()[0]);
        let strikes = sim.limit_stats().strikes;
        let energy = sim.energy().unwrap();
        let want = match strikes {
            0 => 0.0,
            1 => after,
            _ => break,
        };
        assert!(
            (energy - want).abs() <= ENERGY_REL * scale,
            "t = {}: energy {energy} after {strikes} stops, closed form {want}",
            sim.time()
        );
        checked += usize::from(strikes == 1);
    }
    assert!(checked > 100, "only {checked} samples after the first stop");
    assert!(lowest >= q_stop, "passed its stop: {lowest} < {q_stop}");
}

#[test]
fn a_slider_bouncing_on_its_stop_comes_to_rest_on_it_and_lifts_off_when_pushed() {
    let (m, e, h0) = (2.0, 0.5, 0.05);
    let mut sim = Simulation::new(slider(m, e), vec![h0], vec![0.0], tight()).unwrap();
    // Closed form: it lands at t₁ = √(2h₀/g) at u = g·t₁; the k-th rebound leaves at eᵏ·u and
    // flies 2·eᵏ·u/g. Mid-way through the first rebound its height is e·u·τ − ½·g·τ².
    let t1 = (2.0 * h0 / G).sqrt();
    let u = G * t1;
    let tau = e * u / G;
    sim.run_until(t1 + tau).unwrap();
    let want = e * u * tau - 0.5 * G * tau * tau;
    assert!(
        (sim.q()[0] - want).abs() <= EXACT,
        "first rebound's peak {} against {want}",
        sim.q()[0]
    );
    // Zeno's end: every bounce slower than the rest speed is the last.
    let rest = DEFAULT_LIMIT_REST_SPEED;
    let bounces = ((rest / u).ln() / e.ln()).ceil() as i32;
    let end = t1 + (1..bounces).map(|k| 2.0 * e.powi(k) * u / G).sum::<f64>();
    sim.run_until(end + 0.1).unwrap();
    assert!(sim.is_resting_on_stop(0), "not at rest on its stop");
    assert_eq!((sim.q()[0], sim.v()[0]), (0.0, 0.0));
    let stats = sim.limit_stats();
    assert_eq!(stats.rests, 1);
    assert!(
        (i64::from(bounces) - stats.strikes as i64).abs() <= 2,
        "{} stops struck, {bounces} bounces by the closed form",
        stats.strikes
    );
    // Pushed up by twice its weight it lifts off at once: q = ½·(F/m − g)·t².
    let t_push = sim.time();
    sim.set_applied_forces(&[2.0 * m * G]).unwrap();
    sim.run_until(t_push + 0.1).unwrap();
    assert!(!sim.is_resting_on_stop(0));
    assert_eq!(sim.limit_stats().releases, 1);
    let want = 0.5 * G * 0.1 * 0.1;
    assert!(
        (sim.q()[0] - want).abs() <= EXACT,
        "lifted to {} against {want}",
        sim.q()[0]
    );
}

#[test]
fn random_chains_swinging_against_their_stops_never_gain_energy_nor_pass_a_stop() {
    let mut r = rng(13);
    let mut totals = LimitStats::default();
    for case in 0..20 {
        let n = r.random_range(1..=3);
        let mut b = ModelBuilder::new(BaseKind::Fixed);
        b.gravity(DVec3::new(0.0, -G, 0.0))
            .link("l0", SpatialInertia::ZERO);
        let mut lims = Vec::new();
        for i in 1..=n {
            let m = r.random_range(0.2..2.0);
            let c = r.random_range(0.1..0.5);
            let half = r.random_range(0.2..1.2);
            let limit = JointLimit::new(-half, r.random_range(0.1..1.0), r.random_range(0.0..=1.0));
            lims.push(limit);
            let origin =
                Pose::from_translation(DVec3::new(if i == 1 { 0.0 } else { 0.5 }, 0.0, 0.0));
            b.link(
                &format!("l{i}"),
                SpatialInertia::new(m, DVec3::new(c, 0.0, 0.0), DMat3::IDENTITY * 0.01),
            )
            .joint(
                JointSpec::revolute(
                    &format!("j{i}"),
                    &format!("l{}", i - 1),
                    &format!("l{i}"),
                    origin,
                    DVec3::Z,
                )
                .with_limit(limit),
            );
        }
        let model = b.build().unwrap();
        let v0: Vec<f64> = (0..n).map(|_| r.random_range(-4.0..4.0)).collect();
        let mut sim = Simulation::new(model, vec![0.0; n], v0, tight()).unwrap();
        let mut energy = sim.energy().unwrap();
        let scale = energy.abs() + G;
        for k in 1..=1000 {
            sim.run_until(k as f64 * 1e-3).unwrap();
            let now = sim.energy().unwrap();
            assert!(
                now <= energy + ENERGY_REL * scale,
                "case {case} t = {}: energy rose from {energy} to {now}",
                sim.time()
            );
            energy = now;
            for (j, l) in lims.iter().enumerate() {
                let q = sim.q()[j];
                assert!(
                    (l.lower..=l.upper).contains(&q),
                    "case {case}: joint {j} at {q} outside [{}, {}]",
                    l.lower,
                    l.upper
                );
            }
        }
        let stats = sim.limit_stats();
        assert!(stats.strikes > 0, "case {case} struck no stop");
        totals.strikes += stats.strikes;
        totals.rests += stats.rests;
        totals.releases += stats.releases;
    }
    println!("20 chains, 1 s each: {totals:?}");
}

#[test]
fn malformed_limits_and_states_outside_them_are_refused_naming_the_joint() {
    let bad = [
        JointLimit::new(0.5, 0.5, 0.5),
        JointLimit::new(1.0, -1.0, 0.5),
        JointLimit::new(f64::NAN, 1.0, 0.5),
        JointLimit::new(-1.0, 1.0, 1.5),
        JointLimit::new(-1.0, 1.0, -0.1),
        JointLimit::new(f64::INFINITY, f64::INFINITY, 0.5),
    ];
    for limit in bad {
        let mut b = ModelBuilder::new(BaseKind::Fixed);
        b.link("ground", SpatialInertia::ZERO)
            .link("arm", SpatialInertia::new(1.0, DVec3::X, DMat3::IDENTITY))
            .joint(
                JointSpec::revolute("elbow", "ground", "arm", Pose::IDENTITY, DVec3::Z)
                    .with_limit(limit),
            );
        let err = b.build().unwrap_err().to_string();
        assert!(err.contains("elbow"), "{limit:?}: {err}");
    }
    let mut b = ModelBuilder::new(BaseKind::Fixed);
    b.link("ground", SpatialInertia::ZERO)
        .link("arm", SpatialInertia::new(1.0, DVec3::X, DMat3::IDENTITY))
        .joint(
            JointSpec::fixed("weld", "ground", "arm", Pose::IDENTITY)
                .with_limit(JointLimit::new(-1.0, 1.0, 0.5)),
        );
    assert!(b.build().unwrap_err().to_string().contains("weld"));

    let (model, _) = arm(1.0, 0.3, JointLimit::new(-0.5, 0.5, 0.5));
    let err = Simulation::new(model.clone(), vec![0.7], vec![0.0], tight()).unwrap_err();
    assert!(err.to_string().contains("hinge"), "{err}");
    let mut sim = Simulation::new(model, vec![0.2], vec![0.1], tight()).unwrap();
    assert!(sim.set_state(&[-0.6], &[0.0]).is_err());
    assert_eq!(
        (sim.q()[0], sim.v()[0]),
        (0.2, 0.1),
        "the refused state was kept"
    );
    assert!(sim.set_limit_rest_speed(f64::NAN).is_err());
}

/// `run_until_strike` returns at the instant a slider dropped from height h onto its stop
/// strikes it, √(2h/g) in closed form, with the strike resolved (speed −e times the impact
/// speed √(2gh)); run on, it returns at the next strike, and `run_until` passes them all.
#[test]
fn run_until_strike_stops_at_each_strike_with_it_resolved() {
    let (h, e) = (0.05, 0.5);
    let model = slider(2.0, e);
    let mut sim = Simulation::new(model.clone(), vec![h], vec![0.0], tight()).unwrap();
    let t_hit = (2.0 * h / G).sqrt();
    let at = sim.run_until_strike(1.0).unwrap();
    assert!((at - t_hit).abs() < 1e-9, "{at} vs {t_hit}");
    let v_hit = (2.0 * G * h).sqrt();
    assert!(
        (sim.v()[0] - e * v_hit).abs() < 1e-6 * v_hit,
        "{}",
        sim.v()[0]
    );
    // The bounce: up and down again in 2·e·v/g.
    let next = sim.run_until_strike(1.0).unwrap();
    assert!((next - at - 2.0 * e * v_hit / G).abs() < 1e-8, "{next}");
    // Without strikes before the end, the end.
    let mut plain = Simulation::new(model, vec![h], vec![0.0], tight()).unwrap();
    assert_eq!(plain.run_until_strike(0.5 * t_hit).unwrap(), 0.5 * t_hit);
    plain.run_until(1.0).unwrap();
    assert!(plain.limit_stats().strikes >= 3);
}

/// A slider set down on its stop slowly comes to rest there (the closed form's equilibrium:
/// q = 0, v = 0 exactly), and from then on its steps integrate nothing: no derivative is
/// evaluated while it rests, however long it is run, until a push lifts it off, when it
/// moves as the closed form says again.
#[test]
fn a_joint_resting_on_its_stop_is_not_integrated_until_pushed_off() {
    let m = 2.0;
    let mut sim = Simulation::new(slider(m, 0.5), vec![1e-9], vec![0.0], tight()).unwrap();
    sim.run_until(0.01).unwrap();
    assert!(sim.is_resting_on_stop(0), "not at rest on its stop");
    let (evaluations, resting) = (
        sim.stats().derivative_evaluations,
        sim.limit_stats().resting_steps,
    );
    for k in 1..=100 {
        sim.run_until(0.01 + f64::from(k) * 0.01).unwrap();
    }
    assert_eq!((sim.q()[0], sim.v()[0]), (0.0, 0.0));
    assert_eq!(sim.stats().derivative_evaluations, evaluations);
    assert!(sim.limit_stats().resting_steps >= resting + 100);
    let t_push = sim.time();
    sim.set_applied_forces(&[2.0 * m * G]).unwrap();
    sim.run_until(t_push + 0.1).unwrap();
    let want = 0.5 * G * 0.1 * 0.1;
    assert!(
        (sim.q()[0] - want).abs() <= EXACT,
        "lifted to {} against {want}",
        sim.q()[0]
    );
}

/// The travel recorded over steps that strike a stop (what a world checks its predictions
/// against) holds only the motion taken: a slider dropped onto its stop at q = 0 never has a
/// recorded state below it, through all its bounces. The bisection that locates a strike
/// integrates trial steps past the stop; when their states were recorded, samples lay up to
/// 1.5e-4 m below it.
#[test]
fn the_travel_of_a_struck_step_holds_no_state_beyond_the_stop() {
    let mut sim = Simulation::new(slider(2.0, 0.5), vec![0.05], vec![0.0], tight()).unwrap();
    sim.set_tracking(true);
    let mut lowest = f64::INFINITY;
    let mut samples = 0;
    for k in 1..=500 {
        sim.run_until(f64::from(k) * 1e-3).unwrap();
        for travel in sim.take_travel().unwrap() {
            for s in &travel.path {
                lowest = lowest.min(s.origin.z);
                samples += 1;
            }
        }
    }
    assert!(sim.limit_stats().strikes >= 3, "{:?}", sim.limit_stats());
    assert!(samples > 1000, "{samples} samples");
    assert!(
        lowest >= -EXACT,
        "a recorded state {lowest} m below the stop"
    );
}

/// Most trial integrations per located stop, on average, that the interpolating search may
/// take on a smooth approach (bisection from a step of ~1 ms to 1e-12 s takes about 30).
const TRIES_PER_STRIKE: f64 = 4.0;

/// Strikes are located to the tolerance at the closed form's instants, in a few trial
/// integrations each: a slider bouncing on its stop (a polynomial motion, strikes at
/// t₁ = √(2h/g) and then every 2·eᵏ·u/g), and a rod swinging onto its stop (not polynomial:
/// the interpolant's aim is off by O(h⁴) and the search still needs few tries).
#[test]
fn a_strike_is_located_in_a_few_tries_at_the_closed_form_instant() {
    let (h0, e) = (0.05, 0.5);
    let mut sim = Simulation::new(slider(2.0, e), vec![h0], vec![0.0], tight()).unwrap();
    let t1 = (2.0 * h0 / G).sqrt();
    let u = G * t1;
    let mut want = t1;
    for k in 0..6 {
        let at = sim.run_until_strike(1.0).unwrap();
        assert!(
            (at - want).abs() <= 4.0 * LIMIT_TIME_TOLERANCE + 1e-15 * want,
            "strike {k} at {at}, closed form {want}"
        );
        want += 2.0 * e.powi(k + 1) * u / G;
    }
    let stats = sim.limit_stats();
    let per_strike = stats.locating_steps as f64 / stats.strikes as f64;
    assert!(
        per_strike <= TRIES_PER_STRIKE,
        "{per_strike} tries per strike ({stats:?})"
    );
    let (model, _) = arm(1.5, 0.4, JointLimit::new(-0.8, 1.0, 0.6));
    let mut rod = Simulation::new(model, vec![0.0], vec![0.0], tight()).unwrap();
    rod.run_until(3.0).unwrap();
    let stats = rod.limit_stats();
    assert!(stats.strikes >= 3, "{stats:?}");
    let per_strike = stats.locating_steps as f64 / stats.strikes as f64;
    assert!(
        per_strike <= TRIES_PER_STRIKE,
        "{per_strike} tries per strike ({stats:?})"
    );
}
