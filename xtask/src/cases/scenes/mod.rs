//! Scene validation cases (thesis chapter 7; the digest's validation table V6–V17): each runs a
//! bundled scene from `fixtures/scenes/` through `impulse-sim` and compares what happened with
//! a closed form or a conservation law whose parameters are read from the scene file itself
//! (so a check cannot pass against a copy of the numbers it should test).
//!
//! One registry, [`scene_checks`]: each entry names its case once, with its scene, its
//! description and its metrics; `validate` runs every entry as bundled, with the world's
//! checking mode on ([`impulse_sim::World::set_checking`]), and `bench` at several accuracy
//! settings. Every case's no-penetration metric is the independent monitor's
//! ([`impulse_sim::PenetrationMonitor`]), not a counter of the event loop.
//!
//! - `sliding.rs`: V6 block on ramp, V7 sliding to rolling, V8 ball on platter;
//! - `impacts.rs`: V9 two balls, V10 chain of balls, V14 pool break, V15 tumbling box, bullet;
//! - `resting.rs`: V11 balls in dish, V13 block drop, V16 dominos, V17 coins, feeder chute;
//! - `rattleback.rs`: V12, with the reversing direction predicted from the body's
//!   inertia–curvature skew before the run;
//! - `hybrid.rs`: V19 triple pendulum, V20 see-saw, the furniture scene's controllers
//!   (multibodies and controllers in the world, §7.2–7.3), determinism of every hybrid scene;
//! - `rover.rs`: the rover driven by a high-level state machine (§7.3's creature war);
//! - `sorter.rs`: V21 part sorter (spring-loaded trap doors routing three part types, §7.2);
//! - `families.rs`: the coins and the dominos run six times each with one initial condition
//!   scaled by up to 2 %, every run judged by the scene's check (a chaotic scene's one
//!   trajectory hides what its neighbours show);
//! - `perturb.rs` (tests): each case fails when its scene is perturbed in the way it guards
//!   against.

mod families;
mod hybrid;
mod impacts;
#[cfg(test)]
mod perturb;
mod rattleback;
mod resting;
mod rover;
mod sliding;
mod sorter;

use std::path::{Path, PathBuf};

use glam::{DQuat, DVec3};
use impulse_sim::scene::{BodyDesc, ContactDesc, RotationDesc, ShapeDesc};
use impulse_sim::{ContactMode, Recording, Scene, World, run};

use crate::validate::case::{Case, Check, Metric};

/// Relative tolerance of the V6 and V7 comparisons (digest: ±2 %).
const SCENE_REL: f64 = 0.02;
/// "At rest" means a mean speed below this fraction of the scene's characteristic speed
/// (digest 1e-2).
const REST_REL: f64 = 1e-2;
/// The window (s) at the end of the run over which mean speeds are taken.
const REST_WINDOW: f64 = 0.5;

/// The run a scene check judges: the scene as run (so parameters come from it), the world at
/// the end, and the recording.
pub struct Run<'a> {
    /// The scene, as run (the bench changes its ε_c and tolerances).
    pub scene: &'a Scene,
    /// The world at the end of the run.
    pub world: &'a World,
    /// The recorded frames.
    pub rec: &'a Recording,
}

