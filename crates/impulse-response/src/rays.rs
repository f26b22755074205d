//! Rays of constant sliding direction (thesis §3.4.2) and the diverging ray along which sliding
//! resumes after unstable sticking (Theorem 16).
//!
//! With K's entries named as in (3.15), `K = [[a, f, e], [f, b, d], [e, d, c]]`, the tangential
//! velocity moves during sliding as `u_t′ = μ·M·(−cos θ, −sin θ) + s` (3.16), `M = [[a, f], [f, b]]`,
//! s = (e, d). A ray at angle θ keeps its direction: `X(θ) = û × u_t′ = 0` (Theorem 14); it
//! diverges (the velocity point moves away from the origin) iff `D(θ) = û · u_t′ > 0`.
//!
//! **Finding all rays.** X is a trigonometric polynomial of degree 2,
//! `X(θ) = −fμ·cos 2θ + ½(a − b)μ·sin 2θ + d·cos θ − e·sin θ`, with at most four zeros
//! (Corollary 2). The substitution t = tan(φ/2) turns it into a quartic but loses φ = π (t = ∞):
//! if X vanishes there, the quartic drops degree and that ray is missed (the digest's example
//! `K = [[2,0,−1],[0,3,0],[−1,0,4]]`, μ = 0.3 has its only diverging ray at exactly 180°). Here the
//! substitution is centred at θ₀ ∈ {0, π/2, π, 3π/2}, chosen to maximise |X(θ₀ + π)| — the
//! quartic's leading coefficient — so no ray sits at t = ∞. The quartic's real roots are
//! isolated between the real roots of its derivatives (recursively, exact sign changes on
//! monotone intervals, tangential double roots kept), then each is polished by Newton's method
//! on X(θ) itself.

use crate::tol;
use glam::{DMat3, DVec3};
use std::f64::consts::{FRAC_PI_2, PI};

/// A ray of constant sliding direction (Theorem 14).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    /// Its angle θ in (−π, π], from the collision frame's x axis.
    pub theta: f64,
    /// D(θ) = û·u_t′ (Theorem 14): > 0 diverging, otherwise converging.
    pub dot: f64,
    /// Whether the ray diverges (D(θ) > 0).
    pub diverging: bool,
    /// du_z/dp_z = k_z·ξ(θ) along the ray; > 0 on a diverging ray (Theorem 17).
    pub normal_slope: f64,
}

/// All rays of constant sliding direction of a (K, μ), at most four (Corollary 2).
#[derive(Debug, Clone, PartialEq)]
pub struct Rays {
    rays: Vec<Ray>,
    every_direction: bool,
}

impl Rays {
    /// The rays, sorted by angle.
    pub fn as_slice(&self) -> &[Ray] {
        &self.rays
    }

    /// True when X ≡ 0: f = d = e = 0 and a = b (isotropic M, no coupling), so every direction
    /// keeps itself; then every direction converges and sticking is stable. `as_slice` is empty.
    pub fn every_direction(&self) -> bool {
        self.every_direction
    }

    /// The diverging ray (D > 0) — exactly one if sticking is unstable (Theorem 16), none if it
    /// is stable (Theorem 15). Should rounding produce several, the one with the largest D.
    pub fn diverging(&self) -> Option<Ray> {
        self.rays
            .iter()
            .filter(|r| r.diverging)
            .copied()
            .max_by(|a, b| a.dot.total_cmp(&b.dot))
    }
}

/// The sliding vector ξ(θ) = (−μ cos θ, −μ sin θ, 1) (Definition 2): dp/dp_z while sliding
/// in direction θ (Lemma 2).
pub fn sliding_vector(mu: f64, theta: f64) -> DVec3 {
    let (s, c) = theta.sin_cos();
    DVec3::new(-mu * c, -mu * s, 1.0)
}

/// Named entries of K, (3.15) (c = K_33 is not needed here).
#[derive(Clone, Copy)]
struct Entries {
    a: f64,
    b: f64,
    d: f64,
    e: f64,
    f: f64,
}

