//! Bodies of a world and their motion between collisions (thesis §1.2: "dynamic evolution").
//!
//! A body has two frames. Its **pose** maps its principal frame at the centre of mass
//! (dynamic bodies) or the frame its shape was given in (fixed and scripted bodies) to the
//! world; the collision shape and the inertia live there. Its **own frame** is the frame the
//! user placed it with (a scene's `position` and `rotation`): [`Body::frame_pose`] gives it,
//! and that is what the world reports ([`crate::BodyState`]).
//!
//! Between collisions a dynamic body is ballistic: its centre of mass follows the parabola of
//! gravity plus any constant external force over its mass exactly, and it rotates under its
//! external torque (zero for the thesis's torque-free flight). The rotation is integrated with
//! the world angular momentum `L(t) = L₀ + τ·t` in closed form (constant without torque), so
//! `L` is exact to rounding by construction; the orientation `q` follows `q̇ = ½·ω⊗q` with
//! `ω = R·I⁻¹·Rᵀ·L`, by an adaptive fourth-order Runge–Kutta with step doubling (11 derivative
//! evaluations per step, as thesis chapter 7 describes). Kinetic energy `½ L·ω` then drifts
//! only by the orientation error, bounded by [`Integrator::rotation_tolerance`]. Bodies with
//! equal principal moments (spheres, cubes) and no torque rotate at constant ω and use the
//! exact rotation; under a torque their ω changes linearly and the orientation takes Magnus
//! steps (`rotation.rs`: one per millisecond for a rolling pool ball, where the integrator
//! took about 25); axisymmetric ones (two equal moments: coins, cylinders, square rods) with
//! no torque use the closed form of the free symmetric top (`torque_free_axisymmetric`), and
//! bodies with three distinct moments and no torque that of the free asymmetric top
//! (`free_top.rs`: Jacobi elliptic functions for ω, a quadrature to rounding for the angle
//! about L), each a fixed cost whatever the spin and the interval. The integrator serves
//! bodies under a torque and the few motions within `free_top::SEPARATRIX_MC` of the
//! separatrix.

use std::sync::Arc;

use glam::{DMat3, DQuat, DVec3};
use impulse_collide::{Motion, Shape, motion::Ballistic};
use impulse_geom::Pose;

mod elliptic;
mod free_top;
mod rotation;
use free_top::torque_free_asymmetric;
use rotation::{isotropic_with_torque, step_doubling, symmetry_axis, torque_free_axisymmetric};

/// Principal moments closer than this, relative to the largest, count as equal: the body then
/// rotates at constant ω (exact solution). Default `1e-12` (relative).
pub const ISOTROPIC_INERTIA_REL: f64 = 1e-12;

/// Largest number of Runge–Kutta steps one call of [`Body::advance`] may take before it gives
/// up and reports [`AdvanceError::TooManySteps`]. A body spinning at ω for a time T needs about
/// `ω·T / (tolerance^(1/5))` steps; the default `1_000_000` is far beyond any scene's need.
pub const MAX_ROTATION_STEPS: usize = 1_000_000;

/// Smallest step size, relative to the interval, below which the adaptive integrator stops
/// shrinking and accepts the step (guards against a tolerance below rounding). Default `1e-12`.
pub const MIN_STEP_REL: f64 = 1e-12;

/// Settings of the rotation integrator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Integrator {
    /// Largest accepted local error of one step on the orientation quaternion (unitless:
    /// quaternion components, about radians/2). Default `1e-12`.
    pub rotation_tolerance: f64,
}

impl Default for Integrator {
    fn default() -> Self {
        Self {
            rotation_tolerance: 1e-12,
        }
    }
}

/// How a body moves.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BodyKind {
    /// Never moves (floors, walls, ramps): infinite mass.
    Fixed,
    /// Free flight under gravity between collisions, impulses at collisions.
    Dynamic,
    /// Moves on a prescribed path (thesis §2.5) whatever hits it: infinite mass.
    Scripted,
    /// A link of a multibody in the world (thesis ch. 5): its multibody's dynamics move it
    /// and take its collisions. Its pose is the link frame (where its shapes are given, not
    /// its centre of mass), its velocity that of the frame's origin, and it has no mass of its
    /// own here (energies and momenta are the multibody's: [`crate::World::multibody`]).
    Link,
}

/// The mass of a dynamic body, in its principal frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mass {
    /// Mass (kg or the scene's unit).
    pub mass: f64,
    /// Principal moments of inertia about the centre of mass (mass × length²).
    pub moments: DVec3,
}

/// Why a body could not be advanced.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum AdvanceError {
    /// The rotation integrator needed more than [`MAX_ROTATION_STEPS`] steps.
    #[error("the rotation integrator needed more than {MAX_ROTATION_STEPS} steps")]
    TooManySteps,
    /// The state became NaN or infinite.
    #[error("the body's state is no longer finite")]
    NonFinite,
}

