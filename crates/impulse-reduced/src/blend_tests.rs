//! Blending: exact at samples, eigenstructure kept, repeated eigenvalues (Fig. 7 is in
//! `study_tests.rs`).

use faer::Mat;
use glam::DVec3;

use super::*;
use crate::construct::ConstructOptions;
use crate::testutil::{lever, lever_angle, max_abs, rng};

/// Interpolation at a sample point and blends of equal matrices are exact to rounding.
const EXACT_REL: f64 = 1e-12;

/// Agreement of the blended statics with the lever's closed form (scaled twist norm): the
/// fixed point stops at `tol::BLEND_STATIC_TOLERANCE`.
const LEVER_TOL: f64 = 1e-9;

fn random_spd(rng: &mut rand::rngs::Xoshiro256PlusPlus, n: usize, rank: usize) -> Mat<f64> {
    use rand::RngExt;
    let a = Mat::from_fn(n, rank, |_, _| rng.random_range(-1.0..1.0));
    &a * a.transpose()
}

#[test]
fn shepard_weights_interpolate_and_sum_to_one() {
    assert_eq!(shepard_weights(&[0.3, 0.0, 2.0], 2.0), vec![0.0, 1.0, 0.0]);
    let w = shepard_weights(&[1.0, 2.0], 2.0);
    assert!((w[0] - 0.8).abs() < 1e-15 && (w[1] - 0.2).abs() < 1e-15);
    assert!((shepard_weights(&[0.1, 0.7, 3.0], 2.0).iter().sum::<f64>() - 1.0).abs() < 1e-15);
}

#[test]
fn compact_shepard_weights_are_exact_at_samples_local_and_continuous() {
    // Exact at a sample, whatever the support.
    assert_eq!(
        compact_shepard_weights(&[0.3, 0.0, 2.0, 0.1], 4.0, 2),
        vec![0.0, 1.0, 0.0, 0.0]
    );
    // Support at least the number of models: the plain eq. 25.
    assert_eq!(
        compact_shepard_weights(&[0.1, 0.7, 3.0], 2.0, 3),
        shepard_weights(&[0.1, 0.7, 3.0], 2.0)
    );
    // Two of four: the third nearest (0.5) is the cutoff; (1/d − 1/R)^p, normalised.
    let w = compact_shepard_weights(&[0.2, 0.5, 0.25, 0.9], 2.0, 2);
    let (a, b) = (
        (1.0_f64 / 0.2 - 2.0).powi(2),
        (1.0_f64 / 0.25 - 2.0).powi(2),
    );
    let expected = [a / (a + b), 0.0, b / (a + b), 0.0];
    for (x, y) in w.iter().zip(expected) {
        assert!((x - y).abs() < EXACT_REL, "{w:?}");
    }
    // Continuous where the second and third nearest swap (both at 0.4): the model leaving
    // the support has no weight just before and just after.
    for h in [1e-6, 1e-9] {
        let before = compact_shepard_weights(&[0.1, 0.4 - h, 0.4 + h, 0.9], 4.0, 2);
        let after = compact_shepard_weights(&[0.1, 0.4 + h, 0.4 - h, 0.9], 4.0, 2);
        assert!((before[0] - 1.0).abs() < 1e3 * h && (after[0] - 1.0).abs() < 1e3 * h);
        assert!(before[1] < 1e3 * h && after[2] < 1e3 * h);
    }
    // Ties for nearest at the cutoff: the tied models share.
    assert_eq!(
        compact_shepard_weights(&[0.5, 0.5, 0.5, 0.9], 4.0, 2),
        vec![1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0, 0.0]
    );
}

