//! Convex polyhedra with the full feature topology that a closest-features algorithm walks.
//!
//! A [`ConvexPolyhedron`] stores vertices, polygonal faces (counter-clockwise loops seen from
//! outside, each with its outward [`Plane`]), and edges that know their two vertices and two
//! faces. Around every vertex its edges are listed in counter-clockwise order seen from outside;
//! around every face its edges follow the face loop. Lin–Canny and V-Clip walk exactly these
//! adjacencies (thesis chapter 2.2).
//!
//! All constructors — [`ConvexPolyhedron::hull`], [`ConvexPolyhedron::from_faces`] and the
//! primitives in [`crate::primitives`] — end in one validation pipeline, judged at one length
//! scale, [`ConvexPolyhedron::tolerance`] ([`tol::POLYHEDRON_REL`] times the bounding-box
//! diagonal):
//! 1. the faces form a closed, consistently and outwardly oriented surface;
//! 2. adjacent faces that are coplanar within the tolerance are merged into one polygon, and
//!    vertices left between only two faces (on a straight edge) are removed, so every feature
//!    is geometrically distinct (a closest-features walk cycles on coplanar faces);
//! 3. every face is a planar convex polygon, every edge is convex, the faces around every vertex
//!    form a convex cone, and V − E + F = 2.
//!
//! Merging and collinear-vertex removal never change the solid; they only drop redundant
//! vertices and edges.

use std::collections::HashMap;
use std::f64::consts::TAU;

use glam::DVec3;

use crate::aabb::Aabb;
use crate::error::GeomError;
use crate::hull;
use crate::mesh::{self, PolyMesh};
use crate::plane::Plane;
use crate::pose::Pose;
use crate::tol;

/// An edge of a convex polyhedron.
///
/// Seen from outside, walking from `tail` to `head`, face `left` is on the left: its loop
/// traverses `tail → head`, and face `right`'s loop traverses `head → tail`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Edge {
    /// Start vertex.
    pub tail: u32,
    /// End vertex.
    pub head: u32,
    /// Face whose loop runs `tail → head`.
    pub left: u32,
    /// Face whose loop runs `head → tail`.
    pub right: u32,
}

impl Edge {
    /// The endpoint that is not `v` (`v` must be an endpoint).
    pub fn other_vertex(&self, v: u32) -> u32 {
        if v == self.tail { self.head } else { self.tail }
    }

    /// The face that is not `f` (`f` must be one of the edge's faces).
    pub fn other_face(&self, f: u32) -> u32 {
        if f == self.left {
            self.right
        } else {
            self.left
        }
    }
}

/// A validated convex polyhedron with feature topology (see the module documentation).
///
/// Vertices, faces and edges are numbered densely from 0 (`u32`). Coordinates are in the
/// polyhedron's own (body) frame; nothing here assumes the origin is the centre of mass.
#[derive(Clone, Debug)]
pub struct ConvexPolyhedron {
    /// Vertices and counter-clockwise face loops.
    mesh: PolyMesh,
    /// Outward plane of each face (faces).
    planes: Vec<Plane>,
    /// Edges (edges).
    edges: Vec<Edge>,
    /// For half-edge `h` of the mesh (face `f`, corner `k`), the edge from corner `k` to `k + 1`
    /// (half-edges; parallel to the mesh's face loops).
    face_edges: Vec<u32>,
    /// `vertex_edge_starts[v]..vertex_edge_starts[v + 1]` indexes `vertex_edges` (vertices + 1).
    vertex_edge_starts: Vec<u32>,
    /// Edges around each vertex, counter-clockwise seen from outside (2 × edges).
    vertex_edges: Vec<u32>,
    /// The length scale the polyhedron was validated with.
    tolerance: f64,
}

impl ConvexPolyhedron {
    /// The convex hull of a point set.
    ///
    /// Robust to duplicate points and to many coplanar points: coplanar hull triangles are
    /// merged into polygon faces and points on edges or faces are not kept as vertices. Every
    /// input point lies inside the hull or within [`ConvexPolyhedron::tolerance`] outside it.
    ///
    /// # Errors
    /// [`GeomError::NonFinite`], [`GeomError::TooFewPoints`] (fewer than 4),
    /// [`GeomError::DegeneratePoints`] (all points coincident, collinear or coplanar within the
    /// tolerance), or [`GeomError::HullFailed`] if a numerical inconsistency was detected (the
    /// result is then refused rather than returned wrong).
    pub fn hull(points: &[DVec3]) -> Result<Self, GeomError> {
        mesh::check_finite(points, "point")?;
        if points.len() < 4 {
            return Err(GeomError::TooFewPoints {
                count: points.len(),
            });
        }
        let tolerance = tol::POLYHEDRON_REL * diameter(points);
        let triangles = hull::quickhull(points, tolerance)?;
        let faces: Vec<Vec<u32>> = triangles.iter().map(|t| t.to_vec()).collect();
        build(points, faces, tolerance, Origin::Hull)
    }

