//! Worlds of rigid bodies and multibodies (thesis chapters 1–3, 5 and 7): from scene files or
//! built in code, stepped with the GIL released, every body's state read as one array per
//! quantity, the last step's contacts as arrays.

use std::cell::Cell;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::{Arc, Mutex, MutexGuard, PoisonError};

use glam::{DQuat, DVec3};
use impulse_sim::contact::ContactKind;
use impulse_sim::scene::{
    BaseDesc, BodyDesc, JointOverride, MassDesc, MotionDesc, MultibodyDesc, PartDesc, RotationDesc,
    ShapeDesc, UrdfDesc,
};
use impulse_sim::{
    BodyHandle, BodyState, ContactEvent, ContactMode, HeldContact, Load, Material,
    MultibodyOptions, Scene, SimError, StepReport, World, WorldSettings,
};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::{Matrix, Vector, error, finite_vector, rows_to_array, vec3, vector_rows};

/// A 1-D float64 array returned to Python.
type Array1<'py> = Bound<'py, PyArray1<f64>>;

/// The RON options of scene files: optional fields without `Some(…)`.
fn ron_options() -> ron::Options {
    ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
}

/// The shape of a body, as a scene file's `shape:` field describes it (in the body's own
/// frame). Build one with the static constructors; `repr()` is its scene-file text.
#[pyclass(frozen, module = "impulse._impulse")]
#[derive(Clone)]
pub struct Shape {
    pub(crate) desc: ShapeDesc,
}

#[pymethods]
impl Shape {
    /// A box centred on the frame origin; `half_extents`: shape (3,).
    #[staticmethod]
    #[pyo3(name = "box")]
    fn box_(half_extents: Vector<'_>) -> PyResult<Self> {
        Ok(Self {
            desc: ShapeDesc::cuboid(vec3("half_extents", &half_extents)?),
        })
    }

    /// An exact sphere centred on the frame origin.
    #[staticmethod]
    fn sphere(radius: f64) -> Self {
        Self {
            desc: ShapeDesc::sphere(radius),
        }
    }

    /// The convex hull of `points`, shape (n, 3), n ≥ 4 and not coplanar.
    #[staticmethod]
    fn hull(points: Matrix<'_>) -> PyResult<Self> {
        Ok(Self {
            desc: ShapeDesc::hull(crate::points("points", &points)?),
        })
    }

    /// A convex polyhedron read from an OBJ file when the body is built (a relative path
    /// resolves against the world's base directory, the scene file's directory).
    #[staticmethod]
    fn obj(path: PathBuf) -> Self {
        Self {
            desc: ShapeDesc::Obj {
                path: path.to_string_lossy().into_owned(),
            },
        }
    }

    /// A right prism over a regular polygon of `sides` sides and circumradius `radius`, axis
    /// along z, `half_height` along it.
    #[staticmethod]
    fn prism(sides: u32, radius: f64, half_height: f64) -> Self {
        Self {
            desc: ShapeDesc::prism(sides, radius, half_height),
        }
    }

    /// An ellipsoid with `semi_axes` (shape (3,)): exact and smooth, or with `level` the
    /// inscribed polyhedron of that refinement.
    #[staticmethod]
    #[pyo3(signature = (semi_axes, level=None))]
    fn ellipsoid(semi_axes: Vector<'_>, level: Option<u32>) -> PyResult<Self> {
        Ok(Self {
            desc: ShapeDesc::Ellipsoid {
                semi_axes: vec3("semi_axes", &semi_axes)?,
                level,
            },
        })
    }

    /// A non-convex body: convex `parts`, each a tuple (shape, position (3,), rotation as a
    /// quaternion (x, y, z, w)) in the body frame.
    #[staticmethod]
    fn compound(parts: Vec<(Bound<'_, Shape>, Vector<'_>, Vector<'_>)>) -> PyResult<Self> {
        let mut descs = Vec::with_capacity(parts.len());
        for (k, (shape, position, rotation)) in parts.iter().enumerate() {
            let q = finite_vector(&format!("parts[{k}] rotation"), rotation, Some(4))?;
            descs.push(PartDesc {
                position: vec3(&format!("parts[{k}] position"), position)?,
                ..PartDesc::new(shape.get().desc.clone())
                    .with_rotation(RotationDesc::Quaternion(q[0], q[1], q[2], q[3]))
            });
        }
        Ok(Self {
            desc: ShapeDesc::compound(descs),
        })
    }

    /// A shape from its scene-file text, e.g. `Box(half_extents: (1, 1, 0.1))`.
    #[staticmethod]
    fn from_ron(text: &str) -> PyResult<Self> {
        let desc = ron_options()
            .from_str(text)
            .map_err(|e| error(format!("shape: {e}")))?;
        Ok(Self { desc })
    }

    /// The scene-file text of the shape (exact: numbers are written to round-trip).
    fn to_ron(&self) -> PyResult<String> {
        ron::ser::to_string(&self.desc).map_err(error)
    }

    fn __repr__(&self) -> PyResult<String> {
        Ok(format!("Shape.from_ron({:?})", self.to_ron()?))
    }

    /// Pickles as its scene-file text (for Dask and multiprocessing).
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, (String,))> {
        let from_ron = slf.get_type().getattr("from_ron")?;
        Ok((from_ron, (slf.get().to_ron()?,)))
    }
}

