//! Rank decisions and conditioning as first-class output (FORK⁻¹S §3.2, eq. 9; §4–5): what
//! every truncated SVD of a model's construction kept and dropped, how clear each cut was,
//! which end-effector directions the joints allow but the model treats as rigid, and how far
//! the model's matrices can be trusted.
//!
//! **How the end-effector rank is decided.** The compliance is `C = J_E C_θ J_Eᵀ = W Wᵀ` with
//! `W = J_E F`, `F Fᵀ = C_θ` (the joints' compliance-weighted motions,
//! [`crate::reference::LinearStatics::weighted_motions`]), so `σᵢ(C) = σᵢ(W)²`: dropping the
//! singular values of C at or below `τ σ₁(C)` is the same cut as dropping those of W at or
//! below `√τ σ₁(W)`. The cut is made on W, where a small singular value is computed to
//! ε·σ₁(W), not on the walk's C, where it carries the walk's round-off, ε·σ₁(C) = ε·σ₁(W)² —
//! a direction of relative compliance 1e-14 (joints nearly aligned to 1e-7) is invisible in C
//! but still seen in W. C is then truncated at that rank ([`compliance_rank`]), provided the
//! walk resolves its smallest kept singular value (above the measured round-off of C: its
//! difference from the Schur complement `J_E C_θ J_Eᵀ`).
//!
//! Directions the joints allow (W's singular values above eq. 9's round-off) but whose
//! compliance is at or below the threshold are **treated as rigid**: a constraint on the end
//! effectors' motion, applied to the accelerability and damping too (their Schur complement
//! on the remaining directions, [`constrain`]). What that changes in a static displacement
//! is at most `τ σ₁(C)·‖w‖` — τ of the largest compliance.

use core::fmt;

use faer::Mat;

use crate::error::Error;
use crate::linalg::{Tsvd, pinv_scaled};
use crate::tol;

/// What one truncated SVD of a construction did.
#[derive(Clone, Debug, PartialEq)]
pub struct RankReport {
    /// Which map: e.g. "end-effector compliance C", "merge at link `top`".
    pub map: String,
    /// Its size: rows.
    pub rows: usize,
    /// Its size: columns.
    pub cols: usize,
    /// Every singular value, descending.
    pub singular: Vec<f64>,
    /// The threshold: singular values at or below it were dropped (absolute).
    pub threshold: f64,
    /// Singular values kept.
    pub rank: usize,
}

impl RankReport {
    /// A report of `map` (`rows × cols`) from its singular values (any order), threshold and
    /// rank.
    #[must_use]
    pub fn new(
        map: impl Into<String>,
        (rows, cols): (usize, usize),
        mut singular: Vec<f64>,
        threshold: f64,
        rank: usize,
    ) -> Self {
        singular.sort_by(|a, b| b.total_cmp(a));
        RankReport {
            map: map.into(),
            rows,
            cols,
            singular,
            threshold,
            rank,
        }
    }

    /// The largest singular value σ₁ (0 for an empty map).
    #[must_use]
    pub fn largest(&self) -> f64 {
        self.singular.first().copied().unwrap_or(0.0)
    }

    /// `σ_{r+1}/σ_r`: how clear the cut is (0 when nothing was dropped or σ_{r+1} = 0; near 1
    /// when the cut falls inside a continuous spectrum). 0 for rank 0.
    #[must_use]
    pub fn gap(&self) -> f64 {
        match (self.rank, self.singular.get(self.rank)) {
            (0, _) | (_, None) => 0.0,
            (r, Some(&next)) => next / self.singular[r - 1],
        }
    }

    /// `σ₁/σ_r`, the condition number at the rank kept (1 for rank 0).
    #[must_use]
    pub fn condition(&self) -> f64 {
        if self.rank == 0 {
            1.0
        } else {
            self.largest() / self.singular[self.rank - 1]
        }
    }

    /// The threshold relative to σ₁ (0 for a zero map).
    #[must_use]
    pub fn relative_threshold(&self) -> f64 {
        let s = self.largest();
        if s > 0.0 { self.threshold / s } else { 0.0 }
    }

    /// The singular values around the cut, relative to σ₁: up to `k` of the smallest kept,
    /// then up to `k` of the largest dropped.
    #[must_use]
    pub fn around_cut(&self, k: usize) -> (Vec<f64>, Vec<f64>) {
        let s = self.largest();
        let rel = |x: &f64| if s > 0.0 { x / s } else { 0.0 };
        let kept = self.singular[self.rank.saturating_sub(k)..self.rank]
            .iter()
            .map(rel)
            .collect();
        let end = (self.rank + k).min(self.singular.len());
        let dropped = self.singular[self.rank..end].iter().map(rel).collect();
        (kept, dropped)
    }
}

