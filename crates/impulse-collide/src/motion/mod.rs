//! Motion types and their two collision routines (thesis §2.5): a swept box for the broad phase
//! and time-of-impact (TOI) coefficients for the narrow phase.
//!
//! Every body moves according to one [`Motion`]. Each motion type answers, from its state at the
//! current time t0 alone:
//!
//! 1. [`Motion::toi_coefficients`]: `(A, B)` such that the distance **any point of the body**
//!    travels along a direction d̂ over `[t0, t0 + τ]` is at most `A·τ² + B·τ` for every τ ≥ 0
//!    (eq. 2.13). A pair's TOI bound adds the coefficients of its two bodies
//!    ([`crate::toi::pair_toi`], [`crate::root::closing_time`]), so n motion types need n
//!    analyses, not n².
//! 2. [`Motion::swept_com_aabb`]: an axis-aligned box enclosing the **centre-of-mass path** over
//!    `[t0, t0 + Δt]`; the broad phase grows it by the body radius `r_max`.
//!
//! The types, all in the world frame, lengths in the scene's length unit (m), times in s:
//!
//! | type | motion | coefficients |
//! |---|---|---|
//! | [`Motion::Fixed`] | none | `(0, 0)` |
//! | [`Ballistic`] | COM parabola under gravity, free tumbling | eqs. (2.2), (2.3) |
//! | [`Cycler`] | COM on a circle at rate Ω, fixed orientation | (2.14) or (2.15), by D* |
//! | [`Spinner`] | rotation about a fixed axis through a fixed COM | `(0, \|Ω\|·r_max·‖d̂⊥‖)` |
//! | [`Oscillator`] | COM `p_c + a·sin(ωτ + φ)·axis`, fixed orientation | linear or quadratic |
//! | [`LinkMotion`] | a multibody link: padded second-order prediction (§5.2) | padded, **not conservative**: the caller checks |
//! | [`Motion::Unbounded`] | unknown: no bound exists | `(0, +∞)`: check now |
//!
//! Design: *Option A*, a trait with one type per motion and `Box<dyn Motion>` per body;
//! *Option B*, a closed `enum` of small `Copy` structs. Chose B: the set of motion types is
//! closed and small (multibody links, thesis ch. 5, will be one more variant), bodies can be
//! stored by value in one array, dispatch is a `match` the compiler checks for exhaustiveness,
//! and the structs keep their fields private so every stored motion has passed validation
//! (finite values, non-negative radii, unit axes). Each struct also offers the same methods.
//!
//! Angular-velocity bounds for ballistic bodies (§2.3.3): [`omega_max_energy`] (eq. 2.5, the one
//! to use), [`omega_max_momentum`] (eq. 2.4, looser, kept for comparison) and their world-frame
//! forms [`omega_max_energy_world`] and [`omega_max_momentum_world`].
//!
//! Direction arguments: `d_hat` is normally the unit vector from the closest point of this body
//! toward the other body. The coefficients are computed so that they bound the displacement
//! *along the vector as given* (its length multiplies every speed bound), so a slightly
//! non-unit `d_hat` still gets a valid bound; a non-finite `d_hat` gets the unbounded answer
//! [`UNBOUNDED_COEFFICIENTS`].

use core::f64::consts::{PI, TAU};

use glam::DVec3;
use impulse_geom::Aabb;

mod ballistic;
mod cycler;
mod link;
mod omega;
mod oscillator;
mod spinner;
#[cfg(test)]
pub(crate) mod testkit;

pub use ballistic::Ballistic;
pub use cycler::Cycler;
pub use link::{LINK_SWEPT_PADDING, LINK_TOI_PADDING, LinkMotion, SeenSpeeds};
pub use omega::{
    alpha_max_torque_free, omega_max_energy, omega_max_energy_world, omega_max_momentum,
    omega_max_momentum_world,
};
pub use oscillator::Oscillator;
pub use spinner::Spinner;

