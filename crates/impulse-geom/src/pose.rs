//! Rigid-body poses (elements of SE(3)), their exponential and logarithm, and the adjoint maps
//! that move twists and wrenches between frames.
//!
//! A [`Pose`] `g = (R, p)` places a child (body) frame B in a parent (world) frame A:
//! `x_A = R·x_B + p`, with `p` the origin of B in A's coordinates (metres). Its adjoint
//! (FORK⁻¹S eq. 29; MLS §2.4, adjoint transformation) maps twists expressed in B to the same twists
//! expressed in A; its inverse transpose maps wrenches (MLS §2.5). Twists and wrenches pack the
//! linear part on top (see [`crate::se3`]).

use core::ops::Mul;

use glam::{DMat3, DMat4, DQuat, DVec3};

use crate::se3::{Mat6, Twist, Wrench, hat, so3_exp, so3_log};

/// Rotation angle θ = |ω| (rad) below which [`Pose::exp`] and [`Pose::log`] evaluate the
/// coefficients of `V` and `V⁻¹` by Taylor series instead of their closed forms.
///
/// The series are kept to the θ⁶ term, so at the switch the first neglected term is below
/// 1e-20 relative. The closed forms `(θ − sin θ)/θ³` and `(1 − (θ/2)cot(θ/2))/θ²` cancel
/// catastrophically for small θ; just above the switch they lose up to `ε/θ² ≈ 2e-12` relative,
/// but they multiply `ŵ²` (norm θ²), so the absolute error they add to the translation stays
/// below ~ε·|v|. 1e-2 therefore keeps every path at machine precision.
pub const SE3_SERIES_ANGLE: f64 = 1e-2;

/// A rigid transform (element of SE(3)) from a child/body frame B to a parent/world frame A:
/// `x_A = R·x_B + p`.
///
/// Invariant: `rotation` is a unit quaternion (the constructors normalise it). `translation` is
/// the origin of B in A's coordinates, in metres. Composition `a * b` applies `b` first.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Pose {
    /// Rotation R from B's axes to A's axes (unit quaternion).
    pub rotation: DQuat,
    /// Position p of B's origin in A (m).
    pub translation: DVec3,
}

impl Default for Pose {
    fn default() -> Self {
        Pose::IDENTITY
    }
}

/// Coefficients `(A, B)` of `V = I + A·ŵ + B·ŵ²` for `θ = |ω|`, `θ² = theta_sq`:
/// `A = (1 − cos θ)/θ²`, `B = (θ − sin θ)/θ³`.
fn v_coefficients(theta_sq: f64) -> (f64, f64) {
    let theta = theta_sq.sqrt();
    if theta < SE3_SERIES_ANGLE {
        let t2 = theta_sq;
        // (1 − cos θ)/θ² = 1/2 − θ²/24 + θ⁴/720 − θ⁶/40320 + …
        let a = 0.5 + t2 * (-1.0 / 24.0 + t2 * (1.0 / 720.0 - t2 / 40_320.0));
        // (θ − sin θ)/θ³ = 1/6 − θ²/120 + θ⁴/5040 − θ⁶/362880 + …
        let b = 1.0 / 6.0 + t2 * (-1.0 / 120.0 + t2 * (1.0 / 5040.0 - t2 / 362_880.0));
        (a, b)
    } else {
        // (1 − cos θ)/θ² = 2 sin²(θ/2)/θ², free of cancellation.
        let s = (0.5 * theta).sin() / theta;
        (2.0 * s * s, (theta - theta.sin()) / (theta_sq * theta))
    }
}

/// Coefficient `C = (1 − (θ/2)·cot(θ/2))/θ²` of `V⁻¹ = I − ½ŵ + C·ŵ²`, θ ∈ [0, π].
fn v_inv_coefficient(theta_sq: f64) -> f64 {
    let theta = theta_sq.sqrt();
    if theta < SE3_SERIES_ANGLE {
        // x·cot x = 1 − x²/3 − x⁴/45 − 2x⁶/945 − x⁸/4725 …, x = θ/2, gives
        // C = 1/12 + θ²/720 + θ⁴/30240 + θ⁶/1209600 + …
        let t2 = theta_sq;
        1.0 / 12.0 + t2 * (1.0 / 720.0 + t2 * (1.0 / 30_240.0 + t2 / 1_209_600.0))
    } else {
        // Near π, cot(θ/2) → 0 and C → 1/θ²: well conditioned.
        let (s, c) = (0.5 * theta).sin_cos();
        (1.0 - 0.5 * theta * c / s) / theta_sq
    }
}

