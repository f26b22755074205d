//! Statistics of pose studies (thesis §7.5): the error metric of a predicted pose
//! distribution against a measured one (eq. 7.2), the number of drops a confidence statement
//! needs (eq. 7.3, in its squared form) and binomial confidence intervals.
//!
//! On eq. 7.3: the extracted text reads `n = Φ⁻¹(1 − α/2)/(2δ)`, which gives 16.4 for the
//! thesis's worked example; the worst-case binomial bound (the normal approximation with
//! p(1 − p) ≤ ¼) is `n = (Φ⁻¹(1 − α/2)/(2δ))²`, which gives 271 at 90 % and 385 at 95 % for
//! δ = 0.05. The thesis's "385 trials" is the 95 % figure, though its text says 90 %.

use crate::MassError;

/// Error of a predicted distribution `predicted` against the measured one `measured`, both
/// as fractions over the same poses (eq. 7.2): `e = 100 · Σ_i p_i·|a_i − p_i|`, p the
/// measured frequencies and a the predicted ones.
///
/// # Errors
/// [`MassError::InvalidStatistic`] when the lengths differ or a value is not finite.
pub fn pose_error(measured: &[f64], predicted: &[f64]) -> Result<f64, MassError> {
    if measured.len() != predicted.len() {
        return Err(MassError::InvalidStatistic {
            name: "pose distributions",
            reason: format!(
                "{} measured frequencies against {} predicted",
                measured.len(),
                predicted.len()
            ),
        });
    }
    if let Some(x) = measured.iter().chain(predicted).find(|x| !x.is_finite()) {
        return Err(MassError::InvalidStatistic {
            name: "pose distributions",
            reason: format!("{x} is not finite"),
        });
    }
    Ok(100.0
        * measured
            .iter()
            .zip(predicted)
            .map(|(p, a)| p * (a - p).abs())
            .sum::<f64>())
}

/// Φ⁻¹(p), the standard normal quantile, for 0 < p < 1 (Acklam's rational approximation,
/// relative error below 1.2e-9 over the whole range).
///
/// # Errors
/// [`MassError::InvalidStatistic`] unless 0 < p < 1.
pub fn normal_quantile(p: f64) -> Result<f64, MassError> {
    if !(p > 0.0 && p < 1.0) {
        return Err(MassError::InvalidStatistic {
            name: "probability",
            reason: format!("{p} is not in (0, 1)"),
        });
    }
    const A: [f64; 6] = [
        -3.969_683_028_665_376e1,
        2.209_460_984_245_205e2,
        -2.759_285_104_469_687e2,
        1.383_577_518_672_69e2,
        -3.066_479_806_614_716e1,
        2.506_628_277_459_239,
    ];
    const B: [f64; 5] = [
        -5.447_609_879_822_406e1,
        1.615_858_368_580_409e2,
        -1.556_989_798_598_866e2,
        6.680_131_188_771_972e1,
        -1.328_068_155_288_572e1,
    ];
    const C: [f64; 6] = [
        -7.784_894_002_430_293e-3,
        -3.223_964_580_411_365e-1,
        -2.400_758_277_161_838,
        -2.549_732_539_343_734,
        4.374_664_141_464_968,
        2.938_163_982_698_783,
    ];
    const D: [f64; 4] = [
        7.784_695_709_041_462e-3,
        3.224_671_290_700_398e-1,
        2.445_134_137_142_996,
        3.754_408_661_907_416,
    ];
    /// Where the central rational form hands over to the tails.
    const P_LOW: f64 = 0.02425;
    let tail = |q: f64| {
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    };
    Ok(if p < P_LOW {
        tail((-2.0 * p.ln()).sqrt())
    } else if p > 1.0 - P_LOW {
        -tail((-2.0 * (1.0 - p).ln()).sqrt())
    } else {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    })
}

/// The two-sided normal quantile z = Φ⁻¹(1 − α/2) of a confidence level 1 − α.
fn two_sided_z(confidence: f64) -> Result<f64, MassError> {
    if !(confidence > 0.0 && confidence < 1.0) {
        return Err(MassError::InvalidStatistic {
            name: "confidence level",
            reason: format!("{confidence} is not in (0, 1)"),
        });
    }
    normal_quantile(0.5 + 0.5 * confidence)
}

/// The number of drops after which every pose's frequency lies within ±`delta` of its
/// probability with the given `confidence` (e.g. 0.95), whatever the probability (eq. 7.3,
/// squared form): `n = ⌈(Φ⁻¹(1 − α/2)/(2δ))²⌉`.
///
/// # Errors
/// [`MassError::InvalidStatistic`] unless 0 < delta < 1 and 0 < confidence < 1.
pub fn sample_size(delta: f64, confidence: f64) -> Result<u64, MassError> {
    if !(delta > 0.0 && delta < 1.0) {
        return Err(MassError::InvalidStatistic {
            name: "half-width δ",
            reason: format!("{delta} is not in (0, 1)"),
        });
    }
    let z = two_sided_z(confidence)?;
    Ok((z / (2.0 * delta)).powi(2).ceil() as u64)
}

