//! Collision integration (thesis §3.3): the relative contact velocity u is followed through the
//! collision as the normal impulse p_z grows, with Coulomb friction (Assumption 3) and a
//! restitution law that decides where the collision ends.
//!
//! ## Algorithm (digest §11)
//! State: u (relative contact velocity), W_z (normal work, Theorem 12), p (impulse) and W (total
//! work, Theorem 10, a diagnostic). While sliding, `du/dp_z = K·ξ(θ)` (Theorem 8),
//! `dp/dp_z = ξ(θ)` (Lemma 2), `dW_z/dp_z = u_z` (3.7), `dW/dp_z = u·ξ`.
//! 1. **Compression** in the parameter u_z, eq. (3.8), from u_z0 to 0 (a known end point). Where
//!    du_z/dp_z = k_z·ξ(θ) is not safely positive (the impulse first drives the bodies together,
//!    Theorem 17, or Lemma 3 fails) the step uses p_z instead and u_z = 0 becomes an event.
//!    W_c := W_z at u_z = 0.
//! 2. **Stronge** (Assumption 2): the collision ends at `W_z = W_f = (1 − e²)·W_c`.
//!    **Extension** in u_z from 0 to Lemma 3's `b = √(2·W_r·G)`, `G = K_33 − μ√(K_31² + K_32²)`,
//!    when G > 0 (with W_z = W_f as a safety event); then **restitution** in the parameter W_z,
//!    eq. (3.9), to W_f (a known end point). If G ≤ 0 (no Lemma 3 bound) restitution starts in
//!    p_z and switches to W_z once u_z is safely positive.
//!    **Poisson**: restitution in p_z to `(1 + e)·p_z(t_mc)`. **Newton**: restitution in u_z to
//!    `−e·u_z0`. Both can create energy with friction (thesis §3.1); they are here for comparison.
//! 3. **Sticking**: when the tangential velocity reaches the origin, Theorem 9 decides. Stable:
//!    u_t stays 0 and `dp/dp_z = K⁻¹e_z/K⁻¹_33` (3.6). Unstable: sliding resumes along the
//!    unique diverging ray β (Theorem 16, [`crate::rays`]) with constant direction. Either way
//!    the direction of dp/dp_z is constant from then on and the rest of the collision is closed
//!    form (Observation 1, eqs. 3.10–3.14). A collision sticks at most once.
//! 4. If, in rare Lemma-3-violating cases, u_z falls back to 0 during restitution, compression
//!    resumes, and W_c is taken at the last maximum compression \[not in the thesis\].
//!
//! ## Reaching the origin of the tangential plane \[not in the thesis\]
//! The sliding equations are singular at u_t = 0 (ξ is undefined there) and the right-hand side
//! depends only on the direction of u_t, so a plain integrator chatters around the origin
//! instead of stopping on it (digest §11). Three mechanisms, each exact to the tolerances:
//! - a step that crosses the origin (u_t turns by ≥ 90°) is shortened by regula falsi until it
//!   ends within ε_s of it (straight approaches land in one or two iterations);
//! - near the origin the tangential error is bounded relative to |u_t| as well
//!   ([`tol::NEAR_ORIGIN_RTOL`]), and once |u_t| < [`tol::LOG_R_MAX_REL`]·|u₀| and u_t′ points
//!   inwards, the parameter becomes σ = −ln|u_t|, in which the curved approach along a converging
//!   ray (direction error ∝ |u_t|^λ) is smooth; it ends exactly at |u_t| = ε_s;
//! - once the direction has settled onto an attracting ray of constant sliding (Theorem 14) to
//!   within the tolerance, the rest is closed form along it: into the origin on a converging
//!   ray, for the rest of the collision on a diverging one. This removes the stiffness of the
//!   relaxation onto weak rays ([`tol::RAY_SNAP_TOL`]).
//!
//! The integrator is an embedded Runge–Kutta 4(5) pair (Cash–Karp) with error control on u and
//! W_z. Its fifth-order weights are all non-negative, so each step's impulse increment is a
//! positive combination of vectors ξ in the friction cone: the final impulse satisfies
//! |p_t| ≤ μ·p_z to rounding, by construction. Every phase boundary is hit exactly: by clipping
//! the step where the parameter is the boundary's variable, otherwise by root finding.

use crate::rays::{self, sliding_vector};
use crate::{CollisionMatrix, ResponseError, tol};
use glam::{DMat3, DVec3};

/// The restitution law that ends the collision (thesis §3.1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Restitution {
    /// Stronge's energetic law (Assumption 2), the thesis's choice:
    /// `W_z(t_f) − W_z(t_mc) = −e²·W_z(t_mc)`. Never creates energy for e ≤ 1.
    #[default]
    Stronge,
    /// Poisson's kinetic law: `p_z(t_f) = (1 + e)·p_z(t_mc)`. Can create energy with friction.
    Poisson,
    /// Newton's kinematic law: `u_z(t_f) = −e·u_z(0)`. Can create energy with friction.
    Newton,
}

/// Integration settings. `Default` gives the documented constants of [`crate::tol`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Settings {
    /// Relative local error tolerance of the Runge–Kutta steps (dimensionless; default
    /// [`tol::DEFAULT_RTOL`] = 1e-9).
    pub rtol: f64,
    /// Sticking tolerance ε_s relative to |u₀| (dimensionless; default
    /// [`tol::DEFAULT_STICK_TOL_REL`] = 1e-12).
    pub stick_tol: f64,
    /// Cap on step attempts (default [`tol::MAX_STEPS`] = 20 000).
    pub max_steps: usize,
    /// Record a [`TraceSample`] after every step and closed-form segment (default false).
    pub record_trace: bool,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            rtol: tol::DEFAULT_RTOL,
            stick_tol: tol::DEFAULT_STICK_TOL_REL,
            max_steps: tol::MAX_STEPS,
            record_trace: false,
        }
    }
}

impl Settings {
    fn validate(&self) -> Result<(), ResponseError> {
        if !(self.rtol.is_finite() && self.rtol > 0.0 && self.rtol <= tol::MAX_RTOL) {
            return Err(ResponseError::InvalidParameter {
                name: "rtol",
                value: self.rtol,
                requirement: "finite, 0 < rtol ≤ 1e-2",
            });
        }
        if !(self.stick_tol.is_finite()
            && self.stick_tol >= 0.0
            && self.stick_tol <= tol::MAX_STICK_TOL)
        {
            return Err(ResponseError::InvalidParameter {
                name: "stick_tol",
                value: self.stick_tol,
                requirement: "finite, 0 ≤ stick_tol ≤ 1e-3",
            });
        }
        if self.max_steps == 0 {
            return Err(ResponseError::InvalidParameter {
                name: "max_steps",
                value: 0.0,
                requirement: "≥ 1",
            });
        }
        Ok(())
    }
}

/// Phase of the collision (Fig. 3.6).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// u_z < 0, up to maximum compression (u_z = 0).
    Compression,
    /// Early restitution integrated in u_z up to Lemma 3's bound b.
    Extension,
    /// Restitution to the end point of the restitution law.
    Restitution,
}

/// The independent variable of a step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Parameter {
    /// p_z (Theorem 8).
    NormalImpulse,
    /// u_z, eq. (3.8).
    NormalVelocity,
    /// W_z, eq. (3.9).
    NormalWork,
    /// σ = −ln|u_t|, for the final approach to sticking: the sliding velocity heads into the
    /// origin, tangent to a converging ray (§3.4.2), where u_t as a function of p_z is not
    /// smooth (|u_t| ∝ distance, direction ∝ distance^λ); in σ the motion is smooth and the
    /// increments decay like |u_t| \[not in the thesis\].
    LogTangentialSpeed,
    /// A closed-form segment (Observation 1).
    ClosedForm,
}

