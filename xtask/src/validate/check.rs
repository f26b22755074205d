//! Judging a metric by its [`Check`], and printing values and tolerances for the table.
//!
//! A NaN value always fails, whatever the check; so does a malformed check (a negative, NaN or
//! infinite tolerance, an interval with `lo > hi` or a NaN bound), which is reported as such
//! rather than silently passing or failing.

use super::case::{Check, Metric};

/// The verdict on one metric.
#[derive(Clone, Debug, PartialEq)]
pub struct Verdict {
    /// Whether the metric passes its check.
    pub pass: bool,
    /// Why it fails when the reason is not just "out of tolerance" (NaN, malformed check).
    pub note: Option<String>,
}

/// Judges `metric.value` against `metric.reference` with `metric.check`.
pub fn evaluate(metric: &Metric) -> Verdict {
    let fail = |note: &str| Verdict {
        pass: false,
        note: Some(note.to_owned()),
    };
    if let Some(problem) = malformed(metric.check) {
        return fail(&problem);
    }
    if metric.value.is_nan() {
        return fail("value is NaN");
    }
    let (value, reference) = (metric.value, metric.reference);
    let pass = match metric.check {
        Check::Abs(tol) => (value - reference).abs() <= tol,
        Check::Rel(tol) => (value - reference).abs() <= tol * reference.abs(),
        Check::Between(lo, hi) => lo <= value && value <= hi,
        Check::Exact => value == reference,
    };
    // The reference of `Between` is informative only, so only the other checks blame it.
    let note = (!pass && reference.is_nan() && !matches!(metric.check, Check::Between(..)))
        .then(|| "reference is NaN".to_owned());
    Verdict { pass, note }
}

/// What is wrong with a check, if anything.
fn malformed(check: Check) -> Option<String> {
    match check {
        Check::Abs(tol) | Check::Rel(tol) if !(tol.is_finite() && tol >= 0.0) => Some(format!(
            "malformed check: tolerance {tol} is not finite and ≥ 0"
        )),
        Check::Between(lo, hi) if lo.is_nan() || hi.is_nan() || lo > hi => Some(format!(
            "malformed check: interval [{lo}, {hi}] is empty or has a NaN bound"
        )),
        _ => None,
    }
}

/// The tolerance column: `±t`, `rel t`, `[lo, hi]` or `exact`.
pub fn tolerance(check: Check) -> String {
    match check {
        Check::Abs(tol) => format!("±{}", short(tol)),
        Check::Rel(tol) => format!("rel {}", short(tol)),
        Check::Between(lo, hi) => format!("[{}, {}]", short(lo), short(hi)),
        Check::Exact => "exact".to_owned(),
    }
}

/// A value or reference for the table, with enough digits to see a failure of `check`.
///
/// Integers below 10¹⁵ print as integers. Otherwise the number prints in scientific notation
/// down to about a hundredth of the resolution the check judges at (`t` for `Abs(t)`,
/// `t·|reference|` for `Rel(t)`, the width for `Between`), at least 4 and at most 17
/// significant digits; `Exact` prints the shortest representation that round-trips.
pub fn number(x: f64, check: Check, reference: f64) -> String {
    if !x.is_finite() || x == x.trunc() && x.abs() < 1e15 {
        return format!("{}", x + 0.0);
    }
    let resolution = match check {
        Check::Abs(tol) => tol,
        Check::Rel(tol) => tol * reference.abs(),
        Check::Between(lo, hi) => hi - lo,
        Check::Exact => 0.0,
    };
    if !(resolution.is_finite() && resolution > 0.0) {
        return format!("{x:e}");
    }
    let digits = exponent(x) - exponent(resolution) + 2;
    let digits = digits.clamp(3, 16) as usize;
    format!("{x:.digits$e}")
}

/// A short rendering of a tolerance or bound: plain when it reads well, else scientific.
pub fn short(x: f64) -> String {
    let magnitude = x.abs();
    if magnitude == 0.0 || !x.is_finite() || (1e-3..1e6).contains(&magnitude) {
        format!("{}", x + 0.0)
    } else {
        format!("{x:e}")
    }
}

