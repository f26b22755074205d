//! Joint limits as one-sided impulsive stops.
//!
//! A joint that reaches the end of its travel is a collision in joint space, not a penalty
//! spring: the simulation locates the instant the coordinate reaches its limit (a
//! safeguarded interpolating search on the integrator's step, to [`LIMIT_TIME_TOLERANCE`])
//! and applies the generalized impulse that reverses the joint's approach with the stop's
//! restitution e (Newton's law in joint space: q̇ⱼ⁺ = −e·q̇ⱼ⁻). A generalized impulse p along joint j changes the whole velocity by
//! Δv = M⁻¹·eⱼ·p (M the joint-space mass matrix, by the composite-rigid-body algorithm), so
//! p = −(1 + e)·q̇ⱼ⁻ / (M⁻¹)ⱼⱼ; for e ≤ 1 the kinetic energy does not rise (the impulse
//! acts along one constraint and removes (1 − e²)·½·(q̇ⱼ⁻)²/(M⁻¹)ⱼⱼ).
//!
//! A joint that strikes its stop slower than the rest speed
//! ([`crate::Simulation::set_limit_rest_speed`]) is stopped plastically and *rests* on the stop: its
//! velocity and acceleration are held at zero by a constraint force (λ with (M⁻¹·(τ − h +
//! eⱼ·λ))ⱼ = 0) for as long as that force pushes away from the stop, checked at every
//! integrator step; a joint bouncing on a stop under a steady load would otherwise bounce
//! without end in finite time. Stops struck together, and the joints resting on their stops,
//! are solved simultaneously (one small linear system over those joints, with any joint whose
//! impulse would pull dropped from it).
//!
//! **Must not know** about collision detection, worlds or scenes.

use faer::Mat;
use faer::Side;
use faer::linalg::solvers::{Llt, Solve};

use crate::dynamics::{Workspace, mass_matrix};
use crate::error::MultibodyError;
use crate::model::{JointType, Model};

/// Length of the interval (s) to which the instant a joint reaches its limit is located.
/// Default `1e-12`: a joint turning at 10 rad/s is then within 1e-11 rad of its stop.
pub const LIMIT_TIME_TOLERANCE: f64 = 1e-12;

/// Most trial integrations spent locating one stop (the interval is one integrator step).
/// Default `80`: bisection alone reaches [`LIMIT_TIME_TOLERANCE`] from a step of 1e-12·2⁸⁰ s.
pub const MAX_LIMIT_BISECTIONS: usize = 80;

/// A try of the search for a stop ([`crate::Simulation`]'s strike location) aims at the
/// interpolated instant unless the last two tries did not shrink the bracket to this
/// fraction of its width (dimensionless); it is then the bracket's midpoint, so the search
/// is never much slower than bisection. Default `0.5`.
const AIM_SHRINK: f64 = 0.5;

/// Points at which the interpolated margin of a struck joint is sampled for its first
/// sign change on the step (the root of a cubic: at most two turns). Default `16`.
const STOP_SCAN_POINTS: usize = 16;

/// Default rest speed (rad/s or m/s, per joint): a stop struck slower is plastic and the
/// joint rests on it. Default `1e-4`.
pub const DEFAULT_LIMIT_REST_SPEED: f64 = 1e-4;

/// Most stops resolved at one instant ([`STALL_WINDOW`]) before the simulation gives up
/// with [`MultibodyError::LimitStall`] (stops struck together that keep driving each other,
/// or bouncing without end with a rest speed of 0).
/// Default `1000`.
pub const MAX_STOPS_PER_INSTANT: usize = 1000;

/// Stops resolved within this time (s) of the first of a run count as one instant for
/// [`MAX_STOPS_PER_INSTANT`]. Default `1e-9`.
pub const STALL_WINDOW: f64 = 1e-9;

/// The travel of a revolute (rad) or prismatic (m) joint, `lower ≤ q ≤ upper`, with stops of
/// restitution e at both ends. Either bound may be infinite (a one-sided stop).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct JointLimit {
    /// Lower bound of q (rad or m), possibly −∞.
    pub lower: f64,
    /// Upper bound of q (rad or m), possibly +∞.
    pub upper: f64,
    /// Coefficient of restitution of the stops, in [0, 1].
    pub restitution: f64,
}

