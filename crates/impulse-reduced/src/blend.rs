//! Blending several FORK⁻¹S models built at different linearisation points (§7).
//!
//! - **Weights** (eq. 25): `α_i ∝ (Σ_e ‖ξ_e − ξ_e⁽ⁱ⁾‖)^(−p)`, p = 2, with ξ the end-effector
//!   displacement from rest (linear part over the bounding radius r, angular over π).
//!   **\[fix\]** at a sample point the distance is zero: that model gets weight 1, so the blend
//!   interpolates the samples exactly. **\[choose\]** optionally with compact support
//!   ([`BlendedModel::support`], [`compact_shepard_weights`]): only the k nearest models carry
//!   weight, continuously; the paper's weights ([`SUPPORT`] = `None`) are the default.
//! - **Matrices** (Algorithm 3, §7.5): the *inverse* matrices (compliance, accelerability,
//!   damping compliance) are blended by their eigenstructure. **Rank changes** (§7.5: "zero
//!   is used for inadmissible directions"): a matched direction a model does not admit (its
//!   Rayleigh quotient at or below its truncation threshold) brings zero along the closest
//!   model's own vector, and the directions the closest model does not admit hold the other
//!   models' matrices there (`P⊥ Aᵢ P⊥`) blended linearly; the blend's admissible directions
//!   are then `C̄`'s eigenvectors above the threshold ([`admissible`]: the union of the
//!   weighted models', each entering with its weight), on which `K̄`, `M̄`, `D̄` and the step's
//!   system matrix are inverted ([`inverse_on`]). Until then the blend was truncated at the
//!   closest model's rank, and a set whose models changed rank (the straight robot arm, rank
//!   4 at rest and 6 bent) kicked its end effector whenever the closest model changed: the
//!   test `blended_step_across_a_rank_change_converges_as_samples_are_added` shows the error
//!   now falling as samples are added (2.1e-4, 1.9e-4, 9.7e-5, 4.6e-5 for 1, 2, 4, 8
//!   samples) where it was 2.7e-4, 9.0e-4, 7.7e-5, 5.3e-5.
//!   **\[fix\]** the loop body accumulates `q̄ ← q̄ + α_i s_i q`, `λ̄ ← λ̄ + α_i λ`;
//!   **\[choose\]** eigenvectors are matched *per eigenspace* without replacement: the closest
//!   model's eigenvalues are grouped into clusters (relative gap below [`CLUSTER_GAP`]); for
//!   each cluster the same number of model i's eigenvectors with the largest projection on it
//!   are taken and rotated onto it by orthogonal Procrustes, which for a simple eigenvalue is
//!   the sign alignment `s_i = sign(q · Q_j⁽¹⁾)` and for a repeated one removes the arbitrary
//!   rotation inside the eigenspace (a symmetric mechanism meets it at once). Each matched
//!   vector brings its Rayleigh quotient as eigenvalue.
//! - **Poses** (eqs. 26–28, Algorithm 4): `H̄ = H⁽¹⁾ exp(Σ_{j≥2} α_j log(H⁽¹⁾⁻¹ H⁽ʲ⁾))`, model 1
//!   the closest. **\[fix\]** Algorithm 4 evaluates model 1 too (it is the base of eq. 28).
//!   **\[choose\]** the internal links are placed the way the blended end effectors are, as
//!   one blended linear model: `H_l = H̄_l exp(T̄_l K̄ ξ̄)` with `ξ̄ = log(H̄_e⁻¹ H_e)` (eq. 24's
//!   displacement), `H̄_l` eq. 28 over the models' reference poses of link l (as `H̄_e` over
//!   theirs) and `T̄_l = Σ αᵢ T_l⁽ⁱ⁾` (eq. 22's twist maps blended linearly). At a sample point
//!   this is that model's own Algorithm 4, `H_l⁽ⁱ⁾ exp(T_l⁽ⁱ⁾ K⁽ⁱ⁾ ξ_e⁽ⁱ⁾)`, so the blend
//!   reproduces its full static solution.
//!
//!   Each `T_l⁽ⁱ⁾` maps wrenches in model i's end-effector frames `H_e⁽ⁱ⁾` to a twist in its
//!   link frame `H_l⁽ⁱ⁾`, and is applied here in the blended frames `H̄_e`, `H̄_l` as it is.
//!   Re-expressing each map in the blended frames first (`Ad_{H̄_l⁻¹ H_l⁽ⁱ⁾} T_l⁽ⁱ⁾
//!   Ad_{H̄_e⁻¹ H_e⁽ⁱ⁾}ᵀ`) was measured on the Fig. 7 studies between samples against the full
//!   statics and left out: it moves the internal links by at most 7% of their error (4.7% on
//!   the "Y", 7.0% on the ladder-36), lowers the worst internal link's error by at most 5.6%
//!   and raises the constraint error by up to 14% (ladder-36 at 85.4 N); likely because a map
//!   changes between samples by as much through the moving linearisation as through its
//!   frames (docs/forks.md).
//!
//!   Not each model's own wrench `ᵉw⁽ⁱ⁾ = K⁽ⁱ⁾ log(H_e⁽ⁱ⁾⁻¹ H_e)` (Algorithm 4 read per model,
//!   this crate's choice until the mid-way links were measured): between two samples the
//!   blended end effector lies on the blended model's manifold `H̄_e exp(C̄ w)`, which passes
//!   through the chord of eq. 28 between the samples' reference poses, while each model's
//!   manifold `H_e⁽ⁱ⁾ exp(C⁽ⁱ⁾ w)` is its tangent at its own sample. The two part along the
//!   mechanism's near-rigid directions (compliance eigenvalues 1e-8 to 1e-6 of the largest on
//!   the "Y"), by ~1e-3 of the bounding radius mid-way, and `K⁽ⁱ⁾` turns that into wrenches
//!   tens of times the load (1e4 N under 253 N on the "Y"): mid-way the links were up to 25
//!   times (the "Y" at 253.1 N: 1.73e-2) and 86 times (the ladder-36 at 5 N) as far from the
//!   full solution as the worse neighbouring model alone, now 1.15 and 0.97 (the worst link is
//!   then the end effector). See "Internal links mid-way" in [`crate::study`].

