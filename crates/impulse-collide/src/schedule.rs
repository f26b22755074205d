//! When to check a pair again: the scheduling policy of an event loop built on the collision
//! heap (thesis §2.2, §2.3, §2.4.3).
//!
//! A pair's key in the heap is the earliest time it could need attention. The pure bound of
//! [`crate::toi`] answers "when could the gap close completely?"; an event loop needs three
//! refinements of that question, all here so they are tested apart from any loop:
//!
//! 1. **Targets.** A pair farther apart than ε_c is due when it could first come within
//!    [`Schedule::target_fraction`]·ε_c: checks happen at a positive gap, so bodies never
//!    interpenetrate, and the one-sided iteration of §2.3 ends in finitely many checks. A pair
//!    already within ε_c but not colliding is due when it could have closed half its gap
//!    ([`Schedule::target_gap`]).
//! 2. **Progress at the top.** Right after a pair is checked at the top of the heap, a pair
//!    that may be approaching is given a gap of at least [`Schedule::floor_fraction`]·ε_c, so
//!    the loop cannot stall on a pair that touches; a pair that is surely separating from
//!    contact is due when it could be back at contact, so a penetration heals instead of
//!    growing bounce by bounce ([`Schedule::piece_toi`]).
//! 3. **Pruning.** A body made of several convex pieces need not check a piece pair whose
//!    bounding spheres cannot come within reach before the earliest key already found
//!    ([`Schedule::can_skip`], from the direction-free coefficients of
//!    [`free_coefficients`]).
//!
//! Times returned are relative to the current time (s); lengths in the scene's unit.

use glam::DVec3;

use crate::motion::Motion;
use crate::toi;

/// Default fraction of ε_c a pair farther apart than ε_c is aimed at (thesis §2.2: a collision
/// is declared below ε_c; aiming below it makes the one-sided iteration end). Default `0.5`.
pub const TOI_TARGET_FRACTION: f64 = 0.5;

/// Default smallest gap, as a fraction of ε_c, a bound is computed for right after a check at
/// the top of the heap (progress; the price is a penetration of at most about this much).
/// Default `0.01`.
pub const GAP_FLOOR_FRACTION: f64 = 0.01;

/// One piece of a body as the scheduler sees it: its motion and its rotational reach (the r of
/// the rotational term of eq. 2.3; zero for a ball about its own centre).
#[derive(Clone, Copy, Debug)]
pub struct Mover<'a> {
    /// The body's motion at the current time.
    pub motion: &'a Motion,
    /// How far rotation about the centre of mass reaches on this piece (m).
    pub reach: f64,
}

/// The scheduling policy: ε_c and its two fractions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Schedule {
    /// Collision epsilon ε_c (m): pairs closer than this are in contact.
    pub collision_epsilon: f64,
    /// Fraction of ε_c a separated pair is aimed at ([`TOI_TARGET_FRACTION`]).
    pub target_fraction: f64,
    /// Smallest gap, as a fraction of ε_c, after a check at the top ([`GAP_FLOOR_FRACTION`]).
    pub floor_fraction: f64,
}

impl Schedule {
    /// The default policy for collision epsilon `eps_c`.
    #[must_use]
    pub fn new(eps_c: f64) -> Self {
        Self {
            collision_epsilon: eps_c,
            target_fraction: TOI_TARGET_FRACTION,
            floor_fraction: GAP_FLOOR_FRACTION,
        }
    }

    /// The gap a bound aims to close for a piece pair at distance `d`: down to
    /// `target_fraction`·ε_c when farther than ε_c, else half the distance.
    #[must_use]
    pub fn target_gap(&self, d: f64) -> f64 {
        let eps_c = self.collision_epsilon;
        if d > eps_c {
            d - self.target_fraction * eps_c
        } else {
            0.5 * d
        }
    }

