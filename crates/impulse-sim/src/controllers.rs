//! Ready-made high-level controllers ([`crate::world::WorldController`]), the two mechanisms
//! of the thesis's furniture scene (§7.3): [`Steer`] pulls a rigid body through a sequence
//! of goal poses by external forces and torques, [`Launch`] overwrites a body's velocity
//! with the ballistic flight that lands its centre of mass on a target. Both are declared in
//! scene files (`controllers: [Steer(...), Launch(...)]`, [`crate::scene::controllers`]) or
//! built in code.
//!
//! Conventions: scenes are z-up. A goal's yaw is the angle of the body's own x axis about
//! the world z axis (from world x); a goal given relative to another body is in that body's
//! own frame, and its yaw is added to that body's yaw.

use glam::{DQuat, DVec3};

use crate::error::SimError;
use crate::world::{BodyHandle, Control, Load, WorldController};

/// One goal of a [`Steer`] controller.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Goal {
    /// Where the body's own frame origin should go (world, or the reference body's frame).
    pub position: DVec3,
    /// The yaw it should have (rad; `None`: any).
    pub yaw: Option<f64>,
}

/// Gains and limits of a [`Steer`] controller, scaled by the body's own mass and inertia so
/// that one set serves bodies of any size. The position loop is a PD in cascade form with a
/// speed limit: the body is asked for the velocity `v_des = ω_n·e/(2ζ)`, at most `max_speed`
/// long, with the acceleration `2·ζ·ω_n·(v_des − v)`, and pushed by `m` times it — below the
/// limit exactly the PD `ω_n²·e − 2·ζ·ω_n·v`. The yaw loop is the same about z with
/// `ω_t` and `max_turn_rate`, and the uprighting loop a PD with `ω_t`; the torque is the
/// world inertia times the angular acceleration asked.
///
/// A PD loop pulling a body across a floor with friction μ stops where its pull no longer
/// overcomes sliding friction: at most `μ·g/ω_n²` short of the goal (3 cm for μ = 0.3 at
/// the default ω_n = 10 rad/s). Choose `reach` above that (a goal is reached only when the
/// body is within it); an integral term was tried and hunts about the goal in stick-slip.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SteerGains {
    /// Natural frequency ω_n (rad/s).
    pub frequency: f64,
    /// Largest speed the position loop asks for (length/s).
    pub max_speed: f64,
    /// Largest yaw rate the yaw loop asks for (rad/s).
    pub max_turn_rate: f64,
    /// Damping ratio ζ (1: critical).
    pub damping_ratio: f64,
    /// Natural frequency of the yaw and uprighting loops (rad/s). Sliding friction holds a
    /// body short of its goal yaw by up to the friction torque over `I·ω_t²`, which for a
    /// flat body on a floor is several times its offset in position: turning wants a
    /// stiffer loop than moving.
    pub turn_frequency: f64,
    /// A goal is reached when the horizontal position error is below this (length)…
    pub reach: f64,
    /// …the yaw error below this (rad)…
    pub reach_angle: f64,
    /// …and the body's speed below this (length/s; its angular speed below this per unit
    /// of `reach`).
    pub settle_speed: f64,
    /// Also pull the body's z axis toward the world's (the thesis's uprighting torques).
    pub upright: bool,
}

impl Default for SteerGains {
    /// ω_n = 10 rad/s, ω_t = 20 rad/s, ζ = 1, at most 0.5 m/s and 1 rad/s (furniture pushed
    /// about), reach 5 cm and 0.1 rad, settled below 2 cm/s, uprighting on.
    fn default() -> Self {
        Self {
            frequency: 10.0,
            max_speed: 0.5,
            max_turn_rate: 1.0,
            turn_frequency: 20.0,
            damping_ratio: 1.0,
            reach: 0.05,
            reach_angle: 0.1,
            settle_speed: 0.02,
            upright: true,
        }
    }
}

/// Pulls a dynamic body through a sequence of goal poses by an external force (horizontal:
/// the floor carries the weight) and torque (about z toward the goal's yaw, and about the
/// horizontal axes toward upright), the thesis's table and chairs. The next goal is taken
/// once the current one is reached and the motion has died down; the last is held.
#[derive(Clone, Debug, PartialEq)]
pub struct Steer {
    body: BodyHandle,
    relative_to: Option<BodyHandle>,
    goals: Vec<Goal>,
    gains: SteerGains,
    period: f64,
    start: f64,
    /// The goal being pursued.
    current: usize,
    /// When each goal was reached (simulated time), in order.
    reached: Vec<f64>,
}