impl Pose {
    /// The identity transform (B coincides with A).
    pub const IDENTITY: Pose = Pose {
        rotation: DQuat::IDENTITY,
        translation: DVec3::ZERO,
    };

    /// Pose from a rotation (normalised here) and a translation (m). A zero or non-finite
    /// quaternion gives a non-finite pose; check with [`Pose::is_finite`].
    #[must_use]
    pub fn new(rotation: DQuat, translation: DVec3) -> Self {
        Pose {
            rotation: rotation.normalize(),
            translation,
        }
    }

    /// Pure translation by `translation` (m).
    #[must_use]
    pub const fn from_translation(translation: DVec3) -> Self {
        Pose {
            rotation: DQuat::IDENTITY,
            translation,
        }
    }

    /// Pure rotation (normalised here) about the parent origin.
    #[must_use]
    pub fn from_rotation(rotation: DQuat) -> Self {
        Pose {
            rotation: rotation.normalize(),
            translation: DVec3::ZERO,
        }
    }

    /// `true` when rotation and translation are finite.
    #[must_use]
    pub fn is_finite(&self) -> bool {
        self.rotation.is_finite() && self.translation.is_finite()
    }

    /// Inverse transform, from A back to B: `(Rᵀ, −Rᵀp)`.
    #[inline]
    #[must_use]
    pub fn inverse(&self) -> Pose {
        let r_inv = self.rotation.conjugate();
        Pose {
            rotation: r_inv,
            translation: -(r_inv * self.translation),
        }
    }

    /// Maps a point from B to A coordinates: `R·x + p` (m).
    #[inline]
    #[must_use]
    pub fn transform_point(&self, x: DVec3) -> DVec3 {
        self.rotation * x + self.translation
    }

    /// Maps a free vector (direction, velocity, force) from B to A axes: `R·x`.
    #[inline]
    #[must_use]
    pub fn transform_vector(&self, x: DVec3) -> DVec3 {
        self.rotation * x
    }

    /// Maps a point from A back to B coordinates: `Rᵀ(x − p)` (m).
    #[inline]
    #[must_use]
    pub fn inverse_transform_point(&self, x: DVec3) -> DVec3 {
        self.rotation.conjugate() * (x - self.translation)
    }

    /// Maps a free vector from A back to B axes: `Rᵀx`.
    #[inline]
    #[must_use]
    pub fn inverse_transform_vector(&self, x: DVec3) -> DVec3 {
        self.rotation.conjugate() * x
    }

    /// Rotation matrix R (B's axes in A's coordinates, as columns).
    #[inline]
    #[must_use]
    pub fn rotation_matrix(&self) -> DMat3 {
        DMat3::from_quat(self.rotation)
    }

    /// Homogeneous 4×4 matrix `[[R, p], [0, 1]]` (MLS §2.3).
    #[must_use]
    pub fn to_mat4(&self) -> DMat4 {
        DMat4::from_rotation_translation(self.rotation, self.translation)
    }

    /// Exponential map se(3) → SE(3): the pose `exp(ξ̂)` reached by following the constant twist
    /// `ξ = (v, ω)` for unit time (MLS eq. 2.36, generalised to non-unit ω).
    ///
    /// `R = exp(ŵ)` ([`so3_exp`]) and `p = V·v` with
    /// `V = I + (1 − cos θ)/θ²·ŵ + (θ − sin θ)/θ³·ŵ²`, θ = |ω|. MLS eq. 2.36 writes
    /// `p = (I − R)(ω × v) + ωωᵀv·θ` for unit ω; expanding R by Rodrigues' formula gives this
    /// V-form, which has no `1/θ²` blow-up. Coefficients use Taylor series below
    /// [`SE3_SERIES_ANGLE`], so θ = 0 gives `(I, v)` exactly. Units: v in m, ω in rad.
    #[must_use]
    pub fn exp(xi: &Twist) -> Pose {
        let w = xi.w;
        let (a, b) = v_coefficients(w.length_squared());
        // MLS eq. 2.36 in V-form: p = V v = v + A (ω × v) + B ω × (ω × v).
        let wv = w.cross(xi.v);
        let p = xi.v + wv * a + w.cross(wv) * b;
        Pose {
            rotation: so3_exp(w),
            translation: p,
        }
    }

