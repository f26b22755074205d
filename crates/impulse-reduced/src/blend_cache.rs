//! The parts of a blend that do not depend on the weights, once per closest model.
//!
//! Around a given closest model c (the largest weight), Algorithm 3 matches every other
//! model's eigenvectors to c's eigenspaces (the choice of columns, the Procrustes rotation,
//! the Rayleigh quotients) and eq. 28 takes `log(H⁽ᶜ⁾⁻¹ H⁽ʲ⁾)` of every pair of reference
//! poses: functions of the models alone. Only the weighted sums of Algorithm 3 and the sum
//! inside eq. 28's exponential change from step to step. [`ClosestCache`] holds the former
//! for one c; [`crate::blend::BlendedModel`] builds one per model the first time that model
//! is the closest and keeps it, so a step costs the weighted sums, not the matching (before,
//! each step redid the matching of every model for each of the three matrices: most of the
//! growth of a blended step with the number of models, the paper's Table 2; see "Table 2: µs
//! per blended step" in `docs/forks.md`).
//!
//! The matching here is its own implementation on flat arrays; [`crate::blend::blend_rank1`]
//! stays the per-call form of Algorithm 3 and [`crate::blend::blend_poses`] of eq. 28, and
//! the tests compare the two (`blend_cache_tests.rs`).

use faer::Mat;
use impulse_geom::{Pose, Twist};

use crate::blend::{Eigen, eigen_clusters};
use crate::construct::ReducedModel;

/// Algorithm 3's matching of every model onto the closest model's first `rank` eigenvectors,
/// for one matrix (compliance, accelerability or damping compliance).
#[derive(Clone, Debug)]
pub(crate) struct Matching {
    /// Matrix size n (6 per end effector).
    n: usize,
    /// The closest model's rank: eigenvectors kept.
    rank: usize,
    /// Per model: its matched eigenvectors, aligned onto the closest model's (column j of
    /// `rank`, column-major, `n` values each). The closest model's own are its eigenvectors.
    vectors: Vec<Vec<f64>>,
    /// Per model: the eigenvalue each matched vector brings (its Rayleigh quotient; the
    /// closest model's own eigenvalues for it; zero where the model lacks the direction).
    values: Vec<Vec<f64>>,
    /// Per model: its matrix on the closest model's inadmissible directions,
    /// `P⊥ Aᵢ P⊥` (n × n, column-major), blended linearly ([`crate::blend::blend_rank1`]).
    complement: Vec<Vec<f64>>,
}

/// Everything a blend with closest model c reuses: Algorithm 3's matching of the three
/// matrices and eq. 28's logarithms.
#[derive(Clone, Debug)]
pub(crate) struct ClosestCache {
    /// Compliance, accelerability, damping compliance (the order of `BlendedModel`'s
    /// decompositions).
    pub(crate) matching: [Matching; 3],
    /// `log(H_e⁽ᶜ⁾⁻¹ H_e⁽ʲ⁾)` per end effector e and model j, at `e · models + j`.
    pub(crate) ee_logs: Vec<Twist>,
    /// `log(H_l⁽ᶜ⁾⁻¹ H_l⁽ʲ⁾)` per internal link l and model j, at `l · models + j`.
    pub(crate) link_logs: Vec<Twist>,
}

impl ClosestCache {
    /// The cache for closest model `closest` of `models`, whose decompositions are `eig`
    /// (compliance, accelerability, damping compliance) of the matrices `mats`.
    pub(crate) fn new(
        closest: usize,
        models: &[ReducedModel],
        eig: &[[Eigen; 3]],
        mats: &[[&Mat<f64>; 3]],
    ) -> Self {
        let rank = models[closest].rank;
        let matching = core::array::from_fn(|which| {
            let eigs: Vec<&Eigen> = eig.iter().map(|e| &e[which]).collect();
            let m: Vec<&Mat<f64>> = mats.iter().map(|m| m[which]).collect();
            Matching::new(&eigs, &m, closest, rank)
        });
        let k = models.len();
        let logs = |poses: &dyn Fn(&ReducedModel) -> &[Pose], count: usize| -> Vec<Twist> {
            let mut out = Vec::with_capacity(count * k);
            for l in 0..count {
                let inv = poses(&models[closest])[l].inverse();
                // As `blend_poses`: log(H⁽ᶜ⁾⁻¹ H⁽ʲ⁾) (eq. 28).
                out.extend(models.iter().map(|m| (inv * poses(m)[l]).log()));
            }
            out
        };
        ClosestCache {
            matching,
            ee_logs: logs(&|m| &m.reference, models[closest].reference.len()),
            link_logs: logs(
                &|m| &m.internal_reference,
                models[closest].internal_reference.len(),
            ),
        }
    }
}