use std::sync::{Mutex, OnceLock};

use faer::{Mat, Side};
use impulse_geom::{Pose, Twist};

use crate::blend_cache::{ClosestCache, blend_pose};
use crate::construct::ReducedModel;
use crate::error::Error;
use crate::internal::link_twist;
use crate::linalg::Tsvd;
use crate::tol;

/// Exponent p of the Shepard weights (eq. 25; the paper uses 2).
pub const SHEPARD_POWER: f64 = 2.0;

/// Eigenvalues of the closest model closer than this (relative to the largest) form one
/// eigenspace in Algorithm 3 (dimensionless). Eigenvalues of the bundled mechanisms' 6×6 blocks
/// that are equal by symmetry agree to ~1e-12; distinct ones differ by percents.
pub const CLUSTER_GAP: f64 = 1e-6;

/// A model's precomputed eigen-decomposition (Algorithm 3: "pre-computed").
#[derive(Clone, Debug)]
pub struct Eigen {
    /// Eigenvalues, descending.
    pub values: Vec<f64>,
    /// Eigenvectors as columns, in the same order.
    pub vectors: Mat<f64>,
}

impl Eigen {
    /// Decomposes the symmetric `a`.
    ///
    /// # Errors
    /// [`Error::LinearAlgebra`] if the solver fails.
    pub fn new(a: &Mat<f64>) -> Result<Self, Error> {
        let evd = a
            .self_adjoint_eigen(Side::Lower)
            .map_err(|e| Error::LinearAlgebra(format!("eigen: {e:?}")))?;
        let (s, u) = (evd.S(), evd.U());
        let n = a.nrows();
        let mut idx: Vec<usize> = (0..n).collect();
        idx.sort_by(|&i, &j| s[j].total_cmp(&s[i]));
        Ok(Eigen {
            values: idx.iter().map(|&i| s[i]).collect(),
            vectors: Mat::from_fn(n, n, |r, c| u[(r, idx[c])]),
        })
    }
}

/// Shepard weights (eq. 25) from per-model distances with exponent `power` (the paper's p);
/// a zero distance takes all the weight.
#[must_use]
pub fn shepard_weights(distances: &[f64], power: f64) -> Vec<f64> {
    if let Some(i) = distances.iter().position(|&d| d <= 0.0) {
        let mut w = vec![0.0; distances.len()];
        w[i] = 1.0;
        return w;
    }
    let raw: Vec<f64> = distances.iter().map(|d| d.powf(-power)).collect();
    let s: f64 = raw.iter().sum();
    raw.iter().map(|x| x / s).collect()
}

/// Models that may carry weight in a blend (eq. 25 with compact support, see
/// [`compact_shepard_weights`]); `None`, the library's default, blends every model as the
/// paper does. The Fig. 7 study sets [`crate::study::FIG7_SUPPORT`].
pub const SUPPORT: Option<usize> = None;

