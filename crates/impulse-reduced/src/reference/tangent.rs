//! The equations of the full statics and their exact Newton tangent (second-order
//! kinematics), both from the joints' spatial screws.
//!
//! **Equations** (see [`crate::reference::statics`]): with every joint coordinate θ and one
//! multiplier wrench λ_k per loop joint,
//!
//! `f(θ, λ) = −K_q θ + s·Σ_loads J_lᵀ(θ) w_l(θ) + Σ_k G_kᵀ(θ) λ_k = 0`,  `r_k(θ) = 0`,
//!
//! s the load fraction of the continuation. Both sums are generalized forces of world wrenches
//! `W` (about the world origin) through the **spatial screws** `s_i = Ad_{F_j} Ŝ_i(θ_j)` of
//! the joint coordinates i they act through (`F_j` the joint's frame moved by the joint, `Ŝ_i`
//! its body column, [`joint_jacobian`]): `Q_i = ±⟨s_i, W⟩`. A load on link l is
//! `W = s·(f, τ + p_l × f)` through the tree joints from l to the base; a loop multiplier is
//! `W = Ad_{a⁻¹}ᵀ λ_k` (the wrench λ_k held in the loop joint's parent-side frame
//! `a = H_p P E(θ)`) through the child's path with `+`, the parent's path and the loop joint's
//! own columns with `−` — an identity with `G_kᵀ λ_k` for [`loop_jacobian`]'s `G_k` at any θ.
//!
//! **Tangent.** `∂Q_i/∂θ_m = ±(⟨∂s_i/∂θ_m, W⟩ + ⟨s_i, ∂W/∂θ_m⟩)` with
//! - `∂s_i/∂θ_m = ad_{s_m} s_i` when m belongs to a joint between joint i and the base (it
//!   carries joint i's frame rigidly), `Ad_{F_j}(ad_{Ŝ_m} Ŝ_i + ∂Ŝ_i/∂θ_m)` when m is another
//!   (or the same) direction of joint i's own joint, zero otherwise;
//! - a load: `∂W/∂θ_m = s·(0, ṗ_l × f)` with `ṗ_l = v_m + ω_m × p_l` the velocity of the
//!   load's point under `s_m = (v_m, ω_m)`, for m on the load's path;
//! - a loop multiplier (a wrench fixed in the moving frame a): `∂W/∂θ_m = s_m ×* W =
//!   −ad_{s_m}ᵀ W`, for m on the parent's path or the loop joint's own directions;
//! - `∂Ŝ/∂θ` of a joint's own columns: a translation column `(Rᵀa, 0)` turns with the joint's
//!   rotation, `(Rᵀa) × (J_r(φ) b)` per unit of a rotation direction b; a rotation column
//!   `(0, J_r(φ) a)` changes by `(0, DJ_r(φ)[b] a)` ([`right_jacobian_derivative`]); hinges
//!   and sliders have constant columns.
//!
//! The λ-columns are `Gᵀ` exactly; the closure rows take `G_k` ([`loop_jacobian`]), the exact
//! derivative of `r_k` where the loop is closed (off closure it differs by O(|r_k|), which keeps
//! Newton quadratic). The tests check every block against central differences.

use faer::Mat;
use glam::DVec3;
use impulse_geom::{Pose, Twist, Wrench};

use crate::mechanism::{Direction, Joint, Mechanism};
use crate::reference::kinematics::{Configuration, joint_jacobian, joint_motion, link_poses};
use crate::reference::statics::Load;
use crate::tol;

