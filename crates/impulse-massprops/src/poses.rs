//! Stable poses of a part and the quasi-static estimates of how often it comes to rest in each
//! (thesis §7.5, Problem 10 "EPS"; after Wiegley et al. and \[MZG⁺96\]).
//!
//! A part dropped on a large flat surface comes to rest on a facet of its convex hull. For
//! every hull facet (coplanar hull faces are one facet: [`ConvexPolyhedron`] merges them) this
//! module finds
//! - its share of the unit sphere seen from the centre of mass, the facet's solid angle over
//!   4π (eq. 7.1, generalised from a triangle to the facet's convex spherical polygon:
//!   `A = (Σ β_k − (n − 2)·π) / 4π`, β_k its spherical interior angles);
//! - whether it is **stable**: the centre of mass projects into the facet's interior, by more
//!   than [`STABLE_MARGIN_REL`] of the hull's size;
//! - where an unstable facet **rolls to**: resting on it, the part tips about the edge whose
//!   line the centre of mass's projection lies furthest beyond (the nearest edge) onto the
//!   neighbouring facet across that edge, and on from there until a stable facet is reached
//!   (each tip lowers the centre of mass, so the chain ends).
//!
//! [`PoseAnalysis::quasi_static`] is the quasi-static estimate: the solid-angle fractions
//! (what a uniformly random orientation on SO(3) lands on), each unstable facet handing its
//! share to the stable facet it rolls to. [`PoseAnalysis::perturbed_quasi_static`] moves
//! part of each stable facet's share across its edges: a cone of half-angle α projected
//! down from the centre of mass meets the facet's plane in a disk of radius h·tan α (h the
//! height of the centre of mass), and the fraction of that disk beyond an edge is the share
//! that rolls across it \[inferred: the thesis gives only "a cone projected down from the
//! COM estimates how likely the part is to roll across edge e"; the details are in
//! \[MZG⁺96\], not in the seed; the thesis used α = 20° for every part\]. The disk's area
//! beyond each edge is exact: rays from the disk's centre through the facet's corners split
//! it into one wedge per edge, and the part of a wedge beyond its edge's line, at distance
//! d, over the wedge's angles φ₁..φ₂ measured from the edge's normal, is
//! `½ρ²(φ₂ − φ₁) − ½d²(tan φ₂ − tan φ₁)` (φ clipped to ±acos(d/ρ)).
//!
//! **Must not know** about simulation: the dynamic estimate (dropping the part) lives in
//! `impulse-sim`; it classifies its final poses with [`PoseAnalysis::facet_facing`].

use glam::DVec3;
use impulse_geom::ConvexPolyhedron;

use crate::MassError;

/// A facet is stable when the centre of mass projects inside it by more than this fraction
/// of the hull's diameter; default `1e-9`. A projection on an edge (within rounding) is not
/// stable: the least disturbance tips the part.
pub const STABLE_MARGIN_REL: f64 = 1e-9;

/// A centre of mass closer to the hull's boundary than this fraction of the hull's diameter
/// is refused ([`MassError::ComOutsideHull`]): the part would rest on a facet with zero
/// height. Default `1e-9`.
pub const COM_INSIDE_REL: f64 = 1e-9;

/// Two stable facets are one pose class when their signatures (height, facet area, solid
/// angle, edge lengths and corner distances from the centre of mass's foot) agree to this
/// fraction of the hull's diameter (lengths; its square for areas; absolutely for solid
/// angles). Default `1e-6`.
pub const CLASS_REL: f64 = 1e-6;

/// One facet of the hull, as a resting pose.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RestingFacet {
    /// The hull face (index into the [`ConvexPolyhedron`]'s faces).
    pub face: u32,
    /// Outward unit normal in the part's frame: resting on this facet, it points straight
    /// down.
    pub normal: DVec3,
    /// Height of the centre of mass above the facet's plane.
    pub height: f64,
    /// The facet's solid angle seen from the centre of mass, as a fraction of 4π (eq. 7.1).
    pub solid_angle: f64,
    /// Signed distance of the centre of mass's projection from the facet's boundary,
    /// positive inside.
    pub margin: f64,
    /// Whether the part can rest on this facet ([`STABLE_MARGIN_REL`]).
    pub stable: bool,
    /// For an unstable facet, the facet it tips onto (across the edge whose line the centre
    /// of mass's projection lies furthest beyond); `None` for a stable one.
    pub tips_to: Option<u32>,
    /// The stable facet the part ends on when it lands on this one (itself when stable).
    pub rests_on: u32,
}

