//! URDF multibodies in scenes, each test against an independent reference: the equivalent
//! inline description, hand-written shapes, closed-form mass properties.

use std::path::{Path, PathBuf};

use glam::{DQuat, DVec3};

use super::*;
use crate::scene::{MultibodyDesc, Scene, SceneDesc};
use crate::world::World;

/// Largest difference of joint angle (rad) or rate (rad/s) between a URDF multibody and its
/// inline twin over a run with floor impacts: the two are built from the same numbers with
/// rotations composed in different orders (URDF rpy versus a scene quaternion), so they differ
/// by rounding only, amplified a little by each impact. Default `1e-9`.
const TWIN_TOL: f64 = 1e-9;

/// Rounding allowed on mass properties computed two ways. Default `1e-12` (relative).
const MASS_TOL: f64 = 1e-12;

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/scenes")
}

fn multibody(text: &str) -> MultibodyDesc {
    ron::Options::default()
        .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
        .from_str(text)
        .unwrap()
}

/// The pendulum of `fixtures/urdf/pendulum_collision.urdf`, placed at `(0.1, 0, 1)` turned 30°
/// about z, released at 1.3 rad, with `extra` inside `Urdf(...)`.
fn urdf_pendulum(extra: &str) -> MultibodyDesc {
    multibody(&format!(
        r#"Multibody(name: "p", urdf: Urdf(path: "../urdf/pendulum_collision.urdf",
               joints: [JointOverride(name: "hinge", q: 1.3)], {extra}),
               position: (0.1, 0.0, 1.0), rotation: AxisAngle(axis: (0.0, 0.0, 1.0), degrees: 30.0))"#
    ))
}

/// The same pendulum written inline from the URDF's numbers (by hand, not by the reader).
fn inline_pendulum() -> MultibodyDesc {
    let yaw = DQuat::from_rotation_z(0.3);
    let roll = DQuat::from_rotation_x(std::f64::consts::FRAC_PI_2);
    // URDF rpy (r, p, y) is the fixed-axis rotation Rz(y)·Ry(p)·Rx(r).
    let tilt =
        DQuat::from_rotation_z(0.1) * DQuat::from_rotation_y(0.2) * DQuat::from_rotation_x(0.3);
    let h = 0.002 * 10.0;
    let cube: Vec<String> = (0..8)
        .map(|k| {
            let s = |b: usize| if k >> b & 1 == 1 { h } else { -h };
            format!("({}, {}, {})", s(0), s(1), s(2))
        })
        .collect();
    multibody(&format!(
        r#"Multibody(name: "p", position: (0.1, 0.0, 1.0),
            rotation: AxisAngle(axis: (0.0, 0.0, 1.0), degrees: 30.0),
            links: [
              Link(name: "mount", shape: Box(half_extents: (0.1, 0.1, 0.02)), position: (0.0, 0.0, 0.02)),
              Link(name: "rod", shape: Compound(parts: [
                  Part(shape: Box(half_extents: (0.02, 0.02, 0.25)), position: (0.0, 0.0, -0.25)),
                  Part(shape: Prism(sides: 32, radius: 0.05, half_height: 0.02), position: (0.0, 0.0, -0.5),
                       rotation: Quaternion({}, {}, {}, {})),
                  Part(shape: Hull(points: [{}]), position: (0.0, 0.0, -0.55),
                       rotation: Quaternion({}, {}, {}, {})),
                ]),
                inertia: Inertia(mass: 1.0, com: (0.0, 0.0, -0.25),
                  moments: (0.020966666666666668, 0.020966666666666668, 0.00026666666666666668))),
            ],
            joints: [Joint(name: "hinge", kind: Revolute, parent: "mount", child: "rod",
                           position: (0.0, 0.0, -0.05), rotation: Quaternion({}, {}, {}, {}),
                           axis: (0.0, 1.0, 0.0), damping: 0.01, q: 1.3)])"#,
        roll.x,
        roll.y,
        roll.z,
        roll.w,
        cube.join(", "),
        tilt.x,
        tilt.y,
        tilt.z,
        tilt.w,
        yaw.x,
        yaw.y,
        yaw.z,
        yaw.w,
    ))
}

