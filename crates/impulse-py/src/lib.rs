//! # impulse-py — the `impulse` Python package (layer 5)
//!
//! The extension module `impulse._impulse`, built by maturin (`pip install ./crates/impulse-py`),
//! that the Python package `impulse` (`python/impulse/`) re-exports. NumPy `float64` arrays in
//! and out; shapes are given in each function's docstring and in `python/impulse/_impulse.pyi`.
//!
//! **Owns**: the Python-facing names and call shapes of the library — exact mass properties of
//! meshes (thesis ch. 6, `massprops`), worlds built from scene files or in code (bodies and
//! URDF or inline multibodies) and stepped with every body's state read as one array, the
//! last step's contacts and the held pairs' impulses as arrays, loads constant or computed by a
//! Python function the simulator calls back (`world`), articulated-body dynamics of URDF
//! models (ABA, RNEA, CRBA; thesis ch. 4, `dynamics`), pose-study shards and their merge
//! (thesis §7.5, `poses`), bowling-study shards, their merge and binned pins felled (thesis
//! §7.4, `bowling`), FORK⁻¹S reduced mechanisms' matrices, static response and dynamics
//! (`reduced`); turning every library error into the Python exception
//! [`ImpulseError`] carrying the library's message; checking array shapes and finiteness before
//! anything reaches the library; releasing the GIL (`Python::detach`) around every call that
//! may take long, and taking it back only to call a Python load function.
//!
//! **Must not know** any algorithm (each function is a thin shell over a library crate, as
//! the CLI is), nor Dask or any scheduler: `impulse.distributed` is plain Python over the
//! shard and merge functions here.
//!
//! No `unsafe` of ours: PyO3's macros generate the FFI to CPython.
#![forbid(unsafe_code)]

mod bowling;
mod dynamics;
mod massprops;
mod poses;
mod reduced;
mod study_file;
mod world;

use glam::DVec3;
use numpy::ndarray::Array2;
use numpy::{AllowTypeChange, IntoPyArray, PyArray2, PyArrayLike1, PyArrayLike2};
use pyo3::prelude::*;

pyo3::create_exception!(
    impulse,
    ImpulseError,
    pyo3::exceptions::PyValueError,
    "An error of the impulse library: bad input (a NaN, an unknown body, a malformed file) or a \
     failed computation. The message is the library's, naming what is wrong and where."
);

/// An [`ImpulseError`] carrying `e`'s message (the library's typed error, as the CLI prints it).
pub(crate) fn error(e: impl std::fmt::Display) -> PyErr {
    ImpulseError::new_err(e.to_string())
}

/// A 1-D float64 array-like input (any sequence of numbers; integers are converted).
pub(crate) type Vector<'py> = PyArrayLike1<'py, f64, AllowTypeChange>;
/// A 2-D float64 array-like input.
pub(crate) type Matrix<'py> = PyArrayLike2<'py, f64, AllowTypeChange>;

/// The values of a 1-D input named `what`, all finite, of length `len` if given.
pub(crate) fn finite_vector(what: &str, v: &Vector<'_>, len: Option<usize>) -> PyResult<Vec<f64>> {
    let values: Vec<f64> = v.as_array().iter().copied().collect();
    if let Some(n) = len
        && values.len() != n
    {
        return Err(error(format!(
            "{what}: expected {n} values, got {}",
            values.len()
        )));
    }
    if let Some(k) = values.iter().position(|x| !x.is_finite()) {
        return Err(error(format!(
            "{what}[{k}] is {}: every value must be finite",
            values[k]
        )));
    }
    Ok(values)
}

/// A 3-vector input named `what` (finite).
pub(crate) fn vec3(what: &str, v: &Vector<'_>) -> PyResult<[f64; 3]> {
    let values = finite_vector(what, v, Some(3))?;
    Ok([values[0], values[1], values[2]])
}

/// The rows of an (n, 3) input named `what` (finite).
pub(crate) fn points(what: &str, m: &Matrix<'_>) -> PyResult<Vec<[f64; 3]>> {
    let a = m.as_array();
    if a.ncols() != 3 {
        return Err(error(format!(
            "{what}: expected an (n, 3) array, got shape {:?}",
            a.shape()
        )));
    }
    let mut out = Vec::with_capacity(a.nrows());
    for (i, row) in a.rows().into_iter().enumerate() {
        let p = [row[0], row[1], row[2]];
        if let Some(k) = p.iter().position(|x| !x.is_finite()) {
            return Err(error(format!(
                "{what}[{i}, {k}] is {}: every coordinate must be finite",
                p[k]
            )));
        }
        out.push(p);
    }
    Ok(out)
}

/// An (n, k) float64 array from n rows of k values.
pub(crate) fn rows_to_array<'py, const K: usize>(
    py: Python<'py>,
    rows: impl ExactSizeIterator<Item = [f64; K]>,
) -> Bound<'py, PyArray2<f64>> {
    let n = rows.len();
    let mut flat = Vec::with_capacity(n * K);
    for r in rows {
        flat.extend_from_slice(&r);
    }
    Array2::from_shape_vec((n, K), flat)
        .expect("n rows of K values")
        .into_pyarray(py)
}

/// One vector of each item, `f(item)`, as an (n, 3) array.
pub(crate) fn vector_rows<'py, T>(
    py: Python<'py>,
    items: &[T],
    f: impl Fn(&T) -> DVec3,
) -> Bound<'py, PyArray2<f64>> {
    rows_to_array(py, items.iter().map(|x| f(x).to_array()))
}

/// A 3×3 matrix as a (3, 3) array, row by row.
pub(crate) fn mat3_rows(py: Python<'_>, rows: [DVec3; 3]) -> Bound<'_, PyArray2<f64>> {
    rows_to_array(py, rows.into_iter().map(|v| v.to_array()))
}

/// The extension module `impulse._impulse`; `impulse/__init__.py` re-exports its names.
#[pymodule]
fn _impulse(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("ImpulseError", m.py().get_type::<ImpulseError>())?;
    // The crate's version, which maturin also gives the package (`dynamic = ["version"]`).
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    massprops::register(m)?;
    world::register(m)?;
    dynamics::register(m)?;
    poses::register(m)?;
    bowling::register(m)?;
    reduced::register(m)?;
    Ok(())
}
