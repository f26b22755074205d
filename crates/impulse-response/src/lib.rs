//! # impulse-response — layer 1 of the `impulse` workspace
//!
//! **Owns** collision response (Mirtich 1996, thesis chapter 3): given the collision matrix K of
//! a contact, the pre-collision relative contact velocity u₀, the friction coefficient μ and a
//! restitution coefficient e, it computes the collision impulse p by integrating the relative
//! contact velocity through the collision (§3.3), with Coulomb friction, Stronge's energetic
//! restitution and exact handling of sticking.
//!
//! - [`CollisionMatrix`]: a validated K in the collision frame, its (pseudo-)inverse, the
//!   stable-sticking test (Theorem 9) and Lemma 3's bound ([`matrix`]);
//! - [`Body`], [`ContactFrame`], [`collision_matrix_world`]: K of two rigid bodies (eq. 3.4),
//!   built in world axes and rotated into the collision frame ([`body`]);
//! - [`rays`]: rays of constant sliding direction (Theorem 14, Corollary 2) and the unique
//!   diverging ray after unstable sticking (Theorem 16);
//! - [`resolve`]: the collision integration (compression in u_z, extension, restitution in W_z,
//!   p_z where those are not valid; closed forms after sticking, Observation 1), with Stronge,
//!   Poisson or Newton restitution ([`integrate`]);
//! - [`resolve_with_microcollisions`]: static contact by microcollisions (§3.5): boosted
//!   restitution and the reversing impulse ([`micro`]);
//! - [`mod@reference`]: a slow, simple p_z-parameterised oracle used to check [`resolve`];
//! - [`contact`]: sustained contact as constraints \[not in seed; thesis §8.1's remedy\]: the
//!   impulses of an island of bodies over one time step, projected Gauss–Seidel with the exact
//!   Coulomb cone ([`solve_contacts`]).
//!
//! **Must not know** how K was made: shapes, contact detection, multibodies, worlds. The same
//! code serves two rigid bodies (Theorem 6: K symmetric positive definite) and, later,
//! multibodies, whose K may be singular (handled by the SVD pseudo-inverse, see
//! [`CollisionMatrix`]). It depends on `impulse-geom` (glam re-exports), faer (SVD) and
//! thiserror.
//!
//! ## Conventions (thesis §3.2)
//! The collision frame has its z axis along the contact normal, **pointing from body 2 towards
//! body 1**; u = u₁ − u₂ is the velocity of body 1's contact point relative to body 2's, so
//! u_z < 0 means approaching. p is the impulse body 2 gives body 1 (body 2 receives −p). All
//! vectors given to and returned by [`resolve`] are in the collision frame; [`ContactFrame`]
//! converts. Units: any consistent set (K is 1/mass, u is velocity, p is impulse, work is
//! energy). f64 throughout, no fused multiply-add.
//!
//! Equation numbers in comments, e.g. `eq. (3.4)`, are the thesis's.
#![forbid(unsafe_code)]

pub mod body;
pub mod contact;
pub mod integrate;
pub mod matrix;
pub mod micro;
pub mod rays;
pub mod reference;

pub use body::{
    Body, ContactFrame, collision_matrix_world, cross_matrix, relative_contact_velocity,
};
pub use contact::{
    Contact, DEFAULT_ACCELERATION, IslandBody, Member, SolveReport, SolverSettings, System,
    solve_contacts, solve_island,
};
pub use integrate::{
    Mode, Parameter, Phase, Response, ResponseKind, Restitution, Settings, Stats, Sticking,
    TraceSample, resolve,
};
pub use matrix::CollisionMatrix;
pub use micro::{MicrocollisionParams, resolve_with_microcollisions};

