//! Scene files: a world described in RON ([`SceneDesc`]), parsed and validated.
//!
//! Every length, mass and time is in the scene's own consistent units (the bundled scenes use
//! SI, or cm/g/s where the thesis does). A minimal scene:
//!
//! ```ron
//! Scene(
//!     gravity: (0.0, 0.0, -9.81),
//!     duration: 1.0,
//!     collision_epsilon: 1e-4,
//!     bodies: [
//!         Body(name: "floor", shape: Box(half_extents: (1.0, 1.0, 0.1)),
//!              position: (0.0, 0.0, -0.1), motion: Fixed),
//!         Body(name: "ball", shape: Sphere(radius: 0.05), position: (0.0, 0.0, 0.5),
//!              mass: Density(7800.0)),
//!     ],
//! )
//! ```
//!
//! [`SceneDesc::validate`] checks every number before a world is built; its errors name the
//! body (or material, or scene field) and the field that is wrong.
//!
//! The same description is built in code with the builder methods of [`SceneDesc`],
//! [`BodyDesc`], [`ShapeDesc`] and [`ContactDesc`] (their defaults are the file's defaults), and
//! [`SceneDesc::to_ron`] writes it back: file, builder and RON are one-to-one.
//!
//! Sizes a file can ask for are bounded ([`MAX_BODIES`], [`MAX_PRISM_SIDES`],
//! [`MAX_HULL_POINTS`], [`MAX_PARTS`], geodesic levels, [`MAX_FRAMES`]) so that a typo cannot
//! make a run allocate gigabytes; ε_c must be small against the smallest dynamic body
//! ([`MAX_EPSILON_REL`]), and [`SceneDesc::warnings`] says when it is merely large.

use std::path::{Path, PathBuf};

use glam::DVec3;
use rustc_hash::FxHashSet;
use serde::{Deserialize, Serialize};

use crate::error::SimError;

pub mod controllers;
mod multibody;

pub use controllers::{GoalDesc, WorldControllerDesc};
pub use multibody::{
    BaseDesc, ControllerDesc, InertiaDesc, JointDesc, JointKindDesc, JointOverride, LimitDesc,
    LinkDesc, LinkOverride, MultibodyDesc, URDF_CYLINDER_SIDES, UrdfDesc,
};

/// A whole scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Scene", deny_unknown_fields)]
pub struct SceneDesc {
    /// A short name, used in reports.
    #[serde(default)]
    pub name: String,
    /// Free text: what the scene shows and where it comes from.
    #[serde(default)]
    pub description: String,
    /// Gravitational acceleration (world).
    #[serde(default = "default_gravity")]
    pub gravity: [f64; 3],
    /// Simulated time to run (s), unless the caller says otherwise (`impulse run --until`);
    /// optional.
    #[serde(default)]
    pub duration: Option<f64>,
    /// Collision epsilon ε_c (length): bodies closer than this are in contact (thesis §2.2).
    /// Two to three orders of magnitude below the body sizes. Default `1e-4` (suits bodies of
    /// a few centimetres and more in metres).
    #[serde(default = "default_epsilon")]
    pub collision_epsilon: f64,
    /// Frames recorded per simulated second.
    #[serde(default = "default_output_rate")]
    pub output_rate: f64,
    /// Contact properties used for a pair of materials not listed in `contacts`.
    #[serde(default)]
    pub default_contact: ContactDesc,
    /// Contact properties per pair of materials.
    #[serde(default)]
    pub contacts: Vec<MaterialPairDesc>,
    /// Solver settings.
    #[serde(default)]
    pub accuracy: AccuracyDesc,
    /// How contacts are modelled: `Impulse` (every contact an impulse, thesis chapters 2–3)
    /// or `Switching` (impacts as impulses, sustained contact as constraints, thesis §8.1;
    /// [`crate::sustained`]). Default `Switching`.
    #[serde(default)]
    pub contact_model: crate::sustained::ContactMode,
    /// The bodies.
    pub bodies: Vec<BodyDesc>,
    /// Multibodies: jointed mechanisms whose links collide with everything else (thesis
    /// ch. 5; [`MultibodyDesc`]).
    #[serde(default)]
    pub multibodies: Vec<MultibodyDesc>,
    /// High-level controllers: steering bodies by external forces, launching them by
    /// velocity overwrite (thesis §7.3; [`WorldControllerDesc`]).
    #[serde(default)]
    pub controllers: Vec<WorldControllerDesc>,
}

/// Most frames a run may record (`duration × output_rate`): beyond this the recording alone
/// would need gigabytes. Default `10_000_000`.
pub const MAX_FRAMES: f64 = 1e7;

/// Most bodies a scene may hold. Default `1_000_000`.
pub const MAX_BODIES: usize = 1_000_000;

