"""A tracking controller from an optimal_control result folder, end to end.

References: the optimal motion of ``problems/dc_motor_move.toml`` itself (the controller on
the nominal model reproduces it, its feedforward alone does not under a 10 % parameter
mismatch), and the result folder's fields (a wrong status or a missing column is refused
by name).
"""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

from gtmodel.errors import InputError
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
