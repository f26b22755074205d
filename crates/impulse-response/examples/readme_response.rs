//! The example of this crate's README.md, verbatim after this header (`cargo xtask ci` checks
//! that they are equal; `cargo test` builds it). Run it with
//! `cargo run -p impulse-response --example readme_response`.

use impulse_geom::{DMat3, DVec3};
use impulse_response::{CollisionMatrix, ResponseError, Restitution, Settings, resolve};

fn main() -> Result<(), ResponseError> {
    // A particle of mass 1 hitting a fixed wall head-on: K = 1/m. Restitution e = 0.5.
    let k = CollisionMatrix::new(DMat3::IDENTITY)?;
    let u0 = DVec3::new(0.0, 0.0, -2.0); // approaching along the normal (z)
    let r = resolve(&k, u0, 0.3, 0.5, Restitution::Stronge, &Settings::default())?;
    assert!((r.velocity.z - 1.0).abs() < 1e-9); // leaves at e · 2
    assert!((r.impulse.z - 3.0).abs() < 1e-9); // p = m (1 + e) · 2

    // A glancing blow with friction μ = 0.3: sliding stops during the collision (sticking).
    let u0 = DVec3::new(0.1, 0.0, -2.0);
    let r = resolve(&k, u0, 0.3, 0.5, Restitution::Stronge, &Settings::default())?;
    assert!(r.sticking.is_some());
    assert!(r.velocity.x.abs() < 1e-9);
    assert!(r.work <= 0.0); // energy is never created
    Ok(())
}
