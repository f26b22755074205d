//! The example of this crate's README.md, verbatim after this header (`cargo xtask ci` checks
//! that they are equal; `cargo test` builds it). Run it with
//! `cargo run -p impulse-geom --example readme_geom`.

use impulse_geom::{ConvexPolyhedron, DQuat, DVec3, GeomError, Pose};

fn main() -> Result<(), GeomError> {
    // The convex hull of a unit cube's corners and its centre: 8 vertices, 6 square faces.
    let mut points: Vec<DVec3> = (0..8u32)
        .map(|i| DVec3::new(f64::from(i & 1), f64::from((i >> 1) & 1), f64::from(i >> 2)))
        .collect();
    points.push(DVec3::splat(0.5));
    let cube = ConvexPolyhedron::hull(&points)?;
    assert_eq!((cube.vertices().len(), cube.face_count()), (8, 6));

    // A pose maps body coordinates to world coordinates: a quarter turn about z, then up 1.
    let pose = Pose::new(
        DQuat::from_rotation_z(std::f64::consts::FRAC_PI_2),
        DVec3::Z,
    );
    let p = pose.transform_point(DVec3::X);
    assert!((p - DVec3::new(0.0, 1.0, 1.0)).length() < 1e-12);
    // SE(3) exp and log are inverse to each other.
    let back = Pose::exp(&pose.log());
    assert!((back.transform_point(DVec3::X) - p).length() < 1e-12);
    Ok(())
}
