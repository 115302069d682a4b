"""Problem files of the motion kinds: the path-constrained schema, end to end and bad input.

Independent references: the path-constrained optimum of the shipped problem is recomputed
by the IPOPT transcription of the same gridded problem (a second solver), and the thesis'
shape (ch. 3.5): on the straight line one motor is at its force bound most of the time.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from gtmodel.cli import EXIT_NOT_OPTIMAL, EXIT_OK, main
from gtmodel.errors import ProblemError
from gtmodel.problems import load_problem

from ..conftest import PROBLEMS_DIR, replace_once as _edit

PATH_FILE = PROBLEMS_DIR / "l1_path_constrained.toml"
#: Duration of the reachability solution vs IPOPT on the same grid, relative.
DURATION_RTOL = 1e-6
#: "Most of the motion": fraction of 4 ms samples at the bound for the limiting motor.
AT_BOUND_FRACTION = 0.75
#: Forces between grid points may exceed the limit (constraints hold at grid points only;
#: viscous friction grows like sqrt(s_dot^2) right after rest): bound on that overshoot.
FORCE_OVERSHOOT = 0.06


@pytest.fixture(scope="module")
def solved(tmp_path_factory):
    out = tmp_path_factory.mktemp("path")
    code = main(["solve", str(PATH_FILE), "--out", str(out), "--quiet", "--no-plots"])
    return code, out, json.loads((out / "summary.json").read_text())


def test_shipped_path_problem_solves_to_optimal(solved):
    code, out, summary = solved
    assert code == EXIT_OK
    assert summary["status"] == "optimal"
    header = (out / "trajectory.csv").read_text().splitlines()[0]
    assert header.startswith("t,x,y,z,q1,q2,q3,qd1,qd2,qd3,tau1,tau2,tau3") and header.endswith("s,s_dot,s_ddot")
    assert (out / "trajectory.h").exists()


def test_one_motor_at_its_bound_most_of_the_time_and_forces_near_limits(solved):
    _, _, summary = solved
    assert max(summary["fraction_at_force_bound"]) >= AT_BOUND_FRACTION
    assert max(summary["max_force_ratio"]) <= 1 + FORCE_OVERSHOOT


def test_duration_equals_ipopt_on_the_same_grid(solved):
    _, _, summary = solved
    problem = load_problem(PATH_FILE)
    from gtmodel.trajectory.path_constrained import PathConstrainedProblem

    d = problem.declaration
    nlp = PathConstrainedProblem(d.path, d.constraints, robot=d.robot, configuration=d.configuration).solve_nlp(grid=d.grid)
    assert nlp.final_time == pytest.approx(summary["final_time_s"], rel=DURATION_RTOL)



BAD = [
    ("outside_workspace", _edit('shape = "line"', 'shape = "polyline"\nvia = [[0.0, 6.0, -0.5]]'), r"field 'path': .*s = "),
    ("via_on_line", _edit('shape = "line"', 'shape = "line"\nvia = [[0.0, 2.9, -0.5]]'), r"field 'path\.via': expected no via points"),
    ("bad_shape", _edit('shape = "line"', 'shape = "circle"'), r"field 'path\.shape': expected one of line, polyline, spline"),
    ("bad_method", _edit('name = "convex"', 'name = "magic"'), r"field 'method\.name': expected one of convex, collocation"),
    ("weight_on_convex", _edit("grid = 500", "grid = 500\nw = 0.1"), r"field 'method\.w': expected w = 0"),
    ("unknown_field", _edit("grid = 500", "grid = 500\ngrdi = 3"), r"unknown field 'method\.grdi'"),
    ("negative_force", _edit("force = [450.0, 450.0, 450.0]", "force = [450.0, -1.0, 450.0]"), r"field 'limits\.force'"),
]


@pytest.mark.parametrize("case, edit, match", BAD, ids=[c[0] for c in BAD])
def test_bad_path_problem(tmp_path, case, edit, match):
    f = tmp_path / f"{case}.toml"
    f.write_text(edit(PATH_FILE.read_text()))
    with pytest.raises(ProblemError, match=match):
        load_problem(f)


def test_infeasible_limits_give_status_and_nonzero_exit(tmp_path, capsys):
    """Force limits below gravity + friction at the start: no motion exists."""
    f = tmp_path / "weak.toml"
    f.write_text(PATH_FILE.read_text().replace("force = [450.0, 450.0, 450.0]", "force = [150.0, 150.0, 150.0]"))
    out = tmp_path / "out"
    code = main(["solve", str(f), "--out", str(out), "--quiet"])
    assert code == EXIT_NOT_OPTIMAL
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "infeasible"
    assert "grid point" in summary["message"]
    assert not (out / "trajectory.csv").exists()
    assert "Traceback" not in capsys.readouterr().err


def test_collocation_method_agrees_with_convex(tmp_path):
    """The thesis' projection method (collocation) against the convex optimum: equal within
    the discretisation errors of both (50 x 3 Radau vs 500 grid points)."""
    f = tmp_path / "colloc.toml"
    f.write_text(PATH_FILE.read_text().replace('name = "convex"', 'name = "collocation"'))
    out = tmp_path / "out"
    assert main(["solve", str(f), "--out", str(out), "--quiet", "--no-plots"]) == EXIT_OK
    colloc = json.loads((out / "summary.json").read_text())
    convex = load_problem(PATH_FILE)
    from gtmodel.problems import solve_problem

    ref = solve_problem(convex)
    assert colloc["final_time_s"] == pytest.approx(ref.final_time, rel=5e-3)
    assert np.isfinite(colloc["energy"])
