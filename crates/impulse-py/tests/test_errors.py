"""Bad input raises `impulse.ImpulseError` with a message naming what is wrong, never a crash."""

import numpy as np
import pytest

import impulse
from test_massprops import BOX_FACES, box


def test_missing_and_malformed_files(tmp_path):
    with pytest.raises(impulse.ImpulseError, match="nowhere.ron"):
        impulse.World.from_scene(tmp_path / "nowhere.ron")
    bad = tmp_path / "bad.ron"
    bad.write_text("Scene(gravity: (0.0, 0.0, -9.81), bodies: [Body(name: \"a\", shape: Blob)])")
    with pytest.raises(impulse.ImpulseError, match=r"bad\.ron.*1:"):
        impulse.World.from_scene(bad)
    with pytest.raises(impulse.ImpulseError, match="nowhere.obj"):
        impulse.mass_properties_obj(tmp_path / "nowhere.obj")
    with pytest.raises(impulse.ImpulseError, match="nowhere.urdf"):
        impulse.Model.from_urdf(tmp_path / "nowhere.urdf")
    with pytest.raises(impulse.ImpulseError, match="nowhere.ron"):
        impulse.PosePart.from_file(tmp_path / "nowhere.ron")
    part = impulse.PosePart.new("cube", shape=impulse.Shape.box([0.01, 0.01, 0.01]))
    study = impulse.run_pose_shard(part, 2, threads=1)
    with pytest.raises(impulse.ImpulseError, match=r"studies\[1\]: not a pose study"):
        impulse.merge_pose_studies([study, "not json"])
    with pytest.raises(impulse.ImpulseError, match="drop 0"):
        impulse.merge_pose_studies([study, study])  # a drop held twice


def test_unknown_body():
    w = impulse.World()
    w.add_body("ball", impulse.Shape.sphere(0.1))
    with pytest.raises(impulse.ImpulseError, match='body "bal".*no body of that name'):
        w.set_velocity("bal", [1, 0, 0], [0, 0, 0])
    with pytest.raises(impulse.ImpulseError, match="ball"):
        w.add_body("ball", impulse.Shape.sphere(0.1), position=[5, 0, 0])  # a duplicate name


def test_nan_inputs_name_the_value():
    w = impulse.World()
    with pytest.raises(impulse.ImpulseError, match=r"position\[2\] is NaN"):
        w.add_body("b", impulse.Shape.sphere(0.1), position=[0, 0, np.nan])
    with pytest.raises(impulse.ImpulseError, match="dt"):
        w.step(float("nan"))
    with pytest.raises(impulse.ImpulseError, match=r"vertices\[3, 1\] is NaN"):
        v = box(1, 1, 1)
        v[3, 1] = np.nan
        impulse.mass_properties(v, BOX_FACES)
    m = impulse.Model.from_urdf(
        __import__("pathlib").Path(__file__).parents[3] / "fixtures/urdf/two_link_arm.urdf")
    with pytest.raises(impulse.ImpulseError, match=r"q\[1\] is inf"):
        impulse.aba(m, [0.0, np.inf], [0, 0], [0, 0])
    with pytest.raises(impulse.ImpulseError, match=r"tau: expected 2 values .*shoulder, elbow"):
        impulse.aba(m, [0, 0], [0, 0], [0, 0, 0])


def test_bad_meshes_are_named():
    with pytest.raises(impulse.ImpulseError, match="(?i)open|boundary|edge"):
        impulse.mass_properties(box(1, 1, 1), BOX_FACES[:-1])  # a face missing: not closed
    with pytest.raises(impulse.ImpulseError, match=r"faces\[0\].*-1"):
        impulse.mass_properties(box(1, 1, 1), [[-1, 1, 2]] + BOX_FACES[1:])
    with pytest.raises(impulse.ImpulseError, match="(?i)coplanar|degenerate|flat"):
        impulse.convex_hull(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.0]]))


def test_bad_settings():
    with pytest.raises(impulse.ImpulseError, match="contact_model"):
        impulse.World(contact_model="springs")
    with pytest.raises(impulse.ImpulseError, match="collision_epsilon"):
        impulse.World(collision_epsilon=-1.0)
    part = impulse.PosePart.new("cube", shape=impulse.Shape.box([0.01, 0.01, 0.01]))
    with pytest.raises(impulse.ImpulseError, match="shard `3/2`"):
        impulse.run_pose_shard(part, 10, shard=(3, 2))
    with pytest.raises(impulse.ImpulseError, match="friction"):
        impulse.run_pose_shard(part, 10, friction=float("nan"))
