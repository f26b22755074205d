//! Pose studies (thesis §7.5): a part's stable poses, drops run in shards, shards merged with
//! the library's merge, the estimates read back. A shard's result is the text of the file
//! `impulse poses … --shard K/N --out FILE` writes, byte for byte, so a study split over
//! machines by Python (`impulse.distributed`) or by the CLI merges the same way.

use std::path::{Path, PathBuf};

use impulse_sim::poses::{
    self, DropOutcome, DropSettings, PartFileDesc, PosePart as Part, StudyFile, summarize,
};
use impulse_sim::scene::{MassDesc, ShapeDesc};
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::study_file::{Kept, Outcomes, merge_texts, run_kept, study_text};
use crate::world::Shape;
use crate::{Matrix, error};

/// Where a part came from, so that it pickles (a Dask task rebuilds it on its worker).
#[derive(Clone)]
enum Origin {
    /// A part file or convex OBJ (the same path must be readable where it is unpickled).
    File(PathBuf),
    /// A part description (RON text) and the directory its relative paths resolve against.
    Desc(String, PathBuf),
}

/// A part ready for a pose study (thesis §7.5): its convex hull about the centre of mass and
/// its stable poses. Pickles (by its file path or its description) for Dask.
#[pyclass(frozen, module = "impulse._impulse")]
pub struct PosePart {
    part: Part,
    origin: Origin,
}

fn part_from_ron(text: &str, base_dir: &Path) -> Result<Part, String> {
    let desc: PartFileDesc = ron::Options::default()
        .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
        .from_str(text)
        .map_err(|e| format!("part description: {e}"))?;
    Part::new(&desc, base_dir).map_err(|e| e.to_string())
}

#[pymethods]
impl PosePart {
    /// Reads a part: a `.ron` part file (`Part(name, shape, mass)`, see `fixtures/parts/`) or
    /// a convex `.obj` mesh, as `impulse poses PART` does. Raises `ImpulseError` for a missing
    /// or malformed file, or a part that is not polyhedral.
    #[staticmethod]
    fn from_file(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let part = py
            .detach(|| Part::load(&path).map_err(|e| e.to_string()))
            .map_err(error)?;
        Ok(Self {
            part,
            origin: Origin::File(path),
        })
    }

    /// A part from the scene-file text of its description, `Part(name: …, shape: …, mass: …)`;
    /// relative OBJ paths resolve against `base_dir`.
    #[staticmethod]
    #[pyo3(signature = (text, base_dir=None))]
    fn from_ron(py: Python<'_>, text: String, base_dir: Option<PathBuf>) -> PyResult<Self> {
        let base = base_dir.unwrap_or_else(|| PathBuf::from("."));
        let part = py.detach(|| part_from_ron(&text, &base)).map_err(error)?;
        Ok(Self {
            part,
            origin: Origin::Desc(text, base),
        })
    }

    /// A part of uniform density: the convex hull of `points`, shape (n, 3) (n ≥ 4, not
    /// coplanar), or any polyhedral `Shape`. Give `density` (default 1) or `mass`.
    #[staticmethod]
    #[pyo3(signature = (name, points=None, shape=None, density=None, mass=None))]
    fn new(
        py: Python<'_>,
        name: String,
        points: Option<Matrix<'_>>,
        shape: Option<&Shape>,
        density: Option<f64>,
        mass: Option<f64>,
    ) -> PyResult<Self> {
        let shape = match (points, shape) {
            (Some(p), None) => ShapeDesc::hull(crate::points("points", &p)?),
            (None, Some(s)) => s.desc.clone(),
            _ => {
                return Err(error(
                    "give the part's `points` or its `shape` (one of them)",
                ));
            }
        };
        let desc = PartFileDesc {
            name: Some(name),
            shape,
            mass: match (density, mass) {
                (Some(_), Some(_)) => return Err(error("give a density or a mass, not both")),
                (Some(d), None) => Some(MassDesc::Density(d)),
                (None, Some(m)) => Some(MassDesc::Mass(m)),
                (None, None) => None,
            },
            point_masses: Vec::new(),
        };
        let text = ron::ser::to_string(&desc).map_err(error)?;
        Self::from_ron(py, text, None)
    }

    /// The part's name.
    #[getter]
    fn name(&self) -> &str {
        &self.part.name
    }

