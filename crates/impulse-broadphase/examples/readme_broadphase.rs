//! The example of this crate's README.md, verbatim after this header (`cargo xtask ci` checks
//! that they are equal; `cargo test` builds it). Run it with
//! `cargo run -p impulse-broadphase --example readme_broadphase`.

use impulse_broadphase::{BroadphaseError, CoherentHash, Levels};
use impulse_geom::{Aabb, DVec3};

fn main() -> Result<(), BroadphaseError> {
    // Two tile sizes, coarsest first; boxes come in under ids of the caller's choosing.
    let mut hash = CoherentHash::new(Levels::new([4.0, 1.0])?);
    let cube = |x: f64| Aabb::new(DVec3::new(x, 0.0, 0.0), DVec3::new(x + 0.5, 0.5, 0.5));
    hash.insert(0, cube(0.0))?;
    hash.insert(1, cube(0.25))?;
    hash.insert(2, cube(20.0))?;
    assert_eq!(hash.overlapping_pairs(), [(0, 1)]);
    let _ = hash.take_new_close_pairs();

    // Box 2 moves next to box 0: the pair becomes close, and is reported once.
    hash.update(2, cube(0.4))?;
    assert!(hash.take_new_close_pairs().contains(&(0, 2)));
    assert!(hash.take_new_close_pairs().is_empty());
    Ok(())
}
