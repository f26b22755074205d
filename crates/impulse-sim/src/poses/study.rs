//! The drops of a pose study (settings, starts, the drop's scene and run, shards) and merging
//! shard files (see the module documentation of [`crate::poses`]).

use glam::{DQuat, DVec3};
use rand::RngExt;
use rand::rngs::Xoshiro256PlusPlus;
use serde::{Deserialize, Serialize};

use super::{EPSILON_REL, FACET_ANGLE, POLL_RATE, PosePart};
use crate::SimError;
pub use crate::batch::Shard;
use crate::batch::{RunHooks, run_shard_with, stream};
use crate::scene::{BodyDesc, ContactDesc, MotionDesc, RotationDesc, Scene, SceneDesc, ShapeDesc};
use crate::world::{Material, World};

/// The belt reaches this many part diameters from the drop point, plus the distance the exit
/// velocity carries the part in [`DropSettings::max_time`]: far enough that no part leaves it.
const BELT_REACH_DIAMETERS: f64 = 20.0;

/// Settings of a drop (thesis §7.5's values are the defaults).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DropSettings {
    /// Height of the part's lowest point above the belt at release (m). Default `0.12`.
    pub height: f64,
    /// Horizontal speed at release, along x (m/s). Default `0.05`.
    pub exit_speed: f64,
    /// Coulomb friction between part and belt. Default `0.3`.
    pub friction: f64,
    /// Restitution between part and belt. Default `0.3`.
    pub restitution: f64,
    /// Collision epsilon ε_c (m); `None`: [`EPSILON_REL`] of the part's diameter. A study
    /// file leaves it out when it is `None` (as a drop's outcome leaves out its `start` and
    /// `facet`): the file holds no `null` where a number belongs; a file written with `null`
    /// reads the same.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub collision_epsilon: Option<f64>,
    /// Whether every other drop starts at rest on a stable facet (the upper belt) rather than
    /// uniform on SO(3), for the belt-fed estimate. Default `true`.
    pub belt_fed: bool,
    /// Largest tilt of a belt drop's start away from its rest pose (degrees; belt
    /// vibration). Default `1.5`.
    pub jitter_degrees: f64,
    /// A drop not at rest after this long (s) is counted as unsettled. Default `10`.
    pub max_time: f64,
}

impl Default for DropSettings {
    fn default() -> Self {
        Self {
            height: 0.12,
            exit_speed: 0.05,
            friction: 0.3,
            restitution: 0.3,
            collision_epsilon: None,
            belt_fed: true,
            jitter_degrees: 1.5,
            max_time: 10.0,
        }
    }
}

impl DropSettings {
    /// Checks every field.
    ///
    /// # Errors
    /// [`SimError::Invalid`] naming the field.
    pub fn validate(&self) -> Result<(), SimError> {
        let bad = |field: &str, problem: String| SimError::Invalid {
            what: "drop settings".into(),
            field: field.into(),
            problem,
        };
        let nonneg = |field: &str, x: f64| {
            if x.is_finite() && x >= 0.0 {
                Ok(())
            } else {
                Err(bad(field, format!("{x} must be finite and ≥ 0")))
            }
        };
        nonneg("height", self.height)?;
        nonneg("exit_speed", self.exit_speed)?;
        nonneg("jitter_degrees", self.jitter_degrees)?;
        Material {
            friction: self.friction,
            restitution: self.restitution,
        }
        .validate()
        .map_err(|p| bad("friction/restitution", p))?;
        if let Some(eps) = self.collision_epsilon
            && !(eps.is_finite() && eps > 0.0)
        {
            return Err(bad(
                "collision_epsilon",
                format!("{eps} must be finite and > 0"),
            ));
        }
        if !(self.max_time.is_finite() && self.max_time > 0.0) {
            return Err(bad(
                "max_time",
                format!("{} must be finite and > 0", self.max_time),
            ));
        }
        Ok(())
    }
}

/// What became of one drop.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DropOutcome {
    /// The drop's index in the study.
    pub index: u64,
    /// The stable facet (hull face) the drop started at rest on (a belt drop); `None` for a
    /// start uniform on SO(3).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub start: Option<u32>,
    /// The hull face the part rests on; `None` when it did not settle on a facet.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub facet: Option<u32>,
    /// Whether the part came to rest (slept) within [`DropSettings::max_time`].
    pub settled: bool,
    /// Simulated time until rest, or until the run gave up (s).
    pub time: f64,
    /// Final orientation of the part's body frame (world; x, y, z, w).
    pub rotation: [f64; 4],
}