/// Why a collision could not be resolved: bad input, named, or an integration that hit its
/// bounds. Never a panic.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ResponseError {
    /// An input is NaN or infinite.
    #[error("{what} is not finite")]
    NonFinite {
        /// Which input ("collision matrix", "initial velocity", ...).
        what: &'static str,
    },
    /// A scalar parameter is out of its allowed range.
    #[error("invalid {name} = {value}: {requirement}")]
    InvalidParameter {
        /// The parameter's name.
        name: &'static str,
        /// The value given.
        value: f64,
        /// What the value must satisfy.
        requirement: &'static str,
    },
    /// The collision matrix is not symmetric.
    #[error(
        "collision matrix is not symmetric: largest |K_ij - K_ji| = {asymmetry:e} (scale {scale:e})"
    )]
    NotSymmetric {
        /// Largest difference between mirrored entries.
        asymmetry: f64,
        /// Largest entry magnitude.
        scale: f64,
    },
    /// The collision matrix has a negative eigenvalue beyond rounding.
    #[error(
        "collision matrix is not positive semi-definite: eigenvalue {eigenvalue:e} (largest {largest:e})"
    )]
    NotPositiveSemidefinite {
        /// The most negative eigenvalue.
        eigenvalue: f64,
        /// The largest eigenvalue.
        largest: f64,
    },
    /// No impulse can change the normal relative velocity (K_33 ≈ 0, including K = 0: e.g. two
    /// fixed bodies), so the collision cannot be resolved.
    #[error("no impulse can change the normal velocity: K_33 = {k33:e} (scale {scale:e})")]
    NormalUnreachable {
        /// The entry K_33.
        k33: f64,
        /// Largest eigenvalue of K.
        scale: f64,
    },
    /// The bodies are not approaching at the contact (u_z ≥ 0): there is no collision.
    #[error("bodies are not approaching: u_z = {normal_velocity:e} must be < 0")]
    NotApproaching {
        /// The normal component of the initial relative velocity.
        normal_velocity: f64,
    },
    /// A mass is zero, negative or not finite.
    #[error("invalid mass {mass}: must be finite and > 0 (use Body::Fixed for infinite mass)")]
    InvalidMass {
        /// The value given.
        mass: f64,
    },
    /// An inertia tensor is not finite, symmetric and positive definite.
    #[error("invalid inertia tensor: {reason}")]
    InvalidInertia {
        /// What is wrong.
        reason: &'static str,
    },
    /// A contact normal is zero or not finite.
    #[error("invalid contact normal {normal:?}: must be finite and non-zero")]
    InvalidNormal {
        /// The vector given, as [x, y, z].
        normal: [f64; 3],
    },
    /// The integration needed more step attempts than the cap allows.
    #[error("collision integration exceeded {limit} step attempts")]
    StepLimit {
        /// The cap ([`Settings::max_steps`]).
        limit: usize,
    },
    /// The adaptive step size fell below [`tol::MIN_STEP_REL`] of the impulse scale.
    #[error("collision integration step size underflowed at p_z = {normal_impulse:e}")]
    StepUnderflow {
        /// Normal impulse reached.
        normal_impulse: f64,
    },
    /// Sticking is unstable but no diverging ray of constant sliding exists. Impossible for a
    /// positive definite K (Theorem 16); can only happen for a singular K.
    #[error("sticking is unstable and no diverging ray exists (singular collision matrix)")]
    NoSlidingDirection,
    /// The SVD of the collision matrix failed (only possible for non-finite input).
    #[error("SVD of the collision matrix did not converge")]
    Svd,
}

/// Tolerances and limits of this crate, each with its unit, default and reason. Those that a
/// caller may want to change are also fields of [`Settings`] (which defaults to these values).
pub mod tol {
    /// Largest |K_ij − K_ji| accepted, relative to the largest |K_ij|; dimensionless, default
    /// `1e-9`. K built by [`crate::collision_matrix_world`] is symmetric to rounding; a larger
    /// asymmetry means the caller built K wrongly. Accepted matrices are symmetrised.
    pub const K_SYMMETRY_REL: f64 = 1e-9;

    /// Most negative eigenvalue of K accepted (as rounding of a positive semi-definite K),
    /// relative to the largest eigenvalue; dimensionless, default `1e-10`.
    pub const K_PSD_REL: f64 = 1e-10;

    /// Singular values of K below this fraction of the largest are treated as zero (rank
    /// deficiency, Ch. 5: multibody collision matrices); dimensionless, default `1e-11`. A
    /// rigid-body K has a condition number of at most (1 + r²/k²_min) ≲ 1e4 for offsets r a few
    /// radii of gyration k, far from this cut-off.
    pub const RANK_TOL_REL: f64 = 1e-11;

    /// Below this estimate of the reciprocal condition number (det K / trace(K)³, a lower bound
    /// of λ_min/λ_max up to a factor 9), K is inverted by SVD instead of the explicit 3×3 inverse;
    /// dimensionless, default `1e-8`.
    pub const EXPLICIT_INVERSE_MIN_RCOND: f64 = 1e-8;

    /// K_33 must exceed this fraction of K's largest eigenvalue, or no impulse can stop the
    /// approach ([`crate::ResponseError::NormalUnreachable`]); dimensionless, default `1e-12`.
    pub const NORMAL_REACH_REL: f64 = 1e-12;

    /// Relative error tolerance of the adaptive Runge–Kutta integration, default `1e-9`. The
    /// local error of each step is kept below rtol times a scale: |u₀| for the tangential
    /// velocity (and also [`NEAR_ORIGIN_RTOL`]·|u_t| near the tangential origin), the largest
    /// |u_z| so far (at least |u_z0|) for the normal velocity, and the largest |W_z| so far (at
    /// least u_z0²/K_33) for the normal work. Dimensionless. The step count grows like
    /// rtol^(−1/5); 1e-9 gives results to about 1e-8 relative at a mean of ~30 steps.
    pub const DEFAULT_RTOL: f64 = 1e-9;

