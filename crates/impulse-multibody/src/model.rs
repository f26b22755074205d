//! The articulated-body description: links, joints, base, passive joint elements, gravity.

use glam::{DMat3, DQuat, DVec3};
use impulse_geom::{Pose, SpatialInertia};

use crate::error::MultibodyError;
use crate::limit::JointLimit;
use crate::spatial::{Sym6, Xform};
use crate::tol::{AXIS_MIN_NORM, INERTIA_PD_REL, INERTIA_SYMMETRY_REL};

/// How the root link is attached to the world.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Default)]
pub enum BaseKind {
    /// The root link is the ground: it does not move and its inertia is ignored.
    #[default]
    Fixed,
    /// The root link floats freely (6 DOF; thesis §4.6).
    Floating,
}

/// The motion a joint allows between its parent and child link.
///
/// The axis is given in the joint frame, which is also the child link's frame (URDF
/// convention); it need not be unit length (it is normalised) but must not be zero.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum JointType {
    /// Rotation by `q` (rad) about `axis` through the child frame's origin.
    Revolute {
        /// Joint axis in the child (= joint) frame.
        axis: DVec3,
    },
    /// Translation by `q` (m) along `axis`.
    Prismatic {
        /// Joint axis in the child (= joint) frame.
        axis: DVec3,
    },
    /// No relative motion: the child is merged into its parent's rigid body.
    Fixed,
}

/// Passive elements acting at one joint, evaluated inside every derivative evaluation of the
/// integrator (thesis §5.4.1) and added to the joint force. The force (N, or N·m for revolute
/// joints) is the sum of
/// - constant (Coulomb) friction `−μ sgn(q̇)`, with sgn(0) = 0;
/// - viscous damping `−ρ q̇`;
/// - a linear spring `−k (q − q_n)`;
/// - a "hard spring" `−c / (q − q_h)` (sealed prismatic cylinder, \[Rai86\]); with c > 0 it pulls
///   towards `q_h`, with c < 0 it pushes away. Its singularity is guarded: `|q − q_h|` is
///   clamped from below to `hard_spring_min_gap` (sign kept, 0 counts as positive).
#[derive(Copy, Clone, Debug, PartialEq, Default)]
pub struct JointPassive {
    /// Spring constant k ≥ 0 (N/m or N·m/rad).
    pub stiffness: f64,
    /// Spring rest position q_n (m or rad).
    pub rest: f64,
    /// Viscous damping ρ ≥ 0 (N·s/m or N·m·s/rad).
    pub damping: f64,
    /// Constant friction magnitude μ ≥ 0 (N or N·m).
    pub friction: f64,
    /// Hard-spring constant c (N·m or N·m·rad); 0 disables it.
    pub hard_spring: f64,
    /// Hard-spring singular position q_h (m or rad).
    pub hard_spring_rest: f64,
    /// Smallest |q − q_h| used in the hard-spring law (m or rad); must be > 0 when c ≠ 0.
    pub hard_spring_min_gap: f64,
}

impl JointPassive {
    /// A linear spring of stiffness `k` with rest position `rest`.
    #[must_use]
    pub fn spring(k: f64, rest: f64) -> Self {
        JointPassive {
            stiffness: k,
            rest,
            ..Default::default()
        }
    }

    /// A viscous damper of coefficient `rho`.
    #[must_use]
    pub fn damper(rho: f64) -> Self {
        JointPassive {
            damping: rho,
            ..Default::default()
        }
    }

    /// `true` when every element is zero (the joint is passive-free).
    #[must_use]
    pub fn is_zero(&self) -> bool {
        self.stiffness == 0.0
            && self.damping == 0.0
            && self.friction == 0.0
            && self.hard_spring == 0.0
    }

    /// The passive joint force at position `q` and velocity `qd` (thesis §5.4.1).
    #[must_use]
    pub fn force(&self, q: f64, qd: f64) -> f64 {
        let mut f = 0.0;
        if self.friction != 0.0 && qd != 0.0 {
            f -= self.friction * qd.signum();
        }
        f -= self.damping * qd;
        f -= self.stiffness * (q - self.rest);
        if self.hard_spring != 0.0 {
            let gap = q - self.hard_spring_rest;
            let g = if gap < 0.0 {
                gap.min(-self.hard_spring_min_gap)
            } else {
                gap.max(self.hard_spring_min_gap)
            };
            f -= self.hard_spring / g;
        }
        f
    }