/// Most sides of a [`ShapeDesc::Prism`] (a 1024-gon is a circle to 5e-6 of its radius).
/// Default `1024`.
pub const MAX_PRISM_SIDES: u32 = 1024;

/// Most points of a [`ShapeDesc::Hull`]. Default `100_000`.
pub const MAX_HULL_POINTS: usize = 100_000;

/// Most parts of a [`ShapeDesc::Compound`]. Default `10_000`.
pub const MAX_PARTS: usize = 10_000;

/// Largest geodesic level of a [`ShapeDesc::GeodesicSphere`] (20·4⁶ = 81 920 faces).
pub const MAX_GEODESIC_LEVEL: u32 = 7;

/// Largest level of a polyhedral [`ShapeDesc::Ellipsoid`] (20·4⁵ = 20 480 faces).
pub const MAX_ELLIPSOID_LEVEL: u32 = 6;

/// Largest collision epsilon relative to the smallest half-size of a dynamic body (its
/// smallest half extent, radius or half height): a body thinner than a few ε_c would be "in
/// contact" with everything near it, and the microcollision speed √(2gε_c) would no longer be
/// small. Above it the scene is refused. Default `0.1`.
pub const MAX_EPSILON_REL: f64 = 0.1;

/// Above this ratio of ε_c to the smallest dynamic half-size, [`SceneDesc::warnings`] warns
/// (the thesis uses 1e-3 to 1e-2 of the body sizes). Default `0.02`.
pub const WARN_EPSILON_REL: f64 = 0.02;

/// Largest speed of a body's points in a scene file (length per second): its centre's speed
/// and its angular speed times its extent. A body spinning at 1e30 rad/s makes every
/// time-of-impact bound 1e-31 s long and the event loop crawl for ever; no rigid body moves
/// this fast in any unit system (1e8 m/s is a third of the speed of light). Default `1e8`.
pub const MAX_SPEED: f64 = 1e8;

/// Default collision epsilon of a scene that gives none (length). Default `1e-4`.
pub const DEFAULT_COLLISION_EPSILON: f64 = 1e-4;

fn default_epsilon() -> f64 {
    DEFAULT_COLLISION_EPSILON
}

/// Smallest collision epsilon relative to the largest body extent in the scene. Distances are
/// computed to about 1e-15 of the body size; an ε_c within a few orders of that makes every
/// contact a rounding question and the event loop crawl. Default `1e-9`.
pub const MIN_EPSILON_REL: f64 = 1e-9;

fn default_gravity() -> [f64; 3] {
    [0.0, 0.0, -9.81]
}

pub(crate) fn default_output_rate() -> f64 {
    100.0
}

/// Friction and restitution of a contact.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Contact", deny_unknown_fields)]
pub struct ContactDesc {
    /// Coulomb friction coefficient μ ≥ 0.
    pub friction: f64,
    /// Restitution e ∈ [0, 1] (Stronge's energetic coefficient, thesis §3.3).
    pub restitution: f64,
}

impl Default for ContactDesc {
    fn default() -> Self {
        Self {
            friction: 0.3,
            restitution: 0.5,
        }
    }
}

/// Contact properties of one pair of materials (either order).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename = "MaterialPair", deny_unknown_fields)]
pub struct MaterialPairDesc {
    /// First material name.
    pub a: String,
    /// Second material name.
    pub b: String,
    /// Friction coefficient μ ≥ 0.
    pub friction: f64,
    /// Restitution e ∈ [0, 1].
    pub restitution: f64,
}

/// Solver settings with their defaults.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Accuracy", deny_unknown_fields, default)]
pub struct AccuracyDesc {
    /// Local error per step of the rotation integrator (see
    /// [`crate::body::Integrator::rotation_tolerance`]). Default `1e-12`.
    pub rotation_tolerance: f64,
    /// Relative tolerance of the collision integrator of `impulse-response`. Default `1e-10`.
    pub collision_tolerance: f64,
    /// e_max, the boosted restitution of a microcollision at full depth into the ε_c envelope
    /// (thesis §3.5: 5.0); at least 1. Default `5.0`.
    pub max_restitution: f64,
    /// Whether a microcollision tries the reversing impulse first (thesis §3.5: yes). Default
    /// `true`.
    pub reversing: bool,
    /// The position error an island step of the switching contact model may leave, in units
    /// of ε_c ([`crate::sustained::SustainedSettings::step_tolerance`]). Default
    /// [`crate::sustained::DEFAULT_STEP_TOLERANCE`].
    pub step_tolerance: f64,
}

impl Default for AccuracyDesc {
    fn default() -> Self {
        Self {
            rotation_tolerance: 1e-12,
            collision_tolerance: 1e-10,
            max_restitution: 5.0,
            reversing: true,
            step_tolerance: crate::sustained::DEFAULT_STEP_TOLERANCE,
        }
    }
}

