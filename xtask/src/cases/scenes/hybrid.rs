//! Hybrid scenes (thesis §7.2–7.3: multibodies and controllers in the impulse-based world):
//! V19 triple pendulum, V20 see-saw, the furniture scene's controllers.

use glam::{DQuat, DVec3};
use impulse_multibody::Workspace;
use impulse_sim::controllers::yaw_of;
use impulse_sim::scene::WorldControllerDesc;

use super::{REST_WINDOW, Run, SceneCheck, max_mean_speed, no_penetration};
use crate::validate::case::{Check, Metric};

/// V19: the pendulum counts as at rest at its minimum-energy pose when its energy above that
/// pose's is below this fraction of what it was released with (the mallet may come to rest
/// against a ball, a little off the lowest pose).
const V19_REST_ENERGY_REL: f64 = 0.02;

/// Determinism on the hybrid scenes: each is run for this long (s) on 1 and on 2 threads,
/// (its first events: landings, link contacts, controller updates; the whole of every
/// scene would cost several minutes of the suite).
const DETERMINISM_SPAN: f64 = 0.5;

/// Determinism: every hybrid scene (one with multibodies or high-level controllers), in both
/// contact models, run on 1 and on 2 threads, every step through the pool, gives
/// bit-identical trajectories.
pub(super) fn determinism() -> Result<Vec<Metric>, String> {
    let mut metrics = Vec::new();
    for check in super::scene_checks() {
        let bundled = super::load_scene(check.scene)?;
        if bundled.desc.multibodies.is_empty() && bundled.desc.controllers.is_empty() {
            continue;
        }
        for mode in [None, Some(impulse_sim::ContactMode::Impulse)] {
            let mut scene = bundled.clone();
            if let Some(mode) = mode {
                scene.desc.contact_model = mode;
            }
            let mut hashes = Vec::new();
            for threads in [1, 2] {
                let mut world =
                    impulse_sim::World::from_scene(&scene).map_err(|e| e.to_string())?;
                world.set_threads(threads).map_err(|e| e.to_string())?;
                world.set_parallel_min_bodies(0);
                let span = DETERMINISM_SPAN.min(super::duration(&scene)?);
                let rec = impulse_sim::run(&mut world, span, scene.desc.output_rate, |_| {})
                    .map_err(|e| e.to_string())?;
                hashes.push(rec.hash());
            }
            let suffix = if mode.is_some() {
                super::IMPULSE_SUFFIX
            } else {
                ""
            };
            metrics.push(super::holds(
                &format!("{}{suffix}_hash_1_thread_equals_2_threads", check.scene),
                hashes[0] == hashes[1],
            ));
        }
    }
    Ok(metrics)
}

/// Furniture: the launched body rests on its target body when their distance stays below
/// this many ε_c. A microcollision happens within ε_c and its rebound speed is capped at
/// √(2·g·ε_c) (thesis eq. 3.18), which rises at most ε_c more: the impulse model's resting
/// contacts hop up to 2 ε_c (the bottle, steered on the table top: 1.3); held contacts rest
/// at the rest band (0.5).
const LAUNCH_REST_GAP_EPS: f64 = 2.0;

/// Furniture: a steered body with uprighting torques counts as upright when its z axis is
/// within this angle of the world's (degrees).
const FURNITURE_TILT_DEGREES: f64 = 1.0;

pub(super) fn checks() -> Vec<SceneCheck> {
    vec![
        SceneCheck {
            case: "V20-see-saw",
            scene: "see-saw",
            description: "eight balls roll down a tray onto a see-saw hinged in its opening: all eight are below the opening at the end, the plank's hinge point never leaves its pivot (reduced coordinates), no interpenetration",
            headline: "hinge_drift_over_eps_c",
            event_log: false,
            thesis: Some(("see-saw", 3.2)),
            metrics: v20_see_saw,
        },
        SceneCheck {
            case: "V19-triple-pendulum",
            scene: "triple-pendulum",
            description: "an undamped triple pendulum swinging into six balls in a dish: total energy never rises by more than one microcollision kick (Σm·g·ε_c), the pendulum ends at rest at its minimum-energy pose, no interpenetration",
            headline: "pendulum_rest_energy_rel",
            event_log: false,
            thesis: Some(("triple pendulum", 25.9)),
            metrics: v19_triple_pendulum,
        },
        SceneCheck {
            case: "furniture",
            scene: "furniture",
            description: "a table steered through three goals by external forces and torques, two chairs steered to places in the table's frame, a bottle launched onto the table by velocity overwrite and steered to its centre: every steered body ends within its goal's reach, passed through every goal on the way, the bottle rests upright on the table top (their distance within 2 ε_c over the last rest window), all at rest, no interpenetration",
            headline: "worst_goal_error_over_reach",
            event_log: false,
            thesis: Some(("furniture", 53.0)),
            metrics: furniture,
        },
    ]
}

