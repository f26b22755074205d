//! The triangles that draw a body: each convex piece of its shape, in the body's own frame
//! (the frame of its recorded position and rotation). Shared by the `--gltf` and `--html`
//! outputs, so both draw exactly the same geometry; and the check both make of the recording
//! they draw ([`check_recording`]).
//!
//! A convex polyhedron is its faces, each triangulated as a fan with its own flat normal; an
//! exact sphere or ellipsoid is a UV sphere of [`SPHERE_STACKS`] × [`SPHERE_SLICES`], scaled by
//! its semi-axes, with the surface's normals.

use impulse_collide::Convex;
use impulse_geom::{ConvexPolyhedron, DVec3, Pose};
use impulse_sim::Recording;
use impulse_sim::body::Body;

/// `x` rounded to f32, the one place the drawing outputs round (both store f32), refusing a
/// number that is not finite as an f32 (`flag`, e.g. `--gltf`, and `what` name it).
///
/// # Errors
/// The message, naming the number and what it is.
pub(crate) fn finite_f32(x: f64, flag: &str, what: &dyn Fn() -> String) -> Result<f32, String> {
    let y = x as f32;
    if y.is_finite() {
        Ok(y)
    } else {
        Err(format!(
            "{flag}: {}: {x} cannot be written (not a finite f32)",
            what()
        ))
    }
}

/// Refuses a recording that cannot be drawn: no frame, or a frame that does not hold every
/// recorded body. `flag` (`--gltf`, `--html`) starts the message.
///
/// # Errors
/// The message, naming the frame.
pub(crate) fn check_recording(rec: &Recording, flag: &str) -> Result<(), String> {
    if rec.frames.is_empty() {
        return Err(format!("{flag}: the run recorded no frame"));
    }
    match rec
        .frames
        .iter()
        .find(|f| f.bodies.len() != rec.names.len())
    {
        Some(f) => Err(format!(
            "{flag}: the frame at t = {} holds {} bodies, not the {} recorded",
            f.time,
            f.bodies.len(),
            rec.names.len()
        )),
        None => Ok(()),
    }
}

/// Latitude bands of the UV sphere drawn for an exact sphere or ellipsoid.
pub const SPHERE_STACKS: u32 = 16;
/// Longitude segments of the UV sphere drawn for an exact sphere or ellipsoid.
pub const SPHERE_SLICES: u32 = 32;

/// Triangles of one convex piece, in its body's own frame (f64; rounded when written).
#[derive(Clone, Debug, Default)]
pub(crate) struct Triangles {
    /// Vertex positions.
    pub positions: Vec<DVec3>,
    /// Unit normals, one per vertex.
    pub normals: Vec<DVec3>,
    /// Three vertex indices per triangle, counter-clockwise seen from outside.
    pub indices: Vec<u32>,
}

/// The triangles of every convex piece of `body`'s shape, in the order of its pieces, in the
/// body's own frame (the frame of its recorded position and rotation).
pub(crate) fn body_triangles(body: &Body) -> Vec<Triangles> {
    let to_own: Pose = body.frame.inverse();
    body.shape
        .pieces()
        .iter()
        .map(|piece| piece_triangles(&piece.convex).moved(&(to_own * piece.pose)))
        .collect()
}

impl Triangles {
    /// The same triangles moved rigidly by `place`.
    pub(crate) fn moved(mut self, place: &Pose) -> Self {
        for p in &mut self.positions {
            *p = place.transform_point(*p);
        }
        for n in &mut self.normals {
            *n = place.transform_vector(*n);
        }
        self
    }
}

/// A box of half extents `half` centred on the origin, along the axes: six faces of two
/// triangles, each face with its own outward normal.
pub(crate) fn box_triangles(half: DVec3) -> Triangles {
    let mut t = Triangles::default();
    for axis in 0..3 {
        for sign in [-1.0, 1.0] {
            let mut n = DVec3::ZERO;
            n[axis] = sign;
            // Two axes across the face, ordered so that u × v = n (counter-clockwise outside).
            let (mut u, mut v) = (DVec3::ZERO, DVec3::ZERO);
            u[(axis + 1) % 3] = 1.0;
            v[(axis + 2) % 3] = sign;
            let base = t.positions.len() as u32;
            for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                t.positions.push(half * (n + a * u + b * v));
                t.normals.push(n);
            }
            t.indices
                .extend([base, base + 1, base + 2, base, base + 2, base + 3]);
        }
    }
    t
}

