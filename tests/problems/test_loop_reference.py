"""The reference of a loop-controller file (gtmodel.problems.loop_file.loop_reference): verified or opted in, a result
folder's table as written, the declared bounds carried into the controller.

References: the same motion reached two ways (the problem solved in process, and its result folder's
trajectories.csv as written by ``gtmodel solve``: the sampled references agree to 1e-12); the bounds by hand
from the problem file (|v| <= 24 V) and the model (none); the armature current of the series circuit,
``r.i = ind.i`` (closed form), as the MPC's output row.
"""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

from gtmodel.errors import InputError, ProblemError
from gtmodel.problems.controller import result_bounds, tracking_from_result
from gtmodel.problems.mpc_file import load_mpc_file
from gtmodel.problems.run import run_problem

from ..conftest import REPO

MOTOR = (REPO / "codegen" / "mpc" / "dc_motor_mpc.toml").read_text()
MODEL = f'model = "{REPO}/models/dc_motor.py:DCMotorModel"'


def _mpc_file(tmp_path, name, reference, extra_mpc=""):
    """The shipped motor MPC file in ``tmp_path`` with another ``[reference]`` (absolute model path)."""
    text = MOTOR.replace('model = "../../models/dc_motor.py:DCMotorModel"', MODEL)
    head, _, tail = text.partition("[reference]")
    tail = tail[tail.index("[check]"):]
    path = tmp_path / name
    path.write_text(head.replace("[mpc]\n", f"[mpc]\n{extra_mpc}") + "[reference]\n" + reference + "\nsettle_time = 0.3\n\n" + tail)
    return path


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    out = tmp_path_factory.mktemp("dc_motor_move") / "result"
    outcome = run_problem(REPO / "problems" / "dc_motor_move.toml", out, plots=False)
    assert outcome.exit_code == 0  # optimal and verified
    return out


def _unverified(result, tmp_path):
    folder = tmp_path / "unverified"
    shutil.copytree(result, folder)
    summary = json.loads((folder / "summary.json").read_text())
    summary["status"], summary["verification"]["passed"] = "check_failed", False
    summary["verification"]["message"] = "state 'ind.i' deviates"
    (folder / "summary.json").write_text(json.dumps(summary))
    return folder


@pytest.mark.slow  # two solves of the motion (about 15 s)
def test_result_folder_table_is_the_solved_reference(result, tmp_path):
    shutil.copytree(result, tmp_path / "result")  # a data file stays beside the file that names it
    by_table = load_mpc_file(_mpc_file(tmp_path, "table.toml", 'file = "result/trajectories.csv"'))
    by_problem = load_mpc_file(_mpc_file(tmp_path, "problem.toml", f'problem = "{REPO}/problems/dc_motor_move.toml"'))
    a, b = by_table.controller, by_problem.controller
    assert a.length == b.length
    np.testing.assert_allclose(a.x_ref, b.x_ref, rtol=0, atol=1e-9 * np.max(np.abs(b.x_ref)))
    np.testing.assert_allclose(a.u_ref, b.u_ref, rtol=0, atol=1e-9 * 24)
    assert (a.u_lb.tolist(), a.u_ub.tolist()) == ([-24.0], [24.0])  # the summary's bounds, not the model's (none)
    assert by_table.bounds.lb == {"src.v": -24.0} and by_table.notes == by_problem.notes  # verified: the delay's lead alone
    assert [n.split(",")[0] for n in by_table.notes] == ["reference: 1 period(s) at rest before the plan"]


def test_unverified_result_table_needs_the_opt_in(result, tmp_path):
    folder = _unverified(result, tmp_path)
    with pytest.raises(ProblemError, match=r"reference\.file.*a verified reference, or \[reference\] accept_unverified = true.*check_failed"):
        load_mpc_file(_mpc_file(tmp_path, "refused.toml", f'file = "{folder}/trajectories.csv"'))
    setup = load_mpc_file(_mpc_file(tmp_path, "accepted.toml", f'file = "{folder}/trajectories.csv"\naccept_unverified = true'))
    assert setup.notes[0].startswith("reference NOT verified (status check_failed") and "accept_unverified = true" in setup.notes[0]


