//! Validation case F1 of FORK⁻¹S (`impulse_reduced::hard_cases`): fifty random mechanisms —
//! ten chains, ten trees, ten loops, ten ladders (tilted rungs, jittered anchors: nearly
//! redundant closures), five near-singular chains (ball joints nearly on one line, offsets
//! 1e-3 to 1e-8 m) and five stiff trees (compliances over eight decades) — each judged twice:
//!
//! - the reduced model's static end-effector displacement `C w` against an independent Schur
//!   complement at rest (joint screws written from the anchors, closures as constraints), for
//!   three random wrenches: within 1e-9 relative (the acceptance), and within the rounding
//!   bound of its conditioning;
//! - the full nonlinear statics (`impulse reduce --static`'s solver) against a plain Newton
//!   on the same equations (central-difference tangent, ten fixed increments) under four
//!   growing loads: the solver converges wherever the plain Newton does (and everywhere), and
//!   both land on the same equilibrium.

use impulse_reduced::hard_cases::{Family, SplitMix, acceptance_set, run_case};

use crate::validate::case::{Case, Check, Metric};

/// The acceptance's bound on the relative difference of the static displacements.
const LINEAR_ACCEPTANCE: f64 = 1e-9;

/// Largest distance between the two solvers' end effectors where both converge, over the
/// bounding radius: their stopping tests (1e-9 of the force scale) times the compliance
/// ranges of the set (up to 1e8 for the stiff trees) leave ~1e-10; measured ≤ 1e-9.
const AGREEMENT: f64 = 1e-6;

/// Seed of the wrenches and load directions.
const SEED: u64 = 0xF0_4B15;

/// The FORK⁻¹S cases.
pub fn cases() -> Vec<Case> {
    vec![Case {
        name: "F1-random-mechanisms",
        description: "50 random chains, trees, loops, ladders, near-singular and stiff mechanisms: C w vs an independent Schur complement (1e-9), full statics converge wherever a plain Newton does and agree with it",
        run: Box::new(f1),
    }]
}

fn f1() -> Result<Vec<Metric>, String> {
    let mut rng = SplitMix::new(SEED);
    let families = [
        Family::Chain,
        Family::Tree,
        Family::Loop,
        Family::Ladder,
        Family::NearSingular,
        Family::Stiff,
    ];
    // Per family: worst linear, worst linear / bound, solves, plain converged, solver
    // converged, solver missed where plain converged, worst disagreement, mechanisms built
    // with directions treated as rigid.
    let mut per = vec![
        (
            0.0_f64, 0.0_f64, 0usize, 0usize, 0usize, 0usize, 0.0_f64, 0usize
        );
        6
    ];
    let mut count = [0usize; 6];
    for (family, desc) in acceptance_set() {
        let r = run_case(family, &desc, &mut rng).map_err(|e| format!("{}: {e}", desc.name))?;
        let f = families.iter().position(|x| *x == family).unwrap_or(0);
        let p = &mut per[f];
        count[f] += 1;
        p.0 = p.0.max(r.linear);
        p.1 = p.1.max(r.linear / r.linear_bound);
        for &(plain, solved, diff) in &r.nonlinear {
            p.2 += 1;
            p.3 += usize::from(plain);
            p.4 += usize::from(solved);
            p.5 += usize::from(plain && !solved);
            if plain && solved {
                p.6 = p.6.max(diff);
            }
        }
        p.7 += usize::from(r.rank.0 < r.rank.1);
    }
    let mut out = Vec::new();
    for (f, p) in families.iter().zip(&per) {
        let name = f.name();
        let n = count[families.iter().position(|x| x == f).unwrap_or(0)] as f64;
        out.push(Metric::new(
            format!("{name}.linear"),
            p.0,
            0.0,
            Check::Between(0.0, LINEAR_ACCEPTANCE),
        ));
        out.push(Metric::new(
            format!("{name}.linear_over_rounding_bound"),
            p.1,
            0.0,
            Check::Between(0.0, 1.0),
        ));
        out.push(Metric::new(
            format!("{name}.plain_newton_converged"),
            p.3 as f64,
            p.2 as f64,
            Check::Between(0.0, p.2 as f64),
        ));
        out.push(Metric::new(
            format!("{name}.statics_converged"),
            p.4 as f64,
            p.2 as f64,
            Check::Exact,
        ));
        out.push(Metric::new(
            format!("{name}.statics_missed_where_plain_converged"),
            p.5 as f64,
            0.0,
            Check::Exact,
        ));
        out.push(Metric::new(
            format!("{name}.disagreement"),
            p.6,
            0.0,
            Check::Between(0.0, AGREEMENT),
        ));
        out.push(Metric::new(
            format!("{name}.built_with_rigid_directions"),
            p.7 as f64,
            p.7 as f64,
            Check::Between(0.0, n),
        ));
    }
    Ok(out)
}
