//! The cached blend against the per-call one: Algorithm 3 as [`blend_rank1`], eq. 28 as
//! [`blend_poses`], and a whole blend and Algorithm 4 against the same formulas evaluated
//! from the models at every call (the form before the cache).

use faer::Mat;
use glam::DVec3;
use impulse_geom::{Pose, Twist};

use super::*;
use crate::blend::{BlendedModel, Eigen, blend_poses, blend_rank1, elastic_wrench, scaled_norm};
use crate::construct::{ConstructOptions, ReducedModel};
use crate::internal::link_twist;
use crate::linalg::{Tsvd, pinv};
use crate::mechanism::Mechanism;
use crate::reference::{Configuration, Load, StaticOptions, solve_statics};
use crate::testutil::{max_abs, rng};

/// Cached and per-call blends agree to rounding: the same sums in the same order, with the
/// matched vectors and Rayleigh quotients formed by other code (relative to the largest
/// entry; poses as the scaled norm `‖(v/r, ω/π)‖`, dimensionless). Measured: at most 1.5e-15
/// for the matrices and 1.4e-16 for the poses on the "Y" and the robot arm.
const CACHED_REL: f64 = 1e-12;

/// The internal links are placed through `K̄ ξ̄`, and `K̄` carries the rounding differences
/// of the blended compliance times its condition number (the inverses are compared at
/// [`CACHED_REL`] times that number, the first-order perturbation bound): the "Y"'s near-rigid
/// directions have compliance eigenvalues 1e-8 to 1e-6 of the largest. Scaled pose norm,
/// dimensionless; measured 4.0e-13 on the "Y", 1.3e-14 on the robot arm.
const LINKS_REL: f64 = 1e-10;

/// `σ₁ / σ_rank` of `a`.
fn condition(a: &Mat<f64>, rank: usize) -> f64 {
    let s = a.singular_values().unwrap();
    s[0] / s[rank - 1]
}

/// Models of `m` at rest and at the static equilibria under `loads` (each a list of loads).
fn models(m: &Mechanism, loads: &[Vec<Load>]) -> Vec<ReducedModel> {
    let options = ConstructOptions::default();
    let mut out = vec![ReducedModel::build(m, &Configuration::rest(m), &[], &options).unwrap()];
    for l in loads {
        let statics = StaticOptions {
            load_steps: 4,
            ..StaticOptions::default()
        };
        let sol = solve_statics(m, l, None, &statics).unwrap();
        out.push(ReducedModel::build(m, &sol.config, l, &options).unwrap());
    }
    out
}

fn load(m: &Mechanism, link: &str, force: [f64; 3]) -> Load {
    Load {
        link: m.links.iter().position(|l| l.name == link).unwrap(),
        force: DVec3::from_array(force),
        torque: DVec3::ZERO,
    }
}

/// The two test sets: the "Y" (two end effectors, 12 × 12 matrices, equal eigenvalues by
/// symmetry at rest: Procrustes on eigenspaces) and a 6-link robot arm whose rest model has
/// a lower rank than its loaded ones (rank taken from the closest model).
fn sets() -> Vec<(&'static str, Mechanism, Vec<ReducedModel>)> {
    let y = crate::scenes::y_shape(4).build().unwrap();
    let y_loads = vec![
        vec![load(&y, "a3", [100.0, 0.0, 0.0])],
        vec![
            load(&y, "a3", [250.0, 0.0, 0.0]),
            load(&y, "b3", [0.0, 50.0, 0.0]),
        ],
    ];
    let arm = crate::scenes::robot_arm(6).build().unwrap();
    let arm_loads = vec![
        vec![load(&arm, "a5", [3.0, 0.0, 0.0])],
        vec![load(&arm, "a5", [0.0, 5.0, 2.0])],
    ];
    let ym = models(&y, &y_loads);
    let am = models(&arm, &arm_loads);
    vec![("y", y, ym), ("robot-arm-6", arm, am)]
}

/// Weight vectors with model `c` the largest: random ones, and ones with zero weights (a
/// compact support).
fn weights(k: usize, c: usize, r: &mut rand::rngs::Xoshiro256PlusPlus) -> Vec<Vec<f64>> {
    use rand::RngExt;
    let mut out = Vec::new();
    for zeros in [false, true] {
        for _ in 0..3 {
            let mut a: Vec<f64> = (0..k)
                .map(|i| {
                    if zeros && i != c && i % 2 == 0 {
                        0.0
                    } else {
                        r.random_range(0.05..1.0)
                    }
                })
                .collect();
            a[c] = 1.5;
            let s: f64 = a.iter().sum();
            out.push(a.iter().map(|x| x / s).collect());
        }
    }
    out
}

