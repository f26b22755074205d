//! `cargo xtask viewer` (a step of `ci`): the pages of `impulse run --html`, opened in headless
//! Chromium ([`crate::browser`]) and checked from the outside.
//!
//! For the bundled dominos, pool-break and rattleback scenes, a multibody (the URDF arm), a
//! FORK⁻¹S reduced mechanisms (`impulse reduce` of the six-legged robot falling onto the
//! ground, and of the loaded Y, whose massless base has nothing to draw) and a generated scene of [`FIFTY`] bodies tumbling for [`FIFTY_SECONDS`] s, the step
//! runs `impulse run <scene> --html <page> --out <csv>` (or `impulse reduce`) and then, for
//! each page:
//! - it opens with no console error, uncaught exception or error log entry, and holds as many
//!   frames as the CSV;
//! - **the bodies are drawn where the trajectory says**: at the first and the last frame, each
//!   moving body (up to [`MAX_CHECKED`]) in turn is selected and drawn alone (the page paints
//!   it magenta). A point inside it, off its centre ([`PROBE_DEPTH`] toward its surface along
//!   its longest axis, from the scene's shapes), is placed by the position and rotation of the
//!   CSV (not the page's data), projected with the page's camera matrix, and the screenshot
//!   must show magenta within [`HIT_PX`] pixels of it, for every body. A body drawn at the
//!   wrong place, turned the wrong way or offset from its own frame misses;
//! - **clicking a body picks it**: with every body drawn, a real mouse click on a body seen at
//!   the end selects it (of up to [`MAX_PICKS`], as one may hide behind another);
//! - **scrubbing changes the picture**: a real click on the time slider at 3/4 of its width
//!   moves the time cursor there (within [`SCRUB_TOLERANCE`] of the run) and changes at least
//!   [`MIN_CHANGED_PIXELS`] of the view's pixels;
//! - for the fifty-body page: its size is under [`MAX_PAGE_BYTES`], and it plays at
//!   [`MIN_FPS`] frames per second or faster, measured from `requestAnimationFrame`
//!   timestamps over [`PLAY_SECONDS`] s of playback (the best of up to [`PLAY_ATTEMPTS`]);
//!   below that rate it passes only if drawing a frame takes at most [`MAX_DRAW_SHARE`] of
//!   the frame's time (the machine, not the page, was slow).
//!
//! Screenshots at the start, the middle (first moving body selected) and the end of each run
//! are written to `target/viewer/`; `docs/viewer.png`, the README's picture, is
//! `pool-break-middle.png`.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use impulse_collide::Convex;
use impulse_geom::{DQuat, DVec3};
use serde_json::Value;

use crate::browser::{Browser, Image};
use crate::{Result, cargo, workspace_root};

