//! What a bowling study found: mean pins felled against the pin-line crossing, in bins
//! (thesis Fig. 7.10), and over bands of crossings with their standard errors.

use serde::{Deserialize, Serialize};

use super::throw::{ThrowKind, ThrowOutcome};

/// Width of a bin of pin-line crossings (m): thesis Fig. 7.10 averages over 5 mm.
pub const BIN_WIDTH: f64 = 0.005;

/// A window this small a fraction of a bin past a whole number of bins gets no extra bin
/// (the window's width / bin width is rounded, not exact, in binary).
const BIN_ROUNDING: f64 = 1e-9;

/// The pocket of a right-hander (m of crossing): between the head pin and the 3 pin, where
/// the thesis found the hook clearly better, "+6 to +12 cm".
pub const POCKET: (f64, f64) = (0.06, 0.12);

/// Crossings within this distance of the head pin's centre (m) hit it dead on, the dip of
/// Fig. 7.10 (splits).
pub const HEAD_ON: f64 = 0.015;

/// The dip is compared with crossings this far from the head pin's centre, either side
/// (m): the shoulders of the dip.
pub const SHOULDERS: (f64, f64) = (0.03, 0.09);

/// The mean of a sample of pin counts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Mean {
    /// Number of throws.
    pub n: u64,
    /// Mean pins felled (NaN for no throws).
    pub mean: f64,
    /// Standard error of the mean: sample standard deviation over √n (NaN below 2 throws).
    pub se: f64,
}

impl Mean {
    /// The mean and standard error of `values`.
    pub fn of(values: impl IntoIterator<Item = f64>) -> Self {
        let v: Vec<f64> = values.into_iter().collect();
        let n = v.len();
        if n == 0 {
            return Self {
                n: 0,
                mean: f64::NAN,
                se: f64::NAN,
            };
        }
        let mean = v.iter().sum::<f64>() / n as f64;
        let se = if n < 2 {
            f64::NAN
        } else {
            let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
            (var / n as f64).sqrt()
        };
        Self {
            n: n as u64,
            mean,
            se,
        }
    }

    /// `self.mean − other.mean` in units of the standard error of the difference (Welch):
    /// above 2, a difference larger than two standard errors. NaN when that error is zero
    /// or unknown (fewer than 2 throws on a side, or no spread at all).
    pub fn z_over(&self, other: &Mean) -> f64 {
        let se = (self.se.powi(2) + other.se.powi(2)).sqrt();
        if se.is_finite() && se > 0.0 {
            (self.mean - other.mean) / se
        } else {
            f64::NAN
        }
    }
}

/// One bin of crossings with each kind's mean.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct BinRow {
    /// The bin's lower edge (m).
    pub lo: f64,
    /// The bin's upper edge (m).
    pub hi: f64,
    /// The straight throws crossing in the bin.
    pub straight: Mean,
    /// The hooking throws crossing in the bin.
    pub hook: Mean,
}

/// The mean pins felled by throws of `kind` crossing the pin line in `[lo, hi)`; with
/// `mirror`, also those crossing in `(−hi, −lo]`.
pub fn band(outcomes: &[ThrowOutcome], kind: ThrowKind, lo: f64, hi: f64, mirror: bool) -> Mean {
    Mean::of(
        outcomes
            .iter()
            .filter(|o| o.kind == kind)
            .filter(|o| {
                o.crossing
                    .is_some_and(|x| (lo..hi).contains(&x) || (mirror && (lo..hi).contains(&-x)))
            })
            .map(|o| f64::from(o.felled)),
    )
}

/// Most bins [`bins`] makes: a window of more is refused as empty.
pub const MAX_BINS: f64 = 1e6;

