//! Construction of a FORK⁻¹S model (§3–5) at one linearisation point: the coupled compliance,
//! accelerability and damping of the end effectors, their inverses by truncated SVD with the
//! rank checked, and the twist maps of the internal links.

use faer::Mat;
use impulse_geom::{Mat6, Pose, SpatialInertia, Twist, Wrench};

use crate::error::Error;
use crate::linalg::{Pinv, Tsvd, pinv, pinv_rank, to_faer};
use crate::mechanism::Mechanism;
use crate::rank::{
    Conditioning, Diagnostics, DroppedDirection, RankReport, RankWarning, compliance_rank,
    constrain, factored_inverse, motion_rank,
};
use crate::reference::kinematics::{Configuration, joint_jacobian, link_poses};
use crate::reference::{JointMatrix, LinearStatics, Load};
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
    /// Every rank decision of the construction, the directions treated as rigid, the
    /// conditioning and the warnings ([`crate::rank`]).
    pub diagnostics: Diagnostics,
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

impl ReducedModel {
    /// The stacked end-effector body wrenches (6|E|, linear on top, each in its end
    /// effector's axes at the reference pose) of world loads on end effectors: what
    /// [`ReducedModel::static_twists`] and the reduced dynamics take. Loads on one link add.
    ///
    /// # Errors
    /// The index of the first loaded link that is not an end effector.
    pub fn end_effector_wrenches(&self, loads: &[Load]) -> Result<Vec<f64>, usize> {
        let mut w = vec![0.0; 6 * self.end_effectors.len()];
        for l in loads {
            let i = self
                .end_effectors
                .iter()
                .position(|&e| e == l.link)
                .ok_or(l.link)?;
            let b = l.body_wrench(&self.reference[i]).to_array();
            for (wr, br) in w[6 * i..6 * i + 6].iter_mut().zip(b) {
                *wr += br;
            }
        }
        Ok(w)
    }

    /// Builds the model of `m` linearised at configuration `q` (which must close every loop: the
    /// rest pose, or a [`crate::reference::StaticSolution`]); `loads` are the loads that hold
    /// `q` in equilibrium (empty at rest), kept as the bias `b`.
    ///
    /// The rank of the end-effector maps is decided on the joints' compliance-weighted
    /// motions at the threshold of `options.tsvd` and every decision is reported in
    /// [`ReducedModel::diagnostics`] ([`crate::rank`]).
    ///
    /// # Errors
    /// [`Error::Unresolved`] when the threshold keeps a direction whose compliance the walk
    /// cannot resolve; [`Error::Rank`] when the accelerability or damping do not have the
    /// compliance's rank; [`Error::LinearAlgebra`] when a factorisation fails.
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
        let mut maps = Vec::new();

        // The rank of the end-effector maps, from the joints' compliance-weighted motions
        // W = J_E F (σ(C) = σ(W)²; see crate::rank): the full linearised statics.
        let lin = LinearStatics::new(m, q, tsvd)?;
        let je_size = crate::linalg::max_abs(lin.stacked(ee).as_ref());
        let c_size = m
            .joints
            .iter()
            .flat_map(|j| j.compliance.iter())
            .fold(0.0_f64, |a, &c| a.max(c));
        let cw = walk(m, &poses, &compliance_inputs(m, &cols), tsvd)?;
        let w = lin.weighted_motions(ee);
        let (rank, allowed, w_report) = motion_rank(&w, tsvd, je_size * c_size.sqrt(), cw.scale)?;
        maps.push(w_report.clone());
        maps.extend(lin.closure_report.iter().cloned());

        // Compliance (eqs. 10–14), truncated at that rank if the walk resolves it; its
        // measured round-off is its difference from the Schur complement J_E C_θ J_Eᵀ.
        maps.extend(cw.merges.iter().map(|b| b.report.clone()));
        let compliance = symmetrise(&stack(&cw.to_end_effectors, ee));
        let schur = lin.compliance_of(ee);
        let error = frobenius(&(&compliance - &schur));
        let (stiffness, c_report) = compliance_rank(&compliance, rank, tsvd, error)?;
        // The directions the joints allow but the threshold drops, from W (accurate; C's own
        // eigenvectors of its null space are tilted by its round-off over its small
        // eigenvalues), as columns: held rigid in A and D.
        let dropped = dropped_directions(&w, rank, allowed)?;
        let rigid = Mat::from_fn(6 * ne, dropped.len(), |r, k| dropped[k].twist[r]);
        maps.push(c_report.clone());

        // Accelerability (eq. 7, or exact), constrained to the directions C keeps (the
        // dropped ones are rigid: Gauss's principle, crate::rank::constrain).
        let (accelerability, mass, a_report) = match options.mass {
            MassModel::Exact => {
                // A = V Vᵀ, V = J_E Z (Zᵀ M_q Z)^(−½): inverted from V's SVD (rank.rs).
                let mq = lin.joint_mass_matrix(m);
                let v = lin.factor_motions(ee, JointMatrix::Dense(&mq))?;
                factored_inverse(
                    &v,
                    &rigid,
                    rank,
                    "end-effector accelerability A (C's rigid directions held)",
                )?
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
                let a = constrain(&symmetrise(&stack(&aw.to_end_effectors, ee)), &rigid, tsvd)?;
                let mp = pinv_rank(
                    a.as_ref(),
                    rank,
                    tsvd,
                    aw.scale,
                    tol::RANK_GAP,
                    "end-effector accelerability (eq. 7)",
                )?;
                let r = report(
                    "end-effector accelerability A, eq. 7 (C's rigid directions held)",
                    &mp,
                );
                (a, mp.inverse, r)
            }
        };
        maps.push(a_report.clone());

