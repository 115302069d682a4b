"""Shared test configuration: headless matplotlib, paths of shipped files."""

from __future__ import annotations

import atexit
import contextlib
import importlib.util
import os
import shutil
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path

import pytest

from gtmodel.defaults import defaults

os.environ.setdefault("MPLBACKEND", "Agg")
# codegen's planned references (gtmodel.problems.plan_cache): a folder of this session (each xdist worker its own,
# inherited by the CLI's subprocesses), never the user's ~/.cache; shared by the session's tests (a test of the cache
# sets its own), removed at exit. The compiled libraries stay in gtmodel's cache (GTMODEL_CACHE_DIR or ~/.cache).
os.environ["GTMODEL_PLAN_CACHE_DIR"] = tempfile.mkdtemp(prefix="gtmodel-plans-")
atexit.register(shutil.rmtree, os.environ["GTMODEL_PLAN_CACHE_DIR"], ignore_errors=True)

REPO = Path(__file__).resolve().parents[1]
PROBLEMS_DIR = REPO / "problems"
NOTEBOOKS_DIR = REPO / "notebooks"
#: The reference figures (copies of shared/reference/*.toml, see tests/reference/README.md).
SHARED_REFERENCE = REPO / "tests" / "reference"


@contextlib.contextmanager
def verification_tolerance(value: float) -> Iterator[None]:
    """Solve with another default verification tolerance (``defaults["ocp.verification_tolerance"]``).

    For tests that solve on coarse meshes to be fast and test something else than
    accuracy: the L1 motions on 12 elements deviate 1-6 % from their simulation, which the
    default 1e-2 rightly flags ``check_failed``.
    """
    old = defaults["ocp.verification_tolerance"]
    defaults["ocp.verification_tolerance"] = value
    try:
        yield
    finally:
        defaults["ocp.verification_tolerance"] = old


@contextlib.contextmanager
def benchmark_module(name: str) -> Iterator[object]:
    """``benchmarks/<name>.py`` as a module, its folder on ``sys.path`` meanwhile (for the benchmarks it imports)."""
    folder = REPO / "benchmarks"
    sys.path.insert(0, str(folder))
    try:
        spec = importlib.util.spec_from_file_location(name, folder / f"{name}.py")
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        yield module
    finally:
        sys.path.remove(str(folder))


def replace_once(old: str, new: str):
    """An edit of a shipped problem file for a table of bad inputs (fails if ``old`` is gone)."""

    def edit(text: str) -> str:
        assert old in text, f"test table out of date: {old!r} is not in the file"
        return text.replace(old, new, 1)

    return edit


@pytest.fixture(scope="session")
def repo() -> Path:
    return REPO


def solve_through_cli(path: Path, out: Path, *options: str) -> tuple[int, dict]:
    """``gtmodel solve <path> --out <out> --quiet [options]``: exit code and ``summary.json``."""
    import json

    from gtmodel.cli import main

    code = main(["solve", str(path), "--out", str(out), "--quiet", *options])
    return code, json.loads((out / "summary.json").read_text())


def assert_bad_problem(tmp_path: Path, base: Path, case: str, edit, match: str):
    """Write ``edit(base)`` as ``<case>.toml`` and check that loading it raises one
    ProblemError matching ``match`` whose first line names the file; returns the error."""
    from gtmodel.errors import ProblemError
    from gtmodel.problems import load_problem

    f = tmp_path / f"{case}.toml"
    f.write_text(edit(base.read_text()))
    with pytest.raises(ProblemError, match=match) as info:
        load_problem(f)
    assert str(f) in str(info.value).splitlines()[0]
    return info.value


def assert_bad_problem_through_cli(tmp_path: Path, capsys, text: str, match: str) -> None:
    """A problem file ``text`` given to ``gtmodel solve``: exit code EXIT_BAD_INPUT, no
    traceback, a message matching ``match`` on stderr, ``status = "error"`` in the summary."""
    import re

    from gtmodel.cli import EXIT_BAD_INPUT

    f = tmp_path / "bad.toml"
    f.write_text(text)
    code, summary = solve_through_cli(f, tmp_path / "out")
    err = capsys.readouterr().err
    assert code == EXIT_BAD_INPUT and "Traceback" not in err, err
    assert re.search(match, err), err
    assert summary["status"] == "invalid_input"