impl Matching {
    /// Algorithm 3's matching (fixed, see the `blend` module doc): the closest model's
    /// eigenvalues grouped into clusters (relative gap [`crate::blend::CLUSTER_GAP`]); per cluster, per
    /// other model, the unused eigenvectors with the largest projection on the cluster's span,
    /// rotated onto it by orthogonal Procrustes, with their Rayleigh quotients.
    fn new(eigs: &[&Eigen], mats: &[&Mat<f64>], closest: usize, rank: usize) -> Self {
        let r0 = eigs[closest];
        let n = r0.vectors.nrows();
        let col = |e: &Eigen, c: usize| -> Vec<f64> { (0..n).map(|r| e.vectors[(r, c)]).collect() };
        let own: Vec<Vec<f64>> = (0..n).map(|c| col(r0, c)).collect();
        let clusters = eigen_clusters(&r0.values, rank);
        let dot = |a: &[f64], b: &[f64]| -> f64 { a.iter().zip(b).map(|(x, y)| x * y).sum() };
        let mut vectors = Vec::with_capacity(eigs.len());
        let mut values = Vec::with_capacity(eigs.len());
        let mut complement = Vec::with_capacity(eigs.len());
        for (i, e) in eigs.iter().enumerate() {
            if i == closest {
                vectors.push(own[..rank].concat());
                values.push(r0.values[..rank].to_vec());
                complement.push(vec![0.0; n * n]);
                continue;
            }
            let cols: Vec<Vec<f64>> = (0..n).map(|c| col(e, c)).collect();
            let admissible = inadmissible_below(e);
            let mut used = vec![false; n];
            let mut v = vec![0.0; n * rank];
            let mut ev = vec![0.0; rank];
            for &(j0, j1) in &clusters {
                let dim = j1 - j0;
                // The `dim` unused columns with the largest projection on the cluster's span.
                let mut cand: Vec<(f64, usize)> = (0..n)
                    .filter(|&c| !used[c])
                    .map(|c| {
                        let p = (j0..j1).map(|m| dot(&own[m], &cols[c]).powi(2)).sum();
                        (p, c)
                    })
                    .collect();
                cand.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
                let picked: Vec<usize> = cand.iter().take(dim).map(|x| x.1).collect();
                for &c in &picked {
                    used[c] = true;
                }
                // Orthogonal Procrustes: R = U Vᵀ from qᵢᵀ q_c = U Σ Vᵀ, then qᵢ R ≈ q_c; for
                // one vector R is the sign of the dot product.
                let m = Mat::from_fn(dim, dim, |a, b| dot(&cols[picked[a]], &own[j0 + b]));
                let rot = if dim == 1 {
                    Mat::from_fn(1, 1, |_, _| if m[(0, 0)] < 0.0 { -1.0 } else { 1.0 })
                } else {
                    match m.svd() {
                        Ok(svd) => svd.U() * svd.V().transpose(),
                        Err(_) => Mat::identity(dim, dim),
                    }
                };
                for b in 0..dim {
                    let out = &mut v[(j0 + b) * n..(j0 + b + 1) * n];
                    for (a, &c) in picked.iter().enumerate() {
                        for (x, y) in out.iter_mut().zip(&cols[c]) {
                            *x += y * rot[(a, b)];
                        }
                    }
                    // Rayleigh quotient of model i's matrix on the aligned vector.
                    let a = mats[i];
                    let q: f64 = (0..n)
                        .map(|r| out[r] * (0..n).map(|c| a[(r, c)] * out[c]).sum::<f64>())
                        .sum();
                    if q <= admissible {
                        // §7.5: a direction model i does not admit brings zero along the
                        // closest model's own vector (not a stray one of its null space).
                        out.copy_from_slice(&own[j0 + b]);
                        ev[j0 + b] = 0.0;
                    } else {
                        ev[j0 + b] = q;
                    }
                }
            }
            vectors.push(v);
            values.push(ev);
            complement.push(outside(mats[i], &own[rank..]));
        }
        Matching {
            n,
            rank,
            vectors,
            values,
            complement,
        }
    }

