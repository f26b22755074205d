//! Multibodies in scene files (thesis ch. 5): links with their shapes and masses, joints with
//! springs, dampers, friction and limits, the initial joint state, and joint controllers.
//!
//! ```ron
//! Multibody(
//!     name: "pendulum",
//!     base: Fixed,
//!     position: (0.0, 0.0, 1.0),
//!     links: [
//!         Link(name: "support"),
//!         Link(name: "rod", shape: Some(Cuboid(half_extents: (0.02, 0.02, 0.25))),
//!              position: (0.0, 0.0, -0.25), mass: Some(Mass(1.0))),
//!     ],
//!     joints: [
//!         Joint(name: "hinge", kind: Revolute, parent: "support", child: "rod",
//!               axis: (0.0, 1.0, 0.0), q: 1.0),
//!     ],
//! )
//! ```
//!
//! `self_collision: true` makes its links collide with each other, except adjacent ones (two
//! links welded together by fixed joints, and the parent and child of each moving joint);
//! off by default ([`MultibodyDesc::self_collision`], `docs/hybrid.md`).
//!
//! Or from a URDF file with overrides ([`UrdfDesc`], `docs/urdf.md`):
//!
//! ```ron
//! Multibody(
//!     name: "arm",
//!     urdf: Urdf(path: "../urdf/two_link_arm.urdf",
//!                joints: [JointOverride(name: "shoulder", q: 0.5, damping: 0.01)]),
//!     position: (0.0, 0.0, 1.0),
//! )
//! ```

use std::path::Path;

use glam::{DMat3, DQuat, DVec3};
use impulse_geom::{Pose, SpatialInertia};
use impulse_multibody::{
    AdaptiveRk4, BaseKind, Integrator, JointLimit, JointPassive, JointPd, JointPid, JointSpec,
    JointType, ModelBuilder, Simulation,
};
use serde::{Deserialize, Serialize};

use super::{MassDesc, RotationDesc, ShapeDesc, check_rotation, check_shape, finite3, positive};
use crate::build::rotation;
use crate::error::SimError;
use crate::world::LinkShape;

mod stl;
mod urdf;

pub use urdf::{JointOverride, LinkOverride, URDF_CYLINDER_SIDES, UrdfDesc};

fn default_material() -> String {
    "default".to_string()
}

/// How a multibody's base moves.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum BaseDesc {
    /// The root link is welded to the world at the multibody's pose.
    #[default]
    Fixed,
    /// The root link floats freely (6 degrees of freedom), starting at the multibody's pose.
    Floating,
}

/// The kind of a joint.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum JointKindDesc {
    /// Rotation about `axis` (rad).
    Revolute,
    /// Translation along `axis` (m).
    Prismatic,
    /// The child is welded to its parent.
    Fixed,
}

/// A joint's travel limits, impulsive stops (thesis ch. 5: a collision in joint space).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Limit", deny_unknown_fields)]
pub struct LimitDesc {
    /// Lower limit (rad or m).
    pub lower: f64,
    /// Upper limit (rad or m).
    pub upper: f64,
    /// Newton restitution of the stop, in [0, 1]. Default `0`.
    #[serde(default)]
    pub restitution: f64,
}

/// One link.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Link", deny_unknown_fields)]
pub struct LinkDesc {
    /// Unique name within the multibody.
    pub name: String,
    /// Collision shape (`None`: the link collides with nothing).
    #[serde(default)]
    pub shape: Option<ShapeDesc>,
    /// Position of the shape in the link frame (the link frame sits on its inboard joint).
    #[serde(default)]
    pub position: [f64; 3],
    /// Orientation of the shape in the link frame.
    #[serde(default)]
    pub rotation: RotationDesc,
    /// Mass from the shape's volume, by density or total mass (default density 1). A link
    /// without a shape gets its mass from `inertia`, or none (a massless root).
    #[serde(default)]
    pub mass: Option<MassDesc>,
    /// Explicit mass properties, in place of the shape's (a link without a shape).
    #[serde(default)]
    pub inertia: Option<InertiaDesc>,
    /// Material name (contact table); `"default"` if omitted.
    #[serde(default = "default_material")]
    pub material: String,
}