    fn validate(&self, joint: &str) -> Result<(), MultibodyError> {
        let bad = |reason: String| {
            Err(MultibodyError::InvalidJoint {
                joint: joint.to_owned(),
                reason,
            })
        };
        let named = [
            ("stiffness", self.stiffness),
            ("damping", self.damping),
            ("friction", self.friction),
        ];
        for (name, v) in named {
            if !(v.is_finite() && v >= 0.0) {
                return bad(format!("{name} = {v} must be finite and >= 0"));
            }
        }
        for (name, v) in [
            ("spring rest", self.rest),
            ("hard spring", self.hard_spring),
            ("hard spring rest", self.hard_spring_rest),
        ] {
            if !v.is_finite() {
                return bad(format!("{name} = {v} must be finite"));
            }
        }
        if self.hard_spring != 0.0
            && !(self.hard_spring_min_gap.is_finite() && self.hard_spring_min_gap > 0.0)
        {
            return bad(format!(
                "hard spring min gap = {} must be finite and > 0",
                self.hard_spring_min_gap
            ));
        }
        Ok(())
    }
}

/// One joint of a [`ModelBuilder`]: it attaches `child` to `parent`.
///
/// `origin` places the joint frame (= the child link's frame at q = 0) in the parent link's
/// frame, as URDF's `<origin>`. At position q the child frame is `origin · Rot(axis, q)`
/// (revolute) or `origin · Trans(axis·q)` (prismatic).
#[derive(Clone, Debug, PartialEq)]
pub struct JointSpec {
    /// Unique joint name.
    pub name: String,
    /// Parent link name.
    pub parent: String,
    /// Child link name.
    pub child: String,
    /// Joint frame in the parent link's frame.
    pub origin: Pose,
    /// Kind and axis.
    pub joint_type: JointType,
    /// Springs, dampers and friction at this joint.
    pub passive: JointPassive,
    /// Travel limits as impulsive stops (revolute and prismatic joints only).
    pub limit: Option<JointLimit>,
}

impl JointSpec {
    fn new(name: &str, parent: &str, child: &str, origin: Pose, joint_type: JointType) -> Self {
        JointSpec {
            name: name.to_owned(),
            parent: parent.to_owned(),
            child: child.to_owned(),
            origin,
            joint_type,
            passive: JointPassive::default(),
            limit: None,
        }
    }

    /// A revolute joint about `axis` (child frame).
    #[must_use]
    pub fn revolute(name: &str, parent: &str, child: &str, origin: Pose, axis: DVec3) -> Self {
        Self::new(name, parent, child, origin, JointType::Revolute { axis })
    }

    /// A prismatic joint along `axis` (child frame).
    #[must_use]
    pub fn prismatic(name: &str, parent: &str, child: &str, origin: Pose, axis: DVec3) -> Self {
        Self::new(name, parent, child, origin, JointType::Prismatic { axis })
    }

    /// A fixed joint (the child is welded to the parent).
    #[must_use]
    pub fn fixed(name: &str, parent: &str, child: &str, origin: Pose) -> Self {
        Self::new(name, parent, child, origin, JointType::Fixed)
    }

    /// The same joint with passive elements.
    #[must_use]
    pub fn with_passive(mut self, passive: JointPassive) -> Self {
        self.passive = passive;
        self
    }

    /// The same joint with travel limits ([`JointLimit`]: impulsive stops).
    #[must_use]
    pub fn with_limit(mut self, limit: JointLimit) -> Self {
        self.limit = Some(limit);
        self
    }
}

/// Collects links and joints, then validates them into a [`Model`].
#[derive(Clone, Debug, Default)]
pub struct ModelBuilder {
    base: BaseKind,
    gravity: DVec3,
    links: Vec<(String, SpatialInertia)>,
    joints: Vec<JointSpec>,
}

/// Identifies a link of a [`Model`] (its index in the order links were added).
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct LinkId(pub(crate) usize);

impl LinkId {
    /// The link's index in the order links were added to the builder (URDF: file order).
    #[must_use]
    pub fn index(self) -> usize {
        self.0
    }
}

/// Standard gravity (m/s²) along −z, the builder's default.
pub(crate) const STANDARD_GRAVITY: DVec3 = DVec3::new(0.0, 0.0, -9.81);

impl ModelBuilder {
    /// An empty model with the given base and gravity `(0, 0, −9.81)` m/s².
    #[must_use]
    pub fn new(base: BaseKind) -> Self {
        ModelBuilder {
            base,
            gravity: STANDARD_GRAVITY,
            links: Vec::new(),
            joints: Vec::new(),
        }
    }

    /// Sets the world-frame gravity vector (m/s²).
    pub fn gravity(&mut self, g: DVec3) -> &mut Self {
        self.gravity = g;
        self
    }

