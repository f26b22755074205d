//! The scale bench's verdicts, read from a recorded trajectory alone (whatever engine
//! recorded it): the deepest overlap of any two bodies, the lowest point below the ground,
//! whether everything is at rest at the end, and how far any body drifted from its start.
//!
//! The overlaps are measured by code of this file and [`box_penetration`] (separating axes),
//! not by any engine's collision queries: an engine is not its own judge.

use glam::{DQuat, DVec3};
use impulse_sim::scene::{BodyDesc, MotionDesc, SceneDesc, ShapeDesc};

use crate::peers::measure::{Trajectory, box_penetration};

/// A pile is at rest when no point of any body moves faster than this (m/s) in the last frame.
pub const REST_SPEED: f64 = 1e-2;

/// What the judge found over a whole trajectory.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Verdict {
    /// The deepest overlap of two bodies in any frame (m).
    pub max_penetration: f64,
    /// Where: (time, first body, second body).
    pub worst: Option<(f64, String, String)>,
    /// How far the lowest point of any dynamic body went below the ground's top, z = 0 (m; 0
    /// when nothing did).
    pub below_ground: f64,
    /// The fastest point of any dynamic body in the last frame (m/s).
    pub end_speed: f64,
    /// The largest distance of a dynamic body's centre from where it started, in the last
    /// frame (m).
    pub max_drift: f64,
}

/// A body's shape as the judge measures it.
#[derive(Clone, Copy, Debug)]
enum Solid {
    Cuboid(DVec3),
    Ball(f64),
}

impl Solid {
    fn of(b: &BodyDesc) -> Result<Solid, String> {
        match &b.shape {
            ShapeDesc::Box { half_extents } => Ok(Solid::Cuboid(DVec3::from_array(*half_extents))),
            ShapeDesc::Sphere { radius } => Ok(Solid::Ball(*radius)),
            other => Err(format!(
                "body \"{}\": the judge measures boxes and spheres, not {other:?}",
                b.name
            )),
        }
    }

    /// Radius of a sphere about the shape frame's origin that holds the solid.
    fn bound(self) -> f64 {
        match self {
            Solid::Cuboid(h) => h.length(),
            Solid::Ball(r) => r,
        }
    }

    /// The lowest z of the solid at a pose.
    fn lowest(self, position: DVec3, q: DQuat) -> f64 {
        match self {
            Solid::Ball(r) => position.z - r,
            Solid::Cuboid(h) => {
                let reach = h.x * (q * DVec3::X).z.abs()
                    + h.y * (q * DVec3::Y).z.abs()
                    + h.z * (q * DVec3::Z).z.abs();
                position.z - reach
            }
        }
    }
}

/// Depth of the overlap of two solids at their poses (0 when apart).
fn overlap(a: (Solid, DVec3, DQuat), b: (Solid, DVec3, DQuat)) -> f64 {
    match (a, b) {
        ((Solid::Cuboid(ha), pa, qa), (Solid::Cuboid(hb), pb, qb)) => {
            box_penetration((pa, qa, ha), (pb, qb, hb))
        }
        ((Solid::Ball(ra), pa, _), (Solid::Ball(rb), pb, _)) => {
            (ra + rb - pa.distance(pb)).max(0.0)
        }
        ((Solid::Ball(r), c, _), (Solid::Cuboid(h), p, q))
        | ((Solid::Cuboid(h), p, q), (Solid::Ball(r), c, _)) => {
            // The centre in the box's frame; the depth of a ball whose centre is outside is r
            // less the distance to the box, inside it r plus the distance to the nearest face.
            let local = q.inverse() * (c - p);
            let outside = (local.abs() - h).max(DVec3::ZERO);
            if outside.length_squared() > 0.0 {
                (r - outside.length()).max(0.0)
            } else {
                r + (h - local.abs()).min_element()
            }
        }
    }
}

/// Judges `traj`, recorded from `scene` (bodies in the scene's order).
///
/// # Errors
/// A body whose shape the judge does not measure, or a trajectory without frames.
pub fn judge(scene: &SceneDesc, traj: &Trajectory) -> Result<Verdict, String> {
    let solids: Vec<Solid> = scene
        .bodies
        .iter()
        .map(Solid::of)
        .collect::<Result<_, _>>()?;
    let dynamic: Vec<bool> = scene
        .bodies
        .iter()
        .map(|b| b.motion == MotionDesc::Dynamic)
        .collect();
    let first = traj.frames.first().ok_or("no frames")?;
    let last = traj.frames.last().ok_or("no frames")?;
    let mut verdict = Verdict::default();
    // Pairs by a sweep over x of bounding spheres (fixed bodies are boxes as large as the
    // ground: they are paired with everything that reaches below their top).
    let mut order: Vec<usize> = (0..solids.len()).collect();
    for frame in &traj.frames {
        let pose = |i: usize| (frame.bodies[i].position, frame.bodies[i].rotation);
        let lo = |i: usize| pose(i).0.x - solids[i].bound();
        order.sort_by(|&a, &b| lo(a).total_cmp(&lo(b)));
        for (k, &i) in order.iter().enumerate() {
            let hi = pose(i).0.x + solids[i].bound();
            for &j in &order[k + 1..] {
                if lo(j) > hi {
                    break;
                }
                if !dynamic[i] && !dynamic[j] {
                    continue;
                }
                let (pi, qi) = pose(i);
                let (pj, qj) = pose(j);
                if pi.distance(pj) > solids[i].bound() + solids[j].bound() {
                    continue;
                }
                let depth = overlap((solids[i], pi, qi), (solids[j], pj, qj));
                if depth > verdict.max_penetration {
                    verdict.max_penetration = depth;
                    let (a, b) = (traj.names[i.min(j)].clone(), traj.names[i.max(j)].clone());
                    verdict.worst = Some((frame.time, a, b));
                }
            }
        }
        for i in (0..solids.len()).filter(|&i| dynamic[i]) {
            let (p, q) = pose(i);
            verdict.below_ground = verdict.below_ground.max(-solids[i].lowest(p, q));
        }
    }
    for i in (0..solids.len()).filter(|&i| dynamic[i]) {
        let s = last.bodies[i];
        let speed = s.velocity.length() + s.omega.length() * solids[i].bound();
        verdict.end_speed = verdict.end_speed.max(speed);
        verdict.max_drift = verdict
            .max_drift
            .max(s.position.distance(first.bodies[i].position));
    }
    Ok(verdict)
}

