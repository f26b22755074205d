//! The coherent hierarchical hash with close counters (thesis §2.4.2), the variant Impulse
//! uses.
//!
//! A box X's label is stored in every bucket that the standard variant would *check* when
//! storing X: every tile X overlaps at its own level res(X) and at every coarser level
//! (Figure 2.12). The close counter c(X, Y) is the number of buckets at level
//! min(res(X), res(Y)) holding both labels, and X, Y are close iff c(X, Y) > 0 — exactly
//! Definition 1, so the close set equals the standard variant's.
//!
//! The table keeps its state between rounds: [`CoherentHash::update`] touches only the buckets
//! of tiles the box entered or left, so a box that stays in the same tiles costs a few range
//! computations and no bucket work. Pairs whose counter went 0 → 1 are collected for
//! [`CoherentHash::take_new_close_pairs`], which the simulator calls after updating all boxes
//! and before integrating, to put the new pairs into its collision heap (§2.4.3). The price:
//! labels are also written at coarser levels, where pairs already separated at their own
//! level still share buckets, so Theorem 4's O(n + c) bound is not claimed for this variant
//! (nor by the thesis); Table 2.1 and this crate's benchmark show it is faster in practice.
//!
//! Design note — one label list per bucket, or two? Every label in a level-l bucket belongs to
//! a box with res ≥ l, so min(res X, res Y) = l iff X or Y has res = l. Option A: one list, and
//! every write scans it. Option B: each bucket keeps labels at their own level (`own`) apart
//! from labels of finer boxes (`inherited`); a write of an inherited label scans only `own`.
//! Chose B: coarse buckets collect the labels of all finer boxes beneath them, and with A each
//! fine box's write would scan all of them for nothing.

use crate::tiling::{CellKey, CellRange, pair_key, place, sorted_pairs, unpack_pair};
use crate::{BroadphaseError, Levels, Pair, WorkCounters};
use impulse_geom::Aabb;
use rustc_hash::FxHashMap;
use std::collections::hash_map::Entry as MapEntry;

/// The coherent hierarchical spatial hash of §2.4.2: boxes under `u32` ids, kept between
/// rounds, with incrementally maintained close counters (Definition 1).
///
/// Typical round: [`update`](Self::update) every moving box, then
/// [`take_new_close_pairs`](Self::take_new_close_pairs).
#[derive(Clone, Debug)]
pub struct CoherentHash {
    levels: Levels,
    /// Slot of each stored id.
    slot_of: FxHashMap<u32, u32>,
    /// Stored boxes, densely packed (removal moves the last slot into the hole), so a round
    /// that updates boxes in insertion order walks memory in order.
    slots: Vec<Slot>,
    /// Tile ranges of slot `i` at levels `0..=res` in
    /// `ranges[i * levels.count()..][..=res]`.
    ranges: Vec<CellRange>,
    table: Table,
    /// Reused for the new tile ranges during an update.
    scratch: Vec<CellRange>,
}

/// A stored box.
#[derive(Clone, Copy, Debug)]
struct Slot {
    id: u32,
    res: usize,
    aabb: Aabb,
}

/// Buckets, close counters and the record of counter transitions.
#[derive(Clone, Debug, Default)]
struct Table {
    buckets: FxHashMap<CellKey, Bucket>,
    /// c(X, Y) > 0 by pair key; pairs with c = 0 are absent.
    counters: FxHashMap<u64, u32>,
    /// Pairs whose counter went 0 → 1 or 1 → 0 since the last `take_new_close_pairs`, with
    /// whether they were close at that last call (known from their first transition since).
    changed: FxHashMap<u64, bool>,
    /// Set while a box is being removed for good: its pairs are then recorded as not close at
    /// the last take, so a later box under the same id gets its pairs reported as new.
    forget: bool,
    /// Emptied buckets kept for reuse, so steady-state updates do not allocate.
    spare: Vec<Bucket>,
    work: WorkCounters,
}

/// The labels in one bucket (level l, tile): split by whether the box's res is l.
#[derive(Clone, Debug, Default)]
struct Bucket {
    /// Labels of boxes with res = l.
    own: Vec<u32>,
    /// Labels of boxes with res > l (stored here because the coherent variant stores a label
    /// at every level it checks).
    inherited: Vec<u32>,
}

impl Bucket {
    fn is_empty(&self) -> bool {
        self.own.is_empty() && self.inherited.is_empty()
    }
}

