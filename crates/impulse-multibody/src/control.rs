//! Joint controllers at finite rates and the simulation loop that schedules them (thesis
//! §5.4).
//!
//! A controller samples `(q, v)` at its update times `t_0 + k·period` and its output is held
//! constant until the next update (zero-order hold, §5.4.1: "it commands actuator forces which
//! will persist until the next update"). The simulation integrates exactly up to every update
//! time (§5.4.2: control events share the time-ordered schedule, and the simulation is stopped
//! there), so no step straddles an update. Passive joint elements are not scheduled: they are
//! re-evaluated in every derivative evaluation.

use std::any::Any;

use crate::dynamics::{Workspace, forward_dynamics, inverse_dynamics};
use crate::error::MultibodyError;
use crate::integrate::{Accel, Integrator, IntegratorStats, Stepper};
use crate::limit::{DEFAULT_LIMIT_REST_SPEED, InverseMass, LimitStats, Stop};
use crate::model::{Model, check_len};
use crate::travel::{LinkKinematics, LinkTravel};

/// What a controller sees at an update: the time, the model and the sampled state.
#[derive(Debug)]
pub struct ControlInput<'a> {
    /// Simulation time of the update (s).
    pub time: f64,
    /// The model.
    pub model: &'a Model,
    /// Configuration (nq).
    pub q: &'a [f64],
    /// Velocity (nv).
    pub v: &'a [f64],
}

/// A controller run at its own rate by a [`Simulation`].
///
/// `update` writes the generalized force (nv entries, zeroed before the call) to hold until the
/// next update; the outputs of all enabled controllers are summed with the applied forces.
/// High-level controllers (the thesis's callbacks, e.g. finite-state machines) implement this
/// trait too and may write nothing.
///
/// A controller must be `Clone` and `Send` (a world holding the simulation is copied to undo a
/// failed step, and stepped on any thread): derive `Clone` and the blanket [`ControllerClone`]
/// does the rest.
pub trait Controller: ControllerClone + Send {
    /// Update period (s), > 0 and finite.
    fn period(&self) -> f64;
    /// Samples the state and writes the output to hold (nv).
    fn update(&mut self, input: &ControlInput<'_>, output: &mut [f64]);
    /// `self` as `Any`, for [`Simulation::controller_mut`]: implement as `self`.
    fn as_any_mut(&mut self) -> &mut dyn Any;
    /// Checks the controller against the model of the simulation it is added to (joint
    /// indices in range, finite gains), so that a mistake is an error naming the joint when it
    /// is added, not a panic or a non-finite state later. The default accepts everything.
    ///
    /// # Errors
    /// A [`MultibodyError`] saying what does not fit.
    fn check(&self, model: &Model) -> Result<(), MultibodyError> {
        let _ = model;
        Ok(())
    }
}

/// Copies a boxed [`Controller`]; implemented for every `Controller + Clone` type, so a
/// controller only derives `Clone`.
pub trait ControllerClone {
    /// A boxed copy of `self`.
    fn clone_box(&self) -> Box<dyn Controller>;
}

impl<T: Controller + Clone + 'static> ControllerClone for T {
    fn clone_box(&self) -> Box<dyn Controller> {
        Box::new(self.clone())
    }
}

impl Clone for Box<dyn Controller> {
    fn clone(&self) -> Self {
        self.clone_box()
    }
}

/// An error unless joint index `joint` exists in `model`.
fn check_joint(model: &Model, joint: usize) -> Result<&str, MultibodyError> {
    model
        .joint_names()
        .get(joint)
        .map(String::as_str)
        .ok_or_else(|| MultibodyError::UnknownName {
            kind: "joint",
            name: format!(
                "index {joint} (the model has {} joints)",
                model.joint_count()
            ),
        })
}

/// An error naming `joint` unless every named value is finite.
fn check_finite(joint: &str, values: &[(&str, f64)]) -> Result<(), MultibodyError> {
    match values.iter().find(|(_, v)| !v.is_finite()) {
        None => Ok(()),
        Some((name, v)) => Err(MultibodyError::InvalidJoint {
            joint: joint.to_owned(),
            reason: format!("controller {name} = {v} is not finite"),
        }),
    }
}

