//! End-to-end tests of `impulse run --gltf`: the .glb read back by an independent reader (the
//! `gltf` crate, which validates the document) against the trajectory `--out` records.

mod common;

use common::Scratch;
use common::impulse_text as impulse;
use std::path::{Path, PathBuf};

/// How far a keyframe may be from the recorded state (glTF stores f32, whose
/// rounding of these scenes' coordinates is below 1e-7).
const KEYFRAME_TOL: f64 = 1e-6;

fn scenes() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/scenes")
}

/// The recorded trajectory: body names, frame times and each frame's states (16 numbers per
/// body: x y z qx qy qz qw …), from `--out traj.json`.
struct Recorded {
    names: Vec<String>,
    times: Vec<f64>,
    states: Vec<Vec<Vec<f64>>>,
}

fn recorded(json: &Path) -> Recorded {
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap();
    let names = v["bodies"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n.as_str().unwrap().to_owned())
        .collect();
    let frames = v["frames"].as_array().unwrap();
    let times = frames.iter().map(|f| f["t"].as_f64().unwrap()).collect();
    let states = frames
        .iter()
        .map(|f| {
            f["states"]
                .as_array()
                .unwrap()
                .iter()
                .map(|s| {
                    s.as_array()
                        .unwrap()
                        .iter()
                        .map(|x| x.as_f64().unwrap())
                        .collect()
                })
                .collect()
        })
        .collect();
    Recorded {
        names,
        times,
        states,
    }
}

