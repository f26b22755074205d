//! The collision matrix K in the collision frame (thesis §3.2.1), validated, with its inverse.
//!
//! ## Where K⁻¹ is used, and what happens when K is singular
//! For two rigid bodies K is symmetric positive definite (Theorem 6) and K⁻¹ is its ordinary
//! inverse. A multibody K may be singular (thesis Ch. 5, Fig. 5.12: rank 2 for a two-DOF
//! linkage); then [`CollisionMatrix::inverse`] is the Moore–Penrose **pseudo-inverse** K⁺ from
//! the SVD (faer), singular values below [`crate::tol::RANK_TOL_REL`] of the largest dropped. It
//! maps a velocity change to the minimum-norm impulse producing it, with no null-space part.
//! K⁻¹ (or K⁺) appears in exactly these places:
//! 1. the stable-sticking test, Theorem 9 ([`CollisionMatrix::sticking_is_stable`]);
//! 2. the impulse direction while sticking, eq. (3.6): `dp/dp_z = K⁻¹·e_z / K⁻¹_33`
//!    ([`CollisionMatrix::sticking_direction`]). For singular K sticking is taken as stable only
//!    if, in addition, e_z lies in K's range (otherwise no impulse keeps u_t = 0 while u_z
//!    grows), see [`CollisionMatrix::stable_sticking`];
//! 3. the reversing microcollision impulse `p_r = −2·K⁻¹·u₀` (§3.5), used only if it really
//!    reverses u₀ (for singular K: only if u₀ lies in K's range);
//! 4. the closed-form work of Theorem 11 ([`CollisionMatrix::work_between`]), a diagnostic.
//!
//! The integrator itself never inverts K: it carries the impulse p along with u (dp/dp_z = ξ,
//! du/dp_z = K·ξ), so the thesis's final `p = K⁻¹(u_f − u₀)` is not needed and p is exact in
//! the friction cone by construction. A null-space component of p (singular K) changes no
//! velocity.

use crate::body::{max_abs, max_asymmetry, symmetrize};
use crate::{ResponseError, tol};
use glam::{DMat3, DVec3};

/// A validated collision matrix K (collision frame) with its inverse or pseudo-inverse.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CollisionMatrix {
    k: DMat3,
    k_inv: DMat3,
    rank: usize,
    /// Whether e_z lies in range(K) (always true for rank 3).
    normal_in_range: bool,
}

impl CollisionMatrix {
    /// Validates K (collision frame: z = normal from body 2 to body 1) and computes its inverse.
    ///
    /// K must be finite, symmetric to [`tol::K_SYMMETRY_REL`] (it is then symmetrised),
    /// positive semi-definite to [`tol::K_PSD_REL`], and K_33 must exceed
    /// [`tol::NORMAL_REACH_REL`]·λ_max. A well-conditioned K is inverted explicitly (adjugate);
    /// a nearly singular or singular one by SVD, giving the pseudo-inverse.
    ///
    /// # Errors
    /// [`ResponseError::NonFinite`], [`ResponseError::NotSymmetric`],
    /// [`ResponseError::NotPositiveSemidefinite`], [`ResponseError::NormalUnreachable`],
    /// [`ResponseError::Svd`].
    pub fn new(k: DMat3) -> Result<Self, ResponseError> {
        if !k.is_finite() {
            return Err(ResponseError::NonFinite {
                what: "collision matrix",
            });
        }
        let scale = max_abs(&k);
        let asym = max_asymmetry(&k);
        if asym > tol::K_SYMMETRY_REL * scale {
            return Err(ResponseError::NotSymmetric {
                asymmetry: asym,
                scale,
            });
        }
        let k = symmetrize(&k);
        if scale == 0.0 {
            return Err(ResponseError::NormalUnreachable {
                k33: 0.0,
                scale: 0.0,
            });
        }
        // Fast path: Sylvester's criterion says K is positive definite; the explicit inverse is
        // accurate when the conditioning estimate det/trace³ is not tiny.
        let a = k.x_axis.x;
        let minor2 = k.x_axis.x * k.y_axis.y - k.y_axis.x * k.x_axis.y;
        let det = k.determinant();
        let trace = k.x_axis.x + k.y_axis.y + k.z_axis.z;
        if a > 0.0
            && minor2 > 0.0
            && det > 0.0
            && det / (trace * trace * trace) > tol::EXPLICIT_INVERSE_MIN_RCOND
        {
            let k33 = k.z_axis.z;
            if k33 <= tol::NORMAL_REACH_REL * trace {
                return Err(ResponseError::NormalUnreachable { k33, scale: trace });
            }
            return Ok(Self {
                k,
                k_inv: symmetrize(&k.inverse()),
                rank: 3,
                normal_in_range: true,
            });
        }
        Self::by_svd(k)
    }

