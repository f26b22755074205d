//! Impacts: V9 two balls, V10 chain of balls, V14 pool break, V15 tumbling box (elastic and
//! dissipative), a bullet through a plate, and determinism across thread counts.

use glam::DVec3;
use impulse_sim::run;
use impulse_sim::scene::ShapeDesc;

use super::{Run, SceneCheck, half_extents, holds, load_scene, no_penetration, sphere_radius};
use crate::validate::case::{Check, Metric};

/// V9: post-impact velocities, relative to v0 (digest: 1e-6).
const TWO_BALL_REL: f64 = 1e-6;
/// V10: speeds of the balls that should stay, and of the striker, relative to v0 (digest 5 %).
const CHAIN_STILL_REL: f64 = 0.05;
/// V10: the striker must not recoil: its velocity may be negative only by rounding (relative
/// to v0).
const CHAIN_ROUNDING: f64 = 1e-12;
/// V10: least speed of the far ball, relative to v0 (digest 95 %).
const CHAIN_FAR_MIN: f64 = 0.95;
/// V14: a rack ball has been struck when it moves horizontally faster than this fraction of
/// the cue's launch speed (resting balls vibrate vertically, by microcollisions with the
/// table, at a few √(2gε_c) ≈ 3 cm/s: a test of the full speed found the rack "struck" before
/// the cue arrived).
const STRUCK_REL: f64 = 1e-2;
/// V14: frames after the first struck frame that the momentum window spans (at the scene's
/// 1 kHz: 20 ms, the impulse train through the rack, and no rail yet).
const BREAK_FRAMES: usize = 20;
/// V14: by the end of the window the rack must carry at least this fraction of the cue's
/// momentum: the window holds the break (a window before it would check nothing).
const BREAK_TRANSFER_MIN: f64 = 0.5;
/// V14: rounding allowance on momentum and energy, relative to the cue's.
const POOL_ROUNDING_REL: f64 = 1e-9;
/// V15 elastic: kinetic energy conservation, relative (digest: 1e-6).
const ELASTIC_ENERGY_REL: f64 = 1e-6;
/// V15 dissipative: the largest rise of kinetic energy between frames, relative (digest:
/// monotone within 1e-9).
const MONOTONE_ENERGY_REL: f64 = 1e-9;
/// V15: the runs must be busy (so the energy checks mean something).
const TUMBLING_MIN_COLLISIONS: u64 = 100;
/// Bullet: a bullet that deflects has lost at least this fraction of its speed along x.
const DEFLECTED_REL: f64 = 1e-3;

pub(super) fn checks() -> Vec<SceneCheck> {
    vec![
        SceneCheck {
            case: "V14-pool-break",
            scene: "pool-break",
            description: "15-ball rack ε_c apart broken by a cue ball with draw: across the break the balls' horizontal momentum changes by no more than table friction allows (μgΔt per kg) and their kinetic energy does not rise, from recorded states",
            headline: "momentum_change_over_friction_bound",
            event_log: false,
            thesis: Some(("pool break", 9.0)),
            metrics: v14_pool,
        },
        SceneCheck {
            case: "V9-two-ball",
            scene: "two-ball-collision",
            description: "central frictionless collision of equal balls: v0(1 − e)/2 and v0(1 + e)/2 (1e-6)",
            headline: "target_v",
            event_log: false,
            thesis: None,
            metrics: v9_two_ball,
        },
        SceneCheck {
            case: "V10-chain-of-balls",
            scene: "chain-of-balls",
            description: "striker into a row of balls ε_c apart, e = 1: far ball ≥ 0.95 v0, others and striker < 0.05 v0, no recoil",
            headline: "far_ball_speed_over_v0",
            event_log: false,
            thesis: Some(("chain of balls", 1.2)),
            metrics: v10_chain,
        },
        SceneCheck {
            case: "V15-tumbling-box-elastic",
            scene: "tumbling-box-elastic",
            description: "26 tumbling convex bodies in a closed box, g = 0, e = 1, μ = 0: kinetic energy conserved to 1e-6, no interpenetration",
            headline: "max_energy_change_rel",
            event_log: false,
            thesis: Some(("exploding text", 4.5)),
            metrics: v15_elastic,
        },
        SceneCheck {
            case: "V15-tumbling-box",
            scene: "tumbling-box",
            description: "26 tumbling convex bodies in a closed box, g = 0, e = 0.8, μ = 0.3: kinetic energy never rises, no interpenetration",
            headline: "max_energy_rise_rel",
            event_log: false,
            thesis: Some(("exploding text", 4.5)),
            metrics: v15_dissipative,
        },
        SceneCheck {
            case: "bullet-through-plate",
            scene: "bullet-through-plate",
            description: "1 km/s bodies spinning at 1000 rad/s at a 1 mm plate: they bounce or deflect, never pass through",
            headline: "max_penetration_over_eps_c",
            event_log: false,
            thesis: None,
            metrics: bullet,
        },
    ]
}

