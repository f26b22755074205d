//! The error type of this crate: every bad input is reported, never a panic.

use glam::DVec3;

/// What was wrong with an input to the broad phase.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum BroadphaseError {
    /// A box corner has a NaN or infinite coordinate.
    #[error("box {id}: corner not finite (min = {min}, max = {max})")]
    NonFiniteBox {
        /// The box's id.
        id: u32,
        /// The given lower corner.
        min: DVec3,
        /// The given upper corner.
        max: DVec3,
    },
    /// A box has `min > max` along an axis.
    #[error("box {id}: min {min} > max {max} along axis {axis}")]
    InvertedBox {
        /// The box's id.
        id: u32,
        /// The axis (0 = x, 1 = y, 2 = z).
        axis: usize,
        /// The lower coordinate given.
        min: f64,
        /// The upper coordinate given.
        max: f64,
    },
    /// A box lies so far from the origin, relative to a tile size, that its cell index exceeds
    /// [`MAX_CELL_INDEX`](crate::MAX_CELL_INDEX).
    #[error("box {id}: cell index beyond ±{limit} at level {level} (coordinates too far out)")]
    CellIndexOutOfRange {
        /// The box's id.
        id: u32,
        /// The level (0 = coarsest) where it happened.
        level: usize,
        /// The largest allowed |cell index|.
        limit: f64,
    },
    /// A box overlaps more tiles, summed over its levels, than
    /// [`MAX_CELLS_PER_BOX`](crate::MAX_CELLS_PER_BOX): it is far larger than the coarsest tile.
    #[error("box {id}: overlaps {cells} tiles, more than the limit {limit}; add coarser levels")]
    TooManyCells {
        /// The box's id.
        id: u32,
        /// Tiles it would overlap (summed over the levels it is stored at or checks).
        cells: f64,
        /// The limit.
        limit: u64,
    },
    /// No tile sizes were given.
    #[error("at least one tile size is needed")]
    NoLevels,
    /// More levels than [`MAX_LEVELS`](crate::MAX_LEVELS) were given or would be needed.
    #[error("{count} levels needed or given, more than the limit {limit}")]
    TooManyLevels {
        /// Levels requested (for a size range: the count reached when the limit was hit).
        count: usize,
        /// The limit.
        limit: usize,
    },
    /// A tile size is zero, negative, NaN or infinite.
    #[error("tile size {index} = {value}: must be finite and > 0")]
    BadTileSize {
        /// Its index in the given list (0 = coarsest).
        index: usize,
        /// The value given.
        value: f64,
    },
    /// Tile sizes are not strictly decreasing (coarsest first).
    #[error("tile size {index} = {value} is not smaller than the previous one, {previous}")]
    TileSizesNotDecreasing {
        /// Index of the offending size.
        index: usize,
        /// The size before it.
        previous: f64,
        /// The offending size.
        value: f64,
    },
    /// α is not in the open interval (0, 1).
    #[error("alpha = {0}: must satisfy 0 < alpha < 1")]
    BadAlpha(f64),
    /// β is not finite or is below 1.
    #[error("beta = {0}: must be finite and >= 1")]
    BadBeta(f64),
    /// The size range of [`Levels::from_size_range`](crate::Levels::from_size_range) is not
    /// `0 < sz_min <= sz_max < ∞`.
    #[error("size range [{sz_min}, {sz_max}]: need 0 < sz_min <= sz_max, both finite")]
    BadSizeRange {
        /// The smallest size given.
        sz_min: f64,
        /// The largest size given.
        sz_max: f64,
    },
    /// An id was inserted twice.
    #[error("box {0} is already in the table")]
    DuplicateId(u32),
    /// An id that is not in the table was used.
    #[error("box {0} is not in the table")]
    UnknownId(u32),
}
