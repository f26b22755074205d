"""Multibodies (thesis ch. 5) added to a world built in Python: the URDF arm scene rebuilt in
code, and a floating URDF robot added by keywords, each against the same scene file, bit for
bit (the library's own scene loader is the reference)."""

import numpy as np
import pytest

import impulse

# The multibody of fixtures/scenes/urdf-arm.ron, as written there.
ARM = """Multibody(
    name: "arm",
    urdf: Urdf(
        path: "../urdf/two_link_arm.urdf",
        links: [LinkOverride(name: "hand", material: "steel")],
        joints: [
            JointOverride(name: "shoulder", damping: 0.05),
            JointOverride(name: "elbow", q: 0.3,
                          limit: Limit(lower: -2.0, upper: 2.0, restitution: 0.2)),
        ],
    ),
    base: Fixed,
    position: (0.0, 0.0, 0.01),
    controllers: [Pd(joint: "elbow", kp: 2.0, kv: 0.05, target: 0.3, rate: 200.0)],
)"""


def arm_world_in_code(root):
    w = impulse.World(collision_epsilon=1e-4, gravity=[0, 0, -9.81], friction=0.4,
                      restitution=0.3, base_dir=root / "fixtures/scenes")
    w.set_material_pair("steel", "wood", friction=0.3, restitution=0.5)
    w.add_body("floor", impulse.Shape.box([1.5, 1.5, 0.05]), position=[0, 0, -0.05], fixed=True)
    cube = impulse.Shape.box([0.04, 0.04, 0.04])
    w.add_body("block1", cube, position=[0.45, 0, 0.04], density=600.0, material="wood")
    w.add_body("block2", cube, position=[0.6, 0.02, 0.04], density=600.0, material="wood")
    w.add_body("ball", impulse.Shape.sphere(0.03), position=[0.75, -0.01, 0.03],
               density=7800.0, material="steel")
    rows = w.add_multibody(ARM)
    assert rows == [4, 5, 6, 7]
    return w


def same_run(a, b, steps, dt=0.01, multibody=None):
    """Steps both worlds alike; asserts equal states, contacts and joint states at every
    step; returns the collisions counted and the pairs of rows that struck."""
    collisions, pairs = 0, set()
    for _ in range(steps):
        ra, rb = a.step(dt), b.step(dt)
        assert ra == rb
        collisions += ra["collisions"]
        np.testing.assert_array_equal(a.states(), b.states())
        ia, ib = a.impacts(), b.impacts()
        pairs |= set(zip(ia["a"].tolist(), ia["b"].tolist()))
        for key in ("time", "a", "b", "impulse", "normal_speed_before"):
            np.testing.assert_array_equal(ia[key], ib[key])
        if multibody:
            for x, y in zip(a.joint_state(multibody), b.joint_state(multibody)):
                np.testing.assert_array_equal(x, y)
    return collisions, pairs


def test_the_urdf_arm_scene_built_in_code_runs_bit_for_bit(root):
    a = arm_world_in_code(root)
    b = impulse.World.from_scene(root / "fixtures/scenes/urdf-arm.ron")
    assert a.names() == b.names() == ["floor", "block1", "block2", "ball", "arm/pedestal",
                                      "arm/upper", "arm/forearm", "arm/hand"]
    assert a.multibody_names() == b.multibody_names() == ["arm"]  # the scene file's
    q, v = a.joint_state("arm")
    np.testing.assert_array_equal(q, [0.0, 0.3])  # shoulder, elbow as the scene sets them
    np.testing.assert_array_equal(v, [0.0, 0.0])
    # 1 s: the arm falls, its hand and forearm strike block1 and the floor.
    collisions, pairs = same_run(a, b, 100, multibody="arm")
    assert collisions > 10 and (1, 7) in pairs  # the hand struck block1
    assert a.joint_state("arm")[0][0] > 1.0  # the shoulder turned down towards the floor


def robot_scene(urdf):
    return f"""Scene(
    gravity: (0.0, 0.0, -9.81), collision_epsilon: 1e-4,
    default_contact: Contact(friction: 0.5, restitution: 0.4),
    bodies: [Body(name: "floor", motion: Fixed, shape: Box(half_extents: (2.0, 2.0, 0.05)),
                  position: (0.0, 0.0, -0.05))],
    multibodies: [Multibody(
        name: "robot",
        urdf: Urdf(path: "{urdf}", joints: [
            JointOverride(name: "shoulder", q: 0.4),
            JointOverride(name: "elbow", q: -0.3, qd: -12.0),
        ]),
        base: Floating,
        position: (0.1, -0.2, 0.3),
        rotation: Quaternion(0.0, 0.0, 0.6, 0.8),
        self_collision: true,
    )],
)"""


