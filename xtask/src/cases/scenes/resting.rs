//! Bodies that must come to rest: V11 balls in dish, V13 block drop, V16 dominos, V17 coins,
//! the feeder chute, the plank bridge.

use glam::DVec3;
use impulse_sim::scene::ShapeDesc;

use super::{
    REST_REL, REST_WINDOW, Run, SceneCheck, half_extents, holds, longest_axis, max_mean_speed,
    no_penetration, sphere_radius,
};
use crate::validate::case::{Check, Metric};

/// V11: two bodies are in contact when their gap at the end of the run is below this many ε_c
/// (digest: 2ε_c at one instant; resting contact vibrates with an amplitude of about ε_c,
/// thesis §3.5, while the nearest pair not in contact is 2r(√3 − 1) = 1.46 r apart).
const DISH_CONTACT_GAP_EPS: f64 = 2.0;
/// V11: the centre ball lies within this fraction of r from the dish axis (digest r/10).
const DISH_CENTRE_REL: f64 = 0.1;
/// V11: the six outer balls lie 60° ± this apart around the centre ball (digest ±5°).
const DISH_BEARING_DEGREES: f64 = 5.0;
/// V16: a domino has toppled when its long axis leans more than this from the vertical.
const TOPPLE_DEGREES: f64 = 45.0;
/// V16: the last domino falls before this time (s; thesis Table 7.1 simulates 1.2 s).
const LAST_TOPPLE_BY: f64 = 1.2;
/// V17: a coin lies flat when its axis is within this many degrees of the vertical (digest).
const FLAT_DEGREES: f64 = 5.0;
/// V13: largest instantaneous speed at rest, in units of the microcollision candidate speed
/// √(2·g·ε_c): a microcollision with boosted restitution (up to e_max = 5 at full envelope
/// depth) can send a body off at a few times that speed.
const JITTER_MAX: f64 = 5.0;
/// Plank bridge: a body rests on another when its bottom lies within this many ε_c of the
/// other's top (the contact envelope, with room for the rest gap of the switching model).
const RESTS_ON_EPS: f64 = 2.0;

pub(super) fn checks() -> Vec<SceneCheck> {
    vec![
        SceneCheck {
            case: "V16-dominos",
            scene: "dominos",
            description: "seven dominos: topple in order along the row, all down and at rest at the end, no interpenetration",
            headline: "max_mean_speed_rel",
            event_log: false,
            thesis: Some(("dominos", 3.1)),
            metrics: v16_dominos,
        },
        SceneCheck {
            case: "V17-coins",
            scene: "coins",
            description: "eight coins rolled and tossed onto a plate: all end flat (within 5°) and at rest, no interpenetration",
            headline: "worst_tilt_degrees",
            event_log: false,
            thesis: Some(("coins", 4.6)),
            metrics: v17_coins,
        },
        SceneCheck {
            case: "feeder-chute",
            scene: "feeder-chute",
            description: "six non-convex caps slide down a converging chute: all reach the floor and stop, no interpenetration",
            headline: "max_mean_speed_rel",
            event_log: false,
            thesis: Some(("part feeder chute", 6.6)),
            metrics: feeder_chute,
        },
        SceneCheck {
            case: "plank-bridge",
            scene: "plank-bridge",
            description: "a plank on two blocks with a box on it, a steel ball dropped onto the plank: the bridge stands (each body within 2 ε_c of the top it rests on) and comes to rest, no interpenetration",
            headline: "bridge_mean_speed_rel",
            event_log: false,
            thesis: None,
            metrics: plank_bridge,
        },
        SceneCheck {
            case: "V11-balls-in-dish",
            scene: "balls-in-dish",
            description: "seven balls dropped into a dish end as one at the centre and six around at 60°, with exactly 12 ball–ball and 7 ball–dish contacts (gap < 2 ε_c at the end), at rest",
            headline: "centre_ball_off_axis_over_r",
            event_log: false,
            thesis: Some(("balls in dish", 2.4)),
            metrics: v11_dish,
        },
        SceneCheck {
            case: "V13-block-drop",
            scene: "block-drop",
            description: "two blocks dropped on a floor end stacked and at rest (mean speed < 1 % of impact speed) with no interpenetration",
            headline: "upper_mean_speed_rel",
            event_log: false,
            thesis: Some(("block drop", 0.5)),
            metrics: v13_block_drop,
        },
    ]
}