/// The worst-case half-width δ of every pose's interval after `n` drops at the given
/// `confidence` (eq. 7.3 solved for δ): `z/(2√n)`.
///
/// # Errors
/// [`MassError::InvalidStatistic`] for n = 0 or a confidence outside (0, 1).
pub fn worst_half_width(n: u64, confidence: f64) -> Result<f64, MassError> {
    if n == 0 {
        return Err(MassError::InvalidStatistic {
            name: "number of drops",
            reason: "no drops".into(),
        });
    }
    Ok(two_sided_z(confidence)? / (2.0 * (n as f64).sqrt()))
}

/// The Wilson score interval of a binomial proportion: `count` of `n` drops ended in a pose;
/// returns (low, high) within [0, 1]. It is the normal approximation of eq. 7.3 solved for
/// the proportion rather than evaluated at the observed one, so a pose seen 0 (or n) times
/// still gets an interval of positive width, where the plain (Wald) interval collapses to a
/// point.
///
/// # Errors
/// [`MassError::InvalidStatistic`] for n = 0, count > n or a confidence outside (0, 1).
pub fn binomial_interval(count: u64, n: u64, confidence: f64) -> Result<(f64, f64), MassError> {
    if n == 0 || count > n {
        return Err(MassError::InvalidStatistic {
            name: "counts",
            reason: format!("{count} of {n} drops"),
        });
    }
    let z = two_sided_z(confidence)?;
    let (p, n) = (count as f64 / n as f64, n as f64);
    let shrink = 1.0 + z * z / n;
    let centre = (p + z * z / (2.0 * n)) / shrink;
    let half = z / shrink * (p * (1.0 - p) / n + z * z / (4.0 * n * n)).sqrt();
    Ok(((centre - half).max(0.0), (centre + half).min(1.0)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Φ⁻¹ at points of the standard normal table (independent reference values to 16
    /// digits), and its symmetry.
    #[test]
    fn normal_quantile_matches_the_table() {
        for (p, z) in [
            (0.5, 0.0),
            (0.95, 1.644_853_626_951_472_2),
            (0.975, 1.959_963_984_540_054),
            (0.995, 2.575_829_303_548_901),
            (0.841_344_746_068_542_9, 1.0),
            (1e-6, -4.753_424_308_822_899),
        ] {
            let got = normal_quantile(p).unwrap();
            assert!(
                (got - z).abs() <= 2e-9 * z.abs().max(1.0),
                "Φ⁻¹({p}) = {got}, table {z}"
            );
            assert!((normal_quantile(1.0 - p).unwrap() + got).abs() < 1e-8);
        }
        assert!(normal_quantile(0.0).is_err());
        assert!(normal_quantile(1.0).is_err());
        assert!(normal_quantile(f64::NAN).is_err());
    }

    /// Eq. 7.3 squared: the thesis's worked example, δ = 0.05 (digest: 271 at 90 %, 385 at
    /// 95 %), and the interval it promises: (z/(2√n)) ≤ δ exactly at that n.
    #[test]
    fn sample_size_reproduces_the_thesis_example() {
        assert_eq!(sample_size(0.05, 0.90).unwrap(), 271);
        assert_eq!(sample_size(0.05, 0.95).unwrap(), 385);
        for (delta, conf) in [(0.05, 0.9), (0.01, 0.99), (0.022, 0.95)] {
            let n = sample_size(delta, conf).unwrap();
            assert!(worst_half_width(n, conf).unwrap() <= delta);
            assert!(worst_half_width(n - 1, conf).unwrap() > delta);
        }
        // 2000 drops give ±2.2 % at 95 % (digest, V23).
        let d = worst_half_width(2000, 0.95).unwrap();
        assert!((d - 0.0219).abs() < 1e-4, "{d}");
        assert!(sample_size(0.0, 0.9).is_err() && sample_size(0.05, 1.0).is_err());
    }

    /// The Wilson interval against values computed apart (Python, z = 1.959963984540054).
    #[test]
    fn binomial_interval_is_the_wilson_interval() {
        for (count, n, lo, hi) in [
            (333, 2000, 0.150_815_969_870_158, 0.183_462_700_666_437_66),
            (0, 10, 0.0, 0.277_532_799_862_889_2),
            (10, 10, 0.722_467_200_137_110_7, 1.0),
        ] {
            let (l, h) = binomial_interval(count, n, 0.95).unwrap();
            assert!(
                (l - lo).abs() < 1e-8 && (h - hi).abs() < 1e-8,
                "{count}/{n}: ({l}, {h})"
            );
        }
        assert!(binomial_interval(11, 10, 0.95).is_err());
        assert!(binomial_interval(0, 0, 0.95).is_err());
    }

    /// Eq. 7.2 on a hand-computed case; mismatched lengths are refused.
    #[test]
    fn pose_error_is_eq_7_2() {
        // p = (0.5, 0.5), a = (0.7, 0.3): 100·(0.5·0.2 + 0.5·0.2) = 20.
        assert!((pose_error(&[0.5, 0.5], &[0.7, 0.3]).unwrap() - 20.0).abs() < 1e-12);
        assert_eq!(pose_error(&[0.2, 0.8], &[0.2, 0.8]).unwrap(), 0.0);
        assert!(pose_error(&[1.0], &[0.5, 0.5]).is_err());
        assert!(pose_error(&[f64::NAN], &[0.5]).is_err());
    }
}
