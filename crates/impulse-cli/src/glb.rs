//! `impulse run --gltf out.glb`: the run as an animated glTF 2.0 binary that Blender and any
//! glTF viewer play.
//!
//! - **One node per body**, named after it (multibody links too: `<multibody>/<link>`), with
//!   one mesh drawn from its real geometry ([`crate::mesh`]).
//!   Fixed bodies get a muted material, dynamic bodies a bright one, bodies moved by a script
//!   or a multibody another bright one.
//! - **A compound is one mesh with one primitive per convex piece** (the piece's pose baked
//!   into its vertices), not child nodes: the pieces never move relative to each other, so
//!   child nodes would only add static transforms; this way every body is exactly one node
//!   with one translation and one rotation channel, and primitive `k` is piece `k` of the
//!   shape (what the tests check against).
//! - **Frames.** A body's node is its own frame: the position and rotation a program sees
//!   (`BodyState`, the `x … qw` columns of `--out`), so the first and last keyframes are the
//!   recorded states. The simulator keeps the shape in the body frame (`Body::pose`, centred
//!   on the centre of mass, along the principal axes); the own frame is `pose * frame`
//!   (`Body::frame`), so the mesh is the shape moved by `frame⁻¹`.
//! - **Axes.** glTF is +Y up. The body nodes are children of one root node `world` that turns
//!   the scene's up (against gravity; +Z without gravity) onto +Y; below it the coordinates
//!   are the scene's, unchanged. The file has one node per body plus that root.
//! - **Animation**: one animation, a translation and a rotation channel per body, LINEAR, one
//!   keyframe per recorded frame (the scene's `output_rate`, and the end). Each rotation is the
//!   recorded quaternion or its negative (the same rotation), chosen to stay in the hemisphere
//!   of the previous keyframe so that players that interpolate components turn the short way;
//!   the first keyframe has the recorded sign.
//! - **Precision.** Everything is f64 up to the file; glTF stores f32, so numbers are rounded
//!   to f32 only where they are written (`f32s`). A non-finite number, or frame times that f32
//!   cannot keep apart, are refused with an error rather than written into an invalid file.
//!
//! The JSON document is built with `gltf-json` (typed: field names, enums and indices are
//! checked when this compiles); the GLB container (a 12-byte header, a JSON chunk and a BIN
//! chunk) is written here.

use std::path::Path;

use gltf_json as json;
use impulse_geom::{DQuat, DVec3};
use impulse_sim::body::BodyKind;
use impulse_sim::{Recording, World};
use json::validation::{Checked::Valid, USize64};

use crate::mesh::body_triangles;

/// Base colour (linear RGBA) of fixed bodies: a muted grey.
const FIXED_COLOUR: [f32; 4] = [0.45, 0.45, 0.43, 1.0];
/// Base colour of dynamic bodies: a bright orange.
const DYNAMIC_COLOUR: [f32; 4] = [0.95, 0.42, 0.08, 1.0];
/// Base colour of bodies moved by a script or a multibody (links): a bright blue.
const DRIVEN_COLOUR: [f32; 4] = [0.10, 0.50, 0.95, 1.0];

/// The GLB header's magic, `glTF`.
const GLB_MAGIC: &[u8; 4] = b"glTF";
/// The GLB container version written.
const GLB_VERSION: u32 = 2;
/// Chunk type of the JSON chunk (`JSON`, little-endian).
const CHUNK_JSON: u32 = 0x4E4F_534A;
/// Chunk type of the binary chunk (`BIN\0`, little-endian).
const CHUNK_BIN: u32 = 0x004E_4942;

/// Refuses a `--gltf` file name that does not end in `.glb` (checked before the run).
///
/// # Errors
/// A message naming the path.
pub fn check_path(path: &Path) -> Result<(), String> {
    match path.extension().and_then(|e| e.to_str()) {
        Some(e) if e.eq_ignore_ascii_case("glb") => Ok(()),
        _ => Err(format!(
            "--gltf {}: the file name must end in .glb (binary glTF)",
            path.display()
        )),
    }
}

/// Writes the run as a .glb file at `path`.
///
/// # Errors
/// What [`to_glb`] refuses, or the file that cannot be written, named.
pub fn write(path: &Path, rec: &Recording, world: &World) -> Result<(), String> {
    let bytes = to_glb(rec, world)?;
    std::fs::write(path, bytes).map_err(|e| format!("cannot write {}: {e}", path.display()))
}

