//! Wrench maps (FORK⁻¹S §5.1–5.2, eqs. 15–20, Algorithm 2): how wrenches applied at the end
//! effectors are carried by every joint and link on their way to the base.
//!
//! Convention: the wrench a link **transmits** is the wrench its in-joints carry towards its
//! parents, i.e. the wrench the structure below it (its children and the loads on it) applies
//! to it, in its own body frame at the linearisation point. The wrench a joint carries is
//! expressed in its child's frame; its free components `Jᵀ w` are the joint's spring forces
//! `δθ/c`.
//!
//! - **Local map of a merge** (eqs. 16–17): a link k with m parents is m superimposed virtual
//!   links (eq. 13); the wrench ᵏw_k splits into virtual-link wrenches w_i with `Σ w_i = ᵏw_k`
//!   (eq. 15 in frame k, where every adjoint is the identity) and equal virtual-link twists
//!   `C w + Iᵀ λ = 0`, C the coupled compliance of the virtual links (the walk's `C_VV`, every
//!   earlier merge applied). The KKT matrix is inverted by truncated SVD (eq. 9), as the paper
//!   says: a loop with redundant constraints (planar hinges) has self-stress states the springs
//!   cannot decide; the minimum-norm split is taken. **Choice**: the compliance block is scaled
//!   to unit size before the SVD (it does not change the split, `λ` absorbs the scale), so that
//!   the threshold of eq. 9 judges compliance and identity blocks alike.
//! - **Chain** (eq. 18): a joint's wrench, moved to its parent's frame, is `ᶜAd_pᵀ w`.
//! - **Global map** (eq. 19): the product of local maps along every path from an end effector
//!   down to a link, summed over paths; Algorithm 2's recursion is run once, children before
//!   parents (reverse walk order), for all end effectors at once.
//! - **Internal wrench** (eq. 20): `ⁱw_i = Σ_e ⁱW_e ᵉw_e`.
//!
//! **Exactness.** The maps equal the joint wrenches of the full linearised statics on trees,
//! and on loops whose loads enter only through their merge link (a load below the merge of a
//! "Y" with a cross-bar, nested diamonds). Algorithm 2 sends an end effector's wrench only down
//! its own ancestors: when a loop also opens a path from an end effector that is not below its
//! merge (a ladder: a load at the top of one rail, whose rungs are children of the rails), the
//! maps miss the wrench that path carries (the rungs get none). Measured against the full
//! statics' spring forces under random loads: ladder-36 off by 4.4 times the largest spring
//! force, y-4 by 0.35, ring-10 exact (2e-15). Equilibrium still holds
//! everywhere: eq. 15 at every link, and the wrench reaching the base is the resultant of the
//! loads. The twist maps of [`crate::construct`] do not use these maps (they come exactly from
//! the walk's couplings), so the reduced dynamics are unaffected.

use faer::Mat;
use impulse_geom::{Mat6, Pose, Wrench};

use crate::construct::{all_columns, compliance_inputs};
use crate::error::Error;
use crate::linalg::{Tsvd, block, max_abs, pinv, set_block};
use crate::mechanism::Mechanism;
use crate::reference::kinematics::{Configuration, link_poses};
use crate::walk::{MergeBlocks, walk};

/// The wrench maps of a mechanism at one linearisation point.
#[derive(Clone, Debug)]
pub struct WrenchMaps {
    /// End-effector links, the columns of every map.
    pub end_effectors: Vec<usize>,
    /// Link poses at the linearisation point (world).
    pub poses: Vec<Pose>,
    /// Per joint, its local map (child frame to child frame): the share of the child's wrench
    /// this joint carries. The identity for a link's only in-joint; eq. 17's block for each
    /// in-joint of a merge.
    pub local: Vec<Mat6>,
    /// Per link and end effector, the global map `ˡW_e` (eq. 19): the wrench link l transmits
    /// (its frame) per body wrench at end effector e (e's frame). The base's map is the
    /// reaction the ground must supply.
    pub link: Vec<Vec<Mat6>>,
    /// Per joint and end effector, the wrench the joint carries (child frame) per body wrench
    /// at end effector e: `local_j · ᶜW_e`.
    pub joint: Vec<Vec<Mat6>>,
}

/// Local maps of one merge (eq. 17): block i maps the merged link's wrench to virtual link i's.
fn local_merge(merge: &MergeBlocks, tsvd: Tsvd) -> Result<Vec<Mat6>, Error> {
    let m = merge.joints.len();
    let n = 6 * m + 6;
    let mut kkt = Mat::<f64>::zeros(n, n);
    for (i, row) in merge.virtual_blocks.iter().enumerate() {
        for (k, b) in row.iter().enumerate() {
            set_block(&mut kkt, i, k, b);
        }
    }
    let size = max_abs(kkt.as_ref());
    if !(size.is_finite() && size > 0.0) {
        return Err(Error::LinearAlgebra(format!(
            "merge at link {}: virtual-link compliance of size {size}",
            merge.link
        )));
    }
    // Eq. 16: [C Iᵀ; I 0], C scaled to unit size and symmetrised against round-off.
    let kkt = Mat::from_fn(n, n, |r, c| {
        if r < 6 * m && c < 6 * m {
            0.5 * (kkt[(r, c)] + kkt[(c, r)]) / size
        } else if (r >= 6 * m && c < 6 * m && c % 6 == r - 6 * m)
            || (c >= 6 * m && r < 6 * m && r % 6 == c - 6 * m)
        {
            1.0
        } else {
            0.0
        }
    });
    // Eq. 17: the first m block rows of the last block column of the inverse.
    let inv = pinv(kkt.as_ref(), tsvd)?.inverse;
    Ok((0..m).map(|i| block(inv.as_ref(), i, m)).collect())
}

