//! Nonlinear static equilibrium of the full model under end-effector loads, loops included.
//!
//! Unknowns: every joint coordinate θ and one multiplier wrench λ_k per loop joint. Equations
//! (the stationarity of the joint-spring energy under the loads and the closure constraints):
//!
//! `f(θ, λ) = −K_q θ + Σ_loads J_lᵀ(θ) w_l(θ) + Σ_k G_kᵀ(θ) λ_k = 0`,  `r_k(θ) = 0`,
//!
//! with `w_l` the load as a body wrench (a world-fixed force and torque at the link origin,
//! turned into link axes), `r_k` the loop residual and `G_k` its Jacobian
//! ([`crate::reference::kinematics`]).
//!
//! **Solver: globalised Newton with load continuation.**
//! - *Tangent*: exact, from second-order kinematics (`reference/tangent.rs`: the
//!   geometric stiffness of the loads and of the loop multipliers included), checked against
//!   central differences in its tests.
//! - *Newton step*: the KKT system `[∂f/∂θ, Gᵀ; G, 0]` scaled symmetrically by `√c` on the
//!   joint coordinates (the spring block becomes `−I`, so the truncated SVD judges the loop
//!   constraints against the springs and not against the stiffest joint), solved by LU for a
//!   tree and by truncated SVD with loops (redundant closures, e.g. planar loops of hinges,
//!   make the KKT matrix singular).
//! - *Line search*: Armijo backtracking on a fixed merit `½‖D (f, r)‖²`, D = the joint
//!   compliances on the force rows (so each row reads as the coordinate's own displacement
//!   error), lengths over the bounding radius; the Newton direction descends on it for any
//!   fixed D. A merit whose weights moved with the iterate (the force scale of the current
//!   point, as this solver once had) can "decrease" by growing its own scale, and the old
//!   solver then stalled at a floor proportional to the load on random ladders.
//! - *Load continuation*: the loads are applied along `L(s) = L₀ + s (L − L₀)` (L₀ the loads
//!   the start balances, none at rest), s from 0 to 1 in adaptive increments: an increment
//!   whose Newton iteration or line search fails, or whose corrector moves a joint by more
//!   than [`tol::STATIC_MAX_CORRECTION`] from the predictor (it may have left the equilibrium
//!   branch: from rest under a large load Newton can converge straight to a far, unstable
//!   equilibrium, as it did on two of the fifty hard cases, `crate::hard_cases`), is halved
//!   and retried from the last equilibrium; one that converges in few iterations doubles the
//!   next; each starts from the secant through the last two equilibria.
//! - *Failure*: when the increment falls below [`StaticOptions::min_load_step`] (no nearby
//!   equilibrium: a limit point, or none at all) the error ([`Error::NoEquilibrium`]) gives
//!   the load fraction reached, the residual history of the last attempt and the joint or loop
//!   whose equation is furthest from balance.

use faer::Mat;
use faer::linalg::solvers::Solve;
use glam::DVec3;
use impulse_geom::{Pose, Wrench};

use crate::error::Error;
use crate::linalg::{Tsvd, pinv};
use crate::mechanism::{Direction, Mechanism};
use crate::reference::kinematics::Configuration;
use crate::reference::tangent::{Evaluation, Topology, evaluate};
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
    /// Number of equal load increments to start the continuation with (it adapts them).
    pub load_steps: usize,
    /// Newton iterations allowed per increment before the increment is halved.
    pub max_iterations: usize,
    /// Relative residual at which Newton stops ([`tol::STATIC_RESIDUAL_REL`]).
    pub tolerance: f64,
    /// Smallest load increment, as a fraction of the whole load path, before the solve
    /// reports that no equilibrium was found ([`tol::STATIC_MIN_LOAD_STEP`]).
    pub min_load_step: f64,
    /// Most load increments taken in all ([`tol::STATIC_MAX_LOAD_STEPS`]).
    pub max_load_steps: usize,
    /// Truncation of the Newton solves with loops.
    pub tsvd: Tsvd,
}

