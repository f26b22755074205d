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
    #[inline]
    pub fn other_vertex(&self, v: u32) -> u32 {
        if v == self.tail { self.head } else { self.tail }
    }

    /// The face that is not `f` (`f` must be one of the edge's faces).
    #[inline]
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
    /// Visibility during construction is decided by exact orientation predicates, so the
    /// topology is always consistent, however thin, elongated or nearly degenerate the input
    /// (see [`crate::hull`]). A point becomes a vertex only if it lies more than
    /// [`ConvexPolyhedron::tolerance`] outside the hull of the others: duplicates and points on
    /// faces or edges are absorbed, coplanar hull triangles are merged into polygon faces.
    ///
    /// Guarantee: every input point lies inside the result or at most 2 × tolerance outside a
    /// face plane, and every vertex is an input point. (The worst seen over 2,378 adversarial
    /// sets — noisy grids, cylinders, 1000:1 needles, 1e-5 plates — was 1.46 × tolerance.)
    ///
    /// # Errors
    /// [`GeomError::NonFinite`], [`GeomError::TooFewPoints`] (fewer than 4),
    /// [`GeomError::DegeneratePoints`] (all points coincident, collinear or coplanar within the
    /// tolerance). A point set whose hull has features only a few tolerances across (a plate a
    /// couple of tolerances thick) may also be refused with a face error
    /// ([`GeomError::DegenerateFace`] and the like): such a hull is never returned wrong.
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
    #[inline]
    pub fn vertices(&self) -> &[DVec3] {
        self.mesh.vertices()
    }

    /// Position of vertex `v`.
    #[inline]
    pub fn vertex(&self, v: u32) -> DVec3 {
        self.mesh.vertices()[v as usize]
    }

    /// Number of faces.
    #[inline]
    pub fn face_count(&self) -> usize {
        self.planes.len()
    }

    /// Vertices of face `f`, counter-clockwise seen from outside.
    #[inline]
    pub fn face_vertices(&self, f: u32) -> &[u32] {
        self.mesh.face(f as usize)
    }

    /// Edges of face `f`, in loop order: edge `k` joins `face_vertices(f)[k]` to
    /// `face_vertices(f)[k + 1]` (cyclically).
    #[inline]
    pub fn face_edges(&self, f: u32) -> &[u32] {
        let start = self.mesh.face_start(f as usize);
        &self.face_edges[start..start + self.mesh.face(f as usize).len()]
    }

    /// Outward plane of face `f`.
    #[inline]
    pub fn face_plane(&self, f: u32) -> Plane {
        self.planes[f as usize]
    }

    /// All face planes, indexed by face.
    #[inline]
    pub fn planes(&self) -> &[Plane] {
        &self.planes
    }

    /// All edges.
    #[inline]
    pub fn edges(&self) -> &[Edge] {
        &self.edges
    }

    /// Edge `e`.
    #[inline]
    pub fn edge(&self, e: u32) -> Edge {
        self.edges[e as usize]
    }

    /// Edges incident to vertex `v`, counter-clockwise seen from outside. Between consecutive
    /// edges `e_i`, `e_{i+1}` lies the face that is the left face of `e_{i+1}` when it is
    /// oriented away from `v`.
    #[inline]
    pub fn vertex_edges(&self, v: u32) -> &[u32] {
        let r = self.vertex_edge_starts[v as usize] as usize
            ..self.vertex_edge_starts[v as usize + 1] as usize;
        &self.vertex_edges[r]
    }

    /// The length scale this polyhedron was validated with: points within it of a face plane
    /// count as on the face. It is [`tol::POLYHEDRON_REL`] times the bounding-box diagonal of
    /// the input.
    #[inline]
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
    // 1. Closed and consistently oriented. User faces must also be outward and proper polygons;
    //    hull triangles are outward by construction, and their slivers (exact hulls of nearly
    //    coplanar points have some) are left for merging to absorb.
    let input = PolyMesh::new(points.to_vec(), &faces)?;
    match origin {
        Origin::Faces => input.check_closed().map(|_| ())?,
        Origin::Hull => input.check_edges().map(|_| ())?,
    }
    // 2. Merge coplanar faces, then drop vertices on straight edges.
    let faces = merge_coplanar(points, faces, tolerance)?;
    let (faces, removed) = remove_two_face_vertices(points, faces)?;
    // 3. Compact the vertex numbering (kept vertices in input order); planes; shape checks;
    //    topology.
    let mut used = vec![false; points.len()];
    faces
        .iter()
        .flat_map(|f| f.loop_.iter())
        .for_each(|&i| used[i as usize] = true);
    let kept: Vec<u32> = (0..points.len() as u32)
        .filter(|&i| used[i as usize])
        .collect();
    let mut new_index = vec![u32::MAX; points.len()];
    for (k, &i) in kept.iter().enumerate() {
        new_index[i as usize] = k as u32;
    }
    let compact: Vec<Vec<u32>> = faces
        .iter()
        .map(|f| f.loop_.iter().map(|&i| new_index[i as usize]).collect())
        .collect();
    let vertices: Vec<DVec3> = kept.iter().map(|&i| points[i as usize]).collect();
    let mesh = PolyMesh::new(vertices, &compact)?;
    let planes: Vec<Plane> = faces
        .iter()
        .enumerate()
        .map(|(f, face)| match face.normal {
            // A merged polygon keeps the reference normal its vertices were checked against.
            Some(n) => Ok(plane_along(
                n,
                mesh.face(f).iter().map(|&i| mesh.vertices()[i as usize]),
            )),
            None => face_plane(&mesh, f),
        })
        .collect::<Result<_, _>>()?;
    // A removed vertex must still lie on its two faces, within the tolerance.
    for &(v, [f, g]) in &removed {
        let x = points[v as usize];
        for face in [f, g] {
            let d = planes[face].signed_distance(x).abs();
            if d > tolerance {
                return Err(GeomError::NonPlanarFace {
                    face,
                    deviation: d,
                    tolerance,
                });
            }
        }
    }
    let ctx = Checker {
        mesh: &mesh,
        planes: &planes,
        tolerance,
        input_ids: &kept,
    };
    for f in 0..mesh.face_count() {
        ctx.check_face(f)?;
    }
    let topo = Topology::new(&mesh).map_err(|e| match e {
        GeomError::NonManifoldVertex { vertex } => GeomError::NonManifoldVertex {
            vertex: kept[vertex as usize],
        },
        other => other,
    })?;
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
fn plane_of(points: impl Iterator<Item = DVec3> + Clone) -> Option<Plane> {
    let n = mesh::newell(points.clone()).try_normalize()?;
    Some(plane_along(n, points))
}

