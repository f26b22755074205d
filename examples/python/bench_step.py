"""The cost of stepping from Python against the same steps in Rust.

A 100-body world (a 10 × 10 grid of boxes dropped on a floor, switching contact model) is
stepped 1000 times by 1 ms, every body's state read once per step as one (n, 16) array, once
through `impulse` and once by the Rust example `step_bench` on the same scene file; both print
their loop's wall time and a checksum of the trajectory (the sum of every height read),
which must agree to rounding.

    cargo build --release -p impulse-sim --example step_bench
    python examples/python/bench_step.py [--repeat 7]
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
            z = 0.06 + 0.2 * float(rng.random())
            ax = [float(a) for a in rng.normal(size=3)]
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
    return time.perf_counter() - start, checksum, w


def overhead(w, calls=20000):
    """The binding's own cost per call, measured on calls that do no simulation: step(0)
    (argument checks, the GIL released and taken back, the report dict) and states() (n
    rows copied into a new array), on the world the loop left (as the Rust side measures)."""
    best = {}
    for name, call in [("step(0)", lambda: w.step(0.0)), ("states()", w.states)]:
        for _ in range(3):
            start = time.perf_counter()
            for _ in range(calls):
                call()
            per = (time.perf_counter() - start) / calls
            best[name] = min(best.get(name, per), per)
    return best


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--steps", type=int, default=1000)
    ap.add_argument("--dt", type=float, default=1e-3)
    ap.add_argument("--repeat", type=int, default=7)
    args = ap.parse_args()
    exe = ROOT / "target/release/examples/step_bench"
    with tempfile.TemporaryDirectory() as d:
        path = pathlib.Path(d) / "grid.ron"
        path.write_text(scene())
        best_rust = best_py = float("inf")
        for k in range(args.repeat):
            rust = json.loads(subprocess.run(
                [exe, path, str(args.steps), str(args.dt)], check=True, capture_output=True,
                text=True).stdout)
            py_wall, py_sum, world = python_loop(path, args.steps, args.dt)
            n = len(world)
            # The same trajectory: the sums differ only by summation order (NumPy's pairwise).
            assert abs(rust["checksum"] - py_sum) <= 1e-12 * abs(py_sum), (rust, py_sum)
            print(f"run {k}: {n} bodies, {args.steps} steps of {args.dt} s: "
                  f"Rust {rust['wall']:.3f} s, Python {py_wall:.3f} s, "
                  f"ratio {py_wall / rust['wall']:.3f}")
            best_rust, best_py = min(best_rust, rust["wall"]), min(best_py, py_wall)
        cost = overhead(world)
        print(f"step(0) per call: Rust {1e6 * rust['step0']:.1f} µs, Python "
              f"{1e6 * cost['step(0)']:.1f} µs; states() {1e6 * cost['states()']:.1f} µs")
        # The fastest of each: the run least disturbed by other work on the machine.
        print(f"best of {args.repeat}: Rust {best_rust:.3f} s, Python {best_py:.3f} s, "
              f"ratio {best_py / best_rust:.3f} "
              f"({1e6 * (best_py - best_rust) / args.steps:+.1f} µs per step)")


if __name__ == "__main__":
    main()