    /// Time (s from now) before which a piece pair at distance `d` with contact normal `n`
    /// (unit, from the second body toward the first) cannot close its target gap.
    ///
    /// Elsewhere than `at_top`, this is the conservative bound of
    /// [`toi::toi_lower_bound`] on the target gap (a touching pair that is surely separating
    /// is due when it could be back at contact, below). With `at_top` (the pair was just checked
    /// at the top of the heap), a pair that may be approaching gets a gap of at least
    /// `floor_fraction`·ε_c (progress); a pair that is surely separating (its closing-speed
    /// bound is negative, by more than half the floor before turning back, or never turning
    /// back) keeps its own target, and from contact — interpenetrating by `depth` — it is due
    /// when it could be back at contact (the later root of `a·τ² + b·τ = −depth`), or, if it
    /// cannot rise that far, back where it is (`τ = −b/a`). The floor alone would let each
    /// bounce of a body whose bound is exact (a ball) end deeper, and a penetration, once
    /// made, would never heal.
    #[must_use]
    pub fn piece_toi(
        &self,
        d: f64,
        depth: f64,
        n: DVec3,
        at_top: bool,
        a: Mover<'_>,
        b: Mover<'_>,
    ) -> f64 {
        // d̂ points from body a toward body b: the opposite of the normal.
        let d_hat = -n;
        let gap = self.target_gap(d);
        if at_top {
            let floor = self.floor_fraction * self.collision_epsilon;
            let floored = gap.max(floor);
            let c1 = a.motion.toi_coefficients(d_hat, a.reach, floored);
            let c2 = b.motion.toi_coefficients(-d_hat, b.reach, floored);
            let (qa, qb) = (c1.0 + c2.0, c1.1 + c2.1);
            // Surely separating, by more than half the floor before turning back (the bound's
            // apex b²/4a; a body reversed after falling through the floor rises to the floor),
            // or never turning back.
            let separating = qb < 0.0 && (qa <= 0.0 || qb * qb > 2.0 * qa * floor);
            if !separating {
                // Possibly approaching, or barely leaving: the floor guarantees progress (the
                // coefficients above are this gap's: `toi_lower_bound` without recomputing).
                return toi::pair_toi(floored, c1, c2);
            } else if gap <= 0.0 {
                return return_time(qa, qb, depth);
            }
        } else if gap <= 0.0 {
            // Touching, away from the top: due now, unless surely separating (the bound's rate
            // of approach is negative), then when it could be back at contact — no deeper than
            // it is now before then. Without this, touching bodies at rest whose neighbour got
            // an impulse would all be due at the same instant again and again.
            let c1 = a.motion.toi_coefficients(d_hat, a.reach, 0.0);
            let c2 = b.motion.toi_coefficients(-d_hat, b.reach, 0.0);
            let (qa, qb) = (c1.0 + c2.0, c1.1 + c2.1);
            return if qb < 0.0 {
                return_time(qa, qb, depth)
            } else {
                0.0
            };
        }
        toi::toi_lower_bound(gap, d_hat, a.motion, a.reach, b.motion, b.reach)
    }

    /// Whether a piece pair can be skipped in a check: its bounding spheres are at least `lb`
    /// apart (m), no nearer than the closest piece pair found so far (`best`, m, if any), and
    /// even with direction-free coefficients `free_a`, `free_b` ([`free_coefficients`]) it
    /// cannot close its target gap before `until` (s from now, the earliest key so far). Such
    /// a pair can neither be the closest nor give the earliest key.
    #[must_use]
    pub fn can_skip(
        &self,
        lb: f64,
        best: Option<f64>,
        free_a: (f64, f64),
        free_b: (f64, f64),
        until: f64,
    ) -> bool {
        let gap = self.target_gap(lb);
        let may_be_closest = best.is_none_or(|d| lb < d);
        gap > 0.0 && !may_be_closest && toi::pair_toi(gap, free_a, free_b) >= until
    }
}

/// When a pair leaving contact (closing-rate bound `qa·τ² + qb·τ`, `qb < 0`) at penetration
/// `depth` could be back at contact: the later root of `qa·τ² + qb·τ = −depth`; if the bound
/// cannot rise that far, back where it is (`τ = −qb/qa`); never (`∞`) if it never turns back.
fn return_time(qa: f64, qb: f64, depth: f64) -> f64 {
    if qa <= 0.0 {
        return f64::INFINITY;
    }
    let disc = qb * qb - 4.0 * qa * depth.max(0.0);
    if disc > 0.0 {
        (-qb + disc.sqrt()) / (2.0 * qa)
    } else {
        -qb / qa
    }
}

