//! High-level controllers in scene files ([`crate::controllers`]): the furniture scene's
//! steering by external forces and its launch by velocity overwrite (thesis §7.3).
//!
//! ```ron
//! controllers: [
//!     Steer(name: "move table", body: "table", rate: 50.0,
//!           goals: [Goal(position: (1.0, 0.5, 0.4), yaw: Some(0.5)),
//!                   Goal(position: (2.0, 0.5, 0.4))]),
//!     Steer(name: "chair follows", body: "chair", relative_to: Some("table"),
//!           goals: [Goal(position: (0.0, -0.6, -0.2), yaw: Some(1.5708))]),
//!     Launch(name: "bottle jumps", body: "bottle", relative_to: Some("table"),
//!            target: (0.0, 0.0, 0.5), at: 3.0, flight_time: 0.5),
//! ]
//! ```

use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::finite3;
use crate::controllers::{Goal, Launch, Steer, SteerGains};
use crate::error::SimError;
use crate::world::{BodyHandle, World, WorldController};

fn default_rate() -> f64 {
    50.0
}
fn default_frequency() -> f64 {
    SteerGains::default().frequency
}
fn default_max_speed() -> f64 {
    SteerGains::default().max_speed
}
fn default_max_turn_rate() -> f64 {
    SteerGains::default().max_turn_rate
}
fn default_turn_frequency() -> f64 {
    SteerGains::default().turn_frequency
}
fn default_damping_ratio() -> f64 {
    SteerGains::default().damping_ratio
}
fn default_reach() -> f64 {
    SteerGains::default().reach
}
fn default_reach_angle() -> f64 {
    SteerGains::default().reach_angle
}
fn default_settle_speed() -> f64 {
    SteerGains::default().settle_speed
}
fn default_true() -> bool {
    true
}

/// One goal of a `Steer` controller.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Goal", deny_unknown_fields)]
pub struct GoalDesc {
    /// Where the body's own frame origin should go (world, or `relative_to`'s own frame).
    pub position: [f64; 3],
    /// Its yaw about world z (rad; plus `relative_to`'s yaw). Default `None`: any.
    #[serde(default)]
    pub yaw: Option<f64>,
}

/// A high-level controller of a scene, updated `rate` times per second.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum WorldControllerDesc {
    /// Pulls a body through its goals by a horizontal force and a torque
    /// ([`crate::controllers::Steer`]); gains as [`SteerGains`] (defaults there).
    Steer {
        /// Unique name among the scene's controllers.
        name: String,
        /// The body steered (a dynamic body).
        body: String,
        /// Goals in order; the last is held.
        goals: Vec<GoalDesc>,
        /// A body whose own frame the goals are given in. Default `None`: world.
        #[serde(default)]
        relative_to: Option<String>,
        /// Updates per second. Default `50`.
        #[serde(default = "default_rate")]
        rate: f64,
        /// When it starts pulling (s). Default `0`.
        #[serde(default)]
        start: f64,
        /// ω_n of the position loop (rad/s).
        #[serde(default = "default_frequency")]
        frequency: f64,
        /// Largest speed asked for (length/s).
        #[serde(default = "default_max_speed")]
        max_speed: f64,
        /// Largest yaw rate asked for (rad/s).
        #[serde(default = "default_max_turn_rate")]
        max_turn_rate: f64,
        /// ω_t of the yaw and uprighting loops (rad/s).
        #[serde(default = "default_turn_frequency")]
        turn_frequency: f64,
        /// ζ of both loops.
        #[serde(default = "default_damping_ratio")]
        damping_ratio: f64,
        /// Position tolerance of a goal (length).
        #[serde(default = "default_reach")]
        reach: f64,
        /// Yaw tolerance of a goal (rad).
        #[serde(default = "default_reach_angle")]
        reach_angle: f64,
        /// Speed below which the motion has died down (length/s).
        #[serde(default = "default_settle_speed")]
        settle_speed: f64,
        /// Pull the body's z axis upright. Default `true`.
        #[serde(default = "default_true")]
        upright: bool,
    },
    /// Overwrites a body's velocity once with a ballistic flight to a target
    /// ([`crate::controllers::Launch`]).
    Launch {
        /// Unique name among the scene's controllers.
        name: String,
        /// The body launched (a dynamic body).
        body: String,
        /// Where its centre of mass should land (world, or `relative_to`'s own frame).
        target: [f64; 3],
        /// A body whose own frame `target` is in, at the launch. Default `None`: world.
        #[serde(default)]
        relative_to: Option<String>,
        /// Launch time (s; at the first update at or after it).
        at: f64,
        /// Time of flight (s).
        flight_time: f64,
        /// Updates per second (how closely the launch follows `at`). Default `50`.
        #[serde(default = "default_rate")]
        rate: f64,
    },
}

