//! Spatial algebra for the recursions, in the project's linear-on-top packing.
//!
//! # Relation to the thesis's notation
//!
//! Mirtich (chapter 4, Defs. 5–8) writes motion vectors as `[ω; v]` and force vectors as
//! `[f; τ]`, so his spatial inertia `[[0, M], [I, 0]]` is not symmetric and his "spatial
//! transpose" swaps halves. This crate packs both twists and wrenches linear on top
//! (`Twist = (v, ω)`, `Wrench = (f, τ)`, see `impulse_geom::se3`), the pairing is the plain dot
//! product `f·v + τ·ω`, and the spatial (articulated) inertia is the symmetric matrix
//! `[[A, B], [Bᵀ, C]]` with `f = A v + B ω`, `τ = Bᵀ v + C ω`. The thesis's `ŝ'x̂` becomes
//! `Sᵀx` and `S·Î` (the symmetric form the digest recommends) is our matrix directly.
//!
//! A transform [`Xform`] `(R, p)` places a child frame in its parent: `x_parent = R x_child + p`.
//! Definition 6's `_iX̂_h` (parent → child, motion) is [`Xform::motion_to_child`] and
//! `_hX̂_i` applied to a force (child → parent) is [`Xform::force_to_parent`].

use glam::{DMat3, DVec3};
use impulse_geom::{Mat6, Pose, SpatialInertia, Twist, Wrench};

use crate::tol::SPD_PIVOT_REL;

/// `Rᵀ v` without forming the transpose.
#[inline]
pub(crate) fn rt_mul(r: &DMat3, v: DVec3) -> DVec3 {
    DVec3::new(r.x_axis.dot(v), r.y_axis.dot(v), r.z_axis.dot(v))
}

/// Outer product `x yᵀ`.
#[inline]
pub(crate) fn outer(x: DVec3, y: DVec3) -> DMat3 {
    DMat3::from_cols(x * y.x, x * y.y, x * y.z)
}

/// `p̂ M`: the cross product of `p` with every column of `m`.
#[inline]
fn hat_mul(p: DVec3, m: &DMat3) -> DMat3 {
    DMat3::from_cols(p.cross(m.x_axis), p.cross(m.y_axis), p.cross(m.z_axis))
}

/// `R M Rᵀ`.
#[inline]
fn sandwich(r: &DMat3, m: &DMat3) -> DMat3 {
    *r * *m * r.transpose()
}

/// Rotation by `angle` (rad) about the unit vector `u` (Rodrigues, App. A eq. A.6):
/// `R = cos θ·1 + (1 − cos θ) u uᵀ + sin θ û`.
#[inline]
pub(crate) fn axis_angle(u: DVec3, angle: f64) -> DMat3 {
    let (s, c) = angle.sin_cos();
    let t = 1.0 - c;
    let (x, y, z) = (u.x, u.y, u.z);
    let (tx, ty, tz) = (t * x, t * y, t * z);
    let (sx, sy, sz) = (s * x, s * y, s * z);
    DMat3::from_cols(
        DVec3::new(tx * x + c, tx * y + sz, tx * z - sy),
        DVec3::new(tx * y - sz, ty * y + c, ty * z + sx),
        DVec3::new(tx * z + sy, ty * z - sx, tz * z + c),
    )
}

/// A rigid transform from a child frame to its parent: `x_parent = r x_child + p`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Xform {
    /// Rotation from child axes to parent axes.
    pub r: DMat3,
    /// Child origin in parent coordinates.
    pub p: DVec3,
}

impl Xform {
    pub(crate) const IDENTITY: Xform = Xform {
        r: DMat3::IDENTITY,
        p: DVec3::ZERO,
    };

    pub(crate) fn from_pose(pose: &Pose) -> Xform {
        Xform {
            r: pose.rotation_matrix(),
            p: pose.translation,
        }
    }

