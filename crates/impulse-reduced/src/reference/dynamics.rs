//! Full nonlinear dynamics of a [`Mechanism`] with implicit time stepping: the truth for the
//! dynamic error figures of the reduced model and its speed baseline (the paper used Vortex).
//!
//! **Coordinates.** Every joint coordinate θ (loop joints included, tied down by their
//! closure) and, for a free base, the base pose `H_b` with its body twist `φ_b` as velocity.
//! Link body twists follow the tree: `φ_c = ᶜAd_p φ_p + J_j θ̇_j`. Kinetic energy
//! `T = ½ Σ_l φ_lᵀ I_l φ_l`; joint springs `½ Σ θ²/c`, dampers `D = diag(d)`; gravity and
//! world-fixed loads ([`Load`]) on the links.
//!
//! **Backward Euler in momentum form** (Lagrange's equations `d/dt ∂T/∂θ̇ − ∂T/∂θ = Q`): with
//! `θ⁺ = θ + h θ̇⁺`, `H_b⁺ = H_b exp(h φ_b⁺)` and generalized momentum `p = M(q) v`,
//!
//! - joint rows: `p_θ(q⁺, v⁺) − p_θ(q, v) = h (∂T/∂θ(q⁺, v⁺) − Kθ⁺ − Dθ̇⁺ + Q_θ(q⁺)) + Gᵀμ`,
//! - free-base rows: the structure's world momentum `Σ_l Ad*_l I_l φ_l` changes by `h` times
//!   the external wrenches (springs, dampers and closure forces are internal),
//! - closure: `r(θ⁺) = 0` at position level (no drift), `μ = hλ` the closure impulses.
//!
//! `M(q)` by composite inertias (CRBA), `∂T/∂θ` from each subtree's momentum and central
//! differences of the joint's own velocity map (their error, ~1e-10 relative, only perturbs the
//! trajectory at that level). The implicit system is solved by Newton. Small systems (≤ [`tol::FULL_EXACT_TANGENT_MAX`]
//! velocities) take the tangent's velocity columns by differences of the residual; larger
//! ones the tangent `[M + hD + h²K, −Gᵀ; G, 0]` (the Coriolis, load-stiffness and
//! mass-variation terms it leaves out only slow the convergence; the residual is exact), solved
//! for a fixed-base tree in O(n) by the articulated-body recursion with `hD + h²K` as joint
//! armature (the articulated inertias symmetrised at every level: a 50-link chain otherwise
//! amplifies round-off to 15 % of the solution), each solve by LU, or by truncated SVD when loops are
//! present (redundant closures), with backtracking on the residual. Backward Euler dissipates:
//! the energy does not grow for any step (tested at h = 1 s).

use faer::Mat;
use faer::linalg::solvers::Solve;
use glam::DVec3;
use impulse_geom::{Mat6, Pose, SpatialInertia, Twist, Wrench};

use crate::desc::BaseDesc;
use crate::error::Error;
use crate::linalg::{Tsvd, pinv};
use crate::mechanism::Mechanism;
use crate::reference::kinematics::{
    Configuration, joint_jacobian, joint_motion, link_poses, loop_jacobian, loop_residual,
};
use crate::reference::statics::Load;
use crate::tol;

/// Settings of [`FullSim`].
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct FullOptions {
    /// Newton iterations allowed per step before [`Error::NoConvergence`].
    pub max_iterations: usize,
    /// Newton stops when the momentum residual is below this fraction of the step's momentum
    /// scale and the closure below it times the bounding radius ([`tol::FULL_RESIDUAL_REL`]).
    pub tolerance: f64,
    /// Relative step of the central differences of `∂T/∂θ` ([`tol::FULL_FD_STEP`]).
    pub fd_step: f64,
    /// Truncation of the Newton solves when loops are present.
    pub tsvd: Tsvd,
}

impl Default for FullOptions {
    fn default() -> Self {
        FullOptions {
            max_iterations: tol::FULL_MAX_ITERATIONS,
            tolerance: tol::FULL_RESIDUAL_REL,
            fd_step: tol::FULL_FD_STEP,
            tsvd: Tsvd::default(),
        }
    }
}

