//! The example of this crate's README.md, verbatim after this header (`cargo xtask ci` checks
//! that they are equal; `cargo test` builds it). Run it with
//! `cargo run -p impulse-reduced --example readme_reduced`.

use impulse_reduced::reference::Configuration;
use impulse_reduced::{ConstructOptions, Error, ReducedModel, scenes};

fn main() -> Result<(), Error> {
    // A bundled compliant mechanism: a helix of 8 links on a fixed base, its tip the end
    // effector. The reduced model is linearised at rest.
    let mechanism = scenes::helix(8).build()?;
    let rest = Configuration::rest(&mechanism);
    let model = ReducedModel::build(&mechanism, &rest, &[], &ConstructOptions::default())?;
    // 1 mN along the tip's x axis (body wrench: force on top, torque below).
    let mut wrench = vec![0.0; 6 * model.end_effectors.len()];
    wrench[0] = 1e-3;
    let (tips, _links) = model.static_twists(&wrench);
    // The tip gives way along the push: the coupled compliance is positive definite.
    assert!(tips[0].v.x > 0.0);
    Ok(())
}
