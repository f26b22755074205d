//! The energy of a world computed from its state, and how much a world without actuation may
//! gain.
//!
//! **Bound.** Gravity is conservative; restitution e ≤ 1 and friction take energy away
//! (Stronge's law, thesis §3.3, Assumption 2); joint damping, friction and limit stops with
//! e ≤ 1 do too. Two mechanisms add energy by design, both bounded by lifting bodies through
//! the contact envelope:
//! - a boosted microcollision (thesis §3.5) adds at most the potential energy of its depth in
//!   the envelope along gravity, m·|g|·ε_c (`impulse_response::MicrocollisionParams::
//!   rebound_limit`);
//! - the switching model's stabilisation (`impulse_sim::sustained`) draws a held contact to its
//!   rest gap g_r < ε_c, pushing or pulling at most at β·ε_c/h.
//!
//! A body can be lifted so by every body beneath it, so with N bodies that take impulses each
//! body i may gain m_i·|g|·(N + 1)·ε_c of potential energy (the + 1: a body placed up to ε_c
//! into another is pushed out) and ½·m_i·(β·ε_c/h)² of kinetic energy. On top of that,
//! [`ENERGY_SLACK_REL`] of the energy's scale covers rounding.
//!
//! Sources this bound does not cover (the scene checks skip the energy assertion for them,
//! and report it): scripted bodies (a spinner or oscillator does work on what it touches),
//! high-level controllers and joint controllers (they do work by design), joint springs (their
//! potential energy is not in the world's), and a rotation integrator coarser than
//! [`MAX_ROTATION_TOLERANCE`] (its drift is not rounding).

use glam::{DMat3, DVec3};
use impulse_sim::World;

/// Rounding slack of the energy bound, relative to the energy's scale (the initial kinetic
/// energy plus Σ m·|g|·(|x| + ε_c)): the exact parabolas of free flight and the step-doubling
/// RK4 of rotation at [`MAX_ROTATION_TOLERANCE`] keep energy to far better than this over the
/// checks' few hundred steps; a multibody's adaptive RK4 (relative tolerance 1e-8 per step)
/// too. `1e-6`.
pub const ENERGY_SLACK_REL: f64 = 1e-6;

/// Largest rotation tolerance (the scene's `accuracy.rotation_tolerance`) under which energy
/// is checked: a coarser integrator drifts by its tolerance per step, which is not a source
/// this bound knows. `1e-9` (the default is 1e-12).
pub const MAX_ROTATION_TOLERANCE: f64 = 1e-9;

/// Energy of the world now: kinetic plus gravitational potential energy of every dynamic body
/// (computed here from each body's mass, principal moments, pose and velocities: ½·m·v² +
/// ½·ω·(R·I·Rᵀ)·ω − m·g·x), plus the multibodies' (the world's own sum, which is computed from
/// their joint states).
#[must_use]
pub fn world_energy(world: &World) -> f64 {
    let g = world.gravity();
    let mut own = 0.0;
    let mut theirs = 0.0;
    for (_, b) in world.bodies() {
        theirs += b.kinetic_energy() + b.potential_energy(g);
        if let (true, Some(m)) = (b.is_dynamic(), b.mass) {
            let r = DMat3::from_quat(b.pose.rotation);
            let inertia = r * DMat3::from_diagonal(m.moments) * r.transpose();
            own += 0.5 * m.mass * b.velocity.length_squared()
                + 0.5 * b.omega.dot(inertia * b.omega)
                - m.mass * g.dot(b.pose.translation);
        }
    }
    // The multibodies' energy: what the world counts beyond its bodies'.
    let multibodies = world.kinetic_energy() + world.potential_energy() - theirs;
    own + multibodies
}

/// The energy a world starts with and how much above it the check allows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EnergyBound {
    /// Energy at the start ([`world_energy`]).
    pub start: f64,
    /// Largest allowed rise above `start` (module documentation).
    pub allowed: f64,
}

impl EnergyBound {
    /// The bound of `world` as it is now, with the stabilisation settings it runs with.
    #[must_use]
    pub fn of(world: &World, settings: &impulse_sim::SustainedSettings) -> Self {
        let g = world.gravity().length();
        let eps = world.collision_epsilon();
        let push = settings.stabilisation * eps / settings.step;
        let movers: Vec<(f64, DVec3)> = world
            .bodies()
            .filter(|(_, b)| b.takes_impulses())
            .map(|(_, b)| (b.mass.map_or(0.0, |m| m.mass), b.pose.translation))
            .collect();
        let n = movers.len() as f64;
        let start = world_energy(world);
        let lift: f64 = movers
            .iter()
            .map(|(m, _)| m * g * (n + 1.0) * eps + 0.5 * m * push * push)
            .sum();
        let scale = world.kinetic_energy()
            + movers
                .iter()
                .map(|(m, x)| m * g * (x.length() + eps))
                .sum::<f64>()
            + start.abs();
        Self {
            start,
            allowed: lift + ENERGY_SLACK_REL * scale,
        }
    }

    /// Checks the energy `now` at time `t`.
    ///
    /// # Errors
    /// [`crate::Violation::EnergyGained`] with the numbers.
    pub fn check(&self, now: f64, t: f64) -> Result<(), crate::Violation> {
        if now - self.start > self.allowed {
            return Err(crate::Violation::EnergyGained(format!(
                "at t = {t} s the energy is {now:e} J, {:e} J above its start {:e} J \
                 (allowed {:e} J)",
                now - self.start,
                self.start,
                self.allowed
            )));
        }
        Ok(())
    }
}
