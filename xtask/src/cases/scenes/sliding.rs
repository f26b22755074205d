//! Sliding and rolling on a surface: V6 block on ramp, V7 sliding to rolling, V8 ball on a
//! spinning platter. Every reference is computed from the scene's own numbers.

use glam::DVec3;
use impulse_sim::scene::MotionDesc;

use super::{
    REST_REL, Run, SCENE_REL, SceneCheck, fit_line, half_extents, no_penetration, rotation,
    sphere_radius,
};
use crate::validate::case::{Check, Metric};

/// V6: creep down the ramp after the stop, relative to the stop distance (digest < 1 %).
const CREEP_REL: f64 = 0.01;
/// V6: the sliding phase is fitted from this time…
const SLIDE_FIT_START_REL: f64 = 0.1;
/// …to this fraction of the reference stop time.
const SLIDE_FIT_END_REL: f64 = 0.8;
/// V6: the distance is read, and the creep measured from, at this multiple of the reference
/// stop time.
const AFTER_STOP_REL: f64 = 1.25;
/// V7: the sliding line is fitted before this fraction of t*…
const SLIDING_END_REL: f64 = 0.8;
/// …and the rolling speed averaged after this multiple of t*.
const ROLLING_START_REL: f64 = 1.3;
/// V8: orbit rate, relative (digest ±3 %).
const ORBIT_RATE_REL: f64 = 0.03;
/// V8: largest radius drift over the fitted orbit, relative (digest 5 % per orbit).
const ORBIT_RADIUS_DRIFT: f64 = 0.05;
/// V8: the orbit is fitted after this many of the slip phase's duration bound (see `v8`).
const SLIP_TIMES: f64 = 4.0;

pub(super) fn checks() -> Vec<SceneCheck> {
    vec![
        SceneCheck {
            case: "V6-block-on-ramp",
            scene: "block-on-ramp",
            description: "block launched down a ramp (thesis: 548 cm/s, 30°, μ 0.9): stops at v0/a and v0²/2a with a = g(μ cos θ − sin θ) (±2 %), creep < 1 %",
            headline: "stop_time",
            event_log: false,
            thesis: Some(("block on ramp", 0.3)),
            metrics: v6_block_on_ramp,
        },
        SceneCheck {
            case: "V7-sliding-to-rolling",
            scene: "sliding-to-rolling",
            description: "ball launched without spin: rolling from t* = 2v0/(7μg), s* = 12v0²/(49μg), v* = 5v0/7 (±2 %)",
            headline: "v_star",
            event_log: false,
            thesis: None,
            metrics: v7_sliding_to_rolling,
        },
        SceneCheck {
            case: "V8-ball-on-platter",
            scene: "ball-on-platter",
            description: "ball set down at rest on a platter spinning at Ω: once rolling, its centre circles at 2Ω/7 (±3 %), radius drift < 5 % per orbit",
            headline: "orbit_rate",
            event_log: false,
            thesis: Some(("ball on spinning platter", 1.4)),
            metrics: v8_platter,
        },
    ]
}

/// μ of the contact between bodies `a` and `b` of the scene.
pub(super) fn friction(r: &Run<'_>, a: &str, b: &str) -> Result<f64, String> {
    Ok(super::contact(r, a, b)?.friction)
}

