//! Multibodies read from a URDF file (`Multibody(urdf: Urdf(path: …, links: […], joints: […]))`),
//! with the URDF's `<collision>` geometry as the links' collision shapes and per-link and
//! per-joint overrides by name. See `docs/urdf.md`.
//!
//! What comes from the file: links (inertia from `<inertial>`, collision shapes from
//! `<collision>`), joints (origin, axis, kind, `<dynamics>` damping and friction), the root
//! (the one link that is no joint's child). What the scene adds: the base kind and placement,
//! the initial joint state, limits as impulsive stops, springs, controllers, materials, and
//! any link's shape or mass in place of the file's.
//!
//! Shapes: `box` → [`ShapeDesc::Box`], `sphere` → [`ShapeDesc::Sphere`], `cylinder` →
//! [`ShapeDesc::Prism`] with [`URDF_CYLINDER_SIDES`] sides (axis along the collision frame's z,
//! as URDF says), `mesh` → the convex polyhedron of a Wavefront OBJ or an STL file (scaled; a
//! non-convex mesh is an error, as for [`ShapeDesc::Obj`]), each at its `<origin>` in the link
//! frame; several `<collision>` elements make a [`ShapeDesc::Compound`].

use std::path::{Path, PathBuf};

use glam::DVec3;
use impulse_geom::{ConvexPolyhedron, PolyMesh, Pose, obj};
use impulse_multibody::urdf::{UrdfGeometry, UrdfLink, UrdfRobot};
use serde::{Deserialize, Serialize};

use impulse_multibody::{JointLimit, JointSpec, JointType};

use super::{InertiaDesc, LimitDesc, LinkDesc, PartJoint, PartLink, Parts, link_mass};
use crate::scene::{MassDesc, PartDesc, RotationDesc, ShapeDesc};

/// Sides of the prism that stands for a URDF `<cylinder>`: its polygon is inscribed in the
/// cylinder's circle (circumradius = the cylinder's radius), so the prism lies inside the
/// cylinder and its flats are `r·(1 − cos(π/32))` = 0.48 % of r inside it, its volume
/// `(32/2π)·sin(2π/32)` = 99.4 % of the cylinder's. Default `32`.
pub const URDF_CYLINDER_SIDES: u32 = 32;

/// A multibody's URDF source: the file and the overrides of its links and joints.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Urdf", deny_unknown_fields)]
pub struct UrdfDesc {
    /// The URDF file, relative to the scene file (or absolute).
    pub path: String,
    /// Overrides of links, by name (each must name a link of the file).
    #[serde(default)]
    pub links: Vec<LinkOverride>,
    /// Overrides of joints, by name (each must name a joint of the file).
    #[serde(default)]
    pub joints: Vec<JointOverride>,
}

/// What a scene changes about one URDF link. Fields left out keep the file's value.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename = "LinkOverride", deny_unknown_fields)]
pub struct LinkOverride {
    /// The link (must exist in the file).
    pub name: String,
    /// A collision shape in place of the file's `<collision>` elements.
    #[serde(default)]
    pub shape: Option<ShapeDesc>,
    /// Position of `shape` in the link frame (only with `shape`).
    #[serde(default)]
    pub position: [f64; 3],
    /// Orientation of `shape` in the link frame (only with `shape`).
    #[serde(default)]
    pub rotation: RotationDesc,
    /// Mass from the collision shape's volume (the override's or the file's), by density or
    /// total mass, in place of the file's `<inertial>`.
    #[serde(default)]
    pub mass: Option<MassDesc>,
    /// Explicit mass properties in place of the file's `<inertial>`.
    #[serde(default)]
    pub inertia: Option<InertiaDesc>,
    /// Material name (contact table); `"default"` if neither given here nor anywhere else.
    #[serde(default)]
    pub material: Option<String>,
}