/// The triangles of a convex piece in its own frame.
fn piece_triangles(convex: &Convex) -> Triangles {
    match convex {
        Convex::Sphere(s) => uv_ellipsoid(DVec3::splat(s.radius())),
        Convex::Ellipsoid(e) => uv_ellipsoid(e.semi_axes()),
        Convex::Polyhedron(p) => polyhedron_triangles(p),
    }
}

/// A convex polyhedron's faces as triangle fans, each vertex repeated per face with that
/// face's outward normal (flat shading).
fn polyhedron_triangles(p: &ConvexPolyhedron) -> Triangles {
    let mut t = Triangles::default();
    for f in 0..p.face_count() as u32 {
        let normal = p.face_plane(f).normal;
        let face = p.face_vertices(f);
        let base = t.positions.len() as u32;
        for &v in face {
            t.positions.push(p.vertex(v));
            t.normals.push(normal);
        }
        for k in 1..face.len().saturating_sub(1) as u32 {
            t.indices.extend([base, base + k, base + k + 1]);
        }
    }
    t
}

/// A UV sphere of [`SPHERE_STACKS`] × [`SPHERE_SLICES`] scaled by `semi_axes`: its vertices lie
/// on the ellipsoid, with the ellipsoid's normals. The poles' degenerate triangles are left out.
pub(crate) fn uv_ellipsoid(semi_axes: DVec3) -> Triangles {
    let (stacks, slices) = (SPHERE_STACKS, SPHERE_SLICES);
    let mut t = Triangles::default();
    for i in 0..=stacks {
        let theta = std::f64::consts::PI * f64::from(i) / f64::from(stacks);
        for j in 0..=slices {
            let phi = std::f64::consts::TAU * f64::from(j) / f64::from(slices);
            let u = DVec3::new(
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            );
            t.positions.push(semi_axes * u);
            // The gradient of (x/a)² + … at a·u is 2u/a.
            t.normals.push((u / semi_axes).normalize());
        }
    }
    let at = |i: u32, j: u32| i * (slices + 1) + j;
    for i in 0..stacks {
        for j in 0..slices {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            if i + 1 < stacks {
                t.indices.extend([a, b, c]);
            }
            if i > 0 {
                t.indices.extend([a, c, d]);
            }
        }
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A UV sphere's triangles face outward and the poles have no degenerate triangles.
    #[test]
    fn uv_sphere_faces_outward() {
        let t = uv_ellipsoid(DVec3::new(1.0, 2.0, 3.0));
        let expected = 2 * SPHERE_SLICES * (SPHERE_STACKS - 1);
        assert_eq!(t.indices.len() as u32, 3 * expected);
        for tri in t.indices.chunks_exact(3) {
            let [a, b, c] = [0, 1, 2].map(|k| t.positions[tri[k] as usize]);
            let n = (b - a).cross(c - a);
            assert!(n.length() > 0.0, "degenerate triangle {tri:?}");
            assert!(n.dot(a + b + c) > 0.0, "inward triangle {tri:?}");
        }
    }

    /// A box's triangles face outward, cover its six faces (area 8(ab + bc + ca)) and lie on
    /// its surface.
    #[test]
    fn box_faces_outward() {
        let half = DVec3::new(1.0, 2.0, 3.0);
        let t = box_triangles(half);
        assert_eq!(t.indices.len(), 36);
        let mut area = 0.0;
        for tri in t.indices.chunks_exact(3) {
            let [a, b, c] = [0, 1, 2].map(|k| t.positions[tri[k] as usize]);
            let n = (b - a).cross(c - a);
            assert!(n.dot(a + b + c) > 0.0, "inward triangle {tri:?}");
            assert!((n.normalize() - t.normals[tri[0] as usize]).length() < 1e-12);
            area += 0.5 * n.length();
        }
        assert!((area - 8.0 * (2.0 + 6.0 + 3.0)).abs() < 1e-12, "{area}");
        for p in &t.positions {
            assert_eq!((p.abs() - half).max_element(), 0.0, "{p} off the surface");
        }
    }
}