    /// A convex polyhedron from explicit vertices and faces (vertex loops, counter-clockwise
    /// seen from outside).
    ///
    /// Adjacent coplanar faces (a box given as 12 triangles, say) are merged, and vertices on
    /// straight edges removed (see the module documentation).
    ///
    /// # Errors
    /// Every [`PolyMesh::new`] error; [`GeomError::UnusedVertex`] if a vertex belongs to no face;
    /// [`GeomError::OpenEdge`], [`GeomError::InconsistentOrientation`],
    /// [`GeomError::NonManifoldEdge`], [`GeomError::InwardOrientation`],
    /// [`GeomError::ZeroVolume`], [`GeomError::DegenerateFace`], [`GeomError::NonPlanarFace`],
    /// [`GeomError::NotConvex`], [`GeomError::NonConvexFace`], [`GeomError::NonConvexVertex`],
    /// [`GeomError::EulerCharacteristic`].
    pub fn from_faces<F, I>(vertices: Vec<DVec3>, faces: F) -> Result<Self, GeomError>
    where
        F: IntoIterator<Item = I>,
        I: AsRef<[u32]>,
    {
        let mesh = PolyMesh::new(vertices, faces)?;
        Self::from_mesh(&mesh)
    }

    /// A convex polyhedron from a closed polygon mesh; see [`ConvexPolyhedron::from_faces`].
    ///
    /// # Errors
    /// As [`ConvexPolyhedron::from_faces`].
    pub fn from_mesh(mesh: &PolyMesh) -> Result<Self, GeomError> {
        let tolerance = tol::POLYHEDRON_REL * mesh.diameter();
        let faces: Vec<Vec<u32>> = mesh.faces().map(<[u32]>::to_vec).collect();
        build(mesh.vertices(), faces, tolerance, Origin::Faces)
    }

    /// The polygon mesh (vertices and counter-clockwise face loops), e.g. for mass properties.
    pub fn mesh(&self) -> &PolyMesh {
        &self.mesh
    }

    /// Vertex positions (body frame).
    pub fn vertices(&self) -> &[DVec3] {
        self.mesh.vertices()
    }

    /// Position of vertex `v`.
    pub fn vertex(&self, v: u32) -> DVec3 {
        self.mesh.vertices()[v as usize]
    }

    /// Number of faces.
    pub fn face_count(&self) -> usize {
        self.planes.len()
    }

    /// Vertices of face `f`, counter-clockwise seen from outside.
    pub fn face_vertices(&self, f: u32) -> &[u32] {
        self.mesh.face(f as usize)
    }

    /// Edges of face `f`, in loop order: edge `k` joins `face_vertices(f)[k]` to
    /// `face_vertices(f)[k + 1]` (cyclically).
    pub fn face_edges(&self, f: u32) -> &[u32] {
        let start = self.mesh.face_start(f as usize);
        &self.face_edges[start..start + self.mesh.face(f as usize).len()]
    }

    /// Outward plane of face `f`.
    pub fn face_plane(&self, f: u32) -> Plane {
        self.planes[f as usize]
    }

    /// All face planes, indexed by face.
    pub fn planes(&self) -> &[Plane] {
        &self.planes
    }

    /// All edges.
    pub fn edges(&self) -> &[Edge] {
        &self.edges
    }

    /// Edge `e`.
    pub fn edge(&self, e: u32) -> Edge {
        self.edges[e as usize]
    }

    /// Edges incident to vertex `v`, counter-clockwise seen from outside. Between consecutive
    /// edges `e_i`, `e_{i+1}` lies the face that is the left face of `e_{i+1}` when it is
    /// oriented away from `v`.
    pub fn vertex_edges(&self, v: u32) -> &[u32] {
        let r = self.vertex_edge_starts[v as usize] as usize
            ..self.vertex_edge_starts[v as usize + 1] as usize;
        &self.vertex_edges[r]
    }

    /// The length scale this polyhedron was validated with: points within it of a face plane
    /// count as on the face. It is [`tol::POLYHEDRON_REL`] times the bounding-box diagonal of
    /// the input.
    pub fn tolerance(&self) -> f64 {
        self.tolerance
    }

    /// The index of a vertex farthest along `dir` (brute force over all vertices; the lowest
    /// index among ties).
    pub fn support(&self, dir: DVec3) -> u32 {
        let mut best = (0u32, f64::NEG_INFINITY);
        for (i, v) in self.vertices().iter().enumerate() {
            let d = v.dot(dir);
            if d > best.1 {
                best = (i as u32, d);
            }
        }
        best.0
    }

    /// The index of a vertex farthest along `dir`, found by hill climbing over vertex
    /// neighbours from `start`. On a convex polyhedron a vertex with no better neighbour is a
    /// global maximum, so this returns a vertex of the same support value as
    /// [`ConvexPolyhedron::support`], in time proportional to the path length: use it with the
    /// previous answer as `start` when `dir` changes slowly.
    pub fn support_from(&self, dir: DVec3, start: u32) -> u32 {
        let mut v = start;
        let mut best = self.vertex(v).dot(dir);
        loop {
            let mut next = None;
            for &e in self.vertex_edges(v) {
                let w = self.edge(e).other_vertex(v);
                let d = self.vertex(w).dot(dir);
                if d > best {
                    best = d;
                    next = Some(w);
                }
            }
            match next {
                Some(w) => v = w,
                None => return v,
            }
        }
    }

