//! Distance between convex bodies given only by their support mappings: the
//! Gilbert–Johnson–Keerthi (GJK) algorithm, for pairs involving a smooth body (an exact
//! ellipsoid), which has no features for V-Clip to walk.
//!
//! GJK looks for the point of the configuration-space obstacle A − B nearest the origin. Each
//! iteration asks both bodies for their support points along the current estimate −v, which
//! gives a lower bound v·w/|v| on the distance next to the upper bound |v|; the iteration stops
//! when the two agree to [`GJK_RELATIVE_TOLERANCE`]·distance + [`GJK_ABSOLUTE_TOLERANCE`]·size,
//! when the support point adds nothing new, or when the origin lies in the simplex
//! (intersection). Polyhedra answer support queries by hill climbing from their previous
//! support vertex (coherence, [`ConvexPolyhedron::support_from`]).

use glam::DVec3;
use impulse_geom::{ConvexPolyhedron, Ellipsoid, Pose};

use crate::feature::{Closest, Feature, FeaturePair};

/// Relative agreement of the distance's upper and lower bounds at which GJK stops. Default
/// `1e-12`.
pub const GJK_RELATIVE_TOLERANCE: f64 = 1e-12;

/// Absolute agreement of the bounds, as a fraction of the size of the configuration (the
/// largest coordinate magnitude of the support points; rounding makes anything much below
/// 1e-15 of it meaningless). Below this the bodies count as touching. Default `1e-13`.
pub const GJK_ABSOLUTE_TOLERANCE: f64 = 1e-13;

/// Iterations GJK may take before it returns its lower bound on the distance (the safe side
/// for time-of-impact bounds). Smooth bodies converge linearly; tens of iterations is usual.
/// Default `200`.
pub const GJK_MAX_ITERATIONS: u32 = 200;

/// A convex body that answers support queries in world coordinates.
#[derive(Clone, Copy, Debug)]
pub enum SupportBody<'a> {
    /// A sphere of the given radius about a world centre.
    Sphere {
        /// Radius.
        radius: f64,
        /// Centre (world).
        center: DVec3,
    },
    /// An exact ellipsoid placed at a pose.
    Ellipsoid(&'a Ellipsoid, &'a Pose),
    /// A convex polyhedron placed at a pose.
    Polyhedron(&'a ConvexPolyhedron, &'a Pose),
}

impl SupportBody<'_> {
    /// A point of the body farthest along `dir` (world); `hint` is the polyhedron vertex to
    /// start hill climbing from and is updated.
    fn support(&self, dir: DVec3, hint: &mut u32) -> DVec3 {
        match *self {
            SupportBody::Sphere { radius, center } => center + dir.normalize_or_zero() * radius,
            SupportBody::Ellipsoid(e, pose) => {
                pose.transform_point(e.support(pose.rotation.inverse() * dir))
            }
            SupportBody::Polyhedron(p, pose) => {
                let start = if (*hint as usize) < p.vertices().len() {
                    *hint
                } else {
                    0
                };
                let v = p.support_from(pose.rotation.inverse() * dir, start);
                *hint = v;
                pose.transform_point(p.vertex(v))
            }
        }
    }

    /// A point of the body farthest along `dir` (world).
    pub fn support_point(&self, dir: DVec3) -> DVec3 {
        self.support(dir, &mut 0)
    }

    /// A point inside the body (world), to pick the first search direction.
    fn center(&self) -> DVec3 {
        match *self {
            SupportBody::Sphere { center, .. } => center,
            SupportBody::Ellipsoid(_, pose) => pose.translation,
            SupportBody::Polyhedron(p, pose) => {
                pose.transform_point(p.mesh().bounding_box_center())
            }
        }
    }
}

/// A vertex of the simplex: w = a − b with the support points a ∈ A and b ∈ B.
#[derive(Clone, Copy, Debug)]
struct Vertex {
    w: DVec3,
    a: DVec3,
    b: DVec3,
}

/// The simplex (1 to 4 vertices) with the barycentric weights of its closest point.
#[derive(Clone, Copy, Debug)]
struct Simplex {
    v: [Vertex; 4],
    lambda: [f64; 4],
    len: usize,
}

impl Simplex {
    fn point(&self) -> DVec3 {
        (0..self.len).map(|i| self.v[i].w * self.lambda[i]).sum()
    }