/// How the step builds the `impulse` program it runs.
const BUILD: [&str; 4] = ["test", "--workspace", "--no-run", "--quiet"];
/// Bodies of the generated playback scene (a 30 s, 50-body run: the page's
/// frame-rate check at a size a user meets).
pub const FIFTY: usize = 50;
/// Simulated length of the generated playback scene (s).
pub const FIFTY_SECONDS: f64 = 30.0;
/// Largest page the fifty-body run may give (bytes).
pub const MAX_PAGE_BYTES: u64 = 10 * 1024 * 1024;
/// Slowest playback accepted (frames per second, from the mean frame interval).
pub const MIN_FPS: f64 = 30.0;
/// Wall seconds of playback over which the frame rate is measured.
pub const PLAY_SECONDS: f64 = 3.0;
/// Playback measurements made at most before the page is called too slow (the best counts:
/// a loaded machine slows one measurement, not a page that cannot keep up).
pub const PLAY_ATTEMPTS: usize = 3;
/// Share of a frame at [`MIN_FPS`] that the page's own drawing (p95) may take when the
/// measured rate is below [`MIN_FPS`] for the run to pass: a busy machine lowers the rate
/// while the drawing stays fast; a page too heavy to play fails both. Default `0.5`.
pub const MAX_DRAW_SHARE: f64 = 0.5;
/// Wall seconds of playback before the frame rate is measured.
pub const WARM_UP_SECONDS: f64 = 1.0;
/// The page's size in CSS pixels (device scale 1).
pub const PAGE: (u32, u32) = (1200, 750);
/// How far (pixels) from a body's projected centre its highlight may be found.
pub const HIT_PX: i64 = 2;
/// Share of (body, time) checks whose highlight must be found (drawn alone, no body is
/// hidden: all).
pub const MIN_HIT_SHARE: f64 = 1.0;
/// How far from the centre of mass toward the body's surface the checked point lies (0 the
/// centre, 1 the surface).
pub const PROBE_DEPTH: f64 = 0.6;
/// Most moving bodies checked per page and time.
pub const MAX_CHECKED: usize = 12;
/// The drag (CSS pixels, to the right) of the orbit check.
pub const ORBIT_DRAG_PX: f64 = 60.0;
/// The wheel turn (pixels, away from the user: zoom in) of the zoom check.
pub const ZOOM_WHEEL: f64 = 200.0;
/// How much a body's distance from the target on screen must grow under that wheel turn.
pub const ZOOM_MIN_GAIN: f64 = 1.1;
/// Most bodies clicked in the picking check (a clicked body may be hidden behind another).
pub const MAX_PICKS: usize = 5;
/// How far the time after a click on the slider may be from the clicked place, as a share of
/// the run (the slider's thumb takes some of its width).
pub const SCRUB_TOLERANCE: f64 = 0.05;
/// Pixels of the view that scrubbing must change (an unchanged picture changes none: the
/// drawing is deterministic).
pub const MIN_CHANGED_PIXELS: u64 = 100;

/// One page to check.
struct Page {
    name: &'static str,
    /// A scene file for `impulse run`, or a mechanism file for `impulse reduce`.
    scene: PathBuf,
    /// `impulse reduce` with these arguments (after the mechanism), not `impulse run`.
    reduce: Option<&'static [&'static str]>,
    frame_rate: bool,
}

impl Page {
    fn run(name: &'static str, scene: PathBuf) -> Self {
        Self {
            name,
            scene,
            reduce: None,
            frame_rate: false,
        }
    }
}

/// Runs the viewer test.
///
/// # Errors
/// No Chromium, a run or a check that fails (named, with what was measured).
pub fn run() -> Result<()> {
    let program = crate::browser::find()?;
    let root = workspace_root();
    let target =
        std::env::var_os("CARGO_TARGET_DIR").map_or_else(|| root.join("target"), PathBuf::from);
    let out = target.join("viewer");
    std::fs::create_dir_all(&out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
    // The `impulse` program as `cargo test --workspace` builds it (for the CLI's end-to-end
    // tests): in `ci` that step has just built it, so this does nothing. `cargo build -p
    // impulse-cli` would resolve the dependencies' features apart from the workspace's tests
    // and rebuild 32 crates (100 s of the step on 2 cores, measured).
    let status = Command::new(cargo())
        .args(BUILD)
        .current_dir(&root)
        .status()
        .map_err(|e| format!("cannot run cargo: {e}"))?;
    if !status.success() {
        return Err(format!("`cargo {}` failed", BUILD.join(" ")));
    }
    let impulse = target.join("debug").join("impulse");
    let fifty = out.join("fifty.ron");
    std::fs::write(&fifty, fifty_scene())
        .map_err(|e| format!("cannot write {}: {e}", fifty.display()))?;
    let scenes = root.join("fixtures/scenes");
    let mechanisms = root.join("fixtures/mechanisms");
    let pages = [
        Page::run("dominos", scenes.join("dominos.ron")),
        Page::run("pool-break", scenes.join("pool-break.ron")),
        Page::run("rattleback", scenes.join("rattleback.ron")),
        // A multibody: its links are bodies of the page.
        Page::run("urdf-arm", scenes.join("urdf-arm.ron")),
        // FORK⁻¹S reduced mechanisms: on a free base, falling onto the ground; and a Y on a
        // massless fixed base (a body with nothing to draw) under a load.
        Page {
            reduce: Some(&["--until", "0.5", "--ground", "-0.3"]),
            ..Page::run("legged", mechanisms.join("legged-6.ron"))
        },
        Page {
            reduce: Some(&["--until", "0.3", "--load", "a3:100,0,0"]),
            ..Page::run("y", mechanisms.join("y.ron"))
        },
        Page {
            frame_rate: true,
            ..Page::run("fifty", fifty)
        },
    ];
    let mut browser = Browser::start(&program, &out.join("chromium"), PAGE.0, PAGE.1)?;
    let mut report = String::new();
    let mut failed = Vec::new();
    for page in &pages {
        let started = Instant::now();
        let html = out.join(format!("{}.html", page.name));
        let csv = out.join(format!("{}.csv", page.name));
        let mut command = Command::new(&impulse);
        match page.reduce {
            None => command.arg("run").arg(&page.scene),
            Some(args) => command.arg("reduce").arg(&page.scene).args(args),
        };
        let run = command
            .arg("--html")
            .arg(&html)
            .arg("--out")
            .arg(&csv)
            .output()
            .map_err(|e| format!("cannot run {}: {e}", impulse.display()))?;
        if !run.status.success() {
            return Err(format!(
                "impulse run {} failed: {}",
                page.scene.display(),
                String::from_utf8_lossy(&run.stderr)
            ));
        }
        let ran = started.elapsed();
        // Every page is checked; the step fails after the report if one failed.
        let line = match check_page(&mut browser, page, &html, &csv, &out) {
            Ok(line) => line,
            Err(e) => {
                failed.push(page.name);
                format!("FAILED: {e}")
            }
        };
        let _ = writeln!(
            report,
            "  {:<11} {line} (run {:.1} s, checks {:.1} s)",
            page.name,
            ran.as_secs_f64(),
            (started.elapsed() - ran).as_secs_f64()
        );
    }
    print!("viewer pages (Chromium {}):\n{report}", version(&program));
    if failed.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "viewer: the pages of {} failed (above)",
            failed.join(", ")
        ))
    }
}