    pub(crate) fn to_pose(self) -> Pose {
        Pose::new(glam::DQuat::from_mat3(&self.r), self.p)
    }

    /// `self ∘ child`: the transform of `child`'s frame into `self`'s parent.
    #[inline]
    pub(crate) fn compose(&self, child: &Xform) -> Xform {
        Xform {
            r: self.r * child.r,
            p: self.r * child.p + self.p,
        }
    }

    /// Point from child to parent coordinates.
    #[inline]
    pub(crate) fn point_to_parent(&self, x: DVec3) -> DVec3 {
        self.r * x + self.p
    }

    /// Point from parent to child coordinates.
    #[inline]
    pub(crate) fn point_to_child(&self, x: DVec3) -> DVec3 {
        rt_mul(&self.r, x - self.p)
    }

    /// Motion vector from parent to child coordinates, `Ad⁻¹ ξ = (Rᵀ(v − p × ω), Rᵀω)`:
    /// Definition 6's `_iX̂_h` (eq. 4.20 shifts the reference point, then R rotates).
    #[inline]
    pub(crate) fn motion_to_child(&self, t: &Twist) -> Twist {
        Twist {
            v: rt_mul(&self.r, t.v - self.p.cross(t.w)),
            w: rt_mul(&self.r, t.w),
        }
    }

    /// Motion vector from child to parent coordinates, `(R v + p × Rω, Rω)`.
    #[inline]
    pub(crate) fn motion_to_parent(&self, t: &Twist) -> Twist {
        let w = self.r * t.w;
        Twist {
            v: self.r * t.v + self.p.cross(w),
            w,
        }
    }

    /// Force vector from child to parent coordinates, `Ad⁻ᵀ F = (R f, R τ + p × R f)`:
    /// Definition 7 (the thesis's `_hX̂_i` applied to a force).
    #[inline]
    pub(crate) fn force_to_parent(&self, f: &Wrench) -> Wrench {
        let force = self.r * f.f;
        Wrench {
            f: force,
            tau: self.r * f.tau + self.p.cross(force),
        }
    }

    /// Force vector from parent to child coordinates, `(Rᵀ f, Rᵀ(τ − p × f))`.
    #[cfg(test)]
    pub(crate) fn force_to_child(&self, f: &Wrench) -> Wrench {
        Wrench {
            f: rt_mul(&self.r, f.f),
            tau: rt_mul(&self.r, f.tau - self.p.cross(f.f)),
        }
    }
}

/// A symmetric 6×6 spatial or articulated inertia `[[a, b], [bᵀ, c]]` (linear on top): a twist
/// `(v, ω)` maps to the momentum `(a v + b ω, bᵀ v + c ω)`. `a` and `c` are symmetric.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Sym6 {
    pub a: DMat3,
    pub b: DMat3,
    pub c: DMat3,
}

impl Sym6 {
    pub(crate) const ZERO: Sym6 = Sym6 {
        a: DMat3::ZERO,
        b: DMat3::ZERO,
        c: DMat3::ZERO,
    };

    /// The rigid-body inertia `[[m1, −m ĉ], [m ĉ, I_c − m ĉĉ]]` (Def. 13's isolated inertia,
    /// for a body frame whose origin need not be the centre of mass).
    pub(crate) fn from_inertia(i: &SpatialInertia) -> Sym6 {
        let m6 = i.to_mat6();
        Sym6 {
            a: m6.tl,
            b: m6.tr,
            c: m6.br,
        }
    }

    /// The full 6×6 matrix.
    pub(crate) fn to_mat6(self) -> Mat6 {
        Mat6::from_blocks(self.a, self.b, self.b.transpose(), self.c)
    }

    /// Momentum `M ξ`.
    #[inline]
    pub(crate) fn mul(&self, t: &Twist) -> Wrench {
        Wrench {
            f: self.a * t.v + self.b * t.w,
            tau: rt_mul(&self.b, t.v) + self.c * t.w,
        }
    }