/// Explicit mass properties of a link.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Inertia", deny_unknown_fields)]
pub struct InertiaDesc {
    /// Mass (> 0).
    pub mass: f64,
    /// Centre of mass in the link frame.
    #[serde(default)]
    pub com: [f64; 3],
    /// Principal moments about the centre of mass, link axes (each > 0).
    pub moments: [f64; 3],
}

/// One joint.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Joint", deny_unknown_fields)]
pub struct JointDesc {
    /// Unique name within the multibody.
    pub name: String,
    /// Its kind.
    pub kind: JointKindDesc,
    /// The parent link.
    pub parent: String,
    /// The child link.
    pub child: String,
    /// Position of the joint frame in the parent link's frame.
    #[serde(default)]
    pub position: [f64; 3],
    /// Orientation of the joint frame in the parent link's frame.
    #[serde(default)]
    pub rotation: RotationDesc,
    /// The axis (joint frame; revolute and prismatic joints). Default `(0, 0, 1)`.
    #[serde(default = "default_axis")]
    pub axis: [f64; 3],
    /// Initial position (rad or m).
    #[serde(default)]
    pub q: f64,
    /// Initial rate (rad/s or m/s).
    #[serde(default)]
    pub qd: f64,
    /// A linear spring `(stiffness, rest position)`.
    #[serde(default)]
    pub spring: Option<(f64, f64)>,
    /// Viscous damping.
    #[serde(default)]
    pub damping: f64,
    /// Constant (Coulomb) joint friction.
    #[serde(default)]
    pub friction: f64,
    /// Travel limits as impulsive stops.
    #[serde(default)]
    pub limit: Option<LimitDesc>,
}

fn default_axis() -> [f64; 3] {
    [0.0, 0.0, 1.0]
}

/// A joint controller (thesis §5.4), updated `rate` times per second with zero-order hold.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum ControllerDesc {
    /// `τ = −k_p (q − target) − k_v (q̇ − target_rate)`; `kp: 0` regulates velocity.
    Pd {
        /// The joint.
        joint: String,
        /// Position gain.
        kp: f64,
        /// Velocity gain.
        kv: f64,
        /// Desired position.
        #[serde(default)]
        target: f64,
        /// Desired rate.
        #[serde(default)]
        target_rate: f64,
        /// Updates per second.
        rate: f64,
    },
    /// PD plus an integral term `k_i ∫(target − q)`.
    Pid {
        /// The joint.
        joint: String,
        /// Position gain.
        kp: f64,
        /// Velocity gain.
        kv: f64,
        /// Integral gain.
        ki: f64,
        /// Desired position.
        #[serde(default)]
        target: f64,
        /// Updates per second.
        rate: f64,
    },
}

/// A multibody of a scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Multibody", deny_unknown_fields)]
pub struct MultibodyDesc {
    /// Unique name (its links' bodies are `"<name>/<link>"`).
    pub name: String,
    /// Fixed or floating base.
    #[serde(default)]
    pub base: BaseDesc,
    /// Position of the root link's frame (world).
    #[serde(default)]
    pub position: [f64; 3],
    /// Orientation of the root link's frame (world).
    #[serde(default)]
    pub rotation: RotationDesc,
    /// Initial velocity of a floating root link's frame origin (world).
    #[serde(default)]
    pub velocity: [f64; 3],
    /// Initial angular velocity of a floating root link (world, rad/s).
    #[serde(default)]
    pub angular_velocity: [f64; 3],
    /// A URDF file the links and joints are read from, with overrides by name (`None`: the
    /// multibody is all inline).
    #[serde(default)]
    pub urdf: Option<UrdfDesc>,
    /// The links; the first is the root. With `urdf`, links added to the file's (attached by
    /// `joints`; the file's root stays the root).
    #[serde(default)]
    pub links: Vec<LinkDesc>,
    /// The joints (each child's inboard joint); with `urdf`, joints added to the file's.
    #[serde(default)]
    pub joints: Vec<JointDesc>,
    /// Joint controllers.
    #[serde(default)]
    pub controllers: Vec<ControllerDesc>,
    /// Relative error tolerance of the adaptive RK4 integrator per step. Default `1e-9`.
    #[serde(default = "default_tolerance")]
    pub tolerance: f64,
    /// Whether its links collide with each other (self-collision), adjacent links excepted:
    /// two links welded into one rigid body by fixed joints, and the parent and child of
    /// every moving joint never do (`impulse_multibody::Model::links_adjacent`). Default
    /// `false`: links of one multibody never collide.
    #[serde(default)]
    pub self_collision: bool,
}

