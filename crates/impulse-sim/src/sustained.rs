//! The switching contact model (thesis §8.1): impacts stay impulses, sustained contact becomes
//! a constraint.
//!
//! Mirtich's closing chapter names the weakness of pure impulse-based simulation — a body
//! resting, sliding or rolling on another is a train of microcollisions — and its remedy: switch
//! a contact to a constraint when it becomes static, and back to impulses when an abrupt change
//! comes. [`ContactMode::Switching`] does that:
//!
//! - **Onset**: a pair that the event loop finds within ε_c and approaching slower than the
//!   switching speed `v_s` ([`SustainedSettings::switch_speed_factor`] × √(2·g·ε_c), the
//!   thesis's own microcollision threshold, eq. 3.18) gets no impulse: it is *held* — it leaves
//!   the collision heap's schedule and joins the contact islands. Anything faster is a
//!   collision of chapter 3, exactly as in [`ContactMode::Impulse`].
//! - **Struck twice at one instant**: a pair found approaching within ε_c at the very instant
//!   of its last collision is held too, whatever its speed (unless a body of it turns fast).
//!   Bodies pressed together by other impacts at one instant — a heavy ball landing on a stack
//!   of light boxes — would otherwise trade collisions without end (a box 1000 times lighter
//!   than the ball passes on about a thousandth of its momentum per exchange: over 10 000
//!   collisions at one instant). Held, they are solved together by their island's impulsive
//!   solve (e = 0 between held contacts), the limit such a train of collisions tends to;
//!   each pair's first collision keeps its restitution.
//! - **Island steps**: every `h` ([`SustainedSettings::step`], shorter while a body turns: down
//!   to [`SustainedSettings::min_step`]; a pair turning faster than its points within ε_c
//!   allow is held with speculative points beyond ε_c, `world/hold.rs`) the held pairs'
//!   manifolds are
//!   computed (`impulse_collide::manifold`), bodies joined by held pairs form islands, and each
//!   island's contact impulses over the coming step are solved with the exact Coulomb disk
//!   (`impulse_response::contact`). The impulses are not applied as velocity jumps: each body
//!   **holds the contact force P/h and torque constant over the step**, so between island steps
//!   every body is ballistic under gravity, its loads and its held contact load — the motion
//!   model the event loop's time-of-impact bounds already cover. Velocities stay continuous;
//!   a sliding body's motion under constant friction is exact, and a ball rolls without hops.
//!   A polyhedron's contact vertex or edge turns with its body over the step: the held
//!   load acts at its lever arm at mid-step, whose torque is the step's mean to second order
//!   (`impulse_response::Contact::lever_arms`; with the arm at the start a box tipping over
//!   its edge came late by 1.5·‖ω‖·h relative), and the contact law holds for the point's
//!   velocity at the step's end (`impulse_response::Contact::velocity_bias`; left out, a
//!   pivoting edge climbs off its support by ½·h²·ω²·r a step). A turning smooth body's
//!   contact point runs over its surface instead: its arm is its support point at the
//!   mid-step pose, and its step is bounded by the curvature of its motion alone (no feature
//!   of it can come through the envelope; with the arm at the step's start a rattleback
//!   stepped so gained energy).
//!   Full steps end on the grid of multiples of `h` in absolute time, so islands step at
//!   the same instants and share the event loop's steps (each of which advances every body).
//! - **Position stabilisation**: a held contact rests at the gap g_r = `rest_gap_fraction`·ε_c
//!   inside the contact envelope [0, ε_c]; each step asks for the end-of-step normal speed
//!   u_n ≥ β·(g_r − gap)/h (β = [`SustainedSettings::stabilisation`]) for a gap below g_r,
//!   which pushes it back without the velocity ringing of a trapezoidal target. A gap inside
//!   the *rest band* [g_r, g_pull] (g_pull = `pull_gap_fraction`·ε_c) is asked for nothing
//!   (u_n ≥ 0), a wider one is closed at the same rate toward g_pull: bodies already touching
//!   within the band need no motion, and a closed loop of contacts (a pyramid, leaning
//!   dominos) is not asked for approach speeds that differ per contact, which no rigid motion
//!   of the loop meets and which left its solver unconverged at every step; an
//!   overlap (gap < 0) is asked back in full within h on top of that (a contact sliding on a
//!   turning body is driven inward by about ½·ω²·r·h² a step, which β alone lets settle
//!   β⁻¹ times deeper). The
//!   energy this can add is bounded: it lifts a body by at most g_r per contact beneath it
//!   (Σ m·|g|·N·g_r for N bodies) and pushes at most at β·g_r/h (½·m·(β·g_r/h)² each).
//! - **Transitions in time**: when a contact that was slipping at the start of a step sticks
//!   at its end, the step is shortened to the instant sliding friction stops the slip
//!   (the fraction s = |p_t|/(μ·p_n) of the step), so slip → stick is located, not rounded to
//!   h — when rounding would matter: the step's constant load slows the slip u₀ linearly
//!   over the whole step where friction stopped it within s·h, so the rounded step moves the
//!   contact point ½·u₀·h·(1 − s) ≤ ½·u₀·h too far. A transition whose bound ½·u₀·h is below
//!   [`SustainedSettings::step_tolerance`]·ε_c is taken at the step's end (the velocities at
//!   the end are the same either way: the friction impulse that stops the slip is the
//!   same). In a pile nearly every step ends some contact's slip of a fraction of a mm/s;
//!   locating each cut the whole island's step to microseconds.
//! - **Transients**: a held contact whose normal speed at a step is an approach (faster than
//!   a hundredth of `v_s`: a body was struck, an impulse or a new load was applied), and one
//!   that the step's constant load could not stop within a quarter of the rest gap
//!   (|u_n|·h/2), is first resolved by an
//!   impulsive solve of its island (velocity jumps, e = 0 between held contacts: the island
//!   reacts through its constraints), then stepped as usual. A struck body itself gets the
//!   chapter-3 collision from the event loop.
//! - **Lift-off**: a held pair whose manifold is gone (no point within ε_c) is released to the
//!   event loop, which bounds its next approach as it bounds any pair.
//! - **Rest steps**: an island whose bodies all move slower than the sleep speed, under no
//!   load function and touching only fixed bodies, with every gap in or above the rest band,
//!   steps eight nominal steps at a time (a strike, a program's change or a new held pair
//!   still makes it step at once). So does a *steady* island (`world/steady.rs`): its held
//!   loads changed over its last step by less than the step tolerance allows over the long
//!   step (½·Δa·H² ≤ `step_tolerance`·ε_c), it touches only fixed bodies, and each of its
//!   contact points lies on a fixed polyhedron's face, twice its travel over the long step
//!   inside the face's edges: a ball rolling on a table, a block sliding on a floor (the pool
//!   break took 28 490 island steps, now 6 438).
//! - **Sleeping**: an island whose bodies all move slower than the sleep speed for
//!   [`SustainedSettings::sleep_time`] sleeps: velocities and held loads are zeroed and its
//!   bodies are fixed until something touches them, the program changes them, or an awake
//!   body's held pair joins them to an awake island. Waking is exact: a sleeping body is at
//!   rest, so it resumes from the state it slept in.
//! - **Multibody links** are held like rigid bodies, each multibody with a held link one
//!   jointed system of its island, its contact impulses held as joint forces over the step
//!   (`world/held_links.rs`, `docs/hybrid.md`); such an island neither rests nor sleeps.
//!
//! **Must not know** how collisions are resolved (chapter 3, `crate::contact`) or scene files.