impl Entries {
    fn of(k: &DMat3) -> Self {
        // glam is column-major: k.col(j)[i] = K_ij; K is symmetric.
        Self {
            a: k.x_axis.x,
            b: k.y_axis.y,
            d: k.z_axis.y,
            e: k.z_axis.x,
            f: k.y_axis.x,
        }
    }
}

/// X(θ) = (a−b)μ cos θ sin θ + fμ(sin²θ − cos²θ) + d cos θ − e sin θ (Theorem 14): zero on a ray.
pub fn cross_term(k: &DMat3, mu: f64, theta: f64) -> f64 {
    let n = Entries::of(k);
    let (s, c) = theta.sin_cos();
    (n.a - n.b) * mu * c * s + n.f * mu * (s * s - c * c) + n.d * c - n.e * s
}

/// D(θ) = −aμ cos²θ − bμ sin²θ − 2fμ cos θ sin θ + d sin θ + e cos θ (Theorem 14): the rate at
/// which the sliding speed grows along direction θ; a ray diverges iff D > 0.
pub fn dot_term(k: &DMat3, mu: f64, theta: f64) -> f64 {
    let n = Entries::of(k);
    let (s, c) = theta.sin_cos();
    -n.a * mu * c * c - n.b * mu * s * s - 2.0 * n.f * mu * c * s + n.d * s + n.e * c
}

/// du_z/dp_z = k_z·ξ(θ) = c − μ(e cos θ + d sin θ) while sliding in direction θ (Theorem 8).
pub fn normal_slope(k: &DMat3, mu: f64, theta: f64) -> f64 {
    k.row(2).dot(sliding_vector(mu, theta))
}

/// A scale of X(θ) and D(θ): μ(|a| + |b| + |f|) + |d| + |e| (the u_t′ ellipse's size).
pub fn ellipse_size(k: &DMat3, mu: f64) -> f64 {
    let n = Entries::of(k);
    mu * (n.a.abs() + n.b.abs() + n.f.abs()) + n.d.abs() + n.e.abs()
}

/// dX/dθ, the slope of Theorem 14's cross term.
pub fn cross_term_slope(k: &DMat3, mu: f64, theta: f64) -> f64 {
    let n = Entries::of(k);
    let (a2, b2, c1, e1) = (-n.f * mu, 0.5 * (n.a - n.b) * mu, n.d, -n.e);
    let (s, c) = theta.sin_cos();
    let (s2, c2) = (2.0 * s * c, c * c - s * s);
    -2.0 * a2 * s2 + 2.0 * b2 * c2 - c1 * s + e1 * c
}

/// The ray nearest to `theta` by Newton's method on X(θ), if it converges (|X| at rounding
/// level, within 0.2 rad of the start).
pub(crate) fn polish_ray(k: &DMat3, mu: f64, theta: f64) -> Option<f64> {
    let mut t = theta;
    let size = cross_term(k, mu, theta).abs()
        + mu * (k.x_axis.x.abs() + k.y_axis.y.abs() + k.y_axis.x.abs())
        + k.z_axis.x.abs()
        + k.z_axis.y.abs();
    for _ in 0..tol::RAY_POLISH_ITERATIONS {
        let x = cross_term(k, mu, t);
        if x.abs() <= tol::RAY_POLISH_STOP_REL * size {
            break;
        }
        let d = cross_term_slope(k, mu, t);
        if d == 0.0 || !d.is_finite() {
            return None;
        }
        t -= x / d;
    }
    let ok = cross_term(k, mu, t).abs() <= tol::RAY_ACCEPT_REL * size
        && angle_between(t, theta) < tol::RAY_NEAREST_MAX_ANGLE;
    ok.then_some(wrap(t))
}

