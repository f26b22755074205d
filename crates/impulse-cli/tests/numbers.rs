//! Never a silent non-number: every bundled scene, run briefly, writes a summary, a CSV and a
//! JSON trajectory and a glTF file in which every number is a number (no `NaN`, `inf` or
//! `null` where a value belongs). Numbers are read back by parsing, not by trusting the writer.

mod common;

use common::{Scratch, fixture};
use std::process::Command;

/// Simulated time of each run (s): long enough for the first contacts of every scene.
const UNTIL: &str = "0.1";

/// Whether a text token spells a non-number as a writer would print one.
fn non_number(token: &str) -> bool {
    let t = token.trim().trim_matches('"').to_ascii_lowercase();
    matches!(
        t.as_str(),
        "nan" | "-nan" | "inf" | "-inf" | "+inf" | "infinity" | "-infinity" | "null"
    )
}

/// Every number of a JSON value is finite, and nothing in it is `null`; `path` names where.
fn check_json(v: &serde_json::Value, path: &str, bad: &mut Vec<String>) {
    match v {
        serde_json::Value::Null => bad.push(format!("{path}: null")),
        serde_json::Value::Number(n) if !n.as_f64().is_some_and(f64::is_finite) => {
            bad.push(format!("{path}: {n}"));
        }
        serde_json::Value::String(s) if non_number(s) => bad.push(format!("{path}: {s:?}")),
        serde_json::Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                check_json(x, &format!("{path}[{i}]"), bad);
            }
        }
        serde_json::Value::Object(o) => {
            for (k, x) in o {
                check_json(x, &format!("{path}.{k}"), bad);
            }
        }
        _ => {}
    }
}

/// The JSON chunk of a GLB file (12-byte header, then chunks of length, type, data).
fn glb_json(bytes: &[u8]) -> serde_json::Value {
    let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    assert_eq!(&bytes[16..20], b"JSON");
    serde_json::from_slice(&bytes[20..20 + len]).unwrap()
}

#[test]
fn every_bundled_scene_writes_only_numbers() {
    let dir = Scratch::new("numbers");
    let scenes = std::path::PathBuf::from(fixture("scenes"));
    let mut names: Vec<_> = std::fs::read_dir(&scenes)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "ron"))
        .collect();
    names.sort();
    assert!(names.len() >= 20, "{} scenes", names.len());
    let mut bad: Vec<String> = Vec::new();
    for scene in &names {
        let stem = scene.file_stem().unwrap().to_string_lossy().into_owned();
        let (csv, json, glb) = (
            dir.join(format!("{stem}.csv")),
            dir.join(format!("{stem}.json")),
            dir.join(format!("{stem}.glb")),
        );
        for (out, extra) in [(&csv, Some(&glb)), (&json, None)] {
            let mut cmd = Command::new(env!("CARGO_BIN_EXE_impulse"));
            cmd.args(["run", scene.to_str().unwrap(), "--until", UNTIL, "--out"])
                .arg(out);
            if let Some(g) = extra {
                cmd.arg("--gltf").arg(g);
            }
            let run = cmd.output().unwrap();
            assert!(
                run.status.success(),
                "{stem}: {}",
                String::from_utf8_lossy(&run.stderr)
            );
            for (line, text) in String::from_utf8_lossy(&run.stdout).lines().enumerate() {
                if text
                    .split(|c: char| c.is_whitespace() || c == ',' || c == '(' || c == ')')
                    .any(non_number)
                {
                    bad.push(format!("{stem} summary line {}: {text}", line + 1));
                }
            }
        }
        let text = std::fs::read_to_string(&csv).unwrap();
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        for (row, line) in lines.enumerate() {
            // Columns other than `body` are numbers (a body name may hold commas, quoted).
            let fields: Vec<&str> = line.split(',').collect();
            let tail = &fields[fields.len() - (header.len() - 2)..];
            for (k, f) in std::iter::once(&fields[0]).chain(tail).enumerate() {
                if !f.parse::<f64>().is_ok_and(f64::is_finite) {
                    bad.push(format!("{stem}.csv row {} field {k}: {f:?}", row + 1));
                }
            }
        }
        let value: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        check_json(&value, &format!("{stem}.json"), &mut bad);
        check_json(
            &glb_json(&std::fs::read(&glb).unwrap()),
            &format!("{stem}.glb"),
            &mut bad,
        );
        bad.truncate(40);
    }
    assert!(bad.is_empty(), "non-numbers:\n{}", bad.join("\n"));
}

/// The checks above see what they look for: a `null` and a huge number in JSON, the words a
/// writer prints for non-numbers, and nothing in plain numbers and names.
#[test]
fn the_checks_see_a_non_number() {
    let mut bad = Vec::new();
    check_json(
        &serde_json::json!({"a": [1.0, null], "b": "NaN", "c": "ball"}),
        "x",
        &mut bad,
    );
    assert_eq!(bad, ["x.a[1]: null", "x.b: \"NaN\""]);
    for t in ["NaN", "inf", "-inf", "Infinity", "null"] {
        assert!(non_number(t), "{t}");
    }
    for t in ["1.5e-3", "0", "ball", "infinite"] {
        assert!(!non_number(t), "{t}");
    }
}
