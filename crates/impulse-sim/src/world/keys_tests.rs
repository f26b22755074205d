//! Tests of the heap keys that avoid closest-feature queries: island bodies' load envelopes
//! (`envelope.rs`) and far pairs bounded by their spheres ([`World::far_bound`]). Each checks
//! a key against what the bodies do, measured from outside the loop.

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
