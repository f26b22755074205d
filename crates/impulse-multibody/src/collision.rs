//! Multibody collision response pieces (thesis §5.3): the impulse-space articulated-body
//! recursion, the 3×3 collision matrix K of a contact point, propagation of a collision impulse
//! through the tree, and the SVD pseudo-inverse for rank-deficient K.

use faer::Mat;
use glam::{DMat3, DVec3};
use impulse_geom::{Twist, Wrench};

use crate::dynamics::{base_xform, joint_xform};
use crate::error::MultibodyError;
use crate::model::{BodyJoint, LinkId, Model, check_len};
use crate::spatial::{Sym6, Xform, rt_mul};

/// Per-body data of the impulse recursion.
#[derive(Clone, Copy, Debug)]
struct ImpBody {
    /// Body frame in its parent's frame.
    x: Xform,
    /// Body frame in the world.
    world: Xform,
    /// Articulated inertia Î^A (depends on q only, Theorem 19).
    ia: Sym6,
    /// U = Î^A ŝ.
    u: Wrench,
    /// 1 / (ŝ'Î^Aŝ).
    inv_d: f64,
}

/// The articulated inertias of a multibody at one configuration, ready to answer impulse
/// queries in O(depth) (K) or O(n) (propagation): thesis Fig. 5.11 step (A).
///
/// Î^A depends on q only, so the data must be refreshed with [`ImpulseDynamics::update`]
/// whenever q changes (at collision time, at the post-step state; the digest's hard case 7).
/// Contact points and frames may be given in world coordinates (the `*_world` methods) or in
/// the colliding link's frame.
#[derive(Clone, Debug)]
pub struct ImpulseDynamics {
    bodies: Vec<ImpBody>,
    floating: bool,
    /// Scratch: z.a. impulses Ŷ^A (non-zero on the path to the colliding body only).
    y: Vec<Wrench>,
    /// Scratch: velocity jumps Δv̂.
    dv: Vec<Twist>,
    /// Scratch: the path from the colliding body to the root.
    path: Vec<usize>,
}

impl ImpulseDynamics {
    /// Articulated inertias of `model` at configuration `q` (nq).
    ///
    /// # Errors
    /// [`MultibodyError::DimensionMismatch`] if `q` has the wrong length.
    pub fn new(model: &Model, q: &[f64]) -> Result<Self, MultibodyError> {
        let n = model.body_count();
        let zero = ImpBody {
            x: Xform::IDENTITY,
            world: Xform::IDENTITY,
            ia: Sym6::ZERO,
            u: Wrench::ZERO,
            inv_d: 0.0,
        };
        let mut s = ImpulseDynamics {
            bodies: vec![zero; n],
            floating: model.is_floating(),
            y: vec![Wrench::ZERO; n],
            dv: vec![Twist::ZERO; n],
            path: Vec::with_capacity(n),
        };
        s.update(model, q)?;
        Ok(s)
    }

    /// Recomputes the transforms and articulated inertias for configuration `q` (eq. 4.33
    /// without the z.a. forces). Allocation-free.
    ///
    /// # Errors
    /// [`MultibodyError::DimensionMismatch`] if `q` has the wrong length.
    pub fn update(&mut self, model: &Model, q: &[f64]) -> Result<(), MultibodyError> {
        check_len("q", model.nq(), q.len())?;
        assert_eq!(
            self.bodies.len(),
            model.body_count(),
            "built for another model"
        );
        let nb = model.first_joint_body();
        let qo = model.nq() - model.joint_count();
        for i in 0..model.body_count() {
            let body = &model.bodies[i];
            let x = if i < nb {
                base_xform(q)
            } else {
                joint_xform(
                    &body.origin,
                    body.joint,
                    body.axis_in_parent,
                    q[qo + i - nb],
                )
            };
            let world = match body.parent {
                Some(p) => self.bodies[p].world.compose(&x),
                None => x,
            };
            let b = &mut self.bodies[i];
            b.x = x;
            b.world = world;
            b.ia = body.inertia6;
        }
        for i in (nb..model.body_count()).rev() {
            let body = &model.bodies[i];
            let (head, tail) = self.bodies.split_at_mut(i);
            let b = &mut tail[0];
            b.u = axis_times(body.joint, &b.ia);
            b.inv_d = 1.0 / axis_dot(body.joint, &b.u);
            if let Some(p) = body.parent {
                // eq. (4.33)
                let ia = b.ia.minus_outer(&b.u, b.inv_d);
                head[p].ia.add_assign(&ia.to_parent(&b.x));
            }
        }
        Ok(())
    }

    /// The link exists and `self` was made for `model` (else a typed error, never a panic).
    fn check_link(&self, model: &Model, link: LinkId) -> Result<(), MultibodyError> {
        check_len(
            "impulse dynamics bodies",
            model.body_count(),
            self.bodies.len(),
        )?;
        if link.0 < model.link_count() {
            Ok(())
        } else {
            Err(MultibodyError::UnknownName {
                kind: "link",
                name: link.0.to_string(),
            })
        }
    }

