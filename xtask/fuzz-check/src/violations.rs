//! Each check fails when the thing it guards is broken: an energy source the bound does not
//! allow, a penetration beyond ε_c, an indefinite matrix, an anti-damped reduced model, a
//! torque on a URDF model. (Their passing on real inputs is the corpus replay,
//! `tests/corpus.rs`.)

use glam::DVec3;
use impulse_sim::scene::{BodyDesc, ShapeDesc};
use impulse_sim::{
    Load, PenetrationReport, Scene, SceneDesc, SustainedSettings, World, WorldSettings,
};

use crate::energy::{EnergyBound, world_energy};
use crate::{Outcome, Violation};

/// A 5 cm ball resting on a fixed floor (ε_c = 1e-4), the scene of the energy tests.
fn ball_on_floor() -> World {
    let desc = SceneDesc::new()
        .with_body(
            BodyDesc::fixed("floor", ShapeDesc::cuboid([1.0, 1.0, 0.1])).at([0.0, 0.0, -0.1]),
        )
        .with_body(BodyDesc::new("ball", ShapeDesc::sphere(0.05)).at([0.0, 0.0, 0.2]));
    World::from_scene(&Scene::new(desc, ".")).expect("a valid scene")
}

/// The bound holds for the ball's own fall and bounces (the reference: a dropped ball with
/// e = 0.5 loses energy), and fails once a constant upward force does work on it (a source
/// the bound does not know): 20 N over the 0.3 m it lifts the 1 kg ball is far beyond the
/// envelope's m·g·(N + 1)·ε_c.
#[test]
fn energy_check_fails_on_work_done_by_a_load() {
    let mut world = ball_on_floor();
    let bound = EnergyBound::of(&world, &SustainedSettings::default());
    for k in 1..=300 {
        world.step_until(k as f64 * 1e-3).expect("runs");
        bound
            .check(world_energy(&world), world.time())
            .expect("no source: no gain");
    }
    let ball = world.handle("ball").expect("the ball");
    let m = world.body(ball).and_then(|b| b.mass).expect("dynamic").mass;
    world
        .set_load(ball, Load::force(DVec3::new(0.0, 0.0, 3.0 * 9.81 * m)))
        .expect("a load");
    let mut failed = None;
    for k in 301..=600 {
        world.step_until(k as f64 * 1e-3).expect("runs");
        if let Err(v) = bound.check(world_energy(&world), world.time()) {
            failed = Some(v);
            break;
        }
    }
    assert!(
        matches!(failed, Some(Violation::EnergyGained(_))),
        "{failed:?}"
    );
}

/// The energy computed here equals the world's own sum (an independent computation of the
/// same state: ½mv² + ½ω·Iω − m·g·x).
#[test]
fn world_energy_matches_the_worlds_sum() {
    let mut world = ball_on_floor();
    let ball = world.handle("ball").expect("the ball");
    world
        .set_velocity(ball, DVec3::new(0.3, -0.2, 1.0), DVec3::new(4.0, -1.0, 2.0))
        .expect("a velocity");
    let own = world_energy(&world);
    let theirs = world.kinetic_energy() + world.potential_energy();
    assert!(
        (own - theirs).abs() <= 1e-12 * theirs.abs(),
        "{own} vs {theirs}"
    );
    let _ = WorldSettings::new(1e-4);
}

/// The depth check fails on a report deeper than ε_c and passes at ε_c.
#[test]
fn depth_check_fails_beyond_epsilon() {
    let report = |max_depth| PenetrationReport {
        max_depth,
        ..PenetrationReport::default()
    };
    assert!(crate::scene::check_depth(&report(1e-4), 1e-4).is_ok());
    assert!(matches!(
        crate::scene::check_depth(&report(1.01e-4), 1e-4),
        Err(Violation::Penetration(_))
    ));
}

/// A mass matrix that is not positive definite (or not symmetric) is a violation.
#[test]
fn mass_matrix_check_fails_on_an_indefinite_matrix() {
    use impulse_multibody::Mat;
    let m = |a: f64, b: f64, c: f64| Mat::<f64>::from_fn(2, 2, |i, j| [[a, b], [c, a]][i][j]);
    assert!(crate::urdf::check_mass_matrix(&m(2.0, 1.0, 1.0)).is_ok());
    assert!(crate::urdf::check_mass_matrix(&m(1.0, 2.0, 2.0)).is_err()); // eigenvalues 3, −1
    assert!(crate::urdf::check_mass_matrix(&m(2.0, 1.0, 0.5)).is_err()); // not symmetric
}

/// The double pendulum of `fixtures/urdf` passes its run; with a constant torque on its
/// shoulder (work the check does not allow) the energy check fails.
#[test]
fn urdf_energy_check_fails_under_a_torque() {
    let xml = include_str!("../../../fixtures/urdf/double_pendulum.urdf");
    let model = impulse_multibody::urdf::from_str(xml, impulse_multibody::BaseKind::Fixed)
        .expect("the fixture reads");
    let (q, v) = crate::urdf::state(&model);
    let free = crate::urdf::simulate(model.clone(), q.clone(), v.clone(), None);
    assert_eq!(
        free,
        Ok(Outcome::Checked {
            energy_checked: true
        })
    );
    let driven = crate::urdf::simulate(model, q, v, Some(&[5.0, 0.0]));
    assert!(
        matches!(driven, Err(Violation::EnergyGained(_))),
        "{driven:?}"
    );
}

/// The lever of `fixtures/mechanisms` passes its run; with its damping made negative (an
/// anti-damper feeds energy in) the energy check fails, and the PSD check refuses the
/// negative damping matrix.
#[test]
fn reduced_energy_check_fails_with_negative_damping() {
    let text = include_str!("../../../fixtures/mechanisms/lever.ron");
    let m = impulse_reduced::MechanismDesc::from_ron(text)
        .and_then(|d| d.build())
        .expect("the fixture builds");
    let model = impulse_reduced::ReducedModel::build(
        &m,
        &impulse_reduced::reference::Configuration::rest(&m),
        &[],
        &impulse_reduced::ConstructOptions::default(),
    )
    .expect("the lever reduces");
    assert_eq!(
        crate::mechanism::simulate(&m, model.clone()),
        Ok(Outcome::Checked {
            energy_checked: true
        })
    );
    let mut anti = model;
    let n = anti.damping.nrows();
    let scale = (0..n).map(|i| anti.mass[(i, i)]).fold(0.0, f64::max) * 100.0;
    for i in 0..n {
        anti.damping[(i, i)] -= scale;
    }
    assert!(crate::mechanism::check_psd("damping", &anti.damping).is_err());
    let run = crate::mechanism::simulate(&m, anti);
    assert!(matches!(run, Err(Violation::EnergyGained(_))), "{run:?}");
}