/// The furniture scene: the steered bodies' goals, the launched body's landing, read from
/// the scene's controllers; the poses from the recording (the controllers' own bookkeeping
/// is not consulted).
fn furniture(r: &Run<'_>) -> Result<Vec<Metric>, String> {
    let last = r.last()?;
    let pose = |frame: &impulse_sim::Frame, name: &str| -> Result<(DVec3, DQuat), String> {
        let b = &frame.bodies[r.index(name)?];
        Ok((b.position, b.rotation))
    };
    let flat = DVec3::new(1.0, 1.0, 0.0);
    let (mut worst, mut unvisited, mut settle, mut tilt) = (0.0_f64, 0.0, f64::INFINITY, 0.0_f64);
    let (mut gap, mut launches) = (0.0_f64, 0);
    for c in &r.scene.desc.controllers {
        match c {
            WorldControllerDesc::Steer {
                body,
                goals,
                relative_to,
                reach,
                reach_angle,
                settle_speed,
                upright,
                ..
            } => {
                settle = settle.min(*settle_speed);
                // A goal in world coordinates at the frame's instant.
                let goal_at = |frame: &impulse_sim::Frame,
                               g: &impulse_sim::scene::GoalDesc|
                 -> Result<(DVec3, Option<f64>), String> {
                    let p = DVec3::from_array(g.position);
                    match relative_to {
                        None => Ok((p, g.yaw)),
                        Some(other) => {
                            let (x, q) = pose(frame, other)?;
                            Ok((x + q * p, g.yaw.map(|y| y + yaw_of(q))))
                        }
                    }
                };
                let (x, q) = pose(last, body)?;
                let final_goal = goals.last().ok_or("a Steer with no goals")?;
                let (g, yaw) = goal_at(last, final_goal)?;
                worst = worst.max(((g - x) * flat).length() / reach);
                if let Some(yaw) = yaw {
                    let e = (yaw - yaw_of(q) + std::f64::consts::PI)
                        .rem_euclid(std::f64::consts::TAU)
                        - std::f64::consts::PI;
                    worst = worst.max(e.abs() / reach_angle);
                }
                if *upright {
                    tilt = tilt.max((q * DVec3::Z).angle_between(DVec3::Z).to_degrees());
                }
                // Every goal but the last passed within reach at some recorded frame.
                for goal in &goals[..goals.len() - 1] {
                    let mut near = false;
                    for f in &r.rec.frames {
                        let (g, _) = goal_at(f, goal)?;
                        near |= ((g - pose(f, body)?.0) * flat).length() <= *reach;
                    }
                    unvisited += f64::from(u8::from(!near));
                }
            }
            WorldControllerDesc::Launch {
                body, relative_to, ..
            } => {
                let Some(other) = relative_to else { continue };
                // Resting on the body it was launched onto: their distance, from the
                // recorded poses, stays within the envelope over the last rest window.
                let body_of = |name: &str| -> Result<&impulse_sim::body::Body, String> {
                    let h = r.world.handle(name).ok_or("no such body")?;
                    r.world.body(h).ok_or_else(|| "no such body".to_string())
                };
                let (a, b) = (body_of(body)?, body_of(other)?);
                let (ia, ib) = (r.index(body)?, r.index(other)?);
                let mut cache = impulse_collide::PairCache::default();
                for f in r
                    .rec
                    .frames
                    .iter()
                    .filter(|f| f.time >= last.time - REST_WINDOW)
                {
                    // Body frame = own frame composed with the own frame's inverse placement.
                    let place = |st: &impulse_sim::BodyState, b: &impulse_sim::body::Body| {
                        impulse_geom::Pose::new(st.rotation, st.position) * b.frame.inverse()
                    };
                    let (pa, pb) = (place(&f.bodies[ia], a), place(&f.bodies[ib], b));
                    let d =
                        impulse_collide::shape::closest(&a.shape, &pa, &b.shape, &pb, &mut cache)
                            .closest
                            .distance;
                    gap = gap.max(d);
                }
                launches += 1;
            }
        }
    }
    if launches == 0 || !settle.is_finite() {
        return Err("the furniture scene needs a Steer and a Launch controller".into());
    }
    let eps = r.world.collision_epsilon();
    Ok(vec![
        Metric::new(
            "worst_goal_error_over_reach",
            worst,
            0.0,
            Check::Between(0.0, 1.0),
        ),
        Metric::new("unvisited_goals", unvisited, 0.0, Check::Between(0.0, 0.0)),
        Metric::new(
            "launched_max_gap_over_eps_c",
            gap / eps,
            0.0,
            Check::Between(0.0, LAUNCH_REST_GAP_EPS),
        ),
        Metric::new(
            "max_tilt_degrees",
            tilt,
            0.0,
            Check::Between(0.0, FURNITURE_TILT_DEGREES),
        ),
        Metric::new(
            "max_mean_speed_at_end",
            max_mean_speed(r.rec, &r.dynamic())?,
            0.0,
            Check::Between(0.0, settle),
        ),
        no_penetration(r),
    ])
}