def test_unverified_problem_needs_the_opt_in(tmp_path):
    text = (REPO / "problems" / "dc_motor_move.toml").read_text().replace('file = "../models/dc_motor.py"', f'file = "{REPO}/models/dc_motor.py"')
    (tmp_path / "move.toml").write_text(text + "\n[verification]\nenabled = false\n")
    ref = 'problem = "move.toml"'
    with pytest.raises(ProblemError, match=r"reference\.problem.*accept_unverified = true.*not verified"):
        load_mpc_file(_mpc_file(tmp_path, "refused.toml", ref))
    setup = load_mpc_file(_mpc_file(tmp_path, "accepted.toml", ref + "\naccept_unverified = true"))
    assert setup.notes and "NOT verified" in setup.notes[0]


def test_result_folder_controller_needs_the_opt_in(result, tmp_path):
    folder = _unverified(result, tmp_path)
    with pytest.raises(InputError, match=r"expected a verified result \(status check_failed.*--accept-unverified"):
        tracking_from_result(folder)
    c, ode = tracking_from_result(folder, accept_unverified=True)
    bounds, notes = result_bounds(folder, ode)
    assert (c.u_lb.tolist(), c.u_ub.tolist()) == ([-24.0], [24.0]) and bounds.lb == {"src.v": -24.0}
    assert notes[0].startswith("reference NOT verified") and "--accept-unverified" in notes[0]


def test_a_table_without_bounds_says_so(tmp_path):
    t = np.linspace(0.0, 0.2, 11)
    from gtmodel._tables import write_table
    write_table(tmp_path / "ref.csv", ["t", "ind.i", "emf.phi", "rotor.w", "src.v"], np.column_stack([t, 0 * t, t, 1 + 0 * t, 2 + 0 * t]))
    setup = load_mpc_file(_mpc_file(tmp_path, "m.toml", 'file = "ref.csv"'))
    assert np.isinf(setup.controller.u_ub[0])
    assert any(n.startswith("input bounds unknown: src.v (lower), src.v (upper)") and "mpc.u_lb" in n for n in setup.notes)


def test_output_bounds_are_mpc_rows(result, tmp_path):
    # the summary's bounds with the armature current r.i (an algebraic variable: r.i = ind.i in the series circuit)
    folder = tmp_path / "bounded"
    shutil.copytree(result, folder)
    summary = json.loads((folder / "summary.json").read_text())
    summary["bounds"]["r.i"] = [-30.0, None]
    summary["bounds"]["rotor.w"] = [-400.0, 400.0]  # a state's bound: a row of the state itself
    (folder / "summary.json").write_text(json.dumps(summary))
    setup = load_mpc_file(_mpc_file(tmp_path, "m.toml", f'file = "{folder}/trajectories.csv"'))
    c = setup.controller.constraints
    assert c.names == ["rotor.w", "r.i"] and (c.lb.tolist(), c.ub.tolist()) == ([-400.0, -30.0], [400.0, np.inf])
    x = np.array([3.5, 1.0, 2.0])
    np.testing.assert_allclose(np.asarray(c.function(x, [5.0])).ravel(), [2.0, 3.5], rtol=1e-12)
    assert setup.bounds.lb["r.i"] == -30.0 and setup.outputs is not None


@pytest.mark.parametrize("route", [["--mpc", "codegen/mpc/dc_motor_mpc.toml"], ["--controller", "codegen/controllers/dc_motor_tracking.toml"]],
                         ids=["mpc file", "controller file"])
def test_accept_unverified_flag_is_a_result_folders(route, tmp_path, capsys):
    from gtmodel.cli import main

    assert main(["codegen", *[str(REPO / a) if a.endswith(".toml") else a for a in route], "--out", str(tmp_path / "o"), "--accept-unverified"]) == 2
    assert "--accept-unverified applies to a --controller result folder" in capsys.readouterr().err