impl JointLimit {
    /// Stops at `lower` and `upper` with restitution `restitution`.
    #[must_use]
    pub fn new(lower: f64, upper: f64, restitution: f64) -> Self {
        JointLimit {
            lower,
            upper,
            restitution,
        }
    }

    /// Checks the limit of joint `joint` of type `joint_type`.
    pub(crate) fn validate(
        &self,
        joint: &str,
        joint_type: &JointType,
    ) -> Result<(), MultibodyError> {
        let bad = |reason: String| {
            Err(MultibodyError::InvalidJoint {
                joint: joint.to_owned(),
                reason,
            })
        };
        if matches!(joint_type, JointType::Fixed) {
            return bad("a fixed joint cannot have limits".to_owned());
        }
        if self.lower.is_nan() || self.upper.is_nan() {
            return bad(format!(
                "limits [{}, {}] are not numbers",
                self.lower, self.upper
            ));
        }
        if self.lower >= self.upper
            || self.lower == f64::INFINITY
            || self.upper == f64::NEG_INFINITY
        {
            return bad(format!(
                "lower limit {} must lie below upper limit {}",
                self.lower, self.upper
            ));
        }
        if !(0.0..=1.0).contains(&self.restitution) {
            return bad(format!(
                "limit restitution {} must lie in [0, 1]",
                self.restitution
            ));
        }
        Ok(())
    }

    /// How far `q` lies inside the travel: its distance to the nearer stop, negative beyond
    /// one (exactly when [`JointLimit::beyond`] finds a stop, for finite `q`).
    pub(crate) fn margin(&self, q: f64) -> f64 {
        (q - self.lower).min(self.upper - q)
    }

    /// The stop `q` lies beyond, if any: `Some(1.0)` below the lower limit (its impulse
    /// pushes q up), `Some(-1.0)` above the upper one.
    pub(crate) fn beyond(&self, q: f64) -> Option<f64> {
        if q < self.lower {
            Some(1.0)
        } else if q > self.upper {
            Some(-1.0)
        } else {
            None
        }
    }
}

/// A joint pressed against one of its stops: its velocity index and the direction s (+1 at
/// a lower stop, −1 at an upper one) in which the stop may push it.
#[derive(Copy, Clone, Debug, PartialEq)]
pub(crate) struct Stop {
    /// Joint coordinate index (`0..joint_count`).
    pub joint: usize,
    /// +1 at the lower stop, −1 at the upper one.
    pub side: f64,
}

/// Joints beyond a limit at configuration `q`: (joint, side).
pub(crate) fn beyond_limits(model: &Model, q: &[f64]) -> Vec<Stop> {
    let qo = model.nq() - model.joint_count();
    (0..model.joint_count())
        .filter_map(|j| {
            let side = model.limit(j)?.beyond(q[qo + j])?;
            Some(Stop { joint: j, side })
        })
        .collect()
}

/// The joint-space mass matrix at a configuration, factorised, for M⁻¹ applied to unit
/// generalized impulses along joints.
pub(crate) struct InverseMass {
    llt: Llt<f64>,
    nv: usize,
    vo: usize,
}

impl InverseMass {
    /// Factorises M(q) (composite-rigid-body algorithm).
    pub(crate) fn new(
        model: &Model,
        ws: &mut Workspace,
        q: &[f64],
    ) -> Result<Self, MultibodyError> {
        let nv = model.nv();
        let mut m = Mat::<f64>::zeros(nv, nv);
        mass_matrix(model, ws, q, &mut m)?;
        let llt = m
            .llt(Side::Lower)
            .map_err(|_| MultibodyError::InvalidArgument {
                what: "mass matrix",
                reason: "not positive definite at this configuration".to_owned(),
            })?;
        Ok(InverseMass {
            llt,
            nv,
            vo: model.base_dofs(),
        })
    }

    /// M⁻¹·E for E the unit vectors of the given joints (nv × joints).
    fn columns(&self, joints: &[usize]) -> Mat<f64> {
        let e = Mat::<f64>::from_fn(self.nv, joints.len(), |r, c| {
            f64::from(u8::from(r == self.vo + joints[c]))
        });
        self.llt.solve(&e)
    }