fn rel(a: &Mat<f64>, b: &Mat<f64>) -> f64 {
    max_abs(&(a - b)) / max_abs(b).max(f64::MIN_POSITIVE)
}

#[test]
fn cached_algorithm_3_and_eq_28_equal_the_per_call_forms() {
    let mut r = rng(14);
    for (name, m, models) in sets() {
        let radius = m.bounding_radius();
        let dcomp: Vec<Mat<f64>> = models
            .iter()
            .map(|x| pinv(x.damping.as_ref(), Tsvd::default()).unwrap().inverse)
            .collect();
        let eig: Vec<[Eigen; 3]> = models
            .iter()
            .zip(&dcomp)
            .map(|(x, d)| {
                [
                    Eigen::new(&x.compliance).unwrap(),
                    Eigen::new(&x.accelerability).unwrap(),
                    Eigen::new(d).unwrap(),
                ]
            })
            .collect();
        let mats: Vec<[&Mat<f64>; 3]> = models
            .iter()
            .zip(&dcomp)
            .map(|(x, d)| [&x.compliance, &x.accelerability, d])
            .collect();
        let ranks: Vec<usize> = models.iter().map(|x| x.rank).collect();
        let (mut worst_mat, mut worst_pose) = (0.0_f64, 0.0_f64);
        for c in 0..models.len() {
            let cache = ClosestCache::new(c, &models, &eig, &mats);
            for alpha in weights(models.len(), c, &mut r) {
                for which in 0..3 {
                    let e: Vec<&Eigen> = eig.iter().map(|x| &x[which]).collect();
                    let a: Vec<&Mat<f64>> = mats.iter().map(|x| x[which]).collect();
                    let reference = blend_rank1(&e, &a, &alpha, models[c].rank);
                    let cached = cache.matching[which].blend(&alpha, c);
                    worst_mat = worst_mat.max(rel(&cached, &reference));
                }
                let k = models.len();
                let pose_err = |cached: Pose, reference: Pose| {
                    scaled_norm(&(reference.inverse() * cached).log(), radius)
                };
                for e in 0..models[0].reference.len() {
                    let poses: Vec<Pose> = models.iter().map(|x| x.reference[e]).collect();
                    let cached = blend_pose(
                        &models[c].reference[e],
                        &cache.ee_logs[e * k..(e + 1) * k],
                        &alpha,
                        c,
                    );
                    worst_pose = worst_pose.max(pose_err(cached, blend_poses(&poses, &alpha)));
                }
                for l in 0..models[0].internal.len() {
                    let poses: Vec<Pose> = models.iter().map(|x| x.internal_reference[l]).collect();
                    let cached = blend_pose(
                        &models[c].internal_reference[l],
                        &cache.link_logs[l * k..(l + 1) * k],
                        &alpha,
                        c,
                    );
                    worst_pose = worst_pose.max(pose_err(cached, blend_poses(&poses, &alpha)));
                }
            }
        }
        println!("{name} (ranks {ranks:?}): matrices {worst_mat:.1e}, poses {worst_pose:.1e}");
        assert!(worst_mat <= CACHED_REL, "{name}: matrices {worst_mat:e}");
        assert!(worst_pose <= CACHED_REL, "{name}: poses {worst_pose:e}");
    }
}

/// What [`per_call`] returns: (blended matrix, inverse) for compliance, accelerability and
/// damping compliance, the blend's rank (its admissible directions), `H̄_e` and the internal
/// links.
type PerCall = ([(Mat<f64>, Mat<f64>); 3], usize, Vec<Pose>, Vec<Pose>);

