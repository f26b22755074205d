//! Jacobi elliptic functions and the complete elliptic integral of the first kind, for the
//! closed form of the free asymmetric top (`free_top.rs`).
//!
//! K by the arithmetic–geometric mean, the functions by the descending Landen transformation
//! (Abramowitz & Stegun, *Handbook of Mathematical Functions*, 17.6 and 16.12): quadratic
//! convergence, five to seven levels for any parameter short of 1. The parameter is passed as its complement `mc = 1 − m` (m = k²) as well, since
//! the callers compute it without cancellation and near m = 1 that is where the precision is.
//!
//! Must not know: bodies or rotations; numbers in, numbers out.

use std::f64::consts::PI;

/// The arithmetic–geometric mean's iteration stops when `|a − b|/2` falls to this fraction of
/// `a` (unit roundoff: the next iterate would not change `a`). Default `f64::EPSILON`.
const AGM_TOL: f64 = f64::EPSILON;

/// Guard on the number of AGM iterations and Landen levels (convergence is quadratic: about
/// six for any `mc ≥ 1e-300`, so this bound is never reached by finite input). Default `40`.
const AGM_MAX_ITER: usize = 40;

/// The complete elliptic integral of the first kind, K(m) = π / (2·AGM(1, √mc)) (A&S 17.6.1),
/// for the complementary parameter `mc = 1 − m` in (0, 1].
fn complete_k(mc: f64) -> f64 {
    let (mut a, mut b) = (1.0f64, mc.sqrt());
    for _ in 0..AGM_MAX_ITER {
        if (a - b).abs() <= AGM_TOL * a {
            break;
        }
        (a, b) = (0.5 * (a + b), (a * b).sqrt());
    }
    PI / (2.0 * a)
}

/// The descent stops when the parameter m = 1 − k′² of the current level falls below this;
/// there the first-order expansion in m (A&S 16.13.1–3) leaves an error O(m²). Default `1e-9`.
const LANDEN_FLOOR: f64 = 1e-9;

/// The Jacobi elliptic functions of one parameter m = 1 − `mc` (`0 < mc ≤ 1`), with the
/// descending Landen scale and the period computed once, for many arguments.
///
/// The functions by the descending Landen transformation (A&S 16.12.2–4): with k′ = √mc,
/// √μ = (1 − k′)/(1 + k′) and v = u/(1 + √μ),
/// sn(u|m) = (1 + √μ)·sn(v|μ)/D, cn(u|m) = cn(v|μ)·dn(v|μ)/D, dn(u|m) = (1 − √μ·sn²(v|μ))/D,
/// D = 1 + √μ·sn²(v|μ), applied until the parameter falls below [`LANDEN_FLOOR`], where sn,
/// cn, dn are sin, cos and 1 to first order in m (A&S 16.13.1–3). The next level's k′ is
/// 2√k′/(1 + k′), and 1 − √μ·sn² is formed as (1 − √μ) + √μ·cn² with 1 − √μ = 2k′/(1 + k′),
/// so that dn keeps its relative precision where it is small (near the quarter period with m
/// close to 1). An argument is first reduced by the period 4K of sn and cn.
#[derive(Clone, Copy, Debug)]
pub(super) struct Jacobi {
    /// √μ and 1 − √μ of each level, descending.
    levels: [(f64, f64); AGM_MAX_ITER],
    depth: usize,
    /// Π 1/(1 + √μ): the argument's scale at the deepest level.
    scale: f64,
    /// The deepest level's parameter (below [`LANDEN_FLOOR`]).
    m_deep: f64,
    /// The complete integral K(m).
    k: f64,
}

impl Jacobi {
    /// The scale for the complementary parameter `mc` in (0, 1].
    pub(super) fn new(mc: f64) -> Self {
        let mut levels = [(0.0f64, 0.0f64); AGM_MAX_ITER];
        let (mut depth, mut scale) = (0, 1.0);
        let mut kc = mc.min(1.0).sqrt();
        while depth < AGM_MAX_ITER && (1.0 - kc) * (1.0 + kc) >= LANDEN_FLOOR {
            let root_mu = (1.0 - kc) / (1.0 + kc);
            levels[depth] = (root_mu, 2.0 * kc / (1.0 + kc));
            depth += 1;
            scale /= 1.0 + root_mu;
            kc = 2.0 * kc.sqrt() / (1.0 + kc);
        }
        Self {
            levels,
            depth,
            scale,
            m_deep: (1.0 - kc) * (1.0 + kc),
            k: complete_k(mc),
        }
    }

    /// The complete integral of the first kind, K(m): sn and cn have period 4K, dn 2K.
    pub(super) fn k(&self) -> f64 {
        self.k
    }