fn increment(counters: &mut FxHashMap<u64, u32>, changed: &mut FxHashMap<u64, bool>, key: u64) {
    let c = counters.entry(key).or_insert(0);
    *c += 1;
    if *c == 1 {
        changed.entry(key).or_insert(false);
    }
}

fn decrement(
    counters: &mut FxHashMap<u64, u32>,
    changed: &mut FxHashMap<u64, bool>,
    key: u64,
    forget: bool,
) {
    if let Some(c) = counters.get_mut(&key) {
        *c -= 1;
        if *c == 0 {
            counters.remove(&key);
            if forget {
                changed.insert(key, false);
            } else {
                changed.entry(key).or_insert(true);
            }
        }
    } else {
        debug_assert!(false, "close counter of pair {key:#x} would go below zero");
    }
}

impl Table {
    /// Stores label `id` into bucket `key`; `own` = the bucket is at res(id). Increments
    /// c(id, Y) for every Y there with min(res id, res Y) = the bucket's level (§2.4.2).
    fn add(&mut self, key: CellKey, id: u32, own: bool) {
        let bucket = match self.buckets.entry(key) {
            MapEntry::Occupied(e) => e.into_mut(),
            MapEntry::Vacant(e) => e.insert(self.spare.pop().unwrap_or_default()),
        };
        let w = &mut self.work;
        w.bucket_visits += 1;
        w.label_writes += 1;
        let scanned: &[u32] = if own { &bucket.inherited } else { &[] };
        for &y in bucket.own.iter().chain(scanned) {
            w.label_reads += 1;
            w.counter_changes += 1;
            increment(&mut self.counters, &mut self.changed, pair_key(id, y));
        }
        if own {
            bucket.own.push(id);
        } else {
            bucket.inherited.push(id);
        }
    }

    /// Removes label `id` from bucket `key` and decrements the counters [`Table::add`]
    /// incremented.
    fn remove(&mut self, key: CellKey, id: u32, own: bool) {
        let Some(bucket) = self.buckets.get_mut(&key) else {
            debug_assert!(false, "label {id} missing: no bucket {key:?}");
            return;
        };
        let w = &mut self.work;
        w.bucket_visits += 1;
        let list = if own {
            &mut bucket.own
        } else {
            &mut bucket.inherited
        };
        let Some(pos) = list.iter().position(|&y| y == id) else {
            debug_assert!(false, "label {id} missing from bucket {key:?}");
            return;
        };
        w.label_reads += pos as u64 + 1;
        w.label_removals += 1;
        list.swap_remove(pos);
        let scanned: &[u32] = if own { &bucket.inherited } else { &[] };
        for &y in bucket.own.iter().chain(scanned) {
            w.label_reads += 1;
            w.counter_changes += 1;
            decrement(
                &mut self.counters,
                &mut self.changed,
                pair_key(id, y),
                self.forget,
            );
        }
        if bucket.is_empty() {
            if let Some(empty) = self.buckets.remove(&key) {
                self.spare.push(empty);
            }
        }
    }

    /// Stores `id` in every tile of `ranges` (levels 0..=res, res = the last level).
    fn add_all(&mut self, id: u32, ranges: &[CellRange]) {
        for (key, own) in tiles(ranges) {
            self.add(key, id, own);
        }
    }

    /// Removes `id` from every tile of `ranges` (levels 0..=res, res = the last level).
    fn remove_all(&mut self, id: u32, ranges: &[CellRange]) {
        for (key, own) in tiles(ranges) {
            self.remove(key, id, own);
        }
    }
}

/// Every tile of `ranges` (levels 0..=res, res = the last level), with whether it is at res
/// (the level whose tiles own the box).
fn tiles(ranges: &[CellRange]) -> impl Iterator<Item = (CellKey, bool)> + '_ {
    let res = ranges.len() - 1;
    ranges.iter().enumerate().flat_map(move |(level, range)| {
        range.cells().map(move |cell| {
            (
                CellKey {
                    level: level as u32,
                    cell,
                },
                level == res,
            )
        })
    })
}

impl CoherentHash {
    /// An empty table with the given levels.
    pub fn new(levels: Levels) -> Self {
        Self {
            levels,
            slot_of: FxHashMap::default(),
            slots: Vec::new(),
            ranges: Vec::new(),
            table: Table::default(),
            scratch: Vec::new(),
        }
    }

    /// The levels (tile sizes, α, β).
    pub fn levels(&self) -> &Levels {
        &self.levels
    }

    fn slot(&self, id: u32) -> Option<&Slot> {
        self.slot_of.get(&id).map(|&i| &self.slots[i as usize])
    }

