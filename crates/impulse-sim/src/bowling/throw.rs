//! The throws of a bowling study: settings, where each throw starts, one throw's run and
//! count, a shard of throws in parallel, and merging shard files.

use glam::DVec3;
use impulse_geom::Pose;
use rand::RngExt;
use serde::{Deserialize, Serialize};

use super::alley::{AlleyDesc, PIN_COUNT};
use super::{POLL_RATE, STANDING_LIFT, STANDING_TILT};
use crate::SimError;
use crate::batch::{RunHooks, Shard, run_shard_with, stream};
use crate::scene::{Scene, SceneDesc};
use crate::world::World;

/// Moment of inertia of a solid sphere over m r².
const SOLID_SPHERE_K: f64 = 0.4;

/// A throw's run ends at most this many times the ideal time to the pin line, plus
/// [`ThrowSettings::settle_time`], after release: a ball that never reaches the pins (it
/// stopped, or bounced back) is given up on.
const REACH_SLACK: f64 = 2.0;

/// The two kinds of throw of thesis Fig. 7.10.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum ThrowKind {
    /// No spin, velocity along +y.
    Straight,
    /// A right-hander's hook: spin −[`ThrowSettings::hook_spin`] about +y, velocity
    /// [`ThrowSettings::hook_angle_degrees`] to the right of +y.
    Hook,
}

impl ThrowKind {
    /// The kind of throw `index` of a study: even throws straight, odd ones hooks, so that
    /// every shard holds both.
    pub fn of(index: u64) -> Self {
        if index % 2 == 0 {
            Self::Straight
        } else {
            Self::Hook
        }
    }
}

/// Settings of a study's throws. Thesis §7.4 gives the hook's −12 rad/s and −2°; the speed
/// is not printed.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ThrowSettings {
    /// Release speed of the ball's centre (m/s). Default `8` (about 18 mph, a typical
    /// release speed; not from the thesis).
    pub speed: f64,
    /// A hook's spin about +y (rad/s; the ball's angular velocity is −hook_spin·ŷ). Default
    /// `12` (thesis).
    pub hook_spin: f64,
    /// A hook's release direction, degrees to the right of +y (toward +x: the thesis's
    /// "−2° from the y-axis", angles counter-clockwise seen from above). Default `2`.
    pub hook_angle_degrees: f64,
    /// Centre of the window of pin-line crossings the throws are aimed across (m, x; 0 is
    /// the head pin). Default `0`.
    pub window_center: f64,
    /// Width of that window (m). Default `0.40` (thesis: 40 cm).
    pub window_width: f64,
    /// Longest run after the ball crosses the pin line (s): a throw ends earlier once every
    /// pin is at rest or off the deck. Default `4`.
    pub settle_time: f64,
}

impl Default for ThrowSettings {
    fn default() -> Self {
        Self {
            speed: 8.0,
            hook_spin: 12.0,
            hook_angle_degrees: 2.0,
            window_center: 0.0,
            window_width: 0.40,
            settle_time: 4.0,
        }
    }
}

impl ThrowSettings {
    /// The window of pin-line crossings the throws are aimed across, (lo, hi) (m).
    pub fn window(&self) -> (f64, f64) {
        (
            self.window_center - self.window_width / 2.0,
            self.window_center + self.window_width / 2.0,
        )
    }

    /// Checks every field.
    ///
    /// # Errors
    /// [`SimError::Invalid`] naming the field.
    pub fn validate(&self) -> Result<(), SimError> {
        let bad = |field: &str, problem: String| SimError::Invalid {
            what: "throw settings".into(),
            field: field.into(),
            problem,
        };
        let positive = |field: &str, x: f64| crate::scene::positive(x).map_err(|p| bad(field, p));
        positive("speed", self.speed)?;
        positive("window_width", self.window_width)?;
        positive("settle_time", self.settle_time)?;
        if !self.hook_spin.is_finite() {
            return Err(bad(
                "hook_spin",
                format!("{} must be finite", self.hook_spin),
            ));
        }
        if !self.window_center.is_finite() {
            return Err(bad(
                "window_center",
                format!("{} must be finite", self.window_center),
            ));
        }
        if !(self.hook_angle_degrees.is_finite() && self.hook_angle_degrees.abs() < 45.0) {
            return Err(bad(
                "hook_angle_degrees",
                format!(
                    "{} must be within ±45 (a throw down the lane)",
                    self.hook_angle_degrees
                ),
            ));
        }
        Ok(())
    }