fn default_tolerance() -> f64 {
    1e-9
}

impl MultibodyDesc {
    /// Builds the multibody's simulation and its links' shapes, in gravity `gravity`; a URDF
    /// file and shapes from OBJ files resolve against `base_dir` (a URDF's meshes against the
    /// URDF's directory). A fixed root's shape is placed at `position`/`rotation` (its link
    /// frame is the world's; the placement is folded into its joints).
    ///
    /// # Errors
    /// [`SimError::Invalid`] or [`SimError::Geometry`] naming the multibody and the link,
    /// joint or controller that is wrong (an unknown parent, a loop, a zero-mass link with
    /// children, non-finite numbers, NaN gains, a controller on a missing joint), and for a
    /// URDF multibody the file, link, joint or override at fault (an unreadable or malformed
    /// file, a link with two parents, no single root, an unsupported joint, collision geometry
    /// or mesh format, an override naming nothing in the file).
    pub fn build(
        &self,
        gravity: DVec3,
        base_dir: &Path,
    ) -> Result<(Simulation, Vec<LinkShape>), SimError> {
        let what = format!("multibody \"{}\"", self.name);
        let bad = |field: String, problem: String| SimError::Invalid {
            what: what.clone(),
            field,
            problem,
        };
        if self.name.is_empty() {
            return Err(bad("name".into(), "is empty".into()));
        }
        if self.links.is_empty() && self.urdf.is_none() {
            return Err(bad(
                "links".into(),
                "a multibody needs at least one link (or a `urdf` file)".into(),
            ));
        }
        finite3(&self.position).map_err(|p| bad("position".into(), p))?;
        finite3(&self.velocity).map_err(|p| bad("velocity".into(), p))?;
        finite3(&self.angular_velocity).map_err(|p| bad("angular_velocity".into(), p))?;
        check_rotation(&self.rotation).map_err(|p| bad("rotation".into(), p))?;
        positive(self.tolerance).map_err(|p| bad("tolerance".into(), p))?;
        let base = match self.base {
            BaseDesc::Fixed => BaseKind::Fixed,
            BaseDesc::Floating => BaseKind::Floating,
        };
        let placement = Pose::new(rotation(&self.rotation), DVec3::from_array(self.position));
        let mut parts = match &self.urdf {
            Some(u) => urdf::parts(u, base_dir).map_err(|(f, p)| bad(f, p))?,
            None => Parts {
                root: self.links[0].name.clone(),
                ..Parts::default()
            },
        };
        for (k, l) in self.links.iter().enumerate() {
            let field = |f: &str| format!("links[{k}] \"{}\".{f}", l.name);
            let (inertia, shape) = link_mass(l, base_dir).map_err(|(f, p)| bad(field(&f), p))?;
            parts.links.push(PartLink {
                name: l.name.clone(),
                inertia,
                shape,
                material: l.material.clone(),
            });
        }
        for (k, j) in self.joints.iter().enumerate() {
            let field = |f: &str| format!("joints[{k}] \"{}\".{f}", j.name);
            parts
                .joints
                .push(inline_joint(j).map_err(|(f, p)| bad(field(f), p))?);
        }
        let mut b = ModelBuilder::new(base);
        b.gravity(gravity);
        let mut shapes = Vec::new();
        for l in parts.links {
            b.link(&l.name, l.inertia);
            if let Some(mut s) = l.shape {
                if base == BaseKind::Fixed && l.name == parts.root {
                    // A fixed root's link frame is the world's (the placement is folded
                    // into its joints below), so its shape is placed here.
                    s = place(&s, placement);
                }
                shapes.push(LinkShape {
                    link: l.name,
                    shape: s,
                    material: l.material,
                });
            }
        }
        let mut q_joints = Vec::new();
        let mut v_joints = Vec::new();
        for mut j in parts.joints {
            if base == BaseKind::Fixed && j.spec.parent == parts.root {
                // A fixed root's frame is the multibody's placement in the world.
                j.spec.origin = placement * j.spec.origin;
            }
            if !matches!(j.spec.joint_type, JointType::Fixed) {
                q_joints.push((j.spec.name.clone(), j.q));
                v_joints.push(j.qd);
            }
            b.joint(j.spec);
        }
        let model = b.build().map_err(|e| bad("joints".into(), e.to_string()))?;
        // Joint coordinates in the model's order (depth first from the root).
        let mut q = model.neutral_configuration();
        let mut v = vec![0.0; model.nv()];
        let (qo, vo) = (model.nq() - model.joint_count(), model.base_dofs());
        for ((name, qj), vj) in q_joints.iter().zip(&v_joints) {
            let i = model.joint_index(name).ok_or_else(|| {
                bad(
                    format!("joints \"{name}\""),
                    "not a moving joint of the model".into(),
                )
            })?;
            q[qo + i] = *qj;
            v[vo + i] = *vj;
        }
        if base == BaseKind::Floating {
            let r = placement.rotation;
            q[..3].copy_from_slice(&self.position);
            q[3..7].copy_from_slice(&[r.x, r.y, r.z, r.w]);
            // The base twist in base coordinates: velocity of the base origin, ω.
            let inv = r.inverse();
            let vb = inv * DVec3::from_array(self.velocity);
            let wb = inv * DVec3::from_array(self.angular_velocity);
            v[..6].copy_from_slice(&[vb.x, vb.y, vb.z, wb.x, wb.y, wb.z]);
        }
        let integrator = Integrator::AdaptiveRk4(AdaptiveRk4 {
            rel_tol: self.tolerance,
            ..AdaptiveRk4::default()
        });
        let mut sim = Simulation::new(model, q, v, integrator)
            .map_err(|e| bad("state".into(), e.to_string()))?;
        for (k, c) in self.controllers.iter().enumerate() {
            let field = format!("controllers[{k}]");
            let (joint, rate) = match c {
                ControllerDesc::Pd { joint, rate, .. }
                | ControllerDesc::Pid { joint, rate, .. } => (joint, *rate),
            };
            positive(rate).map_err(|p| bad(format!("{field}.rate"), p))?;
            let index = sim.model().joint_index(joint).ok_or_else(|| {
                bad(
                    format!("{field}.joint"),
                    format!("\"{joint}\" is not a moving joint of the multibody"),
                )
            })?;
            let ctrl: Box<dyn impulse_multibody::Controller> = match c {
                ControllerDesc::Pd {
                    kp,
                    kv,
                    target,
                    target_rate,
                    ..
                } => {
                    let mut pd = JointPd::new(index, *kp, *kv, 1.0 / rate);
                    pd.q_des = *target;
                    pd.qd_des = *target_rate;
                    Box::new(pd)
                }
                ControllerDesc::Pid {
                    kp, kv, ki, target, ..
                } => {
                    let mut pid = JointPid::new(index, *kp, *kv, *ki, 1.0 / rate);
                    pid.pd.q_des = *target;
                    Box::new(pid)
                }
            };
            sim.add_controller(ctrl)
                .map_err(|e| bad(field.clone(), e.to_string()))?;
        }
        Ok((sim, shapes))
    }
}

