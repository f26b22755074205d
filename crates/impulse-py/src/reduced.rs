//! Reduced compliant mechanisms (FORK⁻¹S, Andrews, Teichmann & Kry): built from a
//! `Mechanism(...)` file at rest, the model's matrices (compliance C, eq. 9; stiffness K = C⁺;
//! mass M) as arrays, and the static response under end-effector loads beside the full
//! nonlinear statics — what `impulse reduce --static` and `--compliance` give — and the
//! reduced dynamics (FORK⁻¹S §6: backward Euler, frictional contact with a ground plane),
//! stepped from Python or run to an end time as `impulse reduce --until T --dt H --out FILE`
//! runs it, with the same numbers.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::{Mutex, PoisonError};

use glam::DVec3;
use impulse_geom::Pose;
use impulse_reduced::reference::kinematics::link_poses;
use impulse_reduced::reference::{Configuration, Load, StaticOptions, solve_statics};
// faer's matrix, re-exported by impulse-multibody (the same faer as impulse-reduced's).
use impulse_multibody::Mat;
use impulse_reduced::{
    ConstructOptions, Mechanism, MechanismDesc, Obstacle, ReducedModel, ReducedSim, Tsvd,
};
use numpy::ndarray::{Array2, Array3};
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

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

/// The loads of `loads` (link name → force (3,) or force and torque (6,), world) on links of
/// `mechanism`.
fn parse_loads(mechanism: &Mechanism, loads: &BTreeMap<String, Vector<'_>>) -> PyResult<Vec<Load>> {
    let mut out = Vec::with_capacity(loads.len());
    for (name, v) in loads {
        let link = mechanism.link_index(name).ok_or_else(|| {
            error(format!(
                "load on \"{name}\": no link of that name in mechanism \"{}\"",
                mechanism.name
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

/// The end effectors' link names, in the order of the model's 6-blocks.
fn end_effector_names(mechanism: &Mechanism, model: &ReducedModel) -> Vec<String> {
    model
        .end_effectors
        .iter()
        .map(|&e| mechanism.links[e].name.clone())
        .collect()
}

/// The stacked body wrenches (6E) of `loads` on the end effectors, each held in its end
/// effector's frame at rest, as `impulse reduce --load` makes them (only end effectors may be
/// loaded).
fn end_effector_wrenches(
    mechanism: &Mechanism,
    model: &ReducedModel,
    loads: &BTreeMap<String, Vector<'_>>,
) -> PyResult<Vec<f64>> {
    wrenches_of(mechanism, model, &parse_loads(mechanism, loads)?).map_err(error)
}

/// [`end_effector_wrenches`] of parsed loads.
fn wrenches_of(
    mechanism: &Mechanism,
    model: &ReducedModel,
    loads: &[Load],
) -> Result<Vec<f64>, String> {
    model.end_effector_wrenches(loads).map_err(|link| {
        format!(
            "load on \"{}\": not an end effector (those are {:?})",
            mechanism.links[link].name,
            end_effector_names(mechanism, model)
        )
    })
}

/// Most steps one call may take: `impulse reduce`'s limit on `--until / --dt` (at the
/// fastest step measured, about an hour; a count past it is a mistake in `dt` or `until`).
const MAX_STEPS: f64 = 1e9;

/// A prepared reduced simulation of `mechanism`'s model with step `dt`, the `ground` plane and
/// the held `loads`, as `impulse reduce` prepares its run; the system matrix is factored with
/// the GIL released.
fn prepare(
    py: Python<'_>,
    mechanism: &Mechanism,
    model: &ReducedModel,
    dt: f64,
    loads: Option<&BTreeMap<String, Vector<'_>>>,
    ground: Option<f64>,
    threads: Option<usize>,
) -> PyResult<ReducedSim> {
    if !(dt.is_finite() && dt > 0.0) {
        return Err(error(format!(
            "dt {dt}: the time step must be a positive number of seconds (backward Euler is \
             stable for any step; there is no automatic step)"
        )));
    }
    if let Some(z) = ground
        && !z.is_finite()
    {
        return Err(error(format!(
            "ground {z}: the plane's height must be finite"
        )));
    }
    let external = match loads {
        Some(l) => end_effector_wrenches(mechanism, model, l)?,
        None => vec![0.0; 6 * model.end_effectors.len()],
    };
    py.detach(|| {
        let mut sim = ReducedSim::new(mechanism, model.clone(), dt).map_err(|e| e.to_string())?;
        if let Some(n) = threads {
            sim.set_threads(n)
                .map_err(|e| format!("threads {n}: {e}"))?;
        }
        sim.external = external;
        if let Some(z) = ground {
            sim.obstacles.push(Obstacle::Plane {
                normal: DVec3::Z,
                offset: z,
            });
        }
        Ok(sim)
    })
    .map_err(|e: String| error(e))
}

/// The world poses of the end effectors, then of the internal links (the order of `impulse
/// reduce --out`), written into `internal` (one per internal link) and returned.
fn link_poses_of(sim: &ReducedSim, internal: &mut [Pose]) -> Vec<Pose> {
    sim.internal_poses(internal);
    (0..sim.model.end_effectors.len())
        .map(|i| sim.end_effector_pose(i))
        .chain(internal.iter().copied())
        .collect()
}

/// The names of the links in `link_poses_of`'s order.
fn link_names(mechanism: &Mechanism, model: &ReducedModel) -> Vec<String> {
    model
        .end_effectors
        .iter()
        .chain(&model.internal)
        .map(|&l| mechanism.links[l].name.clone())
        .collect()
}

/// The error for a pose that left double precision, as `impulse reduce` words it; `None`
/// while every pose is finite.
fn non_finite(poses: &[Pose], names: &[String], step: u64, dt: f64) -> Option<String> {
    let n = poses
        .iter()
        .position(|p| !(p.translation.is_finite() && p.rotation.is_finite()))?;
    Some(format!(
        "the reduced model's state is not finite at t = {} s (step {step}): link `{}` has no \
         finite pose; the loads or the step are too large for double precision",
        step as f64 * dt,
        names[n]
    ))
}

/// The number of steps of `until` s at `dt` s, checked as `impulse reduce` checks them.
fn step_count(until: f64, dt: f64) -> PyResult<u64> {
    if !(until.is_finite() && until > 0.0) {
        return Err(error(format!(
            "until {until}: the end time must be a positive number of seconds"
        )));
    }
    if !(dt.is_finite() && dt > 0.0) {
        return Err(error(format!(
            "dt {dt}: the time step must be a positive number of seconds"
        )));
    }
    let steps = (until / dt).ceil();
    if steps > MAX_STEPS {
        return Err(error(format!(
            "dt {dt} with until {until}: {steps:.3e} steps, over the limit of {MAX_STEPS:.0e}: \
             raise dt or lower until"
        )));
    }
    Ok(steps as u64)
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
        end_effector_names(&self.mechanism, &self.model)
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
        let w = end_effector_wrenches(&self.mechanism, &self.model, &loads)?;
        let model = &self.model;
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
        let loads = parse_loads(&self.mechanism, &loads)?;
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

    /// A reduced simulation of the mechanism (FORK⁻¹S §6) at rest, to step from Python: step
    /// `dt` (s, > 0; backward Euler, stable for any step, accurate well below the model's
    /// fastest period; the system matrix is factored once for it), `loads` held on the end
    /// effectors (a dict as `static_positions` takes; each held in its end effector's frame at
    /// rest, so it turns with it, as `impulse reduce --load` holds it), `ground`: the height z
    /// of a ground plane (friction 0.5, `--ground`), `threads` placing the internal links
    /// (default: rayon's pool of every core; the result does not depend on it).
    #[pyo3(signature = (dt=1e-3, loads=None, ground=None, threads=None))]
    fn simulation(
        &self,
        py: Python<'_>,
        dt: f64,
        loads: Option<BTreeMap<String, Vector<'_>>>,
        ground: Option<f64>,
        threads: Option<usize>,
    ) -> PyResult<ReducedSimulation> {
        let sim = prepare(
            py,
            &self.mechanism,
            &self.model,
            dt,
            loads.as_ref(),
            ground,
            threads,
        )?;
        Ok(ReducedSimulation {
            names: link_names(&self.mechanism, &self.model),
            mechanism: self.mechanism.clone(),
            state: Mutex::new(SimState {
                sim,
                steps: 0,
                contacts: 0,
            }),
        })
    }

    /// Runs the reduced dynamics from rest to `until` s in steps of `dt` (ceil(until / dt)
    /// steps) with the GIL released, as `impulse reduce --until UNTIL --dt DT [--load …]
    /// [--ground Z] --out FILE` does (same numbers, bit for bit), and returns a dict of
    /// - `links`: the L links' names, end effectors first, then the internal links;
    /// - `time` (F,): the times of the recorded steps (k·dt for step k; every `every`-th
    ///   step and the last, as the CLI's frames with `every` = max(1, steps / 100));
    /// - `positions` (F, L, 3), `orientations` (F, L, 4): the links' world poses (origin and
    ///   quaternion x, y, z, w) at those times;
    /// - `constraint_error` (F,): the relative constraint error of the reconstructed
    ///   mechanism (§8.2), how far the reduced model has left its range.
    ///
    /// `loads`, `ground`, `threads` as `simulation` takes them. Raises `ImpulseError` for a
    /// bad time, step or load, and for a state that leaves double precision.
    #[pyo3(signature = (until, dt=1e-3, loads=None, ground=None, threads=None, every=1))]
    #[allow(clippy::too_many_arguments)] // Python keyword arguments
    fn simulate<'py>(
        &self,
        py: Python<'py>,
        until: f64,
        dt: f64,
        loads: Option<BTreeMap<String, Vector<'_>>>,
        ground: Option<f64>,
        threads: Option<usize>,
        every: u64,
    ) -> PyResult<Bound<'py, PyDict>> {
        let steps = step_count(until, dt)?;
        if every == 0 {
            return Err(error("every 0: must be at least 1 (1 records every step)"));
        }
        let mut sim = prepare(
            py,
            &self.mechanism,
            &self.model,
            dt,
            loads.as_ref(),
            ground,
            threads,
        )?;
        let names = link_names(&self.mechanism, &self.model);
        let m = &self.mechanism;
        let (times, frames, errors) = py
            .detach(|| {
                let mut internal = vec![Pose::IDENTITY; sim.model.internal.len()];
                let (mut times, mut frames, mut errors) = (Vec::new(), Vec::new(), Vec::new());
                for k in 1..=steps {
                    sim.step();
                    let poses = link_poses_of(&sim, &mut internal);
                    if let Some(e) = non_finite(&poses, &names, k, dt) {
                        return Err(e);
                    }
                    if k % every == 0 || k == steps {
                        times.push(k as f64 * dt);
                        errors.push(sim.constraint_error(m));
                        frames.push(poses);
                    }
                }
                Ok((times, frames, errors))
            })
            .map_err(error)?;
        let (f, l) = (frames.len(), names.len());
        let flat = |g: fn(&Pose) -> Vec<f64>| frames.iter().flatten().flat_map(g).collect();
        let positions =
            Array3::from_shape_vec((f, l, 3), flat(|p| p.translation.to_array().to_vec()))
                .expect("F × L × 3 values");
        let orientations =
            Array3::from_shape_vec((f, l, 4), flat(|p| p.rotation.to_array().to_vec()))
                .expect("F × L × 4 values");
        let d = PyDict::new(py);
        d.set_item("links", names)?;
        d.set_item("time", PyArray1::from_vec(py, times))?;
        d.set_item("positions", positions.into_pyarray(py))?;
        d.set_item("orientations", orientations.into_pyarray(py))?;
        d.set_item("constraint_error", PyArray1::from_vec(py, errors))?;
        Ok(d)
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

/// The state of a running reduced simulation.
struct SimState {
    sim: ReducedSim,
    /// Steps taken.
    steps: u64,
    /// End-effector contacts with the ground in the last step.
    contacts: usize,
}

/// A running FORK⁻¹S reduced simulation (§6), made by `ReducedMechanism.simulation`: step it
/// with `step` (the GIL released) and read the links' poses as arrays. Links are numbered as
/// `links()` names them: the E end effectors, then the internal links.
#[pyclass(frozen, module = "impulse._impulse")]
pub struct ReducedSimulation {
    mechanism: Mechanism,
    names: Vec<String>,
    state: Mutex<SimState>,
}

impl ReducedSimulation {
    /// The state, locked (waits without the GIL if another thread holds it).
    fn with<T: Send>(&self, py: Python<'_>, f: impl FnOnce(&mut SimState) -> T + Send) -> T {
        match self.state.try_lock() {
            Ok(mut s) => f(&mut s),
            Err(_) => {
                py.detach(|| f(&mut self.state.lock().unwrap_or_else(PoisonError::into_inner)))
            }
        }
    }

    /// Every link's world pose (`links()` order).
    fn poses(&self, py: Python<'_>) -> Vec<Pose> {
        self.with(py, |s| {
            let mut internal = vec![Pose::IDENTITY; s.sim.model.internal.len()];
            link_poses_of(&s.sim, &mut internal)
        })
    }
}

#[pymethods]
impl ReducedSimulation {
    /// Advances `steps` steps of `dt` with the GIL released; returns the end effectors' world
    /// positions after them, shape (E, 3). Raises `ImpulseError` (and stops at that step) when
    /// a link's pose leaves double precision.
    #[pyo3(signature = (steps=1))]
    fn step<'py>(&self, py: Python<'py>, steps: u64) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let names = &self.names;
        let ends = py
            .detach(|| {
                let mut s = self.state.lock().unwrap_or_else(PoisonError::into_inner);
                let mut internal = vec![Pose::IDENTITY; s.sim.model.internal.len()];
                let dt = s.sim.h;
                for _ in 0..steps {
                    s.contacts = s.sim.step().contacts;
                    s.steps += 1;
                    let poses = link_poses_of(&s.sim, &mut internal);
                    if let Some(e) = non_finite(&poses, names, s.steps, dt) {
                        return Err(e);
                    }
                }
                Ok((0..s.sim.model.end_effectors.len())
                    .map(|i| s.sim.end_effector_pose(i).translation.to_array())
                    .collect::<Vec<_>>())
            })
            .map_err(error)?;
        Ok(rows_to_array(py, ends.into_iter()))
    }

    /// Replaces the loads held on the end effectors (a dict as `static_positions` takes;
    /// `{}` removes them).
    fn set_loads(&self, py: Python<'_>, loads: BTreeMap<String, Vector<'_>>) -> PyResult<()> {
        let loads = parse_loads(&self.mechanism, &loads)?;
        let m = &self.mechanism;
        self.with(py, |s| {
            s.sim.external = wrenches_of(m, &s.sim.model, &loads)?;
            Ok(())
        })
        .map_err(|e: String| error(e))
    }

    /// The time step (s).
    #[getter]
    fn dt(&self, py: Python<'_>) -> f64 {
        self.with(py, |s| s.sim.h)
    }

    /// Simulated time: steps taken × dt (s).
    #[getter]
    fn time(&self, py: Python<'_>) -> f64 {
        self.with(py, |s| s.steps as f64 * s.sim.h)
    }

    /// Steps taken.
    #[getter]
    fn steps(&self, py: Python<'_>) -> u64 {
        self.with(py, |s| s.steps)
    }

    /// End-effector contacts with the ground in the last step.
    #[getter]
    fn contacts(&self, py: Python<'_>) -> usize {
        self.with(py, |s| s.contacts)
    }

    /// The links' names: the end effectors, then the internal links.
    fn links(&self) -> Vec<String> {
        self.names.clone()
    }

    /// The links' world positions (frame origins), shape (L, 3), `links()` order.
    fn positions<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        rows_to_array(py, self.poses(py).iter().map(|p| p.translation.to_array()))
    }

    /// The links' world orientations as quaternions (x, y, z, w), shape (L, 4).
    fn orientations<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        rows_to_array(py, self.poses(py).iter().map(|p| p.rotation.to_array()))
    }

    /// The end effectors' world positions, shape (E, 3).
    fn end_effector_positions<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let rows: Vec<[f64; 3]> = self.with(py, |s| {
            (0..s.sim.model.end_effectors.len())
                .map(|i| s.sim.end_effector_pose(i).translation.to_array())
                .collect()
        });
        rows_to_array(py, rows.into_iter())
    }

    /// The end effectors' displacement twists ξ (body frames at their reference poses, linear
    /// on top), shape (E, 6), and their body velocities φ, shape (E, 6): the reduced state.
    fn state<'py>(
        &self,
        py: Python<'py>,
    ) -> (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<f64>>) {
        let (xi, phi) = self.with(py, |s| (s.sim.xi.clone(), s.sim.phi.clone()));
        let six = |v: Vec<f64>| {
            Array2::from_shape_vec((v.len() / 6, 6), v)
                .expect("6 values per end effector")
                .into_pyarray(py)
        };
        (six(xi), six(phi))
    }

    /// Energy of the end-effector system, ½φᵀMφ + ½ξᵀKξ (J).
    fn energy(&self, py: Python<'_>) -> f64 {
        self.with(py, |s| s.sim.energy())
    }

    /// The relative constraint error of the reconstructed mechanism (§8.2).
    fn constraint_error(&self, py: Python<'_>) -> f64 {
        let m = &self.mechanism;
        self.with(py, |s| s.sim.constraint_error(m))
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        let (steps, dt) = self.with(py, |s| (s.steps, s.sim.h));
        format!(
            "ReducedSimulation({:?}, {} links, dt = {dt}, t = {})",
            self.mechanism.name,
            self.names.len(),
            steps as f64 * dt
        )
    }
}

/// Adds this module's names to the extension module.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<ReducedMechanism>()?;
    m.add_class::<ReducedSimulation>()?;
    Ok(())
}
