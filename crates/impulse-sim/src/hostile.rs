//! Malformed and hostile scenes: every one must give an `Error`, never a panic.

use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

use crate::{Scene, SceneDesc, SimError, World};

/// A valid scene every mutation starts from: a floor, a box, a sphere, a compound.
const VALID: &str = r#"Scene(
    name: "base",
    gravity: (0.0, 0.0, -9.81),
    duration: 0.05,
    collision_epsilon: 1e-4,
    output_rate: 100.0,
    default_contact: Contact(friction: 0.4, restitution: 0.5),
    contacts: [MaterialPair(a: "steel", b: "default", friction: 0.2, restitution: 0.9)],
    bodies: [
        Body(name: "floor", shape: Box(half_extents: (1.0, 1.0, 0.1)), position: (0.0, 0.0, -0.1), motion: Fixed),
        Body(name: "box", shape: Box(half_extents: (0.05, 0.04, 0.03)), position: (0.0, 0.0, 0.031),
             velocity: (0.1, 0.0, -0.2), angular_velocity: (1.0, 2.0, 3.0), mass: Density(700.0)),
        Body(name: "ball", shape: Sphere(radius: 0.05), position: (0.3, 0.0, 0.2), mass: Mass(1.0), material: "steel"),
        Body(name: "egg", shape: Ellipsoid(semi_axes: (0.06, 0.03, 0.02)), position: (0.0, 0.3, 0.0201),
             angular_velocity: (0.0, 0.0, -4.0), mass: Mass(0.5), point_masses: [PointMass(mass: 0.03, position: (0.05, 0.01, 0.005))]),
        Body(name: "hammer", shape: Compound(parts: [
                Part(shape: Box(half_extents: (0.1, 0.01, 0.01))),
                Part(shape: Box(half_extents: (0.02, 0.03, 0.03)), position: (0.1, 0.0, 0.0)),
             ]), position: (-0.4, 0.0, 0.3), rotation: AxisAngle(axis: (0.0, 1.0, 0.0), degrees: 10.0)),
    ],
    multibodies: [
        Multibody(name: "arm", base: Fixed, position: (0.7, 0.0, 0.5),
            links: [
                Link(name: "support"),
                Link(name: "rod", shape: Some(Box(half_extents: (0.02, 0.02, 0.1))), position: (0.0, 0.0, -0.1), mass: Some(Mass(0.5))),
                Link(name: "tip", shape: Some(Sphere(radius: 0.03)), position: (0.0, 0.0, -0.03), mass: Some(Density(2000.0))),
            ],
            joints: [
                Joint(name: "shoulder", kind: Revolute, parent: "support", child: "rod", axis: (0.0, 1.0, 0.0), q: 0.5, qd: 1.0,
                      damping: 0.01, limit: Some(Limit(lower: -1.0, upper: 1.0, restitution: 0.5))),
                Joint(name: "slide", kind: Prismatic, parent: "rod", child: "tip", position: (0.0, 0.0, -0.2), spring: Some((50.0, 0.0))),
            ],
            controllers: [Pd(joint: "shoulder", kp: 2.0, kv: 0.1, rate: 100.0)],
        ),
    ],
)"#;

/// Parse, validate, build and run briefly; `Ok` or a typed error, and no panic.
fn attempt(text: &str) -> Result<(), SimError> {
    let desc = SceneDesc::from_ron(text, "hostile")?;
    let mut world = World::from_scene(&Scene::new(desc, "."))?;
    world.step_until(0.02).map(|_| ())
}

#[test]
fn the_base_scene_is_valid_and_runs() {
    attempt(VALID).unwrap();
}

/// An error (of any kind) whose message names every one of `words`.
fn expect_error(text: &str, words: &[&str]) {
    match attempt(text) {
        Err(e) => {
            let m = e.to_string();
            for w in words {
                assert!(m.contains(w), "{m:?} should name {w:?}");
            }
        }
        Ok(()) => panic!("wanted an error naming {words:?}"),
    }
}

