//! Tests of the heap keys that avoid closest-feature queries: island bodies' load envelopes
//! (`envelope.rs`), far pairs bounded by their spheres ([`World::far_bound`]) and compound
//! pairs bounded from their last query ([`World::cached_bound`]). Each checks a key against
//! what the bodies do, measured from outside the loop, or against a fresh query's.

use glam::DVec3;
use impulse_collide::{PairCache, shape};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

use crate::scene::{BodyDesc, ContactDesc, RotationDesc, Scene, SceneDesc, ShapeDesc};
use crate::sustained::ContactMode;
use crate::world::World;

fn world_of(desc: SceneDesc) -> World {
    World::from_scene(&Scene::new(desc, ".")).expect("a valid scene")
}

fn unit(rng: &mut Xoshiro256PlusPlus) -> DVec3 {
    loop {
        let v = DVec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        );
        if (1e-3..=1.0).contains(&v.length()) {
            return v.normalize();
        }
    }
}

/// Through a small pile settling (eight tilted boxes dropped onto a floor), every island
/// body's actual load lies inside the envelope its keys were computed for after every
/// millisecond, and the independent monitor, sampling at every loop step, sees no overlap
/// deeper than ε_c.
#[test]
fn island_bodies_keep_their_loads_inside_their_envelopes() {
    let eps = 1e-3;
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(8);
    let mut desc = SceneDesc::new()
        .with_collision_epsilon(eps)
        .with_contact_model(ContactMode::Switching)
        .with_default_contact(ContactDesc::new(0.5, 0.2))
        .with_body(
            BodyDesc::fixed("floor", ShapeDesc::cuboid([3.0, 3.0, 0.25])).at([0.0, 0.0, -0.25]),
        );
    for k in 0..8 {
        let (i, j, l) = (k % 2, (k / 2) % 2, k / 4);
        desc = desc.with_body(
            BodyDesc::new(format!("box{k}"), ShapeDesc::cuboid([0.25; 3]))
                .at([
                    0.6 * f64::from(i) - 0.3,
                    0.6 * f64::from(j) - 0.3,
                    0.55 + 0.6 * f64::from(l),
                ])
                .with_rotation(RotationDesc::axis_angle(
                    unit(&mut rng).to_array(),
                    rng.random_range(2.0..6.0),
                ))
                .with_density(1000.0),
        );
    }
    let mut w = world_of(desc);
    w.set_checking(true);
    let g = w.gravity();
    let (mut enveloped, mut t) = (0usize, 0.0);
    while t < 1.5 {
        t += 1e-3;
        w.step_until(t).unwrap();
        for (_, b) in w.bodies() {
            if let Some(e) = b.envelope {
                enveloped += 1;
                assert!(
                    e.holds(b.acceleration(g), b.total_torque()),
                    "t {t}: {} has acceleration {} and torque {} outside {e:?}",
                    b.name,
                    b.acceleration(g),
                    b.total_torque()
                );
            }
        }
    }
    assert!(enveloped > 1000, "only {enveloped} enveloped body-steps");
    let depth = w.checked_penetration().unwrap().max_depth;
    assert!(depth <= eps, "deepest overlap {depth} > ε_c");
}