impl Default for StaticOptions {
    fn default() -> Self {
        StaticOptions {
            load_steps: 1,
            max_iterations: tol::STATIC_MAX_ITERATIONS,
            tolerance: tol::STATIC_RESIDUAL_REL,
            min_load_step: tol::STATIC_MIN_LOAD_STEP,
            max_load_steps: tol::STATIC_MAX_LOAD_STEPS,
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
    /// The loads it balances (a warm start for another load continues from these).
    pub loads: Vec<Load>,
    /// Newton iterations used in all (failed increments included).
    pub iterations: usize,
    /// Load increments accepted.
    pub load_steps: usize,
    /// Final relative residual.
    pub residual: f64,
}

/// The unknowns of the statics.
#[derive(Clone)]
struct State {
    theta: Vec<f64>,
    lambda: Vec<f64>,
}

/// What is fixed during one solve.
struct Problem<'a> {
    m: &'a Mechanism,
    topo: Topology,
    base: Pose,
    /// The loads at s = 0 and at s = 1, on the same links in the same order.
    from: Vec<Load>,
    to: Vec<Load>,
    options: StaticOptions,
    /// Lengths are judged against this (m): 1 + the bounding radius.
    length: f64,
    /// Per coordinate: its compliance, and its unit (1 for angles, `length` for lengths).
    compliance: Vec<f64>,
    unit: Vec<f64>,
}

/// Why one increment failed.
struct Failure {
    reason: String,
    history: Vec<f64>,
    last: Option<Evaluation>,
    iterations: usize,
}

impl Problem<'_> {
    fn config(&self, x: &State) -> Configuration {
        Configuration {
            base: self.base,
            theta: x.theta.clone(),
        }
    }

    fn loads_at(&self, s: f64) -> Vec<Load> {
        self.from
            .iter()
            .zip(&self.to)
            .map(|(a, b)| Load {
                link: b.link,
                force: a.force + (b.force - a.force) * s,
                torque: a.torque + (b.torque - a.torque) * s,
            })
            .collect()
    }

    fn eval(&self, x: &State, s: f64, tangent: bool) -> Evaluation {
        evaluate(
            self.m,
            &self.topo,
            &self.config(x),
            &x.lambda,
            &self.loads_at(s),
            1.0,
            tangent,
        )
    }

    /// The relative residual: force rows over the force scale, closure over `length`.
    fn relative(&self, e: &Evaluation) -> (bool, f64) {
        let n = self.m.ndof;
        let fmax = e.values[..n].iter().fold(0.0_f64, |a, x| a.max(x.abs()));
        let closure = e.values[n..].iter().fold(0.0_f64, |a, x| a.max(x.abs()));
        let rel = fmax / e.force_scale.max(f64::MIN_POSITIVE);
        let tol = self.options.tolerance;
        (
            rel <= tol && closure <= tol * self.length,
            rel.max(closure / self.length),
        )
    }