/// What a scene changes about one URDF joint. Fields left out keep the file's value (the
/// initial state defaults to 0, as for inline joints).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename = "JointOverride", deny_unknown_fields)]
pub struct JointOverride {
    /// The joint (must exist in the file).
    pub name: String,
    /// A linear spring `(stiffness, rest position)`.
    #[serde(default)]
    pub spring: Option<(f64, f64)>,
    /// Viscous damping in place of the file's `<dynamics damping>`.
    #[serde(default)]
    pub damping: Option<f64>,
    /// Constant friction in place of the file's `<dynamics friction>`.
    #[serde(default)]
    pub friction: Option<f64>,
    /// Travel limits as impulsive stops (the file's `<limit>` is not read: see
    /// `docs/urdf.md`).
    #[serde(default)]
    pub limit: Option<LimitDesc>,
    /// Initial position (rad or m).
    #[serde(default)]
    pub q: f64,
    /// Initial rate (rad/s or m/s).
    #[serde(default)]
    pub qd: f64,
}

impl UrdfDesc {
    /// Reads the file named by `path`, resolved against `base_dir`.
    ///
    /// # Errors
    /// The file's problem (unreadable, not URDF, an unsupported joint), as a sentence.
    pub(super) fn read(&self, base_dir: &Path) -> Result<UrdfRobot, String> {
        if self.path.is_empty() {
            return Err("the URDF path is empty".into());
        }
        impulse_multibody::urdf::read_file(&base_dir.join(&self.path)).map_err(|e| e.to_string())
    }

    /// The directory the file's relative mesh names resolve against, relative to the scene's
    /// directory when `path` is relative (it is joined to the scene's directory again when
    /// the shape is built).
    fn mesh_dir(&self) -> PathBuf {
        Path::new(&self.path)
            .parent()
            .map(Path::to_path_buf)
            .unwrap_or_default()
    }
}

/// The collision shape of a URDF link in its link frame (`None` without `<collision>`);
/// meshes are read now, relative to the URDF file.
///
/// # Errors
/// A sentence naming the link's collision element (and the mesh file) that cannot be used.
pub(super) fn collision_shape(
    link: &UrdfLink,
    desc: &UrdfDesc,
    base_dir: &Path,
) -> Result<Option<ShapeDesc>, String> {
    if link.collisions.is_empty() {
        return Ok(None);
    }
    let mut parts = Vec::with_capacity(link.collisions.len());
    for (k, c) in link.collisions.iter().enumerate() {
        let shape =
            geometry(&c.geometry, desc, base_dir).map_err(|e| format!("<collision> #{k}: {e}"))?;
        parts.push(part(shape, c.origin));
    }
    Ok(Some(ShapeDesc::Compound { parts }))
}

fn part(shape: ShapeDesc, pose: Pose) -> PartDesc {
    let r = pose.rotation;
    PartDesc {
        shape,
        position: pose.translation.to_array(),
        rotation: RotationDesc::Quaternion(r.x, r.y, r.z, r.w),
    }
}

fn geometry(g: &UrdfGeometry, desc: &UrdfDesc, base_dir: &Path) -> Result<ShapeDesc, String> {
    Ok(match g {
        UrdfGeometry::Box { size } => ShapeDesc::Box {
            half_extents: size.map(|x| 0.5 * x),
        },
        UrdfGeometry::Sphere { radius } => ShapeDesc::Sphere { radius: *radius },
        UrdfGeometry::Cylinder { radius, length } => ShapeDesc::Prism {
            sides: URDF_CYLINDER_SIDES,
            radius: *radius,
            half_height: 0.5 * length,
        },
        UrdfGeometry::Capsule { .. } => {
            return Err(
                "a capsule is not supported (no capsule shape in scenes): give the \
                        link a `shape` override, e.g. a Compound of a Prism and two Spheres"
                    .into(),
            );
        }
        UrdfGeometry::Mesh { filename, scale } => mesh(filename, *scale, desc, base_dir)?,
    })
}

