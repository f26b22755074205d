//! Convergence of a blended set to the full model as linearisation points are added (§7),
//! across the rank change at rest of Fig. 7's mechanisms: the straight "Y" cannot stretch its
//! two arms apart along one combined direction (rank 11 of 12 at rest, 12 loaded), the flat
//! ladder cannot stretch along its rails when pulled out of its plane (rank 2 at rest, 3
//! loaded), a straight robot arm neither stretch nor twist about itself (rank 4, then 6).
//!
//! A sweep takes `N` samples evenly spaced up to a largest load (`max · k/N`, k = 1 … N; the
//! rest model is always in the set), solves the blended statics ([`crate::blend::blended_statics`], the
//! study's Shepard exponent and support) at the midpoint of every span between neighbouring
//! samples — the span from rest to the first sample included, where the rank changes — and
//! compares with the full nonlinear statics there. Evenly spaced samples make the spans
//! shrink as 1/N, so a blend that interpolates between its samples converges: the constraint
//! error and the absolute end-effector error as 1/N² (interpolation of smooth functions
//! between samples), the end-effector error relative to the displacement as 1/N (the span
//! from rest, where the displacement is itself O(1/N)). The Fig. 7 figures of docs/forks.md
//! come from [`static_convergence`].

use glam::DVec3;
use impulse_geom::Pose;

use crate::blend::{BlendedModel, scaled_norm};
use crate::error::Error;
use crate::mechanism::Mechanism;
use crate::reference::kinematics::link_poses;
use crate::reference::{Load, StaticSolution, solve_statics};
use crate::study::{Fig7Options, sample_models, set_errors};

/// One row of a convergence sweep: the set of `points` samples (and the rest model).
#[derive(Clone, Debug, PartialEq)]
pub struct ConvergenceRow {
    /// Samples besides the rest model.
    pub points: usize,
    /// The rest model's rank and the largest sample rank.
    pub ranks: (usize, usize),
    /// Largest end-effector pose error against the full statics, `‖(v/r, ω/π)‖` of
    /// `log(H_full⁻¹ H)`, over the midpoints.
    pub pose: f64,
    /// Largest of the same relative to the full solution's end-effector displacement.
    pub relative_pose: f64,
    /// Largest relative constraint error (§8.2) over the midpoints.
    pub constraint: f64,
    /// The load (N) of the largest relative pose error.
    pub worst_load: f64,
}

/// A convergence sweep of `m` under a world force along `direction` on end effector `ee`
/// (index into `m.end_effectors`) for every sample count in `counts`, samples evenly up to
/// `max_load` (N); the blend as `settings` (the Fig. 7 study's exponent and support by
/// default). See the module doc.
///
/// # Errors
/// Errors of the statics, the construction or the blending.
pub fn static_convergence(
    m: &Mechanism,
    ee: usize,
    direction: DVec3,
    max_load: f64,
    counts: &[usize],
    settings: &Fig7Options,
) -> Result<Vec<ConvergenceRow>, Error> {
    let link = m.end_effectors[ee];
    let r = m.bounding_radius();
    let rest: Vec<Pose> = m.end_effectors.iter().map(|&e| m.links[e].rest).collect();
    let mut rows = Vec::with_capacity(counts.len());
    for &n in counts {
        let samples: Vec<f64> = (1..=n).map(|k| max_load * k as f64 / n as f64).collect();
        let models = sample_models(m, ee, direction, &samples, settings)?;
        let ranks = (
            models[0].rank,
            models[1..].iter().map(|x| x.rank).max().unwrap_or(0),
        );
        let mut set = BlendedModel::new(models, rest.clone(), r)?;
        set.power = settings.power;
        set.support = settings.support;
        let mut row = ConvergenceRow {
            points: n,
            ranks,
            pose: 0.0,
            relative_pose: 0.0,
            constraint: 0.0,
            worst_load: 0.0,
        };
        let (mut start, mut warm): (Vec<Pose>, Option<StaticSolution>) = (rest.clone(), None);
        let mut low = 0.0;
        for &s in &samples {
            let load = 0.5 * (low + s);
            low = s;
            let full = solve_statics(
                m,
                &[Load {
                    link,
                    force: direction * load,
                    torque: DVec3::ZERO,
                }],
                warm.as_ref(),
                &settings.statics,
            )?;
            let poses = link_poses(m, &full.config);
            let (errors, at) = set_errors(m, &set, ee, direction, load, &poses, &start)?;
            let displacement = scaled_norm(&(m.links[link].rest.inverse() * poses[link]).log(), r);
            let relative = errors.end_effectors / displacement.max(f64::MIN_POSITIVE);
            if relative > row.relative_pose {
                row.relative_pose = relative;
                row.worst_load = load;
            }
            row.pose = row.pose.max(errors.end_effectors);
            row.constraint = row.constraint.max(errors.constraint);
            start = at;
            warm = Some(full);
        }
        rows.push(row);
    }
    Ok(rows)
}

#[cfg(test)]
#[path = "convergence_tests.rs"]
mod tests;
