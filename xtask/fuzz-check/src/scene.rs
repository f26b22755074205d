//! RON scene → world → [`STEPS`] steps of [`STEP`] under the independent penetration monitor.
//!
//! Asserted after every step: every body's state finite; the deepest penetration the monitor
//! ([`impulse_sim::PenetrationMonitor`]: its own sweep, exact distances) has seen at most ε_c
//! (the scene's, with [`DEPTH_SLACK_REL`] for rounding); the energy within
//! [`crate::energy::EnergyBound`] unless the scene has a source that bound does not cover
//! (scripted bodies, controllers, joint springs or a coarse rotation integrator: module
//! documentation of [`crate::energy`]).
//!
//! Out of bounds (module documentation of the crate): more than [`MAX_BODIES`] bodies or
//! [`MAX_LINKS`] multibody links, shapes finer than the `MAX_*` constants below, speeds above
//! [`MAX_SPEED`] or [`MAX_SPIN`], an ε_c below [`MIN_EPSILON_REL`] of the largest body, and
//! scenes that read other files (OBJ shapes, URDF multibodies: the OBJ and URDF targets cover
//! those readers, and a fuzzed path must not reach the file system).

use impulse_sim::scene::{BodyDesc, MotionDesc, ShapeDesc};
use impulse_sim::{PenetrationMonitor, PenetrationReport, Scene, SceneDesc, World, WorldSettings};

use crate::energy::{EnergyBound, MAX_ROTATION_TOLERANCE, world_energy};
use crate::{Outcome, Violation};

/// Steps of a scene check. `200`.
pub const STEPS: usize = 200;
/// Simulated time of one step (s): 200 steps are 0.2 s, a bounce or two of a dropped body.
/// `1e-3`.
pub const STEP: f64 = 1e-3;
/// Most bodies a scene may have. `40`.
pub const MAX_BODIES: usize = 40;
/// Most links over all of a scene's multibodies. `8`.
pub const MAX_LINKS: usize = 8;
/// Most points of a hull shape. `64`.
pub const MAX_HULL_POINTS: usize = 64;
/// Most sides of a prism. `64`.
pub const MAX_PRISM_SIDES: u32 = 64;
/// Largest refinement level of a geodesic sphere or polyhedral ellipsoid (1280 faces). `4`.
pub const MAX_LEVEL: u32 = 4;
/// Most parts of a compound (each bounded as a shape). `64`.
pub const MAX_PARTS: usize = 64;
/// Largest speed of a body at the start (m/s; the bullet of the bundled scenes flies at
/// 1000). `1000`.
pub const MAX_SPEED: f64 = 1000.0;
/// Largest angular speed of a body at the start, or rate of a spinner (rad/s). `2000`.
pub const MAX_SPIN: f64 = 2000.0;
/// Smallest ε_c relative to the largest body's size: a finer envelope at the largest speeds
/// asks for more time-of-impact steps than a fuzz execution has. `1e-5`.
pub const MIN_EPSILON_REL: f64 = 1e-5;
/// Rounding slack of the penetration check, relative to ε_c (the monitor's depth is exact up
/// to the separating-axis computation's rounding). `1e-9`.
pub const DEPTH_SLACK_REL: f64 = 1e-9;

/// Checks one scene file's bytes (module documentation).
///
/// # Errors
/// The [`Violation`] the run broke.
pub fn check_scene(bytes: &[u8]) -> Result<Outcome, Violation> {
    let Some(text) = crate::text(bytes) else {
        return Ok(Outcome::Rejected("not UTF-8".into()));
    };
    let desc = match SceneDesc::from_ron(text, "fuzz") {
        Ok(d) => d,
        Err(e) => return Ok(Outcome::Rejected(e.to_string())),
    };
    if let Some(reason) = out_of_bounds(&desc) {
        return Ok(Outcome::OutOfBounds(reason));
    }
    let settings = WorldSettings::from_desc(&desc);
    let unbounded = unbounded_source(&desc);
    // A directory that does not exist: nothing relative can be read (OBJ and URDF paths are
    // refused above; this is a second guard).
    let scene = Scene::new(desc, "/nonexistent-fuzz-base");
    let mut world = match World::from_scene(&scene) {
        Ok(w) => w,
        Err(e) => return Ok(Outcome::Rejected(e.to_string())),
    };
    run_checked(
        &mut world,
        &settings.sustained,
        unbounded.is_none(),
        STEPS,
        STEP,
    )
}

