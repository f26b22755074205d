//! The headline error of each peer scene, measured from a recorded trajectory, outside the
//! engine that made it: the same functions judge `impulse` and the peer.
//!
//! Every reference is computed from the scene description (gravity, μ, launch velocity,
//! geometry), never copied from the file's comments; the one exception is the dominos' last
//! topple time, which has no closed form ([`DOMINO_TOPPLE_REF`], from converged runs).

use glam::{DMat3, DQuat, DVec3};
use impulse_sim::SceneDesc;

pub(crate) use crate::cases::scenes::rotation as rotation_of;
use crate::cases::scenes::{half_extents, longest_axis, sphere_radius};
use impulse_sim::scene::{BodyDesc, ContactDesc, MassDesc, ShapeDesc};

/// A domino has toppled when its long axis leans more than this from the vertical (degrees;
/// the same criterion as validation case V16).
pub const TOPPLE_DEGREES: f64 = 45.0;
/// The converged time at which the last domino of `dominos.ron` topples (s): MuJoCo at 0.1 ms
/// and the pure-impulse mode both give 0.475–0.479 s. No closed form exists.
pub const DOMINO_TOPPLE_REF: (f64, f64) = (0.475, 0.479);
/// A ball rolls once the slip speed of its contact point is below this fraction of its launch
/// speed (the slip falls linearly from the launch speed to zero while it slides).
pub const ROLLING_SLIP_REL: f64 = 1e-2;
/// A block has stopped once its speed along the ramp is below this fraction of its launch
/// speed (it then has (1e-2)² = 1e-4 of the stop distance left to slide).
pub const STOP_SPEED_REL: f64 = 1e-2;
/// The creep after the stop is measured from this multiple of the reference stop time to the
/// end of the run (as validation case V6 does).
pub const AFTER_STOP_REL: f64 = 1.25;
/// A rack ball is struck when its horizontal speed exceeds this fraction of the cue ball's
/// launch speed (as validation case V14).
pub const STRUCK_REL: f64 = 1e-2;
/// The break window (s) after the first rack ball is struck over which momentum and energy are
/// compared (V14 uses 20 frames at 1 kHz).
pub const BREAK_WINDOW: f64 = 0.02;
/// A stack stands while its top block has drifted sideways less than this fraction of the
/// block's smallest horizontal half extent…
pub const STANDS_DRIFT_REL: f64 = 0.5;
/// …and its centre has dropped less than this fraction of the block's half height.
pub const STANDS_DROP_REL: f64 = 0.5;
/// Cross products of box axes shorter than this (unit axes: the sine of their angle) are
/// parallel edges and give no separating axis of their own.
const PARALLEL_AXES: f64 = 1e-9;

/// A body's state in a recorded frame, whichever engine recorded it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct State {
    /// Origin of the body's shape frame (world), as the scene places it.
    pub position: DVec3,
    /// Rotation of the shape frame (world).
    pub rotation: DQuat,
    /// Centre of mass (world).
    pub com: DVec3,
    /// Velocity of the centre of mass (world).
    pub velocity: DVec3,
    /// Angular velocity (world).
    pub omega: DVec3,
}

/// One recorded instant.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Simulated time (s).
    pub time: f64,
    /// Every body's state, in the order of [`Trajectory::names`].
    pub bodies: Vec<State>,
}

/// A recorded run: frames of every body, named.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Trajectory {
    /// Body names.
    pub names: Vec<String>,
    /// Frames in time order, the first at t = 0.
    pub frames: Vec<Frame>,
}

impl Trajectory {
    /// The index of body `name` in every frame.
    ///
    /// # Errors
    /// When no body has that name.
    pub fn index(&self, name: &str) -> Result<usize, String> {
        self.names
            .iter()
            .position(|n| n == name)
            .ok_or_else(|| format!("no body \"{name}\" in the trajectory"))
    }

    fn first(&self) -> Result<&Frame, String> {
        self.frames.first().ok_or_else(|| "no frames".to_string())
    }

    fn last(&self) -> Result<&Frame, String> {
        self.frames.last().ok_or_else(|| "no frames".to_string())
    }
}

/// One engine's headline error on one scene, with the numbers behind it.
#[derive(Clone, Debug, PartialEq)]
pub struct Measure {
    /// What [`Measure::error`] is.
    pub headline: &'static str,
    /// The headline error (relative unless `headline` says otherwise).
    pub error: f64,
    /// The measurements behind it, named, in the scene's units.
    pub details: Vec<(&'static str, f64)>,
    /// A verdict in words (stands, rolls, tunnelled…), empty when there is none.
    pub note: String,
}

#[cfg(test)]
impl Measure {
    /// The detail named `name`, if the measurement has it (the tests read them by name).
    pub fn detail(&self, name: &str) -> Option<f64> {
        self.details.iter().find(|d| d.0 == name).map(|d| d.1)
    }
}

/// The contact (μ, e) of two materials in a scene: their material pair's, else the default.
pub fn contact_of(scene: &SceneDesc, a: &str, b: &str) -> ContactDesc {
    scene
        .contacts
        .iter()
        .find(|c| (c.a == a && c.b == b) || (c.a == b && c.b == a))
        .map_or(scene.default_contact, |c| {
            ContactDesc::new(c.friction, c.restitution)
        })
}

fn body<'a>(scene: &'a SceneDesc, name: &str) -> Result<&'a BodyDesc, String> {
    scene
        .bodies
        .iter()
        .find(|b| b.name == name)
        .ok_or_else(|| format!("scene has no body \"{name}\""))
}

