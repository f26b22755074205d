//! The example of this crate's README.md, verbatim after this header (`cargo xtask ci` checks
//! that they are equal; `cargo test` builds it). Run it with
//! `cargo run -p impulse-sim --example readme_sim`.

use impulse_sim::scene::{BodyDesc, ShapeDesc};
use impulse_sim::{SimError, World, WorldSettings};

fn main() -> Result<(), SimError> {
    // A 10 cm box resting exactly on a floor whose top is z = 0; collision epsilon 0.1 mm.
    let mut world = World::new(WorldSettings::new(1e-4))?;
    let floor = BodyDesc::fixed("floor", ShapeDesc::cuboid([1.0, 1.0, 0.1]));
    world.add_body(&floor.at([0.0, 0.0, -0.1]))?;
    let cube = BodyDesc::new("box", ShapeDesc::cuboid([0.05, 0.05, 0.05]));
    let cube = world.add_body(&cube.at([0.0, 0.0, 0.05]).with_density(700.0))?;
    // A ball dropped beside it.
    let ball =
        world.add_body(&BodyDesc::new("ball", ShapeDesc::sphere(0.02)).at([0.3, 0.0, 0.2]))?;
    let report = world.step_until(1.0)?;
    assert!((world.state(cube)?.position.z - 0.05).abs() < 1e-3); // still resting
    assert!(world.state(ball)?.position.z < 0.03); // fell and bounced down to the floor
    assert!(report.counters.collisions > 0);
    Ok(())
}
