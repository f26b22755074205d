//! Lie-algebra kernel of SE(3): twists, wrenches, 6×6 matrices and the SO(3) exponential map.
//!
//! # Conventions
//!
//! * All quantities are `f64` (glam `DVec3`, `DQuat`, `DMat3`, `DMat4`) in any consistent units;
//!   the docs quote SI (m, kg, s, rad).
//! * Twists and wrenches pack the **linear part on top and the angular part below**, as in
//!   Murray, Li & Sastry, *A Mathematical Introduction to Robotic Manipulation* (MLS):
//!   a twist is ξ = (v, ω), a wrench is F = (f, τ). Featherstone's spatial algebra puts the
//!   angular part first; his 6×6 matrices appear here with the 3×3 blocks swapped
//!   (his `[[A, B], [C, D]]` is our `[[D, C], [B, A]]`).
//! * A twist or wrench is always *expressed in* some frame F: ω is the angular velocity in F's
//!   axes and v is the velocity of the body-fixed point that momentarily sits at F's origin
//!   (m/s, or metres for a displacement twist); f is the force and τ the moment about F's origin
//!   (N, N·m). [`crate::pose::Pose`] moves them between frames.
//! * The pairing of a wrench with a twist, `f·v + τ·ω`, is power (W) and does not depend on the
//!   frame.

use core::ops::{Add, AddAssign, Mul, Neg, Sub, SubAssign};

use glam::{DMat3, DMat4, DQuat, DVec3};

/// Rotation angle (rad) below which [`so3_exp`] and [`so3_log`] switch from the closed-form
/// factors `sin(θ/2)/θ` and `2·atan2(|xyz|, w)/|xyz|` to their Taylor series.
///
/// Both closed forms are accurate to a few ulp for any angle > 0; the switch exists only to
/// avoid `0/0` at θ = 0. The series are kept to the θ⁶ term, so at the switch the first
/// neglected term is below 1e-19 relative, far under machine epsilon (2.2e-16).
pub const SO3_SERIES_ANGLE: f64 = 1e-2;

/// Pivot threshold of [`Mat6::try_inverse`] (dimensionless), applied to the equilibrated
/// matrix.
///
/// `try_inverse` first scales every row and then every column by a power of two so that its
/// largest absolute entry is about 1 (exact scaling, so it adds no rounding); the test is
/// therefore invariant under changes of units (kg vs g, m vs mm), which rescale rows and
/// columns of physical 6×6 matrices. Elimination reports a singular matrix when the largest
/// available pivot of the equilibrated matrix is at most this value. Exactly singular 6×6
/// matrices leave round-off pivots of order `6·ε ≈ 1.3e-15` (times a small growth factor), so
/// 1e-12 sits about three decades above round-off while accepting every matrix whose
/// equilibrated condition number is below roughly 1e12.
pub const MAT6_PIVOT_TOLERANCE: f64 = 1e-12;

/// Skew-symmetric (“hat”) matrix of `w`: `hat(a) * b == a.cross(b)` for every `b`.
///
/// `hat(w) = [[0, −w_z, w_y], [w_z, 0, −w_x], [−w_y, w_x, 0]]` (MLS §2.2). Units are those of
/// `w`; `hat(w)ᵀ = −hat(w)`.
#[must_use]
pub fn hat(w: DVec3) -> DMat3 {
    DMat3::from_cols(
        DVec3::new(0.0, w.z, -w.y),
        DVec3::new(-w.z, 0.0, w.x),
        DVec3::new(w.y, -w.x, 0.0),
    )
}

/// A twist ξ = (v, ω) expressed in some frame F: a spatial velocity (or, read as a
/// displacement, an element of the Lie algebra se(3)).
///
/// `w` is the angular velocity (rad/s) in F's axes; `v` is the linear velocity (m/s) of the
/// body-fixed point momentarily at F's origin. Packing is linear on top, angular below (MLS).
#[derive(Copy, Clone, Debug, PartialEq, Default)]
pub struct Twist {
    /// Linear part: velocity of the point at the frame origin (m/s or m).
    pub v: DVec3,
    /// Angular part: angular velocity (rad/s) or rotation vector (rad).
    pub w: DVec3,
}

impl Twist {
    /// The zero twist.
    pub const ZERO: Twist = Twist {
        v: DVec3::ZERO,
        w: DVec3::ZERO,
    };

    /// Twist from its linear part `v` and angular part `w`.
    #[must_use]
    pub const fn new(v: DVec3, w: DVec3) -> Self {
        Twist { v, w }
    }

    /// Twist from `[v_x, v_y, v_z, ω_x, ω_y, ω_z]` (linear on top).
    #[must_use]
    pub const fn from_array(a: [f64; 6]) -> Self {
        Twist {
            v: DVec3::new(a[0], a[1], a[2]),
            w: DVec3::new(a[3], a[4], a[5]),
        }
    }

