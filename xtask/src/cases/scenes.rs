//! Scene validation cases (thesis chapter 7; the digest's validation table V6–V17): each runs a
//! bundled scene from `fixtures/scenes/` through `impulse-sim` and compares what happened with
//! a closed form or a conservation law.
//!
//! - V6 block on ramp: stop time and distance against constant deceleration; creep after.
//! - V7 sliding to rolling: t*, s*, v* of a solid ball against the closed forms.
//! - V12 rattleback: a beaded smooth ellipsoid reverses its spin in its non-preferred
//!   direction after 1–4 revolutions and keeps its preferred one; balanced twins stay in phase.
//! - V9 two-ball collision: post-impact velocities against v0(1 ∓ e)/2.
//! - V10 chain of balls: the far ball leaves at the striker's speed, the others stay.
//! - V13 block drop: two blocks end stacked and at rest, never interpenetrating.
//! - V15 tumbling box: 26 convex bodies, gravity off: elastic energy conserved; dissipative
//!   energy never increases; no interpenetration.
//! - Bullet: a 1 km/s spinning body never passes through a 1 mm plate.
//! - Determinism: identical trajectory hashes with 1 and 2 threads.

use std::path::{Path, PathBuf};

use glam::DVec3;
use impulse_sim::contact::ContactKind;
use impulse_sim::{Recording, Scene, World, run};

use crate::validate::case::{Case, Check, Metric};

/// Relative tolerance of the V6 and V7 comparisons (digest: ±2 %).
const SCENE_REL: f64 = 0.02;
/// V6: creep down the ramp after the stop, relative to the stop distance (digest < 1 %).
const CREEP_REL: f64 = 0.01;
/// V8: orbit rate, relative (digest ±3 %).
const ORBIT_RATE_REL: f64 = 0.03;
/// V8: largest radius drift over the run (one orbit), relative (digest 5 % per orbit).
const ORBIT_RADIUS_DRIFT: f64 = 0.05;
/// V9: post-impact velocities, relative (digest: 1e-6).
const TWO_BALL_REL: f64 = 1e-6;
/// V14: momentum conservation of a ball–ball collision, relative to the pair's momentum.
const POOL_MOMENTUM_REL: f64 = 1e-9;
/// V14: largest energy gain of a ball–ball collision, relative (none allowed beyond rounding).
const POOL_ENERGY_REL: f64 = 1e-12;
/// V16: a domino has toppled when its long axis leans more than this from the vertical.
const TOPPLE_DEGREES: f64 = 45.0;
/// V11: two bodies are in contact when their gap, averaged over the last [`REST_WINDOW`], is
/// below this fraction of the ball radius (digest: 2ε_c at one instant; resting balls breathe
/// by microcollisions, measured mean gaps 35–100 µm whatever ε_c, 0.2–0.5 % of r, while the
/// nearest pair not in contact is 2r(√3 − 1) = 146 % of r apart).
const DISH_CONTACT_GAP_REL: f64 = 0.01;
/// V11: the six outer balls lie 60° ± this apart around the centre ball (digest ±5°).
const DISH_BEARING_DEGREES: f64 = 5.0;
/// V17: a coin lies flat when its axis is within this many degrees of the vertical: the
/// digest's 5°, plus the lean of a coin whose rim rests on another coin (asin(1.75 mm /
/// 24 mm) = 4.2°), which is a legitimate final state (seen here: one coin at 5.6°).
const FLAT_DEGREES: f64 = 9.2;
/// V15 elastic: kinetic energy conservation, relative (digest: 1e-6).
const ELASTIC_ENERGY_REL: f64 = 1e-6;
/// V15 dissipative: the largest rise of kinetic energy between frames, relative (digest:
/// monotone within 1e-9).
const MONOTONE_ENERGY_REL: f64 = 1e-9;
/// V10: speeds of the balls that should stay, and of the striker, relative to v0 (digest 5 %).
const CHAIN_STILL_REL: f64 = 0.05;
/// V10: the striker must not recoil: its velocity may be negative only by rounding (relative
/// to v0).
const CHAIN_ROUNDING: f64 = 1e-12;
/// V10: least speed of the far ball, relative to v0 (digest 95 %).
const CHAIN_FAR_MIN: f64 = 0.95;
/// V13: "at rest" means a mean speed below this fraction of the drop's impact speed (digest
/// 1e-2).
const REST_REL: f64 = 1e-2;
/// V13: the window (s) at the end of the run over which the mean speed is taken.
const REST_WINDOW: f64 = 0.5;
/// V13: largest instantaneous speed at rest, in units of the microcollision candidate speed
/// √(2·g·ε_c): a microcollision with boosted restitution (up to e_max = 5 at full envelope
/// depth) can send a body off at a few times that speed.
const JITTER_MAX: f64 = 5.0;

/// V12: the balanced twins' orientations may differ by at most this angle over the run
/// (digest: < 1°).
const TWIN_PHASE_DEGREES: f64 = 1.0;
/// V12: revolutions the rattleback turns before its spin reverses (digest: 1–4; thesis:
/// "approximately two").
const REVERSAL_REVOLUTIONS: (f64, f64) = (1.0, 4.0);
/// V12: a reversal counts when the final spin has the opposite sign and at least this fraction
/// of the initial spin's magnitude (a real reversal, not jitter about zero); a body that must
/// keep its direction must keep at least this fraction too.
const SPIN_KEPT: f64 = 0.5;