/// `DJ_r(φ)[b]·a`: the change of `J_r(φ)·a` ([`impulse_geom::pose::so3_right_jacobian`]) per
/// unit change of the rotation vector φ along `b`. With `J_r(φ)a = a − A φ×a + B φ×(φ×a)`,
/// `A = (1 − cos t)/t²`, `B = (t − sin t)/t³`, t = |φ|:
/// `−(A′/t)(φ·b) φ×a − A b×a + (B′/t)(φ·b) φ×(φ×a) + B (b×(φ×a) + φ×(b×a))`.
#[must_use]
pub fn right_jacobian_derivative(phi: DVec3, b: DVec3, a: DVec3) -> DVec3 {
    let t2 = phi.length_squared();
    let (ca, cb, dca, dcb) = if t2 < tol::DJR_SERIES_ANGLE * tol::DJR_SERIES_ANGLE {
        let t4 = t2 * t2;
        let t6 = t4 * t2;
        (
            0.5 - t2 / 24.0 + t4 / 720.0 - t6 / 40320.0,
            1.0 / 6.0 - t2 / 120.0 + t4 / 5040.0 - t6 / 362_880.0,
            -1.0 / 12.0 + t2 / 180.0 - t4 / 6720.0 + t6 / 453_600.0,
            -1.0 / 60.0 + t2 / 1260.0 - t4 / 60480.0 + t6 / 4_989_600.0,
        )
    } else {
        let t = t2.sqrt();
        let (s, c) = t.sin_cos();
        let t4 = t2 * t2;
        (
            (1.0 - c) / t2,
            (t - s) / (t2 * t),
            (t * s - 2.0 * (1.0 - c)) / t4,
            ((1.0 - c) * t - 3.0 * (t - s)) / (t4 * t),
        )
    };
    let pb = phi.dot(b);
    let pa = phi.cross(a);
    -pa * (dca * pb) - b.cross(a) * ca
        + phi.cross(pa) * (dcb * pb)
        + (b.cross(pa) + phi.cross(b.cross(a))) * cb
}

/// `∂Ŝ_k/∂θ_m` of a joint's own body columns at its coordinates `theta`: `[k][m]`.
fn column_derivatives(joint: &Joint, theta: &[f64]) -> Vec<Vec<Twist>> {
    let phi: DVec3 = joint
        .directions
        .iter()
        .zip(theta)
        .filter(|((d, _), _)| *d == Direction::Rotation)
        .map(|((_, a), q)| *a * *q)
        .sum();
    let rt = glam::DMat3::from_quat(impulse_geom::se3::so3_exp(phi)).transpose();
    let jr = impulse_geom::pose::so3_right_jacobian(phi);
    joint
        .directions
        .iter()
        .map(|(dk, ak)| {
            joint
                .directions
                .iter()
                .map(|(dm, am)| match (dk, dm) {
                    (_, Direction::Translation) => Twist::ZERO,
                    (Direction::Translation, Direction::Rotation) => {
                        Twist::new((rt * *ak).cross(jr * *am), DVec3::ZERO)
                    }
                    (Direction::Rotation, Direction::Rotation) => {
                        Twist::new(DVec3::ZERO, right_jacobian_derivative(phi, *am, *ak))
                    }
                })
                .collect()
        })
        .collect()
}

/// The tree joints from link `l` to the base, nearest first.
fn path(m: &Mechanism, mut l: usize) -> Vec<usize> {
    let mut out = Vec::new();
    while let Some(j) = m.tree_joint[l] {
        out.push(j);
        l = m.joints[j].parent;
    }
    out
}

/// Per-mechanism data of the evaluations: every link's path to the base.
pub(crate) struct Topology {
    /// Tree joints from each link to the base, nearest first.
    paths: Vec<Vec<usize>>,
}

impl Topology {
    /// The paths of `m`.
    pub(crate) fn new(m: &Mechanism) -> Self {
        Topology {
            paths: (0..m.links.len()).map(|l| path(m, l)).collect(),
        }
    }
}

/// One evaluation of the statics at (θ, λ, s).
pub(crate) struct Evaluation {
    /// `f` (ndof rows) then `r` (6 per loop joint).
    pub values: Vec<f64>,
    /// The Newton tangent `∂(f, r)/∂(θ, λ)`, when asked for.
    pub tangent: Option<Mat<f64>>,
    /// Largest magnitude of a spring force or a load's generalized force (the scale of the
    /// force rows' relative test).
    pub force_scale: f64,
}

/// A world wrench acting through joint coordinates: loads and loop multipliers.
struct Application {
    /// The wrench (world, about the origin).
    wrench: Wrench,
    /// Joints it acts through, each with its sign.
    rows: Vec<(usize, f64)>,
    /// How the wrench moves with θ.
    motion: WrenchMotion,
}

