//! Sustained contact as constraints: the contact impulses of an island of bodies over one time
//! step, by projected Gauss–Seidel with the exact Coulomb cone \[not in seed: the thesis's
//! §8.1 names constraint-based resting contact as the remedy for microcollision trains; this is
//! the velocity-level time-stepping formulation of Stewart–Trinkle and Anitescu–Potra, solved as
//! Box2D, rapier and Bullet do, with the tangential step chosen so that the converged friction
//! is exactly Coulomb's\].
//!
//! The caller advances the island's velocities by the non-contact forces over a step of length
//! h (gravity, loads), then calls [`solve_contacts`]: it finds, for every contact, an impulse
//! p = (p_t1, p_t2, p_n) in its contact frame ([`ContactFrame`]: z along the normal, from body
//! 2 to body 1) such that, with u the relative contact velocity after all impulses:
//! - **non-penetration with complementarity**: p_n ≥ 0, u_n ≥ u_target, and p_n = 0 wherever
//!   u_n > u_target ([`Contact::target_normal_velocity`], e.g. 0 for resting, a small positive
//!   speed to close a penetration: position-level stabilisation is the caller's choice);
//! - **the Coulomb cone, exactly**: ‖p_t‖ ≤ μ·p_n; sticking (u_t = 0) inside the cone, and
//!   sliding only on its boundary with p_t = −μ p_n u_t/‖u_t‖ (maximal dissipation): a disk,
//!   not the pyramid of a box-friction solver, so the friction force does not depend on how the
//!   tangent axes are turned.
//!
//! ## The iteration
//! Contacts are visited in order; at each, the normal impulse is updated exactly along its own
//! row, `Δp_n = (u_target − u_n)/K_nn`, clamped so p_n ≥ 0 (K the collision matrix of the
//! pair, eq. 3.4); then the tangential impulse by one projected-gradient step,
//! `p_t ← Π_{‖p_t‖ ≤ μ p_n}(p_t − u_t/λ)`, λ the largest eigenvalue of K's tangential 2 × 2
//! block. With λ (rather than the inverse of the block, as a block solver would use) a fixed
//! point has p_t anti-parallel to u_t, which is Coulomb's law. With targets 0 the solution
//! never adds kinetic energy: with P the stacked impulses, W the island's Delassus matrix
//! (u_f = u₀ + W·P; its diagonal blocks are the pairs' K) and u₀, u_f the contact velocities
//! before and after, ΔT = P·u₀ + ½PᵀWP = P·u_f − ½PᵀWP, and P·u_f = Σ p_n u_n + p_t·u_t ≤ 0
//! by complementarity and the cone. (A single sweep may add a little, where a smaller normal
//! impulse shrinks the disk under a friction impulse.) A [`Contact::velocity_bias`] b moves
//! the law to u + b: the bound becomes P·u_f ≤ −P·b.
//! It stops when no impulse update changed a contact velocity by more than
//! [`SolverSettings::tolerance`], or after [`SolverSettings::max_iterations`] sweeps.
//!
//! **Jumps** ([`SolverSettings::direct_after`]): after that many sweeps without convergence,
//! one jump toward the solution: the patch jump (`patch.rs`) solves every patch of three or
//! more sticking contacts between two bodies as one wrench about its centre — six unknowns
//! for six relative degrees of freedom, where its corners have twelve and a near-null space —
//! with every contact sticking, and spreads each wrench over its corners by least norm; it
//! carries a stack's load through all its patches at once, where a sweep carries it one
//! patch further. An island it cannot take gets the direct solve on the active set
//! (`direct.rs`). Either only moves the iterate; the sweeps that follow enforce the laws.
//!
//! **Acceleration** (`anderson.rs`, [`SolverSettings::acceleration`]): between sweeps, the
//! last few iterates' residuals propose an impulse vector their linear model says is nearer
//! the fixed point; it is projected onto the cones and the velocities rebuilt from it, and the
//! next sweep judges it (a worse sweep drops the history; a solve that stops making progress
//! goes on with plain sweeps). The stopping test and the fixed point are the plain sweep's, so
//! a converged solve obeys the same laws (test
//! `random_islands_obey_complementarity_coulomb_and_dissipation` runs both); a cold stack of
//! 8 converges in 194 sweeps instead of 10 855 (test
//! `acceleration_reaches_the_stack_solution_in_fewer_sweeps`).
//!
//! **Warm starting**: the impulses in [`Contact::impulse`] on entry (e.g. last step's, carried
//! over by the manifold's feature ids) are projected onto the cone and applied before the
//! first sweep; on return they hold the solution.
//!
//! **Cost**: one sweep is O(number of contacts): each contact's update reads its velocity and
//! applies its impulse through maps precomputed once per solve (the contact frame, r × axis
//! and I⁻¹(r × axis) per body side), about 60 multiplications, with one update of the
//! bodies' velocities for the normal and friction impulses together (the velocities are
//! linear in the impulse); a square root and a division only where friction reaches the
//! disk's rim (`cargo bench -p impulse-response --bench contact`, one run: a warm step of
//! the stack of 8 took 18.7 µs against 34.0 µs with a cross product and an inertia product
//! per body per update and separate normal and friction updates, the stack of 16 308 µs
//! against 795 µs). The number of sweeps needed grows with the island's height (a load
//! travels one contact per sweep in the worst order), which warm starting across steps hides
//! for islands at rest.
//!
//! **Jointed systems** ([`solve_island`], `system.rs`): bodies of an island may be links of
//! a mechanism (a multibody), given as the link's Jacobian and the response M⁻¹Jᵀ of the
//! mechanism's generalized velocity; their contacts read and change that velocity, with the
//! same sweep. The solver does not know how those were computed (thesis §5.3's impulse-space
//! articulated-body recursion, in `impulse-multibody`, for the world's multibodies).
//!
//! **Must not know** how the contacts were found (manifolds), the bodies' shapes, or time
//! stepping: it takes velocities, mass properties and contact points, and returns impulses.

