//! The incremental walk of FORK⁻¹S §4 (Algorithm 1: chain, split, merge) that projects a
//! joint-space quantity — compliance `C_θ`, accelerability `A_θ`, or damping compliance `D_θ⁻¹`
//! — onto the links, base first.
//!
//! The walk visits links in [`Mechanism::order`] (every link after all its parents) and keeps
//! the coupled matrix of eq. 11 between every visited link and every **active** link (one that
//! still has unvisited children, or is an end effector):
//!
//! - **chain** (eq. 10): a link c with one parent p through joint j gets
//!   `C_cc = J C_θ Jᵀ + ᶜAdₚ C_pp ᶜAdₚᵀ`, and every visited link d the coupling
//!   `C_dc = C_dp ᶜAdₚᵀ` (eq. 12: split siblings meet through their lowest common ancestor);
//! - **merge** (eqs. 13–14): a link with m parents is m superimposed virtual links, each chained
//!   to its parent; welding them together (`φ_1 = … = φ_m`, constraint `B φ_V = 0`) gives the
//!   constrained matrix `C' = C − C Bᵀ (B C_VV Bᵀ)⁺ B C` for every pair of visited links. Its
//!   block at the merged link is `(𝟙 K 𝟙ᵀ)⁻¹` of eq. 14 when `C_VV` is invertible; written in
//!   compliance form it needs only one truncated SVD (eq. 9) of the 6(m−1)-square `B C_VV Bᵀ`,
//!   which is singular exactly when the loop has redundant constraints (planar loops of
//!   hinges).
//!
//! **Choice beyond the paper.** The paper's walk updates only the merged link; the stiffening
//! a loop brings to links visited earlier (a rung of a ladder stiffens both rails) is lost for
//! links that chain on from them. Updating every stored coupling at a merge keeps the result
//! equal to the Schur complement of the full linearised statics for any DAG walkable from the
//! base (checked against it in the tests), at a cost of O(visited × active) 6×6 products per
//! merge.

use faer::Mat;
use impulse_geom::{Mat6, Pose};

use crate::error::Error;
use crate::linalg::{Tsvd, pinv_scaled};
use crate::mechanism::Mechanism;

/// The result of a walk: coupled blocks between every link and every end effector.
#[derive(Clone, Debug)]
pub struct WalkResult {
    /// Per link, the coupled block with each end effector (`C_{l,e}`, in `end_effectors`
    /// order; link frame rows, end-effector frame columns).
    pub to_end_effectors: Vec<Vec<Mat6>>,
    /// Per link, its own block `C_ll`.
    pub diagonal: Vec<Mat6>,
    /// Largest entry of any block formed before a constraint was applied: the size of the
    /// round-off the results carry (the `scale` of [`crate::linalg::pinv_scaled`]).
    pub scale: f64,
    /// Every merge met, in walk order: the coupled matrix of its virtual links just before
    /// they were welded (the `C` of eq. 16).
    pub merges: Vec<MergeBlocks>,
}

/// The virtual links of one merge (eq. 13) as the walk saw them before welding them.
#[derive(Clone, Debug)]
pub struct MergeBlocks {
    /// The merged link.
    pub link: usize,
    /// The joints into it (one virtual link each), in [`Mechanism::joints_in`] order.
    pub joints: Vec<usize>,
    /// `C_VV`: block (i, k) couples virtual links i and k (merged link's frame, eqs. 10, 12),
    /// every earlier merge applied.
    pub virtual_blocks: Vec<Vec<Mat6>>,
    /// The truncated SVD of the weld's `B C_VV Bᵀ` (eqs. 13–14 in compliance form): its
    /// dropped singular values are the loop's redundant constraints.
    pub report: crate::rank::RankReport,
}

/// Per-joint input of the walk: the joint's body-frame motion columns in the child frame
/// (`J = Ad(Q)·S(θ)`, 6 × dof) and its joint-space matrix (dof × dof, symmetric PSD).
pub struct JointInput {
    /// Motion columns (6 × dof).
    pub columns: Mat<f64>,
    /// Joint-space matrix (dof × dof).
    pub matrix: Mat<f64>,
}

/// `J X Jᵀ` as a 6×6 block.
fn congruence(j: &JointInput) -> Mat6 {
    let m = &j.columns * &j.matrix * j.columns.transpose();
    Mat6::from_rows(core::array::from_fn(|r| {
        core::array::from_fn(|c| m[(r, c)])
    }))
}

