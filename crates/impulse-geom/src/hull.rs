//! Three-dimensional convex hull by Quickhull (Barber, Dobkin & Huhdanpaa 1996).
//!
//! [`quickhull`] returns outward triangles over the input points. It is judged at one length
//! scale, the tolerance: a point counts as outside a face only if it lies more than the
//! tolerance above the face's plane, so duplicate points and points on faces or edges are
//! absorbed, never added as vertices. The near-flat triangles this leaves on coplanar point
//! sets are merged into polygons afterwards by [`crate::ConvexPolyhedron`]'s validation
//! pipeline, which also rechecks convexity, so a numerical slip here cannot produce a wrong
//! polyhedron, only a [`GeomError::HullFailed`].
//!
//! Most users want [`crate::ConvexPolyhedron::hull`].

use std::collections::HashMap;

use glam::DVec3;

use crate::error::GeomError;

/// A hull face under construction.
struct Face {
    /// Vertices, counter-clockwise seen from outside.
    v: [u32; 3],
    /// Unit outward normal.
    n: DVec3,
    /// Plane offset: `n · x = d` on the face.
    d: f64,
    /// `adj[i]` is the face across the edge `v[i] → v[(i + 1) % 3]`.
    adj: [u32; 3],
    /// Points more than the tolerance above this face that no earlier face claimed.
    outside: Vec<u32>,
    alive: bool,
}

impl Face {
    fn dist(&self, p: DVec3) -> f64 {
        self.n.dot(p) - self.d
    }
}

/// Classification of a face during one visibility search.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Mark {
    Unseen,
    Visible,
    Hidden,
}

