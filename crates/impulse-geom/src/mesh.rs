//! Polygon meshes: vertices plus faces given as counter-clockwise vertex loops.
//!
//! [`PolyMesh`] is the boundary representation that mass-property integration walks (thesis
//! chapter 6 needs nothing more: enumerate faces, and the edges of each face counter-clockwise
//! seen from outside). It may be non-convex and its faces may have any number of sides.
//! [`PolyMesh::check_closed`] verifies what such algorithms assume.

use glam::DVec3;

use crate::error::GeomError;
use crate::tol;

/// A polygon mesh: a vertex list and faces as loops of vertex indices.
///
/// Faces are stored compactly (one index array plus per-face start offsets). A face loop is
/// counter-clockwise seen from outside, so the right-hand rule gives the outward normal. The
/// constructor guarantees: every index is in range, every face has at least three distinct
/// vertices, every coordinate is finite. Closedness and orientation are checked separately by
/// [`PolyMesh::check_closed`], because open meshes are legitimate for other uses.
#[derive(Clone, Debug, PartialEq)]
pub struct PolyMesh {
    /// Vertex positions, in the mesh's own frame.
    vertices: Vec<DVec3>,
    /// `face_starts[f]..face_starts[f + 1]` is the range of face `f` in `face_indices`
    /// (length: faces + 1).
    face_starts: Vec<u32>,
    /// All face loops, concatenated.
    face_indices: Vec<u32>,
}

/// A summary of a closed, consistently oriented mesh, returned by [`PolyMesh::check_closed`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClosedMeshInfo {
    /// Number of vertices used by faces.
    pub vertices_used: usize,
    /// Number of (undirected) edges.
    pub edges: usize,
    /// Number of faces.
    pub faces: usize,
}

impl ClosedMeshInfo {
    /// The Euler characteristic V − E + F (2 for one closed shell of genus 0).
    pub fn euler_characteristic(&self) -> i64 {
        self.vertices_used as i64 - self.edges as i64 + self.faces as i64
    }
}

impl PolyMesh {
    /// Builds a mesh from vertices and faces (each a vertex loop, counter-clockwise seen from
    /// outside).
    ///
    /// # Errors
    /// [`GeomError::NonFinite`] for a NaN or infinite coordinate,
    /// [`GeomError::VertexIndexOutOfRange`], [`GeomError::FaceTooSmall`] (fewer than three
    /// vertices) and [`GeomError::RepeatedVertex`].
    pub fn new<F, I>(vertices: Vec<DVec3>, faces: F) -> Result<Self, GeomError>
    where
        F: IntoIterator<Item = I>,
        I: AsRef<[u32]>,
    {
        check_finite(&vertices, "vertex")?;
        let mut face_starts = vec![0u32];
        let mut face_indices = Vec::new();
        for (f, face) in faces.into_iter().enumerate() {
            let face = face.as_ref();
            if face.len() < 3 {
                return Err(GeomError::FaceTooSmall {
                    face: f,
                    len: face.len(),
                });
            }
            for (k, &i) in face.iter().enumerate() {
                if i as usize >= vertices.len() {
                    return Err(GeomError::VertexIndexOutOfRange {
                        face: f,
                        index: i,
                        vertex_count: vertices.len(),
                    });
                }
                if face[..k].contains(&i) {
                    return Err(GeomError::RepeatedVertex { face: f, vertex: i });
                }
            }
            face_indices.extend_from_slice(face);
            face_starts.push(face_indices.len() as u32);
        }
        Ok(Self {
            vertices,
            face_starts,
            face_indices,
        })
    }

    /// Vertex positions.
    pub fn vertices(&self) -> &[DVec3] {
        &self.vertices
    }

    /// Number of faces.
    pub fn face_count(&self) -> usize {
        self.face_starts.len() - 1
    }

    /// The vertex loop of face `f` (counter-clockwise seen from outside).
    ///
    /// # Panics
    /// If `f >= self.face_count()`.
    pub fn face(&self, f: usize) -> &[u32] {
        &self.face_indices[self.face_starts[f] as usize..self.face_starts[f + 1] as usize]
    }

