//! The example of this crate's README.md, verbatim after this header (`cargo xtask ci` checks
//! that they are equal; `cargo test` builds it). Run it with
//! `cargo run -p impulse-massprops --example readme_massprops`.

use impulse_geom::{DVec3, primitives};
use impulse_massprops::{MassError, MassProperties};

fn main() -> Result<(), MassError> {
    // A 2 × 1 × 0.5 box (half extents 1, 0.5, 0.25) of density 2: mass 2.
    let mesh = primitives::cuboid_mesh(DVec3::new(1.0, 0.5, 0.25))?;
    let props = MassProperties::from_mesh(&mesh, 2.0)?;
    assert!((props.mass - 2.0).abs() < 1e-12);
    assert!(props.com.length() < 1e-12);
    // Exact, from the polyhedron's faces: I_xx = m (b² + c²) / 12 with b = 1, c = 0.5.
    let i_xx = 2.0 * (1.0 + 0.25) / 12.0;
    assert!((props.inertia.x_axis.x - i_xx).abs() < 1e-12);
    // Principal moments come in increasing order; for a box they are the diagonal.
    let frame = props.principal()?;
    assert!(frame.moments.x <= frame.moments.y && frame.moments.y <= frame.moments.z);
    Ok(())
}
