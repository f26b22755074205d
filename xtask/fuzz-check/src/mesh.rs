//! OBJ → mass properties and convex hull (`impulse-geom`, `impulse-massprops`).
//!
//! Asserted for a mesh the library accepts:
//! - a closed mesh ([`impulse_geom::PolyMesh::check_closed`]) has mass properties
//!   (thesis ch. 6) whose mass at density 1 is its volume, and whose inertia is positive
//!   definite with principal moments obeying the triangle inequality ([`crate::check_inertia`],
//!   moments from this crate's Jacobi rotations; not asserted beyond [`MAX_ASPECT`]);
//! - the convex hull of its vertices contains every vertex within the hull's documented
//!   2 × tolerance ([`impulse_geom::ConvexPolyhedron::hull`]), has Euler characteristic 2 and
//!   physical mass properties;
//! - a mesh that is itself convex ([`impulse_geom::ConvexPolyhedron::from_mesh`]) has the
//!   volume of the hull of its vertices.
//!
//! Out of bounds: more than [`MAX_FACES`] faces (the reader refuses them with an error, so
//! they are [`Outcome::Rejected`]) or [`MAX_VERTICES`] vertices.

use impulse_geom::{ConvexPolyhedron, PolyMesh, obj};
use impulse_massprops::MassProperties;

use crate::{Outcome, Violation, check_inertia};

/// Most faces a fuzzed mesh may have (the OBJ reader's limit for this check). `2000`.
pub const MAX_FACES: usize = 2000;
/// Most vertices of a fuzzed mesh (the hull's work grows with them). `4000`.
pub const MAX_VERTICES: usize = 4000;
/// Relative agreement of two volumes of one convex solid (its mesh's, its hull's): the hull
/// merges within `impulse_geom::tol::POLYHEDRON_REL` (1e-7) of the diameter, which moves the
/// volume by at most a few of those relative to it. `1e-5`.
pub const VOLUME_REL: f64 = 1e-5;
/// Largest aspect ratio √(D³/V) (D the diameter, V the volume: L/w for a needle of length L
/// and width w) whose inertia is asserted. The volume integrals' rounding relative to the
/// largest moment grows with it (the small moments are differences of faces' contributions
/// of order m·L²): the obj target measured violations of 1e-9 of I₃ at L/w ≈ 2e6, which is
/// the library's own slack (`impulse_massprops::tol::INERTIA_TRIANGLE_REL`), while at 1e5 the
/// rounding is about 2e-11. A longer needle's inertia is not asserted (its other checks are).
/// `1e5`.
pub const MAX_ASPECT: f64 = 1e5;
/// How far outside a hull face an input point may lie, in hull tolerances (the guarantee of
/// [`ConvexPolyhedron::hull`]). `2`.
pub const HULL_OUTSIDE_TOLERANCES: f64 = 2.0;

/// Checks one OBJ file's bytes (module documentation).
///
/// # Errors
/// The [`Violation`] found.
pub fn check_mesh(bytes: &[u8]) -> Result<Outcome, Violation> {
    let Some(text) = crate::text(bytes) else {
        return Ok(Outcome::Rejected("not UTF-8".into()));
    };
    let mesh = match obj::parse_with_limit(text, "fuzz", MAX_FACES) {
        Ok(m) => m,
        Err(e) => return Ok(Outcome::Rejected(e.to_string())),
    };
    if mesh.vertices().len() > MAX_VERTICES {
        return Ok(Outcome::OutOfBounds(format!(
            "{} vertices > {MAX_VERTICES}",
            mesh.vertices().len()
        )));
    }
    let closed = check_closed_mesh(&mesh)?;
    let hull = check_hull(&mesh)?;
    if let (Some(volume), Some(hull_volume)) = (closed, hull)
        && ConvexPolyhedron::from_mesh(&mesh).is_ok()
        && (volume - hull_volume).abs() > VOLUME_REL * hull_volume
    {
        return Err(Violation::Geometry(format!(
            "a convex mesh of volume {volume:e} has a hull of volume {hull_volume:e}"
        )));
    }
    Ok(if closed.is_some() || hull.is_some() {
        Outcome::Checked {
            energy_checked: false,
        }
    } else {
        Outcome::Rejected("neither closed nor with a hull".into())
    })
}

/// The mass-property invariants of a closed mesh; its volume, or `None` when it is not one
/// the library accepts.
fn check_closed_mesh(mesh: &PolyMesh) -> Result<Option<f64>, Violation> {
    if mesh.check_closed().is_err() {
        return Ok(None);
    }
    let Ok(props) = MassProperties::from_mesh(mesh, 1.0) else {
        return Ok(None);
    };
    let volume = mesh.signed_volume();
    if !(props.mass.is_finite() && props.mass > 0.0 && props.com.is_finite()) {
        return Err(Violation::MassProperties(format!(
            "closed mesh: mass {} centre {}",
            props.mass, props.com
        )));
    }
    if (props.mass - volume).abs() > VOLUME_REL * volume {
        return Err(Violation::MassProperties(format!(
            "closed mesh: mass {:e} at density 1, volume {volume:e}",
            props.mass
        )));
    }
    if aspect(mesh.diameter(), volume) <= MAX_ASPECT {
        check_inertia("closed mesh", props.inertia)?;
    }
    Ok(Some(volume))
}

/// The invariants of the hull of the mesh's vertices; its volume, or `None` when the library
/// refuses to build one.
fn check_hull(mesh: &PolyMesh) -> Result<Option<f64>, Violation> {
    let Ok(hull) = ConvexPolyhedron::hull(mesh.vertices()) else {
        return Ok(None);
    };
    let reach = HULL_OUTSIDE_TOLERANCES * hull.tolerance();
    for (i, p) in mesh.vertices().iter().enumerate() {
        for (f, plane) in hull.planes().iter().enumerate() {
            let d = plane.normal.dot(*p) - plane.offset;
            if d > reach {
                return Err(Violation::Geometry(format!(
                    "vertex {i} {p} is {d:e} outside hull face {f} (allowed {reach:e})"
                )));
            }
        }
    }
    let (v, e, f) = (
        hull.vertices().len() as i64,
        hull.edges().len() as i64,
        hull.face_count() as i64,
    );
    if v - e + f != 2 {
        return Err(Violation::Geometry(format!(
            "hull with V − E + F = {v} − {e} + {f} ≠ 2"
        )));
    }
    let props = MassProperties::from_convex(&hull, 1.0).map_err(|e| {
        Violation::MassProperties(format!("a valid hull has no mass properties: {e}"))
    })?;
    if aspect(hull.mesh().diameter(), props.mass) <= MAX_ASPECT {
        check_inertia("hull", props.inertia)?;
    }
    Ok(Some(props.mass))
}

/// The aspect ratio √(D³/V) of a solid of diameter `d` and volume `v` ([`MAX_ASPECT`]).
fn aspect(d: f64, v: f64) -> f64 {
    (d.powi(3) / v).sqrt()
}
