"""The Python examples of the READMEs run as written (from the workspace root)."""

import os
import re

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
