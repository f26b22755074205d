//! The collision matrix of two rigid bodies (eq. 3.4) and the collision frame (thesis §3.2).
//!
//! K is built in world axes from each body's mass, world-frame inertia tensor and contact offset
//! r (contact point minus centre of mass, world axes), then rotated into the collision frame:
//! `K_coll = Qᵀ K_world Q`, where the columns of Q are the frame's axes (t̂₁, t̂₂, n̂) in world
//! coordinates. A fixed body (infinite mass) contributes nothing.

use crate::{CollisionMatrix, ResponseError};
use glam::{DMat3, DVec3};

/// Largest |I_ij − I_ji| accepted in a world inertia tensor, relative to its largest entry;
/// dimensionless, default `1e-9` (tensors rotated as R·I·Rᵀ are symmetric to rounding).
pub const INERTIA_SYMMETRY_REL: f64 = 1e-9;

/// The mass properties of one body as the collision sees them (thesis §3.1: constant during
/// the collision).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Body {
    /// Infinite mass and inertia (the ground, a wall): receives the impulse without moving and
    /// contributes nothing to K.
    Fixed,
    /// A free rigid body.
    Moving {
        /// 1/m.
        inverse_mass: f64,
        /// I⁻¹ of the world-frame inertia tensor about the centre of mass.
        inverse_inertia: DMat3,
    },
}

impl Body {
    /// A free body of mass `mass` whose inertia tensor about its centre of mass, in world axes
    /// (R·I_body·Rᵀ), is `inertia`.
    ///
    /// # Errors
    /// [`ResponseError::InvalidMass`] unless `mass` is finite and > 0;
    /// [`ResponseError::InvalidInertia`] unless `inertia` is finite, symmetric (to
    /// [`INERTIA_SYMMETRY_REL`]) and positive definite.
    pub fn moving(mass: f64, inertia: DMat3) -> Result<Self, ResponseError> {
        if !(mass.is_finite() && mass > 0.0) {
            return Err(ResponseError::InvalidMass { mass });
        }
        if !inertia.is_finite() {
            return Err(ResponseError::InvalidInertia {
                reason: "not finite",
            });
        }
        let scale = max_abs(&inertia);
        if max_asymmetry(&inertia) > INERTIA_SYMMETRY_REL * scale {
            return Err(ResponseError::InvalidInertia {
                reason: "not symmetric",
            });
        }
        let i = symmetrize(&inertia);
        // Sylvester's criterion: all leading principal minors positive.
        let m1 = i.x_axis.x;
        let m2 = i.x_axis.x * i.y_axis.y - i.y_axis.x * i.x_axis.y;
        let m3 = i.determinant();
        if !(m1 > 0.0 && m2 > 0.0 && m3 > 0.0) {
            return Err(ResponseError::InvalidInertia {
                reason: "not positive definite",
            });
        }
        Ok(Body::Moving {
            inverse_mass: 1.0 / mass,
            inverse_inertia: symmetrize(&i.inverse()),
        })
    }

    /// 1/m (zero for a fixed body).
    pub fn inverse_mass(&self) -> f64 {
        match self {
            Body::Fixed => 0.0,
            Body::Moving { inverse_mass, .. } => *inverse_mass,
        }
    }

    /// I⁻¹ in world axes (zero for a fixed body).
    pub fn inverse_inertia(&self) -> DMat3 {
        match self {
            Body::Fixed => DMat3::ZERO,
            Body::Moving {
                inverse_inertia, ..
            } => *inverse_inertia,
        }
    }

    /// This body's term of eq. (3.4), `(1/m)·1 − r̃·I⁻¹·r̃`: the change of velocity of the body
    /// point at offset `r` per unit impulse applied there (world axes).
    pub fn point_compliance(&self, r: DVec3) -> DMat3 {
        match self {
            Body::Fixed => DMat3::ZERO,
            Body::Moving {
                inverse_mass,
                inverse_inertia,
            } => {
                let rt = cross_matrix(r);
                DMat3::from_diagonal(DVec3::splat(*inverse_mass)) - rt * *inverse_inertia * rt
            }
        }
    }