impl fmt::Display for RankReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (kept, dropped) = self.around_cut(2);
        let list = |v: &[f64]| {
            v.iter()
                .map(|x| format!("{x:.2e}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        write!(
            f,
            "{} ({}×{}): rank {} of {}; σ/σ₁ kept [{}] | dropped [{}]; threshold {:.2e}; gap {:.2e}; \
             cond {:.2e}",
            self.map,
            self.rows,
            self.cols,
            self.rank,
            self.singular.len(),
            list(&kept),
            list(&dropped),
            self.relative_threshold(),
            self.gap(),
            self.condition()
        )
    }
}

/// An end-effector direction the joints allow but the model treats as rigid.
#[derive(Clone, Debug, PartialEq)]
pub struct DroppedDirection {
    /// Its compliance relative to the largest, `σ/σ₁(C)` (from the weighted motions W:
    /// `(σ(W)/σ₁(W))²`).
    pub compliance: f64,
    /// The direction: a unit vector of stacked end-effector twists (body frames at the
    /// reference poses, linear on top), C's eigenvector.
    pub twist: Vec<f64>,
}

/// Something a user should know about a model before trusting it.
#[derive(Clone, Debug, PartialEq)]
pub enum RankWarning {
    /// The cut of `map` is not in a clear gap: `σ_{r+1}/σ_r` above [`tol::RANK_GAP`], so the
    /// rank (and the model) depends on the threshold.
    SmallGap {
        /// The map.
        map: String,
        /// Rank kept.
        rank: usize,
        /// `σ_{r+1}/σ_r`.
        gap: f64,
    },
    /// Near-singular: the joints allow `allowed` independent end-effector directions, but only
    /// `rank` are kept; the others' compliance (largest `largest_dropped` of the largest) is at
    /// or below the threshold and they are treated as rigid.
    NearSingular {
        /// Directions the joints allow (W above eq. 9's round-off).
        allowed: usize,
        /// Directions kept.
        rank: usize,
        /// The largest dropped compliance, relative to the largest.
        largest_dropped: f64,
    },
    /// The stiffness `K = C⁺` is known only to about `accuracy` (relative): `cond(C)` times
    /// the measured round-off of C, above [`tol::STIFFNESS_ACCURACY_WARN`].
    IllConditioned {
        /// `σ₁/σ_r` of C.
        condition: f64,
        /// Estimated relative accuracy of K.
        accuracy: f64,
    },
}

impl fmt::Display for RankWarning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RankWarning::SmallGap { map, rank, gap } => write!(
                f,
                "{map}: the cut at rank {rank} is not in a clear gap (σ_(r+1)/σ_r = {gap:.2e} > \
                 {:.0e}); the rank depends on the threshold — check the singular values and \
                 choose --tsvd inside a gap",
                tol::RANK_GAP
            ),
            RankWarning::NearSingular {
                allowed,
                rank,
                largest_dropped,
            } => write!(
                f,
                "near-singular: the joints allow {allowed} independent end-effector directions, \
                 {} of them with compliance at most {largest_dropped:.2e} of the largest, at or \
                 below the threshold: treated as rigid (rank {rank}); a static displacement \
                 changes by at most that fraction of the largest compliance times the load",
                allowed - rank
            ),
            RankWarning::IllConditioned {
                condition,
                accuracy,
            } => write!(
                f,
                "ill-conditioned: cond(C) = {condition:.2e}; the stiffness K = C⁺ is known to \
                 about {accuracy:.1e} relative (cond(C) times the measured round-off of C)"
            ),
        }
    }
}

/// How far a model's matrices can be trusted.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Conditioning {
    /// `σ₁/σ_r` of the end-effector compliance C at its rank.
    pub compliance_condition: f64,
    /// The walk's measured round-off in C: `‖C − J_E C_θ J_Eᵀ‖_F / ‖C‖₂` (the Schur
    /// complement of the full linearised statics, computed independently).
    pub compliance_error: f64,
    /// Estimated relative accuracy of the stiffness `K = C⁺`: `cond(C) · compliance_error`
    /// (the first-order bound on the error of an inverse).
    pub stiffness_error: f64,
    /// `σ₁/σ_r` of the end-effector accelerability A at its rank.
    pub accelerability_condition: f64,
}

/// Every rank decision and the conditioning of one model.
#[derive(Clone, Debug, PartialEq)]
pub struct Diagnostics {
    /// The threshold of the end-effector maps relative to their largest singular value (τ of
    /// `--tsvd`, or eq. 9 for their size).
    pub relative_threshold: f64,
    /// Independent end-effector directions the joints allow (W above eq. 9's round-off).
    pub allowed: usize,
    /// Every truncated SVD, in the order made: the weighted motions W, the loop closure,
    /// the walk's merges, then C, A and the damping compliance.
    pub maps: Vec<RankReport>,
    /// Directions the joints allow but the model treats as rigid (near-singular).
    pub dropped: Vec<DroppedDirection>,
    /// Conditioning and measured accuracy.
    pub conditioning: Conditioning,
    /// What a user should know (empty for a well-posed model).
    pub warnings: Vec<RankWarning>,
}

