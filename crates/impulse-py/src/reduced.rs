//! Reduced compliant mechanisms (FORK⁻¹S, Andrews, Teichmann & Kry): built from a
//! `Mechanism(...)` file at rest, the model's matrices (compliance C, eq. 9; stiffness K = C⁺;
//! mass M) as arrays, and the static response under end-effector loads beside the full
//! nonlinear statics — what `impulse reduce --static` and `--compliance` give. Simulation is
//! not bound yet.

use std::collections::BTreeMap;
use std::path::PathBuf;

use glam::DVec3;
use impulse_geom::Pose;
use impulse_reduced::reference::kinematics::link_poses;
use impulse_reduced::reference::{Configuration, Load, StaticOptions, solve_statics};
// faer's matrix, re-exported by impulse-multibody (the same faer as impulse-reduced's).
use impulse_multibody::Mat;
use impulse_reduced::{ConstructOptions, Mechanism, MechanismDesc, ReducedModel, Tsvd};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray2};
use pyo3::prelude::*;

use crate::{Vector, error, finite_vector, rows_to_array};

/// A FORK⁻¹S reduced model of a compliant mechanism, built at its rest configuration.
#[pyclass(frozen, module = "impulse._impulse")]
pub struct ReducedMechanism {
    mechanism: Mechanism,
    model: ReducedModel,
}

/// A faer matrix as a 2-D array.
fn matrix<'py>(py: Python<'py>, m: &Mat<f64>) -> Bound<'py, PyArray2<f64>> {
    let (r, c) = (m.nrows(), m.ncols());
    let flat: Vec<f64> = (0..r)
        .flat_map(|i| (0..c).map(move |j| (i, j)))
        .map(|(i, j)| m[(i, j)])
        .collect();
    Array2::from_shape_vec((r, c), flat)
        .expect("r × c values")
        .into_pyarray(py)
}

impl ReducedMechanism {
    /// The loads of `loads` (link name → force (3,) or force and torque (6,), world).
    fn loads(&self, loads: &BTreeMap<String, Vector<'_>>) -> PyResult<Vec<Load>> {
        let mut out = Vec::with_capacity(loads.len());
        for (name, v) in loads {
            let link = self.mechanism.link_index(name).ok_or_else(|| {
                error(format!(
                    "load on \"{name}\": no link of that name in mechanism \"{}\"",
                    self.mechanism.name
                ))
            })?;
            let v = finite_vector(&format!("load on \"{name}\""), v, None)?;
            if !(v.len() == 3 || v.len() == 6) {
                return Err(error(format!(
                    "load on \"{name}\": give a force (3 values) or a force and a torque (6), \
                     not {}",
                    v.len()
                )));
            }
            let torque = if v.len() == 6 {
                DVec3::new(v[3], v[4], v[5])
            } else {
                DVec3::ZERO
            };
            out.push(Load {
                link,
                force: DVec3::new(v[0], v[1], v[2]),
                torque,
            });
        }
        Ok(out)
    }
}

#[pymethods]
impl ReducedMechanism {
    /// Reads a `Mechanism(...)` file (see `fixtures/mechanisms/`) and builds its reduced model
    /// at rest (eqs. 9–22), as `impulse reduce` does; `tsvd`: the relative truncation of
    /// `--tsvd` (default: the library's). Raises `ImpulseError` for a missing or malformed
    /// file or a mechanism that cannot be built.
    #[staticmethod]
    #[pyo3(signature = (path, tsvd=None))]
    fn from_file(py: Python<'_>, path: PathBuf, tsvd: Option<f64>) -> PyResult<Self> {
        let tsvd = match tsvd {
            Some(t) => Tsvd::with_relative(t).map_err(|e| error(format!("tsvd {t}: {e}")))?,
            None => Tsvd::default(),
        };
        py.detach(|| {
            let shown = path.display();
            let text = std::fs::read_to_string(&path).map_err(|e| format!("{shown}: {e}"))?;
            let desc = MechanismDesc::from_ron(&text).map_err(|e| format!("{shown}: {e}"))?;
            let mechanism = desc.build().map_err(|e| format!("{shown}: {e}"))?;
            let options = ConstructOptions {
                tsvd,
                ..ConstructOptions::default()
            };
            let model =
                ReducedModel::build(&mechanism, &Configuration::rest(&mechanism), &[], &options)
                    .map_err(|e| format!("{shown}: {e}"))?;
            Ok(Self { mechanism, model })
        })
        .map_err(|e: String| error(e))
    }