    /// The bounding box of the polyhedron placed at `pose` (tight: it touches the polyhedron
    /// on all six sides).
    pub fn aabb(&self, pose: &Pose) -> Aabb {
        Aabb::from_points(self.vertices().iter().map(|&v| pose.transform_point(v)))
    }

    /// Radius of the smallest sphere about `center` (body frame, e.g. the centre of mass)
    /// that contains the polyhedron.
    pub fn bounding_radius(&self, center: DVec3) -> f64 {
        self.vertices()
            .iter()
            .map(|v| v.distance(center))
            .fold(0.0, f64::max)
    }

    /// The largest signed distance of `p` from the face planes: negative inside (minus the
    /// distance to the nearest face plane), positive outside (a lower bound of the distance).
    pub fn max_plane_distance(&self, p: DVec3) -> f64 {
        self.planes
            .iter()
            .map(|pl| pl.signed_distance(p))
            .fold(f64::NEG_INFINITY, f64::max)
    }

    /// True when `p` lies inside or within [`ConvexPolyhedron::tolerance`] of the polyhedron.
    pub fn contains_point(&self, p: DVec3) -> bool {
        self.max_plane_distance(p) <= self.tolerance
    }
}

/// Where the faces came from: hull faces may leave input points unused, user faces may not.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Origin {
    Hull,
    Faces,
}

fn diameter(points: &[DVec3]) -> f64 {
    let (lo, hi) = mesh::bounds(points);
    (hi - lo).length()
}

/// The validation pipeline of the module documentation. `faces` index `points` (input
/// numbering, kept in error messages).
fn build(
    points: &[DVec3],
    faces: Vec<Vec<u32>>,
    tolerance: f64,
    origin: Origin,
) -> Result<ConvexPolyhedron, GeomError> {
    if origin == Origin::Faces {
        let mut used = vec![false; points.len()];
        faces
            .iter()
            .flatten()
            .for_each(|&i| used[i as usize] = true);
        if let Some(vertex) = used.iter().position(|&u| !u) {
            return Err(GeomError::UnusedVertex { vertex });
        }
    }
    // 1. Closed, consistently and outwardly oriented, non-degenerate faces.
    let input = PolyMesh::new(points.to_vec(), &faces)?;
    input.check_closed()?;
    // 2. Merge coplanar faces, then drop vertices on straight edges.
    let faces = merge_coplanar(points, faces, tolerance)?;
    let faces = remove_collinear_vertices(points, faces)?;
    // 3. Compact the vertex numbering; validate shape; build the topology.
    let mut new_index = vec![u32::MAX; points.len()];
    let mut kept = Vec::new();
    for &i in faces.iter().flatten() {
        if new_index[i as usize] == u32::MAX {
            new_index[i as usize] = 0; // mark used; numbered below in input order
        }
    }
    for (i, slot) in new_index.iter_mut().enumerate() {
        if *slot != u32::MAX {
            *slot = kept.len() as u32;
            kept.push(i as u32);
        }
    }
    let compact: Vec<Vec<u32>> = faces
        .iter()
        .map(|f| f.iter().map(|&i| new_index[i as usize]).collect())
        .collect();
    let vertices: Vec<DVec3> = kept.iter().map(|&i| points[i as usize]).collect();
    let mesh = PolyMesh::new(vertices, &compact)?;
    let planes: Vec<Plane> = (0..mesh.face_count())
        .map(|f| face_plane(&mesh, f))
        .collect::<Result<_, _>>()?;
    let ctx = Checker {
        mesh: &mesh,
        planes: &planes,
        tolerance,
        input_ids: &kept,
    };
    for f in 0..mesh.face_count() {
        ctx.check_face(f)?;
    }
    let topo = Topology::new(&mesh)?;
    for e in &topo.edges {
        ctx.check_edge(e)?;
    }
    ctx.check_vertex_angles()?;
    let (v, e, f) = (mesh.vertices().len(), topo.edges.len(), mesh.face_count());
    if v as i64 - e as i64 + f as i64 != 2 {
        return Err(GeomError::EulerCharacteristic { v, e, f });
    }
    Ok(ConvexPolyhedron {
        mesh,
        planes,
        edges: topo.edges,
        face_edges: topo.face_edges,
        vertex_edge_starts: topo.vertex_edge_starts,
        vertex_edges: topo.vertex_edges,
        tolerance,
    })
}

/// The plane of a face: Newell's normal, placed midway between the face's extreme vertices so
/// that the largest vertex deviation is as small as possible along that normal.
fn plane_of(points: impl Iterator<Item = DVec3> + Clone) -> Option<(Plane, f64)> {
    let n = mesh::newell(points.clone()).try_normalize()?;
    let (lo, hi) = points
        .map(|p| n.dot(p))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), d| {
            (lo.min(d), hi.max(d))
        });
    Some((
        Plane {
            normal: n,
            offset: 0.5 * (lo + hi),
        },
        0.5 * (hi - lo),
    ))
}