fn scene(m: MultibodyDesc) -> Scene {
    let floor: crate::scene::BodyDesc = ron::from_str(
        r#"Body(name: "floor", shape: Box(half_extents: (2.0, 2.0, 0.1)), position: (0.0, 0.0, 0.35),
                motion: Fixed)"#,
    )
    .unwrap();
    let mut desc = SceneDesc::new();
    desc.bodies.push(floor);
    desc.multibodies.push(m);
    Scene::new(desc, fixtures())
}

/// A URDF pendulum and the inline pendulum written from the same numbers swing onto a floor
/// (the bob's cube strikes it) and follow the same trajectory to rounding ([`TWIN_TOL`]);
/// the fixed root's collision box sits at the multibody's placement.
#[test]
fn urdf_pendulum_matches_its_inline_twin_through_floor_impacts() {
    let mut a = World::from_scene(&scene(urdf_pendulum(""))).unwrap();
    let mut b = World::from_scene(&scene(inline_pendulum())).unwrap();
    let (ha, hb) = (
        a.multibody_handle("p").unwrap(),
        b.multibody_handle("p").unwrap(),
    );
    let mut worst: f64 = 0.0;
    let mut lowest_q = f64::INFINITY;
    while a.time() < 1.5 {
        let t = a.time() + 0.01;
        a.step_until(t).unwrap();
        b.step_until(t).unwrap();
        let (sa, sb) = (a.multibody(ha).unwrap(), b.multibody(hb).unwrap());
        worst = worst
            .max((sa.q()[0] - sb.q()[0]).abs())
            .max((sa.v()[0] - sb.v()[0]).abs());
        lowest_q = lowest_q.min(sa.q()[0].abs());
    }
    let (ca, cb) = (a.counters(), b.counters());
    assert!(ca.link_contacts > 0, "no impact: {ca:?}");
    // The floor (top at z = 0.45) stops the bob (0.57 m below the pivot at z = 0.95) before
    // the rod hangs straight down: the swing never gets near q = 0.
    assert!(
        lowest_q > 0.3,
        "the floor did not stop the swing: q = {lowest_q}"
    );
    eprintln!(
        "URDF vs inline: worst |Δq|, |Δq̇| {worst:e}; {} link contacts",
        ca.link_contacts
    );
    assert!(worst < TWIN_TOL, "URDF and inline differ by {worst:e}");
    assert_eq!(ca.link_contacts, cb.link_contacts);
    // The fixed root's collision box (half extents 0.1, 0.1, 0.02, 2 cm above the link
    // origin) sits at the placement: centred at (0.1, 0, 1.02), turned 30° about z, so its
    // bounding box reaches 0.1·(cos 30° + sin 30°) either side in x and y.
    for w in [&a, &b] {
        let h = w
            .link_body(w.multibody_handle("p").unwrap(), "mount")
            .unwrap();
        let body = w.body(h).unwrap();
        let bb = body.shape.aabb(&body.pose);
        let reach = 0.1 * (30f64.to_radians().cos() + 30f64.to_radians().sin());
        let want_min = DVec3::new(0.1 - reach, -reach, 1.0);
        let want_max = DVec3::new(0.1 + reach, reach, 1.04);
        assert!(
            (bb.min - want_min).length() < 1e-12 && (bb.max - want_max).length() < 1e-12,
            "mount box {bb:?}, want {want_min} .. {want_max}"
        );
    }
}