/// Stable poses of a part: every facet of its convex hull seen from its centre of mass.
#[derive(Clone, Debug)]
pub struct PoseAnalysis {
    facets: Vec<RestingFacet>,
    /// The facets' corners in the part's frame (the hull's face loops).
    corners: Vec<Vec<DVec3>>,
    /// The facets' edges' neighbour facets: `neighbours[f][k]` is across edge k of facet f
    /// (from corner k to corner k + 1).
    neighbours: Vec<Vec<u32>>,
    com: DVec3,
    /// The hull's bounding-box diagonal.
    size: f64,
}

impl PoseAnalysis {
    /// Analyses `hull` with its centre of mass at `com` (the part's frame).
    ///
    /// # Errors
    /// [`MassError::InvalidInertia`] for a non-finite `com`; [`MassError::ComOutsideHull`]
    /// when `com` is not inside the hull by [`COM_INSIDE_REL`] of its diameter.
    pub fn new(hull: &ConvexPolyhedron, com: DVec3) -> Result<Self, MassError> {
        if !com.is_finite() {
            return Err(MassError::InvalidInertia {
                reason: format!("the centre of mass {com} is not finite"),
            });
        }
        let size = diameter(hull.vertices());
        let n = hull.face_count();
        let mut facets = Vec::with_capacity(n);
        let mut corners = Vec::with_capacity(n);
        let mut neighbours = Vec::with_capacity(n);
        for f in 0..n as u32 {
            let plane = hull.face_plane(f);
            let height = plane.offset - plane.normal.dot(com);
            if height <= COM_INSIDE_REL * size {
                return Err(MassError::ComOutsideHull {
                    com: com.to_array(),
                    face: f,
                    distance: -height,
                });
            }
            let loop_: Vec<DVec3> = hull
                .face_vertices(f)
                .iter()
                .map(|&v| hull.vertex(v))
                .collect();
            let across: Vec<u32> = hull
                .face_edges(f)
                .iter()
                .map(|&e| hull.edge(e).other_face(f))
                .collect();
            let foot = com + height * plane.normal;
            let margin = polygon_margin(&loop_, plane.normal, foot);
            let stable = margin > STABLE_MARGIN_REL * size;
            let tips_to = (!stable).then(|| across[tipping_edge(&loop_, plane.normal, foot)]);
            facets.push(RestingFacet {
                face: f,
                normal: plane.normal,
                height,
                solid_angle: solid_angle_fraction(&loop_, com),
                margin,
                stable,
                tips_to,
                rests_on: f,
            });
            corners.push(loop_);
            neighbours.push(across);
        }
        // Follow each unstable facet's tips to a stable one. Each tip lowers the centre of
        // mass, so a chain visits a facet at most once; a longer chain is a numerical fault.
        for f in 0..n {
            let mut at = f;
            let mut steps = 0;
            while let Some(next) = facets[at].tips_to {
                at = next as usize;
                steps += 1;
                if steps > n {
                    return Err(MassError::InvalidInertia {
                        reason: format!("facet {f} tips round a cycle of facets (rounding?)"),
                    });
                }
            }
            facets[f].rests_on = at as u32;
        }
        Ok(Self {
            facets,
            corners,
            neighbours,
            com,
            size,
        })
    }

    /// Every facet of the hull, indexed by hull face.
    pub fn facets(&self) -> &[RestingFacet] {
        &self.facets
    }

    /// The stable facets (hull face indices), in increasing order.
    pub fn stable(&self) -> Vec<u32> {
        self.facets
            .iter()
            .filter(|f| f.stable)
            .map(|f| f.face)
            .collect()
    }

    /// The stable facets grouped into classes the part cannot tell apart: facets whose
    /// resting configurations have the same signature ([`CLASS_REL`]: the height of the
    /// centre of mass, the facet's area, solid angle, edge lengths and corner distances from
    /// the centre of mass's foot). For a symmetric part (the faces of a cube, the sides of a
    /// prism) these are the facets its symmetries map onto each other; a signature match
    /// without a symmetry is possible in principle, so this is a reading aid, not a proof.
    /// Classes are ordered by their first facet; facets in increasing order.
    pub fn classes(&self) -> Vec<Vec<u32>> {
        let size = self.size;
        let tol = CLASS_REL * size;
        let signature = |f: &RestingFacet| {
            let c = &self.corners[f.face as usize];
            let n = c.len();
            let foot = self.com + f.height * f.normal;
            let mut edges: Vec<f64> = (0..n).map(|k| (c[(k + 1) % n] - c[k]).length()).collect();
            let mut reach: Vec<f64> = c.iter().map(|&x| (x - foot).length()).collect();
            edges.sort_by(f64::total_cmp);
            reach.sort_by(f64::total_cmp);
            let area = (1..n.saturating_sub(1))
                .map(|k| 0.5 * (c[k] - c[0]).cross(c[k + 1] - c[0]).length())
                .sum::<f64>();
            (f.height, area, f.solid_angle, edges, reach)
        };
        let same = |a: &(f64, f64, f64, Vec<f64>, Vec<f64>),
                    b: &(f64, f64, f64, Vec<f64>, Vec<f64>)| {
            (a.0 - b.0).abs() <= tol
                && (a.1 - b.1).abs() <= tol * size
                && (a.2 - b.2).abs() <= CLASS_REL
                && a.3.len() == b.3.len()
                && a.3.iter().zip(&b.3).all(|(x, y)| (x - y).abs() <= tol)
                && a.4.iter().zip(&b.4).all(|(x, y)| (x - y).abs() <= tol)
        };
        let mut classes: Vec<(_, Vec<u32>)> = Vec::new();
        for f in self.facets.iter().filter(|f| f.stable) {
            let sig = signature(f);
            match classes.iter_mut().find(|(s, _)| same(s, &sig)) {
                Some((_, members)) => members.push(f.face),
                None => classes.push((sig, vec![f.face])),
            }
        }
        classes.into_iter().map(|(_, m)| m).collect()
    }

