//! Articulated-body dynamics of URDF models (thesis chapter 4, Featherstone's algorithms):
//! what `impulse dynamics` prints, with a call shape like Pinocchio's (`aba(model, q, v, tau)`;
//! the model holds its own workspace, Pinocchio's `data`).

use std::path::PathBuf;
use std::sync::{Mutex, PoisonError};

use glam::DVec3;
use impulse_multibody::{
    BaseKind, Mat, Model as MbModel, Workspace, forward_dynamics, inverse_dynamics, mass_matrix,
    urdf,
};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pyo3::prelude::*;

use crate::{Vector, error, finite_vector, vec3};

/// A multibody model read from a URDF file (thesis ch. 4): joints in the model's order
/// (depth-first from the root link; `joint_names()`), fixed joints without a coordinate.
#[pyclass(frozen, module = "impulse._impulse")]
pub struct Model {
    model: MbModel,
    /// Pinocchio's `data`: scratch space of the recursions, reused between calls.
    workspace: Mutex<Workspace>,
}

impl Model {
    /// Names the expected layout of a vector of `n` values in messages.
    fn layout(&self, base_values: usize) -> String {
        let names = self.model.joint_names().join(", ");
        if self.model.is_floating() {
            format!("{base_values} base values, then joints [{names}]")
        } else {
            format!("one per joint: [{names}]")
        }
    }

    /// Checks a vector input: finite, of the model's length.
    fn input(&self, what: &str, v: &Vector<'_>, len: usize, base: usize) -> PyResult<Vec<f64>> {
        let values = finite_vector(what, v, None)?;
        if values.len() != len {
            return Err(error(format!(
                "{what}: expected {len} values ({}), got {}",
                self.layout(base),
                values.len()
            )));
        }
        Ok(values)
    }

    /// Runs `f` on the model and its workspace with the GIL released; refuses a non-finite
    /// result (inputs whose products overflow) naming the coordinate.
    fn run<T: Send>(
        &self,
        py: Python<'_>,
        f: impl FnOnce(&MbModel, &mut Workspace) -> Result<T, String> + Send,
    ) -> PyResult<T> {
        py.detach(|| {
            let mut ws = self
                .workspace
                .lock()
                .unwrap_or_else(PoisonError::into_inner);
            f(&self.model, &mut ws)
        })
        .map_err(error)
    }

    /// `Err` naming the first non-finite value of `values`, a result called `quantity`.
    fn finite(&self, quantity: &str, values: &[f64]) -> Result<(), String> {
        let Some(k) = values.iter().position(|x| !x.is_finite()) else {
            return Ok(());
        };
        let base = if self.model.is_floating() { 6 } else { 0 };
        let coordinate = match k.checked_sub(base) {
            Some(j) => format!("joint `{}`", self.model.joint_names()[j]),
            None => format!("base coordinate {k}"),
        };
        Err(format!(
            "{quantity} of {coordinate} is {}: the inputs overflow double precision",
            values[k]
        ))
    }
}

#[pymethods]
impl Model {
    /// Reads a URDF file. `floating_base`: the root link floats freely (q starts with the
    /// base position and quaternion x, y, z, qx, qy, qz, qw; v and tau with the base twist /
    /// wrench in base coordinates); `gravity`: shape (3,), default (0, 0, −9.81). Raises
    /// `ImpulseError` for a missing or malformed file, naming the element.
    #[staticmethod]
    #[pyo3(signature = (path, floating_base=false, gravity=None))]
    fn from_urdf(
        py: Python<'_>,
        path: PathBuf,
        floating_base: bool,
        gravity: Option<Vector<'_>>,
    ) -> PyResult<Self> {
        let g = match gravity {
            Some(g) => DVec3::from_array(vec3("gravity", &g)?),
            None => DVec3::new(0.0, 0.0, -9.81),
        };
        let base = if floating_base {
            BaseKind::Floating
        } else {
            BaseKind::Fixed
        };
        let mut model = py
            .detach(|| urdf::from_file(&path, base).map_err(|e| e.to_string()))
            .map_err(error)?;
        model.set_gravity(g);
        let workspace = Mutex::new(Workspace::new(&model));
        Ok(Self { model, workspace })
    }