    /// The release velocity and angular velocity of a throw of `kind` (world).
    pub fn launch(&self, kind: ThrowKind) -> (DVec3, DVec3) {
        match kind {
            ThrowKind::Straight => (DVec3::new(0.0, self.speed, 0.0), DVec3::ZERO),
            ThrowKind::Hook => {
                let a = self.hook_angle_degrees.to_radians();
                (
                    self.speed * DVec3::new(a.sin(), a.cos(), 0.0),
                    DVec3::new(0.0, -self.hook_spin, 0.0),
                )
            }
        }
    }
}

/// Where and when a ball released on a flat lane at x = 0, y = 0 with velocity `v0` and
/// angular velocity `omega0` crosses the line y = `distance`, in the ideal model: a solid
/// sphere of `radius` in one sliding contact with Coulomb friction `mu` under gravity `g`,
/// until it rolls. Returns (x, t), or `None` if it never gets there.
///
/// The slip velocity at the contact, s = v + ω × (−r ẑ), keeps its direction while it
/// slides and shrinks at (1 + 1/k) μ g with k = I/(m r²) = 2/5, so sliding lasts
/// t* = |s₀|/(3.5 μ g) and leaves v* = v₀ − (2/7) s₀ (with ω = 0, the thesis's sliding-to-
/// rolling case, V7: t* = 2v₀/(7 μ g), v* = 5v₀/7); the ball then rolls straight on.
pub fn ideal_crossing(
    v0: DVec3,
    omega0: DVec3,
    radius: f64,
    mu: f64,
    g: f64,
    distance: f64,
) -> Option<(f64, f64)> {
    let v0 = DVec3::new(v0.x, v0.y, 0.0);
    let slip = v0 + omega0.cross(DVec3::new(0.0, 0.0, -radius));
    let slip = DVec3::new(slip.x, slip.y, 0.0);
    let rate = (1.0 + 1.0 / SOLID_SPHERE_K) * mu * g;
    let (t_star, a) = if slip.length() > 0.0 && rate > 0.0 {
        (slip.length() / rate, mu * g * slip.normalize())
    } else {
        (f64::INFINITY, DVec3::ZERO)
    };
    // Sliding: y(t) = v0y t − a_y t²/2.
    let t_slide = if a.y.abs() > 0.0 {
        let disc = v0.y * v0.y - 2.0 * a.y * distance;
        (disc >= 0.0).then(|| (v0.y - disc.sqrt()) / a.y)
    } else {
        (v0.y > 0.0).then(|| distance / v0.y)
    };
    if let Some(t) = t_slide.filter(|&t| t >= 0.0 && t <= t_star) {
        return Some((v0.x * t - 0.5 * a.x * t * t, t));
    }
    if !t_star.is_finite() {
        return None;
    }
    let p_star = v0 * t_star - 0.5 * a * t_star * t_star;
    let v_star = v0 - a * t_star;
    if v_star.y <= 0.0 {
        return None;
    }
    let dt = (distance - p_star.y) / v_star.y;
    Some((p_star.x + v_star.x * dt, t_star + dt))
}

/// What became of one throw.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ThrowOutcome {
    /// The throw's index in the study.
    pub index: u64,
    /// Straight or hook.
    pub kind: ThrowKind,
    /// The ball's x at release (m).
    pub start_x: f64,
    /// The pin-line crossing x the throw was aimed at (m; the ideal model's).
    pub aim_x: f64,
    /// The ball's x as its centre crossed the pin line (m); `None` if it never did.
    pub crossing: Option<f64>,
    /// Pins down at the end: not standing upright on the deck.
    pub felled: u32,
    /// The numbers of the pins left standing.
    pub standing: Vec<u32>,
    /// Simulated time at the end of the throw (s).
    pub time: f64,
    /// Whether every pin was at rest or off the deck at the end (otherwise the run reached
    /// [`ThrowSettings::settle_time`] past the crossing).
    pub settled: bool,
}

/// A bowling study's file: the alley, the settings and every throw's outcome, sorted by
/// index. Merged shard files equal the unsharded run's file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BowlingFile {
    /// The alley.
    pub alley: AlleyDesc,
    /// The throw settings.
    pub settings: ThrowSettings,
    /// The random seed.
    pub seed: u64,
    /// Throws of each kind in the whole study (all shards): 2 × this many throws.
    pub throws_per_kind: u64,
    /// Outcomes, sorted by index (one shard's, or all).
    pub outcomes: Vec<ThrowOutcome>,
}

