//! The collision heap (thesis §2.3.1, §2.4.3): body pairs ordered by a lower bound on their
//! time of impact, with key changes, a per-body index, and the hysteresis rule for leaving.
//!
//! Each element is a body pair `(a, b)`, `a < b` (body indices, `u32`), keyed by an **absolute**
//! TOI lower bound t (s, simulation time): no collision of that pair can happen before t. The
//! top is the pair with the smallest key; ties are broken by the pair (lexicographic), so the
//! order of checks never depends on insertion history. Keys may be `+∞` (the pair cannot meet on
//! current trajectories) or `−∞`; NaN is refused; `−0.0` is stored as `+0.0`.
//!
//! # Protocol (the `advance` loop of §2.4.3)
//!
//! 1. When the broad phase's close counter of a pair goes 0 → 1 and the pair is not
//!    [`contains`](CollisionHeap::contains)ed, compute its TOI and
//!    [`insert`](CollisionHeap::insert) it — *before* integrating, since it may shorten the step.
//! 2. [`peek`](CollisionHeap::peek) the top `(p, t)`; integrate every body to `t`.
//! 3. Check `p` (closest features). If it collides, apply the impulses, then re-key every
//!    *other* pair of both bodies ([`pairs_of`](CollisionHeap::pairs_of) +
//!    [`set_toi`](CollisionHeap::set_toi); their new keys are ≥ t).
//! 4. Compute `p`'s new TOI and call
//!    [`settle_after_check(p, counter(p) > 0, new_toi)`](CollisionHeap::settle_after_check):
//!    the pair is re-keyed if the broad phase still calls it close, and leaves the heap
//!    otherwise. This is the **only** place a pair should leave during simulation
//!    (hysteresis: a pair whose boxes flicker in and out of closeness near a tile boundary,
//!    Figure 2.15, is not removed and re-inserted each time). `settle_after_check` refuses a pair
//!    that is not at the top (its key above the minimum), which catches protocol slips.
//!
//! [`remove`](CollisionHeap::remove) and [`pop`](CollisionHeap::pop) exist for bodies that are
//! deleted or disabled.
//!
//! # Layout
//!
//! An indexed binary min-heap: the heap array holds `(toi, pair)`; a hash map (fixed-seed
//! `FxHashMap`, never iterated) gives each pair's array index so keys can change in
//! O(log n); a second map gives, per body, the sorted list of its partners in the heap. Every
//! query answer and every iteration order is a function of the sequence of operations alone.

use core::cmp::Ordering;

use rustc_hash::FxHashMap;

/// A body pair `(a, b)` with `a < b` (body indices). Operations accept either order and
/// normalise.
pub type Pair = (u32, u32);

/// Why a heap operation was refused; the heap is unchanged.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum HeapError {
    /// Both members of the pair are the same body.
    #[error("pair ({body}, {body}) names the same body twice")]
    SameBody {
        /// The body.
        body: u32,
    },
    /// The TOI given for the pair is NaN.
    #[error("TOI of pair {pair:?} is NaN")]
    NanToi {
        /// The pair (normalised).
        pair: Pair,
    },
    /// [`CollisionHeap::insert`] of a pair already in the heap.
    #[error("pair {pair:?} is already in the collision heap")]
    AlreadyPresent {
        /// The pair (normalised).
        pair: Pair,
    },
    /// The pair is not in the heap.
    #[error("pair {pair:?} is not in the collision heap")]
    NotPresent {
        /// The pair (normalised).
        pair: Pair,
    },
    /// [`CollisionHeap::settle_after_check`] on a pair that has not reached the top.
    #[error("pair {pair:?} (TOI {toi}) is not at the top of the heap (top TOI {top})")]
    NotAtTop {
        /// The pair (normalised).
        pair: Pair,
        /// Its key (s).
        toi: f64,
        /// The smallest key in the heap (s).
        top: f64,
    },
}

/// What [`CollisionHeap::settle_after_check`] did with the checked pair.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Settled {
    /// Still close: kept, with its new TOI.
    Rekeyed,
    /// No longer close: removed from the heap.
    Removed,
}