/// The URDF's collision elements become the parts written by hand: box half sizes, the
/// cylinder as a 32-gon prism at its origin, the OBJ cube scaled.
#[test]
fn collision_elements_map_to_shapes() {
    let base = fixtures();
    let desc = urdf_pendulum("").urdf.unwrap();
    let robot = desc.read(&base).unwrap();
    let rod = robot.links.iter().find(|l| l.name == "rod").unwrap();
    let Some(ShapeDesc::Compound { parts }) = collision_shape(rod, &desc, &base).unwrap() else {
        panic!("not a compound")
    };
    assert_eq!(parts.len(), 3);
    assert_eq!(
        parts[0].shape,
        ShapeDesc::Box {
            half_extents: [0.02, 0.02, 0.25]
        }
    );
    assert_eq!(parts[0].position, [0.0, 0.0, -0.25]);
    assert_eq!(
        parts[1].shape,
        ShapeDesc::Prism {
            sides: URDF_CYLINDER_SIDES,
            radius: 0.05,
            half_height: 0.02
        }
    );
    let RotationDesc::Quaternion(x, y, z, w) = parts[1].rotation else {
        panic!("{:?}", parts[1].rotation)
    };
    let roll = DQuat::from_rotation_x(std::f64::consts::FRAC_PI_2);
    assert!(DQuat::from_xyzw(x, y, z, w).angle_between(roll) < 1e-15);
    let RotationDesc::Quaternion(x, y, z, w) = parts[2].rotation else {
        panic!("{:?}", parts[2].rotation)
    };
    let tilt =
        DQuat::from_rotation_z(0.1) * DQuat::from_rotation_y(0.2) * DQuat::from_rotation_x(0.3);
    assert!(DQuat::from_xyzw(x, y, z, w).angle_between(tilt) < 1e-15);
    let ShapeDesc::Hull { points } = &parts[2].shape else {
        panic!("{:?}", parts[2].shape)
    };
    assert_eq!(points.len(), 8);
    assert!(
        points
            .iter()
            .all(|p| p.iter().all(|c| (c.abs() - 0.02).abs() < 1e-15)),
        "{points:?}"
    );
    // The mount has one box, placed at its origin.
    let mount = robot.links.iter().find(|l| l.name == "mount").unwrap();
    let Some(ShapeDesc::Compound { parts }) = collision_shape(mount, &desc, &base).unwrap() else {
        panic!("not a compound")
    };
    assert_eq!(
        (parts.len(), &parts[0].shape, parts[0].position),
        (
            1,
            &ShapeDesc::Box {
                half_extents: [0.1, 0.1, 0.02]
            },
            [0.0, 0.0, 0.02]
        )
    );
}

/// Overrides: a link's shape and mass replace the file's (the inertia is the box's closed
/// form), a joint's spring, damping, limit and initial state replace the file's, and links
/// not overridden keep the file's inertia.
#[test]
fn overrides_replace_what_they_name() {
    let base = fixtures();
    let m = urdf_pendulum(
        r#"links: [LinkOverride(name: "rod", shape: Box(half_extents: (0.03, 0.02, 0.3)),
                                position: (0.0, 0.0, -0.3), mass: Mass(2.0), material: "steel")]"#,
    );
    let mut u = m.urdf.clone().unwrap();
    u.joints[0].spring = Some((5.0, 0.1));
    u.joints[0].damping = Some(0.2);
    u.joints[0].qd = -0.5;
    u.joints[0].limit = Some(LimitDesc {
        lower: -1.0,
        upper: 1.5,
        restitution: 0.3,
    });
    let p = parts(&u, &base).unwrap();
    let rod = p.links.iter().find(|l| l.name == "rod").unwrap();
    assert_eq!(rod.material, "steel");
    let (mass, h) = (2.0, DVec3::new(0.03, 0.02, 0.3));
    let want = DVec3::new(
        h.y * h.y + h.z * h.z,
        h.x * h.x + h.z * h.z,
        h.x * h.x + h.y * h.y,
    ) * (mass / 3.0);
    let got = rod.inertia;
    assert!((got.mass - mass).abs() < MASS_TOL * mass);
    assert!((got.com - DVec3::new(0.0, 0.0, -0.3)).length() < MASS_TOL);
    let i = got.inertia_com;
    for k in 0..3 {
        assert!(
            (i.col(k)[k] - want[k]).abs() < MASS_TOL * want[k],
            "{i:?} {want}"
        );
    }
    let j = &p.joints[0];
    assert_eq!((j.q, j.qd), (1.3, -0.5));
    assert_eq!(
        (
            j.spec.passive.stiffness,
            j.spec.passive.rest,
            j.spec.passive.damping,
            j.spec.passive.friction
        ),
        (5.0, 0.1, 0.2, 0.0)
    );
    assert_eq!(j.spec.limit, Some(JointLimit::new(-1.0, 1.5, 0.3)));
    // Without the override the file's <dynamics damping> and <inertial> stand.
    let plain = parts(&urdf_pendulum("").urdf.unwrap(), &base).unwrap();
    assert_eq!(plain.joints[0].spec.passive.damping, 0.01);
    assert_eq!(plain.joints[0].spec.limit, None);
    let rod = plain.links.iter().find(|l| l.name == "rod").unwrap();
    assert_eq!(rod.inertia.mass, 1.0);
    assert_eq!(rod.material, "default");
    assert_eq!(plain.root, "mount");
}