    /// The components as `[v_x, v_y, v_z, ω_x, ω_y, ω_z]` (linear on top).
    #[must_use]
    pub const fn to_array(&self) -> [f64; 6] {
        [self.v.x, self.v.y, self.v.z, self.w.x, self.w.y, self.w.z]
    }

    /// `true` when all six components are finite.
    #[must_use]
    pub fn is_finite(&self) -> bool {
        self.v.is_finite() && self.w.is_finite()
    }

    /// Spatial motion cross product `ξ × η = ad_ξ η`, both twists in the same frame.
    ///
    /// In linear-top form `ad_ξ = [[ŵ, v̂], [0, ŵ]]` (MLS §2.4, Lie bracket of se(3)), so the
    /// result is `(ω × η_v + v × η_ω, ω × η_ω)`; it equals the 4×4 matrix commutator
    /// `ξ̂η̂ − η̂ξ̂`. Featherstone's `crm(ξ)·η` with the blocks swapped.
    #[must_use]
    pub fn cross_motion(&self, other: &Twist) -> Twist {
        // ad_ξ η = [[ŵ, v̂], [0, ŵ]]·(η_v, η_ω): the se(3) bracket [ξ̂, η̂] (MLS §2.4).
        Twist {
            v: self.w.cross(other.v) + self.v.cross(other.w),
            w: self.w.cross(other.w),
        }
    }

    /// Spatial force cross product `ξ ×* F = −ad_ξᵀ F`, twist and wrench in the same frame.
    ///
    /// Result `(ω × f, ω × τ + v × f)`. It is the dual of [`Twist::cross_motion`]:
    /// `(ξ ×* F)·η = −F·(ξ × η)`. Featherstone's `crf(ξ)·F` with the blocks swapped; it gives the
    /// rate of change of a momentum carried along with a body moving at ξ.
    #[must_use]
    pub fn cross_force(&self, f: &Wrench) -> Wrench {
        // −ad_ξᵀ = [[ŵ, 0], [v̂, ŵ]] (since ŵᵀ = −ŵ, v̂ᵀ = −v̂).
        Wrench {
            f: self.w.cross(f.f),
            tau: self.w.cross(f.tau) + self.v.cross(f.f),
        }
    }

    /// The 4×4 twist matrix `ξ̂ = [[ŵ, v], [0, 0]]` (MLS §2.3.1); `exp(ξ̂)` is the homogeneous
    /// matrix of [`crate::pose::Pose::exp`].
    #[must_use]
    pub fn hat4(&self) -> DMat4 {
        let w = hat(self.w);
        DMat4::from_cols(
            w.x_axis.extend(0.0),
            w.y_axis.extend(0.0),
            w.z_axis.extend(0.0),
            self.v.extend(0.0),
        )
    }
}

impl Add for Twist {
    type Output = Twist;
    fn add(self, rhs: Twist) -> Twist {
        Twist {
            v: self.v + rhs.v,
            w: self.w + rhs.w,
        }
    }
}

impl Sub for Twist {
    type Output = Twist;
    fn sub(self, rhs: Twist) -> Twist {
        Twist {
            v: self.v - rhs.v,
            w: self.w - rhs.w,
        }
    }
}

impl Neg for Twist {
    type Output = Twist;
    fn neg(self) -> Twist {
        Twist {
            v: -self.v,
            w: -self.w,
        }
    }
}

impl Mul<f64> for Twist {
    type Output = Twist;
    fn mul(self, s: f64) -> Twist {
        Twist {
            v: self.v * s,
            w: self.w * s,
        }
    }
}

impl AddAssign for Twist {
    fn add_assign(&mut self, rhs: Twist) {
        self.v += rhs.v;
        self.w += rhs.w;
    }
}

impl SubAssign for Twist {
    fn sub_assign(&mut self, rhs: Twist) {
        self.v -= rhs.v;
        self.w -= rhs.w;
    }
}

/// A wrench F = (f, τ) expressed in some frame F: force `f` (N) in F's axes acting along a line
/// through F's origin, plus the moment `tau` (N·m) about F's origin. Also used for momenta
/// (kg·m/s, kg·m²/s) and impulses. Packing is force on top, torque below (MLS).
#[derive(Copy, Clone, Debug, PartialEq, Default)]
pub struct Wrench {
    /// Linear part: force (N), linear momentum or linear impulse.
    pub f: DVec3,
    /// Angular part: moment about the frame origin (N·m), angular momentum or impulse.
    pub tau: DVec3,
}

impl Wrench {
    /// The zero wrench.
    pub const ZERO: Wrench = Wrench {
        f: DVec3::ZERO,
        tau: DVec3::ZERO,
    };

    /// Wrench from force `f` and moment `tau` about the frame origin.
    #[must_use]
    pub const fn new(f: DVec3, tau: DVec3) -> Self {
        Wrench { f, tau }
    }