    /// The centre of mass the analysis was made with.
    pub fn com(&self) -> DVec3 {
        self.com
    }

    /// The hull's size: the diagonal of its axis-aligned bounding box (the scale of this
    /// module's relative tolerances).
    pub fn diameter(&self) -> f64 {
        self.size
    }

    /// The facet's corners (part frame), counter-clockwise seen from outside.
    pub fn corners(&self, face: u32) -> &[DVec3] {
        &self.corners[face as usize]
    }

    /// The quasi-static estimate, per facet (0 for unstable facets): the solid-angle
    /// fractions (eq. 7.1), each unstable facet's share handed to the stable facet it rolls
    /// to. The shares sum to 1.
    pub fn quasi_static(&self) -> Vec<f64> {
        let mut p = vec![0.0; self.facets.len()];
        for f in &self.facets {
            p[f.rests_on as usize] += f.solid_angle;
        }
        p
    }

    /// The perturbed quasi-static estimate with a cone of half-angle `half_angle` (radians;
    /// the thesis used 20°), per facet: from [`Self::quasi_static`], each stable facet hands
    /// the fraction of its cone's disk beyond each edge to the stable facet the part rests on
    /// after tipping across that edge (see the module documentation). One pass: a share
    /// moved is not perturbed again. `half_angle = 0` gives the quasi-static estimate.
    ///
    /// # Errors
    /// [`MassError::InvalidStatistic`] unless `0 ≤ half_angle < π/2`.
    pub fn perturbed_quasi_static(&self, half_angle: f64) -> Result<Vec<f64>, MassError> {
        if !(0.0..std::f64::consts::FRAC_PI_2).contains(&half_angle) {
            return Err(MassError::InvalidStatistic {
                name: "cone half-angle",
                reason: format!("{half_angle} rad is not in [0, π/2)"),
            });
        }
        let q = self.quasi_static();
        let mut p = q.clone();
        for f in self.facets.iter().filter(|f| f.stable) {
            let share = q[f.face as usize];
            let radius = f.height * half_angle.tan();
            if share == 0.0 || radius == 0.0 {
                continue;
            }
            let foot = self.com + f.height * f.normal;
            let fractions =
                disk_beyond_edges(&self.corners[f.face as usize], f.normal, foot, radius);
            for (k, frac) in fractions.into_iter().enumerate() {
                let to = self.facets[self.neighbours[f.face as usize][k] as usize].rests_on;
                p[f.face as usize] -= share * frac;
                p[to as usize] += share * frac;
            }
        }
        Ok(p)
    }

    /// The facet whose outward normal is closest to `down` (a direction in the part's frame:
    /// the world's down turned into the part), if within `max_angle` radians of it: the facet
    /// a part at rest with that orientation stands on.
    pub fn facet_facing(&self, down: DVec3, max_angle: f64) -> Option<u32> {
        let down = down.try_normalize()?;
        let best = self
            .facets
            .iter()
            .max_by(|a, b| a.normal.dot(down).total_cmp(&b.normal.dot(down)))?;
        (best.normal.dot(down).clamp(-1.0, 1.0).acos() <= max_angle).then_some(best.face)
    }
}

/// The diagonal of the axis-aligned bounding box of `points` (a size scale for tolerances).
fn diameter(points: &[DVec3]) -> f64 {
    let lo = points
        .iter()
        .fold(DVec3::splat(f64::INFINITY), |a, &p| a.min(p));
    let hi = points
        .iter()
        .fold(DVec3::splat(f64::NEG_INFINITY), |a, &p| a.max(p));
    (hi - lo).length()
}