/// A far pair's key (its bounding spheres' bound) comes no later than the first time the two
/// bodies actually come within the scheduling target of each other: 200 pairs of tumbling
/// boxes thrown at each other in random gravity, their distance measured by the collision
/// crate's closest features on the bodies advanced outside the world (first crossing found
/// by sampling, then bisection).
#[test]
fn a_far_pairs_key_comes_before_the_bodies_close_in() {
    const CASES: usize = 200;
    let eps = 1e-3;
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(91);
    let (mut checked, mut tightest) = (0, f64::INFINITY);
    for case in 0..CASES {
        let half = |r: &mut Xoshiro256PlusPlus| {
            [
                r.random_range(0.05..0.5),
                r.random_range(0.05..0.5),
                r.random_range(0.05..0.5),
            ]
        };
        let (ha, hb) = (half(&mut rng), half(&mut rng));
        let dir = unit(&mut rng);
        let apart =
            rng.random_range(1.0..4.0) * (DVec3::from(ha).length() + DVec3::from(hb).length());
        let speed = rng.random_range(0.1..5.0);
        let body = |name: &str, h: [f64; 3], at: DVec3, v: DVec3, r: &mut Xoshiro256PlusPlus| {
            BodyDesc::new(name, ShapeDesc::cuboid(h))
                .at(at.to_array())
                .with_rotation(RotationDesc::axis_angle(
                    unit(r).to_array(),
                    r.random_range(0.0..180.0),
                ))
                .with_velocity(v.to_array())
                .with_angular_velocity((unit(r) * r.random_range(0.0..20.0)).to_array())
                .with_density(r.random_range(100.0..5000.0))
        };
        let a = body(
            "a",
            ha,
            DVec3::ZERO,
            dir * speed + unit(&mut rng) * 0.3 * speed,
            &mut rng,
        );
        let b = body(
            "b",
            hb,
            dir * apart,
            -dir * speed * rng.random_range(0.0..1.0),
            &mut rng,
        );
        let g = unit(&mut rng) * rng.random_range(0.0..20.0);
        let mut w = world_of(
            SceneDesc::new()
                .with_collision_epsilon(eps)
                .with_gravity(g.to_array())
                .with_body(a)
                .with_body(b),
        );
        let (ia, ib) = (0u32, 1u32);
        let Some(key) = w.far_bound((ia, ib)) else {
            continue; // not far enough apart for the sphere bound
        };
        checked += 1;
        let (mut ba, mut bb) = (w.b(ia).clone(), w.b(ib).clone());
        let target = 0.5 * eps;
        let mut cache = PairCache::default();
        let mut distance = |x: &crate::body::Body, y: &crate::body::Body| {
            shape::closest(&x.shape, &x.pose, &y.shape, &y.pose, &mut cache)
                .closest
                .distance
        };
        // March in steps of 0.1 ms up to 2 s; bisect the first crossing.
        let (dt, integ) = (1e-4, w.integrator);
        let (mut t, mut crossed) = (0.0, None);
        while t < 2.0 {
            let (pa, pb) = (ba.clone(), bb.clone());
            ba.advance(dt, g, &integ).unwrap();
            bb.advance(dt, g, &integ).unwrap();
            if distance(&ba, &bb) <= target {
                let (mut lo, mut hi) = (0.0, dt);
                for _ in 0..40 {
                    let mid = 0.5 * (lo + hi);
                    let (mut xa, mut xb) = (pa.clone(), pb.clone());
                    xa.advance(mid, g, &integ).unwrap();
                    xb.advance(mid, g, &integ).unwrap();
                    if distance(&xa, &xb) <= target {
                        hi = mid;
                    } else {
                        lo = mid;
                    }
                }
                crossed = Some(t + hi);
                break;
            }
            t += dt;
        }
        if let Some(close) = crossed {
            assert!(
                key <= close + 1e-9,
                "case {case}: key {key} after the bodies came within ½ε_c at {close}"
            );
            tightest = tightest.min(close - key);
        }
    }
    assert!(checked >= CASES / 2, "only {checked} far pairs");
    eprintln!("{checked} far pairs; closest key to a crossing {tightest:e} s before it");
}

#[test]
fn near_pairs_and_links_are_not_bounded_by_spheres() {
    // Two unit cubes 0.2 apart: their spheres (r = 0.87) overlap.
    let mut w = world_of(
        SceneDesc::new()
            .with_body(BodyDesc::new("a", ShapeDesc::cuboid([0.5; 3])))
            .with_body(BodyDesc::new("b", ShapeDesc::cuboid([0.5; 3])).at([1.2, 0.0, 0.0])),
    );
    assert_eq!(w.far_bound((0, 1)), None);
}

