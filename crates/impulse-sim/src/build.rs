//! From a validated scene description to bodies: geometry, mass properties, principal frames.

use std::path::Path;

use glam::{DQuat, DVec3};
use impulse_collide::{Convex, Motion, Shape, motion};
use impulse_geom::{ConvexPolyhedron, Ellipsoid, Pose, Sphere, obj, primitives};
use impulse_massprops::MassProperties;

use crate::body::{Body, BodyKind, Mass};
use crate::error::SimError;
use crate::scene::{BodyDesc, MassDesc, MotionDesc, RotationDesc, ShapeDesc};

/// Density used when a dynamic body gives no mass.
pub const DEFAULT_DENSITY: f64 = 1.0;

/// The rotation a scene gives.
pub(crate) fn rotation(r: &RotationDesc) -> DQuat {
    match *r {
        RotationDesc::Identity => DQuat::IDENTITY,
        RotationDesc::AxisAngle { axis, degrees } => {
            DQuat::from_axis_angle(DVec3::from_array(axis).normalize(), degrees.to_radians())
        }
        RotationDesc::Quaternion(x, y, z, w) => DQuat::from_xyzw(x, y, z, w).normalize(),
    }
}

/// One convex piece and its mass properties at unit density, in the piece's frame.
fn convex(shape: &ShapeDesc, base_dir: &Path) -> Result<(Convex, MassProperties), String> {
    let poly = |p: ConvexPolyhedron| -> Result<(Convex, MassProperties), String> {
        let mp = MassProperties::from_convex(&p, 1.0).map_err(|e| e.to_string())?;
        Ok((Convex::Polyhedron(p), mp))
    };
    match shape {
        ShapeDesc::Sphere { radius } => Ok((
            Convex::Sphere(Sphere::new(*radius).map_err(|e| e.to_string())?),
            MassProperties::solid_sphere(*radius, DVec3::ZERO, 1.0).map_err(|e| e.to_string())?,
        )),
        ShapeDesc::Box { half_extents } => {
            let h = DVec3::from_array(*half_extents);
            Ok((
                Convex::Polyhedron(primitives::cuboid(h).map_err(|e| e.to_string())?),
                MassProperties::solid_cuboid(h, DVec3::ZERO, 1.0).map_err(|e| e.to_string())?,
            ))
        }
        ShapeDesc::GeodesicSphere { radius, level } => {
            poly(primitives::geodesic_sphere(*level, *radius).map_err(|e| e.to_string())?)
        }
        ShapeDesc::Ellipsoid {
            semi_axes,
            level: Some(level),
        } => {
            let mesh = primitives::geodesic_sphere_mesh(*level, 1.0).map_err(|e| e.to_string())?;
            let s = DVec3::from_array(*semi_axes);
            let points: Vec<DVec3> = mesh.vertices().iter().map(|v| *v * s).collect();
            poly(ConvexPolyhedron::hull(&points).map_err(|e| e.to_string())?)
        }
        ShapeDesc::Ellipsoid {
            semi_axes,
            level: None,
        } => {
            let s = DVec3::from_array(*semi_axes);
            Ok((
                Convex::Ellipsoid(Ellipsoid::new(s).map_err(|e| e.to_string())?),
                MassProperties::solid_ellipsoid(s, DVec3::ZERO, 1.0).map_err(|e| e.to_string())?,
            ))
        }
        ShapeDesc::Prism {
            sides,
            radius,
            half_height,
        } => poly(
            primitives::regular_prism(*sides, *radius, *half_height).map_err(|e| e.to_string())?,
        ),
        ShapeDesc::Hull { points } => {
            let pts: Vec<DVec3> = points.iter().map(|p| DVec3::from_array(*p)).collect();
            poly(ConvexPolyhedron::hull(&pts).map_err(|e| e.to_string())?)
        }
        ShapeDesc::Obj { path } => {
            let full = base_dir.join(path);
            let mesh = obj::read(&full).map_err(|e| e.to_string())?;
            poly(ConvexPolyhedron::from_mesh(&mesh).map_err(|e| {
                format!(
                    "{}: {e} (a convex mesh is required; give a non-convex body as a Compound of convex parts)",
                    full.display()
                )
            })?)
        }
        ShapeDesc::Compound { .. } => Err("a part cannot itself be a compound".into()),
    }
}

/// The pieces (each at its pose in the shape frame) and the mass properties at unit density in
/// the shape frame.
fn pieces(
    shape: &ShapeDesc,
    base_dir: &Path,
) -> Result<(Vec<(Pose, Convex)>, MassProperties), String> {
    match shape {
        ShapeDesc::Compound { parts } => {
            let mut out = Vec::with_capacity(parts.len());
            let mut mps = Vec::with_capacity(parts.len());
            for (k, part) in parts.iter().enumerate() {
                let (c, mp) =
                    convex(&part.shape, base_dir).map_err(|e| format!("part {k}: {e}"))?;
                let pose = Pose::new(rotation(&part.rotation), DVec3::from_array(part.position));
                mps.push(mp.transformed(&pose));
                out.push((pose, c));
            }
            let mp = MassProperties::compound(&mps).map_err(|e| e.to_string())?;
            Ok((out, mp))
        }
        _ => {
            let (c, mp) = convex(shape, base_dir)?;
            Ok((vec![(Pose::IDENTITY, c)], mp))
        }
    }
}

