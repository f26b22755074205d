//! Motion types and their two collision routines (thesis §2.5): a swept box for the broad phase
//! and time-of-impact (TOI) coefficients for the narrow phase.
//!
//! Every body moves according to one [`Motion`]. Each motion type answers, from its state at the
//! current time t0 alone:
//!
//! 1. [`Motion::toi_coefficients`]: `(A, B)` such that the distance **any point of the body**
//!    travels along a direction d̂ over `[t0, t0 + τ]` is at most `A·τ² + B·τ` for every τ ≥ 0
//!    (eq. 2.13). A pair's TOI bound adds the coefficients of its two bodies
//!    ([`crate::toi::pair_toi`]), so n motion types need n analyses, not n².
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

use glam::{DMat3, DQuat, DVec3};
use impulse_geom::Aabb;
use impulse_geom::se3::so3_exp;

/// The coefficients `(A, B) = (0, +∞)` returned when an input makes a finite bound impossible
/// (non-finite `d_hat`, NaN, negative or infinite `r_max`). They say "any point may move any
/// distance at once": [`crate::toi::pair_toi`] then returns τ = 0, so the pair is checked
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

/// Ballistic motion (thesis §2.3.2): the centre of mass follows a parabola under constant
/// gravity, the body tumbles freely (no torque), and `omega_max` bounds `‖ω‖` over the whole
/// ballistic phase.
///
/// State at the current time t0, world frame: `com` (m), `velocity` (m/s), `gravity` (m/s²),
/// `omega_max` (rad/s, from [`omega_max_energy`] or [`omega_max_energy_world`], recomputed by
/// the caller after every impulse on the body). COM path: `p(τ) = com + v·τ + ½·g·τ²`.
///
/// Optionally ([`Ballistic::with_spin`]) the current angular velocity ω₀ (world) and a bound
/// α_max on ‖ω̇‖ during the flight, which give a second rotational bound that is much tighter
/// for a body spinning about the direction of approach (a top on a table), see
/// [`Ballistic::toi_coefficients_for_gap`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ballistic {
    com: DVec3,
    velocity: DVec3,
    gravity: DVec3,
    omega_max: f64,
    /// (ω₀ world, α_max), when known.
    spin: Option<(DVec3, f64)>,
}

impl Ballistic {
    /// A ballistic motion from its state at t0 (world frame; m, m/s, m/s², rad/s).
    ///
    /// # Errors
    /// [`MotionError::NonFinite`] for a NaN or infinite input; [`MotionError::InvalidParameter`]
    /// for a negative `omega_max`.
    pub fn new(
        com: DVec3,
        velocity: DVec3,
        gravity: DVec3,
        omega_max: f64,
    ) -> Result<Self, MotionError> {
        Ok(Self {
            com: finite_vec("com", com)?,
            velocity: finite_vec("velocity", velocity)?,
            gravity: finite_vec("gravity", gravity)?,
            omega_max: non_negative("omega_max", omega_max)?,
            spin: None,
        })
    }

    /// Adds the spin refinement: the angular velocity `omega` (world, rad/s) now, and
    /// `alpha_max` (rad/s²) bounding ‖ω̇‖ over the flight. For a torque-free body, L = I_w·ω is
    /// constant, so I_w·ω̇ = L × ω and ‖ω̇‖ ≤ ‖L‖·ω_max / I_min ([`alpha_max_torque_free`]).
    ///
    /// # Errors
    /// [`MotionError::NonFinite`] for a NaN or infinite `omega`; [`MotionError::InvalidParameter`]
    /// for a negative or NaN `alpha_max`.
    pub fn with_spin(self, omega: DVec3, alpha_max: f64) -> Result<Self, MotionError> {
        Ok(Self {
            spin: Some((
                finite_vec("omega", omega)?,
                non_negative("alpha_max", alpha_max)?,
            )),
            ..self
        })
    }

    /// Centre of mass at t0 (world, m).
    #[must_use]
    pub fn com(&self) -> DVec3 {
        self.com
    }

    /// Centre-of-mass velocity at t0 (world, m/s).
    #[must_use]
    pub fn velocity(&self) -> DVec3 {
        self.velocity
    }

    /// Gravitational acceleration (world, m/s²).
    #[must_use]
    pub fn gravity(&self) -> DVec3 {
        self.gravity
    }

    /// Bound on `‖ω‖` over the ballistic phase (rad/s).
    #[must_use]
    pub fn omega_max(&self) -> f64 {
        self.omega_max
    }

    /// TOI coefficients (eqs. 2.2, 2.3): the velocity of a body point is `v(t) + ω(t)×r(t)`, so
    /// its speed along d̂ is at most `[v(t0) + g·(t−t0)]·d̂ + r_max·ω_max`; integrating,
    /// `A = ½·g·d̂` and `B = v(t0)·d̂ + r_max·ω_max·|d̂|`. Exact (equality) for a body that does
    /// not rotate (`omega_max = 0`).
    #[must_use]
    pub fn toi_coefficients(&self, d_hat: DVec3, r_max: f64) -> (f64, f64) {
        let len = d_hat.length();
        if !(len.is_finite() && r_max >= 0.0 && r_max.is_finite()) {
            return UNBOUNDED_COEFFICIENTS;
        }
        let a = 0.5 * self.gravity.dot(d_hat); // (2.2)
        let b = self.velocity.dot(d_hat) + r_max * self.omega_max * len; // (2.3)
        (a, b)
    }

    /// TOI coefficients for closing `gap`, the tighter of two bounds on the rotational part of
    /// a point's displacement along d̂. The thesis's (eq. 2.3, [`Ballistic::toi_coefficients`]):
    /// r_max·ω_max·τ. With the spin refinement: a point r moves along d̂ at
    /// (ω × r)·d̂ = r·(d̂ × ω) ≤ r_max·‖d̂ × ω(t)‖ ≤ r_max·(‖d̂ × ω₀‖ + α_max·t), so its
    /// rotational displacement is at most r_max·(‖d̂ × ω₀‖·τ + ½·α_max·τ²): coefficients
    /// `A = ½·g·d̂ + ½·r_max·α_max·|d̂|`, `B = v·d̂ + r_max·‖d̂ × ω₀‖`. Both hold for every τ; the
    /// one whose own time to close `gap` is later is returned (either is conservative).
    #[must_use]
    pub fn toi_coefficients_for_gap(&self, d_hat: DVec3, r_max: f64, gap: f64) -> (f64, f64) {
        let base = self.toi_coefficients(d_hat, r_max);
        let Some((omega, alpha)) = self.spin else {
            return base;
        };
        if base == UNBOUNDED_COEFFICIENTS || !gap.is_finite() {
            return base;
        }
        let len = d_hat.length();
        let refined = (
            0.5 * self.gravity.dot(d_hat) + 0.5 * r_max * alpha * len,
            self.velocity.dot(d_hat) + r_max * d_hat.cross(omega).length(),
        );
        let none = (0.0, 0.0);
        if crate::toi::pair_toi(gap, refined, none) > crate::toi::pair_toi(gap, base, none) {
            refined
        } else {
            base
        }
    }

    /// Box enclosing the COM parabola between t0 and `t0 + dt` (either order of the two
    /// times): both endpoints, plus on each axis k with `g_k ≠ 0` the apex
    /// `p_k − v_k²/(2g_k)` when its time `−v_k/g_k` lies strictly between 0 and `dt`. Padded by
    /// [`SWEPT_BOX_ROUNDING_REL`]. A NaN or infinite `dt` gives the box of all space.
    #[must_use]
    pub fn swept_com_aabb(&self, dt: f64) -> Aabb {
        if !dt.is_finite() {
            return ALL_SPACE;
        }
        let end = self.com_at(dt);
        let mut b = Aabb::new(self.com, end);
        let (lo, hi) = if dt >= 0.0 { (0.0, dt) } else { (dt, 0.0) };
        for k in 0..3 {
            let (p, v, g) = (self.com[k], self.velocity[k], self.gravity[k]);
            if g != 0.0 {
                let t_apex = -v / g;
                if lo < t_apex && t_apex < hi {
                    let apex = p - v * v / (2.0 * g);
                    b.min[k] = b.min[k].min(apex);
                    b.max[k] = b.max[k].max(apex);
                }
            }
        }
        let scale =
            self.com.abs() + self.velocity.abs() * dt.abs() + 0.5 * self.gravity.abs() * (dt * dt);
        pad(b, scale)
    }

    /// Centre of mass at `t0 + dt` (world, m): `com + v·dt + ½·g·dt²`.
    #[must_use]
    pub fn com_at(&self, dt: f64) -> DVec3 {
        self.com + self.velocity * dt + self.gravity * (0.5 * dt * dt)
    }

    /// Centre-of-mass velocity at `t0 + dt` (world, m/s): `v + g·dt`.
    #[must_use]
    pub fn com_velocity_at(&self, dt: f64) -> DVec3 {
        self.velocity + self.gravity * dt
    }