    /// Adds box `id`: stores its label in every tile it overlaps at res(aabb) and every coarser
    /// level (eq. 2.7 per level), updating close counters.
    ///
    /// Errors: [`BroadphaseError::DuplicateId`] if `id` is present; a non-finite or inverted
    /// box, or one too large or too far out for the levels (see [`BroadphaseError`]). The
    /// table is unchanged on error.
    pub fn insert(&mut self, id: u32, aabb: Aabb) -> Result<(), BroadphaseError> {
        if self.slot_of.contains_key(&id) {
            return Err(BroadphaseError::DuplicateId(id));
        }
        let res = place(id, &aabb, &self.levels, &mut self.scratch)?;
        self.table.work.cell_ranges += self.scratch.len() as u64;
        self.table.add_all(id, &self.scratch);
        let stride = self.levels.count();
        self.slot_of.insert(id, self.slots.len() as u32);
        self.slots.push(Slot { id, res, aabb });
        self.ranges.extend_from_slice(&self.scratch);
        let filler = self.scratch[0];
        self.ranges.resize(self.slots.len() * stride, filler);
        Ok(())
    }

    /// Moves or resizes box `id` to `aabb`, incrementally: nothing happens for an unchanged
    /// box, and otherwise at each level only the tiles entered and left change (new ones are
    /// written before old ones are removed, so a pair that stays close never drops to zero on
    /// the way). If res changes, the box is removed
    /// with its old res and stored with the new one, so counters never drift.
    ///
    /// Errors: [`BroadphaseError::UnknownId`], or a bad box as for [`insert`](Self::insert);
    /// the table is unchanged on error.
    pub fn update(&mut self, id: u32, aabb: Aabb) -> Result<(), BroadphaseError> {
        let i = *self
            .slot_of
            .get(&id)
            .ok_or(BroadphaseError::UnknownId(id))? as usize;
        if self.slots[i].aabb == aabb {
            return Ok(());
        }
        let Self {
            levels,
            slots,
            ranges,
            table,
            scratch,
            ..
        } = self;
        let res = place(id, &aabb, levels, scratch)?;
        table.work.cell_ranges += scratch.len() as u64;
        let slot = &mut slots[i];
        let stride = levels.count();
        let old = &mut ranges[i * stride..][..=slot.res];
        if res == slot.res {
            if old != scratch.as_slice() {
                for (level, (o, n)) in old.iter().zip(scratch.iter()).enumerate() {
                    if o == n {
                        continue;
                    }
                    let own = level == res;
                    let level = level as u32;
                    for cell in n.cells().filter(|&c| !o.contains(c)) {
                        table.add(CellKey { level, cell }, id, own);
                    }
                    for cell in o.cells().filter(|&c| !n.contains(c)) {
                        table.remove(CellKey { level, cell }, id, own);
                    }
                }
                old.copy_from_slice(scratch);
            }
        } else {
            // The pair rule min(res X, res Y) changes with res: take everything out first.
            table.remove_all(id, old);
            table.add_all(id, scratch);
            ranges[i * stride..][..=res].copy_from_slice(scratch);
            slot.res = res;
        }
        slot.aabb = aabb;
        Ok(())
    }

    /// Removes box `id` and all its labels, returning its last box. Its pairs' counters drop
    /// to zero, and they count as not close at the last
    /// [`take_new_close_pairs`](Self::take_new_close_pairs): a new box inserted under the same
    /// id has its close pairs reported as new. Errors: [`BroadphaseError::UnknownId`].
    pub fn remove(&mut self, id: u32) -> Result<Aabb, BroadphaseError> {
        let i = self
            .slot_of
            .remove(&id)
            .ok_or(BroadphaseError::UnknownId(id))? as usize;
        let stride = self.levels.count();
        let slot = self.slots[i];
        self.table.forget = true;
        self.table
            .remove_all(id, &self.ranges[i * stride..][..=slot.res]);
        self.table.forget = false;
        let last = self.slots.len() - 1;
        if i != last {
            self.slots[i] = self.slots[last];
            self.ranges
                .copy_within(last * stride..(last + 1) * stride, i * stride);
            self.slot_of.insert(self.slots[i].id, i as u32);
        }
        self.slots.pop();
        self.ranges.truncate(last * stride);
        Ok(slot.aabb)
    }

    /// Number of boxes stored.
    pub fn len(&self) -> usize {
        self.slots.len()
    }

    /// True when no box is stored.
    pub fn is_empty(&self) -> bool {
        self.slots.is_empty()
    }