/// Malformed multibodies (`docs/hybrid.md`): each is an error naming the multibody and the link,
/// joint or controller at fault.
#[test]
fn malformed_multibodies_name_what_is_wrong() {
    expect_error(
        &VALID.replace("kind: Prismatic", "kind: Twisty"),
        &["Twisty"],
    );
    expect_error(
        &VALID.replace("parent: \"rod\"", "parent: \"nowhere\""),
        &["multibody \"arm\"", "nowhere"],
    );
    // A massless link with a moving child: the model cannot be built.
    expect_error(
        &VALID.replace(
            "Link(name: \"rod\", shape: Some(Box(half_extents: (0.02, 0.02, 0.1))), position: (0.0, 0.0, -0.1), mass: Some(Mass(0.5))),",
            "Link(name: \"rod\"),",
        ),
        &["multibody \"arm\"", "rod"],
    );
    expect_error(
        &VALID.replace("kp: 2.0", "kp: NaN"),
        &["multibody \"arm\"", "controllers[0]", "shoulder"],
    );
    expect_error(
        &VALID.replace("Pd(joint: \"shoulder\"", "Pd(joint: \"elbow\""),
        &["multibody \"arm\"", "controllers[0]", "elbow"],
    );
    expect_error(
        &VALID.replace("q: 0.5, qd: 1.0", "q: NaN, qd: 1.0"),
        &["multibody \"arm\"", "shoulder", "q"],
    );
    expect_error(
        &VALID.replace("q: 0.5, qd: 1.0", "q: 1.5, qd: 1.0"),
        &["multibody \"arm\"", "state"],
    );
    expect_error(
        &VALID.replace("Link(name: \"tip\"", "Link(name: \"rod\""),
        &["multibody \"arm\"", "rod"],
    );
    expect_error(
        &VALID.replace("mass: Some(Mass(0.5))", "mass: Some(Mass(-0.5))"),
        &["multibody \"arm\"", "rod", "mass"],
    );
}

/// A body spinning at 1e30 rad/s made every time-of-impact bound 1e-31 s long: the run
/// crawled for ever (found by the random mutations). Refused at validation.
#[test]
fn absurd_speeds_are_refused() {
    expect_invalid(
        &VALID.replace(
            "angular_velocity: (1.0, 2.0, 3.0)",
            "angular_velocity: (1.0, 2.0, 1e30)",
        ),
        "body \"box\"",
        "angular_velocity",
    );
    expect_invalid(
        &VALID.replace("velocity: (0.1, 0.0, -0.2)", "velocity: (0.1, 0.0, -1e9)"),
        "body \"box\"",
        "velocity",
    );
}

fn expect_invalid(text: &str, what: &str, field: &str) {
    match attempt(text) {
        Err(SimError::Invalid {
            what: w, field: f, ..
        }) => {
            assert!(w.contains(what), "what: {w} (wanted {what})");
            assert!(f.contains(field), "field: {f} (wanted {field})");
        }
        other => panic!("wanted Invalid({what}, {field}), got {other:?}"),
    }
}

#[test]
fn named_errors_for_bad_values() {
    expect_invalid(
        &VALID.replace("mass: Density(700.0)", "mass: Density(-700.0)"),
        "body \"box\"",
        "mass",
    );
    expect_invalid(
        &VALID.replace(
            "mass: Mass(1.0)",
            "mass: Mass(1.0), point_masses: [PointMass(mass: -0.1, position: (0, 0, 0))]",
        ),
        "body \"ball\"",
        "point_masses[0].mass",
    );
    expect_invalid(
        &VALID.replace("mass: Mass(1.0)", "mass: Mass(0.0)"),
        "body \"ball\"",
        "mass",
    );
    expect_invalid(
        &VALID.replace("velocity: (0.1, 0.0, -0.2)", "velocity: (NaN, 0.0, -0.2)"),
        "body \"box\"",
        "velocity",
    );
    expect_invalid(
        &VALID.replace("radius: 0.05", "radius: inf"),
        "body \"ball\"",
        "shape.radius",
    );
    expect_invalid(
        &VALID.replace("collision_epsilon: 1e-4", "collision_epsilon: -1e-4"),
        "scene",
        "collision_epsilon",
    );
    expect_invalid(
        &VALID.replace("collision_epsilon: 1e-4", "collision_epsilon: 1e-300"),
        "scene",
        "collision_epsilon",
    );
    expect_invalid(
        &VALID.replace("restitution: 0.5", "restitution: 1.5"),
        "scene",
        "default_contact.restitution",
    );
    expect_invalid(
        &VALID.replace("friction: 0.2", "friction: -0.2"),
        "contacts[0]",
        "friction",
    );
    expect_invalid(
        &VALID.replace("name: \"ball\"", "name: \"box\""),
        "body \"box\"",
        "name",
    );
    expect_invalid(
        &VALID.replace("output_rate: 100.0", "output_rate: 1e300"),
        "scene",
        "output_rate",
    );
    expect_invalid(
        &VALID.replace("degrees: 10.0", "degrees: NaN"),
        "body \"hammer\"",
        "rotation",
    );
    expect_invalid(
        &VALID.replace(
            "Part(shape: Box(half_extents: (0.1, 0.01, 0.01))),",
            "Part(shape: Compound(parts: [])),",
        ),
        "body \"hammer\"",
        "parts",
    );
}

