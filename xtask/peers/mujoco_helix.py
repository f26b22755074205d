#!/usr/bin/env python3
"""MuJoCo's step time on the FORK⁻¹S helix, for the same-machine ratio in docs/forks.md
("Against MuJoCo").

Builds the helix of `impulse_reduced::scenes::helix(n)` (fixtures/mechanisms/helix-<n>.ron) as
MJCF: link i is a 0.1 kg point-like rod at p_i = (0.2 cos a_i, 0.2 sin a_i, 0.05 i),
a_i = 2π i / 8, with the diagonal inertia of `scenes::rod` (m l²/12, m l²/12, m l²/120 + 1e-6,
world-aligned, centre of mass at the link origin); joint i is a ball at p_{i-1} with stiffness
1/0.001 N·m/rad and damping 0.05 N·m·s/rad on each of its three directions; fixed base at p_0;
no gravity; a held 1 N force along x on the last link (the Table 1 bench's `external[0] = 1`).
Steps it at h = 1 ms and prints µs per step, the median of several timed runs.

MuJoCo's joint springs are explicit in every integrator, and a link's fastest mode here
(≈ √(1000 / 2.2e-4) ≈ 2100 rad/s) makes ω·h > 2 at 1 ms: the helix diverges within ~10 steps and
MuJoCo resets it (reported below; the cost of a step does not depend on the state: both
factorisations of the dense 3n × 3n chain mass matrix are O(n³)). `--timestep 0.0005` is
stable; the script then also prints the cost per simulated millisecond. MuJoCo writes its
warnings to MUJOCO_LOG.TXT in the working directory.

Not run by CI. Needs `pip install mujoco` (tested with 4.0.0). Usage:

    python3 xtask/peers/mujoco_helix.py [--links 400] [--steps 20] [--runs 5]
        [--integrator implicitfast]

Compare with `cargo bench -p impulse-reduced --bench step -- helix-400/N=1` on the same machine
(run both with `nice`, one after the other, on an otherwise quiet machine).
"""

import argparse
import math
import statistics
import sys
import time

import mujoco
import numpy as np

# scenes.rs constants (kept in step with crates/impulse-reduced/src/scenes.rs).
RADIUS, RISE, PER_TURN = 0.2, 0.05, 8.0
LINK_MASS = 0.1
COMPLIANCE = 0.001  # rad/(N·m)
DAMPING = 0.05  # N·m·s/rad
TIMESTEP = 1e-3  # s
LOAD = 1.0  # N along x on the end effector


def at(i):
    a = 2.0 * math.pi * i / PER_TURN
    return np.array([RADIUS * math.cos(a), RADIUS * math.sin(a), RISE * i])


def helix_mjcf(n, integrator):
    step = math.sqrt((2.0 * RADIUS * math.sin(math.pi / PER_TURN)) ** 2 + RISE * RISE)
    it = LINK_MASS * step * step / 12.0
    inertia = f"{it!r} {it!r} {it * 0.1 + 1e-6!r}"
    fmt = lambda v: " ".join(repr(float(x)) for x in v)  # noqa: E731
    body = []
    for i in range(1, n + 1):
        rel = at(i) - at(i - 1)  # body origin in the parent's frame (all frames world-aligned)
        body.append(
            f'<body name="l{i}" pos="{fmt(rel)}">'
            f'<inertial pos="0 0 0" mass="{LINK_MASS!r}" diaginertia="{inertia}"/>'
            f'<joint name="j{i}" type="ball" pos="{fmt(-rel)}" stiffness="{1.0 / COMPLIANCE!r}" '
            f'damping="{DAMPING!r}"/>'
        )
    body.append("</body>" * n)
    return f"""<mujoco model="helix-{n}">
  <option timestep="{TIMESTEP!r}" gravity="0 0 0" integrator="{integrator}"/>
  <worldbody>
    <body name="base" pos="{fmt(at(0))}">
      {"".join(body)}
    </body>
  </worldbody>
</mujoco>"""


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--links", type=int, default=400)
    ap.add_argument("--steps", type=int, default=20, help="steps per timed run")
    ap.add_argument("--runs", type=int, default=5, help="timed runs (the median is printed)")
    ap.add_argument("--timestep", type=float, default=TIMESTEP, help="step (s)")
    ap.add_argument(
        "--integrator",
        default="implicitfast",
        choices=["Euler", "implicitfast", "implicit", "RK4"],
        help="MuJoCo integrator (implicitfast: damping implicit, the closest to our backward Euler)",
    )
    args = ap.parse_args()
    model = mujoco.MjModel.from_xml_string(helix_mjcf(args.links, args.integrator))
    model.opt.timestep = args.timestep
    data = mujoco.MjData(model)
    assert model.nv == 3 * args.links, model.nv
    mujoco.mj_forward(model, data)
    tip = model.body(f"l{args.links}").id
    # Geometry check against scenes::helix: every link origin at p_i, total mass n · 0.1 kg.
    worst = max(
        np.abs(data.xpos[model.body(f"l{i}").id] - at(i)).max() for i in range(1, args.links + 1)
    )
    assert worst < 1e-9, worst
    assert abs(model.body_subtreemass[1] - LINK_MASS * args.links) < 1e-9
    data.xfrc_applied[tip, 0] = LOAD
    start = data.xpos[tip].copy()
    # One warm-up run, then the timed runs; the state carries on (a loaded, vibrating helix).
    mujoco.mj_step(model, data, nstep=args.steps)
    per_step = []
    for _ in range(args.runs):
        t = time.perf_counter()
        mujoco.mj_step(model, data, nstep=args.steps)
        per_step.append((time.perf_counter() - t) / args.steps * 1e6)
    moved = np.linalg.norm(data.xpos[tip] - start)
    resets = data.warning[mujoco.mjtWarning.mjWARN_BADQACC].number
    median = statistics.median(per_step)
    h_ms = args.timestep * 1e3
    print(
        f"mujoco {mujoco.__version__} helix-{args.links} ({args.integrator}, h = {h_ms:g} ms, "
        f"nv = {model.nv}): median {median:.0f} µs/step, {median / h_ms:.0f} µs per simulated ms "
        f"(min {min(per_step):.0f}, max {max(per_step):.0f} µs/step; {args.runs} runs of "
        f"{args.steps} steps); tip moved {moved:.3g} m by t = {data.time:.4f} s; "
        + (f"UNSTABLE: MuJoCo reset the state {resets} times" if resets else "stable")
    )
    if resets:
        sys.exit(2)


if __name__ == "__main__":
    main()