    /// The SVD path: signed eigenvalues λ_i = σ_i·(u_i·v_i) (for symmetric K the singular
    /// vectors agree up to sign), the PSD check, rank and K⁺ = Σ_{σ_i kept} v_i u_iᵀ / σ_i.
    fn by_svd(k: DMat3) -> Result<Self, ResponseError> {
        let m = faer::Mat::<f64>::from_fn(3, 3, |r, c| k.col(c)[r]);
        let svd = m.svd().map_err(|_| ResponseError::Svd)?;
        let (u, s, v) = (svd.U(), svd.S(), svd.V());
        let col = |mat: faer::MatRef<'_, f64>, c: usize| {
            DVec3::new(mat[(0, c)], mat[(1, c)], mat[(2, c)])
        };
        let sigma = [s[0], s[1], s[2]];
        let largest = sigma.iter().fold(0.0f64, |a, &x| a.max(x));
        if !largest.is_finite() {
            return Err(ResponseError::Svd);
        }
        let mut k_inv = DMat3::ZERO;
        let mut projector = DMat3::ZERO;
        let mut rank = 0;
        for (i, &sig) in sigma.iter().enumerate() {
            let (ui, vi) = (col(u, i), col(v, i));
            let lambda = sig * ui.dot(vi);
            if lambda < -tol::K_PSD_REL * largest {
                return Err(ResponseError::NotPositiveSemidefinite {
                    eigenvalue: lambda,
                    largest,
                });
            }
            if sig > tol::RANK_TOL_REL * largest {
                rank += 1;
                k_inv += outer(vi, ui) * (1.0 / sig);
                projector += outer(vi, vi);
            }
        }
        let k33 = k.z_axis.z;
        if k33 <= tol::NORMAL_REACH_REL * largest {
            return Err(ResponseError::NormalUnreachable {
                k33,
                scale: largest,
            });
        }
        let residual = (DVec3::Z - projector * DVec3::Z).length();
        Ok(Self {
            k,
            k_inv: symmetrize(&k_inv),
            rank,
            normal_in_range: residual <= tol::REVERSAL_RANGE_REL,
        })
    }

    /// K (collision frame, symmetrised).
    pub fn k(&self) -> DMat3 {
        self.k
    }

    /// K⁻¹, or the pseudo-inverse K⁺ if K is singular (see the module documentation for where
    /// it is used).
    pub fn inverse(&self) -> DMat3 {
        self.k_inv
    }

    /// The numerical rank of K (3 for rigid bodies).
    pub fn rank(&self) -> usize {
        self.rank
    }

    /// Whether K is (numerically) singular.
    pub fn is_singular(&self) -> bool {
        self.rank < 3
    }

    /// Theorem 9: friction can maintain sticking iff
    /// `(K⁻¹_13)² + (K⁻¹_23)² ≤ μ²·(K⁻¹_33)²`. Equality counts as stable (the thesis's ≤;
    /// Lemma 4's strict < is the same boundary).
    pub fn sticking_is_stable(&self, mu: f64) -> bool {
        let c = self.k_inv.z_axis; // third column (= third row): K⁻¹_13, K⁻¹_23, K⁻¹_33
        c.x * c.x + c.y * c.y <= mu * mu * c.z * c.z
    }

    /// Theorem 9 and, for singular K, e_z ∈ range(K): sticking, once reached, persists.
    pub fn stable_sticking(&self, mu: f64) -> bool {
        self.normal_in_range && self.sticking_is_stable(mu)
    }

    /// The impulse direction per unit normal impulse while sticking, eq. (3.6):
    /// `dp/dp_z = (K⁻¹_13, K⁻¹_23, K⁻¹_33) / K⁻¹_33`. Its tangential part equals −M⁻¹·s.
    pub fn sticking_direction(&self) -> DVec3 {
        let c = self.k_inv.z_axis;
        DVec3::new(c.x / c.z, c.y / c.z, 1.0)
    }

    /// du_z/dp_z while sticking: `1/K⁻¹_33` (= |K|/|M|, the Schur complement c − sᵀM⁻¹s).
    pub fn sticking_normal_slope(&self) -> f64 {
        1.0 / self.k_inv.z_axis.z
    }

    /// Lemma 3's lower bound on du_z/dp_z over all sliding directions,
    /// `G = K_33 − μ·√(K_31² + K_32²)`. The extension bound b = √(2·W_r·G) exists iff G > 0.
    pub fn lemma3_slope(&self, mu: f64) -> f64 {
        let r = self.k.z_axis; // third column: K_13, K_23, K_33 (= K_31, K_32 by symmetry)
        r.z - mu * (r.x * r.x + r.y * r.y).sqrt()
    }

    /// Theorem 11: the total work of a collision taking u₀ to u_f,
    /// `W = ½ (u_f + u₀)ᵀ K⁻¹ (u_f − u₀)` (path independent; the kinetic-energy change).
    pub fn work_between(&self, u0: DVec3, uf: DVec3) -> f64 {
        0.5 * (uf + u0).dot(self.k_inv * (uf - u0))
    }

    /// The kinetic-energy change when impulse `p` is applied at relative velocity `u0`:
    /// `u₀·p + ½ pᵀ K p` (= Theorem 11 with u_f = u₀ + K p, valid for singular K too).
    pub fn work_of_impulse(&self, u0: DVec3, p: DVec3) -> f64 {
        u0.dot(p) + 0.5 * p.dot(self.k * p)
    }

    /// The reversing impulse of §3.5, `p_r = −2·K⁻¹·u₀` (eq. 3.5 with Δu = −2u₀), if it does
    /// reverse u₀: for singular K, `None` when u₀ is not in K's range.
    pub fn reversing_impulse(&self, u0: DVec3) -> Option<DVec3> {
        let p = self.k_inv * u0 * -2.0;
        if self.rank == 3 {
            return Some(p);
        }
        let miss = (self.k * p + u0 * 2.0).length();
        (miss <= tol::REVERSAL_RANGE_REL * u0.length()).then_some(p)
    }
}