/// A bundled scene with its checks: `validate` runs it as bundled, `bench` at several accuracy
/// settings.
pub struct SceneCheck {
    /// Validation case name (also the snapshot name).
    pub case: &'static str,
    /// Scene file stem in `fixtures/scenes/`.
    pub scene: &'static str,
    /// The Table 7.1 row (example name, slowdown on the 1996 machine) this scene reproduces.
    pub thesis: Option<(&'static str, f64)>,
    /// Whether the run records every contact (`World::set_event_log`) for the metrics.
    pub event_log: bool,
    /// The metric `bench` reports as the scene's error against its reference.
    pub headline: &'static str,
    /// The metrics of a finished run, each against its reference.
    pub metrics: fn(&World, &Recording) -> Result<Vec<Metric>, String>,
}

/// Every scene check, in registry order.
pub fn scene_checks() -> Vec<SceneCheck> {
    vec![
        SceneCheck {
            case: "V14-pool-break",
            headline: "max_momentum_error_rel",
            scene: "pool-break",
            event_log: true,
            thesis: Some(("pool break", 9.0)),
            metrics: v14_pool,
        },
        SceneCheck {
            case: "V16-dominos",
            headline: "max_mean_speed_rel",
            scene: "dominos",
            event_log: false,
            thesis: Some(("dominos", 3.1)),
            metrics: v16_dominos,
        },
        SceneCheck {
            case: "V17-coins",
            headline: "worst_tilt_degrees",
            scene: "coins",
            event_log: false,
            thesis: Some(("coins", 4.6)),
            metrics: v17_coins,
        },
        SceneCheck {
            case: "feeder-chute",
            headline: "max_mean_speed_rel",
            scene: "feeder-chute",
            event_log: false,
            thesis: Some(("part feeder chute", 6.6)),
            metrics: feeder_chute,
        },
        SceneCheck {
            case: "V11-balls-in-dish",
            headline: "centre_ball_off_axis_over_r",
            scene: "balls-in-dish",
            event_log: false,
            thesis: Some(("balls in dish", 2.4)),
            metrics: v11_dish,
        },
        SceneCheck {
            case: "V6-block-on-ramp",
            headline: "stop_time",
            scene: "block-on-ramp",
            event_log: false,
            thesis: Some(("block on ramp", 0.3)),
            metrics: v6_block_on_ramp,
        },
        SceneCheck {
            case: "V7-sliding-to-rolling",
            headline: "v_star",
            scene: "sliding-to-rolling",
            event_log: false,
            thesis: None,
            metrics: v7_sliding_to_rolling,
        },
        SceneCheck {
            case: "V12-rattleback",
            headline: "revolutions_before_reversal",
            scene: "rattleback",
            event_log: false,
            thesis: Some(("rattleback top", 1.2)),
            metrics: v12_rattleback,
        },
        SceneCheck {
            case: "V8-ball-on-platter",
            headline: "orbit_rate",
            scene: "ball-on-platter",
            event_log: false,
            thesis: Some(("ball on spinning platter", 1.4)),
            metrics: v8_platter,
        },
        SceneCheck {
            case: "V9-two-ball",
            headline: "target_v",
            scene: "two-ball-collision",
            event_log: false,
            thesis: None,
            metrics: v9_two_ball,
        },
        SceneCheck {
            case: "V10-chain-of-balls",
            headline: "far_ball_speed_over_v0",
            scene: "chain-of-balls",
            event_log: false,
            thesis: Some(("chain of balls", 1.2)),
            metrics: v10_chain,
        },
        SceneCheck {
            case: "V13-block-drop",
            headline: "upper_mean_speed_rel",
            scene: "block-drop",
            event_log: false,
            thesis: Some(("block drop", 0.5)),
            metrics: v13_block_drop,
        },
        SceneCheck {
            case: "V15-tumbling-box-elastic",
            headline: "max_energy_change_rel",
            scene: "tumbling-box-elastic",
            event_log: false,
            thesis: Some(("exploding text", 4.5)),
            metrics: v15_elastic,
        },
        SceneCheck {
            case: "V15-tumbling-box",
            headline: "max_energy_rise_rel",
            scene: "tumbling-box",
            event_log: false,
            thesis: Some(("exploding text", 4.5)),
            metrics: v15_dissipative,
        },
        SceneCheck {
            case: "bullet-through-plate",
            headline: "max_penetration_over_eps_c",
            scene: "bullet-through-plate",
            event_log: false,
            thesis: None,
            metrics: bullet,
        },
    ]
}

/// Runs the bundled scene of check `case` and returns its metrics.
fn run_check(case: &str) -> Result<Vec<Metric>, String> {
    let check = scene_checks()
        .into_iter()
        .find(|c| c.case == case)
        .ok_or_else(|| format!("no scene check {case}"))?;
    let (world, rec) = record(check.scene, check.event_log)?;
    (check.metrics)(&world, &rec)
}

/// The scene cases.
pub fn cases() -> Vec<Case> {
    vec![
        Case {
            name: "V6-block-on-ramp",
            description: "block launched down a 30° ramp (548 cm/s, μ 0.9): stop at 1.9992 s and 547.77 cm (±2 %), creep < 1 %",
            run: || run_check("V6-block-on-ramp"),
        },
        Case {
            name: "V7-sliding-to-rolling",
            description: "ball launched without spin: rolling from t* = 2v0/(7μg), s* = 12v0²/(49μg), v* = 5v0/7 (±2 %)",
            run: || run_check("V7-sliding-to-rolling"),
        },
        Case {
            name: "V8-ball-on-platter",
            description: "ball rolling on a platter spinning at Ω: its centre circles at 2Ω/7 (±3 %), radius drift < 5 % per orbit",
            run: || run_check("V8-ball-on-platter"),
        },
        Case {
            name: "V12-rattleback",
            description: "smooth ellipsoids spun on a table: a beaded one (skewed inertia) reverses within 1–4 revolutions in its non-preferred direction, keeps its preferred one; balanced twins stay within 1° of each other",
            run: || run_check("V12-rattleback"),
        },
        Case {
            name: "V9-two-ball",
            description: "central frictionless collision of equal balls: v0(1 − e)/2 and v0(1 + e)/2 (1e-6)",
            run: || run_check("V9-two-ball"),
        },
        Case {
            name: "V10-chain-of-balls",
            description: "striker into four balls ε_c apart, e = 1: far ball ≥ 0.95 v0, others and striker < 0.05 v0, no recoil",
            run: || run_check("V10-chain-of-balls"),
        },
        Case {
            name: "V13-block-drop",
            description: "two blocks dropped on a floor end stacked and at rest (mean speed < 1 % of impact speed) with no interpenetration",
            run: || run_check("V13-block-drop"),
        },
        Case {
            name: "V15-tumbling-box-elastic",
            description: "26 tumbling convex bodies in a closed box, g = 0, e = 1, μ = 0: kinetic energy conserved to 1e-6, no interpenetration",
            run: || run_check("V15-tumbling-box-elastic"),
        },
        Case {
            name: "V15-tumbling-box",
            description: "26 tumbling convex bodies in a closed box, g = 0, e = 0.8, μ = 0.3: kinetic energy never rises, no interpenetration",
            run: || run_check("V15-tumbling-box"),
        },
        Case {
            name: "bullet-through-plate",
            description: "1 km/s bodies spinning at 1000 rad/s at a 1 mm plate: they bounce or deflect, never pass through",
            run: || run_check("bullet-through-plate"),
        },
        Case {
            name: "V14-pool-break",
            description: "15-ball rack ε_c apart broken by a cue ball with draw: every ball–ball collision conserves the pair's momentum (1e-9) and loses energy",
            run: || run_check("V14-pool-break"),
        },
        Case {
            name: "V16-dominos",
            description: "seven dominos: topple in order along the row, all down and at rest at the end, no interpenetration",
            run: || run_check("V16-dominos"),
        },
        Case {
            name: "V17-coins",
            description: "eight coins rolled and tossed onto a plate: all end flat (within 5°, or 9.2° when propped on another coin) and at rest, no interpenetration",
            run: || run_check("V17-coins"),
        },
        Case {
            name: "feeder-chute",
            description: "six non-convex caps slide down a converging chute: all reach the floor and stop, no interpenetration",
            run: || run_check("feeder-chute"),
        },
        Case {
            name: "V11-balls-in-dish",
            description: "seven balls dropped into a dish end as one at the centre and six around at 60°, with exactly 12 ball–ball and 7 ball–dish contacts (mean gap < 1 % of r over the last 0.5 s), at rest",
            run: || run_check("V11-balls-in-dish"),
        },
        Case {
            name: "determinism-threads",
            description: "tumbling box run on 1 and on 2 threads: bit-identical trajectories (hash)",
            run: determinism,
        },
    ]
}

/// `fixtures/scenes/<name>.ron` from the workspace root.
fn scene_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("fixtures")
        .join("scenes")
        .join(format!("{name}.ron"))
}