/// A mesh file's convex polyhedron, scaled, as a hull of its vertices.
fn mesh(
    filename: &str,
    scale: [f64; 3],
    desc: &UrdfDesc,
    base_dir: &Path,
) -> Result<ShapeDesc, String> {
    if filename.starts_with("package://") {
        return Err(format!(
            "mesh \"{filename}\": `package://` names a ROS package, which is not resolved \
             here: write the path relative to the URDF file"
        ));
    }
    let name = filename.strip_prefix("file://").unwrap_or(filename);
    let full = base_dir.join(desc.mesh_dir()).join(name);
    let ext = full
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if !matches!(ext.as_deref(), Some("obj" | "stl")) {
        return Err(format!(
            "mesh {}: unsupported format (Wavefront .obj and .stl are read; convert COLLADA \
             and other meshes, or give the link a `shape` override)",
            full.display()
        ));
    }
    if !scale.iter().all(|s| s.is_finite() && *s > 0.0) {
        return Err(format!(
            "mesh {}: scale {scale:?} must be finite and > 0 on each axis",
            full.display()
        ));
    }
    let read = if ext.as_deref() == Some("stl") {
        super::stl::read(&full).map_err(|e| format!("mesh {e}"))?
    } else {
        obj::read(&full).map_err(|e| format!("mesh {}: {e}", full.display()))?
    };
    let s = DVec3::from_array(scale);
    let vertices: Vec<DVec3> = read.vertices().iter().map(|v| *v * s).collect();
    let scaled = PolyMesh::new(vertices, read.faces().map(<[u32]>::to_vec))
        .map_err(|e| format!("mesh {}: {e}", full.display()))?;
    let poly = ConvexPolyhedron::from_mesh(&scaled).map_err(|e| {
        format!(
            "mesh {}: {e} (a convex mesh is required; give a non-convex link a `shape` \
             override, a Compound of convex parts)",
            full.display()
        )
    })?;
    Ok(ShapeDesc::Hull {
        points: poly.vertices().iter().map(|v| v.to_array()).collect(),
    })
}

/// The links and joints of a URDF multibody with its overrides applied; `(field, problem)` on
/// error, the field naming the override, link or joint.
pub(super) fn parts(desc: &UrdfDesc, base_dir: &Path) -> Result<Parts, (String, String)> {
    let robot = desc.read(base_dir).map_err(|p| ("urdf".to_string(), p))?;
    check_names(desc, &robot)?;
    let roots = robot.roots();
    let root = match roots.as_slice() {
        [one] => (*one).to_string(),
        [] => {
            return Err((
                "urdf".into(),
                format!(
                    "{}: no root link ({})",
                    desc.path,
                    if robot.links.is_empty() {
                        "the robot has no links"
                    } else {
                        "every link is some joint's child: a loop"
                    }
                ),
            ));
        }
        [a, b, ..] => {
            return Err((
                "urdf".into(),
                format!(
                    "{}: links \"{a}\" and \"{b}\" are both no joint's child: the links \
                     must form one tree with a single root",
                    desc.path
                ),
            ));
        }
    };
    let mut links = Vec::with_capacity(robot.links.len());
    for l in &robot.links {
        let field = |f: &str| format!("urdf link \"{}\"{f}", l.name);
        let o = desc.links.iter().find(|o| o.name == l.name);
        let from_file = collision_shape(l, desc, base_dir).map_err(|p| (field(".collision"), p))?;
        let link = match o {
            None => LinkDesc {
                name: l.name.clone(),
                shape: from_file,
                position: [0.0; 3],
                rotation: RotationDesc::Identity,
                mass: None,
                inertia: None,
                material: "default".into(),
            },
            Some(o) => {
                if o.shape.is_none()
                    && (o.position != [0.0; 3] || o.rotation != RotationDesc::Identity)
                {
                    return Err((
                        field(".position"),
                        "an override's position and rotation place its `shape`; give one".into(),
                    ));
                }
                let (shape, position, rotation) = match &o.shape {
                    Some(s) => (Some(s.clone()), o.position, o.rotation),
                    None => (from_file, [0.0; 3], RotationDesc::Identity),
                };
                LinkDesc {
                    name: l.name.clone(),
                    shape,
                    position,
                    rotation,
                    mass: o.mass,
                    inertia: o.inertia,
                    material: o.material.clone().unwrap_or_else(|| "default".into()),
                }
            }
        };
        let (inertia, shape) =
            link_mass(&link, base_dir).map_err(|(f, p)| (field(&format!(".{f}")), p))?;
        let own_mass = o.is_some_and(|o| o.mass.is_some() || o.inertia.is_some());
        links.push(PartLink {
            name: link.name,
            inertia: if own_mass { inertia } else { l.inertia },
            shape,
            material: link.material,
        });
    }
    let mut joints = Vec::with_capacity(robot.joints.len());
    for spec in robot.joints {
        let Some(o) = desc.joints.iter().find(|o| o.name == spec.name) else {
            joints.push(PartJoint {
                spec,
                q: 0.0,
                qd: 0.0,
            });
            continue;
        };
        let field = |f: &str| format!("urdf joint \"{}\".{f}", spec.name);
        joints.push(joint_override(spec.clone(), o).map_err(|(f, p)| (field(f), p))?);
    }
    Ok(Parts {
        links,
        joints,
        root,
    })
}

