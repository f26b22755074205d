//! temporary (not committed): stacks in the default model, the bench's placement (0.5 ε_c apart)
use impulse_sim::scene::{BodyDesc, ShapeDesc};
use impulse_sim::{World, WorldSettings};
fn main() -> Result<(), Box<dyn std::error::Error>> {
    let blocks: usize = std::env::args().nth(1).map_or(Ok(4), |s| s.parse())?;
    let dur: f64 = std::env::args().nth(2).map_or(Ok(10.0), |s| s.parse())?;
    let eps = 2e-4;
    let mut world = World::new(WorldSettings::new(eps))?;
    world.add_body(
        &BodyDesc::fixed("floor", ShapeDesc::cuboid([0.5, 0.5, 0.05])).at([0.0, 0.0, -0.05]),
    )?;
    let half = [0.05, 0.0375, 0.025];
    let gap = 0.5 * eps;
    for k in 0..blocks {
        let z = half[2] + gap + k as f64 * (2.0 * half[2] + gap);
        world.add_body(
            &BodyDesc::new(format!("block{k}"), ShapeDesc::cuboid(half))
                .at([0.0, 0.0, z])
                .with_density(700.0),
        )?;
    }
    let t0 = std::time::Instant::now();
    let mut t = 0.0;
    let mut prev = world.counters();
    let mut tp = std::time::Instant::now();
    while t < dur - 1e-9 {
        t += 0.25;
        world.step_until(t)?;
        let c = world.counters();
        let asleep = world.bodies().filter(|(_, b)| b.is_asleep()).count();
        println!(
            "t {t:.2} wall {:.3} isl {} trans {} sleeps {} asleep {asleep} micro {}",
            tp.elapsed().as_secs_f64(),
            c.island_steps - prev.island_steps,
            c.transients - prev.transients,
            c.sleeps - prev.sleeps,
            c.microcollisions - prev.microcollisions
        );
        prev = c;
        tp = std::time::Instant::now();
    }
    println!(
        "n {blocks} wall/sim {:.4}",
        t0.elapsed().as_secs_f64() / dur
    );
    Ok(())
}