    /// The same motion re-based at `t0 + dt` (COM and velocity advanced; gravity and
    /// `omega_max` kept, since the ω bound holds for the whole ballistic phase).
    ///
    /// # Errors
    /// [`MotionError::NonFinite`] when `dt` is not finite or the advanced state overflows.
    pub fn advance(&self, dt: f64) -> Result<Self, MotionError> {
        finite_scalar("dt", dt)?;
        Self::new(
            self.com_at(dt),
            self.com_velocity_at(dt),
            self.gravity,
            self.omega_max,
        )
    }
}

/// Scripted circular motion (thesis §2.5, "cycler"): the centre of mass moves on a circle at a
/// constant angular rate Ω while the orientation stays fixed (ω = 0, so every body point moves
/// like the COM).
///
/// World frame: `p(τ) = centre + r·(cos θ(τ)·e1 + sin θ(τ)·e2)`, `θ(τ) = phase + Ω·τ`, with
/// `centre` (m), orthonormal plane axes `e1`, `e2`, radius `r ≥ 0` (m), rate Ω (rad/s, either
/// sign) and `phase` θ(t0) (rad, stored in `[0, 2π)`). Speed `r·|Ω|`, centripetal acceleration
/// `r·Ω²`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cycler {
    centre: DVec3,
    e1: DVec3,
    e2: DVec3,
    radius: f64,
    rate: f64,
    phase: f64,
}

impl Cycler {
    /// A cycler from its circle (world frame) and its phase at t0.
    ///
    /// `e1` and `e2` must be orthonormal within [`CYCLER_AXES_TOLERANCE`]; they are then
    /// re-orthonormalised.
    ///
    /// # Errors
    /// [`MotionError::NonFinite`] for NaN or infinite input; [`MotionError::InvalidParameter`]
    /// for a negative radius or axes that are not orthonormal.
    pub fn new(
        centre: DVec3,
        e1: DVec3,
        e2: DVec3,
        radius: f64,
        rate: f64,
        phase: f64,
    ) -> Result<Self, MotionError> {
        let centre = finite_vec("centre", centre)?;
        let e1 = finite_vec("e1", e1)?;
        let e2 = finite_vec("e2", e2)?;
        let radius = non_negative("radius", radius)?;
        let rate = finite_scalar("rate", rate)?;
        let phase = finite_scalar("phase", phase)?;
        for (name, value) in [
            ("|e1| - 1", e1.length() - 1.0),
            ("|e2| - 1", e2.length() - 1.0),
            ("e1.e2", e1.dot(e2)),
        ] {
            if value.abs() > CYCLER_AXES_TOLERANCE {
                return Err(MotionError::InvalidParameter {
                    name,
                    value,
                    requirement: "cycler axes must be orthonormal (see CYCLER_AXES_TOLERANCE)",
                });
            }
        }
        let e1 = e1.normalize();
        let e2 = (e2 - e1 * e1.dot(e2)).normalize();
        Ok(Self {
            centre,
            e1,
            e2,
            radius,
            rate,
            phase: wrap_angle(phase),
        })
    }

    /// Centre of the circle (world, m).
    #[must_use]
    pub fn centre(&self) -> DVec3 {
        self.centre
    }

    /// The orthonormal plane axes `(e1, e2)` (world, unit).
    #[must_use]
    pub fn axes(&self) -> (DVec3, DVec3) {
        (self.e1, self.e2)
    }

    /// Radius r (m).
    #[must_use]
    pub fn radius(&self) -> f64 {
        self.radius
    }

    /// Angular rate Ω of the COM around the circle (rad/s; positive from e1 toward e2).
    #[must_use]
    pub fn rate(&self) -> f64 {
        self.rate
    }

    /// Phase θ(t0) in `[0, 2π)` (rad).
    #[must_use]
    pub fn phase(&self) -> f64 {
        self.phase
    }

    /// Linear model (eq. 2.14): the speed is always `r|Ω|`, so `(0, r|Ω|·|d̂|)`.
    fn linear_coefficients(&self, d_hat: DVec3) -> (f64, f64) {
        (0.0, self.radius * self.rate.abs() * d_hat.length())
    }

    /// Quadratic model (eq. 2.15): the velocity along d̂ starts at `v(t0)·d̂` and changes at
    /// most at the centripetal rate `rΩ²`, so `(½rΩ²·|d̂|, v(t0)·d̂)`.
    fn quadratic_coefficients(&self, d_hat: DVec3) -> (f64, f64) {
        let a = 0.5 * self.radius * self.rate * self.rate * d_hat.length();
        (a, self.com_velocity_at(0.0).dot(d_hat))
    }

    /// TOI coefficients: eq. (2.14) `(0, r|Ω|)` or eq. (2.15) `(½rΩ², v(t0)·d̂)` (speed terms
    /// times `|d̂|`), chosen by the thesis rule: the two bounds are equal at
    /// `D* = 2[r|Ω| − v(t0)·d̂]/|Ω|`; if `D* > gap` (the
    /// current distance to the other body, m) the quadratic one is returned (it is tighter up to
    /// D*), otherwise the linear one. Both are valid bounds for every τ; `r_max` is not needed
    /// (no rotation). A NaN `gap` selects the linear model; a non-finite `d_hat` gives
    /// [`UNBOUNDED_COEFFICIENTS`].
    #[must_use]
    pub fn toi_coefficients(&self, d_hat: DVec3, gap: f64) -> (f64, f64) {
        if !d_hat.is_finite() {
            return UNBOUNDED_COEFFICIENTS;
        }
        let (_, b_lin) = self.linear_coefficients(d_hat);
        let (a_quad, b_quad) = self.quadratic_coefficients(d_hat);
        select_model(self.rate, b_lin, a_quad, b_quad, gap)
    }

    /// Box enclosing the COM arc between t0 and `t0 + dt` (either order): per axis k the
    /// coordinate is `c_k + r·R_k·cos(θ − α_k)` with `R_k = |(e1_k, e2_k)|`,
    /// `α_k = atan2(e2_k, e1_k)`, so the box holds both endpoints and every axis extremum
    /// (`θ = α_k` or `α_k + π`, mod 2π) the arc passes; if `|Ω·dt| ≥ 2π` it is the whole
    /// circle's box. Padded by [`SWEPT_BOX_ROUNDING_REL`]. NaN `dt` gives the box of all space;
    /// an infinite `dt` the whole circle's box.
    #[must_use]
    pub fn swept_com_aabb(&self, dt: f64) -> Aabb {
        if dt.is_nan() {
            return ALL_SPACE;
        }
        let sweep = if dt.is_infinite() {
            f64::INFINITY
        } else {
            self.rate * dt
        };
        let (t_lo, t_hi) = if sweep.is_infinite() {
            (0.0, f64::INFINITY)
        } else if sweep >= 0.0 {
            (self.phase, self.phase + sweep)
        } else {
            (self.phase + sweep, self.phase)
        };
        let mut min = DVec3::ZERO;
        let mut max = DVec3::ZERO;
        for k in 0..3 {
            let (x, y) = (self.e1[k], self.e2[k]);
            let amp = self.radius * x.hypot(y);
            let alpha = y.atan2(x);
            let (c_min, c_max) = cos_range(t_lo - alpha, t_hi - alpha);
            min[k] = self.centre[k] + amp * c_min;
            max[k] = self.centre[k] + amp * c_max;
        }
        let mut b = Aabb { min, max };
        if dt.is_finite() {
            b = Aabb::from_points([b.min, b.max, self.com_at(0.0), self.com_at(dt)]);
        }
        pad(b, self.centre.abs() + DVec3::splat(self.radius))
    }

    /// Centre of mass at `t0 + dt` (world, m).
    #[must_use]
    pub fn com_at(&self, dt: f64) -> DVec3 {
        let (s, c) = (self.phase + self.rate * dt).sin_cos();
        self.centre + (self.e1 * c + self.e2 * s) * self.radius
    }

    /// Centre-of-mass velocity at `t0 + dt` (world, m/s): `rΩ·(−sin θ·e1 + cos θ·e2)`.
    #[must_use]
    pub fn com_velocity_at(&self, dt: f64) -> DVec3 {
        let (s, c) = (self.phase + self.rate * dt).sin_cos();
        (self.e2 * c - self.e1 * s) * (self.radius * self.rate)
    }

    /// The same motion re-based at `t0 + dt` (phase advanced by `Ω·dt`, wrapped to `[0, 2π)`).
    ///
    /// # Errors
    /// [`MotionError::NonFinite`] when `dt` or the new phase is not finite.
    pub fn advance(&self, dt: f64) -> Result<Self, MotionError> {
        finite_scalar("dt", dt)?;
        let phase = finite_scalar("phase", self.phase + self.rate * dt)?;
        Ok(Self {
            phase: wrap_angle(phase),
            ..*self
        })
    }
}

