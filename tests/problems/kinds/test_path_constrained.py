"""Kind ``path_constrained``: the shipped problem end to end, the study overlay and bad input.

Independent references: the path-constrained optimum of the shipped problem is recomputed
by the IPOPT transcription of the same gridded problem (a second solver), and the thesis'
shape (ch. 3.5): on the straight line one motor is at its force bound most of the time.
"""

from __future__ import annotations

import time

import numpy as np
import pytest

from gtmodel.errors import ProblemError
from gtmodel.problems import get_kind, load_problem, run_problem, solve_problem
from gtmodel.problems.kinds.path_constrained import MAX_GRID_POINTS, PathConstrainedDeclaration, path_trajectory_columns
from gtmodel.status import Status
from gtmodel.trajectory import PathConstrainedProblem

from ...conftest import PROBLEMS_DIR, replace_once as _edit

PATH_FILE = PROBLEMS_DIR / "l1_path_constrained.toml"
#: Duration of the reachability solution vs IPOPT on the same grid, relative.
DURATION_RTOL = 1e-6
#: "Most of the motion": fraction of 4 ms samples at the bound for the limiting motor.
AT_BOUND_FRACTION = 0.75
#: Forces between grid points may exceed the limit (constraints hold at grid points only;
#: viscous friction grows like sqrt(s_dot^2) right after rest): bound on that overshoot.
FORCE_OVERSHOOT = 0.06
#: Longest accepted time to reject a bad file [s] (bad input is found before any solve).
REJECT_SECONDS = 5.0


@pytest.fixture(scope="module")
def solved(tmp_path_factory):
    out = tmp_path_factory.mktemp("path")
    outcome = run_problem(PATH_FILE, out, plots=False)
    return outcome, out


def test_shipped_path_problem_solves_to_optimal(solved):
    outcome, out = solved
    assert outcome.exit_code == 0
    assert outcome.summary["status"] == "optimal"
    header = (out / "trajectory.csv").read_text().splitlines()[0]
    assert header.startswith("t,x,y,z,q1,q2,q3,qd1,qd2,qd3,tau1,tau2,tau3") and header.endswith("s,s_dot,s_ddot")
    assert (out / "trajectory.h").exists()
    assert outcome.summary["files"] == ["summary.json", "trajectory.csv", "trajectory.h"]


def test_declaration_of_the_shipped_file():
    d = load_problem(PATH_FILE).declaration
    assert isinstance(d, PathConstrainedDeclaration)
    assert (d.method, d.grid, d.w, d.configuration, d.viscous_friction) == ("convex", 500, 0.0, 0, True)
    np.testing.assert_array_equal(d.constraints.force_limit, [450.0, 450.0, 450.0])
    np.testing.assert_array_equal(d.path.start, [-0.2, 2.75, -0.4])


def test_one_motor_at_its_bound_most_of_the_time_and_forces_near_limits(solved):
    summary = solved[0].summary
    assert max(summary["fraction_at_force_bound"]) >= AT_BOUND_FRACTION
    assert max(summary["max_force_ratio"]) <= 1 + FORCE_OVERSHOOT


def test_duration_equals_ipopt_on_the_same_grid(solved):
    summary = solved[0].summary
    d = load_problem(PATH_FILE).declaration
    nlp = PathConstrainedProblem(d.path, d.constraints, robot=d.robot, configuration=d.configuration).solve_nlp(grid=d.grid)
    assert nlp.final_time == pytest.approx(summary["final_time_s"], rel=DURATION_RTOL)


def test_trajectory_columns_are_the_csv(solved):
    outcome, out = solved
    cols = path_trajectory_columns(outcome.solution)
    data = np.loadtxt(out / "trajectory.csv", delimiter=",", skiprows=1)
    assert list(cols) == (out / "trajectory.csv").read_text().splitlines()[0].split(",")
    np.testing.assert_allclose(data, np.column_stack(list(cols.values())), rtol=1e-9, atol=1e-12)


def test_study_overlay_writes_the_two_plots(solved, tmp_path):
    outcome, _ = solved
    files = get_kind("path_constrained").overlay({"a": outcome.solution}, tmp_path)
    assert files == ["overlay_forces.png", "overlay_tcp.png"]
    assert all((tmp_path / f).stat().st_size > 0 for f in files)


def test_plots_are_written(tmp_path):
    f = tmp_path / "coarse.toml"
    f.write_text(_edit("grid = 500", "grid = 50")(PATH_FILE.read_text()))
    outcome = run_problem(f, tmp_path / "out", plots=True)
    assert outcome.status == Status.OPTIMAL
    assert set(outcome.summary["files"]) == {"summary.json", "trajectory.csv", "trajectory.h", "tcp_path.png", "forces.png", "profile.png"}

