//! The accuracy study of FORK⁻¹S §8.2 / Fig. 7: relative constraint error against relative
//! end-effector displacement, for a single model and a blended set, with the full nonlinear
//! statics as the truth. Used by the tests and by `cargo xtask bench --case forks`.
//!
//! # Fig. 7: what is plotted, and why the ladder once read 0.24 (issue 14)
//!
//! §8.2 of the paper: an end effector "is displaced by applying an external force in constant
//! direction and slowly increasing the magnitude"; the error is the summed joint-attachment
//! distance over the rest bounding radius r, plotted "versus the relative displacement of the
//! end effector", `‖(v/r, ω/π)‖` of its twist. The paper runs its FORK⁻¹S simulation, so each
//! curve's abscissa is **that method's own** end-effector displacement, and the force is a
//! constant *world* direction (in the end effector's body axes it turns as the body turns).
//! For a single model the paper reports 0.1–0.15 at displacement 1, for several directions.
//!
//! Until issue 14 the study (a) loaded the single model with the force frozen in the rest
//! body frame (linear in the load) and (b) plotted its error at the load's *full-model*
//! displacement. Under a growing force the linear model and the full model part ways, so the
//! single curve was read at the wrong abscissa: at 120 N the full ladder-36 is at 0.985 but
//! the rest-frame linear model at 1.25, whence 0.24 "at 1"; on the "Y" the linear model lags
//! (0.82 when the full one is at 1.01), whence 0.085. Measured (ladder pulled along +y, out of
//! its plane; "Y" tip a3 along +x), single-model error at displacement 1:
//!
//! | load model / abscissa | ladder-36 | ladder-48 | Y |
//! |---|---|---|---|
//! | rest-frame load / full model's displacement (old) | 0.252 | 0.241 | 0.083 |
//! | rest-frame load / own displacement | 0.156 | 0.154 | 0.125 |
//! | world force / full model's displacement | 0.133 | 0.131 | 0.122 |
//! | **world force / own displacement (now, the paper's)** | **0.156** | **0.153** | **0.148** |
//!
//! The "Y" pulled in other directions (own abscissa, world force; rest-frame load in
//! brackets): +y 0.165 (0.167), (1,1,0) 0.159 (0.155), (1,0,1) and (1,1,1) not reached by
//! 1200 N (0.146, 0.155); along +z, −x and (−1,0,1) the tip does not reach displacement 1
//! below 1200 N either way. So the figure lands at 0.12–0.17 against the paper's 0.1–0.15. The ladder is the same in every out-of-plane direction (0.156): our
//! ladder is rigid in its own plane (each level's two posts are pinned to the level below at
//! both rails and to each other by the rung hinge — a three-pin triangle), so only the force's
//! out-of-plane part bends it. The remaining 4% over the band's top edge is within what the
//! paper leaves open: it gives neither the ladder's proportions, link count per level, nor
//! its joint types (ladder-48 reads 0.153), and "the rate of increase in the error is
//! dependent on the direction of the applied force" (§8.2).
//!
//! Both curves are now solved the same way, by [`blended_statics`] (the single model as a
//! set of one), so they differ only by the blending; [`Fig7Row::displacement`] keeps the full
//! model's displacement for the pose-error columns, and [`curve_at`] reads a curve at a given
//! displacement of its own.

use glam::DVec3;
use impulse_geom::Pose;

use crate::blend::{BlendedModel, blended_statics, scaled_norm};
use crate::construct::{ConstructOptions, ReducedModel};
use crate::error::Error;
use crate::mechanism::{Direction, Mechanism};
use crate::reference::kinematics::link_poses;
use crate::reference::{Configuration, Load, StaticOptions, StaticSolution, solve_statics};

/// Relative constraint error (§8.2): the distance between the two attachment points of every
/// joint (less its free translations), summed over the joints, over the bounding radius `r`.
#[must_use]
pub fn constraint_error(m: &Mechanism, poses: &[Pose]) -> f64 {
    let r = m.bounding_radius();
    m.joints
        .iter()
        .map(|j| {
            let a = poses[j.parent] * j.in_parent;
            let b = poses[j.child] * j.in_child;
            // Separation in the parent-side joint frame, free translations removed.
            let mut d = a.inverse_transform_point(b.translation);
            for (kind, axis) in &j.directions {
                if *kind == Direction::Translation {
                    d -= *axis * d.dot(*axis);
                }
            }
            d.length()
        })
        .sum::<f64>()
        / r
}

/// Poses of every link from end-effector and internal-link poses (base at rest).
#[must_use]
pub fn assemble(m: &Mechanism, model: &ReducedModel, ee: &[Pose], internal: &[Pose]) -> Vec<Pose> {
    let mut poses: Vec<Pose> = m.links.iter().map(|l| l.rest).collect();
    poses[m.base] = model.base_pose;
    for (i, &e) in model.end_effectors.iter().enumerate() {
        poses[e] = ee[i];
    }
    for (k, &l) in model.internal.iter().enumerate() {
        poses[l] = internal[k];
    }
    poses
}

/// One row of the Fig. 7 study. Each curve of the figure plots a method's constraint error
/// against *that method's own* end-effector displacement (see the crate docs, "Fig. 7").
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Fig7Row {
    /// Load magnitude (N).
    pub load: f64,
    /// Relative end-effector displacement of the full solution, `‖(v/r, ω/π)‖`.
    pub displacement: f64,
    /// Relative end-effector displacement of the single model (its own Fig. 7 abscissa).
    pub single_displacement: f64,
    /// Relative end-effector displacement of the blended set (its own Fig. 7 abscissa).
    pub blended_displacement: f64,
    /// Relative constraint error of the single (rest) model.
    pub single: f64,
    /// Relative constraint error of the blended set.
    pub blended: f64,
    /// End-effector pose error of the single model against the full solution (scaled).
    pub single_pose: f64,
    /// End-effector pose error of the blended set against the full solution (scaled).
    pub blended_pose: f64,
}