    /// Wrench from `[f_x, f_y, f_z, τ_x, τ_y, τ_z]` (force on top).
    #[must_use]
    pub const fn from_array(a: [f64; 6]) -> Self {
        Wrench {
            f: DVec3::new(a[0], a[1], a[2]),
            tau: DVec3::new(a[3], a[4], a[5]),
        }
    }

    /// The components as `[f_x, f_y, f_z, τ_x, τ_y, τ_z]` (force on top).
    #[must_use]
    pub const fn to_array(&self) -> [f64; 6] {
        [
            self.f.x, self.f.y, self.f.z, self.tau.x, self.tau.y, self.tau.z,
        ]
    }

    /// `true` when all six components are finite.
    #[must_use]
    pub fn is_finite(&self) -> bool {
        self.f.is_finite() && self.tau.is_finite()
    }

    /// Power `f·v + τ·ω` (W) delivered by this wrench on `twist`; both must be expressed in the
    /// same frame. The value is frame-invariant (MLS §2.5).
    #[must_use]
    pub fn power(&self, twist: &Twist) -> f64 {
        self.f.dot(twist.v) + self.tau.dot(twist.w)
    }
}

impl Add for Wrench {
    type Output = Wrench;
    fn add(self, rhs: Wrench) -> Wrench {
        Wrench {
            f: self.f + rhs.f,
            tau: self.tau + rhs.tau,
        }
    }
}

impl Sub for Wrench {
    type Output = Wrench;
    fn sub(self, rhs: Wrench) -> Wrench {
        Wrench {
            f: self.f - rhs.f,
            tau: self.tau - rhs.tau,
        }
    }
}

impl Neg for Wrench {
    type Output = Wrench;
    fn neg(self) -> Wrench {
        Wrench {
            f: -self.f,
            tau: -self.tau,
        }
    }
}

impl Mul<f64> for Wrench {
    type Output = Wrench;
    fn mul(self, s: f64) -> Wrench {
        Wrench {
            f: self.f * s,
            tau: self.tau * s,
        }
    }
}

impl AddAssign for Wrench {
    fn add_assign(&mut self, rhs: Wrench) {
        self.f += rhs.f;
        self.tau += rhs.tau;
    }
}

impl SubAssign for Wrench {
    fn sub_assign(&mut self, rhs: Wrench) {
        self.f -= rhs.f;
        self.tau -= rhs.tau;
    }
}

/// A dense 6×6 matrix stored as four 3×3 blocks `[[tl, tr], [bl, br]]`.
///
/// Rows 0–2 / columns 0–2 are the linear (top) components and rows 3–5 / columns 3–5 the angular
/// (bottom) ones, matching the packing of [`Twist`] and [`Wrench`]. What the matrix maps is up
/// to the caller and chosen by the product used: [`Mat6::mul_twist`] (twist → twist, e.g. the
/// adjoint), [`Mat6::mul_wrench`] (wrench → wrench, e.g. Ad⁻ᵀ), [`Mat6::inertia_mul`]
/// (twist → wrench, e.g. a spatial or articulated inertia) and [`Mat6::compliance_mul`]
/// (wrench → twist). The blocks are glam column-major `DMat3`s; element (r, c) of the whole
/// matrix is `to_rows()[r][c]`.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Mat6 {
    /// Top-left block: rows 0–2, columns 0–2.
    pub tl: DMat3,
    /// Top-right block: rows 0–2, columns 3–5.
    pub tr: DMat3,
    /// Bottom-left block: rows 3–5, columns 0–2.
    pub bl: DMat3,
    /// Bottom-right block: rows 3–5, columns 3–5.
    pub br: DMat3,
}

/// `m · [top; bottom]` for the 6-vector given as two halves.
fn mul_halves(m: &Mat6, top: DVec3, bottom: DVec3) -> (DVec3, DVec3) {
    (m.tl * top + m.tr * bottom, m.bl * top + m.br * bottom)
}

/// 3×3 block of a row-major 6×6 array starting at (`r0`, `c0`).
fn block_from_rows(rows: &[[f64; 6]; 6], r0: usize, c0: usize) -> DMat3 {
    let col = |c: usize| DVec3::new(rows[r0][c0 + c], rows[r0 + 1][c0 + c], rows[r0 + 2][c0 + c]);
    DMat3::from_cols(col(0), col(1), col(2))
}

impl Mat6 {
    /// The zero matrix.
    pub const ZERO: Mat6 = Mat6 {
        tl: DMat3::ZERO,
        tr: DMat3::ZERO,
        bl: DMat3::ZERO,
        br: DMat3::ZERO,
    };

    /// The identity matrix.
    pub const IDENTITY: Mat6 = Mat6 {
        tl: DMat3::IDENTITY,
        tr: DMat3::ZERO,
        bl: DMat3::ZERO,
        br: DMat3::IDENTITY,
    };