    fn witnesses(&self) -> (DVec3, DVec3) {
        let a = (0..self.len).map(|i| self.v[i].a * self.lambda[i]).sum();
        let b = (0..self.len).map(|i| self.v[i].b * self.lambda[i]).sum();
        (a, b)
    }

    fn from(vs: &[(Vertex, f64)]) -> Self {
        let mut s = Simplex {
            v: [vs[0].0; 4],
            lambda: [0.0; 4],
            len: vs.len(),
        };
        for (i, (v, l)) in vs.iter().enumerate() {
            s.v[i] = *v;
            s.lambda[i] = *l;
        }
        s
    }
}

/// Closest point of segment ab to the origin, as a reduced simplex.
fn closest_segment(a: Vertex, b: Vertex) -> Simplex {
    let ab = b.w - a.w;
    let len2 = ab.length_squared();
    let t = if len2 > 0.0 { -a.w.dot(ab) / len2 } else { 0.0 };
    if t <= 0.0 {
        Simplex::from(&[(a, 1.0)])
    } else if t >= 1.0 {
        Simplex::from(&[(b, 1.0)])
    } else {
        Simplex::from(&[(a, 1.0 - t), (b, t)])
    }
}

/// Closest point of triangle abc to the origin by its Voronoi regions (Ericson, Real-Time
/// Collision Detection §5.1.5), as a reduced simplex. A degenerate triangle falls back to the
/// best of its edges.
fn closest_triangle(a: Vertex, b: Vertex, c: Vertex) -> Simplex {
    let (ab, ac) = (b.w - a.w, c.w - a.w);
    let ap = -a.w;
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return Simplex::from(&[(a, 1.0)]);
    }
    let bp = -b.w;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return Simplex::from(&[(b, 1.0)]);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let t = d1 / (d1 - d3);
        return Simplex::from(&[(a, 1.0 - t), (b, t)]);
    }
    let cp = -c.w;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return Simplex::from(&[(c, 1.0)]);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let t = d2 / (d2 - d6);
        return Simplex::from(&[(a, 1.0 - t), (c, t)]);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        let t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return Simplex::from(&[(b, 1.0 - t), (c, t)]);
    }
    let denom = va + vb + vc;
    if denom.is_nan() || denom <= 0.0 || denom.is_infinite() {
        return best_of([
            closest_segment(a, b),
            closest_segment(b, c),
            closest_segment(a, c),
        ]);
    }
    let (v, w) = (vb / denom, vc / denom);
    Simplex::from(&[(a, 1.0 - v - w), (b, v), (c, w)])
}

/// The simplex's point nearest the origin. For a triangle whose interior is nearest, the
/// projection of the origin on the triangle's plane: its normal comes from differences of
/// the vertices, so the direction stays accurate when the distance is far below the size of
/// the coordinates (where the barycentric combination loses it to cancellation).
fn estimate(s: &Simplex) -> DVec3 {
    if s.len == 3 {
        let n = (s.v[1].w - s.v[0].w).cross(s.v[2].w - s.v[0].w);
        let n2 = n.length_squared();
        if n2 > 0.0 && n2.is_finite() {
            return n * (n.dot(s.v[0].w) / n2);
        }
    }
    s.point()
}

fn best_of<const N: usize>(candidates: [Simplex; N]) -> Simplex {
    let mut best = candidates[0];
    for s in &candidates[1..] {
        if s.point().length_squared() < best.point().length_squared() {
            best = *s;
        }
    }
    best
}

/// Closest point of tetrahedron abcd to the origin, or `None` when the origin lies inside
/// (Ericson §5.1.6: only faces whose plane separates the origin from the opposite vertex are
/// candidates).
fn closest_tetrahedron(a: Vertex, b: Vertex, c: Vertex, d: Vertex) -> Option<Simplex> {
    let faces = [(a, b, c, d), (a, c, d, b), (a, d, b, c), (b, d, c, a)];
    let mut best: Option<Simplex> = None;
    for (p, q, r, s) in faces {
        let n = (q.w - p.w).cross(r.w - p.w);
        let origin_side = (-p.w).dot(n);
        let vertex_side = (s.w - p.w).dot(n);
        // Outside this face (or a flat tetrahedron, where every face is a candidate).
        if origin_side * vertex_side < 0.0 || vertex_side == 0.0 {
            let cand = closest_triangle(p, q, r);
            if best.is_none_or(|b| cand.point().length_squared() < b.point().length_squared()) {
                best = Some(cand);
            }
        }
    }
    best
}

