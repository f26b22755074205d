//! A box on a floor pushed sideways by a force held by a load function: below μ·m·g it does
//! not move, above it slides with acceleration (F − μ·m·g)/m, which this example compares with
//! the simulation.
//!
//! `cargo run --release -p impulse-sim --example push`

use glam::DVec3;
use impulse_sim::scene::{BodyDesc, ShapeDesc};
use impulse_sim::{Load, Material, World, WorldSettings};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let (mu, g, m) = (0.4, 9.81, 1.0);
    for push in [0.5, 1.5] {
        let mut world = World::new(WorldSettings {
            default_contact: Material {
                friction: mu,
                restitution: 0.0,
            },
            ..WorldSettings::new(1e-4)
        })?;
        world.add_body(
            &BodyDesc::fixed("floor", ShapeDesc::cuboid([5.0, 5.0, 0.1])).at([0.0, 0.0, -0.1]),
        )?;
        let cube = world.add_body(
            &BodyDesc::new("box", ShapeDesc::cuboid([0.05, 0.05, 0.05]))
                .at([0.0, 0.0, 0.05])
                .with_mass(m),
        )?;
        let force = push * mu * m * g; // half and one and a half times the friction limit
        // Pushed through its centre of mass, re-evaluated 100 times a second.
        world.set_load_fn(cube, 100.0, move |_, _| {
            Load::force(DVec3::new(force, 0.0, 0.0))
        })?;
        world.step_until(0.2)?; // settle into sliding (or sticking)
        // Positions every 10 ms for a second, fitted by x = c + v·t + ½·a·t².
        let mut samples = Vec::new();
        for k in 0..=100 {
            world.step_until(0.2 + 0.01 * f64::from(k))?;
            samples.push((world.time() - 0.2, world.state(cube)?.com.x));
        }
        let measured = quadratic_fit(&samples);
        let expected = ((force - mu * m * g) / m).max(0.0);
        println!(
            "push {:.1}·μmg: acceleration {measured:.4} m/s², expected {expected:.4} m/s²",
            push
        );
    }
    Ok(())
}

/// The acceleration of the least-squares fit x = c + v·t + ½·a·t² (normal equations).
fn quadratic_fit(samples: &[(f64, f64)]) -> f64 {
    let mut ata = glam::DMat3::ZERO;
    let mut atb = glam::DVec3::ZERO;
    for &(t, x) in samples {
        let row = glam::DVec3::new(1.0, t, 0.5 * t * t);
        ata += glam::DMat3::from_cols(row * row.x, row * row.y, row * row.z);
        atb += row * x;
    }
    (ata.inverse() * atb).z
}