/// V20. The pivot is where the scene puts the hinge (the multibody's placement composed with
/// the joint's position, both read from the scene); the plank's link frame sits on it and
/// turns about the joint's axis only. A ball
/// has passed when its centre is below the opening by more than its radius.
fn v20_see_saw(r: &Run<'_>) -> Result<Vec<Metric>, String> {
    let desc = multibody_desc(r, "see-saw")?;
    let joint = desc.joints.first().ok_or("the see-saw has no joint")?;
    let pivot = glam::DVec3::from_array(desc.position) + glam::DVec3::from_array(joint.position);
    let axis = glam::DVec3::from_array(joint.axis).normalize();
    let plank = r.index(&format!("see-saw/{}", joint.child))?;
    // Two points of the plank on its hinge axis, 10 cm either side of the pivot (the scene
    // places the multibody and the joint without rotation): a revolute joint keeps both where
    // they started; any other motion of the plank moves one of them.
    let drift = r
        .rec
        .frames
        .iter()
        .flat_map(|f| {
            let b = &f.bodies[plank];
            [-0.1, 0.1].map(|s| (b.position + b.rotation * (axis * s)).distance(pivot + axis * s))
        })
        .fold(0.0, f64::max);
    let balls: Vec<(usize, f64)> = r
        .scene
        .desc
        .bodies
        .iter()
        .filter_map(|b| match b.shape {
            impulse_sim::scene::ShapeDesc::Sphere { radius } => Some((b.name.as_str(), radius)),
            _ => None,
        })
        .map(|(n, radius)| r.index(n).map(|i| (i, radius)))
        .collect::<Result<_, _>>()?;
    let last = r.rec.frames.last().ok_or("no frames")?;
    let below = balls
        .iter()
        .filter(|&&(i, radius)| last.bodies[i].com.z < pivot.z - radius)
        .count();
    let n = balls.len() as f64;
    Ok(vec![
        Metric::new("balls_below_opening", below as f64, n, Check::Between(n, n)),
        Metric::new(
            "hinge_drift_over_eps_c",
            drift / r.world.collision_epsilon(),
            0.0,
            Check::Between(0.0, 1e-9),
        ),
        no_penetration(r),
    ])
}

/// The description of multibody `name` in the scene that was run.
fn multibody_desc<'a>(
    r: &'a Run<'_>,
    name: &str,
) -> Result<&'a impulse_sim::scene::MultibodyDesc, String> {
    r.scene
        .desc
        .multibodies
        .iter()
        .find(|m| m.name == name)
        .ok_or_else(|| format!("no multibody \"{name}\" in the scene"))
}

/// Kinetic and potential energy of a multibody at `(q, v)`.
fn energy(model: &impulse_multibody::Model, q: &[f64], v: &[f64]) -> Result<(f64, f64), String> {
    let mut ws = Workspace::new(model);
    ws.update_kinematics(model, q, v)
        .map_err(|e| e.to_string())?;
    Ok((ws.kinetic_energy(model), ws.potential_energy(model)))
}

/// V19. The kick bound: a microcollision's rebound limit (thesis eq. 3.18) caps the normal
/// speed after at √(2 g ε_c), a kinetic energy of at most m g ε_c for the body that rebounds;
/// total energy may rise above its lowest value so far by at most the sum over every moving
/// body (balls and the pendulum's links). The pendulum's release energy and its minimum
/// (hanging straight down, every joint at zero) are computed from its model.
fn v19_triple_pendulum(r: &Run<'_>) -> Result<Vec<Metric>, String> {
    let eps = r.world.collision_epsilon();
    let h = r.world.multibody_handle("pendulum").ok_or("no pendulum")?;
    let sim = r.world.multibody(h).ok_or("no pendulum")?;
    let model = sim.model();
    let balls: f64 = r
        .world
        .bodies()
        .filter_map(|(_, b)| b.mass.map(|m| m.mass))
        .sum();
    let kick = (balls + model.total_mass()) * r.g() * eps;
    let (mut lowest, mut rise) = (f64::INFINITY, 0.0_f64);
    for f in &r.rec.frames {
        let e = f.kinetic_energy + f.potential_energy;
        rise = rise.max(e - lowest);
        lowest = lowest.min(e);
    }
    let desc = multibody_desc(r, "pendulum")?;
    let (released, _) = desc
        .build(
            glam::DVec3::from_array(r.scene.desc.gravity),
            &r.scene.base_dir,
        )
        .map_err(|e| e.to_string())?;
    let (_, p0) = energy(model, released.q(), released.v())?;
    let zero = model.neutral_configuration();
    let (_, p_min) = energy(model, &zero, &vec![0.0; model.nv()])?;
    let (k_end, p_end) = energy(model, sim.q(), sim.v())?;
    let rest = (k_end + p_end - p_min) / (p0 - p_min);
    Ok(vec![
        Metric::new(
            "energy_rise_over_kick",
            rise / kick,
            0.0,
            Check::Between(0.0, 1.0),
        ),
        Metric::new(
            "pendulum_rest_energy_rel",
            rest,
            0.0,
            Check::Between(0.0, V19_REST_ENERGY_REL),
        ),
        no_penetration(r),
    ])
}