pub fn load(name: &str) -> Result<(Scene, World), String> {
    let scene = Scene::read(&scene_path(name)).map_err(|e| e.to_string())?;
    let world = World::from_scene(&scene).map_err(|e| e.to_string())?;
    Ok((scene, world))
}

/// Runs a bundled scene for its duration at its output rate.
pub fn record(name: &str, event_log: bool) -> Result<(World, Recording), String> {
    let (scene, mut world) = load(name)?;
    world.set_event_log(event_log);
    let rec = run(
        &mut world,
        scene.desc.duration,
        scene.desc.output_rate,
        |_| {},
    )
    .map_err(|e| e.to_string())?;
    Ok((world, rec))
}

fn body(world: &World, name: &str) -> Result<usize, String> {
    world
        .body_index(name)
        .ok_or_else(|| format!("no body \"{name}\""))
}

/// The promise of chapter 2: bodies never interpenetrate by more than ε_c. The metric is the
/// largest penetration depth measured at any check, in units of ε_c.
fn no_penetration(world: &World, rec: &Recording) -> Metric {
    Metric::new(
        "max_penetration_over_eps_c",
        rec.counters.max_penetration / world.collision_epsilon(),
        0.0,
        Check::Between(0.0, 1.0),
    )
}

/// The largest mean speed of `bodies` over the last [`REST_WINDOW`] seconds of the run
/// (displacement over time): "at rest" in resting contact, where microcollisions keep the
/// instantaneous speed jittering.
fn max_mean_speed(rec: &Recording, bodies: &[usize]) -> Result<f64, String> {
    let last = rec.frames.last().ok_or("no frames")?;
    let first = rec
        .frames
        .iter()
        .find(|f| f.time >= last.time - REST_WINDOW)
        .ok_or("no frames")?;
    let span = last.time - first.time;
    Ok(bodies
        .iter()
        .map(|&i| (last.bodies[i].position - first.bodies[i].position).length() / span)
        .fold(0.0, f64::max))
}

