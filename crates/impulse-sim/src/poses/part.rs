//! A part of a pose study: its geometry and mass from a scene-style description or an OBJ
//! file, its convex hull and its stable poses ([`impulse_massprops::PoseAnalysis`]).

use std::path::{Path, PathBuf};

use glam::{DQuat, DVec3};
use impulse_collide::shape::Convex;
use impulse_geom::{ConvexPolyhedron, Pose};
use impulse_massprops::PoseAnalysis;
use serde::{Deserialize, Serialize};

use crate::SimError;
use crate::scene::{BodyDesc, MassDesc, PointMassDesc, ShapeDesc};
use crate::world::{World, WorldSettings};

/// ε_c of the world a part is built in to read its geometry and mass: far below any part's
/// size (a world refuses bodies smaller than ten ε_c).
const PROBE_EPSILON: f64 = 1e-12;

/// A part file (`part.ron`): the geometry and mass of one part, as a scene's body gives
/// them, without a pose.
///
/// ```ron
/// Part(
///     name: "button",
///     shape: Box(half_extents: (0.01, 0.006, 0.004)),
///     mass: Density(1200.0),
/// )
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Part", deny_unknown_fields)]
pub struct PartFileDesc {
    /// The part's name (the file's stem if omitted).
    #[serde(default)]
    pub name: Option<String>,
    /// Geometry in the part's own frame: any scene shape made of polyhedra (a compound of
    /// convex pieces for a non-convex part).
    pub shape: ShapeDesc,
    /// Mass from a density or a total mass (default density 1; the mass does not change the
    /// poses, only its distribution does).
    #[serde(default)]
    pub mass: Option<MassDesc>,
    /// Point masses fixed to the part (own frame): they move the centre of mass.
    #[serde(default)]
    pub point_masses: Vec<PointMassDesc>,
}

/// A part ready for a pose study: the body it is dropped as, its hull in its body frame (the
/// centre of mass at the origin) and its stable poses.
#[derive(Clone, Debug)]
pub struct PosePart {
    /// The part's name.
    pub name: String,
    /// The body as a scene would give it (its pose and velocity are set per drop).
    pub body: BodyDesc,
    /// Directory that the shape's relative paths resolve against.
    pub base_dir: PathBuf,
    /// The convex hull of every piece, body frame.
    pub hull: ConvexPolyhedron,
    /// The stable poses of the hull about the centre of mass (the body frame's origin).
    pub analysis: PoseAnalysis,
    /// The part's own frame (the frame its shape was given in) in its body frame (centre of
    /// mass at the origin).
    pub frame: Pose,
    /// The part's diameter: its hull's bounding-box diagonal.
    pub diameter: f64,
}

impl PosePart {
    /// Reads a part from `path`: a `.ron` part file ([`PartFileDesc`]) or a convex `.obj`
    /// mesh (density 1).
    ///
    /// # Errors
    /// [`SimError::Io`], [`SimError::Parse`], and every error of [`PosePart::new`]; an
    /// extension other than `.ron` or `.obj` is refused with [`SimError::Invalid`].
    pub fn load(path: &Path) -> Result<Self, SimError> {
        let base_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let stem = path
            .file_stem()
            .map_or_else(|| "part".to_string(), |s| s.to_string_lossy().into_owned());
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        let desc = match ext.as_deref() {
            Some("obj") => PartFileDesc {
                name: Some(stem),
                shape: ShapeDesc::Obj {
                    path: path
                        .file_name()
                        .map(|f| f.to_string_lossy().into_owned())
                        .unwrap_or_default(),
                },
                mass: None,
                point_masses: Vec::new(),
            },
            Some("ron") => {
                let text = std::fs::read_to_string(path).map_err(|e| SimError::Io {
                    path: path.to_path_buf(),
                    message: e.to_string(),
                })?;
                let mut d: PartFileDesc = ron::Options::default()
                    .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
                    .from_str(&text)
                    .map_err(|e| SimError::Parse {
                        source_name: path.display().to_string(),
                        message: e.to_string(),
                    })?;
                d.name.get_or_insert(stem);
                d
            }
            _ => {
                return Err(SimError::Invalid {
                    what: format!("part {}", path.display()),
                    field: "file".into(),
                    problem: "a part is a .ron part file or a .obj mesh".into(),
                });
            }
        };
        Self::new(&desc, &base_dir)
    }