/// The plane with unit normal `n` midway between the extreme vertices along `n`.
fn plane_along(n: DVec3, points: impl Iterator<Item = DVec3>) -> Plane {
    let (lo, hi) = points
        .map(|p| n.dot(p))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), d| {
            (lo.min(d), hi.max(d))
        });
    Plane {
        normal: n,
        offset: 0.5 * (lo + hi),
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

fn face_plane(mesh: &PolyMesh, f: usize) -> Result<Plane, GeomError> {
    let pts = mesh.face(f).iter().map(|&i| mesh.vertices()[i as usize]);
    plane_of(pts).ok_or(GeomError::CollapsedFace { face: f })
}

/// A face after merging: its loop, and for a merged polygon the normal of the plane all its
/// vertices were checked against.
struct MergedFace {
    loop_: Vec<u32>,
    normal: Option<DVec3>,
}

/// Union-find over face indices, with what a group needs to judge a merge.
struct Groups {
    parent: Vec<usize>,
    /// Per root: the member face whose plane is the group's reference plane (the largest).
    reference: Vec<usize>,
    /// Per root: total area of the members.
    area: Vec<f64>,
    /// Per root: the member faces.
    members: Vec<Vec<usize>>,
}

impl Groups {
    fn new(areas: &[f64]) -> Self {
        let n = areas.len();
        Self {
            parent: (0..n).collect(),
            reference: (0..n).collect(),
            area: areas.to_vec(),
            members: (0..n).map(|f| vec![f]).collect(),
        }
    }

    fn find(&mut self, mut i: usize) -> usize {
        while self.parent[i] != i {
            self.parent[i] = self.parent[self.parent[i]];
            i = self.parent[i];
        }
        i
    }
}

/// Merges adjacent coplanar faces; refuses concave edges.
///
/// An edge is a merge candidate when all vertices of its two faces lie within the tolerance of
/// one of the two face planes. Candidates are taken flattest first, and two groups are joined
/// only if every vertex of the smaller lies within the tolerance of the larger group's
/// reference plane (the plane of its largest face), so a merged polygon is planar within the
/// tolerance however many faces it absorbs — curvature cannot creep in along a chain of nearly
/// flat edges. A group whose outline is not one simple loop (a flat ring around a small raised
/// feature) is left as its separate faces: their edges are flat but not concave.
fn merge_coplanar(
    points: &[DVec3],
    faces: Vec<Vec<u32>>,
    tolerance: f64,
) -> Result<Vec<MergedFace>, GeomError> {
    let pos = |i: u32| points[i as usize];
    // A face too thin to have a normal (a hull sliver) has no plane; it can still merge into a
    // neighbour's plane.
    let planes: Vec<Option<Plane>> = faces
        .iter()
        .map(|face| plane_of(face.iter().map(|&i| pos(i))))
        .collect();
    let areas: Vec<f64> = faces
        .iter()
        .map(|face| 0.5 * mesh::newell(face.iter().map(|&i| pos(i))).length())
        .collect();
    let edge_face = directed_edges(&faces);
    // Extreme signed distances of face `g`'s vertices from face `f`'s plane.
    // Extreme signed distances of face `g`'s vertices from face `f`'s plane (an empty range,
    // judged neither flat nor concave, when `f` has no plane).
    let range = |f: usize, g: usize| match planes[f] {
        Some(plane) => faces[g]
            .iter()
            .map(|&i| plane.signed_distance(pos(i)))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), d| {
                (lo.min(d), hi.max(d))
            }),
        None => (f64::INFINITY, f64::NEG_INFINITY),
    };
    let mut candidates: Vec<(f64, usize, usize)> = Vec::new();
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
            let spread = |lo: f64, hi: f64| {
                if lo > hi {
                    f64::INFINITY
                } else {
                    lo.abs().max(hi.abs())
                }
            };
            let flatness = spread(g_lo, g_hi).min(spread(f_lo, f_hi));
            if flatness <= tolerance {
                candidates.push((flatness, f, g));
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
    candidates.sort_by(|x, y| x.0.total_cmp(&y.0).then((x.1, x.2).cmp(&(y.1, y.2))));
    let mut groups = Groups::new(&areas);
    for (_, f, g) in candidates {
        let (rf, rg) = (groups.find(f), groups.find(g));
        if rf == rg {
            continue;
        }
        let (big, small) = if groups.area[rf] >= groups.area[rg] {
            (rf, rg)
        } else {
            (rg, rf)
        };
        let Some(reference) = planes[groups.reference[big]] else {
            continue; // two slivers: neither has a plane to judge the other by
        };
        let flat = groups.members[small]
            .iter()
            .flat_map(|&m| faces[m].iter())
            .all(|&i| reference.signed_distance(pos(i)).abs() <= tolerance);
        if flat {
            groups.parent[small] = big;
            groups.area[big] += groups.area[small];
            let moved = std::mem::take(&mut groups.members[small]);
            groups.members[big].extend(moved);
        }
    }
    // One face per group, in order of each group's first face.
    let mut out = Vec::with_capacity(faces.len());
    for f in 0..faces.len() {
        let root = groups.find(f);
        let members = &groups.members[root];
        if members.iter().min() != Some(&f) {
            continue; // emitted with its group, at its smallest member
        }
        if members.len() == 1 {
            out.push(MergedFace {
                loop_: faces[f].clone(),
                normal: None,
            });
            continue;
        }
        let reference = planes[groups.reference[root]];
        let merged =
            outline(&faces, members, &edge_face)
                .zip(reference)
                .filter(|(loop_, plane)| {
                    convex_loop(loop_.iter().map(|&i| pos(i)), plane.normal, tolerance).is_ok()
                });
        match merged {
            Some((loop_, plane)) => out.push(MergedFace {
                loop_,
                normal: Some(plane.normal),
            }),
            None => {
                // Not one convex polygon: keep the faces separate (their shared edges are flat
                // within the tolerance, not concave).
                let mut sorted = members.clone();
                sorted.sort_unstable();
                out.extend(sorted.into_iter().map(|m| MergedFace {
                    loop_: faces[m].clone(),
                    normal: None,
                }));
            }
        }
    }
    Ok(out)
}