/// A joint controller's velocity loop updated every T seconds with zero-order hold is unstable
/// when `k_v·T / M_jj ≥ 2` (M_jj the joint's effective inertia, the diagonal of the joint-space
/// mass matrix): each update overcorrects the rate by more than its error. Warned at this
/// fraction of that limit. Default `0.5`.
pub const CONTROL_STABILITY_WARN: f64 = 0.5;

impl MultibodyDesc {
    /// Warnings about a multibody that builds but may misbehave: a controller whose
    /// velocity gain, at its rate, is near or past the stability limit of a zero-order-held
    /// loop on its joint's effective inertia at the initial pose (thesis §5.4: controllers at
    /// finite rates). Nothing for a multibody that does not build (its error says why).
    /// `base_dir` resolves a URDF path, as [`MultibodyDesc::build`] does.
    #[must_use]
    pub fn warnings(&self, gravity: DVec3, base_dir: &Path) -> Vec<String> {
        let Ok((sim, _)) = self.build(gravity, base_dir) else {
            return Vec::new();
        };
        let model = sim.model();
        let n = model.nv();
        let mut m = impulse_multibody::Mat::<f64>::zeros(n, n);
        let mut ws = impulse_multibody::Workspace::new(model);
        if impulse_multibody::mass_matrix(model, &mut ws, sim.q(), &mut m).is_err() {
            return Vec::new();
        }
        let vo = model.base_dofs();
        let mut out = Vec::new();
        for c in &self.controllers {
            let (joint, kv, rate) = match c {
                ControllerDesc::Pd {
                    joint, kv, rate, ..
                }
                | ControllerDesc::Pid {
                    joint, kv, rate, ..
                } => (joint, *kv, *rate),
            };
            let Some(j) = model.joint_index(joint) else {
                continue;
            };
            let inertia = m[(vo + j, vo + j)];
            let ratio = kv / rate / inertia;
            if ratio >= 2.0 * CONTROL_STABILITY_WARN {
                out.push(format!(
                    "multibody \"{}\", controller on joint \"{joint}\": k_v/rate/M = {kv}/{rate}/{inertia:.3e} = {ratio:.2} ({}; a zero-order-held velocity loop is unstable from 2): raise its rate or lower k_v",
                    self.name,
                    if ratio >= 2.0 { "unstable" } else { "near the limit" }
                ));
            }
        }
        out
    }
}

