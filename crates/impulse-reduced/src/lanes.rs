//! The arithmetic of [`crate::internal::InternalLinks`] on [`LANES`] links at once, written
//! once against [`Ops`] and run on AVX vectors where the processor has them (chosen at run
//! time through `pulp`, safe), on plain arrays otherwise. Both do the same IEEE operations in
//! the same order (multiplies and adds, never fused), so every link gets the same bits either
//! way, and a lane's result never depends on the other lanes of its group.

use glam::{DQuat, DVec3};
use impulse_geom::Pose;

use crate::internal::{
    EXP_POLY_ANGLE, EXP_REDUCED_ANGLE, LANES, SERIES_B, SERIES_C, SERIES_COS, SERIES_K, SERIES_SIN,
    exp_coefficients_trig,
};

/// One value per lane of a group.
pub(crate) type Lanes = [f64; LANES];

/// Lane-wise arithmetic on a vector type `V` of [`LANES`] f64.
pub(crate) trait Ops: Copy {
    /// The vector.
    type V: Copy;
    /// Every lane `x`.
    fn splat(self, x: f64) -> Self::V;
    /// From an array.
    fn load(self, a: &Lanes) -> Self::V;
    /// To an array.
    fn store(self, v: Self::V) -> Lanes;
    /// `a + b`.
    fn add(self, a: Self::V, b: Self::V) -> Self::V;
    /// `a − b`.
    fn sub(self, a: Self::V, b: Self::V) -> Self::V;
    /// `a · b`.
    fn mul(self, a: Self::V, b: Self::V) -> Self::V;
    /// `a / b` (correctly rounded).
    fn div(self, a: Self::V, b: Self::V) -> Self::V;
    /// `√a` (correctly rounded).
    fn sqrt(self, a: Self::V) -> Self::V;
}

/// Plain arrays (any processor).
#[derive(Copy, Clone)]
pub(crate) struct Portable;

impl Ops for Portable {
    type V = Lanes;
    #[inline(always)]
    fn splat(self, x: f64) -> Lanes {
        [x; LANES]
    }
    #[inline(always)]
    fn load(self, a: &Lanes) -> Lanes {
        *a
    }
    #[inline(always)]
    fn store(self, v: Lanes) -> Lanes {
        v
    }
    #[inline(always)]
    fn add(self, a: Lanes, b: Lanes) -> Lanes {
        core::array::from_fn(|l| a[l] + b[l])
    }
    #[inline(always)]
    fn sub(self, a: Lanes, b: Lanes) -> Lanes {
        core::array::from_fn(|l| a[l] - b[l])
    }
    #[inline(always)]
    fn mul(self, a: Lanes, b: Lanes) -> Lanes {
        core::array::from_fn(|l| a[l] * b[l])
    }
    #[inline(always)]
    fn div(self, a: Lanes, b: Lanes) -> Lanes {
        core::array::from_fn(|l| a[l] / b[l])
    }
    #[inline(always)]
    fn sqrt(self, a: Lanes) -> Lanes {
        core::array::from_fn(|l| a[l].sqrt())
    }
}

#[cfg(target_arch = "x86_64")]
impl Ops for pulp::x86::V3 {
    type V = pulp::f64x4;
    #[inline(always)]
    fn splat(self, x: f64) -> pulp::f64x4 {
        self.splat_f64x4(x)
    }
    #[inline(always)]
    fn load(self, a: &Lanes) -> pulp::f64x4 {
        pulp::f64x4(a[0], a[1], a[2], a[3])
    }
    #[inline(always)]
    fn store(self, v: pulp::f64x4) -> Lanes {
        [v.0, v.1, v.2, v.3]
    }
    #[inline(always)]
    fn add(self, a: pulp::f64x4, b: pulp::f64x4) -> pulp::f64x4 {
        self.add_f64x4(a, b)
    }
    #[inline(always)]
    fn sub(self, a: pulp::f64x4, b: pulp::f64x4) -> pulp::f64x4 {
        self.sub_f64x4(a, b)
    }
    #[inline(always)]
    fn mul(self, a: pulp::f64x4, b: pulp::f64x4) -> pulp::f64x4 {
        self.mul_f64x4(a, b)
    }
    #[inline(always)]
    fn div(self, a: pulp::f64x4, b: pulp::f64x4) -> pulp::f64x4 {
        self.div_f64x4(a, b)
    }
    #[inline(always)]
    fn sqrt(self, a: pulp::f64x4) -> pulp::f64x4 {
        self.sqrt_f64x4(a)
    }
}