fn v6_block_on_ramp(r: &Run<'_>) -> Result<Vec<Metric>, String> {
    let b = r.index("block")?;
    let (block, ramp) = (r.desc("block")?, r.desc("ramp")?);
    let (g, mu) = (r.g(), friction(r, "block", "ramp")?);
    let v0 = DVec3::from_array(block.velocity).length();
    // The ramp's surface normal is its box's local z; the slope angle is its tilt.
    half_extents(ramp)?;
    let up = -DVec3::from_array(r.scene.desc.gravity).normalize();
    let normal = rotation(&ramp.rotation) * DVec3::Z;
    let th = normal.dot(up).clamp(-1.0, 1.0).acos();
    let down = (-up + normal * up.dot(normal)).normalize();
    let a = g * (mu * th.cos() - th.sin());
    if a <= 0.0 {
        return Err(format!(
            "μ = {mu} cannot stop a block on a {:.1}° slope",
            th.to_degrees()
        ));
    }
    let (t_ref, d_ref) = (v0 / a, v0 * v0 / (2.0 * a));
    let frames = &r.rec.frames;
    let x0 = frames[0].bodies[b].com;
    let s = |k: usize| (frames[k].bodies[b].com - x0).dot(down);
    // Velocity along the ramp by central differences over the sliding phase, fitted by a
    // line v = v0' − a'·t: its zero is the stop time, its area the distance.
    let window = SLIDE_FIT_START_REL * t_ref..=SLIDE_FIT_END_REL * t_ref;
    let pts: Vec<(f64, f64)> = (1..frames.len() - 1)
        .filter(|&k| window.contains(&frames[k].time))
        .map(|k| {
            let dt = frames[k + 1].time - frames[k - 1].time;
            (frames[k].time, (s(k + 1) - s(k - 1)) / dt)
        })
        .collect();
    let (v_fit, slope) = fit_line(&pts);
    let t_stop = -v_fit / slope;
    let d_stop = -v_fit * v_fit / (2.0 * slope);
    let k_after = frames
        .iter()
        .position(|f| f.time >= AFTER_STOP_REL * t_ref - 1e-9)
        .ok_or("the run ends before the block can have stopped")?;
    let kend = frames.len() - 1;
    Ok(vec![
        Metric::new("deceleration", -slope, a, Check::Rel(SCENE_REL)),
        Metric::new("stop_time", t_stop, t_ref, Check::Rel(SCENE_REL)),
        Metric::new("stop_distance_fit", d_stop, d_ref, Check::Rel(SCENE_REL)),
        Metric::new(
            "distance_after_stop",
            s(k_after),
            d_ref,
            Check::Rel(SCENE_REL),
        ),
        Metric::new(
            "creep_after_stop_rel",
            (s(kend) - s(k_after)) / d_ref,
            0.0,
            Check::Between(-CREEP_REL, CREEP_REL),
        ),
        no_penetration(r),
    ])
}

fn v7_sliding_to_rolling(r: &Run<'_>) -> Result<Vec<Metric>, String> {
    let b = r.index("ball")?;
    let ball = r.desc("ball")?;
    let radius = sphere_radius(ball)?;
    let (g, mu) = (r.g(), friction(r, "ball", "floor")?);
    let v_launch = DVec3::from_array(ball.velocity);
    let v0 = v_launch.length();
    let dir = v_launch / v0;
    let t_ref = 2.0 * v0 / (7.0 * mu * g);
    let s_ref = 12.0 * v0 * v0 / (49.0 * mu * g);
    let v_ref = 5.0 * v0 / 7.0;
    let frames = &r.rec.frames;
    let x0 = frames[0].bodies[b].com.dot(dir);
    // Sliding: a line through the speeds before 0.8·t*; rolling: the mean after 1.3·t*.
    let sliding: Vec<(f64, f64)> = frames
        .iter()
        .filter(|f| f.time > 0.05 * t_ref && f.time < SLIDING_END_REL * t_ref)
        .map(|f| (f.time, f.bodies[b].velocity.dot(dir)))
        .collect();
    let rolling: Vec<f64> = frames
        .iter()
        .filter(|f| f.time > ROLLING_START_REL * t_ref)
        .map(|f| f.bodies[b].velocity.dot(dir))
        .collect();
    if rolling.is_empty() {
        return Err("the run ends before the ball can roll".into());
    }
    let (v_start, slope) = fit_line(&sliding);
    let v_roll = rolling.iter().sum::<f64>() / rolling.len() as f64;
    let t_star = (v_roll - v_start) / slope;
    // Distance at t*: the sliding parabola.
    let s_star = v_start * t_star + 0.5 * slope * t_star * t_star;
    let last = r.last()?;
    let up = -DVec3::from_array(r.scene.desc.gravity).normalize();
    // Rolling: the contact point is still, v + ω × (−r·up) = 0, so v = r·ω·(up × dir).
    let spin = last.bodies[b].omega.dot(up.cross(dir)) * radius;
    let travelled = last.bodies[b].com.dot(dir) - x0;
    Ok(vec![
        Metric::new("v_star", v_roll, v_ref, Check::Rel(SCENE_REL)),
        Metric::new("t_star", t_star, t_ref, Check::Rel(SCENE_REL)),
        Metric::new("s_star", s_star, s_ref, Check::Rel(SCENE_REL)),
        Metric::new("rolling_omega_r", spin, v_ref, Check::Rel(SCENE_REL)),
        Metric::new(
            "distance_at_end",
            travelled,
            s_ref + v_ref * (last.time - t_ref),
            Check::Rel(SCENE_REL),
        ),
        no_penetration(r),
    ])
}

