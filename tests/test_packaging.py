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


def _package_data_patterns() -> list[str]:
    """``[tool.setuptools.package-data]`` as paths under the repository, e.g. ``gtmodel/robots/data/*.toml``."""
    table = PYPROJECT["tool"]["setuptools"]["package-data"]
    return [f"{package.replace('.', '/')}/{pattern}" for package, patterns in table.items() for pattern in patterns]


_DATA_FILES = sorted(p.relative_to(REPO).as_posix() for p in (REPO / "gtmodel").rglob("*")
                     if p.is_file() and p.suffix not in {".py", ".pyc"} and "__pycache__" not in p.parts)


@pytest.mark.parametrize("path", _DATA_FILES)
def test_every_file_the_package_reads_is_package_data(path):
    """A data file under gtmodel/ that no package-data pattern names is missing from the wheel: the
    installed package would not find it (issue 44: the ILC thesis table read from tests/)."""
    from fnmatch import fnmatchcase

    assert any(fnmatchcase(path, pattern) for pattern in _package_data_patterns()), (
        f"{path} is not package data: add it to [tool.setuptools.package-data] in pyproject.toml")


def test_no_module_reads_the_checkout_outside_the_package():
    """Run-time files are package data: no module of gtmodel/ builds a path to the repository's
    tests/ folder (the fidelity report, a maintainer's tool that rewrites docs/, reads the checkout
    by design)."""
    offenders = [p.relative_to(REPO).as_posix() for p in (REPO / "gtmodel").rglob("*.py")
                 if re.search(r"""["']tests["']\s*/|/\s*["']tests["']""", p.read_text(encoding="utf-8"))]
    assert offenders == []


#: What a package index shows of the wheel (issue 67, item 6): each must be filled in pyproject.toml.
METADATA = ("description", "readme", "license", "authors", "keywords", "classifiers", "requires-python")


def test_the_wheel_metadata_is_complete():
    project = PYPROJECT["project"]
    assert [key for key in METADATA if not project.get(key)] == []
    assert (REPO / project["readme"]).is_file() and (REPO / "LICENSE").read_text().startswith(f"{project['license']['text']} License")


def test_the_classifiers_are_trove_names_that_agree_with_the_project():
    classifiers = PYPROJECT["project"]["classifiers"]
    assert [c for c in classifiers if not re.fullmatch(r"[A-Z][A-Za-z ]+( :: [A-Za-z0-9+/()., -]+)+", c)] == []
    assert "License :: OSI Approved :: MIT License" in classifiers
    minimum = PYPROJECT["project"]["requires-python"].removeprefix(">=")
    assert f"Programming Language :: Python :: {minimum}" in classifiers