    /// Generalized impulses along `joints` such that the joints' entries of `x + M⁻¹·E·p`
    /// equal `target`, added to `x` (a velocity, or an acceleration for constraint forces);
    /// returns p.
    pub(crate) fn constrain(&self, x: &mut [f64], joints: &[usize], target: &[f64]) -> Vec<f64> {
        if joints.is_empty() {
            return Vec::new();
        }
        let cols = self.columns(joints);
        let k = joints.len();
        // A = (M⁻¹)_SS, symmetric positive definite (a principal block of M⁻¹).
        let a = Mat::<f64>::from_fn(k, k, |r, c| cols[(self.vo + joints[r], c)]);
        let b = Mat::<f64>::from_fn(k, 1, |r, _| target[r] - x[self.vo + joints[r]]);
        let p = match a.llt(Side::Lower) {
            Ok(llt) => llt.solve(&b),
            // Two joints whose columns of M⁻¹ coincide cannot be told apart; none here (M⁻¹
            // is positive definite, so is every principal block).
            Err(_) => return vec![0.0; k],
        };
        for (i, xi) in x.iter_mut().enumerate() {
            *xi += (0..k).map(|c| cols[(i, c)] * p[(c, 0)]).sum::<f64>();
        }
        (0..k).map(|r| p[(r, 0)]).collect()
    }

    /// [`Self::constrain`] for stops, which may only push: a stop whose impulse comes out
    /// pulling (s·p < 0) is dropped and the rest solved again. Returns the stops kept.
    pub(crate) fn push(&self, x: &mut [f64], stops: &[(Stop, f64)]) -> Vec<Stop> {
        let mut active: Vec<(Stop, f64)> = stops.to_vec();
        loop {
            let joints: Vec<usize> = active.iter().map(|(s, _)| s.joint).collect();
            let target: Vec<f64> = active.iter().map(|&(_, t)| t).collect();
            let mut trial = x.to_vec();
            let p = self.constrain(&mut trial, &joints, &target);
            let worst = active
                .iter()
                .zip(&p)
                .enumerate()
                .map(|(i, ((s, _), &p))| (i, s.side * p))
                .min_by(|a, b| a.1.total_cmp(&b.1));
            match worst {
                Some((i, push)) if push < 0.0 => {
                    active.remove(i);
                }
                _ => {
                    x.copy_from_slice(&trial);
                    return active.into_iter().map(|(s, _)| s).collect();
                }
            }
        }
    }
}

/// What the stops of a [`crate::Simulation`] have done.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub struct LimitStats {
    /// Stops struck (each located in time and resolved by an impulse).
    pub strikes: u64,
    /// Stops struck slower than the rest speed, where the joint came to rest.
    pub rests: u64,
    /// Joints lifted off a stop they rested on (the constraint force would have pulled).
    pub releases: u64,
    /// Trial integrations spent locating stops in time (interpolated tries and bisections).
    pub locating_steps: u64,
    /// Steps taken without integrating because every joint rested on a stop (the state is
    /// then a fixed point of the motion).
    pub resting_steps: u64,
}

impl crate::Simulation {
    /// Stops struck slower than `speed` (rad/s or m/s) are plastic and the joint rests on
    /// them (module documentation of [`crate::limit`]). Default
    /// [`DEFAULT_LIMIT_REST_SPEED`].
    ///
    /// # Errors
    /// [`MultibodyError::InvalidArgument`] unless `speed` is finite and ≥ 0.
    pub fn set_limit_rest_speed(&mut self, speed: f64) -> Result<(), MultibodyError> {
        if !(speed.is_finite() && speed >= 0.0) {
            return Err(MultibodyError::InvalidArgument {
                what: "limit rest speed",
                reason: format!("{speed} must be finite and >= 0"),
            });
        }
        self.rest_speed = speed;
        Ok(())
    }

    /// What the joint stops have done so far.
    #[must_use]
    pub fn limit_stats(&self) -> LimitStats {
        self.limit_stats
    }

    /// Whether joint `j` rests on one of its stops.
    #[must_use]
    pub fn is_resting_on_stop(&self, j: usize) -> bool {
        self.resting.iter().any(|s| s.joint == j)
    }

    /// An error naming the first joint whose coordinate lies outside its limits.
    pub(crate) fn check_limits(&self) -> Result<(), MultibodyError> {
        let qo = self.model.nq() - self.model.joint_count();
        match beyond_limits(&self.model, &self.q).first() {
            None => Ok(()),
            Some(s) => {
                let l = self
                    .model
                    .limit(s.joint)
                    .expect("only joints with limits are beyond");
                Err(MultibodyError::InvalidJoint {
                    joint: self.model.joint_names()[s.joint].clone(),
                    reason: format!(
                        "q = {} lies outside its limits [{}, {}]",
                        self.q[qo + s.joint],
                        l.lower,
                        l.upper
                    ),
                })
            }
        }
    }