/// Outward triangles (indices into `points`) of the convex hull of `points`.
///
/// `points` must be finite and at least four; `tolerance` is a length (see the module
/// documentation).
///
/// # Errors
/// [`GeomError::DegeneratePoints`] if the points are coincident, collinear or coplanar within
/// `tolerance`; [`GeomError::HullFailed`] if the horizon of a new point is not a simple loop
/// (a numerical inconsistency).
pub fn quickhull(points: &[DVec3], tolerance: f64) -> Result<Vec<[u32; 3]>, GeomError> {
    // Work relative to the bounding-box centre: plane offsets then carry no large constant.
    let (lo, hi) = crate::mesh::bounds(points);
    let centre = 0.5 * (lo + hi);
    let p: Vec<DVec3> = points.iter().map(|&x| x - centre).collect();
    let simplex = initial_simplex(&p, tolerance)?;

    let mut faces: Vec<Face> = Vec::new();
    let [a, b, c, d] = simplex;
    for tri in [[a, b, c], [a, b, d], [a, c, d], [b, c, d]] {
        let apex = simplex
            .iter()
            .copied()
            .find(|i| !tri.contains(i))
            .unwrap_or(a);
        let mut f = new_face(&p, tri)?;
        if f.dist(p[apex as usize]) > 0.0 {
            f = new_face(&p, [tri[0], tri[2], tri[1]])?;
        }
        faces.push(f);
    }
    link_small(&mut faces);

    // Give every other point to the first face it is clearly outside of.
    for i in 0..p.len() as u32 {
        if simplex.contains(&i) {
            continue;
        }
        if let Some(f) = faces.iter_mut().find(|f| f.dist(p[i as usize]) > tolerance) {
            f.outside.push(i);
        }
    }

    let mut marks: Vec<Mark> = vec![Mark::Unseen; faces.len()];
    let mut pending: Vec<u32> = (0..faces.len() as u32).collect();
    let mut visible: Vec<u32> = Vec::new();
    let mut horizon: Vec<(u32, u32, u32)> = Vec::new(); // (tail, head, hidden neighbour)
    let mut search: Vec<u32> = Vec::new();
    while let Some(start) = pending.pop() {
        let f0 = &faces[start as usize];
        if !f0.alive || f0.outside.is_empty() {
            continue;
        }
        // The eye: the outside point farthest from the face.
        let eye = f0
            .outside
            .iter()
            .copied()
            .max_by(|&i, &j| f0.dist(p[i as usize]).total_cmp(&f0.dist(p[j as usize])))
            .unwrap_or(f0.outside[0]);
        let e = p[eye as usize];

        // Visible faces: the connected set around `start` more than the tolerance below the
        // eye. Their boundary with hidden faces is the horizon.
        visible.clear();
        horizon.clear();
        search.clear();
        search.push(start);
        marks[start as usize] = Mark::Visible;
        while let Some(f) = search.pop() {
            visible.push(f);
            for k in 0..3 {
                let g = faces[f as usize].adj[k];
                match marks[g as usize] {
                    Mark::Visible => {}
                    Mark::Hidden => {
                        let v = faces[f as usize].v;
                        horizon.push((v[k], v[(k + 1) % 3], g));
                    }
                    Mark::Unseen => {
                        if faces[g as usize].dist(e) > tolerance {
                            marks[g as usize] = Mark::Visible;
                            search.push(g);
                        } else {
                            marks[g as usize] = Mark::Hidden;
                            let v = faces[f as usize].v;
                            horizon.push((v[k], v[(k + 1) % 3], g));
                        }
                    }
                }
            }
        }

        // A cone of new faces from the eye to the horizon.
        let first_new = faces.len() as u32;
        let mut by_tail: HashMap<u32, u32> = HashMap::with_capacity(horizon.len());
        let mut by_head: HashMap<u32, u32> = HashMap::with_capacity(horizon.len());
        for (k, &(t, h, g)) in horizon.iter().enumerate() {
            let id = first_new + k as u32;
            if by_tail.insert(t, id).is_some() || by_head.insert(h, id).is_some() {
                return Err(GeomError::HullFailed {
                    reason: format!("the horizon seen from point {eye} is not a simple loop"),
                });
            }
            let mut f = new_face(&p, [t, h, eye])?;
            f.adj[0] = g;
            // Point the hidden neighbour's edge (h -> t) at the new face.
            let hidden = &mut faces[g as usize];
            let Some(slot) = (0..3).find(|&j| hidden.v[j] == h && hidden.v[(j + 1) % 3] == t)
            else {
                return Err(GeomError::HullFailed {
                    reason: format!("horizon edge {t}-{h} is not shared with its neighbour"),
                });
            };
            hidden.adj[slot] = id;
            faces.push(f);
            marks.push(Mark::Unseen);
        }
        for (k, &(t, h, _)) in horizon.iter().enumerate() {
            let id = first_new as usize + k;
            // Edge h -> eye borders the new face starting at h; edge eye -> t the one ending at t.
            match (by_tail.get(&h), by_head.get(&t)) {
                (Some(&next), Some(&prev)) => faces[id].adj = [faces[id].adj[0], next, prev],
                _ => {
                    return Err(GeomError::HullFailed {
                        reason: format!("the horizon seen from point {eye} does not close"),
                    });
                }
            }
        }

        // Retire the visible faces and hand their points to the new ones.
        for &f in &visible {
            faces[f as usize].alive = false;
            let orphans = std::mem::take(&mut faces[f as usize].outside);
            for q in orphans {
                if q == eye {
                    continue;
                }
                let x = p[q as usize];
                if let Some(nf) = faces[first_new as usize..]
                    .iter_mut()
                    .find(|nf| nf.dist(x) > tolerance)
                {
                    nf.outside.push(q);
                }
            }
        }
        // Reset only what this search marked (a full reset would make the hull quadratic).
        for &f in &visible {
            marks[f as usize] = Mark::Unseen;
        }
        for &(_, _, g) in &horizon {
            marks[g as usize] = Mark::Unseen;
        }
        pending.extend(first_new..faces.len() as u32);
    }
    Ok(faces.iter().filter(|f| f.alive).map(|f| f.v).collect())
}