/// A bundled scene with its checks: `validate` runs it as bundled, `bench` at several accuracy
/// settings.
pub struct SceneCheck {
    /// Validation case name (also the snapshot name).
    pub case: &'static str,
    /// Scene file stem in `fixtures/scenes/`.
    pub scene: &'static str,
    /// One line: what is checked and against what reference.
    pub description: &'static str,
    /// The Table 7.1 row (example name, slowdown on the 1996 machine) this scene reproduces.
    pub thesis: Option<(&'static str, f64)>,
    /// Whether the run records every contact (`World::set_event_log`) for the metrics.
    pub event_log: bool,
    /// The metric `bench` reports as the scene's error against its reference.
    pub headline: &'static str,
    /// The metrics of a finished run, each against its reference.
    pub metrics: fn(&Run<'_>) -> Result<Vec<Metric>, String>,
}

/// Every scene check, in registry order (the order of `validate` and `bench`).
pub fn scene_checks() -> Vec<SceneCheck> {
    let mut all = Vec::new();
    all.extend(impacts::checks());
    all.extend(resting::checks());
    all.extend(sliding::checks());
    all.extend(rattleback::checks());
    all.extend(hybrid::checks());
    all.extend(sorter::checks());
    all
}

/// Suffix of the cases that run a scene in the thesis's pure impulse model
/// ([`ContactMode::Impulse`]); the unsuffixed case runs it as bundled, in the default model.
pub const IMPULSE_SUFFIX: &str = "-impulse";

/// The scene cases of `validate`: every scene check as bundled (the default contact model,
/// [`ContactMode::Switching`]) and again in the pure impulse model, which keeps its own
/// validation; then the determinism case.
pub fn cases() -> Vec<Case> {
    let mut cases: Vec<Case> = Vec::new();
    for check in scene_checks() {
        for mode in [None, Some(ContactMode::Impulse)] {
            let name: &'static str = match mode {
                None => check.case,
                // One name per case for the process's life (the case table outlives any scope).
                Some(_) => Box::leak(format!("{}{IMPULSE_SUFFIX}", check.case).into_boxed_str()),
            };
            let (scene_name, event_log, metrics) = (check.scene, check.event_log, check.metrics);
            cases.push(Case {
                name,
                description: check.description,
                run: Box::new(move || {
                    let (scene, world, rec) = record(scene_name, event_log, true, mode)?;
                    metrics(&Run {
                        scene: &scene,
                        world: &world,
                        rec: &rec,
                    })
                }),
            });
        }
    }
    cases.push(Case {
        name: "V17-coins-family",
        description: "the coins six times, the rollers' spin about the vertical scaled by 0.98 to 1.02: every run passes V17 (flat, at rest, no interpenetration); each metric the family's worst",
        run: Box::new(families::coins),
    });
    cases.push(Case {
        name: "V16-dominos-family",
        description: "the dominos six times, the first domino's spin scaled by 0.98 to 1.02: every run passes V16 (in order, down by 1.2 s, at rest, no interpenetration); each metric the family's worst",
        run: Box::new(families::dominos),
    });
    cases.push(Case {
        name: "determinism-threads",
        description: "tumbling box run on 1 and on 2 threads: bit-identical trajectories (hash)",
        run: Box::new(impacts::determinism),
    });
    cases.push(Case {
        name: "rover",
        description: "a rover (7-link multibody, PD wheel loops) driven by a high-level state machine written against WorldController pushes every block off its platform (at most two pushes a block) and stays on it; no interpenetration",
        run: Box::new(rover::rover),
    });
    cases.push(Case {
        name: "rover-standing",
        description: "the rover scene as it is (wheel loops holding speed 0): after settling 0.5 s on its shocks, no link moves more than 2 ε_c in 5 s, no link is struck (its wheels rest held in a contact island), no interpenetration",
        run: Box::new(rover::rover_standing),
    });
    cases.push(Case {
        name: "determinism-hybrid",
        description: "every hybrid scene (multibodies or controllers), in both contact models, run for its first half second on 1 and on 2 threads: bit-identical trajectories (hash)",
        run: Box::new(hybrid::determinism),
    });
    cases
}

/// `fixtures/scenes/<name>.ron` from the workspace root.
fn scene_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("fixtures")
        .join("scenes")
        .join(format!("{name}.ron"))
}

/// Reads a bundled scene.
pub fn load_scene(name: &str) -> Result<Scene, String> {
    Scene::read(&scene_path(name)).map_err(|e| e.to_string())
}

/// The scene's duration (every bundled scene has one).
pub fn duration(scene: &Scene) -> Result<f64, String> {
    scene
        .desc
        .duration
        .ok_or_else(|| format!("scene \"{}\" has no duration", scene.desc.name))
}

/// Runs a scene for its duration at its output rate; `checking` turns on the world's checking
/// mode (the penetration monitor at every loop step).
pub fn run_scene(
    scene: &Scene,
    event_log: bool,
    checking: bool,
) -> Result<(World, Recording), String> {
    let mut world = World::from_scene(scene).map_err(|e| e.to_string())?;
    world.set_event_log(event_log);
    world.set_checking(checking);
    let rec = run(&mut world, duration(scene)?, scene.desc.output_rate, |_| {})
        .map_err(|e| e.to_string())?;
    Ok((world, rec))
}

/// Reads and runs a bundled scene, in contact model `mode` when given (as bundled otherwise).
fn record(
    name: &str,
    event_log: bool,
    checking: bool,
    mode: Option<ContactMode>,
) -> Result<(Scene, World, Recording), String> {
    let mut scene = load_scene(name)?;
    if let Some(mode) = mode {
        scene.desc.contact_model = mode;
    }
    let (world, rec) = run_scene(&scene, event_log, checking)?;
    Ok((scene, world, rec))
}

impl Run<'_> {
    /// The position of body `name` in the recording's states.
    fn index(&self, name: &str) -> Result<usize, String> {
        self.rec
            .index(name)
            .ok_or_else(|| format!("no body \"{name}\""))
    }

    /// The description of body `name` in the scene.
    fn desc(&self, name: &str) -> Result<&BodyDesc, String> {
        body_desc(self.scene, name)
    }

    /// The magnitude of the scene's gravity.
    fn g(&self) -> f64 {
        DVec3::from_array(self.scene.desc.gravity).length()
    }

    /// Recording indices of the dynamic bodies.
    fn dynamic(&self) -> Vec<usize> {
        self.rec
            .handles
            .iter()
            .enumerate()
            .filter(|(_, h)| self.world.body(**h).is_some_and(|b| b.is_dynamic()))
            .map(|(i, _)| i)
            .collect()
    }

    fn last(&self) -> Result<&impulse_sim::Frame, String> {
        self.rec
            .frames
            .last()
            .ok_or_else(|| "no frames".to_string())
    }
}