struct State {
    /// rows[d][s]: block between visited link d and the active link in slot s.
    rows: Vec<Vec<Mat6>>,
    diagonal: Vec<Mat6>,
    slot_of: Vec<Option<usize>>,
    free: Vec<usize>,
    slots: usize,
    visited: Vec<usize>,
    active: Vec<usize>,
    scale: f64,
}

impl State {
    fn allocate(&mut self, link: usize) -> usize {
        let s = if let Some(s) = self.free.pop() {
            s
        } else {
            self.slots += 1;
            for &d in &self.visited {
                self.rows[d].push(Mat6::ZERO);
            }
            self.slots - 1
        };
        self.slot_of[link] = Some(s);
        self.active.push(link);
        s
    }

    fn retire(&mut self, link: usize) {
        if let Some(s) = self.slot_of[link].take() {
            self.free.push(s);
            self.active.retain(|&a| a != link);
        }
    }

    fn block(&self, d: usize, a: usize) -> Mat6 {
        self.rows[d][self.slot_of[a].expect("active link has a slot")]
    }
}

/// Runs the walk on `m` at link poses `poses` with per-joint inputs `joints`.
///
/// # Errors
/// [`Error::LinearAlgebra`] if a merge's truncated SVD fails.
pub fn walk(
    m: &Mechanism,
    poses: &[Pose],
    joints: &[JointInput],
    tsvd: Tsvd,
) -> Result<WalkResult, Error> {
    let n = m.links.len();
    let mut pending: Vec<usize> = m.joints_out.iter().map(Vec::len).collect();
    let mut st = State {
        rows: vec![Vec::new(); n],
        diagonal: vec![Mat6::ZERO; n],
        slot_of: vec![None; n],
        free: Vec::new(),
        slots: 0,
        visited: Vec::with_capacity(n),
        active: Vec::new(),
        scale: 0.0,
    };
    let mut merges = Vec::new();
    // The base: zero compliance relative to itself.
    st.visited.push(m.base);
    if pending[m.base] > 0 {
        st.allocate(m.base);
    }

    for &c in &m.order[1..] {
        let ins = &m.joints_in[c];
        let inv_c = poses[c].inverse();
        // Virtual links (one per joint into c): adjoint from parent to c and joint block.
        let virt: Vec<(usize, Mat6, Mat6)> = ins
            .iter()
            .map(|&ji| {
                let p = m.joints[ji].parent;
                let x = (inv_c * poses[p]).adjoint();
                (p, x, congruence(&joints[ji]))
            })
            .collect();
        let nv = virt.len();
        // C_{d, v_i} for every visited d (eq. 12 through the parent).
        let cdv: Vec<Vec<Mat6>> = st
            .visited
            .iter()
            .map(|&d| {
                virt.iter()
                    .map(|(p, x, _)| st.block(d, *p) * x.transpose())
                    .collect()
            })
            .collect();
        // C_{v_i, v_k} (eq. 10 on the diagonal, eq. 12 off it).
        let cvv: Vec<Vec<Mat6>> = virt
            .iter()
            .enumerate()
            .map(|(i, (pi, xi, ji))| {
                virt.iter()
                    .enumerate()
                    .map(|(k, (pk, xk, _))| {
                        let b = *xi * st.block(*pi, *pk) * xk.transpose();
                        if i == k { b + *ji } else { b }
                    })
                    .collect()
            })
            .collect();

        for (i, row) in cvv.iter().enumerate() {
            st.scale = st.scale.max(row[i].max_abs_diff(&Mat6::ZERO));
        }
        let (col, cc) = if nv == 1 {
            // Chain (eq. 10).
            (cdv.iter().map(|v| v[0]).collect::<Vec<_>>(), cvv[0][0])
        } else {
            let (welded, report) = merge(&mut st, &cdv, &cvv, tsvd)?;
            merges.push(MergeBlocks {
                link: c,
                joints: ins.clone(),
                virtual_blocks: cvv,
                report: crate::rank::RankReport::new(
                    format!("merge at link `{}` (B·C_VV·Bᵀ)", m.links[c].name),
                    (report.singular.len(), report.singular.len()),
                    report.singular,
                    report.threshold,
                    report.rank,
                ),
            });
            welded
        };

        for &ji in ins {
            let p = m.joints[ji].parent;
            pending[p] -= 1;
        }
        // New link's row against the active links, then its own slot if it stays active.
        let mut row = vec![Mat6::ZERO; st.slots];
        for (vi, &d) in st.visited.iter().enumerate() {
            if let Some(s) = st.slot_of[d] {
                row[s] = col[vi].transpose();
            }
        }
        st.rows[c] = row;
        st.diagonal[c] = cc;
        let stays = pending[c] > 0 || m.end_effectors.contains(&c);
        for &ji in ins {
            let p = m.joints[ji].parent;
            if pending[p] == 0 && !m.end_effectors.contains(&p) {
                st.retire(p);
            }
        }
        st.visited.push(c);
        if stays {
            let s = st.allocate(c);
            for (vi, &d) in st.visited[..st.visited.len() - 1].iter().enumerate() {
                st.rows[d][s] = col[vi];
            }
            st.rows[c][s] = cc;
        }
    }

    let to_end_effectors = (0..n)
        .map(|l| {
            m.end_effectors
                .iter()
                .map(|&e| {
                    if st.rows[l].is_empty() {
                        Mat6::ZERO
                    } else {
                        st.block(l, e)
                    }
                })
                .collect()
        })
        .collect();
    Ok(WalkResult {
        to_end_effectors,
        diagonal: st.diagonal,
        scale: st.scale,
        merges,
    })
}