/// Sizes a typo could blow up are bounded, and the error names the field; so are the solver
/// settings a scene may now set, and an ε_c too large for the thinnest body.
#[test]
fn caps_and_settings_name_their_field() {
    expect_invalid(
        &VALID.replace(
            "shape: Sphere(radius: 0.05)",
            "shape: Prism(sides: 100000, radius: 0.05, half_height: 0.01)",
        ),
        "body \"ball\"",
        "shape.sides",
    );
    expect_invalid(
        &VALID.replace(
            "shape: Sphere(radius: 0.05)",
            "shape: GeodesicSphere(radius: 0.05, level: 12)",
        ),
        "body \"ball\"",
        "shape.level",
    );
    expect_invalid(
        &VALID
            .replace("output_rate: 100.0,", "output_rate: 100.0, duration: 1e6,")
            .replace("    duration: 0.05,\n", ""),
        "scene",
        "output_rate",
    );
    expect_invalid(
        &VALID.replace(
            "default_contact:",
            "accuracy: Accuracy(max_restitution: 0.5), default_contact:",
        ),
        "scene",
        "accuracy.max_restitution",
    );
    expect_invalid(
        &VALID.replace("collision_epsilon: 1e-4", "collision_epsilon: 0.01"),
        "scene",
        "collision_epsilon",
    );
    // The settings reach the world: without the reversing impulse no microcollision uses it.
    let text = VALID.replace(
        "default_contact:",
        "accuracy: Accuracy(reversing: false, max_restitution: 2.0), default_contact:",
    );
    let desc = SceneDesc::from_ron(&text, "hostile").unwrap();
    let mut world = World::from_scene(&Scene::new(desc, ".")).unwrap();
    world.step_until(0.5).unwrap();
    let c = world.counters();
    assert!(c.microcollisions > 0 && c.reversing == 0, "{c:?}");
}

#[test]
fn empty_scene_and_missing_fields_are_errors() {
    let empty = "Scene(duration: 1.0, collision_epsilon: 1e-3, bodies: [])";
    expect_invalid(empty, "scene", "bodies");
    // `duration` is optional (a caller gives the end time); `bodies` is not.
    attempt(&VALID.replace("duration: 0.05,", "")).unwrap();
    let start = VALID.find("    bodies: [").unwrap();
    let text = format!("{})", &VALID[..start]);
    match attempt(&text) {
        Err(SimError::Parse { message, .. }) => assert!(message.contains("bodies"), "{message}"),
        other => panic!("{other:?}"),
    }
    // Unknown field.
    let text = VALID.replace("duration: 0.05,", "duration: 0.05, durration: 1.0,");
    assert!(matches!(attempt(&text), Err(SimError::Parse { .. })));
    assert!(matches!(attempt(""), Err(SimError::Parse { .. })));
    assert!(matches!(attempt("Scene("), Err(SimError::Parse { .. })));
}

