//! Internal links (FORK⁻¹S §6, eq. 22 and eq. 6): each link's pose from the end-effector
//! twists through the twist maps and the exponential map, every link independently, in fixed
//! batches per rayon task over contiguous arrays.
//!
//! [`InternalLinks`] is the per-step kernel. It is built once per model and folds the fixed
//! parts of a link's pose into its twist map: the stiffness (`ξ_l = T_l K ξ`, eqs. 22 and
//! `w = K ξ` of §6) and the rotation of the reference pose (`H_l exp(ξ_l) = exp(Ad_{R_l} ξ_l)
//! H_l` with `Ad_{R_l} = diag(R_l, R_l)`), so a step is one 6 × 6|E| product per link, the
//! exponential's coefficients, and a quaternion product with the fixed reference rotation.
//! Links are stored structure-of-arrays, [`LANES`] links side by side, and their arithmetic
//! runs on AVX vectors where the processor has them (module `lanes`, chosen at run time).
//! The exponential's coefficients are Taylor series in θ² up to [`EXP_POLY_ANGLE`] (no square
//! root, division or trigonometry), and above it vectorised trigonometry of the half angle
//! (reduction by multiples of π/2, series on `[−π/4, π/4]`) up to [`EXP_REDUCED_ANGLE`]; libm
//! only beyond. All agree with `Pose::exp` to round-off (tested).
//!
//! Outputs do not depend on the thread count: each link's pose is computed by the same
//! sequence of operations whatever thread runs it (a lane's result never depends on the other
//! lanes of its group), and the batches are a fixed layout ([`LINK_BATCH`] links each), never
//! derived from the number of threads (tested with pools of 1, 2, 3 and 7 threads, bitwise).

use glam::{DQuat, DVec3};
use impulse_geom::{Pose, Twist};
use rayon::prelude::*;

use crate::construct::ReducedModel;
use crate::lanes::{Lanes, Ops, Portable};

/// Links per rayon task. Large enough that a task (≈ 32 × 40 ns) outweighs the scheduling
/// cost, small enough that a 400-link helix still splits into 13 tasks for 2–8 threads. The
/// paper reports that batching per thread mattered (§8.3). A multiple of [`LANES`].
pub const LINK_BATCH: usize = 32;

/// Links computed side by side (one structure-of-arrays group): four f64 lanes are one AVX
/// register per quantity.
pub const LANES: usize = 4;

/// Largest rotation angle θ (rad) whose exponential-map coefficients [`InternalLinks`] and
/// [`fast_exp`] take from the truncated Taylor series below; larger angles use trigonometry
/// (see [`EXP_REDUCED_ANGLE`]; [`fast_exp`] uses libm's `sin_cos`).
/// Each series is cut where its first omitted term is below 2⁻⁵⁶ of its value at θ = 1 rad, so
/// the truncation is under a quarter ulp (round-off of the Horner sums dominates: equal to
/// `Pose::exp` to round-off, tested on both sides of the switch). One radian covers every
/// rotation a first-order model is meant for, with three more terms per series than 0.5 rad.
pub const EXP_POLY_ANGLE: f64 = 1.0;

/// Largest rotation angle θ (rad) whose exponential-map coefficients [`InternalLinks`] takes
/// from vectorised trigonometry (the half angle reduced to `[−π/4, π/4]` by multiples of
/// `π/2`, then Taylor series); above, libm's `sin_cos`. The quadrant count stays below 2²⁰,
/// where the two-part `π/2` of the reduction keeps `r` exact to ~1e-16 absolute.
pub const EXP_REDUCED_ANGLE: f64 = 1e6;

/// `sin r = r Σ (−r²)ʲ / (2j+1)!`, coefficients of r^{2j} (j = 0..8): for `|r| ≤ π/4` the first
/// omitted term is below 1e-19.
pub(crate) const SERIES_SIN: [f64; 9] = [
    1.0,
    -1.0 / 6.0,
    1.0 / 120.0,
    -1.0 / 5_040.0,
    1.0 / 362_880.0,
    -1.0 / 39_916_800.0,
    1.0 / 6_227_020_800.0,
    -1.0 / 1_307_674_368_000.0,
    1.0 / 355_687_428_096_000.0,
];