/// The rank of the end-effector maps from the compliance-weighted motions `w` (6|E| × nz):
/// singular values above `√(τ · max(σ₁(W)², compliance_scale))`, τ the threshold of a
/// `6|E| × 6|E|` compliance (module doc) and `compliance_scale` the size of the walk's
/// compliances before any loop closed (`WalkResult::scale`: the walk's round-off is relative
/// to that, so a loop that nearly locks the end effectors leaves no resolvable direction —
/// they are then locked); and the structural count (above eq. 9 on W with the default
/// factor, and above ε·`motion_scale`, the size of `J_E √c`: a locked mechanism's W is
/// round-off). Returns (rank, allowed, report).
///
/// # Errors
/// [`Error::LinearAlgebra`] if the SVD fails.
pub fn motion_rank(
    w: &Mat<f64>,
    tsvd: Tsvd,
    motion_scale: f64,
    compliance_scale: f64,
) -> Result<(usize, usize, RankReport), Error> {
    let (m, n) = (w.nrows(), w.ncols());
    if m == 0 || n == 0 {
        let report = RankReport::new(
            "end-effector motions J_E·F (F·Fᵀ = C_θ)",
            (m, n),
            Vec::new(),
            0.0,
            0,
        );
        return Ok((0, 0, report));
    }
    let s = w
        .singular_values()
        .map_err(|e| Error::LinearAlgebra(format!("singular values of J_E·F: {e:?}")))?;
    let largest = s.iter().fold(0.0_f64, |a, &x| a.max(x));
    let floor = Tsvd::default()
        .threshold(m, n, largest)
        .max(f64::EPSILON * motion_scale);
    let allowed = s.iter().filter(|&&x| x > floor).count();
    let cut = (tsvd.relative_threshold(m, m) * (largest * largest).max(compliance_scale)).sqrt();
    let cut = cut.max(floor);
    let rank = s.iter().filter(|&&x| x > cut).count();
    let report = RankReport::new(
        "end-effector motions J_E·F (F·Fᵀ = C_θ), cut at √τ",
        (m, n),
        s,
        cut,
        rank,
    );
    Ok((rank, allowed, report))
}

/// C truncated at `rank`: its pseudo-inverse K and the report. `error` is the measured absolute round-off of C (Frobenius norm of its
/// difference from the Schur complement): C's smallest kept singular value must stand above
/// it (and above eq. 9's round-off of one SVD) for the walk to resolve the direction.
///
/// # Errors
/// [`Error::Unresolved`] when the rank asks for a direction the walk cannot resolve;
/// [`Error::LinearAlgebra`] if the decomposition fails.
pub fn compliance_rank(
    c: &Mat<f64>,
    rank: usize,
    tsvd: Tsvd,
    error: f64,
) -> Result<(Mat<f64>, RankReport), Error> {
    let n = c.nrows();
    let evd = c
        .self_adjoint_eigen(faer::Side::Lower)
        .map_err(|e| Error::LinearAlgebra(format!("eigen of C: {e:?}")))?;
    let (s, u) = (evd.S(), evd.U());
    // Eigenvalues descending; a PSD matrix's singular values are its eigenvalues (round-off
    // may make the smallest slightly negative: their magnitude is the singular value).
    let mut idx: Vec<usize> = (0..n).collect();
    idx.sort_by(|&i, &j| s[j].total_cmp(&s[i]));
    let values: Vec<f64> = idx.iter().map(|&i| s[i]).collect();
    let largest = values.first().copied().unwrap_or(0.0).max(0.0);
    let threshold = tsvd.threshold(n, n, largest);
    let floor = Tsvd {
        factor: 1.0,
        relative: None,
    }
    .threshold(n, n, largest)
    .max(error);
    let report = RankReport::new(
        "end-effector compliance C",
        (n, n),
        values.iter().map(|x| x.abs()).collect(),
        threshold,
        rank,
    );
    if rank > 0 && values[rank - 1] <= floor {
        return Err(Error::Unresolved {
            rank,
            compliance: values[rank - 1] / largest,
            floor: floor / largest,
        });
    }
    let mut k = Mat::<f64>::zeros(n, n);
    for (p, &i) in idx.iter().take(rank).enumerate() {
        let inv = 1.0 / values[p];
        for a in 0..n {
            for b in 0..n {
                k[(a, b)] += u[(a, i)] * inv * u[(b, i)];
            }
        }
    }
    Ok((k, report))
}