    /// Builds a part from its description; relative paths resolve against `base_dir`.
    ///
    /// # Errors
    /// [`SimError::Invalid`] and [`SimError::Geometry`] for a shape, mass or point mass a
    /// scene would refuse (an open or non-convex OBJ mesh, zero volume, a non-positive mass),
    /// for a sphere or an exact ellipsoid (a part must be polyhedral to have facets), and
    /// for a centre of mass outside the part's convex hull.
    pub fn new(desc: &PartFileDesc, base_dir: &Path) -> Result<Self, SimError> {
        let name = desc.name.clone().unwrap_or_else(|| "part".into());
        // OBJ paths made absolute: a drop's scene (`drop_scene`) may be saved anywhere.
        let mut body = BodyDesc::new(name.clone(), absolute_paths(&desc.shape, base_dir));
        body.mass = desc.mass;
        body.point_masses = desc.point_masses.clone();
        body.validate(0)?;
        // A world only to build the body in (its ε_c must not exceed a tenth of any size).
        let mut settings = WorldSettings::new(PROBE_EPSILON);
        settings.base_dir = base_dir.to_path_buf();
        let mut world = World::new(settings)?;
        let h = world.add_body(&body)?;
        let b = world.body(h).expect("the body was just added");
        let geometry = |message: String| SimError::Geometry {
            body: name.clone(),
            message,
        };
        let mut points = Vec::new();
        for (k, piece) in b.shape.pieces().iter().enumerate() {
            match &piece.convex {
                Convex::Polyhedron(p) => {
                    points.extend(p.vertices().iter().map(|&v| piece.pose.transform_point(v)))
                }
                Convex::Sphere(_) | Convex::Ellipsoid(_) => {
                    return Err(geometry(format!(
                        "piece {k} is smooth (a sphere or an exact ellipsoid): a pose study needs a polyhedral part (give an ellipsoid a `level`)"
                    )));
                }
            }
        }
        // The pieces are placed in the body frame: the centre of mass at the origin.
        let hull =
            ConvexPolyhedron::hull(&points).map_err(|e| geometry(format!("convex hull: {e}")))?;
        let analysis =
            PoseAnalysis::new(&hull, DVec3::ZERO).map_err(|e| geometry(e.to_string()))?;
        let diameter = analysis.diameter();
        Ok(Self {
            name,
            body,
            base_dir: base_dir.to_path_buf(),
            hull,
            analysis,
            frame: b.frame,
            diameter,
        })
    }

    /// The outward normal of hull face `face` in the part's own frame (the frame its shape
    /// was given in): resting on that facet, this direction points down.
    pub fn normal_in_part_frame(&self, face: u32) -> DVec3 {
        self.frame.rotation.inverse() * self.analysis.facets()[face as usize].normal
    }

    /// The position of the body frame's origin (the centre of mass) that puts the part's
    /// lowest point at `height` above the plane z = 0 when its body frame is turned by
    /// `rotation` (world).
    pub fn centre_at_height(&self, rotation: DQuat, height: f64) -> DVec3 {
        let lowest = self
            .hull
            .vertices()
            .iter()
            .map(|&v| (rotation * v).z)
            .fold(f64::INFINITY, f64::min);
        DVec3::new(0.0, 0.0, height - lowest)
    }

    /// Pose of the part's own frame for a body-frame pose (`centre`, `rotation`): what
    /// [`World::set_pose`] takes.
    pub(crate) fn own_frame_pose(&self, centre: DVec3, rotation: DQuat) -> Pose {
        Pose::new(rotation, centre) * self.frame
    }
}

/// `shape` with every OBJ path (of it or its compound's parts) resolved against `base`.
fn absolute_paths(shape: &ShapeDesc, base: &Path) -> ShapeDesc {
    match shape {
        ShapeDesc::Obj { path } => {
            let joined = base.join(path);
            ShapeDesc::Obj {
                path: std::path::absolute(&joined)
                    .unwrap_or(joined)
                    .to_string_lossy()
                    .into_owned(),
            }
        }
        ShapeDesc::Compound { parts } => ShapeDesc::Compound {
            parts: parts
                .iter()
                .map(|p| crate::scene::PartDesc {
                    shape: absolute_paths(&p.shape, base),
                    ..p.clone()
                })
                .collect(),
        },
        other => other.clone(),
    }
}