    /// The change (Δv, Δω) of the body's centre-of-mass and angular velocity when impulse `p`
    /// (world axes) acts at offset `r`: eqs. (3.1), (3.2), `Δv = p/m`, `Δω = I⁻¹(r × p)`. Zero
    /// for a fixed body. Body 1 of a collision receives +p, body 2 receives −p.
    pub fn velocity_change(&self, r: DVec3, p: DVec3) -> (DVec3, DVec3) {
        match self {
            Body::Fixed => (DVec3::ZERO, DVec3::ZERO),
            Body::Moving {
                inverse_mass,
                inverse_inertia,
            } => (p * *inverse_mass, *inverse_inertia * r.cross(p)),
        }
    }
}

/// The cross-product matrix ã of `a` (thesis App. A.2): `ã·b = a × b`, `ãᵀ = −ã`.
pub fn cross_matrix(a: DVec3) -> DMat3 {
    // Columns of [[0, −a_z, a_y], [a_z, 0, −a_x], [−a_y, a_x, 0]].
    DMat3::from_cols(
        DVec3::new(0.0, a.z, -a.y),
        DVec3::new(-a.z, 0.0, a.x),
        DVec3::new(a.y, -a.x, 0.0),
    )
}

/// The collision matrix in **world** axes, eq. (3.4):
/// `K = (1/m₁ + 1/m₂)·1 − (r̃₁·I₁⁻¹·r̃₁ + r̃₂·I₂⁻¹·r̃₂)`, with `r_i` the contact point minus body i's
/// centre of mass (world axes). Δu = K·p, eq. (3.5). Rotate it into the collision frame with
/// [`ContactFrame::matrix_to_contact`], or use [`CollisionMatrix::rigid`] which also validates.
pub fn collision_matrix_world(body1: &Body, r1: DVec3, body2: &Body, r2: DVec3) -> DMat3 {
    body1.point_compliance(r1) + body2.point_compliance(r2)
}

/// The velocity of body 1's contact point relative to body 2's, `u = (v₁ + ω₁ × r₁) − (v₂ +
/// ω₂ × r₂)` (thesis §3.2), in the axes the inputs are given in.
pub fn relative_contact_velocity(
    v1: DVec3,
    omega1: DVec3,
    r1: DVec3,
    v2: DVec3,
    omega2: DVec3,
    r2: DVec3,
) -> DVec3 {
    (v1 + omega1.cross(r1)) - (v2 + omega2.cross(r2))
}

/// The collision frame F_coll (thesis §3.2): z along the contact normal, pointing from body 2
/// towards body 1; x and y an orthonormal right-handed completion chosen deterministically.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactFrame {
    /// Columns t̂₁, t̂₂, n̂ in world coordinates (the matrix Q).
    axes: DMat3,
}

impl ContactFrame {
    /// The frame whose z axis is `normal` (normalised; pointing from body 2 to body 1).
    ///
    /// Tangent choice (deterministic, continuous except where the choice of axis switches):
    /// `t̂₁ = normalize(n̂ × a)` where `a` is the world axis least aligned with n̂ (ties go to x,
    /// then y), and `t̂₂ = n̂ × t̂₁`, so that t̂₁ × t̂₂ = n̂.
    ///
    /// # Errors
    /// [`ResponseError::InvalidNormal`] if `normal` is zero or not finite.
    pub fn from_normal(normal: DVec3) -> Result<Self, ResponseError> {
        let len = normal.length();
        if !(normal.is_finite() && len > 0.0 && len.is_finite()) {
            return Err(ResponseError::InvalidNormal {
                normal: normal.to_array(),
            });
        }
        let n = normal / len;
        let a = n.abs();
        let axis = if a.x <= a.y && a.x <= a.z {
            DVec3::X
        } else if a.y <= a.z {
            DVec3::Y
        } else {
            DVec3::Z
        };
        let t1 = n.cross(axis).normalize();
        let t2 = n.cross(t1);
        Ok(Self {
            axes: DMat3::from_cols(t1, t2, n),
        })
    }

    /// The frame with the given orthonormal axes (columns t̂₁, t̂₂, n̂ in world coordinates).
    /// The caller guarantees orthonormality and right-handedness.
    pub fn from_axes(axes: DMat3) -> Self {
        Self { axes }
    }

    /// Q: columns t̂₁, t̂₂, n̂ in world coordinates.
    pub fn axes(&self) -> DMat3 {
        self.axes
    }