/// How the tangential velocity moves.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Mode {
    /// Sliding with a varying direction (numerical integration).
    Sliding,
    /// Stable sticking: u_t = 0 (Theorem 9).
    Sticking,
    /// Sliding on the diverging ray at angle `theta` (radians) after unstable sticking.
    Ray {
        /// β, the ray's angle.
        theta: f64,
    },
    /// μ = 0: ξ ≡ e_z.
    Frictionless,
}

/// One recorded point of the collision path (only with [`Settings::record_trace`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TraceSample {
    /// Phase at this point.
    pub phase: Phase,
    /// Tangential mode.
    pub mode: Mode,
    /// Parameter of the step that ended here.
    pub parameter: Parameter,
    /// p_z.
    pub normal_impulse: f64,
    /// u (collision frame).
    pub velocity: DVec3,
    /// W_z.
    pub normal_work: f64,
}

/// Where sliding stopped.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sticking {
    /// p_z when u_t reached 0.
    pub normal_impulse: f64,
    /// The phase it happened in.
    pub phase: Phase,
    /// Theorem 9's verdict: true if the bodies stayed stuck.
    pub stable: bool,
    /// The diverging ray β (radians) along which sliding resumed, if unstable.
    pub ray: Option<f64>,
}

/// How the impulse was obtained.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ResponseKind {
    /// μ = 0: closed form (digest §9.4).
    Frictionless,
    /// Collision integration (possibly with closed-form tails).
    Integrated,
    /// Microcollision: the reversing impulse p_r = −2K⁻¹u₀ (§3.5), no integration.
    Reversing,
}

/// Work counters of one collision.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Stats {
    /// Runge–Kutta step attempts of every kind (accepted, rejected, event location); this is
    /// what [`Settings::max_steps`] caps.
    pub attempts: usize,
    /// Accepted steps.
    pub accepted: usize,
    /// Rejected steps (error too large, or invalid parameterisation).
    pub rejected: usize,
    /// Steps spent locating events (sticking, phase boundaries).
    pub event_iterations: usize,
    /// Evaluations of the right-hand side.
    pub evaluations: usize,
    /// Accepted steps that used p_z because u_z or W_z was not a valid parameter there.
    pub normal_impulse_steps: usize,
    /// Number of maximum compressions (1, or more if u_z fell back to 0 in restitution).
    pub compressions: usize,
    /// Whether the Lemma 3 extension itself reached W_f (it should not, up to rounding).
    pub extension_reached_final_work: bool,
    /// Closed-form segments along a converging ray into the origin (see
    /// [`tol::RAY_SNAP_TOL`]).
    pub ray_approaches: usize,
}

/// The result of a collision.
#[derive(Debug, Clone, PartialEq)]
pub struct Response {
    /// The impulse p on body 1 (body 2 receives −p), collision frame.
    pub impulse: DVec3,
    /// The post-collision relative contact velocity u_f, collision frame (= u₀ + K·p to the
    /// integration's rounding; its tangential part is exactly 0 after stable sticking).
    pub velocity: DVec3,
    /// u₀.
    pub initial_velocity: DVec3,
    /// The restitution coefficient used (boosted for microcollisions).
    pub restitution: f64,
    /// The restitution law used.
    pub law: Restitution,
    /// W_c = W_z at maximum compression (≤ 0). Zero for [`ResponseKind::Reversing`].
    pub compression_work: f64,
    /// W_z at the end of the collision. Zero for [`ResponseKind::Reversing`].
    pub normal_work: f64,
    /// Total work W, the change of kinetic energy: `u₀·p + ½·pᵀKp` (Theorem 11).
    pub work: f64,
    /// ∫u·dp accumulated along the integrated path (Theorem 10); equals `work` up to the
    /// integration error (path independence, Theorem 11).
    pub path_work: f64,
    /// p_z at maximum compression.
    pub max_compression_impulse: f64,
    /// Where sliding stopped, if it did.
    pub sticking: Option<Sticking>,
    /// How the impulse was obtained.
    pub kind: ResponseKind,
    /// Work counters.
    pub stats: Stats,
    /// The path, if [`Settings::record_trace`] was set.
    pub trace: Option<Vec<TraceSample>>,
}

impl Response {
    /// Normal work done during restitution, `W_z(t_f) − W_c` (= −e²·W_c under Stronge).
    pub fn restitution_work(&self) -> f64 {
        self.normal_work - self.compression_work
    }

    /// The impulse on body 1 in world axes.
    pub fn impulse_world(&self, frame: &crate::ContactFrame) -> DVec3 {
        frame.to_world(self.impulse)
    }
}

/// Resolves a collision: the impulse for collision matrix `k`, initial relative contact velocity
/// `u0` (collision frame, u0.z < 0), friction `mu` and restitution coefficient `e` under `law`.
///
/// # Errors
/// [`ResponseError::NonFinite`] for a non-finite `u0`; [`ResponseError::NotApproaching`] if
/// u0.z ≥ 0; [`ResponseError::InvalidParameter`] for μ < 0 or non-finite, e outside [0, 1] or
/// bad settings; [`ResponseError::StepLimit`] / [`ResponseError::StepUnderflow`] if the
/// integration cannot finish within its bounds; [`ResponseError::NoSlidingDirection`] (singular
/// K only).
pub fn resolve(
    k: &CollisionMatrix,
    u0: DVec3,
    mu: f64,
    e: f64,
    law: Restitution,
    settings: &Settings,
) -> Result<Response, ResponseError> {
    if !(e.is_finite() && (0.0..=1.0).contains(&e)) {
        return Err(ResponseError::InvalidParameter {
            name: "restitution coefficient e",
            value: e,
            requirement: "finite, 0 ≤ e ≤ 1",
        });
    }
    integrate(k, u0, mu, e, law, settings)
}

/// [`resolve`] without the e ≤ 1 restriction (boosted microcollisions use e up to e_max).
pub(crate) fn integrate(
    k: &CollisionMatrix,
    u0: DVec3,
    mu: f64,
    e: f64,
    law: Restitution,
    settings: &Settings,
) -> Result<Response, ResponseError> {
    check_velocity_and_friction(u0, mu)?;
    if !(e.is_finite() && e >= 0.0) {
        return Err(ResponseError::InvalidParameter {
            name: "restitution coefficient e",
            value: e,
            requirement: "finite, ≥ 0",
        });
    }
    settings.validate()?;
    let mut it = Integrator::new(k, u0, mu, e, law, settings);
    it.run()?;
    let r = it.finish();
    if !(r.impulse.is_finite() && r.velocity.is_finite() && r.work.is_finite()) {
        // A guard, never expected: refuse rather than hand back NaN.
        return Err(ResponseError::NonFinite {
            what: "computed impulse",
        });
    }
    Ok(r)
}

/// Validates u₀ (finite, approaching) and μ (finite, ≥ 0).
pub(crate) fn check_velocity_and_friction(u0: DVec3, mu: f64) -> Result<(), ResponseError> {
    if !u0.is_finite() {
        return Err(ResponseError::NonFinite {
            what: "initial relative velocity",
        });
    }
    if u0.z >= 0.0 {
        return Err(ResponseError::NotApproaching {
            normal_velocity: u0.z,
        });
    }
    if !(mu.is_finite() && mu >= 0.0) {
        return Err(ResponseError::InvalidParameter {
            name: "friction coefficient μ",
            value: mu,
            requirement: "finite, ≥ 0",
        });
    }
    Ok(())
}