/// Direction-free TOI coefficients `(A, B)` of a body whose largest rotational reach over its
/// pieces is `max_reach` (m): along any unit direction, none of its pieces closes a distance
/// by more than `A·τ² + B·τ` in time τ. Fixed: `(0, 0)`; ballistic: `(½|a| + ½·reach·β,
/// |v| + reach·ω_max)` (eqs. 2.2, 2.3 with |d̂| = 1, β the ω bound's growth under torque);
/// scripted and unbounded motions: `None` (no pruning).
#[must_use]
pub fn free_coefficients(motion: &Motion, max_reach: f64) -> Option<(f64, f64)> {
    match motion {
        Motion::Fixed { .. } => Some((0.0, 0.0)),
        Motion::Ballistic(m) => Some((
            0.5 * (m.gravity().length() + m.acceleration_pad())
                + 0.5 * max_reach * m.omega_growth(),
            m.velocity().length() + max_reach * m.omega_max(),
        )),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::Ballistic;
    use crate::motion::testkit::{rng, unit_vector};
    use crate::root::closing_time;
    use rand::RngExt;

    const G: f64 = 9.81;

    fn ball(z_velocity: f64) -> Motion {
        Ballistic::new(
            DVec3::ZERO,
            DVec3::new(0.0, 0.0, z_velocity),
            DVec3::new(0.0, 0.0, -G),
            0.0,
        )
        .unwrap()
        .into()
    }

    fn mover(m: &Motion) -> Mover<'_> {
        Mover {
            motion: m,
            reach: 0.0,
        }
    }

    #[test]
    fn targets_aim_inside_the_envelope_or_halve_the_gap() {
        let s = Schedule::new(1e-3);
        assert_eq!(s.target_gap(0.011), 0.011 - 0.5e-3);
        assert_eq!(s.target_gap(1e-3), 0.5e-3);
        assert_eq!(s.target_gap(4e-4), 2e-4);
        assert_eq!(s.target_gap(0.0), 0.0);
    }

    /// Away from the top, the schedule is the pure bound on the target gap: a ball falling
    /// from rest from height h reaches the target ½ε_c above a floor at √(2(h − ½ε_c)/g).
    #[test]
    fn away_from_the_top_the_bound_is_the_free_fall_time() {
        let s = Schedule::new(1e-3);
        let floor = Motion::fixed(DVec3::ZERO).unwrap();
        let b = ball(0.0);
        for h in [0.5, 0.01, 2e-3] {
            let tau = s.piece_toi(h, 0.0, DVec3::Z, false, mover(&b), mover(&floor));
            let exact = (2.0 * (h - 0.5e-3) / G).sqrt();
            assert!(
                (tau - exact).abs() <= 1e-14 * exact,
                "h {h}: {tau} vs {exact}"
            );
        }
    }

    /// At the top, a ball resting in contact (d = 0, at rest) is given the floor gap: it is due
    /// after the free-fall time over floor_fraction·ε_c, not at once.
    #[test]
    fn at_the_top_a_resting_pair_gets_the_gap_floor() {
        let s = Schedule::new(1e-3);
        let floor = Motion::fixed(DVec3::ZERO).unwrap();
        let b = ball(0.0);
        let tau = s.piece_toi(0.0, 0.0, DVec3::Z, true, mover(&b), mover(&floor));
        let exact = (2.0 * s.floor_fraction * 1e-3 / G).sqrt();
        assert!((tau - exact).abs() <= 1e-14 * exact, "{tau} vs {exact}");
        // Not at the top, the same pair is due now.
        assert_eq!(
            s.piece_toi(0.0, 0.0, DVec3::Z, false, mover(&b), mover(&floor)),
            0.0
        );
    }

    /// At the top, a ball leaving contact upward at speed u from a depth δ is due when it is
    /// back at contact: −δ + u·τ − ½gτ² = 0, the later root (u + √(u² − 2gδ))/g; from no depth,
    /// the full flight 2u/g.
    #[test]
    fn a_separating_pair_is_due_when_it_can_be_back_at_contact() {
        let s = Schedule::new(1e-3);
        let floor = Motion::fixed(DVec3::ZERO).unwrap();
        for (u, depth) in [(0.05, 0.0), (0.05, 1e-5), (0.2, 3e-4)] {
            let b = ball(u);
            let tau = s.piece_toi(0.0, depth, DVec3::Z, true, mover(&b), mover(&floor));
            let exact = (u + (u * u - 2.0 * G * depth).sqrt()) / G;
            assert!(
                (tau - exact).abs() <= 1e-12 * exact,
                "u {u} δ {depth}: {tau} vs {exact}"
            );
        }
        // Too slow to rise out of its depth: back where it is, τ = 2u/g.
        // (u = 0.02 m/s is surely separating: u² > g·floor_fraction·ε_c; it cannot rise 1e-4.)
        let b = ball(0.02);
        let tau = s.piece_toi(0.0, 1e-4, DVec3::Z, true, mover(&b), mover(&floor));
        assert!((tau - 0.04 / G).abs() <= 1e-15, "{tau}");
        // Slower than that, it is not surely separating: it gets the floor like a resting one.
        let b = ball(1e-3);
        let floored = s.piece_toi(0.0, 1e-4, DVec3::Z, true, mover(&b), mover(&floor));
        let v = 1e-3;
        let floor_gap = s.floor_fraction * 1e-3;
        let exact = (v + (v * v + 2.0 * G * floor_gap).sqrt()) / G; // ½gτ² − vτ = floor
        assert!(
            (floored - exact).abs() <= 1e-12 * exact,
            "{floored} vs {exact}"
        );
    }

    /// The direction-free coefficients bound the directional ones of every random ballistic
    /// motion along every direction, so a skipped piece pair could not have been due earlier:
    /// whenever `can_skip` says yes, the exact piece bound along any direction at any distance
    /// ≥ lb is not earlier than the key.
    #[test]
    fn pruning_never_skips_a_pair_that_could_be_due_earlier() {
        let s = Schedule::new(1e-3);
        let mut rng = rng(99);
        let (mut skipped, mut kept) = (0, 0);
        for _ in 0..20_000 {
            let motion = |rng: &mut rand::rngs::Xoshiro256PlusPlus| -> Motion {
                if rng.random::<f64>() < 0.2 {
                    return Motion::fixed(DVec3::ZERO).unwrap();
                }
                let m = Ballistic::new(
                    DVec3::ZERO,
                    unit_vector(rng) * rng.random_range(0.0..3.0),
                    unit_vector(rng) * G,
                    rng.random_range(0.0..20.0),
                )
                .unwrap();
                if rng.random::<bool>() {
                    m.with_omega_growth(rng.random_range(0.0..50.0))
                        .unwrap()
                        .into()
                } else {
                    m.into()
                }
            };
            let (ma, mb) = (motion(&mut rng), motion(&mut rng));
            let (ra, rb) = (rng.random_range(0.0..0.1), rng.random_range(0.0..0.1));
            let (fa, fb) = (
                free_coefficients(&ma, ra).unwrap(),
                free_coefficients(&mb, rb).unwrap(),
            );
            let lb = rng.random_range(0.0..0.2);
            let until = rng.random_range(0.0..0.2);
            if !s.can_skip(lb, Some(0.0), fa, fb, until) {
                kept += 1;
                continue;
            }
            skipped += 1;
            let n = unit_vector(&mut rng);
            let d = lb + rng.random_range(0.0..0.05);
            let a = Mover {
                motion: &ma,
                reach: ra,
            };
            let b = Mover {
                motion: &mb,
                reach: rb,
            };
            let tau = s.piece_toi(d, 0.0, n, false, a, b);
            assert!(
                tau >= until * (1.0 - 1e-12),
                "skipped a pair due at {tau} < {until}"
            );
        }
        assert!(
            skipped > 1000 && kept > 1000,
            "{skipped} skipped, {kept} kept"
        );
        // A pair that may be the closest is never skipped.
        assert!(!s.can_skip(0.5, Some(0.6), (0.0, 0.0), (0.0, 0.0), 0.0));
        assert!(!s.can_skip(0.5, None, (0.0, 0.0), (0.0, 0.0), 0.0));
        // Scripted and unbounded motions give no direction-free bound.
        let u = Motion::Unbounded { com: DVec3::ZERO };
        assert_eq!(free_coefficients(&u, 1.0), None);
        assert_eq!(closing_time(1.0, 0.0, 0.0), f64::INFINITY);
    }
}