/// The browser's version line, for the report.
fn version(program: &Path) -> String {
    Command::new(program)
        .arg("--version")
        .output()
        .ok()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_owned())
        .unwrap_or_default()
}

/// The generated playback scene: [`FIFTY`] bodies (balls, boxes, ellipsoids, hexagonal
/// slabs) tumbling and drifting apart in a grid, without gravity, for [`FIFTY_SECONDS`] s. The
/// playback test needs many bodies that move for a long time; without gravity they never come
/// to rest, never leave the view and cost the simulator almost nothing (no contact), so the
/// step stays short.
fn fifty_scene() -> String {
    let mut s = format!(
        "// Written by `cargo xtask viewer`: {FIFTY} bodies tumbling without gravity (playback test).\n\
         Scene(\n    name: \"fifty bodies\",\n    gravity: (0.0, 0.0, 0.0),\n    duration: {FIFTY_SECONDS:.1},\n    bodies: [\n"
    );
    for k in 0..FIFTY {
        let (i, j) = ((k % 10) as f64, (k / 10) as f64);
        let shape = match k % 4 {
            0 => "Sphere(radius: 0.08)",
            1 => "Box(half_extents: (0.1, 0.06, 0.03))",
            2 => "Ellipsoid(semi_axes: (0.1, 0.06, 0.04))",
            _ => "Prism(sides: 6, radius: 0.08, half_height: 0.03)",
        };
        let spin = [0.3 + 0.1 * i, 0.2 * j - 0.4, 0.5];
        let _ = writeln!(
            s,
            "        Body(name: \"body{k:02}\", shape: {shape}, position: ({:.2}, {:.2}, 0.0), \
             rotation: AxisAngle(axis: (1.0, 1.0, 0.0), degrees: {:.0}), velocity: ({:.3}, {:.3}, 0.0), \
             angular_velocity: ({:.2}, {:.2}, {:.2})),",
            -2.25 + 0.5 * i,
            -1.0 + 0.5 * j,
            17.0 * (k % 5) as f64,
            0.002 * (i - 4.5),
            0.002 * (j - 2.0),
            spin[0],
            spin[1],
            spin[2],
        );
    }
    s.push_str("    ],\n)\n");
    s
}

/// One recorded frame of the CSV: its time and every body's own-frame position and rotation
/// (the `x y z qx qy qz qw` columns), in the CSV's body order.
type CsvFrame = (f64, Vec<(DVec3, DQuat)>);