/// The up direction of a scene (against gravity) and the magnitude of gravity.
fn up_and_g(scene: &SceneDesc) -> (DVec3, f64) {
    let g = DVec3::from_array(scene.gravity);
    (-g.normalize_or(DVec3::NEG_Z), g.length())
}

/// Mass and inertia about the centre (body frame) of a sphere or a box, exactly; `None` for
/// other shapes.
pub fn mass_properties(b: &BodyDesc) -> Option<(f64, DMat3)> {
    let (volume, unit_inertia) = match b.shape {
        ShapeDesc::Sphere { radius } => {
            let i = 0.4 * radius * radius;
            (
                4.0 / 3.0 * std::f64::consts::PI * radius.powi(3),
                DMat3::from_diagonal(DVec3::splat(i)),
            )
        }
        ShapeDesc::Box { half_extents } => {
            let [x, y, z] = half_extents.map(|h| h * h);
            let third = 1.0 / 3.0;
            (
                8.0 * half_extents[0] * half_extents[1] * half_extents[2],
                DMat3::from_diagonal(DVec3::new(y + z, x + z, x + y) * third),
            )
        }
        _ => return None,
    };
    let mass = match b.mass {
        None => volume,
        Some(MassDesc::Density(rho)) => rho * volume,
        Some(MassDesc::Mass(m)) => m,
    };
    Some((mass, unit_inertia * mass))
}

/// The penetration depth of two boxes (centre, rotation, half extents): the smallest overlap
/// of their projections over the 15 separating axes of two boxes (3 + 3 face normals, 9 edge
/// cross products), which for convex polyhedra is the exact depth; 0 when they are apart.
pub fn box_penetration(a: (DVec3, DQuat, DVec3), b: (DVec3, DQuat, DVec3)) -> f64 {
    let (ca, qa, ha) = a;
    let (cb, qb, hb) = b;
    let ax = [qa * DVec3::X, qa * DVec3::Y, qa * DVec3::Z];
    let bx = [qb * DVec3::X, qb * DVec3::Y, qb * DVec3::Z];
    let radius = |axes: &[DVec3; 3], h: DVec3, l: DVec3| {
        h.x * axes[0].dot(l).abs() + h.y * axes[1].dot(l).abs() + h.z * axes[2].dot(l).abs()
    };
    let t = cb - ca;
    let mut depth = f64::INFINITY;
    let mut test = |l: DVec3| {
        let overlap = radius(&ax, ha, l) + radius(&bx, hb, l) - t.dot(l).abs();
        depth = depth.min(overlap);
    };
    for l in ax.iter().chain(&bx) {
        test(*l);
    }
    for u in &ax {
        for v in &bx {
            let c = u.cross(*v);
            let n = c.length();
            if n > PARALLEL_AXES {
                test(c / n);
            }
        }
    }
    depth.max(0.0)
}

/// Time at which `value` first reaches `level`, linearly interpolated between the two frames
/// around the crossing; `None` if it never does.
pub fn first_crossing(samples: &[(f64, f64)], level: f64) -> Option<f64> {
    let k = samples.iter().position(|&(_, v)| v >= level)?;
    if k == 0 {
        return Some(samples[0].0);
    }
    let ((t0, v0), (t1, v1)) = (samples[k - 1], samples[k]);
    Some(t0 + (level - v0) / (v1 - v0) * (t1 - t0))
}

/// The tilt (degrees) of a body's local `axis` from the vertical `up`.
pub fn tilt_degrees(rotation: DQuat, axis: DVec3, up: DVec3) -> f64 {
    (rotation * axis)
        .dot(up)
        .abs()
        .clamp(0.0, 1.0)
        .acos()
        .to_degrees()
}