/// What one step of [`FullSim::step`] took.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct FullStepReport {
    /// Newton iterations.
    pub iterations: usize,
    /// Final relative residual (the largest over sub-steps).
    pub residual: f64,
    /// Backward Euler steps taken: 1, or more when Newton stalled and the step was halved.
    pub substeps: usize,
}

/// A running simulation of the full model.
#[derive(Clone, Debug)]
pub struct FullSim<'m> {
    m: &'m Mechanism,
    /// Time step (s).
    pub h: f64,
    /// Configuration (base pose and θ).
    pub config: Configuration,
    /// Joint velocities θ̇.
    pub theta_dot: Vec<f64>,
    /// Body twist of the base (zero and ignored for a fixed base).
    pub base_twist: Twist,
    /// Loads held on the links (world-fixed force and torque at the link origin).
    pub loads: Vec<Load>,
    /// Gravity (world), from the mechanism.
    pub gravity: DVec3,
    /// Settings.
    pub options: FullOptions,
    free: bool,
}

/// The implicit step's residual at velocities and closure impulses: residual, kinematics at
/// the end of the step, closure Jacobian, momentum scale.
type ResidualFn<'a> = dyn Fn(&[f64], &[f64]) -> (Vec<f64>, Kin, Mat<f64>, f64) + 'a;

/// One joint of the articulated-body recursion: `U = I^A S` (columns), `D⁻¹`, `u = τ − Sᵀp^A`.
type JointSolve = (Vec<[f64; 6]>, Mat<f64>, Vec<f64>);

/// Kinematic state of every link: poses, joint columns (child frame), body twists.
struct Kin {
    poses: Vec<Pose>,
    /// Per joint, its motion columns in the child's frame (tree joints only).
    cols: Vec<Vec<Twist>>,
    twists: Vec<Twist>,
}

/// Body twist of joint `j`'s child at joint coordinates `th` and rates `rates`, its parent
/// moving with `phi_p`: `ᶜAd_p φ_p + J_j θ̇_j`.
fn child_twist(j: &crate::mechanism::Joint, th: &[f64], phi_p: &Twist, rates: &[f64]) -> Twist {
    let rel = j.in_parent * joint_motion(j, th) * j.in_child.inverse();
    let mut t = rel.inverse_transform_twist(phi_p);
    for (s, d) in joint_jacobian(j, th).iter().zip(rates) {
        t += j.in_child.transform_twist(s) * *d;
    }
    t
}

impl<'m> FullSim<'m> {
    /// A simulation of `m` at rest (θ = 0, base at rest) with step `h`.
    ///
    /// # Errors
    /// [`Error::Argument`] for a non-positive or non-finite `h`.
    pub fn new(m: &'m Mechanism, h: f64, options: FullOptions) -> Result<Self, Error> {
        if !(h.is_finite() && h > 0.0) {
            return Err(Error::Argument(format!("time step {h} is not positive")));
        }
        Ok(FullSim {
            m,
            h,
            config: Configuration::rest(m),
            theta_dot: vec![0.0; m.ndof],
            base_twist: Twist::ZERO,
            loads: Vec::new(),
            gravity: m.gravity,
            options,
            free: m.base_kind == BaseDesc::Free,
        })
    }

