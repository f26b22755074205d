//! Shared test kit of the motion types: an RK4 torque-free reference, random launches,
//! swept-box sampling.

use super::*;
use core::f64::consts::TAU;
use glam::{DQuat, DVec3};
use impulse_geom::Aabb;
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

/// Rotation (rad) the RK4 reference advances per step at the fastest possible spin
/// (ω_max): its local error is ~(step)⁵, so energy and |L| stay within
/// [`CONSERVATION_TOL`] over [`SPAN_ANGLE`].
pub(crate) const STEP_ANGLE: f64 = 2e-3;
/// Length of each reference trajectory, as the angle ω_max·T (rad): several turns and
/// several tumbling periods of the Euler equations.
pub(crate) const SPAN_ANGLE: f64 = 30.0;
/// Relative drift of rotational energy and of |L| allowed along an RK4 trajectory.
pub(crate) const CONSERVATION_TOL: f64 = 1e-9;
/// Slack when comparing a true displacement with its bound, relative to the size of the
/// quantities involved (r_max + |v|τ + |g|τ²); covers RK4 and rounding error (~1e-10).
pub(crate) const BOUND_SLACK_REL: f64 = 1e-8;
/// Relative slack of ‖ω(t)‖ ≤ (2.5) along RK4 trajectories (RK4 drift, ~1e-10).
pub(crate) const OMEGA_SLACK_REL: f64 = 1e-9;
/// Agreement of closed forms evaluated two ways (ratios, world vs body frame), relative.
pub(crate) const CLOSED_FORM_TOL: f64 = 1e-12;
/// Time samples per swept interval when checking swept boxes.
pub(crate) const PATH_SAMPLES: usize = 4000;
/// Full-turn swept boxes against the analytic box of the whole path (m, absolute; paths of
/// size ~5 m, padded by 1e-12 relative).
pub(crate) const FULL_PATH_TOL: f64 = 1e-10;
/// Displacement/bound ratios are reported only where the bound exceeds this fraction of the
/// body size (below it the ratio is dominated by rounding).
pub(crate) const RATIO_FLOOR_REL: f64 = 1e-3;
/// How much an endpoints-only box is grown before showing that it still misses the apex (m).
pub(crate) const ENDPOINT_BOX_MARGIN: f64 = 1e-9;
/// Gram–Schmidt output: deviation from orthonormality (a few ε).
pub(crate) const ORTHONORMAL_TOL: f64 = 4.0 * f64::EPSILON;

pub(crate) fn rng(seed: u64) -> Xoshiro256PlusPlus {
    Xoshiro256PlusPlus::seed_from_u64(seed)
}

pub(crate) fn unit_vector(rng: &mut Xoshiro256PlusPlus) -> DVec3 {
    let z: f64 = rng.random_range(-1.0..=1.0);
    let phi = rng.random_range(0.0..TAU);
    let r = (1.0 - z * z).max(0.0).sqrt();
    DVec3::new(r * phi.cos(), r * phi.sin(), z)
}

pub(crate) fn random_rotation(rng: &mut Xoshiro256PlusPlus) -> DQuat {
    DQuat::from_xyzw(
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
    )
    .normalize()
}

/// Rigid rotation integrated by classical RK4: Euler's equations in the principal body frame,
/// `I·ω̇ = (I·ω) × ω + qᵀ·τ` with a constant world torque τ (zero: torque-free), and
/// `q̇ = ½·q ⊗ (ω, 0)` (q maps body to world). The independent reference for every ω and
/// displacement bound.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Tumbler {
    pub(crate) inertia: DVec3,
    pub(crate) q: DQuat,
    pub(crate) w: DVec3,
    /// Constant external torque (world).
    pub(crate) torque: DVec3,
}

impl Tumbler {
    fn derivative(&self, q: DQuat, w: DVec3) -> (DQuat, DVec3) {
        let w_dot = ((self.inertia * w).cross(w) + q.inverse() * self.torque) / self.inertia;
        let q_dot = q * DQuat::from_xyzw(w.x, w.y, w.z, 0.0) * 0.5;
        (q_dot, w_dot)
    }

    pub(crate) fn step(&self, h: f64) -> Tumbler {
        let (q, w) = (self.q, self.w);
        let (k1q, k1w) = self.derivative(q, w);
        let (k2q, k2w) = self.derivative(q + k1q * (0.5 * h), w + k1w * (0.5 * h));
        let (k3q, k3w) = self.derivative(q + k2q * (0.5 * h), w + k2w * (0.5 * h));
        let (k4q, k4w) = self.derivative(q + k3q * h, w + k3w * h);
        Tumbler {
            torque: self.torque,
            inertia: self.inertia,
            q: (q + (k1q + k2q * 2.0 + k3q * 2.0 + k4q) * (h / 6.0)).normalize(),
            w: w + (k1w + k2w * 2.0 + k3w * 2.0 + k4w) * (h / 6.0),
        }
    }

    pub(crate) fn energy2(&self) -> f64 {
        self.inertia.dot(self.w * self.w)
    }

    pub(crate) fn momentum_world(&self) -> DVec3 {
        self.q * (self.inertia * self.w)
    }
}