enum WrenchMotion {
    /// A world-fixed force `force` (already scaled) at the moving point `point`, moved by the
    /// tree joints `path`.
    Load {
        point: DVec3,
        force: DVec3,
        path: Vec<usize>,
    },
    /// Fixed in a frame moved by the joints `movers` (the parent's path, then the loop joint).
    Frame { movers: Vec<usize> },
}

/// Evaluates the statics of `m` at configuration `q`, multipliers `lambda` (6 per loop joint,
/// parent-side joint frame), under `loads` scaled by `scale`; with the tangent if `tangent`.
pub(crate) fn evaluate(
    m: &Mechanism,
    topo: &Topology,
    q: &Configuration,
    lambda: &[f64],
    loads: &[Load],
    scale: f64,
    tangent: bool,
) -> Evaluation {
    let poses = link_poses(m, q);
    let n = m.ndof;
    let nl = m.loop_joints.len();
    // Every joint's moved frame F_j = H_p P E(θ_j), body columns and spatial screws.
    let frames: Vec<Pose> = m
        .joints
        .iter()
        .map(|j| {
            let th = &q.theta[j.offset..j.offset + j.dof()];
            poses[j.parent] * j.in_parent * joint_motion(j, th)
        })
        .collect();
    let local: Vec<Vec<Twist>> = m
        .joints
        .iter()
        .map(|j| joint_jacobian(j, &q.theta[j.offset..j.offset + j.dof()]))
        .collect();
    let screws: Vec<Vec<Twist>> = local
        .iter()
        .zip(&frames)
        .map(|(cols, f)| cols.iter().map(|c| f.transform_twist(c)).collect())
        .collect();

    let mut values = vec![0.0; n + 6 * nl];
    let mut force_scale = 0.0_f64;
    for j in &m.joints {
        for (k, c) in j.compliance.iter().enumerate() {
            let t = -q.theta[j.offset + k] / c;
            values[j.offset + k] = t;
            force_scale = force_scale.max(t.abs());
        }
    }

    let mut apps: Vec<Application> = Vec::with_capacity(loads.len() + nl);
    for load in loads {
        let p = poses[load.link].translation;
        let f = load.force * scale;
        apps.push(Application {
            wrench: Wrench::new(f, load.torque * scale + p.cross(f)),
            rows: topo.paths[load.link].iter().map(|&j| (j, 1.0)).collect(),
            motion: WrenchMotion::Load {
                point: p,
                force: f,
                path: topo.paths[load.link].clone(),
            },
        });
    }
    // Loads first: their generalized forces set the force scale.
    let mut generalized = vec![0.0; n];
    for app in &apps {
        for &(j, sign) in &app.rows {
            for (k, s) in screws[j].iter().enumerate() {
                generalized[m.joints[j].offset + k] += sign * app.wrench.power(s);
            }
        }
    }
    for (v, g) in values.iter_mut().zip(&generalized) {
        *v += g;
        force_scale = force_scale.max(g.abs());
    }
    for (k, &ji) in m.loop_joints.iter().enumerate() {
        let j = &m.joints[ji];
        let l = Wrench::from_array(core::array::from_fn(|r| lambda[6 * k + r]));
        let mut rows: Vec<(usize, f64)> = topo.paths[j.child].iter().map(|&x| (x, 1.0)).collect();
        rows.extend(topo.paths[j.parent].iter().map(|&x| (x, -1.0)));
        rows.push((ji, -1.0));
        let mut movers = topo.paths[j.parent].clone();
        movers.push(ji);
        // λ_k held in frame a, in world form: Ad_a⁻ᵀ λ_k.
        let wrench = frames[ji].transform_wrench(&l);
        for &(jr, sign) in &rows {
            for (c, s) in screws[jr].iter().enumerate() {
                values[m.joints[jr].offset + c] += sign * wrench.power(s);
            }
        }
        // Closure r_k = log((H_p P E)⁻¹ H_c Q).
        let r = (frames[ji].inverse() * (poses[j.child] * j.in_child))
            .log()
            .to_array();
        values[n + 6 * k..n + 6 * k + 6].copy_from_slice(&r);
        apps.push(Application {
            wrench,
            rows,
            motion: WrenchMotion::Frame { movers },
        });
    }

    let tangent = tangent.then(|| {
        let dim = n + 6 * nl;
        let mut t = Mat::<f64>::zeros(dim, dim);
        for j in &m.joints {
            for (k, c) in j.compliance.iter().enumerate() {
                t[(j.offset + k, j.offset + k)] = -1.0 / c;
            }
        }
        let derivs: Vec<Vec<Vec<Twist>>> = m
            .joints
            .iter()
            .map(|j| column_derivatives(j, &q.theta[j.offset..j.offset + j.dof()]))
            .collect();
        for app in &apps {
            add_application(m, topo, &screws, &local, &frames, &derivs, app, &mut t);
        }
        // λ-columns: Gᵀ; closure rows: G. Column i of G_k is Ad_{a⁻¹}(±s_i).
        for (k, &ji) in m.loop_joints.iter().enumerate() {
            let j = &m.joints[ji];
            let inv = frames[ji].inverse();
            let mut add = |jr: usize, sign: f64| {
                for (c, s) in screws[jr].iter().enumerate() {
                    let g = inv.transform_twist(s).to_array();
                    let col = m.joints[jr].offset + c;
                    for (r, x) in g.iter().enumerate() {
                        t[(n + 6 * k + r, col)] += sign * x;
                        t[(col, n + 6 * k + r)] += sign * x;
                    }
                }
            };
            for &x in &topo.paths[j.child] {
                add(x, 1.0);
            }
            for &x in &topo.paths[j.parent] {
                add(x, -1.0);
            }
            add(ji, -1.0);
        }
        t
    });
    Evaluation {
        values,
        tangent,
        force_scale,
    }
}