/// Shepard weights (eq. 25) restricted to the `support` nearest models, continuously: with R
/// the distance of the (`support` + 1)-th nearest model, model i gets
/// `(1/dᵢ − 1/R)₊^p = dᵢ^(−p) · (1 − dᵢ/R)₊^p` (Franke and Nielson's modified Shepard weight:
/// eq. 25's weight times a cutoff that vanishes at R), then the weights are normalised.
///
/// - A zero distance takes all the weight, as in [`shepard_weights`]: exact at the samples.
/// - Continuous in the end-effector poses wherever the nearest model is strictly closer than
///   R: R (an order statistic of continuous distances) is continuous, and a model entering or
///   leaving the `support` nearest does so at distance R, where its weight is zero.
/// - Where the nearest model is as far as R (`support` + 1 models tied for nearest) every
///   weight vanishes; the tied nearest models then share the weight equally (the only
///   discontinuity, on a set of measure zero).
/// - With `support` at least the number of models there is no cutoff: [`shepard_weights`].
#[must_use]
pub fn compact_shepard_weights(distances: &[f64], power: f64, support: usize) -> Vec<f64> {
    if support >= distances.len() || distances.iter().any(|&d| d <= 0.0) {
        return shepard_weights(distances, power);
    }
    let mut sorted = distances.to_vec();
    sorted.sort_by(f64::total_cmp);
    let cutoff = sorted[support];
    let raw: Vec<f64> = distances
        .iter()
        .map(|&d| {
            if d < cutoff {
                (d.recip() - cutoff.recip()).powf(power)
            } else {
                0.0
            }
        })
        .collect();
    let s: f64 = raw.iter().sum();
    if s > 0.0 {
        return raw.iter().map(|x| x / s).collect();
    }
    // Ties at the cutoff: the nearest models share the weight.
    let nearest = sorted[0];
    let tied = distances.iter().filter(|&&d| d == nearest).count() as f64;
    distances
        .iter()
        .map(|&d| if d == nearest { tied.recip() } else { 0.0 })
        .collect()
}

/// Scaled size of a displacement twist: `‖(v/r, ω/π)‖` (§7.1, §8.2).
#[must_use]
pub fn scaled_norm(t: &Twist, r: f64) -> f64 {
    ((t.v / r).length_squared() + (t.w / core::f64::consts::PI).length_squared()).sqrt()
}

/// ξ̄ = log(H̄_e⁻¹ H_e) over the end effectors (eq. 24's displacement) and the elastic
/// wrench K̄ ξ̄ it carries (§6: w = K ξ).
pub(crate) fn elastic_wrench(ee: &[Pose], reference: &[Pose], stiffness: &Mat<f64>) -> Vec<f64> {
    let xi: Vec<f64> = ee
        .iter()
        .zip(reference)
        .flat_map(|(h, r)| (r.inverse() * *h).log().to_array())
        .collect();
    let n = xi.len();
    (0..n)
        .map(|r| (0..n).map(|c| stiffness[(r, c)] * xi[c]).sum())
        .collect()
}

/// The first `rank` eigenvalues (decreasing) grouped into runs of (nearly) equal values,
/// `(first, end)` index ranges: a value within [`CLUSTER_GAP`] times the largest eigenvalue's
/// magnitude of its run's first joins the run (Algorithm 3's repeated eigenvalues).
pub(crate) fn eigen_clusters(values: &[f64], rank: usize) -> Vec<(usize, usize)> {
    let scale = values
        .first()
        .map_or(0.0, |v| v.abs())
        .max(f64::MIN_POSITIVE);
    let mut clusters = Vec::new();
    let mut j = 0;
    while j < rank {
        let mut e = j + 1;
        while e < rank && (values[e] - values[j]).abs() <= CLUSTER_GAP * scale {
            e += 1;
        }
        clusters.push((j, e));
        j = e;
    }
    clusters
}

