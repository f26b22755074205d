//! The peer engine: a scene of `impulse_sim::scene` translated into rapier3d-f64 and run with
//! rapier's defaults (only the time step changes between [`CONFIGS`]), recording every step.
//!
//! What is translated: fixed and dynamic bodies; spheres, boxes and convex hulls (rapier
//! computes the hull of the same points); mass from a density or a total mass (rapier derives
//! the centre of mass and inertia from the collider, as `impulse` does exactly); the pose of
//! the shape frame; the velocity of the centre of mass and the angular velocity; gravity; μ
//! and e per pair of materials (a contact hook sets each manifold's coefficients from the
//! scene's table, so rapier's combine rules never enter). What is refused, by name: every
//! other shape, point masses, and scripted motions.
//!
//! Differences that remain by design: rapier's restitution is Newton's (on the normal
//! velocity), `impulse`'s Stronge's (on the normal work); they agree on frictionless central
//! impacts. Rapier's tolerances are in metres unless told the length unit: the unit is taken
//! from the scene's gravity ([`length_unit`]), as rapier's documentation asks for scenes in
//! other units (`block-on-ramp.ron` is in centimetres).

use std::time::Instant;

use glam::{DQuat, DVec3};
use impulse_sim::Scene;
use impulse_sim::scene::{BodyDesc, MassDesc, MotionDesc, ShapeDesc};
use rapier3d_f64::math::{Pose, Rotation, Vector};
use rapier3d_f64::prelude::{
    ActiveHooks, CCDSolver, ColliderBuilder, ColliderSet, ContactModificationContext,
    DefaultBroadPhase, ImpulseJointSet, IntegrationParameters, IslandManager, MultibodyJointSet,
    NarrowPhase, PhysicsHooks, PhysicsPipeline, RigidBodyBuilder, RigidBodyHandle, RigidBodySet,
    SoftBodySet,
};

use super::measure::{Frame, State, Trajectory, contact_of, rotation_of};

/// Gravity of the scene's unit system at which the length unit is the metre (m/s²): the
/// bundled scenes use 9.81 m/s² or 981 cm/s².
const METRE_GRAVITY: f64 = 9.81;

/// One way of running rapier: a name for the table and its time step.
pub struct Config {
    /// Name in the table.
    pub name: &'static str,
    /// Time step (s); every other parameter is rapier's default.
    pub dt: f64,
}

/// The rapier runs of the scale bench ([`crate::scale`]): its default step, and 1 ms.
pub const SCALE_CONFIGS: [Config; 2] = [
    Config {
        name: "rapier dt 1/60",
        dt: 1.0 / 60.0,
    },
    Config {
        name: "rapier dt 1 ms",
        dt: 1e-3,
    },
];

/// The rapier runs of the bench: its default step, and a 4× finer one.
pub const CONFIGS: [Config; 2] = [
    Config {
        name: "rapier dt 1/60",
        dt: 1.0 / 60.0,
    },
    Config {
        name: "rapier dt 1/240",
        dt: 1.0 / 240.0,
    },
];

/// How many of the scene's length units make a metre, judged from its gravity (1 for SI,
/// 100 for cm): rapier's `length_unit`. Scenes without gravity are taken to be in metres.
pub fn length_unit(gravity: [f64; 3]) -> f64 {
    let g = DVec3::from_array(gravity).length();
    if g > 0.0 { g / METRE_GRAVITY } else { 1.0 }
}

/// The scene's material table, read by the contact hook: each collider carries its material's
/// index in `user_data`.
struct Materials {
    /// (μ, e) of materials `i` and `j` at `[i][j]`.
    table: Vec<Vec<(f64, f64)>>,
}

impl PhysicsHooks for Materials {
    fn modify_solver_contacts(&self, context: &mut ContactModificationContext) {
        let material = |h| context.colliders.get(h).map_or(0, |c| c.user_data as usize);
        let (a, b) = (material(context.collider1), material(context.collider2));
        let (mu, e) = self.table[a][b];
        if let Some(manifold) = context.rigid_mut() {
            *manifold.friction = mu;
            *manifold.restitution = e;
        }
    }
}

fn vector(v: DVec3) -> Vector {
    Vector::new(v.x, v.y, v.z)
}

