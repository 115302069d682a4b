"""The README stays true: its Python example runs, its set-up commands match .ci/run."""

from __future__ import annotations

import re

import pytest

from .conftest import REPO

README = (REPO / "README.md").read_text()


PYTHON_BLOCKS = re.findall(r"```python\n(.*?)```", README, flags=re.S)


def test_readme_has_a_python_example():
    assert PYTHON_BLOCKS


@pytest.mark.parametrize("code", PYTHON_BLOCKS, ids=[f"block{i}" for i in range(len(PYTHON_BLOCKS))])
def test_python_examples_run(code):
    exec(compile(code, "README.md", "exec"), {})


def test_ci_runs_the_readme_test_command():
    commands = re.findall(r"```bash\n(.*?)```", README, flags=re.S)[0]
    test_command = [line for line in commands.splitlines() if "pytest" in line]
    assert len(test_command) == 1
    ci = (REPO / ".ci" / "run").read_text()
    assert test_command[0].strip() in ci.splitlines()


def test_quick_start_command_names_a_shipped_problem():
    commands = re.findall(r"```bash\n(.*?)```", README, flags=re.S)[0]
    solve = re.search(r"gtmodel solve (\S+)", commands)
    assert solve and (REPO / solve.group(1)).is_file()


def test_ci_runs_the_slow_tests_after_the_readme_command():
    """The slow-marked tests are left out of the default run; CI runs them after it."""
    lines = [ln.strip() for ln in (REPO / ".ci" / "run").read_text().splitlines()]
    readme_line = next(i for i, ln in enumerate(lines) if "pytest" in ln)
    assert "python -m pytest -m slow" in lines[readme_line + 1 :]
