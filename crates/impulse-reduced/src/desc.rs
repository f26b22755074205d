//! Mechanism descriptions: what a `Mechanism(...)` RON file holds and what the builder fills
//! in. Descriptions carry serde and defaults; [`MechanismDesc::build`] validates them and
//! compiles a [`crate::Mechanism`].
//!
//! A minimal file (a compliant hinge arm, its tip as end effector):
//!
//! ```ron
//! Mechanism(
//!     name: "arm",
//!     links: [
//!         Link(name: "base"),
//!         Link(name: "tip", position: (1.0, 0.0, 0.0), mass: 1.0, inertia: (0.01, 0.01, 0.01),
//!              shapes: [Sphere(radius: 0.05)]),
//!     ],
//!     joints: [
//!         Joint(name: "hinge", parent: "base", child: "tip", anchor: (0.0, 0.0, 0.0),
//!               kind: Hinge(axis: (0.0, 0.0, 1.0)), compliance: [0.001]),
//!     ],
//!     end_effectors: ["tip"],
//! )
//! ```
//!
//! All poses are the **rest** configuration, in world coordinates. A joint's frame sits at its
//! `anchor` with world-aligned axes at rest and is fixed to both links; its free directions are
//! the hinge or slider `axis` (world, at rest), the three rotations of a ball, or all six
//! motions of a weld, in that order: for a weld, translations x, y, z then rotations x, y, z.

use serde::{Deserialize, Serialize};

use crate::error::Error;

/// How the base link is held.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum BaseDesc {
    /// Fixed in the world.
    #[default]
    Fixed,
    /// A free rigid body (FORK⁻¹S §6.1).
    Free,
}

/// A collision shape of a link, in link coordinates.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum ShapeDesc {
    /// A sphere.
    Sphere {
        /// Radius (m).
        radius: f64,
        /// Centre in link coordinates (m).
        #[serde(default)]
        center: [f64; 3],
    },
    /// An axis-aligned (in link axes) box.
    Box {
        /// Half extents (m).
        half_extents: [f64; 3],
        /// Centre in link coordinates (m).
        #[serde(default)]
        center: [f64; 3],
    },
}

/// A rigid link.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Link", deny_unknown_fields)]
pub struct LinkDesc {
    /// Unique name.
    pub name: String,
    /// Origin of the link frame at rest (world, m).
    #[serde(default)]
    pub position: [f64; 3],
    /// Orientation of the link frame at rest, quaternion `(x, y, z, w)` (normalised on build).
    #[serde(default = "identity_quat")]
    pub rotation: [f64; 4],
    /// Mass (kg), ≥ 0 (a massless link is allowed if the mechanism stays non-singular).
    #[serde(default)]
    pub mass: f64,
    /// Centre of mass in link coordinates (m).
    #[serde(default)]
    pub com: [f64; 3],
    /// Principal moments of inertia about the centre of mass, in link axes (kg·m²), ≥ 0.
    #[serde(default)]
    pub inertia: [f64; 3],
    /// Collision shapes (used by end effectors in contact).
    #[serde(default)]
    pub shapes: Vec<ShapeDesc>,
}

fn identity_quat() -> [f64; 4] {
    [0.0, 0.0, 0.0, 1.0]
}

impl LinkDesc {
    /// A massless link at `position` with identity orientation and no shapes.
    #[must_use]
    pub fn new(name: &str, position: [f64; 3]) -> Self {
        LinkDesc {
            name: name.to_owned(),
            position,
            rotation: identity_quat(),
            mass: 0.0,
            com: [0.0; 3],
            inertia: [0.0; 3],
            shapes: Vec::new(),
        }
    }

    /// Sets mass (kg) and principal moments about the centre of mass (kg·m²).
    #[must_use]
    pub fn mass(mut self, mass: f64, inertia: [f64; 3]) -> Self {
        self.mass = mass;
        self.inertia = inertia;
        self
    }

    /// Sets the rest orientation (quaternion `x, y, z, w`).
    #[must_use]
    pub fn rotation(mut self, q: [f64; 4]) -> Self {
        self.rotation = q;
        self
    }

    /// Sets the centre of mass (link coordinates, m).
    #[must_use]
    pub fn com(mut self, com: [f64; 3]) -> Self {
        self.com = com;
        self
    }