/// The coefficients `(A, B) = (0, +∞)` returned when an input makes a finite bound impossible
/// (non-finite `d_hat`, NaN, negative or infinite `r_max`). They say "any point may move any
/// distance at once": [`crate::root::closing_time`] then returns τ = 0, so the pair is checked
/// immediately. Conservative (no collision is missed), never a panic.
pub const UNBOUNDED_COEFFICIENTS: (f64, f64) = (0.0, f64::INFINITY);

/// Padding of every swept box, relative to the size of the coordinates it bounds
/// (dimensionless; default `1e-12`).
///
/// The extreme coordinates of a path are computed in closed form (apex of a parabola, extremum
/// of a sinusoid) while [`Motion::com_at`] evaluates the path at a given time; the two differ by
/// a few ulps of the coordinate magnitude. Per axis k the box is grown by
/// `SWEPT_BOX_ROUNDING_REL · (|p_k| + extent_k)` so it contains every point `com_at` returns
/// for a time in the interval. `1e-12` is ~4500 ulps: far more than the rounding, and far below
/// any body radius the caller adds.
pub const SWEPT_BOX_ROUNDING_REL: f64 = 1e-12;

/// Largest deviation from orthonormality accepted for a [`Cycler`]'s plane axes
/// (dimensionless; default `1e-9`): `‖e1‖ − 1`, `‖e2‖ − 1` and `e1·e2` must not exceed it in
/// magnitude. Axes within it are re-orthonormalised (Gram–Schmidt); axes outside it are
/// refused, since they would describe an ellipse, not the circle this type models.
pub const CYCLER_AXES_TOLERANCE: f64 = 1e-9;

/// Largest accepted asymmetry of a world inertia tensor, `max |I_ij − I_ji|` relative to
/// `max |I_ij|` (dimensionless; default `1e-9`). Tensors built as `R·diag·Rᵀ` are symmetric to
/// ~1e-16; the (symmetrised) tensor is what the bound uses.
pub const INERTIA_SYMMETRY_TOLERANCE: f64 = 1e-9;

/// Convergence threshold of the Jacobi eigenvalue iteration: sweeps stop when the Frobenius
/// norm of the off-diagonal part is at most this times the Frobenius norm of the matrix
/// (dimensionless; default `1e-15`, a few ε). The remaining off-diagonal norm is subtracted from
/// the smallest diagonal entry (Weyl's inequality), so the returned minimum eigenvalue is a
/// lower bound and the ω bound stays conservative.
pub const JACOBI_OFF_DIAGONAL_REL: f64 = 1e-15;

/// Upper limit on Jacobi sweeps (default 16). Cyclic Jacobi on a 3×3 symmetric matrix converges
/// quadratically and reaches [`JACOBI_OFF_DIAGONAL_REL`] in a few sweeps; the cap only guards
/// against pathological rounding, and the Weyl correction keeps the result a lower bound even
/// if it is reached.
pub const JACOBI_MAX_SWEEPS: usize = 16;

/// Why a motion or an angular-velocity bound could not be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum MotionError {
    /// A parameter (or a component of a vector parameter) is NaN or infinite.
    #[error("{name} is not finite")]
    NonFinite {
        /// The parameter's name.
        name: &'static str,
    },
    /// A scalar parameter, or a derived quantity such as a vector's length, is out of range.
    #[error("invalid {name} = {value}: {requirement}")]
    InvalidParameter {
        /// The parameter's name.
        name: &'static str,
        /// The value found.
        value: f64,
        /// What the value must satisfy.
        requirement: &'static str,
    },
}

fn finite_scalar(name: &'static str, x: f64) -> Result<f64, MotionError> {
    if x.is_finite() {
        Ok(x)
    } else {
        Err(MotionError::NonFinite { name })
    }
}

fn finite_vec(name: &'static str, v: DVec3) -> Result<DVec3, MotionError> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(MotionError::NonFinite { name })
    }
}

