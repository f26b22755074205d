//! How the program writes numbers and messages for people: durations with a resolution that
//! fits them, ratios to three significant digits, and the one form of an error line.

/// The prefix of every error line the program prints (as cargo and rustc write theirs; clap's
/// own usage errors begin the same way).
pub const ERROR_PREFIX: &str = "error: ";

/// The line printed on standard error for a failure: `error: <message>`. A message that
/// already begins with `error:` (any case) is not prefixed twice.
pub fn error_line(message: &str) -> String {
    let message = message.trim();
    let head = message.get(..ERROR_PREFIX.len() - 1);
    let rest = match head {
        Some(h) if h.eq_ignore_ascii_case(ERROR_PREFIX.trim_end()) => {
            message[ERROR_PREFIX.len() - 1..].trim_start()
        }
        _ => message,
    };
    format!("{ERROR_PREFIX}{rest}")
}

/// A duration of `seconds` to three significant digits in the unit that fits it: `12.3 s`,
/// `1.50 s`, `12.3 ms`, `500 µs`, `42.0 ns`; from 1000 s on, whole seconds (`1234 s`). Zero is
/// `0 s`; a negative or non-finite value is written as it is, in seconds.
pub fn duration(seconds: f64) -> String {
    if seconds == 0.0 {
        return "0 s".to_owned();
    }
    if !(seconds.is_finite() && seconds > 0.0) {
        return format!("{seconds} s");
    }
    if seconds >= 999.5 {
        return format!("{seconds:.0} s");
    }
    // Rounded to three significant digits first, so that 0.99996 s is `1.00 s`, not `1000 ms`.
    let rounded: f64 = format!("{seconds:.2e}").parse().unwrap_or(seconds);
    let (scale, unit) = if rounded >= 1.0 {
        (1.0, "s")
    } else if rounded >= 1e-3 {
        (1e3, "ms")
    } else if rounded >= 1e-6 {
        (1e6, "µs")
    } else {
        (1e9, "ns")
    };
    format!("{} {unit}", significant(rounded * scale))
}

/// `x` to three significant digits: fixed-point from 0.001 to below 10⁴ (`0.0940`, `2.50`,
/// `123`, `1235`), otherwise in exponent form (`3.12e-5`).
pub fn significant(x: f64) -> String {
    let magnitude = x.abs();
    if x == 0.0 {
        return "0".to_owned();
    }
    if !(1e-3..1e4).contains(&magnitude) {
        return format!("{x:.2e}");
    }
    // Digits before the point of x rounded to three significant digits (1..=4).
    let rounded: f64 = format!("{magnitude:.2e}").parse().unwrap_or(magnitude);
    let decimals = (2 - rounded.log10().floor() as i32).max(0) as usize;
    format!("{x:.decimals$}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations_get_a_unit_that_fits() {
        assert_eq!(duration(0.0005), "500 µs");
        assert_eq!(duration(0.0123), "12.3 ms");
        assert_eq!(duration(12.3), "12.3 s");
        assert_eq!(duration(1.5), "1.50 s");
        assert_eq!(duration(0.1), "100 ms");
        assert_eq!(duration(0.000_000_042), "42.0 ns");
        assert_eq!(duration(1234.4), "1234 s");
        assert_eq!(duration(0.0), "0 s");
    }

    /// Rounding that crosses into the next unit takes that unit.
    #[test]
    fn rounding_up_changes_the_unit() {
        assert_eq!(duration(0.999_96), "1.00 s");
        assert_eq!(duration(0.000_999_9), "1.00 ms");
        assert_eq!(duration(999.4), "999 s");
    }

    #[test]
    fn ratios_keep_three_significant_digits() {
        assert_eq!(significant(0.094), "0.0940");
        assert_eq!(significant(2.5), "2.50");
        assert_eq!(significant(123.4), "123");
        assert_eq!(significant(0.000_031_2), "3.12e-5");
        assert_eq!(significant(0.0), "0");
    }

    #[test]
    fn every_error_line_starts_the_same_way() {
        assert_eq!(error_line("cannot read x"), "error: cannot read x");
        assert_eq!(error_line("Error: cannot read x"), "error: cannot read x");
        assert_eq!(error_line("error:cannot read x\n"), "error: cannot read x");
        assert_eq!(error_line("errors: 3"), "error: errors: 3");
    }
}
