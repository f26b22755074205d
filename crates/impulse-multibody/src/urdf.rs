//! URDF import into a [`Model`] (parsing by the `urdf-rs` crate).
//!
//! Mapping:
//! - `<link>`: its `<inertial>` (origin xyz/rpy, mass, the six inertia entries about the centre
//!   of mass in the inertial frame) becomes a [`SpatialInertia`] in the link frame. Visual
//!   geometry is ignored; `<collision>` geometry does not enter the dynamics and is handed, as
//!   written, to whoever gives links collision shapes ([`read_str`], [`UrdfRobot`]). A link without `<inertial>` has zero mass, which is fine
//!   when it is welded to a massive link or is the fixed base, and an error when it moves on
//!   its own.
//! - `<joint>`: `revolute` and `continuous` become revolute joints, `prismatic` prismatic,
//!   `fixed` fixed (the child is merged into its parent's rigid body). `<origin>` places the
//!   joint frame in the parent link frame (rpy = fixed-axis roll, pitch, yaw:
//!   `Rz(y)·Ry(p)·Rx(r)`), `<axis>` is in the joint frame (default x). `<dynamics damping
//!   friction>` become a viscous damper and constant (Coulomb) friction ([`JointPassive`]).
//!   `<limit>`, `<calibration>` and `<safety_controller>` are ignored (they do not enter the
//!   dynamics; a URDF `<limit>` is mandatory on revolute joints and often a controller's
//!   range rather than a hard stop, and it carries no restitution: give stops with
//!   [`crate::JointSpec::with_limit`] where a mechanism has them). `floating`, `planar` and `spherical` joints and `<mimic>` are rejected with
//!   [`MultibodyError::Unsupported`] naming the joint: silently ignoring them would give wrong
//!   dynamics.
//! - The root link (the one that is no joint's child) is the base, fixed or floating as asked.
//!
//! Joint order (coordinate order of q, v, τ) is depth-first pre-order from the root, the
//! children of a link visited in the order their joints appear in the file; fixed joints have
//! no coordinate. [`Model::joint_names`] lists it.

use std::path::Path;

use glam::{DMat3, DVec3};
use impulse_geom::{Pose, SpatialInertia};

use crate::error::MultibodyError;
use crate::model::{BaseKind, JointPassive, JointSpec, Model, ModelBuilder, quat_from_rpy};

fn pose(p: &urdf_rs::Pose) -> Pose {
    Pose::new(quat_from_rpy(p.rpy.0), DVec3::from_array(p.xyz.0))
}

/// The model described by URDF text.
///
/// # Errors
/// [`MultibodyError::Urdf`] if the XML cannot be parsed; otherwise a [`MultibodyError`] naming
/// the offending link or joint (see [`ModelBuilder::build`] and the module docs).
pub fn from_str(xml: &str, base: BaseKind) -> Result<Model, MultibodyError> {
    let robot = urdf_rs::read_from_string(xml).map_err(|e| MultibodyError::Urdf(e.to_string()))?;
    from_robot(&robot, base)
}

/// The model described by a URDF file.
///
/// # Errors
/// [`MultibodyError::Urdf`] if the file cannot be read or parsed; otherwise as [`from_str`].
pub fn from_file(path: &Path, base: BaseKind) -> Result<Model, MultibodyError> {
    let xml = std::fs::read_to_string(path)
        .map_err(|e| MultibodyError::Urdf(format!("{}: {e}", path.display())))?;
    from_str(&xml, base)
}