/// All rays of constant sliding direction for collision matrix `k` (collision frame) and
/// friction `mu` (Theorem 14, Corollary 2), including a ray at exactly θ = π.
pub fn rays(k: &DMat3, mu: f64) -> Rays {
    let n = Entries::of(k);
    // X(θ) = A cos 2θ + B sin 2θ + C cos θ + E sin θ.
    let (a2, b2, c1, e1) = (-n.f * mu, 0.5 * (n.a - n.b) * mu, n.d, -n.e);
    let size = ellipse_size(k, mu);
    let coef = a2.abs() + b2.abs() + c1.abs() + e1.abs();
    if size == 0.0 || coef <= tol::RAY_DEGENERATE_REL * size {
        return Rays {
            rays: Vec::new(),
            every_direction: true,
        };
    }
    // Centre the half-angle substitution at θ₀ = jπ/2 maximising |X(θ₀ + π)| = |A' − C'|.
    let centres = [(1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0)]; // (cos θ₀, sin θ₀)
    let rotated = |(c0, s0): (f64, f64)| {
        // cos 2θ₀ = c0² − s0², sin 2θ₀ = 2 c0 s0 (exact for these θ₀).
        let (c2, s2) = (c0 * c0 - s0 * s0, 2.0 * c0 * s0);
        (
            a2 * c2 + b2 * s2,
            -a2 * s2 + b2 * c2,
            c1 * c0 + e1 * s0,
            -c1 * s0 + e1 * c0,
        )
    };
    let mut best = 0;
    let mut best_lead = -1.0;
    for (j, &cs) in centres.iter().enumerate() {
        let (ap, _, cp, _) = rotated(cs);
        let lead = (ap - cp).abs();
        if lead > best_lead {
            best_lead = lead;
            best = j;
        }
    }
    let (ap, bp, cp, ep) = rotated(centres[best]);
    let theta0 = best as f64 * FRAC_PI_2;
    // (1 + t²)²·X(θ₀ + 2 atan t), coefficients from t⁰ to t⁴ (Corollary 2).
    let quartic = [
        ap + cp,
        4.0 * bp + 2.0 * ep,
        -6.0 * ap,
        -4.0 * bp + 2.0 * ep,
        ap - cp,
    ];
    let mut thetas: Vec<f64> = real_roots(&quartic)
        .into_iter()
        .map(|t| polish(k, mu, wrap(theta0 + 2.0 * t.atan())))
        .collect();
    // Safety net: the point the substitution cannot see, θ₀ + π (not a root by the choice of
    // θ₀ unless X is tiny there too).
    let far = wrap(theta0 + PI);
    if cross_term(k, mu, far).abs() <= tol::RAY_RESIDUAL_REL * size {
        thetas.push(far);
    }
    thetas.sort_by(f64::total_cmp);
    let mut out: Vec<Ray> = Vec::with_capacity(4);
    for th in thetas {
        if cross_term(k, mu, th).abs() > tol::RAY_ACCEPT_REL * size {
            continue; // a spurious tangential root that polishing moved away from X = 0
        }
        let dup = out
            .iter()
            .any(|r| angle_between(r.theta, th) < tol::RAY_MERGE_ANGLE);
        if dup {
            continue;
        }
        let dot = dot_term(k, mu, th);
        out.push(Ray {
            theta: th,
            dot,
            diverging: dot > 0.0,
            normal_slope: normal_slope(k, mu, th),
        });
    }
    Rays {
        rays: out,
        every_direction: false,
    }
}

/// |θ₁ − θ₂| modulo 2π, in [0, π].
fn angle_between(t1: f64, t2: f64) -> f64 {
    wrap(t1 - t2).abs()
}

/// θ wrapped into (−π, π].
fn wrap(theta: f64) -> f64 {
    let mut t = theta % std::f64::consts::TAU;
    if t > PI {
        t -= std::f64::consts::TAU;
    } else if t <= -PI {
        t += std::f64::consts::TAU;
    }
    t
}

/// Newton's method on X(θ), keeping the best iterate (the quartic root may have lost accuracy
/// through t = tan(φ/2) for large |t|).
fn polish(k: &DMat3, mu: f64, theta: f64) -> f64 {
    let n = Entries::of(k);
    let (a2, b2, c1, e1) = (-n.f * mu, 0.5 * (n.a - n.b) * mu, n.d, -n.e);
    let x = |t: f64| {
        let (s, c) = t.sin_cos();
        let (s2, c2) = (2.0 * s * c, c * c - s * s);
        a2 * c2 + b2 * s2 + c1 * c + e1 * s
    };
    let dx = |t: f64| {
        let (s, c) = t.sin_cos();
        let (s2, c2) = (2.0 * s * c, c * c - s * s);
        -2.0 * a2 * s2 + 2.0 * b2 * c2 - c1 * s + e1 * c
    };
    let mut best = theta;
    let mut best_res = x(theta).abs();
    let mut t = theta;
    for _ in 0..tol::RAY_POLISH_ITERATIONS {
        let d = dx(t);
        if d == 0.0 || !d.is_finite() {
            break;
        }
        t -= x(t) / d;
        let r = x(t).abs();
        if r < best_res {
            best_res = r;
            best = t;
        } else {
            break;
        }
    }
    wrap(best)
}