use serde::{Deserialize, Serialize};

/// How contacts are modelled.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum ContactMode {
    /// Every contact is an impulse (thesis chapters 2–3): collisions, and microcollisions for
    /// resting contact.
    Impulse,
    /// Impacts are impulses, sustained contact is a constraint (thesis §8.1; module
    /// documentation). The default.
    #[default]
    Switching,
}

/// Settings of the switching contact model (module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SustainedSettings {
    /// Island step h (s): the longest step an island takes. Default [`DEFAULT_STEP`].
    pub step: f64,
    /// Shortest island step (s) taken for turning bodies. An island steps at the rate its
    /// turning needs: a step short enough that rotation cannot bring another feature through
    /// the rest of the contact envelope, (1 − g_r/ε_c)·ε_c / (‖ω‖·r), while that is at least
    /// this; past it, its pairs reach for points beyond ε_c and the step is bounded by the
    /// curvature of the turning and the clearance of what the manifold leaves out
    /// (`world/hold.rs`). A pair needing less than this even then is handed to the event loop.
    /// Default [`DEFAULT_MIN_STEP`].
    pub min_step: f64,
    /// The switching speed in units of the microcollision speed √(2·g·ε_c) (thesis eq.
    /// 3.18). Default `1.0`.
    pub switch_speed_factor: f64,
    /// Where a held contact rests inside the contact envelope, as a fraction of ε_c. Default
    /// `0.1`: a stack of n blocks stands n·0.1·ε_c taller than its blocks.
    pub rest_gap_fraction: f64,
    /// Upper edge of the rest band, as a fraction of ε_c: a held contact whose gap lies
    /// between g_r and this is neither pushed nor pulled (target normal speed 0); a wider gap
    /// is closed at the β rate toward it. Default `0.5`.
    pub pull_gap_fraction: f64,
    /// Fraction β of a gap error corrected per step. Default `0.01`: 0.2 made stacks of 16
    /// sway (the correction feeds speed faster than the solver settles a tall island).
    pub stabilisation: f64,
    /// The sleep speed in units of the microcollision speed: an island sleeps when all its
    /// bodies' points move slower (‖v‖ + ‖ω‖·r_max). Default `0.01`.
    pub sleep_speed_factor: f64,
    /// How long (s) an island must stay below the sleep speed to sleep. Default `0.5`.
    pub sleep_time: f64,
    /// Most projected Gauss–Seidel sweeps per island solve. Default `200`.
    pub max_sweeps: usize,
    /// Solver tolerance in units of the microcollision speed. Default `1e-4`.
    pub solver_tolerance_factor: f64,
    /// Sweeps without convergence after which the solver tries a direct solve on the active
    /// set (`impulse_response::contact`: tall stacks). Default `20`.
    pub direct_after: usize,
    /// Past iterates mixed into each accelerated sweep of an island solve
    /// (`impulse_response::SolverSettings::acceleration`, Anderson's mixing); 0 for plain
    /// projected Gauss–Seidel. Default [`impulse_response::DEFAULT_ACCELERATION`].
    pub acceleration: usize,
    /// The position error an island step may leave, in units of ε_c (module documentation,
    /// "Step sizes from the error"): a slip → stick transition is located only when rounding
    /// it to the step's end would move its contact point by more than this. Default
    /// [`DEFAULT_STEP_TOLERANCE`].
    pub step_tolerance: f64,
}