fn dvec(v: Vector) -> DVec3 {
    DVec3::new(v.x, v.y, v.z)
}

fn rotation(q: DQuat) -> Rotation {
    Rotation::from_xyzw(q.x, q.y, q.z, q.w)
}

fn dquat(q: Rotation) -> DQuat {
    DQuat::from_xyzw(q.x, q.y, q.z, q.w)
}

/// The collider of a body, or why rapier cannot take it.
fn collider(b: &BodyDesc) -> Result<ColliderBuilder, String> {
    let builder = match &b.shape {
        ShapeDesc::Sphere { radius } => ColliderBuilder::ball(*radius),
        ShapeDesc::Box { half_extents: h } => ColliderBuilder::cuboid(h[0], h[1], h[2]),
        ShapeDesc::Hull { points } => {
            let points: Vec<Vector> = points
                .iter()
                .map(|p| vector(DVec3::from_array(*p)))
                .collect();
            ColliderBuilder::convex_hull(&points)
                .ok_or_else(|| format!("body \"{}\": rapier cannot build its hull", b.name))?
        }
        other => {
            let kind = format!("{other:?}");
            let kind = kind.split([' ', '{', '(']).next().unwrap_or("shape");
            return Err(format!(
                "body \"{}\": shape {kind} is not translated to rapier (spheres, boxes and hulls are)",
                b.name
            ));
        }
    };
    if !b.point_masses.is_empty() {
        return Err(format!(
            "body \"{}\": point masses are not translated to rapier",
            b.name
        ));
    }
    Ok(match b.mass {
        None => builder.density(1.0),
        Some(MassDesc::Density(rho)) => builder.density(rho),
        Some(MassDesc::Mass(m)) => builder.mass(m),
    })
}