/// Distance between two convex bodies given by support mappings, warm-started from the
/// polyhedron vertices cached in `warm` (a vertex feature on a polyhedral side). The features
/// reported are those support vertices (vertex 0 for smooth bodies).
pub fn closest(a: &SupportBody<'_>, b: &SupportBody<'_>, warm: FeaturePair) -> Closest {
    let vertex_hint = |f: Feature| match f {
        Feature::Vertex(v) => v,
        _ => 0,
    };
    let (mut ha, mut hb) = (vertex_hint(warm.a), vertex_hint(warm.b));
    let mut dir = b.center() - a.center();
    if dir.length_squared() == 0.0 {
        dir = DVec3::X;
    }
    let pa = a.support(dir, &mut ha);
    let pb = b.support(-dir, &mut hb);
    let first = Vertex {
        w: pa - pb,
        a: pa,
        b: pb,
    };
    let scale = pa.abs().max_element().max(pb.abs().max_element());
    let abs_tol = GJK_ABSOLUTE_TOLERANCE * scale;
    let mut simplex = Simplex::from(&[(first, 1.0)]);
    let mut v = first.w;
    let mut lower = 0.0f64;
    let mut iterations = 0;
    // Separated answers put point_b at point_a − v exactly, so the normal the caller derives
    // from the points is v's (accurate even for thin simplices, see `estimate`).
    let done = |s: &Simplex, v: DVec3, distance: f64, penetrating: bool, steps: u32, ha, hb| {
        let (point_a, mut point_b) = s.witnesses();
        if !penetrating {
            point_b = point_a - v;
        }
        Closest {
            distance,
            point_a,
            point_b,
            features: FeaturePair {
                a: Feature::Vertex(ha),
                b: Feature::Vertex(hb),
            },
            penetrating,
            steps,
            fallback: false,
        }
    };
    loop {
        let v_len = v.length();
        if v_len <= abs_tol {
            return done(&simplex, v, 0.0, true, iterations, ha, hb);
        }
        if iterations >= GJK_MAX_ITERATIONS {
            // Not converged: the lower bound is the safe distance.
            return done(&simplex, v, lower.min(v_len), false, iterations, ha, hb);
        }
        iterations += 1;
        let sa = a.support(-v, &mut ha);
        let sb = b.support(v, &mut hb);
        let w = Vertex {
            w: sa - sb,
            a: sa,
            b: sb,
        };
        // v·w/|v| bounds the distance from below (the plane through w normal to v separates).
        lower = lower.max(v.dot(w.w) / v_len);
        let gap = v_len - lower;
        let repeated = (0..simplex.len).any(|i| simplex.v[i].w == w.w);
        if gap <= GJK_RELATIVE_TOLERANCE * v_len + abs_tol || repeated {
            return done(&simplex, v, v_len, false, iterations, ha, hb);
        }
        let next = match simplex.len {
            1 => closest_segment(simplex.v[0], w),
            2 => closest_triangle(simplex.v[0], simplex.v[1], w),
            _ => match closest_tetrahedron(simplex.v[0], simplex.v[1], simplex.v[2], w) {
                Some(s) => s,
                None => {
                    let s = Simplex::from(&[
                        (simplex.v[0], 0.25),
                        (simplex.v[1], 0.25),
                        (simplex.v[2], 0.25),
                        (w, 0.25),
                    ]);
                    return done(&s, v, 0.0, true, iterations, ha, hb);
                }
            },
        };
        let v_next = estimate(&next);
        if v_next.length_squared() >= v.length_squared() {
            // No progress (rounding): the current estimate is as good as it gets.
            return done(&simplex, v, v_len, false, iterations, ha, hb);
        }
        simplex = next;
        v = v_next;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DQuat;
    use impulse_geom::primitives;
    use rand::rngs::Xoshiro256PlusPlus;
    use rand::{RngExt, SeedableRng};

    /// Agreement asked of a distance certificate, relative to the size of the scene.
    const CERTIFICATE: f64 = 1e-10;

    fn random_rotation(r: &mut Xoshiro256PlusPlus) -> DQuat {
        DQuat::from_euler(
            glam::EulerRot::XYZ,
            r.random::<f64>() * 6.3,
            r.random::<f64>() * 6.3,
            r.random::<f64>() * 6.3,
        )
    }

    /// Largest projection of a body on `u` by brute force (every vertex of a polyhedron; the
    /// closed form for smooth bodies is what is being tested, so those use dense sampling
    /// refined around the best sample).
    fn brute_support_value(body: &SupportBody<'_>, u: DVec3) -> f64 {
        match *body {
            SupportBody::Sphere { radius, center } => center.dot(u) + radius,
            SupportBody::Polyhedron(p, pose) => p
                .vertices()
                .iter()
                .map(|&x| pose.transform_point(x).dot(u))
                .fold(f64::NEG_INFINITY, f64::max),
            SupportBody::Ellipsoid(e, pose) => {
                // Parametrise the surface by a unit vector n: x = S n; maximise u·(R S n) over
                // n, which is |S Rᵀ u| (Cauchy–Schwarz) — the independent form of the support
                // value (the algorithm uses the support point).
                let local = pose.rotation.inverse() * u;
                pose.translation.dot(u) + (e.semi_axes() * local).length()
            }
        }
    }

    /// Checks a separated answer by weak duality: the two points lie on the bodies, and the
    /// slab between them normal to their difference separates the bodies, so the distance is
    /// exactly |a − b| up to the slack. Returns that slack.
    fn certificate_slack(a: &SupportBody<'_>, b: &SupportBody<'_>, c: &Closest) -> f64 {
        let d = c.point_a.distance(c.point_b);
        assert!(
            (d - c.distance).abs() <= 1e-12 * (1.0 + d),
            "{d} vs {}",
            c.distance
        );
        // Each point lies in its body (up to the tolerance): then |a − b| bounds the distance
        // from above, and the slab below from below.
        for (body, p) in [(a, c.point_a), (b, c.point_b)] {
            let outside = match *body {
                SupportBody::Sphere { radius, center } => p.distance(center) - radius,
                SupportBody::Polyhedron(poly, pose) => {
                    poly.max_plane_distance(pose.inverse_transform_point(p))
                }
                SupportBody::Ellipsoid(e, pose) => {
                    let local = pose.inverse_transform_point(p);
                    e.implicit(local) * 0.5 * e.semi_axes().min_element()
                }
            };
            assert!(
                outside <= CERTIFICATE,
                "{p} lies {outside} outside its body"
            );
        }
        let u = (c.point_b - c.point_a) / d;
        // The farthest point of A along u is (about) point_a, the nearest of B is point_b.
        let slack_a = brute_support_value(a, u) - c.point_a.dot(u);
        let slack_b = brute_support_value(b, -u) + c.point_b.dot(u);
        assert!(
            slack_a >= -1e-12 && slack_b >= -1e-12,
            "{slack_a} {slack_b}"
        );
        slack_a + slack_b
    }

    #[test]
    fn ellipsoid_against_polyhedra_spheres_and_ellipsoids_is_certified() {
        let mut r = Xoshiro256PlusPlus::seed_from_u64(7);
        let cube = primitives::cuboid(DVec3::new(0.5, 0.3, 0.2)).unwrap();
        let geo = primitives::geodesic_sphere(3, 0.4).unwrap();
        let mut worst: f64 = 0.0;
        let mut iterations = 0u64;
        let mut separated = 0;
        let mut hints = FeaturePair::default();
        for k in 0..6_000 {
            let axes = DVec3::new(
                0.05 + r.random::<f64>(),
                0.05 + r.random::<f64>(),
                0.01 + 0.5 * r.random::<f64>(),
            );
            let e = Ellipsoid::new(axes).unwrap();
            let pe = Pose::new(random_rotation(&mut r), DVec3::ZERO);
            let dir = (DVec3::new(r.random(), r.random(), r.random()) - 0.5).normalize();
            let dist = 0.3 + 2.5 * r.random::<f64>();
            let po = Pose::new(random_rotation(&mut r), dir * dist);
            let other_axes = DVec3::new(0.3, 0.1, 0.02 + r.random::<f64>() * 0.3);
            let e2 = Ellipsoid::new(other_axes).unwrap();
            let a = SupportBody::Ellipsoid(&e, &pe);
            let b = match k % 4 {
                0 => SupportBody::Polyhedron(&cube, &po),
                1 => SupportBody::Polyhedron(&geo, &po),
                2 => SupportBody::Sphere {
                    radius: 0.25,
                    center: po.translation,
                },
                _ => SupportBody::Ellipsoid(&e2, &po),
            };
            let c = closest(&a, &b, hints);
            hints = c.features;
            iterations += u64::from(c.steps);
            if c.penetrating {
                // A separating direction would contradict it: none of 2000 sampled directions
                // may separate the bodies by more than the tolerance.
                for _ in 0..2_000 {
                    let u = (DVec3::new(r.random(), r.random(), r.random()) - 0.5).normalize();
                    let gap = -brute_support_value(&a, u) - brute_support_value(&b, -u);
                    assert!(gap <= 1e-12, "claimed overlap, but {u} separates by {gap}");
                }
            } else {
                separated += 1;
                worst = worst.max(certificate_slack(&a, &b, &c));
                assert!(c.steps < GJK_MAX_ITERATIONS, "did not converge: {c:?}");
            }
        }
        let mean = iterations as f64 / 6_000.0;
        eprintln!(
            "{separated} of 6000 separated; worst certificate slack {worst:e}; mean iterations {mean:.1}"
        );
        assert!(worst <= CERTIFICATE, "worst slack {worst}");
        assert!(separated > 3_000, "only {separated} separated cases");
        assert!(mean < 30.0, "mean iterations {mean}");
    }

    /// An ellipsoid above a box face: the distance is the height minus the support value
    /// |S Rᵀ ẑ| (closed form), also at gaps far below the body size.
    #[test]
    fn ellipsoid_over_a_face_matches_the_closed_form() {
        let mut r = Xoshiro256PlusPlus::seed_from_u64(3);
        let table = primitives::cuboid(DVec3::new(0.6, 0.6, 0.02)).unwrap();
        let pt = Pose::from_translation(DVec3::new(0.0, 0.0, -0.02));
        let e = Ellipsoid::new(DVec3::new(0.1, 0.03, 0.02)).unwrap();
        let mut hints = FeaturePair::default();
        for k in 0..2_000 {
            let q = random_rotation(&mut r);
            let drop = (q.inverse() * DVec3::Z * e.semi_axes()).length();
            let gap = 10f64.powf(-2.0 - 10.0 * r.random::<f64>());
            let xy = (DVec3::new(r.random(), r.random(), 0.5) - 0.5) * 0.4;
            let pe = Pose::new(q, xy + DVec3::Z * (drop + gap));
            let c = closest(
                &SupportBody::Ellipsoid(&e, &pe),
                &SupportBody::Polyhedron(&table, &pt),
                hints,
            );
            hints = c.features;
            assert!(!c.penetrating, "case {k}");
            assert!(
                (c.distance - gap).abs()
                    <= 2.0 * (GJK_ABSOLUTE_TOLERANCE * 0.6 + GJK_RELATIVE_TOLERANCE * gap),
                "case {k}: {} vs {gap}",
                c.distance
            );
            assert!((c.point_a.z - gap).abs() < 1e-12, "{}", c.point_a);
            assert!(c.point_b.z.abs() < 1e-12, "{}", c.point_b);
            // The normal from points a gap apart, coordinates of size ~1: rounding ε/gap.
            let normal_tol = 1e-9 + 1e-15 / gap;
            assert!(c.direction().unwrap().distance(-DVec3::Z) < normal_tol);
        }
        // Sunk below the face: penetrating.
        let pe = Pose::from_translation(DVec3::new(0.0, 0.0, 0.015));
        let c = closest(
            &SupportBody::Ellipsoid(&e, &pe),
            &SupportBody::Polyhedron(&table, &pt),
            hints,
        );
        assert!(c.penetrating);
    }

    /// Ellipsoid and sphere along a principal axis: distance = gap of centres − a − r.
    #[test]
    fn ellipsoid_and_sphere_on_an_axis() {
        let e = Ellipsoid::new(DVec3::new(0.7, 0.2, 0.1)).unwrap();
        let pe = Pose::IDENTITY;
        for (axis, semi) in [(DVec3::X, 0.7), (DVec3::Y, 0.2), (DVec3::Z, 0.1)] {
            for gap in [1.0, 1e-3, 1e-9] {
                let b = SupportBody::Sphere {
                    radius: 0.3,
                    center: axis * (semi + 0.3 + gap),
                };
                let c = closest(&SupportBody::Ellipsoid(&e, &pe), &b, FeaturePair::default());
                assert!(
                    (c.distance - gap).abs() <= 1e-13 + 1e-12 * gap,
                    "{axis} {gap}: {}",
                    c.distance
                );
            }
        }
    }
}