/// The mass properties of a shape at density 1, in its own frame.
pub(crate) fn mass_properties(desc: &ShapeDesc, base_dir: &Path) -> Result<MassProperties, String> {
    pieces(desc, base_dir).map(|(_, mp)| mp)
}

/// The collision shape a description gives, in its own frame (a multibody link's shape).
pub(crate) fn shape(desc: &ShapeDesc, base_dir: &Path) -> Result<Shape, String> {
    let (parts, _) = pieces(desc, base_dir)?;
    Shape::compound(parts).map_err(|e| e.to_string())
}

/// Builds one body from its (validated) description.
pub(crate) fn body(desc: &BodyDesc, material: usize, base_dir: &Path) -> Result<Body, SimError> {
    let geometry = |message: String| SimError::Geometry {
        body: desc.name.clone(),
        message,
    };
    let (parts, unit_mp) = pieces(&desc.shape, base_dir).map_err(geometry)?;
    let user = Pose::new(rotation(&desc.rotation), DVec3::from_array(desc.position));
    let velocity = DVec3::from_array(desc.velocity);
    let omega = DVec3::from_array(desc.angular_velocity);
    let shape_in = |frame: Pose| -> Result<Shape, SimError> {
        let inv = frame.inverse();
        let moved = parts
            .iter()
            .map(|(p, c)| (inv * *p, c.clone()))
            .collect::<Vec<_>>();
        Shape::compound(moved).map_err(|e| geometry(e.to_string()))
    };
    match desc.motion {
        MotionDesc::Dynamic => {
            let scale = match desc.mass {
                None => DEFAULT_DENSITY,
                Some(MassDesc::Density(d)) => d,
                Some(MassDesc::Mass(m)) => m / unit_mp.mass,
            };
            let solid = MassProperties {
                mass: unit_mp.mass * scale,
                com: unit_mp.com,
                inertia: unit_mp.inertia * scale,
            };
            let mut all = vec![solid];
            for pm in &desc.point_masses {
                all.push(
                    MassProperties::point_mass(pm.mass, DVec3::from_array(pm.position))
                        .map_err(|e| geometry(e.to_string()))?,
                );
            }
            let mp = MassProperties::compound(&all).map_err(|e| geometry(e.to_string()))?;
            let principal = mp.principal().map_err(|e| geometry(e.to_string()))?;
            if !(principal.moments.min_element() > 0.0 && mp.mass.is_finite() && mp.mass > 0.0) {
                return Err(geometry(format!(
                    "mass {} and principal moments {} must be positive",
                    mp.mass, principal.moments
                )));
            }
            let frame = Pose::new(DQuat::from_mat3(&principal.axes).normalize(), mp.com);
            let shape = shape_in(frame)?;
            let mut body = Body::new(
                desc.name.clone(),
                shape,
                BodyKind::Dynamic,
                user * frame,
                velocity,
                omega,
                Some(Mass {
                    mass: mp.mass,
                    moments: principal.moments,
                }),
                material,
                None,
            );
            // The user's frame seen from the principal frame: user = pose · frame⁻¹.
            body.frame = frame.inverse();
            Ok(body)
        }
        MotionDesc::Fixed => Ok(Body::new(
            desc.name.clone(),
            shape_in(Pose::IDENTITY)?,
            BodyKind::Fixed,
            user,
            DVec3::ZERO,
            DVec3::ZERO,
            None,
            material,
            None,
        )),
        MotionDesc::Spinner { axis, rate } => {
            let axis = DVec3::from_array(axis);
            let script = motion::Spinner::new(user.translation, axis, rate)
                .map_err(|e| geometry(e.to_string()))?;
            Ok(Body::new(
                desc.name.clone(),
                shape_in(Pose::IDENTITY)?,
                BodyKind::Scripted,
                user,
                DVec3::ZERO,
                script.axis() * rate,
                None,
                material,
                Some(Motion::Spinner(script)),
            ))
        }
        MotionDesc::Oscillator {
            axis,
            amplitude,
            frequency,
            phase,
        } => {
            let omega_rate = 2.0 * std::f64::consts::PI * frequency;
            let script = motion::Oscillator::new(
                user.translation,
                DVec3::from_array(axis),
                amplitude,
                omega_rate,
                phase,
            )
            .map_err(|e| geometry(e.to_string()))?;
            let start = Pose::new(user.rotation, script.com_at(0.0));
            Ok(Body::new(
                desc.name.clone(),
                shape_in(Pose::IDENTITY)?,
                BodyKind::Scripted,
                start,
                script.com_velocity_at(0.0),
                DVec3::ZERO,
                None,
                material,
                Some(Motion::Oscillator(script)),
            ))
        }
    }
}
