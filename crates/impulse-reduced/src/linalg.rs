//! Dense linear algebra on faer matrices: the truncated SVD of FORK⁻¹S eq. 9 (pseudo-inverse
//! with rank), null spaces, and 6×6 block access to large matrices.

use faer::{Mat, MatRef};
use impulse_geom::Mat6;

use crate::error::Error;

/// Truncated-SVD threshold (FORK⁻¹S §3.2, eq. 9): singular values at or below
/// `factor · max(m, n) · σ_max · ε_mach` count as zero — or, when [`Tsvd::relative`] is set
/// (`impulse reduce --tsvd`), at or below `τ · σ_max`.
///
/// **Choosing it** (docs/forks.md, "Rank and conditioning"): eq. 9 bounds the round-off of one
/// SVD; the reduced matrices carry the round-off of the whole walk, and a direction whose
/// compliance is below that cannot be resolved at all. The default (eq. 9 times
/// [`crate::tol::TSVD_FACTOR`], ~1.3e-13 relative for one end effector) sits just above it.
/// Raise τ to treat nearly rigid directions as rigid (a near-singular configuration: the
/// report names what is dropped and bounds what it changes, at most τ of the largest
/// compliance); lowering it below the default cannot recover a direction the walk cannot
/// resolve (`ReducedModel::build` refuses that, naming the direction's singular value).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Tsvd {
    /// Factor on eq. 9 (1 is the paper's formula; see [`crate::tol::TSVD_FACTOR`]); used
    /// unless [`Tsvd::relative`] is set.
    pub factor: f64,
    /// A relative threshold τ replacing eq. 9: singular values at or below `τ · σ_max` are
    /// dropped. Set through [`Tsvd::with_relative`], which checks `0 < τ < 1`.
    pub relative: Option<f64>,
}

impl Default for Tsvd {
    fn default() -> Self {
        Tsvd {
            factor: crate::tol::TSVD_FACTOR,
            relative: None,
        }
    }
}

impl Tsvd {
    /// A relative threshold τ (`impulse reduce --tsvd`).
    ///
    /// # Errors
    /// [`Error::OutOfRange`] unless τ is a finite number strictly between 0 and 1.
    pub fn with_relative(tau: f64) -> Result<Self, Error> {
        if tau.is_finite() && tau > 0.0 && tau < 1.0 {
            Ok(Tsvd {
                relative: Some(tau),
                ..Tsvd::default()
            })
        } else {
            Err(Error::OutOfRange {
                owner: "truncated SVD".to_owned(),
                field: "relative threshold",
                reason: format!(
                    "is {tau}; it must be a number strictly between 0 and 1 (singular values \
                     at or below that fraction of the largest are dropped)"
                ),
            })
        }
    }

    /// The threshold relative to `σ_max` for an `m × n` matrix: τ, or eq. 9's
    /// `factor · max(m, n) · ε_mach`.
    #[must_use]
    pub fn relative_threshold(&self, m: usize, n: usize) -> f64 {
        // FORK⁻¹S eq. 9: ε = max(m, n)·‖A‖·ε_machine, scaled by `factor`.
        self.relative
            .unwrap_or(self.factor * (m.max(n) as f64) * f64::EPSILON)
    }

    /// The absolute threshold for an `m × n` matrix whose largest singular value is `sigma_max`
    /// (eq. 9, or τ·σ_max).
    #[must_use]
    pub fn threshold(&self, m: usize, n: usize, sigma_max: f64) -> f64 {
        self.relative_threshold(m, n) * sigma_max
    }
}

/// A pseudo-inverse from a truncated SVD.
#[derive(Clone, Debug)]
pub struct Pinv {
    /// `V Σ⁺ Uᵀ` with the singular values at or below the threshold dropped.
    pub inverse: Mat<f64>,
    /// Number of singular values kept.
    pub rank: usize,
    /// The threshold used.
    pub threshold: f64,
    /// Every singular value, descending.
    pub singular: Vec<f64>,
}

/// Truncated-SVD pseudo-inverse of `a` (FORK⁻¹S §3.1–3.2).
///
/// # Errors
/// [`Error::LinearAlgebra`] if `a` has a non-finite entry or the SVD fails.
pub fn pinv(a: MatRef<'_, f64>, tsvd: Tsvd) -> Result<Pinv, Error> {
    pinv_scaled(a, tsvd, 0.0)
}