/// Positional/velocity PD control of one joint (thesis §5.4.1, Fig. 5.13):
/// `Q = −k_p (q − q_des) − k_v (q̇ − q̇_des)`. With `q̇_des = 0` this is the thesis's positional
/// PD; with `k_p = 0` it regulates velocity.
///
/// A prismatic joint carrying weight m·g along its axis settles at `q_des − m g / k_p`.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct JointPd {
    /// Joint index in coordinate order.
    pub joint: usize,
    /// Position gain k_p (N/m or N·m/rad).
    pub kp: f64,
    /// Velocity gain k_v (N·s/m or N·m·s/rad).
    pub kv: f64,
    /// Desired position.
    pub q_des: f64,
    /// Desired velocity.
    pub qd_des: f64,
    /// Update period (s).
    pub period: f64,
}

impl JointPd {
    /// A PD controller on joint `joint` with target 0.
    #[must_use]
    pub fn new(joint: usize, kp: f64, kv: f64, period: f64) -> Self {
        JointPd {
            joint,
            kp,
            kv,
            q_des: 0.0,
            qd_des: 0.0,
            period,
        }
    }
}

fn joint_slots(model: &Model, joint: usize) -> (usize, usize) {
    (
        model.nq() - model.joint_count() + joint,
        model.base_dofs() + joint,
    )
}

impl Controller for JointPd {
    fn period(&self) -> f64 {
        self.period
    }
    fn update(&mut self, input: &ControlInput<'_>, output: &mut [f64]) {
        let (qi, vi) = joint_slots(input.model, self.joint);
        output[vi] = -self.kp * (input.q[qi] - self.q_des) - self.kv * (input.v[vi] - self.qd_des);
    }
    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
    fn check(&self, model: &Model) -> Result<(), MultibodyError> {
        let name = check_joint(model, self.joint)?;
        check_finite(
            name,
            &[
                ("k_p", self.kp),
                ("k_v", self.kv),
                ("q_des", self.q_des),
                ("qd_des", self.qd_des),
            ],
        )
    }
}

/// PID control of one joint, thesis eq. (5.15):
/// `Q = −k_p (q − q_des) − k_v (q̇ − q̇_des) − k_i ∫(q − q_des) dt`.
/// The integral is accumulated at the controller's rate (rectangle rule on the samples), the
/// way a digital controller does. It removes the static offset of PD under a constant load.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct JointPid {
    /// The PD part.
    pub pd: JointPd,
    /// Integral gain k_i (N/(m·s) or N·m/(rad·s)).
    pub ki: f64,
    /// Accumulated `∫(q − q_des) dt`.
    pub integral: f64,
}

impl JointPid {
    /// A PID controller on joint `joint` with target 0.
    #[must_use]
    pub fn new(joint: usize, kp: f64, kv: f64, ki: f64, period: f64) -> Self {
        JointPid {
            pd: JointPd::new(joint, kp, kv, period),
            ki,
            integral: 0.0,
        }
    }
}

impl Controller for JointPid {
    fn period(&self) -> f64 {
        self.pd.period
    }
    fn update(&mut self, input: &ControlInput<'_>, output: &mut [f64]) {
        let (qi, vi) = joint_slots(input.model, self.pd.joint);
        let e = input.q[qi] - self.pd.q_des;
        self.integral += e * self.pd.period;
        output[vi] =
            -self.pd.kp * e - self.pd.kv * (input.v[vi] - self.pd.qd_des) - self.ki * self.integral;
    }
    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
    fn check(&self, model: &Model) -> Result<(), MultibodyError> {
        self.pd.check(model)?;
        let name = check_joint(model, self.pd.joint)?;
        check_finite(name, &[("k_i", self.ki), ("integral", self.integral)])
    }
}

/// Computed-torque control of all joints of a fixed-base model, thesis eq. (5.16) with no
/// contact force: `Q = M(q) q̈_des + h(q, q̇) − Q_passive(q, q̇)`, evaluated by inverse dynamics,
/// with `q̈_des = q̈_ref + k_p (q_ref − q) + k_v (q̇_ref − q̇)`. Substituted into the dynamics
/// it gives `q̈ = q̈_des` at the update instant (exactly, while the output is fresh).
#[derive(Clone, Debug)]
pub struct ComputedTorque {
    /// Reference positions (one per joint).
    pub q_ref: Vec<f64>,
    /// Reference velocities.
    pub qd_ref: Vec<f64>,
    /// Reference (feed-forward) accelerations.
    pub qdd_ref: Vec<f64>,
    /// Position gain of the outer loop (1/s²).
    pub kp: f64,
    /// Velocity gain of the outer loop (1/s).
    pub kv: f64,
    period: f64,
    ws: Workspace,
    qdd: Vec<f64>,
    passive: Vec<f64>,
}

