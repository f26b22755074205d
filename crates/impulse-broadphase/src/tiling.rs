//! The tiling map τ of eq. (2.7), cell ranges of boxes, bucket keys and pair keys.

use crate::{BroadphaseError, Levels, Pair};
use impulse_geom::Aabb;

/// Largest |cell index| ⌊x/ρ⌋ allowed, 2^53: beyond it consecutive f64 coordinates are more
/// than one tile apart and cell ranges lose their meaning. A box this far out, relative to the
/// tile size, is rejected with [`BroadphaseError::CellIndexOutOfRange`].
pub const MAX_CELL_INDEX: f64 = 9_007_199_254_740_992.0;

/// Most tiles one box may overlap, summed over the levels where it is stored or checked
/// (levels 0..=res). 2^20. A box within the levels' size range overlaps at most (⌈β⌉ + 1)³
/// tiles per level (Theorem 3); only a box far larger than the coarsest tile can reach this
/// limit, and it is rejected with [`BroadphaseError::TooManyCells`] instead of filling memory.
pub const MAX_CELLS_PER_BOX: u64 = 1 << 20;

/// An inclusive range of tiles `lo..=hi` per axis at one level: the images under τ (eq. 2.7)
/// of a box's min and max corners and every tile "between" them (§2.4.1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct CellRange {
    pub(crate) lo: [i64; 3],
    pub(crate) hi: [i64; 3],
}

impl CellRange {
    /// Does the range hold `cell`?
    pub(crate) fn contains(&self, cell: [i64; 3]) -> bool {
        (0..3).all(|i| self.lo[i] <= cell[i] && cell[i] <= self.hi[i])
    }

    /// Every cell of the range, x slowest.
    pub(crate) fn cells(&self) -> impl Iterator<Item = [i64; 3]> + use<> {
        let (lo, hi) = (self.lo, self.hi);
        (lo[0]..=hi[0]).flat_map(move |x| {
            (lo[1]..=hi[1]).flat_map(move |y| (lo[2]..=hi[2]).map(move |z| [x, y, z]))
        })
    }
}

/// τ of eq. (2.7) along one axis: the index ⌊x/ρ⌋ of the tile holding coordinate `x`, as an
/// f64 (NaN or beyond ±2^63 when x/ρ is; callers check against [`MAX_CELL_INDEX`]).
fn tile_index(x: f64, rho: f64) -> f64 {
    let q = x / rho;
    // ⌊q⌋ by truncation: `f64::floor` is a libm call on baseline x86-64 (no SSE4.1), and
    // this is the hot path of every update. Exact for |q| < 2^63; other q are rejected.
    let t = q as i64 as f64;
    if t > q { t - 1.0 } else { t }
}

/// The key of one hash bucket: a tile at one level.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) struct CellKey {
    pub(crate) level: u32,
    pub(crate) cell: [i64; 3],
}

/// Checks that `aabb` is finite with `min <= max` on every axis.
fn validate_box(id: u32, aabb: &Aabb) -> Result<(), BroadphaseError> {
    if !(aabb.min.is_finite() && aabb.max.is_finite()) {
        return Err(BroadphaseError::NonFiniteBox {
            id,
            min: aabb.min,
            max: aabb.max,
        });
    }
    for axis in 0..3 {
        if aabb.min[axis] > aabb.max[axis] {
            return Err(BroadphaseError::InvertedBox {
                id,
                axis,
                min: aabb.min[axis],
                max: aabb.max[axis],
            });
        }
    }
    Ok(())
}

/// Validates `aabb` and writes its tile ranges at levels `0..=res` into `out` (reusing its
/// allocation), returning res. On error `out` is unspecified.
pub(crate) fn place(
    id: u32,
    aabb: &Aabb,
    levels: &Levels,
    out: &mut Vec<CellRange>,
) -> Result<usize, BroadphaseError> {
    validate_box(id, aabb)?;
    let res = levels.resolution_of(aabb);
    out.clear();
    let mut cells = 0.0;
    for (level, &rho) in levels.tile_sizes()[..=res].iter().enumerate() {
        let mut range = CellRange {
            lo: [0; 3],
            hi: [0; 3],
        };
        let mut count = 1.0;
        for axis in 0..3 {
            let lo = tile_index(aabb.min[axis], rho);
            let hi = tile_index(aabb.max[axis], rho);
            if !(lo.abs() <= MAX_CELL_INDEX && hi.abs() <= MAX_CELL_INDEX) {
                return Err(BroadphaseError::CellIndexOutOfRange {
                    id,
                    level,
                    limit: MAX_CELL_INDEX,
                });
            }
            range.lo[axis] = lo as i64;
            range.hi[axis] = hi as i64;
            count *= hi - lo + 1.0;
        }
        cells += count;
        if cells > MAX_CELLS_PER_BOX as f64 {
            return Err(BroadphaseError::TooManyCells {
                id,
                cells,
                limit: MAX_CELLS_PER_BOX,
            });
        }
        out.push(range);
    }
    Ok(res)
}

/// The unordered pair {a, b} packed as one key, smaller id in the high half.
pub(crate) fn pair_key(a: u32, b: u32) -> u64 {
    let (lo, hi) = if a < b { (a, b) } else { (b, a) };
    (u64::from(lo) << 32) | u64::from(hi)
}

/// Inverse of [`pair_key`]: `(smaller, larger)`.
pub(crate) fn unpack_pair(key: u64) -> Pair {
    ((key >> 32) as u32, key as u32)
}

/// Sorted pairs from pair keys (the key order is the `(a, b)` lexicographic order).
pub(crate) fn sorted_pairs(keys: impl Iterator<Item = u64>) -> Vec<Pair> {
    let mut keys: Vec<u64> = keys.collect();
    keys.sort_unstable();
    keys.into_iter().map(unpack_pair).collect()
}