/// `A` constrained to move only in the directions orthogonal to the columns of `u`: its
/// Schur complement `A − A U (Uᵀ A U)⁺ Uᵀ A` (Gauss's principle: the end effectors may not
/// move along a direction treated as rigid). Unchanged when `u` has no columns or A has no
/// part along them.
///
/// # Errors
/// [`Error::LinearAlgebra`] if the pseudo-inverse fails.
pub fn constrain(a: &Mat<f64>, u: &Mat<f64>, tsvd: Tsvd) -> Result<Mat<f64>, Error> {
    if u.ncols() == 0 {
        return Ok(a.clone());
    }
    let au = a * u;
    let uau = u.transpose() * &au;
    let scale = crate::linalg::max_abs(a.as_ref());
    let p = pinv_scaled(uau.as_ref(), tsvd, scale)?.inverse;
    let out = a - &au * p * au.transpose();
    Ok(Mat::from_fn(out.nrows(), out.ncols(), |i, j| {
        0.5 * (out[(i, j)] + out[(j, i)])
    }))
}

/// An end-effector map given by its factor, `A = V Vᵀ` (accelerability `J_E Z (ZᵀMZ)⁻¹ Zᵀ
/// J_Eᵀ`, damping compliance), with the directions `rigid` (columns: C's dropped
/// eigenvectors) held — `V' = V N`, N an orthonormal basis of the null space of `rigidᵀ V`,
/// which is the Schur complement of [`constrain`] in factored form — and its pseudo-inverse at
/// `rank` from V′'s singular value decomposition: `(A′, A′⁺, report)`. The report's singular
/// values are `σ(V′)²`, exact to ε σ₁(V′)², where forming A first would leave its small ones
/// at ε σ₁(A).
///
/// # Errors
/// [`Error::Rank`] when V′ has not exactly `rank` singular values above eq. 9's round-off
/// (its map and the compliance disagree on the admissible directions); [`Error::LinearAlgebra`] if an SVD
/// fails.
pub fn factored_inverse(
    v: &Mat<f64>,
    rigid: &Mat<f64>,
    rank: usize,
    map: &str,
) -> Result<(Mat<f64>, Mat<f64>, RankReport), Error> {
    let n = v.nrows();
    let svd_err = |e| Error::LinearAlgebra(format!("SVD of the factor of {map}: {e:?}"));
    let scale = crate::linalg::max_abs(v.as_ref());
    let v = if rigid.ncols() > 0 && v.ncols() > 0 {
        // Rows of rigidᵀV that are round-off (a direction V has no part along) hold nothing.
        let b = rigid.transpose() * v;
        let svd = b.svd().map_err(svd_err)?;
        let k = b.nrows().min(b.ncols());
        let floor = Tsvd::default().threshold(b.nrows(), b.ncols(), scale);
        let held = (0..k).filter(|&i| svd.S()[i] > floor).count();
        let basis = Mat::from_fn(v.ncols(), v.ncols() - held, |i, j| svd.V()[(i, held + j)]);
        v * basis
    } else {
        v.clone()
    };
    let (rows, cols) = (v.nrows(), v.ncols());
    let (values, u) = if cols == 0 {
        (Vec::new(), Mat::zeros(n, 0))
    } else {
        let svd = v.thin_svd().map_err(svd_err)?;
        let k = rows.min(cols);
        let mut idx: Vec<usize> = (0..k).collect();
        idx.sort_by(|&i, &j| svd.S()[j].total_cmp(&svd.S()[i]));
        (
            idx.iter().map(|&i| svd.S()[i]).collect::<Vec<_>>(),
            Mat::from_fn(n, k, |r, c| svd.U()[(r, idx[c])]),
        )
    };
    let largest = values.first().copied().unwrap_or(0.0);
    let floor = Tsvd::default()
        .threshold(rows, cols, largest)
        .max(f64::EPSILON * scale);
    let found = values.iter().filter(|&&x| x > floor).count();
    if found != rank {
        return Err(Error::Rank {
            at: map.to_owned(),
            found,
            expected: rank,
            tolerance: floor * floor,
        });
    }
    let mut a = Mat::<f64>::zeros(n, n);
    let mut inv = Mat::<f64>::zeros(n, n);
    for (i, &s) in values.iter().enumerate() {
        for r in 0..n {
            for c in 0..n {
                let uu = u[(r, i)] * u[(c, i)];
                a[(r, c)] += uu * s * s;
                if i < rank {
                    inv[(r, c)] += uu / (s * s);
                }
            }
        }
    }
    let report = RankReport::new(
        map,
        (n, n),
        values.iter().map(|s| s * s).collect(),
        floor * floor,
        rank,
    );
    Ok((a, inv, report))
}

#[cfg(test)]
#[path = "rank_tests.rs"]
mod tests;