    /// All face loops, in order.
    pub fn faces(&self) -> impl ExactSizeIterator<Item = &[u32]> + '_ {
        self.face_starts
            .windows(2)
            .map(|w| &self.face_indices[w[0] as usize..w[1] as usize])
    }

    /// The offset of face `f`'s first index in the concatenated index array: the id of its first
    /// half-edge. Half-edge `face_start(f) + k` runs from `face(f)[k]` to `face(f)[k + 1]`.
    pub fn face_start(&self, f: usize) -> usize {
        self.face_starts[f] as usize
    }

    /// Total number of face corners, i.e. of directed half-edges.
    pub fn half_edge_count(&self) -> usize {
        self.face_indices.len()
    }

    /// The mesh with every vertex mapped through `f` (faces unchanged). Use it to move, scale or
    /// rotate a mesh; a map that mirrors the mesh (negative determinant) turns it inside out.
    ///
    /// # Errors
    /// [`GeomError::NonFinite`] if the map produces a non-finite coordinate.
    pub fn map_vertices(&self, f: impl Fn(DVec3) -> DVec3) -> Result<Self, GeomError> {
        let vertices: Vec<DVec3> = self.vertices.iter().map(|&v| f(v)).collect();
        check_finite(&vertices, "vertex")?;
        Ok(Self {
            vertices,
            ..self.clone()
        })
    }

    /// Newell's vector of face `f`: its unit normal times twice its area (exact for planar
    /// polygons, a least-squares normal for slightly warped ones).
    pub fn face_area_vector(&self, f: usize) -> DVec3 {
        newell(self.face(f).iter().map(|&i| self.vertices[i as usize]))
    }

    /// The centre of the vertices' bounding box, a cheap point inside or near the body.
    pub fn bounding_box_center(&self) -> DVec3 {
        let (lo, hi) = bounds(&self.vertices);
        0.5 * (lo + hi)
    }

    /// Diagonal of the vertices' bounding box (0 for an empty mesh): the mesh's size.
    pub fn diameter(&self) -> f64 {
        let (lo, hi) = bounds(&self.vertices);
        if self.vertices.is_empty() {
            0.0
        } else {
            (hi - lo).length()
        }
    }

    /// Checks that the mesh is a closed, consistently oriented 2-manifold with non-degenerate
    /// planar faces: every edge `a→b` of a face is matched by exactly one edge `b→a` of another
    /// face, every face has an area and lies in a plane within
    /// [`tol::FACE_PLANARITY_REL`], and the mesh encloses positive volume (faces
    /// counter-clockwise seen from outside).
    ///
    /// # Errors
    /// The first problem found, naming the face or edge: [`GeomError::OpenEdge`],
    /// [`GeomError::InconsistentOrientation`], [`GeomError::NonManifoldEdge`],
    /// [`GeomError::DegenerateFace`], [`GeomError::NonPlanarFace`],
    /// [`GeomError::InwardOrientation`], [`GeomError::ZeroVolume`].
    pub fn check_closed(&self) -> Result<ClosedMeshInfo, GeomError> {
        if self.face_count() == 0 {
            return Err(GeomError::ZeroVolume { volume: 0.0 });
        }
        for f in 0..self.face_count() {
            self.check_face_shape(f)?;
        }
        let edges = self.check_edges()?;
        let mut used = vec![false; self.vertices.len()];
        for &i in &self.face_indices {
            used[i as usize] = true;
        }
        let volume = self.signed_volume();
        let scale = self.diameter();
        // The volume of a sliver whose thickness is at the degenerate-face limit.
        let zero_volume = tol::DEGENERATE_FACE_REL * scale * scale * scale;
        if volume < -zero_volume {
            return Err(GeomError::InwardOrientation { volume });
        }
        if volume <= zero_volume {
            return Err(GeomError::ZeroVolume { volume });
        }
        Ok(ClosedMeshInfo {
            vertices_used: used.iter().filter(|&&u| u).count(),
            edges,
            faces: self.face_count(),
        })
    }

    /// Signed enclosed volume (positive for outward-facing faces), by the divergence theorem
    /// about the bounding-box centre. Meaningful for closed meshes only.
    pub fn signed_volume(&self) -> f64 {
        let c = self.bounding_box_center();
        (0..self.face_count())
            .map(|f| {
                let p = self.vertices[self.face(f)[0] as usize] - c;
                self.face_area_vector(f).dot(p)
            })
            .sum::<f64>()
            / 6.0
    }

    fn check_face_shape(&self, f: usize) -> Result<(), GeomError> {
        let pts: Vec<DVec3> = self
            .face(f)
            .iter()
            .map(|&i| self.vertices[i as usize])
            .collect();
        let (lo, hi) = bounds(&pts);
        let extent = (hi - lo).length();
        let area_vec = newell(pts.iter().copied());
        let area = 0.5 * area_vec.length();
        let limit = tol::DEGENERATE_FACE_REL * extent * extent;
        // Written so that a NaN area also counts as degenerate.
        if area.partial_cmp(&limit) != Some(std::cmp::Ordering::Greater) {
            return Err(GeomError::DegenerateFace {
                face: f,
                area,
                limit,
            });
        }
        if pts.len() > 3 {
            let n = area_vec / (2.0 * area);
            let centroid = pts.iter().sum::<DVec3>() / pts.len() as f64;
            let deviation = pts
                .iter()
                .map(|&p| (p - centroid).dot(n).abs())
                .fold(0.0, f64::max);
            let tolerance = tol::FACE_PLANARITY_REL * extent;
            if deviation > tolerance {
                return Err(GeomError::NonPlanarFace {
                    face: f,
                    deviation,
                    tolerance,
                });
            }
        }
        Ok(())
    }

    /// Pairs every half-edge with its opposite; returns the number of undirected edges.
    pub(crate) fn check_edges(&self) -> Result<usize, GeomError> {
        // (min, max, forward?, face) for every half-edge, sorted so both uses of an edge meet.
        let mut half: Vec<(u32, u32, bool, u32)> = Vec::with_capacity(self.face_indices.len());
        for (f, face) in self.faces().enumerate() {
            for k in 0..face.len() {
                let (a, b) = (face[k], face[(k + 1) % face.len()]);
                half.push((a.min(b), a.max(b), a < b, f as u32));
            }
        }
        half.sort_unstable();
        let mut edges = 0;
        let mut i = 0;
        while i < half.len() {
            let (lo, hi, fwd, face) = half[i];
            let mut j = i + 1;
            while j < half.len() && half[j].0 == lo && half[j].1 == hi {
                j += 1;
            }
            let (from, to) = if fwd { (lo, hi) } else { (hi, lo) };
            match j - i {
                1 => {
                    return Err(GeomError::OpenEdge {
                        from,
                        to,
                        face: face as usize,
                    });
                }
                2 if half[i].2 == half[i + 1].2 => {
                    return Err(GeomError::InconsistentOrientation {
                        from,
                        to,
                        face_a: half[i].3 as usize,
                        face_b: half[i + 1].3 as usize,
                    });
                }
                2 => edges += 1,
                count => {
                    return Err(GeomError::NonManifoldEdge {
                        a: lo,
                        b: hi,
                        count,
                    });
                }
            }
            i = j;
        }
        Ok(edges)
    }
}

