//! End-to-end tests of `impulse run`: the binary on bundled scenes, with its outputs checked
//! against the scene's physics (a two-ball collision with a closed form) and its errors.

mod common;

use common::Scratch;
use common::impulse_text as impulse;
use std::path::{Path, PathBuf};
use std::process::Command;

fn scenes() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/scenes")
}

fn temp_dir(name: &str) -> Scratch {
    Scratch::new(&format!("run-{name}"))
}

/// The two-ball scene: e = 0.6, v0 = 2 m/s, equal balls, no friction, no gravity. The summary
/// reports one collision and no penetration; the CSV's last row of the target ball has
/// v = v0(1 + e)/2 = 1.6 m/s; kinetic energy is the closed-form (1 + e²)/2 of the start.
#[test]
fn run_two_balls_writes_summary_csv_and_plots() {
    let dir = temp_dir("two-balls");
    let csv = dir.join("traj.csv");
    let plots = dir.join("plots");
    let scene = scenes().join("two-ball-collision.ron");
    let (ok, stdout, stderr) = impulse(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        csv.to_str().unwrap(),
        "--plot",
        plots.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    // The trajectory is streamed into a file beside it that takes its name at the end.
    assert!(csv.is_file() && !dir.join("traj.csv.partial").exists());
    assert!(stdout.contains("collisions:       1\n"), "{stdout}");
    assert!(
        stdout.contains("penetration:      none: largest 0.000e0 (0.000 ε_c"),
        "{stdout}"
    );
    assert!(stdout.contains("slowdown:"), "{stdout}");
    let text = std::fs::read_to_string(&csv).unwrap();
    let header = text.lines().next().unwrap();
    assert_eq!(
        header,
        "time,body,x,y,z,qx,qy,qz,qw,vx,vy,vz,wx,wy,wz,cx,cy,cz"
    );
    let last_target = text
        .lines()
        .rev()
        .find(|l| l.split(',').nth(1) == Some("target"))
        .unwrap();
    let cols: Vec<f64> = last_target
        .split(',')
        .enumerate()
        .filter(|(k, _)| *k != 1)
        .map(|(_, c)| c.parse().unwrap())
        .collect();
    // cols: time, x, y, z, qx, qy, qz, qw, vx, …
    assert!((cols[0] - 1.0).abs() < 1e-12, "last frame at {}", cols[0]);
    assert!((cols[8] - 1.6).abs() < 1e-6, "target vx {}", cols[8]);
    // Frames at the scene's rate (100/s over 1 s): 101 frames × 2 bodies + header.
    assert_eq!(text.lines().count(), 1 + 101 * 2);
    for svg in ["energy.svg", "paths.svg"] {
        let s = std::fs::read_to_string(plots.join(svg)).unwrap();
        assert!(s.starts_with("<svg") && s.contains("<polyline"), "{svg}");
    }
}

/// `--until` shortens the run and JSON output parses, with the energy of each frame.
#[test]
fn run_until_with_json_output() {
    let dir = temp_dir("json");
    let json = dir.join("traj.json");
    let scene = scenes().join("two-ball-collision.ron");
    let (ok, _, stderr) = impulse(&[
        "run",
        scene.to_str().unwrap(),
        "--until",
        "0.1",
        "--out",
        json.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let frames = v["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 11);
    // Before the collision (at 0.15 s) the striker's kinetic energy is ½ m v0².
    let m = 1000.0 * 4.0 / 3.0 * std::f64::consts::PI * 0.1f64.powi(3);
    let ke = frames[10]["kinetic_energy"].as_f64().unwrap();
    assert!((ke - 0.5 * m * 4.0).abs() < 1e-9 * ke, "{ke}");
    assert_eq!(v["bodies"][1], "target");
}

#[test]
fn bad_input_is_an_error_with_a_message() {
    let dir = temp_dir("bad");
    let missing = dir.join("missing.ron");
    let (ok, _, stderr) = impulse(&["run", missing.to_str().unwrap()]);
    assert!(!ok);
    assert!(stderr.contains("cannot read"), "{stderr}");

    let bad = dir.join("bad.ron");
    std::fs::write(
        &bad,
        "Scene(duration: 1.0, collision_epsilon: 1e-3, bodies: [
            Body(name: \"b\", shape: Sphere(radius: -1.0))])",
    )
    .unwrap();
    let (ok, _, stderr) = impulse(&["run", bad.to_str().unwrap()]);
    assert!(!ok);
    assert!(
        stderr.contains("body \"b\"") && stderr.contains("shape.radius"),
        "{stderr}"
    );

    let scene = scenes().join("two-ball-collision.ron");
    let (ok, _, stderr) = impulse(&["run", scene.to_str().unwrap(), "--out", "x.txt"]);
    assert!(!ok);
    assert!(stderr.contains(".csv or .json"), "{stderr}");
    let (ok, _, stderr) = impulse(&["run", scene.to_str().unwrap(), "--until", "-1"]);
    assert!(!ok, "{stderr}");
    assert!(
        stderr.contains("--until -1: must be a finite time > 0"),
        "{stderr}"
    );
}

/// Writes a scene file and returns its path.
fn scene_file(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// What a newcomer does first: a box and a ball placed exactly on the floor, no duration in
/// the file, a quaternion written plainly. The run needs `--until` (and says so without it);
/// the trajectory reports the box's own frame — the position and rotation written in the file
/// — not its principal frame, with the centre of mass in extra columns; the summary measures
/// the penetration and finds none beyond ε_c.
#[test]
fn a_newcomers_first_scene() {
    let dir = temp_dir("newcomer");
    let scene = scene_file(
        &dir,
        "first.ron",
        "Scene(collision_epsilon: 1e-4, bodies: [
            Body(name: \"floor\", shape: Box(half_extents: (1, 1, 0.1)), position: (0, 0, -0.1), motion: Fixed),
            Body(name: \"box\", shape: Box(half_extents: (0.3, 0.1, 0.2)), position: (0, 0, 0.2),
                 rotation: Quaternion(0.0, 0.0, 0.0, 1.0)),
            Body(name: \"ball\", shape: Sphere(radius: 0.05), position: (0.5, 0, 0.05)),
        ])",
    );
    let (ok, _, stderr) = impulse(&["run", scene.to_str().unwrap()]);
    assert!(!ok);
    assert!(
        stderr.contains("no `duration`") && stderr.contains("--until"),
        "{stderr}"
    );
    let csv = dir.join("first.csv");
    let (ok, stdout, stderr) = impulse(&[
        "run",
        scene.to_str().unwrap(),
        "--until",
        "1",
        "--out",
        csv.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    let text = std::fs::read_to_string(&csv).unwrap();
    let first_box: Vec<f64> = text
        .lines()
        .find(|l| l.split(',').nth(1) == Some("box"))
        .unwrap()
        .split(',')
        .enumerate()
        .filter(|(k, _)| *k != 1)
        .map(|(_, c)| c.parse().unwrap())
        .collect();
    // time, x, y, z, qx, qy, qz, qw, vx, vy, vz, wx, wy, wz, cx, cy, cz
    assert_eq!(&first_box[1..8], &[0.0, 0.0, 0.2, 0.0, 0.0, 0.0, 1.0]);
    assert_eq!(&first_box[14..17], &[0.0, 0.0, 0.2]);
    let line = stdout
        .lines()
        .find(|l| l.starts_with("penetration:"))
        .unwrap();
    let depth: f64 = line
        .split("largest ")
        .nth(1)
        .unwrap()
        .split_whitespace()
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(depth <= 1e-4, "{line}");
    assert!(
        line.starts_with("penetration:      none: ")
            || line.starts_with("penetration:      none beyond ε_c: "),
        "{line}"
    );
}

/// Scene mistakes get a sentence that says what to write: the old double-parenthesised
/// quaternion, an ε_c larger than the bodies.
#[test]
fn scene_mistakes_are_explained() {
    let dir = temp_dir("mistakes");
    let quat = scene_file(
        &dir,
        "quat.ron",
        "Scene(duration: 1.0, bodies: [
            Body(name: \"b\", shape: Sphere(radius: 0.1), rotation: Quaternion((0.0, 0.0, 0.0, 1.0)))])",
    );
    let (ok, _, stderr) = impulse(&["run", quat.to_str().unwrap()]);
    assert!(!ok);
    assert!(stderr.contains("Quaternion(x, y, z, w)"), "{stderr}");
    let coarse = scene_file(
        &dir,
        "coarse.ron",
        "Scene(duration: 1.0, collision_epsilon: 0.5, bodies: [
            Body(name: \"ball\", shape: Sphere(radius: 0.05))])",
    );
    let (ok, _, stderr) = impulse(&["run", coarse.to_str().unwrap()]);
    assert!(!ok);
    assert!(
        stderr.contains("collision_epsilon") && stderr.contains("\"ball\""),
        "{stderr}"
    );
}

/// `impulse run … | head -1`: the reader goes away before the summary is written; that is no
/// error and no panic.
#[test]
fn a_closed_pipe_is_not_a_panic() {
    let scene = scenes().join("two-ball-collision.ron");
    let mut child = Command::new(env!("CARGO_BIN_EXE_impulse"))
        .args(["run", scene.to_str().unwrap()])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}

/// Body names with quotes and control characters stay valid JSON (and are quoted in CSV).
#[test]
fn odd_names_stay_valid_json_and_csv() {
    let dir = temp_dir("names");
    let scene = scene_file(
        &dir,
        "names.ron",
        "Scene(duration: 0.05, gravity: (0, 0, 0), bodies: [
            Body(name: \"a \\\"quoted\\\", name\\u{1}\", shape: Sphere(radius: 0.1))])",
    );
    let json = dir.join("names.json");
    let (ok, _, stderr) = impulse(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        json.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["bodies"][0], "a \"quoted\", name\u{1}");
    let csv = dir.join("names.csv");
    let (ok, _, _) = impulse(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        csv.to_str().unwrap(),
    ]);
    assert!(ok);
    let text = std::fs::read_to_string(&csv).unwrap();
    assert!(
        text.lines()
            .nth(1)
            .unwrap()
            .contains(",\"a \"\"quoted\"\", name\u{1}\","),
        "{text}"
    );
}

/// `--contact-model` overrides the scene's model: the block drop's two blocks come to rest
/// on microcollisions in the impulse model (none held), and on held contacts in the default
/// switching model (island steps, and far fewer microcollisions); a wrong name is refused.
#[test]
fn contact_model_option_overrides_the_scene() {
    let scene = scenes().join("block-drop.ron");
    let number = |text: &str, label: &str| -> u64 {
        let line = text.lines().find(|l| l.starts_with(label)).unwrap();
        let rest = line[label.len()..].trim_start();
        let digits: String = rest.chars().take_while(char::is_ascii_digit).collect();
        digits.parse().unwrap()
    };
    let (ok, impulse_out, _) =
        impulse(&["run", scene.to_str().unwrap(), "--contact-model", "impulse"]);
    assert!(ok);
    assert!(
        impulse_out.contains("contact model:    impulse\n"),
        "{impulse_out}"
    );
    let (ok, switching_out, _) = impulse(&["run", scene.to_str().unwrap()]);
    assert!(ok);
    let line = switching_out
        .lines()
        .find(|l| l.starts_with("contact model:    switching: "))
        .unwrap();
    let steps: u64 = line["contact model:    switching: ".len()..]
        .split_whitespace()
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(steps > 0, "{switching_out}");
    let (micro_i, micro_s) = (
        number(&impulse_out, "microcollisions:"),
        number(&switching_out, "microcollisions:"),
    );
    assert!(micro_i > 10 * micro_s.max(1), "{micro_i} vs {micro_s}");
    let (ok, _, stderr) = impulse(&["run", scene.to_str().unwrap(), "--contact-model", "glue"]);
    assert!(
        !ok && stderr.contains("possible values: switching, impulse"),
        "{stderr}"
    );
}

/// `--profile` on the bundled triple pendulum (its first second, pure impulse model): the
/// shares of the loop's parts are printed and add up to 100 %, and, as thesis Table 7.2 finds
/// for this scene, multibody dynamics is the largest part.
#[test]
fn profile_prints_shares_that_add_up() {
    let scene = scenes().join("triple-pendulum.ron");
    let (ok, stdout, stderr) = impulse(&[
        "run",
        scene.to_str().unwrap(),
        "--until",
        "1",
        "--contact-model",
        "impulse",
        "--profile",
    ]);
    assert!(ok, "{stderr}");
    let parse = |line: &str| -> Option<(String, f64)> {
        let t = line.trim().strip_suffix('%')?.trim_end();
        let (name, pct) = t.rsplit_once(' ')?;
        Some((name.trim().to_owned(), pct.parse().ok()?))
    };
    let shares: Vec<(String, f64)> = stdout
        .lines()
        .skip_while(|l| !l.starts_with("profile:"))
        .filter_map(parse)
        .collect();
    assert_eq!(shares.len(), 7, "{stdout}");
    let total: f64 = shares.iter().map(|(_, p)| p).sum();
    assert!((total - 100.0).abs() < 0.5, "{shares:?}");
    let top = shares.iter().max_by(|a, b| a.1.total_cmp(&b.1)).unwrap();
    assert_eq!(top.0, "multibody dynamics", "{stdout}");
    assert!(stdout.contains("multibody steps redone"), "{stdout}");
}

/// Every failure is one line on stderr that starts with `error: ` (lower case, as cargo and
/// clap write it): a malformed scene file, an invalid one, a missing one, an unknown argument,
/// a bad value, and a value refused by the program itself; never `Error:`.
#[test]
fn every_error_starts_with_the_same_prefix() {
    let dir = temp_dir("prefix");
    let malformed = scene_file(&dir, "malformed.ron", "Scene(bodies: [Body(name: \"b\",");
    let invalid = scene_file(
        &dir,
        "invalid.ron",
        "Scene(duration: 1.0, bodies: [Body(name: \"b\", shape: Sphere(radius: -1.0))])",
    );
    let missing = dir.join("missing.ron");
    let scene = scenes().join("two-ball-collision.ron");
    let scene = scene.to_str().unwrap();
    let cases: [&[&str]; 7] = [
        &["run", malformed.to_str().unwrap()],
        &["run", invalid.to_str().unwrap()],
        &["run", missing.to_str().unwrap()],
        &["run", scene, "--bogus"],
        &["run", scene, "--until", "abc"],
        &["run", scene, "--until", "-1"],
        &["massprops", missing.to_str().unwrap()],
    ];
    for args in cases {
        let (ok, stdout, stderr) = impulse(args);
        assert!(!ok, "{args:?} succeeded: {stdout}");
        assert!(stderr.starts_with("error: "), "{args:?}: {stderr}");
        assert!(
            !stderr
                .lines()
                .any(|l| l.to_lowercase().starts_with("error: error")),
            "{args:?}: {stderr}"
        );
        assert!(!stderr.contains("Error:"), "{args:?}: {stderr}");
    }
}

/// A run of a few milliseconds of wall time reports its wall time in a unit that shows it
/// (`ms` or `µs`, three significant digits), not `0.000 s`; the slowdown is not `0.0000`.
#[test]
fn a_short_run_reports_a_readable_wall_time() {
    let scene = scenes().join("two-ball-collision.ron");
    let (ok, stdout, stderr) = impulse(&["run", scene.to_str().unwrap(), "--until", "0.01"]);
    assert!(ok, "{stderr}");
    let field = |label: &str| -> String {
        let line = stdout.lines().find(|l| l.starts_with(label)).unwrap();
        line[label.len()..].trim().to_owned()
    };
    let wall = field("wall time:");
    let (number, unit) = wall.split_once(' ').unwrap();
    let value: f64 = number.parse().unwrap();
    assert!(
        value > 0.0 && ["s", "ms", "µs", "ns"].contains(&unit),
        "{wall}"
    );
    let digits = number.chars().filter(char::is_ascii_digit).count();
    assert!(
        digits == 3 || value >= 1000.0,
        "{wall}: not 3 significant digits"
    );
    let slowdown = field("slowdown:");
    let slowdown: f64 = slowdown.split_whitespace().next().unwrap().parse().unwrap();
    assert!(slowdown > 0.0, "{stdout}");
}

/// An output that cannot be written is refused before the run, naming the option, the file
/// and its missing directory: a long run whose results cannot be written is not run at all
/// (no summary is printed).
#[test]
fn an_unwritable_output_is_refused_before_the_run() {
    let scene = scenes().join("two-ball-collision.ron");
    let missing = std::env::temp_dir().join("impulse-no-such-dir-7f3a/sub");
    for (flag, file) in [("--out", "traj.csv"), ("--gltf", "run.glb")] {
        let path = missing.join(file);
        let (ok, stdout, stderr) =
            impulse(&["run", scene.to_str().unwrap(), flag, path.to_str().unwrap()]);
        assert!(!ok, "{flag}: {stdout}");
        assert!(
            stderr.starts_with(&format!("error: {flag} {}", path.display()))
                && stderr.contains("does not exist"),
            "{flag}: {stderr}"
        );
        assert!(!stdout.contains("scene:"), "{flag}: ran anyway: {stdout}");
    }
}

/// More threads than the machine can use end at once with the limit named (100 000 hung
/// while the threads started); a run too short to time says so instead of printing an
/// infinite slowdown. The limit is computed here from the machine.
#[test]
fn too_many_threads_and_a_run_too_short_to_time_say_so() {
    let scene = scenes().join("block-drop.ron");
    let most = 4 * std::thread::available_parallelism().map_or(1, usize::from);
    let start = std::time::Instant::now();
    let (ok, _, stderr) = impulse(&["run", scene.to_str().unwrap(), "--threads", "100000"]);
    assert!(!ok, "{stderr}");
    assert!(
        stderr.contains("--threads 100000") && stderr.contains(&format!("at most {most}")),
        "{stderr}"
    );
    assert!(start.elapsed() < std::time::Duration::from_secs(1));
    let (ok, stdout, stderr) = impulse(&["run", scene.to_str().unwrap(), "--until", "5e-324"]);
    assert!(ok, "{stderr}");
    assert!(stdout.contains("is too short to time"), "{stdout}");
    assert!(!stdout.contains("inf"), "{stdout}");
}

/// `--max-wall` stops a run at the frame after the limit with valid outputs: the CSV is
/// complete up to the frame the summary names (every body at every frame time, read back
/// here), not renamed half-written, and the summary says where the run stopped. A limit that
/// is not a positive number is refused.
#[test]
fn a_wall_time_limit_stops_the_run_with_valid_outputs() {
    let dir = temp_dir("max-wall");
    let csv = dir.join("traj.csv");
    let scene = scenes().join("dominos.ron");
    let (ok, stdout, stderr) = impulse(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        csv.to_str().unwrap(),
        "--max-wall",
        "1e-9",
    ]);
    assert!(ok, "{stderr}");
    assert!(
        stdout.contains("\nstopped:          at the wall-time limit"),
        "{stdout}"
    );
    assert!(!dir.join("traj.csv.partial").exists());
    let last = last_whole_frame(&csv);
    assert!(last < 1.0, "stopped early: last frame at {last} s");
    for bad in ["0", "-1", "nan"] {
        let (ok, _, stderr) = impulse(&["run", scene.to_str().unwrap(), "--max-wall", bad]);
        assert!(!ok && stderr.contains("--max-wall"), "{bad}: {stderr}");
    }
}

/// Ctrl-C (SIGINT, sent here with `kill`) ends a run at its next frame: exit code 130, the
/// summary says it was interrupted and where, and `--out` is a whole file under its own name
/// (every body at every frame up to the stop), with no `.partial` left. The run is long enough
/// (60 s of the pool break, several seconds of wall time) that it cannot end on its own first.
#[cfg(unix)]
#[test]
fn ctrl_c_ends_a_run_with_valid_outputs_and_exit_code_130() {
    let dir = temp_dir("interrupt");
    let csv = dir.join("traj.csv");
    let partial = dir.join("traj.csv.partial");
    let scene = scenes().join("pool-break.ron");
    let child = Command::new(env!("CARGO_BIN_EXE_impulse"))
        .args([
            "run",
            scene.to_str().unwrap(),
            "--until",
            "60",
            "--out",
            csv.to_str().unwrap(),
        ])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Wait until the run is writing frames.
    let start = std::time::Instant::now();
    while std::fs::metadata(&partial).map_or(0, |m| m.len()) < 100_000 {
        assert!(start.elapsed().as_secs() < 60, "the run never wrote frames");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let killed = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    let out = child.wait_with_output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(130), "{stdout}");
    assert!(
        stdout.contains("stopped:          interrupted (Ctrl-C or SIGTERM)"),
        "{stdout}"
    );
    assert!(csv.is_file() && !partial.exists());
    let last = last_whole_frame(&csv);
    assert!(last < 60.0, "interrupted: last frame at {last} s");
}

/// The time of the last frame of a trajectory CSV, after checking that the file is whole:
/// it ends with a line break and every frame has a row for every body.
fn last_whole_frame(csv: &Path) -> f64 {
    let text = std::fs::read_to_string(csv).unwrap();
    assert!(text.ends_with('\n'), "cut mid-line");
    let mut rows_at: std::collections::BTreeMap<String, usize> = Default::default();
    for row in text.lines().skip(1) {
        *rows_at
            .entry(row.split(',').next().unwrap().to_owned())
            .or_default() += 1;
    }
    let bodies = *rows_at.values().next().expect("frames");
    assert!(
        rows_at.values().all(|&n| n == bodies),
        "every body at every frame"
    );
    rows_at
        .keys()
        .map(|t| t.parse::<f64>().unwrap())
        .fold(0.0, f64::max)
}

/// `--events` lists the two-ball scene's one impact: its impulse is the closed form of a
/// central frictionless collision, J = (1 + e)·m₁m₂/(m₁ + m₂)·|u| along the line of centres,
/// its normal speed after is −e times the speed before, and the two energies differ by
/// (1 − e²)·½·m₁m₂/(m₁ + m₂)·u² — e, the speeds and the masses read from the scene file.
/// The JSON form holds the same numbers.
#[test]
fn events_list_the_impact_with_its_closed_form_impulse() {
    /// The collision is resolved by integrating through it (thesis §3.3) to the response's
    /// relative tolerance: measured 3e-16 relative here.
    const IMPULSE_REL: f64 = 1e-9;
    let dir = temp_dir("events");
    let scene_path = scenes().join("two-ball-collision.ron");
    let scene = impulse_sim::Scene::read(&scene_path).unwrap();
    let e = scene.desc.default_contact.restitution;
    let world = impulse_sim::World::from_scene(&scene).unwrap();
    let bodies: Vec<(String, f64, f64)> = world
        .bodies()
        .map(|(_, b)| (b.name.clone(), b.mass.unwrap().mass, b.velocity.x))
        .collect();
    let (m1, m2) = (bodies[0].1, bodies[1].1);
    let reduced = m1 * m2 / (m1 + m2);
    let u = bodies[0].2 - bodies[1].2;
    let csv = dir.join("events.csv");
    let json = dir.join("events.json");
    for out in [&csv, &json] {
        let (ok, _, stderr) = impulse(&[
            "run",
            scene_path.to_str().unwrap(),
            "--events",
            out.to_str().unwrap(),
        ]);
        assert!(ok, "{stderr}");
    }
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 1, "{text}");
    let col = |name: &str| {
        let k = header.iter().position(|h| *h == name).unwrap();
        rows[0][k]
    };
    let num = |name: &str| col(name).parse::<f64>().unwrap();
    assert_eq!(col("kind"), "collision");
    assert_eq!((col("body_a"), col("body_b")), ("striker", "target"));
    let j = (1.0 + e) * reduced * u;
    assert!(
        (num("impulse_x").abs() - j).abs() <= IMPULSE_REL * j,
        "{} vs {j}",
        num("impulse_x")
    );
    assert_eq!((num("impulse_y"), num("impulse_z")), (0.0, 0.0));
    let (before, after) = (num("normal_speed_before"), num("normal_speed_after"));
    assert!((before.abs() - u).abs() <= IMPULSE_REL * u, "{before}");
    assert!((after + e * before).abs() <= IMPULSE_REL * u, "{after}");
    let lost = num("energy_before") - num("energy_after");
    let want = (1.0 - e * e) * 0.5 * reduced * u * u;
    assert!(
        (lost - want).abs() <= IMPULSE_REL * want,
        "{lost} vs {want}"
    );
    // The JSON file: the same event, the same numbers to the bit.
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let events = v.as_array().unwrap();
    assert_eq!(events.len(), 1);
    assert_eq!(events[0]["impulse"][0].as_f64().unwrap(), num("impulse_x"));
    assert_eq!(events[0]["normal_speed_after"].as_f64().unwrap(), after);
    assert_eq!(events[0]["kind"], "collision");
}

/// `--events` refuses a name it cannot write before the run.
#[test]
fn events_with_a_bad_name_are_refused_before_the_run() {
    let scene = scenes().join("two-ball-collision.ron");
    let (ok, _, stderr) = impulse(&["run", scene.to_str().unwrap(), "--events", "e.txt"]);
    assert!(!ok && stderr.contains("--events e.txt: the file name must end in .csv or .json"));
    let (ok, _, stderr) = impulse(&[
        "run",
        scene.to_str().unwrap(),
        "--events",
        "/no/such/dir/e.csv",
    ]);
    assert!(
        !ok && stderr.contains("the directory /no/such/dir does not exist"),
        "{stderr}"
    );
}

/// `--joints` writes a hinge's angle and rate at every frame of `--out`: the same numbers
/// read independently from the link's own row of the trajectory (its orientation is a turn of
/// q about the hinge's y axis, 2·atan2(q_y, q_w); its angular velocity's y component is q̇),
/// in CSV and JSON alike; a scene without multibodies is refused before the run.
#[test]
fn joints_hold_each_frames_coordinates() {
    /// Both files print shortest round-trip decimals; the angle from the quaternion rounds.
    const ANGLE_TOL: f64 = 1e-12;
    let dir = temp_dir("joints");
    let scene = dir.join("hinge.ron");
    std::fs::write(
        &scene,
        r#"Scene(
    name: "hinge", duration: 0.5, output_rate: 50.0,
    bodies: [],
    multibodies: [Multibody(
        name: "pendulum", base: Fixed, position: (0.0, 0.0, 1.0),
        links: [
            Link(name: "support"),
            Link(name: "rod", shape: Some(Box(half_extents: (0.02, 0.02, 0.2))),
                 position: (0.0, 0.0, -0.2), mass: Some(Mass(1.0)), material: "steel"),
        ],
        joints: [Joint(name: "hinge", kind: Revolute, parent: "support", child: "rod",
                       axis: (0.0, 1.0, 0.0), q: 1.2, qd: 0.5)],
    )],
)"#,
    )
    .unwrap();
    let (traj, joints, json) = (dir.join("t.csv"), dir.join("j.csv"), dir.join("j.json"));
    for (out, j) in [(&traj, &joints), (&dir.join("t2.csv"), &json)] {
        let (ok, _, stderr) = impulse(&[
            "run",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--joints",
            j.to_str().unwrap(),
        ]);
        assert!(ok, "{stderr}");
    }
    let joints = std::fs::read_to_string(&joints).unwrap();
    let mut lines = joints.lines();
    assert_eq!(
        lines.next().unwrap(),
        "time,pendulum/hinge.q,pendulum/hinge.qd"
    );
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    let traj = std::fs::read_to_string(&traj).unwrap();
    let links: Vec<Vec<f64>> = traj
        .lines()
        .filter(|l| l.contains(",pendulum/rod,"))
        .map(|l| {
            l.split(',')
                .filter(|c| *c != "pendulum/rod")
                .map(|x| x.parse().unwrap())
                .collect()
        })
        .collect();
    assert_eq!(rows.len(), 26, "0.5 s at 50 Hz and the start");
    assert_eq!(rows.len(), links.len());
    for (j, l) in rows.iter().zip(&links) {
        // time, x, y, z, qx, qy, qz, qw, vx, vy, vz, wx, wy, wz, cx, cy, cz
        assert_eq!(j[0], l[0]);
        let angle = 2.0 * l[5].atan2(l[7]);
        assert!(
            (angle - j[1]).abs() <= ANGLE_TOL,
            "t {}: {angle} vs {}",
            j[0],
            j[1]
        );
        assert!(
            (l[12] - j[2]).abs() <= ANGLE_TOL,
            "t {}: {} vs {}",
            j[0],
            l[12],
            j[2]
        );
    }
    assert_eq!(rows[0][1..], [1.2, 0.5]);
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["columns"][1], "pendulum/hinge.qd");
    let frames = v["frames"].as_array().unwrap();
    assert_eq!(frames.len(), rows.len());
    assert_eq!(frames[25][1].as_f64().unwrap(), rows[25][1]);
    let two = scenes().join("two-ball-collision.ron");
    let (ok, _, stderr) = impulse(&["run", two.to_str().unwrap(), "--joints", "j.csv"]);
    assert!(
        !ok && stderr.contains("the scene has no multibodies"),
        "{stderr}"
    );
}