/// `Σ coeffs[j] x^j` by Horner's rule, in every lane (the same order as
/// [`crate::internal`]'s scalar `horner`).
#[inline(always)]
fn horner<O: Ops, const N: usize>(o: O, coeffs: &[f64; N], x: O::V) -> O::V {
    let mut acc = o.splat(0.0);
    for &c in coeffs.iter().rev() {
        acc = o.add(o.mul(acc, x), o.splat(c));
    }
    acc
}

/// `a × b` lane-wise.
#[inline(always)]
fn cross<O: Ops>(o: O, a: &[O::V; 3], b: &[O::V; 3]) -> [O::V; 3] {
    [
        o.sub(o.mul(a[1], b[2]), o.mul(a[2], b[1])),
        o.sub(o.mul(a[2], b[0]), o.mul(a[0], b[2])),
        o.sub(o.mul(a[0], b[1]), o.mul(a[1], b[0])),
    ]
}

/// `π/2` in two parts (Cody–Waite): `PIO2_HI` has 31 significant bits, so `n · PIO2_HI` is
/// exact for the quadrant counts `n < 2²²` met below [`EXP_REDUCED_ANGLE`], and
/// `PIO2_HI + PIO2_LO` is `π/2` to about 2⁻⁸⁵.
const PIO2_HI: f64 = 1.570_796_326_734_125_6;
/// The rest of `π/2` after [`PIO2_HI`].
const PIO2_LO: f64 = 6.077_100_506_506_192e-11;

/// The exponential's coefficients `(k, c, b)` by trigonometry, lane-wise: for lanes with
/// `θ² = t2` from [`EXP_POLY_ANGLE`]² up to [`EXP_REDUCED_ANGLE`]², `sin` and `cos` of the half
/// angle by reduction to `r ∈ [−π/4, π/4]` and Taylor series in `r²` (truncation below 1e-19);
/// above, libm's `sin_cos` ([`exp_coefficients_trig`]); below, the `series` values given.
#[inline(always)]
fn trig_lanes<O: Ops>(o: O, t2: O::V, series: (O::V, O::V, O::V)) -> (O::V, O::V, O::V) {
    let theta = o.sqrt(t2);
    let half = o.mul(o.splat(0.5), theta);
    // Quadrant n = round(x / (π/2)) and r = x − n π/2 per lane.
    let xa = o.store(half);
    let mut quadrant = [0_u8; LANES];
    let mut r = [0.0; LANES];
    for l in 0..LANES {
        let n = (xa[l] * core::f64::consts::FRAC_2_PI).round();
        r[l] = (xa[l] - n * PIO2_HI) - n * PIO2_LO;
        // n ≥ 0 and below 2²² here (or the lane is recomputed below): exact as an integer.
        quadrant[l] = (n as u32 % 4) as u8;
    }
    let r = o.load(&r);
    let r2 = o.mul(r, r);
    let (sr, cr) = (
        o.store(o.mul(r, horner(o, &SERIES_SIN, r2))),
        o.store(horner(o, &SERIES_COS, r2)),
    );
    let (mut sh, mut ch) = ([0.0; LANES], [0.0; LANES]);
    for l in 0..LANES {
        (sh[l], ch[l]) = match quadrant[l] {
            0 => (sr[l], cr[l]),
            1 => (cr[l], -sr[l]),
            2 => (-sr[l], -cr[l]),
            _ => (-cr[l], sr[l]),
        };
    }
    let (sh, ch) = (o.load(&sh), o.load(&ch));
    // k = sin(θ/2)/θ, c = cos(θ/2), b = (θ − sin θ)/θ³ with sin θ = 2 sin(θ/2) cos(θ/2).
    let k = o.store(o.div(sh, theta));
    let b = o.store(o.div(
        o.sub(theta, o.mul(o.mul(o.splat(2.0), sh), ch)),
        o.mul(t2, theta),
    ));
    let c = o.store(ch);
    let (ks, cs, bs) = (o.store(series.0), o.store(series.1), o.store(series.2));
    let t2a = o.store(t2);
    let (mut ko, mut co, mut bo) = ([0.0; LANES], [0.0; LANES], [0.0; LANES]);
    for l in 0..LANES {
        (ko[l], co[l], bo[l]) = if t2a[l] < EXP_POLY_ANGLE * EXP_POLY_ANGLE {
            (ks[l], cs[l], bs[l])
        } else if t2a[l] < EXP_REDUCED_ANGLE * EXP_REDUCED_ANGLE {
            (k[l], c[l], b[l])
        } else {
            exp_coefficients_trig(t2a[l])
        };
    }
    (o.load(&ko), o.load(&co), o.load(&bo))
}