/// The onset of rolling of a ball: time, distance travelled (horizontal, from the first frame)
/// and horizontal speed, from `(time, centre, velocity, angular velocity)` samples.
///
/// Rolling starts when the slip speed of the contact point, `|v + ω × (−r·up)|` in the
/// horizontal plane, first falls below [`ROLLING_SLIP_REL`]·`v0`. While the ball slides, the
/// slip, the speed and the distance follow the constant-friction motion, so the time is found
/// by extending the slip's line through the two frames before that to zero (kept within the
/// frame interval), and speed and distance by extending the sliding motion to that time. Exact
/// on an ideal trajectory, whatever the frame rate.
pub fn rolling_onset(
    samples: &[(f64, DVec3, DVec3, DVec3)],
    radius: f64,
    up: DVec3,
    v0: f64,
) -> Option<(f64, f64, f64)> {
    let horizontal = |v: DVec3| v - up * v.dot(up);
    let slip = |s: &(f64, DVec3, DVec3, DVec3)| horizontal(s.2 + s.3.cross(-radius * up)).length();
    let k = samples
        .iter()
        .position(|s| slip(s) <= ROLLING_SLIP_REL * v0)?;
    let x0 = horizontal(samples.first()?.1);
    let distance = |s: &(f64, DVec3, DVec3, DVec3)| (horizontal(s.1) - x0).length();
    let speed = |s: &(f64, DVec3, DVec3, DVec3)| horizontal(s.2).length();
    if k < 2 {
        let s = &samples[k];
        return Some((s.0, distance(s), speed(s)));
    }
    let (a, b) = (&samples[k - 2], &samples[k - 1]);
    let dt = b.0 - a.0;
    let slip_rate = (slip(b) - slip(a)) / dt;
    let t_end = samples[k].0;
    let t = if slip_rate < 0.0 {
        (b.0 - slip(b) / slip_rate).clamp(b.0, t_end)
    } else {
        t_end
    };
    let accel = (speed(b) - speed(a)) / dt;
    let h = t - b.0;
    let v = speed(b) + accel * h;
    let d = distance(b) + speed(b) * h + 0.5 * accel * h * h;
    Some((t, d, v))
}

/// Stacks: the top block's horizontal drift and the largest penetration between any two boxes
/// over the run, both in units of the scene's ε_c (the stack bench asks both ≤ ε_c; the
/// error is the larger of the two), and whether the stack still stands at the end (top block within [`STANDS_DRIFT_REL`] of its
/// half width sideways and [`STANDS_DROP_REL`] of its half height down).
///
/// # Errors
/// When the scene has no boxes or the trajectory no frames.
pub fn stack(scene: &SceneDesc, traj: &Trajectory) -> Result<Measure, String> {
    let (up, _) = up_and_g(scene);
    let boxes: Vec<(usize, DVec3)> = scene
        .bodies
        .iter()
        .filter_map(|b| {
            let h = half_extents(b).ok()?;
            Some((traj.index(&b.name).ok()?, h))
        })
        .collect();
    let top_name = &scene
        .bodies
        .iter()
        .filter(|b| b.motion == impulse_sim::scene::MotionDesc::Dynamic)
        .max_by(|a, b| {
            DVec3::from_array(a.position)
                .dot(up)
                .total_cmp(&DVec3::from_array(b.position).dot(up))
        })
        .ok_or("the stack has no blocks")?
        .name;
    let top = traj.index(top_name)?;
    let h_top = half_extents(body(scene, top_name)?)?;
    let (first, last) = (traj.first()?, traj.last()?);
    let d = last.bodies[top].com - first.bodies[top].com;
    let drop = -d.dot(up);
    let drift = (d - up * d.dot(up)).length();
    let mut penetration: f64 = 0.0;
    for f in &traj.frames {
        for (i, &(a, ha)) in boxes.iter().enumerate() {
            for &(b, hb) in &boxes[i + 1..] {
                let (sa, sb) = (&f.bodies[a], &f.bodies[b]);
                if (sa.com - sb.com).length() > ha.length() + hb.length() {
                    continue;
                }
                let depth = box_penetration((sa.com, sa.rotation, ha), (sb.com, sb.rotation, hb));
                penetration = penetration.max(depth);
            }
        }
    }
    let eps = scene.collision_epsilon;
    let stands =
        drift < STANDS_DRIFT_REL * h_top.x.min(h_top.y) && drop < STANDS_DROP_REL * h_top.z;
    Ok(Measure {
        headline: "max(top drift, penetration) / eps_c",
        error: drift.max(penetration) / eps,
        details: vec![
            ("top_drift", drift),
            ("max_penetration_over_eps_c", penetration / eps),
            ("stands", f64::from(u8::from(stands))),
        ],
        note: format!(
            "{} at {:.2} s; drift {:.2e}, penetration {:.2} eps_c",
            if stands { "stands" } else { "FALLEN" },
            last.time,
            drift,
            penetration / eps
        ),
    })
}

