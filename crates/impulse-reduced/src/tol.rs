//! Every tolerance of the crate, with its unit and its reason. Algorithms take these as
//! defaults of explicit parameters ([`crate::Tsvd`], [`crate::reference::StaticOptions`]); none is a bare
//! literal inside an algorithm.

/// Factor on the truncated-SVD threshold of FORK⁻¹S eq. 9, `ε = max(m, n)·‖A‖₂·ε_mach`
/// (dimensionless): the default of [`crate::Tsvd`] (`impulse reduce --tsvd` replaces it by a
/// relative threshold).
///
/// Eq. 9 bounds the round-off of one SVD of `A`. The matrices reduced here are sums of up to
/// hundreds of congruences `Ad C Adᵀ`, whose accumulated round-off in structurally zero
/// directions is tens of ulp of ‖A‖, above eq. 9's bound; the paper reports tuning the threshold
/// "until the rank matches the expected value". A factor of 10² puts the threshold at ~1e-13·‖A‖
/// for 6×6 blocks: above that round-off, and below the smallest physical singular value met in
/// the acceptance test (random trees with compliances over six decades reach 6e-12·‖C‖, which a
/// factor of 10⁴ wrongly truncates). The end-effector rank is decided on the joints'
/// compliance-weighted motions at the same threshold and reported ([`crate::rank`]).
pub const TSVD_FACTOR: f64 = 1e2;

/// Smallest accepted length of a joint axis before normalisation (the axis's own units, usually
/// a unit vector): shorter axes, the zero vector included, have no reliable direction.
pub const AXIS_MIN_NORM: f64 = 1e-9;

/// Newton's stopping test for the nonlinear statics: the residual (joint-space force balance
/// and loop closure), relative to the scale of the loads and spring forces involved. The
/// 36-link ladder's 19 loops stall at 2e-10 (round-off of the multipliers' sums over the
/// loops); 1e-9 is above that floor and, for the displacements of the tests (≥ 1e-5 of the
/// bounding radius), moves a pose by less than 1e-14 of it.
pub const STATIC_RESIDUAL_REL: f64 = 1e-9;

/// Most Newton iterations of the nonlinear statics per load increment before the increment
/// is halved (with the exact tangent Newton converges in 3–8 iterations from the secant
/// predictor on the bundled and random mechanisms; more means the increment is too large).
pub const STATIC_MAX_ITERATIONS: usize = 30;

/// Smallest backtracking fraction of a Newton step in the nonlinear statics (and the full
/// dynamics' Newton): below it the statics give up the load increment (and halve it); the
/// dynamics take the step anyway (their merit is then flat at round-off level).
pub const STATIC_MIN_STEP: f64 = 1.0 / 1024.0;

/// Armijo's sufficient-decrease fraction of the statics' line search (dimensionless): a
/// step is taken when the merit falls by at least this fraction of the decrease its slope
/// predicts (the usual 1e-4: nearly any decrease).
pub const STATIC_ARMIJO: f64 = 1e-4;

/// Smallest load increment of the statics' continuation, as a fraction of the load path
/// (dimensionless): below it no nearby equilibrium is followed (a limit point, or none) and
/// the solve reports [`crate::Error::NoEquilibrium`]. 2⁻²⁰ ≈ 1e-6: twenty halvings.
pub const STATIC_MIN_LOAD_STEP: f64 = 1.0 / 1_048_576.0;

/// Largest change of a joint coordinate (rad, or lengths over 1 + the bounding radius) the
/// statics' Newton corrector may make from the continuation's predictor before the load
/// increment is halved: the secant predictor is exact to first order, so on the equilibrium
/// branch the correction shrinks with the square of the increment; a larger one means Newton
/// went to another equilibrium. 0.2 rad keeps the increments at a few per radian of
/// deflection.
pub const STATIC_MAX_CORRECTION: f64 = 0.2;

/// Most load increments the statics' continuation takes before giving up (each at least
/// [`STATIC_MIN_LOAD_STEP`] long, growing when Newton converges fast).
pub const STATIC_MAX_LOAD_STEPS: usize = 2000;

/// A load increment whose Newton iteration converged in at most this many iterations lets
/// the next increment double (the secant predictor was good).
pub const STATIC_FAST_ITERATIONS: usize = 4;

/// Below this rotation angle (rad) the coefficients of the derivative of the SO(3) right
/// Jacobian (the statics' exact tangent, `reference::tangent`) are evaluated by their Taylor
/// series through t⁶ (truncation below 1e-15 relative at 0.1); above, by the closed forms,
/// whose cancellation costs ~ε/t² relative (2e-14 at 0.1).
pub const DJR_SERIES_ANGLE: f64 = 0.1;