/// A tumbling box: RK4 states on a uniform grid, plus exact ballistic COM motion.
pub(crate) struct Trajectory {
    pub(crate) half: DVec3,
    pub(crate) com0: DVec3,
    pub(crate) v0: DVec3,
    pub(crate) g: DVec3,
    pub(crate) h: f64,
    pub(crate) states: Vec<Tumbler>,
}

impl Trajectory {
    pub(crate) fn new(
        half: DVec3,
        start: Tumbler,
        (com0, v0, g): (DVec3, DVec3, DVec3),
        span: f64,
    ) -> Self {
        let w_bound = omega_max_energy(start.inertia, start.w)
            .unwrap()
            .max(1e-300);
        let steps = ((span * w_bound / STEP_ANGLE).ceil() as usize).max(1000);
        let h = span / steps as f64;
        let mut states = Vec::with_capacity(steps + 1);
        states.push(start);
        for k in 0..steps {
            states.push(states[k].step(h));
        }
        Self {
            half,
            com0,
            v0,
            g,
            h,
            states,
        }
    }

    /// Rotational state at any t in the span: a partial RK4 step from the grid point below.
    pub(crate) fn state_at(&self, t: f64) -> Tumbler {
        let k = ((t / self.h).floor() as usize).min(self.states.len() - 1);
        let rest = t - k as f64 * self.h;
        if rest > 0.0 {
            self.states[k].step(rest)
        } else {
            self.states[k]
        }
    }

    pub(crate) fn com_at(&self, t: f64) -> DVec3 {
        self.com0 + self.v0 * t + self.g * (0.5 * t * t)
    }

    pub(crate) fn vertices(&self, com: DVec3, q: DQuat) -> [DVec3; 8] {
        core::array::from_fn(|i| {
            let s = DVec3::new(
                if i & 1 == 0 { -1.0 } else { 1.0 },
                if i & 2 == 0 { -1.0 } else { 1.0 },
                if i & 4 == 0 { -1.0 } else { 1.0 },
            );
            com + q * (s * self.half)
        })
    }
}

/// Principal moments of a solid box of unit mass with these half extents (kg·m²).
pub(crate) fn box_inertia(half: DVec3) -> DVec3 {
    let s = half * half;
    DVec3::new(s.y + s.z, s.x + s.z, s.x + s.y) / 3.0
}

/// A random box with inertia ratio at most 100, biased toward elongated shapes.
pub(crate) fn random_box(rng: &mut Xoshiro256PlusPlus) -> DVec3 {
    loop {
        let half = DVec3::new(
            10f64.powf(rng.random_range(-1.0..0.15)),
            10f64.powf(rng.random_range(-1.0..0.15)),
            10f64.powf(rng.random_range(-1.0..0.15)),
        );
        let i = box_inertia(half);
        if i.max_element() / i.min_element() <= 100.0 {
            return half;
        }
    }
}

/// A random launch of a body with principal moments `inertia`: spin log-uniform in
/// [0.1, 10^max_log_spin] rad/s about a random axis from a random orientation, speed up to
/// `max_speed`, gravity on odd cases.
pub(crate) fn random_launch(
    rng: &mut Xoshiro256PlusPlus,
    case: usize,
    inertia: DVec3,
    max_log_spin: f64,
    max_speed: f64,
) -> (Tumbler, DVec3, DVec3) {
    let spin = 10f64.powf(rng.random_range(-1.0..max_log_spin));
    let w = unit_vector(rng) * spin;
    let g = if case % 2 == 0 {
        DVec3::ZERO
    } else {
        unit_vector(rng) * 9.81
    };
    let v0 = unit_vector(rng) * rng.random_range(0.0..max_speed);
    let q = random_rotation(rng);
    (
        Tumbler {
            inertia,
            q,
            w,
            torque: DVec3::ZERO,
        },
        v0,
        g,
    )
}

/// Samples `motion.com_at` densely over [0, dt] and checks the swept box contains every
/// sample, and that each face is within `sampling_slack` of the samples (tight: every
/// extremum is a real point of the path).
pub(crate) fn check_swept_box(motion: &Motion, dt: f64, sampling_slack: f64) -> Aabb {
    let b = motion.swept_com_aabb(dt);
    let samples = Aabb::from_points(
        (0..=PATH_SAMPLES).map(|k| motion.com_at(dt * k as f64 / PATH_SAMPLES as f64)),
    );
    assert!(
        b.min.cmple(samples.min).all() && samples.max.cmple(b.max).all(),
        "{motion:?} dt {dt}: box {b:?} misses samples {samples:?}"
    );
    let excess = (samples.min - b.min).max(b.max - samples.max);
    assert!(
        excess.max_element() <= sampling_slack,
        "{motion:?} dt {dt}: box {b:?} larger than path {samples:?}"
    );
    b
}

/// Largest gap between a sampled maximum and the true one for a path with acceleration
/// at most `acc` sampled every `dt / PATH_SAMPLES`, plus the box padding.
pub(crate) fn sampling_slack(acc: f64, dt: f64, scale: f64) -> f64 {
    let step = dt / PATH_SAMPLES as f64;
    0.5 * acc * step * step + 2.0 * SWEPT_BOX_ROUNDING_REL * scale
}
