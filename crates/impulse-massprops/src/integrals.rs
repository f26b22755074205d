//! The ten volume integrals of a polyhedron (thesis §6.2–6.3).
//!
//! For a closed mesh whose faces are counter-clockwise seen from outside, each volume integral
//! of a monomial becomes a sum of face integrals (divergence theorem, eq. 6.2–6.3); each face
//! integral becomes an integral over the face's projection onto the coordinate plane where the
//! projection is largest (eq. 6.4–6.6); each plane integral becomes a sum over the projected
//! edges (Green's theorem, eq. 6.7–6.9), evaluated in closed form (eq. 6.10–6.14). Everything
//! is accumulated in one pass over the faces, sharing subexpressions (Figs. 6.4–6.6).
//!
//! The sign bookkeeping of §6.3 is used: the projected edge sums are computed unsigned and
//! divided by powers of the face normal's γ-component, which carries the sign.

use glam::DVec3;
use impulse_geom::PolyMesh;

use crate::MassError;

/// The ten volume integrals of thesis eq. 6.1, over a polyhedron V, of the coordinates
/// relative to an origin `o` (`x` below means `x − o.x`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VolumeIntegrals {
    /// The origin the coordinates are taken about.
    pub origin: DVec3,
    /// T₁ = ∫ 1 dV, the volume.
    pub volume: f64,
    /// (T_x, T_y, T_z) = (∫x, ∫y, ∫z) dV.
    pub first: DVec3,
    /// (T_x², T_y², T_z²) = (∫x², ∫y², ∫z²) dV.
    pub second: DVec3,
    /// (T_xy, T_yz, T_zx) = (∫xy, ∫yz, ∫zx) dV.
    pub products: DVec3,
}

/// The ten projection integrals of one face (eq. 6.14), without the factor sgn(n̂_γ).
#[derive(Default)]
struct Projection {
    p1: f64,
    pa: f64,
    pb: f64,
    paa: f64,
    pab: f64,
    pbb: f64,
    paaa: f64,
    paab: f64,
    pabb: f64,
    pbbb: f64,
}

impl VolumeIntegrals {
    /// The ten integrals in the column order of thesis Table 6.1:
    /// (T₁, T_x, T_y, T_z, T_x², T_y², T_z², T_xy, T_yz, T_zx).
    pub fn to_array(&self) -> [f64; 10] {
        let (f, s, p) = (self.first, self.second, self.products);
        [self.volume, f.x, f.y, f.z, s.x, s.y, s.z, p.x, p.y, p.z]
    }

    /// Validates `mesh` (closed, consistently and outwardly oriented, non-degenerate planar
    /// faces; see [`PolyMesh::check_closed`]) and integrates over it about the world origin.
    ///
    /// # Errors
    /// [`MassError::Mesh`] naming the first problem of the mesh.
    pub fn of_mesh(mesh: &PolyMesh) -> Result<Self, MassError> {
        mesh.check_closed()?;
        Ok(Self::integrate(mesh, DVec3::ZERO))
    }

