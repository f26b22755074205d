//! The paper's objects as plain data, with their frames and units: the coupled end-effector
//! compliance C of eqs. 10–14 and what is built from it (stiffness, accelerability, mass,
//! damping, the static wrench b of eq. 24, the twist maps of eq. 22), every rank decision and
//! the conditioning ([`crate::rank`]). Serializable (serde); `impulse reduce --compliance`
//! writes it as JSON. Reading it needs the conventions below, which it also carries as text.
//!
//! **Conventions** (docs/forks.md, "Conventions"):
//! - a twist is `(v, ω)` and a wrench `(f, τ)`, linear on top (Murray–Li–Sastry); the
//!   end-effector vectors stack one 6-block per end effector, in `end_effectors` order;
//! - end effector e's block is in its **body frame at the reference pose** `H_e` (the
//!   linearisation point: rest for the model of `impulse reduce`), about the link's origin:
//!   `C` maps such a wrench to such a (small displacement) twist, `H_e exp(ξ)` (eq. 6);
//! - a twist map row block is in its internal link's body frame at its reference pose;
//! - SI units: m, rad, N, N·m, kg, s. The blocks of C are m/N (linear–force), m/(N·m) and
//!   rad/N (cross), rad/(N·m) (angular–torque); K is the inverse's; A is 1/kg, m/(kg·m)…
//!   (accelerability: twist rate per wrench), M its inverse (kg, kg·m, kg·m²); D (N·s/m,
//!   N·m·s/rad …).

use serde::Serialize;

use crate::construct::ReducedModel;
use crate::mechanism::Mechanism;
use crate::rank::Diagnostics;
use impulse_geom::Pose;

/// The text of the conventions carried by every export.
pub const CONVENTIONS: &str = "Twists (v, ω) and wrenches (f, τ), linear on top \
(Murray–Li–Sastry). End-effector vectors stack one 6-block per end effector in `end_effectors` \
order, each in that link's body frame at its reference pose (`end_effectors[i]`: `position` and \
`rotation_xyzw`, world), about the link origin; a displaced end effector is at pose · exp(ξ) (FORK⁻¹S eq. 6). \
`compliance` maps such a stacked wrench to such a stacked twist (eqs. 10–14), `stiffness` is its \
truncated-SVD inverse at `rank` (eq. 9), `accelerability` maps a wrench to a body-acceleration \
(eq. 7, or the exact J M⁻¹ Jᵀ), `mass` is its inverse, `damping` the damping (eq. 8), `bias` the \
static wrench b of eq. 24 (zero at rest). `twist_maps[k].map` (6 × 6|E|) maps the stacked \
end-effector wrench to internal link k's body twist in its frame at `twist_maps[k].frame` \
(eq. 22). Matrices are lists of rows. SI units: m, rad, N, N·m, kg, s.";

/// A frame: a link's pose (world): origin and orientation (unit quaternion x, y, z, w).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Frame {
    /// The link.
    pub link: String,
    /// Origin (world, m).
    pub position: [f64; 3],
    /// Orientation, quaternion `(x, y, z, w)`.
    pub rotation_xyzw: [f64; 4],
}

impl Frame {
    fn new(link: &str, pose: &Pose) -> Self {
        Frame {
            link: link.to_owned(),
            position: pose.translation.to_array(),
            rotation_xyzw: pose.rotation.to_array(),
        }
    }
}

/// One internal link's twist map (eq. 22).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TwistMap {
    /// The link and its reference pose (the frame of the map's rows).
    pub frame: Frame,
    /// 6 × 6|E|, rows.
    pub map: Vec<Vec<f64>>,
}

/// One truncated SVD, as written.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MapRank {
    /// Which map.
    pub map: String,
    /// Rows and columns.
    pub size: [usize; 2],
    /// Singular values kept.
    pub rank: usize,
    /// Every singular value relative to the largest, descending.
    pub singular_relative: Vec<f64>,
    /// The threshold relative to the largest singular value.
    pub threshold_relative: f64,
    /// `σ_{r+1}/σ_r` (0: nothing dropped).
    pub gap: f64,
    /// `σ₁/σ_r`.
    pub condition: f64,
}

/// The rank decisions and conditioning, as written.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RankExport {
    /// The end-effector maps' threshold relative to their largest singular value.
    pub relative_threshold: f64,
    /// Directions the joints allow.
    pub allowed: usize,
    /// Directions kept.
    pub rank: usize,
    /// Directions treated as rigid: relative compliance and unit stacked twist.
    pub dropped: Vec<(f64, Vec<f64>)>,
    /// `σ₁/σ_r` of C.
    pub compliance_condition: f64,
    /// Measured round-off of C relative to its largest singular value.
    pub compliance_error: f64,
    /// Estimated relative accuracy of K.
    pub stiffness_error: f64,
    /// `σ₁/σ_r` of A.
    pub accelerability_condition: f64,
    /// Every truncated SVD.
    pub maps: Vec<MapRank>,
    /// The warnings, as sentences.
    pub warnings: Vec<String>,
}