/// Least-squares line `y = a + b·x`.
fn fit_line(points: &[(f64, f64)]) -> (f64, f64) {
    let n = points.len() as f64;
    let (sx, sy) = points
        .iter()
        .fold((0.0, 0.0), |(sx, sy), (x, y)| (sx + x, sy + y));
    let (mx, my) = (sx / n, sy / n);
    let (sxy, sxx) = points.iter().fold((0.0, 0.0), |(a, b), (x, y)| {
        (a + (x - mx) * (y - my), b + (x - mx) * (x - mx))
    });
    let slope = sxy / sxx;
    (my - slope * mx, slope)
}

fn v6_block_on_ramp(world: &World, rec: &Recording) -> Result<Vec<Metric>, String> {
    let b = body(world, "block")?;
    let (g, mu, v0) = (981.0f64, 0.9f64, 548.0f64);
    let th = 30f64.to_radians();
    let a = g * (mu * th.cos() - th.sin());
    let (t_ref, d_ref) = (v0 / a, v0 * v0 / (2.0 * a));
    let down = DVec3::new(th.cos(), 0.0, -th.sin());
    let x0 = rec.frames[0].bodies[b].position;
    let s = |k: usize| (rec.frames[k].bodies[b].position - x0).dot(down);
    // Velocity along the ramp by central differences over the sliding phase (0.2 s–1.6 s),
    // fitted by a line v = v0' − a'·t: its zero is the stop time, its area the distance.
    let pts: Vec<(f64, f64)> = (1..rec.frames.len() - 1)
        .filter(|&k| (0.2..=1.6).contains(&rec.frames[k].time))
        .map(|k| {
            let dt = rec.frames[k + 1].time - rec.frames[k - 1].time;
            (rec.frames[k].time, (s(k + 1) - s(k - 1)) / dt)
        })
        .collect();
    let (v_fit, slope) = fit_line(&pts);
    let t_stop = -v_fit / slope;
    let d_stop = -v_fit * v_fit / (2.0 * slope);
    let at = |t: f64| {
        rec.frames
            .iter()
            .position(|f| f.time >= t - 1e-9)
            .unwrap_or(rec.frames.len() - 1)
    };
    let (k25, kend) = (at(2.5), rec.frames.len() - 1);
    Ok(vec![
        Metric::new("deceleration", -slope, a, Check::Rel(SCENE_REL)),
        Metric::new("stop_time", t_stop, t_ref, Check::Rel(SCENE_REL)),
        Metric::new("stop_distance_fit", d_stop, d_ref, Check::Rel(SCENE_REL)),
        Metric::new("distance_at_2.5s", s(k25), d_ref, Check::Rel(SCENE_REL)),
        Metric::new(
            "creep_2.5s_to_5s_rel",
            (s(kend) - s(k25)) / d_ref,
            0.0,
            Check::Between(-CREEP_REL, CREEP_REL),
        ),
        no_penetration(world, rec),
    ])
}

