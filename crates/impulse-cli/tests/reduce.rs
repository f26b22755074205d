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

/// The near-aligned chain's dropped direction against the stretch along z (unit vectors):
/// the anchors' 1e-7 m offset tilts it by 5e-7 rad, so its z is 1 − 1.3e-13.
const DIRECTION_TOL: f64 = 1e-9;
/// The lever's compliance entries (≤ 0.01, m/N …) against `c S Sᵀ`: a few ulp.
const COMPLIANCE_TOL: f64 = 1e-15;
/// The lever's stiffness entries (≤ 64) against `S Sᵀ/(c|S|⁴)`: its inverse by SVD, ~1e-13.
const STIFFNESS_TOL: f64 = 1e-9;
/// The reduced lever's position (m) against `L (cos cLF, sin cLF)`: the exponential's
/// rounding.
const POSITION_TOL: f64 = 1e-14;
/// The full lever's position (m) against the bisection of `θ = cLF cos θ`: the statics stop
/// at 1e-9 of the force scale, ~1e-11 m here.
const FULL_POSITION_TOL: f64 = 1e-10;

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

/// A mechanism past the size limit is refused before any work, naming its size, the limit
/// and how to raise it; `--max-dof` moves the limit (the lever's one hinge: 1 dof).
#[test]
fn a_mechanism_over_the_size_limit_names_the_limit() {
    let n = impulse_reduced::MAX_DOF / 3 + 1;
    let mut text = String::from("Mechanism(links: [Link(name: \"l0\")");
    for i in 1..=n {
        text += &format!(
            ", Link(name: \"l{i}\", position: (0.0, 0.0, {i}.0), mass: 1.0, inertia: (0.1, 0.1, 0.1))"
        );
    }
    text += "], joints: [";
    for i in 1..=n {
        text += &format!(
            "Joint(name: \"j{i}\", parent: \"l{}\", child: \"l{i}\", anchor: (0.0, 0.0, {}.0), kind: Ball, compliance: [0.001]),",
            i - 1,
            i - 1
        );
    }
    text += &format!("], end_effectors: [\"l{n}\"])");
    let dir = common::Scratch::new("reduce-large");
    let big = dir.join("big.ron");
    std::fs::write(&big, text).unwrap();
    let out = impulse(&["reduce", big.to_str().unwrap()]);
    let want = format!(
        "{} links and {} joint degrees of freedom, over the limit of {}",
        n + 1,
        3 * n,
        impulse_reduced::MAX_DOF
    );
    assert!(
        !out.ok && out.stderr.contains(&want) && out.stderr.contains("--max-dof"),
        "{}",
        out.stderr
    );
    for (limit, ok) in [("0", false), ("1", true)] {
        let out = impulse(&[
            "reduce",
            &mechanism("lever.ron"),
            "--static",
            "--max-dof",
            limit,
        ]);
        assert_eq!(out.ok, ok, "{}", out.stderr);
        assert_eq!(
            out.stderr.contains("over the limit of 0"),
            !ok,
            "{}",
            out.stderr
        );
    }
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

/// The near-aligned chain (three balls, the third anchor 1e-7 m off the line of the others)
/// builds: the joints allow six end-effector directions, and the stretch along the chain (z of
/// the tip: the one motion three collinear balls cannot make) is treated as rigid, reported
/// with its compliance (below the threshold) and warned about on stderr.
#[test]
fn a_near_aligned_chain_builds_and_names_what_it_treats_as_rigid() {
    let out = impulse(&[
        "reduce",
        &mechanism("near-aligned.ron"),
        "--load",
        "l3:1,0,0",
        "--static",
    ]);
    assert!(out.ok, "{}", out.stderr);
    assert!(
        out.stderr.contains("warning: near-singular"),
        "{}",
        out.stderr
    );
    let json = out.json.expect("JSON output");
    let rank = &json["rank"];
    assert_eq!(rank["allowed"], 6);
    assert_eq!(rank["rank"], 5);
    let rigid = &rank["treated_as_rigid"][0];
    let tau = rank["tsvd"].as_f64().unwrap();
    assert!(rigid["compliance_relative"].as_f64().unwrap() < tau);
    let twist: Vec<f64> = rigid["twist"]["l3"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert!(
        twist[2].abs() > 1.0 - DIRECTION_TOL,
        "the stretch along z: {twist:?}"
    );
    // Every map is reported: the weighted motions decide, then C and A.
    let maps: Vec<&str> = json["maps"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["map"].as_str().unwrap())
        .collect();
    assert!(
        maps.iter()
            .any(|m| m.starts_with("end-effector compliance C")),
        "{maps:?}"
    );
    assert!(json["conditioning"]["cond_C"].as_f64().unwrap() >= 1.0);
    // A threshold below what the walk resolves is refused, naming what to do.
    let refused = impulse(&[
        "reduce",
        &mechanism("near-aligned.ron"),
        "--static",
        "--tsvd",
        "1e-17",
    ]);
    assert!(
        !refused.ok
            && refused.stderr.contains("cannot resolve")
            && refused.stderr.contains("--tsvd"),
        "{}",
        refused.stderr
    );
}

/// Bad numbers are refused before anything is built, naming the flag.
#[test]
fn bad_numbers_are_refused_naming_the_flag() {
    let y = mechanism("y.ron");
    for (flag, value) in [
        ("--tsvd", "-1"),
        ("--tsvd", "nan"),
        ("--tsvd", "0"),
        ("--tsvd", "1"),
        ("--dt", "-1"),
        ("--dt", "0"),
        ("--until", "-1"),
        ("--threads", "0"),
    ] {
        let out = impulse(&["reduce", &y, flag, value]);
        assert!(
            !out.ok && out.stderr.starts_with("error: ") && out.stderr.contains(flag),
            "{flag} {value}: {}",
            out.stderr
        );
    }
    // Sizes past their limits end at once with the limit named: a step count the run could not
    // finish (it panicked on a buffer's size before) and more threads than the machine can use
    // (it hung while starting them). The limits are computed here from the machine and the
    // flags, not read from the code that checks them.
    let most = 4 * std::thread::available_parallelism().map_or(1, usize::from);
    for (args, needle) in [
        (
            vec!["--dt", "1e-300"],
            "1.000e300 steps, over the limit".to_owned(),
        ),
        (
            vec!["--dt", "1e-6", "--until", "1e4"],
            "1.000e10 steps".to_owned(),
        ),
        (
            vec!["--threads", "100000"],
            format!("at most {most} on this machine"),
        ),
    ] {
        let start = std::time::Instant::now();
        let mut all = vec!["reduce", &y];
        all.extend(&args);
        let out = impulse(&all);
        assert!(
            !out.ok && out.stderr.starts_with("error: ") && out.stderr.contains(&needle),
            "{args:?}: {}",
            out.stderr
        );
        assert!(
            start.elapsed() < std::time::Duration::from_secs(1),
            "{args:?}"
        );
    }
    // A valid threshold is taken and reported.
    let ok = impulse(&["reduce", &y, "--tsvd", "1e-10", "--until", "0.01"]);
    assert!(ok.ok, "{}", ok.stderr);
    assert_eq!(ok.json.unwrap()["rank"]["tsvd"].as_f64(), Some(1e-10));
}

/// `us_per_step` averages the steps after the warm-up: 20 steps, at most a quarter of the
/// run; `--threads 1` is reported.
#[test]
fn us_per_step_times_the_steps_after_the_warm_up() {
    for (until, timed) in [("0.2", 180), ("0.04", 30)] {
        let out = impulse(&[
            "reduce",
            &mechanism("y.ron"),
            "--until",
            until,
            "--threads",
            "1",
        ]);
        assert!(out.ok, "{}", out.stderr);
        let json = out.json.unwrap();
        assert_eq!(json["timed_steps"].as_u64(), Some(timed), "--until {until}");
        assert_eq!(json["threads"].as_u64(), Some(1));
        let mean = json["us_per_step"].as_f64().unwrap();
        let median = json["us_per_step_median"].as_f64().unwrap();
        assert!(mean > 0.0 && median > 0.0);
    }
}

/// The worked example of docs/forks.md ("Conventions"): the lever's compliance and stiffness
/// against their closed forms (`C = c S Sᵀ`, `S = (0, L, 0, 0, 0, 1)`, `K = S Sᵀ/(c|S|⁴)`), its
/// static positions against theirs (the follower load turns the reduced lever by exactly
/// `c L F`, the world-fixed one the full lever by `θ = c L F cos θ`), and every number of the
/// json block the document shows against what the command prints and writes.
#[test]
fn worked_example_of_the_docs() {
    let dir = common::Scratch::new("reduce-worked-example");
    let file = dir.join("lever.json");
    let out = impulse(&[
        "reduce",
        &mechanism("lever.ron"),
        "--load",
        "arm:0,10,0",
        "--static",
        "--compliance",
        file.to_str().unwrap(),
    ]);
    assert!(out.ok, "{}", out.stderr);
    let printed = out.json.unwrap();
    let written: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&file).unwrap()).unwrap();
    // Closed forms.
    let (c, l, f) = (0.01, 0.5, 10.0);
    let s = [0.0, l, 0.0, 0.0, 0.0, 1.0];
    let s2: f64 = s.iter().map(|x| x * x).sum();
    for a in 0..6 {
        for b in 0..6 {
            let got = |key: &str| written[key][a][b].as_f64().unwrap();
            assert!((got("compliance") - c * s[a] * s[b]).abs() < COMPLIANCE_TOL);
            assert!((got("stiffness") - s[a] * s[b] / (c * s2 * s2)).abs() < STIFFNESS_TOL);
        }
    }
    let position = |key: &str| -> Vec<f64> {
        printed["end_effectors"][0][key]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect()
    };
    let turn = c * l * f;
    let reduced = position("reduced");
    assert!(
        (reduced[0] - l * turn.cos()).abs() < POSITION_TOL
            && (reduced[1] - l * turn.sin()).abs() < POSITION_TOL
    );
    // θ = c L F cos θ by bisection.
    let (mut lo, mut hi) = (0.0_f64, 1.0_f64);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if mid - turn * mid.cos() > 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let full = position("full");
    assert!(
        (full[0] - l * lo.cos()).abs() < FULL_POSITION_TOL
            && (full[1] - l * lo.sin()).abs() < FULL_POSITION_TOL
    );
    // The document's block: every number in it as printed (the first part) or written (the
    // `lever.json` part).
    let doc =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/forks.md"))
            .unwrap();
    let marker = "<!-- worked-example: the test reads the next json block -->";
    let start = doc.find(marker).expect("the worked example's marker") + marker.len();
    let open = start + doc[start..].find("```json").unwrap() + "```json".len();
    let close = open + doc[open..].find("```").unwrap();
    let block: serde_json::Value = serde_json::from_str(&doc[open..close]).expect("valid json");
    let mut shown = block.clone();
    let file_part = shown.as_object_mut().unwrap().remove("lever.json").unwrap();
    same_numbers("output", &shown, &printed);
    same_numbers("lever.json", &file_part, &written);
}

