//! End-to-end tests of `impulse bowling`: shards merged equal the unsharded run's file byte
//! for byte (throws that hit the pins), a file summarised again prints the same figures,
//! the CSV and SVG are written, the default alley round-trips through `--print-alley`, and
//! malformed arguments are refused.

mod common;

use common::impulse_text as impulse;

/// Two throws of each kind into the pocket, short settle: pins fly, the run stays short.
const POCKET_STUDY: [&str; 8] = [
    "--throws", "2", "--center", "0.08", "--width", "0.04", "--settle", "1",
];

/// The printed figures, without the run's wall time and the shard line.
fn figures(stdout: &str) -> String {
    common::lines_from(stdout, "mean pins felled")
}

#[test]
fn shards_merged_equal_the_whole_run_byte_for_byte() {
    let dir = common::Scratch::new("bowling-shards");
    let whole = dir.join("whole.json");
    let (csv, svg) = (dir.join("bins.csv"), dir.join("fig.svg"));
    let mut args = vec!["bowling"];
    args.extend(POCKET_STUDY);
    args.extend([
        "--threads",
        "2",
        "--out",
        whole.to_str().unwrap(),
        "--csv",
        csv.to_str().unwrap(),
        "--svg",
        svg.to_str().unwrap(),
    ]);
    let (ok, run_out, err) = impulse(&args);
    assert!(ok, "{err}");
    assert!(run_out.contains("throws:      4 of 4"), "{run_out}");
    // Pocket throws fell pins: the file's counts are not all zero.
    let text = std::fs::read_to_string(&whole).unwrap();
    assert!(
        text.contains("\"felled\": ") && !text.contains("\"felled\": 0,"),
        "{text}"
    );
    // 8 bins of 5 mm over the 4 cm window, and a plot.
    assert_eq!(std::fs::read_to_string(&csv).unwrap().lines().count(), 9);
    assert!(std::fs::read_to_string(&svg).unwrap().starts_with("<svg"));
    let mut shards = Vec::new();
    for k in 0..2 {
        let f = dir.join(format!("shard-{k}.json"));
        let mut args = vec!["bowling"];
        args.extend(POCKET_STUDY);
        let shard = format!("{k}/2");
        args.extend([
            "--threads",
            "1",
            "--shard",
            &shard,
            "--out",
            f.to_str().unwrap(),
        ]);
        let (ok, _, err) = impulse(&args);
        assert!(ok, "{err}");
        shards.push(f);
    }
    let merged = dir.join("merged.json");
    let (ok, out, err) = impulse(&[
        "bowling",
        "merge",
        shards[1].to_str().unwrap(),
        shards[0].to_str().unwrap(),
        "--out",
        merged.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(out.contains("4 of 4 throws"), "{out}");
    assert_eq!(
        std::fs::read(&merged).unwrap(),
        std::fs::read(&whole).unwrap()
    );
    // Summarising the file prints the run's figures.
    let (ok, again, err) = impulse(&["bowling", "--from", merged.to_str().unwrap()]);
    assert!(ok, "{err}");
    assert_eq!(figures(&again), figures(&run_out));
    // A shard merged twice is refused.
    let (ok, _, err) = impulse(&[
        "bowling",
        "merge",
        shards[0].to_str().unwrap(),
        shards[0].to_str().unwrap(),
        "--out",
        merged.to_str().unwrap(),
    ]);
    assert!(!ok && err.contains("in two files"), "{err}");
}

#[test]
fn the_default_alley_round_trips_and_bad_alleys_are_named() {
    let dir = common::Scratch::new("bowling-alley");
    let (ok, text, err) = impulse(&["bowling", "--print-alley"]);
    assert!(ok, "{err}");
    let good = dir.join("alley.ron");
    std::fs::write(&good, &text).unwrap();
    // The printed alley is read back: its throw-0 scene equals the default's.
    let scene = |extra: &[&str]| {
        let mut args = vec!["bowling", "--throws", "2", "--scene", "0"];
        args.extend(extra);
        let (ok, out, err) = impulse(&args);
        assert!(ok, "{err}");
        out
    };
    assert_eq!(scene(&["--alley", good.to_str().unwrap()]), scene(&[]));
    let bad = dir.join("bad.ron");
    std::fs::write(&bad, text.replace("lane_width: ", "lane_width: -")).unwrap();
    let (ok, _, err) = impulse(&["bowling", "--alley", bad.to_str().unwrap()]);
    assert!(!ok && err.contains("lane_width"), "{err}");
    std::fs::write(&bad, "Alley(lane_width: 1.0,").unwrap();
    let (ok, _, err) = impulse(&["bowling", "--alley", bad.to_str().unwrap()]);
    assert!(!ok && err.contains("bad.ron"), "{err}");
}

#[test]
fn malformed_arguments_are_refused() {
    for (args, says) in [
        (vec!["bowling", "--shard", "3/2"], "0 ≤ K < N"),
        (vec!["bowling", "--shard", "x"], "expected K/N"),
        (vec!["bowling", "--throws", "0"], "at least one throw"),
        (vec!["bowling", "--speed", "-1"], "speed"),
        (vec!["bowling", "--width", "0"], "window_width"),
        (vec!["bowling", "--angle", "60"], "hook_angle_degrees"),
        (
            vec!["bowling", "--alley", "no-such-alley.ron"],
            "cannot read",
        ),
        (
            vec!["bowling", "--from", "no-such-study.json"],
            "cannot read",
        ),
        (
            vec!["bowling", "--throws", "3", "--scene", "6"],
            "throws 0 to 5",
        ),
    ] {
        let (ok, _, err) = impulse(&args);
        assert!(!ok, "{args:?} was accepted");
        assert!(err.contains(says), "{args:?}: {err}");
    }
    // A file that is not a study is named.
    let dir = common::Scratch::new("bowling-args");
    let f = dir.join("x.json");
    std::fs::write(&f, "{}").unwrap();
    let (ok, _, err) = impulse(&["bowling", "--from", f.to_str().unwrap()]);
    assert!(!ok && err.contains("not a bowling study file"), "{err}");
}

/// `--scene N` prints a scene that `impulse run` accepts; the first tenth of a second runs.
#[test]
fn a_throws_scene_runs() {
    let dir = common::Scratch::new("bowling-scene");
    let (ok, text, err) = impulse(&["bowling", "--throws", "4", "--scene", "3"]);
    assert!(ok, "{err}");
    assert!(
        text.contains("Hook throw 3"),
        "{}",
        &text[..200.min(text.len())]
    );
    let f = dir.join("throw.ron");
    std::fs::write(&f, &text).unwrap();
    let (ok, out, err) = impulse(&["run", f.to_str().unwrap(), "--until", "0.1"]);
    assert!(ok, "{err}");
    assert!(
        out.contains("bowling-throw-3") && out.contains("simulated time:   0.1 s"),
        "{out}"
    );
}

/// A bowling study stopped at a wall-time limit and run again with the same arguments reads
/// back the throws finished before, runs only the others, and writes the file of the same
/// study never stopped, byte for byte.
#[test]
fn a_stopped_study_run_again_does_only_the_missing_throws() {
    let dir = common::Scratch::new("bowling-resume");
    let whole = dir.join("whole.json");
    let run = |out: &std::path::Path, extra: &[&str]| {
        let mut args = vec!["bowling", "--throws", "6", "--out", out.to_str().unwrap()];
        args.extend_from_slice(extra);
        common::impulse_text(&args)
    };
    let (ok, _, err) = run(&whole, &[]);
    assert!(ok, "{err}");
    let out = dir.join("stopped.json");
    let (ok, stdout, err) = run(&out, &["--max-wall", "0.8", "--threads", "1"]);
    assert!(ok, "{err}");
    let line = stdout
        .lines()
        .find(|l| l.starts_with("stopped:"))
        .unwrap_or_else(|| panic!("no stopped line: {stdout}"));
    let done: u64 = line
        .split("after ")
        .nth(1)
        .unwrap()
        .split(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(done < 12, "{line}");
    assert!(!out.exists());
    let (ok, stdout, err) = run(&out, &[]);
    assert!(ok, "{err}");
    if done > 0 {
        assert!(
            stdout.contains(&format!("resumed:          {done} throws read back")),
            "{stdout}"
        );
    }
    assert_eq!(std::fs::read(&out).unwrap(), std::fs::read(&whole).unwrap());
    assert!(!dir.join("stopped.json.partial").exists());
}
