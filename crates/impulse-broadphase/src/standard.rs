//! The standard (non-coherent) hierarchical hash of thesis §2.4.1, rebuilt from scratch every
//! round: the baseline of Table 2.1.
//!
//! [`StandardHash::rebuild`] empties the table and stores the boxes in order of increasing
//! resolution index (coarsest level first). Storing box X checks every tile X overlaps at its
//! own level res(X) and at every coarser level (eq. 2.7 per level) for labels already there,
//! recording each pair found as close, then writes X's label at level res(X) only. Because
//! coarser boxes are stored first, X meets every Y with res(Y) ≤ res(X) in their common tiles
//! at level res(Y) = min(res X, res Y), so the close set is exactly Definition 1's.
//!
//! Cost: storing a box checks O(β^d log R) buckets (Theorem 3, R = largest/smallest box
//! size), so a rebuild reports all c close pairs among n boxes in O(n + c) (Theorem 4), every
//! round, whether or not anything moved.

use crate::tiling::{CellKey, CellRange, pair_key, place, sorted_pairs};
use crate::{BroadphaseError, Levels, Pair, WorkCounters};
use impulse_geom::Aabb;
use rustc_hash::{FxHashMap, FxHashSet};

/// The standard hierarchical spatial hash of §2.4.1: boxes under `u32` ids; the close set is
/// recomputed from scratch by [`rebuild`](Self::rebuild). Queries answer for the boxes as of
/// the last rebuild; call it after the round's inserts, updates and removes.
#[derive(Clone, Debug)]
pub struct StandardHash {
    levels: Levels,
    /// Slot of each stored id.
    slot_of: FxHashMap<u32, u32>,
    /// Stored boxes `(id, box, res)`, densely packed (removal moves the last into the hole).
    slots: Vec<(u32, Aabb, usize)>,
    buckets: FxHashMap<CellKey, Vec<u32>>,
    /// Labels in `buckets` (cleared at the next rebuild).
    stored_labels: u64,
    /// Close pairs found by the last rebuild.
    close: FxHashSet<u64>,
    /// Emptied bucket vectors kept for reuse.
    spare: Vec<Vec<u32>>,
    /// Storage order (slots grouped by res, coarsest first), reused between rebuilds.
    order: Vec<u32>,
    scratch: Vec<CellRange>,
    stale: bool,
    work: WorkCounters,
}

impl StandardHash {
    /// An empty table with the given levels.
    pub fn new(levels: Levels) -> Self {
        Self {
            levels,
            slot_of: FxHashMap::default(),
            slots: Vec::new(),
            buckets: FxHashMap::default(),
            stored_labels: 0,
            close: FxHashSet::default(),
            spare: Vec::new(),
            order: Vec::new(),
            scratch: Vec::new(),
            stale: false,
            work: WorkCounters::default(),
        }
    }

    /// The levels (tile sizes, α, β).
    pub fn levels(&self) -> &Levels {
        &self.levels
    }

    fn slot(&self, id: u32) -> Option<&(u32, Aabb, usize)> {
        self.slot_of.get(&id).map(|&i| &self.slots[i as usize])
    }

    /// Adds box `id` (takes effect at the next [`rebuild`](Self::rebuild)).
    ///
    /// Errors: [`BroadphaseError::DuplicateId`] if `id` is present; a non-finite or inverted
    /// box, or one too large or too far out for the levels (see [`BroadphaseError`]).
    pub fn insert(&mut self, id: u32, aabb: Aabb) -> Result<(), BroadphaseError> {
        if self.slot_of.contains_key(&id) {
            return Err(BroadphaseError::DuplicateId(id));
        }
        let res = place(id, &aabb, &self.levels, &mut self.scratch)?;
        self.slot_of.insert(id, self.slots.len() as u32);
        self.slots.push((id, aabb, res));
        self.stale = true;
        Ok(())
    }

    /// Replaces the box of `id` (takes effect at the next [`rebuild`](Self::rebuild)).
    /// Errors: [`BroadphaseError::UnknownId`], or a bad box as for [`insert`](Self::insert).
    pub fn update(&mut self, id: u32, aabb: Aabb) -> Result<(), BroadphaseError> {
        let i = *self
            .slot_of
            .get(&id)
            .ok_or(BroadphaseError::UnknownId(id))? as usize;
        let res = place(id, &aabb, &self.levels, &mut self.scratch)?;
        self.slots[i] = (id, aabb, res);
        self.stale = true;
        Ok(())
    }