/// A directory holding `files` (name, text) for one test.
fn temp(test: &str, files: &[(&str, &str)]) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("impulse-urdf-{}-{test}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (name, text) in files {
        std::fs::write(dir.join(name), text).unwrap();
    }
    dir
}

const GOOD_LINKS: &str = r#"
  <link name="base"/>
  <link name="arm"><inertial><mass value="1"/><origin xyz="0 0 -0.1"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>"#;

fn robot(body: &str) -> String {
    format!(r#"<?xml version="1.0"?><robot name="r">{body}</robot>"#)
}

fn joint(name: &str, kind: &str, parent: &str, child: &str) -> String {
    format!(
        r#"<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/><axis xyz="0 1 0"/></joint>"#
    )
}

/// Every malformed URDF multibody gives an error naming the multibody and the culprit (file,
/// link, joint or override), never a panic.
#[test]
fn malformed_urdf_multibodies_name_the_culprit() {
    let hinge = joint("hinge", "revolute", "base", "arm");
    let arm_collision = |geometry: &str| {
        robot(&format!(
            r#"<link name="base"/><link name="arm"><inertial><mass value="1"/>
               <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
               <collision><geometry>{geometry}</geometry></collision></link>{hinge}"#
        ))
    };
    let files = [
        ("good.urdf", robot(&format!("{GOOD_LINKS}{hinge}"))),
        ("bad.urdf", "<robot name=\"r\"><link name=".to_string()),
        (
            "two_parents.urdf",
            robot(&format!(
                r#"{GOOD_LINKS}<link name="c"/>{hinge}{}{}"#,
                joint("j2", "revolute", "base", "c"),
                joint("j3", "fixed", "c", "arm")
            )),
        ),
        (
            "two_roots.urdf",
            robot(&format!(r#"{GOOD_LINKS}<link name="loose"/>{hinge}"#)),
        ),
        (
            "no_root.urdf",
            robot(&format!(
                "{GOOD_LINKS}{hinge}{}",
                joint("back", "revolute", "arm", "base")
            )),
        ),
        (
            "planar.urdf",
            robot(&format!(
                "{GOOD_LINKS}{}",
                joint("slider", "planar", "base", "arm")
            )),
        ),
        ("stl.urdf", arm_collision(r#"<mesh filename="arm.dae"/>"#)),
        (
            "dae.urdf",
            arm_collision(r#"<mesh filename="package://robot/arm.dae"/>"#),
        ),
        (
            "concave.urdf",
            arm_collision(r#"<mesh filename="frame.obj"/>"#),
        ),
        (
            "missing_mesh.urdf",
            arm_collision(r#"<mesh filename="nowhere.obj"/>"#),
        ),
        (
            "capsule.urdf",
            arm_collision(r#"<capsule radius="0.1" length="0.2"/>"#),
        ),
        ("bad_box.urdf", arm_collision(r#"<box size="0.1 -1 0.1"/>"#)),
    ];
    let frame = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/meshes/frame.obj"),
    )
    .unwrap();
    let mut all: Vec<(&str, &str)> = files.iter().map(|(n, t)| (*n, t.as_str())).collect();
    all.push(("frame.obj", &frame));
    let dir = temp("malformed", &all);
    let cases: [(&str, &str, &[&str]); 14] = [
        ("missing.urdf", "", &["missing.urdf"]),
        ("bad.urdf", "", &["bad.urdf"]),
        ("two_parents.urdf", "", &["arm", "child of two joints"]),
        ("two_roots.urdf", "", &["\"loose\"", "single root"]),
        ("no_root.urdf", "", &["no root"]),
        ("planar.urdf", "", &["slider", "planar"]),
        (
            "stl.urdf",
            "",
            &["arm.dae", "unsupported format", "\"arm\""],
        ),
        ("dae.urdf", "", &["package://"]),
        ("concave.urdf", "", &["frame.obj", "convex"]),
        ("missing_mesh.urdf", "", &["nowhere.obj"]),
        ("capsule.urdf", "", &["capsule", "\"arm\""]),
        ("bad_box.urdf", "", &["\"arm\"", "half_extents"]),
        (
            "good.urdf",
            r#"links: [LinkOverride(name: "hand")]"#,
            &["\"hand\"", "no link"],
        ),
        (
            "good.urdf",
            r#"joints: [JointOverride(name: "hinge", q: NaN)]"#,
            &["\"hinge\"", "q", "NaN"],
        ),
    ];
    for (file, extra, wanted) in cases {
        let m = multibody(&format!(
            r#"Multibody(name: "robot7", urdf: Urdf(path: "{file}", {extra}))"#
        ));
        let err = m
            .build(DVec3::new(0.0, 0.0, -9.81), &dir)
            .map(|_| ())
            .unwrap_err()
            .to_string();
        assert!(err.contains("robot7"), "{file}: {err}");
        for w in wanted {
            assert!(err.contains(w), "{file} {extra}: `{w}` not in: {err}");
        }
    }
    // More error cases on the good file: unknown joint, a doubled override, a fixed joint
    // given a state, a shape position without a shape.
    for (extra, wanted) in [
        (
            r#"joints: [JointOverride(name: "elbow")]"#,
            &["\"elbow\"", "no joint"][..],
        ),
        (
            r#"joints: [JointOverride(name: "hinge"), JointOverride(name: "hinge")]"#,
            &["\"hinge\"", "twice"][..],
        ),
        (
            r#"links: [LinkOverride(name: "arm", position: (0.0, 0.0, 1.0))]"#,
            &["\"arm\"", "position"][..],
        ),
        (
            r#"joints: [JointOverride(name: "hinge", limit: Limit(lower: NaN, upper: 1.0))]"#,
            &["\"hinge\"", "limit.lower"][..],
        ),
        (
            r#"joints: [JointOverride(name: "hinge", spring: (inf, 0.0))]"#,
            &["\"hinge\"", "spring"][..],
        ),
    ] {
        let m = multibody(&format!(
            r#"Multibody(name: "robot7", urdf: Urdf(path: "good.urdf", {extra}))"#
        ));
        let err = m
            .build(DVec3::new(0.0, 0.0, -9.81), &dir)
            .map(|_| ())
            .unwrap_err()
            .to_string();
        assert!(err.contains("robot7"), "{err}");
        for w in wanted {
            assert!(err.contains(w), "{extra}: `{w}` not in: {err}");
        }
    }
    // And the good file with a good override builds.
    let m = multibody(
        r#"Multibody(name: "robot7", urdf: Urdf(path: "good.urdf",
             joints: [JointOverride(name: "hinge", q: 0.5)]))"#,
    );
    let (sim, shapes) = m.build(DVec3::new(0.0, 0.0, -9.81), &dir).unwrap();
    assert_eq!(sim.q(), [0.5]);
    assert!(shapes.is_empty());
    let _ = std::fs::remove_dir_all(&dir);
}

/// Links and joints given inline besides the file are added to it: a tool welded to the arm
/// adds its mass (the model's total mass is the sum) and collides as its own link.
#[test]
fn inline_links_extend_a_urdf_multibody() {
    let dir = temp(
        "extend",
        &[(
            "arm.urdf",
            &robot(&format!(
                "{GOOD_LINKS}{}",
                joint("hinge", "revolute", "base", "arm")
            )),
        )],
    );
    let m = multibody(
        r#"Multibody(name: "m", urdf: Urdf(path: "arm.urdf"),
             links: [Link(name: "tool", shape: Sphere(radius: 0.05), position: (0.0, 0.0, -0.2),
                          mass: Mass(0.5))],
             joints: [Joint(name: "weld", kind: Fixed, parent: "arm", child: "tool")])"#,
    );
    let (sim, shapes) = m.build(DVec3::new(0.0, 0.0, -9.81), &dir).unwrap();
    assert_eq!(sim.model().joint_names(), ["hinge"]);
    assert_eq!(shapes.len(), 1);
    assert_eq!(shapes[0].link, "tool");
    // The arm swings with both masses: 1 kg at 0.1 m and 0.5 kg at 0.2 m below the hinge,
    // so its inertia about the hinge is 0.01 + 1·0.1² + (0.4·0.5·0.05² + 0.5·0.2²).
    let model = sim.model();
    let mut mm = impulse_multibody::Mat::<f64>::zeros(1, 1);
    impulse_multibody::mass_matrix(
        model,
        &mut impulse_multibody::Workspace::new(model),
        sim.q(),
        &mut mm,
    )
    .unwrap();
    let want = 0.01 + 0.01 + 0.4 * 0.5 * 0.05 * 0.05 + 0.5 * 0.04;
    assert!(
        (mm[(0, 0)] - want).abs() < MASS_TOL,
        "{} {want}",
        mm[(0, 0)]
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The examples of `docs/urdf.md` and README.md parse and build against the bundled arm, and
/// the bundled scene's arm has the file's links and joints in the documented order.
#[test]
fn documented_examples_build() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    for doc in ["docs/urdf.md", "README.md"] {
        let text = std::fs::read_to_string(root.join(doc)).unwrap();
        let block = text
            .split("```ron\n")
            .skip(1)
            .map(|b| b.split("```").next().unwrap())
            .find(|b| b.contains("urdf: Urdf("))
            .unwrap();
        let m = multibody(block);
        let (sim, shapes) = m.build(DVec3::new(0.0, 0.0, -9.81), &fixtures()).unwrap();
        assert_eq!(sim.model().joint_names(), ["shoulder", "elbow"], "{doc}");
        let links: Vec<&str> = shapes.iter().map(|s| s.link.as_str()).collect();
        assert_eq!(links, ["pedestal", "upper", "forearm", "hand"], "{doc}");
        assert_eq!(sim.q()[1], 0.3, "{doc}");
    }
    let scene = Scene::read(&fixtures().join("urdf-arm.ron")).unwrap();
    World::from_scene(&scene).unwrap();
}

/// The same twins with a floating base (the mount given a mass by an override from its
/// collision box, and inline from the same box), tumbling as they fall onto the floor: every
/// coordinate of the base and the joint agrees to rounding ([`TWIN_TOL`]).
#[test]
fn floating_urdf_pendulum_matches_its_inline_twin() {
    let float = |mut m: MultibodyDesc| {
        m.base = crate::scene::BaseDesc::Floating;
        m.angular_velocity = [0.3, -0.2, 0.5];
        m.velocity = [0.0, 0.2, 0.0];
        m
    };
    // A floating root needs mass: the mount plate's, from its collision box, in both.
    let urdf = urdf_pendulum(r#"links: [LinkOverride(name: "mount", mass: Mass(0.5))]"#);
    let mut inline = inline_pendulum();
    inline.links[0].mass = Some(MassDesc::Mass(0.5));
    let mut a = World::from_scene(&scene(float(urdf))).unwrap();
    let mut b = World::from_scene(&scene(float(inline))).unwrap();
    let (ha, hb) = (
        a.multibody_handle("p").unwrap(),
        b.multibody_handle("p").unwrap(),
    );
    let mut worst: f64 = 0.0;
    while a.time() < 1.0 {
        let t = a.time() + 0.01;
        a.step_until(t).unwrap();
        b.step_until(t).unwrap();
        let (sa, sb) = (a.multibody(ha).unwrap(), b.multibody(hb).unwrap());
        assert_eq!(sa.q().len(), 8);
        for (x, y) in sa.q().iter().chain(sa.v()).zip(sb.q().iter().chain(sb.v())) {
            worst = worst.max((x - y).abs());
        }
    }
    let c = a.counters();
    assert!(c.link_contacts > 0, "never reached the floor: {c:?}");
    eprintln!(
        "floating URDF vs inline: worst coordinate difference {worst:e}; {} link contacts",
        c.link_contacts
    );
    assert!(worst < TWIN_TOL, "URDF and inline differ by {worst:e}");
}

/// An STL mesh (binary and ASCII, written here from the OBJ cube by fanning its faces into
/// triangles) gives the same scaled hull as the OBJ it was written from.
#[test]
fn stl_meshes_give_the_hull_of_their_obj_twin() {
    let obj_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/meshes/cube20.obj");
    let mesh = impulse_geom::obj::read(&obj_path).unwrap();
    let tris: Vec<[DVec3; 3]> = mesh
        .faces()
        .flat_map(|f| {
            let v = |k: usize| mesh.vertices()[f[k] as usize];
            (1..f.len() - 1).map(move |k| [v(0), v(k), v(k + 1)])
        })
        .collect();
    let mut binary = vec![0u8; 80];
    binary.extend_from_slice(&(tris.len() as u32).to_le_bytes());
    let mut ascii = String::from("solid cube\n");
    for t in &tris {
        binary.extend_from_slice(&[0u8; 12]);
        ascii.push_str("facet normal 0 0 0\nouter loop\n");
        for p in t {
            for x in p.to_array() {
                binary.extend_from_slice(&(x as f32).to_le_bytes());
            }
            ascii.push_str(&format!("vertex {} {} {}\n", p.x, p.y, p.z));
        }
        binary.extend_from_slice(&[0u8; 2]);
        ascii.push_str("endloop\nendfacet\n");
    }
    ascii.push_str("endsolid cube\n");
    let urdf = |file: &str| {
        robot(&format!(
            r#"<link name="a"><collision><geometry><mesh filename="{file}" scale="0.01 0.02 0.03"/></geometry></collision></link>"#
        ))
    };
    let obj_text = std::fs::read_to_string(&obj_path).unwrap();
    let dir = temp(
        "stl",
        &[
            ("cube.obj", &obj_text),
            ("ascii.stl", &ascii),
            ("obj.urdf", &urdf("cube.obj")),
            ("bin.urdf", &urdf("bin.stl")),
            ("ascii.urdf", &urdf("ascii.stl")),
        ],
    );
    std::fs::write(dir.join("bin.stl"), &binary).unwrap();
    let hull = |file: &str| {
        let desc = UrdfDesc {
            path: file.into(),
            links: vec![],
            joints: vec![],
        };
        let robot = desc.read(&dir).unwrap();
        let Some(ShapeDesc::Compound { parts }) =
            collision_shape(&robot.links[0], &desc, &dir).unwrap()
        else {
            panic!("no compound")
        };
        let ShapeDesc::Hull { points } = &parts[0].shape else {
            panic!("{:?}", parts[0].shape)
        };
        let mut p = points.clone();
        p.sort_by(|a, b| a.partial_cmp(b).unwrap());
        p
    };
    let want = hull("obj.urdf");
    // The cube's corners at ±10, scaled by (0.01, 0.02, 0.03).
    assert_eq!(want.len(), 8);
    for p in &want {
        for (x, h) in p.iter().zip([0.1, 0.2, 0.3]) {
            assert!((x.abs() - h).abs() < 1e-15, "{p:?}");
        }
    }
    assert_eq!(hull("bin.urdf"), want);
    assert_eq!(hull("ascii.urdf"), want);
    let _ = std::fs::remove_dir_all(&dir);
}
