//! The scenes of `cargo xtask bench --scale`: piles of boxes and of spheres of 27, 216 and
//! 1000 bodies, and a pyramid of 20 rows, built as scene descriptions (so that `impulse run`
//! and the peer engine read the same geometry; `--out` writes them as RON files).
//!
//! The geometry, fixed by the comparison it serves (the same in every engine): cubes of 0.5 m
//! on a 0.6 m grid, each tilted by 2–6° about a seeded random axis, the lowest 0.1 m above a
//! ground box; spheres of radius 0.25 on the same grid, nudged sideways by a seeded few
//! millimetres (a column of spheres exactly above each other balances for ever), poured into
//! an open box; μ 0.5, e 0.2, density 1000, ε_c 1 mm; 3 s. The pyramid: rows of 20, 19, …, 1
//! cubes of 0.5 m (210), each centred over the gap of the two below, ε_c/2 apart, 5 s.

use glam::DVec3;
use impulse_sim::scene::{BodyDesc, ContactDesc, RotationDesc, SceneDesc, ShapeDesc};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

/// Half the edge of a cube of the piles and the pyramid (m).
pub const CUBE_HALF: f64 = 0.25;
/// Radius of a sphere of the sphere piles (m).
pub const SPHERE_RADIUS: f64 = 0.25;
/// Distance between neighbouring bodies' centres on the piles' grid (m).
pub const PITCH: f64 = 0.6;
/// Height of the lowest bodies' bottoms above the ground when released (m).
pub const DROP: f64 = 0.1;
/// Range of the cubes' initial tilts (degrees).
pub const TILT_DEGREES: (f64, f64) = (2.0, 6.0);
/// Largest sideways nudge of a sphere from its grid point (m).
pub const SPHERE_NUDGE: f64 = 0.005;
/// Coulomb friction of every contact.
pub const FRICTION: f64 = 0.5;
/// Restitution of every contact.
pub const RESTITUTION: f64 = 0.2;
/// Density of every body (kg/m³).
pub const DENSITY: f64 = 1000.0;
/// Collision epsilon ε_c (m).
pub const EPSILON: f64 = 1e-3;
/// Simulated time of a pile (s).
pub const PILE_SECONDS: f64 = 3.0;
/// Simulated time of the pyramid (s).
pub const PYRAMID_SECONDS: f64 = 5.0;
/// Frames recorded per second (the rate at which the bench samples and checks).
pub const FRAME_RATE: f64 = 100.0;
/// Half the thickness of the ground box and of the container's walls (m).
const SLAB_HALF: f64 = 0.25;
/// The name of the ground body in every scene (the bench checks that nothing goes below its
/// top, z = 0).
pub const GROUND: &str = "ground";

/// The kind of a scale scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// A pile of tilted cubes.
    Boxes,
    /// Spheres poured into an open box.
    Spheres,
    /// A pyramid of cubes.
    Pyramid,
}

/// One scale scene: its name, kind, body count and description.
pub struct ScaleScene {
    /// File and table name, e.g. `boxes-216`.
    pub name: String,
    /// What it is.
    pub kind: Kind,
    /// Dynamic bodies.
    pub bodies: usize,
    /// The scene.
    pub scene: SceneDesc,
}

/// A scene with the common settings and nothing in it.
fn base(name: &str, seconds: f64) -> SceneDesc {
    SceneDesc::new()
        .with_name(name)
        .with_duration(seconds)
        .with_collision_epsilon(EPSILON)
        .with_output_rate(FRAME_RATE)
        .with_default_contact(ContactDesc::new(FRICTION, RESTITUTION))
}

/// The ground: a fixed box whose top is the plane z = 0, `half_width` in x and y.
fn ground(half_width: f64) -> BodyDesc {
    BodyDesc::fixed(
        GROUND,
        ShapeDesc::cuboid([half_width, half_width, SLAB_HALF]),
    )
    .at([0.0, 0.0, -SLAB_HALF])
}

/// The grid point of index (i, j, k) of an n × n × n grid centred on the z axis, its lowest
/// layer's centres at `z0`.
fn grid_point(n: usize, (i, j, k): (usize, usize, usize), z0: f64) -> DVec3 {
    let centre = 0.5 * (n as f64 - 1.0);
    DVec3::new(
        (i as f64 - centre) * PITCH,
        (j as f64 - centre) * PITCH,
        z0 + k as f64 * PITCH,
    )
}

/// A unit vector uniformly distributed on the sphere.
fn random_axis(rng: &mut Xoshiro256PlusPlus) -> DVec3 {
    loop {
        let v = DVec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        );
        let l = v.length();
        if l > 1e-3 && l <= 1.0 {
            return v / l;
        }
    }
}

/// A pile of n³ tilted cubes (seeded).
pub fn boxes(n: usize, seed: u64) -> ScaleScene {
    let count = n * n * n;
    let name = format!("boxes-{count}");
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let span = n as f64 * PITCH;
    let mut scene = base(&name, PILE_SECONDS).with_body(ground(span + 2.0));
    // A tilted cube reaches at most its half diagonal below its centre; the lowest layer's
    // lowest corner is then at least DROP above the ground.
    let z0 = DROP + CUBE_HALF * 3f64.sqrt();
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let p = grid_point(n, (i, j, k), z0);
                let axis = random_axis(&mut rng);
                let angle = rng.random_range(TILT_DEGREES.0..TILT_DEGREES.1);
                scene = scene.with_body(
                    BodyDesc::new(
                        format!("box-{i}-{j}-{k}"),
                        ShapeDesc::cuboid([CUBE_HALF; 3]),
                    )
                    .at(p.to_array())
                    .with_rotation(RotationDesc::axis_angle(axis.to_array(), angle))
                    .with_density(DENSITY),
                );
            }
        }
    }
    ScaleScene {
        name,
        kind: Kind::Boxes,
        bodies: count,
        scene,
    }
}