    /// The unit normal n̂ (world), pointing from body 2 to body 1.
    pub fn normal(&self) -> DVec3 {
        self.axes.z_axis
    }

    /// A world vector in collision-frame coordinates, `Qᵀ·v`.
    pub fn to_contact(&self, v: DVec3) -> DVec3 {
        self.axes.transpose() * v
    }

    /// A collision-frame vector in world coordinates, `Q·v`.
    pub fn to_world(&self, v: DVec3) -> DVec3 {
        self.axes * v
    }

    /// A world-axes tensor (e.g. K from [`collision_matrix_world`]) in collision-frame axes,
    /// `Qᵀ·M·Q`.
    pub fn matrix_to_contact(&self, m: DMat3) -> DMat3 {
        self.axes.transpose() * m * self.axes
    }
}

impl CollisionMatrix {
    /// K of two rigid bodies in contact, eq. (3.4): built in world axes from the bodies and the
    /// offsets `r1`, `r2` (contact point minus centre of mass, world axes), rotated into
    /// `frame`, then validated as in [`CollisionMatrix::new`].
    ///
    /// # Errors
    /// As [`CollisionMatrix::new`]; in particular [`ResponseError::NormalUnreachable`] if both
    /// bodies are fixed.
    pub fn rigid(
        body1: &Body,
        r1: DVec3,
        body2: &Body,
        r2: DVec3,
        frame: &ContactFrame,
    ) -> Result<Self, ResponseError> {
        if !(r1.is_finite() && r2.is_finite()) {
            return Err(ResponseError::NonFinite {
                what: "contact offset",
            });
        }
        let k_world = collision_matrix_world(body1, r1, body2, r2);
        CollisionMatrix::new(symmetrize(&frame.matrix_to_contact(k_world)))
    }
}

/// (M + Mᵀ)/2.
pub(crate) fn symmetrize(m: &DMat3) -> DMat3 {
    (*m + m.transpose()) * 0.5
}

/// max |M_ij|.
pub(crate) fn max_abs(m: &DMat3) -> f64 {
    m.to_cols_array().iter().fold(0.0f64, |a, x| a.max(x.abs()))
}