/// Algorithm 3 (fixed; see the module doc): blends symmetric matrices from their
/// decompositions with weights `alpha`, keeping the rank `rank` of the closest model
/// (largest weight).
#[must_use]
pub fn blend_rank1(eigs: &[&Eigen], mats: &[&Mat<f64>], alpha: &[f64], rank: usize) -> Mat<f64> {
    let k = eigs.len();
    let closest = (0..k)
        .max_by(|&a, &b| alpha[a].total_cmp(&alpha[b]))
        .unwrap_or(0);
    let r0 = eigs[closest];
    let n = r0.vectors.nrows();
    let mut out = Mat::<f64>::zeros(n, n);
    // Clusters of (nearly) equal eigenvalues of the closest model.
    let clusters = eigen_clusters(&r0.values, rank);
    // Per model, which of its eigenvectors are taken (matching without replacement).
    let mut used: Vec<Vec<bool>> = (0..k).map(|_| vec![false; n]).collect();
    for &(j0, j1) in &clusters {
        let dim = j1 - j0;
        let qc = Mat::from_fn(n, dim, |r, c| r0.vectors[(r, j0 + c)]);
        let mut qbar = Mat::<f64>::zeros(n, dim);
        let mut lbar = vec![0.0; dim];
        for i in 0..k {
            if alpha[i] == 0.0 && i != closest {
                // No weight, no contribution (a compact support leaves most models out).
                continue;
            }
            let (q, ev) = if i == closest {
                (
                    qc.clone(),
                    (j0..j1).map(|c| r0.values[c]).collect::<Vec<_>>(),
                )
            } else {
                let e = eigs[i];
                // Take the `dim` unused columns with the largest projection on span(qc).
                let mut cand: Vec<(f64, usize)> = (0..n)
                    .filter(|&c| !used[i][c])
                    .map(|c| {
                        let p: f64 = (0..dim)
                            .map(|m| {
                                (0..n)
                                    .map(|r| qc[(r, m)] * e.vectors[(r, c)])
                                    .sum::<f64>()
                                    .powi(2)
                            })
                            .sum();
                        (p, c)
                    })
                    .collect();
                cand.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
                let cols: Vec<usize> = cand.iter().take(dim).map(|x| x.1).collect();
                for &c in &cols {
                    used[i][c] = true;
                }
                let qi = Mat::from_fn(n, dim, |r, c| e.vectors[(r, cols[c])]);
                // Orthogonal Procrustes: R = U Vᵀ from qiᵀ qc = U Σ Vᵀ; qi R ≈ qc.
                let m = qi.transpose() * &qc;
                let rot = match m.svd() {
                    Ok(svd) => svd.U() * svd.V().transpose(),
                    Err(_) => Mat::identity(dim, dim),
                };
                let mut aligned = &qi * rot;
                // Rayleigh quotients of model i's matrix on the aligned vectors; a direction
                // model i does not admit brings zero along the closest model's own vector
                // (§7.5).
                let admissible = crate::blend_cache::inadmissible_below(e);
                let ev: Vec<f64> = (0..dim)
                    .map(|c| {
                        let v = Mat::from_fn(n, 1, |r, _| aligned[(r, c)]);
                        let q = (v.transpose() * mats[i] * &v)[(0, 0)];
                        if q <= admissible {
                            for r in 0..n {
                                aligned[(r, c)] = qc[(r, c)];
                            }
                            0.0
                        } else {
                            q
                        }
                    })
                    .collect();
                (aligned, ev)
            };
            for c in 0..dim {
                lbar[c] += alpha[i] * ev[c];
                for r in 0..n {
                    qbar[(r, c)] += alpha[i] * q[(r, c)];
                }
            }
        }
        for c in 0..dim {
            let norm = (0..n).map(|r| qbar[(r, c)].powi(2)).sum::<f64>().sqrt();
            if norm == 0.0 {
                continue;
            }
            for a in 0..n {
                for b in 0..n {
                    out[(a, b)] += lbar[c] * qbar[(a, c)] * qbar[(b, c)] / (norm * norm);
                }
            }
        }
    }
    // §7.5: the directions the closest model does not admit (its eigenvectors past `rank`)
    // hold the other models' matrices there, blended linearly (zero for the closest model).
    let null: Vec<Vec<f64>> = (rank..n)
        .map(|c| (0..n).map(|r| r0.vectors[(r, c)]).collect())
        .collect();
    for i in 0..k {
        if i == closest || alpha[i] == 0.0 {
            continue;
        }
        let part = crate::blend_cache::outside(mats[i], &null);
        for b in 0..n {
            for a in 0..n {
                out[(a, b)] += alpha[i] * part[b * n + a];
            }
        }
    }
    out
}

/// The closest model: the largest weight (the last of equal largest ones, as everywhere in
/// this module).
fn closest(alpha: &[f64]) -> usize {
    (0..alpha.len())
        .max_by(|&a, &b| alpha[a].total_cmp(&alpha[b]))
        .unwrap_or(0)
}

/// eq. 28: `H⁽ᶜ⁾ exp(Σ_{j≠c} α_j log(H⁽ᶜ⁾⁻¹ H⁽ʲ⁾))`, c the largest weight.
#[must_use]
pub fn blend_poses(poses: &[Pose], alpha: &[f64]) -> Pose {
    let c = (0..poses.len())
        .max_by(|&a, &b| alpha[a].total_cmp(&alpha[b]))
        .unwrap_or(0);
    let base = poses[c];
    let inv = base.inverse();
    let sum = poses
        .iter()
        .zip(alpha)
        .enumerate()
        .filter(|(j, _)| *j != c)
        .fold(Twist::ZERO, |acc, (_, (p, a))| acc + (inv * *p).log() * *a);
    base * Pose::exp(&sum)
}

/// A set of models of one mechanism, with their decompositions (Algorithm 5's data).
pub struct BlendedModel {
    /// The models; `models[0]` is usually the rest model. Read them, do not change them: the
    /// decompositions and the per-closest-model data are built from them.
    pub models: Vec<ReducedModel>,
    /// Per model: decompositions of compliance, accelerability, damping compliance.
    eig: Vec<[Eigen; 3]>,
    /// Per model: the damping compliance `D⁺`.
    dcomp: Vec<Mat<f64>>,
    /// Rest poses of the end effectors (the zero of ξ in eq. 25).
    rest: Vec<Pose>,
    /// Per model, per end effector: its reference pose's displacement from rest,
    /// `log(H_rest⁻¹ H_e⁽ⁱ⁾)` (the `ξ_e⁽ⁱ⁾` of eq. 25; fixed, so formed once).
    sample_xi: Vec<Vec<Twist>>,
    /// Per model, the weight-independent parts of a blend with that model closest
    /// (Algorithm 3's matching, eq. 28's logarithms), built the first time it is the closest.
    closest: Vec<OnceLock<ClosestCache>>,
    /// Bounding radius r (eq. 25).
    pub radius: f64,
    /// Shepard exponent p (eq. 25; [`SHEPARD_POWER`] unless changed).
    pub power: f64,
    /// Models that may carry weight ([`compact_shepard_weights`]); [`SUPPORT`] (all, the
    /// paper) unless changed.
    pub support: Option<usize>,
    /// The weights, `K̄` and `H̄_e` of the last [`BlendedModel::blend`]: functions of the
    /// weights alone, so [`BlendedModel::internal_poses`] called with the same weights (as
    /// after [`BlendedModel::step`]) reuses them instead of blending and inverting the
    /// compliance again.
    last: Mutex<Option<LinkBlend>>,
}