/// Poses `H_l exp(ξ'_l)` of one group of links (as many as `out` holds): `map` is the group's
/// folded twist maps (`xi.len()` columns of six rows), `h` its reference poses (quaternion
/// `x, y, z, w`, translation `x, y, z`).
#[inline(always)]
pub(crate) fn place_group<O: Ops>(
    o: O,
    map: &[Lanes],
    xi: &[f64],
    h: &[Lanes; 7],
    out: &mut [Pose],
) {
    // ξ'_l = Ad_{R_l} T_l K ξ (eq. 22), six running sums per lane.
    let mut t = [o.splat(0.0); 6];
    for (col, &x) in map.chunks_exact(6).zip(xi) {
        let x = o.splat(x);
        for (acc, m) in t.iter_mut().zip(col) {
            *acc = o.add(*acc, o.mul(o.load(m), x));
        }
    }
    let v = [t[0], t[1], t[2]];
    let w = [t[3], t[4], t[5]];
    let t2 = o.add(
        o.add(o.mul(w[0], w[0]), o.mul(w[1], w[1])),
        o.mul(w[2], w[2]),
    );
    // Exponential coefficients (eq. 6, MLS eq. 2.36): the series in every lane; if a lane turns
    // past EXP_POLY_ANGLE, the trigonometric form in every lane and a choice per lane.
    let (mut k, mut c, mut b) = (
        horner(o, &SERIES_K, t2),
        horner(o, &SERIES_C, t2),
        horner(o, &SERIES_B, t2),
    );
    let t2a = o.store(t2);
    if t2a.iter().any(|&x| x >= EXP_POLY_ANGLE * EXP_POLY_ANGLE) {
        (k, c, b) = trig_lanes(o, t2, (k, c, b));
    }
    let a = o.mul(o.mul(o.splat(2.0), k), k);
    // Translation (MLS eq. 2.36): V(ω') v' + p_l = v' + a ω'×v' + b ω'×(ω'×v') + p_l.
    let wv = cross(o, &w, &v);
    let wwv = cross(o, &w, &wv);
    let place = |i: usize| {
        let moved = o.add(o.add(v[i], o.mul(wv[i], a)), o.mul(wwv[i], b));
        o.store(o.add(moved, o.load(&h[4 + i])))
    };
    let p = [place(0), place(1), place(2)];
    // Rotation (eq. 6): exp(ω') q_l with exp(ω') = (k ω', c) (Hamilton product).
    let (ex, ey, ez) = (o.mul(w[0], k), o.mul(w[1], k), o.mul(w[2], k));
    let (rx, ry, rz, rw) = (o.load(&h[0]), o.load(&h[1]), o.load(&h[2]), o.load(&h[3]));
    let q = [
        o.store(o.sub(
            o.add(o.add(o.mul(c, rx), o.mul(ex, rw)), o.mul(ey, rz)),
            o.mul(ez, ry),
        )),
        o.store(o.add(
            o.add(o.sub(o.mul(c, ry), o.mul(ex, rz)), o.mul(ey, rw)),
            o.mul(ez, rx),
        )),
        o.store(o.add(
            o.sub(o.add(o.mul(c, rz), o.mul(ex, ry)), o.mul(ey, rx)),
            o.mul(ez, rw),
        )),
        o.store(o.sub(
            o.sub(o.sub(o.mul(c, rw), o.mul(ex, rx)), o.mul(ey, ry)),
            o.mul(ez, rz),
        )),
    ];
    for (l, pose) in out.iter_mut().enumerate() {
        *pose = Pose {
            rotation: DQuat::from_xyzw(q[0][l], q[1][l], q[2][l], q[3][l]),
            translation: DVec3::new(p[0][l], p[1][l], p[2][l]),
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    /// Absolute agreement of the reduced half-angle sine and cosine with libm's `sin_cos`
    /// (both within an ulp or two of the exact values, which are at most 1), and of
    /// `θ − sin θ = θ³ b` relative to `max(1, θ)`.
    const TRIG_ABS: f64 = 1e-15;

    /// `sin(θ/2)`, `cos(θ/2)` and `b` from [`trig_lanes`] against libm, θ from 1e-3 to 1e7
    /// rad (the series, reduced and libm lanes, mixed in one group), and the AVX vectors
    /// against plain arrays bit for bit where the processor has AVX.
    #[test]
    fn trig_lanes_match_libm_and_portable_equals_avx() {
        let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(8);
        let mut worst = 0.0_f64;
        for _ in 0..50_000 {
            let theta: Lanes = core::array::from_fn(|_| 10f64.powf(rng.random_range(-3.0..7.0)));
            let t2 = theta.map(|t| t * t);
            let series = (
                t2.map(|x| crate::internal::horner(&SERIES_K, x)),
                t2.map(|x| crate::internal::horner(&SERIES_C, x)),
                t2.map(|x| crate::internal::horner(&SERIES_B, x)),
            );
            let (k, c, b) = trig_lanes(Portable, t2, series);
            for l in 0..LANES {
                let (s, co) = (0.5 * theta[l]).sin_cos();
                let (_, _, bl) = exp_coefficients_trig(t2[l]);
                // b carries the cancellation of θ − sin θ: compare θ³ b = θ − sin θ, whose
                // round-off is relative to θ.
                let db = if theta[l] >= EXP_POLY_ANGLE {
                    (b[l] - bl).abs() * t2[l] * theta[l] / theta[l].max(1.0)
                } else {
                    0.0
                };
                worst = worst
                    .max((k[l] * theta[l] - s).abs())
                    .max((c[l] - co).abs())
                    .max(db);
            }
            #[cfg(target_arch = "x86_64")]
            if let Some(simd) = pulp::x86::V3::try_new() {
                let v = simd.vectorize(|| {
                    let s = (
                        simd.load(&series.0),
                        simd.load(&series.1),
                        simd.load(&series.2),
                    );
                    let (k, c, b) = trig_lanes(simd, simd.load(&t2), s);
                    (simd.store(k), simd.store(c), simd.store(b))
                });
                let bits = |x: Lanes| x.map(f64::to_bits);
                assert_eq!(bits(v.0), bits(k));
                assert_eq!(bits(v.1), bits(c));
                assert_eq!(bits(v.2), bits(b));
            }
        }
        println!("reduced trigonometry against libm: {worst:.1e}");
        assert!(worst <= TRIG_ABS, "{worst:e}");
    }
}