/// The decimal exponent `e` of a finite non-zero `x` = m·10^e, 1 ≤ |m| < 10, read from the
/// shortest round-trip representation (exact, unlike `log10`).
pub fn exponent(x: f64) -> i32 {
    let text = format!("{x:e}");
    text.rsplit_once('e')
        .and_then(|(_, e)| e.parse().ok())
        .unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn passes(value: f64, reference: f64, check: Check) -> bool {
        evaluate(&Metric::new("m", value, reference, check)).pass
    }

    #[test]
    fn abs() {
        assert!(passes(1.0 + 1e-7, 1.0, Check::Abs(1e-6)));
        assert!(passes(1.0 - 1e-7, 1.0, Check::Abs(1e-6)));
        assert!(passes(1.5, 1.0, Check::Abs(0.5)));
        assert!(!passes(1.0 + 2e-6, 1.0, Check::Abs(1e-6)));
        assert!(!passes(-1.0, 1.0, Check::Abs(1.0)));
    }

    #[test]
    fn rel() {
        assert!(passes(1000.0 + 1e-4, 1000.0, Check::Rel(1e-6)));
        assert!(!passes(1000.0 + 1e-2, 1000.0, Check::Rel(1e-6)));
        assert!(passes(-2.0, -2.0 * (1.0 + 1e-10), Check::Rel(1e-9)));
        // A zero reference admits only zero.
        assert!(passes(0.0, 0.0, Check::Rel(1e-6)));
        assert!(!passes(1e-300, 0.0, Check::Rel(1e-6)));
    }

    #[test]
    fn between() {
        assert!(passes(0.5, 99.0, Check::Between(0.0, 1.0)));
        assert!(passes(0.0, 0.0, Check::Between(0.0, 1.0)));
        assert!(passes(1.0, 0.0, Check::Between(0.0, 1.0)));
        assert!(!passes(1.0 + 1e-15, 0.0, Check::Between(0.0, 1.0)));
        assert!(!passes(-1e-300, 0.0, Check::Between(0.0, 1.0)));
    }

    #[test]
    fn exact() {
        assert!(passes(12.0, 12.0, Check::Exact));
        assert!(passes(-0.0, 0.0, Check::Exact));
        assert!(!passes(12.0, 12.000000000000002, Check::Exact));
        assert!(!passes(0.1 + 0.2, 0.3, Check::Exact));
    }

    #[test]
    fn nan_always_fails() {
        for check in [
            Check::Abs(1e300),
            Check::Rel(1e300),
            Check::Between(-1e300, 1e300),
            Check::Exact,
        ] {
            let verdict = evaluate(&Metric::new("m", f64::NAN, f64::NAN, check));
            assert_eq!(
                verdict,
                Verdict {
                    pass: false,
                    note: Some("value is NaN".to_owned())
                }
            );
            assert!(!passes(1.0, f64::NAN, check) || matches!(check, Check::Between(..)));
        }
        assert!(!passes(f64::INFINITY, f64::INFINITY, Check::Abs(1.0)));
    }

    #[test]
    fn malformed_checks_fail() {
        for check in [
            Check::Abs(-1.0),
            Check::Abs(f64::NAN),
            Check::Rel(f64::INFINITY),
            Check::Between(1.0, 0.0),
            Check::Between(f64::NAN, 1.0),
        ] {
            let verdict = evaluate(&Metric::new("m", 0.5, 0.5, check));
            assert!(!verdict.pass, "{check:?}");
            assert!(
                verdict.note.unwrap().starts_with("malformed check"),
                "{check:?}"
            );
        }
    }

    #[test]
    fn tolerance_column() {
        assert_eq!(tolerance(Check::Abs(5e-5)), "±5e-5");
        assert_eq!(tolerance(Check::Abs(0.01)), "±0.01");
        assert_eq!(tolerance(Check::Rel(1e-9)), "rel 1e-9");
        assert_eq!(tolerance(Check::Between(0.25, 2.0)), "[0.25, 2]");
        assert_eq!(tolerance(Check::Exact), "exact");
    }

    #[test]
    fn numbers_show_enough_digits() {
        assert_eq!(number(42.0, Check::Exact, 42.0), "42");
        assert_eq!(number(-0.0, Check::Exact, 0.0), "0");
        assert_eq!(number(f64::NAN, Check::Abs(1.0), 0.0), "NaN");
        assert_eq!(
            number(0.1 + 0.2, Check::Exact, 0.3),
            "3.0000000000000004e-1"
        );
        // Abs(1e-6) at magnitude 1: digits down to 1e-8.
        assert_eq!(number(1.0 + 2e-6, Check::Abs(1e-6), 1.0), "1.00000200e0");
        // Rel(1e-9) of 1000: resolution 1e-6, digits down to 1e-8.
        assert_eq!(
            number(1000.000002, Check::Rel(1e-9), 1000.0),
            "1.00000000200e3"
        );
        // Coarse tolerances still show 4 significant digits.
        assert_eq!(
            number(std::f64::consts::PI, Check::Abs(10.0), 3.0),
            "3.142e0"
        );
    }

    #[test]
    fn exponents_are_exact() {
        assert_eq!(exponent(1e-5), -5);
        assert_eq!(exponent(9.999999e-5), -5);
        assert_eq!(exponent(5e-5), -5);
        assert_eq!(exponent(1e-3), -3);
        assert_eq!(exponent(-250.0), 2);
        assert_eq!(exponent(1.0), 0);
    }
}
