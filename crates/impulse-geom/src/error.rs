//! The error type of `impulse-geom`: every way an input can be refused, naming what and where.

use std::path::PathBuf;

/// Why a mesh, point set, polyhedron or shape parameter was refused.
///
/// Indices are positions in the input the caller gave (vertex and face lists in their original
/// order), so a message can be traced back to the offending line of a file.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum GeomError {
    /// A coordinate or parameter is NaN or infinite.
    #[error("{what} {index} has a non-finite coordinate ({value})")]
    NonFinite {
        /// What kind of item ("vertex", "point").
        what: &'static str,
        /// Its index in the input.
        index: usize,
        /// The offending value, formatted.
        value: String,
    },
    /// A scalar parameter is out of its allowed range.
    #[error("invalid {name} = {value}: {requirement}")]
    InvalidParameter {
        /// The parameter's name.
        name: &'static str,
        /// The value given.
        value: f64,
        /// What the value must satisfy.
        requirement: &'static str,
    },
    /// A face refers to a vertex that does not exist.
    #[error("face {face} refers to vertex {index}, but there are only {vertex_count} vertices")]
    VertexIndexOutOfRange {
        /// Face index.
        face: usize,
        /// The index found in the face.
        index: u32,
        /// Number of vertices.
        vertex_count: usize,
    },
    /// A face has fewer than three vertices.
    #[error("face {face} has {len} vertices; a face needs at least 3")]
    FaceTooSmall {
        /// Face index.
        face: usize,
        /// Number of vertices in it.
        len: usize,
    },
    /// A face visits the same vertex twice.
    #[error("face {face} visits vertex {vertex} more than once")]
    RepeatedVertex {
        /// Face index.
        face: usize,
        /// The repeated vertex.
        vertex: u32,
    },
    /// A face has (almost) zero area, so it has no normal.
    #[error(
        "face {face} is degenerate: area {area:e} is below {limit:e} (collinear or coincident vertices)"
    )]
    DegenerateFace {
        /// Face index.
        face: usize,
        /// Its area.
        area: f64,
        /// The smallest accepted area for its size.
        limit: f64,
    },
    /// A face lost its area while coplanar faces were merged or vertices on straight edges
    /// removed: the input has features at the scale of the tolerance.
    #[error(
        "face {face} collapsed while merging coplanar faces: the input has features only a few tolerances across"
    )]
    CollapsedFace {
        /// Face index (after merging).
        face: usize,
    },
    /// A face's vertices do not lie in one plane.
    #[error(
        "face {face} is not planar: a vertex lies {deviation:e} from its plane (tolerance {tolerance:e}); triangulate it"
    )]
    NonPlanarFace {
        /// Face index.
        face: usize,
        /// Largest distance of a vertex from the face plane.
        deviation: f64,
        /// The tolerance it exceeds.
        tolerance: f64,
    },
    /// An edge is used by one face only: the mesh has a hole.
    #[error(
        "the mesh is open: edge {from}->{to} of face {face} has no matching edge {to}->{from} in another face"
    )]
    OpenEdge {
        /// Edge tail vertex.
        from: u32,
        /// Edge head vertex.
        to: u32,
        /// The face that uses it.
        face: usize,
    },
    /// Two faces traverse an edge in the same direction: their orientations disagree.
    #[error(
        "faces {face_a} and {face_b} both traverse edge {from}->{to}: face orientations are inconsistent"
    )]
    InconsistentOrientation {
        /// Edge tail vertex.
        from: u32,
        /// Edge head vertex.
        to: u32,
        /// First face using it.
        face_a: usize,
        /// Second face using it in the same direction.
        face_b: usize,
    },
    /// More than two faces meet at an edge.
    #[error("edge {a}-{b} is shared by {count} faces; a closed surface needs exactly 2")]
    NonManifoldEdge {
        /// One endpoint.
        a: u32,
        /// The other endpoint.
        b: u32,
        /// How many faces use it.
        count: usize,
    },
    /// A closed mesh encloses negative volume: its faces are ordered clockwise seen from outside.
    #[error(
        "the mesh is oriented inwards (signed volume {volume:e} < 0): faces must be counter-clockwise seen from outside"
    )]
    InwardOrientation {
        /// The signed volume found.
        volume: f64,
    },
    /// A closed mesh encloses no volume.
    #[error("the mesh encloses no volume (signed volume {volume:e})")]
    ZeroVolume {
        /// The signed volume found.
        volume: f64,
    },
    /// A vertex is listed but no face uses it.
    #[error("vertex {vertex} is not used by any face")]
    UnusedVertex {
        /// Vertex index.
        vertex: usize,
    },
    /// The two faces at an edge bend inwards: the polyhedron is not convex.
    #[error(
        "not convex: at edge {a}-{b} face {face_b} rises {excess:e} above the plane of face {face_a} (tolerance {tolerance:e})"
    )]
    NotConvex {
        /// Edge endpoint (input numbering).
        a: u32,
        /// Edge endpoint (input numbering).
        b: u32,
        /// The face whose plane is crossed.
        face_a: usize,
        /// The face that crosses it.
        face_b: usize,
        /// How far above the plane it rises.
        excess: f64,
        /// The tolerance it exceeds.
        tolerance: f64,
    },
    /// A face polygon is not convex (a reflex corner).
    #[error("face {face} is not a convex polygon (reflex or folded corner at vertex {vertex})")]
    NonConvexFace {
        /// Face index.
        face: usize,
        /// The vertex at the offending corner (input numbering).
        vertex: u32,
    },
    /// The faces around a vertex do not form a convex cone.
    #[error(
        "the faces around vertex {vertex} do not form a convex corner (face angles sum to {angle_sum} rad >= 2π)"
    )]
    NonConvexVertex {
        /// Vertex (input numbering).
        vertex: u32,
        /// Sum of the face angles at it.
        angle_sum: f64,
    },
    /// The faces around a vertex form more than one fan (two shells touching at a point).
    #[error("vertex {vertex} is non-manifold: its faces form several separate fans")]
    NonManifoldVertex {
        /// Vertex (input numbering).
        vertex: u32,
    },
    /// Coplanar adjacent faces, once merged, do not bound a single simple polygon.
    #[error("coplanar faces around vertex {vertex} do not merge into one simple polygon")]
    CoplanarMergeFailed {
        /// A vertex on the offending boundary (input numbering).
        vertex: u32,
    },
    /// The surface is not a topological sphere (V − E + F ≠ 2): several pieces or handles.
    #[error("V - E + F = {v} - {e} + {f} = {} != 2: the surface is not a single closed shell of genus 0", *v as i64 - *e as i64 + *f as i64)]
    EulerCharacteristic {
        /// Vertices.
        v: usize,
        /// Edges.
        e: usize,
        /// Faces.
        f: usize,
    },
    /// Too few points for a solid hull.
    #[error("a convex hull needs at least 4 points, got {count}")]
    TooFewPoints {
        /// Number of points given.
        count: usize,
    },
    /// The points span no volume.
    #[error("the points span no volume: {reason} (within tolerance {tolerance:e})")]
    DegeneratePoints {
        /// "coincident", "collinear" or "coplanar".
        reason: &'static str,
        /// The tolerance used.
        tolerance: f64,
    },
    /// The hull construction met an inconsistency it could not resolve (numerical trouble).
    #[error("convex hull construction failed: {reason}")]
    HullFailed {
        /// What went wrong.
        reason: String,
    },
    /// A Wavefront OBJ file could not be parsed.
    #[error("{source_name}:{line}: {message}")]
    Obj {
        /// File name, or `"<string>"` for text not read from a file.
        source_name: String,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// A file could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
}