/// The f32s of `values` (the one place numbers are rounded to f32), refusing a non-finite one.
fn f32s(
    values: impl IntoIterator<Item = f64>,
    what: &dyn Fn() -> String,
) -> Result<Vec<f32>, String> {
    values
        .into_iter()
        .map(|x| crate::mesh::finite_f32(x, "--gltf", what))
        .collect()
}

/// The JSON document being built and its binary buffer.
struct Builder {
    root: json::Root,
    bin: Vec<u8>,
}

impl Builder {
    /// Appends `bytes` to the buffer as a new buffer view (every view starts 4-byte aligned:
    /// all our components are 4 bytes).
    fn view(
        &mut self,
        bytes: impl IntoIterator<Item = [u8; 4]>,
        target: Option<json::buffer::Target>,
    ) -> json::Index<json::buffer::View> {
        let start = self.bin.len();
        self.bin.extend(bytes.into_iter().flatten());
        self.root.push(json::buffer::View {
            buffer: json::Index::new(0),
            byte_length: USize64::from(self.bin.len() - start),
            byte_offset: Some(USize64::from(start)),
            byte_stride: None,
            name: None,
            target: target.map(Valid),
            extensions: None,
            extras: Default::default(),
        })
    }

    /// An accessor of f32 items of `type_` (`values.len()` a multiple of its size), with its
    /// per-component bounds when `bounds` (required for positions and animation inputs).
    fn floats(
        &mut self,
        values: &[f32],
        type_: json::accessor::Type,
        target: Option<json::buffer::Target>,
        bounds: bool,
    ) -> json::Index<json::Accessor> {
        let n = type_.multiplicity();
        let (min, max) = if bounds && !values.is_empty() {
            let mut lo = vec![f32::INFINITY; n];
            let mut hi = vec![f32::NEG_INFINITY; n];
            for item in values.chunks_exact(n) {
                for (k, &x) in item.iter().enumerate() {
                    lo[k] = lo[k].min(x);
                    hi[k] = hi[k].max(x);
                }
            }
            (Some(json::Value::from(lo)), Some(json::Value::from(hi)))
        } else {
            (None, None)
        };
        let view = self.view(values.iter().map(|x| x.to_le_bytes()), target);
        self.root.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: USize64::from(values.len() / n),
            component_type: Valid(json::accessor::GenericComponentType(
                json::accessor::ComponentType::F32,
            )),
            extensions: None,
            extras: Default::default(),
            type_: Valid(type_),
            min,
            max,
            name: None,
            normalized: false,
            sparse: None,
        })
    }

    /// An accessor of triangle indices.
    fn indices(&mut self, values: &[u32]) -> json::Index<json::Accessor> {
        let view = self.view(
            values.iter().map(|x| x.to_le_bytes()),
            Some(json::buffer::Target::ElementArrayBuffer),
        );
        self.root.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: USize64::from(values.len()),
            component_type: Valid(json::accessor::GenericComponentType(
                json::accessor::ComponentType::U32,
            )),
            extensions: None,
            extras: Default::default(),
            type_: Valid(json::accessor::Type::Scalar),
            min: None,
            max: None,
            name: None,
            normalized: false,
            sparse: None,
        })
    }

    /// A material of base colour `colour` (not metallic).
    fn material(
        &mut self,
        name: &str,
        colour: [f32; 4],
        roughness: f32,
    ) -> json::Index<json::Material> {
        self.root.push(json::Material {
            name: Some(name.into()),
            pbr_metallic_roughness: json::material::PbrMetallicRoughness {
                base_color_factor: json::material::PbrBaseColorFactor(colour),
                metallic_factor: json::material::StrengthFactor(0.0),
                roughness_factor: json::material::StrengthFactor(roughness),
                ..Default::default()
            },
            ..Default::default()
        })
    }
}

