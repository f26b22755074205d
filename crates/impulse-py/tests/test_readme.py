"""The Python examples of the READMEs run as written (from the workspace root), and the
version the README's install check prints is the workspace's."""

import importlib.metadata
import os
import re
import subprocess
import sys

import pytest


def python_blocks(path):
    return re.findall(r"```python\n(.*?)```", path.read_text(), flags=re.S)


@pytest.mark.parametrize("readme", ["README.md", "crates/impulse-py/README.md"])
def test_the_readme_examples_run(root, readme):
    blocks = python_blocks(root / readme)
    assert blocks, f"{readme} has no python example"
    cwd = os.getcwd()
    os.chdir(root)
    try:
        for code in blocks:
            scope = {}
            exec(compile(code, readme, "exec"), scope)
    finally:
        os.chdir(cwd)
    if readme == "README.md":
        # The example's study: 400 drops, every drop's outcome merged back.
        assert scope["impulse"].pose_summary(scope["part"], scope["study"])["drops"] == 400
        # The bowling example's 2 + 2 throws, merged from its two shards; 40 cm in 5 mm bins.
        assert scope["bins"]["mean"].shape == (80, 2)
        assert scope["bins"]["throws"] == 4


def test_the_install_check_prints_the_workspace_version(root):
    # The README's line after `pip install`, run as written.
    line = re.search(r'^(python -c "import impulse; print\(impulse.__version__\)")$',
                     (root / "README.md").read_text(), flags=re.M)
    assert line, "README.md has no install check line"
    code = line.group(1).split('"')[1]
    printed = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True,
                             text=True).stdout.strip()
    # The workspace's version, read from Cargo.toml, and the installed distribution's.
    cargo = re.search(r'^\[workspace\.package\][^\[]*?^version = "([^"]+)"',
                      (root / "Cargo.toml").read_text(), flags=re.M | re.S)
    assert printed == cargo.group(1) == importlib.metadata.version("impulse")
