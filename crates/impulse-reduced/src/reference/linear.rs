//! Linearised constrained statics of the full model about a configuration (the rest pose or a
//! static equilibrium): the exact references the construction must reproduce.
//!
//! With joint stiffness `K_q = diag(1/c)` (every coordinate, loop joints included), loop
//! Jacobian `G` and end-effector body Jacobians `J_E`, the statics
//! `K_q δθ = J_Eᵀ w + Gᵀλ`, `G δθ = 0` give, with `Z` an orthonormal basis of `ker G`,
//! `δθ = C_θ J_Eᵀ w` where `C_θ = Z (Zᵀ K_q Z)⁻¹ Zᵀ`. Every link's twist is `J_l δθ`; the
//! end-effector compliance is the Schur complement `J_E C_θ J_Eᵀ` (for a tree, `J_E K_q⁻¹ J_Eᵀ`,
//! i.e. `J C_q Jᵀ` of the digest). The operational-space accelerability is
//! `J_E Z (Zᵀ M_q Z)⁻¹ Zᵀ J_Eᵀ` with `M_q = Σ_l J_lᵀ I_l J_l` the joint-space mass matrix.
//!
//! This is the material (joint-spring) tangent only; the geometric stiffness of a preload is
//! left out, as the FORK⁻¹S construction leaves it out.

use faer::Mat;
use impulse_geom::{Mat6, Pose, Twist, Wrench};

use crate::error::Error;
use crate::linalg::{Tsvd, pinv};
use crate::mechanism::Mechanism;
use crate::reference::kinematics::{Configuration, body_jacobian, link_poses, loop_jacobian};

