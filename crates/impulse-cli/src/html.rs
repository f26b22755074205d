//! `impulse run --html out.html` (and `impulse reduce --html`): the run as one self-contained
//! web page that replays it with WebGL, for a user who wants to watch what happened before
//! reading numbers.
//!
//! The page is written from a [`Replay`], which knows nothing of how the run was made: bodies
//! with triangles, frames of poses, impacts. [`Replay::of_run`] makes one of a rigid-body run
//! (multibody links are bodies, named `<multibody>/<link>`); `impulse reduce` makes one of a
//! FORK⁻¹S reduced mechanism (its links are bodies).
//!
//! The page needs no network: the renderer and its controls (`viewer/*.js`,
//! `viewer/viewer.css`, `viewer/viewer.html`, plain JavaScript written for this page, no
//! library) are compiled into the program with `include_str!` and written inline, and the run
//! itself is one base64 block of little-endian binary data described by a small JSON header.
//!
//! ## What the page gets (of a rigid-body run)
//! - Every body, drawn from the triangles `--gltf` draws ([`crate::mesh`]), with its name and
//!   kind (fixed bodies in a muted colour). Bodies with the same triangles share one mesh (a
//!   row of dominos is one mesh).
//! - Per recorded frame (the frames of `--out`): the time, every body's own-frame position and
//!   rotation (the `x … qw` columns), its speed ‖v‖ (centre of mass, m/s) and its energy
//!   (kinetic plus potential, J; not a number for bodies without mass: fixed, scripted), and
//!   the world's kinetic and potential energy.
//! - The impacts: collisions (and fallback impulses) of the run's event log, with time, point,
//!   the two bodies and the impulse's magnitude, drawn as markers on the time line and as
//!   flashes at the contact point. Microcollisions (resting contact) are left out: at rest
//!   there are thousands per second and they would hide the impacts. At most [`MAX_EVENTS`],
//!   the strongest.
//!
//! ## Layout of the data block
//! All numbers are 4 bytes (f32 or u32, little-endian), sections back to back in this order,
//! with the counts in the header: for each mesh its positions (3 f32 per vertex), normals (3
//! f32 per vertex) and triangle indices (u32); the frame times (F); the poses (F × B × 7: x y z
//! qx qy qz qw); the speeds (F × B); the energies (F × B); the world's kinetic and potential
//! energy (F × 2); the events' numbers (E × 5: time, x, y, z, |impulse|) and their bodies (E
//! × 2 u32 indices into the body list, [`NO_BODY`] for none). Positions are rounded to f32
//! here, the one place, as in `--gltf`.

use std::collections::HashMap;
use std::path::Path;

use base64::Engine as _;
use impulse_geom::{DMat3, DQuat, DVec3};
use impulse_sim::body::{Body, BodyKind};
use impulse_sim::contact::ContactKind;
use impulse_sim::{BodyState, ContactEvent, Recording, Scene, World};
use serde_json::json;

use crate::mesh::{Triangles, body_triangles};

/// The page's markup (the body of the document, without the data and the script).
const MARKUP: &str = include_str!("../viewer/viewer.html");
/// The page's style sheet.
const STYLE: &str = include_str!("../viewer/viewer.css");
/// The renderer and its controls: four files of one script, joined in this order inside one
/// function (one scope, strict mode); `viewer/data.js` says what each holds.
const SCRIPT: [&str; 4] = [
    include_str!("../viewer/data.js"),
    include_str!("../viewer/render.js"),
    include_str!("../viewer/panels.js"),
    include_str!("../viewer/controls.js"),
];

/// The version of the data layout the script reads (checked by the script).
pub const FORMAT: &str = "impulse-viewer 1";
/// Most impacts a page shows; beyond it the strongest are kept (a run with more impacts than
/// this has more than a time line of markers can show anyway).
pub const MAX_EVENTS: usize = 20_000;
/// A page larger than this (bytes) is written with a warning: browsers open it slowly.
pub const LARGE_PAGE_BYTES: usize = 200_000_000;
/// The body index of an event's missing body (a contact with the world).
pub const NO_BODY: u32 = u32::MAX;

