"""Articulated dynamics of URDF models (thesis ch. 4) against `impulse dynamics` and against
each other: ABA's accelerations put into RNEA give back the torques, and M(q) q̈ + bias = τ."""

import numpy as np
import pytest

import impulse


def csv(values):
    return ",".join(repr(float(x)) for x in values)


@pytest.mark.parametrize("urdf", ["two_link_arm.urdf", "double_pendulum.urdf"])
def test_aba_rnea_crba_equal_the_cli(cli, root, urdf):
    path = root / "fixtures/urdf" / urdf
    m = impulse.Model.from_urdf(path)
    assert m.joint_names() == cli.json("dynamics", path, "--joints")["joints"]
    rng = np.random.default_rng(3)
    for _ in range(3):
        q, v, tau = rng.normal(size=m.nq), rng.normal(size=m.nv), rng.normal(size=m.nv)
        qdd = impulse.aba(m, q, v, tau)
        ref = cli.json("dynamics", path, "--q", csv(q), "--qd", csv(v), "--tau", csv(tau))
        np.testing.assert_array_equal(qdd, ref["qdd"])
        a = rng.normal(size=m.nv)
        ref = cli.json("dynamics", path, "--inverse", "--q", csv(q), "--qd", csv(v),
                       "--qdd", csv(a))
        np.testing.assert_array_equal(impulse.rnea(m, q, v, a), ref["tau"])
        ref = cli.json("dynamics", path, "--mass-matrix", "--q", csv(q))
        np.testing.assert_array_equal(impulse.crba(m, q), ref["M"])


def test_the_three_algorithms_agree(root):
    m = impulse.Model.from_urdf(root / "fixtures/urdf/double_pendulum.urdf", gravity=[0, 0, -3.7])
    rng = np.random.default_rng(11)
    for _ in range(20):
        q, v, tau = rng.normal(size=m.nq), rng.normal(size=m.nv), rng.normal(size=m.nv)
        qdd = impulse.aba(m, q, v, tau)
        np.testing.assert_allclose(impulse.rnea(m, q, v, qdd), tau, atol=1e-12)
        mass = impulse.crba(m, q)
        assert mass.shape == (m.nv, m.nv)
        np.testing.assert_allclose(mass, mass.T, atol=1e-15)
        assert np.all(np.linalg.eigvalsh(mass) > 0)
        bias = impulse.rnea(m, q, v, np.zeros(m.nv))
        np.testing.assert_allclose(mass @ qdd + bias, tau, atol=1e-12)


FLOATING = """<robot name="floater">
  <link name="base"><inertial><mass value="2.0"/>
    <inertia ixx="0.02" iyy="0.03" izz="0.04" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="arm"><inertial><origin xyz="0 0 -0.2"/><mass value="0.5"/>
    <inertia ixx="0.01" iyy="0.01" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="hinge" type="revolute"><parent link="base"/><child link="arm"/>
    <origin xyz="0.1 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-3" upper="3" effort="10" velocity="10"/></joint>
</robot>
"""


def test_a_floating_base_falls_freely(cli, tmp_path):
    path = tmp_path / "floater.urdf"
    path.write_text(FLOATING)
    m = impulse.Model.from_urdf(path, floating_base=True)
    assert (m.nq, m.nv) == (7 + 1, 6 + 1)
    q0 = m.neutral_configuration()
    np.testing.assert_array_equal(q0, [0, 0, 0, 0, 0, 0, 1, 0])
    # No forces: the whole body falls at g (base at rest: spatial = classical acceleration)
    # and the joint does not move.
    qdd = impulse.aba(m, q0, np.zeros(m.nv), np.zeros(m.nv))
    np.testing.assert_allclose(qdd[:3], [0, 0, -9.81], atol=1e-12)
    np.testing.assert_allclose(qdd[3:], 0, atol=1e-12)
    q = np.array([0.1, 0.2, 0.3, 0.0, 0.0, np.sin(0.2), np.cos(0.2), 0.4])
    v = np.array([0.1, 0.0, -0.2, 0.3, 0.1, 0.0, 1.0])
    tau = np.array([0, 0, 0, 0, 0, 0, 0.7])
    ref = cli.json("dynamics", path, "--floating-base", "--q", csv(q), "--qd", csv(v),
                   "--tau", csv(tau))
    np.testing.assert_array_equal(impulse.aba(m, q, v, tau), ref["qdd"])
