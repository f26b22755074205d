//! End-to-end tests of `impulse dynamics`: the binary on the bundled double-pendulum URDF,
//! against the closed-form Lagrangian equations of a planar double pendulum.

mod common;

use std::path::{Path, PathBuf};

use common::{Output, impulse};

/// Agreement with the closed forms (evaluated two ways in f64).
const CLOSED_FORM: f64 = 1e-12;

fn fixture() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/urdf/double_pendulum.urdf")
}

fn run(extra: &[&str]) -> Output {
    let path = fixture();
    let mut args = vec!["dynamics", path.to_str().unwrap()];
    args.extend_from_slice(extra);
    impulse(&args)
}

fn list(v: &serde_json::Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

/// The fixture's closed form: rods (m1, l1) and (m2, l2) about parallel horizontal axes,
/// angles from the downward vertical (q2 relative), uniform rods with centres at l/2.
struct Pendulum {
    g: f64,
}

const M1: f64 = 1.3;
const L1: f64 = 0.7;
const M2: f64 = 0.8;
const L2: f64 = 0.5;

impl Pendulum {
    fn mass(&self, q: [f64; 2]) -> [[f64; 2]; 2] {
        let (i1, i2, c1, c2) = (M1 * L1 * L1 / 12.0, M2 * L2 * L2 / 12.0, L1 / 2.0, L2 / 2.0);
        let cos2 = q[1].cos();
        let m11 = i1 + i2 + M1 * c1 * c1 + M2 * (L1 * L1 + c2 * c2 + 2.0 * L1 * c2 * cos2);
        let m12 = i2 + M2 * (c2 * c2 + L1 * c2 * cos2);
        let m22 = i2 + M2 * c2 * c2;
        [[m11, m12], [m12, m22]]
    }

    /// Coriolis, centrifugal and gravity terms h(q, q̇).
    fn bias(&self, q: [f64; 2], v: [f64; 2]) -> [f64; 2] {
        let (c1, c2) = (L1 / 2.0, L2 / 2.0);
        let hh = -M2 * L1 * c2 * q[1].sin();
        let s12 = (q[0] + q[1]).sin();
        [
            hh * (2.0 * v[0] * v[1] + v[1] * v[1])
                + (M1 * c1 + M2 * L1) * self.g * q[0].sin()
                + M2 * c2 * self.g * s12,
            -hh * v[0] * v[0] + M2 * c2 * self.g * s12,
        ]
    }

    fn qdd(&self, q: [f64; 2], v: [f64; 2], tau: [f64; 2]) -> [f64; 2] {
        let m = self.mass(q);
        let h = self.bias(q, v);
        let r = [tau[0] - h[0], tau[1] - h[1]];
        let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
        [
            (m[1][1] * r[0] - m[0][1] * r[1]) / det,
            (m[0][0] * r[1] - m[1][0] * r[0]) / det,
        ]
    }
}

fn close(got: &[f64], want: &[f64]) -> bool {
    let scale = want.iter().fold(1.0f64, |m, x| m.max(x.abs()));
    got.len() == want.len()
        && got
            .iter()
            .zip(want)
            .all(|(a, b)| (a - b).abs() <= CLOSED_FORM * scale)
}

#[test]
fn forward_dynamics_matches_the_closed_form() {
    let p = Pendulum { g: 9.81 };
    let out = run(&["--q", "0.4,-1.1", "--qd", "1.5,-2", "--tau", "0.5,-0.2"]);
    assert!(out.ok, "{}", out.stderr);
    let got = list(&out.json.unwrap()["qdd"]);
    let want = p.qdd([0.4, -1.1], [1.5, -2.0], [0.5, -0.2]);
    assert!(close(&got, &want), "{got:?} {want:?}");
    // Other gravity (magnitude along −z only matters here): 3.7 m/s², and none.
    for (flag, g) in [("0,0,-3.7", 3.7), ("0,0,0", 0.0)] {
        let out = run(&["--q", "-2.5,0.3", "--qd", "0.2,0.1", "--gravity", flag]);
        assert!(out.ok, "{}", out.stderr);
        let got = list(&out.json.unwrap()["qdd"]);
        let want = Pendulum { g }.qdd([-2.5, 0.3], [0.2, 0.1], [0.0, 0.0]);
        assert!(close(&got, &want), "{got:?} {want:?}");
    }
    // Defaults: q = q̇ = τ = 0 hangs at rest.
    let out = run(&[]);
    assert!(out.ok, "{}", out.stderr);
    assert!(close(&list(&out.json.unwrap()["qdd"]), &[0.0, 0.0]));
}

#[test]
fn mass_matrix_and_inverse_dynamics() {
    let p = Pendulum { g: 9.81 };
    let out = run(&["--q", "0.4,-1.1", "--mass-matrix"]);
    assert!(out.ok, "{}", out.stderr);
    let j = out.json.unwrap();
    let m = p.mass([0.4, -1.1]);
    for r in 0..2 {
        assert!(close(&list(&j["M"][r]), &m[r]), "{j}");
    }
    let out = run(&[
        "--inverse",
        "--q",
        "-0.5,0.3",
        "--qd",
        "1,-1",
        "--qdd",
        "1,2",
    ]);
    assert!(out.ok, "{}", out.stderr);
    let got = list(&out.json.unwrap()["tau"]);
    let (m, h) = (p.mass([-0.5, 0.3]), p.bias([-0.5, 0.3], [1.0, -1.0]));
    let want = [
        m[0][0] + 2.0 * m[0][1] + h[0],
        m[1][0] + 2.0 * m[1][1] + h[1],
    ];
    assert!(close(&got, &want), "{got:?} {want:?}");
}

#[test]
fn joint_order_is_listed() {
    let out = run(&["--joints"]);
    assert!(out.ok, "{}", out.stderr);
    assert_eq!(
        out.json.unwrap()["joints"],
        serde_json::json!(["shoulder", "elbow"])
    );
}

#[test]
fn bad_input_fails_naming_the_option() {
    for (args, needle) in [
        (&["--q", "0.4"][..], "--q"),
        (&["--qd", "1,2,3"][..], "--qd"),
        (&["--tau", "1"][..], "--tau"),
        (&["--q", "0.1,zero"][..], "--q"),
        (&["--q", "0.1,inf"][..], "--q"),
        (&["--gravity", "0,-9.81"][..], "--gravity"),
        (&["--inverse", "--qdd", "1"][..], "--qdd"),
        (&["--qdd", "1,2"][..], "--qdd"),
        (&["--inverse"][..], "--qdd"),
    ] {
        let out = run(args);
        assert!(!out.ok, "{args:?} should fail");
        assert!(out.stderr.contains(needle), "{args:?}: {}", out.stderr);
    }
    let out = impulse(&["dynamics", "/nonexistent/robot.urdf"]);
    assert!(!out.ok);
    assert!(out.stderr.contains("robot.urdf"));
}

/// Finite inputs whose products overflow (a velocity of 1e200 in the Coriolis terms, torques
/// at the largest double) give no `null` in the JSON: the command fails, naming the quantity
/// and the joint; the closed form at the same inputs is not finite either. Before this check
/// it printed `{"qdd": [null, null]}` and exited 0.
#[test]
fn overflowing_inputs_fail_naming_the_quantity_and_joint() {
    let p = Pendulum { g: 9.81 };
    assert!(!p.qdd([0.0, 0.0], [1e200, 1e200], [0.0, 0.0])[0].is_finite());
    for (args, quantity) in [
        (&["--qd", "1e200,1e200"][..], "qdd of joint `shoulder`"),
        (&["--tau", "1e308,1e308"][..], "qdd of joint `shoulder`"),
        (
            &["--inverse", "--qd", "1e200,0", "--qdd", "0,0"][..],
            "tau of joint `shoulder`",
        ),
    ] {
        let out = run(args);
        assert!(!out.ok, "{args:?} should fail");
        assert!(out.json.is_none(), "{args:?}: printed {:?}", out.json);
        assert!(out.stderr.contains(quantity), "{args:?}: {}", out.stderr);
    }
}

/// A bad model: the error names the link (the massless root cannot float).
#[test]
fn model_errors_name_the_link() {
    let out = run(&["--floating-base"]);
    assert!(!out.ok);
    assert!(out.stderr.contains("`world`"), "{}", out.stderr);
}
