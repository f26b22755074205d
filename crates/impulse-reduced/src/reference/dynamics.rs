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
//! `M(q)` by composite inertias (CRBA), `∂T/∂θ` by central differences of `T` over each joint's
//! subtree (its error, ~1e-10 relative, only perturbs the trajectory at that level). The
//! implicit system is solved by Newton. Small systems (≤ [`tol::FULL_EXACT_TANGENT_MAX`]
//! velocities) take the tangent's velocity columns by differences of the residual; larger
//! ones the tangent `[M + hD + h²K, −Gᵀ; G, 0]` (the Coriolis, load-stiffness and
//! mass-variation terms it leaves out only slow the convergence; the residual is exact), each solve by LU, or by truncated SVD when loops are
//! present (redundant closures), with backtracking on the residual. Backward Euler dissipates:
//! the energy does not grow for any step (tested at h = 1 s).

use faer::Mat;
use faer::linalg::solvers::Solve;
use glam::DVec3;
use impulse_geom::{Pose, SpatialInertia, Twist, Wrench};

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
    /// Final relative residual.
    pub residual: f64,
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
    /// Links below each link in the tree (itself first, walk order).
    subtree: Vec<Vec<usize>>,
    free: bool,
}

/// Kinematic state of every link: poses, joint columns (child frame), body twists.
struct Kin {
    poses: Vec<Pose>,
    /// Per joint, its motion columns in the child's frame (tree joints only).
    cols: Vec<Vec<Twist>>,
    twists: Vec<Twist>,
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
        let mut subtree = vec![Vec::new(); m.links.len()];
        for &l in m.order.iter().rev() {
            let mut below = vec![l];
            for &j in &m.joints_out[l] {
                let c = m.joints[j].child;
                if m.tree_joint[c] == Some(j) {
                    below.extend(subtree[c].iter().copied());
                }
            }
            subtree[l] = below;
        }
        // Walk order inside each subtree (a child's list is already in walk order).
        let rank: Vec<usize> = {
            let mut r = vec![0; m.links.len()];
            for (i, &l) in m.order.iter().enumerate() {
                r[l] = i;
            }
            r
        };
        for s in &mut subtree {
            s.sort_by_key(|&l| rank[l]);
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
            subtree,
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

    /// `∂T/∂θ` at fixed velocities, by central differences over each tree joint's subtree.
    fn kinetic_gradient(&self, q: &Configuration, td: &[f64], k: &Kin) -> Vec<f64> {
        let mut g = vec![0.0; self.m.ndof];
        let mut work = Kin {
            poses: k.poses.clone(),
            cols: k.cols.clone(),
            twists: k.twists.clone(),
        };
        let mut qp = q.clone();
        for (ji, j) in self.m.joints.iter().enumerate() {
            if self.m.tree_joint[j.child] != Some(ji) {
                continue; // a loop joint moves no link
            }
            let below = &self.subtree[j.child];
            for c in 0..j.dof() {
                let i = j.offset + c;
                let step = self.options.fd_step * (1.0 + q.theta[i].abs());
                let mut t = [0.0; 2];
                for (side, sign) in [1.0, -1.0].into_iter().enumerate() {
                    qp.theta[i] = q.theta[i] + sign * step;
                    for &l in below {
                        self.descend(&mut work, &qp, td, l);
                    }
                    t[side] = below
                        .iter()
                        .map(|&l| self.m.links[l].inertia.kinetic_energy(&work.twists[l]))
                        .sum();
                }
                qp.theta[i] = q.theta[i];
                g[i] = (t[0] - t[1]) / (2.0 * step);
            }
            for &l in below {
                work.poses[l] = k.poses[l];
                work.twists[l] = k.twists[l];
            }
            for &l in below {
                if let Some(jj) = self.m.tree_joint[l] {
                    work.cols[jj].clone_from(&k.cols[jj]);
                }
            }
        }
        g
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

    /// Generalized momentum `M v`, with the base rows as the world momentum when free.
    fn momentum(&self, mq: &Mat<f64>, v: &[f64], base: &Pose) -> Vec<f64> {
        let n = v.len();
        let mut p: Vec<f64> = (0..n)
            .map(|r| (0..n).map(|c| mq[(r, c)] * v[c]).sum())
            .collect();
        if self.free {
            let b = self.base_index();
            let pb = Wrench::from_array(core::array::from_fn(|r| p[b + r]));
            p[b..b + 6].copy_from_slice(&base.transform_wrench(&pb).to_array());
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

    /// Advances one step of length `h`.
    ///
    /// # Errors
    /// [`Error::NoConvergence`] when Newton does not reach the tolerance;
    /// [`Error::Argument`] for a load on an unknown link or a non-finite state;
    /// [`Error::LinearAlgebra`] if a solve fails.
    pub fn step(&mut self) -> Result<FullStepReport, Error> {
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
        let p0 = self.momentum(&self.mass_matrix(&k0), &v0, &self.config.base);
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
        let residual = |v: &[f64], mu: &[f64]| -> (Vec<f64>, Mat<f64>, Mat<f64>, f64) {
            let q = self.advance(v);
            let base_twist = if self.free {
                Twist::from_array(core::array::from_fn(|r| v[n + r]))
            } else {
                Twist::ZERO
            };
            let k = self.kinematics(&q, &v[..n], &base_twist);
            let mq = self.mass_matrix(&k);
            let p = self.momentum(&mq, v, &q.base);
            let dt = self.kinetic_gradient(&q, &v[..n], &k);
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
            (r, mq, g, scale)
        };
        let size = |r: &[f64], scale: f64| -> f64 {
            let mom = r[..nv].iter().fold(0.0_f64, |a, x| a.max(x.abs())) / scale;
            let clo = r[nv..].iter().fold(0.0_f64, |a, x| a.max(x.abs())) * h / length;
            mom.max(clo)
        };

        let mut v = v0.clone();
        let mut mu = vec![0.0; 6 * nl];
        let (mut r, mut mq, mut g, mut scale) = residual(&v, &mu);
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
            // Tangent [M + hD + h²K, −Gᵀ; G, 0].
            let dim = nv + 6 * nl;
            let mut a = Mat::<f64>::zeros(dim, dim);
            for i in 0..nv {
                for c in 0..nv {
                    a[(i, c)] = mq[(i, c)];
                }
            }
            for i in 0..n {
                a[(i, i)] += h * damp[i] + h * h * stiff[i];
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
                    let mut vp = v.clone();
                    vp[c] += step;
                    let (rp, ..) = residual(&vp, &mu);
                    for (i, (x, y)) in rp.iter().zip(&r).enumerate() {
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
            if !(0..dim).all(|i| delta[(i, 0)].is_finite()) {
                return Err(Error::LinearAlgebra("Newton step of the full model".into()));
            }
            let mut alpha = 1.0;
            loop {
                let vn: Vec<f64> = (0..nv).map(|i| v[i] + alpha * delta[(i, 0)]).collect();
                let mn: Vec<f64> = (0..6 * nl)
                    .map(|i| mu[i] + alpha * delta[(nv + i, 0)])
                    .collect();
                let (rn, mqn, gn, sn) = residual(&vn, &mn);
                let en = size(&rn, sn);
                if en < err || alpha < tol::STATIC_MIN_STEP {
                    (v, mu, r, mq, g, scale, err) = (vn, mn, rn, mqn, gn, sn, en);
                    break;
                }
                alpha *= 0.5;
            }
        }
        let _ = (&r, scale);
        self.config = self.advance(&v);
        self.theta_dot.copy_from_slice(&v[..n]);
        if self.free {
            self.base_twist = Twist::from_array(core::array::from_fn(|r| v[n + r]));
        }
        Ok(FullStepReport {
            iterations: it,
            residual: err,
        })
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