/// As [`pinv`], with the `‖A‖` of eq. 9 taken as `max(σ_max, scale)`: `scale` is the size of
/// the inputs `a` was computed from, for matrices that are differences of larger ones (a
/// constrained compliance is a compliance minus a correction; when the constraint locks every
/// direction the result is pure round-off of the size `ε·scale`, which a threshold relative to
/// its own σ_max would keep).
///
/// # Errors
/// As [`pinv`].
pub fn pinv_scaled(a: MatRef<'_, f64>, tsvd: Tsvd, scale: f64) -> Result<Pinv, Error> {
    let (m, n) = (a.nrows(), a.ncols());
    if m == 0 || n == 0 {
        return Ok(Pinv {
            inverse: Mat::zeros(n, m),
            rank: 0,
            threshold: 0.0,
            singular: Vec::new(),
        });
    }
    check_finite(a)?;
    let svd = a
        .svd()
        .map_err(|e| Error::LinearAlgebra(format!("SVD of a {m}×{n} matrix: {e:?}")))?;
    let (u, s, v) = (svd.U(), svd.S(), svd.V());
    let k = m.min(n);
    let sigma_max = (0..k).fold(0.0_f64, |acc, i| acc.max(s[i]));
    let threshold = tsvd.threshold(m, n, sigma_max.max(scale));
    let mut inverse = Mat::<f64>::zeros(n, m);
    let mut rank = 0;
    for i in 0..k {
        if s[i] > threshold {
            rank += 1;
            let inv = 1.0 / s[i];
            let vi = column(v, i);
            for c in 0..m {
                let uc = u[(c, i)] * inv;
                if uc != 0.0 {
                    for (x, &y) in inverse.col_as_slice_mut(c).iter_mut().zip(&vi) {
                        *x += y * uc;
                    }
                }
            }
        }
    }
    Ok(Pinv {
        inverse,
        rank,
        threshold,
        singular: descending((0..k).map(|i| s[i]).collect()),
    })
}

/// `v` sorted descending (faer returns singular values in non-increasing order already;
/// sorted here so that no caller depends on it).
fn descending(mut v: Vec<f64>) -> Vec<f64> {
    v.sort_by(|a, b| b.total_cmp(a));
    v
}

/// Pseudo-inverse of the symmetric positive semi-definite `a` truncated to exactly `r`
/// singular values, after checking that the spectrum has a clear gap there: `σ_r` above the
/// eq. 9 threshold (with `‖A‖ = max(σ_max, scale)`, see [`pinv_scaled`]) and `σ_{r+1}` at most
/// `gap · σ_r` (for `r = 0`, `σ_1` at most `gap · scale`). Returns the inverse and the singular values; on a failed check, the
/// [`Error::Rank`] names `at`.
///
/// # Errors
/// [`Error::Rank`] when the spectrum does not support rank `r`; [`Error::LinearAlgebra`] as
/// [`pinv`].
pub fn pinv_rank(
    a: MatRef<'_, f64>,
    r: usize,
    tsvd: Tsvd,
    scale: f64,
    gap: f64,
    at: &str,
) -> Result<Pinv, Error> {
    let (m, n) = (a.nrows(), a.ncols());
    check_finite(a)?;
    if m == 0 || n == 0 {
        return Ok(Pinv {
            inverse: Mat::zeros(n, m),
            rank: 0,
            threshold: 0.0,
            singular: Vec::new(),
        });
    }
    let svd = a
        .svd()
        .map_err(|e| Error::LinearAlgebra(format!("SVD of a {m}×{n} matrix: {e:?}")))?;
    let (u, s, v) = (svd.U(), svd.S(), svd.V());
    let k = m.min(n);
    let sv: Vec<f64> = (0..k).map(|i| s[i]).collect();
    let threshold = tsvd.threshold(m, n, sv.iter().fold(scale, |acc, &x| acc.max(x)));
    let found = sv.iter().filter(|&&x| x > threshold).count();
    let ok_low = r == 0 || (r <= k && sv[r - 1] > threshold);
    // Rank 0 (a locked mechanism): everything left must be negligible against the inputs.
    let ok_gap = r >= k
        || r == 0 && sv[0] <= threshold.max(gap * scale)
        || r > 0 && sv[r] <= gap * sv[r - 1];
    if !(ok_low && ok_gap) {
        return Err(Error::Rank {
            at: at.to_owned(),
            found,
            expected: r,
            tolerance: threshold,
        });
    }
    let mut inverse = Mat::<f64>::zeros(n, m);
    for i in 0..r {
        let inv = 1.0 / sv[i];
        let vi = column(v, i);
        for c in 0..m {
            let uc = u[(c, i)] * inv;
            for (x, &y) in inverse.col_as_slice_mut(c).iter_mut().zip(&vi) {
                *x += y * uc;
            }
        }
    }
    Ok(Pinv {
        inverse,
        rank: r,
        threshold,
        singular: sv,
    })
}