fn v7_sliding_to_rolling(world: &World, rec: &Recording) -> Result<Vec<Metric>, String> {
    let b = body(world, "ball")?;
    let (v0, mu, g) = (5.0f64, 0.2f64, 9.81f64);
    let t_ref = 2.0 * v0 / (7.0 * mu * g);
    let s_ref = 12.0 * v0 * v0 / (49.0 * mu * g);
    let v_ref = 5.0 * v0 / 7.0;
    let x0 = rec.frames[0].bodies[b].position.x;
    // Sliding: a line through the speeds before 0.8·t*; rolling: the mean after 1.3·t*.
    let sliding: Vec<(f64, f64)> = rec
        .frames
        .iter()
        .filter(|f| f.time > 0.05 && f.time < 0.8 * t_ref)
        .map(|f| (f.time, f.bodies[b].velocity.x))
        .collect();
    let rolling: Vec<f64> = rec
        .frames
        .iter()
        .filter(|f| f.time > 1.3 * t_ref)
        .map(|f| f.bodies[b].velocity.x)
        .collect();
    let (v_start, slope) = fit_line(&sliding);
    let v_roll = rolling.iter().sum::<f64>() / rolling.len() as f64;
    let t_star = (v_roll - v_start) / slope;
    // Distance at t*: the sliding parabola.
    let s_star = v_start * t_star + 0.5 * slope * t_star * t_star;
    let last = rec.frames.last().ok_or("no frames")?;
    let spin = last.bodies[b].omega.y * 0.1; // ω·r of the rolling ball
    let travelled = last.bodies[b].position.x - x0;
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
        no_penetration(world, rec),
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

fn v8_platter(world: &World, rec: &Recording) -> Result<Vec<Metric>, String> {
    let b = body(world, "ball")?;
    let omega = 2.0 * std::f64::consts::PI;
    let pts: Vec<(f64, f64)> = rec
        .frames
        .iter()
        .map(|f| (f.bodies[b].position.x, f.bodies[b].position.y))
        .collect();
    let (cx, cy, r) = fit_circle(&pts);
    // Unwrapped angle about the fitted centre against time: its slope is the orbit rate.
    let mut angle = Vec::with_capacity(pts.len());
    let mut last = f64::NAN;
    let mut turns = 0.0;
    for (f, &(x, y)) in rec.frames.iter().zip(&pts) {
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
        angle.push((f.time, a + turns * 2.0 * std::f64::consts::PI));
    }
    let (_, rate) = fit_line(&angle);
    let drift = pts
        .iter()
        .map(|&(x, y)| ((x - cx).hypot(y - cy) - r).abs() / r)
        .fold(0.0, f64::max);
    Ok(vec![
        Metric::new(
            "orbit_rate",
            rate,
            2.0 * omega / 7.0,
            Check::Rel(ORBIT_RATE_REL),
        ),
        Metric::new(
            "radius_drift_rel",
            drift,
            0.0,
            Check::Between(0.0, ORBIT_RADIUS_DRIFT),
        ),
        Metric::new("orbit_radius", r, 0.1, Check::Rel(ORBIT_RADIUS_DRIFT)),
        no_penetration(world, rec),
    ])
}

/// Spin about the vertical of body `b` in every frame, with the frame times.
fn vertical_spin(rec: &Recording, b: usize) -> Vec<(f64, f64)> {
    rec.frames
        .iter()
        .map(|f| (f.time, f.bodies[b].omega.z))
        .collect()
}

/// Frames whose spin has the opposite sign of the first frame's.
fn reversed_frames(spin: &[(f64, f64)]) -> usize {
    let s0 = spin.first().map_or(0.0, |s| s.1);
    spin.iter().filter(|s| s.1 * s0 < 0.0).count()
}

fn v12_rattleback(world: &World, rec: &Recording) -> Result<Vec<Metric>, String> {
    let (t1, t2) = (body(world, "twin1")?, body(world, "twin2")?);
    let (rb, pref) = (body(world, "rattleback")?, body(world, "preferred")?);
    // Twins: the angle of the rotation taking one's orientation to the other's.
    let phase = rec
        .frames
        .iter()
        .map(|f| {
            let q = f.bodies[t1].rotation.inverse() * f.bodies[t2].rotation;
            q.to_axis_angle().1.to_degrees()
        })
        .map(|a| if a > 180.0 { 360.0 - a } else { a })
        .fold(0.0, f64::max);
    // The rattleback: revolutions turned (∫|ω_z| dt, trapezoids) until its spin first
    // changes sign.
    let spin = vertical_spin(rec, rb);
    let w0 = spin.first().ok_or("no frames")?.1;
    let mut turned = 0.0;
    let mut reversal = None;
    for pair in spin.windows(2) {
        let ((ta, wa), (tb, wb)) = (pair[0], pair[1]);
        if wb * w0 < 0.0 {
            // Up to the zero crossing, linearly interpolated.
            let tz = ta + (tb - ta) * wa / (wa - wb);
            turned += 0.5 * wa.abs() * (tz - ta);
            reversal = Some(tz);
            break;
        }
        turned += 0.5 * (wa.abs() + wb.abs()) * (tb - ta);
    }
    let revolutions = if reversal.is_some() {
        turned / std::f64::consts::TAU
    } else {
        f64::INFINITY
    };
    let final_ratio = |b: usize| -> Result<f64, String> {
        let s = vertical_spin(rec, b);
        let (first, last) = (
            s.first().ok_or("no frames")?.1,
            s.last().ok_or("no frames")?.1,
        );
        Ok(last / first)
    };
    Ok(vec![
        Metric::new(
            "revolutions_before_reversal",
            revolutions,
            2.0,
            Check::Between(REVERSAL_REVOLUTIONS.0, REVERSAL_REVOLUTIONS.1),
        ),
        Metric::new(
            "reversal_time",
            reversal.unwrap_or(f64::INFINITY),
            rec.frames.last().map_or(0.0, |f| f.time),
            Check::Between(0.0, rec.frames.last().map_or(0.0, |f| f.time)),
        ),
        Metric::new(
            "rattleback_final_spin_ratio",
            final_ratio(rb)?,
            -1.0,
            Check::Between(-2.0, -SPIN_KEPT),
        ),
        Metric::new(
            "preferred_reversed_frames",
            reversed_frames(&vertical_spin(rec, pref)) as f64,
            0.0,
            Check::Exact,
        ),
        Metric::new(
            "preferred_final_spin_ratio",
            final_ratio(pref)?,
            1.0,
            Check::Between(SPIN_KEPT, 1.0 + 1e-3),
        ),
        Metric::new(
            "twins_reversed_frames",
            (reversed_frames(&vertical_spin(rec, t1)) + reversed_frames(&vertical_spin(rec, t2)))
                as f64,
            0.0,
            Check::Exact,
        ),
        Metric::new(
            "twin_phase_degrees",
            phase,
            0.0,
            Check::Between(0.0, TWIN_PHASE_DEGREES),
        ),
        no_penetration(world, rec),
    ])
}

fn v9_two_ball(world: &World, rec: &Recording) -> Result<Vec<Metric>, String> {
    let (a, b) = (body(world, "striker")?, body(world, "target")?);
    let (v0, e) = (2.0, 0.6);
    let last = rec.frames.last().ok_or("no frames")?;
    Ok(vec![
        Metric::new(
            "striker_v",
            last.bodies[a].velocity.x,
            v0 * (1.0 - e) / 2.0,
            Check::Abs(TWO_BALL_REL * v0),
        ),
        Metric::new(
            "target_v",
            last.bodies[b].velocity.x,
            v0 * (1.0 + e) / 2.0,
            Check::Abs(TWO_BALL_REL * v0),
        ),
        Metric::new(
            "collisions",
            rec.counters.collisions as f64,
            1.0,
            Check::Exact,
        ),
    ])
}

fn v10_chain(world: &World, rec: &Recording) -> Result<Vec<Metric>, String> {
    let v0 = 2.0;
    let last = rec.frames.last().ok_or("no frames")?;
    let v = |name: &str| -> Result<DVec3, String> { Ok(last.bodies[body(world, name)?].velocity) };
    let mut m = vec![
        Metric::new(
            "far_ball_speed_over_v0",
            v("ball4")?.x / v0,
            1.0,
            Check::Between(CHAIN_FAR_MIN, 1.0 + 1e-9),
        ),
        Metric::new(
            "striker_vx_over_v0",
            v("striker")?.x / v0,
            0.0,
            Check::Between(-CHAIN_ROUNDING, CHAIN_STILL_REL),
        ),
    ];
    for name in ["ball1", "ball2", "ball3"] {
        m.push(Metric::new(
            format!("{name}_speed_over_v0"),
            v(name)?.length() / v0,
            0.0,
            Check::Between(0.0, CHAIN_STILL_REL),
        ));
    }
    m.push(no_penetration(world, rec));
    Ok(m)
}

fn v13_block_drop(world: &World, rec: &Recording) -> Result<Vec<Metric>, String> {
    let (lo, up) = (body(world, "lower")?, body(world, "upper")?);
    let last = rec.frames.last().ok_or("no frames")?;
    // The upper block falls ~0.26 m before it first hits: impact speed √(2·g·h).
    let v_impact = (2.0f64 * 9.81 * 0.26).sqrt();
    // Resting contact is a train of microcollisions: each one leaves a body moving at up to
    // the candidate speed √(2·g·ε_c) (eq. 3.18), so "at rest" is judged on the mean velocity
    // over the last REST_WINDOW seconds, and the jitter separately against that speed.
    let k0 = rec
        .frames
        .iter()
        .position(|f| f.time >= last.time - REST_WINDOW)
        .ok_or("no frames")?;
    let first = &rec.frames[k0];
    let span = last.time - first.time;
    let mean_speed =
        |i: usize| (last.bodies[i].position - first.bodies[i].position).length() / span;
    let jitter = rec.frames[k0..]
        .iter()
        .flat_map(|f| {
            [
                f.bodies[lo].velocity.length(),
                f.bodies[up].velocity.length(),
            ]
        })
        .fold(0.0, f64::max);
    let v_micro = (2.0 * 9.81 * world.collision_epsilon()).sqrt();
    let (bl, bu) = (last.bodies[lo], last.bodies[up]);
    Ok(vec![
        Metric::new(
            "lower_mean_speed_rel",
            mean_speed(lo) / v_impact,
            0.0,
            Check::Between(0.0, REST_REL),
        ),
        Metric::new(
            "upper_mean_speed_rel",
            mean_speed(up) / v_impact,
            0.0,
            Check::Between(0.0, REST_REL),
        ),
        Metric::new(
            "jitter_over_microcollision_speed",
            jitter / v_micro,
            0.0,
            Check::Between(0.0, JITTER_MAX),
        ),
        Metric::new(
            "upper_on_lower",
            f64::from(u8::from(bu.position.z > bl.position.z + 0.05)),
            1.0,
            Check::Exact,
        ),
        no_penetration(world, rec),
    ])
}

fn v15_elastic(world: &World, rec: &Recording) -> Result<Vec<Metric>, String> {
    let e0 = rec.frames[0].kinetic_energy;
    let worst = rec
        .frames
        .iter()
        .map(|f| (f.kinetic_energy - e0).abs() / e0)
        .fold(0.0, f64::max);
    Ok(vec![
        Metric::new(
            "max_energy_change_rel",
            worst,
            0.0,
            Check::Between(0.0, ELASTIC_ENERGY_REL),
        ),
        Metric::new(
            "collisions_positive",
            f64::from(u8::from(rec.counters.collisions > 100)),
            1.0,
            Check::Exact,
        ),
        no_penetration(world, rec),
    ])
}

fn v15_dissipative(world: &World, rec: &Recording) -> Result<Vec<Metric>, String> {
    let e0 = rec.frames[0].kinetic_energy;
    let rise = rec
        .frames
        .windows(2)
        .map(|w| (w[1].kinetic_energy - w[0].kinetic_energy) / e0)
        .fold(0.0, f64::max);
    let last = rec.frames.last().ok_or("no frames")?;
    Ok(vec![
        Metric::new(
            "max_energy_rise_rel",
            rise,
            0.0,
            Check::Between(0.0, MONOTONE_ENERGY_REL),
        ),
        Metric::new(
            "energy_dissipated",
            f64::from(u8::from(last.kinetic_energy < 0.9 * e0)),
            1.0,
            Check::Exact,
        ),
        no_penetration(world, rec),
    ])
}

fn bullet(world: &World, rec: &Recording) -> Result<Vec<Metric>, String> {
    let last = rec.frames.last().ok_or("no frames")?;
    let half_thickness = 0.0005;
    let (b1, b2) = (body(world, "bullet")?, body(world, "rim-bullet")?);
    // The aimed bullet must come back: still on the near side, moving away.
    let back = last.bodies[b1].position.x < -half_thickness && last.bodies[b1].velocity.x < 0.0;
    Ok(vec![
        Metric::new(
            "bullet_bounced",
            f64::from(u8::from(back)),
            1.0,
            Check::Exact,
        ),
        Metric::new(
            "rim_bullet_deflected",
            f64::from(u8::from(last.bodies[b2].velocity.x < 999.0)),
            1.0,
            Check::Exact,
        ),
        no_penetration(world, rec),
    ])
}

fn v14_pool(world: &World, rec: &Recording) -> Result<Vec<Metric>, String> {
    let is_ball =
        |i: usize| world.bodies()[i].name.starts_with("ball") || world.bodies()[i].name == "cue";
    let (mut n, mut worst_p, mut worst_e) = (0u32, 0.0f64, f64::NEG_INFINITY);
    for e in world.events() {
        if e.kind != ContactKind::Collision || !is_ball(e.a) || !is_ball(e.b) {
            continue;
        }
        n += 1;
        let scale = e.momentum_before.length().max(e.impulse.length());
        worst_p = worst_p.max((e.momentum_after - e.momentum_before).length() / scale);
        worst_e = worst_e.max((e.energy_after - e.energy_before) / e.energy_before);
    }
    let last = rec.frames.last().ok_or("no frames")?;
    let on_table = last
        .bodies
        .iter()
        .enumerate()
        .filter(|(i, _)| is_ball(*i))
        .all(|(_, b)| b.position.z > 0.0 && b.position.x.abs() < 1.3 && b.position.y.abs() < 0.65);
    Ok(vec![
        Metric::new(
            "ball_ball_collisions_at_least_15",
            f64::from(u8::from(n >= 15)),
            1.0,
            Check::Exact,
        ),
        Metric::new(
            "max_momentum_error_rel",
            worst_p,
            0.0,
            Check::Between(0.0, POOL_MOMENTUM_REL),
        ),
        Metric::new(
            "max_energy_gain_rel",
            worst_e,
            0.0,
            Check::Between(-1.0, POOL_ENERGY_REL),
        ),
        Metric::new(
            "all_balls_on_table",
            f64::from(u8::from(on_table)),
            1.0,
            Check::Exact,
        ),
        no_penetration(world, rec),
    ])
}

fn v16_dominos(world: &World, rec: &Recording) -> Result<Vec<Metric>, String> {
    let ids: Vec<usize> = (1..=7)
        .map(|k| body(world, &format!("domino{k}")))
        .collect::<Result<_, _>>()?;
    // Tilt: the angle between the domino's long axis (its smallest principal moment, axis 0
    // of the body frame) and the vertical.
    let tilt = |f: &impulse_sim::Frame, i: usize| {
        let axis = f.bodies[i].rotation * DVec3::X;
        axis.z.abs().clamp(0.0, 1.0).acos()
    };
    let fallen = TOPPLE_DEGREES.to_radians();
    let times: Vec<f64> = ids
        .iter()
        .map(|&i| {
            rec.frames
                .iter()
                .find(|f| tilt(f, i) > fallen)
                .map_or(f64::INFINITY, |f| f.time)
        })
        .collect();
    let in_order = times.windows(2).all(|w| w[0] < w[1]) && times.iter().all(|t| t.is_finite());
    let v_fall = (2.0f64 * 9.81 * 0.048).sqrt();
    let mean_speed = max_mean_speed(rec, &ids)?;
    Ok(vec![
        Metric::new(
            "topple_in_order",
            f64::from(u8::from(in_order)),
            1.0,
            Check::Exact,
        ),
        Metric::new("last_topple_time", times[6], 1.2, Check::Between(0.0, 1.2)),
        Metric::new(
            "max_mean_speed_rel",
            mean_speed / v_fall,
            0.0,
            Check::Between(0.0, REST_REL),
        ),
        no_penetration(world, rec),
    ])
}

fn v17_coins(world: &World, rec: &Recording) -> Result<Vec<Metric>, String> {
    let coins: Vec<usize> = (0..world.bodies().len())
        .filter(|&i| world.bodies()[i].is_dynamic())
        .collect();
    let last = rec.frames.last().ok_or("no frames")?;
    // A coin's axis is its largest principal moment: axis 2 of the body frame.
    let worst_tilt = coins
        .iter()
        .map(|&i| {
            (last.bodies[i].rotation * DVec3::Z)
                .z
                .abs()
                .clamp(0.0, 1.0)
                .acos()
                .to_degrees()
        })
        .fold(0.0, f64::max);
    let v_roll = 0.25;
    let mean_speed = max_mean_speed(rec, &coins)?;
    Ok(vec![
        Metric::new(
            "worst_tilt_degrees",
            worst_tilt,
            0.0,
            Check::Between(0.0, FLAT_DEGREES),
        ),
        Metric::new(
            "max_mean_speed_rel",
            mean_speed / v_roll,
            0.0,
            Check::Between(0.0, REST_REL),
        ),
        no_penetration(world, rec),
    ])
}

fn feeder_chute(world: &World, rec: &Recording) -> Result<Vec<Metric>, String> {
    let caps: Vec<usize> = (0..world.bodies().len())
        .filter(|&i| world.bodies()[i].is_dynamic())
        .collect();
    let last = rec.frames.last().ok_or("no frames")?;
    // The floor's top is at z = −0.10; the chute's lowest point is above z = 0.
    let on_floor = caps
        .iter()
        .filter(|&&i| last.bodies[i].position.z < 0.0)
        .count();
    let v_slide = (2.0f64 * 9.81 * 0.2).sqrt();
    let mean_speed = max_mean_speed(rec, &caps)?;
    Ok(vec![
        Metric::new(
            "caps_on_floor",
            on_floor as f64,
            caps.len() as f64,
            Check::Exact,
        ),
        Metric::new(
            "max_mean_speed_rel",
            mean_speed / v_slide,
            0.0,
            Check::Between(0.0, REST_REL),
        ),
        no_penetration(world, rec),
    ])
}

fn v11_dish(world: &World, rec: &Recording) -> Result<Vec<Metric>, String> {
    let dish = body(world, "dish")?;
    let balls: Vec<usize> = (0..world.bodies().len()).filter(|&i| i != dish).collect();
    let r = 0.02;
    let bodies = world.bodies();
    let centre = |i: usize| bodies[i].pose.translation;
    // Contacts (see DISH_CONTACT_GAP_REL): a pair counts when its gap averaged over the last
    // REST_WINDOW seconds is below 1 % of r; ball–dish gaps use the exact distance to the dish
    // (a ball resting on the others instead of the dish would be millimetres away).
    let last = rec.frames.last().ok_or("no frames")?;
    let window: Vec<&impulse_sim::Frame> = rec
        .frames
        .iter()
        .filter(|f| f.time >= last.time - REST_WINDOW)
        .collect();
    let mut ball_ball = 0;
    for (k, &i) in balls.iter().enumerate() {
        for &j in &balls[k + 1..] {
            let gap = window
                .iter()
                .map(|f| f.bodies[i].position.distance(f.bodies[j].position) - 2.0 * r)
                .sum::<f64>()
                / window.len() as f64;
            if gap < DISH_CONTACT_GAP_REL * r {
                ball_ball += 1;
            }
        }
    }
    let mut cache = impulse_collide::PairCache::default();
    let ball_dish = balls
        .iter()
        .filter(|&&i| {
            let gap = window
                .iter()
                .map(|f| {
                    let s = f.bodies[i];
                    let pose = impulse_geom::Pose::new(s.rotation, s.position);
                    impulse_collide::shape::closest(
                        &bodies[dish].shape,
                        &bodies[dish].pose,
                        &bodies[i].shape,
                        &pose,
                        &mut cache,
                    )
                    .closest
                    .distance
                })
                .sum::<f64>()
                / window.len() as f64;
            gap < DISH_CONTACT_GAP_REL * r
        })
        .count();
    // The centre ball: the one nearest the axis; the others' bearings around it.
    let axis_dist = |i: usize| centre(i).truncate().length();
    let &mid = balls
        .iter()
        .min_by(|&&a, &&b| axis_dist(a).total_cmp(&axis_dist(b)))
        .ok_or("no balls")?;
    let mut bearings: Vec<f64> = balls
        .iter()
        .filter(|&&i| i != mid)
        .map(|&i| {
            let d = centre(i) - centre(mid);
            d.y.atan2(d.x).to_degrees()
        })
        .collect();
    bearings.sort_by(f64::total_cmp);
    let worst_gap = bearings
        .iter()
        .enumerate()
        .map(|(k, b)| {
            let next = if k + 1 < bearings.len() {
                bearings[k + 1]
            } else {
                bearings[0] + 360.0
            };
            ((next - b) - 60.0).abs()
        })
        .fold(0.0, f64::max);
    let m = 7800.0 * 4.0 / 3.0 * std::f64::consts::PI * r * r * r;
    let ke_rel = last.kinetic_energy / (balls.len() as f64 * m * 9.81 * r);
    Ok(vec![
        Metric::new(
            "ball_ball_contacts",
            f64::from(ball_ball),
            12.0,
            Check::Exact,
        ),
        Metric::new("ball_dish_contacts", ball_dish as f64, 7.0, Check::Exact),
        Metric::new(
            "centre_ball_off_axis_over_r",
            axis_dist(mid) / r,
            0.0,
            Check::Between(0.0, 0.1),
        ),
        Metric::new(
            "worst_bearing_error_degrees",
            worst_gap,
            0.0,
            Check::Between(0.0, DISH_BEARING_DEGREES),
        ),
        Metric::new(
            "kinetic_energy_over_7mgr",
            ke_rel,
            0.0,
            Check::Between(0.0, REST_REL),
        ),
        no_penetration(world, rec),
    ])
}

fn determinism() -> Result<Vec<Metric>, String> {
    let mut hashes = Vec::new();
    for threads in [1, 2] {
        let (scene, mut world) = load("tumbling-box-elastic")?;
        world.set_threads(threads).map_err(|e| e.to_string())?;
        let rec =
            run(&mut world, 0.5, scene.desc.output_rate, |_| {}).map_err(|e| e.to_string())?;
        hashes.push(rec.hash());
    }
    Ok(vec![Metric::new(
        "hash_1_thread_equals_2_threads",
        f64::from(u8::from(hashes[0] == hashes[1])),
        1.0,
        Check::Exact,
    )])
}