fn face_plane(mesh: &PolyMesh, f: usize) -> Result<Plane, GeomError> {
    let pts = mesh.face(f).iter().map(|&i| mesh.vertices()[i as usize]);
    plane_of(pts)
        .map(|(p, _)| p)
        .ok_or(GeomError::DegenerateFace {
            face: f,
            area: 0.0,
            limit: 0.0,
        })
}

/// Union-find over face indices.
struct Groups(Vec<usize>);

impl Groups {
    fn find(&mut self, mut i: usize) -> usize {
        while self.0[i] != i {
            self.0[i] = self.0[self.0[i]];
            i = self.0[i];
        }
        i
    }
    fn union(&mut self, a: usize, b: usize) -> bool {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra == rb {
            return false;
        }
        let (lo, hi) = (ra.min(rb), ra.max(rb));
        self.0[hi] = lo;
        true
    }
}

/// Map from a directed edge `(tail, head)` to the face containing it.
fn directed_edges(faces: &[Vec<u32>]) -> HashMap<(u32, u32), usize> {
    let mut map = HashMap::with_capacity(faces.iter().map(Vec::len).sum());
    for (f, face) in faces.iter().enumerate() {
        for k in 0..face.len() {
            map.insert((face[k], face[(k + 1) % face.len()]), f);
        }
    }
    map
}

/// Merges adjacent coplanar faces until none remain; refuses concave edges.
///
/// Faces f and g are coplanar when all vertices of both lie within the tolerance of f's plane
/// or of g's plane. This is the test that also absorbs the near-flat, slightly concave edges a
/// floating-point hull can produce (a new triangle whose apex lies just above a neighbour's
/// plane): their union lies within the tolerance of the neighbour's plane.
fn merge_coplanar(
    points: &[DVec3],
    mut faces: Vec<Vec<u32>>,
    tolerance: f64,
) -> Result<Vec<Vec<u32>>, GeomError> {
    let pos = |i: u32| points[i as usize];
    // Each pass merges at least two faces, so the loop ends after at most F passes.
    loop {
        let planes: Vec<Plane> = faces
            .iter()
            .enumerate()
            .map(|(f, face)| {
                plane_of(face.iter().map(|&i| pos(i)))
                    .map(|(p, _)| p)
                    .ok_or(GeomError::DegenerateFace {
                        face: f,
                        area: 0.0,
                        limit: 0.0,
                    })
            })
            .collect::<Result<_, _>>()?;
        let edge_face = directed_edges(&faces);
        // Extreme signed distances of face `g`'s vertices from face `f`'s plane.
        let range = |f: usize, g: usize| {
            faces[g]
                .iter()
                .map(|&i| planes[f].signed_distance(pos(i)))
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), d| {
                    (lo.min(d), hi.max(d))
                })
        };
        let mut groups = Groups((0..faces.len()).collect());
        let mut merged = false;
        for (f, face) in faces.iter().enumerate() {
            for k in 0..face.len() {
                let (a, b) = (face[k], face[(k + 1) % face.len()]);
                let Some(&g) = edge_face.get(&(b, a)) else {
                    return Err(GeomError::OpenEdge {
                        from: a,
                        to: b,
                        face: f,
                    });
                };
                if g < f {
                    continue; // each undirected edge once
                }
                let (g_lo, g_hi) = range(f, g);
                let (f_lo, f_hi) = range(g, f);
                let within = |lo: f64, hi: f64| lo >= -tolerance && hi <= tolerance;
                if within(g_lo, g_hi) || within(f_lo, f_hi) {
                    merged |= groups.union(f, g);
                } else if g_hi > tolerance || f_hi > tolerance {
                    let (face_a, face_b, excess) = if g_hi >= f_hi {
                        (f, g, g_hi)
                    } else {
                        (g, f, f_hi)
                    };
                    return Err(GeomError::NotConvex {
                        a,
                        b,
                        face_a,
                        face_b,
                        excess,
                        tolerance,
                    });
                }
            }
        }
        if !merged {
            return Ok(faces);
        }
        faces = merge_groups(&faces, &mut groups)?;
    }
}