impl Steer {
    /// A controller of `body` at `rate` updates per second, active from time `start`.
    ///
    /// # Errors
    /// [`SimError::Invalid`] for no goals, a non-finite goal, a rate that is not positive
    /// and finite, or gains out of range (each must be finite and > 0).
    pub fn new(
        body: BodyHandle,
        relative_to: Option<BodyHandle>,
        goals: Vec<Goal>,
        gains: SteerGains,
        rate: f64,
        start: f64,
    ) -> Result<Self, SimError> {
        let bad = |field: &str, problem: String| SimError::Invalid {
            what: format!("Steer controller of body {body}"),
            field: field.into(),
            problem,
        };
        if goals.is_empty() {
            return Err(bad("goals", "at least one goal is needed".into()));
        }
        if let Some(g) = goals
            .iter()
            .find(|g| !(g.position.is_finite() && g.yaw.is_none_or(f64::is_finite)))
        {
            return Err(bad("goals", format!("{g:?} is not finite")));
        }
        let positive = |x: f64| x.is_finite() && x > 0.0;
        if !positive(rate) {
            return Err(bad("rate", format!("{rate} must be finite and > 0")));
        }
        if !start.is_finite() {
            return Err(bad("start", format!("{start} must be finite")));
        }
        let g = gains;
        if !(positive(g.frequency)
            && positive(g.turn_frequency)
            && positive(g.max_speed)
            && positive(g.max_turn_rate)
            && positive(g.damping_ratio)
            && positive(g.reach)
            && positive(g.reach_angle)
            && positive(g.settle_speed))
        {
            return Err(bad(
                "gains",
                format!(
                    "{g:?}: frequencies, limits, damping_ratio, reach, reach_angle and \
                     settle_speed must be finite and > 0"
                ),
            ));
        }
        Ok(Self {
            body,
            relative_to,
            goals,
            gains,
            period: 1.0 / rate,
            start,
            current: 0,
            reached: Vec::new(),
        })
    }

    /// The index of the goal being pursued (the last one once all are reached).
    #[must_use]
    pub fn current_goal(&self) -> usize {
        self.current
    }

    /// When each goal was reached so far (simulated time), in order.
    #[must_use]
    pub fn reached(&self) -> &[f64] {
        &self.reached
    }

    /// The current goal in world coordinates: position and yaw.
    fn goal_world(&self, control: &Control<'_>) -> Result<(DVec3, Option<f64>), SimError> {
        let g = self.goals[self.current];
        match self.relative_to {
            None => Ok((g.position, g.yaw)),
            Some(r) => {
                let s = control.world().state(r)?;
                Ok((
                    s.position + s.rotation * g.position,
                    g.yaw.map(|y| y + yaw_of(s.rotation)),
                ))
            }
        }
    }
}

/// The yaw of a rotation: the angle of its x axis about world z, from world x (rad).
#[must_use]
pub fn yaw_of(rotation: DQuat) -> f64 {
    let x = rotation * DVec3::X;
    x.y.atan2(x.x)
}

/// An angle brought into (−π, π].
fn wrap(a: f64) -> f64 {
    let t = std::f64::consts::TAU;
    let r = a.rem_euclid(t);
    if r > std::f64::consts::PI { r - t } else { r }
}

impl WorldController for Steer {
    fn period(&self) -> f64 {
        self.period
    }