/// Scripted rotation about a fixed axis through a fixed centre of mass (a spinning platter or
/// turntable): angular velocity `Ω·axis` is constant, the COM does not move.
///
/// World frame: `com` (m), unit `axis`, rate Ω (rad/s, right-handed about `axis`).
///
/// Coefficients: a body point at offset `r` from the COM moves on a circle about the axis with
/// velocity `Ω·axis × r`, which is perpendicular to the axis and of length `|Ω|·ρ`, where ρ,
/// the point's distance from the axis, is at most `|r| ≤ r_max`. Its rate along d̂ is therefore
/// `(Ω·axis × r)·d̂⊥ ≤ |Ω|·r_max·|d̂⊥|`, where `d̂⊥ = d̂ − (d̂·axis)·axis`; integrating,
/// `A = 0`, `B = |Ω|·r_max·|d̂⊥|`. (A quadratic model like the cycler's does not help here:
/// without the body's shape the worst initial rate along d̂ is already `|Ω|·r_max·|d̂⊥|`.)
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spinner {
    com: DVec3,
    axis: DVec3,
    rate: f64,
}

impl Spinner {
    /// A spinner about `axis` (normalised here) through `com`, at `rate` rad/s.
    ///
    /// # Errors
    /// [`MotionError::NonFinite`] for NaN or infinite input; [`MotionError::InvalidParameter`]
    /// for a zero axis.
    pub fn new(com: DVec3, axis: DVec3, rate: f64) -> Result<Self, MotionError> {
        Ok(Self {
            com: finite_vec("com", com)?,
            axis: unit_axis("axis", axis)?,
            rate: finite_scalar("rate", rate)?,
        })
    }

    /// The fixed centre of mass (world, m).
    #[must_use]
    pub fn com(&self) -> DVec3 {
        self.com
    }

    /// Unit rotation axis (world).
    #[must_use]
    pub fn axis(&self) -> DVec3 {
        self.axis
    }

    /// Rotation rate about [`Spinner::axis`] (rad/s).
    #[must_use]
    pub fn rate(&self) -> f64 {
        self.rate
    }

    /// The rotation the body undergoes between t0 and `t0 + dt` (world frame, about the COM):
    /// new orientation = `rotation_over(dt) * old orientation`.
    #[must_use]
    pub fn rotation_over(&self, dt: f64) -> DQuat {
        so3_exp(self.axis * (self.rate * dt))
    }

    /// TOI coefficients `(0, |Ω|·r_max·|d̂⊥|)` (derivation on the type). A NaN, negative or
    /// infinite `r_max`, or a non-finite `d_hat`, gives [`UNBOUNDED_COEFFICIENTS`].
    #[must_use]
    pub fn toi_coefficients(&self, d_hat: DVec3, r_max: f64) -> (f64, f64) {
        if !(d_hat.is_finite() && r_max >= 0.0 && r_max.is_finite()) {
            return UNBOUNDED_COEFFICIENTS;
        }
        let d_perp = d_hat - self.axis * self.axis.dot(d_hat);
        (0.0, self.rate.abs() * r_max * d_perp.length())
    }

    /// The COM does not move: the point box at `com`. The caller grows it by `r_max`, which
    /// bounds the whole swept body (every point stays within r_max of the COM).
    #[must_use]
    pub fn swept_com_aabb(&self, _dt: f64) -> Aabb {
        Aabb::new(self.com, self.com)
    }
}

/// Scripted sinusoidal translation at fixed orientation (a vibrating feeder tray):
/// `p(τ) = centre + a·sin(ω·τ + φ)·axis`.
///
/// World frame: `centre` (m), unit `axis`, amplitude `a ≥ 0` (m), angular frequency ω (rad/s),
/// phase φ at t0 (rad, stored in `[0, 2π)`). Velocity `aω·cos(ωτ + φ)·axis`, acceleration
/// `−aω²·sin(ωτ + φ)·axis`.
///
/// Coefficients (every point moves like the COM): with `s = axis·d̂`, the rate along d̂ is
/// `aω·cos(ωτ + φ)·s`, so
/// - linear: speed along d̂ ≤ `a|ω||s|`, giving `(0, a|ω||s|)`;
/// - quadratic: it starts at `v(t0)·d̂ = aω·cos φ·s` and changes at most at `aω²|s|`, giving
///   `(½aω²|s|, aω·cos φ·s)`;
///
/// and the cycler's rule chooses: the two meet at `D* = 2[a|ω||s| − v(t0)·d̂]/|ω|`; quadratic
/// when `D* > gap`, linear otherwise.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Oscillator {
    centre: DVec3,
    axis: DVec3,
    amplitude: f64,
    omega: f64,
    phase: f64,
}

impl Oscillator {
    /// An oscillator along `axis` (normalised here) about `centre`.
    ///
    /// # Errors
    /// [`MotionError::NonFinite`] for NaN or infinite input; [`MotionError::InvalidParameter`]
    /// for a negative amplitude or a zero axis.
    pub fn new(
        centre: DVec3,
        axis: DVec3,
        amplitude: f64,
        omega: f64,
        phase: f64,
    ) -> Result<Self, MotionError> {
        Ok(Self {
            centre: finite_vec("centre", centre)?,
            axis: unit_axis("axis", axis)?,
            amplitude: non_negative("amplitude", amplitude)?,
            omega: finite_scalar("omega", omega)?,
            phase: wrap_angle(finite_scalar("phase", phase)?),
        })
    }

    /// Centre of the oscillation (world, m).
    #[must_use]
    pub fn centre(&self) -> DVec3 {
        self.centre
    }

    /// Unit direction of oscillation (world).
    #[must_use]
    pub fn axis(&self) -> DVec3 {
        self.axis
    }

    /// Amplitude a (m).
    #[must_use]
    pub fn amplitude(&self) -> f64 {
        self.amplitude
    }

    /// Angular frequency ω (rad/s).
    #[must_use]
    pub fn omega(&self) -> f64 {
        self.omega
    }

    /// Phase φ at t0 in `[0, 2π)` (rad).
    #[must_use]
    pub fn phase(&self) -> f64 {
        self.phase
    }

    fn linear_coefficients(&self, d_hat: DVec3) -> (f64, f64) {
        let s = self.axis.dot(d_hat).abs();
        (0.0, self.amplitude * self.omega.abs() * s)
    }

    fn quadratic_coefficients(&self, d_hat: DVec3) -> (f64, f64) {
        let s = self.axis.dot(d_hat).abs();
        let a = 0.5 * self.amplitude * self.omega * self.omega * s;
        (a, self.com_velocity_at(0.0).dot(d_hat))
    }

    /// TOI coefficients, linear or quadratic by the D* rule (derivation on the type). `r_max`
    /// is not needed (no rotation). A NaN `gap` selects linear; a non-finite `d_hat` gives
    /// [`UNBOUNDED_COEFFICIENTS`].
    #[must_use]
    pub fn toi_coefficients(&self, d_hat: DVec3, gap: f64) -> (f64, f64) {
        if !d_hat.is_finite() {
            return UNBOUNDED_COEFFICIENTS;
        }
        let (_, b_lin) = self.linear_coefficients(d_hat);
        let (a_quad, b_quad) = self.quadratic_coefficients(d_hat);
        select_model(self.omega, b_lin, a_quad, b_quad, gap)
    }

    /// Box enclosing the COM path between t0 and `t0 + dt` (either order): the path is the
    /// segment `centre + a·sin θ·axis`, so the box spans `sin θ` over the swept phase interval,
    /// including the turning points `sin θ = ±1` reached inside it (the whole segment when
    /// `|ω·dt| ≥ 2π`). Padded by [`SWEPT_BOX_ROUNDING_REL`]. NaN `dt` gives the box of all
    /// space; an infinite `dt` the whole segment.
    #[must_use]
    pub fn swept_com_aabb(&self, dt: f64) -> Aabb {
        if dt.is_nan() {
            return ALL_SPACE;
        }
        let (s_min, s_max) = if dt.is_infinite() {
            (-1.0, 1.0)
        } else {
            let sweep = self.omega * dt;
            let (lo, hi) = if sweep >= 0.0 {
                (self.phase, self.phase + sweep)
            } else {
                (self.phase + sweep, self.phase)
            };
            // sin θ = cos(θ − π/2).
            cos_range(lo - 0.5 * PI, hi - 0.5 * PI)
        };
        let reach = self.axis * self.amplitude;
        let mut b = Aabb::new(self.centre + reach * s_min, self.centre + reach * s_max);
        if dt.is_finite() {
            b = Aabb::from_points([b.min, b.max, self.com_at(0.0), self.com_at(dt)]);
        }
        pad(b, self.centre.abs() + reach.abs())
    }