impl ComputedTorque {
    /// A computed-torque controller for `model` holding every joint at 0.
    ///
    /// # Errors
    /// [`MultibodyError::InvalidArgument`] for a floating base (its base cannot be actuated,
    /// so `q̈ = q̈_des` is unreachable in general) or a bad period.
    pub fn new(model: &Model, kp: f64, kv: f64, period: f64) -> Result<Self, MultibodyError> {
        if model.is_floating() {
            return Err(MultibodyError::InvalidArgument {
                what: "computed torque",
                reason: "needs a fixed base".to_owned(),
            });
        }
        check_period(period)?;
        let n = model.joint_count();
        Ok(ComputedTorque {
            q_ref: vec![0.0; n],
            qd_ref: vec![0.0; n],
            qdd_ref: vec![0.0; n],
            kp,
            kv,
            period,
            ws: Workspace::new(model),
            qdd: vec![0.0; n],
            passive: vec![0.0; n],
        })
    }
}

impl Controller for ComputedTorque {
    fn period(&self) -> f64 {
        self.period
    }
    fn update(&mut self, input: &ControlInput<'_>, output: &mut [f64]) {
        for j in 0..self.qdd.len() {
            self.qdd[j] = self.qdd_ref[j]
                + self.kp * (self.q_ref[j] - input.q[j])
                + self.kv * (self.qd_ref[j] - input.v[j]);
        }
        // Dimensions were checked at creation; the model is the one the controller was made for.
        if inverse_dynamics(
            input.model,
            &mut self.ws,
            input.q,
            input.v,
            &self.qdd,
            None,
            output,
        )
        .is_err()
        {
            output.iter_mut().for_each(|x| *x = 0.0);
            return;
        }
        self.passive.iter_mut().for_each(|x| *x = 0.0);
        if input
            .model
            .add_passive_forces(input.q, input.v, &mut self.passive)
            .is_ok()
        {
            for (o, p) in output.iter_mut().zip(&self.passive) {
                *o -= p;
            }
        }
    }
    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
    fn check(&self, model: &Model) -> Result<(), MultibodyError> {
        if model.is_floating() || model.joint_count() != self.qdd.len() {
            return Err(MultibodyError::InvalidArgument {
                what: "computed torque",
                reason: format!(
                    "made for a fixed-base model of {} joints, added to a {} model of {}",
                    self.qdd.len(),
                    if model.is_floating() {
                        "floating-base"
                    } else {
                        "fixed-base"
                    },
                    model.joint_count()
                ),
            });
        }
        for (j, name) in model.joint_names().iter().enumerate() {
            let at = |v: &[f64]| v.get(j).copied().unwrap_or(f64::NAN);
            check_finite(
                name,
                &[
                    ("k_p", self.kp),
                    ("k_v", self.kv),
                    ("q_ref", at(&self.q_ref)),
                    ("qd_ref", at(&self.qd_ref)),
                    ("qdd_ref", at(&self.qdd_ref)),
                ],
            )?;
        }
        Ok(())
    }
}

fn check_period(period: f64) -> Result<(), MultibodyError> {
    if period.is_finite() && period > 0.0 {
        Ok(())
    } else {
        Err(MultibodyError::InvalidArgument {
            what: "controller period",
            reason: format!("{period} must be finite and > 0"),
        })
    }
}

/// Identifies a controller added to a [`Simulation`].
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub struct ControllerId(usize);

#[derive(Clone)]
struct Slot {
    ctrl: Box<dyn Controller>,
    start: f64,
    period: f64,
    /// Updates done so far; the next is at `start + count·period`.
    count: u64,
    output: Vec<f64>,
    enabled: bool,
    /// Re-enabled since the last update: update at the next opportunity, even off-grid.
    pending: bool,
}

impl Slot {
    fn next_time(&self) -> f64 {
        self.start + self.count as f64 * self.period
    }
}

