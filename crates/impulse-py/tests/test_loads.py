"""Loads and impulses from Python against the closed forms of a free body without gravity:
a constant force gives x = F t² / (2m), a constant torque on a sphere (I = 2/5 m r²) spins it
up as ω = τ t / I, a force off the centre of mass does both."""

import numpy as np
import pytest

import impulse

M, R = 2.0, 0.1
I = 0.4 * M * R * R  # a solid sphere's moment of inertia


def free_sphere(position=(0.0, 0.0, 0.0)):
    w = impulse.World(gravity=[0, 0, 0])
    w.add_body("ball", impulse.Shape.sphere(R), position=list(position), mass=M)
    return w


def test_a_constant_force_moves_the_body_as_f_t2_over_2m():
    x0, f = np.array([0.3, -0.2, 1.0]), np.array([1.5, -4.0, 0.5])
    w = free_sphere(x0)
    w.set_load("ball", force=f)
    for k in range(1, 11):
        w.step(0.1)
        t = 0.1 * k
        np.testing.assert_allclose(w.positions()[0], x0 + f * t * t / (2 * M), rtol=0,
                                   atol=1e-12)
        np.testing.assert_allclose(w.velocities()[0], f * t / M, rtol=0, atol=1e-12)
        np.testing.assert_allclose(w.angular_velocities()[0], 0, atol=1e-15)
    # Cleared, the load stops: the body coasts at the speed it had.
    w.clear_load("ball")
    v = w.velocities()[0].copy()
    w.step(0.5)
    np.testing.assert_allclose(w.velocities()[0], v, rtol=0, atol=1e-12)


def test_a_constant_torque_spins_a_sphere_as_tau_t_over_i():
    tau = 0.02  # N·m about z: θ(t) = τ t² / (2 I)
    w = free_sphere()
    w.set_load("ball", torque=[0, 0, tau])
    for k in range(1, 11):
        w.step(0.05)
        t = 0.05 * k
        np.testing.assert_allclose(w.angular_velocities()[0], [0, 0, tau * t / I], rtol=1e-12,
                                   atol=1e-15)
        theta = tau * t * t / (2 * I)
        np.testing.assert_allclose(w.orientations()[0],
                                   [0, 0, np.sin(theta / 2), np.cos(theta / 2)], atol=1e-9)
        np.testing.assert_allclose(w.positions()[0], 0, atol=1e-15)


def test_a_force_at_a_point_pushes_and_turns():
    f = 3.0  # N along y at the sphere's +x pole: a torque r f about z
    w = free_sphere()
    w.set_load("ball", force=[0, f, 0], point=[R, 0, 0])
    w.step(0.4)
    t = 0.4
    np.testing.assert_allclose(w.velocities()[0], [0, f * t / M, 0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(w.positions()[0], [0, f * t * t / (2 * M), 0], rtol=0,
                               atol=1e-12)
    np.testing.assert_allclose(w.angular_velocities()[0], [0, 0, R * f * t / I], rtol=1e-12)


def test_an_impulse_off_the_centre_of_mass_pushes_and_turns():
    j = 0.5  # N·s along y at the +x pole: Δv = J/m, Δω = r J / I
    w = free_sphere()
    w.apply_impulse("ball", [0, j, 0], [R, 0, 0])
    w.step(0.1)
    np.testing.assert_allclose(w.velocities()[0], [0, j / M, 0], rtol=1e-14)
    np.testing.assert_allclose(w.angular_velocities()[0], [0, 0, R * j / I], rtol=1e-14)


def test_bad_loads_are_refused_with_the_librarys_message():
    w = free_sphere()
    w.add_body("wall", impulse.Shape.box([0.1, 1, 1]), position=[2, 0, 0], fixed=True)
    with pytest.raises(impulse.ImpulseError, match='body "bal".*no body of that name'):
        w.set_load("bal", force=[1, 0, 0])
    with pytest.raises(impulse.ImpulseError, match=r"torque\[1\] is NaN"):
        w.set_load("ball", torque=[0, np.nan, 0])
    with pytest.raises(impulse.ImpulseError, match=r"point: expected 3 values"):
        w.set_load("ball", force=[1, 0, 0], point=[0, 0])
    with pytest.raises(impulse.ImpulseError, match='body "wall".*only a dynamic body'):
        w.set_load("wall", force=[1, 0, 0])
    with pytest.raises(impulse.ImpulseError, match='body "wall".*only a dynamic body'):
        w.apply_impulse("wall", [1, 0, 0], [2, 0, 0])
    with pytest.raises(impulse.ImpulseError, match='body "nobody"'):
        w.clear_load("nobody")
    with pytest.raises(impulse.ImpulseError, match=r"dt.*-0\.1 must be finite and ≥ 0"):
        w.step(-0.1)
    # Nothing refused changed the world.
    w.step(0.1)
    np.testing.assert_array_equal(w.velocities(), 0)