/// A body of the world.
#[derive(Clone, Debug)]
pub struct Body {
    /// The body's name (from the scene).
    pub name: String,
    /// Collision shape in the body frame (shared: copies of a world share their shapes).
    pub shape: Arc<Shape>,
    /// How the body moves.
    pub kind: BodyKind,
    /// Body frame → world; the translation is the centre of mass.
    pub pose: Pose,
    /// The body's own frame (as the user placed it) in the body frame: the own frame's pose in
    /// the world is `pose * frame` ([`Body::frame_pose`]).
    pub frame: Pose,
    /// Constant external force through the centre of mass (world; dynamic bodies).
    pub force: DVec3,
    /// Constant external torque (world; dynamic bodies).
    pub torque: DVec3,
    /// Centre-of-mass velocity (world).
    pub velocity: DVec3,
    /// Angular velocity (world).
    pub omega: DVec3,
    /// Mass and principal moments (dynamic bodies only).
    pub mass: Option<Mass>,
    /// Largest distance of a body point from the centre of mass.
    pub r_max: f64,
    /// Per piece, how far rotation about the centre of mass reaches on it (the r of the
    /// rotational term of a time-of-impact bound; zero for a ball about its centre of mass,
    /// see [`Shape::rotational_reach`]).
    pub reach: Vec<f64>,
    /// Per piece that is a solid of revolution ([`Shape::symmetry_axis`]): its axis (unit,
    /// body frame) and the distance of that axis from the centre of mass, for
    /// [`Body::surface_speed`].
    pub revolution: Vec<Option<(DVec3, f64)>>,
    /// Index of the body's material in the world's material table.
    pub material: usize,
    /// The prescribed motion of a scripted body, re-based at the current time.
    pub script: Option<Motion>,
    /// Step size the rotation integrator found last (s), to start the next interval with.
    step_hint: f64,
    /// The contact force an island holds on the body over its current step (world, through
    /// the centre of mass; the switching contact model, `crate::sustained`).
    pub(crate) held_force: DVec3,
    /// The contact torque an island holds on the body over its current step (world).
    pub(crate) held_torque: DVec3,
    /// The loads the heap keys of an island body were computed for (`world/envelope.rs`);
    /// `None`: for its exact load.
    pub(crate) envelope: Option<crate::world::envelope::Envelope>,
    /// The motion bounds the keys of its far pairs were computed for (`world/envelope.rs`);
    /// `None`: none yet, or its far pairs need new keys.
    pub(crate) far: Option<crate::world::envelope::FarEnvelope>,
    /// The world time its pose and velocities refer to: a body moves only when something
    /// reads or changes it (`world/sync.rs`).
    pub(crate) synced: f64,
    /// The world time up to which its box in the broad phase covers its motion
    /// (`world/sync.rs`); −∞ when its motion changed since.
    pub(crate) box_until: f64,
    /// Asleep: at rest in a sleeping island, it does not move until woken.
    pub(crate) asleep: bool,
    /// For a link: its multibody (index in the world) and link.
    pub(crate) link: Option<(u32, impulse_multibody::LinkId)>,
}