/// `cos r = Σ (−r²)ʲ / (2j)!`, coefficients of r^{2j} (j = 0..9): for `|r| ≤ π/4` the first
/// omitted term is below 1e-20.
pub(crate) const SERIES_COS: [f64; 10] = [
    1.0,
    -1.0 / 2.0,
    1.0 / 24.0,
    -1.0 / 720.0,
    1.0 / 40_320.0,
    -1.0 / 3_628_800.0,
    1.0 / 479_001_600.0,
    -1.0 / 87_178_291_200.0,
    1.0 / 20_922_789_888_000.0,
    -1.0 / 6_402_373_705_728_000.0,
];

/// `sin(θ/2)/θ = ½ Σ (−θ²/4)ʲ / (2j+1)!`, coefficients of θ^{2j} (j = 0..7).
pub(crate) const SERIES_K: [f64; 8] = [
    1.0 / 2.0,
    -1.0 / 48.0,
    1.0 / 3_840.0,
    -1.0 / 645_120.0,
    1.0 / 185_794_560.0,
    -1.0 / 81_749_606_400.0,
    1.0 / 51_011_754_393_600.0,
    -1.0 / 42_849_873_690_624_000.0,
];

/// `cos(θ/2) = Σ (−θ²/4)ʲ / (2j)!`, coefficients of θ^{2j} (j = 0..7).
pub(crate) const SERIES_C: [f64; 8] = [
    1.0,
    -1.0 / 8.0,
    1.0 / 384.0,
    -1.0 / 46_080.0,
    1.0 / 10_321_920.0,
    -1.0 / 3_715_891_200.0,
    1.0 / 1_961_990_553_600.0,
    -1.0 / 1_428_329_123_020_800.0,
];

/// `(θ − sin θ)/θ³ = Σ (−θ²)ʲ / (2j+3)!`, coefficients of θ^{2j} (j = 0..8).
pub(crate) const SERIES_B: [f64; 9] = [
    1.0 / 6.0,
    -1.0 / 120.0,
    1.0 / 5_040.0,
    -1.0 / 362_880.0,
    1.0 / 39_916_800.0,
    -1.0 / 6_227_020_800.0,
    1.0 / 1_307_674_368_000.0,
    -1.0 / 355_687_428_096_000.0,
    1.0 / 121_645_100_408_832_000.0,
];

/// Horner evaluation of `Σ coeffs[j] x^j`.
#[inline(always)]
pub(crate) fn horner<const N: usize>(coeffs: &[f64; N], x: f64) -> f64 {
    coeffs.iter().rev().fold(0.0, |acc, &c| acc * x + c)
}

/// The exponential map's coefficients for `θ² = t2`: `k = sin(θ/2)/θ`, `c = cos(θ/2)` (the
/// unit quaternion `(k ω, c)`, eq. 6) and `b = (θ − sin θ)/θ³` (MLS eq. 2.36 in V-form;
/// `a = (1 − cos θ)/θ² = 2k²`). Series up to [`EXP_POLY_ANGLE`], one `sin_cos` above.
#[inline(always)]
fn exp_coefficients(t2: f64) -> (f64, f64, f64) {
    if t2 < EXP_POLY_ANGLE * EXP_POLY_ANGLE {
        (
            horner(&SERIES_K, t2),
            horner(&SERIES_C, t2),
            horner(&SERIES_B, t2),
        )
    } else {
        exp_coefficients_trig(t2)
    }
}

/// [`exp_coefficients`] by trigonometry (angles above [`EXP_POLY_ANGLE`]): one square root and
/// one `sin_cos` of the half angle, `sin θ = 2 sin(θ/2) cos(θ/2)`.
#[inline(never)]
pub(crate) fn exp_coefficients_trig(t2: f64) -> (f64, f64, f64) {
    let theta = t2.sqrt();
    let (sh, ch) = (0.5 * theta).sin_cos();
    (sh / theta, ch, (theta - 2.0 * sh * ch) / (t2 * theta))
}

/// Equivalent static end-effector wrenches `w = K ξ` (§6), stacked.
#[must_use]
pub fn equivalent_wrenches(model: &ReducedModel, xi: &[f64]) -> Vec<f64> {
    let n = xi.len();
    (0..n)
        .map(|r| (0..n).map(|c| model.stiffness[(r, c)] * xi[c]).sum())
        .collect()
}

