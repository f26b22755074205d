//! Construction of a FORK⁻¹S model (§3–5) at one linearisation point: the coupled compliance,
//! accelerability and damping of the end effectors, their inverses by truncated SVD with the
//! rank checked, and the twist maps of the internal links.

use faer::Mat;
use impulse_geom::{Mat6, Pose, SpatialInertia, Twist, Wrench};

use crate::error::Error;
use crate::linalg::{Tsvd, null_space, pinv, pinv_rank, rank_scaled, to_faer};
use crate::mechanism::Mechanism;
use crate::reference::kinematics::{
    Configuration, body_jacobian, joint_jacobian, link_poses, loop_jacobian,
};
use crate::reference::{LinearStatics, Load};
use crate::tol;
use crate::walk::{JointInput, walk};

/// How the end effectors' inertia is obtained.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub enum MassModel {
    /// The exact operational-space accelerability `J_E Z (Zᵀ M_q Z)⁻¹ Zᵀ J_Eᵀ` (Khatib's Λ⁻¹,
    /// projected on the loop-closure null space).
    #[default]
    Exact,
    /// The paper's projection (eq. 7): the walk of eqs. 10–14 run on a joint accelerability
    /// `A_θ = (Jᵀ I_c J)⁺`, the inverse of the child link's own inertia about the joint.
    Paper,
}

/// Settings of [`ReducedModel::build`].
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct ConstructOptions {
    /// Truncation of every SVD (eq. 9).
    pub tsvd: Tsvd,
    /// Source of the end-effector inertia.
    pub mass: MassModel,
}

/// One FORK⁻¹S model: the reduced end-effector system of eq. 8 / eq. 24 and the twist maps.
///
/// Layout: end-effector vectors are stacked 6-blocks in `end_effectors` order (body frames of
/// the end effectors at the reference poses, linear on top). `twist_maps` is contiguous:
/// internal link k (of `internal`) owns the **column-major** 6 × 6|E| block starting at
/// `k · 36|E|` (each column's six twist components adjacent, so the product with the stacked
/// end-effector wrench is six independent running sums), mapping the stacked end-effector
/// wrench to the link's body twist (eq. 22).
#[derive(Clone, Debug)]
pub struct ReducedModel {
    /// The linearisation point.
    pub config: Configuration,
    /// End-effector links.
    pub end_effectors: Vec<usize>,
    /// End-effector reference poses `H_e` (world).
    pub reference: Vec<Pose>,
    /// Coupled compliance `C` (6|E| square, eqs. 10–14).
    pub compliance: Mat<f64>,
    /// Stiffness `K = C⁺` (truncated SVD).
    pub stiffness: Mat<f64>,
    /// Accelerability `A` (6|E| square).
    pub accelerability: Mat<f64>,
    /// Mass `M = A⁺`.
    pub mass: Mat<f64>,
    /// Damping `D` (zero when the joints are undamped).
    pub damping: Mat<f64>,
    /// Rank of `C` (admissible end-effector directions).
    pub rank: usize,
    /// Static equilibrium wrench `b` of the linearisation point (stacked body wrenches; zero at
    /// rest), the `b̄` of eq. 24.
    pub bias: Vec<f64>,
    /// Internal links (FORK⁻¹S's ℒ), in walk order.
    pub internal: Vec<usize>,
    /// Their reference poses (world).
    pub internal_reference: Vec<Pose>,
    /// Twist maps, contiguous (see the type's doc).
    pub twist_maps: Vec<f64>,
    /// Spatial inertia of the whole structure at the linearisation point, base frame (§6.1).
    pub base_inertia: SpatialInertia,
    /// Pose of the base at the linearisation point (world).
    pub base_pose: Pose,
}

fn stack(blocks: &[Vec<Mat6>], rows: &[usize]) -> Mat<f64> {
    let ne = blocks.first().map_or(0, Vec::len);
    let mut out = Mat::<f64>::zeros(6 * rows.len(), 6 * ne);
    for (i, &l) in rows.iter().enumerate() {
        for (j, b) in blocks[l].iter().enumerate() {
            crate::linalg::set_block(&mut out, i, j, b);
        }
    }
    out
}

fn symmetrise(a: &Mat<f64>) -> Mat<f64> {
    Mat::from_fn(a.nrows(), a.ncols(), |i, j| 0.5 * (a[(i, j)] + a[(j, i)]))
}