    /// Adds a collision shape.
    #[must_use]
    pub fn shape(mut self, shape: ShapeDesc) -> Self {
        self.shapes.push(shape);
        self
    }
}

/// The kind of a compliant joint: which relative motions are free (compliant); all others are
/// rigid.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum JointKindDesc {
    /// One rotation about `axis` (world, at rest) through the anchor.
    Hinge {
        /// Axis direction (normalised on build).
        axis: [f64; 3],
    },
    /// One translation along `axis` (world, at rest).
    Slider {
        /// Axis direction (normalised on build).
        axis: [f64; 3],
    },
    /// Three rotations about the anchor (x, y, z, world axes at rest).
    Ball,
    /// All six motions: "weld with compliance" (translations x, y, z, then rotations x, y, z).
    Weld,
}

/// Most joint degrees of freedom (and links) [`MechanismDesc::build`] accepts. The reduction
/// and its reference statics build dense matrices of dof² entries and factorise them in time
/// growing as dof³ (measured, `impulse reduce --until 0.01` on ball-jointed helices, one run:
/// 1 200 dof in 1.3 s, 2 100 in 32 s, 3 000 in over two minutes; 30 000 dof grew past 23 GB
/// of memory within a minute); the paper's largest mechanism, helix-400, has 1 200. Default
/// `3000`.
pub const MAX_DOF: usize = 3000;

impl JointKindDesc {
    /// Number of free directions.
    #[must_use]
    pub fn dof(&self) -> usize {
        match self {
            JointKindDesc::Hinge { .. } | JointKindDesc::Slider { .. } => 1,
            JointKindDesc::Ball => 3,
            JointKindDesc::Weld => 6,
        }
    }
}

/// A compliant joint from `parent` to `child` (the direction of the walk, FORK⁻¹S §3.3).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Joint", deny_unknown_fields)]
pub struct JointDesc {
    /// Unique name.
    pub name: String,
    /// Parent link (towards the base).
    pub parent: String,
    /// Child link (away from the base).
    pub child: String,
    /// Joint centre at rest (world, m).
    #[serde(default)]
    pub anchor: [f64; 3],
    /// Which motions are free.
    pub kind: JointKindDesc,
    /// Compliance per free direction (rad/(N·m) for rotations, m/N for translations), > 0;
    /// one value applies to every direction.
    pub compliance: Vec<f64>,
    /// Damping per free direction (N·m·s/rad or N·s/m), ≥ 0; one value applies to every
    /// direction; empty means undamped.
    #[serde(default)]
    pub damping: Vec<f64>,
}

impl JointDesc {
    fn new(name: &str, parent: &str, child: &str, anchor: [f64; 3], kind: JointKindDesc) -> Self {
        JointDesc {
            name: name.to_owned(),
            parent: parent.to_owned(),
            child: child.to_owned(),
            anchor,
            kind,
            compliance: vec![1.0],
            damping: Vec::new(),
        }
    }

    /// A hinge about `axis` through `anchor` (world, at rest), unit compliance.
    #[must_use]
    pub fn hinge(name: &str, parent: &str, child: &str, anchor: [f64; 3], axis: [f64; 3]) -> Self {
        Self::new(name, parent, child, anchor, JointKindDesc::Hinge { axis })
    }

    /// A slider along `axis` (world, at rest), unit compliance.
    #[must_use]
    pub fn slider(name: &str, parent: &str, child: &str, anchor: [f64; 3], axis: [f64; 3]) -> Self {
        Self::new(name, parent, child, anchor, JointKindDesc::Slider { axis })
    }

    /// A ball joint at `anchor`, unit compliance.
    #[must_use]
    pub fn ball(name: &str, parent: &str, child: &str, anchor: [f64; 3]) -> Self {
        Self::new(name, parent, child, anchor, JointKindDesc::Ball)
    }

    /// A 6-DoF compliant weld at `anchor`, unit compliance.
    #[must_use]
    pub fn weld(name: &str, parent: &str, child: &str, anchor: [f64; 3]) -> Self {
        Self::new(name, parent, child, anchor, JointKindDesc::Weld)
    }

