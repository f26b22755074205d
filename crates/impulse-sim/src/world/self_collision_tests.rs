//! Self-collision in the world (`docs/hybrid.md`, "Self-collision"): a three-link chain
//! folding onto itself under gravity, its first and last links (not adjacent) sampled by
//! brute-force distance every frame, with the option on and off.

use glam::DVec3;
use impulse_collide::{PairCache, depth, shape};
use impulse_geom::{Pose, SpatialInertia};
use impulse_multibody::{BaseKind, Integrator, JointPassive, JointSpec, ModelBuilder, Simulation};

use super::hybrid_tests::slab;
use super::{BodyHandle, MultibodyOptions, World, WorldSettings};
use crate::LinkShape;
use crate::sustained::ContactMode;

/// ε_c of the world (m).
const EPS: f64 = 1e-3;
/// Frame interval of the brute-force sampling (s).
const FRAME: f64 = 1e-3;
/// Simulated time: the last link folds down onto the first in about 0.3 s.
const DURATION: f64 = 1.5;
/// At rest on the first link, the last is at most this far above it (microcollisions keep a
/// resting pair within the envelope, ε_c).
const REST_GAP: f64 = 2.0 * EPS;
/// Without self-collision, the last link must sink at least this deep into the first (it
/// passes through: its width, 6 cm, not a grazing touch).
const THROUGH: f64 = 10.0 * EPS;

/// The chain, all joints about y: link `a`, a 0.6 m plate hinged to the ground at
/// (0, 0, 0.5) and held level by a stiff damped spring; link `b`, a 0.25 m bar hinged
/// 0.15 m above `a`'s far end and held level, pointing back over `a`, by another; link
/// `c`, a free 0.2 m bar hinged at `b`'s tip, starting level (0.13 m above `a`), which
/// swings down onto `a` (or, without self-collision, through it).
fn chain() -> (Simulation, Vec<LinkShape>) {
    let (ia, sa) = slab(1.0, DVec3::new(0.3, 0.05, 0.01), DVec3::new(0.3, 0.0, 0.0));
    let (ib, sb) = slab(
        0.3,
        DVec3::new(0.015, 0.03, 0.125),
        DVec3::new(0.0, 0.0, 0.125),
    );
    let (ic, sc) = slab(0.2, DVec3::new(0.01, 0.03, 0.1), DVec3::new(0.0, 0.0, 0.1));
    let level = -std::f64::consts::FRAC_PI_2;
    let mut m = ModelBuilder::new(BaseKind::Fixed);
    m.link("ground", SpatialInertia::ZERO)
        .link("a", ia)
        .link("b", ib)
        .link("c", ic)
        .joint(
            JointSpec::revolute(
                "ja",
                "ground",
                "a",
                Pose::from_translation(DVec3::new(0.0, 0.0, 0.5)),
                DVec3::Y,
            )
            .with_passive(JointPassive {
                damping: 5.0,
                ..JointPassive::spring(500.0, 0.0)
            }),
        )
        .joint(
            JointSpec::revolute(
                "jb",
                "a",
                "b",
                Pose::from_translation(DVec3::new(0.6, 0.0, 0.15)),
                DVec3::Y,
            )
            .with_passive(JointPassive {
                damping: 2.0,
                ..JointPassive::spring(200.0, level)
            }),
        )
        .joint(JointSpec::revolute(
            "jc",
            "b",
            "c",
            Pose::from_translation(DVec3::new(0.0, 0.0, 0.25)),
            DVec3::Y,
        ));
    let sim = Simulation::new(
        m.build().unwrap(),
        vec![0.0, level, 0.0],
        vec![0.0; 3],
        Integrator::default(),
    )
    .unwrap();
    let shapes = [("a", sa), ("b", sb), ("c", sc)]
        .into_iter()
        .map(|(link, shape)| LinkShape {
            link: link.into(),
            shape,
            material: "default".into(),
        })
        .collect();
    (sim, shapes)
}

/// Signed distance between two bodies' shapes now: their distance, or minus their
/// penetration depth (the collision crate's exact queries, outside the event loop).
fn signed_distance(w: &World, a: BodyHandle, b: BodyHandle, cache: &mut PairCache) -> f64 {
    let (ba, bb) = (w.body(a).unwrap(), w.body(b).unwrap());
    let c = shape::closest(&ba.shape, &ba.pose, &bb.shape, &bb.pose, cache);
    if !c.closest.penetrating {
        return c.closest.distance;
    }
    depth::shape_penetration(&ba.shape, &ba.pose, &bb.shape, &bb.pose)
        .map_or(0.0, |(p, _)| -p.depth)
}

/// Runs the chain with self-collision `on` in contact model `mode`: the smallest signed
/// distance between links `a` and `c` over every frame, and the world at the end.
fn fold(on: bool, mode: ContactMode) -> (f64, World) {
    let mut settings = WorldSettings::new(EPS);
    settings.contact_mode = mode;
    let mut w = World::new(settings).unwrap();
    let (sim, shapes) = chain();
    let options = MultibodyOptions::default().with_self_collision(on);
    let h = w.add_multibody_with("chain", sim, shapes, options).unwrap();
    assert_eq!(w.self_collision(h), Some(on));
    w.set_checking(true);
    let (a, c) = (w.link_body(h, "a").unwrap(), w.link_body(h, "c").unwrap());
    let mut cache = PairCache::default();
    let mut lowest = signed_distance(&w, a, c, &mut cache);
    let mut k = 0;
    while w.time() < DURATION {
        k += 1;
        w.step_until(k as f64 * FRAME).unwrap();
        lowest = lowest.min(signed_distance(&w, a, c, &mut cache));
    }
    (lowest, w)
}

/// (c) With self-collision on, the last link strikes the first and never sinks into it
/// deeper than ε_c at any frame (brute-force distance; the world's own checking monitor
/// agrees), and comes to rest on it; with it off, the same chain folds through the first
/// link (the option is what stops it). Both contact models (link pairs are impulses in
/// both).
#[test]
fn a_chain_folding_onto_itself_collides_only_with_self_collision_on() {
    for mode in [ContactMode::Switching, ContactMode::Impulse] {
        fold_in(mode);
    }
}

fn fold_in(mode: ContactMode) {
    let (lowest, w) = fold(true, mode);
    let checked = w.checked_penetration().unwrap().clone();
    eprintln!(
        "{mode:?}, on: lowest a–c distance {lowest:.3e} m, {} link contacts, {} unresolved, monitor {:.3e}",
        w.counters().link_contacts,
        w.counters().unresolved,
        checked.max_depth
    );
    assert!(lowest >= -EPS, "link c sank {lowest:e} m into link a");
    assert!(checked.max_depth <= EPS, "{checked:?}");
    assert!(w.counters().link_contacts > 0, "c never struck a");
    let h = w.multibody_handle("chain").unwrap();
    let (a, c) = (w.link_body(h, "a").unwrap(), w.link_body(h, "c").unwrap());
    let rest = signed_distance(&w, a, c, &mut PairCache::default());
    assert!(rest <= REST_GAP, "c ends {rest:e} m above a, not on it");
    let (lowest_off, w) = fold(false, mode);
    eprintln!(
        "{mode:?}, off: lowest a–c distance {lowest_off:.3e} m, {} link contacts",
        w.counters().link_contacts
    );
    assert!(
        lowest_off < -THROUGH,
        "without self-collision c should pass through a: {lowest_off:e}"
    );
    assert_eq!(w.counters().link_contacts, 0);
}