/// Checks that a loop is a convex polygon seen along `normal`: every corner turns left or lies
/// within `tolerance` of the chord of its neighbours, and the loop turns once in all. On failure
/// returns the position of the offending corner (0 when the loop as a whole is folded).
fn convex_loop(
    points: impl Iterator<Item = DVec3>,
    normal: DVec3,
    tolerance: f64,
) -> Result<(), usize> {
    let pts: Vec<DVec3> = points.collect();
    let n = pts.len();
    let mut turning = 0.0;
    for k in 0..n {
        let (a, b, c) = (pts[(k + n - 1) % n], pts[k], pts[(k + 1) % n]);
        let (u, w) = (b - a, c - b);
        let sin = u.cross(w).dot(normal);
        let chord = (c - a).length();
        // Signed distance of the corner from its neighbours' chord, outward positive.
        if !(chord > 0.0 && sin / chord >= -tolerance) {
            return Err(k);
        }
        turning += sin.atan2(u.dot(w));
    }
    // A simple convex loop turns by exactly 2π; a folded one by another multiple of it.
    if (turning - TAU).abs() <= std::f64::consts::PI {
        Ok(())
    } else {
        Err(0)
    }
}

/// The outline of a group of faces: its boundary half-edges chained into one loop, or `None`
/// when they do not form exactly one simple loop.
fn outline(
    faces: &[Vec<u32>],
    members: &[usize],
    edge_face: &HashMap<(u32, u32), usize>,
) -> Option<Vec<u32>> {
    let inside: std::collections::HashSet<usize> = members.iter().copied().collect();
    let mut next: HashMap<u32, u32> = HashMap::new();
    for &f in members {
        let face = &faces[f];
        for k in 0..face.len() {
            let (a, b) = (face[k], face[(k + 1) % face.len()]);
            if !inside.contains(edge_face.get(&(b, a))?) && next.insert(a, b).is_some() {
                return None; // a vertex where the outline touches itself
            }
        }
    }
    // Start at the smallest vertex so the result does not depend on hash order.
    let start = *next.keys().min()?;
    let mut loop_ = vec![start];
    let mut v = *next.get(&start)?;
    while v != start && loop_.len() <= next.len() {
        loop_.push(v);
        v = *next.get(&v)?;
    }
    (v == start && loop_.len() == next.len()).then_some(loop_)
}