/// The contact of bodies `a` and `b` of the scene: their material pair's, else the default.
fn contact(r: &Run<'_>, a: &str, b: &str) -> Result<ContactDesc, String> {
    let (ma, mb) = (&r.desc(a)?.material, &r.desc(b)?.material);
    Ok(r.scene
        .desc
        .contacts
        .iter()
        .find(|c| (&c.a == ma && &c.b == mb) || (&c.a == mb && &c.b == ma))
        .map_or(r.scene.desc.default_contact, |c| {
            ContactDesc::new(c.friction, c.restitution)
        }))
}

/// The description of body `name` in a scene.
fn body_desc<'a>(scene: &'a Scene, name: &str) -> Result<&'a BodyDesc, String> {
    scene
        .desc
        .bodies
        .iter()
        .find(|b| b.name == name)
        .ok_or_else(|| format!("scene has no body \"{name}\""))
}

/// A sphere's radius.
pub(crate) fn sphere_radius(b: &BodyDesc) -> Result<f64, String> {
    match b.shape {
        ShapeDesc::Sphere { radius } => Ok(radius),
        _ => Err(format!("body \"{}\" is not a sphere", b.name)),
    }
}

/// A box's half extents.
pub(crate) fn half_extents(b: &BodyDesc) -> Result<DVec3, String> {
    match b.shape {
        ShapeDesc::Box { half_extents } => Ok(DVec3::from_array(half_extents)),
        _ => Err(format!("body \"{}\" is not a box", b.name)),
    }
}

/// The axis of a box's longest half extent (body frame; z, then y, on ties).
pub(crate) fn longest_axis(h: DVec3) -> DVec3 {
    if h.z >= h.x.max(h.y) {
        DVec3::Z
    } else if h.y >= h.x {
        DVec3::Y
    } else {
        DVec3::X
    }
}

/// The rotation a scene gives a body (as the simulator reads it).
pub(crate) fn rotation(r: &RotationDesc) -> DQuat {
    match *r {
        RotationDesc::Identity => DQuat::IDENTITY,
        RotationDesc::AxisAngle { axis, degrees } => {
            DQuat::from_axis_angle(DVec3::from_array(axis).normalize(), degrees.to_radians())
        }
        RotationDesc::Quaternion(x, y, z, w) => DQuat::from_xyzw(x, y, z, w).normalize(),
    }
}

/// The promise of chapter 2: bodies never interpenetrate by more than ε_c. The metric is the
/// largest penetration depth the independent monitor measured — at every recorded frame, and
/// at every loop step when the checking mode was on — in units of ε_c.
pub(super) fn no_penetration(r: &Run<'_>) -> Metric {
    Metric::new(
        "max_penetration_over_eps_c",
        r.rec.max_penetration() / r.world.collision_epsilon(),
        0.0,
        Check::Between(0.0, 1.0),
    )
}

/// The largest mean speed of recording indices `bodies` over the last [`REST_WINDOW`]
/// seconds of the run (displacement over time): "at rest" in resting contact, where
/// microcollisions keep the instantaneous speed jittering.
fn max_mean_speed(rec: &Recording, bodies: &[usize]) -> Result<f64, String> {
    let last = rec.frames.last().ok_or("no frames")?;
    let first = rec
        .frames
        .iter()
        .find(|f| f.time >= last.time - REST_WINDOW)
        .ok_or("no frames")?;
    let span = last.time - first.time;
    Ok(bodies
        .iter()
        .map(|&i| (last.bodies[i].com - first.bodies[i].com).length() / span)
        .fold(0.0, f64::max))
}

/// Least-squares line `y = a + b·x`.
fn fit_line(points: &[(f64, f64)]) -> (f64, f64) {
    let n = points.len() as f64;
    let (sx, sy) = points
        .iter()
        .fold((0.0, 0.0), |(sx, sy), (x, y)| (sx + x, sy + y));
    let (mx, my) = (sx / n, sy / n);
    let (sxy, sxx) = points.iter().fold((0.0, 0.0), |(a, b), (x, y)| {
        (a + (x - mx) * (y - my), b + (x - mx) * (x - mx))
    });
    let slope = sxy / sxx;
    (my - slope * mx, slope)
}

/// A 0/1 metric that must be 1.
fn holds(name: &str, ok: bool) -> Metric {
    Metric::new(name, f64::from(u8::from(ok)), 1.0, Check::Exact)
}