use glam::{DMat3, DVec2, DVec3};

use crate::{Body, ContactFrame, ResponseError, collision_matrix_world};

mod anderson;
mod direct;
mod patch;
#[cfg(test)]
mod patch_tests;
mod system;
#[cfg(test)]
mod system_tests;
#[cfg(test)]
mod tests;

pub use anderson::{MIXING_RIDGE, PROGRESS, STALL_SWEEPS_PER_MEMORY};
pub use direct::{DENSE_UP_TO, LAW_SLACK, MAX_ROUNDS, REGULARISATION};
pub use patch::{
    JUMP_DIVERGED, MIN_PATCHES as PATCH_MIN, PATCH_MAX_UNKNOWNS, PATCH_SPREAD_REL,
    STICK_MARGIN as PATCH_STICK_MARGIN,
};
use system::{LinkRows, Membership};
pub use system::{Member, System};

/// One body of an island, as the solver sees it: mass properties, centre of mass and velocity,
/// all in world axes. The solver changes `velocity` and `omega` in place.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IslandBody {
    /// Mass properties ([`Body::Fixed`] for an immovable body).
    pub body: Body,
    /// Centre of mass (world).
    pub com: DVec3,
    /// Velocity of the centre of mass (world).
    pub velocity: DVec3,
    /// Angular velocity (world).
    pub omega: DVec3,
}

/// One contact point between body `body1` and body `body2` (or the fixed world).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact {
    /// Index of body 1 in the island (receives +p).
    pub body1: usize,
    /// Index of body 2 (receives −p); `None` for the fixed world.
    pub body2: Option<usize>,
    /// The contact point (world).
    pub point: DVec3,
    /// Contact normal (world), pointing from body 2 towards body 1; normalised by the solver.
    pub normal: DVec3,
    /// Coulomb friction coefficient μ ≥ 0.
    pub friction: f64,
    /// The normal relative velocity the contact may not go below, u_n ≥ this (0 for resting
    /// contact; positive to push an overlap apart).
    pub target_normal_velocity: f64,
    /// A relative velocity (world) added to the contact's before its law is applied: the
    /// solve makes u + this obey non-penetration and Coulomb's law, and friction opposes the
    /// slip u + this. Zero for the plain law; a stepper whose contact velocities are measured
    /// with lever arms that turn over its step passes the change those arms miss.
    pub velocity_bias: DVec3,
    /// The lever arms (world) from body 1's and body 2's centres of mass to where the
    /// impulse acts on each; `None`: `point` less each centre. A stepper that holds the
    /// impulse as a constant load over its step passes the arms at the middle of the step,
    /// about which the load's torque is the step's mean to second order.
    pub lever_arms: Option<(DVec3, DVec3)>,
    /// Accumulated impulse (p_t1, p_t2, p_n) in the contact frame
    /// ([`ContactFrame::from_normal`] of `normal`): the warm start on entry, the solution on
    /// return.
    pub impulse: DVec3,
}