/// The restitution of the contact between bodies `a` and `b`.
fn restitution(r: &Run<'_>, a: &str, b: &str) -> Result<f64, String> {
    Ok(super::contact(r, a, b)?.restitution)
}

fn v9_two_ball(r: &Run<'_>) -> Result<Vec<Metric>, String> {
    let (a, b) = (r.index("striker")?, r.index("target")?);
    let v = DVec3::from_array(r.desc("striker")?.velocity);
    let (v0, dir) = (v.length(), v.normalize());
    let e = restitution(r, "striker", "target")?;
    let last = r.last()?;
    Ok(vec![
        Metric::new(
            "striker_v",
            last.bodies[a].velocity.dot(dir),
            v0 * (1.0 - e) / 2.0,
            Check::Abs(TWO_BALL_REL * v0),
        ),
        Metric::new(
            "target_v",
            last.bodies[b].velocity.dot(dir),
            v0 * (1.0 + e) / 2.0,
            Check::Abs(TWO_BALL_REL * v0),
        ),
        Metric::new(
            "collisions",
            r.rec.counters.collisions as f64,
            1.0,
            Check::Exact,
        ),
    ])
}

/// V10. The chain: the dynamic bodies other than the striker, ordered along its velocity.
fn v10_chain(r: &Run<'_>) -> Result<Vec<Metric>, String> {
    let v = DVec3::from_array(r.desc("striker")?.velocity);
    let (v0, dir) = (v.length(), v.normalize());
    let mut chain: Vec<(f64, &str)> = r
        .scene
        .desc
        .bodies
        .iter()
        .filter(|b| b.name != "striker")
        .map(|b| (DVec3::from_array(b.position).dot(dir), b.name.as_str()))
        .collect();
    chain.sort_by(|x, y| x.0.total_cmp(&y.0));
    let (&(_, far), still) = chain.split_last().ok_or("no chain")?;
    let last = r.last()?;
    let vel = |name: &str| -> Result<DVec3, String> { Ok(last.bodies[r.index(name)?].velocity) };
    let mut m = vec![
        Metric::new(
            "far_ball_speed_over_v0",
            vel(far)?.dot(dir) / v0,
            1.0,
            Check::Between(CHAIN_FAR_MIN, 1.0 + 1e-9),
        ),
        Metric::new(
            "striker_v_over_v0",
            vel("striker")?.dot(dir) / v0,
            0.0,
            Check::Between(-CHAIN_ROUNDING, CHAIN_STILL_REL),
        ),
    ];
    for (_, name) in still {
        m.push(Metric::new(
            format!("{name}_speed_over_v0"),
            vel(name)?.length() / v0,
            0.0,
            Check::Between(0.0, CHAIN_STILL_REL),
        ));
    }
    m.push(no_penetration(r));
    Ok(m)
}

