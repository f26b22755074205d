use glam::DVec3;

use super::*;
use crate::scene::SceneDesc;

/// A wheel on a fixed axle (no gravity torque about it) with a PD velocity loop commanding
/// `target` rad/s at `rate` Hz with gain `kv`.
fn wheel(kv: f64, rate: f64, target: f64) -> MultibodyDesc {
    let text = format!(
        r#"Multibody(name: "wheel", base: Fixed, links: [
            Link(name: "axle"),
            Link(name: "wheel", shape: Some(Prism(sides: 24, radius: 0.06, half_height: 0.02)),
                 rotation: AxisAngle(axis: (1.0, 0.0, 0.0), degrees: 90.0), mass: Some(Mass(0.3))),
        ], joints: [
            Joint(name: "spin", kind: Revolute, parent: "axle", child: "wheel", axis: (0.0, 1.0, 0.0)),
        ], controllers: [
            Pd(joint: "spin", kp: 0.0, kv: {kv}, target_rate: {target}, rate: {rate}),
        ])"#
    );
    ron::from_str(&text).unwrap()
}

/// The zero-order-held velocity loop is the map v ← v − r (v − v*) with r = k_v T / M: it
/// converges for r < 2 and diverges beyond. Checked against the simulated wheel (an
/// independent run of the multibody), and the warning fires exactly where the map says.
#[test]
fn a_wheel_velocity_loop_reaches_its_speed_or_warns_that_it_cannot() {
    let g = DVec3::new(0.0, 0.0, -9.81);
    let (sim, _) = wheel(1.0, 100.0, 10.0).build(g, Path::new(".")).unwrap();
    let m = {
        let model = sim.model();
        let mut mm = impulse_multibody::Mat::<f64>::zeros(1, 1);
        let mut ws = impulse_multibody::Workspace::new(model);
        impulse_multibody::mass_matrix(model, &mut ws, sim.q(), &mut mm).unwrap();
        mm[(0, 0)]
    };
    // The wheel's inertia about its axle: a 24-gon prism of circumradius 6 cm, 0.3 kg, close
    // to a disc's ½ m r² (within the polygon's area deficit).
    assert!(
        (m / (0.5 * 0.3 * 0.06 * 0.06) - 1.0).abs() < 0.03,
        "M = {m}"
    );
    let rate = 100.0;
    for r in [0.5, 1.5, 2.5] {
        let kv = r * m * rate;
        let desc = wheel(kv, rate, 10.0);
        let (mut sim, _) = desc.build(g, Path::new(".")).unwrap();
        sim.run_until(0.5).unwrap();
        let err = (sim.v()[0] - 10.0).abs();
        // 50 updates: |1 − r|^50 of the initial error 10 (the hold makes it exact per update).
        let predicted = 10.0 * (1.0 - r).abs().powi(50);
        if r < 2.0 {
            assert!(err < 1e-6 + 2.0 * predicted, "r = {r}: error {err}");
        } else {
            assert!(err > 1e3, "r = {r}: should diverge, error {err}");
        }
        let warned = !desc.warnings(g, Path::new(".")).is_empty();
        assert_eq!(warned, r >= 2.0 * CONTROL_STABILITY_WARN, "r = {r}");
    }
    // Scene warnings include them.
    let mut scene = SceneDesc::new();
    scene.multibodies.push(wheel(2.5 * m * rate, rate, 1.0));
    assert!(
        scene
            .warnings()
            .iter()
            .any(|w| w.contains("\"spin\"") && w.contains("unstable"))
    );
}

/// A contact pair may name a material only a multibody's link uses (the rover's rubber
/// wheels on the floor); one nobody uses is still refused, naming it.
#[test]
fn contact_pairs_may_name_the_materials_of_links() {
    let scene = |pair: &str| {
        format!(
            r#"Scene(
                contacts: [MaterialPair(a: "{pair}", b: "default", friction: 1.0, restitution: 0.1)],
                bodies: [Body(name: "floor", motion: Fixed, shape: Box(half_extents: (1, 1, 0.1)),
                              position: (0, 0, -0.1))],
                multibodies: [Multibody(name: "wheel", base: Fixed, position: (0, 0, 0.5), links: [
                    Link(name: "axle"),
                    Link(name: "wheel", shape: Some(Sphere(radius: 0.06)), mass: Some(Mass(0.3)),
                         material: "rubber"),
                ], joints: [
                    Joint(name: "spin", kind: Revolute, parent: "axle", child: "wheel",
                          axis: (0.0, 1.0, 0.0)),
                ])],
            )"#
        )
    };
    SceneDesc::from_ron(&scene("rubber"), "test")
        .and_then(|d| d.validate())
        .expect("rubber is a link's material");
    let err = SceneDesc::from_ron(&scene("felt"), "test")
        .and_then(|d| d.validate())
        .expect_err("nobody uses felt");
    assert!(err.to_string().contains("\"felt\""), "{err}");
}