/// Runs `scene` in rapier with `config` until the scene's duration or until `budget` wall
/// seconds have passed, whichever comes first; returns the states of every step (or, with
/// `record_rate`, of the first step at or after each multiple of 1/`record_rate`) and the
/// wall time of the stepping (the world is built before the clock starts, as for `impulse`;
/// recording is outside the clock).
///
/// # Errors
/// A body rapier cannot take (its name and why), or a scene without a duration.
pub fn run(
    scene: &Scene,
    config: &Config,
    budget: f64,
    record_rate: Option<f64>,
) -> Result<(Trajectory, f64), String> {
    let desc = &scene.desc;
    let duration = desc.duration.ok_or("the scene has no duration")?;
    let mut materials: Vec<&str> = desc.bodies.iter().map(|b| b.material.as_str()).collect();
    materials.sort_unstable();
    materials.dedup();
    let hooks = Materials {
        table: materials
            .iter()
            .map(|a| {
                materials
                    .iter()
                    .map(|b| {
                        let c = contact_of(desc, a, b);
                        (c.friction, c.restitution)
                    })
                    .collect()
            })
            .collect(),
    };
    let mut bodies = RigidBodySet::new();
    let mut colliders = ColliderSet::new();
    let mut handles: Vec<RigidBodyHandle> = Vec::with_capacity(desc.bodies.len());
    for b in &desc.bodies {
        let builder = match b.motion {
            MotionDesc::Dynamic => RigidBodyBuilder::dynamic(),
            MotionDesc::Fixed => RigidBodyBuilder::fixed(),
            _ => {
                return Err(format!(
                    "body \"{}\": scripted motions are not translated to rapier",
                    b.name
                ));
            }
        };
        let pose = Pose::from_parts(
            vector(DVec3::from_array(b.position)),
            rotation(rotation_of(&b.rotation)),
        );
        let body = builder
            .pose(pose)
            .linvel(vector(DVec3::from_array(b.velocity)))
            .angvel(vector(DVec3::from_array(b.angular_velocity)))
            .build();
        let handle = bodies.insert(body);
        let index = materials.binary_search(&b.material.as_str()).unwrap_or(0);
        let collider = collider(b)?
            .user_data(index as u128)
            .active_hooks(ActiveHooks::MODIFY_SOLVER_CONTACTS)
            .build();
        colliders.insert_with_parent(collider, handle, &mut bodies);
        handles.push(handle);
    }
    let parameters = IntegrationParameters {
        dt: config.dt,
        length_unit: length_unit(desc.gravity),
        ..IntegrationParameters::default()
    };
    let gravity = vector(DVec3::from_array(desc.gravity));
    let mut pipeline = PhysicsPipeline::new();
    let mut islands = IslandManager::new();
    let mut broad_phase = DefaultBroadPhase::default();
    let mut narrow_phase = NarrowPhase::new();
    let mut impulse_joints = ImpulseJointSet::new();
    let mut multibody_joints = MultibodyJointSet::new();
    let mut soft_bodies = SoftBodySet::new();
    let mut ccd = CCDSolver::new();
    let frame = |bodies: &RigidBodySet, time: f64| Frame {
        time,
        bodies: handles
            .iter()
            .map(|&h| {
                let b = &bodies[h];
                let pose = b.position();
                State {
                    position: dvec(pose.translation),
                    rotation: dquat(pose.rotation),
                    com: dvec(b.center_of_mass()),
                    velocity: dvec(b.linvel()),
                    omega: dvec(b.angvel()),
                }
            })
            .collect(),
    };
    let steps = (duration / config.dt).round() as u64;
    let mut frames = vec![frame(&bodies, 0.0)];
    let mut wall = 0.0;
    let mut next_record = 1u64;
    for k in 1..=steps {
        let start = Instant::now();
        pipeline.step(
            gravity,
            &parameters,
            &mut islands,
            &mut broad_phase,
            &mut narrow_phase,
            &mut bodies,
            &mut colliders,
            &mut impulse_joints,
            &mut multibody_joints,
            &mut soft_bodies,
            &mut ccd,
            &hooks,
            &(),
        );
        wall += start.elapsed().as_secs_f64();
        let t = k as f64 * config.dt;
        let due = record_rate.is_none_or(|rate| t * rate >= next_record as f64 * (1.0 - 1e-9));
        if due || k == steps {
            frames.push(frame(&bodies, t));
            if let Some(rate) = record_rate {
                next_record = (t * rate * (1.0 + 1e-9)).floor() as u64 + 1;
            }
        }
        if wall > budget {
            break;
        }
    }
    let names = desc.bodies.iter().map(|b| b.name.clone()).collect();
    Ok((Trajectory { names, frames }, wall))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Speed tolerance of the sliding test (m/s): rapier's first steps settle the resting
    /// contact, a few per cent of the 0.25 m/s that friction removes.
    const SLIDING_SPEED_TOL: f64 = 0.01;

    /// The length unit of the bundled scenes: metres, and centimetres for the ramp.
    #[test]
    fn length_units_of_the_bundled_scenes() {
        let g = |name| crate::cases::scenes::load_scene(name).unwrap().desc.gravity;
        assert!((length_unit(g("sliding-to-rolling")) - 1.0).abs() < 1e-12);
        assert!((length_unit(g("block-on-ramp")) - 100.0).abs() < 1e-12);
    }

    /// With a recording rate, a frame is kept at the start, at the first step at or after each
    /// multiple of the frame period, and at the end: 0.2 s at 10 frames per second with steps
    /// of 1/240 s keeps t = 0, 0.1, 0.2.
    #[test]
    fn a_recording_rate_keeps_one_frame_per_period() {
        let text = "Scene(gravity: (0.0, 0.0, -9.81), duration: 0.2, bodies: [
            Body(name: \"ball\", shape: Sphere(radius: 0.1), position: (0.0, 0.0, 3.0))])";
        let desc = impulse_sim::SceneDesc::from_ron(text, "test").unwrap();
        let (traj, _) = run(
            &Scene::new(desc, "."),
            &CONFIGS[1],
            f64::INFINITY,
            Some(10.0),
        )
        .unwrap();
        let times: Vec<f64> = traj.frames.iter().map(|f| f.time).collect();
        assert_eq!(times.len(), 3, "{times:?}");
        for (t, expected) in times.iter().zip([0.0, 0.1, 0.2]) {
            assert!((t - expected).abs() < 1e-12, "{times:?}");
        }
    }

    /// A ball dropped in rapier falls freely under the scene's gravity, starting from the
    /// scene's pose and velocity: after 0.2 s it has fallen v0·t + g t²/2 to within what the
    /// symplectic Euler step adds (g·dt·t/2), and its mass is the scene's density times its
    /// volume. Guards the translation of poses, velocities, gravity and mass.
    #[test]
    fn a_free_ball_falls_as_described() {
        let text = "Scene(gravity: (0.0, 0.0, -9.81), duration: 0.2, bodies: [
            Body(name: \"ball\", shape: Sphere(radius: 0.1), position: (1.0, 2.0, 3.0),
                 velocity: (0.5, 0.0, 1.0), mass: Density(1000.0))])";
        let desc = impulse_sim::SceneDesc::from_ron(text, "test").unwrap();
        let scene = Scene::new(desc, ".");
        let config = &CONFIGS[1];
        let (traj, _) = run(&scene, config, f64::INFINITY, None).unwrap();
        let last = traj.frames.last().unwrap();
        let t = last.time;
        let s = last.bodies[0];
        let z = 3.0 + 1.0 * t - 0.5 * 9.81 * t * t;
        let euler = 0.5 * 9.81 * config.dt * t;
        assert!((s.com.z - z).abs() <= euler * 1.01, "z {} vs {z}", s.com.z);
        assert!((s.com.x - (1.0 + 0.5 * t)).abs() < 1e-12);
        assert!((s.velocity.z - (1.0 - 9.81 * t)).abs() < 1e-9);
    }

    /// A box sliding on a floor decelerates at μ·g with the μ of its material pair, not the
    /// scene's default nor rapier's own combination: its speed after 0.5 s is v0 − μ g t.
    /// Guards the contact hook that puts the scene's material table into rapier.
    #[test]
    fn material_pairs_set_the_friction() {
        let text = "Scene(duration: 0.5, gravity: (0.0, 0.0, -9.81),
            default_contact: Contact(friction: 0.3, restitution: 0.0),
            contacts: [MaterialPair(a: \"ice\", b: \"default\", friction: 0.05, restitution: 0.0)],
            bodies: [
                Body(name: \"floor\", shape: Box(half_extents: (5.0, 5.0, 0.1)),
                     position: (0.0, 0.0, -0.1), motion: Fixed),
                Body(name: \"puck\", shape: Box(half_extents: (0.05, 0.05, 0.02)),
                     position: (0.0, 0.0, 0.02), velocity: (1.0, 0.0, 0.0), material: \"ice\")])";
        let desc = impulse_sim::SceneDesc::from_ron(text, "test").unwrap();
        let (traj, _) = run(&Scene::new(desc, "."), &CONFIGS[1], 1.0, None).unwrap();
        let last = traj.frames.last().unwrap();
        let expected = 1.0 - 0.05 * 9.81 * last.time;
        let v = last.bodies[1].velocity.x;
        assert!(
            (v - expected).abs() < SLIDING_SPEED_TOL,
            "{v} vs {expected}"
        );
    }

    /// A shape rapier is not given (a prism) is refused by name, not approximated.
    #[test]
    fn untranslated_shapes_are_refused_by_name() {
        let text = "Scene(duration: 0.1, bodies: [Body(name: \"coin\",
            shape: Prism(sides: 8, radius: 0.01, half_height: 0.002))])";
        let desc = impulse_sim::SceneDesc::from_ron(text, "test").unwrap();
        let err = run(&Scene::new(desc, "."), &CONFIGS[0], 1.0, None).unwrap_err();
        assert!(err.contains("coin") && err.contains("Prism"), "{err}");
    }

    /// A convex hull is translated, and its centre of mass is where the scene's geometry puts
    /// it: a tetrahedron's centroid, the mean of its corners.
    #[test]
    fn hulls_are_translated_with_their_centroid() {
        let text = "Scene(duration: 0.05, gravity: (0.0, 0.0, 0.0), bodies: [Body(name: \"t\",
            shape: Hull(points: [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)]))])";
        let desc = impulse_sim::SceneDesc::from_ron(text, "test").unwrap();
        let (traj, _) = run(&Scene::new(desc, "."), &CONFIGS[0], 1.0, None).unwrap();
        let com = traj.frames[0].bodies[0].com;
        assert!((com - DVec3::splat(0.25)).length() < 1e-9, "{com}");
    }
}
