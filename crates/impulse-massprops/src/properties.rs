//! Mass, centre of mass and inertia tensor (thesis §6.1), and the principal frame.

use faer::{Mat, Side};
use glam::{DMat3, DVec3};
use impulse_geom::{ConvexPolyhedron, PolyMesh, Pose};

use crate::integrals::VolumeIntegrals;
use crate::{MassError, tol};

/// The mass distribution of a rigid body: ten numbers (thesis §6.1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MassProperties {
    /// Total mass (> 0 for a solid body).
    pub mass: f64,
    /// Centre of mass, in the reference frame the geometry was given in.
    pub com: DVec3,
    /// Inertia tensor about the centre of mass, with the reference frame's axes: the
    /// symmetric matrix `[[I_xx, −I_xy, −I_zx], [−I_xy, I_yy, −I_yz], [−I_zx, −I_yz, I_zz]]`
    /// (thesis §6.1; mass × length²).
    pub inertia: DMat3,
}

/// The principal frame of a body: the rotation that diagonalises its inertia tensor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrincipalFrame {
    /// Principal moments of inertia about the centre of mass, in non-decreasing order.
    pub moments: DVec3,
    /// Rotation R whose columns are the principal axes (unit, in reference coordinates),
    /// matching `moments`, with det R = +1, so that `Rᵀ · inertia · R = diag(moments)`.
    pub axes: DMat3,
}

fn positive(name: &'static str, value: f64) -> Result<f64, MassError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(MassError::NotPositive { name, value })
    }
}

impl MassProperties {
    /// Mass properties given directly, validated: `mass` finite and positive, `com` finite,
    /// `inertia` finite, symmetric (within [`tol::INERTIA_SYMMETRY_REL`]) and physical (its
    /// principal moments are non-negative and obey the triangle inequality `I₁ + I₂ ≥ I₃`,
    /// within [`tol::INERTIA_TRIANGLE_REL`]).
    ///
    /// # Errors
    /// [`MassError::NotPositive`] or [`MassError::InvalidInertia`], saying what is wrong.
    pub fn new(mass: f64, com: DVec3, inertia: DMat3) -> Result<Self, MassError> {
        positive("mass", mass)?;
        if !com.is_finite() {
            return Err(MassError::InvalidInertia {
                reason: format!("centre of mass {com} is not finite"),
            });
        }
        if !inertia.is_finite() {
            return Err(MassError::InvalidInertia {
                reason: "the inertia tensor is not finite".into(),
            });
        }
        let scale = inertia
            .to_cols_array()
            .iter()
            .fold(0.0f64, |m, x| m.max(x.abs()));
        let asym = (inertia - inertia.transpose())
            .to_cols_array()
            .iter()
            .fold(0.0f64, |m, x| m.max(x.abs()));
        if asym > tol::INERTIA_SYMMETRY_REL * scale {
            return Err(MassError::InvalidInertia {
                reason: format!("the inertia tensor is not symmetric (|I − Iᵀ| = {asym:e})"),
            });
        }
        let props = Self {
            mass,
            com,
            inertia: 0.5 * (inertia + inertia.transpose()),
        };
        let m = props.principal()?.moments;
        let slack = tol::INERTIA_TRIANGLE_REL * m.z.abs().max(scale);
        if m.x < -slack || m.x + m.y < m.z - slack {
            return Err(MassError::InvalidInertia {
                reason: format!(
                    "principal moments {} {} {} are not those of a physical body \
                     (need all >= 0 and I1 + I2 >= I3)",
                    m.x, m.y, m.z
                ),
            });
        }
        Ok(props)
    }