/// The CSV's body names (in order) and its first and last frames; and how many frames it has.
fn first_and_last(csv: &Path) -> Result<(Vec<String>, [CsvFrame; 2], usize)> {
    let text =
        std::fs::read_to_string(csv).map_err(|e| format!("cannot read {}: {e}", csv.display()))?;
    let mut lines = text.lines();
    let head: Vec<&str> = lines.next().ok_or("empty CSV")?.split(',').collect();
    let col = |name: &str| {
        head.iter()
            .position(|h| *h == name)
            .ok_or_else(|| format!("no column `{name}` in {}", csv.display()))
    };
    let columns = ["time", "x", "y", "z", "qx", "qy", "qz", "qw"]
        .map(col)
        .into_iter()
        .collect::<Result<Vec<_>>>()?;
    let mut names = Vec::new();
    let mut frames: Vec<CsvFrame> = Vec::new();
    for line in lines {
        // The body name is the second column; the numbers are counted from the end so that a
        // quoted name with a comma cannot shift them.
        let fields: Vec<&str> = line.split(',').collect();
        let n = columns
            .iter()
            .map(|&c| {
                fields[fields.len() - (head.len() - c)]
                    .parse::<f64>()
                    .map_err(|e| format!("{}: `{line}`: {e}", csv.display()))
            })
            .collect::<Result<Vec<_>>>()?;
        if frames.last().is_none_or(|f| f.0 != n[0]) {
            frames.push((n[0], Vec::new()));
        }
        if frames.len() == 1 {
            names.push(fields[1..fields.len() + 1 - (head.len() - 1)].join(","));
        }
        frames.last_mut().ok_or("no frame")?.1.push((
            DVec3::new(n[1], n[2], n[3]),
            DQuat::from_xyzw(n[4], n[5], n[6], n[7]).normalize(),
        ));
    }
    let count = frames.len();
    let last = frames.pop().ok_or("no frame in the CSV")?;
    let first = if frames.is_empty() {
        last.clone()
    } else {
        frames.swap_remove(0)
    };
    Ok((names, [first, last], count))
}

/// A point inside each body, off its centre, in the body's own frame (the frame of the CSV's
/// position and rotation), read from the scene's shapes: 0.6 of the way from the centre of
/// mass to the farthest point along the body's longest principal axis (inside, as the body is
/// convex). A page that turned a body the wrong way would draw it away from this point; for a
/// compound body the centre of mass itself (it may lie outside the pieces, so those are not
/// checked).
fn probe_points(scene: &Path, names: &[String]) -> Result<Vec<Option<DVec3>>> {
    let desc = impulse_sim::Scene::read(scene).map_err(|e| e.to_string())?;
    let world = impulse_sim::World::from_scene(&desc).map_err(|e| e.to_string())?;
    names
        .iter()
        .map(|name| {
            let (_, body) = world
                .bodies()
                .find(|(_, b)| b.name == *name)
                .ok_or_else(|| format!("body `{name}` of the CSV is not in {}", scene.display()))?;
            let [piece] = body.shape.pieces() else {
                return Ok(None);
            };
            let far = |d: DVec3| -> DVec3 {
                let local = piece.pose.rotation.inverse() * d;
                let p = match &piece.convex {
                    Convex::Sphere(s) => local * s.radius(),
                    Convex::Ellipsoid(e) => e.support(local),
                    Convex::Polyhedron(p) => p.vertex(p.support(local)),
                };
                piece.pose.transform_point(p)
            };
            let longest = [DVec3::X, DVec3::Y, DVec3::Z]
                .map(far)
                .into_iter()
                .max_by(|a, b| a.length().total_cmp(&b.length()))
                .unwrap_or_default();
            // Body frame (centre of mass, principal axes) to the own frame.
            Ok(Some(
                body.frame.inverse().transform_point(PROBE_DEPTH * longest),
            ))
        })
        .collect()
}

