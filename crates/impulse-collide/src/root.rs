//! The quadratic root behind every time-of-impact bound (thesis eq. 2.13): the first time a
//! displacement bound `a·τ² + b·τ` reaches a gap. Both the motion types (to choose between two
//! bounds) and the pair bound of [`crate::toi`] solve it; it lives here so neither imports the
//! other.

/// Smallest τ > 0 (s) with `a·τ² + b·τ = gap`, for `a` (m/s²), `b` (m/s) and the current
/// distance `gap` (m); `f64::INFINITY` when the bound never reaches the gap
/// (the bodies cannot meet on their current trajectories).
///
/// With `h = b/2` and `R = √(h² + a·gap)` (the discriminant `b² + 4a·gap` divided by 4):
///
/// | case | result |
/// |---|---|
/// | `gap ≤ 0` (touching or, by rounding, overlapping) | `0` |
/// | `a > 0` (approach accelerates) | the one positive root |
/// | `a = 0`, `b > 0` | `gap / b` |
/// | `a = 0`, `b ≤ 0` (not approaching) | `∞` |
/// | `a < 0`, `b > 0`, `R² ≥ 0` (real roots, both positive) | the smaller root |
/// | `a < 0`, `R² < 0` (the bound peaks below the gap) | `∞` |
/// | `a < 0`, `b ≤ 0` (no positive root) | `∞` |
///
/// The positive root is evaluated without cancellation: `τ = gap / (h + R)`, the form
/// `2d / (b + √(b² + 4ad))` of the thesis digest, when `h > 0`; its conjugate `τ = (R − h)/a`
/// when `h ≤ 0` and `a > 0` (there `h + R` would cancel). `h` and `√|a|·√gap` are divided by
/// their larger magnitude before squaring, so no intermediate overflows or underflows unless
/// the result itself does (an overflowing root is reported as `∞`).
///
/// Non-finite input, conservatively: NaN anywhere, or `+∞` in a coefficient (an unbounded
/// motion, [`crate::motion::UNBOUNDED_COEFFICIENTS`]), gives `0` (check now); otherwise
/// `gap = +∞` or a `−∞` coefficient sum gives `∞`.
#[must_use]
pub fn closing_time(gap: f64, a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() || a == f64::INFINITY || b == f64::INFINITY || gap.is_nan() {
        return 0.0;
    }
    if gap <= 0.0 {
        return 0.0;
    }
    if gap == f64::INFINITY || a == f64::NEG_INFINITY || b == f64::NEG_INFINITY {
        return f64::INFINITY;
    }
    let h = 0.5 * b;
    // q² = |a|·gap, formed without the product overflowing.
    let q = a.abs().sqrt() * gap.sqrt();
    let m = h.abs().max(q);
    if m == 0.0 {
        return f64::INFINITY; // a = 0 and b = 0: no motion toward each other.
    }
    let (hs, qs) = (h.abs() / m, q / m);
    let disc = if a >= 0.0 {
        hs * hs + qs * qs
    } else {
        (hs - qs) * (hs + qs)
    };
    if disc < 0.0 {
        return f64::INFINITY;
    }
    let r = m * disc.sqrt();
    if h > 0.0 {
        gap / (h + r)
    } else if a > 0.0 {
        (r - h) / a
    } else {
        f64::INFINITY
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::testkit::rng;
    use rand::RngExt;

    /// Closed-form cases whose bound is exact: a few ulps of the result.
    const EXACT_REL: f64 = 4.0 * f64::EPSILON;
    /// Root accuracy against the double-double reference, in units of ε·(1 + κ), κ the
    /// condition number of the root (see `condition`).
    const ROOT_ULPS: f64 = 8.0;
    /// The textbook root formula must be worse than this (in ε(1 + κ)) somewhere on the random
    /// data, showing the data exercise cancellation.
    const NAIVE_MIN_ERROR: f64 = 1e6;

    // ---- double-double reference (error-free transformations, no FMA) ----

    fn two_sum(a: f64, b: f64) -> (f64, f64) {
        let s = a + b;
        let bb = s - a;
        (s, (a - (s - bb)) + (b - bb))
    }

    fn split(a: f64) -> (f64, f64) {
        let c = 134_217_729.0 * a; // 2^27 + 1 (Dekker)
        let hi = c - (c - a);
        (hi, a - hi)
    }

    fn two_prod(a: f64, b: f64) -> (f64, f64) {
        let p = a * b;
        let ((ah, al), (bh, bl)) = (split(a), split(b));
        (p, ((ah * bh - p) + ah * bl + al * bh) + al * bl)
    }

    #[derive(Clone, Copy)]
    struct Dd(f64, f64);

    impl Dd {
        fn mul(self, y: f64) -> Dd {
            let (p, e) = two_prod(self.0, y);
            let (s, e2) = two_sum(p, e + self.1 * y);
            Dd(s, e2)
        }
        fn add(self, y: Dd) -> Dd {
            let (s, e) = two_sum(self.0, y.0);
            let (s2, e2) = two_sum(s, e + self.1 + y.1);
            Dd(s2, e2)
        }
        fn sign(self) -> f64 {
            if self.0 != 0.0 {
                self.0.signum()
            } else {
                self.1.signum()
            }
        }
    }

    /// Sign of `a·τ² + b·τ − d` to ~106 bits (Horner form, no overflow near the root).
    fn poly_sign(a: f64, b: f64, d: f64, tau: f64) -> f64 {
        Dd(a, 0.0)
            .mul(tau)
            .add(Dd(b, 0.0))
            .mul(tau)
            .add(Dd(-d, 0.0))
            .sign()
    }

    /// The smallest positive root by bisection on the double-double polynomial, to adjacent
    /// doubles; `None` if there is none (existence decided by the exact sign of b² + 4ad).
    fn reference_root(a: f64, b: f64, d: f64) -> Option<f64> {
        let disc = {
            let (p, e) = two_prod(b, b);
            let (q, f) = two_prod(4.0 * a, d);
            Dd(p, e).add(Dd(q, f)).sign()
        };
        let mut hi = if a > 0.0 {
            1.5 * ((-b).max(0.0) / a + (d / a).sqrt())
        } else if a == 0.0 && b > 0.0 {
            2.0 * d / b
        } else if a < 0.0 && b > 0.0 && disc >= 0.0 {
            -b / (2.0 * a) // vertex of the parabola: f ≥ 0 there
        } else {
            return None;
        };
        while a >= 0.0 && poly_sign(a, b, d, hi) < 0.0 {
            hi *= 2.0;
        }
        let mut lo = 0.0;
        loop {
            let mid = lo + 0.5 * (hi - lo);
            if mid <= lo || mid >= hi {
                return Some(hi);
            }
            if poly_sign(a, b, d, mid) < 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
    }

    /// Relative condition number of the root τ of `aτ² + bτ = d` under relative perturbations
    /// of a, b, d: `(|a|τ² + |b|τ + d) / (|2aτ + b|·τ)`.
    fn condition(a: f64, b: f64, d: f64, tau: f64) -> f64 {
        (a.abs() * tau * tau + b.abs() * tau + d) / ((2.0 * a * tau + b).abs() * tau)
    }

    /// The textbook formula, for contrast: cancels when b < 0 < a or |4ad| ≪ b², overflows b².
    fn naive(a: f64, b: f64, d: f64) -> f64 {
        if a == 0.0 {
            d / b
        } else {
            (-b + (b * b + 4.0 * a * d).sqrt()) / (2.0 * a)
        }
    }

    fn check_against_reference(a: f64, b: f64, d: f64) -> f64 {
        let got = closing_time(d, a, b);
        match reference_root(a, b, d) {
            None => {
                assert_eq!(got, f64::INFINITY, "a {a} b {b} d {d}");
                0.0
            }
            Some(want) => {
                let kappa = condition(a, b, d, want);
                let err = (got - want).abs() / want / (f64::EPSILON * (1.0 + kappa));
                assert!(
                    err <= ROOT_ULPS,
                    "a {a} b {b} d {d}: {got} vs {want} ({err} ulps, κ {kappa})"
                );
                err
            }
        }
    }

    #[test]
    fn roots_match_a_double_double_reference() {
        let mut rng = rng(4242);
        let mut worst: f64 = 0.0;
        let mut naive_worst: f64 = 0.0;
        let mut counts = [0usize; 4]; // a > 0, a = 0, a < 0 finite, a < 0 infinite
        for i in 0..40_000 {
            let sign = |r: &mut rand::rngs::Xoshiro256PlusPlus| {
                if r.random::<bool>() { 1.0 } else { -1.0 }
            };
            let (a, b, d) = if i % 2 == 0 {
                // Independent magnitudes over 120 decades.
                let pick = |r: &mut rand::rngs::Xoshiro256PlusPlus| {
                    if r.random_range(0.0..1.0) < 0.1 {
                        0.0
                    } else {
                        sign(r) * 10f64.powf(r.random_range(-60.0..60.0))
                    }
                };
                let (a, b) = (pick(&mut rng), pick(&mut rng));
                (a, b, 10f64.powf(rng.random_range(-60.0..60.0)))
            } else {
                // Balanced terms around a target time: where cancellation would bite.
                let tau = 10f64.powf(rng.random_range(-40.0..40.0));
                let d = 10f64.powf(rng.random_range(-40.0..40.0));
                let a = sign(&mut rng) * 10f64.powf(rng.random_range(-4.0..1.0)) * d / (tau * tau);
                let b = sign(&mut rng) * 10f64.powf(rng.random_range(-4.0..1.0)) * d / tau;
                (a, b, d)
            };
            let got = closing_time(d, a, b);
            let slot = if a > 0.0 {
                0
            } else if a == 0.0 {
                1
            } else if got.is_finite() {
                2
            } else {
                3
            };
            counts[slot] += 1;
            worst = worst.max(check_against_reference(a, b, d));
            if let Some(want) = reference_root(a, b, d) {
                let kappa = condition(a, b, d, want);
                naive_worst = naive_worst
                    .max((naive(a, b, d) - want).abs() / want / (f64::EPSILON * (1.0 + kappa)));
            }
        }
        assert!(counts.iter().all(|&c| c > 1000), "{counts:?}");
        // The naive formula is not accurate on the same data (cancellation).
        assert!(naive_worst > NAIVE_MIN_ERROR);
        eprintln!(
            "pair_toi vs double-double: worst {worst:.2} ε(1+κ); naive formula \
             {naive_worst:.2e}; cases {counts:?}"
        );
    }

    #[test]
    fn scaling_by_powers_of_two_changes_nothing() {
        // Exact invariances: scaling a, b, d by 2^k leaves τ unchanged; scaling time by 2^j
        // (a·4^j, b·2^j) divides τ by 2^j. Powers of two keep every operation exact, so the
        // results agree bitwise, far beyond where b² or a·d would overflow or underflow.
        let mut rng = rng(8);
        for _ in 0..5000 {
            let a = if rng.random::<bool>() { 1.0 } else { -1.0 } * rng.random_range(0.1..10.0);
            let b = if rng.random::<bool>() { 1.0 } else { -1.0 } * rng.random_range(0.1..10.0);
            let d = rng.random_range(0.1..10.0);
            let base = closing_time(d, a, b);
            for k in [-1000, -600, 600, 1000] {
                let s = 2f64.powi(k);
                assert_eq!(closing_time(d * s, a * s, b * s).to_bits(), base.to_bits());
            }
            for j in [-400, -200, 200, 400] {
                let s = 2f64.powi(j);
                let scaled = closing_time(d, a * s * s, b * s);
                assert_eq!(
                    scaled.to_bits(),
                    (base / s).to_bits(),
                    "a {a} b {b} d {d} j {j}"
                );
            }
        }
        // The textbook formula overflows where this one does not.
        let s = 2f64.powi(600);
        assert!(naive(s, s, s).is_nan() || naive(s, s, s) != closing_time(s, s, s));
        assert!((closing_time(s, s, s) - 0.5 * (5f64.sqrt() - 1.0)).abs() <= EXACT_REL);
    }
}
