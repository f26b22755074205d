//! Regression snapshots of the cases' metrics, compared with insta.
//!
//! Each case has one text snapshot `fixtures/snapshots/<case name>.snap`: a line `name = value`
//! per metric, the value **rounded to its tolerance** so that a snapshot changes only when a
//! result moves by a meaningful amount:
//!
//! | Check | Rounded to |
//! |---|---|
//! | `Abs(t)` | the decimal place of `t`: `q = 10^floor(log10 t)`, `round(v / q)·q`, printed with exactly that many decimals (`t = 5e-5` → `q = 1e-5`, 5 decimals; `t = 20` → tens) |
//! | `Rel(t)` | `ceil(-log10 t)` significant digits (at least 1), in scientific notation (`t = 1e-6` → `1.23457e2`) |
//! | `Between(lo, hi)` | like `Abs((hi − lo) / 10)` |
//! | `Exact` | the integer if the value is integral, else its shortest round-trip representation |
//!
//! Decimal exponents come from the shortest round-trip representation of `t`, not from
//! `log10`, so `1e-5` is exactly 10⁻⁵; the rounding itself is done by the (exact) decimal
//! formatting of the binary value, so no float noise such as `0.30000000000000004` appears. A
//! negative zero, or a negative value that rounds to zero, prints without its sign; NaN and
//! infinities print as `NaN`, `inf`, `-inf`. A tolerance finer than the value's own precision
//! prints the shortest round-trip representation instead.
//!
//! insta's update mode is read from the environment, which this process does not change (that
//! would be `unsafe` in edition 2024): [`super::run`] starts the validation in a child process
//! with `INSTA_UPDATE=no` (compare only; nothing is written, no `.snap.new` files) or, with
//! `--update`, `INSTA_UPDATE=always` (write new and changed snapshots in place).

use std::panic::{self, AssertUnwindSafe};
use std::path::Path;

use super::case::{Case, Check, Metric};
use super::check::exponent;