/// V14. The balls are the dynamic spheres; the window runs from the last frame before any
/// rack ball moves to [`BREAK_FRAMES`] frames after. Over it the table can change the balls'
/// horizontal momentum by at most μ·g·Δt·Σm (Coulomb friction under a normal force of at
/// most m·g each, the balls' weight: they do not press harder on the table in a horizontal
/// break), and nothing can raise their kinetic energy by more than the work of gravity, zero
/// on a level table. Both read from recorded states only, not from the impulses applied.
fn v14_pool(r: &Run<'_>) -> Result<Vec<Metric>, String> {
    let balls: Vec<(usize, f64)> = r
        .dynamic()
        .into_iter()
        .filter(|&i| matches!(r.scene.desc.bodies[i].shape, ShapeDesc::Sphere { .. }))
        .map(|i| {
            let m = r
                .world
                .body(r.rec.handles[i])
                .and_then(|b| b.mass)
                .map_or(0.0, |m| m.mass);
            (i, m)
        })
        .collect();
    let cue = r.index("cue")?;
    let cue_desc = r.desc("cue")?;
    let v_cue = DVec3::from_array(cue_desc.velocity).length();
    let frames = &r.rec.frames;
    let rack: Vec<usize> = balls.iter().map(|b| b.0).filter(|&i| i != cue).collect();
    let horizontal = |v: DVec3| DVec3::new(v.x, v.y, 0.0);
    let struck = |f: &impulse_sim::Frame, i: usize| {
        horizontal(f.bodies[i].velocity).length() > STRUCK_REL * v_cue
    };
    let k1 = frames
        .iter()
        .position(|f| rack.iter().any(|&i| struck(f, i)))
        .ok_or("the cue ball never reached the rack")?;
    let (k0, k2) = (k1.saturating_sub(1), k1 + BREAK_FRAMES);
    let end = frames.get(k2).ok_or("the run ends during the break")?;
    let start = &frames[k0];
    // No ball may touch a rail in the window (then the rails would take momentum too).
    let rails: Vec<&impulse_sim::scene::BodyDesc> = r
        .scene
        .desc
        .bodies
        .iter()
        .filter(|b| b.name.starts_with("rail"))
        .collect();
    let radius = sphere_radius(cue_desc)?;
    for f in &frames[k0..=k2] {
        for &(i, _) in &balls {
            let c = f.bodies[i].com;
            for rail in &rails {
                let h = half_extents(rail)?;
                let d = (c - DVec3::from_array(rail.position)).abs() - h;
                if d.max(DVec3::ZERO).length() < 2.0 * radius {
                    return Err(format!(
                        "a ball nears {} during the break window",
                        rail.name
                    ));
                }
            }
        }
    }
    let momentum = |f: &impulse_sim::Frame| -> DVec3 {
        balls
            .iter()
            .map(|&(i, m)| horizontal(f.bodies[i].velocity) * m)
            .sum()
    };
    let energy = |f: &impulse_sim::Frame| -> f64 {
        balls
            .iter()
            .map(|&(i, m)| {
                let b = r.world.body(r.rec.handles[i]);
                let s = f.bodies[i];
                let spin = b.map_or(0.0, |b| {
                    let inertia = b.inertia_world(); // a ball's inertia is isotropic
                    0.5 * s.omega.dot(inertia * s.omega)
                });
                0.5 * m * s.velocity.length_squared() + spin
            })
            .sum()
    };
    let total_mass: f64 = balls.iter().map(|b| b.1).sum();
    let table_mu = super::sliding::friction(r, "cue", "table")?;
    let dt = end.time - start.time;
    let bound = table_mu * r.g() * dt * total_mass;
    let p_cue = balls.iter().find(|b| b.0 == cue).map_or(0.0, |b| b.1) * v_cue;
    let dp = (momentum(end) - momentum(start)).length();
    let (e0, e1) = (energy(start), energy(end));
    let rack_momentum: DVec3 = balls
        .iter()
        .filter(|b| b.0 != cue)
        .map(|&(i, m)| horizontal(end.bodies[i].velocity) * m)
        .sum();
    Ok(vec![
        Metric::new(
            "momentum_change_over_friction_bound",
            dp / (bound + POOL_ROUNDING_REL * p_cue),
            0.0,
            Check::Between(0.0, 1.0),
        ),
        Metric::new(
            "energy_rise_rel",
            (e1 - e0) / e0,
            0.0,
            Check::Between(-1.0, POOL_ROUNDING_REL),
        ),
        Metric::new(
            "rack_momentum_over_cue",
            rack_momentum.length() / p_cue,
            1.0,
            // More than the cue brought when the cue, with draw, comes back.
            Check::Between(BREAK_TRANSFER_MIN, 2.0),
        ),
        holds(
            "all_balls_on_table",
            r.last()?
                .bodies
                .iter()
                .enumerate()
                .filter(|(i, _)| balls.iter().any(|b| b.0 == *i))
                .all(|(_, b)| b.com.z > 0.0),
        ),
        no_penetration(r),
    ])
}

