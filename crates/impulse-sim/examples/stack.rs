//! A stack of blocks built in code, each placed exactly on the one below (touching is contact),
//! stepped for two seconds: prints how far the top block moved and the deepest
//! interpenetration an independent monitor saw, every quarter second.
//!
//! `cargo run --release -p impulse-sim --example stack -- [blocks]`

use impulse_sim::monitor::PenetrationMonitor;
use impulse_sim::scene::{BodyDesc, ShapeDesc};
use impulse_sim::{World, WorldSettings};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let blocks: usize = std::env::args().nth(1).map_or(Ok(4), |s| s.parse())?;
    let eps = 1e-4;
    let mut world = World::new(WorldSettings::new(eps))?;
    world.add_body(
        &BodyDesc::fixed("floor", ShapeDesc::cuboid([0.5, 0.5, 0.05])).at([0.0, 0.0, -0.05]),
    )?;
    let half = [0.05, 0.0375, 0.025];
    let mut top = None;
    for k in 0..blocks {
        let z = half[2] * (1.0 + 2.0 * k as f64);
        top = Some(
            world.add_body(
                &BodyDesc::new(format!("block{k}"), ShapeDesc::cuboid(half))
                    .at([0.0, 0.0, z])
                    .with_density(700.0),
            )?,
        );
    }
    let top = top.ok_or("no blocks")?;
    let start = world.state(top)?.position;
    let mut monitor = PenetrationMonitor::new();
    for k in 1..=8 {
        let report = world.step_until(0.25 * f64::from(k))?;
        monitor.sample(&world);
        let moved = (world.state(top)?.position - start).length();
        println!(
            "t = {:.2} s: top block moved {:.2} ε_c, {} impulses this quarter, deepest overlap {:.3} ε_c",
            world.time(),
            moved / eps,
            report.counters.collisions + report.counters.microcollisions,
            monitor.report().max_depth / eps
        );
    }
    Ok(())
}