/// Settings of [`solve_contacts`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolverSettings {
    /// Largest number of sweeps over the contacts (default 1000).
    pub max_iterations: usize,
    /// Convergence tolerance, a speed (length/time): the solve stops when a whole sweep
    /// changed no contact velocity by more than this (default 1e-9 m/s).
    pub tolerance: f64,
    /// After this many sweeps without convergence, one jump toward the solution, then
    /// sweeps again (once per solve): the patch jump (`patch.rs`: the island's patches of
    /// three or more sticking contacts between two bodies, each solved as one wrench, all at
    /// once; tilted stacks) when the island has [`PATCH_MIN`] patches or more, else a direct
    /// solve on the active set the sweeps found (`direct.rs`: tall stacks; a failed attempt
    /// costs up to 2·[`MAX_ROUNDS`] factorisations). `None` (the default): sweeps only.
    pub direct_after: Option<usize>,
    /// Anderson acceleration of the sweeps (`anderson.rs`): how many past iterates mix into
    /// each proposal; 0 for plain sweeps. Not taken for islands with [`System`]s. Default
    /// [`DEFAULT_ACCELERATION`].
    pub acceleration: usize,
}

impl Default for SolverSettings {
    fn default() -> Self {
        Self {
            max_iterations: DEFAULT_MAX_ITERATIONS,
            tolerance: DEFAULT_TOLERANCE,
            direct_after: None,
            acceleration: DEFAULT_ACCELERATION,
        }
    }
}

/// Default [`SolverSettings::acceleration`]: five past iterates. On the 216-box pile
/// (`cargo xtask bench --scale`, one run each) memories of 3, 5 and 8 cut the sweeps from
/// 2.20 million to 1.06, 0.70 and 0.65 million, the solves stopped at the cap from 8682 to
/// 3385, 1872 and 1520; five is where the sweeps stop falling faster than a proposal's
/// cost grows.
pub const DEFAULT_ACCELERATION: usize = 5;

/// Default [`SolverSettings::max_iterations`].
pub const DEFAULT_MAX_ITERATIONS: usize = 1000;

/// Default [`SolverSettings::tolerance`], m/s: far below any speed a resting or sliding
/// contact is judged by, far above rounding of velocities of order 1 m/s.
pub const DEFAULT_TOLERANCE: f64 = 1e-9;

/// What a solve did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolveReport {
    /// Sweeps performed.
    pub iterations: usize,
    /// Largest contact-velocity change of the last sweep (length/time).
    pub residual: f64,
    /// Whether the residual fell to the tolerance.
    pub converged: bool,
    /// Whether a direct solve on the active set was taken ([`SolverSettings::direct_after`]).
    pub direct: bool,
    /// Whether a direct solve was tried (taken or not): the patch jump or, when that was not
    /// taken, the active-set solve.
    pub direct_tried: bool,
    /// Whether the patch jump (`patch.rs`: every patch of three or more contacts between two
    /// bodies as one wrench, all sticking) was taken at [`SolverSettings::direct_after`], in
    /// place of the active-set solve.
    pub jumped: bool,
}

/// A contact's precomputed geometry: frame, offsets, collision matrix, and the maps between
/// its impulse and its bodies' velocities (so that a sweep's update is a few matrix–vector
/// products, with no cross product or inertia product).
struct Row {
    frame: ContactFrame,
    r1: DVec3,
    r2: DVec3,
    /// K_nn of the contact frame.
    k_nn: f64,
    /// 1/K_nn.
    inv_k_nn: f64,
    /// Largest eigenvalue of K's tangential block.
    k_t: f64,
    /// 1/k_t.
    inv_k_t: f64,
    /// The collision matrix in the contact frame (Δu = K·Δp).
    k: DMat3,
    /// [`Contact::velocity_bias`] in the contact frame.
    bias: DVec3,
    /// Qᵀ: world velocity to the contact frame.
    to_contact: DMat3,
    /// Body 1's side: `(r₁ × Q)ᵀ` (its ω to the contact frame, eq. 3.3's ω × r), and
    /// `I₁⁻¹·(r₁ × Q)` (a contact-frame impulse to its Δω, eq. 3.2; zero for a fixed body).
    side1: Side,
    /// Body 2's side, as body 1's (unused without a body 2).
    side2: Side,
    /// The sides that are links of a [`System`] (their rigid [`Side`]s are a fixed body's,
    /// at rest): boxed, since most rows have none and a sweep reads rows in order.
    links: Option<Box<LinkRows>>,
}