#[test]
fn rank1_blend_is_exact_at_samples_and_for_equal_matrices() {
    let mut rng = rng(5);
    for case in 0..100 {
        let n = 6 * (1 + case % 2);
        let rank = 1 + case % n;
        let mats: Vec<Mat<f64>> = (0..3).map(|_| random_spd(&mut rng, n, rank)).collect();
        let eigs: Vec<Eigen> = mats.iter().map(|m| Eigen::new(m).unwrap()).collect();
        let er: Vec<&Eigen> = eigs.iter().collect();
        let mr: Vec<&Mat<f64>> = mats.iter().collect();
        for i in 0..3 {
            let mut alpha = vec![0.0; 3];
            alpha[i] = 1.0;
            let b = blend_rank1(&er, &mr, &alpha, rank);
            let err = max_abs(&(&b - &mats[i])) / max_abs(&mats[i]);
            assert!(err <= EXACT_REL, "case {case}, sample {i}: {err:e}");
        }
        // The same matrix three times: any weights give it back.
        let same: Vec<&Mat<f64>> = vec![&mats[0]; 3];
        let se: Vec<&Eigen> = vec![&eigs[0]; 3];
        let b = blend_rank1(&se, &same, &[0.2, 0.5, 0.3], rank);
        assert!(max_abs(&(&b - &mats[0])) <= EXACT_REL * max_abs(&mats[0]));
    }
}

#[test]
fn rank1_blend_handles_repeated_eigenvalues() {
    // diag(3, 1, 1, 1, 2, 2) decomposed in two bases of its repeated eigenspaces: model 2's
    // eigenvectors for the triple eigenvalue are a generic 3-D rotation of model 1's. Matching
    // single vectors pairs unrelated directions; matching eigenspaces returns the matrix.
    let n = 6;
    let vals = [3.0, 2.0, 2.0, 1.0, 1.0, 1.0];
    let x = Mat::from_fn(n, n, |i, j| {
        if i == j {
            [3.0, 1.0, 1.0, 1.0, 2.0, 2.0][i]
        } else {
            0.0
        }
    });
    let e1 = Eigen::new(&x).unwrap();
    let rot = glam::DMat3::from_axis_angle(DVec3::new(0.3, 0.8, -0.5).normalize(), 1.2);
    // Model 2: the same eigenvalues; vectors for "1" rotated inside span(e1, e2, e3).
    let mut v2 = e1.vectors.clone();
    for (c, col) in (3..6).enumerate() {
        let _ = c;
        for r in 0..n {
            v2[(r, col)] = (0..3)
                .map(|k| e1.vectors[(r, 3 + k)] * rot.col(col - 3)[k])
                .sum();
        }
    }
    let e2 = Eigen {
        values: vals.to_vec(),
        vectors: v2,
    };
    for alpha in [[0.5, 0.5], [0.3, 0.7], [0.9, 0.1]] {
        let b = blend_rank1(&[&e1, &e2], &[&x, &x], &alpha, n);
        let err = max_abs(&(&b - &x));
        assert!(err <= EXACT_REL * 10.0, "{alpha:?}: {err:e}");
    }
    // Guard that the test can fail: vector-by-vector matching (most similar by |dot|, sign
    // aligned, without replacement) misses the matrix.
    let naive = {
        let mut out = Mat::<f64>::zeros(n, n);
        let mut used = [false; 6];
        for j in 0..n {
            let dot = |c: usize| {
                (0..n)
                    .map(|r| e1.vectors[(r, j)] * e2.vectors[(r, c)])
                    .sum::<f64>()
            };
            let c = (0..n)
                .filter(|&c| !used[c])
                .max_by(|&a, &b| dot(a).abs().total_cmp(&dot(b).abs()))
                .unwrap();
            used[c] = true;
            let s = dot(c).signum();
            let q = Mat::from_fn(n, 1, |r, _| {
                0.5 * e1.vectors[(r, j)] + 0.5 * s * e2.vectors[(r, c)]
            });
            let norm = (q.transpose() * &q)[(0, 0)];
            out += &q * q.transpose() * (0.5 * (e1.values[j] + e2.values[c]) / norm);
        }
        out
    };
    let naive_err = max_abs(&(&naive - &x));
    println!("repeated eigenvalues: vector-by-vector matching misses by {naive_err:.3}");
    assert!(naive_err > 1e-3);
}