    /// Integrates over `mesh` about `origin`, without validating the mesh.
    ///
    /// The result is exact (to rounding) for a closed mesh of planar faces oriented
    /// counter-clockwise seen from outside; for anything else it is meaningless. Use it on
    /// meshes already validated, such as a [`impulse_geom::ConvexPolyhedron`]'s, or call
    /// [`VolumeIntegrals::of_mesh`]. Choosing an `origin` near the body (its bounding-box
    /// centre) keeps the second moments free of cancellation for bodies far from the world
    /// origin.
    pub fn integrate(mesh: &PolyMesh, origin: DVec3) -> Self {
        let verts = mesh.vertices();
        // Fig. 6.4, eq. 6.3.
        let mut t0 = 0.0;
        let mut t1 = [0.0; 3];
        let mut t2 = [0.0; 3];
        let mut tp = [0.0; 3];
        let mut loop_: Vec<DVec3> = Vec::new();
        for f in 0..mesh.face_count() {
            loop_.clear();
            loop_.extend(mesh.face(f).iter().map(|&i| verts[i as usize] - origin));
            let Some(n) = newell(&loop_).try_normalize() else {
                continue; // zero-area face: contributes nothing (rejected by of_mesh anyway)
            };
            let w = -n.dot(loop_[0]);
            // γ: the axis of the largest normal component; (α, β, γ) a cyclic permutation of
            // (x, y, z) so that α̂ × β̂ = γ̂ (§6.2.2).
            let c = n.abs().max_position();
            let a = (c + 1) % 3;
            let b = (a + 1) % 3;
            let fi = face_integrals(&loop_, n, w, a, b, c);
            let [na, nb, nc] = [n[a], n[b], n[c]];
            t0 += n.x
                * if a == 0 {
                    fi.fa
                } else if b == 0 {
                    fi.fb
                } else {
                    fi.fc
                };
            t1[a] += na * fi.faa;
            t1[b] += nb * fi.fbb;
            t1[c] += nc * fi.fcc;
            t2[a] += na * fi.faaa;
            t2[b] += nb * fi.fbbb;
            t2[c] += nc * fi.fccc;
            // The cyclic choice makes index a hold ∫αβ, b hold ∫βγ, c hold ∫γα, which are
            // exactly the (xy, yz, zx) slots for every projection.
            tp[a] += na * fi.faab;
            tp[b] += nb * fi.fbbc;
            tp[c] += nc * fi.fcca;
        }
        Self {
            origin,
            volume: t0,
            first: DVec3::from_array(t1) / 2.0,
            second: DVec3::from_array(t2) / 3.0,
            products: DVec3::from_array(tp) / 2.0,
        }
    }
}

/// Face integrals ∫_F of α, β, γ, α², β², γ², α³, β³, γ³, α²β, β²γ, γ²α.
struct FaceIntegrals {
    fa: f64,
    fb: f64,
    fc: f64,
    faa: f64,
    fbb: f64,
    fcc: f64,
    faaa: f64,
    fbbb: f64,
    fccc: f64,
    faab: f64,
    fbbc: f64,
    fcca: f64,
}

/// Fig. 6.5, eq. 6.6: face integrals from projection integrals. `w` is the plane constant
/// (n̂·p + w = 0 on the face).
fn face_integrals(
    loop_: &[DVec3],
    n: DVec3,
    w: f64,
    a: usize,
    b: usize,
    c: usize,
) -> FaceIntegrals {
    let p = projection_integrals(loop_, a, b);
    let (na, nb) = (n[a], n[b]);
    let k1 = 1.0 / n[c];
    let k2 = k1 * k1;
    let k3 = k2 * k1;
    let k4 = k3 * k1;
    let (na2, nb2) = (na * na, nb * nb);
    FaceIntegrals {
        fa: k1 * p.pa,
        fb: k1 * p.pb,
        fc: -k2 * (na * p.pa + nb * p.pb + w * p.p1),
        faa: k1 * p.paa,
        fbb: k1 * p.pbb,
        fcc: k3
            * (na2 * p.paa
                + 2.0 * na * nb * p.pab
                + nb2 * p.pbb
                + w * (2.0 * (na * p.pa + nb * p.pb) + w * p.p1)),
        faaa: k1 * p.paaa,
        fbbb: k1 * p.pbbb,
        fccc: -k4
            * (na2 * na * p.paaa
                + 3.0 * na2 * nb * p.paab
                + 3.0 * na * nb2 * p.pabb
                + nb2 * nb * p.pbbb
                + 3.0 * w * (na2 * p.paa + 2.0 * na * nb * p.pab + nb2 * p.pbb)
                + w * w * (3.0 * (na * p.pa + nb * p.pb) + w * p.p1)),
        faab: k1 * p.paab,
        fbbc: -k2 * (na * p.pabb + nb * p.pbbb + w * p.pbb),
        fcca: k3
            * (na2 * p.paaa
                + 2.0 * na * nb * p.paab
                + nb2 * p.pabb
                + w * (2.0 * (na * p.paa + nb * p.pab) + w * p.pa)),
    }
}