/// p(x) for coefficients from x⁰ upwards (Horner).
fn poly_eval(c: &[f64], x: f64) -> f64 {
    c.iter().rev().fold(0.0, |acc, &ci| acc * x + ci)
}

/// A bound on Horner's rounding error at x: ~ 2n·ε·Σ|c_i||x|^i.
fn poly_rounding(c: &[f64], x: f64) -> f64 {
    let ax = x.abs();
    let mag = c.iter().rev().fold(0.0, |acc, &ci| acc * ax + ci.abs());
    // Higham's bound for Horner is γ_2n ≈ 2n·ε; a factor 4 of slack for the evaluation of x.
    8.0 * c.len() as f64 * f64::EPSILON * mag
}

/// All real roots of the polynomial with coefficients `c` (from x⁰ up; trailing zeros are
/// dropped), sorted. Roots are isolated on the intervals between consecutive real roots of the
/// derivative (where p is monotone) and found by bisection; a critical point where p vanishes
/// to rounding is a (tangential) root too.
pub(crate) fn real_roots(c: &[f64]) -> Vec<f64> {
    let mut deg = c.len();
    while deg > 0 && c[deg - 1] == 0.0 {
        deg -= 1;
    }
    let c = &c[..deg];
    if c.len() <= 1 {
        return Vec::new();
    }
    if c.len() == 2 {
        return vec![-c[0] / c[1]];
    }
    let lead = c[c.len() - 1];
    let deriv: Vec<f64> = c
        .iter()
        .enumerate()
        .skip(1)
        .map(|(i, &ci)| ci * i as f64)
        .collect();
    let crit = real_roots(&deriv);
    // Cauchy's bound: every root has |x| < 1 + max |c_i / c_n|.
    let bound = 1.0
        + c[..c.len() - 1]
            .iter()
            .fold(0.0f64, |m, &ci| m.max((ci / lead).abs()));
    let mut pts = vec![-bound];
    pts.extend(crit.iter().copied().filter(|x| x.abs() < bound));
    pts.push(bound);
    let mut roots: Vec<f64> = Vec::new();
    for w in pts.windows(2) {
        let (x0, x1) = (w[0], w[1]);
        let (f0, f1) = (poly_eval(c, x0), poly_eval(c, x1));
        if f0 == 0.0 {
            roots.push(x0);
        } else if f0.signum() != f1.signum() && f1 != 0.0 {
            roots.push(bisect(c, x0, x1, f0));
        }
    }
    if poly_eval(c, bound) == 0.0 {
        roots.push(bound);
    }
    // Tangential roots: p has an extremum at ~0.
    for &x in &crit {
        if poly_eval(c, x).abs() <= poly_rounding(c, x) {
            roots.push(x);
        }
    }
    roots.sort_by(f64::total_cmp);
    // Relative to the roots themselves, not to 1 + |x|: the same routine finds the crossings
    // of work and velocity along a ray in Δp_z, whose roots can be 1e-13 apart and both real
    // (a grazing contact); an absolute merge there dropped the positive root.
    roots.dedup_by(|a, b| (*a - *b).abs() <= tol::ROOT_MERGE_REL * a.abs().max(b.abs()));
    roots
}