/// A scene read from a file warns about a URDF multibody's controller too: its relative URDF
/// path resolves against the scene's directory (`Scene::warnings`). The bundled URDF arm with
/// its elbow loop's k_v raised a thousandfold.
#[test]
fn a_urdf_multibody_in_a_scene_file_is_checked_for_controller_stability() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/scenes/urdf-arm.ron");
    let mut scene = crate::Scene::read(&path).expect("the bundled URDF arm");
    let mb = &mut scene.desc.multibodies[0];
    assert!(mb.urdf.is_some(), "the arm comes from a URDF file");
    assert!(scene.warnings().is_empty(), "{:?}", scene.warnings());
    for c in &mut scene.desc.multibodies[0].controllers {
        let (ControllerDesc::Pd { kv, .. } | ControllerDesc::Pid { kv, .. }) = c;
        *kv *= 1000.0;
    }
    let warnings = scene.warnings();
    assert!(
        warnings.iter().any(|w| w.contains("unstable")),
        "{warnings:?}"
    );
}

/// A scene with one three-link chain (`a`, `b`, `c`, the last two free) whose multibody
/// fields end with `extra`.
fn chain_scene(extra: &str) -> String {
    format!(
        r#"Scene(
            bodies: [Body(name: "floor", motion: Fixed, shape: Box(half_extents: (1, 1, 0.1)),
                          position: (0, 0, -0.1))],
            multibodies: [
                Multibody(name: "other", position: (0.5, 0, 1), links: [Link(name: "x")]),
                Multibody(name: "chain", base: Fixed, position: (0, 0, 1), links: [
                    Link(name: "a", shape: Some(Box(half_extents: (0.1, 0.02, 0.02))),
                         position: (0.1, 0, 0)),
                    Link(name: "b", shape: Some(Box(half_extents: (0.1, 0.02, 0.02))),
                         position: (0.1, 0, 0)),
                    Link(name: "c", shape: Some(Box(half_extents: (0.1, 0.02, 0.02))),
                         position: (0.1, 0, 0)),
                ], joints: [
                    Joint(name: "jb", kind: Revolute, parent: "a", child: "b",
                          position: (0.2, 0, 0), axis: (0, 1, 0)),
                    Joint(name: "jc", kind: Revolute, parent: "b", child: "c",
                          position: (0.2, 0, 0), axis: (0, 1, 0)),
                ]{extra}),
            ],
        )"#
    )
}

/// (d) `self_collision` in a scene file: off when left out, on when written `true`, and it
/// reaches the world (the multibody's option); a malformed value or a misspelt field is a
/// parse error naming the multibody (and not a neighbouring one).
#[test]
fn self_collision_parses_defaults_to_off_and_names_the_multibody_when_malformed() {
    let read = |extra: &str| SceneDesc::from_ron(&chain_scene(extra), "test");
    let world = |desc: SceneDesc| {
        let w = crate::World::from_scene(&crate::Scene::new(desc, ".")).unwrap();
        let h = w.multibody_handle("chain").unwrap();
        w.self_collision(h).unwrap()
    };
    let off = read("").unwrap();
    assert!(!off.multibodies[1].self_collision);
    assert!(!world(off));
    let on = read(", self_collision: true").unwrap();
    assert!(on.multibodies[1].self_collision);
    assert!(world(on));
    assert!(!world(read(", self_collision: false").unwrap()));
    for bad in [
        ", self_collision: 1",
        ", self_collision: \"yes\"",
        ", self_colision: true",
    ] {
        let err = read(bad).expect_err(bad).to_string();
        assert!(
            err.contains("multibody \"chain\"") && !err.contains("\"other\""),
            "{bad}: {err}"
        );
        assert!(
            err.contains("field `self_collision`") != bad.contains("colision"),
            "{bad}: {err}"
        );
    }
}