    /// Sticking tolerance ε_s (thesis §3.3.4, no value given there), relative to |u₀|; default
    /// `1e-12`. Sliding is declared stopped when |u_t| ≤ ε_s·|u₀|; the residual is then set to
    /// zero exactly (so u_f and u₀ + K·p may differ by up to ε_s·|u₀| in the tangential
    /// direction). Straight approaches, and those finished in closed form along a ray, land on
    /// u_t = 0 to rounding; a curved approach integrated in σ = −ln|u_t| ends at exactly ε_s.
    pub const DEFAULT_STICK_TOL_REL: f64 = 1e-12;

    /// Relative error bound on the tangential velocity near the tangential origin, relative to
    /// |u_t|; dimensionless, default `1e-2`. The absolute bound `rtol·|u₀|` alone cannot resolve
    /// the direction of u_t once |u_t| falls below it, and the steps then chatter around the
    /// origin instead of reaching it (digest §11). The remaining increments there are within
    /// the absolute tolerance anyway, so a loose relative bound suffices.
    pub const NEAR_ORIGIN_RTOL: f64 = 1e-2;

    /// The final approach to sticking is integrated in σ = −ln|u_t| while u_t′ points into the
    /// tangential origin within this cosine (−D(θ) ≥ cos·|u_t′|, Theorem 14's D);
    /// dimensionless, default `0.5` (60°). The approach is tangent to a converging ray with a
    /// direction error ∝ |u_t|^λ, not smooth in p_z or u_z; in σ it is.
    pub const LOG_R_INWARD_COS: f64 = 0.5;

    /// Once the sliding velocity heads into the origin along an attracting converging ray, the
    /// rest of the approach is done in closed form along the ray if the neglected deviation
    /// (see `ray_approach` in [`crate::integrate`]) is at most this many local error
    /// tolerances rtol·|u₀|; dimensionless, default `10`. Near such a ray the integration is
    /// stiff (the direction relaxes at a rate ∝ 1/|u_t|).
    pub const RAY_SNAP_TOL: f64 = 10.0;

    /// Pre-test for the closed-form ray approach: |X(θ)| (Theorem 14) at most this fraction of
    /// the u_t′ ellipse's size μ(|K₁₁| + |K₂₂| + |K₁₂|) + |K₁₃| + |K₂₃|; dimensionless, default
    /// `1e-3`. Only then is the nearest ray computed and the real criterion checked.
    pub const RAY_SNAP_PRETEST: f64 = 1e-3;

    /// σ = −ln|u_t| is used only once |u_t| is below this fraction of |u₀|; dimensionless,
    /// default `1e-2`. Farther out the approach is nearly straight and u_z or p_z steps are
    /// cheaper than following the exponential decay in σ.
    pub const LOG_R_MAX_REL: f64 = 1e-2;

    /// A ray is followed in closed form only if its D(θ) (the rate of change of the sliding
    /// speed along it) exceeds this fraction of the u_t′ ellipse's size; dimensionless, default
    /// `1e-9`. Excludes the degenerate "rays" of a singular tangential block M, where u_t′ = 0.
    pub const RAY_MIN_DOT_REL: f64 = 1e-9;

    /// Largest accepted [`crate::Settings::rtol`]; dimensionless, `1e-2` (beyond it the error
    /// estimates of the 4(5) pair are meaningless).
    pub const MAX_RTOL: f64 = 1e-2;

    /// Largest accepted [`crate::Settings::stick_tol`]; dimensionless, `1e-3`.
    pub const MAX_STICK_TOL: f64 = 1e-3;

    /// Step-size controller: safety factor on the step the error estimate predicts;
    /// dimensionless, default `0.9` (Numerical Recipes §16.2).
    pub const STEP_SAFETY: f64 = 0.9;

    /// Step-size controller: largest growth of the step after an accepted one; dimensionless,
    /// default `5`.
    pub const STEP_GROW_MAX: f64 = 5.0;

    /// Step-size controller: largest reduction after a rejected step (error too large);
    /// dimensionless, default `0.1`.
    pub const STEP_SHRINK_MIN: f64 = 0.1;

    /// Step-size factor after a step that could not be evaluated (a stage left the parameter's
    /// domain: k_z·ξ ≤ 0 for u_z, u_z ≤ 0 for W_z) or after a rejected step to the tangential
    /// origin; dimensionless, default `0.5`.
    pub const STEP_RETRY_FACTOR: f64 = 0.5;

    /// Root brackets (events, the tangential origin) stop shrinking at this many ulps of the
    /// step; dimensionless, default `4`.
    pub const BRACKET_ULPS: f64 = 4.0;