    #[inline]
    pub(crate) fn add_assign(&mut self, o: &Sym6) {
        self.a += o.a;
        self.b += o.b;
        self.c += o.c;
    }

    /// `self − U Uᵀ / D` with `inv_d = 1/D`: the rank-one correction of eqs. (4.28)/(4.33),
    /// `Î^A − Î^A ŝ ŝ' Î^A / (ŝ' Î^A ŝ)`, since `U = Î^A ŝ`.
    #[inline]
    pub(crate) fn minus_outer(&self, u: &Wrench, inv_d: f64) -> Sym6 {
        let uf = u.f * inv_d;
        let ut = u.tau * inv_d;
        Sym6 {
            a: self.a - outer(uf, u.f),
            b: self.b - outer(uf, u.tau),
            c: self.c - outer(ut, u.tau),
        }
    }

    /// The same inertia expressed in the parent frame of `x`: `Ad⁻ᵀ M Ad⁻¹`, i.e. the thesis's
    /// `_hX̂_i M _iX̂_h` of eqs. (4.28)/(4.33).
    ///
    /// With `A' = R a Rᵀ`, `B' = R b Rᵀ`, `C' = R c Rᵀ` and `p̂` the cross matrix of `p`:
    /// `a'' = A'`, `b'' = B' − A'p̂`, `c'' = C' + p̂ b'' + (p̂ B')ᵀ`.
    #[inline]
    pub(crate) fn to_parent(self, x: &Xform) -> Sym6 {
        let a = sandwich(&x.r, &self.a);
        let b = sandwich(&x.r, &self.b);
        let c = sandwich(&x.r, &self.c);
        // A'p̂ = −(p̂A')ᵀ because A' is symmetric.
        let b2 = b + hat_mul(x.p, &a).transpose();
        let c2 = c + hat_mul(x.p, &b2) + hat_mul(x.p, &b).transpose();
        Sym6 { a, b: b2, c: c2 }
    }

    /// Rows of the full matrix.
    fn rows(&self) -> [[f64; 6]; 6] {
        self.to_mat6().to_rows()
    }