/// Least-squares circle through points (Kåsa's algebraic fit): centre and radius.
fn fit_circle(points: &[(f64, f64)]) -> (f64, f64, f64) {
    let mut a = glam::DMat3::ZERO;
    let mut b = DVec3::ZERO;
    for &(x, y) in points {
        let row = DVec3::new(x, y, 1.0);
        let z = x * x + y * y;
        a += glam::DMat3::from_cols(row * x, row * y, row);
        b -= row * z;
    }
    let s = a.inverse() * b;
    let (cx, cy) = (-0.5 * s.x, -0.5 * s.y);
    (cx, cy, (cx * cx + cy * cy - s.z).sqrt())
}

/// V8. The ball is set down at rest: its contact point slips at first at Ω·ρ₀ (ρ₀ its
/// distance from the axis), and friction removes the slip at (7/2)·μ·g or faster, so after
/// [`SLIP_TIMES`] times Ω·ρ₀ / ((7/2)μg) it rolls; the orbit rate is fitted from then on.
fn v8_platter(r: &Run<'_>) -> Result<Vec<Metric>, String> {
    let b = r.index("ball")?;
    let (ball, platter) = (r.desc("ball")?, r.desc("platter")?);
    let MotionDesc::Spinner { axis, rate } = platter.motion else {
        return Err("the platter is not a spinner".into());
    };
    let axis = DVec3::from_array(axis).normalize();
    let omega = rate * axis.z.signum();
    let (g, mu) = (r.g(), friction(r, "ball", "platter")?);
    let rho0 = (DVec3::from_array(ball.position) - DVec3::from_array(platter.position))
        .truncate()
        .length();
    let settle = SLIP_TIMES * omega.abs() * rho0 / (3.5 * mu * g);
    let frames: Vec<&impulse_sim::Frame> =
        r.rec.frames.iter().filter(|f| f.time >= settle).collect();
    if frames.len() < 10 {
        return Err(format!(
            "the run ends before the ball rolls (settles by {settle:.3} s)"
        ));
    }
    let pts: Vec<(f64, f64)> = frames
        .iter()
        .map(|f| (f.bodies[b].com.x, f.bodies[b].com.y))
        .collect();
    let (cx, cy, radius) = fit_circle(&pts);
    // Unwrapped angle about the fitted centre against time: its slope is the orbit rate.
    let mut angle = Vec::with_capacity(pts.len());
    let mut last = f64::NAN;
    let mut turns = 0.0;
    for (f, &(x, y)) in frames.iter().zip(&pts) {
        let a = (y - cy).atan2(x - cx);
        if last.is_finite() {
            let d = a - last;
            if d > std::f64::consts::PI {
                turns -= 1.0;
            } else if d < -std::f64::consts::PI {
                turns += 1.0;
            }
        }
        last = a;
        angle.push((f.time, a + turns * std::f64::consts::TAU));
    }
    let (_, orbit) = fit_line(&angle);
    let drift = pts
        .iter()
        .map(|&(x, y)| ((x - cx).hypot(y - cy) - radius).abs() / radius)
        .fold(0.0, f64::max);
    // Rolling, not sliding: the contact point moves with the platter (slip over rim speed).
    let f = r.last()?;
    let s = f.bodies[b];
    let contact = s.com - DVec3::Z * sphere_radius(ball)?;
    let surface = (axis * rate).cross(contact - DVec3::from_array(platter.position));
    let point = s.velocity + s.omega.cross(contact - s.com);
    let slip = (point - surface).length() / (omega.abs() * rho0);
    Ok(vec![
        Metric::new(
            "orbit_rate",
            orbit,
            2.0 * omega / 7.0,
            Check::Rel(ORBIT_RATE_REL),
        ),
        Metric::new(
            "radius_drift_rel",
            drift,
            0.0,
            Check::Between(0.0, ORBIT_RADIUS_DRIFT),
        ),
        Metric::new("slip_at_end_rel", slip, 0.0, Check::Between(0.0, REST_REL)),
        no_penetration(r),
    ])
}