    /// Sets the compliances (one value, or one per free direction).
    #[must_use]
    pub fn compliance(mut self, c: &[f64]) -> Self {
        self.compliance = c.to_vec();
        self
    }

    /// Sets the dampings (one value, or one per free direction).
    #[must_use]
    pub fn damping(mut self, d: &[f64]) -> Self {
        self.damping = d.to_vec();
        self
    }
}

/// A whole mechanism: links, joints, base and end effectors.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Mechanism", deny_unknown_fields)]
pub struct MechanismDesc {
    /// A short name, used in reports.
    #[serde(default)]
    pub name: String,
    /// Free text: what the mechanism is.
    #[serde(default)]
    pub description: String,
    /// How the base (the one link that is no joint's child) is held.
    #[serde(default)]
    pub base: BaseDesc,
    /// Gravitational acceleration (world, m/s²).
    #[serde(default)]
    pub gravity: [f64; 3],
    /// The links.
    pub links: Vec<LinkDesc>,
    /// The joints.
    pub joints: Vec<JointDesc>,
    /// Names of the end-effector links (leaves of the walk).
    pub end_effectors: Vec<String>,
}

impl MechanismDesc {
    /// An empty description with a fixed base and no gravity (the builder's start).
    #[must_use]
    pub fn new(name: &str) -> Self {
        MechanismDesc {
            name: name.to_owned(),
            description: String::new(),
            base: BaseDesc::Fixed,
            gravity: [0.0; 3],
            links: Vec::new(),
            joints: Vec::new(),
            end_effectors: Vec::new(),
        }
    }

    /// Adds a link.
    pub fn link(&mut self, link: LinkDesc) -> &mut Self {
        self.links.push(link);
        self
    }

    /// Adds a joint.
    pub fn joint(&mut self, joint: JointDesc) -> &mut Self {
        self.joints.push(joint);
        self
    }

    /// Marks a link as an end effector.
    pub fn end_effector(&mut self, link: &str) -> &mut Self {
        self.end_effectors.push(link.to_owned());
        self
    }

    /// Sets gravity (world, m/s²).
    pub fn gravity(&mut self, g: [f64; 3]) -> &mut Self {
        self.gravity = g;
        self
    }

    /// Sets how the base is held.
    pub fn base(&mut self, base: BaseDesc) -> &mut Self {
        self.base = base;
        self
    }

    /// Parses a `Mechanism(...)` RON text.
    ///
    /// # Errors
    /// [`Error::Parse`] with ron's message (line and column).
    pub fn from_ron(text: &str) -> Result<Self, Error> {
        ron::from_str(text).map_err(|e| Error::Parse(e.to_string()))
    }

    /// The description as pretty RON.
    ///
    /// # Errors
    /// [`Error::Parse`] if serialisation fails (it does not for finite values).
    pub fn to_ron(&self) -> Result<String, Error> {
        ron::ser::to_string_pretty(self, ron::ser::PrettyConfig::default())
            .map_err(|e| Error::Parse(e.to_string()))
    }

    /// Validates and compiles the mechanism, refusing one with more than [`MAX_DOF`] joint
    /// degrees of freedom or links ([`Self::build_with_max_dof`]).
    ///
    /// # Errors
    /// Any of the validation errors of [`Error`], naming the link, joint or end effector;
    /// [`Error::TooLarge`] over the limit.
    pub fn build(&self) -> Result<crate::Mechanism, Error> {
        self.build_with_max_dof(MAX_DOF)
    }

    /// [`Self::build`] with the limit `max_dof` on the joints' degrees of freedom (and
    /// `max_dof + 1` on the links), checked before any other work.
    ///
    /// # Errors
    /// As [`Self::build`].
    pub fn build_with_max_dof(&self, max_dof: usize) -> Result<crate::Mechanism, Error> {
        let dof = self
            .joints
            .iter()
            .fold(0usize, |n, j| n.saturating_add(j.kind.dof()));
        // A valid tree has one joint per link but the base, each with one dof or more.
        if dof > max_dof || self.links.len() > max_dof.saturating_add(1) {
            return Err(Error::TooLarge {
                links: self.links.len(),
                dof,
                limit: max_dof,
            });
        }
        crate::mechanism::compile(self)
    }
}