/// The top of a fixed box (world z of its highest point), for an axis-aligned floor.
fn top_of(r: &Run<'_>, name: &str) -> Result<f64, String> {
    let d = r.desc(name)?;
    Ok(d.position[2] + half_extents(d)?.z)
}

/// The angle (degrees) between the body-frame axis `axis` of recording index `i` in frame `f`
/// and the vertical.
fn tilt(f: &impulse_sim::Frame, i: usize, axis: DVec3) -> f64 {
    (f.bodies[i].rotation * axis)
        .z
        .abs()
        .clamp(0.0, 1.0)
        .acos()
        .to_degrees()
}

/// V13. Resting contact is a train of microcollisions: each one leaves a body moving at up to
/// the candidate speed √(2·g·ε_c) (eq. 3.18), so "at rest" is judged on the mean velocity
/// over the last [`REST_WINDOW`] seconds, and the jitter separately against that speed. The
/// reference speed is the upper block's impact speed √(2·g·h), h its fall onto the lower block
/// resting on the floor (from the scene).
fn v13_block_drop(r: &Run<'_>) -> Result<Vec<Metric>, String> {
    let (lo, up) = (r.index("lower")?, r.index("upper")?);
    let (dl, du) = (r.desc("lower")?, r.desc("upper")?);
    let landing = top_of(r, "floor")? + 2.0 * half_extents(dl)?.z;
    let h = du.position[2] - half_extents(du)?.z - landing;
    let v_impact = (2.0 * r.g() * h).sqrt();
    let frames = &r.rec.frames;
    let last = r.last()?;
    let k0 = frames
        .iter()
        .position(|f| f.time >= last.time - REST_WINDOW)
        .ok_or("no frames")?;
    let jitter = frames[k0..]
        .iter()
        .flat_map(|f| {
            [
                f.bodies[lo].velocity.length(),
                f.bodies[up].velocity.length(),
            ]
        })
        .fold(0.0, f64::max);
    let v_micro = (2.0 * r.g() * r.world.collision_epsilon()).sqrt();
    let (bl, bu) = (last.bodies[lo], last.bodies[up]);
    Ok(vec![
        Metric::new(
            "lower_mean_speed_rel",
            max_mean_speed(r.rec, &[lo])? / v_impact,
            0.0,
            Check::Between(0.0, REST_REL),
        ),
        Metric::new(
            "upper_mean_speed_rel",
            max_mean_speed(r.rec, &[up])? / v_impact,
            0.0,
            Check::Between(0.0, REST_REL),
        ),
        Metric::new(
            "jitter_over_microcollision_speed",
            jitter / v_micro,
            0.0,
            Check::Between(0.0, JITTER_MAX),
        ),
        holds(
            "upper_on_lower",
            bu.com.z > bl.com.z + half_extents(dl)?.z
                && (bu.com - bl.com).truncate().length() < half_extents(dl)?.x,
        ),
        no_penetration(r),
    ])
}

/// V16. A domino's long axis is its box's longest half extent (in its own frame); the fall
/// speed scale is √(2·g·height).
fn v16_dominos(r: &Run<'_>) -> Result<Vec<Metric>, String> {
    let mut names: Vec<&str> = r
        .scene
        .desc
        .bodies
        .iter()
        .filter(|b| b.name.starts_with("domino"))
        .map(|b| b.name.as_str())
        .collect();
    // Along the row: by position.
    names.sort_by(|a, b| {
        let x = |n: &str| r.desc(n).map_or(0.0, |d| d.position[0]);
        x(a).total_cmp(&x(b))
    });
    let ids: Vec<usize> = names.iter().map(|n| r.index(n)).collect::<Result<_, _>>()?;
    let h = half_extents(r.desc(names[0])?)?;
    let long = longest_axis(h);
    let times: Vec<f64> = ids
        .iter()
        .map(|&i| {
            r.rec
                .frames
                .iter()
                .find(|f| tilt(f, i, long) > TOPPLE_DEGREES)
                .map_or(f64::INFINITY, |f| f.time)
        })
        .collect();
    let in_order = times.windows(2).all(|w| w[0] < w[1]) && times.iter().all(|t| t.is_finite());
    let v_fall = (2.0 * r.g() * 2.0 * h.max_element()).sqrt();
    let last_time = times.last().copied().unwrap_or(f64::INFINITY);
    Ok(vec![
        holds("topple_in_order", in_order),
        Metric::new(
            "last_topple_time",
            last_time,
            LAST_TOPPLE_BY,
            Check::Between(0.0, LAST_TOPPLE_BY),
        ),
        Metric::new(
            "max_mean_speed_rel",
            max_mean_speed(r.rec, &ids)? / v_fall,
            0.0,
            Check::Between(0.0, REST_REL),
        ),
        no_penetration(r),
    ])
}

