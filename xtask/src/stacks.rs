//! The stack study of `cargo xtask bench` (thesis §3.5: stacks are the impulse-based method's
//! known weak spot: "three books are noticeably slower; four or more grind to a halt"), run in
//! the pure impulse model ([`ContactMode::Impulse`]; `cargo xtask bench --peers` runs stacks in
//! both models).
//!
//! Stacks of 1 to 8 wooden blocks (10 × 7.5 × 5 cm, ρ = 700 kg/m³) are released at rest, ε_c/2
//! apart, on a fixed floor (μ = 0.5, e = 0.3, ε_c = 0.2 mm) and simulated for one second. The
//! study reports what a stack costs (wall time per simulated second, pair checks, impulses) and
//! whether it stayed a stack (the top block's drift and the largest interpenetration), and
//! fits the growth of the pair checks with the number of blocks.

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use impulse_sim::scene::{BodyDesc, ContactDesc, ShapeDesc};
use impulse_sim::{ContactMode, Scene, SceneDesc, World, run};

use crate::Result;

/// Numbers of blocks studied.
pub const STACK_SIZES: [usize; 6] = [1, 2, 3, 4, 6, 8];
/// Simulated time per stack (s).
pub const STACK_DURATION: f64 = 1.0;
/// Collision epsilon of the study (m).
pub const STACK_EPSILON: f64 = 2e-4;
/// Half extents of a block (m).
const HALF: [f64; 3] = [0.05, 0.0375, 0.025];

/// One stack's measurements.
pub struct StackRow {
    /// Blocks in the stack.
    pub blocks: usize,
    /// Wall time per simulated second.
    pub wall_per_second: f64,
    /// Pair checks in the run.
    pub pair_checks: u64,
    /// Collisions and microcollisions in the run.
    pub impulses: u64,
    /// Horizontal drift of the top block over the run (m).
    pub top_drift: f64,
    /// Largest interpenetration measured, in units of ε_c.
    pub penetration_over_eps: f64,
}

/// The scene of a stack of `n` blocks, built in code.
pub fn stack_scene(n: usize) -> SceneDesc {
    let gap = 0.5 * STACK_EPSILON;
    let mut scene = SceneDesc::new()
        .with_name(format!("stack{n}"))
        .with_duration(STACK_DURATION)
        .with_collision_epsilon(STACK_EPSILON)
        .with_default_contact(ContactDesc::new(0.5, 0.3))
        .with_body(
            BodyDesc::fixed("floor", ShapeDesc::cuboid([0.5, 0.5, 0.05])).at([0.0, 0.0, -0.05]),
        );
    for k in 0..n {
        let z = HALF[2] + gap + k as f64 * (2.0 * HALF[2] + gap);
        scene = scene.with_body(
            BodyDesc::new(format!("block{k}"), ShapeDesc::cuboid(HALF))
                .at([0.0, 0.0, z])
                .with_density(700.0),
        );
    }
    scene
}

/// Runs one stack.
pub fn run_stack(n: usize) -> Result<StackRow> {
    // The study measures the pure impulse model (the peer bench runs both models).
    let desc = stack_scene(n).with_contact_model(ContactMode::Impulse);
    let scene = Scene::new(desc, Path::new("."));
    let mut world = World::from_scene(&scene).map_err(|e| format!("stack {n}: {e}"))?;
    let start = Instant::now();
    let rec =
        run(&mut world, STACK_DURATION, 100.0, |_| {}).map_err(|e| format!("stack {n}: {e}"))?;
    let wall = start.elapsed().as_secs_f64();
    let top = rec
        .index(&format!("block{}", n - 1))
        .ok_or("no top block")?;
    let (first, last) = (
        rec.frames.first().ok_or("no frames")?,
        rec.frames.last().ok_or("no frames")?,
    );
    let d = last.bodies[top].position - first.bodies[top].position;
    Ok(StackRow {
        blocks: n,
        wall_per_second: wall / STACK_DURATION,
        pair_checks: rec.counters.pair_checks,
        impulses: rec.counters.collisions + rec.counters.microcollisions,
        top_drift: d.x.hypot(d.y),
        penetration_over_eps: rec.max_penetration() / STACK_EPSILON,
    })
}