/// Replaces every group of faces by the single loop that bounds it.
fn merge_groups(faces: &[Vec<u32>], groups: &mut Groups) -> Result<Vec<Vec<u32>>, GeomError> {
    let edge_face = directed_edges(faces);
    // Boundary half-edges of each group: those whose opposite lies in another group.
    let mut boundary: HashMap<usize, HashMap<u32, u32>> = HashMap::new();
    let mut order: Vec<usize> = Vec::new(); // group roots in order of their first face
    for (f, face) in faces.iter().enumerate() {
        let root = groups.find(f);
        if let std::collections::hash_map::Entry::Vacant(slot) = boundary.entry(root) {
            slot.insert(HashMap::new());
            order.push(root);
        }
        for k in 0..face.len() {
            let (a, b) = (face[k], face[(k + 1) % face.len()]);
            let g = edge_face[&(b, a)];
            if groups.find(g) != root {
                let next = boundary.get_mut(&root).expect("inserted above");
                if next.insert(a, b).is_some() {
                    return Err(GeomError::CoplanarMergeFailed { vertex: a });
                }
            }
        }
    }
    let mut out = Vec::with_capacity(order.len());
    for root in order {
        let next = &boundary[&root];
        // Start at the smallest vertex so the result does not depend on hash order.
        let Some(&start) = next.keys().min() else {
            return Err(GeomError::ZeroVolume { volume: 0.0 });
        };
        let mut loop_ = vec![start];
        let mut v = next[&start];
        while v != start {
            if loop_.len() > next.len() {
                break;
            }
            loop_.push(v);
            v = match next.get(&v) {
                Some(&w) => w,
                None => break,
            };
        }
        if loop_.len() != next.len() || v != start {
            return Err(GeomError::CoplanarMergeFailed { vertex: start });
        }
        out.push(loop_);
    }
    Ok(out)
}

/// Removes vertices that lie between exactly two faces: they sit on a straight edge and are
/// not features of the solid.
fn remove_collinear_vertices(
    points: &[DVec3],
    mut faces: Vec<Vec<u32>>,
) -> Result<Vec<Vec<u32>>, GeomError> {
    let mut degree = vec![0u32; points.len()];
    faces
        .iter()
        .flatten()
        .for_each(|&i| degree[i as usize] += 1);
    for (f, face) in faces.iter_mut().enumerate() {
        face.retain(|&i| degree[i as usize] != 2);
        if face.len() < 3 {
            return Err(GeomError::DegenerateFace {
                face: f,
                area: 0.0,
                limit: 0.0,
            });
        }
    }
    Ok(faces)
}

/// Shape checks on the final faces; `input_ids` maps compact vertex numbers back to the input.
struct Checker<'a> {
    mesh: &'a PolyMesh,
    planes: &'a [Plane],
    tolerance: f64,
    input_ids: &'a [u32],
}

impl Checker<'_> {
    fn pos(&self, v: u32) -> DVec3 {
        self.mesh.vertices()[v as usize]
    }

    /// Planar within the tolerance, and a convex polygon: every corner turns left (or lies
    /// within the tolerance of the chord of its neighbours) and the loop turns once.
    fn check_face(&self, f: usize) -> Result<(), GeomError> {
        let face = self.mesh.face(f);
        let plane = self.planes[f];
        let deviation = face
            .iter()
            .map(|&v| plane.signed_distance(self.pos(v)).abs())
            .fold(0.0, f64::max);
        if deviation > self.tolerance {
            return Err(GeomError::NonPlanarFace {
                face: f,
                deviation,
                tolerance: self.tolerance,
            });
        }
        let n = face.len();
        let mut turning = 0.0;
        for k in 0..n {
            let (a, b, c) = (
                self.pos(face[(k + n - 1) % n]),
                self.pos(face[k]),
                self.pos(face[(k + 1) % n]),
            );
            let (u, w) = (b - a, c - b);
            let sin = u.cross(w).dot(plane.normal);
            let chord = (c - a).length();
            // Signed distance of the corner from its neighbours' chord, outward positive.
            let bulge = if chord > 0.0 { sin / chord } else { -1.0 };
            if bulge < -self.tolerance {
                return Err(GeomError::NonConvexFace {
                    face: f,
                    vertex: self.input_ids[face[k] as usize],
                });
            }
            turning += sin.atan2(u.dot(w));
        }
        // A simple convex loop turns by exactly 2π; a folded one by a multiple of it.
        if (turning - TAU).abs() > std::f64::consts::PI {
            return Err(GeomError::NonConvexFace {
                face: f,
                vertex: self.input_ids[face[0] as usize],
            });
        }
        Ok(())
    }

    /// The two faces of an edge must not bend inwards by more than the tolerance.
    fn check_edge(&self, e: &Edge) -> Result<(), GeomError> {
        for (f, g) in [(e.left, e.right), (e.right, e.left)] {
            let plane = self.planes[f as usize];
            let excess = self
                .mesh
                .face(g as usize)
                .iter()
                .map(|&v| plane.signed_distance(self.pos(v)))
                .fold(f64::NEG_INFINITY, f64::max);
            if excess > self.tolerance {
                return Err(GeomError::NotConvex {
                    a: self.input_ids[e.tail as usize],
                    b: self.input_ids[e.head as usize],
                    face_a: f as usize,
                    face_b: g as usize,
                    excess,
                    tolerance: self.tolerance,
                });
            }
        }
        Ok(())
    }

    /// The face angles at each vertex must sum to less than 2π: the faces around it form a
    /// convex cone, not a saddle or a cone wound twice.
    fn check_vertex_angles(&self) -> Result<(), GeomError> {
        let mut sums = vec![0.0; self.mesh.vertices().len()];
        for face in self.mesh.faces() {
            let n = face.len();
            for k in 0..n {
                let b = self.pos(face[k]);
                let u = self.pos(face[(k + n - 1) % n]) - b;
                let w = self.pos(face[(k + 1) % n]) - b;
                sums[face[k] as usize] += u.angle_between(w);
            }
        }
        for (v, &angle_sum) in sums.iter().enumerate() {
            if angle_sum >= TAU + tol::VERTEX_ANGLE_SLACK {
                return Err(GeomError::NonConvexVertex {
                    vertex: self.input_ids[v],
                    angle_sum,
                });
            }
        }
        Ok(())
    }
}

