"""The declared dependency bounds are the tested ones: pyproject.toml's lower bounds equal the pins
of .ci/constraints-minimum.txt, which .ci/run installs into a fresh environment and tests."""

from __future__ import annotations

import re
import tomllib

import pytest

from .conftest import REPO

PYPROJECT = tomllib.loads((REPO / "pyproject.toml").read_text())
CI = (REPO / ".ci" / "run").read_text()


def _pins() -> dict[str, str]:
    lines = (REPO / ".ci" / "constraints-minimum.txt").read_text().splitlines()
    pairs = [ln.split("==") for ln in lines if ln.strip() and not ln.startswith("#")]
    return {name.strip().lower(): version.strip() for name, version in pairs}


def _lower_bounds(requirements: list[str]) -> dict[str, str]:
    bounds = {}
    for req in requirements:
        m = re.fullmatch(r"([A-Za-z0-9_.-]+)(?:\[[^\]]*\])?>=([0-9.]+)", req)
        assert m, f"pyproject.toml: {req!r} has no plain '>=' lower bound"
        bounds[m.group(1).lower()] = m.group(2)
    return bounds


def _same_release(a: str, b: str) -> bool:
    pad = lambda v: [int(x) for x in v.split(".")] + [0] * (3 - len(v.split(".")))  # noqa: E731
    return pad(a) == pad(b)


@pytest.mark.parametrize("name, bound", sorted(_lower_bounds(PYPROJECT["project"]["dependencies"]).items()))
def test_every_runtime_lower_bound_is_pinned_in_the_minimum_environment(name, bound):
    pins = _pins()
    assert name in pins, f".ci/constraints-minimum.txt does not pin {name} (pyproject.toml: >={bound})"
    assert _same_release(pins[name], bound), f"{name}: pyproject.toml says >={bound}, CI tests {pins[name]}"


def test_ci_makes_fresh_environments_for_the_newest_and_the_minimum_versions():
    assert CI.count(" -m venv ") == 2
    assert "pip install -c .ci/constraints-minimum.txt \".[test]\"" in CI