/// The blended compliance `C̄`, its inverse `K̄` on its admissible directions, and those
/// directions (orthonormal columns).
type BlendedCompliance = (Mat<f64>, Mat<f64>, Mat<f64>);

/// What Algorithm 4 needs from a blend (see [`BlendedModel::internal_poses`]): weights α,
/// blended stiffness `K̄`, blended end-effector references `H̄_e`.
type LinkBlend = (Vec<f64>, Mat<f64>, Vec<Pose>);

/// The blended end-effector system at one state (Algorithm 5's per-step quantities).
pub struct Blend {
    /// Weights α (eq. 25).
    pub alpha: Vec<f64>,
    /// Blended compliance C̄ (before inversion).
    pub compliance: Mat<f64>,
    /// Blended stiffness K̄, mass M̄, damping D̄.
    pub stiffness: Mat<f64>,
    /// Blended mass.
    pub mass: Mat<f64>,
    /// Blended damping.
    pub damping: Mat<f64>,
    /// Blended static wrench b̄ (stacked).
    pub bias: Vec<f64>,
    /// Blended end-effector reference poses H̄_e (eq. 28).
    pub reference: Vec<Pose>,
    /// The blend's admissible directions (orthonormal columns, n × r̄): the eigenvectors of
    /// `C̄` above the truncation threshold ([`admissible`]), on which `K̄`, `M̄` and the
    /// step's system matrix are inverted.
    pub admissible: Mat<f64>,
}

impl BlendedModel {
    /// Prepares `models` (same mechanism, same end effectors) for blending; `rest` are the end
    /// effectors' rest poses and `radius` the mechanism's bounding radius.
    ///
    /// # Errors
    /// [`Error::Argument`] for an empty set; [`Error::LinearAlgebra`] from the decompositions.
    pub fn new(models: Vec<ReducedModel>, rest: Vec<Pose>, radius: f64) -> Result<Self, Error> {
        if models.is_empty() {
            return Err(Error::Argument(
                "blending needs at least one model".to_owned(),
            ));
        }
        let mut eig = Vec::new();
        let mut dcomp = Vec::new();
        for m in &models {
            let dc = crate::linalg::pinv(m.damping.as_ref(), Tsvd::default())?.inverse;
            eig.push([
                Eigen::new(&m.compliance)?,
                Eigen::new(&m.accelerability)?,
                Eigen::new(&dc)?,
            ]);
            dcomp.push(dc);
        }
        let sample_xi = models
            .iter()
            .map(|m| {
                m.reference
                    .iter()
                    .zip(&rest)
                    .map(|(hi, r)| (r.inverse() * *hi).log())
                    .collect()
            })
            .collect();
        let closest = models.iter().map(|_| OnceLock::new()).collect();
        Ok(BlendedModel {
            models,
            eig,
            dcomp,
            rest,
            sample_xi,
            closest,
            radius,
            power: SHEPARD_POWER,
            support: SUPPORT,
            last: Mutex::new(None),
        })
    }

    /// Weights (eq. 25) for end effectors at world poses `ee` (fixed base).
    #[must_use]
    pub fn weights(&self, ee: &[Pose]) -> Vec<f64> {
        let x: Vec<Twist> = ee
            .iter()
            .zip(&self.rest)
            .map(|(h, r)| (r.inverse() * *h).log())
            .collect();
        let d: Vec<f64> = self
            .sample_xi
            .iter()
            .map(|xi| {
                x.iter()
                    .zip(xi)
                    .map(|(x, xi)| scaled_norm(&(*x - *xi), self.radius))
                    .sum()
            })
            .collect();
        match self.support {
            Some(k) => compact_shepard_weights(&d, self.power, k),
            None => shepard_weights(&d, self.power),
        }
    }