    /// Matrix `[[tl, tr], [bl, br]]` from its four 3×3 blocks.
    #[must_use]
    pub const fn from_blocks(tl: DMat3, tr: DMat3, bl: DMat3, br: DMat3) -> Self {
        Mat6 { tl, tr, bl, br }
    }

    /// Matrix from a row-major array: `rows[r][c]` is element (r, c).
    #[must_use]
    pub fn from_rows(rows: [[f64; 6]; 6]) -> Self {
        Mat6 {
            tl: block_from_rows(&rows, 0, 0),
            tr: block_from_rows(&rows, 0, 3),
            bl: block_from_rows(&rows, 3, 0),
            br: block_from_rows(&rows, 3, 3),
        }
    }

    /// Row-major copy: `to_rows()[r][c]` is element (r, c).
    #[must_use]
    pub fn to_rows(&self) -> [[f64; 6]; 6] {
        let mut out = [[0.0; 6]; 6];
        for (r, row) in out.iter_mut().enumerate() {
            let (left, right) = if r < 3 {
                (&self.tl, &self.tr)
            } else {
                (&self.bl, &self.br)
            };
            let lr = left.row(r % 3);
            let rr = right.row(r % 3);
            *row = [lr.x, lr.y, lr.z, rr.x, rr.y, rr.z];
        }
        out
    }

    /// Outer product `a bᵀ` of two 6-vectors (e.g. the rank-one update `U Uᵀ / D` of the
    /// articulated-body algorithm).
    #[must_use]
    pub fn outer(a: &[f64; 6], b: &[f64; 6]) -> Self {
        let mut rows = [[0.0; 6]; 6];
        for (row, ai) in rows.iter_mut().zip(a) {
            for (x, bj) in row.iter_mut().zip(b) {
                *x = ai * bj;
            }
        }
        Mat6::from_rows(rows)
    }

    /// Transpose `[[tlᵀ, blᵀ], [trᵀ, brᵀ]]`.
    #[must_use]
    pub fn transpose(&self) -> Self {
        Mat6 {
            tl: self.tl.transpose(),
            tr: self.bl.transpose(),
            bl: self.tr.transpose(),
            br: self.br.transpose(),
        }
    }

    /// Product with a 6-vector given as a linear-top array.
    #[must_use]
    pub fn mul_array(&self, x: &[f64; 6]) -> [f64; 6] {
        let (t, b) = mul_halves(
            self,
            DVec3::new(x[0], x[1], x[2]),
            DVec3::new(x[3], x[4], x[5]),
        );
        [t.x, t.y, t.z, b.x, b.y, b.z]
    }

    /// Twist → twist product, for motion maps such as the adjoint `Ad`.
    #[must_use]
    pub fn mul_twist(&self, t: &Twist) -> Twist {
        let (v, w) = mul_halves(self, t.v, t.w);
        Twist { v, w }
    }

    /// Wrench → wrench product, for force maps such as `Ad⁻ᵀ`.
    #[must_use]
    pub fn mul_wrench(&self, f: &Wrench) -> Wrench {
        let (f, tau) = mul_halves(self, f.f, f.tau);
        Wrench { f, tau }
    }

    /// Twist → wrench product, for inertias (momentum `h = M ξ`).
    #[must_use]
    pub fn inertia_mul(&self, t: &Twist) -> Wrench {
        let (f, tau) = mul_halves(self, t.v, t.w);
        Wrench { f, tau }
    }

    /// Wrench → twist product, for compliances / inverse inertias (`ξ = M⁻¹ h`).
    #[must_use]
    pub fn compliance_mul(&self, f: &Wrench) -> Twist {
        let (v, w) = mul_halves(self, f.f, f.tau);
        Twist { v, w }
    }

    /// `true` when all 36 entries are finite.
    #[must_use]
    pub fn is_finite(&self) -> bool {
        self.tl.is_finite() && self.tr.is_finite() && self.bl.is_finite() && self.br.is_finite()
    }

    /// Largest absolute entry difference `max |selfᵢⱼ − otherᵢⱼ|`.
    #[must_use]
    pub fn max_abs_diff(&self, other: &Mat6) -> f64 {
        let a = self.to_rows();
        let b = other.to_rows();
        a.iter()
            .flatten()
            .zip(b.iter().flatten())
            .fold(0.0, |m, (x, y)| f64::max(m, (x - y).abs()))
    }