/// The root of the polynomial on [lo, hi], where it is monotone, p(lo) = f_lo ≠ 0 and the sign
/// changes: Newton's method safeguarded by bisection (a Newton step leaving the bracket is
/// replaced by the midpoint), until p vanishes to rounding or the bracket cannot shrink.
fn bisect(c: &[f64], mut lo: f64, mut hi: f64, f_lo: f64) -> f64 {
    let s_lo = f_lo.signum();
    let mut x = 0.5 * (lo + hi);
    // 2100 halvings exhaust any f64 interval; Newton normally ends it in a handful.
    for _ in 0..2100 {
        // p(x) and p′(x) by Horner.
        let (mut f, mut df) = (0.0, 0.0);
        for &ci in c.iter().rev() {
            df = df * x + f;
            f = f * x + ci;
        }
        if f == 0.0 || f.abs() <= poly_rounding(c, x) {
            return x;
        }
        if f.signum() == s_lo {
            lo = x;
        } else {
            hi = x;
        }
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        let newton = x - f / df;
        x = if newton > lo && newton < hi {
            newton
        } else {
            mid
        };
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::CollisionMatrix;
    use rand::rngs::Xoshiro256PlusPlus;
    use rand::{RngExt, SeedableRng};

    fn sym(a: f64, b: f64, c: f64, f: f64, e: f64, d: f64) -> DMat3 {
        DMat3::from_cols(
            DVec3::new(a, f, e),
            DVec3::new(f, b, d),
            DVec3::new(e, d, c),
        )
    }

    /// The Fig. 3.3 matrix.
    pub(crate) fn fig33() -> DMat3 {
        sym(8.0, 3.0, 5.0, -2.0, 1.0, -1.0)
    }

    #[test]
    fn polynomial_roots() {
        // (x − 1)(x + 2)(x − 3)(x + 0.5) = x⁴ − 1.5x³ − 6x² + 3.5x + 3
        let r = real_roots(&[3.0, 3.5, -6.0, -1.5, 1.0]);
        let want = [-2.0, -0.5, 1.0, 3.0];
        assert_eq!(r.len(), 4, "{r:?}");
        for (a, b) in r.iter().zip(want) {
            assert!((a - b).abs() < 1e-12, "{r:?}");
        }
        // Double root (x − 1)²(x² + 1): tangential.
        let r = real_roots(&[1.0, -2.0, 2.0, -2.0, 1.0]);
        assert!(
            !r.is_empty() && r.iter().all(|x| (x - 1.0).abs() < 1e-7),
            "{r:?}"
        );
        // No real roots.
        assert!(real_roots(&[1.0, 0.0, 1.0]).is_empty());
        // Degree drop.
        assert_eq!(real_roots(&[2.0, -1.0, 0.0, 0.0, 0.0]), vec![2.0]);
    }

    /// Digest test 14 / Fig. 3.3: μ = 0.2 gives a converging ray at 147.00° and a diverging ray
    /// at −71.11° (thesis: 147° and −71°); sticking becomes stable at μ* = √37/20.
    #[test]
    fn figure_3_3_rays() {
        let k = fig33();
        let rs = rays(&k, 0.2);
        assert_eq!(rs.as_slice().len(), 2, "{rs:?}");
        let conv: Vec<_> = rs.as_slice().iter().filter(|r| !r.diverging).collect();
        let div = rs.diverging().unwrap();
        assert_eq!(conv.len(), 1);
        assert!(
            (conv[0].theta.to_degrees() - 147.001).abs() < 5e-3,
            "{rs:?}"
        );
        assert!((div.theta.to_degrees() + 71.113).abs() < 5e-3, "{rs:?}");
        assert!((conv[0].dot + 3.052).abs() < 5e-3 && (div.dot - 0.320).abs() < 5e-3);
        let cm = CollisionMatrix::new(k).unwrap();
        let mu_star = 37f64.sqrt() / 20.0;
        assert!(!cm.sticking_is_stable(0.2));
        assert!(!cm.sticking_is_stable(mu_star * (1.0 - 1e-9)));
        assert!(cm.sticking_is_stable(mu_star * (1.0 + 1e-9)));
        // On the diverging ray u_z grows (Theorem 17); X vanishes.
        assert!(div.normal_slope > 0.0);
        assert!(cross_term(&k, 0.2, div.theta).abs() < 1e-13);
    }

    /// Digest §10.2 edge case: the only diverging ray is at exactly θ = π, where the plain
    /// t = tan(θ/2) quartic has no root (it drops to the cubic 2.6t³ + 1.4t).
    #[test]
    fn ray_at_exactly_180_degrees() {
        let k = sym(2.0, 3.0, 4.0, 0.0, -1.0, 0.0);
        let mu = 0.3;
        assert!(!CollisionMatrix::new(k).unwrap().sticking_is_stable(mu));
        let rs = rays(&k, mu);
        let div = rs.diverging().unwrap();
        assert!((div.theta.abs() - PI).abs() < 1e-12, "{rs:?}");
        assert_eq!(rs.as_slice().iter().filter(|r| r.diverging).count(), 1);
        // The plain substitution misses it: its leading coefficient −(fμ + d) vanishes.
        let n = Entries::of(&k);
        assert_eq!(-(n.f * mu + n.d), 0.0);
        // The other ray, θ = 0 (t = 0), converges.
        assert!(
            rs.as_slice()
                .iter()
                .any(|r| !r.diverging && r.theta.abs() < 1e-12)
        );
    }

    /// Digest test 15: on random SPD K and μ, at most four rays; exactly one diverging iff
    /// sticking is unstable (Theorem 16), none iff stable (Theorem 15); on the diverging ray
    /// du_z/dp_z > 0 (Theorem 17). Cross-checked against a fine scan of X(θ) for sign changes.
    #[test]
    fn ray_counts_match_theorems_15_16_17() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(51);
        let (mut n_stable, mut n_unstable, mut n4) = (0, 0, 0);
        for case in 0..4000 {
            let mut k = crate::matrix::tests::random_spd(&mut rng);
            if case % 10 == 0 {
                // Force fμ + d = 0 sometimes: a ray candidate at exactly θ = π.
                let mu = 0.7;
                k.z_axis.y = -k.y_axis.x * mu;
                k.y_axis.z = k.z_axis.y;
                if CollisionMatrix::new(k).is_err() || k.determinant() <= 0.0 {
                    continue;
                }
            }
            let mu = if case % 10 == 0 {
                0.7
            } else {
                rng.random_range(0.01..2.0)
            };
            let cm = CollisionMatrix::new(k).unwrap();
            let rs = rays(&k, mu);
            assert!(!rs.every_direction());
            let list = rs.as_slice();
            assert!(list.len() <= 4);
            if list.len() == 4 {
                n4 += 1;
            }
            // Away from the stability boundary only.
            let c = cm.inverse().z_axis;
            let margin = (c.x * c.x + c.y * c.y).sqrt() - mu * c.z;
            if margin.abs() < 1e-6 * c.z {
                continue;
            }
            let n_div = list.iter().filter(|r| r.diverging).count();
            if cm.sticking_is_stable(mu) {
                n_stable += 1;
                assert_eq!(n_div, 0, "{k} {mu} {list:?}");
            } else {
                n_unstable += 1;
                assert_eq!(n_div, 1, "{k} {mu} {list:?}");
                assert!(rs.diverging().unwrap().normal_slope > 0.0);
            }
            // Independent scan: count sign changes of X on a fine grid; every one must be a
            // ray found above.
            let grid = 4096;
            let mut prev = cross_term(&k, mu, -PI);
            for i in 1..=grid {
                let th = -PI + std::f64::consts::TAU * i as f64 / grid as f64;
                let x = cross_term(&k, mu, th);
                if prev.signum() != x.signum() && prev != 0.0 {
                    let th_mid = th - std::f64::consts::PI / grid as f64;
                    let near = list
                        .iter()
                        .any(|r| angle_between(r.theta, th_mid) <= 2.0 * PI / grid as f64);
                    assert!(near, "scan found a ray near {th_mid} missing from {list:?}");
                }
                prev = x;
            }
        }
        assert!(
            n_stable > 200 && n_unstable > 200,
            "{n_stable} {n_unstable}"
        );
        eprintln!("ray counting: {n_stable} stable, {n_unstable} unstable, {n4} with four rays");
    }

    #[test]
    fn isotropic_uncoupled_is_every_direction() {
        let k = DMat3::from_diagonal(DVec3::new(3.5, 3.5, 1.0));
        assert!(rays(&k, 0.4).every_direction());
        assert!(rays(&k, 0.4).diverging().is_none());
    }
}