        // Damping: "the same projection" (§3.1), `J_E Z (Zᵀ D_q Z)⁻¹ Zᵀ J_Eᵀ` in factored form
        // (as the accelerability), inverted at the compliance's rank.
        let damped = m.joints.iter().any(|j| j.damping.iter().any(|&d| d > 0.0));
        let damping = if damped {
            let d: Vec<f64> = m
                .joints
                .iter()
                .flat_map(|j| j.damping.iter().copied())
                .collect();
            let v = lin.factor_motions(ee, JointMatrix::Diagonal(&d))?;
            let (_, dmat, r) = factored_inverse(
                &v,
                &rigid,
                rank,
                "end-effector damping compliance D⁺ (C's rigid directions held)",
            )?;
            maps.push(r);
            dmat
        } else {
            Mat::zeros(6 * ne, 6 * ne)
        };

        let diagnostics = diagnose(
            maps, &w_report, &c_report, &a_report, allowed, rank, dropped, error, tsvd,
        )?;

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
            stiffness: symmetrise(&stiffness),
            compliance,
            accelerability: symmetrise(&accelerability),
            mass: symmetrise(&mass),
            damping: symmetrise(&damping),
            rank,
            bias,
            internal_reference: internal.iter().map(|&l| poses[l]).collect(),
            internal,
            twist_maps,
            base_inertia,
            base_pose,
            diagnostics,
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

/// `‖a‖_F`.
fn frobenius(a: &Mat<f64>) -> f64 {
    let mut s = 0.0;
    for j in 0..a.ncols() {
        for i in 0..a.nrows() {
            s += a[(i, j)] * a[(i, j)];
        }
    }
    s.sqrt()
}

/// The report of a [`Pinv`] of a square map.
fn report(map: &str, p: &Pinv) -> RankReport {
    let n = p.singular.len();
    RankReport::new(map, (n, n), p.singular.clone(), p.threshold, p.rank)
}

/// The directions the joints allow but the threshold drops: W's left singular vectors past
/// `rank` up to `allowed`, with their relative compliance `(σ/σ₁)²`.
fn dropped_directions(
    w: &Mat<f64>,
    rank: usize,
    allowed: usize,
) -> Result<Vec<DroppedDirection>, Error> {
    let mut dropped = Vec::new();
    if allowed > rank {
        let svd = w
            .thin_svd()
            .map_err(|e| Error::LinearAlgebra(format!("SVD of J_E·F: {e:?}")))?;
        let (s, u) = (svd.S(), svd.U());
        let mut idx: Vec<usize> = (0..s.dim()).collect();
        idx.sort_by(|&a, &b| s[b].total_cmp(&s[a]));
        let largest = s[idx[0]];
        for &i in &idx[rank..allowed] {
            dropped.push(DroppedDirection {
                compliance: (s[i] / largest).powi(2),
                twist: (0..w.nrows()).map(|r| u[(r, i)]).collect(),
            });
        }
    }
    Ok(dropped)
}

/// The diagnostics of a construction: the maps' reports, the directions treated as rigid,
/// conditioning and warnings.
#[allow(clippy::too_many_arguments)]
fn diagnose(
    maps: Vec<RankReport>,
    w_report: &RankReport,
    c_report: &RankReport,
    a_report: &RankReport,
    allowed: usize,
    rank: usize,
    dropped: Vec<DroppedDirection>,
    error: f64,
    tsvd: Tsvd,
) -> Result<Diagnostics, Error> {
    let largest_c = c_report.largest();
    let compliance_error = if largest_c > 0.0 {
        error / largest_c
    } else {
        0.0
    };
    let conditioning = Conditioning {
        compliance_condition: c_report.condition(),
        compliance_error,
        stiffness_error: c_report.condition() * compliance_error,
        accelerability_condition: a_report.condition(),
    };
    let mut warnings = Vec::new();
    // The end-effector cut, judged on W (accurate): C's gap is W's squared.
    let w_gap = w_report.gap().powi(2);
    if w_gap > tol::RANK_GAP {
        warnings.push(RankWarning::SmallGap {
            map: c_report.map.clone(),
            rank,
            gap: w_gap,
        });
    }
    // The walk's internal cuts (loop closure, merges): a dropped singular value near the kept.
    for r in &maps {
        let internal = r.map.starts_with("merge") || r.map.starts_with("loop closure");
        if internal && r.rank > 0 && r.rank < r.singular.len() && r.gap() > tol::RANK_GAP {
            warnings.push(RankWarning::SmallGap {
                map: r.map.clone(),
                rank: r.rank,
                gap: r.gap(),
            });
        }
    }
    if let Some(d) = dropped.first() {
        warnings.push(RankWarning::NearSingular {
            allowed,
            rank,
            largest_dropped: d.compliance,
        });
    }
    if conditioning.stiffness_error > tol::STIFFNESS_ACCURACY_WARN {
        warnings.push(RankWarning::IllConditioned {
            condition: conditioning.compliance_condition,
            accuracy: conditioning.stiffness_error,
        });
    }
    Ok(Diagnostics {
        relative_threshold: tsvd.relative_threshold(c_report.rows, c_report.rows),
        allowed,
        maps,
        dropped,
        conditioning,
        warnings,
    })
}

#[cfg(test)]
#[path = "construct_tests.rs"]
mod tests;