/// The right-hand side during one control interval.
pub(crate) struct Rhs<'a> {
    pub(crate) model: &'a Model,
    pub(crate) ws: &'a mut Workspace,
    pub(crate) held: &'a [f64],
    pub(crate) tau: &'a mut [f64],
    /// Joints resting on a stop: held at zero acceleration by a constraint force.
    pub(crate) resting: &'a [Stop],
    /// Where every derivative evaluation records the links' states, when tracking is on
    /// ([`Simulation::set_tracking`]).
    pub(crate) track: Option<&'a mut [LinkTravel]>,
}

impl Accel for Rhs<'_> {
    fn accel(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        vdot: &mut [f64],
    ) -> Result<(), MultibodyError> {
        self.tau.copy_from_slice(self.held);
        // Passive elements inside every derivative evaluation (§5.4.1).
        self.model.add_passive_forces(q, v, self.tau)?;
        forward_dynamics(self.model, self.ws, q, v, self.tau, None, vdot)?;
        if let Some(track) = self.track.as_deref_mut() {
            crate::travel::record(self.model, self.ws, t, track);
        }
        if !self.resting.is_empty() {
            let joints: Vec<usize> = self.resting.iter().map(|s| s.joint).collect();
            InverseMass::new(self.model, self.ws, q)?.constrain(
                vdot,
                &joints,
                &vec![0.0; joints.len()],
            );
        }
        Ok(())
    }
}

/// A multibody moving under gravity, passive joint elements, applied forces and scheduled
/// controllers, advanced by an [`Integrator`].
#[derive(Clone)]
pub struct Simulation {
    /// Shared between copies (a world's trial steps copy the simulation at every step; the
    /// model changes only through [`Simulation::model_mut`], which copies it on write).
    pub(crate) model: std::sync::Arc<Model>,
    pub(crate) q: Vec<f64>,
    pub(crate) v: Vec<f64>,
    pub(crate) t: f64,
    pub(crate) integrator: Integrator,
    pub(crate) stepper: Stepper,
    pub(crate) ws: Workspace,
    applied: Vec<f64>,
    /// Generalized contact forces an island holds over its step ([`crate::held`]).
    pub(crate) contact: Vec<f64>,
    pub(crate) held: Vec<f64>,
    pub(crate) tau: Vec<f64>,
    slots: Vec<Slot>,
    /// Joints resting on a stop ([`crate::limit`]).
    pub(crate) resting: Vec<Stop>,
    /// Stops struck slower than this rest (rad/s or m/s).
    pub(crate) rest_speed: f64,
    pub(crate) limit_stats: LimitStats,
    /// The instant of the last stop and how many stops were resolved at it.
    pub(crate) instant: (f64, usize),
    /// Per link, the range of states seen since tracking was last reset (`None`: off).
    pub(crate) travel: Option<Vec<LinkTravel>>,
}

impl std::fmt::Debug for Simulation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Simulation")
            .field("t", &self.t)
            .field("q", &self.q)
            .field("v", &self.v)
            .field("controllers", &self.slots.len())
            .finish_non_exhaustive()
    }
}

impl Simulation {
    /// A simulation of `model` starting at t = 0 from `(q, v)`.
    ///
    /// # Errors
    /// [`MultibodyError::DimensionMismatch`] for wrong lengths, [`MultibodyError::InvalidArgument`]
    /// for a bad integrator setting or a non-finite state.
    pub fn new(
        model: Model,
        q: Vec<f64>,
        v: Vec<f64>,
        integrator: Integrator,
    ) -> Result<Self, MultibodyError> {
        check_len("q", model.nq(), q.len())?;
        check_len("v", model.nv(), v.len())?;
        integrator.validate()?;
        if !(q.iter().chain(&v).all(|x| x.is_finite())) {
            return Err(MultibodyError::InvalidArgument {
                what: "state",
                reason: "not finite".to_owned(),
            });
        }
        let nv = model.nv();
        let mut q = q;
        crate::integrate::normalize_config(&model, &mut q);
        Ok(Simulation {
            stepper: Stepper::new(&model, &integrator),
            ws: Workspace::new(&model),
            q,
            v,
            t: 0.0,
            integrator,
            applied: vec![0.0; nv],
            contact: vec![0.0; nv],
            held: vec![0.0; nv],
            tau: vec![0.0; nv],
            slots: Vec::new(),
            resting: Vec::new(),
            rest_speed: DEFAULT_LIMIT_REST_SPEED,
            limit_stats: LimitStats::default(),
            instant: (f64::NEG_INFINITY, 0),
            travel: None,
            model: std::sync::Arc::new(model),
        })
        .and_then(|sim| {
            sim.check_limits()?;
            Ok(sim)
        })
    }

