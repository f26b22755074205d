//! Nonlinear static equilibrium of the full model under end-effector loads, loops included.
//!
//! Unknowns: every joint coordinate θ and one multiplier wrench λ_k per loop joint. Equations
//! (the stationarity of the joint-spring energy under the loads and the closure constraints):
//!
//! `f(θ, λ) = −K_q θ + Σ_loads J_lᵀ(θ) w_l(θ) + Σ_k G_kᵀ(θ) λ_k = 0`,  `r_k(θ) = 0`,
//!
//! with `w_l` the load as a body wrench (a world-fixed force and torque at the link origin,
//! turned into link axes), `r_k` the loop residual and `G_k` its Jacobian
//! ([`crate::reference::kinematics`]). Newton: the θ-columns of the tangent by central
//! differences of the residual (its accuracy sets only the rate, the residual is exact), the
//! λ-columns exactly; each step solved with the truncated SVD (redundant loop constraints, e.g.
//! planar loops of hinges, make the KKT matrix singular); backtracking on the residual norm;
//! the load applied in `load_steps` increments.

use faer::Mat;
use glam::DVec3;
use impulse_geom::{Pose, Wrench};

use crate::error::Error;
use crate::linalg::{Tsvd, pinv};
use crate::mechanism::Mechanism;
use crate::reference::kinematics::{
    Configuration, body_jacobian, link_poses, loop_jacobian, loop_residual,
};
use crate::tol;

/// A load: a world-fixed force and torque applied at a link's frame origin.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Load {
    /// The loaded link.
    pub link: usize,
    /// Force (world, N).
    pub force: DVec3,
    /// Torque (world, N·m).
    pub torque: DVec3,
}

impl Load {
    /// The load as a body wrench of a link at pose `pose` (link axes, about its origin).
    #[must_use]
    pub fn body_wrench(&self, pose: &Pose) -> Wrench {
        Wrench::new(
            pose.inverse_transform_vector(self.force),
            pose.inverse_transform_vector(self.torque),
        )
    }
}

/// Settings of [`solve_statics`].
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct StaticOptions {
    /// Number of equal load increments.
    pub load_steps: usize,
    /// Newton iterations allowed per increment.
    pub max_iterations: usize,
    /// Relative residual at which Newton stops ([`tol::STATIC_RESIDUAL_REL`]).
    pub tolerance: f64,
    /// Truncation of the Newton solves.
    pub tsvd: Tsvd,
}

impl Default for StaticOptions {
    fn default() -> Self {
        StaticOptions {
            load_steps: 1,
            max_iterations: tol::STATIC_MAX_ITERATIONS,
            tolerance: tol::STATIC_RESIDUAL_REL,
            tsvd: Tsvd::default(),
        }
    }
}

/// A static equilibrium.
#[derive(Clone, Debug)]
pub struct StaticSolution {
    /// The configuration.
    pub config: Configuration,
    /// Loop multipliers (6 per loop joint, parent-side joint frame).
    pub multipliers: Vec<f64>,
    /// Newton iterations used in all.
    pub iterations: usize,
    /// Final relative residual.
    pub residual: f64,
}

struct Residual {
    values: Vec<f64>,
    /// Scale of the force terms (for the relative test).
    force_scale: f64,
    /// Largest closure residual component.
    closure: f64,
}

fn residual(
    m: &Mechanism,
    q: &Configuration,
    lambda: &[f64],
    loads: &[Load],
    scale: f64,
) -> (Residual, Mat<f64>) {
    let poses = link_poses(m, q);
    let n = m.ndof;
    let nl = m.loop_joints.len();
    let mut f = vec![0.0; n + 6 * nl];
    let mut force_scale = 0.0_f64;
    for j in &m.joints {
        for (k, c) in j.compliance.iter().enumerate() {
            let t = -q.theta[j.offset + k] / c;
            f[j.offset + k] = t;
            force_scale = force_scale.max(t.abs());
        }
    }
    for load in loads {
        let w = load.body_wrench(&poses[load.link]).to_array();
        let jac = body_jacobian(m, q, &poses, load.link);
        for (c, fc) in f[..n].iter_mut().enumerate() {
            // As `Iterator::sum` for f64: from -0.0, in order.
            let mut g = -0.0;
            for (j, wr) in jac.col_as_slice(c).iter().zip(&w) {
                g += j * wr * scale;
            }
            *fc += g;
            force_scale = force_scale.max(g.abs());
        }
    }
    let mut gmat = Mat::<f64>::zeros(6 * nl, n);
    let mut closure = 0.0_f64;
    for (k, &ji) in m.loop_joints.iter().enumerate() {
        let g = loop_jacobian(m, q, &poses, ji);
        let r = loop_residual(m, q, &poses, ji).to_array();
        for row in 0..6 {
            f[n + 6 * k + row] = r[row];
            closure = closure.max(r[row].abs());
        }
        // Through column slices: the same copies and sums as element indexing, without
        // faer's per-element index calls (most of the time in the test profile).
        for (c, fc) in f[..n].iter_mut().enumerate() {
            let col = g.col_as_slice(c);
            gmat.col_as_slice_mut(c)[6 * k..6 * k + 6].copy_from_slice(col);
            let mut t = -0.0;
            for (gr, l) in col.iter().zip(&lambda[6 * k..6 * k + 6]) {
                t += gr * l;
            }
            *fc += t;
        }
    }
    (
        Residual {
            values: f,
            force_scale,
            closure,
        },
        gmat,
    )
}

