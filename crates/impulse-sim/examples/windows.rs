//! Prints, per window of simulated time, the wall time and what the loop and the islands did
//! in it (a development probe: where a scene spends its time):
//! `cargo run --release -p impulse-sim --example windows -- <scene.ron> [window s]`.
use std::io::Write;

use impulse_sim::{Scene, World};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let path = args.get(1).ok_or("usage: windows <scene.ron> [window s]")?;
    let window: f64 = args.get(2).map_or(Ok(0.05), |s| s.parse())?;
    let scene = Scene::read(std::path::Path::new(path))?;
    let until = scene.desc.duration.ok_or("the scene has no duration")?;
    let mut world = World::from_scene(&scene)?;
    let mut out = std::io::stdout().lock();
    let header = "until wall_s loop_steps island_steps impulsive solves sweeps at_cap micro collisions asleep";
    if writeln!(out, "{header}").is_err() {
        return Ok(());
    }
    let mut last = world.counters();
    for k in 1.. {
        let t = (f64::from(k) * window).min(until);
        let start = std::time::Instant::now();
        world.step_until(t)?;
        let wall = start.elapsed().as_secs_f64();
        let c = world.counters();
        let asleep = world.bodies().filter(|(_, b)| b.is_asleep()).count();
        let line = format!(
            "{t:.3} {wall:.4} {} {} {} {} {} {} {} {} {asleep}",
            c.steps - last.steps,
            c.island_steps - last.island_steps,
            c.transients - last.transients,
            c.island_solves - last.island_solves,
            c.island_sweeps - last.island_sweeps,
            c.unconverged_solves - last.unconverged_solves,
            c.microcollisions - last.microcollisions,
            c.collisions - last.collisions,
        );
        // A closed pipe (`| head`) ends the probe quietly.
        if writeln!(out, "{line}").is_err() || t >= until {
            break;
        }
        last = c;
    }
    Ok(())
}