/// One body.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Body", deny_unknown_fields)]
pub struct BodyDesc {
    /// Unique name.
    pub name: String,
    /// Geometry, in the body's own frame.
    pub shape: ShapeDesc,
    /// Position of the shape frame's origin (world).
    #[serde(default)]
    pub position: [f64; 3],
    /// Orientation of the shape frame (world).
    #[serde(default)]
    pub rotation: RotationDesc,
    /// Velocity of the centre of mass (world).
    #[serde(default)]
    pub velocity: [f64; 3],
    /// Angular velocity (world, rad/s).
    #[serde(default)]
    pub angular_velocity: [f64; 3],
    /// How the body moves.
    #[serde(default)]
    pub motion: MotionDesc,
    /// Mass from a density or a total mass (dynamic bodies; default density 1).
    #[serde(default)]
    pub mass: Option<MassDesc>,
    /// Material name (for the contact table); `"default"` if omitted.
    #[serde(default = "default_material")]
    pub material: String,
    /// Extra point masses fixed to the body (a bead glued on a rattleback), in the shape
    /// frame; they add mass and inertia but no geometry. Dynamic bodies only.
    #[serde(default)]
    pub point_masses: Vec<PointMassDesc>,
}

/// A point mass fixed to a body.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename = "PointMass", deny_unknown_fields)]
pub struct PointMassDesc {
    /// Mass (> 0).
    pub mass: f64,
    /// Position in the body's shape frame.
    pub position: [f64; 3],
}

fn default_material() -> String {
    "default".to_string()
}

/// An orientation.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub enum RotationDesc {
    /// No rotation.
    #[default]
    Identity,
    /// A rotation by `degrees` about `axis` (need not be unit).
    AxisAngle {
        /// Rotation axis.
        axis: [f64; 3],
        /// Angle (degrees).
        degrees: f64,
    },
    /// A quaternion `Quaternion(x, y, z, w)`, components in that order, scalar last
    /// (normalised when read; the identity is `Quaternion(0.0, 0.0, 0.0, 1.0)`).
    Quaternion(f64, f64, f64, f64),
}

/// How much a body weighs.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum MassDesc {
    /// Uniform density (mass per volume).
    Density(f64),
    /// Total mass, spread uniformly over the volume.
    Mass(f64),
}

/// How a body moves.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub enum MotionDesc {
    /// Ballistic between collisions.
    #[default]
    Dynamic,
    /// Never moves.
    Fixed,
    /// Rotates at `rate` (rad/s) about `axis` through its centre (a spinning platter).
    Spinner {
        /// Rotation axis (world).
        axis: [f64; 3],
        /// Angular rate (rad/s, right-handed about the axis).
        rate: f64,
    },
    /// Translates sinusoidally along `axis`: `x(t) = x0 + amplitude·sin(2π·frequency·t + phase)·axis`
    /// (a vibrating feeder tray).
    Oscillator {
        /// Direction of motion (world).
        axis: [f64; 3],
        /// Amplitude (length).
        amplitude: f64,
        /// Frequency (Hz).
        frequency: f64,
        /// Phase at t = 0 (rad).
        #[serde(default)]
        phase: f64,
    },
}

/// Geometry of a body.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum ShapeDesc {
    /// An exact sphere centred on the frame origin.
    Sphere {
        /// Radius.
        radius: f64,
    },
    /// A box centred on the frame origin.
    Box {
        /// Half side lengths.
        half_extents: [f64; 3],
    },
    /// A polyhedral sphere: the icosahedron refined `level − 1` times (20·4^(level−1) faces).
    GeodesicSphere {
        /// Circumradius.
        radius: f64,
        /// Refinement level ≥ 1.
        level: u32,
    },
    /// An ellipsoid centred on the frame origin: exact (smooth) by default, or with `level`
    /// the polyhedron inscribed in it, the geodesic sphere of that level (20·4^(level−1)
    /// faces) scaled by the semi-axes.
    Ellipsoid {
        /// Semi-axes along x, y, z.
        semi_axes: [f64; 3],
        /// Refinement level 1..=6 of a polyhedral ellipsoid; absent for the exact one.
        #[serde(default)]
        level: Option<u32>,
    },
    /// A right prism over a regular polygon, axis along z (a coin, a disc, a domino-like slab).
    Prism {
        /// Number of sides ≥ 3.
        sides: u32,
        /// Circumradius of the polygon.
        radius: f64,
        /// Half height along z.
        half_height: f64,
    },
    /// The convex hull of points.
    Hull {
        /// The points (at least 4, not coplanar).
        points: Vec<[f64; 3]>,
    },
    /// A convex polyhedron from an OBJ file (path relative to the scene file).
    Obj {
        /// The file.
        path: String,
    },
    /// A non-convex body: convex parts at poses in the body frame.
    Compound {
        /// The parts.
        parts: Vec<PartDesc>,
    },
}

