//! A slow, simple reference solver (digest §16), the oracle for [`crate::resolve`].
//!
//! It shares none of `resolve`'s machinery: the only parameter is p_z (Theorem 8), the
//! integrator is classical fixed-step RK4, every event (u_z = 0, W_z = W_f, sticking, ...) is
//! located by plain bisection on the step, stable sticking is decided by ‖M⁻¹s‖ ≤ μ (the
//! equivalent form of Theorem 9, no K⁻¹) with `dp_t/dp_z = −M⁻¹s`, and the diverging ray by a
//! fine scan of X(θ) for sign changes with D(θ) > 0 (no quartic). After sticking it keeps
//! integrating numerically (no closed forms). Accuracy: about 1e-9 relative for the default
//! step count; cost: thousands of steps per collision.

use crate::integrate::Restitution;
use crate::rays::{cross_term, dot_term, sliding_vector};
use glam::{DMat3, DVec3};

/// Steps per |u_z0|/K_33 of normal impulse used by [`reference_resolve`]'s callers in tests
/// (while sliding, steps are also limited to move u_t by 5 % of |u_t|); dimensionless, default
/// `4000`.
pub const DEFAULT_REFERENCE_STEPS: usize = 4000;

/// Cap on the reference solver's steps, default `10_000_000`.
pub const MAX_REFERENCE_STEPS: usize = 10_000_000;

/// Grid size of the scan for the diverging ray, default `20_000`.
pub const RAY_SCAN_POINTS: usize = 20_000;

/// The reference declares sticking when |u_t| falls below this fraction of |u₀|; default
/// `1e-10`.
pub const REFERENCE_STICK_TOL_REL: f64 = 1e-10;

/// After a step across the tangential origin is bisected back, the path counts as reaching the
/// origin (not passing beside it) within this fraction of |u₀|; default `1e-8`.
pub const REFERENCE_CROSSING_TOL_REL: f64 = 1e-8;

/// While sliding, a step may move u_t by at most this fraction of |u_t| (resolves the fast
/// turning near the origin); default `0.05`.
pub const REFERENCE_MAX_TURN: f64 = 0.05;

/// Bisection steps for events, default `200`.
pub const REFERENCE_BISECTIONS: usize = 200;

/// The reference solution.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReferenceResult {
    /// p (collision frame).
    pub impulse: DVec3,
    /// u_f (collision frame).
    pub velocity: DVec3,
    /// W_z at the last maximum compression.
    pub compression_work: f64,
    /// W_z at the end.
    pub normal_work: f64,
    /// p_z where sliding stopped, if it did.
    pub sticking_impulse: Option<f64>,
    /// The diverging ray taken after unstable sticking.
    pub ray: Option<f64>,
    /// Whether the step cap was hit (the result is then incomplete).
    pub truncated: bool,
}

type S = [f64; 7]; // u, W_z, p

#[derive(Clone, Copy)]
enum M {
    Slide,
    Fixed(DVec3),
}

fn rhs(k: &DMat3, mu: f64, mode: M, y: &S) -> Option<S> {
    let q = match mode {
        M::Fixed(q) => q,
        M::Slide => {
            let r = (y[0] * y[0] + y[1] * y[1]).sqrt();
            if r.is_nan() || r <= 0.0 {
                return None;
            }
            DVec3::new(-mu * y[0] / r, -mu * y[1] / r, 1.0)
        }
    };
    let du = *k * q;
    Some([du.x, du.y, du.z, y[2], q.x, q.y, q.z])
}

