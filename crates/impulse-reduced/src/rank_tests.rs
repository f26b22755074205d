//! Rank decisions and conditioning against an independent computation: the near-singular
//! family of three ball joints nearly on one line, whose end-effector motions at rest are
//! written here directly from the anchors (rotations about three points), independent of the
//! crate's Jacobians and walk.

use faer::Mat;
use glam::DVec3;
use rand::RngExt;

use super::*;
use crate::construct::{ConstructOptions, ReducedModel};
use crate::desc::{JointDesc, LinkDesc, MechanismDesc};
use crate::reference::Configuration;
use crate::testutil::{random_direction, rng};

/// Rounding of a walk of a few links, in units of ε times the largest compliance: the
/// compliance C is a sum of a few congruences, each rounding to a few ε of its size.
const WALK_ROUNDING: f64 = 64.0;

/// Relative agreement of the same singular value from two routes (W's squared against the
/// crate's report of it): both are accurate to ε over the value's gap, ~1e-10 here.
const SVD_AGREEMENT: f64 = 1e-6;

/// Relative agreement of a compliance at the walk's round-off (5e-16 of the largest) between
/// the walk's C and W's square: its own size is of the round-off, so half of it.
const ROUND_OFF_AGREEMENT: f64 = 0.5;

/// A three-link chain of ball joints at `0`, `(0, 0, 0.1)` and `(0, 0, 0.2) + offset`, its
/// third link (frame at `(0, 0, 0.25)`) the end effector; compliances `c`.
fn chain(offset: DVec3, c: [f64; 3]) -> MechanismDesc {
    let mut d = MechanismDesc::new("near-aligned");
    d.link(LinkDesc::new("base", [0.0; 3]));
    for (i, z) in [0.05, 0.15, 0.25].iter().enumerate() {
        d.link(LinkDesc::new(&format!("l{}", i + 1), [0.0, 0.0, *z]).mass(0.1, [1e-4, 1e-4, 1e-5]));
    }
    let anchors = [
        DVec3::ZERO,
        DVec3::new(0.0, 0.0, 0.1),
        DVec3::new(0.0, 0.0, 0.2) + offset,
    ];
    for (i, p) in anchors.iter().enumerate() {
        let parent = if i == 0 {
            "base".to_owned()
        } else {
            format!("l{i}")
        };
        d.joint(
            JointDesc::ball(
                &format!("j{i}"),
                &parent,
                &format!("l{}", i + 1),
                p.to_array(),
            )
            .compliance(&[c[i]]),
        );
    }
    d.end_effector("l3");
    d
}

/// The weighted motions `W` of [`chain`] at rest, written from the anchors: the end effector's
/// body frame is the world's axes at `o = (0, 0, 0.25)`, and a rotation about world axis `e`
/// through anchor `p` moves it with the body twist `(e × (o − p), e)`, times `√c`.
fn weighted_motions(offset: DVec3, c: [f64; 3]) -> Mat<f64> {
    let o = DVec3::new(0.0, 0.0, 0.25);
    let anchors = [
        DVec3::ZERO,
        DVec3::new(0.0, 0.0, 0.1),
        DVec3::new(0.0, 0.0, 0.2) + offset,
    ];
    let mut w = Mat::<f64>::zeros(6, 9);
    for (j, p) in anchors.iter().enumerate() {
        for (k, e) in [DVec3::X, DVec3::Y, DVec3::Z].iter().enumerate() {
            let v = e.cross(o - *p);
            let col = [v.x, v.y, v.z, e.x, e.y, e.z];
            for r in 0..6 {
                w[(r, 3 * j + k)] = col[r] * c[j].sqrt();
            }
        }
    }
    w
}

/// Singular values (descending) and left singular vectors of `a`.
fn svd(a: &Mat<f64>) -> (Vec<f64>, Mat<f64>) {
    let s = a.svd().unwrap();
    let mut idx: Vec<usize> = (0..a.nrows().min(a.ncols())).collect();
    idx.sort_by(|&i, &j| s.S()[j].total_cmp(&s.S()[i]));
    let u = Mat::from_fn(a.nrows(), idx.len(), |r, k| s.U()[(r, idx[k])]);
    (idx.iter().map(|&i| s.S()[i]).collect(), u)
}

