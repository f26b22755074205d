//! The compiled mechanism: links with rest poses and inertias, compliant joints with their
//! frames and free directions, the walk order from the base (FORK⁻¹S §3.3: a DAG that may split
//! and merge), and the end effectors.
//!
//! Coordinates: every joint j has `dof_j` coordinates θ_j (the free directions, in the joint's
//! order). The **tree joint** of a link is the first joint (in declaration order) that has it as
//! child; every other joint into a link closes a loop. Tree joints place the links; a loop joint's
//! coordinates are extra unknowns tied down by its closure constraint.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use glam::{DMat3, DQuat, DVec3};
use impulse_geom::{Pose, SpatialInertia};

use crate::desc::{BaseDesc, JointKindDesc, MechanismDesc, ShapeDesc};
use crate::error::Error;
use crate::tol::AXIS_MIN_NORM;

/// A collision shape in link coordinates.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum Shape {
    /// Sphere of `radius` (m) at `center` (link coordinates, m).
    Sphere {
        /// Centre (m).
        center: DVec3,
        /// Radius (m).
        radius: f64,
    },
    /// Box of `half_extents` (m) at `center`, link axes.
    Box {
        /// Centre (m).
        center: DVec3,
        /// Half extents (m).
        half_extents: DVec3,
    },
}

/// A rigid link.
#[derive(Clone, Debug, PartialEq)]
pub struct Link {
    /// Name from the description.
    pub name: String,
    /// Pose of the link frame at rest (world).
    pub rest: Pose,
    /// Spatial inertia in the link frame.
    pub inertia: SpatialInertia,
    /// Collision shapes.
    pub shapes: Vec<Shape>,
}

/// Whether a free direction of a joint is a rotation or a translation.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Direction {
    /// Rotation about the unit axis (joint frame).
    Rotation,
    /// Translation along the unit axis (joint frame).
    Translation,
}

/// A compliant joint.
#[derive(Clone, Debug, PartialEq)]
pub struct Joint {
    /// Name from the description.
    pub name: String,
    /// Parent link index.
    pub parent: usize,
    /// Child link index.
    pub child: usize,
    /// The joint frame in parent-link coordinates (`P`): world-aligned at rest, at the anchor.
    pub in_parent: Pose,
    /// The joint frame in child-link coordinates (`Q`).
    pub in_child: Pose,
    /// Free directions: kind and unit axis in the joint frame, one per coordinate.
    pub directions: Vec<(Direction, DVec3)>,
    /// Compliance per free direction (> 0).
    pub compliance: Vec<f64>,
    /// Damping per free direction (≥ 0).
    pub damping: Vec<f64>,
    /// Index of this joint's first coordinate in the stacked vector θ.
    pub offset: usize,
}

impl Joint {
    /// Number of free directions.
    #[must_use]
    pub fn dof(&self) -> usize {
        self.directions.len()
    }

    /// The rest-configuration motion subspace `S` (6 × dof, linear on top), joint frame.
    #[must_use]
    pub fn subspace(&self) -> Vec<[f64; 6]> {
        self.directions
            .iter()
            .map(|(d, a)| match d {
                Direction::Translation => [a.x, a.y, a.z, 0.0, 0.0, 0.0],
                Direction::Rotation => [0.0, 0.0, 0.0, a.x, a.y, a.z],
            })
            .collect()
    }
}

/// A validated mechanism, ready for the full reference and for reduction.
#[derive(Clone, Debug, PartialEq)]
pub struct Mechanism {
    /// Name from the description.
    pub name: String,
    /// The links.
    pub links: Vec<Link>,
    /// The joints.
    pub joints: Vec<Joint>,
    /// The base link (the one link that is no joint's child).
    pub base: usize,
    /// Whether the base is fixed or free.
    pub base_kind: BaseDesc,
    /// Gravity (world, m/s²).
    pub gravity: DVec3,
    /// End-effector links, in the description's order.
    pub end_effectors: Vec<usize>,
    /// Links in walk order: base first, every link after all its parents (ties by index).
    pub order: Vec<usize>,
    /// Per link, its tree joint (`None` for the base).
    pub tree_joint: Vec<Option<usize>>,
    /// Joints that close loops (a link's second and later parents), in declaration order.
    pub loop_joints: Vec<usize>,
    /// Per link, the joints into it (parents' side), in declaration order.
    pub joints_in: Vec<Vec<usize>>,
    /// Per link, the joints out of it (children's side), in declaration order.
    pub joints_out: Vec<Vec<usize>>,
    /// Total number of joint coordinates (the length of θ).
    pub ndof: usize,
}

