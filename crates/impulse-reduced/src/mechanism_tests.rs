//! Validation of mechanism descriptions: every bad input gives an error naming the culprit.

use crate::desc::{JointDesc, LinkDesc, MechanismDesc};
use crate::error::Error;

/// A valid three-link chain with a loop: base → a → c and base → b → c, c → tip.
fn valid() -> MechanismDesc {
    let mut d = MechanismDesc::new("t");
    d.link(LinkDesc::new("base", [0.0; 3]))
        .link(LinkDesc::new("a", [0.0, 0.0, 1.0]).mass(1.0, [0.1; 3]))
        .link(LinkDesc::new("b", [1.0, 0.0, 0.0]).mass(1.0, [0.1; 3]))
        .link(LinkDesc::new("c", [1.0, 0.0, 1.0]).mass(1.0, [0.1; 3]))
        .link(LinkDesc::new("tip", [1.0, 0.0, 2.0]).mass(1.0, [0.1; 3]))
        .joint(JointDesc::ball("ja", "base", "a", [0.0; 3]).compliance(&[1e-3]))
        .joint(JointDesc::hinge(
            "jb",
            "base",
            "b",
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
        ))
        .joint(JointDesc::weld("jac", "a", "c", [0.5, 0.0, 1.0]).compliance(&[1e-3]))
        .joint(JointDesc::slider(
            "jbc",
            "b",
            "c",
            [1.0, 0.0, 0.5],
            [0.0, 0.0, 1.0],
        ))
        .joint(JointDesc::hinge(
            "jt",
            "c",
            "tip",
            [1.0, 0.0, 1.5],
            [1.0, 0.0, 0.0],
        ))
        .end_effector("tip");
    d
}

#[test]
fn valid_mechanism_compiles_with_walk_order_and_loops() {
    let m = valid().build().unwrap();
    assert_eq!(m.ndof, 3 + 1 + 6 + 1 + 1);
    let name = |l: usize| m.links[l].name.as_str();
    let order: Vec<&str> = m.order.iter().map(|&l| name(l)).collect();
    assert_eq!(order, ["base", "a", "b", "c", "tip"]);
    assert_eq!(m.loop_joints, [m.joint_index("jbc").unwrap()]);
    assert_eq!(
        m.tree_joint[m.link_index("c").unwrap()],
        m.joint_index("jac")
    );
    let internal: Vec<&str> = m.internal_links().iter().map(|&l| name(l)).collect();
    assert_eq!(internal, ["a", "b", "c"]);
    // Joint frames coincide at rest: P in the parent and Q in the child are the same world pose.
    for j in &m.joints {
        let wp = m.links[j.parent].rest * j.in_parent;
        let wc = m.links[j.child].rest * j.in_child;
        assert!((wp.translation - wc.translation).length() < 1e-15);
    }
}

#[test]
fn ron_round_trip_and_fixture_shape() {
    let d = valid();
    let text = d.to_ron().unwrap();
    assert_eq!(MechanismDesc::from_ron(&text).unwrap(), d);
    let e =
        MechanismDesc::from_ron("Mechanism(links: [], joints: [], end_effectors: [], bogus: 1)")
            .unwrap_err();
    assert!(
        matches!(e, Error::Parse(ref s) if s.contains("bogus")),
        "{e}"
    );
}

fn err(f: impl FnOnce(&mut MechanismDesc)) -> String {
    let mut d = valid();
    f(&mut d);
    d.build().unwrap_err().to_string()
}

/// One edit of the valid description.
type Edit = Box<dyn FnOnce(&mut MechanismDesc)>;

