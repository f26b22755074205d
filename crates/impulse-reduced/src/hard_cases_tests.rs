//! The hard-case families against their independent references: near-singular chains and
//! random ladders under growing load (the rest of the fifty runs in `cargo xtask validate`,
//! case `F1-random-mechanisms`), with tolerances from each mechanism's conditioning.

use super::*;

/// Agreement of the two nonlinear solutions, in units of the solvers' stopping test
/// ([`crate::tol::STATIC_RESIDUAL_REL`]) times the mechanism's compliance range
/// `c_max / c_min` (a residual of that size moves the stiffest joint by that much more than
/// the softest), positions over the bounding radius. Measured ≤ 8e-10 at compliance ranges
/// of 2e1–1e3.
const AGREEMENT_FACTOR: f64 = 10.0;

/// The lever's compliance entries (≤ 0.01) to a few ulp.
const LEVER_ROUNDING: f64 = 1e-16;

#[test]
fn near_singular_chains_and_ladders_under_growing_load() {
    let mut rng = SplitMix::new(0xF0_4B15);
    let set: Vec<(Family, MechanismDesc)> = acceptance_set()
        .into_iter()
        .filter(|(f, _)| matches!(f, Family::NearSingular | Family::Ladder))
        .collect();
    let mut dropped = 0;
    for (family, desc) in &set {
        let r = run_case(*family, desc, &mut rng).unwrap_or_else(|e| panic!("{}: {e}", desc.name));
        let m = desc.build().unwrap();
        let c: Vec<f64> = m.joints.iter().flat_map(|j| j.compliance.clone()).collect();
        let range = c.iter().fold(0.0_f64, |a, &x| a.max(x))
            / c.iter().fold(f64::INFINITY, |a, &x| a.min(x));
        println!(
            "{}: rank {:?}, linear {:.2e} (bound {:.2e}), nonlinear {:?}",
            r.name, r.rank, r.linear, r.linear_bound, r.nonlinear
        );
        assert!(
            r.linear <= r.linear_bound,
            "{}: C w off the Schur complement by {:e}, above its rounding bound {:e}",
            r.name,
            r.linear,
            r.linear_bound
        );
        for (k, &(plain, solved, diff)) in r.nonlinear.iter().enumerate() {
            assert!(
                solved || !plain,
                "{}: load {k}: the plain Newton converged, the solver did not",
                r.name
            );
            if plain && solved {
                let bound = AGREEMENT_FACTOR * crate::tol::STATIC_RESIDUAL_REL * range;
                assert!(
                    diff <= bound,
                    "{}: load {k}: solutions {diff:e} apart (bound {bound:e})",
                    r.name
                );
            }
        }
        if r.rank.0 < r.rank.1 {
            dropped += 1;
        }
    }
    // The last two near-singular chains (offsets 1e-7 and 1e-8 m) drop their stretch.
    assert_eq!(dropped, 2);
}

/// The independent Schur complement of a lever is `c S Sᵀ`, `S = (0, L, 0, 0, 0, 1)`: a rod on
/// a hinge about z through (0.2, 0.1, 0), its frame L = 0.5 m further along x.
#[test]
fn schur_compliance_of_a_lever_is_closed_form() {
    let mut d = MechanismDesc::new("lever");
    d.link(LinkDesc::new("base", [0.0; 3]))
        .link(LinkDesc::new("arm", [0.7, 0.1, 0.0]).mass(1.0, [0.01; 3]))
        .joint(
            JointDesc::hinge("h", "base", "arm", [0.2, 0.1, 0.0], [0.0, 0.0, 1.0])
                .compliance(&[0.01]),
        )
        .end_effector("arm");
    let c = schur_compliance(&d.build().unwrap()).unwrap();
    let s = [0.0, 0.5, 0.0, 0.0, 0.0, 1.0];
    for a in 0..6 {
        for b in 0..6 {
            assert!(
                (c[(a, b)] - 0.01 * s[a] * s[b]).abs() < LEVER_ROUNDING,
                "{a},{b}: {}",
                c[(a, b)]
            );
        }
    }
}
