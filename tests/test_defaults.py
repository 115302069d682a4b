"""One place for defaults (gtmodel.defaults): the loop period written once, read from the robot's file."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from gtmodel import defaults as gd
from gtmodel.errors import InputError
from gtmodel.modeling.ocp.collocation_function import WARM_START_OPTIONS
from gtmodel.modeling.ocp.collocation_nlp import IPOPT_DEFAULTS, merge_options
from gtmodel.robots.actuator_dynamics import load_dynamics_models, loop_period

from .conftest import PROBLEMS_DIR, assert_bad_problem, replace_once

PACKAGE = Path(gd.__file__).resolve().parent


@pytest.fixture(autouse=True)
def _reset():
    yield
    gd.reset_defaults()


def _loop_period_literals():
    """(file, line) of every number 0.004 in gtmodel's code (docstrings and comments are text, not numbers)."""
    found = []
    for path in sorted(PACKAGE.rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        skip = set()
        for node in ast.walk(tree):  # an unrelated perturbation of the F1 self-check may stay
            if isinstance(node, ast.Assign) and any(isinstance(t, ast.Name) and "PERTURBATION" in t.id for t in node.targets):
                skip.update(id(n) for n in ast.walk(node.value))
        found += [(path.relative_to(PACKAGE).as_posix(), node.lineno) for node in ast.walk(tree)
                  if isinstance(node, ast.Constant) and node.value == 0.004 and id(node) not in skip]
    return found


def test_the_loop_period_is_written_once():
    assert _loop_period_literals() == [("defaults.py", _line_of("LOOP_PERIOD_S = 0.004"))]


def _line_of(text):
    return next(i for i, line in enumerate((PACKAGE / "defaults.py").read_text().splitlines(), 1) if line.startswith(text))


@pytest.mark.parametrize("source, expected", [(None, gd.LOOP_PERIOD_S), ("L1_dynamics_models", 0.004)])
def test_loop_period_from_the_robot_file_or_the_fallback(source, expected):
    assert loop_period(source) == expected


def test_loop_period_follows_the_data_file(tmp_path):
    text = (PACKAGE / "robots" / "data" / "L1_dynamics_models.toml").read_text().replace("sample_time_s = 0.004", "sample_time_s = 0.002")
    f = tmp_path / "fast.toml"
    f.write_text(text)
    assert loop_period(f) == 0.002 == loop_period(load_dynamics_models(f))


@pytest.mark.parametrize("problem", ["l1_tracking.toml", "l1_ilc.toml"])
def test_loop_period_field_must_match_the_actuator_models(tmp_path, problem):
    """[robot] loop_period is a field of the closed-loop problems, checked against the robot's file."""
    assert "loop_period = 0.004" in (PROBLEMS_DIR / problem).read_text()
    edit = replace_once("loop_period = 0.004", "loop_period = 0.002")
    assert_bad_problem(tmp_path, PROBLEMS_DIR / problem, "period", edit,
                       r"field 'robot\.loop_period': expected the sample time of the actuator models in robot\.dynamics_models \(0\.004 s\)")


def test_reset_restores_every_key_and_refills_option_dicts_in_place():
    gd.defaults["plot.dpi"] = 300
    gd.defaults["ipopt.options"]["mumps_mem_percent"] = 50
    gd.defaults["ipopt.warm_start"].clear()
    gd.defaults["mine"] = 1
    gd.reset_defaults()
    assert gd.defaults["plot.dpi"] == 110 and "mine" not in gd.defaults
    assert IPOPT_DEFAULTS is gd.defaults["ipopt.options"] and IPOPT_DEFAULTS == {"mumps_mem_percent": 20}
    assert WARM_START_OPTIONS is gd.defaults["ipopt.warm_start"] and WARM_START_OPTIONS["mu_init"] == 1e-4


def test_solver_options_are_read_when_called():
    assert merge_options(False, None)["ipopt"]["max_iter"] == 3000
    gd.defaults["nlp.max_iter"] = 7
    gd.defaults["ipopt.options"]["mumps_mem_percent"] = 30
    inner = merge_options(False, {"tol": 1e-6})["ipopt"]
    assert (inner["max_iter"], inner["tol"], inner["mumps_mem_percent"]) == (7, 1e-6, 30)
    assert "mumps_mem_percent" not in merge_options(False, None, plugin="fatrop")["fatrop"]


@pytest.mark.parametrize("key, value, expected", [("plot.dpi", None, 110), ("plot.dpi", 72, 72), ("loop.period", None, 0.004)])
def test_get(key, value, expected):
    assert gd.get(key, value) == expected


def test_get_unknown_key():
    with pytest.raises(InputError, match="key: expected one of"):
        gd.get("plot.colour")
