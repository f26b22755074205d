//! The held pairs of the switching model and the islands they make, indexed so that the work
//! of an island step is in proportion to the islands it steps.
//!
//! [`HeldSet`] keeps each body's held partners beside the pairs, so "is this body held?" and
//! "which pairs hold it?" take no scan of every held pair; [`DueTimes`] keeps the islands'
//! clocks in order, so the next island step is the first entry; [`World::islands_of`] finds
//! the islands of a few bodies by walking their held pairs, instead of joining every held pair
//! of the world (a pile of 1000 boxes holds thousands, and its islands step at different
//! instants: a union–find over all of them at each instant was a tenth of its run).

use std::collections::BTreeSet;
use std::ops::Index;

use rustc_hash::FxHashMap;

use super::World;
use super::sync::order_key;

/// The held pairs (slot indices, `a < b`) with a value each, and every body's partners.
#[derive(Clone, Debug)]
pub(super) struct HeldSet<V> {
    pairs: FxHashMap<(u32, u32), V>,
    /// Each body's partners in held pairs, ascending; no empty lists.
    partners: FxHashMap<u32, Vec<u32>>,
}

impl<V> Default for HeldSet<V> {
    fn default() -> Self {
        Self {
            pairs: FxHashMap::default(),
            partners: FxHashMap::default(),
        }
    }
}

impl<V: Default> HeldSet<V> {
    /// Whether the pair is held.
    pub(super) fn contains_key(&self, pair: &(u32, u32)) -> bool {
        self.pairs.contains_key(pair)
    }

    /// The pair's value, if it is held.
    pub(super) fn get(&self, pair: &(u32, u32)) -> Option<&V> {
        self.pairs.get(pair)
    }

    /// The pair's value, mutably, if it is held.
    pub(super) fn get_mut(&mut self, pair: &(u32, u32)) -> Option<&mut V> {
        self.pairs.get_mut(pair)
    }

    /// Holds the pair (with a default value if it was not held); its value.
    pub(super) fn hold(&mut self, pair: (u32, u32)) -> &mut V {
        if !self.pairs.contains_key(&pair) {
            for (x, y) in [(pair.0, pair.1), (pair.1, pair.0)] {
                let list = self.partners.entry(x).or_default();
                if let Err(k) = list.binary_search(&y) {
                    list.insert(k, y);
                }
            }
        }
        self.pairs.entry(pair).or_default()
    }

    /// Lets the pair go; its value, if it was held.
    pub(super) fn remove(&mut self, pair: &(u32, u32)) -> Option<V> {
        let value = self.pairs.remove(pair)?;
        for (x, y) in [(pair.0, pair.1), (pair.1, pair.0)] {
            if let Some(list) = self.partners.get_mut(&x) {
                if let Ok(k) = list.binary_search(&y) {
                    list.remove(k);
                }
                if list.is_empty() {
                    self.partners.remove(&x);
                }
            }
        }
        Some(value)
    }

    /// Every held pair (in no particular order).
    pub(super) fn keys(&self) -> impl Iterator<Item = &(u32, u32)> {
        self.pairs.keys()
    }

    /// Body `i`'s partners in held pairs, ascending.
    pub(super) fn partners(&self, i: u32) -> &[u32] {
        self.partners.get(&i).map_or(&[], Vec::as_slice)
    }

    /// Body `i`'s held pairs, ascending by partner.
    pub(super) fn pairs_of(&self, i: u32) -> Vec<(u32, u32)> {
        self.partners(i)
            .iter()
            .map(|&j| (i.min(j), i.max(j)))
            .collect()
    }

    /// Whether body `i` is in a held pair.
    pub(super) fn holds_body(&self, i: u32) -> bool {
        self.partners.contains_key(&i)
    }
}

impl<V> Index<&(u32, u32)> for HeldSet<V> {
    type Output = V;

    fn index(&self, pair: &(u32, u32)) -> &V {
        &self.pairs[pair]
    }
}

/// When each island body is next due (the islands' clocks), in order.
#[derive(Clone, Debug, Default)]
pub(super) struct DueTimes {
    at: FxHashMap<u32, f64>,
    order: BTreeSet<(u64, u32)>,
}

impl DueTimes {
    /// Body `i` is due at `t` (replacing when it was due before).
    pub(super) fn insert(&mut self, i: u32, t: f64) {
        if let Some(old) = self.at.insert(i, t) {
            self.order.remove(&(order_key(old), i));
        }
        self.order.insert((order_key(t), i));
    }