fn converged(r: &Residual, n: usize, tolerance: f64, length: f64) -> (bool, f64) {
    let fmax = r.values[..n].iter().fold(0.0_f64, |a, x| a.max(x.abs()));
    let rel = fmax / r.force_scale.max(f64::MIN_POSITIVE);
    let ok = rel <= tolerance && r.closure <= tolerance * length;
    (ok, rel.max(r.closure / length))
}

fn merit(r: &Residual, n: usize, length: f64) -> f64 {
    let fs = r.force_scale.max(f64::MIN_POSITIVE);
    r.values[..n].iter().map(|x| (x / fs).powi(2)).sum::<f64>()
        + r.values[n..]
            .iter()
            .map(|x| (x / length).powi(2))
            .sum::<f64>()
}

/// Static equilibrium of `m` under `loads`, starting from `start` (rest when `None`).
///
/// # Errors
/// [`Error::NoConvergence`] when Newton stalls; [`Error::Argument`] for a bad load;
/// [`Error::LinearAlgebra`] if a solve fails.
pub fn solve_statics(
    m: &Mechanism,
    loads: &[Load],
    start: Option<&StaticSolution>,
    options: &StaticOptions,
) -> Result<StaticSolution, Error> {
    for l in loads {
        if l.link >= m.links.len() || !l.force.is_finite() || !l.torque.is_finite() {
            return Err(Error::Argument(format!(
                "load on link index {}: unknown link or non-finite force/torque",
                l.link
            )));
        }
    }
    let n = m.ndof;
    let nl = m.loop_joints.len();
    let mut q = start.map_or_else(|| Configuration::rest(m), |s| s.config.clone());
    let mut lambda = start.map_or_else(|| vec![0.0; 6 * nl], |s| s.multipliers.clone());
    let length = 1.0 + m.bounding_radius();
    let steps = options.load_steps.max(1);
    let mut iterations = 0;
    let mut last = 0.0;
    for step in 1..=steps {
        let scale = step as f64 / steps as f64;
        let mut it = 0;
        loop {
            let (r, gmat) = residual(m, &q, &lambda, loads, scale);
            let (ok, rel) = converged(&r, n, options.tolerance, length);
            last = rel;
            if ok {
                break;
            }
            if it == options.max_iterations {
                return Err(Error::NoConvergence {
                    residual: rel,
                    iterations: iterations + it,
                });
            }
            it += 1;
            // Tangent: θ-columns by central differences, λ-columns = Gᵀ (f is linear in λ).
            let dim = n + 6 * nl;
            let mut tangent = Mat::<f64>::zeros(dim, dim);
            for c in 0..n {
                let h = tol::STATIC_FD_STEP * (1.0 + q.theta[c].abs());
                let mut qp = q.clone();
                qp.theta[c] += h;
                let (rp, _) = residual(m, &qp, &lambda, loads, scale);
                let mut qm = q.clone();
                qm.theta[c] -= h;
                let (rm, _) = residual(m, &qm, &lambda, loads, scale);
                for (row, t) in tangent.col_as_slice_mut(c).iter_mut().enumerate() {
                    *t = (rp.values[row] - rm.values[row]) / (2.0 * h);
                }
            }
            for c in 0..n {
                for (k, &x) in gmat.col_as_slice(c).iter().enumerate() {
                    tangent[(c, n + k)] = x;
                }
            }
            let rhs = Mat::from_fn(dim, 1, |i, _| -r.values[i]);
            let step_vec = pinv(tangent.as_ref(), options.tsvd)?.inverse * rhs;
            // Backtracking on the scaled residual norm.
            let m0 = merit(&r, n, length);
            let mut alpha = 1.0;
            loop {
                let mut qn = q.clone();
                for c in 0..n {
                    qn.theta[c] += alpha * step_vec[(c, 0)];
                }
                let ln: Vec<f64> = (0..6 * nl)
                    .map(|k| lambda[k] + alpha * step_vec[(n + k, 0)])
                    .collect();
                let (rn, _) = residual(m, &qn, &ln, loads, scale);
                if merit(&rn, n, length) < m0 || alpha < tol::STATIC_MIN_STEP {
                    q = qn;
                    lambda = ln;
                    break;
                }
                alpha *= 0.5;
            }
        }
        iterations += it;
    }
    Ok(StaticSolution {
        config: q,
        multipliers: lambda,
        iterations,
        residual: last,
    })
}
