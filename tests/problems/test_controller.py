"""A tracking controller from an optimal_control result folder, end to end.

References: the optimal motion of ``problems/dc_motor_move.toml`` itself (the controller on
the nominal model reproduces it, its feedforward alone does not under a 10 % parameter
mismatch), and the result folder's fields (a wrong status or a missing column is refused
by name); the loop-file ranges (:mod:`gtmodel.problems.loop_file`) for the route's flags and size.
"""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

from gtmodel._tables import write_table
from gtmodel.cli import main
from gtmodel.errors import InputError, ProblemError
from gtmodel.problems.controller import tracking_from_result
from gtmodel.problems.run import run_problem

from ..conftest import REPO

PROBLEM = REPO / "problems" / "dc_motor_move.toml"
Q = [1e-2, 1.0, 1e-4]


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    out = tmp_path_factory.mktemp("dc_motor_move")
    outcome = run_problem(PROBLEM, out, plots=False)
    assert outcome.exit_code == 0
    return out


def _angle_errors(ode, c, p, feedback: bool, extra: int = 50) -> np.ndarray:
    """Rotor-angle error per period along the reference and ``extra`` periods after it (the last sample held)."""
    step = ode.step(c.dt, "rk4", substeps=4)
    law = c.function()
    x = c.x_ref[0].copy()
    err = []
    for k in range(c.length - 1 + extra):
        j = min(k, c.length - 1)
        u = np.asarray(law(c.t0 + k * c.dt, x, c.u_initial)[0]).ravel() if feedback else c.u_ref[j]
        x = np.asarray(step(x, u, p)[0]).ravel()
        err.append(x[1] - c.x_ref[min(k + 1, c.length - 1), 1])
    return np.array(err)


@pytest.mark.slow
def test_controller_of_the_solved_motion_tracks_it_and_settles_under_mismatch(result):
    # a minimum-time motion rides the voltage bound: along it the saturated feedback has no
    # authority left, so the test is the nominal tracking and where each ends up
    c, ode = tracking_from_result(result, Q=Q)
    summary = json.loads((result / "summary.json").read_text())
    assert c.length == int(np.floor(summary["final_time_s"] / 0.004 + 1e-6)) + 1
    assert (c.u_lb.tolist(), c.u_ub.tolist()) == ([-24.0], [24.0])
    travel = np.ptp(c.x_ref[:, 1])
    assert np.sqrt(np.mean(_angle_errors(ode, c, ode.p_default, True) ** 2)) < 0.01 * travel
    p = ode.p_default.copy()
    for name in ("r.R", "emf.k", "friction.d", "load.J", "rotor.J"):
        p[ode.p_names.index(name)] *= 1.1
    feedback, feedforward = _angle_errors(ode, c, p, True), _angle_errors(ode, c, p, False)
    assert abs(feedback[-1]) < 0.01 * travel and abs(feedforward[-1]) > 0.05 * travel
    assert c.u_hold.tolist() == pytest.approx([0.0], abs=1e-9)  # at rest the motor needs no voltage


@pytest.mark.slow
@pytest.mark.parametrize(
    "edit, match",
    [
        (lambda d: d.update(status="infeasible"), r"status: expected a solved problem \(optimal or acceptable\), got 'infeasible'"),
        (lambda d: d.update(model={}), "model: expected the model file and class of the solve"),
    ],
    ids=["status", "model"],
)
def test_bad_result_folder(result, tmp_path, edit, match):
    folder = tmp_path / "copy"
    shutil.copytree(result, folder)
    summary = json.loads((folder / "summary.json").read_text())
    edit(summary)
    (folder / "summary.json").write_text(json.dumps(summary))
    with pytest.raises(InputError, match=match):
        tracking_from_result(folder)


@pytest.mark.slow
def test_missing_column_is_named(result, tmp_path):
    folder = tmp_path / "copy"
    shutil.copytree(result, folder)
    lines = (folder / "trajectories.csv").read_text().splitlines()
    (folder / "trajectories.csv").write_text("\n".join(ln.replace("rotor.w", "rotor_w", 1) for ln in lines[:1]) + "\n" + "\n".join(lines[1:]) + "\n")
    with pytest.raises(InputError, match=r"trajectories\.csv: no column 'rotor\.w'"):
        tracking_from_result(folder)


def _fake_result(folder, duration: float):
    """A result folder of the composed motor without a solve: the summary's fields and a table of ``duration`` s."""
    folder.mkdir()
    (folder / "summary.json").write_text(json.dumps({"kind": "optimal_control", "status": "optimal",
                                                     "model": {"file": str(REPO / "models" / "dc_motor.py"), "class": "DCMotorModel"}}))
    t = np.linspace(0.0, duration, 11)
    write_table(folder / "trajectories.csv", ["t", "ind.i", "emf.phi", "rotor.w", "src.v"], np.column_stack([t, 0 * t, t, 0 * t, 0 * t]))
    return folder


@pytest.mark.parametrize("flags, match", [
    (["--period", "1e-12"], "--period: expected a loop period of 1e-05 to 1 s, got 1e-12"),
    (["--period", "nan"], "--period: expected a loop period"),
    (["--q", "1,nan,1"], "--q: expected comma-separated finite weights of 0 to 1e+12"),
    (["--r", "1e300"], "--r: expected comma-separated finite weights"),
    (["--q", "1,-1,1"], "--q: expected comma-separated finite weights"),
], ids=["period 1e-12", "period nan", "q nan", "r 1e300", "q negative"])
def test_result_folder_flags_out_of_range_exit_2_before_anything_is_built(tmp_path, capsys, flags, match):
    # the ranges of a tracking-controller file (gtmodel.problems.loop_file) hold for the flags of the result-folder route
    out = tmp_path / "out"
    assert main(["codegen", "--controller", str(_fake_result(tmp_path / "result", 0.2)), *flags, "--out", str(out), "--check"]) == 2
    assert match in capsys.readouterr().err
    assert not out.exists()


def test_a_result_too_long_for_the_period_is_refused_before_the_gains(tmp_path):
    # 10 s at 10 us: 1,000,001 periods > MAX_LOOP_SAMPLES, refused before the Riccati recursion
    folder = _fake_result(tmp_path / "result", 10.0)
    with pytest.raises(ProblemError, match=r"trajectories\.csv: field 't': expected a period giving at most 100000 loop periods.*1000001 periods"):
        tracking_from_result(folder, dt=1e-5, accept_unverified=True)
