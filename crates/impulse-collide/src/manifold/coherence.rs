//! Coherence of manifolds from one step to the next: which new contact point is which old one,
//! so that a solver can start from the impulses it accumulated there (warm starting).

use super::{MAX_POINTS, Manifold};

/// Smallest cosine between the previous and the current normal for any point to match
/// (dimensionless, default `0.9`, about 26°). An impulse accumulated along the old normal is
/// a useful first guess only while the contact frame has barely turned; past this the pair's
/// contact has changed in kind (a box tipping over an edge) and the solver should start cold.
pub const MATCH_NORMAL_MIN_COS: f64 = 0.9;

/// For each point of `current`, the index of the point of `previous` it continues, if any.
///
/// Points match first by id (the same features of both bodies produced them; each previous
/// point is used once, the first unused one with that id); the rest match by position: the
/// closest pair of unmatched points whose midpoints are at most `distance` apart, then the
/// next closest, and so on (ties by index). Nothing matches when the manifolds belong to
/// different piece pairs or their normals differ by more than [`MATCH_NORMAL_MIN_COS`].
/// `distance` is a length, e.g. the tolerance the manifolds were computed with; a negative or
/// NaN `distance` disables matching by position.
#[must_use]
pub fn match_points(
    previous: &Manifold,
    current: &Manifold,
    distance: f64,
) -> [Option<usize>; MAX_POINTS] {
    let mut out = [None; MAX_POINTS];
    let turn = previous.normal.dot(current.normal);
    if previous.pieces != current.pieces || turn.is_nan() || turn < MATCH_NORMAL_MIN_COS {
        return out;
    }
    let (old, new) = (previous.points(), current.points());
    let mut used = [false; MAX_POINTS];
    for (i, p) in new.iter().enumerate() {
        if let Some(j) = (0..old.len()).find(|&j| !used[j] && old[j].id == p.id) {
            used[j] = true;
            out[i] = Some(j);
        }
    }
    let mut candidates: Vec<(f64, usize, usize)> = Vec::new();
    for (i, p) in new.iter().enumerate().filter(|(i, _)| out[*i].is_none()) {
        for (j, q) in old.iter().enumerate().filter(|(j, _)| !used[*j]) {
            let d = p.midpoint().distance(q.midpoint());
            if d <= distance {
                candidates.push((d, i, j));
            }
        }
    }
    candidates.sort_by(|x, y| x.0.total_cmp(&y.0).then((x.1, x.2).cmp(&(y.1, y.2))));
    for (_, i, j) in candidates {
        if out[i].is_none() && !used[j] {
            used[j] = true;
            out[i] = Some(j);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::feature::{Feature, FeaturePair};
    use crate::manifold::ContactPoint;
    use glam::DVec3;

    fn point(x: f64, a: Feature, b: Feature) -> ContactPoint {
        ContactPoint {
            point_a: DVec3::new(x, 0.0, 0.0),
            point_b: DVec3::new(x, 0.0, 0.0),
            gap: 0.0,
            id: FeaturePair { a, b },
        }
    }

    /// By id first, whatever the order; a new id by the nearest old position within the
    /// distance (the closest pair first); none beyond it, across piece pairs, or after the
    /// normal turned past [`MATCH_NORMAL_MIN_COS`].
    #[test]
    fn points_match_by_id_then_by_position() {
        use Feature::{Edge, Face, Vertex};
        let old = Manifold::new(
            DVec3::Z,
            FeaturePair {
                a: Face(0),
                b: Face(1),
            },
            &[
                point(0.0, Vertex(0), Face(1)),
                point(1.0, Vertex(1), Face(1)),
                point(2.0, Edge(3), Edge(4)),
                point(3.0, Vertex(2), Face(1)),
            ],
        )
        .unwrap();
        let new = Manifold::new(
            DVec3::new(0.0, 0.1, 1.0).normalize(),
            old.features,
            &[
                point(1.1, Vertex(1), Face(1)),
                // A new name 0.02 from the old (2.0) and 0.98 from the old (3.0, taken by id).
                point(2.02, Edge(5), Edge(4)),
                point(0.1, Vertex(0), Face(1)),
                point(3.0, Vertex(2), Face(1)),
            ],
        )
        .unwrap();
        assert_eq!(
            match_points(&old, &new, 0.05),
            [Some(1), Some(2), Some(0), Some(3)]
        );
        assert_eq!(
            match_points(&old, &new, 0.01),
            [Some(1), None, Some(0), Some(3)]
        );
        assert_eq!(
            match_points(&old, &new, f64::NAN),
            [Some(1), None, Some(0), Some(3)]
        );
        // Two new points near one old one: the nearer takes it.
        let near = Manifold::new(
            DVec3::Z,
            old.features,
            &[point(2.04, Edge(7), Edge(8)), point(2.01, Edge(9), Edge(8))],
        )
        .unwrap();
        assert_eq!(match_points(&old, &near, 0.05), [None, Some(2), None, None]);
        let mut other = new;
        other.pieces = (1, 0);
        assert_eq!(match_points(&old, &other, 0.05), [None; MAX_POINTS]);
        let mut turned = new;
        turned.normal = DVec3::new(0.0, 0.5, 1.0).normalize();
        assert_eq!(match_points(&old, &turned, 0.05), [None; MAX_POINTS]);
    }
}