    /// Assembles mass properties from volume integrals and a uniform density (thesis §6.1: the
    /// mass and first moments give the centre of mass; the second moments, moved to the centre
    /// of mass by the transfer-of-axis relations, give the inertia tensor).
    ///
    /// # Errors
    /// [`MassError::NotPositive`] if `density` or the volume is not positive and finite.
    pub fn from_integrals(t: &VolumeIntegrals, density: f64) -> Result<Self, MassError> {
        let rho = positive("density", density)?;
        positive("volume", t.volume)?;
        let mass = rho * t.volume;
        let r = t.first / t.volume; // centre of mass relative to t.origin
        // Moments and products about the integration origin, then transfer of axis (§6.1).
        let (s, p) = (t.second, t.products);
        let ixx = rho * (s.y + s.z) - mass * (r.y * r.y + r.z * r.z);
        let iyy = rho * (s.z + s.x) - mass * (r.z * r.z + r.x * r.x);
        let izz = rho * (s.x + s.y) - mass * (r.x * r.x + r.y * r.y);
        let ixy = rho * p.x - mass * r.x * r.y;
        let iyz = rho * p.y - mass * r.y * r.z;
        let izx = rho * p.z - mass * r.z * r.x;
        let inertia = DMat3::from_cols(
            DVec3::new(ixx, -ixy, -izx),
            DVec3::new(-ixy, iyy, -iyz),
            DVec3::new(-izx, -iyz, izz),
        );
        Ok(Self {
            mass,
            com: t.origin + r,
            inertia,
        })
    }

    /// Mass properties of a closed polygon mesh of uniform `density`.
    ///
    /// The mesh is validated ([`PolyMesh::check_closed`]); it may be non-convex and of any
    /// genus. Integration is done about the mesh's bounding-box centre, so a body far from the
    /// origin loses no accuracy to the transfer-of-axis subtraction.
    ///
    /// # Errors
    /// [`MassError::Mesh`] for an open, inconsistently oriented, inward, degenerate or
    /// non-finite mesh; [`MassError::NotPositive`] for a bad density.
    pub fn from_mesh(mesh: &PolyMesh, density: f64) -> Result<Self, MassError> {
        positive("density", density)?;
        mesh.check_closed()?;
        Self::from_integrals(
            &VolumeIntegrals::integrate(mesh, mesh.bounding_box_center()),
            density,
        )
    }

    /// Mass properties of a closed polygon mesh of uniform density with total `mass` (the
    /// density is `mass / volume`).
    ///
    /// # Errors
    /// As [`MassProperties::from_mesh`], with [`MassError::NotPositive`] for a bad mass.
    pub fn from_mesh_with_mass(mesh: &PolyMesh, mass: f64) -> Result<Self, MassError> {
        positive("mass", mass)?;
        mesh.check_closed()?;
        let t = VolumeIntegrals::integrate(mesh, mesh.bounding_box_center());
        Self::from_integrals(&t, mass / positive("volume", t.volume)?)
    }

    /// Mass properties of a convex polyhedron of uniform `density` (already validated, so the
    /// mesh is not checked again).
    ///
    /// # Errors
    /// [`MassError::NotPositive`] for a bad density.
    pub fn from_convex(poly: &ConvexPolyhedron, density: f64) -> Result<Self, MassError> {
        let mesh = poly.mesh();
        Self::from_integrals(
            &VolumeIntegrals::integrate(mesh, mesh.bounding_box_center()),
            density,
        )
    }

    /// A solid sphere of `radius` centred at `center`: m = ρ·4πr³/3, I = (2/5)·m·r²·1.
    ///
    /// # Errors
    /// [`MassError::NotPositive`] for a bad radius or density.
    pub fn solid_sphere(radius: f64, center: DVec3, density: f64) -> Result<Self, MassError> {
        let r = positive("radius", radius)?;
        let mass = positive("density", density)? * 4.0 / 3.0 * std::f64::consts::PI * r * r * r;
        Ok(Self {
            mass,
            com: center,
            inertia: DMat3::from_diagonal(DVec3::splat(0.4 * mass * r * r)),
        })
    }

    /// A solid ellipsoid with semi-axes `semi_axes` = (a, b, c) along the frame axes, centred at
    /// `center`: m = ρ·4πabc/3, I_xx = m(b² + c²)/5 and cyclically.
    ///
    /// # Errors
    /// [`MassError::NotPositive`] for a bad semi-axis or density.
    pub fn solid_ellipsoid(
        semi_axes: DVec3,
        center: DVec3,
        density: f64,
    ) -> Result<Self, MassError> {
        let s = DVec3::new(
            positive("semi_axes.x", semi_axes.x)?,
            positive("semi_axes.y", semi_axes.y)?,
            positive("semi_axes.z", semi_axes.z)?,
        );
        let mass =
            positive("density", density)? * 4.0 / 3.0 * std::f64::consts::PI * s.x * s.y * s.z;
        let s2 = s * s;
        let diag = DVec3::new(s2.y + s2.z, s2.z + s2.x, s2.x + s2.y) * (mass / 5.0);
        Ok(Self {
            mass,
            com: center,
            inertia: DMat3::from_diagonal(diag),
        })
    }

