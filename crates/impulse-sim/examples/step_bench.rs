//! The Rust side of the Python binding's overhead measurement: a scene stepped `STEPS` times
//! by `dt`, every body's state read once per step (as `World.states()` does from Python), the
//! wall time of the loop printed. `examples/python/bench_step.py` writes the scene, runs this
//! and the same loop through `impulse`, and prints the ratio.
//!
//! `cargo run --release -p impulse-sim --example step_bench -- SCENE.ron [STEPS] [DT]`

use std::time::Instant;

use impulse_sim::{Scene, World};

/// Calls of `step(0)` per round of the per-call cost.
const STEP0_CALLS: usize = 20_000;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = args
        .next()
        .ok_or("usage: step_bench SCENE.ron [STEPS] [DT]")?;
    let steps: usize = args.next().map_or(Ok(1000), |s| s.parse())?;
    let dt: f64 = args.next().map_or(Ok(1e-3), |s| s.parse())?;
    let mut world = World::from_scene(&Scene::read(std::path::Path::new(&path))?)?;
    let start = Instant::now();
    let mut checksum = 0.0;
    for _ in 0..steps {
        world.step(dt)?;
        // The states as rows of 16 numbers, as the binding copies them into one array.
        let rows: Vec<[f64; 16]> = world
            .states()
            .iter()
            .map(|s| {
                let mut r = [0.0; 16];
                r[0..3].copy_from_slice(&s.position.to_array());
                r[3..7].copy_from_slice(&s.rotation.to_array());
                r[7..10].copy_from_slice(&s.velocity.to_array());
                r[10..13].copy_from_slice(&s.omega.to_array());
                r[13..16].copy_from_slice(&s.com.to_array());
                r
            })
            .collect();
        checksum += rows.iter().map(|r| r[2]).sum::<f64>();
    }
    let wall = start.elapsed().as_secs_f64();
    // What a call that simulates nothing costs (`step(0)`: the checks and the copy of the
    // world a failed step is rolled back to), best of three rounds: the Python side's same
    // call costs this plus the binding's own work.
    let mut step0 = f64::INFINITY;
    for _ in 0..3 {
        let start = Instant::now();
        for _ in 0..STEP0_CALLS {
            world.step(0.0)?;
        }
        step0 = step0.min(start.elapsed().as_secs_f64() / STEP0_CALLS as f64);
    }
    println!(
        "{{\"bodies\": {}, \"steps\": {steps}, \"dt\": {dt}, \"wall\": {wall}, \"checksum\": {checksum}, \"step0\": {step0}}}",
        world.len()
    );
    Ok(())
}