impl RankExport {
    /// The export of `d` for a model of rank `rank`.
    #[must_use]
    pub fn new(d: &Diagnostics, rank: usize) -> Self {
        RankExport {
            relative_threshold: d.relative_threshold,
            allowed: d.allowed,
            rank,
            dropped: d
                .dropped
                .iter()
                .map(|x| (x.compliance, x.twist.clone()))
                .collect(),
            compliance_condition: d.conditioning.compliance_condition,
            compliance_error: d.conditioning.compliance_error,
            stiffness_error: d.conditioning.stiffness_error,
            accelerability_condition: d.conditioning.accelerability_condition,
            maps: d
                .maps
                .iter()
                .map(|r| {
                    let s = r.largest();
                    MapRank {
                        map: r.map.clone(),
                        size: [r.rows, r.cols],
                        rank: r.rank,
                        singular_relative: r
                            .singular
                            .iter()
                            .map(|x| if s > 0.0 { x / s } else { 0.0 })
                            .collect(),
                        threshold_relative: r.relative_threshold(),
                        gap: r.gap(),
                        condition: r.condition(),
                    }
                })
                .collect(),
            warnings: d.warnings.iter().map(ToString::to_string).collect(),
        }
    }
}

/// A model as plain data (see the module doc).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ModelExport {
    /// The mechanism's name.
    pub mechanism: String,
    /// The conventions ([`CONVENTIONS`]).
    pub conventions: String,
    /// The end effectors and their reference poses (the frames of every end-effector block).
    pub end_effectors: Vec<Frame>,
    /// Rank of C (admissible end-effector directions).
    pub rank: usize,
    /// C (6|E| square).
    pub compliance: Vec<Vec<f64>>,
    /// K = C⁺ at `rank`.
    pub stiffness: Vec<Vec<f64>>,
    /// A.
    pub accelerability: Vec<Vec<f64>>,
    /// M = A⁺ at `rank`.
    pub mass: Vec<Vec<f64>>,
    /// D.
    pub damping: Vec<Vec<f64>>,
    /// b of eq. 24.
    pub bias: Vec<f64>,
    /// The internal links' twist maps (eq. 22), in walk order.
    pub twist_maps: Vec<TwistMap>,
    /// Rank decisions and conditioning.
    pub diagnostics: RankExport,
}

fn rows(a: &faer::Mat<f64>) -> Vec<Vec<f64>> {
    (0..a.nrows())
        .map(|i| (0..a.ncols()).map(|j| a[(i, j)] + 0.0).collect())
        .collect()
}

impl ModelExport {
    /// The export of `model`, built from `m`.
    #[must_use]
    pub fn new(m: &Mechanism, model: &ReducedModel) -> Self {
        let ne = model.end_effectors.len();
        ModelExport {
            mechanism: m.name.clone(),
            conventions: CONVENTIONS.to_owned(),
            end_effectors: model
                .end_effectors
                .iter()
                .zip(&model.reference)
                .map(|(&e, p)| Frame::new(&m.links[e].name, p))
                .collect(),
            rank: model.rank,
            compliance: rows(&model.compliance),
            stiffness: rows(&model.stiffness),
            accelerability: rows(&model.accelerability),
            mass: rows(&model.mass),
            damping: rows(&model.damping),
            bias: model.bias.clone(),
            twist_maps: model
                .internal
                .iter()
                .zip(&model.internal_reference)
                .enumerate()
                .map(|(k, (&l, p))| {
                    // Column-major 6 × 6|E| in the model (see `ReducedModel`).
                    let t = model.twist_map(k);
                    TwistMap {
                        frame: Frame::new(&m.links[l].name, p),
                        map: (0..6)
                            .map(|r| (0..6 * ne).map(|c| t[6 * c + r] + 0.0).collect())
                            .collect(),
                    }
                })
                .collect(),
            diagnostics: RankExport::new(&model.diagnostics, model.rank),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::construct::ConstructOptions;
    use crate::reference::Configuration;

    /// The exported compliance times a wrench against the model's: the same products, summed
    /// in another order (relative to 1 + the value).
    const SAME_SUMS: f64 = 1e-15;

    /// The exported twist maps times a wrench against the model's eq. 22 kernel, which sums
    /// per end effector in another order over twelve columns of mixed sizes.
    const SUMMED_MAPS: f64 = 1e-12;

    /// The exported matrices are the model's, rows as rows, and each twist map applied to a
    /// stacked wrench gives the internal link's twist the model computes for it
    /// (`ReducedModel::static_twists`, eq. 22), on the "Y" (two end effectors, 12 columns).
    #[test]
    fn exported_maps_act_as_the_model_does() {
        let m = crate::scenes::y_shape(4).build().unwrap();
        let model = ReducedModel::build(
            &m,
            &Configuration::rest(&m),
            &[],
            &ConstructOptions::default(),
        )
        .unwrap();
        let e = ModelExport::new(&m, &model);
        let n = 6 * model.end_effectors.len();
        let w: Vec<f64> = (0..n).map(|k| ((k * 7 + 3) % 11) as f64 - 5.0).collect();
        let (ee, links) = model.static_twists(&w);
        for (i, t) in ee.iter().enumerate() {
            for (r, x) in t.to_array().iter().enumerate() {
                let got: f64 = (0..n).map(|c| e.compliance[6 * i + r][c] * w[c]).sum();
                assert!(
                    (got - x).abs() <= SAME_SUMS * (1.0 + x.abs()),
                    "C row {}",
                    6 * i + r
                );
            }
        }
        assert_eq!(e.twist_maps.len(), links.len());
        for (map, t) in e.twist_maps.iter().zip(&links) {
            for (r, x) in t.to_array().iter().enumerate() {
                let got: f64 = (0..n).map(|c| map.map[r][c] * w[c]).sum();
                assert!(
                    (got - x).abs() <= SUMMED_MAPS * (1.0 + x.abs()),
                    "{}: row {r}",
                    map.frame.link
                );
            }
        }
        assert_eq!(e.end_effectors[0].link, "a3");
        assert_eq!(e.rank, model.rank);
    }
}