    /// The blended system for end effectors at `ee` (Algorithm 5, before the step).
    ///
    /// # Errors
    /// [`Error::Rank`] / [`Error::LinearAlgebra`] from the inversions.
    pub fn blend(&self, ee: &[Pose]) -> Result<Blend, Error> {
        let alpha = self.weights(ee);
        let c = closest(&alpha);
        let cache = self.cache(c);
        let (compliance, stiffness, admissible) = self.blended_compliance(&alpha)?;
        // Ā and D̄⁺ by Algorithm 3, inverted on the blend's admissible directions.
        let inv = |which: usize| -> Result<Mat<f64>, Error> {
            inverse_on(&cache.matching[which].blend(&alpha, c), &admissible)
        };
        let mass = inv(1)?;
        let damped = self
            .models
            .iter()
            .any(|m| crate::linalg::max_abs(m.damping.as_ref()) > 0.0);
        let damping = if damped {
            inv(2)?
        } else {
            Mat::zeros(stiffness.nrows(), stiffness.ncols())
        };
        let n = stiffness.nrows();
        let bias = (0..n)
            .map(|r| {
                self.models
                    .iter()
                    .zip(&alpha)
                    .map(|(m, a)| a * m.bias[r])
                    .sum()
            })
            .collect();
        let reference = self.blended_reference(&alpha);
        if let Ok(mut last) = self.last.lock() {
            *last = Some((alpha.clone(), stiffness.clone(), reference.clone()));
        }
        Ok(Blend {
            alpha,
            compliance,
            stiffness,
            mass,
            damping,
            bias,
            reference,
            admissible,
        })
    }

    /// Algorithm 4 (fixed, see the module doc): internal-link world poses for end effectors at
    /// `ee` with weights `alpha`; one pose per `models[0].internal`. Blends the compliance
    /// with `alpha` to form `K̄` (Algorithm 3, as [`BlendedModel::blend`]); a caller that has
    /// the [`Blend`] of this state uses [`BlendedModel::internal_poses_of`] instead.
    ///
    /// # Errors
    /// [`Error::Rank`] / [`Error::LinearAlgebra`] from the inversion of the blended compliance
    /// (the same inversion as [`BlendedModel::blend`]'s with these weights);
    /// [`Error::Argument`] unless there is one weight per model.
    pub fn try_internal_poses(&self, ee: &[Pose], alpha: &[f64]) -> Result<Vec<Pose>, Error> {
        if alpha.len() != self.models.len() {
            return Err(Error::Argument(format!(
                "{} weights for {} models",
                alpha.len(),
                self.models.len()
            )));
        }
        if let Ok(last) = self.last.lock()
            && let Some((a, stiffness, reference)) = last.as_ref()
            && a.as_slice() == alpha
        {
            return Ok(self.place_internal(ee, alpha, reference, stiffness));
        }
        let (_, stiffness, _) = self.blended_compliance(alpha)?;
        Ok(self.place_internal(ee, alpha, &self.blended_reference(alpha), &stiffness))
    }

    /// [`BlendedModel::try_internal_poses`], infallible: where the blended compliance cannot be
    /// inverted ([`BlendedModel::blend`] reports that error for the same weights) the links are
    /// placed at their blended reference poses `H̄_l` (no elastic displacement).
    #[must_use]
    pub fn internal_poses(&self, ee: &[Pose], alpha: &[f64]) -> Vec<Pose> {
        self.try_internal_poses(ee, alpha).unwrap_or_else(|_| {
            let n = 6 * self.models[0].end_effectors.len();
            self.place_internal(ee, alpha, &self.blended_reference(alpha), &Mat::zeros(n, n))
        })
    }

    /// The weight-independent parts of a blend whose closest model is `c` (built on first
    /// use; see [`crate::blend_cache`]).
    fn cache(&self, c: usize) -> &ClosestCache {
        self.closest[c].get_or_init(|| {
            let mats: Vec<[&Mat<f64>; 3]> = self
                .models
                .iter()
                .zip(&self.dcomp)
                .map(|(m, d)| [&m.compliance, &m.accelerability, d])
                .collect();
            ClosestCache::new(c, &self.models, &self.eig, &mats)
        })
    }

    /// Blended end-effector reference poses `H̄_e` (eq. 28, as [`blend_poses`] over the
    /// models' `reference`).
    fn blended_reference(&self, alpha: &[f64]) -> Vec<Pose> {
        let c = closest(alpha);
        let (k, logs) = (self.models.len(), &self.cache(c).ee_logs);
        self.models[c]
            .reference
            .iter()
            .enumerate()
            .map(|(e, base)| blend_pose(base, &logs[e * k..(e + 1) * k], alpha, c))
            .collect()
    }

    /// The blended compliance `C̄` (Algorithm 3, §7.5's directions the closest model does
    /// not admit included), its inverse `K̄` on its admissible directions, and those
    /// directions (see [`admissible`]) for weights `alpha`.
    fn blended_compliance(&self, alpha: &[f64]) -> Result<BlendedCompliance, Error> {
        let c = closest(alpha);
        let compliance = self.cache(c).matching[0].blend(alpha, c);
        let basis = admissible(&compliance)?;
        let stiffness = inverse_on(&compliance, &basis)?;
        Ok((compliance, stiffness, basis))
    }

    /// [`BlendedModel::internal_poses`] with the blend `b` of the same end-effector poses `ee`
    /// (as from [`BlendedModel::blend`] or [`BlendedModel::step`]): its weights, `K̄` and
    /// `H̄_e`.
    #[must_use]
    pub fn internal_poses_of(&self, ee: &[Pose], b: &Blend) -> Vec<Pose> {
        self.place_internal(ee, &b.alpha, &b.reference, &b.stiffness)
    }