#[test]
fn overlapping_and_degenerate_bodies_are_errors() {
    // The ball moved into the box.
    let text = VALID.replace("position: (0.3, 0.0, 0.2)", "position: (0.0, 0.0, 0.05)");
    match attempt(&text) {
        Err(SimError::Overlap { a, b, .. }) => {
            assert_eq!((a.as_str(), b.as_str()), ("box", "ball"));
        }
        other => panic!("{other:?}"),
    }
    // Coplanar hull points: no volume.
    let text = VALID.replace(
        "shape: Sphere(radius: 0.05)",
        "shape: Hull(points: [(0, 0, 0), (1, 0, 0), (0, 1, 0), (1, 1, 0)])",
    );
    match attempt(&text) {
        Err(SimError::Geometry { body, .. }) => assert_eq!(body, "ball"),
        other => panic!("{other:?}"),
    }
    // A missing OBJ file.
    let text = VALID.replace(
        "shape: Sphere(radius: 0.05)",
        "shape: Obj(path: \"no/such/file.obj\")",
    );
    match attempt(&text) {
        Err(SimError::Geometry { body, message }) => {
            assert_eq!(body, "ball");
            assert!(message.contains("file.obj"), "{message}");
        }
        other => panic!("{other:?}"),
    }
    // Nothing dynamic.
    let only_floor = "Scene(duration: 1.0, collision_epsilon: 1e-3, bodies: [
        Body(name: \"floor\", shape: Box(half_extents: (1, 1, 1)), motion: Fixed)])";
    expect_invalid(only_floor, "scene", "bodies");
}

/// Random mutations of the valid scene: numbers replaced by hostile values, characters
/// deleted, lines dropped. Every outcome is `Ok` or an error; a panic fails the test.
#[test]
fn random_mutations_never_panic() {
    const MUTATIONS: usize = 600;
    const HOSTILE: [&str; 12] = [
        "NaN", "inf", "-inf", "-1.0", "0.0", "1e308", "-1e308", "1e-320", "5e-324", "1e30", "-0.0",
        "3",
    ];
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(2026);
    let numbers: Vec<(usize, usize)> = {
        let bytes = VALID.as_bytes();
        let mut spans = Vec::new();
        let mut k = 0;
        while k < bytes.len() {
            let starts = bytes[k].is_ascii_digit()
                && (k == 0 || !(bytes[k - 1].is_ascii_alphanumeric() || bytes[k - 1] == b'_'));
            if starts {
                let s = k;
                while k < bytes.len()
                    && (bytes[k].is_ascii_digit() || matches!(bytes[k], b'.' | b'e' | b'-'))
                {
                    k += 1;
                }
                spans.push((s, k));
            } else {
                k += 1;
            }
        }
        spans
    };
    let (mut ok, mut errors) = (0, 0);
    for _ in 0..MUTATIONS {
        let mut text = VALID.to_string();
        for _ in 0..rng.random_range(1..4) {
            match rng.random_range(0..3) {
                0 => {
                    let (s, e) = numbers[rng.random_range(0..numbers.len())];
                    if e <= text.len() && text.is_char_boundary(s) && text.is_char_boundary(e) {
                        text.replace_range(s..e, HOSTILE[rng.random_range(0..HOSTILE.len())]);
                    }
                }
                1 => {
                    let k = rng.random_range(0..text.len());
                    if text.is_char_boundary(k) && text.is_char_boundary(k + 1) {
                        text.remove(k);
                    }
                }
                _ => {
                    let lines: Vec<&str> = text.lines().collect();
                    let drop = rng.random_range(0..lines.len());
                    text = lines
                        .iter()
                        .enumerate()
                        .filter(|(i, _)| *i != drop)
                        .map(|(_, l)| *l)
                        .collect::<Vec<_>>()
                        .join("\n");
                }
            }
        }
        match attempt(&text) {
            Ok(()) => ok += 1,
            Err(_) => errors += 1,
        }
    }
    eprintln!("{MUTATIONS} mutated scenes: {ok} ran, {errors} refused with an error");
    // Both outcomes must occur, or the mutations are not exercising anything.
    assert!(ok > 0 && errors > 0, "ok {ok}, errors {errors}");
}

/// The URDF every URDF mutation starts from: the bundled two-link arm (every collision kind,
/// a fixed joint, `<dynamics>`), read through a scene with overrides and a controller.
const VALID_URDF: &str = include_str!("../../../fixtures/urdf/two_link_arm.urdf");

/// The scene around it (`urdf/arm.urdf` relative to the scene's directory).
const URDF_SCENE: &str = r#"Scene(
    duration: 0.05,
    bodies: [
        Body(name: "floor", shape: Box(half_extents: (1.5, 1.5, 0.05)), position: (0.0, 0.0, -0.05), motion: Fixed),
        Body(name: "block", shape: Box(half_extents: (0.04, 0.04, 0.04)), position: (0.45, 0.0, 0.04), mass: Density(600.0)),
    ],
    multibodies: [
        Multibody(name: "arm", position: (0.0, 0.0, 0.01),
            urdf: Urdf(path: "urdf/arm.urdf",
                links: [LinkOverride(name: "hand", material: "steel")],
                joints: [JointOverride(name: "elbow", q: 0.3, qd: -1.0, limit: Limit(lower: -2.0, upper: 2.0))]),
            controllers: [Pd(joint: "shoulder", kp: 1.0, kv: 0.05, rate: 100.0)]),
    ],
)"#;