    /// Integrates from `t0` to `t1` with the current held forces and resting joints.
    fn integrate(&mut self, t0: f64, t1: f64) -> Result<(), MultibodyError> {
        let mut rhs = crate::control::Rhs {
            model: &self.model,
            ws: &mut self.ws,
            held: &self.held,
            tau: &mut self.tau,
            resting: &self.resting,
            track: self.travel.as_deref_mut(),
        };
        self.stepper.advance(
            &self.integrator,
            &self.model,
            &mut rhs,
            t0,
            t1,
            &mut self.q,
            &mut self.v,
        )
    }

    /// Where in `(lo, hi)` the joint most beyond its stop at `hi` first reaches it, by the
    /// cubic Hermite interpolant of its margin ([`JointLimit::margin`], rate ±q̇) between the
    /// two states `(t, q, v)`; `None` when no joint is beyond at `hi` or the interpolant does
    /// not cross zero. Cheap (no integration): a scan for the first sign change, then
    /// bisection of the cubic to rounding.
    fn first_stop_estimate(
        &self,
        (lo, q_lo, v_lo): (f64, &[f64], &[f64]),
        (hi, q_hi, v_hi): (f64, &[f64], &[f64]),
    ) -> Option<f64> {
        let (qo, vo) = (
            self.model.nq() - self.model.joint_count(),
            self.model.base_dofs(),
        );
        let (j, limit) = (0..self.model.joint_count())
            .filter(|&j| !self.resting.iter().any(|r| r.joint == j))
            .filter_map(|j| Some((j, *self.model.limit(j)?)))
            .min_by(|a, b| {
                a.1.margin(q_hi[qo + a.0])
                    .total_cmp(&b.1.margin(q_hi[qo + b.0]))
            })?;
        let lower = (q_hi[qo + j] - limit.lower) <= (limit.upper - q_hi[qo + j]);
        let margin = |q: &[f64], v: &[f64]| {
            if lower {
                (q[qo + j] - limit.lower, v[vo + j])
            } else {
                (limit.upper - q[qo + j], -v[vo + j])
            }
        };
        let (m0, d0) = margin(q_lo, v_lo);
        let (m1, d1) = margin(q_hi, v_hi);
        let w = hi - lo;
        if !(m0 >= 0.0 && m1 < 0.0 && w > 0.0) {
            return None;
        }
        // p(s) on s ∈ [0, 1]: the Hermite basis with the rates scaled by the width.
        let p = |s: f64| {
            let (s2, s3) = (s * s, s * s * s);
            (2.0 * s3 - 3.0 * s2 + 1.0) * m0
                + (s3 - 2.0 * s2 + s) * w * d0
                + (-2.0 * s3 + 3.0 * s2) * m1
                + (s3 - s2) * w * d1
        };
        let mut a = 0.0;
        let mut b = (1..=STOP_SCAN_POINTS)
            .map(|k| k as f64 / STOP_SCAN_POINTS as f64)
            .find(|&s| {
                let inside = p(s) >= 0.0;
                if inside {
                    a = s;
                }
                !inside
            })?;
        while b - a > f64::EPSILON {
            let mid = 0.5 * (a + b);
            if mid <= a || mid >= b {
                break;
            }
            if p(mid) >= 0.0 {
                a = mid;
            } else {
                b = mid;
            }
        }
        let t = lo + 0.5 * (a + b) * w;
        t.is_finite().then_some(t)
    }

    /// Joints beyond a limit that do not rest on a stop.
    fn struck(&self) -> Vec<Stop> {
        beyond_limits(&self.model, &self.q)
            .into_iter()
            .filter(|s| !self.resting.iter().any(|r| r.joint == s.joint))
            .collect()
    }

