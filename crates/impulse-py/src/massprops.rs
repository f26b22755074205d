//! Exact mass properties of closed polygon meshes (thesis chapter 6): what `impulse
//! massprops` prints, as arrays.

use std::path::PathBuf;

use glam::DVec3;
use impulse_geom::{ConvexPolyhedron, PolyMesh};
use impulse_massprops::{MassProperties as Props, VolumeIntegrals};
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pyo3::prelude::*;

use crate::{Matrix, error, mat3_rows, points};

/// Exact mass properties of a solid of uniform density (thesis ch. 6): the numbers `impulse
/// massprops` prints.
#[pyclass(frozen, module = "impulse._impulse")]
pub struct MassProperties {
    volume: f64,
    props: Props,
    moments: DVec3,
    axes: [DVec3; 3],
}

#[pymethods]
impl MassProperties {
    /// Volume of the solid (float).
    #[getter]
    fn volume(&self) -> f64 {
        self.volume
    }

    /// Mass (float).
    #[getter]
    fn mass(&self) -> f64 {
        self.props.mass
    }

    /// Centre of mass, shape (3,).
    #[getter]
    fn com<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.props.com.to_array().to_vec().into_pyarray(py)
    }

    /// Inertia tensor about the centre of mass in the input's axes, shape (3, 3).
    #[getter]
    fn inertia<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let i = self.props.inertia;
        mat3_rows(py, [i.row(0), i.row(1), i.row(2)])
    }

    /// Principal moments of inertia, increasing, shape (3,).
    #[getter]
    fn principal_moments<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.moments.to_array().to_vec().into_pyarray(py)
    }

    /// Principal axes, shape (3, 3): row k is the unit axis of `principal_moments[k]` (a
    /// right-handed set), as `impulse massprops` prints `principal_axes`.
    #[getter]
    fn principal_axes<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        mat3_rows(py, self.axes)
    }

    fn __repr__(&self) -> String {
        format!(
            "MassProperties(volume={}, mass={}, com={:?})",
            self.volume,
            self.props.mass,
            self.props.com.to_array()
        )
    }
}

/// The mass properties of `mesh` with a density or a total mass (density 1 if neither).
fn of_mesh(
    mesh: &PolyMesh,
    density: Option<f64>,
    mass: Option<f64>,
) -> Result<MassProperties, String> {
    let props = match (density, mass) {
        (Some(_), Some(_)) => return Err("give a density or a mass, not both".into()),
        (_, Some(m)) => Props::from_mesh_with_mass(mesh, m),
        (d, None) => Props::from_mesh(mesh, d.unwrap_or(1.0)),
    }
    .map_err(|e| e.to_string())?;
    let volume = VolumeIntegrals::integrate(mesh, mesh.bounding_box_center()).volume;
    let frame = props.principal().map_err(|e| e.to_string())?;
    Ok(MassProperties {
        volume,
        props,
        moments: frame.moments,
        axes: [frame.axes.col(0), frame.axes.col(1), frame.axes.col(2)],
    })
}

/// Exact mass properties of a closed polygon mesh (thesis ch. 6).
///
/// `vertices`: float array of shape (n, 3). `faces`: an integer array of shape (m, k) (every
/// face a k-gon) or a list of index lists (polygons of any size), each face counter-clockwise
/// seen from outside, indices into `vertices`. The mesh must be closed and consistently
/// oriented; it may be non-convex and of any genus. Give `density` (default 1) or `mass`.
/// Raises `ImpulseError` naming the problem (an open edge and its face, an inward orientation,
/// a NaN coordinate, an index out of range).
#[pyfunction]
#[pyo3(signature = (vertices, faces, density=None, mass=None))]
fn mass_properties(
    py: Python<'_>,
    vertices: Matrix<'_>,
    faces: Vec<Vec<i64>>,
    density: Option<f64>,
    mass: Option<f64>,
) -> PyResult<MassProperties> {
    let vertices: Vec<DVec3> = points("vertices", &vertices)?
        .into_iter()
        .map(DVec3::from_array)
        .collect();
    let mut loops = Vec::with_capacity(faces.len());
    for (f, face) in faces.iter().enumerate() {
        let face = face
            .iter()
            .map(|&i| {
                u32::try_from(i).map_err(|_| {
                    error(format!("faces[{f}]: vertex index {i} is not a valid index"))
                })
            })
            .collect::<PyResult<Vec<u32>>>()?;
        loops.push(face);
    }
    py.detach(|| {
        let mesh = PolyMesh::new(vertices, &loops).map_err(|e| e.to_string())?;
        of_mesh(&mesh, density, mass)
    })
    .map_err(error)
}

/// Exact mass properties of the closed mesh in a Wavefront OBJ file: the numbers `impulse
/// massprops PATH [--density D | --mass M]` prints. Raises `ImpulseError` for a missing or
/// malformed file (naming the line) and for a mesh that is not closed.
#[pyfunction]
#[pyo3(signature = (path, density=None, mass=None))]
fn mass_properties_obj(
    py: Python<'_>,
    path: PathBuf,
    density: Option<f64>,
    mass: Option<f64>,
) -> PyResult<MassProperties> {
    py.detach(|| {
        let mesh = impulse_geom::obj::read(&path).map_err(|e| e.to_string())?;
        of_mesh(&mesh, density, mass)
    })
    .map_err(error)
}

/// A hull as arrays: vertices (v, 3) and faces (vertex-index lists).
type HullArrays<'py> = (Bound<'py, PyArray2<f64>>, Vec<Vec<u32>>);

/// The convex hull of `points`, shape (n, 3): its vertices, shape (v, 3), and its faces, a
/// list of vertex-index lists counter-clockwise seen from outside (coplanar triangles merged
/// into polygons) — a closed mesh `mass_properties` takes. Raises `ImpulseError` for fewer
/// than four points or coplanar points.
#[pyfunction]
fn convex_hull<'py>(py: Python<'py>, points: Matrix<'_>) -> PyResult<HullArrays<'py>> {
    let pts: Vec<DVec3> = crate::points("points", &points)?
        .into_iter()
        .map(DVec3::from_array)
        .collect();
    let hull = py
        .detach(|| ConvexPolyhedron::hull(&pts).map_err(|e| e.to_string()))
        .map_err(error)?;
    let mesh = hull.mesh();
    let faces = mesh.faces().map(<[u32]>::to_vec).collect();
    Ok((
        crate::rows_to_array(py, mesh.vertices().iter().map(|v| v.to_array())),
        faces,
    ))
}

/// Adds this module's names to the extension module.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<MassProperties>()?;
    m.add_function(wrap_pyfunction!(mass_properties, m)?)?;
    m.add_function(wrap_pyfunction!(mass_properties_obj, m)?)?;
    m.add_function(wrap_pyfunction!(convex_hull, m)?)?;
    Ok(())
}
