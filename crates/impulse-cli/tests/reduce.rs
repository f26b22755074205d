//! End-to-end tests of `impulse reduce` on the bundled mechanisms.

mod common;

use std::path::{Path, PathBuf};

use common::impulse;

fn mechanism(name: &str) -> String {
    let p: PathBuf =
        Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../../fixtures/mechanisms/{name}"));
    p.to_string_lossy().into_owned()
}

/// Under a small load the reduced static pose matches the full nonlinear one to second order:
/// 1 N on the Y's tip (100 N gives ~9e-3) must be far below 1e-5.
const SMALL_LOAD_ERROR: f64 = 1e-5;

#[test]
fn static_response_matches_full_model_under_a_small_load() {
    let out = impulse(&[
        "reduce",
        &mechanism("y.ron"),
        "--load",
        "a3:1,0,0",
        "--static",
    ]);
    assert!(out.ok, "{}", out.stderr);
    let json = out.json.expect("JSON output");
    for e in json["end_effectors"].as_array().unwrap() {
        let err = e["relative_error"].as_f64().unwrap();
        assert!(err < SMALL_LOAD_ERROR, "{e}");
    }
}

#[test]
fn simulation_writes_a_trajectory_with_the_run_columns() {
    let dir = common::Scratch::new("reduce-trajectory");
    let csv = dir.join("arm.csv");
    let out = impulse(&[
        "reduce",
        &mechanism("robot-arm-20.ron"),
        "--load",
        "a19:0,5,0",
        "--until",
        "0.2",
        "--out",
        csv.to_str().unwrap(),
    ]);
    assert!(out.ok, "{}", out.stderr);
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("time,body,x,y,z,qx,qy,qz,qw,vx,vy,vz,wx,wy,wz")
    );
    // 100 frames × 20 links (the end effector and 19 internal links).
    assert_eq!(lines.count(), 100 * 20);
    let json = out.json.unwrap();
    assert_eq!(json["steps"].as_u64(), Some(200));
}

#[test]
fn bad_input_names_the_problem() {
    let out = impulse(&["reduce", &mechanism("y.ron"), "--load", "t0:1,0,0"]);
    assert!(
        !out.ok && out.stderr.contains("\"t0\" is not an end effector"),
        "{}",
        out.stderr
    );
    let dir = common::Scratch::new("reduce-bad");
    let bad = dir.join("bad.ron");
    std::fs::write(
        &bad,
        "Mechanism(links: [Link(name: \"a\")], joints: [], end_effectors: [\"a\"])",
    )
    .unwrap();
    let out = impulse(&["reduce", bad.to_str().unwrap()]);
    assert!(
        !out.ok && out.stderr.contains("end effector `a`"),
        "{}",
        out.stderr
    );
}

/// `--html` replays the reduced simulation: the page lists the links in the order of `--out`,
/// then the base (free: it moves) and the ground slab (fixed), and holds the frames of
/// `--out`; `--static` has nothing to replay and is refused.
#[test]
fn a_simulation_replays_as_a_page() {
    let dir = common::Scratch::new("reduce-html");
    let (html, csv) = (dir.join("legged.html"), dir.join("legged.csv"));
    let legged = mechanism("legged-6.ron");
    let out = impulse(&[
        "reduce",
        &legged,
        "--until",
        "0.1",
        "--ground",
        "-0.3",
        "--html",
        html.to_str().unwrap(),
        "--out",
        csv.to_str().unwrap(),
    ]);
    assert!(out.ok, "{}", out.stderr);
    let page = std::fs::read_to_string(&html).unwrap();
    let open = "id=\"impulse-header\">";
    let start = page.find(open).unwrap() + open.len();
    let end = start + page[start..].find("</script>").unwrap();
    let header: serde_json::Value = serde_json::from_str(&page[start..end]).unwrap();
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut names: Vec<&str> = Vec::new();
    for line in text.lines().skip(1) {
        let name = line.split(',').nth(1).unwrap();
        if names.contains(&name) {
            break;
        }
        names.push(name);
    }
    let frames = text.lines().skip(1).count() / names.len();
    let bodies = header["bodies"].as_array().unwrap();
    let listed: Vec<&str> = bodies.iter().map(|b| b["name"].as_str().unwrap()).collect();
    assert_eq!(listed[..names.len()], names[..]);
    assert_eq!(listed[names.len()..], ["body", "ground"]);
    assert_eq!(bodies[names.len()]["kind"], "dynamic", "a free base moves");
    assert_eq!(bodies[names.len() + 1]["kind"], "fixed");
    assert_eq!(header["frames"].as_u64(), Some(frames as u64));
    assert_eq!(header["model"], "FORK⁻¹S reduced model");

    let refused = impulse(&[
        "reduce",
        &legged,
        "--static",
        "--html",
        html.to_str().unwrap(),
    ]);
    assert!(
        !refused.ok && refused.stderr.contains("leave out --static"),
        "{}",
        refused.stderr
    );
}

/// Names with quotes and control characters are written as JSON strings: the printed summary,
/// the `--static` report and a `--out` JSON trajectory all parse and keep the names.
#[test]
fn hostile_names_stay_valid_json() {
    let dir = common::Scratch::new("reduce-names");
    let text = std::fs::read_to_string(mechanism("y.ron")).unwrap();
    let hostile = "a\"3\u{1}";
    let edited = text
        .replace("\"a3\"", &format!("\"a\\\"3{}\"", '\u{1}'))
        .replace("name: \"y-4\"", "name: \"y \\\"4\\\"\"");
    let path = dir.join("hostile.ron");
    std::fs::write(&path, edited).unwrap();
    let json = dir.join("y.json");
    let load = format!("{hostile}:1,0,0");
    let out = impulse(&[
        "reduce",
        path.to_str().unwrap(),
        "--load",
        &load,
        "--until",
        "0.01",
        "--out",
        json.to_str().unwrap(),
    ]);
    assert!(out.ok, "{}", out.stderr);
    assert_eq!(
        out.json.expect("the summary is JSON")["mechanism"],
        "y \"4\""
    );
    let written: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert!(
        written["bodies"]
            .as_array()
            .unwrap()
            .iter()
            .any(|b| b == hostile)
    );
    let out = impulse(&[
        "reduce",
        path.to_str().unwrap(),
        "--load",
        &load,
        "--static",
    ]);
    assert!(out.ok, "{}", out.stderr);
    let report = out.json.expect("the static report is JSON");
    assert!(
        report["end_effectors"]
            .as_array()
            .unwrap()
            .iter()
            .any(|e| e["link"] == hostile)
    );
}

/// An output in a directory that does not exist is refused before the simulation, naming it.
#[test]
fn a_missing_output_directory_is_refused_before_the_run() {
    for flag in ["--html", "--out"] {
        let file = if flag == "--html" {
            "/no/such/dir/y.html"
        } else {
            "/no/such/dir/y.csv"
        };
        let out = impulse(&["reduce", &mechanism("y.ron"), "--until", "100", flag, file]);
        assert!(
            !out.ok && out.stderr.contains("/no/such/dir") && out.stderr.contains(flag),
            "{flag}: {}",
            out.stderr
        );
    }
}