    /// Logarithm SE(3) → se(3): the twist ξ with `Pose::exp(&ξ) == self` and rotation angle
    /// |ω| ∈ [0, π].
    ///
    /// `ω = so3_log(R)` (quaternion-based, accurate near 0 and π) and `v = V⁻¹·p` with
    /// `V⁻¹ = I − ½ŵ + C·ŵ²`, `C = (1 − (θ/2)·cot(θ/2))/θ²` (the closed-form inverse of V in
    /// [`Pose::exp`]: use ŵ³ = −θ²ŵ). C uses its Taylor series below [`SE3_SERIES_ANGLE`].
    /// At exactly θ = π the axis sign of ω is ambiguous; either sign reproduces `self` through
    /// `exp`.
    #[must_use]
    pub fn log(&self) -> Twist {
        let w = so3_log(self.rotation);
        let c = v_inv_coefficient(w.length_squared());
        let p = self.translation;
        // Inverse of MLS eq. 2.36: v = V⁻¹ p = p − ½ ω × p + C ω × (ω × p).
        let wp = w.cross(p);
        let v = p - wp * 0.5 + w.cross(wp) * c;
        Twist { v, w }
    }

    /// Adjoint `Ad_g = [[R, p̂R], [0, R]]` (FORK⁻¹S eq. 29; MLS §2.4, adjoint transformation,
    /// linear on top): maps a twist expressed in B to the same twist expressed in A,
    /// `ξ_A = Ad_g ξ_B`. Satisfies `Ad_{a·b} = Ad_a·Ad_b` and `(Ad_g ξ)^ = g ξ̂ g⁻¹`.
    #[must_use]
    pub fn adjoint(&self) -> Mat6 {
        // FORK⁻¹S eq. 29: ᵇAd = [[ᵇR, ᵇp̂ₐ ᵇR], [0, ᵇR]] with b = A (parent), a = B (child).
        let r = self.rotation_matrix();
        Mat6::from_blocks(r, hat(self.translation) * r, DMat3::ZERO, r)
    }

    /// Wrench map `Ad_g⁻ᵀ = [[R, 0], [p̂R, R]]`: maps a wrench expressed in B to the same wrench
    /// expressed in A, `F_A = Ad_g⁻ᵀ F_B` (FORK⁻¹S after eq. 29; MLS §2.5). It keeps power
    /// invariant: `F_A·ξ_A = F_B·ξ_B`.
    #[must_use]
    pub fn adjoint_inv_transpose(&self) -> Mat6 {
        // (Ad⁻¹)ᵀ with Ad⁻¹ = [[Rᵀ, −Rᵀp̂], [0, Rᵀ]] and (−Rᵀp̂)ᵀ = p̂R (FORK⁻¹S after eq. 29).
        let r = self.rotation_matrix();
        Mat6::from_blocks(r, DMat3::ZERO, hat(self.translation) * r, r)
    }

    /// Re-expresses a twist given in B in A: `(R v + p × R ω, R ω)`, i.e. `Ad_g ξ` without
    /// forming the 6×6 matrix.
    #[must_use]
    pub fn transform_twist(&self, xi: &Twist) -> Twist {
        let w = self.rotation * xi.w;
        Twist {
            v: self.rotation * xi.v + self.translation.cross(w),
            w,
        }
    }

    /// Re-expresses a wrench given in B in A: `(R f, R τ + p × R f)`, i.e. `Ad_g⁻ᵀ F` without
    /// forming the 6×6 matrix.
    #[must_use]
    pub fn transform_wrench(&self, f: &Wrench) -> Wrench {
        let force = self.rotation * f.f;
        Wrench {
            f: force,
            tau: self.rotation * f.tau + self.translation.cross(force),
        }
    }

    /// Re-expresses a twist given in A in B: `(Rᵀ(v − p × ω), Rᵀω)` = `Ad_g⁻¹ ξ`.
    #[must_use]
    pub fn inverse_transform_twist(&self, xi: &Twist) -> Twist {
        let r_inv = self.rotation.conjugate();
        Twist {
            v: r_inv * (xi.v - self.translation.cross(xi.w)),
            w: r_inv * xi.w,
        }
    }