/// A symmetric positive definite joint-space matrix (ndof × ndof): diagonal (per-coordinate
/// stiffness or damping) or dense (the mass matrix).
#[derive(Copy, Clone, Debug)]
pub enum JointMatrix<'a> {
    /// Its diagonal.
    Diagonal(&'a [f64]),
    /// The whole matrix.
    Dense(&'a Mat<f64>),
}

/// The linearised statics about one configuration.
#[derive(Clone, Debug)]
pub struct LinearStatics {
    /// The configuration linearised about.
    pub config: Configuration,
    /// Link poses there (world).
    pub poses: Vec<Pose>,
    /// Body Jacobian of every link (6 × ndof).
    pub jacobians: Vec<Mat<f64>>,
    /// Orthonormal basis of the loop-closure null space (ndof × ndof − rank G).
    pub null_space: Mat<f64>,
    /// Constrained joint-space compliance `C_θ = Z (Zᵀ K_q Z)⁻¹ Zᵀ` (ndof × ndof).
    pub joint_compliance: Mat<f64>,
    /// With loops, a factor `F = Z (Zᵀ K_q Z)^(−½)` of `C_θ = F Fᵀ` (ndof × nz); a tree's is
    /// `diag(√c)`, not stored.
    factor: Option<Mat<f64>>,
    /// Per coordinate, its compliance.
    compliances: Vec<f64>,
    /// The truncated SVD of the loop closure's Jacobian G (its null space Z), when there are
    /// loops.
    pub closure_report: Option<crate::rank::RankReport>,
}

impl LinearStatics {
    /// Linearises `m` about `q` (which must close every loop).
    ///
    /// # Errors
    /// [`Error::LinearAlgebra`] if a factorisation fails.
    pub fn new(m: &Mechanism, q: &Configuration, tsvd: Tsvd) -> Result<Self, Error> {
        let poses = link_poses(m, q);
        let jacobians: Vec<Mat<f64>> = (0..m.links.len())
            .map(|l| body_jacobian(m, q, &poses, l))
            .collect();
        let nl = m.loop_joints.len();
        let mut g = Mat::<f64>::zeros(6 * nl, m.ndof);
        for (k, &ji) in m.loop_joints.iter().enumerate() {
            let gk = loop_jacobian(m, q, &poses, ji);
            for c in 0..m.ndof {
                for r in 0..6 {
                    g[(6 * k + r, c)] = gk[(r, c)];
                }
            }
        }
        let c: Vec<f64> = m
            .joints
            .iter()
            .flat_map(|j| j.compliance.iter().copied())
            .collect();
        let (z, joint_compliance, factor, closure_report) = if nl == 0 {
            // A tree: Z = I and C_θ = diag(c).
            (
                Mat::<f64>::identity(m.ndof, m.ndof),
                Mat::from_fn(m.ndof, m.ndof, |a, b| if a == b { c[a] } else { 0.0 }),
                None,
                None,
            )
        } else {
            let (z, report) = null_space_report(g.as_ref(), tsvd)?;
            // Zᵀ K_q Z, symmetric positive definite (K_q is).
            let kz_half = Mat::from_fn(m.ndof, z.ncols(), |i, a| z[(i, a)] / c[i].sqrt());
            let kz = kz_half.transpose() * &kz_half;
            let cz = pinv(kz.as_ref(), tsvd)?.inverse;
            let jc = &z * &cz * z.transpose();
            // F = Z U Λ^½ from the eigen-decomposition U Λ Uᵀ of (Zᵀ K_q Z)⁻¹: F Fᵀ = C_θ
            // (none when the loops lock every joint: faer's eigensolver does not take a 0×0
            // matrix).
            let nz = cz.nrows();
            let f = if nz == 0 {
                Mat::zeros(m.ndof, 0)
            } else {
                let evd = cz
                    .self_adjoint_eigen(faer::Side::Lower)
                    .map_err(|e| Error::LinearAlgebra(format!("eigen of (Zᵀ K Z)⁻¹: {e:?}")))?;
                let (s, u) = (evd.S(), evd.U());
                let mut f = &z * u;
                for k in 0..nz {
                    let h = s[k].max(0.0).sqrt();
                    for x in f.col_as_slice_mut(k) {
                        *x *= h;
                    }
                }
                f
            };
            (z, jc, Some(f), Some(report))
        };
        Ok(LinearStatics {
            config: q.clone(),
            poses,
            jacobians,
            null_space: z,
            joint_compliance,
            factor,
            compliances: c,
            closure_report,
        })
    }

    /// Coupled compliance block `C_ab = J_a C_θ J_bᵀ`: body twist of link `a` per body wrench
    /// on link `b`.
    #[must_use]
    pub fn compliance(&self, a: usize, b: usize) -> Mat6 {
        let m = &self.jacobians[a] * &self.joint_compliance * self.jacobians[b].transpose();
        Mat6::from_rows(core::array::from_fn(|r| {
            core::array::from_fn(|c| m[(r, c)])
        }))
    }

    /// The end-effector compliance (6|E| × 6|E|), blocks in the order of `links`.
    #[must_use]
    pub fn compliance_of(&self, links: &[usize]) -> Mat<f64> {
        let je = self.stacked(links);
        &je * &self.joint_compliance * je.transpose()
    }

    /// Stacked body Jacobians of `links` (6|links| × ndof).
    #[must_use]
    pub fn stacked(&self, links: &[usize]) -> Mat<f64> {
        let ndof = self.joint_compliance.nrows();
        Mat::from_fn(6 * links.len(), ndof, |r, c| {
            self.jacobians[links[r / 6]][(r % 6, c)]
        })
    }

    /// The joints' compliance-weighted motions of `links`, `W = J_E F` with `F Fᵀ = C_θ`
    /// (6|links| × nz): `J_E C_θ J_Eᵀ = W Wᵀ`, so the compliance's singular values are the
    /// squares of W's, which W gives to ε of its largest ([`crate::rank`]).
    #[must_use]
    pub fn weighted_motions(&self, links: &[usize]) -> Mat<f64> {
        let je = self.stacked(links);
        match &self.factor {
            Some(f) => je * f,
            None => Mat::from_fn(je.nrows(), je.ncols(), |r, k| {
                je[(r, k)] * self.compliances[k].sqrt()
            }),
        }
    }

    /// `V = J_E Z (Zᵀ Q Z)^(−½)` for a symmetric positive definite joint-space matrix Q (the
    /// joint damping `D_q`, the mass matrix `M_q`): the factor of the end-effector map
    /// `J_E Z (Zᵀ Q Z)⁻¹ Zᵀ J_Eᵀ = V Vᵀ` (damping compliance, accelerability), whose singular
    /// values V gives to ε of its largest.
    ///
    /// # Errors
    /// [`Error::LinearAlgebra`] if the eigen-decomposition fails or `Zᵀ Q Z` is not positive
    /// definite.
    pub fn factor_motions(&self, links: &[usize], q: JointMatrix<'_>) -> Result<Mat<f64>, Error> {
        let je = self.stacked(links);
        let z = &self.null_space;
        if let (JointMatrix::Diagonal(d), None) = (&q, &self.factor) {
            // A tree: Z = I.
            return Ok(Mat::from_fn(je.nrows(), je.ncols(), |r, k| {
                je[(r, k)] / d[k].sqrt()
            }));
        }
        let tree = self.factor.is_none();
        let zqz = match q {
            // A tree: Z = I.
            JointMatrix::Dense(qm) if tree => qm.clone(),
            JointMatrix::Diagonal(d) => {
                z.transpose() * Mat::from_fn(z.nrows(), z.ncols(), |i, a| d[i] * z[(i, a)])
            }
            JointMatrix::Dense(qm) => z.transpose() * (qm * z),
        };
        let nz = zqz.nrows();
        if nz == 0 {
            return Ok(Mat::zeros(je.nrows(), 0));
        }
        let evd = zqz
            .self_adjoint_eigen(faer::Side::Lower)
            .map_err(|e| Error::LinearAlgebra(format!("eigen of Zᵀ Q Z: {e:?}")))?;
        let (s, u) = (evd.S(), evd.U());
        if (0..nz).any(|k| s[k].is_nan() || s[k] <= 0.0) {
            return Err(Error::LinearAlgebra(
                "a joint-space mass or damping matrix is not positive definite on the \
                 admissible motions"
                    .to_owned(),
            ));
        }
        // V = J_E Z U Λ^(−½): V Vᵀ = J_E Z (Zᵀ Q Z)⁻¹ Zᵀ J_Eᵀ (any orthogonal factor on the
        // right leaves V Vᵀ and V's singular values unchanged).
        let mut v = if tree { je * u } else { je * z * u };
        for k in 0..nz {
            let f = 1.0 / s[k].sqrt();
            for x in v.col_as_slice_mut(k) {
                *x *= f;
            }
        }
        Ok(v)
    }

    /// Joint deflection `δθ = C_θ J_Eᵀ w` under body wrenches `w` on `links`.
    #[must_use]
    pub fn deflection(&self, links: &[usize], w: &[Wrench]) -> Vec<f64> {
        let je = self.stacked(links);
        let wv = Mat::from_fn(6 * links.len(), 1, |r, _| w[r / 6].to_array()[r % 6]);
        let d = &self.joint_compliance * (je.transpose() * wv);
        (0..d.nrows()).map(|i| d[(i, 0)]).collect()
    }

    /// Every link's body twist `J_l δθ` under body wrenches `w` on `links`.
    #[must_use]
    pub fn link_twists(&self, links: &[usize], w: &[Wrench]) -> Vec<Twist> {
        let d = self.deflection(links, w);
        self.jacobians
            .iter()
            .map(|j| {
                Twist::from_array(core::array::from_fn(|r| {
                    (0..d.len()).map(|c| j[(r, c)] * d[c]).sum()
                }))
            })
            .collect()
    }

    /// Joint-space mass matrix `M_q = Σ_l J_lᵀ I_l J_l` (ndof × ndof), body inertias in link
    /// frames.
    #[must_use]
    pub fn joint_mass_matrix(&self, m: &Mechanism) -> Mat<f64> {
        let ndof = self.joint_compliance.nrows();
        let mut mq = Mat::<f64>::zeros(ndof, ndof);
        for (l, j) in self.jacobians.iter().enumerate() {
            let i6 = m.links[l].inertia.to_mat6().to_rows();
            let i6 = Mat::from_fn(6, 6, |r, c| i6[r][c]);
            mq += j.transpose() * &i6 * j;
        }
        mq
    }

    /// Exact operational-space accelerability `J_E Z (Zᵀ M_q Z)⁻¹ Zᵀ J_Eᵀ` of `links`
    /// (the inverse of the end effectors' effective inertia, Khatib's Λ⁻¹).
    ///
    /// # Errors
    /// [`Error::LinearAlgebra`] if a factorisation fails.
    pub fn accelerability_of(
        &self,
        m: &Mechanism,
        links: &[usize],
        tsvd: Tsvd,
    ) -> Result<Mat<f64>, Error> {
        let z = &self.null_space;
        let mz = z.transpose() * self.joint_mass_matrix(m) * z;
        let inv = pinv(mz.as_ref(), tsvd)?.inverse;
        let jz = self.stacked(links) * z;
        Ok(&jz * &inv * jz.transpose())
    }
}

/// The null space of the loop closure's Jacobian `g` (as [`crate::linalg::null_space`]) and
/// the report of its truncated SVD.
fn null_space_report(
    g: faer::MatRef<'_, f64>,
    tsvd: Tsvd,
) -> Result<(Mat<f64>, crate::rank::RankReport), Error> {
    let (m, n) = (g.nrows(), g.ncols());
    for j in 0..n {
        for i in 0..m {
            if !g[(i, j)].is_finite() {
                return Err(Error::LinearAlgebra(format!(
                    "entry ({i}, {j}) of the loop closure's Jacobian is not finite"
                )));
            }
        }
    }
    let svd = g
        .svd()
        .map_err(|e| Error::LinearAlgebra(format!("SVD of a {m}×{n} matrix: {e:?}")))?;
    let (s, v) = (svd.S(), svd.V());
    let k = m.min(n);
    let values: Vec<f64> = (0..k).map(|i| s[i]).collect();
    let sigma_max = values.iter().fold(0.0_f64, |a, &x| a.max(x));
    let threshold = tsvd.threshold(m, n, sigma_max);
    let r = values.iter().filter(|&&x| x > threshold).count();
    let z = Mat::from_fn(n, n - r, |i, j| v[(i, r + j)]);
    let report = crate::rank::RankReport::new(
        "loop closure G (its null space: the admissible joint motions)",
        (m, n),
        values,
        threshold,
        r,
    );
    Ok((z, report))
}
