//! Steady islands take long steps (module documentation of [`crate::sustained`], "Steady
//! steps").
//!
//! An island whose held loads did not change over its last step, whose bodies touch only
//! fixed bodies, each contact point on a fixed polyhedron's face far enough inside it, moves
//! as exactly under a constant held load over [`REST_STEP_MULTIPLE`] nominal steps as over
//! one: a ball rolling on a table, a block sliding on a floor. Its step is the rest step's:
//! to the next multiple of [`REST_STEP_MULTIPLE`] nominal steps (a strike, a program's change
//! or a new held pair still makes it step at once).

use glam::DVec3;
use impulse_collide::Feature;
use impulse_collide::shape::Convex;
use impulse_geom::{ConvexPolyhedron, Pose};

use super::World;
use super::held::Island;
use super::island::REST_STEP_MULTIPLE;

/// How many times the distance its contact point travels over a long step a contact must
/// lie inside its face's edges for the step to be taken long: the point's speed may grow
/// within the step. Default `2.0`.
const FACE_TRAVEL_SAFETY: f64 = 2.0;

impl World {
    /// Whether an island may take the long step of a steady island (module documentation):
    /// its bodies dynamic and under no load function, their held loads changed over the last
    /// step by less than the step tolerance allows over a long step (½·Δa·H² ≤ tol·ε_c,
    /// Δa the change of the centre's acceleration plus that of the angular one times the
    /// body's reach), every pair with a fixed body, and every contact point on a face of that
    /// body's polyhedron at least [`FACE_TRAVEL_SAFETY`] times its travel over the long step
    /// (plus ε_c) from the face's edges.
    pub(super) fn is_steady(&self, island: &Island) -> bool {
        let long = REST_STEP_MULTIPLE * self.islands.settings.step;
        let eps = self.collision_epsilon();
        let allowed = self.islands.settings.step_tolerance * eps;
        let steady_body = |i: u32| {
            let b = self.b(i);
            b.is_dynamic()
                && !b.is_link()
                && !self.loads.iter().any(|l| l.body == i)
                && self
                    .islands
                    .load_change
                    .get(&i)
                    .is_some_and(|&da| 0.5 * da * long * long <= allowed)
        };
        if !island.bodies.iter().all(|&i| steady_body(i)) {
            return false;
        }
        island.pairs.iter().all(|p| {
            let (a, b) = *p;
            let (fixed_is_a, moving) = match (self.b(a).kind, self.b(b).kind) {
                (crate::body::BodyKind::Fixed, _) => (true, b),
                (_, crate::body::BodyKind::Fixed) => (false, a),
                _ => return false,
            };
            let fixed = if fixed_is_a { a } else { b };
            let Some(held) = self.islands.held.get(p) else {
                return false;
            };
            let (fb, mb) = (self.b(fixed), self.b(moving));
            held.manifolds.iter().all(|m| {
                let piece = if fixed_is_a { m.pieces.0 } else { m.pieces.1 };
                let piece = &fb.shape.pieces()[piece as usize];
                let Convex::Polyhedron(poly) = &piece.convex else {
                    return false;
                };
                let pose = fb.pose * piece.pose;
                m.points().iter().all(|q| {
                    let (feature, x) = if fixed_is_a {
                        (q.id.a, q.point_a)
                    } else {
                        (q.id.b, q.point_b)
                    };
                    let Feature::Face(f) = feature else {
                        return false;
                    };
                    let travel = mb.point_velocity(x).length() * long;
                    face_clearance(poly, &pose, f, x) >= FACE_TRAVEL_SAFETY * travel + eps
                })
            })
        })
    }
}