/// Dominos: the time the last domino of the row topples (its long axis passes
/// [`TOPPLE_DEGREES`] from the vertical), against [`DOMINO_TOPPLE_REF`]; the error is the
/// distance to that interval relative to its middle (0 inside it).
///
/// # Errors
/// When the scene has no dominos.
pub fn dominos(scene: &SceneDesc, traj: &Trajectory) -> Result<Measure, String> {
    let (up, _) = up_and_g(scene);
    let mut row: Vec<&BodyDesc> = scene
        .bodies
        .iter()
        .filter(|b| b.name.starts_with("domino"))
        .collect();
    row.sort_by(|a, b| a.position[0].total_cmp(&b.position[0]));
    let first = *row.first().ok_or("no dominos")?;
    let h = half_extents(first)?;
    let long = longest_axis(h);
    let mut times = Vec::with_capacity(row.len());
    for b in &row {
        let i = traj.index(&b.name)?;
        let tilt: Vec<(f64, f64)> = traj
            .frames
            .iter()
            .map(|f| (f.time, tilt_degrees(f.bodies[i].rotation, long, up)))
            .collect();
        times.push(first_crossing(&tilt, TOPPLE_DEGREES).unwrap_or(f64::INFINITY));
    }
    let in_order = times.windows(2).all(|w| w[0] < w[1]);
    let last = times.last().copied().unwrap_or(f64::INFINITY);
    let (lo, hi) = DOMINO_TOPPLE_REF;
    let error = if last.is_finite() {
        (lo - last).max(last - hi).max(0.0) / (0.5 * (lo + hi))
    } else {
        f64::INFINITY
    };
    let fallen = times.iter().filter(|t| t.is_finite()).count();
    Ok(Measure {
        headline: "last topple time vs 0.475-0.479 s",
        error,
        details: vec![
            ("last_topple_time", last),
            ("toppled", fallen as f64),
            ("in_order", f64::from(u8::from(in_order))),
        ],
        note: format!(
            "last topples at {last:.4} s; {fallen}/{} toppled{}",
            times.len(),
            if in_order {
                ", in order"
            } else {
                ", NOT in order"
            }
        ),
    })
}

/// Block on ramp: the distance slid until the block stops (its speed along the ramp first
/// below [`STOP_SPEED_REL`] of the launch speed) against v0²/(2a) with a = g(μ cos θ − sin θ),
/// the stop time against v0/a, and the creep speed from [`AFTER_STOP_REL`]·v0/a to the end.
///
/// # Errors
/// When the scene's μ cannot stop the block or the block never stops.
pub fn ramp(scene: &SceneDesc, traj: &Trajectory) -> Result<Measure, String> {
    let (block, ramp) = (body(scene, "block")?, body(scene, "ramp")?);
    let (up, g) = up_and_g(scene);
    let mu = contact_of(scene, &block.material, &ramp.material).friction;
    let v0 = DVec3::from_array(block.velocity).length();
    let normal = rotation_of(&ramp.rotation) * DVec3::Z;
    let theta = normal.dot(up).clamp(-1.0, 1.0).acos();
    let down = (-up + normal * up.dot(normal)).normalize();
    let a = g * (mu * theta.cos() - theta.sin());
    if a <= 0.0 {
        return Err(format!("μ = {mu} cannot stop the block"));
    }
    let (t_ref, d_ref) = (v0 / a, v0 * v0 / (2.0 * a));
    let b = traj.index("block")?;
    let x0 = traj.first()?.bodies[b].com;
    let s = |f: &Frame| (f.bodies[b].com - x0).dot(down);
    let stop = traj
        .frames
        .iter()
        .find(|f| f.bodies[b].velocity.dot(down) < STOP_SPEED_REL * v0)
        .ok_or("the block never stops")?;
    let (t_stop, d_stop) = (stop.time, s(stop));
    let last = traj.last()?;
    let after = traj
        .frames
        .iter()
        .find(|f| f.time >= AFTER_STOP_REL * t_ref)
        .ok_or("the run ends before the block can have stopped")?;
    let creep = if last.time > after.time {
        (s(last) - s(after)) / (last.time - after.time)
    } else {
        f64::NAN
    };
    Ok(Measure {
        headline: "stop distance rel",
        error: (d_stop - d_ref).abs() / d_ref,
        details: vec![
            ("stop_distance", d_stop),
            ("stop_distance_ref", d_ref),
            ("stop_time", t_stop),
            ("stop_time_ref", t_ref),
            ("creep_speed", creep),
        ],
        note: format!(
            "stops after {d_stop:.4} (ref {d_ref:.4}) at {t_stop:.4} s (ref {t_ref:.4}); creeps at {creep:.3e}/s"
        ),
    })
}