    /// Body and offset of a link; `None` for links on the ground.
    fn locate(model: &Model, link: LinkId) -> Option<(usize, Xform)> {
        let info = &model.links[link.0];
        info.body.map(|b| (b, info.offset))
    }

    /// Upward pass of Figs. 5.7/5.10: Ŷ^A on the path from `k` to the root, eqs. (5.7)/(5.8).
    /// Leaves the path in `self.path` (from `k` up) and Ŷ^A in `self.y` for its bodies.
    fn za_impulses(&mut self, model: &Model, k: usize, p_coll: &Wrench) {
        self.path.clear();
        // (5.7) Ŷ_k^A = −p̂_coll (Lemma 8).
        let mut y = -*p_coll;
        let mut i = k;
        loop {
            self.path.push(i);
            self.y[i] = y;
            let Some(h) = model.bodies[i].parent else {
                break;
            };
            let b = &self.bodies[i];
            // (5.8) Ŷ_h^A = _hX̂_i [1 − Î^A ŝ ŝ'/(ŝ'Î^Aŝ)] Ŷ_i^A = X (Ŷ − U (ŝ'Ŷ)/D).
            let s_y = axis_dot(model.bodies[i].joint, &y);
            y = b.x.force_to_parent(&(y - b.u * (s_y * b.inv_d)));
            i = h;
        }
    }

    /// Velocity jump of the root of the path: zero under a fixed base, and
    /// `Δv̂_1 = −(Î_1^A)^{-1} Ŷ_1^A` for a floating base (§5.3.4).
    fn root_jump(&self, model: &Model, root: usize, y: &Wrench) -> Result<Twist, MultibodyError> {
        if root == 0 && self.floating {
            self.bodies[0]
                .ia
                .solve(&-*y)
                .ok_or_else(|| MultibodyError::SingularInertia {
                    link: model.body_name(0).to_owned(),
                })
        } else {
            Ok(Twist::ZERO)
        }
    }

    /// One step of the downward pass: (5.9) and (5.10) for body `i` given its parent's jump.
    #[inline]
    fn down(&self, model: &Model, i: usize, dv_parent: &Twist, y: &Wrench) -> (f64, Twist) {
        let b = &self.bodies[i];
        let joint = model.bodies[i].joint;
        let xv = b.x.motion_to_child(dv_parent);
        // (5.9) Δq̇_i = −ŝ'[Î^A X Δv̂_h + Ŷ^A] / D = −(U·XΔv̂_h + ŝ'Ŷ^A) / D.
        let dq = -(b.u.power(&xv) + axis_dot(joint, y)) * b.inv_d;
        // (5.10) Δv̂_i = X Δv̂_h + Δq̇_i ŝ_i.
        (dq, xv + axis_motion(joint, dq))
    }

    /// Velocity jump `Δv̂_k` of body `k` (its own frame) for the spatial impulse `p_coll`
    /// applied to it (body frame, about its origin): thesis Fig. 5.7 impulseResponse. O(depth).
    fn body_response(
        &mut self,
        model: &Model,
        k: usize,
        p_coll: &Wrench,
    ) -> Result<Twist, MultibodyError> {
        self.za_impulses(model, k, p_coll);
        let root = *self.path.last().expect("path contains k");
        let mut dv = self.root_jump(model, root, &self.y[root])?;
        let first = usize::from(root == 0 && self.floating);
        // Walk down the path (stored from k up), skipping a floating root already done.
        for idx in (0..self.path.len() - first).rev() {
            let i = self.path[idx];
            dv = self.down(model, i, &dv, &self.y[i]).1;
        }
        Ok(dv)
    }

    /// Velocity jump of `link` (twist in the link's frame, about its origin) caused by the
    /// spatial impulse `impulse` (linear impulse and angular impulse about the link-frame
    /// origin, link coordinates): thesis Fig. 5.7. Zero for links welded to the ground.
    ///
    /// # Errors
    /// [`MultibodyError::UnknownName`] for a link of another model;
    /// [`MultibodyError::SingularInertia`] if the base's articulated inertia is singular.
    pub fn impulse_response(
        &mut self,
        model: &Model,
        link: LinkId,
        impulse: &Wrench,
    ) -> Result<Twist, MultibodyError> {
        self.check_link(model, link)?;
        let Some((k, off)) = Self::locate(model, link) else {
            return Ok(Twist::ZERO);
        };
        let dv = self.body_response(model, k, &off.force_to_parent(impulse))?;
        Ok(off.motion_to_child(&dv))
    }