/// Settings of a Fig. 7 sweep ([`fig7`]).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Fig7Options {
    /// Construction of every model (rest and samples).
    pub construct: ConstructOptions,
    /// The full nonlinear statics (the truth, and the samples' equilibria).
    pub statics: StaticOptions,
    /// Shepard exponent p of the blended set (eq. 25); the single model does not blend.
    pub power: f64,
}

impl Default for Fig7Options {
    /// Default construction and statics, and the paper's exponent
    /// [`crate::blend::SHEPARD_POWER`].
    fn default() -> Self {
        Fig7Options {
            construct: ConstructOptions::default(),
            statics: StaticOptions::default(),
            power: crate::blend::SHEPARD_POWER,
        }
    }
}

/// A Fig. 7 sweep: a world force along `direction` at end effector `ee` (index into
/// `m.end_effectors`), magnitudes `loads` (ascending); extra models built at the full static
/// equilibria for the magnitudes `samples`, blended with exponent `settings.power`. The single model and the blended set are both
/// solved under the constant world force (it turns with the end effector in body axes, as in
/// the paper's simulation), by [`blended_statics`] — the single model as a set of one.
///
/// # Errors
/// Errors of the statics, the construction or the blending.
pub fn fig7(
    m: &Mechanism,
    ee: usize,
    direction: DVec3,
    loads: &[f64],
    samples: &[f64],
    settings: &Fig7Options,
) -> Result<(Vec<Fig7Row>, Vec<f64>), Error> {
    let (options, statics) = (&settings.construct, &settings.statics);
    let link = m.end_effectors[ee];
    let rest = Configuration::rest(m);
    let load_of = |s: f64| Load {
        link,
        force: direction * s,
        torque: DVec3::ZERO,
    };
    let statics = *statics;
    let mut models = vec![ReducedModel::build(m, &rest, &[], options)?];
    let mut warm: Option<StaticSolution> = None;
    for &s in samples {
        let sol = solve_statics(m, &[load_of(s)], warm.as_ref(), &statics)?;
        models.push(ReducedModel::build(m, &sol.config, &[load_of(s)], options)?);
        warm = Some(sol);
    }
    let rest_ee: Vec<Pose> = m.end_effectors.iter().map(|&e| m.links[e].rest).collect();
    let r = m.bounding_radius();
    let single = BlendedModel::new(vec![models[0].clone()], rest_ee.clone(), r)?;
    let mut set = BlendedModel::new(models, rest_ee.clone(), r)?;
    set.power = settings.power;
    let mut rows = Vec::new();
    let mut warm: Option<StaticSolution> = None;
    let mut start = rest_ee.clone();
    let mut single_start = rest_ee.clone();
    let ne = m.end_effectors.len();
    for &s in loads {
        let sol = solve_statics(m, &[load_of(s)], warm.as_ref(), &statics)?;
        let full = link_poses(m, &sol.config);
        // A pose's relative displacement from the end effector's rest pose, ‖(v/r, ω/π)‖.
        let own = |p: &Pose| scaled_norm(&(m.links[link].rest.inverse() * *p).log(), r);
        let displacement = own(&full[link]);

        let mut ft = vec![[0.0; 6]; ne];
        ft[ee] = [
            direction.x * s,
            direction.y * s,
            direction.z * s,
            0.0,
            0.0,
            0.0,
        ];
        // Single model, then blended: the fixed point of the statics, then Algorithm 4.
        let (see, alpha) = blended_statics(&single, &ft, &single_start)?;
        let internal = single.internal_poses(&see, &alpha);
        let sp = assemble(m, &single.models[0], &see, &internal);
        let (bee, alpha) = blended_statics(&set, &ft, &start)?;
        let internal = set.internal_poses(&bee, &alpha);
        let bp = assemble(m, &set.models[0], &bee, &internal);
        let pose_err = |p: &Pose| scaled_norm(&(full[link].inverse() * *p).log(), r);

        rows.push(Fig7Row {
            load: s,
            displacement,
            single_displacement: own(&sp[link]),
            blended_displacement: own(&bp[link]),
            single: constraint_error(m, &sp),
            blended: constraint_error(m, &bp),
            single_pose: pose_err(&sp[link]),
            blended_pose: pose_err(&bp[link]),
        });
        start = bee;
        single_start = see;
        warm = Some(sol);
    }
    Ok((rows, samples.to_vec()))
}

/// A Fig. 7 curve read at relative displacement `at`: the error `error(row)` interpolated
/// linearly between the two rows whose displacements `displacement(row)` bracket `at` (the
/// curve starts at the origin: no load, no displacement, no error); `None` when the sweep
/// does not reach `at`.
#[must_use]
pub fn curve_at(
    rows: &[Fig7Row],
    displacement: fn(&Fig7Row) -> f64,
    error: fn(&Fig7Row) -> f64,
    at: f64,
) -> Option<f64> {
    let pts: Vec<(f64, f64)> = core::iter::once((0.0, 0.0))
        .chain(rows.iter().map(|r| (displacement(r), error(r))))
        .collect();
    pts.windows(2)
        .find(|w| w[0].0 <= at && at <= w[1].0 && w[1].0 > w[0].0)
        .map(|w| w[0].1 + (at - w[0].0) / (w[1].0 - w[0].0) * (w[1].1 - w[0].1))
}

#[cfg(test)]
#[path = "study_tests.rs"]
mod tests;