/// One convex part of a compound body.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Part", deny_unknown_fields)]
pub struct PartDesc {
    /// The part's geometry (not itself a compound).
    pub shape: ShapeDesc,
    /// Position in the body frame.
    #[serde(default)]
    pub position: [f64; 3],
    /// Orientation in the body frame.
    #[serde(default)]
    pub rotation: RotationDesc,
}

/// A parsed scene with the directory its relative paths are resolved against.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// The description.
    pub desc: SceneDesc,
    /// Directory of the scene file (for `Obj` paths).
    pub base_dir: PathBuf,
}

impl SceneDesc {
    /// Parses RON text. `source` names the text in errors (a file name).
    ///
    /// # Errors
    /// [`SimError::Parse`] with the line and column of the first problem.
    pub fn from_ron(text: &str, source: &str) -> Result<Self, SimError> {
        // Optional fields are written without `Some(…)`: `mass: Density(7800.0)`.
        ron::Options::default()
            .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
            .from_str(text)
            .map_err(|e| SimError::Parse {
                source_name: source.to_string(),
                message: with_hint(text, &e),
            })
    }

    /// Serialises to pretty RON.
    ///
    /// # Errors
    /// [`SimError::Parse`] if serialisation fails (not expected for valid values).
    pub fn to_ron(&self) -> Result<String, SimError> {
        let config = ron::ser::PrettyConfig::default()
            .extensions(ron::extensions::Extensions::IMPLICIT_SOME);
        ron::ser::to_string_pretty(self, config).map_err(|e| SimError::Parse {
            source_name: "<serialise>".into(),
            message: e.to_string(),
        })
    }

    /// Checks every field that can be checked without building geometry: finite numbers,
    /// positive ε_c, duration, rates and masses, μ ≥ 0, e ∈ [0, 1], unique body names, known
    /// materials, non-empty scene.
    ///
    /// # Errors
    /// [`SimError::Invalid`] naming the body (or `scene`) and the field.
    pub fn validate(&self) -> Result<(), SimError> {
        let scene = |field: &str, problem: String| SimError::Invalid {
            what: "scene".into(),
            field: field.into(),
            problem,
        };
        if self.bodies.is_empty() && self.multibodies.is_empty() {
            return Err(scene("bodies", "the scene has no bodies".into()));
        }
        if self.bodies.len() > MAX_BODIES {
            return Err(scene(
                "bodies",
                format!("{} bodies is more than {MAX_BODIES}", self.bodies.len()),
            ));
        }
        finite3(&self.gravity).map_err(|p| scene("gravity", p))?;
        if let Some(d) = self.duration {
            positive(d).map_err(|p| scene("duration", p))?;
        }
        positive(self.collision_epsilon).map_err(|p| scene("collision_epsilon", p))?;
        positive(self.output_rate).map_err(|p| scene("output_rate", p))?;
        if let Some(d) = self.duration {
            check_frames(d, self.output_rate).map_err(|p| scene("output_rate", p))?;
        }
        self.accuracy
            .validate()
            .map_err(|(f, p)| scene(&format!("accuracy.{f}"), p))?;
        check_contact(
            self.default_contact.friction,
            self.default_contact.restitution,
        )
        .map_err(|(f, p)| scene(&format!("default_contact.{f}"), p))?;
        // Materials of bodies and of multibodies' links (inline, or a URDF's overrides): a
        // contact pair may name any of them.
        let mut materials: Vec<&str> = vec!["default"];
        let links = self.multibodies.iter().flat_map(|m| {
            let inline = m.links.iter().map(|l| l.material.as_str());
            let overrides = m
                .urdf
                .iter()
                .flat_map(|u| u.links.iter().filter_map(|l| l.material.as_deref()));
            inline.chain(overrides)
        });
        for m in self.bodies.iter().map(|b| b.material.as_str()).chain(links) {
            if !materials.contains(&m) {
                materials.push(m);
            }
        }
        for (k, c) in self.contacts.iter().enumerate() {
            let what = format!("contacts[{k}] ({} / {})", c.a, c.b);
            check_contact(c.friction, c.restitution).map_err(|(f, p)| SimError::Invalid {
                what: what.clone(),
                field: f.into(),
                problem: p,
            })?;
            for (field, m) in [("a", &c.a), ("b", &c.b)] {
                if !materials.contains(&m.as_str()) {
                    return Err(SimError::Invalid {
                        what,
                        field: field.into(),
                        problem: format!("no body or link uses material \"{m}\""),
                    });
                }
            }
        }
        let mut names: FxHashSet<&str> = FxHashSet::default();
        for (k, b) in self.bodies.iter().enumerate() {
            b.validate(k)?;
            if !names.insert(&b.name) {
                return Err(SimError::Invalid {
                    what: format!("body \"{}\"", b.name),
                    field: "name".into(),
                    problem: "another body has the same name".into(),
                });
            }
        }
        let extent = self
            .bodies
            .iter()
            .map(|b| shape_extent(&b.shape))
            .fold(0.0, f64::max);
        if let Some((name, size)) = self.thinnest_dynamic_body() {
            if self.collision_epsilon > MAX_EPSILON_REL * size {
                return Err(scene(
                    "collision_epsilon",
                    format!(
                        "{:e} is more than {MAX_EPSILON_REL} × the half-size {size:e} of body \"{name}\", \
                         the thinnest dynamic body: contact would be declared {:.0} % of its size \
                         away (use 1e-3 to 1e-2 of the body sizes)",
                        self.collision_epsilon,
                        100.0 * self.collision_epsilon / size
                    ),
                ));
            }
        }
        if self.collision_epsilon < MIN_EPSILON_REL * extent {
            return Err(scene(
                "collision_epsilon",
                format!(
                    "{:e} is below {MIN_EPSILON_REL:e} × the largest body size {extent:e}: \
                     distances are not that accurate (use 1e-3 to 1e-2 of the body sizes)",
                    self.collision_epsilon
                ),
            ));
        }
        if self.multibodies.is_empty()
            && !self.bodies.iter().any(|b| b.motion == MotionDesc::Dynamic)
        {
            return Err(scene(
                "bodies",
                "no body is dynamic: nothing would move".into(),
            ));
        }
        let bodies: Vec<&str> = self.bodies.iter().map(|b| b.name.as_str()).collect();
        let mut controllers: FxHashSet<&str> = FxHashSet::default();
        for c in &self.controllers {
            c.validate(&bodies)?;
            if !controllers.insert(c.name()) {
                return Err(SimError::Invalid {
                    what: format!("controller \"{}\"", c.name()),
                    field: "name".into(),
                    problem: "another controller has the same name".into(),
                });
            }
        }
        Ok(())
    }
}

