//! A study's summary per pose: the quasi-static, perturbed and dynamic estimates side by
//! side, and the belt-fed estimate's limit (see the module documentation of
//! [`crate::poses`]).

use impulse_massprops::stats;
use serde::Serialize;

use super::PosePart;
use super::study::DropOutcome;
use crate::SimError;

/// The belt-fed estimate's repeated squaring of the chain stops when a squaring changes no
/// entry by more than this. Default `1e-15`.
const BELT_FED_TOLERANCE: f64 = 1e-15;

/// Most squarings of the belt-fed chain: 2⁶⁰ steps, the limit for any chain that leaves a
/// pose at all (a part that never leaves one keeps its share). Default `60`.
const BELT_FED_SQUARINGS: usize = 60;

/// One pose's line of a study's summary: a class of stable facets the part cannot tell
/// apart ([`impulse_massprops::PoseAnalysis::classes`]: the six faces of a cube are one
/// pose), every share summed over its facets.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PoseRow {
    /// Pose number, 1 for the most likely by the quasi-static estimate.
    pub pose: usize,
    /// The hull faces of the class.
    pub facets: Vec<u32>,
    /// The first facet's outward normal in the part's own frame (points down at rest).
    pub normal: [f64; 3],
    /// Quasi-static estimate (eq. 7.1).
    pub quasi_static: f64,
    /// Perturbed quasi-static estimate.
    pub perturbed: f64,
    /// Drops started uniform on SO(3) that came to rest on one of these facets.
    pub uniform_count: u64,
    /// Their fraction of the uniform drops: the dynamic estimate for a uniformly random
    /// start (what the quasi-static estimates assume).
    pub uniform: f64,
    /// The binomial interval of [`Self::uniform`] (low, high).
    pub interval: (f64, f64),
    /// The belt-fed dynamic estimate: the long-run share of this pose when each drop starts
    /// from a rest pose drawn from the final poses so far (the thesis's feedback of final
    /// poses to initial ones), from the transition frequencies of the belt drops.
    pub belt_fed: Option<f64>,
}

/// A study's summary: a row per stable pose, the drops that did not settle on one, and the
/// belt drops' transition frequencies.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PoseSummary {
    /// The rows, most likely first (quasi-static).
    pub rows: Vec<PoseRow>,
    /// Drops summarised.
    pub drops: u64,
    /// Of those, drops started uniform on SO(3).
    pub uniform_drops: u64,
    /// Drops not at rest within the time limit.
    pub unsettled: u64,
    /// Drops at rest but not on a facet (within [`super::FACET_ANGLE`]).
    pub unclassified: u64,
    /// Confidence level of the intervals.
    pub confidence: f64,
    /// Worst-case half-width of the uniform drops' intervals (eq. 7.3).
    pub half_width: Option<f64>,
    /// `(a, b, n)`: `n` belt drops started on stable facet `stable[a]` ended on `stable[b]`
    /// (facets, not classes: the belt-fed chain runs between facets); the pairs with drops
    /// only, sorted (a hull of 10⁴ facets has 10⁸ pairs).
    pub transitions: Vec<(usize, usize, u64)>,
    /// The stable facets indexing [`Self::transitions`].
    pub stable: Vec<u32>,
}

