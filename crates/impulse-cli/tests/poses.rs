//! End-to-end tests of `impulse poses`: shards merged equal the unsharded run's file byte for
//! byte, a file summarised again prints the same table, the quasi-static column of the
//! 1 × 2 × 3 box is the thesis's, and malformed arguments are refused.

mod common;

use std::path::{Path, PathBuf};

use common::impulse_text as impulse;

fn part(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/parts")
        .join(name)
}

/// The table's lines (from the header on), without the run's wall time.
fn table(stdout: &str) -> String {
    common::lines_from(stdout, "pose")
}

#[test]
fn shards_merged_equal_the_whole_run_byte_for_byte() {
    let dir = common::Scratch::new("poses-shards");
    let boxp = part("box-1x2x3.ron");
    let b = boxp.to_str().unwrap();
    let whole = dir.join("whole.json");
    let (ok, out, err) = impulse(&[
        "poses",
        b,
        "--drops",
        "12",
        "--max-time",
        "3",
        "--out",
        whole.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    // The thesis's quasi-static share of the box's 2 × 3 face pair (V22): 64.50 %.
    assert!(out.contains("64.50 %"), "{out}");
    let mut shards = Vec::new();
    for k in 0..3 {
        let f = dir.join(format!("shard-{k}.json"));
        let (ok, _, err) = impulse(&[
            "poses",
            b,
            "--drops",
            "12",
            "--max-time",
            "3",
            "--threads",
            "1",
            "--shard",
            &format!("{k}/3"),
            "--out",
            f.to_str().unwrap(),
        ]);
        assert!(ok, "{err}");
        shards.push(f);
    }
    let merged = dir.join("merged.json");
    let mut args = vec!["poses", "merge"];
    args.extend(shards.iter().rev().map(|p| p.to_str().unwrap()));
    args.extend(["--out", merged.to_str().unwrap()]);
    let (ok, out, err) = impulse(&args);
    assert!(ok, "{err}");
    assert!(out.contains("12 of 12 drops"), "{out}");
    assert_eq!(
        std::fs::read(&merged).unwrap(),
        std::fs::read(&whole).unwrap()
    );
    // Summarising the file prints the run's table.
    let (ok, again, err) = impulse(&["poses", b, "--from", merged.to_str().unwrap()]);
    assert!(ok, "{err}");
    let (_, first, _) = impulse(&["poses", b, "--from", whole.to_str().unwrap()]);
    assert_eq!(table(&again), table(&first));
    // A shard merged twice is refused; a file of another part is refused.
    let (ok, _, err) = impulse(&[
        "poses",
        "merge",
        shards[0].to_str().unwrap(),
        shards[0].to_str().unwrap(),
        "--out",
        merged.to_str().unwrap(),
    ]);
    assert!(!ok && err.contains("in two files"), "{err}");
    let cube = part("cube.ron");
    let (ok, _, err) = impulse(&[
        "poses",
        cube.to_str().unwrap(),
        "--from",
        whole.to_str().unwrap(),
    ]);
    assert!(!ok && err.contains("not of this \"cube\""), "{err}");
    // The same name with another shape is refused too: the file records the stable facets.
    let dir2 = common::Scratch::new("poses-renamed");
    std::fs::write(
        dir2.join("box-1x2x3.ron"),
        "Part(name: \"box-1x2x3\", shape: Box(half_extents: (0.005, 0.01, 0.02)))",
    )
    .unwrap();
    let (ok, _, err) = impulse(&[
        "poses",
        dir2.join("box-1x2x3.ron").to_str().unwrap(),
        "--from",
        whole.to_str().unwrap(),
    ]);
    assert!(!ok && err.contains("part file changed"), "{err}");
}

#[test]
fn malformed_arguments_are_refused() {
    let b = part("box-1x2x3.ron");
    let b = b.to_str().unwrap();
    for (args, says) in [
        (vec!["poses", b, "--shard", "3/2"], "0 ≤ K < N"),
        (vec!["poses", b, "--shard", "1/0"], "0 ≤ K < N"),
        (vec!["poses", b, "--shard", "x"], "expected K/N"),
        (vec!["poses", b, "--drops", "0"], "at least one drop"),
        (vec!["poses", b, "--friction", "-1"], "friction"),
        (vec!["poses", b, "--cone", "95"], "--cone"),
        (vec!["poses", b, "--confidence", "1.5"], "--confidence"),
        (vec!["poses"], "a part file is needed"),
        (vec!["poses", "no-such-part.ron"], "cannot read"),
        (
            vec!["poses", b, "--drops", "10", "--scene", "10"],
            "drops 0 to 9",
        ),
    ] {
        let (ok, _, err) = impulse(&args);
        assert!(!ok, "{args:?} was accepted");
        assert!(err.contains(says), "{args:?}: {err}");
    }
}

/// `--scene N` prints a scene file that `impulse run` accepts and runs to its end, with the
/// part at rest there.
#[test]
fn a_drops_scene_runs_in_impulse_run() {
    let dir = common::Scratch::new("poses-scene");
    let b = part("box-1x2x3.ron");
    let (ok, text, err) = impulse(&[
        "poses",
        b.to_str().unwrap(),
        "--scene",
        "3",
        "--max-time",
        "3",
    ]);
    assert!(ok, "{err}");
    assert!(text.contains("box-1x2x3-drop-3"), "{text}");
    let file = dir.join("drop.ron");
    std::fs::write(&file, text).unwrap();
    let (ok, out, err) = impulse(&["run", file.to_str().unwrap()]);
    assert!(ok, "{err}");
    assert!(out.contains("simulated time:   3 s"), "{out}");
    assert!(
        out.contains("0.000000e0 at end"),
        "the part is at rest: {out}"
    );
}

/// The drop count of the resumable studies below, and their part: 2 000 drops of the cube
/// run in a few seconds.
const RESUMED_DROPS: &str = "2000";

/// The number after `key` in the line of `stdout` that starts with `line`.
fn count_after(stdout: &str, line: &str, key: &str) -> Option<u64> {
    let l = stdout.lines().find(|l| l.starts_with(line))?;
    let rest = &l[l.find(key)? + key.len()..];
    rest.split_whitespace().next()?.parse().ok()
}

/// A study stopped at a wall-time limit, then one killed (SIGKILL) mid-run, then run again
/// with the same arguments: each rerun reads back the drops finished before and runs only the
/// others, and the final file equals, byte for byte, the file of the same study never
/// stopped. The stopped run says so and names the journal.
#[test]
fn a_stopped_or_killed_study_run_again_does_only_the_missing_drops() {
    let dir = common::Scratch::new("poses-resume");
    let cube = part("cube.ron");
    let c = cube.to_str().unwrap();
    let whole = dir.join("whole.json");
    let (ok, _, err) = impulse(&[
        "poses",
        c,
        "--drops",
        RESUMED_DROPS,
        "--out",
        whole.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let reference = std::fs::read(&whole).unwrap();
    // Stopped at the wall-time limit.
    let out = dir.join("stopped.json");
    let o = out.to_str().unwrap();
    let args = ["poses", c, "--drops", RESUMED_DROPS, "--out", o];
    let limited: Vec<&str> = args.iter().copied().chain(["--max-wall", "0.2"]).collect();
    let (ok, stdout, err) = impulse(&limited);
    assert!(ok, "{err}");
    let done = count_after(&stdout, "stopped:", "after ").expect("a stopped line");
    assert!(done > 0 && done < 2000, "{stdout}");
    assert!(
        !out.exists(),
        "the study's file is written only when it is whole"
    );
    let journal = dir.join("stopped.json.partial");
    let lines = std::fs::read_to_string(&journal).unwrap().lines().count() as u64;
    assert_eq!(lines, done + 1, "a header and one line per drop done");
    let (ok, stdout, err) = impulse(&args);
    assert!(ok, "{err}");
    assert_eq!(
        count_after(&stdout, "resumed:", "resumed:"),
        Some(done),
        "{stdout}"
    );
    assert_eq!(std::fs::read(&out).unwrap(), reference);
    assert!(
        !journal.exists(),
        "the journal is removed once the file is written"
    );
    // Killed mid-run (the last line may be cut short).
    let out = dir.join("killed.json");
    let o = out.to_str().unwrap();
    let args = [
        "poses",
        c,
        "--drops",
        RESUMED_DROPS,
        "--out",
        o,
        "--threads",
        "1",
    ];
    let journal = dir.join("killed.json.partial");
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_impulse"))
        .args(args)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let waited = std::time::Instant::now();
    while std::fs::read_to_string(&journal).map_or(0, |t| t.lines().count()) < 300 {
        assert!(waited.elapsed().as_secs() < 60, "the journal never grew");
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let kept = std::fs::read_to_string(&journal).unwrap().lines().count() as u64;
    assert!(kept < 2001, "killed after the end");
    let (ok, stdout, err) = impulse(&args);
    assert!(ok, "{err}");
    let resumed = count_after(&stdout, "resumed:", "resumed:").expect("a resumed line");
    assert!(
        resumed + 1 >= kept - 1 && resumed < 2000,
        "{resumed} read back of {kept} lines"
    );
    assert_eq!(std::fs::read(&out).unwrap(), reference);
}

/// A journal cut short in its header (killed as it was created) holds nothing: the study
/// starts afresh and completes.
#[test]
fn a_journal_with_a_torn_header_starts_afresh() {
    let dir = common::Scratch::new("poses-torn");
    let cube = part("cube.ron");
    let out = dir.join("study.json");
    std::fs::write(dir.join("study.json.partial"), "{\"journal\": \"impul").unwrap();
    let (ok, _, err) = impulse(&[
        "poses",
        cube.to_str().unwrap(),
        "--drops",
        "20",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(out.exists() && !dir.join("study.json.partial").exists());
}

/// A journal of another study (another seed here) is refused, naming it; nothing is run.
#[test]
fn a_journal_of_another_study_is_refused() {
    let dir = common::Scratch::new("poses-journal");
    let cube = part("cube.ron");
    let out = dir.join("study.json");
    let o = out.to_str().unwrap();
    let c = cube.to_str().unwrap();
    let (ok, _, err) = impulse(&[
        "poses",
        c,
        "--drops",
        "50",
        "--out",
        o,
        "--max-wall",
        "1e-9",
    ]);
    assert!(ok, "{err}");
    assert!(dir.join("study.json.partial").exists());
    let (ok, _, err) = impulse(&["poses", c, "--drops", "50", "--out", o, "--seed", "2"]);
    assert!(!ok);
    assert!(
        err.contains("study.json.partial") && err.contains("another study"),
        "{err}"
    );
}
