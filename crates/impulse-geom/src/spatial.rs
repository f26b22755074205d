//! Rigid-body spatial inertia in linear-top (MLS) packing.
//!
//! A [`SpatialInertia`] maps a twist ξ = (v, ω) to the body's momentum h = (linear, angular),
//! a [`Wrench`]-typed quantity, both expressed in the same frame F and both taken at F's origin.
//! It is stored compactly as (mass, centre of mass, rotational inertia about the COM); the full
//! 6×6 form, for Featherstone's articulated-body algorithm and other dense uses, is
//! [`SpatialInertia::to_mat6`]. Featherstone (angular on top) writes the same matrix as
//! `[[I_c + m c̃c̃ᵀ, m c̃], [m c̃ᵀ, m 1]]`; here the blocks are swapped.

use core::ops::Add;

use glam::{DMat3, DVec3};

use crate::pose::Pose;
use crate::se3::{Mat6, Twist, Wrench, hat};

/// Inertia of a rigid body expressed in some frame F.
///
/// * `mass` — total mass m (kg); physical bodies have m ≥ 0.
/// * `com` — centre of mass c in F's coordinates (m).
/// * `inertia_com` — rotational inertia I_c about the COM, in F's axes (kg·m²); symmetric
///   (positive semi-definite for physical bodies).
///
/// A twist ξ = (v, ω) in F has v = velocity of the body point at F's origin, so the COM moves
/// at `v + ω × c`, and the momentum about F's origin is
/// `h = (m(v + ω × c), I_c ω + c × m(v + ω × c))`.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct SpatialInertia {
    /// Mass m (kg).
    pub mass: f64,
    /// Centre of mass c in F's coordinates (m).
    pub com: DVec3,
    /// Rotational inertia I_c about the COM, F's axes (kg·m²).
    pub inertia_com: DMat3,
}

impl SpatialInertia {
    /// No mass and no inertia (the neutral element of `+`).
    pub const ZERO: SpatialInertia = SpatialInertia {
        mass: 0.0,
        com: DVec3::ZERO,
        inertia_com: DMat3::ZERO,
    };

    /// Inertia from mass (kg), centre of mass in F (m) and rotational inertia about the COM in
    /// F's axes (kg·m², symmetric).
    #[must_use]
    pub const fn new(mass: f64, com: DVec3, inertia_com: DMat3) -> Self {
        SpatialInertia {
            mass,
            com,
            inertia_com,
        }
    }

    /// A point mass `m` (kg) located at `at` (m, in F).
    #[must_use]
    pub const fn point_mass(m: f64, at: DVec3) -> Self {
        SpatialInertia {
            mass: m,
            com: at,
            inertia_com: DMat3::ZERO,
        }
    }

    /// Rotational inertia about F's origin (kg·m²), parallel-axis theorem:
    /// `I_o = I_c − m ĉĉ = I_c + m(|c|²·1 − c cᵀ)`.
    #[must_use]
    pub fn inertia_about_origin(&self) -> DMat3 {
        let c = hat(self.com);
        self.inertia_com - c * c * self.mass
    }

    /// The 6×6 matrix `M = [[m·1, −m ĉ], [m ĉ, I_c − m ĉĉ]]` mapping a twist to the momentum,
    /// `h = M ξ`, both in F at F's origin (linear on top).
    ///
    /// Derivation: the COM velocity is `v + ω × c = v − ĉω`, so the linear momentum is
    /// `m v − m ĉ ω`; the angular momentum about F's origin is
    /// `I_c ω + c × m(v − ĉω) = m ĉ v + (I_c − m ĉĉ) ω`. M is symmetric (ĉᵀ = −ĉ), and positive
    /// semi-definite for physical bodies.
    #[must_use]
    pub fn to_mat6(&self) -> Mat6 {
        let c = hat(self.com);
        let mc = c * self.mass;
        Mat6::from_blocks(
            DMat3::from_diagonal(DVec3::splat(self.mass)),
            -mc,
            mc,
            self.inertia_about_origin(),
        )
    }

    /// Momentum `h = M ξ` of the body moving with twist `xi` (both in F, taken at F's origin):
    /// linear `m(v + ω × c)` (kg·m/s), angular `I_c ω + c × m(v + ω × c)` (kg·m²/s). Computed
    /// directly, without the 6×6 matrix.
    #[must_use]
    pub fn mul_twist(&self, xi: &Twist) -> Wrench {
        let lin = (xi.v + xi.w.cross(self.com)) * self.mass;
        Wrench {
            f: lin,
            tau: self.inertia_com * xi.w + self.com.cross(lin),
        }
    }