// State layout.
const UX: usize = 0;
const UY: usize = 1;
const UZ: usize = 2;
const WZ: usize = 3;
const PX: usize = 4;
const PY: usize = 5;
const PZ: usize = 6;
const WT: usize = 7;
const N: usize = 8;
type Y = [f64; N];

/// Exponent of the error ratio when shrinking a rejected step: −1/4 for the fourth-order
/// error estimate of the 4(5) pair (Numerical Recipes §16.2).
const ERR_EXP_SHRINK: f64 = -0.25;
/// Exponent of the error ratio when growing after an accepted step: −1/5.
const ERR_EXP_GROW: f64 = -0.2;
use tol::{STEP_GROW_MAX, STEP_RETRY_FACTOR, STEP_SAFETY, STEP_SHRINK_MIN};

// Cash–Karp embedded Runge–Kutta 4(5) (Numerical Recipes §16.2).
const A21: f64 = 1.0 / 5.0;
const A31: f64 = 3.0 / 40.0;
const A32: f64 = 9.0 / 40.0;
const A41: f64 = 3.0 / 10.0;
const A42: f64 = -9.0 / 10.0;
const A43: f64 = 6.0 / 5.0;
const A51: f64 = -11.0 / 54.0;
const A52: f64 = 5.0 / 2.0;
const A53: f64 = -70.0 / 27.0;
const A54: f64 = 35.0 / 27.0;
const A61: f64 = 1631.0 / 55296.0;
const A62: f64 = 175.0 / 512.0;
const A63: f64 = 575.0 / 13824.0;
const A64: f64 = 44275.0 / 110592.0;
const A65: f64 = 253.0 / 4096.0;
// Fifth-order weights (all ≥ 0: the impulse increment stays in the friction cone).
const B1: f64 = 37.0 / 378.0;
const B3: f64 = 250.0 / 621.0;
const B4: f64 = 125.0 / 594.0;
const B6: f64 = 512.0 / 1771.0;
// Differences to the fourth-order weights (error estimate).
const D1: f64 = B1 - 2825.0 / 27648.0;
const D3: f64 = B3 - 18575.0 / 48384.0;
const D4: f64 = B4 - 13525.0 / 55296.0;
const D5: f64 = -277.0 / 14336.0;
const D6: f64 = B6 - 0.25;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Var {
    Uz,
    Wz,
    Pz,
}

impl Var {
    fn index(self) -> usize {
        match self {
            Var::Uz => UZ,
            Var::Wz => WZ,
            Var::Pz => PZ,
        }
    }
}

/// The independent variable of a step: one of the event variables, or σ = −ln|u_t| for the
/// final approach to sticking.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Param {
    Uz,
    Wz,
    Pz,
    LogR,
}