/// How far point `x` (world) lies inside face `f` of `poly` placed at `pose`: its smallest
/// distance, in the face's plane, to the face's edges (negative outside).
fn face_clearance(poly: &ConvexPolyhedron, pose: &Pose, f: u32, x: DVec3) -> f64 {
    let local = pose.inverse_transform_point(x);
    let n = poly.face_plane(f).normal;
    let ring = poly.face_vertices(f);
    let centre = ring.iter().map(|&v| poly.vertex(v)).sum::<DVec3>() / ring.len() as f64;
    let mut clearance = f64::INFINITY;
    for (k, &v) in ring.iter().enumerate() {
        let (p, q) = (poly.vertex(v), poly.vertex(ring[(k + 1) % ring.len()]));
        // The in-plane direction from the edge into the face.
        let inward = n.cross(q - p).normalize_or_zero();
        let inward = if (centre - p).dot(inward) < 0.0 {
            -inward
        } else {
            inward
        };
        clearance = clearance.min((local - p).dot(inward));
    }
    clearance
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{BodyDesc, ContactDesc, Scene, SceneDesc, ShapeDesc};
    use crate::sustained::{ContactMode, SustainedSettings};
    use glam::DQuat;

    /// A ball rolling (ω = v/r, no slip) at 1 m/s on a table toward its edge takes the long
    /// steps of a steady island while its contact lies far inside the table's top face, and
    /// leaves the table where the face ends: its centre crosses the edge at t_c = d/v (it
    /// rolls at constant speed), and from there, since v² > g·r, it flies free, so 50 ms later
    /// it is ½·g·(50 ms)² below its rolling height, less what its held load holds up until
    /// the island step that finds the contact gone: at most two nominal steps h, g·T·2h
    /// (0.98 mm; measured 0.49). A held load kept over a long step past the edge held it up
    /// for 7 ms of that (3.6 mm less drop, with the face check off).
    #[test]
    fn a_ball_rolls_in_long_steps_and_leaves_the_table_at_its_edge() {
        let (r, v, d, eps, g) = (0.05, 1.0, 0.4, 1e-4, 9.81);
        let rest_gap = SustainedSettings::default().rest_gap_fraction * eps;
        let desc = SceneDesc::new()
            .with_collision_epsilon(eps)
            .with_contact_model(ContactMode::Switching)
            .with_gravity([0.0, 0.0, -g])
            .with_default_contact(ContactDesc::new(0.5, 0.0))
            .with_body(
                BodyDesc::fixed("table", ShapeDesc::cuboid([1.0, 1.0, 0.5])).at([-1.0, 0.0, -0.5]),
            )
            .with_body(
                BodyDesc::new("ball", ShapeDesc::sphere(r))
                    .at([-d, 0.0, r + rest_gap])
                    .with_velocity([v, 0.0, 0.0])
                    .with_angular_velocity([0.0, v / r, 0.0])
                    .with_density(1000.0),
            );
        let mut world = World::from_scene(&Scene::new(desc, ".")).expect("valid");
        world.set_checking(true);
        let ball = world.handle("ball").expect("named");
        let t_c = d / v;
        world.step_until(0.9 * t_c).expect("runs");
        let c = world.counters();
        let nominal = 0.9 * t_c / SustainedSettings::default().step;
        assert!(
            (c.island_steps as f64) < 0.25 * nominal,
            "{} island steps rolling, {nominal:.0} nominal ones",
            c.island_steps
        );
        let t = t_c + 0.05;
        world.step_until(t).expect("runs");
        let s = world.state(ball).expect("live");
        let fall = 0.5 * g * (t - t_c) * (t - t_c);
        let expected = r + rest_gap - fall;
        let late = g * (t - t_c) * 2.0 * SustainedSettings::default().step;
        assert!(
            s.position.z >= expected - 1e-9 && s.position.z - expected <= late,
            "centre at z = {:.6} m, free flight from the edge puts it at {expected:.6} m \
             (at most {late:.1e} m higher)",
            s.position.z
        );
        assert!(
            (s.position.x - v * t + d).abs() < 1e-4,
            "x = {}",
            s.position.x
        );
        let deepest = world.checked_penetration().expect("checking").max_depth;
        assert!(deepest <= eps, "deepest {:.3} ε_c", deepest / eps);
    }

    /// A unit cube's top face: a point at (0.2, −0.1) is 0.3 from the nearest edge (x = 0.5),
    /// also with the cube turned and moved; a point outside is negative.
    #[test]
    fn face_clearance_is_the_distance_to_the_nearest_edge() {
        let cube = ConvexPolyhedron::hull(&[
            DVec3::new(-0.5, -0.5, -0.5),
            DVec3::new(0.5, -0.5, -0.5),
            DVec3::new(-0.5, 0.5, -0.5),
            DVec3::new(0.5, 0.5, -0.5),
            DVec3::new(-0.5, -0.5, 0.5),
            DVec3::new(0.5, -0.5, 0.5),
            DVec3::new(-0.5, 0.5, 0.5),
            DVec3::new(0.5, 0.5, 0.5),
        ])
        .expect("a cube");
        let top = (0..cube.face_count() as u32)
            .find(|&f| cube.face_plane(f).normal.z > 0.99)
            .expect("a top face");
        let pose = Pose::new(DQuat::from_rotation_z(0.7), DVec3::new(3.0, -1.0, 2.0));
        let at = |x: f64, y: f64| pose.transform_point(DVec3::new(x, y, 0.5));
        assert!((face_clearance(&cube, &pose, top, at(0.2, -0.1)) - 0.3).abs() < 1e-12);
        assert!((face_clearance(&cube, &pose, top, at(0.0, 0.0)) - 0.5).abs() < 1e-12);
        assert!((face_clearance(&cube, &pose, top, at(0.7, 0.0)) + 0.2).abs() < 1e-12);
    }
}