fn rk4(k: &DMat3, mu: f64, mode: M, y: &S, h: f64) -> Option<S> {
    let add = |a: &S, b: &S, c: f64| {
        let mut o = *a;
        for (oi, bi) in o.iter_mut().zip(b) {
            *oi += c * bi;
        }
        o
    };
    let k1 = rhs(k, mu, mode, y)?;
    let k2 = rhs(k, mu, mode, &add(y, &k1, 0.5 * h))?;
    let k3 = rhs(k, mu, mode, &add(y, &k2, 0.5 * h))?;
    let k4 = rhs(k, mu, mode, &add(y, &k3, h))?;
    let mut o = *y;
    for i in 0..7 {
        o[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
    }
    Some(o)
}

/// Bisection on the step size: the largest h' ∈ [0, h] for which `before(step(h'))` holds,
/// given that it fails at h. Returns (state at h', state just after).
fn bisect(k: &DMat3, mu: f64, mode: M, y: &S, h: f64, before: impl Fn(&S) -> bool) -> (S, S, f64) {
    let (mut lo, mut hi) = (0.0f64, h);
    let mut y_lo = *y;
    let mut y_hi = rk4(k, mu, mode, y, h).unwrap_or(*y);
    for _ in 0..REFERENCE_BISECTIONS {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        match rk4(k, mu, mode, y, mid) {
            Some(ym) if before(&ym) => {
                lo = mid;
                y_lo = ym;
            }
            Some(ym) => {
                hi = mid;
                y_hi = ym;
            }
            None => hi = mid,
        }
    }
    (y_lo, y_hi, lo)
}

/// The diverging ray by scanning X(θ) for down-crossings (X′ < 0 at a diverging ray) with
/// D(θ) > 0, refined by bisection; the one with the largest D.
fn scan_diverging_ray(k: &DMat3, mu: f64) -> Option<f64> {
    let tau = std::f64::consts::TAU;
    let th = |i: usize| -std::f64::consts::PI + tau * i as f64 / RAY_SCAN_POINTS as f64;
    let mut best: Option<(f64, f64)> = None;
    for i in 0..RAY_SCAN_POINTS {
        let (a, b) = (th(i), th(i + 1));
        let (xa, xb) = (cross_term(k, mu, a), cross_term(k, mu, b));
        if !(xa >= 0.0 && xb < 0.0) {
            continue;
        }
        let (mut lo, mut hi) = (a, b);
        for _ in 0..REFERENCE_BISECTIONS {
            let mid = 0.5 * (lo + hi);
            if cross_term(k, mu, mid) >= 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let t = 0.5 * (lo + hi);
        let d = dot_term(k, mu, t);
        if d > 0.0 && best.is_none_or(|(_, bd)| d > bd) {
            best = Some((t, d));
        }
    }
    best.map(|(t, _)| t)
}

/// Solves the collision (K, u₀, μ, e, law) with the simple p_z scheme; `steps` fixed RK4 steps
/// per |u_z0|/K_33 of normal impulse (see [`DEFAULT_REFERENCE_STEPS`]). Inputs are assumed
/// valid (K symmetric positive definite, u0.z < 0, μ ≥ 0, e ≥ 0).
pub fn reference_resolve(
    k: DMat3,
    u0: DVec3,
    mu: f64,
    e: f64,
    law: Restitution,
    steps: usize,
) -> ReferenceResult {
    let h = (-u0.z) / k.z_axis.z / steps.max(1) as f64;
    let vscale = u0.length();
    let stick_tol = REFERENCE_STICK_TOL_REL * vscale;
    // ‖M⁻¹s‖ ≤ μ (Theorem 9 via the Schur complement), and dp_t/dp_z = −M⁻¹s while stuck.
    let (a, b, f) = (k.x_axis.x, k.y_axis.y, k.y_axis.x);
    let (se, sd) = (k.z_axis.x, k.z_axis.y);
    let det = a * b - f * f;
    let minv_s = ((b * se - f * sd) / det, (a * sd - f * se) / det);
    let stable = (minv_s.0 * minv_s.0 + minv_s.1 * minv_s.1).sqrt() <= mu;

    let mut y: S = [u0.x, u0.y, u0.z, 0.0, 0.0, 0.0, 0.0];
    let mut mode = if mu == 0.0 {
        M::Fixed(DVec3::Z)
    } else {
        M::Slide
    };
    let mut out = ReferenceResult {
        impulse: DVec3::ZERO,
        velocity: u0,
        compression_work: 0.0,
        normal_work: 0.0,
        sticking_impulse: None,
        ray: None,
        truncated: false,
    };
    let stick = |y: &mut S, mode: &mut M, out: &mut ReferenceResult| {
        y[0] = 0.0;
        y[1] = 0.0;
        out.sticking_impulse = Some(y[6]);
        *mode = if stable {
            M::Fixed(DVec3::new(-minv_s.0, -minv_s.1, 1.0))
        } else {
            let beta = scan_diverging_ray(&k, mu).unwrap_or(0.0);
            out.ray = Some(beta);
            M::Fixed(sliding_vector(mu, beta))
        };
    };
    if mu > 0.0 && (y[0] * y[0] + y[1] * y[1]).sqrt() <= stick_tol {
        stick(&mut y, &mut mode, &mut out);
    }
    let mut compressing = true;
    let mut wf = f64::INFINITY;
    let mut wz_base = 0.0f64;
    let newton_target = -e * u0.z;
    let mut poisson_target = f64::INFINITY;
    let mut n = 0;
    loop {
        n += 1;
        if n > MAX_REFERENCE_STEPS {
            out.truncated = true;
            break;
        }
        let mut step_h = if !compressing && law == Restitution::Poisson {
            h.min(poisson_target - y[6])
        } else {
            h
        };
        if let M::Slide = mode {
            // Resolve the fast turning of the sliding direction near the origin: a step moves
            // u_t by at most 5 % of its length.
            let r = (y[0] * y[0] + y[1] * y[1]).sqrt();
            if r <= stick_tol {
                stick(&mut y, &mut mode, &mut out);
                continue;
            }
            let xi = DVec3::new(-mu * y[0] / r, -mu * y[1] / r, 1.0);
            let dut = (k * xi).truncate().length();
            if dut > 0.0 {
                step_h = step_h.min(REFERENCE_MAX_TURN * r / dut);
            }
        }
        let y1 = rk4(&k, mu, mode, &y, step_h);
        // Sticking: the tangential velocity crosses (or touches) the origin.
        if let M::Slide = mode {
            let crossed = match y1 {
                Some(y1) => y[0] * y1[0] + y[1] * y1[1] <= 0.0,
                None => true,
            };
            if crossed {
                let y0 = y;
                let (y_lo, _, _) = bisect(&k, mu, mode, &y, step_h, |s| {
                    y0[0] * s[0] + y0[1] * s[1] > 0.0
                });
                y = y_lo;
                if (y[0] * y[0] + y[1] * y[1]).sqrt() <= REFERENCE_CROSSING_TOL_REL * vscale {
                    stick(&mut y, &mut mode, &mut out);
                }
                continue;
            }
        }
        let Some(y1) = y1 else {
            out.truncated = true;
            break;
        };
        if compressing {
            if y1[2] >= 0.0 {
                let (mut ye, _, _) = bisect(&k, mu, mode, &y, step_h, |s| s[2] < 0.0);
                // One more bisection step lands within rounding of u_z = 0.
                ye[2] = 0.0;
                y = ye;
                compressing = false;
                // W_z counts from the last maximum compression from here on.
                let wc = wz_base + y[3];
                wz_base = wc;
                y[3] = 0.0;
                out.compression_work = wc;
                if e == 0.0 {
                    break;
                }
                wf = -e * e * wc;
                poisson_target = (1.0 + e) * y[6];
                continue;
            }
        } else {
            match law {
                Restitution::Stronge => {
                    if y1[3] >= wf {
                        let (ye, yh, _) = bisect(&k, mu, mode, &y, step_h, |s| s[3] < wf);
                        y = if (yh[3] - wf).abs() < (ye[3] - wf).abs() {
                            yh
                        } else {
                            ye
                        };
                        break;
                    }
                }
                Restitution::Newton => {
                    if y1[2] >= newton_target {
                        let (ye, _, _) = bisect(&k, mu, mode, &y, step_h, |s| s[2] < newton_target);
                        y = ye;
                        break;
                    }
                }
                Restitution::Poisson => {
                    if y1[6] >= poisson_target * (1.0 - f64::EPSILON) {
                        y = y1;
                        break;
                    }
                }
            }
            if y1[2] < 0.0 && law != Restitution::Poisson {
                // u_z fell back to 0: compression resumes.
                let (ye, _, _) = bisect(&k, mu, mode, &y, step_h, |s| s[2] >= 0.0);
                y = ye;
                compressing = true;
                continue;
            }
        }
        y = y1;
    }
    out.impulse = DVec3::new(y[4], y[5], y[6]);
    out.velocity = DVec3::new(y[0], y[1], y[2]);
    out.normal_work = wz_base + y[3];
    out
}