/// max |M_ij − M_ji|.
pub(crate) fn max_asymmetry(m: &DMat3) -> f64 {
    max_abs(&(*m - m.transpose()))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use rand::rngs::Xoshiro256PlusPlus;
    use rand::{RngExt, SeedableRng};

    fn rel(a: DMat3, b: DMat3) -> f64 {
        max_abs(&(a - b)) / max_abs(&b).max(f64::MIN_POSITIVE)
    }

    /// A random unit vector (rejection sampling in the unit ball).
    pub(crate) fn unit(rng: &mut Xoshiro256PlusPlus) -> DVec3 {
        loop {
            let v = DVec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            );
            let l = v.length();
            if l > 0.1 && l < 1.0 {
                return v / l;
            }
        }
    }

    fn rotation(rng: &mut Xoshiro256PlusPlus) -> DMat3 {
        let axis = unit(rng);
        DMat3::from_axis_angle(axis, rng.random_range(0.0..std::f64::consts::TAU))
    }

    /// A random body with principal moments of a box of random half-sizes in [0.1, 1] (moment
    /// ratios up to 1:100), random mass and orientation: (mass, world inertia).
    pub(crate) fn random_body(rng: &mut Xoshiro256PlusPlus) -> (f64, DMat3) {
        let m = 10f64.powf(rng.random_range(-2.0..2.0));
        let h = DVec3::new(
            rng.random_range(0.1..1.0),
            rng.random_range(0.1..1.0),
            rng.random_range(0.1..1.0),
        );
        let d = DVec3::new(
            h.y * h.y + h.z * h.z,
            h.x * h.x + h.z * h.z,
            h.x * h.x + h.y * h.y,
        ) * (m / 3.0);
        let r = rotation(rng);
        (m, r * DMat3::from_diagonal(d) * r.transpose())
    }

    #[test]
    fn frame_is_right_handed_orthonormal_and_deterministic() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(31);
        for i in 0..1000 {
            let n = if i < 6 {
                [
                    DVec3::X,
                    DVec3::Y,
                    DVec3::Z,
                    -DVec3::X,
                    -DVec3::Y,
                    -DVec3::Z,
                ][i]
            } else {
                unit(&mut rng) * rng.random_range(0.01..100.0)
            };
            let f = ContactFrame::from_normal(n).unwrap();
            let q = f.axes();
            let qtq = q.transpose() * q;
            assert!(rel(qtq, DMat3::IDENTITY) < 1e-15, "{qtq}");
            assert!((q.determinant() - 1.0).abs() < 1e-15);
            assert!((f.normal() - n.normalize()).length() < 1e-15);
            assert_eq!(f, ContactFrame::from_normal(n).unwrap());
            let v = unit(&mut rng);
            assert!((f.to_world(f.to_contact(v)) - v).length() < 1e-15);
        }
        for bad in [
            DVec3::ZERO,
            DVec3::new(f64::NAN, 0.0, 1.0),
            DVec3::splat(f64::INFINITY),
        ] {
            assert!(matches!(
                ContactFrame::from_normal(bad),
                Err(ResponseError::InvalidNormal { .. })
            ));
        }
    }

    /// Digest test 1 (Theorem 6): K is symmetric positive definite for random bodies, random
    /// rotations and offsets, with and without a fixed body.
    #[test]
    fn rigid_k_is_symmetric_positive_definite() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(32);
        for i in 0..2000 {
            let (m1, i1) = random_body(&mut rng);
            let (m2, i2) = random_body(&mut rng);
            let b1 = Body::moving(m1, i1).unwrap();
            let b2 = if i % 4 == 0 {
                Body::Fixed
            } else {
                Body::moving(m2, i2).unwrap()
            };
            let (r1, r2) = (unit(&mut rng) * 1.5, unit(&mut rng) * 1.5);
            let k = collision_matrix_world(&b1, r1, &b2, r2);
            assert!(max_asymmetry(&k) <= 1e-14 * max_abs(&k));
            // Eigenvalues by the independent check xᵀKx > 0 on random directions plus the
            // Sylvester minors.
            let m1_ = k.x_axis.x;
            let m2_ = k.x_axis.x * k.y_axis.y - k.y_axis.x * k.x_axis.y;
            assert!(m1_ > 0.0 && m2_ > 0.0 && k.determinant() > 0.0, "{k}");
            // Lower bound: K ⪰ (1/m₁ + 1/m₂)·1 (Theorem 6 proof).
            let lower = b1.inverse_mass() + b2.inverse_mass();
            for _ in 0..5 {
                let x = unit(&mut rng);
                assert!(x.dot(k * x) >= lower * (1.0 - 1e-12));
            }
            let frame = ContactFrame::from_normal(unit(&mut rng)).unwrap();
            let cm = CollisionMatrix::rigid(&b1, r1, &b2, r2, &frame).unwrap();
            assert_eq!(cm.rank(), 3);
        }
        // Two fixed bodies: nothing can move.
        let f = ContactFrame::from_normal(DVec3::Z).unwrap();
        assert!(matches!(
            CollisionMatrix::rigid(&Body::Fixed, DVec3::X, &Body::Fixed, DVec3::Y, &f),
            Err(ResponseError::NormalUnreachable { .. })
        ));
    }

    /// Digest test 2 (eq. 3.5): applying an impulse p to two bodies by (3.1)/(3.2) changes the
    /// relative contact velocity by exactly K·p.
    #[test]
    fn delta_u_equals_k_p() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(33);
        for i in 0..2000 {
            let (m1, i1) = random_body(&mut rng);
            let (m2, i2) = random_body(&mut rng);
            let fixed2 = i % 5 == 0;
            let (r1, r2) = (unit(&mut rng) * 1.3, unit(&mut rng) * 0.7);
            let (mut v1, mut w1) = (unit(&mut rng), unit(&mut rng));
            let (mut v2, mut w2) = if fixed2 {
                (DVec3::ZERO, DVec3::ZERO)
            } else {
                (unit(&mut rng), unit(&mut rng))
            };
            let u_before = relative_contact_velocity(v1, w1, r1, v2, w2, r2);
            let p = unit(&mut rng) * rng.random_range(0.01..10.0);
            // Independent application: Newton–Euler with the inertia inverted here.
            v1 += p / m1;
            w1 += i1.inverse() * r1.cross(p);
            if !fixed2 {
                v2 += -p / m2;
                w2 += i2.inverse() * r2.cross(-p);
            }
            let u_after = relative_contact_velocity(v1, w1, r1, v2, w2, r2);
            let b1 = Body::moving(m1, i1).unwrap();
            let b2 = if fixed2 {
                Body::Fixed
            } else {
                Body::moving(m2, i2).unwrap()
            };
            let k = collision_matrix_world(&b1, r1, &b2, r2);
            let du = u_after - u_before;
            let scale = (k * p).length() + u_before.length();
            assert!((du - k * p).length() <= 1e-12 * scale, "{du} vs {}", k * p);
        }
    }

    /// Digest test 3: solid sphere (m, R) on a fixed plane gives diag(3.5/m, 3.5/m, 1/m); two
    /// identical spheres head-on give diag(7/m, 7/m, 2/m).
    #[test]
    fn sphere_collision_matrices() {
        for &(m, r) in &[(2.0, 0.5), (0.3, 7.0), (1e4, 1e-2)] {
            let i = DMat3::from_diagonal(DVec3::splat(0.4 * m * r * r));
            let b = Body::moving(m, i).unwrap();
            let f = ContactFrame::from_normal(DVec3::Z).unwrap();
            let cm =
                CollisionMatrix::rigid(&b, DVec3::new(0.0, 0.0, -r), &Body::Fixed, DVec3::ZERO, &f)
                    .unwrap();
            let want = DMat3::from_diagonal(DVec3::new(3.5 / m, 3.5 / m, 1.0 / m));
            assert!(rel(cm.k(), want) < 1e-14, "{}", cm.k());
            let cm2 = CollisionMatrix::rigid(
                &b,
                DVec3::new(0.0, 0.0, -r),
                &b,
                DVec3::new(0.0, 0.0, r),
                &f,
            )
            .unwrap();
            let want2 = DMat3::from_diagonal(DVec3::new(7.0 / m, 7.0 / m, 2.0 / m));
            assert!(rel(cm2.k(), want2) < 1e-14, "{}", cm2.k());
        }
    }

    /// Digest test 4: K built in world axes and rotated (Qᵀ·K·Q) equals K built directly from
    /// offsets and inertias expressed in the collision frame.
    #[test]
    fn frame_invariance() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(34);
        for _ in 0..1000 {
            let (m1, i1) = random_body(&mut rng);
            let (m2, i2) = random_body(&mut rng);
            let (r1, r2) = (unit(&mut rng), unit(&mut rng) * 2.0);
            let frame = ContactFrame::from_normal(unit(&mut rng)).unwrap();
            let q = frame.axes();
            let rotated = frame.matrix_to_contact(collision_matrix_world(
                &Body::moving(m1, i1).unwrap(),
                r1,
                &Body::moving(m2, i2).unwrap(),
                r2,
            ));
            let direct = collision_matrix_world(
                &Body::moving(m1, q.transpose() * i1 * q).unwrap(),
                q.transpose() * r1,
                &Body::moving(m2, q.transpose() * i2 * q).unwrap(),
                q.transpose() * r2,
            );
            assert!(rel(rotated, direct) < 1e-12);
        }
    }

    #[test]
    fn bad_bodies_are_refused() {
        assert!(matches!(
            Body::moving(0.0, DMat3::IDENTITY),
            Err(ResponseError::InvalidMass { .. })
        ));
        assert!(matches!(
            Body::moving(f64::NAN, DMat3::IDENTITY),
            Err(ResponseError::InvalidMass { .. })
        ));
        assert!(matches!(
            Body::moving(1.0, DMat3::from_diagonal(DVec3::new(1.0, -1.0, 1.0))),
            Err(ResponseError::InvalidInertia { .. })
        ));
        let mut a = DMat3::IDENTITY;
        a.x_axis.y = 0.5;
        assert!(matches!(
            Body::moving(1.0, a),
            Err(ResponseError::InvalidInertia { .. })
        ));
        let mut n = DMat3::IDENTITY;
        n.x_axis.x = f64::INFINITY;
        assert!(matches!(
            Body::moving(1.0, n),
            Err(ResponseError::InvalidInertia { .. })
        ));
    }
}