/// Largest ratio `σ_{r+1}/σ_r` at a rank cut that counts as a clear gap (dimensionless): a
/// model whose end-effector cut (or a merge's) is less clear builds, with a
/// [`crate::RankWarning::SmallGap`]; the accelerability and damping must have a clear gap at
/// the compliance's rank ([`crate::Error::Rank`] otherwise). Round-off directions of the walk
/// sit 11–15 decades below the physical ones in the bundled and random mechanisms; 1e-4
/// separates the two with room on both sides.
pub const RANK_GAP: f64 = 1e-4;

/// Estimated relative accuracy of a model's stiffness `K = C⁺` (cond(C) times the measured
/// round-off of C) above which the construction warns
/// ([`crate::RankWarning::IllConditioned`]): a millionth, where the reduced model's own
/// linearisation error at a relative displacement of 1e-3 starts to be of the same size.
pub const STIFFNESS_ACCURACY_WARN: f64 = 1e-6;

/// Projected Gauss–Seidel sweeps allowed per step (contacts of a few end effectors converge
/// in tens of sweeps; the cap bounds the cost of a badly conditioned step).
pub const PGS_ITERATIONS: usize = 200;

/// PGS stops when no impulse changed by more than this fraction of the largest normal impulse
/// in a sweep (dimensionless).
pub const PGS_TOLERANCE: f64 = 1e-10;

/// Fraction of a penetration removed per step (dimensionless): 0.2 removes it in a few steps
/// without the energy gain of a full correction.
pub const CONTACT_ERP: f64 = 0.2;

/// Default contact margin (m): shape points closer than this to an obstacle are contacts, so
/// a contact is seen one step before it closes. Mechanisms in other units set it explicitly.
pub const CONTACT_MARGIN: f64 = 1e-2;

/// Iterations allowed to the fixed point of a blended model's statics (relaxed passes, see
/// [`BLEND_STATIC_MIN_RELAXATION`], converge more slowly than plain ones). The ladder-36's
/// two-model blend of the Fig. 7 study ([`crate::study::FIG7_SUPPORT`]) at 160 N, past its
/// last sample, needs more than 2000 and settles within 4000 (from the 150 N solution).
pub const BLEND_STATIC_ITERATIONS: usize = 4000;

/// Smallest relaxation factor β of the blended statics' substitution (dimensionless): halving
/// stops here. The bundled mechanisms settle with β between 1/2 and 1/8 at the Fig. 7 loads.
pub const BLEND_STATIC_MIN_RELAXATION: f64 = 1.0 / 64.0;

/// The blended statics stop when the end effectors move less than this in a pass (scaled
/// twist norm, dimensionless: lengths over the bounding radius, angles over π).
pub const BLEND_STATIC_TOLERANCE: f64 = 1e-13;

/// Newton's stopping test for a step of the full dynamics reference
/// ([`crate::reference::FullSim`]): the momentum residual relative to the largest momentum or
/// impulse of the step, and the loop closure relative to the bounding radius (dimensionless).
/// 1e-10 sits above the floor set by the central differences of `∂T/∂θ` (~1e-11 of the
/// momentum, see [`FULL_FD_STEP`]) and moves a trajectory by far less than the first-order
/// error of backward Euler itself.
pub const FULL_RESIDUAL_REL: f64 = 1e-10;

/// Newton iterations allowed per step of the full dynamics reference before
/// [`crate::Error::NoConvergence`]. The tangent leaves out the Coriolis and load-stiffness
/// terms, so convergence is linear at a rate `~h·|ω|`; 50 covers steps up to h = 1 s on the
/// tested mechanisms.
pub const FULL_MAX_ITERATIONS: usize = 50;

/// Relative step of the central differences of the kinetic energy in the full dynamics
/// reference (times `1 + |θ|`): truncation ~h² = 1e-12, rounding ~ε/h = 2e-10 of the kinetic
/// energy per unit angle, entering the momentum balance multiplied by the time step.
pub const FULL_FD_STEP: f64 = 1e-6;

/// Largest number of velocity unknowns for which the full dynamics reference forms Newton's
/// tangent by differences of the residual (one residual per column, `O(n·ndof)` each); above
/// it the tangent is `M + hD + h²K` with the closure rows, which converges linearly.
pub const FULL_EXACT_TANGENT_MAX: usize = 48;

/// Relative step (times `1 + |v|`) of the forward differences that form the tangent of small
/// full-dynamics systems: the residual carries ~1e-12 of noise from the differences of
/// `∂T/∂θ`, so 1e-7 keeps the tangent accurate to ~1e-5, ample for Newton.
pub const FULL_TANGENT_STEP: f64 = 1e-7;

/// Times a step of the full dynamics reference may be halved when Newton stalls (so at most
/// 2⁴ = 16 sub-steps); beyond that [`crate::Error::NoConvergence`] is reported.
pub const FULL_MAX_HALVINGS: usize = 4;