# A small free-flying robot: a 2 kg body with a two-link arm, every link a box; the forearm is
# long enough to strike the body when it folds back (a self-collision).
ROBOT_URDF = """<?xml version="1.0"?>
<robot name="crawler">
  <link name="body">
    <inertial><origin xyz="0 0 0"/><mass value="2.0"/>
      <inertia ixx="0.0020833" ixy="0" ixz="0" iyy="0.0070833" iyz="0" izz="0.0083333"/>
    </inertial>
    <collision><origin xyz="0 0 0"/><geometry><box size="0.2 0.1 0.05"/></geometry></collision>
  </link>
  <link name="upper">
    <inertial><origin xyz="0.1 0 0"/><mass value="0.4"/>
      <inertia ixx="0.0001" ixy="0" ixz="0" iyy="0.0014" iyz="0" izz="0.0014"/>
    </inertial>
    <collision><origin xyz="0.1 0 0"/><geometry><box size="0.2 0.03 0.03"/></geometry></collision>
  </link>
  <link name="lower">
    <inertial><origin xyz="0.15 0 0"/><mass value="0.3"/>
      <inertia ixx="0.00002" ixy="0" ixz="0" iyy="0.00226" iyz="0" izz="0.00226"/>
    </inertial>
    <collision><origin xyz="0.15 0 0"/><geometry><box size="0.3 0.02 0.02"/></geometry></collision>
  </link>
  <joint name="shoulder" type="revolute">
    <parent link="body"/><child link="upper"/>
    <origin xyz="0.12 0 0"/><axis xyz="0 1 0"/>
    <dynamics damping="0.01" friction="0"/>
  </joint>
  <joint name="elbow" type="revolute">
    <parent link="upper"/><child link="lower"/>
    <origin xyz="0.22 0 0"/><axis xyz="0 1 0"/>
  </joint>
</robot>
"""


def test_a_floating_urdf_robot_added_by_keywords_equals_its_scene_file(tmp_path):
    urdf = tmp_path / "crawler.urdf"
    urdf.write_text(ROBOT_URDF)
    scene = tmp_path / "robot.ron"
    scene.write_text(robot_scene(urdf))
    b = impulse.World.from_scene(scene)
    a = impulse.World(collision_epsilon=1e-4, gravity=[0, 0, -9.81], friction=0.5,
                      restitution=0.4)
    a.add_body("floor", impulse.Shape.box([2.0, 2.0, 0.05]), position=[0, 0, -0.05], fixed=True)
    rows = a.add_urdf("robot", urdf, position=[0.1, -0.2, 0.3], rotation=[0, 0, 0.6, 0.8],
                      floating=True, q={"shoulder": 0.4, "elbow": -0.3}, qd={"elbow": -12.0},
                      self_collision=True)
    assert rows == [1, 2, 3]
    assert a.names() == b.names() == ["floor", "robot/body", "robot/upper", "robot/lower"]
    q, v = a.joint_state("robot")
    assert q.shape == (7 + 2,) and v.shape == (6 + 2,)  # a free base, then two hinges
    np.testing.assert_array_equal(q[-2:], [0.4, -0.3])
    np.testing.assert_array_equal(v[-2:], [0.0, -12.0])
    # 0.6 s: it lands on the floor, and its forearm, folding back, strikes its body.
    collisions, pairs = same_run(a, b, 60, multibody="robot")
    assert (0, 1) in pairs and (1, 3) in pairs


def test_bad_multibodies_are_refused_with_the_librarys_message(root, tmp_path):
    w = impulse.World(base_dir=root / "fixtures/scenes")
    assert w.multibody_names() == []
    with pytest.raises(impulse.ImpulseError, match=r"multibody: .*1:"):
        w.add_multibody("Multibody(name: \"x\", links: [Blob])")
    with pytest.raises(impulse.ImpulseError, match="nowhere.urdf"):
        w.add_urdf("x", tmp_path / "nowhere.urdf")
    urdf = root / "fixtures/urdf/two_link_arm.urdf"
    with pytest.raises(impulse.ImpulseError, match="wrist"):
        w.add_urdf("x", urdf, q={"wrist": 1.0})  # no such joint in the file
    with pytest.raises(impulse.ImpulseError, match=r'q\["elbow"\] is NaN'):
        w.add_urdf("x", urdf, q={"elbow": float("nan")})
    with pytest.raises(impulse.ImpulseError, match=r"position\[1\] is inf"):
        w.add_urdf("x", urdf, position=[0, np.inf, 0])
    w.add_urdf("arm", urdf)
    with pytest.raises(impulse.ImpulseError, match='multibody "arm".*name'):
        w.add_urdf("arm", urdf, position=[2, 0, 0])  # a second multibody of that name
    with pytest.raises(impulse.ImpulseError, match='multibody "leg": no multibody'):
        w.joint_state("leg")
    assert len(w) == 4  # only the one arm's links, nothing of the refused ones
    assert w.multibody_names() == ["arm"]
    w.add_urdf("second", urdf, position=[2, 0, 0])
    assert w.multibody_names() == ["arm", "second"]  # in the order they were added
    assert w.joint_state("second")[0].shape == (2,)