    /// The model.
    #[must_use]
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// The model, mutable (gravity and passive elements may be changed between calls).
    pub fn model_mut(&mut self) -> &mut Model {
        std::sync::Arc::make_mut(&mut self.model)
    }

    /// Current time (s).
    #[must_use]
    pub fn time(&self) -> f64 {
        self.t
    }

    /// Current configuration (nq).
    #[must_use]
    pub fn q(&self) -> &[f64] {
        &self.q
    }

    /// Current velocity (nv).
    #[must_use]
    pub fn v(&self) -> &[f64] {
        &self.v
    }

    /// Integration counters.
    #[must_use]
    pub fn stats(&self) -> IntegratorStats {
        self.stepper.stats
    }

    /// Replaces the state (e.g. after a collision impulse changed `v`).
    ///
    /// # Errors
    /// [`MultibodyError::DimensionMismatch`] for wrong lengths.
    pub fn set_state(&mut self, q: &[f64], v: &[f64]) -> Result<(), MultibodyError> {
        check_len("q", self.model.nq(), q.len())?;
        check_len("v", self.model.nv(), v.len())?;
        let (old_q, old_v) = (self.q.clone(), self.v.clone());
        self.q.copy_from_slice(q);
        self.v.copy_from_slice(v);
        crate::integrate::normalize_config(&self.model, &mut self.q);
        if let Err(e) = self.check_limits() {
            self.q = old_q;
            self.v = old_v;
            return Err(e);
        }
        // A new state is a new start: no joint rests on a stop until it strikes one.
        self.resting.clear();
        Ok(())
    }

    /// Sets constant applied generalized forces (nv), added to the controllers' outputs.
    ///
    /// # Errors
    /// [`MultibodyError::DimensionMismatch`] for a wrong length.
    pub fn set_applied_forces(&mut self, tau: &[f64]) -> Result<(), MultibodyError> {
        check_len("applied forces", self.model.nv(), tau.len())?;
        self.applied.copy_from_slice(tau);
        Ok(())
    }

    /// Adds a controller; its first update is now and then every `period` seconds.
    ///
    /// # Errors
    /// [`MultibodyError::InvalidArgument`] if its period is not finite and positive; whatever
    /// [`Controller::check`] finds wrong against this simulation's model (a joint index out of
    /// range, a non-finite gain or target, naming the joint).
    pub fn add_controller(
        &mut self,
        ctrl: Box<dyn Controller>,
    ) -> Result<ControllerId, MultibodyError> {
        let period = ctrl.period();
        check_period(period)?;
        ctrl.check(&self.model)?;
        self.slots.push(Slot {
            ctrl,
            start: self.t,
            period,
            count: 0,
            output: vec![0.0; self.model.nv()],
            enabled: true,
            pending: false,
        });
        Ok(ControllerId(self.slots.len() - 1))
    }