/// V17. A coin's axis is its prism's z; the speed scale is the fastest launch in the scene.
fn v17_coins(r: &Run<'_>) -> Result<Vec<Metric>, String> {
    let coins = r.dynamic();
    let last = r.last()?;
    let worst_tilt = coins
        .iter()
        .map(|&i| tilt(last, i, DVec3::Z))
        .fold(0.0, f64::max);
    let v_launch = r
        .scene
        .desc
        .bodies
        .iter()
        .map(|b| DVec3::from_array(b.velocity).length())
        .fold(0.0, f64::max);
    Ok(vec![
        Metric::new(
            "worst_tilt_degrees",
            worst_tilt,
            0.0,
            Check::Between(0.0, FLAT_DEGREES),
        ),
        Metric::new(
            "max_mean_speed_rel",
            max_mean_speed(r.rec, &coins)? / v_launch,
            0.0,
            Check::Between(0.0, REST_REL),
        ),
        no_penetration(r),
    ])
}

/// Feeder chute: a cap is on the floor when its centre of mass is below the chute's lowest
/// point; the speed scale is the free-fall speed from the highest start to the floor.
fn feeder_chute(r: &Run<'_>) -> Result<Vec<Metric>, String> {
    let caps = r.dynamic();
    let last = r.last()?;
    let floor = top_of(r, "floor")?;
    // The tray's lowest corner: its centre less its box's extent along z.
    let tray = r.desc("tray")?;
    let m = glam::DMat3::from_quat(super::rotation(&tray.rotation));
    let h = half_extents(tray)?;
    let tray_bottom = tray.position[2] - (m.row(2).abs() * h).element_sum();
    let on_floor = caps
        .iter()
        .filter(|&&i| last.bodies[i].com.z < tray_bottom)
        .count();
    let start_height = caps
        .iter()
        .map(|&i| r.rec.frames[0].bodies[i].com.z - floor)
        .fold(0.0, f64::max);
    let v_fall = (2.0 * r.g() * start_height).sqrt();
    Ok(vec![
        Metric::new(
            "caps_on_floor",
            on_floor as f64,
            caps.len() as f64,
            Check::Exact,
        ),
        Metric::new(
            "max_mean_speed_rel",
            max_mean_speed(r.rec, &caps)? / v_fall,
            0.0,
            Check::Between(0.0, REST_REL),
        ),
        no_penetration(r),
    ])
}