impl BodyDesc {
    /// Checks every field of one body that can be checked without building it (finite
    /// numbers, positive sizes and masses, bounded counts); `index` is its place in the scene,
    /// for the error when it has no name.
    ///
    /// # Errors
    /// [`SimError::Invalid`] naming the body and the field.
    pub fn validate(&self, index: usize) -> Result<(), SimError> {
        let b = self;
        let what = if b.name.is_empty() {
            format!("body #{index}")
        } else {
            format!("body \"{}\"", b.name)
        };
        let bad = |field: &str, problem: String| SimError::Invalid {
            what: what.clone(),
            field: field.into(),
            problem,
        };
        if b.name.is_empty() {
            return Err(bad("name", "is empty".into()));
        }
        finite3(&b.position).map_err(|p| bad("position", p))?;
        finite3(&b.velocity).map_err(|p| bad("velocity", p))?;
        finite3(&b.angular_velocity).map_err(|p| bad("angular_velocity", p))?;
        let speed = norm3(&b.velocity);
        if speed > MAX_SPEED {
            return Err(bad(
                "velocity",
                format!("speed {speed:e} is above {MAX_SPEED:e} (MAX_SPEED)"),
            ));
        }
        let rim = norm3(&b.angular_velocity) * shape_extent(&b.shape);
        if rim > MAX_SPEED {
            return Err(bad(
                "angular_velocity",
                format!("turns its farthest point at {rim:e}, above {MAX_SPEED:e} (MAX_SPEED)"),
            ));
        }
        check_rotation(&b.rotation).map_err(|p| bad("rotation", p))?;
        check_shape(&b.shape, true).map_err(|(f, p)| bad(&format!("shape.{f}"), p))?;
        match b.mass {
            Some(MassDesc::Density(d)) => positive(d).map_err(|p| bad("mass.Density", p))?,
            Some(MassDesc::Mass(m)) => positive(m).map_err(|p| bad("mass.Mass", p))?,
            None => {}
        }
        for (k, pm) in b.point_masses.iter().enumerate() {
            positive(pm.mass).map_err(|p| bad(&format!("point_masses[{k}].mass"), p))?;
            finite3(&pm.position).map_err(|p| bad(&format!("point_masses[{k}].position"), p))?;
        }
        if !b.point_masses.is_empty() && b.motion != MotionDesc::Dynamic {
            return Err(bad(
                "point_masses",
                "only dynamic bodies take point masses".into(),
            ));
        }
        match b.motion {
            MotionDesc::Dynamic | MotionDesc::Fixed => {}
            MotionDesc::Spinner { axis, rate } => {
                nonzero3(&axis).map_err(|p| bad("motion.axis", p))?;
                finite(rate).map_err(|p| bad("motion.rate", p))?;
            }
            MotionDesc::Oscillator {
                axis,
                amplitude,
                frequency,
                phase,
            } => {
                nonzero3(&axis).map_err(|p| bad("motion.axis", p))?;
                non_negative(amplitude).map_err(|p| bad("motion.amplitude", p))?;
                non_negative(frequency).map_err(|p| bad("motion.frequency", p))?;
                finite(phase).map_err(|p| bad("motion.phase", p))?;
            }
        }
        if !matches!(b.motion, MotionDesc::Dynamic)
            && (b.velocity != [0.0; 3] || b.angular_velocity != [0.0; 3])
        {
            return Err(bad(
                "velocity",
                "only dynamic bodies take an initial velocity (scripted motion sets its own)"
                    .into(),
            ));
        }
        Ok(())
    }
}