fn v15_elastic(r: &Run<'_>) -> Result<Vec<Metric>, String> {
    let e0 = r.rec.frames[0].kinetic_energy;
    let worst = r
        .rec
        .frames
        .iter()
        .map(|f| (f.kinetic_energy - e0).abs() / e0)
        .fold(0.0, f64::max);
    Ok(vec![
        Metric::new(
            "max_energy_change_rel",
            worst,
            0.0,
            Check::Between(0.0, ELASTIC_ENERGY_REL),
        ),
        holds(
            "collisions_positive",
            r.rec.counters.collisions > TUMBLING_MIN_COLLISIONS,
        ),
        no_penetration(r),
    ])
}

fn v15_dissipative(r: &Run<'_>) -> Result<Vec<Metric>, String> {
    let e0 = r.rec.frames[0].kinetic_energy;
    let rise = r
        .rec
        .frames
        .windows(2)
        .map(|w| (w[1].kinetic_energy - w[0].kinetic_energy) / e0)
        .fold(0.0, f64::max);
    Ok(vec![
        Metric::new(
            "max_energy_rise_rel",
            rise,
            0.0,
            Check::Between(0.0, MONOTONE_ENERGY_REL),
        ),
        holds("energy_dissipated", r.last()?.kinetic_energy < 0.9 * e0),
        no_penetration(r),
    ])
}

/// Bullet: the aimed one must come back (still on the near side of the plate, moving away);
/// the rim one must lose speed along its flight (deflected by the rim).
fn bullet(r: &Run<'_>) -> Result<Vec<Metric>, String> {
    let last = r.last()?;
    let half_thickness = half_extents(r.desc("plate")?)?.x;
    let (b1, b2) = (r.index("bullet")?, r.index("rim-bullet")?);
    let v_rim = DVec3::from_array(r.desc("rim-bullet")?.velocity).x;
    let back = last.bodies[b1].com.x < -half_thickness && last.bodies[b1].velocity.x < 0.0;
    Ok(vec![
        holds("bullet_bounced", back),
        holds(
            "rim_bullet_deflected",
            last.bodies[b2].velocity.x < v_rim * (1.0 - DEFLECTED_REL),
        ),
        no_penetration(r),
    ])
}

/// Determinism: the tumbling box on 1 and on 2 threads, bit-identical.
pub(super) fn determinism() -> Result<Vec<Metric>, String> {
    let scene = load_scene("tumbling-box-elastic")?;
    let mut hashes = Vec::new();
    for threads in [1, 2] {
        let mut world = impulse_sim::World::from_scene(&scene).map_err(|e| e.to_string())?;
        world.set_threads(threads).map_err(|e| e.to_string())?;
        // Every step on the pool: the parallel path is what this checks.
        world.set_parallel_min_bodies(0);
        let rec =
            run(&mut world, 0.5, scene.desc.output_rate, |_| {}).map_err(|e| e.to_string())?;
        hashes.push(rec.hash());
    }
    Ok(vec![holds(
        "hash_1_thread_equals_2_threads",
        hashes[0] == hashes[1],
    )])
}