/// Operation counters, for the caller's statistics (deterministic work measures, not timings).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct HeapStats {
    /// Successful insertions.
    pub inserts: u64,
    /// Pairs that left the heap (`remove`, `pop`, `settle_after_check` → `Removed`).
    pub removals: u64,
    /// Key changes (`set_toi`, `settle_after_check` → `Rekeyed`).
    pub key_changes: u64,
    /// Levels an element moved up or down while restoring heap order.
    pub sift_steps: u64,
}

#[derive(Clone, Copy, Debug)]
struct Entry {
    /// Absolute TOI lower bound (s); never NaN, never −0.0.
    toi: f64,
    /// The pair, `a < b`.
    pair: Pair,
}

/// Heap order: by TOI, then by pair.
fn precedes(x: &Entry, y: &Entry) -> bool {
    x.toi.total_cmp(&y.toi).then(x.pair.cmp(&y.pair)) == Ordering::Less
}

fn normalise((a, b): Pair) -> Result<Pair, HeapError> {
    match a.cmp(&b) {
        Ordering::Less => Ok((a, b)),
        Ordering::Greater => Ok((b, a)),
        Ordering::Equal => Err(HeapError::SameBody { body: a }),
    }
}

fn checked_toi(pair: Pair, toi: f64) -> Result<f64, HeapError> {
    if toi.is_nan() {
        Err(HeapError::NanToi { pair })
    } else {
        // −0.0 + 0.0 = +0.0, so both zeros tie and break by pair.
        Ok(toi + 0.0)
    }
}

/// The collision heap: an indexed binary min-heap of body pairs keyed by absolute TOI lower
/// bounds (s). See the module documentation for the protocol.
#[derive(Clone, Debug, Default)]
pub struct CollisionHeap {
    /// Binary heap in array order (len n): parent of i is (i − 1)/2.
    entries: Vec<Entry>,
    /// Pair → index in `entries` (n items).
    position: FxHashMap<Pair, u32>,
    /// Body → its partners in the heap, ascending (no empty lists kept).
    partners: FxHashMap<u32, Vec<u32>>,
    stats: HeapStats,
}

impl CollisionHeap {
    /// An empty heap.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// An empty heap with room for `pairs` pairs.
    #[must_use]
    pub fn with_capacity(pairs: usize) -> Self {
        Self {
            entries: Vec::with_capacity(pairs),
            position: FxHashMap::with_capacity_and_hasher(pairs, Default::default()),
            ..Self::default()
        }
    }

    /// Number of pairs in the heap.
    #[must_use]
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// `true` when the heap holds no pair.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// `true` when the pair (either order) is in the heap.
    #[must_use]
    pub fn contains(&self, pair: Pair) -> bool {
        self.toi(pair).is_some()
    }

    /// The pair's key (absolute TOI lower bound, s), or `None` if it is not in the heap.
    #[must_use]
    pub fn toi(&self, pair: Pair) -> Option<f64> {
        let pair = normalise(pair).ok()?;
        self.position
            .get(&pair)
            .map(|&i| self.entries[i as usize].toi)
    }

    /// The top: the pair with the smallest key (ties: smallest pair), without removing it.
    #[must_use]
    pub fn peek(&self) -> Option<(Pair, f64)> {
        self.entries.first().map(|e| (e.pair, e.toi))
    }

    /// Every pair whose key is below `t`, with its key, in heap order (key, then pair). Walks
    /// only the part of the heap above `t`: O(k) for k pairs found.
    #[must_use]
    pub fn due_before(&self, t: f64) -> Vec<(Pair, f64)> {
        let mut found = Vec::new();
        let mut stack = Vec::new();
        if self.entries.first().is_some_and(|e| e.toi < t) {
            stack.push(0usize);
        }
        while let Some(i) = stack.pop() {
            let e = self.entries[i];
            found.push(e);
            for child in [2 * i + 1, 2 * i + 2] {
                if self.entries.get(child).is_some_and(|c| c.toi < t) {
                    stack.push(child);
                }
            }
        }
        found.sort_by(|x, y| {
            if precedes(x, y) {
                Ordering::Less
            } else {
                Ordering::Greater
            }
        });
        found.into_iter().map(|e| (e.pair, e.toi)).collect()
    }