/// Refuses a `--html` file name that does not end in `.html` or `.htm` (checked before the
/// run).
///
/// # Errors
/// A message naming the path.
pub fn check_path(path: &Path) -> Result<(), String> {
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match extension.as_deref() {
        Some("html" | "htm") => Ok(()),
        _ => Err(format!(
            "--html {}: the file name must end in .html",
            path.display()
        )),
    }
}

/// Writes the run as a page at `path`, titled after the file.
///
/// # Errors
/// What [`Replay::of_run`] and [`Replay::to_html`] refuse, or the file that cannot be written.
pub fn write(path: &Path, rec: &Recording, world: &World, scene: &Scene) -> Result<(), String> {
    let replay = Replay::of_run(rec, world, scene, &title_of(path))?;
    write_replay(path, &replay)
}

/// The page's title: the file's name without its extension.
pub fn title_of(path: &Path) -> String {
    path.file_stem().map_or_else(
        || "impulse run".into(),
        |s| s.to_string_lossy().into_owned(),
    )
}

/// Writes `replay` as a page at `path`.
///
/// # Errors
/// What [`Replay::to_html`] refuses, or the file that cannot be written, named.
pub fn write_replay(path: &Path, replay: &Replay) -> Result<(), String> {
    let text = replay.to_html()?;
    if text.len() > LARGE_PAGE_BYTES {
        eprintln!(
            "warning: --html {}: the page is {:.0} MB ({} frames of {} bodies); browsers may be \
             slow to open it: lower the scene's output_rate or --until",
            path.display(),
            text.len() as f64 / 1e6,
            replay.frames.len(),
            replay.bodies.len()
        );
    }
    std::fs::write(path, text).map_err(|e| format!("cannot write {}: {e}", path.display()))
}

/// How a body is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// Does not move (muted grey).
    Fixed,
    /// Moved by the dynamics (orange).
    Dynamic,
    /// Moved by a script or a multibody (blue).
    Driven,
}

impl Kind {
    fn name(self) -> &'static str {
        match self {
            Kind::Fixed => "fixed",
            Kind::Dynamic => "dynamic",
            Kind::Driven => "driven",
        }
    }
}

/// A body of a replay: what the page draws and names.
#[derive(Clone, Debug)]
pub struct ReplayBody {
    /// Its name.
    pub name: String,
    /// How it is drawn.
    pub kind: Kind,
    /// Its triangles in its own frame (the frame of its recorded position and rotation).
    pub triangles: Vec<Triangles>,
}

/// One frame of a replay: the time and each body's state, in the order of the bodies.
#[derive(Clone, Debug)]
pub struct ReplayFrame {
    /// Simulated time (s).
    pub time: f64,
    /// Each body's own-frame position and rotation (world).
    pub poses: Vec<(DVec3, DQuat)>,
    /// Each body's speed (m/s; `NaN`: unknown).
    pub speeds: Vec<f64>,
    /// Each body's energy (J; `NaN`: unknown).
    pub energies: Vec<f64>,
    /// The world's kinetic and potential energy (J; `NaN`: unknown, no plot).
    pub energy: (f64, f64),
}

/// An impact shown on the time line and flashed where it happened.
#[derive(Clone, Copy, Debug)]
pub struct Impact {
    /// Simulated time (s).
    pub time: f64,
    /// Contact point (world).
    pub point: DVec3,
    /// The two bodies (indices into the replay's bodies; [`NO_BODY`] for none).
    pub bodies: [u32; 2],
    /// Magnitude of the impulse (N·s).
    pub impulse: f64,
}

/// What a page replays, whatever made it: a rigid-body run (multibody links are bodies), or a
/// FORK⁻¹S reduced mechanism (its links are bodies).
#[derive(Clone, Debug)]
pub struct Replay {
    /// The page's title.
    pub title: String,
    /// The world's up (against gravity; +Z without gravity).
    pub up: DVec3,
    /// What simulated it, shown under the title (e.g. `switching contact`).
    pub model: String,
    /// The bodies.
    pub bodies: Vec<ReplayBody>,
    /// The frames, in time order.
    pub frames: Vec<ReplayFrame>,
    /// The impacts, in time order.
    pub impacts: Vec<Impact>,
}

/// The little-endian data block being written.
#[derive(Default)]
struct Block(Vec<u8>);

