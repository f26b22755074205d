"""FORK⁻¹S reduced mechanisms: the lever of docs/forks.md ("Conventions") against its closed
forms, and every number against `impulse reduce --static` / `--compliance`."""

import json

import numpy as np
import pytest
from roots import bisect

import impulse

C_HINGE, L = 0.01, 0.5  # rad/(N·m) and m: the lever's hinge compliance and arm


def test_the_lever_compliance_is_c_s_st(root):
    r = impulse.ReducedMechanism.from_file(root / "fixtures/mechanisms/lever.ron")
    assert r.end_effectors() == ["arm"] and r.rank == 1
    s = np.array([0, L, 0, 0, 0, 1.0])
    np.testing.assert_allclose(r.compliance(), C_HINGE * np.outer(s, s), atol=1e-15)
    np.testing.assert_allclose(r.reference_positions(), [[L, 0, 0]], atol=1e-15)


def test_the_lever_full_statics_solve_theta_equation(root):
    r = impulse.ReducedMechanism.from_file(root / "fixtures/mechanisms/lever.ron")
    force = 20.0  # N along y: theta = c L F cos(theta)
    theta = bisect(lambda t: t - C_HINGE * L * force * np.cos(t), 0.0, 1.0)
    full = r.full_static_positions({"arm": [0.0, force, 0.0]})
    np.testing.assert_allclose(full, [[L * np.cos(theta), L * np.sin(theta), 0]], atol=1e-10)
    # The reduced model is linear at rest: a small load moves the arm by C w.
    small = r.static_positions({"arm": [0.0, 0.1, 0.0]})
    np.testing.assert_allclose(small[0, 1], C_HINGE * L * L * 0.1, rtol=1e-3)


@pytest.mark.parametrize("mechanism,load", [("lever.ron", "arm:0,20,0"),
                                            ("loop.ron", None)])
def test_static_response_and_compliance_equal_the_cli(cli, root, tmp_path, mechanism, load):
    path = root / "fixtures/mechanisms" / mechanism
    r = impulse.ReducedMechanism.from_file(path)
    if load is None:
        link = r.end_effectors()[0]
        load = f"{link}:1.5,-2,0.5"
    link, nums = load.split(":")
    force = [float(x) for x in nums.split(",")]
    out = json.loads(cli("reduce", path, "--load", load, "--static",
                         "--compliance", tmp_path / "c.json"))
    ee = {e["link"]: e for e in out["end_effectors"]}
    names = r.end_effectors()
    red = r.static_positions({link: force})
    full = r.full_static_positions({link: force})
    for i, name in enumerate(names):
        np.testing.assert_array_equal(red[i], ee[name]["reduced"])
        np.testing.assert_array_equal(full[i], ee[name]["full"])
    exported = json.loads((tmp_path / "c.json").read_text())
    np.testing.assert_array_equal(r.compliance(), exported["compliance"])
    np.testing.assert_array_equal(r.stiffness(), exported["stiffness"])


def test_bad_loads_are_named(root):
    r = impulse.ReducedMechanism.from_file(root / "fixtures/mechanisms/lever.ron")
    with pytest.raises(impulse.ImpulseError, match='no link of that name'):
        r.static_positions({"hand": [1, 0, 0]})
    with pytest.raises(impulse.ImpulseError, match=r"\[1\] is NaN"):
        r.static_positions({"arm": [0, np.nan, 0]})
    with pytest.raises(impulse.ImpulseError, match="not an end effector"):
        r.static_positions({"base": [1, 0, 0]})
    with pytest.raises(impulse.ImpulseError, match="nowhere.ron"):
        impulse.ReducedMechanism.from_file(root / "nowhere.ron")