/// The largest difference of two equally long lists.
fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// Runs `scene` with `--out` JSON and `--gltf`, reads the .glb back and checks: one node per
/// body (named after it, with a mesh) under the root `world` node, and nothing else; one
/// translation and one rotation channel per body, LINEAR, with one keyframe per recorded frame
/// at the frame's time; the first and last keyframes equal the recorded states within
/// [`KEYFRAME_TOL`] (a rotation, or its negative: the same rotation). Returns the body names.
fn glb_matches_the_recording(scene: &str, extra: &[&str]) -> Vec<String> {
    let dir = Scratch::new(&format!("gltf-{scene}"));
    let (json, glb) = (dir.join("traj.json"), dir.join("run.glb"));
    let scene_path = scenes().join(scene);
    let mut args = vec![
        "run",
        scene_path.to_str().unwrap(),
        "--out",
        json.to_str().unwrap(),
        "--gltf",
        glb.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let (ok, _, stderr) = impulse(&args);
    assert!(ok, "{stderr}");
    let rec = recorded(&json);
    let bytes = std::fs::read(&glb).unwrap();
    let doc = gltf::Gltf::from_slice(&bytes).expect("a valid glTF binary");
    let blob = doc.blob.as_deref();
    let data = |_: gltf::Buffer<'_>| blob;

    let n = rec.names.len();
    assert_eq!(
        doc.nodes().len(),
        n + 1,
        "{scene}: one node per body and the root"
    );
    let scene_nodes: Vec<_> = doc.default_scene().unwrap().nodes().collect();
    assert_eq!(scene_nodes.len(), 1);
    assert_eq!(scene_nodes[0].name(), Some("world"));
    let bodies: Vec<_> = scene_nodes[0].children().collect();
    let names: Vec<_> = bodies
        .iter()
        .map(|b| b.name().unwrap().to_owned())
        .collect();
    assert_eq!(
        names, rec.names,
        "{scene}: body nodes in the recorded order"
    );
    assert!(
        bodies.iter().all(|b| b.mesh().is_some()),
        "{scene}: a mesh per body"
    );

    let animations: Vec<_> = doc.animations().collect();
    assert_eq!(animations.len(), 1);
    let channels: Vec<_> = animations[0].channels().collect();
    assert_eq!(
        channels.len(),
        2 * n,
        "{scene}: translation and rotation per body"
    );
    let (first, last) = (&rec.states[0], rec.states.last().unwrap());
    for channel in channels {
        let node = channel.target().node();
        let b = rec
            .names
            .iter()
            .position(|x| Some(x.as_str()) == node.name())
            .unwrap();
        let name = &rec.names[b];
        assert_eq!(
            channel.sampler().interpolation(),
            gltf::animation::Interpolation::Linear
        );
        let reader = channel.reader(data);
        let times: Vec<f64> = reader.read_inputs().unwrap().map(f64::from).collect();
        assert_eq!(
            times.len(),
            rec.times.len(),
            "{scene}: `{name}`'s keyframes"
        );
        let dt = max_diff(&times, &rec.times);
        assert!(
            dt <= KEYFRAME_TOL,
            "{scene}: keyframe times off by {dt:.2e}"
        );
        let keys: Vec<Vec<f64>> = match reader.read_outputs().unwrap() {
            gltf::animation::util::ReadOutputs::Translations(t) => t
                .map(|k| k.iter().map(|&x| f64::from(x)).collect())
                .collect(),
            gltf::animation::util::ReadOutputs::Rotations(r) => r
                .into_f32()
                .map(|k| k.iter().map(|&x| f64::from(x)).collect())
                .collect(),
            _ => panic!("{scene}: only translation and rotation channels"),
        };
        assert_eq!(keys.len(), times.len(), "{scene}: `{name}`'s outputs");
        let columns = if keys[0].len() == 3 { 0..3 } else { 3..7 };
        for (key, state, which) in [
            (&keys[0], &first[b], "first"),
            (keys.last().unwrap(), &last[b], "last"),
        ] {
            let want = &state[columns.clone()];
            let mut d = max_diff(key, want);
            if columns.start == 3 {
                let negated: Vec<f64> = want.iter().map(|x| -x).collect();
                d = d.min(max_diff(key, &negated));
            }
            assert!(
                d <= KEYFRAME_TOL,
                "{scene}: `{name}`'s {which} keyframe {key:?} is {d:.2e} from the recorded \
                 {want:?}"
            );
        }
    }
    rec.names
}

/// The pool break (balls and boxes, 2001 frames) reads back with a node and keyframes per
/// body and frame, first and last keyframes equal to the recorded states.
#[test]
fn pool_break_glb_reads_back_as_recorded() {
    assert_eq!(glb_matches_the_recording("pool-break.ron", &[]).len(), 21);
}

/// The same for a scene with a multibody: its links are bodies (`<multibody>/<link>`).
#[test]
fn see_saw_glb_has_the_multibody_links() {
    let names = glb_matches_the_recording("see-saw.ron", &["--until", "0.3"]);
    assert!(
        names.iter().any(|n| n.contains('/')),
        "no link among {names:?}"
    );
}

/// A .glb that cannot be written (its directory is missing) is an `error:` line naming the
/// path, not a panic; so is a file name that is not .glb; both before the run.
#[test]
fn gltf_errors_name_the_path() {
    let dir = Scratch::new("gltf-errors");
    let scene = scenes().join("two-ball-collision.ron");
    let missing = dir.join("no-such-dir").join("run.glb");
    let (ok, _, stderr) = impulse(&[
        "run",
        scene.to_str().unwrap(),
        "--until",
        "0.1",
        "--gltf",
        missing.to_str().unwrap(),
    ]);
    assert!(!ok);
    // Its directory is missing: refused before the run.
    assert!(
        stderr.starts_with(&format!("error: --gltf {}", missing.display()))
            && stderr.contains("does not exist"),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
    let wrong = dir.join("run.gltf");
    let (ok, stdout, stderr) = impulse(&[
        "run",
        scene.to_str().unwrap(),
        "--gltf",
        wrong.to_str().unwrap(),
    ]);
    assert!(!ok && stdout.is_empty());
    assert!(
        stderr.starts_with(&format!(
            "error: --gltf {}: the file name must end in .glb",
            wrong.display()
        )),
        "{stderr}"
    );
}