impl Block {
    /// Appends f32s, refusing a non-finite number where `finite` (a position, a time).
    fn floats(
        &mut self,
        values: impl IntoIterator<Item = f64>,
        finite: bool,
        what: &dyn Fn() -> String,
    ) -> Result<(), String> {
        for x in values {
            let y = if finite {
                crate::mesh::finite_f32(x, "--html", what)?
            } else {
                x as f32
            };
            self.0.extend(y.to_le_bytes());
        }
        Ok(())
    }

    fn u32s(&mut self, values: impl IntoIterator<Item = u32>) {
        for x in values {
            self.0.extend(x.to_le_bytes());
        }
    }
}

/// A body's energy in state `s`: `½ m v² + ½ ω·Iω − m g·c` (J), `NaN` without mass.
///
/// The inertia is the body's principal moments turned by the rotation of its body frame,
/// which is the recorded own frame times the inverse of the body's fixed offset
/// ([`Body::frame`]: own = body frame × offset).
pub fn body_energy(body: &Body, s: &BodyState, gravity: DVec3) -> f64 {
    let Some(m) = body.mass else { return f64::NAN };
    let r = DMat3::from_quat(s.rotation * body.frame.rotation.inverse());
    let inertia = r * DMat3::from_diagonal(m.moments) * r.transpose();
    0.5 * m.mass * s.velocity.length_squared() + 0.5 * s.omega.dot(inertia * s.omega)
        - m.mass * gravity.dot(s.com)
}

/// The impacts a page shows: collisions and fallback impulses, the [`MAX_EVENTS`] strongest,
/// in time order.
fn impacts(events: &[ContactEvent]) -> Vec<&ContactEvent> {
    let mut shown: Vec<&ContactEvent> = events
        .iter()
        .filter(|e| matches!(e.kind, ContactKind::Collision | ContactKind::Fallback))
        .collect();
    if shown.len() > MAX_EVENTS {
        shown.sort_by(|a, b| b.impulse.length().total_cmp(&a.impulse.length()));
        shown.truncate(MAX_EVENTS);
    }
    shown.sort_by(|a, b| a.time.total_cmp(&b.time));
    shown
}

/// The world's up: against gravity, +Z without gravity.
pub fn up_of(gravity: DVec3) -> DVec3 {
    if gravity.length() > 0.0 {
        -gravity.normalize()
    } else {
        DVec3::Z
    }
}

impl Replay {
    /// A rigid-body run: the bodies of `world` (shapes do not change) moved through `rec`'s
    /// frames, with `world`'s event log as impacts (empty unless [`World::set_event_log`] was
    /// on).
    ///
    /// # Errors
    /// No frame, a recorded body no longer in `world`, or frames that do not hold every body.
    pub fn of_run(
        rec: &Recording,
        world: &World,
        scene: &Scene,
        title: &str,
    ) -> Result<Self, String> {
        crate::mesh::check_recording(rec, "--html")?;
        let mut bodies = Vec::with_capacity(rec.names.len());
        for (name, &handle) in rec.names.iter().zip(&rec.handles) {
            let body = world
                .body(handle)
                .ok_or_else(|| format!("--html: body `{name}` is no longer in the world"))?;
            bodies.push(body);
        }
        let gravity = world.gravity();
        let frames = rec
            .frames
            .iter()
            .map(|f| ReplayFrame {
                time: f.time,
                poses: f.bodies.iter().map(|s| (s.position, s.rotation)).collect(),
                speeds: f.bodies.iter().map(|s| s.velocity.length()).collect(),
                energies: f
                    .bodies
                    .iter()
                    .zip(&bodies)
                    .map(|(s, b)| body_energy(b, s, gravity))
                    .collect(),
                energy: (f.kinetic_energy, f.potential_energy),
            })
            .collect();
        let index: HashMap<_, _> = rec
            .handles
            .iter()
            .enumerate()
            .map(|(i, &h)| (h, i as u32))
            .collect();
        let body_index = |h| index.get(&h).copied().unwrap_or(NO_BODY);
        let impacts = impacts(world.events())
            .into_iter()
            .map(|e| Impact {
                time: e.time,
                point: e.point,
                bodies: [body_index(e.a), body_index(e.b)],
                impulse: e.impulse.length(),
            })
            .collect();
        Ok(Self {
            title: title.to_owned(),
            up: up_of(gravity),
            model: match scene.desc.contact_model {
                impulse_sim::ContactMode::Switching => "switching contact model".into(),
                impulse_sim::ContactMode::Impulse => "impulse contact model".into(),
            },
            bodies: bodies
                .iter()
                .zip(&rec.names)
                .map(|(b, name)| ReplayBody {
                    name: name.clone(),
                    kind: match b.kind {
                        BodyKind::Fixed => Kind::Fixed,
                        BodyKind::Dynamic => Kind::Dynamic,
                        BodyKind::Scripted | BodyKind::Link => Kind::Driven,
                    },
                    triangles: body_triangles(b),
                })
                .collect(),
            frames,
            impacts,
        })
    }