    /// The merit `½‖D (f, r)‖²` (fixed weights: see the module doc).
    fn merit(&self, e: &Evaluation) -> f64 {
        let n = self.m.ndof;
        let f: f64 = (0..n)
            .map(|i| (self.compliance[i] * e.values[i] / self.unit[i]).powi(2))
            .sum();
        let r: f64 = e.values[n..]
            .chunks(6)
            .map(|c| {
                (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]) / (self.length * self.length)
                    + c[3] * c[3]
                    + c[4] * c[4]
                    + c[5] * c[5]
            })
            .sum();
        0.5 * (f + r)
    }

    /// The Newton direction: the KKT system scaled by `√c` on the joint coordinates.
    fn direction(&self, e: &Evaluation) -> Result<Vec<f64>, Error> {
        let t = e.tangent.as_ref().expect("tangent evaluated");
        let dim = e.values.len();
        let n = self.m.ndof;
        let d: Vec<f64> = (0..dim)
            .map(|i| {
                if i < n {
                    self.compliance[i].sqrt()
                } else {
                    1.0
                }
            })
            .collect();
        let a = Mat::from_fn(dim, dim, |i, j| d[i] * t[(i, j)] * d[j]);
        let rhs = Mat::from_fn(dim, 1, |i, _| -d[i] * e.values[i]);
        let y = if self.m.loop_joints.is_empty() {
            let y = a.partial_piv_lu().solve(&rhs);
            if (0..dim).all(|i| y[(i, 0)].is_finite()) {
                y
            } else {
                pinv(a.as_ref(), self.options.tsvd)?.inverse * rhs
            }
        } else {
            pinv(a.as_ref(), self.options.tsvd)?.inverse * rhs
        };
        Ok((0..dim).map(|i| d[i] * y[(i, 0)]).collect())
    }

    /// Newton at load fraction `s` from `x`: the equilibrium, or why not.
    fn newton(&self, s: f64, mut x: State) -> Result<Result<(State, usize), Failure>, Error> {
        let n = self.m.ndof;
        let mut history = Vec::new();
        let mut e = self.eval(&x, s, true);
        for it in 0..=self.options.max_iterations {
            let (ok, rel) = self.relative(&e);
            history.push(rel);
            if !rel.is_finite() {
                return Ok(Err(Failure {
                    reason: "the residual is not finite".to_owned(),
                    history,
                    last: None,
                    iterations: it,
                }));
            }
            if ok {
                return Ok(Ok((x, it)));
            }
            if it == self.options.max_iterations {
                break;
            }
            let dir = self.direction(&e)?;
            let m0 = self.merit(&e);
            let mut alpha = 1.0;
            loop {
                let trial = State {
                    theta: (0..n).map(|i| x.theta[i] + alpha * dir[i]).collect(),
                    lambda: (0..x.lambda.len())
                        .map(|k| x.lambda[k] + alpha * dir[n + k])
                        .collect(),
                };
                let et = self.eval(&trial, s, false);
                let mt = self.merit(&et);
                // Armijo on the merit: the Newton direction's slope is −2·m0.
                if mt.is_finite() && mt <= (1.0 - 2.0 * tol::STATIC_ARMIJO * alpha) * m0 {
                    x = trial;
                    e = self.eval(&x, s, true);
                    break;
                }
                alpha *= 0.5;
                if alpha < tol::STATIC_MIN_STEP {
                    return Ok(Err(Failure {
                        reason: format!(
                            "the line search found no decrease along the Newton direction \
                             (step below {:e})",
                            tol::STATIC_MIN_STEP
                        ),
                        history,
                        last: Some(e),
                        iterations: it + 1,
                    }));
                }
            }
        }
        Ok(Err(Failure {
            reason: format!(
                "Newton did not converge in {} iterations",
                self.options.max_iterations
            ),
            history,
            last: Some(e),
            iterations: self.options.max_iterations,
        }))
    }

    /// The largest change of a joint coordinate from `a` to `b`, angles in radians and
    /// lengths over `length`.
    fn correction(&self, a: &State, b: &State) -> f64 {
        a.theta
            .iter()
            .zip(&b.theta)
            .zip(&self.unit)
            .fold(0.0_f64, |m, ((x, y), u)| m.max((x - y).abs() / u))
    }

    /// The equation furthest from balance in `e`, named (joint coordinate or loop).
    fn worst(&self, e: &Evaluation) -> String {
        let m = self.m;
        let n = m.ndof;
        let (mut best, mut what) = (0.0_f64, "none".to_owned());
        for j in &m.joints {
            for k in 0..j.dof() {
                let i = j.offset + k;
                let scaled = (self.compliance[i] * e.values[i] / self.unit[i]).abs();
                if scaled > best {
                    let unit = match j.directions[k].0 {
                        Direction::Rotation => "N·m",
                        Direction::Translation => "N",
                    };
                    best = scaled;
                    what = format!(
                        "joint `{}` direction {k}: force residual {:.3e} {unit} ({:.1e} of the \
                         force scale)",
                        j.name,
                        e.values[i],
                        e.values[i].abs() / e.force_scale.max(f64::MIN_POSITIVE)
                    );
                }
            }
        }
        for (k, &ji) in m.loop_joints.iter().enumerate() {
            let r = &e.values[n + 6 * k..n + 6 * k + 6];
            let lin = (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt();
            let ang = (r[3] * r[3] + r[4] * r[4] + r[5] * r[5]).sqrt();
            let scaled = (lin / self.length).max(ang);
            if scaled > best {
                best = scaled;
                what = format!(
                    "loop joint `{}` does not close: {lin:.3e} m, {ang:.3e} rad apart",
                    m.joints[ji].name
                );
            }
        }
        what
    }
}