    /// A solid axis-aligned box with half side lengths `half_extents` centred at `center`:
    /// m = 8ρ·h_x·h_y·h_z, I_xx = m(h_y² + h_z²)/3 and cyclically.
    ///
    /// # Errors
    /// [`MassError::NotPositive`] for a bad half extent or density.
    pub fn solid_cuboid(
        half_extents: DVec3,
        center: DVec3,
        density: f64,
    ) -> Result<Self, MassError> {
        let h = DVec3::new(
            positive("half_extents.x", half_extents.x)?,
            positive("half_extents.y", half_extents.y)?,
            positive("half_extents.z", half_extents.z)?,
        );
        let mass = positive("density", density)? * 8.0 * h.x * h.y * h.z;
        let h2 = h * h;
        let diag = DVec3::new(h2.y + h2.z, h2.z + h2.x, h2.x + h2.y) * (mass / 3.0);
        Ok(Self {
            mass,
            com: center,
            inertia: DMat3::from_diagonal(diag),
        })
    }

    /// A point mass (thesis §6.1: ∫ f dm = m·f(r) for a point mass): no inertia about itself.
    ///
    /// # Errors
    /// [`MassError::NotPositive`] for a bad mass, [`MassError::InvalidInertia`] for a
    /// non-finite position.
    pub fn point_mass(mass: f64, at: DVec3) -> Result<Self, MassError> {
        positive("mass", mass)?;
        if !at.is_finite() {
            return Err(MassError::InvalidInertia {
                reason: format!("point mass position {at} is not finite"),
            });
        }
        Ok(Self {
            mass,
            com: at,
            inertia: DMat3::ZERO,
        })
    }

    /// A compound body: the sum of parts given in one reference frame (thesis Problem 9).
    /// Masses add, the centre of mass is the mass-weighted mean, and each part's inertia is
    /// moved to the common centre of mass by the parallel-axis theorem.
    ///
    /// # Errors
    /// [`MassError::EmptyCompound`] when `parts` is empty.
    pub fn compound(parts: &[MassProperties]) -> Result<Self, MassError> {
        if parts.is_empty() {
            return Err(MassError::EmptyCompound);
        }
        let mass: f64 = parts.iter().map(|p| p.mass).sum();
        let com = parts.iter().map(|p| p.mass * p.com).sum::<DVec3>() / mass;
        let inertia = parts.iter().fold(DMat3::ZERO, |acc, p| {
            acc + p.inertia + steiner(p.mass, p.com - com)
        });
        Ok(Self { mass, com, inertia })
    }

    /// The inertia tensor about an arbitrary point (reference axes), by the parallel-axis
    /// theorem.
    pub fn inertia_about(&self, point: DVec3) -> DMat3 {
        self.inertia + steiner(self.mass, self.com - point)
    }

    /// The same body moved rigidly by `pose`: the centre of mass is transformed and the
    /// inertia tensor rotated, `R·I·Rᵀ`.
    pub fn transformed(&self, pose: &Pose) -> Self {
        let r = pose.rotation_matrix();
        Self {
            mass: self.mass,
            com: pose.transform_point(self.com),
            inertia: r * self.inertia * r.transpose(),
        }
    }

    /// The principal moments and axes (thesis §6.1: find R with Rᵀ·I·R diagonal), by faer's
    /// symmetric eigendecomposition. Repeated moments (a sphere, a cube) have axes that are an
    /// arbitrary orthonormal basis of their eigenspace.
    ///
    /// # Errors
    /// [`MassError::Eigen`] if the solver fails (non-finite tensor).
    pub fn principal(&self) -> Result<PrincipalFrame, MassError> {
        let i = self.inertia;
        let m = Mat::<f64>::from_fn(3, 3, |r, c| i.col(c)[r]);
        let evd = m
            .self_adjoint_eigen(Side::Lower)
            .map_err(|_| MassError::Eigen)?;
        let (s, u) = (evd.S(), evd.U());
        let moments = DVec3::new(s[0], s[1], s[2]);
        let col = |c: usize| DVec3::new(u[(0, c)], u[(1, c)], u[(2, c)]);
        let (x, y) = (col(0), col(1));
        // Orthonormal eigenvectors; choosing the third as x × y makes det R = +1.
        let axes = DMat3::from_cols(x, y, x.cross(y));
        if !(moments.is_finite() && axes.is_finite()) {
            return Err(MassError::Eigen);
        }
        Ok(PrincipalFrame { moments, axes })
    }
}