/// A vertex dropped by [`remove_two_face_vertices`] and the two faces it lay on.
type RemovedVertex = (u32, [usize; 2]);

/// Removes vertices that lie between exactly two faces: on a straight edge, or at a bend
/// between two faces that are coplanar within the tolerance but were not merged (the reference
/// plane of one did not hold all of the other). Either way the vertex is not a feature of the
/// solid. Returns the faces and, for each removed vertex, the two faces it belonged to, so
/// that the caller can check it still lies within the tolerance of their planes.
fn remove_two_face_vertices(
    points: &[DVec3],
    mut faces: Vec<MergedFace>,
) -> Result<(Vec<MergedFace>, Vec<RemovedVertex>), GeomError> {
    let mut owners: Vec<Vec<usize>> = vec![Vec::new(); points.len()];
    for (f, face) in faces.iter().enumerate() {
        face.loop_.iter().for_each(|&i| owners[i as usize].push(f));
    }
    let removed: Vec<RemovedVertex> = owners
        .iter()
        .enumerate()
        .filter(|(_, o)| o.len() == 2)
        .map(|(v, o)| (v as u32, [o[0], o[1]]))
        .collect();
    for (f, face) in faces.iter_mut().enumerate() {
        face.loop_.retain(|&i| owners[i as usize].len() != 2);
        if face.loop_.len() < 3 {
            return Err(GeomError::CollapsedFace { face: f });
        }
    }
    Ok((faces, removed))
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
        if let Err(k) = convex_loop(
            face.iter().map(|&v| self.pos(v)),
            plane.normal,
            self.tolerance,
        ) {
            return Err(GeomError::NonConvexFace {
                face: f,
                vertex: self.input_ids[face[k] as usize],
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
        // Counter-clockwise rings: between consecutive ring edges v→a and v→b lies a face whose
        // loop runs b → v → a (a face is counter-clockwise from outside, so turning from v→a
        // to v→b counter-clockwise sweeps across it). Checked against the raw loops; with the
        // outward planes checked above, this fixes the orientation of every ring.
        let mut corners = std::collections::HashSet::new();
        for f in 0..p.face_count() as u32 {
            let fv = p.face_vertices(f);
            let n = fv.len();
            for k in 0..n {
                corners.insert((fv[(k + n - 1) % n], fv[k], fv[(k + 1) % n]));
            }
        }
        for vi in 0..p.vertices().len() as u32 {
            let ring = p.vertex_edges(vi);
            assert!(ring.len() >= 3, "vertex {vi} has degree {}", ring.len());
            for k in 0..ring.len() {
                let a = p.edge(ring[k]).other_vertex(vi);
                let b = p.edge(ring[(k + 1) % ring.len()]).other_vertex(vi);
                assert!(
                    corners.contains(&(b, vi, a)),
                    "ring of vertex {vi} is not counter-clockwise"
                );
            }
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
    fn errors_name_vertices_in_input_numbering() {
        // Two corner tetrahedra touching only at the origin (input vertex 1), plus vertex 0 at
        // the middle of an edge: it is dropped, which shifts every later vertex's index inside
        // the polyhedron, yet the error must name the origin as the user numbered it.
        let v = vec![
            DVec3::new(0.5, 0.5, 0.0), // 0: middle of edge 2-3
            DVec3::ZERO,               // 1: the shared corner
            DVec3::X,
            DVec3::Y,
            DVec3::Z,
            -DVec3::X,
            -DVec3::Y,
            -DVec3::Z,
        ];
        let faces: Vec<Vec<u32>> = vec![
            vec![1, 3, 0, 2],
            vec![1, 2, 4],
            vec![1, 4, 3],
            vec![2, 0, 3, 4],
            vec![1, 5, 6],
            vec![1, 7, 5],
            vec![1, 6, 7],
            vec![5, 7, 6],
        ];
        let err = ConvexPolyhedron::from_faces(v, faces).unwrap_err();
        assert!(
            matches!(err, GeomError::NonManifoldVertex { vertex: 1 }),
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
        assert!(primitives::corner_tetrahedron_mesh(DVec3::new(1.0, 0.0, 1.0)).is_err());
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