/// Edges and adjacency of a closed, consistently oriented mesh.
struct Topology {
    edges: Vec<Edge>,
    face_edges: Vec<u32>,
    vertex_edge_starts: Vec<u32>,
    vertex_edges: Vec<u32>,
}

impl Topology {
    fn new(mesh: &PolyMesh) -> Result<Self, GeomError> {
        let nv = mesh.vertices().len();
        let nh = mesh.half_edge_count();
        // Half-edge h = face_start(f) + k runs face[k] -> face[k + 1].
        let mut he_face = vec![0u32; nh];
        let mut he_tail = vec![0u32; nh];
        let mut he_head = vec![0u32; nh];
        let mut he_prev = vec![0u32; nh];
        for (f, face) in mesh.faces().enumerate() {
            let s = mesh.face_start(f);
            let n = face.len();
            for k in 0..n {
                he_face[s + k] = f as u32;
                he_tail[s + k] = face[k];
                he_head[s + k] = face[(k + 1) % n];
                he_prev[s + k] = (s + (k + n - 1) % n) as u32;
            }
        }
        let mut by_ends: HashMap<(u32, u32), u32> = HashMap::with_capacity(nh);
        for h in 0..nh {
            by_ends.insert((he_tail[h], he_head[h]), h as u32);
        }
        let mut edges = Vec::with_capacity(nh / 2);
        let mut face_edges = vec![u32::MAX; nh];
        let mut twin = vec![0u32; nh];
        let mut out_he = vec![u32::MAX; nv]; // one outgoing half-edge per vertex
        let mut degree = vec![0u32; nv];
        for h in 0..nh {
            let (a, b) = (he_tail[h], he_head[h]);
            let Some(&t) = by_ends.get(&(b, a)) else {
                return Err(GeomError::OpenEdge {
                    from: a,
                    to: b,
                    face: he_face[h] as usize,
                });
            };
            twin[h] = t;
            if out_he[a as usize] == u32::MAX {
                out_he[a as usize] = h as u32;
            }
            degree[a as usize] += 1;
            if face_edges[h] == u32::MAX {
                let e = edges.len() as u32;
                edges.push(Edge {
                    tail: a,
                    head: b,
                    left: he_face[h],
                    right: he_face[t as usize],
                });
                face_edges[h] = e;
                face_edges[t as usize] = e;
            }
        }
        // Around each vertex: next outgoing half-edge counter-clockwise = twin(prev(h)).
        let mut vertex_edge_starts = Vec::with_capacity(nv + 1);
        let mut vertex_edges = Vec::with_capacity(nh);
        vertex_edge_starts.push(0);
        for v in 0..nv {
            let start = out_he[v];
            if start == u32::MAX {
                return Err(GeomError::UnusedVertex { vertex: v });
            }
            let mut h = start;
            loop {
                vertex_edges.push(face_edges[h as usize]);
                h = twin[he_prev[h as usize] as usize];
                let fan = vertex_edges.len() - vertex_edge_starts[v] as usize;
                if h == start || fan > degree[v] as usize {
                    break;
                }
            }
            let fan = vertex_edges.len() - vertex_edge_starts[v] as usize;
            if fan != degree[v] as usize {
                return Err(GeomError::NonManifoldVertex { vertex: v as u32 });
            }
            vertex_edge_starts.push(vertex_edges.len() as u32);
        }
        Ok(Self {
            edges,
            face_edges,
            vertex_edge_starts,
            vertex_edges,
        })
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::primitives;
    use glam::DQuat;

    /// Independent checks of a polyhedron's topology and convexity, by brute force from the
    /// raw face loops: every directed edge has exactly one opposite, every vertex lies below
    /// every face plane (within the tolerance), every vertex's edges turn counter-clockwise
    /// about the outward direction, and V − E + F = 2.
    pub(crate) fn assert_valid(p: &ConvexPolyhedron) {
        let mut directed = std::collections::HashSet::new();
        for f in 0..p.face_count() as u32 {
            let fv = p.face_vertices(f);
            for k in 0..fv.len() {
                assert!(
                    directed.insert((fv[k], fv[(k + 1) % fv.len()])),
                    "edge used twice"
                );
            }
        }
        for &(a, b) in &directed {
            assert!(directed.contains(&(b, a)), "open edge {a}-{b}");
        }
        assert_eq!(directed.len(), 2 * p.edges().len());
        let (v, e, f) = (
            p.vertices().len() as i64,
            p.edges().len() as i64,
            p.face_count() as i64,
        );
        assert_eq!(v - e + f, 2);
        for (fi, pl) in p.planes().iter().enumerate() {
            assert!((pl.normal.length() - 1.0).abs() < 1e-12);
            for (vi, &x) in p.vertices().iter().enumerate() {
                let d = pl.signed_distance(x);
                assert!(d <= p.tolerance(), "vertex {vi} is {d:e} above face {fi}");
            }
        }
        for e in p.edges() {
            let (lf, rf) = (p.face_vertices(e.left), p.face_vertices(e.right));
            let runs = |fv: &[u32], a: u32, b: u32| {
                (0..fv.len()).any(|k| fv[k] == a && fv[(k + 1) % fv.len()] == b)
            };
            assert!(runs(lf, e.tail, e.head) && runs(rf, e.head, e.tail));
        }
        let centre = p.vertices().iter().sum::<DVec3>() / p.vertices().len() as f64;
        for vi in 0..p.vertices().len() as u32 {
            let ring = p.vertex_edges(vi);
            assert!(ring.len() >= 3, "vertex {vi} has degree {}", ring.len());
            let x = p.vertex(vi);
            let out = x - centre;
            let mut turn = 0.0;
            for k in 0..ring.len() {
                let a = p.vertex(p.edge(ring[k]).other_vertex(vi)) - x;
                let b = p.vertex(p.edge(ring[(k + 1) % ring.len()]).other_vertex(vi)) - x;
                let (a, b) = (a.reject_from(out), b.reject_from(out));
                turn += a.cross(b).dot(out.normalize()).atan2(a.dot(b));
            }
            assert!(
                (turn - TAU).abs() < 1e-6,
                "edges of vertex {vi} are not CCW (turn {turn})"
            );
        }
    }

    fn cube_triangles(h: f64) -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let m = primitives::cuboid_mesh(DVec3::splat(h)).unwrap();
        let mut tris = Vec::new();
        for face in m.faces() {
            tris.push([face[0], face[1], face[2]]);
            tris.push([face[0], face[2], face[3]]);
        }
        (m.vertices().to_vec(), tris)
    }

