//! Seeded box workloads shared by the unit tests and the benchmark
//! (`benches/broadphase.rs` includes this file with `#[path]`, so it may use only
//! impulse-geom, glam and rand — not this crate).
//!
//! The "settling" workload models bodies coming to rest (the coins, bowling and part-feeder
//! scenes of Table 2.1): boxes of sizes spread over [`SIZE_RATIO`], where each round most
//! boxes move by a small fraction of their size and a few move far.

use glam::DVec3;
use impulse_geom::Aabb;
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

/// Smallest box size sz (largest extent), length units.
pub const SIZE_MIN: f64 = 0.1;
/// Largest / smallest box size (≥ 100 as the tests require).
pub const SIZE_RATIO: f64 = 100.0;
/// Sum of box volumes over the region's volume: sets how crowded the region is.
pub const FILL: f64 = 0.05;
/// Shortest extent of a box relative to its size (extents are drawn in [this, 1] × size).
pub const MIN_ASPECT: f64 = 0.5;
/// A small move displaces a box by up to this fraction of its size along each axis.
pub const SMALL_STEP: f64 = 0.02;
/// Fraction of the boxes that move far each round.
pub const FAR_FRACTION: f64 = 0.01;
/// A far move displaces a box by up to this many times its size along each axis.
pub const FAR_STEP: f64 = 4.0;

/// Largest box size.
pub fn size_max() -> f64 {
    SIZE_MIN * SIZE_RATIO
}

/// A size drawn log-uniformly in [lo, hi].
pub fn log_uniform(rng: &mut Xoshiro256PlusPlus, lo: f64, hi: f64) -> f64 {
    (lo.ln() + rng.random::<f64>() * (hi / lo).ln()).exp()
}

/// A box of size exactly `size` (largest extent, along a random axis) centred at `center`.
pub fn random_box(rng: &mut Xoshiro256PlusPlus, center: DVec3, size: f64) -> Aabb {
    let mut ext = DVec3::new(
        rng.random_range(MIN_ASPECT..=1.0),
        rng.random_range(MIN_ASPECT..=1.0),
        rng.random_range(MIN_ASPECT..=1.0),
    ) * size;
    ext[rng.random_range(0..3usize)] = size;
    Aabb::new(center - 0.5 * ext, center + 0.5 * ext)
}

/// Side of a cubic region holding `n` boxes of sizes log-uniform in [SIZE_MIN, size_max()]
/// at volume fraction [`FILL`] (expected volume used, not sampled, so `n` alone decides it).
pub fn region_side(n: usize) -> f64 {
    let (a, b) = (SIZE_MIN, size_max());
    // E[s³] for s log-uniform on [a, b]; mean extent factor per axis of the other two axes.
    let mean_cube = (b.powi(3) - a.powi(3)) / (3.0 * (b / a).ln());
    let aspect = 0.5 * (1.0 + MIN_ASPECT);
    (n as f64 * mean_cube * aspect * aspect / FILL).cbrt()
}

/// The settling workload: `n` boxes with ids `0..n`, moved by [`Settling::step`].
#[derive(Clone, Debug)]
pub struct Settling {
    rng: Xoshiro256PlusPlus,
    side: f64,
    boxes: Vec<(u32, Aabb)>,
}

impl Settling {
    /// `n` boxes placed uniformly in the region of [`region_side`]`(n)`, seeded by `seed`.
    pub fn new(n: usize, seed: u64) -> Self {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        let side = region_side(n);
        let boxes = (0..n as u32)
            .map(|id| {
                let size = log_uniform(&mut rng, SIZE_MIN, size_max());
                let c = DVec3::new(rng.random(), rng.random(), rng.random()) * side;
                (id, random_box(&mut rng, c, size))
            })
            .collect();
        Self { rng, side, boxes }
    }

    /// The current boxes, by increasing id.
    pub fn boxes(&self) -> &[(u32, Aabb)] {
        &self.boxes
    }

    /// One round: every box moves by up to [`SMALL_STEP`] × its size per axis, except a
    /// fraction [`FAR_FRACTION`] that moves by up to [`FAR_STEP`] × its size; centres stay in
    /// the region.
    pub fn step(&mut self) {
        for (_, b) in &mut self.boxes {
            let size = (b.max - b.min).max_element();
            let reach = if self.rng.random::<f64>() < FAR_FRACTION {
                FAR_STEP
            } else {
                SMALL_STEP
            };
            let d = DVec3::new(
                self.rng.random_range(-1.0..1.0),
                self.rng.random_range(-1.0..1.0),
                self.rng.random_range(-1.0..1.0),
            ) * (reach * size);
            let c = b.center();
            let d = (c + d).clamp(DVec3::ZERO, DVec3::splat(self.side)) - c;
            *b = Aabb {
                min: b.min + d,
                max: b.max + d,
            };
        }
    }
}