/// One body's side of a [`Row`].
struct Side {
    /// 1/m (zero for a fixed body).
    inverse_mass: f64,
    /// Maps the body's ω to its share of the contact velocity (contact frame): row k is
    /// r × axis k.
    omega_to_contact: DMat3,
    /// Maps a contact-frame impulse to the body's Δω: column k is I⁻¹(r × axis k).
    impulse_to_omega: DMat3,
}

impl Side {
    fn new(body: &Body, r: DVec3, axes: DMat3) -> Self {
        // Column k of `arms` is r × (axis k) (eq. 3.2's r × p for a unit impulse along it).
        let arms = DMat3::from_cols(
            r.cross(axes.x_axis),
            r.cross(axes.y_axis),
            r.cross(axes.z_axis),
        );
        // A fixed body may still move (a scripted one): its ω counts, no impulse moves it.
        let (inverse_mass, impulse_to_omega) = match body {
            Body::Fixed => (0.0, DMat3::ZERO),
            Body::Moving {
                inverse_mass,
                inverse_inertia,
            } => (*inverse_mass, *inverse_inertia * arms),
        };
        Self {
            inverse_mass,
            omega_to_contact: arms.transpose(),
            impulse_to_omega,
        }
    }
}

/// Finds the contact impulses of one step and applies them to the bodies' velocities (see the
/// module documentation).
///
/// # Errors
/// [`ResponseError::InvalidParameter`] for a contact that names a body out of range or the
/// same body twice, a negative or non-finite μ, target or tolerance, or zero iterations;
/// [`ResponseError::NonFinite`] for a non-finite point, velocity or impulse;
/// [`ResponseError::InvalidNormal`] for a zero or non-finite normal;
/// [`ResponseError::NormalUnreachable`] for a contact between two fixed bodies. The bodies
/// and contacts are unchanged on error.
pub fn solve_contacts(
    bodies: &mut [IslandBody],
    contacts: &mut [Contact],
    settings: &SolverSettings,
) -> Result<SolveReport, ResponseError> {
    solve_island(bodies, &mut [], contacts, settings)
}

