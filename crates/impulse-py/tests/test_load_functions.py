"""Load functions: a Python callable the simulator calls for a body's load (thesis §7.3's
controllers, here at a fixed rate with the load held in between), against closed forms of a
free body without gravity — a spring −k x against the harmonic oscillator, a damper −c v
against the exponential decay — and against the exact recurrence of a load held constant
between calls; errors raised inside the callable come out of `step` with the world unchanged."""

import math
import threading

import numpy as np
import pytest

import impulse

M, R = 2.0, 0.1
I = 0.4 * M * R * R  # a solid sphere's moment of inertia
RATE = 2000.0  # load evaluations per second
H = 1.0 / RATE
DT = 0.01  # the step the tests call: 20 evaluations each
# A load held constant over each 1/RATE is integrated exactly (a parabola): the recurrence of
# that hold, run in NumPy, matches the simulator to rounding over 2000 evaluations.
HOLD_EXACT = 1e-10
K = M * (2 * math.pi) ** 2  # ω = 2π rad/s: one period a second
OMEGA = math.sqrt(K / M)
T_END = 1.0
# The hold lags the spring by H/2 on average: the sampled oscillator's amplitude grows by
# about ω² H t / 4 and its phase drifts by O(ω H); this bounds both over T_END (relative).
HOLD_DRIFT = OMEGA**2 * H * T_END
# A constant load over a step is a parabola, integrated to rounding (relative).
ROUNDING = 1e-12
C = 1.0  # damping coefficient (N·s/m): v = v0 exp(−C t / M)
# The damper's hold: (1 − C H / M)^n against exp(−C n H / M) differs by n (C H / M)² / 2.
DAMP_DRIFT = T_END * C * C * H / (M * M)


def free_sphere(position=(0.0, 0.0, 0.0), velocity=(0.0, 0.0, 0.0)):
    w = impulse.World(gravity=[0, 0, 0])
    w.add_body("ball", impulse.Shape.sphere(R), position=list(position),
               velocity=list(velocity), mass=M)
    return w


def run(w, steps):
    """Positions and velocities of body 0 after each of `steps` steps of DT."""
    xs, vs = [], []
    for _ in range(steps):
        w.step(DT)
        xs.append(w.positions()[0].copy())
        vs.append(w.velocities()[0].copy())
    return np.array(xs), np.array(vs)


def held_recurrence(x0, v0, force, steps):
    """The exact motion under `force(x, v)` held over each 1/RATE, sampled every DT."""
    x, v = np.array(x0, float), np.array(v0, float)
    per = round(DT * RATE)
    xs, vs = [], []
    for _ in range(steps):
        for _ in range(per):
            a = force(x, v) / M
            x, v = x + v * H + 0.5 * a * H * H, v + a * H
        xs.append(x.copy())
        vs.append(v.copy())
    return np.array(xs), np.array(vs)


def test_a_spring_load_oscillates_as_the_harmonic_closed_form():
    x0 = np.array([0.1, 0.0, 0.0])
    w = free_sphere(x0)
    calls = []

    def spring(t, state):
        calls.append(t)
        return -K * state["com"], np.zeros(3)

    w.set_load_function("ball", spring, RATE)
    steps = round(T_END / DT)
    xs, vs = run(w, steps)
    t = DT * np.arange(1, steps + 1)
    # The closed form x = x0 cos ωt, v = −x0 ω sin ωt, within the hold's drift.
    np.testing.assert_allclose(xs[:, 0], x0[0] * np.cos(OMEGA * t), rtol=0,
                               atol=HOLD_DRIFT * x0[0])
    np.testing.assert_allclose(vs[:, 0], -x0[0] * OMEGA * np.sin(OMEGA * t), rtol=0,
                               atol=HOLD_DRIFT * x0[0] * OMEGA)
    # Energy ½ m v² + ½ k x² stays at ½ k x0², within the hold's drift.
    energy = 0.5 * M * (vs**2).sum(1) + 0.5 * K * (xs**2).sum(1)
    np.testing.assert_allclose(energy, 0.5 * K * x0[0] ** 2, rtol=2 * HOLD_DRIFT)
    # The hold itself, exactly: the simulator integrates each held load as a parabola.
    ref_x, ref_v = held_recurrence(x0, np.zeros(3), lambda x, v: -K * x, steps)
    np.testing.assert_allclose(xs, ref_x, rtol=0, atol=HOLD_EXACT)
    np.testing.assert_allclose(vs, ref_v, rtol=0, atol=HOLD_EXACT * OMEGA)
    # Called at 0, 1/RATE, 2/RATE, ...: the rate asked for, from the time it was set.
    assert len(calls) == steps * round(DT * RATE) + 1
    np.testing.assert_allclose(calls, H * np.arange(len(calls)), rtol=0, atol=ROUNDING)