/// A point inside each link of a reduced mechanism, in its link frame (the frame of the CSV's
/// position and rotation): the centre of its first collision shape, or its centre of mass
/// when it has none (the page then draws the box with its inertia around it).
fn link_points(mechanism: &Path, names: &[String]) -> Result<Vec<Option<DVec3>>> {
    let text = std::fs::read_to_string(mechanism)
        .map_err(|e| format!("cannot read {}: {e}", mechanism.display()))?;
    let m = impulse_reduced::MechanismDesc::from_ron(&text)
        .and_then(|d| d.build())
        .map_err(|e| format!("{}: {e}", mechanism.display()))?;
    names
        .iter()
        .map(|name| {
            let link = m
                .links
                .iter()
                .find(|l| l.name == *name)
                .ok_or_else(|| format!("link `{name}` is not in {}", mechanism.display()))?;
            Ok(Some(match link.shapes.first() {
                Some(impulse_reduced::Shape::Sphere { center, .. }) => *center,
                Some(impulse_reduced::Shape::Box { center, .. }) => *center,
                None => link.inertia.com,
            }))
        })
        .collect()
}

/// Whether a pixel is the selected body's magenta (any shade): red and blue alike and far
/// above green.
fn magenta(p: [u8; 4]) -> bool {
    let (r, g, b) = (i32::from(p[0]), i32::from(p[1]), i32::from(p[2]));
    r > 60 && b > 60 && (r - b).abs() < r / 3 && g < r / 3
}

/// World point `x` through the page's column-major view-projection `m`, to CSS pixels of the
/// page; `None` behind the eye.
fn project(view: &Value, x: DVec3) -> Option<(f64, f64)> {
    let m: Vec<f64> = view["matrix"]
        .as_array()?
        .iter()
        .filter_map(Value::as_f64)
        .collect();
    let clip: Vec<f64> = (0..4)
        .map(|r| m[r] * x[0] + m[4 + r] * x[1] + m[8 + r] * x[2] + m[12 + r])
        .collect();
    if clip[3] <= 0.0 {
        return None;
    }
    let (nx, ny) = (clip[0] / clip[3], clip[1] / clip[3]);
    let (left, top) = (view["left"].as_f64()?, view["top"].as_f64()?);
    let (w, h) = (view["width"].as_f64()?, view["height"].as_f64()?);
    Some((left + (nx + 1.0) / 2.0 * w, top + (1.0 - ny) / 2.0 * h))
}

/// Whether `image` shows magenta within [`HIT_PX`] of (`x`, `y`).
fn hit(image: &Image, (x, y): (f64, f64)) -> bool {
    let (x, y) = (x.round() as i64, y.round() as i64);
    (-HIT_PX..=HIT_PX)
        .any(|dy| (-HIT_PX..=HIT_PX).any(|dx| image.at(x + dx, y + dy).is_some_and(magenta)))
}

fn write_png(path: &Path, png: &[u8]) -> Result<()> {
    std::fs::write(path, png).map_err(|e| format!("cannot write {}: {e}", path.display()))
}