    /// The page.
    ///
    /// # Errors
    /// No frame, a frame that does not hold every body, or a non-finite position, rotation,
    /// time or vertex.
    pub fn to_html(&self) -> Result<String, String> {
        let (frames, b) = (&self.frames, self.bodies.len());
        if frames.is_empty() {
            return Err("--html: the run recorded no frame".into());
        }
        if let Some(f) = frames
            .iter()
            .find(|f| f.poses.len() != b || f.speeds.len() != b || f.energies.len() != b)
        {
            return Err(format!(
                "--html: the frame at t = {} does not hold the {b} bodies",
                f.time
            ));
        }
        let mut block = Block::default();

        // The meshes, one per distinct set of triangles.
        let mut meshes = Vec::new();
        let mut mesh_of: HashMap<Vec<u8>, usize> = HashMap::new();
        let mut body_meshes = Vec::with_capacity(b);
        let mut radii = Vec::with_capacity(b);
        for body in &self.bodies {
            let (mut positions, mut normals, mut indices) = (Vec::new(), Vec::new(), Vec::new());
            for t in &body.triangles {
                let base = (positions.len() / 3) as u32;
                positions.extend(t.positions.iter().flat_map(|p| p.to_array()));
                normals.extend(t.normals.iter().flat_map(|p| p.to_array()));
                indices.extend(t.indices.iter().map(|i| base + i));
            }
            radii.push(
                body.triangles
                    .iter()
                    .flat_map(|t| &t.positions)
                    .map(|p| p.length())
                    .fold(0.0, f64::max),
            );
            let mut bytes = Block::default();
            let what = || format!("body `{}`'s mesh", body.name);
            bytes.floats(positions.iter().copied(), true, &what)?;
            bytes.floats(normals.iter().copied(), true, &what)?;
            bytes.u32s(indices.iter().copied());
            let k = match mesh_of.get(&bytes.0) {
                Some(&k) => k,
                None => {
                    meshes.push(json!({"vertices": positions.len() / 3, "indices": indices.len()}));
                    block.0.extend_from_slice(&bytes.0);
                    mesh_of.insert(bytes.0, meshes.len() - 1);
                    meshes.len() - 1
                }
            };
            body_meshes.push(k);
        }

        // The frames.
        block.floats(frames.iter().map(|f| f.time), true, &|| {
            "a frame time".into()
        })?;
        for f in frames {
            let what = || format!("the state at t = {}", f.time);
            block.floats(
                f.poses.iter().flat_map(|(p, q)| {
                    let q = q.normalize();
                    [p.x, p.y, p.z, q.x, q.y, q.z, q.w]
                }),
                true,
                &what,
            )?;
        }
        for f in frames {
            block.floats(f.speeds.iter().copied(), false, &String::new)?;
        }
        for f in frames {
            block.floats(f.energies.iter().copied(), false, &String::new)?;
        }
        block.floats(
            frames.iter().flat_map(|f| [f.energy.0, f.energy.1]),
            false,
            &String::new,
        )?;

        // The impacts.
        let events = &self.impacts;
        block.floats(
            events
                .iter()
                .flat_map(|e| [e.time, e.point.x, e.point.y, e.point.z, e.impulse]),
            false,
            &String::new,
        )?;
        block.u32s(events.iter().flat_map(|e| e.bodies));

        let header = json!({
            "format": FORMAT,
            "title": self.title,
            "model": self.model,
            "generator": format!("impulse {}", env!("CARGO_PKG_VERSION")),
            "up": self.up.to_array(),
            "bodies": self.bodies.iter().zip(&body_meshes).zip(&radii).map(|((body, &mesh), &radius)| json!({
                "name": body.name,
                "kind": body.kind.name(),
                "mesh": mesh,
                "radius": radius,
            })).collect::<Vec<_>>(),
            "meshes": meshes,
            "frames": frames.len(),
            "events": events.len(),
            "bytes": block.0.len(),
        });
        Ok(page(&self.title, &header.to_string(), &block.0))
    }
}