/// a·bᵀ.
fn outer(a: DVec3, b: DVec3) -> DMat3 {
    DMat3::from_cols(a * b.x, a * b.y, a * b.z)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use rand::rngs::Xoshiro256PlusPlus;
    use rand::{RngExt, SeedableRng};

    /// A random SPD matrix with condition number up to ~1e3.
    pub(crate) fn random_spd(rng: &mut Xoshiro256PlusPlus) -> DMat3 {
        let mut a = DMat3::ZERO;
        for c in 0..3 {
            *a.col_mut(c) = DVec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            );
        }
        a * a.transpose() + DMat3::IDENTITY * rng.random_range(1e-3..0.5)
    }

    #[test]
    fn inverse_and_bad_matrices() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(41);
        for _ in 0..500 {
            let k = random_spd(&mut rng);
            let cm = CollisionMatrix::new(k).unwrap();
            assert_eq!(cm.rank(), 3);
            let e = max_abs(&(cm.k() * cm.inverse() - DMat3::IDENTITY));
            assert!(e < 1e-10, "{e}");
        }
        let mut asym = DMat3::IDENTITY;
        asym.x_axis.y = 0.1;
        assert!(matches!(
            CollisionMatrix::new(asym),
            Err(ResponseError::NotSymmetric { .. })
        ));
        assert!(matches!(
            CollisionMatrix::new(DMat3::from_diagonal(DVec3::new(1.0, -0.5, 1.0))),
            Err(ResponseError::NotPositiveSemidefinite { .. })
        ));
        assert!(matches!(
            CollisionMatrix::new(DMat3::from_diagonal(DVec3::new(1.0, 1.0, 0.0))),
            Err(ResponseError::NormalUnreachable { .. })
        ));
        assert!(matches!(
            CollisionMatrix::new(DMat3::ZERO),
            Err(ResponseError::NormalUnreachable { .. })
        ));
        let mut nan = DMat3::IDENTITY;
        nan.y_axis.y = f64::NAN;
        assert!(matches!(
            CollisionMatrix::new(nan),
            Err(ResponseError::NonFinite { .. })
        ));
    }

    /// Rank-deficient K (multibody): the pseudo-inverse satisfies the Penrose conditions, and a
    /// singular K whose range misses e_z is never "stable" for sticking.
    #[test]
    fn singular_k_uses_the_pseudo_inverse() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(42);
        for rank in [1usize, 2] {
            for _ in 0..200 {
                // K = J·Jᵀ with J 3×rank, so rank(K) = rank.
                let mut k = DMat3::ZERO;
                let mut cols = Vec::new();
                for _ in 0..rank {
                    let c = DVec3::new(
                        rng.random_range(-1.0..1.0),
                        rng.random_range(-1.0..1.0),
                        rng.random_range(-1.0..1.0),
                    );
                    k += outer(c, c);
                    cols.push(c);
                }
                let cm = CollisionMatrix::new(k).unwrap();
                assert_eq!(cm.rank(), rank, "{k}");
                let (kk, kp) = (cm.k(), cm.inverse());
                // Penrose: K K⁺ K = K, K⁺ K K⁺ = K⁺.
                assert!(max_abs(&(kk * kp * kk - kk)) < 1e-9 * max_abs(&kk));
                assert!(max_abs(&(kp * kk * kp - kp)) < 1e-9 * max_abs(&kp));
                // e_z ∉ range(K) generically for rank < 3 unless constructed so.
                assert!(!cm.stable_sticking(1e9));
                // A velocity in the range is reversed exactly; one outside is refused.
                let u_in = kk * DVec3::new(0.3, -0.2, -0.9);
                let pr = cm.reversing_impulse(u_in).unwrap();
                assert!((kk * pr + u_in * 2.0).length() < 1e-9 * u_in.length());
                let n = if rank == 1 {
                    cols[0].normalize().any_orthonormal_vector()
                } else {
                    cols[0].cross(cols[1]).normalize()
                };
                assert!(cm.reversing_impulse(n).is_none());
            }
        }
        // Planar rank 2 with e_z in the range: y is the null direction.
        let k = DMat3::from_cols(
            DVec3::new(2.0, 0.0, -0.5),
            DVec3::ZERO,
            DVec3::new(-0.5, 0.0, 1.0),
        );
        let cm = CollisionMatrix::new(k).unwrap();
        assert_eq!(cm.rank(), 2);
        assert!(cm.stable_sticking(0.3)); // |K⁺_13| / K⁺_33 = 0.5/2 = 0.25 ≤ 0.3
        assert!(!cm.stable_sticking(0.2));
    }

    /// Digest test 9 (Corollary 1): the reversing impulse p_r = −2K⁻¹u₀ gives u_f = −u₀ and
    /// does no work, W = u₀·p + ½pᵀKp = 0 (and Theorem 11 agrees), to rounding.
    #[test]
    fn reversing_impulse_does_no_work() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(44);
        for _ in 0..5000 {
            let k = random_spd(&mut rng);
            let cm = CollisionMatrix::new(k).unwrap();
            let u0 = DVec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                -rng.random_range(0.01..1.0),
            );
            let p = cm.reversing_impulse(u0).unwrap();
            let uf = u0 + cm.k() * p;
            // Rounding, amplified by K's condition number (≲ 1e3 here).
            assert!((uf + u0).length() < 1e-11 * u0.length());
            let e = 0.5 * u0.dot(cm.inverse() * u0);
            let w = cm.work_of_impulse(u0, p);
            assert!(w.abs() < 1e-11 * e, "{w}");
            assert_eq!(cm.work_between(u0, -u0), 0.0);
        }
    }

    /// Digest test 13: Theorem 9 ≡ Lemma 4 ≡ ‖M⁻¹s‖ ≤ μ on random SPD K and μ, away from the
    /// boundary.
    #[test]
    fn sticking_tests_agree() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(43);
        let mut stable = 0;
        let mut unstable = 0;
        for _ in 0..20_000 {
            let k = random_spd(&mut rng);
            let mu = rng.random_range(0.0..1.5);
            let cm = CollisionMatrix::new(k).unwrap();
            let (a, b, c) = (k.x_axis.x, k.y_axis.y, k.z_axis.z);
            let (f, e, d) = (k.y_axis.x, k.z_axis.x, k.z_axis.y);
            let _ = c;
            let det_m = a * b - f * f;
            // Lemma 4 (strict), with K's entries named as in (3.15).
            let lhs = (b * b + f * f) * e * e + (a * a + f * f) * d * d - 2.0 * (a + b) * f * d * e;
            let rhs = mu * mu * det_m * det_m;
            // ‖M⁻¹ s‖ ≤ μ.
            let minv_s = DVec3::new(b * e - f * d, a * d - f * e, 0.0) / det_m;
            let norm = minv_s.length();
            if (norm - mu).abs() < 1e-6 * (1.0 + mu) {
                continue;
            }
            let t9 = cm.sticking_is_stable(mu);
            assert_eq!(t9, lhs < rhs, "Lemma 4 vs Theorem 9");
            assert_eq!(t9, norm <= mu, "‖M⁻¹s‖ vs Theorem 9");
            // Sticking direction: tangential part = −M⁻¹ s.
            let q = cm.sticking_direction();
            assert!((q.x + minv_s.x).abs() + (q.y + minv_s.y).abs() < 1e-9 * (1.0 + norm));
            if t9 {
                stable += 1;
            } else {
                unstable += 1;
            }
        }
        assert!(stable > 1000 && unstable > 1000, "{stable} {unstable}");
    }
}