_COLLOCATION = _edit('name = "convex"', 'name = "collocation"')


def _both(first, second):
    """Two edits of the file, one after the other."""
    return lambda text: second(first(text))


BAD = [
    ("outside_workspace", _edit('shape = "line"', 'shape = "polyline"\nvia = [[0.0, 6.0, -0.5]]'), r"field 'path': .*s = "),
    ("via_on_line", _edit('shape = "line"', 'shape = "line"\nvia = [[0.0, 2.9, -0.5]]'), r"field 'path\.via': expected no via points"),
    ("no_via_on_spline", _edit('shape = "line"', 'shape = "spline"'), r"field 'path\.via': expected at least one via point"),
    ("via_not_a_list", _edit('shape = "line"', 'shape = "spline"\nvia = 5'), r"field 'path\.via': expected a list of at most 1000"),
    ("via_wrong_length", _edit('shape = "line"', 'shape = "spline"\nvia = [[0.0, 2.9]]'), r"field 'path\.via\[0\]': expected a list of 3 finite numbers"),
    ("via_nan", _edit('shape = "line"', 'shape = "spline"\nvia = [[0.0, nan, -0.5]]'), r"field 'path\.via\[0\]': expected a list of 3 finite numbers"),
    ("via_huge", _edit('shape = "line"', 'shape = "spline"\nvia = [[0.0, 1e308, -0.5]]'), r"field 'path\.via\[0\]': expected numbers of magnitude <= 1000 m"),
    ("via_repeats_start", _edit('shape = "line"', 'shape = "polyline"\nvia = [[-0.20, 2.75, -0.40]]'), r"field 'path\.via\[0\]': expected a point different from motion\.start"),
    ("end_equals_start", _edit("end   = [ 0.20, 3.00, -0.60]", "end = [-0.20, 2.75, -0.40]"), r"field 'motion\.end': expected a point different from motion\.start"),
    ("bad_shape", _edit('shape = "line"', 'shape = "circle"'), r"field 'path\.shape': expected one of line, polyline, spline"),
    ("bad_method", _edit('name = "convex"', 'name = "magic"'), r"field 'method\.name': expected one of convex, collocation"),
    ("weight_on_convex", _edit("grid = 500", "grid = 500\nw = 0.1"), r"field 'method\.w': expected w = 0"),
    ("weight_huge", _edit('name = "convex"', 'name = "collocation"\nw = 1e308'), r"field 'method\.w': expected a number <= 1000"),
    ("weight_negative", _edit('name = "convex"', 'name = "collocation"\nw = -1.0'), r"field 'method\.w': expected a non-negative number"),
    ("unknown_field", _edit("grid = 500", "grid = 500\ngrdi = 3"), r"unknown field 'method\.grdi'"),
    ("negative_force", _edit("force = [450.0, 450.0, 450.0]", "force = [450.0, -1.0, 450.0]"), r"field 'limits\.force': expected 3 positive numbers"),
    ("force_huge", _edit("force = [450.0, 450.0, 450.0]", "force = [450.0, 1e308, 450.0]"), r"field 'limits\.force': expected numbers of magnitude <= 1e\+07 N"),
    ("force_inf", _edit("force = [450.0, 450.0, 450.0]", "force = [450.0, inf, 450.0]"), r"field 'limits\.force': expected a list of 3 finite numbers"),
    ("force_string", _edit("force = [450.0, 450.0, 450.0]", 'force = "450"'), r"field 'limits\.force': expected a list of 3 finite numbers"),
    ("force_empty", _edit("force = [450.0, 450.0, 450.0]", "force = []"), r"field 'limits\.force': expected a list of 3 finite numbers"),
    ("no_limit", _edit("force = [450.0, 450.0, 450.0]", ""), r"field 'limits': expected at least one limit"),
    ("tcp_speed_tiny", _edit("force = [450.0, 450.0, 450.0]", "tcp_speed = 1e-300"), r"field 'limits\.tcp_speed': expected a number >= 0\.01"),
    ("tcp_acceleration_tiny", _edit("force = [450.0, 450.0, 450.0]", "tcp_acceleration = [1e-9, 1.0, 1.0]"), r"field 'limits\.tcp_acceleration': expected numbers >= 0\.01 m/s\^2"),
    ("collocation_without_force", _both(_COLLOCATION, _edit("force = [450.0, 450.0, 450.0]", "tcp_speed = 1.0")), r"field 'limits\.force': expected force limits for method \"collocation\""),
    ("collocation_other_limit", _both(_COLLOCATION, _edit("force = [450.0, 450.0, 450.0]", "force = [450.0, 450.0, 450.0]\ntcp_speed = 1.0")), r"field 'limits\.tcp_speed': expected only force limits with method \"collocation\""),
    ("grid_too_fine", _edit("grid = 500", "grid = 1000000"), rf"field 'method\.grid': expected an integer in 2\.\.{MAX_GRID_POINTS}"),
    ("grid_bool", _edit("grid = 500", "grid = true"), r"field 'method\.grid': expected an integer in 2\.\."),
    ("grid_float", _edit("grid = 500", "grid = 500.5"), r"field 'method\.grid': expected an integer in 2\.\."),
    ("bounds_reversed", _edit("grid = 500", "grid = 500\nfinal_time_bounds = [10.0, 0.05]"), r"field 'method\.final_time_bounds': expected \[lo, hi\] with 0 < lo < hi"),
    ("bounds_huge", _edit("grid = 500", "grid = 500\nfinal_time_bounds = [0.05, 1e308]"), r"field 'method\.final_time_bounds': expected numbers of magnitude <= 10000 s"),
    ("guess_outside_bounds", _edit('name = "convex"', 'name = "collocation"\nfinal_time_guess = 100.0'), r"field 'method\.final_time_guess': expected a time within method\.final_time_bounds \[0\.05, 10\.0\]"),
    ("guess_tiny", _edit('name = "convex"', 'name = "collocation"\nfinal_time_guess = 1e-300'), r"field 'method\.final_time_guess': expected a number >= 0\.001"),
    ("bounds_tiny", _edit('name = "convex"', 'name = "collocation"\nfinal_time_bounds = [1e-300, 1.0]'), r"field 'method\.final_time_bounds': expected numbers >= 0\.001 s"),
    ("configuration_out_of_range", _edit("configuration = 0", "configuration = 8"), r"field 'robot\.configuration': expected an integer in 0\.\.7"),
    ("viscous_not_bool", _edit("viscous_friction = true", 'viscous_friction = "yes"'), r"field 'robot\.viscous_friction': expected true or false"),
    ("bad_robot", _edit('parameters = "L1"', 'parameters = "Z9"'), r"field 'robot\.parameters'"),
    ("missing_limits", _edit("[limits]", "[limitz]"), r"unknown field 'limitz'"),
]