    /// Adds a link with its inertia expressed in the link's own frame.
    pub fn link(&mut self, name: &str, inertia: SpatialInertia) -> &mut Self {
        self.links.push((name.to_owned(), inertia));
        self
    }

    /// Adds a joint.
    pub fn joint(&mut self, joint: JointSpec) -> &mut Self {
        self.joints.push(joint);
        self
    }

    /// Validates the links and joints and builds the model.
    ///
    /// Moving bodies (a link together with every link welded to it by fixed joints) are
    /// numbered in depth-first pre-order from the root (thesis Fig. 4.10), children in the
    /// order their joints were added.
    ///
    /// # Errors
    /// A [`MultibodyError`] naming the offending link or joint: duplicate names, unknown
    /// links, a link with two parents, loops, several or no roots, non-finite data, a zero
    /// axis, negative passive constants, negative mass, a non-symmetric or indefinite inertia,
    /// or a moving body without positive mass and positive definite inertia (its articulated
    /// inertia could be singular).
    pub fn build(&self) -> Result<Model, MultibodyError> {
        build(self)
    }
}

/// The joint of a moving body (internal).
#[derive(Copy, Clone, Debug, PartialEq)]
pub(crate) enum BodyJoint {
    /// The floating base (6 DOF).
    Floating,
    /// Revolute about a unit axis in the body frame.
    Revolute(DVec3),
    /// Prismatic along a unit axis in the body frame.
    Prismatic(DVec3),
}

/// A moving rigid body: one link plus every link welded to it (internal).
#[derive(Clone, Debug)]
pub(crate) struct Body {
    /// Parent body, `None` for the ground (fixed base) or the floating base itself.
    pub parent: Option<usize>,
    pub joint: BodyJoint,
    /// Joint frame (= body frame at q = 0) in the parent body's frame.
    pub origin: Xform,
    /// `origin.r · axis`, the prismatic translation direction in the parent frame.
    pub axis_in_parent: DVec3,
    /// Inertia in the body frame (own link plus welded links).
    pub inertia: SpatialInertia,
    /// The same as a 6×6 matrix.
    pub inertia6: Sym6,
}

/// Where a link lives (internal): on which moving body, at which offset.
#[derive(Clone, Debug)]
pub(crate) struct LinkInfo {
    pub name: String,
    /// The moving body, `None` for links welded to the ground.
    pub body: Option<usize>,
    /// Link frame in the body frame (body ← link).
    pub offset: Xform,
}

/// A validated multibody: a tree of moving rigid bodies with 1-DOF joints on a fixed or
/// floating base. Build it with [`ModelBuilder`] or [`crate::urdf`]; it does not change
/// afterwards except for gravity and the passive elements.
#[derive(Clone, Debug)]
pub struct Model {
    pub(crate) base: BaseKind,
    pub(crate) gravity: DVec3,
    pub(crate) bodies: Vec<Body>,
    pub(crate) links: Vec<LinkInfo>,
    /// Names of the moving joints in coordinate order.
    pub(crate) joint_names: Vec<String>,
    /// Passive elements per joint coordinate.
    pub(crate) passive: Vec<JointPassive>,
    /// Travel limits per joint coordinate.
    pub(crate) limits: Vec<Option<JointLimit>>,
    /// Name of the first link of each moving body.
    pub(crate) body_names: Vec<String>,
}

impl Model {
    /// The base kind.
    #[must_use]
    pub fn base(&self) -> BaseKind {
        self.base
    }

    /// `true` for a floating base.
    #[must_use]
    pub fn is_floating(&self) -> bool {
        self.base == BaseKind::Floating
    }

    /// Number of moving 1-DOF joints (revolute and prismatic).
    #[must_use]
    pub fn joint_count(&self) -> usize {
        self.joint_names.len()
    }

    /// Length of the configuration vector `q`: joints, plus 7 for a floating base.
    #[must_use]
    pub fn nq(&self) -> usize {
        self.joint_count() + if self.is_floating() { 7 } else { 0 }
    }

    /// Length of the velocity, acceleration and force vectors: joints, plus 6 for a floating
    /// base.
    #[must_use]
    pub fn nv(&self) -> usize {
        self.joint_count() + self.base_dofs()
    }

    /// Number of leading entries of `v` and `τ` that belong to the base (6 or 0).
    #[must_use]
    pub fn base_dofs(&self) -> usize {
        if self.is_floating() { 6 } else { 0 }
    }

    /// Number of moving rigid bodies (a link plus the links welded to it counts once).
    #[must_use]
    pub fn body_count(&self) -> usize {
        self.bodies.len()
    }