/// The solid angle of a convex planar polygon seen from `eye`, over 4π (eq. 7.1), summed over
/// a fan of triangles by Van Oosterom and Strackee's formula (IEEE Trans. Biomed. Eng. 30,
/// 1983): tan(Ω/2) = |a·(b × c)| / (1 + a·b + a·c + b·c) for unit vectors a, b, c toward a
/// triangle's corners. The spherical excess Σβ_k − (n − 2)π computed from the polygon's
/// angles loses every digit on a facet that is small or seen edge-on from the centre of mass
/// (its tangents at a corner are differences of nearly equal directions): on a 1.8 km spike
/// of a 1 cm pebble, found by the part fuzz target, the shares of a part summed to 0.99987.
fn solid_angle_fraction(corners: &[DVec3], eye: DVec3) -> f64 {
    let dirs: Vec<DVec3> = corners.iter().map(|&c| (c - eye).normalize()).collect();
    let a = dirs[0];
    let omega: f64 = dirs[1..]
        .windows(2)
        .map(|w| {
            let (b, c) = (w[0], w[1]);
            let num = a.dot(b.cross(c)).abs();
            let den = 1.0 + a.dot(b) + a.dot(c) + b.dot(c);
            2.0 * num.atan2(den)
        })
        .sum();
    omega / (4.0 * std::f64::consts::PI)
}

/// Outward unit normal, in the polygon's plane, of edge k (corner k to k + 1) of a polygon
/// counter-clockwise about `normal`, and the edge's signed distance from `p` (positive when
/// `p` is inside its line).
fn edge_line(corners: &[DVec3], normal: DVec3, k: usize, p: DVec3) -> (DVec3, f64) {
    let a = corners[k];
    let b = corners[(k + 1) % corners.len()];
    let out = (b - a).cross(normal).normalize();
    (out, (a - p).dot(out))
}

/// Signed distance of `p` (in the polygon's plane) from a convex polygon's boundary: the
/// smallest distance to an edge line, positive inside; outside, minus the distance to the
/// polygon.
fn polygon_margin(corners: &[DVec3], normal: DVec3, p: DVec3) -> f64 {
    let inside = (0..corners.len())
        .map(|k| edge_line(corners, normal, k, p).1)
        .fold(f64::INFINITY, f64::min);
    if inside > 0.0 {
        inside
    } else {
        -(0..corners.len())
            .map(|k| segment_distance(corners[k], corners[(k + 1) % corners.len()], p))
            .fold(f64::INFINITY, f64::min)
    }
}

fn segment_distance(a: DVec3, b: DVec3, p: DVec3) -> f64 {
    let ab = b - a;
    let t = ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
    (a + t * ab - p).length()
}

/// The edge a part resting on this facet tips about when the centre of mass's projection
/// `p` lies outside or on its boundary: the edge whose line `p` lies furthest beyond. When
/// the facet's point nearest `p` is inside an edge, that edge (the distance to the facet is
/// then the largest distance beyond an edge line); at a corner, the edge whose outward
/// normal is nearest the direction of `p` from the corner. Turning about that edge moves the
/// centre of mass down, since it lies beyond it.
fn tipping_edge(corners: &[DVec3], normal: DVec3, p: DVec3) -> usize {
    (0..corners.len())
        .map(|k| (k, -edge_line(corners, normal, k, p).1))
        .fold((0, f64::NEG_INFINITY), |best, (k, beyond)| {
            if beyond > best.1 { (k, beyond) } else { best }
        })
        .0
}

/// For a disk of `radius` centred at `p` inside a convex polygon (in its plane), the
/// fraction of the disk's area beyond each edge's line within that edge's wedge (rays from
/// `p` through the corners); see the module documentation.
fn disk_beyond_edges(corners: &[DVec3], normal: DVec3, p: DVec3, radius: f64) -> Vec<f64> {
    let n = corners.len();
    let disk = std::f64::consts::PI * radius * radius;
    (0..n)
        .map(|k| {
            let (out, d) = edge_line(corners, normal, k, p);
            if d >= radius {
                return 0.0;
            }
            // Angles of the two corners about p, from the edge's outward normal,
            // counter-clockwise about `normal`.
            let angle = |c: DVec3| {
                let r = c - p;
                normal.dot(out.cross(r)).atan2(out.dot(r))
            };
            let (lo, hi) = {
                let (a, b) = (angle(corners[k]), angle(corners[(k + 1) % n]));
                (a.min(b), a.max(b))
            };
            let reach = (d / radius).clamp(-1.0, 1.0).acos();
            let (phi1, phi2) = (lo.max(-reach), hi.min(reach));
            if phi2 <= phi1 {
                return 0.0;
            }
            let area =
                0.5 * radius * radius * (phi2 - phi1) - 0.5 * d * d * (phi2.tan() - phi1.tan());
            area.max(0.0) / disk
        })
        .collect()
}

#[cfg(test)]
#[path = "poses_tests.rs"]
mod tests;