/// The links and joints a multibody's model is built from, from its URDF file and inline.
#[derive(Default)]
struct Parts {
    links: Vec<PartLink>,
    joints: Vec<PartJoint>,
    /// The root link's name.
    root: String,
}

/// A link as the model and the world receive it.
struct PartLink {
    name: String,
    /// Spatial inertia in the link frame.
    inertia: SpatialInertia,
    /// Collision shape in the link frame.
    shape: Option<ShapeDesc>,
    material: String,
}

/// A joint as the model receives it, with its initial state.
struct PartJoint {
    spec: JointSpec,
    q: f64,
    qd: f64,
}

/// An inline joint's spec and initial state; `(field, problem)` on error.
fn inline_joint(j: &JointDesc) -> Result<PartJoint, (&'static str, String)> {
    finite3(&j.position).map_err(|p| ("position", p))?;
    check_rotation(&j.rotation).map_err(|p| ("rotation", p))?;
    finite3(&j.axis).map_err(|p| ("axis", p))?;
    for (f, x) in [
        ("q", j.q),
        ("qd", j.qd),
        ("damping", j.damping),
        ("friction", j.friction),
    ] {
        if !x.is_finite() {
            return Err((f, format!("{x} is not finite")));
        }
    }
    let origin = Pose::new(rotation(&j.rotation), DVec3::from_array(j.position));
    let axis = DVec3::from_array(j.axis);
    let mut spec = match j.kind {
        JointKindDesc::Revolute => JointSpec::revolute(&j.name, &j.parent, &j.child, origin, axis),
        JointKindDesc::Prismatic => {
            JointSpec::prismatic(&j.name, &j.parent, &j.child, origin, axis)
        }
        JointKindDesc::Fixed => JointSpec::fixed(&j.name, &j.parent, &j.child, origin),
    };
    let (stiffness, rest) = j.spring.unwrap_or((0.0, 0.0));
    if !(stiffness.is_finite() && rest.is_finite()) {
        return Err(("spring", format!("({stiffness}, {rest}) is not finite")));
    }
    spec = spec.with_passive(JointPassive {
        stiffness,
        rest,
        damping: j.damping,
        friction: j.friction,
        ..JointPassive::default()
    });
    if let Some(lim) = j.limit {
        spec = spec.with_limit(JointLimit::new(lim.lower, lim.upper, lim.restitution));
    }
    Ok(PartJoint {
        spec,
        q: j.q,
        qd: j.qd,
    })
}