    /// General inverse by Gaussian elimination with partial (row) pivoting followed by back
    /// substitution, on the row- and column-equilibrated matrix (see [`MAT6_PIVOT_TOLERANCE`]).
    ///
    /// Returns `None` when the matrix has a non-finite entry, a zero row or column, or a pivot
    /// of the equilibrated matrix at most [`MAT6_PIVOT_TOLERANCE`] (numerically singular). For
    /// symmetric positive definite inertias this is a general fallback, not the fastest path.
    #[must_use]
    pub fn try_inverse(&self) -> Option<Mat6> {
        if !self.is_finite() {
            return None;
        }
        let mut a = self.to_rows();
        // Equilibrate: B = diag(rs)·A·diag(cs) with power-of-two factors.
        let mut rs = [1.0; 6];
        for (row, r) in a.iter_mut().zip(rs.iter_mut()) {
            *r = pow2_recip(row.iter().fold(0.0, |m: f64, v| m.max(v.abs())))?;
            for x in row.iter_mut() {
                *x *= *r;
            }
        }
        let mut cs = [1.0; 6];
        for (j, c) in cs.iter_mut().enumerate() {
            *c = pow2_recip(a.iter().fold(0.0, |m: f64, row| m.max(row[j].abs())))?;
            for row in a.iter_mut() {
                row[j] *= *c;
            }
        }
        let tol = MAT6_PIVOT_TOLERANCE;
        let mut x = Mat6::IDENTITY.to_rows();

        // Forward elimination: a becomes upper triangular, x collects the row operations.
        for k in 0..6 {
            let mut piv = k;
            for r in (k + 1)..6 {
                if a[r][k].abs() > a[piv][k].abs() {
                    piv = r;
                }
            }
            if a[piv][k].abs() <= tol {
                return None;
            }
            a.swap(k, piv);
            x.swap(k, piv);
            let (upper, lower) = a.split_at_mut(k + 1);
            let (xupper, xlower) = x.split_at_mut(k + 1);
            let prow = &upper[k];
            let xprow = &xupper[k];
            for (row, xrow) in lower.iter_mut().zip(xlower.iter_mut()) {
                let f = row[k] / prow[k];
                if f != 0.0 {
                    for c in k..6 {
                        row[c] -= f * prow[c];
                    }
                    for c in 0..6 {
                        xrow[c] -= f * xprow[c];
                    }
                }
                row[k] = 0.0;
            }
        }

        // Back substitution for B⁻¹, all six right-hand sides at once.
        let mut binv = [[0.0; 6]; 6];
        for k in (0..6).rev() {
            let mut rhs = x[k];
            for j in (k + 1)..6 {
                let akj = a[k][j];
                for c in 0..6 {
                    rhs[c] -= akj * binv[j][c];
                }
            }
            for c in 0..6 {
                binv[k][c] = rhs[c] / a[k][k];
            }
        }
        // Undo the equilibration: A⁻¹ = diag(cs)·B⁻¹·diag(rs) (exact, powers of two).
        for (row, ci) in binv.iter_mut().zip(cs) {
            for (x, rj) in row.iter_mut().zip(rs) {
                *x *= ci * rj;
            }
        }
        Some(Mat6::from_rows(binv))
    }
}

/// The power of two nearest to `1/m` (an exact scale factor), or `None` when `m` is zero.
fn pow2_recip(m: f64) -> Option<f64> {
    if m > 0.0 {
        Some(2f64.powi(-(m.log2().round() as i32)))
    } else {
        None
    }
}

impl Mul<Mat6> for Mat6 {
    type Output = Mat6;
    fn mul(self, o: Mat6) -> Mat6 {
        Mat6 {
            tl: self.tl * o.tl + self.tr * o.bl,
            tr: self.tl * o.tr + self.tr * o.br,
            bl: self.bl * o.tl + self.br * o.bl,
            br: self.bl * o.tr + self.br * o.br,
        }
    }
}

impl Add for Mat6 {
    type Output = Mat6;
    fn add(self, o: Mat6) -> Mat6 {
        Mat6 {
            tl: self.tl + o.tl,
            tr: self.tr + o.tr,
            bl: self.bl + o.bl,
            br: self.br + o.br,
        }
    }
}

impl Sub for Mat6 {
    type Output = Mat6;
    fn sub(self, o: Mat6) -> Mat6 {
        Mat6 {
            tl: self.tl - o.tl,
            tr: self.tr - o.tr,
            bl: self.bl - o.bl,
            br: self.br - o.br,
        }
    }
}

impl Mul<f64> for Mat6 {
    type Output = Mat6;
    fn mul(self, s: f64) -> Mat6 {
        Mat6 {
            tl: self.tl * s,
            tr: self.tr * s,
            bl: self.bl * s,
            br: self.br * s,
        }
    }
}