/// A link's collision geometry as the URDF writes it (lengths in the file's units).
#[derive(Clone, Debug, PartialEq)]
pub enum UrdfGeometry {
    /// `<box size="x y z"/>`: full side lengths, centred on the collision frame.
    Box {
        /// Full side lengths.
        size: [f64; 3],
    },
    /// `<sphere radius/>` centred on the collision frame.
    Sphere {
        /// Radius.
        radius: f64,
    },
    /// `<cylinder radius length/>`: axis along the collision frame's z, centred on its origin.
    Cylinder {
        /// Radius.
        radius: f64,
        /// Full length along z.
        length: f64,
    },
    /// `<capsule radius length/>` (URDF 1.2): a cylinder of `length` along z with hemispherical
    /// caps.
    Capsule {
        /// Radius.
        radius: f64,
        /// Length of the cylindrical part.
        length: f64,
    },
    /// `<mesh filename scale/>`: the file name as written (relative paths are relative to the
    /// URDF file; `package://` and `file://` URIs are left to the caller).
    Mesh {
        /// The file name or URI.
        filename: String,
        /// Per-axis scale (default `1 1 1`).
        scale: [f64; 3],
    },
}

/// One `<collision>` element of a link.
#[derive(Clone, Debug, PartialEq)]
pub struct UrdfCollision {
    /// Its `<origin>`: the geometry's frame in the link frame.
    pub origin: Pose,
    /// Its geometry.
    pub geometry: UrdfGeometry,
}

/// One `<link>`: its mass properties and its collision elements in file order.
#[derive(Clone, Debug, PartialEq)]
pub struct UrdfLink {
    /// The link's name.
    pub name: String,
    /// Its `<inertial>` in the link frame ([`SpatialInertia::ZERO`] without one).
    pub inertia: SpatialInertia,
    /// Its `<collision>` elements.
    pub collisions: Vec<UrdfCollision>,
}

/// A URDF robot as this crate reads it: links in file order and the joints as
/// [`JointSpec`]s in file order (not yet checked to form a tree: [`UrdfRobot::model`] does).
#[derive(Clone, Debug, PartialEq)]
pub struct UrdfRobot {
    /// The robot's name.
    pub name: String,
    /// The links in file order.
    pub links: Vec<UrdfLink>,
    /// The joints in file order.
    pub joints: Vec<JointSpec>,
}

impl UrdfRobot {
    /// The links that are no joint's child (a well-formed robot has exactly one, its root).
    #[must_use]
    pub fn roots(&self) -> Vec<&str> {
        self.links
            .iter()
            .map(|l| l.name.as_str())
            .filter(|n| !self.joints.iter().any(|j| j.child == *n))
            .collect()
    }

    /// The model (the root link as the base, fixed or floating as asked).
    ///
    /// # Errors
    /// A [`MultibodyError`] naming the offending link or joint ([`ModelBuilder::build`]).
    pub fn model(&self, base: BaseKind) -> Result<Model, MultibodyError> {
        let mut b = ModelBuilder::new(base);
        for l in &self.links {
            b.link(&l.name, l.inertia);
        }
        for j in &self.joints {
            b.joint(j.clone());
        }
        b.build()
    }
}

/// Reads URDF text: links with their inertia and collision geometry, joints as specs.
///
/// # Errors
/// [`MultibodyError::Urdf`] if the XML cannot be parsed; [`MultibodyError::Unsupported`]
/// naming the joint for `floating`, `planar` and `spherical` joints and `<mimic>`.
pub fn read_str(xml: &str) -> Result<UrdfRobot, MultibodyError> {
    let robot = urdf_rs::read_from_string(xml).map_err(|e| MultibodyError::Urdf(e.to_string()))?;
    read_robot(&robot)
}

/// Reads a URDF file as [`read_str`] does.
///
/// # Errors
/// [`MultibodyError::Urdf`] naming the file if it cannot be read; otherwise as [`read_str`].
pub fn read_file(path: &Path) -> Result<UrdfRobot, MultibodyError> {
    let xml = std::fs::read_to_string(path)
        .map_err(|e| MultibodyError::Urdf(format!("{}: {e}", path.display())))?;
    read_str(&xml).map_err(|e| match e {
        MultibodyError::Urdf(m) => MultibodyError::Urdf(format!("{}: {m}", path.display())),
        other => other,
    })
}