/// `BlendedModel::blend` and Algorithm 4 as they were before the cache: every quantity from
/// the models at each call.
fn per_call(set: &BlendedModel, ee: &[Pose]) -> PerCall {
    let models = &set.models;
    let alpha = set.weights(ee);
    let c = (0..alpha.len())
        .max_by(|&a, &b| alpha[a].total_cmp(&alpha[b]))
        .unwrap();
    let rank = models[c].rank;
    let dcomp: Vec<Mat<f64>> = models
        .iter()
        .map(|x| pinv(x.damping.as_ref(), Tsvd::default()).unwrap().inverse)
        .collect();
    let blend = |mats: Vec<&Mat<f64>>| {
        let eigs: Vec<Eigen> = mats.iter().map(|x| Eigen::new(x).unwrap()).collect();
        let e: Vec<&Eigen> = eigs.iter().collect();
        blend_rank1(&e, &mats, &alpha, rank)
    };
    let compliance = blend(models.iter().map(|x| &x.compliance).collect());
    // The blend's admissible directions: C̄'s eigenvectors above the truncation threshold
    // (§7.5, the union of the weighted models' directions), and every inverse on them by LU:
    // B (Bᵀ X B)⁻¹ Bᵀ.
    let ec = Eigen::new(&compliance).unwrap();
    let n = compliance.nrows();
    let threshold = Tsvd::default().threshold(n, n, ec.values[0]);
    let admitted = ec.values.iter().filter(|&&x| x > threshold).count();
    let basis = Mat::from_fn(n, admitted, |i, j| ec.vectors[(i, j)]);
    let inverse = |x: &Mat<f64>| -> Mat<f64> {
        use faer::linalg::solvers::Solve;
        let r = basis.transpose() * x * &basis;
        let inv = r
            .partial_piv_lu()
            .solve(Mat::<f64>::identity(admitted, admitted));
        &basis * inv * basis.transpose()
    };
    let stiffness = inverse(&compliance);
    let mass = {
        let b = blend(models.iter().map(|x| &x.accelerability).collect());
        let i = inverse(&b);
        (b, i)
    };
    let damping = {
        let b = blend(dcomp.iter().collect());
        let i = inverse(&b);
        (b, i)
    };
    let reference: Vec<Pose> = (0..ee.len())
        .map(|e| {
            let p: Vec<Pose> = models.iter().map(|x| x.reference[e]).collect();
            blend_poses(&p, &alpha)
        })
        .collect();
    let w = elastic_wrench(ee, &reference, &stiffness);
    let links = (0..models[0].internal.len())
        .map(|l| {
            let refs: Vec<Pose> = models.iter().map(|x| x.internal_reference[l]).collect();
            let twist = models
                .iter()
                .zip(&alpha)
                .fold(Twist::ZERO, |acc, (x, a)| acc + link_twist(x, l, &w) * *a);
            blend_poses(&refs, &alpha) * Pose::exp(&twist)
        })
        .collect();
    (
        [(compliance, stiffness), mass, damping],
        admitted,
        reference,
        links,
    )
}

#[test]
fn blended_model_with_cache_equals_the_per_call_blend() {
    for (name, m, models) in sets() {
        let radius = m.bounding_radius();
        let rest: Vec<Pose> = m.end_effectors.iter().map(|&e| m.links[e].rest).collect();
        let mut set = BlendedModel::new(models.clone(), rest, radius).unwrap();
        let (mut worst_mat, mut worst_pose) = (0.0_f64, 0.0_f64);
        // The inverses' differences over their first-order bound, CACHED_REL · condition.
        let (mut worst_inv, mut worst_links) = (0.0_f64, 0.0_f64);
        for support in [None, Some(2)] {
            set.support = support;
            // End effectors near each sample and between every two.
            let mut points = Vec::new();
            for (i, a) in models.iter().enumerate() {
                for b in &models[i..] {
                    let mid: Vec<Pose> = a
                        .reference
                        .iter()
                        .zip(&b.reference)
                        .map(|(p, q)| *p * Pose::exp(&((p.inverse() * *q).log() * 0.4)))
                        .collect();
                    points.push(mid);
                }
            }
            for ee in points {
                let b = set.blend(&ee).unwrap();
                let links = set.internal_poses(&ee, &b.alpha);
                let (mats, rank, reference, links_ref) = per_call(&set, &ee);
                worst_mat = worst_mat.max(rel(&b.compliance, &mats[0].0));
                for (g, (x, r)) in [&b.stiffness, &b.mass, &b.damping].iter().zip(&mats) {
                    let bound = CACHED_REL * condition(x, rank);
                    worst_inv = worst_inv.max(rel(g, r) / bound);
                }
                let err = |g: &Pose, r: &Pose| scaled_norm(&(r.inverse() * *g).log(), radius);
                for (g, r) in b.reference.iter().zip(&reference) {
                    worst_pose = worst_pose.max(err(g, r));
                }
                for (g, r) in links.iter().zip(&links_ref) {
                    worst_links = worst_links.max(err(g, r));
                }
            }
        }
        println!(
            "{name}: blended compliance {worst_mat:.1e}, inverses {worst_inv:.1e} of their bound, \
             references {worst_pose:.1e}, internal links {worst_links:.1e}"
        );
        assert!(worst_mat <= CACHED_REL, "{name}: compliance {worst_mat:e}");
        assert!(
            worst_inv <= 1.0,
            "{name}: inverses {worst_inv:e} of their bound"
        );
        assert!(
            worst_pose <= CACHED_REL,
            "{name}: references {worst_pose:e}"
        );
        assert!(worst_links <= LINKS_REL, "{name}: links {worst_links:e}");
    }
}