/// A study's file: the settings and every drop's outcome, sorted by index. Merged shard files
/// equal the unsharded run's file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StudyFile {
    /// The part's name.
    pub part: String,
    /// The drop settings.
    pub settings: DropSettings,
    /// The random seed.
    pub seed: u64,
    /// Number of drops of the whole study (all shards).
    pub drops: u64,
    /// The part's stable facets as the study saw them, (hull face, solid angle): a file read
    /// back for another part, or for an edited part of the same name, is refused on them
    /// ([`StudyFile::fingerprint`]).
    pub stable: Vec<(u32, f64)>,
    /// Outcomes, sorted by index (one shard's, or all).
    pub outcomes: Vec<DropOutcome>,
}

impl StudyFile {
    /// The part's fingerprint a study file records: its stable facets with their solid
    /// angles (exact in the file: numbers are read back bit for bit).
    pub fn fingerprint(part: &PosePart) -> Vec<(u32, f64)> {
        part.analysis
            .stable()
            .into_iter()
            .map(|f| (f, part.analysis.facets()[f as usize].solid_angle))
            .collect()
    }
}

/// A rotation uniform on SO(3) (Shoemake 1992).
pub(super) fn uniform_rotation(rng: &mut Xoshiro256PlusPlus) -> DQuat {
    let (u1, u2, u3): (f64, f64, f64) = (rng.random(), rng.random(), rng.random());
    let tau = std::f64::consts::TAU;
    let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
    DQuat::from_xyzw(
        a * (tau * u2).sin(),
        a * (tau * u2).cos(),
        b * (tau * u3).sin(),
        b * (tau * u3).cos(),
    )
    .normalize()
}

/// A direction uniform on the unit sphere.
fn uniform_direction(rng: &mut Xoshiro256PlusPlus) -> DVec3 {
    let z: f64 = rng.random_range(-1.0..=1.0);
    let phi = std::f64::consts::TAU * rng.random::<f64>();
    let r = (1.0 - z * z).max(0.0).sqrt();
    DVec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// The scene of one drop from the body-frame orientation `start`: the belt and the part at
/// its release pose and velocity, frames at the drop's poll rate ([`POLL_RATE`]), lasting
/// [`DropSettings::max_time`]. [`drop_once`] builds its world from this very scene and steps
/// it as `impulse run` does, so `impulse run` on it replays the drop.
fn scene_of(part: &PosePart, s: &DropSettings, start: DQuat, name: String) -> SceneDesc {
    let mut d = SceneDesc::new();
    d.name = name;
    d.description = format!(
        "a drop of part \"{}\" on a belt (impulse poses); it ends when the part sleeps",
        part.name
    );
    d.duration = Some(s.max_time);
    d.collision_epsilon = s.collision_epsilon.unwrap_or(EPSILON_REL * part.diameter);
    d.output_rate = POLL_RATE;
    d.default_contact = ContactDesc {
        friction: s.friction,
        restitution: s.restitution,
    };
    let reach = BELT_REACH_DIAMETERS * part.diameter + s.exit_speed * s.max_time + s.height;
    let thick = part.diameter.max(1e-3);
    let belt = BodyDesc::new(
        belt_name(part),
        ShapeDesc::Box {
            half_extents: [reach, reach, thick],
        },
    )
    .at([0.0, 0.0, -thick])
    .with_motion(MotionDesc::Fixed);
    let own = part.own_frame_pose(part.centre_at_height(start, s.height), start);
    let mut body = part.body.clone();
    body.position = own.translation.to_array();
    body.rotation = RotationDesc::Quaternion(
        own.rotation.x,
        own.rotation.y,
        own.rotation.z,
        own.rotation.w,
    );
    body.velocity = [s.exit_speed, 0.0, 0.0];
    d.bodies = vec![belt, body];
    d
}

/// The belt's body name: `belt`, unless the part has that name.
fn belt_name(part: &PosePart) -> &'static str {
    if part.name == "belt" {
        "the-belt"
    } else {
        "belt"
    }
}