/// The run as the bytes of a .glb file: the bodies of `world` (as they are now: shapes do not
/// change) moved through `rec`'s frames.
///
/// # Errors
/// No frame, a recorded body no longer in `world`, frames that do not hold every body, a non-finite
/// number, frame times f32 cannot keep strictly increasing, or a file over the 4 GiB a GLB
/// can hold.
pub fn to_glb(rec: &Recording, world: &World) -> Result<Vec<u8>, String> {
    let mut b = Builder {
        root: json::Root {
            asset: json::Asset {
                generator: Some(format!("impulse {}", env!("CARGO_PKG_VERSION"))),
                ..Default::default()
            },
            ..Default::default()
        },
        bin: Vec::new(),
    };
    crate::mesh::check_recording(rec, "--gltf")?;
    let times = f32s(rec.frames.iter().map(|f| f.time), &|| "a frame time".into())?;
    if let Some(w) = times.windows(2).find(|w| w[1] <= w[0]) {
        return Err(format!(
            "--gltf: frame times {} and {} are equal in f32: glTF keyframes must increase",
            w[0], w[1]
        ));
    }
    let input = b.floats(&times, json::accessor::Type::Scalar, None, true);
    let (mut fixed, mut dynamic, mut driven) = (None, None, None);
    let mut body_nodes = Vec::with_capacity(rec.names.len());
    let mut animation = json::Animation {
        extensions: None,
        extras: Default::default(),
        channels: Vec::new(),
        name: Some("run".into()),
        samplers: Vec::new(),
    };
    for (i, (name, &handle)) in rec.names.iter().zip(&rec.handles).enumerate() {
        let body = world
            .body(handle)
            .ok_or_else(|| format!("--gltf: body `{name}` is no longer in the world"))?;
        let material = match body.kind {
            BodyKind::Fixed => *fixed.get_or_insert_with(|| b.material("fixed", FIXED_COLOUR, 0.9)),
            BodyKind::Dynamic => {
                *dynamic.get_or_insert_with(|| b.material("dynamic", DYNAMIC_COLOUR, 0.5))
            }
            BodyKind::Scripted | BodyKind::Link => {
                *driven.get_or_insert_with(|| b.material("driven", DRIVEN_COLOUR, 0.5))
            }
        };
        let mut primitives = Vec::new();
        for (k, t) in body_triangles(body).iter().enumerate() {
            let what = || format!("body `{name}`, piece {k}");
            let positions = f32s(t.positions.iter().flat_map(|p| p.to_array()), &what)?;
            let normals = f32s(t.normals.iter().flat_map(|p| p.to_array()), &what)?;
            let array = Some(json::buffer::Target::ArrayBuffer);
            let position = b.floats(&positions, json::accessor::Type::Vec3, array, true);
            let normal = b.floats(&normals, json::accessor::Type::Vec3, array, false);
            let indices = b.indices(&t.indices);
            primitives.push(json::mesh::Primitive {
                attributes: [
                    (Valid(json::mesh::Semantic::Positions), position),
                    (Valid(json::mesh::Semantic::Normals), normal),
                ]
                .into_iter()
                .collect(),
                extensions: None,
                extras: Default::default(),
                indices: Some(indices),
                material: Some(material),
                mode: Valid(json::mesh::Mode::Triangles),
                targets: None,
            });
        }
        let mesh = b.root.push(json::Mesh {
            extensions: None,
            extras: Default::default(),
            name: Some(name.clone()),
            primitives,
            weights: None,
        });
        // The keyframes: the recorded own frame, rotations kept in one hemisphere.
        let what = || format!("body `{name}`'s state");
        let translations = f32s(
            rec.frames
                .iter()
                .flat_map(|f| f.bodies[i].position.to_array()),
            &what,
        )?;
        let mut previous: Option<DQuat> = None;
        let rotations = f32s(
            rec.frames.iter().flat_map(|f| {
                let mut q = f.bodies[i].rotation.normalize();
                if previous.is_some_and(|p| p.dot(q) < 0.0) {
                    q = -q;
                }
                previous = Some(q);
                q.to_array()
            }),
            &what,
        )?;
        let node = b.root.push(json::Node {
            mesh: Some(mesh),
            name: Some(name.clone()),
            translation: Some([translations[0], translations[1], translations[2]]),
            rotation: Some(json::scene::UnitQuaternion([
                rotations[0],
                rotations[1],
                rotations[2],
                rotations[3],
            ])),
            ..Default::default()
        });
        body_nodes.push(node);
        for (values, type_, path) in [
            (
                &translations,
                json::accessor::Type::Vec3,
                json::animation::Property::Translation,
            ),
            (
                &rotations,
                json::accessor::Type::Vec4,
                json::animation::Property::Rotation,
            ),
        ] {
            let output = b.floats(values, type_, None, false);
            let sampler = json::Index::push(
                &mut animation.samplers,
                json::animation::Sampler {
                    extensions: None,
                    extras: Default::default(),
                    input,
                    interpolation: Valid(json::animation::Interpolation::Linear),
                    output,
                },
            );
            animation.channels.push(json::animation::Channel {
                sampler,
                target: json::animation::Target {
                    extensions: None,
                    extras: Default::default(),
                    node,
                    path: Valid(path),
                },
                extensions: None,
                extras: Default::default(),
            });
        }
    }
    if !animation.channels.is_empty() {
        b.root.push(animation);
    }
    // The root: the scene's up (against gravity) onto glTF's +Y.
    let gravity = world.gravity();
    let up = if gravity.length() > 0.0 {
        -gravity.normalize()
    } else {
        DVec3::Z
    };
    let turn = DQuat::from_rotation_arc(up, DVec3::Y).to_array();
    let turn = f32s(turn, &|| "the world's up".into())?;
    let world_node = b.root.push(json::Node {
        name: Some("world".into()),
        rotation: Some(json::scene::UnitQuaternion([
            turn[0], turn[1], turn[2], turn[3],
        ])),
        children: Some(body_nodes),
        ..Default::default()
    });
    let scene = b.root.push(json::Scene {
        extensions: None,
        extras: Default::default(),
        name: Some("impulse run".into()),
        nodes: vec![world_node],
    });
    b.root.scene = Some(scene);
    b.root.push(json::Buffer {
        byte_length: USize64::from(b.bin.len()),
        name: None,
        uri: None,
        extensions: None,
        extras: Default::default(),
    });
    let text = b
        .root
        .to_vec()
        .map_err(|e| format!("--gltf: cannot write the glTF JSON: {e}"))?;
    container(&text, &b.bin)
}

