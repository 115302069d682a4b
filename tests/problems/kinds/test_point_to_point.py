"""Kind ``point_to_point``: the shipped files' declarations, the result folder and bad input.

The table of broken files shared with the command-line tests is ``tests/bad_problems.py``;
the cases here are the fuzzing reproducers (values of the wrong type, non-finite or
physically absurd), each a load-time error naming its field.
"""

from __future__ import annotations

import time
import tomllib

import numpy as np
import pytest

from tests.conftest import verification_tolerance
from gtmodel.errors import ProblemError
from gtmodel.problems import get_kind, load_problem, run_problem
from gtmodel.problems.kinds.motion_common import AT_BOUND_RTOL
from gtmodel.status import Status
from gtmodel.trajectory import PointToPoint

from ...conftest import PROBLEMS_DIR, replace_once as _edit

SHIPPED = ["l1_time_optimal.toml", "l1_energy_w0_001.toml", "l1_energy_w0_01.toml"]
BASE = PROBLEMS_DIR / "l1_energy_w0_01.toml"
#: Longest accepted time to reject a bad file [s] (bad input is found before any solve).
REJECT_SECONDS = 5.0
#: A coarse mesh: the solve takes about a second.
COARSE = _edit("elements = 50 ", "elements = 10 ")


@pytest.mark.parametrize("name", SHIPPED)
def test_shipped_file_declares_its_settings(name):
    path = PROBLEMS_DIR / name
    data = tomllib.loads(path.read_text())
    d = load_problem(path).declaration
    assert isinstance(d, PointToPoint)
    assert d.named_parameters == data["parameters"]
    assert d.w == data["parameters"]["w"]
    np.testing.assert_array_equal(d.force_limit, data["limits"]["force"])
    assert d.final_time_bounds == tuple(data["optimization"]["final_time"]["bounds"])
    assert (d.elements, d.points, d.scheme) == (50, 3, "radau")


@pytest.fixture(autouse=True, scope="module")
def _coarse_mesh_tolerance():
    """The solves here use 12 elements, whose L1 motions deviate 1-6 % from their simulation
    (check_failed at the default tolerance 1e-2): these tests are about other things."""
    with verification_tolerance(0.1):
        yield


@pytest.fixture(scope="module")
def coarse(tmp_path_factory):
    folder = tmp_path_factory.mktemp("p2p")
    f = folder / "coarse.toml"
    f.write_text(COARSE(BASE.read_text()))
    return run_problem(f, folder / "out", plots=True), folder / "out"


def test_result_folder_of_a_solve(coarse):
    outcome, out = coarse
    assert outcome.status == Status.OPTIMAL
    ver = outcome.summary["verification"]  # verified by simulation, within the coarse tolerance
    assert ver["passed"] and ver["tolerance"] == 0.1 and 0 < ver["max_scaled_deviation"] < 0.1
    files = {"summary.json", "trajectory.csv", "trajectory.h", "tcp_path.png", "forces.png"}
    assert set(outcome.summary["files"]) == files == {p.name for p in out.iterdir()}


def test_summary_times_the_phases_of_a_model_ocp(coarse):
    """The time line of a point-to-point solve has the phases of a model's OCP (build, guess, solve,
    verification; CPU and wall), the solve the solver's own figure (second record: the summary's solve_time_s)."""
    outcome, _ = coarse
    timing = outcome.summary["timing"]
    assert {"load", "build", "guess", "solve", "verification", "writing", "total"} <= set(timing)
    assert all(timing[p]["cpu_s"] > 0 and timing[p]["wall_s"] > 0 for p in ("build", "solve", "verification"))
    assert timing["solve"]["wall_s"] == pytest.approx(outcome.summary["solve_time_s"], rel=1e-3, abs=1e-3)


def test_force_figures_are_those_of_the_csv(coarse):
    outcome, out = coarse
    header = (out / "trajectory.csv").read_text().splitlines()[0].split(",")
    data = np.loadtxt(out / "trajectory.csv", delimiter=",", skiprows=1)
    tau = np.abs(data[:, [header.index(f"tau{i}") for i in (1, 2, 3)]])
    limit = np.array(outcome.summary["force_limit_N"])
    np.testing.assert_allclose(outcome.summary["max_force_ratio"], tau.max(axis=0) / limit, rtol=1e-8)
    np.testing.assert_allclose(outcome.summary["fraction_at_force_bound"], (tau >= (1 - AT_BOUND_RTOL) * limit).mean(axis=0), atol=2 / len(tau))


def test_study_overlay_writes_the_two_plots(coarse, tmp_path):
    outcome, _ = coarse
    files = get_kind("point_to_point").overlay({"a": outcome.solution, "b": outcome.solution}, tmp_path)
    assert files == ["overlay_forces.png", "overlay_tcp.png"]