    /// Algorithm 4 as the blended model's own eq. 22: every internal link from the blended
    /// end-effector state the way the end effectors themselves are, `H̄_l exp(T̄_l K̄ ξ̄)` with
    /// `ξ̄ = log(H̄_e⁻¹ H_e)` (eq. 24's displacement), `H̄_l` eq. 28 over the models' reference
    /// poses of link l and `T̄_l = Σ αᵢ T_l⁽ⁱ⁾` (eq. 22's twist maps, blended linearly).
    fn place_internal(
        &self,
        ee: &[Pose],
        alpha: &[f64],
        reference: &[Pose],
        stiffness: &Mat<f64>,
    ) -> Vec<Pose> {
        let w = elastic_wrench(ee, reference, stiffness);
        let c = closest(alpha);
        let (count, logs) = (self.models.len(), &self.cache(c).link_logs);
        (0..self.models[0].internal.len())
            .map(|l| {
                // eq. 28 on the link's reference poses, then eq. 22 with T̄_l, then eq. 6. A
                // model without weight adds nothing to either: it is not evaluated.
                let twist = self
                    .models
                    .iter()
                    .zip(alpha)
                    .filter(|(_, a)| **a > 0.0)
                    .fold(Twist::ZERO, |acc, (m, a)| acc + link_twist(m, l, &w) * *a);
                let base = &self.models[c].internal_reference[l];
                blend_pose(base, &logs[l * count..(l + 1) * count], alpha, c) * Pose::exp(&twist)
            })
            .collect()
    }
}

impl BlendedModel {
    /// One step of Algorithm 5 (fixed base, no contact): weights at the current end-effector
    /// poses `ee`, blended matrices and references, `ξ = log(H̄_e⁻¹ H_e)`, backward Euler of eq. 24
    /// with the system matrix of the fixed eq. 23 (re-factored every step: it changes with
    /// the blend), `H_e ← H_e exp(h φ)`. `phi` and the stacked body wrenches `w` are per end
    /// effector in its body frame. Returns the blend used (its weights place the internal
    /// links through [`BlendedModel::internal_poses`]).
    ///
    /// # Errors
    /// Errors of [`BlendedModel::blend`] and of the factorisation.
    pub fn step(
        &self,
        ee: &mut [Pose],
        phi: &mut [f64],
        w: &[f64],
        h: f64,
    ) -> Result<Blend, Error> {
        let b = self.blend(ee)?;
        let n = phi.len();
        let xi: Vec<f64> = ee
            .iter()
            .zip(&b.reference)
            .flat_map(|(p, r)| (r.inverse() * *p).log().to_array())
            .collect();
        let a = &b.mass + &b.damping * h + &b.stiffness * (h * h);
        // The system matrix on the blend's admissible directions (§7.5): `M̄` and `K̄` come
        // from different matched eigenvectors (Algorithm 3 on Ā and on C̄), so inverted in
        // full, directions outside `C̄`'s range where `A` holds only the difference of their
        // ranges turn the load into runaway velocities (the straight robot arm blended with
        // bent ones: 1e6 m/s within 20 steps under 1 N, before the blend was restricted).
        let a_inv = inverse_on(&a, &b.admissible)?;
        let rhs: Vec<f64> = (0..n)
            .map(|r| {
                (0..n)
                    .map(|c| b.mass[(r, c)] * phi[c] - h * b.stiffness[(r, c)] * xi[c])
                    .sum::<f64>()
                    + h * (w[r] - b.bias[r])
            })
            .collect();
        for (r, p) in phi.iter_mut().enumerate() {
            *p = (0..n).map(|c| a_inv[(r, c)] * rhs[c]).sum();
        }
        for (e, pose) in ee.iter_mut().enumerate() {
            let t = Twist::from_array(core::array::from_fn(|k| phi[6 * e + k] * h));
            *pose = *pose * Pose::exp(&t);
        }
        Ok(b)
    }
}

/// The admissible directions of a blended compliance `c` (§7.5): its eigenvectors whose
/// eigenvalues are above the truncation threshold (eq. 9 with [`tol::TSVD_FACTOR`], relative
/// to the largest), as orthonormal columns. Across a rank change this is the union of the
/// weighted models' admissible directions, each entering with its weight (the blend holds a
/// lower-rank model's zero there): a direction whose blended compliance is at or below the
/// threshold is rigid.
///
/// # Errors
/// [`Error::LinearAlgebra`] if the eigen-decomposition fails.
pub fn admissible(c: &Mat<f64>) -> Result<Mat<f64>, Error> {
    let e = Eigen::new(c)?;
    let n = c.nrows();
    let threshold = Tsvd::default().threshold(n, n, e.values.first().copied().unwrap_or(0.0));
    let r = e.values.iter().filter(|&&x| x > threshold).count();
    Ok(Mat::from_fn(n, r, |i, j| e.vectors[(i, j)]))
}

