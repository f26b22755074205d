//! Tile sizes of the hierarchical hash and the resolution of a box (thesis §2.4.1).
//!
//! **Numbering.** The thesis numbers resolutions 1..n with ρ_1 > ρ_2 > … > ρ_n (Definition 1,
//! Figure 2.11, Theorem 5). Here levels are 0-based with the same order: **code level k is
//! thesis resolution k + 1**, level 0 is the coarsest (largest tiles) and level `count() − 1`
//! the finest. The proof of Lemma 1 numbers the other way (its ρ_1 = sz_min/α is the *finest*
//! tile); its ρ_i is code level n − i.
//!
//! **Resolution rule.** res(X) is the finest level k with sz(X)/ρ_k ≤ β, or level 0 when even
//! the coarsest tile is too small (sz(X) > β ρ_0). For levels built by
//! [`Levels::from_size_range`] this is the k of eq. (2.8), α ≤ sz(X)/ρ_k ≤ β, for every size in
//! [sz_min, β ρ_0]; sizes below sz_min go to the finest level. For hand-made levels whose
//! ratios exceed β/α, a size falling in a gap gets the level where it is at most β tiles wide
//! (keeping Theorem 3's bound on the number of tiles it overlaps) but α ≤ sz/ρ may fail there,
//! which weakens only the resolving power of Theorem 5, never correctness.

use crate::BroadphaseError;
use impulse_geom::Aabb;

/// Default α, dimensionless: the lower bound on sz(X)/ρ_res(X) in eq. (2.8). 0.5, the value of
/// the thesis's Figure 2.11. Larger α (closer to 1) separates boxes better (Theorem 5) but
/// needs more levels (Lemma 1).
pub const DEFAULT_ALPHA: f64 = 0.5;

/// Default β, dimensionless: the upper bound on sz(X)/ρ_res(X) in eq. (2.8). 1.0, the value of
/// Figure 2.11: a box is at most one tile wide at its own level, so it overlaps at most 2 tiles
/// per axis there (Theorem 3: at most (⌈β⌉ + 1)^d buckets per level).
pub const DEFAULT_BETA: f64 = 1.0;

/// Most levels a [`Levels`] may have. With β/α = 2 this spans box sizes over a ratio of 2^64
/// (Lemma 1); more levels only arise from a ratio β/α very close to 1 and would make every box
/// of the coherent variant write its label into that many levels.
pub const MAX_LEVELS: usize = 64;

/// sz(X), the size of a box: its largest extent along a coordinate axis (thesis §2.4.1, "the
/// maximum distance between two opposite faces"). Same unit as the box coordinates.
pub fn box_size(aabb: &Aabb) -> f64 {
    (aabb.max - aabb.min).max_element()
}

/// The tile sizes ρ of a hierarchical spatial hash, coarsest first, with the α and β of eq.
/// (2.8) that define the resolution of a box. See the [module docs](self) for the numbering.
#[derive(Clone, Debug, PartialEq)]
pub struct Levels {
    /// Tile sizes, strictly decreasing (index 0 = coarsest), each finite and > 0.
    tile_sizes: Vec<f64>,
    /// α ∈ (0, 1).
    alpha: f64,
    /// β ≥ 1, finite.
    beta: f64,
}

impl Levels {
    /// Levels with the given tile sizes (coarsest first, strictly decreasing, finite, > 0) and
    /// the default bounds [`DEFAULT_ALPHA`] and [`DEFAULT_BETA`].
    pub fn new(tile_sizes: impl Into<Vec<f64>>) -> Result<Self, BroadphaseError> {
        Self::with_bounds(tile_sizes, DEFAULT_ALPHA, DEFAULT_BETA)
    }

    /// Levels with the given tile sizes (coarsest first, strictly decreasing, finite, > 0) and
    /// the bounds α ∈ (0, 1), β ≥ 1 of eq. (2.8).
    pub fn with_bounds(
        tile_sizes: impl Into<Vec<f64>>,
        alpha: f64,
        beta: f64,
    ) -> Result<Self, BroadphaseError> {
        let tile_sizes = tile_sizes.into();
        check_bounds(alpha, beta)?;
        if tile_sizes.is_empty() {
            return Err(BroadphaseError::NoLevels);
        }
        if tile_sizes.len() > MAX_LEVELS {
            return Err(BroadphaseError::TooManyLevels {
                count: tile_sizes.len(),
                limit: MAX_LEVELS,
            });
        }
        for (index, &value) in tile_sizes.iter().enumerate() {
            if !(value.is_finite() && value > 0.0) {
                return Err(BroadphaseError::BadTileSize { index, value });
            }
            if index > 0 && value >= tile_sizes[index - 1] {
                return Err(BroadphaseError::TileSizesNotDecreasing {
                    index,
                    previous: tile_sizes[index - 1],
                    value,
                });
            }
        }
        Ok(Self {
            tile_sizes,
            alpha,
            beta,
        })
    }