/// Random mutations of the URDF file of a scene's multibody: numbers replaced by hostile
/// values, characters deleted, lines dropped, joint types, shapes, mesh formats and link
/// names swapped (loops, several roots, unsupported joints and formats). Every outcome is
/// `Ok` or an error; a panic fails the test.
#[test]
fn random_urdf_mutations_never_panic() {
    const MUTATIONS: usize = 300;
    const HOSTILE: [&str; 12] = [
        "NaN", "inf", "-inf", "-1.0", "0.0", "1e308", "-1e308", "1e-320", "5e-324", "1e30", "-0.0",
        "3",
    ];
    const SWAPS: [(&str, &str); 10] = [
        ("\"revolute\"", "\"planar\""),
        ("\"revolute\"", "\"floating\""),
        ("\"revolute\"", "\"prismatic\""),
        ("\"fixed\"", "\"continuous\""),
        ("<box", "<capsule radius=\"0.1\" length=\"0.2\"/><box"),
        ("cube20.obj", "cube20.dae"),
        ("cube20.obj", "nowhere.obj"),
        ("child link=\"hand\"", "child link=\"upper\""),
        ("parent link=\"pedestal\"", "parent link=\"hand\""),
        ("child link=\"forearm\"", "child link=\"pedestal\""),
    ];
    let dir = std::env::temp_dir().join(format!("impulse-hostile-urdf-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("urdf")).unwrap();
    std::fs::create_dir_all(dir.join("meshes")).unwrap();
    std::fs::write(
        dir.join("meshes/cube20.obj"),
        include_str!("../../../fixtures/meshes/cube20.obj"),
    )
    .unwrap();
    let run = |urdf: &str| -> Result<(), SimError> {
        std::fs::write(dir.join("urdf/arm.urdf"), urdf).map_err(|e| SimError::Io {
            path: dir.clone(),
            message: e.to_string(),
        })?;
        let desc = SceneDesc::from_ron(URDF_SCENE, "hostile-urdf")?;
        let mut world = World::from_scene(&Scene::new(desc, &dir))?;
        world.step_until(0.02).map(|_| ())
    };
    run(VALID_URDF).unwrap();
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(1313);
    let numbers: Vec<(usize, usize)> = {
        let bytes = VALID_URDF.as_bytes();
        let mut spans = Vec::new();
        let mut k = 0;
        while k < bytes.len() {
            if bytes[k].is_ascii_digit() && k > 0 && matches!(bytes[k - 1], b'"' | b' ') {
                let s = k;
                while k < bytes.len()
                    && (bytes[k].is_ascii_digit() || matches!(bytes[k], b'.' | b'e' | b'-'))
                {
                    k += 1;
                }
                spans.push((s, k));
            } else {
                k += 1;
            }
        }
        spans
    };
    let (mut ok, mut errors) = (0, 0);
    for _ in 0..MUTATIONS {
        let mut text = VALID_URDF.to_string();
        for _ in 0..rng.random_range(1..4) {
            match rng.random_range(0..4) {
                0 => {
                    let (s, e) = numbers[rng.random_range(0..numbers.len())];
                    if e <= text.len() && text.is_char_boundary(s) && text.is_char_boundary(e) {
                        text.replace_range(s..e, HOSTILE[rng.random_range(0..HOSTILE.len())]);
                    }
                }
                1 => {
                    let k = rng.random_range(0..text.len());
                    if text.is_char_boundary(k) && text.is_char_boundary(k + 1) {
                        text.remove(k);
                    }
                }
                2 => {
                    let (from, to) = SWAPS[rng.random_range(0..SWAPS.len())];
                    text = text.replacen(from, to, 1);
                }
                _ => {
                    let lines: Vec<&str> = text.lines().collect();
                    let drop = rng.random_range(0..lines.len());
                    text = lines
                        .iter()
                        .enumerate()
                        .filter(|(i, _)| *i != drop)
                        .map(|(_, l)| *l)
                        .collect::<Vec<_>>()
                        .join("\n");
                }
            }
        }
        match run(&text) {
            Ok(()) => ok += 1,
            Err(_) => errors += 1,
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    eprintln!("{MUTATIONS} mutated URDF files: {ok} ran, {errors} refused with an error");
    assert!(ok > 0 && errors > 0, "ok {ok}, errors {errors}");
}