impl Mechanism {
    /// Index of the link called `name`.
    #[must_use]
    pub fn link_index(&self, name: &str) -> Option<usize> {
        self.links.iter().position(|l| l.name == name)
    }

    /// Index of the joint called `name`.
    #[must_use]
    pub fn joint_index(&self, name: &str) -> Option<usize> {
        self.joints.iter().position(|j| j.name == name)
    }

    /// Links that are neither the base nor an end effector, in walk order (FORK⁻¹S's ℒ).
    #[must_use]
    pub fn internal_links(&self) -> Vec<usize> {
        self.order
            .iter()
            .copied()
            .filter(|&l| l != self.base && !self.end_effectors.contains(&l))
            .collect()
    }

    /// Total mass (kg).
    #[must_use]
    pub fn total_mass(&self) -> f64 {
        self.links.iter().map(|l| l.inertia.mass).sum()
    }

    /// Radius of the bounding sphere of the link origins and shapes at rest, about their
    /// centroid (m): the `r` that scales lengths in FORK⁻¹S eq. 25 and §8.2.
    #[must_use]
    pub fn bounding_radius(&self) -> f64 {
        let pts: Vec<DVec3> = self.links.iter().map(|l| l.rest.translation).collect();
        let c = pts.iter().copied().sum::<DVec3>() / pts.len() as f64;
        self.links
            .iter()
            .map(|l| {
                let extra = l
                    .shapes
                    .iter()
                    .map(|s| match s {
                        Shape::Sphere { center, radius } => center.length() + radius,
                        Shape::Box {
                            center,
                            half_extents,
                        } => center.length() + half_extents.length(),
                    })
                    .fold(0.0, f64::max);
                (l.rest.translation - c).length() + extra
            })
            .fold(0.0, f64::max)
    }
}

fn vec3(a: [f64; 3]) -> DVec3 {
    DVec3::from_array(a)
}

fn finite3(owner: &str, field: &'static str, a: &[f64]) -> Result<(), Error> {
    if a.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(Error::NonFinite {
            owner: owner.to_owned(),
            field,
        })
    }
}

