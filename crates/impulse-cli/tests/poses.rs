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
