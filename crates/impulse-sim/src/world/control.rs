//! High-level controllers in the world (thesis §5.4 and §7.3): code a user writes in Rust,
//! called at its own rate with read access to the whole world and a few commands — set a
//! body's external force and torque, overwrite its velocity (the furniture scene's bottle,
//! launched "as if after a collision"), give it an impulse, and set the targets of a
//! multibody's joint controllers (the rover's wheel speeds and piston lengths).
//!
//! A controller is scheduled as an event of the loop: a loop step never ends later than the
//! next controller update, as it never ends later than the top of the collision heap, so an
//! update sees the world exactly at `t₀ + k·period` (no drift over long runs: the k-th update
//! time is computed, not accumulated). Commands act at once: the pairs of a body a command
//! touched get new time-of-impact bounds before the loop goes on, so the collision guarantees
//! hold across them. Low-level joint controllers keep their own rates inside their
//! multibody's integration (§5.4.1); targets set here act from their next update.
//!
//! A controller sees the world between loop steps only: it cannot step the world, add or
//! remove bodies, or add controllers.

use std::any::Any;

use glam::DVec3;

use super::api::Load;
use super::{BodyHandle, MultibodyHandle, World};
use crate::error::SimError;

/// A high-level controller. Derive `Clone` on the implementing type: a world is copied to
/// undo a step that fails, controllers included.
pub trait WorldController: WorldControllerClone + Send + Sync {
    /// Seconds of simulated time between two updates (finite, > 0).
    fn period(&self) -> f64;

    /// One update at time [`Control::time`]. An error stops the world's step: it returns the
    /// error (naming the controller) and the world is as it was before that step.
    ///
    /// # Errors
    /// Whatever the controller decides; the commands' own errors.
    fn update(&mut self, control: &mut Control<'_>) -> Result<(), SimError>;
}

/// Copying and downcasting a boxed [`WorldController`]; implemented for every controller type
/// that is `Clone + 'static`.
pub trait WorldControllerClone {
    /// A boxed copy.
    fn clone_box(&self) -> Box<dyn WorldController>;
    /// As [`Any`], to read a controller back as its concrete type.
    fn as_any(&self) -> &dyn Any;
    /// As mutable [`Any`].
    fn as_any_mut(&mut self) -> &mut dyn Any;
}

impl<T: WorldController + Clone + 'static> WorldControllerClone for T {
    fn clone_box(&self) -> Box<dyn WorldController> {
        Box::new(self.clone())
    }
    fn as_any(&self) -> &dyn Any {
        self
    }
    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}

/// A controller added to a world ([`World::add_controller`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ControllerHandle(u32);

/// A controller and its schedule.
pub(super) struct ControllerSlot {
    name: String,
    ctrl: Box<dyn WorldController>,
    start: f64,
    period: f64,
    /// Updates done so far; the next is at `start + updates·period`.
    updates: u64,
}

impl Clone for ControllerSlot {
    fn clone(&self) -> Self {
        Self {
            name: self.name.clone(),
            ctrl: self.ctrl.clone_box(),
            start: self.start,
            period: self.period,
            updates: self.updates,
        }
    }
}

impl ControllerSlot {
    fn next_time(&self) -> f64 {
        self.start + self.updates as f64 * self.period
    }
}

/// What a controller may read and do during an update.
pub struct Control<'a> {
    world: &'a mut World,
}

impl Control<'_> {
    /// The world, read-only: bodies' states, multibodies' joint states, contacts, time.
    #[must_use]
    pub fn world(&self) -> &World {
        self.world
    }

    /// Simulated time of this update (s).
    #[must_use]
    pub fn time(&self) -> f64 {
        self.world.time
    }

    /// Sets the external force (through the centre of mass) and torque on a dynamic body,
    /// held until changed ([`World::set_load`]).
    ///
    /// # Errors
    /// As [`World::set_load`].
    pub fn set_load(&mut self, body: BodyHandle, load: Load) -> Result<(), SimError> {
        self.world.set_load(body, load)
    }

    /// Removes a body's external load ([`World::clear_load`]).
    ///
    /// # Errors
    /// As [`World::clear_load`].
    pub fn clear_load(&mut self, body: BodyHandle) -> Result<(), SimError> {
        self.world.clear_load(body)
    }

    /// Overwrites a dynamic body's velocity and angular velocity ([`World::set_velocity`]).
    ///
    /// # Errors
    /// As [`World::set_velocity`].
    pub fn set_velocity(
        &mut self,
        body: BodyHandle,
        velocity: DVec3,
        omega: DVec3,
    ) -> Result<(), SimError> {
        self.world.set_velocity(body, velocity, omega)
    }

    /// Gives a dynamic body an impulse at a world point ([`World::apply_impulse`]).
    ///
    /// # Errors
    /// As [`World::apply_impulse`].
    pub fn apply_impulse(
        &mut self,
        body: BodyHandle,
        impulse: DVec3,
        point: DVec3,
    ) -> Result<(), SimError> {
        self.world.apply_impulse(body, impulse, point)
    }

    /// Sets the targets `q_des`, `q̇_des` of every PD and PID controller on the named joint
    /// of a multibody, and returns how many there are (at least one).
    ///
    /// # Errors
    /// [`SimError::Invalid`] naming the multibody and joint: an unknown multibody or joint, a
    /// joint without a PD or PID controller, a target that is not finite.
    pub fn set_joint_target(
        &mut self,
        multibody: MultibodyHandle,
        joint: &str,
        q_des: f64,
        qd_des: f64,
    ) -> Result<usize, SimError> {
        let member = self
            .world
            .multibodies
            .get_mut(multibody.0 as usize)
            .ok_or_else(|| SimError::Invalid {
                what: format!("multibody #{}", multibody.0),
                field: "joint target".into(),
                problem: "no such multibody in this world".into(),
            })?;
        let invalid = |problem: String| SimError::Invalid {
            what: format!("multibody \"{}\", joint \"{joint}\"", member.name),
            field: "joint target".into(),
            problem,
        };
        let j = member
            .sim
            .model()
            .joint_index(joint)
            .ok_or_else(|| invalid("no such joint".into()))?;
        let set = member
            .sim
            .set_joint_targets(j, q_des, qd_des)
            .map_err(|e| invalid(e.to_string()))?;
        if set == 0 {
            return Err(invalid("the joint has no PD or PID controller".into()));
        }
        Ok(set)
    }
}