#[test]
fn rank1_blend_keeps_eigenvalues_of_rotated_matrices() {
    // R(θ) diag(4, 1) R(θ)ᵀ at θ = 0 and π/5 (padded to 6×6): the blend at ½ is the same
    // ellipse turned by π/10, not the rounder element-wise average. (Beyond π/4 the "most
    // similar" eigenvector is the other one: models must be close, as the paper says.)
    let make = |theta: f64| {
        let (c, s) = (theta.cos(), theta.sin());
        let mut m = Mat::<f64>::identity(6, 6) * 0.5;
        m[(0, 0)] = 4.0 * c * c + s * s;
        m[(1, 1)] = 4.0 * s * s + c * c;
        m[(0, 1)] = 3.0 * c * s;
        m[(1, 0)] = 3.0 * c * s;
        m
    };
    let (a, b) = (make(0.0), make(core::f64::consts::PI / 5.0));
    let (ea, eb) = (Eigen::new(&a).unwrap(), Eigen::new(&b).unwrap());
    let blend = blend_rank1(&[&ea, &eb], &[&a, &b], &[0.5, 0.5], 6);
    let expect = make(core::f64::consts::PI / 10.0);
    let err = max_abs(&(&blend - &expect));
    let elementwise = max_abs(&((&a + &b) * 0.5 - &expect));
    println!("rotated blend vs R(π/10): {err:e} (element-wise average: {elementwise:.3})");
    assert!(err <= EXACT_REL * 10.0);
    assert!(elementwise > 0.05);
}

#[test]
fn blended_step_with_one_model_follows_the_single_model() {
    // One model: Algorithm 5 is the single-model step (poses by exp instead of additive ξ,
    // which agree to second order in the step's motion).
    let m = crate::scenes::robot_arm(6).build().unwrap();
    let q = crate::reference::Configuration::rest(&m);
    let model = ReducedModel::build(&m, &q, &[], &ConstructOptions::default()).unwrap();
    let rest: Vec<Pose> = model.reference.clone();
    let set = BlendedModel::new(vec![model.clone()], rest.clone(), m.bounding_radius()).unwrap();
    let mut sim = crate::dynamics::ReducedSim::new(&m, model, 1e-3).unwrap();
    sim.gravity = DVec3::ZERO;
    sim.external[0] = 2.0;
    let (mut ee, mut phi) = (rest.clone(), vec![0.0; 6]);
    let w = sim.external.clone();
    for _ in 0..200 {
        sim.step();
        set.step(&mut ee, &mut phi, &w, 1e-3).unwrap();
    }
    let d = (sim.end_effector_pose(0).inverse() * ee[0]).log();
    let size = (rest[0].inverse() * ee[0]).log();
    let rel = scaled_norm(&d, 1.0) / scaled_norm(&size, 1.0);
    println!("blended (1 model) vs single step after 200 steps: {rel:.2e} relative");
    assert!(rel < 1e-3);
}