/// Body twist of internal link `k` under stacked end-effector wrenches `w` (eq. 22).
#[must_use]
pub fn link_twist(model: &ReducedModel, k: usize, w: &[f64]) -> Twist {
    let t = model.twist_map(k);
    // Column-major: six independent running sums, one column (6 adjacent values) at a time.
    let mut acc = [0.0; 6];
    for (col, wc) in t.chunks_exact(6).zip(w) {
        for (a, x) in acc.iter_mut().zip(col) {
            *a += x * wc;
        }
    }
    Twist::from_array(acc)
}

/// `Pose::exp` (MLS eq. 2.36 in V-form, FORK⁻¹S eq. 6) for one twist, with the coefficients
/// of [`InternalLinks`]: Taylor series in θ² up to [`EXP_POLY_ANGLE`] (no square root, no
/// trigonometry), one `sin_cos` of the half angle above. Equal to `Pose::exp` to round-off
/// (tested).
#[must_use]
pub fn fast_exp(xi: &Twist) -> Pose {
    let w = xi.w;
    let (k, c, b) = exp_coefficients(w.length_squared());
    let a = 2.0 * k * k;
    let xyz = w * k;
    let wv = w.cross(xi.v);
    Pose {
        rotation: DQuat::from_xyzw(xyz.x, xyz.y, xyz.z, c),
        translation: xi.v + wv * a + w.cross(wv) * b,
    }
}

/// `reference · exp(ξ)` without renormalising the product quaternion: both factors are unit to
/// round-off and the product is formed afresh each step from the fixed reference (nothing
/// accumulates), so its norm stays within a few ulp of 1 (tested) and the square root and
/// division of `Pose`'s `Mul` are saved.
#[must_use]
pub fn place(reference: &Pose, xi: &Twist) -> Pose {
    let e = fast_exp(xi);
    Pose {
        rotation: reference.rotation * e.rotation,
        translation: reference.rotation * e.translation + reference.translation,
    }
}

/// Per-link data of a model's internal links, laid out for the per-step pose update
/// ([`InternalLinks::update`]): built once (like the factored system matrix), it does not
/// follow later edits of the model.
#[derive(Clone, Debug)]
pub struct InternalLinks {
    /// Internal links.
    count: usize,
    /// Stacked end-effector dimension `6|E|`.
    dofs: usize,
    /// Folded twist maps `Ad_{R_l} T_l K`, per group of [`LANES`] links: `dofs` columns of six
    /// rows, each entry one value per lane (`maps[(g · dofs + c) · 6 + r][lane]`). Lanes past
    /// the last link are zero.
    maps: Vec<Lanes>,
    /// Reference poses per group: quaternion `x, y, z, w`, then translation `x, y, z`. Lanes
    /// past the last link are the identity.
    reference: Vec<[Lanes; 7]>,
}

impl InternalLinks {
    /// Folds the stiffness and the reference rotations into the twist maps of `model`.
    #[must_use]
    pub fn new(model: &ReducedModel) -> Self {
        let count = model.internal.len();
        let dofs = 6 * model.end_effectors.len();
        let groups = count.div_ceil(LANES);
        let mut maps = vec![[0.0; LANES]; groups * dofs * 6];
        let mut reference = vec![[[0.0; LANES]; 7]; groups];
        for g in &mut reference {
            g[3] = [1.0; LANES];
        }
        for k in 0..count {
            let (g, lane) = (k / LANES, k % LANES);
            let t = model.twist_map(k);
            let h = &model.internal_reference[k];
            let r = h.rotation_matrix();
            for c in 0..dofs {
                // Column c of T_l K (eq. 22 with w = K ξ), then rotated: Ad_{R_l} = diag(R_l, R_l).
                let tk: [f64; 6] = core::array::from_fn(|row| {
                    (0..dofs)
                        .map(|j| t[6 * j + row] * model.stiffness[(j, c)])
                        .sum()
                });
                let v = r * DVec3::new(tk[0], tk[1], tk[2]);
                let w = r * DVec3::new(tk[3], tk[4], tk[5]);
                for (row, x) in v.to_array().into_iter().chain(w.to_array()).enumerate() {
                    maps[(g * dofs + c) * 6 + row][lane] = x;
                }
            }
            let q = h.rotation.to_array();
            let p = h.translation.to_array();
            for (i, x) in q.into_iter().chain(p).enumerate() {
                reference[g][i][lane] = x;
            }
        }
        InternalLinks {
            count,
            dofs,
            maps,
            reference,
        }
    }

    /// Number of internal links.
    #[must_use]
    pub fn len(&self) -> usize {
        self.count
    }