/// The scene's initial rotation of body `b` (for tests).
#[cfg(test)]
fn initial(b: &BodyDesc) -> DQuat {
    crate::cases::scenes::rotation(&b.rotation)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::peers::measure::{Frame, State};

    fn state(p: DVec3, q: DQuat, v: DVec3) -> State {
        State {
            position: p,
            rotation: q,
            com: p,
            velocity: v,
            omega: DVec3::ZERO,
        }
    }

    fn scene() -> SceneDesc {
        SceneDesc::new()
            .with_body(
                BodyDesc::fixed("ground", ShapeDesc::cuboid([10.0, 10.0, 0.5]))
                    .at([0.0, 0.0, -0.5]),
            )
            .with_body(BodyDesc::new("a", ShapeDesc::cuboid([0.5, 0.5, 0.5])).at([0.0, 0.0, 0.5]))
            .with_body(BodyDesc::new("b", ShapeDesc::sphere(0.5)).at([0.0, 0.0, 1.5]))
    }

    fn traj(frames: Vec<Vec<State>>) -> Trajectory {
        Trajectory {
            names: vec!["ground".into(), "a".into(), "b".into()],
            frames: frames
                .into_iter()
                .enumerate()
                .map(|(k, bodies)| Frame {
                    time: k as f64,
                    bodies,
                })
                .collect(),
        }
    }

    #[test]
    fn touching_bodies_overlap_by_nothing_and_sunk_ones_by_their_depth() {
        let s = scene();
        let ground = state(DVec3::new(0.0, 0.0, -0.5), DQuat::IDENTITY, DVec3::ZERO);
        let at = |za: f64, zb: f64| {
            vec![
                ground,
                state(DVec3::new(0.0, 0.0, za), initial(&s.bodies[1]), DVec3::ZERO),
                state(DVec3::new(0.0, 0.0, zb), DQuat::IDENTITY, DVec3::ZERO),
            ]
        };
        let v = judge(&s, &traj(vec![at(0.5, 1.5)])).unwrap();
        assert!(v.max_penetration < 1e-12 && v.below_ground < 1e-12, "{v:?}");
        // The box 3 mm into the ground, the ball 7 mm into the box.
        let v = judge(&s, &traj(vec![at(0.5, 1.5), at(0.497, 1.49)])).unwrap();
        assert!((v.max_penetration - 0.007).abs() < 1e-12, "{v:?}");
        assert_eq!(v.worst.as_ref().map(|w| w.0), Some(1.0));
        assert!((v.below_ground - 0.003).abs() < 1e-12, "{v:?}");
    }

    #[test]
    fn a_tilted_box_reaches_down_by_its_projected_half_extents() {
        let s = scene();
        // A unit cube turned 45° about x: its lowest edge √2/2 below its centre.
        let q = DQuat::from_rotation_x(std::f64::consts::FRAC_PI_4);
        let v = judge(
            &s,
            &traj(vec![vec![
                state(DVec3::new(0.0, 0.0, -0.5), DQuat::IDENTITY, DVec3::ZERO),
                state(DVec3::new(0.0, 0.0, 0.7), q, DVec3::ZERO),
                state(
                    DVec3::new(5.0, 0.0, 0.5),
                    DQuat::IDENTITY,
                    DVec3::new(0.0, 0.02, 0.0),
                ),
            ]]),
        )
        .unwrap();
        assert!(
            (v.below_ground - (0.5f64.sqrt() - 0.7)).abs() < 1e-12,
            "{v:?}"
        );
        assert!((v.end_speed - 0.02).abs() < 1e-15);
    }

    #[test]
    fn a_ball_against_a_box_face_and_corner() {
        let cube = (
            Solid::Cuboid(DVec3::splat(0.5)),
            DVec3::ZERO,
            DQuat::IDENTITY,
        );
        let ball = |c: DVec3| (Solid::Ball(0.25), c, DQuat::IDENTITY);
        assert!((overlap(cube, ball(DVec3::new(0.0, 0.0, 0.7))) - 0.05).abs() < 1e-12);
        let corner = DVec3::splat(0.5) + DVec3::splat(0.2 / 3f64.sqrt());
        assert!((overlap(ball(corner), cube) - 0.05).abs() < 1e-12);
        // Centre inside, 0.1 below the top face.
        assert!((overlap(cube, ball(DVec3::new(0.0, 0.0, 0.4))) - 0.35).abs() < 1e-12);
    }
}
