//! Three-dimensional convex hull by Quickhull (Barber, Dobkin & Huhdanpaa 1996) with exact
//! orientation predicates.
//!
//! Whether a face is visible from a new point is decided by the exact sign of Shewchuk's
//! adaptive `orient3d` predicate (the `robust` crate), so the growing hull is always exactly
//! convex and the horizon of a new point is always one simple loop: no floating-point slip can
//! tangle the topology, however thin, elongated or degenerate the input. The tolerance only
//! decides which points are worth adding: a point becomes a hull vertex only if it lies more
//! than the tolerance outside the current hull, so duplicates and points on faces or edges are
//! absorbed. The near-coplanar triangles this leaves are merged into polygons afterwards by
//! [`crate::ConvexPolyhedron`]'s validation pipeline.
//!
//! Most users want [`crate::ConvexPolyhedron::hull`].

use std::collections::HashMap;

use glam::DVec3;

use crate::error::GeomError;

/// A hull face under construction.
struct Face {
    /// Vertices, counter-clockwise seen from outside.
    v: [u32; 3],
    /// 1 / |(v1 − v0) × (v2 − v0)|: turns the orientation determinant into a distance.
    inv_norm: f64,
    /// `adj[i]` is the face across the edge `v[i] → v[(i + 1) % 3]`.
    adj: [u32; 3],
    /// Points more than the tolerance above this face that no earlier face claimed.
    outside: Vec<u32>,
    alive: bool,
}

/// Exact-sign orientation of `q` against the plane of triangle `v`: positive when `q` lies
/// strictly outside (above a triangle counter-clockwise seen from outside), zero when coplanar.
/// Its magnitude is |(v1 − v0) × (v2 − v0)| times the distance of `q` from the plane.
fn above(p: &[DVec3], v: [u32; 3], q: DVec3) -> f64 {
    let c = |x: DVec3| robust::Coord3D {
        x: x.x,
        y: x.y,
        z: x.z,
    };
    // orient3d is positive when q lies below a counter-clockwise triangle, hence the minus.
    -robust::orient3d(
        c(p[v[0] as usize]),
        c(p[v[1] as usize]),
        c(p[v[2] as usize]),
        c(q),
    )
}

impl Face {
    /// Signed distance of `q` from the face's plane (outside positive); its sign is exact.
    fn dist(&self, p: &[DVec3], q: DVec3) -> f64 {
        above(p, self.v, q) * self.inv_norm
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
        let tri = if above(&p, tri, p[apex as usize]) > 0.0 {
            [tri[0], tri[2], tri[1]]
        } else {
            tri
        };
        faces.push(new_face(&p, tri)?);
    }
    link_small(&mut faces);

    // Every point strictly outside the hull (exact sign) is kept in the outside set of one face
    // it lies above; points on or inside it are dropped for good. Only points more than the
    // tolerance out become vertices (see `next_eye`).
    for i in 0..p.len() as u32 {
        if simplex.contains(&i) {
            continue;
        }
        if let Some(f) = faces
            .iter_mut()
            .find(|f| above(&p, f.v, p[i as usize]) > 0.0)
        {
            f.outside.push(i);
        }
    }