/// The scene of drop `index` of a study (the start [`run_drops`] gives it): `impulse run` on
/// it replays that drop, step for step.
///
/// # Errors
/// [`SimError::Invalid`] for bad settings.
pub fn drop_scene(
    part: &PosePart,
    settings: &DropSettings,
    seed: u64,
    index: u64,
) -> Result<SceneDesc, SimError> {
    settings.validate()?;
    let (start, _) = start_of(part, settings, &part.analysis.stable(), seed, index);
    Ok(scene_of(
        part,
        settings,
        start,
        format!("{}-drop-{index}", part.name),
    ))
}

/// Runs one drop from the body-frame orientation `start` and returns its outcome: its world
/// is built from [`scene_of`] and polled at the scene's frame times until the part sleeps.
fn drop_once(
    part: &PosePart,
    s: &DropSettings,
    index: u64,
    (start, from): (DQuat, Option<u32>),
) -> Result<DropOutcome, SimError> {
    let desc = scene_of(part, s, start, part.name.clone());
    let mut world = World::from_scene(&Scene {
        desc,
        base_dir: part.base_dir.clone(),
    })?;
    world.set_parallel_min_bodies(usize::MAX);
    let h = world
        .handle(&part.name)
        .ok_or_else(|| SimError::UnknownBody {
            handle: part.name.clone(),
        })?;
    let mut settled = false;
    // The frame times of `crate::run` at the scene's rate, so that a replay steps alike.
    let mut k = 1u64;
    loop {
        let t = (k as f64 / POLL_RATE).min(s.max_time);
        world.step_until(t)?;
        if world.body(h).is_some_and(|b| b.is_asleep()) {
            settled = true;
            break;
        }
        if t >= s.max_time {
            break;
        }
        k += 1;
    }
    let b = world.body(h).ok_or_else(|| SimError::UnknownBody {
        handle: format!("{h:?}"),
    })?;
    let rotation = b.pose.rotation;
    let down = rotation.inverse() * world.gravity().normalize_or(DVec3::NEG_Z);
    // At rest on an unstable facet (one the centre of mass projects onto within rounding of
    // its edge) is not a pose: counted as unclassified.
    let facet = if settled {
        part.analysis
            .facet_facing(down, FACET_ANGLE)
            .filter(|&f| part.analysis.facets()[f as usize].stable)
    } else {
        None
    };
    Ok(DropOutcome {
        index,
        start: from,
        facet,
        settled,
        time: world.time(),
        rotation: rotation.to_array(),
    })
}

/// The start of drop `index`: uniform on SO(3), or (every odd drop of a belt-fed study) at
/// rest on the stable facets in turn, turned about the vertical at random and tilted by up
/// to the jitter about a random axis.
fn start_of(
    part: &PosePart,
    s: &DropSettings,
    stable: &[u32],
    seed: u64,
    index: u64,
) -> (DQuat, Option<u32>) {
    let mut rng = stream(seed, index);
    if !s.belt_fed || index % 2 == 0 || stable.is_empty() {
        return (uniform_rotation(&mut rng), None);
    }
    let facet = stable[((index / 2) % stable.len() as u64) as usize];
    let normal = part.analysis.facets()[facet as usize].normal;
    let rest = DQuat::from_rotation_arc(normal, DVec3::NEG_Z);
    let yaw = DQuat::from_rotation_z(std::f64::consts::TAU * rng.random::<f64>());
    let tilt = DQuat::from_axis_angle(
        uniform_direction(&mut rng),
        s.jitter_degrees.to_radians() * rng.random::<f64>(),
    );
    ((tilt * yaw * rest).normalize(), Some(facet))
}