/// Motion columns `Ad(Q)·S(θ)` of joint `ji` in its child's frame (6 × dof).
fn columns(m: &Mechanism, q: &Configuration, ji: usize) -> Mat<f64> {
    let j = &m.joints[ji];
    let th = &q.theta[j.offset..j.offset + j.dof()];
    let cols = joint_jacobian(j, th);
    Mat::from_fn(6, cols.len(), |r, c| {
        j.in_child.transform_twist(&cols[c]).to_array()[r]
    })
}

/// Every joint's motion columns in its child's frame at `q` (see [`columns`]).
pub(crate) fn all_columns(m: &Mechanism, q: &Configuration) -> Vec<Mat<f64>> {
    (0..m.joints.len()).map(|ji| columns(m, q, ji)).collect()
}

/// The walk's input for the compliance: each joint's columns and `C_θ = diag(c)`.
pub(crate) fn compliance_inputs(m: &Mechanism, cols: &[Mat<f64>]) -> Vec<JointInput> {
    m.joints
        .iter()
        .zip(cols)
        .map(|(j, c)| JointInput {
            columns: c.clone(),
            matrix: Mat::from_fn(
                j.dof(),
                j.dof(),
                |a, b| {
                    if a == b { j.compliance[a] } else { 0.0 }
                },
            ),
        })
        .collect()
}

/// Rank of `J_E Z`: the end effectors' degrees of freedom counted from the joints.
fn expected_rank(
    m: &Mechanism,
    q: &Configuration,
    poses: &[Pose],
    tsvd: Tsvd,
) -> Result<usize, Error> {
    let nl = m.loop_joints.len();
    let mut g = Mat::<f64>::zeros(6 * nl, m.ndof);
    for (k, &ji) in m.loop_joints.iter().enumerate() {
        let gk = loop_jacobian(m, q, poses, ji);
        for c in 0..m.ndof {
            for r in 0..6 {
                g[(6 * k + r, c)] = gk[(r, c)];
            }
        }
    }
    let z = null_space(g.as_ref(), tsvd)?;
    let mut je = Mat::<f64>::zeros(6 * m.end_effectors.len(), m.ndof);
    for (i, &e) in m.end_effectors.iter().enumerate() {
        let j = body_jacobian(m, q, poses, e);
        for c in 0..m.ndof {
            for r in 0..6 {
                je[(6 * i + r, c)] = j[(r, c)];
            }
        }
    }
    // Judge J_E Z against the size of J_E itself: a locked mechanism has J_E Z ≈ round-off.
    let scale = crate::linalg::max_abs(je.as_ref());
    rank_scaled((je * z).as_ref(), tsvd, scale)
}