    /// The collision matrix K_i (3×3, collision-frame coordinates) of a contact on `link`,
    /// thesis Fig. 5.9 compMultibodyKi: three unit test impulses through the impulse-space
    /// articulated-body recursion, `K_i = [φ(e_x) | φ(e_y) | φ(e_z)]` (eqs. 5.13, 5.14), where
    /// `φ(p)` is the contact-point velocity jump for impulse `p` (both in the collision frame).
    ///
    /// `point` is the contact point in the link's frame; `rot` maps collision-frame axes to
    /// link axes (the thesis's R, F_coll → F_k; its z axis is the contact normal). O(depth).
    /// Zero for links welded to the ground.
    ///
    /// The impulse at the link is the corrected eq. (5.11): `p̂ = [R p; c × R p]` about the
    /// link origin, with `c` the contact point — equivalently the thesis's
    /// `_kX̂_coll = [[R, 0], [−r̃R, R]]` with `r = −c`; the matrix printed in the thesis,
    /// `[[Rᵀ, 0], [r̃Rᵀ, Rᵀ]]`, is wrong (see the crate tests).
    ///
    /// # Errors
    /// As [`ImpulseDynamics::impulse_response`].
    pub fn collision_matrix(
        &mut self,
        model: &Model,
        link: LinkId,
        point: DVec3,
        rot: DMat3,
    ) -> Result<DMat3, MultibodyError> {
        self.check_link(model, link)?;
        let Some((k, off)) = Self::locate(model, link) else {
            return Ok(DMat3::ZERO);
        };
        // Contact point and collision axes in the body frame.
        let c = off.point_to_parent(point);
        let r = off.r * rot;
        let mut cols = [DVec3::ZERO; 3];
        for (axis, col) in cols.iter_mut().enumerate() {
            let f = r.col(axis);
            // Corrected (5.11): p̂_coll = _kX̂_coll [e; 0] = [R e; c × R e].
            let p = Wrench::new(f, c.cross(f));
            let dv = self.body_response(model, k, &p)?;
            // (5.12) lower block of _collX̂_k Δv̂_k: Δu = Rᵀ(Δv + Δω × c).
            *col = rt_mul(&r, dv.v + dv.w.cross(c));
        }
        Ok(DMat3::from_cols(cols[0], cols[1], cols[2]))
    }

    /// [`ImpulseDynamics::collision_matrix`] with the contact point in world coordinates and
    /// the collision frame given by its axes in world coordinates (columns of `frame`; the
    /// third is the contact normal). Returns K in collision-frame coordinates.
    ///
    /// # Errors
    /// As [`ImpulseDynamics::impulse_response`].
    pub fn collision_matrix_world(
        &mut self,
        model: &Model,
        link: LinkId,
        point: DVec3,
        frame: DMat3,
    ) -> Result<DMat3, MultibodyError> {
        self.check_link(model, link)?;
        let lw = self.link_world(model, link);
        self.collision_matrix(
            model,
            link,
            lw.point_to_child(point),
            lw.r.transpose() * frame,
        )
    }

    /// World pose of a link at the configuration of the last update.
    fn link_world(&self, model: &Model, link: LinkId) -> Xform {
        let info = &model.links[link.0];
        match info.body {
            Some(b) => self.bodies[b].world.compose(&info.offset),
            None => info.offset,
        }
    }

    /// Spreads a collision impulse over the whole tree, thesis Fig. 5.10 propagateImpulse:
    /// the linear impulse `impulse` (N·s, world coordinates) acts at `point` (world) on
    /// `link`. Writes the velocity change `Δv` (nv; with a floating base the first six entries
    /// are the base twist change in base coordinates). Positions do not change. O(n).
    ///
    /// # Errors
    /// [`MultibodyError::DimensionMismatch`] if `dv` has the wrong length; otherwise as
    /// [`ImpulseDynamics::impulse_response`].
    pub fn propagate_impulse(
        &mut self,
        model: &Model,
        link: LinkId,
        point: DVec3,
        impulse: DVec3,
        dv: &mut [f64],
    ) -> Result<(), MultibodyError> {
        self.check_link(model, link)?;
        let lw = self.link_world(model, link);
        let p = Wrench::new(
            rt_mul(&lw.r, impulse),
            lw.point_to_child(point).cross(rt_mul(&lw.r, impulse)),
        );
        self.propagate_wrench_impulse(model, link, &p, dv)
    }

    /// [`ImpulseDynamics::propagate_impulse`] for a spatial impulse given in the link's frame
    /// (about its origin).
    ///
    /// # Errors
    /// As [`ImpulseDynamics::propagate_impulse`].
    pub fn propagate_wrench_impulse(
        &mut self,
        model: &Model,
        link: LinkId,
        impulse: &Wrench,
        dv: &mut [f64],
    ) -> Result<(), MultibodyError> {
        self.check_link(model, link)?;
        check_len("dv", model.nv(), dv.len())?;
        dv.iter_mut().for_each(|x| *x = 0.0);
        let Some((k, off)) = Self::locate(model, link) else {
            return Ok(());
        };
        let p = off.force_to_parent(impulse);
        self.y.iter_mut().for_each(|y| *y = Wrench::ZERO);
        self.za_impulses(model, k, &p);
        // Off-path bodies keep Ŷ^A = 0 (Lemma 9); za_impulses wrote only the path.
        let nb = model.first_joint_body();
        let vo = model.base_dofs();
        if nb == 1 {
            let d0 = self.root_jump(model, 0, &self.y[0])?;
            self.dv[0] = d0;
            dv[..6].copy_from_slice(&d0.to_array());
        }
        for i in nb..model.body_count() {
            let parent_dv = model.bodies[i].parent.map_or(Twist::ZERO, |p| self.dv[p]);
            let (dq, dvi) = self.down(model, i, &parent_dv, &self.y[i]);
            self.dv[i] = dvi;
            dv[vo + i - nb] = dq;
        }
        Ok(())
    }
}