    /// `(sn u, cn u, dn u)`.
    pub(super) fn eval(&self, u: f64) -> (f64, f64, f64) {
        let period = 4.0 * self.k;
        let v = (u - period * (u / period).round()) * self.scale;
        // The deepest level: sn(v|m) = sin v − ¼m(v − sin v cos v)cos v, cn(v|m) = cos v +
        // ¼m(v − sin v cos v)sin v, dn(v|m) = 1 − ½m·sin²v, to O(m²).
        let m = self.m_deep;
        let (sin, cos) = v.sin_cos();
        let drift = 0.25 * m * (v - sin * cos);
        let (mut sn, mut cn, mut dn) = (
            sin - drift * cos,
            cos + drift * sin,
            1.0 - 0.5 * m * sin * sin,
        );
        for &(root_mu, one_less) in self.levels[..self.depth].iter().rev() {
            let den = 1.0 + root_mu * sn * sn;
            (sn, cn, dn) = (
                (1.0 + root_mu) * sn / den,
                cn * dn / den,
                (one_less + root_mu * cn * cn) / den,
            );
        }
        (sn, cn, dn)
    }

    /// The argument τ in (−2K, 2K] with (sn τ, cn τ, dn τ) = (`sn`, `cn`, `dn`): the
    /// incomplete integral of the first kind F(φ|m) = sin φ·R_F(cos²φ, dn², 1) (DLMF 19.25.5)
    /// for the acute amplitude, continued by F(π − φ) = 2K − F(φ) and oddness. `dn` is passed,
    /// not formed as √(1 − m·sn²), for its precision near m = 1.
    pub(super) fn argument(&self, sn: f64, cn: f64, dn: f64) -> f64 {
        let acute = sn.abs() * carlson_rf(cn * cn, dn * dn, 1.0);
        let tau = if cn >= 0.0 {
            acute
        } else {
            2.0 * self.k - acute
        };
        tau.copysign(sn)
    }
}

/// The duplication stops when every argument is within this fraction of their mean; the
/// fifth-order series then leaves a relative error below 1e-16 (Carlson 1995, eq. 2.2, with
/// r = 1e-16: (3r)^(1/6) = 2.6e-3). Default `2e-3`.
const CARLSON_SPREAD: f64 = 2e-3;