fn new_face(p: &[DVec3], v: [u32; 3]) -> Result<Face, GeomError> {
    let (a, b, c) = (p[v[0] as usize], p[v[1] as usize], p[v[2] as usize]);
    let Some(n) = (b - a).cross(c - a).try_normalize() else {
        return Err(GeomError::HullFailed {
            reason: format!(
                "points {}, {}, {} form a degenerate hull triangle",
                v[0], v[1], v[2]
            ),
        });
    };
    Ok(Face {
        v,
        n,
        d: n.dot((a + b + c) / 3.0),
        adj: [u32::MAX; 3],
        outside: Vec::new(),
        alive: true,
    })
}

/// Sets adjacency among a handful of faces by matching opposite edges.
fn link_small(faces: &mut [Face]) {
    for f in 0..faces.len() {
        for k in 0..3 {
            let (t, h) = (faces[f].v[k], faces[f].v[(k + 1) % 3]);
            for (g, other) in faces.iter().enumerate() {
                if (0..3).any(|j| other.v[j] == h && other.v[(j + 1) % 3] == t) {
                    faces[f].adj[k] = g as u32;
                    break;
                }
            }
        }
    }
}

/// Four points spanning a tetrahedron as large as cheaply possible: the farthest pair among the
/// axis extremes, the point farthest from their line, and the point farthest from their plane.
fn initial_simplex(p: &[DVec3], tolerance: f64) -> Result<[u32; 4], GeomError> {
    let degenerate = |reason| GeomError::DegeneratePoints { reason, tolerance };
    let mut extremes = Vec::with_capacity(6);
    for axis in 0..3 {
        let key = |i: &usize| p[*i][axis];
        let idx: Vec<usize> = (0..p.len()).collect();
        let lo = idx
            .iter()
            .copied()
            .min_by(|a, b| key(a).total_cmp(&key(b)))
            .unwrap_or(0);
        let hi = idx
            .iter()
            .copied()
            .max_by(|a, b| key(a).total_cmp(&key(b)))
            .unwrap_or(0);
        extremes.push(lo);
        extremes.push(hi);
    }
    let mut best = (0, 0, -1.0);
    for &i in &extremes {
        for &j in &extremes {
            let d = p[i].distance_squared(p[j]);
            if d > best.2 {
                best = (i, j, d);
            }
        }
    }
    let (i0, i1) = (best.0, best.1);
    if best.2.sqrt() <= tolerance {
        return Err(degenerate("all points coincide"));
    }
    let axis = (p[i1] - p[i0]).normalize();
    let line_dist = |x: DVec3| (x - p[i0]).reject_from_normalized(axis).length();
    let i2 = argmax(p, line_dist);
    if line_dist(p[i2]) <= tolerance {
        return Err(degenerate("all points are collinear"));
    }
    let n = (p[i1] - p[i0]).cross(p[i2] - p[i0]).normalize();
    let plane_dist = |x: DVec3| (x - p[i0]).dot(n).abs();
    let i3 = argmax(p, plane_dist);
    if plane_dist(p[i3]) <= tolerance {
        return Err(degenerate("all points are coplanar"));
    }
    Ok([i0 as u32, i1 as u32, i2 as u32, i3 as u32])
}

fn argmax(p: &[DVec3], f: impl Fn(DVec3) -> f64) -> usize {
    let mut best = (0, f64::NEG_INFINITY);
    for (i, &x) in p.iter().enumerate() {
        let v = f(x);
        if v > best.1 {
            best = (i, v);
        }
    }
    best.0
}

#[cfg(test)]
mod tests {
    use crate::error::GeomError;
    use crate::polyhedron::ConvexPolyhedron;
    use crate::polyhedron::tests::assert_valid;
    use crate::primitives;
    use glam::DVec3;
    use rand::rngs::Xoshiro256PlusPlus;
    use rand::{RngExt, SeedableRng};