impl Param {
    fn var(self) -> Option<Var> {
        match self {
            Param::Uz => Some(Var::Uz),
            Param::Wz => Some(Var::Wz),
            Param::Pz => Some(Var::Pz),
            Param::LogR => None,
        }
    }
    fn parameter(self) -> Parameter {
        match self {
            Param::Uz => Parameter::NormalVelocity,
            Param::Wz => Parameter::NormalWork,
            Param::Pz => Parameter::NormalImpulse,
            Param::LogR => Parameter::LogTangentialSpeed,
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Motion {
    Slide,
    /// dp/dp_z = q, du/dp_z = w = K·q, constant (stick, ray or frictionless).
    Constant {
        q: DVec3,
        w: DVec3,
        mode: Mode,
    },
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum EventKind {
    End,
    FinalWork,
    Recompression,
}

/// "Variable `var` reaches `target`", rising or falling. φ < 0 before, φ ≥ 0 after.
#[derive(Debug, Clone, Copy)]
struct Event {
    var: Var,
    target: f64,
    rising: bool,
    kind: EventKind,
}

impl Event {
    fn phi(&self, y: &Y) -> f64 {
        let v = y[self.var.index()];
        if self.rising {
            v - self.target
        } else {
            self.target - v
        }
    }
    /// Whether a step from y0 to y1 triggers the event. Rising events need φ strictly negative
    /// at the start (so a segment starting on its target does not end at once); falling ones
    /// (u_z back to 0) also trigger from φ = 0 when φ becomes positive.
    fn crossed(&self, y0: &Y, y1: &Y) -> bool {
        let (a, b) = (self.phi(y0), self.phi(y1));
        if self.rising {
            a < 0.0 && b >= 0.0
        } else {
            a <= 0.0 && b > 0.0
        }
    }
}

enum Outcome {
    Reached(EventKind),
    /// The motion has become constant-direction (sticking, or a ray): closed forms follow.
    Constant,
}

enum Step {
    Done {
        y: Y,
        err: f64,
    },
    /// A stage had k_z·ξ ≤ 0 (u_z parameter) or u_z ≤ 0 (W_z parameter).
    BadSlope,
    /// A stage had u_t = 0 exactly.
    Origin,
}

struct Integrator<'a> {
    cm: &'a CollisionMatrix,
    k: DMat3,
    mu: f64,
    e: f64,
    law: Restitution,
    settings: &'a Settings,
    u0: DVec3,
    y: Y,
    motion: Motion,
    phase: Phase,
    /// Step size in p_z units.
    h: f64,
    /// |u₀|: error scale of the tangential velocity, sticking tolerance.
    v_scale: f64,
    /// Error scale of the normal velocity: the largest |u_z| so far (at least |u_z0|).
    uz_scale: f64,
    /// Error scale of W_z: the largest |W_z| so far, at least u_z0²/K_33 (twice the
    /// frictionless compression work).
    w_scale: f64,
    /// |u_z0|/K_33 (the frictionless compression impulse): step-size scale.
    p_scale: f64,
    /// W_z at the last maximum compression; the state's W_z component counts from there, so
    /// the restitution target W_r = −e²·W_c is reached without cancellation (for tiny e,
    /// W_f − W_z = (1 − e²)W_c − W_z would lose all digits).
    wz_base: f64,
    eps_s: f64,
    slope_min: f64,
    wz_min_uz: f64,
    stable: bool,
    wc: f64,
    p_mc: f64,
    sticking: Option<Sticking>,
    stats: Stats,
    trace: Option<Vec<TraceSample>>,
}

fn ut(y: &Y) -> (f64, f64) {
    (y[UX], y[UY])
}

fn ut_dot(a: &Y, b: &Y) -> f64 {
    a[UX] * b[UX] + a[UY] * b[UY]
}

fn ut_norm(y: &Y) -> f64 {
    (y[UX] * y[UX] + y[UY] * y[UY]).sqrt()
}

impl<'a> Integrator<'a> {
    fn new(
        cm: &'a CollisionMatrix,
        u0: DVec3,
        mu: f64,
        e: f64,
        law: Restitution,
        settings: &'a Settings,
    ) -> Self {
        let k = cm.k();
        let k33 = k.z_axis.z;
        let v_scale = u0.length();
        let uz_scale = -u0.z;
        let p_scale = uz_scale / k33;
        Self {
            cm,
            k,
            mu,
            e,
            law,
            settings,
            u0,
            y: [u0.x, u0.y, u0.z, 0.0, 0.0, 0.0, 0.0, 0.0],
            motion: Motion::Slide,
            phase: Phase::Compression,
            h: tol::INITIAL_STEP_REL * (-u0.z) / k33,
            v_scale,
            uz_scale,
            w_scale: uz_scale * p_scale,
            p_scale,
            wz_base: 0.0,
            eps_s: settings.stick_tol * v_scale,
            slope_min: tol::UZ_PARAM_MIN_SLOPE_REL * k33,
            wz_min_uz: tol::WZ_PARAM_MIN_UZ_REL * v_scale,
            stable: cm.stable_sticking(mu),
            wc: 0.0,
            p_mc: 0.0,
            sticking: None,
            stats: Stats::default(),
            trace: settings.record_trace.then(Vec::new),
        }
    }

    fn finish(self) -> Response {
        let p = DVec3::new(self.y[PX], self.y[PY], self.y[PZ]);
        Response {
            impulse: p,
            velocity: DVec3::new(self.y[UX], self.y[UY], self.y[UZ]),
            initial_velocity: self.u0,
            restitution: self.e,
            law: self.law,
            compression_work: self.wc,
            normal_work: self.wz_base + self.y[WZ],
            work: self.cm.work_of_impulse(self.u0, p),
            path_work: self.y[WT],
            max_compression_impulse: self.p_mc,
            sticking: self.sticking,
            kind: if self.mu == 0.0 {
                ResponseKind::Frictionless
            } else {
                ResponseKind::Integrated
            },
            stats: self.stats,
            trace: self.trace,
        }
    }

    fn mode(&self) -> Mode {
        match self.motion {
            Motion::Slide => Mode::Sliding,
            Motion::Constant { mode, .. } => mode,
        }
    }

    fn record(&mut self, parameter: Parameter) {
        let (phase, mode) = (self.phase, self.mode());
        if let Some(t) = self.trace.as_mut() {
            t.push(TraceSample {
                phase,
                mode,
                parameter,
                normal_impulse: self.y[PZ],
                velocity: DVec3::new(self.y[UX], self.y[UY], self.y[UZ]),
                normal_work: self.wz_base + self.y[WZ],
            });
        }
    }

    // ---------------------------------------------------------------- the collision driver

    fn run(&mut self) -> Result<(), ResponseError> {
        if self.mu == 0.0 {
            // ξ ≡ e_z: du/dp_z = K·e_z, constant (digest §9.4).
            self.motion = Motion::Constant {
                q: DVec3::Z,
                w: self.k.z_axis,
                mode: Mode::Frictionless,
            };
        } else if ut_norm(&self.y) <= self.eps_s {
            self.stick_now()?;
        }
        self.record(Parameter::ClosedForm);
        loop {
            // 1. Compression to u_z = 0.
            self.phase = Phase::Compression;
            if self.motion == Motion::Slide {
                let end = Event {
                    var: Var::Uz,
                    target: 0.0,
                    rising: true,
                    kind: EventKind::End,
                };
                self.run_segment(end, &[], Var::Uz)?;
            }
            if let Motion::Constant { .. } = self.motion {
                self.constant_to_uz(0.0);
            }
            self.y[UZ] = 0.0;
            self.wc = self.wz_base + self.y[WZ];
            self.wz_base = self.wc;
            self.y[WZ] = 0.0;
            self.p_mc = self.y[PZ];
            self.stats.compressions += 1;
            if self.e == 0.0 {
                return Ok(());
            }
            // 2. Restitution.
            match self.law {
                Restitution::Stronge => {
                    // Assumption 2: W_f − W_c = −e²·W_c. The state's W_z now counts from W_c,
                    // so its target is W_r = −e²·W_c.
                    let wr = -self.e * self.e * self.wc;
                    let wf = wr;
                    if let Motion::Constant { .. } = self.motion {
                        self.phase = Phase::Restitution;
                        self.constant_to_wz(wf);
                        return Ok(());
                    }
                    let g = self.cm.lemma3_slope(self.mu);
                    self.wz_min_uz = tol::WZ_PARAM_MIN_UZ_REL * self.v_scale;
                    if g > 0.0 {
                        // Lemma 3: b = √(2·W_r·G); the extension adds at most W_r of normal work.
                        let b = (2.0 * wr * g).sqrt();
                        self.wz_min_uz = self.wz_min_uz.min(b);
                        self.phase = Phase::Extension;
                        let end = Event {
                            var: Var::Uz,
                            target: b,
                            rising: true,
                            kind: EventKind::End,
                        };
                        let guard = Event {
                            var: Var::Wz,
                            target: wf,
                            rising: true,
                            kind: EventKind::FinalWork,
                        };
                        match self.run_segment(end, &[guard], Var::Uz)? {
                            Outcome::Constant => {
                                self.constant_to_wz(wf);
                                return Ok(());
                            }
                            Outcome::Reached(EventKind::FinalWork) => {
                                self.stats.extension_reached_final_work = true;
                                return Ok(());
                            }
                            Outcome::Reached(_) => {}
                        }
                    }
                    if self.restitute(Var::Wz, wf, true)? {
                        continue;
                    }
                    return Ok(());
                }
                Restitution::Newton => {
                    if self.restitute(Var::Uz, -self.e * self.u0.z, true)? {
                        continue;
                    }
                    return Ok(());
                }
                Restitution::Poisson => {
                    // p_z only grows: no recompression to watch for.
                    self.restitute(Var::Pz, (1.0 + self.e) * self.p_mc, false)?;
                    return Ok(());
                }
            }
        }
    }

    /// Restitution until `var` reaches `target` (the restitution law's end point), by the
    /// closed form once the motion has a constant direction. Returns `true` when u_z fell
    /// back to 0 first (if `watch_recompression`): the caller compresses again.
    fn restitute(
        &mut self,
        var: Var,
        target: f64,
        watch_recompression: bool,
    ) -> Result<bool, ResponseError> {
        self.phase = Phase::Restitution;
        if let Motion::Constant { .. } = self.motion {
            self.constant_to(var, target);
            return Ok(false);
        }
        let end = Event {
            var,
            target,
            rising: true,
            kind: EventKind::End,
        };
        let recompression = [self.recompression()];
        let aux: &[Event] = if watch_recompression {
            &recompression
        } else {
            &[]
        };
        match self.run_segment(end, aux, var)? {
            Outcome::Constant => {
                self.constant_to(var, target);
                Ok(false)
            }
            Outcome::Reached(EventKind::Recompression) => Ok(true),
            Outcome::Reached(_) => Ok(false),
        }
    }

    /// The closed-form advance (constant direction) until `var` reaches `target`.
    fn constant_to(&mut self, var: Var, target: f64) {
        match var {
            Var::Uz => self.constant_to_uz(target),
            Var::Wz => self.constant_to_wz(target),
            Var::Pz => self.constant_to_pz(target),
        }
    }

    /// "u_z falls back to 0 during restitution".
    fn recompression(&self) -> Event {
        Event {
            var: Var::Uz,
            target: 0.0,
            rising: false,
            kind: EventKind::Recompression,
        }
    }

    // ---------------------------------------------------------------- sticking

    /// u_t has reached the origin: decide stable sticking or the diverging ray (Theorems 9, 16)
    /// and switch to the constant-direction motion.
    fn stick_now(&mut self) -> Result<(), ResponseError> {
        self.y[UX] = 0.0;
        self.y[UY] = 0.0;
        let (motion, ray) = if self.stable {
            // (3.6): dp/dp_z = K⁻¹e_z/K⁻¹_33, du/dp_z = (0, 0, 1/K⁻¹_33).
            let q = self.cm.sticking_direction();
            let w = DVec3::new(0.0, 0.0, self.cm.sticking_normal_slope());
            (
                Motion::Constant {
                    q,
                    w,
                    mode: Mode::Sticking,
                },
                None,
            )
        } else {
            match rays::rays(&self.k, self.mu).diverging() {
                Some(r) if r.normal_slope > 0.0 => {
                    // Theorem 16: sliding resumes along β with constant direction.
                    let q = sliding_vector(self.mu, r.theta);
                    (
                        Motion::Constant {
                            q,
                            w: self.k * q,
                            mode: Mode::Ray { theta: r.theta },
                        },
                        Some(r.theta),
                    )
                }
                _ if !self.cm.is_singular() => {
                    // Only on the stability boundary, to rounding: the sticking impulse is on
                    // the cone's edge. Clamp it into the cone.
                    let mut q = self.cm.sticking_direction();
                    let t = (q.x * q.x + q.y * q.y).sqrt();
                    if t > self.mu {
                        q.x *= self.mu / t;
                        q.y *= self.mu / t;
                    }
                    let mut w = self.k * q;
                    w.x = 0.0;
                    w.y = 0.0;
                    (
                        Motion::Constant {
                            q,
                            w,
                            mode: Mode::Sticking,
                        },
                        None,
                    )
                }
                _ => return Err(ResponseError::NoSlidingDirection),
            }
        };
        self.motion = motion;
        self.sticking = Some(Sticking {
            normal_impulse: self.y[PZ],
            phase: self.phase,
            stable: ray.is_none(),
            ray,
        });
        Ok(())
    }

    // ---------------------------------------------------------------- closed forms

    /// Advances by Δp_z = `dpz` along the constant direction; W_z is set by the caller's exact
    /// formula.
    fn advance_constant(&mut self, dpz: f64) {
        let Motion::Constant { q, w, .. } = self.motion else {
            return;
        };
        self.advance_along(q, w, dpz);
    }

    /// Advances by Δp_z = `dpz` with dp/dp_z = q, du/dp_z = w = K·q constant; W_z by (3.11)
    /// (dW_z/dp_z = u_z, linear in p_z).
    fn advance_along(&mut self, q: DVec3, w: DVec3, dpz: f64) {
        let u = DVec3::new(self.y[UX], self.y[UY], self.y[UZ]);
        self.y[WZ] += u.z * dpz + 0.5 * w.z * dpz * dpz;
        // ∫ u·q dp_z with u linear in p_z (Theorem 10).
        self.y[WT] += u.dot(q) * dpz + 0.5 * w.dot(q) * dpz * dpz;
        self.y[UX] += w.x * dpz;
        self.y[UY] += w.y * dpz;
        self.y[UZ] += w.z * dpz;
        self.y[PX] += q.x * dpz;
        self.y[PY] += q.y * dpz;
        self.y[PZ] += dpz;
    }

    fn sigma(&self) -> f64 {
        match self.motion {
            Motion::Constant { w, .. } => w.z,
            Motion::Slide => f64::NAN,
        }
    }

    /// Closed form in the u_z parameter to u_z = `target`: (3.10) for u_t, and
    /// (3.13)/(3.14) with (3.11) for W_z: `W_z(b) = W_z(a) + (b² − a²)/(2σ)`.
    fn constant_to_uz(&mut self, target: f64) {
        let sigma = self.sigma();
        let a = self.y[UZ];
        if target <= a {
            return;
        }
        let dpz = (target - a) / sigma;
        let wz = self.y[WZ] + (target * target - a * a) / (2.0 * sigma);
        self.advance_constant(dpz);
        self.y[UZ] = target;
        self.y[WZ] = wz;
        self.record(Parameter::ClosedForm);
    }

    /// Closed form in the W_z parameter to W_z = `target` (u_z ≥ 0): (3.12),
    /// `u_z(b) = √(u_z(a)² + 2σ(b − a))`, then (3.10) for u_t.
    fn constant_to_wz(&mut self, target: f64) {
        let sigma = self.sigma();
        let (a, uz) = (self.y[WZ], self.y[UZ]);
        if target <= a {
            return;
        }
        let uzb = (uz * uz + 2.0 * sigma * (target - a)).sqrt();
        self.advance_constant((uzb - uz) / sigma);
        self.y[UZ] = uzb;
        self.y[WZ] = target;
        self.record(Parameter::ClosedForm);
    }

    /// Closed form in p_z to p_z = `target` (Poisson): (3.10), and (3.11) for W_z since
    /// dW_z/dp_z = u_z is linear in p_z.
    fn constant_to_pz(&mut self, target: f64) {
        let sigma = self.sigma();
        let dpz = target - self.y[PZ];
        if dpz <= 0.0 {
            return;
        }
        let wz = self.y[WZ] + self.y[UZ] * dpz + 0.5 * sigma * dpz * dpz;
        self.advance_constant(dpz);
        self.y[PZ] = target;
        self.y[WZ] = wz;
        self.record(Parameter::ClosedForm);
    }

    // ---------------------------------------------------------------- sliding integration

    /// du_z/dp_z = k_z·ξ(θ) at state y (sliding).
    fn uz_slope(&self, y: &Y) -> f64 {
        let r = ut_norm(y);
        if r.is_nan() || r <= 0.0 {
            return f64::NAN;
        }
        let k = &self.k;
        k.z_axis.z - self.mu * (k.z_axis.x * y[UX] + k.z_axis.y * y[UY]) / r
    }

    /// dσ/dp_z = −D(θ)/|u_t| = −(u_t·u_t′)/|u_t|² for σ = −ln|u_t| (Theorem 14's D).
    fn log_r_slope(&self, y: &Y) -> f64 {
        let (ux, uy) = ut(y);
        let r2 = ux * ux + uy * uy;
        if r2.is_nan() || r2 <= 0.0 {
            return f64::NAN;
        }
        let r = r2.sqrt();
        let du = self.k * DVec3::new(-self.mu * ux / r, -self.mu * uy / r, 1.0);
        -(ux * du.x + uy * du.y) / r2
    }

    /// dγ/dp_z for parameter `param` at y.
    fn slope(&self, param: Param, y: &Y) -> f64 {
        match param {
            Param::Pz => 1.0,
            Param::Uz => self.uz_slope(y),
            Param::Wz => y[UZ],
            Param::LogR => self.log_r_slope(y),
        }
    }

    /// The right-hand side dy/dγ for parameter `param` (Theorem 8, (3.7), (3.8), (3.9)).
    fn deriv(&mut self, y: &Y, param: Param) -> Result<Y, Step> {
        self.stats.evaluations += 1;
        let (ux, uy) = ut(y);
        let r2 = ux * ux + uy * uy;
        if r2.is_nan() || r2 <= 0.0 {
            return Err(Step::Origin);
        }
        let mu_r = self.mu / r2.sqrt();
        let xi = DVec3::new(-mu_r * ux, -mu_r * uy, 1.0); // Definition 2
        let du = self.k * xi; // Theorem 8
        let g = match param {
            Param::Pz => 1.0,
            Param::Uz => du.z,
            Param::Wz => y[UZ],
            Param::LogR => -(ux * du.x + uy * du.y) / r2,
        };
        if g.is_nan() || g <= 0.0 {
            return Err(Step::BadSlope);
        }
        let inv = 1.0 / g;
        let udotxi = ux * xi.x + uy * xi.y + y[UZ];
        let mut out = [
            du.x * inv,
            du.y * inv,
            du.z * inv,
            y[UZ] * inv, // (3.7)
            xi.x * inv,
            xi.y * inv,
            inv,
            udotxi * inv, // Theorem 10
        ];
        // The parameter's own derivative is exactly 1.
        match param {
            Param::Uz => out[UZ] = 1.0,
            Param::Wz => out[WZ] = 1.0,
            Param::Pz | Param::LogR => {}
        }
        Ok(out)
    }

    /// One Cash–Karp step of size `h` (in the units of `param`) from `y0`.
    fn rk_step(&mut self, y0: &Y, param: Param, h: f64) -> Step {
        fn comb<const M: usize>(y0: &Y, h: f64, c: [f64; M], k: [&Y; M]) -> Y {
            let mut out = *y0;
            for (i, o) in out.iter_mut().enumerate() {
                let mut s = 0.0;
                for j in 0..M {
                    s += c[j] * k[j][i];
                }
                *o += h * s;
            }
            out
        }
        macro_rules! d {
            ($y:expr) => {
                match self.deriv(&$y, param) {
                    Ok(v) => v,
                    Err(s) => return s,
                }
            };
        }
        let k1 = d!(*y0);
        let k2 = d!(comb(y0, h, [A21], [&k1]));
        let k3 = d!(comb(y0, h, [A31, A32], [&k1, &k2]));
        let k4 = d!(comb(y0, h, [A41, A42, A43], [&k1, &k2, &k3]));
        let k5 = d!(comb(y0, h, [A51, A52, A53, A54], [&k1, &k2, &k3, &k4]));
        let k6 = d!(comb(
            y0,
            h,
            [A61, A62, A63, A64, A65],
            [&k1, &k2, &k3, &k4, &k5]
        ));
        let y = comb(y0, h, [B1, B3, B4, B6], [&k1, &k3, &k4, &k6]);
        let err_of =
            |i: usize| (h * (D1 * k1[i] + D3 * k3[i] + D4 * k4[i] + D5 * k5[i] + D6 * k6[i])).abs();
        // Near the tangential origin the error is also bounded relative to |u_t| (at the step's
        // start, down to ε_s): the flow there is scale invariant (u_t′ depends on θ only), and
        // an absolute tolerance alone lets the steps chatter around the origin instead of
        // landing on it. The relative bound only bites for |u_t| < rtol·|u₀|/NEAR_ORIGIN_RTOL,
        // where the increments left are themselves within the absolute tolerance.
        let tol_u = (self.settings.rtol * self.v_scale)
            .min(tol::NEAR_ORIGIN_RTOL * ut_norm(y0).max(self.eps_s));
        let tol_uz = self.settings.rtol * self.uz_scale;
        let tol_w = self.settings.rtol * self.w_scale;
        let err = (err_of(UX) / tol_u)
            .max(err_of(UY) / tol_u)
            .max(err_of(UZ) / tol_uz)
            .max(err_of(WZ) / tol_w);
        if !(y.iter().all(|v| v.is_finite()) && err.is_finite()) {
            return Step::BadSlope;
        }
        Step::Done { y, err }
    }

    fn bump(&mut self) -> Result<(), ResponseError> {
        self.stats.attempts += 1;
        if self.stats.attempts > self.settings.max_steps {
            return Err(ResponseError::StepLimit {
                limit: self.settings.max_steps,
            });
        }
        Ok(())
    }

    fn check_h(&self) -> Result<(), ResponseError> {
        if self.h.is_nan() || self.h < tol::MIN_STEP_REL * self.p_scale {
            return Err(ResponseError::StepUnderflow {
                normal_impulse: self.y[PZ],
            });
        }
        Ok(())
    }

    /// Picks the parameter for the next step: σ = −ln|u_t| while the sliding velocity heads
    /// into the tangential origin; otherwise the phase's preferred one where it is valid and
    /// well conditioned, p_z where it is not.
    fn choose(&self, prefer: Var, end: &Event) -> Param {
        if self.eps_s > 0.0
            && ut_norm(&self.y) <= tol::LOG_R_MAX_REL * self.v_scale
            && self.heads_into_origin(&self.y)
        {
            return Param::LogR;
        }
        let g = self.uz_slope(&self.y);
        match prefer {
            Var::Pz => Param::Pz,
            Var::Uz => {
                let room = end.var != Var::Uz || end.target > self.y[UZ];
                if g >= self.slope_min && room {
                    Param::Uz
                } else {
                    Param::Pz
                }
            }
            Var::Wz => {
                let uz = self.y[UZ];
                if g >= self.slope_min && uz > 0.0 && uz >= self.wz_min_uz {
                    Param::Wz
                } else {
                    Param::Pz
                }
            }
        }
    }

    /// Whether u_t′ points into the origin within [`tol::LOG_R_INWARD_COS`]: −D(θ) ≥
    /// cos·|u_t′|.
    fn heads_into_origin(&self, y: &Y) -> bool {
        let (ux, uy) = ut(y);
        let r = (ux * ux + uy * uy).sqrt();
        if r.is_nan() || r <= 0.0 {
            return false;
        }
        let du = self.k * DVec3::new(-self.mu * ux / r, -self.mu * uy / r, 1.0);
        let inward = -(ux * du.x + uy * du.y) / r;
        inward >= tol::LOG_R_INWARD_COS * (du.x * du.x + du.y * du.y).sqrt()
    }

    fn accept(&mut self, y: Y, param: Param) {
        self.y = y;
        self.uz_scale = self.uz_scale.max(y[UZ].abs());
        self.w_scale = self.w_scale.max((self.wz_base + y[WZ]).abs());
        self.stats.accepted += 1;
        if param == Param::Pz {
            self.stats.normal_impulse_steps += 1;
        }
        self.record(param.parameter());
    }

    /// Integrates while sliding until `end` or one of `aux` happens, or sliding stops.
    fn run_segment(
        &mut self,
        end: Event,
        aux: &[Event],
        prefer: Var,
    ) -> Result<Outcome, ResponseError> {
        let mut force_pz = false;
        loop {
            if let Motion::Constant { .. } = self.motion {
                return Ok(Outcome::Constant);
            }
            if end.var != Var::Uz && end.phi(&self.y) >= 0.0 {
                // Already at the end (e.g. W_z = W_f on entry).
                return Ok(Outcome::Reached(end.kind));
            }
            if let Some(outcome) = self.ray_approach(&end, aux)? {
                return Ok(outcome);
            }
            self.check_h()?;
            let param = if force_pz {
                Param::Pz
            } else {
                self.choose(prefer, &end)
            };
            force_pz = false;
            let y0 = self.y;
            let g0 = self.slope(param, &y0);
            let mut h = self.h * g0;
            let mut clipped = false;
            if param.var() == Some(end.var) {
                let rem = end.target - y0[end.var.index()];
                if rem <= 0.0 {
                    self.y[end.var.index()] = end.target;
                    return Ok(Outcome::Reached(end.kind));
                }
                if h >= rem {
                    h = rem;
                    clipped = true;
                }
            }
            // σ = −ln|u_t| ends where |u_t| = ε_s: sliding stops there.
            let mut to_stick = false;
            if param == Param::LogR {
                let rem = (ut_norm(&y0) / self.eps_s).ln();
                if rem.is_nan() || rem <= 0.0 {
                    self.stick_now()?;
                    return Ok(Outcome::Constant);
                }
                if h >= rem {
                    h = rem;
                    to_stick = true;
                }
            }
            self.bump()?;
            let full = match self.rk_step(&y0, param, h) {
                Step::BadSlope => {
                    self.stats.rejected += 1;
                    self.h *= STEP_RETRY_FACTOR;
                    force_pz = true;
                    continue;
                }
                Step::Origin => None,
                Step::Done { y, err } => (ut_dot(&y0, &y) > 0.0).then_some((y, err)),
            };
            // The candidate step: the full one, or (if it crossed the tangential origin) the
            // part up to the origin.
            let (h_taken, y, err, crossing) = match full {
                Some((y, err)) => (h, y, err, false),
                None => match self.locate_origin(param, h)? {
                    Some((hl, yl, el)) => {
                        clipped = false;
                        to_stick = false;
                        (hl, yl, el, true)
                    }
                    None => {
                        self.stats.rejected += 1;
                        self.h *= STEP_RETRY_FACTOR * STEP_RETRY_FACTOR;
                        continue;
                    }
                },
            };
            if err > 1.0 {
                self.stats.rejected += 1;
                let f = (STEP_SAFETY * err.powf(ERR_EXP_SHRINK)).max(STEP_SHRINK_MIN);
                self.h = if crossing {
                    STEP_RETRY_FACTOR * h_taken / g0
                } else {
                    self.h * f
                };
                continue;
            }
            // Events in variables other than the parameter: locate the earliest.
            let mut first: Option<(f64, Y, Event)> = None;
            for ev in std::iter::once(&end).chain(aux.iter()) {
                if param.var() == Some(ev.var) || !ev.crossed(&y0, &y) {
                    continue;
                }
                let (he, ye) = self.locate_event(&y0, &y, param, h_taken, ev)?;
                if first.as_ref().is_none_or(|f| he < f.0) {
                    first = Some((he, ye, *ev));
                }
            }
            if let Some((_, mut ye, ev)) = first {
                ye[ev.var.index()] = ev.target;
                self.accept(ye, param);
                return Ok(Outcome::Reached(ev.kind));
            }
            let mut y = y;
            if clipped {
                y[end.var.index()] = end.target;
            }
            self.accept(y, param);
            if to_stick || ut_norm(&self.y) <= self.eps_s {
                self.stick_now()?;
                return Ok(Outcome::Constant);
            }
            if clipped {
                return Ok(Outcome::Reached(end.kind));
            }
            let g1 = self.slope(param, &self.y);
            let g = if g1 > 0.0 && g1.is_finite() { g1 } else { g0 };
            let grow = if crossing {
                1.0 // passed beside the origin: no growth
            } else if err > 0.0 {
                (STEP_SAFETY * err.powf(ERR_EXP_GROW)).min(STEP_GROW_MAX)
            } else {
                STEP_GROW_MAX
            };
            self.h = h_taken * grow / g;
        }
    }

    /// If the sliding velocity has settled onto a ray of constant sliding direction θ_c
    /// (Theorem 14) that attracts it, the rest follows in closed form, as after unstable
    /// sticking (Observation 1): along the ray dp/dp_z = ξ(θ_c) and du/dp_z = K·ξ(θ_c) are
    /// constant. This is exactly where the sliding integration is stiff and slow: the
    /// direction relaxes onto the ray at a rate |X′(θ_c)|/|u_t|.
    ///
    /// - A **converging** ray (D < 0) heading into the origin is followed to the origin (or the
    ///   first event on the way), where sliding stops and Theorem 9 decides as usual.
    /// - A **diverging** ray (D > 0) is followed for the rest of the collision (the direction
    ///   then stays constant, [`Mode::Ray`]), like the thesis's treatment after unstable
    ///   sticking.
    ///
    /// Taken only when the neglected deviation δθ = θ − θ_c cannot matter: its effect on p
    /// is about μ·|δθ|·|u_t|/(|X′| ± D) (δθ decays like a power of |u_t|), so
    /// `|u_t|·|sin δθ|·(1 + μ‖K‖/(|X′| ± D))` must not exceed [`tol::RAY_SNAP_TOL`]·rtol·|u₀|,
    /// and on a diverging ray the attraction must dominate, |X′| ≥ 2D. Returns `None` if not
    /// applicable.
    fn ray_approach(
        &mut self,
        end: &Event,
        aux: &[Event],
    ) -> Result<Option<Outcome>, ResponseError> {
        if self.mu == 0.0 {
            return Ok(None);
        }
        let (ux, uy) = ut(&self.y);
        let r = (ux * ux + uy * uy).sqrt();
        if r.is_nan() || r <= 0.0 {
            return Ok(None);
        }
        // Cheap pre-test: near a ray X(θ) = û × u_t′ is small compared with the size of the
        // u_t′ ellipse (no trigonometry: û = u_t/|u_t|).
        let xi = DVec3::new(-self.mu * ux / r, -self.mu * uy / r, 1.0);
        let du = self.k * xi;
        let x0 = (ux * du.y - uy * du.x) / r;
        let size = rays::ellipse_size(&self.k, self.mu);
        if x0.is_nan() || x0.abs() > tol::RAY_SNAP_PRETEST * size {
            return Ok(None);
        }
        let theta = uy.atan2(ux);
        let Some(tc) = rays::polish_ray(&self.k, self.mu, theta) else {
            return Ok(None);
        };
        let d = rays::dot_term(&self.k, self.mu, tc);
        let xp = rays::cross_term_slope(&self.k, self.mu, tc);
        let (sd, cd) = (theta - tc).sin_cos();
        // u_t on the ray's side; attracting or neutral in θ (X′ ≤ 0; X ≡ 0 for an isotropic,
        // uncoupled K); and the sliding speed really changing along it (a singular M can give
        // "rays" with u_t′ = 0).
        if !(cd > 0.0 && xp <= 0.0 && d.abs() > tol::RAY_MIN_DOT_REL * size) {
            return Ok(None);
        }
        let relax = if d < 0.0 {
            d.abs() + xp.abs()
        } else if xp.abs() >= tol::RAY_DIVERGING_MIN_ATTRACTION * d {
            xp.abs() - d
        } else {
            return Ok(None);
        };
        let knorm = crate::body::max_abs(&self.k) * 3.0; // ≥ ‖K‖₂ for a 3×3 matrix
        let amplification = 1.0 + self.mu * knorm / relax;
        let neglected = r * sd.abs() * amplification;
        if neglected.is_nan() || neglected > tol::RAY_SNAP_TOL * self.settings.rtol * self.v_scale {
            return Ok(None);
        }
        let q = sliding_vector(self.mu, tc);
        let w = self.k * q;
        self.stats.ray_approaches += 1;
        if d > 0.0 {
            // Theorem 17: du_z/dp_z > 0 on a diverging ray, so the closed forms apply.
            self.motion = Motion::Constant {
                q,
                w,
                mode: Mode::Ray { theta: tc },
            };
            return Ok(Some(Outcome::Constant));
        }
        // Aim exactly at the origin rather than along the ray, so that no residual u_t is left
        // to discard: the constant impulse direction q = (q_t, 1) with |q_t| = μ (sliding
        // friction) and K·q tangential to −u_t, i.e. M·q_t + s = −λ·u_t, λ > 0. It differs from
        // ξ(θ_c) by O(δθ); the origin is Δp_z = 1/λ away.
        let (q, w, to_origin) = match self.aim_at_origin(ux, uy) {
            Some(aim) => aim,
            None => {
                // u_t·û_c decreases at rate |D| along the ray.
                let t = (ux * tc.cos() + uy * tc.sin()) / -d;
                (q, w, t)
            }
        };
        if !(to_origin.is_finite() && to_origin >= 0.0) {
            return Ok(None);
        }
        let mut first: Option<(f64, Event)> = None;
        for ev in std::iter::once(end).chain(aux.iter()) {
            if let Some(dl) = self.first_crossing(ev, w, to_origin)
                && first.as_ref().is_none_or(|f| dl < f.0)
            {
                first = Some((dl, *ev));
            }
        }
        if let Some((dl, ev)) = first {
            self.advance_along(q, w, dl);
            self.y[ev.var.index()] = ev.target;
            self.record(Parameter::ClosedForm);
            return Ok(Some(Outcome::Reached(ev.kind)));
        }
        self.advance_along(q, w, to_origin);
        self.record(Parameter::ClosedForm);
        // u_t is now 0 to rounding (or, without an aimed direction, the perpendicular residual
        // r·|sin δθ|, within tolerance).
        self.stick_now()?;
        Ok(Some(Outcome::Constant))
    }

    /// The constant sliding impulse direction q = (q_t, 1), |q_t| = μ, that takes u_t straight
    /// to the origin: M·q_t + s = −λ·(u_x, u_y) with λ > 0, q_t = −M⁻¹(s + λ·u_t), solving
    /// |M⁻¹s + λ·M⁻¹u_t|² = μ² for λ. Returns (q, K·q, 1/λ), or `None` if M is singular or
    /// there is no such λ.
    fn aim_at_origin(&self, ux: f64, uy: f64) -> Option<(DVec3, DVec3, f64)> {
        let k = &self.k;
        let (a, b, f) = (k.x_axis.x, k.y_axis.y, k.y_axis.x);
        let (se, sd) = (k.z_axis.x, k.z_axis.y);
        let det = a * b - f * f;
        if det.is_nan() || det <= tol::RANK_TOL_REL * (a * b).abs() {
            return None;
        }
        let minv = |x: f64, y: f64| ((b * x - f * y) / det, (a * y - f * x) / det);
        let (p1, p2) = minv(ux, uy); // M⁻¹u_t
        let (s1, s2) = minv(se, sd); // M⁻¹s
        let aa = p1 * p1 + p2 * p2;
        let ab = p1 * s1 + p2 * s2;
        let cc = s1 * s1 + s2 * s2 - self.mu * self.mu;
        let disc = ab * ab - aa * cc;
        if !(aa > 0.0 && disc >= 0.0) {
            return None;
        }
        let lambda = (-ab + disc.sqrt()) / aa;
        if !(lambda > 0.0 && lambda.is_finite()) {
            return None;
        }
        let q = DVec3::new(-(s1 + lambda * p1), -(s2 + lambda * p2), 1.0);
        Some((q, *k * q, 1.0 / lambda))
    }

    /// The smallest Δp_z ∈ (0, `max`] at which `ev` happens when moving with du/dp_z = `w`
    /// (constant): u_z and p_z are linear in Δ, W_z quadratic (3.11).
    fn first_crossing(&self, ev: &Event, w: DVec3, max: f64) -> Option<f64> {
        let sign = if ev.rising { 1.0 } else { -1.0 };
        // φ(Δ) = c0 + c1·Δ + c2·Δ², φ(0) = current value.
        let (c0, c1, c2) = match ev.var {
            Var::Uz => (self.y[UZ] - ev.target, w.z, 0.0),
            Var::Pz => (self.y[PZ] - ev.target, 1.0, 0.0),
            Var::Wz => (self.y[WZ] - ev.target, self.y[UZ], 0.5 * w.z),
        };
        let (c0, c1, c2) = (sign * c0, sign * c1, sign * c2);
        if c0 > 0.0 || (c0 == 0.0 && ev.rising) {
            return None; // already past, or (rising) starting on the target: not an event
        }
        let roots = crate::rays::real_roots(&[c0, c1, c2]);
        roots
            .into_iter()
            .filter(|&r| r >= 0.0 && r <= max)
            .filter(|&r| {
                // The crossing must be upward in φ (a touch is not a crossing).
                c1 + 2.0 * c2 * r > 0.0
            })
            .min_by(f64::total_cmp)
    }

    /// The step of size `h_hi` from the current state crossed (or touched) the origin of the
    /// tangential plane. Finds the step h* ending at u_t = 0 by regula falsi (Illinois) on
    /// φ(h) = u_t(h)·û_t(0), which is linear in h for a straight approach, stopping once the
    /// end point is within ε_s of the origin. Returns the longest non-crossing step found (size,
    /// state, error estimate); the caller sticks if its end is within ε_s of the origin,
    /// otherwise the path passes beside the origin and integration continues from there.
    /// `None` if no non-crossing step was found.
    fn locate_origin(
        &mut self,
        param: Param,
        h_hi: f64,
    ) -> Result<Option<(f64, Y, f64)>, ResponseError> {
        let y0 = self.y;
        let r0 = ut_norm(&y0);
        let (mut lo, mut hi) = (0.0f64, h_hi);
        let (mut phi_lo, mut phi_hi) = (r0, f64::NAN);
        let mut y_lo = y0;
        let mut err_lo = 0.0;
        let mut last_side = 0i8;
        for _ in 0..tol::MAX_EVENT_ITERATIONS {
            if lo > 0.0 && ut_norm(&y_lo) <= self.eps_s {
                break;
            }
            let width = hi - lo;
            if width <= tol::BRACKET_ULPS * f64::EPSILON * hi {
                break;
            }
            let mut ht = if phi_hi.is_finite() && phi_hi < phi_lo {
                lo + phi_lo * width / (phi_lo - phi_hi)
            } else {
                lo + 0.5 * width
            };
            if !(ht > lo && ht < hi) {
                ht = lo + 0.5 * width;
            }
            self.bump()?;
            self.stats.event_iterations += 1;
            match self.rk_step(&y0, param, ht) {
                Step::Done { y, err } if ut_dot(&y0, &y) > 0.0 => {
                    lo = ht;
                    phi_lo = ut_dot(&y0, &y) / r0;
                    y_lo = y;
                    err_lo = err;
                    if last_side == 1 {
                        phi_hi *= 0.5; // Illinois: halve the stale end's value
                    }
                    last_side = 1;
                }
                Step::Done { y, .. } => {
                    hi = ht;
                    phi_hi = ut_dot(&y0, &y) / r0;
                    if last_side == -1 {
                        phi_lo *= 0.5;
                    }
                    last_side = -1;
                }
                Step::BadSlope | Step::Origin => {
                    hi = ht;
                    phi_hi = f64::NAN;
                    last_side = -1;
                }
            }
        }
        Ok((lo > 0.0).then_some((lo, y_lo, err_lo)))
    }

    /// Locates the step h* ∈ (0, h] at which `ev` happens (regula falsi, Illinois), returning
    /// (h*, state). `y_hi` is the state after the full step h.
    fn locate_event(
        &mut self,
        y0: &Y,
        y_hi: &Y,
        param: Param,
        h: f64,
        ev: &Event,
    ) -> Result<(f64, Y), ResponseError> {
        let (mut lo, mut hi) = (0.0f64, h);
        let (mut f_lo, mut f_hi) = (ev.phi(y0), ev.phi(y_hi));
        if f_lo >= 0.0 {
            return Ok((0.0, *y0));
        }
        let mut y_best = *y_hi;
        let mut best = (f_hi.abs(), hi);
        let scale = match ev.var {
            Var::Uz => self.uz_scale,
            Var::Wz => self.w_scale,
            Var::Pz => self.p_scale,
        };
        let mut last_side = 0i8;
        for _ in 0..tol::MAX_EVENT_ITERATIONS {
            if best.0 <= tol::EVENT_TOL_REL * scale
                || hi - lo <= tol::BRACKET_ULPS * f64::EPSILON * hi
            {
                break;
            }
            let mut ht = lo - f_lo * (hi - lo) / (f_hi - f_lo);
            if !(ht > lo && ht < hi) {
                ht = 0.5 * (lo + hi);
            }
            self.bump()?;
            self.stats.event_iterations += 1;
            let Step::Done { y, .. } = self.rk_step(y0, param, ht) else {
                hi = ht;
                continue;
            };
            let f = ev.phi(&y);
            if f.abs() < best.0 {
                best = (f.abs(), ht);
                y_best = y;
            }
            if f < 0.0 {
                lo = ht;
                f_lo = f;
                if last_side == 1 {
                    f_hi *= 0.5; // Illinois: halve the stale end's value
                }
                last_side = 1;
            } else {
                hi = ht;
                f_hi = f;
                if last_side == -1 {
                    f_lo *= 0.5;
                }
                last_side = -1;
            }
        }
        Ok((best.1, y_best))
    }
}

#[cfg(test)]
mod tests;