#[test]
fn blended_statics_follows_the_equilibrium_where_plain_substitution_diverges() {
    // Loads k = c·L·F up to 3, each solve started from the last: θ* = 1.170 at k = 3. The
    // plain substitution θ ← k cos θ has slope k sin θ* > 1 from k ≈ 1.4 on, so it oscillates
    // away (or lands on the wound-back equilibrium near θ = −2.9); the relaxed iteration must
    // stay on the branch through θ = 0.
    let (c, length) = (1.0, 1.0);
    let m = lever(c, length);
    let model = ReducedModel::build(
        &m,
        &crate::reference::Configuration::rest(&m),
        &[],
        &ConstructOptions::default(),
    )
    .unwrap();
    let rest = vec![m.links[m.end_effectors[0]].rest];
    let set = BlendedModel::new(vec![model], rest.clone(), m.bounding_radius()).unwrap();
    let mut start = rest.clone();
    for step in 1..=12 {
        let force = 0.25 * f64::from(step);
        let (ee, _) = blended_statics(&set, &[[0.0, force, 0.0, 0.0, 0.0, 0.0]], &start)
            .unwrap_or_else(|e| panic!("k = {force}: {e}"));
        let theta = lever_angle(c * length * force);
        let exact = Pose::exp(&Twist::new(DVec3::ZERO, DVec3::Z * theta)) * rest[0];
        let err = scaled_norm(&(exact.inverse() * ee[0]).log(), 1.0);
        println!("k = {force}: θ* = {theta:.12}, pose error {err:.2e}");
        assert!(err < LEVER_TOL, "k = {force}: pose error {err:.2e}");
        start = ee;
    }
}

/// Internal links of a one-model blend against the single model's eq. 22 kernel
/// (`internal::update_internal_links`, folded `T K` and its own exponential): the blend forms
/// `K̄` from the eigen-decomposition of the compliance instead of using `K`, so the two agree
/// to rounding (scaled pose difference, dimensionless). Measured 1.4e-16 on the 6-link robot
/// arm.
const ONE_MODEL_LINKS_TOL: f64 = 1e-12;

#[test]
fn blended_internal_links_of_one_model_are_the_single_models_and_bad_weights_are_an_error() {
    let m = crate::scenes::robot_arm(6).build().unwrap();
    let q = crate::reference::Configuration::rest(&m);
    let model = ReducedModel::build(&m, &q, &[], &ConstructOptions::default()).unwrap();
    let rest = model.reference.clone();
    let r = m.bounding_radius();
    let set = BlendedModel::new(vec![model.clone()], rest.clone(), r).unwrap();
    let xi = Twist::new(
        DVec3::new(0.01, -0.02, 0.005),
        DVec3::new(0.03, 0.01, -0.02),
    );
    let ee = vec![rest[0] * Pose::exp(&xi)];
    let mut single = vec![Pose::IDENTITY; model.internal.len()];
    crate::internal::update_internal_links(&model, &xi.to_array(), &Pose::IDENTITY, &mut single);
    // Before any blend (K̄ formed here), after one (K̄ reused), and from the blend itself.
    let fresh = set.try_internal_poses(&ee, &[1.0]).unwrap();
    let b = set.blend(&ee).unwrap();
    let reused = set.internal_poses(&ee, &b.alpha);
    let of = set.internal_poses_of(&ee, &b);
    let worst = single
        .iter()
        .zip(&fresh)
        .map(|(s, f)| scaled_norm(&(s.inverse() * *f).log(), r))
        .fold(0.0, f64::max);
    println!("one-model blend vs single model, internal links: {worst:.2e}");
    assert!(worst < ONE_MODEL_LINKS_TOL, "{worst:e}");
    assert_eq!(fresh, reused);
    assert_eq!(fresh, of);
    // One weight per model, or an error (not a panic).
    assert!(matches!(
        set.try_internal_poses(&ee, &[0.5, 0.5]),
        Err(Error::Argument(_))
    ));
}

/// Steps of the rank-changing blend test (h = 1 ms): the arm's end effector crosses from
/// the rest model's neighbourhood into the loaded models' within ~20 and swings for a few
/// hundred.
const RANK_CHANGE_STEPS: usize = 300;

/// Sample counts of the rank-changing blend test (samples evenly up to 4 N).
const RANK_CHANGE_COUNTS: [usize; 4] = [1, 2, 4, 8];

/// Largest ratio of the blend's error with eight samples to its error with one: the blend
/// converges to the full model as the samples get closer (measured 0.22: first order, the
/// reduced dynamics' own error is first order in the displacement between samples).
const RANK_CHANGE_CONVERGENCE: f64 = 0.3;