#[test]
fn bad_descriptions_name_the_culprit() {
    // Each edit breaks the valid mechanism in one way; the message must name what and where.
    let cases: Vec<(Edit, &[&str])> = vec![
        (
            Box::new(|d| d.links[1].position[0] = f64::NAN),
            &["link `a`", "position", "not finite"],
        ),
        (
            Box::new(|d| d.links[2].mass = -1.0),
            &["link `b`", "mass", "negative"],
        ),
        (
            Box::new(|d| d.links.push(LinkDesc::new("a", [0.0; 3]))),
            &["link `a`", "twice"],
        ),
        (
            Box::new(|d| d.joints[1].compliance = vec![0.0]),
            &["joint `jb`", "compliance is 0"],
        ),
        (
            Box::new(|d| d.joints[0].compliance = vec![1e-3, -1.0, 1e-3]),
            &["joint `ja`", "direction 1", "-1"],
        ),
        (
            Box::new(|d| d.joints[2].compliance = vec![f64::NAN]),
            &["joint `jac`", "compliance", "not finite"],
        ),
        (
            Box::new(|d| d.joints[0].compliance = vec![1.0, 1.0]),
            &["joint `ja`", "2 values", "3 free"],
        ),
        (
            Box::new(|d| d.joints[4].child = "nowhere".into()),
            &["joint `jt`", "child", "nowhere"],
        ),
        (
            Box::new(|d| d.joints[1].parent = "b".into()),
            &["joint `jb`", "itself"],
        ),
        (
            Box::new(|d| d.joints[1].kind = crate::desc::JointKindDesc::Hinge { axis: [0.0; 3] }),
            &["joint `jb`", "axis", "zero"],
        ),
        (
            Box::new(|d| d.joints[1].damping = vec![1.0]),
            &["joint `jb`", "damping"],
        ),
        (
            Box::new(|d| d.end_effectors = vec!["c".into()]),
            &["end effector `c`", "not a leaf", "jt"],
        ),
        (
            Box::new(|d| d.end_effectors = vec!["base".into()]),
            &["end effector `base`", "base"],
        ),
        (
            Box::new(|d| d.end_effectors = vec!["ghost".into()]),
            &["end effector `ghost`", "no such link"],
        ),
        (Box::new(|d| d.end_effectors.clear()), &["no end effector"]),
        (
            Box::new(|d| {
                d.joints.push(JointDesc::hinge(
                    "back",
                    "tip",
                    "a",
                    [0.0; 3],
                    [1.0, 0.0, 0.0],
                ));
                d.end_effectors = vec!["b".into()];
                d.joints.retain(|j| j.name != "jbc");
            }),
            &["unwalkable loop", "joint `"],
        ),
        (
            Box::new(|d| {
                d.links.push(LinkDesc::new("orphan", [0.0; 3]));
            }),
            &["exactly one base", "orphan"],
        ),
    ];
    for (k, (edit, words)) in cases.into_iter().enumerate() {
        let msg = err(edit);
        for w in words {
            assert!(msg.contains(w), "case {k}: `{msg}` lacks `{w}`");
        }
    }
}

#[test]
fn cycle_names_a_joint_on_the_cycle() {
    // base → a → c → a' (cycle a → c → a through joint "back").
    let mut d = valid();
    d.joints.push(JointDesc::hinge(
        "back",
        "c",
        "a",
        [0.0; 3],
        [1.0, 0.0, 0.0],
    ));
    let e = d.build().unwrap_err();
    let Error::Cycle(j) = e else { panic!("{e}") };
    assert!(j == "back" || j == "jac", "{j}");
}

/// The size limit counts the joints' degrees of freedom as declared (the valid mechanism has
/// 3 + 1 + 6 + 1 + 1 = 12, counted by hand from its joint kinds) and is checked before any
/// other validation: a mechanism over it is refused even when it is also malformed.
#[test]
fn a_mechanism_over_the_dof_limit_is_refused_before_any_work() {
    let d = valid();
    assert!(d.build_with_max_dof(12).is_ok());
    let e = d.build_with_max_dof(11).unwrap_err();
    assert!(
        matches!(
            e,
            Error::TooLarge {
                links: 5,
                dof: 12,
                limit: 11
            }
        ),
        "{e}"
    );
    assert!(e.to_string().contains("--max-dof"), "{e}");
    // Links count too: many links and no joints (which would fail later for want of joints)
    // stop at the limit.
    let mut many = MechanismDesc::new("many");
    for i in 0..crate::desc::MAX_DOF + 2 {
        many.link(LinkDesc::new(&format!("l{i}"), [0.0; 3]));
    }
    assert!(matches!(
        many.build().unwrap_err(),
        Error::TooLarge { links, dof: 0, .. } if links == crate::desc::MAX_DOF + 2
    ));
    // The paper's largest mechanism (helix-400, 400 ball joints) is within the default.
    let helix = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../fixtures/mechanisms/helix-400.ron"
    ))
    .unwrap();
    let m = MechanismDesc::from_ron(&helix).unwrap().build().unwrap();
    assert_eq!(m.ndof, 3 * 400);
}