/// The inverse of the symmetric `a` on the directions `basis` (orthonormal columns):
/// `B (Bᵀ a B)⁺ Bᵀ`, the pseudo-inverse of `Bᵀ a B` by truncated SVD (eq. 9).
///
/// # Errors
/// [`Error::LinearAlgebra`] if the SVD fails.
pub fn inverse_on(a: &Mat<f64>, basis: &Mat<f64>) -> Result<Mat<f64>, Error> {
    let n = a.nrows();
    if basis.ncols() == 0 {
        return Ok(Mat::zeros(n, n));
    }
    let restricted = basis.transpose() * a * basis;
    let sym = Mat::from_fn(restricted.nrows(), restricted.ncols(), |i, j| {
        0.5 * (restricted[(i, j)] + restricted[(j, i)])
    });
    let inv = crate::linalg::pinv(sym.as_ref(), Tsvd::default())?.inverse;
    let out = basis * inv * basis.transpose();
    Ok(Mat::from_fn(n, n, |i, j| 0.5 * (out[(i, j)] + out[(j, i)])))
}

/// Static equilibrium of a blended model (fixed base) under constant stacked world loads
/// `force_torque` (per end effector: force then torque, world): the fixed point
/// `H_e = H̄_e exp(C̄ (w(H_e) − b̄))` of Algorithm 5 at rest, by relaxed successive substitution
/// from `start`: each pass moves `H_e ← H_e exp(β log(H_e⁻¹ H_e'))` towards the substituted
/// pose `H_e'`, with β = 1 until a pass lands where the residual `max_e ‖log(H_e⁻¹ H_e')‖` is
/// larger than where it started; that pass is undone and β halved (down to
/// [`tol::BLEND_STATIC_MIN_RELAXATION`], where passes are always taken). A world force turns
/// with the end effector, so beyond a load of the order of the stiffness over the lever arm
/// the plain substitution (β = 1) oscillates away (the single ladder model past ~140 N) or
/// jumps to another equilibrium; the relaxation leaves the fixed points unchanged. Returns the end-effector poses and the weights there.
///
/// # Errors
/// [`Error::NoConvergence`] when the iteration does not settle; errors of [`BlendedModel::blend`].
pub fn blended_statics(
    set: &BlendedModel,
    force_torque: &[[f64; 6]],
    start: &[Pose],
) -> Result<(Vec<Pose>, Vec<f64>), Error> {
    let mut ee = start.to_vec();
    // The last accepted iterate and its residual, to step back to when a pass overshoots.
    let mut kept = ee.clone();
    let mut kept_residual = f64::INFINITY;
    let mut relax = 1.0_f64;
    for _ in 0..tol::BLEND_STATIC_ITERATIONS {
        let b = set.blend(&ee)?;
        let w: Vec<f64> = ee
            .iter()
            .zip(force_torque)
            .flat_map(|(p, ft)| {
                let f = p.inverse_transform_vector(glam::DVec3::new(ft[0], ft[1], ft[2]));
                let t = p.inverse_transform_vector(glam::DVec3::new(ft[3], ft[4], ft[5]));
                [f.x, f.y, f.z, t.x, t.y, t.z]
            })
            .collect();
        let n = w.len();
        // The substituted poses' offsets from the current ones; their size is the residual.
        let targets: Vec<Twist> = (0..ee.len())
            .map(|e| {
                let xi = Twist::from_array(core::array::from_fn(|r| {
                    (0..n)
                        .map(|c| b.compliance[(6 * e + r, c)] * (w[c] - b.bias[c]))
                        .sum()
                }));
                (ee[e].inverse() * (b.reference[e] * Pose::exp(&xi))).log()
            })
            .collect();
        let residual = targets
            .iter()
            .map(|t| scaled_norm(t, set.radius))
            .fold(0.0, f64::max);
        if residual <= tol::BLEND_STATIC_TOLERANCE {
            let alpha = set.weights(&ee);
            return Ok((ee, alpha));
        }
        if residual > kept_residual && relax > tol::BLEND_STATIC_MIN_RELAXATION {
            // The pass overshot: back to the kept iterate with half the step.
            relax = (0.5 * relax).max(tol::BLEND_STATIC_MIN_RELAXATION);
            ee.clone_from(&kept);
            continue;
        }
        kept.clone_from(&ee);
        kept_residual = residual;
        for (p, t) in ee.iter_mut().zip(&targets) {
            *p = *p * Pose::exp(&scale(t, relax));
        }
    }
    Err(Error::NoConvergence {
        residual: f64::NAN,
        iterations: tol::BLEND_STATIC_ITERATIONS,
    })
}

/// `β ξ`.
fn scale(t: &Twist, beta: f64) -> Twist {
    Twist::new(t.v * beta, t.w * beta)
}

#[cfg(test)]
#[path = "blend_tests.rs"]
mod tests;