/// Text safe inside an HTML element (`&`, `<`, `>` escaped).
fn html_text(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// The document: markup, style, the header (JSON, `<` escaped so no string can close its
/// script element), the data block (base64) and the script.
fn page(title: &str, header: &str, data: &[u8]) -> String {
    let data = base64::engine::general_purpose::STANDARD.encode(data);
    let header = header.replace('<', "\\u003c");
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n\
         <title>{} — impulse</title>\n<style>\n{STYLE}</style>\n</head>\n<body>\n{MARKUP}\
         <script type=\"application/json\" id=\"impulse-header\">{header}</script>\n\
         <script type=\"application/octet-stream\" id=\"impulse-data\">{data}</script>\n\
         <script>\n\"use strict\";\n(function () {{\n{}}})();\n</script>\n</body>\n</html>\n",
        html_text(title),
        SCRIPT.concat()
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn scene(file: &str) -> Scene {
        let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/scenes");
        Scene::read(&path.join(file)).unwrap()
    }

    /// Runs `scene` to `until` with the event log on; returns the world and the recording.
    fn run(scene: &Scene, until: f64) -> (World, Recording) {
        let mut world = World::from_scene(scene).unwrap();
        world.set_event_log(true);
        let rec = impulse_sim::run(&mut world, until, scene.desc.output_rate, |_| {}).unwrap();
        (world, rec)
    }

    /// The text of the element `<script … id="{id}">…</script>` of `page`.
    fn element<'a>(page: &'a str, id: &str) -> &'a str {
        let open = format!("id=\"{id}\">");
        let start = page.find(&open).unwrap() + open.len();
        let end = start + page[start..].find("</script>").unwrap();
        &page[start..end]
    }

    /// The page's header and data block, read back as the script reads them.
    fn read_back(page: &str) -> (serde_json::Value, Vec<u8>) {
        let header = serde_json::from_str(element(page, "impulse-header")).unwrap();
        let data = base64::engine::general_purpose::STANDARD
            .decode(element(page, "impulse-data").trim())
            .unwrap();
        (header, data)
    }

    fn f32_at(data: &[u8], word: usize) -> f32 {
        f32::from_le_bytes(data[4 * word..4 * word + 4].try_into().unwrap())
    }

    /// The data block, read back by its documented layout, holds the recorded states: every
    /// body's position and rotation at the first and last frame to f32 rounding, the frame
    /// times, the world's energies; bodies of one shape share one mesh; the sections fill the
    /// block exactly. Pool break: 21 bodies, 4 shapes (table, two rails, ball), impacts.
    #[test]
    fn the_data_block_holds_the_recording() {
        let scene = scene("pool-break.ron");
        let (world, rec) = run(&scene, 0.2);
        let page = Replay::of_run(&rec, &world, &scene, "pool")
            .unwrap()
            .to_html()
            .unwrap();
        let (h, data) = read_back(&page);
        assert_eq!(h["format"], FORMAT);
        assert_eq!(h["bytes"].as_u64().unwrap() as usize, data.len());
        let b = rec.names.len();
        let f = rec.frames.len();
        let e = h["events"].as_u64().unwrap() as usize;
        assert!(e > 0, "the break has impacts");
        let meshes = h["meshes"].as_array().unwrap();
        assert_eq!(meshes.len(), 4, "table, long rail, short rail, ball");
        let mut word: usize = meshes
            .iter()
            .map(|m| {
                6 * m["vertices"].as_u64().unwrap() as usize
                    + m["indices"].as_u64().unwrap() as usize
            })
            .sum();
        let times = word;
        let poses = times + f;
        word = poses + 7 * f * b + 2 * f * b;
        let totals = word;
        word += 2 * f + 7 * e;
        assert_eq!(4 * word, data.len(), "sections fill the block");
        let close = |a: f32, x: f64| (f64::from(a) - x).abs() <= 1e-6 * x.abs().max(1.0);
        for (k, frame) in [(0, &rec.frames[0]), (f - 1, &rec.frames[f - 1])] {
            assert!(close(f32_at(&data, times + k), frame.time));
            assert!(close(f32_at(&data, totals + 2 * k), frame.kinetic_energy));
            assert!(close(
                f32_at(&data, totals + 2 * k + 1),
                frame.potential_energy
            ));
            for (i, s) in frame.bodies.iter().enumerate() {
                let at = poses + 7 * (k * b + i);
                let got: Vec<f64> = (0..7).map(|c| f64::from(f32_at(&data, at + c))).collect();
                let p = DVec3::new(got[0], got[1], got[2]);
                let q = DQuat::from_xyzw(got[3], got[4], got[5], got[6]);
                assert!(
                    (p - s.position).length() <= 1e-6,
                    "{}: {p} vs {}",
                    rec.names[i],
                    s.position
                );
                assert!(q.dot(s.rotation).abs() >= 1.0 - 1e-6, "{}", rec.names[i]);
            }
        }
        for (i, name) in rec.names.iter().enumerate() {
            assert_eq!(h["bodies"][i]["name"], name.as_str());
        }
    }

    /// Each body's energy, summed over the bodies, is the world's own total at every frame: a
    /// rattleback (an ellipsoid with point masses, so its own frame is apart from its
    /// mass-centred body frame) rocking and spinning, where an inertia turned by the wrong
    /// frame gives a different rotational energy.
    #[test]
    fn body_energies_sum_to_the_worlds() {
        let scene = scene("rattleback.ron");
        let (world, rec) = run(&scene, 0.3);
        let bodies: Vec<&Body> = rec
            .handles
            .iter()
            .map(|&h| world.body(h).unwrap())
            .collect();
        assert!(
            bodies.iter().any(|b| b.frame.rotation != DQuat::IDENTITY),
            "a body whose own frame is turned from its body frame"
        );
        for frame in &rec.frames {
            let sum: f64 = frame
                .bodies
                .iter()
                .zip(&bodies)
                .map(|(s, b)| body_energy(b, s, world.gravity()))
                .filter(|e| !e.is_nan())
                .sum();
            let total = frame.kinetic_energy + frame.potential_energy;
            assert!(
                (sum - total).abs() <= 1e-12 * total.abs().max(frame.kinetic_energy) + 1e-15,
                "t = {}: bodies {sum}, world {total}",
                frame.time
            );
        }
    }

    /// A body name that holds markup, quotes and control characters reaches the page intact and
    /// cannot end its script element early.
    #[test]
    fn hostile_names_stay_inside_the_header() {
        let name = "a</script><b>\"x\u{1}\\";
        let text = format!(
            "Scene(name: \"names\", bodies: [Body(name: {:?}, shape: Sphere(radius: 0.1), position: (0.0, 0.0, 1.0))])",
            name
        );
        let scene = Scene {
            desc: impulse_sim::SceneDesc::from_ron(&text, "names.ron").unwrap(),
            base_dir: PathBuf::new(),
        };
        let (world, rec) = run(&scene, 0.02);
        let page = Replay::of_run(&rec, &world, &scene, "<title>")
            .unwrap()
            .to_html()
            .unwrap();
        let (h, _) = read_back(&page);
        assert_eq!(h["bodies"][0]["name"], name);
        assert_eq!(h["title"], "<title>");
        assert_eq!(
            page.matches("</script>").count(),
            3,
            "three script elements"
        );
        assert!(page.contains("<title>&lt;title&gt; — impulse</title>"));
    }

    #[test]
    fn the_file_must_be_html() {
        assert!(check_path(Path::new("out.html")).is_ok());
        assert!(check_path(Path::new("out.HTM")).is_ok());
        assert!(check_path(Path::new("html")).is_err());
        let e = check_path(Path::new("out.glb")).unwrap_err();
        assert!(e.contains("out.glb") && e.contains(".html"), "{e}");
    }
}
