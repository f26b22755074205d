//! Reading contacts as they happen: three balls dropped from different heights onto a floor;
//! after each step, every contact resolved during it (time, bodies, kind, impulse).
//!
//! `cargo run --release -p impulse-sim --example contacts`

use impulse_sim::contact::ContactKind;
use impulse_sim::scene::{BodyDesc, ShapeDesc};
use impulse_sim::{World, WorldSettings};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut world = World::new(WorldSettings::new(1e-4))?;
    world.add_body(
        &BodyDesc::fixed("floor", ShapeDesc::cuboid([1.0, 1.0, 0.1])).at([0.0, 0.0, -0.1]),
    )?;
    for (k, height) in [0.2, 0.4, 0.8].into_iter().enumerate() {
        world.add_body(
            &BodyDesc::new(format!("ball{k}"), ShapeDesc::sphere(0.05))
                .at([0.3 * k as f64, 0.0, height])
                .with_density(7800.0),
        )?;
    }
    let name = |w: &World, h| w.body(h).map_or("?".to_string(), |b| b.name.clone());
    for _ in 0..50 {
        world.step(0.02)?;
        for c in world.contacts() {
            if c.kind == ContactKind::Collision {
                println!(
                    "t = {:.4} s: {} hit {} with an impulse of {:.4} N·s",
                    c.time,
                    name(&world, c.b),
                    name(&world, c.a),
                    c.impulse.length()
                );
            }
        }
    }
    let resting = world.contacts().len();
    println!("in the last 20 ms: {resting} microcollisions hold the balls at rest");
    Ok(())
}