impl World {
    /// Adds a high-level controller named `name` and runs its first update now; the next are
    /// at `now + k·period`.
    ///
    /// # Errors
    /// [`SimError::Invalid`] for an empty or taken name or a period that is not finite and
    /// positive; whatever the first update returns. The world is then unchanged.
    pub fn add_controller(
        &mut self,
        name: &str,
        controller: Box<dyn WorldController>,
    ) -> Result<ControllerHandle, SimError> {
        let period = controller.period();
        let bad = |problem: String| SimError::Invalid {
            what: format!("controller \"{name}\""),
            field: "name or period".into(),
            problem,
        };
        if name.is_empty() || self.controllers.iter().flatten().any(|c| c.name == name) {
            return Err(bad("the name is empty or taken".into()));
        }
        if !(period.is_finite() && period > 0.0) {
            return Err(bad(format!("period {period} must be finite and > 0")));
        }
        let backup = self.clone();
        self.controllers.push(Some(ControllerSlot {
            name: name.to_owned(),
            ctrl: controller,
            start: self.time,
            period,
            updates: 0,
        }));
        let k = self.controllers.len() - 1;
        if let Err(e) = self.update_controller(k) {
            *self = backup;
            return Err(e);
        }
        Ok(ControllerHandle(k as u32))
    }

    /// Removes a controller and returns it (loads and targets it set stay as they are).
    ///
    /// # Errors
    /// [`SimError::Invalid`] for a controller already removed.
    pub fn remove_controller(
        &mut self,
        h: ControllerHandle,
    ) -> Result<Box<dyn WorldController>, SimError> {
        self.controllers
            .get_mut(h.0 as usize)
            .and_then(Option::take)
            .map(|s| s.ctrl)
            .ok_or_else(|| SimError::Invalid {
                what: format!("controller #{}", h.0),
                field: "handle".into(),
                problem: "no such controller (removed?)".into(),
            })
    }

    /// The controller `h` as its concrete type (`None` for another type or a removed one).
    #[must_use]
    pub fn controller<T: 'static>(&self, h: ControllerHandle) -> Option<&T> {
        self.controllers
            .get(h.0 as usize)?
            .as_ref()?
            .ctrl
            .as_any()
            .downcast_ref()
    }

    /// The controller `h` as its concrete type, to change its settings between steps.
    pub fn controller_mut<T: 'static>(&mut self, h: ControllerHandle) -> Option<&mut T> {
        self.controllers
            .get_mut(h.0 as usize)?
            .as_mut()?
            .ctrl
            .as_any_mut()
            .downcast_mut()
    }

    /// The handle of the controller named `name`.
    #[must_use]
    pub fn controller_handle(&self, name: &str) -> Option<ControllerHandle> {
        self.controllers
            .iter()
            .position(|c| c.as_ref().is_some_and(|c| c.name == name))
            .map(|k| ControllerHandle(k as u32))
    }

    /// When the next controller update is due (∞ without any).
    pub(super) fn next_controller_time(&self) -> f64 {
        self.controllers
            .iter()
            .flatten()
            .map(ControllerSlot::next_time)
            .fold(f64::INFINITY, f64::min)
    }

    /// Runs every controller due now (in the order they were added), then gives new bounds
    /// to the pairs of the bodies their commands touched.
    pub(super) fn update_due_controllers(&mut self) -> Result<(), SimError> {
        for k in 0..self.controllers.len() {
            if self.controllers[k]
                .as_ref()
                .is_some_and(|c| c.next_time() <= self.time)
            {
                self.update_controller(k)?;
            }
        }
        Ok(())
    }

    /// One update of controller `k` (taken out of the world while it runs).
    fn update_controller(&mut self, k: usize) -> Result<(), SimError> {
        let Some(mut slot) = self.controllers[k].take() else {
            return Ok(());
        };
        let result = slot.ctrl.update(&mut Control { world: self });
        // Skip updates that fell between two steps (a rate above the loop's cannot happen:
        // steps end at every update; this guards rounding of the grid).
        while slot.next_time() <= self.time {
            slot.updates += 1;
        }
        let name = slot.name.clone();
        self.controllers[k] = Some(slot);
        self.counters.controller_updates += 1;
        result.map_err(|e| SimError::Runtime {
            time: self.time,
            message: format!("controller \"{name}\": {e}"),
        })
    }
}