impl ReducedModel {
    /// Builds the model of `m` linearised at configuration `q` (which must close every loop: the
    /// rest pose, or a [`crate::reference::StaticSolution`]); `loads` are the loads that hold
    /// `q` in equilibrium (empty at rest), kept as the bias `b`.
    ///
    /// # Errors
    /// [`Error::Rank`] when the truncated SVD's rank of `C` disagrees with the rank of the
    /// joints' Jacobian `J_E Z`; [`Error::LinearAlgebra`] when a factorisation fails.
    pub fn build(
        m: &Mechanism,
        q: &Configuration,
        loads: &[Load],
        options: &ConstructOptions,
    ) -> Result<Self, Error> {
        let tsvd = options.tsvd;
        let poses = link_poses(m, q);
        let ee = &m.end_effectors;
        let ne = ee.len();
        let cols = all_columns(m, q);

        // Compliance (eqs. 10–14).
        let cw = walk(m, &poses, &compliance_inputs(m, &cols), tsvd)?;
        let compliance = symmetrise(&stack(&cw.to_end_effectors, ee));
        // Rank check: truncate C at the rank of J_E Z (the joints' count), and only if C's
        // spectrum has a clear gap there (eq. 9 threshold below, tol::RANK_GAP above).
        let expected = expected_rank(m, q, &poses, tsvd)?;
        let kp = pinv_rank(
            compliance.as_ref(),
            expected,
            tsvd,
            cw.scale,
            tol::RANK_GAP,
            "end-effector compliance",
        )?;

        // Accelerability (eq. 7, or exact).
        let (accelerability, accel_scale) = match options.mass {
            MassModel::Exact => {
                let lin = LinearStatics::new(m, q, tsvd)?;
                (symmetrise(&lin.accelerability_of(m, ee, tsvd)?), 0.0)
            }
            MassModel::Paper => {
                let inputs: Vec<JointInput> = m
                    .joints
                    .iter()
                    .zip(&cols)
                    .map(|(j, c)| {
                        let i6 = to_faer(&m.links[j.child].inertia.to_mat6());
                        let mj = c.transpose() * &i6 * c;
                        Ok(JointInput {
                            columns: c.clone(),
                            matrix: pinv(mj.as_ref(), tsvd)?.inverse,
                        })
                    })
                    .collect::<Result<_, Error>>()?;
                let aw = walk(m, &poses, &inputs, tsvd)?;
                (symmetrise(&stack(&aw.to_end_effectors, ee)), aw.scale)
            }
        };
        let mass = pinv_rank(
            accelerability.as_ref(),
            expected,
            tsvd,
            accel_scale,
            tol::RANK_GAP,
            "end-effector accelerability",
        )?
        .inverse;

        // Damping: the walk on the damping compliance D_θ⁻¹ ("the same projection", §3.1).
        let damped = m.joints.iter().any(|j| j.damping.iter().any(|&d| d > 0.0));
        let damping = if damped {
            let inputs: Vec<JointInput> = m
                .joints
                .iter()
                .zip(&cols)
                .map(|(j, c)| JointInput {
                    columns: c.clone(),
                    matrix: Mat::from_fn(j.dof(), j.dof(), |a, b| {
                        if a == b { 1.0 / j.damping[a] } else { 0.0 }
                    }),
                })
                .collect();
            let dw = walk(m, &poses, &inputs, tsvd)?;
            let dc = symmetrise(&stack(&dw.to_end_effectors, ee));
            pinv_rank(
                dc.as_ref(),
                expected,
                tsvd,
                dw.scale,
                tol::RANK_GAP,
                "end-effector damping",
            )?
            .inverse
        } else {
            Mat::zeros(6 * ne, 6 * ne)
        };

        // Twist maps (eq. 22): the coupled compliance between each internal link and the end
        // effectors.
        let internal = m.internal_links();
        let mut twist_maps = Vec::with_capacity(internal.len() * 36 * ne);
        for &l in &internal {
            for b in &cw.to_end_effectors[l] {
                let rows = b.to_rows();
                for c in 0..6 {
                    twist_maps.extend(rows.iter().map(|row| row[c]));
                }
            }
        }

        let bias = {
            let mut b = vec![0.0; 6 * ne];
            for load in loads {
                if let Some(i) = ee.iter().position(|&e| e == load.link) {
                    let w = load.body_wrench(&poses[load.link]).to_array();
                    for r in 0..6 {
                        b[6 * i + r] += w[r];
                    }
                }
            }
            b
        };
        let base_pose = poses[m.base];
        let inv_base = base_pose.inverse();
        let base_inertia = m
            .links
            .iter()
            .zip(&poses)
            .fold(SpatialInertia::ZERO, |acc, (l, p)| {
                acc + l.inertia.transform(&(inv_base * *p))
            });
        Ok(ReducedModel {
            config: q.clone(),
            end_effectors: ee.clone(),
            reference: ee.iter().map(|&e| poses[e]).collect(),
            stiffness: symmetrise(&kp.inverse),
            compliance,
            accelerability,
            mass: symmetrise(&mass),
            damping: symmetrise(&damping),
            rank: kp.rank,
            bias,
            internal_reference: internal.iter().map(|&l| poses[l]).collect(),
            internal,
            twist_maps,
            base_inertia,
            base_pose,
        })
    }

    /// The twist map of internal link number `k` (column-major 6 × 6|E|).
    #[must_use]
    pub fn twist_map(&self, k: usize) -> &[f64] {
        let w = 36 * self.end_effectors.len();
        &self.twist_maps[k * w..(k + 1) * w]
    }

    /// The static response of the reduced model to stacked end-effector body wrenches `w`
    /// (relative to the bias `b`): end-effector twists `C w` (eq. 5) and internal-link twists
    /// `Σ_e ⁱT_e ᵉw_e` (eq. 22), both body frames at the reference poses.
    #[must_use]
    pub fn static_twists(&self, w: &[f64]) -> (Vec<Twist>, Vec<Twist>) {
        let ne = self.end_effectors.len();
        let ee = (0..ne)
            .map(|i| {
                Twist::from_array(core::array::from_fn(|r| {
                    (0..6 * ne)
                        .map(|c| self.compliance[(6 * i + r, c)] * w[c])
                        .sum()
                }))
            })
            .collect();
        let internal = (0..self.internal.len())
            .map(|k| crate::internal::link_twist(self, k, w))
            .collect();
        (ee, internal)
    }

    /// Stacked end-effector wrench vector from per-end-effector body wrenches.
    #[must_use]
    pub fn stack_wrenches(w: &[Wrench]) -> Vec<f64> {
        w.iter().flat_map(|x| x.to_array()).collect()
    }
}

#[cfg(test)]
#[path = "construct_tests.rs"]
mod tests;
