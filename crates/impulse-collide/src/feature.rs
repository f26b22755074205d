//! Features of convex polyhedra and the result of a closest-features query.

use glam::DVec3;
use impulse_geom::ConvexPolyhedron;

/// A feature of a convex polyhedron: a vertex, an edge or a face, by index.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Feature {
    /// Vertex index.
    Vertex(u32),
    /// Edge index.
    Edge(u32),
    /// Face index.
    Face(u32),
}

impl Feature {
    /// True when the index is in range for `poly`.
    pub fn is_valid_for(&self, poly: &ConvexPolyhedron) -> bool {
        match *self {
            Feature::Vertex(v) => (v as usize) < poly.vertices().len(),
            Feature::Edge(e) => (e as usize) < poly.edges().len(),
            Feature::Face(f) => (f as usize) < poly.face_count(),
        }
    }
}

/// The closest features of a pair of polyhedra: what a caller caches between queries to warm
/// start the next one (thesis §2.2.1, coherence).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct FeaturePair {
    /// Feature of the first polyhedron.
    pub a: Feature,
    /// Feature of the second polyhedron.
    pub b: Feature,
}

impl Default for FeaturePair {
    /// The cold start: vertex 0 of each polyhedron.
    fn default() -> Self {
        Self {
            a: Feature::Vertex(0),
            b: Feature::Vertex(0),
        }
    }
}

/// The answer of a closest-features query between two convex bodies.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Closest {
    /// Distance between the bodies (≥ 0). Zero when they touch or penetrate.
    pub distance: f64,
    /// Closest point on the first body, world frame. When penetrating, a witness point.
    pub point_a: DVec3,
    /// Closest point on the second body, world frame. When penetrating, a witness point.
    pub point_b: DVec3,
    /// The closest features (the witness features when penetrating): cache them for the next
    /// query of the same pair.
    pub features: FeaturePair,
    /// True when the bodies intersect (share interior points, or touch exactly).
    pub penetrating: bool,
    /// Number of feature updates the walk took (0 when the cached pair was already closest).
    pub steps: u32,
    /// True when the walk hit its step limit and the answer came from the brute-force search
    /// (never expected; reported so tests and statistics can see it).
    pub fallback: bool,
}

impl Closest {
    /// Unit vector from the first body's closest point to the second's (the separating
    /// direction d̂ of thesis §2.3.2), or `None` when the bodies touch or penetrate.
    pub fn direction(&self) -> Option<DVec3> {
        if self.penetrating {
            return None;
        }
        (self.point_b - self.point_a).try_normalize()
    }
}