    #[test]
    fn cuboid_has_box_topology_and_planes() {
        let p = primitives::cuboid(DVec3::new(1.0, 2.0, 3.0)).unwrap();
        assert_valid(&p);
        assert_eq!(
            (p.vertices().len(), p.edges().len(), p.face_count()),
            (8, 12, 6)
        );
        for pl in p.planes() {
            let axis = pl.normal.abs().max_position();
            assert_eq!(pl.normal.abs()[axis], 1.0);
            assert_eq!(pl.offset, [1.0, 2.0, 3.0][axis]);
        }
    }

    #[test]
    fn triangulated_box_merges_to_six_quads() {
        let (v, t) = cube_triangles(0.5);
        let p = ConvexPolyhedron::from_faces(v, t).unwrap();
        assert_valid(&p);
        assert_eq!(
            (p.vertices().len(), p.edges().len(), p.face_count()),
            (8, 12, 6)
        );
        assert!((0..6).all(|f| p.face_vertices(f).len() == 4));
    }

    #[test]
    fn rotated_f32_rounded_box_still_merges() {
        // A box exported in single precision: its coplanar triangles are only coplanar to
        // about 1e-7 relative, which the tolerance must absorb.
        let (v, t) = cube_triangles(0.5);
        let q = DQuat::from_euler(glam::EulerRot::XYZ, 0.3, -1.1, 2.0);
        let v: Vec<DVec3> = v.iter().map(|&x| (q * x).as_vec3().as_dvec3()).collect();
        let p = ConvexPolyhedron::from_faces(v, t).unwrap();
        assert_valid(&p);
        assert_eq!(p.face_count(), 6);
    }

    #[test]
    fn vertices_on_straight_edges_are_removed() {
        // A unit box whose bottom and front faces share an extra vertex at the middle of their
        // common edge: it lies between two faces only and is not a corner.
        let mut v = primitives::cuboid_mesh(DVec3::splat(1.0))
            .unwrap()
            .vertices()
            .to_vec();
        v.push(DVec3::new(0.0, -1.0, -1.0)); // vertex 8, midpoint of edge 0-1
        let faces: Vec<Vec<u32>> = vec![
            vec![0, 2, 3, 1, 8],
            vec![4, 5, 7, 6],
            vec![0, 8, 1, 5, 4],
            vec![2, 6, 7, 3],
            vec![0, 4, 6, 2],
            vec![1, 3, 7, 5],
        ];
        let p = ConvexPolyhedron::from_faces(v, faces).unwrap();
        assert_valid(&p);
        assert_eq!(
            (p.vertices().len(), p.edges().len(), p.face_count()),
            (8, 12, 6)
        );
    }

