//! The blended statics converge to the full nonlinear statics as samples are added, across
//! the rank change at rest: Fig. 7's "Y" and ladder-36 (the paper's mechanisms, pulled as in
//! the study) and a straight six-link robot arm.

use glam::DVec3;

use super::*;

/// Samples per sweep: every doubling halves the spans.
const COUNTS: [usize; 4] = [1, 2, 4, 8];

/// Largest ratio of the constraint error and of the absolute end-effector error from one
/// count to the next: interpolation between samples converges as the square of the span
/// (ratio 1/4 per doubling); measured 0.25–0.39 (the first doubling is pre-asymptotic).
const QUADRATIC_RATIO: f64 = 0.45;

/// Largest ratio of the end-effector error relative to the displacement per doubling: the
/// span from rest, where the displacement is itself of the span's size, converges as the
/// span (ratio 1/2); measured 0.36–0.50.
const LINEAR_RATIO: f64 = 0.55;

#[test]
fn blended_statics_converge_across_the_rank_change_at_rest() {
    for (name, m, direction, max) in [
        (
            "y",
            crate::scenes::y_shape(4).build().unwrap(),
            DVec3::X,
            400.0,
        ),
        (
            "ladder-36",
            crate::scenes::ladder(36).build().unwrap(),
            DVec3::Y,
            60.0,
        ),
        (
            "robot-arm-6",
            crate::scenes::robot_arm(6).build().unwrap(),
            DVec3::X,
            4.0,
        ),
    ] {
        let rows = static_convergence(&m, 0, direction, max, &COUNTS, &Fig7Options::default())
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        for r in &rows {
            println!(
                "{name}: {} samples, ranks {:?}: end-effector {:.3e} ({:.3e} of the displacement, \
                 at {:.2} N), constraint {:.3e}",
                r.points, r.ranks, r.pose, r.relative_pose, r.worst_load, r.constraint
            );
            assert!(
                r.ranks.0 < r.ranks.1,
                "{name}: no rank change {:?}",
                r.ranks
            );
        }
        for w in rows.windows(2) {
            let (a, b) = (&w[0], &w[1]);
            assert!(
                b.constraint <= QUADRATIC_RATIO * a.constraint,
                "{name}: {} → {} samples: constraint {:e} → {:e}",
                a.points,
                b.points,
                a.constraint,
                b.constraint
            );
            assert!(
                b.pose <= QUADRATIC_RATIO * a.pose,
                "{name}: {} → {} samples: end effector {:e} → {:e}",
                a.points,
                b.points,
                a.pose,
                b.pose
            );
            assert!(
                b.relative_pose <= LINEAR_RATIO * a.relative_pose,
                "{name}: {} → {} samples: relative {:e} → {:e}",
                a.points,
                b.points,
                a.relative_pose,
                b.relative_pose
            );
        }
    }
}