@pytest.mark.parametrize("case, edit, match", BAD, ids=[c[0] for c in BAD])
def test_bad_path_problem(tmp_path, case, edit, match):
    f = tmp_path / f"{case}.toml"
    f.write_text(edit(PATH_FILE.read_text()))
    start = time.perf_counter()
    with pytest.raises(ProblemError, match=match) as info:
        load_problem(f)
    assert str(f) in str(info.value).splitlines()[0]
    assert time.perf_counter() - start < REJECT_SECONDS


def test_file_that_is_not_utf8(tmp_path):
    f = tmp_path / "latin1.toml"
    f.write_bytes(PATH_FILE.read_text().replace("L1 time-optimal", "L1 temps optimal \u00e9").encode("latin-1"))
    with pytest.raises(ProblemError, match="UTF-8"):
        load_problem(f)


def test_infeasible_limits_give_status_and_no_data_files(tmp_path):
    """Force limits below gravity + friction at the start: no motion exists."""
    f = tmp_path / "weak.toml"
    f.write_text(_edit("force = [450.0, 450.0, 450.0]", "force = [150.0, 150.0, 150.0]")(PATH_FILE.read_text()))
    out = tmp_path / "out"
    outcome = run_problem(f, out, plots=True)
    assert outcome.exit_code == Status.INFEASIBLE.exit_code != 0
    assert outcome.summary["status"] == "infeasible"
    assert "grid point" in outcome.summary["message"]
    assert outcome.summary["files"] == ["summary.json"]
    assert not (out / "trajectory.csv").exists()


def test_collocation_method_agrees_with_convex(tmp_path):
    """The thesis' projection method (collocation) against the convex optimum: equal within
    the discretisation errors of both (50 x 3 Radau vs 500 grid points)."""
    f = tmp_path / "colloc.toml"
    f.write_text(_edit('name = "convex"', 'name = "collocation"')(PATH_FILE.read_text()))
    outcome = run_problem(f, tmp_path / "out", plots=False)
    assert outcome.exit_code == 0
    ref = solve_problem(load_problem(PATH_FILE))
    assert outcome.summary["final_time_s"] == pytest.approx(ref.final_time, rel=5e-3)
    assert np.isfinite(outcome.summary["energy"])