    /// A diverging ray is followed in closed form only if it attracts the sliding direction at
    /// least this many times faster than the sliding speed grows along it, |X′(β)| ≥ this·D(β)
    /// (then the neglected deviation decays as |u_t| grows); dimensionless, default `2`.
    pub const RAY_DIVERGING_MIN_ATTRACTION: f64 = 2.0;

    /// Cap on Runge–Kutta step attempts (accepted, rejected and event-location steps) per
    /// collision, default `20_000`. Typical collisions need tens; the cap only guarantees
    /// termination ([`crate::ResponseError::StepLimit`]).
    pub const MAX_STEPS: usize = 20_000;

    /// The u_z (and W_z) parameterisation is used only while du_z/dp_z = k_z·ξ(θ) is at least
    /// this fraction of K_33; below it the integration switches to p_z (Theorem 17 cases and
    /// Lemma 3 violations). Dimensionless, default `0.05`: the u_z equations (3.8) have
    /// 1/(k_z·ξ) in them and become stiff as k_z·ξ → 0.
    pub const UZ_PARAM_MIN_SLOPE_REL: f64 = 0.05;

    /// The restitution uses W_z as its parameter only once u_z exceeds this fraction of |u₀|
    /// (or Lemma 3's b, if smaller), p_z before (3.9 is singular at u_z = 0); this matters
    /// when Lemma 3's extension bound does not exist (G ≤ 0). Dimensionless, default `1e-3`.
    pub const WZ_PARAM_MIN_UZ_REL: f64 = 1e-3;

    /// Event location (u_z = 0, W_z = W_f, u_z = b, ...) stops when the event variable is within
    /// this fraction of its scale; dimensionless, default `1e-14`. The variable is then set to
    /// its target exactly.
    pub const EVENT_TOL_REL: f64 = 1e-14;

    /// Cap on root-finding iterations per event, default `200`.
    pub const MAX_EVENT_ITERATIONS: usize = 200;

    /// First step of the integration, as a fraction of |u_z0|/K_33 (the normal impulse of a
    /// frictionless compression); dimensionless, default `0.1`.
    pub const INITIAL_STEP_REL: f64 = 0.1;

    /// Smallest step accepted, relative to |u_z0|/K_33 (an impulse scale); dimensionless,
    /// default `1e-15`. Below it the integration stops with
    /// [`crate::ResponseError::StepUnderflow`] rather than spin.
    pub const MIN_STEP_REL: f64 = 1e-15;

    /// X ≡ 0 (every direction a ray) when all its trigonometric coefficients are below this
    /// fraction of the u_t′ ellipse's size; dimensionless, default `1e-14`.
    pub const RAY_DEGENERATE_REL: f64 = 1e-14;

    /// Newton polishing of a ray stops when |X(θ)| is below this fraction of the ellipse's
    /// size; dimensionless, default `1e-15`.
    pub const RAY_POLISH_STOP_REL: f64 = 1e-15;

    /// A polished ray is accepted when |X(θ)| is below this fraction of the ellipse's size
    /// (near-tangential roots are ill-conditioned); dimensionless, default `1e-8`.
    pub const RAY_ACCEPT_REL: f64 = 1e-8;

    /// Newton iterations when polishing a ray, default `12`.
    pub const RAY_POLISH_ITERATIONS: usize = 12;

    /// The ray nearest to the sliding direction (for the closed-form ray approach) must lie
    /// within this angle of it; radians, default `0.2`.
    pub const RAY_NEAREST_MAX_ANGLE: f64 = 0.2;

    /// Real roots of a polynomial closer than this, relative to their magnitude, are one
    /// root; dimensionless, default `1e-12`.
    pub const ROOT_MERGE_REL: f64 = 1e-12;

    /// Rays of constant sliding direction closer than this are the same ray; radians, default
    /// `1e-9`.
    pub const RAY_MERGE_ANGLE: f64 = 1e-9;

    /// The one direction the half-angle substitution cannot see, θ₀ + π, is added as a ray
    /// when |X| there is below this fraction of the u_t′ ellipse's size; dimensionless, default
    /// `1e-10` (θ₀ is chosen to make |X(θ₀ + π)| as large as possible, so this only fires when X
    /// is nearly zero in all four axis directions).
    pub const RAY_RESIDUAL_REL: f64 = 1e-10;

    /// A reversing impulse (§3.5) is used only if K·p_r reproduces −2u₀ to this fraction of
    /// |u₀| (always true for a non-singular K; for a singular K, u₀ must lie in K's range); also
    /// the tolerance for e_z lying in a singular K's range (stable sticking needs it);
    /// dimensionless, default `1e-9`.
    pub const REVERSAL_RANGE_REL: f64 = 1e-9;
}