/// Static equilibrium of `m` under `loads`, starting from `start` (rest when `None`): the
/// loads are applied by continuation from those `start` balances (see the module doc).
///
/// # Errors
/// [`Error::NoEquilibrium`] when the continuation cannot follow the equilibrium to the full
/// load; [`Error::Argument`] for a bad load or bad options; [`Error::LinearAlgebra`] if a
/// solve fails.
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
    let o = options;
    if !(o.tolerance > 0.0 && o.min_load_step > 0.0 && o.min_load_step <= 1.0) {
        return Err(Error::Argument(format!(
            "static options: tolerance {} and min_load_step {} must be positive (and the \
             step at most 1)",
            o.tolerance, o.min_load_step
        )));
    }
    let nl = m.loop_joints.len();
    let length = 1.0 + m.bounding_radius();
    // The load path: from the loads `start` balances to `loads`, link by link.
    let (mut from, mut to) = (Vec::new(), Vec::new());
    let zero = |link| Load {
        link,
        force: DVec3::ZERO,
        torque: DVec3::ZERO,
    };
    for l in start.map_or(&[][..], |s| &s.loads) {
        from.push(*l);
        to.push(zero(l.link));
    }
    for l in loads {
        from.push(zero(l.link));
        to.push(*l);
    }
    let problem = Problem {
        m,
        topo: Topology::new(m),
        base: start.map_or(m.links[m.base].rest, |s| s.config.base),
        from,
        to,
        options: *options,
        length,
        compliance: m
            .joints
            .iter()
            .flat_map(|j| j.compliance.iter().copied())
            .collect(),
        unit: m
            .joints
            .iter()
            .flat_map(|j| {
                j.directions.iter().map(|(d, _)| match d {
                    Direction::Rotation => 1.0,
                    Direction::Translation => length,
                })
            })
            .collect(),
    };
    let mut x = State {
        theta: start.map_or_else(|| vec![0.0; m.ndof], |s| s.config.theta.clone()),
        lambda: start.map_or_else(|| vec![0.0; 6 * nl], |s| s.multipliers.clone()),
    };
    let mut s = 0.0_f64;
    let mut ds = 1.0 / options.load_steps.max(1) as f64;
    let mut previous: Option<(f64, State)> = None;
    let (mut iterations, mut accepted) = (0, 0);
    let mut last_rel = 0.0;
    // A start that balances its loads only to the tolerance: settle it first (s = 0).
    if start.is_some() {
        match problem.newton(0.0, x.clone())? {
            Ok((xs, it)) => {
                x = xs;
                iterations += it;
            }
            Err(f) => return Err(no_equilibrium(&problem, 0.0, 0.0, f)),
        }
    }
    while s < 1.0 {
        if accepted + 1 > options.max_load_steps {
            let e = problem.eval(&x, s, false);
            return Err(Error::NoEquilibrium {
                fraction: s,
                step: ds,
                reason: format!("{accepted} load increments did not reach the load"),
                worst: problem.worst(&e),
                history: vec![problem.relative(&e).1],
            });
        }
        let target = (s + ds).min(1.0);
        // Secant predictor through the last two equilibria.
        let guess = match &previous {
            Some((sp, xp)) if s > *sp => {
                let k = (target - s) / (s - sp);
                State {
                    theta: x
                        .theta
                        .iter()
                        .zip(&xp.theta)
                        .map(|(a, b)| a + k * (a - b))
                        .collect(),
                    lambda: x
                        .lambda
                        .iter()
                        .zip(&xp.lambda)
                        .map(|(a, b)| a + k * (a - b))
                        .collect(),
                }
            }
            _ => x.clone(),
        };
        match problem.newton(target, guess.clone())? {
            // A corrector that moved a joint far from the predictor may have left the branch
            // for another equilibrium (Newton converges from rest straight to a far, unstable
            // one under a large load): the increment is halved, unless it cannot be.
            Ok((xs, it))
                if problem.correction(&guess, &xs) > tol::STATIC_MAX_CORRECTION
                    && ds * 0.5 >= options.min_load_step =>
            {
                iterations += it;
                ds *= 0.5;
            }
            Ok((xs, it)) => {
                iterations += it;
                accepted += 1;
                previous = Some((s, x));
                x = xs;
                s = target;
                last_rel = problem.relative(&problem.eval(&x, s, false)).1;
                if it <= tol::STATIC_FAST_ITERATIONS {
                    ds *= 2.0;
                }
            }
            Err(f) => {
                iterations += f.iterations;
                ds *= 0.5;
                if ds < options.min_load_step {
                    return Err(no_equilibrium(&problem, s, ds * 2.0, f));
                }
            }
        }
    }
    Ok(StaticSolution {
        config: problem.config(&x),
        multipliers: x.lambda,
        loads: loads.to_vec(),
        iterations,
        load_steps: accepted,
        residual: last_rel,
    })
}

fn no_equilibrium(problem: &Problem<'_>, s: f64, step: f64, f: Failure) -> Error {
    Error::NoEquilibrium {
        fraction: s,
        step,
        reason: f.reason,
        worst: f
            .last
            .as_ref()
            .map_or_else(|| "not evaluated".to_owned(), |e| problem.worst(e)),
        history: f.history,
    }
}

#[cfg(test)]
#[path = "statics_tests.rs"]
mod tests;
