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
use crate::linalg::{Tsvd, null_space, pinv};
use crate::mechanism::Mechanism;
use crate::reference::kinematics::{Configuration, body_jacobian, link_poses, loop_jacobian};

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
        let (z, joint_compliance) = if nl == 0 {
            // A tree: Z = I and C_θ = diag(c).
            (
                Mat::<f64>::identity(m.ndof, m.ndof),
                Mat::from_fn(m.ndof, m.ndof, |a, b| if a == b { c[a] } else { 0.0 }),
            )
        } else {
            let z = null_space(g.as_ref(), tsvd)?;
            // Zᵀ K_q Z, symmetric positive definite (K_q is).
            let kz_half = Mat::from_fn(m.ndof, z.ncols(), |i, a| z[(i, a)] / c[i].sqrt());
            let kz = kz_half.transpose() * &kz_half;
            let cz = pinv(kz.as_ref(), tsvd)?.inverse;
            let jc = &z * &cz * z.transpose();
            (z, jc)
        };
        Ok(LinearStatics {
            config: q.clone(),
            poses,
            jacobians,
            null_space: z,
            joint_compliance,
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