impl BowlingFile {
    /// Checks a file read back: its alley, settings and study size.
    ///
    /// # Errors
    /// [`SimError::Invalid`] naming the field.
    pub fn check(&self) -> Result<(), SimError> {
        self.alley.validate()?;
        self.settings.validate()?;
        check_throws(self.throws_per_kind)
    }
}

/// A study's plan: the alley and settings, checked, with each kind's aim offset.
struct Plan<'a> {
    alley: &'a AlleyDesc,
    settings: &'a ThrowSettings,
    seed: u64,
    per_kind: u64,
    /// Ideal crossing x of each kind thrown from x = 0, and its time.
    straight: (f64, f64),
    hook: (f64, f64),
}

impl<'a> Plan<'a> {
    fn new(
        alley: &'a AlleyDesc,
        settings: &'a ThrowSettings,
        seed: u64,
        per_kind: u64,
    ) -> Result<Self, SimError> {
        alley.validate()?;
        settings.validate()?;
        check_throws(per_kind)?;
        let gravity = DVec3::from_array(alley.scene(0.0).gravity).length();
        let ideal = |kind| {
            let (v, w) = settings.launch(kind);
            ideal_crossing(
                v,
                w,
                alley.ball.radius,
                alley.contacts.ball_lane.friction,
                gravity,
                alley.pin_line(),
            )
            .ok_or_else(|| SimError::Invalid {
                what: "throw settings".into(),
                field: "speed".into(),
                problem: format!(
                    "a {kind:?} throw would not reach the pin line (too slow for the ball–lane friction)"
                ),
            })
        };
        let plan = Self {
            straight: ideal(ThrowKind::Straight)?,
            hook: ideal(ThrowKind::Hook)?,
            alley,
            settings,
            seed,
            per_kind,
        };
        // Every release point must be over the lane or a gutter, clear of the gutter walls.
        let reach = alley.lane_width / 2.0 + alley.gutter_width - alley.ball.radius;
        let (lo, hi) = settings.window();
        for (kind, (offset, _)) in [("straight", plan.straight), ("hook", plan.hook)] {
            let far = (lo - offset).abs().max((hi - offset).abs());
            if far > reach {
                return Err(SimError::Invalid {
                    what: "throw settings".into(),
                    field: "window_center/window_width".into(),
                    problem: format!(
                        "{kind} throws aimed at crossings {lo:+.3} … {hi:+.3} m would be released up to {far:.3} m from the lane's middle, beyond the gutters ({reach:.3} m)"
                    ),
                });
            }
        }
        Ok(plan)
    }

    /// Throw `index`'s kind, aim and release x: the throws of a kind are aimed across the
    /// window in equal strata, one throw at a random point of each.
    fn aim(&self, index: u64) -> (ThrowKind, f64, f64) {
        let kind = ThrowKind::of(index);
        let slot = index / 2;
        let u: f64 = stream(self.seed, index).random();
        let s = self.settings;
        let aim = s.window().0 + (slot as f64 + u) * s.window_width / self.per_kind as f64;
        let offset = match kind {
            ThrowKind::Straight => self.straight.0,
            ThrowKind::Hook => self.hook.0,
        };
        (kind, aim, aim - offset)
    }

    /// Longest a throw of `kind` runs (s).
    fn max_time(&self, kind: ThrowKind) -> f64 {
        let t = match kind {
            ThrowKind::Straight => self.straight.1,
            ThrowKind::Hook => self.hook.1,
        };
        REACH_SLACK * t + self.settings.settle_time
    }

    fn scene(&self, index: u64) -> SceneDesc {
        let (kind, aim, x) = self.aim(index);
        let (v, w) = self.settings.launch(kind);
        let mut d = self.alley.scene(x);
        d.name = format!("bowling-throw-{index}");
        d.description = format!(
            "{kind:?} throw {index} of a bowling study (impulse bowling), aimed to cross the pin line at x = {aim:.4} m"
        );
        d.duration = Some(self.max_time(kind));
        d.output_rate = POLL_RATE;
        if let Some(ball) = d.bodies.last_mut() {
            ball.velocity = v.to_array();
            ball.angular_velocity = w.to_array();
        }
        d
    }

