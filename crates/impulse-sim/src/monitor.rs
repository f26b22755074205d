//! An independent measure of the promise "bodies never interpenetrate by more than ε_c".
//!
//! The event loop counts what it sees at its own checks; a penetration that happens between
//! checks (a wrong time-of-impact bound, a missed pair) is invisible to it. The monitor looks
//! from outside: given only the bodies' current poses and shapes, it finds every close pair
//! by its own sweep over axis-aligned boxes (not the loop's broad phase or heap) and measures
//! each pair's exact distance with the collision crate's queries
//! ([`impulse_collide::shape::closest`]) and, when they overlap, the penetration depth
//! ([`impulse_collide::depth::shape_penetration`]). [`crate::run`] samples it at every
//! recorded frame; the world's checking mode ([`crate::World::set_checking`]) at every step of
//! the loop.

use impulse_collide::{PairCache, depth, shape};
use impulse_geom::Aabb;
use rustc_hash::FxHashMap;

use crate::world::{BodyHandle, World};

/// What the monitor has measured so far.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PenetrationReport {
    /// Samples taken (instants at which every close pair was measured).
    pub samples: u64,
    /// Pair measurements, over all samples.
    pub pairs_measured: u64,
    /// The largest penetration depth seen (length; 0 if no pair ever overlapped).
    pub max_depth: f64,
    /// Where and when the largest depth was seen: (time, first body, second body).
    pub worst: Option<(f64, String, String)>,
    /// The smallest distance between two separated bodies seen (length; ∞ if none).
    pub min_distance: f64,
}

/// The monitor: its own feature caches (coherence) and what it has found.
#[derive(Clone, Debug)]
pub struct PenetrationMonitor {
    caches: FxHashMap<(BodyHandle, BodyHandle), PairCache>,
    report: PenetrationReport,
}

impl Default for PenetrationMonitor {
    fn default() -> Self {
        Self::new()
    }
}

impl PenetrationMonitor {
    /// A monitor that has seen nothing.
    #[must_use]
    pub fn new() -> Self {
        Self {
            caches: FxHashMap::default(),
            report: PenetrationReport {
                min_distance: f64::INFINITY,
                ..PenetrationReport::default()
            },
        }
    }

    /// What it has found.
    #[must_use]
    pub fn report(&self) -> &PenetrationReport {
        &self.report
    }

    /// Measures every close pair of the world now: pairs with at least one dynamic body or
    /// multibody link (two links of one multibody only when they can collide: its
    /// self-collision on, not adjacent) whose tight boxes, grown by ε_c, overlap.
    pub fn sample(&mut self, world: &World) {
        let bodies: Vec<_> = world.bodies().collect();
        let eps = world.collision_epsilon();
        let boxes: Vec<Aabb> = bodies
            .iter()
            .map(|(_, b)| b.shape.aabb(&b.pose).expanded(eps))
            .collect();
        self.report.samples += 1;
        for (i, j) in close_pairs(&boxes) {
            let ((ha, a), (hb, b)) = (bodies[i as usize], bodies[j as usize]);
            let never =
                matches!((a.link, b.link), (Some(x), Some(y)) if !world.links_collide(x, y));
            if !(a.takes_impulses() || b.takes_impulses()) || never {
                continue;
            }
            self.report.pairs_measured += 1;
            let cache = self.caches.entry((ha, hb)).or_default();
            let c = shape::closest(&a.shape, &a.pose, &b.shape, &b.pose, cache);
            if !c.closest.penetrating {
                self.report.min_distance = self.report.min_distance.min(c.closest.distance);
                continue;
            }
            let d = depth::shape_penetration(&a.shape, &a.pose, &b.shape, &b.pose)
                .map_or(0.0, |(p, _)| p.depth);
            self.report.min_distance = 0.0;
            if d > self.report.max_depth || self.report.worst.is_none() {
                self.report.max_depth = self.report.max_depth.max(d);
                self.report.worst = Some((world.time(), a.name.clone(), b.name.clone()));
            }
        }
    }
}

/// Index pairs `(i, j)`, `i < j`, of the boxes that overlap (touching counts), by sorting
/// on the lower x bound and sweeping: O(n log n + pairs in x).
#[must_use]
pub(crate) fn close_pairs(boxes: &[Aabb]) -> Vec<(u32, u32)> {
    let mut order: Vec<u32> = (0..boxes.len() as u32).collect();
    order.sort_by(|&a, &b| {
        boxes[a as usize]
            .min
            .x
            .total_cmp(&boxes[b as usize].min.x)
            .then(a.cmp(&b))
    });
    let mut out = Vec::new();
    for (k, &i) in order.iter().enumerate() {
        let bi = &boxes[i as usize];
        for &j in &order[k + 1..] {
            let bj = &boxes[j as usize];
            if bj.min.x > bi.max.x {
                break;
            }
            if bi.overlaps(bj) {
                out.push((i.min(j), i.max(j)));
            }
        }
    }
    out.sort_unstable();
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;
    use rand::rngs::Xoshiro256PlusPlus;
    use rand::{RngExt, SeedableRng};

    /// The sweep finds exactly the overlapping pairs that all-pairs testing finds.
    #[test]
    fn sweep_equals_brute_force() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(3);
        for n in [0, 1, 2, 50, 300] {
            let boxes: Vec<Aabb> = (0..n)
                .map(|_| {
                    let c = DVec3::new(
                        rng.random_range(0.0..10.0),
                        rng.random_range(0.0..10.0),
                        rng.random_range(0.0..10.0),
                    );
                    let h = DVec3::splat(rng.random_range(0.01..1.0));
                    Aabb::new(c - h, c + h)
                })
                .collect();
            let mut brute = Vec::new();
            for i in 0..n {
                for j in i + 1..n {
                    if boxes[i].overlaps(&boxes[j]) {
                        brute.push((i as u32, j as u32));
                    }
                }
            }
            assert_eq!(close_pairs(&boxes), brute, "n = {n}");
        }
    }
}