/// Default island step (s): 1 ms.
pub const DEFAULT_STEP: f64 = 1e-3;

/// Default shortest island step (s): 50 µs, so a toppling domino (r = 27 mm, ε_c = 20 µm) is
/// held by its points within ε_c alone up to ‖ω‖ ≈ 6.6 rad/s, and beyond it by speculative
/// points.
pub const DEFAULT_MIN_STEP: f64 = 5e-5;

/// A contact counts as slipping at the start of a step when its tangential speed exceeds this
/// fraction of the microcollision speed (for locating slip → stick). Below it, a transition
/// rounded to the step's end is off in time by less than this speed over the slip's
/// deceleration: for a ball launched with slip u₀ the relative error of its time to rolling
/// is below this speed over u₀ (1e-4 for u₀ = 0.44 m/s at ε_c = 1e-4 m, g = 9.81 m/s²);
/// settling stacks, whose corners stick and slip by tiny amounts, are not cut into tiny
/// steps. Default `1e-3`.
pub const SLIP_FRACTION: f64 = 1e-3;

/// A contact counts as sticking at the end of a step when its friction impulse is below this
/// fraction of the cone's radius μ·p_n. Default `1.0 − 1e-9`.
pub const STICK_FRACTION: f64 = 1.0 - 1e-9;