    /// Names of the moving joints in coordinate order (depth-first pre-order from the root).
    #[must_use]
    pub fn joint_names(&self) -> &[String] {
        &self.joint_names
    }

    /// World-frame gravity (m/s²).
    #[must_use]
    pub fn gravity(&self) -> DVec3 {
        self.gravity
    }

    /// Sets the world-frame gravity (m/s²).
    pub fn set_gravity(&mut self, g: DVec3) {
        self.gravity = g;
    }

    /// Passive elements of joint `j` (coordinate order).
    #[must_use]
    pub fn passive(&self, j: usize) -> Option<&JointPassive> {
        self.passive.get(j)
    }

    /// Replaces the passive elements of joint `j` (the thesis's installSpring /
    /// installDamper).
    ///
    /// # Errors
    /// [`MultibodyError::UnknownName`] for a bad index, [`MultibodyError::InvalidJoint`] for
    /// negative or non-finite constants.
    pub fn set_passive(&mut self, j: usize, p: JointPassive) -> Result<(), MultibodyError> {
        let Some(name) = self.joint_names.get(j) else {
            return Err(MultibodyError::UnknownName {
                kind: "joint",
                name: j.to_string(),
            });
        };
        p.validate(name)?;
        self.passive[j] = p;
        Ok(())
    }

    /// Travel limits of joint `j` (coordinate order), if it has any.
    #[must_use]
    pub fn limit(&self, j: usize) -> Option<&JointLimit> {
        self.limits.get(j).and_then(Option::as_ref)
    }

    /// Whether any joint has travel limits.
    #[must_use]
    pub fn has_limits(&self) -> bool {
        self.limits.iter().any(Option::is_some)
    }

    /// Index of the named joint in coordinate order (`None` for fixed or unknown joints).
    #[must_use]
    pub fn joint_index(&self, name: &str) -> Option<usize> {
        self.joint_names.iter().position(|n| n == name)
    }

    /// The named link.
    #[must_use]
    pub fn link_id(&self, name: &str) -> Option<LinkId> {
        self.links.iter().position(|l| l.name == name).map(LinkId)
    }

    /// Number of links (including the ground and welded links).
    #[must_use]
    pub fn link_count(&self) -> usize {
        self.links.len()
    }

    /// A link's name.
    #[must_use]
    pub fn link_name(&self, id: LinkId) -> Option<&str> {
        self.links.get(id.0).map(|l| l.name.as_str())
    }

    /// Total mass of the moving bodies (kg).
    #[must_use]
    pub fn total_mass(&self) -> f64 {
        self.bodies.iter().map(|b| b.inertia.mass).sum()
    }

    /// Inertia of moving body `body` in its own frame.
    pub(crate) fn body_name(&self, body: usize) -> &str {
        &self.body_names[body]
    }

    /// Index of the first joint body (1 with a floating base, else 0).
    pub(crate) fn first_joint_body(&self) -> usize {
        usize::from(self.is_floating())
    }

    /// The neutral configuration: all joints at 0, a floating base at the origin with the
    /// identity orientation.
    #[must_use]
    pub fn neutral_configuration(&self) -> Vec<f64> {
        let mut q = vec![0.0; self.nq()];
        if self.is_floating() {
            q[6] = 1.0;
        }
        q
    }

    /// Sum of the passive joint forces at `(q, v)` into `tau` (length nv; the base entries are
    /// left unchanged).
    ///
    /// # Errors
    /// [`MultibodyError::DimensionMismatch`] for wrong lengths.
    pub fn add_passive_forces(
        &self,
        q: &[f64],
        v: &[f64],
        tau: &mut [f64],
    ) -> Result<(), MultibodyError> {
        check_len("q", self.nq(), q.len())?;
        check_len("v", self.nv(), v.len())?;
        check_len("tau", self.nv(), tau.len())?;
        let (qo, vo) = (self.nq() - self.joint_count(), self.base_dofs());
        for (j, p) in self.passive.iter().enumerate() {
            if !p.is_zero() {
                tau[vo + j] += p.force(q[qo + j], v[vo + j]);
            }
        }
        Ok(())
    }
}

pub(crate) fn check_len(
    what: &'static str,
    expected: usize,
    got: usize,
) -> Result<(), MultibodyError> {
    if expected == got {
        Ok(())
    } else {
        Err(MultibodyError::DimensionMismatch {
            what,
            expected,
            got,
        })
    }
}