    /// The part's diameter (its hull's bounding-box diagonal).
    #[getter]
    fn diameter(&self) -> f64 {
        self.part.diameter
    }

    /// The stable facets (hull face indices) the part can rest on.
    fn stable_facets(&self) -> Vec<u32> {
        self.part.analysis.stable()
    }

    /// The outward normal of hull face `face` in the part's own frame, shape (3,): resting on
    /// that facet, it points down.
    fn facet_normal<'py>(&self, py: Python<'py>, face: u32) -> PyResult<Bound<'py, PyArray1<f64>>> {
        if face as usize >= self.part.analysis.facets().len() {
            return Err(error(format!(
                "face {face}: the hull has faces 0 to {}",
                self.part.analysis.facets().len() - 1
            )));
        }
        Ok(PyArray1::from_slice(
            py,
            &self.part.normal_in_part_frame(face).to_array(),
        ))
    }

    /// Pickles by its file path or its description.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        let py = slf.py();
        let ty = slf.get_type();
        Ok(match &slf.get().origin {
            Origin::File(path) => (
                ty.getattr("from_file")?,
                (path.clone(),).into_pyobject(py)?.into_any(),
            ),
            Origin::Desc(text, base) => (
                ty.getattr("from_ron")?,
                (text.clone(), base.clone()).into_pyobject(py)?.into_any(),
            ),
        })
    }

    fn __repr__(&self) -> String {
        format!(
            "PosePart({:?}, stable facets {:?})",
            self.part.name,
            self.part.analysis.stable()
        )
    }
}

fn read_study(text: &str, k: usize) -> Result<StudyFile, String> {
    serde_json::from_str(text).map_err(|e| format!("studies[{k}]: not a pose study file: {e}"))
}

/// Runs the drops of one shard of a pose study (thesis §7.5) with the GIL released; returns
/// the text of the study file, byte for byte what `impulse poses PART --drops DROPS --seed
/// SEED --shard K/N --out FILE` writes (with `shard=(0, 1)`, the whole study). The settings
/// are the CLI's options, with the thesis's values as defaults. `threads` (default: every
/// core) does not change the result.
///
/// With `out`, the study is kept as `impulse poses --out OUT` keeps it: each finished drop in
/// the journal `OUT.partial`, and the file written to `out` when the shard is done. A call
/// stopped before that (by `max_wall` seconds of wall-clock time, after which no drop starts,
/// or by a kill) and made again with the same arguments runs only the drops the journal does
/// not hold — and so does `impulse poses … --out OUT`, which reads the same journal, and the
/// other way round. A call stopped by `max_wall` raises `ImpulseError` saying how many drops
/// it kept. A call whose `out` already holds this shard's finished file (and no journal)
/// returns that file without dropping again (a Dask study re-run after a kill,
/// `impulse.distributed`). Raises `ImpulseError` for a bad shard or setting, or a journal of
/// another study at `OUT.partial`.
#[pyfunction]
#[pyo3(signature = (part, drops, seed=1, shard=(0, 1), threads=None, height=0.12,
                    exit_speed=0.05, friction=0.3, restitution=0.3, epsilon=None, jitter=1.5,
                    uniform_only=false, max_time=10.0, out=None, max_wall=None))]
#[allow(clippy::too_many_arguments)] // the CLI's options as Python keywords
fn run_pose_shard(
    py: Python<'_>,
    part: &PosePart,
    drops: u64,
    seed: u64,
    shard: (u64, u64),
    threads: Option<usize>,
    height: f64,
    exit_speed: f64,
    friction: f64,
    restitution: f64,
    epsilon: Option<f64>,
    jitter: f64,
    uniform_only: bool,
    max_time: f64,
    out: Option<PathBuf>,
    max_wall: Option<f64>,
) -> PyResult<String> {
    let shard: impulse_sim::poses::Shard =
        format!("{}/{}", shard.0, shard.1).parse().map_err(error)?;
    if drops == 0 {
        return Err(error("drops = 0: a study needs at least one drop"));
    }
    let settings = DropSettings {
        height,
        exit_speed,
        friction,
        restitution,
        collision_epsilon: epsilon,
        belt_fed: !uniform_only,
        jitter_degrees: jitter,
        max_time,
    };
    if let Some(w) = max_wall
        && !(w.is_finite() && w > 0.0)
    {
        return Err(error(format!(
            "max_wall {w}: must be a positive number of seconds"
        )));
    }
    let threads =
        threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let part = &part.part;
    py.detach(|| {
        settings.validate().map_err(|e| e.to_string())?;
        let file = StudyFile {
            part: part.name.clone(),
            settings,
            seed,
            drops,
            stable: StudyFile::fingerprint(part),
            outcomes: Vec::new(),
        };
        let study = Kept {
            command: "impulse poses",
            runs: "drops",
            shard,
            total: drops,
            out: out.as_deref(),
            max_wall,
        };
        let outcomes = Outcomes {
            of: |f: &mut StudyFile| &mut f.outcomes,
            index: |d: &DropOutcome| d.index,
        };
        let file = run_kept(&study, file, &outcomes, |hooks| {
            poses::run_drops_with(part, &settings, seed, drops, shard, threads, hooks)
                .map_err(|e| e.to_string())
        })?;
        study_text(&file)
    })
    .map_err(error)
}