/// The family: offsets from 1e-2 to 1e-9 m in random directions, compliances over two
/// decades. At the default threshold the rank is the independent count of W's singular
/// values above √τ of the largest (6 for the larger offsets, 5 below ~1e-6 m); every dropped
/// direction is reported with its compliance `(σ₆/σ₁)²` and its direction (W's singular
/// vector, to the angle the conditioning allows); C equals `W Wᵀ` to the walk's rounding; the
/// kept part of K inverts the kept part of `W Wᵀ` to `cond · rounding`.
#[test]
fn near_aligned_chains_build_at_the_independent_rank_and_report_what_they_drop() {
    let mut rng = rng(71);
    let mut seen = [0usize; 7];
    for case in 0..40 {
        let size = 10f64.powf(-2.0 - 7.0 * case as f64 / 39.0);
        let offset = random_direction(&mut rng) * size;
        let c: [f64; 3] = core::array::from_fn(|_| 10f64.powf(rng.random_range(-4.0..-2.0)));
        let m = chain(offset, c).build().unwrap();
        let model = ReducedModel::build(
            &m,
            &Configuration::rest(&m),
            &[],
            &ConstructOptions::default(),
        )
        .unwrap_or_else(|e| panic!("case {case} (offset {size:e}): {e}"));
        let w = weighted_motions(offset, c);
        let (s, u) = svd(&w);
        let tau = Tsvd::default().relative_threshold(6, 6);
        let want = s.iter().filter(|&&x| (x / s[0]).powi(2) > tau).count();
        assert_eq!(model.rank, want, "case {case} (offset {size:e}): {s:?}");
        seen[want] += 1;
        let d = &model.diagnostics;
        assert_eq!(
            d.allowed, 6,
            "case {case}: three balls off one line allow six directions"
        );
        assert_eq!(d.dropped.len(), 6 - want);
        for (k, x) in d.dropped.iter().enumerate() {
            let i = want + k;
            let rel = (s[i] / s[0]).powi(2);
            assert!(
                (x.compliance / rel - 1.0).abs() < SVD_AGREEMENT,
                "case {case}: dropped compliance {} vs {rel}",
                x.compliance
            );
            let dot: f64 = (0..6).map(|r| x.twist[r] * u[(r, i)]).sum();
            // The direction is W's singular vector up to sign, to round-off over its gap.
            let gap = s[i - 1] / s[0];
            assert!(
                1.0 - dot.abs() < WALK_ROUNDING * f64::EPSILON / gap.powi(2),
                "case {case}: direction off by {}",
                1.0 - dot.abs()
            );
        }
        if want < 6 {
            assert!(
                d.warnings
                    .iter()
                    .any(|x| matches!(x, RankWarning::NearSingular { allowed: 6, .. })),
                "case {case}: {:?}",
                d.warnings
            );
        }
        // C = W Wᵀ to the walk's rounding.
        let reference = &w * w.transpose();
        let sigma1 = s[0] * s[0];
        let err = crate::linalg::max_abs((&model.compliance - &reference).as_ref());
        assert!(
            err <= WALK_ROUNDING * f64::EPSILON * sigma1,
            "case {case}: C off by {err:e} of {sigma1:e}"
        );
        // K = (W Wᵀ)⁺ restricted to the kept directions, to cond(C) times the rounding.
        let mut kref = Mat::<f64>::zeros(6, 6);
        for i in 0..want {
            for a in 0..6 {
                for b in 0..6 {
                    kref[(a, b)] += u[(a, i)] * u[(b, i)] / (s[i] * s[i]);
                }
            }
        }
        let cond = sigma1 / (s[want - 1] * s[want - 1]);
        let kerr = crate::linalg::max_abs((&model.stiffness - &kref).as_ref())
            / crate::linalg::max_abs(kref.as_ref());
        assert!(
            kerr <= WALK_ROUNDING * f64::EPSILON * cond,
            "case {case}: K off by {kerr:e} (cond {cond:e})"
        );
        assert!((d.conditioning.compliance_condition / cond - 1.0).abs() < SVD_AGREEMENT);
    }
    assert!(seen[5] > 5 && seen[6] > 5, "both ranks met: {seen:?}");
}