/// The contact model named `name`: `"switching"` or `"impulse"`.
fn contact_mode(name: &str) -> PyResult<ContactMode> {
    match name {
        "switching" => Ok(ContactMode::Switching),
        "impulse" => Ok(ContactMode::Impulse),
        other => Err(error(format!(
            "contact_model \"{other}\": expected \"switching\" or \"impulse\""
        ))),
    }
}

/// A world of fixed and dynamic rigid bodies and multibodies that collide by impulses (thesis
/// ch. 1–3, 5): `World(...)` for an empty one built in code (`add_body`, `add_urdf`,
/// `add_multibody`), `World.from_scene(path)` from a scene file.
///
/// Bodies are numbered in the order they were added (a scene file's order; multibody links
/// after the bodies, as bodies `"<multibody>/<link>"`); every array method returns one row
/// per body in that order, `names()` gives it. Steps release the GIL.
#[pyclass(frozen, name = "World", module = "impulse._impulse")]
pub struct PyWorld {
    world: Mutex<World>,
    /// The contact model the world was built with.
    mode: ContactMode,
    /// Where relative paths of multibodies added later (URDF files, OBJ shapes) resolve: the
    /// scene file's directory, or the `base_dir` the world was made with.
    base_dir: PathBuf,
    /// The first exception a load function raised (or the first bad value it returned) during
    /// the call running now: the call raises it ([`PyWorld::long`]).
    load_error: LoadError,
}

/// Where a Python load function leaves the exception it raised, for the call that stepped the
/// world to raise it.
type LoadError = Arc<Mutex<Option<PyErr>>>;

thread_local! {
    /// The world this thread is running a call of (its address; 0 for none) while the call
    /// holds the world's lock: a load function called back from inside that call that calls
    /// the same world would wait for the lock its own caller holds.
    static BUSY: Cell<usize> = const { Cell::new(0) };
}

/// A Python callable `function(t, state) -> (force, torque[, point])` as the library's load
/// function of body `body` ([`World::set_load_fn`]): called with the GIL taken for the call
/// only. An exception it raises, or a value that is not a load, goes to `stash` (the first one
/// only) and the library gets a non-finite load, which fails the step that asked for it: the
/// world is then restored and the call raises the stashed exception.
fn load_function(
    function: Py<PyAny>,
    body: String,
    stash: LoadError,
) -> impl Fn(f64, &BodyState) -> Load + Send + Sync + 'static {
    move |t, state| {
        Python::attach(|py| match call_load(py, &function, &body, t, state) {
            Ok(load) => load,
            Err(e) => {
                let note = format!(
                    "raised by the load function of body \"{body}\" at t = {t} s; the world \
                     is left as it was before the call"
                );
                // A note (Python ≥ 3.11) says where; without it the exception is unchanged.
                let _ = e.value(py).call_method1("add_note", (note,));
                let mut slot = stash.lock().unwrap_or_else(PoisonError::into_inner);
                slot.get_or_insert(e);
                Load {
                    force: DVec3::NAN,
                    torque: DVec3::NAN,
                }
            }
        })
    }
}

/// One call of a load function: its arguments built, its value read as a load (a force at
/// `point` adds its moment about the centre of mass in `state`).
fn call_load(
    py: Python<'_>,
    function: &Py<PyAny>,
    body: &str,
    t: f64,
    state: &BodyState,
) -> PyResult<Load> {
    let s = PyDict::new(py);
    let (position, rotation) = (state.position.to_array(), state.rotation.to_array());
    let (velocity, omega, com) = (
        state.velocity.to_array(),
        state.omega.to_array(),
        state.com.to_array(),
    );
    let fields: [(&str, &[f64]); 5] = [
        ("position", &position),
        ("rotation", &rotation),
        ("velocity", &velocity),
        ("angular_velocity", &omega),
        ("com", &com),
    ];
    for (key, value) in fields {
        s.set_item(key, PyArray1::from_slice(py, value))?;
    }
    let value = function.bind(py).call1((t, s))?;
    let what = format!("the load function of body \"{body}\"");
    let bad = || {
        error(format!(
            "{what} returned {}: expected a tuple (force, torque) or (force, torque, point) \
             of three numbers each",
            value
                .repr()
                .map_or_else(|_| "a value".to_owned(), |r| r.to_string())
        ))
    };
    let items: Vec<Bound<'_, PyAny>> = value.extract().map_err(|_| bad())?;
    if !(2..=3).contains(&items.len()) {
        return Err(bad());
    }
    let part = |k: usize, name: &str| -> PyResult<DVec3> {
        let v: Vector<'_> = items[k].extract().map_err(|_| bad())?;
        Ok(DVec3::from_array(vec3(&format!("{what}: {name}"), &v)?))
    };
    let (force, torque) = (part(0, "force")?, part(1, "torque")?);
    let mut load = Load { force, torque };
    if items.len() == 3 {
        load.torque += Load::force_at(force, part(2, "point")?, state.com).torque;
    }
    Ok(load)
}

