//! Primitive convex polyhedra: boxes, regular prisms and geodesic spheres.
//!
//! Each comes as a [`PolyMesh`] (for mass properties or export) and, except the corner
//! tetrahedron, as a validated [`ConvexPolyhedron`]. All but the corner tetrahedron are centred
//! on the origin, which is also their centre of mass.

use std::collections::HashMap;
use std::f64::consts::TAU;

use glam::DVec3;

use crate::error::GeomError;
use crate::mesh::PolyMesh;
use crate::polyhedron::ConvexPolyhedron;

/// The finest geodesic sphere [`geodesic_sphere_mesh`] builds: level 10 has 5,242,880 faces
/// (about 200 MB as a polyhedron). The cap turns a typo into an error instead of exhausting
/// memory.
pub const MAX_GEODESIC_LEVEL: u32 = 10;

fn positive(name: &'static str, value: f64) -> Result<f64, GeomError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(GeomError::InvalidParameter {
            name,
            value,
            requirement: "must be finite and > 0",
        })
    }
}

/// A box with the given half side lengths, centred on the origin, axis-aligned: 8 vertices and
/// 6 quadrilateral faces.
///
/// # Errors
/// [`GeomError::InvalidParameter`] unless every half extent is finite and positive.
pub fn cuboid_mesh(half_extents: DVec3) -> Result<PolyMesh, GeomError> {
    let h = DVec3::new(
        positive("half_extents.x", half_extents.x)?,
        positive("half_extents.y", half_extents.y)?,
        positive("half_extents.z", half_extents.z)?,
    );
    // Vertex i has coordinate sign bits (x: bit 0, y: bit 1, z: bit 2).
    let vertices = (0..8)
        .map(|i: u32| {
            let s = |bit: u32| if i >> bit & 1 == 1 { 1.0 } else { -1.0 };
            DVec3::new(s(0) * h.x, s(1) * h.y, s(2) * h.z)
        })
        .collect();
    let faces = [
        [0, 2, 3, 1], // -z
        [4, 5, 7, 6], // +z
        [0, 1, 5, 4], // -y
        [2, 6, 7, 3], // +y
        [0, 4, 6, 2], // -x
        [1, 3, 7, 5], // +x
    ];
    PolyMesh::new(vertices, faces)
}

/// A box as a convex polyhedron; see [`cuboid_mesh`].
///
/// # Errors
/// As [`cuboid_mesh`].
pub fn cuboid(half_extents: DVec3) -> Result<ConvexPolyhedron, GeomError> {
    ConvexPolyhedron::from_mesh(&cuboid_mesh(half_extents)?)
}