    /// Algorithm 3's blend with weights `alpha` (`closest` their largest): per kept
    /// eigenvector j, `q̄ = Σ αᵢ qᵢⱼ`, `λ̄ = Σ αᵢ λᵢⱼ`, and the result `Σⱼ λ̄ q̄ q̄ᵀ / ‖q̄‖²`.
    /// A model without weight is skipped, the closest never.
    pub(crate) fn blend(&self, alpha: &[f64], closest: usize) -> Mat<f64> {
        let n = self.n;
        let mut out = Mat::<f64>::zeros(n, n);
        let mut q = vec![0.0; n];
        for j in 0..self.rank {
            q.fill(0.0);
            let mut l = 0.0;
            for (i, a) in alpha.iter().enumerate() {
                if *a == 0.0 && i != closest {
                    continue;
                }
                l += a * self.values[i][j];
                for (x, y) in q.iter_mut().zip(&self.vectors[i][j * n..(j + 1) * n]) {
                    *x += a * y;
                }
            }
            let norm = q.iter().map(|x| x * x).sum::<f64>().sqrt();
            if norm == 0.0 {
                continue;
            }
            // The products in `blend_rank1`'s order.
            for b in 0..n {
                for (a, x) in out.col_as_slice_mut(b).iter_mut().enumerate() {
                    *x += l * q[a] * q[b] / (norm * norm);
                }
            }
        }
        // The other models' directions the closest one does not admit, linearly.
        for (i, a) in alpha.iter().enumerate() {
            if i == closest || *a == 0.0 {
                continue;
            }
            for b in 0..n {
                for (x, y) in out
                    .col_as_slice_mut(b)
                    .iter_mut()
                    .zip(&self.complement[i][b * n..(b + 1) * n])
                {
                    *x += a * y;
                }
            }
        }
        out
    }
}

/// The Rayleigh quotient at or below which a direction is not admitted by a model with
/// decomposition `e`: its truncation threshold (eq. 9 with [`crate::tol::TSVD_FACTOR`]) times
/// its largest eigenvalue.
pub(crate) fn inadmissible_below(e: &Eigen) -> f64 {
    let n = e.values.len();
    let largest = e.values.first().copied().unwrap_or(0.0).max(0.0);
    crate::linalg::Tsvd::default().threshold(n, n, largest)
}

/// `P⊥ A P⊥` (column-major) with `P⊥ = Σ u uᵀ` over the vectors `null` (orthonormal): A on
/// the directions the closest model does not admit (§7.5, "zero for inadmissible directions"
/// for the closest model, the others' part there blended linearly).
pub(crate) fn outside(a: &Mat<f64>, null: &[Vec<f64>]) -> Vec<f64> {
    let n = a.nrows();
    let k = null.len();
    if k == 0 {
        return vec![0.0; n * n];
    }
    // B = Uᵀ A U (k × k), then P⊥ A P⊥ = U B Uᵀ.
    let au: Vec<Vec<f64>> = null
        .iter()
        .map(|u| {
            (0..n)
                .map(|r| (0..n).map(|c| a[(r, c)] * u[c]).sum())
                .collect()
        })
        .collect();
    let b: Vec<Vec<f64>> = null
        .iter()
        .map(|u| {
            au.iter()
                .map(|x| u.iter().zip(x).map(|(p, q)| p * q).sum())
                .collect()
        })
        .collect();
    let mut out = vec![0.0; n * n];
    for col in 0..n {
        for row in 0..n {
            let mut s = 0.0;
            for (p, bp) in b.iter().enumerate() {
                for (q, bpq) in bp.iter().enumerate() {
                    s += null[p][row] * bpq * null[q][col];
                }
            }
            out[col * n + row] = s;
        }
    }
    out
}

/// eq. 28 with the logarithms of `logs` (`log(H⁽ᶜ⁾⁻¹ H⁽ʲ⁾)` for every model j, c the closest):
/// `H⁽ᶜ⁾ exp(Σ_{j≠c} α_j log(H⁽ᶜ⁾⁻¹ H⁽ʲ⁾))`; models without weight add nothing.
pub(crate) fn blend_pose(base: &Pose, logs: &[Twist], alpha: &[f64], closest: usize) -> Pose {
    let sum = logs
        .iter()
        .zip(alpha)
        .enumerate()
        .filter(|(j, (_, a))| *j != closest && **a != 0.0)
        .fold(Twist::ZERO, |acc, (_, (t, a))| acc + *t * *a);
    *base * Pose::exp(&sum)
}

#[cfg(test)]
#[path = "blend_cache_tests.rs"]
mod tests;