    /// Removes box `id`, returning its box (takes effect at the next rebuild).
    /// Errors: [`BroadphaseError::UnknownId`].
    pub fn remove(&mut self, id: u32) -> Result<Aabb, BroadphaseError> {
        let i = self
            .slot_of
            .remove(&id)
            .ok_or(BroadphaseError::UnknownId(id))? as usize;
        let (_, aabb, _) = self.slots.swap_remove(i);
        if let Some(&(moved, _, _)) = self.slots.get(i) {
            self.slot_of.insert(moved, i as u32);
        }
        self.stale = true;
        Ok(aabb)
    }

    /// True when boxes were inserted, updated or removed since the last rebuild.
    pub fn is_stale(&self) -> bool {
        self.stale
    }

    /// Empties the table and stores every box again, coarsest level first, recording the
    /// close pairs (Definition 1). This is one round of the standard variant.
    pub fn rebuild(&mut self) {
        let w = &mut self.work;
        w.label_removals += self.stored_labels;
        self.stored_labels = 0;
        for (_, mut v) in self.buckets.drain() {
            v.clear();
            self.spare.push(v);
        }
        self.close.clear();

        // Counting sort of the ids by res, coarsest first.
        let n_levels = self.levels.count();
        let mut start = vec![0usize; n_levels + 1];
        for &(_, _, res) in &self.slots {
            start[res + 1] += 1;
        }
        for l in 0..n_levels {
            start[l + 1] += start[l];
        }
        self.order.clear();
        self.order.resize(self.slots.len(), 0);
        for (i, &(_, _, res)) in self.slots.iter().enumerate() {
            self.order[start[res]] = i as u32;
            start[res] += 1;
        }

        for &i in &self.order {
            let (id, aabb, res) = self.slots[i as usize];
            if place(id, &aabb, &self.levels, &mut self.scratch).is_err() {
                debug_assert!(false, "box {id} was validated when it was set");
                continue;
            }
            w.cell_ranges += self.scratch.len() as u64;
            for (level, range) in self.scratch.iter().enumerate() {
                let own = level == res;
                for cell in range.cells() {
                    let key = CellKey {
                        level: level as u32,
                        cell,
                    };
                    w.bucket_visits += 1;
                    let bucket = if own {
                        Some(
                            self.buckets
                                .entry(key)
                                .or_insert_with(|| self.spare.pop().unwrap_or_default()),
                        )
                    } else {
                        self.buckets.get_mut(&key)
                    };
                    let Some(bucket) = bucket else {
                        continue;
                    };
                    for &y in bucket.iter() {
                        w.label_reads += 1;
                        w.counter_changes += 1;
                        self.close.insert(pair_key(id, y));
                    }
                    if own {
                        bucket.push(id);
                        w.label_writes += 1;
                        self.stored_labels += 1;
                    }
                }
            }
        }
        self.stale = false;
    }

    /// Number of boxes stored.
    pub fn len(&self) -> usize {
        self.slots.len()
    }

    /// True when no box is stored.
    pub fn is_empty(&self) -> bool {
        self.slots.is_empty()
    }

    /// The current box of `id`, if stored.
    pub fn aabb(&self, id: u32) -> Option<Aabb> {
        self.slot(id).map(|&(_, a, _)| a)
    }

    /// res of box `id` (0 = coarsest level), if stored.
    pub fn resolution(&self, id: u32) -> Option<usize> {
        self.slot(id).map(|&(_, _, r)| r)
    }

    /// Were `a` and `b` close at the last rebuild? `false` for `a == b`.
    /// Errors: [`BroadphaseError::UnknownId`] if either is not stored now.
    pub fn is_close(&self, a: u32, b: u32) -> Result<bool, BroadphaseError> {
        for id in [a, b] {
            if !self.slot_of.contains_key(&id) {
                return Err(BroadphaseError::UnknownId(id));
            }
        }
        Ok(a != b && self.close.contains(&pair_key(a, b)))
    }

    /// Number of close pairs at the last rebuild.
    pub fn close_pair_count(&self) -> usize {
        self.close.len()
    }

    /// Close pairs at the last rebuild, `(a, b)` with `a < b`, sorted.
    pub fn close_pairs(&self) -> Vec<Pair> {
        sorted_pairs(self.close.iter().copied())
    }

    /// Close pairs at the last rebuild whose current boxes overlap, sorted; the brute-force
    /// overlap set when nothing changed since the rebuild ([`is_stale`](Self::is_stale)).
    pub fn overlapping_pairs(&self) -> Vec<Pair> {
        let mut v = self.close_pairs();
        v.retain(|&(a, b)| match (self.slot(a), self.slot(b)) {
            (Some(x), Some(y)) => x.1.overlaps(&y.1),
            _ => false,
        });
        v
    }

    /// Operation counts since creation or the last [`reset_work`](Self::reset_work).
    pub fn work(&self) -> WorkCounters {
        self.work
    }

    /// Sets the operation counts to zero.
    pub fn reset_work(&mut self) {
        self.work = WorkCounters::default();
    }
}