    /// Solves `M ξ = h` by Cholesky factorisation (M symmetric positive definite). `None` when a
    /// pivot is at most [`SPD_PIVOT_REL`] times the largest diagonal entry (numerically not
    /// positive definite) or the data is not finite.
    pub(crate) fn solve(&self, h: &Wrench) -> Option<Twist> {
        let mut l = self.rows();
        let scale = (0..6).fold(0.0f64, |m, i| m.max(l[i][i]));
        if !(scale.is_finite() && scale > 0.0) {
            return None;
        }
        // In-place lower Cholesky: l[i][j] for j ≤ i.
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        for j in 0..6 {
            let d = l[j][j] - dot(&l[j][..j], &l[j][..j]);
            if d.is_nan() || d <= SPD_PIVOT_REL * scale {
                return None;
            }
            let d = d.sqrt();
            l[j][j] = d;
            for i in (j + 1)..6 {
                l[i][j] = (l[i][j] - dot(&l[i][..j], &l[j][..j])) / d;
            }
        }
        // Forward substitution L y = h, then back substitution Lᵀ x = y.
        let mut y = h.to_array();
        for i in 0..6 {
            y[i] = (y[i] - dot(&l[i][..i], &y[..i])) / l[i][i];
        }
        for i in (0..6).rev() {
            let s: f64 = ((i + 1)..6).map(|k| l[k][i] * y[k]).sum();
            y[i] = (y[i] - s) / l[i][i];
        }
        Some(Twist::from_array(y))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DQuat;
    use rand::rngs::Xoshiro256PlusPlus;
    use rand::{RngExt, SeedableRng};

    /// Agreement of two evaluations of the same linear map (a few ulp of O(1..10) entries).
    const TIGHT: f64 = 1e-12;

    fn vec3(rng: &mut Xoshiro256PlusPlus, s: f64) -> DVec3 {
        DVec3::new(
            rng.random_range(-s..s),
            rng.random_range(-s..s),
            rng.random_range(-s..s),
        )
    }

    fn xform(rng: &mut Xoshiro256PlusPlus) -> Xform {
        let q = DQuat::from_xyzw(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        )
        .normalize();
        Xform {
            r: DMat3::from_quat(q),
            p: vec3(rng, 2.0),
        }
    }

    #[test]
    fn transforms_agree_with_geom_adjoints() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(601);
        let mut worst = 0.0f64;
        for _ in 0..500 {
            let x = xform(&mut rng);
            let pose = x.to_pose();
            let t = Twist::new(vec3(&mut rng, 3.0), vec3(&mut rng, 3.0));
            let f = Wrench::new(vec3(&mut rng, 3.0), vec3(&mut rng, 3.0));
            let d = |a: Twist, b: Twist| {
                (a.v - b.v)
                    .abs()
                    .max_element()
                    .max((a.w - b.w).abs().max_element())
            };
            let e = |a: Wrench, b: Wrench| {
                (a.f - b.f)
                    .abs()
                    .max_element()
                    .max((a.tau - b.tau).abs().max_element())
            };
            worst = worst.max(d(x.motion_to_parent(&t), pose.transform_twist(&t)));
            worst = worst.max(d(x.motion_to_child(&t), pose.inverse_transform_twist(&t)));
            worst = worst.max(e(x.force_to_parent(&f), pose.transform_wrench(&f)));
            worst = worst.max(e(x.force_to_child(&f), pose.inverse_transform_wrench(&f)));
            // Power is frame-invariant (digest §6 test 2).
            let pw = x.force_to_parent(&f).power(&x.motion_to_parent(&t));
            worst = worst.max((pw - f.power(&t)).abs() / 100.0);
            // Inertia transform equals Ad⁻ᵀ M Ad⁻¹ and equals SpatialInertia::transform.
            let si = SpatialInertia::new(
                rng.random_range(0.5..3.0),
                vec3(&mut rng, 1.0),
                DMat3::from_diagonal(DVec3::new(1.0, 2.0, 2.5)),
            );
            let m = Sym6::from_inertia(&si);
            let moved = m.to_parent(&x).to_mat6();
            let ainv = pose.inverse().adjoint();
            let reference = ainv.transpose() * m.to_mat6() * ainv;
            worst = worst.max(moved.max_abs_diff(&reference) / 100.0);
            let via_geom = Sym6::from_inertia(&si.transform(&pose)).to_mat6();
            worst = worst.max(moved.max_abs_diff(&via_geom) / 100.0);
            // Cholesky solve inverts the product.
            let xi = m.solve(&m.mul(&t)).unwrap();
            worst = worst.max(d(xi, t) / 10.0);
        }
        assert!(worst < TIGHT, "worst {worst:e}");
    }

    #[test]
    fn axis_angle_matches_quaternion() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(602);
        for _ in 0..200 {
            let u = vec3(&mut rng, 1.0).normalize();
            let th = rng.random_range(-7.0..7.0);
            let a = axis_angle(u, th);
            let b = DMat3::from_quat(DQuat::from_axis_angle(u, th));
            for c in 0..3 {
                assert!((a.col(c) - b.col(c)).abs().max_element() < TIGHT);
            }
        }
    }

    #[test]
    fn solve_rejects_singular() {
        let m = Sym6 {
            a: DMat3::IDENTITY,
            b: DMat3::ZERO,
            c: DMat3::from_diagonal(DVec3::new(1.0, 1.0, 0.0)),
        };
        assert!(m.solve(&Wrench::new(DVec3::ONE, DVec3::ONE)).is_none());
        assert!(Sym6::ZERO.solve(&Wrench::ZERO).is_none());
    }
}