/// A URDF joint with a scene's override applied; `(field, problem)` on error.
fn joint_override(
    mut spec: JointSpec,
    o: &JointOverride,
) -> Result<PartJoint, (&'static str, String)> {
    let finite = |f: &'static str, x: f64| {
        if x.is_finite() {
            Ok(())
        } else {
            Err((f, format!("{x} is not finite")))
        }
    };
    finite("q", o.q)?;
    finite("qd", o.qd)?;
    if let Some(d) = o.damping {
        finite("damping", d)?;
        spec.passive.damping = d;
    }
    if let Some(f) = o.friction {
        finite("friction", f)?;
        spec.passive.friction = f;
    }
    if let Some((k, rest)) = o.spring {
        if !(k.is_finite() && rest.is_finite()) {
            return Err(("spring", format!("({k}, {rest}) is not finite")));
        }
        spec.passive.stiffness = k;
        spec.passive.rest = rest;
    }
    if let Some(l) = o.limit {
        for (f, x) in [
            ("limit.lower", l.lower),
            ("limit.upper", l.upper),
            ("limit.restitution", l.restitution),
        ] {
            if x.is_nan() {
                return Err((f, "is NaN".into()));
            }
        }
        spec.limit = Some(JointLimit::new(l.lower, l.upper, l.restitution));
    }
    if matches!(spec.joint_type, JointType::Fixed)
        && (o.q != 0.0 || o.qd != 0.0 || o.spring.is_some() || o.limit.is_some())
    {
        return Err((
            "q",
            "a fixed joint has no coordinate: no q, qd, spring or limit".into(),
        ));
    }
    Ok(PartJoint {
        spec,
        q: o.q,
        qd: o.qd,
    })
}

/// Checks that every override names a link or joint of `robot` (once); the error is the
/// override's field and the problem.
fn check_names(desc: &UrdfDesc, robot: &UrdfRobot) -> Result<(), (String, String)> {
    for (k, o) in desc.links.iter().enumerate() {
        let field = format!("urdf.links[{k}] \"{}\"", o.name);
        if !robot.links.iter().any(|l| l.name == o.name) {
            return Err((field, format!("no link \"{}\" in {}", o.name, desc.path)));
        }
        if desc.links[..k].iter().any(|p| p.name == o.name) {
            return Err((field, "the link is overridden twice".into()));
        }
    }
    for (k, o) in desc.joints.iter().enumerate() {
        let field = format!("urdf.joints[{k}] \"{}\"", o.name);
        if !robot.joints.iter().any(|j| j.name == o.name) {
            return Err((field, format!("no joint \"{}\" in {}", o.name, desc.path)));
        }
        if desc.joints[..k].iter().any(|p| p.name == o.name) {
            return Err((field, "the joint is overridden twice".into()));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests;