def test_a_damping_load_decays_the_speed_exponentially():
    v0 = np.array([0.5, -0.2, 0.3])
    w = free_sphere(velocity=v0)
    w.set_load_function("ball", lambda t, s: (-C * s["velocity"], [0.0, 0.0, 0.0]), RATE)
    steps = round(T_END / DT)
    xs, vs = run(w, steps)
    t = DT * np.arange(1, steps + 1)[:, None]
    decay = np.exp(-C * t / M)
    np.testing.assert_allclose(vs, v0 * decay, rtol=DAMP_DRIFT, atol=0)
    np.testing.assert_allclose(xs, v0 * M / C * (1 - decay), rtol=DAMP_DRIFT, atol=0)
    ref_x, ref_v = held_recurrence(np.zeros(3), v0, lambda x, v: -C * v, steps)
    np.testing.assert_allclose(vs, ref_v, rtol=0, atol=HOLD_EXACT)
    np.testing.assert_allclose(xs, ref_x, rtol=0, atol=HOLD_EXACT)


def test_a_force_at_a_point_turns_the_body_as_tau_t_over_i():
    f = np.array([0.0, 3.0, 0.0])
    arm = np.array([R, 0.0, 0.0])  # at the +x pole: a torque R f about z

    def push(t, s):
        return f, np.zeros(3), s["com"] + arm

    w = free_sphere()
    w.set_load_function("ball", push, 100.0)
    w.step(0.4)
    t = 0.4
    np.testing.assert_allclose(w.angular_velocities()[0], np.cross(arm, f) * t / I,
                               rtol=ROUNDING, atol=0)
    np.testing.assert_allclose(w.velocities()[0], f * t / M, rtol=ROUNDING, atol=0)


def test_an_exception_in_the_load_function_comes_out_of_step_with_the_world_unchanged():
    def failing(t, s):
        if t >= 0.25:
            raise ZeroDivisionError("the controller divided by zero")
        return -K * s["com"], np.zeros(3)

    w = free_sphere([0.1, 0, 0])
    w.set_load_function("ball", failing, RATE)
    w.step(0.2)
    before, t0 = w.states().copy(), w.time
    with pytest.raises(ZeroDivisionError, match="divided by zero") as raised:
        w.step(0.1)
    notes = getattr(raised.value, "__notes__", [])
    assert any('body "ball" at t = 0.25' in n for n in notes), notes
    # The world is as it was before the failed step, bit for bit, and still runs.
    assert w.time == t0
    np.testing.assert_array_equal(w.states(), before)
    w.set_load("ball", force=[1.0, 0, 0])
    w.step(0.1)
    np.testing.assert_allclose(w.velocities()[0], before[0, 7:10] + [0.1 / M, 0, 0],
                               rtol=ROUNDING, atol=ROUNDING)


def test_bad_load_functions_raise_impulse_error_with_the_message():
    w = free_sphere()
    w.add_body("floor", impulse.Shape.box([1, 1, 0.1]), position=[0, 0, -1], fixed=True)
    with pytest.raises(impulse.ImpulseError, match="not callable"):
        w.set_load_function("ball", 3.0, RATE)
    with pytest.raises(impulse.ImpulseError, match='body "nobody"'):
        w.set_load_function("nobody", lambda t, s: (np.zeros(3), np.zeros(3)), RATE)
    with pytest.raises(impulse.ImpulseError, match="rate"):
        w.set_load_function("ball", lambda t, s: (np.zeros(3), np.zeros(3)), 0.0)
    with pytest.raises(impulse.ImpulseError, match="only a dynamic body"):
        w.set_load_function("floor", lambda t, s: (np.zeros(3), np.zeros(3)), RATE)
    # Values that are no load, refused at the first call (when it is set).
    with pytest.raises(impulse.ImpulseError, match=r"returned 'push': expected a tuple"):
        w.set_load_function("ball", lambda t, s: "push", RATE)
    with pytest.raises(impulse.ImpulseError, match="expected 3 values, got 2"):
        w.set_load_function("ball", lambda t, s: ([1.0, 2.0], np.zeros(3)), RATE)
    with pytest.raises(impulse.ImpulseError, match=r"torque\[1\] is NaN"):
        w.set_load_function("ball", lambda t, s: (np.zeros(3), [0, np.nan, 0]), RATE)
    # ... or later, from `step`, the world unchanged.
    w.set_load_function("ball", lambda t, s: ([1.0, 0, 0], [0, 0, 0] if t < 0.05 else None),
                        RATE)
    with pytest.raises(impulse.ImpulseError, match='load function of body "ball"'):
        w.step(0.1)
    assert w.time == 0.0
    # A load function may not call its own world (it would wait for the step's lock).
    with pytest.raises(impulse.ImpulseError, match="cannot call its own world"):
        w.set_load_function("ball", lambda t, s: (w.positions()[0], np.zeros(3)), RATE)
    assert len(w) == 2 and w.time == 0.0


def test_steps_of_two_worlds_with_load_functions_run_in_two_threads():
    # Each step releases the GIL and takes it only to call the load function: two threads
    # stepping two worlds both finish, each as it would alone.
    def make():
        w = free_sphere([0.1, 0, 0])
        w.set_load_function("ball", lambda t, s: (-K * s["com"], np.zeros(3)), RATE)
        return w

    alone = make()
    alone.step(0.5)
    worlds = [make(), make()]
    threads = [threading.Thread(target=w.step, args=(0.5,)) for w in worlds]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for w in worlds:
        np.testing.assert_array_equal(w.states(), alone.states())