    fn update(&mut self, control: &mut Control<'_>) -> Result<(), SimError> {
        if control.time() < self.start {
            return Ok(());
        }
        let (goal, yaw_goal) = self.goal_world(control)?;
        let w = control.world();
        let s = w.state(self.body)?;
        let body = w.body(self.body).ok_or_else(|| SimError::UnknownBody {
            handle: self.body.to_string(),
        })?;
        let Some(mass) = body.mass else {
            return Err(SimError::Invalid {
                what: format!("body \"{}\"", body.name),
                field: "Steer controller".into(),
                problem: "only a dynamic body can be steered".into(),
            });
        };
        let inertia = body.inertia_world();
        let flat = DVec3::new(1.0, 1.0, 0.0);
        let e = (goal - s.position) * flat;
        let v = s.velocity * flat;
        let yaw_err = yaw_goal.map_or(0.0, |y| wrap(y - yaw_of(s.rotation)));
        let g = self.gains;
        // Goal reached and the motion died down: take the next (thesis §7.3's table).
        if e.length() <= g.reach
            && yaw_err.abs() <= g.reach_angle
            && s.velocity.length() <= g.settle_speed
            && s.omega.length() * g.reach <= g.settle_speed
            && self.reached.len() == self.current
        {
            self.reached.push(control.time());
            if self.current + 1 < self.goals.len() {
                self.current += 1;
            }
        }
        let (wn, zeta) = (g.frequency, g.damping_ratio);
        let v_des = (wn * e / (2.0 * zeta)).clamp_length_max(g.max_speed);
        let accel = 2.0 * zeta * wn * (v_des - v);
        // Angular: yaw about z, and the body's z axis toward world z when uprighting.
        let up = s.rotation * DVec3::Z;
        let wt = g.turn_frequency;
        let tilting = if g.upright {
            let horizontal = s.omega * DVec3::new(1.0, 1.0, 0.0);
            wt * wt * up.cross(DVec3::Z) - 2.0 * zeta * wt * horizontal
        } else {
            DVec3::ZERO
        };
        let yaw_rate = (wt * yaw_err / (2.0 * zeta)).clamp(-g.max_turn_rate, g.max_turn_rate);
        let alpha = tilting + DVec3::Z * (2.0 * zeta * wt * (yaw_rate - s.omega.z));
        let load = Load {
            force: mass.mass * accel,
            torque: inertia * alpha,
        };
        control.set_load(self.body, load)
    }
}

/// Overwrites a body's velocity once, at the first update at or after `at`, with the
/// ballistic flight under gravity that brings its centre of mass to `target` after
/// `flight_time` (the thesis's bottle, jumping onto the table "as if after a collision"):
/// `v = (target − x)/T − ½·g·T`, angular velocity zero.
#[derive(Clone, Debug, PartialEq)]
pub struct Launch {
    body: BodyHandle,
    relative_to: Option<BodyHandle>,
    target: DVec3,
    at: f64,
    flight_time: f64,
    period: f64,
    /// When it launched (`None`: not yet).
    launched: Option<f64>,
}

impl Launch {
    /// Launches `body` at time `at` toward `target` (world, or `relative_to`'s own frame at
    /// launch) in `flight_time`; the controller looks at `rate` updates per second.
    ///
    /// # Errors
    /// [`SimError::Invalid`] for a non-finite target or time, a flight time or rate that is
    /// not positive.
    pub fn new(
        body: BodyHandle,
        relative_to: Option<BodyHandle>,
        target: DVec3,
        at: f64,
        flight_time: f64,
        rate: f64,
    ) -> Result<Self, SimError> {
        let bad = |field: &str, problem: String| SimError::Invalid {
            what: format!("Launch controller of body {body}"),
            field: field.into(),
            problem,
        };
        if !(target.is_finite() && at.is_finite()) {
            return Err(bad(
                "target or at",
                format!("{target}, {at} must be finite"),
            ));
        }
        for (field, x) in [("flight_time", flight_time), ("rate", rate)] {
            if !(x.is_finite() && x > 0.0) {
                return Err(bad(field, format!("{x} must be finite and > 0")));
            }
        }
        Ok(Self {
            body,
            relative_to,
            target,
            at,
            flight_time,
            period: 1.0 / rate,
            launched: None,
        })
    }

    /// When it launched (`None`: not yet).
    #[must_use]
    pub fn launched(&self) -> Option<f64> {
        self.launched
    }
}

impl WorldController for Launch {
    fn period(&self) -> f64 {
        self.period
    }

    fn update(&mut self, control: &mut Control<'_>) -> Result<(), SimError> {
        if self.launched.is_some() || control.time() < self.at {
            return Ok(());
        }
        let w = control.world();
        let target = match self.relative_to {
            None => self.target,
            Some(r) => {
                let s = w.state(r)?;
                s.position + s.rotation * self.target
            }
        };
        let com = w.state(self.body)?.com;
        let t = self.flight_time;
        let v = (target - com) / t - 0.5 * w.gravity() * t;
        self.launched = Some(control.time());
        control.set_velocity(self.body, v, DVec3::ZERO)
    }
}
