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


# Reduced dynamics (FORK⁻¹S §6): the runs of `impulse reduce --until … --dt … --out FILE`.
RUNS = [
    # mechanism, CLI options, keywords of `simulate`
    ("lever.ron", ["--load", "arm:0,20,0", "--until", "0.1", "--dt", "1e-3"],
     dict(until=0.1, dt=1e-3, loads={"arm": [0, 20, 0]})),
    # A "Y" with a cross-bar: end effectors and internal links, a force and a torque.
    ("y.ron", ["--load", "a3:0.5,0,-1,0,0.2,0", "--until", "0.05", "--dt", "5e-4"],
     dict(until=0.05, dt=5e-4, loads={"a3": [0.5, 0, -1, 0, 0.2, 0]})),
    # The lever with its arm's frame turned 73.7° about z (quaternion (0, 0, 0.6, 0.8)): the
    # load, given in world axes, is held in the arm's frame at rest, not in the world's axes.
    ("lever-turned", ["--load", "arm:0,20,0", "--until", "0.05", "--dt", "1e-3"],
     dict(until=0.05, dt=1e-3, loads={"arm": [0, 20, 0]})),
    # The six-legged robot on a free base standing on the ground: 200 steps, every 2nd
    # recorded (the CLI keeps about 100 frames), six feet in contact.
    ("legged-6.ron", ["--ground", "0", "--until", "0.2", "--dt", "1e-3"],
     dict(until=0.2, dt=1e-3, ground=0.0, every=2)),
]


@pytest.mark.parametrize("mechanism,args,kw", RUNS, ids=[r[0] for r in RUNS])
def test_simulation_equals_impulse_reduce_out_bit_for_bit(cli, root, tmp_path, mechanism, args,
                                                          kw):
    path = root / "fixtures/mechanisms" / mechanism
    if mechanism == "lever-turned":
        text = (root / "fixtures/mechanisms/lever.ron").read_text()
        text = text.replace("position: (0.5, 0.0, 0.0),",
                            "position: (0.5, 0.0, 0.0), rotation: (0.0, 0.0, 0.6, 0.8),")
        path = tmp_path / "lever-turned.ron"
        path.write_text(text)
    out = tmp_path / "run.json"
    report = cli.json("reduce", path, *args, "--threads", 1, "--out", out)
    ran = json.loads(out.read_text())
    states = np.array([f["states"] for f in ran["frames"]])  # (F, L, 13)
    r = impulse.ReducedMechanism.from_file(path)
    d = r.simulate(threads=1, **kw)
    assert d["links"] == ran["bodies"]
    assert d["positions"].shape == states[:, :, 0:3].shape
    assert d["positions"].dtype == np.float64
    np.testing.assert_array_equal(d["time"], [f["t"] for f in ran["frames"]])
    np.testing.assert_array_equal(d["positions"], states[:, :, 0:3])
    np.testing.assert_array_equal(d["orientations"], states[:, :, 3:7])
    # The internal links placed on two threads: the same numbers (the library's promise).
    np.testing.assert_array_equal(r.simulate(threads=2, **kw)["positions"], d["positions"])
    # Stepped from Python, the same run passes through the same recorded states.
    every = kw.get("every", 1)
    sim = r.simulation(dt=kw["dt"], loads=kw.get("loads"), ground=kw.get("ground"), threads=1)
    assert sim.links() == ran["bodies"]
    for frame in range(len(d["time"])):
        ends = sim.step(every)
        assert sim.time == pytest.approx(d["time"][frame], rel=1e-12)
        np.testing.assert_array_equal(sim.positions(), d["positions"][frame])
        np.testing.assert_array_equal(sim.orientations(), d["orientations"][frame])
        n_ee = ends.shape[0]
        np.testing.assert_array_equal(ends, d["positions"][frame, :n_ee])
    if "ground" in kw:
        assert sim.contacts == 6  # each foot on the ground
    # The CLI prints the largest constraint error of its frames with 4 digits (rel. 5e-4).
    assert d["constraint_error"].max() == pytest.approx(report["max_constraint_error"], rel=5e-4)
    np.testing.assert_array_equal(ends[0], report["end_effector_0"])  # printed in full


def test_the_lever_swings_as_backward_euler_on_its_hinge_equation(root):
    """The lever of docs/forks.md under a force F held perpendicular to its arm: its reduced
    dynamics is I θ'' = L F − θ / c with I = I_com + m L² = 0.01 + 1 · 0.5² about the hinge,
    stepped by backward Euler (eqs. 23–24): θ_{n+1} = θ_n + h ω_{n+1},
    ω_{n+1} = (ω_n + h (L F − θ_n / c) / I) / (1 + h² / (c I)); the arm's end is at
    L (cos θ, sin θ, 0)."""
    r = impulse.ReducedMechanism.from_file(root / "fixtures/mechanisms/lever.ron")
    force, h, inertia, k = 2.0, 1e-3, 0.01 + 1.0 * L * L, 1.0 / C_HINGE
    d = r.simulate(0.5, dt=h, loads={"arm": [0, force, 0]})
    theta, omega, expected = 0.0, 0.0, []
    for _ in range(500):
        omega = (omega + h * (L * force - k * theta) / inertia) / (1 + h * h * k / inertia)
        theta += h * omega
        expected.append([L * np.cos(theta), L * np.sin(theta), 0.0])
    np.testing.assert_allclose(d["positions"][:, 0, :], expected, rtol=0, atol=1e-14)
    # It swings about the static angle θ_s = c L F: the first swing reaches about 2 θ_s at
    # half a period π √(I c) (backward Euler's damping, ~ω²h/2 per second, takes 1.7 %).
    swing = np.arctan2(d["positions"][:, 0, 1], d["positions"][:, 0, 0])
    top = np.argmax(swing[:200])
    assert d["time"][top] == pytest.approx(np.pi * np.sqrt(inertia * C_HINGE), abs=2 * h)
    assert swing[top] == pytest.approx(2 * C_HINGE * L * force, rel=0.03)


def test_bad_simulation_input_is_named(root):
    r = impulse.ReducedMechanism.from_file(root / "fixtures/mechanisms/lever.ron")
    with pytest.raises(impulse.ImpulseError, match=r"dt 0: the time step must be a positive number"):
        r.simulation(dt=0.0)
    with pytest.raises(impulse.ImpulseError, match=r"dt NaN"):
        r.simulate(0.1, dt=float("nan"))
    with pytest.raises(impulse.ImpulseError, match=r"until -1"):
        r.simulate(-1.0)
    with pytest.raises(impulse.ImpulseError, match="not an end effector"):
        r.simulation(loads={"base": [1, 0, 0]})
    with pytest.raises(impulse.ImpulseError, match="threads 0"):
        r.simulation(threads=0)
    with pytest.raises(impulse.ImpulseError, match="every 0"):
        r.simulate(0.1, every=0)
    with pytest.raises(impulse.ImpulseError, match="ground NaN"):
        r.simulation(ground=float("nan"))
    # A load far beyond double precision's reach: named at the step it broke.
    with pytest.raises(impulse.ImpulseError, match=r"not finite at t = .*link `arm`"):
        r.simulate(0.01, loads={"arm": [0, 1e306, 0]})
    sim = r.simulation()
    with pytest.raises(impulse.ImpulseError, match='no link of that name'):
        sim.set_loads({"hand": [1, 0, 0]})
    sim.set_loads({"arm": [0, 1e306, 0]})
    with pytest.raises(impulse.ImpulseError, match=r"not finite at t = .*link `arm`"):
        sim.step(10)