/// A compound's parts moved by `pose` (other shapes are returned as they are: a link's
/// placed shape is always a compound).
fn place(s: &ShapeDesc, pose: Pose) -> ShapeDesc {
    match s {
        ShapeDesc::Compound { parts } => ShapeDesc::Compound {
            parts: parts
                .iter()
                .map(|p| {
                    let at = pose * Pose::new(rotation(&p.rotation), DVec3::from_array(p.position));
                    let r: DQuat = at.rotation;
                    super::PartDesc {
                        shape: p.shape.clone(),
                        position: at.translation.to_array(),
                        rotation: RotationDesc::Quaternion(r.x, r.y, r.z, r.w),
                    }
                })
                .collect(),
        },
        other => other.clone(),
    }
}

/// A link's spatial inertia (link frame) and collision shape (link frame), from its shape and
/// mass or its explicit inertia; `(field, problem)` on error.
fn link_mass(
    l: &LinkDesc,
    base_dir: &Path,
) -> Result<(SpatialInertia, Option<ShapeDesc>), (String, String)> {
    if l.name.is_empty() {
        return Err(("name".into(), "is empty".into()));
    }
    finite3(&l.position).map_err(|p| ("position".into(), p))?;
    check_rotation(&l.rotation).map_err(|p| ("rotation".into(), p))?;
    let placed = l.shape.as_ref().map(|s| {
        let moved = |shape: &ShapeDesc| super::PartDesc {
            shape: shape.clone(),
            position: l.position,
            rotation: l.rotation,
        };
        match s {
            ShapeDesc::Compound { .. } => place(
                s,
                Pose::new(rotation(&l.rotation), DVec3::from_array(l.position)),
            ),
            other => ShapeDesc::Compound {
                parts: vec![moved(other)],
            },
        }
    });
    if let Some(s) = &placed {
        check_shape(s, true).map_err(|(f, p)| (format!("shape.{f}"), p))?;
    }
    let inertia = match (&l.inertia, &placed) {
        (Some(i), _) => {
            positive(i.mass).map_err(|p| ("inertia.mass".to_string(), p))?;
            finite3(&i.com).map_err(|p| ("inertia.com".to_string(), p))?;
            for m in i.moments {
                positive(m).map_err(|p| ("inertia.moments".to_string(), p))?;
            }
            SpatialInertia::new(
                i.mass,
                DVec3::from_array(i.com),
                DMat3::from_diagonal(DVec3::from_array(i.moments)),
            )
        }
        (None, Some(s)) => {
            let mp = crate::build::mass_properties(s, base_dir).map_err(|p| ("shape".into(), p))?;
            let scale = match l.mass {
                None => crate::build::DEFAULT_DENSITY,
                Some(MassDesc::Density(d)) => {
                    positive(d).map_err(|p| ("mass.Density".to_string(), p))?;
                    d
                }
                Some(MassDesc::Mass(m)) => {
                    positive(m).map_err(|p| ("mass.Mass".to_string(), p))?;
                    m / mp.mass
                }
            };
            SpatialInertia::new(mp.mass * scale, mp.com, mp.inertia * scale)
        }
        (None, None) => {
            if l.mass.is_some() {
                return Err((
                    "mass".into(),
                    "a link without a shape takes its mass from `inertia`".into(),
                ));
            }
            SpatialInertia::ZERO
        }
    };
    Ok((inertia, placed))
}

/// Where in a multibody description of a scene's RON text a parse error was found.
#[derive(Debug, PartialEq, Eq)]
pub(crate) struct MultibodyAt {
    /// The multibody's name.
    pub name: String,
    /// The field of its own whose value the error is in (`None` when it is not in one: a
    /// misspelt field's name).
    pub field: Option<String>,
}