    /// Centre of mass at `t0 + dt` (world, m).
    #[must_use]
    pub fn com_at(&self, dt: f64) -> DVec3 {
        self.centre + self.axis * (self.amplitude * (self.omega * dt + self.phase).sin())
    }

    /// Centre-of-mass velocity at `t0 + dt` (world, m/s).
    #[must_use]
    pub fn com_velocity_at(&self, dt: f64) -> DVec3 {
        self.axis * (self.amplitude * self.omega * (self.omega * dt + self.phase).cos())
    }

    /// The same motion re-based at `t0 + dt` (phase advanced by `ω·dt`, wrapped to `[0, 2π)`).
    ///
    /// # Errors
    /// [`MotionError::NonFinite`] when `dt` or the new phase is not finite.
    pub fn advance(&self, dt: f64) -> Result<Self, MotionError> {
        finite_scalar("dt", dt)?;
        let phase = finite_scalar("phase", self.phase + self.omega * dt)?;
        Ok(Self {
            phase: wrap_angle(phase),
            ..*self
        })
    }
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
        }
    }

    /// Centre of mass at `t0 + dt` (world, m). A non-finite `dt` gives a non-finite result for
    /// the types whose COM moves.
    #[must_use]
    pub fn com_at(&self, dt: f64) -> DVec3 {
        match self {
            Motion::Fixed { com } => *com,
            Motion::Ballistic(m) => m.com_at(dt),
            Motion::Cycler(m) => m.com_at(dt),
            Motion::Spinner(m) => m.com,
            Motion::Oscillator(m) => m.com_at(dt),
        }
    }

    /// Centre-of-mass velocity at `t0 + dt` (world, m/s).
    #[must_use]
    pub fn com_velocity_at(&self, dt: f64) -> DVec3 {
        match self {
            Motion::Fixed { .. } | Motion::Spinner(_) => DVec3::ZERO,
            Motion::Ballistic(m) => m.com_velocity_at(dt),
            Motion::Cycler(m) => m.com_velocity_at(dt),
            Motion::Oscillator(m) => m.com_velocity_at(dt),
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
            Motion::Fixed { .. } | Motion::Spinner(_) => *self,
            Motion::Ballistic(m) => Motion::Ballistic(m.advance(dt)?),
            Motion::Cycler(m) => Motion::Cycler(m.advance(dt)?),
            Motion::Oscillator(m) => Motion::Oscillator(m.advance(dt)?),
        })
    }
}

fn check_principal(principal_moments: DVec3, omega: DVec3) -> Result<f64, MotionError> {
    finite_vec("principal moments", principal_moments)?;
    finite_vec("omega", omega)?;
    let i_min = principal_moments.min_element();
    if i_min > 0.0 {
        Ok(i_min)
    } else {
        Err(MotionError::InvalidParameter {
            name: "principal moment of inertia",
            value: i_min,
            requirement: "must be > 0",
        })
    }
}

fn finite_bound(x: f64) -> Result<f64, MotionError> {
    finite_scalar("omega_max (overflow)", x)
}

/// Energy bound on the angular speed of a torque-free body (eq. 2.5; rad/s):
/// `‖ω(t)‖ ≤ √(2E / I_min)`, `2E = I_x·ω_x² + I_y·ω_y² + I_z·ω_z²`.
///
/// `principal_moments` are `(I_x, I_y, I_z)` (kg·m², body principal frame) and `omega_body` the
/// current angular velocity in that frame (rad/s). Rotational kinetic energy is conserved in
/// ballistic flight, and the energy ellipsoid's semi-major axis is `√(2E/I_min)`. Never looser
/// than [`omega_max_momentum`]. Computed with ω scaled by its largest component, so it overflows
/// only if the bound itself does.
///
/// # Errors
/// [`MotionError::NonFinite`] for NaN or infinite input or an overflowing result;
/// [`MotionError::InvalidParameter`] when a principal moment is not positive.
pub fn omega_max_energy(principal_moments: DVec3, omega_body: DVec3) -> Result<f64, MotionError> {
    let i_min = check_principal(principal_moments, omega_body)?;
    let s = omega_body.abs().max_element();
    if s == 0.0 {
        return Ok(0.0);
    }
    let w = omega_body / s;
    let two_e = principal_moments.dot(w * w);
    finite_bound((two_e / i_min).sqrt() * s)
}

/// Bound on the angular acceleration of a torque-free body (rad/s²):
/// `‖ω̇(t)‖ ≤ ‖L‖·ω_max / I_min`, from Euler's equations in world form, I_w·ω̇ = L × ω with L
/// constant, and ω_max the energy bound [`omega_max_energy`]. Same inputs and errors.
///
/// # Errors
/// As [`omega_max_energy`].
pub fn alpha_max_torque_free(
    principal_moments: DVec3,
    omega_body: DVec3,
) -> Result<f64, MotionError> {
    let i_min = check_principal(principal_moments, omega_body)?;
    let omega_max = omega_max_energy(principal_moments, omega_body)?;
    let s = omega_body.abs().max_element();
    if s == 0.0 {
        return Ok(0.0);
    }
    let l = (principal_moments * (omega_body / s)).length() * s;
    finite_bound(l / i_min * omega_max)
}

/// Momentum bound on the angular speed of a torque-free body (eq. 2.4; rad/s):
/// `‖ω(t)‖ ≤ ‖L‖ / I_min = √(I_x²ω_x² + I_y²ω_y² + I_z²ω_z²) / I_min`.
///
/// The bound published in \[MC95b\] (Mirtich & Canny 1995); looser than [`omega_max_energy`]:
/// their ratio (2.6) is `r ∈ [√(I_min/I_max), 1]`. Same inputs and errors.
///
/// # Errors
/// As [`omega_max_energy`].
pub fn omega_max_momentum(principal_moments: DVec3, omega_body: DVec3) -> Result<f64, MotionError> {
    let i_min = check_principal(principal_moments, omega_body)?;
    let s = omega_body.abs().max_element();
    if s == 0.0 {
        return Ok(0.0);
    }
    let l = principal_moments * (omega_body / s);
    finite_bound(l.length() / i_min * s)
}

/// Symmetrises a world inertia tensor and returns it with a lower bound on its smallest
/// eigenvalue (kg·m²), refusing non-finite, asymmetric or non-positive-definite tensors.
fn checked_world_inertia(inertia: DMat3, omega: DVec3) -> Result<(DMat3, f64), MotionError> {
    if !inertia.is_finite() {
        return Err(MotionError::NonFinite {
            name: "world inertia tensor",
        });
    }
    finite_vec("omega", omega)?;
    let t = inertia.transpose();
    let scale = inertia
        .abs()
        .to_cols_array()
        .into_iter()
        .fold(0.0, f64::max);
    let asym = (inertia - t)
        .abs()
        .to_cols_array()
        .into_iter()
        .fold(0.0, f64::max);
    if asym > INERTIA_SYMMETRY_TOLERANCE * scale {
        return Err(MotionError::InvalidParameter {
            name: "world inertia asymmetry (relative)",
            value: asym / scale,
            requirement: "the inertia tensor must be symmetric (see INERTIA_SYMMETRY_TOLERANCE)",
        });
    }
    let sym = (inertia + t) * 0.5;
    let i_min = min_eigenvalue_lower_bound(sym);
    if i_min > 0.0 {
        Ok((sym, i_min))
    } else {
        Err(MotionError::InvalidParameter {
            name: "smallest principal moment of the world inertia tensor",
            value: i_min,
            requirement: "must be > 0 (tensor must be positive definite)",
        })
    }
}

/// Eq. (2.5) from world-frame data: `2E = ω·(I ω)` is the same in every frame, and `I_min` is the
/// smallest eigenvalue of the world inertia tensor (kg·m²; found by Jacobi iteration, as a
/// lower bound). `omega_world` in rad/s; result in rad/s.
///
/// # Errors
/// [`MotionError::NonFinite`] for NaN or infinite input or an overflowing result;
/// [`MotionError::InvalidParameter`] for an asymmetric (beyond
/// [`INERTIA_SYMMETRY_TOLERANCE`]) or non-positive-definite tensor.
pub fn omega_max_energy_world(
    inertia_world: DMat3,
    omega_world: DVec3,
) -> Result<f64, MotionError> {
    let (sym, i_min) = checked_world_inertia(inertia_world, omega_world)?;
    let s = omega_world.abs().max_element();
    if s == 0.0 {
        return Ok(0.0);
    }
    let w = omega_world / s;
    // ω·Iω ≥ I_min·|ω|² > 0 in exact arithmetic; max(0) guards rounding of a tiny ω component.
    let two_e = w.dot(sym * w).max(0.0);
    finite_bound((two_e / i_min).sqrt() * s)
}

