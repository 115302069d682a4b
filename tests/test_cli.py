"""The ``gtmodel`` command, end to end on the shipped problems and on broken input.

Independent checks of a solve: the trajectory file is read back and checked against the
problem's declared poses and limits, the energy in the summary against a trapezoidal
integral of the sampled forces, and the thesis' shape (ch. 3.5: the minimum-time
solution has all three forces at a bound most of the time).
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import tomllib

import numpy as np
import pytest

from gtmodel.cli import EXIT_BAD_INPUT, EXIT_NOT_OPTIMAL, main

from .bad_problems import BAD_PROBLEMS, BASE
from .conftest import PROBLEMS_DIR

#: Shipped free-path problems (the other kinds have their own end-to-end tests).
SHIPPED = sorted(p for p in PROBLEMS_DIR.glob("*.toml") if tomllib.loads(p.read_text())["kind"] == "point_to_point")
HEADER = "t,x,y,z,q1,q2,q3,qd1,qd2,qd3,tau1,tau2,tau3"
#: End poses reached [m] and end velocities [m/s].
POSE_TOL = 1e-8
#: Forces within their limits, relative (issue requirement).
FORCE_RTOL = 1e-6
#: Sampled energy (trapezoid on 4 ms samples) vs the exact polynomial integral, relative.
ENERGY_RTOL = 0.02
#: "Most of the motion" at a bound: at least this fraction of samples per actuator.
AT_BOUND_FRACTION = 0.75
SAMPLE_TIME = 0.004
#: Open-loop replay of the CSV forces through the model vs the CSV path [m]. The forces are
#: interpolated linearly between collocation points (the quadratic polynomial overshoots
#: the limits at bang-bang switches), which costs about 6 mm over the 0.5 m motion.
REPLAY_TOL = 0.01


#: Solved in the slow run only (7 s; the other energy file checks the same in the default run).
SLOW_SOLVES = {"l1_energy_w0_001.toml"}


@pytest.fixture(scope="module", params=[pytest.param(p, id=p.name, marks=pytest.mark.slow if p.name in SLOW_SOLVES else ()) for p in SHIPPED])
def solved(request, tmp_path_factory):
    out = tmp_path_factory.mktemp(request.param.stem)
    env = dict(os.environ, MPLBACKEND="Agg")
    proc = subprocess.run(
        [sys.executable, "-m", "gtmodel.cli", "solve", str(request.param), "--out", str(out)],
        capture_output=True,
        text=True,
        env=env,
        timeout=600,
    )
    return request.param, out, proc


def test_solve_exits_zero_with_optimal_status(solved):
    _, out, proc = solved
    assert proc.returncode == 0, proc.stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "optimal"
    assert "status       optimal" in proc.stdout


@pytest.mark.parametrize(
    "key",
    ["problem", "kind", "status", "final_time_s", "energy", "iterations", "solve_time_s", "objective", "max_constraint_violation"],
)
def test_summary_has_the_required_key(solved, key):
    _, out, _ = solved
    assert key in json.loads((out / "summary.json").read_text())


@pytest.mark.parametrize("name", ["trajectory.csv", "trajectory.h", "tcp_path.png", "forces.png"])
def test_solve_writes_the_result_file(solved, name):
    _, out, _ = solved
    assert (out / name).stat().st_size > 0


def test_c_header_holds_the_csv_table(solved):
    """The C array header (read back independently of its writer's format) equals the CSV."""
    _, out, _ = solved
    from gtmodel.trajectory.export import read_c_header

    data = np.genfromtxt(out / "trajectory.csv", delimiter=",", names=True)
    arrays = read_c_header(out / "trajectory.h")
    assert set(data.dtype.names) <= set(arrays)
    for name in data.dtype.names:
        np.testing.assert_allclose(arrays[name], data[name], rtol=1e-9, atol=1e-12)


def test_trajectory_starts_and_ends_at_rest_at_declared_poses(solved):
    path, out, _ = solved
    declared = tomllib.loads(path.read_text())
    assert (out / "trajectory.csv").read_text().splitlines()[0].startswith(HEADER)
    data = np.genfromtxt(out / "trajectory.csv", delimiter=",", names=True)
    T = np.column_stack([data["x"], data["y"], data["z"]])
    np.testing.assert_allclose(T[0], declared["motion"]["start"], atol=POSE_TOL)
    np.testing.assert_allclose(T[-1], declared["motion"]["end"], atol=POSE_TOL)
    moving = {c: (data[c][0], data[c][-1]) for c in ("qd1", "qd2", "qd3", "xd", "yd", "zd")
              if not (abs(data[c][0]) < POSE_TOL and abs(data[c][-1]) < POSE_TOL)}
    assert not moving, moving  # velocity: (first, last) sample
    dt = np.diff(data["t"])
    np.testing.assert_allclose(dt[:-1], SAMPLE_TIME, rtol=1e-9)
    assert 0 < dt[-1] <= SAMPLE_TIME + 1e-12


def test_forces_within_limits_and_at_bound_most_of_the_time(solved):
    path, out, _ = solved
    declared = tomllib.loads(path.read_text())
    limit = np.array(declared["limits"]["force"])
    data = np.genfromtxt(out / "trajectory.csv", delimiter=",", names=True)
    tau = np.column_stack([data["tau1"], data["tau2"], data["tau3"]])
    assert np.all(np.abs(tau) <= limit * (1 + FORCE_RTOL))
    if declared["parameters"]["w"] == 0:
        at_bound = (np.abs(tau) >= 0.999 * limit).mean(axis=0)
        assert np.all(at_bound >= AT_BOUND_FRACTION), at_bound
    summary = json.loads((out / "summary.json").read_text())
    sampled = np.trapezoid(np.sum(tau**2, axis=1), data["t"])
    assert abs(sampled - summary["energy"]) <= ENERGY_RTOL * summary["energy"]
    assert 0.5 <= summary["final_time_s"] <= 1.5


@pytest.mark.parametrize("case, edit, match", BAD_PROBLEMS, ids=[c[0] for c in BAD_PROBLEMS])
def test_bad_problem_gives_one_message_nonzero_exit_and_error_summary(tmp_path, capsys, case, edit, match):
    f = tmp_path / f"{case}.toml"
    f.write_text(edit(BASE.read_text()))
    out = tmp_path / "out"
    code = main(["solve", str(f), "--out", str(out), "--quiet"])
    assert code == EXIT_BAD_INPUT
    err = capsys.readouterr().err
    assert err.startswith("gtmodel: error: ")
    assert "Traceback" not in err
    import re

    assert re.search(match, err)
    assert sorted(p.name for p in out.iterdir()) == ["summary.json"]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "invalid_input"
    assert re.search(match, summary["message"])


def test_not_optimal_exits_nonzero_without_trajectory(tmp_path, capsys):
    text = BASE.read_text().replace("max_iter = 3000", "max_iter = 3").replace("elements = 50", "elements = 10")
    f = tmp_path / "short.toml"
    f.write_text(text)
    out = tmp_path / "out"
    code = main(["solve", str(f), "--out", str(out), "--quiet"])
    assert code == EXIT_NOT_OPTIMAL
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "max_iterations"
    assert summary["last_iterate"] is True
    assert "NOT a solution" in capsys.readouterr().out
    assert not (out / "trajectory.csv").exists()


def test_codegen_check_from_cli(tmp_path, capsys):
    code = main(["codegen", "--robot", "L1", "--out", str(tmp_path), "--check", "-n", "200"])
    printed = capsys.readouterr().out
    assert code == 0, printed
    assert "PASSED" in printed
    assert (tmp_path / "gt_L1.h").exists()


def test_result_folder_that_is_a_file_is_an_io_error_naming_the_path(tmp_path, capsys):
    blocker = tmp_path / "taken"
    blocker.write_text("not a folder")
    code = main(["solve", str(BASE), "--out", str(blocker), "--quiet", "--no-plots"])
    assert code == EXIT_BAD_INPUT
    err = capsys.readouterr().err
    assert f"cannot write the result folder {blocker}" in err
    assert "internal error" not in err
    assert blocker.read_text() == "not a folder"
    assert [p.name for p in tmp_path.iterdir()] == ["taken"]


def test_csv_forces_replayed_through_the_model_reproduce_the_path(solved):
    """Independent check: forward-simulate the robot model (IDAS) with the sampled forces."""
    from gtmodel.robots import gantry_tau_model

    path, out, _ = solved
    declared = tomllib.loads(path.read_text())
    data = np.genfromtxt(out / "trajectory.csv", delimiter=",", names=True)
    tau = np.column_stack([data["tau1"], data["tau2"], data["tau3"]])
    T = np.column_stack([data["x"], data["y"], data["z"]])
    robot = declared["robot"]
    model = gantry_tau_model(robot["parameters"], states="tcp", friction=robot["friction"], friction_width=robot["friction_width"])
    sim = model.simulate(data["t"], x0={"T": T[0], "T_dot": np.zeros(3)}, u=(tau[:-1] + tau[1:]) / 2, integrator="idas", rtol=1e-9, atol=1e-11)
    assert np.abs(sim.x["T"] - T).max() < REPLAY_TOL


def test_infeasible_duration_bounds_give_status_infeasible(tmp_path, capsys):
    """Limits too tight for the distance: the motion cannot be done within 0.2 s at 450 N."""
    text = (
        BASE.read_text()
        .replace("bounds = [0.05, 10.0]", "bounds = [0.05, 0.2]")
        .replace("initial_guess = 1.0 ", "initial_guess = 0.2 ")
        .replace("elements = 50 ", "elements = 15 ")
    )
    f = tmp_path / "too_fast.toml"
    f.write_text(text)
    out = tmp_path / "out"
    code = main(["solve", str(f), "--out", str(out), "--quiet"])
    assert code == EXIT_NOT_OPTIMAL
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "infeasible"
    assert summary["last_iterate"] is True
    # the bound named as the likely culprit (issue 67: the L1's minimum time is 0.67 s), in the summary and the terminal
    culprit = "likely culprit: final_time at its upper bound 0.2 s at the last iterate: the minimum time may be above it"
    assert culprit in summary["message"]
    assert not (out / "trajectory.csv").exists()
    printed = capsys.readouterr()
    assert "Traceback" not in printed.err and culprit in printed.out


#: Heavy libraries the fast paths of the command must not import (issue 24, item 7).
HEAVY = ("casadi", "scipy", "pandas", "matplotlib", "control", "dask", "pydantic")
FAST_PATHS = {"help": ["--help"], "schema_list": ["schema", "--list"], "missing_file": ["solve", "nope.toml"],
              "missing_study_file": ["study", "nope.toml"], "out_is_a_file": ["solve", str(BASE), "--out", str(BASE)]}


@pytest.mark.parametrize("argv", list(FAST_PATHS.values()), ids=list(FAST_PATHS))
def test_fast_paths_of_the_command_import_no_heavy_library(tmp_path, argv):
    """``gtmodel --help``, ``schema --list`` and a mistyped path start in a fraction of a
    second because they never import the solvers' stack (checked on sys.modules in a fresh
    process, not by timing; benchmarks/bench_cli_startup.py measures the time)."""
    script = ("import sys\nfrom gtmodel.cli import main\ntry:\n    code = main(sys.argv[1:])\nexcept SystemExit as exc:\n    code = exc.code\n"
              f"print('IMPORTED', sorted(m for m in {HEAVY!r} if m in sys.modules))\n")
    proc = subprocess.run([sys.executable, "-c", script, *argv], capture_output=True, text=True, cwd=tmp_path, timeout=120,
                          env=dict(os.environ, PYTHONPATH=str(PROBLEMS_DIR.parent)))
    assert proc.stdout.splitlines()[-1] == "IMPORTED []", proc.stdout + proc.stderr


#: What ``gtmodel solve`` on an optimal-control problem with a user's model (plots off) does
#: not need, and so must not import: pandas, matplotlib, python-control, SciPy's sparse,
#: optimisation, linear-algebra and interpolation packages, the robot models, the inverse
#: model and the acausal components (issue 25: the process within 1.5 s of the solve itself;
#: benchmarks/bench_ocp_suite.py measures the time, ``cli_s``).
NOT_ON_THE_SOLVE_PATH = ("pandas", "matplotlib", "control", "scipy.sparse", "scipy.optimize", "scipy.linalg",
                         "scipy.interpolate", "gtmodel.robots", "gtmodel.modeling.simulation.inverse",
                         "gtmodel.modeling.components")


def test_solving_a_user_model_problem_imports_only_what_it_needs(tmp_path):
    """A published benchmark (the smallest) solved in a fresh process: sys.modules checked,
    not timed; the result is the shipped one (the double integrator's minimum time, 2 s)."""
    problem = PROBLEMS_DIR / "benchmarks" / "double_integrator_min_time.toml"
    script = ("import sys\nfrom gtmodel.cli import main\ntry:\n    code = main(sys.argv[1:])\nexcept SystemExit as exc:\n    code = exc.code\n"
              f"print('EXIT', code)\nprint('IMPORTED', sorted(m for m in {NOT_ON_THE_SOLVE_PATH!r} if m in sys.modules))\n")
    proc = subprocess.run([sys.executable, "-c", script, "solve", str(problem), "--out", str(tmp_path / "out"), "--no-plots", "--quiet"],
                          capture_output=True, text=True, cwd=tmp_path, timeout=300, env=dict(os.environ, PYTHONPATH=str(PROBLEMS_DIR.parent)))
    assert proc.stdout.splitlines()[-2:] == ["EXIT 0", "IMPORTED []"], proc.stdout + proc.stderr
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["status"] == "optimal" and abs(summary["final_time_s"] - 2.0) < 1e-6
    assert (tmp_path / "out" / "trajectories.csv").read_text().startswith("t [s],")  # each column's unit in its header


#: Libraries a problem file with a bad field must not import: it is reported by its kind's
#: light schema before the kind (its solvers) is imported (issue 24, item 7).
SOLVER_STACK = ("casadi", "scipy", "control", "matplotlib", "pandas")


@pytest.mark.parametrize("case", ["unknown_top_field", "unknown_field", "wrong_type"])
def test_a_bad_field_is_reported_without_importing_the_solvers(tmp_path, case):
    """``gtmodel solve`` on a file with an unknown field or a wrong type: exit 2, the usual
    message and an ``invalid_input`` summary, from the schema alone (sys.modules of a fresh
    process; benchmarks/bench_cli_startup.py measures the time)."""
    edit, pattern = {c: (e, p) for c, e, p in BAD_PROBLEMS}[case]
    f = tmp_path / "bad.toml"
    f.write_text(edit(BASE.read_text()))
    script = ("import sys\nfrom gtmodel.cli import main\ntry:\n    code = main(sys.argv[1:])\nexcept SystemExit as exc:\n    code = exc.code\n"
              f"print('EXIT', code)\nprint('IMPORTED', sorted(m for m in {SOLVER_STACK!r} if m in sys.modules))\n")
    proc = subprocess.run([sys.executable, "-c", script, "solve", str(f), "--out", str(tmp_path / "out"), "--quiet"], capture_output=True,
                          text=True, cwd=tmp_path, timeout=120, env=dict(os.environ, PYTHONPATH=str(PROBLEMS_DIR.parent)))
    assert proc.stdout.splitlines()[-2:] == [f"EXIT {EXIT_BAD_INPUT}", "IMPORTED []"], proc.stdout + proc.stderr
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["status"] == "invalid_input"
    assert re.search(pattern, summary["message"]) and re.search(pattern, proc.stderr), proc.stderr


def test_a_mistyped_problem_path_is_one_error_and_writes_nothing(tmp_path, capsys, monkeypatch):
    """Defect (e): ``gtmodel solve nope.toml`` created results/nope/summary.json."""
    monkeypatch.chdir(tmp_path)
    code = main(["solve", "nope.toml", "--quiet"])
    err = capsys.readouterr().err
    assert (code, err) == (EXIT_BAD_INPUT, "gtmodel: error: nope.toml: cannot read the problem file (no such file)\n")
    assert list(tmp_path.iterdir()) == []


def test_run_problem_on_a_missing_file_writes_nothing(tmp_path, monkeypatch):
    """Defect (e), from the library: run_problem reports the missing file and writes no folder."""
    from gtmodel.problems import run_problem

    monkeypatch.chdir(tmp_path)
    outcome = run_problem(tmp_path / "nope.toml")
    assert (outcome.status, outcome.written, list(tmp_path.iterdir())) == ("invalid_input", False, [])


def test_an_invalid_input_summary_is_named_after_the_problem_file(tmp_path, capsys):
    """Defect (h): the summary of a file that does not load had ``"name": null``."""
    f = tmp_path / "broken.toml"
    f.write_text(BASE.read_text().replace("free = true", "free = true\nfree_time = 2.0").replace('name = "l1_time_optimal"', ""))
    code = main(["solve", str(f), "--out", str(tmp_path / "out"), "--quiet"])
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert (code, summary["status"], summary["name"]) == (EXIT_BAD_INPUT, "invalid_input", "broken")


def test_out_naming_a_file_is_found_before_the_solve_with_one_message(tmp_path, capsys, monkeypatch):
    """Defect (b): checked up front (no solve is started), one line, exit 2, the file kept."""
    from gtmodel.problems import run as run_module

    monkeypatch.setattr(run_module, "solve_problem", lambda *a, **k: pytest.fail("solved before checking --out"))
    blocker = tmp_path / "taken"
    blocker.write_text("not a folder")
    code = main(["solve", str(BASE), "--out", str(blocker / "sub"), "--quiet"])
    err = capsys.readouterr().err
    assert (code, err) == (EXIT_BAD_INPUT, f"gtmodel: error: cannot write the result folder {blocker / 'sub'}: its parent {blocker} is a file\n")
    assert [p.name for p in tmp_path.iterdir()] == ["taken"] and blocker.read_text() == "not a folder"


def test_schema_list_prints_every_kind_with_its_title(capsys):
    """``schema --list`` reads the titles from the kinds' sources (no import): they must be the kinds' own."""
    from gtmodel.problems import KINDS
    from gtmodel.problems.registry import LOOP_KINDS

    assert main(["schema", "--list"]) == 0
    listed = [line.split(None, 1) for line in capsys.readouterr().out.splitlines()]
    # the problem kinds, then the loop-controller file kinds (issue 45), each with its declared title
    assert listed == [[name, kind.title] for name, kind in KINDS.items()] + [[name, kind.title] for name, kind in LOOP_KINDS.items()]


def test_a_component_model_reduced_on_the_solve_path_imports_no_scipy_beyond_linalg(tmp_path):
    """dc_motor_min_energy (library components: alias elimination, Pantelides, dummy derivatives) in a fresh
    process: the structural passes run on CasADi's sparsity (issue 49); the dummy derivatives' pivoted QR is
    LAPACK's ``dgeqp3`` of NumPy's own OpenBLAS (structure/pivoting.py), so no SciPy package is imported
    where NumPy ships one (elsewhere SciPy's linear algebra, and with SciPy 1.14 its sparse package: only
    optimize and interpolate are asserted absent); the result is the closed-form optimum 0.2667243572 to 1e-4
    (sys.modules checked, not timed)."""
    from gtmodel.modeling.structure.pivoting import numpy_dgeqp3

    problem = PROBLEMS_DIR / "benchmarks" / "dc_motor_min_energy.toml"
    absent = ("optimize", "interpolate") + (("linalg", "sparse") if numpy_dgeqp3() is not None else ())
    script = ("import sys\nfrom gtmodel.cli import main\ntry:\n    code = main(sys.argv[1:])\nexcept SystemExit as exc:\n    code = exc.code\n"
              "print('EXIT', code)\nprint('IMPORTED', sorted(m for m in sys.modules if m.startswith('scipy.')"
              f" and m.split('.')[1] in {absent!r}))\n")
    proc = subprocess.run([sys.executable, "-c", script, "solve", str(problem), "--out", str(tmp_path / "out"), "--no-plots", "--quiet"],
                          capture_output=True, text=True, cwd=tmp_path, timeout=300)
    assert proc.stdout.splitlines()[-2:] == ["EXIT 0", "IMPORTED []"], proc.stdout + proc.stderr
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["status"] == "optimal" and abs(summary["objective"] - 0.2667243572) < 1e-4 * 0.2667243572


@pytest.mark.parametrize("passes, expected", [
    (None, "solve time   2.000 s wall, 0.500 s CPU (the solver's calls)"),
    ([{"solve_cpu_time": 0.5, "elements": 10}, {"solve_cpu_time": 1.25, "elements": 14}],
     "solve time   2.000 s wall, 1.750 s CPU (the solver's calls over 2 passes)"),
])
def test_printed_solve_time_wall_and_cpu_cover_the_same_solves(tmp_path, capsys, passes, expected):
    # a refined result's solve_time_s sums every pass's solve; its CPU must sum the same passes (the summary's
    # refinement history), not timing.solve (the first pass alone): the two figures checked against their sums by hand
    from gtmodel.cli import _print_summary

    summary = {"name": "p", "kind": "optimal_control", "status": "optimal", "message": "Solve_Succeeded",
               "solve_time_s": 2.0, "timing": {"solve": {"wall_s": 0.6, "cpu_s": 0.5}}}
    if passes is not None:
        summary["refinement"] = passes
    _print_summary(summary, tmp_path)
    assert expected in capsys.readouterr().out