/// [`solve_contacts`] for an island some of whose bodies are links of jointed [`System`]s
/// (module `system`): their contacts read and change the systems' generalized velocities. The
/// direct solve on the active set ([`SolverSettings::direct_after`]) is not taken when there
/// are systems (its couplings know only rigid bodies).
///
/// # Errors
/// As [`solve_contacts`]; also [`ResponseError::InvalidParameter`] for a member naming a body
/// out of range, twice, or one that is not [`crate::Body::Fixed`], or whose Jacobian or
/// response does not have the system's length, and [`ResponseError::NonFinite`] for a
/// non-finite system velocity, Jacobian or response. Bodies, systems and contacts are
/// unchanged on error.
pub fn solve_island(
    bodies: &mut [IslandBody],
    systems: &mut [System],
    contacts: &mut [Contact],
    settings: &SolverSettings,
) -> Result<SolveReport, ResponseError> {
    let of = system::membership(bodies, systems)?;
    let rows = prepare(bodies, systems, &of, contacts, settings)?;
    // A member's rigid side is a fixed body at rest: its motion is read from its system.
    for (b, m) in bodies.iter_mut().zip(&of) {
        if m.is_some() {
            b.velocity = DVec3::ZERO;
            b.omega = DVec3::ZERO;
        }
    }
    let accelerable = settings.acceleration > 0 && systems.is_empty() && contacts.len() > 1;
    // Warm start: last impulses, projected onto the cone.
    for (c, row) in contacts.iter_mut().zip(&rows) {
        let p_n = c.impulse.z.max(0.0);
        let p_t = clamp_to_disk(DVec2::new(c.impulse.x, c.impulse.y), c.friction * p_n);
        c.impulse = DVec3::new(p_t.x, p_t.y, p_n);
        apply(bodies, c, row, c.impulse);
        if let Some(links) = &row.links {
            links.apply(systems, c.impulse);
        }
    }
    let mut report = SolveReport {
        iterations: 0,
        residual: f64::INFINITY,
        converged: contacts.is_empty(),
        direct: false,
        direct_tried: false,
        jumped: false,
    };
    // Made when acceleration first applies (most solves converge before it does).
    let mut accel: Option<anderson::Accelerated> = None;
    let mut stalled = false;
    let (mut best_residual, mut best_at) = (f64::INFINITY, 0);
    let stall_after = anderson::STALL_SWEEPS_PER_MEMORY * settings.acceleration.max(1);
    while !report.converged && report.iterations < settings.max_iterations {
        let mut residual_squared = 0.0_f64;
        for (c, row) in contacts.iter_mut().zip(&rows) {
            residual_squared = residual_squared.max(sweep_contact(bodies, systems, c, row));
        }
        let residual = residual_squared.sqrt();
        report.iterations += 1;
        report.residual = residual;
        report.converged = residual <= settings.tolerance;
        if !report.converged
            && systems.is_empty()
            && settings.direct_after == Some(report.iterations)
        {
            report.direct_tried = true;
            // The patch jump first (cheap, and it reaches tilted stacks the active-set solve
            // diverges on); an island it cannot take (no patch, too many unknowns, a jump
            // that would dwarf the iterate) gets the active-set solve.
            report.jumped = patch::jump(bodies, contacts, &rows, patch::MIN_PATCHES);
            report.direct = !report.jumped
                && direct::solve_active_set(bodies, contacts, &rows, settings.tolerance);
            if let Some(a) = &mut accel {
                a.restart(contacts);
            }
            continue;
        }
        if report.converged || report.iterations == settings.max_iterations {
            break;
        }
        if let Some(a) = &mut accel {
            a.keep_if_best(contacts, residual);
        }
        if residual < best_residual * anderson::PROGRESS {
            best_residual = residual;
            best_at = report.iterations;
        } else if report.iterations - best_at > stall_after {
            // No progress under acceleration: plain sweeps from here.
            stalled = true;
        }
        // With a direct solve to come, the sweeps before it are plain: it takes their active
        // set (measured: accelerated from the first sweep, a dropped stack of 16 that the
        // direct solve settles did not sleep within 2 s, test
        // `a_dropped_stack_of_sixteen_settles_and_sleeps`).
        let direct_pending = settings.direct_after.is_some_and(|d| report.iterations < d);
        if !accelerable || stalled || direct_pending {
            continue;
        }
        match &mut accel {
            Some(a) => a.step(bodies, contacts, &rows, residual),
            None => {
                accel = Some(anderson::Accelerated::new(
                    settings.acceleration,
                    contacts,
                    residual,
                ));
            }
        }
    }
    if let Some(a) = &accel
        && !report.converged
        && a.kept_residual() < report.residual
    {
        a.restore(bodies, contacts, &rows);
        report.residual = a.kept_residual();
    }
    if contacts.is_empty() {
        report.residual = 0.0;
    }
    for s in systems.iter() {
        s.write_members(bodies);
    }
    Ok(report)
}

/// Moves the contacts' impulses to `impulses` (three numbers each), projected onto their
/// cones, and the bodies' velocities with them: the velocities are linear in the impulses,
/// so the change is applied (rigid bodies only: an accelerated solve has no systems).
fn move_impulses(
    bodies: &mut [IslandBody],
    contacts: &mut [Contact],
    rows: &[Row],
    impulses: &[f64],
) {
    for ((c, row), p) in contacts.iter_mut().zip(rows).zip(impulses.chunks_exact(3)) {
        let p_n = p[2].max(0.0);
        let p_t = clamp_to_disk(DVec2::new(p[0], p[1]), c.friction * p_n);
        let next = DVec3::new(p_t.x, p_t.y, p_n);
        apply(bodies, c, row, next - c.impulse);
        c.impulse = next;
    }
}

/// Writes the contacts' impulses into `out`, three numbers each.
fn flatten(contacts: &[Contact], out: &mut [f64]) {
    for (c, o) in contacts.iter().zip(out.chunks_exact_mut(3)) {
        o.copy_from_slice(&[c.impulse.x, c.impulse.y, c.impulse.z]);
    }
}