/// Eq. (2.4) from world-frame data: `‖L‖ = ‖I ω‖` is frame independent. Same inputs and errors
/// as [`omega_max_energy_world`].
///
/// # Errors
/// As [`omega_max_energy_world`].
pub fn omega_max_momentum_world(
    inertia_world: DMat3,
    omega_world: DVec3,
) -> Result<f64, MotionError> {
    let (sym, i_min) = checked_world_inertia(inertia_world, omega_world)?;
    let s = omega_world.abs().max_element();
    if s == 0.0 {
        return Ok(0.0);
    }
    finite_bound((sym * (omega_world / s)).length() / i_min * s)
}

/// Lower bound on the smallest eigenvalue of a symmetric 3×3 matrix by cyclic Jacobi rotations.
///
/// Option A, the closed-form trigonometric solution, loses about √ε relative accuracy when two
/// eigenvalues nearly coincide (acos near ±1); option B, Jacobi, is accurate to ~ε·‖M‖ and its
/// leftover off-diagonal norm bounds the error (Weyl). Chose B. The result is the smallest
/// diagonal entry minus that leftover norm.
fn min_eigenvalue_lower_bound(m: DMat3) -> f64 {
    let mut a = [
        m.x_axis.to_array(),
        m.y_axis.to_array(),
        m.z_axis.to_array(),
    ];
    let frob = |a: &[[f64; 3]; 3]| a.iter().flatten().map(|x| x * x).sum::<f64>().sqrt();
    let off =
        |a: &[[f64; 3]; 3]| (2.0 * (a[0][1].powi(2) + a[0][2].powi(2) + a[1][2].powi(2))).sqrt();
    let total = frob(&a);
    for _ in 0..JACOBI_MAX_SWEEPS {
        if off(&a) <= JACOBI_OFF_DIAGONAL_REL * total {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            let apq = a[p][q];
            if apq == 0.0 {
                continue;
            }
            // Rotation in the (p, q) plane that zeroes a[p][q] (Golub & Van Loan §8.5).
            let theta = (a[q][q] - a[p][p]) / (2.0 * apq);
            let t = theta.signum() / (theta.abs() + theta.hypot(1.0));
            let c = 1.0 / t.hypot(1.0);
            let s = t * c;
            for row in &mut a {
                let (akp, akq) = (row[p], row[q]);
                row[p] = c * akp - s * akq;
                row[q] = s * akp + c * akq;
            }
            let (row_p, row_q) = (a[p], a[q]);
            a[p] = core::array::from_fn(|k| c * row_p[k] - s * row_q[k]);
            a[q] = core::array::from_fn(|k| s * row_p[k] + c * row_q[k]);
            a[p][q] = 0.0;
            a[q][p] = 0.0;
        }
    }
    a[0][0].min(a[1][1]).min(a[2][2]) - off(&a)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use rand::rngs::Xoshiro256PlusPlus;
    use rand::{RngExt, SeedableRng};

    /// Rotation (rad) the RK4 reference advances per step at the fastest possible spin
    /// (ω_max): its local error is ~(step)⁵, so energy and |L| stay within
    /// [`CONSERVATION_TOL`] over [`SPAN_ANGLE`].
    const STEP_ANGLE: f64 = 2e-3;
    /// Length of each reference trajectory, as the angle ω_max·T (rad): several turns and
    /// several tumbling periods of the Euler equations.
    const SPAN_ANGLE: f64 = 30.0;
    /// Relative drift of rotational energy and of |L| allowed along an RK4 trajectory.
    const CONSERVATION_TOL: f64 = 1e-9;
    /// Slack when comparing a true displacement with its bound, relative to the size of the
    /// quantities involved (r_max + |v|τ + |g|τ²); covers RK4 and rounding error (~1e-10).
    const BOUND_SLACK_REL: f64 = 1e-8;
    /// Relative slack of ‖ω(t)‖ ≤ (2.5) along RK4 trajectories (RK4 drift, ~1e-10).
    const OMEGA_SLACK_REL: f64 = 1e-9;
    /// Agreement of closed forms evaluated two ways (ratios, world vs body frame), relative.
    const CLOSED_FORM_TOL: f64 = 1e-12;
    /// Time samples per swept interval when checking swept boxes.
    const PATH_SAMPLES: usize = 4000;
    /// Full-turn swept boxes against the analytic box of the whole path (m, absolute; paths of
    /// size ~5 m, padded by 1e-12 relative).
    const FULL_PATH_TOL: f64 = 1e-10;
    /// Displacement/bound ratios are reported only where the bound exceeds this fraction of the
    /// body size (below it the ratio is dominated by rounding).
    const RATIO_FLOOR_REL: f64 = 1e-3;
    /// How much an endpoints-only box is grown before showing that it still misses the apex (m).
    const ENDPOINT_BOX_MARGIN: f64 = 1e-9;
    /// Gram–Schmidt output: deviation from orthonormality (a few ε).
    const ORTHONORMAL_TOL: f64 = 4.0 * f64::EPSILON;

    pub(crate) fn rng(seed: u64) -> Xoshiro256PlusPlus {
        Xoshiro256PlusPlus::seed_from_u64(seed)
    }

    pub(crate) fn unit_vector(rng: &mut Xoshiro256PlusPlus) -> DVec3 {
        let z: f64 = rng.random_range(-1.0..=1.0);
        let phi = rng.random_range(0.0..TAU);
        let r = (1.0 - z * z).max(0.0).sqrt();
        DVec3::new(r * phi.cos(), r * phi.sin(), z)
    }

    pub(crate) fn random_rotation(rng: &mut Xoshiro256PlusPlus) -> DQuat {
        DQuat::from_xyzw(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        )
        .normalize()
    }

    /// Torque-free rigid rotation integrated by classical RK4: Euler's equations in the
    /// principal body frame, `I·ω̇ = (I·ω) × ω`, and `q̇ = ½·q ⊗ (ω, 0)` (q maps body to world).
    /// The independent reference for every ω and displacement bound.
    #[derive(Clone, Copy, Debug)]
    pub(crate) struct Tumbler {
        pub(crate) inertia: DVec3,
        pub(crate) q: DQuat,
        pub(crate) w: DVec3,
    }

    impl Tumbler {
        fn derivative(&self, q: DQuat, w: DVec3) -> (DQuat, DVec3) {
            let w_dot = (self.inertia * w).cross(w) / self.inertia;
            let q_dot = q * DQuat::from_xyzw(w.x, w.y, w.z, 0.0) * 0.5;
            (q_dot, w_dot)
        }

        pub(crate) fn step(&self, h: f64) -> Tumbler {
            let (q, w) = (self.q, self.w);
            let (k1q, k1w) = self.derivative(q, w);
            let (k2q, k2w) = self.derivative(q + k1q * (0.5 * h), w + k1w * (0.5 * h));
            let (k3q, k3w) = self.derivative(q + k2q * (0.5 * h), w + k2w * (0.5 * h));
            let (k4q, k4w) = self.derivative(q + k3q * h, w + k3w * h);
            Tumbler {
                inertia: self.inertia,
                q: (q + (k1q + k2q * 2.0 + k3q * 2.0 + k4q) * (h / 6.0)).normalize(),
                w: w + (k1w + k2w * 2.0 + k3w * 2.0 + k4w) * (h / 6.0),
            }
        }

        pub(crate) fn energy2(&self) -> f64 {
            self.inertia.dot(self.w * self.w)
        }

        pub(crate) fn momentum_world(&self) -> DVec3 {
            self.q * (self.inertia * self.w)
        }
    }

    /// A tumbling box: RK4 states on a uniform grid, plus exact ballistic COM motion.
    pub(crate) struct Trajectory {
        pub(crate) half: DVec3,
        pub(crate) com0: DVec3,
        pub(crate) v0: DVec3,
        pub(crate) g: DVec3,
        pub(crate) h: f64,
        pub(crate) states: Vec<Tumbler>,
    }

    impl Trajectory {
        pub(crate) fn new(
            half: DVec3,
            start: Tumbler,
            (com0, v0, g): (DVec3, DVec3, DVec3),
            span: f64,
        ) -> Self {
            let w_bound = omega_max_energy(start.inertia, start.w)
                .unwrap()
                .max(1e-300);
            let steps = ((span * w_bound / STEP_ANGLE).ceil() as usize).max(1000);
            let h = span / steps as f64;
            let mut states = Vec::with_capacity(steps + 1);
            states.push(start);
            for k in 0..steps {
                states.push(states[k].step(h));
            }
            Self {
                half,
                com0,
                v0,
                g,
                h,
                states,
            }
        }

        /// Rotational state at any t in the span: a partial RK4 step from the grid point below.
        pub(crate) fn state_at(&self, t: f64) -> Tumbler {
            let k = ((t / self.h).floor() as usize).min(self.states.len() - 1);
            let rest = t - k as f64 * self.h;
            if rest > 0.0 {
                self.states[k].step(rest)
            } else {
                self.states[k]
            }
        }

        pub(crate) fn com_at(&self, t: f64) -> DVec3 {
            self.com0 + self.v0 * t + self.g * (0.5 * t * t)
        }

        pub(crate) fn vertices(&self, com: DVec3, q: DQuat) -> [DVec3; 8] {
            core::array::from_fn(|i| {
                let s = DVec3::new(
                    if i & 1 == 0 { -1.0 } else { 1.0 },
                    if i & 2 == 0 { -1.0 } else { 1.0 },
                    if i & 4 == 0 { -1.0 } else { 1.0 },
                );
                com + q * (s * self.half)
            })
        }
    }

    /// Principal moments of a solid box of unit mass with these half extents (kg·m²).
    pub(crate) fn box_inertia(half: DVec3) -> DVec3 {
        let s = half * half;
        DVec3::new(s.y + s.z, s.x + s.z, s.x + s.y) / 3.0
    }

    /// A random box with inertia ratio at most 100, biased toward elongated shapes.
    fn random_box(rng: &mut Xoshiro256PlusPlus) -> DVec3 {
        loop {
            let half = DVec3::new(
                10f64.powf(rng.random_range(-1.0..0.15)),
                10f64.powf(rng.random_range(-1.0..0.15)),
                10f64.powf(rng.random_range(-1.0..0.15)),
            );
            let i = box_inertia(half);
            if i.max_element() / i.min_element() <= 100.0 {
                return half;
            }
        }
    }

    /// A random launch of a body with principal moments `inertia`: spin log-uniform in
    /// [0.1, 10^max_log_spin] rad/s about a random axis from a random orientation, speed up to
    /// `max_speed`, gravity on odd cases.
    fn random_launch(
        rng: &mut Xoshiro256PlusPlus,
        case: usize,
        inertia: DVec3,
        max_log_spin: f64,
        max_speed: f64,
    ) -> (Tumbler, DVec3, DVec3) {
        let spin = 10f64.powf(rng.random_range(-1.0..max_log_spin));
        let w = unit_vector(rng) * spin;
        let g = if case % 2 == 0 {
            DVec3::ZERO
        } else {
            unit_vector(rng) * 9.81
        };
        let v0 = unit_vector(rng) * rng.random_range(0.0..max_speed);
        let q = random_rotation(rng);
        (Tumbler { inertia, q, w }, v0, g)
    }

    /// The spin refinement: for directions near the spin axis (where it is chosen) and random
    /// ones, the coefficients returned for a small gap bound every vertex's displacement over a
    /// tumbling box's trajectory (RK4 reference), and near the axis they are tighter than
    /// eq. 2.3.
    #[test]
    fn spin_refined_coefficients_bound_every_vertex() {
        const CASES: usize = 32;
        let mut rng = rng(77);
        let (mut refined_used, mut checked) = (0, 0);
        for case in 0..CASES {
            let half = random_box(&mut rng);
            let inertia = box_inertia(half);
            let (start, v0, g) = random_launch(&mut rng, case, inertia, 2.0, 0.5);
            let w0 = start.w;
            let omega_max = omega_max_energy(inertia, w0).unwrap();
            let alpha = alpha_max_torque_free(inertia, w0).unwrap();
            let w_world = start.q * w0;
            let motion = Motion::from(
                Ballistic::new(DVec3::ZERO, v0, g, omega_max)
                    .unwrap()
                    .with_spin(w_world, alpha)
                    .unwrap(),
            );
            let r_max = half.length();
            let dirs: Vec<DVec3> = (0..12)
                .map(|k| {
                    if k < 6 {
                        (w_world.normalize() + unit_vector(&mut rng) * 0.05 * k as f64).normalize()
                    } else {
                        unit_vector(&mut rng)
                    }
                })
                .collect();
            let gap = 1e-4 * r_max;
            let coeffs: Vec<(f64, f64)> = dirs
                .iter()
                .map(|&d| motion.toi_coefficients(d, r_max, gap))
                .collect();
            let Motion::Ballistic(b) = motion else {
                unreachable!()
            };
            for (&d, &c) in dirs.iter().zip(&coeffs) {
                if c != b.toi_coefficients(d, r_max) {
                    refined_used += 1;
                    assert!(
                        crate::toi::pair_toi(gap, c, (0.0, 0.0))
                            > crate::toi::pair_toi(gap, b.toi_coefficients(d, r_max), (0.0, 0.0))
                    );
                }
            }
            let traj = Trajectory::new(half, start, (DVec3::ZERO, v0, g), SPAN_ANGLE / omega_max);
            let v_start = traj.vertices(DVec3::ZERO, start.q);
            for (k, s) in traj.states.iter().enumerate().skip(1) {
                let tau = k as f64 * traj.h;
                let verts = traj.vertices(traj.com_at(tau), s.q);
                let scale = r_max + v0.length() * tau + g.length() * tau * tau;
                for (&d, &(a, b)) in dirs.iter().zip(&coeffs) {
                    let bound = a * tau * tau + b * tau;
                    for (x, x0) in verts.iter().zip(&v_start) {
                        checked += 1;
                        let disp = (*x - *x0).dot(d);
                        assert!(
                            disp <= bound + BOUND_SLACK_REL * scale,
                            "case {case} τ {tau}: displacement {disp} > bound {bound}"
                        );
                    }
                }
            }
        }
        assert!(
            refined_used >= CASES * 3,
            "refinement chosen {refined_used} times"
        );
        eprintln!(
            "spin refinement chosen for {refined_used} of {} directions; {checked} vertex checks",
            CASES * 12
        );
    }

    #[test]
    fn ballistic_coefficients_bound_every_vertex_of_a_tumbling_box() {
        const CASES: usize = 48;
        const DIRECTIONS: usize = 12;
        let mut rng = rng(2024);
        let mut worst_rot_ratio: f64 = 0.0;
        let mut worst_total_ratio: f64 = 0.0;
        let mut max_inertia_ratio: f64 = 0.0;
        let mut max_drift: f64 = 0.0;
        for case in 0..CASES {
            let half = match case {
                0 => DVec3::splat(0.5),         // cube
                1 => DVec3::new(1.4, 0.1, 0.1), // rod, ratio 98.5
                _ => random_box(&mut rng),
            };
            let inertia = box_inertia(half);
            max_inertia_ratio =
                max_inertia_ratio.max(inertia.max_element() / inertia.min_element());
            let (start, v0, g) = random_launch(&mut rng, case, inertia, 3.0, 5.0);
            let w0 = start.w;
            let omega_max = omega_max_energy(inertia, w0).unwrap();
            let traj = Trajectory::new(half, start, (DVec3::ZERO, v0, g), SPAN_ANGLE / omega_max);
            let motion = Motion::from(Ballistic::new(DVec3::ZERO, v0, g, omega_max).unwrap());
            let r_max = half.length();
            let dirs: Vec<DVec3> = (0..DIRECTIONS).map(|_| unit_vector(&mut rng)).collect();
            let coeffs: Vec<(f64, f64)> = dirs
                .iter()
                .map(|&d| motion.toi_coefficients(d, r_max, 1.0))
                .collect();
            let v_start = traj.vertices(DVec3::ZERO, start.q);
            let (e0, l0) = (start.energy2(), start.momentum_world());
            for (k, s) in traj.states.iter().enumerate().skip(1) {
                let tau = k as f64 * traj.h;
                max_drift = max_drift
                    .max((s.energy2() - e0).abs() / e0)
                    .max((s.momentum_world() - l0).length() / l0.length());
                let com = traj.com_at(tau);
                let verts = traj.vertices(com, s.q);
                let rot_bound = r_max * omega_max * tau;
                let scale = r_max + v0.length() * tau + g.length() * tau * tau;
                for (&d, &(a, b)) in dirs.iter().zip(&coeffs) {
                    let bound = a * tau * tau + b * tau;
                    for (x, x0) in verts.iter().zip(&v_start) {
                        let disp = (*x - *x0).dot(d);
                        assert!(
                            disp <= bound + BOUND_SLACK_REL * scale,
                            "case {case} τ {tau}: displacement {disp} > bound {bound}"
                        );
                        let rot = disp - (com.dot(d));
                        worst_rot_ratio = worst_rot_ratio.max(rot / rot_bound);
                        if bound > RATIO_FLOOR_REL * r_max {
                            worst_total_ratio = worst_total_ratio.max(disp / bound);
                        }
                    }
                }
            }
        }
        assert!(max_drift <= CONSERVATION_TOL, "RK4 drift {max_drift}");
        assert!(max_inertia_ratio > 90.0);
        assert!(worst_rot_ratio <= 1.0 + BOUND_SLACK_REL);
        eprintln!(
            "ballistic bound: max rotational displacement / (r_max·ω_max·τ) = \
             {worst_rot_ratio:.4}, \
             max displacement / bound = {worst_total_ratio:.4}, max RK4 drift = {max_drift:.2e}, \
             max inertia ratio = {max_inertia_ratio:.1}"
        );
    }

    #[test]
    fn omega_bounds_hold_along_torque_free_trajectories() {
        const CASES: usize = 40;
        let mut rng = rng(77);
        let mut tightest: f64 = 0.0;
        for case in 0..CASES {
            let half = if case == 0 {
                DVec3::new(1.4, 0.1, 0.1)
            } else {
                random_box(&mut rng)
            };
            let inertia = box_inertia(half);
            let w0 = unit_vector(&mut rng) * 10f64.powf(rng.random_range(-1.0..3.0));
            let energy = omega_max_energy(inertia, w0).unwrap();
            let momentum = omega_max_momentum(inertia, w0).unwrap();
            assert!(energy <= momentum * (1.0 + CLOSED_FORM_TOL));
            let start = Tumbler {
                inertia,
                q: DQuat::IDENTITY,
                w: w0,
            };
            let traj = Trajectory::new(half, start, (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO), {
                SPAN_ANGLE / energy
            });
            for s in &traj.states {
                let w = s.w.length();
                assert!(
                    w <= energy * (1.0 + OMEGA_SLACK_REL),
                    "case {case}: |ω| {w} > {energy}"
                );
                tightest = tightest.max(w / energy);
            }
        }
        eprintln!("max |ω(t)| / eq. 2.5 along trajectories: {tightest:.6}");
    }

    /// The ratio (2.6) of the energy bound to the momentum bound.
    fn ratio(i: DVec3, w: DVec3) -> f64 {
        omega_max_energy(i, w).unwrap() / omega_max_momentum(i, w).unwrap()
    }

    #[test]
    fn ratio_of_energy_to_momentum_bound_lies_in_its_range() {
        let mut rng = rng(5);
        for _ in 0..5000 {
            let i = DVec3::new(
                10f64.powf(rng.random_range(-2.0..2.0)),
                10f64.powf(rng.random_range(-2.0..2.0)),
                10f64.powf(rng.random_range(-2.0..2.0)),
            );
            let w = unit_vector(&mut rng) * 10f64.powf(rng.random_range(-3.0..3.0));
            let r = ratio(i, w);
            let lo = (i.min_element() / i.max_element()).sqrt();
            assert!(r >= lo * (1.0 - CLOSED_FORM_TOL) && r <= 1.0 + CLOSED_FORM_TOL);
            // Spin about the min-inertia axis: 1; about the max axis: √(I_min/I_max).
            let min_axis = DVec3::AXES[i.min_position()] * 3.0;
            let max_axis = DVec3::AXES[i.max_position()] * 3.0;
            assert!((ratio(i, min_axis) - 1.0).abs() <= CLOSED_FORM_TOL);
            assert!((ratio(i, max_axis) - lo).abs() <= CLOSED_FORM_TOL * lo);
            // Equal moments (cube, sphere): 1 for any spin.
            assert!((ratio(DVec3::splat(i.x), w) - 1.0).abs() <= CLOSED_FORM_TOL);
        }
    }

    #[test]
    fn world_frame_bounds_equal_body_frame_bounds() {
        let mut rng = rng(11);
        let mut worst: f64 = 0.0;
        for case in 0..4000 {
            let mut moments = DVec3::new(
                10f64.powf(rng.random_range(-3.0..3.0)),
                10f64.powf(rng.random_range(-3.0..3.0)),
                10f64.powf(rng.random_range(-3.0..3.0)),
            );
            // Repeated eigenvalues: the hard case for closed-form eigenvalue formulas.
            match case % 4 {
                0 => moments.y = moments.x,
                1 => moments = DVec3::splat(moments.x),
                2 => moments.y = moments.x * (1.0 + 1e-9),
                _ => {}
            }
            let r = DMat3::from_quat(random_rotation(&mut rng));
            let inertia_world = r * DMat3::from_diagonal(moments) * r.transpose();
            let w_body = unit_vector(&mut rng) * 10f64.powf(rng.random_range(-2.0..3.0));
            let w_world = r * w_body;
            let body = omega_max_energy(moments, w_body).unwrap();
            let world = omega_max_energy_world(inertia_world, w_world).unwrap();
            let body_l = omega_max_momentum(moments, w_body).unwrap();
            let world_l = omega_max_momentum_world(inertia_world, w_world).unwrap();
            // Tensor rounding is relative to the largest moment; the bound scales as
            // √(I_max/I_min), so compare with that factor.
            let cond = moments.max_element() / moments.min_element();
            let rel = (world - body).abs() / body / cond;
            worst = worst.max(rel);
            assert!(rel <= CLOSED_FORM_TOL, "case {case}: {world} vs {body}");
            assert!((world_l - body_l).abs() / body_l / cond <= CLOSED_FORM_TOL);
            // The eigenvalue is a lower bound (to rounding of the tensor itself).
            let lam = min_eigenvalue_lower_bound(inertia_world);
            let err = lam - moments.min_element();
            assert!(
                err <= CLOSED_FORM_TOL * moments.max_element(),
                "{lam} vs {moments}"
            );
        }
        eprintln!("world vs body ω_max, max relative difference / cond: {worst:.2e}");
    }

    #[test]
    fn bad_inertia_and_spin_are_refused() {
        let w = DVec3::new(1.0, 2.0, 3.0);
        let i = DVec3::new(1.0, 2.0, 3.0);
        for bad in [DVec3::new(0.0, 1.0, 1.0), DVec3::new(-1.0, 1.0, 1.0)] {
            assert!(matches!(
                omega_max_energy(bad, w),
                Err(MotionError::InvalidParameter { .. })
            ));
            assert!(omega_max_momentum(bad, w).is_err());
        }
        assert!(matches!(
            omega_max_energy(DVec3::new(f64::NAN, 1.0, 1.0), w),
            Err(MotionError::NonFinite { .. })
        ));
        assert!(omega_max_energy(i, DVec3::new(0.0, f64::INFINITY, 0.0)).is_err());
        assert_eq!(omega_max_energy(i, DVec3::ZERO), Ok(0.0));
        // Huge but finite spin: no intermediate overflow.
        let big = omega_max_energy(DVec3::ONE, DVec3::new(1e200, 0.0, 0.0)).unwrap();
        assert_eq!(big, 1e200);
        assert!(omega_max_energy(DVec3::new(1e-300, 1.0, 1.0), DVec3::Y * 1e300).is_err());
        let sym = DMat3::from_diagonal(i);
        let mut asym = sym;
        asym.x_axis.y += 1e-3;
        assert!(omega_max_energy_world(asym, w).is_err());
        let indefinite = DMat3::from_diagonal(DVec3::new(1.0, -1.0, 2.0));
        assert!(omega_max_energy_world(indefinite, w).is_err());
        let mut nan = sym;
        nan.z_axis.z = f64::NAN;
        assert!(omega_max_energy_world(nan, w).is_err());
        assert!(omega_max_momentum_world(DMat3::ZERO, w).is_err());
    }

    /// Samples `motion.com_at` densely over [0, dt] and checks the swept box contains every
    /// sample, and that each face is within `sampling_slack` of the samples (tight: every
    /// extremum is a real point of the path).
    fn check_swept_box(motion: &Motion, dt: f64, sampling_slack: f64) -> Aabb {
        let b = motion.swept_com_aabb(dt);
        let samples = Aabb::from_points(
            (0..=PATH_SAMPLES).map(|k| motion.com_at(dt * k as f64 / PATH_SAMPLES as f64)),
        );
        assert!(
            b.min.cmple(samples.min).all() && samples.max.cmple(b.max).all(),
            "{motion:?} dt {dt}: box {b:?} misses samples {samples:?}"
        );
        let excess = (samples.min - b.min).max(b.max - samples.max);
        assert!(
            excess.max_element() <= sampling_slack,
            "{motion:?} dt {dt}: box {b:?} larger than path {samples:?}"
        );
        b
    }

    /// Largest gap between a sampled maximum and the true one for a path with acceleration
    /// at most `acc` sampled every `dt / PATH_SAMPLES`, plus the box padding.
    fn sampling_slack(acc: f64, dt: f64, scale: f64) -> f64 {
        let step = dt / PATH_SAMPLES as f64;
        0.5 * acc * step * step + 2.0 * SWEPT_BOX_ROUNDING_REL * scale
    }

    #[test]
    fn ballistic_swept_box_includes_the_apex() {
        let g = DVec3::new(0.0, 0.0, -9.81);
        let throw =
            Motion::from(Ballistic::new(DVec3::ZERO, DVec3::new(1.0, 0.5, 5.0), g, 3.0).unwrap());
        let dt = 1.0; // apex at 5/9.81 ≈ 0.51 s
        let b = check_swept_box(&throw, dt, sampling_slack(9.81, dt, 10.0));
        let apex = throw.com_at(5.0 / 9.81);
        assert!(b.contains_point(apex));
        // Without the apex, the box of the endpoints alone misses the top of the throw.
        let endpoints_only =
            Aabb::new(throw.com_at(0.0), throw.com_at(dt)).expanded(ENDPOINT_BOX_MARGIN);
        assert!(!endpoints_only.contains_point(apex));
        // Apex outside the interval: endpoints suffice; negative dt covers [t0 + dt, t0].
        check_swept_box(&throw, 0.3, sampling_slack(9.81, 0.3, 10.0));
        check_swept_box(&throw, -0.7, sampling_slack(9.81, 0.7, 10.0));
        let mut rng = rng(3);
        for _ in 0..300 {
            let m = Motion::from(
                Ballistic::new(
                    unit_vector(&mut rng) * rng.random_range(0.0..100.0),
                    unit_vector(&mut rng) * rng.random_range(0.0..20.0),
                    unit_vector(&mut rng) * rng.random_range(0.0..20.0),
                    0.0,
                )
                .unwrap(),
            );
            let dt = rng.random_range(0.0..4.0);
            check_swept_box(&m, dt, sampling_slack(20.0, dt, 500.0));
        }
        assert_eq!(throw.swept_com_aabb(f64::NAN), ALL_SPACE);
        assert_eq!(throw.swept_com_aabb(f64::INFINITY), ALL_SPACE);
    }

    /// Axis extrema (multiples of π/2) strictly inside the phase interval.
    fn extrema_crossed(phase: f64, sweep: f64) -> usize {
        let (lo, hi) = (phase.min(phase + sweep), phase.max(phase + sweep));
        (-20..20)
            .filter(|&n| {
                let t = f64::from(n) * 0.5 * PI;
                lo < t && t < hi
            })
            .count()
    }

    #[test]
    fn cycler_swept_box_covers_arcs_across_axis_extrema() {
        let centre = DVec3::new(1.0, -2.0, 3.0);
        let (r, rate) = (2.0, 1.5);
        // (phase, sweep Ω·dt, number of axis extrema crossed)
        let arcs = [
            (0.2, 1.0, 0),
            (0.2, 1.5, 1),
            (1.4, 2.0, 2),
            (0.1, 4.8, 3),
            (0.3, 6.0, 4),
            (5.9, 1.0, 1), // crosses θ = 2π
        ];
        for (phase, sweep, crossed) in arcs {
            assert_eq!(extrema_crossed(phase, sweep), crossed);
            // The same arc traversed both ways.
            for (start, signed_rate) in [(phase, rate), (phase + sweep, -rate)] {
                let c = Cycler::new(centre, DVec3::X, DVec3::Y, r, signed_rate, start).unwrap();
                let dt = sweep / rate;
                check_swept_box(&c.into(), dt, sampling_slack(r * rate * rate, dt, 10.0));
            }
        }
        // A full turn or more: the whole circle's box.
        let c = Cycler::new(centre, DVec3::X, DVec3::Y, r, rate, 0.7).unwrap();
        for dt in [TAU / rate, 10.0, f64::INFINITY] {
            let b = c.swept_com_aabb(dt);
            let full = Aabb::new(
                centre - DVec3::new(r, r, 0.0),
                centre + DVec3::new(r, r, 0.0),
            );
            assert!((b.min - full.min).abs().max_element() <= FULL_PATH_TOL);
            assert!((b.max - full.max).abs().max_element() <= FULL_PATH_TOL);
        }
        // Tilted planes, random phases and sweeps.
        let mut rng = rng(9);
        for _ in 0..300 {
            let e1 = unit_vector(&mut rng);
            let e2 = e1.any_orthonormal_vector();
            let q = DQuat::from_axis_angle(e1, rng.random_range(0.0..TAU));
            let c = Cycler::new(
                unit_vector(&mut rng) * 5.0,
                e1,
                q * e2,
                rng.random_range(0.0..3.0),
                rng.random_range(-4.0..4.0),
                rng.random_range(-10.0..10.0),
            )
            .unwrap();
            let dt = rng.random_range(0.0..3.0);
            let acc = c.radius() * c.rate() * c.rate();
            check_swept_box(&c.into(), dt, sampling_slack(acc, dt, 10.0));
        }
        assert_eq!(Motion::from(c).swept_com_aabb(f64::NAN), ALL_SPACE);
    }

    #[test]
    fn oscillator_swept_box_covers_turning_points() {
        let centre = DVec3::new(0.5, 1.0, -1.0);
        let axis = DVec3::new(1.0, 2.0, 2.0);
        let (a, w) = (0.3, 2.0);
        // (phase, sweep ω·dt, turning points at π/2 + nπ crossed)
        for (phase, sweep, turns) in [(0.0, 1.0, 0), (1.0, 1.0, 1), (1.0, 4.0, 2), (0.0, 6.0, 2)] {
            let count = (-8..8)
                .filter(|&n| {
                    let t = 0.5 * PI + f64::from(n) * PI;
                    phase < t && t < phase + sweep
                })
                .count();
            assert_eq!(count, turns);
            for (start, signed_w) in [(phase, w), (phase + sweep, -w)] {
                let o = Oscillator::new(centre, axis, a, signed_w, start).unwrap();
                check_swept_box(
                    &o.into(),
                    sweep / w,
                    sampling_slack(a * w * w, sweep / w, 3.0),
                );
            }
        }
        let o = Oscillator::new(centre, axis, a, w, 0.4).unwrap();
        let reach = axis.normalize() * a;
        for dt in [TAU / w, 100.0, f64::INFINITY] {
            let b = o.swept_com_aabb(dt);
            let full = Aabb::new(centre - reach, centre + reach);
            assert!((b.min - full.min).abs().max_element() <= FULL_PATH_TOL);
            assert!((b.max - full.max).abs().max_element() <= FULL_PATH_TOL);
        }
        let mut rng = rng(10);
        for _ in 0..300 {
            let o = Oscillator::new(
                unit_vector(&mut rng) * 3.0,
                unit_vector(&mut rng),
                rng.random_range(0.0..1.0),
                rng.random_range(-20.0..20.0),
                rng.random_range(-10.0..10.0),
            )
            .unwrap();
            let dt = rng.random_range(0.0..1.0);
            let acc = o.amplitude() * o.omega() * o.omega();
            check_swept_box(&o.into(), dt, sampling_slack(acc, dt, 5.0));
        }
        assert_eq!(o.swept_com_aabb(f64::NAN), ALL_SPACE);
    }

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

    /// Rodrigues' rotation of `r` about unit `k` by `theta` (independent of `so3_exp`).
    fn rodrigues(k: DVec3, theta: f64, r: DVec3) -> DVec3 {
        let (s, c) = theta.sin_cos();
        r * c + k.cross(r) * s + k * (k.dot(r) * (1.0 - c))
    }

    #[test]
    fn spinner_bound_holds_for_points_within_r_max() {
        let mut rng = rng(31);
        let mut worst: f64 = 0.0;
        for _ in 0..200 {
            let axis = unit_vector(&mut rng);
            let rate = rng.random_range(-50.0..50.0);
            let com = unit_vector(&mut rng) * 2.0;
            let s = Spinner::new(com, axis * 3.0, rate).unwrap();
            let r_max = rng.random_range(0.1..2.0);
            let points: Vec<DVec3> = (0..16)
                .map(|i| {
                    unit_vector(&mut rng)
                        * if i < 8 {
                            r_max
                        } else {
                            rng.random_range(0.0..r_max)
                        }
                })
                .collect();
            let d = unit_vector(&mut rng);
            let (a, b) = Motion::from(s).toi_coefficients(d, r_max, 1.0);
            assert_eq!(a, 0.0);
            let span = 2.0 * TAU / rate.abs();
            for k in 1..=1000 {
                let tau = span * f64::from(k) / 1000.0;
                for &r in &points {
                    let disp = (rodrigues(axis, rate * tau, r) - r).dot(d);
                    assert!(disp <= b * tau + BOUND_SLACK_REL * r_max);
                    if b * tau > RATIO_FLOOR_REL * r_max {
                        worst = worst.max(disp / (b * tau));
                    }
                    // The rotation the type reports agrees with Rodrigues.
                    if k % 100 == 0 {
                        let q = s.rotation_over(tau);
                        assert!(
                            (q * r - rodrigues(axis, rate * tau, r)).length()
                                <= CLOSED_FORM_TOL * r_max
                        );
                    }
                }
            }
            assert_eq!(Motion::from(s).swept_com_aabb(5.0), Aabb::new(com, com));
        }
        // Spinning about the direction of approach moves no point along it.
        let s = Spinner::new(DVec3::ZERO, DVec3::Z, 100.0).unwrap();
        assert_eq!(s.toi_coefficients(DVec3::Z, 1.0), (0.0, 0.0));
        eprintln!("spinner: max displacement / bound {worst:.4}");
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
}
