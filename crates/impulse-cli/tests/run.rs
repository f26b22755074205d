//! End-to-end tests of `impulse run`: the binary on bundled scenes, with its outputs checked
//! against the scene's physics (a two-ball collision with a closed form) and its errors.

use std::path::{Path, PathBuf};
use std::process::Command;

fn scenes() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/scenes")
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("impulse-run-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn impulse(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_impulse"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
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
    assert!(stdout.contains("collisions:       1\n"), "{stdout}");
    assert!(stdout.contains("penetration:      none"), "{stdout}");
    assert!(stdout.contains("slowdown:"), "{stdout}");
    let text = std::fs::read_to_string(&csv).unwrap();
    let header = text.lines().next().unwrap();
    assert_eq!(header, "time,body,x,y,z,qx,qy,qz,qw,vx,vy,vz,wx,wy,wz");
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
}