    /// One integrator step toward `next` (not past it). A step that carries a joint beyond a
    /// limit is cut to the instant it reaches it (located to [`LIMIT_TIME_TOLERANCE`] by a
    /// safeguarded interpolating search), where the stop is resolved.
    pub(crate) fn step_with_stops(&mut self, next: f64) -> Result<(), MultibodyError> {
        self.release_resting()?;
        let t0 = self.t;
        if self.all_resting() {
            // Every degree of freedom rests on a stop whose constraint force pushes: each
            // derivative evaluation would give zero (the constraint holds the acceleration at
            // zero, the velocity is zero), and the forces hold until `next` (controllers fire
            // only there; passive elements depend on the state alone), so the state is the
            // integrator's fixed point until then, exactly. A door shut on its stop costs
            // nothing while it stays shut.
            self.t = next;
            self.limit_stats.resting_steps += 1;
            return Ok(());
        }
        let to = next.min(t0 + self.stepper.h);
        let (q0, v0, h0) = (self.q.clone(), self.v.clone(), self.stepper.h);
        let travel0 = self.travel.clone();
        self.integrate(t0, to)?;
        let mut hit = self.struck();
        if hit.is_empty() {
            self.t = to;
            self.hold_resting();
            return Ok(());
        }
        // Locate the instant the first joint reaches its stop: a bracket [lo, hi], no joint
        // beyond a stop at lo, one at hi. Each try aims at the first root of the cubic
        // Hermite interpolant of the struck joint's margin (values and rates at both ends:
        // the integrator's own states, so the aim is off by O(width⁴)), a quarter of the
        // tolerance past it on the side the last try did not move, so that the bracket
        // closes from both sides; the midpoint when two tries did not halve the bracket.
        // A joint's approach to its stop takes a few tries where bisection took
        // log₂(h / LIMIT_TIME_TOLERANCE) ≈ 30 (a door bouncing to rest under parts:
        // 251 168 bisections for 9 710 stops in 6 s).
        let (mut lo, mut hi) = (t0, to);
        let (mut q_lo, mut v_lo) = (q0.clone(), v0.clone());
        let (mut q_hi, mut v_hi) = (self.q.clone(), self.v.clone());
        let mut travel_lo = travel0.clone();
        let mut widths = [f64::INFINITY; 2];
        let mut moved_lo: Option<bool> = None;
        let quarter_tol = 0.25 * LIMIT_TIME_TOLERANCE;
        let mut n = 0;
        while hi - lo > LIMIT_TIME_TOLERANCE && n < MAX_LIMIT_BISECTIONS {
            let width = hi - lo;
            let aim = (width <= AIM_SHRINK * widths[1])
                .then(|| self.first_stop_estimate((lo, &q_lo, &v_lo), (hi, &q_hi, &v_hi)))
                .flatten();
            let t = match (aim, moved_lo) {
                (None, _) => 0.5 * (lo + hi),
                (Some(t), Some(true)) => t + quarter_tol,
                (Some(t), Some(false)) => t - quarter_tol,
                (Some(t), None) => t,
            }
            .clamp(lo + quarter_tol, hi - quarter_tol);
            if t <= lo || t >= hi {
                break;
            }
            widths = [width, widths[0]];
            n += 1;
            self.q.copy_from_slice(&q0);
            self.v.copy_from_slice(&v0);
            self.stepper.h = h0;
            self.travel.clone_from(&travel0);
            self.integrate(t0, t)?;
            let at = self.struck();
            moved_lo = Some(at.is_empty());
            if at.is_empty() {
                lo = t;
                q_lo.copy_from_slice(&self.q);
                v_lo.copy_from_slice(&self.v);
                travel_lo.clone_from(&self.travel);
            } else {
                hi = t;
                q_hi.copy_from_slice(&self.q);
                v_hi.copy_from_slice(&self.v);
                hit = at;
            }
        }
        self.limit_stats.locating_steps += n as u64;
        // The recorded travel is that of the motion taken, t0 to the strike: the trials
        // past it (states beyond the stop, and each trial's states again: 1 000 samples a
        // step for a door struck by a falling part) are dropped.
        self.travel = travel_lo;
        self.q = q_lo;
        self.v = v_lo;
        self.stepper.h = h0;
        self.t = lo;
        self.hold_resting();
        self.resolve_stops(&hit)
    }

    /// Whether every degree of freedom is a joint resting on a stop (no free base, one resting
    /// stop per joint velocity).
    pub(crate) fn all_resting(&self) -> bool {
        let nv = self.model.nv();
        self.model.base_dofs() == 0
            && nv > 0
            && self.resting.len() == nv
            && (0..nv).all(|j| self.resting.iter().any(|s| s.joint == j))
            && self.v.iter().all(|&v| v == 0.0)
    }