impl PyWorld {
    /// A world ready for Python.
    fn wrap(world: World, mode: ContactMode, base_dir: PathBuf) -> Self {
        Self {
            world: Mutex::new(world),
            mode,
            base_dir,
            load_error: LoadError::default(),
        }
    }

    /// An error for a call made from inside a call of this same world (a load function calling
    /// its world), which would wait forever for the lock its caller holds.
    fn refuse_reentry(&self) -> PyResult<()> {
        if BUSY.get() == std::ptr::from_ref(self) as usize {
            return Err(error(
                "this world is being stepped: a load function cannot call its own world (it is \
                 given the time and its body's state)",
            ));
        }
        Ok(())
    }

    /// The world, locked, for a short read (waits without the GIL if another thread holds it).
    fn read<T: Send>(&self, py: Python<'_>, f: impl FnOnce(&mut World) -> T + Send) -> PyResult<T> {
        self.refuse_reentry()?;
        Ok(match self.world.try_lock() {
            Ok(mut w) => f(&mut w),
            Err(_) => py.detach(|| f(&mut self.locked())),
        })
    }

    fn locked(&self) -> MutexGuard<'_, World> {
        self.world.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Runs a long call with the GIL released. A load function it calls back takes the GIL
    /// for that call only; an exception one raised fails the call (the library restores the
    /// world) and is raised here, in place of the library's error.
    fn long<T: Send>(
        &self,
        py: Python<'_>,
        f: impl FnOnce(&mut World) -> Result<T, SimError> + Send,
    ) -> PyResult<T> {
        self.refuse_reentry()?;
        let me = std::ptr::from_ref(self) as usize;
        let take = || {
            self.load_error
                .lock()
                .unwrap_or_else(PoisonError::into_inner)
                .take()
        };
        // Cleared and read under the world's lock: another thread's call cannot take this
        // call's exception.
        let (result, raised) = py.detach(|| {
            let mut w = self.locked();
            take();
            let outer = BUSY.replace(me);
            let result = f(&mut w).map_err(|e| e.to_string());
            BUSY.set(outer);
            (result, take())
        });
        result.map_err(|e| raised.unwrap_or_else(|| error(e)))
    }

    /// The handle of the body called `name`.
    fn handle(world: &World, name: &str) -> Result<BodyHandle, SimError> {
        world.handle(name).ok_or_else(|| SimError::Invalid {
            what: format!("body \"{name}\""),
            field: "name".into(),
            problem: format!(
                "no body of that name in the world (it has {} bodies)",
                world.len()
            ),
        })
    }

    /// The row (in `names()` order) of every handle of `handles`, which must be live bodies
    /// of `world` (rows are slot order, as `World::bodies` iterates).
    fn rows_of(world: &World, handles: impl Iterator<Item = BodyHandle>) -> Vec<i64> {
        let all = world.handles();
        handles
            .map(|h| {
                all.binary_search_by_key(&h.index(), |x| x.index())
                    .map_or(-1, |r| r as i64)
            })
            .collect()
    }

    /// Builds multibody `desc` (in the world's gravity, its paths against the world's base
    /// directory) and adds it as `World::from_scene` adds a scene file's multibodies; returns
    /// the rows of its links' bodies.
    fn add_multibody_desc(&self, py: Python<'_>, desc: &MultibodyDesc) -> PyResult<Vec<i64>> {
        let base_dir = &self.base_dir;
        self.long(py, |w| {
            let before = w.handles();
            let (sim, shapes) = desc.build(w.gravity(), base_dir)?;
            let options = MultibodyOptions::default().with_self_collision(desc.self_collision);
            w.add_multibody_with(&desc.name, sim, shapes, options)?;
            let new: Vec<BodyHandle> = w
                .handles()
                .into_iter()
                .filter(|h| !before.contains(h))
                .collect();
            Ok(Self::rows_of(w, new.into_iter()))
        })
    }

    /// One row per body of `f(state)`.
    fn rows<'py, const K: usize>(
        &self,
        py: Python<'py>,
        f: impl Fn(&impulse_sim::BodyState) -> [f64; K] + Send + Sync,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let flat: Vec<[f64; K]> =
            self.read(py, |w| w.bodies().map(|(_, b)| f(&b.state())).collect())?;
        Ok(rows_to_array(py, flat.into_iter()))
    }
}

/// The name the Python side gives a contact's kind.
fn kind_name(kind: ContactKind) -> &'static str {
    match kind {
        ContactKind::Collision => "collision",
        ContactKind::Microcollision => "microcollision",
        ContactKind::Reversing => "reversing",
        ContactKind::Fallback => "fallback",
    }
}