/// Every check of one page; returns its report line.
fn check_page(
    browser: &mut Browser,
    page: &Page,
    html: &Path,
    csv: &Path,
    out: &Path,
) -> Result<String> {
    let url = format!(
        "file://{}",
        html.canonicalize().map_err(|e| e.to_string())?.display()
    );
    let bytes = std::fs::metadata(html).map_err(|e| e.to_string())?.len();
    browser.open(&url)?;
    let deadline = Instant::now() + Duration::from_secs(60);
    loop {
        let state = browser
            .eval("window.impulseViewer ? (impulseViewer.failed || impulseViewer.ready) : false")?;
        match state {
            Value::Bool(true) => break,
            Value::String(why) => return Err(format!("the page failed: {why}")),
            _ if !browser.errors().is_empty() => {
                return Err(format!(
                    "the page reported errors before it was ready: {}",
                    browser.errors().join("; ")
                ));
            }
            _ if Instant::now() > deadline => return Err("the page never became ready".into()),
            _ => std::thread::sleep(Duration::from_millis(100)),
        }
    }
    let (names, [first, last], frames) = first_and_last(csv)?;
    let probes = match page.reduce {
        None => probe_points(&page.scene, &names)?,
        Some(_) => link_points(&page.scene, &names)?,
    };
    let page_frames = browser.eval("impulseViewer.frames")?;
    if page_frames.as_u64() != Some(frames as u64) {
        return Err(format!(
            "the page holds {page_frames} frames, the CSV {frames}"
        ));
    }
    // The moving bodies of the page that the CSV holds, matched by name: (page index, CSV
    // index). A reduced mechanism's page also draws its base and the ground, which the CSV
    // leaves out.
    let listed = browser.eval("impulseViewer.header.bodies.map(b => [b.name, b.kind])")?;
    let moving: Vec<(usize, usize)> = listed
        .as_array()
        .ok_or("no body list")?
        .iter()
        .enumerate()
        .filter(|(_, b)| b[1].as_str() != Some("fixed"))
        .filter_map(|(i, b)| {
            Some((
                i,
                names
                    .iter()
                    .position(|n| Some(n.as_str()) == b[0].as_str())?,
            ))
        })
        .take(MAX_CHECKED)
        .collect();
    if moving.is_empty() {
        return Err("no moving body of the CSV on the page".into());
    }
    // The bodies where the trajectory says, at the first and the last frame.
    let (mut checks, mut hits) = (0, 0);
    let mut seen = Vec::new();
    let mut missed = Vec::new();
    for (label, (time, states)) in [("start", &first), ("end", &last)] {
        browser.eval(&format!(
            "impulseViewer.select(-1); impulseViewer.setTime({time})"
        ))?;
        let (png, _) = browser.screenshot()?;
        write_png(&out.join(format!("{}-{label}.png", page.name)), &png)?;
        let view = browser.eval("impulseViewer.view()")?;
        for &(i, j) in &moving {
            // A compound body has no point known to lie inside it: not checked.
            let Some(probe) = probes[j] else { continue };
            browser.eval(&format!(
                "impulseViewer.select({i}); impulseViewer.solo(true); impulseViewer.setTime({time})"
            ))?;
            let (_, image) = browser.screenshot()?;
            let (position, rotation) = states[j];
            let Some(at) = project(&view, position + rotation * probe) else {
                continue;
            };
            checks += 1;
            if !hit(&image, at) {
                missed.push(format!(
                    "{} at {label} ({:.0}, {:.0})",
                    names[j], at.0, at.1
                ));
            } else {
                hits += 1;
                if *time == last.0 {
                    seen.push((i, at));
                }
            }
        }
    }
    // The picture of the run half-way, with the first moving body selected (the README's
    // screenshot is the pool break's).
    browser.eval(&format!(
        "impulseViewer.solo(false); impulseViewer.select({}); impulseViewer.setTime({})",
        moving[0].0,
        (first.0 + last.0) / 2.0
    ))?;
    let (png, _) = browser.screenshot()?;
    write_png(&out.join(format!("{}-middle.png", page.name)), &png)?;
    let share = f64::from(hits) / f64::from(checks.max(1));
    if checks == 0 || share < MIN_HIT_SHARE {
        return Err(format!(
            "bodies not drawn where the trajectory says: {hits} of {checks} projected centres \
             show the selected body (need {:.0} %); missed: {}",
            100.0 * MIN_HIT_SHARE,
            missed.join(", ")
        ));
    }
    // A click on a body picks it (or the body in front of it: the first seen body that is not
    // hidden must be picked).
    browser.eval("impulseViewer.solo(false)")?;
    if seen.is_empty() {
        return Err("no body was seen at the end, so picking cannot be checked".into());
    }
    let mut picks = Vec::new();
    for &(i, at) in seen.iter().take(MAX_PICKS) {
        browser.eval(&format!(
            "impulseViewer.select(-1); impulseViewer.setTime({})",
            last.0
        ))?;
        browser.click(at.0, at.1)?;
        let picked = browser.eval("impulseViewer.selected()")?;
        picks.push(format!("{} → {picked}", i));
        if picked.as_u64() == Some(i as u64) {
            picks.clear();
            break;
        }
    }
    if !picks.is_empty() {
        return Err(format!(
            "clicks on bodies picked others or none (body → picked): {}",
            picks.join(", ")
        ));
    }
    // The camera: a drag turns the view about its target (the target's projection stays, the
    // eye moves), and the wheel zooms in (a body's projected offset from the target grows).
    browser.eval("impulseViewer.select(-1)")?;
    let before = browser.eval("impulseViewer.view()")?;
    let centre = (
        before["left"].as_f64().unwrap_or(0.0) + before["width"].as_f64().unwrap_or(0.0) / 2.0,
        before["top"].as_f64().unwrap_or(0.0) + before["height"].as_f64().unwrap_or(0.0) / 2.0,
    );
    browser.drag(centre, (centre.0 + ORBIT_DRAG_PX, centre.1), 5)?;
    browser.eval("new Promise(r => requestAnimationFrame(() => requestAnimationFrame(r)))")?;
    let turned = browser.eval("impulseViewer.view()")?;
    let body = last.1[moving[0].1].0;
    let moved = |a: &Value, b: &Value| -> Option<f64> {
        let (p, q) = (project(a, body)?, project(b, body)?);
        Some((p.0 - q.0).hypot(p.1 - q.1))
    };
    if before["matrix"] == turned["matrix"] || moved(&before, &turned).is_none_or(|d| d < 1.0) {
        return Err(format!(
            "a drag of {ORBIT_DRAG_PX} px did not turn the view (a body moved {:?} px)",
            moved(&before, &turned)
        ));
    }
    let target = browser.eval("impulseViewer.view().target")?;
    let target: Vec<f64> = target
        .as_array()
        .ok_or("no target")?
        .iter()
        .filter_map(Value::as_f64)
        .collect();
    let target = DVec3::new(target[0], target[1], target[2]);
    let spread = |v: &Value| -> Option<f64> {
        let (p, q) = (project(v, body)?, project(v, target)?);
        Some((p.0 - q.0).hypot(p.1 - q.1))
    };
    browser.wheel(centre.0, centre.1, -ZOOM_WHEEL)?;
    browser.eval("new Promise(r => requestAnimationFrame(() => requestAnimationFrame(r)))")?;
    let zoomed = browser.eval("impulseViewer.view()")?;
    match (spread(&turned), spread(&zoomed)) {
        (Some(a), Some(b)) if b > a * ZOOM_MIN_GAIN => {}
        other => {
            return Err(format!(
                "a wheel turn of {ZOOM_WHEEL} did not zoom in (a body's distance from the \
                 target on screen: {other:?} px)"
            ));
        }
    }
    // Scrubbing: a click on the slider moves the time and changes the picture (the first
    // view again, at the start).
    // The clock and the help over the view are hidden: only the 3-D picture counts.
    browser.eval(&format!(
        "for (const id of ['hud', 'help']) document.getElementById(id).style.visibility = 'hidden'; \
         impulseViewer.frameAll(); impulseViewer.select(-1); impulseViewer.setTime({})",
        first.0
    ))?;
    let (_, unscrubbed) = browser.screenshot()?;
    let rect = browser.eval(
        "(() => { const r = document.getElementById('scrub').getBoundingClientRect(); \
         return [r.left, r.top, r.width, r.height]; })()",
    )?;
    let r: Vec<f64> = rect
        .as_array()
        .ok_or("no slider")?
        .iter()
        .filter_map(Value::as_f64)
        .collect();
    browser.click(r[0] + 0.75 * r[2], r[1] + r[3] / 2.0)?;
    // Let the page draw the frame the input asked for.
    browser.eval("new Promise(r => requestAnimationFrame(() => requestAnimationFrame(r)))")?;
    let t = browser
        .eval("impulseViewer.time()")?
        .as_f64()
        .ok_or("no time")?;
    let wanted = first.0 + 0.75 * (last.0 - first.0);
    if (t - wanted).abs() > SCRUB_TOLERANCE * (last.0 - first.0) {
        return Err(format!(
            "a click at 3/4 of the slider gave t = {t}, not about {wanted}"
        ));
    }
    let (_, scrubbed) = browser.screenshot()?;
    let view = browser.eval("impulseViewer.view()")?;
    let (changed, all) = changed_pixels(&unscrubbed, &scrubbed, &view);
    if changed < MIN_CHANGED_PIXELS {
        return Err(format!(
            "scrubbing to t = {t:.3} s changed {changed} pixels of the view (need {MIN_CHANGED_PIXELS})"
        ));
    }
    let changed = changed as f64 / all.max(1) as f64;
    let mut line = format!(
        "{:>6.2} MB, {frames} frames, {hits}/{checks} centres hit, pick, orbit and zoom ok, scrub changed {:.1} % of the view",
        bytes as f64 / 1e6,
        100.0 * changed
    );
    if page.frame_rate {
        if bytes > MAX_PAGE_BYTES {
            return Err(format!("the page is {bytes} bytes, over {MAX_PAGE_BYTES}"));
        }
        // Played and measured inside the page, which answers when the time is up; the first
        // WARM_UP_SECONDS are not measured (the page lowers its resolution then if it must).
        // The frame rate is the machine's as much as the page's: on a loaded machine one
        // measurement can be slow with nothing wrong, so up to PLAY_ATTEMPTS are made and the
        // best counts (a page too slow to play fails them all).
        let mut attempts = Vec::new();
        let mut best = f64::NAN;
        let mut best_draw_p95 = f64::NAN;
        let mut best_line = String::new();
        for _ in 0..PLAY_ATTEMPTS {
            let stats = browser.eval(&format!(
                "new Promise(done => {{ impulseViewer.setTime(impulseViewer.start); \
                 impulseViewer.play(1); \
                 setTimeout(() => impulseViewer.resetFrameStats(), {}); \
                 setTimeout(() => {{ impulseViewer.pause(); done(impulseViewer.frameStats()); }}, {}); }})",
                WARM_UP_SECONDS * 1000.0,
                (WARM_UP_SECONDS + PLAY_SECONDS) * 1000.0
            ))?;
            let mean = stats["intervalMean"].as_f64().unwrap_or(f64::NAN);
            let fps = 1000.0 / mean;
            attempts.push(format!("{fps:.1}"));
            if best.is_nan() || fps > best {
                best = fps;
                best_draw_p95 = stats["drawP95"].as_f64().unwrap_or(f64::NAN);
                best_line = format!(
                    "; playback {fps:.1} fps ({} frames, interval mean {mean:.1} ms, p95 {:.1} ms; draw mean {:.2} ms, p95 {:.2} ms; resolution down to {})",
                    stats["intervals"],
                    stats["intervalP95"].as_f64().unwrap_or(f64::NAN),
                    stats["drawMean"].as_f64().unwrap_or(f64::NAN),
                    stats["drawP95"].as_f64().unwrap_or(f64::NAN),
                    stats["lowestRenderScale"],
                );
            }
            if fps >= MIN_FPS {
                break;
            }
        }
        line.push_str(&best_line);
        if attempts.len() > 1 {
            let _ = write!(
                line,
                " (best of {} attempts: {} fps)",
                attempts.len(),
                attempts.join(", ")
            );
        }
        // Below the rate, the page is at fault only if its own drawing takes a large share
        // of a frame: otherwise the browser was not given the time to ask for frames (a
        // loaded machine), which says nothing of the page.
        let budget_ms = 1000.0 / MIN_FPS;
        if best.is_nan() || best < MIN_FPS {
            if best_draw_p95.is_finite() && best_draw_p95 <= MAX_DRAW_SHARE * budget_ms {
                let _ = write!(
                    line,
                    "; below {MIN_FPS} fps with drawing at {best_draw_p95:.2} ms (p95) of the \
                     {budget_ms:.1} ms frame: the machine was busy, not the page"
                );
            } else {
                return Err(format!("playback too slow: {line}"));
            }
        }
    }
    if !browser.errors().is_empty() {
        return Err(format!(
            "the page reported errors: {}",
            browser.errors().join("; ")
        ));
    }
    Ok(line)
}

/// How many of the canvas's pixels (the box in `view`) differ between `a` and `b`, and how
/// many it has.
fn changed_pixels(a: &Image, b: &Image, view: &Value) -> (u64, u64) {
    let f = |k: &str| view[k].as_f64().unwrap_or(0.0).round() as i64;
    let (left, top, w, h) = (f("left"), f("top"), f("width"), f("height"));
    let (mut changed, mut all) = (0u64, 0u64);
    for y in top..top + h {
        for x in left..left + w {
            if let (Some(p), Some(q)) = (a.at(x, y), b.at(x, y)) {
                all += 1;
                if p != q {
                    changed += 1;
                }
            }
        }
    }
    (changed, all)
}