/// One contact's update (normal row, then the friction disk); returns the square of the
/// largest contact velocity change it made.
#[inline(always)]
fn sweep_contact(
    bodies: &mut [IslandBody],
    systems: &mut [System],
    c: &mut Contact,
    row: &Row,
) -> f64 {
    // Normal row: exact minimiser along it, clamped to p_n ≥ 0.
    let mut u = contact_velocity(bodies, c, row);
    if let Some(links) = &row.links {
        u += links.velocity(systems);
    }
    let p_n = (c.impulse.z + (c.target_normal_velocity - u.z) * row.inv_k_nn).max(0.0);
    let dp_n = p_n - c.impulse.z;
    // The tangential velocity after the normal update (u + K·(0, 0, Δp_n)).
    let u_t = DVec2::new(u.x, u.y) + dp_n * DVec2::new(row.k.z_axis.x, row.k.z_axis.y);
    // Friction: one projected-gradient step with step 1/λ onto the disk of radius μ p_n.
    let p_t_old = DVec2::new(c.impulse.x, c.impulse.y);
    let p_t = clamp_to_disk(p_t_old - u_t * row.inv_k_t, c.friction * p_n);
    let dp_t = p_t - p_t_old;
    // Both updates at once: the velocities are linear in the impulse.
    let dp = DVec3::new(dp_t.x, dp_t.y, dp_n);
    apply(bodies, c, row, dp);
    if let Some(links) = &row.links {
        links.apply(systems, dp);
    }
    c.impulse = DVec3::new(p_t.x, p_t.y, p_n);
    (row.k_nn * dp_n)
        .powi(2)
        .max(row.k_t * row.k_t * dp_t.length_squared())
}

/// The relative contact velocity u = u₁ − u₂ in the contact frame (eq. 3.3: v + ω × r for
/// each body), with the contact's [`Contact::velocity_bias`].
#[inline(always)]
fn contact_velocity(bodies: &[IslandBody], c: &Contact, row: &Row) -> DVec3 {
    let b1 = &bodies[c.body1];
    // Each axis a of the frame sees (ω × r)·a = ω·(r × a).
    let mut u = row.to_contact * b1.velocity + row.side1.omega_to_contact * b1.omega;
    if let Some(j) = c.body2 {
        let b2 = &bodies[j];
        u -= row.to_contact * b2.velocity + row.side2.omega_to_contact * b2.omega;
    }
    u + row.bias
}

/// Applies `dp` (contact frame) to body 1 and −dp to body 2 (eqs. 3.1, 3.2).
#[inline(always)]
fn apply(bodies: &mut [IslandBody], c: &Contact, row: &Row, dp: DVec3) {
    let p = row.frame.to_world(dp);
    let b1 = &mut bodies[c.body1];
    b1.velocity += p * row.side1.inverse_mass;
    b1.omega += row.side1.impulse_to_omega * dp;
    if let Some(j) = c.body2 {
        let b2 = &mut bodies[j];
        b2.velocity -= p * row.side2.inverse_mass;
        b2.omega -= row.side2.impulse_to_omega * dp;
    }
}

/// `p` scaled onto the disk of radius `radius` if outside it.
#[inline]
fn clamp_to_disk(p: DVec2, radius: f64) -> DVec2 {
    let len_squared = p.length_squared();
    if len_squared <= radius * radius {
        p
    } else if radius <= 0.0 {
        // A contact that does not press (p_n = 0) has no friction.
        DVec2::ZERO
    } else {
        onto_circle(p, radius, len_squared)
    }
}

/// `p`, of squared length `len_squared` > `radius`², scaled onto the circle of radius
/// `radius`. Kept out of line: inlined, the compiler computes its square root and division for
/// every contact update, inside the disk or not, on the sweep's critical path.
#[cold]
#[inline(never)]
fn onto_circle(p: DVec2, radius: f64, len_squared: f64) -> DVec2 {
    let len = len_squared.sqrt();
    if len > 0.0 { p * (radius / len) } else { p }
}

/// Largest eigenvalue of the symmetric 2 × 2 block [[a, b], [b, d]].
fn largest_eigenvalue_2x2(a: f64, b: f64, d: f64) -> f64 {
    let mean = 0.5 * (a + d);
    let half_diff = 0.5 * (a - d);
    mean + half_diff.hypot(b)
}