    #[test]
    fn non_convex_and_malformed_inputs_are_refused() {
        // Push the centre of the top face of a pyramid-capped box inward: a dent.
        let mut v = primitives::cuboid_mesh(DVec3::splat(1.0))
            .unwrap()
            .vertices()
            .to_vec();
        v.push(DVec3::new(0.0, 0.0, 0.5)); // vertex 8 below the top face z = 1
        let faces: Vec<Vec<u32>> = vec![
            vec![0, 2, 3, 1],
            vec![4, 5, 8],
            vec![5, 7, 8],
            vec![7, 6, 8],
            vec![6, 4, 8],
            vec![0, 1, 5, 4],
            vec![2, 6, 7, 3],
            vec![0, 4, 6, 2],
            vec![1, 3, 7, 5],
        ];
        let err = ConvexPolyhedron::from_faces(v.clone(), &faces).unwrap_err();
        assert!(matches!(err, GeomError::NotConvex { .. }), "{err}");
        // The same shape with the apex raised (z = 1.5) is a convex "house".
        v[8].z = 1.5;
        let p = ConvexPolyhedron::from_faces(v.clone(), &faces).unwrap();
        assert_valid(&p);
        assert_eq!(
            (p.vertices().len(), p.edges().len(), p.face_count()),
            (9, 16, 9)
        );
        // An extra vertex nobody uses.
        let mut w = v.clone();
        w.push(DVec3::splat(9.0));
        let err = ConvexPolyhedron::from_faces(w, &faces).unwrap_err();
        assert!(
            matches!(err, GeomError::UnusedVertex { vertex: 9 }),
            "{err}"
        );
        // Inside out.
        let inward: Vec<Vec<u32>> = faces
            .iter()
            .map(|f| f.iter().rev().copied().collect())
            .collect();
        let err = ConvexPolyhedron::from_faces(v.clone(), inward).unwrap_err();
        assert!(matches!(err, GeomError::InwardOrientation { .. }), "{err}");
        // Open.
        let err = ConvexPolyhedron::from_faces(v, &faces[1..]).unwrap_err();
        assert!(
            matches!(
                err,
                GeomError::OpenEdge { .. } | GeomError::UnusedVertex { .. }
            ),
            "{err}"
        );
    }

    #[test]
    fn two_separate_boxes_are_not_one_polyhedron() {
        let a = primitives::cuboid_mesh(DVec3::splat(1.0)).unwrap();
        let mut v = a.vertices().to_vec();
        v.extend(a.vertices().iter().map(|&x| x + DVec3::splat(3.0)));
        let mut faces: Vec<Vec<u32>> = a.faces().map(<[u32]>::to_vec).collect();
        faces.extend(
            a.faces()
                .map(|f| f.iter().map(|&i| i + 8).collect::<Vec<_>>()),
        );
        let err = ConvexPolyhedron::from_faces(v, faces).unwrap_err();
        assert!(
            matches!(
                err,
                GeomError::EulerCharacteristic {
                    v: 16,
                    e: 24,
                    f: 12
                }
            ),
            "{err}"
        );
    }

    #[test]
    fn prisms_and_geodesic_spheres_have_exact_counts() {
        for n in [3u32, 4, 7, 64] {
            let p = primitives::regular_prism(n, 2.0, 0.5).unwrap();
            assert_valid(&p);
            let n = n as usize;
            assert_eq!(
                (p.vertices().len(), p.edges().len(), p.face_count()),
                (2 * n, 3 * n, n + 2)
            );
        }
        for level in 1..=4u32 {
            let p = primitives::geodesic_sphere(level, 1.5).unwrap();
            assert_valid(&p);
            let k = 4usize.pow(level - 1);
            assert_eq!(
                (p.vertices().len(), p.edges().len(), p.face_count()),
                (10 * k + 2, 30 * k, 20 * k)
            );
            assert!(
                p.vertices()
                    .iter()
                    .all(|v| (v.length() - 1.5).abs() < 1e-14)
            );
        }
        assert!(primitives::geodesic_sphere(0, 1.0).is_err());
        assert!(primitives::geodesic_sphere(1, -1.0).is_err());
        assert!(primitives::regular_prism(2, 1.0, 1.0).is_err());
        assert!(primitives::cuboid(DVec3::new(1.0, f64::NAN, 1.0)).is_err());
    }

    #[test]
    fn support_queries_agree_with_brute_force() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(7);
        let p = primitives::geodesic_sphere(4, 1.0).unwrap();
        let mut warm = 0;
        for _ in 0..2000 {
            let d = DVec3::new(rng.random(), rng.random(), rng.random()) - DVec3::splat(0.5);
            let best = p
                .vertices()
                .iter()
                .map(|v| v.dot(d))
                .fold(f64::NEG_INFINITY, f64::max);
            assert_eq!(p.vertex(p.support(d)).dot(d), best);
            warm = p.support_from(d, warm);
            assert_eq!(p.vertex(warm).dot(d), best);
        }
        let pose = Pose::new(DQuat::from_rotation_z(0.3), DVec3::new(5.0, 0.0, 0.0));
        let b = p.aabb(&pose);
        let expect = Aabb::from_points(p.vertices().iter().map(|&v| pose.transform_point(v)));
        assert_eq!(b, expect);
        assert!((p.bounding_radius(DVec3::ZERO) - 1.0).abs() < 1e-15);
        assert!((p.bounding_radius(DVec3::X) - 2.0).abs() < 1e-2);
    }
}
