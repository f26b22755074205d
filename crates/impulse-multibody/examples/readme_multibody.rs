//! The example of this crate's README.md, verbatim after this header (`cargo xtask ci` checks
//! that they are equal; `cargo test` builds it). Run it with
//! `cargo run -p impulse-multibody --example readme_multibody`.

use impulse_geom::{DMat3, DVec3, Pose, SpatialInertia};
use impulse_multibody::{BaseKind, JointSpec, ModelBuilder, MultibodyError, Workspace};

fn main() -> Result<(), MultibodyError> {
    // A pendulum hanging from a fixed base: a 1 kg rod, its centre of mass 0.5 from the hinge.
    let rod = SpatialInertia::new(1.0, DVec3::new(0.5, 0.0, 0.0), DMat3::IDENTITY * 0.01);
    let mut b = ModelBuilder::new(BaseKind::Fixed);
    b.gravity(DVec3::new(0.0, -9.81, 0.0))
        .link("ground", SpatialInertia::ZERO)
        .link("rod", rod)
        .joint(JointSpec::revolute(
            "hinge",
            "ground",
            "rod",
            Pose::IDENTITY,
            DVec3::Z,
        ));
    let model = b.build()?;
    let mut ws = Workspace::new(&model);
    let mut qdd = [0.0];
    impulse_multibody::forward_dynamics(&model, &mut ws, &[0.0], &[0.0], &[0.0], None, &mut qdd)?;
    // Horizontal rod: q̈ = −m g c / (I + m c²) (Featherstone's articulated-body algorithm).
    assert!((qdd[0] + 9.81 * 0.5 / (0.01 + 0.25)).abs() < 1e-12);
    Ok(())
}