    /// Re-expresses a wrench given in A in B: `(Rᵀf, Rᵀ(τ − p × f))` = `Ad_gᵀ F`.
    #[must_use]
    pub fn inverse_transform_wrench(&self, f: &Wrench) -> Wrench {
        let r_inv = self.rotation.conjugate();
        Wrench {
            f: r_inv * f.f,
            tau: r_inv * (f.tau - self.translation.cross(f.f)),
        }
    }
}

impl Mul<Pose> for Pose {
    type Output = Pose;

    /// Composition `a * b`: apply `b` first, then `a` (`x ↦ a(b(x))`), i.e. `b` places frame C
    /// in B and `a` places B in A. The product quaternion is renormalised so that long chains of
    /// compositions do not drift off the unit sphere.
    #[inline]
    fn mul(self, b: Pose) -> Pose {
        Pose {
            rotation: (self.rotation * b.rotation).normalize(),
            translation: self.rotation * b.translation + self.translation,
        }
    }
}

/// Right Jacobian of SO(3) at the rotation vector `w` (rad):
/// `exp(w + δ) ≈ exp(w)·exp(J_r(w)·δ)` to first order in δ, i.e. the body-frame angular
/// displacement produced by a change δ of the rotation vector.
///
/// `J_r(w) = I − (1 − cos θ)/θ²·ŵ + (θ − sin θ)/θ³·ŵ²`, θ = |w| (the left Jacobian — the `V` of
/// [`Pose::exp`] — at `−w`); the coefficients use the same Taylor series below
/// [`SE3_SERIES_ANGLE`], so `J_r(0) = I` exactly.
#[must_use]
pub fn so3_right_jacobian(w: DVec3) -> DMat3 {
    let (a, b) = v_coefficients(w.length_squared());
    let wh = hat(w);
    DMat3::IDENTITY - wh * a + wh * wh * b
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f64::consts::PI;
    use glam::DVec4;
    use rand::rngs::Xoshiro256PlusPlus;
    use rand::{RngExt, SeedableRng};

    /// Samples per category (uniform, near 0, near π): 3 × 4000 = 12 000 in all.
    const PER_CATEGORY: usize = 4000;
    /// Largest translation magnitude of random poses and linear part of random twists (m).
    const MAX_LEN: f64 = 10.0;
    /// `exp(log(g)) == g`: rotation-matrix entries, absolute; translation relative to `1 + |p|`.
    const EXP_LOG_TOL: f64 = 1e-12;
    /// `log(exp(ξ)) == ξ` relative to `1 + |ξ|` (|ξ|² = |v|² + |ω|²), |ω| < π.
    const LOG_EXP_TOL: f64 = 1e-12;
    /// `Pose::exp(ξ).to_mat4()` vs the scaling-and-squaring matrix exponential of `ξ̂`, entries
    /// relative to `1 + |v|`.
    const MATRIX_EXP_TOL: f64 = 1e-12;
    /// Adjoint identities: entry errors divided by `1 + |p|` (the top-right blocks are p̂R
    /// products whose rounding grows with |p|), by `1 + |p_a| + |p_b|` for the composition test.
    /// The same scaling suffices for the Gaussian-elimination inverse: Ad is block upper
    /// triangular, so elimination only ever pivots inside the R blocks.
    const ADJOINT_TOL: f64 = 1e-12;
    /// Twist/wrench transport and 4×4 conjugation: relative to `(1 + |p|)(1 + |ξ|)`.
    const TRANSPORT_TOL: f64 = 1e-12;
    /// Power invariance: relative to `|F|·|ξ|·(1 + |p|)`, the size of the terms that cancel.
    const POWER_TOL: f64 = 1e-12;

    #[derive(Copy, Clone, Debug, PartialEq)]
    enum Category {
        Uniform,
        NearZero,
        NearPi,
    }

    const CATEGORIES: [Category; 3] = [Category::Uniform, Category::NearZero, Category::NearPi];

    fn unit_vector(rng: &mut Xoshiro256PlusPlus) -> DVec3 {
        let z: f64 = rng.random_range(-1.0..=1.0);
        let phi = rng.random_range(0.0..2.0 * PI);
        let r = (1.0 - z * z).max(0.0).sqrt();
        DVec3::new(r * phi.cos(), r * phi.sin(), z)
    }

    fn ball(rng: &mut Xoshiro256PlusPlus, max: f64) -> DVec3 {
        unit_vector(rng) * rng.random_range(0.0..max)
    }

    /// Uniform (Haar) random unit quaternion, Shoemake's method.
    fn uniform_quat(rng: &mut Xoshiro256PlusPlus) -> DQuat {
        let u1: f64 = rng.random::<f64>();
        let (a, b) = (
            2.0 * PI * rng.random::<f64>(),
            2.0 * PI * rng.random::<f64>(),
        );
        let (s1, s2) = ((1.0 - u1).sqrt(), u1.sqrt());
        DQuat::from_xyzw(s1 * a.sin(), s1 * a.cos(), s2 * b.sin(), s2 * b.cos())
    }

    /// Random rotation of the given category; half of the near-0 / near-π ones are exact.
    fn rotation(rng: &mut Xoshiro256PlusPlus, cat: Category) -> DQuat {
        let exact = rng.random::<f64>() < 0.5;
        let q = match cat {
            Category::Uniform => uniform_quat(rng),
            Category::NearZero if exact => DQuat::IDENTITY,
            Category::NearZero => {
                DQuat::from_axis_angle(unit_vector(rng), 10f64.powf(rng.random_range(-18.0..-8.0)))
            }
            Category::NearPi if exact => {
                // w = 0 exactly: a rotation by exactly π.
                let a = unit_vector(rng);
                DQuat::from_xyzw(a.x, a.y, a.z, 0.0)
            }
            Category::NearPi => {
                let d = 10f64.powf(rng.random_range(-14.0..-8.0));
                let angle = if rng.random::<f64>() < 0.5 {
                    PI - d
                } else {
                    PI + d
                };
                DQuat::from_axis_angle(unit_vector(rng), angle)
            }
        };
        // Either sign of the double cover.
        if rng.random::<f64>() < 0.5 { -q } else { q }
    }

    fn pose(rng: &mut Xoshiro256PlusPlus, cat: Category) -> Pose {
        let q = rotation(rng, cat);
        Pose::new(q, ball(rng, MAX_LEN))
    }

    /// Random twist; `exact_pi` is set when |ω| is π up to rounding (log axis ambiguous).
    fn twist(rng: &mut Xoshiro256PlusPlus, cat: Category) -> (Twist, bool) {
        let axis = unit_vector(rng);
        let exact = rng.random::<f64>() < 0.5;
        let angle = match cat {
            Category::Uniform => rng.random_range(0.0..PI),
            Category::NearZero if exact => 0.0,
            Category::NearZero => 10f64.powf(rng.random_range(-18.0..-8.0)),
            Category::NearPi if exact => PI,
            Category::NearPi => PI - 10f64.powf(rng.random_range(-14.0..-8.0)),
        };
        let exact_pi = cat == Category::NearPi && exact;
        (Twist::new(ball(rng, MAX_LEN), axis * angle), exact_pi)
    }

    fn norm6(t: &Twist) -> f64 {
        (t.v.length_squared() + t.w.length_squared()).sqrt()
    }

    fn twist_diff(a: &Twist, b: &Twist) -> f64 {
        (a.v - b.v)
            .abs()
            .max_element()
            .max((a.w - b.w).abs().max_element())
    }

    fn mat3_diff(a: &DMat3, b: &DMat3) -> f64 {
        (0..3)
            .map(|i| (a.col(i) - b.col(i)).abs().max_element())
            .fold(0.0, f64::max)
    }

    fn mat4_diff(a: &DMat4, b: &DMat4) -> f64 {
        (0..4)
            .map(|i| (a.col(i) - b.col(i)).abs().max_element())
            .fold(0.0, f64::max)
    }

    /// Brute-force reference: matrix exponential by scaling and squaring of a Taylor series.
    fn expm(m: &DMat4) -> DMat4 {
        let norm = (0..4)
            .map(|r| (0..4).map(|c| m.col(c)[r].abs()).sum::<f64>())
            .fold(0.0, f64::max);
        let mut s = 0;
        while norm / f64::from(1u32 << s) > 0.25 {
            s += 1;
        }
        let a = *m * (1.0 / f64::from(1u32 << s));
        let mut term = DMat4::IDENTITY;
        let mut sum = DMat4::IDENTITY;
        for k in 1..=25 {
            term = term * a * (1.0 / f64::from(k));
            sum += term;
        }
        for _ in 0..s {
            sum = sum * sum;
        }
        sum
    }

    /// Running maximum of each error, with the sample that produced it.
    #[derive(Default)]
    struct Max {
        value: f64,
    }

    impl Max {
        fn add(&mut self, e: f64) {
            assert!(e.is_finite(), "non-finite error");
            self.value = self.value.max(e);
        }
    }

    #[test]
    fn exp_log_round_trips() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(11);
        let mut exp_log_rot = [0.0f64; 3];
        let mut exp_log_trans = [0.0f64; 3];
        let mut log_exp = [0.0f64; 3];
        let mut exp_log_exp_pi = Max::default();
        let mut matrix_exp = Max::default();
        for (ci, &cat) in CATEGORIES.iter().enumerate() {
            for _ in 0..PER_CATEGORY {
                // exp(log(g)) == g.
                let g = pose(&mut rng, cat);
                let h = Pose::exp(&g.log());
                exp_log_rot[ci] =
                    exp_log_rot[ci].max(mat3_diff(&h.rotation_matrix(), &g.rotation_matrix()));
                exp_log_trans[ci] = exp_log_trans[ci].max(
                    (h.translation - g.translation).abs().max_element()
                        / (1.0 + g.translation.length()),
                );
                // Angles of logs are in [0, π].
                assert!(g.log().w.length() <= PI * (1.0 + f64::EPSILON));

                // log(exp(ξ)) == ξ for |ω| < π; at exactly π compare through exp instead.
                let (xi, exact_pi) = twist(&mut rng, cat);
                let g = Pose::exp(&xi);
                let back = g.log();
                if exact_pi {
                    let h = Pose::exp(&back);
                    exp_log_exp_pi.add(mat3_diff(&h.rotation_matrix(), &g.rotation_matrix()).max(
                        (h.translation - g.translation).abs().max_element()
                            / (1.0 + g.translation.length()),
                    ));
                } else {
                    log_exp[ci] = log_exp[ci].max(twist_diff(&back, &xi) / (1.0 + norm6(&xi)));
                }

                // Independent reference for exp: brute-force matrix exponential of ξ̂.
                let reference = expm(&xi.hat4());
                matrix_exp.add(mat4_diff(&g.to_mat4(), &reference) / (1.0 + xi.v.length()));
            }
        }
        let e3 = |a: &[f64; 3]| format!("[{:.3e}, {:.3e}, {:.3e}]", a[0], a[1], a[2]);
        println!(
            "exp(log g): rotation  [uniform, ~0, ~π] = {}",
            e3(&exp_log_rot)
        );
        println!(
            "exp(log g): translation/(1+|p|)         = {}",
            e3(&exp_log_trans)
        );
        println!(
            "log(exp ξ) − ξ, /(1+|ξ|), |ω|<π          = {}",
            e3(&log_exp)
        );
        println!(
            "|ω| = π exactly: exp(log(exp ξ)) vs exp ξ = {:.3e}",
            exp_log_exp_pi.value
        );
        println!(
            "exp vs matrix exponential /(1+|v|)      = {:.3e}",
            matrix_exp.value
        );
        for ci in 0..3 {
            assert!(exp_log_rot[ci] <= EXP_LOG_TOL && exp_log_trans[ci] <= EXP_LOG_TOL);
            assert!(log_exp[ci] <= LOG_EXP_TOL);
        }
        assert!(exp_log_exp_pi.value <= EXP_LOG_TOL);
        assert!(matrix_exp.value <= MATRIX_EXP_TOL);
    }

    #[test]
    fn exp_log_exact_special_cases() {
        // θ = 0: exp is (I, v) exactly and log is exact.
        let xi = Twist::new(DVec3::new(1.0, -2.0, 3.0), DVec3::ZERO);
        let g = Pose::exp(&xi);
        assert_eq!(g, Pose::from_translation(xi.v));
        assert_eq!(g.log(), xi);
        assert_eq!(Pose::IDENTITY.log(), Twist::ZERO);
        assert_eq!(Pose::exp(&Twist::ZERO), Pose::IDENTITY);
        // Tiny angle: agrees with the first-order expansion to rounding.
        let w = DVec3::new(1e-9, -2e-9, 0.5e-9);
        let g = Pose::exp(&Twist::new(xi.v, w));
        let expected = xi.v + w.cross(xi.v) * 0.5;
        assert!((g.translation - expected).abs().max_element() <= 4.0 * f64::EPSILON * 4.0);
    }

    #[test]
    fn adjoint_identities() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(12);
        let (mut comp, mut inv, mut inv_t) = (Max::default(), Max::default(), Max::default());
        let (mut transport, mut conj, mut power) = (Max::default(), Max::default(), Max::default());
        for &cat in &CATEGORIES {
            for _ in 0..PER_CATEGORY {
                let a = pose(&mut rng, cat);
                let b = pose(&mut rng, cat);
                let (pa, pb) = (a.translation.length(), b.translation.length());

                // Ad(a)·Ad(b) = Ad(a·b).
                comp.add(
                    (a.adjoint() * b.adjoint()).max_abs_diff(&(a * b).adjoint()) / (1.0 + pa + pb),
                );
                // Ad(g)·Ad(g⁻¹) = I.
                inv.add(
                    (a.adjoint() * a.inverse().adjoint()).max_abs_diff(&Mat6::IDENTITY)
                        / (1.0 + pa),
                );
                // Ad⁻ᵀ = (Ad⁻¹)ᵀ with Ad⁻¹ from general Gaussian elimination.
                let Some(ad_inv) = a.adjoint().try_inverse() else {
                    panic!("adjoint reported singular for {a:?}");
                };
                inv_t.add(a.adjoint_inv_transpose().max_abs_diff(&ad_inv.transpose()) / (1.0 + pa));

                // Direct transport equals the 6×6 products, inverse transport undoes it.
                let (xi, _) = twist(&mut rng, Category::Uniform);
                let f = Wrench::new(ball(&mut rng, MAX_LEN), ball(&mut rng, MAX_LEN));
                let scale = (1.0 + pa) * (1.0 + norm6(&xi));
                let fscale = (1.0 + pa) * (1.0 + f.f.length() + f.tau.length());
                let txi = a.transform_twist(&xi);
                let tf = a.transform_wrench(&f);
                transport.add(twist_diff(&txi, &a.adjoint().mul_twist(&xi)) / scale);
                transport.add(twist_diff(&a.inverse_transform_twist(&txi), &xi) / scale);
                transport.add(
                    twist_diff(
                        &a.inverse_transform_twist(&xi),
                        &a.inverse().transform_twist(&xi),
                    ) / scale,
                );
                let wd = |x: &Wrench, y: &Wrench| {
                    (x.f - y.f)
                        .abs()
                        .max_element()
                        .max((x.tau - y.tau).abs().max_element())
                };
                transport.add(wd(&tf, &a.adjoint_inv_transpose().mul_wrench(&f)) / fscale);
                transport.add(wd(&a.inverse_transform_wrench(&tf), &f) / fscale);

                // g·ξ̂·g⁻¹ = (Ad_g ξ)^, independent reference through DMat4 products.
                let lhs = a.to_mat4() * xi.hat4() * a.inverse().to_mat4();
                conj.add(mat4_diff(&lhs, &txi.hat4()) / scale);

                // Power is frame-invariant.
                let p0 = f.power(&xi);
                let p1 = tf.power(&txi);
                let fnorm = (f.f.length_squared() + f.tau.length_squared()).sqrt();
                power.add(
                    (p0 - p1).abs() / (fnorm * norm6(&xi) * (1.0 + pa)).max(f64::MIN_POSITIVE),
                );
            }
        }
        println!(
            "Ad(a)Ad(b) − Ad(ab), /(1+|pa|+|pb|)     = {:.3e}",
            comp.value
        );
        println!(
            "Ad(g)Ad(g⁻¹) − I, /(1+|p|)               = {:.3e}",
            inv.value
        );
        println!(
            "Ad⁻ᵀ − (try_inverse Ad)ᵀ, /(1+|p|)       = {:.3e}",
            inv_t.value
        );
        println!(
            "transport vs 6×6, /((1+|p|)(1+|ξ|))     = {:.3e}",
            transport.value
        );
        println!(
            "g ξ̂ g⁻¹ − (Ad ξ)^, /((1+|p|)(1+|ξ|))     = {:.3e}",
            conj.value
        );
        println!(
            "power invariance, /(|F||ξ|(1+|p|))       = {:.3e}",
            power.value
        );
        assert!(comp.value <= ADJOINT_TOL && inv.value <= ADJOINT_TOL);
        assert!(inv_t.value <= ADJOINT_TOL);
        assert!(transport.value <= TRANSPORT_TOL && conj.value <= TRANSPORT_TOL);
        assert!(power.value <= POWER_TOL);
    }

    #[test]
    fn pose_basics() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(13);
        let mut err = Max::default();
        for _ in 0..PER_CATEGORY {
            let a = pose(&mut rng, Category::Uniform);
            let b = pose(&mut rng, Category::Uniform);
            let x = ball(&mut rng, MAX_LEN);
            let s = 1.0 + x.length() + a.translation.length() + b.translation.length();
            // Composition applies b first.
            err.add(
                ((a * b).transform_point(x) - a.transform_point(b.transform_point(x)))
                    .abs()
                    .max_element()
                    / s,
            );
            // Homogeneous matrices agree.
            err.add(mat4_diff(&(a * b).to_mat4(), &(a.to_mat4() * b.to_mat4())) / s);
            let hx = a.to_mat4() * DVec4::new(x.x, x.y, x.z, 1.0);
            err.add((hx.truncate() - a.transform_point(x)).abs().max_element() / s);
            err.add(
                (a.rotation_matrix() * x - a.transform_vector(x))
                    .abs()
                    .max_element()
                    / s,
            );
            // Inverses.
            err.add(
                (a.inverse_transform_point(a.transform_point(x)) - x)
                    .abs()
                    .max_element()
                    / s,
            );
            err.add(
                (a.inverse_transform_vector(a.transform_vector(x)) - x)
                    .abs()
                    .max_element()
                    / s,
            );
            err.add(
                (a.inverse().transform_point(x) - a.inverse_transform_point(x))
                    .abs()
                    .max_element()
                    / s,
            );
            let id = a * a.inverse();
            err.add(mat4_diff(&id.to_mat4(), &DMat4::IDENTITY) / s);
            assert!((((a * b).rotation.length()) - 1.0).abs() <= 4.0 * f64::EPSILON);
        }
        println!("pose basics: {:.3e}", err.value);
        assert!(err.value <= TRANSPORT_TOL);
        let p = Pose::new(DQuat::from_xyzw(0.0, 0.0, 2.0, 0.0), DVec3::X);
        assert_eq!(p.rotation, DQuat::from_xyzw(0.0, 0.0, 1.0, 0.0));
        assert_eq!(
            Pose::from_rotation(DQuat::from_xyzw(0.0, 3.0, 0.0, 0.0)).translation,
            DVec3::ZERO
        );
        assert_eq!(Pose::default(), Pose::IDENTITY);
        assert!(p.is_finite());
        assert!(!Pose::new(DQuat::from_xyzw(0.0, 0.0, 0.0, 0.0), DVec3::X).is_finite());
        assert!(!Pose::from_translation(DVec3::NAN).is_finite());
    }

    /// `so3_right_jacobian` against central differences of `so3_exp`: the body-frame rotation
    /// `log(exp(w)⁻¹·exp(w + h e_k)) / h` for each axis, with truncation O(h²) ≈ 1e-12.
    #[test]
    fn so3_right_jacobian_matches_finite_differences() {
        const H: f64 = 1e-6;
        const FD_TOL: f64 = 1e-8;
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(77);
        let mut err: f64 = 0.0;
        for i in 0..2000 {
            let w = if i % 2 == 0 {
                ball(&mut rng, 3.0)
            } else {
                ball(&mut rng, 1e-3)
            };
            let jr = so3_right_jacobian(w);
            let q0 = so3_exp(w).conjugate();
            for k in 0..3 {
                let e = DVec3::AXES[k];
                let plus = so3_log(q0 * so3_exp(w + e * H));
                let minus = so3_log(q0 * so3_exp(w - e * H));
                let fd = (plus - minus) / (2.0 * H);
                err = err.max((fd - jr.col(k)).abs().max_element());
            }
        }
        assert_eq!(so3_right_jacobian(DVec3::ZERO), DMat3::IDENTITY);
        println!("so3_right_jacobian vs central differences: {err:e}");
        assert!(err <= FD_TOL);
    }
}