impl Body {
    /// A body; `step_hint` starts unset.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn new(
        name: String,
        shape: Shape,
        kind: BodyKind,
        pose: Pose,
        velocity: DVec3,
        omega: DVec3,
        mass: Option<Mass>,
        material: usize,
        script: Option<Motion>,
    ) -> Self {
        let r_max = shape.bounding_radius(DVec3::ZERO);
        let reach = (0..shape.pieces().len())
            .map(|i| shape.rotational_reach(i, DVec3::ZERO).unwrap_or(r_max))
            .collect();
        let revolution = (0..shape.pieces().len())
            .map(|i| {
                shape
                    .symmetry_axis(i)
                    .map(|(axis, at)| (axis, (at - axis * at.dot(axis)).length()))
            })
            .collect();
        Self {
            name,
            shape: Arc::new(shape),
            kind,
            pose,
            frame: Pose::IDENTITY,
            force: DVec3::ZERO,
            torque: DVec3::ZERO,
            velocity,
            omega,
            mass,
            r_max,
            reach,
            revolution,
            material,
            script,
            step_hint: 0.0,
            held_force: DVec3::ZERO,
            held_torque: DVec3::ZERO,
            envelope: None,
            far: None,
            synced: 0.0,
            box_until: f64::NEG_INFINITY,
            asleep: false,
            link: None,
        }
    }

    /// The pose of the body's own frame (as the user placed it) in the world.
    #[must_use]
    pub fn frame_pose(&self) -> Pose {
        self.pose * self.frame
    }

    /// The body's state as a program sees it: its own frame, velocities, centre of mass.
    #[must_use]
    pub fn state(&self) -> crate::world::BodyState {
        let frame = self.frame_pose();
        crate::world::BodyState {
            position: frame.translation,
            rotation: frame.rotation,
            velocity: self.velocity,
            omega: self.omega,
            com: self.pose.translation,
        }
    }

    /// The pose of the body frame (the one its shape is in) when its state is `state`:
    /// the inverse of [`Body::state`]'s frame.
    #[must_use]
    pub fn pose_of(&self, state: &crate::world::BodyState) -> Pose {
        Pose::new(state.rotation, state.position) * self.frame.inverse()
    }

    /// Whether the body is one smooth convex piece (a sphere or an ellipsoid): turning it
    /// brings no feature toward anything that its point of contact does not already show.
    /// Against a convex piece it has one support point, whose normal speed is the contact's
    /// own, so only the curvature of its motion escapes a step's linear prediction
    /// (`world/hold.rs`).
    #[must_use]
    pub fn is_smooth(&self) -> bool {
        self.smooth_piece().is_some()
    }

    /// The body's one smooth piece, if it is one ([`Body::is_smooth`]).
    fn smooth_piece(&self) -> Option<&impulse_collide::shape::Piece> {
        use impulse_collide::shape::Convex;
        match self.shape.pieces() {
            [piece] if matches!(piece.convex, Convex::Sphere(_) | Convex::Ellipsoid(_)) => {
                Some(piece)
            }
            _ => None,
        }
    }

    /// For a smooth body ([`Body::is_smooth`]) turned to `rotation` (body frame → world): its
    /// support point in the world direction `dir`, less its centre of mass: the lever arm of a
    /// contact on it facing `dir`. `None` for any other body.
    #[must_use]
    pub fn support_arm(&self, rotation: DQuat, dir: DVec3) -> Option<DVec3> {
        use impulse_collide::shape::Convex;
        let piece = self.smooth_piece()?;
        let to_piece = rotation * piece.pose.rotation;
        let local = to_piece.inverse() * dir;
        let x = match &piece.convex {
            Convex::Sphere(b) => b.support(local),
            Convex::Ellipsoid(e) => e.support(local),
            Convex::Polyhedron(_) => return None,
        };
        Some(rotation * piece.pose.transform_point(x))
    }

    /// How fast turning at `omega` (world) can move the body's surface toward anything: over
    /// its pieces, the largest ‖ω‖·r (r the piece's [`Body::reach`]), except that a solid of
    /// revolution turning about its own axis moves nothing (it stays the same set): split ω
    /// into ω∥ along the piece's axis and ω⊥ across it, the piece's surface moves at most
    /// ‖ω⊥‖·r plus |ω∥| times the axis's distance from the centre of mass (that turn carries
    /// the axis round). A wheel rolling turns about its axle: its surface does not approach
    /// the floor.
    #[must_use]
    pub fn surface_speed(&self, omega: DVec3) -> f64 {
        self.reach
            .iter()
            .zip(&self.revolution)
            .map(|(&r, rev)| match rev {
                None => omega.length() * r,
                Some((axis, offset)) => {
                    let (along, across) = self.split_spin(omega, *axis);
                    across * r + along * offset
                }
            })
            .fold(0.0, f64::max)
    }

    /// |ω∥| and ‖ω⊥‖ of `omega` (world) about the body-frame axis `axis`.
    fn split_spin(&self, omega: DVec3, axis: DVec3) -> (f64, f64) {
        let a = self.pose.rotation * axis;
        let along = omega.dot(a);
        (along.abs(), (omega - a * along).length())
    }

    /// The largest rotational reach over the pieces (≤ r_max).
    #[must_use]
    pub fn max_reach(&self) -> f64 {
        self.reach.iter().copied().fold(0.0, f64::max)
    }

    /// The contact force and torque an island holds on the body over its current step (world;
    /// zero outside islands, see [`crate::sustained`]).
    #[must_use]
    pub fn contact_load(&self) -> (DVec3, DVec3) {
        (self.held_force, self.held_torque)
    }

    /// Whether the body sleeps in an island at rest ([`crate::sustained`]).
    #[must_use]
    pub fn is_asleep(&self) -> bool {
        self.asleep
    }

    /// External force plus the contact force an island holds (world).
    fn total_force(&self) -> DVec3 {
        self.force + self.held_force
    }

    /// External torque plus the contact torque an island holds (world).
    pub(crate) fn total_torque(&self) -> DVec3 {
        self.torque + self.held_torque
    }

    /// True for a dynamic (ballistic) body.
    #[must_use]
    pub fn is_dynamic(&self) -> bool {
        self.kind == BodyKind::Dynamic
    }

    /// True for a link of a multibody.
    #[must_use]
    pub fn is_link(&self) -> bool {
        self.kind == BodyKind::Link
    }

    /// True for a body that collisions move: dynamic bodies and multibody links.
    #[must_use]
    pub fn takes_impulses(&self) -> bool {
        self.is_dynamic() || self.is_link()
    }

    /// Inverse mass (0 for fixed and scripted bodies).
    #[must_use]
    pub fn inverse_mass(&self) -> f64 {
        self.mass.map_or(0.0, |m| 1.0 / m.mass)
    }

    /// World inverse inertia tensor `R·I⁻¹·Rᵀ` (zero for fixed and scripted bodies).
    #[must_use]
    pub fn inverse_inertia_world(&self) -> DMat3 {
        match self.mass {
            None => DMat3::ZERO,
            Some(m) => {
                let r = DMat3::from_quat(self.pose.rotation);
                r * DMat3::from_diagonal(m.moments.recip()) * r.transpose()
            }
        }
    }

    /// World inertia tensor `R·I·Rᵀ` (zero for fixed and scripted bodies).
    #[must_use]
    pub fn inertia_world(&self) -> DMat3 {
        match self.mass {
            None => DMat3::ZERO,
            Some(m) => {
                let r = DMat3::from_quat(self.pose.rotation);
                r * DMat3::from_diagonal(m.moments) * r.transpose()
            }
        }
    }

    /// Velocity of the body point at world position `x`: `v + ω × (x − com)`.
    #[must_use]
    pub fn point_velocity(&self, x: DVec3) -> DVec3 {
        self.velocity + self.omega.cross(x - self.pose.translation)
    }

    /// Kinetic energy `½ m v² + ½ ω·Iω` (0 for fixed and scripted bodies).
    #[must_use]
    pub fn kinetic_energy(&self) -> f64 {
        match self.mass {
            None => 0.0,
            Some(m) => {
                0.5 * m.mass * self.velocity.length_squared()
                    + 0.5 * self.omega.dot(self.inertia_world() * self.omega)
            }
        }
    }

    /// Potential energy `−m·g·x` in gravity `g` (0 for fixed and scripted bodies).
    #[must_use]
    pub fn potential_energy(&self, gravity: DVec3) -> f64 {
        self.mass
            .map_or(0.0, |m| -m.mass * gravity.dot(self.pose.translation))
    }

    /// Linear momentum `m v` (zero for fixed and scripted bodies).
    #[must_use]
    pub fn linear_momentum(&self) -> DVec3 {
        self.mass.map_or(DVec3::ZERO, |m| self.velocity * m.mass)
    }

    /// Angular momentum about the world origin `x × m v + I ω`.
    #[must_use]
    pub fn angular_momentum(&self) -> DVec3 {
        match self.mass {
            None => DVec3::ZERO,
            Some(_) => {
                self.pose.translation.cross(self.linear_momentum())
                    + self.inertia_world() * self.omega
            }
        }
    }

    /// The constant acceleration of the centre of mass: gravity plus the external and held
    /// contact force over the mass (gravity alone for fixed and scripted bodies; zero for a
    /// sleeping body).
    #[must_use]
    pub fn acceleration(&self, gravity: DVec3) -> DVec3 {
        if self.asleep {
            return DVec3::ZERO;
        }
        let f = self.total_force();
        match self.mass {
            Some(m) if f != DVec3::ZERO => gravity + f / m.mass,
            _ => gravity,
        }
    }

    /// The motion model the collision detector bounds (thesis §2.3.2 and §2.5): for a dynamic
    /// body, ballistic under its acceleration with the energy bound on ‖ω‖ (eq. 2.5) and the
    /// spin refinement, or, under an external torque, the momentum bound (eq. 2.4) growing
    /// at ‖τ‖/I_min; the script for a scripted one. A body whose ω cannot be bounded (its
    /// state overflows) gets [`Motion::Unbounded`]: it is due now against everything, never
    /// assumed still.
    #[must_use]
    pub fn motion(&self, gravity: DVec3) -> Motion {
        let com = self.pose.translation;
        match self.kind {
            BodyKind::Fixed => Motion::Fixed { com },
            BodyKind::Scripted | BodyKind::Link => self.script.unwrap_or(Motion::Fixed { com }),
            BodyKind::Dynamic if self.asleep => Motion::Fixed { com },
            BodyKind::Dynamic => {
                let Some(m) = self.mass else {
                    return Motion::Unbounded { com };
                };
                let wb = self.pose.rotation.inverse() * self.omega;
                let acc = self.acceleration(gravity);
                let torque = self.total_torque();
                // An island body's keys hold for every load in its envelope
                // (`world/envelope.rs`), which holds its actual load.
                if let Some(e) = self.envelope.filter(|e| e.holds(acc, torque)) {
                    let Ok(ballistic) = impulse_collide::motion::omega_max_momentum(m.moments, wb)
                        .and_then(|w| {
                            Ballistic::new(com, self.velocity, e.accel, w)?
                                .with_acceleration_pad(e.accel_pad)?
                                .with_omega_growth(e.torque_max / m.moments.min_element())
                        })
                    else {
                        return Motion::Unbounded { com };
                    };
                    return Motion::Ballistic(ballistic);
                }
                let torqued = torque != DVec3::ZERO;
                let omega_max = if torqued {
                    impulse_collide::motion::omega_max_momentum(m.moments, wb)
                } else {
                    impulse_collide::motion::omega_max_energy(m.moments, wb)
                };
                let Ok(ballistic) = omega_max
                    .and_then(|w| Ballistic::new(com, self.velocity, acc, w))
                    .and_then(|b| {
                        if torqued {
                            b.with_omega_growth(torque.length() / m.moments.min_element())
                        } else {
                            Ok(b)
                        }
                    })
                else {
                    return Motion::Unbounded { com };
                };
                if torqued {
                    return Motion::Ballistic(ballistic);
                }
                // The spin refinement (a top spinning about the contact normal), when the
                // angular acceleration bound exists.
                let alpha = impulse_collide::motion::alpha_max_torque_free(m.moments, wb).ok();
                Motion::Ballistic(
                    alpha
                        .and_then(|a| ballistic.with_spin(self.omega, a).ok())
                        .unwrap_or(ballistic),
                )
            }
        }
    }

    /// Applies the impulse `p` (world) at world point `x`: `Δv = p/m`, `ΔL = (x − com) × p`.
    /// No effect on fixed and scripted bodies.
    pub fn apply_impulse(&mut self, p: DVec3, x: DVec3) {
        if let Some(m) = self.mass {
            self.velocity += p / m.mass;
            let dl = (x - self.pose.translation).cross(p);
            self.omega += self.inverse_inertia_world() * dl;
        }
    }

    /// Moves the body `dt` (s) ahead in gravity `gravity`.
    ///
    /// # Errors
    /// [`AdvanceError`] when the state becomes non-finite or the integrator takes too many
    /// steps.
    pub fn advance(
        &mut self,
        dt: f64,
        gravity: DVec3,
        integrator: &Integrator,
    ) -> Result<(), AdvanceError> {
        if dt <= 0.0 {
            return Ok(());
        }
        match self.kind {
            // A link is moved by its multibody (the world's hybrid step).
            BodyKind::Fixed | BodyKind::Link => {}
            BodyKind::Scripted => {
                if let Some(script) = self.script {
                    let com = script.com_at(dt);
                    let mut rotation = self.pose.rotation;
                    if let Motion::Spinner(s) = script {
                        rotation = (s.rotation_over(dt) * rotation).normalize();
                    }
                    self.pose = Pose::new(rotation, com);
                    self.velocity = script.com_velocity_at(dt);
                    self.script = Some(script.advance(dt).map_err(|_| AdvanceError::NonFinite)?);
                }
            }
            BodyKind::Dynamic if self.asleep => {}
            BodyKind::Dynamic => {
                let acc = self.acceleration(gravity);
                let com = self.pose.translation + self.velocity * dt + acc * (0.5 * dt * dt);
                self.velocity += acc * dt;
                let rotation = self.rotate(dt, integrator)?;
                self.pose = Pose::new(rotation, com);
            }
        }
        if self.pose.is_finite() && self.velocity.is_finite() && self.omega.is_finite() {
            Ok(())
        } else {
            Err(AdvanceError::NonFinite)
        }
    }

    /// Rotation over `dt` under the body's constant torque (torque-free when zero); updates ω
    /// and returns the new orientation.
    fn rotate(&mut self, dt: f64, integrator: &Integrator) -> Result<DQuat, AdvanceError> {
        let Some(m) = self.mass else {
            return Ok(self.pose.rotation);
        };
        let q0 = self.pose.rotation;
        let tau = self.total_torque();
        if self.omega == DVec3::ZERO && tau == DVec3::ZERO {
            return Ok(q0);
        }
        let (lo, hi) = (m.moments.min_element(), m.moments.max_element());
        if hi - lo <= ISOTROPIC_INERTIA_REL * hi {
            if tau == DVec3::ZERO {
                // ω is constant: exact rotation.
                return Ok((DQuat::from_scaled_axis(self.omega * dt) * q0).normalize());
            }
            // ω changes linearly: the Magnus expansion (`rotation.rs`).
            let b = tau / (0.5 * (lo + hi));
            let (q, omega) =
                isotropic_with_torque(q0, self.omega, b, dt, integrator.rotation_tolerance)?;
            self.omega = omega;
            return Ok(q);
        }
        if tau == DVec3::ZERO
            && let Some((axis, i_s, i_p)) = symmetry_axis(m.moments)
        {
            let l = self.inertia_world() * self.omega;
            let (q, omega) = torque_free_axisymmetric(q0, l, axis, i_s, i_p, dt);
            self.omega = omega;
            return Ok(q);
        }
        if tau == DVec3::ZERO
            && let Some((q, omega)) = torque_free_asymmetric(q0, self.omega, m.moments, dt)
        {
            self.omega = omega;
            return Ok(q);
        }
        self.rotate_numerically(dt, integrator, m, tau)
    }

    /// [`Body::rotate`] by the adaptive Runge–Kutta integrator (module documentation), for
    /// any principal moments and the constant torque `tau`.
    fn rotate_numerically(
        &mut self,
        dt: f64,
        integrator: &Integrator,
        m: Mass,
        tau: DVec3,
    ) -> Result<DQuat, AdvanceError> {
        let q0 = self.pose.rotation;
        // World angular momentum: L(t) = L₀ + τ·t exactly (constant without torque).
        let inv = m.moments.recip();
        let l0 = self.inertia_world() * self.omega;
        let omega_of = |q: DQuat, t: f64| -> DVec3 {
            let lb = q.inverse() * (l0 + tau * t);
            q * (lb * inv)
        };
        // q̇ = ½ (0, ω) ⊗ q.
        let deriv = |q: DQuat, t: f64| -> DQuat {
            let w = omega_of(q, t);
            DQuat::from_xyzw(w.x, w.y, w.z, 0.0) * q * 0.5
        };
        let rk4 = |q: DQuat, t: f64, h: f64| -> DQuat {
            let k1 = deriv(q, t);
            let k2 = deriv(q + k1 * (0.5 * h), t + 0.5 * h);
            let k3 = deriv(q + k2 * (0.5 * h), t + 0.5 * h);
            let k4 = deriv(q + k3 * h, t + h);
            q + (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (h / 6.0)
        };
        let tol = integrator.rotation_tolerance;
        let h = if self.step_hint > 0.0 {
            self.step_hint
        } else {
            // Start at a tenth of a radian per step.
            let w_end = omega_of(q0, dt).length();
            0.1 / omega_of(q0, 0.0).length().max(w_end).max(f64::MIN_POSITIVE)
        };
        // Local extrapolation (fifth order) on each accepted step.
        let (q, h) = step_doubling(q0, dt, h, f64::INFINITY, tol, rk4, true)?;
        self.step_hint = h;
        self.omega = omega_of(q, dt);
        Ok(q)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The integrator as a reference: a tolerance far below the default's.
    const TIGHT: Integrator = Integrator {
        rotation_tolerance: 1e-14,
    };

    /// How far apart two bodies' orientations are (the largest distance between their body
    /// axes: an angle from a quaternion's acos resolves only about 3e-8 rad) and their ω
    /// (relative to the second's).
    fn apart(a: &Body, b: &Body) -> (f64, f64) {
        let turn = DVec3::AXES
            .iter()
            .map(|&x| (a.pose.rotation * x - b.pose.rotation * x).length())
            .fold(0.0, f64::max);
        (turn, (a.omega - b.omega).length() / b.omega.length())
    }

    /// A random vector in the cube [−1, 1]³.
    fn unit(rng: &mut rand::rngs::Xoshiro256PlusPlus) -> DVec3 {
        use rand::RngExt;
        DVec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        )
    }

    fn brick(omega: DVec3) -> Body {
        let shape = Shape::sphere(1.0).unwrap();
        Body::new(
            "brick".into(),
            shape,
            BodyKind::Dynamic,
            Pose::from_rotation(DQuat::from_rotation_x(0.3) * DQuat::from_rotation_z(0.2)),
            DVec3::new(1.0, 2.0, 3.0),
            omega,
            Some(Mass {
                mass: 2.0,
                moments: DVec3::new(1.0, 10.0, 100.0),
            }),
            0,
            None,
        )
    }

    /// Torque-free rotation of an asymmetric body (inertia 1:10:100, ω near the unstable
    /// middle axis): world angular momentum is conserved to rounding (constant by
    /// construction, so this checks the ω recovery), kinetic energy to the integrator's
    /// tolerance, and the centre of mass follows the exact parabola.
    #[test]
    fn torque_free_rotation_conserves_momentum_and_energy() {
        let g = DVec3::new(0.0, 0.0, -9.81);
        let mut b = brick(DVec3::new(0.01, 3.0, 0.02));
        let (l0, e0) = (b.inertia_world() * b.omega, b.kinetic_energy());
        let (x0, v0) = (b.pose.translation, b.velocity);
        let integ = Integrator::default();
        let (steps, dt) = (1000, 0.01);
        let mut max_l = 0.0f64;
        let mut max_e = 0.0f64;
        for k in 1..=steps {
            b.advance(dt, g, &integ).unwrap();
            let l = b.inertia_world() * b.omega;
            max_l = max_l.max((l - l0).length() / l0.length());
            // Translational energy changes by gravity; compare rotational energy only.
            let e_rot = 0.5 * b.omega.dot(b.inertia_world() * b.omega);
            let e_rot0 = e0 - 0.5 * 2.0 * v0.length_squared();
            max_e = max_e.max((e_rot - e_rot0).abs() / e_rot0);
            let t = k as f64 * dt;
            let x = x0 + v0 * t + g * (0.5 * t * t);
            assert!((b.pose.translation - x).length() <= 1e-12 * (1.0 + x.length()));
        }
        eprintln!("10 s torque-free (1:10:100): |ΔL|/|L| {max_l:.2e}, |ΔE|/E {max_e:.2e}");
        assert!(max_l < 1e-12, "angular momentum drift {max_l}");
        assert!(max_e < 1e-8, "energy drift {max_e}");
        // The intermediate axis is unstable: the body must actually have tumbled (ω changed
        // direction substantially), or the test would not exercise the integrator.
        let w_body = b.pose.rotation.inverse() * b.omega;
        assert!(w_body.y.abs() < 2.9, "no tumbling: ω_body {w_body}");
    }

    /// An axisymmetric body (I1 = I2) against Euler's equations' solution: in the body frame
    /// ω precesses about the symmetry axis at rate Ω = (I3 − I1)/I1 · ω3.
    #[test]
    fn axisymmetric_precession_matches_closed_form() {
        let (i1, i3) = (2.0, 5.0);
        let mut b = brick(DVec3::ZERO);
        b.mass = Some(Mass {
            mass: 1.0,
            moments: DVec3::new(i1, i1, i3),
        });
        b.pose = Pose::IDENTITY;
        let w0 = DVec3::new(0.7, 0.0, 1.3);
        b.omega = w0;
        let t = 3.0;
        b.advance(t, DVec3::ZERO, &Integrator::default()).unwrap();
        let wb = b.pose.rotation.inverse() * b.omega;
        let rate = (i3 - i1) / i1 * w0.z;
        // Euler's equations: ω̇1 = −Ω ω2, ω̇2 = Ω ω1 with Ω = (I3−I1)/I1·ω3 … sign: body frame
        // ω1' = (I2 − I3)/I1 ω2 ω3 = −rate·ω2, ω2' = (I3 − I1)/I2 ω3 ω1 = rate·ω1.
        let expected = DVec3::new(w0.x * (rate * t).cos(), w0.x * (rate * t).sin(), w0.z);
        assert!(
            (wb - expected).length() < 1e-9,
            "ω_body {wb} vs closed form {expected}"
        );
    }

    /// The closed form of the free symmetric top against the numerical integrator (forced,
    /// at a tolerance of 1e-14 per step) on random axisymmetric bodies — the symmetry axis
    /// any of the three, oblate and prolate, any orientation and spin — over several calls
    /// of random length: the orientations agree to 1e-8 and ω to 1e-8 relative, and the
    /// closed form keeps the world angular momentum and the kinetic energy to 1e-12 relative
    /// over 200 calls. Three distinct or three equal moments have no symmetry axis.
    #[test]
    fn axisymmetric_closed_form_matches_the_integrator_and_conserves() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(7);
        let tight = TIGHT;
        for case in 0..40 {
            let axis = case % 3;
            let (i_p, i_s) = (rng.random_range(0.5..2.0), rng.random_range(0.2..4.0));
            let mut moments = DVec3::splat(i_p);
            moments[axis] = i_s;
            assert_eq!(symmetry_axis(moments).map(|(k, _, _)| k), Some(axis));
            let mut b = brick(unit(&mut rng) * rng.random_range(0.5..20.0));
            b.mass = Some(Mass { mass: 1.0, moments });
            b.pose = Pose::from_rotation(DQuat::from_scaled_axis(unit(&mut rng) * 3.0));
            let mut numeric = b.clone();
            let (l0, e0) = (b.angular_momentum(), b.kinetic_energy());
            for _ in 0..200 {
                let dt = rng.random_range(1e-4..2e-2);
                b.advance(dt, DVec3::ZERO, &Integrator::default()).unwrap();
                let m = numeric.mass.unwrap();
                let q = numeric
                    .rotate_numerically(dt, &tight, m, DVec3::ZERO)
                    .unwrap();
                numeric.pose = Pose::new(q, numeric.pose.translation + numeric.velocity * dt);
                let l = b.angular_momentum();
                assert!(
                    (l - l0).length() <= 1e-12 * l0.length(),
                    "L drift {}",
                    (l - l0).length()
                );
                let e = b.kinetic_energy();
                assert!((e - e0).abs() <= 1e-12 * e0, "energy drift {}", e - e0);
            }
            let (turn, dw) = apart(&b, &numeric);
            assert!(
                turn < 1e-8 && dw < 1e-8,
                "case {case}: turned {turn:e} apart, ω {dw:e}"
            );
        }
        assert!(symmetry_axis(DVec3::new(1.0, 2.0, 3.0)).is_none());
        assert!(symmetry_axis(DVec3::splat(0.4)).is_none());
    }

    /// Equal principal moments: constant ω, exact rotation by |ω|·t about ω.
    #[test]
    fn isotropic_body_rotates_exactly() {
        let mut b = brick(DVec3::new(0.0, 0.0, 2.0));
        b.mass = Some(Mass {
            mass: 1.0,
            moments: DVec3::splat(0.4),
        });
        b.pose = Pose::IDENTITY;
        b.advance(0.5, DVec3::ZERO, &Integrator::default()).unwrap();
        let angle = b.pose.rotation.angle_between(DQuat::IDENTITY);
        assert!((angle - 1.0).abs() < 1e-14);
    }

    /// An impulse changes linear momentum by p and angular momentum about the origin by x × p.
    #[test]
    fn impulse_changes_momentum_by_the_impulse() {
        let mut b = brick(DVec3::new(0.3, -0.2, 0.1));
        let (p0, l0) = (b.linear_momentum(), b.angular_momentum());
        let (p, x) = (DVec3::new(0.5, -1.0, 2.0), DVec3::new(0.2, 2.5, 3.1));
        b.apply_impulse(p, x);
        assert!((b.linear_momentum() - p0 - p).length() < 1e-14);
        assert!((b.angular_momentum() - l0 - x.cross(p)).length() < 1e-12);
    }

    /// The surface speed of a body whose pieces are an ellipsoid of revolution (its centre off
    /// the centre of mass, turned) and a three-axis ellipsoid bounds the rate at which its
    /// support function h(d) = max d·x over the shape changes under turning at ω, measured
    /// by turning the body through ω·dt (finite differences over 64 directions), for random
    /// ω; and turning about the wheel's own axis through its centre moves nothing but the
    /// offset: the bound is |ω∥|·d there.
    #[test]
    fn surface_speed_bounds_how_fast_the_support_moves() {
        use impulse_collide::shape::Convex;
        use impulse_geom::Ellipsoid;
        let wheel_pose = Pose::new(
            DQuat::from_rotation_x(1.1) * DQuat::from_rotation_z(0.4),
            DVec3::new(0.03, -0.01, 0.02),
        );
        let shape = Shape::compound(vec![(
            wheel_pose,
            Convex::Ellipsoid(Ellipsoid::new(DVec3::new(0.06, 0.06, 0.02)).unwrap()),
        )])
        .unwrap();
        let pose = Pose::from_rotation(DQuat::from_rotation_y(0.7));
        let at_rest = |name: &str, shape: Shape| {
            Body::new(
                name.into(),
                shape,
                BodyKind::Dynamic,
                pose,
                DVec3::ZERO,
                DVec3::ZERO,
                None,
                0,
                None,
            )
        };
        let body = at_rest("wheel", shape.clone());
        assert!(body.revolution[0].is_some());
        let support = |pose: &Pose, d: DVec3| -> f64 {
            shape
                .pieces()
                .iter()
                .map(|p| {
                    let world = *pose * p.pose;
                    let local = world.rotation.inverse() * d;
                    let x = match &p.convex {
                        Convex::Ellipsoid(e) => e.support(local),
                        _ => unreachable!("ellipsoids only"),
                    };
                    d.dot(world.transform_point(x))
                })
                .fold(f64::NEG_INFINITY, f64::max)
        };
        let dirs: Vec<DVec3> = (0..64)
            .map(|k| {
                let (t, p) = (
                    k as f64 * 0.618 * std::f64::consts::TAU,
                    (k as f64 + 0.5) / 64.0,
                );
                let z = 1.0 - 2.0 * p;
                let r = (1.0 - z * z).sqrt();
                DVec3::new(r * t.cos(), r * t.sin(), z)
            })
            .collect();
        let dt = 1e-7;
        let axis = pose.rotation * body.revolution[0].unwrap().0;
        let mut spins: Vec<DVec3> = (0..40)
            .map(|k| {
                let f = k as f64;
                DVec3::new((1.3 * f).sin(), (2.1 * f).cos(), (0.7 * f).sin()) * (1.0 + f)
            })
            .collect();
        spins.push(axis * 10.0);
        let mut tight_about_axis = 0.0_f64;
        for omega in spins {
            let bound = body.surface_speed(omega);
            let turned = Pose::new(
                DQuat::from_scaled_axis(omega * dt) * pose.rotation,
                pose.translation,
            );
            let rate = dirs
                .iter()
                .map(|&d| ((support(&turned, d) - support(&pose, d)) / dt).abs())
                .fold(0.0, f64::max);
            assert!(
                rate <= bound * (1.0 + 1e-4) + 1e-9,
                "ω {omega:?}: support moves at {rate}, bound {bound}"
            );
            if omega == axis * 10.0 {
                tight_about_axis = bound;
            }
        }
        // About its own axis the wheel moves only by its offset.
        let offset = body.revolution[0].unwrap().1;
        assert!(offset > 0.01);
        assert!((tight_about_axis - 10.0 * offset).abs() < 1e-12);
        assert!(tight_about_axis < 0.5 * 10.0 * body.reach[0]);
        // A three-axis ellipsoid is no solid of revolution: ‖ω‖·r.
        let lump = at_rest(
            "lump",
            Shape::ellipsoid(DVec3::new(0.01, 0.02, 0.03)).unwrap(),
        );
        assert!(lump.revolution[0].is_none());
        let w = DVec3::new(1.0, -2.0, 0.5);
        assert_eq!(lump.surface_speed(w), w.length() * lump.reach[0]);
    }

    /// A body with equal moments under a torque along its spin turns about a fixed axis by
    /// |ω₀|·t + ½·(|τ|/I)·t² (and ω = ω₀ + τ·t/I): exact, checked over 100 calls of random
    /// length to 1e-12 on the quaternion; a torque against the spin reverses it on the way.
    #[test]
    fn an_isotropic_body_under_torque_along_its_spin_turns_by_the_exact_angle() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(3);
        for (spin, torque) in [(40.0, 7.0), (40.0, -30.0), (0.5, 200.0)] {
            let axis = DVec3::new(0.3, -0.5, 0.8).normalize();
            let i = 0.02;
            let mut b = brick(axis * spin);
            b.mass = Some(Mass {
                mass: 1.0,
                moments: DVec3::splat(i),
            });
            b.torque = axis * torque;
            let q0 = b.pose.rotation;
            let mut t = 0.0;
            for _ in 0..100 {
                let dt = rng.random_range(1e-4..5e-3);
                b.advance(dt, DVec3::ZERO, &Integrator::default()).unwrap();
                t += dt;
                let angle = spin * t + 0.5 * torque / i * t * t;
                let exact = DQuat::from_axis_angle(axis, angle) * q0;
                let off = (b.pose.rotation - exact)
                    .length()
                    .min((b.pose.rotation + exact).length());
                assert!(
                    off < 1e-12,
                    "spin {spin}, torque {torque}: {off:e} at t = {t}"
                );
                let w = axis * (spin + torque / i * t);
                assert!((b.omega - w).length() < 1e-12 * w.length().max(1.0));
            }
        }
    }

    /// A body with equal moments under a torque across its spin (a ball rolling under its
    /// friction torque): the Magnus steps against the Runge–Kutta integrator at a tolerance of
    /// 1e-14 (the independent reference), 40 random cases of 100 calls each: the body axes
    /// agree to 1e-10 (7e-12 at worst, measured) and ω to rounding. With the third term,
    /// −(h³/12)·a × b, dropped or of the wrong sign they part by more than 1e-9: the step
    /// control, which compares the expansion with itself, hides some of the error but not
    /// that much.
    #[test]
    fn an_isotropic_body_under_torque_matches_the_integrator() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(11);
        let tight = TIGHT;
        for case in 0..40 {
            let i = rng.random_range(0.01..1.0);
            let mut b = brick(unit(&mut rng) * rng.random_range(1.0..200.0));
            b.mass = Some(Mass {
                mass: 1.0,
                moments: DVec3::splat(i),
            });
            b.torque = unit(&mut rng) * (i * rng.random_range(10.0..500.0));
            b.pose = Pose::from_rotation(DQuat::from_scaled_axis(unit(&mut rng) * 3.0));
            let mut numeric = b.clone();
            for _ in 0..100 {
                let dt = rng.random_range(1e-4..2e-3);
                b.advance(dt, DVec3::ZERO, &Integrator::default()).unwrap();
                let m = numeric.mass.unwrap();
                let tau = numeric.torque;
                let q = numeric.rotate_numerically(dt, &tight, m, tau).unwrap();
                numeric.pose = Pose::new(q, numeric.pose.translation + numeric.velocity * dt);
            }
            let (turn, dw) = apart(&b, &numeric);
            assert!(
                turn < 1e-10 && dw < 1e-12,
                "case {case}: turned {turn:e} apart, ω {dw:e}"
            );
        }
    }
}