    /// Every pair in the heap involving `body`, in ascending order of the partner's index.
    pub fn pairs_of(&self, body: u32) -> impl Iterator<Item = Pair> + '_ {
        self.partners
            .get(&body)
            .map_or(&[][..], Vec::as_slice)
            .iter()
            .map(move |&other| {
                if body < other {
                    (body, other)
                } else {
                    (other, body)
                }
            })
    }

    /// The operation counters since creation or the last [`CollisionHeap::reset_stats`].
    #[must_use]
    pub fn stats(&self) -> HeapStats {
        self.stats
    }

    /// Sets every operation counter to zero.
    pub fn reset_stats(&mut self) {
        self.stats = HeapStats::default();
    }

    /// Removes every pair (the counters are kept).
    pub fn clear(&mut self) {
        self.entries.clear();
        self.position.clear();
        self.partners.clear();
    }

    /// Adds a pair (either order) with key `toi` (absolute, s).
    ///
    /// # Errors
    /// [`HeapError::SameBody`], [`HeapError::NanToi`], or [`HeapError::AlreadyPresent`] (use
    /// [`CollisionHeap::set_toi`] to change a key).
    pub fn insert(&mut self, pair: Pair, toi: f64) -> Result<(), HeapError> {
        let pair = normalise(pair)?;
        let toi = checked_toi(pair, toi)?;
        if self.position.contains_key(&pair) {
            return Err(HeapError::AlreadyPresent { pair });
        }
        let i = self.entries.len();
        self.entries.push(Entry { toi, pair });
        self.position.insert(pair, i as u32);
        self.link(pair.0, pair.1);
        self.link(pair.1, pair.0);
        self.sift_up(i);
        self.stats.inserts += 1;
        Ok(())
    }

    /// Removes a pair (either order); returns its key, or `None` if it was not in the heap
    /// (including a pair naming one body twice).
    pub fn remove(&mut self, pair: Pair) -> Option<f64> {
        let pair = normalise(pair).ok()?;
        let i = *self.position.get(&pair)? as usize;
        Some(self.remove_at(i).toi)
    }

    /// Removes and returns the top pair and its key.
    pub fn pop(&mut self) -> Option<(Pair, f64)> {
        if self.entries.is_empty() {
            return None;
        }
        let e = self.remove_at(0);
        Some((e.pair, e.toi))
    }

    /// Changes a pair's key (up or down); returns the old key.
    ///
    /// # Errors
    /// [`HeapError::SameBody`], [`HeapError::NanToi`], or [`HeapError::NotPresent`].
    pub fn set_toi(&mut self, pair: Pair, toi: f64) -> Result<f64, HeapError> {
        let pair = normalise(pair)?;
        let toi = checked_toi(pair, toi)?;
        let i = *self
            .position
            .get(&pair)
            .ok_or(HeapError::NotPresent { pair })? as usize;
        let old = self.entries[i].toi;
        self.entries[i].toi = toi;
        self.restore(i);
        self.stats.key_changes += 1;
        Ok(old)
    }

    /// The hysteresis rule (§2.4.3), called once per check of the top pair — step 4 of the
    /// protocol in the module documentation: after the caller has integrated to the pair's key,
    /// checked it, applied any collision impulses and re-keyed the bodies' *other* pairs.
    ///
    /// `still_close` is whether the broad phase's close counter of the pair is nonzero now;
    /// `new_toi` (absolute, s) is the pair's freshly computed TOI, used only when `still_close`.
    /// A still-close pair is re-keyed ([`Settled::Rekeyed`]); otherwise it leaves the heap
    /// ([`Settled::Removed`]).
    ///
    /// # Errors
    /// [`HeapError::SameBody`]; [`HeapError::NotPresent`]; [`HeapError::NotAtTop`] if the pair's
    /// key is above the smallest key (a pair tied with the top counts as at the top);
    /// [`HeapError::NanToi`] if `still_close` and `new_toi` is NaN. The heap is then unchanged.
    pub fn settle_after_check(
        &mut self,
        pair: Pair,
        still_close: bool,
        new_toi: f64,
    ) -> Result<Settled, HeapError> {
        let pair = normalise(pair)?;
        let i = *self
            .position
            .get(&pair)
            .ok_or(HeapError::NotPresent { pair })? as usize;
        let (toi, top) = (self.entries[i].toi, self.entries[0].toi);
        if toi.total_cmp(&top) != Ordering::Equal {
            return Err(HeapError::NotAtTop { pair, toi, top });
        }
        if still_close {
            self.set_toi(pair, new_toi)?;
            Ok(Settled::Rekeyed)
        } else {
            self.remove_at(i);
            Ok(Settled::Removed)
        }
    }

    fn link(&mut self, body: u32, other: u32) {
        let list = self.partners.entry(body).or_default();
        if let Err(k) = list.binary_search(&other) {
            list.insert(k, other);
        }
    }

    fn unlink(&mut self, body: u32, other: u32) {
        if let Some(list) = self.partners.get_mut(&body) {
            if let Ok(k) = list.binary_search(&other) {
                list.remove(k);
            }
            if list.is_empty() {
                self.partners.remove(&body);
            }
        }
    }

    fn remove_at(&mut self, i: usize) -> Entry {
        let e = self.entries.swap_remove(i);
        self.position.remove(&e.pair);
        if i < self.entries.len() {
            self.position.insert(self.entries[i].pair, i as u32);
            self.restore(i);
        }
        self.unlink(e.pair.0, e.pair.1);
        self.unlink(e.pair.1, e.pair.0);
        self.stats.removals += 1;
        e
    }

    /// Re-establishes heap order around index `i` after its key changed.
    fn restore(&mut self, i: usize) {
        let j = self.sift_up(i);
        if j == i {
            self.sift_down(i);
        }
    }

    /// Moves `entries[i]` up while it precedes its parent; returns its final index.
    fn sift_up(&mut self, mut i: usize) -> usize {
        let e = self.entries[i];
        while i > 0 {
            let parent = (i - 1) / 2;
            if !precedes(&e, &self.entries[parent]) {
                break;
            }
            self.place(i, self.entries[parent]);
            i = parent;
            self.stats.sift_steps += 1;
        }
        self.place(i, e);
        i
    }

    /// Moves `entries[i]` down while a child precedes it.
    fn sift_down(&mut self, mut i: usize) {
        let e = self.entries[i];
        let n = self.entries.len();
        loop {
            let left = 2 * i + 1;
            if left >= n {
                break;
            }
            let right = left + 1;
            let child = if right < n && precedes(&self.entries[right], &self.entries[left]) {
                right
            } else {
                left
            };
            if !precedes(&self.entries[child], &e) {
                break;
            }
            self.place(i, self.entries[child]);
            i = child;
            self.stats.sift_steps += 1;
        }
        self.place(i, e);
    }

    fn place(&mut self, i: usize, e: Entry) {
        self.entries[i] = e;
        if let Some(p) = self.position.get_mut(&e.pair) {
            *p = i as u32;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::{BTreeMap, BTreeSet};

    use rand::rngs::Xoshiro256PlusPlus;
    use rand::{RngExt, SeedableRng};

    /// Random operations in the model-based test.
    const OPERATIONS: usize = 100_000;
    /// Bodies 0..BODIES take part (up to BODIES·(BODIES−1)/2 = 435 pairs), plus a few huge ids.
    const BODIES: u32 = 30;
    /// Every this many operations the whole heap is compared with the model.
    const FULL_CHECK_EVERY: usize = 1000;

    /// A key with the heap's total order (TOIs are never NaN).
    #[derive(Clone, Copy, Debug, PartialEq)]
    struct Key(f64);
    impl Eq for Key {}
    impl PartialOrd for Key {
        fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
            Some(self.cmp(other))
        }
    }
    impl Ord for Key {
        fn cmp(&self, other: &Self) -> Ordering {
            self.0.total_cmp(&other.0)
        }
    }

    /// The reference: a map of keys and an ordered set of (key, pair).
    #[derive(Default)]
    struct Model {
        toi: BTreeMap<Pair, f64>,
        order: BTreeSet<(Key, Pair)>,
    }

    impl Model {
        fn insert(&mut self, p: Pair, t: f64) {
            self.toi.insert(p, t);
            self.order.insert((Key(t), p));
        }
        fn remove(&mut self, p: Pair) -> Option<f64> {
            let t = self.toi.remove(&p)?;
            self.order.remove(&(Key(t), p));
            Some(t)
        }
        fn top(&self) -> Option<(Pair, f64)> {
            self.order.first().map(|&(k, p)| (p, k.0))
        }
        fn pairs_of(&self, body: u32) -> Vec<Pair> {
            let mut v: Vec<Pair> = self
                .toi
                .keys()
                .copied()
                .filter(|p| p.0 == body || p.1 == body)
                .collect();
            v.sort_by_key(|p| if p.0 == body { p.1 } else { p.0 });
            v
        }
    }

    /// Checks heap order, the index maps and the per-body lists.
    fn check_invariants(h: &CollisionHeap) {
        for i in 1..h.entries.len() {
            assert!(
                !precedes(&h.entries[i], &h.entries[(i - 1) / 2]),
                "heap order broken at {i}"
            );
        }
        assert_eq!(h.position.len(), h.entries.len());
        for (i, e) in h.entries.iter().enumerate() {
            assert_eq!(h.position[&e.pair] as usize, i);
            assert!(e.pair.0 < e.pair.1 && !e.toi.is_nan());
        }
        let links: usize = h.partners.values().map(Vec::len).sum();
        assert_eq!(links, 2 * h.entries.len());
        for list in h.partners.values() {
            assert!(!list.is_empty() && list.windows(2).all(|w| w[0] < w[1]));
        }
    }

    fn random_body(rng: &mut Xoshiro256PlusPlus) -> u32 {
        if rng.random_range(0..100) == 0 {
            u32::MAX - rng.random_range(0..3)
        } else {
            rng.random_range(0..BODIES)
        }
    }

    /// Keys with many ties, both zeros, infinities and plain random values.
    fn random_toi(rng: &mut Xoshiro256PlusPlus) -> f64 {
        match rng.random_range(0..20) {
            0..=7 => f64::from(rng.random_range(0..12u32)),
            8 => f64::INFINITY,
            9 => -0.0,
            10 => f64::NEG_INFINITY,
            _ => rng.random_range(-5.0..20.0),
        }
    }

    #[test]
    fn random_operations_agree_with_an_ordered_map() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(2718);
        let mut heap = CollisionHeap::new();
        let mut model = Model::default();
        let mut expect = HeapStats::default();
        let mut max_len = 0;
        for step in 0..OPERATIONS {
            let (x, y) = (random_body(&mut rng), random_body(&mut rng));
            let norm = (x.min(y), x.max(y));
            let t = random_toi(&mut rng);
            let t_norm = t + 0.0;
            match rng.random_range(0..100) {
                // Insert (either order), sometimes with a NaN key.
                0..=39 => {
                    let t = if rng.random_range(0..50) == 0 {
                        f64::NAN
                    } else {
                        t
                    };
                    let got = heap.insert((x, y), t);
                    if x == y {
                        assert_eq!(got, Err(HeapError::SameBody { body: x }));
                    } else if t.is_nan() {
                        assert_eq!(got, Err(HeapError::NanToi { pair: norm }));
                    } else if model.toi.contains_key(&norm) {
                        assert_eq!(got, Err(HeapError::AlreadyPresent { pair: norm }));
                    } else {
                        assert_eq!(got, Ok(()));
                        model.insert(norm, t_norm);
                        expect.inserts += 1;
                    }
                }
                40..=54 => {
                    let got = heap.remove((y, x));
                    let want = if x == y { None } else { model.remove(norm) };
                    assert_eq!(got.map(f64::to_bits), want.map(f64::to_bits));
                    expect.removals += u64::from(want.is_some());
                }
                // Re-key an existing pair (picked from the model) or a random one.
                55..=74 => {
                    let pair = if !model.toi.is_empty() && rng.random::<bool>() {
                        let k = rng.random_range(0..model.toi.len());
                        *model.toi.keys().nth(k).unwrap()
                    } else {
                        (x, y)
                    };
                    let got = heap.set_toi(pair, t);
                    if pair.0 == pair.1 {
                        assert!(matches!(got, Err(HeapError::SameBody { .. })));
                    } else {
                        let p = (pair.0.min(pair.1), pair.0.max(pair.1));
                        match model.remove(p) {
                            Some(old) => {
                                assert_eq!(got, Ok(old));
                                model.insert(p, t_norm);
                                expect.key_changes += 1;
                            }
                            None => assert_eq!(got, Err(HeapError::NotPresent { pair: p })),
                        }
                    }
                }
                75..=84 => {
                    let got = heap.pop();
                    let want = model.top();
                    assert_eq!(got, want);
                    if let Some((p, _)) = want {
                        model.remove(p);
                        expect.removals += 1;
                    }
                }
                // The hysteresis step on the top pair, or a refused call on another pair.
                85..=94 => {
                    let close = rng.random::<bool>();
                    if let Some((top, top_t)) = model.top() {
                        let other = model.toi.get(&norm).copied();
                        if x != y && other.is_some_and(|o| o.total_cmp(&top_t) != Ordering::Equal) {
                            let got = heap.settle_after_check(norm, close, t);
                            assert!(matches!(got, Err(HeapError::NotAtTop { .. })));
                        }
                        let got = heap.settle_after_check(top, close, t).unwrap();
                        model.remove(top);
                        if close {
                            assert_eq!(got, Settled::Rekeyed);
                            model.insert(top, t_norm);
                            expect.key_changes += 1;
                        } else {
                            assert_eq!(got, Settled::Removed);
                            expect.removals += 1;
                        }
                    } else {
                        assert!(heap.settle_after_check((1, 2), close, t).is_err());
                    }
                }
                _ => {
                    let got = heap.set_toi((x, y), f64::NAN);
                    assert!(got.is_err());
                }
            }
            // After every operation.
            check_invariants(&heap);
            assert_eq!(heap.len(), model.toi.len());
            assert_eq!(heap.is_empty(), model.toi.is_empty());
            assert_eq!(heap.peek(), model.top());
            if step % 17 == 0 {
                // The pairs below a bound, in heap order, as the ordered map lists them.
                let bound = random_toi(&mut rng);
                let want: Vec<(Pair, u64)> = model
                    .order
                    .iter()
                    .take_while(|(k, _)| k.0 < bound)
                    .map(|(k, p)| (*p, k.0.to_bits()))
                    .collect();
                let got: Vec<(Pair, u64)> = heap
                    .due_before(bound)
                    .into_iter()
                    .map(|(p, t)| (p, t.to_bits()))
                    .collect();
                assert_eq!(got, want, "step {step}: pairs below {bound}");
            }
            assert_eq!(
                heap.toi((y, x)).map(f64::to_bits),
                model.toi.get(&norm).map(|t| t.to_bits())
            );
            assert_eq!(
                heap.contains((x, y)),
                x != y && model.toi.contains_key(&norm)
            );
            for body in [x, y, random_body(&mut rng)] {
                assert_eq!(
                    heap.pairs_of(body).collect::<Vec<_>>(),
                    model.pairs_of(body)
                );
            }
            max_len = max_len.max(heap.len());
            if step % FULL_CHECK_EVERY == 0 {
                for (&p, &t) in &model.toi {
                    assert_eq!(heap.toi(p).map(f64::to_bits), Some(t.to_bits()));
                }
                for body in 0..BODIES {
                    assert_eq!(
                        heap.pairs_of(body).collect::<Vec<_>>(),
                        model.pairs_of(body)
                    );
                }
            }
        }
        let stats = heap.stats();
        assert_eq!(
            (stats.inserts, stats.removals, stats.key_changes),
            (expect.inserts, expect.removals, expect.key_changes)
        );
        assert!(
            stats.sift_steps > 0 && max_len > 100,
            "{stats:?}, max len {max_len}"
        );
        // Drain: pops come out in the model's order.
        while let Some(top) = model.top() {
            assert_eq!(heap.pop(), Some(top));
            model.remove(top.0);
        }
        assert!(heap.is_empty() && heap.partners.is_empty());
        eprintln!("heap: {stats:?}, max len {max_len}");
    }

    #[test]
    fn ties_break_by_pair_and_zeros_are_equal() {
        let mut h = CollisionHeap::new();
        h.insert((5, 2), 1.0).unwrap();
        h.insert((1, 9), 1.0).unwrap();
        h.insert((3, 4), -0.0).unwrap();
        h.insert((0, 7), 0.0).unwrap();
        h.insert((0, 8), f64::INFINITY).unwrap();
        h.insert((0, 6), f64::INFINITY).unwrap();
        let order: Vec<Pair> = core::iter::from_fn(|| h.pop().map(|(p, _)| p)).collect();
        assert_eq!(order, [(0, 7), (3, 4), (1, 9), (2, 5), (0, 6), (0, 8)]);
    }

    #[test]
    fn errors_leave_the_heap_unchanged() {
        let mut h = CollisionHeap::new();
        h.insert((1, 2), 3.0).unwrap();
        h.insert((2, 3), 5.0).unwrap();
        let before = (h.peek(), h.len(), h.stats());
        assert_eq!(h.insert((4, 4), 1.0), Err(HeapError::SameBody { body: 4 }));
        assert_eq!(
            h.insert((2, 1), 1.0),
            Err(HeapError::AlreadyPresent { pair: (1, 2) })
        );
        assert_eq!(
            h.insert((7, 8), f64::NAN),
            Err(HeapError::NanToi { pair: (7, 8) })
        );
        assert_eq!(
            h.set_toi((7, 8), 1.0),
            Err(HeapError::NotPresent { pair: (7, 8) })
        );
        assert_eq!(
            h.set_toi((1, 2), f64::NAN),
            Err(HeapError::NanToi { pair: (1, 2) })
        );
        assert_eq!(
            h.settle_after_check((3, 2), true, 9.0),
            Err(HeapError::NotAtTop {
                pair: (2, 3),
                toi: 5.0,
                top: 3.0
            })
        );
        assert_eq!(
            h.settle_after_check((1, 2), true, f64::NAN),
            Err(HeapError::NanToi { pair: (1, 2) })
        );
        assert_eq!(
            h.settle_after_check((1, 9), false, 0.0),
            Err(HeapError::NotPresent { pair: (1, 9) })
        );
        assert_eq!(h.remove((4, 4)), None);
        assert_eq!((h.peek(), h.len(), h.stats()), before);
        assert_eq!(h.pairs_of(2).collect::<Vec<_>>(), [(1, 2), (2, 3)]);
        assert_eq!(h.pairs_of(99).count(), 0);
    }

    /// Figure 2.15: body 1 bounces on fixed body 2 near a tile boundary, so the pair's close
    /// counter flickers. Under hysteresis the pair leaves only when it reaches the top while not
    /// close; under "remove as soon as not close" it leaves and re-enters every flicker.
    #[test]
    fn hysteresis_keeps_a_flickering_pair() {
        const STEPS: usize = 200;
        let ball = (1, 2);
        let mut heap = CollisionHeap::new();
        // Other pairs keep the ball's pair off the top most of the time.
        for k in 0..20u32 {
            heap.insert((10 + k, 100), f64::from(k) * 0.1).unwrap();
        }
        let mut naive_inserts = 0;
        let mut naive_present = false;
        let mut now = 0.0;
        for step in 0..STEPS {
            let close = step % 3 != 2; // boxes flicker: close, close, not close, ...
            // Broad-phase events: a 0 → 1 transition inserts if absent.
            if close && !heap.contains(ball) {
                heap.insert(ball, now + 0.35).unwrap();
            }
            if close && !naive_present {
                naive_inserts += 1;
                naive_present = true;
            }
            if !close {
                naive_present = false;
            }
            // Check the top pair and settle it; its next TOI lies a bit ahead.
            let (top, t) = heap.peek().unwrap();
            now = t;
            let still_close = top != ball || close;
            let settled = heap
                .settle_after_check(top, still_close, now + 0.35)
                .unwrap();
            if top == ball && !close {
                assert_eq!(settled, Settled::Removed);
            } else {
                assert_eq!(settled, Settled::Rekeyed);
                assert!(heap.contains(top));
            }
        }
        let ball_inserts = heap.stats().inserts - 20;
        assert!(
            ball_inserts >= 1 && ball_inserts * 5 < naive_inserts,
            "{ball_inserts} vs {naive_inserts}"
        );
        eprintln!(
            "hysteresis: {ball_inserts} inserts of the flickering pair vs {naive_inserts} \
             with immediate removal"
        );
        // A pair that is not close but not at the top stays in the heap.
        let mut h = CollisionHeap::new();
        h.insert((1, 2), 1.0).unwrap();
        h.insert((3, 4), 2.0).unwrap();
        assert!(h.settle_after_check((3, 4), false, 0.0).is_err());
        assert!(h.contains((3, 4)));
        // A pair tied with the top counts as at the top.
        h.set_toi((3, 4), 1.0).unwrap();
        assert_eq!(
            h.settle_after_check((4, 3), false, 0.0),
            Ok(Settled::Removed)
        );
        assert_eq!(
            h.settle_after_check((1, 2), true, 7.0),
            Ok(Settled::Rekeyed)
        );
        assert_eq!(h.peek(), Some(((1, 2), 7.0)));
    }
}