/// Every number of `shown` (objects' keys followed into `actual`) equals `actual`'s to 1e-9
/// relative (the document prints `relative_error` to four digits: 1e-3 there).
fn same_numbers(path: &str, shown: &serde_json::Value, actual: &serde_json::Value) {
    use serde_json::Value;
    match shown {
        Value::Object(o) => {
            for (k, v) in o {
                same_numbers(&format!("{path}.{k}"), v, &actual[k]);
            }
        }
        Value::Array(a) => {
            for (i, v) in a.iter().enumerate() {
                same_numbers(&format!("{path}[{i}]"), v, &actual[i]);
            }
        }
        Value::Number(n) => {
            let (x, y) = (n.as_f64().unwrap(), actual.as_f64().unwrap_or(f64::NAN));
            let tol = if path.ends_with("relative_error") {
                1e-3
            } else {
                1e-9
            };
            assert!(
                (x - y).abs() <= tol * x.abs().max(1e-300) || x == y,
                "docs/forks.md {path}: {x} but the command gives {y}"
            );
        }
        other => assert_eq!(other, actual, "docs/forks.md {path}"),
    }
}

/// `--max-wall` stops a dynamics run between steps with its outputs valid: the report names
/// the stop and the steps taken, fewer than asked, and the trajectory file ends at that step's
/// time (read back here). A limit that is not a positive number is refused.
#[test]
fn a_wall_time_limit_stops_the_run_with_valid_outputs() {
    let helix = mechanism("helix-400.ron");
    let dir = std::env::temp_dir().join(format!("reduce-max-wall-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let csv = dir.join("traj.csv");
    let out = impulse(&[
        "reduce",
        &helix,
        "--until",
        "1000",
        "--dt",
        "1e-3",
        "--max-wall",
        "0.2",
        "--out",
        csv.to_str().unwrap(),
    ]);
    assert!(out.ok, "{}", out.stderr);
    let json = out.json.unwrap();
    let steps = json["steps"].as_u64().unwrap();
    assert!(steps < 1_000_000, "{json}");
    assert!(
        json["stopped"]
            .as_str()
            .is_some_and(|s| s.starts_with("at the wall-time limit")),
        "{json}"
    );
    let text = std::fs::read_to_string(&csv).unwrap();
    let last: f64 = text
        .lines()
        .skip(1)
        .map(|r| r.split(',').next().unwrap().parse::<f64>().unwrap())
        .fold(0.0, f64::max);
    assert!(
        (last - steps as f64 * 1e-3).abs() < 1e-9,
        "{last} vs {steps} steps"
    );
    let _ = std::fs::remove_dir_all(&dir);
    for bad in ["0", "-1", "nan"] {
        let out = impulse(&["reduce", &helix, "--max-wall", bad]);
        assert!(
            !out.ok && out.stderr.contains("--max-wall"),
            "{bad}: {}",
            out.stderr
        );
    }
}

/// A finite load too large for double precision (1e300 N on the helix's tip) makes the reduced
/// state non-finite at the first step: the run fails naming the link and the time, and prints
/// no `NaN` (it printed `"end_effector_0": [NaN, NaN, NaN]`, not even JSON, and exited 0).
/// The same load at 1 N runs and ends finite.
#[test]
fn a_load_that_overflows_fails_naming_the_link_and_time() {
    let run = |load: &str| {
        impulse(&[
            "reduce",
            &mechanism("helix-100.ron"),
            "--load",
            load,
            "--until",
            "0.01",
        ])
    };
    let out = run("l100:1e300,0,0");
    assert!(!out.ok);
    assert!(out.json.is_none(), "printed {:?}", out.json);
    assert!(
        out.stderr.contains("not finite at t = 0.00100 s") && out.stderr.contains("`l100`"),
        "{}",
        out.stderr
    );
    let out = run("l100:1,0,0");
    assert!(out.ok, "{}", out.stderr);
    let json = out.json.expect("JSON");
    let ee = json["end_effector_0"].as_array().expect("a point");
    assert!(
        ee.iter().all(|x| x.as_f64().is_some_and(f64::is_finite)),
        "{ee:?}"
    );
}