/// n³ spheres (seeded nudges) poured into an open box whose floor is the ground and whose
/// walls stand a pitch beyond the grid.
pub fn spheres(n: usize, seed: u64) -> ScaleScene {
    let count = n * n * n;
    let name = format!("spheres-{count}");
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let inner = 0.5 * n as f64 * PITCH + 0.5 * PITCH;
    let height = DROP + n as f64 * PITCH + SPHERE_RADIUS;
    let mut scene = base(&name, PILE_SECONDS).with_body(ground(inner + 2.0 * SLAB_HALF));
    let wall = |name: &str, centre: [f64; 3], half: [f64; 3]| {
        BodyDesc::fixed(name, ShapeDesc::cuboid(half)).at(centre)
    };
    let (w, h) = (inner + SLAB_HALF, 0.5 * height);
    scene = scene
        .with_body(wall("wall-x-", [-w, 0.0, h], [SLAB_HALF, inner, h]))
        .with_body(wall("wall-x+", [w, 0.0, h], [SLAB_HALF, inner, h]))
        .with_body(wall(
            "wall-y-",
            [0.0, -w, h],
            [inner + 2.0 * SLAB_HALF, SLAB_HALF, h],
        ))
        .with_body(wall(
            "wall-y+",
            [0.0, w, h],
            [inner + 2.0 * SLAB_HALF, SLAB_HALF, h],
        ));
    let z0 = DROP + SPHERE_RADIUS;
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let nudge = DVec3::new(
                    rng.random_range(-SPHERE_NUDGE..SPHERE_NUDGE),
                    rng.random_range(-SPHERE_NUDGE..SPHERE_NUDGE),
                    0.0,
                );
                let p = grid_point(n, (i, j, k), z0) + nudge;
                scene = scene.with_body(
                    BodyDesc::new(
                        format!("sphere-{i}-{j}-{k}"),
                        ShapeDesc::sphere(SPHERE_RADIUS),
                    )
                    .at(p.to_array())
                    .with_density(DENSITY),
                );
            }
        }
    }
    ScaleScene {
        name,
        kind: Kind::Spheres,
        bodies: count,
        scene,
    }
}

/// A pyramid of `rows` rows of cubes: rows of `rows`, `rows − 1`, …, 1, each cube centred over
/// the gap between the two below it, neighbours ε_c/2 apart and every row ε_c/2 above the
/// one below.
pub fn pyramid(rows: usize) -> ScaleScene {
    let count = rows * (rows + 1) / 2;
    let name = format!("pyramid-{rows}");
    let gap = 0.5 * EPSILON;
    let pitch = 2.0 * CUBE_HALF + gap;
    let mut scene = base(&name, PYRAMID_SECONDS).with_body(ground(rows as f64 * pitch + 2.0));
    for row in 0..rows {
        let in_row = rows - row;
        let z = CUBE_HALF + gap + row as f64 * pitch;
        for k in 0..in_row {
            let x = (k as f64 - 0.5 * (in_row as f64 - 1.0)) * pitch;
            scene = scene.with_body(
                BodyDesc::new(format!("row{row}-{k}"), ShapeDesc::cuboid([CUBE_HALF; 3]))
                    .at([x, 0.0, z])
                    .with_density(DENSITY),
            );
        }
    }
    ScaleScene {
        name,
        kind: Kind::Pyramid,
        bodies: count,
        scene,
    }
}

/// Every scene of the bench, smallest first within each kind: piles of 3³, 6³ and 10³ boxes
/// and spheres, and the pyramid of 20 rows.
pub fn all() -> Vec<ScaleScene> {
    let mut scenes = Vec::new();
    for n in [3, 6, 10] {
        scenes.push(boxes(n, n as u64));
    }
    for n in [3, 6, 10] {
        scenes.push(spheres(n, n as u64));
    }
    scenes.push(pyramid(20));
    scenes
}

#[cfg(test)]
mod tests {
    use super::*;
    use impulse_sim::{Scene, World};

    #[test]
    fn the_scenes_build_into_worlds_without_overlap_and_have_the_stated_sizes() {
        for s in [boxes(3, 1), spheres(3, 1), pyramid(4)] {
            let dynamic = s
                .scene
                .bodies
                .iter()
                .filter(|b| b.name != GROUND && !b.name.starts_with("wall"))
                .count();
            assert_eq!(dynamic, s.bodies, "{}", s.name);
            // Building checks every pair for overlap deeper than ε_c; the RON text reads back
            // as the same scene.
            let text = s.scene.to_ron().unwrap();
            assert_eq!(SceneDesc::from_ron(&text, &s.name).unwrap(), s.scene);
            let scene = Scene {
                desc: s.scene,
                base_dir: ".".into(),
            };
            World::from_scene(&scene).unwrap();
        }
        assert_eq!(pyramid(20).bodies, 210);
        assert_eq!(boxes(10, 10).bodies, 1000);
    }

    #[test]
    fn the_tilts_are_in_their_range_and_seeded() {
        let a = boxes(3, 7);
        assert_eq!(a.scene, boxes(3, 7).scene);
        assert_ne!(a.scene, boxes(3, 8).scene);
        for b in a.scene.bodies.iter().filter(|b| b.name != GROUND) {
            let RotationDesc::AxisAngle { degrees, .. } = b.rotation else {
                panic!("{}: not tilted", b.name);
            };
            assert!(
                (TILT_DEGREES.0 - 1e-9..=TILT_DEGREES.1 + 1e-9).contains(&degrees),
                "{}: {degrees}",
                b.name
            );
        }
    }
}