    /// The minimal levels for box sizes in `[sz_min, sz_max]` (proof of Lemma 1): the finest
    /// tile is ρ = sz_min/α, each coarser tile is β/α times the next finer one (eq. 2.9,
    /// β ρ_{i−1} = α ρ_i in the proof's fine-to-coarse numbering), and levels are added until
    /// the coarsest satisfies sz_max/ρ ≤ β. There is always at least one level, and the count is
    /// max(1, ⌈log_{β/α}(sz_max/sz_min)⌉) (Lemma 1), up to rounding when that ratio is an exact
    /// power of β/α.
    ///
    /// Every size in `[sz_min, sz_max]` then gets a level with α ≤ sz/ρ ≤ β (eq. 2.8).
    pub fn from_size_range(
        sz_min: f64,
        sz_max: f64,
        alpha: f64,
        beta: f64,
    ) -> Result<Self, BroadphaseError> {
        check_bounds(alpha, beta)?;
        if !(sz_min > 0.0 && sz_min <= sz_max && sz_max.is_finite()) {
            return Err(BroadphaseError::BadSizeRange { sz_min, sz_max });
        }
        let ratio = beta / alpha;
        // Built fine to coarse, as in the proof, then reversed.
        let mut coarsest = sz_min / alpha;
        let mut sizes = vec![coarsest];
        while sz_max / coarsest > beta {
            if sizes.len() == MAX_LEVELS {
                return Err(BroadphaseError::TooManyLevels {
                    count: sizes.len() + 1,
                    limit: MAX_LEVELS,
                });
            }
            coarsest *= ratio;
            sizes.push(coarsest);
        }
        sizes.reverse();
        Self::with_bounds(sizes, alpha, beta)
    }

    /// Number of levels n (≥ 1).
    pub fn count(&self) -> usize {
        self.tile_sizes.len()
    }

    /// Tile sizes, coarsest first.
    pub fn tile_sizes(&self) -> &[f64] {
        &self.tile_sizes
    }

    /// Tile size ρ of `level` (0 = coarsest), or `None` past the finest level.
    pub fn tile_size(&self, level: usize) -> Option<f64> {
        self.tile_sizes.get(level).copied()
    }

    /// α of eq. (2.8).
    pub fn alpha(&self) -> f64 {
        self.alpha
    }

    /// β of eq. (2.8).
    pub fn beta(&self) -> f64 {
        self.beta
    }

    /// res of a box of size `size` (eq. 2.8): the finest level k with size/ρ_k ≤ β, else the
    /// coarsest level 0. Sizes below the finest level's range (including 0) go to the finest
    /// level; sizes above the coarsest level's range, and NaN, to level 0.
    pub fn resolution(&self, size: f64) -> usize {
        (0..self.count())
            .rev()
            .find(|&k| size / self.tile_sizes[k] <= self.beta)
            .unwrap_or(0)
    }

    /// res(X) of a box: [`Levels::resolution`] of [`box_size`].
    pub fn resolution_of(&self, aabb: &Aabb) -> usize {
        self.resolution(box_size(aabb))
    }
}

fn check_bounds(alpha: f64, beta: f64) -> Result<(), BroadphaseError> {
    if !(alpha > 0.0 && alpha < 1.0) {
        return Err(BroadphaseError::BadAlpha(alpha));
    }
    if !(beta >= 1.0 && beta.is_finite()) {
        return Err(BroadphaseError::BadBeta(beta));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn figure_2_11_style_levels() {
        // α = 0.5, β = 1: tiles 8, 4, 2, 1 cover sizes [0.5, 8].
        let l = Levels::from_size_range(0.5, 8.0, 0.5, 1.0).unwrap();
        assert_eq!(l.tile_sizes(), &[8.0, 4.0, 2.0, 1.0]);
        assert_eq!(l.resolution(0.5), 3);
        assert_eq!(l.resolution(1.0), 3);
        assert_eq!(l.resolution(1.5), 2);
        assert_eq!(l.resolution(8.0), 0);
        // Beyond the range: coarsest / finest.
        assert_eq!(l.resolution(100.0), 0);
        assert_eq!(l.resolution(0.0), 3);
        assert_eq!(l.resolution(f64::NAN), 0);
    }

    #[test]
    fn one_level_when_all_sizes_equal() {
        let l = Levels::from_size_range(2.0, 2.0, 0.5, 1.0).unwrap();
        assert_eq!(l.tile_sizes(), &[4.0]);
        let l = Levels::from_size_range(2.0, 2.0, 0.5, 4.0).unwrap();
        assert_eq!(l.count(), 1);
    }

    #[test]
    fn hand_made_levels_with_a_gap() {
        // Ratio 8 > β/α = 2: a size of 3 fits no level with α ≤ sz/ρ ≤ β; it goes where it is
        // at most β tiles wide.
        let l = Levels::new(vec![8.0, 1.0]).unwrap();
        assert_eq!(l.resolution(3.0), 0);
        assert_eq!(l.resolution(1.0), 1);
        assert_eq!(l.alpha(), DEFAULT_ALPHA);
        assert_eq!(l.beta(), DEFAULT_BETA);
    }
}