/// Summarises `outcomes` of `part`: per stable facet the quasi-static and perturbed
/// estimates (cone half-angle `cone`, rad), the uniform drops' frequency with its interval at
/// `confidence`, and the belt-fed estimate.
///
/// The belt-fed estimate is the thesis's feedback loop run to its limit: with T the belt
/// drops' transition frequencies between stable poses (row a: where drops started at rest
/// on pose a ended), it is lim P₀·T'ᵏ for the lazy chain T' = (I + T)/2 (same long-run
/// shares as T, without periodicity), P₀ the uniform drops' distribution (the quasi-static
/// estimate if there are none). For a chain that can reach every pose from every other this
/// is T's unique stationary distribution, whatever P₀; a pose whose belt drops never leave
/// it keeps the share that reaches it. `None` without belt drops.
///
/// # Errors
/// [`SimError::Invalid`] for no outcomes, a cone outside [0, π/2), a confidence outside
/// (0, 1), or an outcome naming a facet that is not a stable facet of the part (a file of
/// another part).
pub fn summarize(
    part: &PosePart,
    outcomes: &[DropOutcome],
    cone: f64,
    confidence: f64,
) -> Result<PoseSummary, SimError> {
    let bad = |field: &str, problem: String| SimError::Invalid {
        what: "pose summary".into(),
        field: field.into(),
        problem,
    };
    if outcomes.is_empty() {
        return Err(bad("outcomes", "no drops to summarise".into()));
    }
    if !(confidence > 0.0 && confidence < 1.0) {
        return Err(bad("confidence", format!("{confidence} is not in (0, 1)")));
    }
    let qs = part.analysis.quasi_static();
    let pqs = part
        .analysis
        .perturbed_quasi_static(cone)
        .map_err(|e| bad("cone", e.to_string()))?;
    let stable = part.analysis.stable();
    // Each facet's row among the stable ones.
    let mut rows_of = vec![None; stable.iter().map(|&f| f as usize + 1).max().unwrap_or(0)];
    for (k, &f) in stable.iter().enumerate() {
        rows_of[f as usize] = Some(k);
    }
    let row_of = |f: u32, index: u64| {
        rows_of.get(f as usize).copied().flatten().ok_or_else(|| {
            bad(
                "outcomes",
                format!(
                    "drop {index}: facet {f} is not a stable facet of {}",
                    part.name
                ),
            )
        })
    };
    let m = stable.len();
    let mut uniform_counts = vec![0u64; m];
    let mut transitions: std::collections::BTreeMap<(usize, usize), u64> =
        std::collections::BTreeMap::new();
    let (mut uniform_drops, mut unsettled, mut unclassified) = (0u64, 0u64, 0u64);
    for o in outcomes {
        let end = o.facet.map(|f| row_of(f, o.index)).transpose()?;
        match (o.start, end) {
            (None, Some(b)) => uniform_counts[b] += 1,
            (Some(a), Some(b)) => *transitions.entry((row_of(a, o.index)?, b)).or_insert(0) += 1,
            (_, None) if !o.settled => unsettled += 1,
            (_, None) => unclassified += 1,
        }
        if o.start.is_none() {
            uniform_drops += 1;
        }
    }
    let half_width = (uniform_drops > 0)
        .then(|| stats::worst_half_width(uniform_drops, confidence))
        .transpose()
        .map_err(|e| bad("confidence", e.to_string()))?;
    let transitions: Vec<(usize, usize, u64)> = transitions
        .into_iter()
        .map(|((a, b), n)| (a, b, n))
        .collect();
    let belt = (!transitions.is_empty()).then(|| {
        // The uniform drops that came to rest on a stable facet (unsettled ones carry no
        // pose into the loop).
        let classified: u64 = uniform_counts.iter().sum();
        let start: Vec<f64> = if classified > 0 {
            uniform_counts
                .iter()
                .map(|&c| c as f64 / classified as f64)
                .collect()
        } else {
            stable.iter().map(|&f| qs[f as usize]).collect()
        };
        belt_fed_limit(m, &transitions, start)
    });
    let mut classes = part.analysis.classes();
    let share = |c: &[u32]| c.iter().map(|&f| qs[f as usize]).sum::<f64>();
    classes.sort_by(|a, b| share(b).total_cmp(&share(a)).then(a[0].cmp(&b[0])));
    let rows = classes
        .into_iter()
        .enumerate()
        .map(|(k, facets)| {
            let at = |f: u32| rows_of.get(f as usize).copied().flatten().unwrap_or(0);
            let count: u64 = facets.iter().map(|&f| uniform_counts[at(f)]).sum();
            let (uniform, interval) = if uniform_drops > 0 {
                (
                    count as f64 / uniform_drops as f64,
                    stats::binomial_interval(count, uniform_drops, confidence)
                        .map_err(|e| bad("confidence", e.to_string()))?,
                )
            } else {
                (f64::NAN, (f64::NAN, f64::NAN))
            };
            Ok(PoseRow {
                pose: k + 1,
                normal: part.normal_in_part_frame(facets[0]).to_array(),
                quasi_static: share(&facets),
                perturbed: facets.iter().map(|&f| pqs[f as usize]).sum(),
                uniform_count: count,
                uniform,
                interval,
                belt_fed: belt
                    .as_ref()
                    .map(|p| facets.iter().map(|&f| p[at(f)]).sum()),
                facets,
            })
        })
        .collect::<Result<_, SimError>>()?;
    Ok(PoseSummary {
        rows,
        drops: outcomes.len() as u64,
        uniform_drops,
        unsettled,
        unclassified,
        confidence,
        half_width,
        transitions,
        stable,
    })
}

/// The long-run distribution of the lazy chain (I + T)/2 from `p` (see [`summarize`]); a row
/// with no drops keeps its share.
///
/// Only the facets the belt drops touched move any share: a facet no drop started from is
/// absorbing (its row is the identity), and one no drop started from or ended on neither
/// gives nor receives. The chain is squared on those facets alone, O(k³) for the k facets the
/// drops touched, whatever the hull's facet count (on all m facets it was O(m³) a squaring and
/// m² numbers: a hull of 20 480 facets took 6.6 GB and more than 13 minutes).
pub(super) fn belt_fed_limit(m: usize, counts: &[(usize, usize, u64)], p: Vec<f64>) -> Vec<f64> {
    let mut touched: Vec<usize> = counts.iter().flat_map(|&(a, b, _)| [a, b]).collect();
    touched.sort_unstable();
    touched.dedup();
    debug_assert!(touched.last().is_none_or(|&f| f < m));
    let k = touched.len();
    let place = |f: usize| touched.binary_search(&f).expect("a touched facet");
    // Each touched facet's drops, and where they ended.
    let mut count = vec![vec![0u64; k]; k];
    for &(a, b, n) in counts {
        count[place(a)][place(b)] += n;
    }
    let t: Vec<Vec<f64>> = count
        .iter()
        .enumerate()
        .map(|(a, row)| {
            let n: u64 = row.iter().sum();
            (0..k)
                .map(|b| {
                    let stay = if a == b { 0.5 } else { 0.0 };
                    if n == 0 {
                        2.0 * stay
                    } else {
                        stay + 0.5 * row[b] as f64 / n as f64
                    }
                })
                .collect()
        })
        .collect();
    // The limit of p·T'ᵏ by repeated squaring: after j squarings T' stands for 2^j steps.
    let mut t = t;
    for _ in 0..BELT_FED_SQUARINGS {
        let next: Vec<Vec<f64>> = (0..k)
            .map(|a| {
                (0..k)
                    .map(|b| (0..k).map(|j| t[a][j] * t[j][b]).sum())
                    .collect()
            })
            .collect();
        let change = next
            .iter()
            .zip(&t)
            .flat_map(|(x, y)| x.iter().zip(y).map(|(u, v)| (u - v).abs()))
            .fold(0.0, f64::max);
        t = next;
        if change < BELT_FED_TOLERANCE {
            break;
        }
    }
    let mut limit = p.clone();
    for (jb, &b) in touched.iter().enumerate() {
        limit[b] = touched
            .iter()
            .enumerate()
            .map(|(ja, &a)| p[a] * t[ja][jb])
            .sum();
    }
    limit
}