/// The contact events `events` as a dict of arrays, one entry per event; `a`, `b`: the rows
/// of the two bodies.
fn impacts_dict<'py>(
    py: Python<'py>,
    events: &[ContactEvent],
    a: Vec<i64>,
    b: Vec<i64>,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let scalars =
        |f: fn(&ContactEvent) -> f64| PyArray1::from_vec(py, events.iter().map(f).collect());
    let vectors = |f: fn(&ContactEvent) -> DVec3| vector_rows(py, events, f);
    d.set_item("time", scalars(|e| e.time))?;
    d.set_item("a", PyArray1::from_vec(py, a))?;
    d.set_item("b", PyArray1::from_vec(py, b))?;
    d.set_item(
        "kind",
        events.iter().map(|e| kind_name(e.kind)).collect::<Vec<_>>(),
    )?;
    d.set_item("impulse", vectors(|e| e.impulse))?;
    d.set_item("point", vectors(|e| e.point))?;
    d.set_item("normal", vectors(|e| e.normal))?;
    d.set_item("normal_speed_before", scalars(|e| e.normal_speed_before))?;
    d.set_item("normal_speed_after", scalars(|e| e.normal_speed_after))?;
    d.set_item("energy_before", scalars(|e| e.energy_before))?;
    d.set_item("energy_after", scalars(|e| e.energy_after))?;
    Ok(d)
}

/// A step report as a dict.
fn report_dict<'py>(py: Python<'py>, r: &StepReport) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("start", r.start)?;
    d.set_item("end", r.end)?;
    d.set_item("contacts", r.contacts)?;
    let c = &r.counters;
    d.set_item("steps", c.steps)?;
    d.set_item("collisions", c.collisions)?;
    d.set_item("microcollisions", c.microcollisions)?;
    d.set_item("island_steps", c.island_steps)?;
    d.set_item("unresolved", c.unresolved)?;
    Ok(d)
}