/// Exponential map of SO(3): the unit quaternion of the rotation by angle θ = |rotvec| (rad)
/// about `rotvec / θ` (right-handed).
///
/// `q = (sin(θ/2)·rotvec/θ, cos(θ/2))`, the quaternion form of Rodrigues' formula (MLS §2.2).
/// The factor `sin(θ/2)/θ` and `cos(θ/2)` use their Taylor series below [`SO3_SERIES_ANGLE`], so
/// θ = 0 gives the identity exactly and tiny angles are exact to rounding. The result has
/// `w ≥ 0` for θ ≤ π.
#[must_use]
pub fn so3_exp(rotvec: DVec3) -> DQuat {
    let theta_sq = rotvec.length_squared();
    let theta = theta_sq.sqrt();
    let (k, c) = if theta < SO3_SERIES_ANGLE {
        // sin(θ/2)/θ = 1/2 − θ²/48 + θ⁴/3840 − θ⁶/645120 + …, and
        // cos(θ/2) = 1 − θ²/8 + θ⁴/384 − θ⁶/46080 + θ⁸/10321920 − …: no trigonometric call on
        // the small-angle path (the first neglected terms are below 1e-22 at the switch).
        (
            0.5 + theta_sq * (-1.0 / 48.0 + theta_sq * (1.0 / 3840.0 - theta_sq / 645_120.0)),
            1.0 + theta_sq
                * (-1.0 / 8.0
                    + theta_sq
                        * (1.0 / 384.0 + theta_sq * (-1.0 / 46_080.0 + theta_sq / 10_321_920.0))),
        )
    } else {
        let (s, c) = (0.5 * theta).sin_cos();
        (s / theta, c)
    };
    let xyz = rotvec * k;
    DQuat::from_xyzw(xyz.x, xyz.y, xyz.z, c)
}

