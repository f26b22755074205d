"""Worlds from Python: a world built in code against the same scene file (bit for bit), free
flight against the closed-form parabola, the contact model, array shapes."""

import numpy as np
import pytest

import impulse

BODIES = [
    # name, shape (RON, Python), position, quaternion (x, y, z, w), velocity, omega, density
    ("lower", "Box(half_extents: (0.1, 0.075, 0.05))", impulse.Shape.box([0.1, 0.075, 0.05]),
     [0.0, 0.0, 0.15], [0.0691, 0.0207, 0.0, 0.9974], [0.1, 0.0, 0.0], [0.0, 0.5, 0.0], 700.0),
    ("upper", "Box(half_extents: (0.08, 0.06, 0.04))", impulse.Shape.box([0.08, 0.06, 0.04]),
     [0.01, 0.005, 0.4], [0.0103, -0.0522, 0.0, 0.9986], [0.0, 0.0, 0.0], [0.0, 0.0, 2.0], 700.0),
    ("ball", "Sphere(radius: 0.05)", impulse.Shape.sphere(0.05),
     [0.4, 0.0, 0.3], [0.0, 0.0, 0.0, 1.0], [-0.5, 0.1, 0.0], [0.0, 0.0, 0.0], 7800.0),
]


def scene_text(contact_model):
    rows = [
        'Body(name: "floor", shape: Box(half_extents: (1.0, 1.0, 0.1)), '
        "position: (0.0, 0.0, -0.1), motion: Fixed)"
    ]
    for name, ron, _, p, q, v, w, rho in BODIES:
        rows.append(
            f'Body(name: "{name}", shape: {ron}, position: ({p[0]!r}, {p[1]!r}, {p[2]!r}), '
            f"rotation: Quaternion({q[0]!r}, {q[1]!r}, {q[2]!r}, {q[3]!r}), "
            f"velocity: ({v[0]!r}, {v[1]!r}, {v[2]!r}), "
            f"angular_velocity: ({w[0]!r}, {w[1]!r}, {w[2]!r}), mass: Density({rho!r}))"
        )
    return (
        "Scene(gravity: (0.0, 0.0, -9.81), collision_epsilon: 2e-4, "
        "default_contact: Contact(friction: 0.5, restitution: 0.3), "
        f"contact_model: {contact_model}, bodies: [{', '.join(rows)}])"
    )


def world_in_code(contact_model):
    w = impulse.World(collision_epsilon=2e-4, gravity=[0, 0, -9.81], friction=0.5,
                      restitution=0.3, contact_model=contact_model.lower())
    w.add_body("floor", impulse.Shape.box([1.0, 1.0, 0.1]), position=[0, 0, -0.1], fixed=True)
    for name, _, shape, p, q, v, om, rho in BODIES:
        w.add_body(name, shape, position=p, rotation=q, velocity=v, angular_velocity=om,
                   density=rho)
    return w


@pytest.mark.parametrize("model", ["Switching", "Impulse"])
def test_world_in_code_equals_the_scene_file_bit_for_bit(tmp_path, model):
    path = tmp_path / "scene.ron"
    path.write_text(scene_text(model))
    a, b = world_in_code(model), impulse.World.from_scene(path)
    assert a.names() == b.names() == ["floor", "lower", "upper", "ball"]
    assert a.contact_model == b.contact_model == model.lower()
    collisions = 0
    for _ in range(60):  # 0.6 s: the blocks land and stack, the ball rolls
        ra, rb = a.step(0.01), b.step(0.01)
        assert ra == rb
        collisions += ra["collisions"]
        np.testing.assert_array_equal(a.states(), b.states())
    assert collisions > 0  # the trajectories went through contacts, not only free flight
    assert a.time == pytest.approx(0.6)


def test_free_flight_is_the_parabola():
    w = impulse.World(gravity=[0.0, 0.0, -9.81])
    v0, w0 = np.array([0.3, -0.2, 1.5]), np.array([0.0, 0.0, 3.0])
    w.add_body("ball", impulse.Shape.sphere(0.1), position=[0, 0, 1.0], velocity=v0,
               angular_velocity=w0)
    for k in range(1, 21):
        w.step(0.01)
        t = 0.01 * k
        expected = np.array([0, 0, 1.0]) + v0 * t + 0.5 * np.array([0, 0, -9.81]) * t * t
        np.testing.assert_allclose(w.positions()[0], expected, rtol=0, atol=1e-12)
        np.testing.assert_allclose(w.velocities()[0], v0 + [0, 0, -9.81 * t], atol=1e-12)
        np.testing.assert_allclose(w.angular_velocities()[0], w0, atol=1e-12)
        # The sphere turns about z at 3 rad/s: q = (0, 0, sin(3t/2), cos(3t/2)).
        np.testing.assert_allclose(
            w.orientations()[0], [0, 0, np.sin(1.5 * t), np.cos(1.5 * t)], atol=1e-9
        )


def test_arrays_have_one_row_per_body(root):
    w = impulse.World.from_scene(root / "fixtures/scenes/block-drop.ron")
    n = len(w)
    assert n == 3
    for get, cols in [(w.positions, 3), (w.orientations, 4), (w.velocities, 3),
                      (w.angular_velocities, 3), (w.centres_of_mass, 3), (w.states, 16)]:
        a = get()
        assert a.shape == (n, cols) and a.dtype == np.float64
    w.step_until(0.5)
    np.testing.assert_allclose(np.linalg.norm(w.orientations(), axis=1), 1.0, atol=1e-12)
    s = w.states()
    np.testing.assert_array_equal(s[:, 0:3], w.positions())
    np.testing.assert_array_equal(s[:, 3:7], w.orientations())


def test_the_contact_model_is_chosen(root):
    path = root / "fixtures/scenes/block-drop.ron"
    assert impulse.World.from_scene(path).contact_model == "switching"
    assert impulse.World.from_scene(path, contact_model="impulse").contact_model == "impulse"
    # Resting contact: the impulse model resolves it with microcollisions, the switching model
    # holds it as constraints in island steps.
    impulse_world = impulse.World.from_scene(path, contact_model="impulse")
    switching_world = impulse.World.from_scene(path)
    ri, rs = impulse_world.step_until(1.0), switching_world.step_until(1.0)
    assert ri["microcollisions"] > 0 and ri["island_steps"] == 0
    assert rs["island_steps"] > 0


def test_a_push_moves_a_body():
    w = impulse.World(gravity=[0, 0, 0])
    w.add_body("puck", impulse.Shape.box([0.1, 0.1, 0.1]), mass=2.0)
    w.apply_impulse("puck", [1.0, 0.0, 0.0], [0.0, 0.0, 0.0])
    w.step(0.5)
    np.testing.assert_allclose(w.velocities()[0], [0.5, 0, 0], atol=1e-14)  # J / m
    np.testing.assert_allclose(w.positions()[0], [0.25, 0, 0], atol=1e-14)
    w.set_force("puck", [0.0, 4.0, 0.0])  # a = 2 m/s² along y
    w.step(1.0)
    np.testing.assert_allclose(w.velocities()[0], [0.5, 2.0, 0], atol=1e-12)