/// Bins of `width` over `[lo, hi)` with each kind's mean (the last bin ends at `hi`); none
/// for an empty or non-finite window, or one of more than [`MAX_BINS`] bins.
pub fn bins(outcomes: &[ThrowOutcome], lo: f64, hi: f64, width: f64) -> Vec<BinRow> {
    let count = ((hi - lo) / width - BIN_ROUNDING).ceil();
    if !(count.is_finite() && (1.0..=MAX_BINS).contains(&count)) {
        return Vec::new();
    }
    let n = count as usize;
    (0..n)
        .map(|k| {
            let (a, b) = (lo + k as f64 * width, (lo + (k + 1) as f64 * width).min(hi));
            BinRow {
                lo: a,
                hi: b,
                straight: band(outcomes, ThrowKind::Straight, a, b, false),
                hook: band(outcomes, ThrowKind::Hook, a, b, false),
            }
        })
        .collect()
}

/// The bins as CSV: `lo_m,hi_m,straight_n,straight_mean,hook_n,hook_mean` (an empty bin's
/// mean is empty).
pub fn to_csv(rows: &[BinRow]) -> String {
    let mean = |m: &Mean| {
        if m.n == 0 {
            String::new()
        } else {
            format!("{}", m.mean)
        }
    };
    let mut s = String::from("lo_m,hi_m,straight_n,straight_mean,hook_n,hook_mean\n");
    for r in rows {
        s.push_str(&format!(
            "{:.4},{:.4},{},{},{},{}\n",
            r.lo,
            r.hi,
            r.straight.n,
            mean(&r.straight),
            r.hook.n,
            mean(&r.hook)
        ));
    }
    s
}

/// A study's headline figures: the pocket (hook against straight) and the head-on dip
/// (each kind against its shoulders).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BowlingSummary {
    /// Straight throws crossing in [`POCKET`].
    pub pocket_straight: Mean,
    /// Hooking throws crossing in [`POCKET`].
    pub pocket_hook: Mean,
    /// Straight throws within [`HEAD_ON`] of the head pin's centre.
    pub head_on_straight: Mean,
    /// Hooking throws within [`HEAD_ON`].
    pub head_on_hook: Mean,
    /// Straight throws crossing in [`SHOULDERS`] on either side.
    pub shoulders_straight: Mean,
    /// Hooking throws crossing in [`SHOULDERS`] on either side.
    pub shoulders_hook: Mean,
    /// Each kind's mean over its throws that crossed within the window (straight, hook).
    pub all: (Mean, Mean),
    /// Throws whose ball crossed the pin line outside the window (in a gutter, mostly).
    pub outside: u64,
    /// Throws whose ball never crossed the pin line.
    pub no_crossing: u64,
    /// Throws that crossed but were stopped at the settle time with something still moving
    /// on the deck (in the means, counted as the pins stood).
    pub unsettled: u64,
}

/// The headline figures of `outcomes` whose throws were aimed across `window` (lo, hi).
pub fn summarize(outcomes: &[ThrowOutcome], window: (f64, f64)) -> BowlingSummary {
    let b = |kind, lo, hi, mirror| band(outcomes, kind, lo, hi, mirror);
    use ThrowKind::{Hook, Straight};
    BowlingSummary {
        pocket_straight: b(Straight, POCKET.0, POCKET.1, false),
        pocket_hook: b(Hook, POCKET.0, POCKET.1, false),
        head_on_straight: b(Straight, -HEAD_ON, HEAD_ON, false),
        head_on_hook: b(Hook, -HEAD_ON, HEAD_ON, false),
        shoulders_straight: b(Straight, SHOULDERS.0, SHOULDERS.1, true),
        shoulders_hook: b(Hook, SHOULDERS.0, SHOULDERS.1, true),
        all: (
            b(Straight, window.0, window.1, false),
            b(Hook, window.0, window.1, false),
        ),
        outside: outcomes
            .iter()
            .filter(|o| {
                o.crossing
                    .is_some_and(|x| !(window.0..window.1).contains(&x))
            })
            .count() as u64,
        no_crossing: outcomes.iter().filter(|o| o.crossing.is_none()).count() as u64,
        unsettled: outcomes
            .iter()
            .filter(|o| o.crossing.is_some() && !o.settled)
            .count() as u64,
    }
}
