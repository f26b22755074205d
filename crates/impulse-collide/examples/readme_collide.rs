//! The example of this crate's README.md, verbatim after this header (`cargo xtask ci` checks
//! that they are equal; `cargo test` builds it). Run it with
//! `cargo run -p impulse-collide --example readme_collide`.

use impulse_collide::shape::closest;
use impulse_collide::{PairCache, Shape};
use impulse_geom::{DQuat, DVec3, Pose, primitives};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // A unit cube and a ball of radius 0.5 whose centres are 3 apart along x.
    let cube = Shape::polyhedron(primitives::cuboid(DVec3::splat(0.5))?);
    let ball = Shape::sphere(0.5)?;
    let at = |x: f64| Pose::new(DQuat::IDENTITY, DVec3::new(x, 0.0, 0.0));
    let mut cache = PairCache::default(); // closest features, kept for the next query
    let near = closest(&cube, &at(0.0), &ball, &at(3.0), &mut cache);
    assert!((near.closest.distance - 2.0).abs() < 1e-12);
    assert!((near.closest.point_a - DVec3::new(0.5, 0.0, 0.0)).length() < 1e-12);
    assert!(!near.closest.penetrating);
    Ok(())
}