    /// Kinetic energy `½ ξᵀMξ = ½(m|v + ω × c|² + ωᵀ I_c ω)` (J) of the body moving with `xi`.
    #[must_use]
    pub fn kinetic_energy(&self, xi: &Twist) -> f64 {
        let vc = xi.v + xi.w.cross(self.com);
        0.5 * (self.mass * vc.length_squared() + xi.w.dot(self.inertia_com * xi.w))
    }

    /// Re-expresses an inertia given in frame B in the parent frame A of `pose` (which maps B to
    /// A): `c' = R c + p`, `I_c' = R I_c Rᵀ`, mass unchanged. As 6×6 matrices this is
    /// `M_A = Ad⁻ᵀ M_B Ad⁻¹` (momentum transforms as a wrench, twist as a twist).
    #[must_use]
    pub fn transform(&self, pose: &Pose) -> SpatialInertia {
        let r = pose.rotation_matrix();
        SpatialInertia {
            mass: self.mass,
            com: pose.transform_point(self.com),
            inertia_com: r * self.inertia_com * r.transpose(),
        }
    }
}

impl Add for SpatialInertia {
    type Output = SpatialInertia;

    /// Combined inertia of two bodies rigidly joined, both expressed in the same frame: masses
    /// add, the COM is the mass-weighted mean, and each body's rotational inertia is moved to
    /// the new COM by the parallel-axis theorem (`I_c = Σ I_i − m_i d̂_i d̂_i`, `d_i = c_i − c`).
    /// The result's 6×6 matrix is the sum of the two. If the total mass is zero, the COM is the
    /// midpoint of the two (any point is valid for a massless body) and the inertias add.
    fn add(self, o: SpatialInertia) -> SpatialInertia {
        let mass = self.mass + o.mass;
        if mass == 0.0 {
            return SpatialInertia {
                mass,
                com: (self.com + o.com) * 0.5,
                inertia_com: self.inertia_com + o.inertia_com,
            };
        }
        let com = (self.com * self.mass + o.com * o.mass) / mass;
        let d1 = hat(self.com - com);
        let d2 = hat(o.com - com);
        SpatialInertia {
            mass,
            com,
            inertia_com: self.inertia_com + o.inertia_com - d1 * d1 * self.mass - d2 * d2 * o.mass,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DQuat;
    use rand::rngs::Xoshiro256PlusPlus;
    use rand::{RngExt, SeedableRng};

    /// Number of random trials (each with a fresh point cloud, twist and pose).
    const TRIALS: usize = 2000;
    /// Point masses per cloud.
    const POINTS: usize = 20;
    /// Momentum, energy and inertia comparisons against point-cloud sums, relative to the
    /// magnitude of the summed terms (`Σ mᵢ(1 + |rᵢ|)²·(1 + |ξ|)` for momenta and energy).
    const CLOUD_TOL: f64 = 1e-13;
    /// Comparisons of two evaluations of the same formula (6×6 vs direct), relative as above.
    const TIGHT_TOL: f64 = 1e-14;

    fn vec3(rng: &mut Xoshiro256PlusPlus, s: f64) -> DVec3 {
        DVec3::new(
            rng.random_range(-s..s),
            rng.random_range(-s..s),
            rng.random_range(-s..s),
        )
    }

    struct Cloud {
        m: Vec<f64>,
        r: Vec<DVec3>,
    }

    fn cloud(rng: &mut Xoshiro256PlusPlus) -> Cloud {
        let offset = vec3(rng, 3.0);
        let m = (0..POINTS).map(|_| rng.random_range(0.1..2.0)).collect();
        let r = (0..POINTS).map(|_| offset + vec3(rng, 1.5)).collect();
        Cloud { m, r }
    }

    /// Brute-force inertia of a cloud from its definition: m = Σmᵢ, c = Σmᵢrᵢ/m,
    /// I_c = Σ mᵢ(|dᵢ|²·1 − dᵢdᵢᵀ), dᵢ = rᵢ − c.
    fn cloud_inertia(c: &Cloud) -> SpatialInertia {
        let mass: f64 = c.m.iter().sum();
        let com = c.m.iter().zip(&c.r).map(|(m, r)| *r * *m).sum::<DVec3>() / mass;
        let mut i = DMat3::ZERO;
        for (m, r) in c.m.iter().zip(&c.r) {
            let d = *r - com;
            i += (DMat3::from_diagonal(DVec3::splat(d.length_squared()))
                - DMat3::from_cols(d * d.x, d * d.y, d * d.z))
                * *m;
        }
        SpatialInertia::new(mass, com, i)
    }

    /// Brute-force momentum (Σ mᵢvᵢ, Σ rᵢ × mᵢvᵢ) and kinetic energy Σ ½mᵢ|vᵢ|² of a cloud,
    /// vᵢ = v + ω × rᵢ.
    fn cloud_momentum(c: &Cloud, xi: &Twist) -> (Wrench, f64) {
        let mut h = Wrench::ZERO;
        let mut ke = 0.0;
        for (m, r) in c.m.iter().zip(&c.r) {
            let vi = xi.v + xi.w.cross(*r);
            h += Wrench::new(vi * *m, r.cross(vi * *m));
            ke += 0.5 * *m * vi.length_squared();
        }
        (h, ke)
    }

    /// Scale of the summed terms: Σ mᵢ(1 + |rᵢ|)²·(1 + |ξ|)².
    fn cloud_scale(c: &Cloud, xi: &Twist) -> f64 {
        let s: f64 =
            c.m.iter()
                .zip(&c.r)
                .map(|(m, r)| m * (1.0 + r.length()).powi(2))
                .sum();
        s * (1.0 + xi.v.length() + xi.w.length()).powi(2)
    }

    fn wrench_diff(a: &Wrench, b: &Wrench) -> f64 {
        (a.f - b.f)
            .abs()
            .max_element()
            .max((a.tau - b.tau).abs().max_element())
    }

    fn mat3_diff(a: &DMat3, b: &DMat3) -> f64 {
        (0..3)
            .map(|i| (a.col(i) - b.col(i)).abs().max_element())
            .fold(0.0, f64::max)
    }

    fn inertia_diff(a: &SpatialInertia, b: &SpatialInertia, scale: f64) -> f64 {
        ((a.mass - b.mass).abs() / scale)
            .max((a.com - b.com).abs().max_element() / (1.0 + b.com.length()))
            .max(mat3_diff(&a.inertia_com, &b.inertia_com) / scale)
    }

    fn random_pose(rng: &mut Xoshiro256PlusPlus) -> Pose {
        let q = DQuat::from_xyzw(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        );
        Pose::new(q, vec3(rng, 5.0))
    }

    #[test]
    fn inertia_against_point_clouds() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(21);
        let (mut e_mom, mut e_ke, mut e_mat, mut e_sym) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        let (mut e_tf, mut e_tf6, mut e_add) = (0.0f64, 0.0f64, 0.0f64);
        for _ in 0..TRIALS {
            let a = cloud(&mut rng);
            let ia = cloud_inertia(&a);
            let xi = Twist::new(vec3(&mut rng, 3.0), vec3(&mut rng, 3.0));
            let scale = cloud_scale(&a, &xi);

            // Momentum and kinetic energy against the point sums.
            let (h, ke) = cloud_momentum(&a, &xi);
            e_mom = e_mom.max(wrench_diff(&ia.mul_twist(&xi), &h) / scale);
            e_ke = e_ke.max((ia.kinetic_energy(&xi) - ke).abs() / scale);

            // 6×6 form: symmetric, same product, same energy, same origin inertia.
            let m6 = ia.to_mat6();
            e_sym = e_sym.max(m6.max_abs_diff(&m6.transpose()));
            e_mat = e_mat.max(wrench_diff(&m6.inertia_mul(&xi), &ia.mul_twist(&xi)) / scale);
            e_mat = e_mat
                .max((0.5 * m6.inertia_mul(&xi).power(&xi) - ia.kinetic_energy(&xi)).abs() / scale);
            e_mat = e_mat.max(mat3_diff(&m6.br, &ia.inertia_about_origin()) / scale);

            // transform equals transforming the points; and equals Ad⁻ᵀ M Ad⁻¹.
            let g = random_pose(&mut rng);
            let moved = Cloud {
                m: a.m.clone(),
                r: a.r.iter().map(|r| g.transform_point(*r)).collect(),
            };
            let it = ia.transform(&g);
            let mscale = cloud_scale(&moved, &Twist::ZERO);
            e_tf = e_tf.max(inertia_diff(&it, &cloud_inertia(&moved), mscale));
            let xi_a = g.transform_twist(&xi);
            let (h_a, ke_a) = cloud_momentum(&moved, &xi_a);
            let s_a = cloud_scale(&moved, &xi_a);
            e_tf = e_tf.max(wrench_diff(&it.mul_twist(&xi_a), &h_a) / s_a);
            e_tf = e_tf.max((it.kinetic_energy(&xi_a) - ke_a).abs() / s_a);
            let ginv = g.inverse().adjoint();
            let m_a = ginv.transpose() * m6 * ginv;
            e_tf6 = e_tf6.max(m_a.max_abs_diff(&it.to_mat6()) / mscale);

            // Add of two clouds equals the union; folding point masses rebuilds a cloud.
            let b = cloud(&mut rng);
            let ib = cloud_inertia(&b);
            let union = Cloud {
                m: a.m.iter().chain(&b.m).copied().collect(),
                r: a.r.iter().chain(&b.r).copied().collect(),
            };
            let iu = cloud_inertia(&union);
            let uscale = cloud_scale(&union, &Twist::ZERO);
            e_add = e_add.max(inertia_diff(&(ia + ib), &iu, uscale));
            let (hu, keu) = cloud_momentum(&union, &xi);
            let us = cloud_scale(&union, &xi);
            e_add = e_add.max(wrench_diff(&(ia + ib).mul_twist(&xi), &hu) / us);
            e_add = e_add.max(((ia + ib).kinetic_energy(&xi) - keu).abs() / us);
            e_add = e_add.max(((ia + ib).to_mat6()).max_abs_diff(&(m6 + ib.to_mat6())) / uscale);
            let folded =
                a.m.iter()
                    .zip(&a.r)
                    .fold(SpatialInertia::ZERO, |acc, (m, r)| {
                        acc + SpatialInertia::point_mass(*m, *r)
                    });
            e_add = e_add.max(inertia_diff(&folded, &ia, cloud_scale(&a, &Twist::ZERO)));
        }
        println!("spatial: momentum vs cloud {e_mom:.3e}, energy {e_ke:.3e}");
        println!("spatial: to_mat6 vs direct {e_mat:.3e}, asymmetry {e_sym:.3e}");
        println!("spatial: transform vs moved cloud {e_tf:.3e}, vs Ad⁻ᵀMAd⁻¹ {e_tf6:.3e}");
        println!("spatial: add vs union cloud {e_add:.3e}");
        assert!(e_mom <= CLOUD_TOL && e_ke <= CLOUD_TOL);
        assert!(e_sym == 0.0 && e_mat <= TIGHT_TOL);
        assert!(e_tf <= CLOUD_TOL && e_tf6 <= CLOUD_TOL);
        assert!(e_add <= CLOUD_TOL);
    }

    #[test]
    fn zero_mass_and_identities() {
        let z = SpatialInertia::ZERO + SpatialInertia::ZERO;
        assert_eq!(z, SpatialInertia::ZERO);
        let massless = SpatialInertia::new(0.0, DVec3::X, DMat3::IDENTITY)
            + SpatialInertia::new(0.0, DVec3::Y, DMat3::IDENTITY * 2.0);
        assert!(massless.com.is_finite() && massless.inertia_com.is_finite());
        assert_eq!(massless.mass, 0.0);
        assert_eq!(massless.inertia_com, DMat3::IDENTITY * 3.0);
        let p = SpatialInertia::point_mass(2.0, DVec3::new(1.0, 2.0, 3.0));
        let sum = p + SpatialInertia::ZERO;
        assert_eq!(sum.mass, 2.0);
        assert!((sum.com - p.com).abs().max_element() <= 4.0 * f64::EPSILON);
        assert_eq!(p.transform(&Pose::IDENTITY), p);
        // A point mass about the origin: I_o = m(|c|²1 − ccᵀ).
        let c = p.com;
        let expected = (DMat3::from_diagonal(DVec3::splat(c.length_squared()))
            - DMat3::from_cols(c * c.x, c * c.y, c * c.z))
            * 2.0;
        assert!(mat3_diff(&p.inertia_about_origin(), &expected) <= 16.0 * f64::EPSILON);
    }
}
