//! Fig. 7 study against the closed-form lever (`testutil::lever`).

use glam::DVec3;

use super::*;
use crate::testutil::{lever, lever_angle};

/// Agreement of the statics with the lever's closed form (rad and scaled twist norms): the
/// fixed point stops at `tol::BLEND_STATIC_TOLERANCE` and the full Newton at its residual.
const CLOSED_FORM_TOL: f64 = 1e-9;

/// The lever's scaled displacement `‖(v/r, ω/π)‖` at angle θ: the body twist of a rotation θ
/// about the hinge `length` behind the link's origin is θ·(0, length, 0; 0, 0, 1).
fn lever_displacement(theta: f64, length: f64, r: f64) -> f64 {
    theta * ((length / r).powi(2) + (1.0 / core::f64::consts::PI).powi(2)).sqrt()
}

#[test]
fn fig7_single_model_holds_the_constant_world_force_and_is_plotted_at_its_own_displacement() {
    // c·L·F = 1 at 1 N: θ* = 0.739085… (θ = cos θ). The one-hinge reduced model is exact, so
    // the single model's end effector must sit where the full model's does (pose error 0),
    // with the closed-form displacement; a load held fixed in the rest frame would put it at
    // θ = c·L·F = 1 rad instead.
    let (c, length) = (1.0, 1.0);
    let m = lever(c, length);
    let r = m.bounding_radius();
    let loads = [0.5, 1.0];
    let (rows, _) = fig7(&m, 0, DVec3::Y, &loads, &[], &Fig7Options::default()).unwrap();
    for row in &rows {
        let theta = lever_angle(c * length * row.load);
        let d = lever_displacement(theta, length, r);
        println!(
            "load {}: θ* {theta:.9}, displacement exact {d:.9} full {:.9} single {:.9}, single pose error {:.2e}",
            row.load, row.displacement, row.single_displacement, row.single_pose
        );
        assert!((row.displacement - d).abs() < CLOSED_FORM_TOL);
        assert!((row.single_displacement - d).abs() < CLOSED_FORM_TOL);
        assert!(row.single_pose < CLOSED_FORM_TOL);
        assert!(row.single < CLOSED_FORM_TOL);
    }
}