/// Validates the input and precomputes every contact's row.
fn prepare(
    bodies: &[IslandBody],
    systems: &[System],
    of: &Membership,
    contacts: &[Contact],
    settings: &SolverSettings,
) -> Result<Vec<Row>, ResponseError> {
    if settings.max_iterations == 0 {
        return Err(ResponseError::InvalidParameter {
            name: "solver max_iterations",
            value: 0.0,
            requirement: "at least 1",
        });
    }
    if !(settings.tolerance.is_finite() && settings.tolerance > 0.0) {
        return Err(ResponseError::InvalidParameter {
            name: "solver tolerance",
            value: settings.tolerance,
            requirement: "finite, > 0",
        });
    }
    for b in bodies {
        if !(b.com.is_finite() && b.velocity.is_finite() && b.omega.is_finite()) {
            return Err(ResponseError::NonFinite {
                what: "island body position or velocity",
            });
        }
    }
    // Sized at once: a row is several hundred bytes, and a growing vector moves them all.
    let mut rows = Vec::with_capacity(contacts.len());
    for c in contacts {
        rows.push(prepare_row(bodies, systems, of, c)?);
    }
    Ok(rows)
}

/// One contact's row, after checking it.
fn prepare_row(
    bodies: &[IslandBody],
    systems: &[System],
    of: &Membership,
    c: &Contact,
) -> Result<Row, ResponseError> {
    let index = |i: usize| -> Result<&IslandBody, ResponseError> {
        bodies.get(i).ok_or(ResponseError::InvalidParameter {
            name: "contact body index",
            value: i as f64,
            requirement: "below the number of island bodies",
        })
    };
    let b1 = index(c.body1)?;
    let b2 = c.body2.map(index).transpose()?;
    if c.body2 == Some(c.body1) {
        return Err(ResponseError::InvalidParameter {
            name: "contact body2",
            value: c.body1 as f64,
            requirement: "a body other than body1",
        });
    }
    if !(c.friction.is_finite() && c.friction >= 0.0) {
        return Err(ResponseError::InvalidParameter {
            name: "friction coefficient",
            value: c.friction,
            requirement: "finite, ≥ 0",
        });
    }
    if !c.target_normal_velocity.is_finite() {
        return Err(ResponseError::NonFinite {
            what: "contact target normal velocity",
        });
    }
    if !(c.point.is_finite() && c.impulse.is_finite() && c.velocity_bias.is_finite()) {
        return Err(ResponseError::NonFinite {
            what: "contact point, impulse or velocity bias",
        });
    }
    let frame = ContactFrame::from_normal(c.normal)?;
    if c.lever_arms
        .is_some_and(|(a1, a2)| !(a1.is_finite() && a2.is_finite()))
    {
        return Err(ResponseError::NonFinite {
            what: "contact lever arms",
        });
    }
    let r1 = c.lever_arms.map_or(c.point - b1.com, |(a1, _)| a1);
    let (body2, r2) = match b2 {
        Some(b) => (b.body, c.lever_arms.map_or(c.point - b.com, |(_, a2)| a2)),
        None => (Body::Fixed, DVec3::ZERO),
    };
    let axes = frame.axes();
    let links = LinkRows::new(systems, of, (c.body1, r1), c.body2.map(|j| (j, r2)), axes);
    let mut k = frame.matrix_to_contact(collision_matrix_world(&b1.body, r1, &body2, r2));
    if let Some(l) = &links {
        k += l.matrix();
    }
    let k_nn = k.z_axis.z;
    let scale = k.x_axis.x + k.y_axis.y + k_nn;
    if !(k_nn > 0.0 && scale.is_finite()) {
        return Err(ResponseError::NormalUnreachable { k33: k_nn, scale });
    }
    let k_t = largest_eigenvalue_2x2(k.x_axis.x, k.y_axis.x, k.y_axis.y);
    Ok(Row {
        bias: frame.to_contact(c.velocity_bias),
        to_contact: axes.transpose(),
        side1: Side::new(&b1.body, r1, axes),
        side2: Side::new(&body2, r2, axes),
        frame,
        r1,
        r2,
        k_nn,
        inv_k_nn: k_nn.recip(),
        k_t,
        inv_k_t: k_t.recip(),
        k,
        links: links.map(Box::new),
    })
}