    /// Body `i` is due no more.
    pub(super) fn remove(&mut self, i: u32) {
        if let Some(old) = self.at.remove(&i) {
            self.order.remove(&(order_key(old), i));
        }
    }

    /// When body `i` is due, if it is.
    pub(super) fn get(&self, i: u32) -> Option<f64> {
        self.at.get(&i).copied()
    }

    /// The earliest time any body is due (∞ with none).
    pub(super) fn earliest(&self) -> f64 {
        self.order
            .first()
            .map_or(f64::INFINITY, |&(_, i)| self.at[&i])
    }

    /// The bodies due at or before `t`, earliest first (ties by body).
    pub(super) fn due_by(&self, t: f64) -> Vec<u32> {
        let end = order_key(t);
        self.order
            .iter()
            .take_while(|(k, _)| *k <= end)
            .map(|&(_, i)| i)
            .collect()
    }
}

/// One island: its dynamic bodies and multibody links, and its held pairs (both sorted).
pub(super) struct Island {
    pub(super) bodies: Vec<u32>,
    pub(super) pairs: Vec<(u32, u32)>,
}

impl World {
    /// The islands holding any of `seeds`: the bodies and links joined to them by held pairs
    /// (fixed and scripted bodies do not join islands; the held links of one multibody are in
    /// one island), ordered by their smallest body, each with its bodies and pairs sorted.
    /// A seed in no held pair is in no island.
    pub(super) fn islands_of(&self, seeds: &[u32]) -> Vec<Island> {
        let held = &self.islands.held;
        let mut seen: rustc_hash::FxHashSet<u32> = Default::default();
        let mut islands = Vec::new();
        let mut sorted: Vec<u32> = seeds.to_vec();
        sorted.sort_unstable();
        sorted.dedup();
        for &seed in &sorted {
            if seen.contains(&seed) || !held.holds_body(seed) || !self.b(seed).takes_impulses() {
                continue;
            }
            seen.insert(seed);
            let (mut bodies, mut pairs) = (vec![seed], Vec::new());
            let mut k = 0;
            while k < bodies.len() {
                let x = bodies[k];
                k += 1;
                for &y in held.partners(x) {
                    pairs.push((x.min(y), x.max(y)));
                    if self.b(y).takes_impulses() && seen.insert(y) {
                        bodies.push(y);
                    }
                }
                // A multibody's held links move together: one island.
                if let Some((m, _)) = self.b(x).link {
                    for (_, l) in &self.multibodies[m as usize].links {
                        if held.holds_body(*l) && seen.insert(*l) {
                            bodies.push(*l);
                        }
                    }
                }
            }
            bodies.sort_unstable();
            pairs.sort_unstable();
            pairs.dedup();
            islands.push(Island { bodies, pairs });
        }
        islands.sort_by_key(|island| island.bodies[0]);
        islands
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn partners_follow_holds_and_releases() {
        let mut h: HeldSet<u8> = HeldSet::default();
        *h.hold((1, 4)) = 7;
        h.hold((1, 2));
        h.hold((2, 4));
        assert_eq!(h.partners(1), [2, 4]);
        assert_eq!(h.partners(4), [1, 2]);
        assert_eq!(h[&(1, 4)], 7);
        assert_eq!(*h.hold((1, 4)), 7, "holding again keeps the value");
        assert_eq!(h.remove(&(1, 2)), Some(0));
        assert_eq!(h.partners(1), [4]);
        assert_eq!(h.pairs_of(4), [(1, 4), (2, 4)]);
        h.remove(&(1, 4));
        assert!(!h.holds_body(1));
        assert!(h.holds_body(2));
        assert_eq!(h.remove(&(1, 4)), None);
    }

    #[test]
    fn due_times_come_out_in_time_order() {
        let mut d = DueTimes::default();
        d.insert(3, 0.5);
        d.insert(1, 0.25);
        d.insert(2, -1.0);
        d.insert(1, 0.75);
        assert_eq!(d.earliest(), -1.0);
        assert_eq!(d.due_by(0.5), [2, 3]);
        d.remove(2);
        assert_eq!(d.earliest(), 0.5);
        assert_eq!(d.due_by(1.0), [3, 1]);
        assert_eq!(d.get(1), Some(0.75));
        d.remove(3);
        d.remove(1);
        assert_eq!(d.earliest(), f64::INFINITY);
    }
}