fn geometry(g: &urdf_rs::Geometry) -> UrdfGeometry {
    match g {
        urdf_rs::Geometry::Box { size } => UrdfGeometry::Box { size: size.0 },
        urdf_rs::Geometry::Sphere { radius } => UrdfGeometry::Sphere { radius: *radius },
        urdf_rs::Geometry::Cylinder { radius, length } => UrdfGeometry::Cylinder {
            radius: *radius,
            length: *length,
        },
        urdf_rs::Geometry::Capsule { radius, length } => UrdfGeometry::Capsule {
            radius: *radius,
            length: *length,
        },
        urdf_rs::Geometry::Mesh { filename, scale } => UrdfGeometry::Mesh {
            filename: filename.clone(),
            scale: scale.map_or([1.0; 3], |s| s.0),
        },
    }
}

fn from_robot(robot: &urdf_rs::Robot, base: BaseKind) -> Result<Model, MultibodyError> {
    read_robot(robot)?.model(base)
}

fn read_robot(robot: &urdf_rs::Robot) -> Result<UrdfRobot, MultibodyError> {
    let mut links = Vec::with_capacity(robot.links.len());
    for link in &robot.links {
        let i = &link.inertial;
        let frame = pose(&i.origin);
        let t = &i.inertia;
        let inertia = DMat3::from_cols(
            DVec3::new(t.ixx, t.ixy, t.ixz),
            DVec3::new(t.ixy, t.iyy, t.iyz),
            DVec3::new(t.ixz, t.iyz, t.izz),
        );
        let r = frame.rotation_matrix();
        links.push(UrdfLink {
            name: link.name.clone(),
            inertia: SpatialInertia::new(
                i.mass.value,
                frame.translation,
                r * inertia * r.transpose(),
            ),
            collisions: link
                .collision
                .iter()
                .map(|c| UrdfCollision {
                    origin: pose(&c.origin),
                    geometry: geometry(&c.geometry),
                })
                .collect(),
        });
    }
    let mut joints = Vec::with_capacity(robot.joints.len());
    for j in &robot.joints {
        let unsupported = |what: &str| MultibodyError::Unsupported {
            joint: j.name.clone(),
            what: what.to_owned(),
        };
        if j.mimic.is_some() {
            return Err(unsupported("mimic constraint"));
        }
        let origin = pose(&j.origin);
        let axis = DVec3::from_array(j.axis.xyz.0);
        let (parent, child) = (j.parent.link.as_str(), j.child.link.as_str());
        let mut spec = match j.joint_type {
            urdf_rs::JointType::Revolute | urdf_rs::JointType::Continuous => {
                JointSpec::revolute(&j.name, parent, child, origin, axis)
            }
            urdf_rs::JointType::Prismatic => {
                JointSpec::prismatic(&j.name, parent, child, origin, axis)
            }
            urdf_rs::JointType::Fixed => JointSpec::fixed(&j.name, parent, child, origin),
            urdf_rs::JointType::Floating => return Err(unsupported("joint type `floating`")),
            urdf_rs::JointType::Planar => return Err(unsupported("joint type `planar`")),
            urdf_rs::JointType::Spherical => return Err(unsupported("joint type `spherical`")),
        };
        if let Some(d) = &j.dynamics {
            spec.passive = JointPassive {
                damping: d.damping,
                friction: d.friction,
                ..JointPassive::default()
            };
        }
        joints.push(spec);
    }
    Ok(UrdfRobot {
        name: robot.name.clone(),
        links,
        joints,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dynamics::{Workspace, forward_dynamics, mass_matrix};
    use crate::testutil::{max_abs, random_state, rng};
    use faer::Mat;

    fn fixture(name: &str) -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../fixtures/urdf")
            .join(name)
    }

    fn link(name: &str, mass: f64, origin: &str, inertia: &str) -> String {
        format!(
            r#"<link name="{name}"><inertial><origin {origin}/><mass value="{mass}"/>
               <inertia {inertia}/></inertial></link>"#
        )
    }

    const BOX: &str = r#"ixx="0.02" ixy="0.001" ixz="-0.002" iyy="0.03" iyz="0.003" izz="0.025""#;

    fn robot(body: &str) -> String {
        format!(r#"<?xml version="1.0"?><robot name="r">{body}</robot>"#)
    }

    /// A URDF with rotated inertial frames and joint origins gives the same model as the builder
    /// fed the same data with rotations built independently (`Rz(y)·Ry(p)·Rx(r)` as matrices).
    #[test]
    fn urdf_matches_builder() {
        let (rpy_i, xyz_i) = ([0.3, -0.2, 0.9], [0.05, -0.02, 0.1]);
        let (rpy_j, xyz_j) = ([-0.4, 0.25, 1.3], [0.2, 0.1, -0.3]);
        let origin = |xyz: [f64; 3], rpy: [f64; 3]| {
            format!(
                r#"xyz="{} {} {}" rpy="{} {} {}""#,
                xyz[0], xyz[1], xyz[2], rpy[0], rpy[1], rpy[2]
            )
        };
        let xml = robot(&format!(
            r#"{}{}{}
            <joint name="j1" type="revolute"><parent link="base"/><child link="a"/>
              <origin {}/><axis xyz="0 0.6 0.8"/></joint>
            <joint name="j2" type="prismatic"><parent link="a"/><child link="b"/>
              <origin {}/><axis xyz="1 1 0"/><dynamics damping="0.7" friction="0.1"/></joint>"#,
            link("base", 3.0, &origin(xyz_i, rpy_i), BOX),
            link("a", 1.0, &origin(xyz_i, rpy_i), BOX),
            link("b", 2.0, &origin(xyz_j, rpy_j), BOX),
            origin(xyz_j, rpy_j),
            origin(xyz_i, rpy_i),
        ));
        let rot = |rpy: [f64; 3]| {
            DMat3::from_rotation_z(rpy[2])
                * DMat3::from_rotation_y(rpy[1])
                * DMat3::from_rotation_x(rpy[0])
        };
        let pose_of = |xyz: [f64; 3], rpy: [f64; 3]| {
            Pose::new(glam::DQuat::from_mat3(&rot(rpy)), DVec3::from_array(xyz))
        };
        let i0 = DMat3::from_cols(
            DVec3::new(0.02, 0.001, -0.002),
            DVec3::new(0.001, 0.03, 0.003),
            DVec3::new(-0.002, 0.003, 0.025),
        );
        let inertia = |m: f64, xyz: [f64; 3], rpy: [f64; 3]| {
            let r = rot(rpy);
            SpatialInertia::new(m, DVec3::from_array(xyz), r * i0 * r.transpose())
        };
        for base in [BaseKind::Fixed, BaseKind::Floating] {
            let from_urdf = from_str(&xml, base).unwrap();
            let mut b = ModelBuilder::new(base);
            b.link("base", inertia(3.0, xyz_i, rpy_i))
                .link("a", inertia(1.0, xyz_i, rpy_i))
                .link("b", inertia(2.0, xyz_j, rpy_j))
                .joint(JointSpec::revolute(
                    "j1",
                    "base",
                    "a",
                    pose_of(xyz_j, rpy_j),
                    DVec3::new(0.0, 0.6, 0.8),
                ))
                .joint(
                    JointSpec::prismatic(
                        "j2",
                        "a",
                        "b",
                        pose_of(xyz_i, rpy_i),
                        DVec3::new(1.0, 1.0, 0.0),
                    )
                    .with_passive(JointPassive {
                        damping: 0.7,
                        friction: 0.1,
                        ..Default::default()
                    }),
                );
            let built = b.build().unwrap();
            assert_eq!(from_urdf.passive(1), built.passive(1));
            let mut rng = rng(6401);
            let (q, v) = random_state(&mut rng, &built);
            let tau = vec![0.4; built.nv()];
            let (mut a1, mut a2) = (vec![0.0; built.nv()], vec![0.0; built.nv()]);
            forward_dynamics(
                &from_urdf,
                &mut Workspace::new(&from_urdf),
                &q,
                &v,
                &tau,
                None,
                &mut a1,
            )
            .unwrap();
            forward_dynamics(
                &built,
                &mut Workspace::new(&built),
                &q,
                &v,
                &tau,
                None,
                &mut a2,
            )
            .unwrap();
            let d: Vec<f64> = a1.iter().zip(&a2).map(|(x, y)| x - y).collect();
            assert!(
                max_abs(&d) <= 1e-12 * max_abs(&a2).max(1.0),
                "{a1:?} {a2:?}"
            );
        }
    }

    /// Joint order is depth-first pre-order from the root with children in file order.
    #[test]
    fn joint_order_is_depth_first_in_file_order() {
        let links: String = ["base", "a", "b", "c", "d", "e"]
            .iter()
            .map(|n| link(n, 1.0, r#"xyz="0 0 0""#, BOX))
            .collect();
        let joint = |name: &str, p: &str, c: &str, kind: &str| {
            format!(
                r#"<joint name="{name}" type="{kind}"><parent link="{p}"/><child link="{c}"/>
                   <axis xyz="0 0 1"/></joint>"#
            )
        };
        let xml = robot(&format!(
            "{links}{}{}{}{}{}",
            joint("to_c", "a", "c", "revolute"),
            joint("to_b", "base", "b", "prismatic"),
            joint("to_a", "base", "a", "continuous"),
            joint("to_d", "b", "d", "fixed"),
            joint("to_e", "d", "e", "revolute"),
        ));
        let m = from_str(&xml, BaseKind::Fixed).unwrap();
        // Root `base`: children in file order b (to_b), then a (to_a); b's subtree first.
        assert_eq!(m.joint_names(), ["to_b", "to_e", "to_a", "to_c"]);
    }

    #[test]
    fn bad_urdf_names_the_culprit() {
        let two = format!(
            "{}{}",
            link("base", 1.0, r#"xyz="0 0 0""#, BOX),
            link("arm", 1.0, r#"xyz="0 0 0""#, BOX)
        );
        let j = |extra: &str, kind: &str, parent: &str| {
            format!(
                r#"<joint name="hinge" type="{kind}"><parent link="{parent}"/><child link="arm"/>{extra}</joint>"#
            )
        };
        let err = |body: String| from_str(&robot(&body), BaseKind::Fixed).unwrap_err();
        assert_eq!(
            err(format!("{two}{}", j("", "revolute", "nowhere"))),
            MultibodyError::UnknownLink {
                joint: "hinge".into(),
                link: "nowhere".into()
            }
        );
        assert!(matches!(
            err(format!("{two}{}", j(r#"<axis xyz="0 0 0"/>"#, "revolute", "base"))),
            MultibodyError::InvalidJoint { joint, .. } if joint == "hinge"
        ));
        assert!(matches!(
            err(format!("{two}{}", j("", "floating", "base"))),
            MultibodyError::Unsupported { joint, .. } if joint == "hinge"
        ));
        assert!(matches!(
            err(format!("{two}{}", j(r#"<mimic joint="other"/>"#, "revolute", "base"))),
            MultibodyError::Unsupported { joint, .. } if joint == "hinge"
        ));
        // A moving link without inertial data.
        let massless = format!(
            r#"{}<link name="arm"/>{}"#,
            link("base", 1.0, r#"xyz="0 0 0""#, BOX),
            j("", "revolute", "base")
        );
        assert!(
            matches!(err(massless), MultibodyError::InvalidInertia { link, .. } if link == "arm")
        );
        // Negative damping.
        assert!(matches!(
            err(format!("{two}{}", j(r#"<dynamics damping="-1"/>"#, "revolute", "base"))),
            MultibodyError::InvalidJoint { joint, .. } if joint == "hinge"
        ));
        // A loop and two roots.
        let looped = format!(
            "{two}{}{}",
            j("", "revolute", "base"),
            r#"<joint name="back" type="fixed"><parent link="arm"/><child link="base"/></joint>"#
        );
        assert!(matches!(err(looped), MultibodyError::Cycle { .. }));
        assert!(matches!(
            err(two.clone()),
            MultibodyError::MultipleRoots { .. }
        ));
        assert!(matches!(err("<link".to_owned()), MultibodyError::Urdf(_)));
        assert!(matches!(
            from_file(Path::new("/nonexistent/x.urdf"), BaseKind::Fixed),
            Err(MultibodyError::Urdf(_))
        ));
    }

    /// `<collision>` elements are read as written, in file order: geometry sizes, the default
    /// mesh scale 1, the origin's rpy as `Rz(y)·Ry(p)·Rx(r)` built independently.
    #[test]
    fn collisions_are_read_as_written() {
        let xml = robot(
            r#"<link name="a">
                 <collision><origin xyz="1 2 3" rpy="0.1 0.2 0.3"/><geometry><box size="0.4 0.5 0.6"/></geometry></collision>
                 <collision><geometry><cylinder radius="0.1" length="0.7"/></geometry></collision>
                 <collision><geometry><sphere radius="0.25"/></geometry></collision>
                 <collision><geometry><mesh filename="m/part.obj"/></geometry></collision>
                 <collision><geometry><mesh filename="p.obj" scale="1 2 3"/></geometry></collision>
               </link><link name="b"/>"#,
        );
        let r = read_str(&xml).unwrap();
        assert_eq!(r.roots(), ["a", "b"]);
        let c = &r.links[0].collisions;
        let geometries: Vec<&UrdfGeometry> = c.iter().map(|c| &c.geometry).collect();
        assert_eq!(
            geometries,
            [
                &UrdfGeometry::Box {
                    size: [0.4, 0.5, 0.6]
                },
                &UrdfGeometry::Cylinder {
                    radius: 0.1,
                    length: 0.7
                },
                &UrdfGeometry::Sphere { radius: 0.25 },
                &UrdfGeometry::Mesh {
                    filename: "m/part.obj".into(),
                    scale: [1.0; 3]
                },
                &UrdfGeometry::Mesh {
                    filename: "p.obj".into(),
                    scale: [1.0, 2.0, 3.0]
                },
            ]
        );
        let want =
            DMat3::from_rotation_z(0.3) * DMat3::from_rotation_y(0.2) * DMat3::from_rotation_x(0.1);
        let got = c[0].origin.rotation_matrix();
        assert!(
            (got - want)
                .abs()
                .to_cols_array()
                .iter()
                .all(|x| *x < 1e-15),
            "{got} {want}"
        );
        assert_eq!(c[0].origin.translation, DVec3::new(1.0, 2.0, 3.0));
        assert_eq!(c[1].origin, Pose::IDENTITY);
        assert!(r.links[1].collisions.is_empty());
    }

    /// The bundled fixture: a double pendulum whose mass matrix matches the closed form.
    #[test]
    fn fixture_double_pendulum_mass_matrix() {
        let m = from_file(&fixture("double_pendulum.urdf"), BaseKind::Fixed).unwrap();
        assert_eq!(m.joint_names(), ["shoulder", "elbow"]);
        assert_eq!((m.body_count(), m.link_count()), (2, 4));
        let q = [0.4, -1.1];
        let mut mm = Mat::<f64>::zeros(2, 2);
        mass_matrix(&m, &mut Workspace::new(&m), &q, &mut mm).unwrap();
        let (m1, l1, m2, l2) = (1.3, 0.7, 0.8, 0.5);
        let (i1, i2, c1, c2) = (m1 * l1 * l1 / 12.0, m2 * l2 * l2 / 12.0, l1 / 2.0, l2 / 2.0);
        let cos2 = q[1].cos();
        let m11 = i1 + i2 + m1 * c1 * c1 + m2 * (l1 * l1 + c2 * c2 + 2.0 * l1 * c2 * cos2);
        let m12 = i2 + m2 * (c2 * c2 + l1 * c2 * cos2);
        let m22 = i2 + m2 * c2 * c2;
        for (got, want) in [
            (mm[(0, 0)], m11),
            (mm[(0, 1)], m12),
            (mm[(1, 0)], m12),
            (mm[(1, 1)], m22),
        ] {
            assert!((got - want).abs() < 1e-14, "{got} {want}");
        }
    }
}