/// Merges the shard files of one study (their texts, as `run_pose_shard` returns or `impulse
/// poses --out` writes) with the library's merge; returns the text of the whole study's file,
/// byte for byte what `impulse poses merge … --out FILE` writes. Raises `ImpulseError` for
/// files of different studies or a drop held twice.
#[pyfunction]
fn merge_pose_studies(py: Python<'_>, studies: Vec<String>) -> PyResult<String> {
    py.detach(|| merge_texts(&studies, read_study, poses::merge))
        .map_err(error)
}

/// The estimates of a study (its file's text) for `part`: a dict with `drops`,
/// `uniform_drops`, `unsettled`, `unclassified`, `half_width` (None or the worst-case
/// interval half-width, eq. 7.3) and `rows`, one dict per pose: `pose`, `facets`, `normal`
/// (3,), `quasi_static`, `perturbed` (the cone's estimate), `uniform` (share of uniform drops),
/// `interval` (its confidence interval), `belt_fed` (None without belt drops) and
/// `uniform_count` — the table `impulse poses --from FILE` prints.
#[pyfunction]
#[pyo3(signature = (part, study, cone=20.0, confidence=0.95))]
fn pose_summary<'py>(
    py: Python<'py>,
    part: &PosePart,
    study: &str,
    cone: f64,
    confidence: f64,
) -> PyResult<Bound<'py, PyDict>> {
    if !(cone.is_finite() && (0.0..90.0).contains(&cone)) {
        return Err(error(format!("cone {cone}: must be in [0, 90) degrees")));
    }
    let file = read_study(study, 0).map_err(error)?;
    if file.part != part.part.name || file.stable != StudyFile::fingerprint(&part.part) {
        return Err(error(format!(
            "the study's drops are of part \"{}\", not of this \"{}\" (another part, or the part changed)",
            file.part, part.part.name
        )));
    }
    let s = py
        .detach(|| {
            summarize(&part.part, &file.outcomes, cone.to_radians(), confidence)
                .map_err(|e| e.to_string())
        })
        .map_err(error)?;
    let d = PyDict::new(py);
    d.set_item("drops", s.drops)?;
    d.set_item("uniform_drops", s.uniform_drops)?;
    d.set_item("unsettled", s.unsettled)?;
    d.set_item("unclassified", s.unclassified)?;
    d.set_item("half_width", s.half_width)?;
    let rows = PyList::empty(py);
    for r in &s.rows {
        let row = PyDict::new(py);
        row.set_item("pose", r.pose)?;
        row.set_item("facets", r.facets.clone())?;
        row.set_item("normal", PyArray1::from_slice(py, &r.normal))?;
        row.set_item("quasi_static", r.quasi_static)?;
        row.set_item("perturbed", r.perturbed)?;
        row.set_item("uniform", r.uniform)?;
        row.set_item("interval", r.interval)?;
        row.set_item("belt_fed", r.belt_fed)?;
        row.set_item("uniform_count", r.uniform_count)?;
        rows.append(row)?;
    }
    d.set_item("rows", rows)?;
    Ok(d)
}

/// Adds this module's names to the extension module.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PosePart>()?;
    m.add_function(wrap_pyfunction!(run_pose_shard, m)?)?;
    m.add_function(wrap_pyfunction!(merge_pose_studies, m)?)?;
    m.add_function(wrap_pyfunction!(pose_summary, m)?)?;
    Ok(())
}