    /// The mechanism's name.
    #[getter]
    fn name(&self) -> &str {
        &self.mechanism.name
    }

    /// Rank of C: the number of admissible end-effector directions.
    #[getter]
    fn rank(&self) -> usize {
        self.model.rank
    }

    /// The end effectors' link names, in the order of the matrices' 6-blocks.
    fn end_effectors(&self) -> Vec<String> {
        self.model
            .end_effectors
            .iter()
            .map(|&e| self.mechanism.links[e].name.clone())
            .collect()
    }

    /// The compliance C (eq. 9), shape (6E, 6E): end-effector twists (linear on top, in each
    /// end effector's reference frame) per unit body wrench — `--compliance`'s `compliance`.
    fn compliance<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        matrix(py, &self.model.compliance)
    }

    /// The stiffness K = C⁺ at the model's rank, shape (6E, 6E).
    fn stiffness<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        matrix(py, &self.model.stiffness)
    }

    /// The reduced mass matrix M = A⁺, shape (6E, 6E).
    fn mass<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        matrix(py, &self.model.mass)
    }

    /// The end effectors' reference positions (world), shape (E, 3).
    fn reference_positions<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        rows_to_array(
            py,
            self.model
                .reference
                .iter()
                .map(|p| p.translation.to_array()),
        )
    }

    /// The reduced model's static response: end-effector positions (world), shape (E, 3),
    /// under `loads`, a dict from link name to a world force (3,) or force and torque (6,) —
    /// `impulse reduce --static`'s `reduced` positions. Only end effectors may be loaded.
    fn static_positions<'py>(
        &self,
        py: Python<'py>,
        loads: BTreeMap<String, Vector<'_>>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let loads = self.loads(&loads)?;
        let model = &self.model;
        let mut w = vec![0.0; 6 * model.end_effectors.len()];
        for l in &loads {
            let i = model
                .end_effectors
                .iter()
                .position(|&e| e == l.link)
                .ok_or_else(|| {
                    error(format!(
                        "load on \"{}\": not an end effector (those are {:?})",
                        self.mechanism.links[l.link].name,
                        self.end_effectors()
                    ))
                })?;
            let b = l.body_wrench(&model.reference[i]).to_array();
            for r in 0..6 {
                w[6 * i + r] += b[r];
            }
        }
        let (ee, _) = py.detach(|| model.static_twists(&w));
        let rows: Vec<[f64; 3]> = model
            .reference
            .iter()
            .zip(&ee)
            .map(|(p, t)| (*p * Pose::exp(t)).translation.to_array())
            .collect();
        Ok(rows_to_array(py, rows.into_iter()))
    }

    /// The full nonlinear statics under `loads` (as `static_positions`; any link may be
    /// loaded): the end-effector positions, shape (E, 3) — `impulse reduce --static`'s `full`
    /// positions, the reference the reduced model is judged by.
    fn full_static_positions<'py>(
        &self,
        py: Python<'py>,
        loads: BTreeMap<String, Vector<'_>>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let loads = self.loads(&loads)?;
        let m = &self.mechanism;
        let poses = py
            .detach(|| {
                solve_statics(m, &loads, None, &StaticOptions::default())
                    .map(|sol| link_poses(m, &sol.config))
                    .map_err(|e| e.to_string())
            })
            .map_err(error)?;
        Ok(rows_to_array(
            py,
            self.model
                .end_effectors
                .iter()
                .map(|&e| poses[e].translation.to_array()),
        ))
    }

    fn __repr__(&self) -> String {
        format!(
            "ReducedMechanism({:?}, end effectors {:?}, rank {})",
            self.mechanism.name,
            self.end_effectors(),
            self.model.rank
        )
    }
}

/// Adds this module's names to the extension module.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<ReducedMechanism>()?;
    Ok(())
}