impl Model {
    /// Whether two links of this multibody are *adjacent*, the pairs that self-collision
    /// (two links of one multibody colliding with each other) never considers:
    ///
    /// - a link with itself;
    /// - two links welded into one rigid body by a chain of fixed joints (both welded to the
    ///   ground included);
    /// - two links whose rigid bodies are joined by one moving joint, parent and child
    ///   (under a fixed base, a link welded to the ground and a body jointed to the ground
    ///   too).
    ///
    /// Every other pair (siblings, grandparent and grandchild, …) is not adjacent.
    ///
    /// # Errors
    /// [`MultibodyError::UnknownName`] for a link id outside the model.
    pub fn links_adjacent(&self, a: LinkId, b: LinkId) -> Result<bool, MultibodyError> {
        let body = |l: LinkId| {
            self.links
                .get(l.0)
                .map(|info| info.body)
                .ok_or_else(|| MultibodyError::UnknownName {
                    kind: "link",
                    name: l.0.to_string(),
                })
        };
        let (ba, bb) = (body(a)?, body(b)?);
        // The parent of a body, as a link's body is given: `None` is the ground.
        let parent = |x: usize| self.bodies[x].parent;
        Ok(match (ba, bb) {
            (x, y) if x == y => true,
            (Some(x), Some(y)) => parent(x) == Some(y) || parent(y) == Some(x),
            // The ground and a body: adjacent when the body is jointed to the ground (never
            // a floating base, which has no joint).
            (None, Some(x)) | (Some(x), None) => !self.is_floating() && parent(x).is_none(),
            (None, None) => true,
        })
    }
}

#[inline]
fn axis_times(joint: BodyJoint, ia: &Sym6) -> Wrench {
    match joint {
        BodyJoint::Revolute(u) => Wrench::new(ia.b * u, ia.c * u),
        BodyJoint::Prismatic(u) => Wrench::new(ia.a * u, rt_mul(&ia.b, u)),
        BodyJoint::Floating => Wrench::ZERO,
    }
}

#[inline]
fn axis_dot(joint: BodyJoint, f: &Wrench) -> f64 {
    match joint {
        BodyJoint::Revolute(u) => u.dot(f.tau),
        BodyJoint::Prismatic(u) => u.dot(f.f),
        BodyJoint::Floating => 0.0,
    }
}

#[inline]
fn axis_motion(joint: BodyJoint, x: f64) -> Twist {
    match joint {
        BodyJoint::Revolute(u) => Twist::new(DVec3::ZERO, u * x),
        BodyJoint::Prismatic(u) => Twist::new(u * x, DVec3::ZERO),
        BodyJoint::Floating => Twist::ZERO,
    }
}

/// The SVD ("canonical") pseudo-inverse of a 3×3 matrix (thesis §5.3, Fig. 5.12, after
/// \[PTVF92\]): singular values below `rel_cutoff · σ_max` count as zero, so `K̃⁻¹ Δu` is the
/// minimum-norm impulse producing the part of `Δu` in K's range, with no null-space component.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct PseudoInverse {
    /// The pseudo-inverse `V Σ⁺ Uᵀ`.
    pub inverse: DMat3,
    /// Number of singular values kept.
    pub rank: usize,
    /// Singular values, non-increasing.
    pub singular_values: DVec3,
}

