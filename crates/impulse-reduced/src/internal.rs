//! Internal links (FORK⁻¹S §6, eq. 22 and eq. 6): each link's pose from the end-effector
//! twists through the twist maps and the exponential map, every link independently, in fixed
//! batches per rayon task over the contiguous twist-map array.
//!
//! Outputs do not depend on the thread count: each link's pose is computed by the same
//! sequence of operations whatever thread runs it, and the batches are a fixed layout
//! ([`LINK_BATCH`] links each), never derived from the number of threads (tested with pools of
//! 1, 2, 3 and 7 threads, bitwise).

use glam::DQuat;
use impulse_geom::pose::SE3_SERIES_ANGLE;
use impulse_geom::{Pose, Twist};
use rayon::prelude::*;

use crate::construct::ReducedModel;

/// Links per rayon task. Large enough that a task (≈ 32 × 0.1 µs) outweighs the scheduling
/// cost, small enough that a 400-link helix still splits into 13 tasks for 2–8 threads. The
/// paper reports that batching per thread mattered (§8.3).
pub const LINK_BATCH: usize = 32;

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

/// `Pose::exp` (MLS eq. 2.36 in V-form, FORK⁻¹S eq. 6) with one square root and one
/// `sin_cos` instead of two and three: `sin θ = 2 sin(θ/2) cos(θ/2)` and
/// `1 − cos θ = 2 sin²(θ/2)` come from the half angle the quaternion needs anyway. Below
/// [`SE3_SERIES_ANGLE`] the same Taylor series as `impulse_geom` (no trigonometry). Equal to
/// `Pose::exp` to round-off (tested); the exponential is most of an internal link's cost.
#[must_use]
pub fn fast_exp(xi: &Twist) -> Pose {
    let w = xi.w;
    let t2 = w.length_squared();
    let theta = t2.sqrt();
    // k = sin(θ/2)/θ, c = cos(θ/2), a = (1 − cos θ)/θ², b = (θ − sin θ)/θ³.
    let (k, c, a, b) = if theta < SE3_SERIES_ANGLE {
        (
            0.5 + t2 * (-1.0 / 48.0 + t2 * (1.0 / 3840.0 - t2 / 645_120.0)),
            1.0 + t2
                * (-1.0 / 8.0 + t2 * (1.0 / 384.0 + t2 * (-1.0 / 46_080.0 + t2 / 10_321_920.0))),
            0.5 + t2 * (-1.0 / 24.0 + t2 * (1.0 / 720.0 - t2 / 40_320.0)),
            1.0 / 6.0 + t2 * (-1.0 / 120.0 + t2 * (1.0 / 5040.0 - t2 / 362_880.0)),
        )
    } else {
        let (sh, ch) = (0.5 * theta).sin_cos();
        let k = sh / theta;
        (k, ch, 2.0 * k * k, (theta - 2.0 * sh * ch) / (t2 * theta))
    };
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

/// Writes every internal link's world pose `frame · H_l exp(ξ_l)` into `out` (one per
/// `model.internal`), in parallel batches. `frame` is `H_b H_b0⁻¹` for a free base, identity
/// for a fixed one.
///
/// # Panics
/// If `out` does not have one entry per internal link (a caller bug).
pub fn update_internal_links(model: &ReducedModel, xi: &[f64], frame: &Pose, out: &mut [Pose]) {
    assert_eq!(
        out.len(),
        model.internal.len(),
        "one output pose per internal link"
    );
    let w = equivalent_wrenches(model, xi);
    let moving = *frame != Pose::IDENTITY;
    out.par_chunks_mut(LINK_BATCH)
        .enumerate()
        .for_each(|(batch, chunk)| {
            for (i, pose) in chunk.iter_mut().enumerate() {
                let k = batch * LINK_BATCH + i;
                let xi_l = link_twist(model, k, &w);
                let local = place(&model.internal_reference[k], &xi_l);
                *pose = if moving { *frame * local } else { local };
            }
        });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Tsvd;
    use crate::construct::ConstructOptions;
    use crate::reference::{Configuration, LinearStatics};

    /// Bit patterns of every pose component.
    fn bits(p: &[Pose]) -> Vec<u64> {
        p.iter()
            .flat_map(|x| {
                x.rotation
                    .to_array()
                    .into_iter()
                    .chain(x.translation.to_array())
                    .map(f64::to_bits)
            })
            .collect()
    }

    /// [`fast_exp`] against `impulse_geom`'s `Pose::exp` (rotation quaternion components,
    /// translation relative to `|v|`) and [`place`] against the renormalising product (and its
    /// quaternion's norm against 1), angles from 1e-8 to 3 rad across the series switch.
    const FAST_EXP_REL: f64 = 1e-14;

    #[test]
    fn fast_exp_equals_pose_exp() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(6);
        let mut worst = 0.0_f64;
        for _ in 0..20_000 {
            let dir = glam::DVec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            )
            .normalize();
            let angle = 10f64.powf(rng.random_range(-8.0..0.5));
            let v = glam::DVec3::new(
                rng.random_range(-2.0..2.0),
                rng.random_range(-2.0..2.0),
                rng.random_range(-2.0..2.0),
            );
            let xi = Twist::new(v, dir * angle);
            let (a, b) = (fast_exp(&xi), Pose::exp(&xi));
            let dq = (a.rotation - b.rotation).length();
            let dp = (a.translation - b.translation).length() / v.length();
            // `place` against Pose's renormalising product, from a random reference.
            let axis = glam::DVec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            );
            let reference = Pose::exp(&Twist::new(glam::DVec3::new(v.y, v.z, v.x), axis * 3.0));
            let (c, d) = (place(&reference, &xi), reference * Pose::exp(&xi));
            let dc = (c.rotation - d.rotation).length() + (c.rotation.length() - 1.0).abs();
            let dt = (c.translation - d.translation).length() / (1.0 + v.length());
            worst = worst.max(dq).max(dp).max(dc).max(dt);
        }
        println!("fast_exp against Pose::exp: {worst:e}");
        assert!(worst <= FAST_EXP_REL, "{worst:e}");
    }

    #[test]
    fn parallel_update_is_bit_identical_and_matches_serial_statics() {
        let m = crate::scenes::helix(100).build().unwrap();
        let q = Configuration::rest(&m);
        let model = ReducedModel::build(&m, &q, &[], &ConstructOptions::default()).unwrap();
        // A displacement produced by a static wrench: then ξ_l = T_l K C w = T_l w.
        let w: Vec<f64> = (0..6)
            .map(|k| [3.0, -2.0, 1.0, 0.2, 0.1, -0.3][k])
            .collect();
        let xi: Vec<f64> = (0..6)
            .map(|r| (0..6).map(|c| model.compliance[(r, c)] * w[c]).sum())
            .collect();
        let mut reference = vec![Pose::IDENTITY; model.internal.len()];
        for (k, p) in reference.iter_mut().enumerate() {
            let xi_l = link_twist(&model, k, &equivalent_wrenches(&model, &xi));
            *p = place(&model.internal_reference[k], &xi_l);
        }
        for threads in [1, 2, 3, 7] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let mut out = vec![Pose::IDENTITY; model.internal.len()];
            pool.install(|| update_internal_links(&model, &xi, &Pose::IDENTITY, &mut out));
            assert_eq!(bits(&out), bits(&reference), "{threads} threads");
        }
        // Against the full linearised statics: every internal link's twist.
        let lin = LinearStatics::new(&m, &q, Tsvd::default()).unwrap();
        let full = lin.link_twists(
            &m.end_effectors,
            &[impulse_geom::Wrench::from_array(core::array::from_fn(
                |k| w[k],
            ))],
        );
        let wk = equivalent_wrenches(&model, &xi);
        let mut worst = 0.0_f64;
        let mut size = 0.0_f64;
        for (k, &l) in model.internal.iter().enumerate() {
            let d = link_twist(&model, k, &wk) - full[l];
            worst = worst.max(d.v.abs().max_element().max(d.w.abs().max_element()));
            size = size.max(
                full[l]
                    .v
                    .abs()
                    .max_element()
                    .max(full[l].w.abs().max_element()),
            );
        }
        println!(
            "helix-100 internal links vs linearised full statics: {:.2e} relative",
            worst / size
        );
        assert!(worst <= 1e-9 * size);
    }
}