fn non_negative(name: &'static str, x: f64) -> Result<f64, MotionError> {
    let x = finite_scalar(name, x)?;
    if x >= 0.0 {
        Ok(x)
    } else {
        Err(MotionError::InvalidParameter {
            name,
            value: x,
            requirement: "must be >= 0",
        })
    }
}

fn unit_axis(name: &'static str, v: DVec3) -> Result<DVec3, MotionError> {
    let v = finite_vec(name, v)?;
    v.try_normalize().ok_or(MotionError::InvalidParameter {
        name,
        value: v.length(),
        requirement: "length must be > 0",
    })
}

/// Angle reduced to `[0, 2π)` (rad), so phases never grow and lose precision.
fn wrap_angle(theta: f64) -> f64 {
    let w = theta.rem_euclid(TAU);
    // rem_euclid can round up to exactly 2π for tiny negative inputs.
    if w >= TAU { 0.0 } else { w }
}

/// Range `(min, max)` of `cos θ` over `θ ∈ [lo, hi]` (rad, `lo ≤ hi`): the endpoint values, plus
/// the maximum 1 at every `2πn` and the minimum −1 at every `π + 2πn` inside the interval.
fn cos_range(lo: f64, hi: f64) -> (f64, f64) {
    if hi - lo >= TAU {
        return (-1.0, 1.0);
    }
    let (c_lo, c_hi) = (lo.cos(), hi.cos());
    let mut min = c_lo.min(c_hi);
    let mut max = c_lo.max(c_hi);
    if TAU * (lo / TAU).ceil() <= hi {
        max = 1.0;
    }
    if PI + TAU * ((lo - PI) / TAU).ceil() <= hi {
        min = -1.0;
    }
    (min, max)
}

/// The box containing all of space: the swept box of a motion whose interval is NaN (or
/// infinite for a ballistic body), so the broad phase treats it as close to everything.
const ALL_SPACE: Aabb = Aabb {
    min: DVec3::NEG_INFINITY,
    max: DVec3::INFINITY,
};

/// `box` grown per axis by [`SWEPT_BOX_ROUNDING_REL`] times `scale`.
fn pad(b: Aabb, scale: DVec3) -> Aabb {
    let p = scale * SWEPT_BOX_ROUNDING_REL;
    Aabb {
        min: b.min - p,
        max: b.max + p,
    }
}

/// Chooses between a linear model `(0, b_lin)` and a quadratic model `(a_quad, b_quad)` of the
/// same displacement (thesis §2.5, cycler rule). The two curves cross at
/// `τ* = (b_lin − b_quad)/a_quad`, where both equal `D* = b_lin·τ*`; for the cycler
/// (`b_lin = r|Ω|`, `a_quad = ½rΩ²`, `b_quad = v(t0)·d̂`) and the oscillator alike
/// `b_lin/a_quad = 2/|rate|`, so `D* = 2(b_lin − b_quad)/|rate|`. The quadratic model is tighter
/// before the crossing, so it is returned when `D* > gap`, the linear one otherwise (also when
/// `rate = 0` or `gap` is NaN).
fn select_model(rate: f64, b_lin: f64, a_quad: f64, b_quad: f64, gap: f64) -> (f64, f64) {
    let rate = rate.abs();
    if rate > 0.0 {
        let d_star = 2.0 * (b_lin - b_quad) / rate;
        if d_star > gap {
            return (a_quad, b_quad);
        }
    }
    (0.0, b_lin)
}