/// The GLB container: a 12-byte header, the JSON chunk (padded with spaces) and the BIN chunk
/// (padded with zeros), each chunk a multiple of 4 bytes.
fn container(text: &[u8], bin: &[u8]) -> Result<Vec<u8>, String> {
    let padded = |n: usize| n.div_ceil(4) * 4;
    let (json_len, bin_len) = (padded(text.len()), padded(bin.len()));
    let total = 12 + 8 + json_len + 8 + bin_len;
    let too_big =
        || format!("--gltf: the file would be {total} bytes, over the 4 GiB a .glb can hold");
    let total32 = u32::try_from(total).map_err(|_| too_big())?;
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(GLB_MAGIC);
    out.extend_from_slice(&GLB_VERSION.to_le_bytes());
    out.extend_from_slice(&total32.to_le_bytes());
    for (chunk, kind, pad, len) in [
        (text, CHUNK_JSON, b' ', json_len),
        (bin, CHUNK_BIN, 0u8, bin_len),
    ] {
        out.extend_from_slice(&u32::try_from(len).map_err(|_| too_big())?.to_le_bytes());
        out.extend_from_slice(&kind.to_le_bytes());
        out.extend_from_slice(chunk);
        out.resize(out.len() + len - chunk.len(), pad);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use impulse_collide::Convex;
    use impulse_sim::Scene;
    use std::path::PathBuf;

    /// How many f32 roundings a placed vertex may be off the surface, in units of
    /// `f32::EPSILON` times the coordinates' magnitude (the vertex in its own frame, the
    /// keyframe's translation): a vertex and a translation rounded once each, the rotation's
    /// four components once each, with room to spare.
    const F32_ROUNDINGS: f64 = 16.0;

    fn scene(file: &str) -> Scene {
        let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/scenes");
        Scene::read(&path.join(file)).unwrap()
    }

    /// Signed distance of `p` (piece frame) from the piece's surface: exact for a sphere, to
    /// first order for an ellipsoid (its implicit function over the gradient's length), and
    /// the largest face-plane distance for a polyhedron (zero on its surface).
    fn surface_distance(convex: &Convex, p: DVec3) -> f64 {
        match convex {
            Convex::Sphere(s) => p.length() - s.radius(),
            Convex::Ellipsoid(e) => {
                let a = e.semi_axes();
                e.implicit(p) / (2.0 * (p / (a * a)).length())
            }
            Convex::Polyhedron(poly) => poly.max_plane_distance(p),
        }
    }

    /// Runs `file` to `until`, writes the .glb, reads it back with the `gltf` crate, places
    /// every mesh vertex by its node's first keyframe and checks it lies on the surface of its
    /// piece as the simulator places it at the start (the body frame `Body::pose`, the piece's
    /// pose in it), within [`F32_ROUNDINGS`]. Returns how many bodies have an own frame apart
    /// from their body frame (where a mix-up of the two would show).
    fn vertices_on_the_surface(file: &str, until: f64) -> usize {
        let scene = scene(file);
        let start = World::from_scene(&scene).unwrap();
        let mut world = World::from_scene(&scene).unwrap();
        let rec = impulse_sim::run(&mut world, until, scene.desc.output_rate, |_| {}).unwrap();
        let bytes = to_glb(&rec, &world).unwrap();
        let doc = gltf::Gltf::from_slice(&bytes).unwrap();
        let blob = doc.blob.as_deref();
        let data = |_: gltf::Buffer<'_>| blob;
        let mut first = vec![(DVec3::ZERO, DQuat::IDENTITY); doc.nodes().len()];
        for channel in doc.animations().flat_map(|a| a.channels()) {
            let node = channel.target().node().index();
            match channel.reader(data).read_outputs().unwrap() {
                gltf::animation::util::ReadOutputs::Translations(mut t) => {
                    first[node].0 = DVec3::from(t.next().unwrap().map(f64::from));
                }
                gltf::animation::util::ReadOutputs::Rotations(r) => {
                    let q = r.into_f32().next().unwrap().map(f64::from);
                    first[node].1 = DQuat::from_array(q);
                }
                _ => panic!("only translations and rotations are animated"),
            }
        }
        let mut offset_frames = 0;
        let mut drawn = 0;
        for node in doc.nodes() {
            let Some(mesh) = node.mesh() else { continue };
            let name = node.name().unwrap();
            let (_, body) = start.bodies().find(|(_, b)| b.name == name).unwrap();
            if body.frame.translation.length() > 0.0 || body.frame.rotation != DQuat::IDENTITY {
                offset_frames += 1;
            }
            let pieces = body.shape.pieces();
            assert_eq!(mesh.primitives().len(), pieces.len(), "{name}");
            let (t, q) = first[node.index()];
            for (k, primitive) in mesh.primitives().enumerate() {
                let placed = body.pose * pieces[k].pose;
                let positions: Vec<_> = primitive.reader(data).read_positions().unwrap().collect();
                assert!(positions.len() >= 4, "{name}: {} vertices", positions.len());
                for v in positions {
                    let v = DVec3::from(v.map(f64::from));
                    let w = q * v + t;
                    let d = surface_distance(&pieces[k].convex, placed.inverse_transform_point(w));
                    let tol = F32_ROUNDINGS
                        * f64::from(f32::EPSILON)
                        * (v.length() + t.length() + pieces[k].radius);
                    assert!(
                        d.abs() <= tol,
                        "{file}: body `{name}` piece {k}: vertex {w} is {d:.3e} off the \
                         surface (tolerance {tol:.1e})"
                    );
                }
            }
            drawn += 1;
        }
        assert_eq!(
            drawn,
            rec.names.len(),
            "{file}: a node with a mesh per body"
        );
        offset_frames
    }

    /// The frame convention: each mesh vertex, placed by its node's first keyframe, lies on
    /// its body's shape where the simulator puts it — for balls and boxes (pool break), an
    /// exact ellipsoid (rattleback), multibody links (see-saw) and compounds of convex pieces
    /// (balls in a dish). Some of these bodies have their own frame apart from their
    /// mass-centred body frame, so a mesh left in the body frame fails here.
    #[test]
    fn placed_vertices_lie_on_the_shapes() {
        let offset: usize = [
            ("pool-break.ron", 0.005),
            ("rattleback.ron", 0.01),
            ("see-saw.ron", 0.02),
            ("balls-in-dish.ron", 0.02),
        ]
        .into_iter()
        .map(|(file, until)| vertices_on_the_surface(file, until))
        .sum();
        assert!(
            offset > 0,
            "no body whose own frame differs from its body frame"
        );
    }

    /// A recording `to_glb` cannot write faithfully is an error naming why, not a panic or an
    /// invalid file: no frame, frame times equal in f32, a non-finite state.
    #[test]
    fn bad_recordings_are_refused() {
        let world = World::from_scene(&scene("two-ball-collision.ron")).unwrap();
        let mut frame = impulse_sim::Frame::of(&world);
        frame.time = 1.0;
        let mut rec = impulse_sim::Recording {
            names: world.bodies().map(|(_, b)| b.name.clone()).collect(),
            handles: world.bodies().map(|(h, _)| h).collect(),
            ..Default::default()
        };
        let refused = |rec: &Recording, why: &str| match to_glb(rec, &world) {
            Ok(bytes) => panic!("accepted ({} bytes), expected `{why}`", bytes.len()),
            Err(e) => assert!(e.contains(why), "{e}"),
        };
        refused(&rec, "no frame");
        let mut close = frame.clone();
        close.time += 1e-12;
        rec.frames = vec![frame.clone(), close];
        refused(&rec, "equal in f32");
        let mut bad = frame.clone();
        bad.time += 0.1;
        bad.bodies[0].position.x = f64::NAN;
        rec.frames = vec![frame.clone(), bad];
        refused(&rec, "not a finite f32");
        rec.frames = vec![frame];
        assert!(to_glb(&rec, &world).is_ok());
    }
}