    /// True when box `id` is stored.
    pub fn contains(&self, id: u32) -> bool {
        self.slot_of.contains_key(&id)
    }

    /// The current box of `id`, if stored.
    pub fn aabb(&self, id: u32) -> Option<Aabb> {
        self.slot(id).map(|s| s.aabb)
    }

    /// res of box `id` (0 = coarsest level), if stored.
    pub fn resolution(&self, id: u32) -> Option<usize> {
        self.slot(id).map(|s| s.res)
    }

    /// All stored ids, sorted.
    pub fn ids(&self) -> Vec<u32> {
        let mut ids: Vec<u32> = self.slots.iter().map(|s| s.id).collect();
        ids.sort_unstable();
        ids
    }

    fn check_known(&self, a: u32, b: u32) -> Result<(), BroadphaseError> {
        for id in [a, b] {
            if !self.slot_of.contains_key(&id) {
                return Err(BroadphaseError::UnknownId(id));
            }
        }
        Ok(())
    }

    /// The close counter c(a, b): the number of buckets at level min(res a, res b) holding
    /// both labels (0 for `a == b`). Errors: [`BroadphaseError::UnknownId`].
    pub fn close_count(&self, a: u32, b: u32) -> Result<u32, BroadphaseError> {
        self.check_known(a, b)?;
        Ok(self
            .table
            .counters
            .get(&pair_key(a, b))
            .copied()
            .unwrap_or(0))
    }

    /// Are `a` and `b` close (Definition 1, c(a, b) > 0)? `false` for `a == b`.
    /// Errors: [`BroadphaseError::UnknownId`].
    pub fn is_close(&self, a: u32, b: u32) -> Result<bool, BroadphaseError> {
        Ok(self.close_count(a, b)? > 0)
    }

    /// Number of close pairs.
    pub fn close_pair_count(&self) -> usize {
        self.table.counters.len()
    }

    /// All close pairs `(a, b)`, `a < b`, sorted.
    pub fn close_pairs(&self) -> Vec<Pair> {
        sorted_pairs(self.table.counters.keys().copied())
    }

    /// All close pairs with their counters c(a, b) > 0, sorted by pair.
    pub fn close_counts(&self) -> Vec<(Pair, u32)> {
        let mut v: Vec<(u64, u32)> = self.table.counters.iter().map(|(&k, &c)| (k, c)).collect();
        v.sort_unstable();
        v.into_iter().map(|(k, c)| (unpack_pair(k), c)).collect()
    }

    /// The close pairs whose current boxes overlap (closed boxes, [`Aabb::overlaps`]): the
    /// same set as a brute-force test of all pairs, since every overlapping pair is close.
    /// Sorted, `a < b`.
    pub fn overlapping_pairs(&self) -> Vec<Pair> {
        let mut v = self.close_pairs();
        v.retain(|&(a, b)| match (self.slot(a), self.slot(b)) {
            (Some(x), Some(y)) => x.aabb.overlaps(&y.aabb),
            _ => false,
        });
        v
    }

    /// The pairs that are close now and were not close at the previous call (or since the
    /// table was made): the pairs whose counter went 0 → 1 since then and is still > 0,
    /// except those that were close at the previous call and only dipped to 0 in between.
    /// Sorted, `a < b`. The simulator inserts these into its collision heap before
    /// integrating (§2.4.3); with hysteresis, a pair that was close at the previous call is
    /// still in the heap. A pair one of whose ids was [removed](Self::remove) since counts as
    /// not close at the previous call.
    ///
    /// Call it every round: until then the record of pairs whose closeness changed grows.
    pub fn take_new_close_pairs(&mut self) -> Vec<Pair> {
        let Table {
            counters, changed, ..
        } = &mut self.table;
        let new = changed
            .drain()
            .filter(|&(k, was_close)| !was_close && counters.contains_key(&k))
            .map(|(k, _)| k);
        sorted_pairs(new)
    }

    /// Whether some pair's closeness changed since the last
    /// [`take_new_close_pairs`](Self::take_new_close_pairs) (then that call has work to do).
    #[must_use]
    pub fn has_pending_changes(&self) -> bool {
        !self.table.changed.is_empty()
    }

    /// Operation counts since creation or the last [`reset_work`](Self::reset_work).
    pub fn work(&self) -> WorkCounters {
        self.table.work
    }

    /// Sets the operation counts to zero.
    pub fn reset_work(&mut self) {
        self.table.work = WorkCounters::default();
    }
}