/// SVD pseudo-inverse of `k` with relative cutoff `rel_cutoff` (use
/// [`crate::tol::PINV_REL_CUTOFF`] unless you know better). A zero matrix gives rank 0 and a
/// zero inverse.
///
/// # Errors
/// [`MultibodyError::InvalidArgument`] if `k` or `rel_cutoff` is not finite, or the SVD fails.
pub fn pseudo_inverse(k: &DMat3, rel_cutoff: f64) -> Result<PseudoInverse, MultibodyError> {
    if !k.is_finite() || !rel_cutoff.is_finite() || rel_cutoff < 0.0 {
        return Err(MultibodyError::InvalidArgument {
            what: "pseudo-inverse input",
            reason: "matrix or cutoff not finite (or cutoff negative)".to_owned(),
        });
    }
    let m = Mat::<f64>::from_fn(3, 3, |r, c| k.col(c)[r]);
    let svd = m.svd().map_err(|_| MultibodyError::InvalidArgument {
        what: "pseudo-inverse input",
        reason: "SVD did not converge".to_owned(),
    })?;
    let (u, s, v) = (svd.U(), svd.S(), svd.V());
    let sv = DVec3::new(s[0], s[1], s[2]);
    let cutoff = rel_cutoff * sv.x;
    let mut inv = DMat3::ZERO;
    let mut rank = 0;
    for i in 0..3 {
        if sv[i] > cutoff && sv[i] > 0.0 {
            rank += 1;
            let vi = DVec3::new(v[(0, i)], v[(1, i)], v[(2, i)]);
            let ui = DVec3::new(u[(0, i)], u[(1, i)], u[(2, i)]);
            inv += crate::spatial::outer(vi, ui) * (1.0 / sv[i]);
        }
    }
    Ok(PseudoInverse {
        inverse: inv,
        rank,
        singular_values: sv,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dynamics::{Workspace, mass_matrix};
    use crate::model::{BaseKind, JointSpec, ModelBuilder};
    use crate::testutil::*;
    use faer::Side;
    use faer::linalg::solvers::Solve;
    use impulse_geom::{Pose, SpatialInertia};
    use rand::RngExt;

    /// Bound on K from test impulses (Fig. 5.9) against the dense `J M⁻¹ Jᵀ`, relative to max |K|
    /// (also on propagateImpulse's Δv and K p against theirs): two exact routes, only rounding.
    const K_REL: f64 = 1e-10;
    /// Symmetry and momentum balances: exact identities evaluated in floating point.
    const TIGHT_REL: f64 = 1e-12;

    fn solve(m: &Mat<f64>, b: &Mat<f64>) -> Mat<f64> {
        m.llt(Side::Lower).expect("M is positive definite").solve(b)
    }

    /// 3 × nv Jacobian of the velocity of world point `c` on `link`, in collision-frame axes.
    fn contact_jacobian(r: &Reference, link: usize, c: DVec3, frame: &DMat3) -> Mat<f64> {
        let j = &r.jacobians[link];
        let o = r.poses[link].translation;
        Mat::<f64>::from_fn(3, j.ncols(), |row, col| {
            let lin = DVec3::new(j[(0, col)], j[(1, col)], j[(2, col)]);
            let ang = DVec3::new(j[(3, col)], j[(4, col)], j[(5, col)]);
            frame.col(row).dot(lin + ang.cross(c - o))
        })
    }

    fn dmat3(m: &Mat<f64>) -> DMat3 {
        let col = |c: usize| DVec3::new(m[(0, c)], m[(1, c)], m[(2, c)]);
        DMat3::from_cols(col(0), col(1), col(2))
    }

    fn max3(m: &DMat3) -> f64 {
        (0..3).fold(0.0, |s, c| s.max(m.col(c).abs().max_element()))
    }

    /// K from test impulses (Fig. 5.9) equals `J_c M⁻¹ J_cᵀ` (M by CRBA, J_c from independent
    /// world kinematics) on random fixed and floating trees, contacts on random links
    /// (welded ones included); K is symmetric positive semi-definite.
    #[test]
    fn collision_matrix_matches_dense_reference() {
        let mut rng = rng(6101);
        let (mut worst, mut asym, mut min_eig) = (0.0f64, 0.0f64, f64::INFINITY);
        for case in 0..300 {
            let base = alternating_base(case);
            let spec = random_spec(&mut rng, 1 + case % 25, base, case % 3 == 0, true);
            let model = spec.model();
            let (q, _) = random_state(&mut rng, &model);
            let mut imp = ImpulseDynamics::new(&model, &q).unwrap();
            let mut m = Mat::<f64>::zeros(model.nv(), model.nv());
            mass_matrix(&model, &mut Workspace::new(&model), &q, &mut m).unwrap();
            let r = reference(&spec, &model, &q);
            for _ in 0..3 {
                let link = rng.random_range(0..spec.links.len());
                let c = r.poses[link].translation + vec3(&mut rng, 0.5);
                let frame = DMat3::from_quat(quat(&mut rng));
                let k = imp
                    .collision_matrix_world(&model, LinkId(link), c, frame)
                    .unwrap();
                let jc = contact_jacobian(&r, link, c, &frame);
                let kref = dmat3(&(&jc * solve(&m, &jc.transpose().to_owned())));
                let scale = max3(&kref);
                if scale == 0.0 {
                    // A link on the ground: both are exactly zero.
                    assert_eq!(k, DMat3::ZERO);
                    continue;
                }
                worst = worst.max(max3(&(k - kref)) / scale);
                asym = asym.max(max3(&(k - k.transpose())) / scale);
                let ev = pseudo_inverse(&k, 0.0).unwrap().singular_values;
                // For symmetric K, PSD ⇔ xᵀKx ≥ 0; check on the singular vectors' quadratic
                // forms via the smallest eigenvalue of the symmetric part.
                let sym = (k + k.transpose()) * 0.5;
                let lo = smallest_eigen(&sym);
                min_eig = min_eig.min(lo / ev.x);
            }
        }
        println!("K vs J M⁻¹ Jᵀ: {worst:.2e}, asymmetry {asym:.2e}, min eig/σmax {min_eig:.2e}");
        assert!(worst <= K_REL && asym <= TIGHT_REL, "{worst:e} {asym:e}");
        assert!(min_eig >= -TIGHT_REL, "{min_eig:e}");
    }

    fn smallest_eigen(m: &DMat3) -> f64 {
        let a = Mat::<f64>::from_fn(3, 3, |r, c| m.col(c)[r]);
        a.self_adjoint_eigenvalues(Side::Lower).unwrap()[0]
    }

    /// One floating link gives Ch. 3's rigid-body matrix `(1/m)1 − r̃ I⁻¹ r̃` (r from the
    /// c.o.m. to the contact, world frame), rotated into the collision frame.
    #[test]
    fn single_floating_link_gives_rigid_body_k() {
        let mut rng = rng(6102);
        let mut worst = 0.0f64;
        for _ in 0..100 {
            let i = inertia(&mut rng);
            let mut b = ModelBuilder::new(BaseKind::Floating);
            b.link("body", i);
            let model = b.build().unwrap();
            let (q, _) = random_state(&mut rng, &model);
            let mut imp = ImpulseDynamics::new(&model, &q).unwrap();
            let pose = crate::dynamics::base_xform(&q);
            let c = vec3(&mut rng, 1.0);
            let frame = DMat3::from_quat(quat(&mut rng));
            let k = imp
                .collision_matrix_world(&model, LinkId(0), c, frame)
                .unwrap();
            let com = pose.point_to_parent(i.com);
            let iw = pose.r * i.inertia_com * pose.r.transpose();
            let rt = impulse_geom::se3::hat(c - com);
            let kw = DMat3::IDENTITY * (1.0 / i.mass) - rt * iw.inverse() * rt;
            let want = frame.transpose() * kw * frame;
            worst = worst.max(max3(&(k - want)) / max3(&want));
        }
        assert!(worst <= TIGHT_REL, "{worst:e}");
    }

    /// Guard (digest test 18): with eq. (5.11) as printed, `[[Rᵀ, 0], [r̃Rᵀ, Rᵀ]]`, K misses
    /// the reference by O(1); the corrected form is what `collision_matrix` uses.
    #[test]
    fn misprinted_eq_5_11_is_detectably_wrong() {
        let mut rng = rng(6103);
        let mut smallest_miss = f64::INFINITY;
        for _ in 0..20 {
            let spec = random_spec(&mut rng, 6, BaseKind::Fixed, false, true);
            let model = spec.model();
            let (q, _) = random_state(&mut rng, &model);
            let mut imp = ImpulseDynamics::new(&model, &q).unwrap();
            let link = LinkId(spec.links.len() - 1);
            let point = vec3(&mut rng, 0.5) + DVec3::splat(0.3);
            let rot = DMat3::from_quat(quat(&mut rng));
            let good = imp.collision_matrix(&model, link, point, rot).unwrap();
            // The printed matrix, with the thesis's r = −point (contact → frame origin):
            // p̂ = [Rᵀ e; r × Rᵀ e] (force first, as the thesis packs forces).
            let r = -point;
            let mut cols = [DVec3::ZERO; 3];
            for (a, col) in cols.iter_mut().enumerate() {
                let f = rot.transpose().col(a);
                let dv = imp
                    .impulse_response(&model, link, &Wrench::new(f, r.cross(f)))
                    .unwrap();
                *col = rot.transpose() * (dv.v + dv.w.cross(point));
            }
            let bad = DMat3::from_cols(cols[0], cols[1], cols[2]);
            smallest_miss = smallest_miss.min(max3(&(bad - good)) / max3(&good));
        }
        println!("misprinted (5.11): smallest relative miss {smallest_miss:.2}");
        assert!(smallest_miss > 0.05, "{smallest_miss}");
    }

    /// propagateImpulse (Fig. 5.10): Δv = M⁻¹ J_cᵀ p; the contact velocity jump is K p; with a
    /// floating base the total momentum changes by exactly (p, c × p); the kinetic energy
    /// changes by p·(u⁻ + u⁺)/2.
    #[test]
    fn impulse_propagation_matches_references_and_balances_momentum() {
        let mut rng = rng(6104);
        let (mut e_dv, mut e_k, mut e_mom, mut e_energy) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        for case in 0..200 {
            let base = alternating_base(case);
            let spec = random_spec(&mut rng, 1 + case % 20, base, case % 4 == 0, true);
            let model = spec.model();
            let (q, v) = random_state(&mut rng, &model);
            let mut imp = ImpulseDynamics::new(&model, &q).unwrap();
            let mut ws = Workspace::new(&model);
            let mut m = Mat::<f64>::zeros(model.nv(), model.nv());
            mass_matrix(&model, &mut ws, &q, &mut m).unwrap();
            let r = reference(&spec, &model, &q);
            let link = 1 + rng.random_range(0..spec.links.len() - 1);
            let c = r.poses[link].translation + vec3(&mut rng, 0.5);
            let p = vec3(&mut rng, 2.0);
            let mut dv = vec![0.0; model.nv()];
            imp.propagate_impulse(&model, LinkId(link), c, p, &mut dv)
                .unwrap();
            let jc = contact_jacobian(&r, link, c, &DMat3::IDENTITY);
            let jtp = Mat::<f64>::from_fn(model.nv(), 1, |row, _| {
                (0..3).map(|k| jc[(k, row)] * p[k]).sum()
            });
            let want = solve(&m, &jtp);
            let scale = (0..model.nv()).fold(0.0f64, |s, i| s.max(want[(i, 0)].abs()));
            if scale == 0.0 {
                continue;
            }
            for (i, d) in dv.iter().enumerate() {
                e_dv = e_dv.max((d - want[(i, 0)]).abs() / scale);
            }
            // Contact velocity jump = K p.
            let k = imp
                .collision_matrix_world(&model, LinkId(link), c, DMat3::IDENTITY)
                .unwrap();
            let du = DVec3::from_array([0, 1, 2].map(|row| {
                (0..model.nv())
                    .map(|col| jc[(row, col)] * dv[col])
                    .sum::<f64>()
            }));
            e_k = e_k.max((du - k * p).abs().max_element() / (k * p).abs().max_element());
            // Energy identity ΔT = p·(u⁻ + u⁺)/2.
            ws.update_kinematics(&model, &q, &v).unwrap();
            let t0 = ws.kinetic_energy(&model);
            let u0 = ws.point_velocity(&model, LinkId(link), c);
            let mom0 = ws.momentum(&model);
            let v1: Vec<f64> = v.iter().zip(&dv).map(|(a, b)| a + b).collect();
            ws.update_kinematics(&model, &q, &v1).unwrap();
            let t1 = ws.kinetic_energy(&model);
            let u1 = ws.point_velocity(&model, LinkId(link), c);
            let de = t1 - t0 - p.dot(u0 + u1) * 0.5;
            e_energy = e_energy.max(de.abs() / t0.max(t1).max(1.0));
            if model.is_floating() {
                let dm = ws.momentum(&model) - mom0;
                let s = p.length() * (1.0 + c.length());
                e_mom = e_mom.max((dm.f - p).length() / s);
                e_mom = e_mom.max((dm.tau - c.cross(p)).length() / s);
            }
        }
        println!(
            "propagate: Δv vs M⁻¹Jᵀp {e_dv:.2e}, Δu vs Kp {e_k:.2e}, momentum {e_mom:.2e}, \
             energy identity {e_energy:.2e}"
        );
        assert!(e_dv <= K_REL && e_k <= K_REL, "{e_dv:e} {e_k:e}");
        assert!(
            e_mom <= TIGHT_REL && e_energy <= TIGHT_REL,
            "{e_mom:e} {e_energy:e}"
        );
    }

    /// Theorems 18/19: Î^A depends on q only — the forward-dynamics pass gives the same
    /// articulated inertias for two different (q̇, τ) as the impulse pass — and every Î^A is
    /// symmetric positive definite with D_i > 0. A structure made for another model is a
    /// typed error.
    #[test]
    fn articulated_inertias_depend_on_configuration_only() {
        let mut rng = rng(6105);
        for case in 0..30 {
            let base = alternating_base(case);
            let spec = random_spec(&mut rng, 1 + case % 12, base, false, true);
            let model = spec.model();
            let (q, v1) = random_state(&mut rng, &model);
            let (_, v2) = random_state(&mut rng, &model);
            let imp = ImpulseDynamics::new(&model, &q).unwrap();
            let mut out = vec![0.0; model.nv()];
            for (v, t) in [(&v1, 1.0), (&v2, -3.0)] {
                let mut ws = Workspace::new(&model);
                let tau = vec![t; model.nv()];
                crate::dynamics::forward_dynamics(&model, &mut ws, &q, v, &tau, None, &mut out)
                    .unwrap();
                for (a, b) in ws.bodies.iter().zip(&imp.bodies) {
                    let (ma, mb) = (a.ia.to_mat6(), b.ia.to_mat6());
                    let scale = mb
                        .to_rows()
                        .iter()
                        .flatten()
                        .fold(0.0f64, |m, x| m.max(x.abs()));
                    assert!(ma.max_abs_diff(&mb) <= TIGHT_REL * scale);
                    assert!(mb.max_abs_diff(&mb.transpose()) <= TIGHT_REL * scale);
                    assert!(b.ia.solve(&Wrench::new(DVec3::ONE, DVec3::ONE)).is_some());
                }
            }
            for b in &imp.bodies[model.first_joint_body()..] {
                assert!(b.inv_d > 0.0 && b.inv_d.is_finite());
            }
        }
        let mut rng2 = crate::testutil::rng(6106);
        let small = random_spec(&mut rng2, 2, BaseKind::Fixed, true, false).model();
        let big = random_spec(&mut rng2, 5, BaseKind::Fixed, true, false).model();
        let mut imp = ImpulseDynamics::new(&small, &[0.0; 2]).unwrap();
        let link = big.link_id("root").unwrap();
        assert!(matches!(
            imp.collision_matrix(&big, link, DVec3::ZERO, DMat3::IDENTITY),
            Err(MultibodyError::DimensionMismatch { .. })
        ));
        let mut ws = Workspace::new(&small);
        let mut out = vec![0.0; big.nv()];
        let z = vec![0.0; big.nv()];
        assert!(matches!(
            crate::dynamics::forward_dynamics(&big, &mut ws, &z, &z, &z, None, &mut out),
            Err(MultibodyError::DimensionMismatch { .. })
        ));
    }

    fn planar_arm(links: usize) -> Model {
        let rod = SpatialInertia::new(
            1.0,
            DVec3::new(0.25, 0.0, 0.0),
            DMat3::from_diagonal(DVec3::new(1e-3, 0.02, 0.02)),
        );
        let mut b = ModelBuilder::new(BaseKind::Fixed);
        b.link("ground", SpatialInertia::ZERO);
        let mut parent = "ground".to_owned();
        for k in 0..links {
            let name = format!("l{k}");
            let origin = if k == 0 {
                Pose::IDENTITY
            } else {
                Pose::from_translation(DVec3::new(0.5, 0.0, 0.0))
            };
            b.link(&name, rod).joint(JointSpec::revolute(
                &format!("j{k}"),
                &parent,
                &name,
                origin,
                DVec3::Z,
            ));
            parent = name;
        }
        b.build().unwrap()
    }

    /// Fig. 5.12: a planar two-link arm (parallel axes) has a rank-2 K whose null space is the
    /// axis direction; the pseudo-inverse impulse has no component along it; one link gives
    /// rank 1; adding a free rigid body's K makes the pair positive definite.
    #[test]
    fn planar_arm_is_rank_deficient() {
        let model = planar_arm(2);
        let q = [0.4, 0.9];
        let mut imp = ImpulseDynamics::new(&model, &q).unwrap();
        let tip = model.link_id("l1").unwrap();
        // Contact at the tip, normal in the plane, tangent axes: one in-plane, one along z.
        let frame = DMat3::from_cols(
            DVec3::Z,
            DVec3::new(-0.6, 0.8, 0.0),
            DVec3::new(0.8, 0.6, 0.0),
        );
        let k = imp
            .collision_matrix(&model, tip, DVec3::new(0.5, 0.0, 0.0), {
                // Link frame of l1 is rotated by q0 + q1 about z: express the world frame in it.
                DMat3::from_rotation_z(-(q[0] + q[1])) * frame
            })
            .unwrap();
        let pinv = pseudo_inverse(&k, crate::tol::PINV_REL_CUTOFF).unwrap();
        println!("planar arm K singular values {:?}", pinv.singular_values);
        assert_eq!(pinv.rank, 2);
        // The null direction is the axis z, the first collision axis: its row/column vanish.
        assert!(k.col(0).abs().max_element() <= 1e-15 && k.row(0).abs().max_element() <= 1e-15);
        let du = DVec3::new(0.3, -1.0, 2.0);
        let p = pinv.inverse * du;
        assert!(p.x.abs() <= 1e-15 && p.is_finite());
        // Minimum-norm solution reproduces the in-range part of Δu.
        assert!((k * p - DVec3::new(0.0, du.y, du.z)).length() <= 1e-12);
        // Moore–Penrose conditions.
        let (kp, pk) = (k * pinv.inverse, pinv.inverse * k);
        assert!(max3(&(kp * k - k)) <= 1e-12 * max3(&k));
        assert!(max3(&(pk * pinv.inverse - pinv.inverse)) <= 1e-12 * max3(&pinv.inverse));
        assert!(max3(&(kp - kp.transpose())) <= 1e-12 && max3(&(pk - pk.transpose())) <= 1e-12);
        // One link: rank 1.
        let one = planar_arm(1);
        let mut imp1 = ImpulseDynamics::new(&one, &[0.3]).unwrap();
        let k1 = imp1
            .collision_matrix(
                &one,
                one.link_id("l0").unwrap(),
                DVec3::new(0.5, 0.1, 0.0),
                DMat3::IDENTITY,
            )
            .unwrap();
        assert_eq!(
            pseudo_inverse(&k1, crate::tol::PINV_REL_CUTOFF)
                .unwrap()
                .rank,
            1
        );
        // Deficient multibody + free sphere (m = 2, I = 0.1·1, contact 0.3 from its centre).
        let rt = impulse_geom::se3::hat(frame * DVec3::new(0.0, 0.0, -0.3));
        let k2 = frame.transpose()
            * (DMat3::IDENTITY * 0.5 - rt * (DMat3::IDENTITY * 10.0) * rt)
            * frame;
        assert_eq!(
            pseudo_inverse(&(k + k2), crate::tol::PINV_REL_CUTOFF)
                .unwrap()
                .rank,
            3
        );
        // A zero matrix: rank 0, zero inverse; non-finite input: an error.
        let z = pseudo_inverse(&DMat3::ZERO, crate::tol::PINV_REL_CUTOFF).unwrap();
        assert_eq!((z.rank, z.inverse), (0, DMat3::ZERO));
        assert!(pseudo_inverse(&(DMat3::IDENTITY * f64::NAN), 1e-10).is_err());
    }
}