/// Runs the drops of `shard` of a study of `drops` drops (see the module documentation) on
/// `threads` worker threads, calling `progress` with the number of drops done after each
/// one. Returns the outcomes, sorted by index. A drop's start depends only on (`seed`, its
/// index), so the outcomes do not depend on `threads` or on the shard split.
///
/// # Errors
/// [`SimError::Invalid`] for bad settings or zero threads; any error of a drop's world
/// (named by the drop's index).
pub fn run_drops(
    part: &PosePart,
    settings: &DropSettings,
    seed: u64,
    drops: u64,
    shard: Shard,
    threads: usize,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<Vec<DropOutcome>, SimError> {
    let done = run_drops_with(
        part,
        settings,
        seed,
        drops,
        shard,
        threads,
        &RunHooks::none(progress),
    )?;
    Ok(done.into_iter().map(|(_, d)| d).collect())
}

/// [`run_drops`] steered by `hooks` ([`RunHooks`]: drops done before are skipped, no drop
/// starts once a stop is asked for, each outcome is recorded as it finishes); returns the
/// drops done, (index, outcome) in index order. A drop's outcome depends only on (seed,
/// index), so the drops of a stopped study and of the call that finishes it are those of one
/// uninterrupted study.
///
/// # Errors
/// As [`run_drops`].
pub fn run_drops_with(
    part: &PosePart,
    settings: &DropSettings,
    seed: u64,
    drops: u64,
    shard: Shard,
    threads: usize,
    hooks: &RunHooks<'_, DropOutcome>,
) -> Result<Vec<(u64, DropOutcome)>, SimError> {
    settings.validate()?;
    // Drop 0's world, built once here to report a scene's errors before the workers start.
    World::from_scene(&Scene {
        desc: scene_of(part, settings, DQuat::IDENTITY, part.name.clone()),
        base_dir: part.base_dir.clone(),
    })?;
    let stable = part.analysis.stable();
    run_shard_with("drop", drops, shard, threads, hooks, |i| {
        drop_once(
            part,
            settings,
            i,
            start_of(part, settings, &stable, seed, i),
        )
    })
}

/// Drops of [`run_thesis_feedback`] that start uniform on SO(3) (the thesis's 20).
pub const THESIS_PILOT: u64 = 20;

/// The thesis's own sampling, for comparison (§7.5): drops one after another, the first
/// [`THESIS_PILOT`] from orientations uniform on SO(3), each later one from the final
/// orientation of an earlier drop drawn at random (the running histogram of final poses),
/// tilted by up to [`DropSettings::jitter_degrees`] about a random axis. Sequential by
/// nature: no threads, no shards. Drop i's random stream is still (seed, i), so its first
/// [`THESIS_PILOT`] drops equal [`run_drops`]'s with [`DropSettings::belt_fed`] off. The
/// dynamic estimate is the histogram of all its final poses; each outcome's `start` is the
/// facet it started on (`None` for the pilot).
///
/// # Errors
/// As [`run_drops`].
pub fn run_thesis_feedback(
    part: &PosePart,
    settings: &DropSettings,
    seed: u64,
    drops: u64,
    progress: &dyn Fn(u64),
) -> Result<Vec<DropOutcome>, SimError> {
    settings.validate()?;
    let mut out: Vec<DropOutcome> = Vec::new();
    for i in 0..drops {
        let mut rng = stream(seed, i);
        let rests: Vec<&DropOutcome> = out.iter().filter(|o| o.facet.is_some()).collect();
        let start = if i < THESIS_PILOT || rests.is_empty() {
            (uniform_rotation(&mut rng), None)
        } else {
            let from = rests[rng.random_range(0..rests.len())];
            let tilt = DQuat::from_axis_angle(
                uniform_direction(&mut rng),
                settings.jitter_degrees.to_radians() * rng.random::<f64>(),
            );
            (
                (tilt * DQuat::from_array(from.rotation)).normalize(),
                from.facet,
            )
        };
        let o = drop_once(part, settings, i, start).map_err(|e| SimError::Runtime {
            time: 0.0,
            message: format!("drop {i}: {e}"),
        })?;
        out.push(o);
        progress(i + 1);
    }
    Ok(out)
}

/// Merges shard files of one study into the file of the whole study.
///
/// # Errors
/// [`SimError::Invalid`] when there are no files, the files are of different parts,
/// settings, seeds or study sizes, or two files hold the same drop.
pub fn merge(files: &[StudyFile]) -> Result<StudyFile, SimError> {
    crate::batch::merge(files)
}

impl crate::batch::StudyFile for StudyFile {
    type Run = DropOutcome;
    const FILES: &'static str = "pose study files";
    const RUN: &'static str = "drop";
    const HEADER: &'static str = "part, stable facets, settings, seed or drops";
    fn same_study(&self, o: &Self) -> bool {
        (
            self.part.as_str(),
            self.settings,
            self.seed,
            self.drops,
            &self.stable,
        ) == (o.part.as_str(), o.settings, o.seed, o.drops, &o.stable)
    }
    fn runs(&self) -> u64 {
        self.drops
    }
    fn outcomes(&self) -> &[DropOutcome] {
        &self.outcomes
    }
    fn index(run: &DropOutcome) -> u64 {
        run.index
    }
    fn with_outcomes(&self, outcomes: Vec<DropOutcome>) -> Self {
        Self {
            outcomes,
            ..self.clone()
        }
    }
}