/// The multibody description, `Multibody(…)`, of a scene's RON `text` that encloses
/// 1-based `line` and `col` (characters), where a parse error was found, so that the error
/// names it: `None` outside any, or for a multibody without a `name`. A small scan of RON's
/// brackets, strings and comments.
pub(crate) fn enclosing_multibody(text: &str, line: usize, col: usize) -> Option<MultibodyAt> {
    let at = text
        .split_inclusive('\n')
        .take(line.saturating_sub(1))
        .map(str::len)
        .sum::<usize>()
        + text
            .split_inclusive('\n')
            .nth(line.saturating_sub(1))
            .map_or(0, |l| {
                l.char_indices()
                    .nth(col.saturating_sub(1))
                    .map_or(l.len(), |(i, _)| i)
            });
    // Open brackets: whether each opens a `Multibody(`, and where its contents start.
    let mut open: Vec<Option<usize>> = Vec::new();
    scan(text, |i, token| {
        if i >= at {
            return false;
        }
        match token {
            Token::Open(ident) => open.push((ident == "Multibody").then_some(i + 1)),
            Token::Close => {
                open.pop();
            }
            Token::Other(_) | Token::Str(_) => {}
        }
        true
    });
    // The innermost open one where the scan stopped (at the error, or at the end of a text
    // that ends inside it).
    let start = open.iter().rev().find_map(|o| *o)?;
    // Its `name: "…"` and the field the error is in, among its own fields (depth 0 here).
    let (mut depth, mut name, mut field) = (0usize, None, None);
    let mut key: (&str, bool) = ("", false);
    scan(&text[start..], |i, token| {
        match token {
            Token::Open(_) => depth += 1,
            Token::Close if depth == 0 => return false,
            Token::Close => depth -= 1,
            Token::Other(":") if depth == 0 && !key.0.is_empty() => {
                key.1 = true;
                if start + i < at {
                    field = Some(key.0.to_owned());
                }
            }
            // A field's value ends at the next comma of its level.
            Token::Other(",") if depth == 0 && start + i < at => {
                field = None;
                key = ("", false);
            }
            Token::Str(s) if depth == 0 && key == ("name", true) => name = Some(s.to_owned()),
            Token::Other(t) if t.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_') => {
                key = (t, false);
            }
            Token::Other(_) | Token::Str(_) => key = ("", false),
        }
        true
    });
    Some(MultibodyAt { name: name?, field })
}

/// A token of [`scan`].
enum Token<'a> {
    /// `(`, `[` or `{`, with the identifier just before it (or "").
    Open(&'a str),
    /// `)`, `]` or `}`.
    Close,
    /// A string's contents (escapes left as written).
    Str(&'a str),
    /// An identifier, a number or another character.
    Other(&'a str),
}

/// Calls `f` with the byte offset and token of each token of RON `text` (comments skipped)
/// while it returns `true`.
fn scan<'a>(text: &'a str, mut f: impl FnMut(usize, Token<'a>) -> bool) {
    let bytes = text.as_bytes();
    let (mut i, mut ident): (usize, &str) = (0, "");
    while i < bytes.len() {
        let c = bytes[i];
        let token_start = i;
        let token = match c {
            b'/' if bytes.get(i + 1) == Some(&b'/') => {
                i = text[i..].find('\n').map_or(bytes.len(), |n| i + n);
                continue;
            }
            b'/' if bytes.get(i + 1) == Some(&b'*') => {
                i = text[i + 2..]
                    .find("*/")
                    .map_or(bytes.len(), |n| i + 2 + n + 2);
                continue;
            }
            b'"' => {
                let mut j = i + 1;
                while j < bytes.len() && bytes[j] != b'"' {
                    j += if bytes[j] == b'\\' { 2 } else { 1 };
                }
                let s = &text[i + 1..j.min(bytes.len())];
                i = j + 1;
                Token::Str(s)
            }
            b'(' | b'[' | b'{' => {
                i += 1;
                Token::Open(std::mem::take(&mut ident))
            }
            b')' | b']' | b'}' => {
                i += 1;
                Token::Close
            }
            c if c.is_ascii_whitespace() => {
                i += 1;
                continue;
            }
            c if c.is_ascii_alphanumeric() || c == b'_' => {
                let mut j = i;
                while j < bytes.len() && (bytes[j].is_ascii_alphanumeric() || bytes[j] == b'_') {
                    j += 1;
                }
                i = j;
                ident = &text[token_start..j];
                if !f(token_start, Token::Other(ident)) {
                    return;
                }
                continue;
            }
            _ => {
                let len = text[i..].chars().next().map_or(1, char::len_utf8);
                i += len;
                Token::Other(&text[token_start..i])
            }
        };
        if !matches!(token, Token::Open(_)) {
            ident = "";
        }
        if !f(token_start, token) {
            return;
        }
    }
}

#[cfg(test)]
mod tests;