/// Column `i` of `a`, copied out once so that the pseudo-inverses' inner loops run over slices
/// (the same products and sums as indexing element by element, without faer's per-element
/// index calls, which are not inlined in the test profile).
fn column(a: MatRef<'_, f64>, i: usize) -> Vec<f64> {
    a.col(i).iter().copied().collect()
}

/// Numerical rank of `a` under the threshold of `tsvd`.
///
/// # Errors
/// As [`pinv`].
pub fn rank(a: MatRef<'_, f64>, tsvd: Tsvd) -> Result<usize, Error> {
    rank_scaled(a, tsvd, 0.0)
}

/// As [`rank`], with `‖A‖ = max(σ_max, scale)` (see [`pinv_scaled`]).
///
/// # Errors
/// As [`pinv`].
pub fn rank_scaled(a: MatRef<'_, f64>, tsvd: Tsvd, scale: f64) -> Result<usize, Error> {
    let (m, n) = (a.nrows(), a.ncols());
    if m == 0 || n == 0 {
        return Ok(0);
    }
    check_finite(a)?;
    let s = a
        .singular_values()
        .map_err(|e| Error::LinearAlgebra(format!("singular values: {e:?}")))?;
    let sigma_max = s.iter().fold(0.0_f64, |acc, &x| acc.max(x));
    let threshold = tsvd.threshold(m, n, sigma_max.max(scale));
    Ok(s.iter().filter(|&&x| x > threshold).count())
}

/// An orthonormal basis of the null space of `a` (columns), from its full SVD, with the
/// threshold of `tsvd`. An empty `a` (no rows) gives the identity.
///
/// # Errors
/// As [`pinv`].
pub fn null_space(a: MatRef<'_, f64>, tsvd: Tsvd) -> Result<Mat<f64>, Error> {
    let (m, n) = (a.nrows(), a.ncols());
    if m == 0 {
        return Ok(Mat::identity(n, n));
    }
    check_finite(a)?;
    let svd = a
        .svd()
        .map_err(|e| Error::LinearAlgebra(format!("SVD of a {m}×{n} matrix: {e:?}")))?;
    let (s, v) = (svd.S(), svd.V());
    let k = m.min(n);
    let sigma_max = (0..k).fold(0.0_f64, |acc, i| acc.max(s[i]));
    let threshold = tsvd.threshold(m, n, sigma_max);
    let r = (0..k).filter(|&i| s[i] > threshold).count();
    Ok(Mat::from_fn(n, n - r, |i, j| v[(i, r + j)]))
}

fn check_finite(a: MatRef<'_, f64>) -> Result<(), Error> {
    for j in 0..a.ncols() {
        for i in 0..a.nrows() {
            if !a[(i, j)].is_finite() {
                return Err(Error::LinearAlgebra(format!(
                    "entry ({i}, {j}) of a {}×{} matrix is not finite",
                    a.nrows(),
                    a.ncols()
                )));
            }
        }
    }
    Ok(())
}

/// The 6×6 block of `a` at block row `bi`, block column `bj`.
#[must_use]
pub fn block(a: MatRef<'_, f64>, bi: usize, bj: usize) -> Mat6 {
    let mut rows = [[0.0; 6]; 6];
    for (r, row) in rows.iter_mut().enumerate() {
        for (c, x) in row.iter_mut().enumerate() {
            *x = a[(6 * bi + r, 6 * bj + c)];
        }
    }
    Mat6::from_rows(rows)
}