impl WrenchMaps {
    /// Builds the wrench maps of `m` at configuration `q` (which must close every loop: the
    /// rest pose or a [`crate::reference::StaticSolution`]), truncating every SVD by `tsvd`.
    ///
    /// # Errors
    /// [`Error::Argument`] when `q` does not fit `m` or is not finite;
    /// [`Error::LinearAlgebra`] when a factorisation fails.
    pub fn build(m: &Mechanism, q: &Configuration, tsvd: Tsvd) -> Result<Self, Error> {
        if q.theta.len() != m.ndof {
            return Err(Error::Argument(format!(
                "configuration has {} joint coordinates, mechanism `{}` has {}",
                q.theta.len(),
                m.name,
                m.ndof
            )));
        }
        if !q.theta.iter().all(|x| x.is_finite()) || !q.base.is_finite() {
            return Err(Error::Argument(format!(
                "configuration of `{}` is not finite",
                m.name
            )));
        }
        let poses = link_poses(m, q);
        let walked = walk(m, &poses, &compliance_inputs(m, &all_columns(m, q)), tsvd)?;
        let mut local = vec![Mat6::IDENTITY; m.joints.len()];
        for merge in &walked.merges {
            for (&ji, w) in merge.joints.iter().zip(local_merge(merge, tsvd)?) {
                local[ji] = w;
            }
        }

        // Algorithm 2, all end effectors at once: children before parents.
        let ne = m.end_effectors.len();
        let mut link = vec![vec![Mat6::ZERO; ne]; m.links.len()];
        for (i, &e) in m.end_effectors.iter().enumerate() {
            link[e][i] = Mat6::IDENTITY;
        }
        let mut joint = vec![vec![Mat6::ZERO; ne]; m.joints.len()];
        for &c in m.order.iter().rev() {
            for &ji in &m.joints_in[c] {
                let p = m.joints[ji].parent;
                // Eq. 18: ᵖW_c = ᶜAd_pᵀ, with ᶜAd_p taking p's twists to c's frame.
                let to_parent = (poses[c].inverse() * poses[p]).adjoint().transpose();
                for i in 0..ne {
                    let carried = local[ji] * link[c][i];
                    joint[ji][i] = carried;
                    // Eq. 19 as a sum over paths (Algorithm 2's recursion, one step).
                    link[p][i] = link[p][i] + to_parent * carried;
                }
            }
        }
        Ok(WrenchMaps {
            end_effectors: m.end_effectors.clone(),
            poses,
            local,
            link,
            joint,
        })
    }

    fn check(&self, w: &[Wrench], index: usize, count: usize, what: &str) -> Result<(), Error> {
        if w.len() != self.end_effectors.len() {
            return Err(Error::Argument(format!(
                "{} end-effector wrenches given, the mechanism has {} end effectors",
                w.len(),
                self.end_effectors.len()
            )));
        }
        if !w.iter().all(Wrench::is_finite) {
            return Err(Error::Argument("end-effector wrench is not finite".into()));
        }
        if index >= count {
            return Err(Error::Argument(format!(
                "{what} {index} out of range (the mechanism has {count})"
            )));
        }
        Ok(())
    }

    fn apply(maps: &[Mat6], w: &[Wrench]) -> Wrench {
        maps.iter()
            .zip(w)
            .fold(Wrench::ZERO, |acc, (map, we)| acc + map.mul_wrench(we))
    }

    /// The wrench link `l` transmits to its parents under end-effector body wrenches `w` (one
    /// per end effector, in their order), in l's frame (eq. 20).
    ///
    /// # Errors
    /// [`Error::Argument`] for a wrong count, a non-finite wrench or an unknown link.
    pub fn link_wrench(&self, l: usize, w: &[Wrench]) -> Result<Wrench, Error> {
        self.check(w, l, self.link.len(), "link")?;
        Ok(Self::apply(&self.link[l], w))
    }

    /// The wrench joint `j` carries under end-effector body wrenches `w`, in its child's frame.
    ///
    /// # Errors
    /// As [`WrenchMaps::link_wrench`], for an unknown joint.
    pub fn joint_wrench(&self, j: usize, w: &[Wrench]) -> Result<Wrench, Error> {
        self.check(w, j, self.joint.len(), "joint")?;
        Ok(Self::apply(&self.joint[j], w))
    }

    /// The wrench joint `j` of `m` passes to its parent, in the parent's frame (eq. 18).
    ///
    /// # Errors
    /// As [`WrenchMaps::joint_wrench`].
    pub fn parent_wrench(&self, m: &Mechanism, j: usize, w: &[Wrench]) -> Result<Wrench, Error> {
        let carried = self.joint_wrench(j, w)?;
        let joint = m
            .joints
            .get(j)
            .ok_or_else(|| Error::Argument(format!("joint {j} is not a joint of `{}`", m.name)))?;
        let (p, c) = (joint.parent, joint.child);
        if p.max(c) >= self.poses.len() {
            return Err(Error::Argument(format!(
                "joint {j} of `{}` does not fit these maps",
                m.name
            )));
        }
        let to_parent = (self.poses[c].inverse() * self.poses[p])
            .adjoint()
            .transpose();
        Ok(to_parent.mul_wrench(&carried))
    }
}

#[cfg(test)]
#[path = "wrench_tests.rs"]
mod tests;