/// A threshold below what the walk resolves is refused, naming the direction's compliance;
/// one above it drops the direction instead.
#[test]
fn a_threshold_below_round_off_is_refused() {
    let offset = DVec3::new(1e-7, 0.0, 0.0);
    let m = chain(offset, [1e-3; 3]).build().unwrap();
    let q = Configuration::rest(&m);
    let options = |tau: f64| ConstructOptions {
        tsvd: Tsvd::with_relative(tau).unwrap(),
        ..ConstructOptions::default()
    };
    let err = ReducedModel::build(&m, &q, &[], &options(1e-17)).unwrap_err();
    let Error::Unresolved {
        rank, compliance, ..
    } = err
    else {
        panic!("{err}");
    };
    let (s, _) = svd(&weighted_motions(offset, [1e-3; 3]));
    assert_eq!(rank, 6);
    assert!(
        (compliance / (s[5] / s[0]).powi(2) - 1.0).abs() < ROUND_OFF_AGREEMENT,
        "{compliance:e}"
    );
    let model = ReducedModel::build(&m, &q, &[], &options(1e-12)).unwrap();
    assert_eq!((model.rank, model.diagnostics.allowed), (5, 6));
}

#[test]
fn relative_thresholds_are_checked() {
    for bad in [0.0, -1.0, 1.0, 2.0, f64::NAN, f64::INFINITY] {
        assert!(
            matches!(Tsvd::with_relative(bad), Err(Error::OutOfRange { .. })),
            "{bad}"
        );
    }
    let t = Tsvd::with_relative(1e-9).unwrap();
    assert_eq!(t.relative_threshold(6, 6), 1e-9);
    assert_eq!(t.threshold(6, 6, 2.0), 2e-9);
    // The default is eq. 9 times the factor.
    let d = Tsvd::default();
    assert_eq!(
        d.relative_threshold(6, 9),
        crate::tol::TSVD_FACTOR * 9.0 * f64::EPSILON
    );
}

/// A stiff slider whose compliance sits 1e-4 below the soft directions: dropping it with
/// `τ = 1e-3` leaves no clear gap at the cut (σ₆/σ₅ ≈ 1e-3 > `RANK_GAP`), and the model warns.
#[test]
fn a_cut_without_a_gap_warns() {
    let mut d = MechanismDesc::new("stiff-slider");
    d.link(LinkDesc::new("base", [0.0; 3]))
        .link(LinkDesc::new("a", [0.0, 0.0, 0.1]).mass(0.1, [1e-4; 3]))
        .link(LinkDesc::new("b", [0.0, 0.0, 0.2]).mass(0.1, [1e-4; 3]))
        .joint(JointDesc::ball("ball", "base", "a", [0.0; 3]).compliance(&[1e-3]))
        .joint(
            JointDesc::weld("weld", "a", "b", [0.0, 0.0, 0.1])
                .compliance(&[1e-3, 1e-3, 1e-6, 1e-3, 1e-3, 1e-3]),
        )
        .end_effector("b");
    let m = d.build().unwrap();
    let q = Configuration::rest(&m);
    let quiet = ReducedModel::build(&m, &q, &[], &ConstructOptions::default()).unwrap();
    assert_eq!(quiet.rank, 6);
    assert!(
        quiet.diagnostics.warnings.is_empty(),
        "{:?}",
        quiet.diagnostics.warnings
    );
    let options = ConstructOptions {
        tsvd: Tsvd::with_relative(1e-3).unwrap(),
        ..ConstructOptions::default()
    };
    let model = ReducedModel::build(&m, &q, &[], &options).unwrap();
    let w = &model.diagnostics.warnings;
    assert_eq!(model.rank, 5);
    assert!(
        w.iter()
            .any(|x| matches!(x, RankWarning::SmallGap { rank: 5, .. })),
        "{w:?}"
    );
    assert!(
        w.iter()
            .any(|x| matches!(x, RankWarning::NearSingular { .. }))
    );
}

/// The report's figures from its singular values.
#[test]
fn report_gap_condition_and_cut() {
    let r = RankReport::new("m", (4, 4), vec![1e-12, 2.0, 0.5, 1e-3], 1e-6, 3);
    assert_eq!(r.singular, vec![2.0, 0.5, 1e-3, 1e-12]);
    assert_eq!(r.gap(), 1e-12 / 1e-3);
    assert_eq!(r.condition(), 2.0 / 1e-3);
    assert_eq!(r.around_cut(2), (vec![0.25, 5e-4], vec![5e-13]));
    let full = RankReport::new("f", (2, 2), vec![1.0, 1.0], 0.0, 2);
    assert_eq!((full.gap(), full.condition()), (0.0, 1.0));
}