#[test]
fn blended_step_across_a_rank_change_converges_as_samples_are_added() {
    // The straight arm at rest has rank 4 (it can neither stretch nor twist about itself),
    // bent under a sideways force rank 6. Until the blend held the directions the closest
    // model lacks (§7.5, the other models' part there blended linearly) and inverted its
    // matrices on the union of the weighted models' directions, the end effector was kicked
    // when the closest model's rank changed: with two samples the blend was 3.3 times worse
    // than the rest model alone (8.99e-4 against 2.72e-4). Reference: the full nonlinear
    // dynamics under the same force.
    use crate::reference::{Configuration, FullOptions, FullSim, Load, StaticOptions};
    let m = crate::scenes::robot_arm(6).build().unwrap();
    let e = m.end_effectors[0];
    let options = ConstructOptions::default();
    let rest = vec![m.links[e].rest];
    let r = m.bounding_radius();
    let h = 1e-3;
    let mut full = FullSim::new(&m, h, FullOptions::default()).unwrap();
    full.gravity = DVec3::ZERO;
    // 1 N along x, held in the end effector's rest frame (body frame = world at rest).
    full.loads = vec![Load {
        link: e,
        force: rest[0].transform_vector(DVec3::X),
        torque: DVec3::ZERO,
    }];
    let truth: Vec<Pose> = (0..RANK_CHANGE_STEPS)
        .map(|_| {
            full.step().unwrap();
            full.poses()[e]
        })
        .collect();
    let w = [1.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    let error = |models: Vec<ReducedModel>| -> (f64, f64) {
        let mut set = BlendedModel::new(models, rest.clone(), r).unwrap();
        set.power = crate::study::FIG7_SHEPARD_POWER;
        set.support = crate::study::FIG7_SUPPORT;
        let (mut ee, mut phi) = (rest.clone(), vec![0.0; 6]);
        let (mut worst, mut far) = (0.0_f64, 0.0_f64);
        for pf in &truth {
            let b = set.step(&mut ee, &mut phi, &w, h).unwrap();
            worst = worst.max(scaled_norm(&(pf.inverse() * ee[0]).log(), r));
            far = far.max(1.0 - b.alpha[0]);
        }
        (worst, far)
    };
    let rest_model = ReducedModel::build(&m, &Configuration::rest(&m), &[], &options).unwrap();
    let (single, _) = error(vec![rest_model.clone()]);
    let mut errors = Vec::new();
    for n in RANK_CHANGE_COUNTS {
        let mut models = vec![rest_model.clone()];
        for k in 1..=n {
            let load = Load {
                link: e,
                force: DVec3::new(4.0 * k as f64 / n as f64, 0.0, 0.0),
                torque: DVec3::ZERO,
            };
            let sol = crate::reference::solve_statics(&m, &[load], None, &StaticOptions::default())
                .unwrap();
            models.push(ReducedModel::build(&m, &sol.config, &[load], &options).unwrap());
        }
        assert!(models[0].rank < models[1].rank, "no rank change to test");
        let (worst, far) = error(models);
        println!(
            "{n} samples: EE error against the full dynamics {worst:.3e} (rest model alone {single:.3e}); largest weight off the rest model {far:.2}"
        );
        errors.push((worst, far));
    }
    // With the most samples the swing is carried by the loaded models, across the rank change.
    assert!(
        errors[3].1 > 0.5,
        "the blend never left the rest model ({errors:?})"
    );
    assert!(errors[0].0 <= single, "{errors:?} against {single:e}");
    for pair in errors.windows(2) {
        assert!(pair[1].0 <= pair[0].0, "not converging: {errors:?}");
    }
    assert!(
        errors[3].0 <= RANK_CHANGE_CONVERGENCE * errors[0].0,
        "{errors:?}"
    );
}