/// Fig. 6.6, eq. 6.14: integrals over the face's projection onto the α-β plane, as closed-form
/// sums over its edges (eq. 6.10–6.13), without the factor sgn(n̂_γ).
fn projection_integrals(loop_: &[DVec3], a: usize, b: usize) -> Projection {
    let mut p = Projection::default();
    let k = loop_.len();
    for e in 0..k {
        let (v0, v1) = (loop_[e], loop_[(e + 1) % k]);
        let (a0, b0, a1, b1) = (v0[a], v0[b], v1[a], v1[b]);
        let (da, db) = (a1 - a0, b1 - b0);
        let (a0_2, b0_2, a1_2, b1_2) = (a0 * a0, b0 * b0, a1 * a1, b1 * b1);
        let (a0_3, b0_3, a1_3, b1_3) = (a0_2 * a0, b0_2 * b0, a1_2 * a1, b1_2 * b1);
        let c1 = a1 + a0;
        let ca = a1 * c1 + a0_2;
        let caa = a1 * ca + a0_3;
        let caaa = a1 * caa + a0_3 * a0;
        let cb = b1 * (b1 + b0) + b0_2;
        let cbb = b1 * cb + b0_3;
        let cbbb = b1 * cbb + b0_3 * b0;
        let cab = 3.0 * a1_2 + 2.0 * a1 * a0 + a0_2;
        let kab = a1_2 + 2.0 * a1 * a0 + 3.0 * a0_2;
        let caab = a0 * cab + 4.0 * a1_3;
        let kaab = a1 * kab + 4.0 * a0_3;
        let cabb = 4.0 * b1_3 + 3.0 * b1_2 * b0 + 2.0 * b1 * b0_2 + b0_3;
        let kabb = b1_3 + 2.0 * b1_2 * b0 + 3.0 * b1 * b0_2 + 4.0 * b0_3;
        p.p1 += db * c1;
        p.pa += db * ca;
        p.paa += db * caa;
        p.paaa += db * caaa;
        p.pb += da * cb;
        p.pbb += da * cbb;
        p.pbbb += da * cbbb;
        p.pab += db * (b1 * cab + b0 * kab);
        p.paab += db * (b1 * caab + b0 * kaab);
        p.pabb += da * (a1 * cabb + a0 * kabb);
    }
    p.p1 /= 2.0;
    p.pa /= 6.0;
    p.paa /= 12.0;
    p.paaa /= 20.0;
    p.pb /= -6.0;
    p.pbb /= -12.0;
    p.pbbb /= -20.0;
    p.pab /= 24.0;
    p.paab /= 60.0;
    p.pabb /= -60.0;
    p
}