/// Adds one application's second-order terms `∂(±⟨s_i, W⟩)/∂θ_m` to the θθ block of `t`.
#[allow(clippy::too_many_arguments)]
fn add_application(
    m: &Mechanism,
    topo: &Topology,
    screws: &[Vec<Twist>],
    local: &[Vec<Twist>],
    frames: &[Pose],
    derivs: &[Vec<Vec<Twist>>],
    app: &Application,
    t: &mut Mat<f64>,
) {
    let w = &app.wrench;
    // ∂W/∂θ_m for the coordinates that move the wrench.
    let moves: Vec<(usize, Wrench)> = match &app.motion {
        WrenchMotion::Load { point, force, path } => path
            .iter()
            .flat_map(|&j| {
                screws[j].iter().enumerate().map(move |(k, s)| {
                    let pdot = s.v + s.w.cross(*point);
                    (
                        m.joints[j].offset + k,
                        Wrench::new(DVec3::ZERO, pdot.cross(*force)),
                    )
                })
            })
            .collect(),
        WrenchMotion::Frame { movers } => movers
            .iter()
            .flat_map(|&j| {
                screws[j]
                    .iter()
                    .enumerate()
                    .map(move |(k, s)| (m.joints[j].offset + k, s.cross_force(w)))
            })
            .collect(),
    };
    for &(j, sign) in &app.rows {
        let joint = &m.joints[j];
        // The joints that carry joint j's frame: those between it and the base.
        let carriers = &topo.paths[joint.parent];
        for (k, s) in screws[j].iter().enumerate() {
            let row = joint.offset + k;
            for &jm in carriers {
                for (km, sm) in screws[jm].iter().enumerate() {
                    t[(row, m.joints[jm].offset + km)] += sign * w.power(&sm.cross_motion(s));
                }
            }
            for (km, sk) in local[j].iter().enumerate() {
                let d = sk.cross_motion(&local[j][k]) + derivs[j][k][km];
                t[(row, joint.offset + km)] += sign * w.power(&frames[j].transform_twist(&d));
            }
            for (col, dw) in &moves {
                t[(row, *col)] += sign * dw.power(s);
            }
        }
    }
}

#[cfg(test)]
#[path = "tangent_tests.rs"]
mod tests;
