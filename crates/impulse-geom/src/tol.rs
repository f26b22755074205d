//! Geometric tolerances of `impulse-geom`, in one place.
//!
//! Every tolerance here is *relative*: it is multiplied by a size of the object it applies to
//! (a face's extent, a polyhedron's bounding-box diagonal), so the same constant serves a 1 mm
//! part and a 20 m alley. The SE(3) kernels keep their small-angle thresholds next to the
//! series they switch ([`crate::se3`], [`crate::pose`]).

/// Largest distance of a face vertex from the face's best-fit plane, relative to the face's
/// extent (the diagonal of its bounding box), before a polygon mesh face counts as non-planar.
///
/// Dimensionless; default `1e-6`. It tolerates coordinates rounded to `f32` (relative error
/// about `6e-8`) but rejects faces that are visibly warped: the volume integrals of a warped
/// face depend on the normal chosen, so such a face has no well-defined mass properties.
/// Triangulate a warped face instead.
pub const FACE_PLANARITY_REL: f64 = 1e-6;

/// Smallest area of a mesh face, relative to the square of its extent, below which the face is
/// degenerate (its vertices are collinear or coincident and its normal is undefined).
///
/// Dimensionless; default `1e-12`. A sliver whose width is a millionth of its length is still
/// accepted: its normal is then accurate to about `1e-6` rad and its contribution to any
/// integral is proportional to its (tiny) area.
pub const DEGENERATE_FACE_REL: f64 = 1e-12;

/// Geometric tolerance of a convex polyhedron, relative to the diagonal of its bounding box.
///
/// Dimensionless; default `1e-7`. It is the one length scale with which a convex hull or an
/// explicit face list is judged: points within this distance of a face plane are on the face;
/// adjacent faces whose vertices all lie within it of each other's planes are coplanar and are
/// merged into one polygon; an edge whose faces bend outward by more than it is non-convex.
/// It is large enough to absorb `f32` rounding of exported meshes (about `6e-8` relative) and
/// orders of magnitude below any collision tolerance (ε_c is `1e-2`..`1e-3` of body size, thesis
/// chapter 2), so merging within it never changes a simulation.
pub const POLYHEDRON_REL: f64 = 1e-7;

/// How far the face angles around a convex polyhedron's vertex may exceed 2π before the vertex
/// is refused as non-convex, in radians; default `1e-6`.
///
/// At a convex corner the angles sum to less than 2π (the angle defect is positive). The check
/// exists to catch gross errors — a saddle, or a fan of faces wound twice round a vertex (sum
/// near 4π) — that the per-edge convexity test cannot see; the slack only absorbs rounding at
/// nearly flat corners.
pub const VERTEX_ANGLE_SLACK: f64 = 1e-6;
