//! The accuracy study of FORK⁻¹S §8.2 / Fig. 7: relative constraint error against relative
//! end-effector displacement, for a single model and a blended set, with the full nonlinear
//! statics as the truth. Used by the tests and by `cargo xtask bench --case forks`.

use glam::DVec3;
use impulse_geom::{Pose, Twist, Wrench};

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

/// Single-model static poses of every link under stacked body wrenches `w` (rest frames).
#[must_use]
pub fn single_model_poses(m: &Mechanism, model: &ReducedModel, w: &[f64]) -> Vec<Pose> {
    let (ee, internal) = model.static_twists(w);
    let ee: Vec<Pose> = ee
        .iter()
        .zip(&model.reference)
        .map(|(t, h)| *h * Pose::exp(t))
        .collect();
    let internal: Vec<Pose> = internal
        .iter()
        .zip(&model.internal_reference)
        .map(|(t, h)| *h * Pose::exp(t))
        .collect();
    assemble(m, model, &ee, &internal)
}

/// One row of the Fig. 7 study.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Fig7Row {
    /// Load magnitude (N).
    pub load: f64,
    /// Relative end-effector displacement of the full solution, `‖(v/r, ω/π)‖`.
    pub displacement: f64,
    /// Relative constraint error of the single (rest) model.
    pub single: f64,
    /// Relative constraint error of the blended set.
    pub blended: f64,
    /// End-effector pose error of the single model against the full solution (scaled).
    pub single_pose: f64,
    /// End-effector pose error of the blended set against the full solution (scaled).
    pub blended_pose: f64,
}

/// A Fig. 7 sweep: a world force along `direction` at end effector `ee` (index into
/// `m.end_effectors`), magnitudes `loads` (ascending); extra models built at the full static
/// equilibria for the magnitudes `samples`.
///
/// # Errors
/// Errors of the statics, the construction or the blending.
pub fn fig7(
    m: &Mechanism,
    ee: usize,
    direction: DVec3,
    loads: &[f64],
    samples: &[f64],
    options: &ConstructOptions,
    statics: &StaticOptions,
) -> Result<(Vec<Fig7Row>, Vec<f64>), Error> {
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
    let single = models[0].clone();
    let set = BlendedModel::new(models, rest_ee.clone(), r)?;
    let mut rows = Vec::new();
    let mut warm: Option<StaticSolution> = None;
    let mut start = rest_ee.clone();
    let ne = m.end_effectors.len();
    for &s in loads {
        let sol = solve_statics(m, &[load_of(s)], warm.as_ref(), &statics)?;
        let full = link_poses(m, &sol.config);
        let displacement = scaled_norm(&(m.links[link].rest.inverse() * full[link]).log(), r);
        // Single model: linear in the load, body wrench at the rest orientation.
        let mut w = vec![0.0; 6 * ne];
        let wb = Wrench::new(
            m.links[link].rest.inverse_transform_vector(direction * s),
            DVec3::ZERO,
        )
        .to_array();
        w[6 * ee..6 * ee + 6].copy_from_slice(&wb);
        let sp = single_model_poses(m, &single, &w);
        // Blended: the fixed point of the blended statics, then Algorithm 4.
        let mut ft = vec![[0.0; 6]; ne];
        ft[ee] = [
            direction.x * s,
            direction.y * s,
            direction.z * s,
            0.0,
            0.0,
            0.0,
        ];
        let (bee, alpha) = blended_statics(&set, &ft, &start)?;
        let internal = set.internal_poses(&bee, &alpha);
        let bp = assemble(m, &set.models[0], &bee, &internal);
        let pose_err = |p: &Pose| scaled_norm(&(full[link].inverse() * *p).log(), r);
        rows.push(Fig7Row {
            load: s,
            displacement,
            single: constraint_error(m, &sp),
            blended: constraint_error(m, &bp),
            single_pose: pose_err(&sp[link]),
            blended_pose: pose_err(&bp[link]),
        });
        start = bee;
        warm = Some(sol);
    }
    let _ = Twist::ZERO;
    Ok((rows, samples.to_vec()))
}