/// Steps `world` `steps` times by `dt`, checking after every step (module documentation).
/// A step the world refuses with an error ends the run as [`Outcome::Rejected`] (the world
/// found a state it cannot go on from and said so).
///
/// # Errors
/// The [`Violation`] found.
pub(crate) fn run_checked(
    world: &mut World,
    sustained: &impulse_sim::SustainedSettings,
    check_energy: bool,
    steps: usize,
    dt: f64,
) -> Result<Outcome, Violation> {
    let bound = EnergyBound::of(world, sustained);
    let eps = world.collision_epsilon();
    let mut monitor = PenetrationMonitor::new();
    monitor.sample(world);
    check_depth(monitor.report(), eps)?;
    for k in 1..=steps {
        let t = k as f64 * dt;
        if let Err(e) = world.step_until(t) {
            return Ok(Outcome::Rejected(format!("at t = {t} s: {e}")));
        }
        check_finite(world)?;
        monitor.sample(world);
        check_depth(monitor.report(), eps)?;
        if check_energy {
            bound.check(world_energy(world), t)?;
        }
    }
    Ok(Outcome::Checked {
        energy_checked: check_energy,
    })
}

/// Every body's pose and velocities are finite.
pub(crate) fn check_finite(world: &World) -> Result<(), Violation> {
    for (_, b) in world.bodies() {
        let ok = b.pose.translation.is_finite()
            && b.pose.rotation.is_finite()
            && b.velocity.is_finite()
            && b.omega.is_finite();
        if !ok {
            return Err(Violation::NotFinite(format!(
                "body {:?} at t = {} s: pose {:?}, v {}, ω {}",
                b.name,
                world.time(),
                b.pose,
                b.velocity,
                b.omega
            )));
        }
    }
    Ok(())
}

/// The monitor's deepest penetration is at most ε_c.
pub(crate) fn check_depth(r: &PenetrationReport, eps: f64) -> Result<(), Violation> {
    if r.max_depth > eps * (1.0 + DEPTH_SLACK_REL) {
        return Err(Violation::Penetration(format!(
            "depth {:e} > ε_c = {eps:e} ({:?})",
            r.max_depth, r.worst
        )));
    }
    Ok(())
}

/// Why the scene is beyond the check's bounds, if it is.
fn out_of_bounds(desc: &SceneDesc) -> Option<String> {
    if desc.bodies.len() > MAX_BODIES {
        return Some(format!("{} bodies > {MAX_BODIES}", desc.bodies.len()));
    }
    let links: usize = desc.multibodies.iter().map(|m| m.links.len()).sum();
    if links > MAX_LINKS {
        return Some(format!("{links} links > {MAX_LINKS}"));
    }
    if desc.multibodies.iter().any(|m| m.urdf.is_some()) {
        return Some("a multibody from a URDF file (the urdf target covers URDF)".into());
    }
    let mut size: f64 = 0.0;
    for b in &desc.bodies {
        if let Some(r) = shape_out_of_bounds(&b.shape, true) {
            return Some(format!("body {:?}: {r}", b.name));
        }
        if let Some(r) = motion_out_of_bounds(b) {
            return Some(format!("body {:?}: {r}", b.name));
        }
        size = size.max(shape_size(&b.shape));
    }
    for m in &desc.multibodies {
        for l in &m.links {
            if let Some(s) = &l.shape {
                if let Some(r) = shape_out_of_bounds(s, true) {
                    return Some(format!("link {:?}: {r}", l.name));
                }
                size = size.max(shape_size(s));
            }
        }
        let speed = norm(m.velocity);
        let spin = norm(m.angular_velocity);
        if !(within(speed, MAX_SPEED) && within(spin, MAX_SPIN)) {
            return Some(format!(
                "multibody {:?}: speed {speed} or spin {spin}",
                m.name
            ));
        }
        if m.joints.iter().any(|j| !within(j.qd.abs(), MAX_SPIN)) {
            return Some(format!(
                "multibody {:?}: a joint speed > {MAX_SPIN}",
                m.name
            ));
        }
    }
    if desc.collision_epsilon.is_finite() && desc.collision_epsilon < MIN_EPSILON_REL * size {
        return Some(format!(
            "ε_c = {} < {MIN_EPSILON_REL} of the largest body ({size})",
            desc.collision_epsilon
        ));
    }
    None
}