fn validate_inertia(link: &str, i: &SpatialInertia) -> Result<(), MultibodyError> {
    let bad = |reason: String| {
        Err(MultibodyError::InvalidInertia {
            link: link.to_owned(),
            reason,
        })
    };
    if !i.mass.is_finite() || i.mass < 0.0 {
        return bad(format!("mass = {} must be finite and >= 0", i.mass));
    }
    if !i.com.is_finite() {
        return bad("centre of mass is not finite".to_owned());
    }
    let m = i.inertia_com;
    if !m.is_finite() {
        return bad("inertia tensor is not finite".to_owned());
    }
    let scale = (0..3).fold(0.0f64, |s, c| s.max(m.col(c).abs().max_element()));
    let asym = (0..3).fold(0.0f64, |s, c| {
        s.max((m.col(c) - m.row(c)).abs().max_element())
    });
    if asym > INERTIA_SYMMETRY_REL * scale {
        return bad(format!(
            "inertia tensor is not symmetric (asymmetry {asym:e})"
        ));
    }
    // Positive semi-definite: smallest eigenvalue ≥ −tol·largest (checked by eigenvalues).
    let (lo, hi) = sym3_eigen_range(&m);
    if lo < -INERTIA_PD_REL * hi.max(0.0) {
        return bad(format!(
            "inertia tensor is not positive semi-definite (eigenvalue {lo:e})"
        ));
    }
    Ok(())
}

/// Smallest and largest eigenvalue of a symmetric 3×3 matrix (closed form, Smith 1961).
fn sym3_eigen_range(m: &DMat3) -> (f64, f64) {
    let (a00, a11, a22) = (m.x_axis.x, m.y_axis.y, m.z_axis.z);
    let (a01, a02, a12) = (
        0.5 * (m.y_axis.x + m.x_axis.y),
        0.5 * (m.z_axis.x + m.x_axis.z),
        0.5 * (m.z_axis.y + m.y_axis.z),
    );
    let p1 = a01 * a01 + a02 * a02 + a12 * a12;
    let q = (a00 + a11 + a22) / 3.0;
    if p1 == 0.0 {
        let lo = a00.min(a11).min(a22);
        let hi = a00.max(a11).max(a22);
        return (lo, hi);
    }
    let p2 = (a00 - q).powi(2) + (a11 - q).powi(2) + (a22 - q).powi(2) + 2.0 * p1;
    let p = (p2 / 6.0).sqrt();
    let b = DMat3::from_cols(
        DVec3::new(a00 - q, a01, a02) / p,
        DVec3::new(a01, a11 - q, a12) / p,
        DVec3::new(a02, a12, a22 - q) / p,
    );
    let r = (b.determinant() / 2.0).clamp(-1.0, 1.0);
    let phi = r.acos() / 3.0;
    let hi = q + 2.0 * p * phi.cos();
    let lo = q + 2.0 * p * (phi + 2.0 * std::f64::consts::PI / 3.0).cos();
    (lo, hi)
}