    /// The mechanism simulated.
    #[must_use]
    pub fn mechanism(&self) -> &'m Mechanism {
        self.m
    }

    /// Number of velocity unknowns: joint coordinates, plus 6 for a free base.
    fn nv(&self) -> usize {
        self.m.ndof + if self.free { 6 } else { 0 }
    }

    /// Pose, columns and body twist of link `l` from its parent's (tree joint).
    fn descend(&self, k: &mut Kin, q: &Configuration, td: &[f64], l: usize) {
        let Some(ji) = self.m.tree_joint[l] else {
            return;
        };
        let j = &self.m.joints[ji];
        let th = &q.theta[j.offset..j.offset + j.dof()];
        let p = j.parent;
        k.poses[l] = k.poses[p] * j.in_parent * joint_motion(j, th) * j.in_child.inverse();
        k.cols[ji] = joint_jacobian(j, th)
            .iter()
            .map(|s| j.in_child.transform_twist(s))
            .collect();
        let mut tw = (k.poses[l].inverse() * k.poses[p]).transform_twist(&k.twists[p]);
        for (c, s) in k.cols[ji].iter().enumerate() {
            tw += *s * td[j.offset + c];
        }
        k.twists[l] = tw;
    }

    fn kinematics(&self, q: &Configuration, td: &[f64], base_twist: &Twist) -> Kin {
        let n = self.m.links.len();
        let mut k = Kin {
            poses: vec![Pose::IDENTITY; n],
            cols: vec![Vec::new(); self.m.joints.len()],
            twists: vec![Twist::ZERO; n],
        };
        k.poses[self.m.base] = q.base;
        k.twists[self.m.base] = if self.free { *base_twist } else { Twist::ZERO };
        for &l in &self.m.order[1..] {
            self.descend(&mut k, q, td, l);
        }
        k
    }

    /// `∂T/∂θ` at fixed velocities. Moving coordinate i of tree joint j moves the subtree of
    /// its child c rigidly: every body twist there is `ᶜAd φ_c` plus terms that do not depend
    /// on θ_i, so `∂T/∂θ_i = h_cᵀ ∂φ_c/∂θ_i` with `h_c` the subtree's momentum in c's frame.
    /// `∂φ_c/∂θ_i` by central differences of the joint's own velocity map (O(1) per coordinate,
    /// O(n) in all).
    fn kinetic_gradient(&self, q: &Configuration, td: &[f64], k: &Kin, h: &[Wrench]) -> Vec<f64> {
        let m = self.m;
        let mut g = vec![0.0; m.ndof];
        for (ji, j) in m.joints.iter().enumerate() {
            if m.tree_joint[j.child] != Some(ji) {
                continue; // a loop joint moves no link
            }
            let range = j.offset..j.offset + j.dof();
            let mut th = q.theta[range.clone()].to_vec();
            let rates = &td[range];
            let phi_p = k.twists[j.parent];
            for c in 0..j.dof() {
                let x = th[c];
                let step = self.options.fd_step * (1.0 + x.abs());
                th[c] = x + step;
                let plus = child_twist(j, &th, &phi_p, rates);
                th[c] = x - step;
                let minus = child_twist(j, &th, &phi_p, rates);
                th[c] = x;
                g[j.offset + c] = h[j.child].power(&((plus - minus) * (0.5 / step)));
            }
        }
        g
    }

    /// Momentum of every link's subtree (the link and all below it in the tree), its frame.
    fn subtree_momenta(&self, k: &Kin) -> Vec<Wrench> {
        let m = self.m;
        let mut h: Vec<Wrench> = m
            .links
            .iter()
            .zip(&k.twists)
            .map(|(l, t)| l.inertia.mul_twist(t))
            .collect();
        for &l in m.order.iter().rev() {
            if let Some(ji) = m.tree_joint[l] {
                let p = m.joints[ji].parent;
                let moved = (k.poses[p].inverse() * k.poses[l]).transform_wrench(&h[l]);
                h[p] += moved;
            }
        }
        h
    }

    /// Composite inertias (link frames) of every subtree.
    fn composite(&self, k: &Kin) -> Vec<SpatialInertia> {
        let mut ic: Vec<SpatialInertia> = self.m.links.iter().map(|l| l.inertia).collect();
        for &l in self.m.order.iter().rev() {
            if let Some(ji) = self.m.tree_joint[l] {
                let p = self.m.joints[ji].parent;
                let moved = ic[l].transform(&(k.poses[p].inverse() * k.poses[l]));
                ic[p] = ic[p] + moved;
            }
        }
        ic
    }

    /// Index of the velocity unknowns of tree joint `ji`'s columns, and of the base's.
    fn base_index(&self) -> usize {
        self.m.ndof
    }

    /// Joint-space mass matrix `M(q)` (CRBA on the composite inertias), free base last.
    fn mass_matrix(&self, k: &Kin) -> Mat<f64> {
        let nv = self.nv();
        let mut mq = Mat::<f64>::zeros(nv, nv);
        let ic = self.composite(k);
        for (ji, j) in self.m.joints.iter().enumerate() {
            if self.m.tree_joint[j.child] != Some(ji) {
                continue;
            }
            for (a, s) in k.cols[ji].iter().enumerate() {
                let row = j.offset + a;
                // F = I^c S (child frame), carried down the tree.
                let mut f = ic[j.child].mul_twist(s);
                let mut at = j.child;
                loop {
                    if let Some(jj) = self.m.tree_joint[at] {
                        let jn = &self.m.joints[jj];
                        for (b, sb) in k.cols[jj].iter().enumerate() {
                            let col = jn.offset + b;
                            let v = f.power(sb);
                            mq[(row, col)] = v;
                            mq[(col, row)] = v;
                        }
                        let p = jn.parent;
                        f = (k.poses[p].inverse() * k.poses[at]).transform_wrench(&f);
                        at = p;
                    } else {
                        if self.free {
                            let fa = f.to_array();
                            for (b, x) in fa.iter().enumerate() {
                                mq[(row, self.base_index() + b)] = *x;
                                mq[(self.base_index() + b, row)] = *x;
                            }
                        }
                        break;
                    }
                }
            }
        }
        if self.free {
            let mb = ic[self.m.base].to_mat6().to_rows();
            for (r, row) in mb.iter().enumerate() {
                for (c, x) in row.iter().enumerate() {
                    mq[(self.base_index() + r, self.base_index() + c)] = *x;
                }
            }
        }
        mq
    }

    /// Body wrenches of gravity and the loads on every link.
    fn external(&self, k: &Kin) -> Vec<Wrench> {
        let mut w: Vec<Wrench> = self
            .m
            .links
            .iter()
            .zip(&k.poses)
            .map(|(l, p)| {
                let g = p.inverse_transform_vector(self.gravity) * l.inertia.mass;
                Wrench::new(g, l.inertia.com.cross(g))
            })
            .collect();
        for load in &self.loads {
            w[load.link] += load.body_wrench(&k.poses[load.link]);
        }
        w
    }

    /// Generalized external force `Σ J_lᵀ w_l` (joint rows) and, for a free base, the total
    /// external wrench in the base frame (base rows).
    fn generalized_force(&self, k: &Kin) -> Vec<f64> {
        let mut acc = self.external(k);
        let mut q = vec![0.0; self.nv()];
        for &l in self.m.order.iter().rev() {
            if let Some(ji) = self.m.tree_joint[l] {
                let j = &self.m.joints[ji];
                for (a, s) in k.cols[ji].iter().enumerate() {
                    q[j.offset + a] = acc[l].power(s);
                }
                let moved = (k.poses[j.parent].inverse() * k.poses[l]).transform_wrench(&acc[l]);
                acc[j.parent] += moved;
            }
        }
        if self.free {
            for (r, x) in acc[self.m.base].to_array().iter().enumerate() {
                q[self.base_index() + r] = *x;
            }
        }
        q
    }

    fn velocities(&self) -> Vec<f64> {
        let mut v = self.theta_dot.clone();
        if self.free {
            v.extend(self.base_twist.to_array());
        }
        v
    }

    fn advance(&self, v: &[f64]) -> Configuration {
        let h = self.h;
        let mut q = self.config.clone();
        for (t, d) in q.theta.iter_mut().zip(v) {
            *t += h * d;
        }
        if self.free {
            let phi = Twist::from_array(core::array::from_fn(|r| v[self.base_index() + r]));
            q.base = self.config.base * Pose::exp(&(phi * h));
        }
        q
    }

    /// Generalized momentum `∂T/∂v = M v` (each joint column against its subtree's momentum),
    /// with the base rows as the structure's world momentum when free.
    fn momentum(&self, k: &Kin, h: &[Wrench]) -> Vec<f64> {
        let mut p = vec![0.0; self.nv()];
        for (ji, j) in self.m.joints.iter().enumerate() {
            if self.m.tree_joint[j.child] == Some(ji) {
                for (c, s) in k.cols[ji].iter().enumerate() {
                    p[j.offset + c] = h[j.child].power(s);
                }
            }
        }
        if self.free {
            let b = self.base_index();
            let world = k.poses[self.m.base].transform_wrench(&h[self.m.base]);
            p[b..b + 6].copy_from_slice(&world.to_array());
        }
        p
    }

    /// Total energy (J): kinetic, joint springs, and gravity's potential.
    #[must_use]
    pub fn energy(&self) -> f64 {
        let k = self.kinematics(&self.config, &self.theta_dot, &self.base_twist);
        let kinetic: f64 = self
            .m
            .links
            .iter()
            .zip(&k.twists)
            .map(|(l, t)| l.inertia.kinetic_energy(t))
            .sum();
        let spring: f64 = self
            .m
            .joints
            .iter()
            .flat_map(|j| (0..j.dof()).map(move |c| (j, c)))
            .map(|(j, c)| 0.5 * self.config.theta[j.offset + c].powi(2) / j.compliance[c])
            .sum();
        let potential: f64 = self
            .m
            .links
            .iter()
            .zip(&k.poses)
            .map(|(l, p)| -l.inertia.mass * self.gravity.dot(p.transform_point(l.inertia.com)))
            .sum();
        kinetic + spring + potential
    }

    /// World poses of every link.
    #[must_use]
    pub fn poses(&self) -> Vec<Pose> {
        link_poses(self.m, &self.config)
    }

    /// Body twists of every link.
    #[must_use]
    pub fn link_twists(&self) -> Vec<Twist> {
        self.kinematics(&self.config, &self.theta_dot, &self.base_twist)
            .twists
    }

    /// Advances one step of length `h`. When Newton stalls (its tangent leaves out terms of
    /// order `h·|v|`, which a whipping chain makes large), the step is retried as two backward
    /// Euler steps of `h/2`, at most [`tol::FULL_MAX_HALVINGS`] times over; the report counts
    /// the sub-steps taken.
    ///
    /// # Errors
    /// [`Error::NoConvergence`] when Newton does not reach the tolerance even at the smallest
    /// sub-step; [`Error::Argument`] for a load on an unknown link or a non-finite state;
    /// [`Error::LinearAlgebra`] if a solve fails.
    pub fn step(&mut self) -> Result<FullStepReport, Error> {
        let h = self.h;
        let out = self.substep(h, 0);
        self.h = h;
        out
    }

    fn substep(&mut self, h: f64, depth: usize) -> Result<FullStepReport, Error> {
        let saved = (self.config.clone(), self.theta_dot.clone(), self.base_twist);
        self.h = h;
        match self.newton_step() {
            Err(Error::NoConvergence { .. }) if depth < tol::FULL_MAX_HALVINGS => {
                (self.config, self.theta_dot, self.base_twist) = saved;
                let a = self.substep(0.5 * h, depth + 1)?;
                let b = self.substep(0.5 * h, depth + 1)?;
                Ok(FullStepReport {
                    iterations: a.iterations + b.iterations,
                    residual: a.residual.max(b.residual),
                    substeps: a.substeps + b.substeps,
                })
            }
            other => other,
        }
    }

    fn newton_step(&mut self) -> Result<FullStepReport, Error> {
        for l in &self.loads {
            if l.link >= self.m.links.len() || !l.force.is_finite() || !l.torque.is_finite() {
                return Err(Error::Argument(format!(
                    "load on link index {}: unknown link or non-finite force/torque",
                    l.link
                )));
            }
        }
        let v0 = self.velocities();
        if !v0.iter().chain(&self.config.theta).all(|x| x.is_finite()) {
            return Err(Error::Argument("full state is not finite".into()));
        }
        let h = self.h;
        let m = self.m;
        let (n, nv) = (m.ndof, self.nv());
        let nl = m.loop_joints.len();
        let k0 = self.kinematics(&self.config, &self.theta_dot, &self.base_twist);
        let p0 = self.momentum(&k0, &self.subtree_momenta(&k0));
        let stiff: Vec<f64> = m
            .joints
            .iter()
            .flat_map(|j| j.compliance.iter().map(|c| 1.0 / c))
            .collect();
        let damp: Vec<f64> = m
            .joints
            .iter()
            .flat_map(|j| j.damping.iter().copied())
            .collect();
        let length = 1.0 + m.bounding_radius();

        // Residual of the implicit step at velocities v and closure impulses mu.
        let residual = |v: &[f64], mu: &[f64]| -> (Vec<f64>, Kin, Mat<f64>, f64) {
            let q = self.advance(v);
            let base_twist = if self.free {
                Twist::from_array(core::array::from_fn(|r| v[n + r]))
            } else {
                Twist::ZERO
            };
            let k = self.kinematics(&q, &v[..n], &base_twist);
            let hm = self.subtree_momenta(&k);
            let p = self.momentum(&k, &hm);
            let dt = self.kinetic_gradient(&q, &v[..n], &k, &hm);
            let f = self.generalized_force(&k);
            let mut r = vec![0.0; nv + 6 * nl];
            let mut scale = p0.iter().fold(0.0_f64, |a, x| a.max(x.abs()));
            for i in 0..n {
                let force = dt[i] - stiff[i] * q.theta[i] - damp[i] * v[i] + f[i];
                scale = scale.max((h * force).abs()).max(p[i].abs());
                r[i] = p[i] - p0[i] - h * force;
            }
            if self.free {
                // World momentum against the external impulse (world), in the base's frame.
                let fw = q
                    .base
                    .transform_wrench(&Wrench::from_array(core::array::from_fn(|c| f[n + c])));
                let d = Wrench::from_array(core::array::from_fn(|c| {
                    p[n + c] - p0[n + c] - h * fw.to_array()[c]
                }));
                let db = q.base.inverse_transform_wrench(&d).to_array();
                for c in 0..6 {
                    scale = scale.max(p[n + c].abs()).max((h * fw.to_array()[c]).abs());
                    r[n + c] = db[c];
                }
            }
            let mut g = Mat::<f64>::zeros(6 * nl, nv);
            let poses = &k.poses;
            for (li, &ji) in m.loop_joints.iter().enumerate() {
                let gk = loop_jacobian(m, &q, poses, ji);
                let rk = loop_residual(m, &q, poses, ji).to_array();
                for row in 0..6 {
                    r[nv + 6 * li + row] = rk[row] / h;
                    for c in 0..n {
                        g[(6 * li + row, c)] = gk[(row, c)];
                    }
                }
            }
            // Closure impulses Gᵀμ on the joint rows.
            for c in 0..n {
                let t: f64 = (0..6 * nl).map(|row| g[(row, c)] * mu[row]).sum();
                r[c] -= t;
            }
            (r, k, g, scale)
        };
        let size = |r: &[f64], scale: f64| -> f64 {
            if !r.iter().all(|x| x.is_finite()) {
                return f64::INFINITY;
            }
            let mom = r[..nv].iter().fold(0.0_f64, |a, x| a.max(x.abs())) / scale;
            let clo = r[nv..].iter().fold(0.0_f64, |a, x| a.max(x.abs())) * h / length;
            mom.max(clo)
        };

        let mut v = v0.clone();
        let mut mu = vec![0.0; 6 * nl];
        let (mut r, mut kin, mut g, mut scale) = residual(&v, &mu);
        let mut err = size(&r, scale);
        let mut it = 0;
        while err > self.options.tolerance {
            if it == self.options.max_iterations {
                return Err(Error::NoConvergence {
                    residual: err,
                    iterations: it,
                });
            }
            it += 1;
            let arm: Vec<f64> = (0..n).map(|i| h * damp[i] + h * h * stiff[i]).collect();
            let delta: Vec<f64> = if nl == 0 && !self.free && nv > tol::FULL_EXACT_TANGENT_MAX {
                // Tangent M + hD + h²K of a fixed-base tree: the articulated-body recursion
                // solves it in O(n) without forming M.
                let rhs: Vec<f64> = r.iter().map(|x| -x).collect();
                self.articulated_solve(&kin, &arm, &rhs)?
            } else {
                self.dense_step(&kin, &arm, &g, &r, &v, &mu, &residual)?
            };
            if !delta.iter().all(|x| x.is_finite()) {
                return Err(Error::LinearAlgebra("Newton step of the full model".into()));
            }
            let mut alpha = 1.0;
            loop {
                let vn: Vec<f64> = (0..nv).map(|i| v[i] + alpha * delta[i]).collect();
                let mn: Vec<f64> = (0..6 * nl).map(|i| mu[i] + alpha * delta[nv + i]).collect();
                let (rn, kn, gn, sn) = residual(&vn, &mn);
                let en = size(&rn, sn);
                if en < err || alpha < tol::STATIC_MIN_STEP {
                    (v, mu, r, kin, g, scale, err) = (vn, mn, rn, kn, gn, sn, en);
                    break;
                }
                alpha *= 0.5;
            }
        }
        let _ = (&r, &kin, &g, scale);
        self.config = self.advance(&v);
        self.theta_dot.copy_from_slice(&v[..n]);
        if self.free {
            self.base_twist = Twist::from_array(core::array::from_fn(|r| v[n + r]));
        }
        Ok(FullStepReport {
            iterations: it,
            residual: err,
            substeps: 1,
        })
    }

    /// One Newton step by a dense solve of `[M + A, −Gᵀ; G, 0] δ = −r` (`A` the diagonal
    /// `hD + h²K`); for small systems the velocity columns are differences of the residual.
    #[allow(clippy::too_many_arguments)]
    fn dense_step(
        &self,
        k: &Kin,
        arm: &[f64],
        g: &Mat<f64>,
        r: &[f64],
        v: &[f64],
        mu: &[f64],
        residual: &ResidualFn<'_>,
    ) -> Result<Vec<f64>, Error> {
        let (n, nv) = (self.m.ndof, self.nv());
        let nl = g.nrows() / 6;
        let dim = nv + 6 * nl;
        let mq = self.mass_matrix(k);
        let mut a = Mat::<f64>::zeros(dim, dim);
        for i in 0..nv {
            for c in 0..nv {
                a[(i, c)] = mq[(i, c)];
            }
        }
        for (i, x) in arm.iter().enumerate() {
            a[(i, i)] += x;
        }
        for row in 0..6 * nl {
            for c in 0..n {
                a[(nv + row, c)] = g[(row, c)];
                a[(c, nv + row)] = -g[(row, c)];
            }
        }
        if nv <= tol::FULL_EXACT_TANGENT_MAX {
            // Small systems: the velocity columns by forward differences of the residual
            // (Newton then converges quadratically, whatever h and the speeds).
            for c in 0..nv {
                let step = tol::FULL_TANGENT_STEP * (1.0 + v[c].abs());
                let mut vp = v.to_vec();
                vp[c] += step;
                let (rp, ..) = residual(&vp, mu);
                for (i, (x, y)) in rp.iter().zip(r).enumerate() {
                    a[(i, c)] = (x - y) / step;
                }
            }
        }
        let rhs = Mat::from_fn(dim, 1, |i, _| -r[i]);
        let delta = if nl == 0 {
            a.partial_piv_lu().solve(&rhs)
        } else {
            pinv(a.as_ref(), self.options.tsvd)?.inverse * rhs
        };
        Ok((0..dim).map(|i| delta[(i, 0)]).collect())
    }

    /// Solves `(M + diag(arm)) x = tau` for a fixed-base tree by the articulated-body
    /// recursion (Featherstone's ABA at zero velocity, the diagonal as joint armature): O(n).
    fn articulated_solve(&self, k: &Kin, arm: &[f64], tau: &[f64]) -> Result<Vec<f64>, Error> {
        let m = self.m;
        let dot = |a: &[f64; 6], b: &[f64; 6]| -> f64 { a.iter().zip(b).map(|(x, y)| x * y).sum() };
        let mut ia: Vec<Mat6> = m.links.iter().map(|l| l.inertia.to_mat6()).collect();
        let mut pa = vec![[0.0; 6]; m.links.len()];
        // Per tree joint: U = I^A S, D⁻¹, u = τ − Sᵀp^A.
        let mut saved: Vec<JointSolve> =
            vec![(Vec::new(), Mat::zeros(0, 0), Vec::new()); m.joints.len()];
        for &l in m.order.iter().rev() {
            let Some(ji) = m.tree_joint[l] else { continue };
            let j = &m.joints[ji];
            let d = j.dof();
            let s: Vec<[f64; 6]> = k.cols[ji].iter().map(Twist::to_array).collect();
            let u_cols: Vec<[f64; 6]> = s.iter().map(|c| ia[l].mul_array(c)).collect();
            let dm = Mat::from_fn(d, d, |a, b| {
                dot(&s[a], &u_cols[b]) + if a == b { arm[j.offset + a] } else { 0.0 }
            });
            let d_inv = dm.partial_piv_lu().solve(Mat::<f64>::identity(d, d));
            if !(0..d).all(|a| (0..d).all(|b| d_inv[(a, b)].is_finite())) {
                return Err(Error::LinearAlgebra(format!(
                    "articulated inertia of joint `{}`",
                    j.name
                )));
            }
            let u: Vec<f64> = (0..d)
                .map(|a| tau[j.offset + a] - dot(&s[a], &pa[l]))
                .collect();
            let mut i_a = ia[l];
            let mut p_a = pa[l];
            for a in 0..d {
                let du: f64 = (0..d).map(|b| d_inv[(a, b)] * u[b]).sum();
                for (x, y) in p_a.iter_mut().zip(&u_cols[a]) {
                    *x += y * du;
                }
                for b in 0..d {
                    i_a = i_a - Mat6::outer(&u_cols[a], &u_cols[b]) * d_inv[(a, b)];
                }
            }
            // To the parent: I_p += Xᵀ I X, p_p += Xᵀ p, X = ˡAd_p.
            let x = (k.poses[l].inverse() * k.poses[j.parent]).adjoint();
            let xt = x.transpose();
            // Symmetric against round-off (a chain of hundreds of links amplifies it).
            let i_a = (i_a + i_a.transpose()) * 0.5;
            ia[j.parent] = ia[j.parent] + xt * i_a * x;
            let moved = xt.mul_array(&p_a);
            for (y, z) in pa[j.parent].iter_mut().zip(moved) {
                *y += z;
            }
            saved[ji] = (u_cols, d_inv, u);
        }
        let mut acc = vec![[0.0; 6]; m.links.len()];
        let mut out = vec![0.0; m.ndof];
        for &l in &m.order[1..] {
            let Some(ji) = m.tree_joint[l] else { continue };
            let j = &m.joints[ji];
            let (u_cols, d_inv, u) = &saved[ji];
            let x = (k.poses[l].inverse() * k.poses[j.parent]).adjoint();
            let mut a_l = x.mul_array(&acc[j.parent]);
            let r: Vec<f64> = (0..j.dof()).map(|a| u[a] - dot(&u_cols[a], &a_l)).collect();
            for a in 0..j.dof() {
                let qdd: f64 = (0..j.dof()).map(|b| d_inv[(a, b)] * r[b]).sum();
                out[j.offset + a] = qdd;
                let s = k.cols[ji][a].to_array();
                for (y, z) in a_l.iter_mut().zip(s) {
                    *y += z * qdd;
                }
            }
            acc[l] = a_l;
        }
        Ok(out)
    }

    /// The structure's linear and angular momentum in world axes (angular about the world
    /// origin), from every link's pose and body twist.
    #[must_use]
    pub fn world_momentum(&self) -> Wrench {
        let k = self.kinematics(&self.config, &self.theta_dot, &self.base_twist);
        self.m
            .links
            .iter()
            .zip(k.poses.iter().zip(&k.twists))
            .fold(Wrench::ZERO, |acc, (l, (p, t))| {
                acc + p.transform_wrench(&l.inertia.mul_twist(t))
            })
    }
}

#[cfg(test)]
#[path = "dynamics_tests.rs"]
mod tests;
