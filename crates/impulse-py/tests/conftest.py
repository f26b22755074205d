"""Shared fixtures: the workspace root and the `impulse` program, the independent reference
most tests compare with (the CLI is built by `cargo test --workspace` before these run)."""

import json
import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[3]


def _find_cli():
    env = os.environ.get("IMPULSE_CLI")
    if env:
        return pathlib.Path(env)
    for profile in ("debug", "release"):
        exe = ROOT / "target" / profile / "impulse"
        if exe.is_file():
            return exe
    return None


@pytest.fixture(scope="session")
def root():
    """The workspace root (fixtures/ is under it)."""
    return ROOT


@pytest.fixture(scope="session")
def cli():
    """Runs `impulse ARGS...` and returns its stdout; fails the test on a non-zero exit."""
    exe = _find_cli()
    if exe is None:
        pytest.fail(
            "the `impulse` program is not built: run `cargo build -p impulse-cli` "
            "(or set IMPULSE_CLI to its path)"
        )

    def run(*args):
        done = subprocess.run(
            [str(exe), *map(str, args)], cwd=ROOT, capture_output=True, text=True
        )
        if done.returncode != 0:
            pytest.fail(f"impulse {' '.join(map(str, args))} failed: {done.stderr}")
        return done.stdout

    run.json = lambda *args: json.loads(run(*args))
    return run


def write_obj(path, vertices, faces):
    """A Wavefront OBJ of the mesh, numbers written to round-trip exactly."""
    with open(path, "w") as f:
        for v in vertices:
            f.write("v {!r} {!r} {!r}\n".format(*map(float, v)))
        for face in faces:
            f.write("f " + " ".join(str(int(i) + 1) for i in face) + "\n")