impl AccuracyDesc {
    fn validate(&self) -> Result<(), (&'static str, String)> {
        positive(self.rotation_tolerance).map_err(|p| ("rotation_tolerance", p))?;
        positive(self.collision_tolerance).map_err(|p| ("collision_tolerance", p))?;
        positive(self.step_tolerance).map_err(|p| ("step_tolerance", p))?;
        if !(self.max_restitution.is_finite() && self.max_restitution >= 1.0) {
            return Err((
                "max_restitution",
                format!("{} must be finite and ≥ 1", self.max_restitution),
            ));
        }
        Ok(())
    }
}

impl SceneDesc {
    /// Things that are allowed but probably not meant: ε_c larger than [`WARN_EPSILON_REL`]
    /// of the thinnest dynamic body; dynamic bodies left at the default density 1 beside
    /// bodies given a mass or density (a steel ball of density 7800 dropped on boxes given no
    /// mass meets boxes 7800 times lighter per volume). Each is one sentence naming the body
    /// or field.
    ///
    /// Relative URDF paths of multibodies resolve against the current directory: use
    /// [`Scene::warnings`] for a scene read from a file.
    #[must_use]
    pub fn warnings(&self) -> Vec<String> {
        self.warnings_in(Path::new("."))
    }

    /// [`SceneDesc::warnings`], with relative paths (URDF files) resolved against `base_dir`.
    #[must_use]
    pub fn warnings_in(&self, base_dir: &Path) -> Vec<String> {
        let mut out = Vec::new();
        let dynamic = || {
            self.bodies
                .iter()
                .filter(|b| b.motion == MotionDesc::Dynamic)
        };
        let unset: Vec<&str> = dynamic()
            .filter(|b| b.mass.is_none())
            .map(|b| b.name.as_str())
            .collect();
        if let (Some(first), Some(given)) = (unset.first(), dynamic().find(|b| b.mass.is_some())) {
            let (others, verb) = match unset.len() {
                1 => (String::new(), "is"),
                n => (
                    format!(
                        " and {} other bod{}",
                        n - 1,
                        if n == 2 { "y" } else { "ies" }
                    ),
                    "are",
                ),
            };
            out.push(format!(
                "body \"{first}\"{others} {verb} left at the default density 1 (no `mass` given) while \
                 body \"{}\" has its mass given: give every dynamic body its mass or density \
                 (a heavy body landing on much lighter ones is a hard case for every contact \
                 model)",
                given.name
            ));
        }
        if let Some((name, size)) = self.thinnest_dynamic_body() {
            if self.collision_epsilon > WARN_EPSILON_REL * size {
                out.push(format!(
                    "collision_epsilon {:e} is {:.1} % of the half-size {size:e} of body \"{name}\" \
                     (the thesis uses 0.1 to 1 %): contacts will be coarse",
                    self.collision_epsilon,
                    100.0 * self.collision_epsilon / size
                ));
            }
        }
        for m in &self.multibodies {
            out.extend(m.warnings(DVec3::from_array(self.gravity), base_dir));
        }
        out
    }

    /// The dynamic body with the smallest half-size (smallest half extent, radius or half
    /// height of its shape or of its largest part) and that size; `None` without dynamic
    /// bodies or when the sizes are not known without reading files.
    fn thinnest_dynamic_body(&self) -> Option<(&str, f64)> {
        self.bodies
            .iter()
            .filter(|b| b.motion == MotionDesc::Dynamic)
            .filter_map(|b| shape_thickness(&b.shape).map(|t| (b.name.as_str(), t)))
            .filter(|(_, t)| *t > 0.0)
            .min_by(|a, b| a.1.total_cmp(&b.1))
    }
}

/// Frames a run of `duration` at `rate` frames/s records must stay below [`MAX_FRAMES`].
///
/// # Errors
/// A sentence saying how many frames that would be.
pub fn check_frames(duration: f64, rate: f64) -> Result<(), String> {
    if duration * rate > MAX_FRAMES {
        return Err(format!(
            "{rate} frames/s over {duration} s is more than {MAX_FRAMES:e} frames"
        ));
    }
    Ok(())
}

