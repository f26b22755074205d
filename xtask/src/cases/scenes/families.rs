//! Families of perturbed runs of the chaotic scenes. One bundled trajectory of the coins or the
//! dominos hides what its neighbours show: the bundled coins ended at 0.9 ε_c of overlap while
//! the same scene with the rollers' spin about the vertical changed by 1 % sank 55 ε_c (a coin
//! held by one side of its face), and another by 1.5 ε_c (a rim dipping through within a
//! step). A family runs its scene once per factor of [`FAMILY_FACTORS`], one initial condition
//! read from the scene file scaled by it, in checking mode, and judges every run by the scene's
//! own check; each metric reported is the family's worst.

use impulse_sim::scene::SceneDesc;

use super::{Run, load_scene, run_scene, scene_checks};
use crate::validate::case::{Check, Metric};

/// The factors each family scales its initial condition by: within 2 % of the bundled value,
/// changes no measurement could tell apart, each a different trajectory of a chaotic scene.
pub(super) const FAMILY_FACTORS: [f64; 6] = [0.98, 0.99, 0.995, 1.005, 1.01, 1.02];

/// V17 coins with the rollers' spin about the vertical scaled.
pub(super) fn coins() -> Result<Vec<Metric>, String> {
    family("V17-coins", |desc, f| {
        for b in desc
            .bodies
            .iter_mut()
            .filter(|b| b.name.starts_with("roller"))
        {
            b.angular_velocity[2] *= f;
        }
    })
}

/// V16 dominos with the first domino's launch spin scaled.
pub(super) fn dominos() -> Result<Vec<Metric>, String> {
    family("V16-dominos", |desc, f| {
        for b in &mut desc.bodies {
            for w in &mut b.angular_velocity {
                *w *= f;
            }
        }
    })
}

/// Runs scene check `case` once per factor, its scene perturbed by `perturb`; returns each
/// metric at its worst over the runs ([`violation`]).
fn family(case: &str, perturb: impl Fn(&mut SceneDesc, f64)) -> Result<Vec<Metric>, String> {
    let check = scene_checks()
        .into_iter()
        .find(|c| c.case == case)
        .ok_or_else(|| format!("no scene check {case}"))?;
    let mut worst: Vec<Metric> = Vec::new();
    for &f in &FAMILY_FACTORS {
        let mut scene = load_scene(check.scene)?;
        perturb(&mut scene.desc, f);
        let (world, rec) = run_scene(&scene, check.event_log, true)?;
        let metrics = (check.metrics)(&Run {
            scene: &scene,
            world: &world,
            rec: &rec,
        })
        .map_err(|e| format!("factor {f}: {e}"))?;
        if worst.is_empty() {
            worst = metrics;
            continue;
        }
        for m in metrics {
            let w = worst
                .iter_mut()
                .find(|w| w.name == m.name)
                .ok_or_else(|| format!("factor {f}: metric {} not in the first run", m.name))?;
            if violation(&m) > violation(w) {
                *w = m;
            }
        }
    }
    Ok(worst)
}

/// How far a metric is from failing (negative) or past it (positive), in its own units. An
/// interval is judged at the bound on the value's side of the reference (a penetration of 0
/// is at the interval's lower bound and as far from failing as it gets).
fn violation(m: &Metric) -> f64 {
    let off = (m.value - m.reference).abs();
    match m.check {
        Check::Between(_, hi) if m.value >= m.reference => m.value - hi,
        Check::Between(lo, _) => lo - m.value,
        Check::Abs(tol) => off - tol,
        Check::Rel(tol) => off - tol * m.reference.abs(),
        Check::Exact => off,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The worst of a family is the one nearest to failing, or furthest past it.
    #[test]
    fn violation_orders_metrics_by_their_margin() {
        let between = |v| Metric::new("m", v, 0.0, Check::Between(0.0, 1.0));
        assert!(violation(&between(0.9)) > violation(&between(0.2)));
        assert!(violation(&between(0.2)) > violation(&between(0.0)));
        assert!(violation(&between(1.5)) > 0.0);
        assert!(violation(&between(-0.1)) > 0.0);
        let exact = |v| Metric::new("e", v, 1.0, Check::Exact);
        assert!(violation(&exact(0.0)) > violation(&exact(1.0)));
        assert_eq!(violation(&exact(1.0)), 0.0);
    }
}