/// How a body moves between collisions; the state is that at the current time t0 (world frame).
///
/// See the module documentation for the table of types and the enum-versus-trait choice.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Motion {
    /// A body that never moves (floor, wall, ramp), with its centre of mass (world, m).
    ///
    /// Coefficients `(0, 0)`. Its swept box is the point box at `com`, but the broad phase
    /// should use the body's own tight box instead, computed once and **not grown** by r_max
    /// (thesis §2.4.3): [`Motion::is_fixed`] tells the caller which case applies. Build it with
    /// [`Motion::fixed`], which refuses a non-finite `com`.
    Fixed {
        /// Centre of mass (world, m).
        com: DVec3,
    },
    /// Free flight under gravity.
    Ballistic(Ballistic),
    /// Scripted circular COM motion at fixed orientation.
    Cycler(Cycler),
    /// Scripted rotation about a fixed axis through a fixed COM.
    Spinner(Spinner),
    /// Scripted sinusoidal COM translation at fixed orientation.
    Oscillator(Oscillator),
    /// A link of a multibody: a padded prediction the caller must check (thesis §5.2).
    Link(LinkMotion),
    /// A body whose motion cannot be bounded (its angular speed bound overflows, or its state
    /// is not finite), with its last centre of mass (world, m; may be NaN). It is never
    /// claimed to stay still: its coefficients are [`UNBOUNDED_COEFFICIENTS`] (every pair with
    /// it is due now) and its swept box is all of space, so a caller must not advance time
    /// past the present while a body has this motion.
    Unbounded {
        /// Last known centre of mass (world, m).
        com: DVec3,
    },
}

impl From<Ballistic> for Motion {
    fn from(m: Ballistic) -> Self {
        Motion::Ballistic(m)
    }
}

impl From<Cycler> for Motion {
    fn from(m: Cycler) -> Self {
        Motion::Cycler(m)
    }
}

impl From<Spinner> for Motion {
    fn from(m: Spinner) -> Self {
        Motion::Spinner(m)
    }
}

impl From<Oscillator> for Motion {
    fn from(m: Oscillator) -> Self {
        Motion::Oscillator(m)
    }
}

impl Motion {
    /// A fixed body with centre of mass `com` (world, m).
    ///
    /// # Errors
    /// [`MotionError::NonFinite`] for a NaN or infinite `com`.
    pub fn fixed(com: DVec3) -> Result<Self, MotionError> {
        Ok(Motion::Fixed {
            com: finite_vec("com", com)?,
        })
    }

    /// `true` for [`Motion::Fixed`]: the broad phase uses the body's own box, not grown.
    #[must_use]
    pub fn is_fixed(&self) -> bool {
        matches!(self, Motion::Fixed { .. })
    }

    /// TOI coefficients `(A, B)` (eq. 2.13): the distance any point of the body moves along
    /// `d_hat` (world; unit, pointing from this body toward the other) over `[t0, t0 + τ]` is
    /// at most `A·τ² + B·τ` for every τ ≥ 0 (A in m/s², B in m/s).
    ///
    /// `r_max` (m) is the largest distance of a body point from the COM (used by the rotating
    /// types); `gap` (m) is the current distance to the other body (used by the cycler and
    /// oscillator to choose between their linear and quadratic models). Invalid inputs give
    /// [`UNBOUNDED_COEFFICIENTS`] (see the variants' methods); a fixed body always gives `(0, 0)`.
    #[must_use]
    pub fn toi_coefficients(&self, d_hat: DVec3, r_max: f64, gap: f64) -> (f64, f64) {
        match self {
            Motion::Fixed { .. } => (0.0, 0.0),
            Motion::Ballistic(m) => m.toi_coefficients_for_gap(d_hat, r_max, gap),
            Motion::Cycler(m) => m.toi_coefficients(d_hat, gap),
            Motion::Spinner(m) => m.toi_coefficients(d_hat, r_max),
            Motion::Oscillator(m) => m.toi_coefficients(d_hat, gap),
            Motion::Link(m) => m.toi_coefficients(d_hat, r_max),
            Motion::Unbounded { .. } => UNBOUNDED_COEFFICIENTS,
        }
    }