/// Newell's normal of a polygon: twice its vector area.
pub(crate) fn newell(points: impl Iterator<Item = DVec3> + Clone) -> DVec3 {
    let mut first = None;
    let mut prev: Option<DVec3> = None;
    let mut n = DVec3::ZERO;
    for p in points {
        if let Some(q) = prev {
            n += q.cross(p);
        } else {
            first = Some(p);
        }
        prev = Some(p);
    }
    if let (Some(p), Some(q)) = (first, prev) {
        n += q.cross(p);
    }
    n
}

/// Component-wise min and max of a point set (infinities for an empty set).
pub(crate) fn bounds(points: &[DVec3]) -> (DVec3, DVec3) {
    points
        .iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| {
            (lo.min(p), hi.max(p))
        })
}

/// Fails on the first non-finite point, naming it.
pub(crate) fn check_finite(points: &[DVec3], what: &'static str) -> Result<(), GeomError> {
    match points.iter().position(|p| !p.is_finite()) {
        Some(index) => Err(GeomError::NonFinite {
            what,
            index,
            value: format!("{:?}", points[index]),
        }),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_cube() -> (Vec<DVec3>, Vec<Vec<u32>>) {
        let v = (0..8)
            .map(|i| DVec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64))
            .collect();
        // Counter-clockwise seen from outside.
        let f = vec![
            vec![0, 2, 3, 1], // z = 0, normal -z
            vec![4, 5, 7, 6], // z = 1
            vec![0, 1, 5, 4], // y = 0
            vec![2, 6, 7, 3], // y = 1
            vec![0, 4, 6, 2], // x = 0
            vec![1, 3, 7, 5], // x = 1
        ];
        (v, f)
    }

    #[test]
    fn closed_cube_is_accepted_with_euler_two_and_unit_volume() {
        let (v, f) = unit_cube();
        let m = PolyMesh::new(v, f).unwrap();
        let info = m.check_closed().unwrap();
        assert_eq!((info.vertices_used, info.edges, info.faces), (8, 12, 6));
        assert_eq!(info.euler_characteristic(), 2);
        assert!((m.signed_volume() - 1.0).abs() < 1e-15);
    }

    #[test]
    fn open_mesh_names_the_open_edge() {
        let (v, mut f) = unit_cube();
        f.pop();
        let err = PolyMesh::new(v, f).unwrap().check_closed().unwrap_err();
        assert!(matches!(err, GeomError::OpenEdge { .. }), "{err}");
        assert!(err.to_string().contains("open"), "{err}");
    }

    #[test]
    fn flipped_face_is_inconsistent_and_flipped_mesh_is_inward() {
        let (v, f) = unit_cube();
        let mut one = f.clone();
        one[2].reverse();
        let err = PolyMesh::new(v.clone(), one)
            .unwrap()
            .check_closed()
            .unwrap_err();
        assert!(
            matches!(err, GeomError::InconsistentOrientation { .. }),
            "{err}"
        );
        let all: Vec<Vec<u32>> = f
            .into_iter()
            .map(|mut x| {
                x.reverse();
                x
            })
            .collect();
        let err = PolyMesh::new(v, all).unwrap().check_closed().unwrap_err();
        match err {
            GeomError::InwardOrientation { volume } => assert!((volume + 1.0).abs() < 1e-15),
            e => panic!("expected InwardOrientation, got {e}"),
        }
    }

    #[test]
    fn bad_faces_and_coordinates_are_refused() {
        let (v, f) = unit_cube();
        let mut bad = v.clone();
        bad[3].y = f64::NAN;
        assert!(matches!(
            PolyMesh::new(bad, f.clone()),
            Err(GeomError::NonFinite { index: 3, .. })
        ));
        assert!(matches!(
            PolyMesh::new(v.clone(), vec![vec![0, 1, 9]]),
            Err(GeomError::VertexIndexOutOfRange { index: 9, .. })
        ));
        assert!(matches!(
            PolyMesh::new(v.clone(), vec![vec![0, 1]]),
            Err(GeomError::FaceTooSmall { len: 2, .. })
        ));
        assert!(matches!(
            PolyMesh::new(v, vec![vec![0, 1, 0]]),
            Err(GeomError::RepeatedVertex { vertex: 0, .. })
        ));
    }

    #[test]
    fn degenerate_and_warped_faces_are_refused() {
        let (mut v, f) = unit_cube();
        // Collapse the top face (z = 1) onto a line by moving vertex 6 onto 4 and 7 onto 5:
        // the top quad becomes zero-area.
        v[6] = v[4];
        v[7] = v[5];
        let err = PolyMesh::new(v, f.clone())
            .unwrap()
            .check_closed()
            .unwrap_err();
        assert!(matches!(err, GeomError::DegenerateFace { .. }), "{err}");
        let (mut v, f) = unit_cube();
        v[7].z += 0.01; // lifts one corner of the top face: warped by ~0.005 of its extent
        let err = PolyMesh::new(v, f).unwrap().check_closed().unwrap_err();
        assert!(
            matches!(err, GeomError::NonPlanarFace { face: 1, .. }),
            "{err}"
        );
    }

    #[test]
    fn non_manifold_edge_is_refused() {
        // Two tetrahedra glued along edge 0-1 (a "book" of four faces at that edge).
        let v = vec![
            DVec3::ZERO,
            DVec3::X,
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(0.0, 0.0, 1.0),
            DVec3::new(0.0, -1.0, 0.0),
            DVec3::new(0.0, 0.0, -1.0),
        ];
        let f = vec![
            vec![0, 2, 1],
            vec![0, 1, 3],
            vec![0, 3, 2],
            vec![1, 2, 3],
            vec![0, 4, 1],
            vec![0, 1, 5],
            vec![0, 5, 4],
            vec![1, 4, 5],
        ];
        let err = PolyMesh::new(v, f).unwrap().check_closed().unwrap_err();
        assert!(
            matches!(err, GeomError::NonManifoldEdge { count: 4, .. }),
            "{err}"
        );
    }
}