/// Sliding to rolling: time, distance and speed at the onset of rolling ([`rolling_onset`])
/// against t* = 2v0/(7μg), s* = 12v0²/(49μg), v* = 5v0/7 for a solid ball launched without
/// spin; the error is the largest of the three relative deviations.
///
/// # Errors
/// When the ball has no launch speed.
pub fn rolling(scene: &SceneDesc, traj: &Trajectory) -> Result<Measure, String> {
    let (ball, floor) = (body(scene, "ball")?, body(scene, "floor")?);
    let (up, g) = up_and_g(scene);
    let mu = contact_of(scene, &ball.material, &floor.material).friction;
    let radius = sphere_radius(ball)?;
    let v0 = DVec3::from_array(ball.velocity).length();
    if v0 == 0.0 {
        return Err("the ball is not launched".into());
    }
    let t_ref = 2.0 * v0 / (7.0 * mu * g);
    let s_ref = 12.0 * v0 * v0 / (49.0 * mu * g);
    let v_ref = 5.0 * v0 / 7.0;
    let b = traj.index("ball")?;
    let samples: Vec<(f64, DVec3, DVec3, DVec3)> = traj
        .frames
        .iter()
        .map(|f| {
            let s = f.bodies[b];
            (f.time, s.com, s.velocity, s.omega)
        })
        .collect();
    let Some((t, d, v)) = rolling_onset(&samples, radius, up, v0) else {
        return Ok(Measure {
            headline: "max rel err of t*, s*, v*",
            error: f64::INFINITY,
            details: vec![],
            note: "never rolls".into(),
        });
    };
    let rel = |x: f64, r: f64| (x - r).abs() / r;
    Ok(Measure {
        headline: "max rel err of t*, s*, v*",
        error: rel(t, t_ref).max(rel(d, s_ref)).max(rel(v, v_ref)),
        details: vec![
            ("t_star", t),
            ("t_star_ref", t_ref),
            ("s_star", d),
            ("s_star_ref", s_ref),
            ("v_star", v),
            ("v_star_ref", v_ref),
        ],
        note: format!(
            "rolls at {t:.4} s (ref {t_ref:.4}) after {d:.4} (ref {s_ref:.4}) at {v:.4} (ref {v_ref:.4})"
        ),
    })
}