    /// Axis-aligned box (world, m) enclosing the centre-of-mass path between t0 and `t0 + dt`
    /// (dt in s; a negative dt covers `[t0 + dt, t0]`). The caller grows it by r_max before
    /// hashing, except for a fixed body (see [`Motion::Fixed`]).
    #[must_use]
    pub fn swept_com_aabb(&self, dt: f64) -> Aabb {
        match self {
            Motion::Fixed { com } => Aabb::new(*com, *com),
            Motion::Ballistic(m) => m.swept_com_aabb(dt),
            Motion::Cycler(m) => m.swept_com_aabb(dt),
            Motion::Spinner(m) => m.swept_com_aabb(dt),
            Motion::Oscillator(m) => m.swept_com_aabb(dt),
            Motion::Link(m) => m.swept_com_aabb(dt),
            Motion::Unbounded { .. } => ALL_SPACE,
        }
    }

    /// Centre of mass at `t0 + dt` (world, m). A non-finite `dt` gives a non-finite result for
    /// the types whose COM moves.
    #[must_use]
    pub fn com_at(&self, dt: f64) -> DVec3 {
        match self {
            Motion::Fixed { com } | Motion::Unbounded { com } => *com,
            Motion::Ballistic(m) => m.com_at(dt),
            Motion::Cycler(m) => m.com_at(dt),
            Motion::Spinner(m) => m.com(),
            Motion::Oscillator(m) => m.com_at(dt),
            Motion::Link(m) => m.com_at(dt),
        }
    }

    /// Centre-of-mass velocity at `t0 + dt` (world, m/s); NaN for an unbounded motion.
    #[must_use]
    pub fn com_velocity_at(&self, dt: f64) -> DVec3 {
        match self {
            Motion::Fixed { .. } | Motion::Spinner(_) => DVec3::ZERO,
            Motion::Unbounded { .. } => DVec3::NAN,
            Motion::Ballistic(m) => m.com_velocity_at(dt),
            Motion::Cycler(m) => m.com_velocity_at(dt),
            Motion::Oscillator(m) => m.com_velocity_at(dt),
            Motion::Link(m) => m.com_velocity_at(dt),
        }
    }