/// Writes `m` into the 6×6 block of `a` at block row `bi`, block column `bj`.
pub fn set_block(a: &mut Mat<f64>, bi: usize, bj: usize, m: &Mat6) {
    let rows = m.to_rows();
    for (r, row) in rows.iter().enumerate() {
        for (c, x) in row.iter().enumerate() {
            a[(6 * bi + r, 6 * bj + c)] = *x;
        }
    }
}

/// A 6×6 block as a faer matrix.
#[must_use]
pub fn to_faer(m: &Mat6) -> Mat<f64> {
    let rows = m.to_rows();
    Mat::from_fn(6, 6, |r, c| rows[r][c])
}

/// Largest absolute entry of `a` (0 for an empty matrix).
#[must_use]
pub fn max_abs(a: MatRef<'_, f64>) -> f64 {
    let mut m = 0.0_f64;
    for j in 0..a.ncols() {
        for i in 0..a.nrows() {
            m = m.max(a[(i, j)].abs());
        }
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::rngs::Xoshiro256PlusPlus;
    use rand::{RngExt, SeedableRng};

    /// Moore–Penrose identities hold to a few hundred ulp of the conditioned products.
    const PENROSE_TOL: f64 = 1e-12;

    /// A random `m × n` matrix of rank `r` with singular values spread over 6 decades.
    fn low_rank(rng: &mut Xoshiro256PlusPlus, m: usize, n: usize, r: usize) -> Mat<f64> {
        let mut a = Mat::<f64>::zeros(m, n);
        for k in 0..r {
            let s = 10f64.powf(rng.random_range(-3.0..3.0));
            let u: Vec<f64> = (0..m).map(|_| rng.random_range(-1.0..1.0)).collect();
            let v: Vec<f64> = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();
            let _ = k;
            for i in 0..m {
                for j in 0..n {
                    a[(i, j)] += s * u[i] * v[j];
                }
            }
        }
        a
    }

    /// The pseudo-inverse satisfies the four Penrose conditions and finds the rank, on random
    /// rank-deficient matrices; the null space is orthonormal and annihilated by `a`.
    #[test]
    fn pinv_penrose_rank_and_null_space() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(11);
        for case in 0..200 {
            let m = 1 + case % 13;
            let n = 1 + (case * 7) % 11;
            let r = rng.random_range(0..=m.min(n));
            let a = low_rank(&mut rng, m, n, r);
            let p = pinv(a.as_ref(), Tsvd::default()).unwrap();
            assert_eq!(p.rank, r, "case {case}: {m}×{n} of rank {r}");
            assert_eq!(rank(a.as_ref(), Tsvd::default()).unwrap(), r);
            let x = &p.inverse;
            let scale = max_abs(a.as_ref()).max(f64::MIN_POSITIVE);
            let xs = max_abs(x.as_ref()).max(f64::MIN_POSITIVE);
            let axa = &a * x * &a - &a;
            let xax = x * &a * x - x;
            let ax = &a * x;
            let xa = x * &a;
            let cond = scale * xs;
            assert!(max_abs(axa.as_ref()) <= PENROSE_TOL * scale * cond);
            assert!(max_abs(xax.as_ref()) <= PENROSE_TOL * xs * cond);
            assert!(max_abs((&ax - ax.transpose()).as_ref()) <= PENROSE_TOL * cond);
            assert!(max_abs((&xa - xa.transpose()).as_ref()) <= PENROSE_TOL * cond);
            let z = null_space(a.as_ref(), Tsvd::default()).unwrap();
            assert_eq!(z.ncols(), n - r);
            assert!(max_abs((&a * &z).as_ref()) <= PENROSE_TOL * scale);
            let ztz = z.transpose() * &z - Mat::<f64>::identity(n - r, n - r);
            assert!(max_abs(ztz.as_ref()) <= PENROSE_TOL);
        }
        let bad = Mat::from_fn(2, 2, |i, j| if i == j { f64::NAN } else { 0.0 });
        assert!(matches!(
            pinv(bad.as_ref(), Tsvd::default()),
            Err(Error::LinearAlgebra(_))
        ));
    }
}