/// Newell's normal (twice the vector area) of a polygon loop.
fn newell(loop_: &[DVec3]) -> DVec3 {
    let k = loop_.len();
    (0..k).map(|i| loop_[i].cross(loop_[(i + 1) % k])).sum()
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use impulse_geom::primitives;

    /// The tetrahedron of Table 6.1: the hull of the origin, 5î, 4ĵ and 3k̂.
    pub(crate) fn tetrahedron() -> PolyMesh {
        primitives::corner_tetrahedron_mesh(DVec3::new(5.0, 4.0, 3.0)).unwrap()
    }

    fn rel(a: f64, b: f64) -> f64 {
        (a - b).abs() / b.abs().max(1.0)
    }

    /// Table 6.1 (thesis §6.4): the exact integrals; the thesis found every value correct to 15
    /// significant figures.
    #[test]
    fn table_6_1_tetrahedron_and_cube() {
        let t = VolumeIntegrals::of_mesh(&tetrahedron()).unwrap();
        let got = t.to_array();
        let want = [10.0, 12.5, 10.0, 7.5, 25.0, 16.0, 9.0, 10.0, 6.0, 7.5];
        for (g, w) in got.iter().zip(want) {
            assert!(rel(*g, w) < 1e-14, "{g} vs {w}");
        }
        let cube = primitives::cuboid_mesh(DVec3::splat(10.0)).unwrap();
        let t = VolumeIntegrals::of_mesh(&cube).unwrap();
        assert!(rel(t.volume, 8000.0) < 1e-14);
        for k in 0..3 {
            assert!(rel(t.second[k], 800_000.0 / 3.0) < 1e-14);
            assert!(t.first[k].abs() < 1e-9 && t.products[k].abs() < 1e-9);
        }
    }

    /// Brute-force reference: the integrals of a monomial over a tetrahedron (0, a, b, c) are
    /// known in closed form; a polyhedron is a sum of tetrahedra from any interior point. This
    /// checks all ten integrals on a random non-convex closed mesh (an extruded star).
    #[test]
    fn agrees_with_tetrahedral_decomposition_on_a_non_convex_mesh() {
        let n = 7;
        let mut v = Vec::new();
        for z in [-0.4, 0.9] {
            for k in 0..2 * n {
                let ang = std::f64::consts::PI * k as f64 / n as f64;
                let r = if k % 2 == 0 { 2.0 } else { 0.7 };
                v.push(DVec3::new(r * ang.cos() + 0.3, r * ang.sin() - 0.2, z));
            }
        }
        let m = 2 * n as u32;
        let mut faces: Vec<Vec<u32>> = vec![(0..m).rev().collect(), (m..2 * m).collect()];
        for k in 0..m {
            faces.push(vec![k, (k + 1) % m, m + (k + 1) % m, m + k]);
        }
        let mesh = PolyMesh::new(v, faces).unwrap();
        let t = VolumeIntegrals::of_mesh(&mesh).unwrap();
        // Reference: fan-triangulate every face, sum signed tetrahedra from the origin, and
        // integrate monomials over each tetrahedron with the exact degree-2 quadrature
        // (vertices and edge midpoints) — independent of projections and Green's theorem.
        let mut r = [0.0f64; 10];
        for face in mesh.faces() {
            for k in 1..face.len() - 1 {
                let p = [
                    DVec3::ZERO,
                    mesh.vertices()[face[0] as usize],
                    mesh.vertices()[face[k] as usize],
                    mesh.vertices()[face[k + 1] as usize],
                ];
                let vol = p[1].dot(p[2].cross(p[3])) / 6.0;
                let c = (p[0] + p[1] + p[2] + p[3]) / 4.0;
                // Degree-2 exactness: ∫q = vol·(Σ_i q(p_i)/20 + ... ) via the rule
                // ∫ x_i x_j = vol/20 (Σ_k p_k,i p_k,j + 16 c_i c_j).
                let second = |i: usize, j: usize| {
                    vol / 20.0 * (p.iter().map(|q| q[i] * q[j]).sum::<f64>() + 16.0 * c[i] * c[j])
                };
                let vals = [
                    vol,
                    vol * c.x,
                    vol * c.y,
                    vol * c.z,
                    second(0, 0),
                    second(1, 1),
                    second(2, 2),
                    second(0, 1),
                    second(1, 2),
                    second(2, 0),
                ];
                for (acc, v) in r.iter_mut().zip(vals) {
                    *acc += v;
                }
            }
        }
        let got = t.to_array();
        for (g, w) in got.iter().zip(r) {
            assert!((g - w).abs() < 1e-12 * r[0].abs().max(1.0), "{g} vs {w}");
        }
    }

    #[test]
    fn refuses_bad_meshes() {
        let t = tetrahedron();
        let open =
            PolyMesh::new(t.vertices().to_vec(), [[0u32, 2, 1], [0, 1, 3], [0, 3, 2]]).unwrap();
        let e = VolumeIntegrals::of_mesh(&open).unwrap_err();
        assert!(e.to_string().contains("open"), "{e}");
        let inward = PolyMesh::new(
            t.vertices().to_vec(),
            [[0u32, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]],
        )
        .unwrap();
        let e = VolumeIntegrals::of_mesh(&inward).unwrap_err();
        assert!(e.to_string().contains("inwards"), "{e}");
    }
}
