//! A pyramid of 55 blocks (rows of 10, 9, …, 1, each block centred over the gap of the two
//! below), in the default (switching) contact model: prints, every half second, the wall time,
//! island steps, the contact solver's sweeps and solves stopped at its cap, how many blocks
//! sleep, the top block's drift and the deepest interpenetration the independent monitor saw.
//!
//! `cargo run --release -p impulse-sim --example pyramid -- [rows] [seconds]`

use impulse_sim::monitor::PenetrationMonitor;
use impulse_sim::scene::{BodyDesc, ShapeDesc};
use impulse_sim::{World, WorldSettings};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let rows: usize = std::env::args().nth(1).map_or(Ok(10), |s| s.parse())?;
    let duration: f64 = std::env::args().nth(2).map_or(Ok(5.0), |s| s.parse())?;
    let eps = 2e-4;
    let mut world = World::new(WorldSettings::new(eps))?;
    world.add_body(
        &BodyDesc::fixed("floor", ShapeDesc::cuboid([2.0, 1.0, 0.05])).at([0.0, 0.0, -0.05]),
    )?;
    // Blocks 10 × 7.5 × 5 cm, a block's width apart plus ε_c/2, released ε_c/2 above the row
    // below.
    let half = [0.05, 0.0375, 0.025];
    let (gap, pitch) = (0.5 * eps, 2.0 * half[0] + 0.5 * eps);
    let mut top = None;
    for row in 0..rows {
        let count = rows - row;
        let z = half[2] + gap + row as f64 * (2.0 * half[2] + gap);
        for k in 0..count {
            let x = (k as f64 - 0.5 * (count as f64 - 1.0)) * pitch;
            top = Some(
                world.add_body(
                    &BodyDesc::new(format!("r{row}b{k}"), ShapeDesc::cuboid(half))
                        .at([x, 0.0, z])
                        .with_density(700.0),
                )?,
            );
        }
    }
    let top = top.ok_or("no blocks")?;
    let start = world.state(top)?.position;
    let mut monitor = PenetrationMonitor::new();
    let wall = std::time::Instant::now();
    let mut t = 0.0;
    while t < duration - 1e-9 {
        t += 0.5;
        world.step_until(t)?;
        monitor.sample(&world);
        let asleep = world.bodies().filter(|(_, b)| b.is_asleep()).count();
        let c = world.counters();
        println!(
            "t {t:.1} s  wall {:.2} s  island steps {}  sweeps {}  unconverged {}  asleep {asleep}  top drift {:.2} ε_c  deepest {:.3} ε_c",
            wall.elapsed().as_secs_f64(),
            c.island_steps,
            c.island_sweeps,
            c.unconverged_solves,
            (world.state(top)?.position - start).length() / eps,
            monitor.report().max_depth / eps
        );
    }
    Ok(())
}
