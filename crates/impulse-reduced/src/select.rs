//! Beyond the paper (§7.5, §8.1 "future work"): automatic choice of linearisation points.
//!
//! Given candidate load cases (a world force and torque on every end effector), the set starts
//! from the rest model and greedily adds a model built at the full static equilibrium of the
//! candidate whose blended relative constraint error (§8.2) is largest, until every candidate
//! is under the threshold or the model budget is spent. Judging a candidate needs only the
//! blended model (its statics and Algorithm 4), not the full solution; the full statics are
//! solved only for the chosen candidates.

use crate::blend::{BlendedModel, blended_statics};
use crate::construct::{ConstructOptions, ReducedModel};
use crate::error::Error;
use crate::mechanism::Mechanism;
use crate::reference::{Configuration, Load, StaticOptions, solve_statics};
use crate::study::{assemble, constraint_error};

/// A load case: per end effector, world force then world torque.
pub type LoadCase = Vec<[f64; 6]>;

/// The outcome of [`select_models`].
pub struct Selection {
    /// The blended set (rest model first, then the chosen ones in order).
    pub set: BlendedModel,
    /// Indices of the chosen candidates, in the order they were added.
    pub chosen: Vec<usize>,
    /// The blended relative constraint error of every candidate with the final set.
    pub error_map: Vec<f64>,
    /// The largest candidate error after each addition (first entry: rest model only).
    pub history: Vec<f64>,
    /// Whether every candidate ended under the threshold.
    pub converged: bool,
}

fn loads_of(m: &Mechanism, case: &LoadCase) -> Vec<Load> {
    m.end_effectors
        .iter()
        .zip(case)
        .map(|(&link, ft)| Load {
            link,
            force: glam::DVec3::new(ft[0], ft[1], ft[2]),
            torque: glam::DVec3::new(ft[3], ft[4], ft[5]),
        })
        .collect()
}

/// The blended relative constraint error of `set` under load `case` (static).
///
/// # Errors
/// Errors of [`blended_statics`].
pub fn blended_error(m: &Mechanism, set: &BlendedModel, case: &LoadCase) -> Result<f64, Error> {
    let start: Vec<_> = set.models[0].reference.clone();
    let (ee, alpha) = blended_statics(set, case, &start)?;
    let internal = set.try_internal_poses(&ee, &alpha)?;
    Ok(constraint_error(
        m,
        &assemble(m, &set.models[0], &ee, &internal),
    ))
}

/// Greedy selection (see the module doc) with Shepard exponent `power` for the set (the
/// paper's p = 2 keeps too much weight on far models once they surround the rest pose; 4–6
/// localises the blend).
///
/// # Errors
/// Errors of the statics, the construction or the blending.
pub fn select_models(
    m: &Mechanism,
    candidates: &[LoadCase],
    threshold: f64,
    max_models: usize,
    power: f64,
    options: &ConstructOptions,
) -> Result<Selection, Error> {
    let rest_ee: Vec<_> = m.end_effectors.iter().map(|&e| m.links[e].rest).collect();
    let r = m.bounding_radius();
    let mut models = vec![ReducedModel::build(
        m,
        &Configuration::rest(m),
        &[],
        options,
    )?];
    let mut chosen = Vec::new();
    let mut history = Vec::new();
    let statics = StaticOptions {
        load_steps: 8,
        ..StaticOptions::default()
    };
    loop {
        let mut set = BlendedModel::new(models.clone(), rest_ee.clone(), r)?;
        set.power = power;
        let errors = candidates
            .iter()
            .map(|c| blended_error(m, &set, c))
            .collect::<Result<Vec<f64>, Error>>()?;
        let (worst, &emax) = errors
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))
            .unwrap_or((0, &0.0));
        history.push(emax);
        let converged = emax <= threshold;
        if converged || models.len() >= max_models || chosen.contains(&worst) {
            return Ok(Selection {
                set,
                chosen,
                error_map: errors,
                history,
                converged,
            });
        }
        let loads = loads_of(m, &candidates[worst]);
        let sol = solve_statics(m, &loads, None, &statics)?;
        models.push(ReducedModel::build(m, &sol.config, &loads, options)?);
        chosen.push(worst);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::RngExt;

    #[test]
    fn selection_meets_threshold_on_candidates_and_held_out_loads() {
        let m = crate::scenes::y_shape(4).build().unwrap();
        // Candidates: a force on the first arm's tip, in the plane of the Y, six directions ×
        // three magnitudes.
        let mut candidates = Vec::new();
        for k in 0..6 {
            let a = core::f64::consts::PI * k as f64 / 3.0;
            for s in [100.0, 200.0, 300.0] {
                candidates.push(vec![
                    [s * a.cos(), 0.0, s * a.sin(), 0.0, 0.0, 0.0],
                    [0.0; 6],
                ]);
            }
        }
        let threshold = SELECT_THRESHOLD;
        let sel = select_models(
            &m,
            &candidates,
            threshold,
            12,
            POWER,
            &ConstructOptions::default(),
        )
        .unwrap();
        println!(
            "selection: {} models added (candidates {:?}); max error after each: {:?}",
            sel.chosen.len(),
            sel.chosen,
            sel.history
        );
        assert!(sel.converged, "{:?}", sel.history);
        assert!(sel.error_map.iter().all(|&e| e <= threshold));
        // Held-out: random in-plane loads inside the candidate range.
        let mut rng = crate::testutil::rng(99);
        let mut worst = 0.0_f64;
        for _ in 0..10 {
            let a = rng.random_range(0.0..2.0 * core::f64::consts::PI);
            let s = rng.random_range(50.0..300.0);
            let case = vec![[s * a.cos(), 0.0, s * a.sin(), 0.0, 0.0, 0.0], [0.0; 6]];
            worst = worst.max(blended_error(&m, &sel.set, &case).unwrap());
        }
        println!("held-out: worst blended constraint error {worst:.3e} (threshold {threshold:e})");
        assert!(worst <= threshold * HELD_OUT_MARGIN);
    }

    /// Shepard exponent of the test's selection. With the paper's p = 2 the greedy set (10
    /// models) meets the threshold on the candidates but a held-out load reaches 1.6e-2: far
    /// models keep too much weight between samples; p = 4 needs 7 models (held-out 3.3e-3),
    /// p = 6 needs 4 (held-out 1.9e-3).
    const POWER: f64 = 6.0;
    /// Threshold of the test's selection (relative constraint error).
    const SELECT_THRESHOLD: f64 = 5e-3;
    /// Held-out loads fall between the candidates, where the blend is least accurate: they
    /// must stay within this factor of the threshold.
    const HELD_OUT_MARGIN: f64 = 1.0;
}