/// RON's message, with the multibody it is in, plus how to write the value it choked on
/// when that is a rotation.
fn with_hint(text: &str, e: &ron::error::SpannedError) -> String {
    let mut message = e.to_string();
    if let Some(at) = multibody::enclosing_multibody(text, e.span.start.line, e.span.start.col) {
        message.push_str(&match at.field {
            Some(field) => format!(" (in multibody \"{}\", field `{field}`)", at.name),
            None => format!(" (in multibody \"{}\")", at.name),
        });
    }
    let line = text
        .lines()
        .nth(e.span.start.line.saturating_sub(1))
        .unwrap_or("");
    if line.contains("Quaternion") {
        message.push_str(
            " (a quaternion is written Quaternion(x, y, z, w), four numbers, scalar last: \
             Quaternion(0.0, 0.0, 0.0, 1.0) is no rotation)",
        );
    } else if line.contains("AxisAngle") {
        message.push_str(
            " (an axis-angle rotation is written AxisAngle(axis: (x, y, z), degrees: a))",
        );
    }
    message
}

impl Scene {
    /// [`SceneDesc::warnings`] of the scene, its relative paths resolved against its
    /// directory (a multibody read from a URDF file is checked too).
    #[must_use]
    pub fn warnings(&self) -> Vec<String> {
        self.desc.warnings_in(&self.base_dir)
    }