    let mut marks: Vec<Mark> = vec![Mark::Unseen; faces.len()];
    let mut pending: Vec<u32> = (0..faces.len() as u32).collect();
    let mut visible: Vec<u32> = Vec::new();
    let mut horizon: Vec<(u32, u32, u32)> = Vec::new(); // (tail, head, hidden neighbour)
    let mut search: Vec<u32> = Vec::new();
    loop {
        let Some(start) = pending.pop() else {
            // Points still waiting lie above their own face by at most the tolerance, but may lie
            // farther above another: move each to the face it is farthest above, and go on if
            // that is more than the tolerance.
            if !settle_near_points(&p, &mut faces, tolerance, &mut pending) {
                break;
            }
            continue;
        };
        let f0 = &faces[start as usize];
        if !f0.alive {
            continue;
        }
        let Some(eye) = next_eye(&p, f0, tolerance) else {
            continue;
        };
        let e = p[eye as usize];

        // Visible faces: the connected set around `start` that the eye lies strictly above
        // (exact sign). The hull is exactly convex, so this set is a disc and its boundary
        // with the hidden faces, the horizon, is one simple loop.
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
                        if above(&p, faces[g as usize].v, e) > 0.0 {
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
                // A point above a visible face and above none of the new ones is inside the new
                // hull (Barber et al.'s partition lemma, exact here because the sign is).
                let x = p[q as usize];
                if let Some(nf) = faces[first_new as usize..]
                    .iter_mut()
                    .find(|nf| above(&p, nf.v, x) > 0.0)
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

/// The point of `face`'s outside set to add next, if any lies more than the tolerance above it:
/// the farthest one; among points within the tolerance of that distance (a grid's whole edge
/// can tie) the one farthest from the face's first vertex, an extreme point of the tied set, so
/// that a corner is added before the points on the edges it ends, which would otherwise become
/// nearly collinear vertices.
fn next_eye(p: &[DVec3], face: &Face, tolerance: f64) -> Option<u32> {
    let dists: Vec<f64> = face
        .outside
        .iter()
        .map(|&i| face.dist(p, p[i as usize]))
        .collect();
    let far = dists.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if far <= tolerance {
        return None;
    }
    let base = p[face.v[0] as usize];
    face.outside
        .iter()
        .zip(&dists)
        .filter(|&(_, &d)| d >= far - tolerance)
        .map(|(&i, _)| i)
        .max_by(|&i, &j| {
            base.distance_squared(p[i as usize])
                .total_cmp(&base.distance_squared(p[j as usize]))
        })
}

/// Reassigns every waiting outside point to the live face it lies farthest above; queues the
/// faces that now hold a point more than the tolerance out. Returns whether any was queued.
fn settle_near_points(
    p: &[DVec3],
    faces: &mut [Face],
    tolerance: f64,
    pending: &mut Vec<u32>,
) -> bool {
    let mut near: Vec<u32> = Vec::new();
    for f in faces.iter_mut().filter(|f| f.alive) {
        near.append(&mut f.outside);
    }
    let live: Vec<usize> = (0..faces.len()).filter(|&f| faces[f].alive).collect();
    let mut queued = false;
    for q in near {
        let x = p[q as usize];
        let mut best = (usize::MAX, 0.0);
        for &f in &live {
            let d = faces[f].dist(p, x);
            if d > best.1 {
                best = (f, d);
            }
        }
        if best.0 != usize::MAX {
            faces[best.0].outside.push(q);
            if best.1 > tolerance {
                pending.push(best.0 as u32);
                queued = true;
            }
        }
    }
    queued
}

fn new_face(p: &[DVec3], v: [u32; 3]) -> Result<Face, GeomError> {
    let (a, b, c) = (p[v[0] as usize], p[v[1] as usize], p[v[2] as usize]);
    let norm = (b - a).cross(c - a).length();
    // Never zero in exact arithmetic (a new face's apex lies strictly above a face through its
    // base edge); a zero here means the cross product underflowed.
    if !(norm > 0.0 && norm.is_finite()) {
        return Err(GeomError::HullFailed {
            reason: format!(
                "points {}, {}, {} form a degenerate hull triangle",
                v[0], v[1], v[2]
            ),
        });
    }
    Ok(Face {
        v,
        inv_norm: 1.0 / norm,
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

    /// Containment slack for input points, in units of the hull's tolerance: the guarantee of
    /// `ConvexPolyhedron::hull` (a point dropped within the tolerance of the exact hull, plus at
    /// most half the tolerance for a merged face's plane). Measured worst over 2,378 adversarial
    /// hulls: 1.46.
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

    /// Families of nearly degenerate point sets, many seeds each. Realistic ones — cylinders
    /// (co-circular and collinear points), grids on a cube's faces with rounding noise, 1000:1
    /// needles, integer-rounded spheres, plates down to 1e-5 of their width — must give a valid
    /// hull. Sets with features a couple of tolerances across (a plate 3e-7 thick, two specks
    /// 1e5 of their size apart) may be refused with an error. None may give a wrong hull.
    #[test]
    fn adversarial_point_sets_never_give_a_wrong_hull() {
        let mut r = rng();
        let mut refused = 0;
        for seed in 0..25 {
            let n = 20 + (r.random::<f64>() * 600.0) as usize;
            let mut uniform = |scale: DVec3| -> Vec<DVec3> {
                (0..n)
                    .map(|_| DVec3::new(r.random(), r.random(), r.random()) * scale)
                    .collect()
            };
            let plate = uniform(DVec3::new(1.0, 1.0, 1e-5));
            let needle = uniform(DVec3::new(1000.0, 1.0, 1.0));
            let thin = uniform(DVec3::new(1.0, 1.0, 3e-7));
            let specks: Vec<DVec3> = uniform(DVec3::splat(1e-3))
                .into_iter()
                .enumerate()
                .map(|(i, p)| {
                    if i % 2 == 0 {
                        p
                    } else {
                        p + DVec3::new(100.0, 3.0, -2.0)
                    }
                })
                .chain([DVec3::new(50.0, 40.0, 1.0)])
                .collect();
            let k = 3 + seed * 2;
            let cylinder: Vec<DVec3> = (0..k * 4)
                .map(|i| {
                    let a = 0.3 + std::f64::consts::TAU * (i % k) as f64 / k as f64;
                    DVec3::new(a.cos(), a.sin(), (i / k) as f64 * 0.3)
                })
                .collect();
            let noise = [0.0, 1e-12, 1e-9][seed % 3];
            let g = 2 + seed % 7;
            let mut grid = Vec::new();
            for i in 0..=g {
                for j in 0..=g {
                    let (a, b) = (i as f64 / g as f64, j as f64 / g as f64);
                    for p in [
                        DVec3::new(0.0, a, b),
                        DVec3::new(1.0, a, b),
                        DVec3::new(a, 0.0, b),
                        DVec3::new(a, 1.0, b),
                        DVec3::new(a, b, 0.0),
                        DVec3::new(a, b, 1.0),
                    ] {
                        let jitter = DVec3::new(r.random(), r.random(), r.random()) - 0.5;
                        grid.push(p + jitter * noise);
                    }
                }
            }
            let rounded: Vec<DVec3> = (0..n)
                .map(|_| (unit_vector(&mut r) * 10.0).round())
                .collect();
            for (name, pts, may_refuse) in [
                ("plate", plate, false),
                ("needle", needle, false),
                ("cylinder", cylinder, false),
                ("grid", grid, false),
                ("rounded", rounded, false),
                ("thin", thin, true),
                ("specks", specks, true),
            ] {
                match ConvexPolyhedron::hull(&pts) {
                    Ok(h) => assert_is_hull(&pts, &h),
                    Err(e) if may_refuse => {
                        refused += 1;
                        assert!(!e.to_string().is_empty());
                    }
                    Err(e) => panic!("{name} (seed {seed}): {e}"),
                }
            }
        }
        // The refusals are the exception even among the extreme families.
        assert!(refused <= 10, "{refused} of 50 extreme sets refused");
    }
}