FORCE = "force = [450.0, 450.0, 450.0]"
BAD = [
    ("force_huge", _edit(FORCE, "force = [450.0, 1e308, 450.0]"), r"field 'limits\.force': expected numbers of magnitude <= 1e\+07 N"),
    ("force_nan", _edit(FORCE, "force = [450.0, nan, 450.0]"), r"field 'limits\.force': expected a list of 3 finite numbers"),
    ("force_zero", _edit(FORCE, "force = [450.0, 0.0, 450.0]"), r"field 'limits\.force': expected 3 positive numbers"),
    ("force_empty", _edit(FORCE, "force = []"), r"field 'limits\.force': expected a list of 3 finite numbers"),
    ("force_bool", _edit(FORCE, "force = true"), r"field 'limits\.force': expected a list of 3 finite numbers"),
    ("start_inf", _edit("start = [-0.20, 2.75, -0.40]", "start = [-0.20, inf, -0.40]"), r"field 'motion\.start': expected a list of 3 finite numbers"),
    ("start_huge", _edit("start = [-0.20, 2.75, -0.40]", "start = [-0.20, 1e308, -0.40]"), r"field 'motion\.start': expected numbers of magnitude <= 1000 m"),
    ("configuration_bool", _edit("configuration = 0 ", "configuration = true "), r"field 'robot\.configuration': expected an integer in 0\.\.7"),
    ("friction_width_string", _edit("friction_width = 0.01 ", 'friction_width = "abc" '), r"field 'robot\.friction_width': expected a finite number"),
    ("friction_width_negative", _edit("friction_width = 0.01 ", "friction_width = -1.0 "), r"field 'robot\.friction_width': expected a positive number"),
    ("weight_nan", _edit("w = 0.01 ", "w = nan "), r"field 'parameters\.w': expected a finite number"),
    ("parameter_list", _edit("w = 0.01 ", "w = [] "), r"field 'parameters\.w': expected a finite number"),
    ("objective_empty", _edit('objective = "final_time', 'objective = "" # "final_time'), r"field 'optimization\.objective': expected a non-empty string"),
    ("constraints_number", _edit("[optimization.final_time]", "constraints = 5\n\n[optimization.final_time]"), r"field 'optimization\.constraints': expected a list of strings"),
    ("free_string", _edit("free = true", 'free = "yes"'), r"field 'optimization\.final_time\.free': expected true or false"),
    ("bounds_huge", _edit("bounds = [0.05, 10.0]", "bounds = [0.05, 1e308]"), r"field 'optimization\.final_time\.bounds': expected numbers of magnitude <= 10000 s"),
    ("bounds_wrong_length", _edit("bounds = [0.05, 10.0]", "bounds = [0.05]"), r"field 'optimization\.final_time\.bounds': expected a list of 2 finite numbers"),
    ("guess_outside_bounds", _edit("initial_guess = 1.0 ", "initial_guess = 20.0 "), r"field 'optimization\.final_time\.initial_guess': expected a time within"),
    ("guess_file_missing", _edit('method = "trapezoid"', 'method = "file"\nfile = "nope.csv"'), r"field 'initial_guess\.file'"),
    ("elements_zero", _edit("elements = 50 ", "elements = 0 "), r"field 'collocation\.elements': expected an integer in 1\.\.10000"),
    ("elements_huge", _edit("elements = 50 ", "elements = 100000000 "), r"field 'collocation\.elements': expected an integer in 1\.\.10000"),
    ("tol_inf", _edit("tol = 1e-8", "tol = inf"), r"field 'solver\.tol': expected a finite number"),
    ("max_iter_float", _edit("max_iter = 3000", "max_iter = 3000.0"), r"field 'solver\.max_iter': expected an integer in 1\.\."),
    ("refine_tolerance_above_1", _edit("[solver]", "[transcription]\nrefine = true\ntolerance = 2.0\n\n[solver]"), r"field 'transcription\.tolerance': expected"),
    ("refine_string", _edit("[solver]", '[transcription]\nrefine = "yes"\n\n[solver]'), r"field 'transcription\.refine': expected true or false"),
    ("refine_max_passes_zero", _edit("[solver]", "[transcription]\nmax_passes = 0\n\n[solver]"), r"field 'transcription\.max_passes': expected an integer in 1\.\.100"),
    ("kind_list", _edit('kind = "point_to_point"', "kind = []"), r"field 'kind': expected one of"),
]


@pytest.mark.parametrize("case, edit, match", BAD, ids=[c[0] for c in BAD])
def test_bad_point_to_point_problem(tmp_path, case, edit, match):
    f = tmp_path / f"{case}.toml"
    f.write_text(edit(BASE.read_text()))
    start = time.perf_counter()
    with pytest.raises(ProblemError, match=match) as info:
        load_problem(f)
    assert str(f) in str(info.value).splitlines()[0]
    assert time.perf_counter() - start < REJECT_SECONDS


@pytest.mark.parametrize("content", [b"", b"\xff\xfe kind = 1"], ids=["empty", "not_utf8"])
def test_empty_or_undecodable_file(tmp_path, content):
    f = tmp_path / "broken.toml"
    f.write_bytes(content)
    with pytest.raises(ProblemError, match=str(f)):
        load_problem(f)