    /// Runs throw `index`: its world is built from [`Plan::scene`] and polled at the scene's
    /// frame times, as `impulse run` steps it.
    fn throw(&self, index: u64) -> Result<ThrowOutcome, SimError> {
        let (kind, aim_x, start_x) = self.aim(index);
        let desc = self.scene(index);
        let max_time = desc.duration.unwrap_or(f64::INFINITY);
        let mut world = World::from_scene(&Scene::new(desc, "."))?;
        world.set_parallel_min_bodies(usize::MAX);
        let find = |name: &str| {
            world.handle(name).ok_or_else(|| SimError::UnknownBody {
                handle: name.into(),
            })
        };
        let ball = find("ball")?;
        let pins = (1..=PIN_COUNT)
            .map(|k| find(&format!("pin{k}")))
            .collect::<Result<Vec<_>, _>>()?;
        let line = self.alley.pin_line();
        let out_of_play = -self.alley.gutter_depth / 2.0;
        let mut last = world
            .body(ball)
            .map(|b| b.pose.translation)
            .unwrap_or_default();
        let (mut crossing, mut crossed_at, mut settled) = (None, None, false);
        let mut k = 1u64;
        loop {
            let t = (k as f64 / POLL_RATE).min(max_time);
            world.step_until(t)?;
            let Some(b) = world.body(ball) else { break };
            let p = b.pose.translation;
            if crossed_at.is_none() && last.y < line && p.y >= line {
                // Linear between frames (a 100 Hz poll moves the ball about 6 cm).
                let f = (line - last.y) / (p.y - last.y);
                crossing = Some(last.x + f * (p.x - last.x));
                crossed_at = Some(t);
            }
            last = p;
            if let Some(tc) = crossed_at {
                let ball_done = b.is_asleep() || p.y > self.alley.deck_end() || p.z < out_of_play;
                let pins_done = pins.iter().all(|&h| {
                    world
                        .body(h)
                        .is_none_or(|q| q.is_asleep() || q.frame_pose().translation.z < out_of_play)
                });
                if ball_done && pins_done {
                    settled = true;
                    break;
                }
                if t >= tc + self.settings.settle_time {
                    break;
                }
            } else if b.is_asleep() {
                break;
            }
            if t >= max_time {
                break;
            }
            k += 1;
        }
        let standing: Vec<u32> = pins
            .iter()
            .enumerate()
            .filter(|&(_, &h)| {
                world
                    .body(h)
                    .is_some_and(|q| self.is_standing(q.frame_pose()))
            })
            .map(|(n, _)| n as u32 + 1)
            .collect();
        Ok(ThrowOutcome {
            index,
            kind,
            start_x,
            aim_x,
            crossing,
            felled: (PIN_COUNT - standing.len()) as u32,
            standing,
            time: world.time(),
            settled,
        })
    }

    fn is_standing(&self, frame: Pose) -> bool {
        pin_stands(self.alley, frame)
    }
}

/// Whether a pin whose own frame (base centre, axis z) is at `frame` stands: upright within
/// [`STANDING_TILT`], its base on the deck (within [`STANDING_LIFT`] of its surface).
pub fn pin_stands(alley: &AlleyDesc, frame: Pose) -> bool {
    let axis = frame.rotation * DVec3::Z;
    let base = frame.translation;
    axis.z >= STANDING_TILT.cos()
        && base.z.abs() <= STANDING_LIFT
        && base.x.abs() <= alley.lane_width / 2.0
        && base.y <= alley.deck_end()
}

/// Most throws of each kind a study may have (2⁴⁰, beyond any run): keeps 2 × throws and
/// the stratum arithmetic exact.
pub const MAX_THROWS_PER_KIND: u64 = 1 << 40;

fn check_throws(per_kind: u64) -> Result<(), SimError> {
    if per_kind == 0 || per_kind > MAX_THROWS_PER_KIND {
        return Err(SimError::Invalid {
            what: "bowling study".into(),
            field: "throws".into(),
            problem: format!(
                "{per_kind}: need at least one throw of each kind and at most {MAX_THROWS_PER_KIND}"
            ),
        });
    }
    Ok(())
}

/// The scene of throw `index` of a study: `impulse run` on it replays that throw.
///
/// # Errors
/// [`SimError::Invalid`] for a bad alley, bad settings, or an index beyond the study.
pub fn throw_scene(
    alley: &AlleyDesc,
    settings: &ThrowSettings,
    seed: u64,
    throws_per_kind: u64,
    index: u64,
) -> Result<SceneDesc, SimError> {
    let plan = Plan::new(alley, settings, seed, throws_per_kind)?;
    check_index(index, throws_per_kind)?;
    Ok(plan.scene(index))
}

