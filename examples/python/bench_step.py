"""The cost of stepping from Python against the same steps in Rust.

A 100-body world (a 10 × 10 grid of boxes dropped on a floor, switching contact model) is
stepped 1000 times by 1 ms, every body's state read once per step as one (n, 16) array, once
through `impulse` and once by the Rust example `step_bench` on the same scene file; both print
their loop's wall time and a checksum of the trajectory, which must agree.

    cargo build --release -p impulse-sim --example step_bench
    python examples/python/bench_step.py [--repeat 3]
"""

import argparse
import json
import pathlib
import subprocess
import tempfile
import time

import numpy as np

import impulse

ROOT = pathlib.Path(__file__).resolve().parents[2]


def scene(n_side=10):
    bodies = ['Body(name: "floor", shape: Box(half_extents: (5.0, 5.0, 0.1)), '
              "position: (0.0, 0.0, -0.1), motion: Fixed)"]
    rng = np.random.default_rng(0)
    for i in range(n_side):
        for j in range(n_side):
            x, y = 0.3 * (i - n_side / 2), 0.3 * (j - n_side / 2)
            z = 0.06 + 0.2 * rng.random()
            ax = rng.normal(size=3)
            bodies.append(
                f'Body(name: "b{i}_{j}", shape: Box(half_extents: (0.05, 0.04, 0.03)), '
                f"position: ({x!r}, {y!r}, {z!r}), "
                f"rotation: AxisAngle(axis: ({ax[0]!r}, {ax[1]!r}, {ax[2]!r}), degrees: 30.0), "
                "mass: Density(700.0))"
            )
    return ("Scene(gravity: (0.0, 0.0, -9.81), collision_epsilon: 1e-4, "
            f"bodies: [{', '.join(bodies)}])")


def python_loop(path, steps, dt):
    w = impulse.World.from_scene(path)
    checksum = 0.0
    start = time.perf_counter()
    for _ in range(steps):
        w.step(dt)
        s = w.states()
        checksum += s[:, 2].sum()
    return time.perf_counter() - start, checksum, len(w)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--steps", type=int, default=1000)
    ap.add_argument("--dt", type=float, default=1e-3)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    exe = ROOT / "target/release/examples/step_bench"
    with tempfile.TemporaryDirectory() as d:
        path = pathlib.Path(d) / "grid.ron"
        path.write_text(scene())
        for k in range(args.repeat):
            rust = json.loads(subprocess.run(
                [exe, path, str(args.steps), str(args.dt)], check=True, capture_output=True,
                text=True).stdout)
            py_wall, py_sum, n = python_loop(path, args.steps, args.dt)
            assert rust["checksum"] == py_sum, (rust["checksum"], py_sum)
            print(f"run {k}: {n} bodies, {args.steps} steps of {args.dt} s: "
                  f"Rust {rust['wall']:.3f} s, Python {py_wall:.3f} s, "
                  f"ratio {py_wall / rust['wall']:.3f}")


if __name__ == "__main__":
    main()