/// `x ≤ max`, false for NaN.
fn within(x: f64, max: f64) -> bool {
    x <= max
}

/// Euclidean norm of a 3-vector (NaN stays NaN).
fn norm(v: [f64; 3]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// Why a body's motion is beyond the bounds.
fn motion_out_of_bounds(b: &BodyDesc) -> Option<String> {
    let speed = norm(b.velocity);
    let spin = norm(b.angular_velocity);
    if !(within(speed, MAX_SPEED) && within(spin, MAX_SPIN)) {
        return Some(format!("speed {speed} or spin {spin}"));
    }
    match b.motion {
        MotionDesc::Spinner { rate, .. } if !within(rate.abs(), MAX_SPIN) => {
            Some(format!("spinner rate {rate}"))
        }
        MotionDesc::Oscillator {
            amplitude,
            frequency,
            ..
        } if !within(
            amplitude.abs() * frequency.abs() * std::f64::consts::TAU,
            MAX_SPEED,
        ) =>
        {
            Some(format!(
                "oscillator amplitude {amplitude} at {frequency} Hz"
            ))
        }
        _ => None,
    }
}

/// Why a shape is beyond the bounds (`compound_ok`: a compound may hold parts here).
pub(crate) fn shape_out_of_bounds(s: &ShapeDesc, compound_ok: bool) -> Option<String> {
    match s {
        ShapeDesc::Hull { points } if points.len() > MAX_HULL_POINTS => {
            Some(format!("{} hull points > {MAX_HULL_POINTS}", points.len()))
        }
        ShapeDesc::Prism { sides, .. } if *sides > MAX_PRISM_SIDES => {
            Some(format!("{sides} prism sides > {MAX_PRISM_SIDES}"))
        }
        ShapeDesc::GeodesicSphere { level, .. }
        | ShapeDesc::Ellipsoid {
            level: Some(level), ..
        } if *level > MAX_LEVEL => Some(format!("level {level} > {MAX_LEVEL}")),
        ShapeDesc::Obj { .. } => Some("an OBJ file (the obj target covers OBJ)".into()),
        ShapeDesc::Compound { parts } => {
            if !compound_ok || parts.len() > MAX_PARTS {
                return Some(format!("a compound of {} parts", parts.len()));
            }
            parts
                .iter()
                .find_map(|p| shape_out_of_bounds(&p.shape, false))
        }
        _ => None,
    }
}

/// A rough size of a shape (its largest half extent, radius or coordinate; NaN for NaN).
fn shape_size(s: &ShapeDesc) -> f64 {
    let max = |v: &[f64]| v.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
    match s {
        ShapeDesc::Sphere { radius } | ShapeDesc::GeodesicSphere { radius, .. } => radius.abs(),
        ShapeDesc::Box { half_extents } => max(half_extents),
        ShapeDesc::Ellipsoid { semi_axes, .. } => max(semi_axes),
        ShapeDesc::Prism {
            radius,
            half_height,
            ..
        } => radius.abs().max(half_height.abs()),
        ShapeDesc::Hull { points } => points.iter().map(|p| max(p)).fold(0.0, f64::max),
        ShapeDesc::Compound { parts } => parts
            .iter()
            .map(|p| shape_size(&p.shape) + norm(p.position))
            .fold(0.0, f64::max),
        _ => 0.0,
    }
}

/// Why the scene's energy cannot be bounded (module documentation of [`crate::energy`]), if
/// it cannot.
#[must_use]
pub fn unbounded_source(desc: &SceneDesc) -> Option<String> {
    if let Some(b) = desc.bodies.iter().find(|b| {
        matches!(
            b.motion,
            MotionDesc::Spinner { .. } | MotionDesc::Oscillator { .. }
        )
    }) {
        return Some(format!("scripted body {:?}", b.name));
    }
    if !desc.controllers.is_empty() {
        return Some("high-level controllers".into());
    }
    for m in &desc.multibodies {
        if !m.controllers.is_empty() {
            return Some(format!("multibody {:?} has joint controllers", m.name));
        }
        if m.joints.iter().any(|j| j.spring.is_some()) {
            return Some(format!("multibody {:?} has joint springs", m.name));
        }
    }
    if !within(desc.accuracy.rotation_tolerance, MAX_ROTATION_TOLERANCE) {
        return Some(format!(
            "rotation tolerance {} > {MAX_ROTATION_TOLERANCE}",
            desc.accuracy.rotation_tolerance
        ));
    }
    None
}