    /// Containment slack for input points, in units of the hull's tolerance: a point dropped
    /// as "within the tolerance of a face" can end up that far outside a merged face's fitted
    /// plane (fit error + the drop threshold).
    const CONTAINMENT_SLACK: f64 = 2.0;

    /// The defining properties of the hull, checked by brute force: it is a valid convex
    /// polyhedron (see `assert_valid`), its vertices are input points (so it lies inside the
    /// true hull), and every input point lies inside it (so it contains the true hull), both
    /// within the tolerance.
    fn assert_is_hull(points: &[DVec3], h: &ConvexPolyhedron) {
        assert_valid(h);
        for v in h.vertices() {
            assert!(points.contains(v), "hull vertex {v} is not an input point");
        }
        let mut worst: f64 = f64::NEG_INFINITY;
        for &q in points {
            worst = worst.max(h.max_plane_distance(q));
        }
        assert!(
            worst <= CONTAINMENT_SLACK * h.tolerance(),
            "an input point lies {worst:e} outside (tolerance {:e})",
            h.tolerance()
        );
    }

    fn rng() -> Xoshiro256PlusPlus {
        Xoshiro256PlusPlus::seed_from_u64(0x1234_5678)
    }

    fn unit_vector(r: &mut Xoshiro256PlusPlus) -> DVec3 {
        loop {
            let v = DVec3::new(r.random(), r.random(), r.random()) * 2.0 - DVec3::ONE;
            if (1e-3..1.0).contains(&v.length_squared()) {
                return v.normalize();
            }
        }
    }

    #[test]
    fn ten_thousand_random_points_in_a_box_and_a_ball() {
        let mut r = rng();
        let cube: Vec<DVec3> = (0..10_000)
            .map(|_| DVec3::new(r.random(), r.random(), r.random()) * DVec3::new(3.0, 1.0, 0.2))
            .collect();
        assert_is_hull(&cube, &ConvexPolyhedron::hull(&cube).unwrap());
        let ball: Vec<DVec3> = (0..10_000)
            .map(|_| unit_vector(&mut r) * r.random::<f64>().cbrt() + DVec3::splat(100.0))
            .collect();
        assert_is_hull(&ball, &ConvexPolyhedron::hull(&ball).unwrap());
    }

    #[test]
    fn ten_thousand_points_on_a_sphere_are_all_vertices() {
        let mut r = rng();
        let pts: Vec<DVec3> = (0..10_000).map(|_| unit_vector(&mut r)).collect();
        let h = ConvexPolyhedron::hull(&pts).unwrap();
        assert_is_hull(&pts, &h);
        // No input point is interior; all are strictly convex vertices unless two random
        // points nearly coincide, which at this density happens for at most a handful.
        assert!(
            h.vertices().len() >= 9_990,
            "{} vertices",
            h.vertices().len()
        );
        // Faces are triangles except where four points are coplanar within the tolerance
        // (close pairs of random points): those merge into polygons, which assert_valid has
        // checked are planar. V − E + F = 2 then fixes E and F from the polygon sizes.
        let extra: usize = (0..h.face_count() as u32)
            .map(|f| h.face_vertices(f).len() - 3)
            .sum();
        assert!(extra <= h.face_count() / 100, "{extra} merged corners");
        assert_eq!(h.face_count() + extra, 2 * h.vertices().len() - 4);
    }

    #[test]
    fn cube_corners_with_duplicates_give_the_cube() {
        let corners = primitives::cuboid_mesh(DVec3::splat(1.0))
            .unwrap()
            .vertices()
            .to_vec();
        let mut pts = Vec::new();
        for k in 0..5 {
            for (i, &c) in corners.iter().enumerate() {
                pts.push(c);
                if (i + k) % 3 == 0 {
                    pts.push(c); // uneven duplication
                }
            }
        }
        let h = ConvexPolyhedron::hull(&pts).unwrap();
        assert_is_hull(&pts, &h);
        assert_eq!(
            (h.vertices().len(), h.edges().len(), h.face_count()),
            (8, 12, 6)
        );
    }