/// V11. Contacts: a pair counts when its gap at the last frame is below
/// [`DISH_CONTACT_GAP_EPS`]·ε_c: ball–ball gaps from the centres, ball–dish gaps by the exact
/// distance to the dish (a ball resting on the others instead of the dish would be
/// millimetres away).
fn v11_dish(r: &Run<'_>) -> Result<Vec<Metric>, String> {
    let dish_handle = r.world.handle("dish").ok_or("no dish")?;
    let dish = r.world.body(dish_handle).ok_or("no dish")?;
    let balls: Vec<usize> = r.dynamic();
    let first_ball = r
        .scene
        .desc
        .bodies
        .iter()
        .find(|b| matches!(b.shape, ShapeDesc::Sphere { .. }))
        .ok_or("no ball")?;
    let radius = sphere_radius(first_ball)?;
    let last = r.last()?;
    let limit = DISH_CONTACT_GAP_EPS * r.world.collision_epsilon();
    let mut ball_ball = 0;
    for (k, &i) in balls.iter().enumerate() {
        for &j in &balls[k + 1..] {
            if last.bodies[i].com.distance(last.bodies[j].com) - 2.0 * radius < limit {
                ball_ball += 1;
            }
        }
    }
    let mut cache = impulse_collide::PairCache::default();
    let ball_dish = balls
        .iter()
        .filter(|&&i| {
            let ball = r.world.body(r.rec.handles[i]).expect("a ball of the run");
            let pose = ball.pose_of(&last.bodies[i]);
            impulse_collide::shape::closest(&dish.shape, &dish.pose, &ball.shape, &pose, &mut cache)
                .closest
                .distance
                < limit
        })
        .count();
    // The centre ball: the one nearest the dish axis; the others' bearings around it.
    let axis = dish.pose.translation.truncate();
    let centre = |i: usize| last.bodies[i].com;
    let axis_dist = |i: usize| (centre(i).truncate() - axis).length();
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
            let next = bearings.get(k + 1).copied().unwrap_or(bearings[0] + 360.0);
            ((next - b) - 60.0).abs()
        })
        .fold(0.0, f64::max);
    let mass: f64 = balls
        .iter()
        .filter_map(|&i| r.world.body(r.rec.handles[i]).and_then(|b| b.mass))
        .map(|m| m.mass)
        .sum();
    let ke_rel = last.kinetic_energy / (mass * r.g() * radius);
    let n = balls.len();
    Ok(vec![
        Metric::new(
            "ball_ball_contacts",
            f64::from(ball_ball),
            // One at the centre, n − 1 around it in a closed ring: n − 1 spokes, n − 1 links.
            2.0 * (n - 1) as f64,
            Check::Exact,
        ),
        Metric::new(
            "ball_dish_contacts",
            ball_dish as f64,
            n as f64,
            Check::Exact,
        ),
        Metric::new(
            "centre_ball_off_axis_over_r",
            axis_dist(mid) / radius,
            0.0,
            Check::Between(0.0, DISH_CENTRE_REL),
        ),
        Metric::new(
            "worst_bearing_error_degrees",
            worst_gap,
            0.0,
            Check::Between(0.0, DISH_BEARING_DEGREES),
        ),
        Metric::new(
            "kinetic_energy_over_mgr",
            ke_rel,
            0.0,
            Check::Between(0.0, REST_REL),
        ),
        no_penetration(r),
    ])
}

/// Plank bridge. Heights come from the scene: a body rests on another when its lowest point
/// is within [`RESTS_ON_EPS`]·ε_c of the other's top, measured at the end for boxes that
/// have not turned (each block and the plank upright, the box on the plank); the speed scale
/// is the ball's impact speed √(2·g·h) onto the plank. (Energy: the switching model's bound
/// is checked by `impulse-sim`'s `energy_never_rises_beyond_the_stabilisation_bound`; the
/// impulse model's microcollisions may raise it by design, thesis eq. 3.18.)
fn plank_bridge(r: &Run<'_>) -> Result<Vec<Metric>, String> {
    let eps = r.world.collision_epsilon();
    let last = r.last()?;
    let top_z = |name: &str| -> Result<f64, String> {
        let i = r.index(name)?;
        Ok(last.bodies[i].com.z + half_extents(r.desc(name)?)?.z)
    };
    let bottom_z = |name: &str| -> Result<f64, String> {
        let i = r.index(name)?;
        Ok(last.bodies[i].com.z - half_extents(r.desc(name)?)?.z)
    };
    let rests = |upper: &str, lower: f64| -> Result<bool, String> {
        Ok((bottom_z(upper)? - lower).abs() <= RESTS_ON_EPS * eps)
    };
    let floor = top_of(r, "floor")?;
    let stands = rests("left", floor)?
        && rests("right", floor)?
        && rests("plank", top_z("left")?)?
        && rests("plank", top_z("right")?)?
        && rests("top", top_z("plank")?)?;
    let bridge: Vec<usize> = ["left", "right", "plank", "top"]
        .iter()
        .map(|n| r.index(n))
        .collect::<Result<_, _>>()?;
    let ball = r.desc("ball")?;
    let radius = sphere_radius(ball)?;
    let plank_top = r.desc("plank")?.position[2] + half_extents(r.desc("plank")?)?.z;
    let drop = ball.position[2] - radius - plank_top;
    let v_impact = (2.0 * r.g() * drop).sqrt();
    Ok(vec![
        holds("bridge_stands", stands),
        Metric::new(
            "bridge_mean_speed_rel",
            max_mean_speed(r.rec, &bridge)? / v_impact,
            0.0,
            Check::Between(0.0, REST_REL),
        ),
        no_penetration(r),
    ])
}