    /// Whether the model has no internal link.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// Writes every internal link's world pose `frame · H_l exp(ξ_l)` (eqs. 22 and 6) for the
    /// stacked end-effector twists `xi` into `out` (one per internal link, in the model's
    /// order), in parallel batches of [`LINK_BATCH`] links; serially when the current rayon
    /// pool has one thread (the same operations per link, so the same bits). `frame` is
    /// `H_b H_b0⁻¹` for a free base, identity for a fixed one.
    ///
    /// # Panics
    /// If `out` does not have one entry per internal link or `xi` one entry per end-effector
    /// direction (caller bugs).
    pub fn update(&self, xi: &[f64], frame: &Pose, out: &mut [Pose]) {
        self.update_on(rayon::current_num_threads() == 1, xi, frame, out);
    }

    /// [`InternalLinks::update`] on the calling thread alone when `serial` (no hand-over to a
    /// pool's worker and back: on one thread that costs more than the links themselves), in
    /// parallel batches on the current rayon pool otherwise.
    ///
    /// # Panics
    /// As [`InternalLinks::update`].
    pub fn update_on(&self, serial: bool, xi: &[f64], frame: &Pose, out: &mut [Pose]) {
        assert_eq!(out.len(), self.count, "one output pose per internal link");
        assert_eq!(
            xi.len(),
            self.dofs,
            "one twist component per end-effector DoF"
        );
        let moving = *frame != Pose::IDENTITY;
        let batch = |first_group: usize, chunk: &mut [Pose]| {
            self.place_groups(first_group, xi, chunk);
            if moving {
                for p in chunk {
                    *p = *frame * *p;
                }
            }
        };
        if serial {
            batch(0, out);
        } else {
            out.par_chunks_mut(LINK_BATCH)
                .enumerate()
                .for_each(|(b, chunk)| batch(b * (LINK_BATCH / LANES), chunk));
        }
    }

    /// Places the links of `out`, groups `first_group…`: with AVX vectors where the processor
    /// has them, plain arrays otherwise (the same bits, see [`crate::lanes`]).
    fn place_groups(&self, first_group: usize, xi: &[f64], out: &mut [Pose]) {
        #[cfg(target_arch = "x86_64")]
        if let Some(simd) = pulp::x86::V3::try_new() {
            simd.vectorize(AvxBatch {
                simd,
                links: self,
                first_group,
                xi,
                out,
            });
            return;
        }
        self.place_groups_with(Portable, first_group, xi, out);
    }

    /// [`InternalLinks::place_groups`] with the lane arithmetic `o`.
    #[inline(always)]
    fn place_groups_with<O: Ops>(&self, o: O, first_group: usize, xi: &[f64], out: &mut [Pose]) {
        let width = self.dofs * 6;
        for (j, links) in out.chunks_mut(LANES).enumerate() {
            let g = first_group + j;
            let map = &self.maps[g * width..(g + 1) * width];
            crate::lanes::place_group(o, map, xi, &self.reference[g], links);
        }
    }
}

/// Consecutive groups of links from `first_group` on, placed by one call compiled with the
/// AVX target features (`pulp` runs [`pulp::NullaryFnOnce::call`] inside a function that
/// enables them; everything below is inlined into it).
#[cfg(target_arch = "x86_64")]
struct AvxBatch<'a> {
    simd: pulp::x86::V3,
    links: &'a InternalLinks,
    first_group: usize,
    xi: &'a [f64],
    out: &'a mut [Pose],
}

#[cfg(target_arch = "x86_64")]
impl pulp::NullaryFnOnce for AvxBatch<'_> {
    type Output = ();

    #[inline(always)]
    fn call(self) {
        self.links
            .place_groups_with(self.simd, self.first_group, self.xi, self.out);
    }
}

/// Writes every internal link's world pose `frame · H_l exp(ξ_l)` into `out` (one per
/// `model.internal`), in parallel batches. `frame` is `H_b H_b0⁻¹` for a free base, identity
/// for a fixed one. Builds an [`InternalLinks`] each call: a simulation keeps one
/// ([`crate::ReducedSim::internal_poses`]).
///
/// # Panics
/// If `out` does not have one entry per internal link (a caller bug).
pub fn update_internal_links(model: &ReducedModel, xi: &[f64], frame: &Pose, out: &mut [Pose]) {
    InternalLinks::new(model).update(xi, frame, out);
}

#[cfg(test)]
#[path = "internal_tests.rs"]
mod tests;