/// Logarithm of SO(3): the rotation vector (axis · angle, rad) of the unit quaternion `q`, with
/// angle in [0, π].
///
/// `q` and `−q` give the same result (q is first flipped to `w ≥ 0`). The angle is
/// `θ = 2·atan2(|xyz|, w)`, well conditioned both near 0 and near π (unlike `acos(w)` or the
/// matrix trace). At exactly θ = π the axis sign is that of `q`'s vector part (both signs are
/// the same rotation). The factor `θ/|xyz|` uses the Taylor series of `atan(x)/x` when the
/// angle is below [`SO3_SERIES_ANGLE`]. `q` must be normalised; a zero quaternion yields a
/// non-finite result.
#[must_use]
pub fn so3_log(q: DQuat) -> DVec3 {
    let q = if q.w < 0.0 { -q } else { q };
    let xyz = DVec3::new(q.x, q.y, q.z);
    let n = xyz.length();
    // tan(θ/2) = n / w; compare θ/2 ≈ n/w with half the switch angle (scale-invariant in q).
    let factor = if n < 0.5 * SO3_SERIES_ANGLE * q.w {
        // θ/n = (2/w)·atan(x)/x, x = n/w; atan(x)/x = 1 − x²/3 + x⁴/5 − x⁶/7 + …
        let x2 = (n / q.w) * (n / q.w);
        (2.0 / q.w) * (1.0 + x2 * (-1.0 / 3.0 + x2 * (1.0 / 5.0 - x2 / 7.0)))
    } else {
        2.0 * n.atan2(q.w) / n
    };
    xyz * factor
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec4;
    use rand::rngs::Xoshiro256PlusPlus;
    use rand::{RngExt, SeedableRng};

    /// Number of random samples per test.
    const N: usize = 10_000;
    /// Bound on errors that should be a few ulp of O(1) quantities.
    const TIGHT_TOL: f64 = 1e-13;
    /// Bound for `so3_exp`/`so3_log` round trips and comparisons with glam.
    const SO3_TOL: f64 = 1e-14;
    /// Bound on `‖M·M⁻¹ − I‖_max / (‖M‖_max·‖M⁻¹‖_max)`: backward-stable elimination gives a
    /// small multiple of 6·ε here.
    const INVERSE_TOL: f64 = 1e-14;

    fn vec3(rng: &mut Xoshiro256PlusPlus, s: f64) -> DVec3 {
        DVec3::new(
            rng.random_range(-s..s),
            rng.random_range(-s..s),
            rng.random_range(-s..s),
        )
    }

    fn twist(rng: &mut Xoshiro256PlusPlus) -> Twist {
        Twist::new(vec3(rng, 3.0), vec3(rng, 3.0))
    }

    fn mat6(rng: &mut Xoshiro256PlusPlus) -> Mat6 {
        let mut rows = [[0.0; 6]; 6];
        for x in rows.iter_mut().flatten() {
            *x = rng.random_range(-1.0..1.0);
        }
        Mat6::from_rows(rows)
    }

    /// Brute-force row-major product.
    fn mul_rows(a: &[[f64; 6]; 6], b: &[[f64; 6]; 6]) -> [[f64; 6]; 6] {
        let mut c = [[0.0; 6]; 6];
        for i in 0..6 {
            for j in 0..6 {
                c[i][j] = (0..6).map(|k| a[i][k] * b[k][j]).sum();
            }
        }
        c
    }

    fn max_abs(m: &Mat6) -> f64 {
        m.max_abs_diff(&Mat6::ZERO)
    }

    fn arr_diff(a: &[f64; 6], b: &[f64; 6]) -> f64 {
        a.iter()
            .zip(b)
            .fold(0.0, |m, (x, y)| f64::max(m, (x - y).abs()))
    }

    fn mat4_diff(a: &DMat4, b: &DMat4) -> f64 {
        a.to_cols_array()
            .iter()
            .zip(b.to_cols_array().iter())
            .fold(0.0, |m, (x, y)| f64::max(m, (x - y).abs()))
    }

    #[test]
    fn hat_is_cross_product() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(1);
        let mut err: f64 = 0.0;
        for _ in 0..N {
            let a = vec3(&mut rng, 5.0);
            let b = vec3(&mut rng, 5.0);
            err = err.max((hat(a) * b - a.cross(b)).abs().max_element());
            assert_eq!(hat(a).transpose() + hat(a), DMat3::ZERO);
        }
        println!("hat: max |hat(a)b − a×b| = {err:e}");
        assert!(err <= TIGHT_TOL * 25.0);
    }

    #[test]
    fn cross_motion_is_lie_bracket_and_cross_force_is_dual() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(2);
        let (mut e_bracket, mut e_dual): (f64, f64) = (0.0, 0.0);
        for _ in 0..N {
            let xi = twist(&mut rng);
            let eta = twist(&mut rng);
            let (a, b) = (xi.hat4(), eta.hat4());
            let reference = a * b - b * a;
            e_bracket = e_bracket.max(mat4_diff(&xi.cross_motion(&eta).hat4(), &reference));
            let f = Wrench::new(vec3(&mut rng, 3.0), vec3(&mut rng, 3.0));
            let lhs = xi.cross_force(&f).power(&eta);
            let rhs = -f.power(&xi.cross_motion(&eta));
            e_dual = e_dual.max((lhs - rhs).abs() / (1.0 + lhs.abs()));
        }
        println!("cross_motion vs 4x4 bracket: {e_bracket:e}; cross_force duality: {e_dual:e}");
        assert!(e_bracket <= TIGHT_TOL * 10.0);
        assert!(e_dual <= TIGHT_TOL * 10.0);
    }

    #[test]
    fn twist_wrench_arrays_and_ops() {
        let t = Twist::from_array([1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        assert_eq!(t.v, DVec3::new(1.0, 2.0, 3.0));
        assert_eq!(t.w, DVec3::new(4.0, 5.0, 6.0));
        assert_eq!(t.to_array(), [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        assert_eq!((t + t - t * 2.0), Twist::ZERO);
        let mut u = -t;
        u += t;
        assert_eq!(u, Twist::ZERO);
        assert_eq!(Twist::default(), Twist::ZERO);
        let f = Wrench::from_array([1.0, 0.0, 0.0, 0.0, 0.0, 2.0]);
        assert_eq!(f.to_array(), [1.0, 0.0, 0.0, 0.0, 0.0, 2.0]);
        assert_eq!(f.power(&t), 1.0 + 12.0);
        let mut g = f - f * 3.0;
        g += f * 2.0;
        assert_eq!(g, Wrench::ZERO);
        assert_eq!(-Wrench::ZERO + Wrench::default(), Wrench::ZERO);
        assert!(t.is_finite() && f.is_finite());
        assert!(!Twist::new(DVec3::NAN, DVec3::ZERO).is_finite());
        assert!(!Wrench::new(DVec3::ZERO, DVec3::INFINITY).is_finite());
    }

    #[test]
    fn mat6_layout_products_and_transpose() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(3);
        let mut err: f64 = 0.0;
        for _ in 0..N {
            let a = mat6(&mut rng);
            let b = mat6(&mut rng);
            let (ra, rb) = (a.to_rows(), b.to_rows());
            assert_eq!(Mat6::from_rows(ra), a);
            let x: [f64; 6] = core::array::from_fn(|_| rng.random_range(-1.0..1.0));
            let ax: [f64; 6] = core::array::from_fn(|i| (0..6).map(|k| ra[i][k] * x[k]).sum());
            err = err.max(arr_diff(&a.mul_array(&x), &ax));
            err = err.max(arr_diff(
                &a.mul_twist(&Twist::from_array(x)).to_array(),
                &ax,
            ));
            err = err.max(arr_diff(
                &a.mul_wrench(&Wrench::from_array(x)).to_array(),
                &ax,
            ));
            err = err.max(arr_diff(
                &a.inertia_mul(&Twist::from_array(x)).to_array(),
                &ax,
            ));
            err = err.max(arr_diff(
                &a.compliance_mul(&Wrench::from_array(x)).to_array(),
                &ax,
            ));
            err = err.max((a * b).max_abs_diff(&Mat6::from_rows(mul_rows(&ra, &rb))));
            let at = a.transpose().to_rows();
            for i in 0..6 {
                for j in 0..6 {
                    assert_eq!(at[i][j], ra[j][i]);
                }
            }
            let sum = (a + b - a * 2.0).to_rows();
            for i in 0..6 {
                for j in 0..6 {
                    err = err.max((sum[i][j] - (rb[i][j] - ra[i][j])).abs());
                }
            }
            let o = Mat6::outer(&x, &ax).to_rows();
            for i in 0..6 {
                for j in 0..6 {
                    assert_eq!(o[i][j], x[i] * ax[j]);
                }
            }
        }
        println!("mat6 products vs brute force: {err:e}");
        assert!(err <= TIGHT_TOL * 10.0);
        assert_eq!(Mat6::IDENTITY * Mat6::IDENTITY, Mat6::IDENTITY);
        assert_eq!(
            Mat6::from_blocks(DMat3::IDENTITY, DMat3::ZERO, DMat3::ZERO, DMat3::IDENTITY),
            Mat6::IDENTITY
        );
    }

    #[test]
    fn mat6_try_inverse() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(4);
        let mut err: f64 = 0.0;
        for i in 0..N {
            // Alternate plain random matrices and badly row/column-scaled ones.
            let mut m = mat6(&mut rng);
            if i % 2 == 1 {
                let d: [f64; 6] = core::array::from_fn(|_| 10f64.powf(rng.random_range(-3.0..3.0)));
                let mut r = m.to_rows();
                for (k, row) in r.iter_mut().enumerate() {
                    for (l, x) in row.iter_mut().enumerate() {
                        *x *= d[k] / d[l];
                    }
                }
                m = Mat6::from_rows(r);
            }
            let Some(inv) = m.try_inverse() else {
                panic!("random matrix reported singular: {m:?}");
            };
            let scale = max_abs(&m) * max_abs(&inv);
            err = err.max((m * inv).max_abs_diff(&Mat6::IDENTITY) / scale);
            err = err.max((inv * m).max_abs_diff(&Mat6::IDENTITY) / scale);
        }
        println!("try_inverse: max ‖MM⁻¹ − I‖ / (‖M‖‖M⁻¹‖) = {err:e}");
        assert!(err <= INVERSE_TOL);
        assert_eq!(Mat6::IDENTITY.try_inverse(), Some(Mat6::IDENTITY));

        // Singular matrices: zero, a repeated row, rank 5, non-finite.
        assert!(Mat6::ZERO.try_inverse().is_none());
        let mut r = mat6(&mut rng).to_rows();
        r[4] = r[1];
        assert!(Mat6::from_rows(r).try_inverse().is_none());
        let mut rank5 = Mat6::ZERO;
        for _ in 0..5 {
            let a: [f64; 6] = core::array::from_fn(|_| rng.random_range(-1.0..1.0));
            let b: [f64; 6] = core::array::from_fn(|_| rng.random_range(-1.0..1.0));
            rank5 = rank5 + Mat6::outer(&a, &b);
        }
        assert!(rank5.try_inverse().is_none());
        let mut nan = Mat6::IDENTITY;
        nan.tr.x_axis.y = f64::NAN;
        assert!(nan.try_inverse().is_none());
    }

    #[test]
    fn so3_exp_log() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(5);
        let (mut e_glam, mut e_round, mut e_log): (f64, f64, f64) = (0.0, 0.0, 0.0);
        for i in 0..N {
            let axis = vec3(&mut rng, 1.0).normalize();
            let angle = match i % 3 {
                0 => rng.random_range(0.0..core::f64::consts::PI),
                1 => 10f64.powf(rng.random_range(-20.0..-1.0)),
                _ => core::f64::consts::PI - 10f64.powf(rng.random_range(-14.0..-1.0)),
            };
            let rv = axis * angle;
            let q = so3_exp(rv);
            // Independent reference: glam's axis-angle constructor.
            let reference = DQuat::from_axis_angle(axis, angle);
            e_glam = e_glam.max(
                (DVec4::from(q) - DVec4::from(reference))
                    .abs()
                    .max_element(),
            );
            e_round = e_round.max((so3_log(q) - rv).abs().max_element());
            let back = so3_exp(so3_log(reference));
            e_log = e_log.max(
                (DVec4::from(back) - DVec4::from(reference))
                    .abs()
                    .max_element(),
            );
            // The sign of q does not matter.
            assert!((so3_log(-q) - so3_log(q)).abs().max_element() == 0.0);
        }
        assert_eq!(so3_exp(DVec3::ZERO), DQuat::IDENTITY);
        assert_eq!(so3_log(DQuat::IDENTITY), DVec3::ZERO);
        // Exactly π: |log| = π.
        let q = DQuat::from_xyzw(0.0, 0.6, 0.8, 0.0);
        assert!((so3_log(q).length() - core::f64::consts::PI).abs() <= SO3_TOL);
        println!("so3: exp vs glam {e_glam:e}, log(exp) {e_round:e}, exp(log) {e_log:e}");
        assert!(e_glam <= SO3_TOL && e_round <= SO3_TOL * 10.0 && e_log <= SO3_TOL);
    }
}