/// Least-squares slope of log(pair checks) against log(blocks), over stacks of 2 or more.
pub fn growth_exponent(rows: &[StackRow]) -> f64 {
    let pts: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| r.blocks >= 2 && r.pair_checks > 0)
        .map(|r| ((r.blocks as f64).ln(), (r.pair_checks as f64).ln()))
        .collect();
    let n = pts.len() as f64;
    let (sx, sy) = pts.iter().fold((0.0, 0.0), |(a, b), p| (a + p.0, b + p.1));
    let (mx, my) = (sx / n, sy / n);
    let (sxy, sxx) = pts.iter().fold((0.0, 0.0), |(a, b), p| {
        (a + (p.0 - mx) * (p.1 - my), b + (p.0 - mx) * (p.0 - mx))
    });
    sxy / sxx
}

/// Runs the study, prints its table and returns it as CSV.
pub fn study() -> Result<String> {
    println!();
    println!(
        "stacks of 10 × 7.5 × 5 cm blocks, ε_c = {STACK_EPSILON} m, {STACK_DURATION} s simulated"
    );
    println!(
        "{:>6} {:>12} {:>12} {:>10} {:>12} {:>12}",
        "blocks", "wall s/sim s", "pair checks", "impulses", "top drift m", "pen / eps_c"
    );
    let mut rows = Vec::new();
    let mut csv = String::from(
        "blocks,wall_per_sim_second,pair_checks,impulses,top_drift_m,penetration_over_eps_c\n",
    );
    for n in STACK_SIZES {
        let r = run_stack(n)?;
        println!(
            "{:>6} {:>12.4} {:>12} {:>10} {:>12.2e} {:>12.3}",
            r.blocks,
            r.wall_per_second,
            r.pair_checks,
            r.impulses,
            r.top_drift,
            r.penetration_over_eps
        );
        let values = [
            r.blocks as f64,
            r.wall_per_second,
            r.pair_checks as f64,
            r.impulses as f64,
            r.top_drift,
            r.penetration_over_eps,
        ];
        let _ = writeln!(csv, "{}", values.map(|v| v.to_string()).join(","));
        rows.push(r);
    }
    println!(
        "pair checks grow as blocks^{:.2} (least squares over 2–8 blocks)",
        growth_exponent(&rows)
    );
    Ok(csv)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The exponent fit recovers a power law exactly.
    #[test]
    fn growth_exponent_of_a_power_law() {
        let rows: Vec<StackRow> = [2usize, 3, 5, 8]
            .iter()
            .map(|&n| StackRow {
                blocks: n,
                wall_per_second: 0.0,
                pair_checks: (7.0e6 * (n as f64).powf(2.5)).round() as u64,
                impulses: 0,
                top_drift: 0.0,
                penetration_over_eps: 0.0,
            })
            .collect();
        assert!((growth_exponent(&rows) - 2.5).abs() < 1e-3);
    }

    /// Sideways drift of a block resting by microcollisions, in units of ε_c: a resting body
    /// vibrates with an amplitude of about ε_c (thesis §3.5) and its position random-walks a
    /// few ε_c (measured: 3–5 ε_c over a second); a block that slid off or toppled would be
    /// hundreds of ε_c away.
    const REST_DRIFT_EPS: f64 = 20.0;

    /// A three-block stack stays a stack: the top block drifts only by the microcollision
    /// vibration and no pair interpenetrates by more than ε_c.
    #[test]
    fn three_block_stack_stands() {
        let r = run_stack(3).unwrap();
        assert!(
            r.top_drift < REST_DRIFT_EPS * STACK_EPSILON,
            "drift {}",
            r.top_drift
        );
        assert!(r.penetration_over_eps <= 1.0);
        assert!(r.impulses > 0);
    }
}