/// The parallel-axis term m(|d|²·1 − d·dᵀ): inertia of a point mass m at offset d.
fn steiner(mass: f64, d: DVec3) -> DMat3 {
    mass * (DMat3::from_diagonal(DVec3::splat(d.length_squared()))
        - DMat3::from_cols(d * d.x, d * d.y, d * d.z))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrals::tests::tetrahedron;
    use glam::DQuat;
    use impulse_geom::primitives;
    use rand::rngs::Xoshiro256PlusPlus;
    use rand::{RngExt, SeedableRng};

    /// Relative agreement required of exact formulas evaluated two ways (thesis: ≥ 15
    /// significant figures on Table 6.1; we allow a few ulps of accumulated rounding).
    const EXACT: f64 = 1e-12;
    /// Relative agreement required under rigid motions far from the origin (V4: 1e-10).
    const INVARIANT: f64 = 1e-10;

    fn mat_rel(a: DMat3, b: DMat3) -> f64 {
        let scale = b
            .to_cols_array()
            .iter()
            .fold(0.0f64, |m, x| m.max(x.abs()))
            .max(f64::MIN_POSITIVE);
        (a - b)
            .to_cols_array()
            .iter()
            .fold(0.0f64, |m, x| m.max(x.abs()))
            / scale
    }

    #[test]
    fn tetrahedron_matches_the_corner_tetrahedron_formulas() {
        // Corner tetrahedron with legs (a, b, c) = (5, 4, 3), ρ = 1: m = abc/6,
        // r = (a, b, c)/4, I_xx = 3m(b² + c²)/80 (cyclic), tensor off-diagonals +m·ab/80 etc.
        let p = MassProperties::from_mesh(&tetrahedron(), 1.0).unwrap();
        let (a, b, c) = (5.0, 4.0, 3.0);
        let m = a * b * c / 6.0;
        assert!((p.mass - m).abs() < EXACT * m);
        assert!(p.com.distance(DVec3::new(a, b, c) / 4.0) < EXACT);
        let want = DMat3::from_cols(
            DVec3::new(
                3.0 * m * (b * b + c * c) / 80.0,
                m * a * b / 80.0,
                m * c * a / 80.0,
            ),
            DVec3::new(
                m * a * b / 80.0,
                3.0 * m * (c * c + a * a) / 80.0,
                m * b * c / 80.0,
            ),
            DVec3::new(
                m * c * a / 80.0,
                m * b * c / 80.0,
                3.0 * m * (a * a + b * b) / 80.0,
            ),
        );
        assert!(mat_rel(p.inertia, want) < EXACT, "{:?}", p.inertia);
        // The digest's printed tensor, as a second reference.
        assert!(
            (p.inertia.x_axis.x - 9.375).abs() < 1e-12 && (p.inertia.y_axis.x - 2.5).abs() < 1e-12
        );
    }

    #[test]
    fn mesh_box_and_sphere_match_exact_formulas() {
        let h = DVec3::new(0.5, 1.5, 2.5);
        let mesh = primitives::cuboid_mesh(h).unwrap();
        let from_mesh = MassProperties::from_mesh(&mesh, 7.0).unwrap();
        let exact = MassProperties::solid_cuboid(h, DVec3::ZERO, 7.0).unwrap();
        assert!((from_mesh.mass - exact.mass).abs() < EXACT * exact.mass);
        assert!(from_mesh.com.length() < EXACT);
        assert!(mat_rel(from_mesh.inertia, exact.inertia) < EXACT);
        // Geodesic sphere, level 6: between the inscribed and circumscribed spheres' values
        // (volume and moment are monotone in the body), and within 0.1 % of the exact sphere.
        let g = primitives::geodesic_sphere_mesh(6, 1.0).unwrap();
        let p = MassProperties::from_mesh(&g, 1.0).unwrap();
        let exact = MassProperties::solid_sphere(1.0, DVec3::ZERO, 1.0).unwrap();
        let inradius = (0..g.face_count())
            .map(|f| {
                let n = g.face_area_vector(f).normalize();
                n.dot(g.vertices()[g.face(f)[0] as usize])
            })
            .fold(f64::INFINITY, f64::min);
        let inner = MassProperties::solid_sphere(inradius, DVec3::ZERO, 1.0).unwrap();
        assert!(inner.mass < p.mass && p.mass < exact.mass);
        let (ii, ip, ie) = (
            inner.inertia.x_axis.x,
            p.inertia.x_axis.x,
            exact.inertia.x_axis.x,
        );
        assert!(ii < ip && ip < ie);
        assert!((p.mass - exact.mass).abs() / exact.mass < 1e-3);
        assert!(p.com.length() < 1e-13);
    }

    #[test]
    fn rigid_motion_far_from_the_origin_transforms_exactly() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(11);
        let mesh = tetrahedron();
        let base = MassProperties::from_mesh(&mesh, 2.0).unwrap();
        for _ in 0..200 {
            let q = DQuat::from_xyzw(
                rng.random::<f64>() - 0.5,
                rng.random::<f64>() - 0.5,
                rng.random::<f64>() - 0.5,
                rng.random::<f64>() - 0.5,
            )
            .normalize();
            // Translations up to 1e3 × the body's size.
            let t = (DVec3::new(rng.random(), rng.random(), rng.random()) - 0.5) * 1e4;
            let pose = Pose::new(q, t);
            let moved = mesh.map_vertices(|v| pose.transform_point(v)).unwrap();
            let got = MassProperties::from_mesh(&moved, 2.0).unwrap();
            let want = base.transformed(&pose);
            assert!((got.mass - want.mass).abs() < INVARIANT * want.mass);
            assert!(got.com.distance(want.com) < INVARIANT * want.com.length());
            assert!(
                mat_rel(got.inertia, want.inertia) < INVARIANT,
                "{}",
                mat_rel(got.inertia, want.inertia)
            );
        }
    }

    #[test]
    fn compound_of_halves_equals_the_whole_and_point_masses_add() {
        let whole =
            MassProperties::solid_cuboid(DVec3::new(2.0, 1.0, 0.5), DVec3::new(1.0, 2.0, 3.0), 3.0)
                .unwrap();
        let left =
            MassProperties::solid_cuboid(DVec3::new(1.0, 1.0, 0.5), DVec3::new(0.0, 2.0, 3.0), 3.0)
                .unwrap();
        let right =
            MassProperties::solid_cuboid(DVec3::new(1.0, 1.0, 0.5), DVec3::new(2.0, 2.0, 3.0), 3.0)
                .unwrap();
        let sum = MassProperties::compound(&[left, right]).unwrap();
        assert!((sum.mass - whole.mass).abs() < EXACT * whole.mass);
        assert!(sum.com.distance(whole.com) < EXACT);
        assert!(mat_rel(sum.inertia, whole.inertia) < EXACT);
        // Eight point masses m/8 at the corners (±h, ±h, ±h): I = 2·m·h²·1.
        let corners: Vec<MassProperties> = (0..8)
            .map(|i| {
                let s = |b: i32| if i >> b & 1 == 1 { 1.0 } else { -1.0 };
                MassProperties::point_mass(0.5, DVec3::new(s(0), s(1), s(2)) * 3.0).unwrap()
            })
            .collect();
        let c = MassProperties::compound(&corners).unwrap();
        assert!(
            mat_rel(
                c.inertia,
                DMat3::from_diagonal(DVec3::splat(2.0 * 4.0 * 9.0))
            ) < EXACT
        );
        assert!(MassProperties::compound(&[]).is_err());
    }

    #[test]
    fn principal_frame_recovers_a_rotated_box() {
        let h = DVec3::new(0.3, 1.0, 2.0);
        let exact = MassProperties::solid_cuboid(h, DVec3::ZERO, 1.0).unwrap();
        let q = DQuat::from_euler(glam::EulerRot::ZYX, 0.4, -1.2, 2.9);
        let rotated = exact.transformed(&Pose::new(q, DVec3::new(4.0, 5.0, 6.0)));
        let pf = rotated.principal().unwrap();
        // Box moments in increasing order are those about z, y, x for h = (0.3, 1, 2)... sort.
        let mut want = exact
            .inertia
            .to_cols_array()
            .iter()
            .step_by(4)
            .copied()
            .collect::<Vec<_>>();
        want.sort_by(f64::total_cmp);
        for k in 0..3 {
            assert!((pf.moments[k] - want[k]).abs() < EXACT * want[2]);
        }
        assert!((pf.axes.determinant() - 1.0).abs() < 1e-12);
        let d = pf.axes.transpose() * rotated.inertia * pf.axes;
        assert!(mat_rel(d, DMat3::from_diagonal(pf.moments)) < EXACT);
        // Each principal axis is a rotated box axis (up to sign).
        let box_axes = [q * DVec3::X, q * DVec3::Y, q * DVec3::Z];
        for k in 0..3 {
            assert!(
                box_axes
                    .iter()
                    .any(|a| (a.dot(pf.axes.col(k)).abs() - 1.0).abs() < 1e-12)
            );
        }
    }

    #[test]
    fn bad_inputs_are_errors() {
        let t = tetrahedron();
        for d in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(matches!(
                MassProperties::from_mesh(&t, d),
                Err(MassError::NotPositive {
                    name: "density",
                    ..
                })
            ));
            assert!(matches!(
                MassProperties::from_mesh_with_mass(&t, d),
                Err(MassError::NotPositive { name: "mass", .. })
            ));
        }
        let p = MassProperties::from_mesh_with_mass(&t, 5.0).unwrap();
        assert!((p.mass - 5.0).abs() < 1e-14);
        // A physically impossible tensor: I3 > I1 + I2.
        let e = MassProperties::new(
            1.0,
            DVec3::ZERO,
            DMat3::from_diagonal(DVec3::new(1.0, 1.0, 3.0)),
        )
        .unwrap_err();
        assert!(e.to_string().contains("physical"), "{e}");
        let mut asym = DMat3::IDENTITY;
        asym.x_axis.y = 0.1;
        assert!(MassProperties::new(1.0, DVec3::ZERO, asym).is_err());
        assert!(MassProperties::new(1.0, DVec3::ZERO, DMat3::IDENTITY).is_ok());
        assert!(MassProperties::new(1.0, DVec3::NAN, DMat3::IDENTITY).is_err());
        // A thin rod meets the triangle inequality with equality: accepted.
        assert!(
            MassProperties::new(
                1.0,
                DVec3::ZERO,
                DMat3::from_diagonal(DVec3::new(0.0, 1.0, 1.0))
            )
            .is_ok()
        );
    }

    /// The closed form against exact polyhedral integrals of inscribed geodesic ellipsoids,
    /// whose error must shrink about fourfold per refinement level.
    #[test]
    fn solid_ellipsoid_is_the_limit_of_inscribed_polyhedra() {
        let axes = DVec3::new(0.1, 0.03, 0.02);
        let exact = MassProperties::solid_ellipsoid(axes, DVec3::ZERO, 2.0).unwrap();
        let mut last = f64::INFINITY;
        for level in 4..=6 {
            let mesh = primitives::geodesic_sphere_mesh(level, 1.0).unwrap();
            let pts: Vec<DVec3> = mesh.vertices().iter().map(|v| *v * axes).collect();
            let poly = impulse_geom::ConvexPolyhedron::hull(&pts).unwrap();
            let p = MassProperties::from_convex(&poly, 2.0).unwrap();
            let err = ((p.mass - exact.mass) / exact.mass)
                .abs()
                .max(mat_rel(p.inertia, exact.inertia));
            assert!(p.mass < exact.mass, "inscribed polyhedra are smaller");
            assert!(err < last / 3.5, "level {level}: {err} after {last}");
            last = err;
        }
        assert!(last < 2e-3, "{last}");
        // A sphere is the equal-axes case.
        let e = MassProperties::solid_ellipsoid(DVec3::splat(0.3), DVec3::X, 5.0).unwrap();
        let s = MassProperties::solid_sphere(0.3, DVec3::X, 5.0).unwrap();
        assert!((e.mass - s.mass).abs() < EXACT * s.mass);
        assert!(mat_rel(e.inertia, s.inertia) < EXACT);
        assert!(matches!(
            MassProperties::solid_ellipsoid(DVec3::new(1.0, 0.0, 1.0), DVec3::ZERO, 1.0),
            Err(MassError::NotPositive {
                name: "semi_axes.y",
                ..
            })
        ));
    }
}