impl WorldControllerDesc {
    /// The controller's name.
    #[must_use]
    pub fn name(&self) -> &str {
        match self {
            Self::Steer { name, .. } | Self::Launch { name, .. } => name,
        }
    }

    /// Checks the description against the scene's body names, naming the controller.
    ///
    /// # Errors
    /// [`SimError::Invalid`] for an empty name, an unknown body, non-finite values, or what
    /// the controller's constructor refuses.
    pub fn validate(&self, bodies: &[&str]) -> Result<(), SimError> {
        let what = format!("controller \"{}\"", self.name());
        let bad = |field: &str, problem: String| SimError::Invalid {
            what: what.clone(),
            field: field.into(),
            problem,
        };
        if self.name().is_empty() {
            return Err(bad("name", "is empty".into()));
        }
        let (body, relative_to) = match self {
            Self::Steer {
                body,
                relative_to,
                goals,
                ..
            } => {
                for (k, g) in goals.iter().enumerate() {
                    finite3(&g.position).map_err(|p| bad(&format!("goals[{k}].position"), p))?;
                    if g.yaw.is_some_and(|y| !y.is_finite()) {
                        return Err(bad(&format!("goals[{k}].yaw"), "is not finite".into()));
                    }
                }
                (body, relative_to)
            }
            Self::Launch {
                body,
                relative_to,
                target,
                ..
            } => {
                finite3(target).map_err(|p| bad("target", p))?;
                (body, relative_to)
            }
        };
        for (field, name) in [("body", Some(body)), ("relative_to", relative_to.as_ref())] {
            if let Some(n) = name
                && !bodies.contains(&n.as_str())
            {
                return Err(bad(field, format!("no body \"{n}\" in the scene")));
            }
        }
        // The constructors' own checks (gains, rates, times), on placeholder handles.
        self.make(BodyHandle::PLACEHOLDER, None)
            .map(|_| ())
            .map_err(|e| rename(e, &what))
    }

    /// Adds the controller to a world whose bodies carry the scene's names.
    ///
    /// # Errors
    /// [`SimError::Invalid`] naming the controller for an unknown body; what
    /// [`World::add_controller`] returns.
    pub fn add_to(&self, world: &mut World) -> Result<(), SimError> {
        let what = format!("controller \"{}\"", self.name());
        let find = |field: &str, name: &str| {
            world.handle(name).ok_or_else(|| SimError::Invalid {
                what: what.clone(),
                field: field.into(),
                problem: format!("no body \"{name}\" in the world"),
            })
        };
        let (body, relative_to) = match self {
            Self::Steer {
                body, relative_to, ..
            }
            | Self::Launch {
                body, relative_to, ..
            } => (body, relative_to),
        };
        let body = find("body", body)?;
        let relative_to = relative_to
            .as_ref()
            .map(|r| find("relative_to", r))
            .transpose()?;
        let ctrl = self.make(body, relative_to).map_err(|e| rename(e, &what))?;
        world.add_controller(self.name(), ctrl)?;
        Ok(())
    }

    fn make(
        &self,
        body: BodyHandle,
        relative_to: Option<BodyHandle>,
    ) -> Result<Box<dyn WorldController>, SimError> {
        Ok(match self {
            Self::Steer {
                goals,
                rate,
                start,
                frequency,
                max_speed,
                max_turn_rate,
                turn_frequency,
                damping_ratio,
                reach,
                reach_angle,
                settle_speed,
                upright,
                ..
            } => {
                let goals = goals
                    .iter()
                    .map(|g| Goal {
                        position: DVec3::from_array(g.position),
                        yaw: g.yaw,
                    })
                    .collect();
                let gains = SteerGains {
                    frequency: *frequency,
                    max_speed: *max_speed,
                    max_turn_rate: *max_turn_rate,
                    turn_frequency: *turn_frequency,
                    damping_ratio: *damping_ratio,
                    reach: *reach,
                    reach_angle: *reach_angle,
                    settle_speed: *settle_speed,
                    upright: *upright,
                };
                Box::new(Steer::new(body, relative_to, goals, gains, *rate, *start)?)
            }
            Self::Launch {
                target,
                at,
                flight_time,
                rate,
                ..
            } => Box::new(Launch::new(
                body,
                relative_to,
                DVec3::from_array(*target),
                *at,
                *flight_time,
                *rate,
            )?),
        })
    }
}

/// A constructor's error, told about the controller by its scene name.
fn rename(e: SimError, what: &str) -> SimError {
    match e {
        SimError::Invalid { field, problem, .. } => SimError::Invalid {
            what: what.to_owned(),
            field,
            problem,
        },
        other => other,
    }
}