    /// Keeps resting joints exactly on their stops (the constraint holds their acceleration
    /// at zero; this removes the rounding).
    fn hold_resting(&mut self) {
        let (qo, vo) = (
            self.model.nq() - self.model.joint_count(),
            self.model.base_dofs(),
        );
        for s in &self.resting {
            if let Some(l) = self.model.limit(s.joint) {
                self.q[qo + s.joint] = if s.side > 0.0 { l.lower } else { l.upper };
                self.v[vo + s.joint] = 0.0;
            }
        }
    }

    /// Lifts off their stops the resting joints whose constraint force would pull.
    fn release_resting(&mut self) -> Result<(), MultibodyError> {
        if self.resting.is_empty() {
            return Ok(());
        }
        let mut free = vec![0.0; self.model.nv()];
        let mut rhs = crate::control::Rhs {
            model: &self.model,
            ws: &mut self.ws,
            held: &self.held,
            tau: &mut self.tau,
            resting: &[],
            track: None,
        };
        crate::integrate::Accel::accel(&mut rhs, self.t, &self.q, &self.v, &mut free)?;
        let minv = InverseMass::new(&self.model, &mut self.ws, &self.q)?;
        let stops: Vec<(Stop, f64)> = self.resting.iter().map(|&s| (s, 0.0)).collect();
        let kept = minv.push(&mut free, &stops);
        let before = self.resting.len();
        self.resting.retain(|s| kept.contains(s));
        self.limit_stats.releases += (before - self.resting.len()) as u64;
        Ok(())
    }

    /// Resolves the stops struck at the current instant (module documentation).
    fn resolve_stops(&mut self, hit: &[Stop]) -> Result<(), MultibodyError> {
        let vo = self.model.base_dofs();
        let minv = InverseMass::new(&self.model, &mut self.ws, &self.q)?;
        let mut stops: Vec<(Stop, f64)> = Vec::new();
        let mut to_rest = Vec::new();
        for &s in hit {
            let approach = -s.side * self.v[vo + s.joint];
            self.limit_stats.strikes += 1;
            let e = self.model.limit(s.joint).map_or(0.0, |l| l.restitution);
            // Slower than the rest speed, or not approaching at all (a joint at rest on its
            // stop whose load drives it in: it crossed within the located instant): it rests.
            if approach < self.rest_speed {
                stops.push((s, 0.0));
                to_rest.push(s);
            } else {
                // Newton's law in joint space: q̇ⱼ⁺ = −e·q̇ⱼ⁻.
                stops.push((s, s.side * e * approach));
            }
        }
        // Joints already resting on stops stay at rest through the impulse (they may only
        // be pushed).
        stops.extend(self.resting.iter().map(|&s| (s, 0.0)));
        let mut kept = minv.push(&mut self.v, &stops);
        // A struck stop dropped because, together with the resting joints, its impulse
        // would pull: it alone always pushes (p = s·(1 + e)·approach / (M⁻¹)ⱼⱼ), and the
        // resting joints are let go (the next step checks whether they rest again).
        let dropped: Vec<(Stop, f64)> = stops[..hit.len()]
            .iter()
            .filter(|(s, _)| !kept.contains(s))
            .copied()
            .collect();
        if !dropped.is_empty() {
            for stop in dropped {
                minv.push(&mut self.v, &[stop]);
            }
            kept.retain(|s| hit.contains(s));
        }
        let before = self.resting.len();
        self.resting.retain(|s| kept.contains(s));
        self.limit_stats.releases += (before - self.resting.len()) as u64;
        for s in to_rest {
            if kept.contains(&s) && !self.resting.contains(&s) {
                self.resting.push(s);
                self.limit_stats.rests += 1;
            }
        }
        self.hold_resting();
        // Stops struck together that keep driving each other would stall the clock.
        if self.t - self.instant.0 <= STALL_WINDOW {
            self.instant.1 += 1;
        } else {
            self.instant = (self.t, 1);
        }
        if self.instant.1 > MAX_STOPS_PER_INSTANT {
            let joint = hit.first().map_or(0, |s| s.joint);
            return Err(MultibodyError::LimitStall {
                joint: self.model.joint_names()[joint].clone(),
                time: self.t,
                count: self.instant.1,
            });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests;