    #[test]
    fn coplanar_grids_give_polygon_faces() {
        // A 7×7×7 lattice: every face of the hull holds 49 coplanar points and every edge 7
        // collinear ones; only the 8 corners are vertices.
        let lattice: Vec<DVec3> = (0..343)
            .map(|i| DVec3::new((i % 7) as f64, (i / 7 % 7) as f64, (i / 49) as f64) * 0.25)
            .collect();
        let h = ConvexPolyhedron::hull(&lattice).unwrap();
        assert_is_hull(&lattice, &h);
        assert_eq!(
            (h.vertices().len(), h.edges().len(), h.face_count()),
            (8, 12, 6)
        );
        // Cube corners, edge midpoints, face centres and the centre.
        let mut pts = Vec::new();
        for x in [-1.0, 0.0, 1.0] {
            for y in [-1.0, 0.0, 1.0] {
                for z in [-1.0, 0.0, 1.0] {
                    pts.push(DVec3::new(x, y, z));
                }
            }
        }
        let h = ConvexPolyhedron::hull(&pts).unwrap();
        assert_is_hull(&pts, &h);
        assert_eq!(h.face_count(), 6);
        // A 100-gon prism: its caps hold 100 coplanar points each.
        let prism = primitives::regular_prism_mesh(100, 1.0, 0.1).unwrap();
        let h = ConvexPolyhedron::hull(prism.vertices()).unwrap();
        assert_is_hull(prism.vertices(), &h);
        assert_eq!(
            (h.vertices().len(), h.edges().len(), h.face_count()),
            (200, 300, 102)
        );
    }

    #[test]
    fn hull_of_a_geodesic_sphere_is_the_geodesic_sphere() {
        let g = primitives::geodesic_sphere_mesh(4, 1.0).unwrap();
        let h = ConvexPolyhedron::hull(g.vertices()).unwrap();
        assert_is_hull(g.vertices(), &h);
        assert_eq!(
            (h.vertices().len(), h.edges().len(), h.face_count()),
            (642, 1920, 1280)
        );
    }

    #[test]
    fn flat_and_tiny_point_sets_are_refused() {
        let grid: Vec<DVec3> = (0..100)
            .map(|i| DVec3::new((i % 10) as f64, (i / 10) as f64, 2.0))
            .collect();
        let e = ConvexPolyhedron::hull(&grid).unwrap_err();
        assert!(
            matches!(
                e,
                GeomError::DegeneratePoints {
                    reason: "all points are coplanar",
                    ..
                }
            ),
            "{e}"
        );
        let line: Vec<DVec3> = (0..10).map(|i| DVec3::splat(i as f64)).collect();
        let e = ConvexPolyhedron::hull(&line).unwrap_err();
        assert!(
            matches!(
                e,
                GeomError::DegeneratePoints {
                    reason: "all points are collinear",
                    ..
                }
            ),
            "{e}"
        );
        let same = vec![DVec3::ONE; 6];
        assert!(matches!(
            ConvexPolyhedron::hull(&same).unwrap_err(),
            GeomError::DegeneratePoints {
                reason: "all points coincide",
                ..
            }
        ));
        assert!(matches!(
            ConvexPolyhedron::hull(&[DVec3::ZERO, DVec3::X, DVec3::Y]).unwrap_err(),
            GeomError::TooFewPoints { count: 3 }
        ));
        let mut nan = grid.clone();
        nan[5].x = f64::NAN;
        assert!(matches!(
            ConvexPolyhedron::hull(&nan).unwrap_err(),
            GeomError::NonFinite { index: 5, .. }
        ));
        // Nearly flat: a slab 1e-9 thick (below the tolerance 1e-7 × size) is flat.
        let mut slab = grid.clone();
        slab[17].z += 1e-9;
        assert!(matches!(
            ConvexPolyhedron::hull(&slab).unwrap_err(),
            GeomError::DegeneratePoints { .. }
        ));
    }
}