/// Carlson's symmetric integral R_F(x, y, z) = ½∫₀^∞ dt/√((t+x)(t+y)(t+z)) (DLMF 19.16.1) for
/// non-negative arguments at most one of which is zero, by the duplication theorem
/// (DLMF 19.26.18) and the series of DLMF 19.36.1.
pub(super) fn carlson_rf(x: f64, y: f64, z: f64) -> f64 {
    let (mut x, mut y, mut z) = (x, y, z);
    let mut mean = (x + y + z) / 3.0;
    for _ in 0..AGM_MAX_ITER {
        let spread = (mean - x).abs().max((mean - y).abs()).max((mean - z).abs());
        if spread <= CARLSON_SPREAD * mean {
            break;
        }
        let (sx, sy, sz) = (x.sqrt(), y.sqrt(), z.sqrt());
        let lambda = sx * sy + sy * sz + sz * sx;
        (x, y, z) = (
            0.25 * (x + lambda),
            0.25 * (y + lambda),
            0.25 * (z + lambda),
        );
        mean = 0.25 * (mean + lambda);
    }
    let (dx, dy) = (1.0 - x / mean, 1.0 - y / mean);
    let dz = -dx - dy;
    let (e2, e3) = (dx * dy - dz * dz, dx * dy * dz);
    (1.0 - e2 / 10.0 + e3 / 14.0 + e2 * e2 / 24.0 - 3.0 * e2 * e3 / 44.0) / mean.sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// K against independent values (mpmath's `ellipk` at 30 digits: K(0) = π/2,
    /// K(0.5) = 1.854074677301372, K(0.9) = 2.578092113348173, K(0.99) = 3.695637362989874)
    /// and the logarithmic limit
    /// K ≈ ln(4/√mc) for mc → 0 (A&S 17.3.26, error O(mc·ln mc)).
    #[test]
    fn complete_integral_matches_the_tables() {
        for (m, k) in [
            (0.0, PI / 2.0),
            (0.5, 1.854_074_677_301_372),
            (0.9, 2.578_092_113_348_173),
            (0.99, 3.695_637_362_989_874),
        ] {
            let got = complete_k(1.0 - m);
            assert!((got - k).abs() < 1e-14 * k, "K({m}) = {got}, table {k}");
        }
        let mc: f64 = 1e-12;
        let limit = (4.0 / mc.sqrt()).ln();
        assert!((complete_k(mc) - limit).abs() < 1e-9);
    }

    /// sn, cn, dn against independent facts: sn² + cn² = 1 and dn² + m·sn² = 1; the quarter
    /// period values sn K = 1, cn K = 0, dn K = √mc; the limits m → 0 (sin, cos, 1) and
    /// m = 1 − 1e-14 (tanh, sech, sech, A&S 16.15); the derivatives sn' = cn·dn, cn' = −sn·dn,
    /// dn' = −m·sn·cn by central differences; and one independent value (mpmath's `ellipfun`
    /// at 30 digits: sn(0.5 | m = 0.5) = 0.470750473655657).
    #[test]
    fn jacobi_functions_satisfy_their_identities() {
        for mc in [1.0, 0.9, 0.5, 0.1, 1e-3, 1e-6] {
            let m = 1.0 - mc;
            for i in -40..=40 {
                let u = 0.37 * f64::from(i);
                let (s, c, d) = Jacobi::new(mc).eval(u);
                assert!((s * s + c * c - 1.0).abs() < 1e-14, "mc {mc} u {u}");
                assert!((d * d + m * s * s - 1.0).abs() < 1e-14, "mc {mc} u {u}");
                let h = 1e-5;
                let (sp, cp, dp) = Jacobi::new(mc).eval(u + h);
                let (sm, cm, dm) = Jacobi::new(mc).eval(u - h);
                let tol = 1e-8;
                assert!(
                    ((sp - sm) / (2.0 * h) - c * d).abs() < tol,
                    "sn' at {u}, {mc}"
                );
                assert!(
                    ((cp - cm) / (2.0 * h) + s * d).abs() < tol,
                    "cn' at {u}, {mc}"
                );
                assert!(
                    ((dp - dm) / (2.0 * h) + m * s * c).abs() < tol,
                    "dn' at {u}"
                );
            }
            let k = complete_k(mc);
            let (s, c, d) = Jacobi::new(mc).eval(k);
            assert!(
                (s - 1.0).abs() < 1e-14 && c.abs() < 1e-12,
                "quarter period, mc {mc}"
            );
            assert!((d - mc.sqrt()).abs() < 1e-12 * (1.0 + mc.sqrt()));
        }
        let (s, c, d) = Jacobi::new(0.5).eval(0.5);
        assert!(
            (s - 0.470_750_473_655_657).abs() < 1e-14,
            "sn(0.5|0.5) = {s}"
        );
        assert!((c - (1.0 - s * s).sqrt()).abs() < 1e-14 && d > c);
        let (s, c, d) = Jacobi::new(1e-14).eval(0.8);
        assert!((s - 0.8f64.tanh()).abs() < 1e-12 && (c - 1.0 / 0.8f64.cosh()).abs() < 1e-12);
        assert!((d - 1.0 / 0.8f64.cosh()).abs() < 1e-12);
    }

    /// R_F against Carlson's published values (computed again with mpmath's `elliprf`:
    /// R_F(1, 2, 0) = 1.31102877714606, R_F(2, 3, 4) = 0.584082841677152), and the argument
    /// τ recovered from sn, cn, dn: against mpmath's `ellipf` (F(1.2 | 0.7) =
    /// 1.42944843302276, F(0.3 | 0.999999) = 0.304603969603144), and `eval` of it giving
    /// back the values on every quadrant of four parameters.
    #[test]
    fn the_argument_inverts_the_functions() {
        assert!((carlson_rf(1.0, 2.0, 0.0) - 1.311_028_777_146_06).abs() < 1e-14);
        assert!((carlson_rf(2.0, 3.0, 4.0) - 0.584_082_841_677_152).abs() < 1e-14);
        for (phi, m, f) in [
            (1.2f64, 0.7, 1.429_448_433_022_76),
            (0.3, 0.999_999, 0.304_603_969_603_144),
        ] {
            let (sn, cn) = phi.sin_cos();
            let dn = (1.0 - m * sn * sn).sqrt();
            let got = Jacobi::new(1.0 - m).argument(sn, cn, dn);
            assert!((got - f).abs() < 1e-13, "F({phi}|{m}) = {got}, mpmath {f}");
        }
        for mc in [0.9, 0.3, 1e-3, 1e-6] {
            let k = complete_k(mc);
            for i in -19..=19 {
                let u = 2.0 * k * f64::from(i) / 20.0;
                let (sn, cn, dn) = Jacobi::new(mc).eval(u);
                let back = Jacobi::new(mc).argument(sn, cn, dn);
                assert!((back - u).abs() < 1e-13 * k, "mc {mc}: {u} → {back}");
            }
        }
    }
}