#[pymethods]
impl PyWorld {
    /// An empty world. `collision_epsilon`: ε_c (length); `gravity`: shape (3,); `friction`
    /// and `restitution`: the default contact of material pairs (Coulomb μ, Stronge's
    /// energetic e); `contact_model`: `"switching"` (impacts as impulses, sustained contact as
    /// constraints; the default) or `"impulse"` (every contact an impulse, the thesis's
    /// model); `base_dir`: where relative OBJ paths of shapes resolve.
    #[new]
    #[pyo3(signature = (collision_epsilon=1e-4, gravity=None, friction=0.3, restitution=0.5,
                        contact_model="switching", base_dir=None))]
    fn new(
        collision_epsilon: f64,
        gravity: Option<Vector<'_>>,
        friction: f64,
        restitution: f64,
        contact_model: &str,
        base_dir: Option<PathBuf>,
    ) -> PyResult<Self> {
        let mut settings = WorldSettings::new(collision_epsilon);
        if let Some(g) = gravity {
            settings.gravity = DVec3::from_array(vec3("gravity", &g)?);
        }
        settings.default_contact = Material {
            friction,
            restitution,
        };
        let mode = contact_mode(contact_model)?;
        settings.contact_mode = mode;
        if let Some(dir) = base_dir {
            settings.base_dir = dir;
        }
        let base_dir = settings.base_dir.clone();
        Ok(Self::wrap(
            World::new(settings).map_err(error)?,
            mode,
            base_dir,
        ))
    }

    /// A world built from a scene file (RON; see `fixtures/scenes/`), as `impulse run` builds
    /// it; `contact_model` (`"switching"` or `"impulse"`) overrides the file's. Raises
    /// `ImpulseError` for a missing file, a parse error (with line and column) or an invalid
    /// scene (naming the body and field).
    #[staticmethod]
    #[pyo3(signature = (path, contact_model=None))]
    fn from_scene(py: Python<'_>, path: PathBuf, contact_model: Option<&str>) -> PyResult<Self> {
        let mode = contact_model.map(contact_mode).transpose()?;
        let (world, mode, base_dir) = py
            .detach(|| {
                let mut scene = Scene::read(&path)?;
                if let Some(m) = mode {
                    scene.desc.contact_model = m;
                }
                let world = World::from_scene(&scene)?;
                Ok::<_, SimError>((world, scene.desc.contact_model, scene.base_dir))
            })
            .map_err(error)?;
        Ok(Self::wrap(world, mode, base_dir))
    }

    /// Adds a body; returns its row in the state arrays.
    ///
    /// `shape`: a `Shape`; `position`: (3,), the origin of the body's own frame; `rotation`:
    /// quaternion (x, y, z, w); `velocity`, `angular_velocity`: (3,); `density` or `mass`
    /// (default density 1); `material`: the name material pairs refer to; `fixed`: a body
    /// that never moves. Raises `ImpulseError` for a duplicate name, a bad value (naming the
    /// field) or a deep overlap with a body already there.
    #[pyo3(signature = (name, shape, position=None, rotation=None, velocity=None,
                        angular_velocity=None, density=None, mass=None, material=None,
                        fixed=false))]
    #[allow(clippy::too_many_arguments)] // Python keyword arguments, all optional
    fn add_body(
        &self,
        py: Python<'_>,
        name: String,
        shape: &Shape,
        position: Option<Vector<'_>>,
        rotation: Option<Vector<'_>>,
        velocity: Option<Vector<'_>>,
        angular_velocity: Option<Vector<'_>>,
        density: Option<f64>,
        mass: Option<f64>,
        material: Option<String>,
        fixed: bool,
    ) -> PyResult<usize> {
        let mut desc = BodyDesc::new(name, shape.desc.clone());
        if let Some(p) = position {
            desc.position = vec3("position", &p)?;
        }
        if let Some(q) = rotation {
            let q = finite_vector("rotation", &q, Some(4))?;
            desc.rotation = RotationDesc::Quaternion(q[0], q[1], q[2], q[3]);
        }
        if let Some(v) = velocity {
            desc.velocity = vec3("velocity", &v)?;
        }
        if let Some(w) = angular_velocity {
            desc.angular_velocity = vec3("angular_velocity", &w)?;
        }
        desc.mass = match (density, mass) {
            (Some(_), Some(_)) => return Err(error("give a density or a mass, not both")),
            (Some(d), None) => Some(MassDesc::Density(d)),
            (None, Some(m)) => Some(MassDesc::Mass(m)),
            (None, None) => None,
        };
        if let Some(m) = material {
            desc.material = m;
        }
        if fixed {
            desc.motion = MotionDesc::Fixed;
        }
        self.long(py, |w| {
            let h = w.add_body(&desc)?;
            Ok(w.handles().iter().position(|&x| x == h).unwrap_or(0))
        })
    }

    /// Adds a multibody (thesis ch. 5) described as a scene file's `Multibody(...)` entry
    /// (RON; see `fixtures/scenes/urdf-arm.ron` and `triple-pendulum.ron`): inline links and
    /// joints, or a URDF file with overrides, springs, limits, controllers, self-collision.
    /// Relative paths resolve against the world's base directory (`base_dir`, or the scene
    /// file's directory). The world then steps it with its bodies exactly as if it were in a
    /// scene file. Its links become bodies named `"<name>/<link>"`; returns their rows.
    /// Raises `ImpulseError` for a parse error (line and column), an invalid multibody
    /// (naming the link, joint or field), an unreadable URDF, or an overlap.
    fn add_multibody(&self, py: Python<'_>, desc: &str) -> PyResult<Vec<i64>> {
        let desc: MultibodyDesc = ron_options()
            .from_str(desc)
            .map_err(|e| error(format!("multibody: {e}")))?;
        self.add_multibody_desc(py, &desc)
    }

    /// Adds the robot of URDF file `path` (links, inertias, `<collision>` shapes, joints and
    /// their `<dynamics>`) as multibody `name` — what a scene file's
    /// `Multibody(name, urdf: Urdf(path, joints: [JointOverride(name, q, qd)]), base,
    /// position, rotation, self_collision)` gives. `position` (3,) and `rotation` (quaternion
    /// x, y, z, w) place its root link; `floating`: a free root (6 degrees of freedom) instead
    /// of one welded to the world; `q`, `qd`: initial joint positions and rates by joint name
    /// (default 0); `self_collision`: its non-adjacent links collide. Returns the rows of its
    /// links' bodies. Raises `ImpulseError` as `add_multibody`.
    #[pyo3(signature = (name, path, position=None, rotation=None, floating=false, q=None,
                        qd=None, self_collision=false))]
    #[allow(clippy::too_many_arguments)] // Python keyword arguments, all optional
    fn add_urdf(
        &self,
        py: Python<'_>,
        name: String,
        path: PathBuf,
        position: Option<Vector<'_>>,
        rotation: Option<Vector<'_>>,
        floating: bool,
        q: Option<BTreeMap<String, f64>>,
        qd: Option<BTreeMap<String, f64>>,
        self_collision: bool,
    ) -> PyResult<Vec<i64>> {
        // The library's defaults for every field left out (the integrator's tolerance), as a
        // scene file's `Multibody(name: …)` gets them.
        let mut desc: MultibodyDesc = ron_options()
            .from_str("Multibody(name: \"\")")
            .map_err(|e| error(format!("multibody: {e}")))?;
        desc.name = name;
        if let Some(p) = position {
            desc.position = vec3("position", &p)?;
        }
        if let Some(r) = rotation {
            let r = finite_vector("rotation", &r, Some(4))?;
            desc.rotation = RotationDesc::Quaternion(r[0], r[1], r[2], r[3]);
        }
        if floating {
            desc.base = BaseDesc::Floating;
        }
        desc.self_collision = self_collision;
        let (q, qd) = (q.unwrap_or_default(), qd.unwrap_or_default());
        let mut joints: BTreeMap<&String, JointOverride> = BTreeMap::new();
        for (j, (map, what)) in [(&q, "q"), (&qd, "qd")].into_iter().enumerate() {
            for (joint, &value) in map {
                if !value.is_finite() {
                    return Err(error(format!(
                        "{what}[\"{joint}\"] is {value}: must be finite"
                    )));
                }
                let o = joints.entry(joint).or_insert_with(|| JointOverride {
                    name: joint.clone(),
                    spring: None,
                    damping: None,
                    friction: None,
                    limit: None,
                    q: 0.0,
                    qd: 0.0,
                });
                if j == 0 {
                    o.q = value;
                } else {
                    o.qd = value;
                }
            }
        }
        desc.urdf = Some(UrdfDesc {
            path: path.to_string_lossy().into_owned(),
            links: Vec::new(),
            joints: joints.into_values().collect(),
        });
        self.add_multibody_desc(py, &desc)
    }

    /// The joint state of multibody `name`: positions q, shape (nq,), and velocities v, shape
    /// (nv,), in the order of `Model.joint_names()` (a floating base's 7 and 6 values first).
    fn joint_state<'py>(
        &self,
        py: Python<'py>,
        name: &str,
    ) -> PyResult<(Array1<'py>, Array1<'py>)> {
        let (q, v) = self
            .read(py, |w| {
                let h = w.multibody_handle(name).ok_or_else(|| {
                    format!(
                        "multibody \"{name}\": no multibody of that name in the world (it has \
                         {})",
                        w.multibody_handles().len()
                    )
                })?;
                let sim = w.multibody(h).expect("a handle of the world");
                Ok::<_, String>((sim.q().to_vec(), sim.v().to_vec()))
            })?
            .map_err(error)?;
        Ok((PyArray1::from_vec(py, q), PyArray1::from_vec(py, v)))
    }

    /// The multibodies' names, in the order they were added (a scene file's order), the names
    /// `joint_state` takes; their links are the bodies `"<multibody>/<link>"`.
    fn multibody_names(&self, py: Python<'_>) -> PyResult<Vec<String>> {
        self.read(py, |w| {
            w.multibody_handles()
                .into_iter()
                .filter_map(|h| w.multibody_name(h).map(str::to_owned))
                .collect()
        })
    }

    /// Sets the contact (Coulomb `friction`, Stronge `restitution`) of materials `a` and `b`.
    fn set_material_pair(
        &self,
        py: Python<'_>,
        a: &str,
        b: &str,
        friction: f64,
        restitution: f64,
    ) -> PyResult<()> {
        self.long(py, |w| {
            w.set_material_pair(
                a,
                b,
                Material {
                    friction,
                    restitution,
                },
            )
        })
    }

    /// Advances the world by `dt` (s) with the GIL released; returns a report (dict: start,
    /// end, contacts, steps, collisions, microcollisions, island_steps, unresolved).
    fn step<'py>(&self, py: Python<'py>, dt: f64) -> PyResult<Bound<'py, PyDict>> {
        let r = self.long(py, |w| w.step(dt))?;
        report_dict(py, &r)
    }

    /// Advances the world to time `t` (s) with the GIL released; returns a report as `step`.
    fn step_until<'py>(&self, py: Python<'py>, t: f64) -> PyResult<Bound<'py, PyDict>> {
        let r = self.long(py, |w| w.step_until(t))?;
        report_dict(py, &r)
    }

    /// The simulated time (s).
    #[getter]
    fn time(&self, py: Python<'_>) -> PyResult<f64> {
        self.read(py, |w| w.time())
    }

    /// The contact model: `"switching"` or `"impulse"`.
    #[getter]
    fn contact_model(&self) -> &'static str {
        match self.mode {
            ContactMode::Switching => "switching",
            ContactMode::Impulse => "impulse",
        }
    }

    /// Number of bodies.
    fn __len__(&self, py: Python<'_>) -> PyResult<usize> {
        self.read(py, |w| w.len())
    }

    /// The bodies' names, in row order.
    fn names(&self, py: Python<'_>) -> PyResult<Vec<String>> {
        self.read(py, |w| w.bodies().map(|(_, b)| b.name.clone()).collect())
    }

    /// Positions of the bodies' own frames (the position given, moved by the motion), shape
    /// (n, 3).
    fn positions<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        self.rows(py, |s| s.position.to_array())
    }

    /// Orientations of the bodies' own frames as quaternions (x, y, z, w), shape (n, 4).
    fn orientations<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        self.rows(py, |s| s.rotation.to_array())
    }

    /// Velocities of the centres of mass, shape (n, 3).
    fn velocities<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        self.rows(py, |s| s.velocity.to_array())
    }

    /// Angular velocities (world), shape (n, 3).
    fn angular_velocities<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        self.rows(py, |s| s.omega.to_array())
    }

    /// Centres of mass (world), shape (n, 3).
    fn centres_of_mass<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        self.rows(py, |s| s.com.to_array())
    }

    /// Every body's state in one call, shape (n, 16): position (3), quaternion x, y, z, w
    /// (4), velocity (3), angular velocity (3), centre of mass (3) — the columns of `impulse
    /// run --out` after `time, body`.
    fn states<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        self.rows(py, |s| {
            let mut r = [0.0; 16];
            r[0..3].copy_from_slice(&s.position.to_array());
            r[3..7].copy_from_slice(&s.rotation.to_array());
            r[7..10].copy_from_slice(&s.velocity.to_array());
            r[10..13].copy_from_slice(&s.omega.to_array());
            r[13..16].copy_from_slice(&s.com.to_array());
            r
        })
    }

    /// Total kinetic energy of the dynamic bodies and multibodies.
    fn kinetic_energy(&self, py: Python<'_>) -> PyResult<f64> {
        self.read(py, |w| w.kinetic_energy())
    }

    /// The contacts resolved during the last `step` or `step_until` call, in the order they
    /// happened (thesis ch. 3: each an impulse at one point), as a dict of arrays with one
    /// entry per contact (k of them; `k == step(...)["contacts"]`):
    /// - `time` (k,): simulated time of the impulse (s);
    /// - `a`, `b` (k,) int: the rows (in `names()` order) of the two bodies;
    /// - `kind`: list of k strings, `"collision"`, `"microcollision"` (an approach slower
    ///   than the microcollision speed, resolved with boosted restitution, thesis §3.5),
    ///   `"reversing"` (a microcollision resolved by the reversing impulse) or `"fallback"`
    ///   (a contact the response could not resolve, given a frictionless Newton impulse);
    /// - `impulse` (k, 3): the impulse on body `a` (world; `b` receives its negative);
    /// - `point` (k, 3): the contact point; `normal` (k, 3): the unit normal from `b` toward
    ///   `a`;
    /// - `normal_speed_before`, `normal_speed_after` (k,): the normal relative velocity
    ///   (v_a(x) − v_b(x))·n before and after the impulse (thesis eq. 3.3: negative while the
    ///   bodies approach; after a frictionless collision of restitution e, −e times before);
    /// - `energy_before`, `energy_after` (k,): the two bodies' kinetic energy (J).
    ///
    /// Under the `"switching"` contact model, contacts held as constraints (see
    /// `held_pairs`) are solved in island steps and are not listed here.
    fn impacts<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let (events, a, b) = self.read(py, |w| {
            let events = w.contacts().to_vec();
            let a = Self::rows_of(w, events.iter().map(|e| e.a));
            let b = Self::rows_of(w, events.iter().map(|e| e.b));
            (events, a, b)
        })?;
        impacts_dict(py, &events, a, b)
    }

    /// The pairs of bodies in contact now that the `"switching"` model holds as constraints
    /// (resting and sliding contact, solved in island steps), shape (p, 2) int: the rows of
    /// the two bodies (in `names()` order), in ascending order. Empty under the `"impulse"`
    /// model, where every contact is a collision or microcollision (`impacts`).
    fn held_pairs<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<i64>>> {
        let rows = self.read(py, |w| {
            let pairs = w.held_pairs();
            let a = Self::rows_of(w, pairs.iter().map(|p| p.0));
            let b = Self::rows_of(w, pairs.iter().map(|p| p.1));
            a.into_iter()
                .zip(b)
                .flat_map(|(a, b)| [a, b])
                .collect::<Vec<_>>()
        })?;
        Ok(Array2::from_shape_vec((rows.len() / 2, 2), rows)
            .expect("two rows per pair")
            .into_pyarray(py))
    }

    /// The points of the pairs `held_pairs` lists, with the impulse the last island step gave
    /// each (the switching model's sustained contact: thesis §5.3's contact forces as impulses
    /// over a step), as a dict of arrays with one entry per point (k of them):
    /// - `a`, `b` (k,) int: the rows of the pair's two bodies (a `held_pairs` row);
    /// - `point` (k, 3): where the impulse acted (world, at the start of that step): on the
    ///   moving body's surface against a fixed one, else midway between the two surfaces;
    /// - `normal` (k, 3): unit normal from `a` toward `b`;
    /// - `impulse` (k, 3): the impulse on `b` over that step (world; `a` receives its
    ///   negative);
    /// - `span` (k,): that step's length (s; 0 for a pair held but not stepped yet), so
    ///   `impulse / span` is the point's mean force over it.
    ///
    /// Pairs in `held_pairs` order, each pair's points in its manifolds' order. A body
    /// resting on a fixed floor has `sum(impulse[:, 2]) ≈ m·g·span`. Empty under the
    /// `"impulse"` model.
    fn held_contacts<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let (contacts, a, b) = self.read(py, |w| {
            let contacts = w.held_contacts();
            let a = Self::rows_of(w, contacts.iter().map(|c| c.bodies.0));
            let b = Self::rows_of(w, contacts.iter().map(|c| c.bodies.1));
            (contacts, a, b)
        })?;
        let d = PyDict::new(py);
        let vectors = |f: fn(&HeldContact) -> DVec3| vector_rows(py, &contacts, f);
        d.set_item("a", PyArray1::from_vec(py, a))?;
        d.set_item("b", PyArray1::from_vec(py, b))?;
        d.set_item("point", vectors(|c| c.point))?;
        d.set_item("normal", vectors(|c| c.normal))?;
        d.set_item("impulse", vectors(|c| c.impulse))?;
        d.set_item(
            "span",
            PyArray1::from_vec(py, contacts.iter().map(|c| c.span).collect()),
        )?;
        Ok(d)
    }

    /// Sets the pose of body `name`: `position` (3,), `rotation` quaternion (x, y, z, w).
    fn set_pose(
        &self,
        py: Python<'_>,
        name: &str,
        position: Vector<'_>,
        rotation: Vector<'_>,
    ) -> PyResult<()> {
        let p = DVec3::from_array(vec3("position", &position)?);
        let q = finite_vector("rotation", &rotation, Some(4))?;
        let q = DQuat::from_xyzw(q[0], q[1], q[2], q[3]);
        self.long(py, |w| w.set_pose(Self::handle(w, name)?, p, q))
    }

    /// Sets the velocity of body `name`'s centre of mass and its angular velocity (3,) each.
    fn set_velocity(
        &self,
        py: Python<'_>,
        name: &str,
        velocity: Vector<'_>,
        angular_velocity: Vector<'_>,
    ) -> PyResult<()> {
        let v = DVec3::from_array(vec3("velocity", &velocity)?);
        let w_ = DVec3::from_array(vec3("angular_velocity", &angular_velocity)?);
        self.long(py, |w| w.set_velocity(Self::handle(w, name)?, v, w_))
    }

    /// Applies an impulse (3,) at a world point (3,) to body `name`.
    fn apply_impulse(
        &self,
        py: Python<'_>,
        name: &str,
        impulse: Vector<'_>,
        point: Vector<'_>,
    ) -> PyResult<()> {
        let j = DVec3::from_array(vec3("impulse", &impulse)?);
        let p = DVec3::from_array(vec3("point", &point)?);
        self.long(py, |w| w.apply_impulse(Self::handle(w, name)?, j, p))
    }

    /// A constant force (3,) through body `name`'s centre of mass, kept until changed
    /// (`set_load(name, force=force)`).
    fn set_force(&self, py: Python<'_>, name: &str, force: Vector<'_>) -> PyResult<()> {
        let f = DVec3::from_array(vec3("force", &force)?);
        self.long(py, |w| w.set_load(Self::handle(w, name)?, Load::force(f)))
    }

    /// Sets a constant load on dynamic body `name`, kept until changed or cleared, replacing
    /// any load: a `force` (3,, world, N) and a `torque` (3,, world, N·m, about the centre of
    /// mass). With `point` (3,, world), the force acts at that point, and its moment about the
    /// centre of mass *now*, (point − com) × force, is added to the torque (it is then held
    /// constant: the force does not follow the point as the body turns). Between collisions
    /// the centre of mass follows the parabola of g + force/m exactly and the angular
    /// momentum grows as L₀ + torque·t. Raises `ImpulseError` for an unknown body, a body that
    /// is not dynamic, or a value that is not finite.
    #[pyo3(signature = (name, force=None, torque=None, point=None))]
    fn set_load(
        &self,
        py: Python<'_>,
        name: &str,
        force: Option<Vector<'_>>,
        torque: Option<Vector<'_>>,
        point: Option<Vector<'_>>,
    ) -> PyResult<()> {
        let read = |what: &str, v: Option<Vector<'_>>| -> PyResult<DVec3> {
            v.map_or(Ok(DVec3::ZERO), |v| Ok(DVec3::from_array(vec3(what, &v)?)))
        };
        let f = read("force", force)?;
        let tau = read("torque", torque)?;
        let point = point
            .map(|p| vec3("point", &p).map(DVec3::from_array))
            .transpose()?;
        self.long(py, |w| {
            let h = Self::handle(w, name)?;
            let mut load = Load {
                force: f,
                torque: tau,
            };
            if let Some(p) = point {
                load.torque += Load::force_at(f, p, w.state(h)?.com).torque;
            }
            w.set_load(h, load)
        })
    }

    /// Sets a load function on dynamic body `name`, replacing any load: the simulator calls
    /// `function(t, state)` now and then every `1/rate` seconds of simulated time (`rate` in
    /// Hz, finite and > 0), and holds the load it returns constant until the next call, as
    /// `set_load` holds one (exactly integrated in between; a zero-order hold, so a spring or a
    /// damper is followed to O(1/rate)). `state` is a dict of float64 arrays: `position` (3,),
    /// `rotation` (4,, quaternion x, y, z, w), `velocity` (3,, of the centre of mass),
    /// `angular_velocity` (3,), `com` (3,); `function` returns `(force, torque)` or `(force,
    /// torque, point)`, each 3 numbers, world (a force at `point` adds its moment about the
    /// centre of mass at that instant). Steps keep the GIL released and take it only to call
    /// `function`. An exception `function` raises (or a value that is not a finite load, as
    /// `ImpulseError`) fails the `step` that called it: the step raises that exception,
    /// with a note naming the body and time, and the world is left as it was before the step.
    /// `function` may not call this world (it raises `ImpulseError`). `clear_load` or
    /// `set_load` removes it.
    fn set_load_function(
        &self,
        py: Python<'_>,
        name: &str,
        function: Bound<'_, PyAny>,
        rate: f64,
    ) -> PyResult<()> {
        if !function.is_callable() {
            return Err(error(format!(
                "function: {} is not callable",
                function.repr()?
            )));
        }
        let f = load_function(function.unbind(), name.to_owned(), self.load_error.clone());
        self.long(py, |w| w.set_load_fn(Self::handle(w, name)?, rate, f))
    }

    /// Removes any load from body `name` (`set_force`, `set_load`, `set_load_function`).
    fn clear_load(&self, py: Python<'_>, name: &str) -> PyResult<()> {
        self.long(py, |w| w.clear_load(Self::handle(w, name)?))
    }

    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        let (n, t) = self.read(py, |w| (w.len(), w.time()))?;
        Ok(format!("World({n} bodies, t = {t})"))
    }
}

/// Adds this module's names to the extension module.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Shape>()?;
    m.add_class::<PyWorld>()?;
    Ok(())
}