fn build(b: &ModelBuilder) -> Result<Model, MultibodyError> {
    use std::collections::HashMap;
    if !b.gravity.is_finite() {
        return Err(MultibodyError::InvalidArgument {
            what: "gravity",
            reason: "not finite".to_owned(),
        });
    }
    // Names and per-item validation.
    let mut link_index: HashMap<&str, usize> = HashMap::new();
    for (k, (name, inertia)) in b.links.iter().enumerate() {
        if link_index.insert(name.as_str(), k).is_some() {
            return Err(MultibodyError::DuplicateName {
                kind: "link",
                name: name.clone(),
            });
        }
        validate_inertia(name, inertia)?;
    }
    if b.links.is_empty() {
        return Err(MultibodyError::NoRoot);
    }
    let mut joint_names: HashMap<&str, usize> = HashMap::new();
    let mut axes = Vec::with_capacity(b.joints.len());
    for (k, j) in b.joints.iter().enumerate() {
        if joint_names.insert(j.name.as_str(), k).is_some() {
            return Err(MultibodyError::DuplicateName {
                kind: "joint",
                name: j.name.clone(),
            });
        }
        let bad = |reason: &str| {
            Err(MultibodyError::InvalidJoint {
                joint: j.name.clone(),
                reason: reason.to_owned(),
            })
        };
        if !j.origin.is_finite() || j.origin.rotation.length() <= 0.0 {
            return bad("origin is not finite");
        }
        let axis = match j.joint_type {
            JointType::Revolute { axis } | JointType::Prismatic { axis } => {
                if !axis.is_finite() {
                    return bad("axis is not finite");
                }
                let n = axis.length();
                if n < AXIS_MIN_NORM {
                    return bad("axis is zero");
                }
                axis / n
            }
            JointType::Fixed => DVec3::ZERO,
        };
        axes.push(axis);
        j.passive.validate(&j.name)?;
        if let Some(limit) = &j.limit {
            limit.validate(&j.name, &j.joint_type)?;
        }
    }
    // Tree structure.
    let n_links = b.links.len();
    let mut parent_joint: Vec<Option<usize>> = vec![None; n_links];
    let mut children: Vec<Vec<usize>> = vec![Vec::new(); n_links];
    for (k, j) in b.joints.iter().enumerate() {
        let lookup = |name: &str| {
            link_index
                .get(name)
                .copied()
                .ok_or_else(|| MultibodyError::UnknownLink {
                    joint: j.name.clone(),
                    link: name.to_owned(),
                })
        };
        let p = lookup(&j.parent)?;
        let c = lookup(&j.child)?;
        if p == c {
            return Err(MultibodyError::Cycle {
                link: j.child.clone(),
            });
        }
        if let Some(first) = parent_joint[c] {
            return Err(MultibodyError::MultipleParents {
                link: j.child.clone(),
                first: b.joints[first].name.clone(),
                second: j.name.clone(),
            });
        }
        parent_joint[c] = Some(k);
        children[p].push(k);
    }
    let roots: Vec<usize> = (0..n_links)
        .filter(|&l| parent_joint[l].is_none())
        .collect();
    let root = match roots.as_slice() {
        [] => {
            return Err(MultibodyError::Cycle {
                link: b.links[0].0.clone(),
            });
        }
        [r] => *r,
        [a, c, ..] => {
            // A second root is either a separate tree or hangs from a loop elsewhere.
            return Err(MultibodyError::MultipleRoots {
                first: b.links[*a].0.clone(),
                second: b.links[*c].0.clone(),
            });
        }
    };

    // Depth-first pre-order traversal (Fig. 4.10), children in joint order.
    let mut links: Vec<Option<LinkInfo>> = vec![None; n_links];
    let mut bodies: Vec<Body> = Vec::new();
    let mut body_names = Vec::new();
    let mut joint_order = Vec::new();
    let mut passive = Vec::new();
    let mut limits = Vec::new();
    let root_body = match b.base {
        BaseKind::Fixed => None,
        BaseKind::Floating => {
            bodies.push(Body {
                parent: None,
                joint: BodyJoint::Floating,
                origin: Xform::IDENTITY,
                axis_in_parent: DVec3::ZERO,
                inertia: b.links[root].1,
                inertia6: Sym6::ZERO,
            });
            body_names.push(b.links[root].0.clone());
            Some(0)
        }
    };
    links[root] = Some(LinkInfo {
        name: b.links[root].0.clone(),
        body: root_body,
        offset: Xform::IDENTITY,
    });
    // Explicit stack of joints still to visit, in reverse so the first child pops first.
    let mut stack: Vec<usize> = children[root].iter().rev().copied().collect();
    while let Some(k) = stack.pop() {
        let j = &b.joints[k];
        let p = link_index[j.parent.as_str()];
        let c = link_index[j.child.as_str()];
        let parent_info = links[p].clone().expect("parent visited before child");
        let origin = parent_info.offset.compose(&Xform::from_pose(&j.origin));
        let (child_name, child_inertia) = &b.links[c];
        let info = match j.joint_type {
            JointType::Fixed => {
                if let Some(body) = parent_info.body {
                    // Weld: add the child's inertia, expressed in the body frame.
                    let moved = child_inertia.transform(&origin.to_pose());
                    let bd = &mut bodies[body];
                    bd.inertia = bd.inertia + moved;
                }
                LinkInfo {
                    name: child_name.clone(),
                    body: parent_info.body,
                    offset: origin,
                }
            }
            JointType::Revolute { .. } | JointType::Prismatic { .. } => {
                let axis = axes[k];
                let joint = if matches!(j.joint_type, JointType::Revolute { .. }) {
                    BodyJoint::Revolute(axis)
                } else {
                    BodyJoint::Prismatic(axis)
                };
                bodies.push(Body {
                    parent: parent_info.body,
                    joint,
                    origin,
                    axis_in_parent: origin.r * axis,
                    inertia: *child_inertia,
                    inertia6: Sym6::ZERO,
                });
                body_names.push(child_name.clone());
                joint_order.push(j.name.clone());
                passive.push(j.passive);
                limits.push(j.limit);
                LinkInfo {
                    name: child_name.clone(),
                    body: Some(bodies.len() - 1),
                    offset: Xform::IDENTITY,
                }
            }
        };
        links[c] = Some(info);
        stack.extend(children[c].iter().rev().copied());
    }
    // Links never reached hang from a loop (each has exactly one parent, yet no path to root).
    let mut link_infos = Vec::with_capacity(n_links);
    for (l, info) in links.into_iter().enumerate() {
        match info {
            Some(i) => link_infos.push(i),
            None => {
                return Err(MultibodyError::Cycle {
                    link: b.links[l].0.clone(),
                });
            }
        }
    }
    // Every moving body needs positive mass and a positive definite inertia.
    for (k, body) in bodies.iter_mut().enumerate() {
        let i = &body.inertia;
        let bad = |reason: String| {
            Err(MultibodyError::InvalidInertia {
                link: body_names[k].clone(),
                reason,
            })
        };
        if i.mass.is_nan() || i.mass <= 0.0 {
            return bad(format!(
                "a moving link needs mass > 0 (mass with welded links = {})",
                i.mass
            ));
        }
        let (lo, hi) = sym3_eigen_range(&i.inertia_com);
        if lo.is_nan() || lo <= INERTIA_PD_REL * hi {
            return bad(format!(
                "a moving link needs a positive definite inertia (eigenvalues {lo:e} .. {hi:e})"
            ));
        }
        body.inertia6 = Sym6::from_inertia(i);
    }
    Ok(Model {
        base: b.base,
        gravity: b.gravity,
        bodies,
        links: link_infos,
        joint_names: joint_order,
        passive,
        limits,
        body_names,
    })
}

