"""Contacts of the last step from Python: a ball dropped on the floor against the closed forms
of a free fall and a Newton impact, microcollisions against the momentum balance of a resting
box, held pairs against what rests and what flies, and the held pairs' impulses against the
weight they carry."""

import math

import numpy as np
import pytest

import impulse

G, H, E, M, R, EPS = 9.81, 0.2, 0.6, 2.0, 0.05, 1e-5


def drop_world(contact_model="switching"):
    """A ball of mass M whose lowest point is H above the floor's top (z = 0), at rest."""
    w = impulse.World(collision_epsilon=EPS, gravity=[0, 0, -G], friction=0.3, restitution=E,
                      contact_model=contact_model)
    w.add_body("floor", impulse.Shape.box([1.0, 1.0, 0.1]), position=[0, 0, -0.1], fixed=True)
    w.add_body("ball", impulse.Shape.sphere(R), position=[0, 0, R + H], mass=M)
    return w


@pytest.mark.parametrize("model", ["switching", "impulse"])
def test_a_dropped_ball_strikes_at_sqrt_2gh_and_leaves_at_e_times_it(model):
    w = drop_world(model)
    report = w.step(0.25)  # it lands at sqrt(2H/G) = 0.202 s; back up for 0.1 s
    hits = w.impacts()
    assert report["contacts"] == 1 == len(hits["time"]) == len(hits["kind"])
    assert hits["kind"] == ["collision"] and report["collisions"] == 1
    ball = w.names().index("ball")
    assert {hits["a"][0], hits["b"][0]} == {0, ball}
    on_ball = 1.0 if hits["a"][0] == ball else -1.0  # the impulse acts on `a`
    t = hits["time"][0]
    v = math.sqrt(2 * G * H)  # the speed of a free fall from H
    # The collision is found within ε_c of touching: the fall is short of H by at most ε_c.
    assert t == pytest.approx(math.sqrt(2 * H / G), abs=EPS / v)
    before, after = hits["normal_speed_before"][0], hits["normal_speed_after"][0]
    assert before == pytest.approx(-v, abs=G * EPS / v)
    assert before == pytest.approx(-G * t, rel=1e-12)  # the ball's own speed at that time
    assert after == pytest.approx(-E * before, rel=1e-12)  # Newton (= Stronge: no slip)
    # The impulse on the ball: M (1 + e) v, straight up; the normal points from b to a.
    np.testing.assert_allclose(on_ball * hits["impulse"][0], [0, 0, M * (1 + E) * v],
                               rtol=0, atol=M * (1 + E) * G * EPS / v)
    np.testing.assert_allclose(on_ball * hits["impulse"][0], [0, 0, -M * (1 + E) * before],
                               rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(on_ball * hits["normal"][0], [0, 0, 1], atol=1e-12)
    np.testing.assert_allclose(hits["point"][0], [0, 0, 0], atol=2 * EPS)
    assert hits["energy_after"][0] == pytest.approx(E * E * hits["energy_before"][0], rel=1e-12)
    assert hits["energy_before"][0] == pytest.approx(0.5 * M * before**2, rel=1e-12)
    # The ball leaves at e times its speed and decelerates under gravity until the end.
    assert w.velocities()[ball][2] == pytest.approx(-E * before - G * (0.25 - t), rel=1e-12)
    # The next call with no contact lists none.
    assert w.step(0.01)["contacts"] == 0 and len(w.impacts()["time"]) == 0


@pytest.mark.parametrize("speed", [0.0, 1.0])
def test_microcollisions_carry_the_momentum_of_a_box_on_the_floor(speed):
    """Under the impulse model a box on the floor, at rest or sliding, is held up by
    microcollisions (thesis §3.5): over a stretch T their impulses on the box add up to
    m Δv − m g T, the linear momentum balance of the box (gravity is the only other force);
    while it slides, each impulse lies on the friction cone, |J_t| = μ J_n (Coulomb)."""
    mu = 0.2
    w = impulse.World(collision_epsilon=1e-4, gravity=[0, 0, -G], friction=mu,
                      restitution=0.5, contact_model="impulse")
    w.add_body("floor", impulse.Shape.box([1.0, 1.0, 0.1]), position=[0, 0, -0.1], fixed=True)
    w.add_body("box", impulse.Shape.box([0.05, 0.04, 0.03]), position=[0, 0, 0.03], mass=M,
               velocity=[speed, 0, 0])
    w.step(0.05)
    v0 = w.velocities()[1].copy()
    T = 0.2  # sliding at 1 m/s, the box slows by μ g T = 0.39 m/s: it still slides at the end
    report = w.step(T)
    v1 = w.velocities()[1]
    hits = w.impacts()
    kinds = hits["kind"]
    assert len(kinds) == report["contacts"] > 20
    assert kinds.count("collision") == report["collisions"]
    assert kinds.count("microcollision") + kinds.count("reversing") == report["microcollisions"]
    assert set(hits["a"]) | set(hits["b"]) == {0, 1}
    sign = np.where(hits["a"] == 1, 1.0, -1.0)
    on_box = sign[:, None] * hits["impulse"]
    np.testing.assert_allclose(on_box.sum(axis=0), M * (v1 - v0) - M * np.array([0, 0, -G]) * T,
                               rtol=1e-10, atol=1e-12)
    assert on_box[:, 2].sum() == pytest.approx(M * G * T, rel=0.05)  # it stays on the floor
    assert np.all((hits["time"] >= 0.05) & (hits["time"] <= 0.05 + T))
    assert np.all(np.diff(hits["time"]) >= 0)  # in the order they happened
    if speed > 0:
        assert v1[0] > 0.4  # still sliding
        np.testing.assert_allclose(np.hypot(on_box[:, 0], on_box[:, 1]), mu * on_box[:, 2],
                                   rtol=1e-9)
        # Sliding makes the box rock: some contacts are fast enough to be collisions.
        assert kinds.count("microcollision") > 0 and kinds.count("collision") > 0
    else:
        # At rest, each microcollision is resolved by the reversing impulse (thesis §3.5).
        assert set(kinds) == {"reversing"}


def test_held_pairs_are_the_resting_contacts():
    w = impulse.World(collision_epsilon=1e-4, gravity=[0, 0, -G])
    w.add_body("floor", impulse.Shape.box([1.0, 1.0, 0.1]), position=[0, 0, -0.1], fixed=True)
    w.add_body("ball", impulse.Shape.sphere(R), position=[0.5, 0, 1.0])
    w.add_body("box", impulse.Shape.box([0.05, 0.05, 0.05]), position=[0, 0, 0.05])
    assert w.held_pairs().shape == (0, 2)
    w.step(0.1)
    pairs = w.held_pairs()
    assert pairs.dtype == np.int64
    np.testing.assert_array_equal(pairs, [[0, 2]])  # the box rests; the ball is in the air
    w.set_velocity("box", [0, 0, 2.0], [0, 0, 0])  # thrown up: the pair lets go
    w.step(0.05)
    assert w.held_pairs().shape == (0, 2)
    # The impulse model holds nothing: every contact is an impulse.
    w2 = impulse.World(collision_epsilon=1e-4, gravity=[0, 0, -G], contact_model="impulse")
    w2.add_body("floor", impulse.Shape.box([1.0, 1.0, 0.1]), position=[0, 0, -0.1], fixed=True)
    w2.add_body("box", impulse.Shape.box([0.05, 0.05, 0.05]), position=[0, 0, 0.05])
    w2.step(0.1)
    assert w2.held_pairs().shape == (0, 2) and len(w2.impacts()["time"]) > 0


# A held contact's impulses carry the weight at rest to within this fraction (the solver stops
# at its speed tolerance; the stabilisation's pull on a drifted gap adds a little).
STATIC_REL = 1e-4
HALF = 0.05  # the box's half extent
EPS_C = 1e-4  # the world's collision epsilon: the points lie within it of the corners
UNIT = 1e-12  # a normal is a unit vector to rounding


@pytest.mark.parametrize("spin", [0.0, 0.7])
def test_a_resting_box_s_held_impulses_carry_m_g_at_its_bottom_corners(spin):
    w = impulse.World(collision_epsilon=EPS_C, gravity=[0, 0, -G])
    w.add_body("floor", impulse.Shape.box([1.0, 1.0, 0.1]), position=[0, 0, -0.1], fixed=True)
    # Turned about z by `spin` (rad), so its corners are not on the world's axes.
    q = [0, 0, math.sin(spin / 2), math.cos(spin / 2)]
    w.add_body("box", impulse.Shape.box([HALF] * 3), position=[0.1, -0.2, HALF], rotation=q,
               mass=M)
    w.step(0.3)
    hc = w.held_contacts()
    np.testing.assert_array_equal(w.held_pairs(), [[0, 1]])
    assert len(hc["a"]) == 4  # a face on a face: four corners
    np.testing.assert_array_equal(hc["a"], 0)
    np.testing.assert_array_equal(hc["b"], 1)
    span = hc["span"][0]
    assert span > 0 and np.all(hc["span"] == span)
    # Static equilibrium over the step: the impulses on the box sum to m g span, straight up,
    # and their moment about its centre of mass vanishes.
    weight = M * G * span
    np.testing.assert_allclose(hc["impulse"].sum(0), [0, 0, weight], rtol=0,
                               atol=STATIC_REL * weight)
    com = w.centres_of_mass()[1]
    moment = np.cross(hc["point"] - com, hc["impulse"]).sum(0)
    np.testing.assert_allclose(moment, 0, atol=STATIC_REL * weight * HALF)
    np.testing.assert_allclose(hc["normal"], [[0, 0, 1]] * 4, rtol=0, atol=UNIT)
    # The points are the bottom face's corners (the box's own frame, turned back by -spin).
    c, s = math.cos(spin), math.sin(spin)
    local = (hc["point"] - com) @ np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    corners = {(int(np.sign(x)), int(np.sign(y))) for x, y, _ in local}
    assert corners == {(-1, -1), (-1, 1), (1, -1), (1, 1)}
    np.testing.assert_allclose(np.abs(local), [[HALF, HALF, HALF]] * 4, rtol=0, atol=EPS_C)
    # The impulse model holds nothing.
    w2 = impulse.World(collision_epsilon=EPS_C, gravity=[0, 0, -G], contact_model="impulse")
    w2.add_body("floor", impulse.Shape.box([1.0, 1.0, 0.1]), position=[0, 0, -0.1], fixed=True)
    w2.add_body("box", impulse.Shape.box([HALF] * 3), position=[0, 0, HALF], mass=M)
    w2.step(0.1)
    hc2 = w2.held_contacts()
    assert hc2["point"].shape == (0, 3) and hc2["span"].shape == (0,)