/// A random fixed body of six boxes around a link (a slider on a prismatic joint, or a
/// rod on a revolute one, moving at up to 3 m/s or 30 rad/s, no gravity), as a scene.
fn link_beside_a_compound(rng: &mut Xoshiro256PlusPlus) -> String {
    let mut parts = Vec::new();
    for _ in 0..6 {
        // A box whose centre is 0.2–1.5 m from the link's, in a random direction.
        let at = unit(rng) * rng.random_range(0.2..1.5);
        let half = [
            rng.random_range(0.02..0.1),
            rng.random_range(0.02..0.1),
            rng.random_range(0.02..0.1),
        ];
        parts.push(format!(
            "Part(shape: Box(half_extents: ({}, {}, {})), position: ({}, {}, {}))",
            half[0], half[1], half[2], at.x, at.y, at.z
        ));
    }
    let axis = unit(rng);
    let (kind, rate, pivot) = if rng.random_bool(0.5) {
        ("Prismatic", rng.random_range(-3.0..3.0), 0.0)
    } else {
        (
            "Revolute",
            rng.random_range(-30.0..30.0),
            rng.random_range(-0.1..0.1),
        )
    };
    format!(
        r#"Scene(gravity: (0.0, 0.0, 0.0), collision_epsilon: 1e-3,
    bodies: [Body(name: "bracket", motion: Fixed, shape: Compound(parts: [{}]))],
    multibodies: [Multibody(name: "m", base: Fixed, position: (0.0, 0.0, 0.0),
        links: [
            Link(name: "support"),
            Link(name: "mover", shape: Some(Box(half_extents: (0.05, 0.03, 0.02))), position: ({pivot}, 0.0, 0.0), mass: Some(Mass(1.0))),
        ],
        joints: [Joint(name: "j", kind: {kind}, parent: "support", child: "mover", axis: ({}, {}, {}), qd: {rate})],
    )],
)"#,
        parts.join(", "),
        axis.x,
        axis.y,
        axis.z
    )
}

/// A compound pair's cached bound (`quick_bounds.rs`), asked at the instant of its query,
/// is that query's key to the bit — every piece pair bounded along its own normal as the
/// query bounds it, the piece pairs skipped by the bodies' direction-free coefficients
/// (links' and fixed bodies') included: 400 random links moving beside random fixed bodies
/// of six boxes, with and without the skip. Where the key comes from a piece pair other
/// than the closest (a link moving fast toward a far box), a cached bound that took the
/// closest piece pair's alone would be late.
#[test]
fn a_compound_pairs_cached_bound_at_its_query_is_its_key() {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(41);
    let (mut compared, mut skipped) = (0, 0u64);
    for case in 0..400 {
        let text = link_beside_a_compound(&mut rng);
        let desc = SceneDesc::from_ron(&text, "case").expect("a valid scene");
        let Ok(w) = World::from_scene(&Scene::new(desc, ".")) else {
            continue; // drawn overlapping
        };
        let bracket = w.handle("bracket").expect("named").index;
        let link = w
            .bodies()
            .find(|(_, b)| b.is_link() && b.shape.pieces().len() == 1)
            .map(|(h, _)| h.index)
            .expect("the mover's body");
        let pair = (bracket.min(link), bracket.max(link));
        for skip in [true, false] {
            let mut w = w.clone();
            w.faults.no_free_skip = !skip;
            // A fresh query (the world's first keys were made when it was built).
            if let Some(state) = w.pairs.get_mut(&pair) {
                state.last = None;
            }
            let queried = w.bound(pair).expect("bounded");
            let Some(cached) = w.cached_bound(pair) else {
                continue; // within the envelope, or a piece pair without a normal
            };
            assert_eq!(
                cached.to_bits(),
                queried.to_bits(),
                "case {case} (skip {skip}): cached {cached} against the query's {queried}"
            );
            compared += 1;
        }
        skipped += w
            .faults
            .free_skips
            .load(std::sync::atomic::Ordering::Relaxed);
    }
    assert!(compared > 400, "only {compared} bounds compared");
    eprintln!("{compared} bounds compared, {skipped} piece pairs skipped");
    assert!(skipped > 100, "only {skipped} piece pairs skipped");
}