fn check_index(index: u64, per_kind: u64) -> Result<(), SimError> {
    if index >= 2 * per_kind {
        return Err(SimError::Invalid {
            what: "bowling study".into(),
            field: "throw".into(),
            problem: format!(
                "throw {index}: the study has throws 0 to {}",
                2 * per_kind - 1
            ),
        });
    }
    Ok(())
}

/// Runs throw `index` of a study alone (what [`run_throws`] does for each of its throws).
///
/// # Errors
/// As [`throw_scene`]; any error of the throw's world.
pub fn run_throw(
    alley: &AlleyDesc,
    settings: &ThrowSettings,
    seed: u64,
    throws_per_kind: u64,
    index: u64,
) -> Result<ThrowOutcome, SimError> {
    let plan = Plan::new(alley, settings, seed, throws_per_kind)?;
    check_index(index, throws_per_kind)?;
    plan.throw(index)
}

/// Runs the throws of `shard` of a study of `throws_per_kind` straight and as many hooking
/// throws (even indices straight, odd hooks) on `threads` worker threads, calling `progress`
/// with the number done after each. Throw i's aim depends only on (`seed`, i), so the
/// outcomes do not depend on `threads` or on the shard split.
///
/// # Errors
/// [`SimError::Invalid`] for a bad alley or settings, zero throws or zero threads; any
/// error of a throw's world (named by its index).
pub fn run_throws(
    alley: &AlleyDesc,
    settings: &ThrowSettings,
    seed: u64,
    throws_per_kind: u64,
    shard: Shard,
    threads: usize,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<Vec<ThrowOutcome>, SimError> {
    let done = run_throws_with(
        alley,
        settings,
        seed,
        throws_per_kind,
        shard,
        threads,
        &RunHooks::none(progress),
    )?;
    Ok(done.into_iter().map(|(_, t)| t).collect())
}

/// [`run_throws`] steered by `hooks` ([`RunHooks`]: throws done before are skipped, none
/// starts once a stop is asked for, each outcome is recorded as it finishes); returns the
/// throws done, (index, outcome) in index order. A throw depends only on (seed, index).
///
/// # Errors
/// As [`run_throws`].
pub fn run_throws_with(
    alley: &AlleyDesc,
    settings: &ThrowSettings,
    seed: u64,
    throws_per_kind: u64,
    shard: Shard,
    threads: usize,
    hooks: &RunHooks<'_, ThrowOutcome>,
) -> Result<Vec<(u64, ThrowOutcome)>, SimError> {
    let plan = Plan::new(alley, settings, seed, throws_per_kind)?;
    // The first throw's world, built here to report a scene's errors before the workers
    // start.
    World::from_scene(&Scene::new(plan.scene(0), "."))?;
    run_shard_with("throw", 2 * throws_per_kind, shard, threads, hooks, |i| {
        plan.throw(i)
    })
}

/// Merges shard files of one study into the file of the whole study.
///
/// # Errors
/// [`SimError::Invalid`] when there are no files, the files are of different studies, or
/// two files hold the same throw.
pub fn merge(files: &[BowlingFile]) -> Result<BowlingFile, SimError> {
    crate::batch::merge(files)
}

impl crate::batch::StudyFile for BowlingFile {
    type Run = ThrowOutcome;
    const FILES: &'static str = "bowling study files";
    const RUN: &'static str = "throw";
    const HEADER: &'static str = "alley, settings, seed or throws";
    fn same_study(&self, o: &Self) -> bool {
        (&self.alley, self.settings, self.seed, self.throws_per_kind)
            == (&o.alley, o.settings, o.seed, o.throws_per_kind)
    }
    fn check_header(&self) -> Result<(), SimError> {
        self.check()
    }
    fn runs(&self) -> u64 {
        2 * self.throws_per_kind
    }
    fn outcomes(&self) -> &[ThrowOutcome] {
        &self.outcomes
    }
    fn index(run: &ThrowOutcome) -> u64 {
        run.index
    }
    fn with_outcomes(&self, outcomes: Vec<ThrowOutcome>) -> Self {
        Self {
            outcomes,
            ..self.clone()
        }
    }
}