/// The merge of eqs. 13–14 in compliance form: welds the virtual links together and updates
/// every stored coupling. Returns the merged link's column against the visited links and its
/// own block, and the truncated SVD of the weld.
fn merge(
    st: &mut State,
    cdv: &[Vec<Mat6>],
    cvv: &[Vec<Mat6>],
    tsvd: Tsvd,
) -> Result<((Vec<Mat6>, Mat6), crate::linalg::Pinv), Error> {
    let nv = cvv.len();
    let k = nv - 1;
    // u_x = C_{x,V} Bᵀ with B's row block r: φ_{v0} − φ_{v(r+1)}.
    let u = |c: &[Mat6]| -> Vec<Mat6> { (0..k).map(|r| c[0] - c[r + 1]).collect() };
    let u_vis: Vec<Vec<Mat6>> = cdv.iter().map(|c| u(c)).collect();
    let u_v: Vec<Vec<Mat6>> = cvv.iter().map(|c| u(c)).collect();
    // S = B C_VV Bᵀ: block (r, s) = u_{v0}[s] − u_{v(r+1)}[s].
    let mut s = Mat::<f64>::zeros(6 * k, 6 * k);
    for (r, ur) in u_v[1..].iter().enumerate() {
        for (c, (a, b)) in u_v[0].iter().zip(ur).enumerate() {
            crate::linalg::set_block(&mut s, r, c, &(*a - *b));
        }
    }
    // Symmetrise against round-off before the SVD.
    let s = Mat::from_fn(6 * k, 6 * k, |i, j| 0.5 * (s[(i, j)] + s[(j, i)]));
    let weld = pinv_scaled(s.as_ref(), tsvd, st.scale)?;
    let p = &weld.inverse;
    let pb: Vec<Vec<Mat6>> = (0..k)
        .map(|r| {
            (0..k)
                .map(|c| crate::linalg::block(p.as_ref(), r, c))
                .collect()
        })
        .collect();
    // y_x = u_x P (block row).
    let times_p = |ux: &[Mat6]| -> Vec<Mat6> {
        (0..k)
            .map(|c| (0..k).fold(Mat6::ZERO, |acc, r| acc + ux[r] * pb[r][c]))
            .collect()
    };
    // y_x u_zᵀ.
    let corr = |yx: &[Mat6], uz: &[Mat6]| -> Mat6 {
        (0..k).fold(Mat6::ZERO, |acc, r| acc + yx[r] * uz[r].transpose())
    };
    let y_vis: Vec<Vec<Mat6>> = u_vis.iter().map(|ux| times_p(ux)).collect();
    let y_v0 = times_p(&u_v[0]);

    // The merged link (virtual link 0 after welding).
    let col: Vec<Mat6> = (0..cdv.len())
        .map(|d| cdv[d][0] - corr(&y_vis[d], &u_v[0]))
        .collect();
    let cc = cvv[0][0] - corr(&y_v0, &u_v[0]);

    // Every stored coupling between visited links and active links, and every diagonal.
    let active_pos: Vec<(usize, usize)> = st
        .active
        .iter()
        .map(|&a| {
            let vi = st
                .visited
                .iter()
                .position(|&d| d == a)
                .expect("active is visited");
            (vi, st.slot_of[a].expect("active has a slot"))
        })
        .collect();
    for (di, &d) in st.visited.iter().enumerate() {
        for &(ai, slot) in &active_pos {
            let delta = corr(&y_vis[di], &u_vis[ai]);
            st.rows[d][slot] = st.rows[d][slot] - delta;
        }
        let dd = corr(&y_vis[di], &u_vis[di]);
        st.diagonal[d] = st.diagonal[d] - dd;
    }
    Ok(((col, cc), weld))
}