    /// The motion's state at `t0 + dt`, so the caller can re-base it at the new current time.
    /// Fixed bodies and spinners have no time-dependent motion state and are returned
    /// unchanged (a spinner's orientation is the body's, see [`Spinner::rotation_over`]).
    ///
    /// # Errors
    /// [`MotionError::NonFinite`] when `dt` is not finite or the new state overflows.
    pub fn advance(&self, dt: f64) -> Result<Self, MotionError> {
        finite_scalar("dt", dt)?;
        Ok(match self {
            Motion::Fixed { .. } | Motion::Spinner(_) | Motion::Unbounded { .. } => *self,
            Motion::Ballistic(m) => Motion::Ballistic(m.advance(dt)?),
            Motion::Cycler(m) => Motion::Cycler(m.advance(dt)?),
            Motion::Oscillator(m) => Motion::Oscillator(m.advance(dt)?),
            Motion::Link(m) => Motion::Link(m.advance(dt)?),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::testkit::*;
    use core::f64::consts::TAU;
    use glam::DVec3;
    use impulse_geom::Aabb;
    use rand::RngExt;

    /// Checks both models of a scripted translating body (cycler or oscillator) against its
    /// sampled path and the choice rule against an independently computed D*. Returns the
    /// largest displacement / bound ratio seen for the chosen model.
    fn check_scripted_models(
        motion: &Motion,
        linear: (f64, f64),
        quadratic: (f64, f64),
        rate: f64,
        d: DVec3,
        span: f64,
    ) -> f64 {
        const STEPS: usize = 2000;
        let p0 = motion.com_at(0.0);
        let mut worst: f64 = 0.0;
        for k in 1..=STEPS {
            let tau = span * k as f64 / STEPS as f64;
            let disp = (motion.com_at(tau) - p0).dot(d);
            let slack = BOUND_SLACK_REL * (1.0 + p0.length());
            for (a, b) in [linear, quadratic] {
                let bound = a * tau * tau + b * tau;
                assert!(
                    disp <= bound + slack,
                    "{motion:?}: τ {tau} disp {disp} > {bound}"
                );
            }
            let tighter = (linear.1 * tau).min(quadratic.0 * tau * tau + quadratic.1 * tau);
            if tighter > RATIO_FLOOR_REL {
                worst = worst.max(disp / tighter);
            }
        }
        // Selection rule: D* where the two bounds meet, computed from the crossing time.
        if rate != 0.0 && quadratic.0 > 0.0 {
            let t_star = (linear.1 - quadratic.1) / quadratic.0;
            let d_star = linear.1 * t_star;
            for gap in [
                0.5 * d_star,
                0.999 * d_star,
                1.001 * d_star,
                2.0 * d_star,
                1e-3,
                10.0,
            ] {
                let want = if d_star > gap { quadratic } else { linear };
                let got = motion.toi_coefficients(d, 1.0, gap);
                assert_eq!(got, want, "{motion:?}: gap {gap} D* {d_star}");
            }
        }
        worst
    }

    #[test]
    fn cycler_and_oscillator_bounds_hold_and_the_rule_picks_by_d_star() {
        let mut rng = rng(21);
        let (mut worst_c, mut worst_o): (f64, f64) = (0.0, 0.0);
        for _ in 0..200 {
            let e1 = unit_vector(&mut rng);
            let e2 = e1.any_orthonormal_vector();
            let c = Cycler::new(
                unit_vector(&mut rng),
                e1,
                e2,
                rng.random_range(0.1..2.0),
                rng.random_range(-5.0..5.0),
                rng.random_range(0.0..TAU),
            )
            .unwrap();
            let d = unit_vector(&mut rng);
            let span = 3.0 * TAU / c.rate().abs();
            let m = Motion::from(c);
            worst_c = worst_c.max(check_scripted_models(
                &m,
                c.linear_coefficients(d),
                c.quadratic_coefficients(d),
                c.rate(),
                d,
                span,
            ));
            let o = Oscillator::new(
                unit_vector(&mut rng),
                unit_vector(&mut rng),
                rng.random_range(0.01..1.0),
                rng.random_range(-30.0..30.0),
                rng.random_range(0.0..TAU),
            )
            .unwrap();
            let m = Motion::from(o);
            let span = 3.0 * TAU / o.omega().abs();
            worst_o = worst_o.max(check_scripted_models(
                &m,
                o.linear_coefficients(d),
                o.quadratic_coefficients(d),
                o.omega(),
                d,
                span,
            ));
        }
        // Thesis worked case: circle in the x-y plane, D* = 2(rΩ − v·d̂)/Ω.
        let c = Cycler::new(DVec3::ZERO, DVec3::X, DVec3::Y, 2.0, 3.0, 0.0).unwrap();
        let d = DVec3::X; // v(t0) = (0, 6, 0) ⟂ d̂, so D* = 2·6/3 = 4.
        assert_eq!(c.toi_coefficients(d, 3.9), (9.0, 0.0));
        assert_eq!(c.toi_coefficients(d, 4.1), (0.0, 6.0));
        assert_eq!(c.toi_coefficients(d, f64::NAN), (0.0, 6.0));
        eprintln!(
            "scripted bounds: max displacement / tighter bound: cycler {worst_c:.4}, \
             oscillator {worst_o:.4}"
        );
    }

    #[test]
    fn fixed_bodies_have_zero_coefficients() {
        let f = Motion::fixed(DVec3::new(1.0, 2.0, 3.0)).unwrap();
        let mut rng = rng(1);
        for _ in 0..100 {
            let d = unit_vector(&mut rng);
            assert_eq!(
                f.toi_coefficients(d, rng.random_range(0.0..10.0), 0.5),
                (0.0, 0.0)
            );
        }
        assert_eq!(
            f.toi_coefficients(DVec3::NAN, f64::NAN, f64::NAN),
            (0.0, 0.0)
        );
        assert!(f.is_fixed());
        assert_eq!(
            f.swept_com_aabb(10.0),
            Aabb::new(DVec3::new(1.0, 2.0, 3.0), DVec3::new(1.0, 2.0, 3.0))
        );
        assert_eq!(f.advance(3.0), Ok(f));
        assert_eq!(f.com_velocity_at(1.0), DVec3::ZERO);
        assert!(Motion::fixed(DVec3::NAN).is_err());
    }

    #[test]
    fn advance_rebases_every_motion_type() {
        /// Re-based positions (m) and velocities (m/s) against the original motion: rounding
        /// of phases and parabolas evaluated at times up to 100 s with speeds up to 60 m/s.
        const REBASE_POS_TOL: f64 = 1e-10;
        const REBASE_VEL_TOL: f64 = 1e-9;
        /// Central-difference step (s) and its accepted error (m/s; truncation ~h²·|p'''|).
        const FD_STEP: f64 = 1e-6;
        const FD_TOL: f64 = 1e-6;
        let motions = [
            Motion::fixed(DVec3::ONE).unwrap(),
            Ballistic::new(
                DVec3::ONE,
                DVec3::new(1.0, 2.0, 3.0),
                DVec3::new(0.0, 0.0, -9.81),
                4.0,
            )
            .unwrap()
            .into(),
            Cycler::new(DVec3::ONE, DVec3::Y, DVec3::Z, 0.5, -2.0, 1.0)
                .unwrap()
                .into(),
            Spinner::new(DVec3::ONE, DVec3::X, 7.0).unwrap().into(),
            Oscillator::new(DVec3::ONE, DVec3::Z, 0.1, 30.0, 0.5)
                .unwrap()
                .into(),
        ];
        for m in motions {
            for (t1, t2) in [(0.3, 0.4), (1.7, 0.01), (100.0, 2.5), (-1.0, 0.5)] {
                let later = m.advance(t1).unwrap();
                assert!((later.com_at(t2) - m.com_at(t1 + t2)).length() <= REBASE_POS_TOL);
                assert!(
                    (later.com_velocity_at(0.0) - m.com_velocity_at(t1)).length() <= REBASE_VEL_TOL
                );
                assert_eq!(later.is_fixed(), m.is_fixed());
            }
            // Velocities are the derivatives of the positions (central difference).
            let h = FD_STEP;
            let fd = (m.com_at(0.2 + h) - m.com_at(0.2 - h)) / (2.0 * h);
            assert!((fd - m.com_velocity_at(0.2)).length() <= FD_TOL);
            assert!(m.advance(f64::NAN).is_err());
            assert!(m.advance(f64::INFINITY).is_err());
        }
        let c = Cycler::new(DVec3::ZERO, DVec3::X, DVec3::Y, 1.0, 1.0, -0.5).unwrap();
        assert!((c.phase() - (TAU - 0.5)).abs() <= ORTHONORMAL_TOL * TAU);
        assert!(c.advance(1e6).unwrap().phase() < TAU);
        // Overflowing state is refused.
        let b = Ballistic::new(DVec3::ZERO, DVec3::X * 1e300, DVec3::ZERO, 0.0).unwrap();
        assert!(b.advance(1e10).is_err());
    }

    #[test]
    fn invalid_parameters_are_refused_or_unbounded() {
        let (c, x, y) = (DVec3::ZERO, DVec3::X, DVec3::Y);
        assert!(Ballistic::new(DVec3::NAN, x, c, 0.0).is_err());
        assert!(Ballistic::new(c, x, c, -1.0).is_err());
        assert!(Ballistic::new(c, x, c, f64::INFINITY).is_err());
        assert!(Cycler::new(c, x, y, -1.0, 1.0, 0.0).is_err());
        assert!(Cycler::new(c, x, x, 1.0, 1.0, 0.0).is_err());
        assert!(Cycler::new(c, x * 2.0, y, 1.0, 1.0, 0.0).is_err());
        assert!(Cycler::new(c, x, y, 1.0, f64::NAN, 0.0).is_err());
        // Within tolerance: accepted and made exactly orthonormal.
        let ok = Cycler::new(c, x * (1.0 + 1e-12), y + x * 1e-12, 1.0, 1.0, 0.0).unwrap();
        let (e1, e2) = ok.axes();
        assert!(
            e1.dot(e2).abs() <= ORTHONORMAL_TOL && (e2.length() - 1.0).abs() <= ORTHONORMAL_TOL
        );
        assert!(Spinner::new(c, DVec3::ZERO, 1.0).is_err());
        assert!(Spinner::new(c, x, f64::INFINITY).is_err());
        assert!(Oscillator::new(c, x, -0.1, 1.0, 0.0).is_err());
        assert!(Oscillator::new(c, DVec3::ZERO, 0.1, 1.0, 0.0).is_err());
        assert!(Oscillator::new(c, x, 0.1, 1.0, f64::NAN).is_err());

        let ball: Motion = Ballistic::new(c, x, DVec3::NEG_Z, 1.0).unwrap().into();
        let spin: Motion = Spinner::new(c, y, 1.0).unwrap().into();
        for m in [ball, spin] {
            for r in [f64::NAN, -1.0, f64::INFINITY] {
                assert_eq!(m.toi_coefficients(x, r, 1.0), UNBOUNDED_COEFFICIENTS);
            }
            assert_eq!(
                m.toi_coefficients(DVec3::NAN, 1.0, 1.0),
                UNBOUNDED_COEFFICIENTS
            );
        }
        let cyc: Motion = Cycler::new(c, x, y, 1.0, 1.0, 0.0).unwrap().into();
        let osc: Motion = Oscillator::new(c, x, 1.0, 1.0, 0.0).unwrap().into();
        for m in [cyc, osc] {
            assert_eq!(
                m.toi_coefficients(DVec3::INFINITY, 1.0, 1.0),
                UNBOUNDED_COEFFICIENTS
            );
            // r_max is irrelevant without rotation.
            assert_eq!(
                m.toi_coefficients(x, f64::NAN, 1.0),
                m.toi_coefficients(x, 1.0, 1.0)
            );
        }
        // A non-unit direction scales the bound: still valid for the displacement along it.
        let (a1, b1) = ball.toi_coefficients(y, 2.0, 1.0);
        let (a2, b2) = ball.toi_coefficients(y * 3.0, 2.0, 1.0);
        assert_eq!((a2, b2), (3.0 * a1, 3.0 * b1));
    }

    /// A motion that cannot be bounded never claims the body stays still: every pair with it
    /// is due at once (τ = 0 against any partner, even a fixed one far away), its swept box is
    /// all of space, and re-basing keeps it unbounded.
    #[test]
    fn an_unbounded_motion_is_checked_now() {
        let u = Motion::Unbounded { com: DVec3::NAN };
        let floor = Motion::fixed(DVec3::ZERO).unwrap();
        for gap in [1e-9, 1.0, 1e9] {
            let tau = crate::toi::toi_lower_bound(gap, DVec3::Z, &u, 1.0, &floor, 0.0);
            assert_eq!(tau, 0.0, "gap {gap}");
        }
        assert_eq!(
            u.toi_coefficients(DVec3::X, 0.0, 1.0),
            UNBOUNDED_COEFFICIENTS
        );
        assert_eq!(u.swept_com_aabb(1e-6), ALL_SPACE);
        assert!(matches!(u.advance(1.0).unwrap(), Motion::Unbounded { .. }));
        assert!(u.com_velocity_at(0.0).is_nan());
    }
}