    /// Reads and parses a scene file (not yet validated).
    ///
    /// # Errors
    /// [`SimError::Io`] when the file cannot be read, [`SimError::Parse`] when it is not a
    /// scene.
    pub fn read(path: &Path) -> Result<Self, SimError> {
        let text = std::fs::read_to_string(path).map_err(|e| SimError::Io {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
        let desc = SceneDesc::from_ron(&text, &path.display().to_string())?;
        Ok(Self {
            desc,
            base_dir: path.parent().map(Path::to_path_buf).unwrap_or_default(),
        })
    }

    /// A scene from a description whose relative paths resolve against `base_dir`.
    #[must_use]
    pub fn new(desc: SceneDesc, base_dir: impl Into<PathBuf>) -> Self {
        Self {
            desc,
            base_dir: base_dir.into(),
        }
    }
}

fn finite(x: f64) -> Result<(), String> {
    if x.is_finite() {
        Ok(())
    } else {
        Err(format!("{x} is not a finite number"))
    }
}

pub(crate) fn positive(x: f64) -> Result<(), String> {
    if x.is_finite() && x > 0.0 {
        Ok(())
    } else {
        Err(format!("{x} must be finite and > 0"))
    }
}

fn non_negative(x: f64) -> Result<(), String> {
    if x.is_finite() && x >= 0.0 {
        Ok(())
    } else {
        Err(format!("{x} must be finite and ≥ 0"))
    }
}

fn norm3(v: &[f64; 3]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

pub(crate) fn finite3(v: &[f64; 3]) -> Result<(), String> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(format!("{v:?} has a component that is not a finite number"))
    }
}

fn nonzero3(v: &[f64; 3]) -> Result<(), String> {
    finite3(v)?;
    if v.iter().any(|&x| x != 0.0) {
        Ok(())
    } else {
        Err("the axis is the zero vector".into())
    }
}

pub(crate) fn check_rotation(r: &RotationDesc) -> Result<(), String> {
    match r {
        RotationDesc::Identity => Ok(()),
        RotationDesc::AxisAngle { axis, degrees } => {
            nonzero3(axis)?;
            finite(*degrees)
        }
        RotationDesc::Quaternion(x, y, z, w) => {
            let q = [*x, *y, *z, *w];
            if q.iter().all(|c| c.is_finite()) && q.iter().any(|&c| c != 0.0) {
                Ok(())
            } else {
                Err(format!(
                    "Quaternion({x}, {y}, {z}, {w}) (x, y, z, w) must be finite and not all zero"
                ))
            }
        }
    }
}

/// A rough size of a (validated) shape: its largest half extent, radius or coordinate. Used
/// only to judge ε_c; an OBJ file counts as 0 (not read here).
fn shape_extent(s: &ShapeDesc) -> f64 {
    match s {
        ShapeDesc::Sphere { radius } | ShapeDesc::GeodesicSphere { radius, .. } => *radius,
        ShapeDesc::Box { half_extents } => half_extents.iter().copied().fold(0.0, f64::max),
        ShapeDesc::Ellipsoid { semi_axes, .. } => semi_axes.iter().copied().fold(0.0, f64::max),
        ShapeDesc::Prism {
            radius,
            half_height,
            ..
        } => radius.max(*half_height),
        ShapeDesc::Hull { points } => points.iter().flatten().map(|x| x.abs()).fold(0.0, f64::max),
        ShapeDesc::Obj { .. } => 0.0,
        ShapeDesc::Compound { parts } => parts
            .iter()
            .map(|p| {
                shape_extent(&p.shape) + p.position.iter().map(|x| x.abs()).fold(0.0, f64::max)
            })
            .fold(0.0, f64::max),
    }
}

/// The smallest half-size of a (validated) shape: its smallest half extent, radius, half
/// height or semi-axis, or for a compound that of its largest part (the parts hold each other
/// together); `None` for an OBJ file or a hull (not measured without building it).
pub(crate) fn shape_thickness(s: &ShapeDesc) -> Option<f64> {
    match s {
        ShapeDesc::Sphere { radius } | ShapeDesc::GeodesicSphere { radius, .. } => Some(*radius),
        ShapeDesc::Box { half_extents } => {
            Some(half_extents.iter().copied().fold(f64::INFINITY, f64::min))
        }
        ShapeDesc::Ellipsoid { semi_axes, .. } => {
            Some(semi_axes.iter().copied().fold(f64::INFINITY, f64::min))
        }
        ShapeDesc::Prism {
            radius,
            half_height,
            ..
        } => Some(radius.min(*half_height)),
        ShapeDesc::Hull { .. } | ShapeDesc::Obj { .. } => None,
        ShapeDesc::Compound { parts } => parts
            .iter()
            .filter_map(|p| shape_thickness(&p.shape))
            .fold(None, |m: Option<f64>, t| Some(m.map_or(t, |m| m.max(t)))),
    }
}

fn check_contact(friction: f64, restitution: f64) -> Result<(), (&'static str, String)> {
    non_negative(friction).map_err(|p| ("friction", p))?;
    if !(restitution.is_finite() && (0.0..=1.0).contains(&restitution)) {
        return Err(("restitution", format!("{restitution} must lie in [0, 1]")));
    }
    Ok(())
}

pub(crate) fn check_shape(s: &ShapeDesc, top: bool) -> Result<(), (String, String)> {
    let err = |f: &str, p: String| (f.to_string(), p);
    match s {
        ShapeDesc::Sphere { radius } => positive(*radius).map_err(|p| err("radius", p)),
        ShapeDesc::Box { half_extents } => {
            for x in half_extents {
                positive(*x).map_err(|p| err("half_extents", p))?;
            }
            Ok(())
        }
        ShapeDesc::GeodesicSphere { radius, level } => {
            positive(*radius).map_err(|p| err("radius", p))?;
            if (1..=MAX_GEODESIC_LEVEL).contains(level) {
                Ok(())
            } else {
                Err(err(
                    "level",
                    format!("{level} must lie in 1..={MAX_GEODESIC_LEVEL}"),
                ))
            }
        }
        ShapeDesc::Ellipsoid { semi_axes, level } => {
            for x in semi_axes {
                positive(*x).map_err(|p| err("semi_axes", p))?;
            }
            match level {
                Some(l) if !(1..=MAX_ELLIPSOID_LEVEL).contains(l) => Err(err(
                    "level",
                    format!("{l} must lie in 1..={MAX_ELLIPSOID_LEVEL}"),
                )),
                _ => Ok(()),
            }
        }
        ShapeDesc::Prism {
            sides,
            radius,
            half_height,
        } => {
            if !(3..=MAX_PRISM_SIDES).contains(sides) {
                return Err(err(
                    "sides",
                    format!("{sides} must lie in 3..={MAX_PRISM_SIDES}"),
                ));
            }
            positive(*radius).map_err(|p| err("radius", p))?;
            positive(*half_height).map_err(|p| err("half_height", p))
        }
        ShapeDesc::Hull { points } => {
            if points.len() < 4 {
                return Err(err(
                    "points",
                    format!("{} points cannot enclose a volume (need ≥ 4)", points.len()),
                ));
            }
            if points.len() > MAX_HULL_POINTS {
                return Err(err(
                    "points",
                    format!("{} points is more than {MAX_HULL_POINTS}", points.len()),
                ));
            }
            for (k, p) in points.iter().enumerate() {
                finite3(p).map_err(|e| err(&format!("points[{k}]"), e))?;
            }
            Ok(())
        }
        ShapeDesc::Obj { path } => {
            if path.is_empty() {
                Err(err("path", "is empty".into()))
            } else {
                Ok(())
            }
        }
        ShapeDesc::Compound { parts } => {
            if !top {
                return Err(err("parts", "a part cannot itself be a compound".into()));
            }
            if parts.is_empty() {
                return Err(err("parts", "a compound needs at least one part".into()));
            }
            if parts.len() > MAX_PARTS {
                return Err(err(
                    "parts",
                    format!("{} parts is more than {MAX_PARTS}", parts.len()),
                ));
            }
            for (k, part) in parts.iter().enumerate() {
                finite3(&part.position).map_err(|e| err(&format!("parts[{k}].position"), e))?;
                check_rotation(&part.rotation)
                    .map_err(|e| err(&format!("parts[{k}].rotation"), e))?;
                check_shape(&part.shape, false)
                    .map_err(|(f, e)| (format!("parts[{k}].shape.{f}"), e))?;
            }
            Ok(())
        }
    }
}