/// Validates `desc` and compiles it (see [`MechanismDesc::build`]).
pub(crate) fn compile(desc: &MechanismDesc) -> Result<Mechanism, Error> {
    finite3("mechanism", "gravity", &desc.gravity)?;
    let mut links = Vec::with_capacity(desc.links.len());
    for (i, l) in desc.links.iter().enumerate() {
        if desc.links[..i].iter().any(|o| o.name == l.name) {
            return Err(Error::DuplicateLink(l.name.clone()));
        }
        let owner = format!("link `{}`", l.name);
        finite3(&owner, "position", &l.position)?;
        finite3(&owner, "rotation", &l.rotation)?;
        finite3(&owner, "com", &l.com)?;
        finite3(&owner, "inertia", &l.inertia)?;
        finite3(&owner, "mass", &[l.mass])?;
        let q = DQuat::from_array(l.rotation);
        if q.length() < AXIS_MIN_NORM {
            return Err(Error::OutOfRange {
                owner,
                field: "rotation",
                reason: "is (nearly) the zero quaternion".to_owned(),
            });
        }
        if l.mass < 0.0 || l.inertia.iter().any(|&x| x < 0.0) {
            return Err(Error::OutOfRange {
                owner,
                field: if l.mass < 0.0 { "mass" } else { "inertia" },
                reason: "is negative".to_owned(),
            });
        }
        let mut shapes = Vec::with_capacity(l.shapes.len());
        for s in &l.shapes {
            shapes.push(match s {
                ShapeDesc::Sphere { radius, center } => {
                    finite3(&owner, "shape", &[*radius])?;
                    finite3(&owner, "shape", center)?;
                    if *radius <= 0.0 {
                        return Err(Error::OutOfRange {
                            owner,
                            field: "shape",
                            reason: format!("sphere radius {radius} is not positive"),
                        });
                    }
                    Shape::Sphere {
                        center: vec3(*center),
                        radius: *radius,
                    }
                }
                ShapeDesc::Box {
                    half_extents,
                    center,
                } => {
                    finite3(&owner, "shape", half_extents)?;
                    finite3(&owner, "shape", center)?;
                    if half_extents.iter().any(|&h| h <= 0.0) {
                        return Err(Error::OutOfRange {
                            owner,
                            field: "shape",
                            reason: "box half extents must be positive".to_owned(),
                        });
                    }
                    Shape::Box {
                        center: vec3(*center),
                        half_extents: vec3(*half_extents),
                    }
                }
            });
        }
        links.push(Link {
            name: l.name.clone(),
            rest: Pose::new(q, vec3(l.position)),
            inertia: SpatialInertia::new(
                l.mass,
                vec3(l.com),
                DMat3::from_diagonal(vec3(l.inertia)),
            ),
            shapes,
        });
    }
    let find = |name: &str| desc.links.iter().position(|l| l.name == name);

    let n = links.len();
    let mut joints = Vec::with_capacity(desc.joints.len());
    let mut joints_in = vec![Vec::new(); n];
    let mut joints_out = vec![Vec::new(); n];
    let mut offset = 0;
    let mut damped = None::<(bool, String)>;
    for (ji, j) in desc.joints.iter().enumerate() {
        if desc.joints[..ji].iter().any(|o| o.name == j.name) {
            return Err(Error::DuplicateJoint(j.name.clone()));
        }
        let owner = format!("joint `{}`", j.name);
        let parent = find(&j.parent).ok_or_else(|| Error::UnknownLink {
            joint: j.name.clone(),
            side: "parent",
            link: j.parent.clone(),
        })?;
        let child = find(&j.child).ok_or_else(|| Error::UnknownLink {
            joint: j.name.clone(),
            side: "child",
            link: j.child.clone(),
        })?;
        if parent == child {
            return Err(Error::SelfJoint(j.name.clone()));
        }
        finite3(&owner, "anchor", &j.anchor)?;
        let unit_axis = |a: &[f64; 3]| -> Result<DVec3, Error> {
            finite3(&owner, "axis", a)?;
            let v = vec3(*a);
            if v.length() < AXIS_MIN_NORM {
                return Err(Error::OutOfRange {
                    owner: owner.clone(),
                    field: "axis",
                    reason: "is (nearly) the zero vector".to_owned(),
                });
            }
            Ok(v.normalize())
        };
        let directions: Vec<(Direction, DVec3)> = match &j.kind {
            JointKindDesc::Hinge { axis } => vec![(Direction::Rotation, unit_axis(axis)?)],
            JointKindDesc::Slider { axis } => vec![(Direction::Translation, unit_axis(axis)?)],
            JointKindDesc::Ball => DVec3::AXES
                .iter()
                .map(|&a| (Direction::Rotation, a))
                .collect(),
            JointKindDesc::Weld => DVec3::AXES
                .iter()
                .map(|&a| (Direction::Translation, a))
                .chain(DVec3::AXES.iter().map(|&a| (Direction::Rotation, a)))
                .collect(),
        };
        let dof = directions.len();
        let expand = |field: &'static str, v: &[f64]| -> Result<Vec<f64>, Error> {
            finite3(&owner, field, v)?;
            match v.len() {
                1 => Ok(vec![v[0]; dof]),
                k if k == dof => Ok(v.to_vec()),
                got => Err(Error::CountMismatch {
                    joint: j.name.clone(),
                    field,
                    expected: dof,
                    got,
                }),
            }
        };
        let compliance = expand("compliance", &j.compliance)?;
        for (direction, &value) in compliance.iter().enumerate() {
            if value <= 0.0 {
                return Err(Error::NonPositiveCompliance {
                    joint: j.name.clone(),
                    direction,
                    value,
                });
            }
        }
        let damping = if j.damping.is_empty() {
            vec![0.0; dof]
        } else {
            expand("damping", &j.damping)?
        };
        for &d in &damping {
            if d < 0.0 {
                return Err(Error::OutOfRange {
                    owner,
                    field: "damping",
                    reason: format!("{d} is negative"),
                });
            }
            let positive = d > 0.0;
            match &damped {
                None => damped = Some((positive, j.name.clone())),
                Some((p, _)) if *p != positive => return Err(Error::MixedDamping(j.name.clone())),
                Some(_) => {}
            }
        }
        let frame = Pose::from_translation(vec3(j.anchor));
        joints.push(Joint {
            name: j.name.clone(),
            parent,
            child,
            in_parent: links[parent].rest.inverse() * frame,
            in_child: links[child].rest.inverse() * frame,
            directions,
            compliance,
            damping,
            offset,
        });
        offset += dof;
        joints_in[child].push(ji);
        joints_out[parent].push(ji);
    }

    // The base: the one link without parents.
    let roots: Vec<usize> = (0..n).filter(|&l| joints_in[l].is_empty()).collect();
    if roots.len() != 1 {
        let names: Vec<&str> = roots.iter().map(|&l| links[l].name.as_str()).collect();
        return Err(Error::Base(if names.is_empty() {
            "none (every link is some joint's child)".to_owned()
        } else {
            format!("{} ({})", names.len(), names.join(", "))
        }));
    }
    let base = roots[0];

    // Walk order (Kahn's algorithm, smallest index first): parents before children.
    let mut missing: Vec<usize> = joints_in.iter().map(Vec::len).collect();
    let mut ready = BinaryHeap::from([Reverse(base)]);
    let mut order = Vec::with_capacity(n);
    while let Some(Reverse(l)) = ready.pop() {
        order.push(l);
        for &ji in &joints_out[l] {
            let c = joints[ji].child;
            missing[c] -= 1;
            if missing[c] == 0 {
                ready.push(Reverse(c));
            }
        }
    }
    if order.len() < n {
        // With a single root, every link left over lies on or downstream of a directed cycle:
        // walk blocked parents from one of them until a link repeats; the last joint taken
        // closes the cycle.
        let mut l = (0..n).find(|&l| missing[l] > 0).unwrap_or(base);
        let mut seen = vec![false; n];
        loop {
            seen[l] = true;
            let Some(&ji) = joints_in[l]
                .iter()
                .find(|&&ji| missing[joints[ji].parent] > 0)
            else {
                return Err(Error::Unreachable(links[l].name.clone()));
            };
            let p = joints[ji].parent;
            if seen[p] {
                return Err(Error::Cycle(joints[ji].name.clone()));
            }
            l = p;
        }
    }

    let mut tree_joint = vec![None; n];
    let mut loop_joints = Vec::new();
    for (l, ins) in joints_in.iter().enumerate() {
        if let Some((&first, rest)) = ins.split_first() {
            tree_joint[l] = Some(first);
            loop_joints.extend_from_slice(rest);
        }
    }
    loop_joints.sort_unstable();

    let mut end_effectors = Vec::with_capacity(desc.end_effectors.len());
    if desc.end_effectors.is_empty() {
        return Err(Error::EndEffector {
            link: String::new(),
            reason: "the mechanism names no end effector".to_owned(),
        });
    }
    for name in &desc.end_effectors {
        let err = |reason: String| Error::EndEffector {
            link: name.clone(),
            reason,
        };
        let l = find(name).ok_or_else(|| err("no such link".to_owned()))?;
        if end_effectors.contains(&l) {
            return Err(err("listed twice".to_owned()));
        }
        if l == base {
            return Err(err("is the base".to_owned()));
        }
        if let Some(&ji) = joints_out[l].first() {
            return Err(err(format!(
                "is not a leaf of the walk: joint `{}` leads on to `{}`",
                joints[ji].name, links[joints[ji].child].name
            )));
        }
        end_effectors.push(l);
    }

    Ok(Mechanism {
        name: desc.name.clone(),
        links,
        joints,
        base,
        base_kind: desc.base,
        gravity: vec3(desc.gravity),
        end_effectors,
        order,
        tree_joint,
        loop_joints,
        joints_in,
        joints_out,
        ndof: offset,
    })
}

#[cfg(test)]
#[path = "mechanism_tests.rs"]
mod tests;