    /// Number of configuration coordinates (length of q).
    #[getter]
    fn nq(&self) -> usize {
        self.model.nq()
    }

    /// Number of velocity coordinates (length of v, tau, and the side of M).
    #[getter]
    fn nv(&self) -> usize {
        self.model.nv()
    }

    /// The moving joints' names in coordinate order.
    fn joint_names(&self) -> Vec<String> {
        self.model.joint_names().to_vec()
    }

    /// The neutral configuration q0, shape (nq,): zeros, the identity base orientation.
    fn neutral_configuration<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.model.neutral_configuration().into_pyarray(py)
    }

    fn __repr__(&self) -> String {
        format!(
            "Model(nq={}, nv={}, joints={:?})",
            self.model.nq(),
            self.model.nv(),
            self.model.joint_names()
        )
    }
}

/// Forward dynamics by the articulated-body algorithm (ABA, thesis §4.3): the accelerations
/// qdd, shape (nv,), for positions `q` (nq,), velocities `v` (nv,) and joint forces `tau`
/// (nv,). Passive damping and friction are not applied (as `impulse dynamics`).
#[pyfunction]
fn aba<'py>(
    py: Python<'py>,
    model: &Model,
    q: Vector<'_>,
    v: Vector<'_>,
    tau: Vector<'_>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let (nq, nv) = (model.model.nq(), model.model.nv());
    let q = model.input("q", &q, nq, 7)?;
    let v = model.input("v", &v, nv, 6)?;
    let tau = model.input("tau", &tau, nv, 6)?;
    let qdd = model.run(py, |m, ws| {
        let mut qdd = vec![0.0; nv];
        forward_dynamics(m, ws, &q, &v, &tau, None, &mut qdd).map_err(|e| e.to_string())?;
        model.finite("qdd", &qdd)?;
        Ok(qdd)
    })?;
    Ok(qdd.into_pyarray(py))
}

/// Inverse dynamics by the recursive Newton–Euler algorithm (RNEA): the joint forces tau,
/// shape (nv,), that give accelerations `a` (nv,) at positions `q` (nq,) and velocities `v`
/// (nv,).
#[pyfunction]
fn rnea<'py>(
    py: Python<'py>,
    model: &Model,
    q: Vector<'_>,
    v: Vector<'_>,
    a: Vector<'_>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let (nq, nv) = (model.model.nq(), model.model.nv());
    let q = model.input("q", &q, nq, 7)?;
    let v = model.input("v", &v, nv, 6)?;
    let a = model.input("a", &a, nv, 6)?;
    let tau = model.run(py, |m, ws| {
        let mut tau = vec![0.0; nv];
        inverse_dynamics(m, ws, &q, &v, &a, None, &mut tau).map_err(|e| e.to_string())?;
        model.finite("tau", &tau)?;
        Ok(tau)
    })?;
    Ok(tau.into_pyarray(py))
}

/// The joint-space mass matrix M(q) by the composite-rigid-body algorithm (CRBA), shape
/// (nv, nv), symmetric positive definite; `q`: (nq,).
#[pyfunction]
fn crba<'py>(py: Python<'py>, model: &Model, q: Vector<'_>) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let (nq, nv) = (model.model.nq(), model.model.nv());
    let q = model.input("q", &q, nq, 7)?;
    let flat = model.run(py, |m, ws| {
        let mut mm = Mat::<f64>::zeros(nv, nv);
        mass_matrix(m, ws, &q, &mut mm).map_err(|e| e.to_string())?;
        let flat: Vec<f64> = (0..nv)
            .flat_map(|r| (0..nv).map(move |c| (r, c)))
            .map(|(r, c)| mm[(r, c)])
            .collect();
        model.finite("mass matrix entry", &flat)?;
        Ok(flat)
    })?;
    Ok(Array2::from_shape_vec((nv, nv), flat)
        .expect("nv × nv values")
        .into_pyarray(py))
}

/// Adds this module's names to the extension module.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Model>()?;
    m.add_function(wrap_pyfunction!(aba, m)?)?;
    m.add_function(wrap_pyfunction!(rnea, m)?)?;
    m.add_function(wrap_pyfunction!(crba, m)?)?;
    Ok(())
}