/// Default [`SustainedSettings::step_tolerance`]: a thousandth of ε_c. A ball sliding into
/// rolling (V7: ε_c = 0.1 mm) has its transition located to the instant unless it falls
/// within the first 3 % of a step (a slip below 0.2 mm/s at the step's start); in a pile,
/// where contacts stick after slips of 0.1–1 mm/s at almost every step, most transitions are
/// taken at the step's end, each moving a contact point by less than 1 µm (ε_c = 1 mm).
/// `cargo xtask bench` measures 1e-3 to 1.
pub const DEFAULT_STEP_TOLERANCE: f64 = 1e-3;

/// Shortest step a transition may cut a step to, as a fraction of [`SustainedSettings::step`]
/// (a transition right at a step's start is taken at the start). Default `1e-3`.
pub const MIN_STEP_FRACTION: f64 = 1e-3;

impl Default for SustainedSettings {
    fn default() -> Self {
        Self {
            step: DEFAULT_STEP,
            min_step: DEFAULT_MIN_STEP,
            switch_speed_factor: 1.0,
            rest_gap_fraction: 0.1,
            pull_gap_fraction: 0.5,
            stabilisation: 0.01,
            sleep_speed_factor: 0.01,
            sleep_time: 0.5,
            max_sweeps: 200,
            solver_tolerance_factor: 1e-4,
            direct_after: 20,
            acceleration: impulse_response::DEFAULT_ACCELERATION,
            step_tolerance: DEFAULT_STEP_TOLERANCE,
        }
    }
}

impl SustainedSettings {
    /// Checks every setting.
    ///
    /// # Errors
    /// A sentence naming the setting that is out of range.
    pub fn validate(&self) -> Result<(), String> {
        let positive = |name: &str, x: f64| {
            if x.is_finite() && x > 0.0 {
                Ok(())
            } else {
                Err(format!("{name} {x} must be finite and > 0"))
            }
        };
        positive("step", self.step)?;
        positive("min_step", self.min_step)?;
        if self.min_step > self.step {
            return Err(format!(
                "min_step {} must not exceed step {}",
                self.min_step, self.step
            ));
        }
        positive("switch_speed_factor", self.switch_speed_factor)?;
        positive("sleep_speed_factor", self.sleep_speed_factor)?;
        positive("solver_tolerance_factor", self.solver_tolerance_factor)?;
        positive("step_tolerance", self.step_tolerance)?;
        if !(self.sleep_time.is_finite() && self.sleep_time >= 0.0) {
            return Err(format!(
                "sleep_time {} must be finite and ≥ 0",
                self.sleep_time
            ));
        }
        for (name, x) in [
            ("rest_gap_fraction", self.rest_gap_fraction),
            ("pull_gap_fraction", self.pull_gap_fraction),
            ("stabilisation", self.stabilisation),
        ] {
            if !(x > 0.0 && x < 1.0) {
                return Err(format!("{name} {x} must lie in (0, 1)"));
            }
        }
        if self.pull_gap_fraction < self.rest_gap_fraction {
            return Err(format!(
                "pull_gap_fraction {} must not be below rest_gap_fraction {}",
                self.pull_gap_fraction, self.rest_gap_fraction
            ));
        }
        if self.max_sweeps == 0 {
            return Err("max_sweeps must be at least 1".into());
        }
        Ok(())
    }
}