/// A quaternion from URDF roll-pitch-yaw (fixed axes x, then y, then z): `Rz(y)·Ry(p)·Rx(r)`.
pub(crate) fn quat_from_rpy(rpy: [f64; 3]) -> DQuat {
    DQuat::from_rotation_z(rpy[2]) * DQuat::from_rotation_y(rpy[1]) * DQuat::from_rotation_x(rpy[0])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit() -> SpatialInertia {
        SpatialInertia::new(1.0, DVec3::new(0.1, 0.0, 0.0), DMat3::IDENTITY * 0.1)
    }

    fn chain(base: BaseKind) -> ModelBuilder {
        let mut b = ModelBuilder::new(base);
        b.link("base", unit())
            .link("a", unit())
            .link("b", unit())
            .joint(JointSpec::revolute(
                "j1",
                "base",
                "a",
                Pose::IDENTITY,
                DVec3::Z,
            ))
            .joint(JointSpec::prismatic(
                "j2",
                "a",
                "b",
                Pose::IDENTITY,
                DVec3::X,
            ));
        b
    }

    #[test]
    fn builds_and_counts() {
        let m = chain(BaseKind::Fixed).build().unwrap();
        assert_eq!((m.nq(), m.nv(), m.body_count()), (2, 2, 2));
        let f = chain(BaseKind::Floating).build().unwrap();
        assert_eq!((f.nq(), f.nv(), f.body_count()), (9, 8, 3));
        // State size 2n + 11 for n links with a quaternion (thesis §4.6), n = 3 here.
        assert_eq!(f.nq() + f.nv(), 2 * 3 + 11);
        assert_eq!(m.joint_names(), ["j1", "j2"]);
    }

    #[test]
    fn errors_name_the_culprit() {
        let mut b = chain(BaseKind::Fixed);
        b.joint(JointSpec::fixed("j3", "nowhere", "b", Pose::IDENTITY));
        assert_eq!(
            b.build().unwrap_err(),
            MultibodyError::UnknownLink {
                joint: "j3".into(),
                link: "nowhere".into()
            }
        );
        let mut b = chain(BaseKind::Fixed);
        b.joint(JointSpec::fixed("j3", "b", "a", Pose::IDENTITY));
        assert!(
            matches!(b.build(), Err(MultibodyError::MultipleParents { link, .. }) if link == "a")
        );
        let mut b = ModelBuilder::new(BaseKind::Fixed);
        b.link("x", unit())
            .link("y", unit())
            .link("r", unit())
            .joint(JointSpec::fixed("a", "x", "y", Pose::IDENTITY))
            .joint(JointSpec::fixed("b", "y", "x", Pose::IDENTITY));
        assert!(matches!(b.build(), Err(MultibodyError::Cycle { .. })));
        let mut b = chain(BaseKind::Fixed);
        b.link("stray", unit());
        assert!(matches!(
            b.build(),
            Err(MultibodyError::MultipleRoots { .. })
        ));
        let mut b = ModelBuilder::new(BaseKind::Fixed);
        b.link("g", unit())
            .link("a", unit())
            .joint(JointSpec::revolute(
                "j",
                "g",
                "a",
                Pose::IDENTITY,
                DVec3::ZERO,
            ));
        assert!(
            matches!(b.build(), Err(MultibodyError::InvalidJoint { joint, .. }) if joint == "j")
        );
        let mut b = ModelBuilder::new(BaseKind::Fixed);
        b.link("g", unit())
            .link("a", SpatialInertia::new(0.0, DVec3::ZERO, DMat3::IDENTITY))
            .joint(JointSpec::revolute("j", "g", "a", Pose::IDENTITY, DVec3::Z));
        assert!(
            matches!(b.build(), Err(MultibodyError::InvalidInertia { link, .. }) if link == "a")
        );
        let mut b = ModelBuilder::new(BaseKind::Fixed);
        b.link("g", unit())
            .link(
                "a",
                SpatialInertia::new(f64::NAN, DVec3::ZERO, DMat3::IDENTITY),
            )
            .joint(JointSpec::revolute("j", "g", "a", Pose::IDENTITY, DVec3::Z));
        assert!(
            matches!(b.build(), Err(MultibodyError::InvalidInertia { link, .. }) if link == "a")
        );
        let mut b = ModelBuilder::new(BaseKind::Fixed);
        let indefinite = DMat3::from_diagonal(DVec3::new(1.0, 1.0, -0.5));
        b.link("g", unit())
            .link("a", SpatialInertia::new(1.0, DVec3::ZERO, indefinite))
            .joint(JointSpec::revolute("j", "g", "a", Pose::IDENTITY, DVec3::Z));
        assert!(
            matches!(b.build(), Err(MultibodyError::InvalidInertia { link, .. }) if link == "a")
        );
        let mut b = chain(BaseKind::Fixed);
        b.link("a", unit());
        assert!(matches!(
            b.build(),
            Err(MultibodyError::DuplicateName { kind: "link", .. })
        ));
        let mut b = ModelBuilder::new(BaseKind::Fixed);
        b.link("g", unit()).link("a", unit()).joint(
            JointSpec::revolute("j", "g", "a", Pose::IDENTITY, DVec3::Z)
                .with_passive(JointPassive::damper(-1.0)),
        );
        assert!(
            matches!(b.build(), Err(MultibodyError::InvalidJoint { joint, .. }) if joint == "j")
        );
    }

    #[test]
    fn massless_links_welded_to_massive_ones_are_fine() {
        let mut b = ModelBuilder::new(BaseKind::Fixed);
        b.link("world", SpatialInertia::ZERO)
            .link("a", unit())
            .link("tool", SpatialInertia::ZERO)
            .joint(JointSpec::revolute(
                "j",
                "world",
                "a",
                Pose::IDENTITY,
                DVec3::Z,
            ))
            .joint(JointSpec::fixed(
                "t",
                "a",
                "tool",
                Pose::from_translation(DVec3::X),
            ));
        let m = b.build().unwrap();
        assert_eq!(m.body_count(), 1);
        assert_eq!(m.link_count(), 3);
    }

    #[test]
    fn eigen_range_matches_diagonal() {
        let r = DMat3::from_quat(DQuat::from_euler(glam::EulerRot::XYZ, 0.3, -0.7, 1.1));
        let m = r * DMat3::from_diagonal(DVec3::new(1.0, 2.0, 5.0)) * r.transpose();
        let (lo, hi) = sym3_eigen_range(&m);
        assert!((lo - 1.0).abs() < 1e-12 && (hi - 5.0).abs() < 1e-12);
    }

    #[test]
    fn rpy_is_fixed_axis_xyz() {
        let (r, p, y) = (0.3, -0.4, 1.2);
        let q = quat_from_rpy([r, p, y]);
        let m = DMat3::from_quat(q);
        let want =
            DMat3::from_rotation_z(y) * DMat3::from_rotation_y(p) * DMat3::from_rotation_x(r);
        for c in 0..3 {
            assert!((m.col(c) - want.col(c)).abs().max_element() < 1e-14);
        }
    }

    #[test]
    fn passive_laws() {
        let p = JointPassive {
            stiffness: 2.0,
            rest: 0.5,
            damping: 3.0,
            friction: 0.25,
            hard_spring: 0.1,
            hard_spring_rest: -1.0,
            hard_spring_min_gap: 1e-3,
        };
        let (q, qd) = (1.0, -2.0);
        let want = 0.25 - 3.0 * qd - 2.0 * (q - 0.5) - 0.1 / (q + 1.0);
        assert!((p.force(q, qd) - want).abs() < 1e-15);
        // Guarded singularity.
        assert!(p.force(-1.0, 0.0).is_finite());
        assert_eq!(JointPassive::default().force(3.0, 4.0), 0.0);
    }
}