    /// The controller `id` as its concrete type (to change targets or gains).
    pub fn controller_mut<T: 'static>(&mut self, id: ControllerId) -> Option<&mut T> {
        self.slots
            .get_mut(id.0)?
            .ctrl
            .as_any_mut()
            .downcast_mut::<T>()
    }

    /// Sets the targets `q_des`, `q̇_des` of every [`JointPd`] and [`JointPid`] on joint
    /// `joint` (coordinate order) and returns how many there are. A digital controller: the
    /// new targets act from each controller's next update on its own grid.
    ///
    /// # Errors
    /// [`MultibodyError::UnknownName`] for a joint out of range,
    /// [`MultibodyError::InvalidJoint`] for a target that is not finite.
    pub fn set_joint_targets(
        &mut self,
        joint: usize,
        q_des: f64,
        qd_des: f64,
    ) -> Result<usize, MultibodyError> {
        let name = check_joint(&self.model, joint)?;
        check_finite(name, &[("q_des", q_des), ("qd_des", qd_des)])?;
        let mut set = 0;
        for slot in &mut self.slots {
            let any = slot.ctrl.as_any_mut();
            let pd = if let Some(pid) = any.downcast_mut::<JointPid>() {
                &mut pid.pd
            } else if let Some(pd) = any.downcast_mut::<JointPd>() {
                pd
            } else {
                continue;
            };
            if pd.joint == joint {
                pd.q_des = q_des;
                pd.qd_des = qd_des;
                set += 1;
            }
        }
        Ok(set)
    }

    /// Enables or disables a controller. A disabled controller contributes nothing and is not
    /// updated. Re-enabled (the thesis's setPID), it updates at once — at the current time,
    /// before any further integration — and then continues on its original grid
    /// `t₀ + k·period`.
    ///
    /// # Errors
    /// [`MultibodyError::UnknownName`] for an unknown id.
    pub fn set_enabled(&mut self, id: ControllerId, enabled: bool) -> Result<(), MultibodyError> {
        let slot = self
            .slots
            .get_mut(id.0)
            .ok_or(MultibodyError::UnknownName {
                kind: "controller",
                name: id.0.to_string(),
            })?;
        if enabled && !slot.enabled {
            slot.pending = true;
        }
        slot.enabled = enabled;
        if !enabled {
            slot.pending = false;
            slot.output.iter_mut().for_each(|x| *x = 0.0);
        }
        Ok(())
    }

    /// The output a controller currently holds (nv).
    #[must_use]
    pub fn controller_output(&self, id: ControllerId) -> Option<&[f64]> {
        self.slots.get(id.0).map(|s| s.output.as_slice())
    }

    /// Kinetic plus gravitational potential energy (J) at the current state.
    ///
    /// # Errors
    /// Never for a consistent simulation (lengths are fixed).
    pub fn energy(&mut self) -> Result<f64, MultibodyError> {
        self.ws.update_kinematics(&self.model, &self.q, &self.v)?;
        Ok(self.ws.kinetic_energy(&self.model) + self.ws.potential_energy(&self.model))
    }

    /// A workspace whose kinematics are those of the current state (for queries such as
    /// momentum or link poses).
    ///
    /// # Errors
    /// Never for a consistent simulation (lengths are fixed).
    pub fn kinematics(&mut self) -> Result<&Workspace, MultibodyError> {
        self.ws.update_kinematics(&self.model, &self.q, &self.v)?;
        Ok(&self.ws)
    }

    /// Turns on (or off) the recording of every link's range of states at every derivative
    /// evaluation ([`Simulation::take_travel`]): what a hybrid event loop checks its
    /// predictions against (thesis §5.2, Figs. 5.3 and 5.4). Off by default.
    pub fn set_tracking(&mut self, on: bool) {
        self.travel = on.then(|| vec![LinkTravel::EMPTY; self.model.link_count()]);
    }

    /// The range of states of every link (in link order) seen since the last call, and
    /// empty ranges from now on; `None` when tracking is off.
    pub fn take_travel(&mut self) -> Option<Vec<LinkTravel>> {
        let n = self.model.link_count();
        self.travel
            .as_mut()
            .map(|t| std::mem::replace(t, vec![LinkTravel::EMPTY; n]))
    }

    /// Every link's kinematics now (in link order): pose, velocity, angular velocity and the
    /// acceleration of its frame origin under the forces held now (gravity, passive
    /// elements, applied forces and controller outputs; a joint resting on a stop is not
    /// held here, but a multibody every joint of which rests on its stop, at rest, has no
    /// acceleration: its state is a fixed point of its motion). What a hybrid event loop
    /// predicts the links' next motion from.
    ///
    /// # Errors
    /// [`MultibodyError::SingularInertia`] for a non-finite state.
    pub fn link_kinematics(&mut self) -> Result<Vec<LinkKinematics>, MultibodyError> {
        if self.all_resting() {
            self.ws.update_kinematics(&self.model, &self.q, &self.v)?;
            let mut at_rest = crate::travel::kinematics(&self.model, &mut self.ws);
            for k in &mut at_rest {
                k.acceleration = glam::DVec3::ZERO;
                k.angular_acceleration = glam::DVec3::ZERO;
            }
            return Ok(at_rest);
        }
        let mut vdot = vec![0.0; self.model.nv()];
        self.tau.copy_from_slice(&self.held);
        self.model
            .add_passive_forces(&self.q, &self.v, &mut self.tau)?;
        forward_dynamics(
            &self.model,
            &mut self.ws,
            &self.q,
            &self.v,
            &self.tau,
            None,
            &mut vdot,
        )?;
        Ok(crate::travel::kinematics(&self.model, &mut self.ws))
    }

    /// When the next controller update is due (simulation time; ∞ without enabled
    /// controllers): [`Simulation::run_until`] stops there, and a hybrid event loop ends its
    /// step there so that its predictions start from the new outputs (thesis §5.4: control
    /// updates are events).
    #[must_use]
    pub fn next_control_time(&self) -> f64 {
        self.slots
            .iter()
            .filter(|s| s.enabled)
            .map(|s| if s.pending { self.t } else { s.next_time() })
            .fold(f64::INFINITY, f64::min)
    }

    /// Runs the controllers due at the current time and sums the held outputs.
    fn fire_due(&mut self) {
        let input = ControlInput {
            time: self.t,
            model: &self.model,
            q: &self.q,
            v: &self.v,
        };
        for slot in &mut self.slots {
            let due = slot.next_time() <= self.t;
            if slot.enabled && (due || slot.pending) {
                slot.pending = false;
                slot.output.iter_mut().for_each(|x| *x = 0.0);
                slot.ctrl.update(&input, &mut slot.output);
            }
            if due {
                // Skip every period that is already due (only possible after set_state/time
                // jumps); the next update is strictly in the future.
                while slot.next_time() <= self.t {
                    slot.count += 1;
                }
            }
        }
        self.held.copy_from_slice(&self.applied);
        for (h, c) in self.held.iter_mut().zip(&self.contact) {
            *h += c;
        }
        for slot in self.slots.iter().filter(|s| s.enabled) {
            for (h, o) in self.held.iter_mut().zip(&slot.output) {
                *h += o;
            }
        }
    }

    /// Advances to time `t_end` (s), stopping exactly at every controller update on the way.
    ///
    /// # Errors
    /// [`MultibodyError::InvalidArgument`] if `t_end` is not finite or lies in the past;
    /// [`MultibodyError::StepSizeUnderflow`] or [`MultibodyError::NonFiniteState`] from the
    /// integrator (the state is then the one at the failure).
    pub fn run_until(&mut self, t_end: f64) -> Result<(), MultibodyError> {
        self.run(t_end, false).map(|_| ())
    }

    /// [`Simulation::run_until`], but returning as soon as a joint strikes a stop, with the
    /// strike resolved ([`crate::limit`]): the time reached, `t_end` when no stop was struck.
    /// A strike changes the velocity at once, which a world's contact island holding a link
    /// must see before its held loads act on (they were solved for the velocity before).
    ///
    /// # Errors
    /// As [`Simulation::run_until`].
    pub fn run_until_strike(&mut self, t_end: f64) -> Result<f64, MultibodyError> {
        self.run(t_end, true)
    }

    fn run(&mut self, t_end: f64, stop_at_strike: bool) -> Result<f64, MultibodyError> {
        if !t_end.is_finite() || t_end < self.t {
            return Err(MultibodyError::InvalidArgument {
                what: "end time",
                reason: format!("{t_end} must be finite and >= the current time {}", self.t),
            });
        }
        loop {
            self.fire_due();
            if self.t >= t_end {
                return Ok(self.t);
            }
            let next = self.slots.iter().map(Slot::next_time).fold(t_end, f64::min);
            if self.model.has_limits() {
                let strikes = self.limit_stats.strikes;
                self.step_with_stops(next)?;
                if stop_at_strike && self.limit_stats.strikes > strikes {
                    return Ok(self.t);
                }
                continue;
            }
            let mut rhs = Rhs {
                model: &self.model,
                ws: &mut self.ws,
                held: &self.held,
                tau: &mut self.tau,
                resting: &[],
                track: self.travel.as_deref_mut(),
            };
            self.stepper.advance(
                &self.integrator,
                &self.model,
                &mut rhs,
                self.t,
                next,
                &mut self.q,
                &mut self.v,
            )?;
            self.t = next;
        }
    }
}

#[cfg(test)]
mod tests;