/// What comparing a case with its snapshot found.
#[derive(Clone, Debug, PartialEq)]
pub enum Outcome {
    /// The snapshot exists and matches.
    Matches,
    /// Update mode: the snapshot was written (`"new"` or `"updated"`).
    Written(&'static str),
    /// The snapshot is missing or differs (or insta failed); the message says what to do.
    Failed(String),
}

/// The snapshot text of a case: `name = value` per metric, values rounded to their checks.
pub fn text(metrics: &[Metric]) -> String {
    let lines: Vec<String> = metrics
        .iter()
        .map(|m| format!("{} = {}", m.name, round(m.value, m.check)))
        .collect();
    lines.join("\n")
}

/// `value` rounded to the tolerance of `check` and printed (see the module documentation).
pub fn round(value: f64, check: Check) -> String {
    let text = if !value.is_finite() {
        format!("{value}")
    } else {
        match check {
            Check::Abs(tol) => to_place(value, tol),
            Check::Rel(tol) => to_significant(value, tol),
            Check::Between(lo, hi) => to_place(value, (hi - lo) / 10.0),
            Check::Exact => shortest(value),
        }
    };
    unsigned_zero(text)
}

/// Rounds to the decimal place of `quantum`'s leading digit.
fn to_place(value: f64, quantum: f64) -> String {
    if !(quantum.is_finite() && quantum > 0.0) {
        return shortest(value);
    }
    let place = exponent(quantum);
    if place <= 0 {
        let decimals = (-place) as usize;
        // Past 17 significant digits the rounding is finer than the value itself.
        if value != 0.0 && exponent(value) + 1 + place.abs() > 17 {
            return shortest(value);
        }
        format!("{value:.decimals$}")
    } else {
        let units = (value / 10f64.powi(place)).round();
        if units == 0.0 {
            "0".to_owned()
        } else if place > 22 || units.abs() >= 1e15 {
            format!("{:e}", units * 10f64.powi(place))
        } else {
            format!("{units:.0}{}", "0".repeat(place as usize))
        }
    }
}

/// Rounds to `ceil(-log10 tol)` significant digits, at least 1 and at most 17.
fn to_significant(value: f64, tol: f64) -> String {
    if !(tol.is_finite() && tol > 0.0) {
        return shortest(value);
    }
    // With tol = m·10^e, 1 ≤ m < 10: ceil(-log10 tol) = -e exactly.
    let digits = (-exponent(tol)).clamp(1, 17) as usize;
    format!("{value:.precision$e}", precision = digits - 1)
}

/// The value as an integer if integral, else its shortest round-trip representation.
fn shortest(value: f64) -> String {
    let magnitude = value.abs();
    if value == value.trunc() && magnitude < 1e15 || (1e-4..1e15).contains(&magnitude) {
        format!("{value}")
    } else {
        format!("{value:e}")
    }
}

/// Drops the sign of a printed zero (`-0`, `-0.000`, `-0.00e0`).
fn unsigned_zero(text: String) -> String {
    let mantissa = text.split('e').next().unwrap_or("");
    match text.strip_prefix('-') {
        Some(rest) if mantissa.chars().all(|c| "-0.".contains(c)) => rest.to_owned(),
        _ => text,
    }
}

/// Compares `text` with the snapshot of `case` in `dir` through insta (which prints the diff
/// on a mismatch); in update mode, reports whether the file was written.
///
/// Runs insta under [`super::run`]'s environment: `INSTA_UPDATE=always` when `update`,
/// otherwise `INSTA_UPDATE=no`. Without `update`, a missing snapshot fails before insta is
/// called.
pub fn compare(case: &Case, text: &str, dir: &Path, update: bool) -> Outcome {
    let path = dir.join(format!("{}.snap", case.name));
    let before = std::fs::read(&path).ok();
    if before.is_none() && !update {
        return Outcome::Failed(format!(
            "no snapshot {}: run `cargo xtask validate --update` and review the new file",
            path.display()
        ));
    }
    let mut settings = insta::Settings::clone_current();
    settings.set_snapshot_path(dir);
    settings.set_prepend_module_to_snapshot(false);
    settings.set_omit_expression(true);
    settings.set_description(case.description);

    // insta panics on a mismatch after printing the diff; the default hook would add a panic
    // report (and backtrace) to that. Other panics (I/O errors) keep their message in the row.
    let hook = panic::take_hook();
    panic::set_hook(Box::new(|_| {}));
    let result = panic::catch_unwind(AssertUnwindSafe(|| {
        settings.bind(|| insta::assert_snapshot!(case.name, text));
    }));
    panic::set_hook(hook);

    match result {
        Err(payload) => {
            let message = super::panic_message(payload.as_ref());
            if message.starts_with("snapshot assertion for") {
                Outcome::Failed(format!(
                    "differs from {} (diff above); if the change is intended, run \
                     `cargo xtask validate --update` and review the diff",
                    path.display()
                ))
            } else {
                Outcome::Failed(format!("insta failed on {}: {message}", path.display()))
            }
        }
        Ok(()) if !update => Outcome::Matches,
        Ok(()) => match (before, std::fs::read(&path).ok()) {
            (_, None) => Outcome::Failed(format!("insta wrote no snapshot at {}", path.display())),
            (None, Some(_)) => Outcome::Written("new"),
            (Some(old), Some(new)) if old != new => Outcome::Written("updated"),
            (Some(_), Some(_)) => Outcome::Matches,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn abs_rounds_to_the_decimal_place_of_the_tolerance() {
        assert_eq!(round(1.234567, Check::Abs(5e-5)), "1.23457");
        assert_eq!(round(1.234567, Check::Abs(1e-4)), "1.2346");
        assert_eq!(round(1.234567, Check::Abs(9.9e-4)), "1.2346");
        assert_eq!(round(1.234567, Check::Abs(1e-3)), "1.235");
        assert_eq!(round(1.234567, Check::Abs(0.5)), "1.2");
        assert_eq!(round(1.234567, Check::Abs(1.0)), "1");
        assert_eq!(round(1234.5678, Check::Abs(20.0)), "1230");
        assert_eq!(round(1250.1, Check::Abs(100.0)), "1300");
        assert_eq!(round(12.0, Check::Abs(1e-6)), "12.000000");
    }

    #[test]
    fn float_noise_is_rounded_away() {
        assert_eq!(round(0.1 + 0.2, Check::Abs(1e-6)), "0.300000");
        assert_eq!(round(0.1 + 0.2, Check::Abs(1e-12)), "0.300000000000");
        assert_eq!(round(0.1 + 0.2, Check::Rel(1e-9)), "3.00000000e-1");
        assert_eq!(round(0.1 + 0.2, Check::Between(0.0, 1.0)), "0.3");
        assert_eq!(round(1.0 / 3.0, Check::Abs(1e-3)), "0.333");
        assert_eq!(round(2.0 / 3.0, Check::Abs(1e-3)), "0.667");
    }

    #[test]
    fn negative_values_round_symmetrically() {
        assert_eq!(round(-1.234567, Check::Abs(5e-5)), "-1.23457");
        assert_eq!(round(-1234.5678, Check::Abs(20.0)), "-1230");
        assert_eq!(round(-0.1 - 0.2, Check::Rel(1e-6)), "-3.00000e-1");
        assert_eq!(round(-2.0 / 3.0, Check::Abs(1e-3)), "-0.667");
    }

    #[test]
    fn negative_zero_loses_its_sign() {
        assert_eq!(round(-0.0, Check::Abs(1e-3)), "0.000");
        assert_eq!(round(-1e-9, Check::Abs(1e-3)), "0.000");
        assert_eq!(round(-1e-9, Check::Abs(10.0)), "0");
        assert_eq!(round(-0.0, Check::Rel(1e-3)), "0.00e0");
        assert_eq!(round(-0.0, Check::Exact), "0");
        assert_eq!(round(-3.0, Check::Exact), "-3");
    }

    #[test]
    fn rel_rounds_to_significant_digits() {
        assert_eq!(round(123.456789, Check::Rel(1e-6)), "1.23457e2");
        assert_eq!(round(123.456789, Check::Rel(5e-6)), "1.23457e2");
        assert_eq!(round(123.456789, Check::Rel(2e-3)), "1.23e2");
        assert_eq!(round(123.456789, Check::Rel(0.5)), "1e2");
        assert_eq!(round(123.456789, Check::Rel(3.0)), "1e2");
        assert_eq!(round(9.9999999, Check::Rel(1e-3)), "1.00e1");
        assert_eq!(round(6.02214076e23, Check::Rel(1e-4)), "6.022e23");
        assert_eq!(round(1.6e-19, Check::Rel(1e-2)), "1.6e-19");
    }

    #[test]
    fn between_rounds_to_a_tenth_of_its_width() {
        assert_eq!(round(0.123456, Check::Between(0.0, 1.0)), "0.1");
        assert_eq!(round(0.123456, Check::Between(0.1, 0.2)), "0.12");
        assert_eq!(round(57.0, Check::Between(0.0, 1000.0)), "100");
    }

    #[test]
    fn exact_prints_integers_and_shortest_round_trips() {
        assert_eq!(round(42.0, Check::Exact), "42");
        assert_eq!(round(0.1 + 0.2, Check::Exact), "0.30000000000000004");
        assert_eq!(round(1e-300, Check::Exact), "1e-300");
        assert_eq!(round(1e20, Check::Exact), "1e20");
    }

    #[test]
    fn degenerate_inputs() {
        assert_eq!(round(f64::NAN, Check::Abs(1e-3)), "NaN");
        assert_eq!(round(f64::NEG_INFINITY, Check::Rel(1e-3)), "-inf");
        // A zero or invalid tolerance, or one finer than f64, keeps every digit.
        assert_eq!(round(0.1 + 0.2, Check::Abs(0.0)), "0.30000000000000004");
        assert_eq!(round(0.1 + 0.2, Check::Abs(1e-30)), "0.30000000000000004");
        assert_eq!(
            round(0.1 + 0.2, Check::Between(1.0, 1.0)),
            "0.30000000000000004"
        );
        assert_eq!(round(1e300, Check::Abs(1e-3)), "1e300");
    }

    #[test]
    fn snapshot_text_has_one_line_per_metric() {
        let metrics = [
            Metric::new("volume", 1.0 / 3.0, 1.0 / 3.0, Check::Rel(1e-9)),
            Metric::new("faces", 20.0, 20.0, Check::Exact),
            Metric::new("T_x2", -1e-17, 0.0, Check::Abs(1e-12)),
        ];
        assert_eq!(
            text(&metrics),
            "volume = 3.33333333e-1\nfaces = 20\nT_x2 = 0.000000000000"
        );
    }
}