/// Pool break: over [`BREAK_WINDOW`] from the last frame before the first rack ball is
/// struck, the change of the balls' total horizontal momentum beyond what the table's
/// friction can give (μ·g·Δt·M), relative to the cue ball's launch momentum, and the largest
/// rise of their kinetic energy relative to its value before the break; the error is the
/// larger of the two (0 when momentum is kept and no energy is made).
///
/// # Errors
/// When the scene has no cue ball.
pub fn pool(scene: &SceneDesc, traj: &Trajectory) -> Result<Measure, String> {
    const POOL_HEADLINE: &str = "max(momentum beyond friction / p_cue, energy gain)";
    let (up, g) = up_and_g(scene);
    let cue = body(scene, "cue")?;
    let table = body(scene, "table")?;
    let mu = contact_of(scene, &cue.material, &table.material).friction;
    let v_cue = DVec3::from_array(cue.velocity).length();
    let mut balls = Vec::new();
    for b in &scene.bodies {
        if b.motion == impulse_sim::scene::MotionDesc::Dynamic {
            let (m, inertia) =
                mass_properties(b).ok_or_else(|| format!("body \"{}\": not a ball", b.name))?;
            balls.push((traj.index(&b.name)?, m, inertia, b.name == cue.name));
        }
    }
    let horizontal = |v: DVec3| v - up * v.dot(up);
    let momentum = |f: &Frame| -> DVec3 {
        balls
            .iter()
            .map(|&(i, m, _, _)| horizontal(f.bodies[i].velocity) * m)
            .sum()
    };
    let energy = |f: &Frame| -> f64 {
        balls
            .iter()
            .map(|&(i, m, inertia, _)| {
                let s = f.bodies[i];
                let r = DMat3::from_quat(s.rotation);
                let world = r * inertia * r.transpose();
                0.5 * m * s.velocity.length_squared() + 0.5 * s.omega.dot(world * s.omega)
            })
            .sum()
    };
    let frames = &traj.frames;
    let struck = |f: &Frame| {
        balls.iter().any(|&(i, _, _, is_cue)| {
            !is_cue && horizontal(f.bodies[i].velocity).length() > STRUCK_REL * v_cue
        })
    };
    let p_cue = balls.iter().find(|b| b.3).map_or(0.0, |b| b.1) * v_cue;
    let Some(k1) = frames.iter().position(struck) else {
        return Ok(Measure {
            headline: POOL_HEADLINE,
            error: f64::INFINITY,
            details: vec![],
            note: "the cue ball never moved the rack (passed through it?)".into(),
        });
    };
    let k0 = k1.saturating_sub(1);
    let start = &frames[k0];
    let end = frames
        .iter()
        .find(|f| f.time >= start.time + BREAK_WINDOW)
        .ok_or("the run ends during the break")?;
    let total_mass: f64 = balls.iter().map(|b| b.1).sum();
    let allowance = mu * g * (end.time - start.time) * total_mass;
    let dp = (momentum(end) - momentum(start)).length();
    let e0 = energy(start);
    let gain = frames
        .iter()
        .filter(|f| f.time >= start.time && f.time <= end.time)
        .map(|f| (energy(f) - e0) / e0)
        .fold(0.0, f64::max);
    let excess = (dp - allowance).max(0.0) / p_cue;
    Ok(Measure {
        headline: POOL_HEADLINE,
        error: excess.max(gain),
        details: vec![
            ("momentum_change_rel", dp / p_cue),
            ("friction_allowance_rel", allowance / p_cue),
            ("momentum_excess_rel", excess),
            ("energy_gain_rel", gain),
            ("window_s", end.time - start.time),
        ],
        note: format!(
            "dP {:.2e} p_cue (friction allows {:.2e}) over {:.3} s; energy gain {gain:.2e}",
            dp / p_cue,
            allowance / p_cue,
            end.time - start.time
        ),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state(com: DVec3, rotation: DQuat, velocity: DVec3, omega: DVec3) -> State {
        State {
            position: com,
            rotation,
            com,
            velocity,
            omega,
        }
    }

    /// Onset of rolling on the ideal trajectory of a ball launched at v0 without spin: found at
    /// t* = 2v0/(7μg) with s* = 12v0²/(49μg) and v* = 5v0/7, from frames 60 Hz apart that
    /// do not land on t*. Guards the extension of the slip to zero: taking the first rolling
    /// frame instead is off by up to a frame (here 1.5 % of t*).
    #[test]
    fn rolling_onset_of_an_ideal_ball() {
        let (v0, mu, g, r) = (5.0, 0.2, 9.81, 0.1);
        let t_star = 2.0 * v0 / (7.0 * mu * g);
        let up = DVec3::Z;
        let dt = 1.0 / 60.0;
        let samples: Vec<(f64, DVec3, DVec3, DVec3)> = (0..120)
            .map(|k| {
                let t = k as f64 * dt;
                let (x, v, w) = if t < t_star {
                    // Friction μmg decelerates the centre and spins the ball up at 5μg/(2r).
                    let v = v0 - mu * g * t;
                    (v0 * t - 0.5 * mu * g * t * t, v, 2.5 * mu * g * t / r)
                } else {
                    let vs = 5.0 * v0 / 7.0;
                    let xs = v0 * t_star - 0.5 * mu * g * t_star * t_star;
                    (xs + vs * (t - t_star), vs, vs / r)
                };
                (
                    t,
                    DVec3::new(x, 0.0, r),
                    DVec3::new(v, 0.0, 0.0),
                    DVec3::new(0.0, w, 0.0),
                )
            })
            .collect();
        let (t, s, v) = rolling_onset(&samples, r, up, v0).unwrap();
        let tol = 1e-9;
        assert!((t - t_star).abs() < tol * t_star, "t {t} vs {t_star}");
        let s_star = 12.0 * v0 * v0 / (49.0 * mu * g);
        assert!((s - s_star).abs() < tol * s_star, "s {s} vs {s_star}");
        assert!((v - 5.0 * v0 / 7.0).abs() < tol * v0, "v {v}");
    }

    /// A ball spinning the wrong way never reaches zero slip: no onset.
    #[test]
    fn a_ball_that_keeps_slipping_never_rolls() {
        let samples: Vec<(f64, DVec3, DVec3, DVec3)> = (0..10)
            .map(|k| {
                (
                    k as f64 * 0.1,
                    DVec3::ZERO,
                    DVec3::X,
                    DVec3::new(0.0, -5.0, 0.0),
                )
            })
            .collect();
        assert!(rolling_onset(&samples, 0.1, DVec3::Z, 1.0).is_none());
    }

    /// A domino tipping at a constant rate ω topples (45°) at t = (π/4)/ω, found between
    /// frames; guards the interpolation and the tilt of the long axis about a horizontal axis.
    #[test]
    fn topple_time_of_a_steady_tip() {
        let omega = 2.0;
        let tilt: Vec<(f64, f64)> = (0..100)
            .map(|k| {
                let t = k as f64 * 0.01;
                let q = DQuat::from_axis_angle(DVec3::Y, omega * t);
                (t, tilt_degrees(q, DVec3::Z, DVec3::Z))
            })
            .collect();
        let t = first_crossing(&tilt, TOPPLE_DEGREES).unwrap();
        let reference = std::f64::consts::FRAC_PI_4 / omega;
        // The tilt is linear in t here, so interpolation is exact to rounding.
        assert!((t - reference).abs() < 1e-12, "{t} vs {reference}");
    }

    /// A row of dominos measured by `dominos`: the last topple time is the crossing of the
    /// last one in the row (sorted by position, not by name), and the error is zero inside the
    /// reference interval and the relative distance to it outside.
    #[test]
    fn dominos_error_against_the_reference_interval() {
        let scene = crate::cases::scenes::load_scene("dominos").unwrap().desc;
        let names: Vec<String> = scene.bodies.iter().map(|b| b.name.clone()).collect();
        let n = names.len();
        let make = |t_last: f64| {
            let frames = (0..=300)
                .map(|k| {
                    let t = k as f64 * 0.005;
                    let bodies = scene
                        .bodies
                        .iter()
                        .map(|b| {
                            // Domino j tips at a steady rate and passes 45° at j/7 of
                            // t_last (the table, j = 0, is not a domino and is ignored).
                            let j: f64 = b.name.trim_start_matches("domino").parse().unwrap_or(0.0);
                            let start = t_last * (j / 7.0) - 0.05;
                            let angle = ((t - start) * (std::f64::consts::FRAC_PI_4 / 0.05))
                                .clamp(0.0, 1.5);
                            let q = DQuat::from_axis_angle(DVec3::Y, angle);
                            state(DVec3::from_array(b.position), q, DVec3::ZERO, DVec3::ZERO)
                        })
                        .collect();
                    Frame { time: t, bodies }
                })
                .collect();
            Trajectory {
                names: names.clone(),
                frames,
            }
        };
        assert_eq!(n, 8);
        let m = dominos(&scene, &make(0.477)).unwrap();
        assert!(
            (m.detail("last_topple_time").unwrap() - 0.477).abs() < 1e-9,
            "{:?}",
            m.details
        );
        assert_eq!(m.error, 0.0);
        let m = dominos(&scene, &make(0.5)).unwrap();
        assert!(
            (m.error - (0.5 - 0.479) / 0.477).abs() < 1e-9,
            "{}",
            m.error
        );
        assert_eq!(m.detail("in_order"), Some(1.0));
    }

    /// Two unit boxes, one rotated 45° about z and pushed down into the other by d: depth d
    /// (a face-normal axis); a box beside another with a gap: 0; one rotated about an edge
    /// direction so that only an edge–edge axis separates them: that axis's overlap.
    #[test]
    fn box_penetration_of_known_overlaps() {
        let h = DVec3::splat(0.5);
        let d = 0.01;
        let a = (DVec3::ZERO, DQuat::IDENTITY, h);
        let twisted = DQuat::from_rotation_z(std::f64::consts::FRAC_PI_4);
        let b = (DVec3::new(0.0, 0.0, 1.0 - d), twisted, h);
        assert!((box_penetration(a, b) - d).abs() < 1e-12);
        let apart = (DVec3::new(1.0 + d, 0.0, 0.0), DQuat::IDENTITY, h);
        assert_eq!(box_penetration(a, apart), 0.0);
        // B turned 45° about y has an edge down along y, 0.5√2 below its centre: with that
        // edge d below A's top face the depth is d, along A's face normal z.
        let tilted = DQuat::from_rotation_y(std::f64::consts::FRAC_PI_4);
        let c = 0.5 + 0.5 * std::f64::consts::SQRT_2 - d;
        let e = (DVec3::new(0.0, 0.0, c), tilted, h);
        assert!((box_penetration(a, e) - d).abs() < 1e-12);
        // Edge against edge: A turned 45° about x (an edge up along x), B turned 45° about y
        // (an edge down along y); along z their edges are 0.5√2 from each centre, and the
        // deepest axis is z = x × y, an edge–edge axis.
        let a2 = (
            DVec3::ZERO,
            DQuat::from_rotation_x(std::f64::consts::FRAC_PI_4),
            h,
        );
        let e2 = (
            DVec3::new(0.0, 0.0, 2.0 * 0.5 * std::f64::consts::SQRT_2 - d),
            tilted,
            h,
        );
        assert!(
            (box_penetration(a2, e2) - d).abs() < 1e-12,
            "{}",
            box_penetration(a2, e2)
        );
    }

    /// The stack measure on a synthetic two-block stack: the top block slides 2 ε_c sideways
    /// and sinks 3 ε_c into the block below; drift 2 ε_c, penetration 3 ε_c, error 3 (the
    /// larger), and it still stands. Slid by two thirds of its width, it has fallen.
    #[test]
    fn stack_drift_penetration_and_standing() {
        let scene = crate::stacks::stack_scene(2);
        let eps = scene.collision_epsilon;
        let names: Vec<String> = scene.bodies.iter().map(|b| b.name.clone()).collect();
        let make = |shift: f64| {
            let frames = (0..=10)
                .map(|k| {
                    let f = k as f64 / 10.0;
                    let bodies = scene
                        .bodies
                        .iter()
                        .map(|b| {
                            let mut p = DVec3::from_array(b.position);
                            if b.name == "block1" {
                                let below = scene.bodies.iter().find(|b| b.name == "block0");
                                let top_of_below = below.map_or(0.0, |d| {
                                    d.position[2] + half_extents(d).map_or(0.0, |h| h.z)
                                });
                                let h = half_extents(b).unwrap();
                                p.z = top_of_below + h.z - f * 3.0 * eps;
                                p.x += f * shift;
                            }
                            state(p, DQuat::IDENTITY, DVec3::ZERO, DVec3::ZERO)
                        })
                        .collect();
                    Frame { time: f, bodies }
                })
                .collect();
            Trajectory {
                names: names.clone(),
                frames,
            }
        };
        let m = stack(&scene, &make(2.0 * eps)).unwrap();
        let pen = m.detail("max_penetration_over_eps_c").unwrap();
        assert!((pen - 3.0).abs() < 1e-6, "{m:?}");
        let drift = m.detail("top_drift").unwrap();
        assert!((drift - 2.0 * eps).abs() < 1e-9, "{m:?}");
        assert!((m.error - 3.0).abs() < 1e-6, "{m:?}");
        assert_eq!(m.detail("stands"), Some(1.0));
        let m = stack(&scene, &make(0.05)).unwrap();
        assert_eq!(m.detail("stands"), Some(0.0), "{m:?}");
    }

    /// The pool measure on a synthetic break: the cue ball (launch momentum p) hands all its
    /// momentum to one rack ball between two frames; the momentum change is 0 and no energy is
    /// gained. With the rack ball leaving 10 % too fast, the momentum change is 0.1 p, of
    /// which all but the friction allowance is error, and the energy gain is 1.1² − 1 = 0.21
    /// (the larger, so the error).
    #[test]
    fn pool_momentum_and_energy_of_a_synthetic_break() {
        let scene = crate::cases::scenes::load_scene("pool-break").unwrap().desc;
        let names: Vec<String> = scene.bodies.iter().map(|b| b.name.clone()).collect();
        let make = |factor: f64| {
            let frames = (0..200)
                .map(|k| {
                    let t = k as f64 * 1e-3;
                    let hit = t >= 0.1;
                    let bodies = scene
                        .bodies
                        .iter()
                        .map(|b| {
                            let v = match b.name.as_str() {
                                "cue" if !hit => DVec3::new(8.0, 0.0, 0.0),
                                "ball01" if hit => DVec3::new(8.0 * factor, 0.0, 0.0),
                                _ => DVec3::ZERO,
                            };
                            state(
                                DVec3::from_array(b.position),
                                DQuat::IDENTITY,
                                v,
                                DVec3::ZERO,
                            )
                        })
                        .collect();
                    Frame { time: t, bodies }
                })
                .collect();
            Trajectory {
                names: names.clone(),
                frames,
            }
        };
        let m = pool(&scene, &make(1.0)).unwrap();
        assert_eq!(m.error, 0.0);
        assert!(m.detail("energy_gain_rel").unwrap().abs() < 1e-12, "{m:?}");
        let m = pool(&scene, &make(1.1)).unwrap();
        let allowance = m.detail("friction_allowance_rel").unwrap();
        let excess = m.detail("momentum_excess_rel").unwrap();
        assert!((excess - (0.1 - allowance)).abs() < 1e-9, "{m:?}");
        assert!(
            (m.detail("energy_gain_rel").unwrap() - 0.21).abs() < 1e-9,
            "{m:?}"
        );
        assert!((m.error - 0.21).abs() < 1e-9, "{m:?}");
    }

    /// The ramp measure on the ideal motion of the block of `block-on-ramp.ron`: constant
    /// deceleration a = g(μ cos θ − sin θ) down the slope, then rest; the stop distance is
    /// v0²/2a to within what is left at the stop threshold (STOP_SPEED_REL² of it) and one
    /// frame's travel at that speed, and the creep is zero.
    #[test]
    fn ramp_stop_distance_of_the_ideal_block() {
        let scene = crate::cases::scenes::load_scene("block-on-ramp")
            .unwrap()
            .desc;
        let names: Vec<String> = scene.bodies.iter().map(|b| b.name.clone()).collect();
        let block = body(&scene, "block").unwrap();
        let ramp_desc = body(&scene, "ramp").unwrap();
        let (up, g) = up_and_g(&scene);
        let mu = contact_of(&scene, "default", "default").friction;
        let normal = rotation_of(&ramp_desc.rotation) * DVec3::Z;
        let theta = normal.dot(up).acos();
        let down = (-up + normal * up.dot(normal)).normalize();
        let a = g * (mu * theta.cos() - theta.sin());
        let v0 = DVec3::from_array(block.velocity).length();
        let (t_ref, d_ref) = (v0 / a, v0 * v0 / (2.0 * a));
        let dt = 1e-3;
        let frames = (0..5000)
            .map(|k| {
                let t = k as f64 * dt;
                let tt = t.min(t_ref);
                let s = v0 * tt - 0.5 * a * tt * tt;
                let v = v0 - a * tt;
                let bodies = scene
                    .bodies
                    .iter()
                    .map(|b| {
                        let p = DVec3::from_array(b.position);
                        if b.name == "block" {
                            state(p + down * s, DQuat::IDENTITY, down * v, DVec3::ZERO)
                        } else {
                            state(p, DQuat::IDENTITY, DVec3::ZERO, DVec3::ZERO)
                        }
                    })
                    .collect();
                Frame { time: t, bodies }
            })
            .collect();
        let traj = Trajectory { names, frames };
        let m = ramp(&scene, &traj).unwrap();
        let slack = STOP_SPEED_REL * STOP_SPEED_REL + STOP_SPEED_REL * v0 * dt / d_ref;
        assert!(m.error <= slack, "{} > {slack}", m.error);
        assert!(m.detail("creep_speed").unwrap().abs() < 1e-9, "{m:?}");
    }
}