/// The corner tetrahedron with legs `legs` along the axes: the hull of the origin,
/// `legs.x·î`, `legs.y·ĵ` and `legs.z·k̂` (thesis Table 6.1 uses legs (5, 4, 3)). Unlike the other
/// primitives it is not centred: its centre of mass is `legs / 4`.
///
/// # Errors
/// [`GeomError::InvalidParameter`] unless every leg is finite and positive.
pub fn corner_tetrahedron_mesh(legs: DVec3) -> Result<PolyMesh, GeomError> {
    let l = DVec3::new(
        positive("legs.x", legs.x)?,
        positive("legs.y", legs.y)?,
        positive("legs.z", legs.z)?,
    );
    let vertices = vec![
        DVec3::ZERO,
        DVec3::new(l.x, 0.0, 0.0),
        DVec3::new(0.0, l.y, 0.0),
        DVec3::new(0.0, 0.0, l.z),
    ];
    PolyMesh::new(vertices, [[0u32, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
}

/// A right prism over a regular `sides`-gon inscribed in a circle of `radius` about the z axis,
/// spanning `z ∈ [−half_height, half_height]`; vertex 0 lies on the +x axis.
///
/// # Errors
/// [`GeomError::InvalidParameter`] if `sides < 3` or a length is not finite and positive.
pub fn regular_prism_mesh(
    sides: u32,
    radius: f64,
    half_height: f64,
) -> Result<PolyMesh, GeomError> {
    if sides < 3 {
        return Err(GeomError::InvalidParameter {
            name: "sides",
            value: f64::from(sides),
            requirement: "a prism needs at least 3 sides",
        });
    }
    let (r, hh) = (
        positive("radius", radius)?,
        positive("half_height", half_height)?,
    );
    let n = sides;
    let mut vertices = Vec::with_capacity(2 * n as usize);
    for z in [-hh, hh] {
        for k in 0..n {
            let a = TAU * f64::from(k) / f64::from(n);
            vertices.push(DVec3::new(r * a.cos(), r * a.sin(), z));
        }
    }
    let mut faces: Vec<Vec<u32>> = Vec::with_capacity(n as usize + 2);
    faces.push((0..n).rev().collect()); // bottom, seen from below
    faces.push((n..2 * n).collect()); // top
    for k in 0..n {
        let k1 = (k + 1) % n;
        faces.push(vec![k, k1, n + k1, n + k]);
    }
    PolyMesh::new(vertices, faces)
}

/// A regular prism as a convex polyhedron; see [`regular_prism_mesh`].
///
/// # Errors
/// As [`regular_prism_mesh`].
pub fn regular_prism(
    sides: u32,
    radius: f64,
    half_height: f64,
) -> Result<ConvexPolyhedron, GeomError> {
    ConvexPolyhedron::from_mesh(&regular_prism_mesh(sides, radius, half_height)?)
}

/// A geodesic sphere: the icosahedron inscribed in the sphere of `radius`, refined
/// `level − 1` times by splitting every triangle into four at its edge midpoints and pushing
/// the midpoints out onto the sphere.
///
/// Levels are numbered as the "approx." column of thesis Table 6.2: level 1 is the icosahedron
/// (12 vertices, 30 edges, 20 faces), and level n has `10·4^(n−1) + 2` vertices,
/// `30·4^(n−1)` edges and `20·4^(n−1)` triangles. Every vertex lies on the sphere.
///
/// # Errors
/// [`GeomError::InvalidParameter`] if `level` is 0 or above [`MAX_GEODESIC_LEVEL`], or `radius`
/// is not finite and positive.
pub fn geodesic_sphere_mesh(level: u32, radius: f64) -> Result<PolyMesh, GeomError> {
    if level == 0 || level > MAX_GEODESIC_LEVEL {
        return Err(GeomError::InvalidParameter {
            name: "level",
            value: f64::from(level),
            requirement: "geodesic levels run from 1 (icosahedron) to MAX_GEODESIC_LEVEL (10)",
        });
    }
    let r = positive("radius", radius)?;
    // Icosahedron: the cyclic permutations of (0, ±1, ±φ), on the unit sphere.
    let phi = 0.5 * (1.0 + 5f64.sqrt());
    let mut vertices: Vec<DVec3> = Vec::new();
    for (a, b) in [(1.0, phi), (-1.0, phi), (1.0, -phi), (-1.0, -phi)] {
        vertices.push(DVec3::new(0.0, a, b));
        vertices.push(DVec3::new(a, b, 0.0));
        vertices.push(DVec3::new(b, 0.0, a));
    }
    for v in &mut vertices {
        *v = v.normalize();
    }
    // The 20 faces are the triples of mutually adjacent vertices (edge length 2 before
    // scaling); orient each counter-clockwise from outside.
    let edge = 2.0 / (1.0 + phi * phi).sqrt();
    let adjacent =
        |i: usize, j: usize| (vertices[i].distance(vertices[j]) - edge).abs() < 0.5 * edge;
    let mut triangles: Vec<[u32; 3]> = Vec::with_capacity(20);
    for i in 0..12 {
        for j in i + 1..12 {
            for k in j + 1..12 {
                if adjacent(i, j) && adjacent(j, k) && adjacent(i, k) {
                    let (a, b, c) = (vertices[i], vertices[j], vertices[k]);
                    let outward = (b - a).cross(c - a).dot(a + b + c) > 0.0;
                    let t = if outward { [i, j, k] } else { [i, k, j] };
                    triangles.push(t.map(|x| x as u32));
                }
            }
        }
    }
    for _ in 1..level {
        let mut midpoint: HashMap<(u32, u32), u32> = HashMap::new();
        let mut mid = |a: u32, b: u32, vertices: &mut Vec<DVec3>| {
            *midpoint.entry((a.min(b), a.max(b))).or_insert_with(|| {
                vertices.push((vertices[a as usize] + vertices[b as usize]).normalize());
                (vertices.len() - 1) as u32
            })
        };
        let mut next = Vec::with_capacity(triangles.len() * 4);
        for [a, b, c] in triangles {
            let (ab, bc, ca) = (
                mid(a, b, &mut vertices),
                mid(b, c, &mut vertices),
                mid(c, a, &mut vertices),
            );
            next.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
        }
        triangles = next;
    }
    for v in &mut vertices {
        *v *= r;
    }
    PolyMesh::new(vertices, triangles)
}

/// A geodesic sphere as a convex polyhedron; see [`geodesic_sphere_mesh`].
///
/// # Errors
/// As [`geodesic_sphere_mesh`].
pub fn geodesic_sphere(level: u32, radius: f64) -> Result<ConvexPolyhedron, GeomError> {
    ConvexPolyhedron::from_mesh(&geodesic_sphere_mesh(level, radius)?)
}
